//! A running scene as an interactive front end drives it, headless: the scene
//! spec with the user's edits, the system built from it, fixed-step pacing
//! (`substeps` steps of `dt` per 1/60 s of wall time, whatever the frame rate),
//! pause / single step / reset, divergence, live parameter edits, and safe stepping
//! (on by default): the step is kept below half the integrator's critical step, with
//! more substeps so that each frame still covers the same simulated time.
//!
//! Live edits are typed ([`Edit`]): [`Session::apply`] records one in the scene spec
//! and changes the running system in place through its setters, so that a slider
//! dragged every frame costs no parsing, no resolving of the scene and no new system;
//! only layout edits (width, height, depth) rebuild it.
//!
//! The scene spec is the whole setup: pins set by a click or a preset are recorded
//! in it too, so that a reset keeps them, [`Session::save_in`] writes it as a scene
//! file that loads back to the same run, and undo, redo and "Defaults" restore a
//! setup by the same in-place path as edits.

use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

pub use crate::scene::Edit;
use glam::DVec3;

mod diverged;
#[cfg(feature = "gpu")]
mod gpu;
mod history;
mod parts;
pub mod reference;
mod sliders;

pub use diverged::DivergenceReport;
pub use sliders::{EARTH_GRAVITY, Slider};

use crate::scene::{Resolved, Scene, SceneError};
use crate::sim::safe::{self, DEFAULT_SAFETY};
use crate::sim::{Clock, Params, SpringKind, State, System};

/// Most substeps per frame safe stepping may choose; past it the simulation runs
/// slower than real time rather than with an unsafe step.
pub const MAX_SAFE_SUBSTEPS: u32 = 100_000;

pub use crate::sim::safe::{SAFE_STRETCH_LIMIT, WIND_LOAD_NEEDING_A_LIMIT, wind_load_ratio};

/// Wall-clock seconds that `substeps` steps stand for (one frame at 60 Hz).
pub const FRAME_PERIOD: f64 = 1.0 / 60.0;

/// Most wall-clock milliseconds one frame may spend stepping before the
/// simulation falls behind real time instead of freezing the UI.
pub const STEP_BUDGET_MS: f64 = 25.0;

/// Scene keys whose change needs the system rebuilt (topology or layout);
/// every other key applies live.
const REBUILD_KEYS: &[&str] = &[
    "layout",
    "orientation",
    "width",
    "height",
    "depth",
    "size",
    "pins",
    "origin",
    "rotation",
    "stretch",
    "shear_scale",
    "bend_scale",
    "material",
    "seed",
    "mesh",
    "pin_above",
];

/// The wind the wind switch turns on when the scene had none to restore: seed
/// 004's breeze, 3 m/s along z (towards the viewer).
pub const DEFAULT_WIND: DVec3 = DVec3::new(0.0, 0.0, 3.0);

/// The slow-motion factors [`Session::set_slow_motion`] takes.
pub const SLOW_MOTION: std::ops::RangeInclusive<f64> = 0.05..=1.0;

/// Most changes [`Session::undo`] can take back.
pub const MAX_UNDO: usize = 200;

/// What one frame did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FrameReport {
    /// Steps run.
    pub steps: u32,
    /// Wall-clock milliseconds spent stepping.
    pub sim_ms: f64,
    /// True when the frame could not run every step due: the simulation is
    /// running slower than real time.
    pub behind: bool,
}

