//! Scenes: TOML descriptions of a system (layout, sizes, materials, forces, pins,
//! integrator), the built-in ones from the seed documents, validation with errors
//! that name the field and the allowed range, and building a [`System`] from them.
//!
//! Scene files and the command line's `--set key=value` share the same keys.

pub(crate) mod build;
mod edit;
mod material;
pub mod mesh;
mod values;

use std::path::Path;

use serde::{Deserialize, Serialize};

pub use build::GRID_MAX_SIDE;
use build::{
    AIR_DAMPING, BAR_ITERATIONS, DAMPING, DT, FORCE, FRICTION, GRAVITY, GUST, MAX_SPEED,
    PARTICLE_MASS, REST_LENGTH, STIFFNESS, STRETCH_LIMIT, SUBSTEPS, TEAR_STRAIN, THICKNESS, WIND,
    side_ranges,
};
pub(crate) use edit::EDIT_ORIGIN;
pub use edit::Edit;
pub use material::{MATERIALS, Material};
pub use values::{PinPreset, Pins, Vector};
// (`ColliderSpec` is defined below, with `SceneSpec`.)

use crate::limits::echo;
use crate::sim::System;

/// How the particles are laid out and connected.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Layout {
    /// A `width` x `height` cloth with structural, shear and bend springs and a surface.
    #[default]
    Grid,
    /// Seed 002's mass on a spring: a fixed and a free mass, displaced from rest.
    Spring,
    /// A line of `width` masses joined by springs (seed 002's chain pendulum).
    Chain,
    /// A `width` x `height` x `depth` block of masses (seed 002's jelly cube).
    Lattice,
    /// A line of `width` masses joined by rigid bars (seed 001's rope).
    Rope,
    /// A triangle mesh from an OBJ file (`mesh`): its vertices are the particles,
    /// its edges structural springs, and the vertices opposite each interior edge
    /// bend springs.
    Mesh,
}

impl Layout {
    /// The layout's name in scene files.
    pub fn name(self) -> &'static str {
        match self {
            Self::Grid => "grid",
            Self::Spring => "spring",
            Self::Chain => "chain",
            Self::Lattice => "lattice",
            Self::Rope => "rope",
            Self::Mesh => "mesh",
        }
    }
}

/// Orientation of a grid cloth.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Orientation {
    /// In the x-y plane, rows going down (a hanging cloth).
    #[default]
    Vertical,
    /// In the x-z plane (a cloth lying flat, e.g. falling onto something).
    Horizontal,
}

