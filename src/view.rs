//! Camera and picking maths for the viewer: an orbit camera (right-handed, +y up,
//! metres, radians) and screen rays, `p_clip = P · V · p_world`, glam `f32` only.
//!
//! Screen coordinates are physical pixels with the origin at the top-left corner
//! and +y pointing down, as winit reports them. Depth follows wgpu's 0..1 range.

use glam::{Mat4, Vec2, Vec3};

/// Smallest orbit distance in metres (zooming in stops here).
pub const MIN_DISTANCE: f32 = 0.05;
/// Largest orbit distance in metres (zooming out stops here).
pub const MAX_DISTANCE: f32 = 5_000.0;
/// Pitch stays this far (radians) from straight up or down so `look_at` never degenerates.
const PITCH_LIMIT: f32 = 1.55;

/// A camera that orbits a target point.
///
/// The eye sits at `target + distance · (cos p · sin y, sin p, cos p · cos y)` for
/// yaw `y` and pitch `p`, looking at `target` with +y up. Yaw 0, pitch 0 looks down -z.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OrbitCamera {
    /// Point the camera looks at and orbits around (m).
    pub target: Vec3,
    /// Rotation about +y (rad); 0 puts the eye on +z.
    pub yaw: f32,
    /// Elevation above the target's horizontal plane (rad), kept within about ±89°.
    pub pitch: f32,
    /// Eye-to-target distance (m), kept in `MIN_DISTANCE..=MAX_DISTANCE`.
    pub distance: f32,
    /// Vertical field of view (rad). Default: 45°.
    pub fov_y: f32,
}

impl Default for OrbitCamera {
    fn default() -> Self {
        Self {
            target: Vec3::ZERO,
            yaw: 0.35,
            pitch: 0.25,
            distance: 10.0,
            fov_y: 45f32.to_radians(),
        }
    }
}

/// Which fly keys are held (seed 001: WASD moves, Q/E go down/up).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct FlyKeys {
    /// W: move towards where the camera looks.
    pub forward: bool,
    /// S: move away.
    pub back: bool,
    /// A: strafe left.
    pub left: bool,
    /// D: strafe right.
    pub right: bool,
    /// E: move up along world +y.
    pub up: bool,
    /// Q: move down along world -y.
    pub down: bool,
}

impl FlyKeys {
    /// True when any fly key is held.
    pub fn any(&self) -> bool {
        self.forward || self.back || self.left || self.right || self.up || self.down
    }
}

/// A half-line `origin + t · dir`, `t >= 0`, with `dir` of unit length.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    /// Start point (m), on the near plane.
    pub origin: Vec3,
    /// Unit direction.
    pub dir: Vec3,
}

impl Ray {
    /// The point at parameter `t` (m along the ray).
    pub fn at(&self, t: f32) -> Vec3 {
        self.origin + self.dir * t
    }

    /// Where the ray meets the plane through `point` with normal `normal`, if it
    /// meets it in front of the origin. `None` for a ray parallel to the plane.
    pub fn intersect_plane(&self, point: Vec3, normal: Vec3) -> Option<Vec3> {
        let denom = self.dir.dot(normal);
        if denom.abs() <= 1e-6 {
            return None;
        }
        let t = (point - self.origin).dot(normal) / denom;
        (t >= 0.0 && t.is_finite()).then(|| self.at(t))
    }

    /// Distance (m) from `p` to the infinite line through the ray.
    pub fn distance_to_point(&self, p: Vec3) -> f32 {
        let v = p - self.origin;
        (v - self.dir * v.dot(self.dir)).length()
    }
}

impl OrbitCamera {
    /// Unit vector from the target towards the eye.
    fn offset_dir(&self) -> Vec3 {
        let (sy, cy) = self.yaw.sin_cos();
        let (sp, cp) = self.pitch.sin_cos();
        Vec3::new(cp * sy, sp, cp * cy)
    }

    /// Eye position (m).
    pub fn eye(&self) -> Vec3 {
        self.target + self.offset_dir() * self.distance
    }

    /// Unit vector the camera looks along.
    pub fn forward(&self) -> Vec3 {
        -self.offset_dir()
    }

    /// Unit vector to the right of the view, horizontal.
    pub fn right(&self) -> Vec3 {
        self.forward().cross(Vec3::Y).normalize_or(Vec3::X)
    }

    /// Unit vector up the screen.
    pub fn up(&self) -> Vec3 {
        self.right().cross(self.forward()).normalize_or(Vec3::Y)
    }

    /// Near clip distance (m): scales with the orbit distance so depth precision holds.
    pub fn near(&self) -> f32 {
        (self.distance * 0.01).clamp(0.01, 1.0)
    }

    /// Far clip distance (m).
    pub fn far(&self) -> f32 {
        self.distance * 50.0 + 100.0
    }

    /// World-to-view matrix.
    pub fn view(&self) -> Mat4 {
        glam::camera::rh::view::look_at_mat4(self.eye(), self.target, Vec3::Y)
    }

