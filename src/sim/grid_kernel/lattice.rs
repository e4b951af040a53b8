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
//! runs on the f64 engine instead (`super::super::fast_path` decides, spring by
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

use glam::DVec3;

use super::{BLOCK, Params, Precision, Real, SimdLevel};

/// Lattices with fewer particles than this run on the calling thread. Measured on
/// two AVX-512 cores (the jelly made `n`³, best of 3 runs of 600 steps, two threads
/// handing over by spinning against one core): 0.9x at 20³, 1.0x at 24³, 1.2x at 28³
/// (21,952 particles) and 1.4x at 32³.
pub const PARALLEL_MIN_PARTICLES: usize = 20_000;

mod band;
mod kernel;
mod spec;
mod step;

pub(super) use band::band_modes;
use kernel::Lattice;
pub use spec::{LatticeShape, LatticeSpec};

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
