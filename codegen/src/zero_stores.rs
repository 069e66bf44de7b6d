//! The structural zeros of output matrices (M's entries of joints on different branches, a Jacobian's
//! columns of joints that do not move the frame): written as short runs of stores spread evenly
//! through the function's statements, not by zeroing the whole matrix first.
//!
//! Why: a `memset` of the floating G1's M (35 × 35, 9.8 KB) alone takes 85 ns here (one 32-byte store
//! per cycle), and it runs as a burst before any arithmetic. Its 596 structural zeros as 172 runs of
//! at most four (one 256-bit store each) spread through the body overlap with the arithmetic instead.
//! Measured 2026-12-05 (AMD EPYC Zen 4, each generator's default crate linked into one binary, the
//! same bits): `crba` of the floating G1 0.965×, TALOS 0.90–0.91×, ANYmal B 0.99–1.00×; a frame
//! function's Jacobian (TALOS's sole) 0.89×, ANYmal B's foot 0.94–0.96×; `aba_derivatives` TALOS
//! 1.00×, ANYmal B 0.98×. The same runs as a burst at the start of the G1's `crba` gained nothing
//! (0.98–1.02×): the store queue fills and stalls either way; starting the spread later in the body
//! (after 10 % or 30 % of it) gained less (0.97×, 0.99×).
//!
//! A zeroed matrix ([`crate::emit::zero_filled`]) is written by runs when they are no more stores than
//! the fill's 256-bit ones (a planar linkage's link frames, zeros scattered one by one, keep the fill),
//! while the function has at most [`MAX_RUNS`] of them (a tree of many branches, where they would be
//! more code than arithmetic: the floating TALOS's `rnea_derivatives` keeps its fills) and at least
//! [`MIN_OPERATIONS_PER_RUN`] operations per run (a short function, such as a floating base's own frame,
//! has nothing to hide them behind).
//!
//! A run is written as one statement per entry (`m[7][12] = 0.0; m[7][13] = 0.0; …`), which LLVM
//! merges into one vector store in release builds; a slice copy would be two calls with panic paths in
//! a debug build (an attacker's trial: a floating base's frame function 8× the time in debug).

use crate::emit::{is_positive_zero, zero_filled, Output};
use crate::trace::Sym;

/// Entries per run: four `f64`, one 256-bit store (two 128-bit ones on the baseline target).
pub(crate) const RUN: usize = 4;

/// Runs per function above which the matrices are zeroed whole first instead.
pub(crate) const MAX_RUNS: usize = 512;

/// Operations of the function per run below which the matrices are zeroed whole first: the runs need
/// arithmetic to hide behind. Measured (an attacker's trial, 2026-12-05, one binary and separate ones,
/// against the `memset`): the floating humanoid34's `frame_pelvis` (2.7 operations per run) 1.3–1.5× the
/// time, a scene of free bodies' `minv` (2.0) 1.13–1.37× and its frames (3.0, 8.2) 1.14–1.27×, ANYmal B's
/// IMU frame (10.0) 1.16–1.18×; gains from 14.9 up: TALOS's sole frame (14.9) 0.89×, ANYmal B's foot
/// (23.7) 0.94–0.96×, the `crba` of TALOS (17.6) 0.90× and of the G1 (25.6) 0.965×.
pub(crate) const MIN_OPERATIONS_PER_RUN: usize = 12;

/// Up to [`RUN`] consecutive structural zeros of one row of an output matrix.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct ZeroRun {
    pub(crate) output: &'static str,
    pub(crate) row: usize,
    pub(crate) col: usize,
    pub(crate) len: usize,
}

impl ZeroRun {
    /// The statement, with `zero` the scalar type's zero as the function writes constants (`0.0`,
    /// or a lane function's splat).
    pub(crate) fn text(&self, zero: &str) -> String {
        let ZeroRun {
            output,
            row,
            col,
            len,
        } = self;
        (*col..col + len)
            .map(|c| format!("{output}[{row}][{c}] = {zero};"))
            .collect::<Vec<_>>()
            .join(" ")
    }
}

/// How a function writes the structural zeros of its zeroed matrices: each such matrix either by runs
/// spread through the body ([`spread`] places them) or whole first.
pub(crate) struct ZeroWrites {
    /// In row order, matrix by matrix.
    runs: Vec<ZeroRun>,
    /// The names of the matrices zeroed whole first.
    filled: Vec<&'static str>,
}

