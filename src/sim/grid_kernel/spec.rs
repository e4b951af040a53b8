//! What defines a grid cloth ([`GridSpec`]) and the rule that picks the float
//! types it is stepped in ([`Precision`]): the float32 noise of its springs,
//! `sum count k r / m`, against 1% of gravity.

use super::frame::{self, FrameRule};
use crate::sim::{Ground, Integrator, Sphere};

/// Stiffness and damping of one kind of spring.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SpringCoefficients {
    /// Stiffness `k` in N/m.
    pub k: f64,
    /// Damping `b` along the spring in N·s/m.
    pub b: f64,
}

/// Everything that defines a grid cloth for [`GridCloth::new`](super::GridCloth::new).
///
/// The cloth starts flat in the x-y plane: particle `(r, c)` at
/// `origin + (c h, -r h, 0)` with `h = spacing`, at rest.
#[derive(Clone, Debug, PartialEq)]
pub struct GridSpec {
    /// Particles per row (columns), at least 1.
    pub width: usize,
    /// Particles per column (rows), at least 1.
    pub height: usize,
    /// Distance between neighbouring particles `h` in m (rest length of structural
    /// springs; shear springs rest at `h√2`, bend springs at `2h`).
    pub spacing: f64,
    /// Mass of every particle in kg.
    pub particle_mass: f64,
    /// Position of particle `(0, 0)` in m.
    pub origin: [f64; 3],
    /// Structural springs `(r, c)-(r, c+1)` and `(r, c)-(r+1, c)`.
    pub structural: SpringCoefficients,
    /// Shear springs `(r, c)-(r+1, c±1)`.
    pub shear: SpringCoefficients,
    /// Bend springs `(r, c)-(r, c+2)` and `(r, c)-(r+2, c)`.
    pub bend: SpringCoefficients,
    /// Gravity in m/s² (default `(0, -9.81, 0)`).
    pub gravity: [f64; 3],
    /// Air velocity in m/s for the drag.
    pub wind: [f64; 3],
    /// Air density ρ in kg/m³; 0 turns the drag off.
    pub air_density: f64,
    /// Drag coefficient `C_d`; 0 turns the drag off.
    pub drag_coefficient: f64,
    /// Indices `r * width + c` of the pinned particles.
    pub pinned: Vec<usize>,
    /// Viscous air damping `c` in `-c v`, N·s/m (0: none).
    pub air_damping: f64,
    /// Ground plane with penalty contact, if any.
    pub ground: Option<Ground>,
    /// Sphere collider, if any: particles inside are projected onto its surface.
    pub sphere: Option<Sphere>,
    /// Coulomb friction coefficient μ of the sphere (the ground's is its own, see
    /// `laws::Contact::resolve`); with friction on either the sphere is
    /// resolved after the step rather than inside it.
    pub friction: f64,
    /// Self-collision's thickness `h_c` in m, if the particles keep it apart
    /// (`crate::sim::self_collision`).
    pub self_collision: Option<f64>,
    /// Provot's stretch limit `tau`, if any: no spring longer than `(1 + tau) L`.
    pub stretch_limit: Option<f64>,
    /// Tear strain `tau`, if springs tear (`crate::sim::tearing`): a spring longer
    /// than `(1 + tau) L` at the end of a step breaks.
    pub tear_strain: Option<f64>,
    /// Speed limit in m/s, if any (`laws::speed_limit`).
    pub max_speed: Option<f64>,
    /// Symplectic Euler, explicit Euler or position Verlet (see
    /// [`GridCloth::supports`](super::GridCloth::supports)).
    pub integrator: Integrator,
    /// Which kinds of spring exist (structural, shear, bend); an absent kind has
    /// `k = b = 0` and no stretch limit.
    pub present: [bool; 3],
    /// The float type of the arithmetic (see [`Precision::needed`]).
    pub precision: Precision,
}

/// The float types a [`GridCloth`](super::GridCloth) keeps and computes in.
///
/// Float32 positions lose the low bits of each move `x += h v`, and float32 spring
/// lengths resolve the stretch only to about `2^-23 L`; times `k / m`, either is an
/// acceleration noise that heats a stiff cloth (0.15 J in 200 steps of a k = 1e7 N/m
/// cloth that the f64 engine keeps at 2e-6 J). [`Precision::needed`] takes the
/// cheapest level whose noise stays under [`Precision::NOISE_LIMIT`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Precision {
    /// Float32 positions and arithmetic: noise `~ k 2^-23 |x| / m`, with `|x|` the
    /// largest coordinate.
    #[default]
    Single,
    /// Float32 arithmetic on fixed-point positions ([`frame`]: 32-bit integers in a
    /// frame that follows the cloth, a spring's `d` exact before its conversion,
    /// `x += h v` rounded to the unit): noise `~ k (2^-23 L + unit / 2) / m`.
    Mixed,
    /// Float64 positions and arithmetic (the same code at half the lanes).
    Double,
}

