//! Volume preservation after Vassilev & Spanlang, eq. (5).

use glam::{DVec3, Vec3, Vec3A};
use tissue_mesh::TriMesh;

use crate::MssError;

/// Springs from each particle of a closed surface to the surface's centre of mass that resist a
/// change of volume, eq. (5):
///
/// `fᵢ = −cᵢ·k_v·(Δl_tot + C·Δlᵢ)·uᵢ`, `Δl_tot = ⅓ Σⱼ cⱼ Δlⱼ`, `Δlᵢ = lᵢ − lᵢ⁰`,
///
/// where `lᵢ = |xᵢ − x_cm|`, `lᵢ⁰` its value at construction, `uᵢ` the unit vector from the
/// centre of mass `x_cm` (mass-weighted, recomputed every step) to the particle, and
/// `cᵢ = Σ_{t∋i} S_t / S_AV` the area of the triangles around `i` in units of the mean triangle
/// area (so a particle stands for its share of the surface). `Δl_tot` couples every particle to
/// the whole: squeezing one side pushes every other particle outwards until the area-weighted sum
/// of radial changes is back near zero. `C ∈ (0, 1)` weighs the particle's own change.
///
/// Units: `k_v` in g/s² (a stiffness).
#[derive(Debug, Clone, PartialEq)]
pub struct VolumePreservation {
    pub(crate) particles: Vec<u32>,
    pub(crate) weight: Vec<f32>,
    pub(crate) rest: Vec<f32>,
    pub(crate) k_v: f32,
    pub(crate) c: f32,
}

impl VolumePreservation {
    /// Volume springs for the closed surface `mesh`, whose vertex `v` is particle
    /// `v + first_particle`; rest lengths from the mesh's positions and mass-weighted centre
    /// (`masses[v]` the vertex masses). Unreferenced vertices take no part.
    pub fn new(
        mesh: &TriMesh,
        masses: &[f32],
        first_particle: u32,
        k_v: f32,
        c: f32,
    ) -> Result<Self, MssError> {
        if !mesh.is_closed() {
            let topo = mesh.topology();
            return Err(tissue_mesh::MeshError::NotClosed {
                boundary_edges: topo.boundary_edge_count(),
                loops: topo.boundary_loops().len(),
            }
            .into());
        }
        if masses.len() != mesh.vertex_count() {
            return Err(MssError::LengthMismatch {
                what: "volume-preservation masses",
                got: masses.len(),
                expected: mesh.vertex_count(),
            });
        }
        if !(k_v.is_finite() && k_v >= 0.0) {
            return Err(MssError::InvalidParameter {
                name: "k_v",
                value: f64::from(k_v),
                expected: "finite and ≥ 0",
            });
        }
        if !(c.is_finite() && c > 0.0 && c < 1.0) {
            return Err(MssError::InvalidParameter {
                name: "C",
                value: f64::from(c),
                expected: "in (0, 1)",
            });
        }
        let areas = mesh.triangle_areas();
        let mean_area = areas.iter().sum::<f64>() / areas.len() as f64;
        let mut around = vec![0.0f64; mesh.vertex_count()];
        for (tri, a) in mesh.triangles().iter().zip(&areas) {
            for &v in tri {
                around[v as usize] += a;
            }
        }
        let used: Vec<u32> = (0..mesh.vertex_count() as u32)
            .filter(|&v| around[v as usize] > 0.0)
            .collect();
        let positions: Vec<Vec3A> = used
            .iter()
            .map(|&v| Vec3A::from(mesh.positions()[v as usize]))
            .collect();
        let m: Vec<f32> = used.iter().map(|&v| masses[v as usize]).collect();
        let centre = centre_of_mass(&positions, &m);
        Ok(VolumePreservation {
            particles: used.iter().map(|&v| v + first_particle).collect(),
            weight: used
                .iter()
                .map(|&v| (around[v as usize] / mean_area) as f32)
                .collect(),
            rest: positions
                .iter()
                .map(|p| (Vec3::from(*p).as_dvec3() - centre).length() as f32)
                .collect(),
            k_v,
            c,
        })
    }

