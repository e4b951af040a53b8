//! The physics thread: the session steps on a thread of its own, so that a slow
//! renderer (a software adapter drawing a 256² cloth) no longer throttles the
//! simulation. Pacing stays fixed-step: the thread calls [`Session::advance`]
//! with the wall time since its last call, in chunks of at most [`CHUNK_MS`], and
//! the simulation keeps real time whenever its own cost allows, however slow the
//! frames are.
//!
//! One thread at a time holds the session. The window's thread takes it for each
//! event that reads or edits it (an action, a grab, a pin; not the cursor moving
//! over the panel, which picks from the positions last drawn) and for the part of
//! a frame that does (the panel, copying the positions to draw), and hands it
//! back before drawing; the physics thread steps it in between. The window's
//! thread goes first: while it waits, the physics thread does not take the
//! session again. So the view shows the latest finished state, never one half
//! stepped, and an edit never races a step.

use std::ops::{Deref, DerefMut};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Condvar, Mutex, MutexGuard, PoisonError};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use cloth_sandbox::session::Session;

/// Most wall-clock milliseconds the physics thread steps before it hands the
/// session back: the longest the window's thread waits for it.
pub const CHUNK_MS: f64 = 4.0;

/// Longest stretch of wall time (s) one [`Session::advance`] call is given; a
/// longer one (the machine stalled) is dropped rather than caught up.
const MAX_ELAPSED: f64 = 0.25;

/// How long the physics thread sleeps when no step was due (paused, or ahead of
/// the wall clock).
const IDLE_SLEEP: Duration = Duration::from_micros(500);

/// What the two threads share.
struct Shared {
    /// The session, when neither thread holds it.
    slot: Mutex<Option<Session>>,
    /// Signalled whenever the session goes back into the slot.
    returned: Condvar,
    /// The window's thread is waiting for the session: the physics thread leaves
    /// it in the slot.
    ui_waiting: AtomicBool,
    /// The app is closing: the physics thread stops.
    quit: AtomicBool,
    /// Why the physics thread stopped, if it stopped on a panic.
    failure: Mutex<Option<String>>,
}

impl Shared {
    fn slot(&self) -> MutexGuard<'_, Option<Session>> {
        self.slot.lock().unwrap_or_else(PoisonError::into_inner)
    }

    fn put_back(&self, session: Session) {
        *self.slot() = Some(session);
        self.returned.notify_all();
    }
}

/// The session, stepped on the physics thread and read or edited on the window's
/// thread. While the window's thread holds it ([`SharedSession::hold`]) it
/// dereferences to the [`Session`]; reading it while released is a bug and panics.
pub struct SharedSession {
    shared: Arc<Shared>,
    held: Option<Session>,
    thread: Option<JoinHandle<()>>,
}

impl SharedSession {
    /// Starts the physics thread on `session`, which the caller holds until its
    /// first [`SharedSession::release`].
    pub fn start(session: Session) -> std::io::Result<Self> {
        let shared = Arc::new(Shared {
            slot: Mutex::new(None),
            returned: Condvar::new(),
            ui_waiting: AtomicBool::new(false),
            quit: AtomicBool::new(false),
            failure: Mutex::new(None),
        });
        let thread = std::thread::Builder::new().name("physics".into()).spawn({
            let shared = shared.clone();
            move || step_while_released(&shared)
        })?;
        Ok(Self {
            shared,
            held: Some(session),
            thread: Some(thread),
        })
    }

    /// Takes the session from the physics thread, waiting at most one chunk for it
    /// to finish, and settles it ([`Session::settle`]): the state read is the
    /// latest, checked in full. Does nothing when already held.
    pub fn hold(&mut self) {
        if self.held.is_some() {
            return;
        }
        self.shared.ui_waiting.store(true, Ordering::Release);
        let mut slot = self.shared.slot();
        loop {
            if let Some(session) = slot.take() {
                self.held = Some(session);
                break;
            }
            slot = self
                .shared
                .returned
                .wait(slot)
                .unwrap_or_else(PoisonError::into_inner);
        }
        drop(slot);
        self.shared.ui_waiting.store(false, Ordering::Release);
        if let Some(session) = &mut self.held {
            session.settle();
        }
    }

    /// Hands the session to the physics thread. Does nothing when not held.
    pub fn release(&mut self) {
        if let Some(session) = self.held.take() {
            self.shared.put_back(session);
        }
    }

    /// Why the physics thread stopped, if it stopped on an internal error.
    pub fn failure(&self) -> Option<String> {
        self.shared
            .failure
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .clone()
    }
}

