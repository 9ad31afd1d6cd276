//! Detection between two surfaces (SPEC A.4): BVH vs BVH, BVH vs voxels, and the brute-force
//! oracle. All three run the same narrow phase on the (edge, triangle) candidates their broad
//! phase finds, each candidate once, and return the same contact set, sorted by
//! [`Contact::key`].

use tissue_bvh::Bvh;

use crate::edge_triangle::TrianglePlane;
use crate::narrow::{ChunkState, Narrow};
use crate::{
    CollideError, Contact, ContactParams, DetectStats, DetectWorkspace, Side, SurfaceView,
    VoxelGrid,
};

fn check_views(
    a: &SurfaceView<'_>,
    b: &SurfaceView<'_>,
    params: &ContactParams,
) -> Result<(), CollideError> {
    params.validate()?;
    for (view, side) in [(a, Side::A), (b, Side::B)] {
        if view.side() != side {
            return Err(CollideError::WrongSide {
                expected: side,
                got: view.side(),
            });
        }
    }
    if params.shared_particles && a.positions().len() != b.positions().len() {
        return Err(CollideError::ParticleCount {
            side: Side::B,
            what: "positions (shared with surface A)",
            expected: a.positions().len(),
            got: b.positions().len(),
        });
    }
    Ok(())
}

fn check_bvh(view: &SurfaceView<'_>, bvh: &Bvh) -> Result<(), CollideError> {
    let expected = view.surface().triangle_count();
    if bvh.primitive_count() != expected {
        return Err(CollideError::TriangleCount {
            side: view.side(),
            what: "hierarchy",
            expected,
            got: bvh.primitive_count(),
        });
    }
    Ok(())
}

/// Candidates per chunk below which the narrow phase stays on the calling thread.
#[cfg(feature = "parallel")]
const PARALLEL_MIN: usize = 512;

/// The chunks' contacts (each sorted by [`Contact::key`]) merged into `contacts`, sorted. Keys
/// are unique, so the result is the one order of the set, whatever the chunking.
fn merge_sorted(chunks: &[ChunkState], contacts: &mut Vec<Contact>) {
    contacts.clear();
    if let [only] = chunks {
        contacts.extend_from_slice(&only.out);
        return;
    }
    if chunks.len() > MERGE_MAX {
        for state in chunks {
            contacts.extend_from_slice(&state.out);
        }
        contacts.sort_unstable_by_key(Contact::key);
        return;
    }
    let mut heads = [0usize; MERGE_MAX];
    loop {
        let mut best: Option<usize> = None;
        for (i, state) in chunks.iter().enumerate() {
            if let Some(c) = state.out.get(heads[i]) {
                if best.is_none_or(|b| c.key() < chunks[b].out[heads[b]].key()) {
                    best = Some(i);
                }
            }
        }
        let Some(i) = best else {
            break;
        };
        contacts.push(chunks[i].out[heads[i]]);
        heads[i] += 1;
    }
}

/// Chunks merged directly by [`merge_sorted`] (more are concatenated and sorted).
const MERGE_MAX: usize = 16;

