// Lit, two-sided triangle meshes (cloth, colliders, the spheres and tubes of
// surfaceless scenes): a front and a back colour, times a UV-mapped texture,
// lit by a shadowed key light, a hemisphere ambient and a fill at the eye.
// Prepended at load time: common.wgsl, shadow_sample.wgsl.

@group(2) @binding(0) var tex: texture_2d<f32>;
@group(2) @binding(1) var tex_sampler: sampler;

struct VertexIn {
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) uv: vec2<f32>,
    // rgb: front colour; a: how much the texture modulates it (0..1).
    @location(3) color: vec4<f32>,
    // rgb: back colour; a: unused.
    @location(4) back: vec4<f32>,
};

struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) uv: vec2<f32>,
    @location(3) color: vec4<f32>,
    @location(4) back: vec4<f32>,
};

@vertex
fn vs_main(in: VertexIn) -> VertexOut {
    var out: VertexOut;
    out.clip = globals.view_proj * vec4<f32>(in.position, 1.0);
    out.world = in.position;
    out.normal = in.normal;
    out.uv = in.uv;
    out.color = in.color;
    out.back = in.back;
    return out;
}

@fragment
fn fs_main(in: VertexOut, @builtin(front_facing) front: bool) -> @location(0) vec4<f32> {
    let texel = textureSample(tex, tex_sampler, in.uv).rgb;
    var n = in.normal;
    let len = length(n);
    if (len > 1e-6) {
        n = n / len;
    } else {
        n = vec3<f32>(0.0, 1.0, 0.0);
    }
    var base = in.color.rgb;
    if (!front) {
        base = in.back.rgb;
    }
    base = base * mix(vec3<f32>(1.0), texel, in.color.a);

    let l = globals.light_dir.xyz;
    let v = normalize(globals.eye.xyz - in.world);
    // Light the side facing the viewer: n turned towards the eye.
    if (dot(n, v) < 0.0) {
        n = -n;
    }
    let ndl = dot(n, l);
    let lit = shadow_factor(in.world, n);
    // Lambert key light n·l on the side facing it; a thin sheet also lets 30 %
    // of it through to its other side (translucency). Both are shadowed.
    let direct = select(-0.3 * ndl, ndl, ndl >= 0.0) * lit;
    let fill = max(dot(n, v), 0.0);
    // Blinn-Phong highlight of the key light: (n·h)^48, h the half vector.
    let h = normalize(l + v);
    let spec = pow(max(dot(n, h), 0.0), 48.0) * 0.15 * lit * f32(ndl > 0.0);
    let shade = 0.34 * ambient(n) + vec3<f32>(0.72 * direct + 0.26 * fill);
    return vec4<f32>(base * shade + vec3<f32>(spec), 1.0);
}
