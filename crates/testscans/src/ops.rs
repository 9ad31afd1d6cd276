//! Mesh operations the generators are built from, public so that tests can build variants:
//! midpoint and Loop subdivision, noise along the normals, holes, the median edge.
//!
//! The generators run these on raw arrays (`Vec<Vec3>`, `Vec<[u32; 3]>`) and validate once at
//! the end; the public functions wrap them and return a validated [`TriMesh`].

use glam::{DVec3, Vec3};
use tissue_mesh::TriMesh;

use crate::{Rng, ScanError};

/// Median length of the unique edges of a mesh, in its unit (`0.0` is never returned for a valid
/// mesh, which has at least one triangle).
pub fn median_edge(mesh: &TriMesh) -> f64 {
    let p = mesh.positions();
    let mut lengths: Vec<f64> = mesh
        .topology()
        .edges()
        .iter()
        .map(|&[a, b]| f64::from((p[a as usize] - p[b as usize]).length()))
        .collect();
    median(&mut lengths)
}

pub(crate) fn median(values: &mut [f64]) -> f64 {
    if values.is_empty() {
        return 0.0;
    }
    let mid = values.len() / 2;
    let (_, m, _) = values.select_nth_unstable_by(mid, f64::total_cmp);
    *m
}

/// Median edge of raw triangles (each interior edge counted twice, which leaves the median of a
/// closed or nearly closed surface unchanged in practice).
pub(crate) fn median_edge_raw(positions: &[Vec3], triangles: &[[u32; 3]]) -> f64 {
    let mut lengths: Vec<f64> = triangles
        .iter()
        .flat_map(|t| {
            (0..3).map(move |s| {
                f64::from((positions[t[s] as usize] - positions[t[(s + 1) % 3] as usize]).length())
            })
        })
        .collect();
    median(&mut lengths)
}

/// Unique edges of raw triangles: the edges (smaller vertex first), for each triangle the edge
/// of each side (`ab`, `bc`, `ca`), and for each edge its one or two triangles (`u32::MAX`
/// for none).
pub(crate) struct Edges {
    pub edges: Vec<[u32; 2]>,
    pub triangle_edges: Vec<[u32; 3]>,
    pub edge_triangles: Vec<[u32; 2]>,
}

pub(crate) fn edges_of(triangles: &[[u32; 3]]) -> Edges {
    let mut sides: Vec<(u64, u32)> = Vec::with_capacity(triangles.len() * 3);
    for (t, tri) in triangles.iter().enumerate() {
        for s in 0..3 {
            let (a, b) = (tri[s], tri[(s + 1) % 3]);
            let key = (u64::from(a.min(b)) << 32) | u64::from(a.max(b));
            sides.push((key, (t as u32) * 3 + s as u32));
        }
    }
    sides.sort_unstable();
    let mut edges = Vec::with_capacity(sides.len() / 2 + 1);
    let mut edge_triangles = Vec::with_capacity(sides.len() / 2 + 1);
    let mut triangle_edges = vec![[0u32; 3]; triangles.len()];
    for group in sides.chunk_by(|x, y| x.0 == y.0) {
        let e = edges.len() as u32;
        edges.push([(group[0].0 >> 32) as u32, group[0].0 as u32]);
        let mut tris = [u32::MAX; 2];
        for (i, &(_, ts)) in group.iter().enumerate() {
            if let Some(slot) = tris.get_mut(i) {
                *slot = ts / 3;
            }
            triangle_edges[(ts / 3) as usize][(ts % 3) as usize] = e;
        }
        edge_triangles.push(tris);
    }
    Edges {
        edges,
        triangle_edges,
        edge_triangles,
    }
}

/// Midpoint (1:4) subdivision of raw triangles; new vertices follow the old ones, one per edge in
/// edge order. Winding is kept.
pub(crate) fn midpoint_raw(
    positions: &[Vec3],
    triangles: &[[u32; 3]],
) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let e = edges_of(triangles);
    let n = positions.len() as u32;
    let mut out = positions.to_vec();
    out.extend(
        e.edges
            .iter()
            .map(|&[a, b]| (positions[a as usize] + positions[b as usize]) * 0.5),
    );
    (out, split_four(triangles, &e.triangle_edges, n))
}

fn split_four(triangles: &[[u32; 3]], triangle_edges: &[[u32; 3]], n: u32) -> Vec<[u32; 3]> {
    let mut tris = Vec::with_capacity(triangles.len() * 4);
    for (tri, te) in triangles.iter().zip(triangle_edges) {
        let [a, b, c] = *tri;
        let [ab, bc, ca] = te.map(|x| x + n);
        tris.push([a, ab, ca]);
        tris.push([ab, b, bc]);
        tris.push([ca, bc, c]);
        tris.push([ab, bc, ca]);
    }
    tris
}

