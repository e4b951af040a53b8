// The physical laws of `src/sim/laws` in WGSL, for the GPU engine. Each function
// carries the name of its Rust law and computes it in the same order, in f32;
// `src/gpu/conformance.rs` runs them (through `probe.wgsl`) on random inputs
// against the f64 laws.
// `mul_add` and `mul_sub` are `fma` here, as in the CPU's vector kernels.

// `EPSILON_LENGTH`, and its square: below them a spring or a sphere offset has
// no direction.
const EPSILON_LENGTH: f32 = 1e-12;
const DEGENERATE_LENGTH2: f32 = 1e-24;
// `DRAG_TINY`: keeps a triangle with no area or no relative wind at zero drag.
const DRAG_TINY: f32 = 1e-30;
// The largest finite f32: a speed over it (or a NaN) is a divergence, not a speed.
const FLOAT_MAX: f32 = 3.40282347e38;

const SYMPLECTIC_EULER: u32 = 0u;
const EXPLICIT_EULER: u32 = 1u;
const VERLET: u32 = 2u;

// `Lanes::rsqrt_or_zero`.
fn rsqrt_or_zero(x: f32, eps2: f32) -> f32 {
    return select(0.0, inverseSqrt(x), x > eps2);
}

// `laws::SpringCoefficients`: -k (N/m), k L (N), -b (N s/m).
struct SpringCoefficients {
    neg_k: f32,
    k_rest: f32,
    neg_b: f32,
}

// `laws::spring_factor`: the damped spring's force on end a is this times d = x_a - x_b.
fn spring_factor(d: vec3<f32>, dv: vec3<f32>, c: SpringCoefficients) -> f32 {
    let l2 = dot(d, d);
    let along = dot(d, dv);
    let inv = rsqrt_or_zero(l2, DEGENERATE_LENGTH2);
    return fma(fma(c.neg_b * along, inv, c.k_rest), inv, c.neg_k);
}

// `laws::spring_force`.
fn spring_force(d: vec3<f32>, dv: vec3<f32>, c: SpringCoefficients) -> vec3<f32> {
    return d * spring_factor(d, dv, c);
}

// `laws::drag_factor`: the drag on each vertex of a triangle of edge cross product m.
fn drag_factor(m: vec3<f32>, v_rel: vec3<f32>, neg_drag: f32) -> f32 {
    let m2 = dot(m, m);
    let vr2 = dot(v_rel, v_rel);
    let vm = dot(v_rel, m);
    let ratio = vr2 * inverseSqrt(fma(vr2, m2, DRAG_TINY));
    return (neg_drag * vm) * ratio;
}

// `laws::air_velocity`: the triangle's mean velocity less the wind.
fn air_velocity(v0: vec3<f32>, v1: vec3<f32>, v2: vec3<f32>, wind: vec3<f32>, third: f32) -> vec3<f32> {
    let rest = fma(v1 + v2, vec3<f32>(third), -wind);
    return fma(v0, vec3<f32>(third), rest);
}

// `laws::triangle_drag`, with half_rho_cd = ρ C_d / 2.
fn triangle_drag(
    x0: vec3<f32>, x1: vec3<f32>, x2: vec3<f32>,
    v0: vec3<f32>, v1: vec3<f32>, v2: vec3<f32>,
    wind: vec3<f32>, half_rho_cd: f32,
) -> vec3<f32> {
    let v_rel = air_velocity(v0, v1, v2, wind, 1.0 / 3.0);
    let m = cross(x1 - x0, x2 - x0);
    let neg_drag = half_rho_cd * (-1.0 / 6.0);
    return m * drag_factor(m, v_rel, neg_drag);
}

// `laws::air_damped`: f - c v, with neg_c = -c.
fn air_damped(f: vec3<f32>, neg_c: f32, v: vec3<f32>) -> vec3<f32> {
    return fma(vec3<f32>(neg_c), v, f);
}

// `laws::ground_support`: k_c d - c_g v_y at depth d > 0, else 0.
fn ground_support(depth: f32, vy: f32, k_c: f32, c_g: f32) -> f32 {
    return select(0.0, fma(k_c, depth, -(c_g * vy)), depth > 0.0);
}

// `laws::acceleration`: f w + g, and 0 for a pinned particle (w = 0).
fn acceleration(f: vec3<f32>, w: f32, g: vec3<f32>) -> vec3<f32> {
    return select(vec3<f32>(0.0), fma(f, vec3<f32>(w), g), w > 0.0);
}

// `laws::Update`.
struct Update {
    moving: vec3<f32>,
    u: vec3<f32>,
    v: vec3<f32>,
}

// `laws::update`: one step h of `method` from update velocity u under acceleration a.
fn update(method: u32, u: vec3<f32>, a: vec3<f32>, w: f32, h: f32, half_h: f32) -> Update {
    let free = w > 0.0;
    let u_new = select(vec3<f32>(0.0), fma(vec3<f32>(h), a, u), free);
    if method == EXPLICIT_EULER {
        return Update(u, u_new, u_new);
    }
    if method == VERLET {
        return Update(u_new, u_new, select(vec3<f32>(0.0), fma(vec3<f32>(half_h), a, u_new), free));
    }
    return Update(u_new, u_new, u_new);
}

