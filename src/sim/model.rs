//! What stays fixed while the state advances: parameters, colliders, topology and
//! the model built from them, with the energy of a state.

use std::sync::OnceLock;

use glam::{DVec2, DVec3};

use super::colliders::Collider;
use super::forces;
use super::{
    Adjacency, Bar, BarPairs, Energy, ForceTerms, GridShape, Integrator, LatticeShape, Spring,
    SpringKind, SpringMaterial, SpringMaterials, Wind,
};

/// A horizontal ground plane `y = height` with penalty contact (seed 002's jelly cube).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ground {
    /// Height of the plane in m.
    pub height: f64,
    /// Penalty stiffness `k_c` in N/m.
    pub stiffness: f64,
    /// Damping of the normal velocity while in contact, N·s/m.
    pub damping: f64,
    /// Coulomb friction coefficient μ of the ground (0: frictionless).
    pub friction: f64,
}

/// A solid sphere that particles cannot enter (seed 003's collider), enforced by
/// projection onto its surface after each step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sphere {
    /// Centre in m.
    pub center: DVec3,
    /// Radius in m.
    pub radius: f64,
}

/// Everything about the simulation that is not topology or state. Units are SI.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Params {
    /// Gravitational acceleration in m/s² (default: (0, -9.81, 0)).
    pub gravity: DVec3,
    /// A force in N on every free particle besides gravity (seed 001's force
    /// vector, whose direction and strength the user sets).
    pub force: DVec3,
    /// Mean wind velocity in m/s.
    pub wind: DVec3,
    /// Gust amplitude in m/s (0: steady).
    pub gust: f64,
    /// Air density `rho` in kg/m³ (default: 1.2).
    pub air_density: f64,
    /// Aerodynamic drag coefficient `C_d` (dimensionless, default: 1).
    pub drag_coefficient: f64,
    /// Viscous air damping `c` in `-c v`, N·s/m (default: 0).
    pub air_damping: f64,
    /// Ground plane the particles touch, if any: its height is the floor's plus the
    /// contact `thickness`.
    pub ground: Option<Ground>,
    /// Sphere collider the particles touch, if any: its radius is the solid's plus
    /// the contact `thickness`.
    pub sphere: Option<Sphere>,
    /// Coulomb friction coefficient μ of the sphere and between the cloth's own
    /// layers (self-collision); the ground has its own, [`Ground::friction`]
    /// (scenes give both the same unless they set `ground_friction`).
    pub friction: f64,
    /// Contact thickness in m: the cloth rests this far above the floor and outside
    /// the solid sphere (already added to `ground` and `sphere`, which are where the
    /// particles touch; the renderer draws the solids themselves).
    pub thickness: f64,
    /// Whether the particles keep `thickness` apart from each other (those joined
    /// by a spring excepted): `super::self_collision`.
    pub self_collision: bool,
    /// Integration method.
    pub integrator: Integrator,
    /// Time step in s.
    pub dt: f64,
    /// Rigid-bar relaxation passes per step (seed 001).
    pub bar_iterations: u32,
    /// Maximum stretch `tau` (Provot 1995): no spring longer than `(1 + tau) L`.
    pub stretch_limit: Option<f64>,
    /// Strain `tau` past which a spring tears (`super::tearing`): it breaks when
    /// longer than `(1 + tau) L` at the end of a step. `None`: springs never tear.
    pub tear_strain: Option<f64>,
    /// Speed limit in m/s (seed 000's `vLim`): after each step a particle faster
    /// than this is slowed to it (`super::laws::speed_limit`). `None`: no limit.
    pub max_speed: Option<f64>,
    /// Seed of the gusts.
    pub seed: u64,
}

impl Params {
    /// Whether self-collision acts: switched on, with a thickness to keep.
    pub fn self_collides(&self) -> bool {
        self.self_collision && self.thickness > 0.0
    }

    /// `ρ C_d / 2` (kg/m³), the aerodynamic drag's factor (`super::forces::triangle_drag`).
    pub fn half_rho_cd(&self) -> f64 {
        0.5 * self.air_density * self.drag_coefficient
    }
}

impl Default for Params {
    fn default() -> Self {
        Self {
            gravity: DVec3::new(0.0, -9.81, 0.0),
            force: DVec3::ZERO,
            wind: DVec3::ZERO,
            gust: 0.0,
            air_density: 1.2,
            drag_coefficient: 1.0,
            air_damping: 0.0,
            ground: None,
            sphere: None,
            friction: 0.0,
            thickness: 0.0,
            self_collision: false,
            integrator: Integrator::default(),
            dt: 1.0 / 960.0,
            bar_iterations: 0,
            stretch_limit: None,
            tear_strain: None,
            max_speed: None,
            seed: 0,
        }
    }
}

