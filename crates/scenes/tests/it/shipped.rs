//! The shipped organs (bunny, liver, appendix) in the finite-element reference against the
//! trainer's material scheme.
#![allow(clippy::unwrap_used)]

use std::time::Instant;

use tissue_fem::ElasticMaterial;
use tissue_pbd::{ContactParams, StepSettings};
use tissue_scenes::{reference, Organ, OrganMaterial, ReferencePlan, ShippedOrgan, Tray};

fn init_tracing() {
    if std::env::var_os("RUST_LOG").is_some() {
        let _ = tracing_subscriber::fmt()
            .with_env_filter(tracing_subscriber::EnvFilter::from_default_env())
            .with_span_events(tracing_subscriber::fmt::format::FmtSpan::CLOSE)
            .with_writer(std::io::stderr)
            .try_init();
    }
}

fn height(ys: impl Iterator<Item = f64>) -> f64 {
    let (lo, hi) = ys.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), y| {
        (lo.min(y), hi.max(y))
    });
    hi - lo
}

/// The material scheme's organ settled `steps` steps on its support as the trainer holds it
/// (the tray's friction `friction`): its height as loaded and settled (cm).
fn pbd_heights(
    organ: &Organ,
    material: &OrganMaterial,
    friction: f32,
    steps: usize,
    substeps: u32,
) -> (f64, f64) {
    let settings = StepSettings {
        parallel: true,
        substeps,
        ..StepSettings::material().with_relaxation_time(material.relaxation_time)
    };
    let contact = ContactParams {
        static_friction: friction,
        kinetic_friction: friction,
        ..ContactParams::default()
    };
    let mut body = organ
        .body(
            &material.pbd().unwrap(),
            settings,
            contact,
            Tray::for_extent(organ.extent()),
        )
        .unwrap();
    let h = |b: &tissue_pbd::SoftBody| height(b.positions().iter().map(|p| f64::from(p.y)));
    let loaded = h(&body);
    for _ in 0..steps {
        body.step().unwrap();
    }
    (loaded, h(&body))
}

fn fem_plan(material: ElasticMaterial) -> ReferencePlan {
    ReferencePlan {
        material,
        probe_radius: 0.4,
        at: [0.0, 0.0],
        depths: Vec::new(),
    }
}

/// The settled sag (height as loaded minus settled, cm) of `which` under `material`: the
/// reference's, with its report, and the material scheme's after `steps` steps on the trainer's
/// tray (friction 0.5).
fn sags(
    which: ShippedOrgan,
    material: &OrganMaterial,
    steps: usize,
) -> (f64, tissue_fem::StaticReport, f64) {
    let organ = Organ::shipped(which).unwrap();
    let fem = reference(&organ, &fem_plan(material.elastic)).unwrap();
    let (loaded, settled) = pbd_heights(
        &organ,
        material,
        0.5,
        steps,
        StepSettings::MATERIAL_SUBSTEPS,
    );
    assert!((loaded - fem.height_loaded).abs() < 1e-4);
    (
        fem.height_loaded - fem.height_settled,
        fem.settle,
        loaded - settled,
    )
}

fn check(which: ShippedOrgan, material: &OrganMaterial, steps: usize, bound: f64) -> String {
    let (fem, report, pbd) = sags(which, material, steps);
    let figures = format!(
        "{}, E = {:.2} kPa, ν = {:.2}: reference sag {fem:.4} cm ({} Newton iterations), \
         material scheme {pbd:.4} cm after {steps} steps ({:+.1} %)",
        which.id(),
        material.elastic.young_kpa,
        material.elastic.poisson,
        report.iterations,
        100.0 * (pbd / fem - 1.0)
    );
    assert!(report.converged, "{figures}: {report:?}");
    // The stall this guards against took hundreds of iterations.
    assert!(report.iterations <= 120, "{figures}");
    assert!(fem > 0.0 && pbd > 0.0, "{figures}");
    assert!((pbd / fem - 1.0).abs() <= bound, "{figures}");
    figures
}

