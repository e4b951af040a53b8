//! Which springs and triangles of a grid cloth are left ([`Torn`]), and tearing
//! ([`crate::sim::tearing`]): a vectorised scan for rows that may hold a spring
//! longer than `(1 + tau) L`, then the f64 test on those.

#[cfg(target_arch = "x86_64")]
use super::x86;
use super::{
    Buf, Grid, Kernel, PARALLEL_MIN_PARTICLES, Real, SimdLevel, SpringCoefficients, State,
};
use crate::sim::duo::Duo;
use crate::sim::springs::{STENCIL_DIRECTIONS, STENCIL_KINDS};

/// In [`Torn::bits`], the bits of the cell's triangles `(a, b, d)` and `(b, e, d)`
/// (after the six springs' bits).
pub(super) const TRIANGLE_BITS: [u8; 2] = [1 << 6, 1 << 7];

/// A grid cloth with springs missing: which springs and triangles are left, and
/// the masks the row pass multiplies their forces and drag by.
#[derive(Clone, Debug)]
pub(super) struct Torn<E> {
    /// Per particle in cloth order: bit `d < 6` set when its spring in stencil
    /// direction `d` ([`STENCIL_DIRECTIONS`]) exists, then [`TRIANGLE_BITS`] for
    /// the triangles of the cell it is the top left corner of.
    pub(super) bits: Vec<u8>,
    /// Per direction, at each particle's array index: 1 where that spring exists.
    pub(super) springs: [Buf<E>; 6],
    /// Per cell, at the array index of its top left particle: 1 where the triangle
    /// `(a, b, d)` (first array) or `(b, e, d)` (second) exists.
    pub(super) triangles: [Buf<E>; 2],
}

impl<E: Real> Torn<E> {
    /// The springs and triangles `bits` (see [`Torn::bits`]) on `grid`, with masks.
    pub(super) fn new(bits: Vec<u8>, grid: &Grid) -> Self {
        let mut torn = Self {
            bits,
            springs: std::array::from_fn(|_| Buf::zeros(grid.len())),
            triangles: std::array::from_fn(|_| Buf::zeros(grid.len())),
        };
        torn.refresh(grid);
        torn
    }

    /// Every stencil spring of the kinds `present` that fits on `grid`, and every
    /// triangle.
    pub(super) fn whole(grid: &Grid, present: [bool; 3]) -> Vec<u8> {
        let (w, h) = (grid.w, grid.h);
        (0..w * h)
            .map(|p| {
                let (r, c) = (p / w, p % w);
                let mut bits = 0;
                for (d, &(dr, dc)) in STENCIL_DIRECTIONS.iter().enumerate() {
                    let cc = c as isize + dc;
                    if present[STENCIL_KINDS[d].index()]
                        && r + dr < h
                        && (0..w as isize).contains(&cc)
                    {
                        bits |= 1 << d;
                    }
                }
                if r + 1 < h && c + 1 < w {
                    bits |= TRIANGLE_BITS[0] | TRIANGLE_BITS[1];
                }
                bits
            })
            .collect()
    }

    /// Whether the spring from particle `p` in stencil direction `d` is left.
    pub(super) fn has(&self, p: usize, d: usize) -> bool {
        self.bits[p] >> d & 1 == 1
    }

    /// Breaks the spring from particle `p` in direction `d` on a grid `w` wide,
    /// and the triangles along it.
    pub(super) fn break_spring(&mut self, p: usize, d: usize, w: usize) {
        self.bits[p] &= !(1 << d);
        let c = p % w;
        let [first, second] = TRIANGLE_BITS;
        let mut clear = |cell: Option<usize>, bit: u8| {
            if let Some(cell) = cell {
                self.bits[cell] &= !bit;
            }
        };
        match STENCIL_DIRECTIONS[d] {
            // Edge a-b of its cell, e-d of the cell above.
            (0, 1) => {
                clear(Some(p), first);
                clear(p.checked_sub(w), second);
            }
            // Edge a-d of its cell, b-e of the cell to the left.
            (1, 0) => {
                clear(Some(p), first);
                clear((c > 0).then(|| p - 1), second);
            }
            // Edge b-d of both triangles of the cell to the left.
            (1, -1) => clear(Some(p - 1), first | second),
            // Bend springs and the other diagonal are no triangle's edge.
            _ => {}
        }
    }

    /// Recomputes the masks from `bits`.
    pub(super) fn refresh(&mut self, grid: &Grid) {
        let one = |on: bool| if on { E::ONE } else { E::ZERO };
        for p in 0..grid.w * grid.h {
            let (i, bits) = (grid.index(p), self.bits[p]);
            for d in 0..6 {
                self.springs[d].as_mut_slice()[i] = one(bits >> d & 1 == 1);
            }
            for (mask, bit) in self.triangles.iter_mut().zip(TRIANGLE_BITS) {
                mask.as_mut_slice()[i] = one(bits & bit != 0);
            }
        }
    }
}

