//! The CSV files: every number `REPORT.md` and the plots show.

use std::fmt::Write as _;
use std::path::Path;

use super::limit_text;
use crate::report::precision::{Outcome, Reference};
use crate::report::stability::{Measured, Row};
use crate::report::{Report, write_file};

fn opt(v: Option<f64>) -> String {
    v.map_or(String::new(), |v| format!("{v:e}"))
}

/// Writes the CSV files into `out`.
pub(super) fn csvs(r: &Report, out: &Path) -> Result<(), String> {
    write_file(out, "precision.csv", &precision(r))?;
    write_file(out, "references.csv", &references(r))?;
    write_file(out, "orders.csv", &orders(r))?;
    for (name, rows) in [("stability.csv", &r.stability), ("damping.csv", &r.damped)] {
        write_file(out, name, &critical_steps(rows))?;
    }
    write_file(out, "extreme.csv", &extreme(r))?;
    write_file(out, "stiff.csv", &stiff(r))?;
    write_file(out, "timings.csv", &timings(r))
}

/// Every work-precision run.
fn precision(r: &Report) -> String {
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
    s
}

/// Each problem's reference and its own error.
fn references(r: &Report) -> String {
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
    s
}

/// The observed orders of convergence.
fn orders(r: &Report) -> String {
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
    s
}

/// The critical steps of the stability or the damping study.
fn critical_steps(rows: &[Row]) -> String {
    let header = "case,stiffness,damping,integrator,measured_kind,measured_lo_s,measured_hi_s,theory_exact_s,estimate_s,gershgorin_s,omega_exact,omega_estimate,omega_gershgorin,zeta_exact,zeta_estimate,zeta_gershgorin,power_iterations,horizon_s\n";
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
    s
}

/// The extreme cases, as given and with safe stepping.
fn extreme(r: &Report) -> String {
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
    s
}

/// The stiff-cloth runs.
fn stiff(r: &Report) -> String {
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
    s
}

/// Wall time of each part.
fn timings(r: &Report) -> String {
    let mut s = String::from("part,wall_s\n");
    for (part, t) in &r.timings {
        let _ = writeln!(s, "{part},{t:.2}");
    }
    s
}
