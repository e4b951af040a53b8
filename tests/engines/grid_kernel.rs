//! The grid fast path against the peers' float64 reference (shared/peers/scene.py).

use cloth_sandbox::sim::grid_kernel::{GridCloth, GridSpec, Precision, SimdLevel};
use glam::DVec3;

const DT: f64 = 1.0 / 960.0;

/// Mean y of all particles and y of the bottom-middle particle.
fn metrics(cloth: &GridCloth, n: usize) -> (f64, f64) {
    let mut p = vec![DVec3::ZERO; cloth.len()];
    cloth.positions_into(&mut p);
    let mean = p.iter().map(|q| q.y).sum::<f64>() / p.len() as f64;
    (mean, p[(n - 1) * n + n / 2].y)
}

fn run(n: usize, wind: bool, threads: usize, steps: usize) -> GridCloth {
    let mut cloth = GridCloth::new(GridSpec::peer_bench(n, wind));
    cloth.set_threads(threads);
    cloth.steps(DT, steps);
    cloth
}

/// NumPy float64 reference after 960 steps at N = 32 (shared/peers/README.md §2).
fn check_reference(wind: bool, mean_ref: f64, bottom_ref: f64) {
    let cloth = run(32, wind, 1, 960);
    let (mean, bottom) = metrics(&cloth, 32);
    println!(
        "wind={wind} simd={:?}: mean y {mean:.9} ({:+.2e}), bottom-middle y {bottom:.9} ({:+.2e})",
        cloth.simd_level(),
        mean - mean_ref,
        bottom - bottom_ref
    );
    assert!(
        (mean - mean_ref).abs() < 5e-6,
        "mean y {mean} vs {mean_ref}"
    );
    assert!(
        (bottom - bottom_ref).abs() < 5e-6,
        "bottom y {bottom} vs {bottom_ref}"
    );
}

#[test]
fn peer_scene_n32_matches_float64_reference() {
    let (wind, mean, bottom) = REFERENCE[0];
    check_reference(wind, mean, bottom);
}

#[test]
fn peer_scene_n32_wind_matches_float64_reference() {
    let (wind, mean, bottom) = REFERENCE[1];
    check_reference(wind, mean, bottom);
}

/// The NumPy float64 reference after 960 steps at N = 32: `(wind, mean y,
/// bottom-middle y)` (shared/peers/README.md §2).
const REFERENCE: [(bool, f64, f64); 2] = [
    (false, -0.064685755, -0.656037594),
    (true, 0.528073639, 0.193166128),
];

/// Every compiled SIMD level this CPU has gives the reference values too: in
/// float32 within 5e-6 m; in float64 to the reference's printed 9 decimals (half
/// a unit of the last, 5e-10 m, plus the float64 round-off of two codes summing
/// the same forces in other orders: bound 1e-9 m), the levels agreeing with each
/// other to float64 round-off (bound 1e-12 m).
#[test]
fn every_simd_level_matches_reference() {
    for (precision, bound) in [(Precision::Single, 5e-6), (Precision::Double, 1e-9)] {
        for (wind, mean_ref, bottom_ref) in REFERENCE {
            let mut portable = Vec::new();
            for level in [SimdLevel::Baseline, SimdLevel::Avx2, SimdLevel::Avx512] {
                let mut spec = GridSpec::peer_bench(32, wind);
                spec.precision = precision;
                let mut cloth = GridCloth::new(spec);
                cloth.set_simd_level(level);
                cloth.steps(DT, 960);
                let (mean, bottom) = metrics(&cloth, 32);
                let mut x = vec![DVec3::ZERO; cloth.len()];
                cloth.positions_into(&mut x);
                if level == SimdLevel::Baseline {
                    portable = x.clone();
                }
                let apart = apart(&x, &portable);
                let ran = cloth.simd_level();
                println!(
                    "{precision:?} {ran:?} wind={wind}: mean y {:+.2e}, bottom-middle y {:+.2e} from float64; {apart:e} m from the portable lanes",
                    mean - mean_ref,
                    bottom - bottom_ref
                );
                assert!(
                    (mean - mean_ref).abs() < bound && (bottom - bottom_ref).abs() < bound,
                    "{precision:?} {ran:?} wind={wind}: {mean} {bottom}"
                );
                if precision == Precision::Double {
                    assert!(apart < 1e-12, "{ran:?} wind={wind}: {apart:e} m");
                }
            }
        }
    }
}

