//! A triangle mesh from a Wavefront OBJ file as a cloth (`layout = "mesh"`,
//! `mesh = "path.obj"`): read with `tobj`, checked, and turned into springs. Each
//! vertex is a particle at the file's coordinates (m); each edge of a triangle is a
//! structural spring, and the two vertices opposite an interior edge (one shared by
//! two triangles) are joined by a bend spring, both of their length in the file.
//!
//! `tobj` parses the numbers and reports syntax errors; it numbers each object's
//! vertices in the order its faces first use them and splits the file into
//! objects, so a light scan of the `v` and `f` lines here gives back the file's own
//! vertex order (particle `i` is the file's vertex `i + 1`, across all objects)
//! and each face's line, for messages that point at it.

use std::sync::{Arc, Mutex};

use glam::{DVec2, DVec3};

use super::build::GRID_MAX_SIDE;

/// Most vertices a mesh may have: as many particles as the largest grid cloth
/// (`GRID_MAX_SIDE²`, 1,048,576).
pub const MESH_MAX_VERTICES: usize = (GRID_MAX_SIDE as usize) * (GRID_MAX_SIDE as usize);

/// Most triangles a mesh may have, polygons counted as the triangles they are split
/// into: twice the vertices, as a grid cloth has about.
pub const MESH_MAX_TRIANGLES: usize = 2 * MESH_MAX_VERTICES;

/// Largest OBJ file read, in bytes (256 MiB: a mesh at the vertex limit written
/// with texture coordinates and normals takes about 150 MB).
pub const MAX_MESH_FILE_BYTES: u64 = 256 << 20;

/// Largest coordinate in m, as for `origin` and `sphere_center`.
const MAX_COORDINATE: f64 = 1e6;

/// The meshes built into the program, by the path the built-in scenes give them
/// (their `../meshes/NAME.obj` from `assets/scenes/`): used where no file is at
/// that path, so that the installed binary finds them from any folder (and a
/// changed file in the source tree is read as it is).
const BUILTIN_MESHES: &[(&str, &str)] = &[
    (
        "assets/meshes/tablecloth.obj",
        include_str!("../../assets/meshes/tablecloth.obj"),
    ),
    (
        "assets/meshes/table.obj",
        include_str!("../../assets/meshes/table.obj"),
    ),
];

/// A checked triangle mesh: particles, triangles, texture coordinates and the
/// springs its edges give, in the file's coordinates (m).
#[derive(Clone, Debug, PartialEq)]
pub struct Mesh {
    /// Vertex positions in m, in the order of the file's `v` lines.
    pub positions: Vec<DVec3>,
    /// Triangles as the file winds them (polygons split as fans from their first
    /// vertex).
    pub triangles: Vec<[u32; 3]>,
    /// Texture coordinates per vertex: the file's (`vt`, with `v` flipped back from
    /// OBJ's bottom-up images, the first a vertex is given), or without them a
    /// planar projection onto the plane of the mesh's two largest extents.
    pub uvs: Vec<DVec2>,
    /// Whether `uvs` came from the file.
    pub uvs_from_file: bool,
    /// The triangles' edges, `[a, b]` with `a < b`, sorted, each once.
    pub edges: Vec<[u32; 2]>,
    /// For each interior edge, its two opposite vertices, `[a, b]` with `a < b`,
    /// sorted, each pair once and none that is also an edge.
    pub bends: Vec<[u32; 2]>,
}

/// A path as messages show it: at most 64 characters, the end kept (the file name
/// matters more than the folders above it).
pub fn shown_path(path: &str) -> String {
    const MAX: usize = 64;
    let chars = path.chars().count();
    if chars <= MAX {
        return crate::limits::echo(path);
    }
    let tail: String = path.chars().skip(chars - (MAX - 1)).collect();
    crate::limits::echo(&format!("…{tail}"))
}

