//! The static problem (body, loads, supports, rigid obstacles) and its Newton solver.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::prelude::Reborrow;
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, LltRef, SymbolicCholesky, SymmetricOrdering,
};
use faer::sparse::{SparseColMat, SymbolicSparseColMat};
use faer::{Conj, Mat, Par, Side};
use glam::DVec3;
use tissue_mesh::TetMesh;

use crate::energy::{StableNeoHookean, TetElement};
use crate::material::{ElasticMaterial, FemError};

const NONE: u32 = u32::MAX;

/// Standard gravity, cm/s².
pub const GRAVITY: f64 = 981.0;

/// A plane `{x : (x − point)·normal = 0}`; `normal` (unit after validation) points to the side
/// where the body is allowed (a floor's normal points up).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Plane {
    /// A point of the plane, cm.
    pub point: DVec3,
    /// Unit normal towards the body.
    pub normal: DVec3,
}

impl Plane {
    /// A horizontal floor `z = height` (normal `+z`).
    pub fn floor(height: f64) -> Self {
        Plane {
            point: DVec3::new(0.0, 0.0, height),
            normal: DVec3::Z,
        }
    }
}

/// A rigid flat plate: `rest` moved by `displacement` (cm, ≥ 0) along its normal, i.e. into the
/// body. A plate resting on top of a body at `z = h` and pressed down is `rest = Plane { point:
/// (0, 0, h), normal: −z }`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Plate {
    /// The plate's plane before it moves.
    pub rest: Plane,
    /// How far it moves along `rest.normal`, cm.
    pub displacement: f64,
}

/// A rigid sphere of `radius` (cm) that touches the rest surface at `contact` and is pushed
/// `depth` (cm) along `direction` (unit, into the body): its centre is
/// `contact + direction (depth − radius)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SphereIndenter {
    /// Where the undisplaced sphere touches the body, cm.
    pub contact: DVec3,
    /// The direction of indentation (into the body).
    pub direction: DVec3,
    /// Radius, cm.
    pub radius: f64,
    /// Indentation depth, cm.
    pub depth: f64,
}

impl SphereIndenter {
    /// The centre at a fraction `t` of the depth.
    pub fn centre(&self, t: f64) -> DVec3 {
        self.contact + self.direction * (t * self.depth - self.radius)
    }
}

/// The solver's knobs. The defaults are what the tests use.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SolverSettings {
    /// Newton stops when `‖r‖₂ ≤ residual_tolerance · scale`: `r` the net force on the free
    /// degrees of freedom, `scale` the larger of the norms of gravity, of the contact forces and
    /// of the support reactions over all nodes (dyn). Default `1e-8`.
    pub residual_tolerance: f64,
    /// Newton iterations allowed per load step. Default 60.
    pub max_iterations: usize,
    /// Gravity, plate displacement, indentation depth and prescribed positions are ramped up in
    /// this many equal steps, each solved to the tolerance. Default 1.
    pub load_steps: usize,
    /// The contact penalty of a boundary node is `contact_stiffness · E · ℓ` (g/s²), `ℓ` the
    /// cube root of the node's lumped volume: this many times the stiffness of an elastic cube
    /// the node's size. Default `1e3`.
    pub contact_stiffness: f64,
    /// Where the exact tangent is not positive definite, project each element's `∂²Ψ/∂F²` to
    /// positive semidefinite (default `true`; the exact tangent is tried first in each Newton
    /// iteration, and after a failure the projected one is used until the residual has fallen
    /// tenfold). With `false` the exact tangent is always used, shifted when it cannot be
    /// factored.
    pub project_hessian: bool,
}

impl Default for SolverSettings {
    fn default() -> Self {
        SolverSettings {
            residual_tolerance: 1e-8,
            max_iterations: 60,
            load_steps: 1,
            contact_stiffness: 1e3,
            project_hessian: true,
        }
    }
}

/// How a solve went.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StaticReport {
    /// Whether every load step met the tolerance.
    pub converged: bool,
    /// Newton iterations over all load steps.
    pub iterations: usize,
    /// Load steps solved.
    pub load_steps: usize,
    /// The final `‖r‖₂` over the free degrees of freedom, dyn.
    pub residual: f64,
    /// The final force scale (see [`SolverSettings::residual_tolerance`]), dyn.
    pub force_scale: f64,
    /// `residual / force_scale` (0 when both are 0).
    pub relative_residual: f64,
    /// The tolerance used.
    pub tolerance: f64,
    /// The total potential energy at the end, erg (elastic + gravity + contact penalty).
    pub energy: f64,
    /// Factorisations that needed a diagonal shift.
    pub shifted_factorisations: usize,
    /// The deepest penetration of a node into an obstacle at the end, cm (penalty contact).
    pub max_penetration: f64,
}

/// The equilibrium and the forces the supports carry.
#[derive(Debug, Clone, PartialEq)]
pub struct StaticSolution {
    /// Deformed positions, cm, one per mesh vertex.
    pub positions: Vec<DVec3>,
    /// Rest positions, cm.
    pub rest: Vec<DVec3>,
    /// The force the floor exerts on the body, dyn.
    pub floor_force: DVec3,
    /// The force the plate exerts on the body, dyn (the force on the plate is its negative).
    pub plate_force: DVec3,
    /// The force the indenter exerts on the body, dyn (the force on the indenter is its negative).
    pub indenter_force: DVec3,
    /// The sum of the support reactions at the fixed degrees of freedom, dyn.
    pub clamp_force: DVec3,
    /// The reaction on each node (non-zero only on fixed axes), dyn.
    pub reactions: Vec<DVec3>,
    /// The total weight force `Σ mᵢ g`, dyn.
    pub weight: DVec3,
    /// How the solve went.
    pub report: StaticReport,
}

impl StaticSolution {
    /// The displacement of a node (zero for an index out of range).
    pub fn displacement(&self, node: u32) -> DVec3 {
        let i = node as usize;
        match (self.positions.get(i), self.rest.get(i)) {
            (Some(x), Some(r)) => *x - *r,
            _ => DVec3::ZERO,
        }
    }

