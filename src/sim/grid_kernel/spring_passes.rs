//! The passes after the step that move particles along the grid's springs:
//! Provot's stretch limit and XPBD's springs ([`SpringRule`]). Each is one
//! Gauss-Seidel pass over the springs in twelve sweeps (six stencil directions,
//! two colour classes each), a class's springs of one row corrected together in
//! SIMD blocks ([`spring_line`]; the stretch limit's springs along rows both
//! colours of a row at once, [`row_line`]), in bands of rows that stay in the
//! core's cache, and most rows on two threads in one hand-over
//! ([`Kernel::spring_pass`]). When a pass is the only one after the step, the
//! step's own bands run it on their rows as soon as they have stepped them
//! ([`SpringPass`], [`BandSweeps`]).

use std::ops::Range;

use super::super::duo::Duo;
use super::{Buf, Kernel, Out, PARALLEL_MIN_PARTICLES, Real, SimdLevel, State, Stencil, Torn};

mod lines;
mod sweep;

pub(super) use lines::spring_sweep;
pub(super) use sweep::{
    ColourClass, Multipliers, RowColour, Sweep, SweepLines, SweepMultipliers, SweepRules,
    SweepSprings,
};

/// What a [`Kernel::spring_pass`] does to each spring.
#[derive(Clone, Copy, Debug)]
pub(super) enum SpringRule {
    /// Provot's stretch limit `tau`: a spring longer than `(1 + tau) L` is shortened
    /// to that by [`crate::sim::laws::length_factor`].
    StretchLimit(f64),
    /// XPBD's springs: each corrected by
    /// [`crate::sim::laws::xpbd_factor`] against the positions at the
    /// start of the step (the kernel's other state buffer, after the swap), once
    /// on a grid, twice on a lattice (forward and back, [`Multipliers`]).
    Xpbd,
}

impl<E: Real> Kernel<E> {
    /// One pass of `rule` over the springs (see [`Self::constrain`]), in the
    /// colour classes of [`crate::sim::springs::constraint_order`], the f64
    /// engine's order. No two springs of a class share a particle, so a class's
    /// springs from one row are corrected together ([`spring_line`]); with
    /// `parallel`, most rows by two threads in one hand-over, with the same result
    /// as on one. A move `δ` adds `δ / dt` to the particle's velocity. (When it is
    /// the only pass after the step, the step runs it instead, on each band's
    /// rows as soon as they are stepped: [`SpringPass`].)
    pub(super) fn spring_pass(
        &mut self,
        rule: SpringRule,
        dt: f64,
        parallel: bool,
        duo: Option<&Duo>,
    ) {
        let h = self.grid.h;
        let parallel = parallel && self.grid.w * h >= PARALLEL_MIN_PARTICLES;
        let pass = SpringPass {
            plan: self.sweep_plan(rule, dt),
            inv_mass: self.inv_mass.as_slice(),
            simd: self.simd,
            torn: self.torn.as_ref(),
            start: step_start(rule, &self.next),
        };
        let mut out = self.cur.rows();
        if !parallel {
            pass.band(0, h).finish(&mut out);
            return;
        }
        // Two threads and one hand-over (a hand-over per sweep cost more than the
        // sweep's half on this 2-core machine), then the lines between the halves.
        let split = h / 2;
        {
            let (mut upper, mut lower) = out.reborrow().split_at(split * self.grid.stride);
            let mut second = || pass.band(split, h).finish(&mut lower);
            let first = || pass.band(0, split).finish(&mut upper);
            match duo {
                Some(duo) => duo.fork(&mut second, first),
                None => {
                    rayon::join(first, second);
                }
            }
        }
        pass.between_bands(&mut out, split);
    }

