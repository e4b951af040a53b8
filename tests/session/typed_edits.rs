//! The panel's typed edits, headless: each changes the running system in place (read
//! back through the system's getters) without touching its state, is kept by a reset
//! and by a rebuild for a new width, matches the same value set as text (`--set`),
//! and a bad value is refused with a message naming the field and changes nothing.

use cloth_sandbox::session::{Edit, SAFE_STRETCH_LIMIT, Session, wind_load_ratio};
use cloth_sandbox::sim::{Integrator, SpringKind, System};
use glam::DVec3;

fn cloth() -> Session {
    Session::load_with("cloth", &[]).expect("the default cloth loads")
}

/// A cloth that has moved for a while, so that a rebuild would show.
fn moving_cloth(safe_stepping: bool) -> Session {
    let mut s = cloth();
    s.set_safe_stepping(safe_stepping);
    for _ in 0..20 {
        s.single_step();
    }
    assert!(s.system().velocities().iter().any(|v| v.length() > 1e-3));
    s
}

/// Every live edit the panel makes, each to a value its scene does not have.
fn live_edits() -> Vec<Edit> {
    vec![
        Edit::Stiffness(250.0),
        Edit::Damping(0.3),
        Edit::RestLength(0.04),
        Edit::ParticleMass(0.003),
        Edit::Gravity(DVec3::new(0.5, -3.0, 0.0)),
        Edit::Force(DVec3::new(0.001, 0.0, -0.002)),
        Edit::Wind(DVec3::new(1.0, 2.0, -3.0)),
        Edit::Gust(2.5),
        Edit::AirDamping(0.01),
        Edit::Dt(0.0005),
        Edit::Substeps(7),
        Edit::Integrator(Integrator::Verlet),
        Edit::StretchLimit(Some(0.2)),
        Edit::TearStrain(Some(0.8)),
        Edit::MaxSpeed(Some(7.0)),
        Edit::Friction(0.4),
        Edit::Thickness(0.01),
        Edit::SelfCollision(true),
    ]
}

/// The stiffness and damping of the springs of `kind`, which the cloth has.
fn material_of(system: &System, kind: SpringKind) -> cloth_sandbox::sim::SpringMaterial {
    system.model().material(spring_of(system, kind).kind)
}

fn spring_of(system: &System, kind: SpringKind) -> cloth_sandbox::sim::Spring {
    *system
        .springs()
        .iter()
        .find(|s| s.kind == kind)
        .unwrap_or_else(|| panic!("the cloth has {kind:?} springs"))
}

/// Panics unless the running system (and the session) has the value `edit` set.
/// Needs safe stepping off for dt and substeps.
fn assert_applied(s: &Session, edit: Edit) {
    let sys = s.system();
    let p = sys.params();
    let r = s.settings();
    match edit {
        Edit::Stiffness(k) => {
            // The cloth scene's shear and bend scales are 1.
            for kind in [SpringKind::Structural, SpringKind::Shear, SpringKind::Bend] {
                let expected = k * r.spring_scale(kind);
                assert_eq!(material_of(sys, kind).stiffness, expected, "{kind:?}");
                assert_eq!(expected, k, "{kind:?}");
            }
        }
        Edit::Damping(b) => {
            for kind in [SpringKind::Structural, SpringKind::Shear, SpringKind::Bend] {
                assert_eq!(material_of(sys, kind).damping, b, "{kind:?}");
            }
        }
        Edit::RestLength(l) => {
            let rest = spring_of(sys, SpringKind::Structural).rest;
            assert!((rest - l).abs() < 1e-12 * l, "{rest} vs {l}");
        }
        Edit::ParticleMass(m) => assert!(sys.masses().iter().all(|&x| x == m)),
        Edit::Gravity(g) => assert_eq!(p.gravity, g),
        Edit::Force(f) => assert_eq!(p.force, f),
        Edit::Wind(w) => assert_eq!(p.wind, w),
        Edit::Gust(g) => assert_eq!(p.gust, g),
        Edit::AirDamping(c) => assert_eq!(p.air_damping, c),
        Edit::Dt(dt) => assert_eq!(p.dt, dt),
        Edit::Substeps(n) => assert_eq!(s.substeps(), n),
        Edit::Integrator(i) => assert_eq!(p.integrator, i),
        Edit::BarIterations(n) => assert_eq!(p.bar_iterations, n),
        Edit::StretchLimit(t) => assert_eq!(p.stretch_limit, t),
        Edit::TearStrain(t) => assert_eq!(p.tear_strain, t),
        Edit::MaxSpeed(v) => assert_eq!(p.max_speed, v),
        Edit::Friction(mu) => assert_eq!(p.friction, mu),
        Edit::Thickness(t) => assert_eq!(p.thickness, t),
        Edit::SelfCollision(on) => assert_eq!(p.self_collision, on),
        Edit::Width(w) => assert_eq!(r.width, w),
        Edit::Height(h) => assert_eq!(r.height, h),
        Edit::Depth(d) => assert_eq!(r.depth, d),
        Edit::Material(m) => {
            assert_eq!((r.stiffness, r.damping), (m.stiffness, m.damping));
            assert_eq!(p.drag_coefficient, m.drag_coefficient);
        }
    }
}

