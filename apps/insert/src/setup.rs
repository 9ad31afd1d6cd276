//! From the command line to a job: load and scale the mesh, place the implant (snapped point,
//! surface normal, tangent), and fill in the library's parameters.

use glam::Vec3;
use tissue_app::{InsertionJob, Placement, SimMesh};
use tissue_collide::BroadPhase;
use tissue_implant::{
    default_snap_distance, snap_to_surface, ImplantShape, ImplantSpec, InsertionParams,
    RegionOptions, RegionRule, ScanOptions,
};
use tissue_mesh::TriMesh;

use crate::cli::{Cli, Detect, Rule, Shape, Unit, KPA};
use crate::failure::{code, Failure};

/// The Table 2 plane: 65 × 65 vertices, 20 cm square, centred at the origin in z = 0 (the same
/// mesh as `fixtures/plane_20cm_65.obj`).
pub const TABLE2_VERTICES_PER_SIDE: u32 = 65;
/// The Table 2 plane's side (cm).
pub const TABLE2_SIDE_CM: f32 = 20.0;

/// The patient and where the implant goes.
#[derive(Debug, Clone)]
pub struct Scenario {
    /// The patient surface, in cm.
    pub patient: TriMesh,
    /// The patient surface as the file has it (mesh unit).
    pub patient_file: TriMesh,
    /// The mesh file's unit.
    pub unit: Unit,
    /// The mesh as named in the report: the path given, or a description of the generated plane.
    pub mesh_label: String,
    /// Whether the mesh is the generated Table 2 plane.
    pub mesh_generated: bool,
    /// The picked point, cm.
    pub point: Vec3,
    /// The nearest surface point, cm.
    pub surface_point: Vec3,
    /// The surface's outward normal there.
    pub normal: Vec3,
    /// The implant's local x direction (unit, across the normal).
    pub tangent: Vec3,
    /// The job for tissue-app (its `implant.volume_cm3` is `--volume`).
    pub job: InsertionJob,
}

impl Scenario {
    /// Centimetres per mesh unit.
    pub fn cm_per_unit(&self) -> f32 {
        self.unit.cm_per_unit()
    }

    /// The region radius the job uses (cm).
    pub fn region_radius(&self) -> Result<f64, Failure> {
        self.job.radius().map_err(|e| Failure::from_implant(&e))
    }
}

/// Checks the numbers a user types, naming the flag: a size, volume or tissue value that cannot
/// be right is refused before anything runs.
pub fn check_numbers(cli: &Cli) -> Result<(), Failure> {
    let positive = |flag: &str, value: f64, unit: &str| {
        if value.is_finite() && value > 0.0 {
            Ok(())
        } else {
            Err(Failure::new(
                code::PARAMETERS,
                format!("{flag} must be a positive number of {unit}, got {value}"),
            ))
        }
    };
    positive("--volume", cli.volume, "cm³ (mL)")?;
    match cli.shape {
        Shape::Round => positive("--diameter", f64::from(cli.diameter), "cm")?,
        Shape::Rectangular | Shape::Crescent => {
            if let Some(l) = cli.length {
                positive("--length", f64::from(l), "cm")?;
            }
            if let Some(w) = cli.width {
                positive("--width", f64::from(w), "cm")?;
            }
            if let Some(b) = cli.bend_radius {
                positive("--bend-radius", f64::from(b), "cm")?;
            }
        }
    }
    if let Some(volumes) = &cli.sweep {
        for &v in volumes {
            positive("every --sweep volume", v, "cm³ (mL)")?;
        }
    }
    if let Some((low, high)) = cli.bracket {
        positive("--bracket LOW", low, "cm³")?;
        if !(high.is_finite() && high > low) {
            return Err(Failure::new(
                code::PARAMETERS,
                format!("--bracket HIGH must be larger than LOW ({low} cm³), got {high}"),
            ));
        }
    }
    positive("--gain-tolerance", cli.gain_tolerance, "cm²")?;
    if let Some(g) = cli.target_gain {
        if !g.is_finite() {
            return Err(Failure::new(
                code::PARAMETERS,
                "--target-gain must be a finite area in cm²",
            ));
        }
    }
    positive("--depth", cli.depth, "cm")?;
    positive("--young", cli.young, "kPa")?;
    positive("--thickness", cli.thickness, "cm")?;
    positive("--density", cli.density, "g/cm³")?;
    if !(cli.poisson.is_finite() && (0.0..0.5).contains(&cli.poisson)) {
        return Err(Failure::new(
            code::PARAMETERS,
            format!(
                "--poisson must be in [0, 0.5) (soft tissue: about 0.45), got {}",
                cli.poisson
            ),
        ));
    }
    if let Some(r) = cli.radius {
        if !(r.is_finite() && r > 0.0) {
            return Err(Failure::new(
                code::PLACEMENT,
                format!("--radius must be a positive region radius in cm, got {r}"),
            ));
        }
    }
    if let Some(h) = cli.sim_edge {
        positive("--sim-edge", h, "cm")?;
    }
    if !(cli.max_hole.is_finite() && cli.max_hole >= 0.0) {
        return Err(Failure::new(
            code::PARAMETERS,
            format!("--max-hole must be a size ≥ 0 in cm, got {}", cli.max_hole),
        ));
    }
    if let Some(h) = cli.time_step {
        positive("--time-step", f64::from(h), "seconds")?;
    }
    if cli.max_steps == 0 {
        return Err(Failure::new(
            code::PARAMETERS,
            "--max-steps must be at least 1",
        ));
    }
    Ok(())
}

