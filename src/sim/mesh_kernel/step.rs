//! The mesh engine's step loop: the passes, then the constraints in the f64
//! engine's order (bars, stretch limit, XPBD, self-collision, contact), the speed
//! limit and tearing.

use super::build::{SpringArrays, SpringSet};
use super::passes::{
    Ctx, Leaves, Out, SpringCtx, TriangleCtx, advance, advance_parallel, copy_positions, load,
    restore_length, split_pass, spring_pass, store, triangle_pass,
};
use super::{MIN_LEAF, MeshKernel};
use crate::sim::colliders::poses_at;
use crate::sim::constraints::{xpbd_pass, xpbd_sweeps_back};
use crate::sim::laws::speed_limit;
use crate::sim::laws::{end_of_step_contacts, overstretched};
use crate::sim::springs;
use crate::sim::springs::Adjacency;
use crate::sim::tearing::remove_broken;
use crate::sim::{Integrator, Spring};

impl MeshKernel {
    /// Advances by `n` steps of the parameters' `dt`. On several threads the pool is
    /// entered once for all `n` steps.
    pub fn steps(&mut self, n: usize) {
        match self.pool.take() {
            Some(pool) => {
                let per_task = |len: usize| (len / (4 * self.threads)).max(MIN_LEAF);
                let leaves = Leaves {
                    springs: per_task(self.model_springs.len()),
                    triangles: per_task(self.triangles.len()),
                    particles: per_task(self.len()),
                };
                pool.install(|| {
                    for _ in 0..n {
                        self.one_step(Some(leaves));
                    }
                });
                self.pool = Some(pool);
            }
            None => {
                for _ in 0..n {
                    self.one_step(None);
                }
            }
        }
    }

    /// The step's last phase with a tear strain `tau`, as the f64 engine's
    /// ([`crate::sim::tearing`]): breaks the springs past it, in this engine's copies
    /// (kept for the model in [`Self::take_torn`]). Allocates, but only when
    /// something breaks.
    pub(super) fn tear(&mut self, tau: f64, leaf: Option<usize>) {
        if !self.overstretched(tau, leaf) {
            return;
        }
        let (mut springs, mut triangles) = (
            self.model_springs.clone(),
            std::mem::take(&mut self.triangles),
        );
        let x = self.x.each_ref().map(Vec::as_slice);
        let pairs = remove_broken(&mut springs, &mut triangles, |s| {
            overstretched(load(x, s.a as usize), load(x, s.b as usize), s.rest, tau)
        });
        let arrays = (self
            .springs
            .kept(&self.model_springs, &springs, &self.materials))
        .unwrap_or_else(|| SpringArrays::new(&springs, &self.materials));
        let set = SpringSet {
            constraint_order: springs::constraint_order(&springs, self.grid, self.lattice),
            adjacency: Adjacency::new(self.len(), &springs),
            springs,
            arrays,
            triangles,
        };
        self.set_springs(set);
        self.torn.extend(pairs);
    }

    /// Whether a spring is past the tear strain `tau` ([`overstretched`], the f64
    /// engine's rule); over the springs in ranges of `leaf` on the pool's threads
    /// when given one.
    pub(super) fn overstretched(&self, tau: f64, leaf: Option<usize>) -> bool {
        let x = self.x.each_ref().map(Vec::as_slice);
        let over =
            |s: &Spring| overstretched(load(x, s.a as usize), load(x, s.b as usize), s.rest, tau);
        match leaf {
            Some(leaf) => {
                use rayon::prelude::*;
                self.model_springs.par_iter().with_min_len(leaf).any(over)
            }
            None => self.model_springs.iter().any(over),
        }
    }

    /// Whether springs tore since the model last took them.
    pub fn has_torn(&self) -> bool {
        !self.torn.is_empty()
    }

    /// The ends of the springs torn since the last call, sorted: the model breaks
    /// them too ([`crate::sim::System`]'s `break_springs`) as it takes the state.
    pub fn take_torn(&mut self) -> Vec<(u32, u32)> {
        let mut torn = std::mem::take(&mut self.torn);
        torn.sort_unstable();
        torn
    }

