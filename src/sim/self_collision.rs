//! Self-collision of a cloth's particles: no two particles that no spring or bar
//! joins come closer than the contact thickness `h_c`, and the layers that touch rub with
//! Coulomb friction. Every engine runs this one pass on f64 positions after the
//! stretch limit and before the colliders.
//!
//! # Method
//! * Candidate pairs: every pair no spring or bar joins closer than `reach = h_c + 2
//!   margin`, with `margin = 3 h_c / 4` (`MARGIN`), listed in order of `(i,
//!   j)`, `i < j` (the same list whatever the hash, the engine's cell round-off or
//!   the threads). They come from a spatial hash (cells of `reach`, filled by a
//!   counting sort, after Müller's dense hash of Ten Minute Physics) whose three
//!   cells `a - 1, a, a + 1` along the first axis fall in consecutive buckets, so
//!   that a particle reads its own cell and the 13 neighbouring cells ahead of it
//!   (one of each opposite pair) as 6 contiguous runs of a sorted copy of the
//!   positions: each pair is found once, from one of its particles, not from
//!   both (1.1-1.2x faster drape and fold than reading all 27 cells).
//! * The list is rebuilt only when some particle has moved more than `margin`
//!   since the last rebuild, a move common to the cloth taken off, so a pair
//!   missing from it cannot have come within `h_c`: each of its particles moved
//!   less than `margin` against the same common move. The common move is the
//!   middle of the moves' range along each axis (exact in any order, and half the
//!   spread of a cloth part of which lies still while the rest falls, where the
//!   mean is nearly all of it); when the half-diagonal of that range is within
//!   `margin`, one pass over the particles decides. A cloth at rest or falling
//!   whole rebuilds never, a folding or draping one every few steps (the 128 x 128
//!   drape: 58 rebuilds in 960 steps, 88 with a margin of `h_c / 2`).
//! * Each step, every candidate pair closer than `h_c` is pushed apart along its
//!   line to `h_c`, split by inverse mass (one Gauss-Seidel pass over the list).
//!   Then friction: the pair's relative move along the contact in this step is cut
//!   by up to `μ` times the push, as Coulomb's law bounds the tangential impulse by
//!   `μ` times the normal one. The moves become velocities (`δ / h`) as every
//!   constraint's do. An engine working on copies writes back only the particles
//!   the pass moved ([`SelfCollision::moved`]).
//!
//! # Threads
//! From [`PARALLEL_MIN_PARTICLES`] particles, and when the engine runs on threads,
//! the move check and the rebuild run on the current rayon pool: the particles in
//! fixed blocks of 1,024, each block's range of the moves (exact) and its pairs
//! (in a list of its own, read block after block) independent of which thread took
//! it, so any number of threads gives the result of one, bit for bit. The pushes
//! stay one Gauss-Seidel pass on the calling thread: they touch only the pairs in
//! contact, a small cost beside the rebuild (under 0.1% of the pass while the
//! drape falls onto its sphere).
//!
//! # Cost
//! The drape's particle-steps per second without self-collision over with it,
//! best of 3 runs of `cloth run --scene drape --set width=N --set height=N --steps
//! 960 --warmup 16 --json` with and without `--set self_collision=false` (grid-mixed,
//! AVX-512, 2 cores shared with another build at load 1.5, 2026-11-23; ±20%): 2.7x
//! at 64, 2.3x at 128, 2.2x at 256, against 4.1x, 4.3x and 6.1x for the one-thread
//! pass before (same run). Nearly all of it is the rebuild's search, 88 rebuilds at
//! 128; the target, 2x at 128, is not reached. With the margin at 3/4 (2026-11-24,
//! AVX-512, 2 threads, best of 3, the machine otherwise idle): 1.20x, 1.26x and
//! 1.32x faster at 64, 128 and 256 (30.0, 60.1 and 85.8 M particle-steps/s), and
//! the cost against the same drape without self-collision 3.6x, 2.5x and 3.0x (the
//! drape without it got faster the same day).
//!
//! # What it cannot catch
//! It is particle against particle. A particle can pass through a patch of cloth
//! only between its particles; with `h_c` at least `1 / √2` of the spacing (the
//! centre of a square is that far from its corners) no such gap is left in an
//! unstretched cloth, which is why the drape uses `h_c = 0.8` spacing. A layer
//! stretched more, or one crossing faster than `h_c` per step, can still pass;
//! edge-edge crossings are not detected, and a tangle once made is not undone
//! (there is no notion of sides). A thickness near the distance of the nearest
//! pairs no spring joins at rest (a knight's move, `√5` spacings on a grid) fights
//! the springs over the cloth's own shape: at 2.5 spacings the hanging cloth
//! jitters chaotically; keep `h_c` to about a spacing.
//!
//! Nothing is allocated per step after the first, unless a rebuild finds more
//! candidate pairs in a block of particles than any before it (room for 8 a
//! particle is made at the first).