impl Precision {
    /// Largest acceleration noise (m/s²) float32 may add to a particle: 1% of
    /// standard gravity.
    pub const NOISE_LIMIT: f64 = 0.0981;

    /// The precision a grid cloth needs whose coordinates stay within `reach` (m)
    /// of the origin, stepped at `dt` s: `Single` when float32 positions keep the
    /// noise under the limit, else `Mixed` when float32 spring lengths do, else
    /// `Double`.
    pub fn needed(spec: &GridSpec, reach: f64, dt: f64) -> Self {
        Self::cheapest(|r| Self::float32_noise(spec, r, dt), reach)
    }

    /// The cheapest level whose float32 noise (`noise(Some(reach))` with float32
    /// positions, `noise(None)` with fixed-point ones) stays under the limit.
    pub fn cheapest(noise: impl Fn(Option<f64>) -> f64, reach: f64) -> Self {
        if noise(Some(reach)) <= Self::NOISE_LIMIT {
            Self::Single
        } else if noise(None) <= Self::NOISE_LIMIT {
            Self::Mixed
        } else {
            Self::Double
        }
    }

    /// The acceleration noise (m/s²) of float32 on `spec`'s cloth stepped at `dt`
    /// s, `sum_kinds 4 k r / m` (a particle has up to 4 springs of each kind),
    /// with `r` the float32 rounding of the position's size `reach`, `2^-23 reach`,
    /// for float32 positions, or for fixed-point positions (`None`) that of each
    /// kind's rest length plus the rounding of a move to half its unit; for XPBD
    /// see [`Precision::spring_noise`].
    pub fn float32_noise(spec: &GridSpec, reach: Option<f64>, dt: f64) -> f64 {
        spec.spring_noise(reach.ok_or_else(|| spec.fixed_unit()), dt)
    }

    /// `sum count k r / m` over a particle's springs, given as `(k, count, rest
    /// length)` of each kind, with `r` the rounding of a length: `2^-23 reach` for
    /// float32 positions (`Ok(reach)`), `2^-23 rest + unit / 2` for fixed-point
    /// ones (`Err(unit)`, see [`frame`]).
    ///
    /// With XPBD at steps of `h` s (`xpbd`), a spring's round-off moves its ends
    /// as a spring of stiffness `k / (1 + 2 k h² / m)` would (XPBD's compliance,
    /// two ends of mass `m`): `k` while `k h² / m` is small, `m / 2h²` for a stiff
    /// one, whose correction takes out the whole round-off in one step. So XPBD's
    /// precision follows its step as well as `k`. (The jelly 8 m up, at h = 1.4 ms
    /// and k = 1e5 N/m: kinetic energy 2.7% from the f64 engine's after 1.4 s on
    /// float32 positions, 2.3% on double-float ones (before fixed point) with
    /// float32 arithmetic, the same to 5 digits in float64, which this picks.)
    pub fn spring_noise(
        springs: impl Iterator<Item = (f64, f64, f64)>,
        mass: f64,
        positions: Result<f64, f64>,
        xpbd: Option<f64>,
    ) -> f64 {
        if mass <= 0.0 {
            return f64::INFINITY;
        }
        let ulp = f32::EPSILON as f64;
        let stiffness = |k: f64| match xpbd {
            Some(h) => k / (1.0 + 2.0 * k * h * h / mass),
            None => k,
        };
        let rounding = |rest: f64| match positions {
            Ok(reach) => ulp * reach.abs(),
            Err(unit) => ulp * rest.abs() + 0.5 * unit,
        };
        let noise: f64 = springs
            .map(|(k, count, rest)| count * stiffness(k.abs()) * rounding(rest))
            .sum();
        noise / mass
    }
}

/// What the precision rule reads of a kernel's spec, a grid's or a lattice's: one
/// rule for both (`System`'s choice of precision, and of when a body has outgrown
/// its fixed-point unit, in [`crate::sim::fast_path`]).
pub(crate) trait SpringNoise {
    /// The float32 noise (m/s²) of its springs at steps of `dt` s, on positions
    /// rounded as [`Precision::spring_noise`] says (`Ok(reach)`: float32 ones
    /// within `reach` m; `Err(unit)`: fixed-point ones of `unit` m), XPBD's
    /// weighed at its step.
    fn spring_noise(&self, positions: Result<f64, f64>, dt: f64) -> f64;
    /// The unit (m) of its positions in fixed point.
    fn fixed_unit(&self) -> f64;
    /// The colliders its positions' frame holds beside the body.
    fn colliders(&self) -> (Option<Ground>, Option<Sphere>);
}