/// The shipped liver (SOFA's, 16 cm) settled on its tray: the material scheme's sag within
/// 10 % of its finite-element reference's, with the material scheme's default organ (10 kPa,
/// ν = 0.45) and the liver's preset tissue (5.4 kPa, ν = 0.49). Measured (2-core machine,
/// release): reference 2.166 / 2.413 cm in 1.1 / 1.6 s (30 / 41 Newton iterations); material
/// scheme after 300 steps (3 s) −1.9 / +1.2 %. After the trainer's 100 settling steps the
/// liver, held by the tray's friction, is not yet settled (−10.9 / −7.3 %; frictionless
/// −1.6 / +1.1 %), hence 300.
#[test]
fn the_shipped_liver_settles_as_its_reference() {
    for material in [
        OrganMaterial::soft_organ(),
        OrganMaterial::preset(ShippedOrgan::Liver.tissue()),
    ] {
        check(ShippedOrgan::Liver, &material, 300, 0.10);
    }
}

/// The shipped bunny (9 046 nodes, 39 706 tets) settled on its tray as the trainer runs it
/// (100 steps, friction 0.5): the material scheme's sag within 10 % of its finite-element
/// reference's, default organ (10 kPa, ν = 0.45) and the liver's preset tissue (5.4 kPa,
/// ν = 0.49). Measured (2-core machine, release): reference sags 2.187 cm (9.911 → 7.724 cm;
/// 15 s, 26 Newton iterations over 4 load steps) and 3.067 cm (31 s, 46 iterations);
/// material scheme +7.7 % and +6.3 % (frictionless tray +2.7 % and +9.4 %). Before the
/// over-relaxation (plain XPBD) +9.1 % and +10.8 %: what is left is the substeps' softness.
#[test]
fn the_shipped_bunny_settles_as_its_reference() {
    check(ShippedOrgan::Bunny, &OrganMaterial::soft_organ(), 100, 0.10);
    check(
        ShippedOrgan::Bunny,
        &OrganMaterial::preset(ShippedOrgan::Bunny.tissue()),
        100,
        0.10,
    );
}

