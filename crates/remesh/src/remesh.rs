//! Isotropic remeshing (Botsch & Kobbelt 2004): split, collapse, flip, relax, project.

use glam::Vec3;
use tissue_mesh::TriMesh;

use crate::edit::{opposite, tri_cross, EditMesh, NONE};
use crate::reference::Reference;
use crate::{MeshQuality, RemeshError};

/// The largest number of triangles [`remesh`] agrees to make (an estimate from the area and the
/// target edge, checked before any work).
pub const MAX_TRIANGLES: u64 = 20_000_000;

/// A collapse or flip may turn a changed triangle by at most `acos(MIN_NORMAL_DOT)` ≈ 78°.
const MIN_NORMAL_DOT: f32 = 0.2;

/// Parameters of [`remesh`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RemeshOptions {
    /// Target edge length `L` (mesh units). Finite, > 0.
    pub target_edge: f64,
    /// Remeshing iterations (split, collapse, flip, relax, project); default 8.
    pub iterations: u32,
    /// `None`: vertices are projected onto the input surface (closest point).
    /// `Some(r)`: onto a smoothed version of it: a moving-least-squares plane fit of the input's
    /// vertices within radius `r` (Gaussian weights, σ = r/3), so noise with wavelengths below
    /// about `r` is removed. About `L` is a good choice.
    pub smoothing_radius: Option<f64>,
}

impl RemeshOptions {
    /// Target edge `target_edge`, 8 iterations, no smoothing.
    pub fn new(target_edge: f64) -> Self {
        RemeshOptions {
            target_edge,
            iterations: 8,
            smoothing_radius: None,
        }
    }

    /// The same options projecting onto the MLS smoothing of radius `radius`.
    pub fn with_smoothing(mut self, radius: f64) -> Self {
        self.smoothing_radius = Some(radius);
        self
    }

    fn check(&self) -> Result<(), RemeshError> {
        if !(self.target_edge.is_finite() && self.target_edge > 0.0) {
            return Err(RemeshError::InvalidTargetEdge {
                value: self.target_edge,
            });
        }
        if let Some(r) = self.smoothing_radius {
            if !(r.is_finite() && r > 0.0) {
                return Err(RemeshError::InvalidSmoothingRadius { value: r });
            }
        }
        Ok(())
    }
}

/// What [`remesh`] did and the shape of its result.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct RemeshStats {
    /// Edge lengths and angles of the result against the target edge.
    pub quality: MeshQuality,
    /// Iterations run.
    pub iterations: u32,
    /// Edge splits, over all iterations.
    pub splits: usize,
    /// Edge collapses.
    pub collapses: usize,
    /// Edge flips.
    pub flips: usize,
}

/// The result of [`remesh`].
#[derive(Debug, Clone, PartialEq)]
pub struct Remeshed {
    /// The new surface.
    pub mesh: TriMesh,
    /// Counts and quality figures.
    pub stats: RemeshStats,
}

/// Remeshes `surface` to near-uniform edges of length `options.target_edge`, keeping its
/// topology (components, boundary loops, Euler characteristic), its orientation and its outline.
///
/// See the crate documentation for the algorithm and the guarantees.
///
/// # Errors
/// [`RemeshError::InvalidTargetEdge`], [`RemeshError::InvalidSmoothingRadius`] for bad options;
/// [`RemeshError::TooManyTriangles`] when the target edge is far too short for the surface;
/// [`RemeshError::Hierarchy`] for a surface too large to index.
pub fn remesh(surface: &TriMesh, options: &RemeshOptions) -> Result<Remeshed, RemeshError> {
    options.check()?;
    let l = options.target_edge;
    let area = surface.area();
    let per_triangle = 3f64.sqrt() / 4.0 * l * l;
    let estimated = (area / per_triangle).ceil();
    if estimated > MAX_TRIANGLES as f64 {
        return Err(RemeshError::TooManyTriangles {
            target_edge: l,
            area,
            estimated: estimated.min(u64::MAX as f64) as u64,
            max: MAX_TRIANGLES,
            min_edge: (area / (MAX_TRIANGLES as f64 * 3f64.sqrt() / 4.0)).sqrt(),
        });
    }
    let _span = tracing::info_span!(
        "remesh",
        triangles = surface.triangle_count(),
        target_edge = l
    )
    .entered();
    let mut reference = Reference::new(surface, options.smoothing_radius)?;
    let mut m = EditMesh::new(surface.positions(), surface.triangles());
    let hi = (4.0 / 3.0 * l) as f32;
    let lo = (4.0 / 5.0 * l) as f32;
    let mut stats = RemeshStats {
        iterations: options.iterations,
        ..RemeshStats::default()
    };
    let mut queue = EdgeQueue::new();
    let mut scratch = Vec::new();
    let mut saved = Vec::new();
    for it in 0..options.iterations {
        stats.splits += split_long(&mut m, hi);
        stats.collapses += collapse_short(&mut m, lo, hi, &mut queue);
        stats.flips += flip_valence(&mut m);
        saved.clear();
        saved.extend_from_slice(&m.pos);
        relax(&mut m, &mut scratch);
        // The MLS fit costs a neighbourhood query per vertex: only the last two projections,
        // the ones the result keeps, use it; earlier ones take the closest point.
        let smooth = it + 2 >= options.iterations;
        project(&mut m, &mut reference, smooth);
        keep_sound(&mut m, &saved);
    }
    let (positions, triangles) = m.compact(false);
    let mesh = TriMesh::new(positions, triangles)
        .map_err(|source| RemeshError::InvalidResult { source })?;
    stats.quality = MeshQuality::measure(&mesh, l);
    tracing::debug!(?stats, "remeshed");
    Ok(Remeshed { mesh, stats })
}

