//! Springs: the compact record, Hooke's law (eq. 4), Van Gelder stiffness (eq. 3) and the springs
//! of a triangle mesh.

use glam::{Vec3, Vec3A};
use tissue_mesh::TriMesh;

use crate::MssError;

/// A spring between particles `a` and `b`: rest length `rest` (cm) and stiffness `k` (g/s²).
///
/// 16 bytes, read together by the force loop.
#[derive(Debug, Clone, Copy, PartialEq)]
#[repr(C)]
pub struct Spring {
    /// First particle.
    pub a: u32,
    /// Second particle.
    pub b: u32,
    /// Rest length, ≥ 0 (0 for a zero-length spring).
    pub rest: f32,
    /// Stiffness, ≥ 0.
    pub k: f32,
}

const _: () = assert!(std::mem::size_of::<Spring>() == 16);

impl Spring {
    /// A spring; checked when a system is built.
    pub fn new(a: u32, b: u32, rest: f32, k: f32) -> Spring {
        Spring { a, b, rest, k }
    }

    /// Checks the spring against a system of `particle_count` particles; `index` names it.
    pub(crate) fn check(&self, index: usize, particle_count: usize) -> Result<(), MssError> {
        let fail = |what: String| {
            Err(MssError::InvalidSpring {
                spring: index,
                a: self.a,
                b: self.b,
                what,
            })
        };
        let n = particle_count;
        if self.a as usize >= n || self.b as usize >= n {
            return fail(format!("particle index out of range (the system has {n})"));
        }
        if self.a == self.b {
            return fail("joins a particle to itself".into());
        }
        if !(self.rest.is_finite() && self.rest >= 0.0) {
            return fail(format!("rest length {} must be finite and ≥ 0", self.rest));
        }
        if !(self.k.is_finite() && self.k >= 0.0) {
            return fail(format!("stiffness {} must be finite and ≥ 0", self.k));
        }
        Ok(())
    }
}

/// A zero-length spring pulling particle `particle` towards the fixed point `target` with
/// stiffness `k`: force `k·(target − x)`, finite for every position (the thesis's springs that
/// return layer-2 particles to their original places).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Anchor {
    /// The particle.
    pub particle: u32,
    /// Stiffness, ≥ 0.
    pub k: f32,
    /// The fixed point (cm).
    pub target: Vec3,
}

/// Hooke's law, eq. (4): the force on particle `a` of a spring from `a` to `b`,
/// `k (|d| − l) d/|d|` with `d = x_b − x_a`; the force on `b` is its negative.
///
/// Written as `k (d − l d/|d|)` with `d/|d|` taken as 0 when `|d| = 0`, so a zero-length spring
/// gives exactly `k d` and a collapsed spring gives 0: finite for every input, never NaN.
#[inline(always)]
pub fn spring_force(xa: Vec3A, xb: Vec3A, rest: f32, k: f32) -> Vec3A {
    let d = xb - xa;
    let len = d.length();
    let inv = if len > 0.0 { 1.0 / len } else { 0.0 };
    d * (k * (1.0 - rest * inv))
}

/// Material of a thin sheet for eq. (3): Young's modulus `young` (g/(cm·s²), i.e. 0.1 Pa),
/// Poisson ratio `poisson` in [0, 0.5) and thickness `thickness` (cm).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SheetMaterial {
    /// Young's modulus E.
    pub young: f64,
    /// Poisson ratio ν.
    pub poisson: f64,
    /// Thickness t.
    pub thickness: f64,
}

impl SheetMaterial {
    pub(crate) fn check(&self) -> Result<(), MssError> {
        if !(self.young.is_finite() && self.young > 0.0) {
            return Err(MssError::InvalidParameter {
                name: "young",
                value: self.young,
                expected: "positive and finite",
            });
        }
        if !(self.poisson.is_finite() && (0.0..0.5).contains(&self.poisson)) {
            return Err(MssError::InvalidParameter {
                name: "poisson",
                value: self.poisson,
                expected: "in [0, 0.5)",
            });
        }
        if !(self.thickness.is_finite() && self.thickness > 0.0) {
            return Err(MssError::InvalidParameter {
                name: "thickness",
                value: self.thickness,
                expected: "positive and finite",
            });
        }
        Ok(())
    }
}