/// Joins a relative mesh path to the folder of the scene file that names it,
/// dropping `folder/..` pairs (`assets/scenes` + `../meshes/a.obj` is
/// `assets/meshes/a.obj`). An absolute path is kept.
pub fn join_relative(base: &std::path::Path, path: &str) -> String {
    use std::path::Component;
    let given = std::path::Path::new(path);
    if given.is_absolute() {
        return path.to_string();
    }
    let mut parts: Vec<Component> = Vec::new();
    for part in base.components().chain(given.components()) {
        match part {
            Component::CurDir => {}
            Component::ParentDir if matches!(parts.last(), Some(Component::Normal(_))) => {
                parts.pop();
            }
            other => parts.push(other),
        }
    }
    parts
        .iter()
        .collect::<std::path::PathBuf>()
        .to_string_lossy()
        .into_owned()
}

/// The text of the built-in mesh at `path` (as the built-in scenes name it), if
/// there is one.
pub fn builtin_text(path: &str) -> Option<&'static str> {
    BUILTIN_MESHES
        .iter()
        .find(|(p, _)| *p == path)
        .map(|(_, text)| *text)
}

/// What identifies a mesh file's contents without reading it: its path, length
/// and modification time.
type FileStamp = (String, u64, Option<std::time::SystemTime>);

/// The last mesh read from a file: a scene is resolved again on each `--set` and
/// each rebuild, and a mesh of a million vertices takes seconds to read.
static LAST_READ: Mutex<Option<(FileStamp, Arc<Mesh>)>> = Mutex::new(None);

/// Reads and checks the mesh at `path`: the file, or where there is none, a
/// built-in mesh of that path. The error is a sentence to follow "file PATH",
/// starting with ": " or with ", line N: ". The same file, unchanged (same length
/// and modification time), is read once.
pub fn load(path: &str) -> Result<Arc<Mesh>, String> {
    let file = std::path::Path::new(path);
    if let Ok(meta) = std::fs::metadata(file) {
        let stamp: FileStamp = (path.to_string(), meta.len(), meta.modified().ok());
        let last = || {
            LAST_READ
                .lock()
                .unwrap_or_else(|poisoned| poisoned.into_inner())
        };
        // Without a modification time a file cannot be told unchanged.
        if let Some((_, mesh)) =
            (last().as_ref()).filter(|(seen, _)| *seen == stamp && seen.2.is_some())
        {
            return Ok(Arc::clone(mesh));
        }
        let text = crate::limits::read_text_file(file, MAX_MESH_FILE_BYTES)
            .map_err(|why| format!(": cannot be read: {why}"))?;
        let mesh = Arc::new(from_text(&text)?);
        *last() = Some((stamp, Arc::clone(&mesh)));
        return Ok(mesh);
    }
    match builtin_text(path) {
        Some(text) => from_text(text).map(Arc::new),
        None => Err(": no such file (a relative path in a scene file starts from the scene file's folder; on the command line, from the working folder)".to_string()),
    }
}

/// The error at line `line` (1-based).
fn at(line: u32, message: impl std::fmt::Display) -> String {
    format!(", line {line}: {message}")
}

/// What the scan of the `v` and `f` lines found: the line of each vertex, and each
/// face's corners as 0-based file vertex indices with its line.
#[derive(Default)]
struct Scan {
    vertex_lines: Vec<u32>,
    /// Corners of all faces, one after another.
    corners: Vec<u32>,
    /// Where each face's corners start in `corners` (one more entry at the end).
    face_starts: Vec<usize>,
    face_lines: Vec<u32>,
}

impl Scan {
    fn face(&self, f: usize) -> &[u32] {
        &self.corners[self.face_starts[f]..self.face_starts[f + 1]]
    }

    fn faces(&self) -> usize {
        self.face_lines.len()
    }
}

/// Largest texture coordinate a mesh may give (a texture repeated a million times).
pub const MAX_TEXCOORD: f64 = 1e6;