/// A scene as written in a file. Where two keys give the same quantity in different
/// terms (`rest_length` or `size`, `particle_mass` or `total_mass`, `stiffness` or
/// `stiffness_per_mass`, `damping`, `damping_ratio` or `damping_per_mass`), give one.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SceneSpec {
    /// Short name.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    /// One line saying what the scene shows.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub description: Option<String>,
    /// Particle layout.
    pub layout: Layout,
    /// The OBJ file of a mesh layout. Relative to the scene file's folder in a
    /// scene file (to the working folder on the command line).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub mesh: Option<String>,
    /// Grid orientation.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub orientation: Option<Orientation>,
    /// Particles across (grid, lattice) or along (chain, rope).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub width: Option<u32>,
    /// Particles down (grid, lattice).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub height: Option<u32>,
    /// Particles deep (lattice).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub depth: Option<u32>,
    /// Spacing between neighbours in m.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rest_length: Option<f64>,
    /// Width of the grid in m (spacing = size / (width - 1)), instead of `rest_length`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub size: Option<f64>,
    /// A built-in material (`"silk"`, `"cotton"`, `"denim"`, `"leather"`,
    /// `"rubber"`): its mass per area, stiffness, damping, shear and bend scales
    /// and drag where the scene gives none of its own.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub material: Option<String>,
    /// Mass of each particle in kg.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub particle_mass: Option<f64>,
    /// Mass of all particles together in kg, instead of `particle_mass`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub total_mass: Option<f64>,
    /// Mass per area of a grid or mesh cloth in kg/m², shared by its particles,
    /// instead of `particle_mass`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub areal_density: Option<f64>,
    /// Spring stiffness k in N/m.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stiffness: Option<f64>,
    /// Stiffness per kg of particle mass, N/(m·kg): k = this × particle_mass.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stiffness_per_mass: Option<f64>,
    /// Spring damping b in N·s/m.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub damping: Option<f64>,
    /// Damping as a fraction of critical, b = ratio × 2 sqrt(k m) (seed 002).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub damping_ratio: Option<f64>,
    /// Damping per kg of particle mass: b = this × particle_mass.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub damping_per_mass: Option<f64>,
    /// Shear springs' stiffness as a multiple of k (grid; default 1, 0 = none).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub shear_scale: Option<f64>,
    /// Bend springs' stiffness as a multiple of k (grid, mesh; default 1, 0 = none).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub bend_scale: Option<f64>,
    /// A grid of rigid bars instead of springs (seed 001's cloth): each particle
    /// is joined to its right and lower neighbours and both diagonals of its cell
    /// by bars relaxed `bar_iterations` times per step.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub bars: Option<bool>,
    /// Wind velocity in m/s, `"x,y,z"`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub wind: Option<Vector>,
    /// Gust amplitude in m/s.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub gust: Option<f64>,
    /// Air density in kg/m³ (aero drag).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub air_density: Option<f64>,
    /// Drag coefficient (aero drag; 0 turns it off).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub drag_coefficient: Option<f64>,
    /// Viscous air damping c in N·s/m.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub air_damping: Option<f64>,
    /// Gravity in m/s², `"x,y,z"` or just the y component.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub gravity: Option<Vector>,
    /// A force in N on every particle besides gravity (seed 001's force vector),
    /// `"x,y,z"`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub force: Option<Vector>,
    /// Pinned particles: `corners`, `top-corners`, `top-edge`, `left-edge`, `first`,
    /// `none`, or a list of indices.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub pins: Option<Pins>,
    /// Pins, besides `pins`, every particle at or above this height (y, in m,
    /// where the scene puts it) (mesh).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub pin_above: Option<f64>,
    /// Integrator name.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub integrator: Option<String>,
    /// Time step in s.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub dt: Option<f64>,
    /// Steps per displayed frame.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub substeps: Option<u32>,
    /// Random seed (gusts): 0 to 2^64 - 1 (from 2^63 on, written as text).
    #[serde(skip_serializing_if = "Option::is_none", with = "values::seed")]
    pub seed: Option<u64>,
    /// Position of particle 0 in m (grid, chain, rope: the first particle; lattice:
    /// the block's centre; spring: the fixed end; mesh: where the file's origin goes).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub origin: Option<Vector>,
    /// Rotation in degrees, applied about z, then x, then y (lattice: about its
    /// centre; mesh: about the file's origin).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rotation: Option<Vector>,
    /// Initial stretch of the spring beyond its rest length in m (spring).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stretch: Option<f64>,
    /// Height of a ground plane in m (absent: no ground).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub ground_height: Option<f64>,
    /// Ground penalty stiffness in N/m.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub ground_stiffness: Option<f64>,
    /// Ground contact damping in N·s/m.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub ground_damping: Option<f64>,
    /// Centre of a sphere collider in m (absent: no sphere).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sphere_center: Option<Vector>,
    /// Sphere radius in m.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sphere_radius: Option<f64>,
    /// Coulomb friction coefficient of the sphere, the ground (unless
    /// `ground_friction` says otherwise) and the cloth's own layers.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub friction: Option<f64>,
    /// Coulomb friction coefficient of the ground, when it differs from `friction`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub ground_friction: Option<f64>,
    /// Contact thickness in m: how far above the ground and outside the sphere the
    /// cloth rests.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub thickness: Option<f64>,
    /// Whether the cloth's particles keep `thickness` apart from each other.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub self_collision: Option<bool>,
    /// Rigid-bar relaxation passes per step (rope).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub bar_iterations: Option<u32>,
    /// Maximum stretch tau (Provot): springs no longer than (1 + tau) L.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stretch_limit: Option<f64>,
    /// Strain past which a spring tears: it breaks when longer than (1 + tau) L.
    /// Absent: springs never tear.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub tear_strain: Option<f64>,
    /// Speed limit in m/s (seed 000's `vLim`). Absent: no limit.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub max_speed: Option<f64>,
    /// Boxes, capsules, meshes and spheres the cloth meets, besides the ground
    /// and `sphere_center` (`[[colliders]]` tables, last in a file).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub colliders: Vec<ColliderSpec>,
}

