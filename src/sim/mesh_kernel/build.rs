//! Building the mesh engine from a model: its springs in the order the spring pass
//! reads them ([`SpringArrays`]), the set it runs on ([`SpringSet`]), its settings,
//! and its state read and written.

use glam::DVec3;

use super::passes::simd_level;
use super::{B_END, BATCH, MeshKernel, MeshParams, PARALLEL_MIN_PARTICLES};
use crate::sim::grid_kernel::SimdLevel;
use crate::sim::laws::Contact;
use crate::sim::springs::Adjacency;
use crate::sim::{Bar, Integrator, Model, SelfCollision, Spring, SpringMaterials};

/// Springs as structure of arrays, in the order the spring pass evaluates them:
/// by the offset `b - a` between their ends, then by `a`. A lattice's springs of one
/// direction then come in runs with consecutive ends (`a, a + 1, ...` and `b, b +
/// 1, ...`), whose positions are read as contiguous slices instead of one by one.
/// (The order of evaluation changes no result: each force is stored apart and the
/// particles sum them in the model's order.)
#[derive(Clone, Debug, Default)]
pub(super) struct SpringArrays {
    /// The model's index of each spring, in evaluation order.
    pub(super) order: Vec<u32>,
    /// Ends `[a, b]`.
    pub(super) ends: Vec<[u32; 2]>,
    /// How many springs from this one on continue its run (at least 1, at most
    /// [`BATCH`]).
    pub(super) run: Vec<u8>,
    /// `[rest length (m), stiffness (N/m), damping (N·s/m)]`.
    pub(super) coefficients: [Vec<f64>; 3],
}

impl SpringArrays {
    pub(super) fn new(springs: &[Spring], materials: &SpringMaterials) -> Self {
        let mut order: Vec<u32> = (0..springs.len() as u32).collect();
        // The keys differ from spring to spring.
        order.sort_unstable_by_key(|&i| {
            let s = &springs[i as usize];
            (i64::from(s.b) - i64::from(s.a), s.a)
        });
        Self::in_order(springs, materials, order)
    }

    /// The arrays for `springs` when they are `old`'s springs with some removed
    /// (torn), in `old`'s order less the removed ones, without sorting again;
    /// `None` when they are not.
    pub(super) fn kept(
        &self,
        old: &[Spring],
        springs: &[Spring],
        materials: &SpringMaterials,
    ) -> Option<Self> {
        // Each old spring's index among those kept (springs keep their order).
        let mut index = vec![u32::MAX; old.len()];
        let mut next = springs.iter().enumerate().peekable();
        for (i, s) in old.iter().enumerate() {
            if let Some((j, _)) = next.next_if(|(_, t)| (t.a, t.b) == (s.a, s.b)) {
                index[i] = j as u32;
            }
        }
        if next.peek().is_some() {
            return None;
        }
        let order = self.order.iter().map(|&i| index[i as usize]);
        Some(Self::in_order(
            springs,
            materials,
            order.filter(|&j| j != u32::MAX).collect(),
        ))
    }

    /// The arrays for `springs` evaluated in `order` (model indices).
    pub(super) fn in_order(
        springs: &[Spring],
        materials: &SpringMaterials,
        order: Vec<u32>,
    ) -> Self {
        let m = springs.len();
        let ends: Vec<[u32; 2]> = order
            .iter()
            .map(|&i| [springs[i as usize].a, springs[i as usize].b])
            .collect();
        let mut run = vec![1u8; m];
        for e in (0..m.saturating_sub(1)).rev() {
            let ([a, b], [na, nb]) = (ends[e], ends[e + 1]);
            if na == a + 1 && nb == b + 1 && usize::from(run[e + 1]) < BATCH {
                run[e] = run[e + 1] + 1;
            }
        }
        let mut arrays = Self {
            order,
            ends,
            run,
            coefficients: [vec![0.0; m], vec![0.0; m], vec![0.0; m]],
        };
        arrays.set_coefficients(springs, materials);
        arrays
    }

    pub(super) fn set_coefficients(&mut self, springs: &[Spring], materials: &SpringMaterials) {
        let [rest, k, b] = &mut self.coefficients;
        for (e, &i) in self.order.iter().enumerate() {
            let s = &springs[i as usize];
            let m = materials[s.kind.index()];
            (rest[e], k[e], b[e]) = (s.rest, m.stiffness, m.damping);
        }
    }
}

