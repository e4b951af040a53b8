//! The seed documents' scenes and controls, headless: seed 002's hanging cloth with
//! the numbers the seed gives, seed 000's cloth pinned at its four corners, the
//! panel's pin presets and "unpin all", and seed 004's wind switch. Expected values
//! are derived from the seed text, not read back from the scene files.

use cloth_sandbox::scene::{PinPreset, Pins, Scene, SceneError};
use cloth_sandbox::session::{DEFAULT_WIND, Edit, Session};
use cloth_sandbox::sim::SpringKind;
use glam::DVec3;

use crate::common;

fn count(session: &Session, kind: SpringKind) -> usize {
    session
        .system()
        .springs()
        .iter()
        .filter(|s| s.kind == kind)
        .count()
}

#[test]
fn seed_002_hanging_cloth_has_the_seeds_numbers() {
    // "15 masses in the x direction ... 8 masses in the y direction ... mass m to be
    // 0.1, and each mass to be a length of 1 apart ... k of 100 ... 10% of the
    // critical dampening constant [2 sqrt(k m)] ... time step ... 0.0002".
    let (w, h, m, k) = (15_usize, 8_usize, 0.1, 100.0);
    let s = Session::load_with("hanging", &[]).expect("the hanging cloth loads");
    let r = s.settings();
    assert_eq!((r.width as usize, r.height as usize), (w, h));
    assert_eq!(r.particle_mass, m);
    assert_eq!(r.rest_length, 1.0);
    assert_eq!(r.stiffness, k);
    let critical = 2.0 * (k * m).sqrt();
    assert!(
        (r.damping - 0.1 * critical).abs() <= 1e-15,
        "damping {} vs 10% of critical {}",
        r.damping,
        0.1 * critical
    );
    assert_eq!(r.params.dt, 0.0002);
    // Still air: no wind, no gusts, no aerodynamic drag; seed 002's viscous air
    // damping (0.05, "all further force calculations ... as described for
    // Simulations 1 and 2").
    assert_eq!(r.params.wind, DVec3::ZERO);
    assert_eq!(r.params.gust, 0.0);
    let terms = s.system().force_terms();
    assert!(!terms.aero, "still air has no aero drag");
    assert!(terms.air_damping && r.params.air_damping == 0.05);
    assert_eq!(r.params.gravity, DVec3::new(0.0, -9.81, 0.0));
    // Structural: neighbours along x and y; shear: both diagonals of every cell;
    // bend: two apart along x and y.
    assert_eq!(s.system().particle_count(), w * h);
    assert_eq!(count(&s, SpringKind::Structural), (w - 1) * h + w * (h - 1));
    assert_eq!(count(&s, SpringKind::Shear), 2 * (w - 1) * (h - 1));
    assert_eq!(count(&s, SpringKind::Bend), (w - 2) * h + w * (h - 2));
    // Every spring's rest length is the distance between its ends at the start.
    let x = s.system().positions();
    for sp in s.system().springs() {
        let d = x[sp.a as usize].distance(x[sp.b as usize]);
        assert!((d - sp.rest).abs() < 1e-12, "{sp:?}");
    }
}

#[test]
fn the_hanging_cloth_hangs_for_two_seconds_without_diverging() {
    let mut s = Session::load_with("hanging", &[]).expect("loads");
    let steps = (2.0 / s.system().params().dt).round() as u32;
    for _ in 0..steps / 100 {
        for _ in 0..100 {
            s.single_step();
        }
        assert!(s.divergence().is_none(), "{:?}", s.divergence());
        assert!(s.system().positions().iter().all(|p| p.is_finite()));
    }
    // It fell from its flat start: the bottom row is below where it began.
    let (w, h) = (15, 8);
    let bottom = s.system().positions()[(h - 1) * w + w / 2].y;
    assert!(bottom < 0.0 - 1e-3, "bottom middle at y = {bottom}");
}

#[test]
fn seed_000_cloth_is_pinned_at_its_four_corners() {
    let s = Session::load_with("corners", &[]).expect("the four-corner cloth loads");
    let r = s.settings();
    let (w, h) = (r.width as usize, r.height as usize);
    assert_eq!(s.pins(), vec![0, w - 1, (h - 1) * w, h * w - 1]);
    // Otherwise the default cloth: the same materials and forces.
    let cloth = Session::load_with("cloth", &[]).expect("loads");
    let c = cloth.settings();
    assert_eq!(
        (r.stiffness, r.damping, r.particle_mass, r.rest_length),
        (c.stiffness, c.damping, c.particle_mass, c.rest_length)
    );
    assert_eq!(r.params, c.params);
}

