//! The error against run time, live: a switch that runs the scene again beside
//! the one shown with RK4 at a finer step (`session::reference`), the error between
//! the two and what each costs per simulated second.

use cloth_sandbox::session::Session;
use cloth_sandbox::session::reference::{self, REFINE};
use egui::{Color32, RichText, Ui};

use super::Action;

pub(super) fn accuracy(ui: &mut Ui, session: &Session, actions: &mut Vec<Action>) {
    egui::CollapsingHeader::new("Error against a reference")
        .default_open(false)
        .show(ui, |ui| {
            let refused = reference::refusal(session.system());
            let mut on = session.reference().is_some();
            let label = format!("Compare with RK4 at dt/{REFINE} (ghost wireframe)");
            let hover = refused.clone().unwrap_or_else(|| {
                "Runs the same scene beside this one on its own thread, with RK4 on the \
                 f64 engine at a finer step, starting again from the shown state after \
                 every edit; the difference is this integrator's error."
                    .into()
            });
            let toggle =
                ui.add_enabled(refused.is_none() || on, egui::Checkbox::new(&mut on, label));
            if toggle
                .on_hover_text(hover)
                .on_disabled_hover_text(refused.unwrap_or_default())
                .changed()
            {
                actions.push(Action::Reference(on));
            }
            if let Some(live) = session.reference() {
                readings(ui, session, live, actions);
            }
        });
}

/// The error now, the two costs, why the reference stopped or lags, and the plot.
fn readings(ui: &mut Ui, session: &Session, live: &reference::Live, actions: &mut Vec<Action>) {
    if let Some(why) = live.stopped() {
        ui.colored_label(Color32::from_rgb(255, 170, 60), why);
        if let Some(factor) = session.slow_motion_for_reference() {
            let button = ui.button(format!("Run at {factor:.2}x and compare again"));
            let hover = "Slow motion to a speed the reference keeps up with, then start it again";
            if button.on_hover_text(hover).clicked() {
                actions.push(Action::SlowMotion(factor));
                actions.push(Action::RestartReference);
            }
        }
        return;
    }
    if let Some(last) = live.samples().back() {
        ui.label(format!(
            "error since the last edit: RMS {:.3} mm · max {:.3} mm (t = {:.2} s)",
            1e3 * last.rms,
            1e3 * last.max,
            last.time
        ));
    }
    let (shown, refined) = (session.cost(), live.cost());
    let ratio = if shown > 0.0 { refined / shown } else { 0.0 };
    ui.label(format!(
        "cost per simulated second: this run {:.3} s · reference {:.3} s ({ratio:.0}x)",
        shown, refined
    ))
    .on_hover_text("Wall-clock seconds each run spends stepping one simulated second.");
    if live.behind() {
        ui.label(
            RichText::new("The reference is slower than the run: it compares fewer frames.")
                .small()
                .color(Color32::from_rgb(255, 200, 60)),
        );
    }
    crate::app::plots::error_plot(ui, live);
}
