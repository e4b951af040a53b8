//! Mouse gestures on the scene: click a particle to pin it, press and drag a
//! particle to move it, Ctrl + left drag to cut the cloth, Shift + left drag on a
//! collider to move it, drag elsewhere to orbit
//! (left/right) or pan (middle, shift+right), wheel to zoom. Pure state machine:
//! the app applies the actions.

use glam::Vec2;

/// Pixels the cursor must travel after a press before it counts as a drag.
pub const DRAG_THRESHOLD_PX: f32 = 4.0;

/// What a mouse button is doing.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Gesture {
    /// No button held over the scene.
    Idle,
    /// Left button went down on particle `particle` at `start`; not yet a drag.
    Pressed { particle: usize, start: Vec2 },
    /// Left button is dragging `particle`.
    Dragging { particle: usize },
    /// Orbiting the camera.
    Orbit,
    /// Panning the camera.
    Pan,
    /// Cutting the springs the cursor's path crosses (Ctrl + left drag).
    Cutting,
    /// Moving collider `index` in the view plane (Shift + left drag on it).
    MovingCollider { index: usize },
}

/// Something the app should do in response to the mouse.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum MouseAction {
    /// Toggle the pin of a particle (a click without drag).
    TogglePin(usize),
    /// Start or continue dragging a particle towards the cursor.
    Drag { particle: usize, cursor: Vec2 },
    /// Stop dragging.
    Release,
    /// Orbit by this cursor motion (px).
    Orbit(Vec2),
    /// Pan by this cursor motion (px).
    Pan(Vec2),
    /// Cut the springs that the cursor's path from the first point to the second
    /// (px) crosses on screen.
    Cut(Vec2, Vec2),
    /// Move collider `index` towards the cursor (px).
    MoveCollider { index: usize, cursor: Vec2 },
    /// Stop moving the collider.
    ReleaseCollider(usize),
}

/// Mouse buttons the scene reacts to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Button {
    /// Primary button: pick, pin, drag; orbit on empty space.
    Left,
    /// Secondary: orbit (pan with shift).
    Right,
    /// Middle: pan.
    Middle,
}

/// The mouse state machine.
#[derive(Clone, Copy, Debug)]
pub struct Mouse {
    /// Current gesture.
    pub gesture: Gesture,
    /// Last cursor position (px), if the cursor is in the window.
    pub cursor: Option<Vec2>,
}

impl Default for Mouse {
    fn default() -> Self {
        Self {
            gesture: Gesture::Idle,
            cursor: None,
        }
    }
}

impl Mouse {
    /// A button went down over the scene with the modifiers `shift` and `ctrl`
    /// held; `picked` is the particle under the cursor.
    pub fn press(
        &mut self,
        button: Button,
        (shift, ctrl): (bool, bool),
        picked: Option<usize>,
    ) -> Option<MouseAction> {
        if self.gesture != Gesture::Idle {
            return None;
        }
        let start = self.cursor?;
        self.gesture = match (button, picked) {
            (Button::Left, _) if ctrl => Gesture::Cutting,
            (Button::Left, Some(particle)) => Gesture::Pressed { particle, start },
            (Button::Left, None) => Gesture::Orbit,
            (Button::Right, _) if shift => Gesture::Pan,
            (Button::Right, _) => Gesture::Orbit,
            (Button::Middle, _) => Gesture::Pan,
        };
        None
    }

    /// Shift + left button went down over collider `index`: a drag moves it.
    pub fn press_collider(&mut self, index: usize) {
        if self.gesture == Gesture::Idle && self.cursor.is_some() {
            self.gesture = Gesture::MovingCollider { index };
        }
    }

