//! Particle masses from triangle areas (eq. 2) and tetrahedron volumes (eq. 1).

use tissue_mesh::{TetMesh, TriMesh};

use crate::MssError;

fn check_total(total_mass: f64) -> Result<(), MssError> {
    if total_mass.is_finite() && total_mass > 0.0 {
        Ok(())
    } else {
        Err(MssError::InvalidParameter {
            name: "total_mass",
            value: total_mass,
            expected: "positive and finite",
        })
    }
}

/// Eq. (2): `mᵢ = M · Σ_{t∋i} a_t / (3A)`: each triangle gives a third of its share of the total
/// mass `M` (g) to each corner. Unreferenced vertices get 0 (give them a mass of their own before
/// building particles, or leave them out). The masses sum to `M` up to rounding.
pub fn masses_from_triangles(mesh: &TriMesh, total_mass: f64) -> Result<Vec<f32>, MssError> {
    check_total(total_mass)?;
    let areas = mesh.triangle_areas();
    let total: f64 = areas.iter().sum();
    let mut m = vec![0.0f64; mesh.vertex_count()];
    for (tri, a) in mesh.triangles().iter().zip(&areas) {
        for &v in tri {
            m[v as usize] += total_mass * a / (3.0 * total);
        }
    }
    Ok(m.into_iter().map(|x| x as f32).collect())
}

/// Eq. (1): `mᵢ = M · Σ_{t∋i} v_t / (4V)` — each tetrahedron gives a quarter of its share to each
/// corner, so the masses sum to `M`. (The thesis prints `3V`, which would make them sum to `4M/3`;
/// a tetrahedron has four corners.)
pub fn masses_from_tets(mesh: &TetMesh, total_mass: f64) -> Result<Vec<f32>, MssError> {
    check_total(total_mass)?;
    let volumes = mesh.tet_volumes();
    let total: f64 = volumes.iter().sum();
    let mut m = vec![0.0f64; mesh.vertex_count()];
    for (tet, v) in mesh.tets().iter().zip(&volumes) {
        for &i in tet {
            m[i as usize] += total_mass * v / (4.0 * total);
        }
    }
    Ok(m.into_iter().map(|x| x as f32).collect())
}

/// Mass (g) of a sheet: `area` (cm²) × `thickness` (cm) × `density` (g/cm³).
pub fn sheet_mass(area: f64, thickness: f64, density: f64) -> f64 {
    area * thickness * density
}

/// Density of water, g/cm³ (the implant's filling).
pub const WATER_DENSITY: f64 = 1.0;