    /// View-to-clip matrix for a viewport of `viewport` pixels (wgpu depth 0..1).
    pub fn projection(&self, viewport: Vec2) -> Mat4 {
        let aspect = if viewport.y > 0.0 {
            viewport.x / viewport.y
        } else {
            1.0
        };
        glam::camera::rh::proj::directx::perspective(
            self.fov_y,
            aspect.max(1e-3),
            self.near(),
            self.far(),
        )
    }

    /// World-to-clip matrix.
    pub fn view_proj(&self, viewport: Vec2) -> Mat4 {
        self.projection(viewport) * self.view()
    }

    /// Screen position (pixels) and view depth (m) of a world point, or `None`
    /// when it is behind the near plane.
    pub fn project(&self, p: Vec3, viewport: Vec2) -> Option<(Vec2, f32)> {
        let depth = (p - self.eye()).dot(self.forward());
        if depth.is_nan() || depth < self.near() {
            return None;
        }
        let clip = self.view_proj(viewport) * p.extend(1.0);
        if clip.w <= 0.0 {
            return None;
        }
        let ndc = clip.truncate() / clip.w;
        let screen = Vec2::new(
            (ndc.x + 1.0) * 0.5 * viewport.x,
            (1.0 - ndc.y) * 0.5 * viewport.y,
        );
        screen.is_finite().then_some((screen, depth))
    }

    /// The ray from the eye through the screen point `screen` (pixels).
    pub fn ray(&self, screen: Vec2, viewport: Vec2) -> Ray {
        let w = viewport.x.max(1.0);
        let h = viewport.y.max(1.0);
        let ndc_x = screen.x / w * 2.0 - 1.0;
        let ndc_y = 1.0 - screen.y / h * 2.0;
        let tan_half = (self.fov_y * 0.5).tan();
        let aspect = w / h;
        let dir = (self.forward()
            + self.right() * (ndc_x * tan_half * aspect)
            + self.up() * (ndc_y * tan_half))
            .normalize_or(self.forward());
        Ray {
            origin: self.eye(),
            dir,
        }
    }

    /// World size (m) of one pixel at view depth `depth` (m).
    pub fn pixel_size_at(&self, depth: f32, viewport: Vec2) -> f32 {
        2.0 * depth * (self.fov_y * 0.5).tan() / viewport.y.max(1.0)
    }

    /// Orbit by a mouse motion of `delta` pixels (0.01 rad per pixel).
    pub fn orbit(&mut self, delta: Vec2) {
        if !delta.is_finite() {
            return;
        }
        self.yaw -= delta.x * 0.01;
        self.pitch = (self.pitch + delta.y * 0.01).clamp(-PITCH_LIMIT, PITCH_LIMIT);
        self.yaw = self.yaw.rem_euclid(std::f32::consts::TAU);
    }

    /// Zoom by `steps` wheel notches: each notch towards the target shortens the
    /// distance by 10 %.
    pub fn zoom(&mut self, steps: f32) {
        if !steps.is_finite() {
            return;
        }
        self.distance = (self.distance * 0.9f32.powf(steps)).clamp(MIN_DISTANCE, MAX_DISTANCE);
    }

    /// Pan so the point under the cursor follows a mouse motion of `delta` pixels.
    pub fn pan(&mut self, delta: Vec2, viewport: Vec2) {
        if !delta.is_finite() {
            return;
        }
        let px = self.pixel_size_at(self.distance, viewport);
        self.target += (-self.right() * delta.x + self.up() * delta.y) * px;
    }

    /// Fly for `dt` seconds with the held keys; speed is half the orbit distance per second.
    pub fn fly(&mut self, keys: FlyKeys, dt: f32) {
        if !dt.is_finite() || dt <= 0.0 {
            return;
        }
        let flat_forward = Vec3::new(self.forward().x, 0.0, self.forward().z).normalize_or_zero();
        let forward = if flat_forward == Vec3::ZERO {
            self.up()
        } else {
            flat_forward
        };
        let axis = |pos: bool, neg: bool| f32::from(u8::from(pos)) - f32::from(u8::from(neg));
        let step = forward * axis(keys.forward, keys.back)
            + self.right() * axis(keys.right, keys.left)
            + Vec3::Y * axis(keys.up, keys.down);
        self.target += step * (0.5 * self.distance.max(1.0) * dt);
    }

    /// Aim at the centre of the box `min..max` and step back until the whole
    /// box fits in view (for a viewport of aspect ≥ 1), keeping yaw and pitch.
    pub fn frame(&mut self, min: Vec3, max: Vec3) {
        if !min.is_finite() || !max.is_finite() {
            return;
        }
        let centre = (min + max) * 0.5;
        let radius = ((max - min).length() * 0.5).max(0.25);
        self.target = centre;
        self.distance =
            (radius / (self.fov_y * 0.5).sin() * 1.05).clamp(MIN_DISTANCE, MAX_DISTANCE);
    }

    /// The drag target for a grabbed particle: where the cursor ray meets the plane
    /// through `anchor` that faces the camera.
    pub fn drag_point(&self, screen: Vec2, viewport: Vec2, anchor: Vec3) -> Option<Vec3> {
        self.ray(screen, viewport)
            .intersect_plane(anchor, self.forward())
    }
}

