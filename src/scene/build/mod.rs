//! From a scene spec to a system: fill in defaults, check every value against its
//! range (the error names the field and the range), then lay out particles, springs,
//! bars, triangles and pins.

use std::sync::Arc;

use glam::{DMat3, DVec2, DVec3};

use super::edit::EDIT_ORIGIN;
use super::mesh::{self, Mesh};
use super::values::{PinPreset, Pins};
use super::{Edit, Layout, Orientation, Scene, SceneError, SceneSpec};
use crate::limits::number as shown;
use crate::sim::laws::out_of_sphere;
use crate::sim::{Bar, Ground, Integrator, Params, Sphere, Spring, SpringKind, System, Topology};
use crate::sim::{GridShape, LatticeShape};

/// Largest grid side (particles), so a typo cannot ask for billions of particles.
pub const GRID_MAX_SIDE: u32 = 1024;
/// Largest chain or rope length (particles).
pub const LINE_MAX: u32 = 100_000;
/// Largest lattice side (particles).
pub const LATTICE_MAX_SIDE: u32 = 64;

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

fn invalid(origin: &str, field: &str, message: String) -> SceneError {
    SceneError::Invalid {
        origin: origin.to_string(),
        field: field.to_string(),
        message,
    }
}

/// The allowed values of a number field: finite and in `[lo, hi]`, or `(lo, hi]`
/// when `lo_open`. One constant per field that a live edit can change, so that a
/// scene file, `--set` and the panel check it against the same range.
#[derive(Clone, Copy, Debug)]
pub struct NumberRange<'a> {
    /// The scene key.
    pub field: &'a str,
    /// Lowest value.
    pub lo: f64,
    /// Whether `lo` itself is excluded.
    pub lo_open: bool,
    /// Highest value.
    pub hi: f64,
}

impl NumberRange<'_> {
    /// `value` if it is in range, else an error naming the field and the range.
    pub fn check(&self, origin: &str, value: f64) -> Result<f64, SceneError> {
        let Self {
            field,
            lo,
            lo_open,
            hi,
        } = *self;
        let low_ok = if lo_open { value > lo } else { value >= lo };
        if value.is_finite() && low_ok && value <= hi {
            return Ok(value);
        }
        let bracket = if lo_open { "(" } else { "[" };
        Err(invalid(
            origin,
            field,
            format!(
                "= {} is out of range: must be a finite number in {bracket}{}, {}]",
                shown(value),
                shown(lo),
                shown(hi)
            ),
        ))
    }
}

/// The allowed values of an integer field: `[lo, hi]`.
#[derive(Clone, Copy, Debug)]
pub struct CountRange {
    /// The scene key.
    pub field: &'static str,
    /// Lowest value.
    pub lo: u32,
    /// Highest value.
    pub hi: u32,
}

impl CountRange {
    /// `value` if it is in range, else an error naming the field and the range.
    pub fn check(&self, origin: &str, value: u32) -> Result<u32, SceneError> {
        count(origin, self.field, value, self.lo, self.hi)
    }
}

/// The allowed values of a vector field: finite components, length at most `max_norm`.
#[derive(Clone, Copy, Debug)]
pub struct VectorRange {
    /// The scene key.
    pub field: &'static str,
    /// Longest allowed vector.
    pub max_norm: f64,
}

impl VectorRange {
    /// `value` if it is in range, else an error naming the field and the range.
    pub fn check(&self, origin: &str, value: DVec3) -> Result<DVec3, SceneError> {
        vector(origin, self.field, value, self.max_norm)
    }
}

