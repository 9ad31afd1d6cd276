//! Ready-made systems for benches and tests (hidden from the docs: not a stable API).
//!
//! [`two_layer_region`] is the thesis's plane-press region (SPEC A.5): the vertices of an `n`×`n`
//! grid of a 1 cm plane within 0.3845 cm of its centre (about 46% of them, as in the thesis's
//! 3922 of 2 × 4225), two layers 0.05 cm apart with their particles interleaved (region vertex
//! `r` is particle `2r` in layer 1 and `2r + 1` in layer 2, so neighbours stay close in memory),
//! Van Gelder springs on both layers' edges, interlayer springs (one vertical per vertex and the
//! two diagonals of each edge's side quad), zero-length anchors on layer 2, and the region
//! boundary fixed.

use glam::Vec3;
use tissue_mesh::{grid, TriMesh};

use crate::{
    masses_from_triangles, springs_from_triangles, Anchor, MassSpringSystem, MssError, Particles,
    SheetMaterial, Spring,
};

/// Radius of the selected disc on the 1 cm plane (cm).
pub const REGION_RADIUS: f32 = 0.3845;
/// Distance between the layers (cm).
pub const LAYER_DEPTH: f32 = 0.05;

/// The region of an `n`×`n` plane of side 1 cm: vertices within [`REGION_RADIUS`] of the centre
/// and the triangles among them, vertices in the plane's (row-major) order.
pub fn region(n: u32) -> Result<TriMesh, MssError> {
    let plane = grid(n, 1.0)?;
    let inside: Vec<bool> = plane
        .positions()
        .iter()
        .map(|p| p.truncate().length() <= REGION_RADIUS)
        .collect();
    let mut index = vec![u32::MAX; plane.vertex_count()];
    let mut positions = Vec::new();
    for (v, p) in plane.positions().iter().enumerate() {
        if inside[v] {
            index[v] = positions.len() as u32;
            positions.push(*p);
        }
    }
    let triangles: Vec<[u32; 3]> = plane
        .triangles()
        .iter()
        .filter(|t| t.iter().all(|&v| inside[v as usize]))
        .map(|t| t.map(|v| index[v as usize]))
        .collect();
    // Vertices inside whose triangles all reach outside would be unreferenced: drop them.
    let mut used = vec![false; positions.len()];
    for t in &triangles {
        for &v in t {
            used[v as usize] = true;
        }
    }
    let mut renumber = vec![u32::MAX; positions.len()];
    let mut kept = Vec::new();
    for (v, p) in positions.iter().enumerate() {
        if used[v] {
            renumber[v] = kept.len() as u32;
            kept.push(*p);
        }
    }
    let triangles = triangles
        .iter()
        .map(|t| t.map(|v| renumber[v as usize]))
        .collect();
    Ok(TriMesh::new(kept, triangles)?)
}

/// The thesis's two-layer region of an `n`×`n` plane (see the module doc), with the skin material
/// used in tests (E = 2·10⁵ g/(cm·s²), ν = 0.3, t = 0.2 cm, density 1.1 g/cm³).
pub fn two_layer_region(n: u32) -> Result<MassSpringSystem, MssError> {
    let layer = region(n)?;
    let v = layer.vertex_count();
    let material = SheetMaterial {
        young: 2e5,
        poisson: 0.3,
        thickness: 0.2,
    };
    let layer_mass = masses_from_triangles(&layer, layer.area() * 0.2 * 1.1)?;
    let mut positions = Vec::with_capacity(2 * v);
    let mut masses = Vec::with_capacity(2 * v);
    for (p, &m) in layer.positions().iter().zip(&layer_mass) {
        positions.push(*p);
        positions.push(*p - Vec3::new(0.0, 0.0, LAYER_DEPTH));
        masses.push(m);
        masses.push(m);
    }
    let mut particles = Particles::new(&positions, &masses)?;
    for l in layer.topology().boundary_loops() {
        for &r in l {
            particles.fix(2 * r)?;
            particles.fix(2 * r + 1)?;
        }
    }
    let edge_springs = springs_from_triangles(&layer, &material, 0)?;
    let mut springs = Vec::with_capacity(5 * edge_springs.len() + v);
    let vertical_k = (material.young * material.thickness) as f32;
    for s in &edge_springs {
        let (a, b) = (s.a, s.b);
        springs.push(Spring::new(2 * a, 2 * b, s.rest, s.k));
        springs.push(Spring::new(2 * a + 1, 2 * b + 1, s.rest, s.k));
        let cross = (s.rest * s.rest + LAYER_DEPTH * LAYER_DEPTH).sqrt();
        springs.push(Spring::new(2 * a, 2 * b + 1, cross, 0.5 * s.k));
        springs.push(Spring::new(2 * b, 2 * a + 1, cross, 0.5 * s.k));
    }
    for r in 0..v as u32 {
        springs.push(Spring::new(2 * r, 2 * r + 1, LAYER_DEPTH, vertical_k));
    }
    let mut system = MassSpringSystem::new(particles, springs)?;
    let anchors: Vec<Anchor> = (0..v as u32)
        .map(|r| Anchor {
            particle: 2 * r + 1,
            k: 0.1 * vertical_k,
            target: positions[2 * r as usize + 1],
        })
        .collect();
    system.add_anchors(&anchors)?;
    system.set_damping(0.99)?;
    Ok(system)
}
