//! The validated tetrahedral mesh (the PBD trainer's volumetric body), its checks, face adjacency
//! and boundary surface.
//!
//! Volumes: a tetrahedron `(a, b, c, d)` has signed volume `V = (b − a)×(c − a)·(d − a) / 6`,
//! positive when `d` lies on the side of triangle `abc` from which `abc` is seen counter-clockwise
//! (the same convention as SPEC B's "old volume constraint" `C = ⅙(p₂−p₁)×(p₃−p₁)·(p₄−p₁) − V₀`).
//! Units are those of the positions: cm, cm³.

use glam::Vec3;

use crate::trimesh::{unreferenced_defects, vertex_defects};
use crate::{MeshError, TriMesh};

/// Marks a face with no neighbour (a boundary face) in [`TetMesh::neighbours`].
pub const NO_TET: u32 = u32::MAX;

/// A tetrahedron counts as flat (and is rejected as [`MeshError::InvertedTet`]) when six times its
/// signed volume is at most this fraction of its longest edge cubed — i.e. when it is inverted, or
/// its height over a face is below about `1e-7` of its longest edge, the resolution of an `f32`
/// coordinate. A tetrahedron that passes has faces that pass [`crate::ZERO_AREA_TOLERANCE`].
pub const ZERO_VOLUME_TOLERANCE: f64 = 1e-7;

/// The faces of a tetrahedron `[v0, v1, v2, v3]` as local vertex numbers: face `i` is the one
/// opposite vertex `i`, wound counter-clockwise seen from outside when the tetrahedron is
/// positively oriented (its normal points away from vertex `i`).
pub const TET_FACES: [[usize; 3]; 4] = [[1, 2, 3], [0, 3, 2], [0, 1, 3], [0, 2, 1]];

/// A tetrahedral mesh whose data have passed every hard check of [`diagnose_tets`].
///
/// Invariants (established by [`TetMesh::new`]):
/// - at least one vertex and one tetrahedron, fewer than `u32::MAX` vertices;
/// - every coordinate finite, every index `< vertex_count`;
/// - every tetrahedron positively oriented and not flat (see [`ZERO_VOLUME_TOLERANCE`]), no two
///   on the same four vertices;
/// - every triangular face shared by at most two tetrahedra;
/// - [`TetMesh::neighbours`] and [`TetMesh::boundary_faces`] describe exactly these tetrahedra.
///
/// Unreferenced vertices are allowed (a warning of [`diagnose_tets`]).
#[derive(Debug, Clone, PartialEq)]
pub struct TetMesh {
    positions: Vec<Vec3>,
    tets: Vec<[u32; 4]>,
    neighbours: Vec<[u32; 4]>,
    boundary_faces: Vec<[u32; 3]>,
}

/// One face of one tetrahedron, keyed by its sorted vertices.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
struct FaceSide {
    key: [u32; 3],
    tet: u32,
    /// Local face number, see [`TET_FACES`].
    face: u8,
}

/// All faces of the tetrahedra `t` with `keep(t)`, sorted by face, then tetrahedron.
fn sorted_faces(tets: &[[u32; 4]], keep: impl Fn(usize) -> bool) -> Vec<FaceSide> {
    let mut faces = Vec::with_capacity(tets.len() * 4);
    for (t, tet) in tets.iter().enumerate() {
        if !keep(t) {
            continue;
        }
        for (f, local) in TET_FACES.iter().enumerate() {
            let mut key = local.map(|i| tet[i]);
            key.sort_unstable();
            faces.push(FaceSide {
                key,
                tet: t as u32,
                face: f as u8,
            });
        }
    }
    faces.sort_unstable();
    faces
}

/// Six times the signed volume, `(b − a)×(c − a)·(d − a)`, in `f64`.
#[inline]
fn sixfold_volume(p: [Vec3; 4]) -> f64 {
    let [a, b, c, d] = p.map(|x| x.as_dvec3());
    (b - a).cross(c - a).dot(d - a)
}

fn longest_edge(p: [Vec3; 4]) -> f64 {
    let mut longest: f64 = 0.0;
    for i in 0..4 {
        for j in i + 1..4 {
            longest = longest.max((p[i].as_dvec3() - p[j].as_dvec3()).length_squared());
        }
    }
    longest.sqrt()
}