/// Band splitting changes nothing: the gather order per particle is fixed, so two
/// and three threads give bit-identical states to one thread (tolerance 0).
#[test]
fn threads_give_bit_identical_results() {
    for wind in [false, true] {
        let one = run(128, wind, 1, 200);
        for threads in [2, 3] {
            let many = run(128, wind, threads, 200);
            for a in 0..3 {
                assert_eq!(
                    one.raw_positions()[a],
                    many.raw_positions()[a],
                    "x, {threads} threads"
                );
                assert_eq!(
                    one.raw_velocities()[a],
                    many.raw_velocities()[a],
                    "v, {threads} threads"
                );
            }
        }
    }
}

/// Non-square grids, thin grids and a single particle stay finite.
#[test]
fn odd_shapes_stay_finite() {
    for (w, h) in [(1, 1), (1, 5), (5, 1), (2, 2), (3, 97), (97, 3), (130, 129)] {
        let mut spec = GridSpec::peer_bench(w.max(h), true);
        spec.width = w;
        spec.height = h;
        spec.pinned = vec![0];
        let mut cloth = GridCloth::new(spec);
        cloth.set_threads(2);
        for _ in 0..100 {
            cloth.step(DT);
            for a in cloth.raw_positions() {
                assert!(a.iter().all(|q| q.is_finite()), "{w}x{h}");
            }
        }
    }
}

/// Coincident particles (zero-length springs, zero-area triangles) give no force
/// and no NaN.
#[test]
fn coincident_particles_stay_finite() {
    let mut cloth = GridCloth::new(GridSpec::peer_bench(16, true));
    let n = cloth.len();
    cloth.set_state(&vec![DVec3::new(0.5, 0.5, 0.0); n], &[]);
    for _ in 0..200 {
        cloth.step(DT);
        for a in cloth.raw_positions() {
            assert!(a.iter().all(|q| q.is_finite()));
        }
    }
}

/// The same with every feature of the engine on, in each precision: Verlet (and
/// XPBD, whose spring pass splits its colour classes among the threads), air
/// damping, a ground, a sphere, the stretch limit, friction (without a stretch
/// limit the contact is resolved on each band's rows inside the step's hand-over)
/// and gusty drag (tolerance 0). At 96 x 96 the threads hand over work with
/// `rayon::join`; from 128 x 128 on, the step's second band and the stretch
/// limit's second half are handed over by spinning.
#[test]
fn threads_give_bit_identical_results_with_every_feature() {
    use cloth_sandbox::sim::grid_kernel::Precision;
    use cloth_sandbox::sim::{Ground, Integrator, Sphere, Wind};
    let wind = Wind::new(DVec3::new(0.0, 0.0, 5.0), 2.0, 7);
    let cases = [Precision::Single, Precision::Mixed, Precision::Double]
        .map(|p| (p, Integrator::Verlet))
        .into_iter()
        .chain([(Precision::Single, Integrator::Xpbd)]);
    for (precision, integrator) in cases {
        for (n, stretch_limit, friction) in [96, 128]
            .into_iter()
            .flat_map(|n| [(n, None, 0.0), (n, Some(0.2), 0.0), (n, None, 0.5)])
        {
            let state = |threads: usize| {
                let mut spec = GridSpec::peer_bench(n, true);
                spec.integrator = integrator;
                spec.air_damping = 1e-5;
                // The bottom row sags into the ground, the wind blows the cloth
                // into the sphere.
                spec.ground = Some(Ground {
                    height: -0.05,
                    stiffness: 50.0,
                    damping: 0.01,
                    friction,
                });
                spec.friction = friction;
                spec.sphere = Some(Sphere {
                    center: DVec3::new(0.5, 0.3, 0.22),
                    radius: 0.2,
                });
                spec.stretch_limit = stretch_limit;
                spec.precision = precision;
                let mut cloth = GridCloth::new(spec);
                cloth.set_threads(threads);
                cloth.steps_in_wind(DT, 150, 0.0, &wind);
                let mut x = vec![DVec3::ZERO; cloth.len()];
                cloth.positions_into(&mut x);
                let mut v = x.clone();
                cloth.velocities_into(&mut v);
                (x, v, cloth.is_parallel())
            };
            let (one, two) = (state(1), state(2));
            assert!(two.2, "the {n} x {n} cloth should run on two threads");
            let finite = |s: &[DVec3]| s.iter().all(|p| p.is_finite());
            // The colliders were reached: particles on the sphere and below the ground.
            let center = DVec3::new(0.5, 0.3, 0.22);
            let on_sphere = one
                .0
                .iter()
                .filter(|p| p.distance(center) < 0.2 + 1e-3)
                .count();
            let below = one.0.iter().filter(|p| p.y < -0.05).count();
            assert!(
                on_sphere > 0 && below > 0,
                "{on_sphere} on the sphere, {below} below"
            );
            assert!(
                finite(&one.0) && finite(&one.1),
                "{n}: {precision:?} {integrator} {stretch_limit:?} {friction}"
            );
            assert!(
                one.0 == two.0 && one.1 == two.1,
                "{n}: {precision:?} {integrator} {stretch_limit:?} {friction}"
            );
        }
    }
}

