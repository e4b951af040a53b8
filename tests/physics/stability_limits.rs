//! Measured critical steps agree with theory (within 10%) for symplectic Euler,
//! Verlet and RK4 on the undamped spring and chain; implicit Euler survives the stiff
//! cloth at 100 times symplectic Euler's limit; air damping alone sets the limit its
//! decay derives for every explicit integrator, on both engines.

use cloth_sandbox::report::stability::{
    Measured, Theory, critical_dt, is_stable, reference_energy,
};
use cloth_sandbox::report::{cloth_undamped, eigen};
use cloth_sandbox::scene::{Resolved, Scene};
use cloth_sandbox::sim::Integrator;

use crate::common;

fn scene(name: &str, overrides: &[&str]) -> Resolved {
    let mut scene = Scene::load(name).unwrap();
    scene.set_all(overrides.iter().copied()).unwrap();
    scene.resolve().unwrap()
}

fn check_case(name: &str, overrides: &[&str]) {
    let s = scene(name, overrides);
    let theory = Theory::of(&s);
    let horizon = 1000.0 * 2.0 / theory.omega_exact;
    let energy = reference_energy(&s, theory.omega_exact, horizon);
    for integrator in [
        Integrator::SymplecticEuler,
        Integrator::Verlet,
        Integrator::Rk4,
    ] {
        let expected = theory.exact(integrator).unwrap();
        let measured = critical_dt(&s, integrator, expected, horizon, energy, (64.0, 256.0), 8);
        let Measured::Between { lo, .. } = measured else {
            panic!("{name} {integrator}: no limit bracketed: {measured:?}");
        };
        let ratio = lo / expected;
        assert!(
            (0.9..=1.1).contains(&ratio),
            "{name} {integrator}: measured {lo:e} s, theory {expected:e} s (ratio {ratio:.3})"
        );
    }
}

#[test]
fn spring_critical_dt_matches_theory() {
    check_case("spring", &["damping=0"]);
}

/// The chain loaded along its length stays straight, so the linearisation at the
/// start holds throughout. (Falling sideways, its pendulum motion modulates the
/// springs and symplectic Euler and Verlet go unstable earlier, near
/// `omega h = sqrt 2`: a nonlinear resonance the report shows, not a linear limit.)
#[test]
fn chain_critical_dt_matches_theory() {
    check_case(
        "chain",
        &[
            "damping=0",
            "air_damping=0",
            "gravity=9.81,0,0",
            "stiffness=1000",
        ],
    );
}

#[test]
fn spring_power_iteration_finds_sqrt_k_over_m() {
    // One free mass on a spring stretched along y: the highest mode is the axial one,
    // omega² = k/m (the transverse one is k (1 - L/l) / m).
    let s = scene("spring", &[]);
    let system = s.build();
    let p = eigen::omega_max(system.model(), system.positions(), 10_000, 1e-12);
    let exact = (s.stiffness / s.particle_mass).sqrt();
    assert!((p.omega_max / exact - 1.0).abs() < 1e-9, "{p:?} vs {exact}");
}

#[test]
fn implicit_euler_is_stable_on_the_stiff_cloth_at_100x_the_symplectic_limit() {
    let mut o = cloth_undamped(8);
    o.push("stiffness=1e6".into());
    let s = scene("cloth", &o.iter().map(String::as_str).collect::<Vec<_>>());
    let theory = Theory::of(&s);
    let symplectic = theory.exact(Integrator::SymplecticEuler).unwrap();
    // The symplectic limit is real: 10% above it symplectic Euler blows up.
    let horizon = 500.0 * symplectic;
    let e = reference_energy(&s, theory.omega_exact, horizon);
    assert!(is_stable(
        &s,
        Integrator::SymplecticEuler,
        0.9 * symplectic,
        horizon,
        e
    ));
    assert!(!is_stable(
        &s,
        Integrator::SymplecticEuler,
        1.1 * symplectic,
        horizon,
        e
    ));
    // 100 times that, over the same horizon and at least 20 steps.
    assert!(is_stable(
        &s,
        Integrator::ImplicitEuler,
        100.0 * symplectic,
        horizon,
        e
    ));
}

/// Checks that `overrides` of the spring scene, with `integrator`, stay finite for
/// `steps` steps at 0.95 of the estimated critical step and diverge at 1.05, on the
/// general and on the fast engine; returns the estimate and the free mass.
fn check_limit_brackets(overrides: &[&str], integrator: Integrator, steps: u64) -> (f64, f64) {
    use cloth_sandbox::sim::stability::estimate;
    let integrator_set = format!("integrator=\"{integrator}\"");
    let all: Vec<&str> = overrides
        .iter()
        .copied()
        .chain([integrator_set.as_str()])
        .collect();
    let system = common::build("spring", &all);
    let model = system.model();
    let free = (model.inv_mass.iter().zip(&model.mass)).find(|(w, _)| **w > 0.0);
    let m = *free.expect("a free particle").1;
    let limit = estimate(model).dt_critical.expect("a stable step");
    for fast in [false, true] {
        for (factor, stable) in [(0.95, true), (1.05, false)] {
            let mut system = common::build("spring", &all);
            system.set_fast_path(fast);
            let mut params = *system.params();
            params.dt = factor * limit;
            system.set_params(params);
            let run = system.run(steps);
            assert_eq!(
                run.is_ok(),
                stable,
                "{overrides:?} {integrator} (fast engine: {fast}) at {factor} of {limit:e} s: {:?}",
                run.err()
            );
        }
    }
    (limit, m)
}