impl TetMesh {
    /// Validates the data and builds the face adjacency and the boundary faces. Returns the first
    /// hard defect that [`diagnose_tets`] finds; warnings (unreferenced vertices) do not stop it.
    pub fn new(positions: Vec<Vec3>, tets: Vec<[u32; 4]>) -> Result<Self, MeshError> {
        let _span =
            tracing::debug_span!("tetmesh_new", vertices = positions.len(), tets = tets.len())
                .entered();
        if let Some(err) = diagnose_tets(&positions, &tets)
            .into_iter()
            .find(|d| !d.is_warning())
        {
            return Err(err);
        }
        let faces = sorted_faces(&tets, |_| true);
        let mut neighbours = vec![[NO_TET; 4]; tets.len()];
        let mut boundary: Vec<(u32, u8)> = Vec::new();
        for group in faces.chunk_by(|x, y| x.key == y.key) {
            match group {
                [x] => boundary.push((x.tet, x.face)),
                [x, y] => {
                    neighbours[x.tet as usize][x.face as usize] = y.tet;
                    neighbours[y.tet as usize][y.face as usize] = x.tet;
                }
                _ => {} // rejected by diagnose_tets
            }
        }
        boundary.sort_unstable();
        let boundary_faces = boundary
            .into_iter()
            .map(|(t, f)| {
                let tet = tets[t as usize];
                TET_FACES[f as usize].map(|i| tet[i])
            })
            .collect();
        Ok(TetMesh {
            positions,
            tets,
            neighbours,
            boundary_faces,
        })
    }

    /// Vertex positions.
    pub fn positions(&self) -> &[Vec3] {
        &self.positions
    }

    /// Tetrahedra as vertex indices, each positively oriented.
    pub fn tets(&self) -> &[[u32; 4]] {
        &self.tets
    }

    /// Number of vertices (including unreferenced ones).
    pub fn vertex_count(&self) -> usize {
        self.positions.len()
    }

    /// Number of tetrahedra.
    pub fn tet_count(&self) -> usize {
        self.tets.len()
    }

    /// For each tetrahedron, the neighbour across each face: entry `i` is the tetrahedron sharing
    /// face `i` — the face opposite local vertex `i`, see [`TET_FACES`] — or [`NO_TET`] when that
    /// face is on the boundary.
    pub fn neighbours(&self) -> &[[u32; 4]] {
        &self.neighbours
    }

    /// The faces used by one tetrahedron only, wound counter-clockwise seen from outside (normals
    /// outward), in increasing order of (tetrahedron, local face).
    pub fn boundary_faces(&self) -> &[[u32; 3]] {
        &self.boundary_faces
    }

    /// The boundary faces as a [`TriMesh`] over the same vertex numbering: interior vertices
    /// become unreferenced vertices of the surface. For a mesh of one solid without cavities the
    /// surface is closed, with outward normals, and its signed volume equals [`TetMesh::volume`].
    ///
    /// # Errors
    /// When the boundary faces do not make a valid surface, e.g.
    /// [`MeshError::NonManifoldEdge`] where two parts of the mesh touch along an edge only.
    pub fn boundary_surface(&self) -> Result<TriMesh, MeshError> {
        TriMesh::new(self.positions.clone(), self.boundary_faces.clone())
    }

    /// Volume of each tetrahedron, `(b − a)×(c − a)·(d − a) / 6` (positive).
    pub fn tet_volumes(&self) -> Vec<f64> {
        self.tets
            .iter()
            .map(|tet| sixfold_volume(tet.map(|i| self.positions[i as usize])) / 6.0)
            .collect()
    }

    /// Total volume, summed in `f64`.
    pub fn volume(&self) -> f64 {
        let mut sum = 0.0;
        for tet in &self.tets {
            sum += sixfold_volume(tet.map(|i| self.positions[i as usize]));
        }
        sum / 6.0
    }

    /// Gives the data back.
    pub fn into_parts(self) -> (Vec<Vec3>, Vec<[u32; 4]>) {
        (self.positions, self.tets)
    }
}

