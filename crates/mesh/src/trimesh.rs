//! The validated triangle surface and the checks that admit it.

use std::sync::Arc;

use glam::Vec3;

use crate::topology::{sorted_half_edges, sorted_half_edges_by_vertex, HalfEdge, Topology};
use crate::MeshError;

/// A triangle counts as zero-area when twice its area is at most this fraction of its longest edge
/// squared, i.e. when its height is below `1e-7` of its longest edge: about the resolution of an
/// `f32` coordinate, so nothing a file stores can distinguish it from a line.
pub const ZERO_AREA_TOLERANCE: f64 = 1e-7;

/// A triangle surface whose data have passed every hard check of [`diagnose`].
///
/// Invariants (established by [`TriMesh::new`], kept by every method):
/// - at least one vertex and one triangle, fewer than `u32::MAX` vertices;
/// - every coordinate finite, every index `< vertex_count`;
/// - no zero-area triangle at construction (see [`ZERO_AREA_TOLERANCE`]), no two triangles on the
///   same three vertices;
/// - every edge in at most two triangles, and two triangles on an edge traverse it in opposite
///   directions (consistent winding), so normals point to one side;
/// - [`TriMesh::topology`] describes exactly these triangles.
///
/// Unreferenced vertices are allowed (a warning of [`diagnose`]); they have no triangles.
///
/// The triangles and the topology are shared between a mesh, its clones and its deformed states
/// ([`TriMesh::with_positions`]): a copy costs its positions only.
#[derive(Debug, Clone, PartialEq)]
pub struct TriMesh {
    positions: Vec<Vec3>,
    triangles: Arc<Vec<[u32; 3]>>,
    topology: Arc<Topology>,
}

impl TriMesh {
    /// Validates the data and builds the topology. Returns the first hard defect that
    /// [`diagnose`] finds; warnings (unreferenced vertices) do not stop it.
    pub fn new(positions: Vec<Vec3>, triangles: Vec<[u32; 3]>) -> Result<Self, MeshError> {
        let _span = tracing::debug_span!(
            "trimesh_new",
            vertices = positions.len(),
            triangles = triangles.len()
        )
        .entered();
        // The common case, a valid surface, in one pass and one sort; anything wrong is found
        // and named by `diagnose`.
        let topology = match valid_half_edges(&positions, &triangles) {
            Some(half_edges) => Topology::from_half_edges(positions.len(), &triangles, &half_edges),
            None => {
                if let Some(err) = diagnose(&positions, &triangles)
                    .into_iter()
                    .find(|d| !d.is_warning())
                {
                    return Err(err);
                }
                Topology::build(positions.len(), &triangles)
            }
        };
        Ok(TriMesh {
            positions,
            triangles: Arc::new(triangles),
            topology: Arc::new(topology),
        })
    }

    /// The same triangles with new vertex positions (a deformed state of this mesh). Checks the
    /// count and that every coordinate is finite; it does not re-check areas, since a deformed
    /// surface may legitimately pass through thin triangles.
    pub fn with_positions(&self, positions: Vec<Vec3>) -> Result<Self, MeshError> {
        if positions.len() != self.positions.len() {
            return Err(MeshError::PositionCount {
                expected: self.positions.len(),
                got: positions.len(),
            });
        }
        check_finite(&positions)?;
        Ok(TriMesh {
            positions,
            triangles: self.triangles.clone(),
            topology: self.topology.clone(),
        })
    }

    /// Vertex positions.
    pub fn positions(&self) -> &[Vec3] {
        &self.positions
    }

    /// Triangles as vertex indices, counter-clockwise seen from the side the normal points to.
    pub fn triangles(&self) -> &[[u32; 3]] {
        &self.triangles
    }

    /// Number of vertices (including unreferenced ones).
    pub fn vertex_count(&self) -> usize {
        self.positions.len()
    }

    /// Number of triangles.
    pub fn triangle_count(&self) -> usize {
        self.triangles.len()
    }

    /// Edges, adjacency, boundary loops and components.
    pub fn topology(&self) -> &Topology {
        &self.topology
    }

    /// `true` when no edge is a boundary edge.
    pub fn is_closed(&self) -> bool {
        self.topology.is_closed()
    }