/// Runs `body` on every candidate, in consecutive chunks (one per rayon thread when there are at
/// least [`PARALLEL_MIN`] candidates per thread, feature `parallel`), each chunk sorting its
/// own contacts on its thread, then merges the chunks' contacts into `contacts` sorted by
/// [`Contact::key`]. Each contact is computed by the same kernel
/// from the same data whichever chunk meets it, and the keys are unique, so the result does not
/// depend on the number of threads.
fn run_narrow<B>(
    a: &SurfaceView<'_>,
    b: &SurfaceView<'_>,
    params: &ContactParams,
    candidates: &[[u32; 2]],
    chunks: &mut Vec<ChunkState>,
    contacts: &mut Vec<Contact>,
    body: B,
) -> DetectStats
where
    B: Fn(&mut Narrow<'_, '_>, [u32; 2]) + Sync,
{
    #[cfg(feature = "parallel")]
    let k = rayon::current_num_threads()
        .min(candidates.len() / PARALLEL_MIN)
        .max(1);
    #[cfg(not(feature = "parallel"))]
    let k = 1;
    if chunks.len() < k {
        chunks.resize_with(k, ChunkState::default);
    }
    let per = candidates.len().div_ceil(k).max(1);
    let work = |(i, state): (usize, &mut ChunkState)| {
        let mut nw = Narrow::new(a, b, params.tolerance, params.shared_particles, state);
        for &c in candidates.iter().skip(i * per).take(per) {
            body(&mut nw, c);
        }
        // Each chunk sorts its own contacts (on its thread); the chunks are merged below.
        state.out.sort_unstable_by_key(Contact::key);
    };
    #[cfg(feature = "parallel")]
    if k > 1 {
        use rayon::prelude::*;
        chunks[..k].par_iter_mut().enumerate().for_each(work);
    } else {
        work((0, &mut chunks[0]));
    }
    #[cfg(not(feature = "parallel"))]
    work((0, &mut chunks[0]));
    contacts.clear();
    let mut stats = DetectStats {
        candidates: candidates.len() as u32,
        ..DetectStats::default()
    };
    for state in &chunks[..k] {
        stats.triangle_pairs += state.stats.triangle_pairs;
        stats.edge_tests += state.stats.edge_tests;
    }
    merge_sorted(&chunks[..k], contacts);
    stats.contacts = contacts.len() as u32;
    stats
}

/// Contacts between surface `a` (side A, with its hierarchy `bvh_a`) and `b` (side B, `bvh_b`),
/// written to `contacts` (cleared first) sorted by [`Contact::key`].
///
/// Broad phase: [`Bvh::leaf_pairs`] with the tolerance as gap. Narrow phase: for each leaf pair,
/// every triangle pair whose boxes overlap (grown by the tolerance), then the edges each triangle
/// owns against the other triangle ([`crate::edge_triangle`]). Both hierarchies must be up to
/// date with the positions (built or refit on them).
///
/// # Errors
/// [`CollideError::WrongSide`] if the views are not tagged A and B, [`CollideError::TriangleCount`]
/// if a hierarchy belongs to another surface, [`CollideError::InvalidParameter`] for a bad
/// tolerance, [`CollideError::ParticleCount`] if shared particle arrays differ in length.
pub fn detect_bvh_bvh(
    a: &SurfaceView<'_>,
    bvh_a: &Bvh,
    b: &SurfaceView<'_>,
    bvh_b: &Bvh,
    params: &ContactParams,
    ws: &mut DetectWorkspace,
    contacts: &mut Vec<Contact>,
) -> Result<DetectStats, CollideError> {
    check_views(a, b, params)?;
    check_bvh(a, bvh_a)?;
    check_bvh(b, bvh_b)?;
    let tol = params.tolerance;
    {
        let _span = tracing::trace_span!("broad_phase", method = "bvh_bvh").entered();
        bvh_a.leaf_pairs(bvh_b, tol, &mut ws.bvh, &mut ws.pairs);
    }
    let _span = tracing::trace_span!("narrow_phase", leaf_pairs = ws.pairs.len()).entered();
    let stats = run_narrow(
        a,
        b,
        params,
        &ws.pairs,
        &mut ws.chunks,
        contacts,
        |nw, [la, lb]| {
            let leaf_b = bvh_b.nodes()[lb as usize].aabb;
            nw.gather_b(bvh_b.leaf_primitives(lb));
            for &ta in bvh_a.leaf_primitives(la) {
                let ta = nw.tri(Side::A, ta);
                if ta.aabb.overlaps(&leaf_b, tol) {
                    nw.against_gathered(&ta, |_| true);
                }
            }
        },
    );
    Ok(stats)
}

