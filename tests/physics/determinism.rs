//! Same scene and seed: bit-identical positions. Another seed: different gusts.

use cloth_sandbox::scene::Scene;

fn run(seed: u64, steps: u64) -> Vec<[u64; 3]> {
    let mut scene = Scene::load("flag").unwrap();
    scene.set("seed", &seed.to_string()).unwrap();
    let mut system = scene.build().unwrap();
    system.run(steps).unwrap();
    system
        .positions()
        .iter()
        .map(|p| p.to_array().map(f64::to_bits))
        .collect()
}

#[test]
fn same_seed_gives_bit_identical_positions() {
    assert_eq!(run(7, 400), run(7, 400));
}

#[test]
fn another_seed_gives_other_gusts() {
    assert_ne!(run(7, 400), run(8, 400));
}

#[test]
fn large_scenes_that_use_threads_are_deterministic_too() {
    // 128 x 128 has enough springs to take the multi-threaded force path.
    let build = || {
        let mut scene = Scene::load("cloth").unwrap();
        scene.set_all(["width=128", "height=128"]).unwrap();
        let mut system = scene.build().unwrap();
        system.run(20).unwrap();
        system.positions().to_vec()
    };
    assert_eq!(build(), build());
}

#[test]
fn the_energy_is_its_terms_summed_and_the_same_on_one_thread_or_two() {
    // 128 x 128 has enough springs for the energy's two halves to take two threads;
    // 400 steps of a fall in the wind, onto a ground, leave every term nonzero.
    let mut scene = Scene::load("cloth").unwrap();
    scene
        .set_all([
            "width=128",
            "height=128",
            "ground_height=-0.5",
            "ground_stiffness=200",
        ])
        .unwrap();
    let mut system = scene.build().unwrap();
    system.run(400).unwrap();
    let (model, x, v) = (system.model(), system.positions(), system.velocities());
    let on = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| model.energy(x, v))
    };
    let (one, two) = (on(1), on(2));
    assert_eq!(
        [one.kinetic, one.gravity, one.elastic].map(f64::to_bits),
        [two.kinetic, two.gravity, two.elastic].map(f64::to_bits)
    );
    // The terms as the module docs define them, summed one by one.
    let (mut kinetic, mut gravity, mut elastic) = (0.0, 0.0, 0.0);
    let p = model.params;
    for i in 0..x.len() {
        if model.inv_mass[i] > 0.0 {
            kinetic += 0.5 * model.mass[i] * v[i].length_squared();
            gravity -= model.mass[i] * p.gravity.dot(x[i]) + p.force.dot(x[i]);
            if let Some(g) = p.ground {
                elastic += 0.5 * g.stiffness * (g.height - x[i].y).max(0.0).powi(2);
            }
        }
    }
    for s in &model.springs {
        let stretch = x[s.a as usize].distance(x[s.b as usize]) - s.rest;
        elastic += 0.5 * model.material(s.kind).stiffness * stretch * stretch;
    }
    for (name, got, want) in [
        ("kinetic", one.kinetic, kinetic),
        ("gravity", one.gravity, gravity),
        ("elastic", one.elastic, elastic),
    ] {
        assert!(want.abs() > 0.0, "{name} is zero: nothing is tested");
        let error = (got - want).abs() / want.abs();
        assert!(error < 1e-12, "{name}: {got} against {want} ({error:e})");
    }
}
