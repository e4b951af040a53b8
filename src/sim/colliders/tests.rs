//! The shapes' distances against geometry worked by hand, and the contact law's
//! push and friction against their definitions.

use glam::{DQuat, DVec3};

use super::mesh::closest_on_triangle;
use super::*;

const EPS: f64 = 1e-12;

/// Numbers uniform on [-0.5, 0.5), from `seed` (a linear congruential generator:
/// the same every run).
fn centred_uniform(seed: u64) -> impl FnMut() -> f64 {
    let mut state = seed;
    move || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    }
}

/// One collider shape of each kind, each some 0.2 to 0.8 m across.
fn every_shape() -> [Shape; 4] {
    [
        Shape::Sphere { radius: 0.3 },
        Shape::Box {
            half_extents: DVec3::new(0.4, 0.1, 0.2),
        },
        Shape::Capsule {
            a: DVec3::new(-0.3, 0.1, 0.0),
            b: DVec3::new(0.4, -0.1, 0.1),
            radius: 0.1,
        },
        Shape::Mesh(std::sync::Arc::new(cube_mesh(0.05))),
    ]
}

/// A box's surface ([`Shape::surface`]) at `p`, within `reach`.
fn cuboid(p: DVec3, half: DVec3, reach: f64) -> Option<(f64, DVec3)> {
    Shape::Box { half_extents: half }.surface(p, reach)
}

/// A capsule of radius 0.2 about `ends`: its surface at `p`.
fn capsule(p: DVec3, (a, b): (DVec3, DVec3)) -> Option<(f64, DVec3)> {
    Shape::Capsule { a, b, radius: 0.2 }.surface(p, 1.0)
}

/// The law ([`crate::sim::laws::collide`]) on a particle at `x` with velocity
/// `v`, `collider` alone at time 0, after a step `h`.
fn respond(collider: &Collider, x: DVec3, v: DVec3, h: f64) -> (DVec3, DVec3) {
    let pose = [collider.pose(0.0)];
    let (x, v) =
        crate::sim::laws::collide(std::slice::from_ref(collider), &pose, x.into(), v.into(), h);
    (x.into(), v.into())
}

/// A box's distance outside a face, an edge and a corner, and inside from the
/// nearest face, each worked by hand.
#[test]
fn box_distances_and_normals() {
    let half = DVec3::new(0.5, 0.2, 0.3);
    let (d, n) = cuboid(DVec3::new(0.0, 0.25, 0.0), half, 1.0).unwrap();
    assert!((d - 0.05).abs() < EPS && n == DVec3::Y, "{d} {n}");
    // Past an edge: (0.6 - 0.5, 0.3 - 0.2) away, along their diagonal.
    let (d, n) = cuboid(DVec3::new(0.6, 0.3, 0.0), half, 1.0).unwrap();
    assert!((d - 0.02f64.sqrt()).abs() < EPS, "{d}");
    assert!((n - DVec3::new(1.0, 1.0, 0.0).normalize()).length() < EPS);
    let (d, _) = cuboid(DVec3::new(-0.6, -0.3, -0.4), half, 1.0).unwrap();
    assert!((d - 0.03f64.sqrt()).abs() < EPS, "{d}");
    // Inside: 0.15 from the top face, farther from the others.
    let (d, n) = cuboid(DVec3::new(0.1, 0.05, 0.0), half, 1.0).unwrap();
    assert!((d + 0.15).abs() < EPS && n == DVec3::Y, "{d} {n}");
    let (d, n) = cuboid(DVec3::new(-0.45, 0.0, 0.0), half, 1.0).unwrap();
    assert!((d + 0.05).abs() < EPS && n == -DVec3::X, "{d} {n}");
    assert!(cuboid(DVec3::new(0.0, 0.25, 0.0), half, 0.04).is_none());
}

/// A capsule is a ball about its axis's nearest point: beside the axis, past an
/// end, and inside.
#[test]
fn capsule_distances_and_normals() {
    let ends = (DVec3::new(-1.0, 0.0, 0.0), DVec3::new(1.0, 0.0, 0.0));
    let (d, n) = capsule(DVec3::new(0.3, 0.0, 0.5), ends).unwrap();
    assert!((d - 0.3).abs() < EPS && (n - DVec3::Z).length() < EPS);
    let (d, n) = capsule(DVec3::new(1.3, 0.4, 0.0), ends).unwrap();
    assert!((d - 0.3).abs() < EPS && (n - DVec3::new(0.6, 0.8, 0.0)).length() < EPS);
    let (d, n) = capsule(DVec3::new(-0.5, -0.05, 0.0), ends).unwrap();
    assert!((d + 0.15).abs() < EPS && (n + DVec3::Y).length() < EPS);
}

