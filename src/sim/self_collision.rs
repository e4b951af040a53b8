//! Self-collision of a cloth's particles: no two particles that no spring joins
//! come closer than the contact thickness `h_c`, and the layers that touch rub with
//! Coulomb friction. Every engine runs this one pass on f64 positions after the
//! stretch limit and before the colliders.
//!
//! # Method
//! * Candidate pairs come from a spatial hash (cells of `reach`, Müller's dense hash
//!   of Ten Minute Physics, filled by a counting sort): every pair not joined by a
//!   spring closer than `reach = h_c + 2 margin`, with `margin = h_c / 2`. The list
//!   is rebuilt only when some particle has moved more than `margin` since the last
//!   rebuild, its cloth's mean move taken off, so a pair missing from it cannot have
//!   come within `h_c`: each of its particles moved less than `margin` against the
//!   same common move. A cloth at rest or falling whole rebuilds never, a folding
//!   one every few steps; the check is two passes over the particles.
//! * Each step, every candidate pair closer than `h_c` is pushed apart along its
//!   line to `h_c`, split by inverse mass (one Gauss-Seidel pass over the list).
//!   Then friction: the pair's relative move along the contact in this step is cut
//!   by up to `μ` times the push, as Coulomb's law bounds the tangential impulse by
//!   `μ` times the normal one. The moves become velocities (`δ / h`) as every
//!   constraint's do.
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
//! Nothing is allocated per step after the first, unless a rebuild finds more than
//! 8 candidate pairs a particle.

use glam::DVec3;

/// The cell itself, then 13 of its 26 neighbours: one of each pair of opposite
/// offsets.
const HALF_NEIGHBOURHOOD: [[i32; 3]; 14] = [
    [0, 0, 0],
    [1, 0, 0],
    [-1, 1, 0],
    [0, 1, 0],
    [1, 1, 0],
    [-1, -1, 1],
    [0, -1, 1],
    [1, -1, 1],
    [-1, 0, 1],
    [0, 0, 1],
    [1, 0, 1],
    [-1, 1, 1],
    [0, 1, 1],
    [1, 1, 1],
];

/// The self-collision pass and what it keeps between steps.
#[derive(Clone, Debug, Default)]
pub struct SelfCollision {
    /// Candidate pairs `(i, j)`, `i < j`, from the last rebuild.
    pairs: Vec<[u32; 2]>,
    /// Positions at the last rebuild.
    anchor: Vec<DVec3>,
    /// First entry of each hash cell in `entries` (counting sort), one more than
    /// the cells.
    cell_start: Vec<u32>,
    /// Particle indices sorted by hash cell.
    entries: Vec<u32>,
    /// Each particle's cell at the last rebuild.
    cells: Vec<[i32; 3]>,
    /// The thickness the list was built for.
    built_for: f64,
    /// Pairs pushed apart by the last pass.
    contacts: usize,
}

impl SelfCollision {
    /// Pairs pushed apart by the last pass (the panel's contact count).
    pub fn contacts(&self) -> usize {
        self.contacts
    }

    /// One pass on positions `x` (moved in place) that were at `start` at the start
    /// of the step, with inverse masses `w` (0: pinned), thickness `h_c` (m),
    /// friction `mu`, where `joined(i, j)` says that a spring joins `i` and `j`.
    pub fn apply(
        &mut self,
        x: &mut [DVec3],
        start: &[DVec3],
        w: &[f64],
        h_c: f64,
        mu: f64,
        joined: impl Fn(usize, usize) -> bool,
    ) {
        self.contacts = 0;
        if h_c <= 0.0 || x.len() < 2 {
            return;
        }
        let margin = 0.5 * h_c;
        if self.moved_more_than(x, margin) || self.built_for != h_c {
            self.rebuild(x, h_c + 2.0 * margin, joined);
            self.built_for = h_c;
        }
        let h2 = h_c * h_c;
        for &[i, j] in &self.pairs {
            let (i, j) = (i as usize, j as usize);
            let d = x[i] - x[j];
            let l2 = d.length_squared();
            let ends = w[i] + w[j];
            if l2 >= h2 || l2 == 0.0 || ends == 0.0 {
                continue;
            }
            let l = l2.sqrt();
            let normal = d / l;
            let push = (h_c - l) / ends;
            x[i] += w[i] * push * normal;
            x[j] -= w[j] * push * normal;
            if mu > 0.0 {
                // The pair's relative move this step, along the contact.
                let rel = (x[i] - start[i]) - (x[j] - start[j]);
                let slide = rel - rel.dot(normal) * normal;
                let length = slide.length();
                if length > 0.0 {
                    let cut = (mu * (h_c - l) / length).min(1.0) / ends;
                    x[i] -= w[i] * cut * slide;
                    x[j] += w[j] * cut * slide;
                }
            }
            self.contacts += 1;
        }
    }

