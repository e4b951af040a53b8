//! The grid kernel's step loop: `n` steps in one entry into the thread pool, each
//! the fused row pass (`row`) and then the constraints in the f64 engine's order
//! (XPBD, stretch limit, self-collision, contact, speed limit, tear).

use glam::DVec3;

use super::frame::{self, Frame};
#[cfg(target_arch = "x86_64")]
use super::x86;
use super::{
    Buf, ContactRows, Ctx, Duo, Kernel, Out, Real, SimdLevel, SpringPass, SpringRule, State,
    run_bands, run_two_bands, step_start,
};
use crate::sim::duo::run_in_pool;
use crate::sim::laws;
use crate::sim::{Integrator, Wind};

/// Grids with at least this many particles hand their second band (and the spring
/// passes and the tear scan their second half) over by spinning ([`Duo`]) rather
/// than with `rayon::join`, when no pass after the step uses rayon's parallel
/// iterators. Measured on two AVX-512 cores (best of 3 runs of 960 steps, old and
/// new binaries interleaved): 1.12x to 1.24x at 256 x 256, 0.9x to 1.1x at 128 x 128
/// and 0.85x at 96 x 96; in runs of 10,000 steps 1.5x at 128 x 128. At the start of
/// a run the system may put both threads on one core for a few milliseconds, and
/// a short step loses most there.
const SPIN_MIN_PARTICLES: usize = 128 * 128;

impl<E: Real> Kernel<E> {
    /// Advance by one semi-implicit Euler step of `dt` seconds.
    pub fn step(&mut self, dt: f64) {
        self.steps(dt, 1);
    }

    /// Advance by `n` steps of `dt` seconds. On several threads the pool is entered
    /// once for all `n` steps, so prefer this to calling [`GridCloth::step`] in a loop.
    pub fn steps(&mut self, dt: f64, n: usize) {
        self.steps_in_wind(dt, n, None);
    }

    /// `n` steps of `dt`; with `wind = Some((t0, wind))` step `i` blows
    /// `wind.at(t0 + i dt)` (gusts), all inside one entry into the thread pool.
    pub(super) fn steps_in_wind(&mut self, dt: f64, n: usize, wind: Option<(f64, &Wind)>) {
        self.params.dt = E::of(dt);
        if self.params.verlet {
            self.params.verlet_half_dt = E::of(0.5 * dt);
        }
        let pool = self.pool.take();
        let parallel = pool.is_some();
        // Two bands and no pass after the step that splits its work with rayon: the
        // second band (and the spring passes' second half) is handed over by
        // spinning (`Duo`).
        let spin = parallel
            && self.par_bands.len() == 2
            && self.len() >= SPIN_MIN_PARTICLES
            && !self.has_pooled_constraints();
        let run = |duo: Option<&Duo>| {
            for i in 0..n {
                if i % frame::CHECK_STEPS == 0 {
                    self.keep_in_frame(frame::CHECK_STEPS.min(n - i) as f64 * dt);
                }
                if let Some((t0, wind)) = wind {
                    self.set_wind(wind.at(t0 + i as f64 * dt));
                }
                self.one_step(dt, parallel, duo);
                self.constrain(dt, parallel, duo);
                self.solids.time += dt;
            }
        };
        run_in_pool(pool.as_ref(), spin, run);
        self.pool = pool;
    }

    /// Whether a pass after the step splits its work with rayon's parallel
    /// iterators (self-collision), which need the pool's other thread free.
    pub(super) fn has_pooled_constraints(&self) -> bool {
        self.spec.self_collision.is_some()
    }

