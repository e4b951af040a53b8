//! The conformance suite: every law of `shaders/gpu/laws.wgsl`, run on the GPU
//! through `shaders/gpu/probe.wgsl` over random cases, against its Rust law in
//! f64 (`sim::laws`) on the same inputs (rounded to f32 first, so that only the
//! arithmetic differs). Each law's tolerance is a stated multiple of f32's
//! epsilon times the size of the terms it adds, so a law that computes
//! something else, or loses precision to cancellation it should not have,
//! fails.
//!
//! Without an adapter the tests print a note and pass, unless
//! `CLOTH_REQUIRE_ADAPTER` is set (CI sets it).

use glam::DVec3;
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};
use wgpu::util::DeviceExt as _;

use crate::sim::laws::{self, Contact, Method, SpringCoefficients, V3};
use crate::sim::{Ground, Sphere};

/// Six vec4 of inputs, as the probe's `Case`.
type Case = [[f32; 4]; 6];
/// Three vec4 of results.
type Results = [[f32; 4]; 3];

const CASES: usize = 4096;

/// The probe pipeline on the machine's adapter.
struct Probe {
    device: wgpu::Device,
    queue: wgpu::Queue,
    pipeline: wgpu::ComputePipeline,
}

impl Probe {
    fn open() -> Option<Self> {
        let (_, device, queue) = match super::device::open() {
            Ok(opened) => opened,
            Err(e) if std::env::var_os("CLOTH_REQUIRE_ADAPTER").is_none() => {
                eprintln!("note: skipping the GPU conformance suite: {e}");
                return None;
            }
            Err(e) => panic!("no adapter for the conformance suite: {e}"),
        };
        let source = concat!(
            include_str!("../../shaders/gpu/laws.wgsl"),
            include_str!("../../shaders/gpu/probe.wgsl")
        );
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("probe.wgsl"),
            source: wgpu::ShaderSource::Wgsl(source.into()),
        });
        let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some("conformance probe"),
            layout: None,
            module: &module,
            entry_point: Some("probe"),
            compilation_options: Default::default(),
            cache: None,
        });
        Some(Self {
            device,
            queue,
            pipeline,
        })
    }

    /// Law number `law` of the probe on each case.
    fn run(&self, law: u32, cases: &[Case]) -> Vec<Results> {
        let buffer = |label, contents: &[u8], usage| {
            (self.device).create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents,
                usage,
            })
        };
        let law = buffer(
            "law",
            bytemuck::cast_slice(&[law, 0, 0, 0]),
            wgpu::BufferUsages::UNIFORM,
        );
        let inputs = buffer(
            "cases",
            bytemuck::cast_slice(cases),
            wgpu::BufferUsages::STORAGE,
        );
        let size = (cases.len() * std::mem::size_of::<Results>()) as u64;
        let results = self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("results"),
            size,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let readback = self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("readback"),
            size,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let bind = self.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("probe"),
            layout: &self.pipeline.get_bind_group_layout(0),
            entries: &[entry(0, &law), entry(1, &inputs), entry(2, &results)],
        });
        let mut encoder = self.device.create_command_encoder(&Default::default());
        {
            let mut pass = encoder.begin_compute_pass(&Default::default());
            pass.set_pipeline(&self.pipeline);
            pass.set_bind_group(0, &bind, &[]);
            pass.dispatch_workgroups(cases.len().div_ceil(64) as u32, 1, 1);
        }
        encoder.copy_buffer_to_buffer(&results, 0, &readback, 0, size);
        self.queue.submit([encoder.finish()]);
        let slice = readback.slice(..);
        slice.map_async(wgpu::MapMode::Read, |r| r.expect("mapped"));
        (self.device)
            .poll(wgpu::PollType::wait_indefinitely())
            .expect("the probe ran");
        let mapped = slice.get_mapped_range().expect("mapped");
        bytemuck::pod_collect_to_vec(&mapped[..])
    }
}

fn entry(binding: u32, buffer: &wgpu::Buffer) -> wgpu::BindGroupEntry<'_> {
    wgpu::BindGroupEntry {
        binding,
        resource: buffer.as_entire_binding(),
    }
}

/// A law's f64 results on a case: the components to compare (at most 12, the
/// three vec4 in order) and the size each is measured against.
struct Expected {
    values: Vec<(usize, f64)>,
    scale: f64,
}