const fn number(field: &'static str, lo: f64, lo_open: bool, hi: f64) -> NumberRange<'static> {
    NumberRange {
        field,
        lo,
        lo_open,
        hi,
    }
}

/// `rest_length` in m.
pub const REST_LENGTH: NumberRange<'static> = number("rest_length", 0.0, false, 1e3);
/// `particle_mass` in kg. The floor (a picogram) keeps 1/m and k/m finite in
/// f32, which the fast engines step in; a mass that underflows is refused.
pub const PARTICLE_MASS: NumberRange<'static> = number("particle_mass", 1e-12, false, 1e6);
/// `stiffness` in N/m.
pub const STIFFNESS: NumberRange<'static> = number("stiffness", 0.0, false, 1e9);
/// `damping` in N·s/m.
pub const DAMPING: NumberRange<'static> = number("damping", 0.0, false, 1e9);
/// `gust` in m/s.
pub const GUST: NumberRange<'static> = number("gust", 0.0, false, 1e4);
/// `air_damping` in N·s/m.
pub const AIR_DAMPING: NumberRange<'static> = number("air_damping", 0.0, false, 1e9);
/// `dt` in s.
pub const DT: NumberRange<'static> = number("dt", 0.0, true, 1.0);
/// `stretch_limit` (a fraction of the rest length).
pub const STRETCH_LIMIT: NumberRange<'static> = number("stretch_limit", 0.0, false, 100.0);
/// `tear_strain` (a fraction of the rest length).
pub const TEAR_STRAIN: NumberRange<'static> = number("tear_strain", 0.0, true, 100.0);
/// `max_speed` in m/s.
pub const MAX_SPEED: NumberRange<'static> = number("max_speed", 0.0, true, 1e6);
/// `friction`, the Coulomb coefficient μ of the colliders.
pub const FRICTION: NumberRange<'static> = number("friction", 0.0, false, 10.0);
/// `thickness` in m: contact thickness of the cloth on the colliders.
pub const THICKNESS: NumberRange<'static> = number("thickness", 0.0, false, 10.0);
/// `force` in N.
pub const FORCE: VectorRange = VectorRange {
    field: "force",
    max_norm: 1e6,
};
/// `gravity` in m/s².
pub const GRAVITY: VectorRange = VectorRange {
    field: "gravity",
    max_norm: 1e4,
};
/// `wind` in m/s.
pub const WIND: VectorRange = VectorRange {
    field: "wind",
    max_norm: 1e4,
};
/// `substeps` per frame.
pub const SUBSTEPS: CountRange = CountRange {
    field: "substeps",
    lo: 1,
    hi: 100_000,
};
/// `bar_iterations` per step.
pub const BAR_ITERATIONS: CountRange = CountRange {
    field: "bar_iterations",
    lo: 0,
    hi: 10_000,
};

/// `bar_iterations = n` on `layout`, checked: only a rope and a grid of bars
/// (`bars = true`) have bars (on any other
/// layout the key would do nothing, so it is refused), and `n` in its range.
pub fn bar_iterations(origin: &str, layout: Layout, bars: bool, n: u32) -> Result<u32, SceneError> {
    if layout != Layout::Rope && !(layout == Layout::Grid && bars) {
        return Err(invalid(
            origin,
            "bar_iterations",
            format!(
                "does not apply to a {} layout without bars: only a rope and a grid with `bars = true` have bars to relax",
                layout.name()
            ),
        ));
    }
    BAR_ITERATIONS.check(origin, n)
}

/// The allowed `width`, `height` and `depth` of a layout; `None` where the layout
/// ignores the key (a spring has two particles; lines have no height or depth).
pub fn side_ranges(layout: Layout) -> [Option<CountRange>; 3] {
    let side = |field, hi| Some(CountRange { field, lo: 1, hi });
    match layout {
        Layout::Grid => [
            side("width", GRID_MAX_SIDE),
            side("height", GRID_MAX_SIDE),
            None,
        ],
        Layout::Lattice => [
            side("width", LATTICE_MAX_SIDE),
            side("height", LATTICE_MAX_SIDE),
            side("depth", LATTICE_MAX_SIDE),
        ],
        Layout::Chain | Layout::Rope => [side("width", LINE_MAX), None, None],
        Layout::Spring | Layout::Mesh => [None, None, None],
    }
}

/// Checks `value` is finite and in `[lo, hi]` (`lo_open`: strictly above `lo`).
fn ranged(
    origin: &str,
    field: &str,
    value: f64,
    lo: f64,
    lo_open: bool,
    hi: f64,
) -> Result<f64, SceneError> {
    NumberRange {
        field,
        lo,
        lo_open,
        hi,
    }
    .check(origin, value)
}

fn count(origin: &str, field: &str, value: u32, lo: u32, hi: u32) -> Result<u32, SceneError> {
    if (lo..=hi).contains(&value) {
        Ok(value)
    } else {
        Err(invalid(
            origin,
            field,
            format!("= {value} is out of range: must be an integer in [{lo}, {hi}]"),
        ))
    }
}

fn vector(origin: &str, field: &str, v: DVec3, max_norm: f64) -> Result<DVec3, SceneError> {
    if v.is_finite() && v.length() <= max_norm {
        Ok(v)
    } else {
        Err(invalid(
            origin,
            field,
            format!(
                "= ({}, {}, {}) is out of range: components must be finite, length at most {}",
                shown(v.x),
                shown(v.y),
                shown(v.z),
                shown(max_norm)
            ),
        ))
    }
}

fn one_of<T: Copy>(
    origin: &str,
    options: &[(&str, Option<T>)],
) -> Result<Option<(String, T)>, SceneError> {
    let given: Vec<_> = options
        .iter()
        .filter_map(|(k, v)| v.map(|v| (k.to_string(), v)))
        .collect();
    if given.len() > 1 {
        let names: Vec<_> = given.iter().map(|(k, _)| format!("`{k}`")).collect();
        return Err(invalid(
            origin,
            &given[0].0,
            format!(
                "conflicts with {}: give only one of them",
                names[1..].join(", ")
            ),
        ));
    }
    Ok(given.into_iter().next())
}

/// Spring stiffness (N/m) and damping (N·s/m) for particles of `particle_mass` kg,
/// from whichever of the spec's alternative keys give them (`stiffness` or
/// `stiffness_per_mass`; `damping`, `damping_ratio` or `damping_per_mass`).
pub fn spring_constants(
    spec: &SceneSpec,
    origin: &str,
    particle_mass: f64,
) -> Result<(f64, f64), SceneError> {
    let o = origin;
    let stiffness = match one_of(
        o,
        &[
            ("stiffness", spec.stiffness),
            ("stiffness_per_mass", spec.stiffness_per_mass),
        ],
    )? {
        Some((k, v)) if k == "stiffness_per_mass" => {
            ranged(o, "stiffness_per_mass", v, 0.0, false, 1e12)? * particle_mass
        }
        Some((_, v)) => STIFFNESS.check(o, v)?,
        None => 100.0,
    };
    let damping_options = [
        ("damping", spec.damping),
        ("damping_ratio", spec.damping_ratio),
        ("damping_per_mass", spec.damping_per_mass),
    ];
    let damping = match one_of(o, &damping_options)? {
        Some((k, v)) if k == "damping_ratio" => {
            ranged(o, "damping_ratio", v, 0.0, false, 100.0)?
                * 2.0
                * (stiffness * particle_mass).sqrt()
        }
        Some((k, v)) if k == "damping_per_mass" => {
            ranged(o, "damping_per_mass", v, 0.0, false, 1e9)? * particle_mass
        }
        Some((_, v)) => DAMPING.check(o, v)?,
        None => 0.0,
    };
    Ok((stiffness, damping))
}

/// Fills in defaults and checks ranges.
pub fn resolve(spec: &SceneSpec, origin: &str) -> Result<Resolved, SceneError> {
    let o = origin;
    let layout = spec.layout;
    let mesh = layout_mesh(spec, o)?;
    let mut sides = match (layout, &mesh) {
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
    let [width, height, depth] = sides;
    let particles = (width as usize) * (height as usize) * (depth as usize);

    let rest_length = match one_of(o, &[("rest_length", spec.rest_length), ("size", spec.size)])? {
        Some((k, v)) if k == "size" => {
            ranged(o, "size", v, 0.0, false, 1e4)? / (width.max(2) - 1) as f64
        }
        Some((_, v)) => REST_LENGTH.check(o, v)?,
        // A mesh's: its mean edge length (shown, not used).
        None => mesh.as_ref().map_or(0.1, |m| {
            let total: f64 = m
                .edges
                .iter()
                .map(|&[a, b]| m.positions[a as usize].distance(m.positions[b as usize]))
                .sum();
            total / m.edges.len().max(1) as f64
        }),
    };
    let particle_mass = match one_of(
        o,
        &[
            ("particle_mass", spec.particle_mass),
            ("total_mass", spec.total_mass),
        ],
    )? {
        Some((k, v)) if k == "total_mass" => {
            let total = ranged(o, "total_mass", v, 0.0, true, 1e9)?;
            let each = total / particles as f64;
            PARTICLE_MASS.check(o, each).map_err(|_| {
                invalid(
                    o,
                    "total_mass",
                    format!(
                        "= {} kg over {particles} particles is {} kg each, out of range: each particle must have a mass in [{}, {}] kg",
                        shown(total),
                        shown(each),
                        shown(PARTICLE_MASS.lo),
                        shown(PARTICLE_MASS.hi)
                    ),
                )
            })?
        }
        Some((_, v)) => PARTICLE_MASS.check(o, v)?,
        None => 0.01,
    };
    let (stiffness, damping) = spring_constants(spec, o, particle_mass)?;
    let bars = match spec.bars {
        Some(true) if layout != Layout::Grid => {
            return Err(invalid(
                o,
                "bars",
                format!(
                    "does not apply to a {} layout: only a grid can be made of bars (a rope always is)",
                    layout.name()
                ),
            ));
        }
        bars => bars.unwrap_or(false),
    };
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

    let integrator = match &spec.integrator {
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
    };
    let thickness = THICKNESS.check(o, spec.thickness.unwrap_or(0.0))?;
    let ground = match spec.ground_height {
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
    };
    // The keys of a part that is off would be ignored: refused instead, saying
    // how to turn the part on.
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
    let sphere = match spec.sphere_center {
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
    };
    let stretch_limit = match spec.stretch_limit {
        None => None,
        Some(t) => Some(STRETCH_LIMIT.check(o, t)?),
    };
    let params = Params {
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
    };
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
    })
}

