//! A run that diverged: the report the app shows (what happened, its cause in
//! plain words, the edit made before it), and the way back ("Undo that edit").

use super::Session;
use crate::scene::SceneError;
use crate::sim::Divergence;

/// How long (simulated s) after an edit a divergence is put down to it.
const EDIT_BLAME_S: f64 = 2.0;

/// What happened when the simulation diverged.
#[derive(Clone, Debug, PartialEq)]
pub struct DivergenceReport {
    /// The core's description (what and when).
    pub message: String,
    /// Simulated time (s) of the divergence.
    pub time: f64,
    /// Stability margin `dt / dt_crit` at the time, if the estimate has one.
    pub margin: Option<f64>,
    /// Simulated time (s) of the state on screen: the last frame that passed its
    /// checks, put back so that the view freezes on it rather than on the wreck.
    pub shown_time: f64,
    /// The last change of the setup (`key = value`) and how long (simulated s)
    /// before the divergence it was made, if one was made since the start.
    pub edit: Option<(String, f64)>,
    /// Why, in plain words, and what to do about it.
    pub cause: String,
}

impl Session {
    /// Puts back the last state that passed its checks and pauses with the report.
    pub(super) fn diverged(&mut self, d: Divergence) {
        let margin = Some(self.system.stability().margin).filter(|m| m.is_finite());
        log::warn!("simulation diverged: {d}");
        self.system.release();
        self.system.set_state(self.last_good.clone());
        let edit = (self.last_edit.clone()).map(|(what, at)| (what, (d.time() - at).max(0.0)));
        self.divergence = Some(DivergenceReport {
            message: d.to_string(),
            time: d.time(),
            margin,
            shown_time: self.system.time(),
            cause: cause(&d, margin, self.safe_stepping, edit.as_ref()),
            edit,
        });
        self.paused = true;
    }

    /// Takes back the last change of the setup after a divergence ("Undo that
    /// edit"): the setup before it, on the last state that passed its checks,
    /// running again. Returns whether there was a divergence and a change to
    /// take back; otherwise nothing changes.
    pub fn undo_divergence(&mut self) -> Result<bool, SceneError> {
        if self.divergence.is_none() || !self.can_undo() {
            return Ok(false);
        }
        // The last good state is on screen already ([`Session::diverged`]); the
        // undo applies to it in place (a rest length rescales it back).
        self.undo()?;
        self.divergence = None;
        self.paused = false;
        Ok(true)
    }
}

/// The cause of `d` in plain words: the step when it was past its limit,
/// otherwise (the step being stable) the edit just made, or what else can push
/// a cloth harder than its springs hold.
fn cause(d: &Divergence, margin: Option<f64>, safe: bool, edit: Option<&(String, f64)>) -> String {
    let remedy = if safe {
        "lower dt, or choose implicit Euler or XPBD"
    } else {
        "turn safe stepping on, lower dt, or choose implicit Euler or XPBD"
    };
    let held_back = matches!(d, Divergence::HeldBack { .. });
    match margin {
        Some(m) if m >= 0.9 || held_back => {
            format!("The step is at or past its stability limit (dt / dt_crit = {m:.2}): {remedy}.")
        }
        None if held_back => format!("No step is stable for this integrator here: {remedy}."),
        _ => {
            let within = match margin {
                Some(m) => format!(
                    "The step was within its stability limit (dt / dt_crit = {m:.2}), so dt is not the cause: "
                ),
                None => "The step is not the cause: ".to_string(),
            };
            let why = match edit {
                Some((what, ago)) if *ago <= EDIT_BLAME_S => format!(
                    "the edit {what}, {ago:.2} s before, changed the cloth faster than its springs could follow. Undo it, or make it in smaller moves."
                ),
                _ => "something pushed the cloth harder than its springs hold: a contact thickness or self-collision, a collider, a fast drag, or a force. Reset, or undo the last edit.".to_string(),
            };
            within + &why
        }
    }
}
