//! The panel's sliders as data: what each sets, over what range and on what
//! scale, for the scene running. Ranges sit around the scene's own values (as
//! loaded), forces and gravity go in units of weight, and every slider's two ends
//! are positions a user can drag to: the session tests drive each one there
//! under safe stepping. The app draws these; it chooses no range of its own.

use std::ops::RangeInclusive;

use glam::DVec3;

use super::Session;
use crate::limits::short;
use crate::scene::{Edit, Resolved};
use crate::sim::Integrator;

/// Earth's gravity (m/s²): the unit of the gravity slider and, times a
/// particle's mass, of the force sliders.
pub const EARTH_GRAVITY: f64 = 9.81;

/// One slider: a scalar of the settings shown as `value / unit`.
#[derive(Clone, Debug)]
pub struct Slider {
    /// Stable name (the scene key, with `_x`, `_y`, `_z` for a vector's axis).
    pub id: &'static str,
    /// The label, with the shown unit.
    pub label: String,
    /// The shown range.
    pub range: RangeInclusive<f64>,
    /// Whether the slider's scale is logarithmic.
    pub log: bool,
    /// SI units per shown unit.
    pub unit: f64,
    /// The hover text: what it does, in which unit, and the range.
    pub tip: String,
    read: Read,
    make: Make,
}

/// Reads a slider's value (SI) from the settings.
type Read = fn(&Resolved) -> f64;
/// Makes the edit that sets a slider's value (SI).
type Make = fn(&Resolved, f64) -> Edit;

impl Slider {
    /// The shown value in `settings`.
    pub fn value(&self, settings: &Resolved) -> f64 {
        (self.read)(settings) / self.unit
    }

    /// The edit that sets the shown value `shown` in `settings`.
    pub fn edit(&self, settings: &Resolved, shown: f64) -> Edit {
        (self.make)(settings, shown * self.unit)
    }
}

/// The scene's own values, as loaded, that the ranges sit around.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(super) struct Home {
    pub(super) stiffness: f64,
    pub(super) damping: f64,
    pub(super) rest_length: f64,
    pub(super) particle_mass: f64,
}

impl Home {
    pub(super) fn of(settings: &Resolved) -> Self {
        Self {
            stiffness: settings.stiffness,
            damping: settings.damping,
            rest_length: settings.rest_length,
            particle_mass: settings.particle_mass,
        }
    }
}

/// Factors the stiffness slider spans below and above the scene's stiffness:
/// a cloth much softer than its scene sags far, and stiffening it again at once
/// stores the energy of that stretch.
const STIFFNESS_SOFTER: f64 = 10.0;
const STIFFNESS_STIFFER: f64 = 100.0;
/// Factor the rest-length slider spans either side of the scene's spacing.
const REST_LENGTH_FACTOR: f64 = 4.0;
/// Factor the mass slider spans either side of the scene's particle mass.
const MASS_FACTOR: f64 = 10.0;
/// Largest force on a particle, in its weights.
const MOST_WEIGHTS: f64 = 5.0;

impl Session {
    /// The sliders of the parameters this scene uses, in the panel's order.
    pub fn sliders(&self) -> Vec<Slider> {
        let (r, home) = (self.settings(), self.home);
        let system = self.system();
        let springs = !system.springs().is_empty();
        let surface = !system.triangles().is_empty();
        let mut out = Vec::new();
        if springs {
            out.push(stiffness(r, home));
            out.push(damping(r, home));
        }
        if r.layout != crate::scene::Layout::Mesh {
            out.push(rest_length(r, home));
        }
        out.push(particle_mass(home));
        out.push(gravity());
        out.extend(forces(r));
        if surface {
            out.extend(winds());
        }
        out.push(dt(r));
        if springs && r.params.stretch_limit.is_some() {
            out.push(stretch_limit());
        }
        let p = &r.params;
        if p.ground.is_some() || p.sphere.is_some() || surface || !r.colliders.is_empty() {
            out.extend(contact(home));
        }
        if (springs || system.broken_springs() > 0) && p.tear_strain.is_some() {
            out.push(tear_strain());
        }
        if p.max_speed.is_some() {
            out.push(max_speed());
        }
        out
    }
}

/// A slider in SI units (`unit` 1).
fn si(
    id: &'static str,
    label: &str,
    range: RangeInclusive<f64>,
    log: bool,
    tip: &str,
    (read, make): (Read, Make),
) -> Slider {
    let scale = if log { ", logarithmic" } else { "" };
    Slider {
        id,
        label: label.to_string(),
        tip: format!(
            "{tip}\nSlider: {} to {}{scale}; type a value in the box for more",
            short(*range.start()),
            short(*range.end())
        ),
        range,
        log,
        unit: 1.0,
        read,
        make,
    }
}

