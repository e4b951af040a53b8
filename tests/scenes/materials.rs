//! Cloth materials (`material = "cotton"`): a mass per area, a stretch stiffness
//! and a damping that hold at any spacing, so that a cloth refined over the same
//! size hangs as the coarser one does, where keeping the per-particle mass does
//! not; what a material fills and what the scene keeps; its errors.

use cloth_sandbox::scene::{MATERIALS, Scene};
use cloth_sandbox::sim::System;

/// The built-in hanging cloth (1.55 m square, corners pinned) in still air, of
/// `material`, `side` particles square, with `more` settings after it.
fn hanging(material: &str, side: u32, more: &[&str]) -> System {
    let mut scene = Scene::load("cloth").unwrap();
    let side = format!("{side}");
    let mut sets = vec![
        ("material", material),
        ("wind", "0,0,0"),
        ("gust", "0"),
        ("dt", "0.00025"),
        ("width", &side),
        ("height", &side),
    ];
    for kv in more {
        let (k, v) = kv.split_once('=').unwrap();
        sets.push((k, v));
    }
    for (k, v) in sets {
        scene.set(k, v).unwrap();
    }
    scene.build().unwrap()
}

/// The mean height (m) and the lowest point of a system's particles.
fn mean_and_lowest(system: &System) -> (f64, f64) {
    let ys = system.positions().iter().map(|p| p.y);
    let n = system.positions().len() as f64;
    let mean = ys.clone().sum::<f64>() / n;
    (mean, ys.fold(f64::INFINITY, f64::min))
}

/// A hanging cloth's stretch under its own weight goes with `ρ_A g / k` (strain
/// `ρ_A g y / k` at depth `y`), not with its spacing: 64 x 64 cotton over the same
/// 1.55 m hangs as 32 x 32 cotton does. The 64² cloth with the 32²'s particle
/// mass (four times the mass per area, as a per-particle mass keeps it) stretches
/// about four times as far. Air damping in proportion to the mass settles each
/// cloth in its rest shape within the 3 s.
#[test]
fn a_finer_cotton_hangs_like_the_coarser() {
    let settled = |side: u32, mass: Option<f64>| {
        let probe = hanging("cotton", side, &[]);
        let m = mass.unwrap_or(probe.masses()[1]);
        let (mass, damping) = (
            format!("particle_mass={m}"),
            format!("air_damping={}", 5.0 * m),
        );
        let mut s = hanging("cotton", side, &[&mass, &damping]);
        s.run(12_000).unwrap();
        assert!(
            s.energy().kinetic < 1e-4,
            "settled: {} J",
            s.energy().kinetic
        );
        mean_and_lowest(&s)
    };
    let coarse = settled(32, None);
    let fine = settled(64, None);
    let heavy = settled(64, Some(hanging("cotton", 32, &[]).masses()[1]));
    let top = 1.55;
    let drop = |(mean, _): (f64, f64)| top - mean;
    // The cloth is 1.55 m tall: what hangs lower is stretch.
    let stretch = |(_, low): (f64, f64)| top - low - 1.55;
    eprintln!(
        "mean drop: 32² {:.4} m, 64² {:.4} m, 64² heavy {:.4} m",
        drop(coarse),
        drop(fine),
        drop(heavy)
    );
    eprintln!(
        "stretch: 32² {:.4} m, 64² {:.4} m, 64² heavy {:.4} m",
        stretch(coarse),
        stretch(fine),
        stretch(heavy)
    );
    let rel = |a: f64, b: f64| (a - b).abs() / b;
    assert!(
        rel(drop(fine), drop(coarse)) < 0.01,
        "mean drop {:?} vs {:?}",
        fine,
        coarse
    );
    assert!(
        rel(stretch(fine), stretch(coarse)) < 0.2,
        "stretch {:?} vs {:?}",
        fine,
        coarse
    );
    let heavier = stretch(heavy) / stretch(fine);
    assert!(
        (3.0..5.0).contains(&heavier),
        "the heavy cloth stretches {heavier} times as far"
    );
}

/// Each material's particles weigh its mass per area times the cloth's area
/// (31 x 31 cells of 5 cm) over its 1,024 particles, and its springs take its
/// stiffness, damping and scales.
#[test]
fn a_material_gives_its_values() {
    for m in &MATERIALS {
        let r = {
            let mut scene = Scene::load("cloth").unwrap();
            scene.set("material", m.name).unwrap();
            scene.resolve().unwrap()
        };
        let area = 31.0 * 31.0 * 0.05 * 0.05;
        let expected = m.areal_density * area / 1024.0;
        assert!((r.particle_mass - expected).abs() < 1e-15, "{}", m.name);
        assert_eq!(r.stiffness, m.stiffness, "{}", m.name);
        assert_eq!(r.damping, m.damping, "{}", m.name);
        assert_eq!((r.shear_scale, r.bend_scale), (m.shear_scale, m.bend_scale));
        assert_eq!(r.params.drag_coefficient, m.drag_coefficient, "{}", m.name);
        assert!(
            (r.rest_length - 0.05).abs() < 1e-15,
            "the cloth keeps its size"
        );
    }
}

/// In a scene file the scene's own keys hold next to its material; `--set
/// material` replaces them; the file written back keeps the material.
#[test]
fn a_scene_keeps_its_own_keys_and_saves_its_material() {
    let text = "layout = \"grid\"\nwidth = 8\nheight = 8\nrest_length = 0.1\nmaterial = \"denim\"\nstiffness = 150.0\n";
    let scene = Scene::parse(text, "test.toml").unwrap();
    let r = scene.resolve().unwrap();
    assert_eq!(r.stiffness, 150.0);
    assert_eq!(r.damping, 0.03);
    assert!((r.particle_mass - 0.4 * 0.49 / 64.0).abs() < 1e-15);

    let mut scene = Scene::load("cloth").unwrap();
    assert_eq!(scene.resolve().unwrap().stiffness, 100.0);
    scene.set("material", "leather").unwrap();
    assert_eq!(scene.resolve().unwrap().stiffness, 600.0);
    let written = toml::to_string(&scene.spec).unwrap();
    assert!(written.contains("material = \"leather\""), "{written}");
    let again = Scene::parse(&written, "written.toml").unwrap();
    assert_eq!(again.resolve().unwrap(), scene.resolve().unwrap());
}

/// Wrong materials are refused with the allowed names or the reason, and the
/// scene is unchanged.
#[test]
fn bad_materials_are_refused_in_plain_words() {
    let mut scene = Scene::load("cloth").unwrap();
    let err = scene.set("material", "wool").unwrap_err().to_string();
    assert!(
        err.contains("\"wool\" is not a material: give one of \"silk\", \"cotton\""),
        "{err}"
    );
    assert_eq!(scene.spec.material, None);
    let mut jelly = Scene::load("jelly").unwrap();
    let err = jelly.set("material", "silk").unwrap_err().to_string();
    assert!(err.contains("only a grid or mesh cloth"), "{err}");
    let mut chain = Scene::load("chain").unwrap();
    let err = chain.set("areal_density", "0.2").unwrap_err().to_string();
    assert!(err.contains("give `particle_mass`"), "{err}");
    let text = "layout = \"grid\"\nparticle_mass = 0.01\nareal_density = 0.2\n";
    let err = Scene::parse(text, "t.toml").unwrap_err().to_string();
    assert!(err.contains("conflicts with"), "{err}");
}
