//! The scene: the organ loaded, scaled and set on the tray (tissue-scenes' `Organ`), the body,
//! and the probe's press-and-drag run (tissue-scenes' `PressAndDrag::on_tray`, the set-up the
//! studio's demonstration uses too).

use std::path::PathBuf;

use glam::Vec3;
use tissue_mesh::tet_box;
use tissue_pbd::{ContactParams, SoftBody, ToolShape};
use tissue_scenes::{Organ, PressAndDrag, PressPlan, ShippedOrgan, Tray};

use crate::cli::Cli;
use crate::failure::{self, Exit, Failure};

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
    pub organ: Organ,
    /// The body with the tray and the probe.
    pub body: SoftBody,
    /// The probe's shape (tip at the local origin, axis +y).
    pub probe: ToolShape,
    /// The press-and-drag script (tissue-scenes), its probe a tool of the body.
    pub script: PressAndDrag,
}

/// Loads the organ, scales and places it, builds the body, the tray and the probe (parked above).
pub fn build(cli: &Cli) -> Result<Scene, Failure> {
    let scene = |e| failure::from_scene(&e);
    let (source, organ) = match (&cli.surface, &cli.organ, cli.box_cells) {
        (Some(p), _, _) => {
            let surface = tissue_meshio::read_surface(p).map_err(|e| failure::from_mesh_io(&e))?;
            let organ = Organ::from_surface(&surface, &p.display().to_string()).map_err(scene)?;
            let report = organ.quality.clone().ok_or_else(|| {
                Failure::new(Exit::Meshing, format!("{}: no mesher report", p.display()))
            })?;
            (Source::Surface(p.clone(), Box::new(report)), organ)
        }
        (None, Some(p), _) => {
            let tets = tissue_meshio::read_tets(p).map_err(|e| failure::from_mesh_io(&e))?;
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
        e => failure::from_scene(&e),
    })?;
    let (material, settings) = cli.physics()?;
    let contact = ContactParams {
        static_friction: cli.friction,
        kinetic_friction: cli.friction,
        ..ContactParams::default()
    };
    // The tray of tissue-scenes' rule (three times the organ), its collider's cell as given.
    let tray = Tray {
        cell: cli.cell,
        ..Tray::for_extent(cli.size)
    };
    let mut body = organ
        .body(&material, settings, contact, tray)
        .map_err(scene)?;
    body.set_self_collision(cli.self_collision())
        .map_err(|e| failure::from_pbd(&e))?;
    if cli.waypoints.len() == 1 {
        return Err(Failure::new(
            Exit::Parameters,
            "one --waypoint is not a path: give two or more",
        ));
    }
    let plan = PressPlan {
        settle: cli.settle_steps,
        press: cli.press_steps,
        drag: cli.drag_steps,
        depth: cli.depth,
        radius: cli.tool_radius,
        waypoints: cli.waypoints.clone(),
        ..PressPlan::default()
    };
    let script = PressAndDrag::on_tray(&mut body, cli.size, plan, contact).map_err(scene)?;
    let probe = body
        .tool(script.tool())
        .map_err(|e| failure::from_pbd(&e))?
        .shape()
        .to_owned();
    Ok(Scene {
        source,
        organ,
        body,
        probe,
        script,
    })
}

#[cfg(test)]
mod tests {
    use clap::Parser;

    use super::*;

    /// With its defaults the headless run is the studio's demonstration on a tray: the same
    /// timeline, probe and path (tissue-scenes' PressPlan::default() through
    /// PressAndDrag::on_tray).
    #[test]
    fn the_default_run_is_the_demonstrations_timeline() {
        let cli = Cli::try_parse_from(["trainer", "--box", "3"]).unwrap_or_else(|e| panic!("{e}"));
        let scene = build(&cli).unwrap_or_else(|e| panic!("{}", e.line()));
        let plan = scene.script.plan();
        let default = PressPlan::default();
        assert_eq!(
            (plan.settle, plan.press, plan.drag, plan.depth, plan.radius),
            (
                default.settle,
                default.press,
                default.drag,
                default.depth,
                default.radius
            )
        );
        assert_eq!(
            plan.waypoints,
            default.path_over(cli.size, scene.body.positions(), plan.reach)
        );
        // A box is as wide one way as the other: crossed along x through its centre.
        let quarter = 0.25 * cli.size;
        for (w, x) in plan.waypoints.iter().zip([-quarter, quarter]) {
            assert!((w[0] - x).abs() < 1e-4 && w[1].abs() < 1e-4, "{w:?}");
        }
        assert_eq!(
            scene.body.tool(scene.script.tool()).map(|t| t.pose()).ok(),
            Some(PressAndDrag::parked(cli.size))
        );
    }
}
