//! The two-layer tissue model of SPEC A.5 steps 1–3.
//!
//! Layer 1 is the selected skin region; layer 2 is a copy offset inward (against the region's
//! vertex normals, which point out of the body) by the placement depth. Region vertex `r` is
//! particle `2r` in layer 1 and `2r + 1` in layer 2: the layers are interleaved so that
//! neighbours stay close in memory (see `tissue-mss`'s layout).
//!
//! ## Springs
//! - Within each layer, one spring per edge with Van Gelder stiffness (eq. 3) from the skin's
//!   Young's modulus `E`, Poisson ratio `ν` and thickness `t`, rest lengths from that layer's
//!   geometry.
//! - Between the layers, a continuum slab of thickness `depth` that resists compression and
//!   shear like the tissue it stands for (`E` here is the slab's modulus,
//!   [`LayerParams::slab_young`], `G = E/(2(1+ν))`):
//!   - a *vertical* spring per vertex, `k = E·Aᵢ/depth`, with `Aᵢ` a third of the area of the
//!     triangles around the vertex (its tributary area): the slab's axial stiffness;
//!   - a *shear* force per vertex ([`TissueLayers::add_slab_shear`]) pulling layer 1's particle
//!     back over layer 2's along layer 2's current normal, `k = G·Aᵢ/depth`: a shear `u` of the
//!     whole slab meets `G·A·u/depth`, and it adds nothing to the compression stiffness.
//! - Every layer-2 particle has a zero-length anchor to its original position (the deeper tissue
//!   holding it): `k = E_a·Aᵢ/depth` with `E_a` the modulus of the attachment to the deep
//!   fascia and muscle (`anchor_young`); lifting layer 2 by `u` costs `E_a·u/depth` per unit
//!   area. An insertion removes them over the expander's pocket ([`TissueLayers::detach`]).
//!
//! - Layer 1 resists bending as a plate of the skin's modulus and thickness,
//!   `D = E t³ / (12 (1 − ν²))`, by discrete-shell hinges on its interior edges
//!   ([`LayerParams::skin_bending`], `crate::bending`): forces, like the slab's shear, added in
//!   [`TissueLayers::compute_forces`] and counted in [`TissueLayers::stable_time_step`].
//!
//! ## Masses and fixed particles
//! The region's mass is the tissue column between the surface and the expander: the skin,
//! area × skin thickness × density (SPEC A.5 step 1), and the slab between the layers, area ×
//! depth × density (tissue too). The column is lumped half on each layer, as a two-node element
//! through the thickness lumps its mass, and each half is spread by eq. (2) on its layer's
//! triangles (the thesis's region, whose counts include both layers, carries the mass on both).
//! The end state of a run does not depend on the masses; its number of steps and its
//! robustness do: layer 2 must carry its share, or its light particles set a smaller stable
//! step and large expanders do not settle (`docs/tuning-log.md`, "Masses shared by the
//! layers"). Particles on the region's boundary loops are fixed in both layers.

use glam::{Vec3, Vec3A};
use tissue_mesh::TriMesh;
use tissue_mss::{
    masses_from_triangles, springs_from_triangles_floored, Anchor, MassSpringSystem, Particles,
    SheetMaterial, Spring,
};

use crate::adjacency::VertexNeighbours;
use crate::ImplantError;
use crate::Param;

/// Triangles of a lower [`shape_quality`] are slivers, whose turning over in the inward offset
/// is not a fold of the surface (about 7° for the smallest angle of an isosceles sliver).
const SLIVER_QUALITY: f64 = 0.2;

/// `4√3·area / Σ edge²`: 1 for an equilateral triangle, towards 0 for a sliver.
pub(crate) fn shape_quality(c: [Vec3; 3]) -> f64 {
    let [a, b, c] = c.map(|p| p.as_dvec3());
    let area = 0.5 * (b - a).cross(c - a).length();
    let squares = (b - a).length_squared() + (c - b).length_squared() + (a - c).length_squared();
    if squares > 0.0 {
        4.0 * 3f64.sqrt() * area / squares
    } else {
        0.0
    }
}