    /// Euler characteristic `V − E + F`, counting every stored vertex.
    pub fn euler_characteristic(&self) -> i64 {
        self.positions.len() as i64 - self.topology.edges().len() as i64
            + self.triangles.len() as i64
    }

    /// The three corner positions of triangle `t`.
    ///
    /// # Panics
    /// If `t >= triangle_count()`.
    #[inline]
    pub fn corners(&self, t: usize) -> [Vec3; 3] {
        let [a, b, c] = self.triangles[t];
        [
            self.positions[a as usize],
            self.positions[b as usize],
            self.positions[c as usize],
        ]
    }

    /// Vertices used by no triangle, in increasing order.
    pub fn unreferenced_vertices(&self) -> Vec<u32> {
        (0..self.positions.len() as u32)
            .filter(|&v| self.topology.vertex_triangles(v).is_empty())
            .collect()
    }

    /// Gives the data back.
    pub fn into_parts(self) -> (Vec<Vec3>, Vec<[u32; 3]>) {
        let triangles = Arc::try_unwrap(self.triangles).unwrap_or_else(|shared| (*shared).clone());
        (self.positions, triangles)
    }
}

fn check_finite(positions: &[Vec3]) -> Result<(), MeshError> {
    match positions.iter().position(|p| !p.is_finite()) {
        None => Ok(()),
        Some(v) => Err(MeshError::NonFiniteCoordinate {
            vertex: v as u32,
            position: positions[v].to_array(),
        }),
    }
}

/// The sorted half-edges of data that pass every hard check of [`diagnose`] (at least one vertex
/// and triangle, fewer than `u32::MAX` vertices, finite coordinates, indices in range, no
/// zero-area or duplicate triangle, manifold edges, consistent winding), or `None` when one
/// fails: one pass over the triangles and one sort, for the common case of a valid surface.
fn valid_half_edges(positions: &[Vec3], triangles: &[[u32; 3]]) -> Option<Vec<HalfEdge>> {
    if positions.is_empty() || triangles.is_empty() || positions.len() >= u32::MAX as usize {
        return None;
    }
    if !positions.iter().all(|p| p.is_finite()) {
        return None;
    }
    let n = positions.len() as u32;
    if triangles.iter().any(|tri| {
        tri.iter().any(|&i| i >= n) || tri[0] == tri[1] || tri[1] == tri[2] || tri[2] == tri[0]
    }) {
        return None;
    }
    let areas_ok = || {
        triangles.iter().all(|tri| {
            let (doubled, longest_sq) =
                doubled_area_and_longest_edge_sq(tri.map(|i| positions[i as usize]));
            doubled > ZERO_AREA_TOLERANCE * longest_sq
        })
    };
    // On a large surface the areas are checked on a second thread while the sides are sorted
    // (each result is the same whatever the threads).
    let (areas, half_edges) = crate::topology::both(triangles.len(), areas_ok, || {
        sorted_half_edges_by_vertex(positions.len(), triangles)
    });
    if !areas {
        return None;
    }
    // Two triangles on the same three vertices `lo < mid < hi` share the edges `lo–mid` and
    // `lo–hi`, both filed under `lo`: a triangle pair seen twice among `lo`'s edges is a
    // duplicate. The pairs of the current smaller vertex:
    let mut pairs: Vec<(u32, u32)> = Vec::new();
    let mut current = u32::MAX;
    for group in half_edges.chunk_by(|x, y| x.key == y.key) {
        let [lo, _] = HalfEdge::edge_of_key(group[0].key);
        if lo != current {
            current = lo;
            pairs.clear();
        }
        match group {
            [_] => {}
            [x, y] => {
                // Same direction: inconsistent winding.
                if x.forward == y.forward {
                    return None;
                }
                let pair = (x.triangle.min(y.triangle), x.triangle.max(y.triangle));
                if pairs.contains(&pair) {
                    return None;
                }
                pairs.push(pair);
            }
            _ => return None,
        }
    }
    Some(half_edges)
}

/// Twice the area of a triangle and its longest edge squared, in `f64`.
pub(crate) fn doubled_area_and_longest_edge_sq(p: [Vec3; 3]) -> (f64, f64) {
    let [a, b, c] = p.map(|x| x.as_dvec3());
    let (ab, bc, ca) = (b - a, c - b, a - c);
    let cross = ab.cross(-ca);
    let longest = ab
        .length_squared()
        .max(bc.length_squared())
        .max(ca.length_squared());
    (cross.length(), longest)
}

