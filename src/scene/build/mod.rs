//! From a scene spec to a system: fill in defaults, check every value against its
//! range (the error names the field and the range), then lay out particles, springs,
//! bars, triangles and pins.

mod anchors;
mod colliders;
mod layout;
mod parts;
mod ranges;

use std::borrow::Cow;
use std::sync::Arc;

use glam::DVec3;

use super::edit::EDIT_ORIGIN;
use super::mesh::{self, Mesh};
use super::values::Pins;
use super::{Edit, Layout, Material, Orientation, Scene, SceneError, SceneSpec};
use crate::limits::number as shown;
use crate::sim::{Params, SpringKind};
use anchors::{anchor, default_pins, pin_indices, rotation_matrix};
use parts::params;
pub use ranges::{
    AIR_DAMPING, BAR_ITERATIONS, DAMPING, DT, FORCE, FRICTION, GRAVITY, GRID_MAX_SIDE, GUST,
    MAX_SPEED, PARTICLE_MASS, REST_LENGTH, STIFFNESS, STRETCH_LIMIT, SUBSTEPS, TEAR_STRAIN,
    THICKNESS, WIND, bar_iterations, side_ranges, spring_constants,
};
use ranges::{invalid, one_of, ranged, vector};

/// Every parameter of a scene in effect, checked.
#[derive(Clone, Debug, PartialEq)]
pub struct Resolved {
    /// Layout.
    pub layout: Layout,
    /// Grid orientation.
    pub orientation: Orientation,
    /// Particles across.
    pub width: u32,
    /// Particles down.
    pub height: u32,
    /// Particles deep.
    pub depth: u32,
    /// Spacing in m.
    pub rest_length: f64,
    /// Mass per particle in kg.
    pub particle_mass: f64,
    /// Spring stiffness in N/m.
    pub stiffness: f64,
    /// Spring damping in N·s/m.
    pub damping: f64,
    /// Shear stiffness multiple.
    pub shear_scale: f64,
    /// Bend stiffness multiple.
    pub bend_scale: f64,
    /// Whether a grid is made of rigid bars (seed 001) rather than springs.
    pub bars: bool,
    /// Pinned particles.
    pub pins: Vec<usize>,
    /// Steps per displayed frame.
    pub substeps: u32,
    /// Position of the layout's anchor in m.
    pub origin: DVec3,
    /// Rotation in degrees about z, x, y.
    pub rotation: DVec3,
    /// Initial spring stretch in m.
    pub stretch: f64,
    /// The mesh of a mesh layout, as read and checked from its file.
    pub mesh: Option<Arc<Mesh>>,
    /// Simulation parameters.
    pub params: Params,
    /// The colliders besides the ground and the sphere.
    pub colliders: Vec<crate::sim::Collider>,
}

/// Why `rest_length` (and the panel's rest length) does not apply to a mesh.
pub const NOT_ON_MESH_REST_LENGTH: &str =
    "does not apply to a mesh layout: the mesh's edges give the rest lengths";

