// The constraint passes of the GPU engine, between `step_particles` and the end
// of the step, in the f64 engine's order (`sim::constraints::apply`): XPBD's
// springs, then the stretch limit, each a Gauss-Seidel sweep over the springs in
// the model's constraint order. That order is cut into runs in which no two
// springs share a particle (a grid's colour classes); one dispatch corrects a
// run, a thread a spring, so the sweep is the f64 engine's, with no atomics and
// no shared writes. Then `end_step`: the velocity of the constraints' moves, the
// contacts and the speed limit. Appended to `laws.wgsl` and `step.wgsl`.

// The run a dispatch corrects: `count` springs from `start` in `springs`, and
// for XPBD which sweep it is (FORWARD, FORWARD_KEPT or BACK).
struct Run {
    start: u32,
    count: u32,
    sweep: u32,
    _pad: u32,
}

// A sweep that keeps no multiplier (λ = 0 from the start; no sweep back follows).
const FORWARD: u32 = 0u;
// The forward sweep of a model swept back too: each spring's λ is kept.
const FORWARD_KEPT: u32 = 1u;
// The sweep back, from the multipliers the forward sweep kept.
const BACK: u32 = 2u;

// A spring in the constraint order: its ends, rest length L (m), stiffness k
// (N/m) and damping b (N s/m).
struct ConstraintSpring {
    a: u32,
    b: u32,
    rest: f32,
    stiffness: f32,
    damping: f32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
}

@group(2) @binding(0) var<uniform> run: Run;
@group(2) @binding(2) var<storage, read> springs: array<ConstraintSpring>;
// XPBD's multiplier λ of each spring (by its place in `springs`) from the forward
// sweep to the sweep back.
@group(2) @binding(3) var<storage, read_write> multipliers: array<f32>;

// Particle i moved by dx (its velocity is `end_step`'s).
fn move_particle(i: u32, p: Particle, dx: vec3<f32>) {
    let x = moved(Position(p.x.xyz, p.low.xyz), dx);
    state_out[i] = Particle(vec4<f32>(x.hi, p.x.w), p.v, vec4<f32>(x.lo, 0.0));
}

// A spring of the run as a pass reads it: the spring, its ends now, the ends'
// inverse masses summed, and its vector d = x_a - x_b.
struct Ends {
    s: ConstraintSpring,
    a: Particle,
    b: Particle,
    w: f32,
    d: vec3<f32>,
}

fn ends_of(place: u32) -> Ends {
    let s = springs[place];
    let a = state_out[s.a];
    let b = state_out[s.b];
    return Ends(s, a, b, a.x.w + b.x.w, offset(a, b));
}

// The spring's ends moved by the correction c: x_a -= w_a c, x_b += w_b c.
fn correct(e: Ends, c: vec3<f32>) {
    move_particle(e.s.a, e.a, -e.a.x.w * c);
    move_particle(e.s.b, e.b, e.b.x.w * c);
}

// `constraints::xpbd_pass` on one spring of the run (`laws::xpbd_correction`):
// positions now are `state_out`, at the step's start `state_in`.
@compute @workgroup_size(64)
fn xpbd_run(@builtin(global_invocation_id) id: vec3<u32>) {
    let k = id.x + id.y * ROW;
    if k >= run.count {
        return;
    }
    let place = run.start + k;
    let e = ends_of(place);
    let s = e.s;
    // `XpbdSpring::new`: k <= 0 constrains nothing.
    if !(s.stiffness > 0.0) || e.w == 0.0 || dot(e.d, e.d) <= DEGENERATE_LENGTH2 {
        return;
    }
    let change = offset(e.a, state_in[s.a]) - offset(e.b, state_in[s.b]);
    let ag = xpbd_coefficients(s.stiffness, s.damping, step.gravity.w);
    let c = XpbdCoefficients(s.rest, ag.x, ag.y, 1.0 + ag.y);
    var alpha_lambda = 0.0;
    if run.sweep == BACK {
        alpha_lambda = ag.x * multipliers[place];
    }
    let st = xpbd_factor(e.d, change, e.w, c, alpha_lambda);
    correct(e, e.d * st.x);
    if run.sweep == FORWARD_KEPT {
        multipliers[place] = -st.y;
    }
}

// `constraints::apply`'s stretch limit on one spring of the run
// (`laws::length_correction`): no spring longer than (1 + τ) L.
@compute @workgroup_size(64)
fn stretch_limit_run(@builtin(global_invocation_id) id: vec3<u32>) {
    let k = id.x + id.y * ROW;
    if k >= run.count {
        return;
    }
    let e = ends_of(run.start + k);
    let l = length(e.d);
    let longest = (1.0 + step.limits.z) * e.s.rest;
    if e.w == 0.0 || l <= EPSILON_LENGTH || !(l > longest) {
        return;
    }
    correct(e, e.d * length_factor(e.d, longest, e.w));
}

// The end of a constrained step (`constraints::apply`): v += (x - before) / h (and
// Verlet's update velocity likewise), then `end_of_step`.
@compute @workgroup_size(64)
fn end_step(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x + id.y * ROW;
    if i >= step.flags.y {
        return;
    }
    let me = state_out[i];
    let w = me.x.w;
    let dx = (me.x.xyz - before[2u * i].xyz) + (me.low.xyz - before[2u * i + 1u].xyz);
    let dv = dx / step.gravity.w;
    var u = vec3<f32>(0.0);
    if step.flags.x == VERLET {
        u = u_out[i].xyz + dv;
    }
    store_particle(i, end_of_step(Position(me.x.xyz, me.low.xyz), me.v.xyz + dv, u, w), w);
}
