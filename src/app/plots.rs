//! Live plots for the panel: the energy (kinetic, elastic, gravity, total) and
//! the stability margin `dt / dt_crit` over the last seconds of simulated time,
//! drawn with egui's painter (one polyline per series).

use std::collections::VecDeque;

use cloth_sandbox::sim::System;
use egui::{Color32, Pos2, Rect, Stroke, Ui, Vec2};

/// Simulated seconds the plots show.
pub const WINDOW_S: f64 = 10.0;

/// Most samples kept (the window at 100 frames/s).
const MAX_SAMPLES: usize = 1000;

/// One frame's readings.
#[derive(Clone, Copy, Debug)]
struct Sample {
    time: f64,
    kinetic: f64,
    elastic: f64,
    gravity: f64,
    margin: f64,
}

/// The readings of the last [`WINDOW_S`] simulated seconds, one per drawn frame.
#[derive(Default)]
pub struct History {
    samples: VecDeque<Sample>,
}

impl History {
    /// Adds `system`'s readings now, once per simulated time; a time earlier than
    /// the last (a reset, a new scene, an undo) starts the plots again.
    pub fn record(&mut self, system: &System) {
        let time = system.time();
        match self.samples.back() {
            Some(last) if last.time == time => return,
            Some(last) if last.time > time => self.samples.clear(),
            _ => {}
        }
        let energy = system.energy();
        self.samples.push_back(Sample {
            time,
            kinetic: energy.kinetic,
            elastic: energy.elastic,
            gravity: energy.gravity,
            margin: system.stability().margin,
        });
        while self.samples.len() > MAX_SAMPLES
            || self
                .samples
                .front()
                .is_some_and(|s| s.time < time - WINDOW_S)
        {
            self.samples.pop_front();
        }
    }

    /// The two plots.
    pub fn show(&self, ui: &mut Ui) {
        if self.samples.len() < 2 {
            ui.label("The plots fill in as the simulation runs.");
            return;
        }
        // Gravity's energy and the total are often a thousand times the motion's:
        // each pair gets its own scale.
        let motion = [
            (
                "kinetic",
                Color32::from_rgb(90, 170, 255),
                self.series(|s| s.kinetic),
            ),
            (
                "elastic",
                Color32::from_rgb(255, 150, 60),
                self.series(|s| s.elastic),
            ),
        ];
        ui.label("Kinetic and elastic energy (J)");
        plot(ui, &motion, None, &[]);
        let whole = [
            (
                "gravity",
                Color32::from_rgb(120, 210, 120),
                self.series(|s| s.gravity),
            ),
            (
                "total",
                Color32::from_rgb(230, 230, 230),
                self.series(|s| s.kinetic + s.elastic + s.gravity),
            ),
        ];
        ui.label("Gravity's and total energy (J)");
        plot(ui, &whole, None, &[]);
        let margin = self.series(|s| s.margin);
        if margin.iter().all(|(_, m)| *m == 0.0) {
            ui.label("dt / dt_crit: no step limit for this integrator.");
        } else {
            ui.label("Stability dt / dt_crit (unstable above 1)");
            let series = [("dt / dt_crit", Color32::from_rgb(255, 200, 60), margin)];
            plot(ui, &series, Some(1.0), &[]);
        }
    }

    fn series(&self, value: impl Fn(&Sample) -> f64) -> Vec<(f64, f64)> {
        self.samples.iter().map(|s| (s.time, value(s))).collect()
    }
}

/// One line of a plot: its name, colour and (time, value) points.
type Series<'a> = (&'a str, Color32, Vec<(f64, f64)>);

/// Height (points) of one plot.
const PLOT_HEIGHT: f32 = 70.0;