/// What connects the particles: springs, bars and the surface.
#[derive(Clone, Debug, Default)]
pub struct Topology {
    /// Damped springs (any order; [`super::System::new`] makes them canonical).
    pub springs: Vec<Spring>,
    /// Each kind's stiffness and damping, indexed by [`SpringKind::index`]
    /// (zero unless set: springs of such a kind pull with no force).
    pub materials: SpringMaterials,
    /// Rigid bars.
    pub bars: Vec<Bar>,
    /// Surface triangles.
    pub triangles: Vec<[u32; 3]>,
    /// Texture coordinates per particle (empty without a surface).
    pub uvs: Vec<DVec2>,
    /// The grid's shape when the particles form a regular grid cloth
    /// (`p = row * width + column`), which the grid fast path needs.
    pub grid: Option<GridShape>,
    /// The lattice's shape when the particles form a lattice block
    /// (`p = (z height + y) width + x`), which the lattice fast path needs.
    pub lattice: Option<LatticeShape>,
}

/// Topology and parameters: what stays fixed while the state advances.
#[derive(Clone, Debug)]
pub struct Model {
    /// Particle masses in kg (kept for pinned particles too, so they can be unpinned).
    pub mass: Vec<f64>,
    /// Inverse masses; 0 for pinned or grabbed particles.
    pub inv_mass: Vec<f64>,
    /// Which particles the scene or the user pinned.
    pub pinned: Vec<bool>,
    /// Damped springs, canonical (see `super::springs::canonicalize`).
    pub springs: Vec<Spring>,
    /// Each spring kind's stiffness and damping.
    pub materials: SpringMaterials,
    /// [`Self::adjacency`], once asked for.
    pub(crate) adjacency: OnceLock<Adjacency>,
    /// [`Self::constraint_order`], once asked for.
    pub(crate) constraint_order: OnceLock<Vec<u32>>,
    /// Springs broken (torn or cut, `super::tearing`) since the model was built.
    pub broken_springs: usize,
    /// Rigid bars, relaxed after each step.
    pub bars: Vec<Bar>,
    /// The pairs of particles the bars join.
    pub bar_pairs: BarPairs,
    /// Surface triangles (empty for scenes without a surface).
    pub triangles: Vec<[u32; 3]>,
    /// Texture coordinates per particle (empty without a surface).
    pub uvs: Vec<DVec2>,
    /// Grid shape, for grid cloths.
    pub grid: Option<GridShape>,
    /// Lattice shape, for lattice blocks.
    pub lattice: Option<LatticeShape>,
    /// Parameters.
    pub params: Params,
    /// Force terms that run.
    pub terms: ForceTerms,
    /// The wind as a function of time.
    pub wind: Wind,
    /// Boxes, capsules, meshes and moving spheres the particles cannot enter,
    /// besides `params.ground` and `params.sphere` (`super::colliders`).
    pub colliders: Vec<Collider>,
}

impl Model {
    /// For each particle, the springs touching it. Built on first use: the grid
    /// and lattice kernels never ask, and on a big cloth it is 8 bytes a spring.
    pub fn adjacency(&self) -> &Adjacency {
        (self.adjacency).get_or_init(|| Adjacency::new(self.mass.len(), &self.springs))
    }

    /// The order the Gauss-Seidel passes over the springs (XPBD, stretch limit)
    /// visit them in (`super::springs::constraint_order`): indices into
    /// `springs`. Built on first use, by the engines that have such a pass.
    pub fn constraint_order(&self) -> &[u32] {
        (self.constraint_order).get_or_init(|| {
            super::springs::constraint_order(&self.springs, self.grid, self.lattice)
        })
    }

    /// Forgets what follows from the spring list, after springs left or came back.
    pub(crate) fn springs_replaced(&mut self) {
        self.adjacency = OnceLock::new();
        self.constraint_order = OnceLock::new();
        self.refresh_terms();
    }

    /// Whether a spring or a bar joins particles `i` and `j`: self-collision leaves
    /// such pairs alone (pushing them apart would fight the link).
    pub fn joins(&self, i: usize, j: usize) -> bool {
        self.adjacency().joins(&self.springs, i, j) || self.bar_pairs.join(i, j)
    }

