//! From the simulation's `f64` state to the renderer's plain `f32` slices:
//! positions, springs and bars as coloured lines (by kind or by strain
//! `(l - L) / L`), pinned flags, colliders. Buffers are reused frame to frame.

use cloth_sandbox::session::Session;
use cloth_sandbox::sim::{SpringKind, System};
use cloth_sandbox::view::OrbitCamera;
use glam::{Vec2, Vec3};

use crate::render::geometry::{kind_color, strain_color};
use crate::render::{SceneFrame, ViewOptions};

/// Reusable per-frame vectors handed to the renderer.
#[derive(Default)]
pub struct FrameData {
    /// Positions as `f32` (non-finite values pass through; the renderer drops them).
    pub positions: Vec<Vec3>,
    uvs: Vec<Vec2>,
    lines: Vec<[u32; 2]>,
    colors: Vec<[f32; 4]>,
    pinned: Vec<bool>,
    triangles: Vec<[u32; 3]>,
    ground: Option<f32>,
    /// Display-only floor under a scene without a ground, and the scene it was
    /// set for (particles, springs, triangles): set when that changes.
    floor: Option<f32>,
    floor_key: (usize, usize, usize),
    /// How far (m) below the scene's lowest point the floor lies.
    floor_gap: f32,
    sphere: Option<(Vec3, f32)>,
    colliders: Vec<cloth_sandbox::sim::Collider>,
    time: f64,
    /// The live reference's positions, empty when it is off.
    ghost: Vec<Vec3>,
}

/// Colour index of a spring kind (see `kind_color`).
fn kind_index(kind: SpringKind) -> usize {
    match kind {
        SpringKind::Structural => 0,
        SpringKind::Shear => 1,
        SpringKind::Bend => 2,
        SpringKind::Other => 3,
    }
}

/// Strain `(l - L) / L` of a segment, 0 for a zero rest length.
fn strain(positions: &[Vec3], a: u32, b: u32, rest: f64) -> f32 {
    let (Some(pa), Some(pb)) = (positions.get(a as usize), positions.get(b as usize)) else {
        return 0.0;
    };
    if rest <= 1e-12 {
        return 0.0;
    }
    ((f64::from(pa.distance(*pb)) - rest) / rest) as f32
}

impl FrameData {
    /// Copies the positions (for picking) without rebuilding anything else.
    pub fn refresh_positions(&mut self, system: &System) {
        self.positions.clear();
        self.positions
            .extend(system.positions().iter().map(|p| p.as_vec3()));
    }

    /// Copies everything the renderer needs from `system`, with `surface` as its
    /// triangles ([`Session::surface`]), so that the frame can be drawn while the
    /// physics thread steps on.
    pub fn build(
        &mut self,
        system: &System,
        surface: &[[u32; 3]],
        view: &ViewOptions,
        by_strain: bool,
    ) {
        self.refresh_positions(system);
        if self.triangles != surface {
            self.triangles.clear();
            self.triangles.extend_from_slice(surface);
        }
        // The solids, under the contact surfaces the cloth rests on.
        let params = system.params();
        self.ground = params.ground.map(|g| (g.height - params.thickness) as f32);
        let key = (
            system.particle_count(),
            system.springs().len(),
            surface.len(),
        );
        if self.floor_key != key || self.floor.is_none() {
            let (lo, hi) = system_bounds(system);
            self.floor_gap = 0.1 * (hi - lo).max_element().max(0.5);
            self.floor = Some(lo.y - self.floor_gap);
            self.floor_key = key;
        }
        // The floor gives way under a cloth that grows or falls past it (a rest
        // length edit, no pins), so nothing ever hangs through it.
        let lowest = (system.positions().iter()).fold(f64::INFINITY, |m, p| m.min(p.y)) as f32;
        if let Some(floor) = self.floor.as_mut()
            && lowest.is_finite()
            && lowest < *floor + 0.25 * self.floor_gap
        {
            *floor = lowest - self.floor_gap;
        }
        self.sphere =
            (params.sphere).map(|s| (s.center.as_vec3(), (s.radius - params.thickness) as f32));
        self.colliders.clear();
        self.colliders.extend_from_slice(system.colliders());
        self.time = system.time();
        self.uvs.clear();
        self.uvs.extend(system.uvs().iter().map(|uv| uv.as_vec2()));
        self.pinned.clear();
        self.pinned
            .extend((0..system.particle_count()).map(|i| system.is_pinned(i)));
        self.lines.clear();
        self.colors.clear();
        if view.springs {
            for s in system.springs() {
                self.lines.push([s.a, s.b]);
                self.colors.push(if by_strain {
                    strain_color(strain(&self.positions, s.a, s.b, s.rest))
                } else {
                    kind_color(kind_index(s.kind))
                });
            }
            for b in system.bars() {
                self.lines.push([b.a, b.b]);
                self.colors.push(if by_strain {
                    strain_color(strain(&self.positions, b.a, b.b, b.length))
                } else {
                    kind_color(4)
                });
            }
        }
    }

