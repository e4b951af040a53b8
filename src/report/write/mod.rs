//! Writes a [`Report`] as CSV files, SVG plots and `REPORT.md`; the conclusions in
//! `REPORT.md` are computed from the measurements, not written in advance.

use std::fmt::Write as _;
use std::path::Path;

use super::plot::{Series, Style, loglog};
use super::precision::{Outcome, Point, Reference};
use super::stability::{Measured, Row, damped_symplectic_limit};
use super::{Report, stiff, write_file};
use crate::sim::Integrator;

fn opt(v: Option<f64>) -> String {
    v.map_or(String::new(), |v| format!("{v:e}"))
}

fn limit_text(v: Option<f64>) -> String {
    match v {
        None => "none".into(),
        Some(v) if v.is_infinite() => "unlimited".into(),
        Some(v) => format!("{v:.4e}"),
    }
}

fn color(i: Integrator) -> usize {
    Integrator::ALL.iter().position(|&j| j == i).unwrap_or(0)
}

/// Writes everything into `out`.
pub fn all(report: &Report, out: &Path) -> Result<(), String> {
    csvs(report, out)?;
    plots(report, out)?;
    write_file(out, "REPORT.md", &markdown(report))
}

fn csvs(r: &Report, out: &Path) -> Result<(), String> {
    let mut s = String::from(
        "problem,integrator,dt_s,steps,error_end_rms_m,error_max_over_time_m,run_time_median_s,run_times_s,outcome,diverged_at_s,message\n",
    );
    for p in &r.points {
        let (outcome, at, msg) = match &p.outcome {
            Outcome::Ok => ("ok", String::new(), String::new()),
            Outcome::NoAccuracy => ("no-accuracy", String::new(), String::new()),
            Outcome::Diverged { time, message } => ("diverged", format!("{time}"), message.clone()),
        };
        let times: Vec<String> = p.run_times.iter().map(|t| format!("{t:e}")).collect();
        let _ = writeln!(
            s,
            "{},{},{:e},{},{:e},{},{:e},{},{outcome},{at},\"{}\"",
            p.problem,
            p.integrator,
            p.dt,
            p.steps,
            p.error_end,
            opt(p.error_max),
            p.run_time,
            times.join(";"),
            msg.replace('"', "'")
        );
    }
    write_file(out, "precision.csv", &s)?;

    let mut s = String::from("problem,reference,dt_s,error_estimate_m,wall_s\n");
    for p in &r.problems {
        match &p.reference {
            Reference::Analytic(_) => {
                let _ = writeln!(s, "{},exact damped oscillator,,0,", p.name);
            }
            Reference::Numerical(n) => {
                let _ = writeln!(
                    s,
                    "{},rk4 + richardson,{:e},{:e},{:.3}",
                    p.name, n.dt, n.error_estimate, n.wall
                );
            }
        }
    }
    write_file(out, "references.csv", &s)?;

    let mut s = String::from("problem,integrator,theory,observed,points,dt_min_s,dt_max_s\n");
    for o in &r.orders {
        let _ = writeln!(
            s,
            "{},{},{},{},{},{},{}",
            o.problem,
            o.integrator,
            o.theory,
            o.observed.map_or(String::new(), |v| format!("{v:.4}")),
            o.points,
            if o.points > 0 {
                format!("{:e}", o.dt_range.0)
            } else {
                String::new()
            },
            if o.points > 0 {
                format!("{:e}", o.dt_range.1)
            } else {
                String::new()
            },
        );
    }
    write_file(out, "orders.csv", &s)?;

    let header = "case,stiffness,damping,integrator,measured_kind,measured_lo_s,measured_hi_s,theory_exact_s,estimate_s,gershgorin_s,omega_exact,omega_estimate,omega_gershgorin,zeta_exact,zeta_estimate,zeta_gershgorin,power_iterations,horizon_s\n";
    for (name, rows) in [("stability.csv", &r.stability), ("damping.csv", &r.damped)] {
        let mut s = String::from(header);
        for row in rows {
            let (kind, lo, hi) = match row.measured {
                Measured::Between { lo, hi } => ("bracketed", format!("{lo:e}"), format!("{hi:e}")),
                Measured::AtLeast(x) => ("stable-up-to-cap", format!("{x:e}"), String::new()),
                Measured::Below(x) => ("unstable-down-to-floor", String::new(), format!("{x:e}")),
                Measured::Transient { lo, hi } => (
                    "none-in-theory-horizon-bracket",
                    format!("{lo:e}"),
                    format!("{hi:e}"),
                ),
            };
            let t = &row.theory;
            let _ = writeln!(
                s,
                "{},{:e},{:e},{},{kind},{lo},{hi},{},{},{},{:e},{:e},{:e},{:e},{:e},{:e},{},{:e}",
                row.case,
                row.stiffness,
                row.damping,
                row.integrator,
                limit_text(t.exact(row.integrator)),
                limit_text(t.estimate(row.integrator)),
                limit_text(t.gershgorin(row.integrator)),
                t.omega_exact,
                t.omega_estimate,
                t.omega_gershgorin,
                t.zeta_exact,
                t.zeta_estimate,
                t.zeta_gershgorin,
                t.iterations,
                row.horizon
            );
        }
        write_file(out, name, &s)?;
    }

    let mut s = String::from(
        "case,overrides,dt_s,raw,raw_detail,safe_substeps,safe_met,safe,safe_detail\n",
    );
    for e in &r.extreme {
        let _ = writeln!(
            s,
            "{},\"{}\",{},{},\"{}\",{},{},{},\"{}\"",
            e.case.name,
            e.case.command_line(),
            e.dt,
            e.raw.label(),
            e.raw.text().replace('"', "'"),
            e.safe_substeps.map_or(String::new(), |n| n.to_string()),
            e.safe_met,
            e.safe.label(),
            e.safe.text().replace('"', "'"),
        );
    }
    write_file(out, "extreme.csv", &s)?;

    let mut s = String::from(
        "side,stiffness_n_per_m,method,integrator,dt_s,steps,engine,wall_s_per_simulated_s,error_m,largest_strain,energy_lost_j,diverged\n",
    );
    for row in &r.stiff {
        let _ = writeln!(
            s,
            "{},{:e},{},{},{:e},{},{},{:e},{:e},{:e},{:e},\"{}\"",
            row.side,
            row.stiffness,
            row.method,
            row.integrator,
            row.dt,
            row.steps,
            row.engine,
            row.cost,
            row.error,
            row.strain,
            row.energy_lost,
            row.diverged.as_deref().unwrap_or("").replace('"', "'")
        );
    }
    write_file(out, "stiff.csv", &s)?;

    let mut s = String::from("part,wall_s\n");
    for (part, t) in &r.timings {
        let _ = writeln!(s, "{part},{t:.2}");
    }
    write_file(out, "timings.csv", &s)
}