/// Runs law `law` on `cases` and checks every compared component within
/// `ulps` f32 epsilons of each case's scale; returns the worst ratio seen.
fn conform(
    probe: &Probe,
    name: &str,
    law: u32,
    ulps: f64,
    cases: &[Case],
    expected: impl Fn(&Case) -> Expected,
) -> f64 {
    let got = probe.run(law, cases);
    let eps = f64::from(f32::EPSILON);
    let mut worst: f64 = 0.0;
    for (case, got) in cases.iter().zip(&got) {
        let want = expected(case);
        let flat: Vec<f64> = got.iter().flatten().map(|&x| f64::from(x)).collect();
        for &(at, value) in &want.values {
            let error = (flat[at] - value).abs();
            let allowed = ulps * eps * want.scale + f64::from(f32::MIN_POSITIVE);
            worst = worst.max(error / allowed * ulps);
            assert!(
                error <= allowed,
                "{name}: component {at} is {} on the GPU, {value} in f64 (error {error:e}, \
                 allowed {allowed:e} = {ulps} eps x {:e}) for {case:?}",
                flat[at],
                want.scale
            );
        }
    }
    eprintln!(
        "{name}: {} cases, worst {worst:.2} eps of the scale (allowed {ulps})",
        cases.len()
    );
    worst
}

fn vec3(rng: &mut StdRng, scale: f32) -> [f32; 3] {
    [0; 3].map(|_| rng.random_range(-scale..=scale))
}

/// An offset within 1 m on each axis, or, one time in fifty, none (the laws'
/// degenerate case: no direction).
fn offset_or_zero(rng: &mut StdRng) -> [f32; 3] {
    if rng.random_bool(0.02) {
        [0.0; 3]
    } else {
        vec3(rng, 1.0)
    }
}

fn cases(seed: u64, make: impl Fn(&mut StdRng) -> Case) -> Vec<Case> {
    let mut rng = StdRng::seed_from_u64(seed);
    (0..CASES).map(|_| make(&mut rng)).collect()
}

fn d3(v: [f32; 4]) -> DVec3 {
    DVec3::new(v[0].into(), v[1].into(), v[2].into())
}

fn v4(v: [f32; 3], w: f32) -> [f32; 4] {
    [v[0], v[1], v[2], w]
}

/// A law of one axis applied to each of x, y and z.
fn per_axis(law: impl Fn(usize) -> f64) -> DVec3 {
    DVec3::new(law(0), law(1), law(2))
}

/// The three components of a vec3 result in vec4 number `slot`.
fn at(slot: usize, v: DVec3) -> [(usize, f64); 3] {
    [(4 * slot, v.x), (4 * slot + 1, v.y), (4 * slot + 2, v.z)]
}

