//! Laying out a resolved scene: the particles' start positions, the springs,
//! bars, triangles and texture coordinates of each layout, and the system.

use glam::{DVec2, DVec3};

use super::Resolved;
use super::anchors::rotation_matrix;
use crate::scene::{Layout, Orientation};
use crate::sim::laws::out_of_sphere;
use crate::sim::{
    Bar, GridShape, LatticeShape, Spring, SpringKind, SpringMaterial, System, Topology,
};

impl Resolved {
    /// The particles' start positions (m), in index order: the layout, with any
    /// particle inside the sphere collider moved out onto its surface, as the
    /// collider itself would move it, so that the run starts from a state that
    /// satisfies it (pushed out by the first step instead, the particles would
    /// gain at once an energy the divergence check cannot tell from a blow-up).
    ///
    /// A lattice (a solid, centred on `origin`) that would start with particles in
    /// the ground is first lifted whole until its lowest particle is one rest
    /// length above it, so that the jelly made bigger is dropped as the small one
    /// is: centred at the default origin, the 16³ jelly started 5 m deep, and the
    /// ground's penalty put 7.4e6 J into it on the first step.
    pub fn positions(&self) -> Vec<DVec3> {
        let mut positions = self.layout_positions();
        if let (Layout::Lattice, Some(ground)) = (self.layout, &self.params.ground) {
            let lowest = positions.iter().map(|x| x.y).fold(f64::INFINITY, f64::min);
            if lowest < ground.height {
                let lift = ground.height + self.rest_length.abs() - lowest;
                for x in &mut positions {
                    x.y += lift;
                }
            }
        }
        if let Some(sphere) = &self.params.sphere {
            for x in &mut positions {
                if let Some(outside) = out_of_sphere(*x, sphere) {
                    *x = outside;
                }
            }
        }
        positions
    }

    /// The layout's positions (m), before any collider.
    fn layout_positions(&self) -> Vec<DVec3> {
        let l = self.rest_length;
        let (w, h, d) = (
            self.width as usize,
            self.height as usize,
            self.depth as usize,
        );
        match self.layout {
            Layout::Grid => (0..h)
                .flat_map(|r| (0..w).map(move |c| (c as f64 * l, r as f64 * l)))
                .map(|(u, v)| {
                    self.origin
                        + match self.orientation {
                            Orientation::Vertical => DVec3::new(u, -v, 0.0),
                            Orientation::Horizontal => DVec3::new(u, 0.0, v),
                        }
                })
                .collect(),
            Layout::Spring => vec![self.origin, self.origin - DVec3::Y * (l + self.stretch)],
            Layout::Chain | Layout::Rope => (0..w)
                .map(|i| self.origin + DVec3::X * (i as f64 * l))
                .collect(),
            Layout::Mesh => {
                let rotation = rotation_matrix(self.rotation);
                (self.mesh.iter())
                    .flat_map(|m| m.positions.iter())
                    .map(|&p| self.origin + rotation * p)
                    .collect()
            }
            Layout::Lattice => {
                let rotation = rotation_matrix(self.rotation);
                let centre = DVec3::new((w - 1) as f64, (h - 1) as f64, (d - 1) as f64) * (0.5 * l);
                let mut positions = Vec::with_capacity(w * h * d);
                for z in 0..d {
                    for y in 0..h {
                        for x in 0..w {
                            let local = DVec3::new(x as f64, y as f64, z as f64) * l - centre;
                            positions.push(self.origin + rotation * local);
                        }
                    }
                }
                positions
            }
        }
    }

