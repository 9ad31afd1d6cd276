//! After carving: recover surface triangles and remove slivers by *edge removal*, then peel the
//! boundary slivers that are left.
//!
//! Edge removal (as in Shewchuk's "topological improvement" of tetrahedral meshes): the
//! tetrahedra around an edge `bd` form a ring whose other vertices make a polygon
//! `P₀ … Pₘ₋₁`. Replacing them by the tetrahedra `(Pᵢ, Pₖ, Pⱼ, d)` and `(Pᵢ, Pⱼ, Pₖ, b)` over a
//! triangulation of the polygon removes the edge. The triangulation that maximises the smallest
//! radius ratio is found by dynamic programming over the polygon (Klincsek); it is used only if
//! every new tetrahedron is positively oriented (exact test) and not flat.
//!
//! Two uses:
//! 1. *Surface recovery.* Where the surface has triangles `abc`, `acd` but the carved mesh has
//!    the other diagonal `bd` of that quad, the tetrahedra around `bd` — an open ring from `a`
//!    to `c` (the quad is a dent or bump of the boundary) or a closed one through the sliver
//!    `abcd` — are replaced over the polygon closed by the edge `ca`, which makes `abc` and
//!    `acd` boundary faces. An open ring changes the volume by the thin tetrahedron `abcd`,
//!    towards the surface.
//! 2. *Sliver removal.* For each tetrahedron with a radius ratio under the threshold, its edges
//!    with a closed ring are tried; a removal is kept only when it raises the smallest radius
//!    ratio of the ring. The boundary and the volume do not change.
//!
//! Peeling: a boundary tetrahedron still under the sliver threshold is removed if that does not
//! lose surface triangles from the boundary; one under the (much smaller) degenerate threshold
//! is removed even if it does. Neither may leave a surface vertex without tetrahedra.

use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};

use glam::DVec3;
use tissue_mesh::{TriMesh, TET_FACES, ZERO_VOLUME_TOLERANCE};

use crate::predicates::{orient, P3};
use crate::quality::tet_quality;

/// A small multiplicative hasher for integer keys (the std SipHash is 3× slower here).
#[derive(Default)]
struct FastHasher(u64);

impl Hasher for FastHasher {
    fn finish(&self) -> u64 {
        self.0
    }
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.write_u64(u64::from(b));
        }
    }
    fn write_u32(&mut self, i: u32) {
        self.write_u64(u64::from(i));
    }
    fn write_u64(&mut self, i: u64) {
        self.0 = (self.0.rotate_left(5) ^ i).wrapping_mul(0x51_7c_c1_b7_27_22_0a_95);
    }
    fn write_usize(&mut self, i: usize) {
        self.write_u64(i as u64);
    }
}

type FastMap<K, V> = HashMap<K, V, BuildHasherDefault<FastHasher>>;

const NONE: u32 = u32::MAX;

fn sorted3(mut f: [u32; 3]) -> [u32; 3] {
    f.sort_unstable();
    f
}

/// `true` when `TetMesh::new` would reject the tetrahedron as flat (with a margin of 2).
pub(crate) fn is_flat(p: [DVec3; 4]) -> bool {
    let six_v = (p[1] - p[0]).cross(p[2] - p[0]).dot(p[3] - p[0]);
    let mut longest: f64 = 0.0;
    for i in 0..4 {
        for j in i + 1..4 {
            longest = longest.max((p[i] - p[j]).length_squared());
        }
    }
    six_v <= 2.0 * ZERO_VOLUME_TOLERANCE * longest.sqrt().powi(3)
}

/// What the improvement did.
#[derive(Debug, Default, Clone, Copy)]
pub(crate) struct ImproveStats {
    pub recovered_quads: usize,
    pub sliver_edges_removed: usize,
    pub peeled: usize,
    pub flat_dropped: usize,
}

