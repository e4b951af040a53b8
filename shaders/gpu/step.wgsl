// One step of the GPU engine for every particle, in the order of the mesh
// engine's passes: gather the damped springs and the triangles' drag, air
// damping, the ground's penalty, the applied force, `acceleration`, `update`,
// then (`end_of_step`) contact with the sphere and the ground's friction, and the
// speed limit. With constraints, the end of the step waits for them
// (`constrain.wgsl`). Each particle gathers its own springs and triangles (no
// atomics, no shared writes), so every run gives the same bits. Appended to
// `laws.wgsl`.

// One step's parameters; positions are relative to the engine's origin.
struct Step {
    gravity: vec4<f32>,   // xyz m/s²; w: the step h in s
    force: vec4<f32>,     // xyz the applied force in N; w: -c, air damping (0: off)
    wind: vec4<f32>,      // xyz the air's velocity at the step's start; w: ρ C_d / 2 (0: no drag)
    ground: vec4<f32>,    // height, stiffness, damping, friction
    sphere: vec4<f32>,    // centre, radius
    limits: vec4<f32>,    // x: the sphere's friction μ; y: the speed limit (0: none); z: the stretch limit τ
    flags: vec4<u32>,     // x: the update rule; y: particles; z: GROUND | SPHERE | SPRINGS | CONSTRAINED; w: 0 (`opaque`)
}

const GROUND: u32 = 1u;
const SPHERE: u32 = 2u;
const SPRINGS: u32 = 4u;
// Constraint passes follow the step: it leaves the end of the step to `end_step`.
const CONSTRAINED: u32 = 8u;

// A particle: its position in m is x.xyz + low.xyz (two f32, about 48 bits
// between them, so that a stiff spring's length is not lost to the rounding of
// its ends); x.w its inverse mass (0: pinned); v in m/s.
struct Particle {
    x: vec4<f32>,
    v: vec4<f32>,
    low: vec4<f32>,
}

// The vector from b to a, from their two-part positions: hi - hi is exact for
// nearby particles, so the difference keeps the low parts' bits.
fn offset(a: Particle, b: Particle) -> vec3<f32> {
    return (a.x.xyz - b.x.xyz) + (a.low.xyz - b.low.xyz);
}

// A two-part position (hi, lo) moved by dx: Knuth's two-sum, then renormalised.
struct Position {
    hi: vec3<f32>,
    lo: vec3<f32>,
}

fn moved(p: Position, dx: vec3<f32>) -> Position {
    let s = opaque(p.hi + dx);
    let bb = opaque(s - p.hi);
    let err = (p.hi - opaque(s - bb)) + (dx - bb);
    let lo = p.lo + err;
    let hi = opaque(s + lo);
    return Position(hi, lo - opaque(hi - s));
}

// `x`, through bits the compiler cannot see through: xor a zero it does not
// know (the step record's flags.w). Shader compilers may reassociate float
// sums, which folds a two-sum's error to 0 (lavapipe does: a particle's moves
// of 1e-9 m were lost); a sum behind this is a value, not an expression.
fn opaque(x: vec3<f32>) -> vec3<f32> {
    return bitcast<vec3<f32>>(bitcast<vec3<u32>>(x) ^ vec3<u32>(step.flags.w));
}

@group(0) @binding(0) var<uniform> step: Step;
@group(0) @binding(1) var<storage, read> state_in: array<Particle>;
// Position Verlet's update velocity `u = (x - x_prev) / h` (unused otherwise).
@group(0) @binding(2) var<storage, read> u_in: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read_write> state_out: array<Particle>;
@group(0) @binding(4) var<storage, read_write> u_out: array<vec4<f32>>;
// Per particle (n + 1 entries): x its first spring link, y its first triangle link.
@group(1) @binding(0) var<storage, read> offsets: array<vec2<u32>>;
// A spring at a particle: -k, k L, -b (as f32 bits) and the other end.
@group(1) @binding(1) var<storage, read> links: array<vec4<u32>>;
// A triangle at a particle: its three vertices in the model's order.
@group(1) @binding(2) var<storage, read> triangle_links: array<vec4<u32>>;
// With constraints, each particle's position before them, as `Position` (hi,
// lo): two vec4 a particle. `end_step` takes the velocity of their moves.
@group(2) @binding(1) var<storage, read_write> before: array<vec4<f32>>;

