//! Pinned particles never move; the grid builder's spring counts per kind match the
//! closed-form counts (and the peers' published totals); scenes without a surface
//! have no triangles and run no aero pass.

use cloth_sandbox::scene::Scene;
use cloth_sandbox::sim::{Integrator, SpringKind};

fn scene(name: &str, overrides: &[&str]) -> Scene {
    let mut scene = Scene::load(name).expect("built-in scene");
    scene
        .set_all(overrides.iter().copied())
        .expect("valid overrides");
    scene
}

#[test]
fn pinned_particles_never_move_under_any_integrator() {
    for integrator in Integrator::ALL {
        let mut system = scene(
            "cloth",
            &[
                &format!("integrator=\"{}\"", integrator.name()),
                // Explicit Euler and RK2 need a step below 2 zeta / omega here.
                if matches!(integrator, Integrator::ExplicitEuler | Integrator::Rk2) {
                    "dt=5e-5"
                } else {
                    "dt=0.001"
                },
                "width=12",
                "height=10",
                "pins=corners",
            ],
        )
        .build()
        .unwrap();
        let pinned: Vec<usize> = (0..system.particle_count())
            .filter(|&i| system.is_pinned(i))
            .collect();
        assert_eq!(pinned.len(), 4);
        let start: Vec<_> = pinned.iter().map(|&i| system.positions()[i]).collect();
        system.run(500).unwrap();
        for (&i, &p) in pinned.iter().zip(&start) {
            assert_eq!(
                system.positions()[i],
                p,
                "{integrator}: pinned particle {i} moved"
            );
        }
        // The rest did move (gravity and wind act on them).
        assert!(system.positions()[5 * 12 + 6].distance(start[0]) > 0.0);
    }
}

#[test]
fn a_user_pinned_particle_stops_and_stays() {
    let mut system = scene("cloth", &["width=8", "height=8"]).build().unwrap();
    system.run(100).unwrap();
    system.set_pinned(60, true);
    let held = system.positions()[60];
    system.run(300).unwrap();
    assert_eq!(system.positions()[60], held);
    system.set_pinned(60, false);
    system.run(50).unwrap();
    assert_ne!(system.positions()[60], held);
}

/// Closed-form spring counts of a W x H grid, written out here from the stencil.
fn expected_counts(w: usize, h: usize) -> [usize; 3] {
    let structural = h * (w - 1) + w * (h - 1);
    let shear = 2 * (w - 1) * (h - 1);
    let bend = h * w.saturating_sub(2) + w * h.saturating_sub(2);
    [structural, shear, bend]
}

#[test]
fn grid_spring_counts_match_the_formulas() {
    for (w, h) in [
        (1, 1),
        (2, 1),
        (1, 2),
        (2, 2),
        (3, 2),
        (5, 7),
        (15, 8),
        (32, 32),
    ] {
        let system = scene("cloth", &[&format!("width={w}"), &format!("height={h}")])
            .build()
            .unwrap();
        let count = |kind| system.springs().iter().filter(|s| s.kind == kind).count();
        let got = [
            count(SpringKind::Structural),
            count(SpringKind::Shear),
            count(SpringKind::Bend),
        ];
        assert_eq!(got, expected_counts(w, h), "{w}x{h}");
        assert_eq!(count(SpringKind::Other), 0);
        assert_eq!(system.triangles().len(), 2 * (w - 1) * (h - 1));
    }
}

#[test]
fn bench_scene_counts_match_the_peers_published_totals() {
    // From the peers' README: particles and springs of the N x N benchmark cloth.
    for (n, springs) in [(32, 5_826), (64, 23_938), (128, 97_026)] {
        let system = scene("bench", &[&format!("width={n}"), &format!("height={n}")])
            .build()
            .unwrap();
        assert_eq!(system.particle_count(), n * n);
        assert_eq!(system.springs().len(), springs);
    }
}

#[test]
fn springs_are_canonical_and_unique() {
    for name in ["cloth", "jelly", "chain"] {
        let system = scene(name, &[]).build().unwrap();
        let mut pairs: Vec<_> = system.springs().iter().map(|s| (s.a, s.b)).collect();
        assert!(pairs.iter().all(|(a, b)| a < b), "{name}: a < b");
        let n = pairs.len();
        pairs.dedup();
        assert_eq!(pairs.len(), n, "{name}: duplicate springs");
    }
}

