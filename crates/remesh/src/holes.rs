//! Hole filling: the max–min-quality triangulation of each loop, refinement by edge splits and Delaunay flips,
//! harmonic (umbrella) fairing of the new vertices with the loop fixed.

use std::collections::HashMap;

use glam::{DVec3, Vec3};
use tissue_mesh::{TriMesh, ZERO_AREA_TOLERANCE};

use crate::edit::{opposite, tri_cross, EditMesh, NONE};
use crate::RemeshError;

/// One boundary loop of a surface.
#[derive(Debug, Clone, PartialEq)]
pub struct Hole {
    /// The loop's vertices in the input's numbering, in the order its triangles traverse it.
    pub vertices: Vec<u32>,
    /// The largest distance between two of its vertices (mesh units).
    pub diameter: f64,
    /// The length of the closed polyline.
    pub perimeter: f64,
    /// The mean of its vertices.
    pub centroid: Vec3,
}

/// The result of [`fill_holes`].
#[derive(Debug, Clone, PartialEq)]
pub struct HoleFill {
    /// The input with the filled holes closed. Its first vertices and triangles are the input's,
    /// unchanged and in order; new vertices and the fill triangles come after them.
    pub mesh: TriMesh,
    /// The loops that were filled, in the order of the input's boundary loops.
    pub filled: Vec<Hole>,
    /// The loops left open: wider than the limit, or (rarely) ones no valid triangulation was found
    /// for (a loop through a vertex twice, or whose every ear would duplicate an existing edge).
    pub open: Vec<Hole>,
    /// Index of the first fill triangle in `mesh` (the input's triangle count).
    pub first_fill_triangle: usize,
}

impl Hole {
    fn measure(positions: &[Vec3], vertices: &[u32]) -> Hole {
        let p: Vec<DVec3> = vertices
            .iter()
            .map(|&v| positions[v as usize].as_dvec3())
            .collect();
        let mut diameter2 = 0.0f64;
        for i in 0..p.len() {
            for j in i + 1..p.len() {
                diameter2 = diameter2.max((p[i] - p[j]).length_squared());
            }
        }
        let perimeter = (0..p.len())
            .map(|i| (p[(i + 1) % p.len()] - p[i]).length())
            .sum();
        let centroid = p.iter().sum::<DVec3>() / p.len().max(1) as f64;
        Hole {
            vertices: vertices.to_vec(),
            diameter: diameter2.sqrt(),
            perimeter,
            centroid: centroid.as_vec3(),
        }
    }
}

/// Fills every boundary loop of `surface` whose diameter is at most `max_diameter` (mesh units)
/// and reports the others.
///
/// Each filled loop is triangulated by the triangulation of its own vertices that maximises the
/// smallest triangle quality (the sine of the smallest angle, weighted by how far the triangle
/// faces the loop's Newell normal; dynamic programming over the loop, Barequet–Sharir / Liepa,
/// `O(n³)`, in `f64` about the loop's centroid), none of whose new edges is already an edge; loops
/// of more than [`MAX_DP_LOOP`] vertices are ear-clipped (smallest interior angle first, an ear
/// taken only when its triangle passes the same quality floor). Fill edges longer than 1.5 × the
/// loop's mean edge (or [`FILL_DIVISIONS`]th of the hole's diameter if longer) are then split and the fill is made Delaunay by flips, the new vertices are
/// placed by harmonic (umbrella) fairing with the loop fixed, so the patch is a smooth membrane;
/// flips again after fairing. Where the refined fill is not clearly sound (a triangle whose
/// height is below 1e-4 of its longest edge, in the stored `f32` positions), the plain
/// triangulation is kept.
///
/// No fill triangle is ever degenerate, whatever the loop's resolution and the coordinates'
/// magnitude: a loop for which no triangulation has every smallest angle above about 0.06° (a
/// loop through a vertex twice, or whose every triangulation would fold or duplicate an edge) is
/// left open and reported in [`HoleFill::open`].
///
/// The work is local: each loop is filled on the triangles at its vertices only, so the cost is
/// that of the holes plus one copy of the surface, whatever the surface's size.
///
/// # Errors
/// [`RemeshError::InvalidMaxDiameter`] for a negative or non-finite `max_diameter`.
pub fn fill_holes(surface: &TriMesh, max_diameter: f64) -> Result<HoleFill, RemeshError> {
    if !(max_diameter.is_finite() && max_diameter >= 0.0) {
        return Err(RemeshError::InvalidMaxDiameter {
            value: max_diameter,
        });
    }
    let _span = tracing::info_span!("fill_holes", triangles = surface.triangle_count()).entered();
    let first_fill = surface.triangle_count();
    let n0 = surface.vertex_count();
    let mut fills = Fills {
        positions: Vec::new(),
        triangles: Vec::new(),
        at_vertex: HashMap::new(),
    };
    let mut filled = Vec::new();
    let mut open = Vec::new();
    for l in surface.topology().boundary_loops() {
        let hole = {
            let _span = tracing::debug_span!("measure_loop", vertices = l.len()).entered();
            Hole::measure(surface.positions(), l)
        };
        if hole.diameter > max_diameter || l.len() < 3 {
            open.push(hole);
            continue;
        }
        let Some(patch) = fill_loop(surface, &fills, l, hole.diameter) else {
            tracing::warn!(
                vertices = l.len(),
                "no triangulation without degenerate triangles for a hole; left open"
            );
            open.push(hole);
            continue;
        };
        fills.add(n0, patch);
        filled.push(hole);
    }
    let mut positions = Vec::with_capacity(n0 + fills.positions.len());
    positions.extend_from_slice(surface.positions());
    positions.extend_from_slice(&fills.positions);
    let mut triangles = Vec::with_capacity(first_fill + fills.triangles.len());
    triangles.extend_from_slice(surface.triangles());
    triangles.extend_from_slice(&fills.triangles);
    let mesh = TriMesh::new(positions, triangles)
        .map_err(|source| RemeshError::InvalidResult { source })?;
    Ok(HoleFill {
        mesh,
        filled,
        open,
        first_fill_triangle: first_fill,
    })
}

