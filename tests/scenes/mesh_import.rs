//! A triangle mesh from an OBJ file as a cloth (`layout = "mesh"`, `mesh =
//! "file.obj"`). Spring counts and rest lengths of tiny meshes worked out by hand;
//! every refused file gets a message naming it (and the line, where there is one);
//! keys that mean nothing for a mesh are refused; the built-in `tablecloth` scene
//! loads from its file and from the binary alike, runs finite on the general engine
//! and agrees with the f64 general engine; and a cloth exported with
//! `export::write_obj` comes back as a mesh with the same particles, triangles,
//! texture coordinates and the springs its edges give.

use crate::common;

use std::path::{Path, PathBuf};

use cloth_sandbox::scene::mesh::MESH_MAX_VERTICES;
use cloth_sandbox::scene::{Edit, Layout, Scene, SceneError};
use cloth_sandbox::sim::{Engine, SpringKind, System};
use glam::DVec2;

/// A fresh scratch folder for one test.
fn scratch(test: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("cloth-mesh-import-{}-{test}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("scratch folder");
    dir
}

/// Writes `obj` as `name` in `dir` and returns its path.
fn write(dir: &Path, name: &str, obj: &str) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, obj).expect("writes the OBJ file");
    path
}

/// A mesh scene of the OBJ file at `path`, with more TOML lines.
fn mesh_scene(path: &Path, more: &str) -> Result<Scene, SceneError> {
    let text = format!("layout = \"mesh\"\nmesh = '{}'\n{more}", path.display());
    Scene::parse(&text, "test scene")
}

fn build(path: &Path, more: &str) -> System {
    mesh_scene(path, more)
        .unwrap_or_else(|e| panic!("{e}"))
        .build()
        .expect("builds")
}

/// The springs of `kind` as sorted `(a, b, rest)`.
fn springs(system: &System, kind: SpringKind) -> Vec<(u32, u32, f64)> {
    let mut s: Vec<_> = system
        .springs()
        .iter()
        .filter(|s| s.kind == kind)
        .map(|s| (s.a.min(s.b), s.a.max(s.b), s.rest))
        .collect();
    s.sort_by_key(|x| (x.0, x.1));
    s
}

/// A unit square in the x-z plane, vertices 1 (0,0,0), 2 (1,0,0), 3 (1,0,1),
/// 4 (0,0,1), as two triangles sharing the diagonal 1-3.
const SQUARE: &str = "v 0 0 0\nv 1 0 0\nv 1 0 1\nv 0 0 1\nf 1 2 3\nf 1 3 4\n";

#[test]
fn two_triangles_sharing_an_edge_give_five_structural_springs_and_one_bend() {
    let dir = scratch("square");
    let system = build(&write(&dir, "square.obj", SQUARE), "");
    let r2 = 2f64.sqrt();
    // The four sides of the square and the shared diagonal 1-3 (0-based 0-2).
    let expected = [
        (0, 1, 1.0),
        (0, 2, r2),
        (0, 3, 1.0),
        (1, 2, 1.0),
        (2, 3, 1.0),
    ];
    let structural = springs(&system, SpringKind::Structural);
    assert_eq!(structural.len(), 5);
    for (got, want) in structural.iter().zip(expected) {
        assert_eq!((got.0, got.1), (want.0, want.1));
        assert!((got.2 - want.2).abs() < 1e-15, "{got:?} against {want:?}");
    }
    // The vertices opposite the diagonal: 2 and 4 (0-based 1 and 3), sqrt 2 apart.
    let bend = springs(&system, SpringKind::Bend);
    assert_eq!(bend.len(), 1);
    assert_eq!((bend[0].0, bend[0].1), (1, 3));
    assert!((bend[0].2 - r2).abs() < 1e-15);
    assert!(springs(&system, SpringKind::Shear).is_empty());
    assert_eq!(system.particle_count(), 4);
    assert_eq!(system.triangles(), &[[0, 1, 2], [0, 2, 3]]);
    // No `vt`: a planar projection onto x and z, each scaled to [0, 1].
    let uvs: Vec<DVec2> = system.uvs().to_vec();
    let want = [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)];
    for (uv, (u, v)) in uvs.iter().zip(want) {
        assert_eq!((uv.x, uv.y), (u, v));
    }
    // Default pins on a mesh: none.
    assert!((0..4).all(|i| !system.is_pinned(i)));
}

