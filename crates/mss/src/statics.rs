//! The building block of a quasi-static solve: a constant stiffness matrix factored once
//! ([`StiffnessBuilder`], [`Preconditioner`]).
//!
//! A static equilibrium `r(x) = 0` (`r` the net force on every free particle) of a mass–spring
//! system is the fixed point of the local/global map of Liu et al. (2013), "Fast simulation of
//! mass-spring systems": `x ← x + P⁻¹ r(x)`, `P = Σₛ kₛ (eₐ − e_b)(eₐ − e_b)ᵀ + …` the springs'
//! Laplacian (plus anchors and whatever else a caller adds). For springs alone this is exactly
//! the projective-dynamics iteration (the local step projects each spring to its rest length,
//! the global step solves with `P`), and `P` does not depend on `x`, so it is factored once
//! (sparse Cholesky, faer) and each application costs one back-substitution of three
//! right-hand sides. It is also a good preconditioner for conjugate gradients on the true
//! Hessian (Newton steps), which is how `tissue-implant`'s quasi-static solver uses it.
//!
//! `P` is scalar (the same for x, y, z): `n × n` for `n` free particles, solved for three
//! columns. Fixed particles have no row. A caller may change the diagonal between iterations
//! ([`Preconditioner::refactor`], e.g. for the stiffness of contacts that come and go); the
//! sparsity pattern, and so the symbolic factorisation, never changes.
//!
//! Everything runs on one thread (faer's `Par::Seq`), so results do not depend on the thread
//! count.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::prelude::Reborrow;
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, LltRef, SymbolicCholesky, SymmetricOrdering,
};
use faer::sparse::{SparseColMat, SymbolicSparseColMat};
use faer::{Conj, Mat, Par, Side};
use glam::DVec3;

use crate::MssError;

const NONE: u32 = u32::MAX;

/// Collects the weights of a constant stiffness matrix over a system's particles (module docs).
#[derive(Debug, Clone)]
pub struct StiffnessBuilder {
    /// Particle → row (`NONE` for a fixed particle).
    rows: Vec<u32>,
    /// Row → particle.
    particles: Vec<u32>,
    /// Lower-triangle entries `(row, col, value)`, row ≥ col, duplicates allowed.
    entries: Vec<(u32, u32, f64)>,
}

impl StiffnessBuilder {
    /// A matrix over `n` particles, of which those `fixed` accepts have no row.
    pub fn new(n: usize, fixed: impl Fn(u32) -> bool) -> Self {
        let mut rows = vec![NONE; n];
        let mut particles = Vec::with_capacity(n);
        for (p, row) in rows.iter_mut().enumerate() {
            if !fixed(p as u32) {
                *row = particles.len() as u32;
                particles.push(p as u32);
            }
        }
        let mut entries = Vec::with_capacity(n * 8);
        // Every free particle has its diagonal, so that a caller can always change it.
        entries.extend((0..particles.len() as u32).map(|r| (r, r, 0.0)));
        StiffnessBuilder {
            rows,
            particles,
            entries,
        }
    }

    fn row(&self, p: u32) -> Option<u32> {
        self.rows.get(p as usize).copied().filter(|&r| r != NONE)
    }

    /// Adds `k·(eₐ − e_b)(eₐ − e_b)ᵀ`: a spring of stiffness `k` (g/s²) between particles `a`
    /// and `b`. A fixed end contributes only the free end's diagonal. Out-of-range particles
    /// are ignored.
    pub fn spring(&mut self, a: u32, b: u32, k: f64) {
        self.coupling(&[a, b], &[1.0, -1.0], k);
    }

    /// Adds `k` to particle `p`'s diagonal (an anchor to a fixed point).
    pub fn diagonal(&mut self, p: u32, k: f64) {
        if let Some(r) = self.row(p) {
            self.entries.push((r, r, k));
        }
    }

    /// Adds `k·c cᵀ` over `particles` (`c[i]` the weight of `particles[i]`): e.g. a bending
    /// hinge's Gauss–Newton stiffness along its gradient.
    pub fn coupling(&mut self, particles: &[u32], c: &[f64], k: f64) {
        if !(k.is_finite() && k > 0.0) {
            return;
        }
        for (i, (&pi, &ci)) in particles.iter().zip(c).enumerate() {
            let Some(ri) = self.row(pi) else { continue };
            for (&pj, &cj) in particles[..=i].iter().zip(c) {
                let Some(rj) = self.row(pj) else { continue };
                let v = k * ci * cj;
                if ri == rj {
                    // Two entries of one particle fold onto its diagonal.
                    let factor = if pi == pj { 1.0 } else { 2.0 };
                    self.entries.push((ri, ri, v * factor));
                } else {
                    self.entries.push((ri.max(rj), ri.min(rj), v));
                }
            }
        }
    }

