//! The pressure of a fluid enclosed by a closed surface: a volume-preserving force that holds the
//! volume itself, not a proxy for it.

use glam::{Vec3, Vec3A};
use tissue_mesh::TriMesh;

use crate::MssError;

/// A nearly incompressible fill inside a closed surface: pressure `p = K·(V₀ − V)/V₀` pushing
/// every vertex along the volume's gradient, `fᵢ = p·∇ᵢV` (for a vertex, `∇ᵢV` is a third of
/// the area-weighted normal of its triangles: the pressure force on its share of the surface).
///
/// `K` is the fill's bulk modulus (g/(cm·s²)): an outside pressure `p` squeezes the volume by
/// `ΔV/V = p/K` at equilibrium, whatever the shape. Eq. (5)'s volume preservation
/// ([`crate::VolumePreservation`]) holds area-weighted radial lengths instead, which a body
/// flattened on one side can keep while losing volume.
///
/// The forces sum to zero (a closed surface's `Σ∇ᵢV = 0`), so the fill adds no momentum.
#[derive(Debug, Clone, PartialEq)]
pub struct VolumePressure {
    pub(crate) triangles: Vec<[u32; 3]>,
    pub(crate) rest: f64,
    pub(crate) bulk_modulus: f64,
    /// `|∇ᵢV|` at rest per particle of the system (0 for others), for the stable step.
    pub(crate) gradient_norm: Vec<(u32, f32)>,
}

impl VolumePressure {
    /// The fill of `mesh` (closed, outward normals) whose vertex `v` is particle
    /// `v + first_particle`, at rest at the mesh's volume, of bulk modulus `bulk_modulus`.
    ///
    /// # Errors
    /// [`MssError::Mesh`] for an open mesh, [`MssError::InvalidParameter`] for a modulus that is
    /// not positive and finite or a mesh whose volume is not positive (inward normals).
    pub fn new(mesh: &TriMesh, first_particle: u32, bulk_modulus: f64) -> Result<Self, MssError> {
        if !mesh.is_closed() {
            let topo = mesh.topology();
            return Err(tissue_mesh::MeshError::NotClosed {
                boundary_edges: topo.boundary_edge_count(),
                loops: topo.boundary_loops().len(),
            }
            .into());
        }
        if !(bulk_modulus.is_finite() && bulk_modulus > 0.0) {
            return Err(MssError::InvalidParameter {
                name: "bulk_modulus",
                value: bulk_modulus,
                expected: "positive and finite",
            });
        }
        let rest = mesh.signed_volume()?;
        if rest.is_nan() || rest <= 0.0 {
            return Err(MssError::InvalidParameter {
                name: "volume",
                value: rest,
                expected: "positive: a closed surface with outward normals",
            });
        }
        let positions: Vec<Vec3A> = mesh.positions().iter().map(|&p| p.into()).collect();
        let mut gradient = vec![Vec3A::ZERO; positions.len()];
        accumulate_gradient(mesh.triangles(), &positions, 0, 1.0, &mut gradient);
        let gradient_norm = gradient
            .iter()
            .enumerate()
            .filter(|(_, g)| **g != Vec3A::ZERO)
            .map(|(v, g)| (v as u32 + first_particle, g.length()))
            .collect();
        Ok(VolumePressure {
            triangles: mesh
                .triangles()
                .iter()
                .map(|t| t.map(|v| v + first_particle))
                .collect(),
            rest,
            bulk_modulus,
            gradient_norm,
        })
    }

    /// The volume at rest (cm³).
    pub fn rest_volume(&self) -> f64 {
        self.rest
    }

    /// The bulk modulus (g/(cm·s²)).
    pub fn bulk_modulus(&self) -> f64 {
        self.bulk_modulus
    }

    /// `out[i] += ∇ᵢV` at `positions` (cm²) for every particle of the fill: the pressure's
    /// force is `K·(V₀ − V)/V₀·∇V`, its stiffness `K/V₀·∇V ∇Vᵀ` (rank one).
    pub fn add_gradient(&self, positions: &[Vec3A], out: &mut [Vec3A]) {
        accumulate_gradient(&self.triangles, positions, 0, 1.0, out);
    }

    /// The fill's surface triangles (particle indices).
    pub fn triangles(&self) -> &[[u32; 3]] {
        &self.triangles
    }

    /// The pressure at `positions`, `K·(V₀ − V)/V₀` (g/(cm·s²)): positive when squeezed.
    pub fn pressure(&self, positions: &[Vec3A]) -> f64 {
        self.bulk_modulus * (self.rest - self.volume(positions)) / self.rest
    }

    /// The enclosed volume at `positions` (cm³).
    pub fn volume(&self, positions: &[Vec3A]) -> f64 {
        let origin = self
            .triangles
            .first()
            .map_or(Vec3::ZERO, |t| Vec3::from(positions[t[0] as usize]))
            .as_dvec3();
        self.triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| Vec3::from(positions[i as usize]).as_dvec3() - origin);
                a.dot(b.cross(c))
            })
            .sum::<f64>()
            / 6.0
    }

    /// Checks the particle indices against a system of `n` particles.
    pub(crate) fn check(&self, n: usize) -> Result<(), MssError> {
        match self.triangles.iter().flatten().find(|&&p| p as usize >= n) {
            Some(&p) => Err(MssError::InvalidParticle {
                particle: p,
                what: format!("a volume pressure refers to it but the system has {n} particles"),
            }),
            None => Ok(()),
        }
    }

    /// Adds the pressure forces.
    pub(crate) fn add_forces(&self, position: &[Vec3A], force: &mut [Vec3A]) {
        let volume = self.volume(position);
        let pressure = (self.bulk_modulus * (self.rest - volume) / self.rest) as f32;
        accumulate_gradient(&self.triangles, position, 0, pressure, force);
    }

    /// Stiffness of particle `i`'s row (Gershgorin): `K/V₀·|∇ᵢV|·Σⱼ|∇ⱼV|`, at rest.
    pub(crate) fn row_stiffness(&self) -> impl Iterator<Item = (u32, f64)> + '_ {
        let total: f64 = self.gradient_norm.iter().map(|&(_, g)| f64::from(g)).sum();
        let scale = self.bulk_modulus / self.rest * total;
        self.gradient_norm
            .iter()
            .map(move |&(p, g)| (p, scale * f64::from(g)))
    }
}

/// `out[i] += scale·∇ᵢV` for the surface `triangles` over `positions` (indices offset by
/// `first`), with positions taken relative to the first triangle's first vertex (the gradient
/// of a closed surface's volume does not depend on the origin; this keeps the cross products
/// small).
fn accumulate_gradient(
    triangles: &[[u32; 3]],
    positions: &[Vec3A],
    first: u32,
    scale: f32,
    out: &mut [Vec3A],
) {
    let Some(origin) = triangles
        .first()
        .map(|t| positions[(t[0] - first) as usize])
    else {
        return;
    };
    let s = scale / 6.0;
    for t in triangles {
        let [i, j, k] = t.map(|v| (v - first) as usize);
        let (a, b, c) = (
            positions[i] - origin,
            positions[j] - origin,
            positions[k] - origin,
        );
        out[i] += b.cross(c) * s;
        out[j] += c.cross(a) * s;
        out[k] += a.cross(b) * s;
    }
}
