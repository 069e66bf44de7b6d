//! Small dense factorizations generic over [`Real`] (nalgebra's own need `ComplexField`, which the
//! double-double type does not implement). Used for a floating base's 6×6 `D`, by tests as the
//! CRBA + Cholesky oracle, and by the constraint embedding of closed kinematic loops (matrices up to
//! about 30×30):
//!
//! - LDLᵀ (square-root-free Cholesky) for symmetric positive-definite systems ([`cholesky_in_place`], [`solve_spd`]);
//! - LU with partial pivoting for general square systems ([`lu_in_place`], [`lu_solve_in_place`],
//!   [`lu_inverse_into`]) and the exact 1-norm condition number ([`condition_number_1`]);
//! - Householder QR with column pivoting ([`qr_column_pivoted`]) for rank decisions
//!   ([`independent_rows`], [`independent_columns`]) and minimum-norm least squares
//!   ([`solve_least_squares`]).
//!
//! The `_in_place` / `_into` functions never allocate: they work in the buffers they are given. The
//! QR-based functions allocate; they run at model load or inside a setup-time Newton iteration.

#[allow(unused_imports)]
use crate::alloc_prelude::*;
use crate::Real;
use nalgebra::{DMatrix, Dim, Matrix, RawStorageMut};

/// In-place factorization `A = L D Lᵀ` of a symmetric positive-definite matrix (unit lower-triangular
/// `L`, diagonal `D`), reading the lower triangle. On return the strict lower triangle holds `L` and the
/// diagonal holds `1 / D` — no square roots, and the solves multiply instead of dividing, which takes
/// the slow operations off the serial chain (one division per column). Returns the smallest pivot `D_kk`
/// seen, or the first non-positive one (then `A` is not SPD and the factor is unusable).
pub fn cholesky_in_place<T: Real, R: Dim, S: RawStorageMut<T, R, R>>(
    a: &mut Matrix<T, R, R, S>,
) -> T {
    let n = a.nrows();
    let mut min_pivot: Option<T> = None;
    for j in 0..n {
        // D_j = A_jj − Σ_k L_jk² D_k, with L_jk D_k kept in the upper triangle (row k, column j) while
        // column j is formed, so every product is computed once.
        let mut d = a[(j, j)];
        for k in 0..j {
            d -= a[(j, k)] * a[(k, j)];
        }
        min_pivot = Some(min_pivot.map_or(d, |m| m.min(d)));
        // Stop at a pivot known to be unusable; one known only at run time is the caller's to check
        // through the returned minimum.
        if d.value().is_some_and(|x| !(x > 0.0 && x.is_finite())) {
            return d;
        }
        let inv = T::one() / d;
        a[(j, j)] = inv;
        for i in j + 1..n {
            // W_ij = A_ij − Σ_k L_ik (L_jk D_k); L_ij = W_ij / D_j.
            let mut w = a[(i, j)];
            for k in 0..j {
                w -= a[(i, k)] * a[(k, j)];
            }
            a[(j, i)] = w;
            a[(i, j)] = w * inv;
        }
    }
    min_pivot.unwrap_or(T::one())
}

