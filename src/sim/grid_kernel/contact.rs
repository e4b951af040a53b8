//! Contact with the colliders after the step, where friction (or a stretch limit,
//! XPBD or self-collision before it) keeps it out of the fused step: the shared
//! [`laws::Contact::resolve_lanes`] on blocks of particles, on the rows
//! that may touch; in float64 near the sphere, the ground's friction alone in the
//! kernel's float. When the contact comes first after the step, each band
//! resolves its rows as soon as it has stepped them, and the ground's friction
//! is given to each row right after it, on the kernel's own vectors
//! ([`ContactRows::ground_friction_row`]).

use super::super::duo::Duo;
use super::super::lanes::{Floats, Lanes, V3};
use super::super::laws::Near;
use super::frame::whole_units;
use super::row::difference;
use super::simd::{Simd, Vector, align_frame};
#[cfg(target_arch = "x86_64")]
use super::x86;
use super::{Frame, Grid, Kernel, Out, PARALLEL_MIN_PARTICLES, Real, SimdLevel};
use crate::sim::laws;

impl<E: Real> Kernel<E> {
    /// The colliders' contact of every free particle that touches one, as the f64
    /// engine resolves it ([`laws::Contact::resolve`]), on the pool's two
    /// threads when it has them: see [`ContactRows`].
    pub(super) fn resolve_contact(
        &mut self,
        contact: &laws::Contact,
        parallel: bool,
        duo: Option<&Duo>,
    ) {
        let (w, h) = (self.grid.w, self.grid.h);
        let ctx = ContactRows::new(
            contact,
            (self.grid, self.inv_mass.as_slice()),
            self.frame,
            self.simd,
            (self.params.verlet, false),
        );
        let split = (parallel || duo.is_some()) && w * h >= PARALLEL_MIN_PARTICLES;
        let stride = self.grid.stride;
        in_halves(
            self.cur.rows(),
            (h, stride),
            split,
            duo,
            |out, first, rows| ctx.resolve(out, first, rows),
        );
    }
}

/// `resolve(out, first, rows)` over all `h` rows (of `stride` array indices) of
/// `out`: with `split`, in two halves of the rows on two threads (the pool's, or
/// `duo`'s), for passes in which each particle's result is its own.
pub(super) fn in_halves<E: Send>(
    out: Out<E>,
    (h, stride): (usize, usize),
    split: bool,
    duo: Option<&Duo>,
    resolve: impl Fn(&mut Out<E>, usize, std::ops::Range<usize>) + Sync,
) {
    if !split {
        return resolve(&mut { out }, 0, 0..h);
    }
    let half = h / 2;
    let (mut first, mut second) = out.split_at(half * stride);
    let mut second_half = || resolve(&mut second, half, half..h);
    let first_half = || resolve(&mut first, 0, 0..half);
    match duo {
        Some(duo) => duo.fork(&mut second_half, first_half),
        None => {
            rayon::join(first_half, second_half);
        }
    }
}

/// What resolving the contacts of rows reads ([`Kernel::resolve_contact`]).
pub(super) struct ContactRows<'a, E> {
    pub(super) simd: SimdLevel,
    pub(super) width: usize,
    pub(super) stride: usize,
    pub(super) inv_mass: &'a [E],
    /// Where a particle may touch what [`ContactRows::resolve`] resolves (the
    /// ground left out when the step gives its friction).
    pub(super) reach: Reach<E>,
    /// The ground's height as stored (below every particle without a ground).
    pub(super) ground: E,
    /// Whether the step gives the ground's friction to each row as soon as it is
    /// stepped, to the particles not near the sphere
    /// ([`ContactRows::ground_friction_row`]), and `resolve` the rest.
    pub(super) friction_in_rows: bool,
    pub(super) contact: &'a laws::Contact,
    /// How the positions are stored.
    pub(super) frame: Frame,
    pub(super) verlet: bool,
}

/// Particles [`ContactRows`] resolves together, one per lane.
const CONTACT_LANES: usize = 8;

