//! Every kind of bad scene input gives an error that names where it came from and
//! the field, and never a panic.

use cloth_sandbox::scene::{Scene, SceneError};

const GOOD: &str = r#"
layout = "grid"
width = 8
height = 8
rest_length = 0.1
particle_mass = 0.01
stiffness = 100.0
"#;

fn parse_err(text: &str) -> String {
    match Scene::parse(text, "scene file test.toml") {
        Ok(_) => panic!("accepted bad scene:\n{text}"),
        Err(e) => e.to_string(),
    }
}

fn with(line: &str) -> String {
    // Replace a key if present, else append it.
    let key = line.split('=').next().unwrap().trim();
    let mut lines: Vec<String> = GOOD
        .lines()
        .filter(|l| !l.starts_with(&format!("{key} ")))
        .map(String::from)
        .collect();
    lines.push(line.to_string());
    lines.join("\n")
}

fn assert_names(message: &str, parts: &[&str]) {
    for part in parts {
        assert!(
            message.contains(part),
            "error {message:?} should mention {part:?}"
        );
    }
}

#[test]
fn the_good_scene_parses() {
    Scene::parse(GOOD, "test").unwrap().build().unwrap();
}

#[test]
fn unknown_key() {
    let e = parse_err(&with("stifness = 5.0"));
    assert_names(&e, &["test.toml", "stifness"]);
}

#[test]
fn wrong_type() {
    assert_names(
        &parse_err(&with("width = \"eight\"")),
        &["test.toml", "width"],
    );
    assert_names(
        &parse_err(&with("stiffness = true")),
        &["test.toml", "stiffness"],
    );
    assert_names(
        &parse_err(&with("wind = \"north\"")),
        &["test.toml", "wind"],
    );
}

#[test]
fn zero_or_negative_mass() {
    for mass in ["0.0", "-1.0"] {
        let e = parse_err(&with(&format!("particle_mass = {mass}")));
        assert_names(&e, &["test.toml", "particle_mass", "out of range"]);
    }
    assert_names(&parse_err(&with("total_mass = -3.0")), &["total_mass"]);
}

#[test]
fn non_finite_numbers() {
    for line in [
        "stiffness = nan",
        "damping = inf",
        "dt = -inf",
        "rest_length = nan",
        "gravity = [0.0, nan, 0.0]",
    ] {
        let field = line.split(' ').next().unwrap();
        assert_names(&parse_err(&with(line)), &["test.toml", field]);
    }
}

#[test]
fn width_and_height_out_of_range() {
    for line in ["width = 0", "height = 0", "width = 5000", "height = 1025"] {
        let field = line.split(' ').next().unwrap();
        assert_names(&parse_err(&with(line)), &["test.toml", field, "[1, 1024]"]);
    }
    assert_names(&parse_err(&with("width = -3")), &["width"]);
}

#[test]
fn unknown_integrator_and_pins() {
    let e = parse_err(&with("integrator = \"leapfrog\""));
    assert_names(&e, &["integrator", "leapfrog", "symplectic-euler"]);
    assert_names(
        &parse_err(&with("pins = \"everywhere\"")),
        &["pins", "everywhere"],
    );
    assert_names(
        &parse_err(&with("pins = [0, 64]")),
        &["pins", "64", "64 particles"],
    );
}

#[test]
fn conflicting_alternatives() {
    assert_names(
        &parse_err(&with("size = 2.0")),
        &["rest_length", "size", "only one"],
    );
}

#[test]
fn bad_dt_and_syntax() {
    assert_names(&parse_err(&with("dt = 0.0")), &["dt", "out of range"]);
    assert_names(&parse_err("width = = 3"), &["test.toml"]);
}

#[test]
fn unknown_scene_lists_the_builtins() {
    match Scene::load("clothh") {
        Err(SceneError::UnknownScene { builtins, .. }) => {
            assert!(builtins.contains("cloth") && builtins.contains("jelly"))
        }
        other => panic!("expected UnknownScene, got {other:?}"),
    }
}

#[test]
fn bad_overrides_name_the_key_and_leave_the_scene_unchanged() {
    let mut scene = Scene::load("cloth").unwrap();
    let before = scene.clone();
    for (assignment, key) in [
        ("particle_mass=-1", "particle_mass"),
        ("width=0", "width"),
        ("stiffness=abc", "stiffness"),
        ("integrator=euler", "integrator"),
        ("colour=red", "colour"),
        ("wind=1,2", "wind"),
    ] {
        let e = scene.set_all([assignment]).unwrap_err().to_string();
        assert!(e.contains(key) && e.contains("--set"), "{assignment}: {e}");
        assert_eq!(scene, before, "{assignment} changed the scene");
    }
    assert!(
        scene
            .set_all(["novalue"])
            .unwrap_err()
            .to_string()
            .contains("key=value")
    );
}

#[test]
fn every_shipped_scene_file_is_valid() {
    for entry in std::fs::read_dir(concat!(env!("CARGO_MANIFEST_DIR"), "/assets/scenes")).unwrap() {
        let path = entry.unwrap().path();
        let scene = Scene::load(path.to_str().unwrap()).unwrap_or_else(|e| panic!("{e}"));
        assert!(
            scene.spec.description.is_some(),
            "{} has no description",
            path.display()
        );
        scene.build().unwrap();
    }
}

/// A collider's bad values and a broken collider mesh are refused with the
/// field (`colliders[i].key`), the range or the file's line named.
#[test]
fn bad_colliders_are_refused_by_name() {
    let dir = std::env::temp_dir().join(format!("cloth-colliders-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(
        dir.join("broken.obj"),
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n",
    )
    .unwrap();
    let base = "layout = \"grid\"\n";
    let cases = [
        ("shape = \"cone\"", "colliders[0].shape"),
        ("shape = \"sphere\"\nradius = -1", "colliders[0].radius"),
        (
            "shape = \"box\"\nhalf_extents = \"1,0,1\"",
            "colliders[0].half_extents",
        ),
        ("shape = \"capsule\"\na = \"0,0,0\"", "colliders[0].b"),
        ("shape = \"sphere\"\nfriction = 11", "colliders[0].friction"),
        ("shape = \"mesh\"", "colliders[0].mesh"),
        ("shape = \"mesh\"\nmesh = \"broken.obj\"", "line 4"),
        ("shape = \"box\"\nradius = 1", "colliders[0].radius"),
    ];
    for (table, named) in cases {
        let text = format!("{base}[[colliders]]\n{table}\n");
        let path = dir.join("scene.toml");
        std::fs::write(&path, &text).unwrap();
        let err = cloth_sandbox::scene::Scene::load(path.to_str().unwrap())
            .err()
            .unwrap_or_else(|| panic!("accepted:\n{text}"))
            .to_string();
        assert!(err.contains(named), "{table}: {err}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}
