//! Provot's stretch limit on a heavily loaded cloth: the peers' `bench` cloth (1 kg
//! hanging from its two top corners on springs of k / m = 5000 s⁻²) with a 10%
//! limit. Its springs alone would stretch far past the limit, so the single
//! Gauss-Seidel pass works on most springs every step.
//!
//! Visited in particle order, that pass let a checkerboard mode near the pins grow
//! until the cloth diverged (at step 512 of the 48 x 48 cloth, at 160 to 192 at
//! 128 x 128, on both engines; an independent NumPy reproduction of the pass on a
//! structural grid diverged the same way). Visited by colour classes
//! (`springs::constraint_order`) it stays bounded.

use crate::common::{build, max_distance};
use cloth_sandbox::sim::System;

/// The bench cloth at `n x n` with a 10% stretch limit, on the fast engine or not.
fn loaded(n: usize, fast: bool) -> System {
    let mut system = build(
        "bench",
        &[
            &format!("width={n}"),
            &format!("height={n}"),
            "stretch_limit=0.1",
        ],
    );
    system.set_fast_path(fast);
    system
}

fn max_speed(system: &System) -> f64 {
    system
        .velocities()
        .iter()
        .map(|v| v.length())
        .fold(0.0, f64::max)
}

/// The largest strain `l / L - 1` among the structural springs (rest length = the
/// smallest rest length).
fn max_structural_strain(system: &System) -> f64 {
    let model = system.model();
    let shortest = model
        .springs
        .iter()
        .map(|s| s.rest)
        .fold(f64::MAX, f64::min);
    let x = system.positions();
    model
        .springs
        .iter()
        .filter(|s| s.rest < 1.01 * shortest)
        .map(|s| x[s.a as usize].distance(x[s.b as usize]) / s.rest - 1.0)
        .fold(0.0, f64::max)
}

#[test]
fn a_heavily_loaded_cloth_with_a_stretch_limit_stays_bounded_on_both_engines() {
    // Three simulated seconds. Bound on the speed: falling 5 m (five times the
    // cloth's size) gives sqrt(2 g 5 m) = 9.9 m/s; the cloth hangs from its corners
    // and cannot fall that far. The divergence in particle order passed 1e5 m/s.
    for n in [48, 96] {
        for fast in [true, false] {
            let mut system = loaded(n, fast);
            system
                .run(2880)
                .unwrap_or_else(|e| panic!("{n} x {n}, fast {fast}: {e}"));
            let speed = max_speed(&system);
            assert!(speed < 9.9, "{n} x {n}, fast {fast}: {speed} m/s");
        }
    }
}

#[test]
fn the_limit_holds_the_cloth_that_its_springs_alone_let_sag() {
    // Without the limit the weak springs stretch the cloth near its pins by far
    // more than 10%; with it the worst structural spring is held near the limit.
    let mut free = build("bench", &["width=48", "height=48"]);
    free.run(960).unwrap();
    let mut limited = loaded(48, true);
    limited.run(960).unwrap();
    let (sag, held) = (
        max_structural_strain(&free),
        max_structural_strain(&limited),
    );
    println!("largest structural strain after 1 s: {sag:.3} free, {held:.3} limited");
    assert!(sag > 1.0, "{sag}");
    assert!(held < 0.5, "{held}");
}

#[test]
fn the_fast_engine_agrees_with_the_f64_engine_under_the_limit() {
    // Same passes in the same colour order; the grid engine's float32 forces
    // (its precision is chosen for 1% of gravity) part from the f64 engine's by
    // round-off, which the constraints do not amplify over a quarter second. The
    // 48 x 160 cloth is tall enough for the grid engine to run its pass in bands
    // of rows (64 rows at 48 columns), each band's sweeps before the next band's,
    // on one thread or on each of two: an order that let a later sweep's line run
    // before an earlier sweep's line it shares a particle with would part the
    // engines by far more than round-off.
    for (w, h) in [(48, 48), (48, 160)] {
        let loaded = |fast: bool| {
            let (width, height) = (format!("width={w}"), format!("height={h}"));
            let mut system = build("bench", &[&width, &height, "stretch_limit=0.1"]);
            system.set_fast_path(fast);
            system
        };
        let (mut fast, mut exact) = (loaded(true), loaded(false));
        let start = exact.positions().to_vec();
        fast.run(240).unwrap();
        exact.run(240).unwrap();
        let apart = max_distance(fast.positions(), exact.positions());
        let moved = max_distance(&start, exact.positions());
        println!("{w} x {h}: apart {apart:e} m, moved {moved:e} m");
        assert!(moved > 0.01, "{w} x {h}: {moved}");
        assert!(apart < 2e-6, "{w} x {h}: {apart}");
    }
}

#[test]
fn far_from_the_origin_the_limit_still_sees_every_spring_over_it() {
    // 1 km out, float32 positions resolve only 6e-5 m, so the engine keeps
    // fixed-point ones (`grid-mixed`) in a frame on the cloth, whose differences
    // are exact: a spring barely over the limit is seen over it, and the cloth
    // keeps as close to the f64 engine's as near the origin.
    let far = |fast: bool| {
        let mut system = build(
            "bench",
            &[
                "width=48",
                "height=48",
                "stretch_limit=0.1",
                "origin=1000,1001,1000",
            ],
        );
        system.set_fast_path(fast);
        system
    };
    let (mut fast, mut exact) = (far(true), far(false));
    assert_eq!(fast.engine().name(), "grid-mixed");
    fast.run(240).unwrap();
    exact.run(240).unwrap();
    let apart = max_distance(fast.positions(), exact.positions());
    println!("apart {apart:e} m");
    assert!(apart < 2e-6, "{apart}");
}

#[test]
fn along_rows_of_more_than_64_blocks_both_colours_keep_the_f64_engines_order() {
    // The fast engine corrects a row's springs along it in both colour classes
    // at once, measured in chunks of up to 64 blocks of lanes (512 columns at 8
    // lanes: AVX2's float32), a colour-1 spring only where a spring near it was
    // over the limit. On this strip of the widest cloth a scene takes, hanging
    // from its top corners and either side of its middle, the springs along the
    // rows carry the load: a colour-1 spring left uncorrected (or corrected
    // before a colour-0 one it shares a particle with) would part the engines by
    // far more than round-off, as in the test above (leaving out the colour 1
    // of the block where the chunks meet parted them by 4e-3 m).
    let strip = |fast: bool, limit: bool| {
        let mut system = build(
            "bench",
            &[
                "width=1024",
                "height=4",
                // Hung also from either side of column 512, where the chunks meet.
                "pins=[0, 508, 516, 1023]",
                if limit {
                    "stretch_limit=0.1"
                } else {
                    "stretch_limit=100"
                },
            ],
        );
        system.set_fast_path(fast);
        system
    };
    let (mut fast, mut exact, mut free) =
        (strip(true, true), strip(false, true), strip(true, false));
    fast.run(240).unwrap();
    exact.run(240).unwrap();
    free.run(240).unwrap();
    let apart = max_distance(fast.positions(), exact.positions());
    let held = max_distance(free.positions(), exact.positions());
    let (sag, strain) = (max_structural_strain(&free), max_structural_strain(&exact));
    println!(
        "apart {apart:e} m; the limit moved the strip {held:e} m; strain {sag:.3} free, {strain:.3} limited"
    );
    assert!(sag > 0.2 && held > 0.01, "{sag} {held}");
    assert!(apart < 2e-6, "{apart}");
}
