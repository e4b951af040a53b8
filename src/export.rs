//! The cloth's surface as a Wavefront OBJ file, for other 3D tools: one `v x y z`
//! per particle (metres), one `vt u v` per particle from the scene's texture
//! coordinates, one `vn x y z` per particle and one `f a/a/a b/b/b c/c/c` per
//! triangle (1-based, the same index for position, texture coordinate and normal,
//! wound as the simulation winds them, so the face normal `(b - a) × (c - a)`
//! points to the front as OBJ readers expect).
//!
//! Vertex normals are area-weighted face normals, `n_i = normalize(Σ (b - a) ×
//! (c - a))` over the triangles touching particle i (the cross product's length is
//! twice the area, so large faces count more); a particle with no triangle of
//! non-zero area gets +y. Texture coordinates are written with `v` flipped
//! (`1 - v`): the renderer samples images top row first, OBJ readers bottom row
//! first, so a texture lands the same way in both. Numbers are printed with 6
//! decimals (micrometres for positions).
//!
//! Only scenes with a surface can be exported: a chain, a spring or a rope is
//! particles and springs without triangles, and that is an error, not an empty
//! file. The module has no GUI dependency: `cloth run --obj` and the app's
//! "Export OBJ" button both write through it.

use std::fs::File;
use std::io::{self, Write};
use std::path::{Path, PathBuf};

use glam::DVec3;

use crate::sim::System;

/// Why a cloth could not be exported.
#[derive(Debug, thiserror::Error)]
pub enum ExportError {
    /// The scene has no triangles (a chain, a spring, a rope, a jelly lattice).
    #[error("the scene `{scene}` has no surface to export: {why}")]
    NoSurface {
        /// The scene's name, as loaded.
        scene: String,
        /// Its particle count.
        particles: usize,
        /// Why there is none: a cloth of one row, a cloth torn apart, or a
        /// layout of particles joined by springs or bars.
        why: String,
    },
    /// A position is not finite (the simulation diverged).
    #[error(
        "particle {index} is at a non-finite position: the cloth diverged, so there is no surface to export"
    )]
    NotFinite {
        /// The first particle that is not finite.
        index: usize,
    },
    /// Writing failed.
    #[error("{0}")]
    Io(#[from] io::Error),
}

/// Checks that `system` has a surface that can be exported, before any work is
/// done: `scene` names it in the error.
pub fn check_surface(system: &System, scene: &str) -> Result<(), ExportError> {
    if system.triangles().is_empty() {
        let particles = system.particle_count();
        let broken = system.broken_springs();
        let why = match system.model().grid {
            Some(g) if g.width < 2 || g.height < 2 => format!(
                "the cloth is {} x {} particles, a single row, and a triangle needs two rows \
                 and two columns: give width and height of at least 2",
                g.width, g.height
            ),
            _ if broken > 0 => format!(
                "tearing or cutting broke {broken} springs, and with them every triangle of the \
                 cloth (a triangle goes with any spring along its edges)"
            ),
            _ => format!(
                "it is {particles} particles joined by springs or bars, with no triangles; OBJ \
                 export needs a cloth scene such as `cloth` or `flag`"
            ),
        };
        return Err(ExportError::NoSurface {
            scene: scene.to_string(),
            particles,
            why,
        });
    }
    Ok(())
}

/// Area-weighted vertex normals of the surface `triangles` over `positions`: unit
/// vectors, +y for a particle no triangle of non-zero area touches.
pub fn vertex_normals(positions: &[DVec3], triangles: &[[u32; 3]]) -> Vec<DVec3> {
    let mut normals = vec![DVec3::ZERO; positions.len()];
    for &[a, b, c] in triangles {
        let (Some(&pa), Some(&pb), Some(&pc)) = (
            positions.get(a as usize),
            positions.get(b as usize),
            positions.get(c as usize),
        ) else {
            continue;
        };
        let n = (pb - pa).cross(pc - pa);
        if !n.is_finite() {
            continue;
        }
        for i in [a, b, c] {
            normals[i as usize] += n;
        }
    }
    for n in &mut normals {
        *n = n.try_normalize().unwrap_or(DVec3::Y);
    }
    normals
}