/// The fills made so far: new vertices and triangles (in the output's numbering), and the fill
/// triangles at each vertex of a filled loop (so a later loop through the same vertex sees them).
struct Fills {
    positions: Vec<Vec3>,
    triangles: Vec<[u32; 3]>,
    at_vertex: HashMap<u32, Vec<u32>>,
}

/// One loop's fill on its local patch.
struct Patch {
    /// New vertices.
    positions: Vec<Vec3>,
    /// Fill triangles: below `first_new` an index into `globals`, from it on a new vertex.
    triangles: Vec<[u32; 3]>,
    /// The patch's vertices in the surface's numbering (the loop's first).
    globals: Vec<u32>,
    first_new: usize,
}

impl Fills {
    fn add(&mut self, n0: usize, patch: Patch) {
        let base = (n0 + self.positions.len()) as u32;
        self.positions.extend_from_slice(&patch.positions);
        for tri in patch.triangles {
            let global = tri.map(|v| {
                if (v as usize) < patch.first_new {
                    patch.globals[v as usize]
                } else {
                    base + (v - patch.first_new as u32)
                }
            });
            let index = self.triangles.len() as u32;
            self.triangles.push(global);
            for v in global {
                if (v as usize) < n0 {
                    self.at_vertex.entry(v).or_default().push(index);
                }
            }
        }
    }
}