/// Position of the layout's anchor in m: the spec's `origin`, or by default a
/// vertical grid's top-left corner such that it hangs centred above y = 0 (a
/// horizontal grid centred at y = 1), which moves with the grid's size.
fn anchor(
    spec: &SceneSpec,
    o: &str,
    [width, height]: [u32; 2],
    rest_length: f64,
) -> Result<DVec3, SceneError> {
    let default_origin = match (spec.layout, spec.orientation.unwrap_or_default()) {
        (Layout::Grid, Orientation::Vertical) => DVec3::new(
            -0.5 * (width - 1) as f64 * rest_length,
            (height - 1) as f64 * rest_length,
            0.0,
        ),
        (Layout::Grid, Orientation::Horizontal) => DVec3::new(
            -0.5 * (width - 1) as f64 * rest_length,
            1.0,
            -0.5 * (height - 1) as f64 * rest_length,
        ),
        _ => DVec3::ZERO,
    };
    match spec.origin {
        Some(v) => vector(o, "origin", v.0, 1e6),
        // No origin was given: the default anchor follows from the grid's size and
        // spacing, so an anchor out of range is their doing, and they are named.
        None => vector(o, "origin", default_origin, 1e6).map_err(|_| SceneError::Invalid {
            origin: o.to_string(),
            field: "rest_length".to_string(),
            message: format!(
                "= {} m with width = {width} and height = {height} makes a cloth {} m across, \
                 whose default anchor (origin, not set) = ({}, {}, {}) is past 1e6 m: give a \
                 smaller rest_length, width or height, or set origin",
                crate::limits::number(rest_length),
                crate::limits::number(f64::from(width.max(height).saturating_sub(1)) * rest_length),
                crate::limits::number(default_origin.x),
                crate::limits::number(default_origin.y),
                crate::limits::number(default_origin.z),
            ),
        }),
    }
}

