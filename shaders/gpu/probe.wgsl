// The conformance probe (`src/gpu/conformance.rs`): one law of `laws.wgsl`,
// chosen by `law`, applied to each case of random inputs, its results written
// as three vec4 per case. Tests only; the engine's pass is `step.wgsl`.

struct Case {
    a: vec4<f32>,
    b: vec4<f32>,
    c: vec4<f32>,
    d: vec4<f32>,
    e: vec4<f32>,
    f: vec4<f32>,
}

@group(0) @binding(0) var<uniform> law: vec4<u32>;
@group(0) @binding(1) var<storage, read> cases: array<Case>;
@group(0) @binding(2) var<storage, read_write> results: array<vec4<f32>>;

fn law_of(k: Case) -> array<vec4<f32>, 3> {
    let z = vec4<f32>(0.0);
    switch law.x {
        case 0u: {
            let c = SpringCoefficients(k.c.x, k.c.y, k.c.z);
            return array(vec4(spring_force(k.a.xyz, k.b.xyz, c), 0.0), z, z);
        }
        case 1u: {
            let wind = vec3(k.a.w, k.b.w, k.c.w);
            let f = triangle_drag(k.a.xyz, k.b.xyz, k.c.xyz, k.d.xyz, k.e.xyz, k.f.xyz, wind, k.d.w);
            return array(vec4(f, 0.0), z, z);
        }
        case 2u: {
            return array(vec4(air_damped(k.a.xyz, k.b.x, k.c.xyz), 0.0), z, z);
        }
        case 3u: {
            return array(vec4(ground_support(k.a.x, k.a.y, k.a.z, k.a.w), 0.0, 0.0, 0.0), z, z);
        }
        case 4u: {
            return array(vec4(acceleration(k.a.xyz, k.b.x, k.c.xyz), 0.0), z, z);
        }
        case 5u: {
            let s = update(u32(k.b.w), k.a.xyz, k.c.xyz, k.b.x, k.b.y, k.b.z);
            return array(vec4(s.moving, 0.0), vec4(s.u, 0.0), vec4(s.v, 0.0));
        }
        case 6u: {
            return array(vec4(surface_offset(k.a.xyz, dot(k.a.xyz, k.a.xyz), k.b.x), 0.0), z, z);
        }
        case 7u: {
            let m = contact_sphere(k.a.xyz, k.b.xyz, k.c.x, k.c.y, k.c.z);
            return array(vec4(m.push, 0.0), vec4(m.v, 0.0), z);
        }
        case 8u: {
            let v = contact_ground_friction(k.a.x, k.b.xyz, k.a.y, k.c, k.a.z);
            return array(vec4(v, 0.0), z, z);
        }
        case 10u: {
            return array(vec4(length_factor(k.a.xyz, k.b.x, k.b.y), 0.0, 0.0, 0.0), z, z);
        }
        case 11u: {
            let c = XpbdCoefficients(k.b.y, k.c.x, k.c.y, k.c.z);
            let st = xpbd_factor(k.a.xyz, k.d.xyz, k.b.x, c, k.b.z);
            return array(vec4(st, 0.0, 0.0), z, z);
        }
        case 12u: {
            return array(vec4(xpbd_coefficients(k.a.x, k.a.y, k.a.z), 0.0, 0.0), z, z);
        }
        default: {
            return array(vec4(speed_limit(k.a.xyz, k.b.x), 0.0, 0.0, 0.0), z, z);
        }
    }
}

@compute @workgroup_size(64)
fn probe(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i >= arrayLength(&cases) {
        return;
    }
    let r = law_of(cases[i]);
    results[3u * i] = r[0];
    results[3u * i + 1u] = r[1];
    results[3u * i + 2u] = r[2];
}