#[test]
fn each_live_edit_changes_the_running_system_without_touching_its_state() {
    for edit in live_edits() {
        let mut s = moving_cloth(false);
        // A pin made by clicking, which a rebuild would drop.
        s.system_mut().set_pinned(5, true);
        let (positions, velocities) = (
            s.system().positions().to_vec(),
            s.system().velocities().to_vec(),
        );
        let (time, steps) = (s.system().time(), s.system().steps_taken());
        let pinned: Vec<bool> = (0..positions.len())
            .map(|i| s.system().is_pinned(i))
            .collect();
        let settings_before = s.settings().clone();
        s.apply(edit).unwrap_or_else(|e| panic!("{edit:?}: {e}"));
        assert_ne!(
            s.settings(),
            &settings_before,
            "{edit:?} changed no setting"
        );
        assert_applied(&s, edit);
        let sys = s.system();
        assert_eq!((sys.time(), sys.steps_taken()), (time, steps), "{edit:?}");
        assert_eq!(sys.velocities(), &velocities[..], "{edit:?}");
        assert!(sys.is_pinned(5), "{edit:?} dropped a clicked pin");
        for (i, &p) in pinned.iter().enumerate() {
            assert_eq!(sys.is_pinned(i), p, "{edit:?}");
        }
        if let Edit::RestLength(l) = edit {
            // The cloth is scaled about its pins, not rebuilt flat.
            let factor = l / 0.05;
            let (a, b) = (positions[0], positions[40]);
            let d = sys.positions()[40] - sys.positions()[0];
            assert!((d - (b - a) * factor).length() < 1e-12, "{d} vs {}", b - a);
        } else {
            assert_eq!(sys.positions(), &positions[..], "{edit:?}");
        }
        // The edit is recorded where a reset will find it.
        assert_eq!(s.settings(), &s.scene().resolve().unwrap(), "{edit:?}");
    }
}

#[test]
fn reset_keeps_every_typed_edit() {
    let mut s = moving_cloth(false);
    for edit in live_edits() {
        s.apply(edit).unwrap();
    }
    s.system_mut().set_pinned(100, true);
    s.reset().unwrap();
    assert_eq!(s.system().steps_taken(), 0);
    assert!(!s.system().is_pinned(100));
    for edit in live_edits() {
        assert_applied(&s, edit);
    }
}

#[test]
fn a_width_edit_rebuilds_the_cloth_keeping_the_other_edits() {
    let mut s = moving_cloth(false);
    let kept = [
        Edit::Stiffness(321.0),
        Edit::Damping(0.05),
        Edit::Wind(DVec3::new(1.0, 0.0, 3.0)),
        Edit::ParticleMass(0.002),
        Edit::RestLength(0.03),
        Edit::Dt(0.0007),
        Edit::Integrator(Integrator::Rk4),
    ];
    for edit in kept {
        s.apply(edit).unwrap();
    }
    s.apply(Edit::Width(12)).unwrap();
    s.apply(Edit::Height(9)).unwrap();
    let sys = s.system();
    assert_eq!(sys.particle_count(), 12 * 9);
    assert_eq!(sys.triangles().len(), 2 * 11 * 8);
    assert_eq!(sys.steps_taken(), 0, "a new cloth");
    for edit in kept {
        assert_applied(&s, edit);
    }
    // Pinned by the scene's preset again: the top corners of the new width.
    assert!(sys.is_pinned(0) && sys.is_pinned(11));
    assert_eq!(
        (0..sys.particle_count())
            .filter(|&i| sys.is_pinned(i))
            .count(),
        2
    );
}