/// The directions layer 2 is offset along: each vertex's normal averaged (area-weighted) over
/// the vertices within `min(depth, half the mean edge)` of it, reached along edges through such
/// vertices. Two vertices closer than `depth · angle between their normals` swap over in the
/// offset: a sliver the remesher left at a seam (a 0.0136 cm edge on the forearm's 0.18 cm
/// mesh) folded it. Averaging over vertices that close merges their directions, while the
/// surface's real curvature, seen over whole edges, is kept (a cap of radius 1 cm still refuses
/// a 1.5 cm depth). Where no vertex is that close (Table 2's grid, the MakeHuman meshes) this is
/// the vertex normal itself.
fn offset_normals(region: &TriMesh, depth: f64, reach: Option<f64>) -> Vec<Vec3> {
    let n = region.vertex_count();
    let p = region.positions();
    // Unnormalised area-weighted normals.
    let mut raw = vec![glam::DVec3::ZERO; n];
    for (t, tri) in region.triangles().iter().enumerate() {
        let [a, b, c] = region.corners(t).map(|x| x.as_dvec3());
        let area_normal = (b - a).cross(c - a);
        for &v in tri {
            raw[v as usize] += area_normal;
        }
    }
    let adjacency = VertexNeighbours::of(region);
    let mean_edge = f64::from(crate::contact_run::mean_edge_length(region));
    let reach = depth.min(reach.unwrap_or(0.5 * mean_edge));
    let reach2 = (reach * reach) as f32;
    let mut stamp = vec![u32::MAX; n];
    let mut stack = Vec::new();
    (0..n)
        .map(|v| {
            let mut sum = raw[v];
            stamp[v] = v as u32;
            stack.clear();
            stack.push(v as u32);
            while let Some(w) = stack.pop() {
                for &x in adjacency.of_vertex(w) {
                    if stamp[x as usize] != v as u32
                        && p[x as usize].distance_squared(p[v]) <= reach2
                    {
                        stamp[x as usize] = v as u32;
                        sum += raw[x as usize];
                        stack.push(x);
                    }
                }
            }
            sum.normalize_or_zero().as_vec3()
        })
        .collect()
}

/// The triangles of `region` (slivers aside) that turn over when offset inward by `depth`
/// along `directions`, into `out`.
fn folded_triangles(region: &TriMesh, directions: &[Vec3], depth: f32, out: &mut Vec<usize>) {
    out.clear();
    let p = region.positions();
    for (t, tri) in region.triangles().iter().enumerate() {
        let c = tri.map(|v| p[v as usize]);
        let q = tri.map(|v| p[v as usize] - directions[v as usize] * depth);
        let before = (c[1] - c[0]).cross(c[2] - c[0]);
        let after = (q[1] - q[0]).cross(q[2] - q[0]);
        if before.dot(after) <= 0.0 && shape_quality(c) >= SLIVER_QUALITY {
            out.push(t);
        }
    }
}

/// Smooths the offset directions where they fold layer 2, no farther than the depth: while
/// triangles turn over, each vertex of one and its neighbours take the mean direction of their
/// one-ring, for at most `depth / mean edge` rounds (at least one). A ripple shorter than the
/// depth (what a noisy scan's border or a coarse body's facet crease leaves on a fine
/// simulation surface) is smoothed out of layer 2 this way, while a surface that curves more
/// tightly than the depth over a longer stretch still folds and is refused by the caller
/// (a cap of radius 1 cm and a 1.5 cm depth). Returns the rounds used.
fn untangle(region: &TriMesh, directions: &mut [Vec3], depth: f64) -> usize {
    let mean_edge = f64::from(crate::contact_run::mean_edge_length(region));
    let max_rounds = if mean_edge > 0.0 {
        ((depth / mean_edge).floor() as usize).clamp(1, 64)
    } else {
        1
    };
    let adjacency = VertexNeighbours::of(region);
    let n = region.vertex_count();
    let mut folded = Vec::new();
    let mut marked = vec![false; n];
    let mut next = directions.to_vec();
    for round in 0..max_rounds {
        folded_triangles(region, directions, depth as f32, &mut folded);
        if folded.is_empty() {
            return round;
        }
        marked.iter_mut().for_each(|m| *m = false);
        for &t in &folded {
            for v in region.triangles()[t] {
                marked[v as usize] = true;
                for &w in adjacency.of_vertex(v) {
                    marked[w as usize] = true;
                }
            }
        }
        for v in 0..n {
            next[v] = if marked[v] {
                let sum = adjacency
                    .of_vertex(v as u32)
                    .iter()
                    .fold(directions[v], |s, &w| s + directions[w as usize]);
                sum.try_normalize().unwrap_or(directions[v])
            } else {
                directions[v]
            };
        }
        directions.copy_from_slice(&next);
    }
    max_rounds
}

/// Which layer of the model.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Layer {
    /// Layer 1: the skin region itself.
    Outer = 0,
    /// Layer 2: the region offset inward by the placement depth; it meets the implant.
    Inner = 1,
}