// `laws::surface_offset`: the sphere's surface point nearest a particle d from its centre.
fn surface_offset(d: vec3<f32>, dist2: f32, radius: f32) -> vec3<f32> {
    var offset = d * (radius * rsqrt_or_zero(dist2, DEGENERATE_LENGTH2));
    if !(dist2 > DEGENERATE_LENGTH2) {
        offset.y = radius;
    }
    return offset;
}

// `contact::coulomb_along`: the part `along` of v shortened by `most`, or removed.
fn coulomb_along(v: vec3<f32>, along: vec3<f32>, most: f32) -> vec3<f32> {
    let speed2 = dot(along, along);
    if speed2 <= most * most * (1.0 - 1e-6) {
        return v - along;
    }
    let speed = sqrt(speed2);
    if speed <= most {
        return v - along;
    }
    return v - along * (most / speed);
}

// `contact::coulomb`: friction on a surface of unit normal `normal`.
fn coulomb(v: vec3<f32>, normal: vec3<f32>, most: f32) -> vec3<f32> {
    return coulomb_along(v, v - normal * dot(v, normal), most);
}

// `contact::coulomb_up`: friction on the ground, whose normal is up.
fn coulomb_up(v: vec3<f32>, most: f32) -> vec3<f32> {
    return coulomb_along(v, vec3<f32>(v.x, 0.0, v.z), most);
}

// A particle's move and new velocity after contact.
struct Moved {
    push: vec3<f32>,
    v: vec3<f32>,
}

// `Contact::sphere_lanes`: a particle d from the centre of a sphere of `radius`,
// projected out with friction μ over the step h.
fn contact_sphere(d: vec3<f32>, v: vec3<f32>, radius: f32, friction: f32, h: f32) -> Moved {
    let dist2 = dot(d, d);
    let dist = sqrt(dist2);
    if !(dist < radius) {
        return Moved(vec3<f32>(0.0), v);
    }
    let outside = surface_offset(d, dist2, radius);
    let push = outside - d;
    var pushed = v + push * (1.0 / h);
    if friction > 0.0 {
        let normal = outside / radius;
        pushed = coulomb(pushed, normal, friction * length(push) / h);
    }
    return Moved(push, pushed);
}

// `Contact::ground_friction_lanes`: the ground's friction on a particle `above` m
// over it, of inverse mass w; `ground` is (height, stiffness, damping, friction).
fn contact_ground_friction(above: f32, v: vec3<f32>, w: f32, ground: vec4<f32>, h: f32) -> vec3<f32> {
    if !(ground.w > 0.0) {
        return v;
    }
    let support = ground_support(-above, v.y, ground.y, ground.z);
    if !(support > 0.0) {
        return v;
    }
    return coulomb_up(v, ground.w * h * support * w);
}

// `laws::speed_limit`: the factor a velocity is scaled by under `max_speed`.
fn speed_limit(v: vec3<f32>, max_speed: f32) -> f32 {
    let speed = length(v);
    if speed > max_speed && speed <= FLOAT_MAX {
        return max_speed / speed;
    }
    return 1.0;
}

// `laws::length_factor`: the factor s that brings the ends of a spring of vector
// d = x_a - x_b to length `goal`, w the ends' inverse masses summed: x_a -= w_a s d,
// x_b += w_b s d (for l w > 0; the callers leave the rest alone).
fn length_factor(d: vec3<f32>, goal: f32, w: f32) -> f32 {
    let l = length(d);
    return (l - goal) / (l * w);
}

// `laws::xpbd_coefficients`: (α̃, γ) = (1 / (k h²), b / (k h)) of a spring (k, b).
fn xpbd_coefficients(k: f32, b: f32, h: f32) -> vec2<f32> {
    return vec2<f32>(1.0 / (k * h * h), b / (k * h));
}

// `laws::XpbdCoefficients`: the rest length L, α̃, γ and 1 + γ.
struct XpbdCoefficients {
    rest: f32,
    alpha: f32,
    gamma: f32,
    one_gamma: f32,
}

// `laws::xpbd_factor`: XPBD's (s, t) for a spring of vector d whose first end moved
// by `moved` more than its second this step, w its ends' inverse masses summed and
// α̃ λ its multiplier so far times α̃: x_a -= w_a s d, x_b += w_b s d, Δλ = -t.
fn xpbd_factor(d: vec3<f32>, moved: vec3<f32>, w: f32, c: XpbdCoefficients, alpha_lambda: f32) -> vec2<f32> {
    let l2 = dot(d, d);
    let inv_l = rsqrt_or_zero(l2, DEGENERATE_LENGTH2);
    let rest = c.rest - alpha_lambda;
    let stretch = fma(l2, inv_l, -rest);
    let along = dot(d, moved) * inv_l;
    let t = fma(c.gamma, along, stretch) / fma(c.one_gamma, w, c.alpha);
    return vec2<f32>(t * inv_l, t);
}
