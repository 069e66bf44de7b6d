//! Walks in a kinematic tree given by each body's parent (`None`: the world), shared by the model's
//! grouping of constraints and by the loader, which works on the bodies before the model is built.
//!
//! Bodies must be numbered so that every parent comes before its children, as [`crate::ModelBuilder`]
//! requires and [`crate::Model`] keeps.

use crate::alloc_prelude::Vec;

/// The deepest body that is an ancestor of (or equal to) both `a` and `b`; `None` when one of them is
/// the world or they hang from the world on different branches.
///
/// ```
/// # use embedyn_runtime as embedyn; // the facade `embedyn` re-exports this crate
/// use embedyn::tree::common_ancestor;
/// // 0 ← 1 ← 2 and 0 ← 3: bodies 2 and 3 meet at 0.
/// let parent = [None, Some(0), Some(1), Some(0)];
/// assert_eq!(common_ancestor(|b| parent[b], Some(2), Some(3)), Some(0));
/// ```
pub fn common_ancestor(
    parent: impl Fn(usize) -> Option<usize>,
    a: Option<usize>,
    b: Option<usize>,
) -> Option<usize> {
    let (mut a, mut b) = (a?, b?);
    loop {
        if a == b {
            return Some(a);
        }
        // The larger index cannot be an ancestor of the smaller: step it up.
        if a > b {
            a = parent(a)?;
        } else {
            b = parent(b)?;
        }
    }
}

/// Appends to `out` the bodies from `from` up to, not including, its ancestor `top` (all the way to the
/// world when `top` is not on the way).
pub fn path_to_ancestor(
    parent: impl Fn(usize) -> Option<usize>,
    from: Option<usize>,
    top: Option<usize>,
    out: &mut Vec<usize>,
) {
    let mut current = from;
    while current != top {
        let Some(body) = current else { break };
        out.push(body);
        current = parent(body);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 0 ← 1 ← 2, 1 ← 3, and a second root 4 ← 5.
    const PARENT: [Option<usize>; 6] = [None, Some(0), Some(1), Some(1), None, Some(4)];

    #[test]
    fn common_ancestor_of_branches_roots_and_the_world() {
        let parent = |b: usize| PARENT[b];
        assert_eq!(common_ancestor(parent, Some(2), Some(3)), Some(1));
        assert_eq!(common_ancestor(parent, Some(3), Some(0)), Some(0));
        assert_eq!(common_ancestor(parent, Some(2), Some(2)), Some(2));
        assert_eq!(common_ancestor(parent, Some(2), Some(5)), None);
        assert_eq!(common_ancestor(parent, None, Some(5)), None);
    }

    #[test]
    fn path_stops_below_the_ancestor_or_at_the_world() {
        let parent = |b: usize| PARENT[b];
        let mut out = Vec::new();
        path_to_ancestor(parent, Some(2), Some(0), &mut out);
        assert_eq!(out, [2, 1]);
        out.clear();
        path_to_ancestor(parent, Some(5), None, &mut out);
        assert_eq!(out, [5, 4]);
        out.clear();
        path_to_ancestor(parent, Some(3), Some(3), &mut out);
        assert!(out.is_empty());
    }
}
