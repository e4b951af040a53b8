//! [`GridCloth`], the grid kernel's public face: the kernel in the precision its
//! spec asks for, every method forwarded to it.

use glam::DVec3;

use super::{GridSpec, Kernel, Precision, SimdLevel};
use crate::sim::{Integrator, Wind};

/// A regular grid cloth stepped by the fast stencil kernel, in float32 or float64
/// arithmetic as its spec asks ([`Precision`]).
///
/// ```
/// use cloth_sandbox::sim::grid_kernel::{GridCloth, GridSpec};
/// let mut cloth = GridCloth::new(GridSpec::peer_bench(32, false));
/// cloth.steps(1.0 / 960.0, 960);
/// let mut p = vec![glam::DVec3::ZERO; cloth.len()];
/// cloth.positions_into(&mut p);
/// assert!(p[1008].y < -0.6);
/// ```
#[derive(Debug)]
pub struct GridCloth(Kernels);

/// The kernel of each precision.
#[derive(Debug)]
pub(super) enum Kernels {
    Single(Kernel<f32>),
    Double(Kernel<f64>),
}

impl GridCloth {
    /// Builds the cloth at rest, flat in the x-y plane (see [`GridSpec`]), in the
    /// spec's precision. Runs on one thread until [`GridCloth::set_threads`] is
    /// called. A width or height of 0 is taken as 1; pinned indices out of range are
    /// ignored.
    ///
    /// # Panics
    /// If the spec's integrator is not one the kernel has ([`GridCloth::supports`]).
    pub fn new(spec: GridSpec) -> Self {
        Self(match spec.precision {
            Precision::Single | Precision::Mixed => Kernels::Single(Kernel::new(spec)),
            Precision::Double => Kernels::Double(Kernel::new(spec)),
        })
    }

    /// Whether the kernel steps with `integrator`: symplectic Euler, explicit Euler
    /// and position Verlet (the methods with one force evaluation per step).
    pub fn supports(integrator: Integrator) -> bool {
        matches!(
            integrator,
            Integrator::SymplecticEuler
                | Integrator::ExplicitEuler
                | Integrator::Verlet
                | Integrator::Xpbd
        )
    }

    /// Changes coefficients in place (stiffness, damping, mass, rest length, wind,
    /// gravity, drag, air damping, colliders, stretch limit) without rebuilding the
    /// arrays or the thread pool. Returns `false`, changing nothing, when `spec` has
    /// another shape, integrator or precision: then build a new cloth. The particles'
    /// inverse masses are reset to the new mass (pins included: pin them again).
    pub fn respec(&mut self, spec: GridSpec) -> bool {
        if spec.precision != self.spec().precision {
            return false;
        }
        match &mut self.0 {
            Kernels::Single(k) => k.respec(spec),
            Kernels::Double(k) => k.respec(spec),
        }
    }

