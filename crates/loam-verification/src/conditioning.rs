//! Condition numbers of assembled tangents, for the hard cases whose failure mode is
//! conditioning rather than convergence (small cuts, stiffness contrasts). A dense
//! eigen-decomposition: exact and simple, and affordable only on their small models.

use loam_solve::BlockPattern;

/// The 2-norm condition number of a symmetric tangent restricted to its free dofs, by a
/// dense eigen-decomposition: for the small models of the hard-case studies only.
pub fn condition_number(pattern: &BlockPattern, values: &[f64], constrained: &[bool]) -> f64 {
    let n = pattern.num_dofs();
    let free: Vec<usize> = (0..n).filter(|&i| !constrained[i]).collect();
    let mut index = vec![usize::MAX; n];
    for (k, &i) in free.iter().enumerate() {
        index[i] = k;
    }
    let mut k = nalgebra::DMatrix::<f64>::zeros(free.len(), free.len());
    for c in 0..n {
        let entries = pattern.col_ptr()[c]..pattern.col_ptr()[c + 1];
        for (&r, &value) in pattern.row_idx()[entries.clone()].iter().zip(&values[entries]) {
            if index[r] != usize::MAX && index[c] != usize::MAX {
                k[(index[r], index[c])] += value;
            }
        }
    }
    let eigenvalues = k.symmetric_eigen().eigenvalues;
    eigenvalues.iter().fold(0.0f64, |m, v| m.max(v.abs()))
        / eigenvalues.iter().fold(f64::INFINITY, |m, v| m.min(v.abs()))
}
