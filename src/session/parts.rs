//! What the user places in a running scene besides its parameters: the pins and
//! the colliders, each recorded in the scene so that a reset, a rebuild and a
//! saved scene keep it, and each a step of undo.

use super::Session;
use crate::scene::{ColliderSpec, Pins, SceneError};

impl Session {
    /// Pins exactly the particles `pins` names (a preset such as the corners, a list,
    /// or none) and frees every other: recorded in the scene (key `pins`), so that a
    /// reset, a rebuild and a saved scene keep it, and applied to the running system
    /// in place, the rest of its state untouched. An index past the last particle is
    /// refused with an error naming `pins` and the range, and nothing changes. The
    /// change can be undone.
    pub fn set_pins(&mut self, pins: Pins) -> Result<(), SceneError> {
        let indices = self.settings.pin_indices(&pins)?;
        self.remember(self.scene.clone(), None, "pins".into());
        self.scene.spec.pins = Some(pins);
        self.settings.pins = indices;
        self.sync_pins();
        Ok(())
    }

    /// Pins particle `i` if it is free, frees it if pinned (a click): recorded in the
    /// scene as the list of pinned particles, and can be undone. An index past the
    /// last particle does nothing.
    pub fn toggle_pin(&mut self, i: usize) {
        if i >= self.system.particle_count() {
            return;
        }
        let mut pins = self.pins();
        match pins.binary_search(&i) {
            Ok(at) => {
                pins.remove(at);
            }
            Err(at) => pins.insert(at, i),
        }
        let what = format!("pin {i} toggled");
        self.remember(self.scene.clone(), None, what);
        self.scene.spec.pins = Some(Pins::Indices(pins.clone()));
        self.settings.pins = pins;
        self.sync_pins();
    }

    /// Pins and frees the running system's particles to match the settings.
    pub(super) fn sync_pins(&mut self) {
        let mut wanted = vec![false; self.system.particle_count()];
        for &i in &self.settings.pins {
            if let Some(w) = wanted.get_mut(i) {
                *w = true;
            }
        }
        for (i, pin) in wanted.into_iter().enumerate() {
            if self.system.is_pinned(i) != pin {
                self.system.set_pinned(i, pin);
            }
        }
    }

    /// Replaces the scene's colliders (the panel's Colliders section): each is
    /// checked as a scene file's `[[colliders]]` table is, and a bad one refused
    /// with its field named, changing nothing. One undo step per gesture.
    pub fn set_colliders(&mut self, colliders: Vec<ColliderSpec>) -> Result<(), SceneError> {
        let before = self.scene.clone();
        let mut scene = self.scene.clone();
        scene.spec.colliders = colliders;
        let settings = scene.resolve()?;
        self.commit(scene, settings, false);
        self.remember(before, Some("colliders"), "colliders".into());
        Ok(())
    }
}
