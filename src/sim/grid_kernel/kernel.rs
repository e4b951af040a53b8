//! The stencil kernel in one precision: its arrays, its construction from a
//! [`GridSpec`], its settings, and the state read and written in metres (through
//! its [`Frame`]), with the divergence check's scan.

use glam::DVec3;

use super::colliders::Solids;
use super::frame::{self, Frame};
use super::{
    Band, Buf, Grid, GridCloth, GridSpec, PARALLEL_MIN_PARTICLES, Params, Real, SimdLevel, State,
    Torn, make_bands,
};
use crate::sim::{Integrator, SelfCollision};

/// The stencil kernel in one precision (see [`GridCloth`], which holds one).
pub(super) struct Kernel<E: Real> {
    pub(super) spec: GridSpec,
    pub(super) grid: Grid,
    /// How the position arrays map to metres.
    pub(super) frame: Frame,
    pub(super) params: Params<E>,
    pub(super) cur: State<E>,
    pub(super) next: State<E>,
    pub(super) inv_mass: Buf<E>,
    /// Two rows: 1 for columns `c < w - 1` (springs to `c + 1` exist), then 1 for
    /// `c < w - 2`; 0 elsewhere.
    pub(super) col_mask: Buf<E>,
    pub(super) drag_on: bool,
    pub(super) threads: usize,
    pub(super) pool: Option<rayon::ThreadPool>,
    /// One band: the sequential path.
    pub(super) seq_band: Vec<Band<E>>,
    /// One band per thread.
    pub(super) par_bands: Vec<Band<E>>,
    pub(super) simd: SimdLevel,
    /// Self-collision's f64 copy of the positions, kept between steps (empty
    /// without it).
    pub(super) self_collision_scratch: Vec<DVec3>,
    /// Self-collision's candidate pairs.
    pub(super) self_collision: SelfCollision,
    /// The springs left when some tore or were cut (`None`: the whole stencil).
    pub(super) torn: Option<Torn<E>>,
    /// Springs torn by the steps since [`GridCloth::take_torn`]: (particle in cloth
    /// order, stencil direction).
    pub(super) torn_log: Vec<(usize, usize)>,
    /// The tear scan's verdict per stencil direction and row (scratch).
    pub(super) tear_rows: Vec<bool>,
    /// The colliders besides the ground and the sphere, and the time.
    pub(super) solids: Solids<E>,
}

impl<E: Real> std::fmt::Debug for Kernel<E> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("GridCloth")
            .field("width", &self.grid.w)
            .field("height", &self.grid.h)
            .field("threads", &self.threads)
            .field("simd", &self.simd)
            .finish_non_exhaustive()
    }
}

impl<E: Real> Kernel<E> {
    /// Build the cloth at rest, flat in the x-y plane (see [`GridSpec`]). Runs on one
    /// thread until [`GridCloth::set_threads`] is called. A width or height of 0 is
    /// taken as 1; pinned indices out of range are ignored.
    ///
    /// # Panics
    /// If the spec's integrator is not one the kernel has ([`GridCloth::supports`]).
    pub fn new(mut spec: GridSpec) -> Self {
        assert!(
            GridCloth::supports(spec.integrator),
            "the grid kernel has no {} step",
            spec.integrator
        );
        spec.width = spec.width.max(1);
        spec.height = spec.height.max(1);
        let grid = Grid::new(spec.width, spec.height);
        let verlet = spec.integrator == Integrator::Verlet;
        let mut cur = State {
            x: std::array::from_fn(|_| Buf::zeros(grid.len())),
            v: std::array::from_fn(|_| Buf::zeros(grid.len())),
            u: std::array::from_fn(|_| Buf::zeros(if verlet { grid.len() } else { 0 })),
        };
        let start = |p: usize| {
            let (r, c) = (p / grid.w, p % grid.w);
            DVec3::new(
                spec.origin[0] + c as f64 * spec.spacing,
                spec.origin[1] - r as f64 * spec.spacing,
                spec.origin[2],
            )
        };
        let corners = [start(0), start(grid.w * grid.h - 1)];
        let frame = (spec.frame_rule().frame(frame::bounds(&corners), 0.0)).unwrap_or(Frame::FLOAT);
        for p in 0..grid.w * grid.h {
            let i = grid.index(p);
            for (a, q) in start(p).to_array().into_iter().enumerate() {
                cur.x[a].as_mut_slice()[i] = frame.encode(q, a);
            }
        }
        let mut inv_mass = Buf::zeros(grid.len());
        let inv_m = if spec.particle_mass > 0.0 {
            E::of(1.0 / spec.particle_mass)
        } else {
            E::ZERO
        };
        for p in 0..grid.w * grid.h {
            inv_mass.as_mut_slice()[grid.index(p)] = inv_m;
        }
        for &p in &spec.pinned {
            if p < grid.w * grid.h {
                inv_mass.as_mut_slice()[grid.index(p)] = E::ZERO;
            }
        }
        let mut col_mask = Buf::zeros(2 * grid.stride);
        for c in 0..grid.w {
            col_mask.as_mut_slice()[c] = if c + 1 < grid.w { E::ONE } else { E::ZERO };
            col_mask.as_mut_slice()[grid.stride + c] =
                if c + 2 < grid.w { E::ONE } else { E::ZERO };
        }
        let params = Params::of(&spec, &frame);
        let drag_on = params.drag != E::ZERO;
        Kernel {
            frame,
            params,
            next: cur.clone(),
            cur,
            inv_mass,
            col_mask,
            drag_on,
            threads: 1,
            pool: None,
            seq_band: make_bands(&grid, 1),
            par_bands: Vec::new(),
            simd: SimdLevel::detect(),
            self_collision_scratch: Vec::new(),
            self_collision: SelfCollision::default(),
            torn: None,
            torn_log: Vec::new(),
            tear_rows: Vec::new(),
            solids: Solids::default(),
            grid,
            spec,
        }
    }