/// A mutable tetrahedral mesh with face adjacency, for local changes.
struct Work<'a> {
    pts: &'a [P3],
    tets: Vec<[u32; 4]>,
    alive: Vec<bool>,
    /// Sorted face → the (one or two) live tetrahedra that have it.
    faces: FastMap<[u32; 3], [u32; 2]>,
    /// Vertex → tetrahedra that had it (dead ones skipped on read).
    vt: Vec<Vec<u32>>,
}

/// The ring of tetrahedra around an edge.
struct Ring {
    b: u32,
    d: u32,
    tets: Vec<u32>,
    /// Polygon vertices, in the order where `orient(b, d, Pᵢ, Pᵢ₊₁) > 0`.
    poly: Vec<u32>,
    closed: bool,
}

impl<'a> Work<'a> {
    fn new(pts: &'a [P3], tets: Vec<[u32; 4]>) -> Self {
        let mut w = Work {
            pts,
            alive: vec![true; tets.len()],
            tets: Vec::with_capacity(tets.len()),
            faces: FastMap::default(),
            vt: vec![Vec::new(); pts.len()],
        };
        w.faces.reserve(tets.len() * 3);
        w.alive.clear();
        for t in tets {
            w.add(t);
        }
        w
    }

    fn p(&self, v: u32) -> DVec3 {
        DVec3::from_array(self.pts[v as usize])
    }

    fn corners(&self, t: &[u32; 4]) -> [DVec3; 4] {
        t.map(|v| self.p(v))
    }

    fn quality(&self, t: &[u32; 4]) -> f64 {
        tet_quality(self.corners(t)).1
    }

    fn add(&mut self, tet: [u32; 4]) -> u32 {
        let id = self.tets.len() as u32;
        self.tets.push(tet);
        self.alive.push(true);
        for f in TET_FACES {
            let e = self
                .faces
                .entry(sorted3(f.map(|i| tet[i])))
                .or_insert([NONE; 2]);
            if e[0] == NONE {
                e[0] = id;
            } else {
                e[1] = id;
            }
        }
        for &v in &tet {
            self.vt[v as usize].push(id);
        }
        id
    }

    fn remove(&mut self, id: u32) {
        self.alive[id as usize] = false;
        let tet = self.tets[id as usize];
        for f in TET_FACES {
            let key = sorted3(f.map(|i| tet[i]));
            if let Some(e) = self.faces.get_mut(&key) {
                if e[0] == id {
                    e[0] = e[1];
                }
                e[1] = NONE;
                if e[0] == NONE {
                    self.faces.remove(&key);
                }
            }
        }
        for &v in &tet {
            self.vt[v as usize].retain(|&t| t != id);
        }
    }

    /// Live tetrahedra on face `f` (sorted key).
    fn on_face(&self, key: &[u32; 3]) -> [u32; 2] {
        self.faces.get(key).copied().unwrap_or([NONE; 2])
    }

    fn is_boundary_face(&self, key: &[u32; 3]) -> bool {
        let e = self.on_face(key);
        e[0] != NONE && e[1] == NONE
    }

    /// The tetrahedron across the face `(b, d, x)` from `t`.
    fn across(&self, t: u32, b: u32, d: u32, x: u32) -> u32 {
        let e = self.on_face(&sorted3([b, d, x]));
        if e[0] == t {
            e[1]
        } else {
            e[0]
        }
    }

