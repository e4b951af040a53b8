//! The messages that sent the user the wrong way now name the
//! cause: why there is no surface, which of the user's values combine, the file
//! and line of a value, the option given a bad number, and keys that would be
//! ignored.

use crate::binary::{cloth, stderr};

/// `cloth` with `args` fails with exit 2 and a message holding each of `words`.
fn refused(args: &[&str], words: &[&str]) -> String {
    let o = cloth(args);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
    for w in words {
        assert!(err.contains(w), "{args:?}: `{w}` not in {err}");
    }
    err
}

/// `--obj` on a one-row cloth said "OBJ export needs a cloth scene such as
/// `cloth`" to a user already on `cloth`: it says the row is the cause.
#[test]
fn obj_on_a_one_row_cloth_says_it_is_one_row() {
    let out = std::env::temp_dir().join(format!("one-row-{}.obj", std::process::id()));
    let out = out.display().to_string();
    let err = refused(
        &[
            "run", "--scene", "cloth", "--set", "width=4", "--set", "height=1", "--obj", &out,
        ],
        &["single row", "width and height of at least 2"],
    );
    assert!(!err.contains("such as `cloth`"), "{err}");
    // A layout without a surface still gets the old advice.
    refused(
        &["run", "--scene", "chain", "--obj", &out],
        &["such as `cloth`"],
    );
}

/// `--obj` on a cloth that tears apart says that tearing took the triangles.
#[test]
fn obj_on_a_torn_cloth_says_tearing_took_the_surface() {
    let out = std::env::temp_dir().join(format!("torn-{}.obj", std::process::id()));
    let shown = out.display().to_string();
    let o = cloth(&[
        "run",
        "--scene",
        "cloth",
        "--set",
        "width=8",
        "--set",
        "height=8",
        "--set",
        "tear_strain=0.000001",
        "--steps",
        "200",
        "--obj",
        &shown,
    ]);
    let err = stderr(&o);
    assert!(err.contains("tearing or cutting broke"), "{err}");
    assert!(!err.contains("such as `cloth`"), "{err}");
    assert!(!out.exists());
}

/// `--set rest_length=1e3 --set width=1024 --set height=1024` said "`origin` ...
/// is out of range", a key the user never set: it names their three values.
#[test]
fn an_anchor_out_of_range_names_the_values_that_make_it() {
    refused(
        &[
            "run",
            "--set",
            "rest_length=1e3",
            "--set",
            "width=1024",
            "--set",
            "height=1024",
        ],
        &[
            "`rest_length` = 1000 m with width = 1024 and height = 1024",
            "origin, not set",
            "--set rest_length given before",
        ],
    );
}

/// A scene file's own value that an unrelated `--set` makes out of range is named
/// with the file and its line, beside the `--set`.
#[test]
fn a_files_value_put_out_of_range_by_a_set_names_the_file_and_line() {
    let path = std::env::temp_dir().join(format!("own-key-{}.toml", std::process::id()));
    std::fs::write(
        &path,
        "layout = \"grid\"\nwidth = 8\nheight = 8\nrest_length = 1000.0\npins = \"top-corners\"\n",
    )
    .unwrap();
    let shown = path.display().to_string();
    refused(
        &[
            "run",
            "--scene",
            &shown,
            "--set",
            "width=1024",
            "--set",
            "height=1024",
        ],
        &[
            "--set height=1024: with it, scene file",
            "line 4",
            "`rest_length` = 1000 m",
        ],
    );
    let _ = std::fs::remove_file(&path);
}

/// `cloth run --set layout=mesh` said "`width` does not apply": it says what a
/// mesh layout needs.
#[test]
fn a_mesh_layout_without_a_mesh_says_it_needs_one() {
    refused(
        &["run", "--set", "layout=mesh"],
        &["a mesh layout needs the OBJ file of its cloth, `mesh = \"path/to/file.obj\"`"],
    );
}

/// `--warmup -1` got "unexpected argument '-1'": the message names the option.
#[test]
fn a_negative_count_names_its_option() {
    refused(&["run", "--warmup", "-1"], &["--warmup"]);
    refused(&["run", "--steps", "-1"], &["--steps"]);
    refused(
        &["screenshot", "--steps", "-3", "--out", "x.png"],
        &["--steps"],
    );
    refused(&["record", "--fps", "-3", "--out", "x.gif"], &["--fps"]);
}

/// Keys the layout ignores, and values of a part that is off, were accepted
/// silently: they are refused, saying how to turn the part on; turning a part
/// off with `none` takes its keys with it.
#[test]
fn keys_that_would_be_ignored_are_refused() {
    refused(
        &["run", "--set", "ground_friction=1e300"],
        &[
            "`ground_friction` applies to a part the scene does not have",
            "ground_height",
        ],
    );
    refused(&["run", "--set", "sphere_radius=2"], &["sphere_center"]);
    refused(
        &["run", "--scene", "chain", "--set", "height=5"],
        &["`height` does not apply to a chain layout: it has only width"],
    );
    refused(
        &["run", "--scene", "spring", "--set", "width=5"],
        &["spring layout"],
    );
    refused(
        &["run", "--scene", "rope", "--set", "depth=5"],
        &["rope layout"],
    );
    // The tear scene's ground goes with its stiffness and damping.
    let o = cloth(&[
        "run",
        "--scene",
        "tear",
        "--set",
        "ground_height=none",
        "--steps",
        "10",
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let o = cloth(&[
        "run",
        "--scene",
        "tear",
        "--set",
        "sphere_center=none",
        "--steps",
        "10",
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
}
