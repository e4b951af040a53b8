//! The passes after the step that move particles along the grid's springs:
//! Provot's stretch limit and XPBD's springs ([`SpringRule`]). Each is one
//! Gauss-Seidel pass over the springs in twelve sweeps (six stencil directions,
//! two colour classes each), a class's springs of one row corrected together in
//! SIMD blocks ([`spring_line`]), in bands of rows that stay in the core's cache,
//! and most rows on two threads in one hand-over ([`Kernel::spring_pass`]).

use std::ops::Range;

use super::super::constraints::XpbdSpring;
use super::super::duo::Duo;
use super::super::forces::EPSILON_LENGTH;
use super::row::{difference, moved};
use super::simd::align_frame;
use super::{
    BLOCK, Buf, Frame, Kernel, Out, PARALLEL_MIN_PARTICLES, Real, Simd, SpringCoefficients, State,
    Stencil,
};

/// What a [`Kernel::spring_pass`] does to each spring.
#[derive(Clone, Copy, Debug)]
pub(super) enum SpringRule {
    /// Provot's stretch limit `tau`: a spring longer than `(1 + tau) L` is shortened
    /// to that, as [`crate::sim::constraints::length_correction`] does.
    StretchLimit(f64),
    /// XPBD's springs: each corrected by
    /// [`crate::sim::constraints::xpbd_correction`] against the positions at the
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
    /// as on one. A move `δ` adds `δ / dt` to the particle's velocity.
    pub(super) fn spring_pass(
        &mut self,
        rule: SpringRule,
        dt: f64,
        parallel: bool,
        duo: Option<&Duo>,
    ) {
        let (w, h, st) = (self.grid.w, self.grid.h, self.grid.stride);
        let parallel = parallel && w * h >= PARALLEL_MIN_PARTICLES;
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
        let (inv_mass, simd) = (self.inv_mass.as_slice(), self.simd);
        let torn = self.torn.as_ref();
        let start = step_start(rule, &self.next);
        // `skew[k]`: the rows sweep k's lines reach below their first, and those
        // of the sweeps before it: `dr` summed over sweeps 0 to k.
        let mut skew = [0; 12];
        let mut reach = 0;
        for (k, sweep) in sweeps.iter().enumerate() {
            reach += sweep.as_ref().map_or(0, |s| s.dr);
            skew[k] = reach;
        }
        // Lines run in bands of rows, each band's sweeps in order, then the next
        // band's. Sweep k's lines from row `cut(k, t)` on belong to the bands from
        // boundary `t` on: a band's boundary moves up by the `dr` of each sweep
        // before. That keeps the sweeps' order wherever it matters: a line of
        // sweep k that runs before a line of an earlier sweep k' from a later band
        // (boundary `t`) ends above row `t - skew[k - 1]` (it starts above
        // `t - skew[k]`), and the other starts at or below `t - skew[k']`, no
        // higher: they share no particle. (Lines of one sweep share none.)
        let cut = |k: usize, t: usize| t.saturating_sub(skew[k]);
        // Bands of about 192 KiB of the state's arrays, with the rows that the skew
        // adds: each band's sweeps then find its rows in the core's cache (at 256
        // columns the twelve sweeps over the whole cloth each went to memory).
        let row_bytes = self.cur.x.len() * 4 * st * std::mem::size_of::<E>();
        let band = (192 * 1024 / row_bytes.max(1)).max(8);
        // The lines of every sweep in `rows(k)`, band by band from row `from`,
        // in `out` (the state's arrays from row `first` on).
        let run =
            |out: &mut Out<E>, first: usize, from: usize, rows: &dyn Fn(usize) -> Range<usize>| {
                let mut t = from;
                while t < h + reach {
                    let next = t + band;
                    for (k, sweep) in sweeps.iter().enumerate() {
                        let Some(sweep) = sweep else { continue };
                        let all = rows(k);
                        let start_row = all.start.max(if t == from { 0 } else { cut(k, t) });
                        let end = all.end.min(cut(k, next)).min(sweep.rows);
                        if start_row >= end {
                            continue;
                        }
                        let lines = SweepLines {
                            sweep,
                            stride: st,
                            rows: start_row..end,
                            inv_mass,
                            alive: torn.map(|t| t.springs[sweep.direction].as_slice()),
                            real: None,
                            start,
                            multipliers: None,
                        };
                        E::spring_sweep(simd, out, first * st, &lines);
                    }
                    t = next;
                }
            };
        if !parallel {
            run(&mut self.cur.rows(), 0, 0, &|_| 0..h);
            return;
        }
        // Two threads and one hand-over (a hand-over per sweep cost more than the
        // sweep's half on this 2-core machine). The top thread runs sweep k's
        // lines wholly above row `split - skew[k - 1]`, the bottom thread its
        // lines from row `split + skew[k - 1]` on, each in its own rows and in
        // bands as above; then this thread runs the lines left, in order. A line
        // left over from sweep k shares no row with any later sweep's line that
        // the threads ran before it, nor with any line of theirs that should have
        // seen it: the bounds move apart by each sweep's `dr`.
        let split = h / 2;
        let below = |k: usize| split + if k == 0 { 0 } else { skew[k - 1] };
        let top = |k: usize| 0..cut(k, split);
        let bottom = |k: usize| below(k)..h;
        {
            let (mut upper, mut lower) = self.cur.rows().split_at(split * st);
            let mut second = || run(&mut lower, split, split, &bottom);
            let first = || run(&mut upper, 0, 0, &top);
            match duo {
                Some(duo) => duo.fork(&mut second, first),
                None => {
                    rayon::join(first, second);
                }
            }
        }
        let rest = |k: usize| cut(k, split)..below(k);
        run(&mut self.cur.rows(), 0, 0, &rest);
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

/// What a [`SpringLine`] does to its springs, in the kernel's float type and the
/// positions' units.
#[derive(Clone, Copy)]
enum LineRule<E> {
    /// The stretch limit: springs longer than `longest` are shortened to it.
    Limit { longest: E },
    /// XPBD: every spring, of rest length `rest`, corrected with `α̃` and `γ`
    /// ([`XpbdSpring`]).
    Xpbd { rest: E, alpha: E, gamma: E },
}

/// One row's springs of one colour class: the first ends at array indices `a ..
/// a + len`, the second ends at `b .. b + len`.
struct SpringLine<E> {
    a: usize,
    b: usize,
    len: usize,
    /// 1 for the lanes of a block in the class, else 0 (see [`SpringLine::class`]).
    class: [E; BLOCK],
    rule: LineRule<E>,
    /// Velocity per unit moved: `unit / h`.
    inv_dt: E,
    /// The squared length (units²) under which a spring has no direction.
    tiny_length2: E,
    /// Whether positions are fixed point.
    fixed: bool,
}

impl<E: Real> SpringLine<E> {
    /// 1 for the lanes of a block in the class, first column `c0`: every lane, or
    /// along rows (`along` = the colour and `dc`) the springs starting at columns
    /// `c` with `(c / dc) % 2 == colour`, a pattern of 2 or 4 lanes that repeats in
    /// every block.
    fn class(c0: usize, along: Option<(usize, isize)>) -> [E; BLOCK] {
        std::array::from_fn(|l| match along {
            Some((colour, dc)) if ((c0 + l) / dc.unsigned_abs()) % 2 != colour => E::ZERO,
            _ => E::ONE,
        })
    }
}

/// What the sweeps of one spring pass share: the rule, the step, and how the
/// positions are stored.
pub(super) struct SweepRules {
    pub(super) rule: SpringRule,
    pub(super) dt: f64,
    pub(super) frame: Frame,
}

/// The springs of one direction: from each particle to the one `dr` rows down and
/// `dc` columns right, of rest length `rest` and coefficients `kind`; `direction`
/// indexes the tear masks.
pub(super) struct SweepSprings {
    pub(super) direction: usize,
    pub(super) dr: usize,
    pub(super) dc: isize,
    pub(super) rest: f64,
    pub(super) kind: SpringCoefficients,
}

/// Which springs of a direction are in a colour class: along rows (no `rows`),
/// those starting at columns `c` with `(c / dc) % 2 == colour`; else those
/// starting on rows `r` with `((r % wrap) / period) % 2 == colour`.
#[derive(Clone, Copy)]
pub(super) struct ColourClass {
    pub(super) rows: Option<RowColour>,
    pub(super) colour: usize,
}

/// A colour of rows: `((r % wrap) / period) % 2` (see [`ColourClass`]).
#[derive(Clone, Copy)]
pub(super) struct RowColour {
    pub(super) wrap: usize,
    pub(super) period: usize,
}

/// One sweep of a spring pass: the springs of one direction `(dr, dc)` in one
/// colour class, a [`SpringLine`] per row.
pub(super) struct Sweep<E> {
    /// Index of the direction in the stencil (and of its tear masks).
    direction: usize,
    dr: usize,
    dc: isize,
    /// First column with both ends on the cloth.
    c0: usize,
    class: ColourClass,
    /// Rows with both ends on the cloth: `0 .. rows`.
    rows: usize,
    /// The line of row 0 (its `a` and `b` set per row by [`Sweep::line_at`]).
    line: SpringLine<E>,
}

impl<E: Real> Sweep<E> {
    /// The sweep of `springs` in `class` on rows of `width` particles, `height`
    /// rows in all, under `rules`; `None` when it has no springs (or, for XPBD,
    /// when their rest length or stiffness leaves nothing to correct).
    pub(super) fn new(
        rules: &SweepRules,
        springs: SweepSprings,
        (width, height): (usize, usize),
        class: ColourClass,
    ) -> Option<Self> {
        let SweepSprings {
            direction,
            dr,
            dc,
            rest,
            kind,
        } = springs;
        // Columns c with both ends on the cloth: 0 <= c + dc < width.
        let c0 = (-dc).max(0) as usize;
        let len = width.saturating_sub(dc.max(0) as usize).saturating_sub(c0);
        if len == 0 || dr >= height {
            return None;
        }
        let frame = &rules.frame;
        let rule = match rules.rule {
            SpringRule::StretchLimit(tau) => LineRule::Limit {
                longest: E::of(frame.units((1.0 + tau) * rest)),
            },
            SpringRule::Xpbd => {
                let spring = XpbdSpring::new(rest, kind.k, kind.b, rules.dt)?;
                LineRule::Xpbd {
                    rest: E::of(frame.units(spring.rest)),
                    alpha: E::of(spring.alpha),
                    gamma: E::of(spring.gamma),
                }
            }
        };
        let along = match class.rows {
            None => Some((class.colour, dc)),
            Some(_) => None,
        };
        Some(Sweep {
            direction,
            dr,
            dc,
            c0,
            class,
            rows: height - dr,
            line: SpringLine {
                a: 0,
                b: 0,
                len,
                class: SpringLine::class(c0, along),
                rule,
                inv_dt: E::of(frame.unit / rules.dt),
                tiny_length2: E::of(frame.units(EPSILON_LENGTH).powi(2)),
                fixed: frame.fixed,
            },
        })
    }

    /// The rows of `rows` whose springs are in the class: every row along rows
    /// (the class is a pattern of columns), else those of the class's colour.
    fn lines(&self, rows: Range<usize>) -> impl Iterator<Item = usize> + '_ {
        let ColourClass {
            rows: colour_of,
            colour,
        } = self.class;
        rows.filter(move |r| colour_of.is_none_or(|c| ((r % c.wrap) / c.period) % 2 == colour))
    }

    /// The rows the sweep's lines start on.
    pub(super) fn rows(&self) -> Range<usize> {
        0..self.rows
    }

    /// The rows from a spring's first end to its second.
    pub(super) fn dr(&self) -> usize {
        self.dr
    }

    /// Whether positions are fixed point.
    pub(super) fn fixed(&self) -> bool {
        self.line.fixed
    }

    /// The line of row `r` (rows `stride` floats apart).
    fn line_at(&self, r: usize, stride: usize) -> SpringLine<E> {
        SpringLine {
            a: r * stride + self.c0,
            b: ((r + self.dr) * stride + self.c0).wrapping_add_signed(self.dc),
            ..self.line
        }
    }
}

/// The lines of a [`Sweep`] starting on `rows`, rows `stride` floats apart, and
/// what they read besides the state: inverse masses, the direction's tear mask
/// when springs tore ([`super::Torn`], indexed by first end), the mask of real
/// particles when the arrays hold ghosts that springs reach (1 for particles, 0
/// for ghosts: a lattice's), and for XPBD the positions at the start of the step
/// (empty for the stretch limit) and, when it sweeps
/// back as well (a lattice's, see [`crate::sim::constraints::xpbd_pass`]), the
/// sweep's [`SweepMultipliers`], all whole arrays indexed from row 0.
pub(super) struct SweepLines<'a, E> {
    pub(super) sweep: &'a Sweep<E>,
    pub(super) stride: usize,
    pub(super) rows: Range<usize>,
    pub(super) inv_mass: &'a [E],
    pub(super) alive: Option<&'a [E]>,
    pub(super) real: Option<&'a [E]>,
    pub(super) start: [&'a [E]; 3],
    pub(super) multipliers: Option<SweepMultipliers<E>>,
}

/// XPBD's multipliers of one sweep's springs, kept from a spring's first
/// correction (the forward sweep) to its second (the backward one), as `α̃ λ` (in
/// the positions' units):
/// one array per sweep, indexed by the springs' first ends as the state's arrays
/// are (see [`crate::sim::constraints::xpbd_pass`]).
#[derive(Default)]
pub(super) struct Multipliers<E>(Vec<Buf<E>>);

impl<E: Real> Multipliers<E> {
    /// The arrays of `sweeps` sweeps of `len` floats, made once.
    pub(super) fn ensure(&mut self, sweeps: usize, len: usize) {
        if self.0.len() != sweeps || self.0.first().is_some_and(|b| b.as_slice().len() < len) {
            self.0 = (0..sweeps).map(|_| Buf::zeros(len)).collect();
        }
    }

