//! A session on the GPU engine (`cloth --engine gpu`, the panel's choice): its
//! frames follow the CPU engine's run, edits reach it, and a scene it does not
//! step runs on the CPU saying why. Without an adapter the tests print a note
//! and pass, unless `CLOTH_REQUIRE_ADAPTER` is set.

use cloth_sandbox::session::{Edit, Session};

fn cloth(gpu: bool) -> Option<Session> {
    let size = ["width=12".to_string(), "height=12".to_string()];
    let mut s = Session::load_with("cloth", &size).unwrap();
    if gpu && let Err(e) = s.set_gpu(true) {
        assert!(std::env::var_os("CLOTH_REQUIRE_ADAPTER").is_none(), "{e}");
        eprintln!("note: skipped, no GPU engine: {e}");
        return None;
    }
    Some(s)
}

/// Largest distance (m) between the two sessions' particles.
fn apart(a: &Session, b: &Session) -> f64 {
    let (a, b) = (a.system().positions(), b.system().positions());
    a.iter()
        .zip(b)
        .map(|(p, q)| p.distance(*q))
        .fold(0.0, f64::max)
}

#[test]
fn a_session_on_the_gpu_follows_the_cpu_and_its_edits() {
    let (Some(mut gpu), Some(mut cpu)) = (cloth(true), cloth(false)) else {
        return;
    };
    assert!(gpu.on_gpu() && gpu.gpu_problem().is_none());
    assert!(gpu.gpu_adapter().is_some());
    let span = 0.55; // the 12 x 12 cloth's side (m)
    for round in 0..3 {
        for _ in 0..15 {
            gpu.step_frame();
            cpu.step_frame();
        }
        let d = apart(&gpu, &cpu);
        eprintln!("round {round}: {d:e} m apart");
        assert!(d < 1e-3 * span, "round {round}: {d:e} m apart");
        // An edit reaches the GPU engine: both runs step the new stiffness (an
        // engine that kept the old one ends 4 cm away after the first edit).
        for s in [&mut gpu, &mut cpu] {
            s.apply(Edit::Stiffness(100.0 * 3f64.powi(round + 1)))
                .unwrap();
        }
    }
    assert_eq!(gpu.system().time(), cpu.system().time());
    assert!(gpu.divergence().is_none());
    gpu.set_gpu(false).unwrap();
    assert!(!gpu.on_gpu() && gpu.gpu_adapter().is_none());
}

#[test]
fn a_scene_the_gpu_engine_does_not_step_runs_on_the_cpu_and_says_why() {
    let Some(mut s) = cloth(true) else {
        return;
    };
    s.apply(Edit::TearStrain(Some(0.5))).unwrap();
    let t = s.system().time();
    s.step_frame();
    assert!(s.system().time() > t, "no steps");
    let why = s.gpu_problem().expect("a reason").to_string();
    assert!(why.contains("tearing"), "{why}");
    // Taken back, it steps on the GPU again.
    s.apply(Edit::TearStrain(None)).unwrap();
    s.step_frame();
    assert_eq!(s.gpu_problem(), None);
}
