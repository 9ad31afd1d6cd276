//! Parallel projection (sibling blocks of the domain decomposition at the same time) is
//! bit-identical to the serial sweep, on 1, 2 and 3 threads.
#![allow(clippy::unwrap_used)]

use glam::Vec3;
use tissue_mesh::tet_box;
use tissue_pbd::{
    ConstraintSlot, Floor, Material, SoftBody, Solver, StepSettings, VolumeConstraintKind,
};

/// The 20³-cell test box (colours of a few thousand constraints, so the parallel path really
/// forks), on a floor `floor` below, node 0 pinned; `None`: the elastic material (neo-Hookean
/// pairs) instead of volume constraints of a kind.
fn box_body(kind: Option<VolumeConstraintKind>, floor: f32) -> SoftBody {
    let mesh = tet_box(20, 20, 20, Vec3::splat(10.0)).unwrap();
    let material = match kind {
        Some(kind) => Material {
            distance_stiffness: 0.7,
            volume_stiffness: 0.9,
            distance_compliance: 1e-4,
            volume_compliance: 1e-4,
            volume: kind,
            ..Material::default()
        },
        None => Material::elastic(2.0, 0.45, 1.0).unwrap(),
    };
    let mut body = SoftBody::new(&mesh, &material).unwrap();
    body.set_floor(Some(Floor::y(floor))).unwrap();
    body.pin(0).unwrap();
    body
}

/// Five steps of `body` on a pool of `threads`; the bits of its positions and velocities.
fn five_steps(mut body: SoftBody, solver: Solver, parallel: bool, threads: usize) -> Vec<u32> {
    body.set_settings(StepSettings {
        dt: 0.01,
        iterations: 5,
        solver,
        parallel,
        ..StepSettings::default()
    })
    .unwrap();
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    pool.install(|| {
        for _ in 0..5 {
            body.step().unwrap();
        }
    });
    body.positions()
        .iter()
        .chain(body.velocities())
        .flat_map(|p| p.to_array())
        .map(f32::to_bits)
        .collect()
}

fn run(
    kind: Option<VolumeConstraintKind>,
    solver: Solver,
    parallel: bool,
    threads: usize,
) -> Vec<u32> {
    let body = box_body(kind, -4.0);
    assert!(
        body.block_count() >= 15,
        "too few blocks to exercise the parallel path"
    );
    five_steps(body, solver, parallel, threads)
}

#[test]
fn parallel_is_bit_identical_for_any_thread_count_and_to_serial() {
    for (kind, solver) in [
        (Some(VolumeConstraintKind::Centroid), Solver::PbdLinearised),
        (Some(VolumeConstraintKind::Classic), Solver::Xpbd),
        (None, Solver::Xpbd),
    ] {
        let serial = run(kind, solver, false, 1);
        for threads in [1, 2, 3] {
            assert!(
                run(kind, solver, true, threads) == serial,
                "{kind:?} {solver:?}: {threads} threads differ from serial"
            );
        }
    }
}

