//! The display options: what the view draws, the strain colours' key, the
//! particle size and the background.

use egui::{Color32, RichText, Ui};

use super::{Action, PanelState};
use crate::render::ViewOptions;

/// The strain colours' key: compressed blue, at rest grey, stretched red to
/// pale yellow, saturating at 10%.
fn strain_legend(ui: &mut Ui) {
    let (rect, _) = ui.allocate_exact_size(
        egui::vec2(ui.available_width().min(240.0), 10.0),
        egui::Sense::hover(),
    );
    let painter = ui.painter_at(rect);
    let steps = 48;
    for i in 0..steps {
        let strain = -0.12 + 0.24 * (i as f32 + 0.5) / steps as f32;
        let [r, g, b, _] = crate::render::geometry::strain_color(strain);
        let linear = egui::Rgba::from_rgb(r, g, b);
        let x0 = rect.left() + rect.width() * i as f32 / steps as f32;
        let x1 = rect.left() + rect.width() * (i + 1) as f32 / steps as f32;
        let cell = egui::Rect::from_x_y_ranges(x0..=x1, rect.y_range());
        painter.rect_filled(cell, 0.0, Color32::from(linear));
    }
    ui.horizontal(|ui| {
        ui.label(RichText::new("-10% compressed").small());
        ui.label(RichText::new("· 0 ·").small());
        ui.label(RichText::new("+10% stretched").small());
    });
}

/// What the view draws, the particle size, the background, and the camera reset.
pub(super) fn display(
    ui: &mut Ui,
    state: &mut PanelState,
    view: &mut ViewOptions,
    actions: &mut Vec<Action>,
) {
    egui::CollapsingHeader::new("Display")
        .default_open(true)
        .show(ui, |ui| {
            ui.horizontal_wrapped(|ui| {
                ui.checkbox(&mut view.mesh, "mesh")
                    .on_hover_text("Draw the cloth surface, lit");
                ui.checkbox(&mut view.wireframe, "wireframe")
                    .on_hover_text("Draw the triangles' edges");
                ui.checkbox(&mut view.textured, "texture")
                    .on_hover_text("A checker texture on the surface, to show how it moves");
            });
            ui.horizontal_wrapped(|ui| {
                ui.checkbox(&mut view.springs, "springs")
                    .on_hover_text("Draw the springs as lines, coloured by kind");
                ui.checkbox(&mut state.strain_colors, "by strain")
                    .on_hover_text(
                        "Colour springs by strain (stretch over rest length) instead of kind",
                    );
            });
            if view.springs && state.strain_colors {
                strain_legend(ui);
            }
            ui.horizontal_wrapped(|ui| {
                ui.checkbox(&mut view.particles, "particles")
                    .on_hover_text("Draw every particle as a dot");
                ui.checkbox(&mut view.pins, "pins")
                    .on_hover_text("Mark the pinned particles in red");
                ui.checkbox(&mut view.shadows, "shadows")
                    .on_hover_text("Soft shadows from the key light, on the floor, the colliders and the cloth itself");
            });
            ui.add(egui::Slider::new(&mut view.particle_px, 2.0..=20.0).text("particle size (px)"))
                .on_hover_text("Diameter of the particle dots in screen pixels, 2 to 20");
            ui.horizontal(|ui| {
                ui.label("horizon");
                ui.color_edit_button_srgb(&mut view.background)
                    .on_hover_text("Colour of the sky at the horizon (the zenith follows it)");
                if ui
                    .button("Reset view")
                    .on_hover_text("Frame the scene with the default camera (F or Home)")
                    .clicked()
                {
                    actions.push(Action::ResetView);
                }
            });
        });
}
