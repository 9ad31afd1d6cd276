//! Meshes for the checks: rectilinear (possibly graded) blocks of linear tetrahedra.
#![allow(dead_code, clippy::unwrap_used, clippy::expect_used)]

use glam::Vec3;
use tissue_mesh::TetMesh;

/// A block on the rectilinear lattice `xs × ys × zs` (increasing coordinates, cm), each cell
/// cut into the six Kuhn tetrahedra around one of its diagonals. With `mirrored`, cell
/// `(i, j, k)` is reflected in x, y, z when `i`, `j`, `k` are odd: the diagonals alternate and
/// the mesh is symmetric under reflection about any lattice plane (faces still match, since a
/// reflection in one axis keeps the diagonals of the faces across it). Without it, this is
/// [`tissue_mesh::tet_box`]'s triangulation.
pub fn lattice_block(xs: &[f64], ys: &[f64], zs: &[f64], mirrored: bool) -> TetMesh {
    let (nx, ny, nz) = (xs.len() - 1, ys.len() - 1, zs.len() - 1);
    let mut positions = Vec::with_capacity(xs.len() * ys.len() * zs.len());
    for &z in zs {
        for &y in ys {
            for &x in xs {
                positions.push(Vec3::new(x as f32, y as f32, z as f32));
            }
        }
    }
    let id = |i: usize, j: usize, k: usize| ((k * (ny + 1) + j) * (nx + 1) + i) as u32;
    const ORDERS: [[usize; 3]; 6] = [
        [0, 1, 2],
        [1, 2, 0],
        [2, 0, 1],
        [0, 2, 1],
        [2, 1, 0],
        [1, 0, 2],
    ];
    let mut tets = Vec::with_capacity(6 * nx * ny * nz);
    for k in 0..nz {
        for j in 0..ny {
            for i in 0..nx {
                let flip = if mirrored {
                    [i % 2 == 1, j % 2 == 1, k % 2 == 1]
                } else {
                    [false; 3]
                };
                // Local corner (a, b, c) ∈ {0,1}³ → global vertex, reflected where flipped.
                let corner = |c: [usize; 3]| {
                    let c = [0, 1, 2].map(|ax| if flip[ax] { 1 - c[ax] } else { c[ax] });
                    id(i + c[0], j + c[1], k + c[2])
                };
                for order in ORDERS {
                    let mut c = [0usize; 3];
                    let v0 = corner(c);
                    c[order[0]] = 1;
                    let v1 = corner(c);
                    c[order[1]] = 1;
                    let v2 = corner(c);
                    c[order[2]] = 1;
                    let v3 = corner(c);
                    let p = [v0, v1, v2, v3].map(|v| positions[v as usize].as_dvec3());
                    let six = (p[1] - p[0]).cross(p[2] - p[0]).dot(p[3] - p[0]);
                    tets.push(if six > 0.0 {
                        [v0, v1, v2, v3]
                    } else {
                        [v0, v1, v3, v2]
                    });
                }
            }
        }
    }
    TetMesh::new(positions, tets).expect("a lattice block is a valid mesh")
}

/// `n + 1` equally spaced coordinates from `a` to `b`.
pub fn uniform(a: f64, b: f64, n: usize) -> Vec<f64> {
    (0..=n).map(|i| a + (b - a) * i as f64 / n as f64).collect()
}

/// Coordinates from 0 to at least `length`: steps of `h0` up to `fine` (rounded up to whole
/// steps), then steps growing by `growth` each until `length` is reached (the last coordinate is
/// set to `length` exactly when it overshoots by less than half a step, else kept).
pub fn graded(h0: f64, fine: f64, growth: f64, length: f64) -> Vec<f64> {
    let mut xs = vec![0.0];
    let mut h = h0;
    while *xs.last().unwrap() < fine - 1e-12 {
        xs.push(xs.last().unwrap() + h0);
    }
    while *xs.last().unwrap() < length - 1e-12 {
        h *= growth;
        xs.push(xs.last().unwrap() + h);
    }
    let n = xs.len();
    xs[n - 1] = length.max(xs[n - 2] + 0.5 * h);
    xs
}
