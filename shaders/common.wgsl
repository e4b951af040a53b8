// Shared by every scene pipeline: camera, light, sky, ground and shadow uniforms
// (bind group 0). Layout matches `Globals` in src/render/mod.rs.
struct Globals {
    view_proj: mat4x4<f32>,
    // Clip to world: the sky turns a screen position back into a view ray.
    inv_view_proj: mat4x4<f32>,
    // World to the key light's clip space (its orthographic shadow frustum).
    light_view_proj: mat4x4<f32>,
    // xyz: eye position (m).
    eye: vec4<f32>,
    // xyz: unit vector towards the key light; w: unused.
    light_dir: vec4<f32>,
    // x, y: viewport size (px); z: tan(fov_y / 2); w: unused.
    viewport: vec4<f32>,
    // rgb: sky colour straight up.
    zenith: vec4<f32>,
    // rgb: sky colour at the horizon (ViewOptions.background).
    horizon: vec4<f32>,
    // x: ground height (m); y: 1 when a ground is drawn; z, w: x and z (m) of its centre.
    ground: vec4<f32>,
    // x, y: radii (m) where the ground starts and ends fading into the sky;
    // z: grid cell (m); w: half the side of the ground quad (m).
    ground_fade: vec4<f32>,
    // x: 1 / shadow map side (texels); y: normal offset (m); z: 1 when shadows
    // are on; w: PCF radius (texels).
    shadow: vec4<f32>,
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

// Sky colour along the unit view direction `d`: from the horizon colour up to
// the zenith colour as elevation e = d.y rises, mix(horizon, zenith, e^0.6)
// (the exponent keeps a bright band near the horizon); below the horizon a haze
// a little darker than the horizon, so the fading ground meets it smoothly.
fn sky_color(d: vec3<f32>) -> vec3<f32> {
    let e = clamp(d.y, -1.0, 1.0);
    if (e >= 0.0) {
        return mix(globals.horizon.rgb, globals.zenith.rgb, pow(e, 0.6));
    }
    return globals.horizon.rgb * mix(1.0, 0.82, smoothstep(0.0, 0.25, -e));
}

// Hemisphere ambient light for a unit normal `n`: a cool sky light from above
// and a warmer, darker bounce from the ground below, blended by n.y.
fn ambient(n: vec3<f32>) -> vec3<f32> {
    return mix(vec3<f32>(0.52, 0.49, 0.46), vec3<f32>(0.88, 0.93, 1.0), 0.5 + 0.5 * n.y);
}
