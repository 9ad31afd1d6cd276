//! Set-ups the cut tests share.
#![allow(dead_code, clippy::unwrap_used)]

use glam::{DVec3, Quat, Vec3};
use tissue_mesh::tet_box;
use tissue_pbd::{Material, Pose, SoftBody, ToolShape};
use tissue_surgery::{Surgery, SurgerySettings, MIN_RATIO};

/// A 6 × 3 × 3 cm block centred at the origin, cells of 0.5 cm.
/// `split`: geometric cuts ([`SurgerySettings::split_tets`]) or face separation only.
pub fn block(split: bool) -> (SoftBody, Surgery) {
    let mesh = tet_box(12, 6, 6, Vec3::new(6.0, 3.0, 3.0)).unwrap();
    let body = SoftBody::new(&mesh, &Material::default()).unwrap();
    let settings = SurgerySettings {
        split_tets: split,
        ..SurgerySettings::default()
    };
    let surgery = Surgery::new(&body, settings).unwrap();
    (body, surgery)
}

/// The incision blade: standing up in the plane z = 0.15 at [`incision_pose`], its lower edge
/// 1 cm below the block's top (y = 1.5).
pub fn incision_blade() -> ToolShape {
    ToolShape::Blade {
        a: Vec3::new(-0.3, 0.0, 0.0),
        b: Vec3::new(0.3, 0.0, 0.0),
        c: Vec3::new(0.0, 3.0, 0.0),
        thickness: 0.01,
    }
}

/// The incision blade's pose at `x` along the block.
pub fn incision_pose(x: f32) -> Pose {
    Pose::new(Quat::IDENTITY, Vec3::new(x, 0.5, 0.15))
}

/// A node's rest position (cm).
pub fn rest(body: &SoftBody, v: u32) -> DVec3 {
    body.rest_positions()[v as usize].as_dvec3()
}

/// A tet's radius ratio (3 × inradius / circumradius: 1 for the regular tet).
pub fn radius_ratio([a, b, c, d]: [DVec3; 4]) -> f64 {
    let (u, v, w) = (b - a, c - a, d - a);
    let six_v = u.cross(v).dot(w);
    let area = |p: DVec3, q: DVec3, r: DVec3| 0.5 * (q - p).cross(r - p).length();
    let s = area(a, b, c) + area(a, b, d) + area(a, c, d) + area(b, c, d);
    let o = (u.length_squared() * v.cross(w)
        + v.length_squared() * w.cross(u)
        + w.length_squared() * u.cross(v))
        / (2.0 * six_v);
    3.0 * (0.5 * six_v / s) / o.length()
}

/// The quality bound holds for every tet in rest space.
pub fn check_quality(body: &SoftBody, surgery: &Surgery) {
    let (volume, ratio) = surgery.quality_bound();
    let mut worst = f64::INFINITY;
    for (t, tet) in body.tets().iter().enumerate() {
        assert!(body.tet_rest_volumes()[t] >= volume, "tet {t}");
        worst = worst.min(radius_ratio(tet.map(|v| rest(body, v))));
    }
    assert!(worst >= ratio.min(MIN_RATIO) * 0.999, "worst ratio {worst}");
}
