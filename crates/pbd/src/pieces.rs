//! Piece volumes: one global volume constraint per connected piece of the body
//! ([`crate::Material::hold_piece_volumes`]).
//!
//! Each connected piece `P` (tets sharing nodes; a cut that separates the tets separates the
//! pieces) carries `C_P = V_P − V₀_P`, `V₀_P` the sum of its tets' rest volumes and `V_P` the sum
//! of its tets' volumes, which equals the flux form over its boundary faces (the tet faces
//! that no other tet shares, outward): `V_P = (1/6) Σ_f a·(b × c)`, with the gradient
//! `∇_a C_P = (1/6) Σ_{f ∋ a} b × c` (cyclically) at the boundary nodes and zero inside. It is
//! projected as every other constraint, `Δxᵢ = −k C_P wᵢ ∇ᵢC_P / Σⱼ wⱼ|∇ⱼC_P|²` (Müller et al.
//! 2007, "Position based dynamics", §4.4, closed meshes). With the per-tet constraints this is a
//! two-level solve: the tets hold the volume locally, and the piece's constraint corrects in one
//! projection the volume's lowest mode, the one a Gauss–Seidel sweep carries across the body
//! slowest (an organ settling under its weight).
//!
//! The step projects it in each iteration of its last substep (once per step with the
//! real-time preset's one iteration: the volume a step's sweeps lost is given back before the
//! step ends, at the cost of one pass over the boundary), after the contacts, with the nodes in
//! contact held (weight zero): the
//! collider or tool keeps them where its contact put them, and the free surface takes up the
//! volume. So it neither pushes nodes back into a tool nor undoes the tool's reaction force.
//! The projection's net impulse is then the contacts' (the support of the tray under an organ),
//! as the held nodes' weight would have it. The nodes a cut split (the walls of wounds) are held
//! too: a wall's outward normal points into the wound, and the correction would close it.
//!
//! The correction is positional only: the step's velocity update leaves it out
//! ([`Pieces::take_shift`]). Given as a velocity (`(p − x)/h` of the last substep), it was a
//! kick outward of several cm/s on a resting organ's surface every step (8 cm/s on the bunny),
//! which the next substeps undid: the surface breathed, and the tray's contacts and
//! self-collision's broad phase had to follow it.
//!
//! The pieces and their boundary are found again after a topology edit, before the next step
//! (union–find over the tets' nodes, faces counted by their sorted nodes); a step allocates
//! nothing.

use std::collections::HashMap;

use glam::{Vec3A, Vec4};

/// The connected pieces of a body, their boundaries and the scratch of their projection.
#[derive(Debug, Clone, Default)]
pub(crate) struct Pieces {
    /// Whether the body holds its pieces' volumes.
    pub enabled: bool,
    /// The material's volume stiffness `k`.
    pub stiffness: f32,
    /// Its per-iteration value `1 − (1 − k)^{1/K}` over the `K` iterations of a step's last
    /// substep, where it is projected (set with the step settings).
    pub per_iteration: f32,
    /// The tets or nodes changed since the pieces were found.
    pub stale: bool,
    /// The boundary faces grouped by piece, outward, as solver slots.
    faces: Vec<[u32; 3]>,
    /// Piece `p`'s faces are `faces[face_start[p]..face_start[p + 1]]`.
    face_start: Vec<u32>,
    /// The boundary nodes grouped by piece, as solver slots.
    nodes: Vec<u32>,
    /// Piece `p`'s boundary nodes are `nodes[node_start[p]..node_start[p + 1]]`.
    node_start: Vec<u32>,
    /// Rest volume of each piece (cm³).
    rest: Vec<f64>,
    /// Six times `∇ᵢC` per solver slot (scratch; zero between projections).
    grad: Vec<Vec3A>,
    /// The projections' displacement of each solver slot in the current step (cm), which the
    /// step's velocity update leaves out ([`Pieces::take_shift`]); zero between steps.
    shift: Vec<Vec3A>,
    /// The inverse masses the projection uses, per solver slot: the body's, zero for a node
    /// in contact (set every substep by [`Pieces::hold`]).
    w: Vec<f32>,
    /// The nodes a cut split (both the source and the copy of [`crate::SoftBody::duplicate_nodes`]):
    /// the walls of wounds. Held, so that the correction does not push the walls of a wound
    /// into each other (a wall's outward normal points into the wound).
    pub split: Vec<u32>,
    /// Their solver slots (at the last rebuild).
    split_slots: Vec<u32>,
    /// The weights with only the nodes in contact held (walls free): those that carry the
    /// translation that gives back the momentum the held walls did not take.
    w_move: Vec<f32>,
    /// All nodes grouped by piece, as solver slots: `members[member_start[p]..member_start[p + 1]]`.
    members: Vec<u32>,
    member_start: Vec<u32>,
    /// Whether each piece has split nodes (walls).
    walled: Vec<bool>,
    /// Whether each slot is a split node.
    wall: Vec<bool>,
}