/// The rotation of `degrees` about z, then x, then y.
fn rotation_matrix(degrees: DVec3) -> DMat3 {
    let rad = degrees * (std::f64::consts::PI / 180.0);
    DMat3::from_rotation_y(rad.y) * DMat3::from_rotation_x(rad.x) * DMat3::from_rotation_z(rad.z)
}

/// The pin set a layout has when its scene names none: a grid's top corners, a
/// lattice or a mesh nothing, the first particle of a line.
fn default_pins(layout: Layout) -> PinPreset {
    match layout {
        Layout::Grid => PinPreset::TopCorners,
        Layout::Lattice | Layout::Mesh => PinPreset::None,
        _ => PinPreset::First,
    }
}

/// The particles `pins` names in a `width` x `height` layout of `particles`, sorted;
/// an index past the last particle is an error naming `pins` and the range.
fn pin_indices(
    o: &str,
    pins: &Pins,
    layout: Layout,
    [width, height]: [u32; 2],
    particles: usize,
) -> Result<Vec<usize>, SceneError> {
    match pins {
        Pins::Indices(list) => {
            if let Some(&bad) = list.iter().find(|&&i| i >= particles) {
                return Err(invalid(
                    o,
                    "pins",
                    format!(
                        "index {bad} is out of range: the scene has {particles} particles (0 to {})",
                        particles.saturating_sub(1)
                    ),
                ));
            }
            Ok(list.clone())
        }
        Pins::Preset(p) => Ok(preset_pins(
            *p,
            layout,
            width as usize,
            height as usize,
            particles,
        )),
    }
}

