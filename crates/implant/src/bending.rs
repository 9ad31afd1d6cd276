//! The skin's bending stiffness: a discrete-shell hinge energy on layer 1 (Grinspun et al. 2003,
//! "Discrete shells"; the gradient of Tamstorf & Grinspun 2013).
//!
//! For every interior edge `e` of layer 1, shared by the triangles `(x₀, x₁, x₂)` and
//! `(x₁, x₀, x₃)`, with dihedral angle `θ` (0 when flat, signed) and rest angle `θ̄`:
//!
//! `E_e = k_e (θ − θ̄)²`, `k_e = D · |ē|² / (2 (Ā₀ + Ā₁))`, `D = E t³ / (12 (1 − ν²))`
//!
//! with `|ē|`, `Āᵢ` the rest edge length and triangle areas. Summed over a mesh rolled onto a
//! cylinder of radius `R` this is the plate's `½ D / R²` per unit area, on a right-triangle grid
//! and on an equilateral lattice rolled either way (tested, within the missing hinges of the
//! sheet's border; the usual `3|ē|²/(Ā₀ + Ā₁)` weight gives three times it on both). The force is
//! `Fᵢ = −2 k_e (θ − θ̄) ∂θ/∂xᵢ`: conservative, zero for any rigid motion, and nothing in the
//! plane. It gives the mass–spring skin what a membrane lacks: without it, a skin compressed
//! beside an expander folds into pleats one simulation edge wide, so the area gain would depend
//! on the simulation edge.

use glam::Vec3A;

/// `atan2(y, x)` to within 2·10⁻⁶ rad: a minimax polynomial for `atan` on [0, 1] (11th order)
/// with the octant reductions, because `f32::atan2` would dominate the hinges' cost. The rest
/// angle goes through the same function, so a hinge at rest has no force.
fn atan2(y: f32, x: f32) -> f32 {
    const C: [f32; 6] = [
        0.999_977_26,
        -0.332_623_47,
        0.193_543_46,
        -0.116_432_87,
        0.052_653_32,
        -0.011_721_2,
    ];
    let (ax, ay) = (x.abs(), y.abs());
    let (small, large) = if ax < ay { (ax, ay) } else { (ay, ax) };
    if large == 0.0 || !large.is_finite() {
        return y.atan2(x);
    }
    let a = small / large;
    let s = a * a;
    let mut r = a * (C[0] + s * (C[1] + s * (C[2] + s * (C[3] + s * (C[4] + s * C[5])))));
    if ay > ax {
        r = std::f32::consts::FRAC_PI_2 - r;
    }
    if x < 0.0 {
        r = std::f32::consts::PI - r;
    }
    if y < 0.0 {
        -r
    } else {
        r
    }
}

/// One hinge: particles `[x₀, x₁, x₂, x₃]` (the edge, then the two opposite vertices), its rest
/// angle (rad) and stiffness `k_e` (g·cm²/s²).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Hinge {
    pub particles: [u32; 4],
    pub rest: f32,
    pub k: f32,
    /// The least `|nᵢ|²` the force's gradient uses: a quarter of the rest value (see
    /// [`add_forces`]).
    pub floor: [f32; 2],
}

/// The dihedral angle of a hinge and its gradient with respect to `[x₀, x₁, x₂, x₃]`, or `None`
/// for a degenerate hinge (a zero-length edge or a zero-area triangle).
pub(crate) fn angle_and_gradient(x: [Vec3A; 4]) -> Option<(f32, [Vec3A; 4])> {
    angle_and_gradient_floored(x, [0.0, 0.0])
}

