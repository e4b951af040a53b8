//! Self-collision (`sim::self_collision`): a cloth's particles that no spring joins
//! keep the contact thickness `h_c` apart, so that its layers fold onto each other
//! instead of passing through.
//!
//! The measure: after the cloth settles, the pairs of particles not joined by a
//! spring that are closer than `h_c / 2`. Without self-collision the layers pass
//! through each other and many pairs are that close.

use crate::common;

use crate::common::build;
use cloth_sandbox::sim::System;

/// Pairs of particles not joined by a spring closer than `distance`, by brute force
/// (independent of the pass's spatial hash).
fn close_pairs(system: &System, distance: f64) -> usize {
    let x = system.positions();
    let model = system.model();
    let mut count = 0;
    for i in 0..x.len() {
        for j in i + 1..x.len() {
            if x[i].distance(x[j]) < distance && !model.adjacency().joins(&model.springs, i, j) {
                count += 1;
            }
        }
    }
    count
}

fn settled(scene: &str, overrides: &[&str], fast: bool, steps: u64) -> System {
    let mut system = build(scene, overrides);
    system.set_fast_path(fast);
    system.run(steps).unwrap();
    system
}

#[test]
fn folded_layers_keep_their_thickness_apart() {
    // The fold scene: the cloth slides off a small frictionless sphere and piles
    // onto the ground (5 s). The pile is chaotic, and the grid engine's round-off
    // differs between SIMD levels (when the cloth started centred over the sphere,
    // 247 pairs crossed on an AVX2 machine, 49 with AVX-512, none on the f64
    // engine); the scene now starts off-centre, and the count without
    // self-collision is taken on the f64 engine, the same on every machine (146).
    let without = settled("fold", &["self_collision=false"], false, 4800);
    let h_c = without.params().thickness;
    let crossed = close_pairs(&without, h_c / 2.0);
    println!("without self-collision: {crossed} pairs closer than h_c / 2");
    assert!(crossed > 100, "{crossed}");
    for fast in [true, false] {
        let with = settled("fold", &[], fast, 4800);
        let close = close_pairs(&with, h_c / 2.0);
        println!("with self-collision (fast {fast}): {close} pairs closer than h_c / 2");
        assert_eq!(close, 0, "fast {fast}");
    }
}

#[test]
fn the_drape_without_friction_no_longer_ends_in_crossed_layers() {
    // The case that crossed its layers: the drape at 64 x 64 after 4000 steps, which slid off its
    // frictionless sphere into crossed layers (615 pairs closer than half the
    // spacing at the time, measured before friction and self-collision).
    let overrides = ["width=64", "height=64", "friction=0"];
    let without = settled(
        "drape",
        &[&overrides[..], &["self_collision=false"]].concat(),
        true,
        4000,
    );
    let half_spacing = 0.025;
    let crossed = close_pairs(&without, half_spacing);
    let with = settled("drape", &overrides, true, 4000);
    let close = close_pairs(&with, with.params().thickness / 2.0);
    println!("drape 64: {crossed} pairs closer than half the spacing without, {close} with");
    assert!(crossed > 100, "{crossed}");
    assert_eq!(close, 0);
}

#[test]
fn the_engines_agree_with_self_collision() {
    // The same pass on f64 copies of the grid engine's positions. A thickness of
    // 2.3 spacings keeps the nearest unjoined pairs (a knight's move apart, 2.24
    // spacings) in contact from the start, so the pass works on every step of a
    // smooth motion: the hanging cloth in still air, one simulated second. (At 2.5
    // spacings the pass and the springs fight over the cloth's own rest shape and
    // the motion turns chaotic on both engines: see the module's limits.)
    let spacing = build("cloth", &[]).model().springs[0].rest;
    let overrides = [
        "wind=\"0,0,0\"".to_string(),
        "gust=0".to_string(),
        "self_collision=true".to_string(),
        format!("thickness={}", 2.3 * spacing),
    ];
    let overrides: Vec<&str> = overrides.iter().map(String::as_str).collect();
    let (mut fast, mut exact) = (build("cloth", &overrides), build("cloth", &overrides));
    fast.set_fast_path(true);
    assert!(fast.engine().is_grid());
    exact.set_fast_path(false);
    let start = exact.positions().to_vec();
    fast.run(960).unwrap();
    exact.run(960).unwrap();
    let contacts = (
        fast.self_collision_contacts(),
        exact.self_collision_contacts(),
    );
    let apart = common::max_distance(fast.positions(), exact.positions());
    let moved = common::max_distance(&start, exact.positions());
    println!("apart {apart:e} m after moving {moved:.3} m, contacts {contacts:?}");
    assert!(contacts.0 > 100 && contacts.0 == contacts.1, "{contacts:?}");
    assert!(apart < 1e-5, "{apart}");
}

