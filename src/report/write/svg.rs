//! The SVG plots: error against run time and against dt, critical dt against k,
//! and the stiff cloth's cost.

use std::path::Path;

use super::STIFF_FAMILIES;
use crate::report::plot::{Series, Style, loglog};
use crate::report::precision::{Outcome, Point, Problem, Reference};
use crate::report::stability::Row;
use crate::report::{Report, stiff};
use crate::sim::Integrator;

fn color(i: Integrator) -> usize {
    Integrator::ALL.iter().position(|&j| j == i).unwrap_or(0)
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

/// Writes the plots into `out`.
pub(super) fn plots(r: &Report, out: &Path) -> Result<(), String> {
    stiff_plot(r, out)?;
    for problem in &r.problems {
        problem_plots(r, problem, out)?;
    }
    stability_plot(r, out)
}

/// One problem's error against run time and against dt, and, with an exact
/// solution, its largest error over time.
fn problem_plots(r: &Report, problem: &Problem, out: &Path) -> Result<(), String> {
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
    Ok(())
}

/// Critical dt against k on the cloth.
fn stability_plot(r: &Report, out: &Path) -> Result<(), String> {
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
