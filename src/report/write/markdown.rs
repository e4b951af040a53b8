//! `REPORT.md`: what was run, the tables, and the conclusions drawn from them.

use std::fmt::Write as _;

use super::conclusions::{conclusions, stiff_conclusions};
use super::limit_text;
use crate::report::precision::{Outcome, Point, Reference};
use crate::report::stability::damped_symplectic_limit;
use crate::report::{Report, stiff};
use crate::sim::Integrator;

fn fmt_s(v: f64) -> String {
    if v < 1e-3 {
        format!("{:.1} µs", v * 1e6)
    } else if v < 1.0 {
        format!("{:.2} ms", v * 1e3)
    } else {
        format!("{v:.2} s")
    }
}

/// The whole of `REPORT.md`, section by section.
pub(super) fn markdown(r: &Report) -> String {
    let mut m = String::new();
    intro(r, &mut m);
    work_precision(r, &mut m);
    orders(r, &mut m);
    cheapest(r, &mut m);
    not_drawn(r, &mut m);
    stability(r, &mut m);
    damping(r, &mut m);
    extreme(r, &mut m);
    stiff_section(r, &mut m);
    let _ = writeln!(m, "## Conclusions from these measurements\n");
    for line in conclusions(r) {
        let _ = writeln!(m, "- {line}");
    }
    m
}

/// The title, the command that wrote the report, and the time each part took.
fn intro(r: &Report, m: &mut String) {
    let cmd = if r.quick {
        "cloth report --quick"
    } else {
        "cloth report"
    };
    let _ = writeln!(m, "# Integrators: error against run time, and stability\n");
    let _ = writeln!(
        m,
        "Written by `{cmd}`{}. Every number below is in the CSV files beside this file; \
         run times are medians of 5 runs of `System::run` (the code path of `cloth run`) on the \
         machine that ran the command ({} threads available). Wall time of each part: {}.\n",
        if r.quick {
            " (quick: smaller problems, a smoke run)"
        } else {
            ""
        },
        std::thread::available_parallelism().map_or(0, |n| n.get()),
        r.timings
            .iter()
            .map(|(p, t)| format!("{p} {t:.0} s"))
            .collect::<Vec<_>>()
            .join(", ")
    );
}

/// The problems, their references, and the error plots.
fn work_precision(r: &Report, m: &mut String) {
    let _ = writeln!(m, "## Work-precision\n");
    for p in &r.problems {
        let reference = match &p.reference {
            Reference::Analytic(_) => "exact solution".to_string(),
            Reference::Numerical(n) => format!(
                "RK4 at dt = {:.3e} s; its own RMS error, estimated by Richardson from a run at twice that step: {:.2e} m",
                n.dt, n.error_estimate
            ),
        };
        let _ = writeln!(
            m,
            "- **{}**: {}. Steps {:.3e} to {:.3e} s ({} values, a factor {:.0}). Reference: {reference}. \
             A run whose error exceeds {:.3} m (the size of the motion) has no accuracy left.",
            p.name,
            p.description,
            p.dts.first().copied().unwrap_or(0.0),
            p.dts.last().copied().unwrap_or(0.0),
            p.dts.len(),
            p.dts.first().copied().unwrap_or(1.0) / p.dts.last().copied().unwrap_or(1.0),
            p.scale
        );
    }
    let _ = writeln!(m);
    for p in &r.problems {
        let _ = writeln!(
            m,
            "![{0}: error against run time](precision-{0}.svg)\n",
            p.name
        );
        if matches!(p.reference, Reference::Analytic(_)) {
            let _ = writeln!(
                m,
                "![{0}: largest error over time against run time](precision-{0}-max.svg)\n",
                p.name
            );
        }
    }
    let _ = writeln!(
        m,
        "Error against dt (the slopes of the order table): {}.\n",
        r.problems
            .iter()
            .map(|p| format!("[{0}](convergence-{0}.svg)", p.name))
            .collect::<Vec<_>>()
            .join(", ")
    );
}

/// The observed order of convergence, integrator by problem.
fn orders(r: &Report, m: &mut String) {
    let _ = writeln!(m, "### Observed order of convergence\n");
    let _ = writeln!(
        m,
        "Least-squares slope of ln(error) against ln(dt) (the spring: the largest error over time; \
         the others: the RMS error at the end time) over the runs with an error below a tenth of \
         the motion's size and above 100 times the reference's own error (and round-off); `n` is \
         the number of steps used. Blank: fewer than 3 such runs.\n"
    );
    let _ = write!(m, "| integrator | theory |");
    for p in &r.problems {
        let _ = write!(m, " {} (n) |", p.name);
    }
    let _ = writeln!(m);
    let _ = writeln!(m, "|---|---|{}", "---|".repeat(r.problems.len()));
    for i in Integrator::ALL {
        let _ = write!(m, "| {i} | {} |", i.order());
        for p in &r.problems {
            let o = r
                .orders
                .iter()
                .find(|o| o.problem == p.name && o.integrator == i);
            let cell = o.map_or(String::new(), |o| {
                o.observed.map_or(format!("— ({})", o.points), |v| {
                    format!("{v:.2} ({})", o.points)
                })
            });
            let _ = write!(m, " {cell} |");
        }
        let _ = writeln!(m);
    }
    let _ = writeln!(m);
}