/// Splits every edge longer than `hi` at its midpoint, sweeping until none is left.
pub(crate) fn split_long(m: &mut EditMesh, hi: f32) -> usize {
    let _span = tracing::debug_span!("split").entered();
    let hi2 = hi * hi;
    let mut count = 0;
    for _sweep in 0..64 {
        let before = count;
        // One pass over the triangles the sweep starts with: splitting the new edges at once too
        // would keep splitting the far sides of a fan and pile edges onto its centre.
        let end = m.tris.len();
        for t in 0..end {
            if m.tri_alive[t] {
                for i in 0..3 {
                    let tri = m.tris[t];
                    let (a, b) = (tri[i], tri[(i + 1) % 3]);
                    let (pa, pb) = (m.pos[a as usize], m.pos[b as usize]);
                    if (pa - pb).length_squared() > hi2 && split_is_sound(m, a, b) {
                        m.split(a, b, 0.5 * (pa + pb));
                        count += 1;
                    }
                }
            }
        }
        if count == before {
            break;
        }
    }
    count
}

/// Whether splitting `ab` at its midpoint leaves every new triangle's height above 1 % of its
/// longest side (a split next to a sliver would make a flatter one).
fn split_is_sound(m: &EditMesh, a: u32, b: u32) -> bool {
    let (t1, t2) = m.edge_tris(a, b);
    let (pa, pb) = (m.pos[a as usize], m.pos[b as usize]);
    let mid = 0.5 * (pa + pb);
    [t1, t2].iter().filter(|&&t| t != NONE).all(|&t| {
        let x = m.pos[opposite(m.tris[t as usize], a, b) as usize];
        [(pa, mid), (mid, pb)].iter().all(|&(p, q)| {
            let longest = (q - p)
                .length_squared()
                .max((x - q).length_squared())
                .max((p - x).length_squared());
            tri_cross(p, q, x).length() > 1e-2 * longest
        })
    })
}

/// Edges waiting for a collapse, shortest first: a bucket queue over the squared length in
/// `[0, lo²)` (`BUCKETS` buckets, last in first out within one), so a push and a pop cost `O(1)`.
/// Entries carry the squared length they were queued with; an entry whose edge has changed since
/// is stale and skipped (the edge was queued again when it changed).
pub(crate) struct EdgeQueue {
    buckets: Vec<Vec<(u32, u32, u32)>>,
    scale: f32,
    lo2: f32,
    current: usize,
}

const BUCKETS: usize = 1024;

impl EdgeQueue {
    pub fn new() -> Self {
        EdgeQueue {
            buckets: vec![Vec::new(); BUCKETS],
            scale: 0.0,
            lo2: 0.0,
            current: 0,
        }
    }

    fn reset(&mut self, lo2: f32) {
        for b in &mut self.buckets {
            b.clear();
        }
        self.lo2 = lo2;
        self.scale = BUCKETS as f32 / lo2;
        self.current = 0;
    }