/// Material and geometry of the two-layer model. Units: cm, g, s.
#[derive(Debug, Clone, PartialEq)]
pub struct LayerParams {
    /// Young's modulus of skin, g/(cm·s²) (1 Pa = 10 g/(cm·s²)).
    pub young: f64,
    /// Poisson ratio of skin, in [0, 0.5).
    pub poisson: f64,
    /// Skin thickness, cm.
    pub skin_thickness: f64,
    /// Tissue density, g/cm³.
    pub density: f64,
    /// Placement depth: the distance between the layers, cm.
    pub depth: f64,
    /// Young's modulus of the springs between the layers (the tissue slab), g/(cm·s²).
    pub slab_young: f64,
    /// The thinnest the slab may be squeezed, as a fraction of `depth` (see
    /// [`TissueLayers::hold_thickness`]); 0 turns the guard off.
    pub min_thickness: f64,
    /// Young's modulus of the loose subcutaneous tissue that anchors layer 2, g/(cm·s²).
    pub anchor_young: f64,
    /// How far (cm) the vertex normals are averaged into layer 2's offset directions (see
    /// [`TissueLayers::new`]); capped at `depth`. `None`: half the region's mean edge. A
    /// simulation surface of its own passes a length of the model, not of the mesh
    /// ([`crate::SimSurface::offset_reach`]), so that refining the mesh does not change the
    /// shape of layer 2.
    pub offset_reach: Option<f64>,
    /// Whether layer 1 resists bending as a plate of the skin's modulus and thickness,
    /// `D = E t³ / (12 (1 − ν²))` (module `bending`). On by default: without it the
    /// mass–spring skin, a membrane, folds into pleats one simulation edge wide where it is
    /// compressed. The thesis's model has none; the plane press (Table 1) turns it off to
    /// reproduce it.
    pub skin_bending: bool,
}

impl Default for LayerParams {
    /// Skin of `E` = 0.2 MPa (in vivo tensile tests on human skin report roughly 0.1–1 MPa at
    /// small strain; Agache et al. 1980, Pailler-Mattei et al. 2008), `ν` = 0.45 (soft tissue is
    /// nearly incompressible), thickness 0.2 cm (dermis 1–4 mm), density 1.1 g/cm³.
    ///
    /// Depth 0.25 cm: an expander is placed in a pocket right under the skin and a thin layer of
    /// fat (subcutaneous or subgaleal plane; the thesis does not give its depth). Layer 2 is
    /// attached outside the pocket (see `InsertionParams::pocket_margin`) to the deep fascia
    /// and muscle, `E_a` = 0.2 MPa, which also sets layer 2's own in-plane springs. Slab springs
    /// of 2 MPa: stiffer than skin on purpose, since linear springs squeezed past zero length
    /// turn the slab inside out, and under the skin's tension over an expander a skin-stiff slab
    /// does. The thickness guard holds layer 1 at least a quarter of the depth above layer 2.
    ///
    /// With these, Table 2's runs land in all of the thesis's bands (docs/validation.md). A
    /// deeper layer 2 makes the skin enclose about `depth × (dome area − base area)` more than
    /// the implant, and loose anchors let the ring around the expander rise too.
    fn default() -> Self {
        LayerParams {
            young: 2.0e6,
            poisson: 0.45,
            skin_thickness: 0.2,
            density: 1.1,
            depth: 0.25,
            anchor_young: 2.0e6,
            slab_young: 2.0e7,
            min_thickness: 0.25,
            offset_reach: None,
            skin_bending: true,
        }
    }
}

impl LayerParams {
    fn check(&self) -> Result<(), ImplantError> {
        let positive = |param: Param, value: f64| {
            if value.is_finite() && value > 0.0 {
                Ok(())
            } else {
                Err(ImplantError::InvalidParameter {
                    param,
                    value,
                    expected: "positive and finite".into(),
                })
            }
        };
        positive(Param::Young, self.young)?;
        positive(Param::SkinThickness, self.skin_thickness)?;
        positive(Param::Density, self.density)?;
        positive(Param::Depth, self.depth)?;
        if !(0.0..1.0).contains(&self.min_thickness) {
            return Err(ImplantError::InvalidParameter {
                param: Param::MinThickness,
                value: self.min_thickness,
                expected: "in [0, 1) (a fraction of the depth)".into(),
            });
        }
        if !(self.anchor_young.is_finite() && self.anchor_young >= 0.0) {
            return Err(ImplantError::InvalidParameter {
                param: Param::AnchorYoung,
                value: self.anchor_young,
                expected: "finite and ≥ 0".into(),
            });
        }
        if !(self.poisson.is_finite() && (0.0..0.5).contains(&self.poisson)) {
            return Err(ImplantError::InvalidParameter {
                param: Param::Poisson,
                value: self.poisson,
                expected: "in [0, 0.5)".into(),
            });
        }
        if let Some(reach) = self.offset_reach {
            if !(reach.is_finite() && reach >= 0.0) {
                return Err(ImplantError::InvalidParameter {
                    param: Param::OffsetReach,
                    value: reach,
                    expected: "finite and ≥ 0 (cm), or None for half the mean edge".into(),
                });
            }
        }
        Ok(())
    }
}

/// The two-layer mass–spring model of a skin region (see the module docs).
#[derive(Debug, Clone)]
pub struct TissueLayers {
    system: MassSpringSystem,
    outer: TriMesh,
    inner: TriMesh,
    normals: Vec<Vec3>,
    /// The slab's shear stiffness `G·Aᵢ/depth` per region vertex.
    pub(crate) shear: Vec<f32>,
    /// Layer 1's bending hinges (module `bending`).
    pub(crate) hinges: Vec<crate::bending::Hinge>,
    /// Layer 2's current vertex normals (unnormalised), scratch of `add_slab_shear` and
    /// `hold_thickness`.
    inner_normals: Vec<Vec3A>,
    /// In-layer springs whose eq. (3) sum was not positive (obtuse triangles), given only the
    /// shear term.
    floored: usize,
    boundary: Vec<u32>,
    min_thickness: f32,
    /// The in-plane springs of both layers as `(spring, edge, rest length as built)`, found on
    /// the first [`TissueLayers::grow`] (skin growth in an expansion over weeks).
    growth_map: Option<Vec<(u32, u32, f32)>>,
}