    /// One step; `leaves` when on the pool.
    pub(super) fn one_step(&mut self, leaves: Option<Leaves>) {
        let x = self.x.each_ref().map(Vec::as_slice);
        let v = self.v.each_ref().map(Vec::as_slice);
        let springs = SpringCtx {
            springs: &self.springs,
            x,
            v,
            avx2: self.avx2,
        };
        let out = self.spring_f.each_mut().map(Vec::as_mut_slice);
        let pass = |start: usize, out: [&mut [f64]; 3]| spring_pass(&springs, start, out);
        match leaves {
            _ if !self.params.spring_forces => {}
            Some(leaves) => split_pass(0, out, leaves.springs, &pass),
            None => pass(0, out),
        }
        if let Some(drag) = self.params.drag {
            let triangles = TriangleCtx {
                triangles: &self.triangles,
                x,
                v,
                wind: drag.wind.at(self.time),
                half_rho_cd: drag.half_rho_cd,
            };
            let out = self.triangle_f.each_mut().map(Vec::as_mut_slice);
            let pass = |start: usize, out: [&mut [f64]; 3]| triangle_pass(&triangles, start, out);
            match leaves {
                Some(leaves) => split_pass(0, out, leaves.triangles, &pass),
                None => pass(0, out),
            }
        }
        let ctx = Ctx {
            p: self.params,
            x,
            v,
            inv_mass: &self.inv_mass,
            offsets: &self.offsets,
            links: &self.links,
            spring_f: self.spring_f.each_ref().map(Vec::as_slice),
            triangle_offsets: &self.triangle_offsets,
            triangle_links: &self.triangle_links,
            triangle_f: self.triangle_f.each_ref().map(Vec::as_slice),
        };
        let out = Out {
            start: 0,
            x: self.x_next.each_mut().map(Vec::as_mut_slice),
            v: self.v_next.each_mut().map(Vec::as_mut_slice),
            u: self.u.each_mut().map(Vec::as_mut_slice),
        };
        match leaves {
            Some(leaves) => advance_parallel(&ctx, out, leaves.particles),
            None => advance(&ctx, out),
        }
        std::mem::swap(&mut self.x, &mut self.x_next);
        std::mem::swap(&mut self.v, &mut self.v_next);
        if self.has_constraints() {
            self.constrain();
        }
        if let Some(max_speed) = self.params.max_speed {
            self.limit_speed(max_speed);
        }
        if let Some(tau) = self.params.tear_strain {
            self.tear(tau, leaves.map(|l| l.springs));
        }
        // As the f64 engine's clock: one `dt` added per step.
        self.time += self.params.dt;
    }

    /// The speed limit, as the f64 engine applies it after the constraints
    /// ([`speed_limit`]): a faster particle's velocity (and Verlet's update
    /// velocity) scaled down to it.
    pub(super) fn limit_speed(&mut self, max_speed: f64) {
        let verlet = !self.u[0].is_empty();
        for i in 0..self.len() {
            let factor = speed_limit(load(self.v.each_ref().map(Vec::as_slice), i), max_speed);
            if factor < 1.0 {
                for a in 0..3 {
                    self.v[a][i] *= factor;
                    if verlet {
                        self.u[a][i] *= factor;
                    }
                }
            }
        }
    }

