//! Symmetric eigenproblems of the clustered PCA: the full decomposition (faer) and, for wide
//! matrices, the leading eigenpairs alone (subspace iteration).

use super::descending;
use nalgebra::{DMatrix, DVector};

/// A symmetric matrix's eigenvalues and its eigenvectors as the columns of a matrix, by faer
/// on the calling thread (the Cargo.toml says why faer).
pub(super) fn eigen_decomposition(matrix: &DMatrix<f64>) -> (DVector<f64>, DMatrix<f64>) {
    let n = matrix.nrows();
    let eigen = to_faer(matrix).selfadjoint_eigendecomposition(faer::Side::Lower);
    let (values, vectors) = (eigen.s().column_vector(), eigen.u());
    (DVector::from_fn(n, |i, _| values.read(i)), DMatrix::from_fn(n, n, |i, j| vectors.read(i, j)))
}

/// Matrices of PCA wider than this are solved for their leading eigenpairs alone: the full
/// decomposition is cubic in the side (92 % of the 200 s that scale-10's first light-cloud zone,
/// up to 8,748 wide, took to reduce).
pub(super) const LEADING_ONLY_SIDE: usize = 2048;
/// Vectors iterated beyond those asked, and the most rounds of the subspace iteration.
const LEADING_OVERSAMPLING: usize = 8;
const LEADING_ROUNDS: usize = 200;
/// The iteration ends once no asked Ritz value moves by more than this, relative to the largest.
const LEADING_TOLERANCE: f64 = 1e-12;

/// The `k` largest eigenpairs of a symmetric positive semi-definite matrix, by subspace
/// iteration with Rayleigh-Ritz: `k` + 8 vectors, from a fixed start, multiplied by the matrix
/// and orthonormalised until the `k` largest Ritz values settle. Returns the k + 8 Ritz pairs
/// (`ClusterPca::eigenvalues` then holds those: the first k settled, the rest approximate; a
/// variable allocation can give such a cluster at most k + 8 vectors); every pair when k + 8
/// is over a quarter of the side. Products are nalgebra's (one
/// thread), so the bytes do not depend on the thread count.
pub(super) fn leading_eigenpairs(matrix: &DMatrix<f64>, k: usize) -> (DVector<f64>, DMatrix<f64>) {
    let n = matrix.nrows();
    let p = (k + LEADING_OVERSAMPLING).min(n);
    if 4 * p > n {
        // So many vectors that the iteration would cost more than the whole decomposition.
        return eigen_decomposition(matrix);
    }
    let start =
        DMatrix::from_fn(n, p, |i, j| crate::sampling::u32_to_unit(crate::sampling::hash_u32(17, i as u32, j as u32, 0)) as f64 - 0.5);
    let mut basis = orthonormal(start);
    let mut previous = vec![f64::INFINITY; k];
    for _ in 0..LEADING_ROUNDS {
        let image = matrix * &basis;
        let (values, _) = eigen_decomposition(&(basis.transpose() * &image));
        let order = descending(&values);
        let values: Vec<f64> = order.iter().take(k).map(|o| o.0).collect();
        let scale = values.first().copied().unwrap_or(0.0).max(f64::MIN_POSITIVE);
        let settled = values.iter().zip(&previous).all(|(a, b)| (a - b).abs() <= LEADING_TOLERANCE * scale);
        previous = values;
        basis = orthonormal(image);
        if settled {
            break;
        }
    }
    // The Ritz vectors of the last basis: its span is the leading subspace.
    let ritz = eigen_decomposition(&(basis.transpose() * matrix * &basis));
    let order = descending(&ritz.0);
    let vectors = &basis * &ritz.1;
    let kept: Vec<usize> = order.iter().map(|o| o.1).collect();
    (DVector::from_iterator(kept.len(), kept.iter().map(|&i| ritz.0[i])), DMatrix::from_fn(n, kept.len(), |r, c| vectors[(r, kept[c])]))
}

/// The columns of `m` orthonormalised in order (modified Gram-Schmidt, twice for accuracy); a
/// column that vanishes stays zero.
fn orthonormal(mut m: DMatrix<f64>) -> DMatrix<f64> {
    for _ in 0..2 {
        for j in 0..m.ncols() {
            for i in 0..j {
                let d = m.column(i).dot(&m.column(j));
                let previous = m.column(i).clone_owned();
                m.column_mut(j).axpy(-d, &previous, 1.0);
            }
            let norm = m.column(j).norm();
            if norm > 0.0 {
                m.column_mut(j).scale_mut(1.0 / norm);
            }
        }
    }
    m
}

/// A symmetric matrix's eigenvalues, in no order, without its eigenvectors (cheaper).
pub(super) fn symmetric_eigenvalues(matrix: &DMatrix<f64>) -> DVector<f64> {
    DVector::from_vec(to_faer(matrix).selfadjoint_eigenvalues(faer::Side::Lower))
}

fn to_faer(matrix: &DMatrix<f64>) -> faer::Mat<f64> {
    faer::Mat::from_fn(matrix.nrows(), matrix.ncols(), |i, j| matrix[(i, j)])
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The subspace iteration finds the leading eigenpairs the full decomposition does: a
    /// matrix of known, decaying spectrum in a random basis.
    #[test]
    fn the_leading_eigenpairs_are_the_full_decompositions() {
        let n = 300;
        let noise = |i: usize, j: usize| crate::sampling::u32_to_unit(crate::sampling::hash_u32(7, i as u32, j as u32, 0)) as f64 - 0.5;
        let q = orthonormal(DMatrix::from_fn(n, n, noise));
        let spectrum = DVector::from_fn(n, |i, _| 0.8f64.powi(i as i32));
        let matrix = &q * DMatrix::from_diagonal(&spectrum) * q.transpose();
        let (values, vectors) = leading_eigenpairs(&matrix, 8);
        assert_eq!((values.len(), vectors.shape()), (16, (n, 16)), "the asked pairs and eight more");
        for d in 0..8 {
            assert!((values[d] - spectrum[d]).abs() < 1e-9, "eigenvalue {d}: {} against {}", values[d], spectrum[d]);
            let alignment = vectors.column(d).dot(&q.column(d)).abs();
            assert!((alignment - 1.0).abs() < 1e-6, "eigenvector {d}: |cos| {alignment}");
        }
    }
}