    /// Triangles to draw a layout that has no cloth surface as a solid: the six
    /// faces of a lattice (the jelly cube). Drawing only: they take no part in
    /// the physics (no aerodynamic drag). Empty for every other layout.
    pub fn display_surface(&self) -> Vec<[u32; 3]> {
        if self.layout != Layout::Lattice {
            return Vec::new();
        }
        let (w, h, d) = (self.width, self.height, self.depth);
        let index = |x: u32, y: u32, z: u32| (z * h + y) * w + x;
        let mut triangles = Vec::new();
        // A face of the box: the grid of points `at(u, v)` for u < nu, v < nv,
        // wound so that every face shows its front outside the box (the
        // renderer's front is clockwise seen from outside: `flip` when u x v
        // points out).
        let mut face = |nu: u32, nv: u32, flip: bool, at: &dyn Fn(u32, u32) -> u32| {
            for v in 0..nv.saturating_sub(1) {
                for u in 0..nu.saturating_sub(1) {
                    let (a, b, c, e) = (at(u, v), at(u + 1, v), at(u, v + 1), at(u + 1, v + 1));
                    if flip {
                        triangles.extend([[a, e, b], [a, c, e]]);
                    } else {
                        triangles.extend([[a, b, e], [a, e, c]]);
                    }
                }
            }
        };
        let (xl, yl, zl) = (w - 1, h - 1, d - 1);
        // x × y = z, z × x = y, y × z = x: the faces at the far end of each
        // axis flip the winding, those at 0 keep it.
        face(w, h, false, &|x, y| index(x, y, 0));
        face(w, h, true, &|x, y| index(x, y, zl));
        face(d, w, false, &|z, x| index(x, 0, z));
        face(d, w, true, &|z, x| index(x, yl, z));
        face(h, d, false, &|y, z| index(0, y, z));
        face(h, d, true, &|y, z| index(xl, y, z));
        triangles
    }

    /// Lays out the system.
    pub fn build(&self) -> System {
        let n = self.particle_count();
        let masses = vec![self.particle_mass; n];
        let positions = self.positions();
        let mut topology = match self.layout {
            Layout::Grid => self.grid_topology(),
            Layout::Spring => Topology {
                springs: vec![self.spring(0, 1, self.rest_length, SpringKind::Other)],
                ..Topology::default()
            },
            Layout::Mesh => self.mesh_topology(),
            Layout::Chain | Layout::Rope => self.line_topology(),
            Layout::Lattice => Topology {
                springs: self.lattice_springs(),
                ..Topology::default()
            },
        };
        if topology.triangles.is_empty() {
            topology.uvs = Vec::new();
        }
        topology.materials = SpringKind::ALL.map(|kind| SpringMaterial {
            stiffness: self.stiffness * self.spring_scale(kind),
            damping: self.damping * self.spring_scale(kind),
        });
        topology.grid = (self.layout == Layout::Grid).then_some(GridShape {
            width: self.width as usize,
            height: self.height as usize,
        });
        topology.lattice = (self.layout == Layout::Lattice).then_some(LatticeShape {
            width: self.width as usize,
            height: self.height as usize,
            depth: self.depth as usize,
        });
        let mut system = System::new(masses, positions, &self.pins, topology, self.params);
        if !self.colliders.is_empty() {
            system.set_colliders(self.colliders.clone());
        }
        system
    }

    /// A spring of `kind` from `a` to `b`.
    fn spring(&self, a: usize, b: usize, rest: f64, kind: SpringKind) -> Spring {
        Spring {
            a: a as u32,
            b: b as u32,
            rest,
            kind,
        }
    }

    /// A grid's springs (or bars), its two triangles per cell and its texture
    /// coordinates.
    fn grid_topology(&self) -> Topology {
        let l = self.rest_length;
        let (w, h) = (self.width as usize, self.height as usize);
        // At most six springs, four bars and two triangles a particle: reserved
        // whole, a big cloth's lists never hold twice their length while growing.
        let (mut springs, mut bars, mut triangles, mut uvs) = (
            Vec::with_capacity(if self.bars { 0 } else { 6 * w * h }),
            Vec::with_capacity(if self.bars { 4 * w * h } else { 0 }),
            Vec::with_capacity(2 * w * h),
            Vec::with_capacity(w * h),
        );
        for r in 0..h {
            for c in 0..w {
                uvs.push(DVec2::new(
                    c as f64 / (w.max(2) - 1) as f64,
                    r as f64 / (h.max(2) - 1) as f64,
                ));
            }
        }
        let p = |r: usize, c: usize| r * w + c;
        let diagonal = l * std::f64::consts::SQRT_2;
        // Springs, or on a grid of bars (seed 001) a bar for each structural
        // and shear pair and nothing for bending.
        let mut join = |a: usize, b: usize, rest: f64, kind: SpringKind| {
            if !self.bars {
                springs.push(self.spring(a, b, rest, kind));
            } else if kind != SpringKind::Bend {
                bars.push(Bar {
                    a: a as u32,
                    b: b as u32,
                    length: rest,
                });
            }
        };
        let (shear, bend) = (
            self.bars || self.shear_scale > 0.0,
            !self.bars && self.bend_scale > 0.0,
        );
        for r in 0..h {
            for c in 0..w {
                if c + 1 < w {
                    join(p(r, c), p(r, c + 1), l, SpringKind::Structural);
                }
                if r + 1 < h {
                    join(p(r, c), p(r + 1, c), l, SpringKind::Structural);
                }
                if shear && r + 1 < h && c + 1 < w {
                    join(p(r, c), p(r + 1, c + 1), diagonal, SpringKind::Shear);
                    join(p(r, c + 1), p(r + 1, c), diagonal, SpringKind::Shear);
                }
                if bend && c + 2 < w {
                    join(p(r, c), p(r, c + 2), 2.0 * l, SpringKind::Bend);
                }
                if bend && r + 2 < h {
                    join(p(r, c), p(r + 2, c), 2.0 * l, SpringKind::Bend);
                }
                if r + 1 < h && c + 1 < w {
                    let (a, b, d, e) = (p(r, c), p(r, c + 1), p(r + 1, c), p(r + 1, c + 1));
                    triangles.push([a, b, d].map(|i| i as u32));
                    triangles.push([b, e, d].map(|i| i as u32));
                }
            }
        }
        Topology {
            springs,
            bars,
            triangles,
            uvs,
            ..Topology::default()
        }
    }