fn plotted(points: &[&Point]) -> Vec<(f64, f64)> {
    points
        .iter()
        .filter(|p| p.outcome == Outcome::Ok)
        .map(|p| (p.run_time, p.error_end))
        .collect()
}

/// Picks the points to draw from one integrator's runs.
type Pick = dyn Fn(&[&Point]) -> Vec<(f64, f64)>;

fn plots(r: &Report, out: &Path) -> Result<(), String> {
    stiff_plot(r, out)?;
    for problem in &r.problems {
        let of = |i: Integrator| -> Vec<&Point> {
            (r.points.iter())
                .filter(|p| p.problem == problem.name && p.integrator == i)
                .collect()
        };
        let series = |f: &Pick| -> Vec<Series> {
            Integrator::ALL
                .iter()
                .map(|&i| Series {
                    label: i.name().to_string(),
                    points: f(&of(i)),
                    color: color(i),
                    style: Style::LineAndMarkers,
                })
                .collect()
        };
        loglog(
            &out.join(format!("precision-{}.svg", problem.name)),
            &format!(
                "{}: RMS position error at t = {} s against run time",
                problem.name, problem.end_time
            ),
            "run time (median of runs), s",
            "RMS position error, m",
            &series(&|p| plotted(p)),
        )?;
        loglog(
            &out.join(format!("convergence-{}.svg", problem.name)),
            &format!(
                "{}: RMS position error at t = {} s against dt",
                problem.name, problem.end_time
            ),
            "dt, s",
            "RMS position error, m",
            &series(&|p| {
                (p.iter())
                    .filter(|p| p.outcome == Outcome::Ok)
                    .map(|p| (p.dt, p.error_end))
                    .collect()
            }),
        )?;
        if matches!(problem.reference, Reference::Analytic(_)) {
            loglog(
                &out.join(format!("precision-{}-max.svg", problem.name)),
                &format!(
                    "{}: largest error over 0..{} s against run time",
                    problem.name, problem.end_time
                ),
                "run time (median of runs), s",
                "max over time of the position error, m",
                &series(&|p| {
                    (p.iter())
                        .filter(|p| p.outcome == Outcome::Ok)
                        .filter_map(|p| p.error_max.map(|e| (p.run_time, e)))
                        .collect()
                }),
            )?;
        }
    }
    // Critical dt against k on the cloth.
    let cloth: Vec<&Row> = r
        .stability
        .iter()
        .filter(|row| row.case.starts_with("cloth"))
        .collect();
    let mut series = Vec::new();
    for i in Integrator::ALL {
        let rows: Vec<&&Row> = cloth.iter().filter(|row| row.integrator == i).collect();
        let measured: Vec<(f64, f64)> = (rows.iter())
            .filter_map(|row| row.measured.value().map(|v| (row.stiffness, v)))
            .collect();
        if !measured.is_empty() {
            series.push(Series {
                label: format!("{i} measured"),
                points: measured,
                color: color(i),
                style: Style::LineAndMarkers,
            });
        }
    }
    for i in [Integrator::SymplecticEuler, Integrator::Rk4] {
        let rows: Vec<&&Row> = cloth.iter().filter(|row| row.integrator == i).collect();
        let pick = |f: &dyn Fn(&Row) -> Option<f64>| -> Vec<(f64, f64)> {
            (rows.iter())
                .filter_map(|row| f(row).filter(|v| v.is_finite()).map(|v| (row.stiffness, v)))
                .collect()
        };
        let name = if i == Integrator::SymplecticEuler {
            "symplectic-euler, verlet"
        } else {
            "rk4"
        };
        series.push(Series {
            label: format!("{name}: theory (power iteration)"),
            points: pick(&|row| row.theory.exact(i)),
            color: 6,
            style: Style::Line,
        });
        series.push(Series {
            label: format!("{name}: estimate (app)"),
            points: pick(&|row| row.theory.estimate(i)),
            color: 7,
            style: Style::Dashed,
        });
    }
    let title = cloth
        .first()
        .map_or("cloth".to_string(), |r| r.case.clone());
    loglog(
        &out.join("stability-k.svg"),
        &format!("{title}: largest stable dt against stiffness k"),
        "spring stiffness k, N/m",
        "critical dt, s",
        &series,
    )
}

