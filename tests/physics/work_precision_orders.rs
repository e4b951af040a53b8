//! The work-precision code on a tiny problem: observed orders of convergence come out
//! at the theoretical ones, so a broken integrator (or a broken order fit) fails here.

use cloth_sandbox::report::analytic::DampedOscillator;
use cloth_sandbox::report::hanging_spring;
use cloth_sandbox::report::precision::{Problem, Reference, measure, observed_order};
use cloth_sandbox::scene::Scene;
use cloth_sandbox::sim::Integrator;

#[test]
fn analytic_oscillator_satisfies_its_equation() {
    // u'' + 2 zeta w u' + w² u = 0 by central differences, in all three regimes.
    for zeta in [0.0, 0.1, 1.0, 2.5] {
        let o = DampedOscillator {
            omega0: 3.0,
            zeta,
            u0: 0.7,
            v0: -0.2,
        };
        assert!((o.displacement(0.0) - 0.7).abs() < 1e-12);
        let h = 1e-4;
        for t in [0.1, 0.5, 1.3] {
            let (a, b, c) = (
                o.displacement(t - h),
                o.displacement(t),
                o.displacement(t + h),
            );
            let (v, acc) = ((c - a) / (2.0 * h), (c - 2.0 * b + a) / (h * h));
            let residual = acc + 2.0 * zeta * 3.0 * v + 9.0 * b;
            assert!(residual.abs() < 1e-5, "zeta {zeta} t {t}: {residual}");
        }
        let v0 = (o.displacement(h) - o.displacement(-h)) / (2.0 * h);
        assert!((v0 + 0.2).abs() < 1e-6, "zeta {zeta}: v0 {v0}");
    }
}

#[test]
fn observed_orders_match_theory_on_the_spring() {
    let resolved = Scene::load("spring").unwrap().resolve().unwrap();
    let spring = hanging_spring(&resolved);
    let problem = Problem {
        name: "spring".into(),
        description: String::new(),
        end_time: 2.0,
        dts: (7..=10).map(|j| 2.0 * 0.5f64.powi(j)).collect(),
        scale: spring.oscillator().u0.abs(),
        scene: resolved,
        reference: Reference::Analytic(spring),
    };
    for integrator in Integrator::ALL {
        let points: Vec<_> = (problem.dts.iter())
            .map(|&dt| measure(&problem, integrator, dt, 1))
            .collect();
        let fit = observed_order("spring", integrator, &points, problem.scale, 1e-11);
        let observed = fit
            .observed
            .unwrap_or_else(|| panic!("{integrator}: no fit {points:?}"));
        assert!(
            (observed - integrator.order() as f64).abs() < 0.25,
            "{integrator}: observed order {observed:.3}, theory {}",
            integrator.order()
        );
    }
}