/// A scene running interactively.
pub struct Session {
    scene: Scene,
    /// The scene's settings in effect, kept in step with `scene` by every edit.
    settings: Resolved,
    name: String,
    system: System,
    /// The kinds of spring the system has, so an edit of k or b touches only those.
    spring_kinds: Vec<SpringKind>,
    clock: Clock,
    paused: bool,
    divergence: Option<DivergenceReport>,
    /// The state at the end of the last frame that passed its checks.
    last_good: State,
    /// Rest length the springs were last scaled to (m).
    rest_length: f64,
    /// The scene's own values that the sliders' ranges sit around.
    home: sliders::Home,
    /// The last change of the setup (`key = value`) and the simulated time it
    /// was made at, which a divergence names.
    last_edit: Option<(String, f64)>,
    /// Simulated time per wall time, as a share of the scene's speed.
    slow_motion: f64,
    /// Steps per 1/60 s of wall time.
    substeps: u32,
    /// Smoothed cost of one step (ms).
    ms_per_step: f64,
    /// Whether safe stepping chooses dt and substeps.
    safe_stepping: bool,
    /// What safe stepping chose, when it is on.
    step_choice: Option<StepChoice>,
    /// Whether the drag's areas have outgrown that choice ([`Session::recheck_step`]).
    step_watch: safe::StepWatch,
    /// Wind and gust (m/s) the wind switch turned off, to turn back on.
    stored_wind: Option<(DVec3, f64)>,
    /// The scene as loaded, before any edit: what "Defaults" restores.
    defaults: Scene,
    /// Real-time factor and physics cost, measured over the last half second.
    pace: PaceMeter,
    /// Triangles that draw the system as a solid where it has no surface of its
    /// own ([`Resolved::display_surface`]).
    display_surface: Vec<[u32; 3]>,
    /// Setups before each change, oldest first, for undo.
    undo: Vec<history::Change>,
    /// Setups undone, most recent last, for redo.
    redo: Vec<history::Change>,
    /// The key of the edit the last undo entry was made for while the same
    /// gesture goes on (a slider being dragged), so that it makes one entry.
    edit_group: Option<&'static str>,
    /// The simulated time per frame a dt drag keeps (see
    /// [`Session::apply_dt_keeping_speed`]).
    dt_drag_frame_time: Option<f64>,
    /// How many times the system was built: with its edits, what the live
    /// reference started from.
    builds: u64,
    /// The live reference, while it is on ([`reference`]).
    reference: Option<reference::Live>,
    /// The GPU engine, while the session steps on it.
    #[cfg(feature = "gpu")]
    gpu: Option<gpu::OnGpu>,
}

/// What safe stepping chose for the running system.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StepChoice {
    /// Steps per frame.
    pub substeps: u32,
    /// Step in s.
    pub dt: f64,
    /// Whether the step is below the safety fraction of a finite critical step
    /// (false when the integrator has no stable step, e.g. explicit Euler undamped).
    pub safe: bool,
    /// The stretch limit safe stepping added, if any.
    pub stretch_limit: Option<f64>,
}

/// How the simulation keeps up with the wall clock, measured over a window of
/// about half a second of [`Session::advance`] calls.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Pace {
    /// Simulated seconds per wall-clock second (1 is real time).
    pub real_time_factor: f64,
    /// The factor asked for ([`Session::speed`]); 0 while paused or diverged.
    pub target: f64,
    /// Share of wall-clock time spent stepping (0 to 1 on one thread).
    pub busy: f64,
    /// Steps per wall-clock second.
    pub steps_per_second: f64,
    /// Whether simulated time was dropped because the steps due could not run.
    pub behind: bool,
}

/// Wall-clock seconds over which [`Pace`] is measured.
const PACE_WINDOW: f64 = 0.5;

/// Sums for the [`Pace`] window being measured, and the last one measured.
#[derive(Clone, Copy, Debug, Default)]
struct PaceMeter {
    wall: f64,
    simulated: f64,
    busy_ms: f64,
    steps: u64,
    behind: bool,
    target: f64,
    shown: Pace,
}

impl PaceMeter {
    fn add(
        &mut self,
        wall: f64,
        simulated: f64,
        busy_ms: f64,
        steps: u32,
        behind: bool,
        target: f64,
    ) {
        if !(wall.is_finite() && wall >= 0.0) {
            return;
        }
        self.wall += wall;
        self.simulated += simulated;
        self.busy_ms += busy_ms;
        self.steps += u64::from(steps);
        self.behind |= behind;
        self.target = self.target.max(target);
        if self.wall >= PACE_WINDOW {
            self.shown = Pace {
                real_time_factor: self.simulated / self.wall,
                target: self.target,
                busy: self.busy_ms * 1e-3 / self.wall,
                steps_per_second: self.steps as f64 / self.wall,
                behind: self.behind,
            };
            *self = Self {
                shown: self.shown,
                ..Self::default()
            };
        }
    }
}

impl Session {
    /// Loads a built-in scene or scene file and applies `key=value` overrides.
    pub fn load_with(name: &str, overrides: &[String]) -> Result<Self, SceneError> {
        let mut scene = Scene::load(name)?;
        scene.set_all(overrides.iter().map(String::as_str))?;
        Self::new(scene, name)
    }