/// The nearest point of a triangle in each of its Voronoi regions.
#[test]
fn nearest_points_of_a_triangle() {
    let (a, b, c) = (DVec3::ZERO, DVec3::X, DVec3::Y);
    let cases = [
        (DVec3::new(0.2, 0.2, 1.0), DVec3::new(0.2, 0.2, 0.0)), // the face
        (DVec3::new(-1.0, -1.0, 0.5), a),                       // corner a
        (DVec3::new(2.0, -0.5, 0.0), b),                        // corner b
        (DVec3::new(0.5, -1.0, 0.0), DVec3::new(0.5, 0.0, 0.0)), // edge ab
        (DVec3::new(1.0, 1.0, 0.0), DVec3::new(0.5, 0.5, 0.0)), // edge bc
        (DVec3::new(-0.5, 0.3, 0.2), DVec3::new(0.0, 0.3, 0.0)), // edge ca
    ];
    for (p, want) in cases {
        let got = closest_on_triangle(p, a, b, c);
        assert!((got - want).length() < EPS, "{p}: {got} not {want}");
    }
}

/// A unit cube as a mesh, wound outwards.
fn cube_mesh(reach: f64) -> ColliderMesh {
    let corners = (0..8)
        .map(|k| DVec3::new((k & 1) as f64, ((k >> 1) & 1) as f64, ((k >> 2) & 1) as f64) - 0.5)
        .collect();
    let quads = [
        [0, 2, 3, 1],
        [4, 5, 7, 6],
        [0, 1, 5, 4],
        [2, 6, 7, 3],
        [0, 4, 6, 2],
        [1, 3, 7, 5],
    ];
    let triangles = quads
        .iter()
        .flat_map(|&[a, b, c, d]| [[a, b, c], [a, c, d]])
        .collect();
    ColliderMesh::new(corners, triangles, reach)
}

/// A cube as a mesh gives the box's distances and normals near its faces, edges
/// and corners, on both sides, and nothing beyond its reach.
#[test]
fn a_mesh_cube_is_the_box() {
    let mesh = cube_mesh(0.1);
    let half = DVec3::splat(0.5);
    let mut next = centred_uniform(7);
    let mut checked = 0;
    for _ in 0..20_000 {
        let p = DVec3::new(next(), next(), next()) * 1.4;
        let want = cuboid(p, half, 0.08);
        let got = mesh.surface(p, 0.08);
        match (want, got) {
            (Some((dw, nw)), Some((dg, ng))) if dw > -0.1 => {
                assert!((dw - dg).abs() < 1e-9, "{p}: {dg} not {dw}");
                assert!((nw - ng).length() < 1e-6 || dw < 0.0, "{p}: {ng} not {nw}");
                checked += 1;
            }
            (Some((dw, _)), None) => assert!(dw <= -0.1 + 1e-9, "{p}: missed at {dw}"),
            (None, Some((dg, _))) => panic!("{p}: found at {dg}, out of reach"),
            _ => {}
        }
    }
    assert!(checked > 1000, "only {checked} points near the surface");
}

/// The law: a particle inside a still collider is put on its contact surface
/// with the push's velocity; on a surface moving along itself, friction μ takes
/// from the velocity relative to the surface at most μ times the push's
/// velocity, and μ = 0 takes none.
#[test]
fn push_and_friction_follow_the_surface() {
    let h = 1e-3;
    let mut ball = Collider::at_rest(Shape::Sphere { radius: 0.5 }, DVec3::ZERO, 0.0, 0.01);
    let x = DVec3::new(0.0, 0.505, 0.0);
    let touch = ball.touch(x, 0.0).unwrap();
    assert!((touch.depth - 0.005).abs() < EPS && touch.normal == DVec3::Y);
    let (x1, v1) = respond(&ball, x, DVec3::ZERO, h);
    assert!((x1.y - 0.51).abs() < EPS && (v1 - DVec3::new(0.0, 5.0, 0.0)).length() < 1e-9);
    // Turning about y at 2 rad/s: at the top, the surface is still; on the
    // equator at +x it moves at -z... take a particle at rest on the equator.
    ball.angular_velocity = DVec3::new(0.0, 2.0, 0.0);
    let x = DVec3::new(0.505, 0.0, 0.0);
    let touch = ball.touch(x, 0.0).unwrap();
    assert!((touch.surface_velocity - DVec3::new(0.0, 0.0, -1.01)).length() < EPS);
    for (mu, dz) in [(0.0, 0.0), (0.1, -0.5), (10.0, -1.01)] {
        ball.friction = mu;
        let (_, v) = respond(&ball, x, DVec3::ZERO, h);
        assert!((v.x - 5.0).abs() < 1e-9, "the push's velocity stays: {v}");
        assert!((v.z - dz).abs() < 1e-9, "μ = {mu}: {v} not {dz} along z");
    }
}

