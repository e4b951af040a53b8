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