/// The mesh of `spec`, read and checked, on a mesh layout; `None` on the others.
/// A key that means nothing for the layout (a grid's `width` on a mesh, `mesh`
/// on a grid) is refused with the reason.
fn layout_mesh(spec: &SceneSpec, o: &str) -> Result<Option<Arc<Mesh>>, SceneError> {
    if spec.layout != Layout::Mesh {
        for (key, given) in [
            ("mesh", spec.mesh.is_some()),
            ("pin_above", spec.pin_above.is_some()),
        ] {
            if given {
                return Err(invalid(
                    o,
                    key,
                    format!(
                        "does not apply to a {} layout: only a mesh layout (`layout = \"mesh\"`) has it",
                        spec.layout.name()
                    ),
                ));
            }
        }
        return Ok(None);
    }
    let vertices = "does not apply to a mesh layout: the mesh's vertices are its particles";
    let not_here = [
        ("width", spec.width.is_some(), vertices),
        ("height", spec.height.is_some(), vertices),
        ("depth", spec.depth.is_some(), vertices),
        (
            "rest_length",
            spec.rest_length.is_some(),
            NOT_ON_MESH_REST_LENGTH,
        ),
        (
            "size",
            spec.size.is_some(),
            "does not apply to a mesh layout: the mesh's coordinates give its size",
        ),
        (
            "orientation",
            spec.orientation.is_some(),
            "does not apply to a mesh layout: turn a mesh with `rotation`",
        ),
        (
            "shear_scale",
            spec.shear_scale.is_some(),
            "does not apply to a mesh layout: a mesh has structural and bend springs, no shear springs",
        ),
        (
            "stretch",
            spec.stretch.is_some(),
            "does not apply to a mesh layout: only the spring layout starts stretched",
        ),
    ];
    // The missing file first: a scene switched to the mesh layout (`--set
    // layout=mesh`) has the keys of its old layout too, but the file is what it
    // needs.
    let given: Vec<&str> = (not_here.iter())
        .filter(|(_, given, _)| *given)
        .map(|(key, _, _)| *key)
        .collect();
    let Some(path) = &spec.mesh else {
        let also = if given.is_empty() {
            String::new()
        } else {
            format!(
                "; the scene's {} then go, as a mesh gives its own shape",
                given.join(", ")
            )
        };
        return Err(invalid(
            o,
            "mesh",
            format!(
                "is missing: a mesh layout needs the OBJ file of its cloth, `mesh = \"path/to/file.obj\"`{also}"
            ),
        ));
    };
    if let Some((key, _, why)) = not_here.iter().find(|(_, given, _)| *given) {
        return Err(invalid(o, key, why.to_string()));
    }
    let mesh = mesh::load(path)
        .map_err(|why| invalid(o, "mesh", format!("file {}{why}", mesh::shown_path(path))))?;
    Ok(Some(mesh))
}

/// `spec` with its material's values filled in ([`SceneSpec::with_material`]),
/// or `spec` itself when it names none. An unknown material, or one on a layout
/// that is not a cloth, is refused with the names allowed.
pub(crate) fn filled<'a>(spec: &'a SceneSpec, o: &str) -> Result<Cow<'a, SceneSpec>, SceneError> {
    let Some(name) = &spec.material else {
        return Ok(Cow::Borrowed(spec));
    };
    let Some(material) = Material::named(name) else {
        return Err(invalid(
            o,
            "material",
            format!(
                "= \"{}\" is not a material: give one of {}",
                crate::limits::echo(name),
                Material::names()
            ),
        ));
    };
    if !matches!(spec.layout, Layout::Grid | Layout::Mesh) {
        return Err(invalid(
            o,
            "material",
            format!(
                "does not apply to a {} layout: only a grid or mesh cloth is made of a material",
                spec.layout.name()
            ),
        ));
    }
    Ok(Cow::Owned(spec.with_material(material)))
}