// Large cloths dispatch in two dimensions (65,535 workgroups a dimension).
const ROW: u32 = 65535u * 64u;

@compute @workgroup_size(64)
fn step_particles(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x + id.y * ROW;
    if i >= step.flags.y {
        return;
    }
    let me = state_in[i];
    let xi = me.x.xyz + me.low.xyz;
    let w = me.x.w;
    let vi = me.v.xyz;
    let h = step.gravity.w;
    var f = vec3<f32>(0.0);
    let range = offsets[i];
    let next = offsets[i + 1u];
    if (step.flags.z & SPRINGS) != 0u {
        for (var k = range.x; k < next.x; k++) {
            let link = links[k];
            let c = SpringCoefficients(bitcast<f32>(link.x), bitcast<f32>(link.y), bitcast<f32>(link.z));
            let other = state_in[link.w];
            f += spring_force(offset(me, other), vi - other.v.xyz, c);
        }
    }
    let half_rho_cd = step.wind.w;
    if half_rho_cd > 0.0 {
        for (var t = range.y; t < next.y; t++) {
            let tri = triangle_links[t];
            let p0 = state_in[tri.x];
            let p1 = state_in[tri.y];
            let p2 = state_in[tri.z];
            f += triangle_drag(
                vec3<f32>(0.0), offset(p1, p0), offset(p2, p0),
                p0.v.xyz, p1.v.xyz, p2.v.xyz,
                step.wind.xyz, half_rho_cd,
            );
        }
    }
    if step.force.w != 0.0 {
        f = air_damped(f, step.force.w, vi);
    }
    let ground = step.ground;
    if (step.flags.z & GROUND) != 0u {
        f.y += ground_support(ground.x - xi.y, vi.y, ground.y, ground.z);
    }
    f += step.force.xyz;
    let a = acceleration(f, w, step.gravity.xyz);
    let method = step.flags.x;
    var u = vi;
    if method == VERLET {
        u = u_in[i].xyz;
    }
    let next_state = update(method, u, a, w, h, 0.5 * h);
    // `advanced` (x + h v) on the two-part position.
    let x = moved(Position(me.x.xyz, me.low.xyz), h * next_state.moving);
    if (step.flags.z & CONSTRAINED) != 0u {
        before[2u * i] = vec4<f32>(x.hi, 0.0);
        before[2u * i + 1u] = vec4<f32>(x.lo, 0.0);
        store_particle(i, Ended(x, next_state.v, next_state.u), w);
        return;
    }
    store_particle(i, end_of_step(x, next_state.v, next_state.u, w), w);
}

// A particle after its constraints: its position, velocity and (Verlet) update
// velocity.
struct Ended {
    x: Position,
    v: vec3<f32>,
    u: vec3<f32>,
}

// `laws::end_of_step_contacts` for the sphere and the ground (the engine steps no
// other colliders), then the speed limit, of a particle at x moving at v, of
// inverse mass w: the push moves x, and the change of velocity goes into u too.
fn end_of_step(x_in: Position, v_in: vec3<f32>, u_in: vec3<f32>, w: f32) -> Ended {
    var x = x_in;
    var v = v_in;
    var u = u_in;
    let h = step.gravity.w;
    let ground = step.ground;
    if w > 0.0 {
        var push = vec3<f32>(0.0);
        if (step.flags.z & SPHERE) != 0u {
            let out = contact_sphere((x.hi - step.sphere.xyz) + x.lo, v, step.sphere.w, step.limits.x, h);
            push = out.push;
            v = out.v;
        }
        if (step.flags.z & GROUND) != 0u {
            v = contact_ground_friction((x.hi.y - ground.x) + x.lo.y + push.y, v, w, ground, h);
        }
        x = moved(x, push);
        u += v - v_in;
    }
    let max_speed = step.limits.y;
    if max_speed > 0.0 {
        let factor = speed_limit(v, max_speed);
        v *= factor;
        u *= factor;
    }
    return Ended(x, v, u);
}

// Particle i's new state (and Verlet's update velocity).
fn store_particle(i: u32, end: Ended, w: f32) {
    state_out[i] = Particle(vec4<f32>(end.x.hi, w), vec4<f32>(end.v, 0.0), vec4<f32>(end.x.lo, 0.0));
    if step.flags.x == VERLET {
        u_out[i] = vec4<f32>(end.u, 0.0);
    }
}
