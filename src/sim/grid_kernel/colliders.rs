//! The colliders of [`crate::sim::colliders`] (boxes, capsules, meshes, moving
//! spheres) on the grid kernel, after the scene's ground and sphere as in the
//! f64 engine: each free particle within a collider's bounds is decoded to
//! metres and given [`laws::collide`], the law every engine calls. A vectorised
//! scan of each block of a row against the bounds, in the stored coordinates,
//! skips the others: a particle outside every collider's bounds comes back from
//! the law unchanged ([`Collider::bounds_at`]).

use glam::DVec3;

use super::contact::{RowsPass, in_halves};
use super::frame::{COLLIDER_RANGE, RANGE, whole_units};
use super::{Frame, Kernel, Out, PARALLEL_MIN_PARTICLES, Real, SimdLevel};
use crate::sim::colliders::{Collider, Pose, poses_at};
use crate::sim::duo::Duo;
use crate::sim::lanes::Floats;
use crate::sim::laws::{V3, collide};

/// Particles tested against the bounds together, one per lane.
const LANES: usize = 16;
/// Particles the law takes together: float64 lanes, 8 to an AVX-512 register.
const LAW_LANES: usize = 8;

/// The kernel's colliders and where they are, kept between steps (nothing
/// allocates once their number stops growing).
#[derive(Debug, Default)]
pub(super) struct Solids<E> {
    colliders: Vec<Collider>,
    poses: Vec<Pose>,
    bounds: Vec<Bounds<E>>,
    /// Simulated time (s) at the start of the next step.
    pub(super) time: f64,
}

/// A collider's bounds on the world's axes, as stored.
#[derive(Clone, Copy, Debug)]
struct Bounds<E> {
    lo: [E; 3],
    hi: [E; 3],
}

impl<E: Real> Solids<E> {
    /// Takes `colliders` as they are at simulated time `time` (s), the start of
    /// the next step (reusing the vector's room and the meshes' `Arc`s).
    pub(super) fn set(&mut self, colliders: &[Collider], time: f64) {
        self.colliders.truncate(colliders.len());
        let kept = self.colliders.len();
        self.colliders.clone_from_slice(&colliders[..kept]);
        self.colliders.extend_from_slice(&colliders[kept..]);
        self.time = time;
    }
}

impl<E: Real> Kernel<E> {
    /// The colliders' contact after a step of `dt`, at their poses at its end, on
    /// the pool's two threads for a large grid (each particle's contact is its
    /// own: the same result).
    pub(super) fn collide_pass(&mut self, dt: f64, parallel: bool, duo: Option<&Duo>) {
        let solids = &mut self.solids;
        if solids.colliders.is_empty() {
            return;
        }
        poses_at(&solids.colliders, solids.time + dt, &mut solids.poses);
        let frame = self.frame;
        solids.bounds.clear();
        let mut everywhere = false;
        for (collider, pose) in solids.colliders.iter().zip(&solids.poses) {
            match stored_bounds(&frame, collider.bounds_at(pose)) {
                Stored::Bounds(b) => solids.bounds.push(b),
                Stored::OutOfReach => {}
                Stored::Everywhere => everywhere = true,
            }
        }
        let (w, h, st) = (self.grid.w, self.grid.h, self.grid.stride);
        let ctx = CollideRows {
            simd: self.simd,
            width: w,
            stride: st,
            inv_mass: self.inv_mass.as_slice(),
            frame,
            verlet: self.params.verlet,
            colliders: &solids.colliders,
            poses: &solids.poses,
            bounds: &solids.bounds,
            everywhere,
            h: dt,
        };
        let split = (parallel || duo.is_some()) && w * h >= PARALLEL_MIN_PARTICLES;
        in_halves(self.cur.rows(), (h, st), split, duo, |out, first, rows| {
            ctx.resolve(out, first, rows)
        });
    }
}

/// A collider's bounds as the pass tests them.
enum Stored<E> {
    Bounds(Bounds<E>),
    /// No particle the frame holds can be inside.
    OutOfReach,
    /// Not comparable in fixed point (not finite): every particle is tested.
    Everywhere,
}

/// The bounds `(lo, hi)` (m) as stored, each coordinate rounded outwards or
/// not at all (encoding is monotonic, so a particle inside in metres is inside
/// as stored).
fn stored_bounds<E: Real>(frame: &Frame, (lo, hi): (DVec3, DVec3)) -> Stored<E> {
    if !frame.fixed {
        return Stored::Bounds(Bounds {
            lo: std::array::from_fn(|a| E::of(lo[a])),
            hi: std::array::from_fn(|a| E::of(hi[a])),
        });
    }
    let (held, range) = (RANGE * frame.unit, COLLIDER_RANGE);
    let mut bounds = Bounds {
        lo: [E::ZERO; 3],
        hi: [E::ZERO; 3],
    };
    for a in 0..3 {
        let (l, h) = (lo[a] - frame.centre[a], hi[a] - frame.centre[a]);
        if !(l.is_finite() && h.is_finite()) {
            return Stored::Everywhere;
        }
        if l > held || h < -held {
            return Stored::OutOfReach;
        }
        // In whole units, outwards, clamped within the colliders' range: there a
        // particle's difference from them is exact, and they are still outside
        // every particle the frame holds.
        let units = |q: f64| whole_units(q.clamp(-range, range));
        bounds.lo[a] = units((l / frame.unit).floor());
        bounds.hi[a] = units((h / frame.unit).ceil());
    }
    Stored::Bounds(bounds)
}