    /// Whether some particle moved more than `margin` since the last rebuild (or
    /// there was none), not counting the cloth's mean move: a pair's distance
    /// changes by at most the sum of its particles' moves less any common move, so
    /// a cloth falling or swinging as a whole keeps its list.
    fn moved_more_than(&self, x: &[DVec3], margin: f64) -> bool {
        if self.anchor.len() != x.len() {
            return true;
        }
        let common = (x.iter().zip(&self.anchor))
            .map(|(p, a)| *p - *a)
            .sum::<DVec3>()
            / x.len() as f64;
        let m2 = margin * margin;
        !common.is_finite()
            || (x.iter().zip(&self.anchor))
                .any(|(p, a)| (*p - *a - common).length_squared() > m2 || !p.is_finite())
    }

    /// Rebuilds the candidate pairs within `reach` of each other.
    fn rebuild(&mut self, x: &[DVec3], reach: f64, joined: impl Fn(usize, usize) -> bool) {
        self.anchor.clear();
        self.anchor.extend_from_slice(x);
        self.pairs.clear();
        let n = x.len();
        // Room for 8 pairs a particle from the first rebuild on (a flat cloth has
        // none, a pile of layers a few): later rebuilds allocate only past that.
        self.pairs.reserve(8 * n);
        // A power of two at least twice the particles, so that a mask picks the bucket.
        let buckets = (2 * n).next_power_of_two();
        // Each particle's cell, once; non-finite positions land in one cell (the
        // divergence check reports them).
        self.cells.clear();
        self.cells.extend(x.iter().map(|p| {
            (*p / reach)
                .floor()
                .to_array()
                .map(|c| if c.is_finite() { c as i32 } else { 0 })
        }));
        let bucket = |[a, b, c]: [i32; 3]| {
            let h = (a.wrapping_mul(92_837_111))
                ^ (b.wrapping_mul(689_287_499))
                ^ (c.wrapping_mul(283_923_481));
            h.unsigned_abs() as usize & (buckets - 1)
        };
        self.cell_start.clear();
        self.cell_start.resize(buckets + 1, 0);
        for &cell in &self.cells {
            self.cell_start[bucket(cell)] += 1;
        }
        let mut total = 0;
        for s in &mut self.cell_start {
            total += *s;
            *s = total;
        }
        self.entries.clear();
        self.entries.resize(n, 0);
        for (i, &cell) in self.cells.iter().enumerate() {
            let b = bucket(cell);
            self.cell_start[b] -= 1;
            self.entries[self.cell_start[b] as usize] = i as u32;
        }
        let reach2 = reach * reach;
        for (i, p) in x.iter().enumerate() {
            let [a, b, c] = self.cells[i];
            // The cell itself (partners after `i`) and the 13 cells on one side of
            // it (every partner): each pair of cells is visited from one of them.
            for (k, [da, db, dc]) in HALF_NEIGHBOURHOOD.iter().enumerate() {
                let cell = [a + da, b + db, c + dc];
                let at = bucket(cell);
                let (from, to) = (self.cell_start[at], self.cell_start[at + 1]);
                for &j in &self.entries[from as usize..to as usize] {
                    let j = j as usize;
                    // A bucket holds every cell that hashes to it: only the
                    // particles of the cell asked for count.
                    if (k > 0 || j > i)
                        && self.cells[j] == cell
                        && p.distance_squared(x[j]) < reach2
                        && !joined(i, j)
                    {
                        self.pairs.push([i.min(j) as u32, i.max(j) as u32]);
                    }
                }
            }
        }
    }
}