#[test]
fn jelly_cube_has_the_seed_lattice() {
    let system = scene("jelly", &[]).build().unwrap();
    assert_eq!(system.particle_count(), 7 * 4 * 4);
    let count = |kind| system.springs().iter().filter(|s| s.kind == kind).count();
    // Axis neighbours, face diagonals (2 per unit square), body diagonals (4 per cube).
    let (w, h, d) = (7, 4, 4);
    let axis = (w - 1) * h * d + w * (h - 1) * d + w * h * (d - 1);
    let faces = 2 * ((w - 1) * (h - 1) * d + (w - 1) * h * (d - 1) + w * (h - 1) * (d - 1));
    let bodies = 4 * (w - 1) * (h - 1) * (d - 1);
    assert_eq!(count(SpringKind::Structural), axis);
    assert_eq!(count(SpringKind::Shear), faces);
    assert_eq!(count(SpringKind::Other), bodies);
    assert!(system.force_terms().ground);
}

#[test]
fn scenes_without_a_surface_have_no_triangles_and_no_aero_pass() {
    for name in ["spring", "chain", "jelly", "rope"] {
        let system = scene(name, &["wind=5,0,0"]).build().unwrap();
        assert!(system.triangles().is_empty(), "{name} has triangles");
        assert!(!system.force_terms().aero, "{name} runs aero");
    }
    let rope = scene("rope", &[]).build().unwrap();
    assert!(rope.springs().is_empty(), "the rope is bars, not springs");
    let bench = scene("bench", &[]).build().unwrap();
    assert!(
        !bench.force_terms().aero,
        "no drag coefficient, no aero pass"
    );
    assert!(scene("cloth", &[]).build().unwrap().force_terms().aero);
}

#[test]
fn wind_changes_nothing_where_there_is_no_aero() {
    let mut calm = scene("chain", &[]).build().unwrap();
    let mut windy = scene("chain", &["wind=30,0,10", "gust=5"]).build().unwrap();
    calm.run(1000).unwrap();
    windy.run(1000).unwrap();
    assert_eq!(calm.positions(), windy.positions());
}

#[test]
fn a_grabbed_particle_stays_held_while_parameters_change() {
    let mut system = scene("cloth", &["width=8", "height=8"]).build().unwrap();
    let target = glam::DVec3::new(0.3, 0.1, 0.2);
    system.grab(36, target);
    let mut params = *system.params();
    params.wind = glam::DVec3::new(3.0, 0.0, 0.0);
    system.set_params(params);
    system.run(50).unwrap();
    assert_eq!(system.positions()[36], target);
    assert_eq!(system.inv_masses()[36], 0.0);
    system.release();
    assert!(system.inv_masses()[36] > 0.0);
    system.run(10).unwrap();
    assert_ne!(system.positions()[36], target, "released, it falls again");
}

/// The jelly cube draws as a solid: its display surface is the lattice's six
/// faces, a closed surface wound one way (every edge is crossed once in each
/// direction), and it is for drawing only: the system itself has no triangles,
/// so no aerodynamic drag.
#[test]
fn the_lattice_draws_as_a_closed_box_of_faces() {
    use std::collections::HashMap;
    let mut scene = Scene::load("jelly").unwrap();
    scene.set_all(["width=5", "height=4", "depth=3"]).unwrap();
    let settings = scene.resolve().unwrap();
    let surface = settings.display_surface();
    let (w, h, d) = (5, 4, 3);
    let quads = (w - 1) * (h - 1) + (w - 1) * (d - 1) + (h - 1) * (d - 1);
    assert_eq!(surface.len(), 2 * 2 * quads);
    let mut directed: HashMap<(u32, u32), u32> = HashMap::new();
    for t in &surface {
        for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
            *directed.entry((a, b)).or_default() += 1;
        }
    }
    for (&(a, b), &n) in &directed {
        assert_eq!(n, 1, "edge {a}->{b} crossed {n} times the same way");
        assert_eq!(
            directed.get(&(b, a)),
            Some(&1),
            "edge {a}-{b} is on one face only"
        );
    }
    assert!(settings.build().triangles().is_empty());
    // A cloth has a surface of its own and no display surface.
    assert!(
        Scene::load("cloth")
            .unwrap()
            .resolve()
            .unwrap()
            .display_surface()
            .is_empty()
    );
}