/// Fills the loop `l` on the patch of the triangles at its vertices (the surface's and earlier
/// fills'); `None` when no triangulation is sound.
fn fill_loop(surface: &TriMesh, fills: &Fills, l: &[u32], diameter: f64) -> Option<Patch> {
    let n = l.len();
    let _span = tracing::debug_span!("fill_loop", vertices = n).entered();
    let mut sorted = l.to_vec();
    sorted.sort_unstable();
    if sorted.windows(2).any(|w| w[0] == w[1]) {
        return None;
    }
    let n0 = surface.vertex_count() as u32;
    let topo = surface.topology();
    // The patch: every triangle at a loop vertex, the surface's then earlier fills'.
    let mut input: Vec<u32> = l
        .iter()
        .flat_map(|&v| topo.vertex_triangles(v).iter().copied())
        .collect();
    input.sort_unstable();
    input.dedup();
    let mut earlier: Vec<u32> = l
        .iter()
        .filter_map(|v| fills.at_vertex.get(v))
        .flatten()
        .copied()
        .collect();
    earlier.sort_unstable();
    earlier.dedup();
    let mut globals: Vec<u32> = l.to_vec();
    let mut local: HashMap<u32, u32> = l.iter().enumerate().map(|(i, &v)| (v, i as u32)).collect();
    let position = |v: u32| {
        if v < n0 {
            surface.positions()[v as usize]
        } else {
            fills.positions[(v - n0) as usize]
        }
    };
    let tris: Vec<[u32; 3]> = input
        .iter()
        .map(|&t| surface.triangles()[t as usize])
        .chain(earlier.iter().map(|&t| fills.triangles[t as usize]))
        .map(|tri| {
            tri.map(|v| {
                *local.entry(v).or_insert_with(|| {
                    globals.push(v);
                    globals.len() as u32 - 1
                })
            })
        })
        .collect();
    let local_positions: Vec<Vec3> = globals.iter().map(|&v| position(v)).collect();
    let mut m = EditMesh::new(&local_positions, &tris);
    let (first_fill, first_new) = (tris.len(), globals.len());
    // The loop in local numbering is 0..n, in the surface's direction.
    let lp: Vec<u32> = (0..n as u32).collect();
    let plain = {
        let _span = tracing::debug_span!("triangulate").entered();
        triangulate(&m, &lp)?
    };
    let perimeter: f64 = (0..n)
        .map(|i| (local_positions[(i + 1) % n].as_dvec3() - local_positions[i].as_dvec3()).length())
        .sum();
    // The fill's edge: the loop's, but no finer than 1/FILL_DIVISIONS of the hole across, so that a
    // fine scan's fill costs what a coarse one's does.
    let tau = (perimeter / n as f64).max(diameter / FILL_DIVISIONS) as f32;
    for &tri in &plain {
        m.add_triangle(tri);
    }
    let area: f64 = plain
        .iter()
        .map(|tri| {
            let [a, b, c] = tri.map(|v| m.pos[v as usize].as_dvec3());
            0.5 * (b - a).cross(c - a).length()
        })
        .sum();
    // A bound on the refinement: four times the triangles of edge `tau` the fill's area holds.
    let cap = first_fill + 4 * (area / (0.433 * f64::from(tau).powi(2))) as usize + 4 * n + 16;
    let _refine = tracing::debug_span!("refine_and_fair").entered();
    refine(&mut m, first_fill, tau, cap);
    fair(&mut m, first_new, first_fill);
    delaunay_flips(&mut m, first_fill);
    fair(&mut m, first_new, first_fill);
    if !sound(&m, first_fill) {
        // Refinement made a sliver (it can on loops with long straight runs): keep the plain
        // triangulation instead, sound by construction.
        tracing::debug!(
            vertices = n,
            "refined hole fill unsound; the plain one kept"
        );
        m.truncate(first_fill, first_new);
        for &tri in &plain {
            m.add_triangle(tri);
        }
    }
    let triangles: Vec<[u32; 3]> = (first_fill..m.tris.len())
        .filter(|&t| m.tri_alive[t])
        .map(|t| m.tris[t])
        .collect();
    // Never emit what the mesh checks would call degenerate.
    if triangles.iter().any(|tri| {
        let [a, b, c] = tri.map(|v| m.pos[v as usize].as_dvec3());
        let longest = (b - a)
            .length_squared()
            .max((c - b).length_squared())
            .max((a - c).length_squared());
        (b - a).cross(c - a).length() <= 10.0 * ZERO_AREA_TOLERANCE * longest
    }) {
        return None;
    }
    Some(Patch {
        positions: m.pos[first_new..].to_vec(),
        triangles,
        globals,
        first_new,
    })
}

/// A fill's edges are no shorter than its hole's diameter over this (about 800 triangles for a
/// round hole, however fine the scan around it).
pub const FILL_DIVISIONS: f64 = 32.0;

/// Loops of up to this many vertices are triangulated optimally (`O(n³)` time, `O(n²)` memory:
/// 0.1 s and 12 MB at the limit); longer ones by ear clipping.
pub const MAX_DP_LOOP: usize = 1000;

/// The smallest quality a fill triangle may have: the sine of its smallest angle (times its
/// facing factor), 1e-3 (0.06°). Its height is then at least 5e-4 of its longest edge: 5000 ×
/// the mesh checks' zero-area tolerance, and 5 × the hole filler's own soundness floor.
const MIN_FILL_QUALITY: f64 = 1e-3;

