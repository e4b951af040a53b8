//! The `cloth` command line as a user runs it: exit codes, output fields, dumps and
//! error messages.

use crate::binary::{cloth, stderr, stdout};
use std::process::Command;

#[test]
fn run_prints_the_summary() {
    let o = cloth(&["run", "--scene", "chain", "--duration", "0.5"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let out = stdout(&o);
    for field in [
        "steps",
        "simulated time",
        "wall time",
        "steps/s",
        "energy",
        "bounding box",
        "max speed",
        "integrator",
    ] {
        assert!(out.contains(field), "missing {field} in\n{out}");
    }
    assert!(out.contains("500"), "0.5 s at dt 1e-3 is 500 steps:\n{out}");
}

#[test]
fn run_json_is_one_object_with_the_fields() {
    let o = cloth(&[
        "run", "--scene", "bench", "--steps", "10", "--json", "--set", "width=8", "--set",
        "height=8",
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_str(stdout(&o).trim()).expect("one JSON object");
    assert_eq!(v["steps"], 10);
    assert_eq!(v["particles"], 64);
    for field in [
        "simulated_time",
        "wall_time",
        "steps_per_second",
        "particle_steps_per_second",
        "spring_steps_per_second",
        "energy",
        "bounding_box",
        "max_speed",
        "integrator",
        "dt",
    ] {
        assert!(!v[field].is_null(), "missing {field}");
    }
    assert_eq!(v["integrator"], "symplectic-euler");
    let dt = v["dt"].as_f64().unwrap();
    assert!(
        (dt * 960.0 - 1.0).abs() < 1e-12,
        "the bench's 1/960 s: {dt}"
    );
}

/// `threads` is what the engine stepped on, and `RAYON_NUM_THREADS` sets it for
/// every engine: a cloth too small to split runs on one whatever is allowed; a
/// 64 x 64 cloth (4,096 particles, 23,938 springs) on as many as allowed, on the
/// grid kernel and on the general engine alike.
#[test]
fn run_reports_the_threads_the_engine_stepped_on() {
    let run = |size: &str, threads: &str, exact: bool| -> serde_json::Value {
        let (width, height) = (format!("width={size}"), format!("height={size}"));
        let mut args = vec!["run", "--scene", "bench", "--steps", "4", "--json"];
        args.extend(["--set", &width, "--set", &height]);
        if exact {
            args.push("--exact");
        }
        let o = Command::new(env!("CARGO_BIN_EXE_cloth"))
            .args(&args)
            .env("RAYON_NUM_THREADS", threads)
            .output()
            .expect("runs");
        assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
        serde_json::from_str(stdout(&o).trim()).expect("one JSON object")
    };
    for exact in [false, true] {
        let engine = if exact { "general-f64" } else { "grid-f32" };
        let small = run("8", "3", exact);
        assert_eq!(small["engine"], engine);
        assert_eq!(small["threads"], 1, "a cloth too small to split, {engine}");
        for threads in [1, 2, 3] {
            let large = run("64", &threads.to_string(), exact);
            assert_eq!(large["engine"], engine);
            assert_eq!(
                large["threads"], threads,
                "RAYON_NUM_THREADS={threads}, {engine}"
            );
        }
    }
}

/// `simd` names the compiled loops the engine stepped with, as this CPU's
/// features (read here, apart from the engine's own detection) decide them: the
/// grid kernel the widest level the CPU has, the general engine the baseline
/// build; `cloth info` says the same.
#[test]
fn run_reports_the_simd_level_the_engine_stepped_with() {
    let grid = grid_simd_level();
    for (scene, exact, engine, simd) in [
        ("bench", false, "grid-f32", grid),
        ("bench", true, "general-f64", "baseline"),
        ("rope", false, "general-f64", "baseline"),
    ] {
        let mut args = vec!["run", "--scene", scene, "--steps", "4", "--json"];
        if exact {
            args.push("--exact");
        }
        let o = cloth(&args);
        assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
        let v: serde_json::Value = serde_json::from_str(stdout(&o).trim()).expect("JSON");
        let ran = (v["engine"].as_str(), v["simd"].as_str());
        assert_eq!(ran, (Some(engine), Some(simd)), "{scene}, exact: {exact}");
    }
    let o = cloth(&["info", "--scene", "bench", "--json"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_str(stdout(&o).trim()).expect("JSON");
    assert_eq!(v["simd"], grid);
}

/// `cloth run --simd LEVEL` runs the grid kernel at each level this CPU has, as
/// `simd` then says, and each level's cloth moves as the best level's does: their
/// kinetic energies after 200 steps of the bench agree to 1e-5 (the levels differ
/// only in how a lane's `1/sqrt` is rounded, about 1e-7 of a spring's force). A
/// name that is no level, or a level the CPU lacks, is refused before the run
/// with the levels named.
#[test]
fn run_simd_runs_the_loops_at_a_lower_level() {
    let grid = grid_simd_level();
    let levels = ["baseline", "avx2", "avx512"];
    let supported = &levels[..=levels.iter().position(|&l| l == grid).expect("a level")];
    let run = |level: &str| {
        let o = cloth(&[
            "run",
            "--scene",
            "bench",
            "--steps",
            "200",
            "--json",
            "--set",
            "width=24",
            "--set",
            "height=24",
            "--simd",
            level,
        ]);
        assert_eq!(o.status.code(), Some(0), "{level}: {}", stderr(&o));
        let v: serde_json::Value = serde_json::from_str(stdout(&o).trim()).expect("JSON");
        assert_eq!(v["engine"], "grid-f32");
        assert_eq!(v["simd"], level);
        v["energy"]["kinetic"].as_f64().expect("kinetic energy")
    };
    let best = run(grid);
    assert!(best > 1e-4, "the bench should be swinging: {best} J");
    for &level in supported {
        let kinetic = run(level);
        assert!(
            (kinetic - best).abs() <= 1e-5 * best,
            "{level}: {kinetic} J against {best} J at {grid}"
        );
    }
    for &level in &levels[supported.len()..] {
        let o = cloth(&["run", "--scene", "bench", "--steps", "1", "--simd", level]);
        assert_eq!(o.status.code(), Some(2), "{level}: {}", stderr(&o));
        assert!(stderr(&o).contains("this CPU cannot run"), "{}", stderr(&o));
    }
    let o = cloth(&["run", "--scene", "bench", "--steps", "1", "--simd", "avx9"]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    let message = stderr(&o);
    assert!(
        message.contains("--simd") && message.contains("baseline, avx2, avx512"),
        "{message}"
    );
}

/// The SIMD level the grid kernel (AVX-512F/VL with AVX2 and FMA, or AVX2 and
/// FMA) can run on this CPU.
#[cfg(target_arch = "x86_64")]
fn grid_simd_level() -> &'static str {
    let avx2 = is_x86_feature_detected!("avx2");
    let fma = is_x86_feature_detected!("fma");
    let avx512 = is_x86_feature_detected!("avx512f") && is_x86_feature_detected!("avx512vl");
    match (avx2 && fma, avx512) {
        (true, true) => "avx512",
        (true, false) => "avx2",
        (false, _) => "baseline",
    }
}

#[cfg(not(target_arch = "x86_64"))]
fn grid_simd_level() -> &'static str {
    "baseline"
}

#[test]
fn dump_with_zero_steps_writes_the_initial_state() {
    let path = std::env::temp_dir().join(format!("cloth-dump-{}.csv", std::process::id()));
    let o = cloth(&[
        "run",
        "--scene",
        "bench",
        "--steps",
        "0",
        "--dump",
        path.to_str().unwrap(),
        "--set",
        "width=4",
        "--set",
        "height=3",
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let text = std::fs::read_to_string(&path).unwrap();
    std::fs::remove_file(&path).ok();
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines[0], "index,x,y,z");
    assert_eq!(lines.len(), 1 + 12);
    // The peers' layout: particle r*N + c at (c h, 1 - r h, 0), h = 1/(N-1) over the width.
    let fields: Vec<f64> = lines[1 + 5]
        .split(',')
        .map(|f| f.parse().unwrap())
        .collect();
    let h = 1.0 / 3.0;
    assert_eq!(fields[0], 5.0);
    assert!(
        (fields[1] - h).abs() < 1e-12 && (fields[2] - (1.0 - h)).abs() < 1e-12 && fields[3] == 0.0,
        "{fields:?}"
    );
}

#[test]
fn divergence_exits_3_with_time_and_hint() {
    let o = cloth(&[
        "run",
        "--scene",
        "cloth",
        "--set",
        "stiffness=100000",
        "--duration",
        "1",
    ]);
    assert_eq!(o.status.code(), Some(3), "{}", stdout(&o));
    let err = stderr(&o);
    assert!(err.contains("diverged") && err.contains("t = "), "{err}");
    assert!(
        err.contains("smaller dt") && err.contains("implicit-euler"),
        "{err}"
    );
}

/// Past RK4's limit the undamped spring's growth saturates before anything
/// overflows; the energy budget catches it, and the message says by how much.
#[test]
fn energy_growth_without_overflow_exits_3_naming_the_energy_check() {
    // w = sqrt(k/m) = sqrt(30) rad/s; RK4 is stable for h w < 2 sqrt(2): h < 0.5164 s.
    let o = cloth(&[
        "run",
        "--scene",
        "spring",
        "--set",
        "damping_ratio=0",
        "--integrator",
        "rk4",
        "--dt",
        "0.52673",
        "--steps",
        "3000",
    ]);
    assert_eq!(o.status.code(), Some(3), "{}", stdout(&o));
    let err = stderr(&o);
    assert!(err.contains("as far as its budget allows"), "{err}");
    assert!(
        !err.contains("non-finite") && !err.contains("km/s"),
        "{err}"
    );
    // The same run at 0.9 of the limit ends normally.
    let o = cloth(&[
        "run",
        "--scene",
        "spring",
        "--set",
        "damping_ratio=0",
        "--integrator",
        "rk4",
        "--dt",
        "0.4648",
        "--steps",
        "3000",
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
}

#[test]
fn bad_input_exits_2_with_a_message() {
    for (args, needle) in [
        (vec!["run", "--scene", "nosuchscene"], "unknown scene"),
        (vec!["run", "--set", "particle_mass=-1"], "particle_mass"),
        (
            vec!["run", "--integrator", "leapfrog"],
            "--integrator leapfrog",
        ),
        (vec!["run", "--dt", "nan"], "--dt nan: `dt`"),
        (vec!["run", "--set", "width=0"], "width"),
        (
            vec!["info", "--scene", "/nonexistent/scene.toml"],
            "unknown scene",
        ),
        (vec!["run", "--steps", "-5"], "steps"),
    ] {
        let o = cloth(&args);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", stderr(&o));
        assert!(stderr(&o).contains(needle), "{args:?}: {}", stderr(&o));
        assert!(!stderr(&o).contains("panicked"), "{args:?} panicked");
    }
}

#[test]
fn a_scene_file_with_a_typo_names_file_and_key() {
    let path = std::env::temp_dir().join(format!("cloth-typo-{}.toml", std::process::id()));
    std::fs::write(&path, "layout = \"grid\"\nwidht = 10\n").unwrap();
    let o = cloth(&["info", "--scene", path.to_str().unwrap()]);
    std::fs::remove_file(&path).ok();
    assert_eq!(o.status.code(), Some(2));
    let err = stderr(&o);
    assert!(err.contains("widht") && err.contains("cloth-typo"), "{err}");
}

#[test]
fn info_reports_counts_terms_parameters_and_stability() {
    let o = cloth(&["info", "--scene", "cloth", "--json"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_str(stdout(&o).trim()).unwrap();
    assert_eq!(v["particles"], 1024);
    assert_eq!(v["springs_per_kind"]["structural"], 2 * 32 * 31);
    assert_eq!(v["triangles"], 2 * 31 * 31);
    let terms: Vec<&str> = v["force_terms"]
        .as_array()
        .unwrap()
        .iter()
        .map(|t| t.as_str().unwrap())
        .collect();
    assert!(
        terms.contains(&"aero-drag") && terms.contains(&"springs") && terms.contains(&"gravity")
    );
    assert!(v["stability"]["dt_over_dt_critical"].as_f64().unwrap() > 0.0);
    assert_eq!(v["parameters"]["integrator"], "symplectic-euler");
    assert_eq!(
        v["engine"], "grid-mixed",
        "k / m = 1e5 needs fixed-point positions"
    );
    let bench = cloth(&["info", "--scene", "bench", "--json"]);
    let v: serde_json::Value = serde_json::from_str(stdout(&bench).trim()).unwrap();
    assert_eq!(
        v["engine"], "grid-f32",
        "the peers' cloth is soft enough for float32"
    );
    let stiff = cloth(&[
        "info",
        "--scene",
        "cloth",
        "--set",
        "stiffness=1e6",
        "--json",
    ]);
    let v: serde_json::Value = serde_json::from_str(stdout(&stiff).trim()).unwrap();
    assert_eq!(
        v["engine"], "grid-f64",
        "float32 cannot resolve k = 1e6 N/m springs"
    );

    // With XPBD the springs are constraints: no force term, no step limit, and the
    // grid's precision follows the step, not the stiffness: its stiff springs act
    // as springs of stiffness `m / 2h²`, so fixed-point positions at the cloth's
    // 1/960 s steps even at 1e9 N/m, float32 ones at 1/60 s steps.
    let xpbd_info = |dt: &str| {
        let info = cloth(&[
            "info",
            "--scene",
            "cloth",
            "--set",
            "integrator=\"xpbd\"",
            "--set",
            "stiffness=1e9",
            "--set",
            dt,
            "--json",
        ]);
        serde_json::from_str::<serde_json::Value>(stdout(&info).trim()).unwrap()
    };
    let v = xpbd_info("dt=0.0010416666666666667");
    assert_eq!(v["engine"], "grid-mixed");
    assert_eq!(xpbd_info("dt=0.016666666666666666")["engine"], "grid-f32");
    assert!(
        !v["force_terms"]
            .as_array()
            .unwrap()
            .contains(&"springs".into())
    );
    assert!(
        v["constraints"][0].as_str().unwrap().contains("XPBD"),
        "{v}"
    );
    // The springs at 1e9 N/m set no limit; the wind's drag on the 1 g particles
    // does (a decay of about 17/s: 0.12 s), far above the step.
    let margin = v["stability"]["dt_over_dt_critical"].as_f64().unwrap();
    assert!(margin > 0.0 && margin < 0.01, "{v}");

    let chain = cloth(&["info", "--scene", "chain"]);
    let text = stdout(&chain);
    assert!(
        text.contains("particles: 11") && text.contains("air-damping"),
        "{text}"
    );
    assert!(!text.contains("aero-drag"), "{text}");
}

#[test]
fn scenes_lists_every_builtin() {
    let out = stdout(&cloth(&["scenes"]));
    for name in [
        "cloth",
        "corners",
        "flag",
        "spring",
        "chain",
        "jelly",
        "hanging",
        "rope",
        "sheet",
        "drape",
        "fold",
        "bench",
        "bench-wind",
    ] {
        assert!(
            out.lines().any(|l| l.starts_with(name)),
            "{name} missing:\n{out}"
        );
    }
}

#[test]
fn implicit_runs_report_their_solver_iterations() {
    let run = |integrator: &str| -> serde_json::Value {
        let o = cloth(&[
            "run",
            "--scene",
            "cloth",
            "--set",
            "width=8",
            "--set",
            "height=8",
            "--integrator",
            integrator,
            "--steps",
            "5",
            "--json",
        ]);
        assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
        serde_json::from_str(stdout(&o).trim()).unwrap()
    };
    assert!(
        run("implicit-euler")["cg_iterations_last_step"]
            .as_u64()
            .is_some_and(|n| n > 0)
    );
    assert!(run("symplectic-euler")["cg_iterations_last_step"].is_null());
}

#[test]
fn the_app_refuses_bad_input_before_looking_for_a_display() {
    // Exit 2 (bad input), not 1 (no display), even where there is no display.
    let o = Command::new(env!("CARGO_BIN_EXE_cloth"))
        .args(["--scene", "cloth", "--set", "width=0"])
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("width"));
}

#[test]
fn safe_stepping_follows_the_apps_rule_in_a_gale() {
    // A soft cloth in a gale gets the app's stretch limit from `cloth run --safe`
    // too (one rule for both), and stays finite; a gentle wind gets none.
    let gale = [
        "run",
        "--scene",
        "cloth",
        "--set",
        "stiffness=1",
        "--set",
        "wind=20,20,20",
        "--set",
        "gust=10",
        "--safe",
        "--duration",
        "0.5",
    ];
    let o = cloth(&gale);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("stretch limit is added"),
        "{}",
        stderr(&o)
    );
    let o = cloth(&["run", "--scene", "cloth", "--safe", "--steps", "10"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(!stderr(&o).contains("stretch limit"), "{}", stderr(&o));
}

/// Mesa's Vulkan driver complains twice when `XDG_RUNTIME_DIR` is missing (as in
/// containers and CI); the binary gives it a private one, so nothing is printed
/// about it, and the directory is gone at exit.
#[test]
fn a_missing_xdg_runtime_dir_is_not_reported() {
    let out = std::env::temp_dir().join(format!("cloth-xdg-{}.png", std::process::id()));
    let child = Command::new(env!("CARGO_BIN_EXE_cloth"))
        .args(["screenshot", "--scene", "chain", "--out"])
        .arg(&out)
        .env_remove("XDG_RUNTIME_DIR")
        .env_remove("WAYLAND_DISPLAY")
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let runtime_dir = std::env::temp_dir().join(format!("cloth-sandbox-runtime-{}", child.id()));
    let o = child.wait_with_output().unwrap();
    let _ = std::fs::remove_file(&out);
    assert!(!stderr(&o).contains("XDG_RUNTIME_DIR"), "{}", stderr(&o));
    assert!(
        !runtime_dir.exists(),
        "{} left behind",
        runtime_dir.display()
    );
}

#[test]
fn info_gives_the_precision_rules_reasons() {
    // The precision rule takes the first level whose float32 noise is under the
    // limit; `cloth info` shows the noise on each kind of positions, and the
    // fixed-point unit. The 32³ jelly at k = 2,000 N/m is over the limit on
    // float32 positions and under it on its tight fixed-point unit, 2^-25 m (on the
    // roomy 2^-23 m it would be 0.1188 m/s², over); the cloth at k = 1e5 N/m is
    // over it on both, and takes float64; the chain has no stencil kernel.
    let info = |args: &[&str]| -> serde_json::Value {
        let o = cloth(&[&["info", "--json"], args].concat());
        assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
        serde_json::from_str(stdout(&o).trim()).unwrap()
    };
    let cube = [
        "--set",
        "width=32",
        "--set",
        "height=32",
        "--set",
        "depth=32",
    ];
    let jelly = info(&[&["--scene", "jelly"], &cube[..]].concat());
    let p = &jelly["precision"];
    let noise = &p["float32_noise_m_per_s2"];
    let limit = noise["limit"].as_f64().unwrap();
    assert_eq!(limit, 0.0981);
    assert!(
        noise["on_float32_positions"].as_f64().unwrap() > limit,
        "{p}"
    );
    let fixed = noise["on_fixed_point_positions"].as_f64().unwrap();
    assert!((fixed - 0.0956).abs() < 1e-4, "{p}");
    let positions = p["positions"].as_str().unwrap();
    assert!(positions.starts_with("fixed point, unit 2^-25 m"), "{p}");
    assert_eq!(jelly["engine"], "lattice-mixed");
    let stiff = info(&["--scene", "cloth", "--set", "stiffness=1e5"]);
    let p = &stiff["precision"];
    assert_eq!(p["positions"], "float64");
    let fixed = &p["float32_noise_m_per_s2"]["on_fixed_point_positions"];
    assert!(fixed.as_f64().unwrap() > limit, "{p}");
    assert_eq!(stiff["engine"], "grid-f64");
    assert!(info(&["--scene", "chain"])["precision"].is_null());
}

/// `cloth info` takes the step flags `cloth run` takes, so that a newcomer can ask
/// about the run they are about to make: `--integrator` and `--dt` reach the
/// parameters, the constraints and the stability estimate, and a wrong value is
/// named by its flag.
#[test]
fn info_takes_the_runs_integrator_and_step_flags() {
    let info = |args: &[&str]| -> serde_json::Value {
        let o = cloth(&[&["info", "--json", "--scene", "jelly"], args].concat());
        assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
        serde_json::from_str(stdout(&o).trim()).unwrap()
    };
    let plain = info(&[]);
    let xpbd = info(&["--integrator", "xpbd", "--dt", "5e-4"]);
    assert_eq!(xpbd["parameters"]["integrator"], "xpbd");
    assert_eq!(xpbd["parameters"]["dt"].as_f64(), Some(5e-4));
    let constraints = xpbd["constraints"].to_string();
    assert!(constraints.contains("XPBD"), "{constraints}");
    assert_ne!(plain["parameters"]["integrator"], "xpbd");
    let o = cloth(&["info", "--scene", "jelly", "--integrator", "rk5"]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("--integrator rk5"), "{}", stderr(&o));
}

/// An integrator's name is taken in any case and with `_` or a space for `-`, as
/// a newcomer types it from the README's prose ("Verlet", "RK4"): `Verlet` had
/// been refused as "not an integrator".
#[test]
fn integrator_names_are_taken_in_any_case() {
    for (typed, name) in [
        ("Verlet", "verlet"),
        ("RK4", "rk4"),
        ("symplectic_euler", "symplectic-euler"),
        ("Implicit Euler", "implicit-euler"),
    ] {
        let o = cloth(&["info", "--scene", "chain", "--json", "--integrator", typed]);
        assert_eq!(o.status.code(), Some(0), "{typed}: {}", stderr(&o));
        let v: serde_json::Value = serde_json::from_str(stdout(&o).trim()).unwrap();
        assert_eq!(v["parameters"]["integrator"], name, "{typed}");
        let run = ["run", "--scene", "chain", "--steps", "2", "--json"];
        let o = cloth(&[&run[..], &["--integrator", typed]].concat());
        assert_eq!(o.status.code(), Some(0), "{typed}: {}", stderr(&o));
        let v: serde_json::Value = serde_json::from_str(stdout(&o).trim()).unwrap();
        assert_eq!(v["integrator"], name, "{typed}");
    }
    let o = cloth(&["run", "--scene", "chain", "--integrator", "euler"]);
    assert_eq!(
        o.status.code(),
        Some(2),
        "an ambiguous name: {}",
        stderr(&o)
    );
}

/// `--set stretch_limit=none` takes the sheet's limit away, as `cloth info` and a
/// run show (an empty list reads "none"), and a word other than `none` is refused
/// with what the key takes.
#[test]
fn none_takes_the_sheets_stretch_limit_away() {
    let info = |args: &[&str]| {
        let o = cloth(&[&["info", "--scene", "sheet"], args].concat());
        assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
        stdout(&o)
    };
    assert!(info(&[]).contains("constraints: stretch limit (10%)"));
    let off = info(&["--set", "stretch_limit=none"]);
    assert!(off.contains("constraints: none"), "{off}");
    let o = cloth(&["run", "--scene", "sheet", "--set", "stretch_limit=off"]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(
        stderr(&o)
            .contains("`stretch_limit` must be a number, got string \"off\"; `none` turns it off"),
        "{}",
        stderr(&o)
    );
}
