//! The accuracy and stability study behind `cloth report`: work-precision (position
//! error against run time per integrator), observed orders of convergence, measured
//! critical steps against theory, and extreme settings. Writes CSV files of every
//! measurement, SVG plots and a `REPORT.md` into a folder.

pub mod analytic;
pub mod eigen;
pub mod extreme;
pub mod plot;
pub mod precision;
pub mod stability;
pub mod stiff;

mod write;

use std::path::{Path, PathBuf};
use std::time::Instant;

use crate::scene::{Resolved, Scene};
use crate::sim::Integrator;
use crate::sim::safe::DEFAULT_SAFETY;

use analytic::HangingSpring;
use precision::{OrderFit, Point, Problem, Reference};

/// Options of `cloth report`.
#[derive(Clone, Debug)]
pub struct Options {
    /// Output folder (created if missing).
    pub out: PathBuf,
    /// Smaller problems and fewer steps: a smoke run for CI (under 2 minutes on 2 cores).
    pub quick: bool,
    /// Timed runs per point (the median is reported); at least 5.
    pub repeats: usize,
}

impl Default for Options {
    fn default() -> Self {
        Self {
            out: PathBuf::from("report"),
            quick: false,
            repeats: 5,
        }
    }
}

/// Everything the study measured.
#[derive(Clone, Debug)]
pub struct Report {
    /// Whether this was a quick run.
    pub quick: bool,
    /// The problems, with their references.
    pub problems: Vec<Problem>,
    /// Work-precision points.
    pub points: Vec<Point>,
    /// Observed orders.
    pub orders: Vec<OrderFit>,
    /// Critical steps, undamped cases.
    pub stability: Vec<stability::Row>,
    /// Critical steps of symplectic Euler with spring damping.
    pub damped: Vec<stability::Row>,
    /// Extreme cases.
    pub extreme: Vec<extreme::Result>,
    /// The stiff-cloth study.
    pub stiff: Vec<stiff::Row>,
    /// Wall time of each part, s.
    pub timings: Vec<(String, f64)>,
}

fn scene(name: &str, overrides: &[String]) -> Result<Resolved, String> {
    let mut scene = Scene::load(name).map_err(|e| e.to_string())?;
    scene
        .set_all(overrides.iter().map(String::as_str))
        .map_err(|e| e.to_string())?;
    scene.resolve().map_err(|e| e.to_string())
}

fn sets(items: &[&str]) -> Vec<String> {
    items.iter().map(|s| s.to_string()).collect()
}

/// `base / 2^j` for `j` in `range`.
fn halvings(base: f64, range: std::ops::RangeInclusive<i32>) -> Vec<f64> {
    range.map(|j| base * 0.5f64.powi(j)).collect()
}

/// The hanging spring of the `spring` scene, from its resolved parameters.
pub fn hanging_spring(scene: &Resolved) -> HangingSpring {
    let system = scene.build();
    let x = system.positions();
    HangingSpring {
        anchor_y: x[0].y,
        rest: scene.rest_length,
        stiffness: scene.stiffness,
        damping: scene.damping,
        mass: scene.particle_mass,
        gravity: -scene.params.gravity.y,
        initial_length: (x[0] - x[1]).length(),
    }
}

