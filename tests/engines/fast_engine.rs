//! The fast grid engine against the f64 engine (the exact reference), feature by
//! feature: each run is built twice from the same scene, stepped on both engines,
//! and compared particle by particle.
//!
//! Tolerance: the fast engine evaluates forces in float32 (relative round-off about
//! 6e-8 per operation) on positions kept to a few nm (fixed point, 2^-29 of twice
//! the cloth's size: 7.5e-9 m for the drape), so the two
//! runs part by float32 round-off of the accelerations, integrated over the run and
//! amplified by whatever instability the motion has. Each case states its bound;
//! every bound is at least 1000 times smaller than the motion it checks (the
//! cloths move by 0.05 to 1 m over these runs).

use cloth_sandbox::sim::grid_kernel::{GridCloth, GridSpec, Precision, SpringCoefficients};
use cloth_sandbox::sim::{Engine, HAND_REACH, Integrator, System, safe};
use glam::DVec3;

use crate::common::{build, max_distance, spread_and_back};

/// Largest distance any particle moved from `start`.
fn motion(start: &[DVec3], end: &[DVec3]) -> f64 {
    max_distance(start, end)
}

/// Largest distance between a particle of `near` and the same one of `far`
/// moved back by `shift`.
fn apart_less(near: &[DVec3], far: &[DVec3], shift: DVec3) -> f64 {
    let far: Vec<DVec3> = far.iter().map(|q| *q - shift).collect();
    max_distance(near, &far)
}

/// The same system twice: one allowed the fast engine (and taking it), one exact.
fn pair(name: &str, overrides: &[&str]) -> (System, System) {
    let mut fast = build(name, overrides);
    fast.set_fast_path(true);
    assert!(
        fast.engine().is_grid(),
        "{name} {overrides:?} should run on the fast engine"
    );
    let exact = build(name, overrides);
    assert_eq!(exact.engine(), Engine::General);
    (fast, exact)
}

/// Runs both for `steps` and returns (largest difference, largest motion) in m.
fn compare(fast: &mut System, exact: &mut System, steps: u64) -> (f64, f64) {
    let start = exact.positions().to_vec();
    fast.run(steps).unwrap();
    exact.run(steps).unwrap();
    assert_eq!(fast.time(), exact.time());
    let d = max_distance(fast.positions(), exact.positions());
    (d, motion(&start, exact.positions()))
}

/// A comparison: scene, base overrides, the feature's overrides, steps, bound (m).
type Case<'a> = (&'a str, &'a [&'a str], &'a [&'a str], u64, f64);