    /// Bars, stretch limit, then `v += δ/h` (and `u` for Verlet) and the colliders'
    /// contact with friction, in the f64 engine's order.
    pub(super) fn constrain(&mut self) {
        let p = self.params;
        for k in 0..3 {
            self.before[k].copy_from_slice(&self.x[k]);
        }
        if p.integrator == Integrator::Xpbd {
            self.xpbd_pass();
        }
        let x = &mut self.x;
        let inv_mass = &self.inv_mass;
        for _ in 0..p.bar_iterations {
            for bar in &self.bars {
                restore_length(x, inv_mass, bar.a as usize, bar.b as usize, |l| {
                    (l != bar.length).then_some(bar.length)
                });
            }
        }
        if let Some(tau) = p.stretch_limit {
            for s in self
                .constraint_order
                .iter()
                .map(|&i| &self.model_springs[i as usize])
            {
                let longest = (1.0 + tau) * s.rest;
                restore_length(x, inv_mass, s.a as usize, s.b as usize, |l| {
                    (l > longest).then_some(longest)
                });
            }
        }
        if let Some(h_c) = p.self_collision {
            self.self_collision_pass(h_c);
        }
        let h = p.dt;
        let contact = self.contact();
        // The colliders where they are at the end of the step.
        poses_at(&self.colliders, self.time + h, &mut self.collider_poses);
        let solids = (&self.colliders[..], &self.collider_poses[..]);
        let verlet = !self.u[0].is_empty();
        for i in 0..self.inv_mass.len() {
            let before = load(self.before.each_ref().map(Vec::as_slice), i);
            let x = load(self.x.each_ref().map(Vec::as_slice), i);
            let v_old = load(self.v.each_ref().map(Vec::as_slice), i);
            let v = v_old + (x - before) / h;
            let (x, v) = end_of_step_contacts(&contact, solids, (x, v), self.inv_mass[i], h);
            store(&mut self.x.each_mut().map(Vec::as_mut_slice), i, x);
            store(&mut self.v.each_mut().map(Vec::as_mut_slice), i, v);
            if verlet {
                let u = load(self.u.each_ref().map(Vec::as_slice), i) + (v - v_old);
                store(&mut self.u.each_mut().map(Vec::as_mut_slice), i, u);
            }
        }
    }

    /// Self-collision ([`crate::sim::self_collision`]) at thickness `h_c`, as the f64
    /// engine runs it after the stretch limit: on a copy of the positions, reading
    /// those at the start of the step (the other half of the ping-pong pair) and
    /// the inverse masses for the pairs in contact; the particles it moved are
    /// written back. On the pool's threads when the engine has them (the same
    /// result as on one).
    pub(super) fn self_collision_pass(&mut self, h_c: f64) {
        let mut x = std::mem::take(&mut self.copy_x);
        copy_positions(&mut x, &self.x);
        let (start, inv_mass) = (self.x_next.each_ref().map(Vec::as_slice), &self.inv_mass);
        let particle = |i: usize| (load(start, i), inv_mass[i]);
        let (adjacency, springs, bars) = (&self.adjacency, &self.model_springs, &self.bar_pairs);
        let joined = |i: usize, j: usize| adjacency.joins(springs, i, j) || bars.join(i, j);
        let (friction, parallel) = (self.params.friction, self.pool.is_some());
        let pass = &mut self.self_collision;
        pass.apply(&mut x, particle, h_c, friction, joined, parallel);
        let mut positions = self.x.each_mut().map(Vec::as_mut_slice);
        for &i in self.self_collision.moved() {
            store(&mut positions, i as usize, x[i as usize]);
        }
        self.copy_x = x;
    }

    /// XPBD's springs ([`xpbd_pass`], the f64 engine's pass) on copies of the
    /// positions now and at the start of the step (the other half of the ping-pong
    /// pair), written back whole.
    pub(super) fn xpbd_pass(&mut self) {
        let (mut x, mut start) = (
            std::mem::take(&mut self.copy_x),
            std::mem::take(&mut self.copy_start),
        );
        copy_positions(&mut x, &self.x);
        copy_positions(&mut start, &self.x_next);
        let springs = (&self.model_springs[..], &self.materials);
        let order = (&self.constraint_order[..], xpbd_sweeps_back(self.lattice));
        xpbd_pass(
            &mut x,
            &start,
            springs,
            order,
            &self.inv_mass,
            self.params.dt,
            &mut self.multipliers,
        );
        let mut positions = self.x.each_mut().map(Vec::as_mut_slice);
        for (i, &p) in x.iter().enumerate() {
            store(&mut positions, i, p);
        }
        (self.copy_x, self.copy_start) = (x, start);
    }

    /// Pairs pushed apart by the last self-collision pass.
    pub fn self_collision_contacts(&self) -> usize {
        self.self_collision.contacts()
    }
}
