//! OBJ export (`cloth_sandbox::export`, `cloth run --obj`): the written file is
//! parsed back here, independently of the writer, and checked against the system
//! it came from: one `v`, `vt` and `vn` per particle and one `f` per triangle, the
//! positions equal to the printed precision, the texture coordinates the scene's
//! (with `v` flipped), the normals unit length and on the side the face winding
//! says. Scenes without a surface and bad paths are refused in plain words.

use crate::common;

use cloth_sandbox::export::{self, ExportError};
use cloth_sandbox::sim::System;
use glam::{DVec2, DVec3};

/// An OBJ file as read back: the four kinds of lines this exporter writes.
#[derive(Default)]
struct Obj {
    positions: Vec<DVec3>,
    uvs: Vec<DVec2>,
    normals: Vec<DVec3>,
    /// Per face, per corner: (position, texture, normal) indices, 0-based.
    faces: Vec<[(usize, usize, usize); 3]>,
}

fn numbers(fields: &[&str]) -> Vec<f64> {
    fields
        .iter()
        .map(|f| {
            f.parse::<f64>()
                .unwrap_or_else(|_| panic!("a number, got {f:?}"))
        })
        .collect()
}

fn parse(text: &str) -> Obj {
    let mut obj = Obj::default();
    for line in text.lines() {
        let fields: Vec<&str> = line.split_whitespace().collect();
        match fields.first().copied() {
            None | Some("#") | Some("o") => {}
            Some("v") => {
                let n = numbers(&fields[1..]);
                assert_eq!(n.len(), 3, "{line}");
                obj.positions.push(DVec3::new(n[0], n[1], n[2]));
            }
            Some("vt") => {
                let n = numbers(&fields[1..]);
                assert_eq!(n.len(), 2, "{line}");
                obj.uvs.push(DVec2::new(n[0], n[1]));
            }
            Some("vn") => {
                let n = numbers(&fields[1..]);
                assert_eq!(n.len(), 3, "{line}");
                obj.normals.push(DVec3::new(n[0], n[1], n[2]));
            }
            Some("f") => {
                assert_eq!(fields.len(), 4, "triangles only: {line}");
                let corner = |f: &str| {
                    let ids: Vec<usize> = f
                        .split('/')
                        .map(|i| i.parse::<usize>().expect("a 1-based index"))
                        .collect();
                    assert_eq!(ids.len(), 3, "v/vt/vn: {line}");
                    assert!(ids.iter().all(|&i| i >= 1), "1-based: {line}");
                    (ids[0] - 1, ids[1] - 1, ids[2] - 1)
                };
                obj.faces
                    .push([corner(fields[1]), corner(fields[2]), corner(fields[3])]);
            }
            Some(other) => panic!("unexpected line kind {other:?}: {line}"),
        }
    }
    obj
}

fn obj_of(system: &System, scene: &str) -> Obj {
    let mut bytes = Vec::new();
    export::write_obj(system, scene, &mut bytes).expect("a cloth exports");
    parse(&String::from_utf8(bytes).expect("OBJ is text"))
}

/// Checks everything an OBJ of `system` must satisfy; returns the worst
/// position error.
fn check(system: &System, obj: &Obj) -> f64 {
    let n = system.particle_count();
    assert_eq!(obj.positions.len(), n, "one v per particle");
    assert_eq!(obj.uvs.len(), n, "one vt per particle");
    assert_eq!(obj.normals.len(), n, "one vn per particle");
    assert_eq!(
        obj.faces.len(),
        system.triangles().len(),
        "one f per triangle"
    );
    // Positions to the 6 printed decimals.
    let worst = common::max_distance(&obj.positions, system.positions());
    assert!(
        worst <= 0.5e-6 * 3f64.sqrt() + 1e-12,
        "positions off by {worst}"
    );
    // Texture coordinates: the scene's, v flipped for OBJ's bottom-up images.
    for (uv, want) in obj.uvs.iter().zip(system.uvs()) {
        assert!((uv.x - want.x).abs() <= 0.5e-6 && (uv.y - (1.0 - want.y)).abs() <= 0.5e-6);
    }
    for (i, n) in obj.normals.iter().enumerate() {
        assert!(
            (n.length() - 1.0).abs() < 1e-5,
            "normal {i} has length {}",
            n.length()
        );
    }
    for (face, tri) in obj.faces.iter().zip(system.triangles()) {
        // The same triangle, in the same winding, with one index per particle.
        let corners = face.map(|(v, vt, vn)| {
            assert!(v == vt && v == vn, "one index for v, vt and vn: {face:?}");
            assert!(v < n);
            v as u32
        });
        assert_eq!(&corners, tri);
        // The face normal by the winding, from the file's own positions.
        let [a, b, c] = corners.map(|i| obj.positions[i as usize]);
        let face_normal = (b - a).cross(c - a);
        if face_normal.length() < 1e-9 {
            continue;
        }
        let vertex_normals: DVec3 = corners.iter().map(|&i| obj.normals[i as usize]).sum();
        assert!(
            face_normal.dot(vertex_normals) > 0.0,
            "the vertex normals of {tri:?} point against its winding"
        );
    }
    worst
}