    /// Each particle's own stiffness under eq. (5), `cᵢ·k_v·(C + cᵢ/3)` (g/s²): the diagonal
    /// of its Jacobian along the radial direction, for a quasi-static solve's matrix.
    pub fn diagonal_stiffness(&self) -> impl Iterator<Item = (u32, f64)> + '_ {
        self.particles.iter().zip(&self.weight).map(|(&p, &c)| {
            let c = f64::from(c);
            (p, c * f64::from(self.k_v) * (f64::from(self.c) + c / 3.0))
        })
    }

    /// `k_v` (g/s²) and `C` of eq. (5).
    pub fn constants(&self) -> (f64, f64) {
        (f64::from(self.k_v), f64::from(self.c))
    }

    /// `out` = `(particle, cᵢ·uᵢ)` at `positions` (`uᵢ` the unit direction from the
    /// mass-weighted centre): eq. (5)'s Jacobian is `k_v·(⅓ w wᵀ + C·Σᵢ cᵢ² uᵢuᵢᵀ)` with
    /// `w = (cᵢ uᵢ)`, its centre held (what a quasi-static solve's Newton step uses).
    pub fn weighted_directions(
        &self,
        position: &[Vec3A],
        mass: &[f32],
        out: &mut Vec<(u32, glam::DVec3)>,
    ) {
        out.clear();
        let mut weighted = DVec3::ZERO;
        let mut total = 0.0f64;
        for &p in &self.particles {
            let m = f64::from(mass[p as usize]);
            weighted += Vec3::from(position[p as usize]).as_dvec3() * m;
            total += m;
        }
        let centre = weighted / total.max(f64::MIN_POSITIVE);
        for (&p, &c) in self.particles.iter().zip(&self.weight) {
            let u = (Vec3::from(position[p as usize]).as_dvec3() - centre).normalize_or_zero();
            out.push((p, u * f64::from(c)));
        }
    }

    /// The particles this acts on.
    pub fn particles(&self) -> &[u32] {
        &self.particles
    }

    /// Checks the particle indices against a system of `n` particles.
    pub(crate) fn check(&self, n: usize) -> Result<(), MssError> {
        match self.particles.iter().find(|&&p| p as usize >= n) {
            Some(&p) => Err(MssError::InvalidParticle {
                particle: p,
                what: format!("volume preservation refers to it but the system has {n} particles"),
            }),
            None => Ok(()),
        }
    }

    /// Adds eq. (5)'s forces. `scratch` holds one length per particle of this object.
    pub(crate) fn add_forces(
        &self,
        position: &[Vec3A],
        mass: &[f32],
        force: &mut [Vec3A],
        scratch: &mut Vec<f32>,
    ) {
        let mut weighted = DVec3::ZERO;
        let mut total = 0.0f64;
        for &p in &self.particles {
            let m = f64::from(mass[p as usize]);
            weighted += Vec3::from(position[p as usize]).as_dvec3() * m;
            total += m;
        }
        let centre = weighted / total;
        let centre_f = Vec3A::from(centre.as_vec3());
        scratch.clear();
        let mut sum = 0.0f64;
        for (j, &p) in self.particles.iter().enumerate() {
            let l = (Vec3::from(position[p as usize]).as_dvec3() - centre).length();
            let dl = (l - f64::from(self.rest[j])) as f32;
            scratch.push(dl);
            sum += f64::from(self.weight[j]) * f64::from(dl);
        }
        let dl_tot = (sum / 3.0) as f32;
        for (j, &p) in self.particles.iter().enumerate() {
            let r = position[p as usize] - centre_f;
            let len = r.length();
            if len > 0.0 {
                let u = r / len;
                force[p as usize] -=
                    u * (self.weight[j] * self.k_v * (dl_tot + self.c * scratch[j]));
            }
        }
    }
}

/// Mass-weighted centre, in `f64`.
fn centre_of_mass(position: &[Vec3A], mass: &[f32]) -> DVec3 {
    let mut weighted = DVec3::ZERO;
    let mut total = 0.0f64;
    for (p, &m) in position.iter().zip(mass) {
        weighted += Vec3::from(*p).as_dvec3() * f64::from(m);
        total += f64::from(m);
    }
    weighted / total
}
