//! The help overlay (F1 or ?): every key and mouse binding of the app, from one
//! table that the overlay, the panel's hint and the README's keys table follow.

/// Every key and mouse binding: (input, what it does).
pub const BINDINGS: &[(&str, &str)] = &[
    ("Left click on a particle", "pin / unpin it"),
    (
        "Left drag on a particle",
        "move it (on the plane through it facing the camera)",
    ),
    (
        "Ctrl + left drag",
        "cut the cloth: break the springs the mouse's path crosses",
    ),
    (
        "Shift + left drag on a collider",
        "move it: it pushes and drags the cloth",
    ),
    (
        "Right drag, or left drag on empty space",
        "orbit the camera",
    ),
    ("Middle drag, or Shift + right drag", "pan"),
    ("Mouse wheel", "zoom"),
    ("W A S D / Q E", "fly forward, left, back, right / down, up"),
    ("F or Home", "reset the view (frame the scene)"),
    ("Space", "pause / resume"),
    (". (period)", "one frame (the steps of 1/60 s) while paused"),
    ("R", "reset the scene (keeps your edits and pins)"),
    (
        "G",
        "compare with a reference: error against RK4 at dt/2, drawn as a ghost",
    ),
    ("Ctrl+S", "save the setup as saved-<scene>-N.toml"),
    ("F12", "save the view as screenshot-N.png"),
    (
        "Ctrl+Z / Ctrl+Shift+Z or Ctrl+Y",
        "undo / redo a parameter or pin change",
    ),
    ("Drop a scene file on the window", "open it"),
    ("F1 or ?", "show / hide this help"),
    ("Tab", "hide / show the panel"),
    ("F2", "hide / show the readout in the view's corner"),
    ("Esc or P", "quit"),
];

/// Shows the help window while `open`; its close button clears `open`.
pub fn show(ctx: &egui::Context, open: &mut bool) {
    egui::Window::new("Help: keys and mouse")
        .open(open)
        .collapsible(false)
        .resizable(false)
        .anchor(egui::Align2::CENTER_CENTER, egui::Vec2::ZERO)
        .show(ctx, |ui| {
            egui::Grid::new("bindings")
                .num_columns(2)
                .striped(true)
                .spacing([16.0, 4.0])
                .show(ui, |ui| {
                    for (input, does) in BINDINGS {
                        ui.strong(*input);
                        ui.label(*does);
                        ui.end_row();
                    }
                });
            ui.separator();
            ui.label("Hover over a control in the panel for its meaning, unit and range.");
            ui.label("Keys work when the view has focus (click it first if a text field has it).");
        });
}