use glam::DVec3;
use rayon::prelude::*;

/// Particles from which [`SelfCollision::apply`] uses the current rayon pool's
/// threads when it is allowed to: smaller cloths stay on the calling thread.
pub const PARALLEL_MIN_PARTICLES: usize = 48 * 48;

/// The margin of the candidate list, in thicknesses: its pairs are those closer
/// than `h_c (1 + 2 MARGIN)`, and it is rebuilt once a particle has moved more than
/// `MARGIN h_c`. The results do not depend on it (a pair that comes within `h_c` is
/// on the list either way, in the same order), only the time does: a wider margin
/// rebuilds less often and lists more pairs. At 3/4, with the drape's and the
/// fold's `h_c` of 0.8 spacings, the reach is 2 spacings, just short of the
/// knight's move (`√5` spacings) of the nearest pairs no spring joins, so a flat
/// cloth lists none. On one core, 1,920 steps of `cloth run --scene drape --set
/// width=N --set height=N` (AVX-512, the same energies to the last digit), against
/// 1/2: 1.16x at the default 40, 1.34x at 128, 1.30x at 256; 0.9 (knight's moves
/// on the list) was slower than 1/2.
const MARGIN: f64 = 0.75;

/// Particles per block of the move check and of the candidate search. Fixed, so
/// that the blocks, and with them the pairs' lists, are the same for any number of
/// threads.
const BLOCK: usize = 1024;

/// Candidate pairs a particle that each block's list has room for from its first
/// rebuild on.
const PAIRS_PER_PARTICLE: usize = 8;

/// Most candidate pairs a block's search lists, per particle of the block: the
/// memory bound of the list, 1 KiB a particle over its two copies (64 MiB for a
/// 256 x 256 cloth). Particles kept `h_c` apart fit about 20 to a layer within
/// the reach of `2.5 h_c` (a flat cloth at one spacing), so a pile of layers
/// stays under it; a thickness many times the spacing does not (at 256 x 256 and
/// `h_c` = 10 m every pair is within reach: 2·10⁹ pairs, 24 GB, where the kernel
/// killed the run). Past it a block's search stops, its particles' remaining
/// pairs are left out, and [`SelfCollision::overfull`] says so; a scene whose
/// start overfills it is refused ([`SelfCollision::would_overfill`]).
pub const MAX_PAIRS_PER_PARTICLE: usize = 64;

/// The rows of cells ahead of a cell along the second and third axes, `(db, dc)`:
/// with the cell `a + 1` of its own row, half of the 26 neighbours, one of each
/// opposite pair, so that a pair of particles in neighbouring cells is found from
/// one of them.
const FORWARD_ROWS: [(i32, i32); 4] = [(0, 1), (1, -1), (1, 0), (1, 1)];

/// The hash's multipliers of the second and third cell coordinates; the first is
/// added, so that the cells `a - 1, a, a + 1` of a row fall in consecutive buckets.
const HASH: [u32; 2] = [689_287_499, 283_923_481];

/// A particle in the sorted copy the candidate search reads.
#[derive(Clone, Copy, Debug, Default)]
struct Entry {
    x: DVec3,
    index: u32,
}