/// Solves `L D Lᵀ x = b` in place with the factor of [`cholesky_in_place`] (reads its strict lower
/// triangle and diagonal).
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
        b[i] = s;
    }
    for i in 0..n {
        b[i] *= l[(i, i)];
    }
    for i in (0..n).rev() {
        let mut s = b[i];
        for k in i + 1..n {
            s -= l[(k, i)] * b[k];
        }
        b[i] = s;
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

// ---------------------------------------------------------------------------------------------------
// LU with partial pivoting
// ---------------------------------------------------------------------------------------------------

/// `+∞` in `T` (for [`DoubleDouble`](crate::DoubleDouble) the pair `(∞, 0)`, which compares greater
/// than every finite value and is not [`is_finite`](Real::is_finite)).
#[inline]
fn infinity<T: Real>() -> T {
    T::from_f64(f64::INFINITY)
}

/// In-place LU factorization with partial (row) pivoting of a square `n×n` matrix: `P A = L U`.
///
/// On return the strict lower triangle of `a` holds the multipliers of the unit lower-triangular `L`
/// and the upper triangle holds `U`. The row exchanges are recorded LAPACK-style (`getrf`'s `ipiv`,
/// 0-based): at step `k` row `k` was exchanged with row `perm[k] ≥ k` (the rows of the partly
/// factored matrix, multipliers included), so `P` is the product of these transpositions applied in
/// order `k = 0, 1, …`; [`lu_row_order`] turns them into a row permutation. This representation is
/// what lets [`lu_solve_in_place`] permute the right-hand side without a scratch buffer.
///
/// Returns `Err(k)` if the pivot column `k` is exactly zero at and below the diagonal (or its pivot is
/// not finite): `A` is singular (or contains NaN/∞) and `a`, `perm` hold an unusable partial factor.
/// Never allocates.
///
/// # Panics
/// If `a` is not square or `perm.len() != a.nrows()`.
pub fn lu_in_place<T: Real>(a: &mut DMatrix<T>, perm: &mut [usize]) -> Result<(), usize> {
    let n = a.nrows();
    assert_eq!(a.ncols(), n, "lu_in_place: matrix must be square");
    assert_eq!(
        perm.len(),
        n,
        "lu_in_place: perm must have one entry per row"
    );
    for k in 0..n {
        // Partial pivoting: the largest magnitude in column k at or below the diagonal (first one on
        // ties, so the choice is deterministic).
        let mut p = k;
        let mut best = a[(k, k)].abs();
        for i in k + 1..n {
            let v = a[(i, k)].abs();
            if v > best {
                best = v;
                p = i;
            }
        }
        if best == T::zero() || !best.is_finite() {
            return Err(k);
        }
        perm[k] = p;
        if p != k {
            a.swap_rows(k, p);
        }
        let pivot = a[(k, k)];
        for i in k + 1..n {
            a[(i, k)] /= pivot;
        }
        // Rank-one update of the trailing block, column by column (column-major friendly).
        for j in k + 1..n {
            let ukj = a[(k, j)];
            if ukj == T::zero() {
                continue;
            }
            for i in k + 1..n {
                let lik = a[(i, k)];
                a[(i, j)] -= lik * ukj;
            }
        }
    }
    Ok(())
}

/// Solves `A X = B` in place for a small square `A`, with `aug = [A | B]` (`n × (n + m)`): Gaussian
/// elimination with partial pivoting in which each candidate row is compared with the pivot row and
/// the two are exchanged by [`Real::select_gt`] rather than by index. The arithmetic is that of ordinary
/// partial pivoting (the largest magnitude wins, the first one on ties), but written without
/// data-dependent control flow, so that generated code keeps the pivoting instead of freezing the row
/// order seen at generation time. On return columns `n..` hold `X`.
///
/// Returns the pivot ratio `min_k |u_kk| / max_ij |a_ij|` (0 for a singular `A`), a cheap measure of
/// singularity: `cond₁(A) ≥ 1 / (n · ratio)` (because `U⁻¹ = A⁻¹ Pᵀ L` with `|l_ij| ≤ 1`). Never
/// allocates.
///
/// # Panics
/// If `aug` has fewer than `n` rows or columns.
pub fn solve_pivoted_in_place<T: Real>(aug: &mut DMatrix<T>, n: usize) -> T {
    assert!(
        aug.nrows() >= n && aug.ncols() >= n,
        "solve_pivoted_in_place: aug is too small"
    );
    let cols = aug.ncols();
    if n == 0 {
        return T::one();
    }
    let mut scale = T::zero();
    for i in 0..n {
        for j in 0..n {
            let a = aug[(i, j)].abs();
            scale = a.select_gt(scale, a, scale);
        }
    }
    let mut min_pivot = T::zero();
    for k in 0..n {
        for i in k + 1..n {
            let (candidate, current) = (aug[(i, k)].abs(), aug[(k, k)].abs());
            for j in k..cols {
                let (top, bottom) = (aug[(k, j)], aug[(i, j)]);
                aug[(k, j)] = candidate.select_gt(current, bottom, top);
                aug[(i, j)] = candidate.select_gt(current, top, bottom);
            }
        }
        let pivot = aug[(k, k)];
        let magnitude = pivot.abs();
        min_pivot = if k == 0 {
            magnitude
        } else {
            min_pivot.select_gt(magnitude, magnitude, min_pivot)
        };
        // The reciprocal once, so the eliminations and the back substitution multiply.
        let inv = T::one() / pivot;
        aug[(k, k)] = inv;
        for i in k + 1..n {
            let f = aug[(i, k)] * inv;
            aug[(i, k)] = T::zero();
            for j in k + 1..cols {
                let u = aug[(k, j)];
                aug[(i, j)] -= f * u;
            }
        }
    }
    for j in n..cols {
        for k in (0..n).rev() {
            let mut s = aug[(k, j)];
            for m in k + 1..n {
                s -= aug[(k, m)] * aug[(m, j)];
            }
            aug[(k, j)] = s * aug[(k, k)];
        }
    }
    // 0/0 for a zero matrix: report 0 (singular) rather than NaN.
    let ratio = min_pivot / scale;
    scale.select_gt(T::zero(), ratio, T::zero())
}

/// The row order of the factor of [`lu_in_place`]: row `i` of `P A` is row `order[i]` of `A`.
/// Allocates (a convenience for callers and tests that want `P` explicitly).
pub fn lu_row_order(perm: &[usize]) -> Vec<usize> {
    let mut order: Vec<usize> = (0..perm.len()).collect();
    for (k, &p) in perm.iter().enumerate() {
        order.swap(k, p);
    }
    order
}

/// Solves `A x = b` in place (`b` becomes `x`) with the factor and pivots of a successful
/// [`lu_in_place`]. Never allocates.
///
/// # Panics
/// If the dimensions of `lu`, `perm` and `b` disagree.
pub fn lu_solve_in_place<T: Real>(lu: &DMatrix<T>, perm: &[usize], b: &mut [T]) {
    let n = lu.nrows();
    assert_eq!(lu.ncols(), n, "lu_solve_in_place: factor must be square");
    assert_eq!(perm.len(), n, "lu_solve_in_place: perm length");
    assert_eq!(b.len(), n, "lu_solve_in_place: right-hand side length");
    for (k, &p) in perm.iter().enumerate() {
        b.swap(k, p);
    }
    // L y = P b (unit diagonal), column-oriented.
    for j in 0..n {
        let yj = b[j];
        if yj != T::zero() {
            for i in j + 1..n {
                b[i] -= lu[(i, j)] * yj;
            }
        }
    }
    // U x = y.
    for j in (0..n).rev() {
        let xj = b[j] / lu[(j, j)];
        b[j] = xj;
        if xj != T::zero() {
            for i in 0..j {
                b[i] -= lu[(i, j)] * xj;
            }
        }
    }
}

/// Solves `A X = B` in place for every column of `b` (`n×k`), with the factor of [`lu_in_place`].
/// Never allocates.
///
/// # Panics
/// If `b.nrows()` differs from the order of the factor.
pub fn lu_solve_matrix_in_place<T: Real>(lu: &DMatrix<T>, perm: &[usize], b: &mut DMatrix<T>) {
    let n = lu.nrows();
    assert_eq!(
        b.nrows(),
        n,
        "lu_solve_matrix_in_place: right-hand side rows"
    );
    if n == 0 {
        return;
    }
    // DMatrix is column-major: each chunk of n is one column.
    for column in b.as_mut_slice().chunks_exact_mut(n) {
        lu_solve_in_place(lu, perm, column);
    }
}

/// Writes `A⁻¹` into `out` (`n×n`) from the factor of [`lu_in_place`]. Never allocates.
///
/// # Panics
/// If `out` is not the same shape as the factor.
pub fn lu_inverse_into<T: Real>(lu: &DMatrix<T>, perm: &[usize], out: &mut DMatrix<T>) {
    assert_eq!(
        out.shape(),
        lu.shape(),
        "lu_inverse_into: output must match the factor's shape"
    );
    out.fill_with_identity();
    lu_solve_matrix_in_place(lu, perm, out);
}

/// The matrix 1-norm `‖A‖₁ = max_j Σ_i |a_ij|` (largest absolute column sum); zero for an empty matrix.
pub fn norm_1<T: Real>(a: &DMatrix<T>) -> T {
    let mut norm = T::zero();
    for j in 0..a.ncols() {
        let mut s = T::zero();
        for i in 0..a.nrows() {
            s += a[(i, j)].abs();
        }
        // `max` would keep a finite norm over a NaN column sum; propagate non-finite sums instead.
        if s > norm || !s.is_finite() {
            norm = s;
        }
    }
    norm
}

/// The exact 1-norm condition number `‖A‖₁ · ‖A⁻¹‖₁` of the square matrix `a`, given its factor
/// `lu`/`perm` from [`lu_in_place`]. `A⁻¹` is formed in `scratch` (`n×n`, overwritten), which for the
/// small matrices this serves is cheaper and simpler than an estimator. Never allocates.
///
/// Returns `+∞` (`T::from_f64(f64::INFINITY)`) if the factor has a zero or non-finite pivot (`A`
/// singular, e.g. after [`lu_in_place`] returned `Err`) or the inverse overflows. An empty (`0×0`)
/// matrix gives `0` (both norms are zero).
///
/// # Panics
/// If the shapes of `a`, `lu`, `perm` and `scratch` disagree.
pub fn condition_number_1<T: Real>(
    a: &DMatrix<T>,
    lu: &DMatrix<T>,
    perm: &[usize],
    scratch: &mut DMatrix<T>,
) -> T {
    let n = lu.nrows();
    assert_eq!(a.shape(), lu.shape(), "condition_number_1: a and lu shapes");
    assert_eq!(perm.len(), n, "condition_number_1: perm length");
    for k in 0..n {
        let u = lu[(k, k)];
        if u == T::zero() || !u.is_finite() {
            return infinity();
        }
    }
    lu_inverse_into(lu, perm, scratch);
    let cond = norm_1(a) * norm_1(scratch);
    if cond.is_finite() {
        cond
    } else {
        infinity()
    }
}

/// Allocating LU: the factor and pivots of [`lu_in_place`] for a copy of `a`, or `Err(k)` at a zero
/// pivot column `k`.
pub fn lu<T: Real>(a: &DMatrix<T>) -> Result<(DMatrix<T>, Vec<usize>), usize> {
    let mut f = a.clone();
    let mut perm = vec![0; a.nrows()];
    lu_in_place(&mut f, &mut perm)?;
    Ok((f, perm))
}

/// Solves the square system `A x = b` by LU with partial pivoting (allocating). `None` if a pivot is
/// exactly zero.
pub fn solve_lu<T: Real>(a: &DMatrix<T>, b: &[T]) -> Option<Vec<T>> {
    let (f, perm) = lu(a).ok()?;
    let mut x = b.to_vec();
    lu_solve_in_place(&f, &perm, &mut x);
    Some(x)
}

/// `A⁻¹` by LU with partial pivoting (allocating). `None` if a pivot is exactly zero.
pub fn inverse<T: Real>(a: &DMatrix<T>) -> Option<DMatrix<T>> {
    let (f, perm) = lu(a).ok()?;
    let mut inv = DMatrix::zeros(a.nrows(), a.ncols());
    lu_inverse_into(&f, &perm, &mut inv);
    Some(inv)
}

/// [`condition_number_1`] of a square matrix, factoring it first (allocating); `+∞` if singular.
pub fn condition_number_1_of<T: Real>(a: &DMatrix<T>) -> T {
    match lu(a) {
        Ok((f, perm)) => {
            let mut scratch = DMatrix::zeros(a.nrows(), a.ncols());
            condition_number_1(a, &f, &perm, &mut scratch)
        }
        Err(_) => infinity(),
    }
}

// ---------------------------------------------------------------------------------------------------
// Householder QR (optionally with column pivoting)
// ---------------------------------------------------------------------------------------------------

/// Default relative tolerance of [`solve_least_squares`]: `|R_kk| ≤ 1e-12·|R_00|` counts as zero.
pub const LEAST_SQUARES_REL_TOL: f64 = 1e-12;

/// Euclidean norm of `f(0), …, f(len − 1)`, scaled by the largest magnitude so that squaring neither
/// overflows nor underflows.
fn scaled_norm<T: Real>(len: usize, f: impl Fn(usize) -> T) -> T {
    let mut scale = T::zero();
    for i in 0..len {
        scale = scale.max(f(i).abs());
    }
    if scale == T::zero() || !scale.is_finite() {
        return scale;
    }
    let mut sum = T::zero();
    for i in 0..len {
        let v = f(i) / scale;
        sum += v * v;
    }
    scale * sum.sqrt()
}

/// `√(a² + b²)` without overflow.
fn hypot<T: Real>(a: T, b: T) -> T {
    let (a, b) = (a.abs(), b.abs());
    let s = a.max(b);
    if s == T::zero() {
        return s;
    }
    let (x, y) = (a / s, b / s);
    s * (x * x + y * y).sqrt()
}

/// Norm of column `j` of `a` from row `from` down.
fn column_norm<T: Real>(a: &DMatrix<T>, j: usize, from: usize) -> T {
    scaled_norm(a.nrows() - from, |i| a[(from + i, j)])
}

/// Turns column `k` of `a` (rows `k..`) into a Householder reflector `H = I − τ v vᵀ` with `v_k = 1`
/// (LAPACK `larfg`): `v_{k+1..}` overwrites the subdiagonal of column `k`, `R_kk = β` the diagonal.
/// Returns `τ` (zero when the column is already zero below the diagonal: `H = I`).
fn make_householder<T: Real>(a: &mut DMatrix<T>, k: usize) -> T {
    let m = a.nrows();
    let alpha = a[(k, k)];
    let xnorm = scaled_norm(m - k - 1, |i| a[(k + 1 + i, k)]);
    if xnorm == T::zero() {
        return T::zero();
    }
    let mut beta = hypot(alpha, xnorm);
    if alpha >= T::zero() {
        beta = -beta;
    }
    let tau = (beta - alpha) / beta;
    let denom = alpha - beta;
    for i in k + 1..m {
        a[(i, k)] /= denom;
    }
    a[(k, k)] = beta;
    tau
}

/// Applies the reflector stored in column `k` of `qr` (with `tau`) from the left to columns `cols` of
/// `target`, rows `k..`.
fn apply_reflector_to_columns<T: Real>(
    qr: &DMatrix<T>,
    k: usize,
    tau: T,
    target: &mut DMatrix<T>,
    cols: core::ops::Range<usize>,
) {
    if tau == T::zero() {
        return;
    }
    let m = qr.nrows();
    for j in cols {
        let mut w = target[(k, j)];
        for i in k + 1..m {
            w += qr[(i, k)] * target[(i, j)];
        }
        w *= tau;
        target[(k, j)] -= w;
        for i in k + 1..m {
            target[(i, j)] -= w * qr[(i, k)];
        }
    }
}

/// Applies the reflector stored in column `k` of `qr` to the vector `b` (length `qr.nrows()`).
fn apply_reflector_to_vector<T: Real>(qr: &DMatrix<T>, k: usize, tau: T, b: &mut [T]) {
    if tau == T::zero() {
        return;
    }
    let m = qr.nrows();
    let mut w = b[k];
    for i in k + 1..m {
        w += qr[(i, k)] * b[i];
    }
    w *= tau;
    b[k] -= w;
    for i in k + 1..m {
        b[i] -= w * qr[(i, k)];
    }
}

/// Householder QR of `a` in place (LAPACK `geqrf`/`geqp3` layout): `R` in the upper triangle, the
/// reflectors below it, their `τ` in `tau` (length `min(m, n)`). With `perm`, columns are pivoted:
/// at each step the remaining column of largest (exactly recomputed) norm is brought forward, first
/// one on ties, and `perm` (initialized by the caller) is permuted alike.
fn householder_qr_in_place<T: Real>(
    a: &mut DMatrix<T>,
    tau: &mut [T],
    mut perm: Option<&mut [usize]>,
) {
    let (m, n) = a.shape();
    let steps = m.min(n);
    debug_assert_eq!(tau.len(), steps);
    for k in 0..steps {
        if let Some(perm) = perm.as_deref_mut() {
            // Norms are recomputed rather than downdated: exact, robust, and cheap at these sizes.
            let mut best = k;
            let mut best_norm = column_norm(a, k, k);
            for j in k + 1..n {
                let norm = column_norm(a, j, k);
                if norm > best_norm {
                    best = j;
                    best_norm = norm;
                }
            }
            if best != k {
                a.swap_columns(k, best);
                perm.swap(k, best);
            }
        }
        let t = make_householder(a, k);
        tau[k] = t;
        if t != T::zero() {
            // The reflector lives in column k, the update touches columns k+1..: split the borrow by
            // working column by column through indices.
            let m = a.nrows();
            for j in k + 1..n {
                let mut w = a[(k, j)];
                for i in k + 1..m {
                    w += a[(i, k)] * a[(i, j)];
                }
                w *= t;
                a[(k, j)] -= w;
                for i in k + 1..m {
                    let vi = a[(i, k)];
                    a[(i, j)] -= w * vi;
                }
            }
        }
    }
}

/// A Householder QR factorization with column pivoting, `A P = Q R`, of an `m×n` matrix (any shape),
/// from [`qr_column_pivoted`].
///
/// `Q` (`m×m` orthogonal, kept as `min(m, n)` reflectors) and `R` (`min(m, n)×n` upper trapezoidal)
/// are such that `|R_00| ≥ |R_11| ≥ …` (in exact arithmetic): each step picks the remaining column
/// farthest from the span of those already chosen, so the leading columns of `A P` are a
/// well-conditioned independent set and the diagonal of `R` reveals the numerical rank.
#[derive(Clone, Debug)]
pub struct ColumnPivotedQr<T: Real> {
    /// `R` in the upper triangle, the Householder vectors (without their unit leading entry) below.
    qr: DMatrix<T>,
    /// The reflector coefficients `τ_k`, `H_k = I − τ_k v_k v_kᵀ`, `Q = H_0 H_1 ⋯`.
    tau: Vec<T>,
    /// Column `k` of `A P` is column `perm[k]` of `A`.
    perm: Vec<usize>,
}

/// Householder QR with column pivoting of `a` (`m×n`, any shape), `A P = Q R`. Allocates (used at
/// model load). See [`ColumnPivotedQr`].
pub fn qr_column_pivoted<T: Real>(a: &DMatrix<T>) -> ColumnPivotedQr<T> {
    let mut qr = a.clone();
    let mut tau = vec![T::zero(); a.nrows().min(a.ncols())];
    let mut perm: Vec<usize> = (0..a.ncols()).collect();
    householder_qr_in_place(&mut qr, &mut tau, Some(&mut perm));
    ColumnPivotedQr { qr, tau, perm }
}

impl<T: Real> ColumnPivotedQr<T> {
    /// Rows `m` of the factored matrix.
    pub fn nrows(&self) -> usize {
        self.qr.nrows()
    }

    /// Columns `n` of the factored matrix.
    pub fn ncols(&self) -> usize {
        self.qr.ncols()
    }

    /// The numerical rank: the number of leading diagonal entries with `|R_kk| > rel_tol · |R_00|`.
    /// Counting stops at the first entry below the threshold (the diagonal is non-increasing in exact
    /// arithmetic; stopping there guarantees that the first `rank` entries of
    /// [`permutation`](Self::permutation) are the independent columns). Zero for a zero or empty matrix.
    pub fn rank(&self, rel_tol: f64) -> usize {
        let steps = self.tau.len();
        if steps == 0 {
            return 0;
        }
        let threshold = T::from_f64(rel_tol) * self.qr[(0, 0)].abs();
        (0..steps)
            .take_while(|&k| self.qr[(k, k)].abs() > threshold)
            .count()
    }

    /// The column order chosen by pivoting: column `k` of `A P` is column `permutation()[k]` of `A`.
    /// The first [`rank`](Self::rank) entries index a well-conditioned, maximal independent set of
    /// columns.
    pub fn permutation(&self) -> &[usize] {
        &self.perm
    }

    /// The diagonal `R_00, R_11, …` (length `min(m, n)`; signed, magnitudes non-increasing).
    pub fn r_diagonal(&self) -> Vec<T> {
        (0..self.tau.len()).map(|k| self.qr[(k, k)]).collect()
    }

    /// The `min(m, n)×n` upper-trapezoidal factor `R` (columns in pivoted order).
    pub fn r(&self) -> DMatrix<T> {
        let steps = self.tau.len();
        DMatrix::from_fn(steps, self.ncols(), |i, j| {
            if i <= j {
                self.qr[(i, j)]
            } else {
                T::zero()
            }
        })
    }

    /// The thin orthonormal factor `Q` (`m×min(m, n)`), so that `A P = Q R`.
    pub fn q(&self) -> DMatrix<T> {
        let (m, steps) = (self.nrows(), self.tau.len());
        let mut q = DMatrix::from_fn(m, steps, |i, j| if i == j { T::one() } else { T::zero() });
        for k in (0..steps).rev() {
            apply_reflector_to_columns(&self.qr, k, self.tau[k], &mut q, 0..steps);
        }
        q
    }

    /// `b ← Qᵀ b` (`b` of length `m`). Never allocates.
    pub fn apply_qt_in_place(&self, b: &mut [T]) {
        assert_eq!(b.len(), self.nrows(), "apply_qt_in_place: length");
        for (k, &t) in self.tau.iter().enumerate() {
            apply_reflector_to_vector(&self.qr, k, t, b);
        }
    }

    /// `b ← Q b` (`b` of length `m`). Never allocates.
    pub fn apply_q_in_place(&self, b: &mut [T]) {
        assert_eq!(b.len(), self.nrows(), "apply_q_in_place: length");
        for (k, &t) in self.tau.iter().enumerate().rev() {
            apply_reflector_to_vector(&self.qr, k, t, b);
        }
    }
}

/// Indices (ascending) of a maximal set of linearly independent rows of `a`, by QR with column
/// pivoting of `aᵀ`: rank decided with `|R_kk| > rel_tol·|R_00|`. Among equal candidates (e.g.
/// duplicated rows) the lower index wins; zero rows are never chosen.
pub fn independent_rows<T: Real>(a: &DMatrix<T>, rel_tol: f64) -> Vec<usize> {
    independent_columns(&a.transpose(), rel_tol)
}

/// Indices (ascending) of a maximal set of linearly independent columns of `a`, chosen by column
/// pivoting (so the chosen set is well conditioned): rank decided with `|R_kk| > rel_tol·|R_00|`.
pub fn independent_columns<T: Real>(a: &DMatrix<T>, rel_tol: f64) -> Vec<usize> {
    let qr = qr_column_pivoted(a);
    let rank = qr.rank(rel_tol);
    let mut chosen = qr.permutation()[..rank].to_vec();
    chosen.sort_unstable();
    chosen
}

// ---------------------------------------------------------------------------------------------------
// Least squares
// ---------------------------------------------------------------------------------------------------

/// The minimum-norm least-squares solution `x = A⁺ b` of `A x ≈ b` for any `m×n` matrix `a` (over- or
/// under-determined, possibly rank deficient); [`solve_least_squares_with_tol`] with
/// [`LEAST_SQUARES_REL_TOL`] (`1e-12`). Allocates.
pub fn solve_least_squares<T: Real>(a: &DMatrix<T>, b: &[T]) -> Vec<T> {
    solve_least_squares_with_tol(a, b, LEAST_SQUARES_REL_TOL)
}

/// The minimum-norm least-squares solution of `A x ≈ b`, treating `A` as having the rank `r` decided by
/// [`ColumnPivotedQr::rank`] with `rel_tol` (the smaller singular directions are dropped, as in a
/// truncated pseudo-inverse). Allocates.
///
/// Method (a complete orthogonal decomposition): `A P = Q R`, keep the first `r` rows `S = [R₁₁ R₁₂]`
/// of `R` and `c = (Qᵀ b)[..r]`; the minimum-norm `y` with `S y = c` comes from the QR of `Sᵀ = Z T`:
/// `y = Z T⁻ᵀ c`; then `x = P y`. When `r = n` this reduces to back substitution with `R₁₁`.
///
/// # Panics
/// If `b.len() != a.nrows()`.
pub fn solve_least_squares_with_tol<T: Real>(a: &DMatrix<T>, b: &[T], rel_tol: f64) -> Vec<T> {
    let (m, n) = a.shape();
    assert_eq!(b.len(), m, "solve_least_squares: right-hand side length");
    let mut x = vec![T::zero(); n];
    if m == 0 || n == 0 {
        return x;
    }
    let qr = qr_column_pivoted(a);
    let r = qr.rank(rel_tol);
    if r == 0 {
        return x;
    }
    let mut c = b.to_vec();
    qr.apply_qt_in_place(&mut c);
    let rf = &qr.qr;
    let mut y = vec![T::zero(); n];
    if r == n {
        // Full column rank: R₁₁ y = c₁.
        for i in (0..n).rev() {
            let mut s = c[i];
            for j in i + 1..n {
                s -= rf[(i, j)] * y[j];
            }
            y[i] = s / rf[(i, i)];
        }
    } else {
        // Sᵀ (n×r) has full column rank because R₁₁ has a non-negligible diagonal.
        let mut st = DMatrix::from_fn(n, r, |j, i| if i <= j { rf[(i, j)] } else { T::zero() });
        let mut tau = vec![T::zero(); r];
        householder_qr_in_place(&mut st, &mut tau, None);
        // S = [Tᵀ 0] Zᵀ: with w = Zᵀ y, Tᵀ w₁ = c₁ and w₂ = 0 for the minimum norm.
        for i in 0..r {
            let mut s = c[i];
            for j in 0..i {
                s -= st[(j, i)] * y[j];
            }
            y[i] = s / st[(i, i)];
        }
        for k in (0..r).rev() {
            apply_reflector_to_vector(&st, k, tau[k], &mut y);
        }
    }
    for (j, &p) in qr.perm.iter().enumerate() {
        x[p] = y[j];
    }
    x
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::DoubleDouble;

    type Dd = DoubleDouble;

    /// The crate's deterministic generator, so failures reproduce, with this module's draws on top.
    struct Rng(crate::random::SplitMix64);

    impl Rng {
        fn new(seed: u64) -> Rng {
            Rng(crate::random::SplitMix64::new(seed))
        }
        /// Uniform in [-1, 1).
        fn signed_unit(&mut self) -> f64 {
            self.0.uniform(-1.0, 1.0)
        }
        fn matrix<T: Real>(&mut self, m: usize, n: usize) -> DMatrix<T> {
            DMatrix::from_fn(m, n, |_, _| T::from_f64(self.signed_unit()))
        }
        fn vector<T: Real>(&mut self, n: usize) -> Vec<T> {
            (0..n).map(|_| T::from_f64(self.signed_unit())).collect()
        }
    }

    fn from_rows<T: Real>(rows: &[&[f64]]) -> DMatrix<T> {
        let n = rows.first().map_or(0, |r| r.len());
        DMatrix::from_fn(rows.len(), n, |i, j| T::from_f64(rows[i][j]))
    }

    fn matmul<T: Real>(a: &DMatrix<T>, b: &DMatrix<T>) -> DMatrix<T> {
        assert_eq!(a.ncols(), b.nrows());
        DMatrix::from_fn(a.nrows(), b.ncols(), |i, j| {
            let mut s = T::zero();
            for k in 0..a.ncols() {
                s += a[(i, k)] * b[(k, j)];
            }
            s
        })
    }

    fn matvec<T: Real>(a: &DMatrix<T>, x: &[T]) -> Vec<T> {
        assert_eq!(a.ncols(), x.len());
        (0..a.nrows())
            .map(|i| {
                let mut s = T::zero();
                for (k, &xk) in x.iter().enumerate() {
                    s += a[(i, k)] * xk;
                }
                s
            })
            .collect()
    }

    fn transpose_matvec<T: Real>(a: &DMatrix<T>, y: &[T]) -> Vec<T> {
        matvec(&a.transpose(), y)
    }

    fn max_abs<T: Real>(v: &[T]) -> T {
        v.iter().fold(T::zero(), |m, &x| m.max(x.abs()))
    }

    fn max_abs_matrix<T: Real>(a: &DMatrix<T>) -> T {
        max_abs(a.as_slice())
    }

    /// `max |a − b|` over two vectors.
    fn max_diff<T: Real>(a: &[T], b: &[T]) -> T {
        assert_eq!(a.len(), b.len());
        a.iter()
            .zip(b)
            .fold(T::zero(), |m, (&x, &y)| m.max((x - y).abs()))
    }

    fn norm_inf<T: Real>(a: &DMatrix<T>) -> T {
        norm_1(&a.transpose())
    }

    fn identity<T: Real>(n: usize) -> DMatrix<T> {
        DMatrix::from_fn(n, n, |i, j| if i == j { T::one() } else { T::zero() })
    }

    /// Converts to double-double without losing a double-double input's low part.
    fn to_dd<T: Real>(v: T) -> Dd {
        let hi = v.to_f64();
        Dd::from_f64(hi) + Dd::from_f64((v - T::from_f64(hi)).to_f64())
    }

    fn hilbert<T: Real>(n: usize) -> DMatrix<T> {
        DMatrix::from_fn(n, n, |i, j| T::one() / T::from_f64((i + j + 1) as f64))
    }

    /// Test matrices for the LU: random (any pivot order), random shifted (well conditioned), and a
    /// row-reversed shifted one with small diagonal (every step must pivot).
    fn lu_test_matrices<T: Real>(rng: &mut Rng) -> Vec<DMatrix<T>> {
        let mut out = Vec::new();
        for n in [1, 2, 3, 4, 6, 9, 13, 20, 30] {
            for _ in 0..3 {
                out.push(rng.matrix::<T>(n, n));
            }
            let mut shifted = rng.matrix::<T>(n, n);
            let shift = T::from_f64(2.0 * (n as f64).sqrt());
            for i in 0..n {
                shifted[(i, i)] += shift;
            }
            let mut reversed = shifted.clone();
            for i in 0..n / 2 {
                reversed.swap_rows(i, n - 1 - i);
            }
            out.push(shifted);
            out.push(reversed);
        }
        out
    }

    /// Solves random systems with known solutions; returns the largest normwise relative residual
    /// `‖A x − b‖∞ / (‖A‖∞ ‖x‖∞)` and the largest forward error divided by `cond₁(A)`.
    fn check_lu_random<T: Real>(residual_tol: f64) -> (f64, f64) {
        let mut rng = Rng::new(0x1234_5678_9abc_def1);
        let (mut worst_residual, mut worst_forward) = (0.0f64, 0.0f64);
        for a in lu_test_matrices::<T>(&mut rng) {
            let n = a.nrows();
            let x_true = rng.vector::<T>(n);
            let b = matvec(&a, &x_true);
            let mut f = a.clone();
            let mut perm = vec![usize::MAX; n];
            lu_in_place(&mut f, &mut perm).expect("random matrix is nonsingular");
            assert!(perm.iter().enumerate().all(|(k, &p)| p >= k && p < n));
            let mut x = b.clone();
            lu_solve_in_place(&f, &perm, &mut x);

            let r = max_diff(&matvec(&a, &x), &b);
            let residual = (r / (norm_inf(&a) * max_abs(&x))).to_f64();
            assert!(
                residual <= residual_tol,
                "{} n={n}: relative residual {residual:e} > {residual_tol:e}",
                T::NAME
            );
            let mut scratch = DMatrix::zeros(n, n);
            let cond = condition_number_1(&a, &f, &perm, &mut scratch).to_f64();
            assert!(cond.is_finite() && cond >= 1.0 - 1e-12, "cond {cond}");
            let forward = (max_diff(&x, &x_true) / max_abs(&x_true)).to_f64();
            assert!(
                forward <= 10.0 * n as f64 * cond * residual_tol,
                "{} n={n}: forward error {forward:e} with cond {cond:e}",
                T::NAME
            );
            worst_residual = worst_residual.max(residual);
            worst_forward = worst_forward.max(forward / cond);
        }
        (worst_residual, worst_forward)
    }

    #[test]
    fn lu_solves_random_systems_f64() {
        let (res, fwd) = check_lu_random::<f64>(1e-13);
        eprintln!("f64 LU: max relative residual {res:.2e}, max forward error / cond {fwd:.2e}");
    }

    #[test]
    fn lu_solves_random_systems_dd() {
        let (res, fwd) = check_lu_random::<Dd>(1e-28);
        eprintln!("dd LU: max relative residual {res:.2e}, max forward error / cond {fwd:.2e}");
    }

    /// `P A = L U` with the factor of `lu_in_place`, `A A⁻¹ = A⁻¹ A = I`, and the multi-column solve
    /// agreeing with column-by-column solves.
    fn check_lu_factor_and_inverse<T: Real>(tol: f64) -> f64 {
        let mut rng = Rng::new(99);
        let mut worst = 0.0f64;
        for a in lu_test_matrices::<T>(&mut rng) {
            let n = a.nrows();
            let (f, perm) = lu(&a).unwrap();
            let l = DMatrix::from_fn(n, n, |i, j| match i.cmp(&j) {
                core::cmp::Ordering::Greater => f[(i, j)],
                core::cmp::Ordering::Equal => T::one(),
                core::cmp::Ordering::Less => T::zero(),
            });
            let u = DMatrix::from_fn(n, n, |i, j| if i <= j { f[(i, j)] } else { T::zero() });
            let order = lu_row_order(&perm);
            let mut sorted = order.clone();
            sorted.sort_unstable();
            assert_eq!(
                sorted,
                (0..n).collect::<Vec<_>>(),
                "row order is a permutation"
            );
            let pa = DMatrix::from_fn(n, n, |i, j| a[(order[i], j)]);
            let recon = (max_abs_matrix(&(matmul(&l, &u) - &pa)) / max_abs_matrix(&a)).to_f64();
            assert!(recon <= tol, "{} n={n}: ‖PA − LU‖ {recon:e}", T::NAME);
            // Partial pivoting bounds the multipliers by 1.
            assert!(max_abs_matrix(&(l.clone() - identity::<T>(n))) <= T::one());

            let mut inv = DMatrix::zeros(n, n);
            lu_inverse_into(&f, &perm, &mut inv);
            let cond = (norm_1(&a) * norm_1(&inv)).to_f64();
            let e1 = max_abs_matrix(&(matmul(&a, &inv) - identity::<T>(n))).to_f64();
            let e2 = max_abs_matrix(&(matmul(&inv, &a) - identity::<T>(n))).to_f64();
            assert!(
                e1.max(e2) <= cond * tol,
                "{} n={n}: ‖A A⁻¹ − I‖ {e1:e}, ‖A⁻¹ A − I‖ {e2:e}, cond {cond:e}",
                T::NAME
            );
            worst = worst.max(e1.max(e2));
            assert_eq!(inverse(&a).unwrap(), inv);

            let mut bm = rng.matrix::<T>(n, 3);
            let columns: Vec<Vec<T>> = (0..3)
                .map(|j| bm.column(j).iter().copied().collect())
                .collect();
            lu_solve_matrix_in_place(&f, &perm, &mut bm);
            for (j, col) in columns.into_iter().enumerate() {
                let x = solve_lu(&a, &col).unwrap();
                let xm: Vec<T> = bm.column(j).iter().copied().collect();
                assert_eq!(
                    x, xm,
                    "matrix solve column {j} differs from the vector solve"
                );
            }
        }
        worst
    }

    #[test]
    fn lu_factor_and_inverse_f64() {
        let worst = check_lu_factor_and_inverse::<f64>(1e-14);
        eprintln!("f64 inverse: max |A A⁻¹ − I|, |A⁻¹ A − I| = {worst:.2e}");
    }

    #[test]
    fn lu_factor_and_inverse_dd() {
        let worst = check_lu_factor_and_inverse::<Dd>(1e-29);
        eprintln!("dd inverse: max |A A⁻¹ − I|, |A⁻¹ A − I| = {worst:.2e}");
    }

    fn check_lu_pivots<T: Real>() {
        // A tiny leading entry: without row exchanges the result would be garbage.
        let a = from_rows::<T>(&[&[1e-20, 1.0], &[1.0, 1.0]]);
        let (f, perm) = lu(&a).unwrap();
        assert_eq!(perm, vec![1, 1]);
        assert_eq!(lu_row_order(&perm), vec![1, 0]);
        assert_eq!(f[(1, 0)], T::from_f64(1e-20));
        let x = solve_lu(&a, &[T::one(), T::from_f64(2.0)]).unwrap();
        // Exact: x₀ = 1/(1 − ε), x₁ = (1 − 2ε)/(1 − ε).
        let eps = T::from_f64(1e-20);
        let exact = [
            T::one() / (T::one() - eps),
            (T::one() - eps - eps) / (T::one() - eps),
        ];
        assert!(max_diff(&x, &exact) <= T::from_f64(4.0) * T::epsilon());

        // A permutation matrix: every step exchanges.
        let p = from_rows::<T>(&[&[0.0, 0.0, 1.0], &[1.0, 0.0, 0.0], &[0.0, 1.0, 0.0]]);
        let x = solve_lu(&p, &[T::from_f64(1.0), T::from_f64(2.0), T::from_f64(3.0)]).unwrap();
        assert_eq!(
            x,
            vec![T::from_f64(2.0), T::from_f64(3.0), T::from_f64(1.0)]
        );
        // Empty system.
        let mut empty = DMatrix::<T>::zeros(0, 0);
        assert_eq!(lu_in_place(&mut empty, &mut []), Ok(()));
        lu_solve_in_place(&empty, &[], &mut []);
    }

    #[test]
    fn lu_pivots_f64() {
        check_lu_pivots::<f64>();
    }

    #[test]
    fn lu_pivots_dd() {
        check_lu_pivots::<Dd>();
    }

    fn check_singular_lu<T: Real>() {
        let inf_f64 = f64::INFINITY;
        // Second column becomes exactly zero after the first elimination step.
        let a = from_rows::<T>(&[&[1.0, 2.0], &[2.0, 4.0]]);
        let mut f = a.clone();
        let mut perm = [0; 2];
        assert_eq!(lu_in_place(&mut f, &mut perm), Err(1));
        let mut scratch = DMatrix::zeros(2, 2);
        let cond = condition_number_1(&a, &f, &perm, &mut scratch);
        assert!(!cond.is_finite() && cond.to_f64() == inf_f64);
        assert!(cond > T::from_f64(f64::MAX));

        assert_eq!(lu(&DMatrix::<T>::zeros(3, 3)).err(), Some(0));
        let zero_column = from_rows::<T>(&[&[1.0, 0.0, 2.0], &[3.0, 0.0, 4.0], &[5.0, 0.0, 6.0]]);
        assert_eq!(lu(&zero_column).err(), Some(1));
        let rank_two = from_rows::<T>(&[&[1.0, 2.0, 3.0], &[2.0, 4.0, 6.0], &[1.0, 0.0, 1.0]]);
        assert_eq!(lu(&rank_two).err(), Some(2));
        let mut nan = identity::<T>(2);
        nan[(1, 0)] = T::from_f64(f64::NAN);
        nan[(0, 0)] = T::from_f64(f64::NAN);
        assert_eq!(lu(&nan).err(), Some(0));

        assert!(solve_lu(&zero_column, &[T::one(), T::one(), T::one()]).is_none());
        assert!(inverse(&zero_column).is_none());
        let cond = condition_number_1_of(&zero_column);
        assert!(!cond.is_finite() && cond.to_f64() == inf_f64);
    }

    #[test]
    fn singular_lu_f64() {
        check_singular_lu::<f64>();
    }

    #[test]
    fn singular_lu_dd() {
        check_singular_lu::<Dd>();
    }

    #[test]
    fn double_double_infinity_behaves() {
        let inf = Dd::from_f64(f64::INFINITY);
        assert!(!inf.is_finite());
        assert_eq!(inf.to_f64(), f64::INFINITY);
        assert!(inf > Dd::from_f64(f64::MAX));
        assert!(infinity::<Dd>() == inf);
        assert!(infinity::<f32>().is_infinite());
    }

    /// Returns the relative errors of cond₁ for diag(1, 1e-6) and the 4×4 Hilbert matrix.
    fn check_condition_numbers<T: Real>(hilbert_tol: f64) -> (f64, f64) {
        let d = from_rows::<T>(&[&[1.0, 0.0], &[0.0, 1e-6]]);
        let cd = condition_number_1_of(&d).to_f64();
        let diag_err = (cd - 1e6).abs() / 1e6;
        assert!(diag_err <= 1e-15, "{} cond(diag(1, 1e-6)) = {cd}", T::NAME);

        let h = hilbert::<T>(4);
        let ch = condition_number_1_of(&h);
        let hilbert_err = ((ch - T::from_f64(28375.0)) / T::from_f64(28375.0))
            .abs()
            .to_f64();
        assert!(
            hilbert_err <= hilbert_tol,
            "{} cond₁(H₄) = {} (relative error {hilbert_err:e})",
            T::NAME,
            ch.to_f64()
        );
        // The exact inverse of H₄ has integer entries; the LU-based one must match them.
        let exact_inv = from_rows::<T>(&[
            &[16.0, -120.0, 240.0, -140.0],
            &[-120.0, 1200.0, -2700.0, 1680.0],
            &[240.0, -2700.0, 6480.0, -4200.0],
            &[-140.0, 1680.0, -4200.0, 2800.0],
        ]);
        let inv = inverse(&h).unwrap();
        let inv_err = (max_abs_matrix(&(inv - &exact_inv)) / T::from_f64(6480.0)).to_f64();
        assert!(inv_err <= hilbert_tol, "{} H₄⁻¹ error {inv_err:e}", T::NAME);

        let a = from_rows::<T>(&[&[2.0, 1.0], &[1.0, 1.0]]);
        let ca = condition_number_1_of(&a).to_f64();
        assert!((ca - 9.0).abs() <= 1e-14, "{ca}");
        // Non-symmetric, so the 1-norm and ∞-norm differ: ‖A‖₁ = 6, A⁻¹ = [[1, −½], [0, ¼]] with
        // ‖A⁻¹‖₁ = 1 (‖A‖∞·‖A⁻¹‖∞ would be 3·1.5).
        let a = from_rows::<T>(&[&[1.0, 2.0], &[0.0, 4.0]]);
        assert_eq!(norm_1(&a), T::from_f64(6.0));
        assert_eq!(condition_number_1_of(&a), T::from_f64(6.0));
        assert_eq!(condition_number_1_of(&a.transpose()), T::from_f64(6.0));
        let scaled_identity = identity::<T>(5) * T::from_f64(3.0);
        assert_eq!(condition_number_1_of(&scaled_identity), T::one());
        let p = from_rows::<T>(&[&[0.0, 1.0], &[1.0, 0.0]]);
        assert_eq!(condition_number_1_of(&p), T::one());
        (diag_err, hilbert_err)
    }

    #[test]
    fn condition_numbers_f64() {
        let (d, h) = check_condition_numbers::<f64>(1e-11);
        eprintln!("f64 cond₁: diag(1,1e-6) rel. error {d:.2e}, Hilbert-4 rel. error {h:.2e}");
    }

    #[test]
    fn condition_numbers_dd() {
        let (d, h) = check_condition_numbers::<Dd>(1e-27);
        eprintln!("dd cond₁: diag(1,1e-6) rel. error {d:.2e}, Hilbert-4 rel. error {h:.2e}");
    }

    #[test]
    fn condition_number_f64_agrees_with_double_double() {
        let mut rng = Rng::new(7);
        for n in [2, 5, 10, 30] {
            let a = rng.matrix::<f64>(n, n);
            let c64 = condition_number_1_of(&a);
            let cdd = condition_number_1_of(&a.map(to_dd)).to_f64();
            // The f64 inverse is accurate to about cond·ε relative.
            let rel = (c64 - cdd).abs() / cdd;
            assert!(rel <= cdd * 1e-14, "n={n}: cond f64 {c64} vs dd {cdd}");
        }
    }

    /// `A P = Q R`, `Qᵀ Q = I`, non-increasing `|R_kk|` and the `Q`/`Qᵀ` products; returns the largest
    /// relative reconstruction error.
    fn check_qr_factor<T: Real>(a: &DMatrix<T>, tol: f64) -> f64 {
        let (m, n) = a.shape();
        let qr = qr_column_pivoted(a);
        let steps = m.min(n);
        let perm = qr.permutation();
        let mut sorted = perm.to_vec();
        sorted.sort_unstable();
        assert_eq!(sorted, (0..n).collect::<Vec<_>>());
        let q = qr.q();
        let r = qr.r();
        assert_eq!(q.shape(), (m, steps));
        assert_eq!(r.shape(), (steps, n));
        let ap = DMatrix::from_fn(m, n, |i, j| a[(i, perm[j])]);
        let scale = max_abs_matrix(a).max(T::one());
        let recon = (max_abs_matrix(&(matmul(&q, &r) - &ap)) / scale).to_f64();
        assert!(recon <= tol, "{} {m}×{n}: ‖QR − AP‖ {recon:e}", T::NAME);
        let orth = max_abs_matrix(&(matmul(&q.transpose(), &q) - identity::<T>(steps))).to_f64();
        assert!(orth <= tol, "{} {m}×{n}: ‖QᵀQ − I‖ {orth:e}", T::NAME);
        let d = qr.r_diagonal();
        assert_eq!(d.len(), steps);
        for k in 1..steps {
            assert!(
                d[k].abs() <= d[k - 1].abs() * T::from_f64(1.0 + 1e-12) + T::from_f64(tol) * scale,
                "{} {m}×{n}: |R_kk| increases at {k}: {:?}",
                T::NAME,
                d.iter().map(|x| x.to_f64()).collect::<Vec<_>>()
            );
        }
        // |R_00| is the largest column norm.
        let largest = (0..n).map(|j| column_norm(a, j, 0)).fold(T::zero(), T::max);
        if steps > 0 {
            assert!((d[0].abs() - largest).abs() <= T::from_f64(tol) * scale);
        }
        // Qᵀ then Q is the identity on vectors; Qᵀ a_{P(0)} = R e_0.
        let mut rng = Rng::new(5);
        let v = rng.vector::<T>(m);
        let mut w = v.clone();
        qr.apply_qt_in_place(&mut w);
        qr.apply_q_in_place(&mut w);
        assert!(max_diff(&v, &w).to_f64() <= tol);
        if steps > 0 {
            let mut col: Vec<T> = a.column(perm[0]).iter().copied().collect();
            qr.apply_qt_in_place(&mut col);
            assert!((col[0] - d[0]).abs().to_f64() <= tol * scale.to_f64());
            assert!(max_abs(&col[1..]).to_f64() <= tol * scale.to_f64());
        }
        recon
    }

    fn check_qr<T: Real>(tol: f64) -> f64 {
        let mut rng = Rng::new(31);
        let mut worst = 0.0f64;
        for (m, n) in [
            (1, 1),
            (1, 4),
            (4, 1),
            (5, 3),
            (3, 5),
            (6, 6),
            (12, 7),
            (7, 12),
            (30, 30),
        ] {
            let a = rng.matrix::<T>(m, n);
            worst = worst.max(check_qr_factor(&a, tol));
            let qr = qr_column_pivoted(&a);
            assert_eq!(qr.rank(1e-12), m.min(n), "random {m}×{n} has full rank");
            assert_eq!((qr.nrows(), qr.ncols()), (m, n));
        }
        // A pivot column that is already almost e₀ (the reflector's sign choice must avoid the
        // cancellation in α − β), and one that is exactly ±e₀ (τ = 0, H = I).
        for first in [1e-7, 1e-20, -1e-20, 0.0] {
            let near_e0 = from_rows::<T>(&[&[1.0, 0.3], &[first, 0.2], &[0.0, 0.1]]);
            worst = worst.max(check_qr_factor(&near_e0, tol));
            let negated = near_e0 * T::from_f64(-1.0);
            worst = worst.max(check_qr_factor(&negated, tol));
        }
        // 5×3 of rank 2: third column = 2·first − second.
        let mut a = rng.matrix::<T>(5, 3);
        for i in 0..5 {
            a[(i, 2)] = T::from_f64(2.0) * a[(i, 0)] - a[(i, 1)];
        }
        worst = worst.max(check_qr_factor(&a, tol));
        let qr = qr_column_pivoted(&a);
        assert_eq!(qr.rank(1e-12), 2);
        assert_eq!(qr.rank(0.5 * tol), 2, "R_22 must be at roundoff level");
        let d = qr.r_diagonal();
        assert!((d[2].abs() / d[0].abs()).to_f64() <= tol);
        // Rank 1 (outer product, wide) and rank 0.
        let u = rng.matrix::<T>(4, 1);
        let v = rng.matrix::<T>(1, 6);
        let outer = matmul(&u, &v);
        worst = worst.max(check_qr_factor(&outer, tol));
        assert_eq!(qr_column_pivoted(&outer).rank(1e-12), 1);
        let zero = DMatrix::<T>::zeros(3, 4);
        check_qr_factor(&zero, tol);
        assert_eq!(qr_column_pivoted(&zero).rank(1e-12), 0);
        assert_eq!(qr_column_pivoted(&DMatrix::<T>::zeros(0, 3)).rank(1e-12), 0);
        // Graded diagonal: the threshold is relative to |R_00|.
        let graded = from_rows::<T>(&[&[1e-8, 0.0, 0.0], &[0.0, 1e-14, 0.0], &[0.0, 0.0, -1.0]]);
        let qr = qr_column_pivoted(&graded);
        assert_eq!(qr.permutation(), &[2, 0, 1]);
        let d: Vec<f64> = qr
            .r_diagonal()
            .into_iter()
            .map(|x| x.to_f64().abs())
            .collect();
        assert_eq!(d, vec![1.0, 1e-8, 1e-14]);
        assert_eq!(qr.rank(1e-16), 3);
        assert_eq!(qr.rank(1e-12), 2);
        assert_eq!(qr.rank(1e-6), 1);
        assert_eq!(qr.rank(1.0), 0);
        // The threshold scales with |R_00|: the same ranks for the matrix scaled up or down.
        for scale in [1e-9, 1e9] {
            let qr = qr_column_pivoted(&(graded.clone() * T::from_f64(scale)));
            assert_eq!(qr.rank(1e-16), 3);
            assert_eq!(qr.rank(1e-12), 2);
            assert_eq!(qr.rank(1e-6), 1);
        }
        worst
    }

    #[test]
    fn qr_column_pivoted_f64() {
        let worst = check_qr::<f64>(1e-14);
        eprintln!("f64 QR: max ‖QR − AP‖/‖A‖ {worst:.2e}");
    }

    #[test]
    fn qr_column_pivoted_dd() {
        let worst = check_qr::<Dd>(1e-29);
        eprintln!("dd QR: max ‖QR − AP‖/‖A‖ {worst:.2e}");
    }

    fn rank_of<T: Real>(a: &DMatrix<T>) -> usize {
        qr_column_pivoted(a).rank(1e-12)
    }

    fn check_independent_rows<T: Real>() {
        // Duplicated, zero and dependent rows.
        let a = from_rows::<T>(&[
            &[1.0, 2.0, 0.0, 1.0],
            &[1.0, 2.0, 0.0, 1.0],
            &[0.0, 0.0, 0.0, 0.0],
            &[0.0, 1.0, 1.0, 0.0],
            &[1.0, 4.0, 2.0, 1.0],
            &[1.0, 0.0, 0.0, 0.0],
        ]);
        let rows = independent_rows(&a, 1e-12);
        assert_eq!(rows.len(), 3, "{rows:?}");
        assert!(rows.windows(2).all(|w| w[0] < w[1]), "sorted: {rows:?}");
        assert!(!rows.contains(&2), "zero row chosen: {rows:?}");
        assert!(
            !(rows.contains(&0) && rows.contains(&1)),
            "duplicates: {rows:?}"
        );
        let sub = DMatrix::from_fn(rows.len(), 4, |i, j| a[(rows[i], j)]);
        assert_eq!(rank_of(&sub), 3);
        assert_eq!(rank_of(&a), 3);

        // Identity rows with duplicates interleaved: ties go to the lower index.
        let e = from_rows::<T>(&[
            &[1.0, 0.0, 0.0],
            &[0.0, 1.0, 0.0],
            &[1.0, 0.0, 0.0],
            &[0.0, 0.0, 1.0],
            &[0.0, 1.0, 0.0],
        ]);
        assert_eq!(independent_rows(&e, 1e-12), vec![0, 1, 3]);
        let twice = from_rows::<T>(&[&[3.0, -1.0, 2.0], &[3.0, -1.0, 2.0]]);
        assert_eq!(independent_rows(&twice, 1e-12), vec![0]);
        assert!(independent_rows(&DMatrix::<T>::zeros(4, 2), 1e-12).is_empty());

        // A random rank-3 8×5 matrix (dependent rows are combinations of others).
        let mut rng = Rng::new(77);
        let b = matmul(&rng.matrix::<T>(8, 3), &rng.matrix::<T>(3, 5));
        let rows = independent_rows(&b, 1e-12);
        assert_eq!(rows.len(), 3);
        let sub = DMatrix::from_fn(3, 5, |i, j| b[(rows[i], j)]);
        assert_eq!(rank_of(&sub), 3);
    }

    #[test]
    fn independent_rows_f64() {
        check_independent_rows::<f64>();
    }

    #[test]
    fn independent_rows_dd() {
        check_independent_rows::<Dd>();
    }

    fn check_independent_columns<T: Real>() {
        // Columns e₀, e₀ + 10⁻³ e₁, e₁: rank 2; {0, 1} is an independent pair but with condition
        // ~10³, pivoting must pick the well-conditioned {1, 2}.
        let a = from_rows::<T>(&[&[1.0, 1.0, 0.0], &[0.0, 1e-3, 1.0], &[0.0, 0.0, 0.0]]);
        assert_eq!(independent_columns(&a, 1e-12), vec![1, 2]);
        // Columns c₀, 3c₀, 0, c₁.
        let mut rng = Rng::new(3);
        let c0 = rng.vector::<T>(5);
        let c1 = rng.vector::<T>(5);
        let b = DMatrix::from_fn(5, 4, |i, j| match j {
            0 => c0[i],
            1 => T::from_f64(3.0) * c0[i],
            2 => T::zero(),
            _ => c1[i],
        });
        let cols = independent_columns(&b, 1e-12);
        assert_eq!(cols.len(), 2);
        assert!(cols.contains(&3) && !cols.contains(&2), "{cols:?}");
        // The largest column (3c₀) is the first pivot, so it is chosen over c₀.
        assert_eq!(cols, vec![1, 3]);
        // Full-rank wide matrix: as many columns as rows.
        let w = rng.matrix::<T>(3, 7);
        let cols = independent_columns(&w, 1e-12);
        assert_eq!(cols.len(), 3);
        let sub = DMatrix::from_fn(3, 3, |i, j| w[(i, cols[j])]);
        assert_eq!(rank_of(&sub), 3);
    }

    #[test]
    fn independent_columns_f64() {
        check_independent_columns::<f64>();
    }

    #[test]
    fn independent_columns_dd() {
        check_independent_columns::<Dd>();
    }

    /// The minimum-norm least-squares solution through the full-rank factorization `A = B C`:
    /// `A⁺ = C⁺ B⁺ = Cᵀ (C Cᵀ)⁻¹ (Bᵀ B)⁻¹ Bᵀ`, computed in double-double by Cholesky.
    fn pinv_via_factors(b: &DMatrix<Dd>, c: &DMatrix<Dd>, rhs: &[Dd]) -> Vec<Dd> {
        let btb = matmul(&b.transpose(), b);
        let cct = matmul(c, &c.transpose());
        let y = solve_spd(&btb, &transpose_matvec(b, rhs)).unwrap();
        let z = solve_spd(&cct, &y).unwrap();
        transpose_matvec(c, &z)
    }

    /// Returns the largest relative error over the least-squares cases.
    fn check_least_squares<T: Real>(tol: f64) -> f64 {
        let mut rng = Rng::new(2024);
        let mut worst = 0.0f64;
        let mut record = |err: f64, what: &str| {
            assert!(
                err <= tol,
                "{} least squares, {what}: error {err:e}",
                T::NAME
            );
            worst = worst.max(err);
        };

        // Overdetermined consistent: recovers the exact solution.
        for (m, n) in [(8, 4), (30, 12), (5, 5)] {
            let a = rng.matrix::<T>(m, n);
            let x_true = rng.vector::<T>(n);
            let b = matvec(&a, &x_true);
            let x = solve_least_squares(&a, &b);
            record(
                (max_diff(&x, &x_true) / max_abs(&x_true)).to_f64(),
                "consistent overdetermined",
            );
        }

        // Overdetermined inconsistent, full rank: the normal equations hold, and it matches the
        // double-double normal-equation solution.
        let a = rng.matrix::<T>(10, 4);
        let b = rng.vector::<T>(10);
        let x = solve_least_squares(&a, &b);
        let r: Vec<T> = matvec(&a, &x)
            .iter()
            .zip(&b)
            .map(|(&p, &q)| p - q)
            .collect();
        let g = transpose_matvec(&a, &r);
        record(
            (max_abs(&g) / (max_abs_matrix(&a) * max_abs(&b))).to_f64(),
            "normal equations",
        );
        let add = a.map(to_dd);
        let bdd: Vec<Dd> = b.iter().map(|&v| to_dd(v)).collect();
        let oracle = solve_spd(
            &matmul(&add.transpose(), &add),
            &transpose_matvec(&add, &bdd),
        )
        .unwrap();
        let xd: Vec<Dd> = x.iter().map(|&v| to_dd(v)).collect();
        record(
            (max_diff(&xd, &oracle) / max_abs(&oracle)).to_f64(),
            "inconsistent overdetermined vs normal equations",
        );

        // Underdetermined full row rank: [1 2 3] x = 14 → x = (1, 2, 3).
        let a = from_rows::<T>(&[&[1.0, 2.0, 3.0]]);
        let x = solve_least_squares(&a, &[T::from_f64(14.0)]);
        let exact: Vec<T> = [1.0, 2.0, 3.0].iter().map(|&v| T::from_f64(v)).collect();
        record(
            (max_diff(&x, &exact) / T::from_f64(3.0)).to_f64(),
            "1×3 min norm",
        );

        // Rank deficient and inconsistent: [[1,1],[1,1]] x ≈ (1, 3) → x = (1, 1).
        let a = from_rows::<T>(&[&[1.0, 1.0], &[1.0, 1.0]]);
        let x = solve_least_squares(&a, &[T::one(), T::from_f64(3.0)]);
        record(max_diff(&x, &[T::one(), T::one()]).to_f64(), "2×2 rank 1");

        // Rank deficient, consistent: columns c₀, c₁, c₀ + c₁ (null space n = (1, 1, −1)/√3), so the
        // minimum-norm solution of A x = A x₀ is x₀ − (n·x₀) n.
        let c = rng.matrix::<T>(4, 2);
        let a = DMatrix::from_fn(4, 3, |i, j| {
            if j < 2 {
                c[(i, j)]
            } else {
                c[(i, 0)] + c[(i, 1)]
            }
        });
        let x0 = vec![T::from_f64(1.0), T::from_f64(-2.0), T::from_f64(0.5)];
        let b = matvec(&a, &x0);
        let x = solve_least_squares(&a, &b);
        let t = (x0[0] + x0[1] - x0[2]) / T::from_f64(3.0);
        let expected = vec![x0[0] - t, x0[1] - t, x0[2] + t];
        record(
            (max_diff(&x, &expected) / max_abs(&expected)).to_f64(),
            "4×3 rank 2 min norm",
        );
        // The plain QR answer (a basic solution) would not be minimal: check x ⟂ null space.
        let along_null = ((x[0] + x[1] - x[2]) / max_abs(&x)).abs().to_f64();
        record(along_null, "orthogonal to null space");

        // Random rank-deficient A = B C of all shapes against the factor-based pseudo-inverse.
        for (m, n, r) in [
            (8, 5, 2),
            (5, 8, 3),
            (6, 6, 4),
            (12, 9, 1),
            (3, 10, 3),
            (30, 20, 7),
        ] {
            let bf = rng.matrix::<T>(m, r);
            let cf = rng.matrix::<T>(r, n);
            let a = matmul(&bf, &cf);
            let rhs = rng.vector::<T>(m);
            let x = solve_least_squares(&a, &rhs);
            let bd = bf.map(to_dd);
            let cd = cf.map(to_dd);
            let rd: Vec<Dd> = rhs.iter().map(|&v| to_dd(v)).collect();
            let oracle = pinv_via_factors(&bd, &cd, &rd);
            let xd: Vec<Dd> = x.iter().map(|&v| to_dd(v)).collect();
            assert_eq!(qr_column_pivoted(&a).rank(1e-12), r);
            record(
                (max_diff(&xd, &oracle) / max_abs(&oracle)).to_f64(),
                &format!("random {m}×{n} rank {r}"),
            );
        }

        // Degenerate shapes.
        assert_eq!(
            solve_least_squares(&DMatrix::<T>::zeros(3, 2), &[T::one(); 3]),
            vec![T::zero(); 2]
        );
        assert!(solve_least_squares(&DMatrix::<T>::zeros(3, 0), &[T::one(); 3]).is_empty());
        assert_eq!(
            solve_least_squares(&DMatrix::<T>::zeros(0, 2), &[]),
            vec![T::zero(); 2]
        );
        worst
    }

    #[test]
    fn least_squares_f64() {
        let worst = check_least_squares::<f64>(1e-12);
        eprintln!("f64 least squares: max relative error {worst:.2e}");
    }

    #[test]
    fn least_squares_dd() {
        let worst = check_least_squares::<Dd>(1e-27);
        eprintln!("dd least squares: max relative error {worst:.2e}");
    }

    #[test]
    fn least_squares_truncates_at_the_given_tolerance() {
        // diag(1, 1e-10): with the default 1e-12 both directions count; with 1e-8 the small one is
        // dropped and its component of the solution is zero.
        let a = from_rows::<f64>(&[&[1.0, 0.0], &[0.0, 1e-10]]);
        let x = solve_least_squares(&a, &[2.0, 3e-10]);
        assert!(
            (x[0] - 2.0).abs() <= 1e-15 && (x[1] - 3.0).abs() <= 1e-6,
            "{x:?}"
        );
        let x = solve_least_squares_with_tol(&a, &[2.0, 3e-10], 1e-8);
        assert_eq!(x, vec![2.0, 0.0]);
    }

    #[test]
    fn select_pivoted_solve_matches_lu_and_bounds_the_condition_number() {
        let mut rng = Rng::new(17);
        for n in 1..=6 {
            for trial in 0..40 {
                let mut a: DMatrix<f64> = rng.matrix(n, n);
                // Some matrices need pivoting from the first step, some are ill-conditioned.
                if trial % 3 == 0 && n > 1 {
                    a[(0, 0)] = 0.0;
                }
                if trial % 5 == 0 && n > 1 {
                    let row: Vec<f64> = (0..n)
                        .map(|j| a[(0, j)] + 1e-9 * rng.signed_unit())
                        .collect();
                    for (j, x) in row.into_iter().enumerate() {
                        a[(n - 1, j)] = x;
                    }
                }
                let b: DMatrix<f64> = rng.matrix(n, 3);
                let mut aug = DMatrix::zeros(n, n + 3);
                aug.view_mut((0, 0), (n, n)).copy_from(&a);
                aug.view_mut((0, n), (n, 3)).copy_from(&b);
                let ratio = solve_pivoted_in_place(&mut aug, n);
                let x = aug.view((0, n), (n, 3)).into_owned();
                let residual = (&a * &x - &b).abs().max();
                let cond = condition_number_1_of(&a);
                assert!(
                    residual <= 1e-14 * cond * (1.0 + x.abs().max()),
                    "n {n} trial {trial}: residual {residual:e}, cond {cond:e}"
                );
                assert!(
                    cond * n as f64 * ratio >= 1.0 - 1e-9,
                    "cond {cond:e} vs ratio {ratio:e}"
                );
                assert!(ratio > 0.0 && ratio <= 1.0);
            }
        }
        // A singular matrix reads as ratio 0; the zero matrix too (not NaN).
        let mut aug = DMatrix::from_row_slice(2, 3, &[1.0, 2.0, 1.0, 2.0, 4.0, 0.0]);
        assert_eq!(solve_pivoted_in_place(&mut aug, 2), 0.0);
        let mut aug = DMatrix::<f64>::zeros(2, 3);
        assert_eq!(solve_pivoted_in_place(&mut aug, 2), 0.0);
        // The same answer in double-double to 1e-25 relative of a well-conditioned system.
        let a: DMatrix<Dd> = DMatrix::from_row_slice(2, 2, &[0.0, 2.0, 3.0, 1.0].map(Dd::from_f64));
        let mut aug = DMatrix::zeros(2, 3);
        aug.view_mut((0, 0), (2, 2)).copy_from(&a);
        aug[(0, 2)] = Dd::from_f64(4.0);
        aug[(1, 2)] = Dd::from_f64(5.0);
        solve_pivoted_in_place(&mut aug, 2);
        // 2 y = 4, 3 x + y = 5 → x = 1, y = 2.
        assert!((aug[(0, 2)] - Dd::from_f64(1.0)).abs().to_f64() < 1e-30);
        assert!((aug[(1, 2)] - Dd::from_f64(2.0)).abs().to_f64() < 1e-30);
    }
}
