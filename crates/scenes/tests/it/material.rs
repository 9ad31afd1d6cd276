//! The trainer's material scheme (tissue-pbd's stable neo-Hookean organ in XPBD substeps)
//! against its finite-element reference (tissue-fem through `tissue_scenes::reference`), on
//! the cantilever both solve on the same mesh.
#![allow(clippy::unwrap_used)]

use tissue_fem::ElasticMaterial;
use tissue_pbd::{ContactParams, Material, StepSettings};
use tissue_scenes::{
    reference, Organ, OrganMaterial, ReferencePlan, SceneError, SceneErrorKind, Session,
    SessionOptions, Tray,
};

/// A 4 × 1 × 1 cm beam of organ tissue (10 kPa, ν = 0.45, 1.05 g/cm³) clamped at x = 0: the
/// material scheme's tip deflection after 3 s, settled (the damping takes the clamp's nodes
/// into its fit of the rigid motion, so the beam's swing is damped), within 5 % of the
/// reference's static solve (measured +2.7 %; plain XPBD, `over_relaxation` 0: +5.3 %), and
/// converged: with 64 substeps instead of 32 it moves by less than 3 % (measured 2.3 %; plain
/// XPBD 3.5 %).
#[test]
fn the_material_schemes_cantilever_sags_as_its_reference() {
    let organ = Organ::cantilever(4.0, 1.0, 4).unwrap();
    let (young, poisson, density) = (
        Material::ORGAN_YOUNG_KPA,
        Material::ORGAN_POISSON,
        Material::ORGAN_DENSITY,
    );
    let plan = ReferencePlan {
        material: tissue_fem::ElasticMaterial {
            young_kpa: f64::from(young),
            poisson: f64::from(poisson),
            density: f64::from(density),
        },
        probe_radius: 0.4,
        at: [0.0, 0.0],
        depths: Vec::new(),
    };
    let fem = reference(&organ, &plan).unwrap();
    assert!(fem.settle.converged);
    let fem_tip = fem.tip_deflection.unwrap();
    let pbd_tip = |substeps: u32| {
        let material = Material::elastic(young, poisson, density).unwrap();
        let settings = StepSettings {
            substeps,
            ..StepSettings::material()
        };
        let mut body = organ
            .body(
                &material,
                settings,
                ContactParams::default(),
                Tray::for_extent(4.0),
            )
            .unwrap();
        let mut last = 0.0;
        for _ in 0..299 {
            body.step().unwrap();
            last = organ.tip_deflection(body.positions()).unwrap();
        }
        body.step().unwrap();
        let tip = organ.tip_deflection(body.positions()).unwrap();
        assert!(
            (tip - last).abs() < 1e-3 * tip,
            "{substeps} substeps: the tip still moves ({last} → {tip} cm in a step)"
        );
        tip
    };
    let (tip32, tip64) = (pbd_tip(32), pbd_tip(64));
    eprintln!(
        "cantilever tip: reference {fem_tip:.4} cm, material scheme {tip32:.4} cm (32 substeps), \
         {tip64:.4} cm (64)"
    );
    assert!(
        (tip32 / fem_tip - 1.0).abs() < 0.05,
        "{tip32} against {fem_tip}"
    );
    assert!(
        (tip64 / tip32 - 1.0).abs() < 0.03,
        "{tip64} against {tip32}"
    );
}

/// The session's material entry point (used by the studio and the C ABI) refuses what the
/// solver cannot take, naming the parameter, and a stiffer organ sags less on its tray.
#[test]
fn a_session_takes_a_material_and_refuses_a_bad_one() {
    let bad = OrganMaterial {
        elastic: ElasticMaterial {
            poisson: 0.6,
            ..OrganMaterial::soft_organ().elastic
        },
        ..OrganMaterial::soft_organ()
    };
    let e = SessionOptions::material(&bad).unwrap_err();
    assert_eq!(e.kind(), SceneErrorKind::Parameters, "{e}");
    assert!(e.to_string().contains("poisson"), "{e}");
    let slow = OrganMaterial {
        relaxation_time: 0.0,
        ..OrganMaterial::soft_organ()
    };
    assert!(matches!(
        SessionOptions::material(&slow),
        Err(SceneError::RelaxationTime { .. })
    ));

    // A 4 cm box on its tray: the top's settled sag at 10 kPa and at 20 kPa.
    let cube = tissue_mesh::tet_box(6, 6, 6, glam::Vec3::splat(4.0)).unwrap();
    let organ = Organ::from_tets(&cube, "cube").unwrap();
    let sag = |young_kpa: f64| {
        let m = OrganMaterial {
            elastic: ElasticMaterial {
                young_kpa,
                ..OrganMaterial::soft_organ().elastic
            },
            ..OrganMaterial::soft_organ()
        };
        let mut s = Session::new(&organ, SessionOptions::material(&m).unwrap()).unwrap();
        let top0 = s.positions().iter().map(|p| p.y).fold(f32::MIN, f32::max);
        for _ in 0..150 {
            s.step().unwrap();
        }
        let top = s.positions().iter().map(|p| p.y).fold(f32::MIN, f32::max);
        top0 - top
    };
    let (soft, stiff) = (sag(10.0), sag(20.0));
    assert!(soft > 0.0, "the organ sags: {soft} cm");
    let ratio = stiff / soft;
    assert!(
        (0.4..0.65).contains(&ratio),
        "twice E: sag × {ratio} ({soft} → {stiff} cm)"
    );
}