    /// Changes coefficients in place (stiffness, damping, mass, rest length, wind,
    /// gravity, drag, air damping, colliders, stretch limit) without rebuilding the
    /// arrays or the thread pool. Returns `false`, changing nothing, when `spec` has
    /// another shape or another integrator: then build a new cloth. The particles'
    /// inverse masses are reset to the new mass (pins included: pin them again).
    pub fn respec(&mut self, spec: GridSpec) -> bool {
        let same_shape = spec.width.max(1) == self.grid.w && spec.height.max(1) == self.grid.h;
        if !same_shape || spec.integrator != self.spec.integrator {
            return false;
        }
        self.params = Params::of(&spec, &self.frame).with_step_of(&self.params);
        self.drag_on = self.params.drag != E::ZERO;
        let inv_m = if spec.particle_mass > 0.0 {
            E::of(1.0 / spec.particle_mass)
        } else {
            E::ZERO
        };
        for p in 0..self.len() {
            self.inv_mass.as_mut_slice()[self.grid.index(p)] = inv_m;
        }
        self.spec = spec;
        true
    }

    /// The spec the cloth was built from (with the current wind and gravity).
    pub fn spec(&self) -> &GridSpec {
        &self.spec
    }

    /// Number of particles.
    pub fn len(&self) -> usize {
        self.grid.w * self.grid.h
    }

    /// True if the cloth has no particles (never: a grid has at least one).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Use `n` threads (at least 1) for grids of [`PARALLEL_MIN_PARTICLES`] particles
    /// or more; smaller grids always run on the calling thread. Builds a rayon pool
    /// of `n` threads (this allocates; the steps do not).
    pub fn set_threads(&mut self, n: usize) {
        let n = n.max(1);
        self.threads = n;
        if n == 1 || self.len() < PARALLEL_MIN_PARTICLES || self.grid.h < 2 * n {
            self.pool = None;
            self.par_bands.clear();
            return;
        }
        self.pool = rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .thread_name(|i| format!("cloth-grid-{i}"))
            .build()
            .ok();
        self.par_bands = make_bands(&self.grid, n);
    }

    /// Threads asked for with [`GridCloth::set_threads`].
    pub fn threads(&self) -> usize {
        self.threads
    }

    /// True if steps run on several threads (enough threads and a large grid).
    pub fn is_parallel(&self) -> bool {
        self.pool.is_some()
    }

    /// The SIMD level the loops run with.
    pub fn simd_level(&self) -> SimdLevel {
        self.simd
    }

    /// The unit (m) of the fixed-point positions now: the spec's
    /// ([`GridSpec::fixed_unit`]) or, once the cloth has spread past what that
    /// holds, a coarser one; `None` on float positions.
    pub fn position_unit(&self) -> Option<f64> {
        self.frame.fixed.then_some(self.frame.unit)
    }

    /// Force a SIMD level (for tests and benches). A level this CPU lacks is
    /// ignored.
    pub fn set_simd_level(&mut self, level: SimdLevel) {
        if level.is_supported() {
            self.simd = level;
        }
    }

    /// Change the wind (m/s), e.g. every step for gusts.
    pub fn set_wind(&mut self, wind: DVec3) {
        self.spec.wind = wind.to_array();
        self.params.wind = self.spec.wind.map(E::of);
    }

    /// Change gravity (m/s²).
    pub fn set_gravity(&mut self, gravity: DVec3) {
        self.spec.gravity = gravity.to_array();
        self.params.gravity = self.spec.gravity.map(E::of);
    }