/// The outward faces of a positively oriented tet `[a, b, c, d]`
/// (`(b − a) × (c − a) · (d − a) > 0`).
const TET_FACES: [[usize; 3]; 4] = [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]];

impl Pieces {
    /// No pieces yet: they are found before the first step.
    pub fn new(enabled: bool, stiffness: f32) -> Self {
        Self {
            enabled,
            stiffness,
            per_iteration: stiffness,
            stale: true,
            ..Default::default()
        }
    }

    /// Finds the pieces of `tets` (caller's node indices, `rest` their rest volumes) and their
    /// boundaries over `slots` solver slots, `rank[i]` node `i`'s slot.
    pub fn rebuild(&mut self, tets: &[[u32; 4]], rest: &[f32], rank: &[u32], slots: usize) {
        let _span = tracing::debug_span!("find_pieces", tets = tets.len()).entered();
        let piece_of_node = label(tets, rank.len());
        let count = piece_of_node
            .iter()
            .filter(|&&p| p != NONE)
            .max()
            .map_or(0, |&p| p as usize + 1);
        self.rest.clear();
        self.rest.resize(count, 0.0);
        for (t, &v) in tets.iter().zip(rest) {
            self.rest[piece_of_node[t[0] as usize] as usize] += v as f64;
        }
        // Boundary faces: those whose sorted nodes occur once (an inner face occurs twice, once
        // each way round).
        let mut seen: HashMap<[u32; 3], (u32, [u32; 3])> = HashMap::with_capacity(2 * tets.len());
        for t in tets {
            for f in TET_FACES {
                let face = f.map(|k| t[k]);
                let mut key = face;
                key.sort_unstable();
                seen.entry(key)
                    .and_modify(|e| e.0 += 1)
                    .or_insert((1, face));
            }
        }
        let mut boundary: Vec<[u32; 3]> = seen
            .into_values()
            .filter(|&(n, _)| n == 1)
            .map(|(_, f)| f)
            .collect();
        // The mesh's order, not the hash map's: sorted by piece, then by nodes.
        boundary.sort_unstable_by_key(|f| (piece_of_node[f[0] as usize], *f));
        self.face_start.clear();
        self.face_start.resize(count + 1, 0);
        self.nodes.clear();
        self.node_start.clear();
        self.node_start.resize(count + 1, 0);
        let mut on_boundary = vec![false; rank.len()];
        for f in &boundary {
            self.face_start[piece_of_node[f[0] as usize] as usize + 1] += 1;
            for &i in f {
                on_boundary[i as usize] = true;
            }
        }
        let mut by_piece: Vec<Vec<u32>> = vec![Vec::new(); count];
        for (i, _) in on_boundary.iter().enumerate().filter(|(_, &b)| b) {
            by_piece[piece_of_node[i] as usize].push(rank[i]);
        }
        for (p, nodes) in by_piece.iter().enumerate() {
            self.face_start[p + 1] += self.face_start[p];
            self.nodes.extend_from_slice(nodes);
            self.node_start[p + 1] = self.nodes.len() as u32;
        }
        self.faces.clear();
        self.faces
            .extend(boundary.iter().map(|f| f.map(|i| rank[i as usize])));
        self.grad.clear();
        self.grad.resize(slots, Vec3A::ZERO);
        self.shift.clear();
        self.shift.resize(slots, Vec3A::ZERO);
        self.w.clear();
        self.w.resize(slots, 0.0);
        self.split.sort_unstable();
        self.split.dedup();
        self.split_slots.clear();
        self.split_slots
            .extend(self.split.iter().map(|&i| rank[i as usize]));
        self.w_move.clear();
        self.w_move.resize(slots, 0.0);
        self.wall.clear();
        self.wall.resize(slots, false);
        self.walled.clear();
        self.walled.resize(count, false);
        for &i in &self.split {
            self.wall[rank[i as usize] as usize] = true;
            if let Some(&p) = piece_of_node.get(i as usize).filter(|&&p| p != NONE) {
                self.walled[p as usize] = true;
            }
        }
        let mut all: Vec<Vec<u32>> = vec![Vec::new(); count];
        for (i, &p) in piece_of_node.iter().enumerate() {
            if p != NONE {
                all[p as usize].push(rank[i]);
            }
        }
        self.members.clear();
        self.member_start.clear();
        self.member_start.push(0);
        for m in &all {
            self.members.extend_from_slice(m);
            self.member_start.push(self.members.len() as u32);
        }
        self.stale = false;
    }