/// The springs and surface triangles the engine runs on (the model's, or those
/// left after a tear), with their constraint order and adjacency, which the
/// model or the tear computes: see [`MeshKernel::set_springs`].
pub(super) struct SpringSet {
    /// Canonical springs.
    pub(super) springs: Vec<Spring>,
    /// The same springs as the spring pass reads them.
    pub(super) arrays: SpringArrays,
    /// The order the stretch limit and XPBD visit `springs` in.
    pub(super) constraint_order: Vec<u32>,
    pub(super) adjacency: Adjacency,
    pub(super) triangles: Vec<[u32; 3]>,
}

impl MeshKernel {
    /// Builds the engine for `model`'s particles, springs, bars and masses, with
    /// `params` ([`MeshParams::of`]). The state starts at rest at the origin: set it
    /// with [`Self::set_state`]. Runs on the calling thread until
    /// [`Self::set_threads`] is called.
    pub fn new(model: &Model, params: MeshParams) -> Self {
        Self::with_springs(
            model,
            params,
            SpringArrays::new(&model.springs, &model.materials),
        )
    }

    /// [`Self::new`] with the springs' arrays given.
    pub(super) fn with_springs(model: &Model, params: MeshParams, springs: SpringArrays) -> Self {
        let n = model.mass.len();
        let zeros = |len| [vec![0.0; len], vec![0.0; len], vec![0.0; len]];
        let verlet = params.integrator == Integrator::Verlet;
        let mut kernel = Self {
            params,
            x: zeros(n),
            v: zeros(n),
            u: zeros(if verlet { n } else { 0 }),
            x_next: zeros(n),
            v_next: zeros(n),
            before: Default::default(),
            inv_mass: model.inv_mass.clone(),
            spring_f: Default::default(),
            offsets: Vec::new(),
            links: Vec::new(),
            springs: SpringArrays::default(),
            triangles: Vec::new(),
            triangle_f: Default::default(),
            triangle_offsets: Vec::new(),
            triangle_links: Vec::new(),
            time: 0.0,
            colliders: model.colliders.clone(),
            collider_poses: Vec::new(),
            grid: model.grid,
            lattice: model.lattice,
            torn: Vec::new(),
            model_springs: Vec::new(),
            materials: model.materials,
            constraint_order: Vec::new(),
            bars: model.bars.clone(),
            threads: 1,
            pool: None,
            avx2: simd_level() == SimdLevel::Avx2,
            adjacency: Adjacency::default(),
            bar_pairs: model.bar_pairs.clone(),
            self_collision: SelfCollision::default(),
            copy_x: Vec::new(),
            copy_start: Vec::new(),
            multipliers: Vec::new(),
        };
        kernel.set_springs(SpringSet {
            springs: model.springs.clone(),
            arrays: springs,
            constraint_order: model.constraint_order().to_vec(),
            adjacency: model.adjacency().clone(),
            triangles: model.triangles.clone(),
        });
        kernel.size_before();
        kernel
    }

    /// Takes a spring set and surface (the model's, or those left after a tear)
    /// with what follows from them: the particles' links to their springs and
    /// triangles, and the per-spring and per-triangle force arrays.
    pub(super) fn set_springs(&mut self, set: SpringSet) {
        let SpringSet {
            springs,
            arrays,
            constraint_order,
            adjacency,
            triangles,
        } = set;
        let n = self.len();
        let m = springs.len();
        let mut offsets = vec![0u32; n + 1];
        for s in &springs {
            offsets[s.a as usize + 1] += 1;
            offsets[s.b as usize + 1] += 1;
        }
        for i in 0..n {
            offsets[i + 1] += offsets[i];
        }
        // Where each of the model's springs is evaluated.
        let mut slot_of = vec![0u32; m];
        for (e, &i) in arrays.order.iter().enumerate() {
            slot_of[i as usize] = e as u32;
        }
        // Filled in the model's spring order per particle: the f64 engine's gather
        // order.
        let mut cursor = offsets.clone();
        let mut links = vec![0u32; 2 * m];
        for (index, s) in springs.iter().enumerate() {
            for (end, flag) in [(s.a, 0), (s.b, B_END)] {
                let slot = &mut cursor[end as usize];
                links[*slot as usize] = slot_of[index] | flag;
                *slot += 1;
            }
        }
        // Each particle's triangles, in the model's order: the f64 engine adds
        // their drag in that order.
        let mut triangle_offsets = vec![0u32; n + 1];
        for &vertex in triangles.iter().flatten() {
            triangle_offsets[vertex as usize + 1] += 1;
        }
        for i in 0..n {
            triangle_offsets[i + 1] += triangle_offsets[i];
        }
        let mut cursor = triangle_offsets.clone();
        let mut triangle_links = vec![0u32; 3 * triangles.len()];
        for (index, triangle) in triangles.iter().enumerate() {
            for &vertex in triangle {
                let slot = &mut cursor[vertex as usize];
                triangle_links[*slot as usize] = index as u32;
                *slot += 1;
            }
        }
        // Written whole by each step's passes before they are read.
        let sized =
            |arrays: &mut [Vec<f64>; 3], len| arrays.iter_mut().for_each(|a| a.resize(len, 0.0));
        sized(&mut self.spring_f, m);
        sized(&mut self.triangle_f, triangles.len());
        (self.offsets, self.links, self.springs) = (offsets, links, arrays);
        (self.triangle_offsets, self.triangle_links) = (triangle_offsets, triangle_links);
        (self.model_springs, self.triangles) = (springs, triangles);
        (self.constraint_order, self.adjacency) = (constraint_order, adjacency);
    }

