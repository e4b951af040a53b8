//! The grid kernel's glue: whether a system is a grid cloth the stencil kernel
//! models exactly (its springs checked against the stencil, [`StencilSprings`];
//! every parameter named in `grid_spec`), and its runs.

use glam::DVec3;

use super::chunks::{FastEngine, copy_state_back, load_state, outgrown};
use super::{Ahead, pool_threads, uniform_acceleration};
use crate::sim::grid_kernel::{self, GridCloth, GridSpec, Precision, SpringCoefficients};
use crate::sim::springs::STENCIL_DIRECTIONS;
use crate::sim::{Divergence, SpringKind, System};

/// The kernel and what it was built from.
#[derive(Debug)]
pub(super) struct FastPath {
    pub(super) kernel: GridCloth,
    pub(super) spec: GridSpec,
    /// Whether the kernel holds the same state as the f64 arrays.
    pub(super) in_sync: bool,
    /// Positions of the particles held in place (pinned or grabbed), exactly as
    /// the f64 state had them: the kernel holds them in f32.
    pub(super) held: Vec<(usize, DVec3)>,
    /// The [`Engines::springs_version`] whose springs the kernel holds.
    pub(super) springs_seen: Option<u64>,
}

/// A grid cloth's or a lattice's springs and masses as its stencil kernel needs
/// them: one mass, and per kind one stiffness and damping. A grid's kinds are
/// structural, shear and bend, with rest lengths `h`, `h√2`, `2h`; every spring is
/// a stencil spring of its kind, though not every stencil spring need be there
/// (springs tear: the kernel takes which are left from the model,
/// [`springs_left`]). A lattice's kinds are its axis springs (structural), face
/// diagonals (shear) and body diagonals (other), with rest lengths `h`, `h√2`,
/// `h√3`, and every spring of the kinds present must be there. A kind with none,
/// e.g. `shear_scale = 0`, gets `k = b = 0`. Computed when springs or masses
/// change, not on every run.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(in crate::sim) struct StencilSprings {
    pub(super) coefficients: [SpringCoefficients; 3],
    /// Which kinds exist.
    pub(super) present: [bool; 3],
    pub(super) spacing: f64,
    pub(super) mass: f64,
    /// Whether this is a lattice's (else a grid's).
    pub(super) lattice: bool,
}

impl StencilSprings {
    /// The summary's slot of springs of `kind`, if the stencil has such springs.
    pub(super) fn slot(kind: SpringKind, lattice: bool) -> Option<usize> {
        match (kind, lattice) {
            (SpringKind::Structural, _) => Some(0),
            (SpringKind::Shear, _) => Some(1),
            (SpringKind::Bend, false) | (SpringKind::Other, true) => Some(2),
            (SpringKind::Bend, true) | (SpringKind::Other, false) => None,
        }
    }

    /// The summary after every spring of `kind` had its coefficients changed by
    /// `edit` (a kind with no springs keeps `k = b = 0`).
    pub(in crate::sim) fn with_kind(
        mut self,
        kind: SpringKind,
        edit: impl Fn(&mut SpringCoefficients),
    ) -> Self {
        if let Some(slot) = Self::slot(kind, self.lattice)
            && self.present[slot]
        {
            edit(&mut self.coefficients[slot]);
        }
        self
    }

