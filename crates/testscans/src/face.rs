//! The noisy, holed photogrammetric face scan (millimetres), from the MakeHuman head.

use glam::{Vec2, Vec3};
use tissue_mesh::TriMesh;

use crate::ops::{
    edges_of, keep_clean, loop_raw, mark_disc, midpoint_raw, noise_raw, vertex_normals_raw,
};
use crate::scan::{
    boundary_points, named_point, nearest_distance, orient_outward, read_shared, PunchedHole,
};
use crate::{Rng, Scan, ScanError};

/// The head patch the face is cut from (decimetres, +Y up, +Z front).
pub const HEAD_FILE: &str = "makehuman_head_open.obj";
/// The face is the largest connected piece of the head's triangles whose three vertices lie in
/// front of this plane, `z > FACE_CUT_Z_MM` (after scaling to millimetres).
pub const FACE_CUT_Z_MM: f32 = 138.0;
/// Standard deviation of the noise along the normals, in millimetres.
pub const FACE_NOISE_SIGMA_MM: f64 = 0.2;
/// Diameter of the one large hole, in millimetres.
pub const FACE_BIG_HOLE_MM: f32 = 30.0;
/// Smallest distance from the outer border to a hole's centre, in millimetres.
pub const FACE_HOLE_BORDER_MM: f32 = 15.0;

/// Placement targets in the head's (x, y), millimetres, and a search radius: each point is the
/// scan's vertex farthest from the border among those within the radius of the target in that
/// projection (the nearest one when the radius is 0; the patch faces +z, so the projection is
/// one-to-one there).
const FACE_POINTS: [(&str, &str, [f32; 2], f32); 5] = [
    (
        "forehead",
        "forehead, on the midline about 4 cm above the eyes",
        [0.0, 770.0],
        0.0,
    ),
    (
        "cheek_left",
        "the model's left inner cheek (+x), beside the nose wing: of the vertices within 12 mm of (24, 675) in (x, y), the one farthest from the border",
        [24.0, 675.0],
        12.0,
    ),
    (
        "cheek_right",
        "the model's right inner cheek (-x), beside the nose wing: of the vertices within 12 mm of (-24, 675) in (x, y), the one farthest from the border",
        [-24.0, 675.0],
        12.0,
    ),
    (
        "chin",
        "chin, on the midline below the lower lip",
        [0.0, 640.0],
        0.0,
    ),
    (
        "nose_bridge",
        "bridge of the nose, between the eyes",
        [0.0, 730.0],
        0.0,
    ),
];

