//! Deterministic mesh generators: the plane, sphere and cube of the thesis's test runs, a disc for
//! region tests, and a box of tetrahedra for the PBD trainer.
//!
//! Every generator validates its parameters ([`MeshError::InvalidParameter`] for a count below
//! its minimum, a non-finite or non-positive size, or more than `u32::MAX − 1` vertices), computes
//! positions in `f64` and rounds them to `f32` once, and returns the result of the validating
//! constructor. Given the same arguments they return bit-identical meshes on a given platform
//! (the sphere and disc use `f64::sin`/`cos` from the platform's math library, which may differ in
//! the last bit between platforms; the grid, cube and box use only `+ − × ÷`, which are
//! correctly rounded everywhere).
//!
//! Lattice coordinates are `side · (2i − m)/(2m)` for `i = 0..=m`: exactly `±side/2` at the
//! ends and mirror-symmetric about 0, so a mesh centred at the origin is exactly symmetric.
//!
//! Units are those of the sizes given (cm in tissue).

use glam::Vec3;

use crate::{MeshError, TetMesh, TriMesh};

fn invalid(what: String) -> MeshError {
    MeshError::InvalidParameter { what }
}

fn at_least(name: &str, value: u32, min: u32) -> Result<usize, MeshError> {
    if value < min {
        return Err(invalid(format!("{name} = {value}, must be at least {min}")));
    }
    Ok(value as usize)
}

fn positive(name: &str, value: f32) -> Result<f64, MeshError> {
    if !(value.is_finite() && value > 0.0) {
        return Err(invalid(format!(
            "{name} = {value}, must be finite and positive"
        )));
    }
    Ok(f64::from(value))
}

/// Checks that `count` (computed with overflow checks) is a possible vertex count.
fn vertex_count(what: &str, count: Option<u64>) -> Result<usize, MeshError> {
    match count {
        Some(c) if c < u64::from(u32::MAX) => usize::try_from(c)
            .map_err(|_| invalid(format!("{what}: {c} vertices do not fit in memory"))),
        _ => Err(invalid(format!(
            "{what}: too many vertices (a mesh holds fewer than 2^32 - 1)"
        ))),
    }
}

/// Lattice coordinate `side · (2i − m)/(2m)`: `−side/2` at `i = 0`, `+side/2` at `i = m`,
/// mirror-symmetric.
fn lattice(i: usize, m: usize, side: f64) -> f64 {
    side * ((2 * i as i64 - m as i64) as f64 / (2 * m) as f64)
}

/// The two triangles of a quad `v00 v10 v11 v01` (counter-clockwise seen from its normal), split
/// along `v00–v11` when `even`, else along `v10–v01`.
fn split_quad(v00: u32, v10: u32, v11: u32, v01: u32, even: bool) -> [[u32; 3]; 2] {
    if even {
        [[v00, v10, v11], [v00, v11, v01]]
    } else {
        [[v00, v10, v01], [v10, v11, v01]]
    }
}

/// A square plane of `n × n` vertices spanning `side` × `side`, centred at the origin in `z = 0`,
/// normals `+z` (triangles counter-clockwise seen from `+z`).
///
/// Vertex `row · n + col` is at `x = side · (2·col − (n−1)) / (2(n−1))`, and `y` likewise from
/// `row`: `x` grows with `col`, `y` with `row`. There are `2(n − 1)²` triangles: cell `(row, col)`
/// is split along the diagonal from its `(row, col)` corner to its `(row+1, col+1)` corner when
/// `row + col` is even, and along the other diagonal when odd. The checkerboard of diagonals makes
/// every other vertex a centre of eight springs (a "union jack" pattern), so a spring network on
/// the grid has no preferred diagonal direction, unlike a grid with all diagonals parallel.
///
/// `grid(65, L)`: 4225 vertices, 8192 triangles; `grid(129, L)`: 16641 / 32768;
/// `grid(257, L)`: 66049 / 131072 (the thesis's plane-press runs).
///
/// # Errors
/// [`MeshError::InvalidParameter`] when `n < 2` or too large, or `side` is not finite and positive.
pub fn grid(n: u32, side: f32) -> Result<TriMesh, MeshError> {
    let n = at_least("grid: n", n, 2)?;
    let side = positive("grid: side", side)?;
    let count = vertex_count("grid", (n as u64).checked_mul(n as u64))?;
    let m = n - 1;
    let coords: Vec<f64> = (0..n).map(|i| lattice(i, m, side)).collect();
    let mut positions = Vec::with_capacity(count);
    for &y in &coords {
        for &x in &coords {
            positions.push(Vec3::new(x as f32, y as f32, 0.0));
        }
    }
    let mut triangles = Vec::with_capacity(2 * m * m);
    let n32 = n as u32;
    for row in 0..m as u32 {
        for col in 0..m as u32 {
            let v00 = row * n32 + col;
            triangles.extend(split_quad(
                v00,
                v00 + 1,
                v00 + n32 + 1,
                v00 + n32,
                (row + col) % 2 == 0,
            ));
        }
    }
    TriMesh::new(positions, triangles)
}

