//! The fast engine for lattices: seed 002's jelly cube at any size, a `width x
//! height x depth` block of particles with a spring to every neighbour within one
//! cell (26 neighbours: axis springs of rest `h`, face diagonals of rest `h√2`,
//! body diagonals of rest `h√3`, one stiffness and damping per kind), under
//! gravity (and the applied force, as an acceleration), air damping and a penalty
//! ground, stepped by symplectic Euler, explicit Euler, position Verlet or XPBD,
//! then projected out of a sphere, and with friction on the sphere or the ground
//! resolved with it. These are the grid kernel's forces, integrators, projection
//! and contact, written once in [`super`] and shared: a spring is `spring`, a
//! particle's step `integrate`, the sphere `project_out_of_sphere`, contact with
//! friction `ContactRows` (over `Contact::resolve`), XPBD's springs and
//! Provot's stretch limit the grid's spring passes (`super::spring_passes`, see
//! `Lattice::spring_pass`). What the lattice does not model (bars, drag, tearing)
//! runs on the mesh engine instead (`super::super::fast_path` decides, spring by
//! spring).
//!
//! # Layout
//! Structure of arrays in the grid kernel's precision levels: float32 arithmetic
//! on float32 or fixed-point positions ([`Precision::Single`],
//! [`Precision::Mixed`]), or float64 throughout ([`Precision::Double`], the same
//! code at half the lanes), as [`Precision::cheapest`] finds for the lattice's
//! springs ([`Precision::spring_noise`]). Particle `(x, y, z)` is at
//! array index `x + y W + z W H` with `W = width + 1` and `H = height + 1`: one
//! ghost column after each row and one ghost row after each slab, and ghost slabs
//! after the last. Every one of the 13 forward neighbours `(x + dx, y + dy, z + dz)`
//! (`dz = 1`, or `dz = 0, dy = 1`, or `dz = dy = 0, dx = 1`) is then at a fixed
//! positive offset, and one that lies outside the lattice is a ghost: a spring's
//! force is multiplied by `real[a] real[b]`, 1 for particles and 0 for ghosts.
//! Ghosts have inverse mass 0 and stay at the origin.
//!
//! # The step
//! One pass over blocks of `LANES` consecutive indices: each block evaluates the 13
//! springs that start on its particles, once each, and adds their forces on the
//! particles it holds in registers; the forces on the other ends go to an
//! accumulator array. The offsets come in a run `+1` (along x) and four runs of
//! three consecutive offsets `o - 1, o, o + 1` (`dx = -1, 0, 1`); within a run the
//! three forces are moved by zero, one and two lanes (`Simd::shift1`, carried
//! from block to block) and stored with one read-modify-write, and the `+1` run's
//! forces reach their other ends by a shift alone. Springs reach only forward, so
//! once a block has stored its runs the forces on its own particles are complete,
//! and it integrates them at once, writing the new state to a second set of arrays
//! (ping-pong).
//!
//! Threads take bands of whole slabs. A band first recomputes, without
//! integrating, the blocks within one slab and a row before it (whose springs
//! reach into it), into its own accumulator, so no thread writes what another
//! reads and the result is bit-identical for any number of threads. Two bands hand
//! over each step by spinning (`Duo`), as the grid kernel's do.
//!
//! With XPBD the step predicts without the springs (their coefficients are 0 in
//! it), and XPBD's pass over the springs follows (forward and back, see
//! `xpbd_sweeps_back`), then the stretch limit's (each sweep's lines split
//! between the two threads), then the contact with friction.

use std::ops::Range;

use glam::DVec3;

use super::row::{EXPLICIT, SYMPLECTIC, VERLET, with_step_constants};
use super::spring_passes::{
    ColourClass, Multipliers, RowColour, SpringRule, Sweep, SweepLines, SweepMultipliers,
    SweepRules, SweepSprings, step_start,
};
use super::{
    BLOCK, Buf, ContactRows, Frame, FrameRule, Out, Params, Particle, Precision, Real, Simd,
    SimdLevel, SpringCoefficients, SpringNoise, State, StepLanes, frame, ground_constants,
    integrate, project_out_of_sphere, runaway_scan, spring, xpbd_step,
};
use crate::sim::constraints::xpbd_sweeps_back;
use crate::sim::duo::{Duo, run_in_pool};
use crate::sim::laws::Contact;
use crate::sim::{Ground, Integrator, Sphere};

/// Lattices with fewer particles than this run on the calling thread. Measured on
/// two AVX-512 cores (the jelly made `n`³, best of 3 runs of 600 steps, two threads
/// handing over by spinning against one core): 0.9x at 20³, 1.0x at 24³, 1.2x at 28³
/// (21,952 particles) and 1.4x at 32³.
pub const PARALLEL_MIN_PARTICLES: usize = 20_000;

/// A lattice's extents: particle `(x, y, z)` is `(z height + y) width + x` in the
/// model.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LatticeShape {
    /// Particles along x.
    pub width: usize,
    /// Particles along y.
    pub height: usize,
    /// Particles along z.
    pub depth: usize,
}

impl LatticeShape {
    /// Number of particles.
    pub fn len(&self) -> usize {
        self.width * self.height * self.depth
    }