    /// Number of pieces (after the last rebuild).
    pub fn count(&self) -> usize {
        self.rest.len()
    }

    /// Rest volume of each piece (cm³).
    #[cfg(test)]
    pub fn rest_volumes(&self) -> &[f64] {
        &self.rest
    }

    /// Six times piece `p`'s volume at `q` (solver order), from its boundary; accumulates six
    /// times the gradient into `grad` when `GRAD`.
    #[inline]
    fn six_volume<const GRAD: bool>(&mut self, q: &[Vec4], p: usize) -> f64 {
        let (s, e) = (self.face_start[p] as usize, self.face_start[p + 1] as usize);
        let Some(first) = self.faces.get(s) else {
            return 0.0;
        };
        // Relative to one of its nodes (the sum is translation invariant on a closed boundary),
        // so that the products keep their precision far from the origin.
        let o = Vec3A::from(q[first[0] as usize].truncate());
        let mut six = 0.0f64;
        for f in &self.faces[s..e] {
            let [a, b, c] = f.map(|s| Vec3A::from(q[s as usize].truncate()) - o);
            let bc = b.cross(c);
            six += a.dot(bc) as f64;
            if GRAD {
                self.grad[f[0] as usize] += bc;
                self.grad[f[1] as usize] += c.cross(a);
                self.grad[f[2] as usize] += a.cross(b);
            }
        }
        six
    }

    /// The volume of each piece at `q` (solver order), into `out` (cm³).
    #[cfg(test)]
    pub fn volumes(&mut self, q: &[Vec4], out: &mut Vec<f64>) {
        out.clear();
        for p in 0..self.count() {
            out.push(self.six_volume::<false>(q, p) / 6.0);
        }
    }

    /// The weights of this substep's projections: `w` (solver order), zero at the slots of
    /// `held` (the nodes in contact).
    pub fn hold(&mut self, w: &[f32], held: impl Iterator<Item = u32>) {
        self.w_move.copy_from_slice(w);
        for s in held {
            self.w_move[s as usize] = 0.0;
        }
        self.w.copy_from_slice(&self.w_move);
        for &s in &self.split_slots {
            self.w[s as usize] = 0.0;
        }
    }

    /// Also holds the nodes at or under the floor `x[axis] = height` at `q` (solver order).
    pub fn hold_on_floor(&mut self, q: &[Vec4], axis: usize, height: f32) {
        for ((w, m), q) in self.w.iter_mut().zip(&mut self.w_move).zip(q) {
            if q[axis] <= height {
                *w = 0.0;
                *m = 0.0;
            }
        }
    }

    /// Projects every piece's constraint once on `q` (xyz; solver order) with the weights of
    /// [`Pieces::hold`], scaled by [`Pieces::per_iteration`].
    pub fn project(&mut self, q: &mut [Vec4]) {
        let k = self.per_iteration;
        let _span = tracing::trace_span!("piece_volumes", pieces = self.count()).entered();
        for p in 0..self.count() {
            let six = self.six_volume::<true>(q, p);
            let nodes = &self.nodes[self.node_start[p] as usize..self.node_start[p + 1] as usize];
            let den: f64 = nodes
                .iter()
                .map(|&s| (self.w[s as usize] * self.grad[s as usize].length_squared()) as f64)
                .sum();
            // λ = −6 C / Σ w|6∇C|², Δx = k λ w (6∇C).
            let lambda = if den > 0.0 {
                (-(six - 6.0 * self.rest[p]) / den * k as f64) as f32
            } else {
                0.0
            };
            // The momentum the held walls would have taken, `λ Σ_walls 6∇C` (g·cm with the
            // weights' masses), before the gradient is cleared.
            let mut walls = Vec3A::ZERO;
            for &s in nodes {
                let s = s as usize;
                if self.wall[s] && self.w_move[s] > 0.0 {
                    walls += self.grad[s];
                }
                let d = lambda * self.w[s] * self.grad[s];
                q[s] += d.extend(0.0);
                self.shift[s] += d;
                self.grad[s] = Vec3A::ZERO;
            }
            if self.walled[p] && lambda != 0.0 {
                self.give_back(q, p, lambda * walls);
            }
        }
    }

