//! The local edits a cut that splits tets needs: a tet split in rest space (one record reshaped,
//! the others appended), a node on the split edge, rest lengths reset. A body split that way
//! is still at rest (every new rest value matches its rest shape) and keeps its rest volume.
#![allow(clippy::unwrap_used)]

use glam::{DVec3, Vec3};
use tissue_mesh::tet_box;
use tissue_pbd::{
    ConstraintSlot, DistanceConstraint, Material, PbdError, SoftBody, StepSettings,
    VolumeConstraintKind,
};

fn body(kind: VolumeConstraintKind) -> SoftBody {
    let mesh = tet_box(2, 2, 2, Vec3::splat(2.0)).unwrap();
    let material = Material {
        volume: kind,
        ..Material::default()
    };
    let mut body = SoftBody::new(&mesh, &material).unwrap();
    body.set_settings(StepSettings {
        gravity: Vec3::ZERO,
        ..StepSettings::default()
    })
    .unwrap();
    body
}

fn rest(body: &SoftBody, t: [u32; 4]) -> [DVec3; 4] {
    t.map(|i| Vec3::from(body.rest_positions()[i as usize]).as_dvec3())
}

/// The farthest any node moves over `steps` steps (cm).
fn drift(body: &mut SoftBody, steps: usize) -> f32 {
    let start = body.positions().to_vec();
    for _ in 0..steps {
        body.step().unwrap();
    }
    body.positions()
        .iter()
        .zip(&start)
        .map(|(p, q)| p.distance(*q))
        .fold(0.0f32, f32::max)
}

/// Splits every tet around the edge `a b` at its midpoint `m` (each tet into two: `b` replaced
/// by `m`, `a` replaced by `m`), the edge's constraint moved onto `a m` with half the rest
/// length, new edges given constraints with their rest lengths. Returns the new node.
fn split_edge(body: &mut SoftBody, a: u32, b: u32) -> u32 {
    let m = body.duplicate_nodes(&[a]).unwrap();
    let r = body.rest_positions();
    let rm = (Vec3::from(r[a as usize]) + Vec3::from(r[b as usize])) * 0.5;
    let x = body.positions();
    let xm = (Vec3::from(x[a as usize]) + Vec3::from(x[b as usize])) * 0.5;
    body.set_rest_position(m, rm).unwrap();
    body.set_node_state(m, xm, xm, Vec3::ZERO).unwrap();
    let around: Vec<usize> = (0..body.tets().len())
        .filter(|&t| body.tets()[t].contains(&a) && body.tets()[t].contains(&b))
        .collect();
    let mut edges: Vec<[u32; 2]> = body
        .distance_constraints()
        .iter()
        .map(|d| [d.nodes[0].min(d.nodes[1]), d.nodes[0].max(d.nodes[1])])
        .collect();
    let template = body.distance_constraints()[0];
    for t in around {
        let old = body.tets()[t];
        let lo = old.map(|i| if i == b { m } else { i });
        let hi = old.map(|i| if i == a { m } else { i });
        let rest_lo = rest(body, lo);
        body.reshape_tet(t, lo, rest_lo).unwrap();
        let rest_hi = rest(body, hi);
        body.add_tet(t, hi, rest_hi).unwrap();
        for tet in [lo, hi] {
            for i in 0..4 {
                for j in i + 1..4 {
                    let e = [tet[i].min(tet[j]), tet[i].max(tet[j])];
                    if !edges.contains(&e) && e != [a.min(b), a.max(b)] {
                        let l = body.rest_positions()[e[0] as usize]
                            .distance(body.rest_positions()[e[1] as usize]);
                        body.add_distance_constraint(DistanceConstraint {
                            nodes: e,
                            rest_length: l,
                            ..template
                        })
                        .unwrap();
                        edges.push(e);
                    }
                }
            }
        }
    }
    let c = edges
        .iter()
        .position(|e| *e == [a.min(b), a.max(b)])
        .unwrap();
    let l = body.rest_positions()[a as usize].distance(body.rest_positions()[m as usize]);
    body.reset_distance_constraint(c, [a, m], l).unwrap();
    // Masses from the tets (eq. (1)).
    let density = body.density();
    let mut mass = vec![0.0f32; body.node_count()];
    for (t, tet) in body.tets().iter().enumerate() {
        for &i in tet {
            mass[i as usize] += density * body.tet_rest_volumes()[t] / 4.0;
        }
    }
    for (i, m) in mass.into_iter().enumerate() {
        body.set_node_mass(i as u32, m).unwrap();
    }
    m
}

