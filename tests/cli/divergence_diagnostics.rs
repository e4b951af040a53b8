//! Honest diagnostics: a divergence on the grid kernel is reported at the step
//! where it happened (as the f64 engine reports it), not at the end of the kernel's
//! 32-step chunk; `max_speed` of a non-finite state is not a number; `cloth
//! screenshot` exits 3 when the simulation diverges; and the hints are true for the
//! case at hand (heavy damping has a small stable step; a sphere holding particles
//! at the start is refused with a message).

use crate::binary::{cloth, stderr};

use cloth_sandbox::scene::Scene;
use cloth_sandbox::sim::max_speed;
use glam::DVec3;

fn diverged(args: &[&str]) -> serde_json::Value {
    let o = cloth(args);
    assert_eq!(o.status.code(), Some(3), "{args:?}: {}", stderr(&o));
    serde_json::from_slice(&o.stdout).expect("one JSON object")
}

#[test]
fn the_grid_kernel_reports_the_true_divergence_step() {
    let base = ["run", "--set", "dt=1", "--steps", "50", "--json"];
    let fast = diverged(&base);
    let engine = fast["engine"].as_str().unwrap();
    assert!(
        engine.starts_with("grid-"),
        "the grid kernel runs it: {engine}"
    );
    let exact = diverged(&[&base[..], &["--exact"]].concat());
    assert_eq!(fast["diverged"]["step"], exact["diverged"]["step"]);
    assert_eq!(fast["steps"], exact["steps"]);
    assert!(fast["diverged"]["step"].as_u64().unwrap() < 32, "{fast}");
    assert_eq!(fast["diverged"]["time"], exact["diverged"]["time"]);
}

#[test]
fn xpbd_on_the_grid_kernel_reports_the_true_divergence_step() {
    // A microgram cloth in the wind: the drag throws it off within a few steps on
    // either engine. The grid kernel finds it at the end of a chunk and replays the
    // chunk from its start, which must give the f64 engine's step: the replay found
    // "non-finite at step 1" while XPBD's pass moved ghost particles by `0 d` with
    // `d` infinite, leaving them NaN for the replay.
    let base = [
        "run",
        "--integrator",
        "xpbd",
        "--set",
        "particle_mass=1e-6",
        "--steps",
        "50",
        "--json",
    ];
    let fast = diverged(&base);
    assert_eq!(fast["engine"], "grid-mixed");
    let exact = diverged(&[&base[..], &["--exact"]].concat());
    assert_eq!(
        fast["diverged"]["step"], exact["diverged"]["step"],
        "{fast}"
    );
    assert_eq!(fast["diverged"]["message"], exact["diverged"]["message"]);
    // Safe stepping and implicit Euler step the drag explicitly too (both run away
    // at step 4 here); a smaller step is what helps (dt = 1e-4 s runs through).
    let hint = fast["diverged"]["hint"].as_str().unwrap();
    assert!(
        hint.contains("smaller dt") && !hint.contains("--safe"),
        "{hint}"
    );
    let slower = cloth(&[&base[..5], &["--set", "dt=1e-4", "--steps", "2000"]].concat());
    assert_eq!(slower.status.code(), Some(0), "{}", stderr(&slower));
}

#[test]
fn the_grid_kernel_finds_a_divergence_late_in_a_long_run_at_its_step() {
    // Explicit Euler runs away after a few dozen steps: the step found between
    // full checks must match the f64 engine's.
    let base = [
        "run",
        "--integrator",
        "explicit-euler",
        "--steps",
        "5000",
        "--json",
    ];
    let fast = diverged(&base);
    let exact = diverged(&[&base[..], &["--exact"]].concat());
    let (a, b) = (
        fast["diverged"]["step"].as_i64().unwrap(),
        exact["diverged"]["step"].as_i64().unwrap(),
    );
    // f32 against f64 may differ by the round-off of a step, never by a chunk.
    assert!((a - b).abs() <= 1, "grid kernel step {a}, f64 step {b}");
}

#[test]
fn max_speed_of_a_non_finite_state_is_not_a_number() {
    assert!(max_speed(&[DVec3::ONE, DVec3::new(f64::NAN, 0.0, 0.0)]).is_nan());
    assert!(max_speed(&[DVec3::new(0.0, f64::INFINITY, 0.0)]).is_nan());
    assert_eq!(max_speed(&[DVec3::new(3.0, 4.0, 0.0)]), 5.0);
}