    forward!(
        /// The spec the cloth was built from (with the current wind and gravity).
        fn spec(&self) -> &GridSpec
    );
    forward!(
        /// Number of particles.
        fn len(&self) -> usize
    );
    forward!(
        /// True if the cloth has no particles (never: a grid has at least one).
        fn is_empty(&self) -> bool
    );
    forward!(
        /// Use `n` threads (at least 1) for grids of
        /// [`PARALLEL_MIN_PARTICLES`](super::PARALLEL_MIN_PARTICLES)
        /// particles or more; smaller grids always run on the calling thread. Builds
        /// a rayon pool of `n` threads (this allocates; the steps do not).
        fn set_threads(&mut self, n: usize)
    );
    forward!(
        /// Threads asked for with [`GridCloth::set_threads`].
        fn threads(&self) -> usize
    );
    forward!(
        /// True if steps run on several threads (enough threads and a large grid).
        fn is_parallel(&self) -> bool
    );
    forward!(
        /// The SIMD level the loops run with.
        fn simd_level(&self) -> SimdLevel
    );
    forward!(
        /// The unit (m) of the fixed-point positions now: the spec's
        /// ([`GridSpec::fixed_unit`]) or, once the cloth has spread past what that
        /// holds, a coarser one; `None` on float positions.
        fn position_unit(&self) -> Option<f64>
    );
    forward!(
        /// Force a SIMD level (for tests and benches). A level this CPU lacks is
        /// ignored.
        fn set_simd_level(&mut self, level: SimdLevel)
    );
    forward!(
        /// Change the wind (m/s), e.g. every step for gusts.
        fn set_wind(&mut self, wind: DVec3)
    );
    forward!(
        /// Change gravity (m/s²).
        fn set_gravity(&mut self, gravity: DVec3)
    );
    forward!(
        /// Advance by one step of `dt` seconds.
        fn step(&mut self, dt: f64)
    );
    forward!(
        /// Advance by `n` steps of `dt` seconds. On several threads the pool is
        /// entered once for all `n` steps, so prefer this to calling
        /// [`GridCloth::step`] in a loop.
        fn steps(&mut self, dt: f64, n: usize)
    );
    /// Advance by `n` steps of `dt` seconds in a gusty wind: step `i` blows
    /// `wind.at(start_time + i dt)`.
    pub fn steps_in_wind(&mut self, dt: f64, n: usize, start_time: f64, wind: &Wind) {
        match &mut self.0 {
            Kernels::Single(k) => k.steps_in_wind(dt, n, Some((start_time, wind))),
            Kernels::Double(k) => k.steps_in_wind(dt, n, Some((start_time, wind))),
        }
    }
    /// Sets the colliders besides the ground and the scene's sphere, as they are
    /// at simulated time `time` (s), the start of the next step: each step
    /// resolves their contact after the others' (`laws::collide`).
    pub fn set_colliders(&mut self, colliders: &[crate::sim::Collider], time: f64) {
        match &mut self.0 {
            Kernels::Single(k) => k.solids.set(colliders, time),
            Kernels::Double(k) => k.solids.set(colliders, time),
        }
    }
    forward!(
        /// Copy the positions (m) of particles `0..out.len()` into `out`.
        fn positions_into(&self, out: &mut [DVec3])
    );
    forward!(
        /// Copy the velocities (m/s) of particles `0..out.len()` into `out`.
        fn velocities_into(&self, out: &mut [DVec3])
    );
    forward!(
        /// Position Verlet's velocities of the last position update,
        /// `(x - x_prev) / h` (m/s), of particles `0..out.len()`; nothing for the
        /// other integrators.
        fn update_velocities_into(&self, out: &mut [DVec3])
    );
    forward!(
        /// Sets position Verlet's velocities of the last position update (m/s);
        /// ignored for the other integrators.
        fn set_update_velocities(&mut self, u: &[DVec3])
    );
    forward!(
        /// Floats per row in the arrays of [`GridCloth::raw_positions`] (width
        /// rounded up, plus ghost columns): particle `(r, c)` is at
        /// `r * row_stride() + c`.
        fn row_stride(&self) -> usize
    );
    forward!(
        /// The padded position arrays `[x, y, z]` in m, copied
        /// to f64 (exactly) for inspection (see [`GridCloth::row_stride`]).
        fn raw_positions(&self) -> [Vec<f64>; 3]
    );
    forward!(
        /// The padded velocity arrays `[vx, vy, vz]` in m/s, copied to f64.
        fn raw_velocities(&self) -> [Vec<f64>; 3]
    );
    forward!(
        /// The largest squared speed (m²/s²) and squared distance from `center`
        /// (m²) of any particle, infinite if anything is NaN: a cheap scan for the
        /// divergence check.
        fn extremes(&self, center: DVec3) -> (f64, f64)
    );
    forward!(
        /// Overwrite the state of particle `i` (ignored if out of range), e.g. for
        /// dragging it with the mouse.
        fn set_particle(&mut self, i: usize, position: DVec3, velocity: DVec3)
    );
    forward!(
        /// Overwrite positions and velocities of particles `0..len` from f64 vectors
        /// (extra entries are ignored, missing ones left unchanged).
        fn set_state(&mut self, positions: &[DVec3], velocities: &[DVec3])
    );
    forward!(
        /// Pin (`true`: inverse mass 0, velocity 0) or free particle `i`.
        fn set_pinned(&mut self, i: usize, pinned: bool)
    );
    forward!(
        /// Pairs of particles the last self-collision pass pushed apart.
        fn self_collision_contacts(&self) -> usize
    );
    forward!(
        /// Sets which springs and triangles are left: per particle in cloth order,
        /// bit `d < 6` for its spring in stencil direction `d`
        /// (`crate::sim::springs::STENCIL_DIRECTIONS`), bits 6 and 7 for the triangles
        /// `(a, b, d)` and `(b, e, d)` of the cell it is the top left corner of;
        /// `None`: the whole stencil and every triangle.
        fn set_springs_left(&mut self, bits: Option<Vec<u8>>)
    );
    forward!(
        /// The springs torn since the last call, as (particle in cloth order,
        /// stencil direction).
        fn take_torn(&mut self) -> Vec<(usize, usize)>
    );
}
