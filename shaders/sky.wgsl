// The sky: one triangle covering the viewport, each pixel coloured by
// `sky_color` along its view ray, with a little noise against banding.
// Prepended at load time: common.wgsl.

struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) ndc: vec2<f32>,
};

@vertex
fn vs_main(@builtin(vertex_index) vi: u32) -> VertexOut {
    // (-1,-1), (3,-1), (-1,3): a triangle whose inside holds the whole screen.
    let ndc = vec2<f32>(f32((vi << 1u) & 2u) * 2.0 - 1.0, f32(vi & 2u) * 2.0 - 1.0);
    var out: VertexOut;
    out.clip = vec4<f32>(ndc, 1.0, 1.0);
    out.ndc = ndc;
    return out;
}

// A hash of the pixel position in 0..1 (Jorge Jimenez's interleaved gradient noise).
fn pixel_noise(p: vec2<f32>) -> f32 {
    return fract(52.9829189 * fract(dot(p, vec2<f32>(0.06711056, 0.00583715))));
}

@fragment
fn fs_main(in: VertexOut) -> @location(0) vec4<f32> {
    // The view ray: the far point under this pixel, unprojected, minus the eye.
    let far = globals.inv_view_proj * vec4<f32>(in.ndc, 1.0, 1.0);
    var d = far.xyz / far.w - globals.eye.xyz;
    let len = length(d);
    d = select(vec3<f32>(0.0, 0.0, -1.0), d / len, len > 1e-12);
    // ±half an 8-bit step of dither hides the gradient's bands.
    let dither = (pixel_noise(in.clip.xy) - 0.5) / 255.0;
    return vec4<f32>(sky_color(d) + vec3<f32>(dither), 1.0);
}
