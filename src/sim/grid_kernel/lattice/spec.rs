//! A lattice's extents ([`LatticeShape`]: its particles, and the kind and colour
//! class of the spring between two of them) and everything that defines the body
//! ([`LatticeSpec`]).

use crate::sim::grid_kernel::{
    FrameRule, Precision, SpringCoefficients, SpringNoise, frame, xpbd_step,
};
use crate::sim::{Ground, Integrator, Sphere};

/// A lattice's extents: particle `(x, y, z)` is `(z height + y) width + x` in the
/// model.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LatticeShape {
    /// Particles along x.
    pub width: usize,
    /// Particles along y.
    pub height: usize,
    /// Particles along z.
    pub depth: usize,
}

impl LatticeShape {
    /// Number of particles.
    pub fn len(&self) -> usize {
        self.width * self.height * self.depth
    }

    /// True if it has no particles.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Springs of each kind (axis, face diagonal, body diagonal) that a full
    /// lattice of this shape has.
    pub fn spring_counts(&self) -> [usize; 3] {
        let mut counts = [0; 3];
        for (dx, dy, dz) in FORWARD {
            let along = |n: usize, d: isize| n.saturating_sub(d.unsigned_abs());
            let steps = dx.unsigned_abs() + dy.unsigned_abs() + dz.unsigned_abs();
            counts[steps - 1] +=
                along(self.width, dx) * along(self.height, dy) * along(self.depth, dz);
        }
        counts
    }

    /// The kind (0 axis, 1 face diagonal, 2 body diagonal) of a spring from
    /// particle `a` to particle `b`, or `None` when `b` is not a forward neighbour
    /// of `a` within one cell.
    pub fn kind_of(&self, a: usize, b: usize) -> Option<usize> {
        self.direction(a, b).map(|d| {
            let (dx, dy, dz) = FORWARD[d];
            dx.unsigned_abs() + dy.unsigned_abs() + dz.unsigned_abs() - 1
        })
    }

    /// The colour class of a spring from particle `a` to particle `b` in the
    /// constraint passes (XPBD's springs, the stretch limit): its direction's index
    /// among the 13 forward neighbours, and the parity of its first end's
    /// coordinate along the direction (z where `dz != 0`, else y where `dy != 0`,
    /// else x). Springs of one direction and parity share no particle (each steps
    /// 1 along that coordinate, from an even one or from an odd one), so a class is
    /// corrected in any order with the same result: the lattice kernel's lanes
    /// and the f64 engine's one spring at a time (`crate::sim::springs::constraint_order`).
    /// `None` when `b` is not a forward neighbour of `a`.
    pub fn constraint_class(&self, a: usize, b: usize) -> Option<(usize, usize)> {
        let direction = self.direction(a, b)?;
        let (_, dy, dz) = FORWARD[direction];
        let [x, y, z] = self.coordinates(a);
        let along = if dz != 0 {
            z
        } else if dy != 0 {
            y
        } else {
            x
        };
        Some((direction, along % 2))
    }

    /// Lattice coordinates `[x, y, z]` of model particle `p`.
    pub(super) fn coordinates(&self, p: usize) -> [usize; 3] {
        let (w, h) = (self.width, self.height);
        [p % w, (p / w) % h, p / (w * h)]
    }

    /// The index in [`FORWARD`] of the step from `a` to `b`.
    pub(super) fn direction(&self, a: usize, b: usize) -> Option<usize> {
        let n = self.len();
        if a >= n || b >= n {
            return None;
        }
        let ([xa, ya, za], [xb, yb, zb]) = (self.coordinates(a), self.coordinates(b));
        let step = |from: usize, to: usize| to as isize - from as isize;
        let offset = (step(xa, xb), step(ya, yb), step(za, zb));
        FORWARD.iter().position(|&o| o == offset)
    }
}

/// The 13 forward neighbours `(dx, dy, dz)` of a lattice particle.
pub(super) const FORWARD: [(isize, isize, isize); 13] = [
    (1, 0, 0),
    (-1, 1, 0),
    (0, 1, 0),
    (1, 1, 0),
    (-1, -1, 1),
    (0, -1, 1),
    (1, -1, 1),
    (-1, 0, 1),
    (0, 0, 1),
    (1, 0, 1),
    (-1, 1, 1),
    (0, 1, 1),
    (1, 1, 1),
];