    /// Sweep `k`'s array, written by its forward sweep or read by its backward one
    /// (`second`).
    pub(super) fn of_sweep(&mut self, k: usize, second: bool) -> SweepMultipliers<E> {
        let values = self.0[k].as_mut_slice();
        SweepMultipliers {
            values: values.as_mut_ptr(),
            len: values.len(),
            second,
        }
    }
}

/// One sweep's array of [`Multipliers`], as its lines use it. A line changes its
/// own springs' entries only (`a .. a + len`; its lanes past the end store back
/// what they read, as they do the state's), and no two lines of a sweep have a
/// spring in common.
#[derive(Clone, Copy)]
pub(super) struct SweepMultipliers<E> {
    values: *mut E,
    len: usize,
    /// Whether this is the springs' second correction, which reads the values (the
    /// first writes them).
    second: bool,
}

// SAFETY: lines on different threads touch different entries, as they touch
// different particles: the threads' lines are kept apart by the rows a line's
// lanes reach (see the lattice's `spring_pass`); and the backward sweep, which
// reads the entries, runs after the forward one has joined.
unsafe impl<E: Send> Send for SweepMultipliers<E> {}
unsafe impl<E: Sync> Sync for SweepMultipliers<E> {}

/// [`spring_line`] on each line of `lines`, in order of rows (one call for a
/// sweep, where a call per line cost its set-up every 8 blocks at 128 columns).
#[inline(always)]
pub(super) fn spring_sweep<S: Simd, const FIXED: bool>(
    s: S,
    out: &mut Out<S::E>,
    base: usize,
    lines: &SweepLines<S::E>,
) {
    align_frame();
    let rows = lines.sweep.lines(lines.rows.clone());
    match lines.sweep.line.rule {
        LineRule::Limit { .. } => {
            for r in rows {
                let line = lines.sweep.line_at(r, lines.stride);
                spring_line::<S, FIXED, false>(s, out, base, lines, &line);
            }
        }
        LineRule::Xpbd { .. } => {
            for r in rows {
                let line = lines.sweep.line_at(r, lines.stride);
                spring_line::<S, FIXED, true>(s, out, base, lines, &line);
            }
        }
    }
}

/// `[f(0), f(1), f(2)]` for `per_axis!(|k| f(k))`, written out: the closures of
/// `std::array::from_fn` were not inlined into the (then) double-float positions' SIMD
/// code, so the vector operations in them ran as calls (3.4x slower for XPBD's
/// pass).
macro_rules! per_axis {
    (|$k:ident| $e:expr) => {
        [
            {
                let $k = 0;
                $e
            },
            {
                let $k = 1;
                $e
            },
            {
                let $k = 2;
                $e
            },
        ]
    };
}

/// Corrects the springs of `line` in `out` (the state's arrays from array index
/// `base` on), in blocks of `S::LANES` springs, four blocks at a time: measures
/// them all, then for each block with a spring to correct its corrections and at
/// once the moves of its first ends and of its second ends.
///
/// * The stretch limit (`XPBD` false) corrects the springs longer than `longest`
///   as [`crate::sim::constraints::length_correction`] does.
/// * XPBD corrects every spring as [`crate::sim::constraints::xpbd_correction`]
///   does, from the positions at the start of the step in `lines.start`.
///
/// Each particle has at most one spring in a class, so the moves do not interact:
/// a lane out of the class (or past the line, or a spring that tore: 0 in the
/// direction's mask, when some did) gets a move of 0, which leaves its particle as
/// it was. A move `δ` adds `δ / h` to the velocity (and to Verlet's `u`): the move
/// as computed, where fixed-point positions take it rounded to a whole unit, so
/// that the part of it under half a unit reaches the position through the
/// velocity at the next step rather than never (a correction that stayed under
/// half a unit step after step, as XPBD's small ones of a cloth do, was lost
/// whole: XPBD's drape parted from the f64 engine by 9e-5 m over 320 steps, 3e-6
/// m so). The lanes
/// past `len` reach ghost columns inside the row's padding (rows are [`BLOCK`]
/// floats longer than their blocks).
#[inline(always)]
fn spring_line<S: Simd, const FIXED: bool, const XPBD: bool>(
    s: S,
    out: &mut Out<S::E>,
    base: usize,
    lines: &SweepLines<S::E>,
    line: &SpringLine<S::E>,
) {
    let n = S::LANES;
    let &SpringLine { len, inv_dt, .. } = line;
    let (zero, one) = (S::E::ZERO, S::E::ONE);
    let (longest, rest, alpha, gamma) = match line.rule {
        LineRule::Limit { longest } => (longest, zero, zero, zero),
        LineRule::Xpbd { rest, alpha, gamma } => (zero, rest, alpha, gamma),
    };
    let (a, b) = (line.a - base, line.b - base);
    let lanes = len.next_multiple_of(n);
    let end = a.max(b) + lanes;
    let inv_mass = &lines.inv_mass[base..];
    let [x, y, z, vx, vy, vz, ux, uy, uz] = &mut out.0;
    let verlet = !ux.is_empty();
    let fits = |arrays: [&[S::E]; 3], end: usize| arrays.iter().all(|p| p.len() >= end);
    // Every block below reads and writes inside these bounds.
    assert!(inv_mass.len() >= end && fits([x, y, z], end) && fits([vx, vy, vz], end));
    assert!(!verlet || fits([ux, uy, uz], end));
    let [sx, sy, sz] = lines.start;
    let start_end = line.a.max(line.b) + lanes;
    assert!(!XPBD || fits([sx, sy, sz], start_end));
    let multipliers = lines.multipliers.filter(|_| XPBD);
    assert!(multipliers.is_none_or(|m| m.len >= line.a + lanes));
    let alive = lines.alive.map(|m| &m[line.a..line.a + lanes]);
    let real = lines.real.map(|m| &m[base..]);
    assert!(real.is_none_or(|m| m.len() >= end));
    let pos = [x.as_mut_ptr(), y.as_mut_ptr(), z.as_mut_ptr()];
    let vel = [vx.as_mut_ptr(), vy.as_mut_ptr(), vz.as_mut_ptr()];
    let upd = [ux.as_mut_ptr(), uy.as_mut_ptr(), uz.as_mut_ptr()];
    let start = [sx.as_ptr(), sy.as_ptr(), sz.as_ptr()];
    let (longest2, inv_dt_v) = (s.splat(longest * longest), s.splat(inv_dt));
    let (longest_v, one_v) = (s.splat(longest), s.splat(one));
    let (rest_v, alpha_v) = (s.splat(rest), s.splat(alpha));
    let (gamma_v, one_gamma_v) = (s.splat(gamma), s.splat(one + gamma));
    let minus_alpha_v = s.splat(zero - alpha);
    let tiny_length2 = line.tiny_length2;
    // SAFETY (every load and store below): `j + n <= lanes`, and the arrays hold
    // `a + lanes` and `b + lanes` floats (asserted above; the starting positions
    // `line.a + lanes` and `line.b + lanes`).
    let load = |p: *const S::E, i: usize| unsafe { s.load(p.add(i)) };
    // Squared lengths of the vectors `d`.
    macro_rules! length2 {
        ($d:expr) => {{
            let d = $d;
            s.mul_add(d[0], d[0], s.mul_add(d[1], d[1], s.mul(d[2], d[2])))
        }};
    }
    // The block at `j`: its springs' vectors `d` (first end less second), their
    // squared lengths, positive where a spring is in the class (and for the
    // stretch limit over the limit), and whether any is.
    macro_rules! measure {
        ($j:expr) => {{
            let j = $j;
            let d: [S::V; 3] =
                per_axis!(|k| difference::<S, FIXED>(s, load(pos[k], a + j), load(pos[k], b + j)));
            let mut keep = load(line.class.as_ptr(), 0);
            if j + n > len {
                let tail: [S::E; BLOCK] =
                    std::array::from_fn(|l| if j + l < len { one } else { zero });
                keep = s.mul(keep, load(tail.as_ptr(), 0));
            }
            if let Some(m) = alive {
                keep = s.mul(keep, load(m.as_ptr(), j));
            }
            if let Some(m) = real {
                let both = s.mul(load(m.as_ptr(), a + j), load(m.as_ptr(), b + j));
                keep = s.mul(keep, both);
            }
            let l2 = length2!(d);
            // Positive where the spring is to be corrected.
            let over = if XPBD {
                keep
            } else {
                s.mul_sub(l2, keep, longest2)
            };
            (d, l2, over, s.any_positive(over))
        }};
    }
    // XPBD's `t = (C + α̃ λ + γ n·Δ) / ((1 + γ) w + α̃)` for the block at `j` (`C
    // = l - rest`, `Δ` the first end's move since the start of the step less the
    // second's, `λ` the multiplier so far, 0 in the forward sweep), and `t / l`,
    // to scale `d` by (0 where `l` is about 0). The multiplier's change is `-t`.
    macro_rules! xpbd_scale {
        ($j:expr, $d:expr, $l2:expr, $w:expr) => {{
            let (j, d, l2, w) = ($j, $d, $l2, $w);
            let moved: [S::V; 3] = per_axis!(|k| {
                let (ia, ib) = (line.a + j, line.b + j);
                s.sub(
                    difference::<S, FIXED>(s, load(pos[k], a + j), load(start[k], ia)),
                    difference::<S, FIXED>(s, load(pos[k], b + j), load(start[k], ib)),
                )
            });
            let inv_l = s.rsqrt_or_zero(l2, tiny_length2);
            // n·Δ with n = d / l, and C + α̃ λ.
            let along = s.mul_add(
                d[0],
                moved[0],
                s.mul_add(d[1], moved[1], s.mul(d[2], moved[2])),
            );
            let stretch = s.mul_sub(l2, inv_l, rest_v);
            let stretch = match multipliers {
                Some(m) if m.second => s.add(stretch, load(m.values, line.a + j)),
                _ => stretch,
            };
            let along = s.mul(along, inv_l);
            let t = s.div(
                s.mul_add(gamma_v, along, stretch),
                s.mul_add(one_gamma_v, w, alpha_v),
            );
            (s.mul(t, inv_l), t)
        }};
    }
    // Moves the ends of the block at `j` by their corrections.
    macro_rules! correct {
        ($j:expr, $d:expr, $l2:expr, $over:expr) => {{
            let (j, d, l2, over) = ($j, $d, $l2, $over);
            let w = s.add(
                load(inv_mass.as_ptr(), a + j),
                load(inv_mass.as_ptr(), b + j),
            );
            // Positive where a spring to correct is not pinned at both ends.
            let over = s.keep_if_positive(w, over);
            let scale = if XPBD {
                let (scale, t) = xpbd_scale!(j, d, l2, w);
                if let Some(m) = multipliers.filter(|m| !m.second) {
                    // `α̃ λ` after the first correction (from `λ = 0`): `-α̃ t`, 0
                    // where no spring was corrected; lanes past the line keep
                    // what they hold (they may be the next row's springs).
                    let mut kept = s.keep_if_positive(over, s.mul(minus_alpha_v, t));
                    let i = line.a + j;
                    if j + n > len {
                        let past: [S::E; BLOCK] =
                            std::array::from_fn(|l| if j + l < len { zero } else { one });
                        let past = load(past.as_ptr(), 0);
                        kept = s.add(kept, s.keep_if_positive(past, load(m.values, i)));
                    }
                    // SAFETY: `i + n <= line.a + lanes <= m.len` (asserted above).
                    unsafe { s.store(m.values.add(i), kept) };
                }
                s.keep_if_positive(over, scale)
            } else {
                // (l - longest) / (l w), with 1 / l from the lanes' reciprocal
                // square root.
                let shortening = s.sub(one_v, s.mul(longest_v, s.rsqrt_or_zero(l2, zero)));
                s.keep_if_positive(over, s.div(shortening, w))
            };
            // Exactly no move where none is due: a lane out of the class or past
            // the line may reach a ghost, whose move `0 d` would be NaN (and stay)
            // once a diverging neighbour's `d` is not finite.
            let d: [S::V; 3] = per_axis!(|axis| s.keep_if_positive(over, d[axis]));
            for (start, sign) in [(a, zero - one), (b, one)] {
                let k = s.mul(
                    s.mul(s.splat(sign), load(inv_mass.as_ptr(), start + j)),
                    scale,
                );
                for axis in 0..3 {
                    let t = s.mul(k, d[axis]);
                    let i = start + j;
                    // SAFETY: as above.
                    unsafe {
                        let new = moved::<S, FIXED>(s, load(pos[axis], i), one_v, t);
                        s.store(pos[axis].add(i), new);
                        let v = s.mul_add(t, inv_dt_v, load(vel[axis], i));
                        s.store(vel[axis].add(i), v);
                        if verlet {
                            let u = s.mul_add(t, inv_dt_v, load(upd[axis], i));
                            s.store(upd[axis].add(i), u);
                        }
                    }
                }
            }
        }};
    }
    // Blocks four at a time (then two, then one), all measured before any moves,
    // so that their measurements overlap in the core: a block's springs in the
    // class share no particle with the next block's, and a lane out of the class
    // moves nothing, so a block's moves change nothing the next one measured.
    macro_rules! blocks {
        ($j:expr; $($k:tt)+) => {{
            let j = $j;
            let m = ($(measure!(j + $k * n),)+);
            $(
                if m.$k.3 {
                    correct!(j + $k * n, m.$k.0, m.$k.1, m.$k.2);
                }
            )+
        }};
    }
    let mut j = 0;
    while j + 3 * n < lanes {
        blocks!(j; 0 1 2 3);
        j += 4 * n;
    }
    if j + n < lanes {
        blocks!(j; 0 1);
        j += 2 * n;
    }
    if j < lanes {
        blocks!(j; 0);
    }
}
