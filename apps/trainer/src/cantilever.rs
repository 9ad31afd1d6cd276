//! `--scenario cantilever`: a beam of `--length` along x and square section `--thickness`,
//! clamped at x = 0 with nothing under it, settling under gravity for `--settle-steps` with
//! the run's scheme; prints its tip deflection, with Euler–Bernoulli's for the material's E
//! and ρ beside it (`δ = q L⁴ / (8 E I)`, `q = ρ g H²`, `I = H⁴/12`: small deflections, a
//! slender beam). With `--reference` the finite-element reference solves the same beam
//! statically instead.

use std::time::Instant;

use tissue_pbd::ContactParams;
use tissue_scenes::{Organ, Tray};

use crate::cli::Cli;
use crate::failure::{self, Exit, Failure};

/// Runs the scenario.
pub fn run(cli: &Cli) -> Result<(), Failure> {
    let organ = Organ::cantilever(cli.length, cli.thickness, cli.cells)
        .map_err(|e| failure::from_scene(&e))?;
    let material = cli.elastic_material();
    let (l, h) = (f64::from(cli.length), f64::from(cli.thickness));
    let beam = material.density * tissue_fem::GRAVITY * h * h * l.powi(4)
        / (8.0 * material.young() * h.powi(4) / 12.0);
    if cli.reference {
        crate::reference::print(
            &organ,
            material,
            ([0.0, 0.0], cli.tool_radius, 0.0),
            l as f32,
        )?;
        println!("  beam theory   {beam:.4} cm (Euler–Bernoulli, small deflection)");
        return Ok(());
    }
    let (pbd_material, settings) = cli.physics()?;
    let mut body = organ
        .body(
            &pbd_material,
            settings,
            ContactParams::default(),
            Tray::for_extent(organ.extent()),
        )
        .map_err(|e| failure::from_scene(&e))?;
    body.set_self_collision(cli.self_collision())
        .map_err(|e| failure::from_pbd(&e))?;
    println!("trainer: {}, clamped at x = 0", organ.label);
    println!(
        "  organ         {} nodes, {} tets, {:.0} g, {} cells through the thickness",
        organ.mesh.vertex_count(),
        organ.mesh.tet_count(),
        body.total_mass(),
        cli.cells
    );
    if cli.settle_steps == 0 {
        return Err(Failure::new(
            Exit::Parameters,
            "--settle-steps 0: the cantilever needs steps to settle",
        ));
    }
    let mut seconds = Vec::with_capacity(cli.settle_steps);
    // The tip's mean over the last half of the steps beside its last value: once settled the
    // two agree (the damping fits the body's rigid motion with the clamp's nodes in it, so
    // the beam's swing is damped).
    let (mut sum, mut count) = (0.0f64, 0usize);
    for k in 0..cli.settle_steps {
        let t = Instant::now();
        body.step().map_err(|e| failure::from_pbd(&e))?;
        seconds.push(t.elapsed().as_secs_f64());
        if 2 * k >= cli.settle_steps {
            sum += organ.tip_deflection(body.positions()).unwrap_or(f64::NAN);
            count += 1;
        }
    }
    let (m, p, x) = crate::run::percentiles(&seconds);
    println!(
        "  run           {} steps, {}",
        cli.settle_steps,
        crate::describe_settings(&body)
    );
    println!(
        "  step time     median {}, p99 {}, max {} (all {} steps)",
        crate::ms(m),
        crate::ms(p),
        crate::ms(x),
        seconds.len()
    );
    let tip = organ.tip_deflection(body.positions()).unwrap_or(f64::NAN);
    println!(
        "  tip deflection {tip:.4} cm settled, {:.4} cm the mean over the last {count} steps",
        sum / count.max(1) as f64
    );
    println!("  beam theory   {beam:.4} cm (Euler–Bernoulli, small deflection)");
    crate::print_self_collision(&body)
}