/// Finds every defect of a would-be tetrahedral mesh, hard ones and warnings, each naming its
/// element. The list is ordered by kind — empty; non-finite coordinates
/// ([`MeshError::NonFiniteCoordinate`]); indices out of range ([`MeshError::TetIndexOutOfRange`]);
/// inverted or flat tetrahedra ([`MeshError::InvertedTet`], see [`ZERO_VOLUME_TOLERANCE`]);
/// duplicates ([`MeshError::DuplicateTet`]); faces of more than two tetrahedra
/// ([`MeshError::NonManifoldFace`]); unreferenced vertices ([`MeshError::UnreferencedVertex`],
/// warning) — and by index within a kind. An empty list means the data make a valid [`TetMesh`].
///
/// Tetrahedra with an out-of-range index are left out of the later checks; those with a repeated
/// vertex (reported as flat) and later duplicates are left out of the face check.
pub fn diagnose_tets(positions: &[Vec3], tets: &[[u32; 4]]) -> Vec<MeshError> {
    let _span = tracing::debug_span!(
        "diagnose_tets",
        vertices = positions.len(),
        tets = tets.len()
    )
    .entered();
    let Some(mut defects) = vertex_defects(positions, tets.len()) else {
        return vec![MeshError::Empty {
            vertices: positions.len(),
            elements: tets.len(),
        }];
    };
    if defects
        .first()
        .is_some_and(|d| matches!(d, MeshError::InvalidParameter { .. }))
    {
        return defects;
    }
    let n = positions.len() as u32;
    // `usable[t]`: indices in range; `in_faces[t]`: also four distinct vertices, not a duplicate.
    let mut usable = vec![true; tets.len()];
    for (t, tet) in tets.iter().enumerate() {
        if let Some(&index) = tet.iter().find(|&&i| i >= n) {
            usable[t] = false;
            defects.push(MeshError::TetIndexOutOfRange {
                tet: t as u32,
                index,
                vertex_count: n,
            });
        }
    }
    let mut in_faces = usable.clone();
    for (t, tet) in tets.iter().enumerate() {
        if !usable[t] {
            continue;
        }
        let repeated = (0..4).any(|i| (i + 1..4).any(|j| tet[i] == tet[j]));
        if repeated {
            in_faces[t] = false;
        }
        let p = tet.map(|i| positions[i as usize]);
        if p.iter().any(|x| !x.is_finite()) {
            continue; // reported above; its volume means nothing
        }
        let six_v = sixfold_volume(p);
        if repeated || six_v <= ZERO_VOLUME_TOLERANCE * longest_edge(p).powi(3) {
            defects.push(MeshError::InvertedTet {
                tet: t as u32,
                vertices: *tet,
                volume: six_v / 6.0,
            });
        }
    }
    // Duplicates: same vertex set, whatever the order.
    let mut keyed: Vec<([u32; 4], u32)> = tets
        .iter()
        .enumerate()
        .filter(|&(t, _)| in_faces[t])
        .map(|(t, tet)| {
            let mut k = *tet;
            k.sort_unstable();
            (k, t as u32)
        })
        .collect();
    keyed.sort_unstable();
    let mut duplicates = Vec::new();
    for group in keyed.chunk_by(|x, y| x.0 == y.0) {
        for &(_, t) in &group[1..] {
            duplicates.push(MeshError::DuplicateTet {
                tet: t,
                first: group[0].1,
                vertices: tets[t as usize],
            });
            in_faces[t as usize] = false;
        }
    }
    duplicates.sort_by_key(|d| match d {
        MeshError::DuplicateTet { tet, .. } => *tet,
        _ => 0,
    });
    defects.extend(duplicates);

    let faces = sorted_faces(tets, |t| in_faces[t]);
    for group in faces.chunk_by(|x, y| x.key == y.key) {
        if group.len() > 2 {
            defects.push(MeshError::NonManifoldFace {
                face: group[0].key,
                tets: group.iter().map(|f| f.tet).collect(),
            });
        }
    }

    unreferenced_defects(positions.len(), tets, &usable, &mut defects);
    defects
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unit_tet() -> (Vec<Vec3>, Vec<[u32; 4]>) {
        (
            vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z],
            vec![[0, 1, 2, 3]],
        )
    }

    #[test]
    fn faces_point_away_from_their_opposite_vertex() {
        let (p, t) = unit_tet();
        let tet = t[0];
        for (i, face) in TET_FACES.iter().enumerate() {
            let [a, b, c] = face.map(|k| p[tet[k] as usize]);
            let normal = (b - a).cross(c - a);
            assert!(
                normal.dot(p[tet[i] as usize] - a) < 0.0,
                "face {i} points inward"
            );
            assert!(!face.contains(&i));
        }
    }

    #[test]
    fn single_tet_is_all_boundary() {
        let (p, t) = unit_tet();
        let m = TetMesh::new(p, t).unwrap();
        assert_eq!(m.neighbours(), &[[NO_TET; 4]]);
        assert_eq!(m.boundary_faces().len(), 4);
        assert!((m.volume() - 1.0 / 6.0).abs() < 1e-15);
        let s = m.boundary_surface().unwrap();
        assert!(s.is_closed());
        assert_eq!(s.euler_characteristic(), 2);
    }

    #[test]
    fn two_tets_sharing_a_face_are_neighbours_across_it() {
        // Tet 0 = unit tet; tet 1 on the other side of face (1, 2, 3).
        let p = vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z, Vec3::ONE];
        let t = vec![[0, 1, 2, 3], [4, 1, 3, 2]];
        assert!(
            diagnose_tets(&p, &t).is_empty(),
            "{:?}",
            diagnose_tets(&p, &t)
        );
        let m = TetMesh::new(p, t).unwrap();
        // Face 0 of both is opposite their vertex 0 (0 and 4 respectively).
        assert_eq!(
            m.neighbours(),
            &[[1, NO_TET, NO_TET, NO_TET], [0, NO_TET, NO_TET, NO_TET]]
        );
        assert_eq!(m.boundary_faces().len(), 6);
    }

    #[test]
    fn flat_tet_is_rejected_even_with_tiny_positive_volume() {
        let p = vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::new(0.3, 0.3, 1e-9)];
        let d = diagnose_tets(&p, &[[0, 1, 2, 3]]);
        assert!(
            matches!(d[..], [MeshError::InvertedTet { tet: 0, .. }]),
            "{d:?}"
        );
        // Repeated vertex: flat, and kept out of the face checks.
        let d = diagnose_tets(&p, &[[0, 1, 2, 3], [0, 1, 1, 2]]);
        assert!(d
            .iter()
            .any(|e| matches!(e, MeshError::InvertedTet { tet: 1, .. })));
    }
}
