//! Writes a [`Report`] as CSV files, SVG plots and `REPORT.md`; the conclusions in
//! `REPORT.md` are computed from the measurements, not written in advance.

mod conclusions;
mod csv;
mod markdown;
mod svg;

use std::path::Path;

use super::{Report, write_file};
use crate::sim::Integrator;
use csv::csvs;
use markdown::markdown;
use svg::plots;

/// A critical step as the tables write it: none, unlimited, or its value.
fn limit_text(v: Option<f64>) -> String {
    match v {
        None => "none".into(),
        Some(v) if v.is_infinite() => "unlimited".into(),
        Some(v) => format!("{v:.4e}"),
    }
}

/// Writes everything into `out`.
pub fn all(report: &Report, out: &Path) -> Result<(), String> {
    csvs(report, out)?;
    plots(report, out)?;
    write_file(out, "REPORT.md", &markdown(report))
}

/// The families of the stiff-cloth study, for its plot and its conclusions.
const STIFF_FAMILIES: [Integrator; 3] = [
    Integrator::SymplecticEuler,
    Integrator::ImplicitEuler,
    Integrator::Xpbd,
];
