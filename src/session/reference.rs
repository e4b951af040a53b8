//! The live reference (the panel's "Compare with a reference"): the shown run
//! stepped again beside it, on a thread of its own, by RK4 on the f64 engine at
//! dt / [`REFINE`], with the position error between the two over time and what
//! each run costs per simulated second. `cloth report` trades error against
//! cost offline; this shows the same trade on the scene being played with.
//!
//! The reference starts from the shown state whenever the shown run is edited
//! ([`System::edits`], or a rebuild), so that the two always start equal and
//! the error is the shown integrator's own, since that edit.

use std::collections::VecDeque;
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::mpsc::{Receiver, Sender, channel};
use std::thread::JoinHandle;
use std::time::Instant;

use glam::DVec3;

use crate::sim::{Integrator, System};

/// The reference's step is the shown step divided by this. With RK4's fourth
/// order its own error is 1/16 of RK4's at the shown step, far below a first or
/// second order integrator's at the same step.
pub const REFINE: u32 = 2;

/// Most particles the reference takes: beyond this it cannot keep up with the
/// shown run on one core at the scenes' steps (`docs/accuracy.md`).
pub const MAX_PARTICLES: usize = 4096;

/// Shown states sent that the reference has not compared yet, at most: a slower
/// reference compares fewer states, never a growing queue of them.
const MAX_IN_FLIGHT: usize = 3;

/// Simulated seconds the reference may fall behind the shown run before it
/// stops, saying how slow it is: past that its error and ghost are too late to
/// read beside the run.
pub const MAX_LAG: f64 = 1.0;

/// Comparisons kept for the plot.
const MAX_SAMPLES: usize = 2000;

/// One comparison of the shown run with the reference at the same time.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ErrorSample {
    /// Simulated time (s).
    pub time: f64,
    /// RMS over the free particles of the distance between the runs (m).
    pub rms: f64,
    /// Largest such distance (m).
    pub max: f64,
}

/// Why [`Reference::start`] refuses a system.
pub fn refusal(system: &System) -> Option<String> {
    let n = system.particle_count();
    (n > MAX_PARTICLES).then(|| {
        format!(
            "The reference takes scenes of up to {MAX_PARTICLES} particles, and this one has {n}: \
             lower width or height to compare."
        )
    })
}

/// RK4 at dt / [`REFINE`] from a state of the shown run, stepped to the shown
/// run's steps on request.
pub struct Reference {
    system: System,
    /// Shown steps at the start.
    start_steps: u64,
    /// Wall-clock seconds spent stepping.
    wall: f64,
}

impl Reference {
    /// Starts from `shown`'s state and setup, with RK4 at its dt / [`REFINE`] on
    /// the f64 engine; refused past [`MAX_PARTICLES`].
    pub fn start(shown: &System) -> Result<Self, String> {
        if let Some(why) = refusal(shown) {
            return Err(why);
        }
        let mut system = shown.clone();
        system.set_fast_path(false);
        let mut params = *system.params();
        params.integrator = Integrator::Rk4;
        params.dt /= f64::from(REFINE);
        system.set_params(params);
        Ok(Self {
            system,
            start_steps: shown.steps_taken(),
            wall: 0.0,
        })
    }

    /// Steps on to the time of the shown run's step `steps` and compares with its
    /// `positions` there; the error, or why the reference stopped.
    pub fn compare(&mut self, steps: u64, positions: &[DVec3]) -> Result<ErrorSample, String> {
        let target = steps.saturating_sub(self.start_steps) * u64::from(REFINE);
        let clock = Instant::now();
        let run = self.system.run(target.saturating_sub(self.steps_done()));
        self.wall += clock.elapsed().as_secs_f64();
        run.map_err(|d| format!("The reference (RK4 at dt/{REFINE}) diverged: {d}"))?;
        if positions.len() != self.system.particle_count() {
            return Err("the shown run changed size".into());
        }
        let (mut sum, mut max, mut free) = (0.0, 0.0f64, 0usize);
        for (i, (a, b)) in positions.iter().zip(self.system.positions()).enumerate() {
            if self.system.is_pinned(i) {
                continue;
            }
            let d = a.distance(*b);
            (sum, max, free) = (sum + d * d, max.max(d), free + 1);
        }
        Ok(ErrorSample {
            time: self.system.time(),
            rms: if free == 0 {
                0.0
            } else {
                (sum / free as f64).sqrt()
            },
            max,
        })
    }

