//! The closed MakeHuman body and the left arm cut from it (decimetres).

use glam::Vec3;
use tissue_mesh::TriMesh;

use crate::ops::{keep_clean, loop_raw, median_edge_raw, midpoint_raw};
use crate::scan::{boundary_points, named_point, orient_outward, read_shared};
use crate::{Scan, ScanError};

/// The closed body (decimetres, +Y up, +Z front, +X the model's left).
pub const BODY_FILE: &str = "makehuman_body_closed.obj";

/// The left arm's axis, decimetres: the upper cut's centre (below the shoulder), the elbow, and
/// the wrist (the lower cut's centre). Read off the body's cross-sections.
pub const ARM_UPPER_CUT: Vec3 = Vec3::new(2.25, 4.6, 0.08);
/// The elbow on the left arm's axis, decimetres (see [`ARM_UPPER_CUT`]).
pub const ARM_ELBOW: Vec3 = Vec3::new(3.05, 3.6, 0.05);
/// The wrist on the left arm's axis, decimetres (see [`ARM_UPPER_CUT`]).
pub const ARM_WRIST: Vec3 = Vec3::new(4.25, 2.4, 1.7);

/// Placement points on the arm: (name, what, segment 0 = upper arm / 1 = forearm, fraction
/// along the segment, side as a direction away from the axis).
const ARM_POINTS: [(&str, &str, usize, f32, [f32; 3]); 4] = [
    (
        "upper_arm_outer",
        "upper arm, outer (lateral, upper) side, near the elbow",
        0,
        0.75,
        [0.7, 0.7, 0.0],
    ),
    (
        "forearm_front",
        "forearm, middle, front (towards +z, the palm side in this pose)",
        1,
        0.45,
        [0.0, 0.0, 1.0],
    ),
    (
        "forearm_outer",
        "forearm, middle, outer (+x) side",
        1,
        0.45,
        [1.0, 0.0, 0.0],
    ),
    (
        "forearm_top",
        "forearm, middle, upper (+y) side",
        1,
        0.55,
        [0.0, 1.0, 0.0],
    ),
];

/// Placement points on the body: (name, what, target x, y, which side: +1 front / −1 back).
const BODY_POINTS: [(&str, &str, f32, f32, f32); 4] = [
    (
        "back",
        "middle of the back, on the spine, y = 4.0 dm (chest height)",
        0.0,
        4.0,
        -1.0,
    ),
    (
        "belly",
        "belly, on the midline, y = 1.5 dm (just below the navel)",
        0.0,
        1.5,
        1.0,
    ),
    (
        "thigh_left",
        "front of the left thigh (+x), middle, y = -2.0 dm",
        0.85,
        -2.0,
        1.0,
    ),
    (
        "lower_back_right",
        "lower back, right of the spine (-x), y = 2.0 dm",
        -0.5,
        2.0,
        -1.0,
    ),
];

/// The MakeHuman body as it is: decimetres, closed (no boundary loops), genus 0, 13,380
/// vertices, 26,756 triangles, outward normals. Not refined (its median edge is about 0.064 dm;
/// the arms and legs are coarser than the face and hands).
///
/// Points (each the extreme vertex, front or back, within 0.15 dm of the target's x and y; see
/// their `what`): `back`, `belly`, `thigh_left`, `lower_back_right`, all well away from the
/// armpits and the crotch.
///
/// # Errors
/// [`ScanError::Absent`] when the fixture mesh is missing; [`ScanError::Io`] when the file
/// cannot be read; [`ScanError::Unexpected`] if the file changed.
pub fn closed_body() -> Result<Scan, ScanError> {
    let body = read_shared(BODY_FILE)?;
    if !body.is_closed() || body.signed_volume()? <= 0.0 {
        return Err(ScanError::Unexpected {
            what: format!("{BODY_FILE}: expected a closed surface with outward normals"),
        });
    }
    let mut points = Vec::with_capacity(BODY_POINTS.len());
    for &(name, what, x, y, side) in &BODY_POINTS {
        let vertex = body
            .positions()
            .iter()
            .enumerate()
            .filter(|(_, p)| (p.x - x).abs() < 0.15 && (p.y - y).abs() < 0.15)
            .max_by(|a, b| (a.1.z * side).total_cmp(&(b.1.z * side)))
            .map(|(v, _)| v as u32);
        let Some(vertex) = vertex else {
            return Err(ScanError::Unexpected {
                what: format!("{BODY_FILE}: no vertex near point {name}"),
            });
        };
        points.push(named_point(&body, &[], name, what, vertex));
    }
    Ok(Scan {
        mesh: body,
        unit_name: "dm",
        cm_per_unit: 10.0,
        points,
        holes: Vec::new(),
        big_hole: None,
        truth: None,
        truth_vertex: Vec::new(),
        radius: None,
    })
}

