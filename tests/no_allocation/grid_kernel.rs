//! The grid fast path allocates nothing while it steps (a counting global allocator).

use std::sync::atomic::Ordering;

use cloth_sandbox::sim::grid_kernel::{GridCloth, GridSpec};

use crate::{ALLOCATIONS, one_at_a_time};

/// The binary's tests take turns (`one_at_a_time`), so no other test thread
/// allocates while we count. The harness's own main thread may still allocate just
/// after the test starts (seen once in CI on a loaded machine: 4 allocations in the
/// first, 1 ms long, window), so a window that counts allocations is measured again,
/// up to three times: a kernel that allocates as it steps allocates in every window.
///
/// `steps(dt, n)` allocates nothing on one or two threads. `step()` called in a
/// loop on two threads enters the rayon pool once per call, and rayon's global job
/// queue (a crossbeam `Injector`) allocates one block per 63 entries: that is
/// rayon's, not the kernel's, so it is counted, printed and bounded, not zero.
#[test]
fn no_allocation_in_1000_steps() {
    let _turn = one_at_a_time();
    let dt = 1.0 / 960.0;
    for (n, threads) in [(32, 1), (128, 1), (128, 2), (256, 2)] {
        for wind in [false, true] {
            let mut cloth = GridCloth::new(GridSpec::peer_bench(n, wind));
            cloth.set_threads(threads);
            assert_eq!(cloth.is_parallel(), threads > 1);
            cloth.steps(dt, 200); // let the pool's threads start (their start allocates)
            let fewest = |cloth: &mut GridCloth, run: &dyn Fn(&mut GridCloth)| {
                let mut counts = Vec::new();
                for _ in 0..3 {
                    let before = ALLOCATIONS.load(Ordering::SeqCst);
                    run(cloth);
                    counts.push(ALLOCATIONS.load(Ordering::SeqCst) - before);
                    if counts.last() == Some(&0) {
                        break;
                    }
                }
                println!("N={n} threads={threads} wind={wind}: windows counted {counts:?}");
                counts.into_iter().min().unwrap()
            };
            let count = fewest(&mut cloth, &|c| c.steps(dt, 1000));
            assert_eq!(
                count, 0,
                "steps(dt, 1000): N={n} threads={threads} wind={wind}"
            );
            let count = fewest(&mut cloth, &|c| {
                for _ in 0..1000 {
                    c.step(dt);
                }
            });
            println!("1000 x step(): N={n} threads={threads} wind={wind}: {count} allocations");
            if threads == 1 {
                assert_eq!(count, 0, "step(): N={n} wind={wind}");
            } else {
                assert!(count <= 1000 / 63 + 2, "step(): N={n} wind={wind}: {count}");
            }
        }
    }
    // Self-collision, threaded from 48 x 48 on: a thickness of 2.3 spacings keeps
    // pairs in contact on every step and its list is rebuilt as the cloth swings
    // in the wind; after the warm-up its buffers have their size.
    for (n, threads) in [(32, 1), (64, 1), (64, 2), (128, 2)] {
        let mut spec = GridSpec::peer_bench(n, true);
        spec.self_collision = Some(2.3 * spec.spacing);
        spec.friction = 0.5;
        let mut cloth = GridCloth::new(spec);
        cloth.set_threads(threads);
        cloth.steps(dt, 200);
        let mut counts = Vec::new();
        for _ in 0..3 {
            let before = ALLOCATIONS.load(Ordering::SeqCst);
            cloth.steps(dt, 500);
            counts.push(ALLOCATIONS.load(Ordering::SeqCst) - before);
            if counts.last() == Some(&0) {
                break;
            }
        }
        println!(
            "self-collision N={n} threads={threads}: {} contacts, windows counted {counts:?}",
            cloth.self_collision_contacts()
        );
        assert!(cloth.self_collision_contacts() > 0);
        assert_eq!(counts.into_iter().min(), Some(0), "N={n} threads={threads}");
    }
}