    /// One step of `dt` (the one [`Self::params`] holds, in f64), and what comes
    /// first after it when the step can run it on its rows as it writes them: the
    /// colliders' contact ([`Self::contact_in_step`]) or the one spring pass
    /// ([`Self::spring_pass_in_step`]).
    pub(super) fn one_step(&mut self, dt: f64, parallel: bool, duo: Option<&Duo>) {
        let colliders = self.contact(dt);
        let contact = self.contact_in_step().then(|| {
            let cloth = (self.grid, self.inv_mass.as_slice());
            ContactRows::new(
                &colliders,
                cloth,
                self.frame,
                self.simd,
                (self.params.verlet, true),
            )
        });
        // The spring pass after the step, run by the step on each band's rows.
        let planned = self
            .spring_pass_in_step(parallel)
            .map(|rule| (rule, self.sweep_plan(rule, dt)));
        let springs = planned.map(|(rule, plan)| SpringPass {
            plan,
            inv_mass: self.inv_mass.as_slice(),
            simd: self.simd,
            torn: self.torn.as_ref(),
            start: step_start(rule, &self.cur),
        });
        let ctx = Ctx {
            grid: self.grid,
            p: self.params,
            x: self.cur.x.each_ref().map(Buf::as_slice),
            v: self.cur.v.each_ref().map(Buf::as_slice),
            u: self.cur.u.each_ref().map(Buf::as_slice),
            inv_mass: self.inv_mass.as_slice(),
            col_mask: self.col_mask.as_slice(),
            // In the order `block` evaluates them: right, two right, down,
            // down-right, the other diagonal (down-left from the next column), two
            // down, then the two triangles.
            torn: self.torn.as_ref().map(|t| {
                let [right, two_right, down_left, down, down_right, two_down] =
                    t.springs.each_ref().map(Buf::as_slice);
                let [first, second] = t.triangles.each_ref().map(Buf::as_slice);
                [
                    right, two_right, down, down_right, down_left, two_down, first, second,
                ]
            }),
            drag: self.drag_on,
            simd: self.simd,
            contact: contact.as_ref(),
            springs: springs.as_ref(),
            rows_in_cache: self.rows_in_cache(),
        };
        let real = self.grid.h * self.grid.stride;
        fn rows<E: Real>(arrays: &mut [Buf<E>; 3], real: usize) -> [&mut [E]; 3] {
            arrays.each_mut().map(|b| {
                let a = b.as_mut_slice();
                let len = real.min(a.len());
                &mut a[..len]
            })
        }
        let State { x, v, u } = &mut self.next;
        let ([x0, x1, x2], [v0, v1, v2], [u0, u1, u2]) =
            (rows(x, real), rows(v, real), rows(u, real));
        let mut out = Out([x0, x1, x2, v0, v1, v2, u0, u1, u2]);
        let bands = if parallel && self.par_bands.len() > 1 {
            &mut self.par_bands
        } else {
            &mut self.seq_band
        };
        if let Some(duo) = duo {
            run_two_bands(&ctx, bands, out.reborrow(), duo);
        } else {
            run_bands(&ctx, bands, out.reborrow(), parallel);
        }
        // The spring pass's lines between the two bands, once both have run.
        if let (Some(springs), [_, second]) = (&springs, &bands[..]) {
            springs.between_bands(&mut out, second.r0);
        }
        std::mem::swap(&mut self.cur, &mut self.next);
    }

    /// The constraints the fused row pass leaves to after the step: XPBD's springs,
    /// Provot's stretch limit, then the colliders' contact with friction, as in the
    /// f64 engine. A move `δ` of a particle also adds `δ / h` to its velocity.
    /// With `duo`, the pool's other thread is serving it: the spring passes hand
    /// it their second half, and the passes that would split their work with rayon
    /// run on this thread ([`Kernel::has_pooled_constraints`] keeps them out of
    /// that mode).
    pub(super) fn constrain(&mut self, dt: f64, parallel: bool, duo: Option<&Duo>) {
        let parallel_pooled = parallel && duo.is_none();
        // Unless the step ran it ([`Self::spring_pass_in_step`]).
        if self.spring_pass_in_step(parallel).is_none() {
            if self.spec.integrator == Integrator::Xpbd {
                self.spring_pass(SpringRule::Xpbd, dt, parallel, duo);
            }
            if let Some(tau) = self.spec.stretch_limit {
                self.spring_pass(SpringRule::StretchLimit(tau), dt, parallel, duo);
            }
        }
        let parallel = parallel_pooled;
        if let Some(thickness) = self.spec.self_collision {
            self.self_collision_pass(thickness, dt, parallel);
        }
        let contact = self.contact(dt);
        // Without friction, stretch limit or XPBD the step itself projected the
        // particles out of the sphere; with nothing before the contact, the step
        // resolved it.
        if contact.is_active() && self.params.sphere.is_none() && !self.contact_in_step() {
            self.resolve_contact(&contact, parallel, duo);
        }
        self.collide_pass(dt, parallel, duo);
        if let Some(max_speed) = self.spec.max_speed {
            self.limit_speed(max_speed);
        }
        if let Some(tau) = self.spec.tear_strain {
            self.tear_pass(tau, parallel, duo);
        }
    }

