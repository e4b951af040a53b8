//! The lattice kernel's step loop: the band pass ([`super::band`]), then XPBD's
//! springs (forward and back), the stretch limit and the contact with friction.

use std::ops::Range;

use super::Ctx;
use super::band::run_bands;
use super::kernel::Lattice;
use super::spec::FORWARD;
use crate::sim::Integrator;
use crate::sim::constraints::xpbd_sweeps_back;
use crate::sim::duo::{Duo, run_in_pool};
use crate::sim::grid_kernel::spring_passes::{
    ColourClass, RowColour, SpringRule, Sweep, SweepLines, SweepMultipliers, SweepRules,
    SweepSprings, step_start,
};
use crate::sim::grid_kernel::{BLOCK, Buf, ContactRows, Real, RowsPass, frame};

impl<E: Real> Lattice<E> {
    /// Advances `n` steps of `dt` seconds (inside the thread pool once).
    pub(super) fn steps(&mut self, dt: f64, n: usize) {
        self.params.dt = E::of(dt);
        if self.params.verlet {
            self.params.verlet_half_dt = E::of(0.5 * dt);
        }
        let pool = self.pool.take();
        let parallel = pool.is_some();
        let two_bands = self.bands.len() == 2;
        let run = |duo: Option<&Duo>| {
            for i in 0..n {
                if i % frame::CHECK_STEPS == 0 {
                    self.keep_in_frame(frame::CHECK_STEPS.min(n - i) as f64 * dt);
                }
                self.one_step(parallel, duo);
                self.constrain(dt, duo);
                self.resolve_contact(dt);
            }
        };
        // Two bands: the second is handed to the pool's other thread by spinning,
        // as the grid kernel's are, rather than woken by `rayon::join` each step.
        run_in_pool(pool.as_ref(), two_bands, run);
        self.pool = pool;
    }

    /// The passes along the springs after the step: XPBD's springs, then
    /// Provot's stretch limit, as in the f64 engine; with `duo`, on both threads.
    pub(super) fn constrain(&mut self, dt: f64, duo: Option<&Duo>) {
        if self.spec.integrator == Integrator::Xpbd {
            self.spring_pass(SpringRule::Xpbd, dt, duo);
        }
        if let Some(tau) = self.spec.stretch_limit {
            self.spring_pass(SpringRule::StretchLimit(tau), dt, duo);
        }
    }

    /// One pass of `rule` over the springs, with the grid's passes
    /// (`grid_kernel::spring_passes`): the lattice's array rows (`x + r W` with
    /// `r = y + z H`) are a grid's rows, a direction `(dx, dy, dz)` is the grid direction
    /// `(dy + dz H, dx)`, and the real-particle mask leaves out the springs that
    /// reach a ghost. Sweeps go by direction in the order of [`FORWARD`], each
    /// direction's two colour classes in turn ([`LatticeShape::constraint_class`],
    /// the f64 engine's order): `z % 2` is the row's `(r / H) % 2`, and `y % 2` is
    /// `(r % H) % 2`.
    ///
    /// With `duo`, each sweep's lines run on two threads: the lines from the
    /// middle row `m` on on the other thread, those that touch no row from `m` on
    /// on this one, then the few between here. A line's lanes past its end reach
    /// the next rows' particles (the lattice has no padding), which they store
    /// unchanged, so a line from row `r` touches rows `r` to `r + dr` and one or
    /// two more; kept apart so, the two threads' lines touch no particle in
    /// common, and the result is the same as on one thread.
    pub(super) fn spring_pass(&mut self, rule: SpringRule, dt: f64, duo: Option<&Duo>) {
        let g = self.geometry;
        let slab_rows = g.shape.height + 1;
        let rows = slab_rows * g.shape.depth;
        let rules = SweepRules {
            rule,
            dt,
            frame: self.frame,
        };
        let rests = Self::rests(&self.spec);
        let sweeps: [Option<Sweep<E>>; 2 * FORWARD.len()] = std::array::from_fn(|k| {
            let (direction, colour) = (k / 2, k % 2);
            let (dx, dy, dz) = FORWARD[direction];
            let kind = dx.unsigned_abs() + dy.unsigned_abs() + dz.unsigned_abs() - 1;
            let springs = SweepSprings {
                direction,
                dr: (dy + dz * slab_rows as isize) as usize,
                dc: dx,
                rest: rests[kind],
                kind: self.spec.kinds[kind],
            };
            let colour_of_rows = if dz != 0 {
                Some(RowColour {
                    wrap: usize::MAX,
                    period: slab_rows,
                })
            } else if dy != 0 {
                Some(RowColour {
                    wrap: slab_rows,
                    period: 1,
                })
            } else {
                None
            };
            let class = ColourClass {
                rows: colour_of_rows,
                colour,
            };
            Sweep::new(&rules, springs, (g.shape.width, rows), class)
        });
        // XPBD sweeps back as well on a lattice, each spring's multiplier kept.
        let back = matches!(rule, SpringRule::Xpbd) && xpbd_sweeps_back(Some(g.shape));
        let mut multipliers = std::mem::take(&mut self.multipliers);
        if back {
            multipliers.ensure(sweeps.len(), self.inv_mass.as_slice().len());
        }
        for (k, sweep) in sweeps.iter().enumerate() {
            if let Some(sweep) = sweep {
                let m = back.then(|| multipliers.of_sweep(k, false));
                self.sweep_lines(rule, sweep, m, duo);
            }
        }
        if back {
            // Backward, but for the last sweep, whose springs' second correction
            // would change nothing.
            let last = sweeps.iter().rposition(Option::is_some);
            for (k, sweep) in sweeps.iter().enumerate().rev() {
                if let Some(sweep) = sweep.as_ref().filter(|_| Some(k) != last) {
                    let m = multipliers.of_sweep(k, true);
                    self.sweep_lines(rule, sweep, Some(m), duo);
                }
            }
        }
        self.multipliers = multipliers;
    }