/// The quality of triangle `abc` of a fill whose loop's normal is `normal` (unit): the sine of its
/// smallest angle, times `(1 + cos θ)/2` for the angle θ between its normal and the loop's (1
/// facing the same way, ½ across, 0 folded back). 0 for a degenerate triangle.
fn quality(a: DVec3, b: DVec3, c: DVec3, normal: DVec3) -> f64 {
    let cross = (b - a).cross(c - a);
    let doubled = cross.length();
    let (ab, bc, ca) = (
        (b - a).length_squared(),
        (c - b).length_squared(),
        (a - c).length_squared(),
    );
    // The smallest angle is opposite the shortest side, between the two longer ones.
    let (hi, mid) = if ab >= bc && ab >= ca {
        (ab, bc.max(ca))
    } else if bc >= ca {
        (bc, ab.max(ca))
    } else {
        (ca, ab.max(bc))
    };
    let denominator = (hi * mid).sqrt();
    if !(doubled > 0.0 && denominator > 0.0) {
        return 0.0;
    }
    let sine = doubled / denominator;
    let facing = if normal == DVec3::ZERO {
        1.0
    } else {
        0.5 * (1.0 + cross.dot(normal) / doubled)
    };
    let q = sine * facing;
    if q.is_finite() {
        q
    } else {
        0.0
    }
}

/// Triangulates the loop `l` (local vertices, as the surface traverses it: fill triangles
/// traverse its edges the other way) with the largest smallest [`quality`], new edges not
/// already edges of `m`; ear clipping for loops longer than [`MAX_DP_LOOP`]. `None` when the best
/// has a triangle below [`MIN_FILL_QUALITY`].
fn triangulate(m: &EditMesh, l: &[u32]) -> Option<Vec<[u32; 3]>> {
    let n = l.len();
    if n < 3 {
        return None;
    }
    // The fill polygon: the loop reversed, in f64 about its centroid.
    let poly: Vec<u32> = l.iter().rev().copied().collect();
    let raw: Vec<DVec3> = poly.iter().map(|&v| m.pos[v as usize].as_dvec3()).collect();
    let centre = raw.iter().sum::<DVec3>() / n as f64;
    let p: Vec<DVec3> = raw.iter().map(|&x| x - centre).collect();
    let mut normal = DVec3::ZERO;
    for i in 0..n {
        let (a, b) = (p[i], p[(i + 1) % n]);
        normal += DVec3::new(
            (a.y - b.y) * (a.z + b.z),
            (a.z - b.z) * (a.x + b.x),
            (a.x - b.x) * (a.y + b.y),
        );
    }
    let normal = normal.normalize_or_zero();
    if n > MAX_DP_LOOP {
        return ear_clip(m, &poly, &p, normal);
    }
    // best[i·n + j], j > i: the largest smallest quality of the sub-polygon i..=j closed by the
    // edge ij (−1 where ij may not be an edge); split[i·n + j]: its apex.
    let mut best = vec![f64::INFINITY; n * n];
    let mut split = vec![0u32; n * n];
    for len in 2..n {
        for i in 0..n - len {
            let j = i + len;
            let at = i * n + j;
            if len < n - 1 && m.adjacent(poly[i], poly[j]) {
                best[at] = -1.0;
                continue;
            }
            let (mut b, mut apex) = (-1.0f64, i + 1);
            for k in i + 1..j {
                let sub = best[i * n + k].min(best[k * n + j]);
                if sub <= b {
                    continue;
                }
                let q = quality(p[i], p[k], p[j], normal).min(sub);
                if q > b {
                    (b, apex) = (q, k);
                }
            }
            best[at] = b;
            split[at] = apex as u32;
        }
    }
    if best[n - 1].is_nan() || best[n - 1] < MIN_FILL_QUALITY {
        return None;
    }
    let mut out = Vec::with_capacity(n - 2);
    let mut stack = vec![(0usize, n - 1)];
    while let Some((i, j)) = stack.pop() {
        if j - i < 2 {
            continue;
        }
        let k = split[i * n + j] as usize;
        out.push([poly[i], poly[k], poly[j]]);
        stack.push((i, k));
        stack.push((k, j));
    }
    Some(out)
}