    /// The spring pass that the step runs on each band's rows as soon as they are
    /// stepped, in the same hand-over ([`SpringPass`]), while the rows are in the
    /// core's cache: the only spring pass after the step (XPBD's or the stretch
    /// limit's, not both), when the step runs in one band or two (the pass's
    /// own halves, [`Self::spring_pass`]). The pass's lines then see the same
    /// positions as after the whole step: a band's lines touch only rows it has
    /// stepped, and the step reads only the positions before it.
    pub(super) fn spring_pass_in_step(&self, parallel: bool) -> Option<SpringRule> {
        let rule = match (self.spec.integrator, self.spec.stretch_limit) {
            (Integrator::Xpbd, None) => SpringRule::Xpbd,
            (Integrator::Xpbd, Some(_)) => return None,
            (_, Some(tau)) => SpringRule::StretchLimit(tau),
            (_, None) => return None,
        };
        let bands = if parallel { self.par_bands.len() } else { 1 };
        (bands <= 2).then_some(rule)
    }

    /// The colliders' contact after a step of `dt`.
    pub(super) fn contact(&self, dt: f64) -> laws::Contact {
        laws::Contact {
            sphere: self.spec.sphere,
            ground: self.spec.ground,
            friction: self.spec.friction,
            dt,
        }
    }

    /// Whether the step resolves the colliders' contact on each band's rows as
    /// soon as they are stepped, in the same hand-over (one fork and join a step,
    /// not two): when the contact is the first constraint after the step (no
    /// XPBD, stretch limit or self-collision) and the step does not project onto
    /// the sphere itself; the ground's friction then goes to each row as soon as
    /// it is stepped ([`ContactRows::ground_friction_row`]). Each particle's
    /// contact is its own, so the result is the same.
    pub(super) fn contact_in_step(&self) -> bool {
        self.spec.integrator != Integrator::Xpbd
            && self.spec.stretch_limit.is_none()
            && self.spec.self_collision.is_none()
            && self.params.sphere.is_none()
            && self.contact(0.0).is_active()
    }

    /// The speed limit, as the f64 engine applies it ([`laws::speed_limit`]):
    /// a cheap check in the kernel's precision, then the particle's velocity (and
    /// Verlet's update velocity) scaled in f64.
    pub(super) fn limit_speed(&mut self, max_speed: f64) {
        let limit2 = E::of(max_speed * max_speed);
        let verlet = self.params.verlet;
        let (w, st) = (self.grid.w, self.grid.stride);
        for r in 0..self.grid.h {
            let row = r * st..r * st + w;
            let [vx, vy, vz] = self.cur.v.each_ref().map(|a| &a.as_slice()[row.clone()]);
            // A vectorised scan of the row, then the particles over the limit one
            // by one: the same test either way.
            let any = match self.simd {
                #[cfg(target_arch = "x86_64")]
                // SAFETY: the level is AVX2 or AVX-512 only when the CPU has AVX2.
                SimdLevel::Avx2 | SimdLevel::Avx512 => unsafe {
                    x86::any_faster_avx2([vx, vy, vz], limit2)
                },
                _ => any_faster([vx, vy, vz], limit2),
            };
            if !any {
                continue;
            }
            for i in row {
                let v = self.cur.v.each_ref().map(|a| a.as_slice()[i]);
                if !faster(v, limit2) {
                    continue;
                }
                let factor = laws::speed_limit(DVec3::from(v.map(E::f64)), max_speed);
                for a in 0..3 {
                    let v = &mut self.cur.v[a].as_mut_slice()[i];
                    *v = E::of(v.f64() * factor);
                    if verlet {
                        let u = &mut self.cur.u[a].as_mut_slice()[i];
                        *u = E::of(u.f64() * factor);
                    }
                }
            }
        }
    }

