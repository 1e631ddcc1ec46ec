//! The least-squares solve iDynTree uses for the contact unknowns: Eigen's
//! `ColPivHouseholderQR::solve`. Overdetermined and square systems get the
//! least-squares solution; underdetermined ones the basic solution, in which
//! the unknowns the column pivoting leaves out are exactly zero (not the
//! minimum-norm one a pseudo-inverse would give).

use nalgebra::{DMatrix, DVector};

/// Solves `a x ≈ b`.
pub fn col_piv_qr_solve(a: &DMatrix<f64>, b: &DVector<f64>) -> DVector<f64> {
    let (rows, cols) = a.shape();
    let mut r = a.clone();
    let mut qtb = b.clone();
    let mut perm: Vec<usize> = (0..cols).collect();
    let steps = rows.min(cols);
    let mut rank = 0;
    let max_norm = (0..cols).map(|c| r.column(c).norm()).fold(0.0, f64::max);
    let threshold = f64::EPSILON * steps as f64 * max_norm;
    for k in 0..steps {
        // The column of largest remaining norm leads (the first on ties).
        let norms: Vec<f64> = (k..cols)
            .map(|c| r.view((k, c), (rows - k, 1)).norm())
            .collect();
        let (best, &norm) =
            norms.iter().enumerate().fold(
                (0, &f64::MIN),
                |acc, (i, n)| if *n > *acc.1 { (i, n) } else { acc },
            );
        if norm <= threshold {
            break;
        }
        r.swap_columns(k, k + best);
        perm.swap(k, k + best);
        // Householder reflection zeroing column k below the diagonal.
        let x = r.view((k, k), (rows - k, 1)).into_owned();
        let alpha = if x[0] > 0.0 { -norm } else { norm };
        let mut v = x;
        v[0] -= alpha;
        let vnorm2 = v.norm_squared();
        if vnorm2 > 0.0 {
            for c in k..cols {
                let dot = v.dot(&r.view((k, c), (rows - k, 1)));
                let scale = 2.0 * dot / vnorm2;
                let mut col = r.view_mut((k, c), (rows - k, 1));
                col -= &v * scale;
            }
            let dot = v.dot(&qtb.rows(k, rows - k));
            let scale = 2.0 * dot / vnorm2;
            let mut tail = qtb.rows_mut(k, rows - k);
            tail -= &v * scale;
        }
        rank = k + 1;
    }
    // Back substitution on the leading `rank` pivot columns; the others are 0.
    let mut y = DVector::zeros(cols);
    for i in (0..rank).rev() {
        let mut s = qtb[i];
        for j in i + 1..rank {
            s -= r[(i, j)] * y[j];
        }
        y[i] = s / r[(i, i)];
    }
    let mut x = DVector::zeros(cols);
    for (k, &c) in perm.iter().enumerate() {
        x[c] = y[k];
    }
    x
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn square_and_overdetermined_systems_are_solved_in_least_squares() {
        let a = DMatrix::from_row_slice(3, 2, &[1.0, 0.0, 0.0, 1.0, 1.0, 1.0]);
        let b = DVector::from_row_slice(&[1.0, 2.0, 3.5]);
        let x = col_piv_qr_solve(&a, &b);
        let normal = (a.transpose() * &a).try_inverse().unwrap() * a.transpose() * &b;
        assert!((x - normal).norm() < 1e-12);
    }

    #[test]
    fn underdetermined_systems_get_the_basic_solution() {
        // Column 1 has the largest norm: it alone carries the solution.
        let a = DMatrix::from_row_slice(1, 3, &[1.0, 3.0, 2.0]);
        let x = col_piv_qr_solve(&a, &DVector::from_row_slice(&[6.0]));
        assert!((x - DVector::from_row_slice(&[0.0, 2.0, 0.0])).norm() < 1e-12);
    }

    #[test]
    fn no_unknowns_no_answer() {
        let x = col_piv_qr_solve(&DMatrix::zeros(6, 0), &DVector::from_element(6, 1.0));
        assert_eq!(x.len(), 0);
    }
}