/// One `[[colliders]]` table of a scene file. Lengths in m, angles in degrees,
/// velocities in m/s and rad/s.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ColliderSpec {
    /// `sphere`, `box`, `capsule` or `mesh`.
    pub shape: String,
    /// Centre (sphere, box; a mesh's origin), `"x,y,z"`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub center: Option<Vector>,
    /// Half the box's size along its axes.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub half_extents: Option<Vector>,
    /// A capsule's ends.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub a: Option<Vector>,
    /// The capsule's other end.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub b: Option<Vector>,
    /// Radius of a sphere or capsule.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub radius: Option<f64>,
    /// A mesh collider's OBJ file, relative to the scene file's folder.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub mesh: Option<String>,
    /// Degrees about z, then x, then y.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rotation: Option<Vector>,
    /// Coulomb friction μ (default: the scene's `friction`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub friction: Option<f64>,
    /// How far outside it the cloth rests (default: the scene's `thickness`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub thickness: Option<f64>,
    /// Velocity of its centre, m/s.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub velocity: Option<Vector>,
    /// Angular velocity about its centre, rad/s on the world's axes.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub angular_velocity: Option<Vector>,
}

/// Keys that give the same quantity: setting one clears the others.
const ALTERNATIVES: &[&[&str]] = &[
    &["rest_length", "size"],
    &["particle_mass", "total_mass", "areal_density"],
    &["stiffness", "stiffness_per_mass"],
    &["damping", "damping_ratio", "damping_per_mass"],
];

/// Keys whose absence turns their part of the scene off, which `--set KEY=none`
/// does: no ground, no sphere, no stretch limit, no tearing, no speed limit.
const OFF_WHEN_ABSENT: &[&str] = &[
    "ground_height",
    "sphere_center",
    "stretch_limit",
    "tear_strain",
    "max_speed",
];

/// The keys that belong to a part that `--set KEY=none` turns off, and go with it.
const PART_KEYS: &[(&str, &[&str])] = &[
    (
        "ground_height",
        &["ground_stiffness", "ground_friction", "ground_damping"],
    ),
    ("sphere_center", &["sphere_radius"]),
];

/// A scene error: always names where the input came from, and the field when there is one.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// Neither a built-in scene nor a readable file.
    #[error("unknown scene `{name}`: not a built-in scene (one of: {builtins}) and not a file")]
    UnknownScene {
        /// What was asked for.
        name: String,
        /// The built-in names.
        builtins: String,
    },
    /// The file exists but cannot be read.
    #[error("cannot read scene file {path}: {source}")]
    Read {
        /// The path.
        path: String,
        /// Why.
        source: std::io::Error,
    },
    /// TOML syntax, an unknown key or a wrong type.
    #[error("{origin}: {message}")]
    Parse {
        /// Where the text came from.
        origin: String,
        /// The parser's message (names the key and line).
        message: String,
    },
    /// A value out of its range.
    #[error("{origin}: `{field}` {message}")]
    Invalid {
        /// Where the value came from.
        origin: String,
        /// The field.
        field: String,
        /// What is wrong and what is allowed.
        message: String,
    },
}

/// A line of a parser's message, which quotes the input, at most 200 characters.
fn clip(line: &str) -> String {
    const MAX: usize = 200;
    match line.char_indices().nth(MAX) {
        Some((cut, _)) => format!("{}…", &line[..cut]),
        None => line.to_string(),
    }
}

/// A TOML error in a scene file `text`, in plain words (see [`plain_words`]): the
/// line and its caret on lines of their own, then what is wrong.
fn file_message(error: &toml::de::Error, text: &str) -> String {
    let what = error.message().trim();
    let Some(span) = error.span() else {
        return plain_words(what, None, Layout::default());
    };
    let start = span.start.min(text.len());
    let line_start = text[..start].rfind('\n').map_or(0, |i| i + 1);
    let line_end = text[start..].find('\n').map_or(text.len(), |i| start + i);
    let line = &text[line_start..line_end];
    let number = text[..start].matches('\n').count() + 1;
    // The key the value belongs to, when the error is in a `key = value` line.
    let key = line.split_once('=').map(|(k, _)| k.trim());
    let column = text[line_start..start].chars().count();
    let width = text[start..span.end.min(line_end).max(start)]
        .chars()
        .count()
        .max(1);
    format!(
        "line {number}:\n  {}\n  {}{}\n{}",
        clip(line),
        " ".repeat(column.min(200)),
        "^".repeat(width.min(200)),
        plain_words(what, key, Layout::default())
    )
}

