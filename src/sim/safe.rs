//! Safe stepping: the number of substeps `n` that splits a frame of `T` seconds into
//! steps `h = T / n <= safety * dt_crit`, where `dt_crit` is the integrator's critical
//! step on the Gershgorin bound of the highest angular frequency (see
//! [`super::stability`]): `omega_max <= sqrt(max_i (2 sum_j k_j + k_c) / m_i)`.
//!
//! The bound holds for springs at or beyond their rest length (each spring's
//! linearised stiffness block then has eigenvalues between 0 and `k`), so a step
//! below it is stable for the linear part of the model whatever k, b or mass the
//! user picks. A strongly compressed spring adds a transverse term
//! `k (1 - L/l) < 0` (buckling) that the bound does not cover: that is why the app
//! scales the whole cloth when the user changes its rest length (see
//! [`super::System::rescale`]).
//!
//! It costs one pass over the springs and a bisection on a 2x2 amplification
//! matrix: cheap enough to call whenever a slider moves.

use super::{Model, System, stability};

/// Default fraction of the critical step that safe stepping keeps below.
pub const DEFAULT_SAFETY: f64 = 0.5;
/// Default cap on substeps per frame, so that one frame cannot take unbounded time.
pub const DEFAULT_MAX_SUBSTEPS: u32 = 100_000;

/// What safe stepping chose for one frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SafeStep {
    /// Substeps per frame (at least 1).
    pub substeps: u32,
    /// The step that results, `frame_time / substeps`, in s.
    pub dt: f64,
    /// Critical step of the integrator on the Gershgorin bound, in s: `Some(inf)` for
    /// no limit (implicit Euler, or nothing oscillates), `None` when no step is stable
    /// (explicit Euler or RK2 without enough damping).
    pub dt_critical: Option<f64>,
    /// Whether the step meets `dt <= safety * dt_critical`. False when no step is
    /// stable or when `max_substeps` was not enough.
    pub safe: bool,
}

/// Substeps for a frame of `frame_time` seconds so that each step stays below
/// `safety` (in (0, 1]) times the critical step of `model.params.integrator`, capped
/// at `max_substeps`. Ignores `model.params.dt`.
pub fn safe_step(model: &Model, frame_time: f64, safety: f64, max_substeps: u32) -> SafeStep {
    let dt_critical = stability::estimate(model).dt_critical;
    safe_step_below(dt_critical, frame_time, safety, max_substeps)
}

/// [`safe_step`] for a critical step `dt_critical` given (as [`SafeStep::dt_critical`]
/// reads): a running system's, whose drag areas may have outgrown its rest ones
/// ([`stability::dt_critical_at`]).
pub fn safe_step_below(
    dt_critical: Option<f64>,
    frame_time: f64,
    safety: f64,
    max_substeps: u32,
) -> SafeStep {
    let max_substeps = max_substeps.max(1);
    let safety = if safety.is_finite() && safety > 0.0 {
        safety.min(1.0)
    } else {
        DEFAULT_SAFETY
    };
    if !(frame_time.is_finite() && frame_time > 0.0) {
        return SafeStep {
            substeps: 1,
            dt: frame_time,
            dt_critical,
            safe: false,
        };
    }
    let (substeps, safe) = match dt_critical {
        Some(c) if c.is_infinite() => (1, true),
        Some(c) => {
            let wanted = (frame_time / (safety * c)).ceil();
            if wanted <= max_substeps as f64 {
                ((wanted as u32).max(1), true)
            } else {
                (max_substeps, false)
            }
        }
        None => (max_substeps, false),
    };
    SafeStep {
        substeps,
        dt: frame_time / substeps as f64,
        dt_critical,
        safe,
    }
}

/// How far the step safe stepping chose may come towards the critical step of a
/// running system, as a multiple of the safety fraction, before it chooses again:
/// a step of `DEFAULT_SAFETY` (half the critical step) is chosen again once the
/// critical step has shrunk by a third (the drag areas grew), so that it runs at
/// most at three quarters of it.
pub const RECHOOSE_ABOVE: f64 = 1.5;
/// The same the other way: a step that safe stepping cut below the frame's own
/// step is chosen again once it has stayed under half the safety fraction of the
/// critical step for [`ROOMY_FOR`] (the areas shrank back), so that the run speeds
/// up again, but not at every flap of a cloth in the wind.
pub const RECHOOSE_BELOW: f64 = 0.5;
/// Simulated seconds a cut step must have had room at every check before it
/// is chosen again ([`RECHOOSE_BELOW`]).
pub const ROOMY_FOR: f64 = 1.0;

/// Safe stepping's watch over a running system's step: whether to choose it again
/// as the drag's areas grow and shrink ([`stability::dt_critical_at`]). The app
/// (every frame) and `cloth run --safe` (every 1/60 s simulated) follow it.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StepWatch {
    /// Simulated time since which a cut step has had room at every check.
    roomy_since: Option<f64>,
}

