//! CPU-side vertex building: per-vertex normals (area-weighted sum of face
//! normals, `n_i = normalize(Σ (b - a) × (c - a))`), line and point vertices,
//! the sphere collider's mesh, and the scene's colours. Everything that leaves
//! here is finite.

use bytemuck::{Pod, Zeroable};
use glam::{Vec2, Vec3};

/// Coordinates are clamped to ±this (m) so huge but finite values cannot overflow in shaders.
const MAX_COORD: f32 = 1.0e5;

/// A vertex of a lit mesh.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct MeshVertex {
    pub position: [f32; 3],
    pub normal: [f32; 3],
    pub uv: [f32; 2],
    /// rgb: front colour; a: how much the texture modulates it.
    pub color: [f32; 4],
    /// rgb: back colour (seen from behind the triangle's winding); a: unused.
    pub back: [f32; 4],
}

/// A vertex of a line segment.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct LineVertex {
    pub position: [f32; 3],
    pub color: [f32; 4],
}

/// One particle disc.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct PointInstance {
    pub position: [f32; 3],
    /// Diameter in pixels.
    pub size: f32,
    pub color: [f32; 4],
}

/// Cloth front colour, warm (linear RGB; a: unused here, set to the texture weight).
pub const CLOTH_COLOR: [f32; 4] = [0.93, 0.56, 0.34, 1.0];
/// Cloth back colour, a cool blue-grey, clearly apart from the front.
pub const CLOTH_BACK_COLOR: [f32; 4] = [0.38, 0.50, 0.68, 1.0];
/// Sphere collider colour, untextured.
const SPHERE_COLOR: [f32; 4] = SOLID_COLOR;
/// Colour of every collider (boxes, capsules, meshes, spheres): a light
/// porcelain grey, apart from both sides of the cloth.
pub const SOLID_COLOR: [f32; 4] = [0.86, 0.86, 0.84, 0.0];
/// Wireframe colour.
pub const WIRE_COLOR: [f32; 4] = [0.08, 0.09, 0.12, 1.0];

/// Colour of the triangle edges drawn alone, without the surface: dark slate
/// on the light sky and floor (linear RGBA).
pub const WIRE_ALONE_COLOR: [f32; 4] = [0.14, 0.18, 0.27, 1.0];
/// Colour of the live reference's ghost wireframe: a magenta apart from the
/// warm front, the cool back, the sky and the colliders (linear RGBA).
pub const GHOST_COLOR: [f32; 4] = [0.85, 0.10, 0.75, 1.0];
/// Free particle colour.
pub const PARTICLE_COLOR: [f32; 4] = [0.95, 0.95, 0.98, 1.0];
/// Pinned particle colour.
pub const PIN_COLOR: [f32; 4] = [0.90, 0.12, 0.10, 1.0];
/// Colour of the particle under the cursor or being dragged.
pub const HIGHLIGHT_COLOR: [f32; 4] = [1.0, 0.85, 0.1, 1.0];

/// `p` if it is finite, clamped to the coordinate range; `None` otherwise.
pub fn sanitize(p: Vec3) -> Option<Vec3> {
    p.is_finite()
        .then(|| p.clamp(Vec3::splat(-MAX_COORD), Vec3::splat(MAX_COORD)))
}

/// Finite copies of `positions` (non-finite ones become the origin) and a mask of
/// which were valid.
pub fn sanitize_all(positions: &[Vec3], out: &mut Vec<Vec3>, valid: &mut Vec<bool>) {
    out.clear();
    valid.clear();
    for &p in positions {
        match sanitize(p) {
            Some(q) => {
                out.push(q);
                valid.push(true);
            }
            None => {
                out.push(Vec3::ZERO);
                valid.push(false);
            }
        }
    }
}

/// Triangles whose three indices are in range and refer to valid vertices.
pub fn usable_triangle(t: &[u32; 3], valid: &[bool]) -> bool {
    t.iter()
        .all(|&i| valid.get(i as usize).copied().unwrap_or(false))
}

/// Area-weighted vertex normals; a vertex with no non-degenerate face gets +y.
pub fn vertex_normals(positions: &[Vec3], triangles: &[[u32; 3]], valid: &[bool]) -> Vec<Vec3> {
    let mut normals = vec![Vec3::ZERO; positions.len()];
    for t in triangles {
        if !usable_triangle(t, valid) {
            continue;
        }
        let [a, b, c] = t.map(|i| positions[i as usize]);
        let n = (b - a).cross(c - a);
        if !n.is_finite() {
            continue;
        }
        for &i in t {
            normals[i as usize] += n;
        }
    }
    for n in &mut normals {
        *n = n.normalize_or(Vec3::Y);
    }
    normals
}