/// The physics symbols of the seeds and the panel's sliders ("stiffness k"), and
/// their scene keys.
const SYMBOLS: [(&str, &str); 2] = [("k", "stiffness"), ("b", "damping")];

/// The keys of `keys` that an `unknown` one most likely meant, best first, or
/// none: the keys that have it as one of their parts (`mass`: `particle_mass`,
/// `total_mass`, ...), however far by spelling (`bars` is 2 edits from `mass`),
/// and the key of a symbol (`k`: `stiffness`); else the nearest by spelling, within
/// fewer edits than the word has letters (a one-letter word is two edits from any
/// two-letter key: `k` is not `dt`).
fn guesses<'k>(unknown: &str, keys: &[&'k str]) -> Vec<&'k str> {
    let symbol = SYMBOLS
        .iter()
        .filter(|&&(s, key)| s == unknown && keys.contains(&key))
        .map(|&(_, key)| key);
    let meant: Vec<&str> = keys
        .iter()
        .copied()
        .filter(|k| k.split('_').any(|part| part == unknown))
        .chain(symbol)
        .collect();
    if !meant.is_empty() {
        return meant;
    }
    keys.iter()
        .map(|k| (edit_distance(unknown, k), *k))
        .min()
        .filter(|&(d, _)| d <= 2.max(unknown.len() / 3) && d < unknown.len())
        .map(|(_, k)| vec![k])
        .unwrap_or_default()
}

/// A deserialiser's message in plain words, for `key` when known: an unknown key
/// gets the keys it likely meant ("did you mean", [`guesses`]); a whole number out of its type, or
/// a value of the wrong type, says what the key takes and, for the counts, their
/// range. Other messages are kept, clipped.
fn plain_words(message: &str, key: Option<&str>, layout: Layout) -> String {
    if let Some(rest) = message.strip_prefix("unknown field `") {
        let unknown = rest.split('`').next().unwrap_or("");
        // serde lists the keys: "unknown field `x`, expected one of `a`, `b`".
        let known = rest.split_once("expected").map_or("", |(_, list)| list);
        let keys: Vec<&str> = known.split('`').skip(1).step_by(2).collect();
        let guesses = guesses(unknown, &keys);
        if guesses.is_empty() {
            return format!(
                "`{}` is not a scene key (README, \"Scene files and --set share keys\", lists them)",
                echo(unknown)
            );
        }
        let listed: Vec<String> = guesses.iter().map(|k| format!("`{k}`")).collect();
        return format!(
            "`{}` is not a scene key; did you mean {}?",
            echo(unknown),
            listed.join(" or ")
        );
    }
    // serde: "invalid value: integer `-3`, expected u32",
    // "invalid type: string \"abc\", expected f64".
    let expected = message.rsplit_once(", expected ").map(|(_, e)| e.trim());
    let got = message
        .split_once(": ")
        .and_then(|(_, rest)| rest.rsplit_once(", expected "))
        .map(|(got, _)| got.trim());
    if let (Some(expected), Some(got), Some(key)) = (expected, got, key) {
        let got = got
            .trim_start_matches("integer ")
            .trim_start_matches("floating point ")
            .trim_matches('`');
        let whole = matches!(expected, "u32" | "u64" | "i64" | "usize");
        let range = side_ranges(layout)
            .into_iter()
            .flatten()
            .chain([SUBSTEPS, BAR_ITERATIONS])
            .find(|r| r.field == key);
        let takes = match (whole, range) {
            (true, Some(r)) => format!("a whole number from {} to {}", r.lo, r.hi),
            (true, None) => "a whole number, 0 or more".to_string(),
            (false, _) if expected == "f64" => "a number".to_string(),
            (false, _) => expected.to_string(),
        };
        return format!("`{}` must be {takes}, got {}", echo(key), clip(got));
    }
    clip(message)
}

/// Levenshtein distance between two keys.
fn edit_distance(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut row: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut diagonal = row[0];
        row[0] = i + 1;
        for (j, &cb) in b.iter().enumerate() {
            let next = (diagonal + usize::from(ca != cb))
                .min(row[j] + 1)
                .min(row[j + 1] + 1);
            diagonal = row[j + 1];
            row[j + 1] = next;
        }
    }
    row[b.len()]
}