    /// Starts `scene`, named `name` in the UI.
    pub fn new(scene: Scene, name: &str) -> Result<Self, SceneError> {
        let settings = scene.resolve()?;
        let home = sliders::Home::of(&settings);
        let system = settings.build();
        let p = &settings.params;
        crate::scene::check_self_collision(&scene.origin, &system, p.self_collision, p.thickness)?;
        let mut session = Self {
            defaults: scene.clone(),
            undo: Vec::new(),
            redo: Vec::new(),
            edit_group: None,
            dt_drag_frame_time: None,
            scene,
            name: name.to_string(),
            system,
            settings,
            spring_kinds: Vec::new(),
            clock: Clock::default(),
            paused: false,
            divergence: None,
            last_good: State::default(),
            rest_length: 0.0,
            home,
            last_edit: None,
            slow_motion: 1.0,
            substeps: 1,
            ms_per_step: 0.0,
            safe_stepping: true,
            step_choice: None,
            step_watch: safe::StepWatch::default(),
            stored_wind: None,
            pace: PaceMeter::default(),
            display_surface: Vec::new(),
            builds: 0,
            reference: None,
            #[cfg(feature = "gpu")]
            gpu: None,
        };
        session.built();
        Ok(session)
    }

    /// Builds the system anew from the settings (which hold the pins).
    fn rebuild(&mut self) {
        self.system = self.settings.build();
        self.built();
    }

    /// Starts a system just built from the settings.
    fn built(&mut self) {
        self.builds += 1;
        self.system.set_fast_path(true);
        self.spring_kinds = SpringKind::ALL
            .into_iter()
            .filter(|&kind| self.system.springs().iter().any(|s| s.kind == kind))
            .collect();
        self.rest_length = self.settings.rest_length;
        self.substeps = self.settings.substeps;
        self.display_surface = self.settings.display_surface();
        self.clock.reset();
        self.divergence = None;
        self.last_good = self.system.state().clone();
        self.choose_step();
    }

    /// Applies the scene's dt and substeps, or, with safe stepping on, a step no
    /// larger than `DEFAULT_SAFETY * dt_crit` (with the drag taken on the
    /// triangles' areas now as well: [`System::dt_critical_now`]) and as many
    /// substeps as keep the simulated time per frame (`substeps * dt` of the
    /// scene) the same, up to [`MAX_SAFE_SUBSTEPS`] (beyond that the simulation
    /// runs slower, never unsafe).
    fn choose_step(&mut self) {
        let user = self.settings.params;
        // The stability estimate reads the integrator, the air damping and the
        // ground from the running model: bring them up to date first, keeping the
        // step and stretch limit it runs with until they are chosen below.
        let running = *self.system.params();
        let live = Params {
            dt: running.dt,
            stretch_limit: running.stretch_limit,
            ..user
        };
        if running != live {
            self.system.set_params(live);
        }
        let (user_dt, user_substeps) = (user.dt, self.settings.substeps);
        let mut params = user;
        let mut substeps = user_substeps;
        self.step_choice = None;
        // A new choice starts a new watch: a cut step grows back only after a
        // second of room since this choice.
        self.step_watch = safe::StepWatch::default();
        if self.safe_stepping {
            let frame_time = user_dt * f64::from(user_substeps);
            let choice = safe::safe_step_below(
                self.system.dt_critical_now(),
                frame_time,
                DEFAULT_SAFETY,
                MAX_SAFE_SUBSTEPS,
            );
            let safe_dt = choice.dt_critical.map(|c| DEFAULT_SAFETY * c);
            if let Some(limit) = safe_dt.filter(|l| *l < user_dt) {
                params.dt = limit.min(choice.dt);
                substeps = ((frame_time / params.dt).ceil() as u32).clamp(1, MAX_SAFE_SUBSTEPS);
            }
            let added_limit = safe::added_stretch_limit(self.system.model(), params.stretch_limit);
            params.stretch_limit = params.stretch_limit.or(added_limit);
            self.step_choice = Some(StepChoice {
                substeps,
                dt: params.dt,
                safe: safe_dt.is_some(),
                stretch_limit: added_limit,
            });
        }
        if *self.system.params() != params {
            self.system.set_params(params);
        }
        self.substeps = substeps;
    }