    /// Self-collision ([`crate::sim::self_collision`]) at thickness `h_c`, on an f64
    /// copy of the positions (made on the pool's threads with `parallel`); springs
    /// are the stencil's kinds that exist. The pass reads the positions at the
    /// start of the step and the inverse masses from the kernel's arrays, for the
    /// pairs in contact only, and only the particles it moved are written back,
    /// each with its move over `dt` added to its velocity.
    pub(super) fn self_collision_pass(&mut self, h_c: f64, dt: f64, parallel: bool) {
        let (width, h, st) = (self.grid.w, self.grid.h, self.grid.stride);
        let n = width * h;
        let parallel = parallel && n >= crate::sim::self_collision::PARALLEL_MIN_PARTICLES;
        let mut x = std::mem::take(&mut self.self_collision_scratch);
        x.resize(n, DVec3::ZERO);
        let (positions, frame) = (&self.cur.x, &self.frame);
        // Blocks of 8 rows, each row's arrays read as slices.
        let copy = |(k, out): (usize, &mut [DVec3])| {
            for (r, out) in out.chunks_exact_mut(width).enumerate() {
                row_to_f64(out, frame, positions, (8 * k + r) * st);
            }
        };
        if parallel {
            use rayon::prelude::*;
            x.par_chunks_mut(8 * width).enumerate().for_each(copy);
        } else {
            x.chunks_mut(8 * width).enumerate().for_each(copy);
        }

        // The stencil direction of each step `(dr, dc)` from a particle to one after
        // it (`dr` 0 to 2, `dc` -2 to 2) whose kind of spring exists, and the
        // springs left when some tore. (The search asks this of every pair within
        // its reach: by table and in 32 bits, the fold scene ran 1% fewer
        // instructions than with a search of the stencil; valgrind, 1,500 steps.)
        let mut direction = [[None; 5]; 3];
        for (d, stencil) in self.stencil().into_iter().enumerate() {
            if stencil.present {
                let (dr, dc) = stencil.offset;
                direction[dr][(dc + 2) as usize] = Some(d);
            }
        }
        let torn = self.torn.as_ref();
        let w = width as u32;
        let joined = |i: usize, j: usize| {
            let (a, b) = (i.min(j) as u32, i.max(j) as u32);
            let (dr, dc) = (b / w - a / w, (b % w) as i32 - (a % w) as i32);
            let d = (dr <= 2 && dc.abs() <= 2)
                .then(|| direction[dr as usize][(dc + 2) as usize])
                .flatten();
            d.is_some_and(|d| torn.is_none_or(|t| t.has(a as usize, d)))
        };
        // Each particle's position at the start of the step (the other state
        // buffer, after the swap) and inverse mass.
        let (start, inv_mass) = (self.next.x.each_ref().map(Buf::as_slice), &self.inv_mass);
        let particle = |i: usize| {
            let g = (i / width) * st + i % width;
            (frame.decode3(&start, g), inv_mass.as_slice()[g].f64())
        };
        let (friction, pass) = (self.spec.friction, &mut self.self_collision);
        pass.apply(&mut x, particle, h_c, friction, joined, parallel);
        for k in 0..self.self_collision.moved().len() {
            let i = self.self_collision.moved()[k] as usize;
            let g = (i / width) * st + i % width;
            if x[i] != self.position_at(g) {
                self.move_particle(g, x[i], dt);
            }
        }
        self.self_collision_scratch = x;
    }

    /// Pairs pushed apart by the last self-collision pass.
    pub(super) fn self_collision_contacts(&self) -> usize {
        self.self_collision.contacts()
    }

    /// Moves the particle at array index `i` to `to` (m) after a step of `dt`,
    /// adding the move over `dt` to its velocities.
    pub(super) fn move_particle(&mut self, i: usize, to: DVec3, dt: f64) {
        let dv = (to - self.position_at(i)) / dt;
        self.set_position_at(i, to);
        for a in 0..3 {
            self.cur.v[a].as_mut_slice()[i] += E::of(dv[a]);
            if self.params.verlet {
                self.cur.u[a].as_mut_slice()[i] += E::of(dv[a]);
            }
        }
    }
}

/// Whether a particle moving at `[vx, vy, vz]` is faster than `sqrt(limit2)`, in
/// the kernel's precision (the speed limit's cheap test).
#[inline(always)]
pub(super) fn faster<E: Real>([vx, vy, vz]: [E; 3], limit2: E) -> bool {
    vx * vx + vy * vy + vz * vz > limit2
}

/// Whether any of the particles with velocities `[vx, vy, vz]` is [`faster`] than
/// `sqrt(limit2)`: a plain loop for the compiler to vectorise, the verdict an
/// integer OR.
#[inline(always)]
pub(super) fn any_faster<E: Real>([vx, vy, vz]: [&[E]; 3], limit2: E) -> bool {
    let (vy, vz) = (&vy[..vx.len()], &vz[..vx.len()]);
    let mut any = 0u8;
    for c in 0..vx.len() {
        any |= u8::from(faster([vx[c], vy[c], vz[c]], limit2));
    }
    any != 0
}

/// One row of positions (m) in `frame` from array index `start` on, into `out`
/// (as many particles as it holds).
pub(super) fn row_to_f64<E: Real>(out: &mut [DVec3], frame: &Frame, x: &[Buf<E>; 3], start: usize) {
    let at = start..start + out.len();
    let [x, y, z] = x.each_ref().map(|a| &a.as_slice()[at.clone()]);
    for (c, p) in out.iter_mut().enumerate() {
        *p = DVec3::new(
            frame.decode(x[c], 0),
            frame.decode(y[c], 1),
            frame.decode(z[c], 2),
        );
    }
}
