//! Colliders (boxes, capsules, meshes, moving spheres) over whole scene runs, on
//! every engine that runs them: no particle ends a step inside one, friction on a
//! turning sphere turns the cloth (and μ = 0 does not), the table holds the
//! tablecloth, a capsule at its fastest does not pass through a cloth, and the
//! grid kernel agrees with the f64 reference.

use glam::DVec3;

use crate::common::{build, max_distance};
use cloth_sandbox::scene::Scene;
use cloth_sandbox::sim::grid_kernel::Precision;
use cloth_sandbox::sim::{Engine, System};

/// The deepest any free particle is within a collider's contact surface, as a
/// fraction of that collider's thickness.
fn deepest(system: &System) -> f64 {
    let (x, t) = (system.positions(), system.time());
    let mut worst: f64 = 0.0;
    for (i, &p) in x.iter().enumerate() {
        if system.inv_masses()[i] == 0.0 {
            continue;
        }
        for c in system.colliders() {
            if let Some(touch) = c.touch(p, t) {
                worst = worst.max(touch.depth / c.thickness);
            }
        }
    }
    worst
}

/// No particle ends a frame more than a tenth of the thickness inside a
/// collider, over 2 s of each collider scene, on the f64 reference and on the
/// fast engine the scene runs on. (Each collider puts the particles it touches
/// on its contact surface; a later collider's push or the cloth's own springs in
/// the next step are what may leave one inside, by far less than this.)
#[test]
fn no_particle_ends_inside_a_collider() {
    for scene in ["table", "twist", "slide"] {
        for exact in [true, false] {
            let mut system = build(scene, &[]);
            system.set_fast_path(!exact);
            let mut worst: f64 = 0.0;
            for _ in 0..120 {
                system.run(16).unwrap();
                worst = worst.max(deepest(&system));
            }
            let engine = system.engine().name();
            assert!(
                worst < 0.1,
                "{scene} on {engine}: {worst} of the thickness inside"
            );
        }
    }
}

/// Angular momentum (kg m²/s) about the vertical through the origin, and what it
/// would be if the whole cloth turned rigidly at `omega` rad/s.
fn spin(system: &System, omega: f64) -> (f64, f64) {
    let (x, v, m) = (system.positions(), system.velocities(), system.masses());
    let l: f64 = (0..x.len()).map(|i| m[i] * x[i].cross(v[i]).y).sum();
    let rigid: f64 = (0..x.len())
        .map(|i| m[i] * (x[i].x * x[i].x + x[i].z * x[i].z) * omega)
        .sum();
    (l, rigid)
}

/// The twist scene's sphere turns at π rad/s about y: with friction the cloth
/// picks up angular momentum the same way round, a good share of turning with it;
/// with μ = 0 the surface's motion gives it none (the push is along the normal,
/// which passes through the axis).
#[test]
fn a_turning_sphere_turns_the_cloth_only_with_friction() {
    let omega = std::f64::consts::PI;
    // The f64 reference, then the grid kernel.
    for fast in [false, true] {
        let mut turning = build("twist", &[]);
        turning.set_fast_path(fast);
        turning.run(960).unwrap();
        let (l, rigid) = spin(&turning, omega);
        let engine = turning.engine().name();
        assert!(
            l > 0.2 * rigid,
            "μ = 0.8 on {engine}: {l} kg m²/s, rigid would be {rigid}"
        );
        let mut slippery = build("twist", &["friction=0"]);
        slippery.set_fast_path(fast);
        slippery.run(960).unwrap();
        let (l, rigid) = spin(&slippery, omega);
        assert!(
            l.abs() < 1e-3 * rigid,
            "μ = 0 on {engine}: {l} kg m²/s, rigid would be {rigid}"
        );
    }
}

