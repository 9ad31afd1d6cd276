//! The reference surface vertices are projected back onto: the input's triangles (closest point),
//! its boundary polylines, and optionally a moving-least-squares smoothing of it.

use glam::{DVec3, Vec3, Vec3A};
use tissue_bvh::{Aabb, BuildOptions, Bvh, BvhWorkspace, ClosestPoint, Primitives, Triangles};
use tissue_mesh::TriMesh;

use crate::RemeshError;

/// Boundary segments of the input as primitives of a hierarchy.
struct Segments<'a> {
    pos: &'a [Vec3A],
    segs: &'a [[u32; 2]],
}

impl Primitives for Segments<'_> {
    fn primitive_count(&self) -> usize {
        self.segs.len()
    }

    fn bounds(&self, i: u32) -> Aabb {
        let [a, b] = self.segs[i as usize];
        Aabb::from_segment(self.pos[a as usize], self.pos[b as usize])
    }
}

impl ClosestPoint for Segments<'_> {
    fn closest_point(&self, i: u32, p: Vec3A) -> Vec3A {
        let [a, b] = self.segs[i as usize];
        closest_on_segment(p, self.pos[a as usize], self.pos[b as usize])
    }
}

/// The point of segment `ab` closest to `p`.
pub(crate) fn closest_on_segment(p: Vec3A, a: Vec3A, b: Vec3A) -> Vec3A {
    let d = b - a;
    let len2 = d.length_squared();
    let t = if len2 > 0.0 {
        ((p - a).dot(d) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    a + d * t
}

/// The moving-least-squares data: the input's vertices as point boxes, their normals.
struct Mls {
    radius: f32,
    points: Vec<Aabb>,
    normals: Vec<Vec3A>,
    bvh: Bvh,
}

/// The input surface prepared for projection queries.
pub(crate) struct Reference<'a> {
    mesh: &'a TriMesh,
    pos: Vec<Vec3A>,
    bvh: Bvh,
    segs: Vec<[u32; 2]>,
    seg_pos: Vec<Vec3A>,
    seg_bvh: Option<Bvh>,
    mls: Option<Mls>,
    ws: BvhWorkspace,
    hits: Vec<u32>,
}

fn hierarchy(source: tissue_bvh::BvhError) -> RemeshError {
    RemeshError::Hierarchy { source }
}

impl<'a> Reference<'a> {
    /// Indexes the triangles and boundary of `mesh`; with `smoothing_radius`, its vertices too.
    pub fn new(mesh: &'a TriMesh, smoothing_radius: Option<f64>) -> Result<Self, RemeshError> {
        let _span = tracing::debug_span!("reference_build").entered();
        let pos: Vec<Vec3A> = mesh.positions().iter().map(|&p| p.into()).collect();
        let options = BuildOptions::default();
        let bvh = Bvh::build(
            &Triangles::from_mesh(mesh, &pos).map_err(hierarchy)?,
            &options,
        )
        .map_err(hierarchy)?;
        let mut segs = Vec::new();
        for l in mesh.topology().boundary_loops() {
            for i in 0..l.len() {
                segs.push([l[i], l[(i + 1) % l.len()]]);
            }
        }
        // With smoothing, the outline is smoothed too (Gaussian along the arc length, σ = r/3),
        // so that boundary vertices lose the scan's noise like interior ones.
        let seg_pos = match smoothing_radius {
            Some(r) => smoothed_outline(mesh, &pos, r),
            None => pos.clone(),
        };
        let seg_bvh = if segs.is_empty() {
            None
        } else {
            Some(
                Bvh::build(
                    &Segments {
                        pos: &seg_pos,
                        segs: &segs,
                    },
                    &options,
                )
                .map_err(hierarchy)?,
            )
        };
        let mls = match smoothing_radius {
            None => None,
            Some(r) => {
                // Area-weighted vertex normals; unreferenced vertices get no box that matters.
                let normals: Vec<Vec3A> =
                    mesh.vertex_normals().into_iter().map(Vec3A::from).collect();
                let points: Vec<Aabb> = pos.iter().map(|&p| Aabb::from_point(p)).collect();
                let bvh = Bvh::build(points.as_slice(), &options).map_err(hierarchy)?;
                Some(Mls {
                    radius: r as f32,
                    points,
                    normals,
                    bvh,
                })
            }
        };
        Ok(Reference {
            mesh,
            pos,
            bvh,
            segs,
            seg_pos,
            seg_bvh,
            mls,
            ws: BvhWorkspace::new(),
            hits: Vec::new(),
        })
    }

    /// The input's point closest to `p` and its triangle.
    pub fn closest_on_surface(&mut self, p: Vec3) -> (Vec3, u32) {
        let tris = Triangles::from_mesh(self.mesh, &self.pos);
        let hit = tris.ok().and_then(|tris| {
            self.bvh
                .closest_point(&tris, p.into(), f32::INFINITY, &mut self.ws)
        });
        match hit {
            Some(h) => (h.point.into(), h.primitive),
            None => (p, 0),
        }
    }

    /// The input boundary's point closest to `p` (`p` itself on a closed input); with a
    /// smoothing radius, of the smoothed outline (cheap, so every iteration uses it).
    pub fn closest_on_boundary(&mut self, p: Vec3) -> Vec3 {
        let Some(bvh) = &self.seg_bvh else {
            return p;
        };
        let segs = Segments {
            pos: &self.seg_pos,
            segs: &self.segs,
        };
        bvh.closest_point(&segs, p.into(), f32::INFINITY, &mut self.ws)
            .map_or(p, |h| h.point.into())
    }

    /// Where an interior vertex at `p` goes: the closest point of the input, or with `smooth`
    /// (and a smoothing radius) the projection of `p` onto the MLS plane fitted around it.
    pub fn project_interior(&mut self, p: Vec3, smooth: bool) -> Vec3 {
        let (q, _) = self.closest_on_surface(p);
        match smooth && self.mls.is_some() {
            false => q,
            true => self.mls_project(p, q),
        }
    }

    /// Projects `p` onto the plane fitted to the input's vertices around `q` (Gaussian weights
    /// `exp(−4.5·d²/r²)`, i.e. σ = r/3, cut at `r`; normal = weighted mean of vertex normals,
    /// point = weighted centroid), twice, re-centring the fit on the projected point.
    fn mls_project(&mut self, p: Vec3, q: Vec3) -> Vec3 {
        let Some(mls) = &self.mls else {
            return q;
        };
        let r = mls.radius;
        let inv = 4.5 / f64::from(r * r);
        let mut centre = q;
        let mut out = q;
        for _ in 0..2 {
            let c = Vec3A::from(centre);
            let probe = Aabb::new(centre - Vec3::splat(r), centre + Vec3::splat(r));
            mls.bvh.overlapping_primitives(
                mls.points.as_slice(),
                &probe,
                0.0,
                &mut self.ws,
                &mut self.hits,
            );
            let (mut sw, mut sx, mut sn) = (0.0f64, DVec3::ZERO, DVec3::ZERO);
            for &i in &self.hits {
                let x = self.pos[i as usize];
                let d2 = f64::from((x - c).length_squared());
                if d2 > f64::from(r * r) {
                    continue;
                }
                let w = (-inv * d2).exp();
                sw += w;
                sx += w * Vec3::from(x).as_dvec3();
                sn += w * Vec3::from(mls.normals[i as usize]).as_dvec3();
            }
            let n = sn.normalize_or_zero();
            if sw <= 1e-12 || n == DVec3::ZERO {
                return out;
            }
            let centroid = sx / sw;
            let pd = p.as_dvec3();
            let projected = pd - (pd - centroid).dot(n) * n;
            out = projected.as_vec3();
            centre = out;
        }
        out
    }
}

/// `pos` with every boundary loop's vertices replaced by Gaussian averages (weights
/// `exp(−4.5·s²/r²)` over the arc length `s ≤ r` along the loop, both ways).
fn smoothed_outline(mesh: &TriMesh, pos: &[Vec3A], r: f64) -> Vec<Vec3A> {
    let mut out = pos.to_vec();
    let inv = 4.5 / (r * r);
    for l in mesh.topology().boundary_loops() {
        let n = l.len();
        let p: Vec<DVec3> = l
            .iter()
            .map(|&v| Vec3::from(pos[v as usize]).as_dvec3())
            .collect();
        let seg: Vec<f64> = (0..n).map(|i| (p[(i + 1) % n] - p[i]).length()).collect();
        for i in 0..n {
            let (mut sw, mut sx) = (1.0f64, p[i]);
            for dir in [1usize, n - 1] {
                let (mut j, mut s) = (i, 0.0f64);
                for _ in 0..n / 2 {
                    // Step from j to its neighbour in direction `dir`.
                    let k = (j + dir) % n;
                    s += if dir == 1 { seg[j] } else { seg[k] };
                    if s > r {
                        break;
                    }
                    let w = (-inv * s * s).exp();
                    sw += w;
                    sx += w * p[k];
                    j = k;
                }
            }
            out[l[i] as usize] = Vec3A::from((sx / sw).as_vec3());
        }
    }
    out
}