/// What the colliders' pass over rows reads ([`Kernel::collide_pass`]).
pub(super) struct CollideRows<'a, E> {
    simd: SimdLevel,
    width: usize,
    stride: usize,
    inv_mass: &'a [E],
    frame: Frame,
    verlet: bool,
    colliders: &'a [Collider],
    poses: &'a [Pose],
    bounds: &'a [Bounds<E>],
    /// Test every free particle (bounds that fixed point cannot compare).
    everywhere: bool,
    h: f64,
}

impl<E: Real> RowsPass<E> for CollideRows<'_, E> {
    fn simd(&self) -> SimdLevel {
        self.simd
    }

    /// The contact of the particles of rows `rows`, whose arrays `out` holds from
    /// row `first` on. A row's last block reads past its last column, into the
    /// grid's ghost columns; lanes past it are never written.
    #[inline(always)]
    fn rows(&self, out: &mut Out<E>, first: usize, rows: impl Iterator<Item = usize>) {
        if self.frame.fixed {
            self.resolve_in::<true>(out, first, rows);
        } else {
            self.resolve_in::<false>(out, first, rows);
        }
    }
}

impl<E: Real> CollideRows<'_, E> {
    #[inline(always)]
    fn resolve_in<const FIXED: bool>(
        &self,
        out: &mut Out<E>,
        first: usize,
        rows: impl Iterator<Item = usize>,
    ) {
        for r in rows {
            let at = (r - first) * self.stride;
            for c in (0..self.width).step_by(LANES) {
                let inside = self.inside::<FIXED>(out, r * self.stride + c, at + c);
                for part in (0..LANES).step_by(LAW_LANES) {
                    let active: [bool; LAW_LANES] =
                        std::array::from_fn(|l| inside[part + l] & (c + part + l < self.width));
                    if active.contains(&true) {
                        self.collide_block::<FIXED>(out, at + c + part, &active);
                    }
                }
            }
        }
    }

    /// Which of the `LANES` particles from array index `i` (written at `j` in
    /// `out`) are free and inside some collider's bounds.
    #[inline(always)]
    fn inside<const FIXED: bool>(&self, out: &Out<E>, i: usize, j: usize) -> [bool; LANES] {
        let w = &self.inv_mass[i..i + LANES];
        let mut inside = [self.everywhere; LANES];
        for b in self.bounds {
            let mut each = [true; LANES];
            for a in 0..3 {
                let p = &out.0[a][j..j + LANES];
                for l in 0..LANES {
                    each[l] &= if FIXED {
                        (E::fixed_sub(p[l], b.lo[a]) >= E::ZERO)
                            & (E::fixed_sub(b.hi[a], p[l]) >= E::ZERO)
                    } else {
                        (p[l] >= b.lo[a]) & (p[l] <= b.hi[a])
                    };
                }
            }
            for l in 0..LANES {
                inside[l] |= each[l];
            }
        }
        std::array::from_fn(|l| inside[l] & (w[l] > E::ZERO))
    }

    /// The law on the block of particles from `j` in `out`, decoded to metres, in
    /// float64 lanes (each lane gets what the f64 engine gives its particle): the
    /// `active` lanes' pushes move their stored positions (rounded to a whole
    /// unit in fixed point), and their velocities (and Verlet's update
    /// velocities) get the change as computed.
    #[inline(always)]
    fn collide_block<const FIXED: bool>(
        &self,
        out: &mut Out<E>,
        j: usize,
        active: &[bool; LAW_LANES],
    ) {
        let frame = &self.frame;
        let block = |a: usize| -> &[E] { &out.0[a][j..j + LAW_LANES] };
        let position = |a: usize| {
            let p = block(a);
            Floats::<f64, LAW_LANES>(std::array::from_fn(|l| {
                if FIXED {
                    p[l].fixed_value() * frame.unit + frame.centre[a]
                } else {
                    p[l].f64()
                }
            }))
        };
        let velocity = |a: usize| {
            let v = block(3 + a);
            Floats::<f64, LAW_LANES>(std::array::from_fn(|l| v[l].f64()))
        };
        let x = V3 {
            x: position(0),
            y: position(1),
            z: position(2),
        };
        let v = V3 {
            x: velocity(0),
            y: velocity(1),
            z: velocity(2),
        };
        let (x_new, v_new) = collide(self.colliders, self.poses, x, v, self.h);
        let axes = |p: V3<Floats<f64, LAW_LANES>>| [p.x.0, p.y.0, p.z.0];
        let (x, v, x_new, v_new) = (axes(x), axes(v), axes(x_new), axes(v_new));
        // Lanes as arrays, written whole, without a branch per lane.
        let changed: [bool; LAW_LANES] = std::array::from_fn(|l| {
            let moved = (0..3).fold(false, |c, a| {
                c | (x_new[a][l] != x[a][l]) | (v_new[a][l] != v[a][l])
            });
            active[l] & moved
        });
        if !changed.contains(&true) {
            return;
        }
        let per_unit = 1.0 / frame.unit;
        for a in 0..3 {
            let p = &mut out.0[a][j..j + LAW_LANES];
            let moved: [E; LAW_LANES] = std::array::from_fn(|l| {
                let push = x_new[a][l] - x[a][l];
                let to = if FIXED {
                    whole_units(p[l].fixed_value() + (push * per_unit).round())
                } else {
                    E::of(x_new[a][l])
                };
                E::select(changed[l] & (push != 0.0), to, p[l])
            });
            p.copy_from_slice(&moved);
            let dv: [E; LAW_LANES] = std::array::from_fn(|l| E::of(v_new[a][l] - v[a][l]));
            let rows = if self.verlet {
                [3, 6].as_slice()
            } else {
                [3].as_slice()
            };
            for &row in rows {
                let speed = &mut out.0[row + a][j..j + LAW_LANES];
                for l in 0..LAW_LANES {
                    speed[l] = E::select(changed[l], speed[l] + dv[l], speed[l]);
                }
            }
        }
    }
}