    /// The projections' displacement of solver slot `s` in this step, zeroed (the step's
    /// velocity update reads each slot once).
    #[inline]
    pub fn take_shift(&mut self, s: usize) -> Vec3A {
        self.shift.get_mut(s).map_or(Vec3A::ZERO, std::mem::take)
    }

    /// Translates piece `p`'s nodes that are not in contact (a translation keeps the volume)
    /// so that they take the momentum `impulse` (g·cm), which the held walls would have taken:
    /// without it a cut piece would push itself along (the projection's corrections sum to
    /// zero only over all its boundary nodes).
    fn give_back(&mut self, q: &mut [Vec4], p: usize, impulse: Vec3A) {
        let members =
            &self.members[self.member_start[p] as usize..self.member_start[p + 1] as usize];
        let mass: f64 = members
            .iter()
            .map(|&s| self.w_move[s as usize])
            .filter(|&w| w > 0.0)
            .map(|w| 1.0 / w as f64)
            .sum();
        if mass <= 0.0 {
            return;
        }
        let d = impulse / mass as f32;
        for &s in members {
            if self.w_move[s as usize] > 0.0 {
                q[s as usize] += d.extend(0.0);
                self.shift[s as usize] += d;
            }
        }
    }
}

/// No piece: a node in no tet.
const NONE: u32 = u32::MAX;

