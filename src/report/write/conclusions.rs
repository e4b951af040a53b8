//! The conclusions of `REPORT.md`, computed from the measurements.

use std::fmt::Write as _;

use super::STIFF_FAMILIES;
use crate::report::precision::{Outcome, Point};
use crate::report::stability::{Measured, Row, damped_symplectic_limit};
use crate::report::{Report, extreme, stiff};
use crate::sim::Integrator;

pub(super) fn conclusions(r: &Report) -> Vec<String> {
    let mut c = Vec::new();
    orders(r, &mut c);
    stability(r, &mut c);
    no_stable_step(r, &mut c);
    implicit(r, &mut c);
    damped(r, &mut c);
    not_caught(r, &mut c);
    extreme_cases(r, &mut c);
    c
}

/// Where the observed orders of convergence meet theory.
fn orders(r: &Report, c: &mut Vec<String>) {
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
}

/// Measured critical steps against theory, and the estimate and Gershgorin against the exact step.
fn stability(r: &Report, c: &mut Vec<String>) {
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
}

/// Explicit Euler and RK2, which have no stable step undamped.
fn no_stable_step(r: &Report, c: &mut Vec<String>) {
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
}

/// How far implicit Euler stayed stable.
fn implicit(r: &Report, c: &mut Vec<String>) {
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
}

/// Symplectic Euler's damped limit against the formula.
fn damped(r: &Report, c: &mut Vec<String>) {
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
}

/// Runs that lost all accuracy without tripping the divergence check.
fn not_caught(r: &Report, c: &mut Vec<String>) {
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
}

/// The extreme cases: refused, caught, and what safe stepping changed.
fn extreme_cases(r: &Report, c: &mut Vec<String>) {
    let refused = r
        .extreme
        .iter()
        .filter(|e| matches!(e.raw, extreme::Outcome::Refused(_)))
        .count();
    let caught = r
        .extreme
        .iter()
        .filter(|e| matches!(e.raw, extreme::Outcome::Caught { .. }))
        .count();
    let safe_bad: Vec<&str> = (r.extreme.iter())
        .filter(|e| matches!(e.safe, extreme::Outcome::Caught { .. }))
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
}

/// Per cloth and stiffness, which family was cheapest within the target error, and
/// where a family never met it.
pub(super) fn stiff_conclusions(r: &Report) -> Vec<String> {
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
