//! The editable triangle mesh the remesher and the hole filler work on: flat arrays (positions,
//! triangles with an alive flag, vertex→triangles lists updated incrementally) and the three local
//! operations, edge split, edge collapse and edge flip, each keeping the surface a consistently
//! wound manifold.

use glam::Vec3;

/// Marks a missing triangle or vertex.
pub(crate) const NONE: u32 = u32::MAX;

/// An editable surface. Dead triangles and vertices stay in the arrays (flagged) until
/// [`EditMesh::compact`].
///
/// Invariants between operations: `vtris[v]` lists exactly the alive triangles containing `v`;
/// every edge of the alive triangles is in one or two of them, traversed in opposite directions;
/// `boundary[v]` is true exactly when `v` is on an edge with one triangle.
#[derive(Debug, Clone)]
pub(crate) struct EditMesh {
    pub pos: Vec<Vec3>,
    pub tris: Vec<[u32; 3]>,
    pub tri_alive: Vec<bool>,
    pub vtris: Vec<Vec<u32>>,
    pub v_alive: Vec<bool>,
    pub boundary: Vec<bool>,
    /// Vertices that are never moved or removed: unreferenced ones and those where two boundary
    /// loops touch (a "bowtie"), whose neighbourhood the local operations do not model.
    pub locked: Vec<bool>,
    stamp: Vec<u32>,
    stamp2: Vec<u32>,
    generation: u32,
}

/// Cross product of a triangle's sides (twice its area times its unit normal).
#[inline]
pub(crate) fn tri_cross(a: Vec3, b: Vec3, c: Vec3) -> Vec3 {
    (b - a).cross(c - a)
}

/// The vertex of `tri` that is neither `a` nor `b`.
#[inline]
pub(crate) fn opposite(tri: [u32; 3], a: u32, b: u32) -> u32 {
    if tri[0] != a && tri[0] != b {
        tri[0]
    } else if tri[1] != a && tri[1] != b {
        tri[1]
    } else {
        tri[2]
    }
}

/// Whether `tri` traverses `a → b`.
#[inline]
pub(crate) fn has_directed(tri: [u32; 3], a: u32, b: u32) -> bool {
    (tri[0] == a && tri[1] == b) || (tri[1] == a && tri[2] == b) || (tri[2] == a && tri[0] == b)
}

fn remove_value(list: &mut Vec<u32>, value: u32) {
    if let Some(i) = list.iter().position(|&x| x == value) {
        list.swap_remove(i);
    }
}

fn replace_value(list: &mut [u32], old: u32, new: u32) {
    if let Some(x) = list.iter_mut().find(|x| **x == old) {
        *x = new;
    }
}

fn replace_vertex(tri: &mut [u32; 3], old: u32, new: u32) {
    if let Some(x) = tri.iter_mut().find(|x| **x == old) {
        *x = new;
    }
}

impl EditMesh {
    /// From a valid surface's data.
    pub fn new(positions: &[Vec3], triangles: &[[u32; 3]]) -> EditMesh {
        let n = positions.len();
        let mut vtris: Vec<Vec<u32>> = vec![Vec::new(); n];
        for (t, tri) in triangles.iter().enumerate() {
            for &v in tri {
                vtris[v as usize].push(t as u32);
            }
        }
        let mut m = EditMesh {
            pos: positions.to_vec(),
            tris: triangles.to_vec(),
            tri_alive: vec![true; triangles.len()],
            vtris,
            v_alive: vec![true; n],
            boundary: vec![false; n],
            locked: vec![false; n],
            stamp: vec![0; n],
            stamp2: vec![0; n],
            generation: 0,
        };
        for v in 0..n as u32 {
            if m.vtris[v as usize].is_empty() {
                m.locked[v as usize] = true;
                continue;
            }
            let (outgoing, _) = m.boundary_sides(v);
            m.boundary[v as usize] = outgoing > 0;
            m.locked[v as usize] = outgoing > 1;
        }
        m
    }

    /// Number of boundary sides leaving `v` and one boundary neighbour after it (`v → next` is a
    /// boundary side), or `NONE`.
    fn boundary_sides(&self, v: u32) -> (usize, u32) {
        let mut count = 0;
        let mut next = NONE;
        for &t in &self.vtris[v as usize] {
            let tri = self.tris[t as usize];
            let i = tri.iter().position(|&x| x == v).unwrap_or(0);
            let w = tri[(i + 1) % 3];
            if self.edge_tris(v, w).1 == NONE {
                count += 1;
                next = w;
            }
        }
        (count, next)
    }

