//! Incremental Delaunay tetrahedralisation (Bowyer–Watson) inside a bounding super-tetrahedron.
//!
//! Data: one `[u32; 4]` per tetrahedron (positively oriented, tissue's convention) and one
//! `[u32; 4]` of neighbours, entry `i` across the face opposite local vertex `i` (faces as
//! [`tissue_mesh::TET_FACES`]). Dead slots go to a free list and are reused.
//!
//! Insertion of point `p`:
//! 1. *Locate*: a visibility walk from the last tetrahedron made, crossing any face whose outer
//!    side holds `p` (faces tried from a rotating start so the walk cannot cycle). Points come in
//!    spatially sorted order, so walks are a few steps long.
//! 2. *Cavity*: breadth-first from the containing tetrahedron over neighbours whose circumsphere
//!    holds `p` ([`in_sphere`], exact with symbolically broken ties).
//! 3. *Fill*: every face of the cavity's boundary makes a new tetrahedron with `p`, which takes
//!    the place of the cavity tetrahedron's vertex opposite that face (so it is positively
//!    oriented); new tetrahedra are linked to each other through the boundary edges they share.
//!
//! With exact predicates the cavity is star-shaped from `p`, so every new tetrahedron has
//! positive volume. Coincident points must not be inserted (the caller removes them).

use tissue_mesh::TET_FACES;

use crate::predicates::{in_sphere, orient, P3};

/// No neighbour (the outer faces of the super-tetrahedron).
pub(crate) const NONE: u32 = u32::MAX;

/// What went wrong inside the triangulator: only reachable through a numerical failure.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum DelaunayFailure {
    /// The walk to `point` did not end.
    WalkDidNotEnd { point: u32 },
    /// The walk to `point` left the super-tetrahedron.
    OutsideSuperTet { point: u32 },
    /// The cavity of `point` did not have a closed boundary.
    OpenCavity { point: u32 },
}

/// The triangulation under construction.
pub(crate) struct Delaunay {
    /// All points: the caller's, then the four super-tetrahedron corners.
    pub pts: Vec<P3>,
    pub tets: Vec<[u32; 4]>,
    pub nbr: Vec<[u32; 4]>,
    pub dead: Vec<bool>,
    /// Index of the first super-tetrahedron corner (= number of the caller's points).
    pub super_start: u32,
    free: Vec<u32>,
    visit: Vec<u32>,
    in_cavity: Vec<bool>,
    stamp: u32,
    cavity: Vec<u32>,
    boundary: Vec<(u32, u8)>,
    made: Vec<([u32; 4], u8, u32)>,
    links: Vec<(u64, u32, u8)>,
    last: u32,
    rng: u32,
    /// Total walk steps, cavity tets (for the trace).
    pub walk_steps: u64,
    pub cavity_tets: u64,
}

