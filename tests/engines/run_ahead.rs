//! `System::run_ahead` (the app's physics thread steps a few steps at a time and
//! reads the state only when it draws): the steps are the same steps as
//! `System::run`'s, only the copy to the f64 state and the full check wait for
//! `System::settle` or the next edit. Compared bit for bit with plain runs on each
//! engine, across edits made while an engine is ahead, and on a blow-up.

use crate::common;

use crate::common::build;
use cloth_sandbox::sim::{Engine, System};

/// `total` steps as many short runs ahead (of 1 to 37 steps), then a settle.
fn run_in_short_calls(system: &mut System, total: u64) {
    let mut done = 0;
    let mut call = 0u64;
    while done < total {
        let n = (1 + (call * 7) % 37).min(total - done);
        system.run_ahead(n).unwrap();
        done += n;
        call += 1;
    }
    system.settle().unwrap();
}

fn assert_same_state(a: &System, b: &System, what: &str) {
    assert_eq!(a.steps_taken(), b.steps_taken(), "{what}: steps");
    assert_eq!(a.time().to_bits(), b.time().to_bits(), "{what}: time");
    assert!(
        a.positions() == b.positions() && a.velocities() == b.velocities(),
        "{what}: states differ by {:e} m",
        common::max_distance(a.positions(), b.positions())
    );
}

/// Scenes on each engine: the grid kernel in two precisions and the general f64
/// engine (the chain, and RK4).
const CASES: &[(&str, &[&str])] = &[
    ("cloth", &["width=16", "height=16"]),
    ("bench", &["width=16", "height=16"]),
    ("drape", &["width=12", "height=12"]),
    ("chain", &[]),
    ("cloth", &["width=8", "height=8", "integrator=rk4"]),
];

#[test]
fn short_runs_ahead_then_a_settle_are_one_run() {
    for &(scene, overrides) in CASES {
        let what = format!("{scene} {overrides:?}");
        let mut plain = build(scene, overrides);
        plain.set_fast_path(true);
        let mut ahead = plain.clone();
        // Past one energy-check interval (1024 steps), so that a full check falls
        // inside the runs ahead.
        plain.run(1500).unwrap();
        run_in_short_calls(&mut ahead, 1500);
        assert_same_state(&plain, &ahead, &what);
        assert_eq!(plain.engine(), ahead.engine(), "{what}");
        assert!(plain.energy().total().is_finite());
        assert_eq!(plain.energy(), ahead.energy(), "{what}: energy");
    }
}

/// An edit of a running system, as the panel or the mouse makes it.
type EditFn = fn(&mut System);

/// The edits the panel and the mouse make, each on its own.
const EDITS: &[(&str, EditFn)] = &[
    ("stiffness", |s| {
        let kind = s.springs()[0].kind;
        let k = s.model().material(kind).stiffness * 1.5;
        s.set_spring_stiffness(kind, k);
    }),
    ("damping", |s| {
        let kind = s.springs()[0].kind;
        let b = s.model().material(kind).damping * 3.0 + 0.05;
        s.set_spring_damping(kind, b);
    }),
    ("mass", |s| s.set_particle_mass(0.02)),
    ("pin", |s| s.set_pinned(3, true)),
    // A fixed target: the positions are not read before the settle.
    ("grab", |s| s.grab(5, glam::DVec3::new(0.2, 0.3, 0.4))),
    ("gravity", |s| {
        let mut params = *s.params();
        params.gravity *= 0.5;
        s.set_params(params);
    }),
];

#[test]
fn an_edit_while_an_engine_is_ahead_keeps_its_steps() {
    // The cases on a fast engine, which can run ahead of the f64 state.
    for &(scene, overrides) in &CASES[..3] {
        for &(edit_name, edit) in EDITS {
            let what = format!("{scene} {overrides:?}, {edit_name}");
            let mut reference = build(scene, overrides);
            reference.set_fast_path(true);
            assert!(!matches!(reference.engine(), Engine::General), "{what}");
            let mut ahead = reference.clone();

            reference.run(300).unwrap();
            ahead.run_ahead(300).unwrap();
            // The edit, without a settle first.
            edit(&mut reference);
            edit(&mut ahead);
            reference.run(300).unwrap();
            ahead.run_ahead(300).unwrap();
            ahead.settle().unwrap();
            assert_same_state(&reference, &ahead, &what);
            // The edit took: the run differs from one without it.
            let mut unedited = build(scene, overrides);
            unedited.set_fast_path(true);
            unedited.run(600).unwrap();
            assert!(
                common::max_distance(unedited.positions(), ahead.positions()) > 1e-9,
                "{what}: the edit changed nothing"
            );
        }
    }
}

#[test]
fn a_blow_up_is_caught_by_a_run_ahead_at_its_step() {
    // Explicit Euler far past its stable step: the positions become non-finite.
    let overrides = [
        "width=16",
        "height=16",
        "integrator=explicit-euler",
        "dt=0.01",
    ];
    let mut plain = build("cloth", &overrides);
    plain.set_fast_path(true);
    let mut ahead = plain.clone();
    let caught = plain.run(100_000).unwrap_err();
    let mut caught_ahead = None;
    for _ in 0..100_000 / 10 {
        if let Err(d) = ahead.run_ahead(10) {
            caught_ahead = Some(d);
            break;
        }
    }
    let caught_ahead = caught_ahead.expect("the run ahead never diverged");
    assert_eq!(caught.to_string(), caught_ahead.to_string());
}

/// The energy a full check computed is reused until the state or a coefficient
/// changes: doubling every spring's stiffness doubles the elastic energy read
/// right after, at the same step.
#[test]
fn the_energy_read_after_a_stiffness_edit_is_the_edited_ones() {
    let mut system = build("cloth", &["width=12", "height=12"]);
    system.set_fast_path(true);
    system.run(500).unwrap();
    let before = system.energy();
    assert!(before.elastic > 0.0);
    let kinds: Vec<_> = system
        .springs()
        .iter()
        .map(|s| (s.kind, system.model().material(s.kind).stiffness))
        .collect();
    for (kind, k) in kinds {
        system.set_spring_stiffness(kind, 2.0 * k);
    }
    let after = system.energy();
    assert!(
        (after.elastic - 2.0 * before.elastic).abs() <= 1e-9 * before.elastic,
        "elastic {} J, then {} J at twice the stiffness",
        before.elastic,
        after.elastic
    );
    assert_eq!(after.kinetic, before.kinetic);
}
