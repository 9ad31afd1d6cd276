//! Shared test scenes and helpers.
#![allow(dead_code, clippy::print_stderr)]

use glam::{DVec3, Vec3};
use tissue_mesh::{tet_box, TetMesh};
use tissue_pbd::SoftBody;

/// The bunny of `../shared/meshes` (≈ 1 unit tall, +y up, min y = 0), scaled ×10 to a 10 cm body,
/// or `None` (with a message) when the shared folder is missing.
pub fn bunny() -> Option<TetMesh> {
    let stem = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../../shared/meshes/bunny_10k_tet42k"
    );
    if !std::path::Path::new(&format!("{stem}.node")).exists() {
        eprintln!(
            "SKIP bunny: {stem}.node not found (../shared/meshes is missing); using a tet_box"
        );
        return None;
    }
    let data = tissue_meshio::read_tetgen(stem).expect("bunny reads");
    let positions = data.positions.iter().map(|p| *p * 10.0).collect();
    Some(TetMesh::new(positions, data.tets).expect("bunny is valid"))
}

/// A box standing on y = 0 when no bunny is available.
pub fn bunny_or_box() -> TetMesh {
    bunny().unwrap_or_else(|| {
        let m = tet_box(20, 20, 20, Vec3::splat(10.0)).expect("box");
        let (p, t) = m.into_parts();
        TetMesh::new(p.iter().map(|p| *p + Vec3::new(0.0, 5.0, 0.0)).collect(), t).expect("box")
    })
}

/// SplitMix64.
pub struct Rng(pub u64);
impl Rng {
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// Uniform in [-1, 1).
    pub fn signed(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 / (1u64 << 23) as f32 - 1.0
    }
    pub fn vec3(&mut self, scale: f32) -> Vec3 {
        Vec3::new(self.signed(), self.signed(), self.signed()) * scale
    }
}

/// Centre of mass, linear momentum, angular momentum about the centre of mass, and the kinetic
/// energy not in the body's best-fit rigid motion (all nodes).
pub fn non_rigid_energy(body: &SoftBody) -> f64 {
    let m: Vec<f64> = body.masses().iter().map(|&m| m as f64).collect();
    let x: Vec<DVec3> = body.positions().iter().map(|p| p.as_dvec3()).collect();
    let v: Vec<DVec3> = body.velocities().iter().map(|p| p.as_dvec3()).collect();
    let total: f64 = m.iter().sum();
    let xc = m.iter().zip(&x).map(|(m, x)| *m * *x).sum::<DVec3>() / total;
    let vc = m.iter().zip(&v).map(|(m, v)| *m * *v).sum::<DVec3>() / total;
    let mut l = DVec3::ZERO;
    let mut i = glam::DMat3::ZERO;
    for k in 0..m.len() {
        let r = x[k] - xc;
        l += r.cross(m[k] * v[k]);
        i += m[k]
            * (glam::DMat3::from_diagonal(DVec3::splat(r.length_squared()))
                - glam::DMat3::from_cols(r * r.x, r * r.y, r * r.z));
    }
    let omega = i.inverse() * l;
    let ke = 0.5
        * m.iter()
            .zip(&v)
            .map(|(m, v)| m * v.length_squared())
            .sum::<f64>();
    ke - 0.5 * total * vc.length_squared() - 0.5 * omega.dot(l)
}
