// Shadow lookups for the lit pipelines (bind group 1): the key light's depth
// map and a comparison sampler. Prepended after common.wgsl.

@group(1) @binding(0) var shadow_map: texture_depth_2d;
@group(1) @binding(1) var shadow_sampler: sampler_comparison;

// 12 Poisson-disc taps in the unit disc (PCF kernel).
const POISSON = array<vec2<f32>, 12>(
    vec2<f32>(-0.326, -0.406), vec2<f32>(-0.840, -0.074), vec2<f32>(-0.696, 0.457),
    vec2<f32>(-0.203, 0.621), vec2<f32>(0.962, -0.195), vec2<f32>(0.473, -0.480),
    vec2<f32>(0.519, 0.767), vec2<f32>(0.185, -0.893), vec2<f32>(0.507, 0.064),
    vec2<f32>(0.896, 0.412), vec2<f32>(-0.322, -0.933), vec2<f32>(-0.792, -0.598),
);

// Fraction (0 shadowed .. 1 lit) of the key light reaching the world point `p`
// of a surface with unit normal `n`. The point is first pushed along the normal
// (turned towards the light) by `globals.shadow.y`, about a shadow texel: this
// normal offset, with the shadow pass's slope-scaled depth bias, keeps a thin
// two-sided sheet from shadowing itself (acne). Then percentage-closer
// filtering: the mean of 12 comparisons `depth(p) <= map` over a Poisson disc of
// `globals.shadow.w` texels, each tap itself bilinearly filtered by the
// comparison sampler, so the edge fades over a few texels. Points outside the
// light's frustum are lit.
fn shadow_factor(p: vec3<f32>, n: vec3<f32>) -> f32 {
    if (globals.shadow.z < 0.5) {
        return 1.0;
    }
    let l = globals.light_dir.xyz;
    let towards_light = select(-n, n, dot(n, l) >= 0.0);
    let q = p + towards_light * globals.shadow.y;
    let clip = globals.light_view_proj * vec4<f32>(q, 1.0);
    let ndc = clip.xyz / clip.w;
    let uv = vec2<f32>(ndc.x * 0.5 + 0.5, 0.5 - ndc.y * 0.5);
    if (any(uv < vec2<f32>(0.0)) || any(uv > vec2<f32>(1.0)) || ndc.z > 1.0) {
        return 1.0;
    }
    let radius = globals.shadow.w * globals.shadow.x;
    var lit = 0.0;
    for (var i = 0; i < 12; i = i + 1) {
        lit = lit + textureSampleCompareLevel(shadow_map, shadow_sampler, uv + POISSON[i] * radius, ndc.z);
    }
    return lit / 12.0;
}