/// Ear clipping of the fill polygon `poly` (positions `p` about its centre, Newell `normal`):
/// always the ear with the smallest interior angle whose new edge is not already an edge and
/// whose triangle's [`quality`] is at least [`MIN_FILL_QUALITY`]. `None` when no ear is left.
fn ear_clip(m: &EditMesh, poly: &[u32], p: &[DVec3], normal: DVec3) -> Option<Vec<[u32; 3]>> {
    let n = poly.len();
    let mut prev: Vec<usize> = (0..n).map(|i| (i + n - 1) % n).collect();
    let mut next: Vec<usize> = (0..n).map(|i| (i + 1) % n).collect();
    let mut alive = vec![true; n];
    let angle = |i: usize, prev: &[usize], next: &[usize]| {
        let (a, b, c) = (p[prev[i]], p[i], p[next[i]]);
        let (u, w) = (a - b, c - b);
        let inner = u.angle_between(w);
        let inner = if inner.is_finite() { inner } else { 0.0 };
        if (b - a).cross(c - b).dot(normal) >= 0.0 {
            inner
        } else {
            std::f64::consts::TAU - inner
        }
    };
    let mut angles: Vec<f64> = (0..n).map(|i| angle(i, &prev, &next)).collect();
    let mut diagonals: Vec<(u32, u32)> = Vec::new();
    let mut out = Vec::with_capacity(n - 2);
    let mut remaining = n;
    let mut order: Vec<usize> = Vec::with_capacity(n);
    while remaining > 3 {
        order.clear();
        order.extend((0..n).filter(|&i| alive[i]));
        order.sort_by(|&x, &y| angles[x].total_cmp(&angles[y]).then(x.cmp(&y)));
        let mut chosen = None;
        for &i in &order {
            let (a, c) = (poly[prev[i]], poly[next[i]]);
            let key = (a.min(c), a.max(c));
            if m.adjacent(a, c) || diagonals.contains(&key) {
                continue;
            }
            if quality(p[prev[i]], p[i], p[next[i]], normal) < MIN_FILL_QUALITY {
                continue;
            }
            chosen = Some((i, key));
            break;
        }
        let (i, key) = chosen?;
        out.push([poly[prev[i]], poly[i], poly[next[i]]]);
        diagonals.push(key);
        alive[i] = false;
        let (a, c) = (prev[i], next[i]);
        next[a] = c;
        prev[c] = a;
        angles[a] = angle(a, &prev, &next);
        angles[c] = angle(c, &prev, &next);
        remaining -= 1;
    }
    let i = (0..n).find(|&i| alive[i])?;
    if quality(p[prev[i]], p[i], p[next[i]], normal) < MIN_FILL_QUALITY {
        return None;
    }
    out.push([poly[prev[i]], poly[i], poly[next[i]]]);
    Some(out)
}

/// A fill edge is not split when a new triangle's smallest angle would be below this (radians, 10°).
const MIN_SPLIT_ANGLE: f32 = 0.1745;

/// Whether `ab` is a loop edge (one of its triangles is the input's).
fn on_loop(m: &EditMesh, a: u32, b: u32, first_fill: usize) -> bool {
    let (t1, t2) = m.edge_tris(a, b);
    (t1 != NONE && (t1 as usize) < first_fill) || (t2 != NONE && (t2 as usize) < first_fill)
}

/// Whether edge `ab` lies inside the fill (both its triangles are fill triangles); returns them.
fn fill_edge(m: &EditMesh, a: u32, b: u32, first_fill: usize) -> Option<(u32, u32)> {
    let (t1, t2) = m.edge_tris(a, b);
    (t2 != NONE && t1 as usize >= first_fill && t2 as usize >= first_fill).then_some((t1, t2))
}

/// Splits fill edges longer than `1.5·tau` (`tau`: the hole's mean loop edge), with Delaunay flips after
/// each sweep, until none is left or the mesh has `cap` triangles (a sweep is not started past it).
fn refine(m: &mut EditMesh, first_fill: usize, tau: f32, cap: usize) {
    for _round in 0..200 {
        let mut splits = 0;
        if m.tris.len() >= cap {
            break;
        }
        // One sweep over the triangles the round starts with, then flips: splitting the new
        // edges at once too would cluster vertices around the ear clipping's fan apexes.
        let end = m.tris.len();
        for t in first_fill..end {
            for i in 0..3 {
                let tri = m.tris[t];
                let (a, b) = (tri[i], tri[(i + 1) % 3]);
                let (pa, pb) = (m.pos[a as usize], m.pos[b as usize]);
                if (pa - pb).length() > 1.5 * tau && fill_edge(m, a, b, first_fill).is_some() {
                    // Refuse a split that would make a triangle on a loop edge a worse sliver:
                    // no flip can mend it there, and repeated splits would flatten it to nothing.
                    let mid = 0.5 * (pa + pb);
                    let (t1, t2) = m.edge_tris(a, b);
                    let sliver = [t1, t2].iter().any(|&tt| {
                        let xv = opposite(m.tris[tt as usize], a, b);
                        let x = m.pos[xv as usize];
                        let old = min_angle(pa, pb, x);
                        let worse = |new: f32| new < MIN_SPLIT_ANGLE && new < old;
                        (on_loop(m, a, xv, first_fill) && worse(min_angle(pa, mid, x)))
                            || (on_loop(m, b, xv, first_fill) && worse(min_angle(mid, pb, x)))
                    });
                    if sliver {
                        continue;
                    }
                    m.split(a, b, mid);
                    splits += 1;
                }
            }
        }
        delaunay_flips(m, first_fill);
        if splits == 0 {
            break;
        }
    }
}

