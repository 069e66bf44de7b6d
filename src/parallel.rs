//! Many states across threads: a batch of states split over the cores with `rayon`, each thread running
//! the generated lane functions' `_batch` forms on its share.
//!
//! A generated `aba_batch` (from `robot!(…, lanes = 4)` or `embedyn generate --lanes 4`) already runs
//! any number of states, `LANES` at a time in the SIMD lanes of one call. [`par_batch`] splits such a
//! batch into contiguous pieces of whole chunks and runs the pieces on rayon's thread pool: every slice of
//! the call (inputs and outputs) is cut at the same state, so each piece is again a valid batch, and the
//! results are bit-identical to one thread's (the arithmetic of each state does not depend on its
//! neighbours).
//!
//! ```
//! mod arm {
//!     embedyn::robot!("models/arm7.urdf", f64_only, only(aba), lanes = 4);
//! }
//! use arm::{NQ, NV};
//! let n = 1000;
//! let q = vec![[0.1; NQ]; n];
//! let v = vec![[0.0; NV]; n];
//! let tau = vec![[0.5; NV]; n];
//! let mut qdd = vec![[0.0; NV]; n];
//! // 64 states per piece: 16 calls of four lanes, then the next piece, on any thread.
//! let ok = embedyn::parallel::par_batch((&q[..], &v[..], &tau[..], &mut qdd[..]), 64, |(q, v, tau, qdd)| {
//!     assert!(arm::f64x4::aba_batch(q, v, tau, qdd));
//! });
//! assert!(ok);
//! let mut one = [0.0; NV];
//! arm::f64::aba(&q[999], &v[999], &tau[999], &mut one);
//! assert_eq!(qdd[999], one);
//! ```

/// The slices of one batch call, cut together at a state: `&[T]` (inputs), `&mut [T]` (outputs) and
/// tuples of up to eight of them.
pub trait BatchSlices: Sized + Send {
    /// The number of states, or `None` when the slices' lengths differ.
    fn states(&self) -> Option<usize>;
    /// The first `mid` states and the rest.
    fn split_at_state(self, mid: usize) -> (Self, Self);
}

impl<T: Sync> BatchSlices for &[T] {
    fn states(&self) -> Option<usize> {
        Some(self.len())
    }
    fn split_at_state(self, mid: usize) -> (Self, Self) {
        self.split_at(mid)
    }
}

impl<T: Send> BatchSlices for &mut [T] {
    fn states(&self) -> Option<usize> {
        Some(self.len())
    }
    fn split_at_state(self, mid: usize) -> (Self, Self) {
        self.split_at_mut(mid)
    }
}

macro_rules! tuple_slices {
    ($($name:ident $index:tt),+) => {
        impl<$($name: BatchSlices),+> BatchSlices for ($($name,)+) {
            fn states(&self) -> Option<usize> {
                let lengths = [$(self.$index.states()),+];
                let first = lengths[0]?;
                lengths.iter().all(|&n| n == Some(first)).then_some(first)
            }
            #[allow(non_snake_case)]
            fn split_at_state(self, mid: usize) -> (Self, Self) {
                $(let $name = self.$index.split_at_state(mid);)+
                (($($name.0,)+), ($($name.1,)+))
            }
        }
    };
}
tuple_slices!(A 0);
tuple_slices!(A 0, B 1);
tuple_slices!(A 0, B 1, C 2);
tuple_slices!(A 0, B 1, C 2, D 3);
tuple_slices!(A 0, B 1, C 2, D 3, E 4);
tuple_slices!(A 0, B 1, C 2, D 3, E 4, F 5);
tuple_slices!(A 0, B 1, C 2, D 3, E 4, F 5, G 6);
tuple_slices!(A 0, B 1, C 2, D 3, E 4, F 5, G 6, H 7);

/// Runs `f` on pieces of `slices` across rayon's thread pool: each piece is `grain` consecutive states
/// (the last one fewer), cut at the same state in every slice. Returns `false`, calling nothing, when the
/// slices' lengths differ (as the `_batch` functions do).
///
/// `grain` trades scheduling against balance: a multiple of the lane count (so that only the last piece
/// pads a chunk) of a few dozen states keeps the pool's overhead (about a microsecond per piece) small
/// against the work (a quadruped's `aba` through four lanes takes a few hundred nanoseconds per state, so a
/// piece of 64 states tens of microseconds). A `grain` of 0 is taken as 1.
///
/// The slices are slices (`&q[..]`, `&mut qdd[..]`), not `&Vec`s. A panic in `f` reaches the caller once
/// the other pieces have finished (rayon's `join`); the outputs of pieces that did not run are untouched.
pub fn par_batch<S, F>(slices: S, grain: usize, f: F) -> bool
where
    S: BatchSlices,
    F: Fn(S) + Sync,
{
    let Some(states) = slices.states() else {
        return false;
    };
    split(slices, states, grain.max(1), &f);
    true
}

/// Halves the batch at a multiple of `grain` until a piece is at most `grain` states, the halves run by
/// `rayon::join` (work stealing keeps both cores busy when pieces take unequal time).
fn split<S: BatchSlices, F: Fn(S) + Sync>(slices: S, states: usize, grain: usize, f: &F) {
    if states <= grain {
        if states > 0 {
            f(slices);
        }
        return;
    }
    let pieces = states.div_ceil(grain);
    let mid = (pieces / 2) * grain;
    let (left, right) = slices.split_at_state(mid);
    rayon::join(
        || split(left, mid, grain, f),
        || split(right, states - mid, grain, f),
    );
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::atomic::{AtomicUsize, Ordering};
    use std::vec::Vec;

    #[test]
    fn every_state_is_visited_once_in_pieces_of_grain() {
        for (n, grain) in [
            (0, 4),
            (1, 4),
            (7, 4),
            (64, 16),
            (1000, 64),
            (1001, 64),
            (5, 0),
        ] {
            let input: Vec<usize> = (0..n).collect();
            let mut output = std::vec![0usize; n];
            let pieces = AtomicUsize::new(0);
            let ok = par_batch((&input[..], &mut output[..]), grain, |(i, o)| {
                assert!(!i.is_empty() && i.len() <= grain.max(1));
                assert_eq!(i.len(), o.len());
                pieces.fetch_add(1, Ordering::Relaxed);
                for (x, y) in i.iter().zip(o.iter_mut()) {
                    *y = x * 3 + 1;
                }
            });
            assert!(ok);
            assert_eq!(output, (0..n).map(|x| x * 3 + 1).collect::<Vec<_>>());
            assert_eq!(pieces.into_inner(), n.div_ceil(grain.max(1)));
        }
    }

    #[test]
    fn mismatched_lengths_call_nothing() {
        let a = [1.0; 5];
        let mut b = [0.0; 4];
        let called = AtomicUsize::new(0);
        let ok = par_batch((&a[..], &mut b[..]), 2, |_| {
            called.fetch_add(1, Ordering::Relaxed);
        });
        assert!(!ok);
        assert_eq!(called.into_inner(), 0);
    }
}