/// The self-collision pass and what it keeps between steps.
#[derive(Clone, Debug, Default)]
pub struct SelfCollision {
    /// Candidate pairs `(i, j)`, `i < j`, from the last rebuild, by block of
    /// particles `i` ([`BLOCK`]); in order of `i` then `j` when read block after
    /// block.
    found: Vec<Vec<[u32; 2]>>,
    /// The pairs each block's particles found at the last rebuild, before they go
    /// to `found`.
    found_by_searcher: Vec<Vec<[u32; 2]>>,
    /// Positions at the last rebuild.
    anchor: Vec<DVec3>,
    /// Each block's smallest and largest moves along each axis since the last
    /// rebuild.
    block_moves: Vec<[DVec3; 2]>,
    /// First entry of each hash bucket in `sorted` (counting sort), one more than
    /// the buckets.
    cell_start: Vec<u32>,
    /// Each particle's cell and bucket at the last rebuild.
    cells: Vec<([i32; 3], u32)>,
    /// The particles sorted by bucket, with their positions and cells.
    sorted: Vec<Entry>,
    /// Particles the last pass moved, each once.
    touched: Vec<u32>,
    /// Per particle: whether it is in `touched`.
    marked: Vec<bool>,
    /// The thickness the list was built for.
    built_for: f64,
    /// Pairs pushed apart by the last pass.
    contacts: usize,
    /// Rebuilds so far.
    rebuilds: u64,
    /// Per block: whether its search stopped at [`MAX_PAIRS_PER_PARTICLE`].
    overflowed: Vec<bool>,
}

impl SelfCollision {
    /// Pairs pushed apart by the last pass (the panel's contact count).
    pub fn contacts(&self) -> usize {
        self.contacts
    }

    /// Candidate-list rebuilds so far.
    pub fn rebuilds(&self) -> u64 {
        self.rebuilds
    }

    /// Candidate pairs in the list (pairs no spring joins closer than `2 h_c` at the
    /// last rebuild).
    pub fn candidates(&self) -> usize {
        self.found.iter().map(Vec::len).sum()
    }

    /// Whether the last rebuild found more candidate pairs than the list has room
    /// for ([`MAX_PAIRS_PER_PARTICLE`]) and left some out: the thickness is too
    /// large for the particles' spacing.
    pub fn overfull(&self) -> bool {
        self.overflowed.iter().any(|&o| o)
    }

    /// Whether particles at `x` kept `h_c` apart (those `joined` excepted) would
    /// list more candidate pairs than [`MAX_PAIRS_PER_PARTICLE`] allows: one
    /// rebuild, within the memory bound and a time in proportion to it.
    pub fn would_overfill(
        x: &[DVec3],
        h_c: f64,
        joined: impl Fn(usize, usize) -> bool + Sync,
    ) -> bool {
        if h_c <= 0.0 || x.len() < 2 {
            return false;
        }
        let mut probe = Self::default();
        probe.rebuild(
            x,
            h_c * (1.0 + 2.0 * MARGIN),
            joined,
            x.len() >= PARALLEL_MIN_PARTICLES,
        );
        probe.overfull()
    }

    /// The particles the last pass moved (a superset: each once, in the order it
    /// first touched them), for an engine that works on copies to write back.
    pub fn moved(&self) -> &[u32] {
        &self.touched
    }

