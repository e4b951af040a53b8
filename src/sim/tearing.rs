//! Tearing and cutting: springs that break for good.
//!
//! - **The rule.** With a `tear_strain` `tau`, a spring tears when, at the end of a
//!   step (after the constraints), it is longer than `(1 + tau) L`
//!   ([`overstretched`]). A spring whose length is not finite never tears: a NaN
//!   or an infinity is a divergence, which its own check reports.
//! - **Cutting.** The user cuts the springs that the mouse's path crosses on screen
//!   ([`System::cut`]); the app finds them, the system breaks them the same way.
//! - **What breaking means.** A broken spring leaves the model for good: its force,
//!   its place in the constraint passes (XPBD, stretch limit) and its exemption
//!   from self-collision go with it. A surface triangle with a broken spring along
//!   one of its edges leaves the aero pass and the mesh, so the hole renders clean
//!   and no triangle spans it.
//! - **Both engines.** The f64 engine tears here, after its constraints. The grid
//!   kernel applies the same rule at the same point of its step, with [`overstretched`]
//!   deciding in f64, and keeps masks of the springs left for its row pass; it
//!   hands its breaks back to the model after each run of steps
//!   ([`super::fast_path`]).

pub use super::laws::overstretched;
use super::{Spring, System, fast_path};

impl System {
    /// Springs broken so far (torn or cut) since the system was built.
    pub fn broken_springs(&self) -> usize {
        self.model.broken_springs
    }

    /// Cuts the springs joining any of `pairs` (particle indices, either order):
    /// they break as a tear breaks them (see `super::tearing`). Returns how many
    /// were cut; pairs that no spring joins are ignored.
    pub fn cut(&mut self, pairs: &[(usize, usize)]) -> usize {
        let mut wanted: Vec<(u32, u32)> = pairs
            .iter()
            .filter_map(|&(i, j)| Some((u32::try_from(i).ok()?, u32::try_from(j).ok()?)))
            .map(|(i, j)| (i.min(j), i.max(j)))
            .collect();
        wanted.sort_unstable();
        let cut = self.break_springs(|s| wanted.binary_search(&(s.a, s.b)).is_ok());
        if cut > 0 {
            self.mark_edited();
        }
        cut
    }

    /// The step's last phase with a tear strain `tau`: breaks the springs past it.
    pub(super) fn tear(&mut self, tau: f64) {
        let x = &self.state.positions;
        let over = |s: &Spring| overstretched(x[s.a as usize], x[s.b as usize], s.rest, tau);
        if self.model.springs.iter().any(over) {
            let x = std::mem::take(&mut self.state.positions);
            self.break_springs(|s| overstretched(x[s.a as usize], x[s.b as usize], s.rest, tau));
            self.state.positions = x;
        }
    }

    /// Removes the springs for which `broken` holds, and the triangles along them,
    /// and rebuilds what depends on the spring list (adjacency, constraint order,
    /// scratch, the fast engines' view of the grid). Returns how many broke.
    /// Allocates, but only when something breaks.
    pub(super) fn break_springs(&mut self, broken: impl Fn(&Spring) -> bool) -> usize {
        let model = &mut self.model;
        let pairs = remove_broken(&mut model.springs, &mut model.triangles, broken);
        if pairs.is_empty() {
            return 0;
        }
        model.broken_springs += pairs.len();
        self.springs_replaced();
        pairs.len()
    }

    /// Puts back springs that a cut or a tear removed, and the surface triangles
    /// along them, as they were (an undo of a cut). Springs already present, and
    /// springs or triangles joining particles the system lacks, are left out, so
    /// that a system rebuilt since takes nothing twice. Returns how many springs
    /// came back.
    pub fn mend(&mut self, springs: &[Spring], triangles: &[[u32; 3]]) -> usize {
        let model = &mut self.model;
        let n = model.mass.len() as u64;
        let within = |i: u32| u64::from(i) < n;
        let mut mended = 0;
        for s in springs.iter().filter(|s| within(s.a) && within(s.b)) {
            // Canonical springs are sorted by their ends: they go back in place.
            if let Err(at) = (model.springs).binary_search_by_key(&(s.a, s.b), |t| (t.a, t.b)) {
                model.springs.insert(at, *s);
                mended += 1;
            }
        }
        if mended == 0 {
            return 0;
        }
        let present: std::collections::HashSet<[u32; 3]> =
            model.triangles.iter().copied().collect();
        let back = triangles.iter().filter(|t| t.iter().all(|&i| within(i)));
        let back: Vec<[u32; 3]> = back.filter(|t| !present.contains(*t)).copied().collect();
        model.triangles.extend(back);
        model.broken_springs = model.broken_springs.saturating_sub(mended);
        self.springs_replaced();
        self.mark_edited();
        mended
    }

    /// Rebuilds what depends on the spring list after springs left or came back
    /// (adjacency, constraint order, scratch, the fast engines' view of the grid).
    fn springs_replaced(&mut self) {
        let model = &mut self.model;
        let n = model.mass.len();
        model.springs_replaced();
        let m = model.springs.len();
        self.work.spring_forces.resize(m, glam::DVec3::ZERO);
        if self.model.params.integrator == super::Integrator::ImplicitEuler {
            self.work.implicit.resize(n, m);
        }
        self.engines.stencil_springs = fast_path::StencilSprings::of(&self.model);
        self.engines.springs_changed();
        self.forget_rest_drag_areas();
    }
}

/// Removes from `springs` (canonical: sorted by their ends) those for which
/// `broken` holds, and from `triangles` those with a removed spring along an edge;
/// returns the removed springs' ends, sorted.
fn remove_broken(
    springs: &mut Vec<Spring>,
    triangles: &mut Vec<[u32; 3]>,
    broken: impl Fn(&Spring) -> bool,
) -> Vec<(u32, u32)> {
    let mut pairs: Vec<(u32, u32)> = Vec::new();
    springs.retain(|s| {
        let b = broken(s);
        if b {
            pairs.push((s.a, s.b));
        }
        !b
    });
    if pairs.is_empty() {
        return pairs;
    }
    // Canonical springs are sorted by their ends, so `pairs` is too.
    let along_break = |&[a, b, c]: &[u32; 3]| {
        [(a, b), (b, c), (c, a)]
            .iter()
            .any(|&(i, j)| pairs.binary_search(&(i.min(j), i.max(j))).is_ok())
    };
    triangles.retain(|t| !along_break(t));
    pairs
}