/// Fills in defaults and checks ranges.
pub fn resolve(spec: &SceneSpec, origin: &str) -> Result<Resolved, SceneError> {
    let o = origin;
    let spec = &*filled(spec, o)?;
    let layout = spec.layout;
    let mesh = layout_mesh(spec, o)?;
    let [width, height, depth] = sides(spec, o, mesh.as_deref())?;
    let particles = (width as usize) * (height as usize) * (depth as usize);
    let rest_length = rest_length(spec, o, width, mesh.as_deref())?;
    let area = cloth_area(layout, [width, height], rest_length, mesh.as_deref());
    let particle_mass = particle_mass(spec, o, particles, area)?;
    let (stiffness, damping) = spring_constants(spec, o, particle_mass)?;
    let bars = bars(spec, o)?;
    let shear_scale = ranged(
        o,
        "shear_scale",
        spec.shear_scale.unwrap_or(1.0),
        0.0,
        false,
        1e3,
    )?;
    let bend_scale = ranged(
        o,
        "bend_scale",
        spec.bend_scale.unwrap_or(1.0),
        0.0,
        false,
        1e3,
    )?;
    let params = params(spec, o, bars)?;
    let colliders = colliders::colliders(&spec.colliders, o, params.thickness, params.friction)?;
    let substeps = SUBSTEPS.check(o, spec.substeps.unwrap_or(16))?;

    let mut pins = pin_indices(
        o,
        spec.pins
            .as_ref()
            .unwrap_or(&Pins::Preset(default_pins(layout))),
        layout,
        [width, height],
        particles,
    )?;
    let origin_at = anchor(spec, o, [width, height], rest_length)?;
    let rotation = vector(
        o,
        "rotation",
        spec.rotation.map_or(DVec3::ZERO, |v| v.0),
        1e6,
    )?;
    if let (Some(height), Some(m)) = (spec.pin_above, &mesh) {
        let height = ranged(o, "pin_above", height, -1e6, false, 1e6)?;
        let turn = rotation_matrix(rotation);
        let above = (m.positions.iter().enumerate())
            .filter(|(_, p)| (origin_at + turn * **p).y >= height)
            .map(|(i, _)| i);
        pins.extend(above);
        pins.sort_unstable();
        pins.dedup();
    }
    Ok(Resolved {
        layout,
        orientation: spec.orientation.unwrap_or_default(),
        width,
        height,
        depth,
        rest_length,
        particle_mass,
        stiffness,
        damping,
        shear_scale,
        bend_scale,
        bars,
        pins,
        substeps,
        origin: origin_at,
        rotation,
        stretch: ranged(o, "stretch", spec.stretch.unwrap_or(1.0), -1e3, false, 1e3)?,
        mesh,
        params,
        colliders,
    })
}

/// The layout's `width`, `height` and `depth`, each given or the layout's default
/// and in its range; a side the layout does not have is refused.
fn sides(spec: &SceneSpec, o: &str, mesh: Option<&Mesh>) -> Result<[u32; 3], SceneError> {
    let layout = spec.layout;
    let mut sides = match (layout, mesh) {
        (Layout::Grid, _) => [32, 32, 1],
        (Layout::Lattice, _) => [7, 4, 4],
        (Layout::Chain | Layout::Rope, _) => [11, 1, 1],
        (Layout::Spring, _) => [2, 1, 1],
        // At most MESH_MAX_VERTICES, a u32.
        (Layout::Mesh, Some(m)) => [m.positions.len() as u32, 1, 1],
        (Layout::Mesh, None) => [0, 1, 1],
    };
    let given = [spec.width, spec.height, spec.depth];
    let names = ["width", "height", "depth"];
    for (((side, range), value), name) in
        (sides.iter_mut().zip(side_ranges(layout)).zip(given)).zip(names)
    {
        match range {
            Some(range) => *side = range.check(o, value.unwrap_or(*side))?,
            // A side the layout does not have is refused, not ignored (the mesh
            // layout says why above).
            None if value.is_some() && layout != Layout::Mesh => {
                let has: Vec<&str> = (side_ranges(layout).iter().flatten())
                    .map(|r| r.field)
                    .collect();
                let has = if has.is_empty() {
                    "its particles are fixed by the layout".to_string()
                } else {
                    format!("it has only {}", has.join(" and "))
                };
                return Err(invalid(
                    o,
                    name,
                    format!("does not apply to a {} layout: {has}", layout.name()),
                ));
            }
            None => {}
        }
    }
    Ok(sides)
}

