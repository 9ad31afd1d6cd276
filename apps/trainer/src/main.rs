//! `trainer`: a headless surgical-trainer run from the command line.
//!
//! Command line ([`cli`]) → the organ on the tray with a probe ([`scene`]) → settle, press, drag
//! with per-step timing, volume drift and frames ([`run`]) → a summary on stdout. Every failure is
//! one line on stderr and a documented exit code ([`failure`]); see `trainer --help`.
#![allow(clippy::print_stdout, clippy::print_stderr)]

mod appendix;
mod cantilever;
mod cli;
mod failure;
mod reference;
mod run;
mod scene;

use std::process::ExitCode;

use clap::Parser;

use crate::cli::Cli;
use crate::failure::Failure;

fn ms(s: f64) -> String {
    format!("{:.2} ms", s * 1e3)
}

/// The scheme of a run, for the summaries: `dt = 0.01 s, 9 substeps × K = 1, Xpbd, Classic
/// volume`.
fn describe_settings(body: &tissue_pbd::SoftBody) -> String {
    let s = body.settings();
    let material = match body.elastic() {
        Some(e) => format!(
            "neo-Hookean E = {} kPa, ν = {}, ρ = {} g/cm³, τ = {:.3} s",
            e.young_kpa,
            e.poisson,
            body.density(),
            s.relaxation_time()
        ),
        None => format!("{:?} volume", body.volume_kind()),
    };
    format!(
        "dt = {} s, {} substep{} × K = {}, {:?}, {material}{}",
        s.dt,
        s.substeps,
        if s.substeps == 1 { "" } else { "s" },
        s.iterations,
        s.solver,
        if s.parallel { ", colour-parallel" } else { "" }
    )
}

/// The self-collision lines every run ends with: whether it is on (its thickness, the last
/// step's self-contacts; on unless `--no-self-collision`), then `self-intersections N`, the pairs of surface triangles that
/// intersect at the end (tissue-scenes' exact count over the body's boundary faces, cut walls
/// included; 0 when the organ does not pass through itself).
fn print_self_collision(body: &tissue_pbd::SoftBody) -> Result<(), Failure> {
    match body.self_collision() {
        Some(_) => {
            let (found, active) = body.self_contact_counts();
            println!(
                "  self-collision on, thickness {:.3} cm, the last step's self-contacts: found \
                 {found}, active {active}, dropped {}; suspended {} times for a tangled surface",
                body.self_collision_thickness().unwrap_or(f32::NAN),
                body.self_contacts_dropped(),
                body.self_collision_suspensions()
            );
        }
        // Off by `--no-self-collision` (tissue-scenes' default is on), or by that default.
        None if tissue_scenes::SessionOptions::default()
            .self_collision
            .is_some() =>
        {
            println!("  self-collision off (--no-self-collision; on by default)");
        }
        None => println!("  self-collision off (the default; --self-collision switches it on)"),
    }
    let n = tissue_scenes::surface_self_intersections(body.positions(), &body.surface_triangles())
        .map_err(|e| failure::from_scene(&e))?;
    println!("  self-intersections {n}");
    Ok(())
}

fn main_inner(cli: &Cli) -> Result<(), Failure> {
    match cli.scenario {
        Some(cli::Scenario::Appendix) if cli.reference => {
            return Err(Failure::new(
                failure::Exit::Parameters,
                "--reference solves a press on the tray or the cantilever, not the appendix's \
                 surgery: drop one of them",
            ))
        }
        Some(cli::Scenario::Appendix) => return appendix::run(cli),
        Some(cli::Scenario::Cantilever) => return cantilever::run(cli),
        None => {}
    }
    let mut scene = scene::build(cli)?;
    if cli.reference {
        let at = scene
            .script
            .plan()
            .waypoints
            .first()
            .copied()
            .unwrap_or([0.0, 0.0]);
        reference::print(
            &scene.organ,
            cli.elastic_material(),
            (at, cli.tool_radius, cli.depth),
            cli.size,
        )?;
        return Ok(());
    }
    let (nodes, tets) = (
        scene.organ.mesh.vertex_count(),
        scene.organ.mesh.tet_count(),
    );
    println!("trainer: {}", scene.source);
    println!(
        "  organ         {nodes} nodes, {tets} tets, {:.1} cm, {:.0} g, V0 = {:.1} cm³",
        cli.size,
        scene.body.total_mass(),
        scene.body.rest_volume()
    );
    let summary = run::run(cli, &mut scene)?;
    let all = &summary.step_seconds;
    let tool = &all[summary.tool_from.min(all.len())..];
    let (m, p, x) = run::percentiles(all);
    println!(
        "  run           {} steps (settle {}, press {}, drag {}), {}",
        all.len(),
        cli.settle_steps,
        cli.press_steps,
        cli.drag_steps,
        describe_settings(&scene.body)
    );
    println!(
        "  step time     median {}, p99 {}, max {} (all {} steps)",
        ms(m),
        ms(p),
        ms(x),
        all.len()
    );
    if !tool.is_empty() {
        let (m, p, x) = run::percentiles(tool);
        println!(
            "  with probe    median {}, p99 {}, max {} ({} steps)",
            ms(m),
            ms(p),
            ms(x),
            tool.len()
        );
    }
    println!(
        "  volume drift  {:+.3} % at the end (V/V0 = {:.4}, V0 as loaded), largest |drift| {:.3} %",
        (summary.volume_ratio - 1.0) * 100.0,
        summary.volume_ratio,
        summary.worst_drift * 100.0
    );
    println!(
        "  tet volumes   |V/V0 - 1| per tet at the end: median {:.2} %, p90 {:.2} %, volume-weighted mean {:.2} %",
        summary.tet_error[0] * 100.0,
        summary.tet_error[1] * 100.0,
        summary.tet_error[2] * 100.0
    );
    let (loaded, settled) = summary.height;
    println!(
        "  height        {loaded:.2} cm as loaded, {settled:.2} cm settled ({:+.1} %)",
        (settled / loaded - 1.0) * 100.0
    );
    println!(
        "  contacts      {} with the tray, {} with the probe (last step)",
        summary.contacts.0, summary.contacts.1
    );
    let (largest, last) = summary.probe_force;
    println!(
        "  probe force   largest {largest:.4} N, final {:.4} N ({:.4}, {:.4}, {:.4}) N, on the probe from the tissue",
        last.length(),
        last.x,
        last.y,
        last.z
    );
    if let Some(dir) = &cli.frames {
        println!(
            "  frames        {} written to {}",
            summary.frames,
            dir.display()
        );
    }
    print_self_collision(&scene.body)
}

fn main() -> ExitCode {
    // A closed stdout (`| head`) ends the program by SIGPIPE, silently; see tissue-cli.
    tissue_cli::reset_sigpipe();
    let cli = Cli::parse();
    if let Err(message) = cli.check() {
        use clap::CommandFactory;
        Cli::command()
            .error(clap::error::ErrorKind::ArgumentConflict, message)
            .exit();
    }
    match main_inner(&cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(failure) => {
            let hint = if failure.code == failure::Exit::Usage {
                " (see trainer --help)"
            } else {
                ""
            };
            eprintln!("trainer: error: {}{hint}", failure.line());
            ExitCode::from(failure.code)
        }
    }
}