/// A built-in scene: its name and TOML text.
#[derive(Clone, Copy, Debug)]
pub struct BuiltinScene {
    /// Name, as given to `--scene`.
    pub name: &'static str,
    /// The scene file's text.
    pub toml: &'static str,
}

macro_rules! builtin {
    ($name:literal) => {
        BuiltinScene {
            name: $name,
            toml: include_str!(concat!("../../assets/scenes/", $name, ".toml")),
        }
    };
}

const BUILTINS: &[BuiltinScene] = &[
    builtin!("cloth"),
    builtin!("corners"),
    builtin!("flag"),
    builtin!("sheet"),
    builtin!("drape"),
    builtin!("tablecloth"),
    builtin!("table"),
    builtin!("twist"),
    builtin!("slide"),
    builtin!("fold"),
    builtin!("tear"),
    builtin!("spring"),
    builtin!("chain"),
    builtin!("jelly"),
    builtin!("hanging"),
    builtin!("bars"),
    builtin!("rope"),
    builtin!("bench"),
    builtin!("bench-wind"),
];

/// The built-in scenes, the default (`cloth`) first.
pub fn builtin_scenes() -> &'static [BuiltinScene] {
    BUILTINS
}

/// A scene ready to build: the spec and where it came from (for error messages).
/// Two scenes are equal when their specs and origins are (where each value was
/// written is for messages only).
#[derive(Clone, Debug)]
pub struct Scene {
    /// The spec, with overrides applied.
    pub spec: SceneSpec,
    /// "built-in scene `cloth`" or "scene file path/to.toml".
    pub origin: String,
    /// The line of each top-level `key = value` of the text it was parsed from,
    /// for messages that name where a value came from.
    lines: Vec<(String, u32)>,
    /// The keys given since by `--set` ([`Self::set`]), which replace the text's.
    overridden: Vec<String>,
}

impl PartialEq for Scene {
    fn eq(&self, other: &Self) -> bool {
        self.spec == other.spec && self.origin == other.origin
    }
}

/// Each top-level `key = value` line of a scene text, with its number.
fn key_lines(text: &str) -> Vec<(String, u32)> {
    (text.lines().enumerate())
        .filter_map(|(i, line)| {
            let (key, _) = line.split_once('=')?;
            let key = key.trim();
            let plain =
                !key.is_empty() && key.chars().all(|c| c.is_ascii_alphanumeric() || c == '_');
            plain.then(|| (key.to_string(), u32::try_from(i + 1).unwrap_or(u32::MAX)))
        })
        .collect()
}

impl Scene {
    /// Parses TOML text; `origin` says where it came from in errors. A relative
    /// `mesh` path is taken from the working folder.
    pub fn parse(text: &str, origin: &str) -> Result<Self, SceneError> {
        Self::parse_in(text, origin, None)
    }

    /// Parses TOML text from a file in the folder `base`: a relative `mesh` path
    /// in it starts from `base` (and is kept joined to it, so that `--set` and a
    /// saved copy in the working folder find the same file).
    pub fn parse_in(text: &str, origin: &str, base: Option<&Path>) -> Result<Self, SceneError> {
        let mut spec: SceneSpec = toml::from_str(text).map_err(|e| SceneError::Parse {
            origin: origin.to_string(),
            message: file_message(&e, text),
        })?;
        if let Some(base) = base {
            let collider_meshes = spec.colliders.iter_mut().filter_map(|c| c.mesh.as_mut());
            for mesh in spec.mesh.iter_mut().chain(collider_meshes) {
                *mesh = mesh::join_relative(base, mesh);
            }
        }
        let scene = Self {
            spec,
            origin: origin.to_string(),
            lines: key_lines(text),
            overridden: Vec::new(),
        };
        scene.resolve()?;
        Ok(scene)
    }

