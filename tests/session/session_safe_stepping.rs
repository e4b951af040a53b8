//! With safe stepping on (the app's default), the panel's slider extremes do not make
//! the cloth explode: stiffest springs on the lightest particles, the largest dt,
//! strongest damping, strongest wind. Without it, the stiff case does explode, so the
//! test would notice safe stepping doing nothing.

use cloth_sandbox::session::Session;

fn run_steps(session: &mut Session, steps: usize) -> Result<(), String> {
    for _ in 0..steps {
        session.single_step();
        if let Some(d) = session.divergence() {
            return Err(d.message.clone());
        }
    }
    let finite = session.system().positions().iter().all(|p| p.is_finite());
    if finite {
        Ok(())
    } else {
        Err("non-finite".into())
    }
}

fn session(settings: &[(&str, &str)]) -> Session {
    let mut s = Session::load_with("cloth", &["width=10".into(), "height=10".into()]).unwrap();
    for (k, v) in settings {
        s.set(k, v).unwrap_or_else(|e| panic!("{k}={v}: {e}"));
    }
    s
}

#[test]
fn slider_extremes_stay_finite_with_safe_stepping() {
    let corners: &[&[(&str, &str)]] = &[
        &[
            ("stiffness", "100000"),
            ("particle_mass", "0.000001"),
            ("dt", "0.05"),
        ],
        &[
            ("stiffness", "100000"),
            ("particle_mass", "0.000001"),
            ("damping", "100"),
        ],
        &[
            ("stiffness", "0.01"),
            ("particle_mass", "0.000001"),
            ("wind", "20,20,20"),
            ("gust", "10"),
        ],
        &[
            ("stiffness", "100000"),
            ("particle_mass", "10"),
            ("wind", "-20,20,-20"),
            ("dt", "0.05"),
        ],
        &[
            ("stiffness", "100000"),
            ("rest_length", "0.001"),
            ("particle_mass", "0.000001"),
        ],
        &[
            ("stiffness", "100000"),
            ("rest_length", "5"),
            ("gravity", "-30"),
            ("dt", "0.05"),
        ],
        &[
            ("integrator", "\"rk4\""),
            ("stiffness", "100000"),
            ("particle_mass", "0.000001"),
        ],
        &[
            ("integrator", "\"verlet\""),
            ("stiffness", "100000"),
            ("dt", "0.05"),
        ],
        &[("integrator", "\"explicit-euler\""), ("damping", "1")],
        &[
            ("integrator", "\"rk2\""),
            ("damping", "1"),
            ("stiffness", "10000"),
        ],
    ];
    for settings in corners {
        let mut s = session(settings);
        let choice = s.step_choice().expect("safe stepping is on by default");
        assert!(choice.safe, "{settings:?}: no safe step chosen");
        run_steps(&mut s, 3_000)
            .unwrap_or_else(|e| panic!("{settings:?} diverged with safe stepping: {e}"));
    }
}

#[test]
fn safe_stepping_keeps_simulated_time_per_frame() {
    let mut s = session(&[("stiffness", "100000")]);
    let c = s.step_choice().unwrap();
    let scene_frame = 16.0 / 960.0;
    assert!(
        c.substeps > 16,
        "stiff springs need more substeps, got {}",
        c.substeps
    );
    assert!((c.dt * f64::from(c.substeps) - scene_frame).abs() < 1e-3 * scene_frame);
    s.set("stiffness", "10").unwrap();
    assert_eq!(
        s.step_choice().unwrap().substeps,
        16,
        "a soft cloth keeps the scene's steps"
    );
}

#[test]
fn without_safe_stepping_the_stiff_cloth_explodes() {
    let mut s = session(&[
        ("stiffness", "100000"),
        ("particle_mass", "0.000001"),
        ("dt", "0.05"),
    ]);
    s.set_safe_stepping(false);
    assert!(s.step_choice().is_none());
    assert!(run_steps(&mut s, 3_000).is_err());
}