    pub(super) fn extremes(&self, center: DVec3) -> (f64, f64) {
        let x = self.cur.x.each_ref().map(Buf::as_slice);
        runaway_scan(
            &self.frame,
            x,
            self.cur.v.each_ref().map(Buf::as_slice),
            center,
        )
    }

    /// The real particles' array indices, row by row.
    pub(super) fn real_rows(
        &self,
    ) -> impl Iterator<Item = std::ops::Range<usize>> + Clone + use<E> {
        let Grid { w, h, stride, .. } = self.grid;
        (0..h).map(move |r| r * stride..r * stride + w)
    }

    /// Keeps fixed-point positions in range for `time` s more ([`frame`]): when
    /// the particles, moved at their top speed for that long, would leave the
    /// frame's range (or the spec asks for another unit), re-encodes them in a
    /// frame that fits them.
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
        self.params = Params::of(&self.spec, &frame).with_step_of(&self.params);
    }

    pub(super) fn read_into(&self, arrays: &[Buf<E>; 3], out: &mut [DVec3]) {
        let [x, y, z] = arrays.each_ref().map(Buf::as_slice);
        for (p, o) in out.iter_mut().enumerate().take(self.len()) {
            let i = self.grid.index(p);
            *o = DVec3::new(x[i].f64(), y[i].f64(), z[i].f64());
        }
    }

    /// Position (m) of array index `i`.
    pub(super) fn position_at(&self, i: usize) -> DVec3 {
        self.frame
            .decode3(&self.cur.x.each_ref().map(Buf::as_slice), i)
    }

    /// Sets the position (m) of array index `i`, refitting the frame first if it
    /// does not hold it.
    pub(super) fn set_position_at(&mut self, i: usize, q: DVec3) {
        if self.frame.fixed && !self.frame.holds((q.into(), q.into()), 0.0) {
            let x = self.cur.x.each_ref().map(Buf::as_slice);
            let v = self.cur.v.each_ref().map(Buf::as_slice);
            let ((lo, hi), _) = frame::span(&self.frame, x, v, self.real_rows());
            let bounds = (q.min(lo.into()).into(), q.max(hi.into()).into());
            if let Some(frame) = self.spec.frame_rule().frame(bounds, 0.0) {
                self.adopt(frame);
            }
        }
        for a in 0..3 {
            self.cur.x[a].as_mut_slice()[i] = self.frame.encode(q[a], a);
        }
    }

    /// Copy the positions (m) of particles `0..out.len()` into `out`.
    pub fn positions_into(&self, out: &mut [DVec3]) {
        for (p, o) in out.iter_mut().enumerate().take(self.len()) {
            *o = self.position_at(self.grid.index(p));
        }
    }

    /// Position Verlet's velocities of the last position update, `(x - x_prev) / h`
    /// (m/s), of particles `0..out.len()`; nothing for the other integrators.
    pub fn update_velocities_into(&self, out: &mut [DVec3]) {
        if self.params.verlet {
            self.read_into(&self.cur.u, out);
        }
    }

    /// Sets position Verlet's velocities of the last position update (m/s); ignored
    /// for the other integrators.
    pub fn set_update_velocities(&mut self, u: &[DVec3]) {
        if !self.params.verlet {
            return;
        }
        for (p, q) in u.iter().enumerate().take(self.len()) {
            let j = self.grid.index(p);
            for a in 0..3 {
                self.cur.u[a].as_mut_slice()[j] = E::of(q[a]);
            }
        }
    }

    /// Copy the velocities (m/s) of particles `0..out.len()` into `out`.
    pub fn velocities_into(&self, out: &mut [DVec3]) {
        self.read_into(&self.cur.v, out);
    }

    /// Floats per row in the arrays of [`GridCloth::raw_positions`] (width rounded up,
    /// plus ghost columns): particle `(r, c)` is at `r * row_stride() + c`.
    pub fn row_stride(&self) -> usize {
        self.grid.stride
    }

    /// The padded position arrays `[x, y, z]` in m (see [`GridCloth::row_stride`]).
    pub fn raw_positions(&self) -> [Vec<f64>; 3] {
        let frame = &self.frame;
        let mut axis = 0..3;
        self.cur.x.each_ref().map(|b| {
            let a = axis.next().unwrap_or_default();
            b.as_slice().iter().map(|&x| frame.decode(x, a)).collect()
        })
    }

    /// The padded velocity arrays `[vx, vy, vz]` in m/s.
    pub fn raw_velocities(&self) -> [Vec<f64>; 3] {
        self.cur
            .v
            .each_ref()
            .map(|b| b.as_slice().iter().map(|x| x.f64()).collect())
    }

    /// Overwrite the state of particle `i` (ignored if out of range), e.g. for
    /// dragging it with the mouse.
    pub fn set_particle(&mut self, i: usize, position: DVec3, velocity: DVec3) {
        if i < self.len() {
            let j = self.grid.index(i);
            self.set_position_at(j, position);
            for a in 0..3 {
                self.cur.v[a].as_mut_slice()[j] = E::of(velocity[a]);
                if self.params.verlet {
                    self.cur.u[a].as_mut_slice()[j] = E::of(velocity[a]);
                }
            }
        }
    }

    /// Overwrite positions and velocities of particles `0..len` from f64 vectors
    /// (extra entries are ignored, missing ones left unchanged).
    pub fn set_state(&mut self, positions: &[DVec3], velocities: &[DVec3]) {
        if self.frame.fixed && positions.len() >= self.len() {
            // A frame around the new positions.
            let bounds = frame::bounds(&positions[..self.len()]);
            let frame = self.spec.frame_rule().frame(bounds, 0.0);
            if let Some(frame) = frame.filter(|f| *f != self.frame) {
                self.adopt(frame);
            }
        }
        for (p, &q) in positions.iter().enumerate().take(self.len()) {
            self.set_position_at(self.grid.index(p), q);
        }
        for (p, q) in velocities.iter().enumerate().take(self.len()) {
            let j = self.grid.index(p);
            for a in 0..3 {
                self.cur.v[a].as_mut_slice()[j] = E::of(q[a]);
            }
        }
        // Verlet's update velocities start equal to the velocities (call
        // `set_update_velocities` after this to give them their own values).
        if self.params.verlet {
            self.set_update_velocities(velocities);
        }
    }

    /// Pin (`true`: inverse mass 0, velocity 0) or free particle `i`.
    pub fn set_pinned(&mut self, i: usize, pinned: bool) {
        if i < self.len() {
            let j = self.grid.index(i);
            if pinned {
                self.inv_mass.as_mut_slice()[j] = E::ZERO;
                for a in 0..3 {
                    self.cur.v[a].as_mut_slice()[j] = E::ZERO;
                    if self.params.verlet {
                        self.cur.u[a].as_mut_slice()[j] = E::ZERO;
                    }
                }
            } else if self.spec.particle_mass > 0.0 {
                self.inv_mass.as_mut_slice()[j] = E::of(1.0 / self.spec.particle_mass);
            }
        }
    }
}

