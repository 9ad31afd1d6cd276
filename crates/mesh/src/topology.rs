//! Edges, adjacency, boundary loops and connected components of a triangle surface.

/// Marks the missing second triangle of a boundary edge in [`Topology::edge_triangles`].
pub const NO_TRIANGLE: u32 = u32::MAX;

/// One side of one triangle, keyed by its undirected edge.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub(crate) struct HalfEdge {
    /// `(min << 32) | max` of the two vertex indices.
    pub key: u64,
    /// Triangle the side belongs to.
    pub triangle: u32,
    /// Which side of the triangle: 0 = (v0,v1), 1 = (v1,v2), 2 = (v2,v0).
    pub side: u8,
    /// `true` when the triangle traverses the edge from the smaller index to the larger.
    pub forward: bool,
}

impl HalfEdge {
    pub fn edge_of_key(key: u64) -> [u32; 2] {
        [(key >> 32) as u32, key as u32]
    }
}

/// All sides of the triangles `t` for which `keep(t)`, sorted by edge then triangle.
pub(crate) fn sorted_half_edges(
    triangles: &[[u32; 3]],
    keep: impl Fn(usize) -> bool,
) -> Vec<HalfEdge> {
    let mut half_edges = Vec::with_capacity(triangles.len() * 3);
    for (t, tri) in triangles.iter().enumerate() {
        if !keep(t) {
            continue;
        }
        for side in 0..3 {
            let (a, b) = (tri[side], tri[(side + 1) % 3]);
            let (lo, hi) = if a < b { (a, b) } else { (b, a) };
            half_edges.push(HalfEdge {
                key: (u64::from(lo) << 32) | u64::from(hi),
                triangle: t as u32,
                side: side as u8,
                forward: a < b,
            });
        }
    }
    half_edges.sort_unstable();
    half_edges
}

/// All sides of `triangles` (every index below `vertex_count`), sorted as [`sorted_half_edges`]
/// sorts them, by a counting sort on the edges' smaller vertex and small sorts within each
/// vertex's run: linear time, for the large surfaces of fine scans.
pub(crate) fn sorted_half_edges_by_vertex(
    vertex_count: usize,
    triangles: &[[u32; 3]],
) -> Vec<HalfEdge> {
    let mut offsets = vec![0u32; vertex_count + 1];
    for tri in triangles {
        for side in 0..3 {
            let lo = tri[side].min(tri[(side + 1) % 3]);
            offsets[lo as usize + 1] += 1;
        }
    }
    for v in 0..vertex_count {
        offsets[v + 1] += offsets[v];
    }
    let mut fill = offsets.clone();
    let empty = HalfEdge {
        key: 0,
        triangle: 0,
        side: 0,
        forward: false,
    };
    let mut half_edges = vec![empty; triangles.len() * 3];
    for (t, tri) in triangles.iter().enumerate() {
        for side in 0..3 {
            let (a, b) = (tri[side], tri[(side + 1) % 3]);
            let (lo, hi) = if a < b { (a, b) } else { (b, a) };
            let at = &mut fill[lo as usize];
            half_edges[*at as usize] = HalfEdge {
                key: (u64::from(lo) << 32) | u64::from(hi),
                triangle: t as u32,
                side: side as u8,
                forward: a < b,
            };
            *at += 1;
        }
    }
    for v in 0..vertex_count {
        half_edges[offsets[v] as usize..offsets[v + 1] as usize].sort_unstable();
    }
    half_edges
}

/// Surfaces of at least this many triangles are checked and built on two threads.
const PARALLEL_TRIANGLES: usize = 200_000;

/// `(first(), second())`: `first` on a second thread when `triangles` is at least
/// [`PARALLEL_TRIANGLES`] and the machine has more than one, else one after the other (also
/// when the thread cannot be started). The results do not depend on which.
pub(crate) fn both<A: Send, B>(
    triangles: usize,
    first: impl Fn() -> A + Sync,
    second: impl FnOnce() -> B,
) -> (A, B) {
    let parallel = triangles >= PARALLEL_TRIANGLES
        && std::thread::available_parallelism().is_ok_and(|n| n.get() > 1);
    if !parallel {
        return (first(), second());
    }
    std::thread::scope(|scope| {
        let spawned = std::thread::Builder::new()
            .name("tissue-mesh".into())
            .spawn_scoped(scope, &first);
        let b = second();
        let a = match spawned {
            // A panic of `first` is a bug: it goes on as it would have on this thread.
            Ok(handle) => handle
                .join()
                .unwrap_or_else(|panic| std::panic::resume_unwind(panic)),
            Err(_) => first(),
        };
        (a, b)
    })
}

/// Connectivity of a valid triangle surface (see [`crate::TriMesh`]'s invariants).
///
/// Edges are numbered in increasing order of `(smaller vertex, larger vertex)`; that numbering is
/// what [`Topology::edge_triangles`] and [`Topology::triangle_edges`] refer to.
#[derive(Debug, Clone, PartialEq)]
pub struct Topology {
    edges: Vec<[u32; 2]>,
    edge_triangles: Vec<[u32; 2]>,
    triangle_edges: Vec<[u32; 3]>,
    vertex_triangle_offsets: Vec<u32>,
    vertex_triangles: Vec<u32>,
    boundary_loops: Vec<Vec<u32>>,
    boundary_edge_count: usize,
    triangle_components: Vec<u32>,
    component_count: usize,
}

