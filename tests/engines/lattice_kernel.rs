//! The lattice kernel (`sim::grid_kernel::lattice`) against the f64 general engine
//! (the exact reference), feature by feature, on the jelly cube made bigger; its
//! threads and SIMD levels; its choice of precision at every stiffness; and what it
//! leaves to the other engines.
//!
//! Tolerance. The kernel computes spring forces in float32 on fixed-point
//! positions, in the precision that `Precision::cheapest` picks so that float32's
//! resolution of the spring lengths, times `k / m` summed over a particle's
//! springs, is an acceleration noise of at most `Precision::NOISE_LIMIT` (1% of
//! gravity). A noise `a` moves a particle at most `a t² / 2` in a time `t` (the
//! system being stable, the stiff springs and ground make the difference oscillate
//! rather than grow), so the bound after `t` simulated seconds is
//! `NOISE_LIMIT t² / 2` ([`bound`]): 1.8e-4 m after the 0.06 s of the cases below,
//! which measure 2e-7 to 4e-6 m (each case prints its figure). A wrong force term
//! moves the particles by far more: left out, the carry of one run of springs
//! between blocks puts the jelly on the ground 1.3e-2 m away.

use cloth_sandbox::sim::grid_kernel::lattice::{LatticeKernel, LatticeShape, LatticeSpec};
use cloth_sandbox::sim::grid_kernel::{Precision, SimdLevel, SpringCoefficients};
use cloth_sandbox::sim::{Engine, Integrator, SpringKind, System};
use glam::DVec3;

use crate::common::{build, max_distance, spread_and_back};

/// Largest distance (m) allowed between the lattice kernel and the f64 engine after
/// `time` s (see the module comment).
fn bound(time: f64) -> f64 {
    0.5 * Precision::NOISE_LIMIT * time * time
}

/// The jelly made `n`³.
fn cube(n: usize) -> [String; 3] {
    ["width", "height", "depth"].map(|k| format!("{k}={n}"))
}

/// Steps `system` on the lattice kernel and a copy of it on the f64 engine after
/// `prepare` ran on both; returns the largest particle distance and how far the
/// particles moved.
fn lattice_and_exact(
    label: &str,
    mut fast: System,
    steps: u64,
    prepare: impl Fn(&mut System),
) -> (f64, f64) {
    let mut exact = fast.clone();
    let start = exact.positions().to_vec();
    fast.set_fast_path(true);
    for system in [&mut fast, &mut exact] {
        prepare(system);
    }
    assert!(
        matches!(fast.engine(), Engine::Lattice(_)),
        "{label}: took {:?}",
        fast.engine()
    );
    assert_eq!(exact.engine(), Engine::General);
    fast.run(steps).unwrap();
    exact.run(steps).unwrap();
    assert_eq!(fast.steps_taken(), exact.steps_taken());
    let d = max_distance(fast.positions(), exact.positions());
    let moved = max_distance(exact.positions(), &start);
    println!("{label}: {d:.2e} m apart after moving {moved:.3e} m");
    assert!(moved > 1e-3, "{label}: nothing moved ({moved:e} m)");
    let bound = bound(exact.time());
    assert!(
        d <= bound,
        "{label}: engines differ by {d:e} m after {steps} steps (bound {bound:e} m)"
    );
    // Float32 arithmetic: not bit for bit the f64 engine's, which shows that the
    // kernel ran.
    assert!(
        d > 0.0,
        "{label}: identical results: the kernel did not run"
    );
    (d, moved)
}

/// The lowest particle height of a system (m).
fn lowest(system: &System) -> f64 {
    system
        .positions()
        .iter()
        .map(|p| p.y)
        .fold(f64::INFINITY, f64::min)
}