/// Draws `series` (name, colour, (time, value) points) in one frame sharing its
/// axes, with the value range written at the left and a legend below; `line`
/// draws a dashed level (e.g. the stability limit 1) when in range or near it,
/// and `marks` thin vertical lines at those times.
fn plot(ui: &mut Ui, series: &[Series<'_>], line: Option<f64>, marks: &[f64]) {
    let finite = |v: &f64| v.is_finite();
    let points = series.iter().flat_map(|(_, _, p)| p.iter());
    let (mut t0, mut t1) = (f64::INFINITY, f64::NEG_INFINITY);
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for &(t, v) in points.filter(|(t, v)| finite(t) && finite(v)) {
        (t0, t1) = (t0.min(t), t1.max(t));
        (lo, hi) = (lo.min(v), hi.max(v));
    }
    if let Some(level) = line {
        (lo, hi) = (lo.min(0.0), hi.max(level * 1.1));
    }
    if !(t1 > t0 && lo.is_finite() && hi.is_finite()) {
        return;
    }
    if hi - lo < 1e-12 * hi.abs().max(1e-12) {
        (lo, hi) = (lo - 0.5, hi + 0.5);
    }
    let (rect, _) = ui.allocate_exact_size(
        Vec2::new(ui.available_width(), PLOT_HEIGHT),
        egui::Sense::hover(),
    );
    let painter = ui.painter_at(rect);
    painter.rect_filled(rect, 2.0, Color32::from_gray(25));
    let to_screen = |t: f64, v: f64| {
        Pos2::new(
            rect.left() + ((t - t0) / (t1 - t0)) as f32 * rect.width(),
            rect.bottom() - ((v - lo) / (hi - lo)) as f32 * rect.height(),
        )
    };
    if let Some(level) = line {
        let y = to_screen(t0, level).y;
        painter.add(egui::Shape::dashed_line(
            &[Pos2::new(rect.left(), y), Pos2::new(rect.right(), y)],
            Stroke::new(1.0, Color32::from_rgb(255, 90, 80)),
            4.0,
            3.0,
        ));
    }
    for &t in marks.iter().filter(|t| (t0..=t1).contains(*t)) {
        let x = to_screen(t, lo).x;
        let ends = [Pos2::new(x, rect.top()), Pos2::new(x, rect.bottom())];
        painter.line_segment(ends, Stroke::new(1.0, Color32::from_gray(90)));
    }
    for (_, color, points) in series {
        let line: Vec<Pos2> = points
            .iter()
            .filter(|(t, v)| finite(t) && finite(v))
            .map(|&(t, v)| to_screen(t, v))
            .collect();
        painter.add(egui::Shape::line(line, Stroke::new(1.5, *color)));
    }
    let text = |pos: Pos2, anchor, s: String| {
        painter.text(pos, anchor, s, egui::FontId::monospace(10.0), Color32::GRAY)
    };
    let inner = rect.shrink(2.0);
    text(
        inner.left_top(),
        egui::Align2::LEFT_TOP,
        format!("{hi:.3e}"),
    );
    text(
        inner.left_bottom(),
        egui::Align2::LEFT_BOTTOM,
        format!("{lo:.3e}"),
    );
    text(
        inner.right_bottom(),
        egui::Align2::RIGHT_BOTTOM,
        format!("t = {t0:.1} to {t1:.1} s"),
    );
    legend(ui, series.iter().map(|(name, color, _)| (*name, *color)));
}

/// The live reference's RMS and largest position error (mm) over simulated
/// time, a thin line at each restart after an edit.
pub fn error_plot(ui: &mut Ui, live: &cloth_sandbox::session::reference::Live) {
    let samples = live.samples();
    if samples.len() < 2 {
        ui.label("The error plot fills in as the simulation runs.");
        return;
    }
    let of = |value: fn(&cloth_sandbox::session::reference::ErrorSample) -> f64| {
        samples.iter().map(|s| (s.time, 1e3 * value(s))).collect()
    };
    let series = [
        ("RMS error", Color32::from_rgb(90, 170, 255), of(|s| s.rms)),
        ("max error", Color32::from_rgb(255, 110, 200), of(|s| s.max)),
    ];
    ui.label("Position error against the reference (mm)");
    let restarts: Vec<f64> = live.restarts().iter().copied().collect();
    plot(ui, &series, None, &restarts);
}

fn legend<'a>(ui: &mut Ui, entries: impl Iterator<Item = (&'a str, Color32)>) {
    ui.horizontal_wrapped(|ui| {
        for (name, color) in entries {
            let (rect, _) = ui.allocate_exact_size(Vec2::new(12.0, 3.0), egui::Sense::hover());
            ui.painter().rect_filled(
                Rect::from_center_size(rect.center(), rect.size()),
                0.0,
                color,
            );
            ui.label(egui::RichText::new(name).small());
        }
    });
}
