//! Bad input in plain words (clearer input messages): ranges, not Rust types; a
//! misspelt key gets the nearest real one; a scene file's error shows its line and
//! a caret on lines of their own.

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
    // (typed, the guess). A word of a key is that key (or those keys), not the
    // nearest spelling (`bars`, 2 edits from `mass`); the panel's symbols are
    // their keys.
    let guessed = [
        ("widht", "`width`?"),
        ("stifness", "`stiffness`?"),
        ("mass", "`particle_mass` or `total_mass`"),
        ("k", "`stiffness`?"),
        ("b", "`damping`?"),
        ("density", "`areal_density` or `air_density`?"),
    ];
    for (typed, guess) in guessed {
        let message = set_error(typed, "1");
        assert!(
            message.contains(&format!("did you mean {guess}")),
            "{message}"
        );
        assert!(!message.contains("expected one of"), "{message}");
    }
    assert!(!set_error("mass", "1").contains("`bars`"));
    // Another single letter, or nothing near: no guess.
    for typed in ["q", "zzzzqqq"] {
        let message = set_error(typed, "1");
        assert!(!message.contains("did you mean"), "{message}");
        assert!(message.contains("not a scene key"), "{message}");
    }
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

#[test]
fn none_turns_off_what_the_scene_file_turned_on_and_only_that() {
    // The drape has a ground and a sphere, the sheet a stretch limit, the tear
    // scene a tear strain: `none` removes each, as if the file never had it.
    for (scene, key) in [
        ("drape", "ground_height"),
        ("drape", "sphere_center"),
        ("sheet", "stretch_limit"),
        ("tear", "tear_strain"),
    ] {
        let mut s = Scene::load(scene).unwrap();
        assert!(s.resolve().is_ok());
        s.set(key, "none").unwrap();
        let p = s.resolve().unwrap().params;
        let off = match key {
            "ground_height" => p.ground.is_none(),
            "sphere_center" => p.sphere.is_none(),
            "stretch_limit" => p.stretch_limit.is_none(),
            _ => p.tear_strain.is_none(),
        };
        assert!(off, "{scene}: {key}=none left it on");
        let saved = toml::to_string(&s.spec).unwrap();
        assert!(!saved.contains(key), "{scene}: {key} still saved:\n{saved}");
    }
    let mut s = Scene::load("cloth").unwrap();
    s.set("max_speed", "3").unwrap();
    s.set("max_speed", "None").unwrap();
    assert_eq!(s.resolve().unwrap().params.max_speed, None);
    // A key that is never off is refused `none`, and the off keys' messages offer it.
    let message = set_error("stiffness", "none");
    assert!(
        message.contains("`stiffness` must be a number, got"),
        "{message}"
    );
    let message = set_error("stretch_limit", "off");
    assert!(
        message.contains("`stretch_limit` must be a number, got")
            && message.ends_with("; `none` turns it off"),
        "{message}"
    );
    let message = set_error("sphere_center", "off");
    assert!(
        message.contains("not a vector") && message.ends_with("; `none` turns it off"),
        "{message}"
    );
    assert!(!set_error("stiffness", "none").contains("`none`"));
    // A scene file turns a part off by leaving its key out: no `none` offered there.
    let message = Scene::parse("layout = \"grid\"\nstretch_limit = \"off\"\n", "test.toml")
        .unwrap_err()
        .to_string();
    assert!(
        message.contains("`stretch_limit` must be a number") && !message.contains("none"),
        "{message}"
    );
}
