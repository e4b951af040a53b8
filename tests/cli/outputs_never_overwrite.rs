//! No output of any command overwrites an input of the same
//! run, whatever the path's spelling; every output path is checked before the run;
//! texture coordinates and normals are checked as vertices are.
//!
//! The matrix: every output flag (`run --dump`, `run --obj`, `screenshot --out`,
//! `record --out` as a GIF, a PNG pattern and a folder) against every input kind
//! (the scene file, its mesh) in every spelling (as given, `./`, `../dir/`,
//! absolute, a link to it). Each must be refused before any work, and the input
//! must keep its bytes.

use std::path::{Path, PathBuf};
use std::process::Command;

use crate::binary::stderr;

/// A fresh folder for one test, with a mesh scene: `scene.toml` naming `m.obj`.
fn workspace(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!(
        "cloth-never-overwrite-{name}-{}",
        std::process::id()
    ));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(dir.join("sub")).unwrap();
    std::fs::write(
        dir.join("m.obj"),
        "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nf 1/1 2/2 3/3\nf 1/1 3/3 4/4\n",
    )
    .unwrap();
    std::fs::write(
        dir.join("scene.toml"),
        "layout = \"mesh\"\nmesh = \"m.obj\"\nparticle_mass = 0.01\nstiffness = 100.0\npins = \"none\"\n",
    )
    .unwrap();
    dir
}

/// Runs `cloth` in `dir` with `args`.
fn cloth_in(dir: &Path, args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_cloth"))
        .current_dir(dir)
        .args(args)
        .output()
        .unwrap()
}

/// The spellings of `file` (in `dir`) as seen from `dir`, and one from `dir/sub`
/// given as `../file`; a link `dir/link-<file>` is made to it.
fn spellings(dir: &Path, file: &str) -> Vec<String> {
    let link = format!("link-{file}");
    let _ = std::fs::remove_file(dir.join(&link));
    #[cfg(unix)]
    std::os::unix::fs::symlink(dir.join(file), dir.join(&link)).unwrap();
    vec![
        file.to_string(),
        format!("./{file}"),
        format!("sub/../{file}"),
        dir.join(file).display().to_string(),
        link,
    ]
}

/// Every output flag, as the arguments of one command writing to `out`, reading
/// the scene `scene.toml`.
fn commands(out: &str) -> Vec<Vec<String>> {
    let s = |v: &[&str]| v.iter().map(|x| x.to_string()).collect::<Vec<_>>();
    vec![
        s(&[
            "run",
            "--scene",
            "scene.toml",
            "--steps",
            "10",
            "--dump",
            out,
        ]),
        s(&[
            "run",
            "--scene",
            "scene.toml",
            "--steps",
            "10",
            "--obj",
            out,
        ]),
        s(&["screenshot", "--scene", "scene.toml", "--out", out]),
        s(&[
            "record",
            "--scene",
            "scene.toml",
            "--seconds",
            "0.1",
            "--out",
            out,
        ]),
    ]
}