impl<E: Real> Kernel<E> {
    /// The springs the model has left (`bits` as in [`Torn::bits`]; `None`: the
    /// whole stencil, every triangle).
    pub fn set_springs_left(&mut self, bits: Option<Vec<u8>>) {
        self.torn = bits.map(|bits| Torn::new(bits, &self.grid));
    }

    /// The springs torn since the last call: (particle in cloth order, stencil
    /// direction).
    pub fn take_torn(&mut self) -> Vec<(usize, usize)> {
        std::mem::take(&mut self.torn_log)
    }

    /// Tearing, the step's last phase ([`crate::sim::tearing`]): breaks every spring
    /// past the tear strain `tau`. A scan of each row of each stencil direction in
    /// the kernel's precision (vectorised, its rows split over the pool's threads
    /// when `parallel`, or handed half to the spinning server with `duo`) finds
    /// the rows that may hold one, with a margin; there
    /// [`crate::sim::tearing::overstretched`] decides in f64, as in the f64 engine, in
    /// a fixed order, so the breaks do not depend on the threads.
    pub(super) fn tear_pass(&mut self, tau: f64, parallel: bool, duo: Option<&Duo>) {
        let (w, h, st) = (self.grid.w, self.grid.h, self.grid.stride);
        let fixed = self.frame.fixed;
        // Per direction: first column, columns, rows, rest length, scan bound (in
        // the positions' units).
        let lines = self.stencil().map(|stencil| {
            let Stencil {
                offset: (dr, dc),
                rest,
                present,
                ..
            } = stencil;
            let c0 = (-dc).max(0) as usize;
            let len = w.saturating_sub(dc.max(0) as usize).saturating_sub(c0);
            let longest = self.frame.units((1.0 + tau) * rest);
            // f32 lengths are good to about 1e-6 of themselves: the scan's margin.
            let scan2 = E::of(longest * longest * (1.0 - 1e-4));
            let rows = if present && len > 0 {
                h.saturating_sub(dr)
            } else {
                0
            };
            (c0, len, rows, rest, scan2)
        });
        let mut flags = std::mem::take(&mut self.tear_rows);
        flags.clear();
        flags.resize(6 * h, false);
        {
            let (cur, torn, simd) = (&self.cur, self.torn.as_ref(), self.simd);
            // Row by row, all six directions of a row together: the rows they
            // read stay in cache.
            let scan = |k: usize, flag: &mut bool| {
                let (d, r) = (k % 6, k / 6);
                let (c0, len, rows, _, scan2) = lines[d];
                if r >= rows {
                    return;
                }
                let (dr, dc) = STENCIL_DIRECTIONS[d];
                let (a, b) = (r * st + c0, ((r + dr) * st + c0).wrapping_add_signed(dc));
                let alive = torn.map(|t| &t.springs[d].as_slice()[a..a + len]);
                let ends = (a, b, len);
                *flag = row_may_tear_dispatch(simd, cur, fixed, ends, alive, scan2);
            };
            let large = w * h >= PARALLEL_MIN_PARTICLES;
            let scan_all = |from: usize, flags: &mut [bool]| {
                (flags.iter_mut().enumerate()).for_each(|(k, f)| scan(from + k, f));
            };
            match duo {
                // The rows in two halves, the second handed over by spinning.
                Some(duo) if large => {
                    let half = 6 * (h / 2);
                    let (first, second) = flags.split_at_mut(half);
                    duo.fork_once(|| scan_all(half, second), || scan_all(0, first));
                }
                _ if parallel && large => {
                    use rayon::prelude::*;
                    // Whole rows of 16 at a time: a task per row cost more than its scan.
                    flags
                        .par_iter_mut()
                        .enumerate()
                        .with_min_len(6 * 16)
                        .for_each(|(k, f)| scan(k, f));
                }
                _ => scan_all(0, &mut flags),
            }
        }
        let mut broke = false;
        for k in (0..6 * h).filter(|&k| flags[k]) {
            let (d, r) = (k % 6, k / 6);
            let (c0, len, _, rest, _) = lines[d];
            let (dr, dc) = STENCIL_DIRECTIONS[d];
            for c in c0..c0 + len {
                let p = r * w + c;
                let q = (p + dr * w).wrapping_add_signed(dc);
                let there = self.torn.as_ref().is_none_or(|t| t.has(p, d));
                let (i, j) = (self.grid.index(p), self.grid.index(q));
                let (xi, xj) = (self.position_at(i), self.position_at(j));
                if there && crate::sim::tearing::overstretched(xi, xj, rest, tau) {
                    let (present, grid) = (self.spec.present, self.grid);
                    let torn = self
                        .torn
                        .get_or_insert_with(|| Torn::new(Torn::<E>::whole(&grid, present), &grid));
                    torn.break_spring(p, d, w);
                    self.torn_log.push((p, d));
                    broke = true;
                }
            }
        }
        self.tear_rows = flags;
        if broke && let Some(torn) = &mut self.torn {
            torn.refresh(&self.grid);
        }
    }