fn stiffness(r: &Resolved, home: Home) -> Slider {
    // XPBD is stable at any stiffness: its slider reaches the scene files' limit.
    let k0 = if home.stiffness > 0.0 {
        home.stiffness
    } else {
        100.0
    };
    let hi = if r.params.integrator == Integrator::Xpbd {
        1e9
    } else {
        (k0 * STIFFNESS_STIFFER).min(1e9)
    };
    si(
        "stiffness",
        "stiffness k (N/m)",
        (k0 / STIFFNESS_SOFTER).max(1e-3)..=hi,
        true,
        "Spring stiffness k in N/m: force per metre of stretch (shear and bend springs keep their multiples of it)",
        (|r| r.stiffness, |_, k| Edit::Stiffness(k)),
    )
}

/// Damping up to twice the larger of the scene's and the critical damping of
/// one spring on its particle at the scene's stiffness (beyond it the cloth only
/// crawls, and an explicit step must shrink to follow).
fn damping(r: &Resolved, home: Home) -> Slider {
    let critical = 2.0 * (r.stiffness.max(home.stiffness) * r.particle_mass).sqrt();
    let hi = 2.0 * home.damping.max(critical).max(1e-3);
    let hint = if r.params.integrator == Integrator::ImplicitEuler {
        ""
    } else {
        "; heavier damping keeps an explicit step small: implicit Euler takes it at any dt"
    };
    let mut s = si(
        "damping",
        "damping b (N·s/m)",
        0.0..=hi,
        true,
        "",
        (|r| r.damping, |_, b| Edit::Damping(b)),
    );
    s.tip = format!(
        "Spring damping b in N·s/m: force per m/s of stretching speed along the spring{hint}\nSlider: 0 to {} (twice critical damping), logarithmic; type a value in the box for more",
        short(hi)
    );
    s
}

/// The spacing, down to the contact thickness where the particles keep that far
/// apart (closer, every particle would start inside its neighbours' reach).
fn rest_length(r: &Resolved, home: Home) -> Slider {
    let l0 = if home.rest_length > 0.0 {
        home.rest_length
    } else {
        0.1
    };
    let p = &r.params;
    let apart = if p.self_collision { p.thickness } else { 0.0 };
    let lo = (l0 / REST_LENGTH_FACTOR).max(apart).min(l0);
    let mut s = si(
        "rest_length",
        "rest length (m)",
        lo..=l0 * REST_LENGTH_FACTOR,
        true,
        "Spacing between neighbouring particles in m; the cloth grows or shrinks about its pins",
        (|r| r.rest_length, |_, l| Edit::RestLength(l)),
    );
    if apart > l0 / REST_LENGTH_FACTOR {
        s.tip += "; no closer than the self-collision thickness";
    }
    s
}

fn particle_mass(home: Home) -> Slider {
    let m0 = home.particle_mass;
    si(
        "particle_mass",
        "particle mass (kg)",
        m0 / MASS_FACTOR..=m0 * MASS_FACTOR,
        true,
        "Mass of each particle in kg, eased in over a few frames",
        (|r| r.particle_mass, |_, m| Edit::ParticleMass(m)),
    )
}

/// Gravity along y in Earth's gravities.
fn gravity() -> Slider {
    Slider {
        id: "gravity_y",
        label: "gravity y (g)".into(),
        range: -3.0..=1.0,
        log: false,
        unit: EARTH_GRAVITY,
        tip: "Gravity along y in Earth's gravities (1 g = 9.81 m/s², negative is down)\nSlider: -3 g to 1 g; type a value in the box for more".into(),
        read: |r| r.params.gravity.y,
        make: |r, g| Edit::Gravity(DVec3 { y: g, ..r.params.gravity }),
    }
}

