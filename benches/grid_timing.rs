//! Steps/s of the grid fast path on the peers' benchmark scene, timed like the
//! peers (shared/peers/harness.py): every run starts from rest and times 960 steps
//! (1 s of physics) after a 16-step warm-up; the median and best of several runs
//! are printed. Before each run it waits (up to `--quiet-wait` s) until other
//! processes use under 10 % of the machine, and redoes a run (up to 6 tries) when
//! they used more meanwhile; the `other` column is their share during the kept
//! runs (max). `cpu/wall` is this process's CPU time over wall time (~1 per busy
//! thread). Linux only for the load figures (reads /proc).
//!
//! `cargo bench --bench grid_timing -- [--sizes 32,64,128,256,512]
//! [--threads 1,2] [--runs 5] [--wind | --calm] [--quiet-wait 60]
//! [--simd avx512|avx2|baseline]`

use std::time::{Duration, Instant};

use cloth_sandbox::sim::grid_kernel::{GridCloth, GridSpec, SimdLevel};

const MAX_OTHER: f64 = 0.10;

fn list(arg: Option<String>, default: &[usize]) -> Vec<usize> {
    arg.map(|s| s.split(',').filter_map(|t| t.trim().parse().ok()).collect())
        .unwrap_or_else(|| default.to_vec())
}

/// System-wide busy CPU seconds (all cores) from /proc/stat.
fn busy_seconds() -> f64 {
    let Ok(s) = std::fs::read_to_string("/proc/stat") else {
        return 0.0;
    };
    let v: Vec<f64> = s
        .lines()
        .next()
        .unwrap_or("")
        .split_whitespace()
        .skip(1)
        .filter_map(|t| t.parse().ok())
        .collect();
    if v.len() < 8 {
        return 0.0;
    }
    (v[0] + v[1] + v[2] + v[5] + v[6] + v[7]) / 100.0
}

/// CPU seconds used by this process: the sum over its threads of /proc schedstat.
fn process_cpu_seconds() -> f64 {
    let Ok(dir) = std::fs::read_dir("/proc/self/task") else {
        return 0.0;
    };
    dir.filter_map(|e| e.ok())
        .filter_map(|e| std::fs::read_to_string(e.path().join("schedstat")).ok())
        .filter_map(|s| s.split_whitespace().next()?.parse::<f64>().ok())
        .sum::<f64>()
        / 1e9
}

fn cpus() -> f64 {
    std::thread::available_parallelism().map_or(1, |n| n.get()) as f64
}

/// Share of the machine used by other processes over a window (0..1).
fn other_load(b0: f64, c0: f64, wall: f64) -> f64 {
    let busy = busy_seconds() - b0;
    let own = process_cpu_seconds() - c0;
    ((busy - own) / (wall * cpus())).max(0.0)
}

fn wait_quiet(max_wait: f64) {
    let end = Instant::now() + Duration::from_secs_f64(max_wait);
    loop {
        let (b0, c0) = (busy_seconds(), process_cpu_seconds());
        std::thread::sleep(Duration::from_millis(500));
        if other_load(b0, c0, 0.5) < MAX_OTHER || Instant::now() > end {
            return;
        }
    }
}

fn main() {
    let mut args = std::env::args().skip(1);
    let (mut sizes, mut threads, mut runs, mut quiet_wait) = (None, None, 5usize, 60.0);
    let mut winds = vec![false, true];
    let mut simd = None;
    while let Some(a) = args.next() {
        match a.as_str() {
            "--sizes" => sizes = args.next(),
            "--threads" => threads = args.next(),
            "--runs" => runs = args.next().and_then(|s| s.parse().ok()).unwrap_or(runs),
            "--quiet-wait" => {
                quiet_wait = args
                    .next()
                    .and_then(|s| s.parse().ok())
                    .unwrap_or(quiet_wait)
            }
            "--simd" => {
                simd = args.next().as_deref().and_then(SimdLevel::from_name);
            }
            "--wind" => winds = vec![true],
            "--calm" => winds = vec![false],
            // `cargo bench` passes --bench to every bench binary.
            "--bench" => {}
            _ => eprintln!("unknown argument {a}"),
        }
    }
    let sizes = list(sizes, &[32, 64, 128, 256, 512]);
    let threads = list(threads, &[1, 2]);
    let dt = 1.0 / 960.0;
    println!(
        "| N | threads | wind | steps/s median | best | Mparticle-steps/s | Mspring-steps/s | ns/particle-step | cpu/wall | other |"
    );
    println!("|---|---|---|---:|---:|---:|---:|---:|---:|---:|");
    for &wind in &winds {
        for &n in &sizes {
            for &t in &threads {
                let spec = GridSpec::peer_bench(n, wind);
                let springs = spec.spring_count() as f64;
                let mut rates = Vec::new();
                let (mut cpu_ratio, mut worst_other) = (0.0f64, 0.0f64);
                for _ in 0..runs {
                    let mut kept = None;
                    for attempt in 0..6 {
                        wait_quiet(quiet_wait);
                        let mut cloth = GridCloth::new(spec.clone());
                        cloth.set_threads(t);
                        if let Some(level) = simd {
                            cloth.set_simd_level(level);
                        }
                        cloth.steps(dt, 16);
                        let mut cloth = GridCloth::new(spec.clone());
                        cloth.set_threads(t);
                        if let Some(level) = simd {
                            cloth.set_simd_level(level);
                        }
                        let (b0, c0) = (busy_seconds(), process_cpu_seconds());
                        let start = Instant::now();
                        cloth.steps(dt, 960);
                        let wall = start.elapsed().as_secs_f64();
                        let cpu = process_cpu_seconds() - c0;
                        let other = other_load(b0, c0, wall);
                        kept = Some((960.0 / wall, cpu / wall, other));
                        if other < MAX_OTHER || attempt == 5 {
                            break;
                        }
                    }
                    let (rate, ratio, other) = kept.unwrap_or((0.0, 0.0, 0.0));
                    rates.push(rate);
                    cpu_ratio = cpu_ratio.max(ratio);
                    worst_other = worst_other.max(other);
                }
                rates.sort_by(|a, b| a.total_cmp(b));
                let med = rates[rates.len() / 2];
                let best = rates[rates.len() - 1];
                let np = (n * n) as f64;
                println!(
                    "| {n} | {t} | {} | {med:.0} | {best:.0} | {:.0} | {:.0} | {:.2} | {cpu_ratio:.2} | {:.0}% |",
                    if wind { "yes" } else { "no" },
                    med * np / 1e6,
                    med * springs / 1e6,
                    1e9 / (med * np),
                    100.0 * worst_other,
                );
            }
        }
    }
}