/// Loose copies of node `source` (no constraint, no mass) until its leaf has no spare slot
/// left: every copy after them goes past the block tree. Returns how many were made.
fn fill_leaf(body: &mut SoftBody, source: u32) -> usize {
    // A leaf has at most twice as many slots as the body has nodes.
    let count = 2 * body.node_count();
    let first = body.duplicate_nodes(&vec![source; count]).unwrap();
    for i in first..first + count as u32 {
        body.set_node_mass(i, 0.0).unwrap();
    }
    count
}

#[test]
fn a_body_split_in_rest_space_stays_at_rest_and_keeps_its_volume() {
    for (kind, full) in [
        (VolumeConstraintKind::Classic, false),
        (VolumeConstraintKind::Centroid, false),
        (VolumeConstraintKind::Classic, true),
        (VolumeConstraintKind::Centroid, true),
    ] {
        let mut body = body(kind);
        let (volume, mass, tets) = (body.rest_volume(), body.total_mass(), body.tets().len());
        // An inner edge: the first tet's first two nodes.
        let [a, b, ..] = body.tets()[0];
        if full {
            fill_leaf(&mut body, a);
        }
        let m = split_edge(&mut body, a, b);
        // The new node takes a spare slot of its leaf and the split's constraints stay in the
        // block tree; with the leaf full, it goes past the tree and they are projected serially.
        let serial = body.serial_dynamic_counts();
        if full {
            assert_eq!(serial, body.dynamic_counts(), "{kind:?}");
            assert!(serial.0 > 0 && serial.1 > 0);
        } else {
            assert_eq!(serial, (0, 0), "{kind:?}");
            assert!(body.dynamic_counts().0 > 0 && body.dynamic_counts().1 > 0);
            let last = body.tets().len() - 1;
            assert!(matches!(
                body.tet_slot(last),
                Some(ConstraintSlot::Block { .. })
            ));
        }
        assert!(body.tets().len() > tets);
        assert!(
            (body.rest_volume() / volume - 1.0).abs() < 1e-6,
            "{kind:?}: rest volume {} of {volume}",
            body.rest_volume()
        );
        assert!((body.total_mass() / mass - 1.0).abs() < 1e-5);
        // Rewriting a dynamic constraint keeps its lane (no dead lane, no new batch).
        let batches = body.dynamic_batch_counts();
        let last = body.tets().len() - 1;
        let (tet, shape) = (body.tets()[last], rest(&body, body.tets()[last]));
        body.reshape_tet(last, tet, shape).unwrap();
        body.set_tet_nodes(last, tet).unwrap();
        let c = body.distance_constraints().len() - 1;
        let d = body.distance_constraints()[c];
        body.reset_distance_constraint(c, d.nodes, d.rest_length)
            .unwrap();
        assert_eq!(body.dynamic_batch_counts(), batches, "{kind:?}");
        let moved = drift(&mut body, 20);
        assert!(
            moved < 1e-5,
            "{kind:?} full {full}: a body at rest moved {moved} cm"
        );
        assert!(body.positions()[m as usize].is_finite());
    }
}

#[test]
fn a_reset_rest_length_is_what_the_solver_pulls_to() {
    let mut body = body(VolumeConstraintKind::None);
    // Shrink every edge's rest length: the body contracts.
    let before = body.volume();
    for c in 0..body.distance_constraints().len() {
        let d = body.distance_constraints()[c];
        body.reset_distance_constraint(c, d.nodes, 0.5 * d.rest_length)
            .unwrap();
    }
    for _ in 0..50 {
        body.step().unwrap();
    }
    assert!(
        body.volume() < 0.5 * before,
        "{} of {before}",
        body.volume()
    );
}

#[test]
fn bad_reshapes_are_refused_and_change_nothing() {
    let mut body = body(VolumeConstraintKind::Classic);
    let t0 = body.tets()[0];
    let flat = [DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::new(1.0, 1.0, 0.0)];
    let tets = body.tets().len();
    assert!(matches!(
        body.add_tet(0, t0, flat),
        Err(PbdError::InvalidParameter { .. })
    ));
    let inverted = {
        let r = rest(&body, t0);
        [r[1], r[0], r[2], r[3]]
    };
    assert!(matches!(
        body.reshape_tet(0, t0, inverted),
        Err(PbdError::InvalidParameter { .. })
    ));
    assert!(matches!(
        body.add_tet(tets, t0, rest(&body, t0)),
        Err(PbdError::NoSuchElement { .. })
    ));
    assert!(matches!(
        body.reset_distance_constraint(0, [0, 0], 1.0),
        Err(PbdError::InvalidParameter { .. })
    ));
    assert!(matches!(
        body.reset_distance_constraint(0, [0, 1], f32::NAN),
        Err(PbdError::InvalidParameter { .. })
    ));
    assert!(matches!(
        body.set_node_state(0, Vec3::NAN, Vec3::ZERO, Vec3::ZERO),
        Err(PbdError::NonFinite { .. })
    ));
    assert_eq!(body.tets().len(), tets);
    assert_eq!(body.tets()[0], t0);
    assert_eq!(body.dynamic_counts(), (0, 0));
}

