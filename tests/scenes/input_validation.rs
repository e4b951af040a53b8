//! Input validation: masses that underflow are refused, an out-of-range pin index
//! says so, seeds up to 2^64 - 1 are taken, a value with a line break is refused
//! rather than cut, and echoed input is shortened.

use cloth_sandbox::scene::Scene;

fn set_error(key: &str, value: &str) -> String {
    let mut scene = Scene::load("cloth").unwrap();
    scene.set(key, value).unwrap_err().to_string()
}

#[test]
fn a_total_mass_that_underflows_is_refused() {
    let err = set_error("total_mass", "5e-324");
    assert!(err.contains("total_mass") && err.contains("1e-12"), "{err}");
    let err = set_error("particle_mass", "1e-320");
    assert!(
        err.contains("particle_mass") && err.contains("1e-12"),
        "{err}"
    );
}

#[test]
fn a_pin_index_past_u64_is_out_of_range() {
    let err = set_error("pins", "[18446744073709551615]");
    assert!(err.contains("out of range"), "{err}");
    assert!(!err.contains("unknown pin set"), "{err}");
    let err = set_error("pins", "[0, 99999999999999999999999]");
    assert!(err.contains("pin index"), "{err}");
}

#[test]
fn seeds_up_to_2_pow_64_minus_1_are_taken_and_kept() {
    let mut scene = Scene::load("flag").unwrap();
    scene.set("seed", "9223372036854775808").unwrap();
    // Another edit after it serialises the spec again.
    scene.set("width", "8").unwrap();
    scene.set("seed", "18446744073709551615").unwrap();
    scene.set("height", "8").unwrap();
    assert_eq!(scene.spec.seed, Some(u64::MAX));
    assert_eq!(scene.build().unwrap().params().seed, u64::MAX);
    let err = set_error("seed", "-1");
    assert!(
        err.contains("seed") && err.contains("18446744073709551615"),
        "{err}"
    );
    let file = Scene::parse("seed = \"18446744073709551615\"\n", "test").unwrap();
    assert_eq!(file.spec.seed, Some(u64::MAX));
}

#[test]
fn a_value_with_a_line_break_is_refused_not_cut() {
    let err = set_error("width", "32\nheight=4");
    assert!(err.contains("width") && err.contains("one line"), "{err}");
    let mut scene = Scene::load("cloth").unwrap();
    assert!(scene.set_all(["width=32\rheight=4"]).is_err());
}

#[test]
fn echoed_values_are_short() {
    let err = set_error("dt", "1e300");
    assert!(err.contains("1e300"), "{err}");
    assert!(err.len() < 200, "{err}");
    let long = "a".repeat(100_000);
    for key in ["integrator", "wind", "pins", "width"] {
        let err = set_error(key, &long);
        assert!(err.len() < 1000, "{key}: {} characters", err.len());
    }
    let err = Scene::load(&long).unwrap_err().to_string();
    assert!(err.len() < 1000, "{} characters", err.len());
    let text = format!("width = {long}\n");
    let err = Scene::parse(&text, "test").unwrap_err().to_string();
    assert!(err.len() < 1000, "{} characters", err.len());
}