/// Loop subdivision of raw triangles (Warren's weights; boundary edges and vertices follow the
/// boundary curve's 1/2 and 1/8–3/4–1/8 rules; a vertex on more than two boundary edges stays).
pub(crate) fn loop_raw(positions: &[Vec3], triangles: &[[u32; 3]]) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let e = edges_of(triangles);
    let n = positions.len();
    let p: Vec<DVec3> = positions.iter().map(|x| x.as_dvec3()).collect();
    let mut sum = vec![DVec3::ZERO; n];
    let mut degree = vec![0u32; n];
    let mut boundary_sum = vec![DVec3::ZERO; n];
    let mut boundary_degree = vec![0u32; n];
    let mut out: Vec<Vec3> = Vec::with_capacity(n + e.edges.len());
    let mut odd = Vec::with_capacity(e.edges.len());
    for (&[a, b], &[t0, t1]) in e.edges.iter().zip(&e.edge_triangles) {
        let (a, b) = (a as usize, b as usize);
        sum[a] += p[b];
        sum[b] += p[a];
        degree[a] += 1;
        degree[b] += 1;
        if t1 == u32::MAX {
            boundary_sum[a] += p[b];
            boundary_sum[b] += p[a];
            boundary_degree[a] += 1;
            boundary_degree[b] += 1;
            odd.push((p[a] + p[b]) * 0.5);
        } else {
            let opposite = |t: u32| {
                let tri = triangles[t as usize];
                tri.iter()
                    .copied()
                    .find(|&v| v as usize != a && v as usize != b)
                    .map_or(DVec3::ZERO, |v| p[v as usize])
            };
            odd.push((p[a] + p[b]) * 0.375 + (opposite(t0) + opposite(t1)) * 0.125);
        }
    }
    for v in 0..n {
        let moved = match (boundary_degree[v], degree[v]) {
            (_, 0) => p[v],
            (0, k) => {
                let k = f64::from(k);
                let beta = if k > 3.0 { 3.0 / (8.0 * k) } else { 3.0 / 16.0 };
                p[v] * (1.0 - k * beta) + sum[v] * beta
            }
            (2, _) => p[v] * 0.75 + boundary_sum[v] * 0.125,
            _ => p[v],
        };
        out.push(moved.as_vec3());
    }
    out.extend(odd.iter().map(|x| x.as_vec3()));
    (out, split_four(triangles, &e.triangle_edges, n as u32))
}

/// Area-weighted vertex normals of raw triangles.
pub(crate) fn vertex_normals_raw(positions: &[Vec3], triangles: &[[u32; 3]]) -> Vec<Vec3> {
    let mut sums = vec![DVec3::ZERO; positions.len()];
    for tri in triangles {
        let [a, b, c] = tri.map(|i| positions[i as usize].as_dvec3());
        let n = (b - a).cross(c - a);
        for &v in tri {
            sums[v as usize] += n;
        }
    }
    sums.iter()
        .map(|n| n.normalize_or_zero().as_vec3())
        .collect()
}

/// Moves every vertex along its normal by a Gaussian amount of standard deviation `sigma`.
pub(crate) fn noise_raw(positions: &mut [Vec3], normals: &[Vec3], sigma: f64, seed: u64) {
    let mut rng = Rng::new(seed);
    for (p, n) in positions.iter_mut().zip(normals) {
        *p += *n * (sigma * rng.normal()) as f32;
    }
}