/// Axis-aligned bounds of the finite points in `points`, or `None` if there are none.
pub fn bounds(points: &[Vec3]) -> Option<(Vec3, Vec3)> {
    points
        .iter()
        .filter(|p| p.is_finite())
        .fold(None, |acc, &p| match acc {
            None => Some((p, p)),
            Some((lo, hi)) => Some((lo.min(p), hi.max(p))),
        })
}

/// Whether any of the finite `points` projects inside the viewport, in front of
/// the camera (the app frames the scene again when none has for a while).
pub fn any_in_view(camera: &OrbitCamera, viewport: Vec2, points: &[Vec3]) -> bool {
    let view_proj = camera.view_proj(viewport);
    points.iter().filter(|p| p.is_finite()).any(|p| {
        let clip = view_proj * p.extend(1.0);
        clip.w > camera.near() && clip.x.abs() <= clip.w && clip.y.abs() <= clip.w
    })
}

/// The particle under the cursor: among the particles whose projection lies within
/// `radius_px` pixels of `screen`, the one closest to the cursor on screen; when
/// two are equally close (within half a pixel) the one nearer the camera wins.
/// Non-finite positions and particles behind the camera are ignored.
pub fn pick_particle(
    camera: &OrbitCamera,
    viewport: Vec2,
    screen: Vec2,
    positions: &[Vec3],
    radius_px: f32,
) -> Option<usize> {
    let mut best: Option<(usize, f32, f32)> = None;
    for (i, &p) in positions.iter().enumerate() {
        if !p.is_finite() {
            continue;
        }
        let Some((s, depth)) = camera.project(p, viewport) else {
            continue;
        };
        let d = s.distance(screen);
        if d > radius_px {
            continue;
        }
        let better = match best {
            None => true,
            Some((_, bd, bdepth)) => d < bd - 0.5 || (d <= bd + 0.5 && depth < bdepth),
        };
        if better {
            best = Some((i, d, depth));
        }
    }
    best.map(|(i, _, _)| i)
}

/// The springs (pairs of particle indices) whose projections on screen cross the
/// polyline `path` (pixels): what a cut along the mouse's path breaks. The app
/// passes the last few points of the path, not only the last move, so that a
/// spring the moving cloth carries across a joint between two moves is still cut.
/// Springs with an end behind the camera or not finite are never cut.
pub fn springs_crossed(
    camera: &OrbitCamera,
    viewport: Vec2,
    path: &[Vec2],
    positions: &[Vec3],
    springs: impl Iterator<Item = (usize, usize)>,
) -> Vec<(usize, usize)> {
    let Some((lo, hi)) = path.iter().fold(None, |acc: Option<(Vec2, Vec2)>, &p| {
        Some(acc.map_or((p, p), |(lo, hi)| (lo.min(p), hi.max(p))))
    }) else {
        return Vec::new();
    };
    let screen: Vec<Option<Vec2>> = positions
        .iter()
        .map(|&p| {
            p.is_finite()
                .then(|| camera.project(p, viewport))
                .flatten()
                .map(|(s, _)| s)
        })
        .collect();
    springs
        .filter(|&(a, b)| match (screen.get(a), screen.get(b)) {
            (Some(Some(p)), Some(Some(q))) => {
                // Cheap test first: the spring's box against the path's.
                let near = p.min(*q).cmple(hi).all() && p.max(*q).cmpge(lo).all();
                near && path.windows(2).any(|w| segments_cross(w[0], w[1], *p, *q))
            }
            _ => false,
        })
        .collect()
}

/// Whether the segments `a`-`b` and `c`-`d` cross (touching counts).
fn segments_cross(a: Vec2, b: Vec2, c: Vec2, d: Vec2) -> bool {
    let side = |p: Vec2, q: Vec2, r: Vec2| (q - p).perp_dot(r - p);
    let (d1, d2) = (side(c, d, a), side(c, d, b));
    let (d3, d4) = (side(a, b, c), side(a, b, d));
    let apart = |x: f32, y: f32| (x > 0.0 && y > 0.0) || (x < 0.0 && y < 0.0);
    !(apart(d1, d2) || apart(d3, d4)) && (a != b || c != d)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn crossing_segments() {
        let v = |x: f32, y: f32| Vec2::new(x, y);
        assert!(segments_cross(
            v(0.0, 0.0),
            v(2.0, 2.0),
            v(0.0, 2.0),
            v(2.0, 0.0)
        ));
        assert!(!segments_cross(
            v(0.0, 0.0),
            v(1.0, 0.0),
            v(0.0, 1.0),
            v(1.0, 1.0)
        ));
        assert!(!segments_cross(
            v(0.0, 0.0),
            v(1.0, 1.0),
            v(2.0, 2.0),
            v(3.0, 0.0)
        ));
    }

    #[test]
    fn default_camera_looks_at_target() {
        let cam = OrbitCamera::default();
        let f = cam.forward();
        let to_target = (cam.target - cam.eye()).normalize();
        assert!(f.abs_diff_eq(to_target, 1e-5));
    }
}