    /// With safe stepping on, chooses the step again where the drag's areas have
    /// grown (or shrunk back) past [`safe::StepWatch`]'s bounds since it was
    /// chosen. Called on a settled state, once per frame's steps.
    fn recheck_step(&mut self) {
        let Some(choice) = self.step_choice else {
            return;
        };
        if !self.system.model().terms.aero {
            return;
        }
        let steps = (choice.dt, self.settings.params.dt);
        let (time, now) = (self.system.time(), self.system.dt_critical_now());
        if (self.step_watch).outgrown(time, steps, now, DEFAULT_SAFETY) {
            self.choose_step();
        }
    }

    /// Whether safe stepping is on.
    pub fn safe_stepping(&self) -> bool {
        self.safe_stepping
    }

    /// Turns safe stepping on or off.
    pub fn set_safe_stepping(&mut self, on: bool) {
        self.safe_stepping = on;
        self.choose_step();
    }

    /// With safe stepping on, the scene's own step, which it splits: what a copy
    /// of the running system stepped elsewhere (a recording) splits to keep its
    /// watch on the drag's areas ([`safe::follow_areas`]). None when it is off.
    pub fn safe_scene_step(&self) -> Option<f64> {
        self.step_choice.map(|_| self.settings.params.dt)
    }

    /// What safe stepping chose (None when it is off).
    pub fn step_choice(&self) -> Option<StepChoice> {
        self.step_choice
    }

    /// Replaces the running scene with another one, dropping the user's edits.
    /// On error nothing changes.
    pub fn load_scene(&mut self, name: &str) -> Result<(), SceneError> {
        let (paused, safe_stepping) = (self.paused, self.safe_stepping);
        let slow_motion = self.slow_motion;
        let loaded = Self::load_with(name, &[])?;
        let reference = self.reference.take();
        *self = loaded;
        (self.paused, self.slow_motion) = (paused, slow_motion);
        self.set_safe_stepping(safe_stepping);
        // The reference stays on, and starts on the new scene (its builds count
        // anew, so it is told to).
        self.reference = reference.map(|mut live| {
            live.forget();
            live
        });
        self.follow_reference();
        Ok(())
    }

    /// Name of the scene (as loaded).
    pub fn name(&self) -> &str {
        &self.name
    }

    /// The scene spec with the user's edits.
    pub fn scene(&self) -> &Scene {
        &self.scene
    }

    /// The scene's settings in effect (defaults filled in, the user's edits
    /// included): what the panel shows. Safe stepping may run a smaller step than
    /// `params.dt`; [`Self::system`] has the parameters that run.
    pub fn settings(&self) -> &Resolved {
        &self.settings
    }

    /// The triangles to draw: the system's surface, or for a layout without one
    /// (the jelly cube) the faces that show it as a solid.
    pub fn surface(&self) -> &[[u32; 3]] {
        match self.system.triangles() {
            [] => &self.display_surface,
            own => own,
        }
    }

    /// The running system.
    pub fn system(&self) -> &System {
        &self.system
    }

    /// The running system, for pinning and dragging.
    pub fn system_mut(&mut self) -> &mut System {
        &mut self.system
    }

    /// Whether the simulation is paused.
    pub fn paused(&self) -> bool {
        self.paused
    }

    /// Pauses or resumes; resuming forgets the wall time spent paused.
    pub fn set_paused(&mut self, paused: bool) {
        if !paused {
            self.clock.reset();
        }
        self.paused = paused;
    }

    /// The last divergence, until the next reset or rebuild.
    pub fn divergence(&self) -> Option<&DivergenceReport> {
        self.divergence.as_ref()
    }

    /// Steps per 1/60 s of wall time (the "speed").
    pub fn substeps(&self) -> u32 {
        self.substeps
    }

    /// Smoothed wall-clock cost of one step (ms).
    pub fn ms_per_step(&self) -> f64 {
        self.ms_per_step
    }

    /// Rebuilds the system from the scene with the user's edits (R, "Reset").
    /// Pins set by clicking or a preset are kept (they are in the scene); the pause
    /// state is kept.
    pub fn reset(&mut self) -> Result<(), SceneError> {
        self.settings = self.scene.resolve()?;
        self.rebuild();
        Ok(())
    }

