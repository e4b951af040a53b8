//! The conformance suite: every law of [`crate::sim::laws`] on random inputs, in
//! every kind of lanes an engine runs it in, against the f64 reference.
//!
//! - The f64 instance of each law is first held to the textbook formula, written
//!   here with glam in the physics' own terms (`-(k (l - L) + b dv·u) u`, `-½ ρ
//!   C_d A (v·n) |v| n / 3`, `x' = 2x - x_prev + h² a`, `(l - goal) / (l w) d`,
//!   XPBD's `t n`, `r d / l`, ...), within `1e-12` of each output's scale (the
//!   largest term it sums).
//! - Lanes that round as the reference does (`Floats<f64, _>`, the portable
//!   kernel's float64 vectors without FMA) must give its numbers bit for bit.
//! - Float64 vector kernels (fused, the root's estimate refined) within `1e-13`
//!   of the scale; float32 lanes and kernels within `2e-6` of it (inputs rounded
//!   to float32, some 6e-8 each, then summed and cancelled).

use glam::DVec3;
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};

use super::Real;
use super::simd::{Portable, Simd, Vector};
use crate::sim::lanes::{Floats, Lanes, V3};
use crate::sim::laws::{self, Method, SpringCoefficients, XpbdCoefficients};

/// One random case's inputs, every law's at once.
#[derive(Clone, Copy, Debug)]
struct Case {
    d: DVec3,
    dv: DVec3,
    k: f64,
    rest: f64,
    b: f64,
    tri: [DVec3; 3],
    tri_v: [DVec3; 3],
    wind: DVec3,
    half_rho_cd: f64,
    f: f64,
    c: f64,
    v: f64,
    depth: f64,
    kc: f64,
    cg: f64,
    w: f64,
    g: f64,
    u: f64,
    a: f64,
    h: f64,
    x: f64,
    /// A length to restore a spring to (the stretch limit's `(1 + tau) L`, a bar's).
    goal: f64,
    /// XPBD: the first end's move since the start of the step less the second's,
    /// `α̃ λ` so far, `α̃` and `γ`.
    moved: DVec3,
    alpha_lambda: f64,
    alpha: f64,
    gamma: f64,
    radius: f64,
}

/// The laws' outputs, in the order of [`Case::textbook`].
const N_OUT: usize = 28;

const OUTPUTS: [&str; N_OUT] = [
    "spring x",
    "spring y",
    "spring z",
    "drag x",
    "drag y",
    "drag z",
    "air damped",
    "ground",
    "acceleration",
    "symplectic x'",
    "symplectic v'",
    "explicit x'",
    "explicit v'",
    "verlet x'",
    "verlet u'",
    "verlet v'",
    "advanced",
    "length correction x",
    "length correction y",
    "length correction z",
    "xpbd correction x",
    "xpbd correction y",
    "xpbd correction z",
    "xpbd t",
    "xpbd t from λ = 0",
    "sphere surface x",
    "sphere surface y",
    "sphere surface z",
];

impl Case {
    fn random(rng: &mut StdRng) -> Self {
        let mut vec = |r: f64| {
            DVec3::new(
                rng.random_range(-r..r),
                rng.random_range(-r..r),
                rng.random_range(-r..r),
            )
        };
        let (d, dv, wind) = (vec(1.0), vec(5.0), vec(10.0));
        let tri = [vec(1.0), vec(1.0), vec(1.0)];
        let tri_v = [vec(3.0), vec(3.0), vec(3.0)];
        let moved = vec(0.05);
        let mut c = Self {
            d,
            dv,
            k: rng.random_range(1.0..1e4),
            rest: rng.random_range(0.01..2.0),
            b: rng.random_range(0.0..10.0),
            tri,
            tri_v,
            wind,
            half_rho_cd: rng.random_range(0.0..1.0),
            f: rng.random_range(-10.0..10.0),
            c: rng.random_range(0.0..2.0),
            v: rng.random_range(-5.0..5.0),
            depth: rng.random_range(-0.1..0.1),
            kc: rng.random_range(0.0..1e4),
            cg: rng.random_range(0.0..10.0),
            w: rng.random_range(0.1..100.0),
            g: rng.random_range(-10.0..10.0),
            u: rng.random_range(-5.0..5.0),
            a: rng.random_range(-100.0..100.0),
            h: rng.random_range(1e-4..1e-2),
            x: rng.random_range(-2.0..2.0),
            goal: rng.random_range(0.01..2.0),
            moved,
            alpha_lambda: rng.random_range(-0.05..0.05),
            alpha: 0.0,
            gamma: 0.0,
            radius: rng.random_range(0.05..2.0),
        };
        // XPBD's `α̃ = 1 / (k h²)` and `γ = b / (k h)` of the case's spring.
        (c.alpha, c.gamma) = (1.0 / (c.k * c.h * c.h), c.b / (c.k * c.h));
        // The degenerate cases every engine meets: coincident spring ends (a
        // particle at the sphere's centre), a triangle with no area, a still
        // triangle in still air, a pinned particle (a spring pinned at both ends),
        // a spring at its goal or rest length, a spring that did not move.
        match rng.random_range(0..14) {
            0 => c.d = DVec3::ZERO,
            1 => c.tri[2] = c.tri[0] + 0.5 * (c.tri[1] - c.tri[0]),
            2 => (c.tri_v, c.wind) = ([DVec3::ZERO; 3], DVec3::ZERO),
            3 => c.w = 0.0,
            4 => (c.goal, c.rest) = (c.d.length(), c.d.length()),
            5 => (c.moved, c.alpha_lambda) = (DVec3::ZERO, 0.0),
            _ => {}
        }
        c
    }