    /// True if it has no particles.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Springs of each kind (axis, face diagonal, body diagonal) that a full
    /// lattice of this shape has.
    pub fn spring_counts(&self) -> [usize; 3] {
        let mut counts = [0; 3];
        for (dx, dy, dz) in FORWARD {
            let along = |n: usize, d: isize| n.saturating_sub(d.unsigned_abs());
            let steps = dx.unsigned_abs() + dy.unsigned_abs() + dz.unsigned_abs();
            counts[steps - 1] +=
                along(self.width, dx) * along(self.height, dy) * along(self.depth, dz);
        }
        counts
    }

    /// The kind (0 axis, 1 face diagonal, 2 body diagonal) of a spring from
    /// particle `a` to particle `b`, or `None` when `b` is not a forward neighbour
    /// of `a` within one cell.
    pub fn kind_of(&self, a: usize, b: usize) -> Option<usize> {
        self.direction(a, b).map(|d| {
            let (dx, dy, dz) = FORWARD[d];
            dx.unsigned_abs() + dy.unsigned_abs() + dz.unsigned_abs() - 1
        })
    }

    /// The colour class of a spring from particle `a` to particle `b` in the
    /// constraint passes (XPBD's springs, the stretch limit): its direction's index
    /// among the 13 forward neighbours, and the parity of its first end's
    /// coordinate along the direction (z where `dz != 0`, else y where `dy != 0`,
    /// else x). Springs of one direction and parity share no particle (each steps
    /// 1 along that coordinate, from an even one or from an odd one), so a class is
    /// corrected in any order with the same result: the lattice kernel's lanes
    /// and the f64 engine's one spring at a time ([`crate::sim::springs::constraint_order`]).
    /// `None` when `b` is not a forward neighbour of `a`.
    pub fn constraint_class(&self, a: usize, b: usize) -> Option<(usize, usize)> {
        let direction = self.direction(a, b)?;
        let (_, dy, dz) = FORWARD[direction];
        let [x, y, z] = self.coordinates(a);
        let along = if dz != 0 {
            z
        } else if dy != 0 {
            y
        } else {
            x
        };
        Some((direction, along % 2))
    }

    /// Lattice coordinates `[x, y, z]` of model particle `p`.
    fn coordinates(&self, p: usize) -> [usize; 3] {
        let (w, h) = (self.width, self.height);
        [p % w, (p / w) % h, p / (w * h)]
    }

    /// The index in [`FORWARD`] of the step from `a` to `b`.
    fn direction(&self, a: usize, b: usize) -> Option<usize> {
        let n = self.len();
        if a >= n || b >= n {
            return None;
        }
        let ([xa, ya, za], [xb, yb, zb]) = (self.coordinates(a), self.coordinates(b));
        let step = |from: usize, to: usize| to as isize - from as isize;
        let offset = (step(xa, xb), step(ya, yb), step(za, zb));
        FORWARD.iter().position(|&o| o == offset)
    }
}

/// The 13 forward neighbours `(dx, dy, dz)` of a lattice particle.
const FORWARD: [(isize, isize, isize); 13] = [
    (1, 0, 0),
    (-1, 1, 0),
    (0, 1, 0),
    (1, 1, 0),
    (-1, -1, 1),
    (0, -1, 1),
    (1, -1, 1),
    (-1, 0, 1),
    (0, 0, 1),
    (1, 0, 1),
    (-1, 1, 1),
    (0, 1, 1),
    (1, 1, 1),
];

/// Everything that defines a lattice for [`LatticeKernel::new`] (the positions and
/// velocities come from [`LatticeKernel::set_state`]).
#[derive(Clone, Debug, PartialEq)]
pub struct LatticeSpec {
    /// The extents.
    pub shape: LatticeShape,
    /// Rest length `h` of the axis springs in m.
    pub spacing: f64,
    /// Mass of every particle in kg.
    pub particle_mass: f64,
    /// Axis springs (rest `h`), face diagonals (`h√2`), body diagonals (`h√3`).
    pub kinds: [SpringCoefficients; 3],
    /// Acceleration of every free particle in m/s²: gravity plus the applied force
    /// over the mass.
    pub gravity: [f64; 3],
    /// Viscous air damping `c` in N·s/m (0: off).
    pub air_damping: f64,
    /// Penalty ground, with its friction.
    pub ground: Option<Ground>,
    /// Sphere collider.
    pub sphere: Option<Sphere>,
    /// Coulomb friction coefficient of the sphere.
    pub friction: f64,
    /// Provot's stretch limit `tau`: after the step no spring longer than `(1 +
    /// tau)` times its rest length (`None`: off).
    pub stretch_limit: Option<f64>,
    /// Symplectic Euler, explicit Euler, position Verlet or XPBD.
    pub integrator: Integrator,
    /// The precision to compute in.
    pub precision: Precision,
}

impl LatticeSpec {
    /// [`Precision::spring_noise`] of its springs with `positions` rounded as
    /// there, and XPBD's steps: a particle has up to 6 axis springs, 12 face
    /// diagonals and 8 body diagonals.
    fn noise(&self, positions: Result<f64, f64>, xpbd: Option<f64>) -> f64 {
        let h = self.spacing.abs();
        let springs = [(6.0, h), (12.0, h * 2f64.sqrt()), (8.0, h * 3f64.sqrt())];
        let springs =
            (self.kinds.iter().zip(springs)).map(|(kind, (count, rest))| (kind.k, count, rest));
        Precision::spring_noise(springs, self.particle_mass, positions, xpbd)
    }

    /// Radius (m) of the lattice at rest: half its diagonal.
    pub fn extent(&self) -> f64 {
        let LatticeShape {
            width,
            height,
            depth,
        } = self.shape;
        let cells = [width, height, depth].map(|n| n.max(1) as f64 - 1.0);
        0.5 * self.spacing.abs() * cells.iter().map(|c| c * c).sum::<f64>().sqrt()
    }

