//! The tapered tube (a limb stand-in, centimetres), generated.

use std::f64::consts::{PI, TAU};

use glam::Vec3;
use tissue_mesh::TriMesh;

use crate::scan::{boundary_points, named_point};
use crate::{Rng, Scan, ScanError};

/// Length of the tube along +y, cm.
pub const TUBE_LENGTH_CM: f32 = 25.0;
/// Radius at y = 0, cm.
pub const TUBE_RADIUS_START_CM: f32 = 2.5;
/// Radius at y = [`TUBE_LENGTH_CM`], cm.
pub const TUBE_RADIUS_END_CM: f32 = 4.0;

/// Placement points: (name, what, y in cm, angle about +y from +x towards +z, degrees).
const TUBE_POINTS: [(&str, &str, f64, f64); 6] = [
    ("y8_front", "y = 8.5 cm, front (+z)", 8.5, 90.0),
    ("y8_back", "y = 8.5 cm, back (-z)", 8.5, 270.0),
    ("y12_side", "y = 12.5 cm, side (+x)", 12.5, 0.0),
    (
        "y12_other_side",
        "y = 12.5 cm, other side (-x)",
        12.5,
        180.0,
    ),
    ("y16_front", "y = 16.5 cm, front (+z)", 16.5, 90.0),
    ("y16_oblique", "y = 16.5 cm, 210° from +x", 16.5, 210.0),
];

fn radius_at(y: f64) -> f64 {
    let (r0, r1) = (
        f64::from(TUBE_RADIUS_START_CM),
        f64::from(TUBE_RADIUS_END_CM),
    );
    r0 + (r1 - r0) * y / f64::from(TUBE_LENGTH_CM)
}

/// An open tapered tube in centimetres, deterministic in `seed`: axis along +y from 0 to
/// [`TUBE_LENGTH_CM`], radius growing linearly from [`TUBE_RADIUS_START_CM`] to
/// [`TUBE_RADIUS_END_CM`], outward normals, two boundary loops (the ends, at y = 0 and y = 25).
///
/// Triangles are uneven, 0.1–0.4 cm: the wanted edge length follows a seeded wave along the tube
/// (wavelength 4–8 cm) with ±10 % jitter per ring, clamped to 0.1–0.4 cm; rings are spaced
/// 0.85–1.15 × 0.87 of it, each ring has its own segment count and rotation, every vertex is
/// jittered by ±20 % of a segment around the ring, and neighbouring rings are zipped in angle
/// order. Points: at y = 8.5, 12.5 and 16.5 cm (8.5 cm or more from both ends), on several sides
/// (names and `what` say where). `radius` is the mean radius, 3.25 cm.
///
/// # Errors
/// Only [`ScanError::Mesh`], which a valid generator never returns.
pub fn tapered_tube(seed: u64) -> Result<Scan, ScanError> {
    let mut rng = Rng::new(seed ^ 0x7B0E_0001);
    let wavelength = rng.range(4.0, 8.0);
    let phase = rng.range(0.0, TAU);
    let size_at = |y: f64, rng: &mut Rng| {
        let s = 0.28 + 0.1 * (TAU * y / wavelength + phase).sin();
        (s * rng.range(0.9, 1.1)).clamp(0.1, 0.4)
    };
    // Ring heights and sizes.
    let mut rings: Vec<(f64, f64)> = Vec::new();
    let mut y = 0.0;
    loop {
        let s = size_at(y, &mut rng);
        rings.push((y, s));
        let h = (s * rng.range(0.5, 0.9)).clamp(0.1, 0.4);
        y += h;
        if y >= f64::from(TUBE_LENGTH_CM) {
            break;
        }
    }
    // Stretch so that the last ring is at the end exactly.
    let last = rings.last().map_or(1.0, |r| r.0);
    let stretch = f64::from(TUBE_LENGTH_CM) / last;
    let mut positions: Vec<Vec3> = Vec::new();
    let mut ring_angles: Vec<Vec<f64>> = Vec::with_capacity(rings.len());
    let mut ring_start: Vec<u32> = Vec::with_capacity(rings.len());
    for &(y, s) in &rings {
        let y = y * stretch;
        let r = radius_at(y);
        let n = ((TAU * r / s).round() as usize).max(8);
        let rotation = rng.range(0.0, TAU);
        ring_start.push(positions.len() as u32);
        let mut angles = Vec::with_capacity(n);
        for j in 0..n {
            let a = rotation + TAU * (j as f64 + rng.range(-0.2, 0.2)) / n as f64;
            angles.push(a);
            positions.push(Vec3::new(
                (r * a.cos()) as f32,
                y as f32,
                (r * a.sin()) as f32,
            ));
        }
        ring_angles.push(angles);
    }
    let mut triangles: Vec<[u32; 3]> = Vec::new();
    for i in 0..rings.len() - 1 {
        zip_rings(
            &ring_angles[i],
            ring_start[i],
            &ring_angles[i + 1],
            ring_start[i + 1],
            &mut triangles,
        );
    }
    let mesh = TriMesh::new(positions, triangles)?;
    let border = boundary_points(&mesh);
    let points = TUBE_POINTS
        .iter()
        .map(|&(name, what, y, degrees)| {
            let a = degrees.to_radians();
            let dir = Vec3::new(a.cos() as f32, 0.0, a.sin() as f32);
            let vertex = nearest_on_side(&mesh, y as f32, dir);
            named_point(&mesh, &border, name, what, vertex)
        })
        .collect();
    Ok(Scan {
        mesh,
        unit_name: "cm",
        cm_per_unit: 1.0,
        points,
        holes: Vec::new(),
        big_hole: None,
        truth: None,
        truth_vertex: Vec::new(),
        radius: Some(0.5 * (TUBE_RADIUS_START_CM + TUBE_RADIUS_END_CM)),
    })
}

