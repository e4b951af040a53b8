//! Contact with the colliders after the step, where friction (or a stretch limit,
//! XPBD or self-collision before it) keeps it out of the fused step: the shared
//! [`constraints::Contact::resolve_lanes`] on blocks of particles, in float64, on
//! the rows that may touch.

use super::super::duo::Duo;
use super::super::lanes::{F64s, V3};
#[cfg(target_arch = "x86_64")]
use super::x86;
use super::{Kernel, Out, PARALLEL_MIN_PARTICLES, Real, SimdLevel, constraints};

impl<E: Real> Kernel<E> {
    /// The colliders' contact of every free particle that touches one, as the f64
    /// engine resolves it ([`constraints::Contact::resolve`]), on the pool's two
    /// threads when it has them: see [`ContactRows`].
    pub(super) fn resolve_contact(
        &mut self,
        contact: &constraints::Contact,
        parallel: bool,
        duo: Option<&Duo>,
    ) {
        let (w, h, st) = (self.grid.w, self.grid.h, self.grid.stride);
        let large = w * h >= PARALLEL_MIN_PARTICLES;
        let split = h / 2;
        // In two halves of the rows on two threads when allowed (each particle's
        // resolution is its own: the same results).
        let ctx = ContactRows {
            simd: self.simd,
            width: w,
            stride: st,
            inv_mass: self.inv_mass.as_slice(),
            reach: Reach::of(contact),
            contact,
            compensated: self.params.compensated,
            verlet: self.params.verlet,
        };
        let out = self.cur.rows();
        if (parallel || duo.is_some()) && large {
            let (mut first, mut second) = out.split_at(split * st);
            let mut second_half = || ctx.resolve(&mut second, split, split..h);
            let first_half = || ctx.resolve(&mut first, 0, 0..split);
            match duo {
                Some(duo) => duo.fork(&mut second_half, first_half),
                None => {
                    rayon::join(first_half, second_half);
                }
            }
        } else {
            ctx.resolve(&mut { out }, 0, 0..h);
        }
    }
}

/// What resolving the contacts of rows reads ([`Kernel::resolve_contact`]).
pub(super) struct ContactRows<'a, E> {
    pub(super) simd: SimdLevel,
    pub(super) width: usize,
    pub(super) stride: usize,
    pub(super) inv_mass: &'a [E],
    pub(super) reach: Reach<E>,
    pub(super) contact: &'a constraints::Contact,
    pub(super) compensated: bool,
    pub(super) verlet: bool,
}

/// Particles [`ContactRows`] resolves together, one per float64 lane.
const CONTACT_LANES: usize = 8;

