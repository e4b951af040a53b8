//! The sweeps of a spring pass: which springs of a stencil direction are in each
//! colour class ([`ColourClass`]), the lines of springs a class has on each row
//! ([`SpringLine`], [`SweepLines`]), and XPBD's multipliers between sweeps.

use std::ops::Range;

use super::SpringRule;
use crate::sim::grid_kernel::{BLOCK, Buf, Frame, Real, SpringCoefficients};
use crate::sim::laws::XpbdSpring;

/// What a [`SpringLine`] does to its springs, in the kernel's float type and the
/// positions' units.
#[derive(Clone, Copy)]
pub(super) enum LineRule<E> {
    /// The stretch limit: springs longer than `longest` are shortened to it.
    Limit { longest: E },
    /// XPBD: every spring, of rest length `rest`, corrected with `α̃` and `γ`
    /// ([`XpbdSpring`]).
    Xpbd { rest: E, alpha: E, gamma: E },
}

/// One row's springs of one colour class: the first ends at array indices `a ..
/// a + len`, the second ends at `b .. b + len`.
pub(super) struct SpringLine<E> {
    pub(super) a: usize,
    pub(super) b: usize,
    pub(super) len: usize,
    /// 1 for the lanes of a block in the class, else 0 (see [`SpringLine::class`]).
    pub(super) class: [E; BLOCK],
    pub(super) rule: LineRule<E>,
    /// Velocity per unit moved: `unit / h`.
    pub(super) inv_dt: E,
    /// Whether positions are fixed point.
    pub(super) fixed: bool,
}

impl<E: Real> SpringLine<E> {
    /// 1 for the lanes of a block in the class, first column `c0`: every lane, or
    /// along rows (`along` = the colour and `dc`) the springs starting at columns
    /// `c` with `(c / dc) % 2 == colour`, a pattern of 2 or 4 lanes that repeats in
    /// every block.
    pub(super) fn class(c0: usize, along: Option<(usize, isize)>) -> [E; BLOCK] {
        std::array::from_fn(|l| match along {
            Some((colour, dc)) if ((c0 + l) / dc.unsigned_abs()) % 2 != colour => E::ZERO,
            _ => E::ONE,
        })
    }
}

/// What the sweeps of one spring pass share: the rule, the step, and how the
/// positions are stored.
pub(in crate::sim::grid_kernel) struct SweepRules {
    pub(in crate::sim::grid_kernel) rule: SpringRule,
    pub(in crate::sim::grid_kernel) dt: f64,
    pub(in crate::sim::grid_kernel) frame: Frame,
}

/// The springs of one direction: from each particle to the one `dr` rows down and
/// `dc` columns right, of rest length `rest` and coefficients `kind`; `direction`
/// indexes the tear masks.
pub(in crate::sim::grid_kernel) struct SweepSprings {
    pub(in crate::sim::grid_kernel) direction: usize,
    pub(in crate::sim::grid_kernel) dr: usize,
    pub(in crate::sim::grid_kernel) dc: isize,
    pub(in crate::sim::grid_kernel) rest: f64,
    pub(in crate::sim::grid_kernel) kind: SpringCoefficients,
}

/// Which springs of a direction are in a colour class: along rows (no `rows`),
/// those starting at columns `c` with `(c / dc) % 2 == colour`; else those
/// starting on rows `r` with `((r % wrap) / period) % 2 == colour`.
#[derive(Clone, Copy)]
pub(in crate::sim::grid_kernel) struct ColourClass {
    pub(in crate::sim::grid_kernel) rows: Option<RowColour>,
    pub(in crate::sim::grid_kernel) colour: usize,
}

/// A colour of rows: `((r % wrap) / period) % 2` (see [`ColourClass`]).
#[derive(Clone, Copy)]
pub(in crate::sim::grid_kernel) struct RowColour {
    pub(in crate::sim::grid_kernel) wrap: usize,
    pub(in crate::sim::grid_kernel) period: usize,
}