/// Writes the surface of `system` as OBJ text to `out`; `scene` names the object
/// and the header comment.
pub fn write_obj(system: &System, scene: &str, out: &mut impl Write) -> Result<(), ExportError> {
    check_surface(system, scene)?;
    let positions = system.positions();
    if let Some(index) = positions.iter().position(|p| !p.is_finite()) {
        return Err(ExportError::NotFinite { index });
    }
    let triangles = system.triangles();
    let uvs = system.uvs();
    // Every surface the scenes build has one texture coordinate per particle; a
    // surface without them is written without `vt` rather than refused.
    let textured = uvs.len() == positions.len();
    let normals = vertex_normals(positions, triangles);
    let mut out = io::BufWriter::new(out);
    writeln!(
        out,
        "# cloth-sandbox: scene {scene} at t = {:.6} s (step {}), {} vertices, {} triangles",
        system.time(),
        system.steps_taken(),
        positions.len(),
        triangles.len()
    )?;
    writeln!(
        out,
        "# positions in metres; area-weighted vertex normals; texture v = 1 - the scene's v"
    )?;
    writeln!(out, "o {}", object_name(scene))?;
    for p in positions {
        writeln!(out, "v {:.6} {:.6} {:.6}", p.x, p.y, p.z)?;
    }
    if textured {
        for uv in uvs {
            writeln!(out, "vt {:.6} {:.6}", uv.x, 1.0 - uv.y)?;
        }
    }
    for n in &normals {
        writeln!(out, "vn {:.6} {:.6} {:.6}", n.x, n.y, n.z)?;
    }
    for t in triangles {
        let [a, b, c] = t.map(|i| i + 1);
        if textured {
            writeln!(out, "f {a}/{a}/{a} {b}/{b}/{b} {c}/{c}/{c}")?;
        } else {
            writeln!(out, "f {a}//{a} {b}//{b} {c}//{c}")?;
        }
    }
    out.flush()?;
    Ok(())
}

/// Writes the surface of `system` as `cloth-<scene>-N.obj` in `dir`, with the
/// first N from 1 that names no file yet (an existing file is never replaced),
/// and returns the path.
pub fn export_obj_in(system: &System, scene: &str, dir: &Path) -> Result<PathBuf, ExportError> {
    check_surface(system, scene)?;
    let stem = format!("cloth-{}", scene_stem(scene));
    let (path, mut file) = create_numbered(dir, &stem, "obj")?;
    let written = write_obj(system, scene, &mut file)
        .and_then(|()| file.sync_all().map_err(ExportError::from));
    if written.is_err() {
        // No half-written file is left behind under a name that looks finished.
        let _ = std::fs::remove_file(&path);
    }
    written.map(|()| path)
}

/// The scene part of an output file's name, as Save names its files: a built-in
/// scene's name, or a scene file's stem without an earlier save's `saved-` and
/// `-N`, in letters, digits, `-` and `_`.
pub fn scene_stem(scene: &str) -> String {
    crate::session::save_stem(scene)
}

/// Creates `<stem>-N.<extension>` in `dir` for the first N from 1 that names no
/// file (atomically: a file made meanwhile by another program is skipped, never
/// replaced); the error names the folder.
pub fn create_numbered(dir: &Path, stem: &str, extension: &str) -> io::Result<(PathBuf, File)> {
    const MOST: u32 = 10_000;
    for n in 1..=MOST {
        let path = dir.join(format!("{stem}-{n}.{extension}"));
        match std::fs::OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(&path)
        {
            Ok(file) => return Ok((path, file)),
            Err(e) if e.kind() == io::ErrorKind::AlreadyExists => {}
            Err(e) => {
                return Err(io::Error::new(
                    e.kind(),
                    format!("cannot write in the folder {}: {e}", dir.display()),
                ));
            }
        }
    }
    Err(io::Error::other(format!(
        "the folder {} already holds {stem}-1.{extension} to {stem}-{MOST}.{extension}: move some away",
        dir.display()
    )))
}

/// The scene's name as an OBJ object name: no spaces or line breaks.
fn object_name(scene: &str) -> String {
    let name = scene_stem(scene);
    if name.is_empty() {
        "cloth".to_string()
    } else {
        name
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_flat_square_has_unit_normals_along_its_winding() {
        let positions = [
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(1.0, 0.0, 0.0),
            DVec3::new(0.0, 1.0, 0.0),
            DVec3::new(1.0, 1.0, 0.0),
        ];
        let normals = vertex_normals(&positions, &[[0, 1, 2], [1, 3, 2]]);
        for n in normals {
            assert!((n - DVec3::Z).length() < 1e-12, "{n}");
        }
    }

    #[test]
    fn degenerate_and_untouched_vertices_get_up() {
        let positions = [DVec3::ZERO, DVec3::X, DVec3::X * 2.0, DVec3::ONE];
        let normals = vertex_normals(&positions, &[[0, 1, 2]]);
        assert!(normals.iter().all(|&n| n == DVec3::Y));
    }
}