    /// The mean displacement of some nodes (zero for none).
    pub fn mean_displacement(&self, nodes: &[u32]) -> DVec3 {
        if nodes.is_empty() {
            return DVec3::ZERO;
        }
        nodes.iter().map(|&n| self.displacement(n)).sum::<DVec3>() / nodes.len() as f64
    }

    /// The node that moved most and its displacement.
    pub fn max_displacement(&self) -> (u32, DVec3) {
        let mut best = (0, DVec3::ZERO);
        for (i, (x, r)) in self.positions.iter().zip(&self.rest).enumerate() {
            let d = *x - *r;
            if d.length_squared() > best.1.length_squared() {
                best = (i as u32, d);
            }
        }
        best
    }
}

/// A static equilibrium problem on a tetrahedral mesh: minimise the total potential energy
/// (stable neo-Hookean elastic energy − gravity's work + contact penalties) over the free
/// positions.
#[derive(Debug, Clone)]
pub struct StaticProblem {
    material: ElasticMaterial,
    model: StableNeoHookean,
    rest: Vec<DVec3>,
    tets: Vec<[u32; 4]>,
    elements: Vec<TetElement>,
    /// Lumped mass of each node, g.
    mass: Vec<f64>,
    /// Whether a node belongs to a tetrahedron.
    referenced: Vec<bool>,
    /// Boundary vertices, the only ones that touch obstacles.
    surface: Vec<u32>,
    /// Per-node contact penalty, g/s² (0 off the surface).
    contact_k: Vec<f64>,
    /// Whether a node is a boundary vertex.
    on_surface: Vec<bool>,
    /// The floor as a bound on one coordinate when its normal is a coordinate axis (see
    /// [`StaticProblem::set_floor`]); `None` for no floor or a tilted one (penalty contact).
    floor_bound: Option<FloorBound>,
    /// How far above the floor (cm) a vertex still counts as on it: round-off, `10⁻¹²` of the
    /// body's size.
    bound_slack: f64,
    fixed: Vec<[bool; 3]>,
    targets: Vec<DVec3>,
    gravity: DVec3,
    floor: Option<Plane>,
    plate: Option<Plate>,
    indenter: Option<SphereIndenter>,
    settings: SolverSettings,
}

fn problem(what: String, fix: &'static str) -> FemError {
    FemError::Problem { what, fix }
}

fn unit(v: DVec3, name: &str) -> Result<DVec3, FemError> {
    let len = v.length();
    if !(len.is_finite() && len > 0.0) {
        return Err(problem(
            format!("{name} = {v} has no direction"),
            "give a finite non-zero vector",
        ));
    }
    Ok(v / len)
}

fn finite_point(p: DVec3, name: &str) -> Result<(), FemError> {
    if p.is_finite() {
        Ok(())
    } else {
        Err(problem(
            format!("{name} = {p} is not finite"),
            "give finite coordinates in cm",
        ))
    }
}