/// Finds every defect of a would-be triangle surface, hard ones and warnings, each naming its
/// element. The list is ordered by kind (coordinates, indices, areas, duplicates, edges, winding,
/// unreferenced vertices) and by index within a kind. An empty list means the data make a valid
/// [`TriMesh`].
///
/// Triangles with an out-of-range index are left out of the later checks, and so are zero-area and
/// duplicate triangles from the edge checks, so that one bad triangle is reported once.
pub fn diagnose(positions: &[Vec3], triangles: &[[u32; 3]]) -> Vec<MeshError> {
    let Some(mut defects) = vertex_defects(positions, triangles.len()) else {
        return vec![MeshError::Empty {
            vertices: positions.len(),
            elements: triangles.len(),
        }];
    };
    if defects
        .first()
        .is_some_and(|d| matches!(d, MeshError::InvalidParameter { .. }))
    {
        return defects;
    }
    let n = positions.len() as u32;
    // `usable[t]`: indices in range; `in_surface[t]`: also non-degenerate and not a duplicate.
    let mut usable = vec![true; triangles.len()];
    for (t, tri) in triangles.iter().enumerate() {
        if let Some(&index) = tri.iter().find(|&&i| i >= n) {
            usable[t] = false;
            defects.push(MeshError::IndexOutOfRange {
                triangle: t as u32,
                index,
                vertex_count: n,
            });
        }
    }
    let mut in_surface = usable.clone();
    for (t, tri) in triangles.iter().enumerate() {
        if !usable[t] {
            continue;
        }
        let p = tri.map(|i| positions[i as usize]);
        if p.iter().any(|x| !x.is_finite()) {
            continue; // reported above; its area means nothing
        }
        let (doubled, longest_sq) = doubled_area_and_longest_edge_sq(p);
        let repeated = tri[0] == tri[1] || tri[1] == tri[2] || tri[2] == tri[0];
        if repeated || doubled <= ZERO_AREA_TOLERANCE * longest_sq {
            in_surface[t] = false;
            defects.push(MeshError::DegenerateTriangle {
                triangle: t as u32,
                vertices: *tri,
                area: 0.5 * doubled,
            });
        }
    }
    // Duplicates: same vertex set, whatever the order.
    let mut keyed: Vec<([u32; 3], u32)> = triangles
        .iter()
        .enumerate()
        .filter(|&(t, _)| in_surface[t])
        .map(|(t, tri)| {
            let mut k = *tri;
            k.sort_unstable();
            (k, t as u32)
        })
        .collect();
    keyed.sort_unstable();
    let mut duplicates = Vec::new();
    for w in keyed.chunk_by(|x, y| x.0 == y.0) {
        for &(_, t) in &w[1..] {
            duplicates.push(MeshError::DuplicateTriangle {
                triangle: t,
                first: w[0].1,
                vertices: triangles[t as usize],
            });
            in_surface[t as usize] = false;
        }
    }
    duplicates.sort_by_key(|d| match d {
        MeshError::DuplicateTriangle { triangle, .. } => *triangle,
        _ => 0,
    });
    defects.extend(duplicates);

    let half_edges = sorted_half_edges(triangles, |t| in_surface[t]);
    let mut winding = Vec::new();
    for group in half_edges.chunk_by(|x, y| x.key == y.key) {
        let edge = HalfEdge::edge_of_key(group[0].key);
        match group {
            [_] => {}
            [x, y] => {
                if x.forward == y.forward {
                    winding.push(MeshError::InconsistentWinding {
                        edge,
                        triangles: [x.triangle, y.triangle],
                    });
                }
            }
            _ => defects.push(MeshError::NonManifoldEdge {
                edge,
                triangles: group.iter().map(|h| h.triangle).collect(),
            }),
        }
    }
    defects.extend(winding);

    unreferenced_defects(positions.len(), triangles, &usable, &mut defects);
    defects
}