/// A pose moves and turns with the collider's velocities.
#[test]
fn poses_follow_the_motion() {
    let mut c = Collider::at_rest(
        Shape::Box {
            half_extents: DVec3::ONE,
        },
        DVec3::ZERO,
        0.0,
        0.0,
    );
    c.velocity = DVec3::new(1.0, 0.0, 0.0);
    c.angular_velocity = DVec3::new(0.0, std::f64::consts::PI, 0.0);
    let (center, rotation) = c.pose_at(0.5);
    assert!((center - DVec3::new(0.5, 0.0, 0.0)).length() < EPS);
    let turned = DQuat::from_rotation_y(0.5 * std::f64::consts::PI);
    assert!(rotation.angle_between(turned) < 1e-9);
    // Moved and stopped there at 0.5 s, it keeps turning.
    c.move_to(DVec3::new(3.0, 0.0, 0.0), DVec3::ZERO, 0.5);
    let (center, rotation) = c.pose_at(1.0);
    let turned = DQuat::from_rotation_y(std::f64::consts::PI);
    assert!(center == DVec3::new(3.0, 0.0, 0.0) && rotation.angle_between(turned) < 1e-9);
}

/// A ray meets a box, a sphere and a turned capsule where geometry says, to
/// within the march's step, and misses beside them.
#[test]
fn rays_hit_the_solids() {
    let half = DVec3::new(0.5, 0.3, 0.4);
    let cube = Collider::at_rest(
        Shape::Box { half_extents: half },
        DVec3::new(1.0, 0.0, 0.0),
        0.0,
        0.0,
    );
    let s = cube
        .ray_hit(DVec3::new(1.0, 0.0, 5.0), -DVec3::Z, 0.0, 100.0)
        .unwrap();
    assert!((s - 4.6).abs() <= 0.25 * 0.3 + 1e-9, "{s}");
    assert!(
        cube.ray_hit(DVec3::new(2.0, 0.0, 5.0), -DVec3::Z, 0.0, 100.0)
            .is_none()
    );
    let ball = Collider::at_rest(Shape::Sphere { radius: 0.5 }, DVec3::ZERO, 0.0, 0.0);
    let s = ball
        .ray_hit(DVec3::new(0.0, 3.0, 0.0), -DVec3::Y, 0.0, 100.0)
        .unwrap();
    assert!((s - 2.5).abs() <= 0.125 + 1e-9, "{s}");
    let ends = (DVec3::new(-1.0, 0.0, 0.0), DVec3::new(1.0, 0.0, 0.0));
    let mut rod = Collider::at_rest(
        Shape::Capsule {
            a: ends.0,
            b: ends.1,
            radius: 0.1,
        },
        DVec3::ZERO,
        0.0,
        0.0,
    );
    rod.rotation = DQuat::from_rotation_z(std::f64::consts::FRAC_PI_2);
    assert!(
        rod.ray_hit(DVec3::new(0.0, 0.8, 3.0), -DVec3::Z, 0.0, 100.0)
            .is_some()
    );
    assert!(
        rod.ray_hit(DVec3::new(0.8, 0.0, 3.0), -DVec3::Z, 0.0, 100.0)
            .is_none()
    );
}