#[test]
fn a_jelly_agrees_with_the_f64_engine_feature_by_feature() {
    let big = cube(12);
    let with = |extra: &[String]| {
        let overrides: Vec<&str> = big.iter().chain(extra).map(String::as_str).collect();
        build("jelly", &overrides)
    };
    // On the ground from the start: its lowest particle touching it (a ground
    // above it would have the scene lift the cube clear).
    let ground = format!("ground_height={}", lowest(&with(&[])));
    // A sphere of radius 2 m under the cube's lowest corner, 1 cm below it: the
    // corner lands on it after 0.045 s and is held on its surface. (A sphere that
    // starts inside the cube throws the particles out at 1,800 m/s, and the
    // projection's float32 round-off, 1e-6 m over a step, is then 5e-3 m/s.)
    let start = with(&[]);
    let corner =
        (start.positions().iter()).fold(DVec3::INFINITY, |m, &p| if p.y < m.y { p } else { m });
    let centre = corner - DVec3::Y * 2.01;
    let sphere = format!("sphere_center=\"{},{},{}\"", centre.x, centre.y, centre.z);
    let sphere_below = sphere.clone();
    let cases: Vec<(&str, Vec<String>)> = vec![
        ("falling", vec![]),
        ("on the ground", vec![ground.clone()]),
        (
            "air damping",
            vec![ground.clone(), "air_damping=0.5".into()],
        ),
        (
            "sphere below",
            vec![sphere.clone(), "sphere_radius=2".into()],
        ),
        (
            "sphere below, friction",
            vec![sphere, "sphere_radius=2".into(), "friction=0.5".into()],
        ),
        (
            "verlet",
            vec!["integrator=\"verlet\"".into(), ground.clone()],
        ),
        (
            "explicit euler",
            vec!["integrator=\"explicit-euler\"".into(), ground.clone()],
        ),
        (
            "tilted gravity",
            vec![ground.clone(), "gravity=\"3,-9.81,0\"".into()],
        ),
        (
            "applied force",
            vec![ground.clone(), "force=\"0.2,0,0.1\"".into()],
        ),
        // Stiff enough for float64 (`lattice-f64`).
        (
            "stiff, float64",
            vec![ground.clone(), "stiffness=20000".into()],
        ),
        // Friction on a tilted gravity, so that the cube slides or grips.
        (
            "ground friction",
            vec![
                ground.clone(),
                "friction=0.3".into(),
                "gravity=\"3,-9.81,0\"".into(),
            ],
        ),
        (
            "verlet, friction",
            vec![
                "integrator=\"verlet\"".into(),
                ground.clone(),
                "friction=0.3".into(),
                "gravity=\"3,-9.81,0\"".into(),
            ],
        ),
        // XPBD's springs and the stretch limit are passes after the step, and
        // the sphere and the friction come after them. The passes visit the
        // springs in one order of colour classes on both engines: with the f64
        // engine's in canonical order instead, "xpbd" ends 2.2e-4 m apart, past
        // the bound, and the stiff jelly's kinetic energy 3.1% off (the stretch
        // limit's cases, which share the order, stay inside the bound here).
        ("xpbd", vec!["integrator=\"xpbd\"".into(), ground.clone()]),
        (
            "xpbd, sphere below, friction",
            vec![
                "integrator=\"xpbd\"".into(),
                sphere_below.clone(),
                "sphere_radius=2".into(),
                "friction=0.5".into(),
            ],
        ),
        (
            "stretch limit, on the ground",
            vec!["stretch_limit=0.001".into(), ground.clone()],
        ),
        (
            "stretch limit, sphere below",
            vec![
                "stretch_limit=0.01".into(),
                sphere_below,
                "sphere_radius=2".into(),
            ],
        ),
        (
            "stretch limit, verlet, ground friction",
            vec![
                "stretch_limit=0.01".into(),
                "integrator=\"verlet\"".into(),
                ground,
                "friction=0.3".into(),
                "gravity=\"3,-9.81,0\"".into(),
            ],
        ),
    ];
    for (label, extra) in cases {
        lattice_and_exact(label, with(&extra), 300, |_| {});
    }
}

#[test]
fn pins_grabs_and_edits_reach_the_lattice_kernel() {
    let big = cube(12);
    let overrides: Vec<&str> = big.iter().map(String::as_str).collect();
    let system = build("jelly", &overrides);
    let (d, _) = lattice_and_exact("pinned corner, edits", system, 100, |s| {
        s.set_pinned(0, true);
        s.run(100).unwrap();
        s.set_spring_stiffness(SpringKind::Shear, 3000.0);
        s.set_spring_damping(SpringKind::Other, 2.0);
        s.grab(100, DVec3::new(1.0, 9.0, 0.5));
        s.run(100).unwrap();
        s.release();
        s.set_pinned(0, false);
        s.set_particle_mass(0.2);
    });
    assert!(d > 0.0);
}

