//! Work-precision: position error against run time for each integrator over a sweep
//! of steps `dt`, and the observed order of convergence (slope of `ln error` against
//! `ln dt`, least squares) beside the theoretical one.
//!
//! Error is the RMS over free particles of `|x - x_ref|` at the end time `T`; the
//! reference is the exact solution ([`super::analytic`]) or an RK4 run at a step at
//! least 64 times smaller than the smallest swept one, whose own error is estimated by
//! Richardson extrapolation, `|x_h - x_2h| / (2^4 - 1)`. Run time is the median of
//! several runs of [`System::run`], the code path of `cloth run`, timing the
//! simulation only (not building the system).

use std::time::Instant;

use glam::DVec3;

use super::analytic::HangingSpring;
use crate::scene::Resolved;
use crate::sim::{Integrator, System};

/// What a run is compared with.
#[derive(Clone, Debug)]
pub enum Reference {
    /// The exact solution of the hanging spring (particle 1; particle 0 is fixed).
    Analytic(HangingSpring),
    /// Positions from a fine RK4 run.
    Numerical(NumericalReference),
}

/// A fine RK4 reference run and its estimated error.
#[derive(Clone, Debug)]
pub struct NumericalReference {
    /// Positions at the end time, in m.
    pub positions: Vec<DVec3>,
    /// Its step, in s.
    pub dt: f64,
    /// Richardson estimate of its RMS position error, in m.
    pub error_estimate: f64,
    /// Wall time it took (both runs), in s.
    pub wall: f64,
}

/// One problem of the study.
#[derive(Clone, Debug)]
pub struct Problem {
    /// Short name (`spring`, `chain`, `cloth`).
    pub name: String,
    /// One line for the report.
    pub description: String,
    /// The scene, resolved; integrator and `dt` are replaced per run.
    pub scene: Resolved,
    /// End time in s (a whole number of every swept step).
    pub end_time: f64,
    /// Swept steps in s, largest first.
    pub dts: Vec<f64>,
    /// Size of the motion in m: a larger error means no accuracy is left.
    pub scale: f64,
    /// What runs are compared with.
    pub reference: Reference,
}

/// How a run ended.
#[derive(Clone, Debug, PartialEq)]
pub enum Outcome {
    /// Finished with an error below the problem's scale.
    Ok,
    /// The divergence check stopped it.
    Diverged {
        /// Simulated time in s.
        time: f64,
        /// The check's message.
        message: String,
    },
    /// Finished, but the error exceeds the size of the motion (an instability the
    /// divergence check did not catch).
    NoAccuracy,
}

/// One run of one integrator at one step.
#[derive(Clone, Debug)]
pub struct Point {
    /// Problem name.
    pub problem: String,
    /// Integrator.
    pub integrator: Integrator,
    /// Step in s.
    pub dt: f64,
    /// Steps taken per run.
    pub steps: u64,
    /// RMS position error over free particles at the end time, m.
    pub error_end: f64,
    /// Largest error of the free particle over all steps (analytic reference only), m.
    pub error_max: Option<f64>,
    /// Median run time, s.
    pub run_time: f64,
    /// Every run time, s.
    pub run_times: Vec<f64>,
    /// How it ended.
    pub outcome: Outcome,
}

/// Observed order of one integrator on one problem.
#[derive(Clone, Debug)]
pub struct OrderFit {
    /// Problem name.
    pub problem: String,
    /// Integrator.
    pub integrator: Integrator,
    /// Theoretical order.
    pub theory: u32,
    /// Least-squares slope of `ln error` against `ln dt` (None: fewer than 3 usable points).
    pub observed: Option<f64>,
    /// Points used.
    pub points: usize,
    /// Range of `dt` used, s.
    pub dt_range: (f64, f64),
}

/// Builds the system for `integrator` at step `dt`.
pub fn build(scene: &Resolved, integrator: Integrator, dt: f64) -> System {
    let mut scene = scene.clone();
    scene.params.integrator = integrator;
    scene.params.dt = dt;
    scene.build()
}

/// Steps to reach `end_time` with `dt` (rounded).
pub fn steps_for(end_time: f64, dt: f64) -> u64 {
    (end_time / dt).round() as u64
}

/// RMS over particles with `free[i]` of `|a - b|`.
pub fn rms_error(a: &[DVec3], b: &[DVec3], free: &[bool]) -> f64 {
    let (sum, n) = (a.iter().zip(b).zip(free))
        .filter(|(_, f)| **f)
        .fold((0.0, 0usize), |(s, n), ((a, b), _)| {
            (s + (*a - *b).length_squared(), n + 1)
        });
    if n == 0 { 0.0 } else { (sum / n as f64).sqrt() }
}

/// Free particles of a scene (not pinned).
pub fn free_particles(system: &System) -> Vec<bool> {
    (0..system.particle_count())
        .map(|i| !system.is_pinned(i))
        .collect()
}

/// The RK4 reference at `dt` and its Richardson error estimate from a second run at
/// `2 dt` (the two run in parallel). Errors if either diverges.
pub fn rk4_reference(
    scene: &Resolved,
    end_time: f64,
    dt: f64,
) -> Result<NumericalReference, String> {
    let start = Instant::now();
    let run = |h: f64| -> Result<(Vec<DVec3>, Vec<bool>), String> {
        let mut system = build(scene, Integrator::Rk4, h);
        system
            .run(steps_for(end_time, h))
            .map_err(|d| format!("the RK4 reference at dt = {h:e} diverged: {d}"))?;
        let free = free_particles(&system);
        Ok((system.positions().to_vec(), free))
    };
    let (fine, coarse) = rayon::join(|| run(dt), || run(2.0 * dt));
    let (fine, free) = fine?;
    let (coarse, _) = coarse?;
    let error_estimate = rms_error(&fine, &coarse, &free) / 15.0;
    Ok(NumericalReference {
        positions: fine,
        dt,
        error_estimate,
        wall: start.elapsed().as_secs_f64(),
    })
}

