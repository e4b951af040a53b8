// The ground: a large square at globals.ground.x, a soft checker with thin grid
// lines, lit by the shadowed key light, fading into the sky with distance.
// Prepended at load time: common.wgsl, shadow_sample.wgsl.

struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
};

@vertex
fn vs_main(@builtin(vertex_index) vi: u32) -> VertexOut {
    var corners = array<vec2<f32>, 6>(
        vec2<f32>(-1.0, -1.0), vec2<f32>(1.0, -1.0), vec2<f32>(1.0, 1.0),
        vec2<f32>(-1.0, -1.0), vec2<f32>(1.0, 1.0), vec2<f32>(-1.0, 1.0),
    );
    let c = corners[vi] * globals.ground_fade.w;
    let world = vec3<f32>(globals.ground.z + c.x, globals.ground.x, globals.ground.w + c.y);
    var out: VertexOut;
    out.clip = globals.view_proj * vec4<f32>(world, 1.0);
    out.world = world;
    return out;
}

@fragment
fn fs_main(in: VertexOut) -> @location(0) vec4<f32> {
    let cell = max(globals.ground_fade.z, 1e-6);
    let g = in.world.xz / cell;
    // Grid lines, anti-aliased: distance to the nearest cell edge in pixels
    // (the cell coordinate's change per pixel from fwidth), 1 on a line, 0 a
    // pixel away.
    let w = max(fwidth(g), vec2<f32>(1e-6));
    let edge = abs(fract(g - 0.5) - 0.5) / w;
    let line = 1.0 - min(min(edge.x, edge.y), 1.0);
    // Lines thinner than a pixel's footprint fade out instead of aliasing.
    let line_fade = 1.0 - smoothstep(0.15, 0.6, max(w.x, w.y));
    // A soft checker: alternate cells 4 % darker.
    let parity = (i32(floor(g.x)) + i32(floor(g.y))) & 1;
    var albedo = vec3<f32>(0.66, 0.66, 0.64) * select(1.0, 0.95, parity == 1);
    albedo = albedo * (1.0 - 0.14 * line * line_fade);

    let n = vec3<f32>(0.0, 1.0, 0.0);
    let lit = shadow_factor(in.world, n);
    let ndl = max(globals.light_dir.y, 0.0);
    let shade = 0.50 * ambient(n) + vec3<f32>(0.60 * ndl * lit);
    let colour = albedo * shade;

    // Fade into the sky seen along the same ray: smoothstep over the radii
    // ground_fade.x .. ground_fade.y from the ground's centre.
    let r = distance(in.world.xz, globals.ground.zw);
    let fade = smoothstep(globals.ground_fade.x, globals.ground_fade.y, r);
    let d = normalize(in.world - globals.eye.xyz);
    return vec4<f32>(mix(colour, sky_color(d), fade), 1.0);
}
