// The shadow pass: meshes drawn from the key light into its depth map, depth
// only (no fragment stage). Prepended at load time: common.wgsl.

@vertex
fn vs_main(@location(0) position: vec3<f32>) -> @builtin(position) vec4<f32> {
    return globals.light_view_proj * vec4<f32>(position, 1.0);
}
