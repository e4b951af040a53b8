//! Provot's stretch limit on the grid: one Gauss-Seidel pass over the springs in
//! twelve sweeps (six stencil directions, two colour classes each), a class's
//! springs of one row corrected together in SIMD blocks ([`stretch_limit_line`]),
//! in bands of rows that stay in the core's cache, and most rows on two threads in
//! one hand-over ([`Kernel::stretch_limit_pass`]).

use std::ops::Range;

use super::super::duo::Duo;
#[cfg(target_arch = "x86_64")]
use super::x86;
use super::{BLOCK, Buf, Kernel, Out, PARALLEL_MIN_PARTICLES, Real, Simd, SimdLevel, add_double};

impl<E: Real> Kernel<E> {
    /// With double-float positions, how far (m) the high parts' difference may be
    /// from a spring's vector, with room to spare: a low part is at most half an
    /// ulp of its high part, so for coordinates up to `R` the two ends' low parts
    /// and the high parts' subtraction put it at most `4 R 2^-24` per coordinate
    /// away; this is `16 R 2^-23`. A spring whose high parts alone show it
    /// shorter than a bound less this is shorter than the bound (the stretch
    /// limit's `StretchLine::near2`, the tear scan's first look). 0 without low
    /// parts; infinite when a coordinate is not finite.
    pub(super) fn high_parts_slack(&self) -> f64 {
        if self.params.compensated {
            16.0 * largest_magnitude(self.simd, &self.cur.x) * f32::EPSILON as f64
        } else {
            0.0
        }
    }

