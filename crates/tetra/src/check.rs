//! Input checks: what a surface must be before it can be filled with tetrahedra.

use glam::Vec3;
use tissue_mesh::{diagnose, MeshError, TriMesh, NO_TRIANGLE};

use crate::TetraError;

/// What the checks found out about a valid surface.
pub(crate) struct CheckedSurface {
    /// `used[v]`: vertex `v` is on a triangle.
    pub used: Vec<bool>,
    /// Signed volume (positive).
    pub volume: f64,
    /// Mean length of the surface's edges.
    pub mean_edge: f64,
}

/// Maps the first hard defect of raw data to a [`TetraError`].
pub(crate) fn check_raw(positions: &[Vec3], triangles: &[[u32; 3]]) -> Result<(), TetraError> {
    let mut used = vec![false; positions.len()];
    for t in triangles {
        for &v in t {
            if let Some(u) = used.get_mut(v as usize) {
                *u = true;
            }
        }
    }
    let count = used.iter().filter(|&&u| u).count();
    if count < 4
        && triangles
            .iter()
            .flatten()
            .all(|&v| (v as usize) < positions.len())
    {
        return Err(TetraError::TooFewPoints { vertices: count });
    }
    match diagnose(positions, triangles)
        .into_iter()
        .find(|d| !d.is_warning())
    {
        None => Ok(()),
        Some(MeshError::NonManifoldEdge { edge, triangles }) => {
            Err(TetraError::NonManifoldEdge { edge, triangles })
        }
        Some(MeshError::DegenerateTriangle {
            triangle,
            vertices,
            area,
        }) => Err(TetraError::DegenerateTriangle {
            triangle,
            vertices,
            area,
        }),
        Some(e) => Err(TetraError::InvalidSurface(e)),
    }
}

/// Checks that `surface` is closed, manifold at every vertex, without coincident vertices, and
/// encloses a positive volume.
pub(crate) fn check_surface(surface: &TriMesh) -> Result<CheckedSurface, TetraError> {
    let topo = surface.topology();
    let tris = surface.triangles();
    // Closed: name the first boundary edge and its triangle.
    if let Some(e) = topo
        .edge_triangles()
        .iter()
        .position(|t| t[1] == NO_TRIANGLE)
    {
        return Err(TetraError::OpenSurface {
            edge: topo.edges()[e],
            triangle: topo.edge_triangles()[e][0],
            boundary_edges: topo.boundary_edge_count(),
            loops: topo.boundary_loops().len(),
        });
    }
    let n = surface.vertex_count();
    let mut used = vec![false; n];
    for t in tris {
        for &v in t {
            used[v as usize] = true;
        }
    }
    let count = used.iter().filter(|&&u| u).count();
    if count < 4 {
        return Err(TetraError::TooFewPoints { vertices: count });
    }
    // Manifold vertices: walking across edges around v must visit all of v's triangles.
    for v in 0..n as u32 {
        let around = topo.vertex_triangles(v);
        if around.is_empty() {
            continue;
        }
        let start = around[0];
        let mut t = start;
        let mut steps = 0usize;
        loop {
            let tri = tris[t as usize];
            let Some(i) = tri.iter().position(|&x| x == v) else {
                break;
            };
            // Side i of [a, b, c] is ab, bc, ca: the edge from v to the next corner.
            let e = topo.triangle_edges()[t as usize][i] as usize;
            let [x, y] = topo.edge_triangles()[e];
            t = if x == t { y } else { x };
            steps += 1;
            if t == start || t == NO_TRIANGLE || steps > around.len() {
                break;
            }
        }
        if steps != around.len() {
            let fans = count_fans(surface, v);
            return Err(TetraError::NonManifoldVertex {
                vertex: v,
                triangles: around.len(),
                fans,
            });
        }
    }
    // Coincident vertices.
    let mut order: Vec<u32> = (0..n as u32).filter(|&v| used[v as usize]).collect();
    let pos = surface.positions();
    order.sort_unstable_by(|&a, &b| {
        let (p, q) = (pos[a as usize], pos[b as usize]);
        p.x.total_cmp(&q.x)
            .then(p.y.total_cmp(&q.y))
            .then(p.z.total_cmp(&q.z))
            .then(a.cmp(&b))
    });
    for w in order.windows(2) {
        let (p, q) = (pos[w[0] as usize], pos[w[1] as usize]);
        if p == q {
            return Err(TetraError::CoincidentVertices {
                first: w[0].min(w[1]),
                second: w[0].max(w[1]),
                position: p.to_array(),
            });
        }
    }
    let volume = surface
        .signed_volume()
        .map_err(TetraError::InvalidSurface)?;
    let bb = surface.bounding_box();
    let diagonal = f64::from((bb.max - bb.min).length());
    if volume.abs() <= 1e-9 * diagonal.powi(3) {
        return Err(TetraError::NoVolume { volume, diagonal });
    }
    if volume < 0.0 {
        return Err(TetraError::InsideOut { volume });
    }
    let edges = topo.edges();
    let total: f64 = edges
        .iter()
        .map(|&[a, b]| f64::from((pos[a as usize] - pos[b as usize]).length()))
        .sum();
    Ok(CheckedSurface {
        used,
        volume,
        mean_edge: total / edges.len().max(1) as f64,
    })
}

/// Number of edge-connected fans of triangles around `v`.
fn count_fans(surface: &TriMesh, v: u32) -> usize {
    let topo = surface.topology();
    let around = topo.vertex_triangles(v);
    let mut seen = vec![false; around.len()];
    let mut fans = 0;
    for s in 0..around.len() {
        if seen[s] {
            continue;
        }
        fans += 1;
        let mut stack = vec![s];
        seen[s] = true;
        while let Some(k) = stack.pop() {
            let t = around[k] as usize;
            for (i, &e) in topo.triangle_edges()[t].iter().enumerate() {
                let tri = surface.triangles()[t];
                // Only the two sides of t that touch v.
                if tri[i] != v && tri[(i + 1) % 3] != v {
                    continue;
                }
                for &u in &topo.edge_triangles()[e as usize] {
                    if let Some(j) = around.iter().position(|&x| x == u) {
                        if !seen[j] {
                            seen[j] = true;
                            stack.push(j);
                        }
                    }
                }
            }
        }
    }
    fans
}