/// Mesh vertices for the cloth surface.
pub fn cloth_vertices(
    positions: &[Vec3],
    normals: &[Vec3],
    uvs: &[Vec2],
    textured: bool,
    out: &mut Vec<MeshVertex>,
) {
    out.clear();
    // The checker modulates the colour partly, so its dark cells keep the hue.
    let weight = if textured { 0.6 } else { 0.0 };
    let mut color = CLOTH_COLOR;
    color[3] = weight;
    for (i, p) in positions.iter().enumerate() {
        let uv = uvs
            .get(i)
            .copied()
            .filter(|uv| uv.is_finite())
            .unwrap_or(Vec2::ZERO);
        out.push(MeshVertex {
            position: p.to_array(),
            normal: normals.get(i).copied().unwrap_or(Vec3::Y).to_array(),
            uv: uv.to_array(),
            color,
            back: CLOTH_BACK_COLOR,
        });
    }
}

/// Unique undirected edges of `triangles`, each as `(min, max)`, sorted.
pub fn triangle_edges(triangles: &[[u32; 3]]) -> Vec<[u32; 2]> {
    let mut edges: Vec<[u32; 2]> = triangles
        .iter()
        .flat_map(|&[a, b, c]| [[a, b], [b, c], [c, a]])
        .map(|[a, b]| [a.min(b), a.max(b)])
        .collect();
    edges.sort_unstable();
    edges.dedup();
    edges
}

/// Appends a segment per edge whose endpoints are valid.
pub fn push_lines(
    positions: &[Vec3],
    valid: &[bool],
    edges: &[[u32; 2]],
    color: impl Fn(usize) -> [f32; 4],
    out: &mut Vec<LineVertex>,
) {
    for (k, &[a, b]) in edges.iter().enumerate() {
        let (a, b) = (a as usize, b as usize);
        if !(valid.get(a).copied().unwrap_or(false) && valid.get(b).copied().unwrap_or(false)) {
            continue;
        }
        let c = color(k);
        let c = if c.iter().all(|x| x.is_finite()) {
            c
        } else {
            WIRE_COLOR
        };
        out.push(LineVertex {
            position: positions[a].to_array(),
            color: c,
        });
        out.push(LineVertex {
            position: positions[b].to_array(),
            color: c,
        });
    }
}

/// A UV sphere of radius `r` about `c`.
pub fn sphere_mesh(c: Vec3, r: f32, out: &mut Vec<MeshVertex>, idx: &mut Vec<u32>) {
    const RINGS: u32 = 24;
    const SEGMENTS: u32 = 48;
    let base = out.len() as u32;
    for i in 0..=RINGS {
        let theta = std::f32::consts::PI * i as f32 / RINGS as f32;
        for j in 0..=SEGMENTS {
            let phi = std::f32::consts::TAU * j as f32 / SEGMENTS as f32;
            let n = Vec3::new(
                theta.sin() * phi.cos(),
                theta.cos(),
                theta.sin() * phi.sin(),
            );
            out.push(MeshVertex {
                position: (c + n * r).to_array(),
                normal: n.to_array(),
                uv: [j as f32 / SEGMENTS as f32, i as f32 / RINGS as f32],
                color: SPHERE_COLOR,
                back: SPHERE_COLOR,
            });
        }
    }
    let row = SEGMENTS + 1;
    for i in 0..RINGS {
        for j in 0..SEGMENTS {
            let a = base + i * row + j;
            let b = a + row;
            idx.extend_from_slice(&[a, a + 1, b, a + 1, b + 1, b]);
        }
    }
}

/// Colour of a spring by its kind index (0 structural, 1 shear, 2 bend, 3+ other).
pub fn kind_color(kind: usize) -> [f32; 4] {
    match kind {
        0 => [0.20, 0.45, 0.95, 1.0],
        1 => [0.15, 0.70, 0.35, 1.0],
        2 => [0.95, 0.60, 0.10, 1.0],
        _ => [0.65, 0.30, 0.85, 1.0],
    }
}

/// Colour of a spring by its strain `(l - rest) / rest`: blue when compressed,
/// grey at rest, through red to glowing yellow-white when stretched by 10 % or more.
pub fn strain_color(strain: f32) -> [f32; 4] {
    if !strain.is_finite() {
        return [1.0, 0.0, 1.0, 1.0];
    }
    let rest = Vec3::new(0.45, 0.45, 0.50);
    let c = if strain < 0.0 {
        let t = (-strain / 0.1).min(1.0);
        rest.lerp(Vec3::new(0.1, 0.35, 1.0), t)
    } else {
        let t = (strain / 0.1).min(1.0);
        if t < 0.5 {
            rest.lerp(Vec3::new(1.0, 0.15, 0.05), t * 2.0)
        } else {
            Vec3::new(1.0, 0.15, 0.05).lerp(Vec3::new(1.0, 1.0, 0.6), t * 2.0 - 1.0)
        }
    };
    c.extend(1.0).to_array()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn degenerate_triangle_normals_stay_finite() {
        let p = vec![
            Vec3::ZERO,
            Vec3::ZERO,
            Vec3::ZERO,
            Vec3::new(f32::NAN, 0.0, 0.0),
        ];
        let valid = vec![true, true, true, false];
        let n = vertex_normals(&p, &[[0, 1, 2], [0, 1, 3], [0, 1, 9]], &valid);
        assert!(n.iter().all(|n| n.is_finite()));
    }

    #[test]
    fn edges_are_deduplicated() {
        assert_eq!(triangle_edges(&[[0, 1, 2], [2, 1, 3]]).len(), 5);
    }
}
