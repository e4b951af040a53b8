//! A divergence names its true cause: the step when it is past its stability
//! limit, the edit just made when the step was stable; and "Undo that edit" takes
//! the edit back and runs on from the last good frame.

use cloth_sandbox::session::{Edit, Session};

fn frames(session: &mut Session, n: u32) {
    for _ in 0..n {
        session.frame(1.0 / 60.0);
    }
}

#[test]
fn a_step_past_its_limit_is_named_as_the_cause() {
    let mut s = Session::load_with("cloth", &["width=12".into(), "height=12".into()]).unwrap();
    s.set_safe_stepping(false);
    s.apply(Edit::Stiffness(1e5)).unwrap();
    s.apply(Edit::Dt(0.01)).unwrap();
    frames(&mut s, 120);
    let d = s
        .divergence()
        .expect("k = 1e5 at dt = 0.01 without safe stepping diverges");
    let margin = d.margin.expect("a spring cloth has a critical step");
    assert!(margin > 1.0, "dt / dt_crit = {margin}");
    assert!(d.cause.contains("past its stability limit"), "{}", d.cause);
    assert!(d.cause.contains("turn safe stepping on"), "{}", d.cause);
    assert_eq!(d.edit.as_ref().map(|(w, _)| w.as_str()), Some("dt = 0.01"));
}

#[test]
fn an_edit_at_a_stable_step_is_named_and_can_be_undone() {
    // The tear scene keeps its particles 0.03 m apart (self-collision): shrinking
    // its 0.04 m spacing to a third puts every particle inside its neighbours'
    // reach, which pushes them apart harder than the springs hold, at a stable step.
    let mut s = Session::load_with("tear", &["width=12".into(), "height=12".into()]).unwrap();
    frames(&mut s, 10);
    for i in 1..=12 {
        let l = 0.04 * (0.25f64).powf(f64::from(i) / 12.0);
        s.apply(Edit::RestLength(l)).unwrap();
        frames(&mut s, 1);
        if s.divergence().is_some() {
            break;
        }
    }
    frames(&mut s, 30);
    let d = s
        .divergence()
        .expect("the shrunk tear scene diverges")
        .clone();
    assert!(d.margin.is_some_and(|m| m < 0.9), "{:?}", d.margin);
    assert!(d.cause.contains("dt is not the cause"), "{}", d.cause);
    assert!(d.cause.contains("the edit rest_length = "), "{}", d.cause);
    let (what, ago) = d.edit.clone().unwrap();
    assert!(what.starts_with("rest_length = "), "{what}");
    assert!((0.0..=2.0).contains(&ago), "{ago}");

    assert!(s.undo_divergence().unwrap());
    assert!(s.divergence().is_none() && !s.paused());
    assert_eq!(
        s.settings().rest_length,
        0.04,
        "the whole drag is taken back"
    );
    assert_eq!(
        s.system().time(),
        d.shown_time,
        "it runs on from the last good frame"
    );
    frames(&mut s, 60);
    assert!(s.divergence().is_none(), "{:?}", s.divergence());
    assert!(s.system().time() > d.shown_time);
    // Nothing left to take back: the button does nothing.
    assert!(!s.undo_divergence().unwrap());
}