    /// Queues edge `ab` if it is shorter than `lo`.
    #[inline]
    fn push(&mut self, m: &EditMesh, a: u32, b: u32) {
        let d2 = (m.pos[a as usize] - m.pos[b as usize]).length_squared();
        if d2 < self.lo2 {
            let i = ((d2 * self.scale) as usize).min(BUCKETS - 1);
            // An edge shorter than the bucket being emptied joins that bucket.
            let i = i.max(self.current);
            self.buckets[i].push((d2.to_bits(), a, b));
        }
    }

    #[inline]
    fn pop(&mut self) -> Option<(u32, u32, u32)> {
        while self.current < BUCKETS {
            if let Some(e) = self.buckets[self.current].pop() {
                return Some(e);
            }
            self.current += 1;
        }
        None
    }
}

/// Collapses edges shorter than `lo`, about shortest first, unless the collapse would make an
/// edge longer than `hi` or break the surface.
pub(crate) fn collapse_short(m: &mut EditMesh, lo: f32, hi: f32, queue: &mut EdgeQueue) -> usize {
    let _span = tracing::debug_span!("collapse").entered();
    queue.reset(lo * lo);
    for t in 0..m.tris.len() {
        if !m.tri_alive[t] {
            continue;
        }
        let tri = m.tris[t];
        for i in 0..3 {
            let (a, b) = (tri[i], tri[(i + 1) % 3]);
            if a < b || m.edge_tris(a, b).1 == NONE {
                queue.push(m, a, b);
            }
        }
    }
    let mut count = 0;
    while let Some((bits, a, b)) = queue.pop() {
        if !m.v_alive[a as usize] || !m.v_alive[b as usize] {
            continue;
        }
        let (pa, pb) = (m.pos[a as usize], m.pos[b as usize]);
        if (pa - pb).length_squared().to_bits() != bits {
            continue; // stale: an end moved since it was queued (and was queued again)
        }
        let (t1, t2) = m.edge_tris(a, b);
        if t1 == NONE {
            continue;
        }
        let (ba, bb) = (m.boundary[a as usize], m.boundary[b as usize]);
        let (la, lb) = (m.locked[a as usize], m.locked[b as usize]);
        let (r, k, p) = if la && lb {
            continue;
        } else if t2 == NONE {
            // A boundary edge: collapsed along the boundary.
            if la {
                (b, a, pa)
            } else if lb {
                (a, b, pb)
            } else {
                (b, a, 0.5 * (pa + pb))
            }
        } else if ba && bb {
            continue; // an interior edge between two boundary vertices would pinch the surface
        } else if ba {
            (b, a, pa)
        } else if bb {
            (a, b, pb)
        } else {
            (b, a, 0.5 * (pa + pb))
        };
        if m.try_collapse(r, k, p, hi, MIN_NORMAL_DOT) {
            count += 1;
            for i in 0..m.vtris[k as usize].len() {
                let tri = m.tris[m.vtris[k as usize][i] as usize];
                // Each neighbour once: the one after k in each triangle (plus, at the boundary,
                // the one before k on the boundary side).
                let j = tri.iter().position(|&x| x == k).unwrap_or(0);
                queue.push(m, k, tri[(j + 1) % 3]);
                if m.boundary[k as usize] {
                    let w = tri[(j + 2) % 3];
                    if m.edge_tris(k, w).1 == NONE {
                        queue.push(m, k, w);
                    }
                }
            }
        }
    }
    count
}

/// Flips interior edges where that brings the four vertices' valences closer to 6 (4 on the
/// boundary), without folding.
pub(crate) fn flip_valence(m: &mut EditMesh) -> usize {
    let _span = tracing::debug_span!("flip").entered();
    let target = |m: &EditMesh, v: u32| if m.boundary[v as usize] { 4 } else { 6 };
    let minimum = |m: &EditMesh, v: u32| if m.boundary[v as usize] { 2 } else { 3 };
    let mut count = 0;
    for t in 0..m.tris.len() {
        for i in 0..3 {
            if !m.tri_alive[t] {
                break;
            }
            let tri = m.tris[t];
            let (a, b) = (tri[i], tri[(i + 1) % 3]);
            if a > b {
                continue;
            }
            let (t1, t2) = m.edge_tris(a, b);
            if t2 == NONE {
                continue;
            }
            let (t1, t2) = m.oriented_pair(a, b, t1, t2);
            let c = opposite(m.tris[t1 as usize], a, b);
            let d = opposite(m.tris[t2 as usize], a, b);
            let dev = |v: u32, delta: i64| {
                let x = m.valence(v) as i64 + delta - target(m, v);
                x * x
            };
            let before = dev(a, 0) + dev(b, 0) + dev(c, 0) + dev(d, 0);
            let after = dev(a, -1) + dev(b, -1) + dev(c, 1) + dev(d, 1);
            if after >= before
                || (m.valence(a) as i64) - 1 < minimum(m, a)
                || (m.valence(b) as i64) - 1 < minimum(m, b)
                || c == d
                || m.adjacent(c, d)
                || !m.flip_is_flat(a, b, t1, t2, MIN_NORMAL_DOT)
            {
                continue;
            }
            m.flip(a, b, t1, t2);
            count += 1;
        }
    }
    count
}