/// One sweep of a spring pass: the springs of one direction `(dr, dc)` in one
/// colour class, a [`SpringLine`] per row.
pub(in crate::sim::grid_kernel) struct Sweep<E> {
    /// Index of the direction in the stencil (and of its tear masks).
    pub(super) direction: usize,
    pub(super) dr: usize,
    pub(super) dc: isize,
    /// First column with both ends on the cloth.
    pub(super) c0: usize,
    pub(super) class: ColourClass,
    /// Rows with both ends on the cloth: `0 .. rows`.
    pub(super) rows: usize,
    /// The line of row 0 (its `a` and `b` set per row by [`Sweep::line_at`]).
    pub(super) line: SpringLine<E>,
}

impl<E: Real> Sweep<E> {
    /// The sweep of `springs` in `class` on rows of `width` particles, `height`
    /// rows in all, under `rules`; `None` when it has no springs (or, for XPBD,
    /// when their rest length or stiffness leaves nothing to correct).
    pub(in crate::sim::grid_kernel) fn new(
        rules: &SweepRules,
        springs: SweepSprings,
        (width, height): (usize, usize),
        class: ColourClass,
    ) -> Option<Self> {
        let SweepSprings {
            direction,
            dr,
            dc,
            rest,
            kind,
        } = springs;
        // Columns c with both ends on the cloth: 0 <= c + dc < width.
        let c0 = (-dc).max(0) as usize;
        let len = width.saturating_sub(dc.max(0) as usize).saturating_sub(c0);
        if len == 0 || dr >= height {
            return None;
        }
        let frame = &rules.frame;
        let rule = match rules.rule {
            SpringRule::StretchLimit(tau) => LineRule::Limit {
                longest: E::of(frame.units((1.0 + tau) * rest)),
            },
            SpringRule::Xpbd => {
                let spring = XpbdSpring::new(rest, kind.k, kind.b, rules.dt)?;
                LineRule::Xpbd {
                    rest: E::of(frame.units(spring.rest)),
                    alpha: E::of(spring.alpha),
                    gamma: E::of(spring.gamma),
                }
            }
        };
        let along = match class.rows {
            None => Some((class.colour, dc)),
            Some(_) => None,
        };
        Some(Sweep {
            direction,
            dr,
            dc,
            c0,
            class,
            rows: height - dr,
            line: SpringLine {
                a: 0,
                b: 0,
                len,
                class: SpringLine::class(c0, along),
                rule,
                inv_dt: E::of(frame.unit / rules.dt),
                fixed: frame.fixed,
            },
        })
    }

    /// The rows of `rows` whose springs are in the class, in runs of consecutive
    /// rows: every row along rows (the class is a pattern of columns), else those
    /// of the class's colour ([`ClassRuns`]). A grid's class rows are a run every
    /// `2 period` rows: stepping from run to run, rather than counting each row
    /// in its run and wrap, the sheet at 128 ran 0.5 instructions a
    /// particle-step fewer (99.7 to 99.3, valgrind, AVX2).
    pub(super) fn lines(&self, rows: Range<usize>) -> ClassRuns {
        ClassRuns::new(self.class, rows)
    }

    /// The rows the sweep's lines start on.
    pub(in crate::sim::grid_kernel) fn rows(&self) -> Range<usize> {
        0..self.rows
    }

    /// The rows from a spring's first end to its second.
    pub(in crate::sim::grid_kernel) fn dr(&self) -> usize {
        self.dr
    }

    /// Whether positions are fixed point.
    pub(in crate::sim::grid_kernel) fn fixed(&self) -> bool {
        self.line.fixed
    }

    /// The line of row `r` (rows `stride` floats apart).
    pub(super) fn line_at(&self, r: usize, stride: usize) -> SpringLine<E> {
        SpringLine {
            a: r * stride + self.c0,
            b: ((r + self.dr) * stride + self.c0).wrapping_add_signed(self.dc),
            ..self.line
        }
    }
}

/// The rows of `rows` in a colour class ([`Sweep::lines`]), as runs of
/// consecutive rows: runs of `period` rows, every other run of a wrap in the class
/// (every row, along rows: one run).
pub(super) enum ClassRuns {
    /// No wrap (a grid's sweeps): the class's runs are `2 period` rows apart, the
    /// next from `start`, of which `left` rows remain.
    Striding {
        start: usize,
        left: usize,
        end: usize,
        period: usize,
    },
    /// With a wrap (a lattice's sweeps across the rows of a plane, whose colours
    /// start again at each plane's first row), counted along.
    Wrapping(ClassRows),
}

