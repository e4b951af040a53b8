//! What the GPU engine's buffers hold, as the shaders read them
//! (`shaders/gpu/step.wgsl`): the particles, each particle's springs and
//! triangles in a compressed adjacency, and one step's parameters.

use bytemuck::{Pod, Zeroable};
use glam::{DVec3, Vec3};

use crate::sim::Model;
use crate::sim::laws::SpringCoefficients;

/// A particle: position (m, from the engine's origin) as `x + low`, two f32,
/// with its inverse mass in `x[3]`, and velocity (m/s). The shader's `Particle`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub(crate) struct Particle {
    pub x: [f32; 4],
    pub v: [f32; 4],
    pub low: [f32; 4],
}

impl Particle {
    /// A particle at `x` (from `origin`) moving at `v`, of inverse mass `w`.
    pub fn new(x: DVec3, origin: DVec3, v: DVec3, w: f64) -> Self {
        let exact = x - origin;
        let hi = exact.as_vec3();
        let low = (exact - hi.as_dvec3()).as_vec3();
        let v = v.as_vec3();
        Self {
            x: [hi.x, hi.y, hi.z, w as f32],
            v: [v.x, v.y, v.z, 0.0],
            low: [low.x, low.y, low.z, 0.0],
        }
    }

    /// Its position in m, back from `origin`.
    pub fn position(&self, origin: DVec3) -> DVec3 {
        let part = |p: &[f32; 4]| Vec3::from_slice(&p[..3]).as_dvec3();
        part(&self.x) + part(&self.low) + origin
    }

    /// Its velocity in m/s.
    pub fn velocity(&self) -> DVec3 {
        Vec3::from_slice(&self.v[..3]).as_dvec3()
    }
}

/// The adjacency each particle gathers from: its springs (coefficients and the
/// other end) and the triangles it is a vertex of, in spring and triangle order.
pub(crate) struct Adjacency {
    /// `n + 1` pairs: particle `i`'s links are `links[offsets[i].0..offsets[i + 1].0]`
    /// and its triangles `triangles[offsets[i].1..offsets[i + 1].1]`.
    pub offsets: Vec<[u32; 2]>,
    /// `-k`, `k L`, `-b` as f32 bits, and the other end.
    pub links: Vec<[u32; 4]>,
    /// The three vertices of a triangle at a particle, in the model's order.
    pub triangles: Vec<[u32; 4]>,
}

impl Adjacency {
    /// The springs and surface triangles of `model`. A spring is listed at both
    /// ends with the same coefficients: its force on one end is
    /// `spring_force(x_i - x_j, v_i - v_j)`, which is exactly the negative of the
    /// other end's (the law's factor depends on `d` only through `|d|²` and `d·dv`).
    pub fn of(model: &Model) -> Self {
        let n = model.mass.len();
        let mut springs_at = vec![0u32; n];
        let mut triangles_at = vec![0u32; n];
        for s in &model.springs {
            springs_at[s.a as usize] += 1;
            springs_at[s.b as usize] += 1;
        }
        for t in &model.triangles {
            for &i in t {
                triangles_at[i as usize] += 1;
            }
        }
        let mut offsets = Vec::with_capacity(n + 1);
        let (mut spring_start, mut triangle_start) = (0u32, 0u32);
        for i in 0..n {
            offsets.push([spring_start, triangle_start]);
            spring_start += springs_at[i];
            triangle_start += triangles_at[i];
        }
        offsets.push([spring_start, triangle_start]);
        let mut next: Vec<[u32; 2]> = offsets[..n].to_vec();
        let mut links = vec![[0u32; 4]; spring_start as usize];
        for s in &model.springs {
            let c = SpringCoefficients::new(s.stiffness, s.rest, s.damping);
            let bits = [c.neg_k, c.k_rest, c.neg_b].map(|c| (c as f32).to_bits());
            for (end, other) in [(s.a, s.b), (s.b, s.a)] {
                let slot = &mut next[end as usize][0];
                links[*slot as usize] = [bits[0], bits[1], bits[2], other];
                *slot += 1;
            }
        }
        let mut triangles = vec![[0u32; 4]; triangle_start as usize];
        for t in &model.triangles {
            for &i in t {
                let slot = &mut next[i as usize][1];
                triangles[*slot as usize] = [t[0], t[1], t[2], 0];
                *slot += 1;
            }
        }
        Self {
            offsets,
            links,
            triangles,
        }
    }
}

/// The update rules the shader knows (its `SYMPLECTIC_EULER`, `EXPLICIT_EULER`,
/// `VERLET`).
pub(crate) const SYMPLECTIC_EULER: u32 = 0;
pub(crate) const EXPLICIT_EULER: u32 = 1;
pub(crate) const VERLET: u32 = 2;

/// The shader's flags: which terms run.
pub(crate) const GROUND: u32 = 1;
pub(crate) const SPHERE: u32 = 2;
pub(crate) const SPRINGS: u32 = 4;

/// One step's parameters, the shader's `Step` (see its fields there), padded to
/// 256 bytes: one record per step in a uniform buffer, bound at its offset.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub(crate) struct StepRecord {
    pub gravity: [f32; 4],
    pub force: [f32; 4],
    pub wind: [f32; 4],
    pub ground: [f32; 4],
    pub sphere: [f32; 4],
    pub limits: [f32; 4],
    pub flags: [u32; 4],
    pub _pad: [u32; 36],
}

/// Bytes between two step records: the largest uniform offset alignment wgpu allows.
pub(crate) const RECORD_BYTES: u64 = 256;

const _: () = assert!(std::mem::size_of::<StepRecord>() as u64 == RECORD_BYTES);