#[test]
fn bad_values_are_refused_with_the_field_and_range_and_change_nothing() {
    let bad = [
        (Edit::Stiffness(f64::NAN), "stiffness", "[0, 1000000000]"),
        (Edit::Stiffness(-1.0), "stiffness", "[0, 1000000000]"),
        (
            Edit::ParticleMass(-0.001),
            "particle_mass",
            "[1e-12, 1000000]",
        ),
        (Edit::ParticleMass(0.0), "particle_mass", "[1e-12, 1000000]"),
        (Edit::Damping(f64::INFINITY), "damping", "[0, 1000000000]"),
        (Edit::RestLength(f64::NAN), "rest_length", "[0, 1000]"),
        (
            Edit::Gravity(DVec3::new(0.0, f64::NAN, 0.0)),
            "gravity",
            "at most 10000",
        ),
        (
            Edit::Wind(DVec3::new(2e4, 0.0, 0.0)),
            "wind",
            "at most 10000",
        ),
        (Edit::Gust(-1.0), "gust", "[0, 10000]"),
        (
            Edit::AirDamping(f64::NEG_INFINITY),
            "air_damping",
            "[0, 1000000000]",
        ),
        (Edit::Dt(0.0), "dt", "(0, 1]"),
        (Edit::Dt(2.0), "dt", "(0, 1]"),
        (Edit::Substeps(0), "substeps", "[1, 100000]"),
        // Only a rope has bars: on the cloth the key does nothing, so it is refused.
        (
            Edit::BarIterations(5),
            "bar_iterations",
            "does not apply to a grid",
        ),
        (
            Edit::StretchLimit(Some(f64::NAN)),
            "stretch_limit",
            "[0, 100]",
        ),
        (Edit::Width(0), "width", "[1, 1024]"),
        (Edit::Height(5000), "height", "[1, 1024]"),
        (Edit::Depth(3), "depth", "does not apply to a grid"),
    ];
    for (edit, field, range) in bad {
        let mut s = moving_cloth(true);
        let scene = s.scene().clone();
        let settings = s.settings().clone();
        let springs = s.system().springs().to_vec();
        let (params, masses) = (*s.system().params(), s.system().masses().to_vec());
        let positions = s.system().positions().to_vec();
        let (choice, substeps) = (s.step_choice(), s.substeps());
        let message = s
            .apply(edit)
            .expect_err(&format!("{edit:?} is refused"))
            .to_string();
        assert!(
            message.contains(&format!("`{field}`")) && message.contains(range),
            "{edit:?}: {message}"
        );
        assert_eq!(s.scene(), &scene, "{edit:?}");
        assert_eq!(s.settings(), &settings, "{edit:?}");
        assert_eq!(s.system().springs(), &springs[..], "{edit:?}");
        assert_eq!(s.system().params(), &params, "{edit:?}");
        assert_eq!(s.system().masses(), &masses[..], "{edit:?}");
        assert_eq!(s.system().positions(), &positions[..], "{edit:?}");
        assert_eq!((s.step_choice(), s.substeps()), (choice, substeps));
        // Still running.
        assert_eq!(s.single_step().steps, 1);
    }
}

#[test]
fn a_width_that_drops_a_pinned_index_is_refused_and_changes_nothing() {
    let mut s = Session::load_with("cloth", &["pins=[0, 1023]".into()]).unwrap();
    let scene = s.scene().clone();
    let message = s.apply(Edit::Width(16)).unwrap_err().to_string();
    assert!(message.contains("`pins`"), "{message}");
    assert_eq!(s.scene(), &scene);
    assert_eq!(s.system().particle_count(), 32 * 32);
}