#[test]
fn a_quad_is_split_as_a_fan_into_the_same_two_triangles() {
    let dir = scratch("quad");
    let quad = "v 0 0 0\nv 1 0 0\nv 1 0 1\nv 0 0 1\nf 1 2 3 4\n";
    let from_quad = build(&write(&dir, "quad.obj", quad), "");
    let from_triangles = build(&write(&dir, "square.obj", SQUARE), "");
    assert_eq!(from_quad.triangles(), from_triangles.triangles());
    assert_eq!(from_quad.springs(), from_triangles.springs());
}

#[test]
fn a_closed_tetrahedron_has_six_edges_and_its_bend_pairs_collapse_onto_them() {
    // Every edge of a tetrahedron is interior, and the two vertices opposite it
    // are the ends of the opposite edge: each bend pair is already an edge, so the
    // six edges stay six springs and there is no bend spring.
    let dir = scratch("tetra");
    let tetra = "v 0 0 0\nv 1 0 0\nv 0 0 1\nv 0 1 0\nf 1 3 2\nf 1 2 4\nf 2 3 4\nf 3 1 4\n";
    let system = build(&write(&dir, "tetra.obj", tetra), "");
    assert_eq!(springs(&system, SpringKind::Structural).len(), 6);
    assert!(springs(&system, SpringKind::Bend).is_empty());
    assert_eq!(system.springs().len(), 6);
    // The mesh itself lists no bend pair that is an edge (the system would drop the
    // duplicate anyway, keeping the structural spring).
    let mesh = cloth_sandbox::scene::mesh::from_text(tetra).unwrap();
    assert_eq!(mesh.edges.len(), 6);
    assert!(mesh.bends.is_empty(), "{:?}", mesh.bends);
}

#[test]
fn bend_scale_zero_leaves_only_the_edges() {
    let dir = scratch("bend0");
    let system = build(&write(&dir, "square.obj", SQUARE), "bend_scale = 0.0");
    assert_eq!(system.springs().len(), 5);
    let stiff = build(
        &write(&dir, "square.obj", SQUARE),
        "stiffness = 50.0\nbend_scale = 0.25",
    );
    let bend = stiff
        .springs()
        .iter()
        .find(|s| s.kind == SpringKind::Bend)
        .unwrap();
    assert_eq!(stiff.model().material(bend.kind).stiffness, 12.5);
    let edge = stiff
        .springs()
        .iter()
        .find(|s| s.kind == SpringKind::Structural)
        .unwrap();
    assert_eq!(stiff.model().material(edge.kind).stiffness, 50.0);
}

#[test]
fn pins_come_from_a_list_and_from_a_height() {
    let dir = scratch("pins");
    // A vertical strip: vertices at heights 0, 0, 1, 1, 2, 2.
    let strip = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nv 0 2 0\nv 1 2 0\n\
                 f 1 2 4\nf 1 4 3\nf 3 4 6\nf 3 6 5\n";
    let path = write(&dir, "strip.obj", strip);
    let pinned = |s: &System| {
        (0..s.particle_count())
            .filter(|&i| s.is_pinned(i))
            .collect::<Vec<_>>()
    };
    assert_eq!(pinned(&build(&path, "pins = [0, 3]")), [0, 3]);
    assert_eq!(pinned(&build(&path, "pin_above = 1.5")), [4, 5]);
    // At or above; with a list, both.
    assert_eq!(
        pinned(&build(&path, "pin_above = 1.0\npins = [0]")),
        [0, 2, 3, 4, 5]
    );
    // The height is where the scene puts the mesh: 1 m up, so the middle row is at 2.
    assert_eq!(
        pinned(&build(&path, "pin_above = 1.5\norigin = \"0,1,0\"")),
        [2, 3, 4, 5]
    );
    // Turned upside down about x (y -> -y), the bottom row is the top one.
    assert_eq!(
        pinned(&build(&path, "pin_above = -0.5\nrotation = \"180,0,0\"")),
        [0, 1]
    );
    let e = mesh_scene(&path, "pins = [6]").unwrap_err().to_string();
    assert!(e.contains("`pins`") && e.contains("6 particles"), "{e}");
}

