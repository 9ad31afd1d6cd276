//! The scene: the organ loaded, scaled and set on the tray (tissue-scenes' `Organ`), the body,
//! and the probe's press-and-drag script (tissue-scenes' `PressAndDrag`).

use std::path::PathBuf;

use glam::Vec3;
use tissue_mesh::{tet_box, TetMesh};
use tissue_pbd::{ContactParams, Pose, SoftBody, ToolShape};
use tissue_scenes::{Organ, PressAndDrag, PressPlan, ShippedOrgan, Tray};

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
    /// The probe's shape (tip at the local origin, axis +y).
    pub probe: ToolShape,
    /// The press-and-drag script (tissue-scenes), its probe a tool of the body.
    pub script: PressAndDrag,
}

/// Loads the organ, scales and places it, builds the body, the tray and the probe (parked above).
pub fn build(cli: &Cli) -> Result<Scene, Failure> {
    let scene = |e| Failure::from_scene(&e);
    let (source, organ) = match (&cli.surface, &cli.organ, cli.box_cells) {
        (Some(p), _, _) => {
            let surface = tissue_meshio::read_surface(p).map_err(|e| Failure::from_mesh_io(&e))?;
            let organ = Organ::from_surface(&surface, &p.display().to_string()).map_err(scene)?;
            let report = organ.quality.clone().ok_or_else(|| {
                Failure::new(Exit::Meshing, format!("{}: no mesher report", p.display()))
            })?;
            (Source::Surface(p.clone(), Box::new(report)), organ)
        }
        (None, Some(p), _) => {
            let tets = tissue_meshio::read_tets(p).map_err(|e| Failure::from_mesh_io(&e))?;
            let organ = Organ::from_tets(&tets, &p.display().to_string()).map_err(scene)?;
            (Source::File(p.clone()), organ)
        }
        (None, None, Some(n)) => {
            let tets = tet_box(n, n, n, Vec3::ONE)
                .map_err(|e| Failure::new(Exit::Parameters, format!("--box: {e}")))?;
            (
                Source::Box(n),
                Organ::from_tets(&tets, "--box").map_err(scene)?,
            )
        }
        (None, None, None) => {
            let bunny = ShippedOrgan::Bunny;
            let organ = Organ::shipped(bunny)
                .map_err(|e| Failure::new(Exit::Meshing, format!("the shipped bunny: {e}")))?;
            (Source::Shipped(bunny), organ)
        }
    };
    if !(cli.depth.is_finite() && cli.depth >= 0.0) {
        return Err(Failure::new(
            Exit::Parameters,
            format!("--depth {} must be ≥ 0 cm", cli.depth),
        ));
    }
    let organ = organ.scaled_to(cli.size).map_err(|e| match e {
        tissue_scenes::SceneError::Mesh { .. } => {
            Failure::new(Exit::Mesh, format!("{e}; use a larger --size"))
        }
        e => Failure::from_scene(&e),
    })?;
    let (material, settings) = cli.physics();
    let contact = ContactParams {
        static_friction: cli.friction,
        kinetic_friction: cli.friction,
        ..ContactParams::default()
    };
    let tray = Tray {
        side: 3.0 * cli.size,
        cell: cli.cell,
    };
    let mut body = organ
        .body(&material, settings, contact, tray)
        .map_err(scene)?;
    let probe = ToolShape::Capsule {
        a: Vec3::ZERO,
        b: Vec3::new(0.0, cli.size, 0.0),
        radius: cli.tool_radius,
    };
    let parked = Pose::from_translation(Vec3::new(0.0, 3.0 * cli.size, 0.0));
    let tool = body
        .add_tool(probe, parked, contact)
        .map_err(|e| Failure::from_pbd(&e))?;
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
    let plan = PressPlan {
        settle: cli.settle_steps as usize,
        press: cli.press_steps as usize,
        drag: cli.drag_steps as usize,
        depth: cli.depth,
        waypoints,
        // 1 cm, or the mean tet edge length when that is longer.
        reach: (mean_edge as f32).max(1.0),
    };
    let script = PressAndDrag::new(tool, cli.tool_radius, plan).map_err(scene)?;
    Ok(Scene {
        source,
        mesh: organ.mesh,
        body,
        probe,
        script,
    })
}