/// The piece of each of `n` nodes (connected through `tets`), numbered in order of their
/// smallest node; [`NONE`] for a node in no tet.
fn label(tets: &[[u32; 4]], n: usize) -> Vec<u32> {
    fn find(parent: &mut [u32], mut i: u32) -> u32 {
        while parent[i as usize] != i {
            let up = parent[parent[i as usize] as usize];
            parent[i as usize] = up;
            i = up;
        }
        i
    }
    let mut parent: Vec<u32> = (0..n as u32).collect();
    let mut used = vec![false; n];
    for t in tets {
        for &i in t {
            used[i as usize] = true;
        }
        for &j in &t[1..] {
            let (a, b) = (find(&mut parent, t[0]), find(&mut parent, j));
            if a != b {
                // The root of a piece is its smallest node, so `parent[i] < i` off the roots.
                parent[a.max(b) as usize] = a.min(b);
            }
        }
    }
    // In index order every parent is final before its children: one pass flattens.
    let mut piece = vec![NONE; n];
    let mut count = 0u32;
    for i in 0..n {
        let p = parent[i] as usize;
        parent[i] = parent[p];
        if parent[i] as usize == i {
            if used[i] {
                piece[i] = count;
                count += 1;
            }
        } else {
            piece[i] = piece[parent[i] as usize];
        }
    }
    piece
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two cubes of five tets each, apart, and a lone node.
    fn two_cubes() -> (Vec<Vec4>, Vec<[u32; 4]>) {
        let cube = |o: f32| -> Vec<Vec4> {
            (0..8)
                .map(|i| {
                    Vec4::new(
                        o + (i & 1) as f32,
                        ((i >> 1) & 1) as f32,
                        ((i >> 2) & 1) as f32,
                        1.0,
                    )
                })
                .collect()
        };
        let five = [
            [0, 1, 2, 4],
            [1, 3, 2, 7],
            [1, 2, 4, 7],
            [1, 4, 5, 7],
            [2, 4, 7, 6],
        ];
        let mut q = cube(0.0);
        q.extend(cube(3.0));
        q.push(Vec4::new(9.0, 9.0, 9.0, 1.0));
        let mut tets: Vec<[u32; 4]> = Vec::new();
        for base in [0u32, 8] {
            for t in five {
                let t = t.map(|i| i + base);
                let six = {
                    let [a, b, c, d] = t.map(|i| q[i as usize].truncate());
                    (b - a).cross(c - a).dot(d - a)
                };
                tets.push(if six > 0.0 {
                    t
                } else {
                    [t[1], t[0], t[2], t[3]]
                });
            }
        }
        (q, tets)
    }

    #[test]
    fn labels_follow_the_smallest_node_wherever_it_is_in_a_tet() {
        assert_eq!(
            label(&[[3, 1, 2, 0], [7, 5, 6, 4], [2, 9, 3, 1]], 11),
            [0, 0, 0, 0, 1, 1, 1, 1, NONE, 0, NONE]
        );
    }

    #[test]
    fn pieces_their_boundaries_and_volumes() {
        let (q, tets) = two_cubes();
        let rank: Vec<u32> = (0..q.len() as u32).collect();
        let mut pieces = Pieces::new(true, 1.0);
        pieces.rebuild(&tets, &[0.2; 10], &rank, q.len());
        assert_eq!(pieces.count(), 2);
        assert_eq!(pieces.rest_volumes(), &[1.0000000149011612; 2]);
        // Each cube's boundary: 2 triangles per side, 8 corners.
        assert_eq!(pieces.face_start, [0, 12, 24]);
        assert_eq!(pieces.node_start, [0, 8, 16]);
        let mut v = Vec::new();
        pieces.volumes(&q, &mut v);
        for v in v {
            assert!((v - 1.0).abs() < 1e-6, "{v}");
        }
    }

    #[test]
    fn one_projection_restores_a_squashed_piece_and_keeps_its_momentum() {
        let (mut q, tets) = two_cubes();
        let rank: Vec<u32> = (0..q.len() as u32).collect();
        let mut pieces = Pieces::new(true, 1.0);
        pieces.rebuild(&tets, &[0.2; 10], &rank, q.len());
        // Squash the first cube to 0.8 of its height.
        for p in &mut q[..8] {
            p.y *= 0.8;
        }
        // And turn it, so that its nodes are anywhere.
        let turn = glam::Quat::from_euler(glam::EulerRot::XYZ, 0.3, -0.7, 1.1);
        for p in &mut q[..8] {
            *p = (turn * p.truncate() + glam::Vec3::new(5.0, -3.0, 2.0)).extend(1.0);
        }
        let centre = |q: &[Vec4]| q[..8].iter().map(|p| p.truncate()).sum::<glam::Vec3>() / 8.0;
        let before = centre(&q);
        let w: Vec<f32> = vec![1.0; q.len()];
        pieces.hold(&w, std::iter::empty());
        let old = q.clone();
        pieces.project(&mut q);
        // Equal masses: Σ p × Δp = 0 (the constraint is invariant under rotations).
        let turning: glam::Vec3 = old[..8]
            .iter()
            .zip(&q[..8])
            .map(|(a, b)| a.truncate().cross(b.truncate() - a.truncate()))
            .sum();
        assert!(turning.length() < 1e-5, "{turning}");
        let mut v = Vec::new();
        pieces.volumes(&q, &mut v);
        // The constraint is cubic in the positions: one linearised projection leaves a
        // second-order error (0.2² of the volume at most); two get it to float precision.
        assert!((v[0] - 1.0).abs() < 0.04, "{v:?}");
        pieces.project(&mut q);
        pieces.volumes(&q, &mut v);
        assert!((v[0] - 1.0).abs() < 1e-3, "{v:?}");
        assert!((v[1] - 1.0).abs() < 1e-6, "the other piece moved: {v:?}");
        // Equal masses: the centre of mass does not move.
        assert!((centre(&q) - before).length() < 1e-5);
    }

    #[test]
    fn held_nodes_stay() {
        let (mut q, tets) = two_cubes();
        let rank: Vec<u32> = (0..q.len() as u32).collect();
        let mut pieces = Pieces::new(true, 1.0);
        pieces.rebuild(&tets, &[0.2; 10], &rank, q.len());
        for p in &mut q[..8] {
            p.y *= 0.8;
        }
        let held: Vec<u32> = (0..8).filter(|i| (i >> 1) & 1 == 0).collect();
        let bottom: Vec<Vec4> = held.iter().map(|&i| q[i as usize]).collect();
        pieces.hold(&[1.0; 17], held.iter().copied());
        pieces.project(&mut q);
        pieces.project(&mut q);
        let mut v = Vec::new();
        pieces.volumes(&q, &mut v);
        assert!((v[0] - 1.0).abs() < 1e-3, "{v:?}");
        for (&i, b) in held.iter().zip(bottom) {
            assert_eq!(q[i as usize], b);
        }
    }
}