impl ClassRuns {
    pub(super) fn new(class: ColourClass, rows: Range<usize>) -> Self {
        let (start, end) = (rows.start, rows.end);
        match class.rows {
            // Every row along rows: one run to the end.
            None => ClassRuns::Striding {
                start,
                left: usize::MAX,
                end,
                period: usize::MAX,
            },
            Some(RowColour {
                wrap: usize::MAX,
                period,
            }) => {
                // The run `start` is in, if it is the class's, else the next.
                let (run, into) = (start / period, start % period);
                let (start, left) = if run % 2 == class.colour {
                    (start, period - into)
                } else {
                    (start + period - into, period)
                };
                ClassRuns::Striding {
                    start,
                    left,
                    end,
                    period,
                }
            }
            Some(colour_of) => ClassRuns::Wrapping(ClassRows::new(colour_of, class.colour, rows)),
        }
    }
}

impl Iterator for ClassRuns {
    type Item = Range<usize>;

    // (Inlined: as a call a run, it cost the sheet at 128 0.7 instructions a
    // particle-step.)
    #[inline(always)]
    fn next(&mut self) -> Option<Range<usize>> {
        match self {
            ClassRuns::Striding {
                start,
                left,
                end,
                period,
            } => {
                let r = *start;
                (r < *end).then(|| {
                    let run = r..r + (*left).min(*end - r);
                    *start = r.saturating_add(*left).saturating_add(*period);
                    *left = *period;
                    run
                })
            }
            ClassRuns::Wrapping(rows) => rows.next().map(|r| r..r + 1),
        }
    }
}

/// The rows of `rows` in a colour class with a wrap ([`ClassRuns::Wrapping`]):
/// runs of `period` rows, every other run of a wrap in the class, from where
/// `rows.start` is in its wrap (`at`) and run (`into`) and that run's colour
/// (`odd`). A run out of the class is passed over in one go.
pub(super) struct ClassRows {
    pub(super) rows: Range<usize>,
    pub(super) at: usize,
    pub(super) into: usize,
    pub(super) odd: usize,
    pub(super) wrap: usize,
    pub(super) period: usize,
    pub(super) colour: usize,
}

impl ClassRows {
    pub(super) fn new(
        RowColour { wrap, period }: RowColour,
        colour: usize,
        rows: Range<usize>,
    ) -> Self {
        let at = rows.start % wrap;
        let odd = (at / period) % 2;
        ClassRows {
            rows,
            at,
            into: at % period,
            odd,
            wrap,
            period,
            colour,
        }
    }

    /// Moves on `m` rows, to the end of the run or the wrap at most.
    pub(super) fn advance(&mut self, m: usize) {
        self.rows.start += m;
        self.at += m;
        self.into += m;
        if self.at == self.wrap {
            (self.at, self.into, self.odd) = (0, 0, 0);
        } else if self.into == self.period {
            (self.into, self.odd) = (0, self.odd ^ 1);
        }
    }
}

impl Iterator for ClassRows {
    type Item = usize;

    fn next(&mut self) -> Option<usize> {
        while self.odd != self.colour && !self.rows.is_empty() {
            self.advance((self.period - self.into).min(self.wrap - self.at));
        }
        let r = self.rows.start;
        (r < self.rows.end).then(|| {
            self.advance(1);
            r
        })
    }
}

/// The lines of a [`Sweep`] starting on `rows`, rows `stride` floats apart, and
/// what they read besides the state: inverse masses, the direction's tear mask
/// when springs tore ([`crate::sim::grid_kernel::Torn`], indexed by first end), the mask of real
/// particles when the arrays hold ghosts that springs reach (1 for particles, 0
/// for ghosts: a lattice's), and for XPBD the positions at the start of the step
/// (empty for the stretch limit) and, when it sweeps
/// back as well (a lattice's, see [`crate::sim::constraints::xpbd_pass`]), the
/// sweep's [`SweepMultipliers`], all whole arrays indexed from row 0.
pub(in crate::sim::grid_kernel) struct SweepLines<'a, E> {
    pub(in crate::sim::grid_kernel) sweep: &'a Sweep<E>,
    pub(in crate::sim::grid_kernel) stride: usize,
    pub(in crate::sim::grid_kernel) rows: Range<usize>,
    pub(in crate::sim::grid_kernel) inv_mass: &'a [E],
    pub(in crate::sim::grid_kernel) alive: Option<&'a [E]>,
    pub(in crate::sim::grid_kernel) real: Option<&'a [E]>,
    pub(in crate::sim::grid_kernel) start: [&'a [E]; 3],
    pub(in crate::sim::grid_kernel) multipliers: Option<SweepMultipliers<E>>,
    /// Whether the sweep (colour 0 of the stretch limit along rows) runs with
    /// its colour 1, row by row ([`row_line`]).
    pub(in crate::sim::grid_kernel) both_colours: bool,
}

