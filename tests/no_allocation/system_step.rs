//! A step allocates nothing: every integrator, with constraints and colliders, and
//! the multi-threaded force path, counted by a global allocator over 1,000 steps
//! after a warm-up. The threaded path may push one job per `run` call into rayon's
//! global queue (it allocates a block every 63 pushes), never one per step.

use std::sync::atomic::Ordering;

use cloth_sandbox::scene::Scene;
use cloth_sandbox::sim::Integrator;

use crate::{ALLOCATIONS, one_at_a_time};

fn allocations_during(scene: &str, overrides: &[&str], steps: u64) -> usize {
    allocations_on(false, scene, overrides, steps)
}

/// Allocations of `steps` steps on the general engine, or on a fast engine when
/// `fast` (the first run, not counted, builds the engine). A window that counts
/// some is measured again, up to three times, and the fewest returned: the test
/// harness's own thread may allocate while a window runs, but a system that
/// allocates as it steps does so in every window.
fn allocations_on(fast: bool, scene: &str, overrides: &[&str], steps: u64) -> usize {
    allocations_of(built(scene, overrides, fast), steps)
}

fn built(scene: &str, overrides: &[&str], fast: bool) -> cloth_sandbox::sim::System {
    let mut scene = Scene::load(scene).unwrap();
    scene.set_all(overrides.iter().copied()).unwrap();
    let mut system = scene.build().unwrap();
    system.set_fast_path(fast);
    system
}

/// As [`allocations_on`], for a system already built.
fn allocations_of(mut system: cloth_sandbox::sim::System, steps: u64) -> usize {
    system.run(10).unwrap();
    let mut fewest = usize::MAX;
    for _ in 0..3 {
        let before = ALLOCATIONS.load(Ordering::SeqCst);
        system.run(steps).unwrap();
        fewest = fewest.min(ALLOCATIONS.load(Ordering::SeqCst) - before);
        if fewest == 0 {
            break;
        }
    }
    fewest
}

// One test function, taking its turn: the counter is global, and tests in one binary
// run in parallel.
#[test]
fn stepping_allocates_nothing() {
    let _turn = one_at_a_time();
    // The test harness's own threads allocate as a test starts: let that pass.
    allocations_during("chain", &[], 10);
    for integrator in Integrator::ALL {
        let name = format!("integrator=\"{}\"", integrator.name());
        let dt = if matches!(integrator, Integrator::ExplicitEuler | Integrator::Rk2) {
            "dt=5e-5"
        } else {
            "dt=0.001"
        };
        let n = allocations_during("cloth", &[&name, dt, "width=16", "height=16"], 1_000);
        assert_eq!(n, 0, "{integrator} allocated {n} times in 1,000 steps");
    }
    for scene in ["drape", "sheet", "rope", "jelly", "chain"] {
        let n = allocations_during(scene, &[], 1_000);
        assert_eq!(n, 0, "{scene} allocated {n} times in 1,000 steps");
    }
    // The general engine (the jelly with a stretch limit) and the lattice engine (the
    // jelly, with friction, in float64), on one thread and (16³ particles for the
    // general engine, kept off the lattice kernel; 28³ for the lattice engine) on the
    // machine's threads, which they enter once per chunk of 32 steps: rayon's queue
    // allocates a block every 63 entries.
    for (scene, overrides) in [
        ("rope", &[][..]),
        ("jelly", &[][..]),
        ("jelly", &["friction=0.3", "integrator=\"verlet\""][..]),
        ("jelly", &["stiffness=5000"][..]),
        ("chain", &[][..]),
        ("spring", &[][..]),
        (
            "jelly",
            &["integrator=\"verlet\"", "stretch_limit=0.01"][..],
        ),
    ] {
        let n = allocations_on(true, scene, overrides, 1_000);
        assert_eq!(
            n, 0,
            "{scene} {overrides:?} on a fast engine allocated {n} times in 1,000 steps"
        );
    }
    let mut general = built("jelly", &["width=16", "height=16", "depth=16"], true);
    general.refuse_lattice_kernel(true);
    let n = allocations_of(general, 1_000);
    assert!(
        n <= 1,
        "the threaded general engine allocated {n} times in 1,000 steps"
    );
    let n = allocations_on(true, "jelly", &["width=28", "height=28", "depth=28"], 1_000);
    assert!(
        n <= 1,
        "the threaded lattice engine allocated {n} times in 1,000 steps"
    );
    // Self-collision on the grid engine (the drape at its default size, and at
    // 64 x 64, where the pass runs on threads), falling onto its sphere while
    // its candidate list is rebuilt.
    for size in [&[][..], &["width=64", "height=64"][..]] {
        let n = allocations_on(true, "drape", size, 500);
        assert_eq!(
            n, 0,
            "the drape {size:?} on the grid engine allocated {n} times"
        );
    }
    // Big enough for the threaded force path.
    let n = allocations_during("bench", &["width=128", "height=128"], 200);
    assert!(
        n <= 1,
        "the threaded path allocated {n} times in one run of 200 steps"
    );
}