/// The vertex nearest to the tube's surface point at height `y` in direction `dir`.
fn nearest_on_side(mesh: &TriMesh, y: f32, dir: Vec3) -> u32 {
    let target = Vec3::new(0.0, y, 0.0) + dir * radius_at(f64::from(y)) as f32;
    let mut best = (f32::INFINITY, 0u32);
    for (v, p) in mesh.positions().iter().enumerate() {
        let d = p.distance_squared(target);
        if d < best.0 {
            best = (d, v as u32);
        }
    }
    best.1
}

/// Angle `x` brought into `[base, base + 2π)`.
fn wrap_from(x: f64, base: f64) -> f64 {
    base + (x - base).rem_euclid(TAU)
}

/// Triangulates the band between ring `a` (lower y) and ring `b`, merging their vertices in angle
/// order; triangles are wound so that normals point away from the axis.
fn zip_rings(a: &[f64], a0: u32, b: &[f64], b0: u32, out: &mut Vec<[u32; 3]>) {
    let (na, nb) = (a.len(), b.len());
    let base = a[0];
    // The b vertex nearest in angle to a[0] starts the merge.
    let start = (0..nb)
        .min_by(|&i, &j| {
            let di = (wrap_from(b[i], base - PI) - base).abs();
            let dj = (wrap_from(b[j], base - PI) - base).abs();
            di.total_cmp(&dj)
        })
        .unwrap_or(0);
    // Unwrapped, increasing angles; a[na] = a[0] + 2π, likewise for b.
    let ua: Vec<f64> = (0..=na)
        .map(|k| wrap_from(a[k % na], base) + if k == na { TAU } else { 0.0 })
        .collect();
    let b_first = wrap_from(b[start], base - PI);
    let mut ub = vec![b_first];
    for k in 1..=nb {
        let prev = ub[k - 1];
        ub.push(wrap_from(b[(start + k) % nb], prev));
    }
    let (mut i, mut j) = (0usize, 0usize);
    while i < na || j < nb {
        let va = a0 + (i % na) as u32;
        let vb = b0 + ((start + j) % nb) as u32;
        let advance_a = j == nb || (i < na && ua[i + 1] - ub[j] < ub[j + 1] - ua[i]);
        if advance_a {
            out.push([va, vb, a0 + ((i + 1) % na) as u32]);
            i += 1;
        } else {
            out.push([va, vb, b0 + ((start + j + 1) % nb) as u32]);
            j += 1;
        }
    }
}
