//! Spectral calculus on symmetric 3×3 tensors, used to build logarithmic strain
//! (ε = ½ ln b) and the finite-strain spatial tangent (de Souza Neto et al. 2008,
//! eq. 14.103).
//!
//! [`Tensor4`] is a full fourth-order tensor stored as a 9×9 matrix with entry
//! `(3*i + j, 3*k + l) = A_ijkl`; see [`idx`].

use nalgebra::{Matrix3, SMatrix, SVector, Vector3};

use crate::ConstitutiveError;

/// Full fourth-order tensor, entry `(3*i + j, 3*k + l) = A_ijkl`.
pub type Tensor4 = SMatrix<f64, 9, 9>;

/// Row/column of the pair `(i, j)` in a [`Tensor4`].
#[inline]
pub const fn idx(i: usize, j: usize) -> usize {
    3 * i + j
}

/// Row-major flattening of a second-order tensor, matching the [`Tensor4`] convention.
#[inline]
pub fn flatten(m: &Matrix3<f64>) -> SVector<f64, 9> {
    SVector::<f64, 9>::from_fn(|r, _| m[(r / 3, r % 3)])
}

/// Inverse of [`flatten`].
#[inline]
pub fn unflatten(v: &SVector<f64, 9>) -> Matrix3<f64> {
    Matrix3::from_fn(|i, j| v[idx(i, j)])
}

/// `A : g`, i.e. `(A:g)_ij = A_ijkl g_kl`.
#[inline]
pub fn contract(a: &Tensor4, g: &Matrix3<f64>) -> Matrix3<f64> {
    unflatten(&(a * flatten(g)))
}

/// Symmetric identity: `I^s_ijkl = ½(δ_ik δ_jl + δ_il δ_jk)`.
pub fn sym_identity() -> Tensor4 {
    Tensor4::from_fn(|r, c| {
        let (i, j, k, l) = (r / 3, r % 3, c / 3, c % 3);
        0.5 * (f64::from(u8::from(i == k && j == l)) + f64::from(u8::from(i == l && j == k)))
    })
}

/// `I ⊗ I`: `δ_ij δ_kl`.
pub fn identity_dyad() -> Tensor4 {
    Tensor4::from_fn(|r, c| f64::from(u8::from(r % 4 == 0 && c % 4 == 0)))
}

/// Isotropic elasticity tensor `λ I⊗I + 2μ I^s`.
pub fn isotropic(lambda: f64, mu: f64) -> Tensor4 {
    // Set the 21 non-zero entries directly: this runs once per point per Newton iteration.
    let mut d = Tensor4::zeros();
    for i in 0..3 {
        for k in 0..3 {
            d[(idx(i, i), idx(k, k))] = lambda;
        }
        d[(idx(i, i), idx(i, i))] += 2.0 * mu;
    }
    for i in 0..3 {
        for j in 0..3 {
            if i != j {
                d[(idx(i, j), idx(i, j))] = mu;
                d[(idx(i, j), idx(j, i))] = mu;
            }
        }
    }
    d
}

/// Eigen-decomposition of a symmetric tensor: `m = Σ_A values[A] n_A ⊗ n_A`, with
/// `n_A = vectors.column(A)` orthonormal.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Spectral {
    pub values: Vector3<f64>,
    pub vectors: Matrix3<f64>,
}

impl Spectral {
    /// `Σ_A f(values[A]) n_A ⊗ n_A`: an isotropic tensor function of the decomposed tensor.
    /// Formed as the sum of the three outer products, entry by entry on and above the
    /// diagonal and mirrored (36 products where N D Nᵀ takes 54): symmetric by construction.
    #[inline]
    pub fn map(&self, f: impl Fn(f64) -> f64) -> Matrix3<f64> {
        let n = &self.vectors;
        let d = self.values.map(f);
        let entry = |i: usize, j: usize| (0..3).map(|a| d[a] * n[(i, a)] * n[(j, a)]).sum::<f64>();
        let (xy, xz, yz) = (entry(0, 1), entry(0, 2), entry(1, 2));
        Matrix3::new(entry(0, 0), xy, xz, xy, entry(1, 1), yz, xz, yz, entry(2, 2))
    }