    /// The summary of `model`, or `None` when no stencil kernel can model it.
    pub(in crate::sim) fn of(model: &crate::sim::Model) -> Option<Self> {
        let mass = *model.mass.first()?;
        if model.mass.iter().any(|&m| m != mass) {
            return None;
        }
        let (lattice, rest_ratio) = match (model.grid, model.lattice) {
            (Some(_), _) => (false, [1.0, std::f64::consts::SQRT_2, 2.0]),
            (None, Some(_)) => (true, [1.0, std::f64::consts::SQRT_2, 3f64.sqrt()]),
            (None, None) => return None,
        };
        let mut kinds: [Option<(f64, f64, f64)>; 3] = [None; 3];
        let mut counts = [0; 3];
        for s in &model.springs {
            let slot = Self::slot(s.kind, lattice)?;
            // The scene says this is a grid or a lattice: check that the spring is
            // a stencil spring of its kind (canonical springs being unique, the
            // springs are then a subset of the stencil, and the grid kernel masks
            // the others).
            let (a, b) = (s.a as usize, s.b as usize);
            let in_stencil = match (model.grid, model.lattice) {
                (Some(shape), _) => {
                    let (ra, ca) = (a / shape.width, a % shape.width);
                    let (rb, cb) = (b / shape.width, b % shape.width);
                    let offset = (rb as isize - ra as isize, cb as isize - ca as isize);
                    let in_stencil = match slot {
                        0 => offset == (0, 1) || offset == (1, 0),
                        1 => offset == (1, 1) || offset == (1, -1),
                        _ => offset == (0, 2) || offset == (2, 0),
                    };
                    in_stencil && b < shape.width * shape.height
                }
                (None, Some(shape)) => shape.kind_of(a, b) == Some(slot),
                (None, None) => false,
            };
            if !in_stencil {
                return None;
            }
            counts[slot] += 1;
            let m = model.material(s.kind);
            let coefficients = (m.stiffness, m.damping, s.rest);
            match kinds[slot] {
                None => kinds[slot] = Some(coefficients),
                Some(c) if c == coefficients => {}
                Some(_) => return None,
            }
        }
        if let Some(shape) = model.lattice.filter(|_| lattice) {
            // The lattice kernel evaluates every spring of a kind present.
            let full = shape.spring_counts();
            if (0..3).any(|k| kinds[k].is_some() && counts[k] != full[k]) {
                return None;
            }
        }
        let h = kinds[0]?.2;
        let mut coefficients = [SpringCoefficients::default(); 3];
        for slot in 0..3 {
            if let Some((k, b, rest)) = kinds[slot] {
                let stencil_rest = (rest - rest_ratio[slot] * h).abs() <= 1e-12 * h.max(1e-300);
                if !stencil_rest {
                    return None;
                }
                coefficients[slot] = SpringCoefficients { k, b };
            }
        }
        Some(Self {
            coefficients,
            present: kinds.map(|k| k.is_some()),
            spacing: h,
            mass,
            lattice,
        })
    }
}

/// Which stencil springs and triangles `model` (a grid that [`StencilSprings::of`]
/// accepted) has left, as [`GridCloth::set_springs_left`] takes them; `None` when
/// it has every stencil spring of the kinds `present` and every triangle.
pub(super) fn springs_left(model: &crate::sim::Model, present: [bool; 3]) -> Option<Vec<u8>> {
    let shape = model.grid?;
    let (w, h) = (shape.width, shape.height);
    let stencil = grid_kernel::stencil_counts(w, h);
    let whole_springs: usize = (0..3).filter(|&k| present[k]).map(|k| stencil[k]).sum();
    let whole_triangles = 2 * w.saturating_sub(1) * h.saturating_sub(1);
    if model.springs.len() == whole_springs && model.triangles.len() == whole_triangles {
        return None;
    }
    let mut bits = vec![0u8; w * h];
    for s in &model.springs {
        let (a, b) = (s.a as usize, s.b as usize);
        let offset = (b / w - a / w, (b % w) as isize - (a % w) as isize);
        if let Some(d) = STENCIL_DIRECTIONS.iter().position(|&o| o == offset) {
            bits[a] |= 1 << d;
        }
    }
    for &[a, b, c] in &model.triangles {
        let [a, b, c] = [a, b, c].map(|i| i as usize);
        // (a, b, d) with b = a + 1, d = a + w; (b, e, d) with e = b + w, d = e - 1.
        if b == a + 1 && c == a + w {
            bits[a] |= 1 << 6;
        } else if b == a + w && c + 1 == b && a >= 1 {
            bits[a - 1] |= 1 << 7;
        }
    }
    Some(bits)
}