/// The forces: the damped spring, aero drag, air damping, the ground's
/// penalty and the acceleration.
#[test]
fn the_wgsl_forces_agree_with_the_f64_laws() {
    let Some(probe) = Probe::open() else {
        return;
    };
    let f = f64::from;
    let spring = cases(1, |r| {
        let d = offset_or_zero(r);
        let length = d.iter().map(|x| x * x).sum::<f32>().sqrt();
        let (k, rest, b) = (
            r.random_range(1.0..1e4),
            r.random_range(0.5..1.5) * length,
            r.random_range(0.0..10.0),
        );
        [
            v4(d, 0.0),
            v4(vec3(r, 5.0), 0.0),
            [-k, k * rest, -b, 0.0],
            [0.0; 4],
            [0.0; 4],
            [0.0; 4],
        ]
    });
    conform(&probe, "spring_force", 0, 4.0, &spring, |c| {
        let coefficients = SpringCoefficients {
            neg_k: f(c[2][0]),
            k_rest: f(c[2][1]),
            neg_b: f(c[2][2]),
        };
        let (d, dv) = (d3(c[0]), d3(c[1]));
        let force = laws::spring_force(V3::from(d), V3::from(dv), coefficients);
        let scale = -coefficients.neg_k * d.length() + coefficients.k_rest
            - coefficients.neg_b * dv.length();
        Expected {
            values: at(0, force.into()).to_vec(),
            scale,
        }
    });
    let drag = cases(2, |r| {
        let wind = vec3(r, 5.0);
        let half = r.random_range(0.1..1.0);
        let (x, v) = ([0; 3].map(|_| vec3(r, 1.0)), [0; 3].map(|_| vec3(r, 3.0)));
        [
            v4(x[0], wind[0]),
            v4(x[1], wind[1]),
            v4(x[2], wind[2]),
            v4(v[0], half),
            v4(v[1], 0.0),
            v4(v[2], 0.0),
        ]
    });
    conform(&probe, "triangle_drag", 1, 4.0, &drag, |c| {
        let x = [0, 1, 2].map(|i| V3::from(d3(c[i])));
        let v = [3, 4, 5].map(|i| V3::from(d3(c[i])));
        let wind = DVec3::new(f(c[0][3]), f(c[1][3]), f(c[2][3]));
        let force: DVec3 = laws::triangle_drag(x, v, V3::from(wind), f(c[3][3])).into();
        let m = (d3(c[1]) - d3(c[0])).cross(d3(c[2]) - d3(c[0]));
        let speed = v.iter().map(|v| DVec3::from(*v).length()).sum::<f64>() + wind.length();
        Expected {
            values: at(0, force).to_vec(),
            scale: f(c[3][3]) * m.length() * speed * speed,
        }
    });
    let damped = cases(3, |r| {
        [
            v4(vec3(r, 1.0), 0.0),
            [-r.random_range(0.0..1.0), 0.0, 0.0, 0.0],
            v4(vec3(r, 5.0), 0.0),
            [0.0; 4],
            [0.0; 4],
            [0.0; 4],
        ]
    });
    conform(&probe, "air_damped", 2, 4.0, &damped, |c| {
        let (force, neg_c, v) = (d3(c[0]), f(c[1][0]), d3(c[2]));
        let damped = per_axis(|i| laws::air_damped(force[i], neg_c, v[i]));
        Expected {
            values: at(0, damped).to_vec(),
            scale: force.length() - neg_c * v.length(),
        }
    });
    let support = cases(4, |r| {
        let a = [
            r.random_range(-0.1..0.1),
            r.random_range(-3.0..3.0),
            r.random_range(1e2..1e5),
            r.random_range(0.0..10.0),
        ];
        [a, [0.0; 4], [0.0; 4], [0.0; 4], [0.0; 4], [0.0; 4]]
    });
    conform(&probe, "ground_support", 3, 4.0, &support, |c| {
        let [depth, vy, k_c, c_g] = c[0].map(f);
        let value = laws::ground_support(depth, vy, k_c, c_g);
        Expected {
            values: vec![(0, value)],
            scale: k_c * depth.abs() + c_g * vy.abs(),
        }
    });
    let acceleration = cases(5, |r| {
        let w = if r.random_bool(0.1) {
            0.0
        } else {
            r.random_range(1.0..1e3)
        };
        [
            v4(vec3(r, 1.0), 0.0),
            [w, 0.0, 0.0, 0.0],
            v4(vec3(r, 10.0), 0.0),
            [0.0; 4],
            [0.0; 4],
            [0.0; 4],
        ]
    });
    conform(&probe, "acceleration", 4, 4.0, &acceleration, |c| {
        let (force, w, g) = (d3(c[0]), f(c[1][0]), d3(c[2]));
        let a = per_axis(|i| laws::acceleration(force[i], w, g[i]));
        Expected {
            values: at(0, a).to_vec(),
            scale: force.length() * w + g.length(),
        }
    });
}

/// Symplectic Euler, explicit Euler and Verlet, pinned particles among them.
#[test]
fn the_wgsl_update_rules_agree_with_the_f64_laws() {
    let Some(probe) = Probe::open() else {
        return;
    };
    let f = f64::from;
    let update = cases(6, |r| {
        let w = if r.random_bool(0.1) {
            0.0
        } else {
            r.random_range(1.0..1e3)
        };
        let h: f32 = r.random_range(1e-5..1e-2);
        let method = r.random_range(0..3u32) as f32;
        [
            v4(vec3(r, 2.0), 0.0),
            [w, h, h * 0.5, method],
            v4(vec3(r, 20.0), 0.0),
            [0.0; 4],
            [0.0; 4],
            [0.0; 4],
        ]
    });
    conform(&probe, "update", 5, 4.0, &update, |c| {
        let (u, a) = (d3(c[0]), d3(c[2]));
        let [w, h, half_h, method] = c[1].map(f);
        let method = [
            Method::SymplecticEuler,
            Method::ExplicitEuler,
            Method::Verlet,
        ][method as usize];
        let [x, y, z] = [0, 1, 2].map(|i| laws::update(method, u[i], a[i], w, h, half_h));
        let mut values = at(0, DVec3::new(x.moving, y.moving, z.moving)).to_vec();
        values.extend(at(1, DVec3::new(x.u, y.u, z.u)));
        values.extend(at(2, DVec3::new(x.v, y.v, z.v)));
        Expected {
            values,
            scale: u.length() + h * a.length(),
        }
    });
}