/// The stretch limit's pass at every SIMD level this CPU has, in each precision,
/// against the portable lanes: the bench cloth (45 wide, so rows end inside a block)
/// with a 10% limit under Verlet, whose weak springs put most springs over the limit
/// every step (tests/stretch_limit.rs). The levels' steps differ by the round-off of
/// their fused multiply-adds and float32 reciprocal square roots: without the limit
/// they part by 6e-7 m in float32 after these 240 steps, with it by 1.6e-6 m (both
/// measured with AVX2 on 2026-11-24). Bound: 1e-5 m. A lane given the wrong spring
/// moves particles by millimetres (8.6e-3 m when the AVX-512 lanes ignored the
/// colour classes along rows).
/// The positions of the cloth of `spec` after `steps` steps at `level`, and the
/// level that ran (the best this CPU has, at most `level`).
fn stepped(spec: GridSpec, level: SimdLevel, steps: usize) -> (Vec<DVec3>, SimdLevel) {
    let mut cloth = GridCloth::new(spec);
    cloth.set_simd_level(level);
    cloth.steps(DT, steps);
    let mut x = vec![DVec3::ZERO; cloth.len()];
    cloth.positions_into(&mut x);
    (x, cloth.simd_level())
}

/// The largest distance between the particles of two cloths.
fn apart(x: &[DVec3], y: &[DVec3]) -> f64 {
    let d = x.iter().zip(y).map(|(a, b)| a.distance(*b));
    d.fold(0.0, f64::max)
}

/// The passes along the springs after the step, Provot's stretch limit (with
/// Verlet) and XPBD's springs, give the same cloth on every SIMD level within
/// float32 round-off, in each precision; and each precision's cloth is the float64
/// one's within what float32 rounds off over the run. Fixed-point positions are
/// checked 300 m from the origin, where they are needed: their exact differences
/// in both passes are what keep the cloth there, and in the wind, the drag's
/// (its triangles' edges are the springs' vectors, accurate to their own size).
#[test]
fn every_simd_level_runs_the_spring_passes_alike() {
    use cloth_sandbox::sim::Integrator;
    use cloth_sandbox::sim::grid_kernel::Precision;
    type Setting = fn(&mut GridSpec);
    let passes: [(&str, Setting); 2] = [
        ("stretch limit", |spec| {
            spec.integrator = Integrator::Verlet;
            spec.stretch_limit = Some(0.1);
        }),
        ("XPBD", |spec| spec.integrator = Integrator::Xpbd),
    ];
    for (pass, set) in passes {
        let state = |precision: Precision, x0: f64, level: SimdLevel| {
            let mut spec = GridSpec::peer_bench(45, true);
            set(&mut spec);
            spec.precision = precision;
            spec.origin[0] = x0;
            stepped(spec, level, 240)
        };
        // Float32 positions round each move to 2^-24 of the 1 m cloth's
        // coordinates; fixed-point ones to half their unit (4e-9 m), and leave the
        // float32 arithmetic's 2^-24 of each correction.
        for (precision, x0, bound) in [
            (Precision::Single, 0.0, 1e-5),
            (Precision::Mixed, 300.0, 1e-6),
            (Precision::Double, 300.0, 0.0),
        ] {
            let (float64, _) = state(Precision::Double, x0, SimdLevel::Baseline);
            let (portable, _) = state(precision, x0, SimdLevel::Baseline);
            let off = apart(&portable, &float64);
            println!("{pass}, {precision:?}, {x0} m out: {off:e} m from float64");
            assert!(
                off <= bound,
                "{pass}, {precision:?}: {off:e} m from float64"
            );
            // Float64's lanes differ from the portable ones as float32's do, in
            // round-off: float64's epsilon (2^-29 of float32's) of coordinates
            // `x0` (300 m) out, where float32 positions were within 1 m of 0.
            let level_bound = match precision {
                Precision::Double => 1e-5 * x0.max(1.0) * f64::EPSILON / f32::EPSILON as f64,
                _ => 1e-5,
            };
            for level in [SimdLevel::Avx2, SimdLevel::Avx512] {
                let (x, ran) = state(precision, x0, level);
                let off = apart(&x, &portable);
                println!("{pass}, {precision:?} {ran:?}: {off:e} m from the portable lanes");
                assert!(
                    off < level_bound,
                    "{pass}, {precision:?} {ran:?}: {off:e} m"
                );
            }
        }
    }
}

