//! No panic when tearing ends a fast kernel's run early, a work
//! limit that counts every pass of a step, and self-collision memory bounded
//! whatever the thickness.

use std::time::{Duration, Instant};

use cloth_sandbox::sim::{MAX_PAIRS_PER_PARTICLE, SelfCollision};
use glam::DVec3;

use crate::binary::{cloth, stderr};

/// A panic seen ("the same system still has a spec", fast_path.rs:600): a
/// 4 x 1 cloth inside a sphere of 100 m is thrown out and tears; the grid kernel
/// stops early once tearing has broken its grid, and the rest of the run goes to
/// the engine that models what is left. A few other shapes that tear their grid
/// apart too, on every integrator the grid kernel runs.
#[test]
fn a_kernel_stopped_by_tearing_hands_the_rest_of_the_run_on() {
    let base = [
        "--set",
        "tear_strain=0.4",
        "--set",
        "sphere_center=0,0.5,0",
        "--set",
        "sphere_radius=100",
        "--steps",
        "3000",
    ];
    for (w, h) in [("4", "1"), ("3", "3"), ("16", "2")] {
        for integrator in ["symplectic-euler", "verlet", "explicit-euler"] {
            let width = format!("width={w}");
            let height = format!("height={h}");
            let mut args = vec!["run", "--scene", "cloth", "--set", &width, "--set", &height];
            args.extend(["--integrator", integrator]);
            args.extend(base);
            let o = cloth(&args);
            let err = stderr(&o);
            assert!(!err.contains("panicked"), "{w}x{h} {integrator}: {err}");
            assert!(
                matches!(o.status.code(), Some(0 | 3)),
                "{w}x{h} {integrator}: {:?} {err}",
                o.status
            );
        }
    }
}

/// Runs `cloth` with `args`, which must be refused within a few seconds with a
/// message holding each of `words`.
fn refused_at_once(args: &[&str], words: &[&str]) {
    let start = Instant::now();
    let o = cloth(args);
    let took = start.elapsed();
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
    assert!(took < Duration::from_secs(20), "{args:?} took {took:?}");
    for w in words {
        assert!(err.contains(w), "{args:?}: `{w}` not in {err}");
    }
}

/// Hangs seen: a rope of 100,000 points with 10,000 bar passes a step, and
/// the bar cloth at 1024² with 10,000, ran for minutes to hours. The bar passes
/// are work: each bar correction counts as 6 particle-steps (its measured cost).
#[test]
fn the_work_limit_counts_every_bar_pass() {
    refused_at_once(
        &[
            "run",
            "--scene",
            "rope",
            "--set",
            "width=100000",
            "--set",
            "bar_iterations=10000",
        ],
        &["bar corrections", "particle-steps of work"],
    );
    refused_at_once(
        &[
            "run",
            "--scene",
            "bars",
            "--set",
            "width=1024",
            "--set",
            "height=1024",
            "--set",
            "bar_iterations=10000",
        ],
        &["bar corrections", "particle-steps of work"],
    );
    // The same rope with its 8 passes runs.
    let o = cloth(&[
        "run",
        "--scene",
        "rope",
        "--set",
        "width=1000",
        "--steps",
        "10",
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
}

/// Runaway memory seen: self-collision at a thickness of 10 m on a 256 x
/// 256 cloth listed every pair (2·10⁹, 24 GB) and the kernel killed the run. Under
/// a 3 GB address-space cap the run is refused with the figure, and neither
/// crashes nor runs out of memory.
#[test]
fn a_thickness_far_past_the_spacing_is_refused_within_a_memory_cap() {
    let o = std::process::Command::new("prlimit")
        .args(["--as=3000000000", "--"])
        .arg(env!("CARGO_BIN_EXE_cloth"))
        .args([
            "run",
            "--scene",
            "cloth",
            "--set",
            "width=256",
            "--set",
            "height=256",
            "--set",
            "self_collision=true",
            "--set",
            "thickness=10",
            "--steps",
            "3",
        ])
        .output();
    let Ok(o) = o else {
        eprintln!("no prlimit here: skipped");
        return;
    };
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("`thickness` of 10 m with self_collision"),
        "{err}"
    );
    assert!(
        err.contains(&format!("more than {MAX_PAIRS_PER_PARTICLE} others")),
        "{err}"
    );
    assert!(err.contains("GB"), "{err}");
    // A thickness of about a spacing still runs under the same cap.
    let o = std::process::Command::new("prlimit")
        .args(["--as=3000000000", "--"])
        .arg(env!("CARGO_BIN_EXE_cloth"))
        .args([
            "run",
            "--scene",
            "drape",
            "--set",
            "width=128",
            "--set",
            "height=128",
            "--steps",
            "200",
        ])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
}

/// The pass itself keeps its list within [`MAX_PAIRS_PER_PARTICLE`] a particle
/// whatever it is given (a live edit, a cloth crumpled into a ball): 20,000
/// particles in a 1 cm box with a thickness of 1 m, where every one of the 2·10⁸
/// pairs is within reach, list at most the bound, say that they left pairs out,
/// and keep every particle finite.
#[test]
fn the_pass_lists_at_most_its_bound_and_says_when_it_left_pairs_out() {
    let n: usize = 20_000;
    let mut x: Vec<DVec3> = (0..n)
        .map(|i| {
            let f = i as f64;
            DVec3::new(
                (f * 0.618).fract(),
                (f * 0.414).fract(),
                (f * 0.732).fract(),
            ) * 0.01
        })
        .collect();
    assert!(SelfCollision::would_overfill(&x, 1.0, |_, _| false));
    let start = x.clone();
    let mut pass = SelfCollision::default();
    pass.apply(&mut x, |i| (start[i], 1.0), 1.0, 0.0, |_, _| false, false);
    assert!(pass.overfull());
    // Each block's search stops once it has its room, after the particle that
    // filled it: at most the bound and one particle's pairs more a block.
    let blocks = n.div_ceil(1024);
    assert!(
        pass.candidates() <= MAX_PAIRS_PER_PARTICLE * n + blocks * n,
        "{} pairs",
        pass.candidates()
    );
    assert!(x.iter().all(|p| p.is_finite()));
    // A flat grid at one spacing with a thickness of 0.8 spacings fits.
    let grid: Vec<DVec3> = (0..10_000)
        .map(|i| DVec3::new((i % 100) as f64, 0.0, (i / 100) as f64) * 0.01)
        .collect();
    assert!(!SelfCollision::would_overfill(&grid, 0.008, |_, _| false));
}