    /// The sweeps of one pass of `rule` over the springs after a step of `dt`, in
    /// their order ([`SpringPass`]).
    pub(super) fn sweep_plan(&self, rule: SpringRule, dt: f64) -> SweepPlan<E> {
        let (w, h, st) = (self.grid.w, self.grid.h, self.grid.stride);
        let rules = SweepRules {
            rule,
            dt,
            frame: self.frame,
        };
        // The sweeps in their order: each direction's two colour classes.
        let stencil = self.stencil();
        let sweeps: [Option<Sweep<E>>; 12] = std::array::from_fn(|k| {
            let (d, colour) = (k / 2, k % 2);
            let Stencil {
                offset: (dr, dc),
                rest,
                present,
                coefficients,
            } = stencil[d];
            if !present {
                return None;
            }
            let class = ColourClass {
                rows: (dr > 0).then_some(RowColour {
                    wrap: usize::MAX,
                    period: dr,
                }),
                colour,
            };
            let springs = SweepSprings {
                direction: d,
                dr,
                dc,
                rest,
                kind: coefficients,
            };
            Sweep::new(&rules, springs, (w, h), class)
        });
        let torn = self.torn.as_ref();
        // `skew[k]`: the rows sweep k's lines reach below their first, and those
        // of the sweeps before it: `dr` summed over sweeps 0 to k.
        let mut skew = [0; 12];
        let mut reach = 0;
        for (k, sweep) in sweeps.iter().enumerate() {
            reach += sweep.as_ref().map_or(0, |s| s.dr);
            skew[k] = reach;
        }
        // Whether sweep `k`, colour 0 of a direction along rows, runs with
        // colour 1 (sweep `k + 1`), row by row ([`row_line`]): under the
        // stretch limit without tears. A line along rows changes only its own
        // row, so rows apart need no order, and the two sweeps' rows in every
        // band and on every thread are the same (`dr` 0 adds no skew).
        let joined = std::array::from_fn(|k| {
            matches!(rule, SpringRule::StretchLimit(_))
                && torn.is_none()
                && k.is_multiple_of(2)
                && sweeps[k + 1].is_some()
                && sweeps[k]
                    .as_ref()
                    .is_some_and(|s| s.dr == 0 && matches!(s.dc, 1 | 2))
        });
        SweepPlan {
            sweeps,
            skew,
            reach,
            joined,
            height: h,
            stride: st,
            rows_in_cache: self.rows_in_cache(),
        }
    }

    /// Rows of about 192 KiB of the state's arrays: a band of rows that a pass
    /// over them finds in the core's cache (at 256 columns the stretch limit's
    /// twelve sweeps over the whole cloth each went to memory).
    pub(super) fn rows_in_cache(&self) -> usize {
        let row_bytes = self.cur.x.len() * 4 * self.grid.stride * std::mem::size_of::<E>();
        (192 * 1024 / row_bytes.max(1)).max(8)
    }
}

/// One spring pass over the cloth, planned: its twelve sweeps (six stencil
/// directions, two colour classes each) in order, each a line per row. The lines
/// run in bands of rows that stay in the core's cache, each band's sweeps in
/// order, then the next band's ([`SpringPass::lines`]), on one band of the
/// step's rows or two (two threads: [`SpringPass::band`], then
/// [`SpringPass::between_bands`]). A band's lines touch only its own rows, and
/// only rows the step has written, so the step runs them on each band's rows as
/// soon as it has stepped them, while they are in the cache ([`BandSweeps`]).
pub(super) struct SpringPass<'a, E> {
    pub(super) plan: SweepPlan<E>,
    pub(super) inv_mass: &'a [E],
    pub(super) simd: SimdLevel,
    pub(super) torn: Option<&'a Torn<E>>,
    /// The positions at the start of the step ([`step_start`]).
    pub(super) start: [&'a [E]; 3],
}

/// The sweeps of a [`SpringPass`] in their order, and how its bands cut them.
pub(super) struct SweepPlan<E> {
    sweeps: [Option<Sweep<E>>; 12],
    /// `skew[k]`: `dr` summed over sweeps 0 to `k`.
    skew: [usize; 12],
    /// `skew[11]`: how far below a band's last row its last sweep's lines end.
    reach: usize,
    /// Whether sweep `k` runs with sweep `k + 1`, row by row ([`row_line`]).
    joined: [bool; 12],
    height: usize,
    stride: usize,
    /// Rows a band of lines covers ([`Kernel::rows_in_cache`]).
    rows_in_cache: usize,
}

impl<E: Real> SweepPlan<E> {
    /// Sweep k's lines from row `cut(k, t)` on belong to the bands from
    /// boundary `t` on: a band's boundary moves up by the `dr` of each sweep
    /// before. That keeps the sweeps' order wherever it matters: a line of sweep
    /// k that runs before a line of an earlier sweep k' from a later band
    /// (boundary `t`) ends above row `t - skew[k - 1]` (it starts above `t -
    /// skew[k]`), and the other starts at or below `t - skew[k']`, no higher:
    /// they share no particle. (Lines of one sweep share none.)
    fn cut(&self, k: usize, t: usize) -> usize {
        t.saturating_sub(self.skew[k])
    }

    /// The first row of sweep k's lines that a band starting at row `r0 > 0`
    /// runs: the lines from there on share no row with the band above it, nor
    /// with any line above them that should have seen them.
    fn below(&self, k: usize, r0: usize) -> usize {
        r0 + if k == 0 { 0 } else { self.skew[k - 1] }
    }
}

