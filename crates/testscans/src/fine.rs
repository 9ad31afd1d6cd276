//! The face scan as a finer scanner gives it: millions of triangles, far from the origin.

use glam::Vec3;
use tissue_mesh::TriMesh;

use crate::ops::{edges_of, keep_clean, mark_disc, midpoint_raw, noise_raw, vertex_normals_raw};
use crate::scan::{boundary_points, named_point};
use crate::{noisy_face_scan, PunchedHole, Scan, ScanError};

/// How many of the face scan's small holes [`fine_face_scan`] keeps.
pub const FINE_FACE_HOLES: usize = 6;

/// The noisy face of [`noisy_face_scan`] (`seed`, millimetres) as a scanner `2^subdivisions`
/// times finer would give it, placed `offset` (mm) from the origin in `f32`: what a new user
/// gets by subdividing a scan to its device's resolution, or from a scanner whose coordinates
/// are the room's.
///
/// Made from the face's noisy surface before its holes (about 166k triangles, 0.5 mm edges),
/// with only the first [`FINE_FACE_HOLES`] of its small holes punched (`holes`; no big hole,
/// no notches), moved by `offset`, then midpoint-subdivided `subdivisions` times (each × 4
/// triangles): every hole's loop has straight runs of `2^subdivisions` exactly (up to `f32`
/// rounding at the offset) collinear vertices, the case a naive hole fill makes zero-area
/// triangles from. Two subdivisions give about 2.6 million triangles (0.125 mm edges), one
/// about 660k. The noise is not refined (it stays at the 0.5 mm scale, as a scan smoothed by
/// its device). Points as the face's, moved; `truth` is `None` (not kept, to save memory).
///
/// # Errors
/// Those of [`noisy_face_scan`]; [`ScanError::Mesh`] if the offset is so large that `f32`
/// cannot tell the subdivided vertices apart.
pub fn fine_face_scan(seed: u64, subdivisions: u32, offset: Vec3) -> Result<Scan, ScanError> {
    let face = noisy_face_scan(seed)?;
    let Some(truth) = &face.truth else {
        return Err(ScanError::Unexpected {
            what: "the face scan has no truth surface".into(),
        });
    };
    let normals = vertex_normals_raw(truth.positions(), truth.triangles());
    let mut noisy = truth.positions().to_vec();
    noise_raw(&mut noisy, &normals, crate::FACE_NOISE_SIGMA_MM, seed);
    let adjacency = edges_of(truth.triangles());
    let mut remove = vec![false; truth.triangle_count()];
    let holes: Vec<PunchedHole> = face.holes.iter().take(FINE_FACE_HOLES).copied().collect();
    for h in &holes {
        mark_disc(
            &noisy,
            truth.triangles(),
            &adjacency,
            h.centre,
            0.5 * h.diameter,
            &mut remove,
        );
    }
    let mut keep: Vec<bool> = remove.iter().map(|r| !r).collect();
    let (p, t, old_vertex) = keep_clean(&noisy, truth.triangles(), &mut keep);
    let mut new_of_old = vec![u32::MAX; truth.vertex_count()];
    for (new, &old) in old_vertex.iter().enumerate() {
        new_of_old[old as usize] = new as u32;
    }
    let (mut p, mut t): (Vec<Vec3>, Vec<[u32; 3]>) = (p.iter().map(|&x| x + offset).collect(), t);
    for _ in 0..subdivisions {
        (p, t) = midpoint_raw(&p, &t);
    }
    let mesh = TriMesh::new(p, t)?;
    let border = boundary_points(&mesh);
    let mut points = Vec::with_capacity(face.points.len());
    for point in &face.points {
        let old = face.truth_vertex[point.vertex as usize];
        let vertex = new_of_old[old as usize];
        if vertex == u32::MAX {
            return Err(ScanError::Unexpected {
                what: format!("placement point {} was removed with a hole", point.name),
            });
        }
        points.push(named_point(&mesh, &border, point.name, point.what, vertex));
    }
    let moved = |h: &PunchedHole| PunchedHole {
        centre: h.centre + offset,
        diameter: h.diameter,
    };
    Ok(Scan {
        mesh,
        unit_name: "mm",
        cm_per_unit: 0.1,
        points,
        holes: holes.iter().map(moved).collect(),
        big_hole: None,
        truth: None,
        truth_vertex: Vec::new(),
        radius: None,
    })
}
