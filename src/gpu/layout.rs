//! What the GPU engine's buffers hold, as the shaders read them
//! (`shaders/gpu/step.wgsl`, `shaders/gpu/constrain.wgsl`): the particles, each
//! particle's springs and triangles in a compressed adjacency, one step's
//! parameters, and the springs in their constraint order, cut into runs.

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
            let m = model.material(s.kind);
            let c = SpringCoefficients::new(m.stiffness, s.rest, m.damping);
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
pub(crate) const CONSTRAINED: u32 = 8;

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

/// A spring as the constraint passes read it, the shader's `ConstraintSpring`:
/// its ends, rest length (m), stiffness (N/m) and damping (N s/m).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub(crate) struct ConstraintSpring {
    pub a: u32,
    pub b: u32,
    pub rest: f32,
    pub stiffness: f32,
    pub damping: f32,
    pub _pad: [u32; 3],
}

/// The runs of the model's constraint order (`Model::constraint_order`) in which
/// no two springs share a particle, as (first place, springs): a run's
/// corrections can be made in any order, in parallel, with the result of the
/// f64 engine's sequential sweep. On a grid or a lattice the runs are its colour
/// classes (12 on a grid, 26 on a lattice); an order without them falls into
/// many short runs.
pub(crate) fn constraint_runs(model: &Model) -> Vec<(u32, u32)> {
    let mut last_run = vec![u32::MAX; model.mass.len()];
    let mut runs: Vec<(u32, u32)> = Vec::new();
    for (place, &i) in model.constraint_order().iter().enumerate() {
        let s = &model.springs[i as usize];
        let (a, b) = (s.a as usize, s.b as usize);
        // The open run, if the spring shares no particle with it.
        let open = (runs.len() as u32).checked_sub(1);
        let current = match open.filter(|&r| last_run[a] != r && last_run[b] != r) {
            Some(run) => run,
            None => {
                runs.push((place as u32, 0));
                runs.len() as u32 - 1
            }
        };
        (last_run[a], last_run[b]) = (current, current);
        runs[current as usize].1 += 1;
    }
    runs
}

/// The model's springs in its constraint order, as the constraint passes read them.
pub(crate) fn constraint_springs(model: &Model) -> Vec<ConstraintSpring> {
    let spring = |&i: &u32| {
        let s = &model.springs[i as usize];
        let m = model.material(s.kind);
        ConstraintSpring {
            a: s.a,
            b: s.b,
            rest: s.rest as f32,
            stiffness: m.stiffness as f32,
            damping: m.damping as f32,
            _pad: [0; 3],
        }
    };
    model.constraint_order().iter().map(spring).collect()
}

/// Which sweep a run's dispatch is, the shader's `FORWARD`, `FORWARD_KEPT`, `BACK`.
pub(crate) const FORWARD: u32 = 0;
pub(crate) const FORWARD_KEPT: u32 = 1;
pub(crate) const BACK: u32 = 2;

/// One constraint dispatch's run, the shader's `Run`, padded to a record.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub(crate) struct RunRecord {
    pub start: u32,
    pub count: u32,
    pub sweep: u32,
    pub _pad: [u32; 61],
}

const _: () = assert!(std::mem::size_of::<RunRecord>() as u64 == RECORD_BYTES);

#[cfg(test)]
mod tests {
    use super::constraint_runs;
    use crate::scene::Scene;

    /// The runs cover the constraint order in order, none sharing a particle,
    /// and fall into at most the order's colour classes: a grid's 6 stencil
    /// directions by 2 parities, a lattice's 13 directions by 2.
    #[test]
    fn constraint_runs_share_no_particle() {
        for (name, most) in [("cloth", 12), ("sheet", 12), ("jelly", 26)] {
            let system = Scene::load(name).unwrap().build().unwrap();
            let model = system.model();
            let runs = constraint_runs(model);
            let mut next = 0;
            for &(start, count) in &runs {
                assert_eq!(start, next, "{name}: the runs leave a gap");
                let mut ends: Vec<u32> = (start..start + count)
                    .map(|p| &model.springs[model.constraint_order()[p as usize] as usize])
                    .flat_map(|s| [s.a, s.b])
                    .collect();
                ends.sort_unstable();
                let shared = ends.windows(2).any(|w| w[0] == w[1]);
                assert!(!shared, "{name}: a run shares a particle");
                next += count;
            }
            assert_eq!(next as usize, model.constraint_order().len(), "{name}");
            eprintln!("{name}: {} runs", runs.len());
            assert!(runs.len() <= most, "{name}: {} runs", runs.len());
        }
    }
}