/// On a topology other than a grid: the tablecloth (a triangle mesh) draping over
/// its sphere into folds, and its layers meet.
#[test]
fn the_tablecloth_folds_onto_itself() {
    // Without the air's drag the cloth falls faster and folds within the 2 s.
    let mut system = build("tablecloth", &["self_collision=true", "drag_coefficient=0"]);
    let mut most = 0;
    for _ in 0..12 {
        system.run(160).unwrap();
        most = most.max(system.self_collision_contacts());
    }
    println!("at most {most} pairs in contact");
    assert!(most > 5, "{most}");
}

/// The pass on two threads gives the result of one, bit for bit, on both engines:
/// the grid kernel on its own pool (`GridCloth::set_threads`), the f64 engine in
/// `System::run`'s scope on the pool it is run in. Each run ends with pairs in
/// contact, so the list, its rebuilds and the pushes all count.
#[test]
fn one_and_two_threads_give_bit_identical_results() {
    use cloth_sandbox::sim::grid_kernel::{GridCloth, GridSpec, Precision};
    use glam::DVec3;

    // The grid kernel: the peers' 64 x 64 cloth hanging in a gusty wind, with a
    // thickness of 2.3 spacings (in contact from the start, as in the test above).
    let grid = |threads: usize| {
        let mut spec = GridSpec::peer_bench(64, true);
        spec.precision = Precision::Mixed;
        spec.self_collision = Some(2.3 * spec.spacing);
        spec.friction = 0.5;
        let mut cloth = GridCloth::new(spec);
        cloth.set_threads(threads);
        cloth.steps(1.0 / 960.0, 300);
        let mut x = vec![DVec3::ZERO; cloth.len()];
        cloth.positions_into(&mut x);
        let mut v = x.clone();
        cloth.velocities_into(&mut v);
        (x, v, cloth.self_collision_contacts(), cloth.is_parallel())
    };
    let (one, two) = (grid(1), grid(2));
    println!("grid kernel: {} contacts", one.2);
    assert!(two.3 && !one.3);
    assert!(one.2 > 100, "{}", one.2);
    assert!(one.0 == two.0 && one.1 == two.1 && one.2 == two.2);

    // The f64 engine: the fold scene at 64 x 64 (enough springs for its threads)
    // landing in folds on the ground.
    let exact = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            let system = settled("fold", &["width=64", "height=64"], false, 1500);
            let contacts = system.self_collision_contacts();
            (
                system.positions().to_vec(),
                system.velocities().to_vec(),
                contacts,
            )
        })
    };
    let (one, two) = (exact(1), exact(2));
    println!("f64 engine: {} contacts", one.2);
    assert!(one.2 > 10, "{}", one.2);
    assert!(one.0 == two.0 && one.1 == two.1 && one.2 == two.2);
}

/// Bars join their particles as springs do: self-collision leaves the rope's
/// neighbours (0.1 m apart on their bars) alone at a thickness of 0.15 m, where it
/// had pushed them apart against the bars every step and pumped the rope to about
/// 13 kJ in 3,000 steps. The rope swinging from its end holds a few joules (its
/// 1.2 kg falling its 2.3 m length: 27 J at most).
#[test]
fn self_collision_leaves_the_particles_a_bar_joins_alone() {
    for fast in [false, true] {
        let mut rope = build("rope", &["self_collision=true", "thickness=0.15"]);
        rope.set_fast_path(fast);
        rope.run(3000).unwrap();
        let kinetic = rope.energy().kinetic;
        assert!(kinetic < 27.0, "fast {fast}: {kinetic} J");
        assert!(rope.model().joins(3, 4) && rope.model().joins(4, 3) && !rope.model().joins(3, 5));
    }
}