#[test]
fn a_soft_cloth_in_a_gale_is_held_by_the_stretch_limit() {
    let gale = [
        ("stiffness", "1"),
        ("particle_mass", "0.001"),
        ("wind", "20,20,20"),
        ("gust", "10"),
    ];
    let mut s = session(&gale);
    assert_eq!(
        s.step_choice().unwrap().stretch_limit,
        Some(cloth_sandbox::session::SAFE_STRETCH_LIMIT)
    );
    run_steps(&mut s, 5_000).unwrap();
    // Without the limit, drag outgrows the springs and the cloth runs away.
    let mut raw = session(&gale);
    raw.set_safe_stepping(false);
    assert_eq!(raw.system().params().stretch_limit, None);
    assert!(run_steps(&mut raw, 5_000).is_err());
}

#[test]
fn a_rest_length_jump_scales_the_cloth_and_keeps_its_strains() {
    let mut s = session(&[("stiffness", "100000")]);
    run_steps(&mut s, 200).unwrap();
    let strain = |s: &Session| -> Vec<f64> {
        let x = s.system().positions();
        (s.system().springs().iter())
            .map(|sp| (x[sp.a as usize] - x[sp.b as usize]).length() / sp.rest - 1.0)
            .collect()
    };
    let before = strain(&s);
    let energy_before = s.system().energy().elastic;
    s.set("rest_length", "5").unwrap();
    let after = strain(&s);
    for (a, b) in before.iter().zip(&after) {
        assert!((a - b).abs() < 1e-9, "strain {a} became {b}");
    }
    // Elastic energy scales with L² at equal strain: 100² for 0.05 -> 5 m.
    let ratio = s.system().energy().elastic / energy_before;
    assert!((ratio / 1e4 - 1.0).abs() < 1e-6, "{ratio}");
    run_steps(&mut s, 3_000).unwrap();
}

#[test]
fn the_default_cloth_needs_no_limit_and_runs_on_the_grid_kernel() {
    let s = Session::load_with("cloth", &[]).unwrap();
    assert_eq!(s.step_choice().unwrap().stretch_limit, None);
    assert!(s.system().engine().is_grid());
}

#[test]
fn the_wind_load_ratio_separates_the_default_from_the_gale() {
    use cloth_sandbox::session::{WIND_LOAD_NEEDING_A_LIMIT, wind_load_ratio};
    let ratio = |settings: &[(&str, &str)]| wind_load_ratio(session(settings).system().model());
    assert!(ratio(&[]) < 0.01 * WIND_LOAD_NEEDING_A_LIMIT);
    let gale = ratio(&[("stiffness", "1"), ("wind", "20,20,20"), ("gust", "10")]);
    assert!(gale > 10.0 * WIND_LOAD_NEEDING_A_LIMIT, "{gale}");
}

/// The peers' bench cloth in its wind at 128 x 128, on position Verlet: its 1 kg
/// hangs from 0.3 N/m springs far past their rest length, so the drag works on
/// many times the rest areas the step was chosen for. Safe stepping watches the
/// areas frame by frame and cuts the step as they grow; with the step it chose at
/// rest kept (as it did until it watched), the cloth runs away at 1.77 s.
#[test]
fn safe_stepping_cuts_the_step_as_a_hanging_cloths_drag_areas_grow() {
    let settings = [
        "width=128".to_string(),
        "height=128".into(),
        "integrator=\"verlet\"".into(),
    ];
    let mut s = Session::load_with("bench-wind", &settings).unwrap();
    let at_rest = s.step_choice().unwrap();
    let mut frames = 0;
    while s.system().time() < 2.5 {
        s.step_frame();
        frames += 1;
        assert!(s.divergence().is_none(), "{:?}", s.divergence());
    }
    let now = s.step_choice().unwrap();
    assert!(
        now.substeps >= 4 * at_rest.substeps,
        "{} substeps at rest, {} after {frames} frames",
        at_rest.substeps,
        now.substeps
    );
    // The frame's simulated time is kept.
    let frame = |c: cloth_sandbox::session::StepChoice| c.dt * f64::from(c.substeps);
    assert!((frame(now) / frame(at_rest) - 1.0).abs() < 1e-9);
    assert!(s.system().positions().iter().all(|p| p.is_finite()));
}
