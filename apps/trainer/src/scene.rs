//! The scene: the organ loaded, scaled and set on the tray, the body, and the probe's path.

use std::path::PathBuf;

use glam::Vec3;
use tissue_mesh::{tet_box, TetMesh};
use tissue_pbd::{ContactParams, OrientedBox, Pose, SoftBody, ToolShape, VoxelCollider};

use crate::cli::Cli;
use crate::failure::{Exit, Failure};

/// Where the organ came from.
#[derive(Debug, Clone)]
pub enum Source {
    /// An organ shipped with `tissue-scenes` (the default: the bunny).
    Shipped(tissue_scenes::ShippedOrgan),
    /// A file.
    File(PathBuf),
    /// A generated box of N³ cells.
    Box(u32),
    /// A closed surface, tetrahedralised by `tissue-tetra` (with its quality report).
    Surface(PathBuf, Box<tissue_tetra::QualityReport>),
}

impl std::fmt::Display for Source {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Source::Shipped(o) => write!(f, "shipped: {}", o.label()),
            Source::File(p) => write!(f, "{}", p.display()),
            Source::Box(n) => write!(f, "generated tet box of {n}×{n}×{n} cells"),
            Source::Surface(p, report) => write!(
                f,
                "{} tetrahedralised: {} tets, {} nodes ({} interior), dihedral {:.1}°–{:.1}°, \
                 volume {:.4} of the surface's",
                p.display(),
                report.tets,
                report.nodes,
                report.interior_nodes,
                report.min_dihedral_deg,
                report.max_dihedral_deg,
                report.volume_ratio
            ),
        }
    }
}

/// Everything set up, before the run.
pub struct Scene {
    /// Where the organ came from.
    pub source: Source,
    /// The organ as placed (cm), resting on the tray's plane y = 0.
    pub mesh: TetMesh,
    /// The body with the tray and the probe.
    pub body: SoftBody,
    /// The probe's id in the body.
    pub tool: usize,
    /// The probe's shape (tip at the local origin, axis +y).
    pub probe: ToolShape,
    /// The drag path (x, z), at least two points.
    pub waypoints: Vec<[f32; 2]>,
    /// Horizontal radius within which [`top_at`] looks for nodes (cm): 1 cm, or the mean tet
    /// edge length when that is longer.
    pub reach: f32,
}

/// Loads the organ, scales and places it, builds the body, the tray and the probe (parked above).
pub fn build(cli: &Cli) -> Result<Scene, Failure> {
    let (source, raw) = match (&cli.surface, &cli.organ, cli.box_cells) {
        (Some(p), _, _) => {
            let surface = tissue_meshio::read_surface(p).map_err(|e| Failure::from_mesh_io(&e))?;
            let tets =
                tissue_tetra::tetrahedralize(&surface, &tissue_tetra::TetraOptions::default())
                    .map_err(|e| {
                        Failure::new(
                            Exit::Meshing,
                            format!("{} cannot be tetrahedralised: {e}", p.display()),
                        )
                    })?;
            (Source::Surface(p.clone(), Box::new(tets.report)), tets.mesh)
        }
        (None, Some(p), _) => (
            Source::File(p.clone()),
            tissue_meshio::read_tets(p).map_err(|e| Failure::from_mesh_io(&e))?,
        ),
        (None, None, Some(n)) => (
            Source::Box(n),
            tet_box(n, n, n, Vec3::ONE)
                .map_err(|e| Failure::new(Exit::Parameters, format!("--box: {e}")))?,
        ),
        (None, None, None) => {
            let bunny = tissue_scenes::ShippedOrgan::Bunny;
            let organ = tissue_scenes::Organ::shipped(bunny)
                .map_err(|e| Failure::new(Exit::Meshing, format!("the shipped bunny: {e}")))?;
            (Source::Shipped(bunny), organ.mesh)
        }
    };
    if !(cli.size.is_finite() && cli.size > 0.0) {
        return Err(Failure::new(
            Exit::Parameters,
            format!("--size {} must be a positive length in cm", cli.size),
        ));
    }
    if !(cli.depth.is_finite() && cli.depth >= 0.0) {
        return Err(Failure::new(
            Exit::Parameters,
            format!("--depth {} must be ≥ 0 cm", cli.depth),
        ));
    }
    let mesh = place(&raw, cli.size)?;
    let (material, settings) = cli.physics();
    let pbd = |e| Failure::from_pbd(&e);
    let mut body = SoftBody::new(&mesh, &material).map_err(pbd)?;
    body.set_settings(settings).map_err(pbd)?;
    let contact = ContactParams {
        static_friction: cli.friction,
        kinetic_friction: cli.friction,
        ..ContactParams::default()
    };
    let side = 3.0 * cli.size;
    let tray = VoxelCollider::new(
        &[tissue_pbd::ColliderShape::Box(OrientedBox::tray(
            0.0, 0.0, 0.0, side, side, 2.0,
        ))],
        cli.cell,
        cli.cell.max(contact.margin + contact.detection),
    )
    .map_err(pbd)?;
    body.add_collider(tray, contact).map_err(pbd)?;
    let probe = ToolShape::Capsule {
        a: Vec3::ZERO,
        b: Vec3::new(0.0, cli.size, 0.0),
        radius: cli.tool_radius,
    };
    let parked = Pose::from_translation(Vec3::new(0.0, 3.0 * cli.size, 0.0));
    let tool = body.add_tool(probe, parked, contact).map_err(pbd)?;
    let waypoints = match cli.waypoints.len() {
        0 => vec![[-0.25 * cli.size, 0.0], [0.25 * cli.size, 0.0]],
        1 => {
            return Err(Failure::new(
                Exit::Parameters,
                "one --waypoint is not a path: give two or more",
            ))
        }
        _ => cli.waypoints.clone(),
    };
    let edges = body.distance_constraints();
    let mean_edge =
        edges.iter().map(|c| c.rest_length as f64).sum::<f64>() / edges.len().max(1) as f64;
    Ok(Scene {
        reach: (mean_edge as f32).max(1.0),
        source,
        mesh,
        body,
        tool,
        probe,
        waypoints,
    })
}

/// Scales the mesh so its largest extent is `size`, centres it on x = z = 0 and sets its lowest
/// node on y = 0.
fn place(raw: &TetMesh, size: f32) -> Result<TetMesh, Failure> {
    let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
    for &p in raw.positions() {
        lo = lo.min(p);
        hi = hi.max(p);
    }
    let scale = size / (hi - lo).max_element();
    let centre = Vec3::new((lo.x + hi.x) * 0.5, lo.y, (lo.z + hi.z) * 0.5);
    let positions = raw
        .positions()
        .iter()
        .map(|&p| (p - centre) * scale)
        .collect();
    TetMesh::new(positions, raw.tets().to_vec()).map_err(|e| {
        Failure::new(
            Exit::Mesh,
            format!("the organ scaled to --size {size} cm is not valid: {e}; use a larger --size"),
        )
    })
}

/// Height of the organ's top under the point (x, z): the highest node within `reach`
/// horizontally.
pub fn top_at(body: &SoftBody, xz: [f32; 2], reach: f32) -> Option<f32> {
    body.positions()
        .iter()
        .filter(|p| (p.x - xz[0]).hypot(p.z - xz[1]) <= reach)
        .map(|p| p.y)
        .reduce(f32::max)
}