impl TissueLayers {
    /// Builds the model of `region` (an open surface whose normals point out of the body).
    ///
    /// Errors if the parameters are out of range, the region is closed (it needs a boundary to
    /// hold), or the placement depth is too large for the surface's curvature (the inward offset
    /// would fold a triangle over).
    pub fn new(region: &TriMesh, params: &LayerParams) -> Result<Self, ImplantError> {
        let _span = tracing::debug_span!("layers_new", vertices = region.vertex_count()).entered();
        params.check()?;
        let topo = region.topology();
        if region.is_closed() {
            return Err(ImplantError::ClosedRegion {
                triangles: region.triangle_count(),
            });
        }
        let n = region.vertex_count();
        let mut normals = offset_normals(region, params.depth, params.offset_reach);
        let rounds = untangle(region, &mut normals, params.depth);
        tracing::debug!(rounds, "offset untangled");
        let depth = params.depth as f32;
        let inner_positions: Vec<Vec3> = region
            .positions()
            .iter()
            .zip(&normals)
            .map(|(p, nrm)| *p - *nrm * depth)
            .collect();
        let inner = region.with_positions(inner_positions)?;
        // The offset must not fold: every inner triangle keeps the orientation of its original,
        // slivers aside (shape quality below SLIVER_QUALITY: a triangle a few degrees from flat,
        // such as the remesher can leave at a seam, turns over in any offset whose directions
        // differ by its own small height; that says nothing of the surface's curvature).
        let mut folded = Vec::new();
        folded_triangles(region, &normals, depth, &mut folded);
        if let Some(&t) = folded.first() {
            let [a, b, c] = region.corners(t);
            let at = (a + b + c) / 3.0;
            return Err(ImplantError::InvalidParameter {
                param: Param::Depth,
                value: params.depth,
                expected: format!(
                    "smaller: offsetting the region inward by it folds {} triangle(s) over, the \
                     first ({t}) at ({:.2}, {:.2}, {:.2}) (the surface curves more tightly than \
                     the depth there)",
                    folded.len(),
                    at.x,
                    at.y,
                    at.z
                ),
            });
        }

        let skin_mass = region.area() * params.skin_thickness * params.density;
        let slab_mass = region.area() * params.depth * params.density;
        // The column of skin and slab, lumped half on each face (module docs).
        let half_column = 0.5 * (skin_mass + slab_mass);
        let outer_mass = masses_from_triangles(region, half_column)?;
        let inner_mass = masses_from_triangles(&inner, half_column)?;
        let mut positions = Vec::with_capacity(2 * n);
        let mut masses = Vec::with_capacity(2 * n);
        for r in 0..n {
            positions.push(region.positions()[r]);
            positions.push(inner.positions()[r]);
            // An unreferenced vertex gets a token mass so the particle is valid; it has no springs.
            masses.push(outer_mass[r].max(f32::MIN_POSITIVE));
            masses.push(inner_mass[r].max(f32::MIN_POSITIVE));
        }
        let mut particles = Particles::new(&positions, &masses)?;
        let mut boundary: Vec<u32> = topo.boundary_loops().iter().flatten().copied().collect();
        boundary.sort_unstable();
        boundary.dedup();
        for &r in &boundary {
            particles.fix(Self::particle(Layer::Outer, r))?;
            particles.fix(Self::particle(Layer::Inner, r))?;
        }

        let material = SheetMaterial {
            young: params.young,
            poisson: params.poisson,
            thickness: params.skin_thickness,
        };
        let remap = |layer: Layer, springs: Vec<Spring>| {
            springs.into_iter().map(move |s| {
                Spring::new(
                    Self::particle(layer, s.a),
                    Self::particle(layer, s.b),
                    s.rest,
                    s.k,
                )
            })
        };
        // Layer 2 is the deep face of the subcutaneous tissue: as soft in its plane as the
        // tissue its anchors stand for.
        let deep = SheetMaterial {
            young: params.anchor_young.max(f64::MIN_POSITIVE),
            ..material
        };
        // Scans have obtuse triangles, whose eq. (3) sums can turn negative at ν = 0.45: such
        // an edge keeps eq. (3)'s shear term ([`springs_from_triangles_floored`]).
        let (outer_springs, outer_floored) = springs_from_triangles_floored(region, &material, 0)?;
        let (inner_springs, inner_floored) = springs_from_triangles_floored(&inner, &deep, 0)?;
        let floored = outer_floored.len() + inner_floored.len();
        if floored > 0 {
            tracing::warn!(
                floored,
                first = ?outer_floored.first().or(inner_floored.first()),
                "obtuse triangles: springs keep only eq. (3)'s shear term"
            );
        }
        let mut springs: Vec<Spring> = remap(Layer::Outer, outer_springs)
            .chain(remap(Layer::Inner, inner_springs))
            .collect();

        // Tributary areas: a third of each triangle to each of its vertices.
        let areas = region.triangle_areas();
        let mut vertex_area = vec![0.0f64; n];
        for (tri, &area) in region.triangles().iter().zip(&areas) {
            for &v in tri {
                vertex_area[v as usize] += area / 3.0;
            }
        }
        let vertical_k: Vec<f64> = vertex_area
            .iter()
            .map(|a| params.slab_young * a / params.depth)
            .collect();
        for r in 0..n as u32 {
            if vertical_k[r as usize] > 0.0 {
                springs.push(Spring::new(
                    Self::particle(Layer::Outer, r),
                    Self::particle(Layer::Inner, r),
                    params.depth as f32,
                    vertical_k[r as usize] as f32,
                ));
            }
        }
        // The slab's shear: G·Aᵢ/depth per vertex (see TissueLayers::add_slab_shear).
        let g = params.slab_young / (2.0 * (1.0 + params.poisson));
        let shear: Vec<f32> = vertex_area
            .iter()
            .map(|a| (g * a / params.depth) as f32)
            .collect();
        let mut system = MassSpringSystem::new(particles, springs)?;
        let anchors: Vec<Anchor> = (0..n as u32)
            .map(|r| Anchor {
                particle: Self::particle(Layer::Inner, r),
                k: (params.anchor_young * vertex_area[r as usize] / params.depth) as f32,
                target: inner.positions()[r as usize],
            })
            .collect();
        system.add_anchors(&anchors)?;
        let plate = params.young * params.skin_thickness.powi(3)
            / (12.0 * (1.0 - params.poisson * params.poisson));
        let hinges = if params.skin_bending {
            crate::bending::hinges(
                region.positions(),
                region.triangles(),
                topo.edges(),
                topo.edge_triangles(),
                plate,
                |v| Self::particle(Layer::Outer, v),
            )
        } else {
            Vec::new()
        };
        Ok(TissueLayers {
            system,
            outer: region.clone(),
            inner,
            normals,
            shear,
            hinges,
            inner_normals: vec![Vec3A::ZERO; n],
            floored,
            boundary,
            min_thickness: (params.min_thickness * params.depth) as f32,
            growth_map: None,
        })
    }

