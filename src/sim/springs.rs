//! Spring topology: damped springs between particle pairs, built once per scene.
//!
//! A spring joining particles `a` and `b` with rest length `L`, stiffness `k` (N/m)
//! and damping `b` (N·s/m) pushes on `a` with
//! `f_a = -(k (l - L) + b (v_a - v_b)·u) u`, `f_b = -f_a`, where `u` is the unit
//! vector from `b` to `a` and `l` their distance. This module only stores the
//! springs; `forces` evaluates them.

use super::{GridShape, LatticeShape};

/// What a spring stands for in the cloth, so that counts and colours can be shown per kind.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum SpringKind {
    /// Direct neighbours along a grid axis: resists stretching.
    Structural,
    /// Diagonal neighbours in a grid cell: resists shearing.
    Shear,
    /// Neighbours two apart along an axis: resists bending.
    Bend,
    /// Anything else (the chain's links, the jelly cube's body diagonals).
    Other,
}

impl SpringKind {
    /// Every kind, in display order.
    pub const ALL: [SpringKind; 4] = [Self::Structural, Self::Shear, Self::Bend, Self::Other];

    /// The kind's place in [`Self::ALL`], for tables indexed by kind.
    pub const fn index(self) -> usize {
        self as usize
    }

    /// Lower-case name used in reports and the command line.
    pub fn name(self) -> &'static str {
        match self {
            Self::Structural => "structural",
            Self::Shear => "shear",
            Self::Bend => "bend",
            Self::Other => "other",
        }
    }
}

/// One damped spring. Endpoints are particle indices with `a < b`. Its
/// stiffness and damping are its kind's ([`SpringMaterial`]): 24 bytes a spring,
/// where two more coefficients each would take 40.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Spring {
    /// First endpoint (the smaller index).
    pub a: u32,
    /// Second endpoint.
    pub b: u32,
    /// Rest length `L` in metres.
    pub rest: f64,
    /// What the spring stands for, and so its stiffness and damping.
    pub kind: SpringKind,
}

const _: () = assert!(std::mem::size_of::<Spring>() == 24);

/// The stiffness and damping every spring of one kind has.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SpringMaterial {
    /// Stiffness `k` in N/m.
    pub stiffness: f64,
    /// Damping `b` along the spring in N·s/m.
    pub damping: f64,
}

/// One [`SpringMaterial`] per [`SpringKind`], indexed by [`SpringKind::index`].
pub type SpringMaterials = [SpringMaterial; SpringKind::ALL.len()];

// [`SpringKind::index`] is the declaration order: `ALL` must keep it.
const _: () = {
    let mut i = 0;
    while i < SpringKind::ALL.len() {
        assert!(SpringKind::ALL[i].index() == i);
        i += 1;
    }
};

/// A rigid bar (seed 001): a distance constraint relaxed after each step, not a force.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bar {
    /// First endpoint.
    pub a: u32,
    /// Second endpoint.
    pub b: u32,
    /// Length the bar keeps, in metres.
    pub length: f64,
}

/// Normalises each spring to `a < b`, drops self-springs, sorts by endpoints and removes
/// duplicates (the first of equal pairs wins), so that the list is canonical and
/// reproducible whatever order a builder produced.
pub fn canonicalize(springs: &mut Vec<Spring>) {
    for s in springs.iter_mut() {
        if s.a > s.b {
            std::mem::swap(&mut s.a, &mut s.b);
        }
    }
    springs.retain(|s| s.a != s.b);
    springs.sort_by_key(|s| (s.a, s.b));
    springs.dedup_by_key(|s| (s.a, s.b));
}

/// The order in which the Gauss-Seidel passes over the springs (XPBD's springs and
/// Provot's stretch limit) visit `springs` (canonical: sorted by their ends), as
/// indices. On a grid (`p = row * width + column`) or a lattice the springs are
/// grouped into colour classes in which no two share a particle, so that a class
/// can be corrected in any order, in parallel or in SIMD lanes, with the same
/// result. On a grid: by stencil direction (in the grid kernel's order: right, two
/// right, down-left, down, down-right, two down), then by the parity of the
/// spring's step along its direction (column `c / dc` for rows, row `r / dr`
/// otherwise), then by first end. On a lattice: by direction and colour as
/// [`LatticeShape::constraint_class`] says, then by first end. Springs that are not
/// on the stencil come last, in canonical order; without a grid or a lattice the
/// order is the canonical one.
///
/// Each spring's key is worked out once, before a stable sort: compared afresh,
/// the keys' searches of the stencil would dominate a big model's build.
///
/// The colour order is also what keeps a single pass stable: visited in particle
/// order, one stretch-limit pass on a heavily loaded cloth (the 48 x 48 `bench`
/// cloth with a 10% limit) lets a checkerboard mode near the pins grow until it
/// diverges, in this engine and in an independent NumPy reproduction; visited by
/// colour, the same pass stays bounded (`tests/physics/stretch_limit.rs`).
pub fn constraint_order(
    springs: &[Spring],
    grid: Option<GridShape>,
    lattice: Option<LatticeShape>,
) -> Vec<u32> {
    let mut order: Vec<u32> = (0..springs.len() as u32).collect();
    if let Some(lattice) = lattice.filter(|l| !l.is_empty()) {
        let key = |s: &Spring| {
            let (a, b) = (s.a as usize, s.b as usize);
            let class = lattice.constraint_class(a, b);
            (class.unwrap_or((usize::MAX, 0)), a)
        };
        order.sort_by_cached_key(|&i| key(&springs[i as usize]));
        return order;
    }
    let Some(GridShape { width, .. }) = grid.filter(|g| g.width > 0) else {
        return order;
    };
    let key = |s: &Spring| {
        let (a, b) = (s.a as usize, s.b as usize);
        let (r, c) = (a / width, a % width);
        let (dr, dc) = (b / width - r, (b % width) as isize - c as isize);
        let direction = STENCIL_DIRECTIONS
            .iter()
            .position(|&d| d == (dr, dc))
            .unwrap_or(STENCIL_DIRECTIONS.len());
        let colour = match r.checked_div(dr) {
            Some(run) => run % 2,
            None => (c / dc.unsigned_abs().max(1)) % 2,
        };
        ((direction as u64) << 33) | ((colour as u64) << 32) | a as u64
    };
    // One packed key a spring (8 bytes), where a cached tuple key took 32.
    let keys: Vec<u64> = springs.iter().map(key).collect();
    order.sort_by_key(|&i| keys[i as usize]);
    order
}