/// [`angle_and_gradient`] with the gradient's `|nᵢ|²` (twice each triangle's area, squared)
/// taken as at least `floor`.
fn angle_and_gradient_floored(x: [Vec3A; 4], floor: [f32; 2]) -> Option<(f32, [Vec3A; 4])> {
    let e = x[1] - x[0];
    let n1 = e.cross(x[2] - x[0]);
    let n2 = (x[3] - x[0]).cross(e);
    let le2 = e.length_squared();
    let (a1, a2) = (
        n1.length_squared().max(floor[0]),
        n2.length_squared().max(floor[1]),
    );
    if le2 <= 0.0 || a1 <= 0.0 || a2 <= 0.0 || !(le2 + a1 + a2).is_finite() {
        return None;
    }
    let le = le2.sqrt();
    let inv_le = 1.0 / le;
    let theta = atan2(n1.cross(n2).dot(e) * inv_le, n1.dot(n2));
    // n₁/|n₁|² and n₂/|n₂|², then the edge vertices' weights along them.
    let m1 = n1 * (1.0 / a1);
    let m2 = n2 * (1.0 / a2);
    let g2 = m1 * -le;
    let g3 = m2 * -le;
    let g0 = m1 * (e.dot(x[1] - x[2]) * inv_le) + m2 * (e.dot(x[1] - x[3]) * inv_le);
    let g1 = m1 * (e.dot(x[2] - x[0]) * inv_le) + m2 * (e.dot(x[3] - x[0]) * inv_le);
    Some((theta, [g0, g1, g2, g3]))
}

/// Triangles of a lower shape quality (`4√3·A / Σ ℓ²`, 1 equilateral) carry no hinge.
const MIN_QUALITY: f64 = 0.2;

fn quality(positions: &[glam::Vec3], t: [u32; 3]) -> f64 {
    crate::layers::shape_quality(t.map(|i| positions[i as usize]))
}

/// The hinges of `triangles` over `positions` (its interior edges, each with its two triangles
/// consistently oriented), with stiffness from the plate modulus `d` (g·cm²/s²). `particle`
/// maps a mesh vertex to its particle.
pub(crate) fn hinges(
    positions: &[glam::Vec3],
    triangles: &[[u32; 3]],
    edges: &[[u32; 2]],
    edge_triangles: &[[u32; 2]],
    d: f64,
    particle: impl Fn(u32) -> u32,
) -> Vec<Hinge> {
    let mut out = Vec::new();
    for (&[a, b], &[t0, t1]) in edges.iter().zip(edge_triangles) {
        if t0 == u32::MAX || t1 == u32::MAX {
            continue;
        }
        // Order the edge as triangle t0 runs it: t0 = (x₀, x₁, x₂).
        let tri0 = triangles[t0 as usize];
        let tri1 = triangles[t1 as usize];
        let k0 = tri0.iter().position(|&v| v == a);
        let Some(k0) = k0 else { continue };
        let (x0, x1) = if tri0[(k0 + 1) % 3] == b {
            (a, b)
        } else {
            (b, a)
        };
        let Some(&x2) = tri0.iter().find(|&&v| v != a && v != b) else {
            continue;
        };
        let Some(&x3) = tri1.iter().find(|&&v| v != a && v != b) else {
            continue;
        };
        let p = [x0, x1, x2, x3].map(|v| Vec3A::from(positions[v as usize]));
        let Some((rest, _)) = angle_and_gradient(p) else {
            continue;
        };
        let area = |t: [u32; 3]| {
            let [u, v, w] = t.map(|i| positions[i as usize].as_dvec3());
            0.5 * (v - u).cross(w - u).length()
        };
        // A sliver's hinge (a few degrees from flat, such as the remesher leaves at a seam) would
        // be as stiff as its area is small: its angle says nothing of the surface's bending,
        // and its stiffness set a time step ten times shorter. It has none.
        if quality(positions, tri0) < MIN_QUALITY || quality(positions, tri1) < MIN_QUALITY {
            continue;
        }
        let areas = area(tri0) + area(tri1);
        let edge2 = positions[a as usize]
            .as_dvec3()
            .distance_squared(positions[b as usize].as_dvec3());
        if areas <= 0.0 {
            continue;
        }
        out.push(Hinge {
            particles: [x0, x1, x2, x3].map(&particle),
            rest,
            k: (d * edge2 / (2.0 * areas)) as f32,
            // |n|² = (2A)²; a quarter of it is the triangle at half its rest area.
            floor: [area(tri0).powi(2) as f32, area(tri1).powi(2) as f32],
        });
    }
    out
}

