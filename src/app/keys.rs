//! The app's keys: F1 and ? (help), Tab and F2 (panel, readout), Ctrl+S, Ctrl+Z
//! and Ctrl+Shift+Z, the fly keys, and the single keys of `help::BINDINGS`.

use winit::event::{ElementState, KeyEvent};
use winit::event_loop::ActiveEventLoop;
use winit::keyboard::{KeyCode, PhysicalKey};

use super::App;
use super::panel::Action;

impl App {
    /// One key pressed or released while the view, not the panel, has the keys.
    pub(super) fn key(&mut self, event: &KeyEvent, event_loop: &ActiveEventLoop) {
        let PhysicalKey::Code(code) = event.physical_key else {
            return;
        };
        let down = event.state == ElementState::Pressed;
        if down && !event.repeat && (code == KeyCode::F1 || event.text.as_deref() == Some("?")) {
            self.apply(Action::ToggleHelp, event_loop);
            return;
        }
        if down && !event.repeat && matches!(code, KeyCode::Tab | KeyCode::F2) {
            let toggle = if code == KeyCode::Tab {
                Action::TogglePanel
            } else {
                Action::ToggleReadout
            };
            self.apply(toggle, event_loop);
            return;
        }
        // Ctrl+S, Ctrl+Z, Ctrl+Shift+Z, Ctrl+Y. Only presses are taken: a release
        // still reaches the fly keys below, so S held before Ctrl never sticks.
        if down && self.modifiers.control_key() {
            let action = match code {
                KeyCode::KeyS => Some(Action::Save),
                KeyCode::KeyZ if self.modifiers.shift_key() => Some(Action::Redo),
                KeyCode::KeyZ => Some(Action::Undo),
                KeyCode::KeyY => Some(Action::Redo),
                _ => None,
            };
            if let Some(action) = action {
                if !event.repeat {
                    self.apply(action, event_loop);
                }
                return;
            }
        }
        match code {
            KeyCode::KeyW => self.fly.forward = down,
            KeyCode::KeyS => self.fly.back = down,
            KeyCode::KeyA => self.fly.left = down,
            KeyCode::KeyD => self.fly.right = down,
            KeyCode::KeyE => self.fly.up = down,
            KeyCode::KeyQ => self.fly.down = down,
            _ if !down || event.repeat => {}
            // Seed 000 quits on P as well as Esc.
            KeyCode::Escape | KeyCode::KeyP => self.apply(Action::Quit, event_loop),
            KeyCode::KeyR => self.apply(Action::Reset, event_loop),
            KeyCode::KeyG => {
                self.session.hold();
                let on = self.session.reference().is_none();
                self.apply(Action::Reference(on), event_loop);
            }
            KeyCode::Space => self.apply(Action::TogglePause, event_loop),
            KeyCode::KeyF | KeyCode::Home => self.apply(Action::ResetView, event_loop),
            KeyCode::Period => self.apply(Action::Step, event_loop),
            KeyCode::F12 => self.apply(Action::Screenshot, event_loop),
            _ => {}
        }
    }
}