/// The colliders' contact with friction, resolved in the step (the ground's
/// friction on each row as soon as it is stepped, on the level's own vectors; the
/// sphere's after each band), gives the same cloth on every SIMD level within
/// float32 round-off, and the float64 cloth's within what float32 rounds off over
/// the run (measured: 2e-7 m from float64, 1e-7 m between levels): the bench
/// cloth, 300 m out on fixed-point positions, falling from its corners onto a
/// sphere and its lower rows onto the ground, with a ground soft enough for the
/// step (`k_c dt² / m` = 0.04).
#[test]
fn every_simd_level_gives_the_contact_alike() {
    use cloth_sandbox::sim::grid_kernel::Precision;
    use cloth_sandbox::sim::{Ground, Sphere};
    let state = |precision: Precision, level: SimdLevel| {
        let mut spec = GridSpec::peer_bench(45, false);
        spec.origin[0] = 300.0;
        spec.precision = precision;
        spec.ground = Some(Ground {
            height: -0.8,
            stiffness: 20.0,
            damping: 0.005,
            friction: 0.6,
        });
        spec.sphere = Some(Sphere {
            center: DVec3::new(300.5, -0.55, 0.12),
            radius: 0.15,
        });
        spec.friction = 0.3;
        // 400 steps: the cloth has come down onto the sphere and the ground; later
        // it slides off the sphere, where float32's round-off decides which
        // particles catch (the runs part by centimetres).
        stepped(spec, level, 400)
    };
    let (float64, _) = state(Precision::Double, SimdLevel::Baseline);
    let on_ground = float64.iter().filter(|x| x.y < -0.79).count();
    let on_sphere = float64
        .iter()
        .filter(|x| x.distance(DVec3::new(300.5, -0.55, 0.12)) < 0.16)
        .count();
    println!("{on_ground} particles on the ground, {on_sphere} on the sphere");
    assert!(on_ground > 40 && on_sphere > 20);
    let (portable, _) = state(Precision::Mixed, SimdLevel::Baseline);
    let off = apart(&portable, &float64);
    println!("fixed point, portable: {off:e} m from float64");
    assert!(off < 1e-6, "{off:e} m from float64");
    for level in [SimdLevel::Avx2, SimdLevel::Avx512] {
        let (x, ran) = state(Precision::Mixed, level);
        let off = apart(&x, &portable);
        println!("fixed point, {ran:?}: {off:e} m from the portable lanes");
        assert!(off < 1e-6, "{ran:?}: {off:e} m");
    }
}

/// The divergence check's scan: the largest squared speed and distance from a
/// centre, as computed here in f64 from the kernel's own arrays (within float32
/// rounding), in each precision; infinite once a coordinate or a velocity is NaN,
/// whatever its sign bit, or infinite.
#[test]
fn the_runaway_scan_finds_the_largest_speed_and_distance_and_any_nan() {
    use cloth_sandbox::sim::grid_kernel::Precision;
    for precision in [Precision::Single, Precision::Double] {
        let mut spec = GridSpec::peer_bench(16, true);
        spec.precision = precision;
        let mut cloth = GridCloth::new(spec);
        for _ in 0..50 {
            cloth.step(DT);
        }
        let center = DVec3::new(0.3, -0.2, 0.1);
        let (speed2, dist2) = cloth.extremes(center);
        let mut x = vec![DVec3::ZERO; cloth.len()];
        cloth.positions_into(&mut x);
        let mut v = x.clone();
        cloth.velocities_into(&mut v);
        let most = |a: &[f64]| a.iter().copied().fold(0.0, f64::max);
        let speeds: Vec<f64> = v.iter().map(|v| v.length_squared()).collect();
        let dists: Vec<f64> = x.iter().map(|x| x.distance_squared(center)).collect();
        assert!(most(&speeds) > 0.01, "the cloth should be moving");
        assert!(
            (speed2 - most(&speeds)).abs() <= 1e-5 * most(&speeds),
            "{precision:?}"
        );
        assert!(
            (dist2 - most(&dists)).abs() <= 1e-5 * most(&dists),
            "{precision:?}"
        );
        let broken = |i: usize, position: DVec3, velocity: DVec3| {
            let mut cloth = GridCloth::new(GridSpec {
                precision,
                ..GridSpec::peer_bench(16, true)
            });
            cloth.set_particle(i, position, velocity);
            cloth.extremes(center)
        };
        let inf = f64::INFINITY;
        for nan in [f64::NAN, -f64::NAN] {
            let at = DVec3::new(0.5, 0.5, 0.0);
            assert_eq!(broken(37, at, DVec3::new(0.0, nan, 0.0)), (inf, inf));
            assert_eq!(
                broken(200, DVec3::new(nan, 0.5, 0.0), DVec3::ZERO),
                (inf, inf)
            );
        }
        assert_eq!(broken(37, DVec3::ZERO, DVec3::new(0.0, inf, 0.0)).0, inf);
        assert_eq!(broken(200, DVec3::new(0.0, -inf, 0.0), DVec3::ZERO).1, inf);
    }
}