/// Adds every hinge's force `−2 k (θ − θ̄) ∂θ/∂xᵢ` to `force`.
///
/// A triangle squeezed below half its rest area bends with the gradient it would have at half
/// its area: the exact gradient grows as 1/area², and where the remeshed chin of the face scan
/// was squeezed it outran the time step, set at rest, in a slow blow-up. The floor only acts
/// on the way: that run settled to the gain of the exact gradient at half the time step
/// (1.391 against 1.396 cm², with the run's times then at Table 2's).
pub(crate) fn add_forces(hinges: &[Hinge], position: &[Vec3A], force: &mut [Vec3A]) {
    for h in hinges {
        let x = h.particles.map(|i| position[i as usize]);
        let Some((theta, grad)) = angle_and_gradient_floored(x, h.floor) else {
            continue;
        };
        let mut delta = theta - h.rest;
        // The shorter way round (an angle near ±π).
        if delta > std::f32::consts::PI {
            delta -= std::f32::consts::TAU;
        } else if delta < -std::f32::consts::PI {
            delta += std::f32::consts::TAU;
        }
        let s = -2.0 * h.k * delta;
        for (i, g) in h.particles.iter().zip(grad) {
            force[*i as usize] += g * s;
        }
    }
}

/// The hinges' energy `Σ k (θ − θ̄)²` at `position` (g·cm²/s²).
pub(crate) fn energy(hinges: &[Hinge], position: &[Vec3A]) -> f64 {
    hinges
        .iter()
        .filter_map(|h| {
            let (theta, _) = angle_and_gradient(h.particles.map(|i| position[i as usize]))?;
            Some(f64::from(h.k) * f64::from(theta - h.rest).powi(2))
        })
        .sum()
}