impl<E: Real> ContactRows<'_, E> {
    /// Resolves the particles of the rows `rows` that may touch a collider, whose
    /// arrays `out` holds from row `first` on. A vectorised scan of a row first
    /// ([`row_may_touch`]) skips the rows with none that may ([`Reach::may_touch`]:
    /// a particle out of reach would leave `resolve` unchanged, so skipping it
    /// changes nothing); in the others, in blocks of [`CONTACT_LANES`] columns,
    /// those that may touch are resolved together
    /// ([`constraints::Contact::resolve_lanes`], which gives each exactly what
    /// `resolve` gives it alone). A row's last block reads past its last column:
    /// the grid's ghost columns (its rows are [`super::BLOCK`] floats longer than their
    /// blocks), or the next row of a lattice (whose arrays end in ghosts); lanes
    /// that do not touch are written back what they held.
    pub(super) fn resolve(&self, out: &mut Out<E>, first: usize, rows: std::ops::Range<usize>) {
        match self.simd {
            #[cfg(target_arch = "x86_64")]
            // SAFETY: the level is AVX-512 only when the CPU has AVX-512F/VL, AVX2 and FMA.
            SimdLevel::Avx512 => unsafe { x86::contact_rows_avx512(self, out, first, rows) },
            #[cfg(target_arch = "x86_64")]
            // SAFETY: the level is AVX2 only when the CPU has AVX2 and FMA.
            SimdLevel::Avx2 => unsafe { x86::contact_rows_avx2(self, out, first, rows) },
            _ => self.resolve_rows(out, first, rows),
        }
    }

    /// [`ContactRows::resolve`], compiled for the caller's SIMD level.
    #[inline(always)]
    pub(super) fn resolve_rows(
        &self,
        out: &mut Out<E>,
        first: usize,
        rows: std::ops::Range<usize>,
    ) {
        const N: usize = CONTACT_LANES;
        let [x, y, z, xl, yl, zl, vx, vy, vz, ux, uy, uz] = &mut out.0;
        let (pos, vel, upd) = ([x, y, z], [vx, vy, vz], [ux, uy, uz]);
        let lows = [xl, yl, zl];
        for r in rows {
            let start = r * self.stride;
            let row = (r - first) * self.stride..(r - first) * self.stride + self.width;
            let coordinates = [&pos[0][row.clone()], &pos[1][row.clone()], &pos[2][row]];
            let masses = &self.inv_mass[start..start + self.width];
            if !row_may_touch(coordinates, masses, &self.reach) {
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
                    sphere[l] = real & self.reach.near_sphere(at);
                    touch[l] = sphere[l] | (real & self.reach.below_ground(at));
                }
                if !touch.contains(&true) {
                    continue;
                }
                let lanes = |p: &[E]| {
                    let p = &p[j..j + N];
                    F64s::<N>(std::array::from_fn(|l| p[l].f64()))
                };
                let v = V3 {
                    x: lanes(vel[0]),
                    y: lanes(vel[1]),
                    z: lanes(vel[2]),
                };
                let mass = F64s::<N>(std::array::from_fn(|l| w[l].f64()));
                let height = || lanes(pos[1]) + lanes(lows[1]);
                let v_new = if !sphere.contains(&true) {
                    // None near the sphere: only the ground's friction, which
                    // leaves the positions as they are (`resolve_lanes` gives the
                    // same, its sphere part then changing nothing).
                    self.contact.ground_friction_lanes(height(), v, mass)
                } else {
                    let at = V3 {
                        x: lanes(pos[0]) + lanes(lows[0]),
                        y: height(),
                        z: lanes(pos[2]) + lanes(lows[2]),
                    };
                    let (to, v_new) = self.contact.resolve_lanes(at, v, mass);
                    // Back into the lanes that moved, all lanes at once: a
                    // particle that moved gets its new position (every axis). The
                    // other lanes are written what they held.
                    let moved: [bool; N] = std::array::from_fn(|l| {
                        let (x, y, z) = (to.x.0[l], to.y.0[l], to.z.0[l]);
                        touch[l] & ((x != at.x.0[l]) | (y != at.y.0[l]) | (z != at.z.0[l]))
                    });
                    for (a, to) in [to.x, to.y, to.z].into_iter().enumerate() {
                        let (p, q) = (&mut pos[a][j..j + N], &mut lows[a][j..j + N]);
                        // Both parts of every lane, with one branch on
                        // `compensated`, and both arrays read before either is
                        // written: with a branch in each lane, or `p` and `q` read
                        // and written in turn (two arrays that may overlap, to the
                        // compiler), it wrote lane by lane.
                        let hi: [E; N] = std::array::from_fn(|l| E::of(to.0[l]));
                        let lo: [E; N] = if self.compensated {
                            std::array::from_fn(|l| E::of(to.0[l] - hi[l].f64()))
                        } else {
                            [E::ZERO; N]
                        };
                        let (old_hi, old_lo): ([E; N], [E; N]) =
                            (std::array::from_fn(|l| p[l]), std::array::from_fn(|l| q[l]));
                        let hi: [E; N] =
                            std::array::from_fn(|l| if moved[l] { hi[l] } else { old_hi[l] });
                        let lo: [E; N] =
                            std::array::from_fn(|l| if moved[l] { lo[l] } else { old_lo[l] });
                        p.copy_from_slice(&hi);
                        q.copy_from_slice(&lo);
                    }
                    v_new
                };
                // The touching lanes' velocities get the change (and Verlet's
                // update velocities with them).
                for (a, (v_new, v)) in [(v_new.x, v.x), (v_new.y, v.y), (v_new.z, v.z)]
                    .into_iter()
                    .enumerate()
                {
                    let dv: [E; N] = std::array::from_fn(|l| E::of(v_new.0[l] - v.0[l]));
                    let speed = &mut vel[a][j..j + N];
                    for l in 0..N {
                        speed[l] = if touch[l] { speed[l] + dv[l] } else { speed[l] };
                    }
                    if self.verlet {
                        let update = &mut upd[a][j..j + N];
                        for l in 0..N {
                            update[l] = if touch[l] {
                                update[l] + dv[l]
                            } else {
                                update[l]
                            };
                        }
                    }
                }
            }
        }
    }
}