/// Flips fill edges where that raises the pair's smallest angle (Lawson: a stack of edges to
/// check, the four around each flip pushed again), with a cap on the flips so that non-planar
/// fills, where the criterion can cycle, still stop.
fn delaunay_flips(m: &mut EditMesh, first_fill: usize) {
    let mut stack: Vec<(u32, u32)> = Vec::new();
    for t in first_fill..m.tris.len() {
        let tri = m.tris[t];
        for i in 0..3 {
            let (a, b) = (tri[i], tri[(i + 1) % 3]);
            if a < b {
                stack.push((a, b));
            }
        }
    }
    let mut budget = 20 * (m.tris.len() - first_fill) + 100;
    while let Some((a, b)) = stack.pop() {
        let Some((t1, t2)) = fill_edge(m, a, b, first_fill) else {
            continue;
        };
        let (t1, t2) = m.oriented_pair(a, b, t1, t2);
        let c = opposite(m.tris[t1 as usize], a, b);
        let d = opposite(m.tris[t2 as usize], a, b);
        let [pa, pb, pc, pd] = [a, b, c, d].map(|v| m.pos[v as usize]);
        // Max–min angle: the plane's Delaunay criterion, and one that cannot cycle in 3D since
        // every flip raises the smaller of the pair's smallest angles.
        let before = min_angle(pa, pb, pc).min(min_angle(pb, pa, pd));
        let after = min_angle(pc, pa, pd).min(min_angle(pd, pb, pc));
        if after > before + 1e-3 && c != d && !m.adjacent(c, d) && m.flip_is_flat(a, b, t1, t2, 0.5)
        {
            m.flip(a, b, t1, t2);
            stack.extend([(a, c), (c, b), (b, d), (d, a)]);
            budget -= 1;
            if budget == 0 {
                break;
            }
        }
    }
}

/// Whether every fill triangle is clearly non-degenerate (height above 1e-4 of its longest edge,
/// in `f64` from the stored positions).
fn sound(m: &EditMesh, first_fill: usize) -> bool {
    (first_fill..m.tris.len()).all(|t| {
        let [a, b, c] = m.tris[t].map(|v| m.pos[v as usize].as_dvec3());
        let longest = (b - a)
            .length_squared()
            .max((c - b).length_squared())
            .max((a - c).length_squared());
        (b - a).cross(c - a).length() > 1e-4 * longest
    })
}

/// The smallest interior angle of a triangle, radians.
fn min_angle(a: Vec3, b: Vec3, c: Vec3) -> f32 {
    let angle = |p: Vec3, q: Vec3, r: Vec3| (q - p).angle_between(r - p);
    let x = angle(a, b, c).min(angle(b, c, a)).min(angle(c, a, b));
    if x.is_finite() {
        x
    } else {
        0.0
    }
}