impl Deref for SharedSession {
    type Target = Session;

    fn deref(&self) -> &Session {
        self.held
            .as_ref()
            .expect("the window's thread reads the session only while it holds it")
    }
}

impl DerefMut for SharedSession {
    fn deref_mut(&mut self) -> &mut Session {
        self.held
            .as_mut()
            .expect("the window's thread edits the session only while it holds it")
    }
}

impl Drop for SharedSession {
    fn drop(&mut self) {
        self.shared.quit.store(true, Ordering::Release);
        self.shared.returned.notify_all();
        if let Some(thread) = self.thread.take() {
            let _ = thread.join();
        }
    }
}

/// The physics thread: whenever the session is in the slot and the window's
/// thread is not waiting for it, takes it and steps what the wall clock says is
/// due (at most [`CHUNK_MS`] of work), then puts it back.
fn step_while_released(shared: &Shared) {
    let mut last = Instant::now();
    loop {
        let mut slot = shared.slot();
        let mut session = loop {
            if shared.quit.load(Ordering::Acquire) {
                return;
            }
            if !shared.ui_waiting.load(Ordering::Acquire)
                && let Some(session) = slot.take()
            {
                break session;
            }
            slot = shared
                .returned
                .wait_timeout(slot, Duration::from_millis(2))
                .unwrap_or_else(PoisonError::into_inner)
                .0;
        };
        drop(slot);
        let now = Instant::now();
        let elapsed = now.duration_since(last).as_secs_f64().min(MAX_ELAPSED);
        last = now;
        let stepped = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            session.advance(elapsed, CHUNK_MS)
        }));
        shared.put_back(session);
        match stepped {
            Ok(report) if report.steps == 0 => std::thread::sleep(IDLE_SLEEP),
            Ok(_) => {}
            Err(panic) => {
                let text = super::panic_text(panic.as_ref());
                log::error!("the physics thread stopped: {text}");
                *shared
                    .failure
                    .lock()
                    .unwrap_or_else(PoisonError::into_inner) = Some(format!(
                    "The simulation stopped on an internal error: {text}"
                ));
                return;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cloth() -> Session {
        Session::load_with("cloth", &["width=8".into(), "height=8".into()]).unwrap()
    }

    /// Waits (up to 10 s of wall time) until the released session has run a step.
    fn wait_for_steps(shared: &mut SharedSession) -> f64 {
        for _ in 0..1000 {
            std::thread::sleep(Duration::from_millis(10));
            shared.hold();
            let t = shared.system().time();
            if t > 0.0 {
                return t;
            }
            shared.release();
        }
        panic!("the physics thread ran no step in 10 s");
    }

    #[test]
    fn the_physics_thread_steps_only_while_the_session_is_released() {
        let mut shared = SharedSession::start(cloth()).unwrap();
        // Held from the start: nothing steps, however long we wait.
        std::thread::sleep(Duration::from_millis(50));
        assert_eq!(shared.system().time(), 0.0);
        shared.release();
        let t = wait_for_steps(&mut shared);
        std::thread::sleep(Duration::from_millis(50));
        assert_eq!(shared.system().time(), t, "stepped while held");
        // An edit made while holding it is what the thread steps next.
        shared.set_paused(true);
        shared.release();
        std::thread::sleep(Duration::from_millis(50));
        shared.hold();
        assert_eq!(shared.system().time(), t, "stepped while paused");
        assert!(shared.failure().is_none());
    }

    #[test]
    fn the_thread_keeps_to_the_speed_asked_for() {
        // The thread counts wall time from its start, so the whole run since then
        // is what the fixed-step clock bounds (time due before a measurement's
        // start may be stepped after it).
        let start = Instant::now();
        let mut shared = SharedSession::start(cloth()).unwrap();
        shared.release();
        wait_for_steps(&mut shared);
        shared.release();
        std::thread::sleep(Duration::from_millis(300));
        shared.hold();
        let wall = start.elapsed().as_secs_f64();
        let simulated = shared.system().time();
        // Never ahead of the wall clock: at most the speed asked for, plus one
        // step of rounding.
        let dt = shared.system().params().dt;
        assert!(
            simulated <= shared.speed() * wall + dt,
            "{simulated} s simulated in {wall} s of wall time at speed {}",
            shared.speed()
        );
    }

    #[test]
    fn dropping_it_stops_the_thread() {
        let mut shared = SharedSession::start(cloth()).unwrap();
        shared.release();
        drop(shared);
    }
}
