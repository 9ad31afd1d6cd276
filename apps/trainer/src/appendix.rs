//! `--scenario appendix`: an appendix-like organ (8 × 2 × 2 cm, 32 × 8 × 8 cells) pinned at its
//! base, lying on the abdominal wall, is deformed (its tip lifted by a grasper, then let go), is incised near the base (a partial cut over 20 steps), has its tip
//! cut off (a full cut over 30 steps: the piece falls away), and the incision is sutured (a
//! needle across the wound, three stitches). Prints every surgery event and the step times
//! (median, p99; the steps with a cut with the cut's own time included), writes OBJ frames of
//! the boundary surface with `--frames DIR` every `--every` steps.

use std::time::Instant;

use glam::{Quat, Vec3};
use tissue_mesh::{tet_box, TriMesh};
use tissue_pbd::{Floor, Pose, SoftBody, StepSettings, ToolShape};
use tissue_surgery::{BladeSweep, Surgery, SurgeryEvent, SurgerySettings};

use crate::cli::{Cli, Scheme};
use crate::failure::{Exit, Failure};
use crate::ms;
use crate::run::percentiles;

fn surgery_failure(e: &tissue_surgery::SurgeryError) -> Failure {
    Failure::new(Exit::Run, format!("surgery: {e}"))
}