    /// Provot's stretch limit `tau` (see [`Self::constrain`]): one Gauss-Seidel pass
    /// over the colour classes of [`crate::sim::springs::constraint_order`], the f64
    /// engine's order, each spring corrected as [`crate::sim::constraints::length_correction`]
    /// does. No two springs of a class share a particle, so a class's springs from
    /// one row are corrected together ([`stretch_limit_line`]); with `parallel`,
    /// most rows by two threads in one hand-over, with the same result as on one.
    pub(super) fn stretch_limit_pass(
        &mut self,
        tau: f64,
        dt: f64,
        parallel: bool,
        duo: Option<&Duo>,
    ) {
        let (w, h, st) = (self.grid.w, self.grid.h, self.grid.stride);
        let parallel = parallel && w * h >= PARALLEL_MIN_PARTICLES;
        let inv_dt = E::of(1.0 / dt);
        let compensated = self.params.compensated;
        let slack = self.high_parts_slack();
        // The sweeps in their order: each direction's two colour classes.
        let stencil = self.stencil();
        let sweeps: [Option<Sweep<E>>; 12] = std::array::from_fn(|k| {
            let (d, colour) = (k / 2, k % 2);
            let ((dr, dc), rest, present, _) = stencil[d];
            // Columns c with both ends on the cloth: 0 <= c + dc < w.
            let c0 = (-dc).max(0) as usize;
            let len = w.saturating_sub(dc.max(0) as usize).saturating_sub(c0);
            if !present || len == 0 || dr >= h {
                return None;
            }
            let near = ((1.0 + tau) * rest - slack).max(0.0);
            Some(Sweep {
                direction: d,
                dr,
                dc,
                c0,
                colour,
                rows: h - dr,
                line: StretchLine {
                    a: 0,
                    b: 0,
                    len,
                    class: StretchLine::class(c0, (dr == 0).then_some((colour, dc))),
                    longest: E::of((1.0 + tau) * rest),
                    near2: E::of(near * near * (1.0 - 1.0 / 65536.0)),
                    inv_dt,
                    compensated,
                },
            })
        });
        let (inv_mass, simd) = (self.inv_mass.as_slice(), self.simd);
        let torn = self.torn.as_ref();
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
                        let start = all.start.max(if t == from { 0 } else { cut(k, t) });
                        let end = all.end.min(cut(k, next)).min(sweep.rows);
                        if start >= end {
                            continue;
                        }
                        let alive = torn.map(|t| t.springs[sweep.direction].as_slice());
                        let lines = SweepLines {
                            sweep,
                            stride: st,
                            rows: start..end,
                        };
                        E::stretch_sweep(simd, out, first * st, inv_mass, alive, &lines);
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

/// One row's springs of one colour class of the stretch limit: the first ends at
/// array indices `a .. a + len`, the second ends at `b .. b + len`.
struct StretchLine<E> {
    a: usize,
    b: usize,
    len: usize,
    /// 1 for the lanes of a block in the class, else 0 (see [`StretchLine::class`]).
    class: [E; BLOCK],
    longest: E,
    /// With double-float positions, a squared length under which the high parts'
    /// difference shows a spring shorter than `longest` whatever the low parts: a
    /// low part is at most half an ulp of its high part, so the two ends' low parts
    /// and the high parts' subtraction put the difference at most `4 R 2^-24` per
    /// coordinate from the spring's vector, for coordinates of magnitude up to `R`
    /// (which a pass does not raise: it moves a particle towards the other end of
    /// a spring). `near2` is `(longest - 16 R 2^-23)²`, less 2^-16 of it for the
    /// float32 rounding of the squared lengths.
    near2: E,
    inv_dt: E,
    compensated: bool,
}

impl<E: Real> StretchLine<E> {
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

/// One sweep of the stretch limit: the springs of one stencil direction `(dr, dc)`
/// in one colour class, a [`StretchLine`] per row.
pub(super) struct Sweep<E> {
    /// Index of the direction in the stencil (and of its tear masks).
    direction: usize,
    dr: usize,
    dc: isize,
    /// First column with both ends on the cloth.
    c0: usize,
    colour: usize,
    /// Rows with both ends on the cloth: `0 .. rows`.
    rows: usize,
    /// The line of row 0 (its `a` and `b` set per row by [`Sweep::line_at`]).
    line: StretchLine<E>,
}

impl<E: Real> Sweep<E> {
    /// The rows of `rows` whose springs are in the class: every row along rows
    /// (the class is a pattern of columns), else rows `2 dr m + dr colour + j`,
    /// `j < dr`.
    fn lines(&self, rows: Range<usize>) -> impl Iterator<Item = usize> + '_ {
        rows.filter(|r| self.dr == 0 || (r / self.dr) % 2 == self.colour)
    }

    /// Whether positions have low parts.
    pub(super) fn compensated(&self) -> bool {
        self.line.compensated
    }

    /// The line of row `r` (rows `stride` floats apart).
    fn line_at(&self, r: usize, stride: usize) -> StretchLine<E> {
        StretchLine {
            a: r * stride + self.c0,
            b: ((r + self.dr) * stride + self.c0).wrapping_add_signed(self.dc),
            ..self.line
        }
    }
}

/// The lines of a [`Sweep`] starting on `rows`, rows `stride` floats apart.
pub(super) struct SweepLines<'a, E> {
    pub(super) sweep: &'a Sweep<E>,
    pub(super) stride: usize,
    pub(super) rows: Range<usize>,
}

/// [`stretch_limit_line`] on each line of `lines`, in order of rows (one call for
/// a sweep, where a call per line cost its set-up every 8 blocks at 128 columns).
#[inline(always)]
pub(super) fn stretch_limit_sweep<S: Simd, const LO: bool>(
    s: S,
    out: &mut Out<S::E>,
    base: usize,
    inv_mass: &[S::E],
    alive: Option<&[S::E]>,
    lines: &SweepLines<S::E>,
) {
    for r in lines.sweep.lines(lines.rows.clone()) {
        let line = lines.sweep.line_at(r, lines.stride);
        stretch_limit_line::<S, LO>(s, out, base, inv_mass, alive, &line);
    }
}

/// Corrects the springs of `line` that are longer than `line.longest` as
/// [`crate::sim::constraints::length_correction`] does, in `out` (the state's
/// arrays from array index `base` on), in blocks of `S::LANES` springs, four
/// blocks' lengths at a time (with double-float positions, from the high parts
/// first, and from both parts only when those come near the limit:
/// [`StretchLine::near2`]), then for
/// each block with a spring over the limit its corrections and at once the moves
/// of its first ends and of its second ends. Each particle has at most one spring
/// in a class, so the moves do not interact: a lane out of the class (or past the
/// line, or a spring that tore: 0 in `alive`, the direction's mask, when some did)
/// gets a move of 0, which leaves its particle as it was. A move `δ` adds `δ / h`
/// to the velocity (and to Verlet's `u`). The lanes past `len` reach ghost columns
/// inside the row's padding (rows are [`BLOCK`] floats longer than their blocks).
#[inline(always)]
fn stretch_limit_line<S: Simd, const LO: bool>(
    s: S,
    out: &mut Out<S::E>,
    base: usize,
    inv_mass: &[S::E],
    alive: Option<&[S::E]>,
    line: &StretchLine<S::E>,
) {
    let n = S::LANES;
    let &StretchLine {
        len,
        longest,
        inv_dt,
        ..
    } = line;
    let (zero, one) = (S::E::ZERO, S::E::ONE);
    let (a, b) = (line.a - base, line.b - base);
    let lanes = len.next_multiple_of(n);
    let end = a.max(b) + lanes;
    let inv_mass = &inv_mass[base..];
    let [x, y, z, xl, yl, zl, vx, vy, vz, ux, uy, uz] = &mut out.0;
    let verlet = !ux.is_empty();
    let fits = |arrays: [&[S::E]; 3]| arrays.iter().all(|p| p.len() >= end);
    // Every block below reads and writes inside these bounds.
    assert!(inv_mass.len() >= end && fits([x, y, z]) && fits([vx, vy, vz]));
    assert!((!LO || fits([xl, yl, zl])) && (!verlet || fits([ux, uy, uz])));
    let alive = alive.map(|m| &m[line.a..line.a + lanes]);
    let pos = [x.as_mut_ptr(), y.as_mut_ptr(), z.as_mut_ptr()];
    let low = [xl.as_mut_ptr(), yl.as_mut_ptr(), zl.as_mut_ptr()];
    let vel = [vx.as_mut_ptr(), vy.as_mut_ptr(), vz.as_mut_ptr()];
    let upd = [ux.as_mut_ptr(), uy.as_mut_ptr(), uz.as_mut_ptr()];
    let (longest2, inv_dt_v) = (s.splat(longest * longest), s.splat(inv_dt));
    let (near2, zero_v) = (s.splat(line.near2), s.splat(zero));
    let (longest_v, one_v) = (s.splat(longest), s.splat(one));
    // SAFETY (every load and store below): `j + n <= lanes`, and the arrays hold
    // `a + lanes` and `b + lanes` floats (asserted above).
    let load = |p: *const S::E, i: usize| unsafe { s.load(p.add(i)) };
    // Squared lengths of the vectors `d`.
    macro_rules! length2 {
        ($d:expr) => {{
            let d = $d;
            s.mul_add(d[0], d[0], s.mul_add(d[1], d[1], s.mul(d[2], d[2])))
        }};
    }
    // The block at `j`: its springs' vectors `d` (first end less second), their
    // squared lengths, positive where a spring is in the class and over the limit,
    // and whether any is (with the high parts' vectors and zeros when, with
    // double-float positions, those alone show none near the limit).
    macro_rules! measure {
        ($j:expr) => {{
            let j = $j;
            let high: [S::V; 3] =
                std::array::from_fn(|k| s.sub(load(pos[k], a + j), load(pos[k], b + j)));
            let mut keep = load(line.class.as_ptr(), 0);
            if j + n > len {
                let tail: [S::E; BLOCK] =
                    std::array::from_fn(|l| if j + l < len { one } else { zero });
                keep = s.mul(keep, load(tail.as_ptr(), 0));
            }
            if let Some(m) = alive {
                keep = s.mul(keep, load(m.as_ptr(), j));
            }
            if LO && !s.any_positive(s.mul_sub(length2!(high), keep, near2)) {
                // The high parts alone show every spring within the limit.
                (high, zero_v, zero_v, false)
            } else {
                let d: [S::V; 3] = if LO {
                    std::array::from_fn(|k| {
                        s.add(high[k], s.sub(load(low[k], a + j), load(low[k], b + j)))
                    })
                } else {
                    high
                };
                let l2 = length2!(d);
                // Positive where the spring is in the class and over the limit.
                let over = s.mul_sub(l2, keep, longest2);
                (d, l2, over, s.any_positive(over))
            }
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
            // Positive where a spring over the limit is not pinned at both ends.
            let over = s.keep_if_positive(w, over);
            // (l - longest) / (l w), with 1 / l from the lanes' reciprocal square root.
            let shortening = s.sub(one_v, s.mul(longest_v, s.rsqrt_or_zero(l2, zero)));
            let scale = s.keep_if_positive(over, s.div(shortening, w));
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
                        if LO {
                            let old = (load(pos[axis], i), load(low[axis], i));
                            let (hi, lo) = add_double(s, old, t);
                            s.store(pos[axis].add(i), hi);
                            s.store(low[axis].add(i), lo);
                        } else {
                            s.store(pos[axis].add(i), s.add(load(pos[axis], i), t));
                        }
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

/// The largest magnitude of the coordinates in `arrays` (infinite when one is not
/// finite, and for float64 arrays, which have no low parts to bound).
fn largest_magnitude<E: Real>(simd: SimdLevel, arrays: &[Buf<E>; 3]) -> f64 {
    let mut bits = 0;
    for a in arrays {
        let Ok(a) = bytemuck::try_cast_slice::<E, u32>(a.as_slice()) else {
            return f64::INFINITY;
        };
        bits = bits.max(match simd {
            #[cfg(target_arch = "x86_64")]
            // SAFETY: the level is AVX2 or AVX-512 only when the CPU has AVX2.
            SimdLevel::Avx2 | SimdLevel::Avx512 => unsafe { x86::largest_magnitude_bits_avx2(a) },
            _ => largest_magnitude_bits(a),
        });
    }
    match f32::from_bits(bits) {
        m if m.is_nan() => f64::INFINITY,
        m => m as f64,
    }
}

/// The largest of the float32 bit patterns `bits` with the sign bit cleared: the
/// bits of the largest magnitude, as the bits of floats of one sign order as
/// their magnitudes do (a NaN's above infinity's). A plain reduction for the
/// compiler to vectorise.
#[inline(always)]
pub(super) fn largest_magnitude_bits(bits: &[u32]) -> u32 {
    bits.iter().fold(0, |m, &b| m.max(b & !(1 << 31)))
}