    /// The current setup as a scene file: the scene with every edit and the pins
    /// in effect, which `cloth --scene FILE` and `cloth run --scene FILE` read back
    /// to the same run (the state the run has reached is not part of it).
    pub fn scene_text(&self) -> String {
        let body = toml::to_string(&self.scene.spec).unwrap_or_else(|e| {
            // Every field of a spec is a plain number, string or list: unreachable.
            log::error!("cannot write the scene as TOML: {e}");
            String::new()
        });
        format!(
            "# Saved by cloth-sandbox from {}.\n# Open it with `cloth --scene FILE` or `cloth run --scene FILE`.\n{body}",
            self.scene.origin
        )
    }

    /// Writes [`Self::scene_text`] to a new file `saved-<scene>-<N>.toml` in `dir`,
    /// with the first N from 1 that names no file there (an existing file is never
    /// replaced), and returns its path.
    pub fn save_in(&self, dir: &Path) -> std::io::Result<PathBuf> {
        let text = self.scene_text();
        let stem = save_stem(&self.name);
        for n in 1..=10_000 {
            let path = dir.join(format!("saved-{stem}-{n}.toml"));
            match std::fs::OpenOptions::new()
                .write(true)
                .create_new(true)
                .open(&path)
            {
                Ok(mut file) => {
                    file.write_all(text.as_bytes())?;
                    return Ok(path);
                }
                Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => {}
                Err(e) => return Err(e),
            }
        }
        Err(std::io::Error::other(format!(
            "{} already holds saved-{stem}-1.toml to saved-{stem}-10000.toml: move some away",
            dir.display()
        )))
    }

    /// Whether changing `key` rebuilds the system rather than applying live.
    pub fn needs_rebuild(&self, key: &str) -> bool {
        REBUILD_KEYS.contains(&key)
    }

    /// The pinned particles of the running system, in index order.
    pub fn pins(&self) -> Vec<usize> {
        (0..self.system.particle_count())
            .filter(|&i| self.system.is_pinned(i))
            .collect()
    }

    /// Whether any wind blows: a mean wind or gusts.
    pub fn wind_on(&self) -> bool {
        let p = &self.settings.params;
        p.wind != DVec3::ZERO || p.gust != 0.0
    }

    /// The wind switch (seed 004): off sets the wind and the gusts to zero and
    /// remembers them; on brings back what it turned off, or else [`DEFAULT_WIND`]. Both are ordinary edits of `wind`
    /// and `gust`, so a saved scene keeps the switch's state.
    pub fn set_wind_on(&mut self, on: bool) -> Result<(), SceneError> {
        if on == self.wind_on() {
            return Ok(());
        }
        let (wind, gust) = if on {
            self.stored_wind.take().unwrap_or((DEFAULT_WIND, 0.0))
        } else {
            let p = &self.settings.params;
            self.stored_wind = Some((p.wind, p.gust));
            (DVec3::ZERO, 0.0)
        };
        let before = self.scene.clone();
        self.apply_unrecorded(Edit::Wind(wind))?;
        self.apply_unrecorded(Edit::Gust(gust))?;
        let what = if on { "wind on" } else { "wind off" };
        self.remember(before, None, what.into());
        Ok(())
    }

    /// Applies a typed edit (a panel slider): records it in the scene spec, so that
    /// a reset or a rebuild keeps it, and changes the running system in place
    /// through its setters without disturbing its state (positions, velocities,
    /// time). Width, height, depth and a material rebuild the system with every
    /// other setting kept. A value out of range (or not finite) is refused with an error naming
    /// the field and the allowed range, and nothing changes.
    ///
    /// The change can be undone; edits of the same key in a row make one undo
    /// step until [`Self::end_edit_group`] (the app calls it when the pointer lets
    /// go of a slider).
    pub fn apply(&mut self, edit: Edit) -> Result<(), SceneError> {
        let before = self.scene.clone();
        self.apply_unrecorded(edit)?;
        self.remember(before, Some(edit.key()), edit.to_string());
        Ok(())
    }

