//! The grid kernel's state and scratch in padded structure-of-arrays form: 64-byte
//! aligned float buffers ([`Buf`]), rows padded to [`BLOCK`] floats plus ghost
//! columns, the per-step constants ([`Params`]) and each band's accumulator rows.

use super::frame::{self, Frame, FrameRule};
use super::{GridSpec, Real, SpringCoefficients};
use crate::sim::laws;
use crate::sim::{Ground, Integrator};

/// Rows are padded to a multiple of this many floats (the widest SIMD block).
pub(super) const BLOCK: usize = 16;

/// 16 floats, so that buffers and padded rows start on a cache line.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
pub(super) struct Line<E>(pub(super) [E; BLOCK]);

/// A zero-initialised, 64-byte aligned float buffer.
#[derive(Clone, Debug, Default)]
pub(super) struct Buf<E>(pub(super) Vec<Line<E>>);

impl<E: Real> Buf<E> {
    pub(super) fn zeros(n: usize) -> Self {
        Buf(vec![Line([E::ZERO; BLOCK]); n.div_ceil(BLOCK)])
    }
    pub(super) fn as_slice(&self) -> &[E] {
        // SAFETY: `Line<E>` is `repr(C)` around `[E; BLOCK]`, 64 or 128 bytes: a
        // multiple of its alignment, so there is no padding between lines.
        unsafe { std::slice::from_raw_parts(self.0.as_ptr().cast(), self.0.len() * BLOCK) }
    }
    pub(super) fn as_mut_slice(&mut self) -> &mut [E] {
        // SAFETY: as in `as_slice`.
        unsafe { std::slice::from_raw_parts_mut(self.0.as_mut_ptr().cast(), self.0.len() * BLOCK) }
    }
}

/// Sizes of the padded arrays.
#[derive(Clone, Copy, Debug)]
pub(super) struct Grid {
    /// Columns and rows of real particles.
    pub(super) w: usize,
    pub(super) h: usize,
    /// Columns covered by the SIMD blocks: `w` rounded up to [`BLOCK`].
    pub(super) nv: usize,
    /// Floats per row: `nv + BLOCK` (at least two ghost columns).
    pub(super) stride: usize,
}

impl Grid {
    pub(super) fn new(w: usize, h: usize) -> Self {
        let nv = w.next_multiple_of(BLOCK);
        Grid {
            w,
            h,
            nv,
            stride: nv + BLOCK,
        }
    }
    /// Floats per array: `h` rows and two ghost rows.
    pub(super) fn len(&self) -> usize {
        (self.h + 2) * self.stride
    }
    /// Array index of particle `p = r * w + c`.
    pub(super) fn index(&self, p: usize) -> usize {
        (p / self.w) * self.stride + p % self.w
    }
}

/// Per-step constants shared by all bands (f32, as the kernel uses them).
#[derive(Clone, Copy, Debug)]
pub(super) struct Params<E> {
    /// Per spring kind (0 structural, 1 bend, 2 shear): `k`, `k L`, `b`.
    pub(super) ks: [E; 3],
    pub(super) kls: [E; 3],
    pub(super) bs: [E; 3],
    pub(super) gravity: [E; 3],
    pub(super) wind: [E; 3],
    /// `ρ C_d / 12`: a third of the drag force with `A = |m| / 2`, over
    /// `air_scale²`.
    pub(super) drag: E,
    /// What the drag multiplies the relative air velocity by: 2^-32 with
    /// fixed-point positions, else 1. A triangle's `|v_rel|² |m|²` is in units⁴ m²/s²
    /// there, which overflowed float32 for a small cloth on a fine unit (a 2 x 2
    /// cloth on its tight unit, 2^-34 m, went non-finite in its first step in a 30
    /// m/s wind); the power of two changes no other result by a bit (the drag is
    /// `σ² v_rel (v_rel·m) m / (σ |v_rel| |m|)` times `drag / σ²`).
    pub(super) air_scale: E,
    pub(super) dt: E,
    /// `-c` of the air damping `-c v`.
    pub(super) neg_air: E,
    /// Ground height (as positions are stored), penalty stiffness per unit of
    /// depth and damping.
    pub(super) ground: [E; 3],
    /// Explicit Euler (positions move with the old velocity).
    pub(super) explicit: bool,
    /// `h/2` for position Verlet's velocity estimate `u + h/2 a`, else 0.
    pub(super) verlet_half_dt: E,
    /// Whether the velocity of the last position update `u` is its own array (Verlet).
    pub(super) verlet: bool,
    /// Whether positions are fixed point ([`Precision::Mixed`], [`frame`]).
    pub(super) fixed: bool,
    /// Metres per unit of the positions (1 unless fixed point), and units per metre.
    pub(super) unit: E,
    pub(super) inv_unit: E,
    /// Whether there is a ground.
    pub(super) ground_on: bool,
    /// Sphere centre (as positions are stored), radius and squared radius (in
    /// units), projected onto inside the fused step.
    pub(super) sphere: Option<([E; 3], E, E)>,
}

