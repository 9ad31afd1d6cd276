//! Seeded scenes shared by the tests and benches of `tissue-bvh` and `tissue-collide` (hidden from
//! the docs; not part of the supported API). One place, so the benches and the oracle tests
//! measure and check the same geometry.

use glam::{Vec3, Vec3A};
use tissue_mesh::{grid, uv_sphere, MeshError, TriMesh};

/// SplitMix64: a tiny seeded generator, so tests need no `rand` dependency.
#[derive(Debug, Clone)]
pub struct Rng(u64);

impl Rng {
    /// A generator from a seed.
    pub fn new(seed: u64) -> Rng {
        Rng(seed)
    }

    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in `[0, 1)`.
    pub fn unit(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 / (1u64 << 24) as f32
    }

    /// Uniform in `[lo, hi)`.
    pub fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.unit()
    }

    /// Uniform in the cube `[−h, h)³`.
    pub fn in_cube(&mut self, h: f32) -> Vec3A {
        Vec3A::new(self.range(-h, h), self.range(-h, h), self.range(-h, h))
    }
}

/// `count` separate triangles (3 vertices each), centres uniform in `[−extent/2, extent/2)³`,
/// corners within `size` of the centre; thin ones are redrawn so the mesh validates.
pub fn triangle_soup(
    seed: u64,
    count: usize,
    extent: f32,
    size: f32,
) -> Result<TriMesh, MeshError> {
    let mut rng = Rng::new(seed);
    let mut positions = Vec::with_capacity(3 * count);
    let mut triangles = Vec::with_capacity(count);
    while triangles.len() < count {
        let c = rng.in_cube(extent / 2.0);
        let [a, b, d] = [
            c + rng.in_cube(size),
            c + rng.in_cube(size),
            c + rng.in_cube(size),
        ];
        let doubled = (b - a).cross(d - a).length();
        let longest = (b - a).length().max((d - b).length()).max((a - d).length());
        if doubled < 0.05 * longest * longest {
            continue;
        }
        let v = positions.len() as u32;
        positions.extend([a, b, d].map(Vec3::from));
        triangles.push([v, v + 1, v + 2]);
    }
    TriMesh::new(positions, triangles)
}

/// Radius of the plane-press region: a disc of the thesis's 0.446 cm² around the plane's centre.
pub const REGION_RADIUS: f32 = 0.3768;

/// The thesis's plane-press scene (SPEC A.5) at a given plane resolution.
#[derive(Debug, Clone)]
pub struct PlanePress {
    /// Both layers in one mesh: layer 1 (the triangles of `grid(n, 1.0)` whose centroid lies
    /// within [`REGION_RADIUS`] of the centre, in z = 0) and layer 2 (a copy at z = −`depth`).
    /// Layer-1 vertices come first.
    pub region: TriMesh,
    /// Triangles in one layer (layer 2 is `triangles()[layer_triangles..]`).
    pub layer_triangles: usize,
    /// The sphere `uv_sphere(32, 31, 0.25)` (994 vertices, 1984 triangles), below the region,
    /// its top `penetration` above layer 2 (pushed into it from below).
    pub sphere: TriMesh,
    /// Distance between the layers (cm).
    pub depth: f32,
}

/// Builds [`PlanePress`] from `grid(n, 1.0)`: `n = 257` gives the thesis's largest case
/// (≈ 117 k region triangles over both layers).
pub fn plane_press(n: u32, depth: f32, penetration: f32) -> Result<PlanePress, MeshError> {
    let plane = grid(n, 1.0)?;
    let r2 = REGION_RADIUS * REGION_RADIUS;
    let selected: Vec<[u32; 3]> = plane
        .triangles()
        .iter()
        .copied()
        .filter(|t| {
            let c = t
                .iter()
                .fold(Vec3::ZERO, |s, &v| s + plane.positions()[v as usize])
                / 3.0;
            c.x * c.x + c.y * c.y <= r2
        })
        .collect();
    let mut remap = vec![u32::MAX; plane.vertex_count()];
    let mut used: Vec<u32> = selected.iter().flatten().copied().collect();
    used.sort_unstable();
    used.dedup();
    for (new, &old) in used.iter().enumerate() {
        remap[old as usize] = new as u32;
    }
    let per_layer = used.len() as u32;
    let mut positions: Vec<Vec3> = used
        .iter()
        .map(|&v| plane.positions()[v as usize])
        .collect();
    positions.extend(
        used.iter()
            .map(|&v| plane.positions()[v as usize] - Vec3::new(0.0, 0.0, depth)),
    );
    let layer1: Vec<[u32; 3]> = selected
        .iter()
        .map(|t| t.map(|v| remap[v as usize]))
        .collect();
    let mut triangles = layer1.clone();
    triangles.extend(layer1.iter().map(|t| t.map(|v| v + per_layer)));
    let region = TriMesh::new(positions, triangles)?;

    let radius = 0.25f32;
    let sphere = uv_sphere(32, 31, radius)?;
    let lift = Vec3::new(0.0, 0.0, -depth - radius + penetration);
    let moved = sphere.positions().iter().map(|&p| p + lift).collect();
    let sphere = sphere.with_positions(moved)?;
    Ok(PlanePress {
        region,
        layer_triangles: layer1.len(),
        sphere,
        depth,
    })
}

/// `Vec3` positions as the `Vec3A` the hot arrays use.
pub fn to_vec3a(positions: &[Vec3]) -> Vec<Vec3A> {
    positions.iter().map(|&p| Vec3A::from(p)).collect()
}

/// Moves every position by a uniform random offset in `[−amplitude, amplitude)³`.
pub fn jitter(positions: &mut [Vec3A], rng: &mut Rng, amplitude: f32) {
    for p in positions {
        *p += rng.in_cube(amplitude);
    }
}