impl ZeroWrites {
    /// The runs of the positive zeros of every zeroed matrix of `outputs`, in a function of `operations`
    /// operations.
    pub(crate) fn of(outputs: &[Output], operations: usize) -> ZeroWrites {
        let mut runs = Vec::new();
        let mut filled = Vec::new();
        for out in outputs {
            let Output::Matrix {
                name, cols, values, ..
            } = out
            else {
                continue;
            };
            if !zero_filled(values) {
                continue;
            }
            let own = matrix_runs(name, *cols, values);
            // No more stores than the fill's 256-bit ones (a planar linkage's frames, zeros
            // scattered one by one, keep the fill).
            if own.len() * RUN <= values.len() {
                runs.extend(own);
            } else {
                filled.push(*name);
            }
        }
        if runs.len() > MAX_RUNS || operations < MIN_OPERATIONS_PER_RUN * runs.len() {
            filled.extend(runs.iter().map(|r| r.output));
            filled.dedup();
            return ZeroWrites {
                runs: Vec::new(),
                filled,
            };
        }
        ZeroWrites { runs, filled }
    }

    /// The matrices zeroed whole first.
    pub(crate) fn filled(&self) -> &[&'static str] {
        &self.filled
    }

    /// The runs to spread through the body.
    pub(crate) fn runs(&self) -> &[ZeroRun] {
        &self.runs
    }
}

/// The runs of the positive zeros of one matrix, row by row.
fn matrix_runs(output: &'static str, cols: usize, values: &[Sym]) -> Vec<ZeroRun> {
    let mut runs = Vec::new();
    for (row, entries) in values.chunks(cols).enumerate() {
        let mut col = 0;
        while col < cols {
            if !is_positive_zero(&entries[col]) {
                col += 1;
                continue;
            }
            let len = entries[col..]
                .iter()
                .take(RUN)
                .take_while(|v| is_positive_zero(v))
                .count();
            runs.push(ZeroRun {
                output,
                row,
                col,
                len,
            });
            col += len;
        }
    }
    runs
}

