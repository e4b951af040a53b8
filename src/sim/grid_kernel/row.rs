//! The fused row pass: each row's springs and drag triangles evaluated once, the
//! forces carried to the rows below and the lanes beside, and each particle
//! integrated as soon as its force is complete (see the module doc of
//! [`super`]).

use std::ops::Range;

use super::contact::{ContactRows, RowsPass};
use super::simd::{Vector, align_frame};
use super::spring_passes::SpringPass;
use super::{BLOCK, Band, Duo, Grid, Out, Params, Portable, Real, SLOTS, Simd, SimdLevel};
use crate::sim::laws::{self, Method, SpringCoefficients, V3};

/// Read-only inputs of a step.
pub(super) struct Ctx<'a, E> {
    pub(super) grid: Grid,
    pub(super) p: Params<E>,
    /// Positions as the kernel's [`super::Frame`] stores them.
    pub(super) x: [&'a [E]; 3],
    pub(super) v: [&'a [E]; 3],
    /// Verlet's update velocities (empty for the Euler methods).
    pub(super) u: [&'a [E]; 3],
    pub(super) inv_mass: &'a [E],
    pub(super) col_mask: &'a [E],
    /// With springs missing, the masks of the springs a block evaluates and of its
    /// triangles (see [`block`]).
    pub(super) torn: Option<[&'a [E]; 8]>,
    pub(super) drag: bool,
    pub(super) simd: SimdLevel,
    /// The colliders' contact, resolved on each band's rows right after them (in
    /// the same hand-over) when it is the first thing after the step
    /// ([`super::Kernel::contact_in_step`]); the ground's friction on each row
    /// right after the row ([`ContactRows::ground_friction_row`]).
    pub(super) contact: Option<&'a ContactRows<'a, E>>,
    /// The spring pass after the step, run on each band's rows as soon as they
    /// are stepped, when it is the only thing after the step
    /// ([`super::Kernel::spring_pass_in_step`]).
    pub(super) springs: Option<&'a SpringPass<'a, E>>,
    /// Rows stepped before the contact or the spring pass runs on them: few
    /// enough that they are still in the core's cache.
    pub(super) rows_in_cache: usize,
}

/// One band of the step, and the contact of its rows if the step has it (with
/// the ground's friction given in the step, that of the rows with a particle near
/// the sphere) or the spring pass after the step, each on a few rows at a time as
/// soon as they are stepped ([`Ctx::rows_in_cache`]).
fn run_band<E: Real>(ctx: &Ctx<E>, band: &mut Band<E>, mut out: Out<E>) {
    if ctx.contact.is_none() && ctx.springs.is_none() {
        E::band_dispatch(ctx, band, out, band.r0..band.r1);
        return;
    }
    let mut springs = ctx.springs.map(|pass| pass.band(band.r0, band.r1));
    let mut r = band.r0;
    while r < band.r1 {
        let end = (r + ctx.rows_in_cache).min(band.r1);
        E::band_dispatch(ctx, band, out.reborrow(), r..end);
        if let Some(contact) = ctx.contact {
            if contact.friction_in_rows {
                let near = &band.near_sphere;
                let rows = (r..end).filter(|r| near[r - band.r0]);
                contact.resolve(&mut out, band.r0, rows);
            } else {
                contact.resolve(&mut out, band.r0, r..end);
            }
        }
        if let Some(springs) = &mut springs {
            springs.advance(&mut out, end);
        }
        r = end;
    }
    if let Some(springs) = &mut springs {
        springs.finish(&mut out);
    }
}

/// Run the bands, splitting the output rows among them; in parallel with
/// `rayon::join` (inside the caller's pool) when `parallel`.
pub(super) fn run_bands<E: Real>(ctx: &Ctx<E>, bands: &mut [Band<E>], out: Out<E>, parallel: bool) {
    if bands.len() == 1 {
        run_band(ctx, &mut bands[0], out);
        return;
    }
    let mid = bands.len() / 2;
    let at = (bands[mid].r0 - bands[0].r0) * ctx.grid.stride;
    let (lo, hi) = bands.split_at_mut(mid);
    let (out_lo, out_hi) = out.split_at(at);
    if parallel {
        rayon::join(
            || run_bands(ctx, lo, out_lo, true),
            || run_bands(ctx, hi, out_hi, true),
        );
    } else {
        run_bands(ctx, lo, out_lo, false);
        run_bands(ctx, hi, out_hi, false);
    }
}

/// The two bands of `bands`, the second handed to the thread serving `duo`.
pub(super) fn run_two_bands<E: Real>(ctx: &Ctx<E>, bands: &mut [Band<E>], out: Out<E>, duo: &Duo) {
    let at = (bands[1].r0 - bands[0].r0) * ctx.grid.stride;
    let (first, second) = bands.split_at_mut(1);
    let (out_first, out_second) = out.split_at(at);
    duo.fork_once(
        || run_band(ctx, &mut second[0], out_second),
        || run_band(ctx, &mut first[0], out_first),
    );
}

/// One row of the fused pass in one mode ([`row_step`]'s constants: drag, whether
/// the row is integrated, plain, fixed-point positions), for one SIMD level and
/// precision.
/// Each level compiles each mode as a function of its own: in one function
/// holding all twelve, how each came out moved with unrelated changes (the plain
/// cloth's step once ran 1.3x slower after code moved between files).
pub(super) trait RowMode<E> {
    /// [`row_step`] in this mode.
    fn row<const DRAG: bool, const OWN: bool, const PLAIN: bool, const FIXED: bool>(
        self,
        ctx: &Ctx<E>,
        band: &mut Band<E>,
        row: usize,
        out: &mut Out<E>,
        lo: usize,
    );
}

/// [`RowMode`] with the portable lanes.
#[derive(Clone, Copy)]
struct PortableRows;

impl<E: Real> RowMode<E> for PortableRows {
    #[inline(never)]
    fn row<const DRAG: bool, const OWN: bool, const PLAIN: bool, const FIXED: bool>(
        self,
        ctx: &Ctx<E>,
        band: &mut Band<E>,
        row: usize,
        out: &mut Out<E>,
        lo: usize,
    ) {
        row_step::<_, DRAG, OWN, PLAIN, FIXED>(Portable::<E>::default(), ctx, band, row, out, lo);
    }
}

/// One row with the portable lanes.
pub(super) fn row_portable<E: Real>(
    ctx: &Ctx<E>,
    band: &mut Band<E>,
    row: usize,
    out: &mut Out<E>,
    lo: usize,
    own: bool,
) {
    row_variant(PortableRows, ctx, band, row, out, lo, own);
}

/// [`row_step`] in the mode for the scene (drag, plain, fixed point), integrating
/// the row if `own`.
#[inline(always)]
pub(super) fn row_variant<E: Real>(
    mode: impl RowMode<E>,
    ctx: &Ctx<E>,
    band: &mut Band<E>,
    row: usize,
    out: &mut Out<E>,
    lo: usize,
    own: bool,
) {
    // A plain cloth (symplectic Euler, no air damping, ground or sphere) gets a
    // version of the step without them.
    let plain = ctx.p.is_plain();
    macro_rules! modes {
        ($fixed:literal) => {
            match (ctx.drag, own, plain) {
                (true, true, true) => mode.row::<true, true, true, $fixed>(ctx, band, row, out, lo),
                (true, true, false) => {
                    mode.row::<true, true, false, $fixed>(ctx, band, row, out, lo)
                }
                (false, true, true) => {
                    mode.row::<false, true, true, $fixed>(ctx, band, row, out, lo)
                }
                (false, true, false) => {
                    mode.row::<false, true, false, $fixed>(ctx, band, row, out, lo)
                }
                (true, false, _) => mode.row::<true, false, true, $fixed>(ctx, band, row, out, lo),
                (false, false, _) => {
                    mode.row::<false, false, true, $fixed>(ctx, band, row, out, lo)
                }
            }
        };
    }
    if ctx.p.fixed {
        modes!(true)
    } else {
        modes!(false)
    }
}

/// The rows `rows` of one band: from the band's first row, prime the
/// accumulator ring with the two rows above the band; then compute and integrate
/// the rows one by one (the ring carries what a row adds to the next two into
/// the band's next call). Each row is one call of `row`, compiled for the chosen
/// SIMD level.
pub(super) fn band_rows<E: Real>(
    ctx: &Ctx<E>,
    band: &mut Band<E>,
    mut out: Out<E>,
    rows: Range<usize>,
    row: impl Fn(&Ctx<E>, &mut Band<E>, usize, &mut Out<E>, usize, bool),
) {
    debug_assert!(band.r0 <= rows.start && rows.end <= band.r1);
    if rows.start == band.r0 {
        // Rows 0 and 1 get nothing from rows above the cloth.
        if band.r0 < 2 {
            band.acc.as_mut_slice().fill(E::ZERO);
        }
        for r in band.r0.saturating_sub(2)..band.r0 {
            row(ctx, band, r, &mut out, 0, false);
        }
    }
    let st = ctx.grid.stride;
    for r in rows {
        row(ctx, band, r, &mut out, (r - band.r0) * st, true);
    }
}

/// A particle's position (as stored) and velocity, one per lane.
pub(super) type Particle<'a, V> = (&'a [V; 3], &'a [V; 3]);

/// `a - b` of two stored coordinates, in the positions' units: an exact integer
/// difference converted to float for fixed point (`FIXED`), else a float one.
#[inline(always)]
pub(super) fn difference<S: Simd, const FIXED: bool>(s: S, a: S::V, b: S::V) -> S::V {
    if FIXED {
        s.fixed_sub(a, b)
    } else {
        s.sub(a, b)
    }
}

/// The stored coordinate `x` moved by `scale t` units (rounded to a whole unit
/// for fixed point).
#[inline(always)]
pub(super) fn moved<S: Simd, const FIXED: bool>(s: S, x: S::V, scale: S::V, t: S::V) -> S::V {
    if FIXED {
        s.fixed_add(x, s.mul(scale, t))
    } else {
        laws::advanced(Vector(s, x), Vector(s, scale), Vector(s, t)).1
    }
}

/// Forces on the first ends of springs `i`-`j`, one per lane, times `mask` (if
/// any): `f = (k L / l - k - b (d·dv) / l²) d = ((-b (d·dv) / l + k L) / l - k) d`
/// with `d = x_i - x_j` ([`difference`]: accurate to its own size with fixed-point
/// positions, not only to that of the positions) in the positions' units,
/// `dv = v_i - v_j`. `kind` is `[-k, k L, -b]` (`k` per unit). Returns the
/// forces and `d`.
#[inline(always)]
pub(super) fn spring<S: Simd, const FIXED: bool>(
    s: S,
    (xi, vi): Particle<S::V>,
    (xj, vj): Particle<S::V>,
    kind: [S::V; 3],
    mask: Option<S::V>,
) -> ([S::V; 3], [S::V; 3]) {
    let d = std::array::from_fn(|a| difference::<S, FIXED>(s, xi[a], xj[a]));
    spring_of(s, d, (vi, vj), kind, mask)
}

/// [`spring`] of the vector `d = x_i - x_j` as already computed
/// ([`laws::spring_factor`]).
#[inline(always)]
fn spring_of<S: Simd>(
    s: S,
    d: [S::V; 3],
    (vi, vj): (&[S::V; 3], &[S::V; 3]),
    [nk, kl, nb]: [S::V; 3],
    mask: Option<S::V>,
) -> ([S::V; 3], [S::V; 3]) {
    let dv = lanes3(s, std::array::from_fn(|a| s.sub(vi[a], vj[a])));
    let c = SpringCoefficients {
        neg_k: Vector(s, nk),
        k_rest: Vector(s, kl),
        neg_b: Vector(s, nb),
    };
    let a = laws::spring_factor(lanes3(s, d), dv, c).1;
    let a = match mask {
        Some(m) => s.mul(a, m),
        None => a,
    };
    ([s.mul(a, d[0]), s.mul(a, d[1]), s.mul(a, d[2])], d)
}

/// Three vectors as the laws' [`V3`] of [`Vector`]s.
#[inline(always)]
pub(super) fn lanes3<S: Simd>(s: S, v: [S::V; 3]) -> V3<Vector<S>> {
    V3 {
        x: Vector(s, v[0]),
        y: Vector(s, v[1]),
        z: Vector(s, v[2]),
    }
}

/// The components of a [`V3`] of [`Vector`]s.
#[inline(always)]
fn unlanes3<S: Simd>(v: V3<Vector<S>>) -> [S::V; 3] {
    [v.x.1, v.y.1, v.z.1]
}

/// Drag on each vertex of a triangle with edges `e1 = q - p` and `e2 = d - p` (or
/// both negated) and relative air velocity `vr`, times `mask`
/// ([`laws::drag_factor`] of `m = e1 × e2`). The edges are the springs' `d` (or
/// their difference), accurate to their own size as those are. Returns the drag
/// as `a m`: `a` and `m`, for the sums that take it to fuse its product.
#[inline(always)]
fn triangle<S: Simd>(
    s: S,
    [e1, e2]: [[S::V; 3]; 2],
    vr: V3<Vector<S>>,
    neg_drag: S::V,
    mask: Option<S::V>,
) -> (S::V, [S::V; 3]) {
    let m = lanes3(s, e1).cross(lanes3(s, e2));
    let a = laws::drag_factor(m, vr, Vector(s, neg_drag)).1;
    let a = match mask {
        Some(m) => s.mul(a, m),
        None => a,
    };
    (a, unlanes3(m))
}

/// Splatted constants and raw pointers of one row, shared by its blocks.
struct RowKernel<S: Simd> {
    s: S,
    /// What integrating a particle needs.
    step: StepLanes<S>,
    kinds: [[S::V; 3]; 3],
    /// The wind and a third, both scaled as the kernel's velocities are.
    wind: V3<Vector<S>>,
    third: S::V,
    neg_drag: S::V,
    down: S::V,
    down2: S::V,
    x: [*const S::E; 3],
    v: [*const S::E; 3],
    inv_mass: *const S::E,
    col_mask: *const S::E,
    /// [`Ctx::torn`]'s masks.
    torn: Option<[*const S::E; 8]>,
    acc: *mut S::E,
    /// Array offsets of the rows `row`, `row + 1`, `row + 2`.
    b: [usize; 3],
    /// Accumulator offsets of the rows `row`, `row + 1`, `row + 2`.
    a: [usize; 3],
    nv: usize,
    stride: usize,
    lo: usize,
}

/// [`integrate`]'s methods: a constant of each compiled step, with whether it has
/// a ground, so that a block's step is one stretch of code without tests. With
/// tests of flags per axis and block, the drape at 128 x 128 ran 88.9
/// instructions per particle-step, air damping 62.0 and Verlet in the wind 81.0;
/// so 84.6, 56.0 and 78.1 (valgrind, AVX2).
pub(super) const SYMPLECTIC: u8 = 0;
pub(super) const EXPLICIT: u8 = 1;
pub(super) const VERLET: u8 = 2;

/// Runs `$run!(METHOD, GROUND)`, a macro of the caller's that takes the step's
/// method and ground as constants, with those of `$step` ([`StepLanes`]), or the
/// plain step's where `$plain`: the one choice the row pass and the lattice make
/// before their blocks.
macro_rules! with_step_constants {
    ($plain:expr, $step:expr, $run:ident) => {
        match ($step.method, $step.ground_on) {
            _ if $plain => $run!(SYMPLECTIC, false),
            (SYMPLECTIC, false) => $run!(SYMPLECTIC, false),
            (SYMPLECTIC, true) => $run!(SYMPLECTIC, true),
            (EXPLICIT, false) => $run!(EXPLICIT, false),
            (EXPLICIT, true) => $run!(EXPLICIT, true),
            (_, false) => $run!(VERLET, false),
            (_, true) => $run!(VERLET, true),
        }
    };
}
pub(super) use with_step_constants;

/// Splatted constants and raw pointers for [`integrate`] and
/// [`project_out_of_sphere`]: the step of a particle under its force, shared by the
/// grid's rows and the lattice's blocks ([`super::lattice`]).
pub(super) struct StepLanes<S: Simd> {
    pub(super) s: S,
    pub(super) gravity: [S::V; 3],
    pub(super) dt: S::V,
    /// The step in units of the positions per m/s: `h / unit`.
    pub(super) dt_units: S::V,
    pub(super) zero: S::V,
    pub(super) one: S::V,
    /// `-c` (air damping), ground height, `k_c` (per unit), damping, `h/2`
    /// (Verlet).
    pub(super) neg_air: S::V,
    pub(super) ground: [S::V; 3],
    pub(super) verlet_half_dt: S::V,
    /// Velocity per unit moved in a step: `unit / h`.
    pub(super) inv_dt: S::V,
    /// Sphere centre, radius and squared radius (in units; when the step projects
    /// onto it).
    pub(super) sphere: Option<SphereLanes<S::V>>,
    /// [`SYMPLECTIC`], [`EXPLICIT`] or [`VERLET`].
    pub(super) method: u8,
    /// Whether the step has a ground.
    pub(super) ground_on: bool,
    /// Verlet's update velocities (the velocities for the other methods).
    pub(super) u: [*const S::E; 3],
    /// [`Out`]'s nine arrays.
    pub(super) out: [*mut S::E; 9],
}

impl<S: Simd> StepLanes<S> {
    /// The lanes of `p`, reading Verlet's `u` from `u` (else from `v`) and writing
    /// to `out`. (Inlined: called once a row, it cost the drape 3% as a call.)
    #[inline(always)]
    pub(super) fn new(
        s: S,
        p: &Params<S::E>,
        u: [&[S::E]; 3],
        v: [&[S::E]; 3],
        out: &mut Out<S::E>,
    ) -> Self {
        StepLanes {
            s,
            gravity: p.gravity.map(|w| s.splat(w)),
            dt: s.splat(p.dt),
            dt_units: s.splat(p.dt * p.inv_unit),
            zero: s.splat(S::E::ZERO),
            one: s.splat(S::E::ONE),
            neg_air: s.splat(p.neg_air),
            ground: p.ground.map(|g| s.splat(g)),
            verlet_half_dt: s.splat(p.verlet_half_dt),
            inv_dt: s.splat(p.unit / p.dt),
            sphere: p
                .sphere
                .map(|(c, r, r2)| (c.map(|c| s.splat(c)), s.splat(r), s.splat(r2))),
            method: if p.verlet {
                VERLET
            } else if p.explicit {
                EXPLICIT
            } else {
                SYMPLECTIC
            },
            ground_on: p.ground_on,
            // Without Verlet's own array the update velocity is the velocity.
            u: if p.verlet { u } else { v }.map(<[S::E]>::as_ptr),
            out: out.0.each_mut().map(|o| o.as_mut_ptr()),
        }
    }
}

/// A sphere collider's centre, radius and squared radius, splatted.
type SphereLanes<V> = ([V; 3], V, V);

/// One row `row` of the cloth, in SIMD blocks of columns: evaluate the six springs
/// that start on each particle of the row, `(row, c)` to `(row, c+1)`, `(row, c+2)`,
/// `(row+1, c)`, `(row+1, c+1)`, `(row+2, c)`, and `(row, c+1)` to `(row+1, c)`,
/// and (with `DRAG`) the two triangles of cell `(row, c)`. Forces on the particles
/// of rows `row+1` and `row+2` are added to their accumulators in the ring; the
/// force on a particle of `row` is its accumulator (from the two rows above) plus
/// the forces just computed, and with `OWN` the particle is integrated at once:
/// `v' = v + dt (f / m + g)` (0 when pinned), `x' = x + dt v'`, written to `out`
/// at `lo + c`. Forces between columns of the same row reach the neighbouring
/// lanes through `shift1`/`shift2`, carried from block to block. Blocks that touch
/// the last two columns, and the last two rows, mask the springs and triangles
/// that reach ghost particles.
#[inline(always)]
pub(super) fn row_step<
    S: Simd,
    const DRAG: bool,
    const OWN: bool,
    const PLAIN: bool,
    const FIXED: bool,
>(
    s: S,
    ctx: &Ctx<S::E>,
    band: &mut Band<S::E>,
    row: usize,
    out: &mut Out<S::E>,
    lo: usize,
) {
    let g = ctx.grid;
    let nv = g.nv;
    let acc = band.acc.as_mut_slice();
    let b = [row * g.stride, (row + 1) * g.stride, (row + 2) * g.stride];
    // Everything read or written by `block` lies inside these bounds.
    assert!(S::LANES <= BLOCK && nv.is_multiple_of(S::LANES) && acc.len() == SLOTS * 3 * nv);
    assert!(b[2] + nv + 2 <= g.len() && ctx.inv_mass.len() == g.len());
    assert!(ctx.col_mask.len() >= g.stride + nv);
    for mask in ctx.torn.iter().flatten() {
        // Read up to one past the row's last block (the other diagonal's).
        assert!(mask.len() > b[0] + nv);
    }
    for a in ctx.x.iter().chain(&ctx.v) {
        assert_eq!(a.len(), g.len());
    }
    let verlet = ctx.p.verlet;
    if verlet {
        for a in &ctx.u {
            assert_eq!(a.len(), g.len());
        }
    }
    if OWN {
        for o in &out.0[..if verlet { 9 } else { 6 }] {
            assert!(lo + nv <= o.len());
        }
    }
    let slot = |r: usize| (r % SLOTS) * 3 * nv;
    let p = &ctx.p;
    let kind = |i: usize| [s.splat(-p.ks[i]), s.splat(p.kls[i]), s.splat(-p.bs[i])];
    let k = RowKernel {
        s,
        step: StepLanes::new(s, p, ctx.u, ctx.v, out),
        kinds: [kind(0), kind(1), kind(2)],
        wind: lanes3(s, p.wind.map(|w| s.splat(w * p.air_scale))),
        third: s.splat(S::E::of(1.0 / 3.0) * p.air_scale),
        neg_drag: s.splat(-p.drag),
        down: s.splat(if row + 1 < g.h { S::E::ONE } else { S::E::ZERO }),
        down2: s.splat(if row + 2 < g.h { S::E::ONE } else { S::E::ZERO }),
        x: ctx.x.map(<[S::E]>::as_ptr),
        v: ctx.v.map(<[S::E]>::as_ptr),
        inv_mass: ctx.inv_mass.as_ptr(),
        col_mask: ctx.col_mask.as_ptr(),
        torn: ctx.torn.map(|t| t.map(<[S::E]>::as_ptr)),
        acc: acc.as_mut_ptr(),
        b,
        a: [slot(row), slot(row + 1), slot(row + 2)],
        nv,
        stride: g.stride,
        lo,
    };
    // Blocks from `c_mask` on hold a column >= w - 2; near the bottom all blocks
    // reach ghost rows; with springs missing every block is masked.
    let c_mask = if row + 2 < g.h && ctx.torn.is_none() {
        (g.w.saturating_sub(2) / S::LANES) * S::LANES
    } else {
        0
    };
    align_frame();
    let mut carry = [[k.step.zero; 3]; 3];
    let mut c = 0;
    // The blocks of the row, with the step's method and ground chosen once for the
    // row ([`integrate`]).
    macro_rules! blocks {
        ($method:ident, $ground:literal) => {{
            while c < c_mask {
                // SAFETY: c < nv, a multiple of LANES; bounds asserted above.
                unsafe {
                    block::<S, DRAG, OWN, false, PLAIN, FIXED, { $method }, $ground>(
                        &k, c, &mut carry,
                    )
                };
                c += S::LANES;
            }
            while c < nv {
                // SAFETY: as above.
                unsafe {
                    block::<S, DRAG, OWN, true, PLAIN, FIXED, { $method }, $ground>(
                        &k, c, &mut carry,
                    )
                };
                c += S::LANES;
            }
        }};
    }
    with_step_constants!(PLAIN, k.step, blocks);
    if let Some(contact) = ctx.contact.filter(|c| OWN && c.friction_in_rows) {
        band.near_sphere[row - band.r0] =
            contact.ground_friction_row::<S, FIXED>(s, out, (b[0], lo), nv);
    }
}

/// Columns `c .. c + LANES` of a row (see [`row_step`]): the block's springs and
/// drag triangles ([`cell_forces`]), then each axis's forces carried and its
/// particles stepped ([`block_axis`]).
///
/// # Safety
/// `c + LANES <= nv`, and the pointers and offsets of `k` are valid as asserted in
/// [`row_step`].
#[inline(always)]
unsafe fn block<
    S: Simd,
    const DRAG: bool,
    const OWN: bool,
    const MASK: bool,
    const PLAIN: bool,
    const FIXED: bool,
    const METHOD: u8,
    const GROUND: bool,
>(
    k: &RowKernel<S>,
    c: usize,
    carry: &mut [[S::V; 3]; 3],
) {
    let s = k.s;
    // SAFETY: offsets are inside the arrays (caller's contract).
    let ld = |ptr: [*const S::E; 3], i: usize| unsafe {
        [
            s.load(ptr[0].add(i)),
            s.load(ptr[1].add(i)),
            s.load(ptr[2].add(i)),
        ]
    };
    let [b0, b1, b2] = k.b;
    let p00 = (&ld(k.x, b0 + c), &ld(k.v, b0 + c));
    let p01 = (&ld(k.x, b0 + c + 1), &ld(k.v, b0 + c + 1));
    let p02 = (&ld(k.x, b0 + c + 2), &ld(k.v, b0 + c + 2));
    let p10 = (&ld(k.x, b1 + c), &ld(k.v, b1 + c));
    let p11 = (&ld(k.x, b1 + c + 1), &ld(k.v, b1 + c + 1));
    let p20 = (&ld(k.x, b2 + c), &ld(k.v, b2 + c));
    // SAFETY: as above.
    let masks = if MASK {
        Some(unsafe { block_masks(k, c) })
    } else {
        None
    };
    let forces = cell_forces::<S, DRAG, FIXED>(k, [p00, p01, p02, p10, p11, p20], masks);
    // SAFETY: as above.
    let w = if OWN {
        unsafe { s.load(k.inv_mass.add(b0 + c)) }
    } else {
        k.step.zero
    };
    // Each axis in turn, written out where the level asks it (`Simd::UNROLL_AXES`).
    macro_rules! axis {
        ($i:expr) => {
            // SAFETY: as above.
            unsafe {
                block_axis::<S, DRAG, OWN, PLAIN, FIXED, METHOD, GROUND>(
                    k, c, $i, &forces, carry, w, p00,
                )
            }
        };
    }
    if S::UNROLL_AXES && !PLAIN {
        axis!(0);
        axis!(1);
        axis!(2);
    } else {
        for i in 0..3 {
            axis!(i);
        }
    }
    if OWN && !PLAIN && k.step.sphere.is_some() {
        // SAFETY: as above.
        unsafe { project_out_of_sphere::<S, FIXED>(&k.step, k.lo + c, w) };
    }
}

/// The masks of a block's springs right, two right, down, down-right, the other
/// diagonal and two down, and of its two triangles: the torn cloth's, else the
/// columns' and rows' that have them.
///
/// # Safety
/// As for [`block`].
#[inline(always)]
unsafe fn block_masks<S: Simd>(k: &RowKernel<S>, c: usize) -> [S::V; 8] {
    let s = k.s;
    match k.torn {
        // SAFETY: as above (the other diagonal's mask is read one column on).
        Some(t) => unsafe {
            std::array::from_fn(|m| s.load(t[m].add(k.b[0] + c + usize::from(m == 4))))
        },
        None => {
            // SAFETY: as above.
            let (m1, m2) = unsafe {
                (
                    s.load(k.col_mask.add(c)),
                    s.load(k.col_mask.add(k.stride + c)),
                )
            };
            let m1d = s.mul(m1, k.down);
            [m1, m2, k.down, m1d, m1d, k.down2, m1d, m1d]
        }
    }
}

/// The forces on a block's particles of the springs that start on them and the
/// drag of the triangles of their cells (see [`cell_forces`]).
struct CellForces<V> {
    /// The springs right, two right, down, down-right, the other diagonal
    /// (down-left from the next column) and two down.
    right: [V; 3],
    right2: [V; 3],
    down: [V; 3],
    down_right: [V; 3],
    anti: [V; 3],
    down2: [V; 3],
    /// The drag `(a, m)` of the triangles `(a, b, d)` and `(b, e, d)`.
    drag: [(V, [V; 3]); 2],
}

/// [`CellForces`] of the particles `[p00, p01, p02, p10, p11, p20]` (row and
/// column offsets from the block's own) with the block's `masks`.
#[inline(always)]
fn cell_forces<S: Simd, const DRAG: bool, const FIXED: bool>(
    k: &RowKernel<S>,
    [p00, p01, p02, p10, p11, p20]: [Particle<S::V>; 6],
    masks: Option<[S::V; 8]>,
) -> CellForces<S::V> {
    let s = k.s;
    let zero = k.step.zero;
    let mask = |m: usize| masks.map(|masks| masks[m]);
    let [structural, bend, shear] = k.kinds;
    let (right, e_right) = spring::<S, FIXED>(s, p00, p01, structural, mask(0));
    let (right2, _) = spring::<S, FIXED>(s, p00, p02, bend, mask(1));
    let (down, e_down) = spring::<S, FIXED>(s, p00, p10, structural, mask(2));
    let (down_right, e_diagonal) = spring::<S, FIXED>(s, p00, p11, shear, mask(3));
    // The other diagonal: with fixed-point positions, `x_01 - x_10` as the down
    // spring's vector less the right one's, rather than as a difference of
    // positions, which costs a conversion more. Exact while the three are under
    // 2^24 units; else rounded to its own size, as a difference is.
    let (anti, e_anti) = if FIXED {
        let d = std::array::from_fn(|i| s.sub(e_down[i], e_right[i]));
        spring_of(s, d, (p01.1, p10.1), shear, mask(4))
    } else {
        spring::<S, FIXED>(s, p01, p10, shear, mask(4))
    };
    let (down2, _) = spring::<S, FIXED>(s, p00, p20, bend, mask(5));
    let drag = if DRAG {
        // Relative air velocity of (a, b, d) and (b, e, d), which share `b + d`.
        let [va, vb, vd, ve] = [p00.1, p01.1, p10.1, p11.1].map(|v| lanes3(s, *v));
        let third = Vector(s, k.third);
        let vr1 = laws::air_velocity([va, vb, vd], k.wind, third);
        let vr2 = laws::air_velocity([ve, vb, vd], k.wind, third);
        [
            // (a, b, d): edges b - a and d - a, the springs right and down negated.
            triangle(s, [e_right, e_down], vr1, k.neg_drag, mask(6)),
            // (b, e, d): edges e - b and d - b negated, b - e = (a - e) - (a - b)
            // and the other diagonal.
            triangle(
                s,
                [
                    std::array::from_fn(|i| s.sub(e_diagonal[i], e_right[i])),
                    e_anti,
                ],
                vr2,
                k.neg_drag,
                mask(7),
            ),
        ]
    } else {
        [(zero, [zero; 3]); 2]
    };
    CellForces {
        right,
        right2,
        down,
        down_right,
        anti,
        down2,
        drag,
    }
}

/// Component `i` of a block's forces: those carried to the lanes beside and the
/// rows below, and (`OWN`) the block's particles, whose force is now complete,
/// stepped ([`integrate`]).
///
/// # Safety
/// As for [`block`].
#[inline(always)]
unsafe fn block_axis<
    S: Simd,
    const DRAG: bool,
    const OWN: bool,
    const PLAIN: bool,
    const FIXED: bool,
    const METHOD: u8,
    const GROUND: bool,
>(
    k: &RowKernel<S>,
    c: usize,
    i: usize,
    f: &CellForces<S::V>,
    carry: &mut [[S::V; 3]; 3],
    w: S::V,
    p00: Particle<S::V>,
) {
    let s = k.s;
    let zero = k.step.zero;
    let nv = k.nv;
    let CellForces {
        right,
        right2,
        down: d,
        down_right: dr,
        anti,
        down2: d2,
        drag: [(a1, m1), (a2, m2)],
    } = f;
    let (a1, a2) = (*a1, *a2);
    // Terms for the lane to the right (column c+1), two to the right (c+2) and,
    // on the next row, one to the right.
    let q = s.sub(zero, right2[i]);
    // With the triangles' drag `a m` (the first triangle's on this lane and
    // the lane beside and below; the second's on the lane beside, below, and
    // beside below), each product fused into a sum.
    let (l, m, in1) = if DRAG {
        (
            s.mul_add(a1, m1[i], s.mul_add(a2, m2[i], s.sub(anti[i], right[i]))),
            s.mul_sub(a2, m2[i], dr[i]),
            s.mul_add(a1, m1[i], s.mul_sub(a2, m2[i], s.add(d[i], anti[i]))),
        )
    } else {
        (
            s.sub(anti[i], right[i]),
            s.sub(zero, dr[i]),
            s.sub(zero, s.add(d[i], anti[i])),
        )
    };
    let in1 = s.add(in1, s.shift1(carry[2][i], m));
    // SAFETY: accumulator rows a1, a2, component i, columns c .. c + LANES.
    unsafe {
        let pa1 = k.acc.add(k.a[1] + i * nv + c);
        s.store(pa1, s.add(s.load(pa1), in1));
        s.store(k.acc.add(k.a[2] + i * nv + c), s.sub(zero, d2[i]));
    }
    if OWN {
        let mut own = s.add(s.add(right[i], right2[i]), s.add(d[i], dr[i]));
        own = s.add(own, d2[i]);
        if DRAG {
            own = s.mul_add(a1, m1[i], own);
        }
        own = s.add(
            own,
            s.add(s.shift1(carry[0][i], l), s.shift2(carry[1][i], q)),
        );
        // SAFETY: as above; outputs hold `lo + nv` floats.
        unsafe {
            let force = s.add(s.load(k.acc.add(k.a[0] + i * nv + c)), own);
            integrate::<S, PLAIN, FIXED, METHOD, GROUND>(
                &k.step,
                k.b[0] + c,
                k.lo + c,
                i,
                w,
                p00,
                force,
            );
        }
    }
    carry[0][i] = l;
    carry[1][i] = q;
    carry[2][i] = m;
}

/// Integrates component `i` of the `LANES` particles at array index `at` (inverse
/// masses `w`) under `force` (springs and drag): adds air damping and, for `y`, the
/// ground penalty, then steps them (symplectic Euler, explicit Euler or position
/// Verlet) and writes the new state to the outputs at index `o`.
///
/// # Safety
/// As for [`block`], with `OWN`.
///
/// `PLAIN`: symplectic Euler with no air damping or ground (see `Params::is_plain`).
/// `METHOD` and `GROUND`: [`StepLanes::method`] and [`StepLanes::ground_on`], as
/// constants.
#[inline(always)]
pub(super) unsafe fn integrate<
    S: Simd,
    const PLAIN: bool,
    const FIXED: bool,
    const METHOD: u8,
    const GROUND: bool,
>(
    k: &StepLanes<S>,
    at: usize,
    o: usize,
    i: usize,
    w: S::V,
    (x, v): Particle<S::V>,
    force: S::V,
) {
    let s = k.s;
    debug_assert!(METHOD == k.method && GROUND == k.ground_on);
    let method = match METHOD {
        _ if PLAIN => Method::SymplecticEuler,
        EXPLICIT => Method::ExplicitEuler,
        VERLET => Method::Verlet,
        _ => Method::SymplecticEuler,
    };
    let l = |v: S::V| Vector(s, v);
    // SAFETY: inside the arrays (caller's contract).
    let u = if METHOD == VERLET && !PLAIN {
        unsafe { s.load(k.u[i].add(at)) }
    } else {
        v[i]
    };
    let mut force = l(force);
    if !PLAIN {
        // Air damping as arithmetic, with a 0 where the step has none: as a branch
        // (a test of the flag per axis and block) the drape ran 96.4 instructions
        // per particle-step, 89.8 so (valgrind, AVX2).
        force = laws::air_damped(force, l(k.neg_air), l(v[i]));
        if i == 1 && GROUND {
            let [height, kc, cg] = k.ground;
            let depth = difference::<S, FIXED>(s, height, x[1]);
            force = force + laws::ground_support(l(depth), l(v[1]), l(kc), l(cg));
        }
    }
    let a = laws::free_acceleration(force, l(w), l(k.gravity[i]));
    let next = laws::update(method, l(u), a, l(w), l(k.dt), l(k.verlet_half_dt));
    let xn = moved::<S, FIXED>(s, x[i], k.dt_units, next.moving.1);
    // SAFETY: outputs hold `lo + nv` floats (Verlet's `u` only with Verlet).
    unsafe {
        s.store(k.out[i].add(o), xn);
        s.store(k.out[3 + i].add(o), next.v.1);
        if method == Method::Verlet {
            s.store(k.out[6 + i].add(o), next.u.1);
        }
    }
}

/// Projects the just integrated particles at output index `o` that are inside
/// the sphere (and free) onto its surface ([`laws::surface_offset`], in the
/// positions' units); the move `δ` (as computed: fixed-point positions take it
/// rounded to a unit, see `spring_line`) also changes their velocities by `δ / h`.
///
/// # Safety
/// As for [`integrate`], after it ran for all three components.
#[inline(always)]
pub(super) unsafe fn project_out_of_sphere<S: Simd, const FIXED: bool>(
    k: &StepLanes<S>,
    o: usize,
    w: S::V,
) {
    let s = k.s;
    let Some((center, radius, radius2)) = k.sphere else {
        return;
    };
    // SAFETY: the outputs just written (caller's contract).
    let out = |j: usize| unsafe { s.load(k.out[j].add(o)) };
    let xn: [S::V; 3] = std::array::from_fn(out);
    let d = lanes3(
        s,
        std::array::from_fn(|i| difference::<S, FIXED>(s, xn[i], center[i])),
    );
    let d2 = d.dot(d);
    let inside = s.keep_if_positive(w, s.keep_if_positive(s.sub(radius2, d2.1), k.one));
    // A block with no particle inside passes over the rest: most of a cloth
    // bigger than the sphere.
    if !s.any_positive(inside) {
        return;
    }
    let surface = unlanes3(laws::surface_offset(d, d2, Vector(s, radius)));
    let d = unlanes3(d);
    for i in 0..3 {
        // The move onto the surface.
        let dx = s.mul(inside, s.sub(surface[i], d[i]));
        let to = moved::<S, FIXED>(s, xn[i], k.one, dx);
        let dv = s.mul(dx, k.inv_dt);
        // SAFETY: as above.
        unsafe {
            s.store(k.out[i].add(o), to);
            s.store(k.out[3 + i].add(o), s.add(out(3 + i), dv));
            if k.method == VERLET {
                s.store(k.out[6 + i].add(o), s.add(out(6 + i), dv));
            }
        }
    }
}
