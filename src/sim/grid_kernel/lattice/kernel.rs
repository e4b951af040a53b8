//! The lattice kernel in one float type: its arrays, built from a [`LatticeSpec`]
//! at rest, its settings, and its state read and written in metres.

use std::ops::Range;

use glam::DVec3;

use super::spec::LatticeSpec;
use super::{Band, Geometry, PARALLEL_MIN_PARTICLES, make_bands};
use crate::sim::Integrator;
use crate::sim::grid_kernel::spring_passes::Multipliers;
use crate::sim::grid_kernel::{
    Buf, Frame, Params, Real, SimdLevel, State, frame, ground_constants, runaway_scan,
};
use crate::sim::laws::Contact;

/// The lattice kernel in one float type (see [`LatticeKernel`], which holds one).
pub(super) struct Lattice<E: Real> {
    pub(super) spec: LatticeSpec,
    pub(super) geometry: Geometry,
    /// How the position arrays map to metres.
    pub(super) frame: Frame,
    pub(super) params: Params<E>,
    pub(super) cur: State<E>,
    pub(super) next: State<E>,
    /// 1 for particles, 0 for ghosts.
    pub(super) real: Buf<E>,
    pub(super) inv_mass: Buf<E>,
    pub(super) bands: Vec<Band<E>>,
    pub(super) pool: Option<rayon::ThreadPool>,
    pub(super) simd: SimdLevel,
    /// XPBD's multipliers, kept from each spring's first correction to its second.
    pub(super) multipliers: Multipliers<E>,
}

impl<E: Real> std::fmt::Debug for Lattice<E> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Lattice")
            .field("spec", &self.spec)
            .field("bands", &self.bands.len())
            .field("simd", &self.simd)
            .finish()
    }
}

impl<E: Real> Lattice<E> {
    pub(super) fn new(spec: LatticeSpec) -> Self {
        let geometry = Geometry::new(spec.shape);
        let len = geometry.len;
        let verlet = spec.integrator == Integrator::Verlet;
        let cur = State {
            x: std::array::from_fn(|_| Buf::zeros(len)),
            v: std::array::from_fn(|_| Buf::zeros(len)),
            u: std::array::from_fn(|_| Buf::zeros(if verlet { len } else { 0 })),
        };
        let mut real = Buf::zeros(len);
        for p in 0..spec.shape.len() {
            real.as_mut_slice()[geometry.index(p)] = E::ONE;
        }
        // Fixed-point positions get their frame with the state (`set_state`).
        let frame = (spec.frame_rule().frame(([0.0; 3], [0.0; 3]), 0.0)).unwrap_or(Frame::FLOAT);
        let mut kernel = Lattice {
            params: Self::params(&spec, &frame),
            frame,
            geometry,
            next: cur.clone(),
            cur,
            real,
            inv_mass: Buf::zeros(len),
            bands: make_bands(&geometry, 1),
            pool: None,
            simd: SimdLevel::detect(),
            multipliers: Multipliers::default(),
            spec,
        };
        kernel.reset_masses();
        kernel
    }

    /// The per-step constants of `spec` with positions in `frame` (the step `dt` is
    /// set by each run), lengths in its units. The kinds are indexed 0 axis, 1
    /// face diagonal, 2 body diagonal.
    pub(super) fn params(spec: &LatticeSpec, frame: &Frame) -> Params<E> {
        let rests = Self::rests(spec);
        // XPBD's springs are constraints (`constrain`), not forces: the step
        // predicts with every other force.
        let xpbd = spec.integrator == Integrator::Xpbd;
        let kinds = spec
            .kinds
            .map(|kind| if xpbd { Default::default() } else { kind });
        Params {
            ks: kinds.map(|kind| E::of(kind.k * frame.unit)),
            kls: std::array::from_fn(|i| E::of(kinds[i].k * rests[i])),
            bs: kinds.map(|kind| E::of(kind.b)),
            gravity: spec.gravity.map(E::of),
            wind: [E::ZERO; 3],
            drag: E::ZERO,
            air_scale: E::ONE,
            dt: E::ZERO,
            neg_air: E::of(-spec.air_damping),
            ground: ground_constants(spec.ground.as_ref(), frame),
            ground_on: spec.ground.is_some(),
            explicit: spec.integrator == Integrator::ExplicitEuler,
            verlet_half_dt: E::ZERO,
            verlet: spec.integrator == Integrator::Verlet,
            fixed: frame.fixed,
            unit: E::of(frame.unit),
            inv_unit: E::of(1.0 / frame.unit),
            // With friction the sphere is resolved after the step, with the
            // ground's friction, in the f64 engine's order (`resolve_contact`),
            // and so with XPBD or a stretch limit, after their passes.
            sphere: spec
                .sphere
                .filter(|_| !Self::contact(spec, 0.0).has_friction())
                .filter(|_| !xpbd && spec.stretch_limit.is_none())
                .and_then(|s| frame.sphere(&s)),
        }
    }