#[test]
fn each_feature_agrees_with_the_f64_engine() {
    // (scene, base overrides, the feature's overrides, steps, bound in m). Without
    // wind the motion is regular and the engines agree to about 1e-7 m over a
    // simulated second; a cloth flapping in the wind amplifies round-off (measured:
    // 2e-4 m apart after a second of the default cloth in steady wind), so the windy
    // cases are compared before the flapping sets in, and the drape before it
    // buckles over the sphere (about 0.35 s).
    let still = &["gust=0", "wind=\"0,0,0\""][..];
    let cases: &[Case] = &[
        ("cloth", still, &["air_damping=0.005"], 960, 1e-6),
        (
            "cloth",
            still,
            &["ground_height=-0.05", "ground_stiffness=500"],
            960,
            1e-6,
        ),
        ("cloth", still, &["integrator=\"verlet\""], 960, 1e-6),
        (
            "cloth",
            still,
            &["integrator=\"explicit-euler\"", "damping=0.2"],
            200,
            1e-6,
        ),
        ("cloth", still, &["stretch_limit=0.005"], 960, 1e-6),
        ("cloth", still, &["gravity=-30"], 960, 1e-6),
        ("cloth", &[], &["wind=\"0,0,8\"", "gust=4"], 120, 1e-6),
        (
            "drape",
            &["sphere_radius=0.01"],
            &["sphere_radius=0.5"],
            320,
            1e-5,
        ),
        // The sphere met off-centre, on its side (compared until the cloth sliding
        // off it amplifies round-off: 7e-8 m apart at 160 steps, 8e-5 at 280), and
        // from inside its lower half (the cloth starts in it and is thrown out at
        // hundreds of m/s): contacts in some rows and columns only, below the
        // centre as well as above, with friction.
        (
            "drape",
            &["sphere_radius=0.01"],
            &["sphere_radius=0.5", "sphere_center=\"0.9,0.2,0.3\""],
            160,
            1e-6,
        ),
        // Thrown out at hundreds of m/s, the cloth amplifies the rounding of its
        // fixed-point positions (half its 7.5e-9 m unit a step): 2.4e-6 m apart,
        // where double-float positions gave 5e-7 m and a unit 16 times finer 6e-7.
        (
            "drape",
            &["sphere_radius=0.01"],
            &["sphere_radius=0.5", "sphere_center=\"0.5,1.0,0\""],
            40,
            1e-5,
        ),
        (
            "drape",
            &["stretch_limit=0.1", "sphere_radius=0.01"],
            &["sphere_radius=0.5"],
            320,
            1e-5,
        ),
        (
            "sheet",
            &["stretch_limit=1"],
            &["stretch_limit=0.1"],
            240,
            1e-6,
        ),
        ("bench", &["width=40"], &["height=24"], 960, 1e-6),
        // XPBD's grid runs on float32 positions (its springs are not forces, see
        // `Precision::needed`): round-off of 6e-8 of the 1.5 m cloth per step.
        ("cloth", still, &["integrator=\"xpbd\""], 960, 1e-5),
        // XPBD corrects a spring by a small part of its stretch each step; on
        // fixed-point positions the part of a move under half a unit reaches the
        // position through the velocity (`spring_line`), where rounding it away
        // had put this case 9e-5 m apart: 3.0e-6 m (9.6e-7 on the double-float
        // positions before).
        (
            "drape",
            &["integrator=\"xpbd\"", "sphere_radius=0.01"],
            &["sphere_radius=0.5"],
            320,
            1e-5,
        ),
    ];
    for &(name, base, feature, steps, bound) in cases {
        let overrides: Vec<&str> = base.iter().chain(feature).copied().collect();
        let (mut fast, mut exact) = pair(name, &overrides);
        let (d, moved) = compare(&mut fast, &mut exact, steps);
        // What the feature changes, so that agreeing means something.
        let mut without = build(name, base);
        without.run(steps).unwrap();
        let effect = max_distance(without.positions(), exact.positions());
        println!(
            "{name} {overrides:?}: {d:.3e} m apart after {steps} steps; moved {moved:.3} m, \
             the feature changed it by {effect:.3e} m"
        );
        assert!(
            d < bound,
            "{name} {overrides:?}: {d:e} m apart (bound {bound:e})"
        );
        assert!(
            moved > 1000.0 * bound,
            "{name} {overrides:?}: moved only {moved} m"
        );
        assert!(
            effect > 100.0 * bound,
            "{name} {overrides:?}: the feature did nothing"
        );
        assert!(
            d > 0.0,
            "identical results would mean the fast engine did not run"
        );
    }
}

#[test]
fn pins_anywhere_and_grabs_agree_with_the_f64_engine() {
    let (mut fast, mut exact) = pair("bench", &["width=48", "height=48"]);
    // 50 pins at scattered places (a fixed permutation, no randomness to chase).
    let n = fast.particle_count();
    for system in [&mut fast, &mut exact] {
        for j in 0..50 {
            system.set_pinned((j * 7919 + 13) % n, true);
        }
        system.run(100).unwrap();
        system.grab(n / 2 + 7, DVec3::new(0.3, 0.4, 0.2));
        system.run(200).unwrap();
    }
    let d = max_distance(fast.positions(), exact.positions());
    println!("50 pins and a grab: {d:.3e} m");
    assert!(d < 1e-5, "{d:e}");
    assert_eq!(fast.positions()[n / 2 + 7], DVec3::new(0.3, 0.4, 0.2));
}

