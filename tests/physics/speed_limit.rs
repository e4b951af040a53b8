//! The speed limit (`max_speed`, seed 000's `vLim`): after each step a particle
//! faster than the limit is slowed to it (`sim::constraints::speed_limit`).
//!
//! Checked against free fall, derived by hand: a cloth with no pins, no springs
//! stretched and no air falls at `g t` until it reaches the limit `v` at
//! `t1 = v / g`, then at `v`, so that it has fallen `v t1 / 2 + v (t - t1)` by
//! time `t > t1`. A step of `h` differs from that in two known ways: the start
//! is off by `O(h v)`, and since the limit is applied at the end of a step, each
//! step's move uses the velocity before it, up to `v + h g`: up to `h g (t - t1)`
//! more in all.

use crate::common::{build, max_distance};
use cloth_sandbox::sim::System;

/// The `cloth` scene let go in still air with no drag, with `overrides`.
fn falling(overrides: &[&str], fast: bool) -> System {
    let base = ["pins=none", "wind=0,0,0", "gust=0", "drag_coefficient=0"];
    let mut system = build("cloth", &[&base[..], overrides].concat());
    system.set_fast_path(fast);
    system
}

fn mean_y(system: &System) -> f64 {
    system.positions().iter().map(|p| p.y).sum::<f64>() / system.particle_count() as f64
}

fn fastest(system: &System) -> f64 {
    system
        .velocities()
        .iter()
        .map(|v| v.length())
        .fold(0.0, f64::max)
}

#[test]
fn a_falling_cloth_reaches_the_limit_and_falls_at_it() {
    let (limit, g, seconds) = (2.0, 9.81, 1.0);
    for integrator in ["symplectic-euler", "verlet"] {
        for fast in [true, false] {
            let integrator = format!("integrator={integrator}");
            let mut free = falling(&[&integrator], fast);
            let steps = (seconds / free.params().dt).round() as u64;
            let y0 = mean_y(&free);
            free.run(steps).unwrap();
            let mut limited = falling(&[&integrator, "max_speed=2"], fast);
            limited.run(steps).unwrap();
            let t = limited.time();
            let t1 = limit / g;
            let expected = limit * t1 / 2.0 + limit * (t - t1);
            let fallen = y0 - mean_y(&limited);
            let h = limited.params().dt;
            println!(
                "{integrator} fast {fast}: fell {fallen:.5} m, expected {expected:.5} m; \
                 fastest {:.6} m/s (free: {:.3} m/s)",
                fastest(&limited),
                fastest(&free)
            );
            assert!(fastest(&free) > 4.0 * limit);
            assert!(fastest(&limited) <= limit * (1.0 + 1e-6));
            let (below, above) = (2.0 * h * limit, 2.0 * h * limit + h * g * (t - t1));
            assert!(fallen > expected - below, "{integrator} {fast}");
            assert!(fallen < expected + above, "{integrator} {fast}");
        }
    }
}

#[test]
fn the_engines_agree_under_the_limit() {
    for integrator in ["symplectic-euler", "verlet"] {
        let integrator = format!("integrator={integrator}");
        let run = |fast: bool| {
            let mut system = falling(&[&integrator, "max_speed=2"], fast);
            system.run(960).unwrap();
            system
        };
        let (fast, exact) = (run(true), run(false));
        assert!(fast.engine().is_grid());
        let gap = max_distance(fast.positions(), exact.positions());
        println!("{integrator}: the engines differ by {gap:.2e} m");
        assert!(gap < 1e-5, "{gap}");
    }
}

#[test]
fn off_by_default_and_refused_out_of_range() {
    assert_eq!(build("cloth", &[]).params().max_speed, None);
    let mut scene = cloth_sandbox::scene::Scene::load("cloth").unwrap();
    let message = scene.set("max_speed", "-1").unwrap_err().to_string();
    assert!(message.contains("max_speed"), "{message}");
}