    /// A built-in scene by name, or a scene file by path.
    pub fn load(name_or_path: &str) -> Result<Self, SceneError> {
        if let Some(builtin) = BUILTINS.iter().find(|b| b.name == name_or_path) {
            // Its meshes are built in under the paths it names from assets/scenes/.
            return Self::parse_in(
                builtin.toml,
                &format!("built-in scene `{}`", builtin.name),
                Some(Path::new("assets/scenes")),
            );
        }
        let path = Path::new(name_or_path);
        if !path.exists() {
            let builtins = BUILTINS
                .iter()
                .map(|b| b.name)
                .collect::<Vec<_>>()
                .join(", ");
            return Err(SceneError::UnknownScene {
                name: echo(name_or_path),
                builtins,
            });
        }
        let text = crate::limits::read_text_file(path, crate::limits::MAX_SCENE_FILE_BYTES)
            .map_err(|why| SceneError::Read {
                path: echo(name_or_path),
                source: std::io::Error::other(why),
            })?;
        Self::parse_in(
            &text,
            &format!("scene file {}", echo(name_or_path)),
            path.parent(),
        )
    }

    /// Sets one key from text, as `--set key=value` does: the value is read as TOML
    /// (`32`, `0.5`, `[0, 5]`, `true`) or, failing that, as a string (`corners`,
    /// `1,0,0`). `none` removes a key whose absence turns its part off
    /// (`stretch_limit=none`: no stretch limit; so do `ground_height`,
    /// `sphere_center`, `tear_strain` and `max_speed`). Setting
    /// one of a group of alternative keys clears the others. On error the scene is
    /// unchanged.
    pub fn set(&mut self, key: &str, value: &str) -> Result<(), SceneError> {
        let origin = format!("--set {}={}", echo(key), echo(value));
        if let Some(c) = value.chars().find(|c| c.is_control() && *c != '\t') {
            return Err(SceneError::Invalid {
                origin,
                field: echo(key),
                message: format!(
                    "value holds a control character ({}): give one value on one line, and one --set per key",
                    c.escape_default()
                ),
            });
        }
        let mut table = toml::Table::try_from(&self.spec).map_err(|e| SceneError::Parse {
            origin: origin.clone(),
            message: e.to_string(),
        })?;
        let parsed = toml::from_str::<toml::Table>(&format!("v = {value}"))
            .ok()
            .and_then(|mut t| t.remove("v"))
            .unwrap_or_else(|| toml::Value::String(value.trim().to_string()));
        for group in ALTERNATIVES.iter().filter(|g| g.contains(&key)) {
            for other in group.iter().filter(|k| **k != key) {
                table.remove(*other);
            }
        }
        if value.trim().eq_ignore_ascii_case("none") && OFF_WHEN_ABSENT.contains(&key) {
            table.remove(key);
            // A part turned off takes its own keys with it.
            for (part, keys) in PART_KEYS {
                if key == *part {
                    for k in *keys {
                        table.remove(*k);
                    }
                }
            }
        } else {
            table.insert(key.to_string(), parsed);
        }
        let mut spec: SceneSpec = table.try_into().map_err(|e: toml::de::Error| {
            let mut message = plain_words(e.message().trim(), Some(key), self.spec.layout);
            // Only `--set` takes `none` (a scene file leaves the key out).
            if OFF_WHEN_ABSENT.contains(&key) {
                message.push_str("; `none` turns it off");
            }
            SceneError::Parse {
                origin: origin.clone(),
                message,
            }
        })?;
        // A material chosen replaces the scene's own values of what it sets.
        if let Some(m) = (key == "material")
            .then_some(spec.material.as_deref())
            .flatten()
            .and_then(Material::named)
        {
            spec.take_material(m);
        }
        let candidate = Self {
            spec,
            origin: self.origin.clone(),
            lines: self.lines.clone(),
            overridden: self.overridden.clone(),
        };
        candidate.resolve().map_err(|e| match e {
            // Another key's value, valid before, is out of range with this one:
            // both are named, the other with where it came from.
            SceneError::Invalid { field, message, .. } if field != key => {
                let line = self.lines.iter().find(|(k, _)| *k == field);
                let origin = if self.overridden.contains(&field) {
                    format!("{origin}: with it, --set {field} given before")
                } else if let Some((_, line)) = line {
                    format!("{origin}: with it, {} line {line}", self.origin)
                } else {
                    format!("{origin}: with it")
                };
                SceneError::Invalid {
                    origin,
                    field,
                    message,
                }
            }
            SceneError::Invalid { field, message, .. } => SceneError::Invalid {
                origin,
                field,
                message,
            },
            other => other,
        })?;
        *self = candidate;
        if !self.overridden.iter().any(|k| k == key) {
            self.overridden.push(key.to_string());
        }
        Ok(())
    }