    /// The boundary neighbours `(prev, next)` of a boundary vertex: `prev → v → next` runs along
    /// the boundary in its triangles' direction. `None` for an interior or bowtie vertex.
    pub fn boundary_neighbours(&self, v: u32) -> Option<(u32, u32)> {
        let (mut prev, mut next) = (NONE, NONE);
        for &t in &self.vtris[v as usize] {
            let tri = self.tris[t as usize];
            let i = tri.iter().position(|&x| x == v)?;
            let after = tri[(i + 1) % 3];
            let before = tri[(i + 2) % 3];
            if self.edge_tris(v, after).1 == NONE {
                if next != NONE {
                    return None;
                }
                next = after;
            }
            if self.edge_tris(before, v).1 == NONE {
                if prev != NONE {
                    return None;
                }
                prev = before;
            }
        }
        (prev != NONE && next != NONE).then_some((prev, next))
    }

    /// The (up to two) alive triangles containing both `a` and `b`: `(NONE, NONE)` when `ab` is no
    /// edge, `(t, NONE)` on a boundary edge.
    #[inline]
    pub fn edge_tris(&self, a: u32, b: u32) -> (u32, u32) {
        let mut found = (NONE, NONE);
        for &t in &self.vtris[a as usize] {
            if self.tris[t as usize].contains(&b) {
                if found.0 == NONE {
                    found.0 = t;
                } else {
                    found.1 = t;
                    break;
                }
            }
        }
        found
    }

    /// Number of neighbours of `v`.
    #[inline]
    pub fn valence(&self, v: u32) -> usize {
        self.vtris[v as usize].len() + usize::from(self.boundary[v as usize])
    }

    /// Whether `a` and `b` share an edge.
    #[inline]
    pub fn adjacent(&self, a: u32, b: u32) -> bool {
        self.vtris[a as usize]
            .iter()
            .any(|&t| self.tris[t as usize].contains(&b))
    }

    /// Appends a vertex (no triangles yet).
    pub fn add_vertex(&mut self, p: Vec3, boundary: bool) -> u32 {
        let m = self.pos.len() as u32;
        self.pos.push(p);
        self.vtris.push(Vec::with_capacity(8));
        self.v_alive.push(true);
        self.boundary.push(boundary);
        self.locked.push(false);
        self.stamp.push(0);
        self.stamp2.push(0);
        m
    }

    /// Appends a triangle and registers it with its vertices.
    pub fn add_triangle(&mut self, tri: [u32; 3]) -> u32 {
        let t = self.tris.len() as u32;
        self.tris.push(tri);
        self.tri_alive.push(true);
        for v in tri {
            self.vtris[v as usize].push(t);
        }
        t
    }

    /// Removes the triangles from `tri_len` on and the vertices from `vert_len` on (which only
    /// those triangles may use): undoes a sequence of additions and splits confined to them.
    pub fn truncate(&mut self, tri_len: usize, vert_len: usize) {
        for t in tri_len..self.tris.len() {
            for v in self.tris[t] {
                if (v as usize) < vert_len {
                    self.vtris[v as usize].retain(|&x| (x as usize) < tri_len);
                }
            }
        }
        self.tris.truncate(tri_len);
        self.tri_alive.truncate(tri_len);
        for list in [&mut self.v_alive, &mut self.boundary, &mut self.locked] {
            list.truncate(vert_len);
        }
        self.pos.truncate(vert_len);
        self.vtris.truncate(vert_len);
        self.stamp.truncate(vert_len);
        self.stamp2.truncate(vert_len);
    }

    /// Splits edge `ab` at `p`; returns the new vertex. Each triangle `t` of the edge keeps `a`
    /// (its `b` becomes the new vertex) and a new triangle, appended, takes the `b` side.
    pub fn split(&mut self, a: u32, b: u32, p: Vec3) -> u32 {
        let (t1, t2) = self.edge_tris(a, b);
        let m = self.add_vertex(p, t2 == NONE);
        for t in [t1, t2] {
            if t == NONE {
                continue;
            }
            let old = self.tris[t as usize];
            let x = opposite(old, a, b);
            let mut new_tri = old;
            replace_vertex(&mut new_tri, a, m);
            replace_vertex(&mut self.tris[t as usize], b, m);
            let nt = self.tris.len() as u32;
            self.tris.push(new_tri);
            self.tri_alive.push(true);
            replace_value(&mut self.vtris[b as usize], t, nt);
            self.vtris[x as usize].push(nt);
            let mv = &mut self.vtris[m as usize];
            mv.push(t);
            mv.push(nt);
        }
        m
    }

