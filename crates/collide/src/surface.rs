//! A surface as collision detection sees it: its triangles, its unique edges (the springs), and
//! which triangle "owns" each edge, so that an edge is tested once against a given triangle of the
//! other surface however many triangle pairs bring it up.

use glam::Vec3A;
use tissue_bvh::Triangles;
use tissue_mesh::TriMesh;

use crate::{CollideError, Side};

/// Marks a side of a triangle whose edge another triangle owns, in [`Surface::owned_edges`].
pub const NOT_OWNED: u32 = u32::MAX;

/// The topology of one colliding surface, built once from a validated mesh.
///
/// Edge `e` (an index into `mesh().topology().edges()`) is *owned* by the first of its triangles
/// (`edge_triangles()[e][0]`, the smaller index). Detection tests edge `e` against triangle `t` of
/// the other surface only when it meets the pair (owner of `e`, `t`); since the owner contains the
/// edge, its box contains the edge's box, and every broad phase that finds all triangle pairs
/// with overlapping boxes finds each (edge, triangle) candidate exactly once.
#[derive(Debug, Clone, PartialEq)]
pub struct Surface {
    mesh: TriMesh,
    owned: Vec<[u32; 3]>,
}

impl Surface {
    /// The collision topology of `mesh` (its positions are only its initial state; detection takes
    /// positions per step).
    pub fn new(mesh: &TriMesh) -> Surface {
        let topo = mesh.topology();
        let owned = topo
            .triangle_edges()
            .iter()
            .enumerate()
            .map(|(t, sides)| {
                sides.map(|e| {
                    if topo.edge_triangles()[e as usize][0] == t as u32 {
                        e
                    } else {
                        NOT_OWNED
                    }
                })
            })
            .collect();
        Surface {
            mesh: mesh.clone(),
            owned,
        }
    }

    /// The mesh (its positions are the initial state).
    pub fn mesh(&self) -> &TriMesh {
        &self.mesh
    }

    /// Triangles as particle indices.
    pub fn triangles(&self) -> &[[u32; 3]] {
        self.mesh.triangles()
    }

    /// Unique edges as particle indices, smaller first (`Topology::edges`).
    pub fn edges(&self) -> &[[u32; 2]] {
        self.mesh.topology().edges()
    }

    /// Number of particles (vertices) the positions must have.
    pub fn vertex_count(&self) -> usize {
        self.mesh.vertex_count()
    }

    /// Number of triangles.
    pub fn triangle_count(&self) -> usize {
        self.mesh.triangle_count()
    }

    /// For triangle `t`, the edge indices of its sides `ab`, `bc`, `ca` that it owns, or
    /// [`NOT_OWNED`].
    #[inline]
    pub fn owned_edges(&self, t: u32) -> [u32; 3] {
        self.owned[t as usize]
    }

    /// This surface at `positions` (one per vertex).
    ///
    /// # Errors
    /// [`CollideError::ParticleCount`] when the length is not [`Surface::vertex_count`].
    pub fn view<'a>(
        &'a self,
        side: Side,
        positions: &'a [Vec3A],
    ) -> Result<SurfaceView<'a>, CollideError> {
        if positions.len() != self.vertex_count() {
            return Err(CollideError::ParticleCount {
                side,
                what: "positions",
                expected: self.vertex_count(),
                got: positions.len(),
            });
        }
        let triangles = Triangles::from_mesh(&self.mesh, positions)
            .map_err(|source| CollideError::Bvh { side, source })?;
        Ok(SurfaceView {
            surface: self,
            triangles,
            side,
        })
    }
}

/// A [`Surface`] at given particle positions, tagged with the side it plays in a pair.
#[derive(Debug, Clone, Copy)]
pub struct SurfaceView<'a> {
    surface: &'a Surface,
    triangles: Triangles<'a>,
    side: Side,
}

impl<'a> SurfaceView<'a> {
    /// The surface.
    pub fn surface(&self) -> &'a Surface {
        self.surface
    }

    /// The positions, one per vertex.
    pub fn positions(&self) -> &'a [Vec3A] {
        self.triangles.positions()
    }

    /// Which side of the pair this is.
    pub fn side(&self) -> Side {
        self.side
    }

    /// The triangles as hierarchy primitives.
    pub fn triangles(&self) -> &Triangles<'a> {
        &self.triangles
    }

    /// The corners of triangle `t`.
    #[inline]
    pub(crate) fn corners(&self, t: u32) -> [Vec3A; 3] {
        self.triangles.corners(t)
    }
}
