//! Hole filling: ear clipping by smallest angle, refinement by edge splits and Delaunay flips,
//! harmonic (umbrella) fairing of the new vertices with the loop fixed.

use glam::{DVec3, Vec3};
use tissue_mesh::TriMesh;

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
/// Each filled loop is triangulated by ear clipping (always the ear with the smallest interior
/// angle, measured against the loop's Newell normal, whose new edge is not already an edge); fill
/// edges longer than 1.5 × the loop's mean edge are split and the fill is made Delaunay by flips,
/// then the new vertices are placed by harmonic (umbrella) fairing with the loop fixed, so the
/// patch is a smooth membrane; flips again after fairing. The result is a valid, consistently
/// oriented [`TriMesh`].
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
    let mut m = EditMesh::new(surface.positions(), surface.triangles());
    let mut filled = Vec::new();
    let mut open = Vec::new();
    for l in surface.topology().boundary_loops() {
        let hole = Hole::measure(surface.positions(), l);
        if hole.diameter > max_diameter || l.len() < 3 {
            open.push(hole);
            continue;
        }
        let Some(tris) = ear_clip(&m, l) else {
            tracing::warn!(
                vertices = l.len(),
                "no valid ear clipping for a hole; left open"
            );
            open.push(hole);
            continue;
        };
        let (hole_tris, hole_vertices) = (m.tris.len(), m.pos.len());
        let tau = (hole.perimeter / l.len() as f64) as f32;
        for &tri in &tris {
            m.add_triangle(tri);
        }
        refine(&mut m, hole_tris, tau);
        fair(&mut m, hole_vertices, hole_tris);
        delaunay_flips(&mut m, hole_tris);
        fair(&mut m, hole_vertices, hole_tris);
        if !sound(&m, hole_tris) {
            // Refinement made a sliver (it can on loops with long straight runs): keep the plain
            // ear clipping instead, which is sound by construction.
            tracing::warn!(
                vertices = l.len(),
                "refined hole fill unsound; ear clipping kept"
            );
            m.truncate(hole_tris, hole_vertices);
            for &tri in &tris {
                m.add_triangle(tri);
            }
        }
        filled.push(hole);
    }
    let (positions, triangles) = m.compact(true);
    let mesh = TriMesh::new(positions, triangles)
        .map_err(|source| RemeshError::InvalidResult { source })?;
    Ok(HoleFill {
        mesh,
        filled,
        open,
        first_fill_triangle: first_fill,
    })
}

/// Ear clipping of the loop `l` (as the surface traverses it): fill triangles traverse its edges
/// the other way. `None` when the loop repeats a vertex or no ear is valid at some step.
fn ear_clip(m: &EditMesh, l: &[u32]) -> Option<Vec<[u32; 3]>> {
    let n = l.len();
    let mut sorted = l.to_vec();
    sorted.sort_unstable();
    if sorted.windows(2).any(|w| w[0] == w[1]) {
        return None;
    }
    // The fill polygon: the loop reversed.
    let poly: Vec<u32> = l.iter().rev().copied().collect();
    let p: Vec<DVec3> = poly.iter().map(|&v| m.pos[v as usize].as_dvec3()).collect();
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
            let (pa, pb, pc) = (p[prev[i]], p[i], p[next[i]]);
            if (pb - pa).cross(pc - pa).length_squared() <= 1e-24 * (pc - pa).length_squared() {
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
/// each sweep, until none is left.
fn refine(m: &mut EditMesh, first_fill: usize, tau: f32) {
    for _round in 0..200 {
        let mut splits = 0;
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

/// Whether every fill triangle is clearly non-degenerate (height above 1e-4 of its longest edge).
fn sound(m: &EditMesh, first_fill: usize) -> bool {
    (first_fill..m.tris.len()).all(|t| {
        let [a, b, c] = m.tris[t].map(|v| m.pos[v as usize]);
        let longest = (b - a)
            .length_squared()
            .max((c - b).length_squared())
            .max((a - c).length_squared());
        tri_cross(a, b, c).length() > 1e-4 * longest
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
