//! The vector code of a spring pass: [`spring_sweep`] runs a sweep's lines,
//! [`spring_line`] corrects one row's springs of a colour class in SIMD blocks,
//! and [`row_line`] the stretch limit's springs along a row, both colours at once.

use super::sweep::{LineRule, Sweep, SweepLines, SweepMultipliers};
use crate::sim::grid_kernel::row::{difference, lanes3, moved};
use crate::sim::grid_kernel::simd::{Vector, align_frame};
use crate::sim::grid_kernel::{BLOCK, Out, Real, Simd};
use crate::sim::laws::{self, XpbdCoefficients};

/// [`spring_line`] on each line of `lines`, in order of rows: one call for a
/// sweep, where a call per line cost its set-up every 8 blocks at 128 columns.
/// What the lines share ([`LineKernel`]: the rule's constants, the arrays, the
/// bounds) is set up once; a line is then its two offsets.
#[inline(always)]
pub(in crate::sim::grid_kernel) fn spring_sweep<S: Simd, const FIXED: bool>(
    s: S,
    out: &mut Out<S::E>,
    base: usize,
    lines: &SweepLines<S::E>,
) {
    align_frame();
    let Some(kernel) = LineKernel::new(s, out, base, lines) else {
        return;
    };
    let (stride, sweep) = (lines.stride, lines.sweep);
    let rows = sweep.lines(lines.rows.clone());
    // The lanes' masks (torn springs, ghosts) are tested in the blocks only when
    // there are some, not in every block of every sweep.
    macro_rules! run {
        ($xpbd:literal, $masked:literal) => {
            for r in rows.flatten() {
                let line = sweep.line_at(r, stride);
                // SAFETY: every line of the sweep is inside the bounds that
                // `LineKernel::new` asserted.
                unsafe { spring_line::<S, FIXED, $xpbd, $masked>(&kernel, (line.a, line.b)) };
            }
        };
    }
    let masked = kernel.alive.is_some() || kernel.real.is_some();
    // Both colours of the stretch limit along rows, row by row ([`row_line`]).
    if lines.both_colours {
        assert!(
            matches!(sweep.line.rule, LineRule::Limit { .. }) && !masked && sweep.dr == 0,
            "both colours run together only for the stretch limit along rows, without masks"
        );
        let blocks = RowBlocks::new(&kernel, sweep, lines);
        for r in rows.flatten() {
            let row = sweep.line_at(r, stride).a;
            // SAFETY: every row of the sweep is inside the bounds that
            // `RowBlocks::new` asserted.
            unsafe {
                match sweep.dc {
                    1 => row_line::<S, FIXED, 1>(&kernel, &blocks, row),
                    2 => row_line::<S, FIXED, 2>(&kernel, &blocks, row),
                    dc => unreachable!("no direction along rows is {dc} columns long"),
                }
            }
        }
        return;
    }
    match (sweep.line.rule, masked) {
        (LineRule::Limit { .. }, false) => run!(false, false),
        (LineRule::Limit { .. }, true) => run!(false, true),
        (LineRule::Xpbd { .. }, false) => run!(true, false),
        (LineRule::Xpbd { .. }, true) => run!(true, true),
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

/// How a row's springs along it (`dr` 0, `dc` 1 or 2) are covered when both
/// colour classes run together ([`row_line`]): in `blocks` blocks of `LANES`
/// springs from the row's first column, every spring of a block measured once for
/// both colours; the squared limit of the last block on the row (`limit_last`:
/// infinite in its lanes past the row, see [`LineKernel::over`]), and per colour
/// the lanes of its [`pair_block`] in the last block with both ends on the cloth
/// (`pairs_last`).
struct RowBlocks<V> {
    blocks: usize,
    limit_last: V,
    pairs_last: [V; 2],
}

impl<V: Copy> RowBlocks<V> {
    /// The blocks of `lines`' sweep (colour 0 of a direction along rows, the
    /// class whose blocks start on a row's first column), after asserting that
    /// every array holds what the last line reaches.
    #[inline(always)]
    fn new<S: Simd<V = V>>(
        k: &LineKernel<S>,
        sweep: &Sweep<S::E>,
        lines: &SweepLines<S::E>,
    ) -> Self {
        let n = S::LANES;
        let dc = sweep.dc.unsigned_abs();
        let len = sweep.line.len;
        let width = len + dc;
        let blocks = len.div_ceil(n);
        // A block's lanes pair up within it (`n` is a multiple of `2 dc`), and
        // its lanes' colours are the same pattern in every block.
        assert!(n.is_multiple_of(2 * dc) && n <= BLOCK);
        assert!(sweep.class.colour == 0 && sweep.c0 == 0 && blocks > 0);
        if let Some(r) = lines.rows.clone().last() {
            // The furthest a line reaches: its second colour's pair block in
            // its last block, `dc` columns on.
            let end = sweep.line_at(r, lines.stride).a + dc + blocks * n;
            assert!(end >= k.base && lines.inv_mass.len() >= end);
            // The state's arrays, as long as `LineKernel::new` found them.
            assert!(end - k.base <= k.state_len);
        }
        let (zero, one) = (S::E::ZERO, S::E::ONE);
        let lanes_of = |f: &dyn Fn(usize) -> S::E| -> V {
            let a: [S::E; BLOCK] = std::array::from_fn(f);
            // SAFETY: `a` holds `BLOCK >= LANES` floats.
            unsafe { k.s.load(a.as_ptr()) }
        };
        let lanes =
            |f: &dyn Fn(usize) -> bool| lanes_of(&|l| if l < n && f(l) { one } else { zero });
        // The colour of lane `l`'s spring, and whether the lane is a first end
        // of its pair block's spring.
        let colour = |l: usize| (l / dc) % 2;
        let last = (blocks - 1) * n;
        let limit_last = lanes_of(&|l| limit2_of(k.longest2_value, last + l < len));
        let pairs_last = [0, 1].map(|c| {
            lanes(&|l| {
                let column = c * dc + last + l;
                let far = if colour(l) == 0 { column + dc } else { column };
                far < width
            })
        });
        RowBlocks {
            blocks,
            limit_last,
            pairs_last,
        }
    }
}

/// The stretch limit on both colour classes of a row's springs along it, `dc` 1
/// or 2 columns long, the row's first column at array index `row`: the two
/// sweeps' Gauss-Seidel order, each spring measured once where nothing moves it.
///
/// A colour's springs share no particle, and a spring of colour 1 shares
/// particles only with springs of colour 0 in its own block and the next one
/// (its second end is at most `dc` columns past its block). The row's blocks of
/// `LANES` springs are measured first, both colours at once. Colour 0 is then
/// corrected in the blocks with a spring over the limit, and colour 1 in those
/// and in the blocks before them (where colour 0 may have moved a particle), by
/// [`pair_block`], which measures the colour's springs again: every other
/// spring of colour 1 is as it was measured, within the limit. Each particle
/// sees its colour-0 move before its colour-1 move, and each colour-1 spring
/// every colour-0 move, as when the two sweeps run one after the other. (A row
/// of more than 64 blocks runs in chunks of 64, a chunk's last block's colour 1
/// after the next chunk's colour 0.) Where few springs are over the limit, a
/// spring costs a lane of one block, not the two of a block of pairs.
///
/// # Safety
/// The row is one of the sweep whose bounds `k` and `blocks` asserted
/// ([`LineKernel::new`], [`RowBlocks::new`]).
#[inline(always)]
unsafe fn row_line<S: Simd, const FIXED: bool, const DC: usize>(
    k: &LineKernel<S>,
    blocks: &RowBlocks<S::V>,
    row: usize,
) {
    let s = k.s;
    let n = S::LANES;
    let first = row - k.base;
    // SAFETY (every load below): `j + DC + n <= first + DC + blocks n`, inside
    // the arrays (asserted by `RowBlocks::new`).
    let load = |p: *const S::E, i: usize| unsafe { s.load(p.add(i)) };
    // The lanes of the block at `j` whose spring is over the limit (`$limit2`:
    // the squared limit, infinite in lanes past the row). (Macros, not closures:
    // closures did not take the function's target features, and their vector
    // operations ran as calls.)
    macro_rules! over {
        ($j:expr, $limit2:expr) => {{
            let j = $j;
            let d: [S::V; 3] =
                per_axis!(|i| difference::<S, FIXED>(s, load(k.pos[i], j), load(k.pos[i], j + DC)));
            k.over(d, $limit2)
        }};
    }
    // Colour `c`'s springs in block `m`, corrected.
    macro_rules! correct {
        ($c:expr, $m:expr) => {{
            let (c, m) = ($c, $m);
            let keep = if m + 1 == blocks.blocks {
                blocks.pairs_last[c]
            } else {
                k.one
            };
            // SAFETY: the pair block is inside the row's reach (see above).
            unsafe { pair_block::<S, FIXED, DC>(k, first + c * DC + m * n, keep) };
        }};
    }
    // The row in chunks of up to 64 blocks: each chunk's blocks measured, then
    // its colour 0 corrected where a block has a spring over the limit, then its
    // colour 1 there and where colour 0 may have moved a particle (in the block
    // or the next one), each by `pair_block`, which measures its colour's
    // springs again. A chunk's last block's colour 1 waits for the next chunk's
    // colour 0.
    let mut carried = false;
    let mut m0 = 0;
    while m0 < blocks.blocks {
        let count = (blocks.blocks - m0).min(64);
        // The chunk's blocks with every lane on the row: all but the row's last.
        let on_row = if m0 + count == blocks.blocks {
            count - 1
        } else {
            count
        };
        // Bit `i`: a spring of block `m0 + i` is over. Four blocks are tested
        // at once, and each of them only where one is over; the chunk's last
        // four blocks close it (setting again the bits of those tested before),
        // where single blocks cost more. The last of them takes `last_limit2`:
        // the row's last block's limit where the chunk ends the row.
        let last_limit2 = if on_row < count {
            blocks.limit_last
        } else {
            k.longest2
        };
        let mut over = 0u64;
        macro_rules! four_from {
            ($i:expr, $last_limit2:expr) => {{
                let i = $i;
                let j = first + (m0 + i) * n;
                let limit2 = |b: usize| if b == 3 { $last_limit2 } else { k.longest2 };
                let some = s.either(
                    s.either(over!(j, limit2(0)), over!(j + n, limit2(1))),
                    s.either(over!(j + 2 * n, limit2(2)), over!(j + 3 * n, limit2(3))),
                );
                if s.any(some) {
                    for b in 0..4 {
                        over |= (s.any(over!(j + b * n, limit2(b))) as u64) << (i + b);
                    }
                }
            }};
        }
        let mut i = 0;
        while i + 4 <= on_row {
            four_from!(i, k.longest2);
            i += 4;
        }
        if i < count && count >= 4 {
            four_from!(count - 4, last_limit2);
        } else {
            while i < count {
                let limit2 = if i + 1 == count {
                    last_limit2
                } else {
                    k.longest2
                };
                over |= (s.any(over!(first + (m0 + i) * n, limit2)) as u64) << i;
                i += 1;
            }
        }
        let mut todo = over;
        while todo != 0 {
            correct!(0, m0 + todo.trailing_zeros() as usize);
            todo &= todo - 1;
        }
        if m0 > 0 && (carried || over & 1 != 0) {
            correct!(1, m0 - 1);
        }
        let mut todo = over | (over >> 1);
        if m0 + count < blocks.blocks {
            let last = 1u64 << (count - 1);
            carried = todo & last != 0;
            todo &= !last;
        }
        while todo != 0 {
            correct!(1, m0 + todo.trailing_zeros() as usize);
            todo &= todo - 1;
        }
        m0 += count;
    }
}

/// The stretch limit on the springs of one colour along a row, `DC` columns
/// long, in the block of lanes at array index `j` (from the kernel's base) that
/// holds both ends of its springs: lanes `l` and `l ^ DC` are the two ends of one
/// ([`Simd::swap_pairs`]), the lanes of `keep` on the cloth. Each lane takes its
/// end's move, `-w d s` with `d` its end less the other (the first end's `d`
/// negated at the second) and `s` the spring's scale: the same numbers, in the
/// same operations, as [`spring_line`] gives each end (which stores the first
/// ends' block and loads the second ends' block `dc` lanes on: a load that
/// overlaps a store just made waits for it to reach the cache).
///
/// # Safety
/// `j + LANES` is inside the state's arrays and the inverse masses.
#[inline(always)]
unsafe fn pair_block<S: Simd, const FIXED: bool, const DC: usize>(
    k: &LineKernel<S>,
    j: usize,
    keep: S::V,
) {
    let s = k.s;
    let (zero, one) = (S::E::ZERO, S::E::ONE);
    // SAFETY (every load below): the caller's contract.
    let load = |p: *const S::E, i: usize| unsafe { s.load(p.add(i)) };
    let x: [S::V; 3] = per_axis!(|i| load(k.pos[i], j));
    let d: [S::V; 3] = per_axis!(|i| difference::<S, FIXED>(s, x[i], s.swap_pairs::<DC>(x[i])));
    let l2 = k.length2(d);
    let over = k.over_limit(l2, keep);
    if !s.any_positive(over) {
        return;
    }
    let inv_mass = load(k.inv_mass, j);
    let w = s.add(inv_mass, s.swap_pairs::<DC>(inv_mass));
    let over = s.keep_if_positive(w, over);
    let scale = k.limit_scale(d, w, over);
    let d: [S::V; 3] = per_axis!(|i| s.keep_if_positive(over, d[i]));
    let f = s.mul(s.mul(s.splat(zero - one), inv_mass), scale);
    for axis in 0..3 {
        // SAFETY: as above.
        unsafe { k.move_by::<FIXED>(axis, j, x[axis], s.mul(f, d[axis])) };
    }
}

/// What the lines of one [`SweepLines`] share, splatted and checked once: the
/// rule's constants, the class's lanes, and raw pointers to the arrays (the
/// state's from array index `base` on, the rest from 0), whose bounds hold every
/// line of the sweep.
struct LineKernel<S: Simd> {
    s: S,
    /// Springs in a line, and the lanes of its blocks (`len` rounded up).
    len: usize,
    lanes: usize,
    base: usize,
    /// [`SpringLine::class`], and times the lanes inside the line in its last
    /// block.
    class: S::V,
    class_tail: S::V,
    /// The squared limit in the lanes of `class` and of `class_tail`, infinite
    /// in the others ([`Self::over`]).
    class_limit2: S::V,
    class_tail_limit2: S::V,
    /// 1 in the lanes past the line's end in its last block.
    past_tail: S::V,
    longest: S::V,
    longest2: S::V,
    /// `longest2`'s value, for the limits of [`limit2_of`].
    longest2_value: S::E,
    rest: S::V,
    alpha: S::V,
    minus_alpha: S::V,
    gamma: S::V,
    one_gamma: S::V,
    one: S::V,
    inv_dt: S::V,
    pos: [*mut S::E; 3],
    vel: [*mut S::E; 3],
    /// Verlet's update velocities (empty without Verlet).
    upd: [*mut S::E; 3],
    verlet: bool,
    /// The floats every state array holds from `base` on.
    state_len: usize,
    inv_mass: *const S::E,
    start: [*const S::E; 3],
    alive: Option<*const S::E>,
    real: Option<*const S::E>,
    multipliers: Option<SweepMultipliers<S::E>>,
}

impl<S: Simd> LineKernel<S> {
    /// The squared lengths of springs of vectors `d`, as the laws measure them
    /// ([`laws::length_factor`]'s `d·d`). Every path of the pass measures with
    /// this one sum, so that a spring `row_line` found within the limit is found
    /// within it when measured again.
    #[inline(always)]
    fn length2(&self, d: [S::V; 3]) -> S::V {
        let d = lanes3(self.s, d);
        d.dot(d).1
    }

    /// Positive in the lanes of `keep` (1 or 0) whose squared length `l2` is
    /// over the stretch limit's.
    #[inline(always)]
    fn over_limit(&self, l2: S::V, keep: S::V) -> S::V {
        self.s.mul_sub(l2, keep, self.longest2)
    }

    /// The lanes whose spring of vector `d` is over `limit2`: the squared limit
    /// in the lanes kept, infinite in the others ([`limit2_of`]). The one
    /// test of the sweeps that skip blocks, so that a block skipped is one that
    /// [`pair_block`] and `spring_line`'s correction would leave as it is: they
    /// measure with [`Self::length2`] and correct where [`Self::over_limit`] is
    /// positive, which for `keep` 1 is where `l2 > longest²` (the difference of
    /// two normal floats keeps its sign when rounded) and for `keep` 0 nowhere,
    /// as `l2 > ∞` (one comparison a block, where the difference and its sign
    /// were two).
    #[inline(always)]
    fn over(&self, d: [S::V; 3], limit2: S::V) -> S::Mask {
        self.s.gt(self.length2(d), limit2)
    }

    /// The stretch limit's scale of springs of vectors `d` and summed inverse
    /// masses `w`, where `over` is positive, else 0: [`laws::length_factor`] to
    /// `longest`. An end moves by `∓` its inverse mass times the scale times the
    /// spring's vector.
    #[inline(always)]
    fn limit_scale(&self, d: [S::V; 3], w: S::V, over: S::V) -> S::V {
        let s = self.s;
        let scale = laws::length_factor(lanes3(s, d), Vector(s, self.longest), Vector(s, w));
        s.keep_if_positive(over, scale.1)
    }

    /// Moves the particles at array index `i` (from `base`), at `x` along `axis`
    /// as stored, by `t` units (rounded to a whole unit in fixed point), and adds
    /// `t / h` to their velocities (and Verlet's): see [`spring_line`].
    ///
    /// # Safety
    /// `i + LANES` is inside the state's arrays.
    #[inline(always)]
    unsafe fn move_by<const FIXED: bool>(&self, axis: usize, i: usize, x: S::V, t: S::V) {
        let s = self.s;
        // SAFETY: inside the arrays (the caller's contract).
        unsafe {
            s.store(self.pos[axis].add(i), moved::<S, FIXED>(s, x, self.one, t));
            let v = self.vel[axis].add(i);
            s.store(v, s.mul_add(t, self.inv_dt, s.load(v)));
            if self.verlet {
                let u = self.upd[axis].add(i);
                s.store(u, s.mul_add(t, self.inv_dt, s.load(u)));
            }
        }
    }

    /// The kernel of `lines` on `out` (the state's arrays from array index `base`
    /// on), after asserting that every array holds what the sweep's first and
    /// last lines reach (lines further down reach further); `None` without lines.
    #[inline(always)]
    fn new(s: S, out: &mut Out<S::E>, base: usize, lines: &SweepLines<S::E>) -> Option<Self> {
        let n = S::LANES;
        let sweep = lines.sweep;
        let line = &sweep.line;
        let rows = lines.rows.clone();
        if rows.is_empty() {
            return None;
        }
        let (first, last) = (
            sweep.line_at(rows.start, lines.stride),
            sweep.line_at(rows.end - 1, lines.stride),
        );
        let len = line.len;
        let lanes = len.next_multiple_of(n);
        // The state's arrays, the inverse masses and the ghosts' mask from `base`:
        // every line's ends from the first's (the second end is below or right of
        // the first) to the last's, `lanes` floats each.
        assert!(first.a >= base && first.b >= base);
        // The last line's reach: from index 0 (`whole_end`), and from `base`.
        let whole_end = last.a.max(last.b) + lanes;
        let end = whole_end - base;
        let [x, y, z, vx, vy, vz, ux, uy, uz] = &mut out.0;
        let verlet = !ux.is_empty();
        let fits = |arrays: [&[S::E]; 3], end: usize| arrays.iter().all(|p| p.len() >= end);
        let shortest = |arrays: [&[S::E]; 3]| arrays.iter().map(|a| a.len()).min().unwrap_or(0);
        let state_len = shortest([x, y, z]).min(shortest([vx, vy, vz]));
        let state_len = if verlet {
            state_len.min(shortest([ux, uy, uz]))
        } else {
            state_len
        };
        assert!(lines.inv_mass.len() >= whole_end);
        assert!(fits([x, y, z], end) && fits([vx, vy, vz], end));
        assert!(!verlet || fits([ux, uy, uz], end));
        let xpbd = matches!(line.rule, LineRule::Xpbd { .. });
        assert!(!xpbd || fits(lines.start, whole_end));
        let multipliers = lines.multipliers.filter(|_| xpbd);
        assert!(multipliers.is_none_or(|m| m.len >= last.a + lanes));
        assert!(lines.alive.is_none_or(|m| m.len() >= last.a + lanes));
        assert!(lines.real.is_none_or(|m| m.len() >= whole_end));
        let (zero, one) = (S::E::ZERO, S::E::ONE);
        let (longest, rest, alpha, gamma) = match line.rule {
            LineRule::Limit { longest } => (longest, zero, zero, zero),
            LineRule::Xpbd { rest, alpha, gamma } => (zero, rest, alpha, gamma),
        };
        let tail: [S::E; BLOCK] =
            std::array::from_fn(|l| if lanes - n + l < len { one } else { zero });
        let past: [S::E; BLOCK] = tail.map(|t| one - t);
        let class = line.class;
        let class_tail: [S::E; BLOCK] = std::array::from_fn(|l| class[l] * tail[l]);
        let longest2 = longest * longest;
        let limit2 = |kept: [S::E; BLOCK]| kept.map(|k| limit2_of(longest2, k == one));
        // SAFETY: the arrays hold at least `BLOCK >= LANES` floats.
        let splat_block = |a: &[S::E; BLOCK]| unsafe { s.load(a.as_ptr()) };
        Some(LineKernel {
            s,
            len,
            lanes,
            base,
            class: splat_block(&class),
            class_tail: splat_block(&class_tail),
            class_limit2: splat_block(&limit2(class)),
            class_tail_limit2: splat_block(&limit2(class_tail)),
            past_tail: splat_block(&past),
            longest: s.splat(longest),
            longest2: s.splat(longest2),
            longest2_value: longest2,
            rest: s.splat(rest),
            alpha: s.splat(alpha),
            minus_alpha: s.splat(zero - alpha),
            gamma: s.splat(gamma),
            one_gamma: s.splat(one + gamma),
            one: s.splat(one),
            inv_dt: s.splat(line.inv_dt),
            pos: [x.as_mut_ptr(), y.as_mut_ptr(), z.as_mut_ptr()],
            vel: [vx.as_mut_ptr(), vy.as_mut_ptr(), vz.as_mut_ptr()],
            upd: [ux.as_mut_ptr(), uy.as_mut_ptr(), uz.as_mut_ptr()],
            verlet,
            state_len,
            // SAFETY: `base <= first.a <= inv_mass.len()` (asserted).
            inv_mass: unsafe { lines.inv_mass.as_ptr().add(base) },
            start: lines.start.map(<[S::E]>::as_ptr),
            alive: lines.alive.map(<[S::E]>::as_ptr),
            // SAFETY: as for the inverse masses.
            real: lines.real.map(|m| unsafe { m.as_ptr().add(base) }),
            multipliers,
        })
    }
}

/// A lane's squared limit for [`LineKernel::over`]: `longest2` where the lane is
/// kept, else infinite.
fn limit2_of<E: Real>(longest2: E, kept: bool) -> E {
    if kept { longest2 } else { E::of(f64::INFINITY) }
}

/// Corrects the springs of the line whose first ends are at array indices `line.0
/// .. + len` and second ends at `line.1 .. + len`, in blocks of `S::LANES`
/// springs, four blocks at a time: measures them all, then for each block with a
/// spring to correct its corrections and at once the moves of its first ends and
/// of its second ends. The stretch limit without masks first tests the four
/// blocks (and the blocks left at the line's end) with nothing kept, and goes on
/// only where a spring is over the limit.
///
/// * The stretch limit (`XPBD` false) corrects the springs longer than `longest`
///   by [`crate::sim::laws::length_factor`].
/// * XPBD corrects every spring by [`crate::sim::laws::xpbd_factor`]
///   from the positions at the start of the step in `lines.start`.
///
/// Each particle has at most one spring in a class, so the moves do not interact:
/// a lane out of the class (or past the line, or a spring that tore: 0 in the
/// direction's mask, when some did, tested with `MASKED`) gets a move of 0, which
/// leaves its particle as it was. A move `δ` adds `δ / h` to the velocity (and to
/// Verlet's `u`): the move as computed, where fixed-point positions take it
/// rounded to a whole unit, so that the part of it under half a unit reaches the
/// position through the velocity at the next step rather than never (a correction
/// that stayed under half a unit step after step, as XPBD's small ones of a cloth
/// do, was lost whole: XPBD's drape parted from the f64 engine by 9e-5 m over 320
/// steps, 3e-6 m so). The lanes past `len` reach ghost columns inside the row's
/// padding (rows are [`BLOCK`] floats longer than their blocks).
///
/// # Safety
/// The line is one of the sweep whose bounds `k` asserted ([`LineKernel::new`]).
#[inline(always)]
unsafe fn spring_line<S: Simd, const FIXED: bool, const XPBD: bool, const MASKED: bool>(
    k: &LineKernel<S>,
    (line_a, line_b): (usize, usize),
) {
    let s = k.s;
    let n = S::LANES;
    let (len, lanes) = (k.len, k.lanes);
    let line = LineEnds::<S, FIXED, XPBD, MASKED>::new(k, (line_a, line_b));
    // Blocks four at a time (then two, then one), all measured before any moves,
    // so that their measurements overlap in the core: a block's springs in the
    // class share no particle with the next block's, and a lane out of the class
    // moves nothing, so a block's moves change nothing the next one measured.
    // (`$tail`: whether the block may be the line's last, with lanes past it.)
    // SAFETY (every block): `j + n <= lanes` (see `LineEnds`).
    macro_rules! blocks {
        ($tail:literal; $j:expr; $($b:tt)+) => {{
            let j = $j;
            let m = ($(unsafe { line.measure::<$tail>(j + $b * n) },)+);
            $(
                if m.$b.2 {
                    unsafe { line.correct(j + $b * n, m.$b.0, m.$b.1) };
                }
            )+
        }};
    }
    // The blocks below `whole` have no lanes past the line: they take the class's
    // lanes without a test (the sheet at 128: 0.45 instructions a particle-step
    // fewer).
    let whole = len - len % n;
    // The stretch limit without masks tests four blocks at once first, with
    // nothing kept from it: most groups of blocks have no spring to correct.
    let zero_lanes = s.splat(S::E::ZERO);
    // SAFETY (each test): as above.
    macro_rules! over {
        ($j:expr) => {
            over!($j, k.class_limit2)
        };
        ($j:expr, $limit2:expr) => {
            unsafe { line.over($j, $limit2) }
        };
    }
    let mut j = 0;
    while j + 4 * n <= whole {
        if XPBD
            || MASKED
            || s.any(s.either(
                s.either(over!(j), over!(j + n)),
                s.either(over!(j + 2 * n), over!(j + 3 * n)),
            ))
        {
            blocks!(false; j; 0 1 2 3);
        }
        j += 4 * n;
    }
    // The blocks left (at most four), likewise tested together first: four
    // (three whole and the last, as on the diagonals' lines of a 128-column
    // cloth) written out.
    if !XPBD && !MASKED && lanes - j == 4 * n {
        debug_assert!(j + 3 * n == whole);
        let some = s.either(
            s.either(over!(j), over!(j + n)),
            s.either(over!(j + 2 * n), over!(j + 3 * n, k.class_tail_limit2)),
        );
        if !s.any(some) {
            return;
        }
    } else if !XPBD && !MASKED {
        let mut some = s.gt(zero_lanes, zero_lanes);
        let mut i = j;
        while i < lanes {
            let limit2 = if i + n > len {
                k.class_tail_limit2
            } else {
                k.class_limit2
            };
            some = s.either(some, over!(i, limit2));
            i += n;
        }
        if !s.any(some) {
            return;
        }
    }
    if j + 2 * n <= whole {
        blocks!(false; j; 0 1);
        j += 2 * n;
    }
    while j < lanes {
        blocks!(true; j; 0);
        j += n;
    }
}

/// One line of [`spring_line`]: its kernel, and its springs' first and second
/// ends as array indices from the kernel's `base` (`a`, `b`) and from 0 (`line_a`,
/// `line_b`, which index the starting positions, masks and multipliers). Each
/// block's method takes the block's offset `j` in the line.
///
/// SAFETY (every load and store of the methods, whose callers keep `j + LANES <=
/// lanes`): the arrays hold `a + lanes` and `b + lanes` floats from `base` on (the
/// starting positions, the masks of torn springs and the multipliers `line_a +
/// lanes` and `line_b + lanes` from 0; asserted by `LineKernel::new`).
struct LineEnds<'k, S: Simd, const FIXED: bool, const XPBD: bool, const MASKED: bool> {
    k: &'k LineKernel<S>,
    a: usize,
    b: usize,
    line_a: usize,
    line_b: usize,
    /// The coordinates of the springs' first and second ends, from the line's
    /// start: a block's loads then take its offset as a constant, where an
    /// address a block cost the pass a register and an instruction.
    ends: [[*const S::E; 3]; 2],
}

impl<'k, S: Simd, const FIXED: bool, const XPBD: bool, const MASKED: bool>
    LineEnds<'k, S, FIXED, XPBD, MASKED>
{
    /// The line whose springs' ends are at array indices `line_a` and `line_b`
    /// from 0, of a sweep whose bounds `k` asserted.
    #[inline(always)]
    fn new(k: &'k LineKernel<S>, (line_a, line_b): (usize, usize)) -> Self {
        let (a, b) = (line_a - k.base, line_b - k.base);
        let pos = k.pos;
        // SAFETY: `a` and `b` are inside the arrays (see above).
        // (Written out: `map` here ran as a call a line.)
        let ends = unsafe {
            [
                [
                    pos[0].add(a).cast_const(),
                    pos[1].add(a).cast_const(),
                    pos[2].add(a).cast_const(),
                ],
                [
                    pos[0].add(b).cast_const(),
                    pos[1].add(b).cast_const(),
                    pos[2].add(b).cast_const(),
                ],
            ]
        };
        LineEnds {
            k,
            a,
            b,
            line_a,
            line_b,
            ends,
        }
    }

    /// The lanes at `p + i`.
    ///
    /// # Safety
    /// Inside the arrays (see above).
    #[inline(always)]
    unsafe fn load(&self, p: *const S::E, i: usize) -> S::V {
        // SAFETY: the caller's contract.
        unsafe { self.k.s.load(p.add(i)) }
    }

    /// The vectors `d` of the block at `j`, first end less second.
    ///
    /// # Safety
    /// As for [`Self::load`].
    #[inline(always)]
    unsafe fn vectors(&self, j: usize) -> [S::V; 3] {
        let (s, ends) = (self.k.s, &self.ends);
        // SAFETY: the caller's contract.
        per_axis!(|i| unsafe {
            difference::<S, FIXED>(s, self.load(ends[0][i], j), self.load(ends[1][i], j))
        })
    }

    /// The block at `j`: its springs' vectors `d` (first end less second), lanes
    /// positive where a spring is in the class (and for the stretch limit over
    /// the limit), and whether any is. (`TAIL`: whether the
    /// block may be the line's last, with lanes past it.)
    ///
    /// # Safety
    /// As for [`Self::load`].
    #[inline(always)]
    unsafe fn measure<const TAIL: bool>(&self, j: usize) -> ([S::V; 3], S::V, bool) {
        let (k, s) = (self.k, self.k.s);
        // SAFETY (every load): the caller's contract.
        let d: [S::V; 3] = unsafe { self.vectors(j) };
        let mut keep = if TAIL && j + S::LANES > k.len {
            k.class_tail
        } else {
            k.class
        };
        if MASKED {
            if let Some(m) = k.alive {
                keep = s.mul(keep, unsafe { self.load(m, self.line_a + j) });
            }
            if let Some(m) = k.real {
                let (ma, mb) = unsafe { (self.load(m, self.a + j), self.load(m, self.b + j)) };
                keep = s.mul(keep, s.mul(ma, mb));
            }
        }
        let l2 = k.length2(d);
        // Positive where the spring is to be corrected.
        let over = if XPBD { keep } else { k.over_limit(l2, keep) };
        (d, over, s.any_positive(over))
    }

    /// Whether a spring of the block at `j` is over `limit2` ([`LineKernel::over`]).
    ///
    /// # Safety
    /// As for [`Self::load`].
    #[inline(always)]
    unsafe fn over(&self, j: usize, limit2: S::V) -> S::Mask {
        // SAFETY: the caller's contract.
        self.k.over(unsafe { self.vectors(j) }, limit2)
    }

    /// XPBD's [`laws::xpbd_factor`] for the block at `j` of springs of vectors
    /// `d` with summed inverse masses `w`: `t / l`, to scale `d` by (0 where `l`
    /// is about 0), and `t`, from the first ends' moves since the start of the
    /// step less the second ends' and `α̃ λ` as the first sweep left it (none in
    /// the first sweep, from `λ = 0`). The multiplier's change is `-t`. (The
    /// law's degenerate length is in the positions' units here, as the row
    /// pass's springs take it: metres in float, and in fixed point under the
    /// unit², below any nonzero squared length of integers.)
    ///
    /// # Safety
    /// As for [`Self::load`].
    #[inline(always)]
    unsafe fn xpbd_scale(&self, j: usize, d: [S::V; 3], w: S::V) -> (S::V, S::V) {
        let (k, s) = (self.k, self.k.s);
        let (pos, start) = (k.pos, k.start);
        let (ia, ib) = (self.line_a + j, self.line_b + j);
        // SAFETY (every load): the caller's contract.
        let moved: [S::V; 3] = per_axis!(|i| unsafe {
            s.sub(
                difference::<S, FIXED>(s, self.load(pos[i], self.a + j), self.load(start[i], ia)),
                difference::<S, FIXED>(s, self.load(pos[i], self.b + j), self.load(start[i], ib)),
            )
        });
        let c = XpbdCoefficients {
            rest: Vector(s, k.rest),
            alpha: Vector(s, k.alpha),
            gamma: Vector(s, k.gamma),
            one_gamma: Vector(s, k.one_gamma),
        };
        let (d, moved, w) = (lanes3(s, d), lanes3(s, moved), Vector(s, w));
        // The law inlined once per sweep kind, with one test a block: with the
        // multiplier as an `Option` made here, the law's test was a second one.
        let (scale, t) = match k.multipliers {
            Some(m) if m.second => {
                let alpha_lambda = Vector(s, unsafe { self.load(m.values, ia) });
                laws::xpbd_factor(d, moved, w, c, Some(alpha_lambda))
            }
            _ => laws::xpbd_factor(d, moved, w, c, None),
        };
        (scale.1, t.1)
    }

    /// Moves the ends of the block at `j` by their corrections, where `over` is
    /// positive. (The stretch limit measures its springs again: kept from
    /// `measure`, the vectors of four blocks went to the stack, where most blocks
    /// correct none; the sheet at 128 ran 1.4 instructions a particle-step more.)
    ///
    /// # Safety
    /// As for [`Self::load`].
    #[inline(always)]
    unsafe fn correct(&self, j: usize, d: [S::V; 3], over: S::V) {
        let (s, n, (a, b)) = (self.k.s, S::LANES, (self.a, self.b));
        let (zero, one) = (S::E::ZERO, S::E::ONE);
        // The stretch limit's kernel, opaque here: else the compiler worked
        // out the addresses of every array the correction touches before
        // each line and kept them on the stack, for blocks that mostly
        // correct nothing (the sheet at 128: 3.0 instructions a particle-step
        // more). XPBD corrects every block.
        let k = if XPBD {
            self.k
        } else {
            std::hint::black_box(self.k)
        };
        // SAFETY (every load and store): the caller's contract.
        let d = if XPBD { d } else { unsafe { self.vectors(j) } };
        let w = unsafe { s.add(self.load(k.inv_mass, a + j), self.load(k.inv_mass, b + j)) };
        // Positive where a spring to correct is not pinned at both ends.
        let over = s.keep_if_positive(w, over);
        let scale = if XPBD {
            let (scale, t) = unsafe { self.xpbd_scale(j, d, w) };
            if let Some(m) = k.multipliers.filter(|m| !m.second) {
                // `α̃ λ` after the first correction (from `λ = 0`): `-α̃ t`, 0
                // where no spring was corrected; lanes past the line keep
                // what they hold (they may be the next row's springs).
                let mut kept = s.keep_if_positive(over, s.mul(k.minus_alpha, t));
                let i = self.line_a + j;
                if j + n > k.len {
                    let held = unsafe { self.load(m.values, i) };
                    kept = s.add(kept, s.keep_if_positive(k.past_tail, held));
                }
                // SAFETY: `i + n <= line_a + lanes <= m.len` (asserted).
                unsafe { s.store(m.values.add(i), kept) };
            }
            s.keep_if_positive(over, scale)
        } else {
            k.limit_scale(d, w, over)
        };
        // Exactly no move where none is due: a lane out of the class or past
        // the line may reach a ghost, whose move `0 d` would be NaN (and stay)
        // once a diverging neighbour's `d` is not finite.
        let d: [S::V; 3] = per_axis!(|axis| s.keep_if_positive(over, d[axis]));
        for (start, sign) in [(a, zero - one), (b, one)] {
            let inv_mass = unsafe { self.load(k.inv_mass, start + j) };
            let f = s.mul(s.mul(s.splat(sign), inv_mass), scale);
            for (axis, &d) in d.iter().enumerate() {
                let t = s.mul(f, d);
                let i = start + j;
                unsafe { k.move_by::<FIXED>(axis, i, self.load(k.pos[axis], i), t) };
            }
        }
    }
}