/// Median of `values` (0 when empty).
pub fn median(values: &[f64]) -> f64 {
    let mut v = values.to_vec();
    v.sort_by(f64::total_cmp);
    match v.len() {
        0 => 0.0,
        n if n % 2 == 1 => v[n / 2],
        n => 0.5 * (v[n / 2 - 1] + v[n / 2]),
    }
}

/// Runs `integrator` at `dt` on `problem`: `repeats` timed runs of `System::run`,
/// then the error against the reference.
pub fn measure(problem: &Problem, integrator: Integrator, dt: f64, repeats: usize) -> Point {
    let steps = steps_for(problem.end_time, dt);
    let mut run_times = Vec::with_capacity(repeats);
    let mut last = None;
    for _ in 0..repeats.max(1) {
        let mut system = build(&problem.scene, integrator, dt);
        let start = Instant::now();
        let outcome = system.run(steps);
        run_times.push(start.elapsed().as_secs_f64());
        last = Some((system, outcome));
    }
    let (system, outcome) = last.expect("at least one run");
    let free = free_particles(&system);
    let (error_end, error_max) = match &problem.reference {
        Reference::Numerical(r) => (rms_error(system.positions(), &r.positions, &free), None),
        Reference::Analytic(spring) => {
            let exact = |t: f64| DVec3::new(0.0, spring.height(t), 0.0);
            let end = rms_error(
                system.positions(),
                &[DVec3::ZERO, exact(steps as f64 * dt)],
                &free,
            );
            // Largest error over time, stepping one at a time (System::run is a loop of
            // System::step, so the trajectory is the same as the timed runs').
            let mut again = build(&problem.scene, integrator, dt);
            let mut worst: f64 = 0.0;
            for n in 1..=steps {
                if again.step().is_err() {
                    worst = f64::INFINITY;
                    break;
                }
                let e = (again.positions()[1] - exact(n as f64 * dt)).length();
                worst = worst.max(if e.is_finite() { e } else { f64::INFINITY });
            }
            (end, Some(worst))
        }
    };
    let outcome = match outcome {
        Err(d) => Outcome::Diverged {
            time: d.time(),
            message: d.to_string(),
        },
        Ok(()) if error_end.is_nan() || error_end > problem.scale => Outcome::NoAccuracy,
        Ok(()) => Outcome::Ok,
    };
    Point {
        problem: problem.name.clone(),
        integrator,
        dt,
        steps,
        error_end,
        error_max,
        run_time: median(&run_times),
        run_times,
        outcome,
    }
}

/// Least-squares slope of `ln y` against `ln x`.
pub fn loglog_slope(points: &[(f64, f64)]) -> Option<f64> {
    if points.len() < 2 {
        return None;
    }
    let n = points.len() as f64;
    let (sx, sy) = points
        .iter()
        .fold((0.0, 0.0), |(a, b), p| (a + p.0.ln(), b + p.1.ln()));
    let (mx, my) = (sx / n, sy / n);
    let (mut sxy, mut sxx) = (0.0, 0.0);
    for p in points {
        let (dx, dy) = (p.0.ln() - mx, p.1.ln() - my);
        sxy += dx * dy;
        sxx += dx * dx;
    }
    (sxx > 0.0).then(|| sxy / sxx)
}

/// Observed order from `points` of one integrator: the slope over runs that ended
/// [`Outcome::Ok`] with an error below `0.1 scale` (the asymptotic range) and above
/// `floor` (100 times the reference's own error estimate, and round-off). The error
/// is the largest over time where it was measured (the spring: a single particle's
/// error at one instant passes near zero as its phase drifts, which makes the end
/// error a noisy measure of the order), the RMS at the end time otherwise.
pub fn observed_order(
    problem: &str,
    integrator: Integrator,
    points: &[Point],
    scale: f64,
    floor: f64,
) -> OrderFit {
    let used: Vec<(f64, f64)> = (points.iter())
        .filter(|p| p.integrator == integrator && p.outcome == Outcome::Ok)
        .map(|p| (p.dt, p.error_max.unwrap_or(p.error_end)))
        .filter(|&(_, e)| e < 0.1 * scale && e > floor)
        .collect();
    let observed = if used.len() >= 3 {
        loglog_slope(&used)
    } else {
        None
    };
    let dt_range = used.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), p| {
        (lo.min(p.0), hi.max(p.0))
    });
    OrderFit {
        problem: problem.to_string(),
        integrator,
        theory: integrator.order(),
        observed,
        points: used.len(),
        dt_range,
    }
}

/// The error floor of a problem: 100 times its reference's error estimate, and
/// `1e-11` of its scale for round-off.
pub fn error_floor(problem: &Problem) -> f64 {
    let reference = match &problem.reference {
        Reference::Numerical(r) => r.error_estimate,
        Reference::Analytic(_) => 0.0,
    };
    (100.0 * reference).max(1e-11 * problem.scale)
}