impl Topology {
    /// Builds the connectivity of triangles already known to be manifold and consistently wound.
    pub(crate) fn build(vertex_count: usize, triangles: &[[u32; 3]]) -> Topology {
        let half_edges = sorted_half_edges_by_vertex(vertex_count, triangles);
        Topology::from_half_edges(vertex_count, triangles, &half_edges)
    }

    /// [`Topology::build`] from the triangles' sides as [`sorted_half_edges`] gives them.
    pub(crate) fn from_half_edges(
        vertex_count: usize,
        triangles: &[[u32; 3]],
        half_edges: &[HalfEdge],
    ) -> Topology {
        let edges_of = || {
            let mut edges = Vec::with_capacity(half_edges.len() / 2 + 1);
            let mut edge_triangles = Vec::with_capacity(half_edges.len() / 2 + 1);
            let mut triangle_edges = vec![[0u32; 3]; triangles.len()];
            // Boundary sides directed as their triangle traverses them.
            let mut boundary: Vec<(u32, u32)> = Vec::new();
            for group in half_edges.chunk_by(|x, y| x.key == y.key) {
                let e = edges.len() as u32;
                edges.push(HalfEdge::edge_of_key(group[0].key));
                let second = group.get(1).map_or(NO_TRIANGLE, |h| h.triangle);
                edge_triangles.push([group[0].triangle, second]);
                for h in group {
                    triangle_edges[h.triangle as usize][h.side as usize] = e;
                }
                if group.len() == 1 {
                    let tri = triangles[group[0].triangle as usize];
                    let side = group[0].side as usize;
                    boundary.push((tri[side], tri[(side + 1) % 3]));
                }
            }
            (edges, edge_triangles, triangle_edges, boundary)
        };
        // Vertex -> triangles, compressed rows.
        let vertex_rows = || {
            let mut offsets = vec![0u32; vertex_count + 1];
            for tri in triangles {
                for &v in tri {
                    offsets[v as usize + 1] += 1;
                }
            }
            for v in 0..vertex_count {
                offsets[v + 1] += offsets[v];
            }
            let mut fill = offsets.clone();
            let mut vertex_triangles = vec![0u32; triangles.len() * 3];
            for (t, tri) in triangles.iter().enumerate() {
                for &v in tri {
                    vertex_triangles[fill[v as usize] as usize] = t as u32;
                    fill[v as usize] += 1;
                }
            }
            (offsets, vertex_triangles)
        };
        let ((offsets, vertex_triangles), (edges, edge_triangles, triangle_edges, boundary)) =
            both(triangles.len(), vertex_rows, edges_of);

        let boundary_edge_count = boundary.len();
        let boundary_loops = trace_loops(boundary);
        let (triangle_components, component_count) = components(triangles.len(), &edge_triangles);
        Topology {
            edges,
            edge_triangles,
            triangle_edges,
            vertex_triangle_offsets: offsets,
            vertex_triangles,
            boundary_loops,
            boundary_edge_count,
            triangle_components,
            component_count,
        }
    }

    /// Unique undirected edges, smaller vertex first, in increasing order.
    pub fn edges(&self) -> &[[u32; 2]] {
        &self.edges
    }

    /// For each edge, its one or two triangles; the second is [`NO_TRIANGLE`] on a boundary edge.
    pub fn edge_triangles(&self) -> &[[u32; 2]] {
        &self.edge_triangles
    }

    /// For each triangle `[a, b, c]`, the edge indices of its sides `ab`, `bc`, `ca`.
    pub fn triangle_edges(&self) -> &[[u32; 3]] {
        &self.triangle_edges
    }

    /// Triangles that contain vertex `v`, in increasing order (empty for an unreferenced vertex).
    ///
    /// # Panics
    /// If `v` is not a vertex of the mesh.
    pub fn vertex_triangles(&self, v: u32) -> &[u32] {
        let (a, b) = (
            self.vertex_triangle_offsets[v as usize] as usize,
            self.vertex_triangle_offsets[v as usize + 1] as usize,
        );
        &self.vertex_triangles[a..b]
    }

    /// Boundary loops as ordered vertex cycles (the edge from the last vertex back to the first
    /// closes each). A loop runs in the direction its triangles traverse their boundary edges, so
    /// seen from the side the normals point to, a disc's outer loop runs counter-clockwise.
    /// Loops are listed in increasing order of their first vertex, and each starts at its smallest
    /// unvisited vertex.
    pub fn boundary_loops(&self) -> &[Vec<u32>] {
        &self.boundary_loops
    }

    /// Number of edges with exactly one triangle.
    pub fn boundary_edge_count(&self) -> usize {
        self.boundary_edge_count
    }

    /// `true` when there is no boundary edge.
    pub fn is_closed(&self) -> bool {
        self.boundary_edge_count == 0
    }

