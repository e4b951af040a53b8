//! A scene's `[[colliders]]`: each checked (the error names `colliders[i].key`
//! and its range) and built into a [`Collider`].

use std::sync::Arc;

use glam::{DQuat, DVec3};

use super::ranges::{FRICTION, THICKNESS, invalid, ranged, vector};
use crate::scene::mesh;
use crate::scene::{ColliderSpec, SceneError};
use crate::sim::{Collider, ColliderMesh, Shape};

/// Largest size and coordinate of a collider, m.
const MAX_SIZE: f64 = 1e6;
/// Fastest a collider may move, m/s, and turn, rad/s.
const MAX_SPEED: f64 = 1e4;

/// The colliders of a scene whose cloth has contact `thickness` and friction μ
/// `friction` (each collider's own unless it gives one).
pub(super) fn colliders(
    specs: &[ColliderSpec],
    o: &str,
    thickness: f64,
    friction: f64,
) -> Result<Vec<Collider>, SceneError> {
    (specs.iter().enumerate())
        .map(|(i, spec)| collider(spec, o, &format!("colliders[{i}]"), thickness, friction))
        .collect()
}

/// One collider; `at` names it in messages (`colliders[2]`).
fn collider(
    spec: &ColliderSpec,
    o: &str,
    at: &str,
    thickness: f64,
    friction: f64,
) -> Result<Collider, SceneError> {
    let key = |k: &str| format!("{at}.{k}");
    let thickness = match spec.thickness {
        Some(t) => ranged(o, &key("thickness"), t, THICKNESS.lo, false, THICKNESS.hi)?,
        None => thickness,
    };
    let friction = match spec.friction {
        Some(f) => ranged(o, &key("friction"), f, FRICTION.lo, false, FRICTION.hi)?,
        None => friction,
    };
    let length = |k: &str, v: Option<f64>, default: f64| {
        ranged(o, &key(k), v.unwrap_or(default), 0.0, true, MAX_SIZE)
    };
    let point = |k: &str, v: Option<crate::scene::values::Vector>| {
        v.map(|v| vector(o, &key(k), v.0, MAX_SIZE)).transpose()
    };
    check_keys(spec, o, at)?;
    let (shape, center) = match spec.shape.as_str() {
        "capsule" => {
            let missing = |k: &str| {
                invalid(
                    o,
                    &key(k),
                    "is missing: a capsule needs both ends, `a` and `b` (m, `\"x,y,z\"`)".into(),
                )
            };
            let a = point("a", spec.a)?.ok_or_else(|| missing("a"))?;
            let b = point("b", spec.b)?.ok_or_else(|| missing("b"))?;
            let center = 0.5 * (a + b);
            let radius = length("radius", spec.radius, 0.1)?;
            let (a, b) = (a - center, b - center);
            (Shape::Capsule { a, b, radius }, center)
        }
        shape => {
            let center = point("center", spec.center)?.unwrap_or(DVec3::ZERO);
            let shape = match shape {
                "sphere" => Shape::Sphere {
                    radius: length("radius", spec.radius, 0.5)?,
                },
                "box" => {
                    let half =
                        point("half_extents", spec.half_extents)?.unwrap_or(DVec3::splat(0.5));
                    if half.min_element() <= 0.0 {
                        return Err(invalid(
                            o,
                            &key("half_extents"),
                            "must be three positive lengths in m, `\"x,y,z\"`".into(),
                        ));
                    }
                    Shape::Box { half_extents: half }
                }
                _ => Shape::Mesh(mesh_shape(spec, o, &key("mesh"), thickness)?),
            };
            (shape, center)
        }
    };
    let degrees = point("rotation", spec.rotation)?.unwrap_or(DVec3::ZERO);
    let motion = |k: &str, v: Option<crate::scene::values::Vector>| {
        v.map_or(Ok(DVec3::ZERO), |v| vector(o, &key(k), v.0, MAX_SPEED))
    };
    Ok(Collider {
        shape,
        center,
        rotation: rotation(degrees),
        velocity: motion("velocity", spec.velocity)?,
        angular_velocity: motion("angular_velocity", spec.angular_velocity)?,
        since: 0.0,
        friction,
        thickness,
    })
}

/// The keys that only some shapes take, and those shapes.
const SHAPE_KEYS: &[(&str, &[&str])] = &[
    ("center", &["sphere", "box", "mesh"]),
    ("radius", &["sphere", "capsule"]),
    ("half_extents", &["box"]),
    ("a", &["capsule"]),
    ("b", &["capsule"]),
    ("mesh", &["mesh"]),
];

/// An unknown shape, or a key its shape does not take, refused by name.
fn check_keys(spec: &ColliderSpec, o: &str, at: &str) -> Result<(), SceneError> {
    let shape = spec.shape.as_str();
    if !["sphere", "box", "capsule", "mesh"].contains(&shape) {
        return Err(invalid(
            o,
            &format!("{at}.shape"),
            format!(
                "= \"{}\" is not a shape: must be one of sphere, box, capsule, mesh",
                crate::limits::echo(shape)
            ),
        ));
    }
    let given = [
        spec.center.is_some(),
        spec.radius.is_some(),
        spec.half_extents.is_some(),
        spec.a.is_some(),
        spec.b.is_some(),
        spec.mesh.is_some(),
    ];
    for (&(key, shapes), given) in SHAPE_KEYS.iter().zip(given) {
        if given && !shapes.contains(&shape) {
            return Err(invalid(
                o,
                &format!("{at}.{key}"),
                format!(
                    "does not apply to a {shape}: only a {} has it",
                    shapes.join(" or ")
                ),
            ));
        }
    }
    Ok(())
}

/// Degrees about z, then x, then y, as a cloth's `rotation` turns it.
fn rotation(degrees: DVec3) -> DQuat {
    let rad = degrees * (std::f64::consts::PI / 180.0);
    DQuat::from_rotation_y(rad.y) * DQuat::from_rotation_x(rad.x) * DQuat::from_rotation_z(rad.z)
}

/// A mesh collider's mesh, read and checked as a cloth's mesh is, with the line
/// of the first fault named.
fn mesh_shape(
    spec: &ColliderSpec,
    o: &str,
    field: &str,
    thickness: f64,
) -> Result<Arc<ColliderMesh>, SceneError> {
    let Some(path) = &spec.mesh else {
        return Err(invalid(
            o,
            field,
            "is missing: a mesh collider needs its OBJ file, `mesh = \"path/to/file.obj\"`".into(),
        ));
    };
    let m = mesh::load(path)
        .map_err(|why| invalid(o, field, format!("file {}{why}", mesh::shown_path(path))))?;
    // Queries reach twice the thickness, so that a particle that went a little
    // deeper in a step is still found.
    let reach = (2.0 * thickness).max(0.01);
    Ok(Arc::new(ColliderMesh::new(
        m.positions.clone(),
        m.triangles.clone(),
        reach,
    )))
}