    fn ring(&self, b: u32, d: u32) -> Option<Ring> {
        let &t0 = self.vt[b as usize]
            .iter()
            .find(|&&t| self.tets[t as usize].contains(&d))?;
        let others = |t: u32| -> [u32; 2] {
            let v = self.tets[t as usize];
            let mut o = [NONE; 2];
            let mut k = 0;
            for x in v {
                if x != b && x != d {
                    o[k] = x;
                    k += 1;
                }
            }
            o
        };
        let [mut x, mut y] = others(t0);
        if orient(
            &self.pts[b as usize],
            &self.pts[d as usize],
            &self.pts[x as usize],
            &self.pts[y as usize],
        ) < 0.0
        {
            std::mem::swap(&mut x, &mut y);
        }
        // Forward from y.
        let mut tets = vec![t0];
        let mut poly = vec![x, y];
        let mut t = t0;
        let mut last = y;
        let mut closed = false;
        loop {
            let n = self.across(t, b, d, last);
            if n == NONE {
                break;
            }
            if n == t0 {
                closed = true;
                break;
            }
            let [p, q] = others(n);
            let next = if p == last { q } else { p };
            tets.push(n);
            t = n;
            last = next;
            if next != x {
                poly.push(next);
            }
            if tets.len() > 64 {
                return None;
            }
        }
        if closed {
            // `poly` ends with the vertex before x; the last tet links back to t0.
            return Some(Ring {
                b,
                d,
                tets,
                poly,
                closed,
            });
        }
        // Backward from x.
        let mut front: Vec<u32> = Vec::new();
        let mut t = t0;
        let mut last = x;
        loop {
            let n = self.across(t, b, d, last);
            if n == NONE {
                break;
            }
            let [p, q] = others(n);
            let next = if p == last { q } else { p };
            tets.push(n);
            front.push(next);
            t = n;
            last = next;
            if tets.len() > 64 {
                return None;
            }
        }
        front.reverse();
        front.extend_from_slice(&poly);
        Some(Ring {
            b,
            d,
            tets,
            poly: front,
            closed,
        })
    }

    /// The best triangulation of `poly` (closed by its edge from last to first) for the two
    /// apexes: the new tetrahedra and their smallest radius ratio, or `None` when no
    /// triangulation gives only positive, non-flat tetrahedra.
    fn triangulate(&self, b: u32, d: u32, poly: &[u32]) -> Option<(f64, Vec<[u32; 4]>)> {
        let n = poly.len();
        if !(3..=12).contains(&n) {
            return None;
        }
        let tq = |i: usize, k: usize, j: usize| -> f64 {
            let (pi, pk, pj) = (poly[i], poly[k], poly[j]);
            let td = [pi, pk, pj, d];
            let tb = [pi, pj, pk, b];
            let mut q = f64::INFINITY;
            for t in [td, tb] {
                let c = self.corners(&t);
                let p = t.map(|v| &self.pts[v as usize]);
                if orient(p[0], p[1], p[2], p[3]) <= 0.0 || is_flat(c) {
                    return f64::NEG_INFINITY;
                }
                q = q.min(tet_quality(c).1);
            }
            q
        };
        let mut best = vec![f64::NEG_INFINITY; n * n];
        let mut split = vec![0usize; n * n];
        for i in 0..n - 1 {
            best[i * n + i + 1] = f64::INFINITY;
        }
        for len in 2..n {
            for i in 0..n - len {
                let j = i + len;
                for k in i + 1..j {
                    let q = best[i * n + k].min(best[k * n + j]).min(tq(i, k, j));
                    if q > best[i * n + j] {
                        best[i * n + j] = q;
                        split[i * n + j] = k;
                    }
                }
            }
        }
        let q = best[n - 1];
        if q == f64::NEG_INFINITY {
            return None;
        }
        let mut out = Vec::new();
        let mut stack = vec![(0usize, n - 1)];
        while let Some((i, j)) = stack.pop() {
            if j < i + 2 {
                continue;
            }
            let k = split[i * n + j];
            out.push([poly[i], poly[k], poly[j], d]);
            out.push([poly[i], poly[j], poly[k], b]);
            stack.push((i, k));
            stack.push((k, j));
        }
        Some((q, out))
    }