/// Everything that defines a lattice for
/// [`LatticeKernel::new`](super::LatticeKernel::new) (the positions and velocities
/// come from [`LatticeKernel::set_state`](super::LatticeKernel::set_state)).
#[derive(Clone, Debug, PartialEq)]
pub struct LatticeSpec {
    /// The extents.
    pub shape: LatticeShape,
    /// Rest length `h` of the axis springs in m.
    pub spacing: f64,
    /// Mass of every particle in kg.
    pub particle_mass: f64,
    /// Axis springs (rest `h`), face diagonals (`h√2`), body diagonals (`h√3`).
    pub kinds: [SpringCoefficients; 3],
    /// Acceleration of every free particle in m/s²: gravity plus the applied force
    /// over the mass.
    pub gravity: [f64; 3],
    /// Viscous air damping `c` in N·s/m (0: off).
    pub air_damping: f64,
    /// Penalty ground, with its friction.
    pub ground: Option<Ground>,
    /// Sphere collider.
    pub sphere: Option<Sphere>,
    /// Coulomb friction coefficient of the sphere.
    pub friction: f64,
    /// Provot's stretch limit `tau`: after the step no spring longer than `(1 +
    /// tau)` times its rest length (`None`: off).
    pub stretch_limit: Option<f64>,
    /// Symplectic Euler, explicit Euler, position Verlet or XPBD.
    pub integrator: Integrator,
    /// The precision to compute in.
    pub precision: Precision,
}

impl LatticeSpec {
    /// [`Precision::spring_noise`] of its springs with `positions` rounded as
    /// there, and XPBD's steps: a particle has up to 6 axis springs, 12 face
    /// diagonals and 8 body diagonals.
    pub(super) fn noise(&self, positions: Result<f64, f64>, xpbd: Option<f64>) -> f64 {
        let h = self.spacing.abs();
        let springs = [(6.0, h), (12.0, h * 2f64.sqrt()), (8.0, h * 3f64.sqrt())];
        let springs =
            (self.kinds.iter().zip(springs)).map(|(kind, (count, rest))| (kind.k, count, rest));
        Precision::spring_noise(springs, self.particle_mass, positions, xpbd)
    }

    /// Radius (m) of the lattice at rest: half its diagonal.
    pub fn extent(&self) -> f64 {
        let LatticeShape {
            width,
            height,
            depth,
        } = self.shape;
        let cells = [width, height, depth].map(|n| n.max(1) as f64 - 1.0);
        0.5 * self.spacing.abs() * cells.iter().map(|c| c * c).sum::<f64>().sqrt()
    }

    /// The unit (m) of its positions in fixed point, chosen as the grid's is
    /// ([`crate::sim::grid_kernel::GridSpec::fixed_unit`]).
    pub fn fixed_unit(&self) -> f64 {
        frame::fixed_unit(self.extent(), |unit| self.noise(Err(unit), None))
    }

    /// How its positions are stored: fixed point with [`Precision::Mixed`].
    pub(super) fn frame_rule(&self) -> FrameRule<'_> {
        FrameRule {
            fixed: self.precision == Precision::Mixed,
            unit: self.fixed_unit(),
            ground: self.ground.as_ref(),
            sphere: self.sphere.as_ref(),
        }
    }

    /// Whether the kernel models an integrator.
    pub fn supports(integrator: Integrator) -> bool {
        matches!(
            integrator,
            Integrator::SymplecticEuler
                | Integrator::ExplicitEuler
                | Integrator::Verlet
                | Integrator::Xpbd
        )
    }
}

impl SpringNoise for LatticeSpec {
    fn spring_noise(&self, positions: Result<f64, f64>, dt: f64) -> f64 {
        self.noise(positions, xpbd_step(self.integrator, dt))
    }
    fn fixed_unit(&self) -> f64 {
        LatticeSpec::fixed_unit(self)
    }
    fn colliders(&self) -> (Option<Ground>, Option<Sphere>) {
        (self.ground, self.sphere)
    }
}
