//! The live stats: counts, the physics' and the frame's cost, time, energy,
//! stability, the limiters and the engine.

use cloth_sandbox::session::Session;
use cloth_sandbox::sim::{Integrator, System};
use egui::{Color32, RichText, Ui};

use super::PanelState;

/// Counts, the physics' and the frame's cost, time, energy, stability, the
/// limiters and the engine.
pub(super) fn stats(ui: &mut Ui, state: &PanelState, session: &Session, adapter: &str) {
    let system = session.system();
    let p = session.settings().params;
    egui::CollapsingHeader::new("Stats")
        .default_open(true)
        .show(ui, |ui| {
            ui.label(format!(
                "particles {} · springs {} · bars {} · triangles {}",
                system.particle_count(),
                system.springs().len(),
                system.bars().len(),
                system.triangles().len()
            ));
            let pace = session.pace();
            ui.label(format!(
                "physics {:.3} ms/step · {:.0} steps/s · busy {:.0}%",
                session.ms_per_step(),
                pace.steps_per_second,
                pace.busy * 100.0
            ))
            .on_hover_text("The physics thread's cost: wall time per step, steps per wall second, and the share of wall time it spends stepping.");
            ui.label(format!(
                "frame {:.1} ms ({:.0} frames/s)",
                state.frame_time * 1e3,
                1.0 / state.frame_time.max(1e-6)
            ));
            ui.label(format!(
                "t = {:.3} s · step {}",
                system.time(),
                system.steps_taken()
            ));
            let e = system.energy();
            ui.label(format!(
                "energy {:.4} J (kinetic {:.4}, gravity {:.4}, elastic {:.4})",
                e.total(),
                e.kinetic,
                e.gravity,
                e.elastic
            ));
            stability(ui, system, p.integrator);
            if let Some(budget) = system.energy_budget() {
                // How much of the energy rise the budget allows is used.
                let used = (e.total() - budget.base) / budget.allowed;
                let color = if used >= 0.5 {
                    Color32::from_rgb(255, 200, 60)
                } else {
                    Color32::from_rgb(120, 220, 120)
                };
                ui.colored_label(
                    color,
                    format!("energy budget used {:.0}%", 100.0 * used.max(0.0)),
                )
                .on_hover_text(format!(
                    "The run counts as diverged when its energy rises more than {:.3e} J \
                         above the {:.3e} J it had at the start or the last edit",
                    budget.limit() - budget.base,
                    budget.base
                ));
            }
            if system.broken_springs() > 0 {
                ui.label(format!("broken springs {}", system.broken_springs()));
            }
            if p.max_speed.is_some() || p.stretch_limit.is_some() || p.tear_strain.is_some() {
                let activity = system.limiter_activity();
                let held: Vec<String> = (activity.working())
                    .map(|(l, n, of)| l.holding(n, of))
                    .collect();
                if !held.is_empty() {
                    ui.label(format!("limiters hold {}", held.join(", ")));
                }
                if let Some(warning) = activity.warning() {
                    ui.colored_label(Color32::from_rgb(255, 200, 60), warning);
                }
            }
            if p.self_collision {
                ui.label(format!(
                    "self-collision contacts {}",
                    system.self_collision_contacts()
                ));
            }
            ui.label(format!("engine {}", engine_label(session)));
            ui.label(RichText::new(format!("adapter: {adapter}")).small());
        });
}

/// The engine stepping the session: the GPU engine and its adapter, or the CPU
/// engine with its threads.
pub(crate) fn engine_label(session: &Session) -> String {
    match session
        .gpu_adapter()
        .filter(|_| session.gpu_problem().is_none())
    {
        Some(adapter) => format!("gpu on {}", adapter.name),
        None => {
            let system = session.system();
            system.engine().label(system.engine_threads())
        }
    }
}

/// dt / dt_crit, coloured by how close it is to 1, or why there is no limit.
fn stability(ui: &mut Ui, system: &System, integrator: Integrator) {
    let s = system.stability();
    let margin = s.margin;
    let color = if !margin.is_finite() || margin >= 1.0 {
        Color32::from_rgb(255, 90, 80)
    } else if margin >= 0.7 {
        Color32::from_rgb(255, 200, 60)
    } else {
        Color32::from_rgb(120, 220, 120)
    };
    match s.dt_critical {
        Some(c) if c.is_infinite() => {
            let why = if s.omega_max == 0.0 {
                "nothing here oscillates on a step: bars and constraints only \
                 (XPBD's springs are constraints)"
            } else {
                "this integrator is stable at any dt"
            };
            ui.label(format!("stability: no step limit ({why})"));
        }
        Some(c) => {
            ui.colored_label(
                color,
                format!("stability dt / dt_crit = {margin:.3} (dt_crit {c:.3e} s)"),
            );
        }
        None => {
            ui.colored_label(
                color,
                format!("stability: {integrator} has no stable step here without damping"),
            );
        }
    }
}
