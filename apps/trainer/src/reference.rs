//! `--reference`: the run's organ, material, support and probe depth solved for their static
//! states by the finite-element reference (`tissue_scenes::reference`, tissue-fem's stable
//! neo-Hookean energy) instead of stepped, printed in the run's own summary lines so that the
//! two can be held side by side.

use tissue_fem::ElasticMaterial;
use tissue_scenes::{Organ, ReferencePlan, ReferenceSummary, Setting};

use crate::failure::{self, Failure};

/// Solves and prints the reference of `organ` pressed at `at` by a probe of `radius` to
/// `depth` below its settled top (no press for a cantilever).
pub fn print(
    organ: &Organ,
    material: ElasticMaterial,
    (at, radius, depth): ([f32; 2], f32, f32),
    size: f32,
) -> Result<ReferenceSummary, Failure> {
    let plan = ReferencePlan {
        material,
        probe_radius: radius,
        at,
        depths: if organ.setting == Setting::Cantilever {
            Vec::new()
        } else {
            vec![depth]
        },
    };
    let summary = tissue_scenes::reference(organ, &plan).map_err(|e| failure::from_scene(&e))?;
    println!(
        "trainer: finite-element reference (tissue-fem, stable neo-Hookean, E = {} kPa, ν = {}, \
         ρ = {} g/cm³, static): {}",
        material.young_kpa, material.poisson, material.density, organ.label
    );
    println!(
        "  organ         {} nodes, {} tets, {size:.1} cm",
        organ.mesh.vertex_count(),
        organ.mesh.tet_count()
    );
    println!(
        "  height        {:.2} cm as loaded, {:.2} cm settled ({:+.1} %)",
        summary.height_loaded,
        summary.height_settled,
        100.0 * (summary.height_settled / summary.height_loaded - 1.0)
    );
    if let Some(tip) = summary.tip_deflection {
        println!("  tip deflection {tip:.4} cm settled");
    }
    for press in &summary.presses {
        println!(
            "  probe force   {:.4} N at {:.2} cm below the settled top, on the probe from the \
             tissue",
            press.force_n, press.depth
        );
    }
    let report = |r: &tissue_fem::StaticReport| {
        format!(
            "{} Newton iterations, residual {:.1e} of the load{}",
            r.iterations,
            r.relative_residual,
            if r.converged { "" } else { " (NOT converged)" }
        )
    };
    println!("  solver        settled: {}", report(&summary.settle));
    for press in &summary.presses {
        println!("                pressed: {}", report(&press.report));
    }
    Ok(summary)
}
