//! The dome profile: the shape of a membrane inflated over the base, then a cap of height `H`.
//!
//! 1. **Membrane.** `u` solves `−Δu = 1` on the base with `u = 0` on the outline: the
//!    small-deflection shape of a membrane under uniform tension and pressure (Prandtl's stress
//!    function). It is solved with linear finite elements on the dome grid in plan (cotangent
//!    stiffness, lumped load) by Jacobi-preconditioned conjugate gradients. For a disc of radius
//!    `R`, `u = (R² − r²)/4`; for a long strip of width `W`, `u = (W²/4 − y²)/2`, flat along the
//!    strip. [`normalised_membrane`] returns `ũ = u / max u ∈ (0, 1]`.
//! 2. **Cap.** The dome height over a point is `z = cap(H, R, ũ)` ([`cap_height`]), with `R` the
//!    base's half-width (half its smaller dimension). On a round base, `1 − ũ = (r/R)²`, and the
//!    dome is exactly the spherical cap of height `H` over the base while `H ≤ R` (the shape of
//!    an inflated membrane of uniform tension, a surface of constant mean curvature) and the
//!    half-spheroid `z = H·√(1 − r²/R²)` beyond (a hemisphere at `H = R`, where both agree; a
//!    taller cap would overhang its base). For small `H` the cap tends to `H·ũ`, the linear
//!    membrane itself.

/// `ũ = u / max u` at every vertex for the membrane equation `−Δu = 1` on the triangles
/// `triangles` (counter-clockwise in plan), with `u = 0` at the vertices where `free` is false.
///
/// # Errors
/// A message when the discrete problem is not positive definite, the solver does not converge,
/// or some free vertex gets `u ≤ 0` (a grid too distorted for the shape).
pub(crate) fn normalised_membrane(
    xy: &[[f64; 2]],
    triangles: &[[u32; 3]],
    free: &[bool],
) -> Result<Vec<f64>, String> {
    let nv = xy.len();
    // Per triangle, the stiffness weight of each edge (opposite corner k): cot(angle at k)/2.
    let mut weights = Vec::with_capacity(triangles.len());
    let mut load = vec![0.0; nv];
    let mut diagonal = vec![0.0; nv];
    for tri in triangles {
        let p = tri.map(|i| xy[i as usize]);
        let doubled =
            (p[1][0] - p[0][0]) * (p[2][1] - p[0][1]) - (p[1][1] - p[0][1]) * (p[2][0] - p[0][0]);
        if !is_positive(doubled) {
            return Err(format!("triangle {tri:?} is not counter-clockwise in plan"));
        }
        let mut w = [0.0; 3];
        for (k, wk) in w.iter_mut().enumerate() {
            let (i, j) = ((k + 1) % 3, (k + 2) % 3);
            let e1 = [p[i][0] - p[k][0], p[i][1] - p[k][1]];
            let e2 = [p[j][0] - p[k][0], p[j][1] - p[k][1]];
            // cot = dot / |cross| and |cross| = doubled area; the weight is cot/2.
            *wk = 0.5 * (e1[0] * e2[0] + e1[1] * e2[1]) / doubled;
        }
        for (k, &wk) in w.iter().enumerate() {
            let (i, j) = (tri[(k + 1) % 3] as usize, tri[(k + 2) % 3] as usize);
            diagonal[i] += wk;
            diagonal[j] += wk;
        }
        for &i in tri {
            if free[i as usize] {
                load[i as usize] += doubled / 6.0;
            }
        }
        weights.push(w);
    }
    if let Some(v) = (0..nv).find(|&v| free[v] && !is_positive(diagonal[v])) {
        return Err(format!("vertex {v} has a non-positive stiffness"));
    }
    // y = K x over the free vertices (x is zero on the fixed ones).
    let apply = |x: &[f64], y: &mut [f64]| {
        y.iter_mut().for_each(|v| *v = 0.0);
        for (tri, w) in triangles.iter().zip(&weights) {
            for (k, &wk) in w.iter().enumerate() {
                let (i, j) = (tri[(k + 1) % 3] as usize, tri[(k + 2) % 3] as usize);
                let d = wk * (x[i] - x[j]);
                y[i] += d;
                y[j] -= d;
            }
        }
        for (v, yv) in y.iter_mut().enumerate() {
            if !free[v] {
                *yv = 0.0;
            }
        }
    };
    let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
    let precondition = |r: &[f64], z: &mut [f64]| {
        for v in 0..nv {
            z[v] = if free[v] { r[v] / diagonal[v] } else { 0.0 };
        }
    };
    let mut u = vec![0.0; nv];
    let mut r = load.clone();
    let mut z = vec![0.0; nv];
    precondition(&r, &mut z);
    let mut d = z.clone();
    let mut kd = vec![0.0; nv];
    let mut rz = dot(&r, &z);
    let stop = 1e-12 * dot(&load, &load).sqrt();
    let max_iterations = 4 * nv + 100;
    let mut converged = false;
    for _ in 0..max_iterations {
        if dot(&r, &r).sqrt() <= stop {
            converged = true;
            break;
        }
        apply(&d, &mut kd);
        let dkd = dot(&d, &kd);
        if !is_positive(dkd) {
            return Err("the membrane stiffness is not positive definite".into());
        }
        let alpha = rz / dkd;
        for v in 0..nv {
            u[v] += alpha * d[v];
            r[v] -= alpha * kd[v];
        }
        precondition(&r, &mut z);
        let rz_next = dot(&r, &z);
        let beta = rz_next / rz;
        rz = rz_next;
        for v in 0..nv {
            d[v] = z[v] + beta * d[v];
        }
    }
    if !converged {
        return Err(format!(
            "the membrane solve did not converge in {max_iterations} iterations"
        ));
    }
    if let Some(v) = (0..nv).find(|&v| free[v] && !is_positive(u[v])) {
        return Err(format!(
            "the membrane deflection at vertex {v} is {:e}, not positive",
            u[v]
        ));
    }
    let peak = u.iter().copied().fold(0.0, f64::max);
    Ok(u.iter().map(|&x| x / peak).collect())
}