    /// Smallest eigenvalue.
    pub fn min_value(&self) -> f64 {
        self.values.min()
    }
}

/// Symmetric spectral decomposition. The input is symmetrised first, so round-off
/// asymmetry from products such as `ΔF b ΔFᵀ` is harmless. A plane-strain tensor (no
/// coupling between the plane and z) is decomposed in closed form: z is an eigenvector and
/// the in-plane block has the eigenvalues m ± r, m = (a + c)/2, r = √(((a − c)/2)² + b²);
/// 3D tensors by cyclic Jacobi rotations ([`jacobi_spectral`]).
#[inline]
pub fn spectral(m: &Matrix3<f64>) -> Result<Spectral, ConstitutiveError> {
    crate::check_finite(m, "spectral decomposition input")?;
    let s = (m + m.transpose()) * 0.5;
    if s[(0, 2)] == 0.0 && s[(1, 2)] == 0.0 {
        return Ok(plane_spectral(&s));
    }
    jacobi_spectral(&s)
}

/// Sweeps after which a Jacobi decomposition that has not converged reports the input as
/// garbage: a 3 × 3 converges quadratically, in 3 to 5 sweeps from any start.
const JACOBI_SWEEPS: usize = 50;

/// The spectral decomposition of a symmetric 3 × 3 `s` by cyclic Jacobi rotations (Golub &
/// Van Loan, Matrix Computations, §8.5; the rotation of Rutishauser's form, t = sgn θ /
/// (|θ| + √(θ² + 1)), θ = (s_qq − s_pp)/(2 s_pq), with the update of the off-pair entries
/// through τ = s/(1 + c)). An off-diagonal entry below round-off of both diagonal entries
/// it couples is set to zero, as the QR deflates it. The eigenvectors are a product of
/// rotations, orthonormal to round-off; the eigenvalues have the high relative accuracy of
/// Jacobi's method. For the nearly diagonal b_tr of a small step it takes one or two
/// sweeps, against a Householder reduction and QR iterations for nalgebra's decomposition:
/// the 3D explicit step's stress update spent about 1 200 instructions a point there.
fn jacobi_spectral(s: &Matrix3<f64>) -> Result<Spectral, ConstitutiveError> {
    let mut a = *s;
    let mut v = Matrix3::identity();
    for _ in 0..JACOBI_SWEEPS {
        if a[(0, 1)] == 0.0 && a[(0, 2)] == 0.0 && a[(1, 2)] == 0.0 {
            return Ok(Spectral { values: a.diagonal(), vectors: v });
        }
        for (p, q) in [(0, 1), (0, 2), (1, 2)] {
            jacobi_rotate(&mut a, &mut v, p, q);
        }
    }
    Err(ConstitutiveError::EigenFailed)
}

/// One Jacobi rotation of the symmetric `a` in the (p, q) plane that zeroes a_pq, its
/// vectors accumulated into `v`.
#[inline]
fn jacobi_rotate(a: &mut Matrix3<f64>, v: &mut Matrix3<f64>, p: usize, q: usize) {
    let apq = a[(p, q)];
    if apq == 0.0 {
        return;
    }
    let (app, aqq) = (a[(p, p)], a[(q, q)]);
    let g = 100.0 * apq.abs();
    if app.abs() + g == app.abs() && aqq.abs() + g == aqq.abs() {
        a[(p, q)] = 0.0;
        a[(q, p)] = 0.0;
        return;
    }
    let h = aqq - app;
    let t = if h.abs() + g == h.abs() {
        // θ so large that θ² would overflow: t = 1/(2θ).
        apq / h
    } else {
        jacobi_tangent(0.5 * h / apq)
    };
    let (sn, tau) = jacobi_sine_and_tau(t);
    a[(p, p)] = app - t * apq;
    a[(q, q)] = aqq + t * apq;
    a[(p, q)] = 0.0;
    a[(q, p)] = 0.0;
    let r = 3 - p - q;
    let (arp, arq) = (a[(r, p)], a[(r, q)]);
    a[(r, p)] = arp - sn * (arq + arp * tau);
    a[(r, q)] = arq + sn * (arp - arq * tau);
    a[(p, r)] = a[(r, p)];
    a[(q, r)] = a[(r, q)];
    for k in 0..3 {
        let (vkp, vkq) = (v[(k, p)], v[(k, q)]);
        v[(k, p)] = vkp - sn * (vkq + vkp * tau);
        v[(k, q)] = vkq + sn * (vkp - vkq * tau);
    }
}