    /// All forces on both layers: the system's ([`MassSpringSystem::compute_forces`]) and the
    /// slab's shear ([`TissueLayers::add_slab_shear`]). Call this, not the system's own, before
    /// a velocity update.
    pub fn compute_forces(&mut self) {
        self.system.compute_forces();
        self.add_slab_shear();
        let (position, force) = self.system.particles_mut().positions_and_forces_mut();
        crate::bending::add_forces(&self.hinges, position, force);
    }

    /// The skin's bending energy at the current positions (g·cm²/s², module `bending`).
    pub fn bending_energy(&self) -> f64 {
        crate::bending::energy(&self.hinges, self.system.particles().positions())
    }

    /// Adds the slab's resistance to shear: for every region vertex, the part of the slab
    /// vector `s = x₁ − x₂` (layer 1's particle minus layer 2's) across layer 2's current normal
    /// `n` is pulled back, `f₁ = −k·(s − (s·n)n)`, `f₂ = −f₁`, with `k = G·Aᵢ/depth` (`G` the
    /// slab's shear modulus, `Aᵢ` the vertex's tributary area): a shear `u` of the whole slab
    /// meets `G·A·u/depth`. Along `n` the vertical springs act. The pair's forces cancel, so
    /// linear momentum is kept; the force vanishes for any rigid motion of the slab.
    ///
    /// Springs between the layers would do this too, but diagonals steep enough to span a deep
    /// slab from one vertex to its neighbour's partner also resist compression by
    /// `2·G·Aₑ·(depth/Lₑ)²/depth` per edge: on a fine mesh, far stiffer than the slab itself, and
    /// that stiffness set the time step.
    pub fn add_slab_shear(&mut self) {
        let (position, force) = self.system.particles_mut().positions_and_forces_mut();
        accumulate_inner_normals(&self.inner, position, &mut self.inner_normals);
        let normals = &self.inner_normals;
        for (r, (&k, normal)) in self.shear.iter().zip(normals.iter()).enumerate() {
            if k == 0.0 {
                continue;
            }
            let outer = Self::particle(Layer::Outer, r as u32) as usize;
            let inner = outer + 1;
            let n = normal.normalize_or_zero();
            let slab = position[outer] - position[inner];
            let f = (slab - n * slab.dot(n)) * -k;
            force[outer] += f;
            force[inner] -= f;
        }
    }