/// The implant shape from the flags; a missing size is a usage error.
pub fn shape(cli: &Cli) -> Result<ImplantShape, Failure> {
    let need = |flag: &str, value: Option<f32>| {
        value.ok_or_else(|| {
            Failure::new(
                code::USAGE,
                format!(
                    "--shape {} needs {flag} (cm)",
                    match cli.shape {
                        Shape::Round => "round",
                        Shape::Rectangular => "rectangular",
                        Shape::Crescent => "crescent",
                    }
                ),
            )
        })
    };
    Ok(match cli.shape {
        Shape::Round => ImplantShape::Round {
            diameter: cli.diameter,
        },
        Shape::Rectangular => ImplantShape::Rectangular {
            length: need("--length", cli.length)?,
            width: need("--width", cli.width)?,
            corner_radius: cli.corner_radius,
        },
        Shape::Crescent => ImplantShape::Crescent {
            length: need("--length", cli.length)?,
            width: need("--width", cli.width)?,
            bend_radius: need("--bend-radius", cli.bend_radius)?,
        },
    })
}

/// The library parameters from the flags (the library's defaults for everything else).
pub fn params(cli: &Cli) -> InsertionParams {
    let mut params = InsertionParams::default();
    params.layers.young = cli.young * KPA;
    params.layers.poisson = cli.poisson;
    params.layers.skin_thickness = cli.thickness;
    params.layers.density = cli.density;
    params.layers.depth = cli.depth;
    params.run.broad_phase = match cli.detect {
        Detect::Bvh => BroadPhase::BvhBvh,
        Detect::Voxels => BroadPhase::BvhVoxels,
    };
    params.run.stop.max_steps = cli.max_steps;
    if cli.time_step.is_some() {
        params.run.time_step = cli.time_step;
    }
    params
}

/// The surface the mechanics run on: the region remeshed (a scan), or the mesh's own triangles
/// (`--scan-triangles`, and the generated Table 2 plane unless `--sim-edge` is given).
pub fn sim_mesh(cli: &Cli) -> SimMesh {
    if cli.scan_triangles || (cli.mesh.is_none() && cli.sim_edge.is_none()) {
        SimMesh::Patient
    } else {
        SimMesh::Remeshed(ScanOptions {
            sim_edge: cli.sim_edge,
            max_hole: cli.max_hole,
            ..ScanOptions::default()
        })
    }
}

/// The patient as read and scaled to cm.
#[derive(Debug, Clone)]
pub struct Patient {
    /// As the file has it (mesh unit).
    pub file: TriMesh,
    /// Scaled to cm.
    pub cm: TriMesh,
    /// The path, or a description of the generated plane.
    pub label: String,
    /// Whether it is the generated Table 2 plane.
    pub generated: bool,
}

/// Reads the patient mesh (or generates the Table 2 plane) and scales it to cm.
pub fn load_patient(cli: &Cli) -> Result<Patient, Failure> {
    let Some(path) = &cli.mesh else {
        let plane = tissue_mesh::grid(TABLE2_VERTICES_PER_SIDE, TABLE2_SIDE_CM)
            .map_err(|e| Failure::new(code::RUN, format!("cannot make the Table 2 plane: {e}")))?;
        let label = format!(
            "generated: Table 2 plane, {TABLE2_VERTICES_PER_SIDE} x {TABLE2_VERTICES_PER_SIDE} \
             vertices, {TABLE2_SIDE_CM} cm (= fixtures/plane_20cm_65.obj)"
        );
        return Ok(Patient {
            file: plane.clone(),
            cm: plane,
            label,
            generated: true,
        });
    };
    // A closed (watertight) body is taken as it is: the region is cut out of it.
    let mesh = tissue_meshio::read_surface(path).map_err(|e| Failure::from_mesh_io(&e))?;
    let scale = cli.unit().cm_per_unit();
    let cm = if scale == 1.0 {
        mesh.clone()
    } else {
        let scaled = mesh.positions().iter().map(|&p| p * scale).collect();
        mesh.with_positions(scaled).map_err(|e| {
            Failure::new(
                code::MESH,
                format!(
                    "{}: not valid once scaled to cm: {e}; check --unit",
                    path.display()
                ),
            )
        })?
    };
    Ok(Patient {
        file: mesh,
        cm,
        label: path.display().to_string(),
        generated: false,
    })
}