/// Positions and velocities of a cloth.
fn state(cloth: &GridCloth) -> (Vec<DVec3>, Vec<DVec3>) {
    let (mut p, mut v) = (
        vec![DVec3::ZERO; cloth.len()],
        vec![DVec3::ZERO; cloth.len()],
    );
    cloth.positions_into(&mut p);
    cloth.velocities_into(&mut v);
    (p, v)
}

#[test]
fn recentring_fixed_point_positions_changes_nothing() {
    // The peers' cloth unpinned, on fixed-point positions, falling 2 s in a side
    // wind (it tumbles and flaps): about 11 m, several times the room its frame
    // holds (2 to 4 times its 0.7 m radius), so the kernel recentres the frame on
    // it again and again (a frame left behind would wrap the integers round, and
    // tear the cloth apart by 2^32 units). A second cloth, the same, has its frame moved as well
    // after the first second (its state set again: a frame around where it is
    // then). Recentring shifts the stored integers by whole units, so the two must
    // step alike to the last bit of their integers: their positions differ only
    // by the float64 rounding of reading them back (1e-15 of 20 m).
    let mut spec = GridSpec::peer_bench(32, true);
    spec.pinned.clear();
    spec.wind = [2.0, 0.0, 5.0];
    spec.precision = Precision::Mixed;
    let (mut a, mut b) = (GridCloth::new(spec.clone()), GridCloth::new(spec));
    let start = state(&a).0;
    for cloth in [&mut a, &mut b] {
        cloth.steps(DT, 960);
    }
    let (p, v) = state(&b);
    b.set_state(&p, &v);
    for cloth in [&mut a, &mut b] {
        cloth.steps(DT, 960);
    }
    let (pa, pb) = (state(&a).0, state(&b).0);
    let fell = start[0].y - pa[0].y;
    let apart = apart(&pa, &pb);
    let shape = pa.iter().map(|p| p.distance(pa[0])).fold(0.0, f64::max);
    println!("fell {fell:.2} m, {shape:.3} m across; the two {apart:.3e} m apart");
    assert!(fell > 10.0, "fell {fell} m");
    assert!(shape > 0.5 && shape < 1.5, "{shape} m across");
    assert!(pa.iter().all(|p| p.is_finite()));
    assert!(apart < 1e-13, "{apart:e} m apart");
}

#[test]
fn a_particle_dragged_far_away_widens_the_frame_and_the_cloth_goes_on() {
    // Fixed-point positions hold a few cloth sizes about the cloth. A particle
    // dragged 5 km off (a grab) no longer fits: the kernel doubles its unit until
    // it does. Every particle then reads back where it was put, to half the new
    // unit, and the cloth steps on without a NaN.
    let mut spec = GridSpec::peer_bench(32, false);
    spec.precision = Precision::Mixed;
    let mut cloth = GridCloth::new(spec);
    cloth.steps(DT, 100);
    let (before, _) = state(&cloth);
    let far = DVec3::new(5000.0, -3000.0, 1000.0);
    cloth.set_particle(500, far, DVec3::ZERO);
    let (after, _) = state(&cloth);
    // A frame holding 5.9 km around the cloth has a unit of about 2^-16 m or less.
    let half_unit = 2f64.powi(-17);
    assert!(after[500].distance(far) <= half_unit, "{:?}", after[500]);
    for (p, (q, r)) in before.iter().zip(&after).enumerate() {
        if p != 500 {
            assert!(q.distance(*r) <= half_unit, "particle {p}: {q} -> {r}");
        }
    }
    cloth.set_pinned(500, true);
    cloth.steps(DT, 100);
    assert!(state(&cloth).0.iter().all(|p| p.is_finite()));
}