    /// The cursor moved to `to`.
    pub fn moved(&mut self, to: Vec2) -> Option<MouseAction> {
        let from = self.cursor.replace(to);
        let delta = from.map_or(Vec2::ZERO, |f| to - f);
        match self.gesture {
            Gesture::Idle => None,
            Gesture::Pressed { particle, start } => {
                if to.distance(start) > DRAG_THRESHOLD_PX {
                    self.gesture = Gesture::Dragging { particle };
                    Some(MouseAction::Drag {
                        particle,
                        cursor: to,
                    })
                } else {
                    None
                }
            }
            Gesture::Dragging { particle } => Some(MouseAction::Drag {
                particle,
                cursor: to,
            }),
            Gesture::Orbit => Some(MouseAction::Orbit(delta)),
            Gesture::Pan => Some(MouseAction::Pan(delta)),
            Gesture::Cutting => from.map(|from| MouseAction::Cut(from, to)),
            Gesture::MovingCollider { index } => {
                Some(MouseAction::MoveCollider { index, cursor: to })
            }
        }
    }

    /// A button went up (anywhere: releases are never swallowed, so a drag
    /// that ends over the panel still ends).
    pub fn release(&mut self, button: Button) -> Option<MouseAction> {
        let action = match (self.gesture, button) {
            (Gesture::Pressed { particle, .. }, Button::Left) => {
                Some(MouseAction::TogglePin(particle))
            }
            (Gesture::Dragging { .. }, Button::Left) => Some(MouseAction::Release),
            (Gesture::MovingCollider { index }, Button::Left) => {
                Some(MouseAction::ReleaseCollider(index))
            }
            (Gesture::Orbit, Button::Left | Button::Right)
            | (Gesture::Pan, Button::Right | Button::Middle)
            | (Gesture::Cutting, Button::Left) => None,
            _ => return None,
        };
        self.gesture = Gesture::Idle;
        action
    }

    /// The particle being dragged, if any.
    pub fn dragged(&self) -> Option<usize> {
        match self.gesture {
            Gesture::Dragging { particle } => Some(particle),
            _ => None,
        }
    }

    /// Forget any gesture (scene reset or focus lost); returns `Release` (or
    /// `ReleaseCollider`) if a drag was in progress.
    pub fn cancel(&mut self) -> Option<MouseAction> {
        let action = match self.gesture {
            Gesture::Dragging { .. } => Some(MouseAction::Release),
            Gesture::MovingCollider { index } => Some(MouseAction::ReleaseCollider(index)),
            _ => None,
        };
        self.gesture = Gesture::Idle;
        action
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shift_drag_on_a_collider_moves_it_until_release() {
        let mut m = Mouse::default();
        m.moved(Vec2::new(10.0, 10.0));
        m.press_collider(2);
        let to = Vec2::new(30.0, 12.0);
        assert_eq!(
            m.moved(to),
            Some(MouseAction::MoveCollider {
                index: 2,
                cursor: to
            })
        );
        assert_eq!(
            m.release(Button::Left),
            Some(MouseAction::ReleaseCollider(2))
        );
        assert_eq!(m.gesture, Gesture::Idle);
    }

    #[test]
    fn click_without_motion_toggles_pin() {
        let mut m = Mouse::default();
        m.moved(Vec2::new(10.0, 10.0));
        m.press(Button::Left, (false, false), Some(3));
        m.moved(Vec2::new(11.0, 10.0));
        assert_eq!(m.release(Button::Left), Some(MouseAction::TogglePin(3)));
    }

    #[test]
    fn ctrl_drag_cuts_along_the_path_even_from_a_particle() {
        let mut m = Mouse::default();
        m.moved(Vec2::new(10.0, 10.0));
        m.press(Button::Left, (false, true), Some(3));
        assert_eq!(
            m.moved(Vec2::new(30.0, 10.0)),
            Some(MouseAction::Cut(
                Vec2::new(10.0, 10.0),
                Vec2::new(30.0, 10.0)
            ))
        );
        assert_eq!(m.release(Button::Left), None);
        assert_eq!(m.gesture, Gesture::Idle);
    }

    #[test]
    fn press_and_drag_moves_then_releases() {
        let mut m = Mouse::default();
        m.moved(Vec2::new(10.0, 10.0));
        m.press(Button::Left, (false, false), Some(3));
        assert!(matches!(
            m.moved(Vec2::new(30.0, 10.0)),
            Some(MouseAction::Drag { particle: 3, .. })
        ));
        assert_eq!(m.release(Button::Left), Some(MouseAction::Release));
        assert_eq!(m.gesture, Gesture::Idle);
    }
}
