//! Static colliders as a uniform voxel grid of signed distances.
//!
//! SPEC Part B: "static objects (table, other organs) as a uniform voxel grid; soft-body contacts
//! checked only in occupied voxels". A [`VoxelCollider`] samples the signed distance `φ` of a
//! union of closed triangle meshes and oriented boxes at the corners of a uniform grid (negative
//! inside, in cm); between corners `φ` is trilinear, so it and its gradient are continuous across
//! faces of cells and a plane (a tray's top, even tilted) is reproduced exactly. A cell is
//! *occupied* when `φ < reach` at one of its corners; since a trilinear field lies between its
//! corner values, a point in an unoccupied cell is farther than `reach` from the solid and is
//! rejected after one bit test.
//!
//! Distances of a mesh: exact point–triangle distances at the corners within one cell of each
//! triangle, then two fast-sweeping passes in the eight diagonal orders that hand each corner the
//! closest triangle of its neighbours (Bridson's `makelevelset3`); the result is the exact
//! distance to a nearby triangle, within a small fraction of a cell of the true distance. Signs:
//! the parity of crossings of grid lines with the mesh, along x, y and z, by majority. The
//! point-in-triangle tests of the parity use exactly evaluated orientations with a symbolic
//! perturbation of the line (simulation of simplicity), so a line through an edge or a vertex of
//! a closed mesh is counted consistently.

use glam::{Quat, Vec3, Vec3A};
use tissue_mesh::TriMesh;

use crate::geometry::closest_point_on_triangle;
use crate::{PbdError, PbdParam};

/// The largest grid [`VoxelCollider::new`] builds (corners; 64 MB of distances).
pub const MAX_COLLIDER_CORNERS: u64 = 1 << 24;

/// A box with its own orientation: the points `center + rotation·l` with `|l| ≤ half_extents`
/// in each coordinate (cm).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OrientedBox {
    /// Centre (cm).
    pub center: Vec3,
    /// Half the edge lengths along the box's own axes (cm), each `> 0`.
    pub half_extents: Vec3,
    /// Rotation from the box's axes to the world's.
    pub rotation: Quat,
}

impl OrientedBox {
    /// The axis-aligned box between two corners.
    pub fn from_corners(min: Vec3, max: Vec3) -> Self {
        Self {
            center: (min + max) * 0.5,
            half_extents: (max - min).abs() * 0.5,
            rotation: Quat::IDENTITY,
        }
    }

    /// A tray: an axis-aligned slab of `size.x × thickness × size.z` whose top face is the plane
    /// `y = top`, centred on `(center_x, ·, center_z)`.
    pub fn tray(
        center_x: f32,
        center_z: f32,
        top: f32,
        size_x: f32,
        size_z: f32,
        thickness: f32,
    ) -> Self {
        Self {
            center: Vec3::new(center_x, top - thickness * 0.5, center_z),
            half_extents: Vec3::new(size_x * 0.5, thickness * 0.5, size_z * 0.5),
            rotation: Quat::IDENTITY,
        }
    }

    /// The same box rotated by `rotation` about its centre.
    pub fn rotated(self, rotation: Quat) -> Self {
        Self {
            rotation: (rotation * self.rotation).normalize(),
            ..self
        }
    }

    /// Exact signed distance (negative inside).
    pub fn signed_distance(&self, p: Vec3) -> f32 {
        let l = self.rotation.inverse() * (p - self.center);
        let q = l.abs() - self.half_extents;
        q.max(Vec3::ZERO).length() + q.max_element().min(0.0)
    }

    /// The world-axis bounding box `(min, max)`.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        let m = glam::Mat3::from_quat(self.rotation);
        let e = Vec3::new(
            m.row(0).abs().dot(self.half_extents),
            m.row(1).abs().dot(self.half_extents),
            m.row(2).abs().dot(self.half_extents),
        );
        (self.center - e, self.center + e)
    }
}