/// The sphere's surface point and contact with friction, the ground's
/// friction and the speed limit.
#[test]
fn the_wgsl_contact_and_speed_limit_agree_with_the_f64_laws() {
    let Some(probe) = Probe::open() else {
        return;
    };
    let f = f64::from;
    let offset = cases(7, |r| {
        let d = offset_or_zero(r);
        [
            v4(d, 0.0),
            [r.random_range(0.1..2.0), 0.0, 0.0, 0.0],
            [0.0; 4],
            [0.0; 4],
            [0.0; 4],
            [0.0; 4],
        ]
    });
    conform(&probe, "surface_offset", 6, 4.0, &offset, |c| {
        let (d, radius) = (d3(c[0]), f(c[1][0]));
        let offset = laws::surface_offset(V3::from(d), d.length_squared(), radius);
        Expected {
            values: at(0, offset.into()).to_vec(),
            scale: radius,
        }
    });
    let sphere = cases(8, |r| {
        let radius: f32 = r.random_range(0.2..2.0);
        let direction = glam::Vec3::from(vec3(r, 1.0))
            .try_normalize()
            .unwrap_or(glam::Vec3::Y);
        let d = direction * radius * r.random_range(0.5..1.5);
        let (friction, h) = (r.random_range(0.0..1.0), r.random_range(1e-4..1e-2));
        [
            v4(d.to_array(), 0.0),
            v4(vec3(r, 3.0), 0.0),
            [radius, friction, h, 0.0],
            [0.0; 4],
            [0.0; 4],
            [0.0; 4],
        ]
    });
    conform(&probe, "contact_sphere", 7, 8.0, &sphere, |c| {
        let (d, v, [radius, friction, h, _]) = (d3(c[0]), d3(c[1]), c[2].map(f));
        let sphere = Some(Sphere {
            center: DVec3::ZERO,
            radius,
        });
        let contact = Contact {
            sphere,
            ground: None,
            friction,
            dt: h,
        };
        let (x, v_new) = contact.resolve(d, v, 1.0);
        let mut values = at(0, x - d).to_vec();
        values.extend(at(1, v_new));
        Expected {
            values,
            scale: radius / h + v.length(),
        }
    });
    let ground = cases(9, |r| {
        let a = [
            r.random_range(-0.05..0.05),
            r.random_range(1.0..1e3),
            r.random_range(1e-4..1e-2),
            0.0,
        ];
        let g = [
            0.0,
            r.random_range(1e2..1e4),
            r.random_range(0.0..5.0),
            r.random_range(0.0..1.0),
        ];
        [a, v4(vec3(r, 3.0), 0.0), g, [0.0; 4], [0.0; 4], [0.0; 4]]
    });
    conform(&probe, "contact_ground_friction", 8, 4.0, &ground, |c| {
        let ([above, w, h, _], v, [_, stiffness, damping, friction]) =
            (c[0].map(f), d3(c[1]), c[2].map(f));
        let ground = Some(Ground {
            height: 0.0,
            stiffness,
            damping,
            friction,
        });
        let contact = Contact {
            sphere: None,
            ground,
            friction: 0.0,
            dt: h,
        };
        let (_, v_new) = contact.resolve(DVec3::new(0.0, above, 0.0), v, w);
        let most = friction * h * w * (stiffness * above.abs() + damping * v.y.abs());
        Expected {
            values: at(0, v_new).to_vec(),
            scale: v.length() + most,
        }
    });
    let limit = cases(10, |r| {
        [
            v4(vec3(r, 10.0), 0.0),
            [r.random_range(0.1..20.0), 0.0, 0.0, 0.0],
            [0.0; 4],
            [0.0; 4],
            [0.0; 4],
            [0.0; 4],
        ]
    });
    conform(&probe, "speed_limit", 9, 4.0, &limit, |c| {
        let factor = laws::speed_limit(d3(c[0]), f(c[1][0]));
        Expected {
            values: vec![(0, factor)],
            scale: 1.0,
        }
    });
}