    /// One pass on positions `x` (moved in place) with thickness `h_c` (m) and
    /// friction `mu`. `particle(i)` gives particle `i`'s position at the start of
    /// the step and its inverse mass (0: pinned), asked only for pairs in contact;
    /// `joined(i, j)` says that a spring joins `i` and `j`. With `parallel`, a cloth
    /// of `PARALLEL_MIN_PARTICLES` or more checks its moves and rebuilds its list
    /// on the current rayon pool's threads, with the same result as on one.
    pub fn apply(
        &mut self,
        x: &mut [DVec3],
        particle: impl Fn(usize) -> (DVec3, f64),
        h_c: f64,
        mu: f64,
        joined: impl Fn(usize, usize) -> bool + Sync,
        parallel: bool,
    ) {
        self.contacts = 0;
        for &i in &self.touched {
            self.marked[i as usize] = false;
        }
        self.touched.clear();
        if h_c <= 0.0 || x.len() < 2 {
            return;
        }
        let parallel = parallel && x.len() >= PARALLEL_MIN_PARTICLES;
        let margin = MARGIN * h_c;
        let m = self.moved_more_than(x, margin, parallel);
        if m || self.built_for != h_c {
            self.rebuild(x, h_c + 2.0 * margin, joined, parallel);
            self.built_for = h_c;
        }
        self.marked.resize(x.len(), false);
        let h2 = h_c * h_c;
        for &[i, j] in self.found.iter().flatten() {
            let (i, j) = (i as usize, j as usize);
            let d = x[i] - x[j];
            let l2 = d.length_squared();
            if l2 >= h2 || l2 == 0.0 {
                continue;
            }
            let ((start_i, w_i), (start_j, w_j)) = (particle(i), particle(j));
            let ends = w_i + w_j;
            if ends == 0.0 {
                continue;
            }
            let l = l2.sqrt();
            let normal = d / l;
            let push = (h_c - l) / ends;
            x[i] += w_i * push * normal;
            x[j] -= w_j * push * normal;
            if mu > 0.0 {
                // The pair's relative move this step, along the contact.
                let rel = (x[i] - start_i) - (x[j] - start_j);
                let slide = rel - rel.dot(normal) * normal;
                let length = slide.length();
                if length > 0.0 {
                    let cut = (mu * (h_c - l) / length).min(1.0) / ends;
                    x[i] -= w_i * cut * slide;
                    x[j] += w_j * cut * slide;
                }
            }
            for k in [i, j] {
                if !self.marked[k] {
                    self.marked[k] = true;
                    self.touched.push(k as u32);
                }
            }
            self.contacts += 1;
        }
    }

    /// Whether some particle moved more than `margin` since the last rebuild (or
    /// there was none), a move common to the whole cloth taken off: a pair's
    /// distance changes by at most the sum of its particles' moves less any common
    /// move `c`, so a cloth falling or swinging as a whole keeps its list. `c` is
    /// the middle of the moves' range along each axis, which bounds every
    /// particle's move less `c` by the half-diagonal of that range: within
    /// `margin`, one pass decides; past it, a second pass looks at each particle.
    /// Minima and maxima are exact in any order, so blocks ([`BLOCK`]) on any
    /// number of threads give the same answer.
    fn moved_more_than(&mut self, x: &[DVec3], margin: f64, parallel: bool) -> bool {
        let n = x.len();
        if self.anchor.len() != n {
            return true;
        }
        let anchor = &self.anchor;
        let range = |k: usize| k * BLOCK..((k + 1) * BLOCK).min(n);
        let bounds = |(k, out): (usize, &mut [DVec3; 2])| {
            let r = range(k);
            let (mut lo, mut hi, mut finite) = (DVec3::INFINITY, DVec3::NEG_INFINITY, true);
            for (p, a) in x[r.clone()].iter().zip(&anchor[r]) {
                let d = *p - *a;
                lo = lo.min(d);
                hi = hi.max(d);
                finite &= d.is_finite();
            }
            *out = if finite { [lo, hi] } else { [DVec3::NAN; 2] };
        };
        self.block_moves.resize(n.div_ceil(BLOCK), [DVec3::ZERO; 2]);
        if parallel {
            self.block_moves.par_iter_mut().enumerate().for_each(bounds);
        } else {
            self.block_moves.iter_mut().enumerate().for_each(bounds);
        }
        let (mut lo, mut hi) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
        for [l, h] in &self.block_moves {
            if !(l.is_finite() && h.is_finite()) {
                return true;
            }
            (lo, hi) = (lo.min(*l), hi.max(*h));
        }
        let m2 = margin * margin;
        if (0.5 * (hi - lo)).length_squared() <= m2 {
            return false;
        }
        let common = 0.5 * (lo + hi);
        let far = |k: usize| {
            let r = range(k);
            (x[r.clone()].iter().zip(&anchor[r]))
                .any(|(p, a)| (*p - *a - common).length_squared() > m2)
        };
        if parallel {
            (0..self.block_moves.len()).into_par_iter().any(far)
        } else {
            (0..self.block_moves.len()).any(far)
        }
    }