/// The largest squared speed (m²/s²) and squared distance from `center` (m²) of
/// the particles at `x` with velocities `v`, infinite when any is NaN: every fast
/// engine's cheap scan for the divergence check. A square is at least 0 or NaN,
/// and the bits of floats with the sign bit clear order as their values do, a
/// NaN's above infinity's (a NaN with the sign bit set above all): integer maxima,
/// which the compiler vectorises, give the largest squares and whether any is NaN
/// at once.
pub(super) fn runaway_scan<E: Real>(
    frame: &Frame,
    x: [&[E]; 3],
    v: [&[E]; 3],
    center: DVec3,
) -> (f64, f64) {
    if frame.fixed {
        extremes_in::<E, true>(frame, x, v, center)
    } else {
        extremes_in::<E, false>(frame, x, v, center)
    }
}

/// [`runaway_scan`] with positions in fixed point (`FIXED`) or floats.
#[inline(always)]
pub(super) fn extremes_in<E: Real, const FIXED: bool>(
    frame: &Frame,
    [x, y, z]: [&[E]; 3],
    [vx, vy, vz]: [&[E]; 3],
    center: DVec3,
) -> (f64, f64) {
    // A coordinate less the centre: `n unit + (frame centre - center)` in fixed
    // point, `x - center` for floats.
    let offset: [E; 3] = std::array::from_fn(|a| E::of(frame.centre[a] - center[a]));
    let unit = E::of(frame.unit);
    let from_center = |p: E, a: usize| {
        if FIXED {
            E::fixed_sub(p, E::ZERO) * unit + offset[a]
        } else {
            p + offset[a]
        }
    };
    let n = x.len();
    let (y, z, vx, vy, vz) = (&y[..n], &z[..n], &vx[..n], &vy[..n], &vz[..n]);
    let (mut speed2, mut dist2) = (E::ZERO.bits(), E::ZERO.bits());
    for i in 0..n {
        let v2 = vx[i] * vx[i] + vy[i] * vy[i] + vz[i] * vz[i];
        let (dx, dy, dz) = (
            from_center(x[i], 0),
            from_center(y[i], 1),
            from_center(z[i], 2),
        );
        let d2 = dx * dx + dy * dy + dz * dz;
        speed2 = speed2.max(v2.bits());
        dist2 = dist2.max(d2.bits());
    }
    let infinity = E::of(f64::INFINITY).bits();
    if speed2 > infinity || dist2 > infinity {
        return (f64::INFINITY, f64::INFINITY);
    }
    (E::from_bits(speed2).f64(), E::from_bits(dist2).f64())
}