/// Where a particle may touch a collider, in the kernel's precision: below the
/// ground's height, or within the sphere's radius plus a margin (`1e-4` of it plus
/// 1 µm, far above the rounding of a position's high part) of its centre.
#[derive(Clone, Copy, Debug)]
pub(super) struct Reach<E> {
    ground: E,
    /// The sphere's centre and squared reach (a negative reach: no sphere).
    center: [E; 3],
    reach2: E,
}

impl<E: Real> Reach<E> {
    pub(super) fn of(contact: &constraints::Contact) -> Self {
        let ground = contact.ground.map_or(E::LOWEST, |g| E::of(g.height));
        match contact.sphere {
            Some(s) => {
                let reach = s.radius * (1.0 + 1e-4) + 1e-6;
                Self {
                    ground,
                    center: s.center.to_array().map(E::of),
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

    /// Whether a particle at `[x, y, z]` (high parts) with inverse mass `w` is free
    /// and may touch a collider.
    #[inline(always)]
    fn may_touch(&self, at: [E; 3], w: E) -> bool {
        // `&` and `|`, not `&&` and `||`: no branches, for the compiler to vectorise.
        (w > E::ZERO) & (self.below_ground(at) | self.near_sphere(at))
    }

    /// Whether a particle at `[x, y, z]` (high parts) may be inside the sphere.
    #[inline(always)]
    fn near_sphere(&self, [x, y, z]: [E; 3]) -> bool {
        let [cx, cy, cz] = self.center;
        let (dx, dy, dz) = (x - cx, y - cy, z - cz);
        dx * dx + dy * dy + dz * dz < self.reach2
    }

    /// Whether a particle at `[_, y, _]` (high parts) may be below the ground:
    /// `<=`, since a height just below the ground's may have a high part equal to
    /// the ground's height in the kernel's precision (and a negative low part).
    #[inline(always)]
    fn below_ground(&self, [_, y, _]: [E; 3]) -> bool {
        y <= self.ground
    }
}

/// Whether any of the particles at `[x, y, z]` with inverse masses `w` may touch a
/// collider ([`Reach::may_touch`]). A plain loop over slices for the compiler to
/// vectorise; the verdict is an integer OR.
#[inline(always)]
fn row_may_touch<E: Real>([x, y, z]: [&[E]; 3], w: &[E], reach: &Reach<E>) -> bool {
    let (y, z, w) = (&y[..x.len()], &z[..x.len()], &w[..x.len()]);
    let mut any = 0u8;
    for j in 0..x.len() {
        any |= u8::from(reach.may_touch([x[j], y[j], z[j]], w[j]));
    }
    any != 0
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::{Ground, Sphere};
    use glam::DVec3;

    /// A particle below the ground or inside the sphere by less than its high
    /// part's rounding may touch: its double-float height just under the ground's
    /// (whose float32 rounds to the same float as the ground's height), and a point
    /// just inside the sphere.
    #[test]
    fn particles_just_inside_a_collider_may_touch() {
        let (height, radius) = (-0.9, 0.5);
        let contact = constraints::Contact {
            sphere: Some(Sphere {
                center: DVec3::new(0.0, 0.3, 0.0),
                radius,
            }),
            ground: Some(Ground {
                height,
                stiffness: 200.0,
                damping: 0.05,
                friction: 0.5,
            }),
            friction: 0.5,
            dt: 1e-3,
        };
        let reach = Reach::<f32>::of(&contact);
        for below in [1e-12, 1e-10, 1e-9, 1e-7] {
            let y = height - below;
            let hi = y as f32;
            assert!(reach.may_touch([3.0, hi, 3.0], 1.0), "{below} m below");
            assert!(!reach.may_touch([3.0, hi, 3.0], 0.0), "pinned");
        }
        assert!(!reach.may_touch([3.0, (height + 1e-6) as f32, 3.0], 1.0));
        let inside = (0.3 + radius - 1e-9) as f32;
        assert!(reach.may_touch([0.0, inside, 0.0], 1.0));
        assert!(!reach.may_touch([0.0, (0.3 + radius * 1.01) as f32, 0.0], 1.0));
    }
}
