//! Camera and picking maths, headless: rays from known screen points hit the
//! expected particles, projections invert, and the camera controls behave.

use cloth_sandbox::view::{FlyKeys, OrbitCamera, any_in_view, bounds, pick_particle};
use glam::{Vec2, Vec3};

const VIEWPORT: Vec2 = Vec2::new(800.0, 600.0);

/// A camera on +z looking at the origin.
fn front_camera() -> OrbitCamera {
    OrbitCamera {
        target: Vec3::ZERO,
        yaw: 0.0,
        pitch: 0.0,
        distance: 10.0,
        fov_y: 60f32.to_radians(),
    }
}

/// A 5x5 grid in the z = 0 plane, 1 m apart, centred on the origin.
fn grid() -> Vec<Vec3> {
    (0..25)
        .map(|i| Vec3::new((i % 5) as f32 - 2.0, (i / 5) as f32 - 2.0, 0.0))
        .collect()
}

#[test]
fn centre_of_screen_picks_the_particle_at_the_target() {
    let cam = front_camera();
    let picked = pick_particle(&cam, VIEWPORT, VIEWPORT * 0.5, &grid(), 8.0);
    assert_eq!(picked, Some(12));
}

#[test]
fn projected_particle_is_picked_from_its_screen_position() {
    let cam = OrbitCamera {
        yaw: 0.6,
        pitch: 0.3,
        ..front_camera()
    };
    let points = grid();
    for (i, &p) in points.iter().enumerate() {
        let (s, _) = cam.project(p, VIEWPORT).expect("in front of the camera");
        // A few pixels off still picks it.
        assert_eq!(
            pick_particle(&cam, VIEWPORT, s + Vec2::new(2.0, -2.0), &points, 6.0),
            Some(i)
        );
    }
}

#[test]
fn right_of_centre_on_screen_is_plus_x_and_up_is_plus_y() {
    let cam = front_camera();
    let (s, _) = cam.project(Vec3::new(1.0, 0.0, 0.0), VIEWPORT).unwrap();
    assert!(s.x > 400.0 && (s.y - 300.0).abs() < 1e-3);
    let (s, _) = cam.project(Vec3::new(0.0, 1.0, 0.0), VIEWPORT).unwrap();
    assert!(s.y < 300.0 && (s.x - 400.0).abs() < 1e-3);
    // 1 m at 10 m with a 60° fov spans 300 / (10 tan 30°) pixels.
    let expected = 300.0 / (10.0 * 30f32.to_radians().tan());
    assert!(
        (300.0 - s.y - expected).abs() < 0.1,
        "{} vs {expected}",
        300.0 - s.y
    );
}

#[test]
fn nothing_is_picked_far_from_every_particle() {
    let cam = front_camera();
    assert_eq!(
        pick_particle(&cam, VIEWPORT, Vec2::new(5.0, 5.0), &grid(), 8.0),
        None
    );
}

#[test]
fn nearer_particle_wins_when_two_overlap_on_screen() {
    let cam = front_camera();
    let points = vec![
        Vec3::new(0.0, 0.0, -3.0),
        Vec3::new(0.0, 0.0, 2.0),
        Vec3::new(0.0, 0.0, 0.0),
    ];
    assert_eq!(
        pick_particle(&cam, VIEWPORT, VIEWPORT * 0.5, &points, 8.0),
        Some(1)
    );
}

#[test]
fn particles_behind_the_camera_or_not_finite_are_ignored() {
    let cam = front_camera();
    let points = vec![
        Vec3::new(0.0, 0.0, 20.0),
        Vec3::splat(f32::NAN),
        Vec3::new(0.0, 0.0, f32::INFINITY),
    ];
    assert_eq!(
        pick_particle(&cam, VIEWPORT, VIEWPORT * 0.5, &points, 50.0),
        None
    );
}

#[test]
fn ray_through_a_projected_point_passes_through_it() {
    let cam = OrbitCamera {
        target: Vec3::new(1.0, 2.0, -1.0),
        yaw: -0.8,
        pitch: 0.5,
        distance: 7.0,
        fov_y: 45f32.to_radians(),
    };
    let p = Vec3::new(1.5, 2.5, -0.5);
    let (s, _) = cam.project(p, VIEWPORT).unwrap();
    let ray = cam.ray(s, VIEWPORT);
    assert!(
        ray.distance_to_point(p) < 1e-3,
        "{}",
        ray.distance_to_point(p)
    );
    assert!((ray.dir.length() - 1.0).abs() < 1e-5);
}