    /// The reference's own steps since its start.
    fn steps_done(&self) -> u64 {
        self.system.steps_taken() - self.start_steps
    }

    /// The reference's positions (m) at its last comparison.
    pub fn positions(&self) -> &[DVec3] {
        self.system.positions()
    }

    /// Wall-clock seconds the reference spent per simulated second so far.
    pub fn cost(&self) -> f64 {
        let simulated = self.steps_done() as f64 * self.system.params().dt;
        if simulated > 0.0 {
            self.wall / simulated
        } else {
            0.0
        }
    }
}

/// What the window's side asks of the reference's thread; each job carries the
/// epoch it belongs to, and the thread skips those of an epoch gone by.
enum Job {
    Start(u64, Box<System>),
    Compare {
        epoch: u64,
        steps: u64,
        positions: Vec<DVec3>,
    },
}

/// What the thread answers.
enum Answer {
    Compared {
        epoch: u64,
        sample: ErrorSample,
        positions: Vec<DVec3>,
        cost: f64,
    },
    Stopped {
        epoch: u64,
        why: String,
    },
}

/// The reference running on its own thread beside a session, and what it has
/// measured: the error samples, its positions last compared (the ghost) and its
/// cost.
pub struct Live {
    jobs: Option<Sender<Job>>,
    answers: Receiver<Answer>,
    /// The epoch of the reference running now; the thread reads it to skip stale jobs.
    epoch: Arc<AtomicU64>,
    /// What the reference started from: the session's build and its system's edits.
    key: Option<(u64, u64)>,
    /// The shown step last sent.
    sent: Option<u64>,
    in_flight: usize,
    samples: VecDeque<ErrorSample>,
    /// Times at which the reference started again from the shown state.
    restarts: VecDeque<f64>,
    ghost: Vec<DVec3>,
    cost: f64,
    /// Why it does not compare now.
    stopped: Option<String>,
    /// Whether it stopped for falling [`MAX_LAG`] behind.
    fell_behind: bool,
    thread: Option<JoinHandle<()>>,
}

impl Live {
    /// Starts the reference's thread (it starts comparing at the first
    /// [`Self::follow`]).
    pub fn spawn() -> std::io::Result<Self> {
        let (jobs, inbox) = channel();
        let (outbox, answers) = channel();
        let epoch = Arc::new(AtomicU64::new(0));
        let thread = std::thread::Builder::new()
            .name("reference".into())
            .spawn({
                let epoch = epoch.clone();
                move || serve(&inbox, &outbox, &epoch)
            })?;
        Ok(Self {
            jobs: Some(jobs),
            answers,
            epoch,
            key: None,
            sent: None,
            in_flight: 0,
            samples: VecDeque::new(),
            restarts: VecDeque::new(),
            ghost: Vec::new(),
            cost: 0.0,
            stopped: None,
            fell_behind: false,
            thread: Some(thread),
        })
    }

    /// Takes the shown run as it is now (settled): starts the reference again
    /// from it if it was edited since (`build` counts the session's rebuilds),
    /// or sends its state to be compared. Collects what the thread has answered.
    pub fn follow(&mut self, build: u64, shown: &System) {
        self.collect();
        if self.restart_if_edited(build, shown) {
            return;
        }
        let steps = shown.steps_taken();
        if self.stopped.is_some() || self.sent == Some(steps) {
            return;
        }
        let answered = self.samples.back().map_or(shown.time(), |s| s.time);
        if shown.time() - answered > MAX_LAG {
            self.fell_behind = true;
            self.stopped = Some(format!(
                "The reference fell {MAX_LAG} s of simulated time behind: it needs {:.2} s of \
                 wall time per simulated second. Slow the run down or make the cloth smaller, \
                 then turn it off and on (or edit) to start it again.",
                self.cost
            ));
            return;
        }
        if self.behind() {
            return;
        }
        let job = Job::Compare {
            epoch: self.epoch.load(Ordering::Acquire),
            steps,
            positions: shown.positions().to_vec(),
        };
        self.send(job);
        self.sent = Some(steps);
        self.in_flight += 1;
    }

    /// Starts again at the next [`Self::follow`], whatever it follows then (a
    /// new scene, whose builds and edits count from the start again).
    pub fn forget(&mut self) {
        self.key = None;
    }

