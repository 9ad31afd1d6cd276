//! Seeded test surfaces shared by the tests and the bench (hidden from the docs; not part of the
//! supported API): noisy planes, discs, cylinder patches and spheres with holes punched in them.

use glam::Vec3;
use tissue_bvh::scenes::Rng;
use tissue_mesh::{grid, subdivided_cube, MeshError, TriMesh};

/// A standard normal sample from `rng` (Box–Muller on two 53-bit uniforms).
fn standard_normal(rng: &mut Rng) -> f64 {
    let mut unit = || (rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64;
    let u1 = unit().max(1e-300);
    let u2 = unit();
    (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
}

/// Keeps the triangles `keep(t)` and drops the vertices no kept triangle uses (kept ones in order).
pub fn keep_triangles(mesh: &TriMesh, keep: impl Fn(usize) -> bool) -> Result<TriMesh, MeshError> {
    let mut map = vec![u32::MAX; mesh.vertex_count()];
    let mut positions = Vec::new();
    let mut triangles = Vec::new();
    for (t, tri) in mesh.triangles().iter().enumerate() {
        if !keep(t) {
            continue;
        }
        triangles.push(tri.map(|v| {
            if map[v as usize] == u32::MAX {
                map[v as usize] = positions.len() as u32;
                positions.push(mesh.positions()[v as usize]);
            }
            map[v as usize]
        }));
    }
    TriMesh::new(positions, triangles)
}

/// Removes the triangles whose centroid is within `radius` of one of `centres` (punched holes).
pub fn punch_holes(mesh: &TriMesh, centres: &[Vec3], radius: f32) -> Result<TriMesh, MeshError> {
    keep_triangles(mesh, |t| {
        let [a, b, c] = mesh.corners(t);
        let g = (a + b + c) / 3.0;
        centres.iter().all(|&x| (g - x).length() > radius)
    })
}

/// Moves every vertex by `sigma · N(0,1)` along `normal(p)`.
pub fn add_noise(
    mesh: &TriMesh,
    sigma: f64,
    seed: u64,
    normal: impl Fn(Vec3) -> Vec3,
) -> Result<TriMesh, MeshError> {
    let mut rng = Rng::new(seed);
    let positions = mesh
        .positions()
        .iter()
        .map(|&p| p + normal(p) * (sigma * standard_normal(&mut rng)) as f32)
        .collect();
    TriMesh::new(positions, mesh.triangles().to_vec())
}

/// A square patch in `z = 0` of side `side` with `spacing` between grid lines (two triangles per
/// cell), its vertices displaced along `z` by seeded Gaussian noise of deviation `noise`.
pub fn noisy_plane(side: f32, spacing: f32, noise: f64, seed: u64) -> Result<TriMesh, MeshError> {
    let n = (side / spacing).round() as u32 + 1;
    let plane = grid(n, side)?;
    add_noise(&plane, noise, seed, |_| Vec3::Z)
}

/// A disc of radius `radius` in `z = 0` cut from a grid of `spacing` (with noise as
/// [`noisy_plane`]).
pub fn noisy_disc(radius: f32, spacing: f32, noise: f64, seed: u64) -> Result<TriMesh, MeshError> {
    let plane = noisy_plane(2.0 * radius + 2.0 * spacing, spacing, noise, seed)?;
    keep_triangles(&plane, |t| {
        let [a, b, c] = plane.corners(t);
        let g = (a + b + c) / 3.0;
        g.truncate().length() <= radius
    })
}

/// A patch of a cylinder of radius `radius` around the `y` axis: a `width × height` grid of
/// `spacing` wrapped onto it (normals outward), with radial noise.
pub fn noisy_cylinder_patch(
    radius: f32,
    width: f32,
    height: f32,
    spacing: f32,
    noise: f64,
    seed: u64,
) -> Result<TriMesh, MeshError> {
    let n = (width.max(height) / spacing).round() as u32 + 1;
    let side = spacing * (n - 1) as f32;
    let plane = grid(n, side)?;
    let wrapped = keep_triangles(&plane, |t| {
        let [a, b, c] = plane.corners(t);
        let g = (a + b + c) / 3.0;
        g.x.abs() <= 0.5 * width && g.y.abs() <= 0.5 * height
    })?;
    let positions = wrapped
        .positions()
        .iter()
        .map(|p| {
            let phi = p.x / radius;
            Vec3::new(radius * phi.sin(), p.y, radius * phi.cos())
        })
        .collect();
    let cyl = TriMesh::new(positions, wrapped.triangles().to_vec())?;
    add_noise(&cyl, noise, seed, |p| Vec3::new(p.x, 0.0, p.z).normalize())
}

/// A closed sphere of radius `radius` (a subdivided cube pushed onto it, edges about `spacing`)
/// with radial noise.
pub fn noisy_sphere(
    radius: f32,
    spacing: f32,
    noise: f64,
    seed: u64,
) -> Result<TriMesh, MeshError> {
    let per_edge = ((std::f32::consts::FRAC_PI_2 * radius / spacing).round() as u32).max(1);
    let cube = subdivided_cube(per_edge, 2.0)?;
    let positions = cube
        .positions()
        .iter()
        .map(|p| p.normalize() * radius)
        .collect();
    let sphere = TriMesh::new(positions, cube.triangles().to_vec())?;
    add_noise(&sphere, noise, seed, |p| p.normalize())
}