/// A pass over rows of a kernel's arrays in which each particle's result is its
/// own (contact, the colliders), compiled for the kernel's SIMD level.
pub(super) trait RowsPass<E: Real> {
    /// The level the pass runs at.
    fn simd(&self) -> SimdLevel;

    /// The pass over rows `rows`, whose arrays `out` holds from row `first` on,
    /// compiled for the caller's SIMD level (inlined into each level's entry).
    fn rows(&self, out: &mut Out<E>, first: usize, rows: impl Iterator<Item = usize>);

    /// [`RowsPass::rows`] with the code for the pass's level.
    fn resolve(&self, out: &mut Out<E>, first: usize, rows: impl Iterator<Item = usize>) {
        match self.simd() {
            #[cfg(target_arch = "x86_64")]
            // SAFETY: the level is AVX-512 only when the CPU has AVX-512F/VL, AVX2 and FMA.
            SimdLevel::Avx512 => unsafe { x86::rows_avx512(self, out, first, rows) },
            #[cfg(target_arch = "x86_64")]
            // SAFETY: the level is AVX2 only when the CPU has AVX2 and FMA.
            SimdLevel::Avx2 => unsafe { x86::rows_avx2(self, out, first, rows) },
            _ => self.rows(out, first, rows),
        }
    }
}

impl<E: Real> RowsPass<E> for ContactRows<'_, E> {
    fn simd(&self) -> SimdLevel {
        self.simd
    }

    #[inline(always)]
    fn rows(&self, out: &mut Out<E>, first: usize, rows: impl Iterator<Item = usize>) {
        self.resolve_rows(out, first, rows)
    }
}