#[test]
fn drag_point_stays_on_the_camera_facing_plane_through_the_particle() {
    let cam = OrbitCamera {
        yaw: 0.4,
        pitch: 0.2,
        ..front_camera()
    };
    let anchor = Vec3::new(0.5, -0.5, 0.3);
    let target = cam
        .drag_point(Vec2::new(100.0, 450.0), VIEWPORT, anchor)
        .unwrap();
    assert!((target - anchor).dot(cam.forward()).abs() < 1e-3);
    let (s, _) = cam.project(target, VIEWPORT).unwrap();
    assert!(s.distance(Vec2::new(100.0, 450.0)) < 0.05);
    // At the particle's own screen position the target is the particle itself.
    let (here, _) = cam.project(anchor, VIEWPORT).unwrap();
    assert!(
        cam.drag_point(here, VIEWPORT, anchor)
            .unwrap()
            .distance(anchor)
            < 1e-3
    );
}

#[test]
fn framing_fits_the_box_in_view() {
    let mut cam = OrbitCamera::default();
    let (lo, hi) = (Vec3::new(-3.0, -1.0, -0.5), Vec3::new(5.0, 4.0, 0.5));
    cam.frame(lo, hi);
    assert_eq!(cam.target, (lo + hi) * 0.5);
    for corner in 0..8 {
        let p = Vec3::new(
            if corner & 1 == 0 { lo.x } else { hi.x },
            if corner & 2 == 0 { lo.y } else { hi.y },
            if corner & 4 == 0 { lo.z } else { hi.z },
        );
        let (s, _) = cam.project(p, VIEWPORT).unwrap();
        assert!(
            s.x >= 0.0 && s.x <= VIEWPORT.x && s.y >= 0.0 && s.y <= VIEWPORT.y,
            "{p} -> {s}"
        );
    }
}

#[test]
fn orbit_keeps_distance_and_clamps_pitch() {
    let mut cam = front_camera();
    cam.orbit(Vec2::new(120.0, 10_000.0));
    assert!((cam.eye().distance(cam.target) - 10.0).abs() < 1e-4);
    assert!(cam.pitch < std::f32::consts::FRAC_PI_2);
    assert!(cam.view().is_finite());
    cam.orbit(Vec2::new(f32::NAN, 0.0));
    assert!(cam.yaw.is_finite());
}

#[test]
fn zoom_in_moves_closer_and_stays_in_range() {
    let mut cam = front_camera();
    cam.zoom(1.0);
    assert!(cam.distance < 10.0);
    cam.zoom(-1000.0);
    assert!(cam.distance <= cloth_sandbox::view::MAX_DISTANCE);
    cam.zoom(1000.0);
    assert!(cam.distance >= cloth_sandbox::view::MIN_DISTANCE);
}

#[test]
fn pan_moves_the_target_with_the_cursor() {
    let mut cam = front_camera();
    let p = Vec3::ZERO;
    let (before, _) = cam.project(p, VIEWPORT).unwrap();
    cam.pan(Vec2::new(50.0, 20.0), VIEWPORT);
    let (after, _) = cam.project(p, VIEWPORT).unwrap();
    assert!(
        (after - before - Vec2::new(50.0, 20.0)).length() < 0.5,
        "{before} -> {after}"
    );
}

#[test]
fn fly_keys_move_forward_and_up() {
    let mut cam = front_camera();
    let eye = cam.eye();
    cam.fly(
        FlyKeys {
            forward: true,
            ..FlyKeys::default()
        },
        0.5,
    );
    assert!((cam.eye() - eye).dot(cam.forward()) > 0.0);
    let y = cam.target.y;
    cam.fly(
        FlyKeys {
            up: true,
            ..FlyKeys::default()
        },
        0.5,
    );
    assert!(cam.target.y > y);
}

#[test]
fn bounds_skip_non_finite_points() {
    let (lo, hi) = bounds(&[Vec3::ONE, Vec3::splat(f32::NAN), -Vec3::ONE]).unwrap();
    assert_eq!((lo, hi), (-Vec3::ONE, Vec3::ONE));
    assert!(bounds(&[]).is_none());
}

#[test]
fn a_scene_is_in_view_while_one_point_projects_inside() {
    let camera = front_camera();
    // Half the vertical field of view is 30°: at 10 m the view reaches
    // 10 tan 30° = 5.77 m up and down.
    let half_height = 10.0 * 30f32.to_radians().tan();
    assert!(any_in_view(&camera, VIEWPORT, &grid()));
    let below = |y: f32| vec![Vec3::new(0.0, y, 0.0), Vec3::new(1.0, y, 0.0)];
    assert!(any_in_view(&camera, VIEWPORT, &below(-0.95 * half_height)));
    assert!(!any_in_view(&camera, VIEWPORT, &below(-1.05 * half_height)));
    // Behind the camera, or not finite: never in view.
    assert!(!any_in_view(
        &camera,
        VIEWPORT,
        &[Vec3::new(0.0, 0.0, 20.0)]
    ));
    assert!(!any_in_view(
        &camera,
        VIEWPORT,
        &[Vec3::NAN, Vec3::new(0.0, 50.0, 0.0)]
    ));
    // One point inside is enough.
    let mut fallen = below(-100.0);
    fallen.push(Vec3::ZERO);
    assert!(any_in_view(&camera, VIEWPORT, &fallen));
}