/// Places `extra` items evenly among the statements of consecutive parts (`parts[c]` the statements
/// of part c): item k goes before the statement at k / extra.len() of the whole, or at the end of
/// the last part. Returns the parts with their items in place.
pub(crate) fn spread<T>(parts: Vec<Vec<T>>, extra: Vec<T>) -> Vec<Vec<T>> {
    let total: usize = parts.iter().map(Vec::len).sum();
    let count = extra.len();
    // Global position of each item, in order (positions never decrease).
    let mut items = extra
        .into_iter()
        .enumerate()
        .map(|(k, item)| (k * total / count.max(1), item))
        .peekable();
    let mut out = Vec::with_capacity(parts.len());
    let mut start = 0;
    let last = parts.len().saturating_sub(1);
    for (c, part) in parts.into_iter().enumerate() {
        let end = start + part.len();
        let mut merged = Vec::with_capacity(part.len());
        for (i, statement) in part.into_iter().enumerate() {
            while let Some((_, item)) = items.next_if(|(at, _)| *at <= start + i) {
                merged.push(item);
            }
            merged.push(statement);
        }
        if c == last {
            merged.extend(items.by_ref().map(|(_, item)| item));
        }
        out.push(merged);
        start = end;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn matrix(name: &'static str, rows: usize, cols: usize, nonzero: &[(usize, usize)]) -> Output {
        let mut values = vec![Sym::Const(0.0); rows * cols];
        for &(r, c) in nonzero {
            values[r * cols + c] = Sym::Const(1.0);
        }
        Output::Matrix {
            name,
            rows,
            cols,
            values,
        }
    }

    #[test]
    fn runs_cover_the_positive_zeros_of_each_row_in_fours() {
        // Row 0: a zero, then ten after a one; row 1: -0.0 is no structural zero.
        let mut out = matrix("m", 3, 12, &[(0, 1), (1, 0), (2, 10)]);
        if let Output::Matrix { values, .. } = &mut out {
            values[12 + 5] = Sym::Const(-0.0);
        }
        let Output::Matrix { values, .. } = &out else {
            unreachable!()
        };
        let found = matrix_runs("m", 12, values);
        let runs: Vec<(usize, usize, usize)> =
            found.iter().map(|r| (r.row, r.col, r.len)).collect();
        assert_eq!(
            runs,
            [
                (0, 0, 1),
                (0, 2, 4),
                (0, 6, 4),
                (0, 10, 2),
                (1, 1, 4),
                (1, 6, 4),
                (1, 10, 2),
                (2, 0, 4),
                (2, 4, 4),
                (2, 8, 2),
                (2, 11, 1),
            ]
        );
        let zeros: usize = runs.iter().map(|r| r.2).sum();
        assert_eq!(zeros, 3 * 12 - 3 - 1);
        assert_eq!(
            found[1].text("0.0"),
            "m[0][2] = 0.0; m[0][3] = 0.0; m[0][4] = 0.0; m[0][5] = 0.0;"
        );
        assert_eq!(found[0].text("0.0"), "m[0][0] = 0.0;");
        // Eleven runs are more stores than the fill's nine of 36 entries: this matrix keeps the
        // fill; one of 4 × 16 with a nonzero takes its 16 runs of four.
        let writes = ZeroWrites::of(&[out, matrix("n", 4, 16, &[(0, 0)])], 100_000);
        assert_eq!(writes.filled(), ["m"]);
        assert_eq!(writes.runs().len(), 16);
        assert!(writes.runs().iter().all(|r| r.output == "n"));
    }

    #[test]
    fn scattered_zeros_and_too_many_runs_keep_the_fill() {
        // 15 zeros: under ZERO_FILL_MIN, written one by one as before.
        let few = matrix("m", 4, 4, &[(0, 0)]);
        let writes = ZeroWrites::of(&[few], 100_000);
        assert!(writes.runs().is_empty() && writes.filled().is_empty());
        // One nonzero every other entry: a run per zero, more stores than the fill's.
        let n = 40;
        let every_other: Vec<(usize, usize)> = (0..n * n)
            .filter(|k| k % 2 == 0)
            .map(|k| (k / n, k % n))
            .collect();
        let sparse = matrix("a", n, n, &every_other);
        // One nonzero every fifth entry: runs of four, 720 of them, fewer stores than its fill's
        // 900, but above MAX_RUNS with the next matrix's.
        let n = 60;
        let every_fifth: Vec<(usize, usize)> = (0..n * n)
            .filter(|k| k % 5 == 0)
            .map(|k| (k / n, k % n))
            .collect();
        let blocky = matrix("b", n, n, &every_fifth);
        let writes = ZeroWrites::of(&[sparse, blocky], 100_000);
        assert_eq!(writes.filled(), ["a", "b"]);
        assert!(writes.runs().is_empty());
        // A matrix of few runs beside the scattered one: runs for it, the fill for the other.
        let every_other: Vec<(usize, usize)> = (0..40 * 40)
            .filter(|k| k % 2 == 0)
            .map(|k| (k / 40, k % 40))
            .collect();
        let writes = ZeroWrites::of(
            &[
                matrix("a", 40, 40, &every_other),
                matrix("c", 8, 8, &[(0, 0)]),
            ],
            100_000,
        );
        assert_eq!(writes.filled(), ["a"]);
        assert_eq!(writes.runs().len(), 16);
        assert!(writes.runs().iter().all(|r| r.output == "c"));
        // Sixteen runs need 16 × MIN_OPERATIONS_PER_RUN operations to hide behind; one fewer: the fill.
        let c = || matrix("c", 8, 8, &[(0, 0)]);
        let enough = ZeroWrites::of(&[c()], 16 * MIN_OPERATIONS_PER_RUN);
        assert_eq!(enough.runs().len(), 16);
        let short = ZeroWrites::of(&[c()], 16 * MIN_OPERATIONS_PER_RUN - 1);
        assert!(short.runs().is_empty());
        assert_eq!(short.filled(), ["c"]);
    }

    #[test]
    fn spread_places_items_evenly_across_parts_and_keeps_every_statement() {
        let parts = vec![(0..6).collect::<Vec<i32>>(), (6..10).collect()];
        let out = spread(parts, vec![-1, -2, -3, -4, -5]);
        // Ten statements, five items: before statements 0, 2, 4, 6 and 8.
        assert_eq!(out[0], [-1, 0, 1, -2, 2, 3, -3, 4, 5]);
        assert_eq!(out[1], [-4, 6, 7, -5, 8, 9]);
        // More items than statements: several before one statement.
        let out = spread(vec![vec![0], vec![]], vec![-1, -2, -3]);
        assert_eq!(out, [vec![-1, -2, -3, 0], vec![]]);
        // No statements at all.
        let out = spread(vec![Vec::<i32>::new()], vec![-1]);
        assert_eq!(out, [vec![-1]]);
    }
}