/// Keeps the triangles `keep[t]`, then repairs what removal can break: every vertex where two
/// fans of kept triangles meet (more than two boundary sides) loses all its triangles, until none
/// is left; then only the largest edge-connected component stays (ties: the one with the smallest
/// triangle). Returns the compacted vertices and triangles and, for each new vertex, its old index.
pub(crate) fn keep_clean(
    positions: &[Vec3],
    triangles: &[[u32; 3]],
    keep: &mut [bool],
) -> (Vec<Vec3>, Vec<[u32; 3]>, Vec<u32>) {
    loop {
        let kept: Vec<u32> = (0..triangles.len() as u32)
            .filter(|&t| keep[t as usize])
            .collect();
        let sub: Vec<[u32; 3]> = kept.iter().map(|&t| triangles[t as usize]).collect();
        let e = edges_of(&sub);
        let mut boundary_degree = vec![0u32; positions.len()];
        for (&[a, b], &[_, t1]) in e.edges.iter().zip(&e.edge_triangles) {
            if t1 == u32::MAX {
                boundary_degree[a as usize] += 1;
                boundary_degree[b as usize] += 1;
            }
        }
        let mut changed = false;
        for (&t, tri) in kept.iter().zip(&sub) {
            if tri.iter().any(|&v| boundary_degree[v as usize] > 2) {
                keep[t as usize] = false;
                changed = true;
            }
        }
        if changed {
            continue;
        }
        // Largest component by union–find over shared edges.
        let mut parent: Vec<u32> = (0..sub.len() as u32).collect();
        fn find(parent: &mut [u32], mut x: u32) -> u32 {
            while parent[x as usize] != x {
                let g = parent[parent[x as usize] as usize];
                parent[x as usize] = g;
                x = g;
            }
            x
        }
        for &[t0, t1] in &e.edge_triangles {
            if t1 != u32::MAX {
                let (r0, r1) = (find(&mut parent, t0), find(&mut parent, t1));
                if r0 != r1 {
                    parent[r0.max(r1) as usize] = r0.min(r1);
                }
            }
        }
        let mut size = vec![0u32; sub.len()];
        for t in 0..sub.len() as u32 {
            let r = find(&mut parent, t);
            size[r as usize] += 1;
        }
        let best = (0..sub.len()).max_by_key(|&r| (size[r], std::cmp::Reverse(r)));
        let mut new_index = vec![u32::MAX; positions.len()];
        let mut old_of_new = Vec::new();
        let mut out_tris = Vec::with_capacity(sub.len());
        for (t, tri) in sub.iter().enumerate() {
            if Some(find(&mut parent, t as u32) as usize) != best {
                continue;
            }
            out_tris.push(tri.map(|v| {
                if new_index[v as usize] == u32::MAX {
                    new_index[v as usize] = old_of_new.len() as u32;
                    old_of_new.push(v);
                }
                new_index[v as usize]
            }));
        }
        let out_pos = old_of_new.iter().map(|&v| positions[v as usize]).collect();
        return (out_pos, out_tris, old_of_new);
    }
}

/// Marks the triangles whose centroid lies within `radius` of `centre` (Euclidean, in 3D) and
/// that are connected to the triangle nearest to `centre` through such triangles: one disc on
/// the surface, even where a fold of the surface (a nose) passes through the ball. Returns how
/// many triangles it marked (0 when no centroid is within `radius`).
pub(crate) fn mark_disc(
    positions: &[Vec3],
    triangles: &[[u32; 3]],
    adjacency: &Edges,
    centre: Vec3,
    radius: f32,
    remove: &mut [bool],
) -> usize {
    let centroid = |t: usize| {
        let tri = triangles[t];
        (positions[tri[0] as usize] + positions[tri[1] as usize] + positions[tri[2] as usize]) / 3.0
    };
    let r2 = radius * radius;
    let seed = (0..triangles.len())
        .map(|t| (centroid(t).distance_squared(centre), t))
        .min_by(|a, b| a.0.total_cmp(&b.0));
    let Some((d2, seed)) = seed else {
        return 0;
    };
    if d2 > r2 {
        return 0;
    }
    let mut seen = std::collections::HashSet::new();
    let mut stack = vec![seed];
    seen.insert(seed);
    while let Some(t) = stack.pop() {
        remove[t] = true;
        for &e in &adjacency.triangle_edges[t] {
            for &n in &adjacency.edge_triangles[e as usize] {
                let n = n as usize;
                if n != t
                    && n < triangles.len()
                    && centroid(n).distance_squared(centre) <= r2
                    && seen.insert(n)
                {
                    stack.push(n);
                }
            }
        }
    }
    seen.len()
}

/// Midpoint (1:4) subdivision: every edge gets its midpoint, every triangle becomes four. The old
/// vertices keep their indices; the new ones follow, one per edge in [`tissue_mesh::Topology`]'s
/// edge order. Shape and winding are unchanged.
///
/// # Errors
/// [`ScanError::Mesh`] if the result is not a valid mesh (it always is for a valid input, unless
/// the positions are so large that midpoints overflow `f32`).
pub fn subdivide_midpoint(mesh: &TriMesh) -> Result<TriMesh, ScanError> {
    let (p, t) = midpoint_raw(mesh.positions(), mesh.triangles());
    Ok(TriMesh::new(p, t)?)
}