/// One solid of a [`VoxelCollider`]; the collider is their union.
#[derive(Debug, Clone, Copy)]
pub enum ColliderShape<'a> {
    /// A closed triangle mesh (either winding: the sign comes from crossing parity).
    Mesh(&'a TriMesh),
    /// An oriented box (analytic distance).
    Box(OrientedBox),
}

/// A static collider: signed distances on a uniform grid, with a bit per occupied cell.
///
/// Invariants: `phi.len()` is the product of `corners`, each `corners[a] ≥ 2`; corner `(i, j, k)`
/// is at `origin + (i, j, k)·cell` and stored at `(k·corners[1] + j)·corners[0] + i`; bit `c` of
/// `occupied` is set exactly when cell `c` (numbered like the corners, with `corners − 1` per
/// axis) has a corner with `φ < reach`.
#[derive(Debug, Clone, PartialEq)]
pub struct VoxelCollider {
    origin: Vec3A,
    cell: f32,
    inv_cell: f32,
    corners: [usize; 3],
    phi: Vec<f32>,
    occupied: Vec<u64>,
    occupied_count: usize,
    reach: f32,
}

/// The grid's geometry while it is built.
#[derive(Debug, Clone, Copy)]
struct Grid {
    origin: Vec3A,
    cell: f32,
    n: [usize; 3],
}

impl Grid {
    #[inline]
    fn index(&self, i: usize, j: usize, k: usize) -> usize {
        (k * self.n[1] + j) * self.n[0] + i
    }
    /// Coordinate of corner line `i` along `axis` (the one formula used everywhere).
    #[inline]
    fn coord(&self, axis: usize, i: usize) -> f32 {
        self.origin[axis] + i as f32 * self.cell
    }
    #[inline]
    fn corner(&self, i: usize, j: usize, k: usize) -> Vec3A {
        Vec3A::new(self.coord(0, i), self.coord(1, j), self.coord(2, k))
    }
    fn len(&self) -> usize {
        self.n[0] * self.n[1] * self.n[2]
    }
    /// Corner index range along `axis` covering `[lo, hi]`, widened by `pad` corners, clamped.
    fn range(&self, axis: usize, lo: f32, hi: f32, pad: usize) -> (usize, usize) {
        let a = ((lo - self.origin[axis]) / self.cell).floor() as i64 - pad as i64;
        let b = ((hi - self.origin[axis]) / self.cell).ceil() as i64 + pad as i64;
        let last = self.n[axis] as i64 - 1;
        (a.clamp(0, last) as usize, b.clamp(0, last) as usize)
    }
}