    /// Assembles and factors the matrix.
    ///
    /// # Errors
    /// [`MssError::NotPositiveDefinite`] when the matrix has no Cholesky factor: a free
    /// particle held by nothing (no spring path to a fixed particle or an anchor).
    pub fn build(mut self) -> Result<Preconditioner, MssError> {
        let _span = tracing::debug_span!("stiffness_factor", rows = self.particles.len()).entered();
        let n = self.particles.len();
        // Column-major lower triangle: sort by (col, row), merge duplicates.
        self.entries
            .sort_unstable_by_key(|&(r, c, _)| (u64::from(c) << 32) | u64::from(r));
        let mut col_ptr = vec![0usize; n + 1];
        let mut row_idx = Vec::with_capacity(self.entries.len());
        let mut values: Vec<f64> = Vec::with_capacity(self.entries.len());
        let mut last = (NONE, NONE);
        for &(r, c, v) in &self.entries {
            if (r, c) == last {
                if let Some(x) = values.last_mut() {
                    *x += v;
                }
                continue;
            }
            last = (r, c);
            row_idx.push(r as usize);
            values.push(v);
            col_ptr[c as usize + 1] += 1;
        }
        for c in 0..n {
            col_ptr[c + 1] += col_ptr[c];
        }
        // The diagonal is each column's first entry (rows sorted, row ≥ col, always present).
        let diagonal_at: Vec<usize> = col_ptr[..n].to_vec();
        let symbolic = SymbolicSparseColMat::new_checked(n, n, col_ptr, None, row_idx);
        let cholesky = factorize_symbolic_cholesky(
            symbolic.rb(),
            Side::Lower,
            SymmetricOrdering::Amd,
            Default::default(),
        )
        .map_err(|e| MssError::NotPositiveDefinite {
            what: format!("symbolic factorisation failed: {e:?}"),
        })?;
        let scratch = cholesky
            .factorize_numeric_llt_scratch::<f64>(Par::Seq, Default::default())
            .or(cholesky.solve_in_place_scratch::<f64>(3, Par::Seq));
        let factor = vec![0.0; cholesky.len_val()];
        let mut pre = Preconditioner {
            rows: self.rows,
            particles: self.particles,
            matrix: SparseColMat::new(symbolic, values.clone()),
            base: values,
            diagonal_at,
            cholesky,
            factor,
            stack: MemBuffer::new(scratch),
            rhs: Mat::zeros(n, 3),
        };
        pre.refactor(&[])?;
        Ok(pre)
    }
}

/// A factored constant stiffness matrix (module docs): `P⁻¹` applied to forces.
pub struct Preconditioner {
    rows: Vec<u32>,
    particles: Vec<u32>,
    matrix: SparseColMat<usize, f64>,
    /// The matrix's values as built, before any extra diagonal.
    base: Vec<f64>,
    diagonal_at: Vec<usize>,
    cholesky: SymbolicCholesky<usize>,
    factor: Vec<f64>,
    stack: MemBuffer,
    rhs: Mat<f64>,
}

impl std::fmt::Debug for Preconditioner {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Preconditioner")
            .field("rows", &self.particles.len())
            .field("nonzeros", &self.base.len())
            .field("factor_nonzeros", &self.factor.len())
            .finish()
    }
}

impl Preconditioner {
    /// The number of rows (free particles).
    pub fn rows(&self) -> usize {
        self.particles.len()
    }

    /// Factors the matrix as built plus `extra` on the diagonal (`(particle, k)`, k ≥ 0; fixed
    /// particles ignored; repeated particles summed).
    ///
    /// # Errors
    /// [`MssError::NotPositiveDefinite`] when it has no Cholesky factor.
    pub fn refactor(&mut self, extra: &[(u32, f64)]) -> Result<(), MssError> {
        let _span = tracing::trace_span!("refactor", extra = extra.len()).entered();
        let values = self.matrix.val_mut();
        values.copy_from_slice(&self.base);
        for &(p, k) in extra {
            if let Some(&r) = self.rows.get(p as usize) {
                if r != NONE && k.is_finite() && k > 0.0 {
                    values[self.diagonal_at[r as usize]] += k;
                }
            }
        }
        let stack = MemStack::new(&mut self.stack);
        self.cholesky
            .factorize_numeric_llt::<f64>(
                &mut self.factor,
                self.matrix.rb(),
                Side::Lower,
                LltRegularization::default(),
                Par::Seq,
                stack,
                Default::default(),
            )
            .map_err(|e| MssError::NotPositiveDefinite {
                what: format!(
                    "{e:?}: a free particle is held by nothing (no spring path to a fixed \
                     particle or an anchor)"
                ),
            })?;
        Ok(())
    }