/// The text `--set` takes for the same value.
fn as_text(edit: Edit) -> (&'static str, String) {
    let vec3 = |v: DVec3| format!("{},{},{}", v.x, v.y, v.z);
    let value = match edit {
        Edit::Stiffness(x)
        | Edit::Damping(x)
        | Edit::RestLength(x)
        | Edit::ParticleMass(x)
        | Edit::Gust(x)
        | Edit::AirDamping(x)
        | Edit::Dt(x)
        | Edit::Friction(x)
        | Edit::Thickness(x) => x.to_string(),
        Edit::Gravity(v) | Edit::Wind(v) | Edit::Force(v) => vec3(v),
        Edit::Substeps(n)
        | Edit::BarIterations(n)
        | Edit::Width(n)
        | Edit::Height(n)
        | Edit::Depth(n) => n.to_string(),
        Edit::Integrator(i) => i.name().to_string(),
        Edit::SelfCollision(on) => on.to_string(),
        Edit::Material(m) => m.name.to_string(),
        // Off is the key's absence, which `none` asks for.
        Edit::StretchLimit(x) | Edit::TearStrain(x) | Edit::MaxSpeed(x) => {
            x.map_or("none".to_string(), |x| x.to_string())
        }
    };
    (edit.key(), value)
}

fn same_running_system(a: &Session, b: &Session, context: &str) {
    assert_eq!(a.scene(), b.scene(), "{context}");
    assert_eq!(a.settings(), b.settings(), "{context}");
    assert_eq!(a.settings(), &a.scene().resolve().unwrap(), "{context}");
    let (x, y) = (a.system(), b.system());
    assert_eq!(x.springs(), y.springs(), "{context}");
    assert_eq!(x.bars(), y.bars(), "{context}");
    assert_eq!(x.masses(), y.masses(), "{context}");
    assert_eq!(x.params(), y.params(), "{context}");
    assert_eq!(x.positions(), y.positions(), "{context}");
    assert_eq!(x.velocities(), y.velocities(), "{context}");
    assert_eq!(a.step_choice(), b.step_choice(), "{context}");
    assert_eq!(a.substeps(), b.substeps(), "{context}");
}

#[test]
fn a_typed_edit_matches_the_same_value_set_as_text_in_every_scene() {
    let edits = [
        Edit::Stiffness(250.0),
        Edit::Damping(0.3),
        Edit::ParticleMass(0.003),
        Edit::RestLength(0.07),
        Edit::Gravity(DVec3::new(0.0, -4.0, 1.0)),
        Edit::Wind(DVec3::new(3.0, 0.0, -1.5)),
        Edit::Gust(0.25),
        Edit::AirDamping(0.125),
        Edit::Dt(0.0004),
        Edit::Substeps(9),
        Edit::Integrator(Integrator::Rk4),
        Edit::BarIterations(3),
        Edit::StretchLimit(Some(0.3)),
        Edit::StretchLimit(None),
        Edit::TearStrain(Some(0.6)),
        Edit::TearStrain(None),
        Edit::MaxSpeed(Some(5.0)),
        Edit::MaxSpeed(None),
        Edit::Material(cloth_sandbox::scene::Material::named("leather").unwrap()),
        Edit::Width(9),
        Edit::Height(5),
        Edit::Depth(3),
    ];
    let scenes = [
        "cloth", "flag", "sheet", "drape", "spring", "chain", "jelly", "rope", "bench",
    ];
    let moved = |scene: &str| {
        let mut s = Session::load_with(scene, &[]).unwrap();
        for _ in 0..10 {
            s.single_step();
        }
        s
    };
    for scene in scenes {
        // Each edit alone, on the scene as written (damping ratios, values per kg),
        // then all of them one after the other.
        let singles = edits.iter().map(|&e| (vec![e], format!("{scene}: {e:?}")));
        let all = (edits.to_vec(), format!("{scene}: all in turn"));
        for (sequence, context) in singles.chain([all]) {
            let (mut typed, mut text) = (moved(scene), moved(scene));
            for edit in sequence {
                let context = format!("{context}, at {edit:?}");
                let (key, value) = as_text(edit);
                match typed.apply(edit) {
                    // `--set` stores a key the layout ignores (a grid's depth); the
                    // panel never offers it, and a typed edit says so.
                    Err(e) if e.to_string().contains("does not apply") => {}
                    a => {
                        let b = text.set(key, &value);
                        assert_eq!(a.is_ok(), b.is_ok(), "{context}: {a:?} vs {b:?}");
                    }
                }
                same_running_system(&typed, &text, &context);
                typed.single_step();
                text.single_step();
                same_running_system(&typed, &text, &context);
            }
        }
    }
}