    /// Records a typed edit in the spec, as `--set` would record the same value: it is
    /// checked against the key's range (the same constants as scene files), and
    /// setting one of a group of alternative keys clears the others (a stiffness in
    /// N/m replaces a stiffness per kg, a damping in N·s/m a damping ratio). Nothing
    /// is resolved or built. On error (the message names the field and the allowed
    /// range) the scene is unchanged.
    pub fn apply(&mut self, edit: Edit) -> Result<(), SceneError> {
        let o = edit::EDIT_ORIGIN;
        let layout = self.spec.layout;
        let side = |axis: usize, n: u32| match side_ranges(layout)[axis] {
            Some(range) => range.check(o, n),
            None => Err(SceneError::Invalid {
                origin: o.to_string(),
                field: edit.key().to_string(),
                message: format!("does not apply to a {} layout", layout.name()),
            }),
        };
        let spec = &mut self.spec;
        match edit {
            Edit::Stiffness(k) => {
                spec.stiffness = Some(STIFFNESS.check(o, k)?);
                spec.stiffness_per_mass = None;
            }
            Edit::Damping(b) => {
                spec.damping = Some(DAMPING.check(o, b)?);
                spec.damping_ratio = None;
                spec.damping_per_mass = None;
            }
            Edit::RestLength(_) if layout == Layout::Mesh => {
                return Err(SceneError::Invalid {
                    origin: o.to_string(),
                    field: edit.key().to_string(),
                    message: build::NOT_ON_MESH_REST_LENGTH.to_string(),
                });
            }
            Edit::RestLength(l) => {
                spec.rest_length = Some(REST_LENGTH.check(o, l)?);
                spec.size = None;
            }
            Edit::ParticleMass(m) => {
                spec.particle_mass = Some(PARTICLE_MASS.check(o, m)?);
                spec.total_mass = None;
                spec.areal_density = None;
            }
            Edit::Gravity(g) => spec.gravity = Some(Vector(GRAVITY.check(o, g)?)),
            Edit::Force(f) => spec.force = Some(Vector(FORCE.check(o, f)?)),
            Edit::Wind(w) => spec.wind = Some(Vector(WIND.check(o, w)?)),
            Edit::Gust(g) => spec.gust = Some(GUST.check(o, g)?),
            Edit::AirDamping(c) => spec.air_damping = Some(AIR_DAMPING.check(o, c)?),
            Edit::Dt(dt) => spec.dt = Some(DT.check(o, dt)?),
            Edit::Substeps(n) => spec.substeps = Some(SUBSTEPS.check(o, n)?),
            Edit::Integrator(i) => spec.integrator = Some(i.name().to_string()),
            Edit::BarIterations(n) => {
                let bars = spec.bars.unwrap_or(false);
                spec.bar_iterations = Some(build::bar_iterations(o, spec.layout, bars, n)?)
            }
            Edit::StretchLimit(t) => {
                spec.stretch_limit = t.map(|t| STRETCH_LIMIT.check(o, t)).transpose()?
            }
            Edit::TearStrain(t) => {
                spec.tear_strain = t.map(|t| TEAR_STRAIN.check(o, t)).transpose()?
            }
            Edit::MaxSpeed(v) => spec.max_speed = v.map(|v| MAX_SPEED.check(o, v)).transpose()?,
            Edit::Friction(mu) => {
                spec.friction = Some(FRICTION.check(o, mu)?);
                spec.ground_friction = None;
            }
            Edit::Thickness(t) => spec.thickness = Some(THICKNESS.check(o, t)?),
            Edit::SelfCollision(on) => spec.self_collision = Some(on),
            Edit::Width(n) => spec.width = Some(side(0, n)?),
            Edit::Height(n) => spec.height = Some(side(1, n)?),
            Edit::Depth(n) => spec.depth = Some(side(2, n)?),
            Edit::Material(m) => spec.take_material(m),
        }
        Ok(())
    }