    /// Rest lengths of the kinds: axis `h`, face diagonal `h√2`, body diagonal `h√3`.
    pub(super) fn rests(spec: &LatticeSpec) -> [f64; 3] {
        let h = spec.spacing;
        [h, h * 2f64.sqrt(), h * 3f64.sqrt()]
    }

    /// The colliders as the f64 engine resolves them after a step `dt`.
    pub(super) fn contact(spec: &LatticeSpec, dt: f64) -> Contact {
        Contact {
            sphere: spec.sphere,
            ground: spec.ground,
            friction: spec.friction,
            dt,
        }
    }

    /// Every particle free, with the spec's mass.
    pub(super) fn reset_masses(&mut self) {
        let inv_m = if self.spec.particle_mass > 0.0 {
            E::of(1.0 / self.spec.particle_mass)
        } else {
            E::ZERO
        };
        for p in 0..self.len() {
            self.inv_mass.as_mut_slice()[self.geometry.index(p)] = inv_m;
        }
    }

    /// Changes coefficients in place (stiffness, damping, mass, rest length,
    /// gravity, air damping, colliders). Returns `false`, changing nothing, when
    /// `spec` has another shape, integrator or precision: then build a new kernel.
    /// Every particle is freed (pin them again).
    pub(super) fn respec(&mut self, spec: LatticeSpec) -> bool {
        let same = spec.shape == self.spec.shape
            && spec.integrator == self.spec.integrator
            && spec.precision == self.spec.precision;
        if !same {
            return false;
        }
        self.params = Self::params(&spec, &self.frame).with_step_of(&self.params);
        self.spec = spec;
        self.reset_masses();
        true
    }

    /// The spec the kernel models now.
    pub(super) fn spec(&self) -> &LatticeSpec {
        &self.spec
    }

    /// Number of particles.
    pub(super) fn len(&self) -> usize {
        self.spec.shape.len()
    }

    /// True if the lattice has no particles.
    pub(super) fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Use `n` threads (at least 1) for lattices of [`PARALLEL_MIN_PARTICLES`] or
    /// more particles and at least `n` slabs; others run on the calling thread.
    /// Builds a rayon pool (this allocates; the steps do not).
    pub(super) fn set_threads(&mut self, n: usize) {
        let n = n.max(1);
        let parallel = n > 1 && self.len() >= PARALLEL_MIN_PARTICLES && self.spec.shape.depth >= n;
        self.pool = parallel
            .then(|| {
                rayon::ThreadPoolBuilder::new()
                    .num_threads(n)
                    .thread_name(|i| format!("cloth-lattice-{i}"))
                    .build()
                    .ok()
            })
            .flatten();
        let bands = if self.pool.is_some() { n } else { 1 };
        self.bands = make_bands(&self.geometry, bands);
    }

    /// True if steps run on several threads.
    pub(super) fn is_parallel(&self) -> bool {
        self.pool.is_some()
    }

    /// The unit (m) of the fixed-point positions now (see
    /// [`crate::sim::grid_kernel::GridCloth::position_unit`]); `None` on float positions.
    pub(super) fn position_unit(&self) -> Option<f64> {
        self.frame.fixed.then_some(self.frame.unit)
    }

    /// Force a SIMD level (for tests and benches). A level this CPU lacks is
    /// ignored.
    pub(super) fn set_simd_level(&mut self, level: SimdLevel) {
        if level.is_supported() {
            self.simd = level;
        }
    }

    /// Pins (inverse mass 0) or frees model particle `p`.
    pub(super) fn set_pinned(&mut self, p: usize, pinned: bool) {
        if p < self.len() {
            let inv_m = if pinned || self.spec.particle_mass <= 0.0 {
                E::ZERO
            } else {
                E::of(1.0 / self.spec.particle_mass)
            };
            self.inv_mass.as_mut_slice()[self.geometry.index(p)] = inv_m;
        }
    }