/// A body cut in place through the edit API (nodes on the plane x = 0 duplicated, the tets on
/// the right moved onto the copies, new tets, edges and a link constraint added, one edge
/// removed). The changed constraints keep their tree lanes, the added ones are projected in
/// their blocks of the tree (the copies take spare slots of their sources' leaves); with `full`
/// (the leaves' spare slots used up before the cut) most of both are in the serial set after
/// the tree. Parallel stays bit-identical either way.
fn run_cut(
    kind: Option<VolumeConstraintKind>,
    solver: Solver,
    parallel: bool,
    threads: usize,
    full: bool,
) -> Vec<u32> {
    let mut body = box_body(kind, -6.0);
    // Separate along x = 0 for z > 0 (a partial cut): nodes on that half-plane get a copy used
    // by the tets whose centroid is at x > 0.
    let x: Vec<Vec3> = body.positions().iter().map(|p| Vec3::from(*p)).collect();
    let on_cut: Vec<u32> = (0..x.len() as u32)
        .filter(|&i| x[i as usize].x.abs() < 1e-4 && x[i as usize].z > 0.1)
        .collect();
    if full {
        // Loose copies (no constraint) until every leaf of a cut node is full: each leaf has as
        // many spares as real nodes, fewer than the box's nodes.
        let sources: Vec<u32> = (0..x.len() as u32).collect();
        body.duplicate_nodes(&sources).unwrap();
    }
    let first = body.duplicate_nodes(&on_cut).unwrap();
    let copy = |i: u32| {
        on_cut
            .iter()
            .position(|&c| c == i)
            .map(|k| first + k as u32)
    };
    let tets: Vec<[u32; 4]> = body.tets().to_vec();
    let (mut moved, mut added) = (Vec::new(), Vec::new());
    for (t, tet) in tets.iter().enumerate() {
        let c: f32 = tet.iter().map(|&i| x[i as usize].x).sum::<f32>() / 4.0;
        if c > 0.0 && tet.iter().any(|&i| copy(i).is_some()) {
            let nodes = tet.map(|i| copy(i).unwrap_or(i));
            body.set_tet_nodes(t, nodes).unwrap();
            moved.push(t);
            // Every third one doubled by a new tet (the same rest shape).
            if moved.len() % 3 == 0 {
                let rest = nodes.map(|i| Vec3::from(body.rest_positions()[i as usize]).as_dvec3());
                added.push(body.add_tet(t, nodes, rest).unwrap());
            }
        }
    }
    // Edges between two cut nodes now exist on both sides.
    let records: Vec<_> = body.distance_constraints().to_vec();
    for r in records {
        if let (Some(a), Some(b)) = (copy(r.nodes[0]), copy(r.nodes[1])) {
            body.add_distance_constraint(tissue_pbd::DistanceConstraint { nodes: [a, b], ..r })
                .unwrap();
        }
    }
    for (k, &i) in on_cut.iter().enumerate() {
        body.set_node_mass(first + k as u32, body.masses()[i as usize] * 0.5)
            .unwrap();
        body.set_node_mass(i, body.masses()[i as usize] * 0.5)
            .unwrap();
    }
    let link = body
        .add_distance_constraint(tissue_pbd::DistanceConstraint {
            nodes: [on_cut[0], first + 3],
            rest_length: 0.0,
            stiffness: 1.0,
            compliance: 0.0,
        })
        .unwrap();
    body.remove_distance_constraint(link).unwrap();
    let link = body
        .add_link_constraint(tissue_pbd::DistanceConstraint {
            nodes: [on_cut[2], first + 7],
            rest_length: 0.0,
            stiffness: 1.0,
            compliance: 0.0,
        })
        .unwrap();
    body.add_link_constraint(tissue_pbd::DistanceConstraint {
        nodes: [on_cut[4], first + 9],
        rest_length: 0.1,
        stiffness: 0.8,
        compliance: 1e-4,
    })
    .unwrap();
    body.remove_distance_constraint(link).unwrap();
    body.add_distance_constraint(tissue_pbd::DistanceConstraint {
        nodes: [on_cut[1], first + 5],
        rest_length: 0.0,
        stiffness: 0.5,
        compliance: 1e-3,
    })
    .unwrap();
    // One tet split at the middle of an edge (one record reshaped, one appended, a node on the
    // edge), one rest length reset: the edits a cut through a tet makes.
    let tet = body.tets()[5];
    let m = body.duplicate_nodes(&[tet[0]]).unwrap();
    let r = |i: u32| Vec3::from(body.rest_positions()[i as usize]);
    let (rm, xm) = (
        (r(tet[0]) + r(tet[1])) * 0.5,
        Vec3::from(body.positions()[tet[0] as usize] + body.positions()[tet[1] as usize]) * 0.5,
    );
    body.set_rest_position(m, rm).unwrap();
    body.set_node_state(m, xm, xm, Vec3::ZERO).unwrap();
    let lo = [tet[0], m, tet[2], tet[3]];
    let hi = [m, tet[1], tet[2], tet[3]];
    let shape = |b: &SoftBody, t: [u32; 4]| {
        t.map(|i| Vec3::from(b.rest_positions()[i as usize]).as_dvec3())
    };
    let rest_lo = shape(&body, lo);
    body.reshape_tet(5, lo, rest_lo).unwrap();
    let rest_hi = shape(&body, hi);
    body.add_tet(5, hi, rest_hi).unwrap();
    let d = body.distance_constraints()[3];
    body.reset_distance_constraint(3, d.nodes, 0.9 * d.rest_length)
        .unwrap();
    assert!(body.dynamic_counts().0 > 0 && body.dynamic_counts().1 > 0);
    // Packed: several dynamic constraints share a batch.
    assert!(body.dynamic_batch_counts().0 * 2 < body.dynamic_counts().0);
    assert!(body.dynamic_batch_counts().1 * 2 < body.dynamic_counts().1);
    // The reset edge (two tree nodes) keeps its lane.
    assert!(matches!(
        body.distance_slot(3),
        Some(ConstraintSlot::Tree { .. })
    ));
    let serial = body.serial_dynamic_counts();
    if full {
        // The copies are past the tree: their constraints are projected serially.
        assert!(serial.0 > 0 && serial.1 > 0, "{serial:?}");
        assert!(moved
            .iter()
            .chain(&added)
            .all(|&t| matches!(body.tet_slot(t), Some(ConstraintSlot::Dynamic { .. }))));
    } else {
        // Everything the cut changed or added is in the tree, none of it serial.
        assert_eq!(serial, (0, 0));
        assert_eq!(body.serial_dynamic_batch_counts(), (0, 0));
        let blocks = (0..body.distance_constraints().len())
            .filter(|&c| matches!(body.distance_slot(c), Some(ConstraintSlot::Block { .. })))
            .count();
        assert_eq!(blocks, body.dynamic_counts().0);
        // The moved tets keep their lanes in the tree (a copy is in its source's leaf, and no
        // other lane of a batch has the source); the added ones are in blocks of the tree.
        assert!(moved
            .iter()
            .all(|&t| matches!(body.tet_slot(t), Some(ConstraintSlot::Tree { .. }))));
        assert!(added
            .iter()
            .all(|&t| matches!(body.tet_slot(t), Some(ConstraintSlot::Block { .. }))));
        // Spread over several blocks, i.e. projected in parallel.
        let mut used: Vec<u32> = (0..body.tets().len())
            .filter_map(|t| match body.tet_slot(t) {
                Some(ConstraintSlot::Block { block, .. }) => Some(block),
                _ => None,
            })
            .collect();
        used.sort_unstable();
        used.dedup();
        assert!(used.len() >= 4, "{used:?}");
    }
    five_steps(body, solver, parallel, threads)
}

#[test]
fn a_cut_body_is_bit_identical_in_parallel_and_serial() {
    for (kind, solver) in [
        (Some(VolumeConstraintKind::Centroid), Solver::PbdLinearised),
        (Some(VolumeConstraintKind::Classic), Solver::Xpbd),
        (None, Solver::Xpbd),
    ] {
        for full in [false, true] {
            let serial = run_cut(kind, solver, false, 1, full);
            for threads in [1, 2, 3] {
                assert!(
                    run_cut(kind, solver, true, threads, full) == serial,
                    "{kind:?} {solver:?} full {full}: cut body, {threads} threads differ from serial"
                );
            }
        }
    }
}