impl VoxelCollider {
    /// The union of `shapes` sampled on a grid of cubic cells of `cell_size` cm, padded so that
    /// every point within `reach + 2·cell_size` of a shape is inside the grid. Contacts can be
    /// found up to `reach` from the surface (a body's `margin + detection` must not exceed it).
    ///
    /// # Errors
    /// [`PbdError::InvalidParameter`] for a non-finite or non-positive `cell_size`, a negative
    /// `reach` or no shapes; [`PbdError::ColliderMeshNotClosed`] for a mesh with holes;
    /// [`PbdError::InvalidColliderShape`] for a box with a non-positive or non-finite size;
    /// [`PbdError::ColliderTooLarge`] when the grid would exceed [`MAX_COLLIDER_CORNERS`].
    pub fn new(shapes: &[ColliderShape<'_>], cell_size: f32, reach: f32) -> Result<Self, PbdError> {
        let _span = tracing::debug_span!("voxel_collider_new", shapes = shapes.len()).entered();
        if !(cell_size.is_finite() && cell_size > 0.0) {
            return Err(PbdError::InvalidParameter {
                param: PbdParam::CellSize,
                value: cell_size as f64,
                expected: "finite and > 0 (cm)",
            });
        }
        if !(reach.is_finite() && reach >= 0.0) {
            return Err(PbdError::InvalidParameter {
                param: PbdParam::ColliderReach,
                value: reach as f64,
                expected: "finite and ≥ 0 (cm)",
            });
        }
        if shapes.is_empty() {
            return Err(PbdError::InvalidParameter {
                param: PbdParam::Shapes,
                value: 0.0,
                expected: "at least one mesh or box",
            });
        }
        let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
        for (s, shape) in shapes.iter().enumerate() {
            let (a, b) = match shape {
                ColliderShape::Mesh(mesh) => {
                    if !mesh.is_closed() {
                        return Err(PbdError::ColliderMeshNotClosed {
                            shape: s,
                            boundary_edges: mesh.topology().boundary_edge_count(),
                        });
                    }
                    let b = mesh.bounding_box();
                    (b.min, b.max)
                }
                ColliderShape::Box(b) => {
                    if !(b.half_extents.is_finite() && b.half_extents.min_element() > 0.0) {
                        return Err(PbdError::InvalidColliderShape {
                            shape: s,
                            reason: "the box's half extents must be finite and > 0 (cm)",
                        });
                    }
                    if !(b.center.is_finite() && b.rotation.is_finite())
                        || (b.rotation.length() - 1.0).abs() > 1e-3
                    {
                        return Err(PbdError::InvalidColliderShape {
                            shape: s,
                            reason:
                                "the box's centre must be finite and its rotation a unit quaternion",
                        });
                    }
                    b.bounds()
                }
            };
            lo = lo.min(a);
            hi = hi.max(b);
        }
        let pad = reach + 2.0 * cell_size;
        let (lo, hi) = (lo - Vec3::splat(pad), hi + Vec3::splat(pad));
        let counts = ((hi - lo) / cell_size).ceil().as_dvec3() + 1.0;
        let corners_f = counts.x * counts.y * counts.z;
        if !(corners_f.is_finite() && corners_f <= MAX_COLLIDER_CORNERS as f64) {
            return Err(PbdError::ColliderTooLarge {
                corners: if corners_f.is_finite() {
                    corners_f as u64
                } else {
                    u64::MAX
                },
                limit: MAX_COLLIDER_CORNERS,
                cell_size,
            });
        }
        let grid = Grid {
            origin: lo.into(),
            cell: cell_size,
            n: [counts.x as usize, counts.y as usize, counts.z as usize],
        };
        let mut phi = vec![f32::INFINITY; grid.len()];
        for shape in shapes {
            match shape {
                ColliderShape::Box(b) => {
                    for k in 0..grid.n[2] {
                        for j in 0..grid.n[1] {
                            for i in 0..grid.n[0] {
                                let d = b.signed_distance(grid.corner(i, j, k).into());
                                let e = &mut phi[grid.index(i, j, k)];
                                *e = e.min(d);
                            }
                        }
                    }
                }
                ColliderShape::Mesh(mesh) => {
                    let d = mesh_signed_distance(mesh, &grid);
                    for (e, d) in phi.iter_mut().zip(d) {
                        *e = e.min(d);
                    }
                }
            }
        }
        Ok(Self::from_grid(grid, phi, reach))
    }

    /// A collider of one closed mesh, `reach` = one cell.
    ///
    /// # Errors
    /// As [`VoxelCollider::new`].
    pub fn from_mesh(mesh: &TriMesh, cell_size: f32) -> Result<Self, PbdError> {
        Self::new(&[ColliderShape::Mesh(mesh)], cell_size, cell_size)
    }

    /// A collider of one box (e.g. a tray, [`OrientedBox::tray`]), `reach` = one cell.
    ///
    /// # Errors
    /// As [`VoxelCollider::new`].
    pub fn from_box(b: OrientedBox, cell_size: f32) -> Result<Self, PbdError> {
        Self::new(&[ColliderShape::Box(b)], cell_size, cell_size)
    }

    fn from_grid(grid: Grid, phi: Vec<f32>, reach: f32) -> Self {
        let [nx, ny, nz] = grid.n;
        let cells = (nx - 1) * (ny - 1) * (nz - 1);
        let mut occupied = vec![0u64; cells.div_ceil(64)];
        let mut occupied_count = 0;
        for k in 0..nz - 1 {
            for j in 0..ny - 1 {
                for i in 0..nx - 1 {
                    let base = grid.index(i, j, k);
                    let (sx, sy) = (1, nx);
                    let sz = nx * ny;
                    let m = [0, sx, sy, sx + sy, sz, sz + sx, sz + sy, sz + sx + sy]
                        .iter()
                        .map(|&o| phi[base + o])
                        .fold(f32::INFINITY, f32::min);
                    if m < reach {
                        let c = (k * (ny - 1) + j) * (nx - 1) + i;
                        occupied[c / 64] |= 1 << (c % 64);
                        occupied_count += 1;
                    }
                }
            }
        }
        Self {
            origin: grid.origin,
            cell: grid.cell,
            inv_cell: 1.0 / grid.cell,
            corners: grid.n,
            phi,
            occupied,
            occupied_count,
            reach,
        }
    }

    /// Edge length of a cell (cm).
    pub fn cell_size(&self) -> f32 {
        self.cell
    }
    /// How far from the surface contacts can be found (cm).
    pub fn reach(&self) -> f32 {
        self.reach
    }
    /// Corners per axis.
    pub fn corner_counts(&self) -> [usize; 3] {
        self.corners
    }
    /// Position of corner `(0, 0, 0)` (cm).
    pub fn origin(&self) -> Vec3 {
        self.origin.into()
    }
    /// The grid's extent `(min, max)` (cm).
    pub fn bounds(&self) -> (Vec3, Vec3) {
        let n = Vec3::new(
            (self.corners[0] - 1) as f32,
            (self.corners[1] - 1) as f32,
            (self.corners[2] - 1) as f32,
        );
        (self.origin.into(), Vec3::from(self.origin) + n * self.cell)
    }
    /// Number of cells that have a corner closer than [`VoxelCollider::reach`] (or inside).
    pub fn occupied_cell_count(&self) -> usize {
        self.occupied_count
    }
    /// Number of cells.
    pub fn cell_count(&self) -> usize {
        (self.corners[0] - 1) * (self.corners[1] - 1) * (self.corners[2] - 1)
    }
    /// Signed distances at the corners (cm, negative inside), x fastest, then y, then z.
    pub fn corner_distances(&self) -> &[f32] {
        &self.phi
    }

    /// The cell of `p` (its linear index and the corner index of its lower corner) and the
    /// position within it in `[0, 1]³`; `None` outside the grid.
    #[inline]
    fn locate(&self, p: Vec3A) -> Option<(usize, usize, Vec3A)> {
        let g = (p - self.origin) * self.inv_cell;
        let f = g.floor();
        let [nx, ny, nz] = self.corners;
        if !(f.x >= 0.0 && f.y >= 0.0 && f.z >= 0.0) {
            return None;
        }
        let (i, j, k) = (f.x as usize, f.y as usize, f.z as usize);
        if i + 1 >= nx || j + 1 >= ny || k + 1 >= nz {
            return None;
        }
        let cell = (k * (ny - 1) + j) * (nx - 1) + i;
        Some((cell, (k * ny + j) * nx + i, g - f))
    }

    /// Trilinear `φ` and its gradient in the cell with lower corner `base`.
    #[inline]
    fn interpolate(&self, base: usize, t: Vec3A) -> (f32, Vec3A) {
        let [nx, ny, _] = self.corners;
        let (sy, sz) = (nx, nx * ny);
        let c = |o: usize| self.phi[base + o];
        let (c000, c100, c010, c110) = (c(0), c(1), c(sy), c(sy + 1));
        let (c001, c101, c011, c111) = (c(sz), c(sz + 1), c(sz + sy), c(sz + sy + 1));
        let (x, y, z) = (t.x, t.y, t.z);
        let (ux, uy, uz) = (1.0 - x, 1.0 - y, 1.0 - z);
        let c00 = c000 * ux + c100 * x;
        let c10 = c010 * ux + c110 * x;
        let c01 = c001 * ux + c101 * x;
        let c11 = c011 * ux + c111 * x;
        let c0 = c00 * uy + c10 * y;
        let c1 = c01 * uy + c11 * y;
        let value = c0 * uz + c1 * z;
        let dx = ((c100 - c000) * uy + (c110 - c010) * y) * uz
            + ((c101 - c001) * uy + (c111 - c011) * y) * z;
        let dy = (c10 - c00) * uz + (c11 - c01) * z;
        let dz = c1 - c0;
        (value, Vec3A::new(dx, dy, dz) * self.inv_cell)
    }

    /// `φ` and its gradient at `p` when `p` is in an occupied cell (the contact query).
    #[inline]
    pub(crate) fn probe(&self, p: Vec3A) -> Option<(f32, Vec3A)> {
        let (cell, base, t) = self.locate(p)?;
        if self.occupied[cell / 64] & (1 << (cell % 64)) == 0 {
            return None;
        }
        Some(self.interpolate(base, t))
    }

    /// Whether `p` lies in an occupied cell (one that can hold a contact).
    pub fn is_occupied(&self, p: Vec3) -> bool {
        self.locate(p.into())
            .is_some_and(|(cell, _, _)| self.occupied[cell / 64] & (1 << (cell % 64)) != 0)
    }

    /// The interpolated signed distance at `p` (cm, negative inside), `None` outside the grid.
    pub fn signed_distance(&self, p: Vec3) -> Option<f32> {
        let (_, base, t) = self.locate(p.into())?;
        Some(self.interpolate(base, t).0)
    }

    /// The outward unit normal at `p` (the normalised gradient of the interpolated distance),
    /// `None` outside the grid or where the gradient vanishes (on a medial surface).
    pub fn normal(&self, p: Vec3) -> Option<Vec3> {
        let (_, base, t) = self.locate(p.into())?;
        let g = self.interpolate(base, t).1;
        let len = g.length();
        (len > 1e-6).then(|| Vec3::from(g / len))
    }
}

/// Signed distance of a closed mesh at every grid corner.
fn mesh_signed_distance(mesh: &TriMesh, grid: &Grid) -> Vec<f32> {
    let _span = tracing::debug_span!("mesh_distance", triangles = mesh.triangle_count()).entered();
    let pos: Vec<Vec3A> = mesh.positions().iter().map(|&p| p.into()).collect();
    let tris = mesh.triangles();
    let corners = |t: u32| tris[t as usize].map(|i| pos[i as usize]);
    let dist_to = |p: Vec3A, t: u32| {
        let [a, b, c] = corners(t);
        p.distance(closest_point_on_triangle(p, a, b, c))
    };
    const NONE: u32 = u32::MAX;
    let mut dist = vec![f32::INFINITY; grid.len()];
    let mut closest = vec![NONE; grid.len()];
    // Exact distances within one cell of each triangle.
    for (t, tri) in tris.iter().enumerate() {
        let q = tri.map(|i| pos[i as usize]);
        let (lo, hi) = (q[0].min(q[1]).min(q[2]), q[0].max(q[1]).max(q[2]));
        let (i0, i1) = grid.range(0, lo.x, hi.x, 1);
        let (j0, j1) = grid.range(1, lo.y, hi.y, 1);
        let (k0, k1) = grid.range(2, lo.z, hi.z, 1);
        for k in k0..=k1 {
            for j in j0..=j1 {
                for i in i0..=i1 {
                    let p = grid.corner(i, j, k);
                    let d = p.distance(closest_point_on_triangle(p, q[0], q[1], q[2]));
                    let c = grid.index(i, j, k);
                    if d < dist[c] {
                        dist[c] = d;
                        closest[c] = t as u32;
                    }
                }
            }
        }
    }
    // Fast sweeping: each corner tries its upwind neighbours' closest triangles.
    let [nx, ny, nz] = grid.n;
    for _ in 0..2 {
        for dir in 0..8u32 {
            let (di, dj, dk) = (
                if dir & 1 == 0 { 1i64 } else { -1 },
                if dir & 2 == 0 { 1i64 } else { -1 },
                if dir & 4 == 0 { 1i64 } else { -1 },
            );
            // Step `s` of a sweep of `n` corners in direction `d`, skipping the first corner.
            let at = |s: usize, n: usize, d: i64| if d > 0 { s + 1 } else { n - 2 - s };
            for sk in 0..nz - 1 {
                let k = at(sk, nz, dk);
                for sj in 0..ny - 1 {
                    let j = at(sj, ny, dj);
                    for si in 0..nx - 1 {
                        let i = at(si, nx, di);
                        let c = grid.index(i, j, k);
                        let p = grid.corner(i, j, k);
                        let (pi, pj, pk) = (
                            (i as i64 - di) as usize,
                            (j as i64 - dj) as usize,
                            (k as i64 - dk) as usize,
                        );
                        for (a, b, e) in [
                            (pi, j, k),
                            (i, pj, k),
                            (pi, pj, k),
                            (i, j, pk),
                            (pi, j, pk),
                            (i, pj, pk),
                            (pi, pj, pk),
                        ] {
                            let t = closest[grid.index(a, b, e)];
                            if t != NONE && t != closest[c] {
                                let d = dist_to(p, t);
                                if d < dist[c] {
                                    dist[c] = d;
                                    closest[c] = t;
                                }
                            }
                        }
                    }
                }
            }
        }
    }
    // Signs by crossing parity along each axis, majority of three.
    let mut votes = vec![0u8; grid.len()];
    for axis in 0..3 {
        parity_votes(&pos, tris, grid, axis, &mut votes);
    }
    for (d, v) in dist.iter_mut().zip(votes) {
        if v >= 2 {
            *d = -*d;
        }
    }
    dist
}

/// Sign of the 2-D orientation `(b − a) × (p − a)` (u, v coordinates), evaluated exactly in
/// `f64` (differences and products of `f32` values are exact there for coordinates of similar
/// magnitude), with `p` perturbed by `(ε, ε²)` so that it is never zero unless `a = b`.
#[inline]
fn orient(a: [f32; 2], b: [f32; 2], p: [f32; 2]) -> (f64, i8) {
    let (ax, ay, bx, by) = (a[0] as f64, a[1] as f64, b[0] as f64, b[1] as f64);
    let (px, py) = (p[0] as f64, p[1] as f64);
    let det = (bx - ax) * (py - ay) - (by - ay) * (px - ax);
    let sign = if det != 0.0 {
        det.signum() as i8
    } else if by != ay {
        // ∂det/∂px = −(by − ay)
        if by > ay {
            -1
        } else {
            1
        }
    } else if bx != ax {
        // ∂det/∂py = bx − ax
        if bx > ax {
            1
        } else {
            -1
        }
    } else {
        0
    };
    (det, sign)
}

/// Adds 1 to `votes` at every corner that an odd number of triangles lies below along `axis`.
fn parity_votes(pos: &[Vec3A], tris: &[[u32; 3]], grid: &Grid, axis: usize, votes: &mut [u8]) {
    let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
    let (nu, nv) = (grid.n[u], grid.n[v]);
    let mut crossings: Vec<(u32, f32)> = Vec::new();
    for tri in tris {
        let q = tri.map(|i| pos[i as usize]);
        let uv = q.map(|p| [p[u], p[v]]);
        if orient(uv[0], uv[1], uv[2]).0 == 0.0 {
            continue; // parallel to the lines
        }
        let lo = q[0].min(q[1]).min(q[2]);
        let hi = q[0].max(q[1]).max(q[2]);
        let (u0, u1) = grid.range(u, lo[u], hi[u], 1);
        let (v0, v1) = grid.range(v, lo[v], hi[v], 1);
        for jv in v0..=v1 {
            for ju in u0..=u1 {
                let p = [grid.coord(u, ju), grid.coord(v, jv)];
                let (wc, s0) = orient(uv[0], uv[1], p);
                let (wa, s1) = orient(uv[1], uv[2], p);
                let (wb, s2) = orient(uv[2], uv[0], p);
                if s0 == 0 || s0 != s1 || s1 != s2 {
                    continue;
                }
                let sum = wa + wb + wc;
                let along = if sum != 0.0 {
                    ((wa * q[0][axis] as f64 + wb * q[1][axis] as f64 + wc * q[2][axis] as f64)
                        / sum) as f32
                } else {
                    q[0][axis]
                };
                crossings.push(((jv * nu + ju) as u32, along));
            }
        }
    }
    crossings.sort_unstable_by(|a, b| a.0.cmp(&b.0).then(a.1.total_cmp(&b.1)));
    let n = grid.n[axis];
    let mut s = 0;
    while s < crossings.len() {
        let line = crossings[s].0 as usize;
        let mut e = s;
        while e < crossings.len() && crossings[e].0 as usize == line {
            e += 1;
        }
        let (ju, jv) = (line % nu, line / nu);
        debug_assert!(jv < nv);
        let mut c = s;
        for i in 0..n {
            let x = grid.coord(axis, i);
            while c < e && crossings[c].1 < x {
                c += 1;
            }
            if (c - s) % 2 == 1 {
                let mut idx = [0usize; 3];
                idx[axis] = i;
                idx[u] = ju;
                idx[v] = jv;
                votes[grid.index(idx[0], idx[1], idx[2])] += 1;
            }
        }
        s = e;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_box_mesh_on_grid_lines_gets_consistent_signs() {
        // A cube whose faces, edges and vertices lie exactly on grid lines: every parity line
        // through an edge or a vertex must still be counted once.
        let cube = tissue_mesh::subdivided_cube(4, 2.0).unwrap_or_else(|e| panic!("{e}"));
        let c = VoxelCollider::from_mesh(&cube, 0.25).unwrap_or_else(|e| panic!("{e}"));
        let b = OrientedBox::from_corners(Vec3::splat(-1.0), Vec3::splat(1.0));
        let analytic = VoxelCollider::from_box(b, 0.25).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(c.corner_counts(), analytic.corner_counts());
        let worst = c
            .corner_distances()
            .iter()
            .zip(analytic.corner_distances())
            .map(|(a, b)| (a - b).abs())
            .fold(0.0f32, f32::max);
        assert!(worst < 1e-4, "mesh and analytic box differ by {worst}");
        assert!(c.occupied_cell_count() > 0 && c.occupied_cell_count() < c.cell_count());
    }

    #[test]
    fn tilted_plane_is_exact_between_corners() {
        let b =
            OrientedBox::tray(0.0, 0.0, 0.0, 20.0, 20.0, 2.0).rotated(Quat::from_rotation_z(0.3));
        let c = VoxelCollider::from_box(b, 0.5).unwrap_or_else(|e| panic!("{e}"));
        let n = Vec3::new(-(0.3f32).sin(), (0.3f32).cos(), 0.0);
        for s in 0..20 {
            let p = Vec3::new(-3.0 + 0.31 * s as f32, 0.0, 1.7) + n * (0.05 * s as f32 - 0.4);
            let exact = b.signed_distance(p);
            let got = c.signed_distance(p).unwrap_or(f32::NAN);
            assert!((got - exact).abs() < 1e-4, "{p}: {got} vs {exact}");
            let normal = c.normal(p).unwrap_or(Vec3::ZERO);
            assert!(normal.distance(n) < 1e-4, "{normal} vs {n}");
        }
    }
}