/// Measuring aid: `TISSUE_ORGAN=bunny TISSUE_MATERIAL=default|preset TISSUE_STEPS=100[,300] [TISSUE_SUBSTEPS=64]
/// [RUST_LOG=tissue_fem=debug] cargo test --release -p tissue-scenes --test it
/// shipped::measure -- --ignored --nocapture`.
#[test]
#[ignore = "minutes: a measuring aid"]
fn measure() {
    init_tracing();
    let id = std::env::var("TISSUE_ORGAN").unwrap_or_else(|_| "bunny".into());
    let which = ShippedOrgan::from_id(&id).unwrap();
    let organ = Organ::shipped(which).unwrap();
    let material = match std::env::var("TISSUE_MATERIAL").as_deref() {
        Ok("preset") => OrganMaterial::preset(which.tissue()),
        _ => OrganMaterial::soft_organ(),
    };
    let ys: Vec<f32> = organ.mesh.positions().iter().map(|p| p.y).collect();
    let lowest = ys.iter().copied().fold(f32::INFINITY, f32::min);
    for tol in [1e-6, 1e-3, 1e-2, 1e-1] {
        let n = ys.iter().filter(|&&y| y <= lowest + tol).count();
        eprintln!("{id}: {n} nodes within {tol} cm of the lowest ({lowest})");
    }
    let fem_sag: f64 = match std::env::var("TISSUE_FEM_SAG")
        .ok()
        .and_then(|s| s.parse().ok())
    {
        Some(sag) => sag,
        None => {
            let start = Instant::now();
            let s = reference(&organ, &fem_plan(material.elastic)).unwrap();
            let fem_seconds = start.elapsed().as_secs_f64();
            let fem_sag = s.height_loaded - s.height_settled;
            eprintln!(
        "{id} {:?}: reference loaded {:.4} settled {:.4} sag {fem_sag:.4} cm in {fem_seconds:.1} s; \
         {:?}",
                material.elastic, s.height_loaded, s.height_settled, s.settle
            );
            fem_sag
        }
    };
    let steps: Vec<usize> = std::env::var("TISSUE_STEPS")
        .unwrap_or_default()
        .split(',')
        .filter_map(|s| s.parse().ok())
        .collect();
    let substeps = std::env::var("TISSUE_SUBSTEPS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(StepSettings::MATERIAL_SUBSTEPS);
    for friction in [0.5, 0.0] {
        for &steps in &steps {
            let start = Instant::now();
            let (loaded, settled) = pbd_heights(&organ, &material, friction, steps, substeps);
            let sag = loaded - settled;
            eprintln!(
                "{id}: material scheme, friction {friction}, {steps} steps: loaded {loaded:.4} \
                 settled {settled:.4} sag {sag:.4} cm ({:+.1} % of the reference's) in {:.1} s",
                100.0 * (sag / fem_sag - 1.0),
                start.elapsed().as_secs_f64()
            );
        }
    }
}

/// The shipped appendix (8 × 2 × 2 cm on the abdominal wall, base pinned) settled: its pinned
/// base keeps the full height, so the sag measured is the top's over its free half (x > 0),
/// the material scheme's after 100 steps within 10 % of the reference's (tissue-fem held as
/// `tissue_scenes::reference` holds it: base clamped, frictionless floor at y = 0). Measured:
/// default organ 0.02025 cm against 0.02092 cm (+3.3 %; plain XPBD +3.8 %), the bowel's preset
/// (3.84 kPa, ν = 0.49) 0.05166 cm against plain XPBD's 0.05377 cm (+4.1 %; +1.2 % after 300
/// steps); under a second.
#[test]
fn the_shipped_appendix_settles_as_its_reference() {
    let which = ShippedOrgan::Appendix;
    let organ = Organ::shipped(which).unwrap();
    let rest: Vec<glam::Vec3> = organ.mesh.positions().to_vec();
    let top: Vec<usize> = (0..rest.len())
        .filter(|&i| rest[i].y > 2.0 - 1e-4 && rest[i].x > 0.0)
        .collect();
    assert!(!top.is_empty());
    let sag = |ys: &dyn Fn(usize) -> f64| {
        top.iter()
            .map(|&i| f64::from(rest[i].y) - ys(i))
            .sum::<f64>()
            / top.len() as f64
    };
    for material in [
        OrganMaterial::soft_organ(),
        OrganMaterial::preset(which.tissue()),
    ] {
        let mut p = tissue_fem::StaticProblem::new(&organ.mesh, material.elastic).unwrap();
        p.set_gravity(glam::DVec3::new(0.0, -tissue_fem::GRAVITY, 0.0))
            .unwrap();
        p.set_floor(tissue_fem::Plane {
            point: glam::DVec3::ZERO,
            normal: glam::DVec3::Y,
        })
        .unwrap();
        p.set_settings(tissue_fem::SolverSettings {
            residual_tolerance: 1e-6,
            load_steps: 4,
            ..tissue_fem::SolverSettings::default()
        })
        .unwrap();
        p.clamp_where(|q| q.x < f64::from(tissue_scenes::APPENDIX_BASE_X));
        let s = p.solve().unwrap();
        assert!(s.report.converged, "{:?}", s.report);
        let fem = sag(&|i| s.positions[i].y);
        let settings = StepSettings {
            parallel: true,
            ..StepSettings::material().with_relaxation_time(material.relaxation_time)
        };
        let mut body = organ
            .body(
                &material.pbd().unwrap(),
                settings,
                ContactParams::default(),
                Tray::for_extent(organ.extent()),
            )
            .unwrap();
        for _ in 0..100 {
            body.step().unwrap();
        }
        let pbd = sag(&|i| f64::from(body.positions()[i].y));
        let figures = format!(
            "appendix, E = {:.2} kPa, ν = {:.2}: top sag reference {fem:.5} cm, material \
             scheme {pbd:.5} cm ({:+.1} %)",
            material.elastic.young_kpa,
            material.elastic.poisson,
            100.0 * (pbd / fem - 1.0)
        );
        assert!(fem > 0.0, "{figures}");
        assert!((pbd / fem - 1.0).abs() <= 0.10, "{figures}");
    }
}
