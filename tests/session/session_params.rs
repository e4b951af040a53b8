//! The parameter changes the panel makes, headless: live edits keep the state,
//! rest length rescales the springs, width/height rebuild the cloth keeping the
//! other settings, and divergence pauses with a report.

use cloth_sandbox::session::Session;
use cloth_sandbox::sim::SpringKind;

fn cloth() -> Session {
    Session::load_with("cloth", &[]).expect("the default cloth loads")
}

#[test]
fn stiffness_applies_live_without_resetting_the_state() {
    let mut s = cloth();
    for _ in 0..20 {
        s.single_step();
    }
    let before = s.system().positions().to_vec();
    let steps = s.system().steps_taken();
    s.set("stiffness", "250").unwrap();
    assert_eq!(
        s.system().steps_taken(),
        steps,
        "a live edit must not rebuild"
    );
    assert_eq!(s.system().positions(), &before[..]);
    let structural = s
        .system()
        .springs()
        .iter()
        .find(|sp| sp.kind == SpringKind::Structural)
        .unwrap();
    assert_eq!(
        s.system().model().material(structural.kind).stiffness,
        250.0
    );
}

#[test]
fn rest_length_changes_the_springs_rest_lengths_live() {
    let mut s = cloth();
    let old: Vec<f64> = s.system().springs().iter().map(|sp| sp.rest).collect();
    let r0 = s.scene().resolve().unwrap().rest_length;
    s.set("rest_length", &(r0 * 1.5).to_string()).unwrap();
    assert_eq!(s.system().steps_taken(), 0);
    for (sp, o) in s.system().springs().iter().zip(&old) {
        assert!(
            (sp.rest - o * 1.5).abs() < 1e-12,
            "{} vs {}",
            sp.rest,
            o * 1.5
        );
    }
}

#[test]
fn width_and_height_rebuild_the_cloth_keeping_other_settings() {
    let mut s = cloth();
    s.set("stiffness", "321").unwrap();
    s.set("wind", "1,0,3").unwrap();
    s.set("particle_mass", "0.002").unwrap();
    s.set("width", "12").unwrap();
    s.set("height", "9").unwrap();
    let sys = s.system();
    assert_eq!(sys.particle_count(), 12 * 9);
    assert_eq!(sys.triangles().len(), 2 * 11 * 8);
    let structural = sys
        .springs()
        .iter()
        .find(|sp| sp.kind == SpringKind::Structural)
        .unwrap();
    assert_eq!(sys.model().material(structural.kind).stiffness, 321.0);
    assert_eq!(sys.params().wind, glam::DVec3::new(1.0, 0.0, 3.0));
    assert!(sys.masses().iter().all(|&m| m == 0.002));
    // The rebuilt cloth is pinned by the scene's preset again.
    assert!((0..sys.particle_count()).any(|i| sys.is_pinned(i)));
}

#[test]
fn a_bad_value_changes_nothing() {
    let mut s = cloth();
    let before = s.scene().clone();
    assert!(s.set("width", "-3").is_err());
    assert!(s.set("stiffness", "banana").is_err());
    assert_eq!(s.scene(), &before);
}

#[test]
fn reset_keeps_edits_and_drops_clicked_pins() {
    let mut s = cloth();
    s.set("stiffness", "222").unwrap();
    s.system_mut().set_pinned(100, true);
    for _ in 0..5 {
        s.single_step();
    }
    s.reset().unwrap();
    assert_eq!(s.system().steps_taken(), 0);
    assert!(!s.system().is_pinned(100));
    assert_eq!(s.scene().resolve().unwrap().stiffness, 222.0);
}

#[test]
fn divergence_pauses_and_reports_the_margin() {
    let mut s = cloth();
    // Safe stepping (on by default) would prevent the divergence this test provokes.
    s.set_safe_stepping(false);
    s.set("integrator", "explicit-euler").unwrap();
    s.set("stiffness", "100000").unwrap();
    s.set("dt", "0.01").unwrap();
    for _ in 0..10_000 {
        s.single_step();
        if s.divergence().is_some() {
            break;
        }
    }
    let d = s
        .divergence()
        .expect("explicit Euler with a huge step diverges");
    assert!(s.paused());
    assert!(!d.message.is_empty());
    assert!(d.margin.is_some_and(|m| m > 1.0), "{:?}", d.margin);
    // The view freezes on the last frame that passed its checks: finite, and
    // before the divergence.
    assert!(d.shown_time < d.time, "{} {}", d.shown_time, d.time);
    assert_eq!(s.system().time(), d.shown_time);
    let state = s.system().state();
    assert!(
        state
            .positions
            .iter()
            .chain(&state.velocities)
            .all(|p| p.is_finite())
    );
    // Frames do nothing until reset.
    assert_eq!(s.frame(0.1).steps, 0);
    s.reset().unwrap();
    assert!(s.divergence().is_none());
}

#[test]
fn frames_run_at_the_fixed_step_whatever_the_frame_rate() {
    let mut a = cloth();
    let mut b = cloth();
    // 1/6 s of wall time: in 10 frames of 1/60 s, or 40 of 1/240 s.
    let sa: u32 = (0..10).map(|_| a.frame(1.0 / 60.0).steps).sum();
    let sb: u32 = (0..40).map(|_| b.frame(1.0 / 240.0).steps).sum();
    assert!(sa.abs_diff(sb) <= 1, "{sa} vs {sb}");
}

#[test]
fn paused_frames_do_not_step_but_single_step_does() {
    let mut s = cloth();
    s.set_paused(true);
    assert_eq!(s.frame(0.1).steps, 0);
    assert_eq!(s.single_step().steps, 1);
    assert_eq!(s.system().steps_taken(), 1);
}