/// The largest strain `l / L - 1` of a system's springs.
fn max_strain(system: &System) -> f64 {
    let x = system.positions();
    (system.springs().iter())
        .map(|s| x[s.a as usize].distance(x[s.b as usize]) / s.rest - 1.0)
        .fold(f64::NEG_INFINITY, f64::max)
}

#[test]
fn xpbd_and_the_stretch_limit_hold_a_hanging_jelly_as_the_f64_engine_does() {
    // The jelly hanging from its highest particle: the springs there stretch as
    // the rest falls (by 0.85% of their length in the 0.06 s here), so a 0.3%
    // limit binds.
    let big = cube(12);
    let limit = "stretch_limit=0.003";
    let cases: [(&str, &[&str]); 4] = [
        ("stretch limit", &[limit]),
        ("stretch limit, verlet", &[limit, "integrator=\"verlet\""]),
        ("xpbd", &["integrator=\"xpbd\""]),
        ("xpbd, stretch limit", &["integrator=\"xpbd\"", limit]),
    ];
    for (label, extra) in cases {
        let overrides: Vec<&str> = big
            .iter()
            .map(String::as_str)
            .chain(extra.iter().copied())
            .collect();
        let system = build("jelly", &overrides);
        let top = (0..system.particle_count())
            .max_by(|&i, &j| system.positions()[i].y.total_cmp(&system.positions()[j].y))
            .unwrap();
        let hang = |s: &mut System| s.set_pinned(top, true);
        lattice_and_exact(label, system.clone(), 300, hang);
        if extra.contains(&limit) {
            // The limit binds: without it the same run stretches a spring past it,
            // and with it the excess is under a tenth of that (one Gauss-Seidel
            // pass: a correction stretches the springs next to it a little).
            let unlimited: Vec<&str> = overrides.iter().copied().filter(|&o| o != limit).collect();
            let mut free = build("jelly", &unlimited);
            let mut held = system;
            for s in [&mut free, &mut held] {
                hang(s);
                s.set_fast_path(true);
                s.run(300).unwrap();
            }
            let (free, held) = (max_strain(&free), max_strain(&held));
            println!("{label}: largest strain {free:.4} without the limit, {held:.6} with it");
            assert!(free > 0.006, "{label}: the limit would not bind ({free})");
            let excess = held - 0.003;
            assert!(
                excess < 0.1 * (free - 0.003),
                "{label}: {held} with the limit"
            );
        }
    }
}

#[test]
fn edits_update_the_kernel_in_place() {
    // Soft enough that every edit keeps fixed-point positions (`lattice-mixed`).
    let big = cube(12);
    let mut overrides: Vec<&str> = big.iter().map(String::as_str).collect();
    overrides.push("stiffness=1000");
    let mut system = build("jelly", &overrides);
    system.set_fast_path(true);
    system.run(10).unwrap();
    system.set_spring_stiffness(SpringKind::Structural, 1500.0);
    system.set_spring_damping(SpringKind::Shear, 1.0);
    system.set_particle_mass(0.12);
    system.set_pinned(3, true);
    system.run(10).unwrap();
    // The stretch limit turned on, changed and off: coefficients of the passes.
    for limit in [Some(0.1), Some(0.05), None] {
        let mut params = *system.params();
        params.stretch_limit = limit;
        system.set_params(params);
        system.run(10).unwrap();
    }
    assert!(matches!(system.engine(), Engine::Lattice(_)));
    assert_eq!(system.kernel_builds(), 1, "an edit rebuilt the kernel");
}

/// A lattice spec for the kernel alone: `shape`, the jelly's springs, gravity and
/// a ground below.
fn spec(shape: LatticeShape, integrator: Integrator) -> LatticeSpec {
    LatticeSpec {
        shape,
        spacing: 1.0,
        particle_mass: 0.1,
        kinds: [
            SpringCoefficients { k: 2000.0, b: 0.7 },
            SpringCoefficients { k: 2000.0, b: 0.7 },
            SpringCoefficients { k: 2000.0, b: 0.7 },
        ],
        gravity: [0.0, -9.81, 0.0],
        air_damping: 0.0,
        ground: Some(cloth_sandbox::sim::Ground {
            height: 0.5,
            stiffness: 50_000.0,
            damping: 5.0,
            friction: 0.0,
        }),
        sphere: None,
        friction: 0.0,
        stretch_limit: None,
        integrator,
        precision: Precision::Mixed,
    }
}