    /// Rebuilds the candidate pairs: every pair `i < j` no spring or bar joins closer than
    /// `reach`, in order of `i` then `j` (the same list whatever the hash, and for
    /// any number of threads).
    ///
    /// Cells of about `reach` are hashed to buckets so that the three cells of a
    /// row along the first axis, `a - 1, a, a + 1`, fall in consecutive buckets; a
    /// counting sort puts the particles, with their positions and cells, in bucket
    /// order. Each particle then reads the partners after it in its own bucket,
    /// and the 13 cells ahead of its cell ([`FORWARD_ROWS`] and the next cell of
    /// its row) as 5 runs of buckets, contiguous in the sorted copy: a pair in
    /// neighbouring cells is found from the particle whose cell the other's lies
    /// ahead of. The particles are searched by block ([`BLOCK`]), each block's
    /// finds in its own list, on the pool's threads with `parallel`; then each pair
    /// goes to the list of its first particle's block, sorted and found once (the
    /// same lists whichever block found them).
    fn rebuild(
        &mut self,
        x: &[DVec3],
        reach: f64,
        joined: impl Fn(usize, usize) -> bool + Sync,
        parallel: bool,
    ) {
        self.rebuilds += 1;
        self.anchor.clear();
        self.anchor.extend_from_slice(x);
        let hash = CellHash::new(x.len(), reach);
        self.sort_into_buckets(x, hash, parallel);
        self.search(x, reach, hash, joined, parallel);
        self.gather_found(parallel);
    }

    /// Puts each particle's cell and bucket in `cells`, then, by a counting sort,
    /// the particles with their positions in bucket order in `sorted`, and where
    /// each bucket starts in `cell_start`.
    fn sort_into_buckets(&mut self, x: &[DVec3], hash: CellHash, parallel: bool) {
        let n = x.len();
        self.cells.resize(n, ([0; 3], 0));
        let locate = |(k, out): (usize, &mut [([i32; 3], u32)])| {
            for (o, p) in out.iter_mut().zip(&x[k * BLOCK..]) {
                let cell = hash.cell_of(*p);
                *o = (cell, hash.bucket(cell));
            }
        };
        if parallel {
            self.cells
                .par_chunks_mut(BLOCK)
                .enumerate()
                .for_each(locate);
        } else {
            self.cells.chunks_mut(BLOCK).enumerate().for_each(locate);
        }
        self.cell_start.clear();
        self.cell_start.resize(hash.buckets + 1, 0);
        for &(_, b) in &self.cells {
            self.cell_start[b as usize] += 1;
        }
        let mut total = 0;
        for s in &mut self.cell_start {
            total += *s;
            *s = total;
        }
        self.sorted.resize(n, Entry::default());
        for (i, &(_, b)) in self.cells.iter().enumerate() {
            let at = &mut self.cell_start[b as usize];
            *at -= 1;
            self.sorted[*at as usize] = Entry {
                x: x[i],
                index: i as u32,
            };
        }
    }