    /// Takes the live reference's positions to draw as a ghost (`None` or empty:
    /// no ghost).
    pub fn set_ghost(&mut self, ghost: Option<&[glam::DVec3]>) {
        self.ghost.clear();
        self.ghost
            .extend(ghost.unwrap_or_default().iter().map(|p| p.as_vec3()));
    }

    /// The renderer's view of the frame last built.
    pub fn scene_frame(&self, highlight: Option<usize>) -> SceneFrame<'_> {
        SceneFrame {
            positions: &self.positions,
            triangles: &self.triangles,
            uvs: &self.uvs,
            lines: &self.lines,
            line_colors: &self.colors,
            pinned: &self.pinned,
            highlight,
            ground: self.ground,
            floor: self.floor,
            sphere: self.sphere,
            colliders: &self.colliders,
            time: self.time,
            ghost: &self.ghost,
        }
    }
}

/// The camera the off-screen commands (`cloth screenshot`, `cloth record`) start
/// from: the scene framed, turned to `yaw` and `pitch` (degrees) where given.
pub fn framed_camera(session: &Session, yaw: Option<f32>, pitch: Option<f32>) -> OrbitCamera {
    let mut camera = OrbitCamera::default();
    let (lo, hi) = scene_bounds(session);
    camera.frame(lo, hi);
    if let Some(y) = yaw {
        camera.yaw = y.to_radians();
    }
    if let Some(p) = pitch {
        camera.pitch = p.to_radians().clamp(-1.5, 1.5);
    }
    camera
}

/// The box to frame when a scene loads: its particles, its sphere and its colliders.
pub fn scene_bounds(session: &Session) -> (Vec3, Vec3) {
    system_bounds(session.system())
}

/// [`scene_bounds`] of a system.
fn system_bounds(system: &System) -> (Vec3, Vec3) {
    let points: Vec<Vec3> = system.positions().iter().map(|p| p.as_vec3()).collect();
    let (mut lo, mut hi) =
        cloth_sandbox::view::bounds(&points).unwrap_or((Vec3::splat(-1.0), Vec3::splat(1.0)));
    // A line hanging from pins (chain, rope, spring) swings below them: frame
    // the half-disc it can sweep, not just where it starts.
    if system.triangles().is_empty() {
        for (i, p) in points.iter().enumerate() {
            if !system.is_pinned(i) || !p.is_finite() {
                continue;
            }
            let reach = points
                .iter()
                .filter(|q| q.is_finite())
                .map(|q| q.distance(*p))
                .fold(0.0f32, f32::max);
            lo = lo.min(*p - Vec3::new(reach, reach, 0.0));
            hi = hi.max(*p + Vec3::new(reach, 0.0, 0.0));
        }
    }
    // Scenes with a ground show it: things fall onto it.
    if let Some(g) = system.params().ground {
        let y = g.height as f32;
        if y.is_finite() {
            lo.y = lo.y.min(y);
        }
    }
    if let Some(s) = system.params().sphere {
        let c = s.center.as_vec3();
        let r = s.radius as f32;
        if c.is_finite() && r.is_finite() {
            lo = lo.min(c - Vec3::splat(r));
            hi = hi.max(c + Vec3::splat(r));
        }
    }
    // The colliders where they start, each by the ball that holds it (a
    // mesh's or a long capsule's reaches past its shape: framed to its middle).
    for c in system.colliders() {
        let (centre, radius) = (c.center.as_vec3(), (0.7 * c.shape.bounding_radius()) as f32);
        if centre.is_finite() && radius.is_finite() && radius < 1e4 {
            lo = lo.min(centre - Vec3::splat(radius));
            hi = hi.max(centre + Vec3::splat(radius));
        }
    }
    (lo, hi)
}
