//! A static triangle mesh as a collider: its triangles binned once into a uniform
//! grid of cells, each listing the triangles within the contact's reach of it, so
//! that a query reads one cell.

use glam::DVec3;

/// Most cells the grid may have; past it the cells grow.
const MAX_CELLS: usize = 1 << 21;

/// A closed triangle mesh (outward normals by its counter-clockwise winding) in its
/// own frame, with its grid of cells.
#[derive(Clone, Debug, PartialEq)]
pub struct ColliderMesh {
    positions: Vec<DVec3>,
    triangles: Vec<[u32; 3]>,
    /// Unit normal of each triangle.
    normals: Vec<DVec3>,
    /// A ball (centre, radius in m) holding each triangle: a query skips the
    /// triangles whose ball is farther than its nearest so far.
    balls: Vec<(DVec3, f64)>,
    /// The grid's lowest corner (m), its cell size (m) and its cells per axis.
    origin: DVec3,
    cell: f64,
    cells: [usize; 3],
    /// Triangles of cell `c`: `members[starts[c]..starts[c + 1]]`.
    starts: Vec<u32>,
    members: Vec<u32>,
    /// The reach (m) a query is answered to: each cell lists every triangle within
    /// it of the cell.
    reach: f64,
    bounding_radius: f64,
}