impl<'a, E: Real> ContactRows<'a, E> {
    /// The contact with the colliders of `contact` of a grid's cloth: its
    /// inverse masses, frame, SIMD level, whether it steps by Verlet, and whether
    /// it is resolved in the step (`in_step`, [`super::Kernel::contact_in_step`]),
    /// where the ground's friction goes to each row as soon as it is stepped.
    pub(super) fn new(
        contact: &'a laws::Contact,
        (grid, inv_mass): (Grid, &'a [E]),
        frame: Frame,
        simd: SimdLevel,
        (verlet, in_step): (bool, bool),
    ) -> Self {
        let cloth = (grid.w, grid.stride, inv_mass);
        Self::of_rows(contact, cloth, frame, simd, (verlet, in_step))
    }

    /// [`ContactRows::new`] for rows of `width` particles every `stride` array
    /// indices (a grid's, or a lattice's).
    pub(super) fn of_rows(
        contact: &'a laws::Contact,
        (width, stride, inv_mass): (usize, usize, &'a [E]),
        frame: Frame,
        simd: SimdLevel,
        (verlet, in_step): (bool, bool),
    ) -> Self {
        let friction_in_rows = in_step && contact.ground.is_some_and(|g| g.friction > 0.0);
        let resolved = if friction_in_rows {
            laws::Contact {
                ground: None,
                ..*contact
            }
        } else {
            *contact
        };
        let ground = contact.ground.map_or(f64::NEG_INFINITY, |g| g.height);
        ContactRows {
            simd,
            width,
            stride,
            inv_mass,
            reach: Reach::of(&resolved, &frame),
            ground: frame.ground_height(ground),
            friction_in_rows,
            contact,
            frame,
            verlet,
        }
    }

    /// Resolves the particles of the rows `rows` that may touch a collider, whose
    /// arrays `out` holds from row `first` on. A vectorised scan of a row first
    /// ([`row_may_touch`]) skips the rows with none that may ([`Reach::may_touch`]:
    /// a particle out of reach would leave `resolve` unchanged, so skipping it
    /// changes nothing); in the others, in blocks of [`CONTACT_LANES`] columns,
    /// those that may touch are resolved together
    /// ([`laws::Contact::resolve_lanes`], which gives each exactly what
    /// `resolve` gives it alone): in float64 where a lane is near the sphere (bit
    /// for bit the f64 engine's contact); where none is, the ground's friction in
    /// the kernel's own float, that of its velocities (in a float32 kernel, rounded
    /// to float32: the conversions to float64 and back had the contact at 23% of a
    /// one-core drape at 128, 21% without). A row's last block reads past its last
    /// column: the grid's ghost columns (its rows are [`super::BLOCK`] floats longer than their
    /// blocks), or the next row of a lattice (whose arrays end in ghosts); lanes
    /// that do not touch are written back what they held.
    #[inline(always)]
    fn resolve_rows(&self, out: &mut Out<E>, first: usize, rows: impl Iterator<Item = usize>) {
        align_frame();
        if self.frame.fixed {
            self.resolve_rows_in::<true>(out, first, rows)
        } else {
            self.resolve_rows_in::<false>(out, first, rows)
        }
    }

    /// [`ContactRows::resolve_rows`] with positions in fixed point (`FIXED`) or
    /// floats.
    #[inline(always)]
    fn resolve_rows_in<const FIXED: bool>(
        &self,
        out: &mut Out<E>,
        first: usize,
        rows: impl Iterator<Item = usize>,
    ) {
        const N: usize = CONTACT_LANES;
        let [x, y, z, vx, vy, vz, ux, uy, uz] = &mut out.0;
        let (mut pos, vel, upd) = ([x, y, z], [vx, vy, vz], [ux, uy, uz]);
        let frame = &self.frame;
        // The colliders' coordinates as stored and in metres (0 for an absent
        // one, which `resolve_lanes` then leaves out).
        let exact = self
            .contact
            .sphere
            .map_or([0.0; 3], |s| s.center.to_array());
        let centre: [(E, f64); 3] = std::array::from_fn(|a| (self.reach.center[a], exact[a]));
        let ground = (self.ground, self.contact.ground.map_or(0.0, |g| g.height));
        for r in rows {
            let start = r * self.stride;
            let row = (r - first) * self.stride..(r - first) * self.stride + self.width;
            let coordinates = [&pos[0][row.clone()], &pos[1][row.clone()], &pos[2][row]];
            let masses = &self.inv_mass[start..start + self.width];
            if !row_may_touch::<E, FIXED>(coordinates, masses, &self.reach) {
                continue;
            }
            for c in (0..self.width).step_by(N) {
                let (i, j) = (start + c, (r - first) * self.stride + c);
                // Every slice `N` long, in the compiler's sight. (Written out:
                // arrays' `map` was left a call in this loop.)
                let w = &self.inv_mass[i..i + N];
                let (px, py, pz) = (&pos[0][j..j + N], &pos[1][j..j + N], &pos[2][j..j + N]);
                let (mut touch, mut sphere) = ([false; N], [false; N]);
                for l in 0..N {
                    let real = (c + l < self.width) & (w[l] > E::ZERO);
                    let at = [px[l], py[l], pz[l]];
                    sphere[l] = real & self.reach.near_sphere::<FIXED>(at);
                    touch[l] = sphere[l] | (real & self.reach.below_ground::<FIXED>(at));
                }
                if !touch.contains(&true) {
                    continue;
                }
                // The touching lanes' changes of velocity.
                let dv: [[E; N]; 3] = if !sphere.contains(&true) {
                    // None near the sphere: only the ground's friction, which
                    // leaves the positions as they are (`resolve_lanes` gives the
                    // same, its sphere part then changing nothing); in the
                    // kernel's float, whose velocities these are.
                    let lanes = |p: &[E]| {
                        let p = &p[j..j + N];
                        Floats::<E, N>(std::array::from_fn(|l| p[l]))
                    };
                    let v = V3 {
                        x: lanes(vel[0]),
                        y: lanes(vel[1]),
                        z: lanes(vel[2]),
                    };
                    // Height (m) above the ground: from the stored one in fixed
                    // point, exact (both are whole units), from the exact one in
                    // floats.
                    let (stored, exact) = (self.ground, E::of(ground.1));
                    let above = Floats::<E, N>(std::array::from_fn(|l| {
                        if FIXED {
                            E::fixed_sub(py[l], stored) * E::of(frame.unit)
                        } else {
                            py[l] - exact
                        }
                    }));
                    let mass = Floats::<E, N>(std::array::from_fn(|l| w[l]));
                    let v_new = self.contact.ground_friction_lanes(above, v, mass);
                    change(v_new, v, |dv| dv)
                } else {
                    let [x, y, z] = &mut pos;
                    let (pos, vel) = (
                        [&mut ***x, &mut ***y, &mut ***z],
                        [&**vel[0], &**vel[1], &**vel[2]],
                    );
                    self.resolve_near_sphere::<FIXED>(pos, vel, (i, j), (centre, ground), &touch)
                };
                // The touching lanes' velocities get the change (and Verlet's
                // update velocities with them).
                for (a, dv) in dv.iter().enumerate() {
                    let speed = &mut vel[a][j..j + N];
                    for l in 0..N {
                        speed[l] = E::select(touch[l], speed[l] + dv[l], speed[l]);
                    }
                    if self.verlet {
                        let update = &mut upd[a][j..j + N];
                        for l in 0..N {
                            update[l] = E::select(touch[l], update[l] + dv[l], update[l]);
                        }
                    }
                }
            }
        }
    }

    /// The ground's friction on the row just stepped, given as soon as it is
    /// (`friction_in_rows`), on the kernel's vectors `s`: to each of its particles
    /// (array index `i` on, written to `out` at `o` on, `nv` of them) that is below
    /// the ground and not near the sphere, whose contact [`ContactRows::resolve`]
    /// gives after the row (with the ground's friction after it, as the f64 engine
    /// does). Each particle's friction is its own, so these are the numbers the
    /// contact's pass after the step gives in the kernel's float
    /// ([`laws::Contact::ground_friction_lanes`], the same rule): without
    /// that pass's loads, per-lane tests and stores, and with the row still in the
    /// first cache. (After the row's blocks, not in them: in them, the row's code
    /// came out slower.)
    /// Returns whether any free particle of the row is near the sphere: only
    /// then has `resolve` anything to do in it.
    #[inline(always)]
    pub(super) fn ground_friction_row<S: Simd<E = E>, const FIXED: bool>(
        &self,
        s: S,
        out: &mut Out<E>,
        (i, o): (usize, usize),
        nv: usize,
    ) -> bool {
        let Some(height) = self.contact.ground.map(|g| g.height) else {
            return true;
        };
        let [x, y, z, vx, vy, vz, ux, uy, uz] = &mut out.0;
        // Everything the loop reads and writes lies inside these bounds.
        assert!(nv.is_multiple_of(S::LANES) && i + nv <= self.inv_mass.len());
        for a in [&**x, y, z, vx, vy, vz] {
            assert!(o + nv <= a.len());
        }
        if self.verlet {
            assert!(o + nv <= ux.len() && o + nv <= uy.len() && o + nv <= uz.len());
        }
        let lanes = |v: S::V| Vector(s, v);
        let splat = |e: E| s.splat(e);
        let (zero, ground) = (splat(E::ZERO), splat(self.ground));
        let (exact, unit) = (
            lanes(splat(E::of(height))),
            lanes(splat(E::of(self.frame.unit))),
        );
        let (centre, reach2) = (
            self.reach.center.map(splat),
            lanes(splat(self.reach.reach2)),
        );
        // The free lanes near the sphere so far, tested once after the loop; the
        // blocks counted by hand (`step_by` cost the loop three instructions a
        // block).
        let mut near_free = s.gt(zero, zero);
        let mut next = 0;
        while next < nv {
            let c = next;
            next += S::LANES;
            // SAFETY: `o + c + LANES <= o + nv` and `i + c + LANES <= i + nv`,
            // inside the arrays (asserted).
            let load = |a: &[E], at: usize| unsafe { s.load(a.as_ptr().add(at + c)) };
            let (px, py, pz) = (load(x, o), load(y, o), load(z, o));
            let w = load(self.inv_mass, i);
            // Free, below the ground and not near the sphere: `Reach`'s tests, in
            // the same operations.
            let from = |p: S::V, q: S::V| lanes(difference::<S, FIXED>(s, p, q));
            let d = [
                from(px, centre[0]),
                from(py, centre[1]),
                from(pz, centre[2]),
            ];
            let near = distance2(d).lt(reach2);
            // Height above the ground: as stored (exact in fixed point), and in m
            // as `resolve` takes it.
            let (under, above) = if FIXED {
                let rise = from(py, ground);
                (s.le(rise.1, zero), rise * unit)
            } else {
                (s.le(py, ground), lanes(py) - exact)
            };
            let free = s.gt(w, zero);
            near_free = s.either(near_free, s.both(free, near.1));
            let touch = s.both(free, s.but_not(under, near.1));
            if !s.any(touch) {
                continue;
            }
            let v = V3 {
                x: lanes(load(vx, o)),
                y: lanes(load(vy, o)),
                z: lanes(load(vz, o)),
            };
            let v_new = self.contact.ground_friction_lanes(above, v, lanes(w));
            // The touching lanes' velocities (and Verlet's update velocities)
            // get the change, as in `resolve`.
            let add = |a: &mut [E], dv: S::V| {
                // SAFETY: as above.
                unsafe {
                    let p = a.as_mut_ptr().add(o + c);
                    let old = s.load(p);
                    s.store(p, s.select(touch, s.add(old, dv), old));
                }
            };
            let dv = [v_new.x - v.x, v_new.y - v.y, v_new.z - v.z];
            add(vx, dv[0].1);
            add(vy, dv[1].1);
            add(vz, dv[2].1);
            if self.verlet {
                add(ux, dv[0].1);
                add(uy, dv[1].1);
                add(uz, dv[2].1);
            }
        }
        s.any(near_free)
    }

    /// The contact of the block of lanes at array index `j` (particle index `i`)
    /// with a lane near the sphere, in float64 as the f64 engine resolves it
    /// ([`laws::Contact::resolve_lanes`]): moves the `touch` lanes by
    /// their push (rounded to a whole unit in fixed point) and returns the
    /// changes of their velocities (which take the push as computed). `colliders`:
    /// the sphere's centre and the ground's height, as stored and in metres.
    #[inline(always)]
    fn resolve_near_sphere<const FIXED: bool>(
        &self,
        pos: [&mut [E]; 3],
        vel: [&[E]; 3],
        (i, j): (usize, usize),
        (centre, ground): ([(E, f64); 3], (E, f64)),
        touch: &[bool; CONTACT_LANES],
    ) -> [[E; CONTACT_LANES]; 3] {
        const N: usize = CONTACT_LANES;
        let frame = &self.frame;
        let per_unit = 1.0 / frame.unit;
        let lanes = |p: &[E]| {
            let p = &p[j..j + N];
            Floats::<f64, N>(std::array::from_fn(|l| p[l].f64()))
        };
        let v = V3 {
            x: lanes(vel[0]),
            y: lanes(vel[1]),
            z: lanes(vel[2]),
        };
        let w = &self.inv_mass[i..i + N];
        let mass = Floats::<f64, N>(std::array::from_fn(|l| w[l].f64()));
        // Offsets (m) of coordinate `a` of the lanes from a collider's, given as
        // stored and in metres: in fixed point from the stored one, exact (both are
        // whole units); in floats from the exact one (float32 rounds the stored
        // one).
        let offset = |a: usize, (stored, exact): (E, f64)| {
            let p = &pos[a][j..j + N];
            Floats::<f64, N>(std::array::from_fn(|l| {
                if FIXED {
                    (p[l].fixed_value() - stored.fixed_value()) * frame.unit
                } else {
                    p[l].f64() - exact
                }
            }))
        };
        let near = Near {
            from_centre: V3 {
                x: offset(0, centre[0]),
                y: offset(1, centre[1]),
                z: offset(2, centre[2]),
            },
            above_ground: offset(1, ground),
        };
        let (push, v_new) = self.contact.resolve_lanes(near, v, mass);
        // The touching lanes move by their push, all lanes at once: the others are
        // written what they held.
        for (a, push) in [push.x, push.y, push.z].into_iter().enumerate() {
            let p = &mut pos[a][j..j + N];
            let new: [E; N] = std::array::from_fn(|l| {
                let (p, push) = (p[l], push.0[l]);
                let to = if FIXED {
                    whole_units(p.fixed_value() + (push * per_unit).round())
                } else {
                    E::of(p.f64() + push)
                };
                E::select(touch[l] & (push != 0.0), to, p)
            });
            p.copy_from_slice(&new);
        }
        change(v_new, v, E::of)
    }
}

/// `to - from` of each lane, as `E` by `as_e`. (Written out: arrays' `map` was
/// left a call in this loop.)
#[inline(always)]
fn change<F: Copy + std::ops::Sub<Output = F>, E>(
    to: V3<Floats<F, CONTACT_LANES>>,
    from: V3<Floats<F, CONTACT_LANES>>,
    as_e: impl Fn(F) -> E,
) -> [[E; CONTACT_LANES]; 3] {
    let axis = |to: Floats<F, CONTACT_LANES>, from: Floats<F, CONTACT_LANES>| {
        std::array::from_fn(|l| as_e(to.0[l] - from.0[l]))
    };
    [axis(to.x, from.x), axis(to.y, from.y), axis(to.z, from.z)]
}

/// Where a particle may touch a collider, in the kernel's precision and the
/// positions' frame: at or below the ground's height (as stored), or within the
/// sphere's radius plus a margin (`1e-4` of it plus 1 µm, far above the rounding of
/// a float32 coordinate or a fixed-point unit) of its centre.
#[derive(Clone, Copy, Debug)]
pub(super) struct Reach<E> {
    ground: E,
    /// The sphere's centre (as stored) and squared reach in units² (a negative
    /// reach: no sphere).
    center: [E; 3],
    reach2: E,
}

impl<E: Real> Reach<E> {
    pub(super) fn of(contact: &laws::Contact, frame: &Frame) -> Self {
        // No ground: below every particle.
        let ground = frame.ground_height(contact.ground.map_or(f64::NEG_INFINITY, |g| g.height));
        match contact.sphere {
            Some(s) => {
                let reach = frame.units(s.radius * (1.0 + 1e-4) + 1e-6);
                Self {
                    ground,
                    center: std::array::from_fn(|a| frame.encode(s.center[a], a)),
                    reach2: E::of(reach * reach),
                }
            }
            None => Self {
                ground,
                center: [E::ZERO; 3],
                reach2: E::ZERO - E::ONE,
            },
        }
    }

    /// Whether a particle at `[x, y, z]` (as stored, in fixed point with `FIXED`)
    /// with inverse mass `w` is free and may touch a collider.
    #[inline(always)]
    fn may_touch<const FIXED: bool>(&self, at: [E; 3], w: E) -> bool {
        // `&` and `|`, not `&&` and `||`: no branches, for the compiler to vectorise.
        (w > E::ZERO) & (self.below_ground::<FIXED>(at) | self.near_sphere::<FIXED>(at))
    }

    /// Whether a particle at `[x, y, z]` may be inside the sphere.
    #[inline(always)]
    fn near_sphere<const FIXED: bool>(&self, [x, y, z]: [E; 3]) -> bool {
        let [cx, cy, cz] = self.center;
        let d = |p: E, c: E| if FIXED { E::fixed_sub(p, c) } else { p - c };
        distance2([d(x, cx), d(y, cy), d(z, cz)]) < self.reach2
    }

    /// Whether a particle at `[_, y, _]` may be below the ground (`<=`: one at the
    /// ground's height as stored may be just below it).
    #[inline(always)]
    fn below_ground<const FIXED: bool>(&self, [_, y, _]: [E; 3]) -> bool {
        if FIXED {
            E::fixed_sub(y, self.ground) <= E::ZERO
        } else {
            y <= self.ground
        }
    }
}

/// The squared distance of particles `d` from the sphere's centre (per axis, in
/// the positions' units), as [`Reach::near_sphere`] compares it with the reach:
/// for one particle or a block of them, in the same operations.
#[inline(always)]
fn distance2<T: Copy + std::ops::Add<Output = T> + std::ops::Mul<Output = T>>(
    [dx, dy, dz]: [T; 3],
) -> T {
    dx * dx + dy * dy + dz * dz
}

/// Whether any of the particles at `[x, y, z]` with inverse masses `w` may touch a
/// collider ([`Reach::may_touch`]). A plain loop over slices for the compiler to
/// vectorise; the verdict is an integer OR.
#[inline(always)]
fn row_may_touch<E: Real, const FIXED: bool>(
    [x, y, z]: [&[E]; 3],
    w: &[E],
    reach: &Reach<E>,
) -> bool {
    let (y, z, w) = (&y[..x.len()], &z[..x.len()], &w[..x.len()]);
    let mut any = 0u8;
    for j in 0..x.len() {
        any |= u8::from(reach.may_touch::<FIXED>([x[j], y[j], z[j]], w[j]));
    }
    any != 0
}

#[cfg(test)]
mod tests {
    use super::super::simd::Portable;
    use super::*;
    use crate::sim::{Ground, Sphere};
    use glam::DVec3;
    use rand::rngs::StdRng;
    use rand::{Rng, SeedableRng};

    /// The ground's friction given row by row in the step (`ground_friction_row`,
    /// then `resolve` for the sphere) gives each particle what the contact's pass
    /// after the step gives it, once: bit for bit, except beside a particle near
    /// the sphere, whose block of eight the pass resolves in float64 (there to
    /// float32's rounding). Particles above, on and below the ground, inside, near
    /// and far from a sphere that dips below the ground, sliding and resting,
    /// pinned among them, on float32 and fixed-point positions, by symplectic
    /// Euler and Verlet.
    #[test]
    fn the_rows_friction_is_the_contacts() {
        let height = -0.5;
        let ground = Ground {
            height,
            stiffness: 200.0,
            damping: 0.05,
            friction: 0.6,
        };
        let sphere = Sphere {
            center: DVec3::new(0.0, -0.6, 0.0),
            radius: 0.4,
        };
        let contact = laws::Contact {
            sphere: Some(sphere),
            ground: Some(ground),
            friction: 0.3,
            dt: 1e-3,
        };
        let unit = super::super::frame::fixed_unit(4.0, |_| 0.0);
        let bounds = ([-2.0, -1.5, -2.0], [2.0, 1.0, 2.0]);
        let fixed = Frame::fitting(unit, bounds, 0.0, Some(&ground), Some(&sphere)).unwrap();
        let grid = Grid::new(37, 24);
        let mut rng = StdRng::seed_from_u64(11);
        for frame in [Frame::FLOAT, fixed] {
            for verlet in [false, true] {
                let n = grid.len();
                let mut inv_mass = vec![0.0f32; n];
                let mut arrays: [Vec<f32>; 9] = std::array::from_fn(|_| vec![0.0; n]);
                for r in 0..grid.h {
                    for c in 0..grid.w {
                        let i = r * grid.stride + c;
                        inv_mass[i] = if rng.random_bool(0.1) { 0.0 } else { 2.0 };
                        let y = if rng.random_bool(0.5) {
                            height - rng.random_range(0.0..0.02)
                        } else {
                            rng.random_range(-1.1..0.0)
                        };
                        let at = [rng.random_range(-0.8..0.8), y, rng.random_range(-0.8..0.8)];
                        let scale = if rng.random_bool(0.5) { 1e-3 } else { 1.0 };
                        for a in 0..3 {
                            arrays[a][i] = frame.encode(at[a], a);
                            arrays[3 + a][i] = rng.random_range(-1.0..1.0) * scale;
                            arrays[6 + a][i] = arrays[3 + a][i];
                        }
                    }
                }
                let cloth = (grid, inv_mass.as_slice());
                let level = SimdLevel::Baseline;
                // After the step, as one pass.
                let mut after = arrays.clone();
                let pass = ContactRows::new(&contact, cloth, frame, level, (verlet, false));
                let mut out = Out(after.each_mut().map(|a| a.as_mut_slice()));
                pass.resolve(&mut out, 0, 0..grid.h);
                // In the step, row by row.
                let mut rows = arrays.clone();
                let in_step = ContactRows::new(&contact, cloth, frame, level, (verlet, true));
                assert!(in_step.friction_in_rows);
                let mut out = Out(rows.each_mut().map(|a| a.as_mut_slice()));
                for r in 0..grid.h {
                    let at = r * grid.stride;
                    let lanes = Portable::<f32>::default();
                    let near = if frame.fixed {
                        in_step.ground_friction_row::<_, true>(lanes, &mut out, (at, at), grid.nv)
                    } else {
                        in_step.ground_friction_row::<_, false>(lanes, &mut out, (at, at), grid.nv)
                    };
                    // The sphere's contact only where the row says it may touch.
                    if near {
                        in_step.resolve(&mut out, 0, r..r + 1);
                    }
                }
                let (mut exact, mut changed) = (0, 0);
                for r in 0..grid.h {
                    for c in 0..grid.w {
                        let i = r * grid.stride + c;
                        let block = r * grid.stride + c / CONTACT_LANES * CONTACT_LANES;
                        let near_sphere = (block..block + CONTACT_LANES).any(|j| {
                            let at = [0, 1, 2].map(|a| after[a][j]);
                            inv_mass[j] > 0.0
                                && if frame.fixed {
                                    pass.reach.near_sphere::<true>(at)
                                } else {
                                    pass.reach.near_sphere::<false>(at)
                                }
                        });
                        for a in 0..if verlet { 9 } else { 6 } {
                            let (got, want) = (rows[a][i], after[a][i]);
                            changed += usize::from(want.to_bits() != arrays[a][i].to_bits());
                            let what = format!("{frame:?} verlet {verlet}: ({r}, {c}) array {a}");
                            // The pass's float64 friction beside the sphere: a
                            // velocity's rounding.
                            if a >= 3 && near_sphere {
                                let error = (got - want).abs();
                                assert!(
                                    error <= 4.0 * f32::EPSILON * (1.0 + want.abs()),
                                    "{what}: {got}, {want}"
                                );
                            } else {
                                assert_eq!(got.to_bits(), want.to_bits(), "{what}");
                                exact += 1;
                            }
                        }
                    }
                }
                assert!(exact > 0 && changed > 0);
            }
        }
    }

    /// A particle below the ground or inside the sphere by less than its
    /// coordinates' rounding may touch, with float32 or fixed-point positions: its
    /// height just under the ground's (which rounds to the ground's height as
    /// stored), and a point just inside the sphere.
    #[test]
    fn particles_just_inside_a_collider_may_touch() {
        let (height, radius) = (-0.9, 0.5);
        let ground = Ground {
            height,
            stiffness: 200.0,
            damping: 0.05,
            friction: 0.5,
        };
        let sphere = Sphere {
            center: DVec3::new(0.0, 0.3, 0.0),
            radius,
        };
        let contact = laws::Contact {
            sphere: Some(sphere),
            ground: Some(ground),
            friction: 0.5,
            dt: 1e-3,
        };
        let unit = super::super::frame::fixed_unit(4.0, |_| 0.0);
        let bounds = ([-4.0, -1.0, -4.0], [4.0, 1.0, 4.0]);
        let fixed = Frame::fitting(unit, bounds, 0.0, Some(&ground), Some(&sphere)).unwrap();
        for frame in [Frame::FLOAT, fixed] {
            let reach = Reach::<f32>::of(&contact, &frame);
            let may_touch = |[x, y, z]: [f64; 3], w: f32| {
                let at = [frame.encode(x, 0), frame.encode(y, 1), frame.encode(z, 2)];
                if frame.fixed {
                    reach.may_touch::<true>(at, w)
                } else {
                    reach.may_touch::<false>(at, w)
                }
            };
            for below in [1e-12, 1e-10, 1e-9, 1e-7] {
                let y = height - below;
                assert!(may_touch([3.0, y, 3.0], 1.0), "{below} m below");
                assert!(!may_touch([3.0, y, 3.0], 0.0), "pinned");
            }
            assert!(!may_touch([3.0, height + 1e-6, 3.0], 1.0));
            assert!(may_touch([0.0, 0.3 + radius - 1e-9, 0.0], 1.0));
            assert!(!may_touch([0.0, 0.3 + radius * 1.01, 0.0], 1.0));
        }
    }
}