    /// Recomputes which force terms run, from the parameters and topology.
    pub fn refresh_terms(&mut self) {
        let p = &self.params;
        self.terms = ForceTerms {
            gravity: p.gravity != DVec3::ZERO,
            // XPBD treats springs as constraints, not forces.
            springs: !self.springs.is_empty() && p.integrator != Integrator::Xpbd,
            aero: !self.triangles.is_empty() && p.air_density > 0.0 && p.drag_coefficient > 0.0,
            air_damping: p.air_damping > 0.0,
            ground: p.ground.is_some(),
            applied: p.force != DVec3::ZERO,
        };
    }

    pub(super) fn refresh_inv_mass(&mut self, grabbed: Option<usize>) {
        for (i, w) in self.inv_mass.iter_mut().enumerate() {
            let m = self.mass[i];
            *w = if self.pinned[i] || grabbed == Some(i) || m <= 0.0 {
                0.0
            } else {
                1.0 / m
            };
        }
    }

    /// Energy of positions `x` and velocities `v`; gravity relative to y = 0, with
    /// the applied force's potential `-F·x` counted in it. With
    /// XPBD the springs hold the energy of the stiffness it simulates at its step.
    ///
    /// Summed in two fixed halves of the particles and of the springs, added at
    /// the end: on two threads where the model's forces are threaded, and the
    /// same total on one thread or two. The app reads the energy every frame and
    /// the energy budget at every edit; on a 256 x 256 cloth one thread took 1.4
    /// ms over its 390,000 springs.
    pub fn energy(&self, x: &[DVec3], v: &[DVec3]) -> Energy {
        let [first, second] = forces::in_halves(self, |h| {
            let mut e = Energy::default();
            for i in forces::half(x.len(), h) {
                if self.inv_mass[i] == 0.0 {
                    continue;
                }
                let m = self.mass[i];
                e.kinetic += 0.5 * m * v[i].length_squared();
                e.gravity -= m * self.params.gravity.dot(x[i]) + self.params.force.dot(x[i]);
                if let Some(g) = self.params.ground {
                    let depth = g.height - x[i].y;
                    if depth > 0.0 {
                        e.elastic += 0.5 * g.stiffness * depth * depth;
                    }
                }
            }
            let strain = |s: &Spring| self.spring_energy(s, x);
            // Four running sums, so that a spring's addition need not wait for
            // the one before it.
            let springs = &self.springs[forces::half(self.springs.len(), h)];
            let mut sums = [0.0; 4];
            let quads = springs.chunks_exact(4);
            let rest = quads.remainder();
            for quad in quads {
                for (sum, s) in sums.iter_mut().zip(quad) {
                    *sum += strain(s);
                }
            }
            for (sum, s) in sums.iter_mut().zip(rest) {
                *sum += strain(s);
            }
            e.elastic += (sums[0] + sums[1]) + (sums[2] + sums[3]);
            e
        });
        Energy {
            kinetic: first.kinetic + second.kinetic,
            gravity: first.gravity + second.gravity,
            elastic: first.elastic + second.elastic,
        }
    }

    /// Elastic energy (J) of spring `s` at positions `x`: `1/2 k (l - L)²`, with
    /// the stiffness it acts with ([`Self::stiffness_in_effect`]).
    pub fn spring_energy(&self, s: &Spring, x: &[DVec3]) -> f64 {
        let stretch = (x[s.a as usize] - x[s.b as usize]).length() - s.rest;
        0.5 * self.stiffness_in_effect(s) * stretch * stretch
    }

    /// Elastic energy (J) of the springs at particle `i`, at positions `x`: all of
    /// the energy that moving `i` alone changes, when `i` is held (a held
    /// particle's own kinetic and gravity terms are not counted: [`Self::energy`]).
    pub fn energy_of_springs_at(&self, i: usize, x: &[DVec3]) -> f64 {
        (self.adjacency().springs_of(i))
            .map(|(s, _)| self.spring_energy(&self.springs[s], x))
            .sum()
    }

    /// The stiffness and damping of the springs of `kind`.
    pub fn material(&self, kind: SpringKind) -> SpringMaterial {
        self.materials[kind.index()]
    }

    /// The stiffness (N/m) spring `s` acts with: its kind's, except under XPBD, which
    /// at step `h` moves the ends as a spring of stiffness `k / (1 + k h² w)` would
    /// (one iteration from `λ = 0`, `w` the ends' inverse masses): that is the
    /// material XPBD simulates, and whose energy it holds.
    pub fn stiffness_in_effect(&self, s: &Spring) -> f64 {
        let k = self.material(s.kind).stiffness;
        if self.params.integrator != Integrator::Xpbd {
            return k;
        }
        let w = self.inv_mass[s.a as usize] + self.inv_mass[s.b as usize];
        k / (1.0 + k * self.params.dt * self.params.dt * w)
    }
}