#[test]
fn bar_iterations_apply_to_the_rope_in_place_and_are_checked() {
    let mut s = Session::load_with("rope", &[]).unwrap();
    for _ in 0..10 {
        s.single_step();
    }
    let positions = s.system().positions().to_vec();
    s.apply(Edit::BarIterations(5)).unwrap();
    assert_eq!(s.system().params().bar_iterations, 5);
    assert_eq!(s.system().positions(), &positions[..], "applied in place");
    let message = s
        .apply(Edit::BarIterations(20_000))
        .unwrap_err()
        .to_string();
    assert!(
        message.contains("`bar_iterations`") && message.contains("[0, 10000]"),
        "{message}"
    );
    assert_eq!(s.system().params().bar_iterations, 5);
}

#[test]
fn stiffness_and_mass_edits_carry_a_damping_ratio_along() {
    // The chain gives its damping as 25% of critical: b = 0.25 * 2 sqrt(k m).
    let mut s = Session::load_with("chain", &[]).unwrap();
    let b = |s: &Session| {
        s.system()
            .model()
            .material(s.system().springs()[0].kind)
            .damping
    };
    let critical = |k: f64, m: f64| 0.25 * 2.0 * (k * m).sqrt();
    assert!((b(&s) - critical(100.0, 0.5)).abs() < 1e-12);
    s.apply(Edit::Stiffness(400.0)).unwrap();
    assert!((b(&s) - critical(400.0, 0.5)).abs() < 1e-12, "{}", b(&s));
    s.apply(Edit::ParticleMass(2.0)).unwrap();
    assert!((b(&s) - critical(400.0, 2.0)).abs() < 1e-12, "{}", b(&s));
    // A damping in N·s/m replaces the ratio: k no longer moves it.
    s.apply(Edit::Damping(3.0)).unwrap();
    s.apply(Edit::Stiffness(100.0)).unwrap();
    assert_eq!(b(&s), 3.0);
    assert_eq!(s.scene().spec.damping_ratio, None);
}

#[test]
fn safe_stepping_follows_typed_edits() {
    let mut s = Session::load_with("cloth", &["width=10".into(), "height=10".into()]).unwrap();
    let frame = 16.0 / 960.0;
    s.apply(Edit::Stiffness(100_000.0)).unwrap();
    let c = s.step_choice().unwrap();
    assert!(c.substeps > 16, "stiff springs need more substeps: {c:?}");
    assert!((c.dt * f64::from(c.substeps) - frame).abs() < 1e-3 * frame);
    assert_eq!(s.system().params().dt, c.dt);
    assert_eq!(s.settings().params.dt, 1.0 / 960.0, "the user's dt is kept");
    s.apply(Edit::Stiffness(10.0)).unwrap();
    assert_eq!(s.step_choice().unwrap().substeps, 16);
    assert_eq!(s.system().params().dt, 1.0 / 960.0);

    // The wind-load stretch limit comes and goes with the wind and the springs.
    for edit in [
        Edit::Stiffness(1.0),
        Edit::ParticleMass(0.001),
        Edit::Wind(DVec3::new(20.0, 20.0, 20.0)),
        Edit::Gust(10.0),
    ] {
        s.apply(edit).unwrap();
    }
    assert!(wind_load_ratio(s.system().model()) > 1.0);
    assert_eq!(
        s.step_choice().unwrap().stretch_limit,
        Some(SAFE_STRETCH_LIMIT)
    );
    assert_eq!(s.system().params().stretch_limit, Some(SAFE_STRETCH_LIMIT));
    s.apply(Edit::Wind(DVec3::ZERO)).unwrap();
    s.apply(Edit::Gust(0.0)).unwrap();
    assert_eq!(s.step_choice().unwrap().stretch_limit, None);
    assert_eq!(s.system().params().stretch_limit, None);
}

