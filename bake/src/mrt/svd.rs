//! Thin SVDs by the Gram route (as clustered PCA takes them): A^T A (the smaller side)
//! through a symmetric eigensolver, singular values its square roots, U = A V / sigma. The
//! order of every sum is fixed, so the result does not depend on the thread count.

use nalgebra::{DMatrix, DVector, SymmetricEigen};

/// Eigenvalues of the Gram matrix (squared singular values) below this share of the largest
/// are rank deficiency, not signal: singular values below 1e-5 of the largest are dropped.
const RANK_TOLERANCE: f64 = 1e-10;

/// The thin SVD of A (rows x cols, cols <= rows): U (rows x r), sigma (r, descending) and V
/// (cols x r), r the numerical rank.
pub struct Svd {
    pub u: DMatrix<f64>,
    pub sigma: Vec<f64>,
    pub v: DMatrix<f64>,
}

pub fn thin(a: &DMatrix<f64>) -> Svd {
    let gram = a.transpose() * a;
    let eigen = SymmetricEigen::new(gram);
    let mut order: Vec<(f64, usize)> = eigen.eigenvalues.iter().enumerate().map(|(i, &l)| (l.max(0.0).sqrt(), i)).collect();
    order.sort_by(|x, y| y.0.total_cmp(&x.0).then(x.1.cmp(&y.1)));
    let largest = order.first().map_or(0.0, |o| o.0);
    order.retain(|o| o.0 > RANK_TOLERANCE.sqrt() * largest && o.0 > 0.0);
    let v = DMatrix::from_fn(a.ncols(), order.len(), |row, col| eigen.eigenvectors[(row, order[col].1)]);
    let sigma: Vec<f64> = order.iter().map(|o| o.0).collect();
    let u = (a * &v) * DMatrix::from_diagonal(&DVector::from_iterator(sigma.len(), sigma.iter().map(|s| 1.0 / s)));
    Svd { u, sigma, v }
}

/// The matrices (of one row count) side by side.
pub fn side_by_side(blocks: &[DMatrix<f64>]) -> DMatrix<f64> {
    let rows = blocks.first().map_or(0, |b| b.nrows());
    let mut joined = DMatrix::zeros(rows, blocks.iter().map(|b| b.ncols()).sum());
    let mut at = 0;
    for b in blocks {
        joined.columns_mut(at, b.ncols()).copy_from(b);
        at += b.ncols();
    }
    joined
}

/// The number of leading singular values that hold `fraction` of the energy (the sum of
/// their squares), as the paper's Table 2 counts.
pub fn modes_for_energy(sigma: &[f64], fraction: f64) -> usize {
    let total: f64 = sigma.iter().map(|s| s * s).sum();
    let mut held = 0.0;
    for (i, s) in sigma.iter().enumerate() {
        held += s * s;
        if held >= fraction * total {
            return i + 1;
        }
    }
    sigma.len()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_thin_svd_reconstructs_its_matrix_with_orthonormal_factors() {
        let a = DMatrix::from_fn(7, 4, |r, c| ((r * 3 + c * 5) % 7) as f64 - 2.5 + (r == c) as u8 as f64);
        let svd = thin(&a);
        let back = &svd.u * DMatrix::from_diagonal(&DVector::from_vec(svd.sigma.clone())) * svd.v.transpose();
        assert!((back - &a).amax() < 1e-9);
        assert!((svd.u.transpose() * &svd.u - DMatrix::identity(svd.sigma.len(), svd.sigma.len())).amax() < 1e-9);
        assert!(svd.sigma.windows(2).all(|w| w[0] >= w[1]));
        assert_eq!(modes_for_energy(&[3.0, 2.0, 1.0], 0.9), 2);
    }
}