/// Every point a collider touches lies in its bounds (`Collider::bounds_at`),
/// for each shape turned at random; and the bounds of a box on the world's axes
/// are the box grown by the thickness, no looser.
#[test]
fn what_a_collider_touches_lies_in_its_bounds() {
    let mut next = centred_uniform(11);
    let shapes = every_shape();
    for shape in shapes {
        let mut touched = 0;
        for _ in 0..200 {
            let mut collider =
                Collider::at_rest(shape.clone(), DVec3::new(1.0, -2.0, 0.5), 0.5, 0.05);
            let axis = DVec3::new(next(), next(), next()).normalize_or(DVec3::Y);
            collider.rotation = DQuat::from_axis_angle(axis, 8.0 * next());
            let pose = collider.pose(0.0);
            let (lo, hi) = collider.bounds_at(&pose);
            for _ in 0..100 {
                let x = pose.center + DVec3::new(next(), next(), next()) * 2.0;
                if collider.touch_at(&pose, x).is_some() {
                    touched += 1;
                    assert!(
                        x.cmpge(lo).all() && x.cmple(hi).all(),
                        "{}: {x} out of {lo}..{hi}",
                        shape.name()
                    );
                }
            }
        }
        assert!(
            touched > 100,
            "{}: only {touched} points touched",
            shape.name()
        );
    }
    let half = DVec3::new(0.4, 0.1, 0.2);
    let flat = Collider::at_rest(Shape::Box { half_extents: half }, DVec3::ZERO, 0.5, 0.05);
    let (lo, hi) = flat.bounds_at(&flat.pose(0.0));
    assert!((hi - (half + 0.05)).abs().max_element() < 1e-8, "{hi}");
    assert!((lo + (half + 0.05)).abs().max_element() < 1e-8, "{lo}");
}

/// The law on a block of 8 particles in float64 lanes (as the grid kernel runs
/// it) gives each lane, bit for bit, what it gives the particle alone (as the f64
/// engine runs it): four colliders of every shape, turning and sliding, with
/// friction, each block's points scattered over all of them.
#[test]
fn the_law_in_lanes_is_the_law_on_each_particle() {
    use crate::sim::lanes::{Floats, V3};
    use crate::sim::laws::collide;
    type Block = Floats<f64, 8>;
    let mut next = centred_uniform(5);
    let shapes = every_shape();
    let colliders: Vec<Collider> = shapes
        .into_iter()
        .enumerate()
        .map(|(i, shape)| {
            let centre = DVec3::new(0.5 * i as f64, 0.0, 0.0);
            let mut c = Collider::at_rest(shape, centre, 0.1 + 0.3 * i as f64, 0.02);
            c.rotation = DQuat::from_axis_angle(DVec3::new(1.0, 2.0, 3.0).normalize(), i as f64);
            c.velocity = DVec3::new(0.3, -0.2, 0.1) * i as f64;
            c.angular_velocity = DVec3::new(0.0, 2.0, 1.0 - i as f64);
            c
        })
        .collect();
    let mut poses = Vec::new();
    poses_at(&colliders, 0.37, &mut poses);
    let h = 1e-3;
    let mut moved = 0;
    for _ in 0..5_000 {
        let points: [(DVec3, DVec3); 8] = std::array::from_fn(|_| {
            let x = DVec3::new(0.75 + 2.4 * next(), 0.7 * next(), 0.7 * next());
            (x, DVec3::new(next(), next(), next()) * 4.0)
        });
        let block = |k: usize| {
            let axis = |a: usize| -> Block {
                Floats(std::array::from_fn(|l| {
                    if k == 0 {
                        points[l].0[a]
                    } else {
                        points[l].1[a]
                    }
                }))
            };
            V3 {
                x: axis(0),
                y: axis(1),
                z: axis(2),
            }
        };
        let (x, v) = (block(0), block(1));
        let (xs, vs) = collide(&colliders, &poses, x, v, h);
        for (l, &(x, v)) in points.iter().enumerate() {
            let (x1, v1) = collide(&colliders, &poses, V3::from(x), V3::from(v), h);
            let (x1, v1): (DVec3, DVec3) = (x1.into(), v1.into());
            let lane = |p: V3<Block>| DVec3::new(p.x.0[l], p.y.0[l], p.z.0[l]);
            let bits = |p: DVec3| p.to_array().map(f64::to_bits);
            assert_eq!(bits(lane(xs)), bits(x1), "position of {x}");
            assert_eq!(bits(lane(vs)), bits(v1), "velocity of {x}, {v}");
            moved += usize::from(x1 != x);
        }
    }
    assert!(
        moved > 2_000,
        "only {moved} of 40,000 points touched a collider"
    );
}