    /// The largest stable step of symplectic Euler for the layers (s), the slab's shear included
    /// ([`MassSpringSystem::stable_time_step_with`]).
    pub fn stable_time_step(&self) -> Option<f32> {
        let extra: Vec<(u32, f64)> = self
            .shear
            .iter()
            .enumerate()
            .flat_map(|(r, &k)| {
                let outer = Self::particle(Layer::Outer, r as u32);
                [(outer, f64::from(k)), (outer + 1, f64::from(k))]
            })
            .collect();
        let mut extra = extra;
        extra.extend(crate::bending::row_stiffness(
            &self.hinges,
            self.system.particles().positions(),
        ));
        self.system.stable_time_step_with(&extra)
    }

    /// How many in-layer springs of very obtuse triangles keep only eq. (3)'s shear term (their
    /// eq. (3) sum was not positive; see `tissue_mss::springs_from_triangles_floored`).
    pub fn floored_springs(&self) -> usize {
        self.floored
    }

    /// The thinnest the slab may be (cm): [`LayerParams::min_thickness`] × depth.
    pub fn min_thickness(&self) -> f32 {
        self.min_thickness
    }

    /// The thickness guard as a penalty, for the quasi-static solver: every free layer-1
    /// particle closer than [`TissueLayers::min_thickness`] to layer 2 along layer 2's current
    /// normal is pushed out by `k·(min − gap)` and its layer-2 partner back, `k = factor ×
    /// diagonal[outer]`; adds the forces to `r` (per particle), the stiffness of each pair to
    /// `active`; returns how many pairs.
    pub(crate) fn thickness_forces(
        &mut self,
        factor: f64,
        diagonal: &[f64],
        r: &mut [glam::DVec3],
        active: &mut Vec<crate::quasi_static::Contact>,
    ) -> u32 {
        let min = self.min_thickness;
        if min <= 0.0 {
            return 0;
        }
        let particles = self.system.particles();
        let (position, inverse_mass) = (particles.positions(), particles.inverse_masses());
        accumulate_inner_normals(&self.inner, position, &mut self.inner_normals);
        let mut count = 0;
        for (v, normal) in self.inner_normals.iter().enumerate() {
            let outer = Self::particle(Layer::Outer, v as u32);
            let inner = Self::particle(Layer::Inner, v as u32);
            if inverse_mass[outer as usize] == 0.0 {
                continue;
            }
            let normal = normal.normalize_or_zero();
            let gap = (position[outer as usize] - position[inner as usize]).dot(normal);
            if gap < min {
                let k = factor * diagonal[outer as usize];
                let f = normal.as_dvec3() * (k * f64::from(min - gap));
                r[outer as usize] += f;
                let held = inverse_mass[inner as usize] > 0.0;
                if held {
                    r[inner as usize] -= f;
                }
                active.push(crate::quasi_static::Contact {
                    particles: [outer, inner, 0, 0],
                    c: [1.0, if held { -1.0 } else { 0.0 }, 0.0, 0.0],
                    normal: normal.as_dvec3(),
                    k,
                });
                count += 1;
            }
        }
        count
    }

    /// Keeps layer 1 at least [`TissueLayers::min_thickness`] above layer 2, measured along
    /// layer 2's current vertex normals; returns how many vertices it moved.
    ///
    /// Linear springs let a slab squeezed hard enough pass through zero thickness and turn
    /// inside out, a state tissue cannot reach (it thins and flows aside). A layer-1 particle
    /// found closer than the minimum is moved out to it, and the pair's approach along the
    /// normal is stopped by an inelastic impulse between the two particles (momentum
    /// conserved): layer 2 is its support, as the implant is layer 2's.
    pub fn hold_thickness(&mut self) -> u32 {
        let min = self.min_thickness;
        if min <= 0.0 {
            return 0;
        }
        let (position, velocity, inverse_mass) = self.system.particles_mut().state_mut();
        accumulate_inner_normals(&self.inner, position, &mut self.inner_normals);
        let normals = &self.inner_normals;
        let mut moved = 0;
        for (r, normal) in normals.iter().enumerate() {
            let outer = Self::particle(Layer::Outer, r as u32) as usize;
            let inner = Self::particle(Layer::Inner, r as u32) as usize;
            if inverse_mass[outer] == 0.0 {
                continue;
            }
            let normal = normal.normalize_or_zero();
            let gap = (position[outer] - position[inner]).dot(normal);
            if gap < min {
                position[outer] += normal * (min - gap);
                let approach = (velocity[outer] - velocity[inner]).dot(normal);
                if approach < 0.0 {
                    // An inelastic impulse between the two (momentum conserved): removing the
                    // approach from layer 1 alone fed a slow oscillation that kept Table 2's
                    // 150 cm³ run from settling when the impulse sums were merely reordered.
                    let (wo, wi) = (inverse_mass[outer], inverse_mass[inner]);
                    let j = -approach / (wo + wi);
                    velocity[outer] += normal * (j * wo);
                    velocity[inner] -= normal * (j * wi);
                }
                moved += 1;
            }
        }
        moved
    }

