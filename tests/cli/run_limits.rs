//! Hangs and overflows: a run whose length cannot finish (`--dt 1e-300`,
//! `--duration 1e300`), or whose steps × substeps overflow, is refused before it
//! starts with a message giving the limit; a scene "file" that never ends
//! (`/dev/zero`) or is too large is refused rather than read.

use crate::binary::{cloth, stderr};

/// Exit code 2 with a message holding every one of `words`.
fn refused(args: &[&str], words: &[&str]) {
    let o = cloth(args);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
    for w in words {
        assert!(err.contains(w), "{args:?}: `{w}` missing from: {err}");
    }
}

#[test]
fn a_tiny_dt_with_the_default_duration_is_refused_with_the_limit() {
    refused(&["run", "--dt", "1e-300"], &["1000000000 steps", "dt"]);
}

#[test]
fn an_endless_duration_is_refused_with_the_limit() {
    refused(
        &["run", "--duration", "1e300"],
        &["--duration", "1000000000 steps"],
    );
}

#[test]
fn steps_times_substeps_cannot_overflow_to_zero() {
    // Used to exit 0 with `"steps": 0`: 2^63 × 2 substeps wrapped around.
    refused(
        &["run", "--steps", "9223372036854775808", "--safe", "--json"],
        &["substeps", "1000000000 steps"],
    );
}

#[test]
fn too_many_particle_steps_are_refused() {
    refused(
        &[
            "run",
            "--scene",
            "bench",
            "--set",
            "width=1024",
            "--set",
            "height=1024",
            "--steps",
            "10000000",
        ],
        &["particle-steps", "1e12"],
    );
}

#[test]
fn warmup_is_counted_too() {
    refused(&["run", "--warmup", "18446744073709551615"], &["--warmup"]);
}

#[test]
fn screenshot_steps_are_bounded_too() {
    let out = std::env::temp_dir().join(format!("cloth-run-limits-{}.png", std::process::id()));
    refused(
        &[
            "screenshot",
            "--steps",
            "18446744073709551615",
            "--out",
            out.to_str().unwrap(),
        ],
        &["--steps", "1000000000 steps"],
    );
    assert!(!out.exists());
}

#[test]
fn a_scene_that_is_not_a_regular_file_is_refused() {
    refused(
        &["run", "--scene", "/dev/zero"],
        &["/dev/zero", "not a regular file"],
    );
    refused(&["info", "--scene", "/"], &["not a regular file"]);
}

#[test]
fn an_oversized_scene_file_is_refused_unread() {
    let path =
        std::env::temp_dir().join(format!("cloth-run-limits-big-{}.toml", std::process::id()));
    let mut text = String::from("width = 8\n");
    text.push_str(&"# padding\n".repeat(200_000));
    std::fs::write(&path, text).unwrap();
    refused(
        &["info", "--scene", path.to_str().unwrap()],
        &["1048576 bytes"],
    );
    std::fs::remove_file(&path).unwrap();
}