    /// Starts the reference again from `shown` if it was edited since the
    /// reference last started; `shown` must be settled, as it is after an edit.
    /// Whoever steps the shown run calls this first, so that the reference
    /// starts from the state the edit left, not from one stepped on after it.
    pub fn restart_if_edited(&mut self, build: u64, shown: &System) -> bool {
        let key = (build, shown.edits());
        let edited = self.key != Some(key);
        if edited {
            self.restart(key, shown);
        }
        edited
    }

    fn restart(&mut self, key: (u64, u64), shown: &System) {
        self.key = Some(key);
        self.sent = Some(shown.steps_taken());
        self.in_flight = 0;
        self.ghost.clear();
        self.cost = 0.0;
        self.fell_behind = false;
        let time = shown.time();
        // A time gone back (a reset, an undo) starts the plot again.
        if self.samples.back().is_some_and(|s| s.time > time) {
            self.samples.clear();
            self.restarts.clear();
        }
        self.restarts.push_back(time);
        self.stopped = refusal(shown);
        let epoch = self.epoch.fetch_add(1, Ordering::AcqRel) + 1;
        if self.stopped.is_none() {
            self.send(Job::Start(epoch, Box::new(shown.clone())));
            self.ghost.extend_from_slice(shown.positions());
            self.push(ErrorSample {
                time,
                rms: 0.0,
                max: 0.0,
            });
        }
    }

    fn send(&mut self, job: Job) {
        let sent = self
            .jobs
            .as_ref()
            .is_some_and(|jobs| jobs.send(job).is_ok());
        if !sent {
            self.stopped = Some("The reference's thread stopped.".into());
        }
    }

    /// Takes the thread's answers for the reference running now.
    fn collect(&mut self) {
        let now = self.epoch.load(Ordering::Acquire);
        while let Ok(answer) = self.answers.try_recv() {
            match answer {
                Answer::Compared {
                    epoch,
                    sample,
                    positions,
                    cost,
                } if epoch == now => {
                    self.in_flight = self.in_flight.saturating_sub(1);
                    self.push(sample);
                    self.ghost = positions;
                    self.cost = cost;
                }
                Answer::Stopped { epoch, why } if epoch == now => {
                    self.in_flight = 0;
                    self.stopped = Some(why);
                }
                _ => {}
            }
        }
    }

    fn push(&mut self, sample: ErrorSample) {
        self.samples.push_back(sample);
        while self.samples.len() > MAX_SAMPLES {
            self.samples.pop_front();
        }
        let first = self.samples.front().map_or(0.0, |s| s.time);
        while self.restarts.len() > 1 && self.restarts[1] <= first {
            self.restarts.pop_front();
        }
    }

    /// Waits until the thread has answered every state sent, or `timeout`
    /// passes (tests, and whoever wants the figures of a run just made).
    pub fn wait(&mut self, timeout: std::time::Duration) {
        let deadline = Instant::now() + timeout;
        self.collect();
        while self.in_flight > 0 && self.stopped.is_none() && Instant::now() < deadline {
            std::thread::sleep(std::time::Duration::from_millis(1));
            self.collect();
        }
    }

    /// The comparisons so far, oldest first (since the plot last started).
    pub fn samples(&self) -> &VecDeque<ErrorSample> {
        &self.samples
    }

    /// The simulated times at which the reference started again after an edit.
    pub fn restarts(&self) -> &VecDeque<f64> {
        &self.restarts
    }

    /// The reference's positions at its last comparison (the ghost drawn);
    /// none while it is stopped, when they would be stale.
    pub fn ghost(&self) -> &[DVec3] {
        match self.stopped {
            Some(_) => &[],
            None => &self.ghost,
        }
    }

    /// Wall-clock seconds the reference spends per simulated second, measured
    /// since it last started (0 before its first comparison).
    pub fn cost(&self) -> f64 {
        self.cost
    }

    /// Why the reference does not compare now: a scene too large, or its own
    /// run diverged (until the next edit starts it again).
    pub fn stopped(&self) -> Option<&str> {
        self.stopped.as_deref()
    }

    /// Whether it stopped for falling [`MAX_LAG`] behind the shown run.
    pub fn fell_behind(&self) -> bool {
        self.fell_behind
    }

    /// Whether it has as many states to compare as it takes: the next shown
    /// states go by uncompared, the reference being slower than the shown run.
    pub fn behind(&self) -> bool {
        self.in_flight >= MAX_IN_FLIGHT
    }
}