    /// `out = P·v` per particle with the matrix as built (no extra diagonal): the operator a
    /// conjugate-gradient solve preconditioned by [`Preconditioner::solve`] starts from.
    /// Fixed particles get zero.
    pub fn multiply(&self, v: &[DVec3], out: &mut [DVec3]) {
        out.iter_mut().for_each(|o| *o = DVec3::ZERO);
        let symbolic = self.matrix.symbolic();
        let col_ptr = symbolic.col_ptr();
        let row_idx = symbolic.row_idx();
        let at = |row: usize| {
            v.get(self.particles[row] as usize)
                .copied()
                .unwrap_or(DVec3::ZERO)
        };
        for col in 0..self.particles.len() {
            let vc = at(col);
            let pc = self.particles[col] as usize;
            let range = col_ptr[col]..col_ptr[col + 1];
            for (&row, &a) in row_idx[range.clone()].iter().zip(&self.base[range]) {
                let pr = self.particles[row] as usize;
                if row == col {
                    out[pc] += vc * a;
                } else {
                    out[pr] += vc * a;
                    out[pc] += at(row) * a;
                }
            }
        }
    }

    /// `out = P⁻¹ r` per particle (`r`, `out` one entry per particle of the system; fixed
    /// particles get zero).
    pub fn solve(&mut self, r: &[DVec3], out: &mut [DVec3]) {
        for (row, &p) in self.particles.iter().enumerate() {
            let v = r.get(p as usize).copied().unwrap_or(DVec3::ZERO);
            self.rhs[(row, 0)] = v.x;
            self.rhs[(row, 1)] = v.y;
            self.rhs[(row, 2)] = v.z;
        }
        let stack = MemStack::new(&mut self.stack);
        LltRef::new(&self.cholesky, &self.factor).solve_in_place_with_conj(
            Conj::No,
            self.rhs.as_mut(),
            Par::Seq,
            stack,
        );
        out.iter_mut().for_each(|o| *o = DVec3::ZERO);
        for (row, &p) in self.particles.iter().enumerate() {
            if let Some(o) = out.get_mut(p as usize) {
                *o = DVec3::new(self.rhs[(row, 0)], self.rhs[(row, 1)], self.rhs[(row, 2)]);
            }
        }
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::panic)]
mod tests {
    use super::*;

    /// A chain of springs from a fixed particle 0, pulled at its free end by a force `F`:
    /// every spring carries `F`, so spring `i` stretches by `F/kᵢ` (analytic).
    #[test]
    fn the_global_solve_of_a_spring_chain_under_an_end_load_is_exact() {
        let k = [2.0e4, 5.0e4, 1.0e4, 3.0e4];
        let mut b = StiffnessBuilder::new(5, |p| p == 0);
        for (i, &ki) in k.iter().enumerate() {
            b.spring(i as u32, i as u32 + 1, ki);
        }
        let mut pre = b.build().unwrap();
        let force = 7.0e2;
        let mut r = vec![DVec3::ZERO; 5];
        r[4] = DVec3::new(force, 0.0, -force);
        let mut x = vec![DVec3::ZERO; 5];
        pre.solve(&r, &mut x);
        let mut expected = 0.0;
        for (i, &ki) in k.iter().enumerate() {
            expected += force / ki;
            assert!((x[i + 1].x - expected).abs() < 1e-12 * expected.abs().max(1.0));
            assert!((x[i + 1].z + expected).abs() < 1e-12 * expected.abs().max(1.0));
        }
        assert_eq!(x[0], DVec3::ZERO);
    }

    #[test]
    fn a_free_particle_held_by_nothing_is_refused() {
        let mut b = StiffnessBuilder::new(3, |p| p == 0);
        b.spring(0, 1, 1.0);
        assert!(matches!(
            b.build(),
            Err(MssError::NotPositiveDefinite { .. })
        ));
    }

    #[test]
    fn an_extra_diagonal_acts_as_an_anchor() {
        let mut b = StiffnessBuilder::new(2, |_| false);
        b.spring(0, 1, 1.0);
        b.diagonal(0, 1.0);
        let mut pre = b.build().unwrap();
        pre.refactor(&[(1, 3.0)]).unwrap();
        // [[2, −1], [−1, 4]] x = (1, 0): x = (4/7, 1/7).
        let mut x = vec![DVec3::ZERO; 2];
        pre.solve(&[DVec3::X, DVec3::ZERO], &mut x);
        assert!((x[0].x - 4.0 / 7.0).abs() < 1e-12 && (x[1].x - 1.0 / 7.0).abs() < 1e-12);
    }
}
