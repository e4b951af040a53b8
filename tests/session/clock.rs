//! The fixed-step clock: whole steps of dt from wall time, remainder carried over,
//! a cap per frame with the excess dropped (no spiral of death), and the physics
//! identical whatever the frame rate.

use cloth_sandbox::scene::Scene;
use cloth_sandbox::sim::Clock;

#[test]
fn steps_follow_wall_time_and_carry_the_remainder() {
    let mut clock = Clock::default();
    let dt = 0.01;
    let mut total = 0;
    for _ in 0..100 {
        let due = clock.advance(0.0166, 1.0, dt, 100);
        assert_eq!(due.dropped, 0.0);
        total += due.steps;
    }
    // 1.66 s of wall time is 166 steps, give or take the carried remainder.
    assert!((165..=166).contains(&total), "{total}");
}

#[test]
fn a_slow_frame_is_capped_and_the_excess_dropped() {
    let mut clock = Clock::default();
    let due = clock.advance(10.0, 1.0, 0.001, 50);
    assert_eq!(due.steps, 50);
    assert!((due.dropped - (10.0 - 0.05)).abs() < 1e-9);
    // Nothing piles up for the next frame.
    assert_eq!(clock.advance(0.0, 1.0, 0.001, 50).steps, 0);
}

#[test]
fn speed_scales_and_bad_numbers_run_nothing() {
    let mut clock = Clock::default();
    assert_eq!(clock.advance(0.1, 2.0, 0.01, 1000).steps, 20);
    assert_eq!(clock.advance(f64::NAN, 1.0, 0.01, 1000).steps, 0);
    assert_eq!(clock.advance(0.1, 1.0, 0.0, 1000).steps, 0);
}

#[test]
fn the_frame_rate_does_not_change_the_physics() {
    // 30 Hz and 144 Hz frames over the same wall time give the same steps and state.
    let run = |frame: f64| {
        let mut system = Scene::load("chain").unwrap().build().unwrap();
        let mut clock = Clock::default();
        let dt = system.params().dt;
        let mut wall = 0.0;
        while wall < 1.0 - 1e-9 {
            let due = clock.advance(frame, 1.0, dt, 10_000);
            system.run(due.steps as u64).unwrap();
            wall += frame;
        }
        system
    };
    let (slow, fast) = (run(1.0 / 30.0), run(1.0 / 144.0));
    let common = slow.steps_taken().min(fast.steps_taken());
    assert!(slow.steps_taken().abs_diff(fast.steps_taken()) <= 1);
    let mut a = Scene::load("chain").unwrap().build().unwrap();
    a.run(common).unwrap();
    let reference = if slow.steps_taken() == common {
        &slow
    } else {
        &fast
    };
    assert_eq!(a.positions(), reference.positions());
}

#[test]
fn slow_motion_runs_the_same_steps_slower() {
    use cloth_sandbox::session::Session;
    let load = || Session::load_with("spring", &[]).unwrap();
    let (mut full, mut slow) = (load(), load());
    slow.set_slow_motion(0.1);
    assert_eq!(slow.slow_motion(), 0.1);
    let dt = full.system().params().dt;
    for _ in 0..60 {
        full.frame(1.0 / 60.0);
        slow.frame(1.0 / 60.0);
    }
    // One wall second: the scene's speed of simulated time, and a tenth of it,
    // within a step.
    let speed = full.speed();
    assert!(
        (full.system().time() - speed).abs() <= dt + 1e-9,
        "{}",
        full.system().time()
    );
    assert!(
        (slow.system().time() - 0.1 * speed).abs() <= dt + 1e-9,
        "{}",
        slow.system().time()
    );
    // The same steps: ten times fewer of them, each the same dt.
    assert_eq!(slow.system().params().dt, dt);
    // Out-of-range factors are held to the range; NaN changes nothing.
    slow.set_slow_motion(0.0);
    assert_eq!(slow.slow_motion(), 0.05);
    slow.set_slow_motion(f64::NAN);
    assert_eq!(slow.slow_motion(), 0.05);
    slow.set_slow_motion(7.0);
    assert_eq!(slow.slow_motion(), 1.0);
}
