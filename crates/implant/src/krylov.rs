//! Restarted GMRES with right preconditioning on vectors of `DVec3` (Saad & Schultz 1986):
//! the quasi-static solver's linear solve, whose Jacobian is not symmetric (the slab's shear is
//! taken across layer 2's current normal, which turns with layer 2's neighbours).
//!
//! It solves `A x = b` for `x = M⁻¹ y`, minimising `‖b − A M⁻¹ y‖` over a Krylov space of at
//! most [`Gmres::restart`] vectors, restarted until the residual has fallen by the requested
//! factor or the iteration limit is reached. The workspace is allocated once and reused.

use glam::DVec3;

/// GMRES's workspace: the Krylov basis, the Hessenberg matrix in Givens-rotated form.
pub(crate) struct Gmres {
    restart: usize,
    basis: Vec<Vec<DVec3>>,
    /// Column-major `(restart + 1) × restart`.
    h: Vec<f64>,
    cs: Vec<f64>,
    sn: Vec<f64>,
    g: Vec<f64>,
    y: Vec<f64>,
    w: Vec<DVec3>,
    z: Vec<DVec3>,
}

fn dot(a: &[DVec3], b: &[DVec3]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x.dot(*y)).sum()
}

impl Gmres {
    /// A workspace for vectors of `n` entries and a Krylov space of `restart` vectors.
    pub(crate) fn new(n: usize, restart: usize) -> Self {
        let restart = restart.max(1);
        Gmres {
            restart,
            basis: (0..=restart).map(|_| vec![DVec3::ZERO; n]).collect(),
            h: vec![0.0; (restart + 1) * restart],
            cs: vec![0.0; restart],
            sn: vec![0.0; restart],
            g: vec![0.0; restart + 1],
            y: vec![0.0; restart],
            w: vec![DVec3::ZERO; n],
            z: vec![DVec3::ZERO; n],
        }
    }

