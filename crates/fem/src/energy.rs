//! The stable neo-Hookean energy density (Smith, de Goes & Kim 2018) and the linear tetrahedron
//! built on it: energy, gradient (12), Hessian (12×12) with an optional positive-semidefinite
//! projection.
//!
//! Storage conventions: `vec F` is column-major, entry `i + 3j` is `F[i][j]` (row `i`, column
//! `j`); a tetrahedron's 12 coordinates are ordered `(node a, axis i) → 3a + i`.

use glam::{DMat3, DVec3};

use crate::material::ElasticMaterial;

/// The stable neo-Hookean energy density with the paper's constants fitted to `(E, ν)`:
///
/// `Ψ(F) = μ'/2 (I_C − 3) + λ'/2 (J − α)² − μ'/2 log(I_C + 1) − Ψ₀`
///
/// with `I_C = tr(FᵀF)`, `J = det F`, `μ' = 4μ/3`, `λ' = λ + 5μ/6`, `α = 1 + 3μ'/(4λ') = 1 +
/// μ/λ'` (μ, λ the Lamé constants of [`ElasticMaterial::lame`]) and the constant `Ψ₀ = λ'/2
/// (1 − α)² − μ'/2 log 4` that makes `Ψ(I) = 0`. `α` makes the rest state stress-free, and the
/// linearisation at `F = I` is Hooke's law `σ = 2μ ε + λ tr(ε) I`. `λ' ≥ 5μ/6 > 0`, so `ν = 0`
/// (`λ = 0`) needs no special case. Units: dyn/cm² (erg/cm³).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StableNeoHookean {
    /// `μ' = 4μ/3`, dyn/cm².
    pub mu: f64,
    /// `λ' = λ + 5μ/6`, dyn/cm².
    pub lambda: f64,
    /// `α = 1 + 3μ'/(4λ')`.
    pub alpha: f64,
    /// `Ψ₀`, the energy density of the raw formula at rest (subtracted).
    pub rest_offset: f64,
}

/// Cofactor matrix `∂J/∂F`: columns `f₁×f₂, f₂×f₀, f₀×f₁`.
#[inline]
fn cofactor(f: &DMat3) -> DMat3 {
    DMat3::from_cols(
        f.y_axis.cross(f.z_axis),
        f.z_axis.cross(f.x_axis),
        f.x_axis.cross(f.y_axis),
    )
}

#[inline]
fn frobenius2(f: &DMat3) -> f64 {
    f.x_axis.length_squared() + f.y_axis.length_squared() + f.z_axis.length_squared()
}

#[inline]
fn vec9(m: &DMat3) -> [f64; 9] {
    m.to_cols_array()
}

impl StableNeoHookean {
    /// The energy fitted to a material (which is assumed valid, see
    /// [`ElasticMaterial::validate`]).
    pub fn new(material: &ElasticMaterial) -> Self {
        let (mu_l, lambda_l) = material.lame();
        let mu = 4.0 / 3.0 * mu_l;
        let lambda = lambda_l + 5.0 / 6.0 * mu_l;
        let alpha = 1.0 + 0.75 * mu / lambda;
        let rest_offset = 0.5 * lambda * (1.0 - alpha).powi(2) - 0.5 * mu * 4.0f64.ln();
        StableNeoHookean {
            mu,
            lambda,
            alpha,
            rest_offset,
        }
    }

    /// `Ψ(F)`, erg/cm³ (zero at `F = I`).
    pub fn energy_density(&self, f: &DMat3) -> f64 {
        let ic = frobenius2(f);
        let j = f.determinant();
        0.5 * self.mu * (ic - 3.0) + 0.5 * self.lambda * (j - self.alpha).powi(2)
            - 0.5 * self.mu * (ic + 1.0).ln()
            - self.rest_offset
    }

    /// The first Piola–Kirchhoff stress `P = ∂Ψ/∂F = μ'(1 − 1/(I_C + 1)) F + λ'(J − α) cof F`,
    /// dyn/cm².
    pub fn first_piola(&self, f: &DMat3) -> DMat3 {
        let ic = frobenius2(f);
        let j = f.determinant();
        *f * (self.mu * (1.0 - 1.0 / (ic + 1.0))) + cofactor(f) * (self.lambda * (j - self.alpha))
    }

    /// The Cauchy stress `σ = P Fᵀ / J`, dyn/cm² (`J ≠ 0`).
    pub fn cauchy(&self, f: &DMat3) -> DMat3 {
        self.first_piola(f) * f.transpose() / f.determinant()
    }