impl<E: Real> Params<E> {
    /// These constants with the step (`dt`, and Verlet's `h/2`) of `old`.
    pub(super) fn with_step_of(self, old: &Self) -> Self {
        Params {
            dt: old.dt,
            verlet_half_dt: old.verlet_half_dt,
            ..self
        }
    }

    /// Symplectic Euler with no air damping, ground or sphere in the step.
    pub(super) fn is_plain(&self) -> bool {
        !self.verlet
            && !self.explicit
            && self.neg_air == E::ZERO
            && !self.ground_on
            && self.sphere.is_none()
    }

    /// The constants of `spec` with positions in `frame` (the step `dt` is set by
    /// each run). Lengths are in the frame's units: a spring's `k` per unit, the
    /// drag's `ρ C_d` per unit².
    pub(super) fn of(spec: &GridSpec, frame: &Frame) -> Self {
        let hs = spec.spacing;
        // XPBD's springs are constraints (`constrain`), not forces: the fused pass
        // predicts with every other force.
        let xpbd = spec.integrator == Integrator::Xpbd;
        let frictional = laws::Contact {
            sphere: spec.sphere,
            ground: spec.ground,
            friction: spec.friction,
            dt: 0.0,
        }
        .has_friction();
        let force = |kind: SpringCoefficients| {
            if xpbd {
                SpringCoefficients::default()
            } else {
                kind
            }
        };
        // Index 0: structural (rest h), 1: bend (2h), 2: shear (h√2).
        let kinds = [
            (force(spec.structural), hs),
            (force(spec.bend), 2.0 * hs),
            (force(spec.shear), hs * std::f64::consts::SQRT_2),
        ];
        let unit = frame.unit;
        let air_scale = if frame.fixed { 2f64.powi(-32) } else { 1.0 };
        Params {
            ks: kinds.map(|(kind, _)| E::of(kind.k * unit)),
            kls: kinds.map(|(kind, rest)| E::of(kind.k * rest)),
            bs: kinds.map(|(kind, _)| E::of(kind.b)),
            gravity: spec.gravity.map(E::of),
            wind: spec.wind.map(E::of),
            drag: E::of(
                spec.air_density * spec.drag_coefficient / 12.0 * unit * unit
                    / (air_scale * air_scale),
            ),
            air_scale: E::of(air_scale),
            dt: E::ZERO,
            neg_air: E::of(-spec.air_damping),
            ground: ground_constants(spec.ground.as_ref(), frame),
            ground_on: spec.ground.is_some(),
            explicit: spec.integrator == Integrator::ExplicitEuler,
            verlet_half_dt: E::ZERO,
            verlet: spec.integrator == Integrator::Verlet,
            fixed: frame.fixed,
            unit: E::of(unit),
            inv_unit: E::of(1.0 / unit),
            // With a stretch limit or XPBD the sphere comes after them, in the
            // constraint pass, and so with friction (the sphere's or the ground's:
            // the pass resolves both, in the f64 engine's order).
            sphere: spec
                .sphere
                .filter(|_| spec.stretch_limit.is_none() && !xpbd && !frictional)
                .and_then(|s| frame.sphere(&s)),
        }
    }
}

/// A ground's height (as positions are stored), penalty stiffness per unit of
/// depth and damping in `frame`; with no ground, the lowest height.
pub(super) fn ground_constants<E: Real>(ground: Option<&Ground>, frame: &Frame) -> [E; 3] {
    match ground {
        Some(g) => [
            frame.ground_height(g.height),
            E::of(g.stiffness * frame.unit),
            E::of(g.damping),
        ],
        None => [E::LOWEST, E::ZERO, E::ZERO],
    }
}