    /// Number of edge-connected components of triangles.
    pub fn component_count(&self) -> usize {
        self.component_count
    }

    /// For each triangle, its component, numbered `0..component_count()` in order of each
    /// component's smallest triangle.
    pub fn triangle_components(&self) -> &[u32] {
        &self.triangle_components
    }

    /// Whether vertex `v` lies on a boundary edge.
    pub fn is_boundary_vertex(&self, v: u32) -> bool {
        self.boundary_loops.iter().any(|l| l.contains(&v))
    }

    /// A mask over vertices: `true` for vertices on a boundary edge.
    pub fn boundary_vertex_mask(&self, vertex_count: usize) -> Vec<bool> {
        let mut mask = vec![false; vertex_count];
        for l in &self.boundary_loops {
            for &v in l {
                if let Some(m) = mask.get_mut(v as usize) {
                    *m = true;
                }
            }
        }
        mask
    }
}

/// Chains directed boundary sides into cycles. On a consistently wound manifold surface every
/// boundary vertex has as many boundary sides leaving as entering, so each chain closes; at a
/// vertex touched by two loops (a "bowtie") the first unused side is taken.
fn trace_loops(mut sides: Vec<(u32, u32)>) -> Vec<Vec<u32>> {
    sides.sort_unstable();
    let mut used = vec![false; sides.len()];
    let mut loops = Vec::new();
    for start in 0..sides.len() {
        if used[start] {
            continue;
        }
        used[start] = true;
        let first = sides[start].0;
        let mut cycle = vec![first];
        let mut at = sides[start].1;
        while at != first {
            cycle.push(at);
            // The sides leaving `at` form a run in the sorted list.
            let lo = sides.partition_point(|s| s.0 < at);
            let next = (lo..sides.len())
                .take_while(|&i| sides[i].0 == at)
                .find(|&i| !used[i]);
            match next {
                Some(i) => {
                    used[i] = true;
                    at = sides[i].1;
                }
                None => break, // cannot happen on a valid mesh; keep the open chain
            }
        }
        loops.push(cycle);
    }
    loops
}

/// Union–find over triangles joined by shared edges.
fn components(triangle_count: usize, edge_triangles: &[[u32; 2]]) -> (Vec<u32>, usize) {
    let mut parent: Vec<u32> = (0..triangle_count as u32).collect();
    fn find(parent: &mut [u32], mut x: u32) -> u32 {
        while parent[x as usize] != x {
            let grand = parent[parent[x as usize] as usize];
            parent[x as usize] = grand;
            x = grand;
        }
        x
    }
    for &[a, b] in edge_triangles {
        if b != NO_TRIANGLE {
            let (ra, rb) = (find(&mut parent, a), find(&mut parent, b));
            if ra != rb {
                let (lo, hi) = if ra < rb { (ra, rb) } else { (rb, ra) };
                parent[hi as usize] = lo;
            }
        }
    }
    let mut label = vec![u32::MAX; triangle_count];
    let mut out = vec![0u32; triangle_count];
    let mut count = 0u32;
    for t in 0..triangle_count as u32 {
        let r = find(&mut parent, t);
        if label[r as usize] == u32::MAX {
            label[r as usize] = count;
            count += 1;
        }
        out[t as usize] = label[r as usize];
    }
    (out, count as usize)
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    /// The linear-time sort gives the comparison sort's order, on meshes whose triangles are
    /// numbered in any order.
    #[test]
    fn half_edges_by_vertex_are_sorted_as_by_comparison() {
        let sphere = crate::uv_sphere(12, 7, 1.0).unwrap();
        let grid = crate::grid(9, 2.0).unwrap();
        for mesh in [sphere, grid] {
            let mut triangles = mesh.triangles().to_vec();
            triangles.reverse();
            triangles.rotate_left(5);
            let expected = sorted_half_edges(&triangles, |_| true);
            let got = sorted_half_edges_by_vertex(mesh.vertex_count(), &triangles);
            assert_eq!(got, expected);
        }
    }

    /// A surface large enough to be checked and built on two threads has the topology a small
    /// one's counts say it must have.
    #[test]
    fn a_large_surface_built_on_two_threads_has_its_topology() {
        let n = 330u32;
        let grid = crate::grid(n, 10.0).unwrap();
        assert!(grid.triangle_count() >= PARALLEL_TRIANGLES);
        let topo = grid.topology();
        let cells = u64::from(n - 1);
        assert_eq!(
            topo.edges().len() as u64,
            2 * cells * u64::from(n) + cells * cells
        );
        assert_eq!(topo.boundary_loops().len(), 1);
        assert_eq!(topo.boundary_loops()[0].len() as u64, 4 * cells);
        assert_eq!(topo.component_count(), 1);
        let built = Topology::build(grid.vertex_count(), grid.triangles());
        assert_eq!(&built, topo);
        for v in [0, n * n / 2 + n / 2, n * n - 1] {
            for &t in topo.vertex_triangles(v) {
                assert!(grid.triangles()[t as usize].contains(&v));
            }
        }
        let (a, b) = both(PARALLEL_TRIANGLES, || 1 + 1, || 3);
        assert_eq!((a, b), (2, 3));
    }
}