/// A particle dragged by the mouse: one grab, then its target moved again and
/// again with steps between (the grid kernel takes each move in place, Verlet
/// reloads), on float32 and fixed-point positions. The fast engine must follow the
/// f64 engine, and the particle end exactly at the last target. The moves pull
/// the cloth far enough that a kernel missing one would part from the f64 engine by
/// far more than the bound (0.16 m, with the in-place move left out). Bounds: 1e-5
/// m for the bench, as for the pins and grab above; 1e-4 m for the default cloth,
/// whose fixed-point positions and gusts part it from the f64 engine by 3.6e-5 m
/// here when every move reloads the whole kernel too.
#[test]
fn a_dragged_particle_agrees_with_the_f64_engine() {
    let verlet = ["width=32", "height=32", "integrator=\"verlet\""];
    for (name, overrides, bound) in [
        ("bench", &["width=32", "height=32"][..], 1e-5),
        ("bench", &verlet[..], 1e-5),
        ("cloth", &["width=32", "height=32"][..], 1e-4),
    ] {
        let (mut fast, mut exact) = pair(name, overrides);
        let n = fast.particle_count();
        let i = n / 2 + 5;
        let start = fast.positions()[i];
        let target = |k: u32| start + DVec3::new(0.02 * f64::from(k), 0.01 * f64::from(k % 3), 0.0);
        for system in [&mut fast, &mut exact] {
            system.run(20).unwrap();
            for k in 0..12 {
                system.grab(i, target(k));
                system.run(10).unwrap();
            }
        }
        let d = max_distance(fast.positions(), exact.positions());
        let mut still = build(name, overrides);
        still.run(140).unwrap();
        let pulled = max_distance(still.positions(), exact.positions());
        println!("{name} {overrides:?}: dragged particle, {d:.3e} m apart, pulled {pulled:.3} m");
        assert!(d < bound, "{name} {overrides:?}: {d:e} m");
        assert!(
            pulled > 1e3 * bound,
            "{name} {overrides:?}: the drag moved {pulled} m"
        );
        assert_eq!(fast.positions()[i], target(11));
    }
}

/// A hand a metre away: the held particle goes towards it [`HAND_REACH`] of its
/// shortest spring a step, in a straight line, and gets there; on both engines.
#[test]
fn a_held_particle_follows_a_far_hand_half_a_spring_a_step() {
    let (mut fast, mut exact) = pair("cloth", &["width=16", "height=16"]);
    let i = fast.particle_count() / 2 + 3;
    let shortest = (fast.springs().iter())
        .filter(|s| s.a as usize == i || s.b as usize == i)
        .map(|s| s.rest)
        .fold(f64::INFINITY, f64::min);
    let reach = HAND_REACH * shortest;
    for system in [&mut fast, &mut exact] {
        let start = system.positions()[i];
        system.grab(i, start);
        system.run(10).unwrap();
        let hand = start + DVec3::new(0.6, 0.0, 0.8);
        system.grab(i, hand);
        for k in 1..=4 {
            system.run(1).unwrap();
            let at = system.positions()[i];
            let expected = start + (hand - start) * ((k + 1) as f64 * reach);
            assert!(
                at.distance(expected) < 1e-12,
                "step {k}: {at} against {expected}"
            );
        }
        let steps = (1.0 / reach).ceil() as u64;
        system.run(steps).unwrap();
        assert_eq!(system.positions()[i], hand);
        assert_eq!(system.grabbed(), Some((i, hand)));
    }
    let d = max_distance(fast.positions(), exact.positions());
    assert!(d < 1e-4, "{d:e} m apart");
}

