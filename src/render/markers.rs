//! Scenes without a surface (spring, chain, rope, jelly): the particles as lit
//! low-poly spheres and the springs as lit tubes, real meshes drawn by the mesh
//! pipeline, so they are shaded and cast shadows like the cloth.

use glam::Vec3;

use super::geometry::MeshVertex;

/// Rings and segments of a particle's sphere.
const SPHERE_RINGS: u32 = 8;
const SPHERE_SEGMENTS: u32 = 12;
/// Sides of a spring's tube.
const TUBE_SIDES: u32 = 10;
/// Particles plus springs above which the scene falls back to lines and discs
/// (the meshes are rebuilt on the CPU every frame).
pub const MAX_MARKERS: usize = 8192;
/// A tube's radius as a fraction of the particles' sphere radius.
pub const TUBE_FRACTION: f32 = 0.5;

/// Radius (m) of the particles' spheres: 20 % of the median spring length but
/// at least 1 % of the bounds' diagonal (2 % without springs), never over 4 %;
/// `None` when nothing sensible can be had (no valid particle).
pub fn sphere_radius(positions: &[Vec3], valid: &[bool], lines: &[[u32; 2]]) -> Option<f32> {
    let live: Vec<Vec3> = (positions.iter().zip(valid))
        .filter(|(_, v)| **v)
        .map(|(p, _)| *p)
        .collect();
    let (lo, hi) = cloth_sandbox::view::bounds(&live)?;
    let diagonal = (hi - lo).length();
    let mut lengths: Vec<f32> = lines
        .iter()
        .filter_map(|&[a, b]| {
            let (a, b) = (a as usize, b as usize);
            let ok =
                valid.get(a).copied().unwrap_or(false) && valid.get(b).copied().unwrap_or(false);
            ok.then(|| positions[a].distance(positions[b]))
        })
        .filter(|l| l.is_finite() && *l > 0.0)
        .collect();
    let r = if lengths.is_empty() {
        0.02 * diagonal
    } else {
        let mid = lengths.len() / 2;
        let (_, median, _) = lengths.select_nth_unstable_by(mid, f32::total_cmp);
        let r = (0.2 * *median).max(0.01 * diagonal);
        if diagonal > 0.0 {
            r.min(0.04 * diagonal)
        } else {
            r
        }
    };
    let r = if r > 0.0 { r } else { 0.05 };
    (r.is_finite() && r < 1e4).then_some(r)
}

/// Appends a sphere of radius `r` about `c` in `color` (a UV sphere, flat-shaded
/// by its smooth normals `n = (p - c) / r`).
pub fn push_sphere(
    c: Vec3,
    r: f32,
    color: [f32; 4],
    out: &mut Vec<MeshVertex>,
    idx: &mut Vec<u32>,
) {
    let base = out.len() as u32;
    for i in 0..=SPHERE_RINGS {
        let theta = std::f32::consts::PI * i as f32 / SPHERE_RINGS as f32;
        for j in 0..=SPHERE_SEGMENTS {
            let phi = std::f32::consts::TAU * j as f32 / SPHERE_SEGMENTS as f32;
            let n = Vec3::new(
                theta.sin() * phi.cos(),
                theta.cos(),
                theta.sin() * phi.sin(),
            );
            out.push(vertex(c + n * r, n, color));
        }
    }
    let row = SPHERE_SEGMENTS + 1;
    for i in 0..SPHERE_RINGS {
        for j in 0..SPHERE_SEGMENTS {
            let a = base + i * row + j;
            let b = a + row;
            idx.extend_from_slice(&[a, a + 1, b, a + 1, b + 1, b]);
        }
    }
}

/// Appends an open cylinder of radius `r` from `a` to `b` in `color`, its
/// normals pointing radially out; nothing for a zero-length segment.
pub fn push_tube(
    a: Vec3,
    b: Vec3,
    r: f32,
    color: [f32; 4],
    out: &mut Vec<MeshVertex>,
    idx: &mut Vec<u32>,
) {
    let axis = b - a;
    let Some(dir) = axis.try_normalize() else {
        return;
    };
    // Two unit vectors across the axis.
    let (u, v) = dir.any_orthonormal_pair();
    let base = out.len() as u32;
    for k in 0..=TUBE_SIDES {
        let phi = std::f32::consts::TAU * k as f32 / TUBE_SIDES as f32;
        let n = u * phi.cos() + v * phi.sin();
        out.push(vertex(a + n * r, n, color));
        out.push(vertex(b + n * r, n, color));
    }
    for k in 0..TUBE_SIDES {
        let i = base + 2 * k;
        idx.extend_from_slice(&[i, i + 2, i + 1, i + 1, i + 2, i + 3]);
    }
}

fn vertex(p: Vec3, n: Vec3, color: [f32; 4]) -> MeshVertex {
    let color = [color[0], color[1], color[2], 0.0];
    MeshVertex {
        position: p.to_array(),
        normal: n.to_array(),
        uv: [0.0, 0.0],
        color,
        back: color,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn radius_follows_the_springs_and_stays_finite() {
        let p = [Vec3::ZERO, Vec3::X, Vec3::new(2.0, 0.0, 0.0)];
        let r = sphere_radius(&p, &[true; 3], &[[0, 1], [1, 2]]).unwrap();
        assert!((r - 0.08).abs() < 1e-6, "{r}");
        assert_eq!(sphere_radius(&[], &[], &[]), None);
        let mut out = Vec::new();
        let mut idx = Vec::new();
        push_tube(Vec3::ZERO, Vec3::ZERO, 1.0, [1.0; 4], &mut out, &mut idx);
        assert!(out.is_empty());
    }
}