impl StaticProblem {
    /// A body of `material` on `mesh` (cm), under standard gravity `(0, 0, −981)` cm/s², with no
    /// support yet.
    ///
    /// # Errors
    /// [`FemError::Material`] for a bad material; [`FemError::DegenerateTet`] for a flat rest
    /// tetrahedron (a [`TetMesh`] has none, but its `f32` positions are re-read in `f64`).
    pub fn new(mesh: &TetMesh, material: ElasticMaterial) -> Result<Self, FemError> {
        material.validate()?;
        let _span = tracing::debug_span!("fem_problem", tets = mesh.tet_count()).entered();
        let rest: Vec<DVec3> = mesh.positions().iter().map(|p| p.as_dvec3()).collect();
        let tets = mesh.tets().to_vec();
        let n = rest.len();
        let mut elements = Vec::with_capacity(tets.len());
        let mut volume = vec![0.0; n];
        let mut referenced = vec![false; n];
        for (t, tet) in tets.iter().enumerate() {
            let x = tet.map(|i| rest[i as usize]);
            let element = TetElement::new(x).ok_or_else(|| FemError::DegenerateTet {
                tet: t,
                six_volume: (x[1] - x[0]).cross(x[2] - x[0]).dot(x[3] - x[0]),
            })?;
            for &i in tet {
                volume[i as usize] += element.volume / 4.0;
                referenced[i as usize] = true;
            }
            elements.push(element);
        }
        let mass = volume.iter().map(|v| v * material.density).collect();
        let mut on_surface = vec![false; n];
        for face in mesh.boundary_faces() {
            for &i in face {
                on_surface[i as usize] = true;
            }
        }
        let surface = (0..n as u32).filter(|&i| on_surface[i as usize]).collect();
        let extent = rest
            .iter()
            .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), p| {
                (lo.min(*p), hi.max(*p))
            });
        let size = (extent.1 - extent.0).length();
        let settings = SolverSettings::default();
        let mut p = StaticProblem {
            material,
            model: StableNeoHookean::new(&material),
            targets: rest.clone(),
            rest,
            tets,
            elements,
            mass,
            referenced,
            surface,
            contact_k: Vec::new(),
            on_surface,
            floor_bound: None,
            bound_slack: 1e-12 * if size.is_finite() { size.max(1.0) } else { 1.0 },
            fixed: vec![[false; 3]; n],
            gravity: DVec3::new(0.0, 0.0, -GRAVITY),
            floor: None,
            plate: None,
            indenter: None,
            settings,
        };
        p.update_contact_stiffness(&volume);
        Ok(p)
    }

    fn update_contact_stiffness(&mut self, volume: &[f64]) {
        let e = self.material.young();
        let kappa = self.settings.contact_stiffness;
        let mut k = vec![0.0; self.rest.len()];
        for &i in &self.surface {
            k[i as usize] = kappa * e * volume[i as usize].cbrt();
        }
        self.contact_k = k;
    }

    /// The material.
    pub fn material(&self) -> &ElasticMaterial {
        &self.material
    }

    /// The energy density in use.
    pub fn model(&self) -> &StableNeoHookean {
        &self.model
    }

    /// Rest positions, cm (the mesh's, in `f64`).
    pub fn rest_positions(&self) -> &[DVec3] {
        &self.rest
    }

    /// Lumped nodal masses, g (`ρ Σ V/4` over the node's tetrahedra).
    pub fn masses(&self) -> &[f64] {
        &self.mass
    }

    /// The nodes whose rest position satisfies `pred`.
    pub fn nodes_where(&self, pred: impl Fn(DVec3) -> bool) -> Vec<u32> {
        (0..self.rest.len() as u32)
            .filter(|&i| pred(self.rest[i as usize]))
            .collect()
    }

    /// The solver settings.
    pub fn settings(&self) -> &SolverSettings {
        &self.settings
    }

    /// Replaces the solver settings.
    ///
    /// # Errors
    /// [`FemError::Problem`] for a tolerance that is not finite and positive, no iterations or
    /// load steps, or a contact stiffness that is not finite and positive.
    pub fn set_settings(&mut self, settings: SolverSettings) -> Result<(), FemError> {
        if !(settings.residual_tolerance.is_finite() && settings.residual_tolerance > 0.0) {
            return Err(problem(
                format!("residual_tolerance = {}", settings.residual_tolerance),
                "give a finite positive relative tolerance, e.g. 1e-8",
            ));
        }
        if settings.max_iterations == 0 || settings.load_steps == 0 {
            return Err(problem(
                format!(
                    "max_iterations = {}, load_steps = {}",
                    settings.max_iterations, settings.load_steps
                ),
                "give at least one iteration and one load step",
            ));
        }
        if !(settings.contact_stiffness.is_finite() && settings.contact_stiffness > 0.0) {
            return Err(problem(
                format!("contact_stiffness = {}", settings.contact_stiffness),
                "give a finite positive factor, e.g. 1e3",
            ));
        }
        self.settings = settings;
        let mut volume = vec![0.0; self.rest.len()];
        for (tet, e) in self.tets.iter().zip(&self.elements) {
            for &i in tet {
                volume[i as usize] += e.volume / 4.0;
            }
        }
        self.update_contact_stiffness(&volume);
        Ok(())
    }

    /// Sets gravity (cm/s², default `(0, 0, −981)`).
    ///
    /// # Errors
    /// [`FemError::Problem`] when not finite.
    pub fn set_gravity(&mut self, gravity: DVec3) -> Result<(), FemError> {
        finite_point(gravity, "gravity")?;
        self.gravity = gravity;
        Ok(())
    }

    fn check_node(&self, node: u32) -> Result<usize, FemError> {
        let i = node as usize;
        if i >= self.rest.len() {
            return Err(problem(
                format!("node {node} (the mesh has {} vertices)", self.rest.len()),
                "give the index of a mesh vertex",
            ));
        }
        Ok(i)
    }

    /// Clamps a node at its rest position (all three axes).
    ///
    /// # Errors
    /// [`FemError::Problem`] for an index out of range.
    pub fn clamp(&mut self, node: u32) -> Result<(), FemError> {
        let i = self.check_node(node)?;
        self.fixed[i] = [true; 3];
        self.targets[i] = self.rest[i];
        Ok(())
    }

    /// Clamps a node at a given position (reached gradually over the load steps).
    ///
    /// # Errors
    /// [`FemError::Problem`] for an index out of range or a position that is not finite.
    pub fn clamp_at(&mut self, node: u32, position: DVec3) -> Result<(), FemError> {
        let i = self.check_node(node)?;
        finite_point(position, "clamp position")?;
        self.fixed[i] = [true; 3];
        self.targets[i] = position;
        Ok(())
    }

    /// Holds the chosen axes of a node at their rest coordinates and frees the others (a
    /// roller: e.g. `[true, true, false]` stops a node sliding sideways but lets it move
    /// vertically; symmetry planes hold the normal axis).
    ///
    /// # Errors
    /// [`FemError::Problem`] for an index out of range.
    pub fn fix_axes(&mut self, node: u32, axes: [bool; 3]) -> Result<(), FemError> {
        let i = self.check_node(node)?;
        self.fixed[i] = axes;
        self.targets[i] = self.rest[i];
        Ok(())
    }

    /// Clamps every node whose rest position satisfies `pred`; returns how many.
    pub fn clamp_where(&mut self, pred: impl Fn(DVec3) -> bool) -> usize {
        let nodes = self.nodes_where(pred);
        for &i in &nodes {
            self.fixed[i as usize] = [true; 3];
            self.targets[i as usize] = self.rest[i as usize];
        }
        nodes.len()
    }

    /// Puts a rigid frictionless floor under the body (replacing any). A floor whose normal is
    /// a coordinate axis bounds the boundary vertices' coordinate along it (exact contact, no
    /// penetration; see the crate's documentation); a tilted one acts through the contact
    /// penalty of [`SolverSettings::contact_stiffness`].
    ///
    /// # Errors
    /// [`FemError::Problem`] for a non-finite point or a zero normal.
    pub fn set_floor(&mut self, floor: Plane) -> Result<(), FemError> {
        finite_point(floor.point, "floor point")?;
        let normal = unit(floor.normal, "floor normal")?;
        self.floor = Some(Plane { normal, ..floor });
        self.floor_bound = (0..3)
            .find(|&a| (normal[a].abs() - 1.0).abs() <= 1e-12)
            .map(|axis| FloorBound {
                axis,
                sign: normal[axis].signum(),
                level: floor.point[axis],
            });
        Ok(())
    }

    /// Puts a rigid frictionless plate on the body (replacing any).
    ///
    /// # Errors
    /// [`FemError::Problem`] for a non-finite point or displacement or a zero normal.
    pub fn set_plate(&mut self, plate: Plate) -> Result<(), FemError> {
        finite_point(plate.rest.point, "plate point")?;
        let normal = unit(plate.rest.normal, "plate normal")?;
        if !plate.displacement.is_finite() {
            return Err(problem(
                format!("plate displacement = {}", plate.displacement),
                "give a finite displacement in cm",
            ));
        }
        self.plate = Some(Plate {
            rest: Plane {
                normal,
                ..plate.rest
            },
            ..plate
        });
        Ok(())
    }

    /// Puts a rigid frictionless spherical indenter on the body (replacing any).
    ///
    /// # Errors
    /// [`FemError::Problem`] for a non-finite contact point, a zero direction, a radius that is
    /// not finite and positive, or a depth that is not finite.
    pub fn set_indenter(&mut self, indenter: SphereIndenter) -> Result<(), FemError> {
        finite_point(indenter.contact, "indenter contact")?;
        let direction = unit(indenter.direction, "indenter direction")?;
        if !(indenter.radius.is_finite() && indenter.radius > 0.0) {
            return Err(problem(
                format!("indenter radius = {} cm", indenter.radius),
                "give a finite positive radius in cm",
            ));
        }
        if !indenter.depth.is_finite() {
            return Err(problem(
                format!("indenter depth = {} cm", indenter.depth),
                "give a finite depth in cm",
            ));
        }
        self.indenter = Some(SphereIndenter {
            direction,
            ..indenter
        });
        Ok(())
    }

    /// Solves for the static equilibrium from the rest shape (see [`SolverSettings`]).
    ///
    /// A body must be held against rigid motion: clamped nodes, or a floor plus
    /// [`StaticProblem::fix_axes`] on a few nodes for the sideways motions a frictionless floor
    /// allows. When the tangent stiffness cannot be factored the solver adds
    /// `10⁻⁸, 10⁻⁶, …, 10⁻²` times its largest diagonal entry before giving up; when the line
    /// search rejects a Newton step (a nearly singular tangent) the step is recomputed with
    /// `10⁻⁶, 10⁻⁴, 10⁻², 1` times that entry on the diagonal (towards gradient descent).
    /// The first Newton step starts from the rest shape (vertices below an axis-aligned floor
    /// put onto it); vertices touching the floor hold from the first step, and vertices
    /// touching a penalty obstacle exactly (gap 0) already get its stiffness in the tangent, so
    /// a body resting on the floor at the start is supported from the first step.
    ///
    /// # Errors
    /// [`FemError::Factorisation`] when the tangent stiffness cannot be factored even so.
    /// Running out of iterations is not an error: see [`StaticReport::converged`].
    pub fn solve(&self) -> Result<StaticSolution, FemError> {
        let _span =
            tracing::info_span!("fem_solve", nodes = self.rest.len(), tets = self.tets.len())
                .entered();
        let mut ws = Workspace::new(self)?;
        let steps = self.settings.load_steps;
        let mut report = StaticReport {
            converged: true,
            iterations: 0,
            load_steps: steps,
            residual: 0.0,
            force_scale: 0.0,
            relative_residual: 0.0,
            tolerance: self.settings.residual_tolerance,
            energy: 0.0,
            shifted_factorisations: 0,
            max_penetration: 0.0,
        };
        for step in 1..=steps {
            let t = step as f64 / steps as f64;
            let _span = tracing::debug_span!("load_step", step, t).entered();
            let ok = self.newton(&mut ws, t, &mut report)?;
            report.converged &= ok;
        }
        // Final forces at the equilibrium.
        let t = 1.0;
        let forces = self.gradient(&ws.u, t, &mut ws.grad);
        let mut reactions = vec![DVec3::ZERO; self.rest.len()];
        let mut clamp_force = DVec3::ZERO;
        for (i, fixed) in self.fixed.iter().enumerate() {
            for a in 0..3 {
                if fixed[a] || !self.referenced[i] {
                    reactions[i][a] = ws.grad[i][a];
                }
            }
            clamp_force += reactions[i];
        }
        report.energy = self.energy(&ws.u, t).total;
        report.max_penetration = forces.max_penetration;
        let weight = self.gravity * self.mass.iter().sum::<f64>();
        Ok(StaticSolution {
            positions: self.rest.iter().zip(&ws.u).map(|(r, u)| *r + *u).collect(),
            rest: self.rest.clone(),
            floor_force: forces.floor,
            plate_force: forces.plate,
            indenter_force: forces.indenter,
            clamp_force,
            reactions,
            weight,
            report,
        })
    }

    fn is_free(&self, i: usize, a: usize) -> bool {
        self.referenced[i] && !self.fixed[i][a]
    }

    /// The floor's bound on node `i` if the node can touch it (a boundary vertex whose
    /// coordinate along the floor's normal is free): the bound and the node's gap above it at
    /// displacement `u`, cm.
    #[inline]
    fn floor_gap(&self, i: usize, u: DVec3) -> Option<(FloorBound, f64)> {
        let b = self.floor_bound?;
        if !(self.on_surface[i] && self.is_free(i, b.axis)) {
            return None;
        }
        Some((b, b.sign * (self.rest[i][b.axis] + u[b.axis] - b.level)))
    }

    /// The floor's reaction on node `i` (along its normal, dyn) when the floor holds it: the
    /// node is on the floor (within `bound_slack`) and the rest of the model
    /// pushes it into the floor (`grad` is the energy gradient at the node).
    #[inline]
    fn floor_holds(&self, i: usize, u: DVec3, grad: DVec3) -> Option<f64> {
        let (b, gap) = self.floor_gap(i, u)?;
        let reaction = b.sign * grad[b.axis];
        (gap <= self.bound_slack && reaction >= 0.0).then_some(reaction)
    }

    /// Moves every node below the floor back onto it.
    fn project_onto_floor(&self, u: &mut [DVec3]) {
        if self.floor_bound.is_none() {
            return;
        }
        for &i in &self.surface {
            let i = i as usize;
            if let Some((b, gap)) = self.floor_gap(i, u[i]) {
                if gap < 0.0 {
                    u[i][b.axis] = b.level - self.rest[i][b.axis];
                }
            }
        }
    }

    /// The obstacles at load fraction `t`: `[floor, plate, indenter]`; the floor only when it
    /// is tilted (a penalty contact; an axis-aligned floor is a bound on the unknowns).
    fn obstacles(&self, t: f64) -> [Option<Obstacle>; 3] {
        [
            self.floor
                .filter(|_| self.floor_bound.is_none())
                .map(|p| Obstacle::Plane(p.point, p.normal)),
            self.plate.map(|p| {
                Obstacle::Plane(
                    p.rest.point + p.rest.normal * (t * p.displacement),
                    p.rest.normal,
                )
            }),
            self.indenter
                .map(|s| Obstacle::Sphere(s.centre(t), s.radius)),
        ]
    }

    /// Total potential energy at displacements `u`, load fraction `t`.
    fn energy(&self, u: &[DVec3], t: f64) -> Energy {
        let mut elastic = 0.0;
        for (tet, e) in self.tets.iter().zip(&self.elements) {
            let f = e.displacement_gradient(&tet.map(|i| u[i as usize]));
            elastic += e.energy_at(&self.model, &f);
        }
        let g = self.gravity * t;
        let mut gravity = 0.0;
        for (ui, m) in u.iter().zip(&self.mass) {
            gravity -= m * g.dot(*ui);
        }
        let mut contact = 0.0;
        for obstacle in self.obstacles(t).iter().flatten() {
            for &i in &self.surface {
                let gap = obstacle.gap(self.rest[i as usize] + u[i as usize]);
                if gap < 0.0 {
                    contact += 0.5 * self.contact_k[i as usize] * gap * gap;
                }
            }
        }
        Energy {
            total: elastic + gravity + contact,
            magnitude: elastic + gravity.abs() + contact,
        }
    }

    /// The energy gradient at displacements `u` at every node (fixed ones included) into
    /// `grad`; returns the contact forces and the force scale.
    fn gradient(&self, u: &[DVec3], t: f64, grad: &mut [DVec3]) -> Forces {
        let g = self.gravity * t;
        let mut gravity_norm2 = 0.0;
        for (gi, m) in grad.iter_mut().zip(&self.mass) {
            *gi = -g * *m;
            gravity_norm2 += gi.length_squared();
        }
        for (tet, e) in self.tets.iter().zip(&self.elements) {
            let f = e.displacement_gradient(&tet.map(|i| u[i as usize]));
            let ge = e.gradient_at(&self.model, &f);
            for (a, &i) in tet.iter().enumerate() {
                grad[i as usize] += ge[a];
            }
        }
        let mut forces = Forces::default();
        let mut contact_norm2 = 0.0;
        for (k, obstacle) in self.obstacles(t).iter().enumerate() {
            let Some(obstacle) = obstacle else { continue };
            let mut total = DVec3::ZERO;
            for &i in &self.surface {
                let (gap, n) = obstacle.gap_normal(self.rest[i as usize] + u[i as usize]);
                if gap < 0.0 {
                    // Force on the body: −k g n (pushes out along n).
                    let f = n * (-self.contact_k[i as usize] * gap);
                    grad[i as usize] -= f;
                    total += f;
                    contact_norm2 += f.length_squared();
                    forces.max_penetration = forces.max_penetration.max(-gap);
                }
            }
            match k {
                0 => forces.floor = total,
                1 => forces.plate = total,
                _ => forces.indenter = total,
            }
        }
        if let Some(b) = self.floor_bound {
            // The floor holds the nodes on it that the rest pushes into it; its reaction there
            // is what is left of the gradient along its normal.
            let mut normal = DVec3::ZERO;
            normal[b.axis] = b.sign;
            let mut total = DVec3::ZERO;
            for &i in &self.surface {
                let i = i as usize;
                if let Some((_, gap)) = self.floor_gap(i, u[i]) {
                    forces.max_penetration = forces.max_penetration.max(-gap);
                    if let Some(reaction) = self.floor_holds(i, u[i], grad[i]) {
                        total += normal * reaction;
                        contact_norm2 += reaction * reaction;
                    }
                }
            }
            forces.floor = total;
        }
        let mut residual2 = 0.0;
        let mut reaction2 = 0.0;
        for (i, gi) in grad.iter().enumerate() {
            let held = self
                .floor_bound
                .filter(|_| self.floor_holds(i, u[i], *gi).is_some())
                .map(|b| b.axis);
            for a in 0..3 {
                if held == Some(a) {
                    continue;
                }
                if self.is_free(i, a) {
                    residual2 += gi[a] * gi[a];
                } else {
                    reaction2 += gi[a] * gi[a];
                }
            }
        }
        forces.residual = residual2.sqrt();
        forces.scale = gravity_norm2
            .sqrt()
            .max(contact_norm2.sqrt())
            .max(reaction2.sqrt());
        forces
    }

    /// Assembles the (projected) tangent stiffness of the free degrees of freedom into the
    /// matrix's values.
    fn assemble_hessian(&self, ws: &mut Workspace, t: f64, project: bool) {
        let _span = tracing::trace_span!("assemble", project).entered();
        let values = &mut ws.assembled;
        values.iter_mut().for_each(|v| *v = 0.0);
        for (e, (tet, element)) in self.tets.iter().zip(&self.elements).enumerate() {
            let f = element.displacement_gradient(&tet.map(|i| ws.u[i as usize]));
            let h = element.hessian_at(&self.model, &f, project);
            let map = &ws.scatter[e * 144..e * 144 + 144];
            for (r, row) in h.iter().enumerate() {
                for (c, &v) in row.iter().enumerate() {
                    let at = map[r * 12 + c];
                    if at != NONE {
                        values[at as usize] += v;
                    }
                }
            }
        }
        for obstacle in self.obstacles(t).iter().flatten() {
            for (s, &i) in self.surface.iter().enumerate() {
                let (gap, n) = obstacle.gap_normal(self.rest[i as usize] + ws.u[i as usize]);
                // Touching vertices (gap = 0, e.g. a body resting on the floor at the start)
                // get the stiffness too, so that the first step knows about the support.
                if gap <= 0.0 {
                    // k n nᵀ; the sphere's curvature term k g/|x − c| (I − n nᵀ) is negative
                    // inside the sphere and is left out so that the matrix stays PSD.
                    let k = self.contact_k[i as usize];
                    let block = &ws.surface_block[s];
                    for a in 0..3 {
                        for b in 0..3 {
                            let at = block[a * 3 + b];
                            if at != NONE {
                                values[at as usize] += k * n[a] * n[b];
                            }
                        }
                    }
                }
            }
        }
    }

    /// Takes the degrees of freedom the floor holds out of the assembled tangent: their rows
    /// and columns are zeroed but for the diagonal, so their Newton step is zero and the rest
    /// is solved as if they were fixed.
    fn eliminate_held(&self, ws: &mut Workspace) {
        if !ws.held.iter().any(|&h| h) {
            return;
        }
        let symbolic = ws.matrix.symbolic();
        let (col_ptr, row_idx) = (symbolic.col_ptr(), symbolic.row_idx());
        for (c, window) in col_ptr.windows(2).enumerate() {
            let range = window[0]..window[1];
            for (v, &r) in ws.assembled[range.clone()].iter_mut().zip(&row_idx[range]) {
                if r != c && (ws.held[r] || ws.held[c]) {
                    *v = 0.0;
                }
            }
        }
    }

    /// Factors the assembled matrix plus `shift` times its largest diagonal entry on the
    /// diagonal, raising the shift (`10⁻⁸, 10⁻⁶, …, 10⁻²`) while the factorisation fails.
    /// Returns the shift used.
    fn factor(&self, ws: &mut Workspace, shift: f64) -> Result<f64, FemError> {
        let _span = tracing::trace_span!("factor", shift).entered();
        let max_diag = ws
            .diagonal_at
            .iter()
            .map(|&d| ws.assembled[d].abs())
            .fold(0.0, f64::max)
            .max(f64::MIN_POSITIVE);
        let mut last = String::new();
        for fallback in [0.0, 1e-8, 1e-6, 1e-4, 1e-2] {
            let used = shift.max(fallback);
            match Self::try_factor(ws, used * max_diag) {
                Ok(()) => return Ok(used),
                Err(e) => {
                    tracing::debug!(used, "factorisation failed: {e}");
                    last = e;
                }
            }
        }
        Err(FemError::Factorisation { what: last })
    }

    /// Factors the assembled matrix plus `shift` on the diagonal.
    fn try_factor(ws: &mut Workspace, shift: f64) -> Result<(), String> {
        let values = ws.matrix.val_mut();
        values.copy_from_slice(&ws.assembled);
        if shift > 0.0 {
            for &d in &ws.diagonal_at {
                values[d] += shift;
            }
        }
        let stack = MemStack::new(&mut ws.stack);
        ws.cholesky
            .factorize_numeric_llt::<f64>(
                &mut ws.factor,
                ws.matrix.rb(),
                Side::Lower,
                LltRegularization::default(),
                Par::Seq,
                stack,
                Default::default(),
            )
            .map(|_| ())
            .map_err(|e| format!("{e:?}"))
    }

    /// The tangent without the projection to positive semidefinite (the exact Hessian, so
    /// Newton converges quadratically), assembled and factored; whether it is positive
    /// definite.
    fn exact_tangent(&self, ws: &mut Workspace, t: f64) -> bool {
        self.assemble_hessian(ws, t, false);
        self.eliminate_held(ws);
        let _span = tracing::trace_span!("factor_exact").entered();
        match Self::try_factor(ws, 0.0) {
            Ok(()) => true,
            Err(e) => {
                tracing::debug!("the exact tangent is not positive definite: {e}");
                false
            }
        }
    }

    /// Newton iterations at load fraction `t`; returns whether the tolerance was met.
    fn newton(
        &self,
        ws: &mut Workspace,
        t: f64,
        report: &mut StaticReport,
    ) -> Result<bool, FemError> {
        // Prescribed positions at this load fraction.
        for (i, fixed) in self.fixed.iter().enumerate() {
            let target = (self.targets[i] - self.rest[i]) * t;
            for a in 0..3 {
                if fixed[a] {
                    ws.u[i][a] = target[a];
                }
            }
        }
        self.project_onto_floor(&mut ws.u);
        let tol = self.settings.residual_tolerance;
        let mut exact_below = f64::INFINITY;
        for _ in 0..self.settings.max_iterations {
            let forces = self.gradient(&ws.u, t, &mut ws.grad);
            let mut held = 0usize;
            for (d, &(i, a)) in ws.dofs.iter().enumerate() {
                let i = i as usize;
                ws.held[d] = self.floor_bound.is_some_and(|b| b.axis == a as usize)
                    && self.floor_holds(i, ws.u[i], ws.grad[i]).is_some();
                held += usize::from(ws.held[d]);
            }
            forces.record(report);
            tracing::debug!(
                iteration = report.iterations,
                residual = forces.residual,
                relative = report.relative_residual,
                held,
                "newton"
            );
            if forces.residual <= tol * forces.scale || forces.residual == 0.0 {
                return Ok(true);
            }
            report.iterations += 1;
            // The projected tangent converges only linearly where it differs from the exact
            // one (compressed elements), and its eigen-decompositions are most of the
            // assembly's cost: the exact one is used where it is positive definite (once it
            // is not, not again until the residual has fallen tenfold).
            let exact = self.settings.project_hessian && forces.residual < exact_below && {
                let ok = self.exact_tangent(ws, t);
                if !ok {
                    exact_below = 0.1 * forces.residual;
                }
                ok
            };
            if !exact {
                self.assemble_hessian(ws, t, self.settings.project_hessian);
                self.eliminate_held(ws);
            }
            // A step the line search rejects (a nearly singular tangent: a body barely held) is
            // retried with a growing diagonal shift, towards gradient descent.
            let mut moved = false;
            for shift in [0.0, 1e-6, 1e-4, 1e-2, 1.0] {
                if !(exact && shift == 0.0) {
                    let used = self.factor(ws, shift)?;
                    if used > 0.0 {
                        report.shifted_factorisations += 1;
                    }
                }
                let slope = self.newton_direction(ws);
                if !(slope.is_finite() && slope < 0.0) {
                    tracing::debug!(slope, "not a descent direction");
                    continue;
                }
                if self.line_search(ws, t, slope, forces.residual) {
                    moved = true;
                    break;
                }
            }
            if !moved {
                return Ok(false);
            }
        }
        let forces = self.gradient(&ws.u, t, &mut ws.grad);
        forces.record(report);
        Ok(forces.residual <= tol * forces.scale)
    }

    /// Solves `K dx = −∇Π` on the free degrees of freedom with the current factor into `ws.dx`;
    /// returns the slope `∇Π·dx`.
    fn newton_direction(&self, ws: &mut Workspace) -> f64 {
        for (d, &(i, a)) in ws.dofs.iter().enumerate() {
            ws.rhs[(d, 0)] = if ws.held[d] {
                0.0
            } else {
                -ws.grad[i as usize][a as usize]
            };
        }
        {
            let _span = tracing::trace_span!("solve").entered();
            let stack = MemStack::new(&mut ws.stack);
            LltRef::new(&ws.cholesky, &ws.factor).solve_in_place_with_conj(
                Conj::No,
                ws.rhs.as_mut(),
                Par::Seq,
                stack,
            );
        }
        let mut slope = 0.0;
        ws.dx.iter_mut().for_each(|d| *d = DVec3::ZERO);
        for (d, &(i, a)) in ws.dofs.iter().enumerate() {
            let v = ws.rhs[(d, 0)];
            ws.dx[i as usize][a as usize] = v;
            slope += v * ws.grad[i as usize][a as usize];
        }
        slope
    }

    /// Backtracking line search along `dx` (halving). While the predicted decrease `−slope`
    /// is above round-off (`10⁻¹⁰` of the magnitude of the energy's terms), Armijo with
    /// `c = 10⁻⁴` on the total potential energy; near convergence, where energy differences
    /// drown in round-off, the residual norm must fall instead (`‖r(α)‖ ≤ (1 − 10⁻⁴ α)‖r‖`).
    fn line_search(&self, ws: &mut Workspace, t: f64, slope: f64, residual: f64) -> bool {
        let _span = tracing::trace_span!("line_search").entered();
        let e0 = self.energy(&ws.u, t);
        let energy_reliable = -slope > 1e-10 * e0.magnitude;
        let mut alpha = 1.0;
        if energy_reliable {
            for _ in 0..40 {
                for ((ut, u), d) in ws.trial.iter_mut().zip(&ws.u).zip(&ws.dx) {
                    *ut = *u + *d * alpha;
                }
                // A step through the floor ends on it (a projected search): the decrease
                // expected is the gradient along the projected step.
                self.project_onto_floor(&mut ws.trial);
                let expected = if self.floor_bound.is_some() {
                    ws.trial
                        .iter()
                        .zip(&ws.u)
                        .zip(&ws.grad)
                        .map(|((ut, u), g)| (*ut - *u).dot(*g))
                        .sum::<f64>()
                        .min(0.0)
                } else {
                    alpha * slope
                };
                let e1 = self.energy(&ws.trial, t);
                if e1.total.is_finite() && e1.total - e0.total <= 1e-4 * expected {
                    std::mem::swap(&mut ws.u, &mut ws.trial);
                    return true;
                }
                alpha *= 0.5;
            }
            alpha = 1.0;
        }
        for _ in 0..12 {
            for ((ut, u), d) in ws.trial.iter_mut().zip(&ws.u).zip(&ws.dx) {
                *ut = *u + *d * alpha;
            }
            self.project_onto_floor(&mut ws.trial);
            // Into its own buffer: a rejected search leaves the gradient at `u` for a retry.
            let forces = self.gradient(&ws.trial, t, &mut ws.trial_grad);
            if forces.residual <= (1.0 - 1e-4 * alpha) * residual {
                std::mem::swap(&mut ws.u, &mut ws.trial);
                return true;
            }
            alpha *= 0.5;
        }
        tracing::debug!(slope, energy = e0.total, "line search failed");
        false
    }
}

