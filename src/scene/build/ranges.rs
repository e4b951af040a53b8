//! The allowed range of every scene value, and the checks that name the field and
//! the range when a value is out of it.

use glam::DVec3;

use crate::limits::number as shown;
use crate::scene::{Layout, SceneError, SceneSpec};

/// Largest grid side (particles), so a typo cannot ask for billions of particles.
pub const GRID_MAX_SIDE: u32 = 1024;
/// Largest chain or rope length (particles).
pub const LINE_MAX: u32 = 100_000;
/// Largest lattice side (particles).
pub const LATTICE_MAX_SIDE: u32 = 64;

pub(super) fn invalid(origin: &str, field: &str, message: String) -> SceneError {
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
pub(super) fn ranged(
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

pub(super) fn vector(
    origin: &str,
    field: &str,
    v: DVec3,
    max_norm: f64,
) -> Result<DVec3, SceneError> {
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

pub(super) fn one_of<T: Copy>(
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