/// The step that XPBD's noise follows under `integrator` (`None` for the other
/// integrators: [`Precision::spring_noise`]).
pub(super) fn xpbd_step(integrator: Integrator, dt: f64) -> Option<f64> {
    (integrator == Integrator::Xpbd).then_some(dt)
}

impl SpringNoise for GridSpec {
    fn spring_noise(&self, positions: Result<f64, f64>, dt: f64) -> f64 {
        self.noise(positions, xpbd_step(self.integrator, dt))
    }
    fn fixed_unit(&self) -> f64 {
        GridSpec::fixed_unit(self)
    }
    fn colliders(&self) -> (Option<Ground>, Option<Sphere>) {
        (self.ground, self.sphere)
    }
}

impl GridSpec {
    /// The peers' benchmark scene (`shared/peers/scene.py`, "stable" variant): an
    /// `n x n` cloth 1 m square hanging from its two top corners, particle mass
    /// `m = 1/n²` kg, `k = 5000 m` N/m and `b = 0.5 m` N·s/m for every spring, and,
    /// with `wind`, drag with ρ = 1.2 kg/m³, `C_d` = 1 and a wind of (0, 0, 5) m/s.
    pub fn peer_bench(n: usize, wind: bool) -> Self {
        let n = n.max(2);
        let m = 1.0 / (n * n) as f64;
        let kind = SpringCoefficients {
            k: 5000.0 * m,
            b: 0.5 * m,
        };
        GridSpec {
            width: n,
            height: n,
            spacing: 1.0 / (n - 1) as f64,
            particle_mass: m,
            origin: [0.0, 1.0, 0.0],
            structural: kind,
            shear: kind,
            bend: kind,
            gravity: [0.0, -9.81, 0.0],
            wind: if wind { [0.0, 0.0, 5.0] } else { [0.0; 3] },
            air_density: if wind { 1.2 } else { 0.0 },
            drag_coefficient: 1.0,
            pinned: vec![0, n - 1],
            air_damping: 0.0,
            ground: None,
            sphere: None,
            friction: 0.0,
            self_collision: None,
            stretch_limit: None,
            tear_strain: None,
            max_speed: None,
            integrator: Integrator::SymplecticEuler,
            present: [true; 3],
            precision: Precision::Single,
        }
    }

    /// Radius (m) of the cloth laid flat: half its diagonal.
    pub fn extent(&self) -> f64 {
        let (w, h) = (self.width.max(1) - 1, self.height.max(1) - 1);
        0.5 * self.spacing.abs() * ((w * w + h * h) as f64).sqrt()
    }

    /// [`Precision::spring_noise`] of its springs (a particle has up to 4 of each
    /// kind) with `positions` rounded as there, and XPBD's steps.
    pub(super) fn noise(&self, positions: Result<f64, f64>, xpbd: Option<f64>) -> f64 {
        let h = self.spacing.abs();
        let rests = [h, std::f64::consts::SQRT_2 * h, 2.0 * h];
        let kinds = [self.structural, self.shear, self.bend];
        let springs = (kinds.iter().zip(rests)).map(|(kind, rest)| (kind.k, 4.0, rest));
        Precision::spring_noise(springs, self.particle_mass, positions, xpbd)
    }

    /// The unit (m) of its positions in fixed point: [`frame::fixed_unit`] of its
    /// radius and its springs' noise. The noise is weighed without XPBD's step,
    /// which the unit does not follow: at any step XPBD's noise is at most that
    /// (its compliance only softens a spring, [`Precision::spring_noise`]), so the
    /// unit holds it at every step the sliders reach.
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

    /// Number of springs of the 12-neighbour stencil on this grid.
    pub fn spring_count(&self) -> usize {
        let (w, h) = (self.width, self.height);
        stencil_counts(w, h).iter().sum()
    }
}

/// Springs of each kind (structural, shear, bend) of the 12-neighbour stencil on a
/// `w x h` grid.
pub fn stencil_counts(w: usize, h: usize) -> [usize; 3] {
    [
        w.saturating_sub(1) * h + w * h.saturating_sub(1),
        2 * w.saturating_sub(1) * h.saturating_sub(1),
        w.saturating_sub(2) * h + w * h.saturating_sub(2),
    ]
}