impl Delaunay {
    /// A triangulation of the four corners of a tetrahedron enclosing `pts` with a wide margin.
    /// `pts` must be finite and not empty.
    pub fn new(mut pts: Vec<P3>) -> Self {
        let n = pts.len();
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for p in &pts {
            for k in 0..3 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        let centre = [0, 1, 2].map(|k| 0.5 * (lo[k] + hi[k]));
        let radius = (0..3)
            .map(|k| (hi[k] - lo[k]).powi(2))
            .sum::<f64>()
            .sqrt()
            .max(1e-3);
        // Regular tetrahedron with inradius r·100/√3 ≫ the points' radius.
        let r = 100.0 * radius;
        let corners = [
            [1.0, 1.0, 1.0],
            [1.0, -1.0, -1.0],
            [-1.0, 1.0, -1.0],
            [-1.0, -1.0, 1.0],
        ];
        for c in corners {
            pts.push([0, 1, 2].map(|k| centre[k] + r * c[k]));
        }
        let s = n as u32;
        let mut tet = [s, s + 1, s + 2, s + 3];
        if orient(
            &pts[tet[0] as usize],
            &pts[tet[1] as usize],
            &pts[tet[2] as usize],
            &pts[tet[3] as usize],
        ) < 0.0
        {
            tet.swap(0, 1);
        }
        let cap = 7 * n + 16;
        let mut tets = Vec::with_capacity(cap);
        let mut nbr = Vec::with_capacity(cap);
        tets.push(tet);
        nbr.push([NONE; 4]);
        Delaunay {
            pts,
            tets,
            nbr,
            dead: vec![false],
            super_start: s,
            free: Vec::new(),
            visit: vec![0],
            in_cavity: vec![false],
            stamp: 0,
            cavity: Vec::new(),
            boundary: Vec::new(),
            made: Vec::new(),
            links: Vec::new(),
            last: 0,
            rng: 0x9e37_79b9,
            walk_steps: 0,
            cavity_tets: 0,
        }
    }

    fn next_random(&mut self) -> u32 {
        // xorshift32: only to vary the first face a walk tries.
        let mut x = self.rng;
        x ^= x << 13;
        x ^= x >> 17;
        x ^= x << 5;
        self.rng = x;
        x
    }

    /// `true` when `p` lies strictly on the outer side of face `f` of tetrahedron `t`.
    #[inline]
    fn beyond(&self, t: u32, f: usize, p: &P3) -> bool {
        let v = self.tets[t as usize];
        let [a, b, c] = TET_FACES[f].map(|i| &self.pts[v[i] as usize]);
        orient(a, b, c, p) > 0.0
    }

    fn locate(&mut self, point: u32) -> Result<u32, DelaunayFailure> {
        let p = self.pts[point as usize];
        let mut t = self.last;
        let limit = 4 * self.tets.len() as u64 + 64;
        let mut steps = 0u64;
        'walk: loop {
            steps += 1;
            if steps > limit {
                return Err(DelaunayFailure::WalkDidNotEnd { point });
            }
            let r = self.next_random() as usize;
            for k in 0..4 {
                let f = (k + r) & 3;
                if self.beyond(t, f, &p) {
                    let next = self.nbr[t as usize][f];
                    if next == NONE {
                        return Err(DelaunayFailure::OutsideSuperTet { point });
                    }
                    t = next;
                    continue 'walk;
                }
            }
            self.walk_steps += steps;
            return Ok(t);
        }
    }

    #[inline]
    fn circumsphere_holds(&self, t: u32, point: u32) -> bool {
        let v = self.tets[t as usize];
        in_sphere(
            v.map(|i| &self.pts[i as usize]),
            v,
            &self.pts[point as usize],
            point,
        )
    }

    fn alloc(&mut self, tet: [u32; 4]) -> u32 {
        if let Some(t) = self.free.pop() {
            self.tets[t as usize] = tet;
            self.nbr[t as usize] = [NONE; 4];
            self.dead[t as usize] = false;
            t
        } else {
            self.tets.push(tet);
            self.nbr.push([NONE; 4]);
            self.dead.push(false);
            self.visit.push(0);
            self.in_cavity.push(false);
            (self.tets.len() - 1) as u32
        }
    }

    /// Inserts point `point` (an index into `pts`, not yet inserted, not coincident with any
    /// inserted point).
    pub fn insert(&mut self, point: u32) -> Result<(), DelaunayFailure> {
        let t0 = self.locate(point)?;
        self.stamp = self.stamp.wrapping_add(1);
        if self.stamp == 0 {
            self.visit.iter_mut().for_each(|v| *v = 0);
            self.stamp = 1;
        }
        let stamp = self.stamp;
        self.cavity.clear();
        self.boundary.clear();
        self.visit[t0 as usize] = stamp;
        self.in_cavity[t0 as usize] = true;
        self.cavity.push(t0);
        let mut k = 0;
        while k < self.cavity.len() {
            let t = self.cavity[k];
            k += 1;
            for f in 0..4u8 {
                let n = self.nbr[t as usize][f as usize];
                if n == NONE {
                    self.boundary.push((t, f));
                    continue;
                }
                if self.visit[n as usize] == stamp {
                    if !self.in_cavity[n as usize] {
                        self.boundary.push((t, f));
                    }
                    continue;
                }
                self.visit[n as usize] = stamp;
                let inside = self.circumsphere_holds(n, point);
                self.in_cavity[n as usize] = inside;
                if inside {
                    self.cavity.push(n);
                } else {
                    self.boundary.push((t, f));
                }
            }
        }
        self.cavity_tets += self.cavity.len() as u64;

        // New tetrahedra: the cavity tet with the vertex opposite the boundary face replaced.
        self.made.clear();
        for &(t, f) in &self.boundary {
            let mut v = self.tets[t as usize];
            v[f as usize] = point;
            self.made.push((v, f, self.nbr[t as usize][f as usize]));
        }
        for i in 0..self.cavity.len() {
            let t = self.cavity[i];
            self.dead[t as usize] = true;
            self.in_cavity[t as usize] = false;
            self.free.push(t);
        }
        self.links.clear();
        for i in 0..self.made.len() {
            let (v, f, out) = self.made[i];
            let t = self.alloc(v);
            self.nbr[t as usize][f as usize] = out;
            if out != NONE {
                // The slot of `out` across this face: its vertex not on the face.
                let ov = self.tets[out as usize];
                let face = TET_FACES[f as usize].map(|j| v[j]);
                if let Some(j) = (0..4).find(|&j| !face.contains(&ov[j])) {
                    self.nbr[out as usize][j] = t;
                }
            }
            for j in 0..4u8 {
                if j == f {
                    continue;
                }
                // Face opposite slot j holds `point` and the two vertices other than v[f], v[j].
                let mut e = [0u32; 2];
                let mut m = 0;
                for (s, &x) in v.iter().enumerate() {
                    if s != f as usize && s != j as usize {
                        e[m] = x;
                        m += 1;
                    }
                }
                let key = (u64::from(e[0].min(e[1])) << 32) | u64::from(e[0].max(e[1]));
                self.links.push((key, t, j));
            }
            self.last = t;
        }
        self.links.sort_unstable_by_key(|l| l.0);
        for pair in self.links.chunks(2) {
            match pair {
                [a, b] if a.0 == b.0 => {
                    self.nbr[a.1 as usize][a.2 as usize] = b.1;
                    self.nbr[b.1 as usize][b.2 as usize] = a.1;
                }
                _ => return Err(DelaunayFailure::OpenCavity { point }),
            }
        }
        Ok(())
    }

