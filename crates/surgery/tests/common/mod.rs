//! Set-ups the cut tests share.
#![allow(dead_code)]

use glam::{Quat, Vec3};
use tissue_mesh::tet_box;
use tissue_pbd::{Material, Pose, SoftBody, ToolShape};
use tissue_surgery::{Surgery, SurgerySettings};

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