    /// Collapses edge `rk`: vertex `r` is removed, `k` kept and moved to `p`, if the collapse keeps
    /// the surface's topology (link condition, no vertex left with too few neighbours) and its
    /// geometry (no new edge longer than `max_edge`, no changed triangle turning by more than
    /// `acos(min_dot)` or becoming degenerate). Returns whether it collapsed.
    pub fn try_collapse(&mut self, r: u32, k: u32, p: Vec3, max_edge: f32, min_dot: f32) -> bool {
        let (t1, t2) = self.edge_tris(r, k);
        if t1 == NONE {
            return false;
        }
        // Link condition: the common neighbours are exactly the opposite vertices.
        self.generation = self.generation.wrapping_add(1);
        if self.generation == 0 {
            self.stamp.fill(0);
            self.stamp2.fill(0);
            self.generation = 1;
        }
        let g = self.generation;
        for &t in &self.vtris[k as usize] {
            for w in self.tris[t as usize] {
                self.stamp[w as usize] = g;
            }
        }
        let mut common = 0;
        for &t in &self.vtris[r as usize] {
            for w in self.tris[t as usize] {
                if w != r && w != k && self.stamp[w as usize] == g && self.stamp2[w as usize] != g {
                    self.stamp2[w as usize] = g;
                    common += 1;
                }
            }
        }
        let expected = if t2 == NONE { 1 } else { 2 };
        if common != expected {
            return false;
        }
        for t in [t1, t2] {
            if t == NONE {
                continue;
            }
            let x = opposite(self.tris[t as usize], r, k);
            let minimum = if self.boundary[x as usize] { 2 } else { 3 };
            if self.valence(x) <= minimum {
                return false;
            }
        }
        // A closed component as small as a tetrahedron would collapse onto itself.
        if t2 != NONE
            && self.vtris[r as usize].len() + self.vtris[k as usize].len() <= 6
            && !self.boundary[r as usize]
            && !self.boundary[k as usize]
        {
            return false;
        }
        let max2 = max_edge * max_edge;
        for (moved, other) in [(r, k), (k, r)] {
            for &t in &self.vtris[moved as usize] {
                let tri = self.tris[t as usize];
                if tri.contains(&other) {
                    continue;
                }
                let old = tri.map(|v| self.pos[v as usize]);
                let mut new = old;
                for i in 0..3 {
                    if tri[i] == moved {
                        new[i] = p;
                    } else if (self.pos[tri[i] as usize] - p).length_squared() > max2 {
                        return false;
                    }
                }
                let n_old = tri_cross(old[0], old[1], old[2]);
                let n_new = tri_cross(new[0], new[1], new[2]);
                let (lo, ln) = (n_old.length(), n_new.length());
                let longest = (new[1] - new[0])
                    .length_squared()
                    .max((new[2] - new[1]).length_squared())
                    .max((new[0] - new[2]).length_squared());
                if ln.is_nan() || ln <= 1e-4 * longest || n_old.dot(n_new) < min_dot * lo * ln {
                    return false;
                }
            }
        }
        // Commit.
        for t in [t1, t2] {
            if t == NONE {
                continue;
            }
            self.tri_alive[t as usize] = false;
            for v in self.tris[t as usize] {
                if v != r {
                    remove_value(&mut self.vtris[v as usize], t);
                }
            }
        }
        let moved = std::mem::take(&mut self.vtris[r as usize]);
        for &t in &moved {
            if self.tri_alive[t as usize] {
                replace_vertex(&mut self.tris[t as usize], r, k);
                self.vtris[k as usize].push(t);
            }
        }
        // Give the (empty) list back its capacity's worth of nothing: keep the memory dropped.
        drop(moved);
        self.v_alive[r as usize] = false;
        self.pos[k as usize] = p;
        true
    }

    /// Flips interior edge `ab` of triangles `t1` (`a → b`) and `t2` (`b → a`) to `cd`.
    pub fn flip(&mut self, a: u32, b: u32, t1: u32, t2: u32) {
        let c = opposite(self.tris[t1 as usize], a, b);
        let d = opposite(self.tris[t2 as usize], a, b);
        self.tris[t1 as usize] = [c, a, d];
        self.tris[t2 as usize] = [d, b, c];
        remove_value(&mut self.vtris[a as usize], t2);
        remove_value(&mut self.vtris[b as usize], t1);
        self.vtris[c as usize].push(t2);
        self.vtris[d as usize].push(t1);
    }

    /// Whether flipping interior edge `ab` (triangles `t1` with `a → b`, `t2`) keeps both new
    /// triangles turned by less than `acos(min_dot)` from the old pair's mean normal, and
    /// non-degenerate. Topological checks are the caller's.
    pub fn flip_is_flat(&self, a: u32, b: u32, t1: u32, t2: u32, min_dot: f32) -> bool {
        let c = opposite(self.tris[t1 as usize], a, b);
        let d = opposite(self.tris[t2 as usize], a, b);
        let [pa, pb, pc, pd] = [a, b, c, d].map(|v| self.pos[v as usize]);
        let old = (tri_cross(pa, pb, pc).normalize_or_zero()
            + tri_cross(pb, pa, pd).normalize_or_zero())
        .normalize_or_zero();
        for n in [tri_cross(pc, pa, pd), tri_cross(pd, pb, pc)] {
            let len = n.length();
            let longest = (pc - pd).length_squared().max((pa - pb).length_squared());
            if len.is_nan() || len <= 1e-4 * longest || old.dot(n) < min_dot * len {
                return false;
            }
        }
        true
    }