/// The rotation's t = sgn θ / (|θ| + √(θ² + 1)). Where θ² + 1 rounds to θ², √(θ² + 1) is
/// |θ| exactly and t is 0.5/|θ| to the last bit: the root is skipped (most rotations of a
/// second sweep, whose angles are below 1e-8).
#[inline]
fn jacobi_tangent(theta: f64) -> f64 {
    let square = theta * theta;
    let t = if square + 1.0 == square { 0.5 / theta.abs() } else { 1.0 / (theta.abs() + (square + 1.0).sqrt()) };
    if theta < 0.0 {
        -t
    } else {
        t
    }
}

/// The rotation's s = t c and τ = s / (1 + c), c = 1/√(t² + 1). Where t² + 1 rounds to 1,
/// c is 1, s is t and τ is t/2, each to the last bit: a root and two divisions skipped.
#[inline]
fn jacobi_sine_and_tau(t: f64) -> (f64, f64) {
    if t * t + 1.0 == 1.0 {
        return (t, 0.5 * t);
    }
    let c = 1.0 / (t * t + 1.0).sqrt();
    let sn = t * c;
    (sn, sn / (1.0 + c))
}

/// The spectral decomposition of a symmetric `s` whose z axis is an eigenvector: the
/// in-plane eigenvector of m + r is (λ₁ − c, b) or (b, λ₁ − a), whichever is the longer
/// (both are exact, the longer is the better conditioned), the other one perpendicular.
#[inline]
fn plane_spectral(s: &Matrix3<f64>) -> Spectral {
    let (a, b, c) = (s[(0, 0)], s[(0, 1)], s[(1, 1)]);
    // An off-diagonal within round-off of the diagonal is zero, as the QR deflates it: a
    // nearly diagonal tensor (a body at rest, a rigid motion) keeps its diagonal exactly,
    // where the closed form would rotate it by an angle set by round-off.
    if b.abs() <= f64::EPSILON * (a.abs() + c.abs()) {
        return Spectral { values: Vector3::new(a, c, s[(2, 2)]), vectors: Matrix3::identity() };
    }
    let (m, half) = (0.5 * (a + c), 0.5 * (a - c));
    let r = hypot(half, b);
    let (x, y) = if half >= 0.0 { (half + r, b) } else { (b, r - half) };
    let norm = hypot(x, y);
    let (x, y) = if norm > 0.0 { (x / norm, y / norm) } else { (1.0, 0.0) };
    Spectral {
        values: Vector3::new(m + r, m - r, s[(2, 2)]),
        vectors: Matrix3::new(x, -y, 0.0, y, x, 0.0, 0.0, 0.0, 1.0),
    }
}

/// √(x² + y²) by the plain formula where its square neither overflows nor underflows to a
/// subnormal (to within an ulp of `f64::hypot`, at a fraction of its cost), by `f64::hypot`
/// elsewhere.
#[inline]
fn hypot(x: f64, y: f64) -> f64 {
    let sq = x * x + y * y;
    if sq.is_finite() && sq >= f64::MIN_POSITIVE {
        sq.sqrt()
    } else {
        x.hypot(y)
    }
}