fn preset_pins(preset: PinPreset, layout: Layout, w: usize, h: usize, n: usize) -> Vec<usize> {
    let mut pins = match (preset, layout) {
        (PinPreset::None, _) => vec![],
        (PinPreset::First, _) => vec![0],
        (_, Layout::Grid) => match preset {
            PinPreset::Corners => vec![0, w - 1, (h - 1) * w, h * w - 1],
            PinPreset::TopCorners => vec![0, w - 1],
            PinPreset::TopEdge => (0..w).collect(),
            PinPreset::LeftEdge => (0..h).map(|r| r * w).collect(),
            PinPreset::LeftEdgeEveryFourth => (0..h).step_by(4).map(|r| r * w).collect(),
            _ => vec![],
        },
        // Off a grid, the grid presets mean the ends of the line or block.
        (PinPreset::Corners | PinPreset::TopCorners, _) => vec![0, n - 1],
        _ => vec![0],
    };
    pins.sort_unstable();
    pins.dedup();
    pins
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
        let (spec, o) = (&scene.spec, EDIT_ORIGIN);
        let p = &mut self.params;
        match edit {
            Edit::Stiffness(_) | Edit::Damping(_) => {
                (self.stiffness, self.damping) = spring_constants(spec, o, self.particle_mass)?;
            }
            Edit::ParticleMass(m) => {
                (self.stiffness, self.damping) = spring_constants(spec, o, m)?;
                self.particle_mass = m;
            }
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
            Edit::Width(_) | Edit::Height(_) | Edit::Depth(_) => *self = scene.resolve()?,
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
        let spring = |a: usize, b: usize, rest: f64, kind| Spring {
            a: a as u32,
            b: b as u32,
            rest,
            stiffness: self.stiffness * self.spring_scale(kind),
            damping: self.damping * self.spring_scale(kind),
            kind,
        };
        let positions = self.positions();
        let (mut springs, mut bars, mut triangles, mut uvs) =
            (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        let l = self.rest_length;
        match self.layout {
            Layout::Grid => {
                let (w, h) = (self.width as usize, self.height as usize);
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
                        springs.push(spring(a, b, rest, kind));
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
            }
            Layout::Spring => {
                springs.push(spring(0, 1, l, SpringKind::Other));
            }
            Layout::Mesh => {
                if let Some(m) = &self.mesh {
                    // Rest lengths from the file's coordinates (the start positions
                    // may have been moved out of the sphere).
                    let rest = |[a, b]: [u32; 2]| {
                        m.positions[a as usize].distance(m.positions[b as usize])
                    };
                    for &edge in &m.edges {
                        springs.push(spring(
                            edge[0] as usize,
                            edge[1] as usize,
                            rest(edge),
                            SpringKind::Structural,
                        ));
                    }
                    if self.bend_scale > 0.0 {
                        for &pair in &m.bends {
                            springs.push(spring(
                                pair[0] as usize,
                                pair[1] as usize,
                                rest(pair),
                                SpringKind::Bend,
                            ));
                        }
                    }
                    triangles.clone_from(&m.triangles);
                    uvs.clone_from(&m.uvs);
                }
            }
            Layout::Chain | Layout::Rope => {
                for i in 0..self.width as usize {
                    if i > 0 {
                        if self.layout == Layout::Chain {
                            springs.push(spring(i - 1, i, l, SpringKind::Other));
                        } else {
                            bars.push(Bar {
                                a: (i - 1) as u32,
                                b: i as u32,
                                length: l,
                            });
                        }
                    }
                }
            }
            Layout::Lattice => {
                let (w, h, d) = (
                    self.width as usize,
                    self.height as usize,
                    self.depth as usize,
                );
                let index = |x: usize, y: usize, z: usize| (z * h + y) * w + x;
                // Every neighbour within one cell: axis (structural), face diagonal
                // (shear) and body diagonal (other), as in seed 002's cube.
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
                                        let steps = dx.unsigned_abs() as usize
                                            + dy.unsigned_abs() as usize
                                            + dz;
                                        let kind = [
                                            SpringKind::Structural,
                                            SpringKind::Shear,
                                            SpringKind::Other,
                                        ][steps - 1];
                                        let rest = l * (steps as f64).sqrt();
                                        springs.push(spring(
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
            }
        }
        let uvs = if triangles.is_empty() {
            Vec::new()
        } else {
            uvs
        };
        let grid = (self.layout == Layout::Grid).then_some(GridShape {
            width: self.width as usize,
            height: self.height as usize,
        });
        let lattice = (self.layout == Layout::Lattice).then_some(LatticeShape {
            width: self.width as usize,
            height: self.height as usize,
            depth: self.depth as usize,
        });
        let topology = Topology {
            springs,
            bars,
            triangles,
            uvs,
            grid,
            lattice,
        };
        System::new(masses, positions, &self.pins, topology, self.params)
    }
}