    /// Each block's particles' partners within `reach` that `joined` does not
    /// join, into the block's list in `found_by_searcher` (see [`Self::rebuild`]).
    fn search(
        &mut self,
        x: &[DVec3],
        reach: f64,
        hash: CellHash,
        joined: impl Fn(usize, usize) -> bool + Sync,
        parallel: bool,
    ) {
        let (n, buckets) = (x.len(), hash.buckets);
        let (cells, sorted, starts) = (&self.cells, &self.sorted, &self.cell_start);
        let reach2 = reach * reach;
        // The entries of buckets `from .. from + len`: one or two runs of the
        // sorted copy (two where they wrap past the last bucket; the second empty
        // otherwise).
        let entries = |from: u32, len: usize| {
            let (lo, hi) = (from as usize, from as usize + len);
            let (first, second) = if hi <= buckets {
                ((lo, hi), (0, 0))
            } else {
                ((lo, buckets), (0, hi - buckets))
            };
            let run = |(a, b): (usize, usize)| &sorted[starts[a] as usize..starts[b] as usize];
            [run(first), run(second)]
        };
        let search = |(k, (out, overflowed)): (usize, (&mut Vec<[u32; 2]>, &mut bool))| {
            out.clear();
            let range = k * BLOCK..((k + 1) * BLOCK).min(n);
            // Room for 8 pairs a particle from the first rebuild on (a flat cloth
            // has none, a pile of layers a few): later rebuilds allocate only past
            // that.
            out.reserve(PAIRS_PER_PARTICLE * range.len());
            let room = MAX_PAIRS_PER_PARTICLE * range.len();
            *overflowed = false;
            for i in range {
                if out.len() >= room {
                    *overflowed = true;
                    break;
                }
                let ([a, b, c], own) = cells[i];
                let (p, me) = (x[i], i as u32);
                let mut keep = |e: &Entry| {
                    if !joined(i, e.index as usize) {
                        out.push([me.min(e.index), me.max(e.index)]);
                    }
                };
                // Its own bucket: the partners after it (each pair of a cell once).
                for run in entries(own, 1) {
                    for e in run {
                        if (e.index > me) & (p.distance_squared(e.x) < reach2) {
                            keep(e);
                        }
                    }
                }
                // The cells ahead of it: `a + 1` in its own row, and the rows
                // `a - 1 ..= a + 1` of the cells ahead along the other two axes.
                // Other cells that share these buckets are farther than `reach`
                // (or hold this particle itself).
                let mut scan = |run: &[Entry]| {
                    for e in run {
                        if (e.index != me) & (p.distance_squared(e.x) < reach2) {
                            keep(e);
                        }
                    }
                };
                // Plain loops over slices: with iterators chaining them the fold
                // scene ran 3.6% more instructions (valgrind, 1,500 steps).
                for (db, dc) in FORWARD_ROWS {
                    let cell = [a.wrapping_sub(1), b.wrapping_add(db), c.wrapping_add(dc)];
                    let [first, second] = entries(hash.bucket(cell), 3);
                    scan(first);
                    scan(second);
                }
                let [first, second] = entries(hash.bucket([a.wrapping_add(1), b, c]), 1);
                scan(first);
                scan(second);
            }
        };
        let blocks = n.div_ceil(BLOCK);
        self.found_by_searcher.resize_with(blocks, Vec::new);
        self.overflowed.resize(blocks, false);
        if parallel {
            let lists = self.found_by_searcher.par_iter_mut();
            (lists.zip(self.overflowed.par_iter_mut()).enumerate()).for_each(search);
        } else {
            let lists = self.found_by_searcher.iter_mut();
            (lists.zip(self.overflowed.iter_mut()).enumerate()).for_each(search);
        }
    }

    /// Each pair the searchers found to the block of its first particle, then
    /// each block's in order, once (a pair is found twice where the hash puts two
    /// cells that a particle reads in one bucket).
    fn gather_found(&mut self, parallel: bool) {
        let blocks = self.found_by_searcher.len();
        self.found.resize_with(blocks, Vec::new);
        for list in &mut self.found {
            // The same room as the searchers' lists.
            list.clear();
            list.reserve(PAIRS_PER_PARTICLE * BLOCK);
        }
        for &pair in self.found_by_searcher.iter().flatten() {
            self.found[pair[0] as usize / BLOCK].push(pair);
        }
        let order = |list: &mut Vec<[u32; 2]>| {
            list.sort_unstable();
            list.dedup();
        };
        if parallel {
            self.found.par_iter_mut().for_each(order);
        } else {
            self.found.iter_mut().for_each(order);
        }
    }
}

/// The spatial hash of [`SelfCollision::rebuild`]: cells of about `reach`, hashed
/// to a power of two of buckets, at least twice the particles, so that a mask
/// picks the bucket.
#[derive(Clone, Copy)]
struct CellHash {
    buckets: usize,
    mask: u32,
    /// Cells per metre.
    scale: f64,
}

impl CellHash {
    fn new(particles: usize, reach: f64) -> Self {
        let buckets = (2 * particles).next_power_of_two();
        CellHash {
            buckets,
            mask: buckets as u32 - 1,
            // Cells a little over `reach`, so that round-off cannot put two
            // particles within `reach` two cells apart.
            scale: 1.0 / (reach * (1.0 + 1e-6)),
        }
    }

    /// The bucket of `cell`: the three cells of a row along the first axis, `a -
    /// 1, a, a + 1`, fall in consecutive buckets.
    #[inline]
    fn bucket(&self, [a, b, c]: [i32; 3]) -> u32 {
        ((b as u32).wrapping_mul(HASH[0]) ^ (c as u32).wrapping_mul(HASH[1])).wrapping_add(a as u32)
            & self.mask
    }