    /// The textbook value of each output, and its scale.
    fn textbook(&self) -> [(f64, f64); N_OUT] {
        let l = self.d.length();
        // Restoring a length: `c = (l - goal) / (l w) d`, nothing where `l w` is
        // 0 (the engines leave those springs alone).
        let correction = if l > 0.0 && self.w > 0.0 {
            (l - self.goal) / (l * self.w) * self.d
        } else {
            DVec3::ZERO
        };
        let correction_scale = (l + self.goal) / self.w.max(1e-300);
        // XPBD: `t = (C + α̃ λ + γ n·Δ) / ((1 + γ) w + α̃)`, `c = t n`, with `n` 0
        // for coincident ends (which move nothing).
        let n = if l > 0.0 { self.d / l } else { DVec3::ZERO };
        let den = (1.0 + self.gamma) * self.w + self.alpha;
        let along = self.gamma * n.dot(self.moved);
        let xpbd_t = (l - self.rest + self.alpha_lambda + along) / den;
        let xpbd_t0 = (l - self.rest + along) / den;
        let xpbd_scale =
            (l + self.rest + self.alpha_lambda.abs() + self.gamma * self.moved.length()) / den;
        // The sphere: `r d / l`, straight up at the centre.
        let surface = if l > 0.0 {
            self.radius * self.d / l
        } else {
            self.radius * DVec3::Y
        };
        let spring = if l > 0.0 {
            let u = self.d / l;
            -(self.k * (l - self.rest) + self.b * self.dv.dot(u)) * u
        } else {
            DVec3::ZERO
        };
        let spring_scale = self.k * (l + self.rest) + self.b * self.dv.length();
        let [p, q, r] = self.tri;
        let cross = (q - p).cross(r - p);
        let v_rel = (self.tri_v[0] + self.tri_v[1] + self.tri_v[2]) / 3.0 - self.wind;
        let area = 0.5 * cross.length();
        let drag = if area > 0.0 && v_rel.length() > 0.0 {
            let n = cross / (2.0 * area);
            -self.half_rho_cd * area * v_rel.dot(n) * v_rel.length() * n / 3.0
        } else {
            DVec3::ZERO
        };
        let drag_scale =
            self.half_rho_cd * (q - p).length() * (r - p).length() * v_rel.length_squared()
                + 1e-300;
        let ground = if self.depth > 0.0 {
            self.kc * self.depth - self.cg * self.v
        } else {
            0.0
        };
        let accel = if self.w > 0.0 {
            self.f * self.w + self.g
        } else {
            0.0
        };
        let (h, u, a) = (self.h, self.u, self.a);
        // A pinned particle (w = 0) is left at rest, where it is.
        let free = self.w > 0.0;
        let v_new = if free { u + h * a } else { 0.0 };
        let x_prev = self.x - h * u;
        let verlet_x = if free {
            2.0 * self.x - x_prev + h * h * a
        } else {
            self.x
        };
        let speed = u.abs() + h * a.abs();
        let step_scale = self.x.abs() + h * speed;
        [
            (spring.x, spring_scale),
            (spring.y, spring_scale),
            (spring.z, spring_scale),
            (drag.x, drag_scale),
            (drag.y, drag_scale),
            (drag.z, drag_scale),
            (
                self.f - self.c * self.v,
                self.f.abs() + (self.c * self.v).abs(),
            ),
            (
                ground,
                self.kc * self.depth.abs() + (self.cg * self.v).abs(),
            ),
            (accel, (self.f * self.w).abs() + self.g.abs()),
            (self.x + h * v_new, step_scale),
            (v_new, speed),
            (self.x + h * u, step_scale),
            (v_new, speed),
            (verlet_x, step_scale),
            // (A difference of positions over `h`: good to their rounding over `h`.)
            ((verlet_x - self.x) / h, speed + self.x.abs() / h),
            (
                if free {
                    (verlet_x - self.x) / h + 0.5 * h * a
                } else {
                    0.0
                },
                speed + self.x.abs() / h,
            ),
            (self.x + h * self.v, self.x.abs() + h * self.v.abs()),
            (correction.x, correction_scale),
            (correction.y, correction_scale),
            (correction.z, correction_scale),
            (xpbd_t * n.x, xpbd_scale),
            (xpbd_t * n.y, xpbd_scale),
            (xpbd_t * n.z, xpbd_scale),
            (xpbd_t, xpbd_scale),
            (xpbd_t0, xpbd_scale),
            (surface.x, self.radius),
            (surface.y, self.radius),
            (surface.z, self.radius),
        ]
    }
}