    /// Whether the engine steps a system with this integrator.
    pub fn supports(integrator: Integrator) -> bool {
        match integrator {
            Integrator::SymplecticEuler
            | Integrator::ExplicitEuler
            | Integrator::Verlet
            | Integrator::Xpbd => true,
            Integrator::Rk2 | Integrator::Rk4 | Integrator::ImplicitEuler => false,
        }
    }

    /// Number of particles.
    pub fn len(&self) -> usize {
        self.inv_mass.len()
    }

    /// Whether there are no particles.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The parameters in effect.
    pub fn params(&self) -> &MeshParams {
        &self.params
    }

    /// Takes in `model`'s current springs, bars and inverse masses and `params`
    /// without new arrays when only coefficients changed (a live edit). Returns
    /// `false`, changing nothing, when the topology or the integrator differs (a
    /// new engine is needed).
    pub fn refresh(&mut self, model: &Model, params: MeshParams) -> bool {
        let same_ends = |a: &Spring, b: &Spring| (a.a, a.b) == (b.a, b.b);
        let same_bars = |a: &Bar, b: &Bar| (a.a, a.b) == (b.a, b.b);
        if params.integrator != self.params.integrator
            || model.inv_mass.len() != self.len()
            || model.springs.len() != self.model_springs.len()
            || model.bars.len() != self.bars.len()
            || model.triangles != self.triangles
            || !model
                .springs
                .iter()
                .zip(&self.model_springs)
                .all(|(a, b)| same_ends(a, b))
            || !model
                .bars
                .iter()
                .zip(&self.bars)
                .all(|(a, b)| same_bars(a, b))
        {
            return false;
        }
        self.params = params;
        self.colliders.clone_from(&model.colliders);
        self.size_before();
        self.inv_mass.copy_from_slice(&model.inv_mass);
        self.bars.copy_from_slice(&model.bars);
        if model.springs != self.model_springs || model.materials != self.materials {
            self.model_springs.copy_from_slice(&model.springs);
            self.materials = model.materials;
            self.springs
                .set_coefficients(&model.springs, &self.materials);
        }
        true
    }

    /// Builds the engine anew for `model` and `params` ([`Self::new`]) when
    /// [`Self::refresh`] cannot take them (springs cut, a new integrator), keeping
    /// its threads when the particle count is the same. The state must be set again.
    pub fn rebuild(&mut self, model: &Model, params: MeshParams) {
        let (threads, pool) = (self.threads, self.pool.take());
        let same_size = model.mass.len() == self.len();
        let springs = (self
            .springs
            .kept(&self.model_springs, &model.springs, &model.materials))
        .unwrap_or_else(|| SpringArrays::new(&model.springs, &model.materials));
        *self = Self::with_springs(model, params, springs);
        if same_size {
            (self.threads, self.pool) = (threads, pool);
        } else {
            self.set_threads(threads);
        }
    }