/// Air damping alone: the spring scene with its spring's stiffness at 0 is a mass
/// falling under gravity against the drag `-c v`, whose homogeneous part decays as
/// `v' = -(c/m) v`. One step of `g = c h / m` multiplies it by `1 - g` (the Euler
/// methods and XPBD's prediction), `1 - g + g²/2` (RK2) or the fourth-order Taylor
/// polynomial at `-g` (RK4), which stay within 1 up to `g = 2`, 2 and 2.7853; position
/// Verlet, whose velocity is `(x - x_prev)/h + h/2 a_prev`, only up to `g = 1` (its
/// two-step recurrence reaches an eigenvalue of -1 there). The estimate must give
/// those limits (it gave none: nothing oscillates), and each engine must stay finite
/// for 3,000 steps at 0.95 of the limit and diverge at 1.05.
#[test]
fn air_damping_alone_sets_the_critical_step_of_each_integrator() {
    let c = 1000.0;
    for (integrator, g) in [
        (Integrator::SymplecticEuler, 2.0),
        (Integrator::ExplicitEuler, 2.0),
        (Integrator::Xpbd, 2.0),
        (Integrator::Rk2, 2.0),
        (Integrator::Rk4, 2.785_293_563_405_282),
        (Integrator::Verlet, 1.0),
    ] {
        let air = format!("air_damping={c}");
        let (limit, m) = check_limit_brackets(&["stiffness=0", &air], integrator, 3000);
        let expected = g * m / c;
        assert!(
            (limit / expected - 1.0).abs() < 1e-9,
            "{integrator}: estimated {limit:e} s, derived {expected:e} s"
        );
    }
}

/// A heavily damped spring between two free masses (the Gershgorin bound is then
/// the pair's own frequency, `2k/m`): position Verlet's damping sees the velocity
/// half a step late, so its limit is about half symplectic Euler's (it had been
/// estimated as equal, and diverged at 0.55 of it). Both estimates must bracket
/// the runs: finite for 2,000 steps at 0.95, diverging at 1.05.
#[test]
fn damped_verlet_reaches_its_limit_before_symplectic_euler() {
    let pair = ["pins=[]", "damping=100"];
    let (symplectic, _) = check_limit_brackets(&pair, Integrator::SymplecticEuler, 2000);
    let (verlet, _) = check_limit_brackets(&pair, Integrator::Verlet, 2000);
    let ratio = verlet / symplectic;
    assert!(
        (0.45..0.55).contains(&ratio),
        "Verlet / symplectic: {ratio}"
    );
}

/// The wind's drag on light particles. Implicit Euler solves for the springs but
/// steps the drag explicitly, as XPBD's prediction does, and the estimate gave
/// both no limit: the cloth at the panel's lightest mass, 1e-6 kg, ran away at
/// its step with safe stepping taking one substep. The drag, linearised, is the
/// decay `ρ C_d A s / m` plus `sqrt(2 ρ C_d A g / m)` (the fall through still air),
/// with `A = L²` an inner particle's share of the grid's triangles and `s` the
/// strongest wind, `|wind| + gust`; explicit Euler's step on it is stable up to
/// `2 / gamma`. The estimate must give that; each integrator must run 5,000 steps
/// at 0.95 of it and one simulated second at the substeps safe stepping takes, and
/// run away at the scene's step.
#[test]
fn drag_on_light_particles_limits_implicit_euler_and_xpbd() {
    use cloth_sandbox::sim::safe::{DEFAULT_SAFETY, safe_step};
    use cloth_sandbox::sim::stability::estimate;
    for integrator in [Integrator::ImplicitEuler, Integrator::Xpbd] {
        let set = format!("integrator=\"{integrator}\"");
        let light = || {
            let mut system = common::build("cloth", &["particle_mass=1e-6", &set]);
            system.set_fast_path(true);
            system
        };
        let system = light();
        let p = *system.params();
        let rho_cd_a = p.air_density * p.drag_coefficient * 0.05 * 0.05;
        let (wind, gust) = (glam::DVec3::new(0.5, 0.0, 2.0).length(), 1.0);
        let gamma =
            rho_cd_a * (wind + gust) / 1e-6 + (2.0 * rho_cd_a * p.gravity.length() / 1e-6).sqrt();
        let limit = estimate(system.model()).dt_critical.expect("a stable step");
        assert!(
            (limit * gamma / 2.0 - 1.0).abs() < 1e-6,
            "{integrator}: estimated {limit:e} s, derived {:e} s",
            2.0 / gamma
        );
        let run = |dt: f64, steps: u64| {
            let mut system = light();
            let mut params = *system.params();
            params.dt = dt;
            system.set_params(params);
            system.run(steps)
        };
        assert!(run(p.dt, 960).is_err(), "{integrator} at the scene's step");
        run(0.95 * limit, 5000).unwrap_or_else(|e| panic!("{integrator} at 0.95: {e}"));
        let safe = safe_step(system.model(), p.dt, DEFAULT_SAFETY, 100_000);
        assert!(safe.safe && safe.substeps > 1, "{integrator}: {safe:?}");
        let steps = (1.0 / safe.dt).ceil() as u64;
        run(safe.dt, steps).unwrap_or_else(|e| panic!("{integrator} safe: {e}"));
    }
}

