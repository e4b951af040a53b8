//! Bad input in plain words (issue 12's "clearer input messages"): ranges, not Rust
//! types; a misspelt key gets the nearest real one; a scene file's error shows its
//! line and a caret on lines of their own.

use cloth_sandbox::scene::Scene;

fn set_error(key: &str, value: &str) -> String {
    let mut scene = Scene::load("cloth").unwrap();
    let before = scene.clone();
    let message = scene.set(key, value).unwrap_err().to_string();
    assert_eq!(scene, before, "a refused --set changes nothing");
    message
}

#[test]
fn a_negative_width_is_told_its_range_not_its_type() {
    let message = set_error("width", "-3");
    assert!(
        message.contains("`width` must be a whole number from 1 to 1024, got -3"),
        "{message}"
    );
    assert!(!message.contains("u32"), "{message}");
    let message = set_error("substeps", "2.5");
    assert!(
        message.contains("`substeps` must be a whole number from 1 to"),
        "{message}"
    );
    let message = set_error("stiffness", "stiff");
    assert!(
        message.contains("`stiffness` must be a number"),
        "{message}"
    );
}

#[test]
fn a_misspelt_key_gets_the_nearest_real_one() {
    let message = set_error("widht", "3");
    assert!(message.contains("did you mean `width`?"), "{message}");
    assert!(!message.contains("expected one of"), "{message}");
    let message = set_error("stifness", "3");
    assert!(message.contains("did you mean `stiffness`?"), "{message}");
    // A word of a key is that key (or those keys), not the nearest spelling
    // (`bars`, 2 edits from `mass`).
    let message = set_error("mass", "0.01");
    assert!(
        message.contains("did you mean `particle_mass` or `total_mass`"),
        "{message}"
    );
    assert!(!message.contains("`bars`"), "{message}");
    // The panel's symbols are their keys; another single letter is no guess.
    let message = set_error("k", "100");
    assert!(message.contains("did you mean `stiffness`?"), "{message}");
    let message = set_error("b", "0.1");
    assert!(message.contains("did you mean `damping`?"), "{message}");
    let message = set_error("q", "1");
    assert!(!message.contains("did you mean"), "{message}");
    let message = set_error("density", "1");
    assert!(message.contains("did you mean `air_density`?"), "{message}");
    // Nothing near: no guess.
    let message = set_error("zzzzqqq", "3");
    assert!(!message.contains("did you mean"), "{message}");
    assert!(message.contains("not a scene key"), "{message}");
}

#[test]
fn a_scene_file_error_shows_its_line_and_a_caret() {
    let text = "layout = \"grid\"\nwidht = 12\n";
    let message = Scene::parse(text, "scene file typo.toml")
        .unwrap_err()
        .to_string();
    let lines: Vec<&str> = message.lines().collect();
    assert!(lines[0].ends_with("line 2:"), "{message}");
    assert_eq!(lines[1].trim(), "widht = 12", "{message}");
    assert_eq!(lines[2].trim(), "^^^^^", "{message}");
    // The caret sits under the key.
    assert_eq!(lines[2].find('^'), lines[1].find('w'), "{message}");
    assert!(lines[3].contains("did you mean `width`?"), "{message}");
}
