//! A dense matrix's inverse by blocked LU with partial pivoting, whose bulk is matrix products
//! (nalgebra's, on matrixmultiply's kernels). nalgebra's `try_inverse` eliminates a column at a
//! time over the whole matrix: on a 169-block level (5,408 feedback coefficients) it was 96 %
//! of the bake (docs/BENCHMARKS.md, "Scale sweep").

use nalgebra::DMatrix;

/// Columns factored together; the rest of the matrix is updated once per block, by a product.
const BLOCK: usize = 64;

/// A^-1 of a square `a`, or None when a pivot is zero (A is singular) or the inverse is not
/// finite. The row exchanges and the order of every sum are fixed by `a` alone.
pub fn inverse(mut a: DMatrix<f64>) -> Option<DMatrix<f64>> {
    let n = a.nrows();
    assert_eq!(n, a.ncols(), "a square matrix");
    let mut order: Vec<usize> = (0..n).collect();
    for start in (0..n).step_by(BLOCK) {
        let width = BLOCK.min(n - start);
        factor_panel(&mut a, start, width, &mut order)?;
        let rest = start + width;
        if rest < n {
            let (factored, right) = a.as_mut_slice().split_at_mut(rest * n);
            right.chunks_mut(n).for_each(|column| solve_unit_lower(factored, n, start, width, column));
            let (l21, u12) =
                (a.view((rest, start), (n - rest, width)).clone_owned(), a.view((start, rest), (width, n - rest)).clone_owned());
            a.view_mut((rest, rest), (n - rest, n - rest)).gemm(-1.0, &l21, &u12, 1.0);
        }
    }
    // P A = L U, so A^-1 = U^-1 L^-1 P: P's row i is the unit row of A's row order[i].
    let mut x = DMatrix::zeros(n, n);
    order.iter().enumerate().for_each(|(i, &o)| x[(i, o)] = 1.0);
    forward(&a, &mut x);
    backward(&a, &mut x);
    x.iter().all(|v| v.is_finite()).then_some(x)
}

/// LU of columns start..start + width, rows from start on, one column at a time, with the
/// largest remaining value of each column as its pivot (whole rows exchanged).
fn factor_panel(a: &mut DMatrix<f64>, start: usize, width: usize, order: &mut [usize]) -> Option<()> {
    let n = a.nrows();
    for j in start..start + width {
        let column = &a.as_slice()[j * n..][..n];
        let pivot_row = (j..n).fold(j, |best, i| if column[i].abs() > column[best].abs() { i } else { best });
        if column[pivot_row] == 0.0 {
            return None;
        }
        if pivot_row != j {
            a.swap_rows(j, pivot_row);
            order.swap(j, pivot_row);
        }
        let values = a.as_mut_slice();
        let pivot = values[j * n + j];
        values[j * n + j + 1..(j + 1) * n].iter_mut().for_each(|v| *v /= pivot);
        for c in j + 1..start + width {
            let u = values[c * n + j];
            if u != 0.0 {
                for i in j + 1..n {
                    values[c * n + i] -= values[j * n + i] * u;
                }
            }
        }
    }
    Some(())
}

/// Rows start..start + width of `column` solved by the unit lower triangle of the diagonal
/// block there of `a` (n rows a column, column-major).
fn solve_unit_lower(a: &[f64], n: usize, start: usize, width: usize, column: &mut [f64]) {
    for j in start..start + width {
        let v = column[j];
        if v != 0.0 {
            (j + 1..start + width).for_each(|i| column[i] -= a[j * n + i] * v);
        }
    }
}

/// X <- L^-1 X, L the unit lower triangle of `a`: block by block, each block's rows solved by
/// its diagonal block, then taken from the rows below by one product.
fn forward(a: &DMatrix<f64>, x: &mut DMatrix<f64>) {
    let n = a.nrows();
    for start in (0..n).step_by(BLOCK) {
        let width = BLOCK.min(n - start);
        x.as_mut_slice().chunks_mut(n).for_each(|column| solve_unit_lower(a.as_slice(), n, start, width, column));
        let rest = start + width;
        if rest < n {
            let (l, solved) = (a.view((rest, start), (n - rest, width)).clone_owned(), x.rows(start, width).clone_owned());
            x.rows_mut(rest, n - rest).gemm(-1.0, &l, &solved, 1.0);
        }
    }
}

/// X <- U^-1 X, U the upper triangle of `a` with its diagonal, from the last block up.
fn backward(a: &DMatrix<f64>, x: &mut DMatrix<f64>) {
    let n = a.nrows();
    let starts: Vec<usize> = (0..n).step_by(BLOCK).collect();
    for &start in starts.iter().rev() {
        let width = BLOCK.min(n - start);
        let u = a.as_slice();
        for column in x.as_mut_slice().chunks_mut(n) {
            for j in (start..start + width).rev() {
                column[j] /= u[j * n + j];
                let v = column[j];
                if v != 0.0 {
                    (start..j).for_each(|i| column[i] -= u[j * n + i] * v);
                }
            }
        }
        if start > 0 {
            let (u, solved) = (a.view((0, start), (start, width)).clone_owned(), x.rows(start, width).clone_owned());
            x.rows_mut(0, start).gemm(-1.0, &u, &solved, 1.0);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A matrix whose first rows need exchanges (a zero and tiny values on the diagonal).
    fn awkward(n: usize) -> DMatrix<f64> {
        let mut state = 7u64;
        let mut m = DMatrix::from_fn(n, n, |_, _| {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        });
        if n >= 3 {
            (0..3).for_each(|i| m[(i, i)] = [0.0, 1e-9, -1e-7][i]);
        }
        m
    }

    #[test]
    fn the_inverse_times_the_matrix_is_the_identity() {
        for n in [1, 2, 5, 63, 64, 65, 130, 200] {
            let a = awkward(n);
            let x = inverse(a.clone()).expect("invertible");
            let residual = (&a * &x - DMatrix::identity(n, n)).amax();
            let theirs = a.clone().try_inverse().unwrap();
            let difference = (&x - &theirs).amax() / theirs.amax();
            assert!(residual < 1e-9 && difference < 1e-9, "n = {n}: |AX - I| = {residual:e}, from nalgebra's {difference:e}");
        }
    }

    #[test]
    fn a_singular_matrix_has_none() {
        assert!(inverse(DMatrix::zeros(66, 66)).is_none());
        let mut rank_one = DMatrix::zeros(3, 3);
        rank_one[(0, 0)] = 1.0;
        assert!(inverse(rank_one).is_none());
    }
}