/// Positions and velocities after `steps` steps of the kernel on `threads`
/// threads at `simd`, from a lattice shaken by a velocity field.
fn kernel_run(
    spec: &LatticeSpec,
    threads: usize,
    simd: SimdLevel,
    steps: usize,
) -> (Vec<DVec3>, Vec<DVec3>) {
    let LatticeShape { width, height, .. } = spec.shape;
    let n = spec.shape.len();
    let at = |p: usize| {
        DVec3::new(
            (p % width) as f64,
            ((p / width) % height) as f64,
            (p / (width * height)) as f64,
        )
    };
    let x: Vec<DVec3> = (0..n).map(|p| at(p) + DVec3::Y).collect();
    let v: Vec<DVec3> = (0..n)
        .map(|p| {
            let q = at(p);
            DVec3::new((q.y * 0.7).sin(), (q.z * 0.3).cos(), (q.x * 0.5).sin()) * 0.5
        })
        .collect();
    let mut kernel = LatticeKernel::new(spec.clone());
    kernel.set_threads(threads);
    assert_eq!(kernel.is_parallel(), threads > 1);
    kernel.set_simd_level(simd);
    kernel.set_pinned(7, true);
    kernel.set_state(&x, &v);
    kernel.set_update_velocities(&v);
    kernel.steps(2e-4, steps);
    let (mut x, mut v) = (vec![DVec3::ZERO; n], vec![DVec3::ZERO; n]);
    kernel.positions_into(&mut x);
    kernel.velocities_into(&mut v);
    (x, v)
}

#[test]
fn one_two_and_three_threads_give_identical_results() {
    // 21,168 particles: past `lattice::PARALLEL_MIN_PARTICLES`, 27 slabs cut into
    // bands that start mid-block; two threads hand over by spinning, three join.
    // The spring passes (XPBD, the stretch limit) split each sweep's lines; on a
    // lattice 3 wide, a line's lanes past its end reach several rows on.
    let shape = LatticeShape {
        width: 28,
        height: 28,
        depth: 27,
    };
    let narrow = LatticeShape {
        width: 3,
        height: 90,
        depth: 80,
    };
    for (shape, integrator, precision, stretch_limit) in [
        (shape, Integrator::SymplecticEuler, Precision::Mixed, None),
        (shape, Integrator::Verlet, Precision::Mixed, None),
        (shape, Integrator::SymplecticEuler, Precision::Double, None),
        (shape, Integrator::Xpbd, Precision::Single, None),
        (shape, Integrator::Xpbd, Precision::Mixed, None),
        (shape, Integrator::Verlet, Precision::Mixed, Some(0.001)),
        (narrow, Integrator::Xpbd, Precision::Mixed, None),
        (
            narrow,
            Integrator::SymplecticEuler,
            Precision::Mixed,
            Some(0.001),
        ),
    ] {
        let spec = LatticeSpec {
            precision,
            stretch_limit,
            ..spec(shape, integrator)
        };
        let simd = SimdLevel::detect();
        let one = kernel_run(&spec, 1, simd, 60);
        for threads in [2, 3] {
            let many = kernel_run(&spec, threads, simd, 60);
            assert!(
                one == many,
                "{shape:?} {integrator:?} {precision:?}: 1 and {threads} threads differ"
            );
        }
    }
}