#[test]
fn a_flat_cloth_has_the_face_normal_at_every_vertex() {
    // Not square, so that rows and columns cannot be swapped unseen.
    let system = common::build("cloth", &["width=9", "height=6"]);
    let obj = obj_of(&system, "cloth");
    check(&system, &obj);
    let [a, b, c] = system.triangles()[0].map(|i| system.positions()[i as usize]);
    let face = (b - a).cross(c - a).normalize();
    for n in &obj.normals {
        assert!(n.distance(face) < 1e-5, "{n} against {face}");
    }
}

#[test]
fn a_moving_cloth_reads_back_as_written() {
    for scene in ["cloth", "flag", "drape"] {
        let mut system = common::build(scene, &["width=17", "height=11"]);
        system.run(300).expect("stable");
        let obj = obj_of(&system, scene);
        let worst = check(&system, &obj);
        assert!(worst > 0.0 || system.steps_taken() == 0);
    }
}

#[test]
fn scenes_without_a_surface_are_refused_in_words() {
    for scene in ["chain", "spring", "rope"] {
        let system = common::build(scene, &[]);
        let mut bytes = Vec::new();
        let err = export::write_obj(&system, scene, &mut bytes).unwrap_err();
        assert!(matches!(err, ExportError::NoSurface { .. }), "{err:?}");
        let text = err.to_string();
        assert!(
            text.contains(&format!("`{scene}` has no surface")),
            "{text}"
        );
        assert!(bytes.is_empty(), "nothing written");
    }
}

#[test]
fn export_in_a_folder_never_replaces_a_file() {
    let dir = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("export_obj_in");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let system = common::build("cloth", &["width=4", "height=4"]);
    std::fs::write(dir.join("cloth-flag-1.obj"), "keep me").unwrap();
    let first = export::export_obj_in(&system, "flag", &dir).unwrap();
    let second = export::export_obj_in(&system, "flag", &dir).unwrap();
    assert_eq!(first, dir.join("cloth-flag-2.obj"));
    assert_eq!(second, dir.join("cloth-flag-3.obj"));
    assert_eq!(
        std::fs::read_to_string(dir.join("cloth-flag-1.obj")).unwrap(),
        "keep me"
    );
    check(&system, &parse(&std::fs::read_to_string(&second).unwrap()));
    // A saved scene file's name gives the scene part, as Save's names do.
    let third = export::export_obj_in(&system, "/some/where/saved-drape-4.toml", &dir).unwrap();
    assert_eq!(third, dir.join("cloth-drape-1.obj"));
    let missing = dir.join("no-such-folder");
    let err = export::export_obj_in(&system, "flag", &missing).unwrap_err();
    assert!(err.to_string().contains("no-such-folder"), "{err}");
}

/// `cloth run --obj`: the file, and the refusals, through the real binary.
#[cfg(feature = "app")]
mod cli {
    use super::*;
    use std::path::PathBuf;
    use std::process::Command;

    fn dir() -> PathBuf {
        let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("export_obj_cli");
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    fn cloth(args: &[&str]) -> (i32, String) {
        let out = Command::new(env!("CARGO_BIN_EXE_cloth"))
            .args(args)
            .output()
            .expect("the cloth binary runs");
        let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
        assert!(!stderr.contains("panicked"), "{stderr}");
        (out.status.code().expect("exited"), stderr)
    }

    #[test]
    fn run_writes_the_end_state() {
        let path = dir().join("end.obj");
        let _ = std::fs::remove_file(&path);
        let shown = path.to_str().unwrap();
        let (code, stderr) = cloth(&[
            "run", "--scene", "cloth", "--set", "width=12", "--set", "height=8", "--steps", "200",
            "--obj", shown,
        ]);
        assert_eq!(code, 0, "{stderr}");
        assert!(
            stderr.contains(&format!("wrote {shown} (96 vertices, 154 triangles")),
            "{stderr}"
        );
        // The same run in the library gives the same cloth.
        let mut system = common::build("cloth", &["width=12", "height=8"]);
        system.set_fast_path(true);
        system.run(200).unwrap();
        let obj = parse(&std::fs::read_to_string(&path).unwrap());
        let worst = check(&system, &obj);
        assert!(worst < 1e-6, "{worst}");
    }

    #[test]
    fn bad_obj_paths_and_surfaceless_scenes_exit_2_in_words() {
        let d = dir();
        let folder = d.to_str().unwrap().to_string();
        let missing = d.join("missing").join("x.obj");
        let missing = missing.to_str().unwrap();
        let cases: [(&[&str], &str); 3] = [
            (&["--obj", &folder], "is a folder"),
            (&["--obj", missing], "does not exist"),
            (
                &["--scene", "chain", "--obj", "never.obj"],
                "`chain` has no surface",
            ),
        ];
        for (args, expect) in cases {
            let mut all = vec!["run", "--steps", "10"];
            all.extend_from_slice(args);
            let (code, stderr) = cloth(&all);
            assert_eq!(code, 2, "{all:?}: {stderr}");
            assert!(stderr.starts_with("error: --obj "), "{stderr}");
            assert!(stderr.contains(expect), "{all:?}: {stderr}");
        }
        assert!(!std::path::Path::new("never.obj").exists());
    }
}