    /// Orders a triangle pair of edge `ab` so that the first traverses `a → b`.
    #[inline]
    pub fn oriented_pair(&self, a: u32, b: u32, t1: u32, t2: u32) -> (u32, u32) {
        if has_directed(self.tris[t1 as usize], a, b) {
            (t1, t2)
        } else {
            (t2, t1)
        }
    }

    /// Alive vertices renumbered in order (dead ones and those with no triangle dropped, unless
    /// `keep_all_vertices`), alive triangles in order.
    #[allow(clippy::needless_range_loop)] // v indexes four parallel arrays
    pub fn compact(&self, keep_all_vertices: bool) -> (Vec<Vec3>, Vec<[u32; 3]>) {
        let mut map = vec![NONE; self.pos.len()];
        let mut positions = Vec::new();
        for v in 0..self.pos.len() {
            let used = self.v_alive[v] && (keep_all_vertices || !self.vtris[v].is_empty());
            if used {
                map[v] = positions.len() as u32;
                positions.push(self.pos[v]);
            }
        }
        let triangles = self
            .tris
            .iter()
            .zip(&self.tri_alive)
            .filter(|(_, &alive)| alive)
            .map(|(tri, _)| tri.map(|v| map[v as usize]))
            .collect();
        (positions, triangles)
    }

    /// Checks the invariants listed on [`EditMesh`] (tests only).
    #[cfg(test)]
    pub fn check(&self) {
        for (v, list) in self.vtris.iter().enumerate() {
            for &t in list {
                assert!(
                    self.tri_alive[t as usize],
                    "vertex {v} lists dead triangle {t}"
                );
                assert!(self.tris[t as usize].contains(&(v as u32)));
            }
        }
        for (t, tri) in self.tris.iter().enumerate() {
            if !self.tri_alive[t] {
                continue;
            }
            for i in 0..3 {
                let (a, b) = (tri[i], tri[(i + 1) % 3]);
                assert!(self.vtris[a as usize].contains(&(t as u32)));
                let (t1, t2) = self.edge_tris(a, b);
                if t2 != NONE {
                    let other = if t1 == t as u32 { t2 } else { t1 };
                    assert!(has_directed(self.tris[other as usize], b, a));
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square() -> EditMesh {
        EditMesh::new(
            &[Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y],
            &[[0, 1, 2], [0, 2, 3]],
        )
    }

    #[test]
    fn split_flip_collapse_keep_a_manifold() {
        let mut m = square();
        assert!(m.boundary.iter().all(|&b| b));
        let c = m.split(0, 2, Vec3::new(0.3, 0.6, 0.0));
        m.check();
        assert!(!m.boundary[c as usize]);
        assert_eq!(m.valence(c), 4);
        let e = m.split(0, 1, Vec3::new(0.5, 0.0, 0.0));
        m.check();
        assert!(m.boundary[e as usize]);
        // Flipping c–e would put 0–1 through e: flat, refused.
        let (t1, t2) = m.edge_tris(c, e);
        let (t1, t2) = m.oriented_pair(c, e, t1, t2);
        assert!(!m.flip_is_flat(c, e, t1, t2, 0.0));
        // Flipping c–1 makes e–2, a sound flip; flipping it back restores c–1.
        let (t1, t2) = m.edge_tris(c, 1);
        let (t1, t2) = m.oriented_pair(c, 1, t1, t2);
        assert!(m.flip_is_flat(c, 1, t1, t2, 0.0));
        m.flip(c, 1, t1, t2);
        m.check();
        assert!(m.adjacent(e, 2) && !m.adjacent(c, 1));
        let (s1, s2) = m.edge_tris(e, 2);
        let (s1, s2) = m.oriented_pair(e, 2, s1, s2);
        m.flip(e, 2, s1, s2);
        m.check();
        assert!(m.adjacent(c, 1));
        // Collapse the centre onto corner 2.
        assert!(m.try_collapse(c, 2, Vec3::new(1.0, 1.0, 0.0), 10.0, 0.0));
        m.check();
        let (p, t) = m.compact(false);
        assert!(tissue_mesh::TriMesh::new(p, t).is_ok());
    }

    #[test]
    fn collapse_refuses_to_break_a_triangle_hole() {
        // A single triangle: every collapse would leave a degenerate surface.
        let mut m = EditMesh::new(&[Vec3::ZERO, Vec3::X, Vec3::Y], &[[0, 1, 2]]);
        assert!(!m.try_collapse(1, 0, Vec3::ZERO, 10.0, 0.0));
    }
}