/// A realistic photogrammetric face scan in millimetres, deterministic in `seed`.
///
/// Made from [`HEAD_FILE`] (decimetres) scaled by 100: the front of the face (`z >`
/// [`FACE_CUT_Z_MM`]; the mouth's opening, which lies behind that plane, is capped), one
/// connected disc of about 196 cm² from the chin to the forehead with both eyes, the nose, the
/// mouth and the inner cheeks. It is refined by two Loop subdivisions and one midpoint
/// subdivision to about 0.5 mm edges (about 150k triangles), moved along the normals by
/// Gaussian noise of σ = [`FACE_NOISE_SIGMA_MM`], then holed. Each hole removes the triangles
/// whose centroid is within half its diameter of its centre and that connect to it through such
/// triangles. There is one hole of [`FACE_BIG_HOLE_MM`] at the spot farthest from the border and
/// from the placement points (`big_hole`, the same for every seed), and 10–20 seeded holes of
/// 2–15 mm (`holes`; centres at least [`FACE_HOLE_BORDER_MM`] and half a diameter plus 5 mm
/// inside the border, 4 mm apart edge to edge, and half a diameter plus 15 mm from every
/// placement point); 3–5 notches of 2–5 mm are cut into the outer border. The surface is one
/// component whose boundary loops are the outer border and one per hole; normals point out of
/// the head.
///
/// `truth` is the refined surface before noise and holes, and `truth_vertex` maps each scan
/// vertex to it. Points: `forehead`, `cheek_left`, `cheek_right`, `chin`, `nose_bridge` (see
/// their `what`); the patch is only about 8 cm wide, so they are 1.5–1.7 cm from the nearest
/// boundary (outer border or hole), not 6 cm.
///
/// # Errors
/// [`ScanError::Absent`] when the fixture mesh is missing;
/// [`ScanError::Io`] when the file cannot be read; the others only if the file changed.
pub fn noisy_face_scan(seed: u64) -> Result<Scan, ScanError> {
    let head = read_shared(HEAD_FILE)?;
    let positions: Vec<Vec3> = head.positions().iter().map(|p| *p * 100.0).collect();
    let mut triangles = head.triangles().to_vec();
    let inside = positions.iter().copied().sum::<Vec3>() / positions.len() as f32;
    orient_outward(&mut triangles, &positions, inside);

    let mut keep: Vec<bool> = triangles
        .iter()
        .map(|t| t.iter().all(|&v| positions[v as usize].z > FACE_CUT_Z_MM))
        .collect();
    let (p, mut t, _) = keep_clean(&positions, &triangles, &mut keep);
    // The mouth's opening lies behind the cut: close every inner loop with a flat cap.
    let loops = TriMesh::new(p.clone(), t.clone())?
        .topology()
        .boundary_loops()
        .to_vec();
    let outer = (0..loops.len()).max_by_key(|&l| loops[l].len());
    for (l, lp) in loops.iter().enumerate() {
        if Some(l) != outer {
            cap_xy(&p, lp, &mut t);
        }
    }
    if t.len() < 1000 {
        return Err(ScanError::Unexpected {
            what: format!(
                "{HEAD_FILE}: only {} face triangles in front of z = {FACE_CUT_Z_MM} mm",
                t.len()
            ),
        });
    }
    let (p, t) = loop_raw(&p, &t);
    let (p, t) = loop_raw(&p, &t);
    let (p, t) = midpoint_raw(&p, &t);
    let truth = TriMesh::new(p, t)?;

    let normals = vertex_normals_raw(truth.positions(), truth.triangles());
    let mut noisy = truth.positions().to_vec();
    noise_raw(&mut noisy, &normals, FACE_NOISE_SIGMA_MM, seed);

    // Placement points (on the truth's vertices; the same vertices in the scan).
    let border = boundary_points(&truth);
    let point_vertices: Vec<u32> = FACE_POINTS
        .iter()
        .map(|&(_, _, [x, y], search)| {
            let target = Vec2::new(x, y);
            if search <= 0.0 {
                return nearest_in_xy(&truth, target);
            }
            let p = truth.positions();
            (0..p.len())
                .filter(|&v| Vec2::new(p[v].x, p[v].y).distance(target) <= search)
                .map(|v| (nearest_distance(&border, p[v]), v as u32))
                .max_by(|a, b| a.0.total_cmp(&b.0))
                .map_or_else(|| nearest_in_xy(&truth, target), |(_, v)| v)
        })
        .collect();
    let point_positions: Vec<Vec3> = point_vertices.iter().map(|&v| noisy[v as usize]).collect();

    // Candidate hole centres: every 8th referenced vertex, with its distance to the border.
    let candidates: Vec<(Vec3, f32)> = (0..noisy.len())
        .step_by(8)
        .map(|v| (noisy[v], nearest_distance(&border, noisy[v])))
        .collect();
    let mut remove = vec![false; truth.triangle_count()];
    let adjacency = edges_of(truth.triangles());

    let big_radius = 0.5 * FACE_BIG_HOLE_MM;
    let big = candidates
        .iter()
        .filter(|(_, b)| *b >= FACE_HOLE_BORDER_MM.max(big_radius + 5.0))
        .map(|&(c, b)| {
            (
                c,
                b.min(nearest_distance(&point_positions, c) - big_radius - 15.0),
            )
        })
        .max_by(|x, y| x.1.total_cmp(&y.1))
        .map(|(c, _)| PunchedHole {
            centre: c,
            diameter: FACE_BIG_HOLE_MM,
        });
    let Some(big) = big else {
        return Err(ScanError::Unexpected {
            what: format!("{HEAD_FILE}: no room for the {FACE_BIG_HOLE_MM} mm hole"),
        });
    };
    mark_disc(
        &noisy,
        truth.triangles(),
        &adjacency,
        big.centre,
        big_radius,
        &mut remove,
    );

    let mut rng = Rng::new(seed ^ 0x5CA7_F00D);
    let wanted = 10 + rng.below(11);
    let mut holes: Vec<PunchedHole> = Vec::with_capacity(wanted);
    for _ in 0..20_000 {
        if holes.len() == wanted {
            break;
        }
        let (centre, border_distance) = candidates[rng.below(candidates.len())];
        let diameter = rng.range(2.0, 15.0) as f32;
        let r = 0.5 * diameter;
        let clear_of_holes = holes
            .iter()
            .chain(std::iter::once(&big))
            .all(|h| h.centre.distance(centre) >= r + 0.5 * h.diameter + 4.0);
        if border_distance >= FACE_HOLE_BORDER_MM.max(r + 5.0)
            && clear_of_holes
            && nearest_distance(&point_positions, centre) >= r + 15.0
        {
            let marked = mark_disc(
                &noisy,
                truth.triangles(),
                &adjacency,
                centre,
                r,
                &mut remove,
            );
            if marked > 0 {
                holes.push(PunchedHole { centre, diameter });
            }
        }
    }
    // Notches: small bites out of the outer border.
    let notches = 3 + rng.below(3);
    let far_border: Vec<Vec3> = border
        .iter()
        .copied()
        .filter(|&b| nearest_distance(&point_positions, b) >= 20.0)
        .collect();
    for _ in 0..notches {
        if far_border.is_empty() {
            break;
        }
        let at = far_border[rng.below(far_border.len())];
        let radius = rng.range(1.0, 2.5) as f32;
        mark_disc(
            &noisy,
            truth.triangles(),
            &adjacency,
            at,
            radius,
            &mut remove,
        );
    }

    let mut keep: Vec<bool> = remove.iter().map(|r| !r).collect();
    let (p, t, truth_vertex) = keep_clean(&noisy, truth.triangles(), &mut keep);
    let mesh = TriMesh::new(p, t)?;
    let mut new_of_old = vec![u32::MAX; truth.vertex_count()];
    for (new, &old) in truth_vertex.iter().enumerate() {
        new_of_old[old as usize] = new as u32;
    }
    let final_border = boundary_points(&mesh);
    let mut points = Vec::with_capacity(FACE_POINTS.len());
    for (&(name, what, _, _), &old) in FACE_POINTS.iter().zip(&point_vertices) {
        let vertex = new_of_old[old as usize];
        if vertex == u32::MAX {
            return Err(ScanError::Unexpected {
                what: format!("placement point {name} was removed with a hole"),
            });
        }
        points.push(named_point(&mesh, &final_border, name, what, vertex));
    }
    Ok(Scan {
        mesh,
        unit_name: "mm",
        cm_per_unit: 0.1,
        points,
        holes,
        big_hole: Some(big),
        truth: Some(truth),
        truth_vertex,
        radius: None,
    })
}