/// Lanes filled from f64 values and read back as f64.
trait Probe: Lanes {
    fn width(self) -> usize;
    fn fill(self, xs: &[f64]) -> Self;
    fn read(self) -> Vec<f64>;
}

impl Probe for f64 {
    fn width(self) -> usize {
        1
    }
    fn fill(self, xs: &[f64]) -> Self {
        xs[0]
    }
    fn read(self) -> Vec<f64> {
        vec![self]
    }
}

impl<F: Real, const N: usize> Probe for Floats<F, N> {
    fn width(self) -> usize {
        N
    }
    fn fill(self, xs: &[f64]) -> Self {
        Floats(std::array::from_fn(|i| F::of(xs[i])))
    }
    fn read(self) -> Vec<f64> {
        self.0.iter().map(|x| x.f64()).collect()
    }
}

impl<S: Simd> Probe for Vector<S> {
    fn width(self) -> usize {
        S::LANES
    }
    fn fill(self, xs: &[f64]) -> Self {
        let e: Vec<S::E> = xs.iter().map(|&x| S::E::of(x)).collect();
        // SAFETY: `e` holds `LANES` floats.
        Vector(self.0, unsafe { self.0.load(e.as_ptr()) })
    }
    fn read(self) -> Vec<f64> {
        let mut e = vec![S::E::ZERO; S::LANES];
        // SAFETY: `e` holds `LANES` floats.
        unsafe { self.0.store(e.as_mut_ptr(), self.1) };
        e.iter().map(|x| x.f64()).collect()
    }
}

/// Every law's outputs for a block of cases, one per lane of `like`.
fn laws_in<L: Probe>(like: L, cases: &[Case]) -> Vec<[f64; N_OUT]> {
    let lane = |f: &dyn Fn(&Case) -> f64| like.fill(&cases.iter().map(f).collect::<Vec<_>>());
    let v3 = |f: &dyn Fn(&Case) -> DVec3| V3 {
        x: lane(&|c| f(c).x),
        y: lane(&|c| f(c).y),
        z: lane(&|c| f(c).z),
    };
    let coefficients = SpringCoefficients {
        neg_k: lane(&|c| -c.k),
        k_rest: lane(&|c| c.k * c.rest),
        neg_b: lane(&|c| -c.b),
    };
    let spring = laws::spring_force(v3(&|c| c.d), v3(&|c| c.dv), coefficients);
    let tri = [0, 1, 2].map(|i| v3(&|c| c.tri[i]));
    let tri_v = [0, 1, 2].map(|i| v3(&|c| c.tri_v[i]));
    let drag = laws::triangle_drag(tri, tri_v, v3(&|c| c.wind), lane(&|c| c.half_rho_cd));
    let (f, v, h, u, a, x) = (
        lane(&|c| c.f),
        lane(&|c| c.v),
        lane(&|c| c.h),
        lane(&|c| c.u),
        lane(&|c| c.a),
        lane(&|c| c.x),
    );
    let damped = laws::air_damped(f, lane(&|c| -c.c), v);
    let ground = laws::ground_support(lane(&|c| c.depth), v, lane(&|c| c.kc), lane(&|c| c.cg));
    let w = lane(&|c| c.w);
    let accel = laws::acceleration(f, w, lane(&|c| c.g));
    let half_h = h * h.splat(0.5);
    let step = |m| laws::update(m, u, a, w, h, half_h);
    let (sym, exp, ver) = (
        step(Method::SymplecticEuler),
        step(Method::ExplicitEuler),
        step(Method::Verlet),
    );
    let d = v3(&|c| c.d);
    // The length correction where an engine applies it (`l w > 0`), 0 elsewhere
    // as an engine's masks leave it.
    let applies = d.length() * w;
    let correction =
        d.scale(applies.keep_if_positive(laws::length_factor(d, lane(&|c| c.goal), w)));
    let xpbd = XpbdCoefficients {
        rest: lane(&|c| c.rest),
        alpha: lane(&|c| c.alpha),
        gamma: lane(&|c| c.gamma),
        one_gamma: lane(&|c| 1.0 + c.gamma),
    };
    let moved = v3(&|c| c.moved);
    let (xpbd_s, xpbd_t) = laws::xpbd_factor(d, moved, w, xpbd, Some(lane(&|c| c.alpha_lambda)));
    let (_, xpbd_t0) = laws::xpbd_factor(d, moved, w, xpbd, None);
    let xpbd_c = d.scale(xpbd_s);
    let surface = laws::surface_offset(d, d.dot(d), lane(&|c| c.radius));
    let outputs = [
        spring.x,
        spring.y,
        spring.z,
        drag.x,
        drag.y,
        drag.z,
        damped,
        ground,
        accel,
        laws::advanced(x, h, sym.moving),
        sym.v,
        laws::advanced(x, h, exp.moving),
        exp.v,
        laws::advanced(x, h, ver.moving),
        ver.u,
        ver.v,
        laws::advanced(x, h, v),
        correction.x,
        correction.y,
        correction.z,
        xpbd_c.x,
        xpbd_c.y,
        xpbd_c.z,
        xpbd_t,
        xpbd_t0,
        surface.x,
        surface.y,
        surface.z,
    ]
    .map(Probe::read);
    (0..cases.len())
        .map(|l| outputs.each_ref().map(|o| o[l]))
        .collect()
}