    /// Whether anything is enforced after integration.
    pub(super) fn has_constraints(&self) -> bool {
        let p = &self.params;
        (p.bar_iterations > 0 && !self.bars.is_empty())
            || (p.stretch_limit.is_some() && !self.model_springs.is_empty())
            || p.self_collision.is_some()
            || (p.integrator == Integrator::Xpbd && !self.model_springs.is_empty())
            || self.contact().is_active()
            || !self.colliders.is_empty()
    }

    /// The colliders and their friction.
    pub(super) fn contact(&self) -> Contact {
        let p = &self.params;
        Contact {
            sphere: p.sphere,
            ground: p.ground,
            friction: p.friction,
            dt: p.dt,
        }
    }

    pub(super) fn size_before(&mut self) {
        let len = if self.has_constraints() {
            self.len()
        } else {
            0
        };
        for axis in &mut self.before {
            axis.resize(len, 0.0);
        }
    }

    /// Use `n` threads (at least 1) for models of [`PARALLEL_MIN_PARTICLES`]
    /// particles or more; smaller ones run on the calling thread. Builds a rayon pool
    /// (this allocates; the steps do not).
    pub fn set_threads(&mut self, n: usize) {
        self.set_threads_from(n, PARALLEL_MIN_PARTICLES);
    }

    /// As [`Self::set_threads`], with the size from which threads are used given
    /// (for tests: results must not depend on the thread count at any size).
    pub fn set_threads_from(&mut self, n: usize, min_particles: usize) {
        let n = n.max(1);
        self.threads = n;
        self.pool = if n > 1 && self.len() >= min_particles.max(2) {
            rayon::ThreadPoolBuilder::new()
                .num_threads(n)
                .thread_name(|i| format!("cloth-mesh-{i}"))
                .build()
                .ok()
        } else {
            None
        };
    }

    /// True if steps run on several threads.
    pub fn is_parallel(&self) -> bool {
        self.pool.is_some()
    }

    /// Sets positions (m) and velocities (m/s). Verlet's update velocities start
    /// equal to the velocities (call [`Self::set_update_velocities`] after this to
    /// give them their own values).
    pub fn set_state(&mut self, positions: &[DVec3], velocities: &[DVec3]) {
        for (i, (p, v)) in positions
            .iter()
            .zip(velocities)
            .enumerate()
            .take(self.len())
        {
            for k in 0..3 {
                self.x[k][i] = p[k];
                self.v[k][i] = v[k];
            }
        }
        if self.params.integrator == Integrator::Verlet {
            self.set_update_velocities(velocities);
        }
    }

    /// Sets position Verlet's velocities of the last position update,
    /// `(x - x_prev) / h` (m/s); ignored for the other integrators.
    pub fn set_update_velocities(&mut self, u: &[DVec3]) {
        if self.u[0].is_empty() {
            return;
        }
        for (i, q) in u.iter().enumerate().take(self.len()) {
            for k in 0..3 {
                self.u[k][i] = q[k];
            }
        }
    }

    pub(super) fn read_into(arrays: &[Vec<f64>; 3], out: &mut [DVec3]) {
        for (i, o) in out.iter_mut().enumerate().take(arrays[0].len()) {
            *o = DVec3::new(arrays[0][i], arrays[1][i], arrays[2][i]);
        }
    }

    /// Copies the positions (m) into `out`.
    pub fn positions_into(&self, out: &mut [DVec3]) {
        Self::read_into(&self.x, out);
    }

    /// Copies the velocities (m/s) into `out`.
    pub fn velocities_into(&self, out: &mut [DVec3]) {
        Self::read_into(&self.v, out);
    }

    /// Copies Verlet's update velocities (m/s) into `out`; nothing for the other
    /// integrators.
    pub fn update_velocities_into(&self, out: &mut [DVec3]) {
        Self::read_into(&self.u, out);
    }

    /// The largest squared speed and squared distance from `center`, or infinities
    /// when a value is not finite (for a cheap divergence scan).
    pub fn extremes(&self, center: DVec3) -> (f64, f64) {
        let n = self.len();
        let x = self.x.each_ref().map(|a| &a[..n]);
        let v = self.v.each_ref().map(|a| &a[..n]);
        crate::sim::grid_kernel::runaway_scan_f64(x, v, center)
    }

    /// Sets the simulated time (s) at the start of the next step, which the gusts
    /// of the drag's wind follow (0 when built); each step advances it by `dt`.
    pub fn set_time(&mut self, time: f64) {
        self.time = time;
    }
}