/// The three work-precision problems (the references of chain and cloth computed here).
pub fn problems(quick: bool, progress: &mut dyn FnMut(&str)) -> Result<Vec<Problem>, String> {
    let spring_scene = scene("spring", &[])?;
    let spring = hanging_spring(&spring_scene);
    let spring_end = 4.0;
    let mut problems = vec![Problem {
        name: "spring".into(),
        description: format!(
            "built-in `spring` scene (k = {} N/m, m = {} kg, 10% of critical damping, gravity), \
             0 to {spring_end} s, against the exact damped-oscillator solution",
            spring_scene.stiffness, spring_scene.particle_mass
        ),
        end_time: spring_end,
        dts: halvings(spring_end, 5..=13),
        scale: spring.oscillator().u0.abs(),
        scene: spring_scene,
        reference: Reference::Analytic(spring),
    }];

    let chain_scene = scene("chain", &[])?;
    let (chain_end, chain_dts, chain_ref) = if quick {
        (1.0, halvings(1.0, 5..=12), 1.0 * 0.5f64.powi(18))
    } else {
        (2.0, halvings(2.0, 6..=13), 2.0 * 0.5f64.powi(19))
    };
    progress(&format!("chain: RK4 reference at dt = {chain_ref:.3e} s"));
    let reference = precision::rk4_reference(&chain_scene, chain_end, chain_ref)?;
    let (_, radius) = crate::sim::bounding_sphere(chain_scene.build().positions());
    problems.push(Problem {
        name: "chain".into(),
        description: format!(
            "built-in `chain` scene (11 masses, k = 100 N/m, 25% of critical, air damping), \
             falling from horizontal, 0 to {chain_end} s, against RK4 at dt = {chain_ref:.3e} s"
        ),
        end_time: chain_end,
        dts: chain_dts,
        scale: 2.0 * radius,
        scene: chain_scene,
        reference: Reference::Numerical(reference),
    });

    let side = if quick { 12 } else { 32 };
    let cloth_scene = scene(
        "cloth",
        &[format!("width={side}"), format!("height={side}")],
    )?;
    let (cloth_end, cloth_ref) = if quick {
        (0.5f64.powi(5), 0.5f64.powi(23))
    } else {
        (0.5f64.powi(4), 0.5f64.powi(23))
    };
    progress(&format!(
        "cloth {side}x{side}: RK4 reference at dt = {cloth_ref:.3e} s (and twice that, for Richardson)"
    ));
    let reference = precision::rk4_reference(&cloth_scene, cloth_end, cloth_ref)?;
    let (_, radius) = crate::sim::bounding_sphere(cloth_scene.build().positions());
    problems.push(Problem {
        name: "cloth".into(),
        description: format!(
            "built-in `cloth` scene at {side}x{side} (k = 100 N/m, b = 0.02 N·s/m, gusty wind, aero drag), \
             hanging from its top corners, 0 to {cloth_end} s, against RK4 at dt = {cloth_ref:.3e} s"
        ),
        end_time: cloth_end,
        dts: halvings(1.0, 10..=17),
        scale: 2.0 * radius,
        scene: cloth_scene,
        reference: Reference::Numerical(reference),
    });
    Ok(problems)
}

/// Runs the whole study and writes it into `options.out`.
pub fn run(options: &Options, progress: &mut dyn FnMut(&str)) -> Result<Report, String> {
    let out = &options.out;
    std::fs::create_dir_all(out).map_err(|e| format!("cannot create {}: {e}", out.display()))?;
    let quick = options.quick;
    let repeats = options.repeats.max(5);
    let mut timings = Vec::new();

    let clock = Instant::now();
    let problems = problems(quick, progress)?;
    timings.push(("references".to_string(), clock.elapsed().as_secs_f64()));

    let clock = Instant::now();
    let mut points = Vec::new();
    let mut orders = Vec::new();
    for problem in &problems {
        progress(&format!(
            "work-precision on {}: {} integrators x {} steps x {repeats} runs",
            problem.name,
            Integrator::ALL.len(),
            problem.dts.len()
        ));
        let floor = precision::error_floor(problem);
        for integrator in Integrator::ALL {
            let mine: Vec<Point> = (problem.dts.iter())
                .map(|&dt| precision::measure(problem, integrator, dt, repeats))
                .collect();
            orders.push(precision::observed_order(
                &problem.name,
                integrator,
                &mine,
                problem.scale,
                floor,
            ));
            points.extend(mine);
        }
    }
    timings.push(("work-precision".to_string(), clock.elapsed().as_secs_f64()));

    let clock = Instant::now();
    let stability = stability_rows(quick, progress)?;
    timings.push(("stability".to_string(), clock.elapsed().as_secs_f64()));
    let clock = Instant::now();
    let damped = damped_rows(quick, progress)?;
    timings.push(("damping".to_string(), clock.elapsed().as_secs_f64()));

    let clock = Instant::now();
    progress("extreme cases");
    let extreme: Vec<extreme::Result> = extreme::cases(quick)
        .iter()
        .map(|c| extreme::run_case(c, DEFAULT_SAFETY))
        .collect();
    timings.push(("extreme cases".to_string(), clock.elapsed().as_secs_f64()));

    let clock = Instant::now();
    let stiff = stiff::measure(quick, &stiff_cloth, progress)?;
    timings.push(("stiff cloth".to_string(), clock.elapsed().as_secs_f64()));

    let report = Report {
        quick,
        problems,
        points,
        orders,
        stability,
        damped,
        extreme,
        stiff,
        timings,
    };
    progress(&format!("writing {}", out.display()));
    write::all(&report, out)?;
    Ok(report)
}

/// Stiffness values of the cloth sweep.
pub fn cloth_stiffnesses(quick: bool) -> Vec<f64> {
    if quick {
        vec![1e2, 1e4, 1e6]
    } else {
        vec![1e2, 1e3, 1e4, 1e5, 1e6]
    }
}