    /// Sets positions (m) and velocities (m/s) of the model's particles.
    pub(super) fn set_state(&mut self, positions: &[DVec3], velocities: &[DVec3]) {
        if self.frame.fixed && positions.len() >= self.len() {
            // A frame around the new positions.
            let bounds = frame::bounds(&positions[..self.len()]);
            let frame = self.spec.frame_rule().frame(bounds, 0.0);
            if let Some(frame) = frame.filter(|f| *f != self.frame) {
                self.adopt(frame);
            }
        }
        for (p, (q, v)) in positions
            .iter()
            .zip(velocities)
            .enumerate()
            .take(self.len())
        {
            let i = self.geometry.index(p);
            for a in 0..3 {
                self.cur.x[a].as_mut_slice()[i] = self.frame.encode(q[a], a);
                self.cur.v[a].as_mut_slice()[i] = E::of(v[a]);
            }
        }
    }

    /// Sets Verlet's velocities of the last position update (ignored for the
    /// other integrators).
    pub(super) fn set_update_velocities(&mut self, u: &[DVec3]) {
        if !self.params.verlet {
            return;
        }
        for (p, u) in u.iter().enumerate().take(self.len()) {
            let i = self.geometry.index(p);
            for a in 0..3 {
                self.cur.u[a].as_mut_slice()[i] = E::of(u[a]);
            }
        }
    }

    /// Positions in m, in model order.
    pub(super) fn positions_into(&self, out: &mut [DVec3]) {
        let x = self.cur.x.each_ref().map(Buf::as_slice);
        for (p, o) in out.iter_mut().enumerate().take(self.len()) {
            *o = self.frame.decode3(&x, self.geometry.index(p));
        }
    }

    /// Velocities in m/s, in model order.
    pub(super) fn velocities_into(&self, out: &mut [DVec3]) {
        self.read_into(&self.cur.v, out);
    }

    /// Verlet's velocities of the last position update (the velocities for the
    /// other integrators).
    pub(super) fn update_velocities_into(&self, out: &mut [DVec3]) {
        let u = if self.params.verlet {
            &self.cur.u
        } else {
            &self.cur.v
        };
        self.read_into(u, out);
    }

    pub(super) fn read_into(&self, arrays: &[Buf<E>; 3], out: &mut [DVec3]) {
        for (p, o) in out.iter_mut().enumerate().take(self.len()) {
            let i = self.geometry.index(p);
            *o = DVec3::from_array(std::array::from_fn(|a| arrays[a].as_slice()[i].f64()));
        }
    }

    /// The largest squared speed and squared distance from `center` of any
    /// particle (infinite if any is NaN).
    pub(super) fn extremes(&self, center: DVec3) -> (f64, f64) {
        let blocks = self.geometry.blocks;
        let x = self.cur.x.each_ref().map(|a| &a.as_slice()[..blocks]);
        let v = self.cur.v.each_ref().map(|a| &a.as_slice()[..blocks]);
        runaway_scan(&self.frame, x, v, center)
    }

    /// The real particles' array indices, row by row.
    pub(super) fn real_rows(&self) -> impl Iterator<Item = Range<usize>> + Clone + use<E> {
        let (shape, row) = (self.geometry.shape, self.geometry.row);
        let rows = (shape.height + 1) * shape.depth;
        (0..rows)
            .filter(move |r| r % (shape.height + 1) < shape.height)
            .map(move |r| r * row..r * row + shape.width)
    }

    /// Keeps fixed-point positions in range for `time` s more, as the grid kernel
    /// does (`Kernel::keep_in_frame`).
    pub(super) fn keep_in_frame(&mut self, time: f64) {
        let rule = self.spec.frame_rule();
        if let Some(frame) = self.cur.refit(&self.frame, rule, self.real_rows(), time) {
            self.adopt(frame);
        }
    }

    /// Re-encodes the positions in `frame`, and the constants with them.
    pub(super) fn adopt(&mut self, frame: Frame) {
        let rows = self.real_rows();
        self.cur.reframe(&mut self.frame, frame, rows);
        self.params = Self::params(&self.spec, &frame).with_step_of(&self.params);
    }
}
