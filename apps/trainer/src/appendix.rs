//! `--scenario appendix`: tissue-scenes' appendix procedure (`AppendixProcedure`, the same
//! script the studio's demonstration plays) on the shipped appendix (8 × 2 × 2 cm, 32 × 8 × 8
//! cells, base pinned, on the abdominal wall) with this run's physics: the tip lifted by a
//! grasper and let go, an incision near the base, the tip cut off, the incision sutured with
//! three stitches. Prints every surgery event (as tissue-scenes' `TrainerEvent::surgery` words
//! it, the studio's events list too) and the step times (median, p99; the steps with a
//! cut with the cut's own time included), writes OBJ frames of the boundary surface with
//! `--frames DIR` every `--every` steps.

use std::time::Instant;

use glam::Vec3;
use tissue_mesh::TriMesh;
use tissue_pbd::{ContactParams, SoftBody, StepSettings};
use tissue_scenes::{
    AppendixPlan, AppendixProcedure, Organ, SceneError, Script, ShippedOrgan, TrainerEvent, Tray,
};
use tissue_surgery::{Surgery, SurgerySettings};

use crate::cli::{Cli, Scheme};
use crate::failure::{self, Exit, Failure};
use crate::ms;
use crate::run::percentiles;

fn surgery_failure(e: &tissue_surgery::SurgeryError) -> Failure {
    failure::from_scene(&SceneError::Surgery(e.clone()))
}

/// Runs the scenario and prints its summary.
pub fn run(cli: &Cli) -> Result<(), Failure> {
    let organ = Organ::shipped(ShippedOrgan::Appendix)
        .map_err(|e| Failure::new(Exit::Meshing, format!("the appendix: {e}")))?;
    let (material, mut settings) = cli.physics()?;
    if cli.scheme() == Scheme::Legacy {
        // The scenario's own damping before the real-time preset (the library's default step).
        settings.damping = StepSettings::default().damping;
    }
    let tray = Tray::for_extent(organ.extent());
    let mut body = organ
        .body(&material, settings, ContactParams::default(), tray)
        .map_err(|e| failure::from_scene(&e))?;
    body.set_self_collision(cli.self_collision())
        .map_err(|e| failure::from_pbd(&e))?;
    let mut surgery =
        Surgery::new(&body, SurgerySettings::default()).map_err(|e| surgery_failure(&e))?;
    println!(
        "trainer: appendix scenario, {} nodes, {} tets, {:.1} g",
        body.node_count(),
        body.tets().len(),
        body.total_mass()
    );
    let mut script = AppendixProcedure::new(&mut body, AppendixPlan::default())
        .map_err(|e| failure::from_scene(&e))?;
    let total = script.steps();
    let mut plain = Vec::new();
    let mut with_cut = Vec::new();
    let mut frames = 0usize;
    let mut events_seen = 0usize;
    let mut worst_drift = 0.0f64;
    for step in 1..=total {
        script
            .before_step(step, &mut body)
            .map_err(|e| failure::from_scene(&e))?;
        let t = Instant::now();
        body.step().map_err(|e| failure::from_pbd(&e))?;
        let drift = body.volume() / body.rest_volume() - 1.0;
        worst_drift = worst_drift.max(drift.abs());
        let done = script
            .after_step(step, &mut body, &mut surgery)
            .map_err(|e| failure::from_scene(&e))?;
        let elapsed = t.elapsed().as_secs_f64();
        if done.cut {
            with_cut.push(elapsed);
        } else {
            plain.push(elapsed);
        }
        for e in &done.events {
            events_seen += 1;
            let event = TrainerEvent::surgery(step as u64, e);
            println!("  step {step:3}  {}", event.text);
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
        crate::describe_settings(&body)
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
        body.node_count() - organ.mesh.vertex_count(),
        surgery.sutures().iter().flatten().count()
    );
    surgery
        .validate(&body)
        .map_err(|e| Failure::new(Exit::Run, format!("surface after the run: {e}")))?;
    if let Some(dir) = &cli.frames {
        println!("  frames        {frames} written to {}", dir.display());
    }
    crate::print_self_collision(&body)
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