/// Tangential relaxation (Jacobi): an interior vertex moves towards the area-weighted centroid of
/// its triangles, within its tangent plane; a boundary vertex towards the midpoint of its two
/// boundary neighbours, along the boundary.
#[allow(clippy::needless_range_loop)] // v indexes several parallel arrays
pub(crate) fn relax(m: &mut EditMesh, new: &mut Vec<Vec3>) {
    let _span = tracing::debug_span!("relax").entered();
    new.clear();
    new.extend_from_slice(&m.pos);
    for v in 0..m.pos.len() {
        if !m.v_alive[v] || m.locked[v] || m.vtris[v].is_empty() {
            continue;
        }
        let p = m.pos[v];
        if m.boundary[v] {
            if let Some((prev, next)) = m.boundary_neighbours(v as u32) {
                let (pp, pn) = (m.pos[prev as usize], m.pos[next as usize]);
                let q = 0.5 * (pp + pn);
                let dir = (pn - pp).normalize_or_zero();
                new[v] = p + dir * dir.dot(q - p);
            }
            continue;
        }
        let (mut sa, mut sc, mut sn) = (0.0f32, Vec3::ZERO, Vec3::ZERO);
        for &t in &m.vtris[v] {
            let [a, b, c] = m.tris[t as usize].map(|x| m.pos[x as usize]);
            let cr = (b - a).cross(c - a);
            let area = cr.length();
            sa += area;
            sc += area * (a + b + c) * (1.0 / 3.0);
            sn += cr;
        }
        let n = sn.normalize_or_zero();
        if sa > 0.0 {
            let d = sc / sa - p;
            new[v] = p + d - n * n.dot(d);
        }
    }
    std::mem::swap(&mut m.pos, new);
}

/// Undoes the moves of relaxation and projection around triangles they flattened or flipped: near
/// the boundary, a vertex relaxed past it projects onto the outline, flat with its neighbours. The
/// corners of such a triangle go back to `saved` (where the triangle was sound), repeatedly, and
/// if that does not settle, every vertex does.
pub(crate) fn keep_sound(m: &mut EditMesh, saved: &[Vec3]) {
    for _round in 0..8 {
        let mut reverted = false;
        for t in 0..m.tris.len() {
            if !m.tri_alive[t] {
                continue;
            }
            let tri = m.tris[t];
            let [a, b, c] = tri.map(|v| m.pos[v as usize]);
            let now = tri_cross(a, b, c);
            let longest = (b - a)
                .length_squared()
                .max((c - b).length_squared())
                .max((a - c).length_squared());
            let [oa, ob, oc] = tri.map(|v| saved[v as usize]);
            let before = tri_cross(oa, ob, oc);
            if now.length() > 1e-3 * longest && now.dot(before) > 0.0 {
                continue;
            }
            if tri.iter().all(|&v| m.pos[v as usize] == saved[v as usize]) {
                continue; // already as it was: nothing to undo here
            }
            for v in tri {
                m.pos[v as usize] = saved[v as usize];
            }
            reverted = true;
        }
        if !reverted {
            return;
        }
    }
    m.pos.copy_from_slice(saved);
}

/// Projects interior vertices onto the reference surface, boundary ones onto its boundary
/// (with `smooth`, interior ones onto the MLS fit if the reference has one).
pub(crate) fn project(m: &mut EditMesh, reference: &mut Reference<'_>, smooth: bool) {
    let _span = tracing::debug_span!("project").entered();
    for v in 0..m.pos.len() {
        if !m.v_alive[v] || m.locked[v] || m.vtris[v].is_empty() {
            continue;
        }
        m.pos[v] = if m.boundary[v] {
            reference.closest_on_boundary(m.pos[v])
        } else {
            reference.project_interior(m.pos[v], smooth)
        };
    }
}