#[test]
fn copies_take_spare_slots_of_their_leaf_then_go_past_the_tree() {
    // A 4×4×4-cell box: 125 nodes in one leaf, the root.
    let mesh = tet_box(4, 4, 4, Vec3::splat(2.0)).unwrap();
    let mut body = SoftBody::new(&mesh, &Material::default()).unwrap();
    assert_eq!(body.block_count(), 1);
    let n = body.node_count();
    let template = body.distance_constraints()[0];
    // Copies of node 0 one at a time, each tied to node 1 by a new distance constraint.
    let mut slots = Vec::new();
    for k in 0..3 * n {
        let copy = body.duplicate_nodes(&[0]).unwrap();
        assert_eq!(copy as usize, n + k);
        let c = body
            .add_distance_constraint(DistanceConstraint {
                nodes: [1, copy],
                ..template
            })
            .unwrap();
        slots.push(body.distance_slot(c).unwrap());
    }
    // At least as many spares as real nodes, then the tail, for good.
    let spares = slots
        .iter()
        .position(|s| matches!(s, ConstraintSlot::Dynamic { .. }))
        .unwrap();
    assert!(spares >= n, "{spares} spares for {n} nodes");
    assert!(slots[..spares]
        .iter()
        .all(|s| matches!(s, ConstraintSlot::Block { block: 0, .. })));
    assert!(slots[spares..]
        .iter()
        .all(|s| matches!(s, ConstraintSlot::Dynamic { .. })));
    assert_eq!(body.serial_dynamic_counts(), (3 * n - spares, 0));
    assert_eq!(body.dynamic_counts(), (3 * n, 0));
    // A copy of a tail node stays in the tail; a constraint between a spare-slot node and a
    // tail node is serial, one between two spare-slot nodes is in the tree.
    let tail = body.node_count() as u32 - 1;
    let copy = body.duplicate_nodes(&[tail]).unwrap();
    let c = body
        .add_distance_constraint(DistanceConstraint {
            nodes: [n as u32, copy],
            ..template
        })
        .unwrap();
    assert!(matches!(
        body.distance_slot(c),
        Some(ConstraintSlot::Dynamic { .. })
    ));
    // (The copies coincide: rest length 0.)
    let c = body
        .add_distance_constraint(DistanceConstraint {
            nodes: [n as u32, n as u32 + 1],
            rest_length: 0.0,
            ..template
        })
        .unwrap();
    assert!(matches!(
        body.distance_slot(c),
        Some(ConstraintSlot::Block { block: 0, .. })
    ));
    // Moving a tree-slot constraint onto a tail node moves it to the serial set, and back.
    body.set_distance_nodes(c, [n as u32, copy]).unwrap();
    assert!(matches!(
        body.distance_slot(c),
        Some(ConstraintSlot::Dynamic { .. })
    ));
    body.set_distance_nodes(c, [n as u32, n as u32 + 1])
        .unwrap();
    assert!(matches!(
        body.distance_slot(c),
        Some(ConstraintSlot::Block { block: 0, .. })
    ));
    // Node 1 pinned, under gravity: every copy swings from node 1 at the rest length, the
    // same way (bit for bit) whether in a spare slot or past the tree (but for the first two,
    // also tied to each other).
    body.set_settings(StepSettings::default()).unwrap();
    body.pin(1).unwrap();
    let start = Vec3::from(body.positions()[n]);
    for _ in 0..30 {
        body.step().unwrap();
    }
    let x = body.positions();
    for k in 0..3 * n {
        let d = x[1].distance(x[n + k]);
        assert!(
            (d - template.rest_length).abs() < 1e-4,
            "copy {k}: {d} vs {}",
            template.rest_length
        );
        if k >= 2 {
            assert_eq!(x[n + k], x[n + 2], "copy {k}");
        }
    }
    assert!(Vec3::from(x[n]).distance(start) > 0.1);
    assert!(x.iter().all(|p| p.is_finite()));
}

