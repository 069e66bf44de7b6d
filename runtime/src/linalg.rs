//! Small dense factorizations generic over [`Real`] (nalgebra's own need `ComplexField`, which the
//! double-double type does not implement). Used for a floating base's 6×6 `D` and by tests as the
//! CRBA + Cholesky oracle.

use crate::Real;
use nalgebra::{DMatrix, Dim, Matrix, RawStorageMut};

/// In-place Cholesky `A = L Lᵀ` of a symmetric positive-definite matrix, reading the lower triangle.
/// Returns the smallest pivot `L_kk²` seen, or the first non-positive one (then `A` is not SPD and the
/// factor is unusable).
pub fn cholesky_in_place<T: Real, R: Dim, S: RawStorageMut<T, R, R>>(
    a: &mut Matrix<T, R, R, S>,
) -> T {
    let n = a.nrows();
    let mut min_pivot: Option<T> = None;
    for j in 0..n {
        let mut d = a[(j, j)];
        for k in 0..j {
            d -= a[(j, k)] * a[(j, k)];
        }
        min_pivot = Some(min_pivot.map_or(d, |m| m.min(d)));
        if !d.is_positive_finite() {
            return d;
        }
        let l = d.sqrt();
        a[(j, j)] = l;
        for i in j + 1..n {
            let mut s = a[(i, j)];
            for k in 0..j {
                s -= a[(i, k)] * a[(j, k)];
            }
            a[(i, j)] = s / l;
        }
    }
    min_pivot.unwrap_or(T::one())
}

/// Solves `L Lᵀ x = b` in place with the factor of [`cholesky_in_place`].
pub fn cholesky_solve_in_place<T: Real, R: Dim, S: RawStorageMut<T, R, R>>(
    l: &Matrix<T, R, R, S>,
    b: &mut [T],
) {
    let n = l.nrows();
    for i in 0..n {
        let mut s = b[i];
        for k in 0..i {
            s -= l[(i, k)] * b[k];
        }
        b[i] = s / l[(i, i)];
    }
    for i in (0..n).rev() {
        let mut s = b[i];
        for k in i + 1..n {
            s -= l[(k, i)] * b[k];
        }
        b[i] = s / l[(i, i)];
    }
}

/// Solves `A x = b` for a symmetric positive-definite `A` (copied, not modified). `None` if not SPD.
pub fn solve_spd<T: Real>(a: &DMatrix<T>, b: &[T]) -> Option<Vec<T>> {
    let mut l = a.clone();
    if !cholesky_in_place(&mut l).is_positive_finite() {
        return None;
    }
    let mut x = b.to_vec();
    cholesky_solve_in_place(&l, &mut x);
    Some(x)
}
