// Particles as screen-facing discs of a fixed size in pixels, one instance per
// particle, six vertices (two triangles) each; a dark rim outlines every disc.
// Prepended at load time: common.wgsl.

struct InstanceIn {
    @location(0) position: vec3<f32>,
    // Diameter in pixels.
    @location(1) size: f32,
    @location(2) color: vec4<f32>,
};

struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) corner: vec2<f32>,
    @location(1) color: vec4<f32>,
};

@vertex
fn vs_main(@builtin(vertex_index) vi: u32, in: InstanceIn) -> VertexOut {
    var corners = array<vec2<f32>, 6>(
        vec2<f32>(-1.0, -1.0), vec2<f32>(1.0, -1.0), vec2<f32>(1.0, 1.0),
        vec2<f32>(-1.0, -1.0), vec2<f32>(1.0, 1.0), vec2<f32>(-1.0, 1.0),
    );
    let corner = corners[vi];
    var clip = globals.view_proj * vec4<f32>(towards_eye(in.position, in.size), 1.0);
    let half_px = 0.5 * in.size;
    clip = vec4<f32>(clip.xy + corner * half_px * 2.0 / max(globals.viewport.xy, vec2<f32>(1.0)) * clip.w, clip.zw);
    var out: VertexOut;
    out.clip = clip;
    out.corner = corner;
    out.color = in.color;
    return out;
}

@fragment
fn fs_main(in: VertexOut) -> @location(0) vec4<f32> {
    let r2 = dot(in.corner, in.corner);
    if (r2 > 1.0) {
        discard;
    }
    if (r2 > 0.55) {
        return vec4<f32>(in.color.rgb * 0.25, 1.0);
    }
    return in.color;
}
