//! Experiment: implant under uniform pressure.
use glam::Vec3;
use tissue_implant::*;
fn main() -> Result<(), Box<dyn std::error::Error>> {
    let p: f32 = std::env::args().nth(1).map(|s| s.parse().unwrap()).unwrap_or(8e4);
    let spec = ImplantSpec::new(ImplantShape::Round { diameter: 7.0 }, 100.0);
    let implant = spec.build()?;
    let mut sys = implant_system(&implant, &ImplantParams::default())?;
    let mesh = implant.mesh();
    let normals = mesh.vertex_normals();
    let areas = mesh.triangle_areas();
    let mut va = vec![0.0f32; mesh.vertex_count()];
    for (t, a) in mesh.triangles().iter().zip(&areas) { for &v in t { va[v as usize] += (*a / 3.0) as f32; } }
    let f: Vec<Vec3> = normals.iter().zip(&va).map(|(n, a)| if n.z > 0.7 { -*n * p * *a } else { Vec3::ZERO }).collect();
    sys.set_external_forces(&f)?;
    let h = sys.stable_time_step().unwrap() * 0.5;
    sys.set_integrator(tissue_mss::Integrator::SymplecticEuler);
    sys.set_damping((-(h as f64) / 2e-3).exp() as f32)?;
    for i in 0..20000 {
        sys.step(h)?;
        if i % 4000 == 0 {
            let m = mesh.with_positions(sys.particles().positions().iter().map(|&p| p.into()).collect())?;
            eprintln!("{i} h {h:e} vol {:.3}", m.signed_volume()?);
        }
    }
    Ok(())
}