/// Ring of accumulator rows: row `r` collects forces from rows `r-2` and `r-1`.
pub(super) const SLOTS: usize = 3;

/// Scratch of one row band: a ring of three rows of force accumulators (x, y, z).
#[derive(Clone, Debug)]
pub(super) struct Band<E> {
    /// First row of the band.
    pub(super) r0: usize,
    /// One past the last row.
    pub(super) r1: usize,
    /// `SLOTS` x 3 components x `nv` floats.
    pub(super) acc: Buf<E>,
    /// Per row, whether a free particle is near the sphere after the step, when
    /// the step gives the ground's friction ([`ContactRows::ground_friction_row`]):
    /// the rows the sphere's contact then resolves.
    pub(super) near_sphere: Vec<bool>,
}

impl<E: Real> Band<E> {
    pub(super) fn new(r0: usize, r1: usize, grid: &Grid) -> Self {
        Band {
            r0,
            r1,
            acc: Buf::zeros(SLOTS * 3 * grid.nv),
            near_sphere: vec![true; r1 - r0],
        }
    }
}

/// Split the rows into `n` bands of nearly equal size.
pub(super) fn make_bands<E: Real>(grid: &Grid, n: usize) -> Vec<Band<E>> {
    let n = n.clamp(1, grid.h);
    (0..n)
        .map(|i| Band::new(i * grid.h / n, (i + 1) * grid.h / n, grid))
        .collect()
}

/// Cloth state in padded structure-of-arrays form: positions as the kernel's
/// [`Frame`] stores them (floats in metres, or fixed point), velocities in m/s.
#[derive(Clone, Debug)]
pub(super) struct State<E> {
    pub(super) x: [Buf<E>; 3],
    pub(super) v: [Buf<E>; 3],
    /// Position Verlet's velocity of the last position update, `(x - x_prev) / h`
    /// (empty for the Euler methods, whose positions move with `v`).
    pub(super) u: [Buf<E>; 3],
}

impl<E: Real> State<E> {
    /// [`FrameRule::refit`] of these positions (real particles at the indices
    /// `rows`), stored in `frame`.
    pub(super) fn refit(
        &self,
        frame: &Frame,
        rule: FrameRule,
        rows: impl Iterator<Item = std::ops::Range<usize>>,
        time: f64,
    ) -> Option<Frame> {
        let state = (
            self.x.each_ref().map(Buf::as_slice),
            self.v.each_ref().map(Buf::as_slice),
        );
        rule.refit(frame, state, rows, time)
    }

    /// Re-encodes the positions (real particles at `rows`) from `frame` to `new`,
    /// which becomes the frame.
    pub(super) fn reframe(
        &mut self,
        frame: &mut Frame,
        new: Frame,
        rows: impl Iterator<Item = std::ops::Range<usize>> + Clone,
    ) {
        frame::reencode(frame, &new, self.x.each_mut().map(Buf::as_mut_slice), rows);
        *frame = new;
    }

    /// Every array, whole (ghost rows included), as [`Out`] rows from row 0.
    pub(super) fn rows(&mut self) -> Out<'_, E> {
        let State { x, v, u } = self;
        let [[x0, x1, x2], [v0, v1, v2], [u0, u1, u2]] =
            [x, v, u].map(|a| a.each_mut().map(Buf::as_mut_slice));
        Out([x0, x1, x2, v0, v1, v2, u0, u1, u2])
    }
}

/// Output rows of a band (or of several consecutive bands): `x`, `y`, `z`, `vx`,
/// `vy`, `vz`, and (Verlet only, else empty) `ux`, `uy`, `uz`, each starting at the
/// band's first row.
pub(super) struct Out<'a, E>(pub(super) [&'a mut [E]; 9]);

impl<'a, E> Out<'a, E> {
    /// The same arrays, borrowed for a shorter while.
    pub(super) fn reborrow(&mut self) -> Out<'_, E> {
        Out(self.0.each_mut().map(|a| &mut **a))
    }

    pub(super) fn split_at(self, at: usize) -> (Out<'a, E>, Out<'a, E>) {
        let mut lo: [&'a mut [E]; 9] = Default::default();
        let mut hi: [&'a mut [E]; 9] = Default::default();
        for (i, a) in self.0.into_iter().enumerate() {
            let at = at.min(a.len());
            (lo[i], hi[i]) = a.split_at_mut(at);
        }
        (Out(lo), Out(hi))
    }
}
