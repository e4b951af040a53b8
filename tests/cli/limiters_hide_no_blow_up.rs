//! A blow-up held back by a limiter (tearing, the speed limit,
//! the stretch limit) is not reported as a success.
//!
//! Theory decides which runs have blown up: explicit Euler has no stable step on
//! an undamped oscillator and, with the cloth's light damping, a limit of a
//! fraction of its step (`dt / dt_crit` = 3.1 on `tear`, 5.2 on `cloth`); on such
//! a step every mode the step touches grows, so a limiter that holds anything is
//! holding the blow-up. Symplectic Euler at the same step is within its limit.

use crate::binary::{cloth, stderr};

/// `cloth run` with `args`, its exit code, its JSON summary and its standard error.
fn run(args: &[&str]) -> (i32, serde_json::Value, String) {
    let mut all = vec!["run"];
    all.extend_from_slice(args);
    all.push("--json");
    let o = cloth(&all);
    let json = serde_json::from_slice(&o.stdout).unwrap_or(serde_json::Value::Null);
    (o.status.code().unwrap_or(-1), json, stderr(&o))
}

/// A reproducer: explicit Euler on `tear` broke every one of its 13,346
/// springs, spread the cloth over 98 m, and exited 0.
#[test]
fn explicit_euler_on_tear_is_a_divergence_that_names_tearing() {
    let (code, json, err) = run(&[
        "--scene",
        "tear",
        "--integrator",
        "explicit-euler",
        "--duration",
        "2",
    ]);
    assert_eq!(code, 3, "{err}");
    let message = json["diverged"]["message"].as_str().unwrap();
    assert!(message.contains("tearing held back a blow-up"), "{message}");
    assert!(message.contains("dt / dt_crit"), "{message}");
    assert!(message.contains("springs torn (tear_strain)"), "{message}");
    assert!(err.contains("tearing held back a blow-up"), "{err}");
}

/// Each limiter on the cloth: explicit Euler's blow-up under it is caught and the
/// message names the limiter and what it holds; symplectic Euler on the same
/// scene exits 0, and its summary says what the limiter holds without a warning.
#[test]
fn each_limiter_holding_a_blow_up_is_named_and_a_stable_run_is_not() {
    for (set, limiter, holds) in [
        (
            "max_speed=1",
            "the speed limit",
            "free particles at the speed cap (max_speed)",
        ),
        (
            "stretch_limit=0.1",
            "the stretch limit",
            "springs at the stretch limit (stretch_limit)",
        ),
        ("tear_strain=0.5", "tearing", "springs torn (tear_strain)"),
    ] {
        let blown = [
            "--scene",
            "cloth",
            "--set",
            set,
            "--integrator",
            "explicit-euler",
            "--duration",
            "2",
        ];
        let (code, json, err) = run(&blown);
        assert_eq!(code, 3, "{set}: {err}");
        let message = json["diverged"]["message"].as_str().unwrap();
        assert!(
            message.starts_with(&format!("{limiter} held back a blow-up")),
            "{set}: {message}"
        );
        assert!(message.contains(holds), "{set}: {message}");
        let stable = [
            "--scene",
            "cloth",
            "--set",
            set,
            "--integrator",
            "symplectic-euler",
            "--duration",
            "2",
        ];
        let (code, json, err) = run(&stable);
        assert_eq!(code, 0, "{set}: {err}");
        assert!(json["limiters"].is_object(), "{set}: {json}");
        assert!(json["limiters"]["warning"].is_null(), "{set}: {json}");
        assert!(!err.contains("warning"), "{set}: {err}");
    }
}

/// No false positive: every built-in scene at its defaults exits 0 with no
/// limiter warning (the `tear` scene tears 42 of its 13,346 springs, 0.3%).
#[test]
fn no_built_in_scene_at_its_defaults_is_flagged() {
    let o = cloth(&["scenes"]);
    let names = String::from_utf8_lossy(&o.stdout).into_owned();
    let names: Vec<&str> = names
        .lines()
        .filter_map(|l| l.split_whitespace().next())
        .filter(|n| std::path::Path::new(&format!("assets/scenes/{n}.toml")).exists())
        .collect();
    assert!(names.len() >= 16, "{names:?}");
    for name in names {
        let (code, json, err) = run(&["--scene", name]);
        assert_eq!(code, 0, "{name}: {err}");
        assert!(!err.contains("warning"), "{name}: {err}");
        if let Some(limiters) = json.get("limiters").filter(|l| l.is_object()) {
            assert!(limiters["warning"].is_null(), "{name}: {limiters}");
        }
    }
}

/// Within the stability limit a limiter that holds much of the cloth is a
/// warning, in the summary and the JSON: a speed cap the falling cloth reaches
/// everywhere (0.01 m/s).
#[test]
fn a_limiter_doing_much_of_the_work_within_the_limit_is_a_warning() {
    let (code, json, err) = run(&[
        "--scene",
        "cloth",
        "--set",
        "max_speed=0.01",
        "--duration",
        "1",
    ]);
    assert_eq!(code, 0, "{err}");
    let warning = json["limiters"]["warning"].as_str().unwrap();
    assert!(
        warning.contains("at the speed cap (max_speed)"),
        "{warning}"
    );
    assert!(
        err.contains("warning: limiters hold much of the motion"),
        "{err}"
    );
}
