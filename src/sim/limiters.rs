//! When a limiter does the work of stability: tearing, the speed limit and the
//! stretch limit each hold back motion the step gives, so an integrator that has
//! blown up can run on under them, its energy and speeds kept within bounds, and
//! look like a success (explicit Euler on the `tear` scene broke 13,346 of its
//! springs, spread the cloth over 98 m and moved it at 37 m/s, and exited 0;
//! symplectic Euler tore 42 at 0.75 m/s).
//!
//! **What is measured.** At each full check (every [`super::energy_budget::
//! ENERGY_CHECK_STEPS`] steps and at the end of a run), one pass over the
//! particles and springs counts what each limiter is holding now ([`Activity`]):
//! the free particles at the speed cap (within 0.01% of it), the springs at the
//! stretch limit (within 1% of its strain), and the springs torn since the energy
//! budget was set (the start or the last edit).
//!
//! **When it is a divergence.** Where the step is past the stability estimate's
//! limit (`dt / dt_crit >= 1`, or no step is stable: explicit Euler and RK2
//! undamped) the linearised step grows every mode it touches, so whatever a
//! limiter holds then is the blow-up it hides: any limiter at work is a
//! divergence ([`Divergence::HeldBack`], exit 3), named with what it holds. The
//! estimate's frequency is never above the true one (a Rayleigh quotient), so a
//! step it calls past the limit is past it.
//!
//! **When it is a warning.** Within the limit the limiters may be doing what they
//! are for (a tear, a speed cap on a fast fall). [`Activity::warning`] says so
//! when one holds more than [`WARN_SHARE`] of what it acts on at the end of a run:
//! the built-in scenes at their defaults hold at most 0.1% (the `tear` scene's 42
//! torn springs of 13,536), a blown-up run nearly all.

use super::{Divergence, EnergyBudget, Model, State};

/// The share of particles at the cap, or springs at the stretch limit or torn, past
/// which a limiter within the stability limit is reported as doing much of the
/// work (a warning, not a divergence).
pub const WARN_SHARE: f64 = 0.1;

/// A limiter that holds motion back.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Limiter {
    /// Springs torn past the tear strain.
    Tearing,
    /// Particles slowed to `max_speed`.
    SpeedLimit,
    /// Springs held at the stretch limit.
    StretchLimit,
}

impl Limiter {
    /// The scene key that sets it.
    pub fn key(self) -> &'static str {
        match self {
            Self::Tearing => "tear_strain",
            Self::SpeedLimit => "max_speed",
            Self::StretchLimit => "stretch_limit",
        }
    }

    /// What it holds, "3 of 1024 particles at the speed cap (max_speed)".
    pub fn holding(self, count: usize, of: usize) -> String {
        let what = match self {
            Self::Tearing => "springs torn",
            Self::SpeedLimit => "free particles at the speed cap",
            Self::StretchLimit => "springs at the stretch limit",
        };
        format!("{count} of {of} {what} ({})", self.key())
    }
}

/// What the limiters hold in one state.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Activity {
    /// Free particles at the speed cap, and free particles (0, 0 without a limit).
    pub at_speed_cap: (usize, usize),
    /// Springs at the stretch limit, and springs (0, 0 without a limit).
    pub at_stretch_limit: (usize, usize),
    /// Springs torn since the budget was set, and the springs there were then
    /// (0, 0 without tearing).
    pub torn: (usize, usize),
}

impl Activity {
    /// What `model`'s limiters hold in `state`, with tearing counted since
    /// `budget` was set.
    pub fn of(model: &Model, state: &State, budget: &EnergyBudget) -> Self {
        let p = &model.params;
        let at_speed_cap = match p.max_speed {
            Some(cap) => {
                let near = (cap * (1.0 - 1e-4)).powi(2);
                (state.velocities.iter().zip(&model.inv_mass))
                    .filter(|(_, w)| **w > 0.0)
                    .fold((0, 0), |(n, of), (v, _)| {
                        (n + usize::from(v.length_squared() >= near), of + 1)
                    })
            }
            None => (0, 0),
        };
        let at_stretch_limit = match p.stretch_limit {
            Some(tau) if state.positions.len() == model.mass.len() => {
                let x = &state.positions;
                let held = (model.springs.iter())
                    .filter(|s| {
                        let l = (x[s.a as usize] - x[s.b as usize]).length();
                        l >= (1.0 + 0.99 * tau) * s.rest
                    })
                    .count();
                (held, model.springs.len())
            }
            _ => (0, 0),
        };
        let torn = match p.tear_strain {
            Some(_) => (
                model.broken_springs.saturating_sub(budget.broken),
                budget.springs,
            ),
            None => (0, 0),
        };
        Self {
            at_speed_cap,
            at_stretch_limit,
            torn,
        }
    }

    /// Each limiter at work, with what it holds and of how many.
    pub fn working(&self) -> impl Iterator<Item = (Limiter, usize, usize)> + '_ {
        [
            (Limiter::Tearing, self.torn),
            (Limiter::SpeedLimit, self.at_speed_cap),
            (Limiter::StretchLimit, self.at_stretch_limit),
        ]
        .into_iter()
        .filter(|(_, (n, _))| *n > 0)
        .map(|(l, (n, of))| (l, n, of))
    }

    /// The limiter holding the largest share, if any is at work.
    pub fn strongest(&self) -> Option<(Limiter, usize, usize)> {
        let share = |&(_, n, of): &(Limiter, usize, usize)| n as f64 / of.max(1) as f64;
        self.working().max_by(|a, b| share(a).total_cmp(&share(b)))
    }

    /// A warning where a limiter holds more than `WARN_SHARE` of what it acts
    /// on: "the speed limit does much of the work: 1024 of 1024 free particles at
    /// the speed cap (max_speed); the step may be unstable under it".
    pub fn warning(&self) -> Option<String> {
        let heavy: Vec<String> = (self.working())
            .filter(|&(_, n, of)| n as f64 > WARN_SHARE * of.max(1) as f64)
            .map(|(l, n, of)| l.holding(n, of))
            .collect();
        (!heavy.is_empty()).then(|| {
            format!(
                "limiters hold much of the motion: {}; a motion the step cannot follow may be \
                 under them (try a smaller dt, or turn the limiter off to see)",
                heavy.join(", ")
            )
        })
    }
}

/// The divergence of a run whose step is past the stability limit
/// (`budget.margin >= 1`) while a limiter holds something (see the module doc).
pub fn check(model: &Model, state: &State, budget: &EnergyBudget) -> Result<(), Divergence> {
    // NaN (no estimate) is no limit passed.
    if budget.margin.is_nan() || budget.margin < 1.0 {
        return Ok(());
    }
    let p = &model.params;
    if p.max_speed.is_none() && p.stretch_limit.is_none() && p.tear_strain.is_none() {
        return Ok(());
    }
    match Activity::of(model, state, budget).strongest() {
        Some((limiter, count, of)) => Err(Divergence::HeldBack {
            time: state.time,
            step: state.steps,
            limiter,
            count,
            of,
            margin: budget.margin,
        }),
        None => Ok(()),
    }
}

impl super::System {
    /// What the limiters hold now, tearing counted since the energy budget was
    /// set ([`Activity::of`]); none before a budget is.
    pub fn limiter_activity(&self) -> Activity {
        match self.budget {
            Some(budget) => Activity::of(&self.model, &self.state, &budget),
            None => Activity::default(),
        }
    }
}
