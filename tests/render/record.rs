//! `cloth record` through the real binary: a short GIF of a small scene decodes
//! (with the `gif` crate) to the frames and size asked for, and consecutive frames
//! differ because the cloth moves; a PNG sequence gets its numbered files; bad
//! `--out` paths and values are refused with exit code 2 before any work.
//!
//! Without any graphics adapter the rendering tests print a note and pass, unless
//! `CLOTH_REQUIRE_ADAPTER` is set (CI sets it), in which case they fail.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn dir(name: &str) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR"))
        .join("record")
        .join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn cloth(args: &[&str]) -> Output {
    let out = Command::new(env!("CARGO_BIN_EXE_cloth"))
        .arg("record")
        .args(args)
        .output()
        .expect("the cloth binary runs");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!stderr.contains("panicked"), "{stderr}");
    out
}

/// Records with `args`; `false` when there is no adapter and adapters are not
/// required (the test then has nothing to check).
fn record(args: &[&str]) -> bool {
    let out = cloth(args);
    let stderr = String::from_utf8_lossy(&out.stderr);
    if !out.status.success() {
        if stderr.contains("no graphics adapter")
            && std::env::var_os("CLOTH_REQUIRE_ADAPTER").is_none()
        {
            eprintln!("note: skipping the recording test: {}", stderr.trim());
            return false;
        }
        panic!("cloth record {args:?} failed: {stderr}");
    }
    assert!(stderr.contains("wrote "), "{stderr}");
    true
}

/// The frames of a GIF as RGBA, with the logical screen size and the delays.
fn decode_gif(path: &Path) -> ((u16, u16), Vec<Vec<u8>>, Vec<u16>) {
    let mut options = gif::DecodeOptions::new();
    options.set_color_output(gif::ColorOutput::RGBA);
    let file = std::fs::File::open(path).expect("the GIF was written");
    let mut decoder = options.read_info(file).expect("a GIF");
    let size = (decoder.width(), decoder.height());
    let (mut frames, mut delays) = (Vec::new(), Vec::new());
    while let Some(frame) = decoder.read_next_frame().expect("a readable frame") {
        assert_eq!((frame.width, frame.height), size, "whole frames");
        delays.push(frame.delay);
        frames.push(frame.buffer.to_vec());
    }
    (size, frames, delays)
}

/// Fraction of pixels that differ between two RGBA images by more than a little.
fn changed(a: &[u8], b: &[u8]) -> f64 {
    let differ = a
        .chunks_exact(4)
        .zip(b.chunks_exact(4))
        .filter(|(p, q)| p.iter().zip(q.iter()).any(|(x, y)| x.abs_diff(*y) > 8))
        .count();
    differ as f64 / (a.len() / 4) as f64
}

#[test]
fn a_short_gif_has_the_frames_and_size_asked_for_and_moves() {
    let out = dir("gif").join("flag.gif");
    // 6 frames at 10 fps of a small flag in a strong wind: 0.5 s of motion.
    let shown = out.to_str().unwrap();
    let args = [
        "--scene",
        "flag",
        "--set",
        "width=12",
        "--set",
        "height=8",
        "--seconds",
        "0.6",
        "--fps",
        "10",
        "--size",
        "96x64",
        "--out",
        shown,
    ];
    if !record(&args) {
        return;
    }
    let (size, frames, delays) = decode_gif(&out);
    assert_eq!(size, (96, 64));
    assert_eq!(frames.len(), 6);
    assert!(delays.iter().all(|&d| d == 10), "{delays:?}");
    for (i, pair) in frames.windows(2).enumerate() {
        let c = changed(&pair[0], &pair[1]);
        assert!(
            c > 0.002,
            "frames {i} and {} are the same ({c:.4} changed)",
            i + 1
        );
    }
    // Not a blank picture: the cloth covers part of the first frame.
    let first = &frames[0];
    let background = [first[0], first[1], first[2]];
    let cloth = first
        .chunks_exact(4)
        .filter(|p| {
            p[..3]
                .iter()
                .zip(background)
                .any(|(x, y)| x.abs_diff(y) > 20)
        })
        .count();
    assert!(
        cloth > 96 * 64 / 50,
        "only {cloth} pixels differ from the corner's colour"
    );
}

#[test]
fn png_sequences_by_pattern_and_by_folder() {
    let d = dir("png");
    let pattern = d.join("f-%03d.png");
    if !record(&[
        "--set",
        "width=6",
        "--set",
        "height=6",
        "--seconds",
        "0.12",
        "--fps",
        "25",
        "--size",
        "40x30",
        "--out",
        pattern.to_str().unwrap(),
    ]) {
        return;
    }
    for i in 0..3 {
        assert!(d.join(format!("f-{i:03}.png")).is_file(), "frame {i}");
    }
    assert!(!d.join("f-003.png").exists());
    let folder = format!("{}/", d.join("frames").display());
    assert!(record(&[
        "--set",
        "width=6",
        "--set",
        "height=6",
        "--seconds",
        "0.08",
        "--size",
        "40x30",
        "--out",
        &folder,
    ]));
    let mut names: Vec<String> = std::fs::read_dir(d.join("frames"))
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert_eq!(names, ["frame-0000.png", "frame-0001.png"]);
    // The folder now holds a recording: a second one is refused, not mixed in.
    let again = cloth(&["--seconds", "0.04", "--size", "40x30", "--out", &folder]);
    assert_eq!(again.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&again.stderr).contains("is not empty"));
}

#[test]
fn bad_input_exits_2_in_words_before_any_work() {
    let d = dir("bad");
    let missing = d.join("missing").join("x.gif");
    let cases: [(Vec<String>, &str); 6] = [
        (
            vec!["--out".into(), missing.display().to_string()],
            "does not exist",
        ),
        (
            vec!["--out".into(), "x.mp4".into()],
            "give a name ending in .gif",
        ),
        (vec!["--out".into(), "x.png".into()], "frame number"),
        (
            vec![
                "--out".into(),
                "x.gif".into(),
                "--seconds".into(),
                "-1".into(),
            ],
            "--seconds -1 must be",
        ),
        (
            vec!["--out".into(), "x.gif".into(), "--fps".into(), "60".into()],
            "60 is not in 1..=50",
        ),
        (
            vec![
                "--out".into(),
                "x.gif".into(),
                "--scene".into(),
                "nope".into(),
            ],
            "unknown scene",
        ),
    ];
    for (args, expect) in cases {
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let out = cloth(&args);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {stderr}");
        assert!(stderr.contains(expect), "{args:?}: {stderr}");
    }
    assert!(!Path::new("x.gif").exists());
}

/// A recording keeps safe stepping's watch on the drag's areas, as the app does:
/// the peers' bench cloth in its wind at 128 x 128 on position Verlet hangs far
/// past its rest length, and with the step chosen at rest kept it runs away at
/// 1.77 s (a recording of it stopped there, at frame 18 of 25). It now
/// records its 2.4 s, frames PNG-numbered to the last.
#[test]
fn a_recording_of_a_cloth_stretching_in_the_wind_follows_its_drag_areas() {
    let out = dir("stretching");
    let pattern = out.join("f-%02d.png");
    let ran = record(&[
        "--scene",
        "bench-wind",
        "--set",
        "width=128",
        "--set",
        "height=128",
        "--set",
        "integrator=\"verlet\"",
        "--seconds",
        "2.5",
        "--fps",
        "10",
        "--size",
        "64x48",
        "--out",
        pattern.to_str().unwrap(),
    ]);
    if ran {
        assert!(out.join("f-24.png").exists(), "the last frame, at 2.4 s");
    }
}
