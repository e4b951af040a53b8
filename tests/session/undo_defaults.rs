//! Undo, redo and "Defaults", headless: parameter edits and pins come back in
//! place (no rebuild) unless the layout changed, a dragged slider makes one undo
//! step, and the defaults are the scene as it was loaded, bit for bit.

use cloth_sandbox::scene::{PinPreset, Pins};
use cloth_sandbox::session::{Edit, Session};
use glam::DVec3;

fn cloth() -> Session {
    Session::load_with("cloth", &[]).expect("the cloth loads")
}

/// Whether every spring's kind has stiffness `k` (N/m).
fn every_spring_has_stiffness(s: &Session, k: f64) -> bool {
    let model = s.system().model();
    model
        .springs
        .iter()
        .all(|sp| model.material(sp.kind).stiffness == k)
}

fn bits(s: &Session) -> Vec<[u64; 3]> {
    s.system()
        .positions()
        .iter()
        .map(|p| [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()])
        .collect()
}

#[test]
fn undo_and_redo_a_parameter_edit_in_place() {
    let mut s = cloth();
    let k0 = s.settings().stiffness;
    assert!(!s.can_undo() && !s.can_redo());
    assert!(!s.undo().expect("no error"), "nothing to undo yet");
    s.system_mut().run(20).expect("stable");
    s.apply(Edit::Stiffness(300.0)).expect("applies");
    let t = s.system().time();
    let x = bits(&s);
    assert!(s.undo().expect("undoes"));
    assert_eq!(s.settings().stiffness, k0);
    assert!(every_spring_has_stiffness(&s, k0));
    // In place: same time and positions, no rebuild.
    assert_eq!(s.system().time(), t);
    assert_eq!(bits(&s), x);
    assert!(s.can_redo());
    assert!(s.redo().expect("redoes"));
    assert_eq!(s.settings().stiffness, 300.0);
    assert!(every_spring_has_stiffness(&s, 300.0));
    assert!(!s.redo().expect("no error"), "nothing left to redo");
}

#[test]
fn a_dragged_slider_is_one_undo_step_and_a_new_drag_another() {
    let mut s = cloth();
    let k0 = s.settings().stiffness;
    // One drag: many edits of one key.
    for k in [110.0, 120.0, 130.0, 140.0] {
        s.apply(Edit::Stiffness(k)).expect("applies");
    }
    s.end_edit_group();
    // A second drag of the same slider.
    for k in [150.0, 160.0] {
        s.apply(Edit::Stiffness(k)).expect("applies");
    }
    // A different slider in the same gesture is a step of its own.
    s.apply(Edit::Gust(0.25)).expect("applies");
    s.end_edit_group();
    assert!(s.undo().expect("undoes"));
    assert_eq!(s.settings().params.gust, 1.0);
    assert_eq!(s.settings().stiffness, 160.0);
    assert!(s.undo().expect("undoes"));
    assert_eq!(s.settings().stiffness, 140.0);
    assert!(s.undo().expect("undoes"));
    assert_eq!(s.settings().stiffness, k0);
    assert!(!s.can_undo());
}

#[test]
fn a_new_change_after_undo_forgets_the_redo() {
    let mut s = cloth();
    s.apply(Edit::Damping(0.05)).expect("applies");
    s.undo().expect("undoes");
    s.apply(Edit::Gravity(DVec3::new(0.0, -5.0, 0.0)))
        .expect("applies");
    assert!(!s.can_redo());
}

#[test]
fn pins_undo_and_redo_in_place() {
    let mut s = cloth();
    let original = s.pins();
    s.system_mut().run(30).expect("stable");
    s.set_pins(Pins::Preset(PinPreset::TopEdge)).expect("pins");
    let top_edge = s.pins();
    s.toggle_pin(500);
    let x = bits(&s);
    assert!(s.undo().expect("undoes the click"));
    assert_eq!(s.pins(), top_edge);
    assert!(s.undo().expect("undoes the preset"));
    assert_eq!(s.pins(), original);
    assert_eq!(bits(&s), x, "undoing pins moves nothing");
    assert!(s.redo().expect("redoes"));
    assert_eq!(s.pins(), top_edge);
    // A reset keeps what undo left.
    s.reset().expect("resets");
    assert_eq!(s.pins(), top_edge);
}