/// The constraints' laws: the factor that brings a spring to a length (the
/// stretch limit's), and XPBD's correction and coefficients.
#[test]
fn the_wgsl_constraint_laws_agree_with_the_f64_laws() {
    let Some(probe) = Probe::open() else {
        return;
    };
    let f = f64::from;
    let length = cases(11, |r| {
        let d = glam::Vec3::from(vec3(r, 1.0));
        let d = d.normalize_or(glam::Vec3::X) * r.random_range(0.01..1.0);
        let goal = d.length() * r.random_range(0.5..1.5);
        [
            v4(d.to_array(), 0.0),
            [goal, r.random_range(1.0..1e3), 0.0, 0.0],
            [0.0; 4],
            [0.0; 4],
            [0.0; 4],
            [0.0; 4],
        ]
    });
    conform(&probe, "length_factor", 10, 4.0, &length, |c| {
        let (d, [goal, w, _, _]) = (d3(c[0]), c[1].map(f));
        let l = d.length();
        Expected {
            values: vec![(0, laws::length_factor(V3::from(d), goal, w))],
            scale: (l + goal) / (l * w),
        }
    });
    // A spring (k, b) at a step h, as the engines meet them.
    let spring = |r: &mut StdRng| -> [f32; 3] {
        [
            r.random_range(1e2..1e7),
            r.random_range(0.0..10.0),
            r.random_range(1e-4..1e-2),
        ]
    };
    let factor = cases(12, |r| {
        let d = offset_or_zero(r);
        let l = d.iter().map(|x| x * x).sum::<f32>().sqrt();
        let [k, b, h] = spring(r);
        let (alpha, gamma) = (1.0 / (k * h * h), b / (k * h));
        let alpha_lambda = if r.random_bool(0.5) {
            0.0
        } else {
            r.random_range(-0.1..0.1) * l
        };
        [
            v4(d, 0.0),
            [
                r.random_range(1.0..1e3),
                l * r.random_range(0.5..1.5),
                alpha_lambda,
                0.0,
            ],
            [alpha, gamma, 1.0 + gamma, 0.0],
            v4(vec3(r, 0.01), 0.0),
            [0.0; 4],
            [0.0; 4],
        ]
    });
    let xpbd = |c: &Case| {
        let (d, moved) = (d3(c[0]), d3(c[3]));
        let [w, rest, alpha_lambda, _] = c[1].map(f);
        let [alpha, gamma, one_gamma, _] = c[2].map(f);
        let coefficients = laws::XpbdCoefficients {
            rest,
            alpha,
            gamma,
            one_gamma,
        };
        let (s, t) = laws::xpbd_factor(
            V3::from(d),
            V3::from(moved),
            w,
            coefficients,
            Some(alpha_lambda),
        );
        // The terms of t's numerator over its denominator.
        let l = d.length();
        let along = (d.dot(moved) / l.max(1e-12)).abs();
        let t_scale =
            (l + rest.abs() + alpha_lambda.abs() + gamma * along) / (one_gamma * w + alpha);
        (s, t, t_scale, l)
    };
    conform(&probe, "xpbd_factor (t)", 11, 4.0, &factor, |c| {
        let (_, t, scale, _) = xpbd(c);
        Expected {
            values: vec![(1, t)],
            scale,
        }
    });
    conform(&probe, "xpbd_factor (s)", 11, 4.0, &factor, |c| {
        let (s, _, scale, l) = xpbd(c);
        // Coincident ends: s is 0, whatever t.
        let scale = if l > 1e-12 { scale / l } else { 1.0 };
        Expected {
            values: vec![(0, s)],
            scale,
        }
    });
    let coefficients = cases(13, |r| {
        let [k, b, h] = spring(r);
        [
            [k, b, h, 0.0],
            [0.0; 4],
            [0.0; 4],
            [0.0; 4],
            [0.0; 4],
            [0.0; 4],
        ]
    });
    for (slot, name) in [
        (0, "xpbd_coefficients (alpha)"),
        (1, "xpbd_coefficients (gamma)"),
    ] {
        conform(&probe, name, 12, 4.0, &coefficients, |c| {
            let [k, b, h, _] = c[0].map(f);
            let spring = laws::XpbdSpring::new(1.0, k, b, h).expect("k > 0");
            let value = [spring.alpha, spring.gamma][slot];
            Expected {
                values: vec![(slot, value)],
                scale: value,
            }
        });
    }
}