/// Runs the scenario and prints its summary.
pub fn run(cli: &Cli) -> Result<(), Failure> {
    let mesh = tet_box(32, 8, 8, Vec3::new(8.0, 2.0, 2.0))
        .map_err(|e| Failure::new(Exit::Mesh, format!("appendix mesh: {e}")))?;
    let (material, mut settings) = cli.physics();
    if cli.scheme == Scheme::Legacy {
        // The scenario's own damping before issue 19 (the library's default step).
        settings.damping = StepSettings::default().damping;
    }
    let mut body = SoftBody::new(&mesh, &material).map_err(|e| Failure::from_pbd(&e))?;
    body.set_settings(settings)
        .map_err(|e| Failure::from_pbd(&e))?;
    // It lies on the abdominal wall (a floor at its underside).
    body.set_floor(Some(Floor::y(-1.0)))
        .map_err(|e| Failure::from_pbd(&e))?;
    // The base (x < −3.7 cm) is fixed to the cecum.
    for i in 0..body.node_count() as u32 {
        if body.positions()[i as usize].x < -3.7 {
            body.pin(i).map_err(|e| Failure::from_pbd(&e))?;
        }
    }
    let mut surgery =
        Surgery::new(&body, SurgerySettings::default()).map_err(|e| surgery_failure(&e))?;
    println!(
        "trainer: appendix scenario, {} nodes, {} tets, {:.1} g",
        body.node_count(),
        body.tets().len(),
        body.total_mass()
    );
    let scalpel = ToolShape::Blade {
        a: Vec3::new(0.0, 0.0, -0.4),
        b: Vec3::new(0.0, 0.0, 0.4),
        c: Vec3::new(0.0, 3.0, 0.0),
        thickness: 0.02,
    };
    let wide = ToolShape::Blade {
        a: Vec3::new(0.0, 0.0, -2.0),
        b: Vec3::new(0.0, 0.0, 2.0),
        c: Vec3::new(0.0, 4.0, 0.0),
        thickness: 0.02,
    };
    // Deformation: the tip is lifted 1.5 cm by a grasper during the settling, then let go.
    let tip: Vec<u32> = (0..body.node_count() as u32)
        .filter(|&i| {
            let p = body.positions()[i as usize];
            p.x > 3.7 && p.y > 0.9
        })
        .collect();
    let mut grasp = Vec::new();
    for &i in &tip {
        let p = Vec3::from(body.positions()[i as usize]);
        grasp.push((i, p, body.attach(i, p).map_err(|e| Failure::from_pbd(&e))?));
    }
    // Phases (steps): settle 60, incise 20, cut off 30, suture at 140, run to 200.
    let (settle, incise, cutoff, suture_at, total) =
        (60usize, 20usize, 30usize, 140usize, 200usize);
    // The grasper lets go as the cut-off starts: the tip falls while it is cut.
    let release = settle + incise + 1;
    let mut plain = Vec::new();
    let mut with_cut = Vec::new();
    let mut frames = 0usize;
    let mut events_seen = 0usize;
    let mut last_pose: Option<Pose> = None;
    let mut worst_drift = 0.0f64;
    for step in 1..=total {
        // The blade's pose for this step, relative to the sagging organ: found on the nodes.
        if step <= settle {
            let lift = 1.5 * (step as f32 / (settle as f32 * 0.5)).min(1.0);
            for &(_, p, id) in &grasp {
                body.set_attachment_target(id, p + Vec3::new(0.0, lift, 0.0))
                    .map_err(|e| Failure::from_pbd(&e))?;
            }
        } else if step == release {
            for &(i, _, _) in &grasp {
                body.unpin(i).map_err(|e| Failure::from_pbd(&e))?;
            }
        }
        let blade = if step > settle + incise {
            &wide
        } else {
            &scalpel
        };
        let pose = if step > settle && step <= settle + incise {
            // Incision near the base at x = −2.45, 0.8 cm deep, drawn across z over 20 steps.
            let k = (step - settle) as f32 / incise as f32;
            let top = top_near(&body, -2.45);
            Some(Pose::new(
                Quat::IDENTITY,
                Vec3::new(-2.45, top - 0.8, -1.4 + 2.8 * k),
            ))
        } else if step > settle + incise && step <= settle + incise + cutoff {
            // Cut-off at x = 2.05: the blade is drawn down through the whole organ, from above
            // the lifted tip (y 3) to below the abdominal wall (y −2).
            let k = (step - settle - incise) as f32 / cutoff as f32;
            Some(Pose::new(
                Quat::IDENTITY,
                Vec3::new(2.05, 3.0 - 5.0 * k, 0.0),
            ))
        } else {
            None
        };
        if step == settle + incise + 1 {
            // A new blade: its first pose starts a new sweep (not one from where the scalpel
            // ended, 4.5 cm away).
            last_pose = None;
        }
        let t = Instant::now();
        body.step().map_err(|e| Failure::from_pbd(&e))?;
        let drift = body.volume() / body.rest_volume() - 1.0;
        worst_drift = worst_drift.max(drift.abs());
        let mut events = Vec::new();
        if let (Some(to), Some(from)) = (pose, last_pose) {
            let sweep = BladeSweep::new(blade, &from, &to).map_err(|e| surgery_failure(&e))?;
            events = surgery
                .cut(&mut body, &sweep)
                .map_err(|e| surgery_failure(&e))?;
        }
        if step == suture_at {
            // Three stitches across the incision, needles along x at mid-depth.
            for z in [-0.6f32, 0.0, 0.6] {
                let top = top_near(&body, -2.45);
                let needle = ToolShape::Capsule {
                    a: Vec3::new(-0.6, 0.0, 0.0),
                    b: Vec3::new(0.6, 0.0, 0.0),
                    radius: 0.02,
                };
                // As the studio's needle: 0.35 cm under the top, then shallower and deeper
                // until it crosses the wound.
                for depth in [0.35f32, 0.21, 0.56, 0.84] {
                    let at = Pose::from_translation(Vec3::new(-2.45, top - depth, z + 0.05));
                    if let Some(e) = surgery
                        .suture(&mut body, &needle, &at)
                        .map_err(|e| surgery_failure(&e))?
                    {
                        events.push(e);
                        break;
                    }
                }
            }
        }
        let elapsed = t.elapsed().as_secs_f64();
        if pose.is_some() && last_pose.is_some() {
            with_cut.push(elapsed);
        } else {
            plain.push(elapsed);
        }
        last_pose = pose;
        for e in &events {
            events_seen += 1;
            println!("  step {step:3}  {}", describe(e));
        }
        if let Some(dir) = &cli.frames {
            if step % cli.every as usize == 0 || step == total {
                write_frame(dir, step, &body, &surgery)?;
                frames += 1;
            }
        }
    }
    let (m, p, x) = percentiles(&plain);
    println!(
        "  steps         {} without a cut: median {}, p99 {}, max {}",
        plain.len(),
        ms(m),
        ms(p),
        ms(x)
    );
    let (m, p, x) = percentiles(&with_cut);
    println!(
        "  with a cut    {} steps (step + cut): median {}, p99 {}, max {}",
        with_cut.len(),
        ms(m),
        ms(p),
        ms(x)
    );
    println!(
        "  run           {total} steps, {}",
        crate::describe_settings(body.settings(), body.volume_kind())
    );
    println!(
        "  volume drift  {:+.3} % at the end (V/V0 = {:.4}, V0 as built), largest |drift| {:.3} %",
        (body.volume() / body.rest_volume() - 1.0) * 100.0,
        body.volume() / body.rest_volume(),
        worst_drift * 100.0
    );
    println!(
        "  surgery       {events_seen} events, {} pieces, {} nodes now ({} added), {} sutures",
        surgery.component_count(),
        body.node_count(),
        body.node_count() - mesh.vertex_count(),
        surgery.sutures().iter().flatten().count()
    );
    surgery
        .validate(&body)
        .map_err(|e| Failure::new(Exit::Run, format!("surface after the run: {e}")))?;
    if let Some(dir) = &cli.frames {
        println!("  frames        {frames} written to {}", dir.display());
    }
    Ok(())
}