    /// The panel's dt edit: the steps per frame change with it so that the speed
    /// (simulated time per frame) stays, and a larger dt means coarser steps, not a
    /// faster run. One undo step, grouped with the rest of a slider drag; the
    /// speed kept is the one at the drag's start, so that rounding to whole steps
    /// does not drift along the drag.
    pub fn apply_dt_keeping_speed(&mut self, dt: f64) -> Result<(), SceneError> {
        let before = self.scene.clone();
        let key = Edit::Dt(dt).key();
        let frame_time = match self.dt_drag_frame_time {
            Some(t) if self.edit_group == Some(key) => t,
            _ => self.settings.params.dt * f64::from(self.settings.substeps),
        };
        self.apply_unrecorded(Edit::Dt(dt))?;
        let range = crate::scene::build::SUBSTEPS;
        let steps = (frame_time / dt)
            .round()
            .clamp(f64::from(range.lo), f64::from(range.hi)) as u32;
        if steps != self.settings.substeps {
            self.apply_unrecorded(Edit::Substeps(steps))?;
        }
        self.remember(before, Some(key), Edit::Dt(dt).to_string());
        self.dt_drag_frame_time = Some(frame_time);
        Ok(())
    }

    /// [`Self::apply`] without an undo entry.
    fn apply_unrecorded(&mut self, edit: Edit) -> Result<(), SceneError> {
        let mut scene = self.scene.clone();
        scene.apply(edit)?;
        let mut settings = self.settings.clone();
        settings.follow(edit, &scene)?;
        if matches!(edit, Edit::Thickness(_) | Edit::SelfCollision(true)) && !edit.rebuilds() {
            let p = &settings.params;
            let origin = crate::scene::EDIT_ORIGIN;
            crate::scene::check_self_collision(
                origin,
                &self.system,
                p.self_collision,
                p.thickness,
            )?;
        }
        self.commit(scene, settings, edit.rebuilds());
        Ok(())
    }

    /// Sets a scene key from text, as `--set key=value` does (the panel sends typed
    /// [`Edit`]s instead; this takes any key). Layout keys (width, height, pins, ...)
    /// rebuild the system with every other setting kept; the rest apply to the
    /// running system as [`Self::apply`] does. On error nothing changes.
    pub fn set(&mut self, key: &str, value: &str) -> Result<(), SceneError> {
        let before = self.scene.clone();
        let mut scene = self.scene.clone();
        scene.set(key, value)?;
        let settings = scene.resolve()?;
        self.commit(scene, settings, self.needs_rebuild(key));
        self.remember(before, None, format!("{key} = {value}"));
        Ok(())
    }

    /// Restores the scene's own parameters and pins as it was loaded ("Defaults"),
    /// dropping every edit; the running state is kept where the layout allows, as
    /// for an edit. The change can be undone.
    pub fn restore_defaults(&mut self) -> Result<(), SceneError> {
        let before = self.scene.clone();
        self.restore(self.defaults.clone())?;
        // Safe stepping is the app's default, as the scene's values are its own.
        if !self.safe_stepping {
            self.set_safe_stepping(true);
        }
        self.remember(before, None, "Defaults".into());
        Ok(())
    }

    /// Makes `scene` the setup: in place, as edits apply, unless it lays the
    /// particles out differently, which rebuilds. On error nothing changes.
    fn restore(&mut self, scene: Scene) -> Result<(), SceneError> {
        let settings = scene.resolve()?;
        let (a, b) = (&self.settings, &settings);
        let rebuild = (a.layout, a.orientation, a.width, a.height, a.depth)
            != (b.layout, b.orientation, b.width, b.height, b.depth)
            || (
                a.rotation,
                a.stretch,
                a.shear_scale,
                a.bend_scale,
                a.params.seed,
            ) != (
                b.rotation,
                b.stretch,
                b.shear_scale,
                b.bend_scale,
                b.params.seed,
            )
            || self.scene.spec.origin != scene.spec.origin
            || self.scene.spec.mesh != scene.spec.mesh;
        self.commit(scene, settings, rebuild);
        if !rebuild {
            self.sync_pins();
        }
        Ok(())
    }

