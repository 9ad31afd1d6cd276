//! Checks shared by the integration tests.
#![allow(dead_code, clippy::unwrap_used)]

use glam::{Vec3, Vec3A};
use tissue_bvh::{BuildOptions, Bvh, BvhWorkspace, Triangles};
use tissue_mesh::TriMesh;

/// Distances and orientation of `out` against the surface `input`.
pub struct Fit {
    /// Largest distance of a boundary vertex of `out` from `input`'s boundary polylines.
    pub boundary_max: f64,
    /// Largest distance of an interior vertex of `out` from `input`'s triangles.
    pub interior_max: f64,
    /// Smallest dot of an output triangle's normal with the input normal at its closest point.
    pub min_normal_dot: f64,
    /// Fraction of output triangles whose normal has a positive dot with the input's there.
    pub agreeing: f64,
}

pub fn closest_on_segment(p: Vec3, a: Vec3, b: Vec3) -> Vec3 {
    let d = b - a;
    let t = ((p - a).dot(d) / d.length_squared().max(1e-30)).clamp(0.0, 1.0);
    a + d * t
}

#[allow(clippy::needless_range_loop)] // t indexes the corners and the normals
pub fn fit(input: &TriMesh, out: &TriMesh) -> Fit {
    let pos: Vec<Vec3A> = input.positions().iter().map(|&p| p.into()).collect();
    let tris = Triangles::from_mesh(input, &pos).unwrap();
    let bvh = Bvh::build(&tris, &BuildOptions::default()).unwrap();
    let mut ws = BvhWorkspace::new();
    let normals = input.triangle_normals();
    let mut segs = Vec::new();
    for l in input.topology().boundary_loops() {
        for i in 0..l.len() {
            segs.push((
                input.positions()[l[i] as usize],
                input.positions()[l[(i + 1) % l.len()] as usize],
            ));
        }
    }
    let boundary = out.topology().boundary_vertex_mask(out.vertex_count());
    let (mut boundary_max, mut interior_max) = (0.0f64, 0.0f64);
    for (v, &p) in out.positions().iter().enumerate() {
        if boundary[v] {
            let d = segs
                .iter()
                .map(|&(a, b)| (closest_on_segment(p, a, b) - p).length())
                .fold(f32::INFINITY, f32::min);
            boundary_max = boundary_max.max(f64::from(d));
        } else {
            let hit = bvh
                .closest_point(&tris, p.into(), f32::INFINITY, &mut ws)
                .unwrap();
            interior_max = interior_max.max(f64::from(hit.distance));
        }
    }
    let out_normals = out.triangle_normals();
    let mut min_dot = 1.0f64;
    let mut agree = 0usize;
    for t in 0..out.triangle_count() {
        let [a, b, c] = out.corners(t);
        let g = (a + b + c) / 3.0;
        let hit = bvh
            .closest_point(&tris, g.into(), f32::INFINITY, &mut ws)
            .unwrap();
        let d = f64::from(out_normals[t].dot(normals[hit.primitive as usize]));
        min_dot = min_dot.min(d);
        agree += usize::from(d > 0.0);
    }
    Fit {
        boundary_max,
        interior_max,
        min_normal_dot: min_dot,
        agreeing: agree as f64 / out.triangle_count() as f64,
    }
}

/// Same components, boundary loops and Euler characteristic.
pub fn assert_same_topology(input: &TriMesh, out: &TriMesh) {
    assert_eq!(
        out.topology().component_count(),
        input.topology().component_count(),
        "components"
    );
    assert_eq!(
        out.topology().boundary_loops().len(),
        input.topology().boundary_loops().len(),
        "boundary loops"
    );
    assert_eq!(
        out.euler_characteristic(),
        input.euler_characteristic(),
        "Euler characteristic"
    );
}

/// Reads the `v` and `f` lines of an OBJ (polygons fanned; `f a/b/c` forms accepted), scaled.
pub fn read_obj(path: &str, scale: f32) -> Option<TriMesh> {
    let text = std::fs::read_to_string(path).ok()?;
    let mut positions = Vec::new();
    let mut triangles = Vec::new();
    for line in text.lines() {
        let mut it = line.split_whitespace();
        match it.next() {
            Some("v") => {
                let c: Vec<f32> = it.take(3).map(|x| x.parse().unwrap()).collect();
                positions.push(Vec3::new(c[0], c[1], c[2]) * scale);
            }
            Some("f") => {
                let idx: Vec<u32> = it
                    .map(|x| x.split('/').next().unwrap().parse::<u32>().unwrap() - 1)
                    .collect();
                for i in 1..idx.len() - 1 {
                    triangles.push([idx[0], idx[i], idx[i + 1]]);
                }
            }
            _ => {}
        }
    }
    Some(TriMesh::new(positions, triangles).unwrap())
}