    /// Sets the rest metric of a grown skin (expansion over weeks): `theta_g[t]` is region triangle `t`'s
    /// area growth `θg ≥ 1` relative to its rest (scan) area. Every in-plane spring of both
    /// layers gets the rest length it had as built times `√θ̄g`, `θ̄g` the area-weighted mean of
    /// its edge's one or two triangles (in-plane isotropic growth, `Fg = √θg·I` in the plane);
    /// the springs through the thickness, the slab's shear, the anchors and the hinges are left
    /// as built (the thickness does not grow). All ones restore the skin as built.
    ///
    /// # Errors
    /// [`ImplantError::InvalidParameter`] when `theta_g` does not have one finite value ≥ 1 per
    /// region triangle.
    pub fn grow(&mut self, theta_g: &[f64]) -> Result<(), ImplantError> {
        let triangles = self.outer.triangle_count();
        if theta_g.len() != triangles {
            return Err(ImplantError::InvalidParameter {
                param: Param::ThetaG,
                value: theta_g.len() as f64,
                expected: format!("one area growth per region triangle ({triangles})"),
            });
        }
        if let Some((t, &g)) = theta_g
            .iter()
            .enumerate()
            .find(|(_, g)| !(g.is_finite() && **g >= 1.0))
        {
            return Err(ImplantError::InvalidParameter {
                param: Param::ThetaG,
                value: g,
                expected: format!("finite and ≥ 1 (skin does not resorb), at triangle {t}"),
            });
        }
        if self.growth_map.is_none() {
            let topo = self.outer.topology();
            let edges = topo.edges();
            let map: Vec<(u32, u32, f32)> = self
                .system
                .springs()
                .iter()
                .enumerate()
                .filter(|(_, s)| s.a % 2 == s.b % 2)
                .filter_map(|(i, s)| {
                    let (u, v) = (s.a / 2, s.b / 2);
                    let key = [u.min(v), u.max(v)];
                    edges
                        .binary_search(&key)
                        .ok()
                        .map(|e| (i as u32, e as u32, s.rest))
                })
                .collect();
            self.growth_map = Some(map);
        }
        let topo = self.outer.topology();
        let edge_triangles = topo.edge_triangles();
        let areas = self.outer.triangle_areas();
        let factor: Vec<f32> = edge_triangles
            .iter()
            .map(|pair| {
                let (mut sum, mut weight) = (0.0, 0.0);
                for &t in pair {
                    if t != tissue_mesh::NO_TRIANGLE {
                        sum += theta_g[t as usize] * areas[t as usize];
                        weight += areas[t as usize];
                    }
                }
                if weight > 0.0 {
                    (sum / weight).sqrt() as f32
                } else {
                    1.0
                }
            })
            .collect();
        let map = self.growth_map.as_deref().unwrap_or(&[]);
        let mut rest = vec![None; self.system.springs().len()];
        for &(i, e, r0) in map {
            rest[i as usize] = Some(r0 * factor[e as usize]);
        }
        self.system
            .set_rest_lengths(|i, s| rest[i].unwrap_or(s.rest))?;
        Ok(())
    }

    /// Scales the skin's stiffness (layer 1's in-plane springs and bending hinges) by `factor`
    /// from what it is now: the band's stiffness samples, warm-started from a settled state.
    ///
    /// # Errors
    /// [`ImplantError::InvalidParameter`] for a factor that is not positive and finite.
    pub fn scale_skin_stiffness(&mut self, factor: f64) -> Result<(), ImplantError> {
        if !(factor.is_finite() && factor > 0.0) {
            return Err(ImplantError::InvalidParameter {
                param: Param::Stiffness,
                value: factor,
                expected: "a positive, finite factor".into(),
            });
        }
        let f = factor as f32;
        self.system.set_stiffnesses(|_, s| {
            if s.a % 2 == 0 && s.b % 2 == 0 {
                s.k * f
            } else {
                s.k
            }
        })?;
        for h in &mut self.hinges {
            h.k *= f;
        }
        Ok(())
    }

    /// Writes every region triangle's total area stretch `θ = A / A_rest` of layer 1 (current
    /// area over rest area) into `out` (one per triangle; no allocation).
    pub fn area_stretch(&self, out: &mut [f64]) {
        let position = self.system.particles().positions();
        let rest = self.outer.positions();
        let at = |v: u32| position[Self::particle(Layer::Outer, v) as usize];
        for (o, &[a, b, c]) in out.iter_mut().zip(self.outer.triangles()) {
            let now = 0.5 * f64::from((at(b) - at(a)).cross(at(c) - at(a)).length());
            let (ra, rb, rc) = (rest[a as usize], rest[b as usize], rest[c as usize]);
            let was = 0.5 * f64::from((rb - ra).cross(rc - ra).length());
            *o = if was > 0.0 { now / was } else { 1.0 };
        }
    }