    /// Takes an edited scene and its settings: rebuilds the system, or brings the
    /// running one in step with the settings that changed.
    fn commit(&mut self, scene: Scene, settings: Resolved, rebuild: bool) {
        self.scene = scene;
        let old = std::mem::replace(&mut self.settings, settings);
        if rebuild {
            self.rebuild();
            return;
        }
        let new = &self.settings;
        // Per-kind constants are multiples of k and b (shear and bend scales on a grid).
        let kinds = &self.spring_kinds;
        let of_kind = |value: f64| {
            move |kind| {
                kinds
                    .contains(&kind)
                    .then(|| value * new.spring_scale(kind))
            }
        };
        if new.stiffness != old.stiffness {
            self.system.set_stiffness_by_kind(of_kind(new.stiffness));
        }
        if new.damping != old.damping {
            self.system.set_damping_by_kind(of_kind(new.damping));
        }
        // The cloth grows or shrinks with its rest length (positions too, about the
        // pins), so strains are kept: changing the rest length of springs pinned in
        // place would store the energy of a huge compression and release it at once.
        if new.rest_length != self.rest_length && self.rest_length > 0.0 {
            self.system.rescale(new.rest_length / self.rest_length);
            self.rest_length = new.rest_length;
        }
        if new.particle_mass != old.particle_mass {
            self.system.set_particle_mass(new.particle_mass);
        }
        if new.colliders != old.colliders {
            self.system.set_colliders(new.colliders.clone());
        }
        // Parameters (with dt and the stretch limit safe stepping picks) and substeps.
        self.choose_step();
    }

    /// Advances by `elapsed` wall-clock seconds at the scene's speed, unless
    /// paused or diverged. Runs at most what fits in `STEP_BUDGET_MS`.
    pub fn frame(&mut self, elapsed: f64) -> FrameReport {
        self.advance_by(elapsed, STEP_BUDGET_MS, true)
    }

    /// Adds `elapsed` wall-clock seconds at the scene's speed and runs the steps
    /// due, as many as fit in `budget_ms`; the rest stay due for the next call. Up
    /// to [`STEP_BUDGET_MS`] of steps may be due: past that backlog the simulation
    /// falls behind real time instead of catching up in a burst. Nothing runs while
    /// paused or diverged. A caller that calls often with a small budget (the app's
    /// physics thread) keeps real time in short chunks.
    ///
    /// The steps run with [`System::run_ahead`]: until [`Session::settle`], the
    /// system's positions may lag behind its time. Whoever reads or edits the
    /// session between `advance` calls settles it first.
    pub fn advance(&mut self, elapsed: f64, budget_ms: f64) -> FrameReport {
        self.advance_by(elapsed, budget_ms, false)
    }

    fn advance_by(&mut self, elapsed: f64, budget_ms: f64, settle: bool) -> FrameReport {
        if self.paused || self.divergence.is_some() {
            self.pace.add(elapsed, 0.0, 0.0, 0, false, 0.0);
            return FrameReport::default();
        }
        let dt = self.system.params().dt;
        let speed = self.speed();
        let (ms_per_step, substeps) = (self.ms_per_step, self.substeps);
        let steps_in = |ms: f64| {
            if ms_per_step > 0.0 {
                (ms / ms_per_step).floor().clamp(1.0, 1e6) as u32
            } else {
                substeps
            }
        };
        let backlog = steps_in(STEP_BUDGET_MS)
            .min(substeps.saturating_mul(16))
            .max(1);
        let due = self.clock.advance(elapsed, speed, dt, backlog);
        let now = due.steps.min(steps_in(budget_ms.max(0.0)));
        self.clock.defer(due.steps - now, dt);
        let report = self.run_steps(now, settle);
        let behind = due.dropped > 0.0;
        let simulated = f64::from(report.steps) * dt;
        self.pace.add(
            elapsed,
            simulated,
            report.sim_ms,
            report.steps,
            behind,
            speed,
        );
        FrameReport { behind, ..report }
    }

    /// Simulated seconds per wall-clock second asked for: `substeps` steps of `dt`
    /// per 1/60 s (1 is real time), slowed by [`Session::slow_motion`].
    pub fn speed(&self) -> f64 {
        self.slow_motion * f64::from(self.substeps) * self.system.params().dt / FRAME_PERIOD
    }

    /// The slow-motion factor: 1 runs at the scene's speed, 0.05 twenty times
    /// slower, with the same steps (a view setting, not part of the scene).
    pub fn slow_motion(&self) -> f64 {
        self.slow_motion
    }

