//! The live reference: the shown run stepped again by RK4 at dt / REFINE on its
//! own thread, and the error between the two. Checked against the analytic
//! oscillator, against the order of the shown integrator, and for starting
//! again from the shown state after each edit.

use std::time::Duration;

use crate::common::spring_oscillator;
use cloth_sandbox::session::reference::{ErrorSample, MAX_PARTICLES};
use cloth_sandbox::session::{Edit, Session};
use cloth_sandbox::sim::Integrator;

const WAIT: Duration = Duration::from_secs(60);

fn session(scene: &str, overrides: &[&str]) -> Session {
    let overrides: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
    let mut s = Session::load_with(scene, &overrides).unwrap();
    s.set_safe_stepping(false);
    s.set_reference(true).unwrap();
    s
}

/// Runs `frames` frames, each compared once the reference has answered.
fn frames(s: &mut Session, frames: usize) -> Vec<ErrorSample> {
    let mut samples = Vec::new();
    for _ in 0..frames {
        s.step_frame();
        s.wait_for_reference(WAIT);
        let live = s.reference().unwrap();
        assert_eq!(live.stopped(), None);
        let last = *live.samples().back().unwrap();
        assert!(
            (last.time - s.system().time()).abs() < 1e-9,
            "compared at {} s, the shown run is at {} s",
            last.time,
            s.system().time()
        );
        samples.push(last);
    }
    samples
}

#[test]
fn the_live_error_of_the_spring_is_its_error_against_the_analytic_oscillator() {
    // Symplectic Euler at w dt = 0.055: an error of centimetres, which the
    // reference must report as the distance from the exact motion.
    let mut s = session("spring", &["dt=0.01", "substeps=5"]);
    let exact = spring_oscillator(0.1, 9.81);
    let mut worst: f64 = 0.0;
    for _ in 0..60 {
        let sample = frames(&mut s, 1)[0];
        let shown = -s.system().positions()[1].y;
        let analytic = (shown - exact.distance(s.system().time())).abs();
        worst = worst.max(analytic);
        assert!(
            (sample.max - analytic).abs() <= 1e-3 * analytic + 1e-6,
            "at t = {:.2} s the reference says {:.4e} m, the analytic oscillator {analytic:.4e} m",
            sample.time,
            sample.max
        );
        assert_eq!(sample.rms, sample.max, "one free particle");
    }
    assert!(worst > 1e-3, "a real error to measure: {worst:e} m");
}

/// RMS error against the reference after 0.5 s of the 8 x 8 cloth with
/// `integrator` at `dt`.
fn cloth_error(integrator: Integrator, dt: f64) -> f64 {
    let mut s = session(
        "cloth",
        &[
            "width=8",
            "height=8",
            &format!("integrator=\"{integrator}\""),
        ],
    );
    s.apply(Edit::Dt(dt)).unwrap();
    s.apply(Edit::Substeps((0.5 / dt).round() as u32)).unwrap();
    frames(&mut s, 1)[0].rms
}

#[test]
fn the_error_shrinks_with_dt_as_the_integrators_order_says() {
    // Error ~ dt^p: halving dt divides it by 2^p.
    for (integrator, p) in [(Integrator::SymplecticEuler, 1), (Integrator::Verlet, 2)] {
        let dt = 1e-3;
        let (coarse, fine) = (
            cloth_error(integrator, dt),
            cloth_error(integrator, dt / 2.0),
        );
        let ratio = coarse / fine;
        eprintln!(
            "{integrator}: RMS error {coarse:.3e} m at dt {dt}, {fine:.3e} m at dt/2: ratio {ratio:.2}"
        );
        let expected = 2f64.powi(p);
        assert!(
            (ratio / expected - 1.0).abs() < 0.25,
            "{integrator}: error {coarse:.3e} m at dt {dt}, {fine:.3e} m at dt/2: ratio \
             {ratio:.2}, order {p} says {expected}"
        );
    }
}

#[test]
fn an_edit_starts_the_reference_again_from_the_shown_state() {
    let mut s = session("cloth", &["width=8", "height=8"]);
    let before = frames(&mut s, 20);
    assert!(before.last().unwrap().rms > 0.0);
    for (what, edit) in [
        ("stiffness", Some(Edit::Stiffness(300.0))),
        ("integrator", Some(Edit::Integrator(Integrator::Verlet))),
        ("pin", None),
    ] {
        match edit {
            Some(edit) => s.apply(edit).unwrap(),
            None => s.toggle_pin(40),
        }
        let t = s.system().time();
        s.settle();
        let live = s.reference().unwrap();
        assert_eq!(*live.restarts().back().unwrap(), t, "{what}");
        let first = *live.samples().back().unwrap();
        assert_eq!((first.time, first.rms), (t, 0.0), "{what}");
        assert_eq!(live.ghost(), s.system().positions(), "{what}");
        let after = frames(&mut s, 3);
        assert!(after.iter().all(|e| e.time > t), "{what}");
    }
    // A rebuild (a new width) starts it on the new cloth.
    s.apply(Edit::Width(10)).unwrap();
    frames(&mut s, 2);
    assert_eq!(s.reference().unwrap().ghost().len(), 80);
    assert!(s.reference().unwrap().cost() > 0.0 && s.cost() > 0.0);
    // Another scene: the reference stays on and follows it.
    s.load_scene("spring").unwrap();
    frames(&mut s, 2);
    assert_eq!(s.reference().unwrap().ghost().len(), 2);
}

#[test]
fn a_scene_past_the_limit_is_refused_with_the_figures() {
    let side = ((MAX_PARTICLES as f64).sqrt() as usize + 1).to_string();
    let mut s = session(
        "cloth",
        &[&format!("width={side}"), &format!("height={side}")],
    );
    let why = s.reference().unwrap().stopped().unwrap().to_string();
    assert!(
        why.contains(&MAX_PARTICLES.to_string())
            && why.contains(&(side.parse::<usize>().unwrap().pow(2)).to_string()),
        "{why}"
    );
    s.step_frame();
    assert!(s.reference().unwrap().samples().is_empty());
    // Made small enough, it compares.
    s.apply(Edit::Width(8)).unwrap();
    s.settle();
    assert_eq!(s.reference().unwrap().stopped(), None);
    s.set_reference(false).unwrap();
    assert!(s.reference().is_none());
}

#[test]
fn a_reference_that_falls_behind_stops_and_says_how_slow_it_is() {
    // The largest cloth it takes, stepped by the fast engine as fast as it goes,
    // without waiting: RK4 on the f64 engine at half the step cannot follow.
    let side = (MAX_PARTICLES as f64).sqrt() as usize;
    let size = [format!("width={side}"), format!("height={side}")];
    let mut s = session("cloth", &[&size[0], &size[1]]);
    for _ in 0..2000 {
        s.step_frame();
        if s.reference().unwrap().stopped().is_some() {
            break;
        }
    }
    let why = s.reference().unwrap().stopped().map(str::to_string);
    let why = why.expect("still following after 2000 frames unwaited");
    assert!(
        why.contains("behind") && why.contains("per simulated second"),
        "{why}"
    );
}