impl Drop for Live {
    fn drop(&mut self) {
        // Closing the channel ends the thread after the job in hand.
        self.jobs = None;
        self.epoch.fetch_add(1, Ordering::AcqRel);
        if let Some(thread) = self.thread.take() {
            let _ = thread.join();
        }
    }
}

/// The reference's thread: starts and steps the reference as asked, skipping
/// jobs of an epoch gone by.
fn serve(jobs: &Receiver<Job>, answers: &Sender<Answer>, epoch: &AtomicU64) {
    let mut reference: Option<(u64, Reference)> = None;
    for job in jobs {
        let now = epoch.load(Ordering::Acquire);
        let answer = match job {
            Job::Start(e, system) if e == now => match Reference::start(&system) {
                Ok(r) => {
                    reference = Some((e, r));
                    continue;
                }
                Err(why) => Answer::Stopped { epoch: e, why },
            },
            Job::Compare {
                epoch: e,
                steps,
                positions,
            } if e == now => {
                let Some((_, r)) = reference.as_mut().filter(|(re, _)| *re == e) else {
                    continue;
                };
                match r.compare(steps, &positions) {
                    Ok(sample) => Answer::Compared {
                        epoch: e,
                        sample,
                        positions: r.positions().to_vec(),
                        cost: r.cost(),
                    },
                    Err(why) => {
                        reference = None;
                        Answer::Stopped { epoch: e, why }
                    }
                }
            }
            _ => continue,
        };
        if answers.send(answer).is_err() {
            return;
        }
    }
}

impl super::Session {
    /// Turns the live reference on or off. On, it starts from the state now and
    /// follows every settled state after; a scene past [`MAX_PARTICLES`] is
    /// refused, with the reason in [`Live::stopped`].
    pub fn set_reference(&mut self, on: bool) -> std::io::Result<()> {
        match (on, self.reference.is_some()) {
            (true, false) => {
                self.reference = Some(Live::spawn()?);
                self.follow_reference();
            }
            (false, true) => self.reference = None,
            _ => {}
        }
        Ok(())
    }

    /// The live reference, while it is on.
    pub fn reference(&self) -> Option<&Live> {
        self.reference.as_ref()
    }

    /// Waits until the reference has compared every state sent to it, or
    /// `timeout` passes.
    pub fn wait_for_reference(&mut self, timeout: std::time::Duration) {
        if let Some(live) = &mut self.reference {
            live.wait(timeout);
        }
    }

    /// Wall-clock seconds the shown run spends per simulated second (its smoothed
    /// cost per step over its step), beside [`Live::cost`].
    pub fn cost(&self) -> f64 {
        let dt = self.system.params().dt;
        if dt > 0.0 {
            self.ms_per_step * 1e-3 / dt
        } else {
            0.0
        }
    }

    /// Before steps: an edit since the reference started starts it again from
    /// the state the edit left (settled, as every edit leaves it).
    pub(super) fn restart_reference_if_edited(&mut self) {
        if let Some(live) = &mut self.reference {
            live.restart_if_edited(self.builds, &self.system);
        }
    }

    /// The slow-motion factor at which the reference, stopped for falling behind,
    /// would keep up with room to spare (at 80 % of its measured speed), when
    /// that is slower than now and within [`super::SLOW_MOTION`].
    pub fn slow_motion_for_reference(&self) -> Option<f64> {
        let live = self.reference.as_ref().filter(|l| l.fell_behind())?;
        let asked = self.speed() / self.slow_motion;
        let factor = 0.8 / (live.cost() * asked);
        let factor = (factor * 100.0).floor() / 100.0;
        let range = super::SLOW_MOTION;
        (factor.is_finite() && factor < self.slow_motion).then(|| factor.max(*range.start()))
    }

    /// Starts the reference again from the state now (after a change of speed,
    /// which is no edit of the run).
    pub fn restart_reference(&mut self) -> std::io::Result<()> {
        self.set_reference(false)?;
        self.set_reference(true)
    }

    /// Hands the settled state to the reference, which starts again after an edit.
    pub(super) fn follow_reference(&mut self) {
        if self.divergence.is_some() {
            return;
        }
        if let Some(live) = &mut self.reference {
            live.follow(self.builds, &self.system);
        }
    }
}
