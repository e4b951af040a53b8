//! The view's corner readout (F2 shows or hides it, as MuJoCo's): frame rate,
//! how the simulation keeps up with real time, simulated time, the engine and
//! the energy, where they stay in sight whatever the panel scrolls to.

use cloth_sandbox::session::Session;
use egui::{Color32, RichText};

/// Draws the readout in the top right corner of `view` (points).
pub fn show(ctx: &egui::Context, view: egui::Rect, session: &Session, frame_time: f64) {
    if !view.is_positive() {
        return;
    }
    let system = session.system();
    let pace = session.pace();
    let behind = pace.behind && pace.real_time_factor < 0.97 * pace.target;
    let plain = Color32::from_gray(235);
    let keeping = if behind {
        let text = format!(
            "{:.2}x real time, asked {:.2}x: slower",
            pace.real_time_factor, pace.target
        );
        (text, Color32::from_rgb(255, 200, 60))
    } else {
        (format!("{:.2}x real time", pace.real_time_factor), plain)
    };
    let mut lines = vec![
        (
            format!(
                "{:.0} frames/s · {:.1} ms",
                1.0 / frame_time.max(1e-6),
                frame_time * 1e3
            ),
            plain,
        ),
        keeping,
        (
            format!("t = {:.3} s · step {}", system.time(), system.steps_taken()),
            plain,
        ),
        (
            format!("engine {}", super::panel::engine_label(session)),
            plain,
        ),
        (format!("energy {:.4} J", system.energy().total()), plain),
    ];
    let error =
        (session.reference()).and_then(|r| r.samples().back().filter(|_| r.stopped().is_none()));
    if let Some(e) = error {
        let ghost = Color32::from_rgb(240, 110, 220);
        lines.push((
            format!("error {:.3} mm RMS vs reference", 1e3 * e.rms),
            ghost,
        ));
    }
    egui::Area::new(egui::Id::unique("corner readout"))
        .order(egui::Order::Foreground)
        .interactable(false)
        .pivot(egui::Align2::RIGHT_TOP)
        .fixed_pos(view.right_top() + egui::vec2(-8.0, 8.0))
        .show(ctx, |ui| {
            egui::Frame::new()
                .fill(Color32::from_black_alpha(150))
                .corner_radius(4.0)
                .inner_margin(6.0)
                .show(ui, |ui| {
                    for (text, color) in lines {
                        ui.label(RichText::new(text).monospace().color(color));
                    }
                });
        });
}