/// Kinetic energy of the cloth after `steps` safe steps, on both engines.
fn stiff_energies(stiffness: f64, mass: f64, steps: u64) -> (f64, f64, f64) {
    let overrides = [
        "wind=\"0,0,0\"".to_string(),
        "gust=0".to_string(),
        format!("stiffness={stiffness}"),
        format!("particle_mass={mass}"),
    ];
    let overrides: Vec<&str> = overrides.iter().map(String::as_str).collect();
    let (mut fast, mut exact) = pair("cloth", &overrides);
    let step = safe::safe_step(exact.model(), 1.0 / 60.0, safe::DEFAULT_SAFETY, 1 << 20);
    for system in [&mut fast, &mut exact] {
        let mut params = *system.params();
        params.dt = step.dt;
        system.set_params(params);
        system.run(steps).unwrap();
    }
    let scale = exact.masses().iter().sum::<f64>() * 9.81 * 0.05;
    (fast.energy().kinetic, exact.energy().kinetic, scale)
}

#[test]
fn stiff_cloth_does_not_heat_up_on_the_fast_engine() {
    // Float32 positions lose `x += h v` below 6e-8 m; times k that is force noise
    // that heated a k = 1e7 cloth to 0.15 J. The engine keeps positions in fixed point
    // and computes in float64 where float32 lengths are too coarse for k
    // (`Precision::needed`), so its kinetic energy must follow the f64 engine's to
    // 1% at every stiffness the panel allows, down to the 1e-15 J of a cloth at rest.
    for (k, m) in [(1e3, 1e-3), (1e5, 1e-3), (1e7, 1e-3), (1e9, 1e-6)] {
        let (fast, exact, scale) = stiff_energies(k, m, 2000);
        println!(
            "k = {k:e}, m = {m:e}: kinetic {fast:.3e} J (fast) vs {exact:.3e} J (f64), \
             scale {scale:.3e} J"
        );
        assert!(
            (fast - exact).abs() <= 0.01 * exact + 1e-12 * scale,
            "k = {k:e}: kinetic energy {fast:e} J against {exact:e} J"
        );
    }
}

#[test]
fn float32_arithmetic_heats_a_stiff_cloth_so_the_engine_does_not_use_it() {
    // The peers' cloth made stiff (k = 1e7 N/m, 1 g particles), stepped at half its
    // critical step from rest in both precisions: float32 spring lengths feed it
    // noise that float64 does not.
    let kinetic = |precision: Precision| {
        let mut spec = GridSpec::peer_bench(32, false);
        let kind = SpringCoefficients { k: 1e7, b: 0.0 };
        (spec.structural, spec.shear, spec.bend) = (kind, kind, kind);
        spec.gravity = [0.0; 3];
        spec.precision = precision;
        let m = spec.particle_mass;
        // Gershgorin: omega² <= 2 * 12 k / m.
        let dt = 0.5 * 2.0 / (24.0 * 1e7 / m).sqrt();
        let mut cloth = GridCloth::new(spec);
        cloth.steps(dt, 3000);
        let mut v = vec![DVec3::ZERO; cloth.len()];
        cloth.velocities_into(&mut v);
        v.iter().map(|v| 0.5 * m * v.length_squared()).sum::<f64>()
    };
    let [single, mixed, double] =
        [Precision::Single, Precision::Mixed, Precision::Double].map(kinetic);
    println!(
        "kinetic energy from rest: {single:.3e} J (float32), {mixed:.3e} J (float32 on \
         fixed-point positions), {double:.3e} J (float64)"
    );
    assert!(
        single > 1e3 * double.max(1e-30),
        "{single:e} J vs {double:e} J"
    );
    assert!(
        mixed > 1e3 * double.max(1e-30),
        "{mixed:e} J vs {double:e} J"
    );
    // The rule: float64 for this cloth, fixed-point positions for a moderately
    // stiff one, float32 for the peers' cloth.
    let mut spec = GridSpec::peer_bench(32, false);
    spec.structural.k = 1e7;
    assert_eq!(Precision::needed(&spec, 2.0, 1e-3), Precision::Double);
    spec.structural.k = 100.0;
    assert_eq!(Precision::needed(&spec, 2.0, 1e-3), Precision::Mixed);
    assert_eq!(
        Precision::needed(&GridSpec::peer_bench(32, false), 2.0, 1e-3),
        Precision::Single
    );
    // XPBD: its stiff springs act as springs of stiffness `m / 2h²` whatever k
    // is, so float32 positions for whole 1/60 s frames (noise 5e-3 m/s² at 2 m),
    // fixed-point ones for steps of 1e-3 s (0.48 m/s² on float32 positions,
    // 8e-3 on fixed-point ones), never float64.
    spec.integrator = Integrator::Xpbd;
    for k in [1e7, 1e9] {
        spec.structural.k = k;
        assert_eq!(Precision::needed(&spec, 2.0, 1.0 / 60.0), Precision::Single);
        assert_eq!(Precision::needed(&spec, 2.0, 1e-3), Precision::Mixed);
    }
}