/// The message for the OBJ text `obj`, which must be refused.
fn refusal(dir: &Path, name: &str, obj: &str) -> String {
    let path = write(dir, name, obj);
    let e = mesh_scene(&path, "").expect_err(&format!("{name} must be refused"));
    let message = e.to_string();
    assert!(matches!(e, SceneError::Invalid { .. }), "{message}");
    assert!(message.contains("`mesh`"), "names the key: {message}");
    assert!(
        message.contains(&path.display().to_string()) || message.contains(name),
        "names the file: {message}"
    );
    message
}

#[test]
fn each_bad_mesh_is_refused_naming_the_file_and_the_line() {
    let dir = scratch("bad");
    let cases: &[(&str, &str, &[&str])] = &[
        (
            "unparseable.obj",
            "v 0 0 0\nv 1 0 0\nv 1 x 1\nf 1 2 3\n",
            &["line 3", "three numbers"],
        ),
        ("no-faces.obj", "v 0 0 0\nv 1 0 0\nv 1 0 1\n", &["no faces"]),
        (
            "two-corners.obj",
            "v 0 0 0\nv 1 0 0\nv 1 0 1\nf 1 2\n",
            &["line 4", "at least 3 vertices"],
        ),
        (
            "polyline.obj",
            "v 0 0 0\nv 1 0 0\nv 1 0 1\nl 1 2 3\nf 1 2 3\n",
            &["line 4", "polyline"],
        ),
        (
            "repeated.obj",
            "v 0 0 0\nv 1 0 0\nv 1 0 1\nf 1 2 3\nf 1 3 3\n",
            &["line 5", "repeats vertex 3"],
        ),
        (
            "flat.obj",
            "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n",
            &["line 4", "no area"],
        ),
        (
            "same-place.obj",
            "v 0 0 0\nv 1 0 0\nv 0 0 0\nf 1 2 3\n",
            &["line 4", "no area"],
        ),
        (
            "out-of-range.obj",
            "v 0 0 0\nv 1 0 0\nv 1 0 1\nf 1 2 3\nf 1 3 9\n",
            &["line 5", "vertex 9 is out of range", "3 vertices"],
        ),
        (
            "relative-out.obj",
            "v 0 0 0\nv 1 0 0\nf -1 -2 -3\n",
            &["line 3", "out of range"],
        ),
        (
            "zero.obj",
            "v 0 0 0\nv 1 0 0\nv 1 0 1\nf 0 1 2\n",
            &["line 4", "from 1"],
        ),
        (
            "bad-ref.obj",
            "v 0 0 0\nv 1 0 0\nv 1 0 1\nf 1 2 x\n",
            &["line 4", "`x` is not a vertex reference"],
        ),
        (
            "bad-vt.obj",
            "v 0 0 0\nv 1 0 0\nv 1 0 1\nvt 0 0\nf 1/1 2/2 3/3\n",
            &["line 5", "texture coordinate"],
        ),
        (
            "non-manifold.obj",
            "v 0 0 0\nv 1 0 0\nv 0 0 1\nv 0 1 0\nv 0 -1 0\nf 1 2 3\nf 1 2 4\nf 2 1 5\n",
            &[
                "vertices 1 and 2",
                "shared by 3 triangles",
                "lines 6, 7, 8",
                "not manifold",
            ],
        ),
        (
            "twice.obj",
            "v 0 0 0\nv 1 0 0\nv 1 0 1\nf 1 2 3\nf 3 2 1\n",
            &["line 5", "again", "line 4"],
        ),
        (
            "unused.obj",
            "v 0 0 0\nv 1 0 0\nv 1 0 1\nv 5 5 5\nf 1 2 3\n",
            &["line 4", "vertex 4 belongs to no face"],
        ),
        (
            "nan.obj",
            "v 0 0 0\nv nan 0 0\nv 1 0 1\nf 1 2 3\n",
            &["line 2", "not a finite number"],
        ),
        (
            "far.obj",
            "v 0 0 0\nv 1e9 0 0\nv 1 0 1\nf 1 2 3\n",
            &["line 2", "not a finite number"],
        ),
    ];
    for (name, obj, words) in cases {
        let message = refusal(&dir, name, obj);
        for w in *words {
            assert!(message.contains(w), "{name}: expected `{w}` in: {message}");
        }
    }
}