/// The checks every mesh's vertices get: `None` when there are no vertices or no elements (the
/// caller reports [`MeshError::Empty`]); otherwise a too-large vertex count (alone — nothing else
/// is checked then) or every non-finite coordinate.
pub(crate) fn vertex_defects(positions: &[Vec3], elements: usize) -> Option<Vec<MeshError>> {
    if positions.is_empty() || elements == 0 {
        return None;
    }
    if positions.len() >= u32::MAX as usize {
        return Some(vec![MeshError::InvalidParameter {
            what: format!(
                "{} vertices: a mesh holds fewer than 2^32 - 1",
                positions.len()
            ),
        }]);
    }
    Some(
        positions
            .iter()
            .enumerate()
            .filter(|(_, p)| !p.is_finite())
            .map(|(v, p)| MeshError::NonFiniteCoordinate {
                vertex: v as u32,
                position: p.to_array(),
            })
            .collect(),
    )
}

/// Appends a warning for every vertex that no usable element (`usable[e]`) refers to.
pub(crate) fn unreferenced_defects<const K: usize>(
    vertex_count: usize,
    elements: &[[u32; K]],
    usable: &[bool],
    defects: &mut Vec<MeshError>,
) {
    let mut referenced = vec![false; vertex_count];
    for (element, _) in elements.iter().zip(usable).filter(|(_, &u)| u) {
        for &i in element {
            referenced[i as usize] = true;
        }
    }
    defects.extend(
        referenced
            .iter()
            .enumerate()
            .filter(|(_, &r)| !r)
            .map(|(v, _)| MeshError::UnreferencedVertex { vertex: v as u32 }),
    );
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The one-pass check agrees with `diagnose`: a duplicate in either orientation (the
    /// opposite one passes every edge check), among other triangles, is refused as a duplicate.
    #[test]
    fn duplicates_in_either_orientation_are_refused_as_diagnose_names_them() {
        let grid = crate::grid(5, 1.0).unwrap();
        for flip in [false, true] {
            let mut triangles = grid.triangles().to_vec();
            let [a, b, c] = triangles[7];
            triangles.push(if flip { [a, c, b] } else { [b, c, a] });
            let expected = diagnose(grid.positions(), &triangles)
                .into_iter()
                .find(|d| !d.is_warning());
            assert!(
                matches!(expected, Some(MeshError::DuplicateTriangle { .. })),
                "{expected:?}"
            );
            let got = TriMesh::new(grid.positions().to_vec(), triangles).err();
            assert_eq!(got, expected);
        }
        let again = TriMesh::new(grid.positions().to_vec(), grid.triangles().to_vec()).unwrap();
        assert_eq!(again, grid);
    }
    /// Two triangles making the unit square, normal +z.
    fn square() -> (Vec<Vec3>, Vec<[u32; 3]>) {
        (
            vec![
                Vec3::new(0.0, 0.0, 0.0),
                Vec3::new(1.0, 0.0, 0.0),
                Vec3::new(1.0, 1.0, 0.0),
                Vec3::new(0.0, 1.0, 0.0),
            ],
            vec![[0, 1, 2], [0, 2, 3]],
        )
    }

    #[test]
    fn valid_square_has_no_defects() {
        let (p, t) = square();
        assert!(diagnose(&p, &t).is_empty());
        let m = TriMesh::new(p, t).unwrap();
        assert_eq!(m.euler_characteristic(), 1);
        assert!(!m.is_closed());
    }

    #[test]
    fn empty_mesh_is_an_error() {
        assert!(matches!(
            TriMesh::new(vec![], vec![]),
            Err(MeshError::Empty { .. })
        ));
    }

    #[test]
    fn with_positions_checks_count_and_finiteness() {
        let (p, t) = square();
        let m = TriMesh::new(p.clone(), t).unwrap();
        assert!(matches!(
            m.with_positions(p[..3].to_vec()),
            Err(MeshError::PositionCount {
                expected: 4,
                got: 3
            })
        ));
        let mut bad = p.clone();
        bad[2].z = f32::NAN;
        assert!(matches!(
            m.with_positions(bad),
            Err(MeshError::NonFiniteCoordinate { vertex: 2, .. })
        ));
        let mut moved = p;
        moved[2].z = 0.5;
        assert_eq!(m.with_positions(moved).unwrap().positions()[2].z, 0.5);
    }
}