#[test]
fn pin_presets_pin_exactly_their_particles_in_place() {
    let mut s = Session::load_with("cloth", &[]).expect("loads");
    for _ in 0..30 {
        s.single_step();
    }
    let (w, h) = (s.settings().width as usize, s.settings().height as usize);
    let cases = [
        (PinPreset::Corners, vec![0, w - 1, (h - 1) * w, h * w - 1]),
        (PinPreset::TopCorners, vec![0, w - 1]),
        (PinPreset::TopEdge, (0..w).collect()),
        (PinPreset::LeftEdge, (0..h).map(|r| r * w).collect()),
        (PinPreset::None, vec![]),
    ];
    for (preset, expected) in cases {
        let before = s.system().positions().to_vec();
        let t = s.system().time();
        s.set_pins(Pins::Preset(preset)).expect("a preset applies");
        assert_eq!(s.pins(), expected, "{preset:?}");
        // In place: no rebuild, the cloth stays where it is.
        assert_eq!(s.system().positions(), &before[..], "{preset:?}");
        assert_eq!(s.system().time(), t);
        // Recorded in the scene: a reset keeps it.
        s.reset().expect("resets");
        assert_eq!(s.pins(), expected, "{preset:?} after reset");
        let start = s.system().positions().to_vec();
        for _ in 0..5 {
            s.single_step();
        }
        for &i in &expected {
            assert_eq!(s.system().positions()[i], start[i], "pinned {i} moved");
        }
        let free = (0..w * h)
            .find(|i| !expected.contains(i))
            .expect("a free one");
        assert_ne!(
            s.system().positions()[free],
            start[free],
            "free {free} stuck"
        );
    }
    // "Unpin all", then a click pins one particle and a second click frees it.
    s.toggle_pin(7);
    assert_eq!(s.pins(), vec![7]);
    s.toggle_pin(3);
    assert_eq!(s.pins(), vec![3, 7]);
    s.toggle_pin(7);
    assert_eq!(s.pins(), vec![3]);
    s.reset().expect("resets");
    assert_eq!(s.pins(), vec![3], "a clicked pin is part of the setup");
    s.toggle_pin(usize::MAX);
    assert_eq!(
        s.pins(),
        vec![3],
        "a click past the last particle does nothing"
    );
}

#[test]
fn a_pin_list_past_the_last_particle_is_refused_naming_pins() {
    let mut s = Session::load_with("hanging", &[]).expect("loads");
    let err = s.set_pins(Pins::Indices(vec![3, 120])).unwrap_err();
    let text = err.to_string();
    assert!(matches!(err, SceneError::Invalid { ref field, .. } if field == "pins"));
    assert!(text.contains("0 to 119"), "{text}");
    assert_eq!(s.pins(), vec![0, 14], "nothing changed");
}

#[test]
fn presets_off_a_grid_mean_the_ends_of_the_line() {
    let mut s = Session::load_with("chain", &[]).expect("loads");
    let n = s.system().particle_count();
    s.set_pins(Pins::Preset(PinPreset::Corners))
        .expect("applies");
    assert_eq!(s.pins(), vec![0, n - 1]);
    s.set_pins(Pins::Preset(PinPreset::First)).expect("applies");
    assert_eq!(s.pins(), vec![0]);
}

#[test]
fn the_wind_switch_turns_wind_and_gusts_off_and_back_on() {
    let mut s = Session::load_with("cloth", &[]).expect("loads");
    let scene = Scene::load("cloth")
        .expect("loads")
        .resolve()
        .expect("valid");
    let (wind, gust) = (scene.params.wind, scene.params.gust);
    assert!(wind != DVec3::ZERO && gust > 0.0);
    assert!(s.wind_on());
    s.set_wind_on(false).expect("turns off");
    assert!(!s.wind_on());
    let p = s.system().params();
    assert_eq!((p.wind, p.gust), (DVec3::ZERO, 0.0), "the running system");
    assert_eq!(s.scene().spec.wind.map(|v| v.0), Some(DVec3::ZERO));
    s.set_wind_on(true).expect("turns on");
    let p = s.system().params();
    assert_eq!((p.wind, p.gust), (wind, gust), "the wind it turned off");
    // An edit while on, then off and on again: the edited wind comes back.
    let edited = DVec3::new(-2.0, 0.0, 1.0);
    s.apply(Edit::Wind(edited)).expect("applies");
    s.set_wind_on(false).expect("off");
    s.set_wind_on(true).expect("on");
    assert_eq!(s.system().params().wind, edited);
}

#[test]
fn the_wind_switch_in_still_air_brings_a_breeze() {
    let mut s = Session::load_with("hanging", &[]).expect("loads");
    assert!(!s.wind_on());
    s.set_wind_on(true).expect("turns on");
    assert_eq!(s.system().params().wind, DEFAULT_WIND);
    assert!(s.wind_on());
}

#[test]
fn the_jelly_made_bigger_is_dropped_from_above_the_ground_not_started_in_it() {
    // Centred at the default origin (8 m up), the 16³ cube's rotated corner lies
    // 5 m deep; it is lifted whole until its lowest particle is one rest length
    // (1 m) above the ground, with its shape kept. The first steps then are a
    // fall: no more kinetic energy than the 1 m drop gives, where the ground's
    // penalty had put 7.4e6 J into it.
    let system = common::build("jelly", &["width=16", "height=16", "depth=16"]);
    let x = system.positions();
    let lowest = x.iter().map(|p| p.y).fold(f64::INFINITY, f64::min);
    assert!((lowest - 1.0).abs() < 1e-9, "lowest particle at {lowest} m");
    let springs = system.springs();
    let strained = springs
        .iter()
        .map(|s| (x[s.a as usize].distance(x[s.b as usize]) - s.rest).abs())
        .fold(0.0, f64::max);
    assert!(
        strained < 1e-9,
        "the lift deformed the cube by {strained} m"
    );
    let mut system = system;
    system.run(100).unwrap();
    let e = system.energy();
    let mass: f64 = system.masses().iter().sum();
    assert!(e.kinetic <= mass * 9.81 * 1.0, "{e:?}");
    // The default jelly already starts clear of the ground: it is not moved.
    let small = common::build("jelly", &[]);
    let lowest = (small.positions().iter())
        .map(|p| p.y)
        .fold(f64::INFINITY, f64::min);
    assert!(lowest > 1.0, "the default jelly starts at {lowest} m");
}