fn check_spd(s: &Spectral) -> Result<(), ConstitutiveError> {
    let min = s.min_value();
    if min > 0.0 && min.is_finite() {
        Ok(())
    } else {
        Err(ConstitutiveError::NotPositiveDefinite { min_eigenvalue: min })
    }
}

/// Logarithm of a symmetric positive-definite tensor.
pub fn sym_log(b: &Matrix3<f64>) -> Result<Matrix3<f64>, ConstitutiveError> {
    let s = spectral(b)?;
    check_spd(&s)?;
    Ok(s.map(f64::ln))
}

/// Exponential of a symmetric tensor.
pub fn sym_exp(a: &Matrix3<f64>) -> Result<Matrix3<f64>, ConstitutiveError> {
    let s = spectral(a)?;
    let e = s.map(f64::exp);
    crate::check_finite(&e, "sym_exp result")?;
    Ok(e)
}

/// Daleckii–Krein divided difference of ln: `(ln a − ln b)/(a − b)`, `1/a` at `a = b`.
///
/// Written as `2 atanh(d) / (d (a + b))` with `d = (a − b)/(a + b)`, which is symmetric in
/// `(a, b)`; below `|d| = 1e-3` the series `atanh(d)/d = 1 + d²/3 + d⁴/5 + d⁶/7` is exact to
/// ~d⁸/9 ≈ 1e-25, so nearly repeated eigenvalues (including b = I) never divide 0 by 0.
#[inline]
pub fn log_divided_difference(a: f64, b: f64) -> f64 {
    let s = a + b;
    let d = (a - b) / s;
    if d.abs() < 1e-3 {
        let d2 = d * d;
        (2.0 / s) * (1.0 + d2 * (1.0 / 3.0 + d2 * (1.0 / 5.0 + d2 / 7.0)))
    } else {
        (a / b).ln() / (a - b)
    }
}

/// `L_mnpq = ∂(ln b)_mn / ∂b_pq` from an existing decomposition of SPD `b`, symmetrised
/// over `(p, q)` (and hence over `(m, n)`) so that it acts correctly on symmetric increments.
///
/// Daleckii–Krein: `L = Σ_AB θ_AB (n_A⊗n_B)(n_A⊗n_B)`; pairing the (A,B) and (B,A) terms
/// after symmetrisation gives `L = Σ_A θ_AA S_AA⊗S_AA + Σ_{A<B} 2 θ_AB S_AB⊗S_AB`
/// with `S_AB = sym(n_A ⊗ n_B)`, which is six rank-one updates.
pub fn log_derivative_spectral(s: &Spectral) -> Tensor4 {
    let n = &s.vectors;
    let lam = &s.values;
    let mut out = Tensor4::zeros();
    for a in 0..3 {
        for b in a..3 {
            let na = n.column(a);
            let nb = n.column(b);
            let p = na * nb.transpose();
            let sab = flatten(&((p + p.transpose()) * 0.5));
            let mut theta = log_divided_difference(lam[a], lam[b]);
            if a != b {
                theta *= 2.0;
            }
            out += sab * sab.transpose() * theta;
        }
    }
    out
}

/// `L = ∂ ln b / ∂ b` for symmetric positive-definite `b` (see [`log_derivative_spectral`]).
pub fn log_derivative(b: &Matrix3<f64>) -> Result<Tensor4, ConstitutiveError> {
    let s = spectral(b)?;
    check_spd(&s)?;
    Ok(log_derivative_spectral(&s))
}

/// `B_pqkl = δ_pk b_ql + δ_qk b_pl`, so that `B : g = g b + b gᵀ` is the change of
/// `b = F Fᵀ`-type tensors under `δF = g F`.
pub fn b_operator(b: &Matrix3<f64>) -> Tensor4 {
    let mut out = Tensor4::zeros();
    for p in 0..3 {
        for q in 0..3 {
            for l in 0..3 {
                out[(idx(p, q), idx(p, l))] += b[(q, l)];
                out[(idx(p, q), idx(q, l))] += b[(p, l)];
            }
        }
    }
    out
}