    /// The unit (m) of its positions in fixed point, chosen as the grid's is
    /// ([`super::GridSpec::fixed_unit`]).
    pub fn fixed_unit(&self) -> f64 {
        frame::fixed_unit(self.extent(), |unit| self.noise(Err(unit), None))
    }

    /// How its positions are stored: fixed point with [`Precision::Mixed`].
    fn frame_rule(&self) -> FrameRule<'_> {
        FrameRule {
            fixed: self.precision == Precision::Mixed,
            unit: self.fixed_unit(),
            ground: self.ground.as_ref(),
            sphere: self.sphere.as_ref(),
        }
    }

    /// Whether the kernel models an integrator.
    pub fn supports(integrator: Integrator) -> bool {
        matches!(
            integrator,
            Integrator::SymplecticEuler
                | Integrator::ExplicitEuler
                | Integrator::Verlet
                | Integrator::Xpbd
        )
    }
}

impl SpringNoise for LatticeSpec {
    fn spring_noise(&self, positions: Result<f64, f64>, dt: f64) -> f64 {
        self.noise(positions, xpbd_step(self.integrator, dt))
    }
    fn fixed_unit(&self) -> f64 {
        LatticeSpec::fixed_unit(self)
    }
    fn colliders(&self) -> (Option<Ground>, Option<Sphere>) {
        (self.ground, self.sphere)
    }
}

/// Where a lattice's particles lie in the padded arrays.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Geometry {
    shape: LatticeShape,
    /// Floats per row (`width + 1`) and per slab (`(height + 1) row`).
    row: usize,
    slab: usize,
    /// Indices the blocks cover: the slabs, rounded up to [`BLOCK`].
    blocks: usize,
    /// Floats per array: `blocks`, then ghosts for the farthest neighbour.
    len: usize,
}

impl Geometry {
    fn new(shape: LatticeShape) -> Self {
        let row = shape.width + 1;
        let slab = row * (shape.height + 1);
        let blocks = (slab * shape.depth).next_multiple_of(BLOCK);
        Geometry {
            shape,
            row,
            slab,
            blocks,
            len: blocks + Self::reach(slab, row).next_multiple_of(BLOCK) + BLOCK,
        }
    }

    /// The largest offset of a forward neighbour, plus the two lanes a run of
    /// three is shifted by.
    fn reach(slab: usize, row: usize) -> usize {
        slab + row + 1 + 2
    }

    /// The first offsets `o - 1` of the four runs of three (`dx = -1, 0, 1`):
    /// `(dy, dz) = (1, 0), (-1, 1), (0, 1), (1, 1)`.
    fn runs(&self) -> [usize; 4] {
        let (row, slab) = (self.row, self.slab);
        [row - 1, slab - row - 1, slab - 1, slab + row - 1]
    }

    /// Array index of model particle `p`.
    fn index(&self, p: usize) -> usize {
        let (w, h) = (self.shape.width, self.shape.height);
        p % w + ((p / w) % h) * self.row + (p / (w * h)) * self.slab
    }
}

/// A band of blocks one thread steps, with its own accumulator.
#[derive(Clone, Debug)]
pub(super) struct Band<E> {
    /// The band's first index and one past its last (multiples of [`BLOCK`]).
    start: usize,
    end: usize,
    /// Where the band starts recomputing springs (see the module doc), the index
    /// of `acc`'s first entry.
    from: usize,
    /// Forces on the particles `from ..` (x, y, z) from the springs of earlier
    /// blocks.
    acc: [Vec<E>; 3],
}

impl<E: Real> Band<E> {
    fn new(start: usize, end: usize, geometry: &Geometry) -> Self {
        let reach = Geometry::reach(geometry.slab, geometry.row).next_multiple_of(BLOCK);
        // One block more than the springs reach, for the lanes the runs carry.
        let from = start.saturating_sub(reach + BLOCK);
        let len = end - from + reach + BLOCK;
        Band {
            start,
            end,
            from,
            acc: std::array::from_fn(|_| vec![E::ZERO; len]),
        }
    }
}

/// `n` bands of whole slabs (as nearly equal as the blocks allow).
fn make_bands<E: Real>(geometry: &Geometry, n: usize) -> Vec<Band<E>> {
    let depth = geometry.shape.depth;
    let n = n.clamp(1, depth.max(1));
    let cut = |i: usize| {
        if i == n {
            geometry.blocks
        } else {
            (i * depth / n * geometry.slab) / BLOCK * BLOCK
        }
    };
    (0..n)
        .map(|i| Band::new(cut(i), cut(i + 1), geometry))
        .collect()
}