    /// Replaces `old` by `new` unless that would put a face on three tetrahedra.
    fn replace(&mut self, old: &[u32], new: &[[u32; 4]]) -> bool {
        let mut count: FastMap<[u32; 3], u32> = FastMap::default();
        for t in new {
            for f in TET_FACES {
                *count.entry(sorted3(f.map(|i| t[i]))).or_insert(0) += 1;
            }
        }
        for (key, &c) in &count {
            let e = self.on_face(key);
            let mut existing = e.iter().filter(|&&t| t != NONE && !old.contains(&t));
            match (existing.next(), existing.next(), c) {
                (None, _, _) => {}
                (Some(_), Some(_), _) | (Some(_), None, 2..) => return false,
                (Some(&other), None, _) => {
                    // The new tet on this face must lie on the other side from `other`.
                    let Some(mine) = new.iter().find(|t| {
                        let mut k = **t;
                        k.sort_unstable();
                        key.iter().all(|v| k.binary_search(v).is_ok())
                    }) else {
                        return false;
                    };
                    let apex = |t: &[u32; 4]| t.iter().copied().find(|v| !key.contains(v));
                    let ot = self.tets[other as usize];
                    let (Some(a1), Some(a2)) = (apex(mine), apex(&ot)) else {
                        return false;
                    };
                    let f = key.map(|v| &self.pts[v as usize]);
                    let s1 = orient(f[0], f[1], f[2], &self.pts[a1 as usize]);
                    let s2 = orient(f[0], f[1], f[2], &self.pts[a2 as usize]);
                    if s1 * s2 >= 0.0 {
                        return false;
                    }
                }
            }
        }
        for &t in old {
            self.remove(t);
        }
        for &t in new {
            self.add(t);
        }
        true
    }

    fn live(&self) -> impl Iterator<Item = u32> + '_ {
        (0..self.tets.len() as u32).filter(|&t| self.alive[t as usize])
    }
}