/// An axis-aligned floor as a bound on one coordinate: `sign (x[axis] − level) ≥ 0`.
#[derive(Debug, Clone, Copy, PartialEq)]
struct FloorBound {
    axis: usize,
    sign: f64,
    level: f64,
}

#[derive(Debug, Clone, Copy)]
enum Obstacle {
    /// Point, unit normal towards the body.
    Plane(DVec3, DVec3),
    /// Centre, radius.
    Sphere(DVec3, f64),
}

impl Obstacle {
    #[inline]
    fn gap(&self, x: DVec3) -> f64 {
        match *self {
            Obstacle::Plane(p, n) => (x - p).dot(n),
            Obstacle::Sphere(c, r) => (x - c).length() - r,
        }
    }

    /// The signed gap and the outward normal of the obstacle at the closest point.
    #[inline]
    fn gap_normal(&self, x: DVec3) -> (f64, DVec3) {
        match *self {
            Obstacle::Plane(p, n) => ((x - p).dot(n), n),
            Obstacle::Sphere(c, r) => {
                let d = x - c;
                let len = d.length();
                if len > 0.0 {
                    (len - r, d / len)
                } else {
                    (-r, DVec3::Z)
                }
            }
        }
    }
}

#[derive(Debug, Clone, Copy, Default)]
struct Forces {
    floor: DVec3,
    plate: DVec3,
    indenter: DVec3,
    residual: f64,
    scale: f64,
    max_penetration: f64,
}