/// The unit symmetric directions E_kl = (e_k ⊗ e_l + e_l ⊗ e_k) / 2 for k ≤ l, with their
/// indices: the six directions along which a function of a symmetric tensor is probed.
pub fn symmetric_unit_directions() -> impl Iterator<Item = (usize, usize, Matrix3<f64>)> {
    (0..3).flat_map(|k| {
        (k..3).map(move |l| {
            let mut e = Matrix3::zeros();
            e[(k, l)] += 0.5;
            e[(l, k)] += 0.5;
            (k, l, e)
        })
    })
}

/// Central-difference derivative ∂f/∂x of a tensor function of a symmetric argument,
/// (f(x + h E_kl) − f(x − h E_kl)) / 2h in columns (k, l) and (l, k): the minor-symmetric
/// form that algorithmic tangents take. The reference every tangent test checks against
/// (truncation O(h²), round-off O(ε/h) relative).
pub fn central_difference(mut f: impl FnMut(&Matrix3<f64>) -> Matrix3<f64>, x: &Matrix3<f64>, h: f64) -> Tensor4 {
    let mut out = Tensor4::zeros();
    for (k, l, e) in symmetric_unit_directions() {
        let column = flatten(&((f(&(x + e * h)) - f(&(x - e * h))) / (2.0 * h)));
        out.set_column(idx(k, l), &column);
        out.set_column(idx(l, k), &column);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Rotation3, SymmetricEigen};
    use proptest::prelude::*;

    /// Relative difference in the Frobenius norm (reference `b` is never zero here).
    fn rel(a: &[f64], b: &[f64]) -> f64 {
        let num: f64 = a.iter().zip(b).map(|(x, y)| (x - y).powi(2)).sum::<f64>().sqrt();
        let den: f64 = b.iter().map(|y| y * y).sum::<f64>().sqrt();
        num / den
    }

    fn spd(angles: [f64; 3], lam: [f64; 3]) -> Matrix3<f64> {
        let q = Rotation3::from_scaled_axis(Vector3::from(angles)).into_inner();
        q * Matrix3::from_diagonal(&Vector3::from(lam)) * q.transpose()
    }

    /// Central differences of `sym_log` along symmetric unit directions; step 1e-5 gives
    /// truncation ~h² ≈ 1e-10 and round-off ~ε/h ≈ 1e-11, far below the 1e-6 tolerance.
    fn fd_log_derivative(b: &Matrix3<f64>) -> Tensor4 {
        central_difference(|x| sym_log(x).unwrap(), b, 1e-5)
    }

    #[test]
    fn isotropic_matches_definition() {
        let c = isotropic(1.7, 0.6);
        let expect = identity_dyad() * 1.7 + sym_identity() * 1.2;
        assert!((c - expect).norm() < 1e-15);
    }

    #[test]
    fn isotropic_tensor_entries() {
        let c = isotropic(2.0, 3.0);
        assert_eq!(c[(idx(0, 0), idx(0, 0))], 8.0);
        assert_eq!(c[(idx(0, 0), idx(1, 1))], 2.0);
        assert_eq!(c[(idx(0, 1), idx(0, 1))], 3.0);
        assert_eq!(c[(idx(0, 1), idx(1, 0))], 3.0);
        assert_eq!(c[(idx(0, 1), idx(0, 0))], 0.0);
    }

    #[test]
    fn spectral_reconstructs() {
        let b = spd([0.3, -0.7, 1.1], [0.5, 1.7, 2.9]);
        let s = spectral(&b).unwrap();
        assert!((s.map(|x| x) - b).norm() < 1e-14 * b.norm());
        assert!((s.vectors.transpose() * s.vectors - Matrix3::identity()).norm() < 1e-14);
    }

    /// The 3D Jacobi decomposition against nalgebra's symmetric QR (the reference):
    /// reconstruction and orthonormality to 8 ulp, and the eigenvalues of the QR to 8 ulp of
    /// the tensor's norm (both are backward stable, their eigenvalues within a few ε‖s‖ of
    /// the exact ones).
    fn assert_jacobi_agrees_with_the_qr(m: &Matrix3<f64>) {
        let s = jacobi_spectral(m).unwrap();
        let scale = m.norm();
        assert!((s.map(|x| x) - m).norm() <= 8.0 * f64::EPSILON * scale, "{m}");
        assert!((s.vectors.transpose() * s.vectors - Matrix3::identity()).norm() <= 8.0 * f64::EPSILON);
        let mut ours: Vec<f64> = s.values.iter().copied().collect();
        let mut qr: Vec<f64> = SymmetricEigen::new(*m).eigenvalues.iter().copied().collect();
        ours.sort_by(f64::total_cmp);
        qr.sort_by(f64::total_cmp);
        for (x, y) in ours.iter().zip(&qr) {
            assert!((x - y).abs() <= 8.0 * f64::EPSILON * scale, "{m}: {ours:?} vs {qr:?}");
        }
    }

    /// Rotated tensors with distinct, pairwise equal, all equal, widely spread (10⁻⁸ to
    /// 10³) and nearly equal principal values, a nearly diagonal one (a small step's b_tr)
    /// and an indefinite one (random ones: the property test below).
    #[test]
    fn jacobi_agrees_with_the_qr() {
        for m in [
            spd([0.3, -0.7, 1.1], [0.5, 1.7, 2.9]),
            spd([1.2, 0.4, -0.3], [2.0, 2.0, 0.5]),
            spd([0.1, 0.2, 0.3], [1.0, 1.0, 1.0]),
            spd([-0.5, 0.9, 0.2], [1e-8, 1.0, 1e3]),
            spd([0.7, 0.1, -1.3], [1.0, 1.0 + 1e-12, 1.0 - 1e-12]),
            Matrix3::new(1.0 + 1e-6, 2e-7, -1e-7, 2e-7, 1.0 - 3e-6, 5e-8, -1e-7, 5e-8, 1.0 + 2e-6),
            Matrix3::new(0.3, -1.2, 0.8, -1.2, -0.4, 0.1, 0.8, 0.1, -2.0),
        ] {
            assert_jacobi_agrees_with_the_qr(&m);
        }
    }

    /// The rotation's t, s and τ from the full formulas, roots and all.
    fn full_rotation(theta: f64) -> (f64, f64, f64) {
        let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
        let c = 1.0 / (t * t + 1.0).sqrt();
        (t, t * c, t * c / (1.0 + c))
    }

    /// The shortcuts of small angles give the full formulas' t, s and τ to the last bit: θ
    /// from 1e-3 to 1e150 on both sides of where θ² + 1 rounds to θ² (2^26.5) and t² + 1
    /// rounds to 1, and either sign.
    #[test]
    fn small_angle_shortcuts_are_the_full_formulas() {
        let mut theta = 1e-3;
        while theta < 1e150 {
            for th in [theta, -theta, theta * (1.0 + f64::EPSILON), theta * (1.0 - f64::EPSILON)] {
                let t = jacobi_tangent(th);
                let (sn, tau) = jacobi_sine_and_tau(t);
                let bits = |x: (f64, f64, f64)| [x.0.to_bits(), x.1.to_bits(), x.2.to_bits()];
                assert_eq!(bits((t, sn, tau)), bits(full_rotation(th)), "θ = {th:e}");
            }
            theta *= 1.01;
        }
    }

    /// The plane-strain closed form: reconstruction and orthonormality to round-off, and
    /// the eigenvalues of nalgebra's QR to 4 ulp of the largest, for isotropic, nearly
    /// isotropic, diagonal (either order), strongly stretched and sheared tensors.
    #[test]
    fn plane_spectral_agrees_with_the_qr() {
        let cases = [
            (1.0, 0.0, 1.0, 1.0),
            (1.0 + 1e-13, 3e-14, 1.0, 0.9),
            (2.0, 0.0, 0.5, 1.0),
            (0.5, 0.0, 2.0, 3.0),
            (1e-3, 2e-4, 40.0, 0.7),
            (1.3, -0.45, 0.8, 1.1),
            (0.9, 0.6, 0.9, 1.0),
        ];
        for (a, b, c, z) in cases {
            let m = Matrix3::new(a, b, 0.0, b, c, 0.0, 0.0, 0.0, z);
            let s = spectral(&m).unwrap();
            let scale = m.norm();
            assert!((s.map(|x| x) - m).norm() <= 4.0 * f64::EPSILON * scale, "{m}");
            assert!((s.vectors.transpose() * s.vectors - Matrix3::identity()).norm() <= 4.0 * f64::EPSILON);
            let mut ours: Vec<f64> = s.values.iter().copied().collect();
            let mut qr: Vec<f64> = SymmetricEigen::new(m).eigenvalues.iter().copied().collect();
            ours.sort_by(f64::total_cmp);
            qr.sort_by(f64::total_cmp);
            for (x, y) in ours.iter().zip(&qr) {
                assert!((x - y).abs() <= 4.0 * f64::EPSILON * scale, "{ours:?} vs {qr:?}");
            }
        }
        // A nearly diagonal tensor keeps its diagonal to the last bit, as the QR's does.
        let m = Matrix3::new(1.0 + 3e-16, 1e-17, 0.0, 1e-17, 1.0 - 2e-16, 0.0, 0.0, 0.0, 1.0);
        let s = spectral(&m).unwrap();
        assert_eq!((s.values, s.vectors), (m.diagonal(), Matrix3::identity()));
    }

    #[test]
    fn spectral_rejects_nan() {
        let mut b = Matrix3::identity();
        b[(1, 2)] = f64::NAN;
        assert!(matches!(spectral(&b), Err(ConstitutiveError::NonFinite { .. })));
    }

    #[test]
    fn log_of_diag() {
        let b = Matrix3::from_diagonal(&Vector3::new(2.0, 0.5, 7.0));
        let l = sym_log(&b).unwrap();
        let expect = Matrix3::from_diagonal(&Vector3::new(2f64.ln(), 0.5f64.ln(), 7f64.ln()));
        assert!((l - expect).norm() < 1e-15);
    }

    #[test]
    fn log_rejects_non_spd() {
        let b = Matrix3::from_diagonal(&Vector3::new(1.0, -0.1, 2.0));
        assert!(matches!(sym_log(&b), Err(ConstitutiveError::NotPositiveDefinite { .. })));
        assert!(log_derivative(&b).is_err());
        let z = Matrix3::from_diagonal(&Vector3::new(1.0, 0.0, 2.0));
        assert!(sym_log(&z).is_err());
    }

    #[test]
    fn exp_log_round_trip() {
        let b = spd([0.2, 0.4, -0.9], [0.3, 1.0, 4.0]);
        let back = sym_exp(&sym_log(&b).unwrap()).unwrap();
        assert!((back - b).norm() < 1e-13 * b.norm());
        let a = Matrix3::new(0.1, 0.2, -0.3, 0.2, -0.5, 0.05, -0.3, 0.05, 0.4);
        let back = sym_log(&sym_exp(&a).unwrap()).unwrap();
        assert!((back - a).norm() < 1e-13);
    }

    #[test]
    fn divided_difference_limits_and_continuity() {
        assert_eq!(log_divided_difference(1.0, 1.0), 1.0);
        assert!((log_divided_difference(2.5, 2.5) - 0.4).abs() < 1e-16);
        // Across the series/closed-form switch the two branches must agree to round-off.
        for &r in &[0.999e-3f64, 1.001e-3] {
            let (a, b) = (1.0 + r, 1.0 - r);
            let closed = (a / b).ln() / (a - b);
            assert!((log_divided_difference(a, b) - closed).abs() < 1e-12);
        }
        assert!((log_divided_difference(3.0, 1.0) - 3f64.ln() / 2.0).abs() < 1e-15);
    }

    #[test]
    fn log_derivative_identity_is_sym_identity() {
        let l = log_derivative(&Matrix3::identity()).unwrap();
        assert!(l.iter().all(|v| v.is_finite()));
        assert!((l - sym_identity()).norm() < 1e-15);
        let fd = fd_log_derivative(&Matrix3::identity());
        assert!(rel(l.as_slice(), fd.as_slice()) < 1e-6);
    }

    #[test]
    fn log_derivative_two_equal_eigenvalues() {
        for lam in [[1.3, 1.3, 0.6], [2.0, 0.7, 2.0], [0.9, 0.9, 0.9 * (1.0 + 1e-10)]] {
            let b = spd([0.5, -0.2, 0.8], lam);
            let l = log_derivative(&b).unwrap();
            assert!(l.iter().all(|v| v.is_finite()));
            let fd = fd_log_derivative(&b);
            let r = rel(l.as_slice(), fd.as_slice());
            assert!(r < 1e-6, "lam {lam:?}: rel {r}");
        }
    }

    #[test]
    fn log_derivative_scaled_identity() {
        let b = Matrix3::identity() * 3.7;
        let l = log_derivative(&b).unwrap();
        assert!((l - sym_identity() / 3.7).norm() < 1e-15);
    }

    #[test]
    fn b_operator_action() {
        let b = spd([0.1, 0.2, 0.3], [0.5, 1.0, 2.0]);
        let g = Matrix3::new(0.3, -0.1, 0.7, 0.2, 0.5, -0.4, 0.9, 0.0, -0.2);
        let lhs = contract(&b_operator(&b), &g);
        let rhs = g * b + b * g.transpose();
        assert!((lhs - rhs).norm() < 1e-14);
    }

    proptest! {
        /// Any symmetric tensor with entries in (−1, 1) (see `jacobi_agrees_with_the_qr`).
        #[test]
        fn jacobi_agrees_with_the_qr_for_any_symmetric_tensor(
            d in prop::array::uniform3(-1.0f64..1.0),
            o in prop::array::uniform3(-1.0f64..1.0),
        ) {
            let m = Matrix3::new(d[0], o[0], o[1], o[0], d[1], o[2], o[1], o[2], d[2]);
            assert_jacobi_agrees_with_the_qr(&m);
        }

        #[test]
        fn log_rotation_equivariance(
            a in prop::array::uniform3(-3.0f64..3.0),
            r in prop::array::uniform3(-3.0f64..3.0),
            lam in prop::array::uniform3(0.05f64..20.0),
        ) {
            let b = spd(a, lam);
            let q = Rotation3::from_scaled_axis(Vector3::from(r)).into_inner();
            let lhs = sym_log(&(q * b * q.transpose())).unwrap();
            let rhs = q * sym_log(&b).unwrap() * q.transpose();
            // Round-off of two decompositions and products: a few ulps of |ln λ| ≲ 3.
            prop_assert!((lhs - rhs).norm() < 1e-12);
        }

        #[test]
        fn exp_log_round_trip_random(
            a in prop::array::uniform3(-3.0f64..3.0),
            lam in prop::array::uniform3(0.05f64..20.0),
        ) {
            let b = spd(a, lam);
            let back = sym_exp(&sym_log(&b).unwrap()).unwrap();
            prop_assert!((back - b).norm() < 1e-12 * b.norm());
        }

        #[test]
        fn log_derivative_matches_fd(
            a in prop::array::uniform3(-3.0f64..3.0),
            lam in prop::array::uniform3(0.2f64..5.0),
        ) {
            let b = spd(a, lam);
            let l = log_derivative(&b).unwrap();
            let fd = fd_log_derivative(&b);
            let r = rel(l.as_slice(), fd.as_slice());
            prop_assert!(r < 1e-6, "rel {}", r);
        }
    }
}
