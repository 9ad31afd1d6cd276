//! Vertex → neighbour adjacency in compressed rows, built from a mesh's unique edges (used by
//! the offset's normal averaging and the distance-to-border search).

use tissue_mesh::TriMesh;

/// For each vertex, the vertices it shares an edge with.
pub(crate) struct VertexNeighbours {
    offsets: Vec<usize>,
    neighbours: Vec<u32>,
}

impl VertexNeighbours {
    /// The neighbours of every vertex of `mesh`.
    pub(crate) fn of(mesh: &TriMesh) -> Self {
        let n = mesh.vertex_count();
        let edges = mesh.topology().edges();
        let mut offsets = vec![0usize; n + 1];
        for &[a, b] in edges {
            offsets[a as usize + 1] += 1;
            offsets[b as usize + 1] += 1;
        }
        for v in 0..n {
            offsets[v + 1] += offsets[v];
        }
        let mut fill = offsets.clone();
        let mut neighbours = vec![0u32; offsets[n]];
        for &[a, b] in edges {
            neighbours[fill[a as usize]] = b;
            fill[a as usize] += 1;
            neighbours[fill[b as usize]] = a;
            fill[b as usize] += 1;
        }
        VertexNeighbours {
            offsets,
            neighbours,
        }
    }

    /// The neighbours of vertex `v`.
    pub(crate) fn of_vertex(&self, v: u32) -> &[u32] {
        &self.neighbours[self.offsets[v as usize]..self.offsets[v as usize + 1]]
    }
}
