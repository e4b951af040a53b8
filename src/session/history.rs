//! Undo and redo: each change of the setup (an edit, pins, colliders, the
//! defaults) and each cut of the cloth is one step back, in the order made.

use super::Session;
use crate::scene::{Scene, SceneError};
use crate::sim::{Spring, State};

/// One step of the history.
#[derive(Clone, Debug)]
pub(super) enum Change {
    /// The setup as it was before a change: taking it back restores it.
    Setup(Box<Scene>),
    /// Springs a cut removed and the triangles along them: taking it back mends them.
    Cut(Cut),
    /// A cut taken back: taking that back cuts the same springs again.
    Recut(Cut),
}

/// What one cut gesture removed, and the state just before it.
#[derive(Clone, Debug)]
pub(super) struct Cut {
    springs: Vec<Spring>,
    triangles: Vec<[u32; 3]>,
    /// Taking a cut back puts the cloth where it was when it was cut: a piece
    /// cut off may have fallen far since, and a spring mended across that gap
    /// would throw it back with the energy of the whole stretch.
    before: State,
}

impl Session {
    /// Records `before`, the setup before a change described as `what`, for
    /// [`Self::undo`], and forgets what was undone. A change of the same `group`
    /// (edit key) as the last one, within one gesture, adds no entry.
    pub(super) fn remember(&mut self, before: Scene, group: Option<&'static str>, what: String) {
        self.last_edit = Some((what, self.system.time()));
        if group.is_some() && group == self.edit_group {
            return;
        }
        self.push_change(Change::Setup(Box::new(before)));
        self.edit_group = group;
    }

    /// Ends the gesture that groups edits of one key into one undo step: the next
    /// edit makes a new one.
    pub fn end_edit_group(&mut self) {
        self.edit_group = None;
    }

    fn push_change(&mut self, change: Change) {
        if self.undo.len() >= super::MAX_UNDO {
            self.undo.remove(0);
        }
        self.undo.push(change);
        self.redo.clear();
    }

    /// Cuts the springs joining any of `pairs` (Ctrl + drag; see
    /// [`crate::sim::System::cut`]) as a step of undo: the moves of one gesture
    /// (`continues`: this is not its first) make one step. Returns how many were cut.
    pub fn cut(&mut self, pairs: &[(usize, usize)], continues: bool) -> usize {
        let springs = self.system.springs().to_vec();
        let triangles = self.system.triangles().to_vec();
        let before = self.system.state().clone();
        let count = self.system.cut(pairs);
        if count == 0 {
            return 0;
        }
        let removed = Cut {
            springs: missing(&springs, self.system.springs()),
            triangles: missing(&triangles, self.system.triangles()),
            before,
        };
        self.last_edit = Some((format!("cut {count} springs"), self.system.time()));
        // The app ends edit groups every frame the pointer is off the panel, so
        // the gesture is the caller's word, and only a cut can be the last step.
        match self.undo.last_mut() {
            Some(Change::Cut(last)) if continues => {
                // The gesture's first move keeps the state before it.
                last.springs.extend(removed.springs);
                last.triangles.extend(removed.triangles);
            }
            _ => self.push_change(Change::Cut(removed)),
        }
        self.edit_group = None;
        count
    }

    /// Whether there is a change to undo.
    pub fn can_undo(&self) -> bool {
        !self.undo.is_empty()
    }

    /// Whether there is an undone change to redo.
    pub fn can_redo(&self) -> bool {
        !self.redo.is_empty()
    }

    /// Takes back the last change (Ctrl+Z): a setup comes back, applied in place
    /// as edits are, or by a rebuild where the layout differs; after a cut, the
    /// springs it removed come back, on the cloth as it was when cut. Returns
    /// whether there was anything to undo.
    pub fn undo(&mut self) -> Result<bool, SceneError> {
        let Some(change) = self.undo.pop() else {
            return Ok(false);
        };
        let taken = self.take_back(&change);
        match taken {
            Ok(inverse) => self.redo.push(inverse),
            Err(e) => {
                self.undo.push(change);
                return Err(e);
            }
        }
        self.edit_group = None;
        Ok(true)
    }

    /// Does again the last change undone (Ctrl+Shift+Z). Returns whether there was
    /// anything to redo.
    pub fn redo(&mut self) -> Result<bool, SceneError> {
        let Some(change) = self.redo.pop() else {
            return Ok(false);
        };
        let taken = self.take_back(&change);
        match taken {
            Ok(inverse) => self.undo.push(inverse),
            Err(e) => {
                self.redo.push(change);
                return Err(e);
            }
        }
        self.edit_group = None;
        Ok(true)
    }

    /// Takes back `change`, returning the change that takes that back in turn;
    /// on error nothing changed.
    fn take_back(&mut self, change: &Change) -> Result<Change, SceneError> {
        match change {
            Change::Setup(scene) => {
                let current = Box::new(self.scene.clone());
                self.restore((**scene).clone())?;
                Ok(Change::Setup(current))
            }
            Change::Cut(cut) => {
                self.system.mend(&cut.springs, &cut.triangles);
                self.system.set_state(cut.before.clone());
                self.last_good.clone_from(&cut.before);
                // The springs and triangles back change the critical step.
                self.choose_step();
                Ok(Change::Recut(cut.clone()))
            }
            Change::Recut(cut) => {
                let pairs: Vec<(usize, usize)> = (cut.springs.iter())
                    .map(|s| (s.a as usize, s.b as usize))
                    .collect();
                self.system.cut(&pairs);
                Ok(Change::Cut(cut.clone()))
            }
        }
    }
}

/// The items of `before` missing from `after`, a subsequence of it (what
/// `retain` left).
fn missing<T: PartialEq + Copy>(before: &[T], after: &[T]) -> Vec<T> {
    let mut kept = after.iter().peekable();
    let mut gone = Vec::new();
    for item in before {
        if kept.peek() == Some(&item) {
            kept.next();
        } else {
            gone.push(*item);
        }
    }
    gone
}