fn fmt_s(v: f64) -> String {
    if v < 1e-3 {
        format!("{:.1} µs", v * 1e6)
    } else if v < 1.0 {
        format!("{:.2} ms", v * 1e3)
    } else {
        format!("{v:.2} s")
    }
}

fn markdown(r: &Report) -> String {
    let mut m = String::new();
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
        super::stability::MIN_STEPS,
        super::stability::ENERGY_FACTOR
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

    stiff_section(r, &mut m);

    let _ = writeln!(m, "## Conclusions from these measurements\n");
    for line in conclusions(r) {
        let _ = writeln!(m, "- {line}");
    }
    m
}

fn conclusions(r: &Report) -> Vec<String> {
    let mut c = Vec::new();
    // Orders.
    for p in &r.problems {
        let (mut good, mut off, mut none) = (Vec::new(), Vec::new(), Vec::new());
        for o in r.orders.iter().filter(|o| o.problem == p.name) {
            match o.observed {
                Some(v) if (v - o.theory as f64).abs() <= 0.3 => {
                    good.push(format!("{} {v:.2}", o.integrator))
                }
                Some(v) => off.push(format!("{} {v:.2} (theory {})", o.integrator, o.theory)),
                None => none.push(o.integrator.to_string()),
            }
        }
        let mut s = format!(
            "On the {}, the observed order is within 0.3 of theory for {}.",
            p.name,
            if good.is_empty() {
                "no integrator".to_string()
            } else {
                good.join(", ")
            }
        );
        if !off.is_empty() {
            let _ = write!(s, " It is not for {}.", off.join(", "));
        }
        if !none.is_empty() {
            let _ = write!(
                s,
                " Too few runs in the asymptotic range to fit: {}.",
                none.join(", ")
            );
        }
        c.push(s);
    }
    // Stability against theory.
    let ratios: Vec<(String, f64)> = (r.stability.iter())
        .filter(|row| {
            matches!(
                row.integrator,
                Integrator::SymplecticEuler | Integrator::Verlet | Integrator::Rk4
            )
        })
        .filter_map(|row| {
            let e = row.theory.exact(row.integrator)?;
            Some((
                format!("{} {} k={:.0e}", row.case, row.integrator, row.stiffness),
                row.measured.value()? / e,
            ))
        })
        .collect();
    if !ratios.is_empty() {
        let (lo, hi) = ratios
            .iter()
            .fold((f64::INFINITY, 0.0f64), |(a, b), (_, v)| {
                (a.min(*v), b.max(*v))
            });
        let worst = ratios
            .iter()
            .max_by(|a, b| (a.1 - 1.0).abs().total_cmp(&(b.1 - 1.0).abs()))
            .map(|(n, v)| format!("{n}: {v:.3}"))
            .unwrap_or_default();
        c.push(format!(
            "Symplectic Euler, Verlet and RK4: measured critical dt / theory from the exact eigenfrequency \
             lies in [{lo:.3}, {hi:.3}] over {} undamped cases (furthest from 1: {worst}).",
            ratios.len()
        ));
    }
    let span = |f: &dyn Fn(&Row) -> f64| {
        (r.stability.iter())
            .filter(|row| row.integrator == Integrator::SymplecticEuler)
            .map(f)
            .fold((f64::INFINITY, 0.0f64), |(a, b), v| (a.min(v), b.max(v)))
    };
    let (lo, hi) = span(&|row| row.theory.omega_exact / row.theory.omega_estimate);
    let (glo, ghi) = span(&|row| row.theory.omega_exact / row.theory.omega_gershgorin);
    if lo.is_finite() {
        c.push(format!(
            "The estimate the app uses gives a critical step {lo:.3} to {hi:.3} times the one from the \
             exact highest frequency (undamped); Gershgorin's bound, without positions, {glo:.2} to {ghi:.2}."
        ));
    }
    for i in [Integrator::ExplicitEuler, Integrator::Rk2] {
        let rows: Vec<&Row> = r
            .stability
            .iter()
            .filter(|row| row.integrator == i)
            .collect();
        let none = rows
            .iter()
            .filter(|row| matches!(row.measured, Measured::Below(_)))
            .count();
        let finite: Vec<String> = (rows.iter())
            .filter_map(|row| {
                let Measured::Transient { lo: v, .. } = row.measured else {
                    return None;
                };
                Some(format!(
                    "{} k={:.0e}: {:.3}× 2/omega",
                    row.case,
                    row.stiffness,
                    v * row.theory.omega_exact / 2.0
                ))
            })
            .collect();
        let mut s = format!(
            "{i} has no stable step on an undamped oscillator in theory; in {none} of {} undamped cases no \
             tried step was stable.",
            rows.len()
        );
        if !finite.is_empty() {
            let _ = write!(
                s,
                " Elsewhere a step stayed within the energy bound over the finite horizon only because the growth \
                 per step is small at small dt ({}); that is not stability.",
                finite.join("; ")
            );
        }
        c.push(s);
    }
    let implicit: Vec<&Row> = r
        .stability
        .iter()
        .filter(|row| row.integrator == Integrator::ImplicitEuler)
        .collect();
    let capped = implicit
        .iter()
        .filter(|row| matches!(row.measured, Measured::AtLeast(_)))
        .count();
    let min_factor = (implicit.iter())
        .filter_map(|row| match row.measured {
            Measured::AtLeast(x) => Some(x * row.theory.omega_exact / 2.0),
            _ => None,
        })
        .fold(f64::INFINITY, f64::min);
    c.push(format!(
        "Implicit Euler was stable at every step tried in {capped} of {} cases{}.",
        implicit.len(),
        if min_factor.is_finite() {
            format!(
                ", up to at least {min_factor:.0} times symplectic Euler's undamped limit 2/omega"
            )
        } else {
            String::new()
        }
    ));
    let damped: Vec<(String, f64)> = (r.damped.iter())
        .filter_map(|row| {
            let ratio = row.measured.value()?
                / damped_symplectic_limit(row.theory.omega_exact, row.damping / row.stiffness);
            Some((format!("{} b={}", row.case, row.damping), ratio))
        })
        .collect();
    if !damped.is_empty() {
        let close: Vec<&(String, f64)> = damped
            .iter()
            .filter(|(_, v)| (v - 1.0).abs() <= 0.05)
            .collect();
        let far: Vec<String> = (damped.iter())
            .filter(|(_, v)| (v - 1.0).abs() > 0.05)
            .map(|(n, v)| format!("{n} ({v:.3})"))
            .collect();
        let mut s = format!(
            "With spring damping, symplectic Euler's measured limit is within 5% of `omega² h (h + 2b/k) < 4` \
             in {} of {} cases.",
            close.len(),
            damped.len()
        );
        if !far.is_empty() {
            let _ = write!(s, " Not in: {}.", far.join(", "));
        }
        c.push(s);
    }
    let raw_missed: Vec<&Point> = r
        .points
        .iter()
        .filter(|p| p.outcome == Outcome::NoAccuracy)
        .collect();
    if !raw_missed.is_empty() {
        c.push(format!(
            "{} work-precision runs finished without tripping the divergence check although their error \
             exceeded the size of the motion (listed above): over short runs an instability can grow without \
             reaching the check's limits (100 km/s, 10,000 scene sizes).",
            raw_missed.len()
        ));
    }
    let refused = r
        .extreme
        .iter()
        .filter(|e| matches!(e.raw, super::extreme::Outcome::Refused(_)))
        .count();
    let caught = r
        .extreme
        .iter()
        .filter(|e| matches!(e.raw, super::extreme::Outcome::Caught { .. }))
        .count();
    let safe_bad: Vec<&str> = (r.extreme.iter())
        .filter(|e| matches!(e.safe, super::extreme::Outcome::Caught { .. }))
        .map(|e| e.case.name)
        .collect();
    c.push(format!(
        "Extreme cases: {} of {} were refused with a message, {caught} diverged as given and were caught, the rest \
         stayed finite. With safe stepping {}.",
        refused,
        r.extreme.len(),
        if safe_bad.is_empty() {
            "every case that was not refused stayed finite".to_string()
        } else {
            format!("these still diverged: {}", safe_bad.join(", "))
        }
    ));
    c
}