impl Forces {
    /// The residual, its scale and their ratio into `report`.
    fn record(&self, report: &mut StaticReport) {
        report.residual = self.residual;
        report.force_scale = self.scale;
        report.relative_residual = if self.scale > 0.0 {
            self.residual / self.scale
        } else {
            0.0
        };
    }
}

#[derive(Debug, Clone, Copy)]
struct Energy {
    total: f64,
    /// Sum of the magnitudes of the terms, for the round-off allowance.
    magnitude: f64,
}

/// Everything the Newton loop needs, allocated once per solve.
struct Workspace {
    /// Displacements from the rest positions (the unknowns), cm.
    u: Vec<DVec3>,
    trial: Vec<DVec3>,
    dx: Vec<DVec3>,
    grad: Vec<DVec3>,
    trial_grad: Vec<DVec3>,
    /// Free degree of freedom → (node, axis).
    dofs: Vec<(u32, u8)>,
    /// Whether the floor holds a free degree of freedom in this Newton iteration.
    held: Vec<bool>,
    /// Per tetrahedron, 12×12 local entry → position in the matrix's values (NONE: not stored).
    scatter: Vec<u32>,
    /// Per surface node, its 3×3 block → position in the values.
    surface_block: Vec<[u32; 9]>,
    diagonal_at: Vec<usize>,
    /// The assembled tangent's values (the matrix's values before any shift).
    assembled: Vec<f64>,
    matrix: SparseColMat<usize, f64>,
    cholesky: SymbolicCholesky<usize>,
    factor: Vec<f64>,
    stack: MemBuffer,
    rhs: Mat<f64>,
}