/// Runs every law in `like`'s lanes over `blocks` blocks of random cases and
/// compares each lane with the f64 reference: bit for bit when `exact`, else
/// within `tol` of the output's scale. Returns the largest error found, in
/// scales.
fn conforms<L: Probe>(like: L, name: &str, exact: bool, tol: f64) -> f64 {
    let mut rng = StdRng::seed_from_u64(54);
    let n = like.width();
    let mut worst: f64 = 0.0;
    for _ in 0..4000 / n + 1 {
        let cases: Vec<Case> = (0..n).map(|_| Case::random(&mut rng)).collect();
        let got = laws_in(like, &cases);
        for (case, got) in cases.iter().zip(&got) {
            let reference = laws_in(0.0_f64, std::slice::from_ref(case))[0];
            let textbook = case.textbook();
            for (o, name_o) in OUTPUTS.iter().enumerate() {
                let (want, scale) = textbook[o];
                let own = (reference[o] - want).abs() / scale.max(1e-300);
                assert!(
                    own <= 1e-12,
                    "f64 {name_o}: {} against the textbook {want}, case {case:?}",
                    reference[o]
                );
                if exact {
                    assert_eq!(
                        got[o].to_bits(),
                        reference[o].to_bits(),
                        "{name} {name_o}: case {case:?}"
                    );
                } else {
                    let err = (got[o] - reference[o]).abs() / scale.max(1e-300);
                    worst = worst.max(err);
                    assert!(
                        err <= tol,
                        "{name} {name_o}: {} against {} (scale {scale}), case {case:?}",
                        got[o],
                        reference[o]
                    );
                }
            }
        }
    }
    worst
}

#[test]
fn every_law_agrees_with_the_f64_reference_on_every_lane_width() {
    conforms(Floats::<f64, 4>::of(0.0), "float64 lanes", true, 0.0);
    conforms(Floats::<f32, 8>::of(0.0), "float32 lanes", false, 2e-6);
    let portable32 = Vector(Portable::<f32>::default(), [0.0f32; 8]);
    conforms(portable32, "portable float32 kernel", false, 2e-6);
    let portable64 = Vector(Portable::<f64>::default(), [0.0f64; 8]);
    conforms(portable64, "portable float64 kernel", false, 1e-13);
    #[cfg(target_arch = "x86_64")]
    {
        let (avx2, avx512) = super::x86::tokens();
        if let Some((f32s, f64s)) = avx2 {
            kernel_conforms(f32s, "AVX2");
            kernel_conforms(f64s, "AVX2");
        }
        if let Some((f32s, f64s)) = avx512 {
            kernel_conforms(f32s, "AVX-512");
            kernel_conforms(f64s, "AVX-512");
        }
    }
}

/// [`conforms`] for a vector kernel's lanes, within its precision's tolerance.
#[cfg(target_arch = "x86_64")]
fn kernel_conforms<S: Simd>(s: S, level: &str) {
    let (bits, tol) = match std::mem::size_of::<S::E>() {
        4 => (32, 2e-6),
        _ => (64, 1e-13),
    };
    let name = format!("{level} float{bits} kernel");
    conforms(Vector(s, s.splat(S::E::ZERO)), &name, false, tol);
}
