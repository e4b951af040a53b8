// Shared by every scene pipeline: camera and light uniforms (bind group 0).
struct Globals {
    view_proj: mat4x4<f32>,
    // xyz: eye position (m).
    eye: vec4<f32>,
    // xyz: unit vector towards the light.
    light_dir: vec4<f32>,
    // rgb: tint of back faces; a: unused.
    back_tint: vec4<f32>,
    // x, y: viewport size (px); z: tan(fov_y / 2); w: unused.
    viewport: vec4<f32>,
};

@group(0) @binding(0) var<uniform> globals: Globals;

// World size (m) of one pixel at the distance of `p` from the eye.
fn pixel_size(p: vec3<f32>) -> f32 {
    let depth = max(distance(p, globals.eye.xyz), 1e-4);
    return 2.0 * depth * globals.viewport.z / max(globals.viewport.y, 1.0);
}

// Moves `p` towards the eye by `px` pixels' worth so overlays win the depth test
// against the surface they sit on.
fn towards_eye(p: vec3<f32>, px: f32) -> vec3<f32> {
    let to_eye = globals.eye.xyz - p;
    let len = length(to_eye);
    if (len <= 1e-6) {
        return p;
    }
    return p + to_eye / len * min(px * pixel_size(p), 0.5 * len);
}
