//! Force terms, each separate, each run only when the scene uses it (see [`ForceTerms`]).
//!
//! Units are SI: positions in m, velocities in m/s, forces in N.
//! - gravity: `m g`;
//! - damped springs: `f_a = -(k (l - L) + b (v_a - v_b)·u) u`, `f_b = -f_a`;
//! - aerodynamic drag per triangle (seed 000): `v_rel` = mean vertex velocity minus
//!   wind, `F = -1/2 rho C_d A (v_rel·n) |v_rel| n`, a third to each vertex;
//! - viscous air damping `-c v` (seed 002);
//! - ground penalty contact `k_c d n - c_g (v·n) n` for a particle at depth `d > 0`;
//! - the applied force `F` on every particle (seed 001's force vector).

use glam::DVec3;
use rayon::prelude::*;

use super::Model;
use super::laws::{self, SpringCoefficients, V3};

pub use super::laws::EPSILON_LENGTH;

/// Spring count above which spring forces are computed on several threads.
const PARALLEL_SPRINGS: usize = 20_000;

/// Whether the model's spring forces are computed on several threads.
pub fn uses_threads(model: &Model) -> bool {
    model.springs.len() >= PARALLEL_SPRINGS
}

/// `part(0)` and `part(1)`, a pass over a model's particles or springs cut in
/// two ([`half`]): on two threads where the model's forces are
/// threaded ([`uses_threads`]), one after the other elsewhere. Each half runs in
/// its own order whichever way, so a total made of the two is the same on one
/// thread or several.
pub(crate) fn in_halves<T: Send>(model: &Model, part: impl Fn(usize) -> T + Sync) -> [T; 2] {
    if uses_threads(model) {
        let (first, second) = rayon::join(|| part(0), || part(1));
        [first, second]
    } else {
        [part(0), part(1)]
    }
}

/// The first (`h` = 0) or the second half of `0..n`.
pub(crate) fn half(n: usize, h: usize) -> std::ops::Range<usize> {
    match h {
        0 => 0..n / 2,
        _ => n / 2..n,
    }
}

/// Which force terms a model evaluates. Derived from the scene: a term that cannot
/// contribute is not run.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ForceTerms {
    /// Uniform gravity (gravity is non-zero).
    pub gravity: bool,
    /// Damped springs (the model has springs).
    pub springs: bool,
    /// Per-triangle aerodynamic drag (triangles, and air density and drag coefficient > 0).
    pub aero: bool,
    /// Viscous air damping (coefficient > 0).
    pub air_damping: bool,
    /// Ground penalty contact (the scene has a ground).
    pub ground: bool,
    /// The applied force on every particle (it is non-zero).
    pub applied: bool,
}

impl ForceTerms {
    /// Names of the terms that run, for reports.
    pub fn names(&self) -> Vec<&'static str> {
        let mut names = Vec::new();
        for (on, name) in [
            (self.gravity, "gravity"),
            (self.springs, "springs"),
            (self.aero, "aero-drag"),
            (self.air_damping, "air-damping"),
            (self.ground, "ground-contact"),
            (self.applied, "applied-force"),
        ] {
            if on {
                names.push(name);
            }
        }
        names
    }
}

impl Model {
    /// Accelerations `a = F / m + g` at positions `x`, velocities `v` and time `t`,
    /// written into `out` (zero for pinned particles). `spring_forces` is scratch
    /// space of one entry per spring.
    pub fn accelerations(
        &self,
        x: &[DVec3],
        v: &[DVec3],
        t: f64,
        spring_forces: &mut [DVec3],
        out: &mut [DVec3],
    ) {
        self.forces(x, v, t, spring_forces, out);
        let g = if self.terms.gravity {
            self.params.gravity
        } else {
            DVec3::ZERO
        };
        for (a, &w) in out.iter_mut().zip(&self.inv_mass) {
            *a = V3::from(*a)
                .zip(V3::from(g), |f, g| laws::acceleration(f, w, g))
                .into();
        }
    }