/// One step of Loop subdivision (smooth; Warren's weights `β = 3/(8n)`, `3/16` for `n = 3`):
/// every triangle becomes four, old vertices move towards their neighbours, boundary curves are
/// smoothed by the cubic B-spline rules (a vertex on more than two boundary edges stays put).
///
/// # Errors
/// [`ScanError::Mesh`] if the result is not a valid mesh.
pub fn loop_subdivide(mesh: &TriMesh) -> Result<TriMesh, ScanError> {
    let (p, t) = loop_raw(mesh.positions(), mesh.triangles());
    Ok(TriMesh::new(p, t)?)
}

/// Moves every vertex along its area-weighted normal by a seeded Gaussian distance of standard
/// deviation `sigma` (in the mesh's unit). Deterministic: the same `seed` gives the same bits.
///
/// # Errors
/// [`ScanError::Mesh`] if the noise made a triangle degenerate (only when `sigma` is large
/// against the edges).
pub fn add_normal_noise(mesh: &TriMesh, sigma: f64, seed: u64) -> Result<TriMesh, ScanError> {
    let normals = mesh.vertex_normals();
    let mut p = mesh.positions().to_vec();
    noise_raw(&mut p, &normals, sigma, seed);
    Ok(TriMesh::new(p, mesh.triangles().to_vec())?)
}

/// A mesh with triangles removed, and where each of its vertices came from.
#[derive(Debug, Clone)]
pub struct Trimmed {
    /// The valid remaining surface (largest component, no vertex where two fans meet).
    pub mesh: TriMesh,
    /// For each vertex of `mesh`, its index in the mesh it was cut from.
    pub old_vertex: Vec<u32>,
}

/// Removes the triangles whose centroid lies within `diameter / 2` of `centre` and that are
/// connected to the triangle nearest to `centre` through such triangles (one disc), then repairs as [`remove_triangles`] does.
///
/// # Errors
/// [`ScanError::NothingLeft`] if no triangle remains; [`ScanError::Mesh`] if the rest is invalid.
pub fn punch_hole(mesh: &TriMesh, centre: Vec3, diameter: f32) -> Result<Trimmed, ScanError> {
    let mut remove = vec![false; mesh.triangle_count()];
    mark_disc(
        mesh.positions(),
        mesh.triangles(),
        &edges_of(mesh.triangles()),
        centre,
        0.5 * diameter,
        &mut remove,
    );
    remove_triangles(mesh, &remove)
}

/// Removes the triangles `remove[t]` (missing entries count as `false`), then repairs what removal
/// breaks: triangles at a vertex where two fans meet go too, and only the largest connected
/// component is kept. Unreferenced vertices are dropped.
///
/// # Errors
/// [`ScanError::NothingLeft`] if no triangle remains; [`ScanError::Mesh`] if the rest is invalid.
pub fn remove_triangles(mesh: &TriMesh, remove: &[bool]) -> Result<Trimmed, ScanError> {
    let mut keep: Vec<bool> = (0..mesh.triangle_count())
        .map(|t| !remove.get(t).copied().unwrap_or(false))
        .collect();
    let (p, t, old_vertex) = keep_clean(mesh.positions(), mesh.triangles(), &mut keep);
    if t.is_empty() {
        return Err(ScanError::NothingLeft);
    }
    Ok(Trimmed {
        mesh: TriMesh::new(p, t)?,
        old_vertex,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn subdivisions_keep_a_valid_sphere_and_quadruple_it() -> Result<(), ScanError> {
        let sphere = tissue_mesh::uv_sphere(16, 8, 1.0)?;
        let mid = subdivide_midpoint(&sphere)?;
        assert_eq!(mid.triangle_count(), 4 * sphere.triangle_count());
        assert!(mid.is_closed());
        let smooth = loop_subdivide(&sphere)?;
        assert!(smooth.is_closed());
        assert!(smooth.signed_volume()? > 0.0);
        assert!(
            (median_edge(&mid) - 0.5 * median_edge(&sphere)).abs() < 0.1 * median_edge(&sphere)
        );
        Ok(())
    }

    #[test]
    fn a_hole_in_a_grid_is_one_more_loop() -> Result<(), ScanError> {
        let grid = tissue_mesh::grid(40, 4.0)?;
        let centre = grid.bounding_box().center();
        let holed = punch_hole(&grid, centre, 1.0)?;
        assert_eq!(holed.mesh.topology().boundary_loops().len(), 2);
        assert_eq!(holed.mesh.topology().component_count(), 1);
        for (v, &old) in holed.old_vertex.iter().enumerate() {
            assert_eq!(holed.mesh.positions()[v], grid.positions()[old as usize]);
        }
        let noisy = add_normal_noise(&grid, 0.01, 3)?;
        assert_eq!(noisy, add_normal_noise(&grid, 0.01, 3)?);
        assert_ne!(noisy.positions(), grid.positions());
        Ok(())
    }
}