/// The spacing in m: `rest_length`, or `size` over a layout `width` particles
/// across, or a mesh's mean edge length.
fn rest_length(
    spec: &SceneSpec,
    o: &str,
    width: u32,
    mesh: Option<&Mesh>,
) -> Result<f64, SceneError> {
    Ok(
        match one_of(o, &[("rest_length", spec.rest_length), ("size", spec.size)])? {
            Some((k, v)) if k == "size" => {
                ranged(o, "size", v, 0.0, false, 1e4)? / (width.max(2) - 1) as f64
            }
            Some((_, v)) => REST_LENGTH.check(o, v)?,
            // A mesh's: its mean edge length (shown, not used).
            None => mesh.map_or(0.1, |m| {
                let total: f64 = m
                    .edges
                    .iter()
                    .map(|&[a, b]| m.positions[a as usize].distance(m.positions[b as usize]))
                    .sum();
                total / m.edges.len().max(1) as f64
            }),
        },
    )
}

/// The area in m² of a grid cloth (its cells) or a mesh (its triangles); `None`
/// for the layouts that are not a cloth.
fn cloth_area(layout: Layout, [w, h]: [u32; 2], rest: f64, mesh: Option<&Mesh>) -> Option<f64> {
    match (layout, mesh) {
        (Layout::Grid, _) => Some(f64::from(w - 1) * f64::from(h - 1) * rest * rest),
        (Layout::Mesh, Some(m)) => Some(
            (m.triangles.iter())
                .map(|t| {
                    let [a, b, c] = t.map(|i| m.positions[i as usize]);
                    0.5 * (b - a).cross(c - a).length()
                })
                .sum(),
        ),
        _ => None,
    }
}

/// The mass of each particle in kg: `particle_mass`, or `total_mass` shared by
/// `particles`, or `areal_density` times the cloth's `area` shared by them.
fn particle_mass(
    spec: &SceneSpec,
    o: &str,
    particles: usize,
    area: Option<f64>,
) -> Result<f64, SceneError> {
    Ok(
        match one_of(
            o,
            &[
                ("particle_mass", spec.particle_mass),
                ("total_mass", spec.total_mass),
                ("areal_density", spec.areal_density),
            ],
        )? {
            Some((k, v)) if k == "areal_density" => {
                let density = ranged(o, "areal_density", v, 0.0, true, 1e6)?;
                let Some(area) = area else {
                    return Err(invalid(
                        o,
                        "areal_density",
                        format!(
                            "does not apply to a {} layout: only a grid or mesh cloth has an area; give `particle_mass`",
                            spec.layout.name()
                        ),
                    ));
                };
                per_particle(o, "areal_density", density * area, particles)?
            }
            Some((k, v)) if k == "total_mass" => {
                let total = ranged(o, "total_mass", v, 0.0, true, 1e9)?;
                per_particle(o, "total_mass", total, particles)?
            }
            Some((_, v)) => PARTICLE_MASS.check(o, v)?,
            None => 0.01,
        },
    )
}

/// A mass of `total` kg (from `key`) shared by `particles`, each within the
/// particle mass's range.
fn per_particle(o: &str, key: &str, total: f64, particles: usize) -> Result<f64, SceneError> {
    let each = total / particles as f64;
    PARTICLE_MASS.check(o, each).map_err(|_| {
        invalid(
            o,
            key,
            format!(
                "gives {} kg over {particles} particles, {} kg each, out of range: each particle must have a mass in [{}, {}] kg",
                shown(total),
                shown(each),
                shown(PARTICLE_MASS.lo),
                shown(PARTICLE_MASS.hi)
            ),
        )
    })
}

/// Whether a grid is made of bars; only a grid can be.
fn bars(spec: &SceneSpec, o: &str) -> Result<bool, SceneError> {
    match spec.bars {
        Some(true) if spec.layout != Layout::Grid => Err(invalid(
            o,
            "bars",
            format!(
                "does not apply to a {} layout: only a grid can be made of bars (a rope always is)",
                spec.layout.name()
            ),
        )),
        bars => Ok(bars.unwrap_or(false)),
    }
}

impl Resolved {
    /// Stiffness and damping of springs of `kind` as multiples of `stiffness` and
    /// `damping`: on a grid, shear and bend springs take `shear_scale` and
    /// `bend_scale`; every other spring takes 1.
    pub fn spring_scale(&self, kind: SpringKind) -> f64 {
        match (self.layout, kind) {
            (Layout::Grid, SpringKind::Shear) => self.shear_scale,
            (Layout::Grid | Layout::Mesh, SpringKind::Bend) => self.bend_scale,
            _ => 1.0,
        }
    }