#[test]
fn a_grid_whose_springs_are_not_the_stencil_is_not_taken_for_one() {
    // A 6 x 5 grid with its structural springs, declared a grid; then the same with
    // one spring moved onto a diagonal (same count, same rest length and kind).
    use cloth_sandbox::sim::{GridShape, Params, Spring, SpringKind, SpringMaterial, Topology};
    let (w, h, spacing) = (6usize, 5usize, 0.1);
    let at = |r: usize, c: usize| (r * w + c) as u32;
    let build = |rewire: bool| {
        let mut springs = Vec::new();
        for r in 0..h {
            for c in 0..w {
                for (dr, dc) in [(0, 1), (1, 0)] {
                    if r + dr < h && c + dc < w {
                        let (a, b) = (at(r, c), at(r + dr, c + dc));
                        springs.push(Spring {
                            a,
                            b,
                            rest: spacing,
                            kind: SpringKind::Structural,
                        });
                    }
                }
            }
        }
        if rewire {
            springs[0].b = at(1, 1);
        }
        let positions = (0..w * h)
            .map(|p| DVec3::new((p % w) as f64 * spacing, -((p / w) as f64) * spacing, 0.0))
            .collect();
        let structural = SpringMaterial {
            stiffness: 10.0,
            damping: 0.0,
        };
        let topology = Topology {
            springs,
            materials: [structural; 4],
            grid: Some(GridShape {
                width: w,
                height: h,
            }),
            ..Topology::default()
        };
        let mut system = System::new(
            vec![0.01; w * h],
            positions,
            &[0],
            topology,
            Params::default(),
        );
        system.set_fast_path(true);
        system.engine()
    };
    assert!(build(false).is_grid());
    // Not a grid after all: the engine for any topology takes it.
    assert_eq!(build(true), Engine::General);
}

#[test]
fn live_edits_update_the_kernel_in_place() {
    // What the panel's sliders do, each followed by steps: one kernel for all.
    use cloth_sandbox::sim::SpringKind;
    let mut system = build("cloth", &["width=64", "height=64"]);
    system.set_fast_path(true);
    system.run(5).unwrap();
    assert_eq!(system.kernel_builds(), 1);
    let edits: [&dyn Fn(&mut System); 6] = [
        &|s| s.set_spring_stiffness(SpringKind::Structural, 150.0),
        &|s| s.set_spring_damping(SpringKind::Shear, 0.05),
        &|s| s.set_particle_mass(0.0015),
        &|s| s.rescale(1.1),
        &|s| {
            let mut p = *s.params();
            (p.wind, p.gravity, p.air_damping) =
                (DVec3::new(1.0, 0.0, 3.0), DVec3::new(0.0, -5.0, 0.0), 0.01);
            s.set_params(p);
        },
        &|s| s.set_pinned(100, true),
    ];
    for edit in edits {
        edit(&mut system);
        system.run(5).unwrap();
    }
    assert_eq!(system.kernel_builds(), 1, "an edit rebuilt the kernel");
    // And the kernel saw the edits: it agrees with the f64 engine given the same ones.
    let mut exact = build("cloth", &["width=64", "height=64"]);
    exact.run(5).unwrap();
    for edit in edits {
        edit(&mut exact);
        exact.run(5).unwrap();
    }
    let d = max_distance(system.positions(), exact.positions());
    assert!(d < 1e-6, "{d:e} m");
    // A new integrator is a new kernel.
    let mut p = *system.params();
    p.integrator = cloth_sandbox::sim::Integrator::Verlet;
    system.set_params(p);
    system.run(1).unwrap();
    assert_eq!(system.kernel_builds(), 2);
}

