//! The geometry of a cut: walls on the blade's plane, crossed surface triangles split, rest
//! volume conserved by every split, no piece below the quality bound.
#![allow(clippy::unwrap_used)]

use glam::{Quat, Vec3};
use tissue_mesh::tet_box;
use tissue_pbd::{Material, Pose, SoftBody, ToolShape};
use tissue_surgery::{BladeSweep, Surgery, SurgeryEvent, SurgerySettings};

fn block() -> (SoftBody, Surgery) {
    let mesh = tet_box(12, 6, 6, Vec3::new(6.0, 3.0, 3.0)).unwrap();
    let body = SoftBody::new(&mesh, &Material::default()).unwrap();
    let surgery = Surgery::new(&body, SurgerySettings::default()).unwrap();
    (body, surgery)
}

#[test]
fn debug_full_cut() {
    let (mut body, mut surgery) = block();
    let blade = ToolShape::Blade {
        a: Vec3::new(0.0, 0.0, -5.0),
        b: Vec3::new(0.0, 0.0, 5.0),
        c: Vec3::new(0.0, 5.0, 0.0),
        thickness: 0.01,
    };
    for k in 0..4 {
        let from = Pose::from_translation(Vec3::new(0.3, 2.0 - 1.5 * k as f32, 0.0));
        let to = Pose::from_translation(Vec3::new(0.3, 0.5 - 1.5 * k as f32, 0.0));
        let events = surgery
            .cut(&mut body, &BladeSweep::new(&blade, &from, &to).unwrap())
            .unwrap();
        for e in &events {
            if let SurgeryEvent::CutAdvanced {
                new_nodes,
                new_tets,
                split_tets,
                snapped_nodes,
                split_triangles,
                opened_faces,
                ..
            } = e
            {
                eprintln!("step {k}: nodes {new_nodes:?} tets {new_tets:?} split {} snapped {} tris {} opened {}", split_tets.len(), snapped_nodes.len(), split_triangles.len(), opened_faces.len());
            }
        }
        surgery.validate(&body).unwrap();
    }
    let _ = Quat::IDENTITY;
}