#[test]
fn a_missing_file_and_a_huge_one_are_refused_naming_them() {
    let dir = scratch("huge");
    let missing = dir.join("nowhere.obj");
    let e = mesh_scene(&missing, "").unwrap_err().to_string();
    assert!(
        e.contains("nowhere.obj") && e.contains("no such file"),
        "{e}"
    );
    // One vertex past the limit (about 8 MB of `v 0 0 0`).
    let mut obj = "v 0 0 0\n".repeat(MESH_MAX_VERTICES + 1);
    obj.push_str("f 1 2 3\n");
    let message = refusal(&dir, "huge.obj", &obj);
    assert!(
        message.contains(&format!("more than {MESH_MAX_VERTICES} vertices")),
        "{message}"
    );
    // A folder is not a mesh file.
    let e = mesh_scene(&dir, "").unwrap_err().to_string();
    assert!(e.contains("not a regular file"), "{e}");
}

#[test]
fn keys_that_mean_nothing_for_the_layout_are_refused() {
    let dir = scratch("keys");
    let path = write(&dir, "square.obj", SQUARE);
    for (line, key) in [
        ("width = 4", "width"),
        ("height = 4", "height"),
        ("depth = 2", "depth"),
        ("rest_length = 0.1", "rest_length"),
        ("size = 1.0", "size"),
        ("orientation = \"horizontal\"", "orientation"),
        ("shear_scale = 0.5", "shear_scale"),
        ("stretch = 0.5", "stretch"),
        ("bars = true", "bars"),
        ("bar_iterations = 4", "bar_iterations"),
    ] {
        let e = mesh_scene(&path, line).expect_err(line).to_string();
        assert!(
            e.contains(&format!("`{key}`")) && e.contains("mesh layout"),
            "{line}: {e}"
        );
    }
    let e = Scene::parse("layout = \"mesh\"", "test")
        .unwrap_err()
        .to_string();
    assert!(e.contains("`mesh` is missing"), "{e}");
    for line in [
        format!("mesh = '{}'", path.display()),
        "pin_above = 1.0".to_string(),
    ] {
        let e = Scene::parse(&line, "test").unwrap_err().to_string();
        assert!(
            e.contains("grid layout") && e.contains("layout = \"mesh\""),
            "{e}"
        );
    }
    // `--set` and the panel's edits take the same rules.
    let mut scene = mesh_scene(&path, "").unwrap();
    let e = scene.set("width", "8").unwrap_err().to_string();
    assert!(e.contains("`width`") && e.contains("mesh layout"), "{e}");
    let e = scene.apply(Edit::RestLength(0.2)).unwrap_err().to_string();
    assert!(
        e.contains("rest_length") && e.contains("edges give the rest lengths"),
        "{e}"
    );
    let e = scene.apply(Edit::Width(8)).unwrap_err().to_string();
    assert!(e.contains("mesh layout"), "{e}");
    // A misspelt key gets the usual hint.
    let e = mesh_scene(&path, "pin_abve = 1.0").unwrap_err().to_string();
    assert!(e.contains("did you mean `pin_above`"), "{e}");
}

#[test]
fn a_relative_mesh_path_starts_from_the_scene_files_folder() {
    let dir = scratch("relative");
    std::fs::create_dir_all(dir.join("scenes")).unwrap();
    std::fs::create_dir_all(dir.join("meshes")).unwrap();
    write(&dir.join("meshes"), "square.obj", SQUARE);
    let scene_path = write(
        &dir.join("scenes"),
        "square.toml",
        "layout = \"mesh\"\nmesh = \"../meshes/square.obj\"\n",
    );
    let scene = Scene::load(scene_path.to_str().unwrap()).unwrap_or_else(|e| panic!("{e}"));
    let system = scene.build().unwrap();
    assert_eq!(system.particle_count(), 4);
    assert_eq!(
        scene.spec.mesh.as_deref(),
        Some(dir.join("meshes/square.obj").to_str().unwrap())
    );
    // Without the scene file's folder the same text names a file that is not there.
    let e = Scene::parse("layout = \"mesh\"\nmesh = \"../meshes/square.obj\"", "text")
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("../meshes/square.obj") && e.contains("no such file"),
        "{e}"
    );
}