/// Places the vertices from `first_new` on by solving the uniform Laplace equation (each the mean
/// of its neighbours) with the others fixed: conjugate gradients in `f64`, per coordinate.
fn fair(m: &mut EditMesh, first_new: usize, first_fill: usize) {
    let n = m.pos.len() - first_new;
    if n == 0 {
        return;
    }
    // Neighbour lists of the new vertices (compressed rows, global indices).
    let mut offsets = Vec::with_capacity(n + 1);
    let mut nbrs: Vec<u32> = Vec::new();
    offsets.push(0);
    for v in first_new..m.pos.len() {
        let start = nbrs.len();
        for &t in &m.vtris[v] {
            for w in m.tris[t as usize] {
                if w as usize != v {
                    nbrs.push(w);
                }
            }
        }
        nbrs[start..].sort_unstable();
        let mut k = start;
        for j in start..nbrs.len() {
            if j == start || nbrs[j] != nbrs[k - 1] {
                nbrs[k] = nbrs[j];
                k += 1;
            }
        }
        nbrs.truncate(k);
        offsets.push(nbrs.len());
    }
    let degree: Vec<f64> = (0..n)
        .map(|i| (offsets[i + 1] - offsets[i]) as f64)
        .collect();
    // A x = b with A = D − (adjacency among new vertices), b = Σ fixed neighbours.
    let apply = |x: &[DVec3], out: &mut [DVec3]| {
        for i in 0..n {
            let mut s = degree[i] * x[i];
            for &w in &nbrs[offsets[i]..offsets[i + 1]] {
                if w as usize >= first_new {
                    s -= x[w as usize - first_new];
                }
            }
            out[i] = s;
        }
    };
    let mut b = vec![DVec3::ZERO; n];
    for i in 0..n {
        for &w in &nbrs[offsets[i]..offsets[i + 1]] {
            if (w as usize) < first_new {
                b[i] += m.pos[w as usize].as_dvec3();
            }
        }
    }
    let mut x: Vec<DVec3> = m.pos[first_new..].iter().map(|p| p.as_dvec3()).collect();
    let mut ax = vec![DVec3::ZERO; n];
    apply(&x, &mut ax);
    let mut r: Vec<DVec3> = b.iter().zip(&ax).map(|(b, a)| *b - *a).collect();
    let mut d = r.clone();
    let dot = |u: &[DVec3], v: &[DVec3]| -> DVec3 {
        u.iter().zip(v).fold(DVec3::ZERO, |s, (a, b)| s + *a * *b)
    };
    let mut rr = dot(&r, &r);
    let bb = dot(&b, &b).max_element().max(1e-300);
    for _ in 0..(4 * n).clamp(50, 2000) {
        if rr.max_element() <= 1e-24 * bb {
            break;
        }
        apply(&d, &mut ax);
        let dad = dot(&d, &ax);
        // Per coordinate step (three independent systems sharing A).
        let alpha = DVec3::select(dad.cmpgt(DVec3::ZERO), rr / dad, DVec3::ZERO);
        for i in 0..n {
            x[i] += alpha * d[i];
            r[i] -= alpha * ax[i];
        }
        let rr_new = dot(&r, &r);
        let beta = DVec3::select(rr.cmpgt(DVec3::ZERO), rr_new / rr, DVec3::ZERO);
        for i in 0..n {
            d[i] = r[i] + beta * d[i];
        }
        rr = rr_new;
    }
    // Harmonic positions can fold or flatten a triangle when a new vertex's neighbours are (nearly)
    // collinear loop vertices: move only as far towards them as keeps every fill triangle sound.
    let old: Vec<Vec3> = m.pos[first_new..].to_vec();
    let before: Vec<Vec3> = (first_fill..m.tris.len())
        .map(|t| {
            let [a, b, c] = m.tris[t].map(|v| m.pos[v as usize]);
            tri_cross(a, b, c)
        })
        .collect();
    let mut lambda = 1.0f64;
    for _ in 0..8 {
        for i in 0..n {
            let target = if x[i].is_finite() {
                x[i]
            } else {
                old[i].as_dvec3()
            };
            let o = old[i].as_dvec3();
            m.pos[first_new + i] = (o + lambda * (target - o)).as_vec3();
        }
        let sound = (first_fill..m.tris.len()).all(|t| {
            let [a, b, c] = m.tris[t].map(|v| m.pos[v as usize]);
            let now = tri_cross(a, b, c);
            let longest = (b - a)
                .length_squared()
                .max((c - b).length_squared())
                .max((a - c).length_squared());
            now.length() > 1e-3 * longest && now.dot(before[t - first_fill]) > 0.0
        });
        if sound {
            return;
        }
        lambda *= 0.5;
    }
    m.pos[first_new..].copy_from_slice(&old);
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used)]
mod tests {
    use super::*;