    /// A mesh's edge and bend springs, its triangles and its texture coordinates.
    fn mesh_topology(&self) -> Topology {
        let Some(m) = &self.mesh else {
            return Topology::default();
        };
        // Rest lengths from the file's coordinates (the start positions
        // may have been moved out of the sphere).
        let rest = |[a, b]: [u32; 2]| m.positions[a as usize].distance(m.positions[b as usize]);
        let mut springs = Vec::new();
        for &edge in &m.edges {
            springs.push(self.spring(
                edge[0] as usize,
                edge[1] as usize,
                rest(edge),
                SpringKind::Structural,
            ));
        }
        if self.bend_scale > 0.0 {
            for &pair in &m.bends {
                springs.push(self.spring(
                    pair[0] as usize,
                    pair[1] as usize,
                    rest(pair),
                    SpringKind::Bend,
                ));
            }
        }
        Topology {
            springs,
            triangles: m.triangles.clone(),
            uvs: m.uvs.clone(),
            ..Topology::default()
        }
    }

    /// A chain's springs or a rope's bars, each particle to the next.
    fn line_topology(&self) -> Topology {
        let (mut springs, mut bars) = (Vec::new(), Vec::new());
        let l = self.rest_length;
        for i in 0..self.width as usize {
            if i > 0 {
                if self.layout == Layout::Chain {
                    springs.push(self.spring(i - 1, i, l, SpringKind::Other));
                } else {
                    bars.push(Bar {
                        a: (i - 1) as u32,
                        b: i as u32,
                        length: l,
                    });
                }
            }
        }
        Topology {
            springs,
            bars,
            ..Topology::default()
        }
    }

    /// A lattice's springs: every neighbour within one cell, axis (structural),
    /// face diagonal (shear) and body diagonal (other), as in seed 002's cube.
    fn lattice_springs(&self) -> Vec<Spring> {
        let l = self.rest_length;
        let (w, h, d) = (
            self.width as usize,
            self.height as usize,
            self.depth as usize,
        );
        let index = |x: usize, y: usize, z: usize| (z * h + y) * w + x;
        let mut springs = Vec::new();
        for z in 0..d {
            for y in 0..h {
                for x in 0..w {
                    for dz in 0..=1usize {
                        for dy in -1..=1i64 {
                            for dx in -1..=1i64 {
                                let forward = dz == 1 || dy == 1 || (dy == 0 && dx == 1);
                                let (nx, ny, nz) = (x as i64 + dx, y as i64 + dy, z + dz);
                                if !forward
                                    || nx < 0
                                    || ny < 0
                                    || nx >= w as i64
                                    || ny >= h as i64
                                    || nz >= d
                                {
                                    continue;
                                }
                                let steps =
                                    dx.unsigned_abs() as usize + dy.unsigned_abs() as usize + dz;
                                let kind =
                                    [SpringKind::Structural, SpringKind::Shear, SpringKind::Other]
                                        [steps - 1];
                                let rest = l * (steps as f64).sqrt();
                                springs.push(self.spring(
                                    index(x, y, z),
                                    index(nx as usize, ny as usize, nz),
                                    rest,
                                    kind,
                                ));
                            }
                        }
                    }
                }
            }
        }
        springs
    }
}
