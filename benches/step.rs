//! Criterion benches of the grid fast path on the peers' benchmark scene
//! (shared/peers/scene.py): N = 32 ... 512, with and without wind, 1 and 2 threads.
//! One iteration is one 60 Hz frame of 16 steps (dt = 1/960 s); the reported
//! throughput in elements/s is steps/s. And safe stepping's estimate on a large
//! cloth, and the divergence checks' cost against the steps they watch.

// criterion_group! and criterion_main! generate undocumented items.
#![allow(missing_docs)]

use std::time::Duration;

use cloth_sandbox::scene::Scene;
use cloth_sandbox::sim::grid_kernel::{GridCloth, GridSpec};
use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};

const DT: f64 = 1.0 / 960.0;
const SUBSTEPS: usize = 16;

fn grid_step(c: &mut Criterion) {
    for wind in [false, true] {
        let mut group = c.benchmark_group(if wind { "grid_step_wind" } else { "grid_step" });
        group
            .warm_up_time(Duration::from_millis(300))
            .measurement_time(Duration::from_millis(1500))
            .sample_size(20)
            .throughput(Throughput::Elements(SUBSTEPS as u64));
        for n in [32, 64, 128, 256, 512] {
            for threads in [1, 2] {
                let mut cloth = GridCloth::new(GridSpec::peer_bench(n, wind));
                cloth.set_threads(threads);
                group.bench_function(BenchmarkId::new(format!("{threads}t"), n), |b| {
                    b.iter(|| cloth.steps(DT, SUBSTEPS))
                });
            }
        }
        group.finish();
    }
}

/// Safe stepping's substeps for a frame (the stability estimate: one pass over the
/// springs and the drag triangles) on the default cloth made 256 x 256, as the app
/// computes them when a slider moves.
fn safe_substeps(c: &mut Criterion) {
    let mut scene = Scene::load("cloth").unwrap();
    scene.set_all(["width=256", "height=256"]).unwrap();
    let system = scene.build().unwrap();
    c.bench_function("safe_substeps_256", |b| {
        b.iter(|| cloth_sandbox::sim::safe::safe_substeps(system.model(), 1.0 / 60.0, 0.5))
    });
}

/// The checks a run makes every `ENERGY_CHECK_STEPS` steps (runaways, the energy
/// budget, the limiters) against the steps between them, on the bench cloth at
/// 256 x 256: their share of a step is `check / (ENERGY_CHECK_STEPS * step)`.
fn checks(c: &mut Criterion) {
    use cloth_sandbox::sim::ENERGY_CHECK_STEPS;
    let mut scene = Scene::load("bench").unwrap();
    scene.set_all(["width=256", "height=256"]).unwrap();
    let mut system = scene.build().unwrap();
    // The engine `cloth run` and the app step it with.
    system.set_fast_path(true);
    system.run(64).unwrap();
    let mut group = c.benchmark_group("checks_256");
    group.sample_size(10);
    group.bench_function("check", |b| b.iter(|| system.check().unwrap()));
    group.throughput(Throughput::Elements(ENERGY_CHECK_STEPS));
    group.bench_function("steps_between_checks", |b| {
        b.iter(|| system.run(ENERGY_CHECK_STEPS).unwrap())
    });
    group.finish();
}

criterion_group!(benches, grid_step, safe_substeps, checks);
criterion_main!(benches);