/// What a band reads.
pub(super) struct Ctx<'a, E> {
    p: Params<E>,
    geometry: Geometry,
    x: [&'a [E]; 3],
    v: [&'a [E]; 3],
    u: [&'a [E]; 3],
    real: &'a [E],
    inv_mass: &'a [E],
    pub(super) simd: SimdLevel,
}

/// The fast engine for a lattice (see the module doc): float32 arithmetic on
/// float32 or fixed-point positions, or float64 throughout, as the spec's
/// precision says.
#[derive(Debug)]
pub struct LatticeKernel(Kernels);

#[derive(Debug)]
enum Kernels {
    /// Float32 arithmetic: [`Precision::Single`] and [`Precision::Mixed`].
    Single(Lattice<f32>),
    /// Float64: [`Precision::Double`].
    Double(Lattice<f64>),
}

// `forward!` is the grid kernel's: a method that the kernel of either float type
// has, called on the one held.
impl LatticeKernel {
    /// A lattice at the origin, at rest, every particle free; on one thread.
    ///
    /// # Panics
    /// If the spec's integrator is one the kernel does not model
    /// ([`LatticeSpec::supports`]).
    pub fn new(spec: LatticeSpec) -> Self {
        assert!(
            LatticeSpec::supports(spec.integrator),
            "integrator not modelled"
        );
        LatticeKernel(match spec.precision {
            Precision::Double => Kernels::Double(Lattice::new(spec)),
            Precision::Single | Precision::Mixed => Kernels::Single(Lattice::new(spec)),
        })
    }

    forward!(
        /// Changes coefficients in place (stiffness, damping, mass, rest length,
        /// gravity, air damping, colliders). Returns `false`, changing nothing, when
        /// `spec` has another shape, integrator or precision: then build a new
        /// kernel. Every particle is freed (pin them again).
        fn respec(&mut self, spec: LatticeSpec) -> bool
    );
    forward!(
        /// The spec the kernel models now.
        fn spec(&self) -> &LatticeSpec
    );
    forward!(
        /// Number of particles.
        fn len(&self) -> usize
    );
    forward!(
        /// True if the lattice has no particles.
        fn is_empty(&self) -> bool
    );
    forward!(
        /// Use `n` threads (at least 1) for lattices of [`PARALLEL_MIN_PARTICLES`] or
        /// more particles and at least `n` slabs; others run on the calling thread.
        /// Builds a rayon pool (this allocates; the steps do not).
        fn set_threads(&mut self, n: usize)
    );
    forward!(
        /// True if steps run on several threads.
        fn is_parallel(&self) -> bool
    );
    forward!(
        /// The unit (m) of the fixed-point positions now: the spec's
        /// ([`LatticeSpec::fixed_unit`]) or, once the body has spread past what
        /// that holds, a coarser one; `None` on float positions.
        fn position_unit(&self) -> Option<f64>
    );
    forward!(
        /// Force a SIMD level (for tests and benches). A level this CPU lacks is
        /// ignored.
        fn set_simd_level(&mut self, level: SimdLevel)
    );
    forward!(
        /// Pins (inverse mass 0) or frees model particle `p`.
        fn set_pinned(&mut self, p: usize, pinned: bool)
    );
    forward!(
        /// Sets positions (m) and velocities (m/s) of the model's particles.
        fn set_state(&mut self, positions: &[DVec3], velocities: &[DVec3])
    );
    forward!(
        /// Sets Verlet's velocities of the last position update (ignored for the
        /// other integrators).
        fn set_update_velocities(&mut self, u: &[DVec3])
    );
    forward!(
        /// Positions in m, in model order.
        fn positions_into(&self, out: &mut [DVec3])
    );
    forward!(
        /// Velocities in m/s, in model order.
        fn velocities_into(&self, out: &mut [DVec3])
    );
    forward!(
        /// Verlet's velocities of the last position update (the velocities for the
        /// other integrators).
        fn update_velocities_into(&self, out: &mut [DVec3])
    );
    forward!(
        /// The largest squared speed and squared distance from `center` of any
        /// particle (infinite if any is NaN).
        fn extremes(&self, center: DVec3) -> (f64, f64)
    );
    forward!(
        /// Advances `n` steps of `dt` seconds (inside the thread pool once).
        fn steps(&mut self, dt: f64, n: usize)
    );
}

/// The lattice kernel in one float type (see [`LatticeKernel`], which holds one).
struct Lattice<E: Real> {
    spec: LatticeSpec,
    geometry: Geometry,
    /// How the position arrays map to metres.
    frame: Frame,
    params: Params<E>,
    cur: State<E>,
    next: State<E>,
    /// 1 for particles, 0 for ghosts.
    real: Buf<E>,
    inv_mass: Buf<E>,
    bands: Vec<Band<E>>,
    pool: Option<rayon::ThreadPool>,
    simd: SimdLevel,
    /// XPBD's multipliers, kept from each spring's first correction to its second.
    multipliers: Multipliers<E>,
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
    fn new(spec: LatticeSpec) -> Self {
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
    fn params(spec: &LatticeSpec, frame: &Frame) -> Params<E> {
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
    fn rests(spec: &LatticeSpec) -> [f64; 3] {
        let h = spec.spacing;
        [h, h * 2f64.sqrt(), h * 3f64.sqrt()]
    }

    /// The colliders as the f64 engine resolves them after a step `dt`.
    fn contact(spec: &LatticeSpec, dt: f64) -> Contact {
        Contact {
            sphere: spec.sphere,
            ground: spec.ground,
            friction: spec.friction,
            dt,
        }
    }

    /// Every particle free, with the spec's mass.
    fn reset_masses(&mut self) {
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
    fn respec(&mut self, spec: LatticeSpec) -> bool {
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
    fn spec(&self) -> &LatticeSpec {
        &self.spec
    }

    /// Number of particles.
    fn len(&self) -> usize {
        self.spec.shape.len()
    }

    /// True if the lattice has no particles.
    fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Use `n` threads (at least 1) for lattices of [`PARALLEL_MIN_PARTICLES`] or
    /// more particles and at least `n` slabs; others run on the calling thread.
    /// Builds a rayon pool (this allocates; the steps do not).
    fn set_threads(&mut self, n: usize) {
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
    fn is_parallel(&self) -> bool {
        self.pool.is_some()
    }

    /// The unit (m) of the fixed-point positions now (see
    /// [`super::GridCloth::position_unit`]); `None` on float positions.
    fn position_unit(&self) -> Option<f64> {
        self.frame.fixed.then_some(self.frame.unit)
    }

    /// Force a SIMD level (for tests and benches). A level this CPU lacks is
    /// ignored.
    fn set_simd_level(&mut self, level: SimdLevel) {
        if level.is_supported() {
            self.simd = level;
        }
    }

    /// Pins (inverse mass 0) or frees model particle `p`.
    fn set_pinned(&mut self, p: usize, pinned: bool) {
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
    fn set_state(&mut self, positions: &[DVec3], velocities: &[DVec3]) {
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
    fn set_update_velocities(&mut self, u: &[DVec3]) {
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
    fn positions_into(&self, out: &mut [DVec3]) {
        let x = self.cur.x.each_ref().map(Buf::as_slice);
        for (p, o) in out.iter_mut().enumerate().take(self.len()) {
            *o = self.frame.decode3(&x, self.geometry.index(p));
        }
    }

    /// Velocities in m/s, in model order.
    fn velocities_into(&self, out: &mut [DVec3]) {
        self.read_into(&self.cur.v, out);
    }

    /// Verlet's velocities of the last position update (the velocities for the
    /// other integrators).
    fn update_velocities_into(&self, out: &mut [DVec3]) {
        let u = if self.params.verlet {
            &self.cur.u
        } else {
            &self.cur.v
        };
        self.read_into(u, out);
    }

    fn read_into(&self, arrays: &[Buf<E>; 3], out: &mut [DVec3]) {
        for (p, o) in out.iter_mut().enumerate().take(self.len()) {
            let i = self.geometry.index(p);
            *o = DVec3::from_array(std::array::from_fn(|a| arrays[a].as_slice()[i].f64()));
        }
    }

    /// The largest squared speed and squared distance from `center` of any
    /// particle (infinite if any is NaN).
    fn extremes(&self, center: DVec3) -> (f64, f64) {
        let blocks = self.geometry.blocks;
        let x = self.cur.x.each_ref().map(|a| &a.as_slice()[..blocks]);
        let v = self.cur.v.each_ref().map(|a| &a.as_slice()[..blocks]);
        runaway_scan(&self.frame, x, v, center)
    }

    /// The real particles' array indices, row by row.
    fn real_rows(&self) -> impl Iterator<Item = Range<usize>> + Clone + use<E> {
        let (shape, row) = (self.geometry.shape, self.geometry.row);
        let rows = (shape.height + 1) * shape.depth;
        (0..rows)
            .filter(move |r| r % (shape.height + 1) < shape.height)
            .map(move |r| r * row..r * row + shape.width)
    }

    /// Keeps fixed-point positions in range for `time` s more, as the grid kernel
    /// does (`Kernel::keep_in_frame`).
    fn keep_in_frame(&mut self, time: f64) {
        let rule = self.spec.frame_rule();
        if let Some(frame) = self.cur.refit(&self.frame, rule, self.real_rows(), time) {
            self.adopt(frame);
        }
    }

    /// Re-encodes the positions in `frame`, and the constants with them.
    fn adopt(&mut self, frame: Frame) {
        let rows = self.real_rows();
        self.cur.reframe(&mut self.frame, frame, rows);
        self.params = Self::params(&self.spec, &frame).with_step_of(&self.params);
    }

    /// Advances `n` steps of `dt` seconds (inside the thread pool once).
    fn steps(&mut self, dt: f64, n: usize) {
        self.params.dt = E::of(dt);
        if self.params.verlet {
            self.params.verlet_half_dt = E::of(0.5 * dt);
        }
        let pool = self.pool.take();
        let parallel = pool.is_some();
        let two_bands = self.bands.len() == 2;
        let run = |duo: Option<&Duo>| {
            for i in 0..n {
                if i % frame::CHECK_STEPS == 0 {
                    self.keep_in_frame(frame::CHECK_STEPS.min(n - i) as f64 * dt);
                }
                self.one_step(parallel, duo);
                self.constrain(dt, duo);
                self.resolve_contact(dt);
            }
        };
        // Two bands: the second is handed to the pool's other thread by spinning,
        // as the grid kernel's are, rather than woken by `rayon::join` each step.
        run_in_pool(pool.as_ref(), two_bands, run);
        self.pool = pool;
    }

    /// The passes along the springs after the step: XPBD's springs, then
    /// Provot's stretch limit, as in the f64 engine; with `duo`, on both threads.
    fn constrain(&mut self, dt: f64, duo: Option<&Duo>) {
        if self.spec.integrator == Integrator::Xpbd {
            self.spring_pass(SpringRule::Xpbd, dt, duo);
        }
        if let Some(tau) = self.spec.stretch_limit {
            self.spring_pass(SpringRule::StretchLimit(tau), dt, duo);
        }
    }

    /// One pass of `rule` over the springs, with the grid's passes
    /// ([`super::spring_passes`]): the lattice's array rows (`x + r W` with
    /// `r = y + z H`) are a grid's rows, a direction `(dx, dy, dz)` is the grid direction
    /// `(dy + dz H, dx)`, and the real-particle mask leaves out the springs that
    /// reach a ghost. Sweeps go by direction in the order of [`FORWARD`], each
    /// direction's two colour classes in turn ([`LatticeShape::constraint_class`],
    /// the f64 engine's order): `z % 2` is the row's `(r / H) % 2`, and `y % 2` is
    /// `(r % H) % 2`.
    ///
    /// With `duo`, each sweep's lines run on two threads: the lines from the
    /// middle row `m` on on the other thread, those that touch no row from `m` on
    /// on this one, then the few between here. A line's lanes past its end reach
    /// the next rows' particles (the lattice has no padding), which they store
    /// unchanged, so a line from row `r` touches rows `r` to `r + dr` and one or
    /// two more; kept apart so, the two threads' lines touch no particle in
    /// common, and the result is the same as on one thread.
    fn spring_pass(&mut self, rule: SpringRule, dt: f64, duo: Option<&Duo>) {
        let g = self.geometry;
        let slab_rows = g.shape.height + 1;
        let rows = slab_rows * g.shape.depth;
        let rules = SweepRules {
            rule,
            dt,
            frame: self.frame,
        };
        let rests = Self::rests(&self.spec);
        let sweeps: [Option<Sweep<E>>; 2 * FORWARD.len()] = std::array::from_fn(|k| {
            let (direction, colour) = (k / 2, k % 2);
            let (dx, dy, dz) = FORWARD[direction];
            let kind = dx.unsigned_abs() + dy.unsigned_abs() + dz.unsigned_abs() - 1;
            let springs = SweepSprings {
                direction,
                dr: (dy + dz * slab_rows as isize) as usize,
                dc: dx,
                rest: rests[kind],
                kind: self.spec.kinds[kind],
            };
            let colour_of_rows = if dz != 0 {
                Some(RowColour {
                    wrap: usize::MAX,
                    period: slab_rows,
                })
            } else if dy != 0 {
                Some(RowColour {
                    wrap: slab_rows,
                    period: 1,
                })
            } else {
                None
            };
            let class = ColourClass {
                rows: colour_of_rows,
                colour,
            };
            Sweep::new(&rules, springs, (g.shape.width, rows), class)
        });
        // XPBD sweeps back as well on a lattice, each spring's multiplier kept.
        let back = matches!(rule, SpringRule::Xpbd) && xpbd_sweeps_back(Some(g.shape));
        let mut multipliers = std::mem::take(&mut self.multipliers);
        if back {
            multipliers.ensure(sweeps.len(), self.inv_mass.as_slice().len());
        }
        for (k, sweep) in sweeps.iter().enumerate() {
            if let Some(sweep) = sweep {
                let m = back.then(|| multipliers.of_sweep(k, false));
                self.sweep_lines(rule, sweep, m, duo);
            }
        }
        if back {
            // Backward, but for the last sweep, whose springs' second correction
            // would change nothing.
            let last = sweeps.iter().rposition(Option::is_some);
            for (k, sweep) in sweeps.iter().enumerate().rev() {
                if let Some(sweep) = sweep.as_ref().filter(|_| Some(k) != last) {
                    let m = multipliers.of_sweep(k, true);
                    self.sweep_lines(rule, sweep, Some(m), duo);
                }
            }
        }
        self.multipliers = multipliers;
    }

    /// The lines of one sweep, on two threads with `duo` (see
    /// [`Self::spring_pass`]).
    fn sweep_lines(
        &mut self,
        rule: SpringRule,
        sweep: &Sweep<E>,
        multipliers: Option<SweepMultipliers<E>>,
        duo: Option<&Duo>,
    ) {
        let g = self.geometry;
        let start = step_start(rule, &self.next);
        let lines = |rows: Range<usize>| SweepLines {
            sweep,
            stride: g.row,
            rows,
            inv_mass: self.inv_mass.as_slice(),
            alive: None,
            real: Some(self.real.as_slice()),
            start,
            multipliers,
            both_colours: false,
        };
        // A line from row `r` touches rows `r` to `r + dr` and, through its lanes
        // past the end (up to `BLOCK` more), the rows after those.
        let all = sweep.rows();
        let split = all.end / 2;
        let touched = sweep.dr() + (g.shape.width + 1 + BLOCK).div_ceil(g.row);
        let above = split.saturating_sub(touched);
        let simd = self.simd;
        match duo {
            Some(duo) if above > 0 => {
                let (mut upper, mut lower) = self.cur.rows().split_at(split * g.row);
                let (top, bottom) = (lines(0..above), lines(split..all.end));
                let mut second = || E::spring_sweep(simd, &mut lower, split * g.row, &bottom);
                duo.fork(&mut second, || E::spring_sweep(simd, &mut upper, 0, &top));
                E::spring_sweep(simd, &mut self.cur.rows(), 0, &lines(above..split));
            }
            _ => E::spring_sweep(simd, &mut self.cur.rows(), 0, &lines(all)),
        }
    }

    /// The colliders with friction, after the step (without friction the step
    /// projected the particles out of the sphere itself): the grid kernel's
    /// contact rows, one lattice row each, on this thread.
    fn resolve_contact(&mut self, dt: f64) {
        let contact = Self::contact(&self.spec, dt);
        if !contact.is_active() || self.params.sphere.is_some() {
            return;
        }
        let g = self.geometry;
        let rows = (g.shape.height + 1) * g.shape.depth;
        let (cur, inv_mass) = (&mut self.cur, self.inv_mass.as_slice());
        let rows_of = ContactRows::of_rows(
            &contact,
            (g.shape.width, g.row, inv_mass),
            self.frame,
            self.simd,
            (self.params.verlet, false),
        );
        rows_of.resolve(&mut cur.rows(), 0, 0..rows);
    }

    fn one_step(&mut self, parallel: bool, duo: Option<&Duo>) {
        let ctx = Ctx {
            p: self.params,
            geometry: self.geometry,
            x: self.cur.x.each_ref().map(Buf::as_slice),
            v: self.cur.v.each_ref().map(Buf::as_slice),
            u: self.cur.u.each_ref().map(Buf::as_slice),
            real: self.real.as_slice(),
            inv_mass: self.inv_mass.as_slice(),
            simd: self.simd,
        };
        let out = self.next.rows();
        match (duo, &mut self.bands[..]) {
            (Some(duo), [first, second]) => {
                let (out_first, out_second) = out.split_at(second.start);
                duo.fork_once(
                    || E::lattice_band(&ctx, second, out_second),
                    || E::lattice_band(&ctx, first, out_first),
                );
            }
            (_, bands) => run_bands(&ctx, bands, out, parallel),
        }
        std::mem::swap(&mut self.cur, &mut self.next);
    }
}

/// Runs the bands, splitting the outputs (which start at the first band's start)
/// among them; in parallel with `rayon::join` when `parallel`.
fn run_bands<E: Real>(ctx: &Ctx<E>, bands: &mut [Band<E>], out: Out<E>, parallel: bool) {
    if let [band] = bands {
        E::lattice_band(ctx, band, out);
        return;
    }
    let mid = bands.len() / 2;
    let (first, second) = bands.split_at_mut(mid);
    let (out_first, out_second) = out.split_at(second[0].start - first[0].start);
    if parallel {
        rayon::join(
            || run_bands(ctx, first, out_first, true),
            || run_bands(ctx, second, out_second, true),
        );
    } else {
        run_bands(ctx, first, out_first, false);
        run_bands(ctx, second, out_second, false);
    }
}

/// [`band_steps`] for the spec's integrator terms and precision.
#[inline(always)]
pub(super) fn band_modes<S: Simd>(s: S, ctx: &Ctx<S::E>, band: &mut Band<S::E>, out: Out<S::E>) {
    match (ctx.p.is_plain(), ctx.p.fixed) {
        (true, true) => band_steps::<S, true, true>(s, ctx, band, out),
        (true, false) => band_steps::<S, true, false>(s, ctx, band, out),
        (false, true) => band_steps::<S, false, true>(s, ctx, band, out),
        (false, false) => band_steps::<S, false, false>(s, ctx, band, out),
    }
}

/// Splatted constants and raw pointers of one band.
struct Lanes<S: Simd> {
    s: S,
    step: StepLanes<S>,
    /// `[-k, k L, -b]` of the axis springs, face and body diagonals.
    kinds: [[S::V; 3]; 3],
    x: [*const S::E; 3],
    v: [*const S::E; 3],
    real: *const S::E,
    inv_mass: *const S::E,
    /// The band's accumulator, whose entry 0 is index `from`.
    acc: [*mut S::E; 3],
    from: usize,
    /// The band's first index (entry 0 of the outputs).
    start: usize,
    runs: [usize; 4],
}

impl<S: Simd> Lanes<S> {
    /// Positions (as stored) and velocities of the particles at `i .. i + LANES`.
    ///
    /// # Safety
    /// `i + LANES` must be within the arrays.
    #[inline(always)]
    unsafe fn particle<const FIXED: bool>(&self, i: usize) -> Lanes3<S::V> {
        let s = self.s;
        // SAFETY: caller's contract.
        let ld = |p: [*const S::E; 3]| unsafe {
            [
                s.load(p[0].add(i)),
                s.load(p[1].add(i)),
                s.load(p[2].add(i)),
            ]
        };
        (ld(self.x), ld(self.v))
    }

    /// Forces of the springs of `kind` from the particles `a` (whose `real` is
    /// `real_a`) to those at `b .. b + LANES`, zero where either end is a ghost.
    ///
    /// # Safety
    /// As for [`Lanes::particle`] at `b`.
    #[inline(always)]
    unsafe fn spring_to<const FIXED: bool>(
        &self,
        a: Particle<S::V>,
        real_a: S::V,
        b: usize,
        kind: usize,
    ) -> [S::V; 3] {
        let s = self.s;
        // SAFETY: caller's contract.
        let ((bx, bv), real_b) = unsafe { (self.particle::<FIXED>(b), s.load(self.real.add(b))) };
        let mask = s.mul(real_a, real_b);
        spring::<S, FIXED>(s, a, (&bx, &bv), self.kinds[kind], Some(mask)).0
    }
}

/// A block's positions and velocities.
type Lanes3<V> = ([V; 3], [V; 3]);

/// Forces of the previous block carried to the next: the `+1` run's, and the
/// second and third springs of each run of three.
struct Carry<V> {
    along: [V; 3],
    runs: [[[V; 3]; 2]; 4],
}

/// The band's blocks: those before `start` only for their springs, then its own.
#[inline(always)]
fn band_steps<S: Simd, const PLAIN: bool, const FIXED: bool>(
    s: S,
    ctx: &Ctx<S::E>,
    band: &mut Band<S::E>,
    mut out: Out<S::E>,
) {
    let g = &ctx.geometry;
    let reach = Geometry::reach(g.slab, g.row);
    // Everything `block` reads or writes lies inside these bounds.
    assert!(S::LANES <= BLOCK && band.start.is_multiple_of(S::LANES));
    assert!(band.end <= g.blocks && band.end.is_multiple_of(S::LANES));
    assert!(band.from.is_multiple_of(S::LANES) && band.from <= band.start);
    for a in ctx.x.iter().chain(&ctx.v).chain([&ctx.real, &ctx.inv_mass]) {
        assert!(a.len() >= g.blocks + reach + S::LANES);
    }
    for a in &band.acc {
        assert!(a.len() >= band.end - band.from + reach + S::LANES);
    }
    let verlet = ctx.p.verlet;
    if verlet {
        assert!(ctx.u.iter().all(|u| u.len() >= g.blocks));
    }
    for o in &out.0[..if verlet { 9 } else { 6 }] {
        assert!(o.len() >= band.end - band.start);
    }
    for a in &mut band.acc {
        a.fill(S::E::ZERO);
    }
    let p = &ctx.p;
    let kind = |i: usize| [s.splat(-p.ks[i]), s.splat(p.kls[i]), s.splat(-p.bs[i])];
    let k = Lanes {
        s,
        step: StepLanes::new(s, p, ctx.u, ctx.v, &mut out),
        kinds: [kind(0), kind(1), kind(2)],
        x: ctx.x.map(<[S::E]>::as_ptr),
        v: ctx.v.map(<[S::E]>::as_ptr),
        real: ctx.real.as_ptr(),
        inv_mass: ctx.inv_mass.as_ptr(),
        acc: band.acc.each_mut().map(|a| a.as_mut_ptr()),
        from: band.from,
        start: band.start,
        runs: g.runs(),
    };
    let zero = [k.step.zero; 3];
    let mut carry = Carry {
        along: zero,
        runs: [[zero; 2]; 4],
    };
    let mut at = band.from;
    while at < band.start {
        // SAFETY: `at` is a multiple of LANES below `blocks`; bounds asserted above.
        unsafe { block::<S, false, PLAIN, FIXED>(&k, at, &mut carry) };
        at += S::LANES;
    }
    while at < band.end {
        // SAFETY: as above.
        unsafe { block::<S, true, PLAIN, FIXED>(&k, at, &mut carry) };
        at += S::LANES;
    }
}

/// The particles at indices `at .. at + LANES`: their 13 forward springs, and with
/// `OWN` their step (see the module doc).
///
/// # Safety
/// `from <= at < blocks`, a multiple of `LANES`, with the bounds of
/// [`band_steps`]; with `OWN`, `at >= start`.
#[inline(always)]
unsafe fn block<S: Simd, const OWN: bool, const PLAIN: bool, const FIXED: bool>(
    k: &Lanes<S>,
    at: usize,
    carry: &mut Carry<S::V>,
) {
    let s = k.s;
    // SAFETY: `at` is inside the arrays (caller's contract).
    let (ax, av) = unsafe { k.particle::<FIXED>(at) };
    let a = (&ax, &av);
    // SAFETY: as above.
    let real_a = unsafe { s.load(k.real.add(at)) };
    // SAFETY: every forward neighbour of `at` is inside the arrays (as above).
    let to =
        |offset: usize, kind: usize| unsafe { k.spring_to::<FIXED>(a, real_a, at + offset, kind) };
    let along = to(1, 0);
    let mut own = along;
    let shifted: [S::V; 3] = std::array::from_fn(|i| s.shift1(carry.along[i], along[i]));
    carry.along = along;
    for (r, &first) in k.runs.iter().enumerate() {
        // Runs along y (r = 0) and of dy = 0 (r = 2) have an axis spring in the
        // middle and face diagonals at the sides; the others a face diagonal and
        // body diagonals.
        let middle = r % 2;
        let (left, centre, right) = (
            to(first, middle + 1),
            to(first + 1, middle),
            to(first + 2, middle + 1),
        );
        let [previous_centre, previous_right] = carry.runs[r];
        for i in 0..3 {
            own[i] = s.add(own[i], s.add(s.add(left[i], centre[i]), right[i]));
            let other = s.add(
                s.add(left[i], s.shift1(previous_centre[i], centre[i])),
                s.shift2(previous_right[i], right[i]),
            );
            // SAFETY: the accumulator holds every index a band's springs reach.
            unsafe {
                let q = k.acc[i].add(at + first - k.from);
                s.store(q, s.sub(s.load(q), other));
            }
        }
        carry.runs[r] = [centre, right];
    }
    if OWN {
        // SAFETY: as above.
        let w = unsafe { s.load(k.inv_mass.add(at)) };
        // The three components in the step's method and ground, chosen once.
        macro_rules! step {
            ($method:ident, $ground:literal) => {
                for i in 0..3 {
                    // SAFETY: the accumulator's entries for this block are complete
                    // (every other end but the `+1` run's is a row or more back); the
                    // outputs hold the band from `start`.
                    unsafe {
                        let earlier = s.load(k.acc[i].add(at - k.from));
                        let force = s.sub(s.add(earlier, own[i]), shifted[i]);
                        integrate::<S, PLAIN, FIXED, { $method }, $ground>(
                            &k.step,
                            at,
                            at - k.start,
                            i,
                            w,
                            a,
                            force,
                        )
                    }
                }
            };
        }
        with_step_constants!(PLAIN, k.step, step);
        if !PLAIN && k.step.sphere.is_some() {
            // SAFETY: as above, after `integrate` ran for all three components.
            unsafe { project_out_of_sphere::<S, FIXED>(&k.step, at - k.start, w) };
        }
    }
}