impl ColliderMesh {
    /// The mesh of `positions` (m) and `triangles`, answering queries within
    /// `reach` (m) of its surface. Triangles of no area are left out.
    pub fn new(positions: Vec<DVec3>, triangles: Vec<[u32; 3]>, reach: f64) -> Self {
        let reach = reach.max(1e-6);
        let corner = |t: &[u32; 3], k: usize| positions[t[k] as usize];
        let triangles: Vec<[u32; 3]> = triangles
            .into_iter()
            .filter(|t| {
                let n = (corner(t, 1) - corner(t, 0)).cross(corner(t, 2) - corner(t, 0));
                n.length_squared() > 0.0
            })
            .collect();
        let normals = triangles
            .iter()
            .map(|t| {
                (corner(t, 1) - corner(t, 0))
                    .cross(corner(t, 2) - corner(t, 0))
                    .normalize()
            })
            .collect();
        let (lo, hi) = positions.iter().fold(
            (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
            |(lo, hi), &p| (lo.min(p), hi.max(p)),
        );
        let (lo, hi) = if positions.is_empty() {
            (DVec3::ZERO, DVec3::ZERO)
        } else {
            (lo - DVec3::splat(reach), hi + DVec3::splat(reach))
        };
        let size = hi - lo;
        // About two cells a triangle, none much smaller than the reach (each
        // lists the triangles within the reach of it, which then dominate).
        let volume = size.x * size.y * size.z;
        let target = (volume / (2.0 * triangles.len().max(1) as f64)).cbrt();
        let mut cell = target.max(0.5 * reach);
        let count = |cell: f64| size.to_array().map(|s| ((s / cell).ceil() as usize).max(1));
        while count(cell).iter().product::<usize>() > MAX_CELLS {
            cell *= 1.25;
        }
        let balls = triangles
            .iter()
            .map(|t| {
                let centre = (corner(t, 0) + corner(t, 1) + corner(t, 2)) / 3.0;
                let radius = (0..3)
                    .map(|k| corner(t, k).distance(centre))
                    .fold(0.0, f64::max);
                (centre, radius)
            })
            .collect();
        let bounding_radius = positions.iter().map(|p| p.length()).fold(0.0, f64::max);
        let mut mesh = Self {
            positions,
            triangles,
            normals,
            balls,
            origin: lo,
            cell,
            cells: count(cell),
            starts: Vec::new(),
            members: Vec::new(),
            reach,
            bounding_radius,
        };
        mesh.bin();
        mesh
    }

    /// Lists each triangle in every cell its box (grown by the reach) overlaps,
    /// by counting sort.
    fn bin(&mut self) {
        let n = self.cells.iter().product::<usize>();
        let ranges: Vec<[[usize; 2]; 3]> = (0..self.triangles.len())
            .map(|t| self.cell_range(t))
            .collect();
        let mut counts = vec![0u32; n + 1];
        for_each_cell(&ranges, self.cells, |c, _| counts[c + 1] += 1);
        for c in 0..n {
            counts[c + 1] += counts[c];
        }
        let mut fill = counts.clone();
        let mut members = vec![0u32; counts[n] as usize];
        for_each_cell(&ranges, self.cells, |c, t| {
            members[fill[c] as usize] = t as u32;
            fill[c] += 1;
        });
        (self.starts, self.members) = (counts, members);
    }

    /// The cells (from, to inclusive, per axis) that triangle `t`'s box, grown by
    /// the reach, overlaps.
    fn cell_range(&self, t: usize) -> [[usize; 2]; 3] {
        let corners = self.triangles[t].map(|i| self.positions[i as usize]);
        let lo = corners[0].min(corners[1]).min(corners[2]) - DVec3::splat(self.reach);
        let hi = corners[0].max(corners[1]).max(corners[2]) + DVec3::splat(self.reach);
        std::array::from_fn(|a| {
            let index = |x: f64| {
                let i = ((x - self.origin[a]) / self.cell).floor();
                (i.max(0.0) as usize).min(self.cells[a] - 1)
            };
            [index(lo[a]), index(hi[a])]
        })
    }

    /// The cell holding `p`, if inside the grid.
    fn cell_of(&self, p: DVec3) -> Option<usize> {
        let mut index = 0;
        for a in (0..3).rev() {
            let i = ((p[a] - self.origin[a]) / self.cell).floor();
            if !(i >= 0.0 && (i as usize) < self.cells[a]) {
                return None;
            }
            index = index * self.cells[a] + i as usize;
        }
        Some(index)
    }

    /// Its triangles.
    pub fn triangles(&self) -> &[[u32; 3]] {
        &self.triangles
    }

    /// Its vertices (m, in its own frame).
    pub fn positions(&self) -> &[DVec3] {
        &self.positions
    }

    /// The radius of a ball about its frame's origin that holds it.
    pub fn bounding_radius(&self) -> f64 {
        self.bounding_radius
    }

    /// The box (m, in its own frame) outside which no query finds a surface: its
    /// grid's.
    pub fn bounds(&self) -> (DVec3, DVec3) {
        let size = DVec3::new(
            self.cells[0] as f64,
            self.cells[1] as f64,
            self.cells[2] as f64,
        );
        (self.origin, self.origin + size * self.cell)
    }

    /// How far a query reaches from the surface: the least half size that a move
    /// in one step may take without passing a particle.
    pub fn smallest_half_size(&self) -> f64 {
        self.reach
    }

    /// The signed distance of `p` from the surface (negative inside, by the
    /// nearest triangle's side) and the outward normal, when within `reach` (at
    /// most the mesh's own) of it.
    pub fn surface(&self, p: DVec3, reach: f64) -> Option<(f64, DVec3)> {
        let c = self.cell_of(p)?;
        let list = &self.members[self.starts[c] as usize..self.starts[c + 1] as usize];
        let reach = reach.min(self.reach);
        // The nearest triangle; among those as near (an edge or a corner), the one
        // whose plane is farthest, which tells the side.
        let mut best: Option<(f64, f64, DVec3, usize)> = None;
        // Past the cells' reach no triangle changes the answer (the nearest that
        // far gives none); the margins are far above the rounding of the gap.
        let far2 = self.reach * self.reach * (1.0 + 1e-9);
        for &t in list {
            let t = t as usize;
            // A triangle whose ball is farther than the nearest so far (or than
            // the reach) has no point as near: skipped, the answer unchanged.
            let limit2 = best.map_or(far2, |(b2, ..)| b2.min(far2)) * (1.0 + 1e-9);
            let (centre, radius) = self.balls[t];
            let gap = p.distance(centre) - radius;
            if gap > 0.0 && gap * gap > limit2 {
                continue;
            }
            let [a, b, c] = self.triangles[t].map(|i| self.positions[i as usize]);
            let q = closest_on_triangle(p, a, b, c);
            let d2 = (p - q).length_squared();
            let side = (p - q).dot(self.normals[t]);
            let better = match best {
                None => true,
                Some((b2, bside, _, _)) => {
                    d2 < b2 * (1.0 - 1e-12)
                        || (d2 <= b2 * (1.0 + 1e-12) && side.abs() > bside.abs())
                }
            };
            if better {
                best = Some((d2, side, q, t));
            }
        }
        let (d2, side, q, t) = best?;
        let d = d2.sqrt();
        // Inside, as deep as the cells reach; outside, within `reach`.
        if side < 0.0 {
            return (d < self.reach).then_some((-d, self.normals[t]));
        }
        if d >= reach {
            return None;
        }
        let normal = if d > 1e-12 {
            (p - q) / d
        } else {
            self.normals[t]
        };
        Some((d, normal))
    }
}

/// Calls `f(cell, triangle)` for every cell of each triangle's range.
fn for_each_cell(ranges: &[[[usize; 2]; 3]], cells: [usize; 3], mut f: impl FnMut(usize, usize)) {
    for (t, [x, y, z]) in ranges.iter().enumerate() {
        for k in z[0]..=z[1] {
            for j in y[0]..=y[1] {
                for i in x[0]..=x[1] {
                    f((k * cells[1] + j) * cells[0] + i, t);
                }
            }
        }
    }
}

/// The point of triangle `a b c` nearest to `p` (by the triangle's Voronoi
/// regions: its corners, its edges, its face).
pub(super) fn closest_on_triangle(p: DVec3, a: DVec3, b: DVec3, c: DVec3) -> DVec3 {
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return a;
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return a + ab * (d1 / (d1 - d3));
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return a + ac * (d2 / (d2 - d6));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
    }
    let denom = 1.0 / (va + vb + vc);
    a + ab * (vb * denom) + ac * (vc * denom)
}