    /// The current area of layer 1 (cm²), from the particles' positions (no allocation).
    pub fn outer_area(&self) -> f64 {
        let position = self.system.particles().positions();
        let at = |v: u32| position[Self::particle(Layer::Outer, v) as usize];
        self.outer
            .triangles()
            .iter()
            .map(|&[a, b, c]| {
                let (a, b, c) = (at(a), at(b), at(c));
                0.5 * f64::from((b - a).cross(c - a).length())
            })
            .sum()
    }

    /// Detaches layer 2 from the deeper tissue at the region vertices `pocket` accepts (their
    /// anchors are removed): the pocket a surgeon dissects for the expander. Returns how many
    /// were detached.
    pub fn detach(&mut self, mut pocket: impl FnMut(u32) -> bool) -> usize {
        let before = self.system.anchored_particles().count();
        self.system
            .retain_anchors(|p| !(p % 2 == Layer::Inner as u32 && pocket(p / 2)));
        before - self.system.anchored_particles().count()
    }

    /// The particle of region vertex `vertex` in `layer`.
    pub const fn particle(layer: Layer, vertex: u32) -> u32 {
        2 * vertex + layer as u32
    }

    /// The mass–spring system (both layers).
    pub fn system(&self) -> &MassSpringSystem {
        &self.system
    }

    /// The mass–spring system, to step it, add forces or set damping and gravity.
    pub fn system_mut(&mut self) -> &mut MassSpringSystem {
        &mut self.system
    }

    /// A layer at rest (as built).
    pub fn rest(&self, layer: Layer) -> &TriMesh {
        match layer {
            Layer::Outer => &self.outer,
            Layer::Inner => &self.inner,
        }
    }

    /// The directions layer 2 was offset along at rest (unit, out of the body): the vertex
    /// normals averaged over the placement depth (see `offset_normals`).
    pub fn normals(&self) -> &[Vec3] {
        &self.normals
    }

    /// Region vertices on the boundary (fixed in both layers), in increasing order.
    pub fn boundary(&self) -> &[u32] {
        &self.boundary
    }

    /// Current positions of one layer, by region vertex.
    pub fn positions(&self, layer: Layer) -> Vec<Vec3> {
        self.system
            .particles()
            .positions()
            .iter()
            .skip(layer as usize)
            .step_by(2)
            .map(|&p| Vec3::from(p))
            .collect()
    }

    /// One layer as a mesh at its current positions.
    pub fn current(&self, layer: Layer) -> Result<TriMesh, ImplantError> {
        Ok(self.rest(layer).with_positions(self.positions(layer))?)
    }

    /// Moves every free particle of both layers `height` (cm) outward along the region's rest
    /// normals: the thesis's start, with the tissue lifted by the implant's height. (The insertion
    /// run fills the expander under the resting tissue instead; see `Insertion`.)
    pub fn lift(&mut self, height: f32) -> Result<(), ImplantError> {
        let heights = vec![height; self.normals.len()];
        self.lift_by(&heights)
    }

    /// Moves the free particles of region vertex `r` in both layers `heights[r]` (cm) outward
    /// along the region's rest normal at `r`.
    ///
    /// # Errors
    /// [`ImplantError::InvalidParameter`] for a wrong length or a non-finite height (the
    /// message names the vertex); nothing is moved then.
    pub fn lift_by(&mut self, heights: &[f32]) -> Result<(), ImplantError> {
        if heights.len() != self.normals.len() {
            return Err(ImplantError::InvalidParameter {
                param: Param::Heights,
                value: heights.len() as f64,
                expected: format!("one height per region vertex ({})", self.normals.len()),
            });
        }
        if let Some(r) = heights.iter().position(|h| !h.is_finite()) {
            return Err(ImplantError::InvalidParameter {
                param: Param::Heights,
                value: f64::from(heights[r]),
                expected: format!("finite (region vertex {r})"),
            });
        }
        let particles = self.system.particles_mut();
        let free: Vec<bool> = particles
            .inverse_masses()
            .iter()
            .map(|&w| w > 0.0)
            .collect();
        for (i, x) in particles.positions_mut().iter_mut().enumerate() {
            if free[i] {
                *x += Vec3A::from(self.normals[i / 2] * heights[i / 2]);
            }
        }
        Ok(())
    }
}

/// `out[r]` = layer 2's area-weighted (unnormalised) normal at region vertex `r`, from the
/// interleaved particle `position`s (layer 2's particle of `r` is `2r + 1`).
fn accumulate_inner_normals(inner: &TriMesh, position: &[Vec3A], out: &mut [Vec3A]) {
    out.iter_mut().for_each(|n| *n = Vec3A::ZERO);
    for t in inner.triangles() {
        let [a, b, c] = t.map(|r| position[TissueLayers::particle(Layer::Inner, r) as usize]);
        let normal = (b - a).cross(c - a);
        for &r in t {
            out[r as usize] += normal;
        }
    }
}