impl StepWatch {
    /// Whether to choose the step again at simulated time `time`: the step `dt`
    /// chosen under `safety` is over [`RECHOOSE_ABOVE`] times `safety` of the
    /// critical step now, `dt_critical`; or it was cut below the scene's own step
    /// `scene_dt` and has been under [`RECHOOSE_BELOW`] times that for
    /// [`ROOMY_FOR`].
    pub fn outgrown(
        &mut self,
        time: f64,
        (dt, scene_dt): (f64, f64),
        dt_critical: Option<f64>,
        safety: f64,
    ) -> bool {
        let cut = dt < scene_dt * (1.0 - 1e-12);
        let critical = dt_critical.filter(|c| c.is_finite() && *c > 0.0);
        let Some(critical) = critical else {
            self.roomy_since = None;
            return false;
        };
        if dt > RECHOOSE_ABOVE * safety * critical {
            self.roomy_since = None;
            return true;
        }
        if !(cut && dt < RECHOOSE_BELOW * safety * critical) {
            self.roomy_since = None;
            return false;
        }
        let since = *self.roomy_since.get_or_insert(time);
        let roomy = time - since >= ROOMY_FOR;
        if roomy {
            self.roomy_since = None;
        }
        roomy
    }
}

/// Safe stepping's watch kept on a running `system` whose step splits the scene's
/// own step, `scene_dt` (`cloth run --safe`, recordings; the app's session chooses
/// its own, with the stretch limit it may add): after a frame's steps, where
/// `watch` says the drag's areas have outgrown the step, sets the step safe
/// stepping chooses now ([`safe_step_below`] on [`System::dt_critical_now`]:
/// `scene_dt` split into the fewest substeps below `DEFAULT_SAFETY` of it, never
/// a step longer than `scene_dt`) and returns that choice.
pub fn follow_areas(system: &mut System, watch: &mut StepWatch, scene_dt: f64) -> Option<SafeStep> {
    let dt = system.params().dt;
    let now = system.dt_critical_now();
    if !watch.outgrown(system.time(), (dt, scene_dt), now, DEFAULT_SAFETY) {
        return None;
    }
    let choice = safe_step_below(now, scene_dt, DEFAULT_SAFETY, DEFAULT_MAX_SUBSTEPS);
    let mut params = *system.params();
    params.dt = choice.dt;
    system.set_params(params);
    Some(choice)
}

/// Stretch limit (Provot's tau) that safe stepping adds to a cloth with aero drag,
/// no limit of its own, and a wind strong for its springs (see [`wind_load_ratio`]).
/// Drag grows with a triangle's stretched area (as L²) and a spring only as k L, so
/// a soft enough cloth in a strong wind has no equilibrium and stretches without
/// bound; the limit stops that.
pub const SAFE_STRETCH_LIMIT: f64 = 0.5;

/// Wind load ratio above which safe stepping adds [`SAFE_STRETCH_LIMIT`]. Measured
/// on 10x10 and 16x16 cloths in the panel's strongest wind (35 m/s plus 10 m/s
/// gusts): ratios up to 2 stayed bounded, 6 and more ran away.
pub const WIND_LOAD_NEEDING_A_LIMIT: f64 = 0.5;

/// Drag on one particle's rest area in the strongest wind, `1/2 rho C_d (|wind| +
/// gust)² L²`, as a fraction of the force `k L` that stretches a spring to twice its
/// rest length, for the spring with the smallest `k L` (a grid's structural ones).
/// The default cloth: 0.003. Infinite when no spring holds anything.
pub fn wind_load_ratio(model: &Model) -> f64 {
    // The weakest spring's `k L` and `L`.
    let mut weakest: Option<(f64, f64)> = None;
    for s in model.springs.iter().filter(|s| s.rest > 0.0) {
        let capacity = model.material(s.kind).stiffness * s.rest;
        if weakest.is_none_or(|(least, _)| capacity.total_cmp(&least).is_lt()) {
            weakest = Some((capacity, s.rest));
        }
    }
    let Some((capacity, l)) = weakest else {
        return f64::INFINITY;
    };
    let p = &model.params;
    let wind = p.wind.length() + p.gust;
    let drag = 0.5 * p.air_density * p.drag_coefficient * wind * wind * l * l;
    if capacity > 0.0 {
        drag / capacity
    } else {
        f64::INFINITY
    }
}

/// The stretch limit safe stepping adds to `model`, whose own limit is `own`:
/// [`SAFE_STRETCH_LIMIT`] when it has none, aero drag runs and the wind load ratio
/// passes [`WIND_LOAD_NEEDING_A_LIMIT`]; otherwise none. The app and `cloth run
/// --safe` both follow this rule.
pub fn added_stretch_limit(model: &Model, own: Option<f64>) -> Option<f64> {
    let needed =
        own.is_none() && model.terms.aero && wind_load_ratio(model) > WIND_LOAD_NEEDING_A_LIMIT;
    needed.then_some(SAFE_STRETCH_LIMIT)
}

/// Substeps per frame of `frame_time` seconds for the model's integrator, keeping the
/// step below `safety * dt_crit` (capped at [`DEFAULT_MAX_SUBSTEPS`]).
pub fn safe_substeps(model: &Model, frame_time: f64, safety: f64) -> u32 {
    safe_step(model, frame_time, safety, DEFAULT_MAX_SUBSTEPS).substeps
}
