//! The `bench` scenes reproduce the peers' benchmark cloth: after 960 steps (1 s) at
//! N = 32 the mean y and the bottom-middle particle's y agree with the independent
//! float64 NumPy reference published in the peers' README.

use cloth_sandbox::scene::Scene;

fn after_one_second(name: &str) -> (f64, f64) {
    let mut system = Scene::load(name).unwrap().build().unwrap();
    system.run(960).unwrap();
    let ys: Vec<f64> = system.positions().iter().map(|p| p.y).collect();
    (ys.iter().sum::<f64>() / ys.len() as f64, ys[31 * 32 + 16])
}

#[test]
fn bench_matches_the_float64_reference() {
    let (mean, bottom) = after_one_second("bench");
    assert!((mean - -0.064685755).abs() < 1e-8, "mean y {mean}");
    assert!(
        (bottom - -0.656037594).abs() < 1e-8,
        "bottom-middle y {bottom}"
    );
}

#[test]
fn bench_wind_matches_the_float64_reference() {
    let (mean, bottom) = after_one_second("bench-wind");
    assert!((mean - 0.528073639).abs() < 1e-8, "mean y {mean}");
    assert!(
        (bottom - 0.193166128).abs() < 1e-8,
        "bottom-middle y {bottom}"
    );
}