/// Each hinge particle's share of the Gershgorin row sum of the hinges' stiffness at rest,
/// `2 k |gᵢ| Σⱼ |gⱼ|` halved as [`tissue_mss::MassSpringSystem::stable_time_step_with`]
/// counts a spring's `k` once per end.
pub(crate) fn row_stiffness(hinges: &[Hinge], position: &[Vec3A]) -> Vec<(u32, f64)> {
    let mut out = Vec::with_capacity(4 * hinges.len());
    for h in hinges {
        let Some((_, grad)) = angle_and_gradient(h.particles.map(|i| position[i as usize])) else {
            continue;
        };
        let total: f64 = grad.iter().map(|g| f64::from(g.length())).sum();
        for (i, g) in h.particles.iter().zip(grad) {
            out.push((*i, f64::from(h.k) * f64::from(g.length()) * total));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_fast_atan2_is_within_two_microradians_everywhere() {
        let mut worst = 0.0f64;
        for k in 0..20_000 {
            let phi = -std::f64::consts::PI + std::f64::consts::TAU * f64::from(k) / 20_000.0;
            for r in [1e-3f64, 1.0, 250.0] {
                let (y, x) = ((r * phi.sin()) as f32, (r * phi.cos()) as f32);
                let exact = f64::from(y).atan2(f64::from(x));
                worst = worst.max((f64::from(atan2(y, x)) - exact).abs());
            }
        }
        assert!(worst < 2e-6, "{worst}");
        assert_eq!(atan2(0.0, 0.0), 0.0);
    }

    #[test]
    fn the_gradient_matches_finite_differences() {
        let x = [
            Vec3A::new(0.0, 0.0, 0.0),
            Vec3A::new(1.0, 0.1, 0.05),
            Vec3A::new(0.4, 0.9, 0.3),
            Vec3A::new(0.6, -0.8, 0.25),
        ];
        let (theta, grad) = angle_and_gradient(x).unwrap();
        assert!(theta.abs() > 0.1);
        let h = 1e-3f32;
        for i in 0..4 {
            for axis in 0..3 {
                let mut plus = x;
                let mut minus = x;
                plus[i][axis] += h;
                minus[i][axis] -= h;
                let fd = (angle_and_gradient(plus).unwrap().0
                    - angle_and_gradient(minus).unwrap().0)
                    / (2.0 * h);
                assert!(
                    (fd - grad[i][axis]).abs() < 2e-3 * (1.0 + fd.abs()),
                    "vertex {i} axis {axis}: {fd} against {}",
                    grad[i][axis]
                );
            }
        }
    }

    /// The energy of `mesh` (flat at rest) rolled onto a cylinder of radius `radius` about an
    /// axis along `y` (`along_x`) or `x`, over the plate's `½ D / R²` per unit area.
    fn rolled_energy_ratio(mesh: &tissue_mesh::TriMesh, radius: f32, along_x: bool) -> f64 {
        let topo = mesh.topology();
        let d = 1.0;
        let hinges = hinges(
            mesh.positions(),
            mesh.triangles(),
            topo.edges(),
            topo.edge_triangles(),
            d,
            |v| v,
        );
        let rolled: Vec<Vec3A> = mesh
            .positions()
            .iter()
            .map(|p| {
                let (u, v) = if along_x { (p.x, p.y) } else { (p.y, p.x) };
                let a = u / radius;
                Vec3A::new(radius * a.sin(), v, radius * a.cos())
            })
            .collect();
        energy(&hinges, &rolled) / (0.5 * d / f64::from(radius * radius) * mesh.area())
    }

    #[test]
    fn a_rolled_sheet_has_the_plates_bending_energy() {
        // A right-triangle grid (4 cm, 0.05 cm edges).
        let grid = tissue_mesh::grid(81, 4.0).unwrap();
        for radius in [3.0, 1.5] {
            let ratio = rolled_energy_ratio(&grid, radius, true);
            assert!((0.97..=1.0).contains(&ratio), "grid, R {radius}: {ratio}");
        }
        // An equilateral lattice (0.07 cm edges), rolled along both of its axes.
        let (cols, rows, h) = (60usize, 60usize, 0.07f32);
        let mut positions = Vec::new();
        for r in 0..rows {
            for c in 0..cols {
                let shift = if r % 2 == 1 { 0.5 * h } else { 0.0 };
                positions.push(glam::Vec3::new(
                    c as f32 * h + shift,
                    r as f32 * h * 0.866_025_4,
                    0.0,
                ));
            }
        }
        let mut triangles = Vec::new();
        for r in 0..rows - 1 {
            for c in 0..cols - 1 {
                let i = (r * cols + c) as u32;
                let (a, b, up, up_b) = (i, i + 1, i + cols as u32, i + cols as u32 + 1);
                if r % 2 == 0 {
                    triangles.extend([[a, b, up], [b, up_b, up]]);
                } else {
                    triangles.extend([[a, up_b, up], [a, b, up_b]]);
                }
            }
        }
        let lattice = tissue_mesh::TriMesh::new(positions, triangles).unwrap();
        for along_x in [true, false] {
            let ratio = rolled_energy_ratio(&lattice, 2.0, along_x);
            assert!(
                (0.96..=1.0).contains(&ratio),
                "lattice, along x {along_x}: {ratio}"
            );
        }
    }

    #[test]
    fn a_flat_hinge_has_angle_zero_and_a_rigid_motion_changes_nothing() {
        let x = [
            Vec3A::new(0.0, 0.0, 0.0),
            Vec3A::new(1.0, 0.0, 0.0),
            Vec3A::new(0.5, 1.0, 0.0),
            Vec3A::new(0.5, -1.0, 0.0),
        ];
        assert!(angle_and_gradient(x).unwrap().0.abs() < 1e-6);
        let bent = [x[0], x[1], x[2], Vec3A::new(0.5, -0.8, 0.6)];
        let (theta, grad) = angle_and_gradient(bent).unwrap();
        let rot = glam::Mat3A::from_axis_angle(glam::Vec3::new(0.3, 0.5, 0.8).normalize(), 1.1);
        let moved = bent.map(|p| rot * p + Vec3A::new(2.0, -1.0, 0.5));
        assert!((angle_and_gradient(moved).unwrap().0 - theta).abs() < 1e-5);
        // The gradient sums to zero (no net force) and has no torque.
        let sum: Vec3A = grad.iter().copied().sum();
        let torque: Vec3A = bent.iter().zip(grad).map(|(p, g)| p.cross(g)).sum();
        assert!(
            sum.length() < 1e-5 && torque.length() < 1e-5,
            "{sum} {torque}"
        );
    }
}