/// Van Gelder stiffness, eq. (3), of the spring along side `c` of a triangle with side lengths
/// `a`, `b`, `c` and area `area`:
///
/// `k_c = E₂/(1+ν) · 2A/c² + E₂ν/(1−ν²) · (a² + b² − c²)/(4A)`, `E₂ = E·t`.
///
/// The second term is negative for an obtuse angle opposite `c`.
pub fn van_gelder(a: f64, b: f64, c: f64, area: f64, material: &SheetMaterial) -> f64 {
    let e2 = material.young * material.thickness;
    let nu = material.poisson;
    e2 / (1.0 + nu) * (2.0 * area / (c * c))
        + e2 * nu / (1.0 - nu * nu) * ((a * a + b * b - c * c) / (4.0 * area))
}

/// One spring per edge of `mesh`, rest length = the edge's length, stiffness = the sum of eq. (3)
/// over the edge's one or two triangles. Particle `v` of the result is vertex `v + first_particle`.
/// Springs come in the mesh's edge order.
///
/// Errors if the material is out of range or a stiffness comes out non-positive (a very obtuse
/// triangle with a large Poisson ratio can make a side's sum negative: remesh, or lower ν, or
/// use [`springs_from_triangles_floored`]).
pub fn springs_from_triangles(
    mesh: &TriMesh,
    material: &SheetMaterial,
    first_particle: u32,
) -> Result<Vec<Spring>, MssError> {
    let (k, _) = edge_stiffness(mesh, material)?;
    let topo = mesh.topology();
    let positions = mesh.positions();
    topo.edges()
        .iter()
        .zip(&k)
        .enumerate()
        .map(|(e, (&[a, b], &k))| {
            if !(k.is_finite() && k > 0.0) {
                return Err(MssError::InvalidSpring {
                    spring: e,
                    a,
                    b,
                    what: format!(
                        "Van Gelder stiffness {k} is not positive (obtuse triangles with ν = {})",
                        material.poisson
                    ),
                });
            }
            let rest = positions[a as usize].distance(positions[b as usize]);
            Ok(Spring::new(
                a + first_particle,
                b + first_particle,
                rest,
                k as f32,
            ))
        })
        .collect()
}

/// [`springs_from_triangles`] for meshes with very obtuse triangles (scans): an edge whose eq. (3)
/// sum is not positive keeps only the sum of the formula's first, shear term,
/// `E₂/(1+ν)·2A/c²`, which is positive for every triangle. Eq. (3)'s second term is negative
/// opposite an obtuse angle, and can outweigh the rest when ν is large.
///
/// Returns the springs and the edges (indices in the mesh's edge order) whose stiffness was
/// replaced. Errors only for a bad material.
pub fn springs_from_triangles_floored(
    mesh: &TriMesh,
    material: &SheetMaterial,
    first_particle: u32,
) -> Result<(Vec<Spring>, Vec<u32>), MssError> {
    let (k, shear) = edge_stiffness(mesh, material)?;
    let topo = mesh.topology();
    let positions = mesh.positions();
    let mut replaced = Vec::new();
    let springs = topo
        .edges()
        .iter()
        .enumerate()
        .map(|(e, &[a, b])| {
            let stiffness = if k[e].is_finite() && k[e] > 0.0 {
                k[e]
            } else {
                replaced.push(e as u32);
                shear[e]
            };
            let rest = positions[a as usize].distance(positions[b as usize]);
            Spring::new(
                a + first_particle,
                b + first_particle,
                rest,
                stiffness as f32,
            )
        })
        .collect();
    Ok((springs, replaced))
}

/// Per edge: eq. (3) summed over its triangles, and the first term alone.
fn edge_stiffness(
    mesh: &TriMesh,
    material: &SheetMaterial,
) -> Result<(Vec<f64>, Vec<f64>), MssError> {
    material.check()?;
    let topo = mesh.topology();
    let mut k = vec![0.0f64; topo.edges().len()];
    let mut shear = vec![0.0f64; topo.edges().len()];
    let e2 = material.young * material.thickness;
    for (t, edges) in topo.triangle_edges().iter().enumerate() {
        let p = mesh.corners(t).map(|x| x.as_dvec3());
        // Side s runs from corner s to corner s+1; its opposite sides are the other two.
        let len = [
            (p[1] - p[0]).length(),
            (p[2] - p[1]).length(),
            (p[0] - p[2]).length(),
        ];
        let area = 0.5 * (p[1] - p[0]).cross(p[2] - p[0]).length();
        for s in 0..3 {
            let c = len[s];
            let (a, b) = (len[(s + 1) % 3], len[(s + 2) % 3]);
            k[edges[s] as usize] += van_gelder(a, b, c, area, material);
            shear[edges[s] as usize] += e2 / (1.0 + material.poisson) * (2.0 * area / (c * c));
        }
    }
    Ok((k, shear))
}