impl Workspace {
    /// The sparsity pattern (lower triangle of the free degrees of freedom, node-major) and its
    /// symbolic factorisation.
    fn new(p: &StaticProblem) -> Result<Self, FemError> {
        let _span = tracing::debug_span!("symbolic").entered();
        let n_nodes = p.rest.len();
        let mut dof_of = vec![NONE; 3 * n_nodes];
        let mut dofs = Vec::with_capacity(3 * n_nodes);
        for i in 0..n_nodes {
            for a in 0..3 {
                if p.is_free(i, a) {
                    dof_of[3 * i + a] = dofs.len() as u32;
                    dofs.push((i as u32, a as u8));
                }
            }
        }
        let n = dofs.len();
        // Node adjacency (upper: j ≥ i).
        let mut pairs: Vec<(u32, u32)> = Vec::with_capacity(p.tets.len() * 10 + n_nodes);
        for tet in &p.tets {
            for a in 0..4 {
                for b in 0..4 {
                    if tet[a] <= tet[b] {
                        pairs.push((tet[a], tet[b]));
                    }
                }
            }
        }
        pairs.extend((0..n_nodes as u32).map(|i| (i, i)));
        pairs.sort_unstable();
        pairs.dedup();
        let mut col_ptr = Vec::with_capacity(n + 1);
        col_ptr.push(0usize);
        let mut row_idx: Vec<usize> = Vec::new();
        let mut start = 0;
        for i in 0..n_nodes {
            let mut end = start;
            while end < pairs.len() && pairs[end].0 as usize == i {
                end += 1;
            }
            let neighbours = &pairs[start..end];
            start = end;
            for a in 0..3 {
                let c = dof_of[3 * i + a];
                if c == NONE {
                    continue;
                }
                for &(_, j) in neighbours {
                    for b in 0..3 {
                        let r = dof_of[3 * j as usize + b];
                        if r != NONE && r >= c {
                            row_idx.push(r as usize);
                        }
                    }
                }
                col_ptr.push(row_idx.len());
            }
        }
        if row_idx.len() >= NONE as usize {
            return Err(problem(
                format!("{} stiffness entries", row_idx.len()),
                "use a smaller mesh",
            ));
        }
        let position = |r: u32, c: u32| -> u32 {
            let (lo, hi) = (col_ptr[c as usize], col_ptr[c as usize + 1]);
            match row_idx[lo..hi].binary_search(&(r as usize)) {
                Ok(k) => (lo + k) as u32,
                Err(_) => NONE,
            }
        };
        let mut scatter = vec![NONE; p.tets.len() * 144];
        for (e, tet) in p.tets.iter().enumerate() {
            for (la, &na) in tet.iter().enumerate() {
                for i in 0..3 {
                    let r = dof_of[3 * na as usize + i];
                    if r == NONE {
                        continue;
                    }
                    for (lb, &nb) in tet.iter().enumerate() {
                        for k in 0..3 {
                            let c = dof_of[3 * nb as usize + k];
                            if c == NONE || r < c {
                                continue;
                            }
                            scatter[e * 144 + (3 * la + i) * 12 + 3 * lb + k] = position(r, c);
                        }
                    }
                }
            }
        }
        let surface_block = p
            .surface
            .iter()
            .map(|&s| {
                let mut block = [NONE; 9];
                for a in 0..3 {
                    for b in 0..3 {
                        let (r, c) = (dof_of[3 * s as usize + a], dof_of[3 * s as usize + b]);
                        if r != NONE && c != NONE && r >= c {
                            block[a * 3 + b] = position(r, c);
                        }
                    }
                }
                block
            })
            .collect();
        let diagonal_at = col_ptr[..n].to_vec();
        let nnz = row_idx.len();
        let symbolic = SymbolicSparseColMat::new_checked(n, n, col_ptr, None, row_idx);
        let cholesky = factorize_symbolic_cholesky(
            symbolic.rb(),
            Side::Lower,
            SymmetricOrdering::Amd,
            Default::default(),
        )
        .map_err(|e| FemError::Factorisation {
            what: format!("symbolic factorisation failed: {e:?}"),
        })?;
        let scratch = cholesky
            .factorize_numeric_llt_scratch::<f64>(Par::Seq, Default::default())
            .or(cholesky.solve_in_place_scratch::<f64>(1, Par::Seq));
        tracing::debug!(dofs = n, nnz, factor = cholesky.len_val(), "pattern");
        Ok(Workspace {
            u: vec![DVec3::ZERO; n_nodes],
            trial: vec![DVec3::ZERO; n_nodes],
            dx: vec![DVec3::ZERO; n_nodes],
            grad: vec![DVec3::ZERO; n_nodes],
            trial_grad: vec![DVec3::ZERO; n_nodes],
            held: vec![false; n],
            dofs,
            scatter,
            surface_block,
            diagonal_at,
            assembled: vec![0.0; nnz],
            matrix: SparseColMat::new(symbolic, vec![0.0; nnz]),
            factor: vec![0.0; cholesky.len_val()],
            cholesky,
            stack: MemBuffer::new(scratch),
            rhs: Mat::zeros(n, 1),
        })
    }
}