#[test]
fn every_simd_level_agrees() {
    let shape = LatticeShape {
        width: 9,
        height: 7,
        depth: 6,
    };
    let specs = [
        ("springs", spec(shape, Integrator::SymplecticEuler)),
        ("xpbd", spec(shape, Integrator::Xpbd)),
        (
            "stretch limit",
            // Tight enough to bind in the shake.
            LatticeSpec {
                stretch_limit: Some(0.001),
                ..spec(shape, Integrator::SymplecticEuler)
            },
        ),
        (
            "springs in float64",
            LatticeSpec {
                precision: Precision::Double,
                ..spec(shape, Integrator::SymplecticEuler)
            },
        ),
        (
            "stretch limit in float64",
            LatticeSpec {
                precision: Precision::Double,
                stretch_limit: Some(0.001),
                ..spec(shape, Integrator::SymplecticEuler)
            },
        ),
    ];
    for (label, spec) in specs {
        let (reference, _) = kernel_run(&spec, 1, SimdLevel::Baseline, 200);
        for simd in [SimdLevel::Avx2, SimdLevel::Avx512] {
            let (x, _) = kernel_run(&spec, 1, simd, 200);
            let d = max_distance(&x, &reference);
            println!("{label}, {simd:?} against the portable lanes: {d:e} m");
            // The levels differ only in `1 / l` (a reciprocal square root estimate
            // and a Newton step against `1 / sqrt`): float32 round-off. Where the
            // stretch limit binds, that round-off of `1 - L' / l` moves a particle
            // by a few ulp of the 1 m spacing, once a step for each of its springs
            // corrected, without the springs' forces to pull the difference back:
            // up to `200 steps x 4 x 2^-23 m`.
            // In float64 (whose lanes differ in where a product and a sum are
            // fused) the same holds at float64's epsilon, 2^-29 of float32's.
            let bound = match spec.stretch_limit {
                Some(_) => 200.0 * 4.0 * f32::EPSILON as f64,
                None => 1e-5,
            };
            let bound = match spec.precision {
                Precision::Double => bound * f64::EPSILON / f32::EPSILON as f64,
                _ => bound,
            };
            assert!(
                d < bound,
                "{label}, {simd:?}: {d:e} m from the portable lanes"
            );
        }
    }
}

#[test]
fn a_stiff_jelly_does_not_heat_up_on_the_lattice_kernel() {
    // The jelly on the ground (its lowest corner touching it), stepped at
    // the safe step for each stiffness: the lattice kernel's kinetic energy must
    // follow the f64 engine's to 1% at every stiffness, down to the round-off of a
    // cube at rest. The precision rule has the stiff ones computed in float64,
    // and so XPBD's from k = 1e5 N/m, whose springs move their ends as springs
    // of stiffness up to `m / 2h²` would (on double-float positions, which fixed-
    // point ones replaced, with float32 arithmetic its kinetic energy came out
    // 2.3% off at k = 1e5).
    use cloth_sandbox::sim::safe;
    let mut engines = Vec::new();
    let stiffnesses = [(1e3, 0.1), (1e5, 0.1), (1e7, 0.1), (1e9, 1e-3)];
    // (XPBD from 1e7 N/m ran away on every engine at these steps while its pass
    // swept the lattice forward only, `constraints::xpbd_sweeps_back`.)
    let cases = (stiffnesses.iter().map(|&s| ("symplectic-euler", s)))
        .chain(stiffnesses.iter().map(|&s| ("xpbd", s)));
    for (integrator, (k, m)) in cases {
        let cube = cube(6);
        let overrides: Vec<String> = cube
            .into_iter()
            .chain([format!("stiffness={k}"), format!("particle_mass={m}")])
            .chain([format!("integrator=\"{integrator}\"")])
            .collect();
        let overrides: Vec<&str> = overrides.iter().map(String::as_str).collect();
        let ground = format!("ground_height={}", lowest(&build("jelly", &overrides)));
        let overrides: Vec<&str> = overrides.into_iter().chain([ground.as_str()]).collect();
        let mut exact = build("jelly", &overrides);
        let step = safe::safe_step(exact.model(), 1.0 / 60.0, safe::DEFAULT_SAFETY, 1 << 20);
        let mut params = *exact.params();
        params.dt = step.dt;
        exact.set_params(params);
        let mut fast = exact.clone();
        fast.set_fast_path(true);
        engines.push(fast.engine());
        for system in [&mut fast, &mut exact] {
            system.run(1000).unwrap();
        }
        let (fast, exact) = (fast.energy().kinetic, exact.energy().kinetic);
        let scale = 216.0 * m * 9.81 * 0.01;
        println!(
            "{integrator}, k = {k:e}, m = {m}: kinetic {fast:.4e} J (fast) vs {exact:.4e} J (f64)"
        );
        assert!(
            (fast - exact).abs() <= 0.01 * exact + 1e-12 * scale,
            "{integrator}, k = {k:e}: kinetic energy {fast:e} J against {exact:e} J"
        );
    }
    println!("engines: {engines:?}");
    assert_eq!(engines[0], Engine::Lattice(Precision::Mixed));
    assert_eq!(engines[3], Engine::Lattice(Precision::Double));
    assert_eq!(engines[4], Engine::Lattice(Precision::Mixed));
    assert_eq!(engines[5], Engine::Lattice(Precision::Double));
}

