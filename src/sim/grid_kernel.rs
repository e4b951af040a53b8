//! The fast engine for regular grid cloths: a stencil kernel for damped springs,
//! gravity, per-triangle aero drag, air damping and a ground, stepped with
//! symplectic Euler, explicit Euler or position Verlet, then constrained by a sphere
//! collider and Provot's stretch limit. With XPBD the fused pass predicts with every
//! force but the springs, and the springs become distance constraints corrected
//! after it (`spring_passes`, in the f64 engine's colour classes).
//!
//! Units are SI (m, s, kg, N). The cloth is a `width x height` grid of particles,
//! `p = r * width + c` (row `r` from the top). Every particle is joined to its
//! 12-neighbour stencil: structural springs to `(r, c±1)`, `(r±1, c)` (rest `h`),
//! shear springs to `(r±1, c±1)` (rest `h√2`) and bend springs to `(r, c±2)`,
//! `(r±2, c)` (rest `2h`), with one stiffness `k` and damping `b` per kind. A spring
//! with `d = x_i - x_j`, `l = |d|`, `u = d / l` pushes particle `i` with
//! `f_i = -(k (l - L) + b u·(v_i - v_j)) u` and `j` with `-f_i`. Each cell
//! `(r, c)` gives the drag triangles `(a, b, d)` and `(b, e, d)` with `a = (r, c)`,
//! `b = (r, c+1)`, `d = (r+1, c)`, `e = (r+1, c+1)`; with `v_rel` the mean vertex
//! velocity minus the wind and `n` the unit normal of the current triangle of area
//! `A`, each vertex gets a third of `F = -½ ρ C_d A |v_rel| (v_rel·n) n`. Each
//! particle adds `-c v` (air damping) and, below the ground at depth `d`,
//! `k_c d - c_g v_y` upwards. These are the f64 engine's force terms
//! (`super::forces`), and the three integrators are its ones (`super::integrators`):
//! with `a = F / m + g`, symplectic Euler `v += h a; x += h v`, explicit Euler
//! `x += h v; v += h a`, and position Verlet written with the velocity of the last
//! position update `u = (x - x_prev) / h`: `u += h a; x += h u`, and the velocity
//! the forces see `v = u + h/2 a`. A particle with inverse mass 0 is pinned or held
//! (its velocity is 0). After the step, particles inside the sphere are projected
//! onto it (fused into the step when there is no stretch limit) and the stretch limit
//! runs a Gauss-Seidel pass in the f64 engine's colour order; a move `δ` adds `δ/h`
//! to the velocity, as in `super::constraints` (when it is the only spring pass,
//! the step runs it on each band's few rows as soon as it has stepped them, with
//! the same result). With friction, the colliders'
//! contact is the f64 engine's rule (`super::laws::Contact`) after the
//! step (`contact`); when nothing else comes after the step before it, it goes
//! into the step: the ground's friction to each row as soon as the row is stepped,
//! the sphere's to each band's few rows after them.
//!
//! # Precision
//! * Float32 positions lose the low bits of each move `x += h v`, and the lost bits
//!   times `k` are force noise that heats stiff cloth (0.15 J in 200 steps of a k =
//!   1e7 N/m cloth that the f64 engine keeps at 2e-6 J). Where that noise, summed
//!   over a particle's springs ([`Precision::needed`]), would pass 1% of gravity,
//!   positions are fixed point ([`Precision::Mixed`], [`frame`]): 32-bit integers
//!   in a unit chosen from the cloth's size, in a frame that follows the cloth. A
//!   spring's `d` is then exact before its conversion to float, and a move loses
//!   at most half a unit.
//! * The arithmetic is float32 when the noise of float32 spring lengths, about
//!   `2^-23 L` per spring, and of the positions, times `k / m` summed over a
//!   particle's springs, stays under 1% of gravity; otherwise the same code runs in
//!   float64 ([`Precision::Double`]), at half the lanes. `tests/engines/fast_engine.rs`
//!   shows both: float32 heats the stiff cloth, and the engine's choice follows
//!   the f64 engine's kinetic energy to 1% from k = 1e3 to 1e9 N/m.
//!
//! # How it is fast
//! * Structure of arrays (`x`, `y`, `z`, `vx`, `vy`, `vz`,
//!   inverse mass, and Verlet's `u`),
//!   rows padded to a multiple of 16 floats plus 16 ghost columns, and two ghost rows
//!   below the cloth: every loop runs over whole SIMD blocks with no scalar tail.
//!   Ghost particles are pinned at the origin; forces of springs or triangles that
//!   reach a ghost are zeroed before use.
//! * Each spring and each triangle is evaluated **once** (a plain per-particle
//!   gather evaluates every spring twice), in one fused pass per row `s` over SIMD
//!   blocks of columns: it computes the six springs that start on the row, `(s, c)`
//!   to `(s, c+1)`, `(s, c+2)`, `(s+1, c)`, `(s+1, c+1)`, `(s+2, c)` and `(s, c+1)`
//!   to `(s+1, c)`, and the two drag triangles of cell `(s, c)`; adds their forces
//!   on rows `s+1` and `s+2` to a ring of three accumulator rows; moves the forces
//!   between neighbours of the same row by one or two lanes (a lane shift carried
//!   from block to block); and, the force on `(s, c)` now being complete,
//!   integrates the particle at once. Positions and velocities are read from memory
//!   once per step (neighbour reads hit L1) and written once.
//! * The step reads the old state and writes the new one into a second set of
//!   arrays (ping-pong), so row bands can run on different threads: a band first
//!   recomputes the two spring rows above it, no thread writes memory another one
//!   reads, and the result is bit-identical for any number of threads.
//! * The loops are written once over a small SIMD trait with three versions:
//!   AVX-512 (16 lanes, `vrsqrt14ps` + one Newton step for `1/l`), AVX2 + FMA
//!   (8 lanes, `vrsqrtps` + one Newton step) and a portable one (`1/sqrt`, which
//!   the compiler vectorises for SSE2 or NEON); in float64, AVX-512 (8 lanes,
//!   `vrsqrt14pd` + one fourth-order step, within an ulp of `1/sqrt`: on an
//!   Intel core the divider had bound the float64 kernels), AVX2 (4 lanes, a
//!   correctly rounded `1/sqrt`) and the portable one. The
//!   best one this CPU has is picked at run time; the binary runs on any x86-64 or
//!   aarch64 machine.
//! * Nothing is allocated inside a step.
//!
//! # Where things are
//! * `spec`: [`GridSpec`] and the precision rule ([`Precision`]); `real`: the float
//!   types the kernels compute in and the SIMD levels ([`SimdLevel`]) their loops
//!   are compiled for.
//! * `state`: the padded arrays, the per-step constants and the bands' scratch;
//!   `kernel`: the kernel in one precision, its construction and state access;
//!   `step`: its step loop (the row pass, then `Kernel::constrain`);
//!   `tear`: the springs left and the tear pass; `cloth`: the public face,
//!   [`GridCloth`].
//! * `row`: the fused row pass, the step itself: springs, drag triangles,
//!   integration and the sphere, per SIMD block.
//! * `simd`: the vector operations the loops are written over, and `x86` their
//!   AVX2 and AVX-512 versions with the entry points compiled for them.
//! * `spring_passes` (XPBD's springs, the stretch limit), `contact` (the
//!   colliders with friction, also in the step): the passes after the step;
//!   [`lattice`]: the same
//!   physics on a 3-D lattice (the jelly cube).