/// The grid stencil's directions (row, column offsets), in the order the grid
/// kernel and [`constraint_order`] visit them.
pub const STENCIL_DIRECTIONS: [(usize, isize); 6] =
    [(0, 1), (0, 2), (1, -1), (1, 0), (1, 1), (2, 0)];

/// The kind of spring in each of [`STENCIL_DIRECTIONS`].
pub const STENCIL_KINDS: [SpringKind; 6] = [
    SpringKind::Structural,
    SpringKind::Bend,
    SpringKind::Shear,
    SpringKind::Structural,
    SpringKind::Shear,
    SpringKind::Bend,
];

/// For each particle, the springs that touch it: a compressed adjacency list
/// (`offsets[i]..offsets[i + 1]` indexes `entries`). It lets every particle gather
/// its own spring forces, so threads never write the same memory.
#[derive(Clone, Debug, Default)]
pub struct Adjacency {
    offsets: Vec<u32>,
    /// Spring index, with the top bit set when the particle is the spring's `b` end.
    entries: Vec<u32>,
}

const B_END: u32 = 1 << 31;

/// The pairs of particles that rigid bars join, which self-collision leaves alone
/// as it does the pairs a spring joins.
#[derive(Clone, Debug, Default)]
pub struct BarPairs(Vec<(u32, u32)>);

impl BarPairs {
    /// The pairs `bars` join.
    pub fn new(bars: &[Bar]) -> Self {
        let mut pairs: Vec<(u32, u32)> =
            bars.iter().map(|b| (b.a.min(b.b), b.a.max(b.b))).collect();
        pairs.sort_unstable();
        Self(pairs)
    }

    /// Whether a bar joins particles `i` and `j`.
    pub fn join(&self, i: usize, j: usize) -> bool {
        let (Ok(a), Ok(b)) = (u32::try_from(i.min(j)), u32::try_from(i.max(j))) else {
            return false;
        };
        self.0.binary_search(&(a, b)).is_ok()
    }
}

impl Adjacency {
    /// Builds the adjacency of `springs` over `particle_count` particles.
    pub fn new(particle_count: usize, springs: &[Spring]) -> Self {
        let mut counts = vec![0u32; particle_count + 1];
        for s in springs {
            counts[s.a as usize + 1] += 1;
            counts[s.b as usize + 1] += 1;
        }
        for i in 0..particle_count {
            counts[i + 1] += counts[i];
        }
        let offsets = counts.clone();
        let mut cursor = counts;
        let mut entries = vec![0u32; springs.len() * 2];
        for (index, s) in springs.iter().enumerate() {
            let index = index as u32;
            entries[cursor[s.a as usize] as usize] = index;
            cursor[s.a as usize] += 1;
            entries[cursor[s.b as usize] as usize] = index | B_END;
            cursor[s.b as usize] += 1;
        }
        Self { offsets, entries }
    }

    /// Whether one of `springs` (the ones this adjacency was built from) joins
    /// particles `i` and `j`.
    pub fn joins(&self, springs: &[Spring], i: usize, j: usize) -> bool {
        self.springs_of(i).any(|(s, _)| {
            let s = &springs[s];
            (s.a as usize == j) || (s.b as usize == j)
        })
    }

    /// The springs touching particle `i`, each with the sign of its force on `i`
    /// (`+1` at the `a` end, `-1` at the `b` end).
    pub fn springs_of(&self, i: usize) -> impl Iterator<Item = (usize, f64)> + '_ {
        let range = self.offsets[i] as usize..self.offsets[i + 1] as usize;
        self.entries[range].iter().map(|&e| {
            if e & B_END == 0 {
                (e as usize, 1.0)
            } else {
                ((e & !B_END) as usize, -1.0)
            }
        })
    }
}