#[test]
fn only_layout_edits_rebuild_and_the_session_agrees() {
    let s = cloth();
    for edit in live_edits()
        .into_iter()
        .chain([Edit::Width(4), Edit::Height(4), Edit::Depth(4)])
    {
        assert_eq!(s.needs_rebuild(edit.key()), edit.rebuilds(), "{edit:?}");
    }
}

#[test]
fn the_stretch_limit_turns_on_and_off_in_place_as_if_the_scene_had_it() {
    // Each scene as loaded, the limit turned on (or off) in place, against the same
    // scene loaded with it: the same engine, and the same state to the bit after
    // the steps; and the limit must change the run (against the scene as loaded).
    let cases = [
        ("cloth", Some(0.0), "0"),
        ("sheet", None, "none"),
        ("jelly", Some(0.0), "0"),
        ("chain", Some(0.0), "0"),
        ("flag", Some(0.0), "0"),
    ];
    for (scene, limit, text) in cases {
        let mut plain = Session::load_with(scene, &[]).unwrap();
        let mut edited = Session::load_with(scene, &[]).unwrap();
        let mut built = Session::load_with(scene, &[format!("stretch_limit={text}")]).unwrap();
        edited.apply(Edit::StretchLimit(limit)).unwrap();
        assert_eq!(built.system().params().stretch_limit, limit, "{scene}");
        for _ in 0..60 {
            for s in [&mut plain, &mut edited, &mut built] {
                s.single_step();
            }
        }
        let (a, b) = (edited.system(), built.system());
        assert_eq!(a.engine(), b.engine(), "{scene}");
        assert!(a.positions() == b.positions(), "{scene}: positions differ");
        assert!(
            a.velocities() == b.velocities(),
            "{scene}: velocities differ"
        );
        assert!(
            a.positions() != plain.system().positions(),
            "{scene}: no effect"
        );
    }
}

/// The panel's material choice: the cloth takes the material's values and keeps
/// its size, so a width edit after it refines the same cloth (spacing and particle
/// mass follow, stiffness stays); a stiffness edit then overrides the material;
/// undo goes back to the scene's own values.
#[test]
fn a_material_keeps_the_size_as_the_width_changes() {
    use cloth_sandbox::scene::Material;
    let mut s = Session::load_with("cloth", &[]).expect("the cloth loads");
    let own = s.settings().stiffness;
    let cotton = Material::named("cotton").unwrap();
    s.apply(Edit::Material(cotton)).expect("applies");
    let r = s.settings();
    assert_eq!((r.stiffness, r.damping), (cotton.stiffness, cotton.damping));
    assert_eq!(s.scene().spec.material.as_deref(), Some("cotton"));
    let (l32, m32) = (r.rest_length, r.particle_mass);
    assert!((l32 - 0.05).abs() < 1e-15);
    s.apply(Edit::Width(63)).expect("applies");
    s.apply(Edit::Height(63)).expect("applies");
    let r = s.settings();
    assert!(
        (r.rest_length - l32 * 31.0 / 62.0).abs() < 1e-15,
        "{}",
        r.rest_length
    );
    // The same mass per area: 62² cells of a quarter the area over 63² particles.
    let expected = m32 * 1024.0 / (31.0 * 31.0) * (62.0 * 62.0 * 0.25) / (63.0 * 63.0);
    assert!(
        (r.particle_mass - expected).abs() < 1e-15,
        "{} vs {expected}",
        r.particle_mass
    );
    assert_eq!(r.stiffness, cotton.stiffness);
    let extent = |s: &Session| {
        let xs = s.system().positions().iter().map(|p| p.x);
        xs.clone().fold(f64::MIN, f64::max) - xs.fold(f64::MAX, f64::min)
    };
    assert!((extent(&s) - 1.55).abs() < 1e-9, "{}", extent(&s));
    assert!(!s.scene().spec.overrides_material());
    s.apply(Edit::Stiffness(120.0)).expect("applies");
    assert!(
        s.scene().spec.overrides_material(),
        "the panel shows \"cotton (edited)\""
    );
    assert_eq!(s.settings().stiffness, 120.0);
    assert_eq!(
        s.settings().damping,
        cotton.damping,
        "the rest of the material holds"
    );
    for _ in 0..4 {
        s.undo().expect("undoes");
    }
    assert_eq!(s.settings().stiffness, own);
    assert_eq!(s.scene().spec.material, None);
}