/// The picked point (cm): `--vertex`, `--at`, or the origin of the generated plane.
fn picked_point(cli: &Cli, patient: &TriMesh) -> Result<Vec3, Failure> {
    if let Some(v) = cli.vertex {
        return patient.positions().get(v as usize).copied().ok_or_else(|| {
            Failure::new(
                code::PLACEMENT,
                format!(
                    "--vertex {v} is out of range: the mesh has {} vertices (0 to {})",
                    patient.vertex_count(),
                    patient.vertex_count().saturating_sub(1)
                ),
            )
        });
    }
    match (cli.at, &cli.mesh) {
        (Some(at), _) => Ok(Vec3::from_array(at) * cli.unit().cm_per_unit()),
        (None, None) => Ok(Vec3::ZERO),
        (None, Some(_)) => Err(Failure::new(
            code::USAGE,
            "--mesh needs --at X,Y,Z (in the mesh's unit) or --vertex N: where the implant goes",
        )),
    }
}

/// The outward normal at a surface point: the area-weighted vertex normals of its triangle,
/// interpolated with its barycentric coordinates (the triangle's own normal where they cancel).
fn surface_normal(patient: &TriMesh, triangle: u32, barycentric: [f32; 3]) -> Vec3 {
    let normals = patient.vertex_normals();
    let tri = patient.triangles()[triangle as usize];
    let n = tri
        .iter()
        .zip(barycentric)
        .map(|(&v, w)| normals[v as usize] * w)
        .fold(Vec3::ZERO, |a, b| a + b)
        .normalize_or_zero();
    if n != Vec3::ZERO {
        return n;
    }
    patient.triangle_normals()[triangle as usize]
}

/// The tangent: `wanted` (or +x, or +y near ±x) with its part along `normal` removed.
fn tangent(normal: Vec3, wanted: Option<[f32; 3]>) -> Result<Vec3, Failure> {
    let axis = match wanted {
        Some(t) => Vec3::from_array(t),
        // cos 25° ≈ 0.906
        None if normal.x.abs() > 0.906 => Vec3::Y,
        None => Vec3::X,
    };
    let t = (axis - normal * axis.dot(normal)).normalize_or_zero();
    if t == Vec3::ZERO {
        return Err(Failure::new(
            code::PLACEMENT,
            format!(
                "--tangent {axis} is along the surface normal {normal} at the point: give a \
                 direction across the skin"
            ),
        ));
    }
    Ok(t)
}

/// Everything from the command line: the patient in cm, the placement, the job.
pub fn scenario(cli: &Cli) -> Result<Scenario, Failure> {
    check_numbers(cli)?;
    let shape = shape(cli)?;
    let Patient {
        file: patient_file,
        cm: patient,
        label: mesh_label,
        generated: mesh_generated,
    } = load_patient(cli)?;
    let point = picked_point(cli, &patient)?;
    let snapped = snap_to_surface(&patient, point, default_snap_distance(&patient))
        .map_err(|e| Failure::from_implant(&e))?;
    let normal = surface_normal(&patient, snapped.triangle(), snapped.barycentric());
    let tangent = tangent(normal, cli.tangent)?;
    let spec = ImplantSpec::new(shape, cli.volume).with_vertex_budget(cli.implant_vertices);
    let job = InsertionJob {
        patient: patient.clone(),
        placement: Placement::new(point, normal, tangent),
        implant: spec,
        region_radius: cli.radius,
        region: RegionOptions {
            rule: match cli.region_rule {
                Rule::TouchesVertex => RegionRule::TouchesVertex,
                Rule::Centroid => RegionRule::Centroid,
            },
            ..RegionOptions::default()
        },
        params: params(cli),
        sim: sim_mesh(cli),
    };
    Ok(Scenario {
        patient,
        patient_file,
        unit: cli.unit(),
        mesh_label,
        mesh_generated,
        point,
        surface_point: snapped.position(),
        normal,
        tangent,
        job,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tangent_is_x_across_a_z_normal_and_y_near_x() {
        assert_eq!(tangent(Vec3::Z, None), Ok(Vec3::X));
        assert_eq!(tangent(Vec3::X, None), Ok(Vec3::Y));
        assert!(tangent(Vec3::Z, Some([0.0, 0.0, 2.0])).is_err());
    }

    #[test]
    fn the_plane_normal_is_z() {
        let plane = tissue_mesh::grid(9, 4.0).map_err(|e| e.to_string());
        let plane = plane.unwrap_or_else(|e| panic!("{e}"));
        let p = snap_to_surface(&plane, Vec3::new(0.3, -0.2, 0.1), 1.0)
            .unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(
            surface_normal(&plane, p.triangle(), p.barycentric()),
            Vec3::Z
        );
    }
}