/// Contacts between surface `a` (side A, hierarchy `bvh_a`) and `b` (side B, represented by its
/// voxel grid `grid_b`), the same set [`detect_bvh_bvh`] returns.
///
/// Broad phase (SPEC A.4): every occupied cell of `grid_b` is tested against `bvh_a` from the
/// root ([`Bvh::overlapping_leaves`]). Narrow phase: for a (cell, leaf) pair, each triangle `ta`
/// of the leaf whose box overlaps the cell against each triangle `tb` the cell lists, with
/// overlapping boxes. A pair `(ta, tb)` meets in every cell `tb` spans that `ta` overlaps; it is
/// tested only in the first of them (the first cell in `tb`'s list whose box overlaps `ta`'s), so
/// once. Any pair that has a contact has a common point within the tolerance inside some cell of
/// `tb`, so that first cell exists. `bvh_a` and `grid_b` must be up to date with the positions.
///
/// # Errors
/// As [`detect_bvh_bvh`]; [`CollideError::TriangleCount`] if the grid belongs to another surface.
pub fn detect_bvh_voxels(
    a: &SurfaceView<'_>,
    bvh_a: &Bvh,
    b: &SurfaceView<'_>,
    grid_b: &VoxelGrid,
    params: &ContactParams,
    ws: &mut DetectWorkspace,
    contacts: &mut Vec<Contact>,
) -> Result<DetectStats, CollideError> {
    check_views(a, b, params)?;
    check_bvh(a, bvh_a)?;
    if grid_b.triangle_count() != b.surface().triangle_count() {
        return Err(CollideError::TriangleCount {
            side: Side::B,
            what: "voxel grid",
            expected: b.surface().triangle_count(),
            got: grid_b.triangle_count(),
        });
    }
    let tol = params.tolerance;
    {
        let _span = tracing::trace_span!("broad_phase", method = "bvh_voxels").entered();
        ws.pairs.clear();
        for &cell in grid_b.occupied_cells() {
            let cell_box = grid_b.cell_box_with_slack(cell);
            bvh_a.overlapping_leaves(&cell_box, tol, &mut ws.bvh, &mut ws.leaves);
            ws.pairs.extend(ws.leaves.iter().map(|&leaf| [cell, leaf]));
        }
    }
    let _span = tracing::trace_span!("narrow_phase", cell_leaf_pairs = ws.pairs.len()).entered();
    let stats = run_narrow(
        a,
        b,
        params,
        &ws.pairs,
        &mut ws.chunks,
        contacts,
        |nw, [cell, leaf]| {
            let cell_box = grid_b.cell_box_with_slack(cell);
            nw.gather_b(grid_b.cell_triangles(cell));
            for &ta in bvh_a.leaf_primitives(leaf) {
                let ta = nw.tri(Side::A, ta);
                if ta.aabb.overlaps(&cell_box, tol) {
                    // The pair is tested only in the first of tb's cells that ta overlaps.
                    nw.against_gathered(&ta, |tb| {
                        grid_b.first_cell_overlapping(tb.t, &ta.aabb, tol) == Some(cell)
                    });
                }
            }
        },
    );
    Ok(stats)
}

/// Contacts by testing every edge of each surface against every triangle of the other with
/// [`crate::edge_triangle`] (each triangle's plane prepared once): the oracle the other methods
/// are checked against (`O(edges × triangles)`, for tests; allocates).
///
/// # Errors
/// As [`detect_bvh_bvh`] (without the hierarchy checks).
pub fn detect_brute_force(
    a: &SurfaceView<'_>,
    b: &SurfaceView<'_>,
    params: &ContactParams,
    contacts: &mut Vec<Contact>,
) -> Result<DetectStats, CollideError> {
    check_views(a, b, params)?;
    let mut state = ChunkState::default();
    let mut nw = Narrow::new(a, b, params.tolerance, params.shared_particles, &mut state);
    for (ev, tv) in [(*a, *b), (*b, *a)] {
        let planes: Vec<TrianglePlane> = (0..tv.surface().triangle_count() as u32)
            .map(|t| {
                let [x, y, z] = tv.corners(t);
                TrianglePlane::new(x, y, z)
            })
            .collect();
        for e in 0..ev.surface().edges().len() as u32 {
            for (t, plane) in planes.iter().enumerate() {
                nw.edge(&ev, e, &tv, t as u32, plane);
            }
        }
    }
    contacts.clear();
    contacts.extend_from_slice(&state.out);
    contacts.sort_unstable_by_key(Contact::key);
    Ok(DetectStats {
        contacts: contacts.len() as u32,
        ..state.stats
    })
}