/// The left arm cut from the body, decimetres: from about 9 cm below the shoulder (the plane
/// through [`ARM_UPPER_CUT`] across the upper arm) to the wrist (the plane through
/// [`ARM_WRIST`] across the forearm, the hand left out); the elbow is bent, the forearm
/// points forward. One open tube-like piece with two boundary loops (the cuts), refined by one
/// Loop subdivision and then midpoint subdivisions until the median edge is at most 0.03 dm,
/// giving uneven triangles of about 0.1–0.4 cm. Normals point out of the arm.
///
/// Points (see `what`): `upper_arm_outer`, `forearm_front`, `forearm_outer`, `forearm_top`, each
/// the vertex farthest from the axis in its direction within 0.05 dm of its axial position.
/// `radius` is the mean distance of the vertices from the axis (upper cut → elbow → wrist).
///
/// # Errors
/// [`ScanError::Absent`] when the fixture mesh is missing; [`ScanError::Io`] when the file
/// cannot be read; [`ScanError::Unexpected`] if the file changed.
pub fn forearm_from_body() -> Result<Scan, ScanError> {
    let body = read_shared(BODY_FILE)?;
    let positions = body.positions().to_vec();
    let mut triangles = body.triangles().to_vec();
    let inside = positions.iter().copied().sum::<Vec3>() / positions.len() as f32;
    orient_outward(&mut triangles, &positions, inside);
    let upper = (ARM_ELBOW - ARM_UPPER_CUT).normalize();
    let fore = (ARM_WRIST - ARM_ELBOW).normalize();
    let on_arm = |p: Vec3| (p - ARM_UPPER_CUT).dot(upper) > 0.0 && (p - ARM_WRIST).dot(fore) < 0.0;
    let mut keep: Vec<bool> = triangles
        .iter()
        .map(|t| t.iter().all(|&v| on_arm(positions[v as usize])))
        .collect();
    // Of the pieces between the planes, keep only the one around the elbow.
    let elbow_vertex = positions
        .iter()
        .enumerate()
        .filter(|(_, p)| p.x > 1.0)
        .min_by(|a, b| a.1.distance(ARM_ELBOW).total_cmp(&b.1.distance(ARM_ELBOW)))
        .map_or(0, |(v, _)| v as u32);
    let mut reach = vec![false; positions.len()];
    reach[elbow_vertex as usize] = true;
    // Flood over kept triangles from the elbow.
    loop {
        let mut changed = false;
        for (t, tri) in triangles.iter().enumerate() {
            if keep[t] && tri.iter().any(|&v| reach[v as usize]) {
                for &v in tri {
                    if !reach[v as usize] {
                        reach[v as usize] = true;
                        changed = true;
                    }
                }
            }
        }
        if !changed {
            break;
        }
    }
    for (t, tri) in triangles.iter().enumerate() {
        keep[t] = keep[t] && reach[tri[0] as usize];
    }
    let (mut p, mut t, _) = keep_clean(&positions, &triangles, &mut keep);
    (p, t) = loop_raw(&p, &t);
    while median_edge_raw(&p, &t) > 0.03 {
        (p, t) = midpoint_raw(&p, &t);
    }
    let mesh = TriMesh::new(p, t)?;
    let loops = mesh.topology().boundary_loops().len();
    if loops != 2 || mesh.topology().component_count() != 1 {
        return Err(ScanError::Unexpected {
            what: format!("{BODY_FILE}: the arm cut has {loops} boundary loops, expected 2"),
        });
    }
    let segments = [(ARM_UPPER_CUT, ARM_ELBOW), (ARM_ELBOW, ARM_WRIST)];
    let border = boundary_points(&mesh);
    let mut points = Vec::with_capacity(ARM_POINTS.len());
    for &(name, what, segment, along, side) in &ARM_POINTS {
        let (s0, s1) = segments[segment];
        let axis = (s1 - s0).normalize();
        let centre = s0.lerp(s1, along);
        let side = Vec3::from(side);
        let side = (side - axis * side.dot(axis)).normalize();
        let vertex = mesh
            .positions()
            .iter()
            .enumerate()
            .filter(|(_, p)| (**p - centre).dot(axis).abs() < 0.05)
            .max_by(|a, b| {
                (*a.1 - centre)
                    .dot(side)
                    .total_cmp(&(*b.1 - centre).dot(side))
            })
            .map(|(v, _)| v as u32);
        let Some(vertex) = vertex else {
            return Err(ScanError::Unexpected {
                what: format!("{BODY_FILE}: no arm vertex near point {name}"),
            });
        };
        points.push(named_point(&mesh, &border, name, what, vertex));
    }
    let radius = mesh
        .positions()
        .iter()
        .map(|&p| {
            segments
                .iter()
                .map(|&(a, b)| distance_to_segment(p, a, b))
                .fold(f32::INFINITY, f32::min)
        })
        .map(f64::from)
        .sum::<f64>()
        / mesh.vertex_count() as f64;
    Ok(Scan {
        mesh,
        unit_name: "dm",
        cm_per_unit: 10.0,
        points,
        holes: Vec::new(),
        big_hole: None,
        truth: None,
        truth_vertex: Vec::new(),
        radius: Some(radius as f32),
    })
}

/// Distance from `p` to the segment `a`–`b`.
pub(crate) fn distance_to_segment(p: Vec3, a: Vec3, b: Vec3) -> f32 {
    let ab = b - a;
    let s = ((p - a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0);
    p.distance(a + ab * s)
}