    /// Live tetrahedra that use none of the super-tetrahedron's corners.
    pub fn finite_tets(&self) -> impl Iterator<Item = (u32, [u32; 4])> + '_ {
        self.tets
            .iter()
            .enumerate()
            .filter(move |&(t, v)| !self.dead[t] && v.iter().all(|&i| i < self.super_start))
            .map(|(t, v)| (t as u32, *v))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn check(d: &Delaunay) {
        for (t, v) in d.tets.iter().enumerate() {
            if d.dead[t] {
                continue;
            }
            let p = v.map(|i| &d.pts[i as usize]);
            assert!(orient(p[0], p[1], p[2], p[3]) > 0.0, "tet {t} not positive");
            for f in 0..4 {
                let n = d.nbr[t][f];
                if n == NONE {
                    continue;
                }
                assert!(!d.dead[n as usize]);
                assert!(d.nbr[n as usize].contains(&(t as u32)), "asymmetric link");
                // Local Delaunay: the opposite vertex is not inside.
                let nv = d.tets[n as usize];
                let opp = (0..4)
                    .find(|&j| !v.contains(&nv[j]))
                    .map(|j| nv[j])
                    .unwrap();
                assert!(
                    !in_sphere(p, *v, &d.pts[opp as usize], opp),
                    "face {f} of tet {t} not locally Delaunay"
                );
            }
        }
    }

    #[test]
    fn lattice_with_ties_is_delaunay_and_positive() {
        // A 4×4×4 cubic lattice: every cube's corners are cospherical.
        let mut pts = Vec::new();
        for i in 0..4 {
            for j in 0..4 {
                for k in 0..4 {
                    pts.push([f64::from(i), f64::from(j), f64::from(k)]);
                }
            }
        }
        let n = pts.len() as u32;
        let mut d = Delaunay::new(pts);
        for i in 0..n {
            d.insert(i).unwrap();
        }
        check(&d);
        let volume: f64 = d
            .finite_tets()
            .map(|(_, v)| {
                let p = v.map(|i| &d.pts[i as usize]);
                orient(p[0], p[1], p[2], p[3]) / 6.0
            })
            .sum();
        assert!((volume - 27.0).abs() < 1e-9, "hull volume {volume}");
    }

    #[test]
    fn random_points_are_delaunay() {
        let mut s = 12345u64;
        let mut rnd = || {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (s >> 11) as f64 / (1u64 << 53) as f64
        };
        let pts: Vec<P3> = (0..500).map(|_| [rnd(), rnd(), rnd()]).collect();
        let mut d = Delaunay::new(pts);
        for i in 0..500 {
            d.insert(i).unwrap();
        }
        check(&d);
    }
}