    /// The stencil's directions in the order the springs sort (the f64 engine's
    /// order, [`STENCIL_DIRECTIONS`]).
    pub(super) fn stencil(&self) -> [Stencil; 6] {
        let h = self.spec.spacing;
        // Indexed by kind: structural, shear, bend.
        let rests = [h, std::f64::consts::SQRT_2 * h, 2.0 * h];
        let coefficients = [self.spec.structural, self.spec.shear, self.spec.bend];
        std::array::from_fn(|d| {
            let i = STENCIL_KINDS[d].index();
            Stencil {
                offset: STENCIL_DIRECTIONS[d],
                rest: rests[i],
                present: self.spec.present[i],
                coefficients: coefficients[i],
            }
        })
    }
}

/// Whether any spring from `a .. a + len` to `b .. b + len` (array indices in
/// `state`) that `alive` keeps (all without a mask) is longer than `sqrt(scan2)`,
/// in the state's precision and units, with positions in fixed point (`FIXED`) or
/// floats. Written as a plain loop over slices for the compiler to vectorise.
#[inline(always)]
pub(super) fn row_may_tear<E: Real, const FIXED: bool>(
    state: &State<E>,
    (a, b, len): (usize, usize, usize),
    alive: Option<&[E]>,
    scan2: E,
) -> bool {
    fn ends<E: Real>(p: &Buf<E>, a: usize, b: usize, len: usize) -> (&[E], &[E]) {
        let p = p.as_slice();
        (&p[a..a + len], &p[b..b + len])
    }
    let ends = |p| ends(p, a, b, len);
    let [(xa, xb), (ya, yb), (za, zb)] = state.x.each_ref().map(ends);
    // Every slice `len` long, in the compiler's sight, so the loops below carry no
    // bounds checks and vectorise; the verdict is an integer OR. (A macro, not a
    // closure: a closure is not inlined into the AVX2 entry point.)
    let [xa, xb, ya, yb, za, zb] = [xa, xb, ya, yb, za, zb].map(|s| &s[..len]);
    macro_rules! l2 {
        ($j:expr) => {{
            let j = $j;
            let (dx, dy, dz) = if FIXED {
                (
                    E::fixed_sub(xa[j], xb[j]),
                    E::fixed_sub(ya[j], yb[j]),
                    E::fixed_sub(za[j], zb[j]),
                )
            } else {
                (xa[j] - xb[j], ya[j] - yb[j], za[j] - zb[j])
            };
            dx * dx + dy * dy + dz * dz
        }};
    }
    let mut over = 0u8;
    match alive {
        Some(alive) => {
            for (j, &m) in alive[..len].iter().enumerate() {
                over |= u8::from(l2!(j) * m > scan2);
            }
        }
        None => {
            for j in 0..len {
                over |= u8::from(l2!(j) > scan2);
            }
        }
    }
    over != 0
}

/// [`row_may_tear`] with the best code this CPU has.
pub(super) fn row_may_tear_dispatch<E: Real>(
    simd: SimdLevel,
    state: &State<E>,
    fixed: bool,
    ends: (usize, usize, usize),
    alive: Option<&[E]>,
    scan2: E,
) -> bool {
    macro_rules! scan {
        ($lo:literal) => {
            match simd {
                #[cfg(target_arch = "x86_64")]
                // SAFETY: the level is AVX-512 only when the CPU has AVX-512F/VL, AVX2
                // and FMA.
                SimdLevel::Avx512 => unsafe {
                    x86::row_may_tear_avx512::<E, $lo>(state, ends, alive, scan2)
                },
                #[cfg(target_arch = "x86_64")]
                // SAFETY: the level is AVX2 only when the CPU has AVX2 and FMA.
                SimdLevel::Avx2 => unsafe {
                    x86::row_may_tear_avx2::<E, $lo>(state, ends, alive, scan2)
                },
                _ => row_may_tear::<E, $lo>(state, ends, alive, scan2),
            }
        };
    }
    if fixed { scan!(true) } else { scan!(false) }
}

/// One direction of the grid's stencil.
#[derive(Clone, Copy)]
pub(super) struct Stencil {
    /// (row, column) from a spring's first end to its second.
    pub(super) offset: (usize, isize),
    /// Rest length in m.
    pub(super) rest: f64,
    /// Whether the cloth has springs of this kind.
    pub(super) present: bool,
    pub(super) coefficients: SpringCoefficients,
}