#[test]
fn far_from_the_origin_a_cloth_moves_as_it_does_at_the_origin() {
    // Fixed-point positions are stored relative to a frame on the cloth, so a
    // cloth 10 km out steps as the same cloth at the origin (float32 positions
    // there would resolve only 1 mm). Both runs on the fast engine, compared less
    // the shift: the f64 coordinates near 1e4 m are themselves good to 2e-12 m.
    let run = |origin: &str| {
        let mut system = build("cloth", &["gust=0", "wind=\"0,0,0\"", origin]);
        system.set_fast_path(true);
        assert_eq!(system.engine(), Engine::Grid(Precision::Mixed));
        let start = system.positions().to_vec();
        system.run(960).unwrap();
        (start, system.positions().to_vec())
    };
    let (start, near) = run("origin=\"0,1,0\"");
    let (_, far) = run("origin=\"10000,1,-5000\"");
    let shift = DVec3::new(10000.0, 0.0, -5000.0);
    let d = apart_less(&near, &far, shift);
    let moved = motion(&start, &near);
    println!("{d:.3e} m apart after moving {moved:.3} m");
    assert!(moved > 0.01);
    assert!(d < 1e-9, "{d:e} m apart");
}

#[test]
fn far_from_the_origin_colliders_and_a_jelly_act_exactly_as_at_the_origin() {
    // The drape over its sphere onto a frictional ground (self-collision and all,
    // through its buckling), and the jelly dropped onto its ground, given friction
    // there so that the lattice's contact pass runs too: each run at
    // the origin and again with the body and its colliders moved 10 km out and 3
    // km up, compared less the shift. The frame's centre moves by whole units (a
    // power of two, so the shift is a whole number of them), the colliders are
    // stored in the same frame, and contact works on the offsets from them, exact
    // in fixed point: the two runs are the same integers, step for step. (With
    // contact in metres from the origin, as before, a push rounded to the unit
    // the other way now and then parted the drapes by 2.1e-8 m after 320 steps,
    // and by 7.5e-3 m after 1280 once the cloth buckled.)
    let shift = DVec3::new(10000.0, 3000.0, -5000.0);
    let at = |p: [f64; 3], by: DVec3| {
        let q = DVec3::from(p) + by;
        format!("\"{},{},{}\"", q.x, q.y, q.z)
    };
    // Scene, origin, sphere centre, ground height, engine, steps.
    type Case = (&'static str, [f64; 3], Option<[f64; 3]>, f64, Engine, u64);
    let cases: [Case; 2] = [
        (
            "drape",
            [-0.975, 0.8, -0.975],
            Some([0.0; 3]),
            // Raised from its -0.9 m, for the hanging flaps to reach it.
            -0.4,
            Engine::Grid(Precision::Mixed),
            1280,
        ),
        // 4 s: the jelly lands after about 2 s.
        (
            "jelly",
            [0.0, 8.0, 0.0],
            None,
            0.0,
            Engine::Lattice(Precision::Mixed),
            20000,
        ),
    ];
    for (scene, origin, sphere, ground, engine, steps) in cases {
        let run = |by: DVec3| {
            let origin = format!("origin={}", at(origin, by));
            let height = format!("ground_height={}", ground + by.y);
            let sphere = sphere.map(|c| format!("sphere_center={}", at(c, by)));
            let mut settings = vec![origin.as_str(), height.as_str(), "friction=0.5"];
            settings.extend(sphere.as_deref());
            let mut system = build(scene, &settings);
            system.set_fast_path(true);
            assert_eq!(system.engine(), engine, "{scene} {by}");
            let start = system.positions().to_vec();
            // The lowest any particle came, over its ground's surface (a
            // particle rests its thickness above the ground).
            let mut lowest = f64::MAX;
            for _ in 0..steps / 40 {
                system.run(40).unwrap();
                let y = system.positions().iter().map(|p| p.y - by.y);
                lowest = y.fold(lowest, f64::min);
            }
            let lowest = lowest - system.params().thickness - ground;
            (start, system.positions().to_vec(), lowest)
        };
        let (start, near, lowest) = run(DVec3::ZERO);
        let (_, far, _) = run(shift);
        let d = apart_less(&near, &far, shift);
        let moved = motion(&start, &near);
        println!(
            "{scene}: {d:.3e} m apart after moving {moved:.3} m, lowest {lowest:.1e} m over its ground"
        );
        // It reached its ground: the ground's part of contact ran.
        assert!(lowest < 0.005, "{scene}: lowest {lowest} m over its ground");
        // Up to the f64 coordinates near 1e4 m, themselves good to 2e-12 m.
        assert!(d < 1e-11, "{scene}: {d:e} m apart");
    }
}

#[test]
fn a_small_cloth_on_a_fine_unit_takes_a_strong_wind() {
    // A 2 x 2 cloth at k = 1,690 N/m: its roomy fixed-point unit is just too coarse
    // for the precision rule, so it runs on its tight unit, 2^-34 m. There a drag
    // triangle's `|v_rel|² |m|²`, in units⁴ m²/s², passed float32's range in a 30
    // m/s wind, and the cloth went non-finite in its first step. Safe steps for
    // 0.2 s against the f64 engine, the wind blowing through the cloth.
    let overrides = [
        "width=2",
        "height=2",
        "stiffness=1690",
        "wind=\"0,0,30\"",
        "gust=0",
    ];
    let (mut fast, mut exact) = pair("cloth", &overrides);
    assert_eq!(fast.engine(), Engine::Grid(Precision::Mixed));
    let step = safe::safe_step(exact.model(), 1.0 / 60.0, safe::DEFAULT_SAFETY, 1 << 20);
    for system in [&mut fast, &mut exact] {
        let mut params = *system.params();
        params.dt = step.dt;
        system.set_params(params);
    }
    let steps = (0.2 / step.dt).ceil() as u64;
    let (d, moved) = compare(&mut fast, &mut exact, steps);
    println!("2 x 2 cloth in a 30 m/s wind: {d:.2e} m apart after moving {moved:.3e} m");
    assert!(moved > 0.03, "the wind moved it {moved} m");
    assert!(d < 1e-6, "{d} m from the f64 engine");
}

#[test]
fn a_cloth_spread_past_its_fixed_point_unit_goes_on_in_float64_until_it_draws_in() {
    // The default cloth at k = 800 N/m is on fixed-point positions just under the
    // precision rule's limit. Spread to eight times its size (every particle moved
    // out from the centre: past the four or so radii its unit holds) a kernel
    // keeping fixed point must double its unit, which puts the noise over the
    // limit: the run goes on in float64 and follows the f64 engine to its
    // round-off (on fixed point, even on its own unit, the cloth is 9e-9 m off
    // after 8 steps). Put back, the cloth returns to fixed point. (Only 8 steps
    // spread: the springs, stretched to eight times their length, fling the
    // particles, and in a few dozen steps even the two float64 engines part.)
    let overrides = ["stiffness=800", "wind=\"0,0,0\"", "gust=0", "dt=0.0004"];
    let (mut fast, _) = pair("cloth", &overrides);
    let before = (fast.engine(), fast.precision_rule().unwrap());
    assert_eq!(before.0, Engine::Grid(Precision::Mixed));
    let run = spread_and_back(&mut fast, 8.0, 8);
    println!("spread 8x: {run:?}");
    let (engine, rule) = run.spread;
    assert_eq!(engine, Engine::Grid(Precision::Double));
    assert!(rule.fixed_point > Precision::NOISE_LIMIT && rule.unit > before.1.unit);
    assert!(run.apart < 1e-12, "{:e} m from the f64 engine", run.apart);
    assert_eq!(run.back, before);
}