/// A UV sphere of radius `radius` centred at the origin, normals outward.
///
/// Vertex order: vertex 0 is the north pole `(0, 0, r)`; then `rings` latitude circles from north
/// to south, ring `i = 1..=rings` at polar angle `θ_i = π·i/(rings + 1)`, each of `segments`
/// vertices at azimuth `φ_j = 2π·j/segments` (`j = 0..segments`, counter-clockwise seen from
/// `+z`): vertex `1 + (i−1)·segments + j` is `r·(sin θ_i cos φ_j, sin θ_i sin φ_j, cos θ_i)`; the
/// last vertex is the south pole `(0, 0, −r)`. So `rings·segments + 2` vertices and
/// `2·rings·segments` triangles (north cap fan, bands from north to south, south cap fan).
///
/// `uv_sphere(32, 31, r)`: 994 vertices, 1984 triangles (the thesis's pressing sphere);
/// `uv_sphere(12, 11, r)`: 134 / 264 (the thesis's 3.9 cm³ sphere has `r = 1`).
///
/// # Errors
/// [`MeshError::InvalidParameter`] when `segments < 3`, `rings < 1`, the mesh is too large, or
/// `radius` is not finite and positive.
pub fn uv_sphere(segments: u32, rings: u32, radius: f32) -> Result<TriMesh, MeshError> {
    let segments = at_least("uv_sphere: segments", segments, 3)?;
    let rings = at_least("uv_sphere: rings", rings, 1)?;
    let r = positive("uv_sphere: radius", radius)?;
    let count = vertex_count(
        "uv_sphere",
        (segments as u64)
            .checked_mul(rings as u64)
            .and_then(|c| c.checked_add(2)),
    )?;
    let mut positions = Vec::with_capacity(count);
    positions.push(Vec3::new(0.0, 0.0, radius));
    let azimuths: Vec<(f64, f64)> = (0..segments)
        .map(|j| {
            let phi = std::f64::consts::TAU * j as f64 / segments as f64;
            (phi.cos(), phi.sin())
        })
        .collect();
    for i in 1..=rings {
        let theta = std::f64::consts::PI * i as f64 / (rings + 1) as f64;
        let (s, c) = (r * theta.sin(), r * theta.cos());
        for &(cos_phi, sin_phi) in &azimuths {
            positions.push(Vec3::new(
                (s * cos_phi) as f32,
                (s * sin_phi) as f32,
                c as f32,
            ));
        }
    }
    positions.push(Vec3::new(0.0, 0.0, -radius));

    let (seg, rings32) = (segments as u32, rings as u32);
    let south = (count - 1) as u32;
    let ring = |i: u32, j: u32| 1 + (i - 1) * seg + j % seg;
    let mut triangles = Vec::with_capacity(2 * rings * segments);
    for j in 0..seg {
        triangles.push([0, ring(1, j), ring(1, j + 1)]);
    }
    for i in 1..rings32 {
        for j in 0..seg {
            let (a, b) = (ring(i, j), ring(i, j + 1));
            let (c, d) = (ring(i + 1, j), ring(i + 1, j + 1));
            triangles.push([a, c, d]);
            triangles.push([a, d, b]);
        }
    }
    for j in 0..seg {
        triangles.push([south, ring(rings32, j + 1), ring(rings32, j)]);
    }
    TriMesh::new(positions, triangles)
}