/// Closes a hole's boundary loop by ear clipping in the (x, y) projection (the face looks to
/// +z): the loop runs clockwise seen from +z, so its reverse is triangulated counter-clockwise,
/// each time clipping the ear whose smallest angle is largest.
fn cap_xy(positions: &[Vec3], boundary: &[u32], out: &mut Vec<[u32; 3]>) {
    let mut poly: Vec<u32> = boundary.iter().rev().copied().collect();
    let xy = |v: u32| {
        let p = positions[v as usize];
        Vec2::new(p.x, p.y)
    };
    let cross = |a: Vec2, b: Vec2, c: Vec2| (b - a).perp_dot(c - a);
    while poly.len() > 3 {
        let n = poly.len();
        let mut best: Option<(f32, usize)> = None;
        for i in 0..n {
            let (a, b, c) = (poly[(i + n - 1) % n], poly[i], poly[(i + 1) % n]);
            let (pa, pb, pc) = (xy(a), xy(b), xy(c));
            if cross(pa, pb, pc) <= 0.0 {
                continue;
            }
            let inside = poly.iter().any(|&v| {
                let q = xy(v);
                v != a
                    && v != b
                    && v != c
                    && cross(pa, pb, q) >= 0.0
                    && cross(pb, pc, q) >= 0.0
                    && cross(pc, pa, q) >= 0.0
            });
            if inside {
                continue;
            }
            let angle = (pb - pa)
                .angle_to(pc - pa)
                .abs()
                .min((pc - pb).angle_to(pa - pb).abs())
                .min((pa - pc).angle_to(pb - pc).abs());
            if best.is_none_or(|(x, _)| angle > x) {
                best = Some((angle, i));
            }
        }
        let Some((_, i)) = best else {
            return;
        };
        out.push([poly[(i + n - 1) % n], poly[i], poly[(i + 1) % n]]);
        poly.remove(i);
    }
    if let [a, b, c] = poly[..] {
        out.push([a, b, c]);
    }
}

/// The referenced vertex nearest to `target` in the (x, y) projection.
fn nearest_in_xy(mesh: &TriMesh, target: Vec2) -> u32 {
    let mut best = (f32::INFINITY, 0u32);
    for tri in mesh.triangles() {
        for &v in tri {
            let p = mesh.positions()[v as usize];
            let d = Vec2::new(p.x, p.y).distance_squared(target);
            if d < best.0 {
                best = (d, v);
            }
        }
    }
    best.1
}