#[test]
fn screenshot_exits_3_when_the_simulation_diverges() {
    let out = std::env::temp_dir().join(format!("cloth-diverged-shot-{}.png", std::process::id()));
    // Explicit Euler without any damping has no stable step, so safe stepping (on
    // in the screenshot, as in the app) cannot save it.
    let o = cloth(&[
        "screenshot",
        "--set",
        "stiffness=1e9",
        "--set",
        "damping=0",
        "--set",
        "air_damping=0",
        "--set",
        "drag_coefficient=0",
        "--set",
        "integrator=explicit-euler",
        "--steps",
        "50",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(3), "{}", stderr(&o));
    assert!(stderr(&o).contains("diverged"), "{}", stderr(&o));
    assert!(!out.exists(), "no picture of a diverged run");
}

#[test]
fn heavy_damping_has_a_small_stable_step_and_the_hint_says_so() {
    let o = cloth(&["info", "--json", "--set", "damping=1e9"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let critical = v["stability"]["dt_critical"].as_f64();
    assert!(
        critical.is_some_and(|c| c > 0.0 && c < 1e-9),
        "a finite, small critical step: {v}"
    );
    let o = cloth(&["run", "--set", "damping=1e9", "--steps", "10"]);
    assert_eq!(o.status.code(), Some(3), "{}", stderr(&o));
    let err = stderr(&o);
    assert!(!err.contains("no stable step"), "{err}");
    assert!(err.contains("smaller dt"), "{err}");
    // The smaller step the hint points to is stable.
    let o = cloth(&[
        "run",
        "--set",
        "damping=1e9",
        "--steps",
        "10",
        "--dt",
        "1e-14",
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
}

#[test]
fn the_hint_does_not_suggest_the_integrator_in_use() {
    // A free fall under a huge gravity runs away with any integrator.
    let o = cloth(&[
        "run",
        "--integrator",
        "implicit-euler",
        "--set",
        "pins=none",
        "--set",
        "gravity=0,-1e4,0",
        "--set",
        "air_density=0",
        "--set",
        "dt=1",
        "--steps",
        "100",
    ]);
    assert_eq!(o.status.code(), Some(3), "{}", stderr(&o));
    let err = stderr(&o);
    assert!(err.contains("hint:"), "{err}");
    assert!(!err.contains("implicit-euler"), "{err}");
    assert!(
        err.contains("within the estimated stability limit"),
        "{err}"
    );
}

#[test]
fn a_cloth_stretched_past_the_estimate_gets_a_step_that_runs_and_safe_stepping_follows_its_areas() {
    // The peers' bench cloth in its wind at 128 x 128 hangs far past its springs'
    // rest length under its weight (1 kg on 0.3 N/m springs), so its drag works on
    // many times the rest areas that the step limit at rest is estimated on; with
    // Verlet, whose damping limit is half symplectic Euler's, it runs away at the
    // scene's step: at 1.83 s on the f64 engine, and between 1.7 and 2.2 s on
    // builds of the f32 engine that round differently (the runaway's growth
    // amplifies its rounding), so the runs last 3 s. The hint says the estimate
    // took the areas at rest, and gives a step that runs. Safe stepping now
    // watches the areas as they grow and cuts the step (it had kept the step
    // chosen at rest, and ran away as early).
    let run = |dt: &str, safe: bool| {
        let mut args = vec![
            "run",
            "--scene",
            "bench-wind",
            "--set",
            "width=128",
            "--set",
            "height=128",
            "--integrator",
            "verlet",
            "--duration",
            "3",
            "--dt",
            dt,
        ];
        if safe {
            args.push("--safe");
        }
        cloth(&args)
    };
    let scene_dt = "0.0010416666666666667";
    let o = run(scene_dt, false);
    assert_eq!(o.status.code(), Some(3), "{}", stderr(&o));
    let err = stderr(&o);
    let hint = err.lines().find(|l| l.starts_with("hint:")).expect(&err);
    assert!(
        hint.contains("within the estimated stability limit")
            && hint.contains("drag areas at rest"),
        "{hint}"
    );
    assert!(hint.contains("--safe"), "{hint}");
    let dt = hint
        .split("--dt ")
        .nth(1)
        .and_then(|rest| rest.split([',', ' ']).next())
        .expect(hint);
    assert_eq!(dt.parse::<f64>().ok(), Some(5.208e-4), "{hint}");
    let o = run(dt, false);
    assert_eq!(o.status.code(), Some(0), "--dt {dt}: {}", stderr(&o));
    let o = run(scene_dt, true);
    assert_eq!(o.status.code(), Some(0), "--safe: {}", stderr(&o));
    assert!(
        stderr(&o).contains("the cloth's drag areas have grown"),
        "{}",
        stderr(&o)
    );
}

#[test]
fn a_sphere_overlapping_the_cloth_at_the_start_pushes_it_out_at_build_time() {
    let mut scene = Scene::load("drape").unwrap();
    scene.set("sphere_center", "0,1,0").unwrap();
    let system = scene.build().unwrap();
    let sphere = system.params().sphere.unwrap();
    let inside = system
        .positions()
        .iter()
        .filter(|x| x.distance(sphere.center) < sphere.radius * (1.0 - 1e-12))
        .count();
    assert_eq!(inside, 0, "every particle starts on or outside the sphere");
    // Used to diverge with every integrator, the hint suggesting implicit Euler
    // even to implicit Euler.
    for integrator in ["implicit-euler", "symplectic-euler", "xpbd"] {
        let o = cloth(&[
            "run",
            "--scene",
            "drape",
            "--set",
            "sphere_center=0,1,0",
            "--integrator",
            integrator,
            "--duration",
            "0.5",
        ]);
        assert_eq!(o.status.code(), Some(0), "{integrator}: {}", stderr(&o));
    }
}