/// XPBD's multipliers of one sweep's springs, kept from a spring's first
/// correction (the forward sweep) to its second (the backward one), as `α̃ λ` (in
/// the positions' units):
/// one array per sweep, indexed by the springs' first ends as the state's arrays
/// are (see [`crate::sim::constraints::xpbd_pass`]).
#[derive(Default)]
pub(in crate::sim::grid_kernel) struct Multipliers<E>(Vec<Buf<E>>);

impl<E: Real> Multipliers<E> {
    /// The arrays of `sweeps` sweeps of `len` floats, made once.
    pub(in crate::sim::grid_kernel) fn ensure(&mut self, sweeps: usize, len: usize) {
        if self.0.len() != sweeps || self.0.first().is_some_and(|b| b.as_slice().len() < len) {
            self.0 = (0..sweeps).map(|_| Buf::zeros(len)).collect();
        }
    }

    /// Sweep `k`'s array, written by its forward sweep or read by its backward one
    /// (`second`).
    pub(in crate::sim::grid_kernel) fn of_sweep(
        &mut self,
        k: usize,
        second: bool,
    ) -> SweepMultipliers<E> {
        let values = self.0[k].as_mut_slice();
        SweepMultipliers {
            values: values.as_mut_ptr(),
            len: values.len(),
            second,
        }
    }
}

/// One sweep's array of [`Multipliers`], as its lines use it. A line changes its
/// own springs' entries only (`a .. a + len`; its lanes past the end store back
/// what they read, as they do the state's), and no two lines of a sweep have a
/// spring in common.
#[derive(Clone, Copy)]
pub(in crate::sim::grid_kernel) struct SweepMultipliers<E> {
    pub(super) values: *mut E,
    pub(super) len: usize,
    /// Whether this is the springs' second correction, which reads the values (the
    /// first writes them).
    pub(super) second: bool,
}

// SAFETY: lines on different threads touch different entries, as they touch
// different particles: the threads' lines are kept apart by the rows a line's
// lanes reach (see the lattice's `spring_pass`); and the backward sweep, which
// reads the entries, runs after the forward one has joined.
unsafe impl<E: Send> Send for SweepMultipliers<E> {}
unsafe impl<E: Sync> Sync for SweepMultipliers<E> {}

#[cfg(test)]
mod tests {
    use super::{ClassRuns, ColourClass, RowColour};

    /// The rows of each class, counted along, are those the class's rule
    /// names: `((r % wrap) / period) % 2 == colour` (every row along rows),
    /// from every start.
    #[test]
    fn class_rows_are_the_rule_s() {
        for wrap in [usize::MAX, 5, 7, 12] {
            for period in [1, 2, 3] {
                for colour in [0, 1] {
                    for start in 0..30 {
                        let rows = start..start + 25;
                        let class = ColourClass {
                            rows: Some(RowColour { wrap, period }),
                            colour,
                        };
                        let rule: Vec<usize> = rows
                            .clone()
                            .filter(|r| ((r % wrap) / period) % 2 == colour)
                            .collect();
                        let counted: Vec<usize> =
                            ClassRuns::new(class, rows.clone()).flatten().collect();
                        assert_eq!(counted, rule, "wrap {wrap} period {period} colour {colour}");
                        let along = ColourClass { rows: None, colour };
                        let all: Vec<usize> =
                            ClassRuns::new(along, rows.clone()).flatten().collect();
                        assert_eq!(all, rows.collect::<Vec<_>>());
                    }
                }
            }
        }
    }
}
