//! The probe's force against the finite-element reference: a probe pressed into a block on its
//! tray with the material scheme (tissue-pbd's stable neo-Hookean organ in XPBD substeps, the
//! press-and-drag timeline of the trainer and the studio) and the same block, material, support
//! and probe solved statically by `tissue_scenes::reference` (issue 32).
#![allow(clippy::unwrap_used)]

use glam::Vec3;
use tissue_pbd::{ContactParams, Material, StepSettings, DYN_PER_NEWTON};
use tissue_scenes::{reference, Organ, PressAndDrag, PressPlan, ReferencePlan, Script, Tray};

/// The block's side (cm), its cells a side, the probe's radius (cm) and where it presses.
const SIDE: f32 = 4.0;
const CELLS: u32 = 8;
const RADIUS: f32 = 1.0;
const AT: [f32; 2] = [0.0, 0.0];

fn block() -> Organ {
    let tets = tissue_mesh::tet_box(CELLS, CELLS, CELLS, Vec3::splat(SIDE)).unwrap();
    Organ::from_tets(&tets, "block").unwrap()
}

/// The material scheme's probe force (N) at `depth` below the settled top: the trainer's
/// press (settle, press), then the probe held still for 0.5 s and its force averaged over the
/// last 0.25 s.
fn pbd_force(organ: &Organ, depth: f32, friction: f32) -> f64 {
    let material = Material::elastic(
        Material::ORGAN_YOUNG_KPA,
        Material::ORGAN_POISSON,
        Material::ORGAN_DENSITY,
    )
    .unwrap();
    let contact = ContactParams {
        static_friction: friction,
        kinetic_friction: friction,
        ..ContactParams::default()
    };
    let mut body = organ
        .body(
            &material,
            StepSettings::material(),
            contact,
            Tray::for_extent(SIDE),
        )
        .unwrap();
    let plan = PressPlan {
        drag: 0,
        depth,
        radius: RADIUS,
        waypoints: vec![AT, AT],
        ..PressPlan::default()
    };
    let mut script = PressAndDrag::on_tray(&mut body, SIDE, plan, contact).unwrap();
    for k in 1..=script.steps() {
        script.before_step(k, &mut body).unwrap();
        body.step().unwrap();
    }
    let (hold, read) = (50, 25);
    let mut sum = 0.0;
    for k in 0..hold {
        body.step().unwrap();
        if k >= hold - read {
            sum += f64::from(body.tool_force(script.tool()).unwrap().length() / DYN_PER_NEWTON);
        }
    }
    sum / f64::from(read)
}

/// A 4 cm block of organ tissue (10 kPa, ν = 0.45, 1.05 g/cm³; 8 cells a side, 0.5 cm between
/// nodes, 3 072 tets) on its tray, a probe of radius 1 cm pressed 0.2, 0.4 and 0.6 cm below its
/// settled top: the material scheme's probe force within 10 % of the reference's at each depth,
/// with the trainer's friction (0.5 on the tray and the probe, `ContactParams::default`).
/// Measured: reference 0.1396 / 0.4580 / 0.8237 N, material scheme +0.6 / +2.2 / +2.9 %.
#[test]
fn the_probe_force_matches_the_reference_at_three_depths() {
    let organ = block();
    let depths = [0.2f32, 0.4, 0.6];
    let plan = ReferencePlan {
        material: tissue_fem::ElasticMaterial {
            young_kpa: f64::from(Material::ORGAN_YOUNG_KPA),
            poisson: f64::from(Material::ORGAN_POISSON),
            density: f64::from(Material::ORGAN_DENSITY),
        },
        probe_radius: RADIUS,
        at: AT,
        depths: depths.to_vec(),
    };
    let fem = reference(&organ, &plan).unwrap();
    let mut figures = String::new();
    let mut worst = 0.0f64;
    {
        let friction = 0.5;
        for (press, &depth) in fem.presses.iter().zip(&depths) {
            assert!(press.report.converged, "{:?}", press.report);
            let pbd = pbd_force(&organ, depth, friction);
            let error = pbd / press.force_n - 1.0;
            worst = worst.max(error.abs());
            figures += &format!(
                "\n  probe friction {friction}, {depth} cm: reference {:.4} N, material scheme \
                 {pbd:.4} N ({:+.1} %)",
                press.force_n,
                100.0 * error
            );
        }
    }
    assert!(worst <= 0.10, "{figures}");
    // The force grows with the depth, faster than linearly (Hertz: d^1.5).
    let f: Vec<f64> = fem.presses.iter().map(|p| p.force_n).collect();
    assert!(f[1] > 2.0 * f[0] && f[2] > 1.5 * f[1], "{figures}");
    eprintln!("{figures}");
}

/// The press starts from an organ at rest: a 10 cm box (8 cells a side) on its tray, the
/// default timeline's settling (100 steps), its top where it is after 2 s more (the probe
/// waiting 0.5 cm above it) within 0.01 cm. The rigid-mode damping alone keeps the bounce's
/// centre-of-mass motion: without the settling's damping the top was 0.06 cm off on the 16-cell
/// box and each press went that much deeper than planned.
#[test]
fn the_press_starts_from_a_settled_organ() {
    let side = 10.0;
    let tets = tissue_mesh::tet_box(8, 8, 8, Vec3::splat(side)).unwrap();
    let organ = Organ::from_tets(&tets, "box").unwrap();
    let material = Material::soft_organ();
    let contact = ContactParams::default();
    let mut body = organ
        .body(
            &material,
            StepSettings::material(),
            contact,
            Tray::for_extent(side),
        )
        .unwrap();
    let plan = PressPlan {
        waypoints: vec![AT, AT],
        ..PressPlan::default()
    };
    let settle = plan.settle;
    let mut script = PressAndDrag::on_tray(&mut body, side, plan, contact).unwrap();
    let top = |body: &tissue_pbd::SoftBody| {
        body.positions()
            .iter()
            .filter(|p| p.x.hypot(p.z) <= 1.5)
            .map(|p| p.y)
            .fold(f32::MIN, f32::max)
    };
    let mut tops = Vec::new();
    for k in 1..=settle {
        script.before_step(k, &mut body).unwrap();
        body.step().unwrap();
        tops.push(top(&body));
    }
    // The press's first step: the probe goes to 0.5 cm above the top and stays there.
    script.before_step(settle + 1, &mut body).unwrap();
    assert_eq!(
        body.settings(),
        &StepSettings::material(),
        "the damping is back"
    );
    for _ in 0..200 {
        body.step().unwrap();
    }
    let (at_press, rest) = (tops[settle - 1], top(&body));
    let sag = side - rest;
    assert!(
        (at_press - rest).abs() <= 0.01 && sag > 0.1,
        "top {at_press} cm when the press starts, {rest} cm at rest (sag {sag} cm); \
         the last settling steps: {:?}",
        &tops[settle - 10..]
    );
}
