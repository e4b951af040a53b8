//! The band pass: each block of `LANES` indices evaluates the 13 springs that
//! start on its particles once, carries the forces on their other ends to the
//! accumulator, and integrates its particles once their forces are complete.

use super::{Band, Ctx, Geometry};
use crate::sim::grid_kernel::row::{EXPLICIT, SYMPLECTIC, VERLET, with_step_constants};
use crate::sim::grid_kernel::{
    BLOCK, Out, Particle, Real, Simd, StepLanes, integrate, project_out_of_sphere, spring,
};

/// Runs the bands, splitting the outputs (which start at the first band's start)
/// among them; in parallel with `rayon::join` when `parallel`.
pub(super) fn run_bands<E: Real>(ctx: &Ctx<E>, bands: &mut [Band<E>], out: Out<E>, parallel: bool) {
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
pub(in crate::sim::grid_kernel) fn band_modes<S: Simd>(
    s: S,
    ctx: &Ctx<S::E>,
    band: &mut Band<S::E>,
    out: Out<S::E>,
) {
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
