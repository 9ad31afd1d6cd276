//! The body's material through the C ABI (issue 32): a 4 cm tet box of the material scheme at
//! `E` and at `2E` settles on its tray and is pressed by a probe to the same depth; the stiffer
//! one sags about half as much and pushes back about twice as hard (both would be equal if the
//! material were ignored). A Poisson's ratio out of range is refused naming `poisson`; the
//! presets and the material in force read back.
#![allow(clippy::unwrap_used, clippy::panic, clippy::print_stderr)]

use std::ptr;

use tissue::*;

fn last_error() -> String {
    let n = tissue_last_error(ptr::null_mut(), 0);
    let mut buffer = vec![0u8; n.max(1)];
    tissue_last_error(buffer.as_mut_ptr().cast(), buffer.len());
    buffer.pop();
    String::from_utf8_lossy(&buffer).into_owned()
}

fn ok(status: tissue_status, what: &str) {
    assert_eq!(status, tissue_status::TISSUE_OK, "{what}: {}", last_error());
}

/// A 4 cm box of 6 × 6 × 6 cells (six tets a cell) as a C mesh.
fn cube() -> *mut tissue_mesh {
    let m = ::tissue_mesh::tet_box(6, 6, 6, glam::Vec3::splat(4.0)).unwrap();
    let positions: Vec<f32> = m.positions().iter().flat_map(|p| p.to_array()).collect();
    let tets: Vec<u32> = m.tets().iter().flatten().copied().collect();
    let mut mesh = ptr::null_mut();
    ok(
        tissue_mesh_from_tets(
            positions.as_ptr(),
            positions.len() / 3,
            tets.as_ptr(),
            tets.len() / 4,
            &mut mesh,
        ),
        "mesh",
    );
    mesh
}

fn material(young_kpa: f64) -> tissue_material {
    let mut m = tissue_material::default();
    ok(tissue_material_default(&mut m), "default material");
    m.young_kpa = young_kpa;
    m
}

fn positions(body: *const tissue_body) -> Vec<[f32; 3]> {
    let mut info = tissue_body_info::default();
    ok(tissue_body_get_info(body, &mut info), "info");
    let mut xyz = vec![0.0f32; 3 * info.nodes as usize];
    ok(
        tissue_body_copy_positions(body, xyz.as_mut_ptr(), xyz.len(), ptr::null_mut()),
        "positions",
    );
    xyz.chunks_exact(3).map(|p| [p[0], p[1], p[2]]).collect()
}

/// The highest node within 0.3 cm of the vertical axis x = z = 0.
fn top(body: *const tissue_body) -> f32 {
    positions(body)
        .iter()
        .filter(|p| p[0].hypot(p[2]) < 0.3)
        .map(|p| p[1])
        .fold(f32::MIN, f32::max)
}

/// The probe's radius and how far below the settled top its tip is pressed (cm).
const PROBE_RADIUS: f32 = 0.5;
const DEPTH: f32 = 0.5;

/// The box of `young_kpa` settled for 150 steps: the top's sag (cm); then a vertical probe
/// lowered over 30 steps until its tip is `DEPTH` below the settled top, held for 60: the
/// tissue's force on it (N, up).
fn sag_and_force(mesh: *const tissue_mesh, young_kpa: f64) -> (f32, f32) {
    let mut body = ptr::null_mut();
    ok(
        tissue_body_new_with_material(mesh, 1.0, &material(young_kpa), &mut body),
        "body",
    );
    let top0 = top(body);
    for _ in 0..150 {
        ok(tissue_body_step(body, ptr::null_mut()), "settle");
    }
    let settled = top(body);
    let (tip, end) = ([0.0f32; 3], [0.0f32, 3.0, 0.0]);
    let pose = |y: f32| tissue_pose {
        rotation: [0.0, 0.0, 0.0, 1.0],
        translation: [0.0, y, 0.0],
    };
    let (above, pressed) = (settled + PROBE_RADIUS + 0.3, settled - DEPTH + PROBE_RADIUS);
    let mut probe = 0u32;
    ok(
        tissue_body_add_capsule(
            body,
            tip.as_ptr(),
            end.as_ptr(),
            PROBE_RADIUS,
            &pose(above),
            &mut probe,
        ),
        "probe",
    );
    for k in 1..=90 {
        let s = (k as f32 / 30.0).min(1.0);
        ok(
            tissue_tool_set_pose(body, probe, &pose(above + s * (pressed - above))),
            "pose",
        );
        ok(tissue_body_step(body, ptr::null_mut()), "press");
    }
    let mut f = [0.0f32; 3];
    ok(
        tissue_tool_force(body, probe, f.as_mut_ptr(), ptr::null_mut()),
        "force",
    );
    tissue_body_free(body);
    (top0 - settled, f[1])
}

#[test]
fn twice_the_modulus_sags_half_as_much_and_pushes_back_twice_as_hard() {
    let mesh = cube();
    let (young, stiff) = (10.0, 20.0);
    let (sag_e, force_e) = sag_and_force(mesh, young);
    let (sag_2e, force_2e) = sag_and_force(mesh, stiff);
    tissue_mesh_free(mesh);
    let (sag_ratio, force_ratio) = (sag_2e / sag_e, force_2e / force_e);
    eprintln!(
        "E = {young} kPa: sag {sag_e:.4} cm, probe force {force_e:.4} N; E = {stiff} kPa: sag \
         {sag_2e:.4} cm, probe force {force_2e:.4} N; sag ratio {sag_ratio:.3}, force ratio \
         {force_ratio:.3}"
    );
    assert!(sag_e > 0.0 && force_e > 0.0, "{sag_e} cm, {force_e} N");
    assert!(
        (0.4..0.65).contains(&sag_ratio),
        "twice E: sag × {sag_ratio}"
    );
    assert!(
        (1.6..2.4).contains(&force_ratio),
        "twice E: force × {force_ratio}"
    );
}