/// Seed 001's force on every particle, along each axis, in the particle's
/// weight (`MOST_WEIGHTS` either way, or the force set if larger).
fn forces(r: &Resolved) -> [Slider; 3] {
    let weight = r.particle_mass * EARTH_GRAVITY;
    let set = r.params.force.abs().max_element() / weight;
    let reach = if set.is_finite() {
        set.max(MOST_WEIGHTS)
    } else {
        MOST_WEIGHTS
    };
    let axis = |id, label: &str, read: fn(&Resolved) -> f64, make| Slider {
        id,
        label: format!("force {label} (× weight)"),
        range: -reach..=reach,
        log: false,
        unit: weight,
        tip: format!(
            "Force along {label} on every particle besides gravity, in the particle's weight (1 = {} N)\nSlider: ±{}; type a value in the box for more",
            short(weight),
            short(reach)
        ),
        read,
        make,
    };
    [
        axis(
            "force_x",
            "x",
            |r| r.params.force.x,
            |r, v| {
                Edit::Force(DVec3 {
                    x: v,
                    ..r.params.force
                })
            },
        ),
        axis(
            "force_y",
            "y",
            |r| r.params.force.y,
            |r, v| {
                Edit::Force(DVec3 {
                    y: v,
                    ..r.params.force
                })
            },
        ),
        axis(
            "force_z",
            "z",
            |r| r.params.force.z,
            |r, v| {
                Edit::Force(DVec3 {
                    z: v,
                    ..r.params.force
                })
            },
        ),
    ]
}

/// Wind along each axis, and gusts.
fn winds() -> [Slider; 4] {
    let axis = |id, tip: &str, read, make| si(id, &id[5..], -20.0..=20.0, false, tip, (read, make));
    [
        axis(
            "wind_x",
            "Wind velocity along x in m/s",
            |r| r.params.wind.x,
            |r, v| {
                Edit::Wind(DVec3 {
                    x: v,
                    ..r.params.wind
                })
            },
        ),
        axis(
            "wind_y",
            "Wind velocity along y in m/s",
            |r| r.params.wind.y,
            |r, v| {
                Edit::Wind(DVec3 {
                    y: v,
                    ..r.params.wind
                })
            },
        ),
        axis(
            "wind_z",
            "Wind velocity along z in m/s (towards the viewer)",
            |r| r.params.wind.z,
            |r, v| {
                Edit::Wind(DVec3 {
                    z: v,
                    ..r.params.wind
                })
            },
        ),
        si(
            "gust",
            "gust (m/s)",
            0.0..=10.0,
            false,
            "Gust amplitude in m/s: random variation of the wind about its mean",
            (|r| r.params.gust, |_, g| Edit::Gust(g)),
        ),
    ]
}

/// The step, up to one frame's simulated time (one step a frame): a longer step
/// could not keep the speed.
fn dt(r: &Resolved) -> Slider {
    let frame = r.params.dt * f64::from(r.substeps);
    si(
        "dt",
        "dt (s)",
        1e-5_f64.min(frame)..=frame.max(1e-5),
        true,
        "Time step in s. The speed stays: the steps per frame change with it, so a larger dt means coarser steps, not a faster run, up to one step a frame. Safe stepping may run smaller steps over the same simulated time",
        (|r| r.params.dt, |_, dt| Edit::Dt(dt)),
    )
}

fn stretch_limit() -> Slider {
    si(
        "stretch_limit",
        "max stretch (tau)",
        0.0..=1.0,
        false,
        "Maximum stretch tau (Provot): springs are kept no longer than (1 + tau) times their rest length; 0.1 = 10% (0 to 100)",
        (
            |r| r.params.stretch_limit.unwrap_or(0.0),
            |_, t| Edit::StretchLimit(Some(t)),
        ),
    )
}

/// Friction, and a thickness up to the scene's spacing.
fn contact(home: Home) -> [Slider; 2] {
    let thickest = if home.rest_length > 0.0 {
        home.rest_length.min(0.1)
    } else {
        0.1
    };
    [
        si(
            "friction",
            "friction μ",
            0.0..=2.0,
            false,
            "Coulomb friction coefficient μ of the ground and the colliders (no unit); 0 is frictionless",
            (|r| r.params.friction, |_, mu| Edit::Friction(mu)),
        ),
        si(
            "thickness",
            "thickness (m)",
            0.0..=thickest,
            false,
            "Contact thickness in m: how far above the ground and outside the colliders the cloth rests",
            (|r| r.params.thickness, |_, t| Edit::Thickness(t)),
        ),
    ]
}

fn tear_strain() -> Slider {
    si(
        "tear_strain",
        "tear strain",
        0.01..=2.0,
        true,
        "A spring breaks when longer than (1 + strain) times its rest length: 0.5 = 50% stretched (0.01 to 100)",
        (
            |r| r.params.tear_strain.unwrap_or(0.5),
            |_, t| Edit::TearStrain(Some(t)),
        ),
    )
}

fn max_speed() -> Slider {
    si(
        "max_speed",
        "max speed (m/s)",
        0.1..=100.0,
        true,
        "Speed limit in m/s: no particle leaves a step faster than this (above 0, up to 1e6)",
        (
            |r| r.params.max_speed.unwrap_or(10.0),
            |_, v| Edit::MaxSpeed(Some(v)),
        ),
    )
}