/// Scans the `v`, `f` and `l` lines as `tobj` reads them (one line each, words
/// split on white space, negative indices counting back from the vertices so
/// far), checking counts and vertex references.
fn scan(text: &str) -> Result<Scan, String> {
    let mut scan = Scan {
        face_starts: vec![0],
        ..Scan::default()
    };
    // Vertex references as written (1-based or negative), checked once all
    // vertices are counted (a face may name a vertex given after it).
    let mut triangles = 0usize;
    let (mut texcoords, mut normals) = (0usize, 0usize);
    for (i, line) in text.lines().enumerate() {
        let number = u32::try_from(i + 1).unwrap_or(u32::MAX);
        let mut words = line.split_whitespace();
        let keyword = words.next();
        match keyword {
            Some(kind @ ("vt" | "vn")) => {
                let count = if kind == "vt" {
                    texcoords += 1;
                    texcoords
                } else {
                    normals += 1;
                    normals
                };
                check_finite(number, kind, count, words)?;
            }
            Some("v") => {
                if scan.vertex_lines.len() == MESH_MAX_VERTICES {
                    return Err(format!(
                        ": more than {MESH_MAX_VERTICES} vertices (a mesh may have at most {GRID_MAX_SIDE}², as many as the largest grid cloth)"
                    ));
                }
                scan.vertex_lines.push(number);
            }
            Some(kind @ ("f" | "l")) => {
                let refs: Vec<&str> = words.collect();
                if kind == "l" {
                    if refs.len() <= 2 {
                        continue; // a line between two points: not part of the surface
                    }
                    return Err(at(
                        number,
                        "a polyline (`l`) of three or more points is not a face: a cloth takes its faces from `f` lines",
                    ));
                }
                if refs.len() < 3 {
                    return Err(at(
                        number,
                        format!(
                            "a face needs at least 3 vertices, this one has {}",
                            refs.len()
                        ),
                    ));
                }
                push_corners(&mut scan, number, &refs)?;
                triangles += refs.len() - 2;
                if triangles > MESH_MAX_TRIANGLES {
                    return Err(format!(
                        ": more than {MESH_MAX_TRIANGLES} triangles (a mesh may have at most twice as many triangles as its {MESH_MAX_VERTICES} vertices)"
                    ));
                }
                scan.face_starts.push(scan.corners.len());
                scan.face_lines.push(number);
            }
            _ => {}
        }
    }
    check_references(&scan)?;
    if scan.faces() == 0 {
        return Err(": has no faces (`f` lines): a cloth needs at least one triangle".to_string());
    }
    Ok(scan)
}

/// Checks the values of texture coordinate or normal `count` (`kind`: `vt` or
/// `vn`) on line `number`, as vertices are checked: a number that is not finite
/// (`vt nan nan`) would reach the cloth's texture and `--obj`'s output.
fn check_finite<'a>(
    number: u32,
    kind: &str,
    count: usize,
    words: impl Iterator<Item = &'a str>,
) -> Result<(), String> {
    let (what, limit) = if kind == "vt" {
        ("texture coordinate", MAX_TEXCOORD)
    } else {
        ("normal", f64::MAX)
    };
    let bad = words
        .filter_map(|w| w.parse::<f64>().ok())
        .any(|x| !(x.is_finite() && x.abs() <= limit));
    if bad {
        let range = if kind == "vt" {
            format!(" of at most {MAX_TEXCOORD:e}")
        } else {
            String::new()
        };
        return Err(at(
            number,
            format!("{what} {count} (`{kind}`) has a value that is not a finite number{range}"),
        ));
    }
    Ok(())
}

/// Appends the corners `refs` of the face on line `number` to `scan`, 0-based
/// (negative references count back from the vertices so far).
fn push_corners(scan: &mut Scan, number: u32, refs: &[&str]) -> Result<(), String> {
    let so_far = scan.vertex_lines.len() as i64;
    for r in refs.iter() {
        let index = r
            .split('/')
            .next()
            .and_then(|v| v.parse::<i64>().ok())
            .ok_or_else(|| {
                at(
                    number,
                    format!(
                        "`{}` is not a vertex reference (faces are written `f 1 2 3`, `f 1/1 2/2 3/3` or `f 1//1 2//2 3//3`)",
                        crate::limits::echo(r)
                    ),
                )
            })?;
        let zero_based = match index {
            0 => {
                return Err(at(
                    number,
                    "vertex 0 does not exist: OBJ numbers vertices from 1",
                ));
            }
            i if i > 0 => i - 1,
            i => so_far + i,
        };
        // Out of range either way: kept as a value `check_references` refuses.
        scan.corners
            .push(u32::try_from(zero_based).unwrap_or(u32::MAX));
    }
    Ok(())
}

