//! Element quality of a tetrahedral mesh: dihedral angles, radius ratio, volumes, and how well
//! its boundary matches a surface.

use std::fmt;

use glam::DVec3;
use tissue_mesh::{TetMesh, TriMesh};

/// Number of bins of [`QualityReport::radius_ratio_histogram`].
pub const RADIUS_RATIO_BINS: usize = 10;

/// Quality figures of a tetrahedral mesh (see [`QualityReport::measure`]).
///
/// The radius ratio of a tetrahedron is `3 r / R` (`r` inradius, `R` circumradius): 1 for the
/// regular tetrahedron, 0 for a flat one. Dihedral angles are the interior angles between two
/// faces along their shared edge: 70.53° everywhere for the regular tetrahedron.
#[derive(Debug, Clone, PartialEq)]
pub struct QualityReport {
    /// Number of tetrahedra.
    pub tets: usize,
    /// Number of nodes, `surface_nodes + interior_nodes`.
    pub nodes: usize,
    /// Nodes that come from the surface (the first ones).
    pub surface_nodes: usize,
    /// The other nodes.
    pub interior_nodes: usize,
    /// Smallest dihedral angle, degrees.
    pub min_dihedral_deg: f64,
    /// Largest dihedral angle, degrees.
    pub max_dihedral_deg: f64,
    /// Tetrahedra with a dihedral angle under 5°.
    pub tets_under_5_deg: usize,
    /// Smallest radius ratio.
    pub min_radius_ratio: f64,
    /// Mean radius ratio.
    pub mean_radius_ratio: f64,
    /// Tetrahedra per radius-ratio bin: bin `i` holds ratios in `[i/10, (i+1)/10)` (1.0 in the
    /// last).
    pub radius_ratio_histogram: [usize; RADIUS_RATIO_BINS],
    /// Smallest tetrahedron volume (cm³).
    pub min_volume: f64,
    /// Total volume of the tetrahedra (cm³).
    pub volume: f64,
    /// Volume enclosed by the surface (its signed volume, cm³).
    pub surface_volume: f64,
    /// `volume / surface_volume`.
    pub volume_ratio: f64,
    /// Number of surface triangles.
    pub surface_triangles: usize,
    /// Surface triangles that are boundary faces of the tetrahedral mesh with the same
    /// orientation (outward).
    pub surface_triangles_recovered: usize,
    /// Boundary faces of the tetrahedral mesh.
    pub boundary_faces: usize,
}