/// The closed surface of an axis-aligned cube of edge `side` centred at the origin, each face a
/// `per_edge × per_edge` grid of squares split into two triangles (diagonals in the same
/// checkerboard as [`grid`]), vertices shared between faces welded, normals outward.
///
/// Vertices lie on the lattice `side · (2i − per_edge)/(2·per_edge)` on each axis and are ordered
/// by `z` index, then `y` index, then `x` index (each increasing). `6·per_edge² + 2` vertices and
/// `12·per_edge²` triangles: `subdivided_cube(8, 2.0)` has 386 vertices and 768 triangles and
/// encloses 8 cm³ (the thesis's volume-preservation test cube).
///
/// # Errors
/// [`MeshError::InvalidParameter`] when `per_edge < 1` or too large, or `side` is not finite and
/// positive.
pub fn subdivided_cube(per_edge: u32, side: f32) -> Result<TriMesh, MeshError> {
    let per_edge = at_least("subdivided_cube: per_edge", per_edge, 1)?;
    let side = positive("subdivided_cube: side", side)?;
    let p = per_edge;
    // Lattice indices are packed 21 bits per axis; 6·p² + 2 < 2^32 already needs p < 26755.
    vertex_count(
        "subdivided_cube",
        (p as u64)
            .checked_mul(p as u64)
            .and_then(|c| c.checked_mul(6))
            .and_then(|c| c.checked_add(2)),
    )?;
    let key = |l: [usize; 3]| ((l[2] as u64) << 42) | ((l[1] as u64) << 21) | l[0] as u64;
    // Faces as (fixed axis, fixed index, u axis, v axis) with u × v the outward normal.
    let faces: [(usize, usize, usize, usize); 6] = [
        (0, p, 1, 2), // +x: y × z = x
        (0, 0, 2, 1), // −x: z × y = −x
        (1, p, 2, 0), // +y: z × x = y
        (1, 0, 0, 2), // −y: x × z = −y
        (2, p, 0, 1), // +z: x × y = z
        (2, 0, 1, 0), // −z: y × x = −z
    ];
    let lattice_point = |(axis, fixed, u, v): (usize, usize, usize, usize), a: usize, b: usize| {
        let mut l = [0usize; 3];
        l[axis] = fixed;
        l[u] = a;
        l[v] = b;
        l
    };
    let mut keys: Vec<u64> = Vec::with_capacity(6 * (p + 1) * (p + 1));
    for &face in &faces {
        for b in 0..=p {
            for a in 0..=p {
                keys.push(key(lattice_point(face, a, b)));
            }
        }
    }
    keys.sort_unstable();
    keys.dedup(); // 6p² + 2 keys: the lattice points on the surface
    let index = |l: [usize; 3]| keys.partition_point(|&k| k < key(l)) as u32;
    let coords: Vec<f32> = (0..=p).map(|i| lattice(i, p, side) as f32).collect();
    let mask = (1u64 << 21) - 1;
    let positions: Vec<Vec3> = keys
        .iter()
        .map(|&k| {
            Vec3::new(
                coords[(k & mask) as usize],
                coords[((k >> 21) & mask) as usize],
                coords[(k >> 42) as usize],
            )
        })
        .collect();
    let mut triangles = Vec::with_capacity(12 * p * p);
    for &face in &faces {
        for b in 0..p {
            for a in 0..p {
                let v = |da: usize, db: usize| index(lattice_point(face, a + da, b + db));
                triangles.extend(split_quad(
                    v(0, 0),
                    v(1, 0),
                    v(1, 1),
                    v(0, 1),
                    (a + b) % 2 == 0,
                ));
            }
        }
    }
    TriMesh::new(positions, triangles)
}

/// A flat disc of radius `radius` in `z = 0`, centred at the origin, normal `+z`.
///
/// Vertex 0 is the centre; ring `i = 1..=radial` at distance `radius·i/radial` holds `segments`
/// vertices at azimuth `2π·j/segments` (counter-clockwise seen from `+z`): vertex
/// `1 + (i−1)·segments + j`. The outer ring is the boundary; its polygon has area
/// `(segments/2)·radius²·sin(2π/segments)`. `1 + radial·segments` vertices and
/// `segments·(2·radial − 1)` triangles (the centre fan, then bands outward, each quad split along
/// the diagonal from its inner `j` vertex to its outer `j + 1` vertex).
///
/// # Errors
/// [`MeshError::InvalidParameter`] when `radial < 1`, `segments < 3`, the mesh is too large, or
/// `radius` is not finite and positive.
pub fn disc(radial: u32, segments: u32, radius: f32) -> Result<TriMesh, MeshError> {
    let radial = at_least("disc: radial", radial, 1)?;
    let segments = at_least("disc: segments", segments, 3)?;
    let r = positive("disc: radius", radius)?;
    let count = vertex_count(
        "disc",
        (radial as u64)
            .checked_mul(segments as u64)
            .and_then(|c| c.checked_add(1)),
    )?;
    let azimuths: Vec<(f64, f64)> = (0..segments)
        .map(|j| {
            let phi = std::f64::consts::TAU * j as f64 / segments as f64;
            (phi.cos(), phi.sin())
        })
        .collect();
    let mut positions = Vec::with_capacity(count);
    positions.push(Vec3::ZERO);
    for i in 1..=radial {
        let rho = r * i as f64 / radial as f64;
        for &(c, s) in &azimuths {
            positions.push(Vec3::new((rho * c) as f32, (rho * s) as f32, 0.0));
        }
    }
    let seg = segments as u32;
    let ring = |i: u32, j: u32| 1 + (i - 1) * seg + j % seg;
    let mut triangles = Vec::with_capacity(segments * (2 * radial - 1));
    for j in 0..seg {
        triangles.push([0, ring(1, j), ring(1, j + 1)]);
    }
    for i in 1..radial as u32 {
        for j in 0..seg {
            let (a, b) = (ring(i, j), ring(i, j + 1));
            let (c, d) = (ring(i + 1, j), ring(i + 1, j + 1));
            triangles.push([a, c, d]);
            triangles.push([a, d, b]);
        }
    }
    TriMesh::new(positions, triangles)
}