impl<E: Real> SpringPass<'_, E> {
    /// The pass on the rows `r0 .. r1` of the step's bands (the whole cloth, or
    /// one of its two halves), which it runs as the step writes them.
    pub(super) fn band(&self, r0: usize, r1: usize) -> BandSweeps<'_, '_, E> {
        BandSweeps {
            pass: self,
            r0,
            r1,
            done: r0,
        }
    }

    /// The lines left between two bands split at row `split`, once both have
    /// run, in order: sweep k's from row `cut(k, split)` to `below(k, split)`.
    /// A line left over from sweep k shares no row with any later sweep's line
    /// that the bands ran before it, nor with any line of theirs that should have
    /// seen it: the bounds move apart by each sweep's `dr`.
    pub(super) fn between_bands(&self, out: &mut Out<E>, split: usize) {
        let rest = |k: usize| self.plan.cut(k, split)..self.plan.below(k, split);
        let mut t = 0;
        while t < self.plan.height + self.plan.reach {
            let next = t + self.plan.rows_in_cache;
            self.lines(out, 0, (t, next), t == 0, &rest);
            t = next;
        }
    }

    /// The lines of every sweep in `rows(k)` between the boundaries `t` and
    /// `next` (from the first of `rows(k)` when `first_band`), each sweep's in
    /// order, in `out` (the state's arrays from row `first` on).
    fn lines(
        &self,
        out: &mut Out<E>,
        first: usize,
        (t, next): (usize, usize),
        first_band: bool,
        rows: &dyn Fn(usize) -> Range<usize>,
    ) {
        for (k, sweep) in self.plan.sweeps.iter().enumerate() {
            let Some(sweep) = sweep else { continue };
            if k % 2 == 1 && self.plan.joined[k - 1] {
                continue;
            }
            let all = rows(k);
            let start_row = all
                .start
                .max(if first_band { 0 } else { self.plan.cut(k, t) });
            let end = all.end.min(self.plan.cut(k, next)).min(sweep.rows);
            if start_row >= end {
                continue;
            }
            let lines = SweepLines {
                sweep,
                stride: self.plan.stride,
                rows: start_row..end,
                inv_mass: self.inv_mass,
                alive: self.torn.map(|t| t.springs[sweep.direction].as_slice()),
                real: None,
                start: self.start,
                multipliers: None,
                both_colours: self.plan.joined[k],
            };
            E::spring_sweep(self.simd, out, first * self.plan.stride, &lines);
        }
    }
}

/// A [`SpringPass`] on one band of the step's rows, `r0 .. r1`, run as the
/// step writes them: sweep k's lines from the band's first (`below(k, r0)`
/// when the band is not the first) to its last (`cut(k, r1)` when it is not the
/// last), in bands of rows in order, each as soon as the rows it touches are
/// written ([`BandSweeps::advance`]).
pub(super) struct BandSweeps<'p, 'a, E> {
    pass: &'p SpringPass<'a, E>,
    r0: usize,
    r1: usize,
    /// The boundary the lines have run to.
    done: usize,
}

impl<E: Real> BandSweeps<'_, '_, E> {
    /// The band's lines in rows `r0 .. r1` of sweep `k`.
    fn rows(&self, k: usize) -> Range<usize> {
        let plan = &self.pass.plan;
        let first = if self.r0 == 0 {
            0
        } else {
            plan.below(k, self.r0)
        };
        let last = if self.r1 == plan.height {
            plan.height
        } else {
            plan.cut(k, self.r1)
        };
        first..last
    }

    /// Runs the band's lines that touch only rows above `written` (which the
    /// step has written), in `out` (the state's arrays from the band's first
    /// row on).
    pub(super) fn advance(&mut self, out: &mut Out<E>, written: usize) {
        if written <= self.done {
            return;
        }
        let first_band = self.done == self.r0;
        self.pass
            .lines(out, self.r0, (self.done, written), first_band, &|k| {
                self.rows(k)
            });
        self.done = written;
    }

    /// Runs the band's lines left, once all its rows are written.
    pub(super) fn finish(&mut self, out: &mut Out<E>) {
        let end = self.pass.plan.height + self.pass.plan.reach;
        while self.done < end {
            let next = (self.done + self.pass.plan.rows_in_cache).min(end);
            self.advance(out, next);
        }
    }
}

/// What `rule` reads of the positions at the start of the step, `state` (the
/// kernel's other state buffer, after the step's swap): XPBD the whole arrays;
/// the stretch limit nothing.
pub(super) fn step_start<E: Real>(rule: SpringRule, state: &State<E>) -> [&[E]; 3] {
    match rule {
        SpringRule::Xpbd => state.x.each_ref().map(Buf::as_slice),
        SpringRule::StretchLimit(_) => Default::default(),
    }
}