/// Runs recovery, sliver removal and peeling on the carved tetrahedra (indices into `pts`;
/// surface vertices are `0..surface.vertex_count()`).
pub(crate) fn improve(
    pts: &[P3],
    tets: Vec<[u32; 4]>,
    surface: &TriMesh,
    sliver_ratio: f64,
    degenerate_ratio: f64,
) -> (Vec<[u32; 4]>, ImproveStats) {
    let mut w = Work::new(pts, tets);
    let mut stats = ImproveStats::default();
    let n_surface = surface.vertex_count();
    let tris = surface.triangles();
    let topo = surface.topology();

    // 1. Surface recovery, a few passes (a removal can make another quad recoverable).
    {
        let _s = tracing::debug_span!("recover").entered();
        for _pass in 0..3 {
            let mut changed = 0;
            for (e, &[t1, t2]) in topo.edge_triangles().iter().enumerate() {
                let [a, c] = topo.edges()[e];
                let k1 = sorted3(tris[t1 as usize]);
                let k2 = sorted3(tris[t2 as usize]);
                if w.is_boundary_face(&k1) && w.is_boundary_face(&k2) {
                    continue;
                }
                let opposite = |t: u32| {
                    tris[t as usize]
                        .iter()
                        .copied()
                        .find(|&v| v != a && v != c)
                        .unwrap_or(NONE)
                };
                let (b, d) = (opposite(t1), opposite(t2));
                if b == NONE || d == NONE {
                    continue;
                }
                let Some(ring) = w.ring(b, d) else { continue };
                // Rotate the polygon so that it runs from a to c (or c to a) with the closing
                // edge between them.
                let m = ring.poly.len();
                let Some(ia) = ring.poly.iter().position(|&v| v == a) else {
                    continue;
                };
                let Some(ic) = ring.poly.iter().position(|&v| v == c) else {
                    continue;
                };
                let poly: Vec<u32> = if ring.closed {
                    // The tet between a and c in the ring must be the sliver abcd.
                    let adjacent_ca = (ic + 1) % m == ia;
                    let adjacent_ac = (ia + 1) % m == ic;
                    if adjacent_ca {
                        (0..m).map(|k| ring.poly[(ia + k) % m]).collect()
                    } else if adjacent_ac {
                        (0..m).map(|k| ring.poly[(ic + k) % m]).collect()
                    } else {
                        continue;
                    }
                } else {
                    let ends = (ring.poly[0], ring.poly[m - 1]);
                    if ends != (a, c) && ends != (c, a) {
                        continue;
                    }
                    ring.poly.clone()
                };
                let Some((q, new)) = w.triangulate(ring.b, ring.d, &poly) else {
                    continue;
                };
                if q < 1e-3 {
                    continue;
                }
                if w.replace(&ring.tets, &new) {
                    changed += 1;
                }
            }
            stats.recovered_quads += changed;
            if changed == 0 {
                break;
            }
        }
    }

    // 2. Sliver removal by edge removal over closed rings.
    {
        let _s = tracing::debug_span!("slivers").entered();
        for _pass in 0..2 {
            let mut changed = 0;
            let bad: Vec<u32> = w
                .live()
                .filter(|&t| w.quality(&w.tets[t as usize]) < 0.1)
                .collect();
            for t in bad {
                if !w.alive[t as usize] {
                    continue;
                }
                let v = w.tets[t as usize];
                let mut best: Option<(f64, Vec<u32>, Vec<[u32; 4]>)> = None;
                for i in 0..4 {
                    for j in i + 1..4 {
                        let Some(ring) = w.ring(v[i], v[j]) else {
                            continue;
                        };
                        if !ring.closed {
                            continue;
                        }
                        let old_q = ring
                            .tets
                            .iter()
                            .map(|&t| w.quality(&w.tets[t as usize]))
                            .fold(f64::INFINITY, f64::min);
                        let Some((q, new)) = w.triangulate(ring.b, ring.d, &ring.poly) else {
                            continue;
                        };
                        if q > old_q && best.as_ref().is_none_or(|b| q > b.0) {
                            best = Some((q, ring.tets.clone(), new));
                        }
                    }
                }
                if let Some((_, old, new)) = best {
                    if w.replace(&old, &new) {
                        changed += 1;
                    }
                }
            }
            stats.sliver_edges_removed += changed;
            if changed == 0 {
                break;
            }
        }
    }

    // 3. Peel boundary slivers that cost no surface triangle and orphan no surface vertex.
    {
        let _s = tracing::debug_span!("peel").entered();
        let mut surface_keys: FastMap<[u32; 3], ()> = FastMap::default();
        for &t in tris {
            surface_keys.insert(sorted3(t), ());
        }
        let mut stack: Vec<u32> = w.live().collect();
        while let Some(t) = stack.pop() {
            if !w.alive[t as usize] {
                continue;
            }
            let v = w.tets[t as usize];
            let flat = is_flat(w.corners(&v));
            let q = w.quality(&v);
            if !flat && q >= sliver_ratio {
                continue;
            }
            let degenerate = flat || q < degenerate_ratio;
            // Boundary faces that are surface triangles now, and faces that would become ones.
            let mut lost = 0;
            let mut gained = 0;
            let mut on_boundary = false;
            for f in TET_FACES {
                let key = sorted3(f.map(|i| v[i]));
                let e = w.on_face(&key);
                let boundary = e[1] == NONE;
                on_boundary |= boundary;
                if surface_keys.contains_key(&key) {
                    if boundary {
                        lost += 1;
                    } else {
                        gained += 1;
                    }
                }
            }
            if !on_boundary {
                continue;
            }
            let orphan = v.iter().any(|&x| {
                (x as usize) < n_surface
                    && w.vt[x as usize]
                        .iter()
                        .filter(|&&s| w.alive[s as usize])
                        .count()
                        == 1
            });
            if orphan || (lost > gained && !degenerate) {
                continue;
            }
            w.remove(t);
            stats.peeled += 1;
            for f in TET_FACES {
                let key = sorted3(f.map(|i| v[i]));
                let e = w.on_face(&key);
                if e[0] != NONE {
                    stack.push(e[0]);
                }
            }
        }
    }

    // 4. Flat tetrahedra left inside: `TetMesh` would refuse them.
    let dead: Vec<u32> = w
        .live()
        .filter(|&t| is_flat(w.corners(&w.tets[t as usize])))
        .collect();
    stats.flat_dropped = dead.len();
    for t in dead {
        w.remove(t);
    }
    let out = w.live().map(|t| w.tets[t as usize]).collect();
    (out, stats)
}