    /// The lines of one sweep, on two threads with `duo` (see
    /// [`Self::spring_pass`]).
    pub(super) fn sweep_lines(
        &mut self,
        rule: SpringRule,
        sweep: &Sweep<E>,
        multipliers: Option<SweepMultipliers<E>>,
        duo: Option<&Duo>,
    ) {
        let g = self.geometry;
        let start = step_start(rule, &self.next);
        let lines = |rows: Range<usize>| SweepLines {
            sweep,
            stride: g.row,
            rows,
            inv_mass: self.inv_mass.as_slice(),
            alive: None,
            real: Some(self.real.as_slice()),
            start,
            multipliers,
            both_colours: false,
        };
        // A line from row `r` touches rows `r` to `r + dr` and, through its lanes
        // past the end (up to `BLOCK` more), the rows after those.
        let all = sweep.rows();
        let split = all.end / 2;
        let touched = sweep.dr() + (g.shape.width + 1 + BLOCK).div_ceil(g.row);
        let above = split.saturating_sub(touched);
        let simd = self.simd;
        match duo {
            Some(duo) if above > 0 => {
                let (mut upper, mut lower) = self.cur.rows().split_at(split * g.row);
                let (top, bottom) = (lines(0..above), lines(split..all.end));
                let mut second = || E::spring_sweep(simd, &mut lower, split * g.row, &bottom);
                duo.fork(&mut second, || E::spring_sweep(simd, &mut upper, 0, &top));
                E::spring_sweep(simd, &mut self.cur.rows(), 0, &lines(above..split));
            }
            _ => E::spring_sweep(simd, &mut self.cur.rows(), 0, &lines(all)),
        }
    }

    /// The colliders with friction, after the step (without friction the step
    /// projected the particles out of the sphere itself): the grid kernel's
    /// contact rows, one lattice row each, on this thread.
    pub(super) fn resolve_contact(&mut self, dt: f64) {
        let contact = Self::contact(&self.spec, dt);
        if !contact.is_active() || self.params.sphere.is_some() {
            return;
        }
        let g = self.geometry;
        let rows = (g.shape.height + 1) * g.shape.depth;
        let (cur, inv_mass) = (&mut self.cur, self.inv_mass.as_slice());
        let rows_of = ContactRows::of_rows(
            &contact,
            (g.shape.width, g.row, inv_mass),
            self.frame,
            self.simd,
            (self.params.verlet, false),
        );
        rows_of.resolve(&mut cur.rows(), 0, 0..rows);
    }

    pub(super) fn one_step(&mut self, parallel: bool, duo: Option<&Duo>) {
        let ctx = Ctx {
            p: self.params,
            geometry: self.geometry,
            x: self.cur.x.each_ref().map(Buf::as_slice),
            v: self.cur.v.each_ref().map(Buf::as_slice),
            u: self.cur.u.each_ref().map(Buf::as_slice),
            real: self.real.as_slice(),
            inv_mass: self.inv_mass.as_slice(),
            simd: self.simd,
        };
        let out = self.next.rows();
        match (duo, &mut self.bands[..]) {
            (Some(duo), [first, second]) => {
                let (out_first, out_second) = out.split_at(second.start);
                duo.fork_once(
                    || E::lattice_band(&ctx, second, out_second),
                    || E::lattice_band(&ctx, first, out_first),
                );
            }
            (_, bands) => run_bands(&ctx, bands, out, parallel),
        }
        std::mem::swap(&mut self.cur, &mut self.next);
    }
}
