//! A model's parameters as the GPU engine's step reads them.

use glam::DVec3;

use crate::sim::{Ground, Integrator, Model, Sphere, Wind};

/// What the GPU engine needs of a model's parameters, reduced to the terms that
/// run (gravity zero when off, air damping 0 when off).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct StepParams {
    /// Gravitational acceleration in m/s² (zero when the term is off).
    pub(crate) gravity: DVec3,
    /// The applied force on every particle in N (zero when the term is off).
    pub(crate) force: DVec3,
    /// Viscous air damping `c` in N·s/m (0: off).
    pub(crate) air_damping: f64,
    /// Ground plane, if any.
    pub(crate) ground: Option<Ground>,
    /// Sphere collider, if any.
    pub(crate) sphere: Option<Sphere>,
    /// Symplectic Euler, explicit Euler, position Verlet or XPBD (symplectic Euler
    /// without the springs' forces, then their constraint pass).
    pub(crate) integrator: Integrator,
    /// Time step in s.
    pub(crate) dt: f64,
    /// Bar relaxation passes per step.
    pub(crate) bar_iterations: u32,
    /// Maximum stretch `tau` of springs, if any.
    pub(crate) stretch_limit: Option<f64>,
    /// Coulomb friction coefficient of the ground and the sphere (and of the
    /// cloth on itself).
    pub(crate) friction: f64,
    /// Self-collision's thickness `h_c` in m, if the particles keep it apart
    /// (`sim::self_collision`).
    pub(crate) self_collision: Option<f64>,
    /// Speed limit in m/s, if any (`sim::laws::speed_limit`).
    pub(crate) max_speed: Option<f64>,
    /// Whether the springs are forces; under XPBD they are constraints instead,
    /// one Gauss-Seidel pass of `xpbd_pass` after the prediction.
    pub(crate) spring_forces: bool,
    /// Per-triangle aerodynamic drag, if on.
    pub(crate) drag: Option<Drag>,
    /// Tear strain `tau`, if springs tear (`sim::tearing`).
    pub(crate) tear_strain: Option<f64>,
}

/// Per-triangle aerodynamic drag ([`triangle_drag`](crate::sim::forces::triangle_drag)).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Drag {
    /// `ρ C_d / 2` in kg/m³.
    pub(crate) half_rho_cd: f64,
    /// The air's velocity over time.
    pub(crate) wind: Wind,
}

impl StepParams {
    /// The parameters of `model`, if its integrator takes one force evaluation a
    /// step: symplectic Euler, explicit Euler, position Verlet or XPBD.
    ///
    /// Every parameter and force term is named here (no `..`): a new one fails to
    /// compile until it is either passed to the engine or made a reason to refuse it.
    pub(crate) fn of(model: &Model) -> Option<Self> {
        let crate::sim::Params {
            gravity,
            force,
            wind: _, // in `model.wind`, with the gusts
            gust: _,
            air_density: _,      // in `Params::half_rho_cd`
            drag_coefficient: _, // likewise
            air_damping,
            ground,
            sphere,
            integrator,
            dt,
            bar_iterations,
            stretch_limit,
            tear_strain,
            max_speed,
            friction,
            thickness,
            self_collision: _, // with `thickness`, in `Params::self_collides`
            seed: _,           // only the gusts use it, in `model.wind`
        } = model.params;
        let crate::sim::ForceTerms {
            gravity: gravity_on,
            springs: spring_forces,
            aero,
            air_damping: air_damping_on,
            ground: _, // `ground` itself says
            applied,
        } = model.terms;
        if matches!(
            integrator,
            Integrator::Rk2 | Integrator::Rk4 | Integrator::ImplicitEuler
        ) {
            return None;
        }
        Some(Self {
            gravity: if gravity_on { gravity } else { DVec3::ZERO },
            force: if applied { force } else { DVec3::ZERO },
            air_damping: if air_damping_on { air_damping } else { 0.0 },
            ground,
            sphere,
            integrator,
            dt,
            bar_iterations,
            stretch_limit,
            friction,
            self_collision: model.params.self_collides().then_some(thickness),
            max_speed,
            spring_forces,
            drag: aero.then_some(Drag {
                half_rho_cd: model.params.half_rho_cd(),
                wind: model.wind,
            }),
            tear_strain,
        })
    }
}