    /// Total force on each particle except gravity, written into `out`.
    pub fn forces(
        &self,
        x: &[DVec3],
        v: &[DVec3],
        t: f64,
        spring_forces: &mut [DVec3],
        out: &mut [DVec3],
    ) {
        out.fill(DVec3::ZERO);
        if self.terms.springs {
            self.add_spring_forces(x, v, spring_forces, out);
        }
        if self.terms.aero {
            self.add_aero_forces(x, v, t, out);
        }
        if self.terms.air_damping {
            let neg_c = -self.params.air_damping;
            for (f, &vi) in out.iter_mut().zip(v) {
                *f = V3::from(*f)
                    .zip(V3::from(vi), |f, v| laws::air_damped(f, neg_c, v))
                    .into();
            }
        }
        if self.terms.ground {
            self.add_ground_forces(x, v, out);
        }
        if self.terms.applied {
            let force = self.params.force;
            out.iter_mut().for_each(|f| *f += force);
        }
    }

    /// Spring forces in two passes: each spring's force on its `a` end (one writer
    /// per spring), then each particle gathers from its own springs (one writer per
    /// particle). No two threads ever write the same memory.
    fn add_spring_forces(
        &self,
        x: &[DVec3],
        v: &[DVec3],
        spring_forces: &mut [DVec3],
        out: &mut [DVec3],
    ) {
        let force_on_a = |s: &super::Spring| {
            let (a, b) = (s.a as usize, s.b as usize);
            let m = self.materials[s.kind.index()];
            spring_force(x[a] - x[b], v[a] - v[b], s.rest, m.stiffness, m.damping)
        };
        let parallel = uses_threads(self);
        if parallel {
            (spring_forces.par_iter_mut().zip(self.springs.par_iter()))
                .for_each(|(f, s)| *f = force_on_a(s));
        } else {
            for (f, s) in spring_forces.iter_mut().zip(&self.springs) {
                *f = force_on_a(s);
            }
        }
        let (spring_forces, adjacency) = (&*spring_forces, self.adjacency());
        let gather = |(i, f): (usize, &mut DVec3)| {
            for (spring, sign) in adjacency.springs_of(i) {
                *f += sign * spring_forces[spring];
            }
        };
        if parallel {
            out.par_iter_mut().enumerate().for_each(gather);
        } else {
            out.iter_mut().enumerate().for_each(gather);
        }
    }

    fn add_aero_forces(&self, x: &[DVec3], v: &[DVec3], t: f64, out: &mut [DVec3]) {
        let wind = self.wind.at(t);
        let half_rho_cd = self.params.half_rho_cd();
        for tri in &self.triangles {
            let [a, b, c] = tri.map(|i| i as usize);
            let f = triangle_drag([x[a], x[b], x[c]], [v[a], v[b], v[c]], wind, half_rho_cd);
            out[a] += f;
            out[b] += f;
            out[c] += f;
        }
    }

    fn add_ground_forces(&self, x: &[DVec3], v: &[DVec3], out: &mut [DVec3]) {
        let Some(ground) = self.params.ground else {
            return;
        };
        for ((f, xi), vi) in out.iter_mut().zip(x).zip(v) {
            f.y += ground_force(&ground, *xi, *vi);
        }
    }
}

/// Upward force (N) of the ground on a particle at `x` moving at `v`
/// (`laws::ground_support` at depth `height - y`).
#[inline]
pub fn ground_force(ground: &super::Ground, x: DVec3, v: DVec3) -> f64 {
    laws::ground_support(ground.height - x.y, v.y, ground.stiffness, ground.damping)
}

/// Force on end `a` of a damped spring, given `d = x_a - x_b` and `dv = v_a - v_b`
/// (`laws::spring_force`). Zero for coincident endpoints.
#[inline]
pub fn spring_force(d: DVec3, dv: DVec3, rest: f64, k: f64, b: f64) -> DVec3 {
    let c = SpringCoefficients::new(k, rest, b);
    laws::spring_force(V3::from(d), V3::from(dv), c).into()
}

/// The drag on each vertex of a triangle with corners `x` moving at `v` in a
/// `wind` (`laws::triangle_drag`), with `half_rho_cd = ρ C_d / 2`.
#[inline]
pub fn triangle_drag(x: [DVec3; 3], v: [DVec3; 3], wind: DVec3, half_rho_cd: f64) -> DVec3 {
    laws::triangle_drag(
        x.map(V3::from),
        v.map(V3::from),
        V3::from(wind),
        half_rho_cd,
    )
    .into()
}
