//! Helpers shared by the integration tests: the analytic damped oscillator, derived
//! here from the equation of motion and independent of the simulator.

#![allow(dead_code)]

use cloth_sandbox::scene::Scene;
use cloth_sandbox::sim::{Engine, PrecisionRule, State, System};

/// A built-in scene with `key=value` overrides, built.
pub fn build(name: &str, overrides: &[&str]) -> System {
    let mut scene = Scene::load(name).unwrap();
    scene.set_all(overrides.iter().copied()).unwrap();
    scene.build().unwrap()
}

/// The largest distance (m) between corresponding points.
pub fn max_distance(a: &[glam::DVec3], b: &[glam::DVec3]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(p, q)| p.distance(*q))
        .fold(0.0, f64::max)
}

/// The `spring` scene's vertical oscillator: a mass `m` hanging from a fixed point on a
/// spring (k, L, b) under gravity g. With s the distance below the fixed point,
/// `m s'' = m g - k (s - L) - b s'`, so `u = s - s_eq` with `s_eq = L + m g / k`
/// obeys `u'' + 2 zeta w u' + w² u = 0`, `w = sqrt(k/m)`, `zeta = b / (2 sqrt(k m))`.
pub struct Oscillator {
    pub w: f64,
    pub zeta: f64,
    pub s_eq: f64,
    pub u0: f64,
}

impl Oscillator {
    /// From the spring scene's parameters, starting at rest at distance `s0`.
    pub fn new(m: f64, k: f64, b: f64, rest: f64, g: f64, s0: f64) -> Self {
        let w = (k / m).sqrt();
        let s_eq = rest + m * g / k;
        Self {
            w,
            zeta: b / (2.0 * (k * m).sqrt()),
            s_eq,
            u0: s0 - s_eq,
        }
    }

    /// Distance below the fixed point at time t (underdamped, starting at rest).
    pub fn distance(&self, t: f64) -> f64 {
        let wd = self.w * (1.0 - self.zeta * self.zeta).sqrt();
        let decay = (-self.zeta * self.w * t).exp();
        let u = self.u0 * decay * ((wd * t).cos() + self.zeta * self.w / wd * (wd * t).sin());
        self.s_eq + u
    }
}

/// The built-in spring scene with overrides, built.
pub fn spring_system(overrides: &[&str]) -> System {
    let mut scene = Scene::load("spring").expect("spring scene");
    scene
        .set_all(overrides.iter().copied())
        .expect("valid overrides");
    scene.build().expect("builds")
}

/// The analytic oscillator matching the spring scene's file values (m 0.5, k 15,
/// rest 5, 10% of critical damping, released 1 m below rest, g 9.81).
pub fn spring_oscillator(zeta: f64, g: f64) -> Oscillator {
    let (m, k): (f64, f64) = (0.5, 15.0);
    let b = zeta * 2.0 * (k * m).sqrt();
    Oscillator::new(m, k, b, 5.0, g, 6.0)
}

/// Largest |simulated - analytic| distance of the free mass over `duration` seconds.
pub fn max_spring_error(integrator: &str, dt: f64, duration: f64) -> f64 {
    let mut system = spring_system(&[&format!("integrator=\"{integrator}\""), &format!("dt={dt}")]);
    let exact = spring_oscillator(0.1, 9.81);
    let steps = (duration / dt).round() as u64;
    let mut worst: f64 = 0.0;
    for _ in 0..steps {
        system.step().expect("stable");
        let s = -system.positions()[1].y;
        worst = worst.max((s - exact.distance(system.time())).abs());
    }
    worst
}

/// `state` with every particle moved `factor` times as far from their centroid,
/// at rest.
fn spread(state: &State, factor: f64) -> State {
    let mut spread = state.clone();
    let n = spread.positions.len() as f64;
    let centre = spread.positions.iter().sum::<glam::DVec3>() / n;
    for (p, v) in spread.positions.iter_mut().zip(&mut spread.velocities) {
        *p = centre + factor * (*p - centre);
        *v = glam::DVec3::ZERO;
    }
    spread
}

/// What [`spread_and_back`] saw: the engine and its precision rule while the body
/// was spread, how far (m) it was then from the f64 engine, and the engine and
/// rule once put back.
#[derive(Debug)]
pub struct SpreadRun {
    pub spread: (Engine, PrecisionRule),
    pub apart: f64,
    pub back: (Engine, PrecisionRule),
}

/// Spreads `system` (allowed the fast engines) to `factor` times its size about
/// its centroid, at rest, and runs it `steps` steps beside a copy on the f64
/// engine; then puts it back as it was and runs it `steps` more.
pub fn spread_and_back(system: &mut System, factor: f64, steps: u64) -> SpreadRun {
    let start = system.state().clone();
    system.set_state(spread(&start, factor));
    let mut exact = system.clone();
    exact.set_fast_path(false);
    system.run(steps).unwrap();
    exact.run(steps).unwrap();
    let spread = (system.engine(), system.precision_rule().unwrap());
    let apart = max_distance(system.positions(), exact.positions());
    system.set_state(start);
    system.run(steps).unwrap();
    let back = (system.engine(), system.precision_rule().unwrap());
    SpreadRun {
        spread,
        apart,
        back,
    }
}