/// The tablecloth's counts, from its construction (make_tablecloth.py): 24 rings,
/// ring k holding 6k vertices, the centre one more; 6 (2k - 1) triangles between
/// rings k - 1 and k, 6 K² in all. A disc has V - E + F = 1, and its 6 K boundary
/// edges are the only ones not shared by two triangles.
const RINGS: usize = 24;
const TABLECLOTH_V: usize = 1 + 3 * RINGS * (RINGS + 1);
const TABLECLOTH_F: usize = 6 * RINGS * RINGS;
const TABLECLOTH_E: usize = TABLECLOTH_V + TABLECLOTH_F - 1;
const TABLECLOTH_BENDS: usize = TABLECLOTH_E - 6 * RINGS;

#[test]
fn the_tablecloth_scene_loads_from_its_file_and_the_binary_alike() {
    let builtin = Scene::load("tablecloth").unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(builtin.spec.layout, Layout::Mesh);
    assert!(builtin.spec.description.is_some());
    let file = Scene::load("assets/scenes/tablecloth.toml").unwrap_or_else(|e| panic!("{e}"));
    let (a, b) = (builtin.build().unwrap(), file.build().unwrap());
    assert_eq!(a.positions(), b.positions());
    assert_eq!(a.springs(), b.springs());
    assert_eq!(a.uvs(), b.uvs());
    assert_eq!(a.particle_count(), TABLECLOTH_V);
    assert_eq!(a.triangles().len(), TABLECLOTH_F);
    assert_eq!(springs(&a, SpringKind::Structural).len(), TABLECLOTH_E);
    assert_eq!(springs(&a, SpringKind::Bend).len(), TABLECLOTH_BENDS);
    // Lying flat 0.8 m up, within 0.9 m of the vertical axis.
    for p in a.positions() {
        assert!(
            (p.y - 0.8).abs() < 1e-12 && p.x.hypot(p.z) <= 0.9 + 1e-6,
            "{p}"
        );
    }
    // The copy built into the binary (used where no file is at the path) is the
    // file, and builds the same cloth.
    let path = "assets/meshes/tablecloth.obj";
    let builtin_text = cloth_sandbox::scene::mesh::builtin_text(path).expect("built in");
    assert_eq!(builtin_text, std::fs::read_to_string(path).unwrap());
    let mesh = cloth_sandbox::scene::mesh::from_text(builtin_text).unwrap();
    assert_eq!(mesh.positions.len(), TABLECLOTH_V);
    // The built-in scene is in the list the app and `cloth scenes` show.
    assert!(
        cloth_sandbox::scene::builtin_scenes()
            .iter()
            .any(|s| s.name == "tablecloth")
    );
}

#[test]
fn the_tablecloth_drapes_over_the_sphere_finite_at_every_step() {
    let mut system = common::build("tablecloth", &[]);
    system.set_fast_path(true);
    assert_eq!(system.engine(), Engine::General);
    let sphere = system.params().sphere.expect("a sphere");
    // 2 s in chunks, finite after each.
    for _ in 0..60 {
        system.run(32).expect("no divergence");
        assert!(system.positions().iter().all(|p| p.is_finite()));
        assert!(system.velocities().iter().all(|v| v.is_finite()));
    }
    // Draped: the middle rests on top of the sphere, the rim hangs below its equator.
    let centre = system.positions()[0];
    assert!(
        (centre - sphere.center).length() < sphere.radius + 0.01,
        "{centre}"
    );
    let lowest = system
        .positions()
        .iter()
        .map(|p| p.y)
        .fold(f64::INFINITY, f64::min);
    assert!(lowest < sphere.center.y, "lowest {lowest}");
}

