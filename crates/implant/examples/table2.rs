//! Experiment: Table 2 runs.
use glam::Vec3;
use tissue_implant::*;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let volume: f64 = args.get(1).map(|s| s.parse().unwrap()).unwrap_or(100.0);
    let patient = tissue_mesh::grid(65, 20.0)?;
    let radius = default_radius(3.5)?;
    let sel = select_region_with(
        &patient,
        Vec3::ZERO,
        radius,
        &RegionOptions {
            rule: RegionRule::TouchesVertex,
            ..RegionOptions::default()
        },
    )?;
    eprintln!("selected {}", sel.mesh().vertex_count());
    let mut params = InsertionParams::default();
    if let Ok(k) = std::env::var("BULK") {
        params.implant.fill_bulk_modulus = k.parse().unwrap();
    }
    if let Ok(k) = std::env::var("DEPTH") {
        params.layers.depth = k.parse().unwrap();
    }
    if let Ok(n) = std::env::var("STEPS") {
        params.run.stop.max_steps = n.parse().unwrap();
    }
    let layers = TissueLayers::new(sel.mesh(), &params.layers)?;
    let centre = sel.centre().position();
    let spec = ImplantSpec::new(ImplantShape::Round { diameter: 7.0 }, volume);
    let implant = place_implant(&layers, &spec, centre, Vec3::Z, Vec3::X)?;
    eprintln!("placed {}", implant.mesh().vertex_count());
    let mut ins = Insertion::new(sel.mesh(), &implant, &params)?;
    eprintln!(
        "h = {:e}, region {} vertices, area {:.2}",
        ins.contact_run().time_step(),
        sel.mesh().vertex_count(),
        sel.area()
    );
    if std::env::var("TRACE").is_ok() {
        let c = sel.patient_to_region()[patient
            .positions()
            .iter()
            .position(|p| p.length() < 1e-4)
            .unwrap()] as usize;
        for i in 0..800 {
            let s = ins.step()?;
            if i % 40 == 0 {
                let run = ins.contact_run();
                let l1 = run.layers().positions(Layer::Outer)[c];
                let l2 = run.layers().positions(Layer::Inner)[c];
                let apex = run
                    .body()
                    .particles()
                    .positions()
                    .iter()
                    .map(|p| p.z)
                    .fold(f32::MIN, f32::max);
                eprintln!(
                    "{i} l1 {l1} l2 {l2} apex {apex} contacts {} disp {:.3e}",
                    s.contacts, s.displacement
                );
            }
        }
        return Ok(());
    }
    let t0 = std::time::Instant::now();
    let out = ins.run(|p| {
        if p.steps % 100 == 0 || p.steps < 5 {
            eprintln!(
                "{:?} {} disp {:.4e} contacts {} remaining {}",
                t0.elapsed(),
                p.steps,
                p.last.displacement,
                p.last.contacts,
                p.last.remaining_crossings
            );
        }
        std::ops::ControlFlow::Continue(())
    })?;
    eprintln!(
        "V={volume} steps {} {:?} wall {:?}: area {:.2} -> {:.2} (+{:.2}), vol diff {:.2}, implant {:.2} -> {:.2} ({:.2}%), maxdisp {:.2}, pen {:.4}, dome {:.2}",
        out.steps, out.stop_reason, out.wall_time, out.area_before, out.area_after, out.area_gain,
        out.volume_difference, out.implant_volume, out.implant_volume_after,
        100.0 * out.implant_compression, out.max_displacement, out.max_penetration, out.dome_height
    );
    let apex = out
        .implant_after
        .positions()
        .iter()
        .map(|p| p.z)
        .fold(f32::MIN, f32::max);
    let l1 = out
        .region_after
        .positions()
        .iter()
        .map(|p| p.z)
        .fold(f32::MIN, f32::max);
    let l2 = out
        .inner_after
        .positions()
        .iter()
        .map(|p| p.z)
        .fold(f32::MIN, f32::max);
    let l2min = out
        .inner_after
        .positions()
        .iter()
        .map(|p| p.z)
        .fold(f32::MAX, f32::min);
    eprintln!("apex {apex} layer1 max {l1} layer2 max {l2} min {l2min}");
    tissue_meshio::write_surface(
        std::path::Path::new("/tmp/implant_after.obj"),
        &out.implant_after,
    )
    .unwrap();
    tissue_meshio::write_surface(
        std::path::Path::new("/tmp/inner_after.obj"),
        &out.inner_after,
    )
    .unwrap();
    Ok(())
}