    /// A triangular hole 77 cm from the origin whose top side `A → B` (0.5 cm) is cut into
    /// `k` pieces by vertices `eps` off the line (0: exactly collinear in `f32`), its apex 1.5
    /// cm below (an 18.9° angle, the smallest of the loop), in a ring of quads around it.
    fn collinear_hole(k: usize, eps: f32) -> TriMesh {
        let (x0, apex) = (77.0f32, Vec3::new(77.25, -1.5, 0.0));
        let mut inner: Vec<Vec3> = (0..=k)
            .map(|i| {
                let y = if i == 0 || i == k { 0.0 } else { eps };
                Vec3::new(x0 + 0.5 * i as f32 / k as f32, y, 0.0)
            })
            .collect();
        inner.push(apex);
        let centre = inner.iter().sum::<Vec3>() / inner.len() as f32;
        let outer: Vec<Vec3> = inner
            .iter()
            .enumerate()
            .map(|(i, &p)| {
                if i <= k {
                    Vec3::new(x0 - 0.25 + 1.0 * i as f32 / k as f32, 0.5, 0.0)
                } else {
                    centre + (p - centre) * 2.0
                }
            })
            .collect();
        let n = inner.len() as u32;
        let mut positions = inner;
        positions.extend(outer);
        let mut triangles = Vec::new();
        for i in 0..n {
            let j = (i + 1) % n;
            for tri in [[i, j, n + j], [i, n + j, n + i]] {
                let [a, b, c] = tri.map(|v| positions[v as usize]);
                let ccw = (b - a).cross(c - a).z > 0.0;
                triangles.push(if ccw { tri } else { [tri[0], tri[2], tri[1]] });
            }
        }
        TriMesh::new(positions, triangles).unwrap()
    }

    /// The smallest `2·area / longest²` of the triangles from `first` on, in `f64`: 0 for a
    /// line, `√3/2` for an equilateral triangle.
    fn thinnest(mesh: &TriMesh, first: usize) -> f64 {
        (first..mesh.triangle_count())
            .map(|t| {
                let [a, b, c] = mesh.corners(t).map(|p| p.as_dvec3());
                let longest = (b - a)
                    .length_squared()
                    .max((c - b).length_squared())
                    .max((a - c).length_squared());
                (b - a).cross(c - a).length() / longest
            })
            .fold(f64::INFINITY, f64::min)
    }

    /// Ear clipping by smallest angle takes the apex first and is left with `A, M, B`: a
    /// zero-area triangle (an invalid result) when `M` is on the line, a sliver when it is a
    /// hair off it. The fill never makes either, far from the origin or not.
    #[test]
    fn a_hole_with_collinear_loop_vertices_far_from_the_origin_fills_without_slivers() {
        for k in [2, 3, 4, 8] {
            for eps in [0.0f32, 1e-9, -1e-9, 2e-6] {
                let mesh = collinear_hole(k, eps);
                let out =
                    fill_holes(&mesh, 2.0).unwrap_or_else(|e| panic!("k = {k}, eps = {eps}: {e}"));
                assert_eq!((out.filled.len(), out.open.len()), (1, 1), "k = {k}");
                assert_eq!(out.mesh.topology().boundary_loops().len(), 1);
                let floor = thinnest(&out.mesh, out.first_fill_triangle);
                assert!(
                    floor >= 5e-4,
                    "k = {k}, eps = {eps}: a fill triangle of height {floor:e} × its longest edge"
                );
            }
        }
    }

    /// The quality is 0 for a line and a fold, and the sine of the smallest angle for a
    /// triangle facing the loop's normal; the triangulation refuses a loop whose every
    /// triangulation is degenerate (three collinear vertices and one more on the line).
    #[test]
    fn the_quality_floor_refuses_degenerate_triangulations() {
        let z = DVec3::Z;
        let (a, b) = (DVec3::new(77.0, 0.0, 0.0), DVec3::new(78.0, 0.0, 0.0));
        let c = DVec3::new(77.5, 0.5 * 3f64.sqrt(), 0.0);
        assert!((quality(a, b, c, z) - 0.5 * 3f64.sqrt()).abs() < 1e-9);
        assert_eq!(quality(a, b, c, -z), 0.0);
        assert_eq!(quality(a, b, DVec3::new(77.5, 0.0, 0.0), z), 0.0);
        let line: Vec<Vec3> = (0..4)
            .map(|i| Vec3::new(77.0 + i as f32, 0.0, 0.0))
            .collect();
        let m = EditMesh::new(&line, &[]);
        assert_eq!(triangulate(&m, &[0, 1, 2, 3]), None);
    }
}