#[test]
fn what_the_lattice_kernel_does_not_model_runs_on_the_other_engines() {
    for (overrides, engine) in [
        (&["tear_strain=0.5"][..], Engine::General),
        (&["integrator=\"rk4\""][..], Engine::General),
    ] {
        let mut system = build("jelly", overrides);
        system.set_fast_path(true);
        assert_eq!(system.engine(), engine, "{overrides:?}");
        system.run(10).unwrap();
    }
    let mut system = build("jelly", &[]);
    system.set_fast_path(true);
    assert!(matches!(system.engine(), Engine::Lattice(_)));
    system.refuse_lattice_kernel(true);
    assert_eq!(system.engine(), Engine::General);
}

#[test]
fn a_big_stiff_jelly_runs_on_a_tight_fixed_point_unit() {
    // The jelly made 12³ at its k = 2,000 N/m, its lowest corner on the ground. At
    // the roomy fixed-point unit (twice its 9.5 m radius in a quarter of the
    // integers' range: 2^-24 m) the precision rule's noise is 0.1033 m/s², over the
    // limit, and it ran in float64; at the tight unit (`frame::fixed_unit`: 2^-26 m,
    // the radius with an eighth to spare in just under half the range) it is
    // 0.0917, and it runs on fixed-point positions, following the f64 engine within
    // the bound as it settles on the ground. XPBD takes the same unit: its
    // compliance softens the springs by only 1 + 2 k h² / m = 1.0016 at the jelly's
    // 0.2 ms steps. (Until 2026-11-27 XPBD kept the roomy unit, in float64.)
    let overrides = cube(12);
    let overrides: Vec<&str> = overrides.iter().map(String::as_str).collect();
    let ground = format!("ground_height={}", lowest(&build("jelly", &overrides)));
    for integrator in ["symplectic-euler", "xpbd"] {
        let integrator = format!("integrator={integrator}");
        let overrides: Vec<&str> = (overrides.iter().copied())
            .chain([ground.as_str(), integrator.as_str()])
            .collect();
        let system = build("jelly", &overrides);
        let mut fast = system.clone();
        fast.set_fast_path(true);
        assert_eq!(
            fast.engine(),
            Engine::Lattice(Precision::Mixed),
            "{integrator}"
        );
        let label = format!("12³ jelly on a tight unit, {integrator}");
        lattice_and_exact(&label, system, 600, |_| {});
    }
}

#[test]
fn a_jelly_spread_past_its_fixed_point_unit_goes_on_in_float64_until_it_draws_in() {
    // The 12³ jelly at k = 2,000 N/m is on its tight unit (2^-26 m: its radius with
    // an eighth to spare). Spread to five times its size it no longer fits, and a
    // kernel keeping fixed-point positions must double its unit, which puts the
    // precision rule's noise over the limit: the run goes on in float64, as the
    // rule would have chosen for a body that size, and so follows the f64 engine
    // to its round-off (on the doubled unit it was 1e-6 m off after 64 steps). Put
    // back, the jelly fits its unit again and returns to fixed point. (High up,
    // clear of the ground.)
    let overrides = cube(12);
    let overrides: Vec<&str> = (overrides.iter().map(String::as_str))
        .chain(["origin=0,100,0"])
        .collect();
    let mut system = build("jelly", &overrides);
    system.set_fast_path(true);
    let before = (system.engine(), system.precision_rule().unwrap());
    assert_eq!(before.0, Engine::Lattice(Precision::Mixed));
    assert_eq!(before.1.unit, 2f64.powi(-26));
    let run = spread_and_back(&mut system, 5.0, 64);
    println!("spread 5x: {run:?}");
    let (engine, rule) = run.spread;
    assert_eq!(engine, Engine::Lattice(Precision::Double));
    assert!(rule.fixed_point > Precision::NOISE_LIMIT && rule.unit > before.1.unit);
    assert!(run.apart < 1e-9, "{:e} m from the f64 engine", run.apart);
    assert_eq!(run.back, before);
}