/// The peers' windy cloth at 8 x 8, with gravity off and springs too soft to
/// bind: its step limit is the drag's.
fn drag_bound_cloth() -> cloth_sandbox::sim::System {
    let mut scene = Scene::load("bench-wind").unwrap();
    let overrides = [
        "width=8",
        "height=8",
        "gravity=0,0,0",
        "stiffness_per_mass=1",
        "damping_per_mass=0",
    ];
    scene.set_all(overrides).unwrap();
    scene.build().unwrap()
}

/// The drag's step limit on a running cloth is taken on its triangles' areas now:
/// at rest it is the estimate's; stretched `s` times along its height, each inner
/// particle's share of the area is `s L²` (six triangles of `L² / 2`, a third each),
/// and with gravity off and the springs too soft to bind, the limit is symplectic
/// Euler's on the decay `gamma = rho C_d A |wind| / m`: `h = 2 / gamma`.
#[test]
fn the_drag_limit_follows_the_areas_a_cloth_is_stretched_to() {
    use cloth_sandbox::sim::stability::{dt_critical_at, estimate};
    let system = drag_bound_cloth();
    let model = system.model();
    let at_rest = estimate(model).dt_critical;
    let rest = system.positions().to_vec();
    let same = dt_critical_at(model, &rest, at_rest).unwrap();
    assert!(
        (same / at_rest.unwrap() - 1.0).abs() < 1e-12,
        "{same} {at_rest:?}"
    );
    let (m, l, wind, rho_cd) = (1.0 / 64.0, 1.0 / 7.0, 5.0, 1.2);
    for s in [4.0, 16.0] {
        let top = rest.iter().map(|p| p.y).fold(f64::MIN, f64::max);
        let stretched: Vec<_> = (rest.iter())
            .map(|p| glam::DVec3::new(p.x, top + s * (p.y - top), p.z))
            .collect();
        let limit = dt_critical_at(model, &stretched, at_rest).unwrap();
        let expected = 2.0 * m / (rho_cd * s * l * l * wind);
        assert!(
            expected < at_rest.unwrap() && (limit / expected - 1.0).abs() < 1e-9,
            "stretched {s}x: {limit} s, expected {expected} s (at rest {at_rest:?})"
        );
    }
}

/// A running system keeps its drag areas at rest across edits of its coefficients
/// (finding them is most of the estimate's work on a grid), so its estimate must
/// find them again where they change: a rest-length edit (areas times the factor
/// squared) and cut springs (the triangles along them go). Each time the system's
/// own estimate must equal one made from scratch, and the drag must have moved it.
#[test]
fn the_systems_estimate_follows_rest_length_edits_and_cut_springs() {
    use cloth_sandbox::sim::SpringKind;
    use cloth_sandbox::sim::stability::estimate;
    let mut system = drag_bound_cloth();
    let limit = |system: &cloth_sandbox::sim::System| {
        let own = system.stability().dt_critical.unwrap();
        let fresh = estimate(system.model()).dt_critical.unwrap();
        assert_eq!(own, fresh, "the system's estimate against one from scratch");
        own
    };
    let start = limit(&system);
    // A stiffness edit keeps the areas, and the drag's limit with them.
    system.set_spring_stiffness(SpringKind::Structural, 1e-3);
    assert_eq!(limit(&system), start);
    system.scale_rest_lengths(2.0);
    let longer = limit(&system);
    assert!(longer < 0.3 * start, "{longer} s against {start} s before");
    // Every horizontal spring below the top row cut: each triangle has one, so only
    // the top row's upper triangles are left, and the most area a particle has is a
    // third of an inner particle's before.
    let pairs: Vec<(usize, usize)> = (1..8)
        .flat_map(|r| (0..7).map(move |c| (8 * r + c, 8 * r + c + 1)))
        .collect();
    assert!(system.cut(&pairs) > 0);
    assert!(!system.triangles().is_empty());
    let cut = limit(&system);
    assert!(
        cut > 2.0 * longer,
        "{cut} s against {longer} s before the cut"
    );
}