/// The families of the stiff-cloth study, for its plot and its conclusions.
const STIFF_FAMILIES: [Integrator; 3] = [
    Integrator::SymplecticEuler,
    Integrator::ImplicitEuler,
    Integrator::Xpbd,
];

fn stiff_plot(r: &Report, out: &Path) -> Result<(), String> {
    if r.stiff.is_empty() {
        return Ok(());
    }
    let best = stiff::cheapest_within_target(&r.stiff);
    let mut sides: Vec<u32> = r.stiff.iter().map(|row| row.side).collect();
    sides.dedup();
    let mut series = Vec::new();
    for (n, &side) in sides.iter().enumerate() {
        for family in STIFF_FAMILIES {
            let points: Vec<(f64, f64)> = (best.iter())
                .filter(|b| b.0 == side && b.2 == family)
                .map(|b| (b.1, b.3))
                .collect();
            series.push(Series {
                label: format!("{family}, {side}x{side}"),
                points,
                color: color(family),
                style: if n == 0 {
                    Style::LineAndMarkers
                } else {
                    Style::Dashed
                },
            });
        }
    }
    loglog(
        &out.join("stiff-cost.svg"),
        &format!(
            "Stiff cloth: cheapest run within {:.1} cm of the reference at t = {} s",
            stiff::TARGET_ERROR * 100.0,
            stiff::HORIZON
        ),
        "stiffness k (N/m)",
        "wall seconds per simulated second",
        &series,
    )
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

/// Per cloth and stiffness, which family was cheapest within the target error, and
/// where a family never met it.
fn stiff_conclusions(r: &Report) -> Vec<String> {
    let best = stiff::cheapest_within_target(&r.stiff);
    let mut lines = Vec::new();
    let mut keys: Vec<(u32, f64)> = r
        .stiff
        .iter()
        .map(|row| (row.side, row.stiffness))
        .collect();
    keys.dedup();
    for (side, k) in keys {
        let mut here: Vec<_> = best.iter().filter(|b| b.0 == side && b.1 == k).collect();
        here.sort_by(|a, b| a.3.total_cmp(&b.3));
        let text = match here.as_slice() {
            [] => format!(
                "no method came within {:.1} cm",
                stiff::TARGET_ERROR * 100.0
            ),
            [first, rest @ ..] => {
                let others: Vec<String> = rest
                    .iter()
                    .map(|b| format!("{} {:.1}x its cost", b.2, b.3 / first.3))
                    .collect();
                let missed: Vec<String> = (STIFF_FAMILIES.iter())
                    .filter(|f| !here.iter().any(|b| b.2 == **f))
                    .map(|f| f.to_string())
                    .collect();
                format!(
                    "{} is cheapest ({:.3e} s per simulated second){}{}",
                    first.2,
                    first.3,
                    if others.is_empty() {
                        String::new()
                    } else {
                        format!("; then {}", others.join(", "))
                    },
                    if missed.is_empty() {
                        String::new()
                    } else {
                        format!("; never within the target: {}", missed.join(", "))
                    }
                )
            }
        };
        lines.push(format!("{side}x{side}, k = {k:.0e} N/m: {text}."));
    }
    lines
}