/// Checks that every face's vertices are in the file.
fn check_references(scan: &Scan) -> Result<(), String> {
    let n = scan.vertex_lines.len();
    for f in 0..scan.faces() {
        if let Some(&bad) = scan.face(f).iter().find(|&&c| c as usize >= n) {
            let written = if bad == u32::MAX {
                "a vertex".to_string()
            } else {
                format!("vertex {}", u64::from(bad) + 1)
            };
            return Err(at(
                scan.face_lines[f],
                format!("{written} is out of range: the file has {n} vertices (1 to {n})"),
            ));
        }
    }
    Ok(())
}

fn tobj_options() -> tobj::LoadOptions {
    tobj::LoadOptions {
        single_index: false,
        triangulate: false,
        ignore_points: true,
        ignore_lines: true,
    }
}

fn run_tobj(text: &str) -> Result<Vec<tobj::Model>, tobj::LoadError> {
    let mut reader = text.as_bytes();
    // Materials (`mtllib`) are not read: a cloth has its own texture.
    tobj::load_obj_buf(&mut reader, &tobj_options(), |_| {
        Err(tobj::LoadError::OpenFileFailed)
    })
    .map(|(models, _materials)| models)
}

/// `tobj`'s error in plain words.
fn plain(error: &tobj::LoadError) -> String {
    use tobj::LoadError as E;
    match error {
        E::PositionParseError => {
            "a vertex (`v x y z`) needs three numbers (then optionally w, or r g b)".into()
        }
        E::ScalingByZeroError => "a vertex's w (its fourth number) is 0".into(),
        E::ColorParseError => {
            "a vertex takes 3 numbers, 4 (with w) or 6 (with a colour), not 5 or more than 6".into()
        }
        E::TexcoordParseError => "a texture coordinate (`vt u v`) needs two numbers".into(),
        E::NormalParseError => "a normal (`vn x y z`) needs three numbers".into(),
        E::FaceParseError => "a face (`f a b c`) needs whole vertex numbers".into(),
        E::FaceTexCoordOutOfBounds => {
            "a face names a texture coordinate (`vt`) the file does not have".into()
        }
        E::FaceNormalOutOfBounds => "a face names a normal (`vn`) the file does not have".into(),
        E::FaceVertexOutOfBounds => "a face names a vertex the file does not have".into(),
        other => format!("cannot be read as OBJ ({other})"),
    }
}