#[test]
fn a_bad_material_is_refused_naming_its_field() {
    let mesh = cube();
    let mut body = ptr::null_mut();
    let bad = tissue_material {
        poisson: 0.6,
        ..material(10.0)
    };
    let status = tissue_body_new_with_material(mesh, 1.0, &bad, &mut body);
    assert_eq!(status, tissue_status::TISSUE_PARAMETERS);
    assert!(body.is_null());
    let message = last_error();
    assert!(message.contains("poisson"), "{message}");
    eprintln!("ν = 0.6: {message}");
    let slow = tissue_material {
        relaxation_time: 0.0,
        ..material(10.0)
    };
    assert_eq!(
        tissue_body_new_shipped_with_material(2, &slow, &mut body),
        tissue_status::TISSUE_PARAMETERS
    );
    assert!(last_error().contains("relaxation_time"), "{}", last_error());
    let unknown = tissue_material {
        scheme: 7,
        ..material(10.0)
    };
    assert_eq!(
        tissue_body_new_with_material(mesh, 1.0, &unknown, &mut body),
        tissue_status::TISSUE_INVALID_ARGUMENT
    );
    assert!(last_error().contains("tissue_scheme"), "{}", last_error());
    // A zeroed struct is the material scheme with nothing set: refused (its first zero field
    // named), not taken for the real-time preset.
    assert_eq!(
        tissue_body_new_with_material(mesh, 1.0, &tissue_material::default(), &mut body),
        tissue_status::TISSUE_PARAMETERS
    );
    assert!(last_error().starts_with("`material->"), "{}", last_error());
    assert_eq!(
        tissue_body_new_with_material(mesh, 1.0, ptr::null(), &mut body),
        tissue_status::TISSUE_NULL_ARGUMENT
    );
    tissue_mesh_free(mesh);
}

#[test]
fn presets_and_the_material_in_force_read_back() {
    let mut skin = tissue_material::default();
    ok(
        tissue_material_preset(tissue_preset::TISSUE_PRESET_SKIN as u32, &mut skin),
        "skin",
    );
    let mut liver = tissue_material::default();
    ok(
        tissue_material_preset(tissue_preset::TISSUE_PRESET_LIVER as u32, &mut liver),
        "liver",
    );
    assert_eq!(skin.scheme, tissue_scheme::TISSUE_SCHEME_MATERIAL as u32);
    assert!(
        skin.young_kpa > 10.0 * liver.young_kpa,
        "{skin:?} {liver:?}"
    );
    assert_eq!(
        tissue_material_preset(5, &mut skin),
        tissue_status::TISSUE_INVALID_ARGUMENT
    );
    let mut appendix = tissue_material::default();
    ok(
        tissue_material_shipped(
            tissue_shipped_organ::TISSUE_ORGAN_APPENDIX as u32,
            &mut appendix,
        ),
        "appendix",
    );
    let mut bowel = tissue_material::default();
    ok(
        tissue_material_preset(tissue_preset::TISSUE_PRESET_BOWEL as u32, &mut bowel),
        "bowel",
    );
    assert_eq!(appendix, bowel);
    // Self-collision on in what every fill function gives (tissue-scenes' default), off in a
    // struct zeroed by hand.
    assert!(
        skin.self_collision && liver.self_collision && bowel.self_collision,
        "{skin:?} {liver:?} {bowel:?}"
    );
    assert!(!tissue_material::default().self_collision);

    // The material in force: the one given, and the real-time preset's.
    let mut body = ptr::null_mut();
    let given = tissue_material {
        relaxation_time: 0.25,
        ..bowel
    };
    ok(
        tissue_body_new_shipped_with_material(2, &given, &mut body),
        "appendix body",
    );
    let mut read = tissue_material::default();
    ok(tissue_body_get_material(body, &mut read), "material");
    assert_eq!(read, given);
    tissue_body_free(body);
    ok(tissue_body_new_shipped(2, &mut body), "realtime body");
    ok(tissue_body_get_material(body, &mut read), "material");
    assert_eq!(read.scheme, tissue_scheme::TISSUE_SCHEME_REALTIME as u32);
    assert_eq!((read.young_kpa, read.poisson), (0.0, 0.0));
    assert!(read.density > 0.0 && read.relaxation_time > 0.0, "{read:?}");
    tissue_body_free(body);
    // (Self-collision on, as `tissue_body_new_shipped` has it: the default.)
    assert!(read.self_collision, "{read:?}");
    // The real-time preset by its scheme in a zeroed struct: the same, self-collision off (the
    // zeroed field), and on again once the field says so.
    let realtime = tissue_material {
        scheme: tissue_scheme::TISSUE_SCHEME_REALTIME as u32,
        ..tissue_material::default()
    };
    ok(
        tissue_body_new_shipped_with_material(2, &realtime, &mut body),
        "realtime by its scheme",
    );
    let mut again = tissue_material::default();
    ok(tissue_body_get_material(body, &mut again), "material");
    assert_eq!(
        again,
        tissue_material {
            self_collision: false,
            ..read
        }
    );
    tissue_body_free(body);
    let realtime_on = tissue_material {
        self_collision: true,
        ..realtime
    };
    ok(
        tissue_body_new_shipped_with_material(2, &realtime_on, &mut body),
        "realtime by its scheme, self-collision on",
    );
    ok(tissue_body_get_material(body, &mut again), "material");
    assert_eq!(again, read);
    tissue_body_free(body);
}