/// The highest node y within 0.3 cm of `x` (the organ's top there).
fn top_near(body: &SoftBody, x: f32) -> f32 {
    body.positions()
        .iter()
        .filter(|p| (p.x - x).abs() < 0.3 && p.z.abs() < 0.3)
        .map(|p| p.y)
        .fold(f32::NEG_INFINITY, f32::max)
        .max(-10.0)
}

fn describe(e: &SurgeryEvent) -> String {
    match e {
        SurgeryEvent::CutAdvanced {
            new_nodes,
            changed_tets,
            opened_faces,
            ..
        } => format!(
            "cut advanced: {} wall triangles, {} new nodes ({}..{}), {} tets moved",
            opened_faces.len(),
            new_nodes.len(),
            new_nodes.start,
            new_nodes.end,
            changed_tets.len()
        ),
        SurgeryEvent::PieceDetached {
            component,
            tets,
            nodes,
            rest_volume,
        } => format!(
            "piece detached: component {component}, {} tets, {} nodes, {rest_volume:.2} cm³",
            tets.len(),
            nodes.len()
        ),
        SurgeryEvent::SuturePlaced {
            suture,
            nodes,
            constraint,
        } => format!(
            "suture {suture} placed: nodes {} and {}, constraint {constraint}",
            nodes[0], nodes[1]
        ),
        SurgeryEvent::SutureRemoved { suture, nodes } => {
            format!(
                "suture {suture} removed: nodes {} and {}",
                nodes[0], nodes[1]
            )
        }
        other => format!("{other:?}"),
    }
}

fn write_frame(
    dir: &std::path::Path,
    step: usize,
    body: &SoftBody,
    surgery: &Surgery,
) -> Result<(), Failure> {
    std::fs::create_dir_all(dir).map_err(|e| Failure::output(&dir.display().to_string(), e))?;
    let positions: Vec<Vec3> = body.positions().iter().map(|p| Vec3::from(*p)).collect();
    let surface = TriMesh::new(positions, surgery.boundary_faces(body))
        .map_err(|e| Failure::new(Exit::Run, format!("frame {step}: boundary surface: {e}")))?;
    let path = dir.join(format!("appendix_{step:04}.obj"));
    tissue_meshio::write_surface(&path, &surface)
        .map_err(|e| Failure::output(&path.display().to_string(), e))
}