/// Dihedral angles (radians) and radius ratio of a positively oriented tetrahedron.
pub(crate) fn tet_quality(p: [DVec3; 4]) -> ([f64; 6], f64, f64) {
    let [a, b, c, d] = p;
    let six_v = (b - a).cross(c - a).dot(d - a);
    // Outward face normals (unnormalised), face i opposite vertex i.
    let n = [
        (c - b).cross(d - b),
        (d - a).cross(c - a),
        (b - a).cross(d - a),
        (c - a).cross(b - a),
    ];
    let area2: [f64; 4] = n.map(|x| x.length());
    // Edge (i, j) is shared by the faces opposite the other two vertices k, l.
    const PAIRS: [(usize, usize); 6] = [(2, 3), (1, 3), (1, 2), (0, 3), (0, 2), (0, 1)];
    let mut dihedral = [0.0; 6];
    for (e, &(k, l)) in PAIRS.iter().enumerate() {
        let cos = (n[k].dot(n[l]) / (area2[k] * area2[l])).clamp(-1.0, 1.0);
        dihedral[e] = std::f64::consts::PI - cos.acos();
    }
    // r = 3V / A = six_v / (sum of doubled areas); R from the circumcentre.
    let r_in = six_v / area2.iter().sum::<f64>();
    let (u, v, w) = (b - a, c - a, d - a);
    let centre = (u.length_squared() * v.cross(w)
        + v.length_squared() * w.cross(u)
        + w.length_squared() * u.cross(v))
        / (2.0 * six_v);
    let r_circ = centre.length();
    let ratio = if r_circ > 0.0 && r_circ.is_finite() {
        (3.0 * r_in / r_circ).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (dihedral, ratio, six_v / 6.0)
}

impl QualityReport {
    /// Measures `mesh` against the closed `surface` it was made from: the surface's vertices are
    /// taken to be the first `surface.vertex_count()` nodes (as [`crate::tetrahedralize`] makes
    /// them, and as TetGen's `-Y` keeps them).
    ///
    /// If `surface` is open its volume is `NaN`.
    pub fn measure(mesh: &TetMesh, surface: &TriMesh) -> Self {
        let surface_volume = surface.signed_volume().unwrap_or(f64::NAN);
        let surface_nodes = surface.vertex_count().min(mesh.vertex_count());
        let mut keys: Vec<[u32; 3]> = mesh
            .boundary_faces()
            .iter()
            .map(|&f| canonical(f))
            .collect();
        keys.sort_unstable();
        let recovered = surface
            .triangles()
            .iter()
            .filter(|&&t| keys.binary_search(&canonical(t)).is_ok())
            .count();
        Self::build(
            mesh,
            surface_nodes,
            surface_volume,
            surface.triangle_count(),
            recovered,
        )
    }

    /// Measures `mesh` on its own: its boundary faces play the surface (all recovered), nodes
    /// on a boundary face count as surface nodes, and the surface volume is the boundary's
    /// divergence-theorem volume. For meshes from other tools (e.g. TetGen files).
    pub fn of_mesh(mesh: &TetMesh) -> Self {
        let mut on_boundary = vec![false; mesh.vertex_count()];
        let mut sixfold = 0.0;
        for f in mesh.boundary_faces() {
            for &v in f {
                on_boundary[v as usize] = true;
            }
            let [a, b, c] = f.map(|v| mesh.positions()[v as usize].as_dvec3());
            sixfold += a.dot(b.cross(c));
        }
        let surface_nodes = on_boundary.iter().filter(|&&b| b).count();
        let faces = mesh.boundary_faces().len();
        Self::build(mesh, surface_nodes, sixfold / 6.0, faces, faces)
    }

    fn build(
        mesh: &TetMesh,
        surface_nodes: usize,
        surface_volume: f64,
        surface_triangles: usize,
        recovered: usize,
    ) -> Self {
        let _span = tracing::debug_span!("quality", tets = mesh.tet_count()).entered();
        let mut min_d = f64::INFINITY;
        let mut max_d = f64::NEG_INFINITY;
        let mut under5 = 0;
        let mut hist = [0usize; RADIUS_RATIO_BINS];
        let mut min_rr = f64::INFINITY;
        let mut sum_rr = 0.0;
        let mut min_v = f64::INFINITY;
        let mut volume = 0.0;
        let five = 5f64.to_radians();
        for tet in mesh.tets() {
            let p = tet.map(|i| mesh.positions()[i as usize].as_dvec3());
            let (d, rr, v) = tet_quality(p);
            let lo = d.iter().copied().fold(f64::INFINITY, f64::min);
            let hi = d.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            min_d = min_d.min(lo);
            max_d = max_d.max(hi);
            if lo < five {
                under5 += 1;
            }
            hist[((rr * RADIUS_RATIO_BINS as f64) as usize).min(RADIUS_RATIO_BINS - 1)] += 1;
            min_rr = min_rr.min(rr);
            sum_rr += rr;
            min_v = min_v.min(v);
            volume += v;
        }
        let tets = mesh.tet_count();
        QualityReport {
            tets,
            nodes: mesh.vertex_count(),
            surface_nodes,
            interior_nodes: mesh.vertex_count() - surface_nodes,
            min_dihedral_deg: min_d.to_degrees(),
            max_dihedral_deg: max_d.to_degrees(),
            tets_under_5_deg: under5,
            min_radius_ratio: min_rr,
            mean_radius_ratio: sum_rr / tets.max(1) as f64,
            radius_ratio_histogram: hist,
            min_volume: min_v,
            volume,
            surface_volume,
            volume_ratio: volume / surface_volume,
            surface_triangles,
            surface_triangles_recovered: recovered,
            boundary_faces: mesh.boundary_faces().len(),
        }
    }
}

/// A triangle rotated so that its smallest vertex comes first (orientation kept).
fn canonical(t: [u32; 3]) -> [u32; 3] {
    let [a, b, c] = t;
    if a <= b && a <= c {
        [a, b, c]
    } else if b <= a && b <= c {
        [b, c, a]
    } else {
        [c, a, b]
    }
}

impl fmt::Display for QualityReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "{} tets, {} nodes ({} surface, {} interior)",
            self.tets, self.nodes, self.surface_nodes, self.interior_nodes
        )?;
        writeln!(
            f,
            "volume {:.6} vs surface {:.6} (ratio {:.4}), smallest tet {:.3e}",
            self.volume, self.surface_volume, self.volume_ratio, self.min_volume
        )?;
        writeln!(
            f,
            "dihedral angles {:.2}°–{:.2}° ({} tets under 5°)",
            self.min_dihedral_deg, self.max_dihedral_deg, self.tets_under_5_deg
        )?;
        writeln!(
            f,
            "surface triangles recovered as boundary faces: {} of {} ({:.2} %), {} boundary faces",
            self.surface_triangles_recovered,
            self.surface_triangles,
            100.0 * self.surface_triangles_recovered as f64 / self.surface_triangles.max(1) as f64,
            self.boundary_faces
        )?;
        write!(
            f,
            "radius ratio min {:.4}, mean {:.3}; histogram [0,1] in {} bins:",
            self.min_radius_ratio, self.mean_radius_ratio, RADIUS_RATIO_BINS
        )?;
        for n in self.radius_ratio_histogram {
            write!(f, " {n}")?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn regular_tet_is_perfect() {
        let p = [
            DVec3::new(1.0, 1.0, 1.0),
            DVec3::new(1.0, -1.0, -1.0),
            DVec3::new(-1.0, 1.0, -1.0),
            DVec3::new(-1.0, -1.0, 1.0),
        ];
        let p = if (p[1] - p[0]).cross(p[2] - p[0]).dot(p[3] - p[0]) < 0.0 {
            [p[1], p[0], p[2], p[3]]
        } else {
            p
        };
        let (d, rr, v) = tet_quality(p);
        for a in d {
            assert!(
                (a.to_degrees() - 70.528_779).abs() < 1e-5,
                "{}",
                a.to_degrees()
            );
        }
        assert!((rr - 1.0).abs() < 1e-12);
        assert!((v - 8.0 / 3.0).abs() < 1e-12);
    }

    #[test]
    fn corner_tet_has_right_and_acute_dihedrals() {
        let p = [DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z];
        let (d, rr, _) = tet_quality(p);
        let mut deg: Vec<f64> = d.iter().map(|a| a.to_degrees()).collect();
        deg.sort_by(f64::total_cmp);
        // Three right angles at the corner edges, three of acos(1/√3) = 54.74° at the far ones.
        for a in &deg[..3] {
            assert!((a - 54.735_61).abs() < 1e-4, "{deg:?}");
        }
        for a in &deg[3..] {
            assert!((a - 90.0).abs() < 1e-9, "{deg:?}");
        }
        assert!(rr > 0.5 && rr < 0.8);
    }
}
