//! The simulation parameters of a scene, checked: the integrator, the forces and
//! the air, the colliders (ground and sphere), the limiters and the step.

use glam::DVec3;

use super::ranges::{
    AIR_DAMPING, DT, FORCE, FRICTION, GRAVITY, GUST, MAX_SPEED, STRETCH_LIMIT, TEAR_STRAIN,
    THICKNESS, WIND, bar_iterations, invalid, ranged, vector,
};
use crate::scene::{SceneError, SceneSpec};
use crate::sim::{Ground, Integrator, Params, Sphere};

/// The parameters of `spec` (a grid of `bars` or not), defaults filled in.
pub(super) fn params(spec: &SceneSpec, o: &str, bars: bool) -> Result<Params, SceneError> {
    let layout = spec.layout;
    let integrator = integrator(spec, o)?;
    let thickness = THICKNESS.check(o, spec.thickness.unwrap_or(0.0))?;
    let ground = ground(spec, o, thickness)?;
    refuse_off_parts(spec, o)?;
    let sphere = sphere(spec, o, thickness)?;
    let stretch_limit = match spec.stretch_limit {
        None => None,
        Some(t) => Some(STRETCH_LIMIT.check(o, t)?),
    };
    Ok(Params {
        gravity: GRAVITY.check(o, spec.gravity.map_or(DVec3::new(0.0, -9.81, 0.0), |v| v.0))?,
        force: FORCE.check(o, spec.force.map_or(DVec3::ZERO, |v| v.0))?,
        wind: WIND.check(o, spec.wind.map_or(DVec3::ZERO, |v| v.0))?,
        gust: GUST.check(o, spec.gust.unwrap_or(0.0))?,
        air_density: ranged(
            o,
            "air_density",
            spec.air_density.unwrap_or(1.2),
            0.0,
            false,
            1e4,
        )?,
        drag_coefficient: ranged(
            o,
            "drag_coefficient",
            spec.drag_coefficient.unwrap_or(1.0),
            0.0,
            false,
            1e3,
        )?,
        air_damping: AIR_DAMPING.check(o, spec.air_damping.unwrap_or(0.0))?,
        ground,
        sphere,
        friction: FRICTION.check(o, spec.friction.unwrap_or(0.0))?,
        thickness,
        self_collision: spec.self_collision.unwrap_or(false),
        integrator,
        dt: DT.check(o, spec.dt.unwrap_or(1.0 / 960.0))?,
        bar_iterations: match spec.bar_iterations {
            Some(n) => bar_iterations(o, layout, bars, n)?,
            None => 0,
        },
        stretch_limit,
        tear_strain: (spec.tear_strain)
            .map(|t| TEAR_STRAIN.check(o, t))
            .transpose()?,
        max_speed: (spec.max_speed)
            .map(|v| MAX_SPEED.check(o, v))
            .transpose()?,
        seed: spec.seed.unwrap_or(1),
    })
}

/// The integrator `spec` names, or the default.
fn integrator(spec: &SceneSpec, o: &str) -> Result<Integrator, SceneError> {
    Ok(match &spec.integrator {
        None => Integrator::default(),
        Some(name) => Integrator::from_name(name).ok_or_else(|| {
            let names: Vec<_> = Integrator::ALL.iter().map(|i| i.name()).collect();
            invalid(
                o,
                "integrator",
                format!(
                    "`{}` is not an integrator: expected one of {}",
                    crate::limits::echo(name),
                    names.join(", ")
                ),
            )
        })?,
    })
}

/// The ground of `spec`, its contact surface `thickness` above its height.
fn ground(spec: &SceneSpec, o: &str, thickness: f64) -> Result<Option<Ground>, SceneError> {
    Ok(match spec.ground_height {
        None => None,
        Some(h) => Some(Ground {
            height: ranged(o, "ground_height", h, -1e6, false, 1e6)? + thickness,
            stiffness: ranged(
                o,
                "ground_stiffness",
                spec.ground_stiffness.unwrap_or(1e4),
                0.0,
                false,
                1e12,
            )?,
            friction: match spec.ground_friction {
                Some(mu) => ranged(o, "ground_friction", mu, 0.0, false, FRICTION.hi)?,
                None => FRICTION.check(o, spec.friction.unwrap_or(0.0))?,
            },
            damping: ranged(
                o,
                "ground_damping",
                spec.ground_damping.unwrap_or(0.0),
                0.0,
                false,
                1e9,
            )?,
        }),
    })
}

/// The keys of a part that is off would be ignored: refused instead, saying how
/// to turn the part on.
fn refuse_off_parts(spec: &SceneSpec, o: &str) -> Result<(), SceneError> {
    let off_parts = [
        (
            spec.ground_height.is_none(),
            "ground_height",
            [
                ("ground_stiffness", spec.ground_stiffness.is_some()),
                ("ground_friction", spec.ground_friction.is_some()),
                ("ground_damping", spec.ground_damping.is_some()),
            ],
        ),
        (
            spec.sphere_center.is_none(),
            "sphere_center",
            [
                ("sphere_radius", spec.sphere_radius.is_some()),
                ("", false),
                ("", false),
            ],
        ),
    ];
    for (off, switch, keys) in off_parts {
        if let Some((key, _)) = keys.iter().find(|(_, given)| off && *given) {
            return Err(invalid(
                o,
                key,
                format!(
                    "applies to a part the scene does not have: set `{switch}` to add it, or \
                     leave `{key}` out"
                ),
            ));
        }
    }
    Ok(())
}

/// The sphere of `spec`, its contact surface `thickness` outside its radius.
fn sphere(spec: &SceneSpec, o: &str, thickness: f64) -> Result<Option<Sphere>, SceneError> {
    Ok(match spec.sphere_center {
        None => None,
        Some(c) => Some(Sphere {
            center: vector(o, "sphere_center", c.0, 1e6)?,
            radius: ranged(
                o,
                "sphere_radius",
                spec.sphere_radius.unwrap_or(0.5),
                0.0,
                true,
                1e6,
            )? + thickness,
        }),
    })
}