    /// `∂²Ψ/∂F²` on `vec F` (column-major):
    /// `μ'(1 − 1/(I_C+1)) I₉ + 2μ'/(I_C+1)² f fᵀ + λ' g gᵀ + λ'(J − α) ∂²J/∂F²`
    /// with `f = vec F`, `g = vec cof F`.
    pub fn hessian_density(&self, f: &DMat3) -> [[f64; 9]; 9] {
        let ic = frobenius2(f);
        let j = f.determinant();
        let fv = vec9(f);
        let gv = vec9(&cofactor(f));
        let diag = self.mu * (1.0 - 1.0 / (ic + 1.0));
        let ff = 2.0 * self.mu / ((ic + 1.0) * (ic + 1.0));
        let mut h = [[0.0; 9]; 9];
        for r in 0..9 {
            for c in 0..9 {
                h[r][c] = ff * fv[r] * fv[c] + self.lambda * gv[r] * gv[c];
            }
            h[r][r] += diag;
        }
        // ∂²J/∂F²: block (p, q) (columns f_p, f_q) is ε_{pqs}·[f_s]×, with [a]× the cross-product
        // matrix (∂(f₁×f₂)/∂f₂ = [f₁]×, ∂(f₁×f₂)/∂f₁ = −[f₂]×, …).
        let s = self.lambda * (j - self.alpha);
        let cols = [f.x_axis, f.y_axis, f.z_axis];
        let mut add_block = |p: usize, q: usize, a: DVec3, sign: f64| {
            let cross = [[0.0, -a.z, a.y], [a.z, 0.0, -a.x], [-a.y, a.x, 0.0]];
            for (i, row) in cross.iter().enumerate() {
                for (k, &v) in row.iter().enumerate() {
                    h[3 * p + i][3 * q + k] += s * sign * v;
                }
            }
        };
        add_block(0, 1, cols[2], -1.0);
        add_block(0, 2, cols[1], 1.0);
        add_block(1, 0, cols[2], 1.0);
        add_block(1, 2, cols[0], -1.0);
        add_block(2, 0, cols[1], -1.0);
        add_block(2, 1, cols[0], 1.0);
        h
    }
}

/// Eigen-decomposition of a symmetric `N × N` matrix by cyclic Jacobi rotations: on return the
/// diagonal of `a` holds the eigenvalues and the columns of `v` the eigenvectors.
#[allow(clippy::needless_range_loop)] // rotations index rows and columns p, q together
fn jacobi_eigen<const N: usize>(a: &mut [[f64; N]; N], v: &mut [[f64; N]; N]) {
    for (i, row) in v.iter_mut().enumerate() {
        *row = [0.0; N];
        row[i] = 1.0;
    }
    let total: f64 = a.iter().flatten().map(|x| x * x).sum();
    for _sweep in 0..30 {
        let mut off = 0.0;
        for p in 0..N {
            for q in p + 1..N {
                off += a[p][q] * a[p][q];
            }
        }
        if off <= 1e-30 * total || off == 0.0 {
            return;
        }
        for p in 0..N {
            for q in p + 1..N {
                let apq = a[p][q];
                if apq == 0.0 {
                    continue;
                }
                let theta = (a[q][q] - a[p][p]) / (2.0 * apq);
                let t = if theta.is_finite() {
                    theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt())
                } else {
                    0.0
                };
                let c = 1.0 / (t * t + 1.0).sqrt();
                let s = t * c;
                for row in a.iter_mut() {
                    let (akp, akq) = (row[p], row[q]);
                    row[p] = c * akp - s * akq;
                    row[q] = s * akp + c * akq;
                }
                for k in 0..N {
                    let (apk, aqk) = (a[p][k], a[q][k]);
                    a[p][k] = c * apk - s * aqk;
                    a[q][k] = s * apk + c * aqk;
                }
                for row in v.iter_mut() {
                    let (vkp, vkq) = (row[p], row[q]);
                    row[p] = c * vkp - s * vkq;
                    row[q] = s * vkp + c * vkq;
                }
            }
        }
    }
}

/// Replaces a symmetric matrix by its nearest positive-semidefinite one (negative eigenvalues
/// clamped to zero). Returns whether anything was clamped.
pub fn project_psd<const N: usize>(h: &mut [[f64; N]; N]) -> bool {
    let mut a = *h;
    let mut v = [[0.0; N]; N];
    jacobi_eigen(&mut a, &mut v);
    let scale = (0..N).map(|k| a[k][k].abs()).fold(0.0, f64::max);
    if (0..N).all(|k| a[k][k] >= -1e-14 * scale) {
        return false;
    }
    for (r, row) in h.iter_mut().enumerate() {
        for (c, x) in row.iter_mut().enumerate() {
            let mut sum = 0.0;
            for k in 0..N {
                let lambda = a[k][k];
                if lambda > 0.0 {
                    sum += lambda * v[r][k] * v[c][k];
                }
            }
            *x = sum;
        }
    }
    true
}

/// A linear tetrahedron at rest: its volume and the gradients of its four shape functions.
///
/// `F = Σₐ xₐ ⊗ bₐ` (`xₐ` the deformed corners), `bₐ` the rows of `Dₘ⁻¹` for `a = 1, 2, 3`
/// (`Dₘ = [X₁ − X₀, X₂ − X₀, X₃ − X₀]`) and `b₀ = −(b₁ + b₂ + b₃)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TetElement {
    /// Shape-function gradients `bₐ`, 1/cm.
    pub grads: [DVec3; 4],
    /// Rest volume, cm³ (positive).
    pub volume: f64,
}