/// The undamped stability cases: spring, chain, and the cloth over k.
fn stability_rows(
    quick: bool,
    progress: &mut dyn FnMut(&str),
) -> Result<Vec<stability::Row>, String> {
    let undamped = sets(&["damping=0", "air_damping=0"]);
    let iterations = if quick { 10 } else { 14 };
    let mut rows = Vec::new();
    progress("stability: undamped spring and chain");
    let mut axial = undamped.clone();
    axial.extend(sets(&["gravity=9.81,0,0", "stiffness=1000"]));
    for (name, label, overrides) in [
        ("spring", "spring (undamped)", &undamped),
        ("chain", "chain (undamped, falling)", &undamped),
        (
            "chain",
            "chain (undamped, k=1e3, loaded along its length)",
            &axial,
        ),
    ] {
        let s = scene(name, overrides)?;
        rows.extend(stability::measure_case(
            label,
            &s,
            &Integrator::ALL,
            1000.0,
            (64.0, 256.0),
            iterations,
        ));
    }
    let side = if quick { 12 } else { 32 };
    for k in cloth_stiffnesses(quick) {
        progress(&format!(
            "stability: undamped cloth {side}x{side}, k = {k:e} N/m"
        ));
        let mut o = cloth_undamped(side);
        o.push(format!("stiffness={k:?}"));
        let s = scene("cloth", &o)?;
        rows.extend(stability::measure_case(
            &format!("cloth {side}x{side} (undamped)"),
            &s,
            &Integrator::ALL,
            500.0,
            (16.0, 256.0),
            iterations,
        ));
    }
    Ok(rows)
}

/// The stiff-cloth study's scene: the `cloth` scene at `side` x `side` and stiffness
/// `k`, in still air.
fn stiff_cloth(side: u32, k: f64) -> Result<Resolved, String> {
    scene(
        "cloth",
        &[
            format!("width={side}"),
            format!("height={side}"),
            format!("stiffness={k:?}"),
            "wind=0,0,0".into(),
            "gust=0".into(),
        ],
    )
}

/// Overrides that make the `cloth` scene `side` x `side`, undamped and without air.
pub fn cloth_undamped(side: u32) -> Vec<String> {
    vec![
        format!("width={side}"),
        format!("height={side}"),
        "damping=0".into(),
        "wind=0,0,0".into(),
        "gust=0".into(),
        "drag_coefficient=0".into(),
    ]
}

/// Symplectic Euler with spring damping: the spring over b/k, the chain and the cloth.
fn damped_rows(quick: bool, progress: &mut dyn FnMut(&str)) -> Result<Vec<stability::Row>, String> {
    progress("stability with damping (symplectic Euler)");
    let iterations = if quick { 10 } else { 14 };
    let se = [Integrator::SymplecticEuler];
    let mut rows = Vec::new();
    let k = scene("spring", &[])?.stiffness;
    for b_over_k in [0.0, 0.01, 0.03, 0.1, 0.3, 1.0] {
        let s = scene("spring", &[format!("damping={:?}", k * b_over_k)])?;
        rows.extend(stability::measure_case(
            "spring",
            &s,
            &se,
            1000.0,
            (64.0, 256.0),
            iterations,
        ));
    }
    let s = scene("chain", &sets(&["air_damping=0"]))?;
    rows.extend(stability::measure_case(
        "chain (25% of critical)",
        &s,
        &se,
        1000.0,
        (64.0, 256.0),
        iterations,
    ));
    let side = if quick { 12 } else { 32 };
    for b in [0.02, 0.2] {
        let mut o = cloth_undamped(side);
        o.retain(|s| !s.starts_with("damping"));
        o.push(format!("damping={b:?}"));
        let s = scene("cloth", &o)?;
        rows.extend(stability::measure_case(
            &format!("cloth {side}x{side}"),
            &s,
            &se,
            500.0,
            (16.0, 256.0),
            iterations,
        ));
    }
    Ok(rows)
}

/// Writes `text` into `dir/name`, whole or not at all: into a file beside it,
/// renamed over it once written ([`crate::limits::PendingFile`]), so that a full
/// disk leaves the old file or none, never a truncated one.
pub(crate) fn write_file(dir: &Path, name: &str, text: &str) -> Result<(), String> {
    use std::io::Write as _;
    let path = dir.join(name);
    let cannot = |e: &dyn std::fmt::Display| format!("cannot write {}: {e}", path.display());
    let mut file = crate::limits::PendingFile::create(&path).map_err(|e| cannot(&e))?;
    file.writer()
        .write_all(text.as_bytes())
        .map_err(|e| cannot(&e))?;
    file.commit().map_err(|e| cannot(&e))
}