#[test]
fn with_aerodynamic_drag_the_mesh_catches_the_wind() {
    // A side wind moves the cloth along it.
    let run = |wind: &str| {
        let mut s = common::build(
            "tablecloth",
            &["drag_coefficient=1", &format!("wind={wind}")],
        );
        s.set_fast_path(true);
        assert_eq!(s.engine(), Engine::General);
        s.run(480).unwrap();
        assert!(s.positions().iter().all(|p| p.is_finite()));
        s.positions().iter().map(|p| p.x).sum::<f64>() / s.particle_count() as f64
    };
    let (still, windy) = (run("0,0,0"), run("4,0,0"));
    println!("mean x after 0.5 s: {still:e} m still, {windy:e} m in the wind");
    assert!(still.abs() < 1e-9, "no wind, no drift: {still}");
    assert!(
        windy > 0.01,
        "a 4 m/s wind along x moves the cloth along x: {windy}"
    );
}

#[test]
fn an_exported_cloth_comes_back_as_a_mesh_with_the_same_particles_and_springs() {
    let dir = scratch("round-trip");
    let mut cloth = common::build("cloth", &[]);
    cloth.run(200).unwrap();
    let mut text = Vec::new();
    cloth_sandbox::export::write_obj(&cloth, "cloth", &mut text).unwrap();
    let path = write(&dir, "cloth.obj", std::str::from_utf8(&text).unwrap());
    let mesh = build(&path, "");
    // 32 x 32 particles, two triangles per cell; the edges are the grid's
    // structural springs (2 x 32 x 31) and one diagonal per cell (31 x 31); every
    // edge inside the cloth is shared by two triangles: all but the 4 x 31 on
    // its border.
    let (n, cells) = (32 * 32, 31 * 31);
    assert_eq!(mesh.particle_count(), n);
    assert_eq!(mesh.triangles(), cloth.triangles());
    let edges = 2 * 32 * 31 + cells;
    assert_eq!(springs(&mesh, SpringKind::Structural).len(), edges);
    assert_eq!(springs(&mesh, SpringKind::Bend).len(), edges - 4 * 31);
    // Positions to the 6 decimals written; texture coordinates as the scene's.
    for (p, q) in mesh.positions().iter().zip(cloth.positions()) {
        assert!(
            (*p - *q).abs().max_element() <= 5e-7 + 1e-12,
            "{p} against {q}"
        );
    }
    for (p, q) in mesh.uvs().iter().zip(cloth.uvs()) {
        assert!(
            (*p - *q).abs().max_element() <= 5e-7 + 1e-12,
            "{p} against {q}"
        );
    }
    // Each edge's rest length is its length in the exported file.
    for s in mesh.springs() {
        let (a, b) = (
            mesh.positions()[s.a as usize],
            mesh.positions()[s.b as usize],
        );
        assert!((a.distance(b) - s.rest).abs() < 1e-12);
    }
}

#[cfg(feature = "app")]
#[test]
fn cloth_info_names_the_general_engine_and_run_json_works() {
    use crate::binary::{cloth, stderr, stdout};
    let o = cloth(&["info", "--scene", "tablecloth"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(stdout(&o).contains("engine: general-f64"), "{}", stdout(&o));
    let o = cloth(&["run", "--scene", "tablecloth", "--steps", "100", "--json"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let out = stdout(&o);
    assert!(
        out.trim_start().starts_with('{') && out.contains("general-f64"),
        "{out}"
    );
    let o = cloth(&[
        "run",
        "--scene",
        "tablecloth",
        "--steps",
        "1",
        "--set",
        "width=8",
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("mesh layout"), "{}", stderr(&o));
    // From a folder without assets/: the mesh built into the binary.
    let elsewhere = scratch("elsewhere");
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_cloth"))
        .args(["info", "--scene", "tablecloth"])
        .current_dir(&elsewhere)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(stdout(&o).contains("particles: 1801"), "{}", stdout(&o));
}

#[test]
fn a_mesh_file_changed_on_disk_is_read_again() {
    // The last file read is kept while its length and modification time stay.
    let dir = scratch("changed");
    let path = write(&dir, "m.obj", SQUARE);
    assert_eq!(build(&path, "").particle_count(), 4);
    assert_eq!(build(&path, "").particle_count(), 4);
    write(&dir, "m.obj", &format!("{SQUARE}v 2 0 0\nf 2 5 3\n"));
    assert_eq!(build(&path, "").particle_count(), 5);
    write(&dir, "m.obj", "v 0 0 0\n");
    let e = mesh_scene(&path, "").unwrap_err().to_string();
    assert!(e.contains("no faces"), "{e}");
}