/// `x > 0`, false for NaN.
fn is_positive(x: f64) -> bool {
    x > 0.0
}

/// Dome height over a point of normalised membrane deflection `u ∈ [0, 1]`, for a dome of
/// height `h` over a base of half-width `half_width` (module docs, step 2): `0` at `u = 0`, `h`
/// at `u = 1`, increasing in both `u` and `h`.
///
/// With `R = half_width`: for `h ≥ R`, `h·√u`; for `h < R`, the spherical cap
/// `√(ρ² − R²(1 − u)) − (ρ − h)` with `ρ = (R² + h²)/(2h)`, evaluated as
/// `h − R²(1 − u) / (√(ρ² − R²(1 − u)) + ρ)` to keep its precision for flat caps.
pub(crate) fn cap_height(h: f64, half_width: f64, u: f64) -> f64 {
    if h >= half_width {
        return h * u.sqrt();
    }
    let rho = (half_width * half_width + h * h) / (2.0 * h);
    let a = half_width * half_width * (1.0 - u);
    h - a / ((rho * rho - a).max(0.0).sqrt() + rho)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shape::outline::{circle, Grid};

    #[test]
    fn membrane_on_a_disc_matches_the_paraboloid() {
        let radius = 3.5;
        let grid = Grid::new(&circle(radius, 64), 16, None);
        let free: Vec<bool> = (0..grid.xy.len() as u32)
            .map(|v| v >= grid.dome_start)
            .collect();
        let u =
            normalised_membrane(&grid.xy, &grid.triangles[..grid.dome_triangles], &free).unwrap();
        let start = grid.dome_start as usize;
        for (v, (&[x, y], &u)) in grid.xy.iter().zip(&u).enumerate().skip(start) {
            let exact = 1.0 - (x * x + y * y) / (radius * radius);
            assert!((u - exact).abs() < 0.01, "vertex {v}: {u} vs {exact}");
        }
    }

    #[test]
    fn cap_height_is_continuous_and_has_the_right_limits() {
        let r = 3.5;
        for u in [0.0, 0.1, 0.5, 0.9, 1.0] {
            // Continuous at h = R (hemisphere), exact at the ends, linear for flat caps.
            assert!((cap_height(r * (1.0 - 1e-12), r, u) - cap_height(r, r, u)).abs() < 1e-9);
            assert!(cap_height(2.0, r, 0.0).abs() < 1e-12);
            assert!((cap_height(2.0, r, 1.0) - 2.0).abs() < 1e-12);
            assert!((cap_height(1e-6, r, u) - 1e-6 * u).abs() < 1e-15);
        }
        // The spherical cap of height 2 over radius 3.5 at r = 2.
        let rho = (r * r + 4.0) / 4.0;
        let exact = (rho * rho - 4.0f64).sqrt() - (rho - 2.0);
        assert!((cap_height(2.0, r, 1.0 - 4.0 / (r * r)) - exact).abs() < 1e-12);
    }
}