/// A box of `nx × ny × nz` cells spanning `size`, centred at the origin, each cell split into six
/// positively oriented tetrahedra.
///
/// Vertex `(k·(ny+1) + j)·(nx+1) + i` is at the lattice point `(i, j, k)`, with `x =
/// size.x·(2i − nx)/(2nx)` and likewise `y`, `z`. Each cell is cut by the Kuhn (Freudenthal)
/// triangulation: the six tetrahedra `v000 → v000 + e_a → v000 + e_a + e_b → v111` for the six
/// orders `(a, b, c)` of the axes, all sharing the cell's main diagonal `v000–v111`. The split is
/// the same in every cell, so the faces of neighbouring cells match. Tetrahedra of odd axis orders
/// store their last two vertices swapped so that every one has `(b−a)×(c−a)·(d−a) > 0`; each has
/// volume `cell volume / 6`. `(nx+1)(ny+1)(nz+1)` vertices, `6·nx·ny·nz` tetrahedra.
///
/// # Errors
/// [`MeshError::InvalidParameter`] when a count is 0, the mesh is too large, or a component of
/// `size` is not finite and positive.
pub fn tet_box(nx: u32, ny: u32, nz: u32, size: Vec3) -> Result<TetMesh, MeshError> {
    let nx = at_least("tet_box: nx", nx, 1)?;
    let ny = at_least("tet_box: ny", ny, 1)?;
    let nz = at_least("tet_box: nz", nz, 1)?;
    let sx = positive("tet_box: size.x", size.x)?;
    let sy = positive("tet_box: size.y", size.y)?;
    let sz = positive("tet_box: size.z", size.z)?;
    let count = vertex_count(
        "tet_box",
        (nx as u64 + 1)
            .checked_mul(ny as u64 + 1)
            .and_then(|c| c.checked_mul(nz as u64 + 1)),
    )?;
    let xs: Vec<f32> = (0..=nx).map(|i| lattice(i, nx, sx) as f32).collect();
    let ys: Vec<f32> = (0..=ny).map(|j| lattice(j, ny, sy) as f32).collect();
    let zs: Vec<f32> = (0..=nz).map(|k| lattice(k, nz, sz) as f32).collect();
    let mut positions = Vec::with_capacity(count);
    for &z in &zs {
        for &y in &ys {
            for &x in &xs {
                positions.push(Vec3::new(x, y, z));
            }
        }
    }
    let strides = [1u32, nx as u32 + 1, (nx as u32 + 1) * (ny as u32 + 1)];
    // The six axis orders; the odd ones (positions 3..6) get their last two vertices swapped.
    const ORDERS: [[usize; 3]; 6] = [
        [0, 1, 2],
        [1, 2, 0],
        [2, 0, 1],
        [0, 2, 1],
        [2, 1, 0],
        [1, 0, 2],
    ];
    let mut tets = Vec::with_capacity(6 * nx * ny * nz);
    for k in 0..nz as u32 {
        for j in 0..ny as u32 {
            for i in 0..nx as u32 {
                let v000 = i * strides[0] + j * strides[1] + k * strides[2];
                for (o, order) in ORDERS.iter().enumerate() {
                    let v1 = v000 + strides[order[0]];
                    let v2 = v1 + strides[order[1]];
                    let v3 = v2 + strides[order[2]];
                    tets.push(if o < 3 {
                        [v000, v1, v2, v3]
                    } else {
                        [v000, v1, v3, v2]
                    });
                }
            }
        }
    }
    TetMesh::new(positions, tets)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lattice_is_exact_at_the_ends_and_symmetric() {
        for m in [1, 2, 7, 64, 256] {
            for side in [1.0, 2.0, 20.0, 0.3] {
                assert_eq!(lattice(0, m, side), -side / 2.0);
                assert_eq!(lattice(m, m, side), side / 2.0);
                for i in 0..=m {
                    assert_eq!(lattice(i, m, side), -lattice(m - i, m, side));
                }
            }
        }
    }

    #[test]
    fn bad_parameters_are_errors_not_panics() {
        let bad = |r: Result<TriMesh, MeshError>| {
            assert!(
                matches!(r, Err(MeshError::InvalidParameter { .. })),
                "{r:?}"
            )
        };
        bad(grid(1, 1.0));
        bad(grid(0, 1.0));
        bad(grid(3, 0.0));
        bad(grid(3, -1.0));
        bad(grid(3, f32::NAN));
        bad(grid(3, f32::INFINITY));
        bad(grid(u32::MAX, 1.0));
        bad(grid(70_000, 1.0)); // 4.9e9 vertices
        bad(uv_sphere(2, 3, 1.0));
        bad(uv_sphere(3, 0, 1.0));
        bad(uv_sphere(8, 8, f32::NAN));
        bad(uv_sphere(u32::MAX, u32::MAX, 1.0));
        bad(subdivided_cube(0, 1.0));
        bad(subdivided_cube(2, f32::NEG_INFINITY));
        bad(subdivided_cube(1 << 20, 1.0));
        bad(disc(0, 8, 1.0));
        bad(disc(2, 2, 1.0));
        bad(disc(2, 8, 0.0));
        let bad_tet = |r: Result<TetMesh, MeshError>| {
            assert!(
                matches!(r, Err(MeshError::InvalidParameter { .. })),
                "{r:?}"
            )
        };
        bad_tet(tet_box(0, 1, 1, Vec3::ONE));
        bad_tet(tet_box(1, 0, 1, Vec3::ONE));
        bad_tet(tet_box(1, 1, 0, Vec3::ONE));
        bad_tet(tet_box(1, 1, 1, Vec3::new(1.0, -1.0, 1.0)));
        bad_tet(tet_box(1, 1, 1, Vec3::new(1.0, 1.0, f32::NAN)));
        bad_tet(tet_box(u32::MAX, 2, 2, Vec3::ONE));
    }

    #[test]
    fn smallest_meshes_are_valid() {
        assert_eq!(grid(2, 1.0).unwrap().triangle_count(), 2);
        let bipyramid = uv_sphere(3, 1, 1.0).unwrap();
        assert_eq!(
            (bipyramid.vertex_count(), bipyramid.triangle_count()),
            (5, 6)
        );
        assert!(bipyramid.is_closed());
        let cube = subdivided_cube(1, 1.0).unwrap();
        assert_eq!((cube.vertex_count(), cube.triangle_count()), (8, 12));
        assert!(cube.is_closed());
        let fan = disc(1, 3, 1.0).unwrap();
        assert_eq!((fan.vertex_count(), fan.triangle_count()), (4, 3));
        let cell = tet_box(1, 1, 1, Vec3::ONE).unwrap();
        assert_eq!((cell.vertex_count(), cell.tet_count()), (8, 6));
    }

    #[test]
    fn grid_vertex_numbering() {
        let g = grid(3, 2.0).unwrap();
        let p = g.positions();
        assert_eq!(p[0], Vec3::new(-1.0, -1.0, 0.0));
        assert_eq!(p[1], Vec3::new(0.0, -1.0, 0.0));
        assert_eq!(p[3], Vec3::new(-1.0, 0.0, 0.0));
        assert_eq!(p[8], Vec3::new(1.0, 1.0, 0.0));
        // Checkerboard: cell (0,0) uses diagonal 0–4, cell (0,1) diagonal 2–4.
        assert_eq!(
            &g.triangles()[..4],
            &[[0, 1, 4], [0, 4, 3], [1, 2, 4], [2, 5, 4]]
        );
    }

    #[test]
    fn cube_vertex_order_is_z_then_y_then_x() {
        let c = subdivided_cube(2, 2.0).unwrap();
        let p = c.positions();
        assert_eq!(p[0], Vec3::new(-1.0, -1.0, -1.0));
        assert_eq!(p[1], Vec3::new(0.0, -1.0, -1.0));
        assert_eq!(p[p.len() - 1], Vec3::new(1.0, 1.0, 1.0));
        let key = |v: &Vec3| (v.z, v.y, v.x);
        assert!(p.windows(2).all(|w| key(&w[0]) < key(&w[1])));
    }
}
