// Lit, two-sided triangle meshes (cloth, ground, sphere): Lambert + Blinn-Phong
// with per-vertex normals, base colour times a UV-mapped texture.
// Prepended at load time: common.wgsl.

@group(1) @binding(0) var tex: texture_2d<f32>;
@group(1) @binding(1) var tex_sampler: sampler;

struct VertexIn {
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) uv: vec2<f32>,
    // rgb: base colour; a: how much the texture modulates it (0..1).
    @location(3) color: vec4<f32>,
};

struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) uv: vec2<f32>,
    @location(3) color: vec4<f32>,
};

@vertex
fn vs_main(in: VertexIn) -> VertexOut {
    var out: VertexOut;
    out.clip = globals.view_proj * vec4<f32>(in.position, 1.0);
    out.world = in.position;
    out.normal = in.normal;
    out.uv = in.uv;
    out.color = in.color;
    return out;
}

@fragment
fn fs_main(in: VertexOut, @builtin(front_facing) front: bool) -> @location(0) vec4<f32> {
    var n = in.normal;
    let len = length(n);
    if (len > 1e-6) {
        n = n / len;
    } else {
        n = vec3<f32>(0.0, 1.0, 0.0);
    }
    var base = in.color.rgb;
    if (!front) {
        n = -n;
        base = base * globals.back_tint.rgb;
    }
    let texel = textureSample(tex, tex_sampler, in.uv).rgb;
    base = base * mix(vec3<f32>(1.0), texel, in.color.a);

    let l = globals.light_dir.xyz;
    let v = normalize(globals.eye.xyz - in.world);
    // Light the side facing the viewer: a thin sheet is lit from either side,
    // by a fixed key light and a fill light at the eye.
    if (dot(n, v) < 0.0) {
        n = -n;
    }
    let key = abs(dot(n, l));
    let fill = max(dot(n, v), 0.0);
    let h = normalize(l * sign(dot(n, l) + 1e-6) + v);
    let spec = pow(max(dot(n, h), 0.0), 48.0) * 0.12;
    let shade = 0.22 + 0.5 * key + 0.35 * fill;
    return vec4<f32>(base * shade + vec3<f32>(spec), 1.0);
}