/// The matrix: every output flag onto the scene file and onto its mesh, in every
/// spelling, is refused and the input keeps its bytes.
#[test]
fn no_output_flag_overwrites_the_scene_file_or_its_mesh_in_any_spelling() {
    let dir = workspace("matrix");
    // The scene runs and writes where nothing is read.
    let o = cloth_in(
        &dir,
        &[
            "run",
            "--scene",
            "scene.toml",
            "--steps",
            "10",
            "--obj",
            "out.obj",
        ],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(dir.join("out.obj").exists());
    let mut failures = Vec::new();
    for input in ["scene.toml", "m.obj"] {
        let before = std::fs::read(dir.join(input)).unwrap();
        for spelled in spellings(&dir, input) {
            for args in commands(&spelled) {
                let args: Vec<&str> = args.iter().map(String::as_str).collect();
                let o = cloth_in(&dir, &args);
                let err = stderr(&o);
                // The record command reads `--out` as a GIF, a pattern or a
                // folder by its name (its three forms onto inputs: below), so
                // onto `scene.toml` or `m.obj` it is refused by that rule.
                let refused = err.contains("refusing to overwrite")
                    || (args[0] == "record" && err.contains("give a name ending in .gif"));
                if o.status.success() || !refused {
                    failures.push(format!("{args:?}: {:?} {err}", o.status));
                }
                if std::fs::read(dir.join(input)).unwrap() != before {
                    failures.push(format!("{args:?} changed {input}"));
                    std::fs::write(dir.join(input), &before).unwrap();
                }
            }
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

/// `record --out` in its three forms onto an input: a GIF named like the scene
/// file, a PNG pattern whose first frame is the mesh's name, a folder holding
/// the scene (with `--force`, as an empty folder is required otherwise).
#[test]
fn every_form_of_record_out_keeps_off_the_inputs() {
    let dir = workspace("record");
    std::fs::copy(dir.join("scene.toml"), dir.join("scene.gif")).unwrap();
    std::fs::copy(dir.join("scene.toml"), dir.join("sub/frame-0000.png")).unwrap();
    // The mesh named as a PNG pattern's first frame.
    std::fs::copy(dir.join("m.obj"), dir.join("m-0.png")).unwrap();
    let mesh_scene = "layout = \"mesh\"\nmesh = \"m-0.png\"\npins = \"none\"\n";
    std::fs::write(dir.join("png-mesh.toml"), mesh_scene).unwrap();
    let cases: [(&[&str], &str); 3] = [
        (
            &["record", "--scene", "scene.gif", "--out", "scene.gif"],
            "scene.gif",
        ),
        (
            &[
                "record",
                "--scene",
                "png-mesh.toml",
                "--out",
                "m-%d.png",
                "--force",
            ],
            "m-0.png",
        ),
        (
            &[
                "record",
                "--scene",
                "sub/frame-0000.png",
                "--out",
                "sub/",
                "--force",
            ],
            "sub/frame-0000.png",
        ),
    ];
    for (args, input) in cases {
        let before = std::fs::read(dir.join(input)).unwrap();
        let o = cloth_in(&dir, args);
        let err = stderr(&o);
        assert!(!o.status.success(), "{args:?}: {err}");
        assert_eq!(
            std::fs::read(dir.join(input)).unwrap(),
            before,
            "{args:?}: {err}"
        );
    }
}

/// An existing frame of an earlier recording is not replaced by a PNG pattern
/// without `--force` (a folder must be empty without it, as before).
#[test]
fn a_png_pattern_does_not_replace_an_earlier_recordings_frames() {
    let dir = workspace("frames");
    std::fs::write(dir.join("shot-0003.png"), b"earlier").unwrap();
    let o = cloth_in(
        &dir,
        &[
            "record",
            "--scene",
            "cloth",
            "--seconds",
            "0.2",
            "--out",
            "shot-%04d.png",
        ],
    );
    let err = stderr(&o);
    assert!(!o.status.success(), "{err}");
    assert!(err.contains("shot-0003.png exists"), "{err}");
    assert_eq!(
        std::fs::read(dir.join("shot-0003.png")).unwrap(),
        b"earlier"
    );
}

/// Every output path is checked before the run: `--dump newdir/` where `newdir`
/// is a file failed only after a 4,000-step run.
#[test]
fn an_output_path_that_cannot_be_written_fails_before_the_run() {
    let dir = workspace("before");
    std::fs::write(dir.join("newdir"), b"a file").unwrap();
    for args in [
        &[
            "run",
            "--scene",
            "cloth",
            "--set",
            "width=128",
            "--set",
            "height=128",
            "--steps",
            "4000",
            "--dump",
            "newdir/",
        ][..],
        &[
            "run",
            "--scene",
            "cloth",
            "--set",
            "width=128",
            "--set",
            "height=128",
            "--steps",
            "4000",
            "--obj",
            "newdir/",
        ],
        &[
            "run",
            "--scene",
            "cloth",
            "--set",
            "width=128",
            "--set",
            "height=128",
            "--steps",
            "4000",
            "--dump",
            "newdir/x.csv",
        ],
        &[
            "screenshot",
            "--scene",
            "cloth",
            "--steps",
            "4000",
            "--out",
            "newdir/",
        ],
    ] {
        let start = std::time::Instant::now();
        let o = cloth_in(&dir, args);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert!(start.elapsed().as_secs_f64() < 5.0, "{args:?} ran first");
        assert!(err.contains("newdir"), "{args:?}: {err}");
        assert_eq!(std::fs::read(dir.join("newdir")).unwrap(), b"a file");
    }
    // Nothing half-made is left beside it.
    let left: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .filter_map(|e| e.ok())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".tmp"))
        .collect();
    assert!(left.is_empty(), "{left:?}");
}

/// `vt nan nan` was accepted, and `--obj` then wrote NaN: texture coordinates and
/// normals are refused as vertices are, naming the line.
#[test]
fn texture_coordinates_and_normals_are_checked_like_vertices() {
    let dir = workspace("obj");
    let base = "v 0 0 0\nv 1 0 0\nv 1 1 0\n";
    for (extra, face, what) in [
        (
            "vt nan nan\nvt 1 0\nvt 1 1\n",
            "f 1/1 2/2 3/3\n",
            "texture coordinate 1 (`vt`)",
        ),
        (
            "vt 0 0\nvt inf 0\nvt 1 1\n",
            "f 1/1 2/2 3/3\n",
            "texture coordinate 2 (`vt`)",
        ),
        (
            "vt 0 0\nvt 1e300 0\nvt 1 1\n",
            "f 1/1 2/2 3/3\n",
            "texture coordinate 2 (`vt`)",
        ),
        ("vn 0 0 nan\n", "f 1//1 2//1 3//1\n", "normal 1 (`vn`)"),
        (
            "vn 0 0 1\nvn -inf 0 0\n",
            "f 1//1 2//2 3//1\n",
            "normal 2 (`vn`)",
        ),
    ] {
        std::fs::write(dir.join("bad.obj"), format!("{base}{extra}{face}")).unwrap();
        std::fs::write(
            dir.join("bad.toml"),
            "layout = \"mesh\"\nmesh = \"bad.obj\"\npins = \"none\"\n",
        )
        .unwrap();
        let o = cloth_in(
            &dir,
            &[
                "run", "--scene", "bad.toml", "--steps", "1", "--obj", "out.obj",
            ],
        );
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{extra}: {err}");
        assert!(err.contains(what), "{extra}: {err}");
        assert!(err.contains("line"), "{extra}: {err}");
        assert!(!dir.join("out.obj").exists(), "{extra}");
    }
}