#[test]
fn a_changed_tree_constraint_keeps_its_lane_unless_its_batch_has_its_new_nodes() {
    // Seven blocks; the batches in the middle of the projection order are not the first leaf's
    // (whose slots start at 0), the last ones are the root's.
    let mesh = tet_box(14, 14, 14, Vec3::splat(7.0)).unwrap();
    for root in [false, true] {
        let mut body = SoftBody::new(&mesh, &Material::default()).unwrap();
        assert!(body.block_count() >= 7);
        let slot = |b: &SoftBody, c: usize| b.distance_slot(c).unwrap();
        // Two constraints of the middle (or last) tree batch with two.
        let mut by_batch = std::collections::BTreeMap::<u32, Vec<usize>>::new();
        for c in 0..body.distance_constraints().len() {
            if let ConstraintSlot::Tree { batch } = slot(&body, c) {
                by_batch.entry(batch).or_default().push(c);
            }
        }
        let pairs: Vec<&Vec<usize>> = by_batch.values().filter(|v| v.len() >= 2).collect();
        let pair = pairs.get(if root {
            pairs.len() - 1
        } else {
            pairs.len() / 2
        });
        let (c1, c2) = pair.map(|v| (v[0], v[1])).unwrap();
        let before = slot(&body, c1);
        let [a, b] = body.distance_constraints()[c1].nodes;
        // Onto a copy of its own node (a spare slot of the same leaf): the same lane.
        let copy = body.duplicate_nodes(&[a]).unwrap();
        body.set_distance_nodes(c1, [copy, b]).unwrap();
        assert_eq!(slot(&body, c1), before);
        assert_eq!(body.distance_constraints()[c1].nodes, [copy, b]);
        assert_eq!(body.dynamic_counts(), (0, 0));
        // Onto a node another lane of its batch has: it leaves the tree batch.
        let other = body.distance_constraints()[c2].nodes[0];
        body.set_distance_nodes(c1, [copy, other]).unwrap();
        assert!(matches!(slot(&body, c1), ConstraintSlot::Block { .. }));
        assert_eq!(slot(&body, c2), before);
        assert_eq!(body.dynamic_counts(), (1, 0));
        // Tets likewise: moved onto a copy, a tet keeps its lane.
        let k = if root {
            body.tets().len() - 1
        } else {
            body.tets().len() / 2
        };
        let t = body.tets()[k];
        let before = body.tet_slot(k).unwrap();
        assert!(matches!(before, ConstraintSlot::Tree { .. }));
        let copy2 = body.duplicate_nodes(&[t[2]]).unwrap();
        body.set_tet_nodes(k, [t[0], t[1], copy2, t[3]]).unwrap();
        assert_eq!(body.tet_slot(k).unwrap(), before);
        assert_eq!(body.dynamic_counts(), (1, 0));
        // The body is still at rest: the rewritten lanes pull to the same rest values, on the
        // right nodes.
        body.set_settings(StepSettings {
            gravity: Vec3::ZERO,
            ..StepSettings::default()
        })
        .unwrap();
        body.set_distance_nodes(c1, [a, b]).unwrap();
        body.set_distance_nodes(c1, [copy, b]).unwrap();
        let moved = drift(&mut body, 10);
        // (An unedited body of this size drifts 3e-5 cm in 10 steps: float rounding.)
        assert!(moved < 1e-4, "root {root}: {moved}");
        // And they act on the right nodes: the copy pulled away drags `b`, the tet's copy the
        // tet's other nodes.
        let mut pulled = body.clone();
        let (xc, xb) = (
            Vec3::from(body.positions()[copy as usize]),
            Vec3::from(body.positions()[b as usize]),
        );
        let away = (xc - xb).normalize();
        pulled
            .set_node_state(copy, xc + away, xc + away, Vec3::ZERO)
            .unwrap();
        pulled.step().unwrap();
        let dragged = (Vec3::from(pulled.positions()[b as usize]) - xb).dot(away);
        assert!(dragged > 1e-3, "root {root}: {dragged}");
        let pull = Vec3::from(body.positions()[copy2 as usize]) + Vec3::Y;
        body.set_node_state(copy2, pull, pull, Vec3::ZERO).unwrap();
        let before = body.positions().to_vec();
        body.step().unwrap();
        let dragged = [t[0], t[1], t[3]]
            .map(|i| body.positions()[i as usize].distance(before[i as usize]))
            .into_iter()
            .fold(0.0f32, f32::max);
        assert!(dragged > 1e-3, "root {root}: {dragged}");
    }
}