/// The table scene's mesh holds the tablecloth: after 3 s the part over the
/// table's 1.2 m square top lies on it (its top face at y = 0, the cloth 0.02 m
/// above), and the rest hangs over the edges above the ground.
#[test]
fn the_table_holds_the_tablecloth() {
    let mut system = build("table", &[]);
    system.set_fast_path(true);
    assert_eq!(system.engine(), Engine::General);
    system.run(2880).unwrap();
    for &p in system.positions() {
        if p.x.abs() < 0.5 && p.z.abs() < 0.5 {
            assert!((0.0..0.03).contains(&p.y), "over the top at {p}");
        }
        assert!(p.y > -0.75, "fell through to the ground at {p}");
    }
    let lowest = system
        .positions()
        .iter()
        .map(|p| p.y)
        .fold(f64::INFINITY, f64::min);
    assert!(
        lowest < -0.1,
        "nothing hangs over the edges: lowest at {lowest}"
    );
}

/// A capsule swept across a floating cloth as fast as a collider may move
/// (`Collider::speed_limit`, where a mouse drag is clamped) pushes all of it
/// ahead: no particle is left behind its axis, as one would be had the capsule
/// passed through it in a step.
#[test]
fn a_fast_capsule_does_not_pass_through_the_cloth() {
    let text = r#"
layout = "grid"
orientation = "horizontal"
width = 24
height = 24
rest_length = 0.04
particle_mass = 0.0005
stiffness = 60.0
damping = 0.01
gravity = "0,0,0"
pins = "none"
thickness = 0.02
origin = "-0.46,0,-0.46"
dt = 0.0010416666666666667

[[colliders]]
shape = "capsule"
a = "-0.6,0,-0.7"
b = "-0.6,0,0.7"
radius = 0.03
"#;
    // The f64 reference, then the grid kernel.
    for fast in [false, true] {
        let mut system = Scene::parse(text, "test").unwrap().build().unwrap();
        system.set_fast_path(fast);
        let dt = system.params().dt;
        let limit = system.colliders()[0].speed_limit(dt);
        let mut x = -0.6;
        while x < 1.0 {
            // As the app does every frame: towards the cursor, far ahead, at most
            // the limit.
            system.move_collider(0, DVec3::new(x, 0.0, 0.0), DVec3::new(1e6, 0.0, 0.0));
            system.run(16).unwrap();
            x += limit * 16.0 * dt;
        }
        let engine = system.engine().name();
        let (axis, _) = system.colliders()[0].pose_at(system.time());
        for p in system.positions() {
            assert!(
                p.x > axis.x,
                "{engine}: a particle at {p} is behind the capsule at {axis}: it passed through"
            );
        }
    }
}

/// The grid kernel agrees with the f64 reference on each collider scene on a
/// grid (the table's cloth, a mesh, runs on the reference itself). The twist's
/// and the slide's grids run on the grid kernel in fixed point and float32: particle by
/// particle within float32 round-off for 200 steps (measured 1.3e-7 and 5.7e-8
/// m), and the cloth's mean position within 1 mm after 1,000 (measured 0.57 mm
/// and 6.7e-7 mm). The twist amplifies round-off as the cloth wraps the turning
/// sphere (1e-7 m on one particle of the reference grows to 4e-4 m in 1,000
/// steps); the grid kernel in float64 stays within 1e-9 m of the reference
/// (`fast_path::grid::tests`).
#[test]
fn every_fast_engine_agrees_with_the_reference() {
    let mean =
        |s: &System| s.positions().iter().copied().sum::<DVec3>() / s.particle_count() as f64;
    for (scene, engine, early, later) in [
        ("twist", Engine::Grid(Precision::Mixed), 1e-6, 1e-3),
        ("slide", Engine::Grid(Precision::Mixed), 1e-6, 1e-3),
    ] {
        let mut fast = build(scene, &[]);
        fast.set_fast_path(true);
        let mut exact = build(scene, &[]);
        fast.run(200).unwrap();
        exact.run(200).unwrap();
        assert_eq!(fast.engine(), engine, "{scene}");
        let d = max_distance(fast.positions(), exact.positions());
        assert!(d < early, "{scene}: {d:e} m apart after 200 steps");
        assert!(d > 0.0, "{scene}: bit for bit: did the grid kernel run?");
        fast.run(800).unwrap();
        exact.run(800).unwrap();
        let d = (mean(&fast) - mean(&exact)).length();
        assert!(d < later, "{scene}: means {d:e} m apart after 1,000 steps");
    }
}
