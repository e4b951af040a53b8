//! The colliders as triangles to draw, at their pose at a time: spheres, boxes,
//! capsules and meshes, lit with their own normals, in the colliders' colour.

use glam::{DQuat, DVec3};

use super::geometry::{MeshVertex, SOLID_COLOR};
use cloth_sandbox::sim::{Collider, Shape};

/// Rings and segments of a round shape.
const RINGS: u32 = 24;
const SEGMENTS: u32 = 48;

/// Largest coordinate drawn (m): a collider flung far off is left out.
const FARTHEST: f64 = 1e4;

/// Appends `collider` at time `t`, drawn `skin` of its size (a little inside its
/// surface, so that the cloth's flat triangles resting on it hide it).
pub fn push_collider(
    collider: &Collider,
    t: f64,
    skin: f64,
    out: &mut Vec<MeshVertex>,
    idx: &mut Vec<u32>,
) {
    let (center, rotation) = collider.pose_at(t);
    if !(center.is_finite() && center.abs().max_element() < FARTHEST) {
        return;
    }
    let place = |p: DVec3| center + rotation * p;
    match &collider.shape {
        Shape::Sphere { radius } => round(
            place(DVec3::ZERO),
            place(DVec3::ZERO),
            rotation,
            skin * radius,
            out,
            idx,
        ),
        Shape::Capsule { a, b, radius } => {
            let axis = (*b - *a).normalize_or(DVec3::Y);
            let turn = rotation * DQuat::from_rotation_arc(DVec3::Y, axis);
            round(place(*a), place(*b), turn, skin * radius, out, idx)
        }
        Shape::Box { half_extents } => cuboid(*half_extents * skin, &place, rotation, out, idx),
        Shape::Mesh(mesh) => {
            for t in mesh.triangles() {
                let [p, q, r] = t.map(|i| place(mesh.positions()[i as usize]));
                let normal = (q - p).cross(r - p).normalize_or_zero();
                flat(&[p, q, r], normal, out, idx);
            }
        }
    }
}

/// A ball of `radius` drawn as two hemispheres about `bottom` and `top` joined by
/// a cylinder (a sphere when they coincide), its axis `turn`'s y.
fn round(
    bottom: DVec3,
    top: DVec3,
    turn: DQuat,
    radius: f64,
    out: &mut Vec<MeshVertex>,
    idx: &mut Vec<u32>,
) {
    let base = out.len() as u32;
    // Ring i from the top pole down; the equator twice, once for each end.
    let rings: Vec<(f64, DVec3)> = (0..=RINGS)
        .flat_map(|i| {
            let theta = std::f64::consts::PI * f64::from(i) / f64::from(RINGS);
            match i.cmp(&(RINGS / 2)) {
                std::cmp::Ordering::Less => vec![(theta, top)],
                std::cmp::Ordering::Equal => vec![(theta, top), (theta, bottom)],
                std::cmp::Ordering::Greater => vec![(theta, bottom)],
            }
        })
        .collect();
    for (k, &(theta, end)) in rings.iter().enumerate() {
        for j in 0..=SEGMENTS {
            let phi = std::f64::consts::TAU * f64::from(j) / f64::from(SEGMENTS);
            let local = DVec3::new(
                theta.sin() * phi.cos(),
                theta.cos(),
                theta.sin() * phi.sin(),
            );
            let n = turn * local;
            out.push(vertex(
                end + n * radius,
                n,
                [j as f32 / SEGMENTS as f32, k as f32 / rings.len() as f32],
            ));
        }
    }
    let row = SEGMENTS + 1;
    for i in 0..rings.len() as u32 - 1 {
        for j in 0..SEGMENTS {
            let a = base + i * row + j;
            let b = a + row;
            idx.extend_from_slice(&[a, a + 1, b, a + 1, b + 1, b]);
        }
    }
}

/// A box of half extents `half`, each face flat.
fn cuboid(
    half: DVec3,
    place: &impl Fn(DVec3) -> DVec3,
    rotation: DQuat,
    out: &mut Vec<MeshVertex>,
    idx: &mut Vec<u32>,
) {
    for axis in 0..3 {
        for sign in [-1.0, 1.0] {
            let mut n = DVec3::ZERO;
            n[axis] = sign;
            // The two axes across the face.
            let (a, b) = ((axis + 1) % 3, (axis + 2) % 3);
            let corner = |s: f64, r: f64| {
                let mut p = n * half[axis];
                p[a] = s * half[a];
                p[b] = r * half[b];
                place(p)
            };
            let quad = if sign > 0.0 {
                [
                    corner(-1.0, -1.0),
                    corner(1.0, -1.0),
                    corner(1.0, 1.0),
                    corner(-1.0, 1.0),
                ]
            } else {
                [
                    corner(-1.0, -1.0),
                    corner(-1.0, 1.0),
                    corner(1.0, 1.0),
                    corner(1.0, -1.0),
                ]
            };
            flat(&quad, rotation * n, out, idx);
        }
    }
}

/// A flat convex polygon (a triangle or a quad) facing `normal`.
fn flat(corners: &[DVec3], normal: DVec3, out: &mut Vec<MeshVertex>, idx: &mut Vec<u32>) {
    let base = out.len() as u32;
    for (k, &p) in corners.iter().enumerate() {
        out.push(vertex(p, normal, [(k & 1) as f32, (k >> 1) as f32]));
    }
    for k in 1..corners.len() as u32 - 1 {
        idx.extend_from_slice(&[base, base + k, base + k + 1]);
    }
}

fn vertex(p: DVec3, n: DVec3, uv: [f32; 2]) -> MeshVertex {
    MeshVertex {
        position: p.as_vec3().to_array(),
        normal: n.as_vec3().to_array(),
        uv,
        color: SOLID_COLOR,
        back: SOLID_COLOR,
    }
}