    /// Brings these settings, resolved from `scene` before `edit`, in step with
    /// `scene` after [`Scene::apply`] recorded `edit`, without resolving the whole
    /// scene again: the edited value, and the stiffness and damping where the scene
    /// gives them per kg or as a ratio of critical damping (so that they follow a
    /// mass or stiffness edit as a full resolve would). A layout edit (see
    /// [`Edit::rebuilds`]) changes pins, spacing and masses given in total, and
    /// resolves the scene. On error the settings are unchanged.
    pub fn follow(&mut self, edit: Edit, scene: &Scene) -> Result<(), SceneError> {
        let o = EDIT_ORIGIN;
        let spec = &*filled(&scene.spec, o)?;
        let p = &mut self.params;
        match edit {
            Edit::Stiffness(_) | Edit::Damping(_) => {
                (self.stiffness, self.damping) = spring_constants(spec, o, self.particle_mass)?;
            }
            Edit::ParticleMass(m) => {
                (self.stiffness, self.damping) = spring_constants(spec, o, m)?;
                self.particle_mass = m;
            }
            // A mass per area gives particles a mass that follows the spacing.
            Edit::RestLength(_) if spec.areal_density.is_some() => *self = scene.resolve()?,
            Edit::RestLength(l) => {
                // A grid's default anchor depends on its spacing.
                self.origin = anchor(spec, o, [self.width, self.height], l)?;
                self.rest_length = l;
            }
            Edit::Gravity(g) => p.gravity = g,
            Edit::Force(f) => p.force = f,
            Edit::Wind(w) => p.wind = w,
            Edit::Gust(g) => p.gust = g,
            Edit::AirDamping(c) => p.air_damping = c,
            Edit::Dt(dt) => p.dt = dt,
            Edit::Substeps(n) => self.substeps = n,
            Edit::Integrator(i) => p.integrator = i,
            Edit::BarIterations(n) => p.bar_iterations = n,
            Edit::StretchLimit(t) => p.stretch_limit = t,
            Edit::TearStrain(t) => p.tear_strain = t,
            Edit::MaxSpeed(v) => p.max_speed = v,
            Edit::Friction(mu) => {
                p.friction = mu;
                if let Some(g) = &mut p.ground {
                    g.friction = mu;
                }
            }
            Edit::SelfCollision(on) => p.self_collision = on,
            Edit::Thickness(t) => {
                // The contact surfaces move with the thickness; the solids stay.
                let change = t - p.thickness;
                if let Some(g) = &mut p.ground {
                    g.height += change;
                }
                if let Some(s) = &mut p.sphere {
                    s.radius += change;
                }
                p.thickness = t;
            }
            Edit::Width(_) | Edit::Height(_) | Edit::Depth(_) | Edit::Material(_) => {
                *self = scene.resolve()?
            }
        }
        // Colliders without their own friction or thickness take the scene's.
        if matches!(edit, Edit::Friction(_) | Edit::Thickness(_)) {
            let (thickness, friction) = (self.params.thickness, self.params.friction);
            self.colliders = colliders::colliders(&spec.colliders, o, thickness, friction)?;
        }
        Ok(())
    }

    /// The particles `pins` names in this layout (a preset resolved for its shape),
    /// as a scene file's `pins` key would give them. An index past the last particle
    /// is an error naming `pins` and the allowed range.
    pub fn pin_indices(&self, pins: &Pins) -> Result<Vec<usize>, SceneError> {
        pin_indices(
            EDIT_ORIGIN,
            pins,
            self.layout,
            [self.width, self.height],
            self.particle_count(),
        )
    }

    /// Number of particles.
    pub fn particle_count(&self) -> usize {
        (self.width * self.height * self.depth) as usize
    }
}