/// The cheapest run reaching each error target.
fn cheapest(r: &Report, m: &mut String) {
    let _ = writeln!(m, "### Cheapest run reaching an error\n");
    let _ = writeln!(
        m,
        "For each problem and error target (as a fraction of the motion's size), the run with the \
         smallest median run time whose end error is at most the target.\n"
    );
    let _ = writeln!(
        m,
        "| problem | target error | integrator | dt (s) | error (m) | run time |"
    );
    let _ = writeln!(m, "|---|---|---|---|---|---|");
    for p in &r.problems {
        for frac in [1e-2, 1e-4, 1e-6] {
            let target = frac * p.scale;
            let best = (r.points.iter())
                .filter(|q| {
                    q.problem == p.name && q.outcome == Outcome::Ok && q.error_end <= target
                })
                .min_by(|a, b| a.run_time.total_cmp(&b.run_time));
            match best {
                Some(q) => {
                    let _ = writeln!(
                        m,
                        "| {} | {target:.1e} m | {} | {:.3e} | {:.2e} | {} |",
                        p.name,
                        q.integrator,
                        q.dt,
                        q.error_end,
                        fmt_s(q.run_time)
                    );
                }
                None => {
                    let _ = writeln!(m, "| {} | {target:.1e} m | none reached it | | | |", p.name);
                }
            }
        }
    }
    let _ = writeln!(m);
}

/// The runs that diverged or lost all accuracy.
fn not_drawn(r: &Report, m: &mut String) {
    let _ = writeln!(m, "### Runs not drawn\n");
    let failed: Vec<&Point> = r
        .points
        .iter()
        .filter(|p| p.outcome != Outcome::Ok)
        .collect();
    if failed.is_empty() {
        let _ = writeln!(
            m,
            "None: every run finished with an error below the motion's size.\n"
        );
    } else {
        let _ = writeln!(m, "| problem | integrator | dt (s) | what happened |");
        let _ = writeln!(m, "|---|---|---|---|");
        for p in &failed {
            let what = match &p.outcome {
                Outcome::Diverged { message, .. } => {
                    format!("diverged, caught by the check: {message}")
                }
                Outcome::NoAccuracy => format!(
                    "finished, not caught by the check, but its error {:.2e} m exceeds the motion's size",
                    p.error_end
                ),
                Outcome::Ok => String::new(),
            };
            let _ = writeln!(
                m,
                "| {} | {} | {:.3e} | {what} |",
                p.problem, p.integrator, p.dt
            );
        }
        let _ = writeln!(m);
    }
}

/// Measured critical steps against theory, the estimate and Gershgorin.
fn stability(r: &Report, m: &mut String) {
    let _ = writeln!(m, "## Stability\n");
    let _ = writeln!(
        m,
        "Largest stable dt by bisection (stable: over a fixed simulated time, shown as the horizon, \
         and at least {} steps, nothing non-finite, the divergence check silent, and kinetic plus \
         elastic energy below {:e} times its largest value in an accurate run: RK4 at a quarter of \
         2/omega). Theory: the integrator's critical \
         step on the highest eigenfrequency of M^-1 K, the springs linearised at the initial state, \
         by power iteration. Estimate: the one the app, safe stepping and the energy check use \
         (`System::stability`: Lanczos at the initial state, at most the exact value). Gershgorin: the \
         bound `sim::stability::estimate` gives without positions. Where theory has no stable step \
         (explicit Euler and RK2 undamped) the table says `none` and gives the largest step whose growth \
         the criterion did not see within the horizon. \
         `none`: no step is stable in theory; `< x (none found)`: every step tried down to x was \
         unstable; `>= x (cap)`: stable at every step tried up to x.\n",
        crate::report::stability::MIN_STEPS,
        crate::report::stability::ENERGY_FACTOR
    );
    let _ = writeln!(m, "![critical dt against k](stability-k.svg)\n");
    let _ = writeln!(
        m,
        "| case | k (N/m) | integrator | measured dt_crit (s) | theory (s) | measured / theory | estimate (s) | estimate / theory | Gershgorin (s) | Gershgorin / theory | omega_max exact (rad/s) | horizon (s) |"
    );
    let _ = writeln!(m, "|---|---|---|---|---|---|---|---|---|---|---|---|");
    for row in &r.stability {
        let exact = row.theory.exact(row.integrator);
        let gersh = row.theory.gershgorin(row.integrator);
        let est = row.theory.estimate(row.integrator);
        let ratio = |a: Option<f64>, b: Option<f64>| match (a, b) {
            (Some(a), Some(b)) if a.is_finite() && b.is_finite() && b > 0.0 => {
                format!("{:.3}", a / b)
            }
            _ => String::new(),
        };
        let _ = writeln!(
            m,
            "| {} | {:.0e} | {} | {} | {} | {} | {} | {} | {} | {} | {:.4e} | {:.3e} |",
            row.case,
            row.stiffness,
            row.integrator,
            row.measured.text(),
            limit_text(exact),
            ratio(row.measured.value(), exact),
            limit_text(est),
            ratio(est, exact),
            limit_text(gersh),
            ratio(gersh, exact),
            row.theory.omega_exact,
            row.horizon
        );
    }
    let _ = writeln!(m);
}