impl TetElement {
    /// The element of a positively oriented rest tetrahedron; `None` when it is flat or
    /// inverted (`det Dₘ ≤ 0` or not finite).
    pub fn new(rest: [DVec3; 4]) -> Option<Self> {
        let dm = DMat3::from_cols(rest[1] - rest[0], rest[2] - rest[0], rest[3] - rest[0]);
        let det = dm.determinant();
        if !(det.is_finite() && det > 0.0) {
            return None;
        }
        let inv = dm.inverse();
        let (b1, b2, b3) = (inv.row(0), inv.row(1), inv.row(2));
        Some(TetElement {
            grads: [-(b1 + b2 + b3), b1, b2, b3],
            volume: det / 6.0,
        })
    }

    /// The deformation gradient `F = Σₐ xₐ ⊗ bₐ`.
    #[inline]
    pub fn deformation_gradient(&self, x: &[DVec3; 4]) -> DMat3 {
        let b = &self.grads;
        let col = |j: usize| x[0] * b[0][j] + x[1] * b[1][j] + x[2] * b[2][j] + x[3] * b[3][j];
        DMat3::from_cols(col(0), col(1), col(2))
    }

    /// The deformation gradient from the corners' displacements, `F = I + Σₐ uₐ ⊗ bₐ`: the
    /// same as [`TetElement::deformation_gradient`] of `X + u` without the round-off of
    /// subtracting large coordinates (the solver's unknowns are displacements).
    #[inline]
    pub fn displacement_gradient(&self, u: &[DVec3; 4]) -> DMat3 {
        DMat3::IDENTITY + self.deformation_gradient(u)
    }

    /// The element's energy `V Ψ(F)`, erg, at deformed corners `x`.
    #[inline]
    pub fn energy(&self, model: &StableNeoHookean, x: &[DVec3; 4]) -> f64 {
        self.energy_at(model, &self.deformation_gradient(x))
    }

    /// The element's energy `V Ψ(F)`, erg, for a given `F`.
    #[inline]
    pub fn energy_at(&self, model: &StableNeoHookean, f: &DMat3) -> f64 {
        self.volume * model.energy_density(f)
    }

    /// `∂(VΨ)/∂xₐ = V P bₐ`, dyn (the elastic force on corner `a` is its negative).
    pub fn gradient(&self, model: &StableNeoHookean, x: &[DVec3; 4]) -> [DVec3; 4] {
        self.gradient_at(model, &self.deformation_gradient(x))
    }

    /// [`TetElement::gradient`] for a given `F`.
    #[inline]
    pub fn gradient_at(&self, model: &StableNeoHookean, f: &DMat3) -> [DVec3; 4] {
        let p = model.first_piola(f) * self.volume;
        self.grads.map(|b| p * b)
    }

    /// `∂²(VΨ)/∂x²`, 12×12, dyn/cm; with `project` the 9×9 `∂²Ψ/∂F²` is first projected to the
    /// nearest positive-semidefinite matrix (negative eigenvalues clamped to zero), so the
    /// result is positive semidefinite.
    pub fn hessian(
        &self,
        model: &StableNeoHookean,
        x: &[DVec3; 4],
        project: bool,
    ) -> [[f64; 12]; 12] {
        self.hessian_at(model, &self.deformation_gradient(x), project)
    }

    /// [`TetElement::hessian`] for a given `F`.
    pub fn hessian_at(
        &self,
        model: &StableNeoHookean,
        f: &DMat3,
        project: bool,
    ) -> [[f64; 12]; 12] {
        let mut h = model.hessian_density(f);
        if project {
            project_psd(&mut h);
        }
        self.hessian_from_density(&h)
    }

    /// `V Bᵀ H B` with `B = ∂ vec F / ∂x`: entry `(3a+i, 3b+k) = V Σⱼₗ H[i+3j][k+3l] bₐ[j] b_b[l]`.
    pub fn hessian_from_density(&self, h: &[[f64; 9]; 9]) -> [[f64; 12]; 12] {
        let b = &self.grads;
        // t[i+3j][3b+k] = Σₗ H[i+3j][k+3l] b_b[l]
        let mut t = [[0.0; 12]; 9];
        for (r, trow) in t.iter_mut().enumerate() {
            for (nb, bb) in b.iter().enumerate() {
                for k in 0..3 {
                    trow[3 * nb + k] = h[r][k] * bb.x + h[r][k + 3] * bb.y + h[r][k + 6] * bb.z;
                }
            }
        }
        let mut out = [[0.0; 12]; 12];
        for (na, ba) in b.iter().enumerate() {
            for i in 0..3 {
                let row = &mut out[3 * na + i];
                for (c, x) in row.iter_mut().enumerate() {
                    *x = self.volume * (t[i][c] * ba.x + t[i + 3][c] * ba.y + t[i + 6][c] * ba.z);
                }
            }
        }
        out
    }
}
