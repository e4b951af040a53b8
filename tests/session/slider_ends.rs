//! Every slider the panel shows, in every built-in scene, dragged to each end
//! and held there under safe stepping, as a user drags it: the run must not
//! diverge, nothing may turn non-finite, and the cloth must stay in view (within
//! a bound of the size the slider's range allows). The ranges are the session's
//! own table ([`Session::sliders`]), the one the panel draws.

use cloth_sandbox::scene::builtin_scenes;
use cloth_sandbox::session::{Edit, Session, Slider};

/// Frames a drag takes from one value to the next, and frames held at each end.
const DRAG_FRAMES: u32 = 12;
const HOLD_FRAMES: u32 = 40;

/// The scenes at a size that keeps the test short (the ranges do not depend on it).
fn load(name: &str) -> Session {
    let small: &[String] = &["width=12".into(), "height=12".into()];
    let grid = matches!(
        name,
        "cloth" | "flag" | "corners" | "sheet" | "drape" | "fold" | "tear" | "twist" | "slide"
    ) || name.starts_with("bench")
        || name.starts_with("table");
    let overrides = if grid { small } else { &[] };
    Session::load_with(name, overrides)
        .or_else(|_| Session::load_with(name, &[]))
        .unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// Applies a slider's shown value as the panel does (dt keeps the speed).
fn slide(session: &mut Session, slider: &Slider, shown: f64) {
    let edit = slider.edit(session.settings(), shown);
    let done = match edit {
        Edit::Dt(dt) => session.apply_dt_keeping_speed(dt),
        e => session.apply(e),
    };
    done.unwrap_or_else(|e| panic!("{} = {shown}: {e}", slider.id));
}

/// The shown values of a drag from `from` to `to` over `DRAG_FRAMES` frames.
fn drag(slider: &Slider, from: f64, to: f64) -> impl Iterator<Item = f64> {
    let log = slider.log && from > 0.0 && to > 0.0;
    (1..=DRAG_FRAMES).map(move |i| {
        let s = f64::from(i) / f64::from(DRAG_FRAMES);
        if log {
            from * (to / from).powf(s)
        } else {
            from + (to - from) * s
        }
    })
}

/// Largest distance (m) of a particle from the cloth's centre of mass.
fn extent(session: &Session) -> f64 {
    let x = session.system().positions();
    let c = x.iter().sum::<glam::DVec3>() / x.len() as f64;
    x.iter().map(|p| p.distance(c)).fold(0.0, f64::max)
}

/// What went wrong with one slider in one scene, if anything.
fn check(name: &str, id: &str) -> Option<String> {
    let mut session = load(name);
    let slider = session.sliders().into_iter().find(|s| s.id == id)?;
    let start = slider.value(session.settings());
    let size = extent(&session).max(1e-3);
    let (lo, hi) = (*slider.range.start(), *slider.range.end());
    let mut at = start;
    for end in [lo, hi, start] {
        for shown in drag(&slider, at, end) {
            slide(&mut session, &slider, shown);
            session.frame(1.0 / 60.0);
        }
        session.end_edit_group();
        at = end;
        for _ in 0..HOLD_FRAMES {
            session.frame(1.0 / 60.0);
        }
        if let Some(d) = session.divergence() {
            return Some(format!("{name}: {id} at {end}: diverged: {}", d.message));
        }
        if !session.system().positions().iter().all(|p| p.is_finite()) {
            return Some(format!("{name}: {id} at {end}: non-finite positions"));
        }
        // A slider may scale the cloth (rest length) by its range's factor, and
        // stretch it under load; well past that the cloth has left the view.
        let scale = if id == "rest_length" { hi / start } else { 1.0 };
        let reach = extent(&session);
        // (A torn cloth's pieces part by design.)
        let torn = session.system().broken_springs() > 0;
        if reach > 6.0 * size * scale + 0.5 && !torn {
            return Some(format!(
                "{name}: {id} at {end}: the cloth spread to {reach:.1} m from {size:.2} m"
            ));
        }
    }
    None
}

#[test]
fn every_slider_end_keeps_every_scene_stable_under_safe_stepping() {
    let mut failures = Vec::new();
    let mut tried = 0;
    for scene in builtin_scenes() {
        let ids: Vec<&str> = load(scene.name).sliders().iter().map(|s| s.id).collect();
        assert!(ids.len() >= 5, "{}: only {ids:?}", scene.name);
        for id in ids {
            tried += 1;
            failures.extend(check(scene.name, id));
        }
    }
    assert!(tried > 100, "only {tried} sliders tried");
    assert!(
        failures.is_empty(),
        "{} of {tried}:\n{}",
        failures.len(),
        failures.join("\n")
    );
}
