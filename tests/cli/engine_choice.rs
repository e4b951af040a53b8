//! `--engine cpu|gpu|auto`: the GPU engine when asked for and able, a refusal in
//! one line when not (no adapter: exit 1; a scene it does not step: exit 2), and
//! `auto` on the CPU, saying why when it looked for a GPU. `WGPU_BACKEND=dx12`
//! leaves a Linux machine without any adapter.

use std::process::{Command, Output};

use crate::binary::{cloth, stderr, stdout};

/// `cloth args` with no graphics adapter to be had.
fn without_adapter(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_cloth"))
        .args(args)
        .env("WGPU_BACKEND", "dx12")
        .output()
        .expect("runs")
}

fn json(o: &Output) -> serde_json::Value {
    serde_json::from_str(&stdout(o)).unwrap_or_else(|e| panic!("{e}: {}", stdout(o)))
}

/// The one line said, which names the flag.
fn one_line(o: &Output) -> String {
    let err = stderr(o);
    let lines: Vec<&str> = err
        .lines()
        .filter(|l| !l.contains("XDG_RUNTIME_DIR"))
        .collect();
    assert_eq!(lines.len(), 1, "{err}");
    lines[0].to_string()
}

#[test]
fn gpu_without_an_adapter_is_refused_in_one_line() {
    let run = [
        "run", "--scene", "cloth", "--steps", "10", "--engine", "gpu",
    ];
    let info = ["info", "--scene", "cloth", "--engine", "gpu"];
    let dir = tempfile_dir();
    let png = dir.join("shot.png");
    let shot = [
        "screenshot",
        "--engine",
        "gpu",
        "--out",
        png.to_str().unwrap(),
    ];
    for args in [&run[..], &info[..], &shot[..]] {
        let o = without_adapter(args);
        assert_eq!(o.status.code(), Some(1), "{args:?}: {}", stderr(&o));
        let line = one_line(&o);
        assert!(
            line.contains("--engine gpu") && line.contains("no GPU adapter"),
            "{line}"
        );
        assert!(stdout(&o).is_empty(), "{args:?}");
    }
    assert!(!png.exists(), "a refused screenshot left a file");
    // The app, before any window.
    let o = without_adapter(&["--engine", "gpu"]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    let line = one_line(&o);
    assert!(
        line.contains("--engine gpu") && line.contains("no GPU adapter"),
        "{line}"
    );
}

#[test]
fn auto_falls_back_to_the_cpu_and_says_so() {
    // Big enough for auto to look for a GPU, and none to be had.
    let args = [
        "run",
        "--scene",
        "bench",
        "--set",
        "width=256",
        "--set",
        "height=256",
    ];
    let o = without_adapter(&[&args[..], &["--steps", "1", "--json"]].concat());
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let line = one_line(&o);
    assert!(line.starts_with("--engine auto: the CPU engine"), "{line}");
    assert_ne!(json(&o)["engine"], "gpu");
    // A small cloth does not look, and says nothing.
    let o = without_adapter(&["run", "--scene", "cloth", "--steps", "1", "--json"]);
    assert_eq!(o.status.code(), Some(0));
    assert!(!stderr(&o).contains("--engine"), "{}", stderr(&o));
    assert_ne!(json(&o)["engine"], "gpu");
}

#[test]
fn what_the_gpu_engine_cannot_step_is_refused_with_the_reason() {
    for (scene, reason) in [
        ("fold", "self-collision"),
        ("rope", "bars"),
        ("cloth", "rk4"),
    ] {
        let mut args = vec!["run", "--scene", scene, "--steps", "1", "--engine", "gpu"];
        if reason == "rk4" {
            args.extend(["--integrator", "rk4"]);
        }
        let o = cloth(&args);
        assert_eq!(o.status.code(), Some(2), "{scene}: {}", stderr(&o));
        let line = one_line(&o);
        assert!(
            line.contains("--engine gpu") && line.contains(reason),
            "{line}"
        );
    }
    let o = cloth(&["run", "--scene", "cloth", "--engine", "gpx"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(one_line(&o).contains("cpu, gpu or auto"));
    let o = cloth(&["run", "--scene", "cloth", "--exact", "--engine", "gpu"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(one_line(&o).contains("--exact"));
}

#[test]
fn gpu_runs_name_the_adapter_and_agree_with_the_cpu() {
    let args = [
        "run", "--scene", "cloth", "--steps", "480", "--json", "--engine",
    ];
    let gpu = cloth(&[&args[..], &["gpu"]].concat());
    if gpu.status.code() == Some(1) && std::env::var_os("CLOTH_REQUIRE_ADAPTER").is_none() {
        eprintln!("note: no adapter, skipped: {}", stderr(&gpu));
        return;
    }
    assert_eq!(gpu.status.code(), Some(0), "{}", stderr(&gpu));
    let (gpu, cpu) = (json(&gpu), json(&cloth(&[&args[..], &["cpu"]].concat())));
    assert_eq!(gpu["engine"], "gpu");
    assert!(gpu["adapter"].as_str().is_some_and(|a| !a.is_empty()));
    assert!(cpu["adapter"].is_null() && cpu["engine"] != "gpu");
    // GPU time a step, where the adapter has timestamps: within the wall
    // clock's time a step, which holds it and the upload and readback.
    let wall = gpu["wall_time"].as_f64().unwrap() / 480.0;
    match gpu["gpu_seconds_per_step"].as_f64() {
        Some(t) => assert!(
            t > 0.0 && t <= wall,
            "{t} s a step on the GPU, {wall} s by the wall"
        ),
        None => assert!(gpu["gpu_seconds_per_step"].is_null()),
    }
    assert!(cpu["gpu_seconds_per_step"].is_null());
    // Both engines are checked against the f64 one elsewhere; here, that the run
    // is the same run: energy within 1e-5 relative after 0.5 s.
    let energy = |v: &serde_json::Value| v["energy"]["total"].as_f64().unwrap();
    let (e_gpu, e_cpu) = (energy(&gpu), energy(&cpu));
    assert!(
        ((e_gpu - e_cpu) / e_cpu).abs() < 1e-5,
        "{e_gpu} J on the GPU, {e_cpu} J on the CPU"
    );
    let info = json(&cloth(&[
        "info", "--scene", "cloth", "--engine", "gpu", "--json",
    ]));
    assert_eq!(
        (&info["engine"], &info["adapter"]),
        (&gpu["engine"], &gpu["adapter"])
    );
}

/// A new empty folder under the system's temporary one.
fn tempfile_dir() -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("cloth-engine-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}
