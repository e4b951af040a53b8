// FXAA (after Timothy Lottes' FXAA, the compact "PC" variant): anti-aliasing as a
// post pass over the finished picture, for adapters drawn without MSAA. Edges
// are found from the luma of the four diagonal neighbours; the pixel is then
// blurred along the edge (across the luma gradient's perpendicular) by up to
// SPAN_MAX pixels, keeping the two-tap blend when the four-tap one overshoots
// the neighbourhood's luma range. Standalone (no common.wgsl).

@group(0) @binding(0) var scene: texture_2d<f32>;
@group(0) @binding(1) var scene_sampler: sampler;

const SPAN_MAX: f32 = 8.0;
const REDUCE_MUL: f32 = 0.125;
const REDUCE_MIN: f32 = 0.0078125;

@vertex
fn vs_main(@builtin(vertex_index) vi: u32) -> @builtin(position) vec4<f32> {
    let ndc = vec2<f32>(f32((vi << 1u) & 2u) * 2.0 - 1.0, f32(vi & 2u) * 2.0 - 1.0);
    return vec4<f32>(ndc, 0.0, 1.0);
}

fn rgb_at(uv: vec2<f32>) -> vec3<f32> {
    return textureSampleLevel(scene, scene_sampler, uv, 0.0).rgb;
}

// Perceived brightness (Rec. 601 weights).
fn luma(c: vec3<f32>) -> f32 {
    return dot(c, vec3<f32>(0.299, 0.587, 0.114));
}

@fragment
fn fs_main(@builtin(position) pos: vec4<f32>) -> @location(0) vec4<f32> {
    let size = vec2<f32>(textureDimensions(scene));
    let texel = 1.0 / size;
    let uv = pos.xy * texel;
    let nw = luma(rgb_at(uv + vec2<f32>(-1.0, -1.0) * texel));
    let ne = luma(rgb_at(uv + vec2<f32>(1.0, -1.0) * texel));
    let sw = luma(rgb_at(uv + vec2<f32>(-1.0, 1.0) * texel));
    let se = luma(rgb_at(uv + vec2<f32>(1.0, 1.0) * texel));
    let centre = rgb_at(uv);
    let m = luma(centre);
    let lo = min(m, min(min(nw, ne), min(sw, se)));
    let hi = max(m, max(max(nw, ne), max(sw, se)));
    // Direction along the edge: perpendicular to the luma gradient.
    var dir = vec2<f32>(-((nw + ne) - (sw + se)), (nw + sw) - (ne + se));
    let reduce = max((nw + ne + sw + se) * 0.25 * REDUCE_MUL, REDUCE_MIN);
    let scale = 1.0 / (min(abs(dir.x), abs(dir.y)) + reduce);
    dir = clamp(dir * scale, vec2<f32>(-SPAN_MAX), vec2<f32>(SPAN_MAX)) * texel;
    let a = 0.5 * (rgb_at(uv + dir * (1.0 / 3.0 - 0.5)) + rgb_at(uv + dir * (2.0 / 3.0 - 0.5)));
    let b = a * 0.5 + 0.25 * (rgb_at(uv - dir * 0.5) + rgb_at(uv + dir * 0.5));
    let lb = luma(b);
    if (lb < lo || lb > hi) {
        return vec4<f32>(a, 1.0);
    }
    return vec4<f32>(b, 1.0);
}
