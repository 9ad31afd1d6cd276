//! Edge-length and angle figures of a triangle surface, measured against a target edge length.

use tissue_mesh::TriMesh;

/// Shape figures of a surface against a target edge length `L` (see [`MeshQuality::measure`]).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct MeshQuality {
    /// Number of vertices and triangles.
    pub vertices: usize,
    /// Number of triangles.
    pub triangles: usize,
    /// Shortest edge (mesh units).
    pub edge_min: f64,
    /// Mean edge length.
    pub edge_mean: f64,
    /// Longest edge.
    pub edge_max: f64,
    /// Fraction of edges with length in `[0.8·L, 4/3·L]` (the remesher's own band).
    pub edges_in_band: f64,
    /// Fraction of edges with length in `[0.7·L, 1.45·L]`.
    pub edges_in_wide_band: f64,
    /// Smallest interior angle of any triangle, degrees.
    pub min_angle_deg: f64,
    /// Largest interior angle of any triangle, degrees.
    pub max_angle_deg: f64,
    /// Mean over triangles of each triangle's smallest angle, degrees (60 for equilateral).
    pub mean_min_angle_deg: f64,
    /// Number of triangles whose smallest angle is below 20°.
    pub triangles_below_20_deg: usize,
    /// Number of triangles whose smallest angle is below 10°.
    pub triangles_below_10_deg: usize,
}

impl MeshQuality {
    /// Measures `mesh` against the target edge length `target_edge` (in `f64`).
    pub fn measure(mesh: &TriMesh, target_edge: f64) -> MeshQuality {
        let p = mesh.positions();
        let edges = mesh.topology().edges();
        let (mut min, mut max, mut sum) = (f64::INFINITY, 0.0f64, 0.0f64);
        let (mut band, mut wide) = (0usize, 0usize);
        let l = target_edge;
        for &[a, b] in edges {
            let len = (p[a as usize].as_dvec3() - p[b as usize].as_dvec3()).length();
            min = min.min(len);
            max = max.max(len);
            sum += len;
            band += usize::from(len >= 0.8 * l && len <= 4.0 / 3.0 * l);
            wide += usize::from(len >= 0.7 * l && len <= 1.45 * l);
        }
        let (mut amin, mut amax, mut asum) = (180.0f64, 0.0f64, 0.0f64);
        let (mut below20, mut below10) = (0, 0);
        for t in 0..mesh.triangle_count() {
            let c = mesh.corners(t).map(|x| x.as_dvec3());
            let mut tri_min = 180.0f64;
            for i in 0..3 {
                let u = c[(i + 1) % 3] - c[i];
                let v = c[(i + 2) % 3] - c[i];
                let angle = u.angle_between(v).to_degrees();
                let angle = if angle.is_finite() { angle } else { 0.0 };
                tri_min = tri_min.min(angle);
                amax = amax.max(angle);
            }
            amin = amin.min(tri_min);
            asum += tri_min;
            below20 += usize::from(tri_min < 20.0);
            below10 += usize::from(tri_min < 10.0);
        }
        let ne = edges.len().max(1) as f64;
        MeshQuality {
            vertices: mesh.vertex_count(),
            triangles: mesh.triangle_count(),
            edge_min: if edges.is_empty() { 0.0 } else { min },
            edge_mean: sum / ne,
            edge_max: max,
            edges_in_band: band as f64 / ne,
            edges_in_wide_band: wide as f64 / ne,
            min_angle_deg: amin,
            max_angle_deg: amax,
            mean_min_angle_deg: asum / mesh.triangle_count().max(1) as f64,
            triangles_below_20_deg: below20,
            triangles_below_10_deg: below10,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn equilateral_triangle_is_perfect() {
        let h = 3f32.sqrt() / 2.0;
        let m = TriMesh::new(
            vec![
                glam::Vec3::ZERO,
                glam::Vec3::X,
                glam::Vec3::new(0.5, h, 0.0),
            ],
            vec![[0, 1, 2]],
        )
        .unwrap();
        let q = MeshQuality::measure(&m, 1.0);
        assert!((q.min_angle_deg - 60.0).abs() < 1e-3);
        assert!((q.edge_mean - 1.0).abs() < 1e-6);
        assert_eq!(q.edges_in_band, 1.0);
        assert_eq!(q.triangles_below_20_deg, 0);
    }
}
