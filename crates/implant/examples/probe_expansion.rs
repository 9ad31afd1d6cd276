#![allow(missing_docs, clippy::print_stdout)]
use std::ops::ControlFlow;
use glam::Vec3;
use tissue_implant::*;
fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<f64> = std::env::args().skip(1).filter_map(|a| a.parse().ok()).collect();
    let n = args.first().map_or(33, |&v| v as u32);
    let volume = args.get(1).copied().unwrap_or(200.0);
    let weeks = args.get(2).map_or(10, |&v| v as u32);
    let patient = tissue_mesh::grid(n, 20.0)?;
    let sel = select_region_with(&patient, Vec3::ZERO, default_radius(3.5)?, &RegionOptions { rule: RegionRule::TouchesVertex, ..RegionOptions::default() })?;
    let setup = ExpansionSetup { region: sel.mesh().clone(), centre: Vec3::ZERO, normal: Vec3::Z, tangent: Vec3::X,
        implant: ImplantSpec::new(ImplantShape::Round { diameter: 7.0 }, volume).with_vertex_budget(200), params: InsertionParams::default() };
    let protocol = Protocol::weekly(volume, weeks, 1.0, LEAKAGE_MEAN, 0.0)?;
    let t = std::time::Instant::now();
    let mut g = GrowthParams::human(); if let Some(&c) = args.get(3) { g.law.threshold = c; }
    let o = expand(&setup, &protocol, &g, Some(&BandOptions::default()), &|_| ControlFlow::Continue(()))?;
    println!("wall {:?} steps {} ref {}", t.elapsed(), o.steps, o.reference_steps);
    let rest = &o.region_rest; let now = &o.region_expanded;
    let mut count = 0; let mut maxr: f32 = 0.0;
    for (i, tri) in rest.triangles().iter().enumerate() {
        if o.flap[i] { count += 1; let c = (rest.positions()[tri[0] as usize] + rest.positions()[tri[1] as usize] + rest.positions()[tri[2] as usize]) / 3.0; maxr = maxr.max(c.truncate().length()); }
    }
    println!("flap tris {count} of {}, max rest radius {maxr}", rest.triangle_count());
    for r in [0.0f32, 1.0, 2.0, 3.0, 3.5, 4.0, 4.5, 5.0] {
        // nearest vertex to (r,0) at rest, and where it is now
        let (i, _) = rest.positions().iter().enumerate().map(|(i,p)| (i, (p.truncate() - glam::Vec2::new(r, 0.0)).length())).min_by(|a,b| a.1.total_cmp(&b.1)).unwrap();
        println!("rest r {r}: now {:?}", now.positions()[i]);
    }
    println!("base {:.2} recruited {:.2} dome {:.2} grown {:.2} flap {:.2} G {:.2} eff {:.3} retr {:.3}", o.base_area, o.recruited_area, o.dome_area, o.grown_area, o.flap_area, o.geometric_gain, o.efficiency, o.retraction);
    if let Some(b) = &o.band { println!("band flap {:?} retr {:?} eff {:?}", b.flap_area, b.retraction, b.efficiency); }
    Ok(())
}
