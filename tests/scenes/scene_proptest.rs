//! A property-based test of the scene parser and `--set`. Random keys, values and
//! types never panic, and whatever is accepted builds a system with finite,
//! positive masses, finite spring rest lengths (positive where the particles are
//! apart) and a finite, positive step. Bounded (a few hundred small cases) so that
//! CI stays fast.

use cloth_sandbox::scene::{Scene, builtin_scenes};
use proptest::prelude::*;

/// Every scene key, and a few that are not.
const KEYS: &[&str] = &[
    "layout",
    "orientation",
    "width",
    "height",
    "depth",
    "rest_length",
    "size",
    "particle_mass",
    "total_mass",
    "stiffness",
    "stiffness_per_mass",
    "damping",
    "damping_ratio",
    "damping_per_mass",
    "shear_scale",
    "bend_scale",
    "wind",
    "gust",
    "air_density",
    "drag_coefficient",
    "air_damping",
    "gravity",
    "pins",
    "integrator",
    "dt",
    "substeps",
    "seed",
    "origin",
    "rotation",
    "stretch",
    "ground_height",
    "ground_stiffness",
    "ground_damping",
    "sphere_center",
    "sphere_radius",
    "bar_iterations",
    "stretch_limit",
    "friction",
    "ground_friction",
    "thickness",
    "self_collision",
    "tear_strain",
    "max_speed",
    "force",
    "bars",
    "mesh",
    "pin_above",
    "name",
    "description",
    "nope",
    "",
    "width\n",
    "[x]",
];

/// Values of every TOML type and of the shapes the keys take, with the edges
/// that broke things: huge and tiny numbers, u64 past i64, line breaks.
fn value() -> impl Strategy<Value = String> {
    prop_oneof![
        any::<i64>().prop_map(|i| i.to_string()),
        any::<u64>().prop_map(|i| i.to_string()),
        (0u32..40).prop_map(|i| i.to_string()),
        any::<f64>().prop_map(|x| format!("{x:e}")),
        (-1e3f64..1e3).prop_map(|x| x.to_string()),
        prop::sample::select(vec![
            "5e-324",
            "1e-300",
            "1e300",
            "-0",
            "nan",
            "inf",
            "-inf",
            "true",
            "\"\"",
            "[]",
            "[0, 1]",
            "[18446744073709551615]",
            "corners",
            "none",
            "grid",
            "lattice",
            "chain",
            "rope",
            "spring",
            "horizontal",
            "rk4",
            "implicit-euler",
            "xpbd",
            "1,0,0",
            "0,-9.81,0",
            "{a = 1}",
            "32\nheight=4",
            "\"a\nb\"",
        ])
        .prop_map(str::to_string),
        "[ -~]{0,12}",
    ]
}

/// The system built from `scene`, if it builds, checked.
fn check_built(scene: &Scene) {
    let Ok(resolved) = scene.resolve() else {
        return;
    };
    // Keep the property test small: large layouts are covered elsewhere.
    if resolved.particle_count() > 4096 {
        return;
    }
    let system = resolved.build();
    let p = system.params();
    assert!(p.dt.is_finite() && p.dt > 0.0, "dt = {}", p.dt);
    for (i, m) in system.model().mass.iter().enumerate() {
        assert!(m.is_finite() && *m > 0.0, "mass {i} = {m}");
        let w = system.model().inv_mass[i];
        assert!(w.is_finite() && w >= 0.0, "inverse mass {i} = {w}");
    }
    for s in system.springs() {
        assert!(
            s.rest.is_finite() && s.rest >= 0.0,
            "rest length {}",
            s.rest
        );
        let m = system.model().material(s.kind);
        assert!(m.stiffness.is_finite() && m.damping.is_finite());
    }
    assert!(system.positions().iter().all(|x| x.is_finite()));
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 256, ..ProptestConfig::default() })]

    #[test]
    fn set_never_panics_and_accepted_scenes_build_sound_systems(
        scene in prop::sample::select(builtin_scenes().iter().map(|b| b.name).collect::<Vec<_>>()),
        edits in prop::collection::vec((prop::sample::select(KEYS.to_vec()), value()), 1..4),
    ) {
        let mut scene = Scene::load(scene).unwrap();
        for (key, value) in &edits {
            let before = scene.clone();
            if scene.set(key, value).is_err() {
                // Compared as text: an earlier accepted `nan` is never equal to itself.
                let (now, then) = (format!("{scene:?}"), format!("{before:?}"));
                prop_assert_eq!(now, then, "a refused edit changes nothing");
            }
            let _ = scene.set_all([format!("{key}={value}").as_str()]);
        }
        check_built(&scene);
    }

    #[test]
    fn scene_files_never_panic(
        lines in prop::collection::vec((prop::sample::select(KEYS.to_vec()), value()), 0..5),
    ) {
        let text: String = lines.iter().map(|(k, v)| format!("{k} = {v}\n")).collect();
        if let Ok(scene) = Scene::parse(&text, "proptest") {
            check_built(&scene);
        }
    }
}
