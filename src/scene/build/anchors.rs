//! Where the layout sits and what holds it: its anchor, its rotation, and the
//! pinned particles.

use glam::{DMat3, DVec3};

use super::ranges::{invalid, vector};
use crate::scene::values::{PinPreset, Pins};
use crate::scene::{Layout, Orientation, SceneError, SceneSpec};

/// Position of the layout's anchor in m: the spec's `origin`, or by default a
/// vertical grid's top-left corner such that it hangs centred above y = 0 (a
/// horizontal grid centred at y = 1), which moves with the grid's size.
pub(super) fn anchor(
    spec: &SceneSpec,
    o: &str,
    [width, height]: [u32; 2],
    rest_length: f64,
) -> Result<DVec3, SceneError> {
    let default_origin = match (spec.layout, spec.orientation.unwrap_or_default()) {
        (Layout::Grid, Orientation::Vertical) => DVec3::new(
            -0.5 * (width - 1) as f64 * rest_length,
            (height - 1) as f64 * rest_length,
            0.0,
        ),
        (Layout::Grid, Orientation::Horizontal) => DVec3::new(
            -0.5 * (width - 1) as f64 * rest_length,
            1.0,
            -0.5 * (height - 1) as f64 * rest_length,
        ),
        _ => DVec3::ZERO,
    };
    match spec.origin {
        Some(v) => vector(o, "origin", v.0, 1e6),
        // No origin was given: the default anchor follows from the grid's size and
        // spacing, so an anchor out of range is their doing, and they are named.
        None => vector(o, "origin", default_origin, 1e6).map_err(|_| SceneError::Invalid {
            origin: o.to_string(),
            field: "rest_length".to_string(),
            message: format!(
                "= {} m with width = {width} and height = {height} makes a cloth {} m across, \
                 whose default anchor (origin, not set) = ({}, {}, {}) is past 1e6 m: give a \
                 smaller rest_length, width or height, or set origin",
                crate::limits::number(rest_length),
                crate::limits::number(f64::from(width.max(height).saturating_sub(1)) * rest_length),
                crate::limits::number(default_origin.x),
                crate::limits::number(default_origin.y),
                crate::limits::number(default_origin.z),
            ),
        }),
    }
}

/// The rotation of `degrees` about z, then x, then y.
pub(super) fn rotation_matrix(degrees: DVec3) -> DMat3 {
    let rad = degrees * (std::f64::consts::PI / 180.0);
    DMat3::from_rotation_y(rad.y) * DMat3::from_rotation_x(rad.x) * DMat3::from_rotation_z(rad.z)
}

/// The pin set a layout has when its scene names none: a grid's top corners, a
/// lattice or a mesh nothing, the first particle of a line.
pub(super) fn default_pins(layout: Layout) -> PinPreset {
    match layout {
        Layout::Grid => PinPreset::TopCorners,
        Layout::Lattice | Layout::Mesh => PinPreset::None,
        _ => PinPreset::First,
    }
}

/// The particles `pins` names in a `width` x `height` layout of `particles`, sorted;
/// an index past the last particle is an error naming `pins` and the range.
pub(super) fn pin_indices(
    o: &str,
    pins: &Pins,
    layout: Layout,
    [width, height]: [u32; 2],
    particles: usize,
) -> Result<Vec<usize>, SceneError> {
    match pins {
        Pins::Indices(list) => {
            if let Some(&bad) = list.iter().find(|&&i| i >= particles) {
                return Err(invalid(
                    o,
                    "pins",
                    format!(
                        "index {bad} is out of range: the scene has {particles} particles (0 to {})",
                        particles.saturating_sub(1)
                    ),
                ));
            }
            Ok(list.clone())
        }
        Pins::Preset(p) => Ok(preset_pins(
            *p,
            layout,
            width as usize,
            height as usize,
            particles,
        )),
    }
}

fn preset_pins(preset: PinPreset, layout: Layout, w: usize, h: usize, n: usize) -> Vec<usize> {
    let mut pins = match (preset, layout) {
        (PinPreset::None, _) => vec![],
        (PinPreset::First, _) => vec![0],
        (_, Layout::Grid) => match preset {
            PinPreset::Corners => vec![0, w - 1, (h - 1) * w, h * w - 1],
            PinPreset::TopCorners => vec![0, w - 1],
            PinPreset::TopEdge => (0..w).collect(),
            PinPreset::LeftEdge => (0..h).map(|r| r * w).collect(),
            PinPreset::LeftEdgeEveryFourth => (0..h).step_by(4).map(|r| r * w).collect(),
            _ => vec![],
        },
        // Off a grid, the grid presets mean the ends of the line or block.
        (PinPreset::Corners | PinPreset::TopCorners, _) => vec![0, n - 1],
        _ => vec![0],
    };
    pins.sort_unstable();
    pins.dedup();
    pins
}