/// The line `tobj` fails at: the first `k` for which the file's first `k` lines
/// fail (it reads line by line and checks a face's references when its object
/// ends, which is where a prefix ends), found by bisection.
fn failing_line(text: &str) -> Option<u32> {
    let mut ends: Vec<usize> = text.match_indices('\n').map(|(i, _)| i + 1).collect();
    if ends.last() != Some(&text.len()) {
        ends.push(text.len());
    }
    let fails = |k: usize| run_tobj(&text[..ends[k - 1]]).is_err();
    let (mut lo, mut hi) = (0usize, ends.len()); // lines 1..=lo pass, 1..=hi fail
    if hi == 0 || !fails(hi) {
        return None;
    }
    while hi - lo > 1 {
        let mid = lo + (hi - lo) / 2;
        if fails(mid) {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    u32::try_from(hi).ok()
}

/// Checks and builds the mesh from an OBJ file's text.
pub fn from_text(text: &str) -> Result<Mesh, String> {
    let scan = scan(text)?;
    let models = run_tobj(text).map_err(|e| match failing_line(text) {
        Some(line) => at(line, plain(&e)),
        None => format!(": {}", plain(&e)),
    })?;
    let n = scan.vertex_lines.len();
    let mut positions = vec![DVec3::NAN; n];
    let mut used = vec![false; n];
    let mut file_uvs: Vec<Option<DVec2>> = vec![None; n];
    let mut face = 0usize;
    let mismatch = |read: usize| {
        format!(
            ": the faces read ({read}) do not match the `f` lines counted ({}); please report this file",
            scan.faces()
        )
    };
    for model in &models {
        let m = &model.mesh;
        let arities: Vec<usize> = if m.face_arities.is_empty() {
            vec![3; m.indices.len() / 3]
        } else {
            m.face_arities.iter().map(|&a| a as usize).collect()
        };
        let mut c = 0usize;
        for arity in arities {
            if face >= scan.faces() || scan.face(face).len() != arity {
                return Err(mismatch(face + 1));
            }
            for (k, &vertex) in scan.face(face).iter().enumerate() {
                let Some(&local) = m.indices.get(c + k) else {
                    return Err(mismatch(face + 1));
                };
                let local = local as usize;
                let v = vertex as usize;
                positions[v] = DVec3::new(
                    m.positions[3 * local],
                    m.positions[3 * local + 1],
                    m.positions[3 * local + 2],
                );
                used[v] = true;
                if let Some(&t) = m.texcoord_indices.get(c + k) {
                    let t = t as usize;
                    file_uvs[v].get_or_insert(DVec2::new(
                        m.texcoords[2 * t],
                        1.0 - m.texcoords[2 * t + 1],
                    ));
                }
            }
            c += arity;
            face += 1;
        }
    }
    if face != scan.faces() {
        return Err(mismatch(face));
    }
    check_vertices(&scan, &positions, &used)?;
    let (triangles, triangle_lines) = triangulate(&scan, &positions)?;
    let (edges, bends) = springs(&triangles, &triangle_lines)?;
    let uvs_from_file = file_uvs.iter().all(Option::is_some);
    let uvs = if uvs_from_file {
        file_uvs.into_iter().flatten().collect()
    } else {
        planar_uvs(&positions)
    };
    Ok(Mesh {
        positions,
        triangles,
        uvs,
        uvs_from_file,
        edges,
        bends,
    })
}

/// Checks that every vertex is used by a face and has finite coordinates in range.
fn check_vertices(scan: &Scan, positions: &[DVec3], used: &[bool]) -> Result<(), String> {
    for (i, x) in positions.iter().enumerate() {
        let line = scan.vertex_lines[i];
        if !used[i] {
            return Err(at(
                line,
                format!(
                    "vertex {} belongs to no face: a particle without springs would fall on its own; remove it or use it in a face",
                    i + 1
                ),
            ));
        }
        if !(x.is_finite() && x.abs().max_element() <= MAX_COORDINATE) {
            return Err(at(
                line,
                format!(
                    "vertex {} has a coordinate that is not a finite number of at most {MAX_COORDINATE:e} m",
                    i + 1
                ),
            ));
        }
    }
    Ok(())
}

/// The faces as triangle fans, each triangle checked, with the line of its face.
fn triangulate(scan: &Scan, positions: &[DVec3]) -> Result<(Vec<[u32; 3]>, Vec<u32>), String> {
    let mut triangles = Vec::new();
    let mut triangle_lines = Vec::new();
    for f in 0..scan.faces() {
        let corners = scan.face(f);
        let line = scan.face_lines[f];
        for w in 1..corners.len() - 1 {
            let t = [corners[0], corners[w], corners[w + 1]];
            check_triangle(t, positions).map_err(|why| at(line, why))?;
            triangles.push(t);
            triangle_lines.push(line);
        }
    }
    Ok((triangles, triangle_lines))
}

/// A triangle's problem, if it has one: a repeated vertex, or no area (its
/// corners on one line, to 1e-12 of its longest edge squared).
fn check_triangle(t: [u32; 3], positions: &[DVec3]) -> Result<(), String> {
    let [a, b, c] = t;
    if a == b || b == c || a == c {
        let repeated = if a == b || a == c { a } else { b };
        return Err(format!(
            "the face repeats vertex {}: a triangle needs three different vertices",
            repeated + 1
        ));
    }
    let [pa, pb, pc] = t.map(|i| positions[i as usize]);
    let twice_area = (pb - pa).cross(pc - pa).length();
    let longest = (pb - pa)
        .length_squared()
        .max((pc - pb).length_squared())
        .max((pa - pc).length_squared());
    if twice_area <= 1e-12 * longest || twice_area == 0.0 {
        return Err(format!(
            "the triangle of vertices {}, {} and {} has no area (its corners are on one line or in one place)",
            a + 1,
            b + 1,
            c + 1
        ));
    }
    Ok(())
}

/// Two vertices, `[a, b]` with `a < b`.
type Pair = [u32; 2];

/// The structural edges and bend pairs of `triangles` (see [`Mesh`]); an edge of
/// more than two triangles (non-manifold) or a triangle given twice is an error
/// naming the lines.
fn springs(triangles: &[[u32; 3]], lines: &[u32]) -> Result<(Vec<Pair>, Vec<Pair>), String> {
    // (a, b, opposite vertex, triangle), a < b.
    let mut sides: Vec<(u32, u32, u32, u32)> = Vec::with_capacity(3 * triangles.len());
    for (t, &[a, b, c]) in triangles.iter().enumerate() {
        for (p, q, opposite) in [(a, b, c), (b, c, a), (c, a, b)] {
            sides.push((p.min(q), p.max(q), opposite, t as u32));
        }
    }
    sides.sort_unstable();
    let (mut edges, mut bends) = (Vec::new(), Vec::new());
    for group in sides.chunk_by(|x, y| (x.0, x.1) == (y.0, y.1)) {
        let (a, b) = (group[0].0, group[0].1);
        let line = |k: usize| lines[group[k].3 as usize];
        match group.len() {
            1 => {}
            2 if group[0].2 == group[1].2 => {
                return Err(at(
                    line(1),
                    format!(
                        "the face gives again the triangle of vertices {}, {} and {} (line {}): each triangle once",
                        a + 1,
                        b + 1,
                        group[0].2 + 1,
                        line(0)
                    ),
                ));
            }
            2 => {
                let (p, q) = (group[0].2, group[1].2);
                bends.push([p.min(q), p.max(q)]);
            }
            k => {
                let mut at_lines: Vec<u32> = (0..k).map(line).collect();
                at_lines.dedup();
                let shown: Vec<String> = at_lines.iter().map(u32::to_string).collect();
                return Err(format!(
                    ": the edge between vertices {} and {} is shared by {k} triangles (lines {}): the mesh is not manifold, and an edge of a cloth joins at most two triangles",
                    a + 1,
                    b + 1,
                    shown.join(", ")
                ));
            }
        }
        edges.push([a, b]);
    }
    bends.sort_unstable();
    bends.dedup();
    bends.retain(|pair| edges.binary_search(pair).is_err());
    Ok((edges, bends))
}

/// Texture coordinates from the positions projected onto the plane of the two
/// largest extents of the bounding box, each scaled to [0, 1].
fn planar_uvs(positions: &[DVec3]) -> Vec<DVec2> {
    let lo = positions.iter().fold(DVec3::INFINITY, |m, p| m.min(*p));
    let hi = positions.iter().fold(DVec3::NEG_INFINITY, |m, p| m.max(*p));
    let extent = (hi - lo).to_array();
    let mut axes = [0usize, 1, 2];
    axes.sort_by(|&i, &j| extent[j].total_cmp(&extent[i]));
    let (u, v) = (axes[0], axes[1]);
    let scaled = |p: DVec3, axis: usize| {
        if extent[axis] > 0.0 {
            (p.to_array()[axis] - lo.to_array()[axis]) / extent[axis]
        } else {
            0.0
        }
    };
    positions
        .iter()
        .map(|&p| DVec2::new(scaled(p, u), scaled(p, v)))
        .collect()
}