/// Symplectic Euler's damped limit, measured against the formula.
fn damping(r: &Report, m: &mut String) {
    let _ = writeln!(m, "### Damping and symplectic Euler\n");
    let _ = writeln!(
        m,
        "With spring damping b (all springs with the same b/k, so the modes decouple), symplectic \
         Euler is stable while `omega² h (h + 2 b/k) < 4`: `h* = -b/k + sqrt((b/k)² + 4/omega²)` on the \
         highest mode (omega exact, by power iteration; the chain keeps its springs' damping but not \
         its air damping).\n"
    );
    let _ = writeln!(
        m,
        "| case | k (N/m) | b (N·s/m) | b/k (s) | measured (s) | formula h* (s) | measured / formula | undamped 2/omega (s) |"
    );
    let _ = writeln!(m, "|---|---|---|---|---|---|---|---|");
    for row in &r.damped {
        let bk = row.damping / row.stiffness;
        let formula = damped_symplectic_limit(row.theory.omega_exact, bk);
        let _ = writeln!(
            m,
            "| {} | {} | {:.4} | {:.3e} | {} | {:.4e} | {} | {:.4e} |",
            row.case,
            row.stiffness,
            row.damping,
            bk,
            row.measured.text(),
            formula,
            row.measured
                .value()
                .map_or(String::new(), |v| format!("{:.3}", v / formula)),
            2.0 / row.theory.omega_exact
        );
    }
    let _ = writeln!(m);
}

/// The extreme cases, as given and with safe stepping.
fn extreme(r: &Report, m: &mut String) {
    let _ = writeln!(m, "## Extreme cases\n");
    let _ = writeln!(
        m,
        "Each on the built-in `cloth` scene (32x32, symplectic Euler, dt = 1/960 s unless set), run \
         as given and again with safe stepping (each step of dt split into substeps below {} of the \
         estimated critical step). Reproduce one with `cloth run --scene cloth <overrides> --duration <t>` \
         (add `--safe` for the second column).\n",
        crate::sim::safe::DEFAULT_SAFETY
    );
    let _ = writeln!(
        m,
        "| case | overrides | run | as given | safe substeps | with safe stepping |"
    );
    let _ = writeln!(m, "|---|---|---|---|---|---|");
    for e in &r.extreme {
        let run = match e.case.steps {
            Some(n) => format!("{n} steps"),
            None => format!("{} s", e.case.duration),
        };
        let _ = writeln!(
            m,
            "| {} | `{}` | {run} | {} | {} | {} |",
            e.case.name,
            e.case.command_line(),
            e.raw.text(),
            e.safe_substeps.map_or("—".to_string(), |n| {
                if e.safe_met {
                    n.to_string()
                } else {
                    format!("{n} (cap: not safe)")
                }
            }),
            e.safe.text()
        );
    }
    let _ = writeln!(m);
}

fn stiff_section(r: &Report, m: &mut String) {
    if r.stiff.is_empty() {
        return;
    }
    let _ = writeln!(m, "## Stiff cloth\n");
    let _ = writeln!(
        m,
        "The `cloth` scene in still air, released flat from its top corners, run {} s on the engine \
         `cloth run` uses, against symplectic Euler at a fifth of its critical step (see \
         `src/report/stiff.rs`). Error: the largest distance of a particle from the reference at \
         the end. Strain: the largest `(l - L) / L`. Energy lost: since the start, each method's own \
         energy (XPBD's springs at the stiffness it simulates, `k / (1 + k h² w)`). Cost: wall seconds \
         per simulated second. The plot keeps, per stiffness, the cheapest run of each family within \
         {:.1} cm of the reference.\n",
        stiff::HORIZON,
        stiff::TARGET_ERROR * 100.0
    );
    let _ = writeln!(m, "![cost against k](stiff-cost.svg)\n");
    let _ = writeln!(
        m,
        "| cloth | k (N/m) | method | dt (s) | engine | cost (s/s) | error (m) | largest strain | energy lost (J) |"
    );
    let _ = writeln!(m, "|---|---|---|---|---|---|---|---|---|");
    for row in &r.stiff {
        let error = match &row.diverged {
            Some(why) => format!("diverged: {why}"),
            None => format!("{:.3e}", row.error),
        };
        let _ = writeln!(
            m,
            "| {0}x{0} | {1:.0e} | {2} | {3:.3e} | {4} | {5:.3e} | {6} | {7:.3e} | {8:.3e} |",
            row.side,
            row.stiffness,
            row.method,
            row.dt,
            row.engine,
            row.cost,
            error,
            row.strain,
            row.energy_lost
        );
    }
    let _ = writeln!(m);
    let _ = writeln!(m, "**Which solver when** (from this table):\n");
    for line in stiff_conclusions(r) {
        let _ = writeln!(m, "- {line}");
    }
    let _ = writeln!(m);
}