    /// [`Self::apply`] for building a scene in one expression: the typed
    /// counterpart of `--set`, checked against the same ranges.
    ///
    /// ```rust
    /// use cloth_sandbox::scene::{Edit, Scene};
    ///
    /// let scene = Scene::load("cloth")?
    ///     .with(Edit::Width(16))?
    ///     .with(Edit::Height(12))?
    ///     .with(Edit::Stiffness(800.0))?;
    /// assert_eq!(scene.build()?.positions().len(), 16 * 12);
    /// // A value out of range is refused with the field and its range.
    /// let refused = Scene::load("cloth")?.with(Edit::Stiffness(-1.0)).unwrap_err();
    /// assert!(refused.to_string().contains("stiffness"));
    /// # Ok::<(), cloth_sandbox::scene::SceneError>(())
    /// ```
    pub fn with(mut self, edit: Edit) -> Result<Self, SceneError> {
        self.apply(edit)?;
        Ok(self)
    }

    /// Applies `key=value` overrides in order.
    pub fn set_all<'a>(
        &mut self,
        assignments: impl IntoIterator<Item = &'a str>,
    ) -> Result<(), SceneError> {
        for assignment in assignments {
            let Some((key, value)) = assignment.split_once('=') else {
                return Err(SceneError::Parse {
                    origin: format!("--set {assignment}"),
                    message: "expected key=value, e.g. --set stiffness=500".to_string(),
                });
            };
            self.set(key.trim(), value)?;
        }
        Ok(())
    }

    /// The files this scene, loaded from `name_or_path` ([`Self::load`]), reads:
    /// its scene file (not a built-in's) and its mesh, for the outputs of the
    /// same command to keep off ([`crate::limits::Inputs`]).
    pub fn inputs(&self, name_or_path: &str) -> crate::limits::Inputs {
        let mut inputs = crate::limits::Inputs::default();
        if !BUILTINS.iter().any(|b| b.name == name_or_path) {
            inputs.add("the scene file being run", Path::new(name_or_path));
        }
        if let Some(mesh) = &self.spec.mesh {
            inputs.add("the scene's mesh", Path::new(mesh));
        }
        inputs
    }

    /// Every parameter in effect, with defaults filled in and ranges checked.
    pub fn resolve(&self) -> Result<build::Resolved, SceneError> {
        build::resolve(&self.spec, &self.origin)
    }

    /// Builds the system.
    pub fn build(&self) -> Result<System, SceneError> {
        let system = self.resolve()?.build();
        let p = system.params();
        check_self_collision(&self.origin, &system, p.self_collision, p.thickness)?;
        Ok(system)
    }
}

/// Refuses self-collision at a thickness `h_c` (m) that would list more candidate
/// pairs at `system`'s positions than the pass has room for
/// ([`crate::sim::self_collision::MAX_PAIRS_PER_PARTICLE`] a particle): a
/// thickness many times the particles' spacing, at which every particle keeps
/// apart from many it is not joined to and the pairs grow as the square of the
/// particles. `origin` says where the setting came from; `on`: whether
/// self-collision is on.
pub fn check_self_collision(
    origin: &str,
    system: &System,
    on: bool,
    h_c: f64,
) -> Result<(), SceneError> {
    use crate::sim::self_collision::{MAX_PAIRS_PER_PARTICLE, SelfCollision};
    if !(on && h_c > 0.0) {
        return Ok(());
    }
    let model = system.model();
    if !SelfCollision::would_overfill(system.positions(), h_c, |i, j| model.joins(i, j)) {
        return Ok(());
    }
    let n = system.particle_count();
    let spacing = (system.springs().iter().map(|s| s.rest))
        .chain(system.bars().iter().map(|b| b.length))
        .filter(|l| *l > 0.0)
        .fold(f64::INFINITY, f64::min);
    let pairs = n as f64 * (n as f64 - 1.0) / 2.0;
    let gb = pairs * 16.0 / 1e9;
    let spacing = if spacing.is_finite() {
        format!(" (the nearest {} m apart)", crate::limits::number(spacing))
    } else {
        String::new()
    };
    Err(SceneError::Invalid {
        origin: origin.to_string(),
        field: "thickness".to_string(),
        message: format!(
            "of {} m with self_collision keeps each of the {n} particles{spacing} away from \
             more than {MAX_PAIRS_PER_PARTICLE} others at the start: the pairs to check grow as \
             the square of the particles (up to {pairs:.1e} of them, {gb:.1} GB), past the \
             memory set aside for them; keep the thickness to about a spacing, or set \
             self_collision = false",
            crate::limits::number(h_c),
        ),
    })
}

pub use build::Resolved;