impl System {
    /// The kernel's description of this system, if the kernel models it exactly.
    ///
    /// Every parameter is named here (no `..`): a new one fails to compile until
    /// it is either passed to the kernel or made a reason to refuse it.
    pub(super) fn grid_spec(&self) -> Option<GridSpec> {
        let model = &self.model;
        let (shape, springs) = (model.grid?, self.engines.stencil_springs?);
        let crate::sim::Params {
            gravity,
            force,
            wind,
            gust: _, // the wind's gusts are set step by step (`run_on_grid`)
            air_density,
            drag_coefficient,
            air_damping,
            ground,
            sphere,
            integrator,
            dt: _,             // given to each run
            bar_iterations: _, // bars are refused below
            stretch_limit,
            tear_strain,
            max_speed,
            friction,
            thickness,
            self_collision,
            seed: _, // only the gusts use it
        } = model.params;
        let crate::sim::ForceTerms {
            gravity: gravity_on,
            springs: _, // the kernel always evaluates the stencil
            aero,
            air_damping: air_damping_on,
            ground: _, // `ground` itself says
            applied,
        } = model.terms;
        if !GridCloth::supports(integrator)
            || (!model.bars.is_empty() && model.params.bar_iterations > 0)
        {
            return None;
        }
        let (air_density, drag_coefficient) = if aero {
            (air_density, drag_coefficient)
        } else {
            (0.0, 0.0)
        };
        let [structural, shear, bend] = springs.coefficients;
        let mut spec = GridSpec {
            width: shape.width,
            height: shape.height,
            spacing: springs.spacing,
            particle_mass: springs.mass,
            origin: [0.0; 3],
            structural,
            shear,
            bend,
            gravity: uniform_acceleration(
                gravity_on.then_some(gravity),
                applied.then_some(force),
                springs.mass,
            ),
            wind: wind.to_array(),
            air_density,
            drag_coefficient,
            pinned: Vec::new(),
            air_damping: if air_damping_on { air_damping } else { 0.0 },
            ground,
            sphere,
            friction,
            self_collision: self_collision.then_some(thickness).filter(|&t| t > 0.0),
            stretch_limit: stretch_limit.filter(|_| !model.springs.is_empty()),
            tear_strain,
            max_speed,
            integrator,
            present: springs.present,
            precision: Precision::Single,
        };
        let precision = Precision::cheapest(self.noise_rule(&spec).1, self.float32_reach());
        spec.precision = precision;
        Some(spec)
    }

    /// Runs `n` steps on the kernel if allowed and possible; `None` when the general
    /// path must run them.
    pub(in crate::sim) fn run_on_grid(
        &mut self,
        n: u64,
        settle: bool,
    ) -> Option<Result<(), Divergence>> {
        if !self.engines.allowed {
            return None;
        }
        self.run_choosing(n, settle, Self::grid_spec, |system, spec, n| {
            system.run_grid_once(spec, n, settle)
        })
    }

    /// [`Self::run_on_grid`]'s run of up to `n` steps on a grid kernel for `spec`,
    /// the one built before when it can take the spec: the steps run
    /// ([`Self::run_in_chunks`]).
    pub(super) fn run_grid_once(
        &mut self,
        spec: GridSpec,
        n: u64,
        settle: bool,
    ) -> Result<u64, Divergence> {
        // The kernel is taken out of `self` while it runs, so that the divergence
        // check can borrow the system.
        let reused = self.engines.grid.take().and_then(|mut fast| {
            if fast.spec != spec {
                // A live edit of a coefficient: updated in place, no new arrays or
                // threads; a new shape or integrator needs a new kernel.
                if !fast.kernel.respec(spec.clone()) {
                    return None;
                }
                fast.spec = spec.clone();
                fast.in_sync = false;
            }
            Some(fast)
        });
        let mut fast = match reused {
            Some(fast) => fast,
            None => {
                self.engines.builds += 1;
                let mut kernel = GridCloth::new(spec.clone());
                kernel.set_threads(pool_threads());
                FastPath {
                    kernel,
                    spec,
                    in_sync: false,
                    held: Vec::new(),
                    springs_seen: None,
                }
            }
        };
        if fast.springs_seen != Some(self.engines.springs_version) {
            (fast.kernel).set_springs_left(springs_left(&self.model, fast.spec.present));
            fast.springs_seen = Some(self.engines.springs_version);
        }
        if !fast.in_sync {
            load_state(&mut fast.kernel, self);
            fast.held = self.held(|i, pinned| fast.kernel.set_pinned(i, pinned));
            fast.in_sync = true;
        }
        let result = self.run_in_chunks(n, &mut fast, settle);
        self.engines.grid = Some(fast);
        result
    }
}