#[test]
fn undoing_a_width_edit_rebuilds_the_old_layout() {
    let mut s = cloth();
    let n = s.system().particle_count();
    s.apply(Edit::Width(20)).expect("applies");
    assert_ne!(s.system().particle_count(), n);
    s.undo().expect("undoes");
    assert_eq!(s.system().particle_count(), n);
    assert_eq!(s.pins(), vec![0, 31]);
}

#[test]
fn the_wind_switch_is_one_undo_step() {
    let mut s = cloth();
    s.set_wind_on(false).expect("off");
    s.undo().expect("undoes");
    assert!(s.wind_on());
    assert_eq!(s.settings(), cloth().settings());
}

#[test]
fn defaults_restore_the_scene_as_loaded_and_can_be_undone() {
    let mut s = cloth();
    let fresh = cloth();
    s.apply(Edit::Stiffness(250.0)).expect("applies");
    s.apply(Edit::ParticleMass(0.002)).expect("applies");
    s.apply(Edit::RestLength(0.04)).expect("applies");
    s.apply(Edit::Height(20)).expect("applies");
    s.set_pins(Pins::Preset(PinPreset::Corners)).expect("pins");
    let edited = s.settings().clone();
    s.restore_defaults().expect("restores");
    assert_eq!(s.settings(), fresh.settings());
    assert_eq!(s.pins(), fresh.pins());
    assert_eq!(s.scene().spec, fresh.scene().spec);
    // From its start, the restored run is the unedited run, bit for bit.
    let mut fresh = fresh;
    s.reset().expect("resets");
    s.system_mut().run(200).expect("stable");
    fresh.system_mut().run(200).expect("stable");
    assert_eq!(bits(&s), bits(&fresh));
    // And "Defaults" itself can be undone.
    s.undo().expect("undoes");
    assert_eq!(s.settings(), &edited);
}

#[test]
fn defaults_keep_the_command_lines_overrides() {
    let mut s = Session::load_with("cloth", &["stiffness=50".to_string()]).expect("loads");
    s.apply(Edit::Stiffness(400.0)).expect("applies");
    s.restore_defaults().expect("restores");
    assert_eq!(s.settings().stiffness, 50.0);
}

/// The panel's dt slider keeps the speed: every dt it passes through comes with
/// the steps per frame that keep the simulated time per frame (to the nearest
/// step), and the whole drag is one undo step that brings both back.
#[test]
fn a_dt_drag_keeps_the_speed_and_is_one_undo_step() {
    let mut s = cloth();
    let (dt0, steps0) = (s.settings().params.dt, s.settings().substeps);
    let frame_time = dt0 * f64::from(steps0);
    // Down, then up in small steps to 12 times dt (rounding to whole steps at
    // each one must not drift the speed), then back.
    let up = (0..=40).map(|i| dt0 * 0.25 * 48f64.powf(f64::from(i) / 40.0));
    for dt in [dt0 * 0.9, dt0 * 0.5]
        .into_iter()
        .chain(up)
        .chain([dt0 * 0.3])
    {
        s.apply_dt_keeping_speed(dt).unwrap();
        let r = s.settings();
        assert_eq!(r.params.dt, dt);
        let kept = r.params.dt * f64::from(r.substeps);
        assert!(
            (kept - frame_time).abs() <= 0.5 * dt,
            "dt {dt}: {} steps give {kept} s per frame, not {frame_time}",
            r.substeps
        );
    }
    assert_ne!(s.settings().substeps, steps0);
    s.end_edit_group();
    assert!(s.undo().unwrap());
    assert_eq!(
        (s.settings().params.dt, s.settings().substeps),
        (dt0, steps0)
    );
    assert!(!s.can_undo(), "the drag left more than one undo step");
}

#[test]
fn defaults_turn_safe_stepping_back_on() {
    let mut s = cloth();
    s.set_safe_stepping(false);
    s.apply(Edit::Stiffness(5e4)).unwrap();
    assert!(s.step_choice().is_none());
    s.restore_defaults().expect("restores");
    assert!(s.safe_stepping());
    assert!(s.step_choice().is_some_and(|c| c.safe));
}