    /// The cell of position `p`. Non-finite coordinates land in cell 0 or far out
    /// (the divergence check reports them).
    #[inline]
    fn cell_of(&self, p: DVec3) -> [i32; 3] {
        (p * self.scale).to_array().map(|c| {
            let c = c.clamp(-1e9, 1e9);
            let t = c as i32;
            t - i32::from(f64::from(t) > c)
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Points from a small linear congruential generator, each coordinate in
    /// `[0, scale)`.
    fn points(n: usize, scale: DVec3, seed: u64) -> Vec<DVec3> {
        let mut state = seed;
        let mut next = || {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        (0..n)
            .map(|_| DVec3::new(next(), next(), next()) * scale)
            .collect()
    }

    /// A rebuild lists every pair within reach that no spring joins, each once, in
    /// order, as a search of every pair does; on threads too. In a dense box many
    /// particles share a cell; spread over a wide one the cells outnumber the
    /// buckets (8,192 for 3,000 particles), so that many buckets hold several.
    #[test]
    fn a_rebuild_lists_every_pair_within_reach_once_in_order() {
        let (n, reach) = (3000, 0.1);
        let joined = |i: usize, j: usize| (i + j).is_multiple_of(5);
        for (size, fewest) in [
            (DVec3::new(1.0, 0.5, 0.8), 5 * n),
            (DVec3::new(6.0, 0.3, 6.0), n / 4),
        ] {
            let x = points(n, size, 5);
            let mut expected = Vec::new();
            for i in 0..n {
                for j in i + 1..n {
                    if x[i].distance_squared(x[j]) < reach * reach && !joined(i, j) {
                        expected.push([i as u32, j as u32]);
                    }
                }
            }
            assert!(expected.len() > fewest, "only {} pairs", expected.len());
            for parallel in [false, true] {
                let mut pass = SelfCollision::default();
                pass.rebuild(&x, reach, joined, parallel);
                let listed: Vec<[u32; 2]> = pass.found.iter().flatten().copied().collect();
                assert_eq!(listed, expected, "{size}, parallel: {parallel}");
            }
        }
    }

    /// After any moves of up to the margin each (plus one common to all) the list
    /// is kept, and it holds every pair that has come within `h_c`, as a search of
    /// every pair finds them; a move past the margin rebuilds it.
    #[test]
    fn the_kept_list_holds_every_pair_within_the_thickness() {
        let (n, h_c) = (1500, 0.05);
        let margin = MARGIN * h_c;
        let start = points(n, DVec3::new(1.0, 1.0, 0.2), 7);
        let mut pass = SelfCollision::default();
        let still = |i: usize| (start[i], 0.0);
        pass.apply(&mut start.clone(), still, h_c, 0.0, |_, _| false, false);
        assert_eq!(pass.rebuilds(), 1);
        // Each particle moved by 0.9 of the margin in a direction of its own, and
        // the whole cloth by 3 m (the middle of the moves' range, taken as the
        // common move, then lies within a tenth of the margin of the 3 m).
        let moved: Vec<DVec3> = (start.iter().zip(points(n, DVec3::ONE, 11)))
            .map(|(p, d)| {
                let d = (d - DVec3::splat(0.5)).normalize_or(DVec3::X);
                *p + d * (0.9 * margin) + DVec3::new(3.0, 0.0, 0.0)
            })
            .collect();
        assert!(!pass.moved_more_than(&moved, margin, false));
        let listed: std::collections::HashSet<[u32; 2]> =
            pass.found.iter().flatten().copied().collect();
        let mut within = 0;
        for i in 0..n {
            for j in i + 1..n {
                if moved[i].distance(moved[j]) < h_c {
                    within += 1;
                    assert!(listed.contains(&[i as u32, j as u32]), "({i}, {j})");
                }
            }
        }
        assert!(within > 100, "only {within} pairs within h_c");
        // One particle past the margin: rebuilt.
        let mut far = moved.clone();
        far[0] += DVec3::new(0.0, 2.0 * margin, 0.0);
        assert!(pass.moved_more_than(&far, margin, false));
    }
}