impl FastEngine for FastPath {
    const KIND: Ahead = Ahead::Grid;
    fn advance(&mut self, system: &System, steps: usize) {
        let (model, dt) = (&system.model, system.model.params.dt);
        self.kernel
            .set_colliders(&model.colliders, system.state.time);
        if model.wind.gust != 0.0 && model.terms.aero {
            (self.kernel).steps_in_wind(dt, steps, system.state.time, &model.wind);
        } else {
            self.kernel.steps(dt, steps);
        }
    }
    fn extremes(&self, center: DVec3) -> (f64, f64) {
        self.kernel.extremes(center)
    }
    fn copy_back(&mut self, system: &mut System) {
        let torn = self.kernel.take_torn();
        if !torn.is_empty() {
            let width = self.spec.width;
            let mut pairs: Vec<(usize, usize)> = torn
                .into_iter()
                .map(|(p, d)| {
                    let (dr, dc) = STENCIL_DIRECTIONS[d];
                    (p, (p + dr * width).wrapping_add_signed(dc))
                })
                .collect();
            pairs.sort_unstable();
            let pair = |s: &crate::sim::Spring| (s.a as usize, s.b as usize);
            system.break_springs(|s| pairs.binary_search(&pair(s)).is_ok());
            // The kernel broke them itself: its masks are the model's.
            self.springs_seen = Some(system.engines.springs_version);
        }
        copy_state_back(&self.kernel, &self.held, system);
    }
    fn load(&mut self, system: &System) {
        load_state(&mut self.kernel, system);
    }
    fn outgrown_unit(&self, dt: f64) -> Option<f64> {
        outgrown(self.kernel.position_unit(), self.kernel.spec(), dt)
    }
}

#[cfg(test)]
mod tests {
    use glam::DVec3;

    use super::super::chunks::load_state;
    use crate::scene::Scene;
    use crate::sim::grid_kernel::{GridCloth, Precision};

    /// The grid kernel runs the colliders with the f64 engine's law: in float64 it
    /// stays within round-off of the reference over 500 steps of the twist (a
    /// sphere turning under the cloth, measured 1.5e-10 m) and the slide (a capsule
    /// dragging it off a box, 1.8e-16 m). The twist amplifies round-off: a nudge of
    /// 1e-7 m on one particle of the reference grows to 4e-4 m in 1,000 steps.
    #[test]
    fn the_grid_kernel_in_float64_runs_the_colliders_as_the_reference() {
        for name in ["twist", "slide"] {
            let mut exact = Scene::load(name).unwrap().build().unwrap();
            let mut spec = exact.grid_spec().unwrap();
            spec.precision = Precision::Double;
            let mut kernel = GridCloth::new(spec);
            load_state(&mut kernel, &exact);
            let _ = exact.held(|i, pinned| kernel.set_pinned(i, pinned));
            let dt = exact.model.params.dt;
            for _ in 0..5 {
                kernel.set_colliders(&exact.model.colliders, exact.state.time);
                kernel.steps(dt, 100);
                exact.run(100).unwrap();
            }
            let mut p = vec![DVec3::ZERO; kernel.len()];
            kernel.positions_into(&mut p);
            let d = (p.iter().zip(exact.positions()))
                .map(|(a, b)| a.distance(*b))
                .fold(0.0, f64::max);
            assert!(d < 1e-9, "{name}: {d:e} m from the reference");
        }
    }
}
