//! Extreme settings of the `cloth` scene, each run twice: as given (raw) and with
//! safe stepping ([`crate::sim::safe`]), and classified as finite, refused with a
//! message (the scene is rejected), or diverged and caught by the divergence check.

use crate::scene::Scene;
use crate::sim::{System, safe::safe_step_below};

/// How one run of an extreme case ended.
#[derive(Clone, Debug, PartialEq)]
pub enum Outcome {
    /// Ran to the end with finite values.
    Finite {
        /// Steps taken.
        steps: u64,
        /// Largest speed at the end, m/s.
        max_speed: f64,
    },
    /// The scene was rejected before running.
    Refused(String),
    /// The divergence check stopped the run.
    Caught {
        /// Simulated time in s.
        time: f64,
        /// The check's message.
        message: String,
    },
}

impl Outcome {
    /// One-line text for tables.
    pub fn text(&self) -> String {
        match self {
            Self::Finite { steps, max_speed } => {
                format!("finite ({steps} steps, max speed {max_speed:.3} m/s)")
            }
            Self::Refused(m) => format!("refused: {m}"),
            Self::Caught { message, .. } => format!("diverged, caught: {message}"),
        }
    }

    /// Short label: `finite`, `refused`, `caught`.
    pub fn label(&self) -> &'static str {
        match self {
            Self::Finite { .. } => "finite",
            Self::Refused(_) => "refused",
            Self::Caught { .. } => "caught",
        }
    }
}

/// One extreme case.
#[derive(Clone, Debug)]
pub struct Case {
    /// Short name.
    pub name: &'static str,
    /// `--set` overrides on the `cloth` scene.
    pub overrides: Vec<String>,
    /// Multiply every rest length by this after building (the app's rest-length slider).
    pub rest_scale: Option<f64>,
    /// Simulated time (raw steps of the scene's dt; `steps` if given).
    pub duration: f64,
    /// Number of outer steps instead of `duration`.
    pub steps: Option<u64>,
}

/// Result of one case.
#[derive(Clone, Debug)]
pub struct Result {
    /// The case.
    pub case: Case,
    /// Step of the raw run, s.
    pub dt: f64,
    /// Raw outcome.
    pub raw: Outcome,
    /// Substeps safe stepping chose per step of `dt` (None if refused).
    pub safe_substeps: Option<u32>,
    /// Whether safe stepping met its safety fraction.
    pub safe_met: bool,
    /// Outcome with safe stepping.
    pub safe: Outcome,
}

/// The extreme cases of issue 4.
pub fn cases(quick: bool) -> Vec<Case> {
    let case = |name, overrides: &[&str]| Case {
        name,
        overrides: overrides.iter().map(|s| s.to_string()).collect(),
        rest_scale: None,
        duration: if quick { 0.1 } else { 0.25 },
        steps: None,
    };
    vec![
        case("k = 1e6 N/m", &["stiffness=1e6"]),
        case("particle mass 1e-6 kg", &["particle_mass=1e-6"]),
        Case {
            steps: Some(20),
            ..case("dt = 0.1 s", &["dt=0.1"])
        },
        Case {
            steps: Some(3),
            ..case("512x512 cloth", &["width=512", "height=512"])
        },
        case("wind 100 m/s", &["wind=100,0,0"]),
        case("rest length 0 (scene)", &["rest_length=0"]),
        Case {
            rest_scale: Some(0.0),
            ..case("rest length scaled to 0 (slider)", &[])
        },
        case("every particle pinned (8x8)", &["width=8", "height=8"]).with_all_pinned(64),
        case("none pinned", &["pins=none"]),
        case("width 1", &["width=1"]),
        case("height 1", &["height=1"]),
        case("width 0", &["width=0"]),
    ]
}

impl Case {
    fn with_all_pinned(mut self, n: usize) -> Self {
        let list: Vec<String> = (0..n).map(|i| i.to_string()).collect();
        self.overrides.push(format!("pins=[{}]", list.join(",")));
        self
    }

    /// The `--set` arguments as a command line fragment.
    pub fn command_line(&self) -> String {
        self.overrides
            .iter()
            .map(|o| format!("--set {o}"))
            .collect::<Vec<_>>()
            .join(" ")
    }

    /// Builds the system, or the scene's error message.
    pub fn build(&self) -> std::result::Result<System, String> {
        let mut scene = Scene::load("cloth").map_err(|e| e.to_string())?;
        scene
            .set_all(self.overrides.iter().map(String::as_str))
            .map_err(|e| e.to_string())?;
        let mut system = scene.build().map_err(|e| e.to_string())?;
        if let Some(f) = self.rest_scale {
            system.scale_rest_lengths(f);
        }
        Ok(system)
    }
}

fn run(mut system: System, steps: u64) -> Outcome {
    match system.run(steps) {
        Ok(()) => Outcome::Finite {
            steps,
            max_speed: system
                .velocities()
                .iter()
                .map(|v| v.length())
                .fold(0.0, f64::max),
        },
        Err(d) => Outcome::Caught {
            time: d.time(),
            message: d.to_string(),
        },
    }
}

/// Runs one case raw and with safe stepping at `safety`.
pub fn run_case(case: &Case, safety: f64) -> Result {
    let system = match case.build() {
        Ok(s) => s,
        Err(message) => {
            return Result {
                case: case.clone(),
                dt: f64::NAN,
                raw: Outcome::Refused(message.clone()),
                safe_substeps: None,
                safe_met: false,
                safe: Outcome::Refused(message),
            };
        }
    };
    let dt = system.params().dt;
    let outer = case
        .steps
        .unwrap_or_else(|| (case.duration / dt).round().max(1.0) as u64);
    let choice = safe_step_below(
        system.stability().dt_critical,
        dt,
        safety,
        crate::sim::safe::DEFAULT_MAX_SUBSTEPS,
    );
    let mut safe_system = system.clone();
    let mut params = *safe_system.params();
    params.dt = choice.dt;
    safe_system.set_params(params);
    let raw = run(system, outer);
    let safe = run(safe_system, outer * choice.substeps as u64);
    Result {
        case: case.clone(),
        dt,
        raw,
        safe_substeps: Some(choice.substeps),
        safe_met: choice.safe,
        safe,
    }
}