    /// `x ≈ A⁻¹ b` from `x = 0`, until `‖b − A x‖ ≤ forcing·‖b‖` or `max_iterations`
    /// applications of `A`. Returns the iterations and the final relative residual.
    pub(crate) fn solve(
        &mut self,
        mut apply: impl FnMut(&[DVec3], &mut [DVec3]),
        mut precondition: impl FnMut(&[DVec3], &mut [DVec3]),
        b: &[DVec3],
        x: &mut [DVec3],
        forcing: f64,
        max_iterations: u32,
    ) -> (u32, f64) {
        let m = self.restart;
        let rows = m + 1;
        x.iter_mut().for_each(|v| *v = DVec3::ZERO);
        let b_norm = dot(b, b).sqrt();
        if b_norm == 0.0 || !b_norm.is_finite() {
            return (0, 0.0);
        }
        let target = forcing * b_norm;
        let mut iterations = 0u32;
        // r₀ = b (x = 0).
        self.basis[0].copy_from_slice(b);
        let mut beta = b_norm;
        loop {
            let inv = 1.0 / beta;
            self.basis[0].iter_mut().for_each(|v| *v *= inv);
            self.g.iter_mut().for_each(|g| *g = 0.0);
            self.g[0] = beta;
            let mut k = 0;
            while k < m && iterations < max_iterations {
                precondition(&self.basis[k], &mut self.z);
                apply(&self.z, &mut self.w);
                iterations += 1;
                // Modified Gram–Schmidt.
                for i in 0..=k {
                    let hik = dot(&self.w, &self.basis[i]);
                    self.h[k * rows + i] = hik;
                    for (w, v) in self.w.iter_mut().zip(&self.basis[i]) {
                        *w -= *v * hik;
                    }
                }
                let norm = dot(&self.w, &self.w).sqrt();
                self.h[k * rows + k + 1] = norm;
                if norm > 0.0 {
                    let inv = 1.0 / norm;
                    let (w, next) = (&self.w, &mut self.basis[k + 1]);
                    for (n, w) in next.iter_mut().zip(w) {
                        *n = *w * inv;
                    }
                }
                // The earlier rotations on the new column, then a new one to zero h[k+1][k].
                for i in 0..k {
                    let (a, b) = (self.h[k * rows + i], self.h[k * rows + i + 1]);
                    self.h[k * rows + i] = self.cs[i] * a + self.sn[i] * b;
                    self.h[k * rows + i + 1] = -self.sn[i] * a + self.cs[i] * b;
                }
                let (a, b) = (self.h[k * rows + k], self.h[k * rows + k + 1]);
                let r = a.hypot(b);
                let (c, s) = if r > 0.0 { (a / r, b / r) } else { (1.0, 0.0) };
                self.cs[k] = c;
                self.sn[k] = s;
                self.h[k * rows + k] = r;
                self.h[k * rows + k + 1] = 0.0;
                self.g[k + 1] = -s * self.g[k];
                self.g[k] *= c;
                k += 1;
                if self.g[k].abs() <= target || norm == 0.0 {
                    break;
                }
            }
            // y = R⁻¹ g, x += M⁻¹ V y.
            for i in (0..k).rev() {
                let mut sum = self.g[i];
                for j in i + 1..k {
                    sum -= self.h[j * rows + i] * self.y[j];
                }
                let d = self.h[i * rows + i];
                self.y[i] = if d != 0.0 { sum / d } else { 0.0 };
            }
            self.w.iter_mut().for_each(|v| *v = DVec3::ZERO);
            for (j, &yj) in self.y[..k].iter().enumerate() {
                for (w, v) in self.w.iter_mut().zip(&self.basis[j]) {
                    *w += *v * yj;
                }
            }
            precondition(&self.w, &mut self.z);
            for (x, z) in x.iter_mut().zip(&self.z) {
                *x += *z;
            }
            let estimate = self.g[k].abs();
            if estimate <= target || iterations >= max_iterations || k == 0 {
                return (iterations, estimate / b_norm);
            }
            // Restart from the true residual r = b − A x.
            apply(x, &mut self.w);
            for ((r, b), w) in self.basis[0].iter_mut().zip(b).zip(&self.w) {
                *r = *b - *w;
            }
            beta = dot(&self.basis[0], &self.basis[0]).sqrt();
            if beta <= target {
                return (iterations, beta / b_norm);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;

    /// A non-symmetric, diagonally dominant tridiagonal system against its exact solution.
    #[test]
    fn solves_a_nonsymmetric_system() {
        let n = 200;
        let apply = |v: &[DVec3], out: &mut [DVec3]| {
            for i in 0..n {
                let mut o = v[i] * 4.0;
                if i > 0 {
                    o -= v[i - 1] * 1.5;
                }
                if i + 1 < n {
                    o -= v[i + 1] * 0.5;
                }
                out[i] = o;
            }
        };
        let exact: Vec<DVec3> = (0..n)
            .map(|i| DVec3::new(i as f64, (i as f64).sin(), 1.0))
            .collect();
        let mut b = vec![DVec3::ZERO; n];
        apply(&exact, &mut b);
        let mut x = vec![DVec3::ZERO; n];
        let mut gmres = Gmres::new(n, 8);
        // A Jacobi preconditioner, to exercise the right-preconditioned path and restarts.
        let (its, rel) = gmres.solve(
            apply,
            |v, out| out.iter_mut().zip(v).for_each(|(o, v)| *o = *v / 4.0),
            &b,
            &mut x,
            1e-12,
            500,
        );
        assert!(rel <= 1e-12, "relative residual {rel} after {its}");
        assert!(its > 8, "a restart was exercised ({its} iterations)");
        let err = x
            .iter()
            .zip(&exact)
            .map(|(a, b)| (*a - *b).length())
            .fold(0.0, f64::max);
        assert!(err < 1e-9, "error {err}");
    }
}