use super::duo::Duo;
use frame::{Frame, FrameRule};

/// Grids with fewer particles than this run on the calling thread even when
/// several threads are allowed (threading costs more than it saves there).
pub const PARALLEL_MIN_PARTICLES: usize = 48 * 48;

/// Calls the same method on the kernel, whichever precision it has.
macro_rules! forward {
    ($(#[$doc:meta])* fn $name:ident(&self $(, $arg:ident: $ty:ty)*) $(-> $ret:ty)?) => {
        $(#[$doc])*
        pub fn $name(&self $(, $arg: $ty)*) $(-> $ret)? {
            match &self.0 {
                Kernels::Single(k) => k.$name($($arg),*),
                Kernels::Double(k) => k.$name($($arg),*),
            }
        }
    };
    ($(#[$doc:meta])* fn $name:ident(&mut self $(, $arg:ident: $ty:ty)*) $(-> $ret:ty)?) => {
        $(#[$doc])*
        pub fn $name(&mut self $(, $arg: $ty)*) $(-> $ret)? {
            match &mut self.0 {
                Kernels::Single(k) => k.$name($($arg),*),
                Kernels::Double(k) => k.$name($($arg),*),
            }
        }
    };
}

// After `forward!`, which the facade and the lattice kernel use.
mod cloth;
mod colliders;
#[cfg(test)]
mod conformance;
mod contact;
pub mod frame;
mod kernel;
pub mod lattice;
mod real;
mod row;
mod simd;
mod spec;
mod spring_passes;
mod state;
mod step;
mod tear;
#[cfg(target_arch = "x86_64")]
mod x86;

pub use cloth::GridCloth;
pub use real::SimdLevel;
pub(crate) use spec::SpringNoise;
pub use spec::{GridSpec, Precision, SpringCoefficients, stencil_counts};

use contact::{ContactRows, RowsPass};
use kernel::{Kernel, runaway_scan};
use real::Real;
use row::{
    Ctx, Particle, StepLanes, band_rows, integrate, project_out_of_sphere, row_portable,
    row_variant, run_bands, run_two_bands, spring,
};
use simd::{Portable, Simd};
use spec::xpbd_step;
use spring_passes::{SpringPass, SpringRule, SweepLines, spring_sweep, step_start};
use state::{BLOCK, Band, Buf, Grid, Out, Params, SLOTS, State, ground_constants, make_bands};
use step::any_faster;
use tear::{Stencil, Torn, row_may_tear};