    /// Sets the slow-motion factor, kept within [`SLOW_MOTION`] (a value that is
    /// not a number leaves it as it is).
    pub fn set_slow_motion(&mut self, factor: f64) {
        if !factor.is_nan() {
            self.slow_motion = factor.clamp(*SLOW_MOTION.start(), *SLOW_MOTION.end());
        }
    }

    /// How the simulation has kept up with the wall clock lately.
    pub fn pace(&self) -> Pace {
        self.pace.shown
    }

    /// One frame's steps ([`Session::substeps`], 1/60 s at the speed asked for),
    /// whether paused or not (the "Step" button and the `.` key).
    pub fn step_frame(&mut self) -> FrameReport {
        if self.divergence.is_some() {
            return FrameReport::default();
        }
        self.run_steps(self.substeps, true)
    }

    /// One step, whether paused or not.
    pub fn single_step(&mut self) -> FrameReport {
        if self.divergence.is_some() {
            return FrameReport::default();
        }
        self.run_steps(1, true)
    }

    /// Brings the state up to the steps [`Session::advance`] ran and checks it in
    /// full, as [`Session::frame`] leaves it; a divergence found here is handled as
    /// one found while stepping.
    pub fn settle(&mut self) {
        let before = self.system.steps_taken();
        match self.system.settle() {
            Ok(()) if self.last_good.steps != before => {
                self.last_good.clone_from(self.system.state());
                self.recheck_step();
            }
            Ok(()) => {}
            Err(d) => self.diverged(d),
        }
        self.follow_reference();
    }

    /// Runs `steps` steps in one call (so that a grid cloth runs on a fast engine);
    /// `settle`: checked in full at the end, with the state brought up to date.
    fn run_steps(&mut self, steps: u32, settle: bool) -> FrameReport {
        self.restart_reference_if_edited();
        let start = Instant::now();
        let before = self.system.steps_taken();
        #[cfg(feature = "gpu")]
        let on_gpu = self.run_on_gpu(steps);
        #[cfg(not(feature = "gpu"))]
        let on_gpu = None;
        let outcome = match (on_gpu, settle) {
            (Some(outcome), _) => outcome,
            (None, true) => self.system.run(u64::from(steps)),
            (None, false) => self.system.run_ahead(u64::from(steps)),
        };
        let done = (self.system.steps_taken() - before) as u32;
        match outcome {
            Ok(()) if settle => {
                self.last_good.clone_from(self.system.state());
                self.recheck_step();
                self.follow_reference();
            }
            Ok(()) => {}
            Err(d) => self.diverged(d),
        }
        let sim_ms = start.elapsed().as_secs_f64() * 1e3;
        if done > 0 {
            let per = sim_ms / f64::from(done);
            self.ms_per_step = if self.ms_per_step > 0.0 {
                0.8 * self.ms_per_step + 0.2 * per
            } else {
                per
            };
        }
        FrameReport {
            steps: done,
            sim_ms,
            behind: false,
        }
    }
}

/// The scene part of a saved file's name: a built-in scene's name, or a scene file's
/// stem without an earlier save's `saved-` and `-N`, in letters, digits, `-` and `_`.
pub(crate) fn save_stem(name: &str) -> String {
    let stem = Path::new(name)
        .file_stem()
        .map_or(name.into(), |s| s.to_string_lossy());
    let stem = stem.strip_prefix("saved-").unwrap_or(&stem);
    let stem = match stem.rsplit_once('-') {
        Some((head, n)) if !n.is_empty() && n.bytes().all(|b| b.is_ascii_digit()) => head,
        _ => stem,
    };
    let clean: String = stem
        .chars()
        .filter(|c| c.is_ascii_alphanumeric() || *c == '-' || *c == '_')
        .take(40)
        .collect();
    if clean.is_empty() {
        "scene".to_string()
    } else {
        clean
    }
}

#[cfg(test)]
mod tests {
    use super::save_stem;

    #[test]
    fn saved_file_names_come_from_the_scene() {
        assert_eq!(save_stem("cloth"), "cloth");
        assert_eq!(save_stem("bench-wind"), "bench-wind");
        assert_eq!(save_stem("/tmp/my flag.toml"), "myflag");
        assert_eq!(save_stem("saved-cloth-3.toml"), "cloth");
        assert_eq!(save_stem("../.."), "scene");
    }
}
