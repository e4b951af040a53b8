//! Typed edits of a scene's settings, as the app's panel makes them while the scene
//! runs: the value in SI units, checked against the same range as the scene file's
//! key. Text (`--set key=value`, scene files) is parsed at the edge instead; an edit
//! never goes through a string.

use glam::DVec3;

use super::Material;
use crate::sim::Integrator;

/// Where a typed edit's value comes from, in error messages.
pub(crate) const EDIT_ORIGIN: &str = "live edit";

/// One changed setting. Every edit but [`Edit::Width`], [`Edit::Height`],
/// [`Edit::Depth`] and [`Edit::Material`] applies to a running system in place.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Edit {
    /// Spring stiffness k in N/m (`stiffness`). On a grid, shear and bend springs
    /// keep their multiples of it (`shear_scale`, `bend_scale`).
    Stiffness(f64),
    /// Spring damping b in N·s/m (`damping`), scaled per kind as the stiffness is.
    Damping(f64),
    /// Spacing between neighbours in m (`rest_length`); a running cloth is scaled
    /// about its pins, keeping its strains.
    RestLength(f64),
    /// Mass of each particle in kg (`particle_mass`).
    ParticleMass(f64),
    /// Gravitational acceleration in m/s² (`gravity`).
    Gravity(DVec3),
    /// Force in N on every particle besides gravity (`force`).
    Force(DVec3),
    /// Mean wind velocity in m/s (`wind`).
    Wind(DVec3),
    /// Gust amplitude in m/s (`gust`).
    Gust(f64),
    /// Viscous air damping c in N·s/m (`air_damping`).
    AirDamping(f64),
    /// Time step in s (`dt`), before safe stepping shortens it.
    Dt(f64),
    /// Steps per displayed frame (`substeps`, the speed).
    Substeps(u32),
    /// Integration method (`integrator`).
    Integrator(Integrator),
    /// Rigid-bar relaxation passes per step (`bar_iterations`).
    BarIterations(u32),
    /// Maximum stretch tau (`stretch_limit`): springs no longer than (1 + tau) L;
    /// `None`: no limit.
    StretchLimit(Option<f64>),
    /// Strain past which a spring tears (`tear_strain`); `None`: springs never tear.
    TearStrain(Option<f64>),
    /// Speed limit in m/s (`max_speed`); `None`: no limit.
    MaxSpeed(Option<f64>),
    /// Coulomb friction coefficient μ of the ground and the sphere (`friction`).
    Friction(f64),
    /// Contact thickness in m on the ground and the sphere (`thickness`).
    Thickness(f64),
    /// Whether the particles keep `thickness` apart (`self_collision`).
    SelfCollision(bool),
    /// Particles across a grid or lattice, or along a chain or rope (`width`): rebuilds.
    Width(u32),
    /// Particles down a grid or lattice (`height`): rebuilds.
    Height(u32),
    /// Particles deep in a lattice (`depth`): rebuilds.
    Depth(u32),
    /// A cloth's material (`material`), replacing the scene's own mass, stiffness,
    /// damping, shear and bend scales and drag: rebuilds.
    Material(&'static Material),
}

impl Edit {
    /// The scene key the edit sets, as in scene files and `--set`.
    pub fn key(self) -> &'static str {
        match self {
            Self::Stiffness(_) => "stiffness",
            Self::Damping(_) => "damping",
            Self::RestLength(_) => "rest_length",
            Self::ParticleMass(_) => "particle_mass",
            Self::Gravity(_) => "gravity",
            Self::Force(_) => "force",
            Self::Wind(_) => "wind",
            Self::Gust(_) => "gust",
            Self::AirDamping(_) => "air_damping",
            Self::Dt(_) => "dt",
            Self::Substeps(_) => "substeps",
            Self::Integrator(_) => "integrator",
            Self::BarIterations(_) => "bar_iterations",
            Self::StretchLimit(_) => "stretch_limit",
            Self::TearStrain(_) => "tear_strain",
            Self::MaxSpeed(_) => "max_speed",
            Self::Friction(_) => "friction",
            Self::Thickness(_) => "thickness",
            Self::SelfCollision(_) => "self_collision",
            Self::Width(_) => "width",
            Self::Height(_) => "height",
            Self::Depth(_) => "depth",
            Self::Material(_) => "material",
        }
    }

    /// Whether the edit changes the layout, so that the system is rebuilt (keeping
    /// every other setting) rather than changed in place.
    pub fn rebuilds(self) -> bool {
        matches!(
            self,
            Self::Width(_) | Self::Height(_) | Self::Depth(_) | Self::Material(_)
        )
    }
}

/// `key = value` as a scene file writes it (vectors as `x,y,z`; an option
/// turned off as `off`).
impl std::fmt::Display for Edit {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let key = self.key();
        let g = crate::limits::short;
        let vector = |v: DVec3| format!("{},{},{}", g(v.x), g(v.y), g(v.z));
        let option = |o: Option<f64>| o.map_or("off".to_string(), g);
        let value = match *self {
            Self::Stiffness(x)
            | Self::Damping(x)
            | Self::RestLength(x)
            | Self::ParticleMass(x)
            | Self::Gust(x)
            | Self::AirDamping(x)
            | Self::Dt(x)
            | Self::Friction(x)
            | Self::Thickness(x) => g(x),
            Self::Gravity(v) | Self::Force(v) | Self::Wind(v) => vector(v),
            Self::Substeps(n)
            | Self::BarIterations(n)
            | Self::Width(n)
            | Self::Height(n)
            | Self::Depth(n) => n.to_string(),
            Self::Integrator(i) => i.to_string(),
            Self::StretchLimit(o) | Self::TearStrain(o) | Self::MaxSpeed(o) => option(o),
            Self::SelfCollision(on) => on.to_string(),
            Self::Material(m) => m.name.to_string(),
        };
        write!(f, "{key} = {value}")
    }
}
