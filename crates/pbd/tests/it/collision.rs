//! Contacts with static voxel colliders and kinematic tools ("Collisions"): resting,
//! volume on a tray, friction on a slope, tools pushing and dragging, no tunnelling, the distance
//! field against brute force, and bad input.
#![allow(clippy::print_stderr, clippy::unwrap_used)]

use crate::common;

use std::sync::Arc;

use common::{bunny, fixture, Rng};
use glam::{DVec3, Quat, Vec3, Vec3A};
use tissue_mesh::{tet_box, TetMesh, TriMesh};
use tissue_pbd::{
    ColliderShape, ContactParams, ContactSource, Material, OrientedBox, PbdError, PbdParam, Pose,
    SoftBody, StepSettings, ToolShape, VolumeConstraintKind, VoxelCollider,
};

/// A 40 × 40 cm tray, 2 cm thick, top at `y = top`, as a voxel collider of 0.5 cm cells.
fn tray(top: f32) -> Arc<VoxelCollider> {
    Arc::new(
        VoxelCollider::from_box(OrientedBox::tray(0.0, 0.0, top, 40.0, 40.0, 2.0), 0.5).unwrap(),
    )
}

fn translated(mesh: &TetMesh, by: Vec3) -> TetMesh {
    TetMesh::new(
        mesh.positions().iter().map(|p| *p + by).collect(),
        mesh.tets().to_vec(),
    )
    .unwrap()
}

/// The smallest `V/V₀` over the tets.
fn min_tet_ratio(body: &SoftBody, rest: &[Vec3]) -> f64 {
    let six = |q: [DVec3; 4]| (q[1] - q[0]).cross(q[2] - q[0]).dot(q[3] - q[0]);
    body.tets()
        .iter()
        .map(|t| {
            let now = six(t.map(|i| body.positions()[i as usize].as_dvec3()));
            let before = six(t.map(|i| rest[i as usize].as_dvec3()));
            now / before
        })
        .fold(f64::INFINITY, f64::min)
}

/// Deepest node inside the collider (cm, ≥ 0).
fn max_penetration(body: &SoftBody, collider: &VoxelCollider) -> f32 {
    body.positions()
        .iter()
        .filter_map(|p| collider.signed_distance((*p).into()))
        .fold(0.0f32, |m, d| m.max(-d))
}

#[test]
fn armadillo_dropped_on_a_tray_comes_to_rest_without_inverted_tets_or_penetration() {
    let data = tissue_meshio::read_tetgen(fixture("armadillo_4k")).unwrap();
    // The model is about 3 units tall: ×5 makes a 15 cm figure of 230 g. It is dropped upside
    // down from 0.5 cm: standing, it topples (its PBD legs are soft at this step), and in the
    // other orientations tried the topple's impact leaves one or two tets inverted against the
    // tray, where they stay trapped (recovering would take a node through the tray). With the
    // `Floor` the same happens: it is the solver's limit, not the contacts'.
    let flip = Quat::from_rotation_x(std::f32::consts::PI);
    let scaled: Vec<Vec3> = data.positions.iter().map(|p| flip * (*p * 5.0)).collect();
    let min_y = scaled.iter().map(|p| p.y).fold(f32::INFINITY, f32::min);
    let mesh = TetMesh::new(
        scaled
            .iter()
            .map(|p| *p + Vec3::new(0.0, 0.5 - min_y, 0.0))
            .collect(),
        data.tets,
    )
    .unwrap();
    let height = mesh.positions().iter().map(|p| p.y).fold(0.0f32, f32::max) - 0.5;
    let material = Material {
        distance_stiffness: 1.0,
        volume_stiffness: 1.0,
        volume: VolumeConstraintKind::Classic,
        ..Material::default()
    };
    let mut body = SoftBody::new(&mesh, &material).unwrap();
    // A 60 cm tray: the figure topples over.
    let tray = Arc::new(
        VoxelCollider::from_box(OrientedBox::tray(0.0, 0.0, 0.0, 60.0, 60.0, 2.0), 0.5).unwrap(),
    );
    body.add_collider(tray.clone(), ContactParams::default())
        .unwrap();
    // 2 ms, K = 10: at 5 ms the impact leaves tets inverted.
    body.set_settings(StepSettings {
        dt: 0.002,
        iterations: 10,
        damping: 0.05,
        ..StepSettings::default()
    })
    .unwrap();
    let (mut worst_depth, mut worst_ratio) = (0.0f32, f64::INFINITY);
    let mut touched = false;
    for _ in 0..1250 {
        body.step().unwrap();
        worst_depth = worst_depth.max(max_penetration(&body, &tray));
        worst_ratio = worst_ratio.min(min_tet_ratio(&body, mesh.positions()));
        touched |= !body.contacts().is_empty();
    }
    let ratio = min_tet_ratio(&body, mesh.positions());
    let depth = max_penetration(&body, &tray);
    let mass = body.total_mass();
    let v_rms = (2.0 * body.kinetic_energy() / mass).sqrt();
    let lowest = body
        .positions()
        .iter()
        .map(|p| p.y)
        .fold(f32::INFINITY, f32::min);
    eprintln!(
        "armadillo ({} nodes, {} tets, {height:.1} cm tall, {mass:.0} g) dropped 0.5 cm upside down, after 2.5 s: min tet V/V₀ {ratio:.3} at rest ({worst_ratio:.2} at worst during the impact), max penetration {depth:.1e} cm at rest ({worst_depth:.1e} cm at worst), rms speed {v_rms:.3} cm/s, lowest node y = {lowest:.4} cm, {} contacts",
        mesh.vertex_count(),
        mesh.tet_count(),
        body.contacts().len()
    );
    assert!(touched, "the armadillo never reached the tray");
    assert!(
        ratio > 0.25,
        "a tet is inverted or crushed at rest: min V/V₀ = {ratio}"
    );
    // The tolerance of "no node inside": 10 µm.
    assert!(
        depth <= 1e-3,
        "a node is {depth} cm inside the tray at rest"
    );
    assert!(
        worst_depth <= 1e-3,
        "a node went {worst_depth} cm into the tray"
    );
    assert!(v_rms < 0.5, "not at rest: rms speed {v_rms} cm/s");
    assert!(lowest < 0.1, "it floats at {lowest} cm");
}

/// Rests `mesh` (standing on y = 0) on the tray under gravity for `steps` steps and returns the
/// volume ratio, the max penetration and the mean step time (ms).
fn rest_on_voxel_tray(
    mesh: &TetMesh,
    volume: VolumeConstraintKind,
    steps: usize,
    dt: f32,
    iterations: u32,
) -> (f64, f32, f64) {
    let material = Material {
        distance_stiffness: 0.5,
        volume_stiffness: 1.0,
        volume,
        ..Material::default()
    };
    let mut body = SoftBody::new(mesh, &material).unwrap();
    let tray = tray(0.0);
    body.add_collider(tray.clone(), ContactParams::default())
        .unwrap();
    body.set_settings(StepSettings {
        dt,
        iterations,
        damping: 0.05,
        ..StepSettings::default()
    })
    .unwrap();
    let t = std::time::Instant::now();
    for _ in 0..steps {
        body.step().unwrap();
    }
    let ms = t.elapsed().as_secs_f64() * 1e3 / steps as f64;
    (
        body.volume() / body.rest_volume(),
        max_penetration(&body, &tray),
        ms,
    )
}

#[test]
fn bunny_resting_on_the_voxel_tray_keeps_its_volume_with_volume_constraints() {
    let mesh = bunny();
    // The benchmark step (10 ms, K = 10) cannot hold 2 %: with the tray as with the
    // `Floor`, the classic constraint ends near 0.88 and the centroid one near 0.57 after 1 s
    // (K = 40 at 10 ms: 0.96). 2 ms with K = 10 holds it; that is what is asserted, over the same
    // 0.3 s as the `Floor` test of physics.rs. The 10 ms run is kept to show the difference.
    let (dt, k, steps) = (0.002, 10, 150);
    let (classic, pv, tv) = rest_on_voxel_tray(&mesh, VolumeConstraintKind::Classic, steps, dt, k);
    let (none, pn, tn) = rest_on_voxel_tray(&mesh, VolumeConstraintKind::None, steps, dt, k);
    let (coarse, pc, tc) = rest_on_voxel_tray(&mesh, VolumeConstraintKind::Classic, 100, 0.01, 10);
    eprintln!(
        "{} tets on the voxel tray, distance k = 0.5, volume k = 1: {steps} steps of {} ms, K = {k}: V/V₀ classic {classic:.4} ({tv:.2} ms/step, max penetration {pv:.1e} cm), none {none:.4} ({tn:.2} ms/step, {pn:.1e} cm); 100 steps of 10 ms, K = 10: classic {coarse:.4} ({tc:.2} ms/step, {pc:.1e} cm)",
        mesh.tet_count(),
        dt * 1e3
    );
    assert!(
        (classic - 1.0).abs() <= 0.02,
        "classic constraint lost volume on the tray: {classic}"
    );
    assert!(
        1.0 - none > 0.04 && 1.0 - none > 2.0 * (classic - 1.0).abs(),
        "without volume constraints: {none}"
    );
    assert!(pv.max(pn).max(pc) <= 1e-3, "nodes inside the tray");
}

/// A 3 × 1 × 3 cm block resting on a tray tilted by `angle` about z, with friction `mu` (static
/// = kinetic). Returns the downhill displacement of the centre of mass over `seconds`, and the
/// mean downhill acceleration measured between 0.1 s and the end.
fn block_on_slope(angle: f32, mu: f32, seconds: f32) -> (f64, f64) {
    let dt = 0.005;
    let rot = Quat::from_rotation_z(angle);
    let slope = OrientedBox::tray(0.0, 0.0, 0.0, 40.0, 40.0, 2.0).rotated(rot);
    let collider = VoxelCollider::from_box(slope, 0.5).unwrap();
    let normal = rot * Vec3::Y;
    let downhill = -(rot * Vec3::X);
    let block = tet_box(6, 2, 6, Vec3::new(3.0, 1.0, 3.0)).unwrap();
    let centre = slope.center + normal * (1.0 + 0.5 + 1e-3);
    let placed = TetMesh::new(
        block
            .positions()
            .iter()
            .map(|p| rot * *p + centre)
            .collect(),
        block.tets().to_vec(),
    )
    .unwrap();
    let material = Material {
        distance_stiffness: 1.0,
        volume_stiffness: 1.0,
        volume: VolumeConstraintKind::Classic,
        ..Material::default()
    };
    let mut body = SoftBody::new(&placed, &material).unwrap();
    body.add_collider(
        collider,
        ContactParams {
            static_friction: mu,
            kinetic_friction: mu,
            ..ContactParams::default()
        },
    )
    .unwrap();
    body.set_settings(StepSettings {
        dt,
        iterations: 10,
        damping: 0.05,
        ..StepSettings::default()
    })
    .unwrap();
    let com = |b: &SoftBody| {
        let m = b.total_mass();
        b.masses()
            .iter()
            .zip(b.positions())
            .map(|(&mi, p)| mi as f64 * p.as_dvec3())
            .sum::<DVec3>()
            / m
    };
    let vel = |b: &SoftBody| b.linear_momentum().dot(downhill.as_dvec3()) / b.total_mass();
    let start = com(&body);
    let steps = (seconds / dt).round() as usize;
    let (mut v1, mut t1) = (0.0, 0.0);
    for s in 1..=steps {
        body.step().unwrap();
        if s == (0.1 / dt) as usize {
            (v1, t1) = (vel(&body), s as f64 * dt as f64);
        }
    }
    let accel = (vel(&body) - v1) / (steps as f64 * dt as f64 - t1);
    ((com(&body) - start).dot(downhill.as_dvec3()), accel)
}

#[test]
fn friction_holds_a_block_above_tan_angle_and_lets_it_slide_below() {
    let angle = 20f32.to_radians();
    let g = 981.0f64;
    let (stuck, stuck_a) = block_on_slope(angle, 0.6, 0.5);
    let (slid, a) = block_on_slope(angle, 0.2, 0.4);
    let expected = g * (angle.sin() as f64 - 0.2 * angle.cos() as f64);
    let frictionless = g * angle.sin() as f64;
    eprintln!(
        "slope 20° (tan = {:.3}): μ = 0.6 moved {stuck:.2e} cm in 0.5 s (a = {stuck_a:.2} cm/s²); μ = 0.2 slid {slid:.2} cm in 0.4 s, a = {a:.1} cm/s² vs g(sinθ − μcosθ) = {expected:.1} (frictionless {frictionless:.1})",
        angle.tan()
    );
    assert!(
        stuck.abs() < 0.01,
        "μ > tanθ but the block moved {stuck} cm"
    );
    assert!(
        (a - expected).abs() <= 0.1 * expected,
        "sliding acceleration {a} cm/s², expected {expected}"
    );
}

/// A 6 × 3 × 6 cm block of 0.5 cm cells, bottom pinned, top at y = 3.
fn pinned_block() -> (TetMesh, SoftBody) {
    let mesh = translated(
        &tet_box(12, 6, 12, Vec3::new(6.0, 3.0, 6.0)).unwrap(),
        Vec3::new(0.0, 1.5, 0.0),
    );
    let material = Material {
        distance_stiffness: 0.9,
        volume_stiffness: 1.0,
        volume: VolumeConstraintKind::Classic,
        ..Material::default()
    };
    let mut body = SoftBody::new(&mesh, &material).unwrap();
    for (i, p) in mesh.positions().iter().enumerate() {
        if p.y < 1e-4 {
            body.pin(i as u32).unwrap();
        }
    }
    body.set_settings(StepSettings {
        dt: 0.005,
        iterations: 10,
        damping: 0.05,
        ..StepSettings::default()
    })
    .unwrap();
    (mesh, body)
}

#[test]
fn capsule_pressed_into_a_block_keeps_nodes_out_and_drags_tissue() {
    let (mesh, mut body) = pinned_block();
    let radius = 0.4;
    let capsule = ToolShape::Capsule {
        a: Vec3::new(0.0, 0.0, -4.0),
        b: Vec3::new(0.0, 0.0, 4.0),
        radius,
    };
    let above = Vec3::new(0.0, 3.0 + radius + 0.2, 0.0);
    let id = body
        .add_tool(
            capsule,
            Pose::from_translation(above),
            ContactParams::default(),
        )
        .unwrap();
    let axis_distance = |body: &SoftBody, at: Vec3| {
        body.positions()
            .iter()
            .map(|p| Vec3::new(p.x - at.x, p.y - at.y, 0.0).length())
            .fold(f32::INFINITY, f32::min)
    };
    let mut closest = f32::INFINITY;
    let mut at = above;
    // Press 1.4 cm down over 40 steps (7 cm/s), so the axis ends 0.8 cm below the top.
    for _ in 0..40 {
        at.y -= 1.4 / 40.0;
        body.set_tool_pose(id, Pose::from_translation(at)).unwrap();
        body.step().unwrap();
        closest = closest.min(axis_distance(&body, at));
    }
    for _ in 0..20 {
        body.step().unwrap();
        closest = closest.min(axis_distance(&body, at));
    }
    let under: Vec<u32> = body
        .contacts()
        .iter()
        .filter(|c| c.source == ContactSource::Tool(id))
        .map(|c| c.node)
        .collect();
    let before: Vec<Vec3A> = body.positions().to_vec();
    let top_sag = 3.0 - body.positions()[under[0] as usize].y;
    // Drag 1.5 cm along +x over 60 steps (5 cm/s).
    let drag = 1.5;
    for _ in 0..60 {
        at.x += drag / 60.0;
        body.set_tool_pose(id, Pose::from_translation(at)).unwrap();
        body.step().unwrap();
        closest = closest.min(axis_distance(&body, at));
    }
    let dragged = under
        .iter()
        .map(|&i| body.positions()[i as usize].x - before[i as usize].x)
        .sum::<f32>()
        / under.len() as f32;
    let far = mesh
        .positions()
        .iter()
        .enumerate()
        .filter(|(_, p)| p.x.abs() > 2.9 && p.y > 2.9)
        .map(|(i, _)| (body.positions()[i].x - before[i].x).abs())
        .fold(0.0f32, f32::max);
    eprintln!(
        "capsule r = {radius} cm pressed 1.4 cm into a pinned block: closest node to the axis {closest:.4} cm (over every step), {} nodes in contact, top pushed down {top_sag:.2} cm; dragged 1.5 cm: those nodes moved {dragged:.2} cm along, the far edges at most {far:.3} cm",
        under.len()
    );
    assert!(under.len() >= 10, "the capsule barely touches the block");
    assert!(
        closest >= radius - 0.01,
        "a node came within {closest} cm of the axis (radius {radius})"
    );
    assert!(top_sag > 0.5, "the capsule did not press the block in");
    assert!(
        dragged > 0.3 * drag,
        "dragging moved the touched tissue by only {dragged} cm"
    );
}

/// A blade dropping 3 cm in one step through a 0.4 cm slab hung by two opposite edges. Returns
/// how far the highest node under the blade's footprint is above the blade's lower face after
/// each of three steps (≤ 0: none tunnelled).
fn blade_through_slab(continuous: bool) -> f32 {
    let mesh = tet_box(12, 1, 12, Vec3::new(6.0, 0.4, 6.0)).unwrap();
    let material = Material {
        distance_stiffness: 0.5,
        volume: VolumeConstraintKind::Classic,
        ..Material::default()
    };
    let mut body = SoftBody::new(&mesh, &material).unwrap();
    for (i, p) in mesh.positions().iter().enumerate() {
        if p.x.abs() > 2.99 {
            body.pin(i as u32).unwrap();
        }
    }
    body.set_settings(StepSettings {
        dt: 0.01,
        iterations: 10,
        gravity: Vec3::ZERO,
        ..StepSettings::default()
    })
    .unwrap();
    let thickness = 0.1;
    let (a, b, c) = (
        Vec3::new(-1.5, 0.0, -1.5),
        Vec3::new(1.5, 0.0, -1.5),
        Vec3::new(0.0, 0.0, 1.5),
    );
    let blade = ToolShape::Blade { a, b, c, thickness };
    let id = body
        .add_tool(
            blade,
            Pose::from_translation(Vec3::new(0.0, 1.0, 0.0)),
            ContactParams {
                continuous,
                ..ContactParams::frictionless()
            },
        )
        .unwrap();
    // Inside the blade's footprint, 0.3 cm from its edges.
    let footprint = |p: Vec3A| {
        let inside = |u: Vec3, v: Vec3| {
            let e = v - u;
            let n = Vec3::new(e.z, 0.0, -e.x).normalize(); // either side: both signs are accepted
            n.dot(Vec3::new(p.x, 0.0, p.z) - u)
        };
        let s = [inside(a, b), inside(b, c), inside(c, a)];
        s.iter().all(|&d| d < -0.3) || s.iter().all(|&d| d > 0.3)
    };
    let bottom = -2.0 - thickness / 2.0;
    body.set_tool_pose(id, Pose::from_translation(Vec3::new(0.0, -2.0, 0.0)))
        .unwrap();
    let mut worst = f32::NEG_INFINITY;
    let mut count = 0;
    for _ in 0..3 {
        body.step().unwrap();
        for &p in body.positions() {
            if footprint(p) {
                worst = worst.max(p.y - bottom);
                count += 1;
            }
        }
    }
    assert!(count > 0, "no node under the blade");
    worst
}

#[test]
fn a_fast_blade_does_not_tunnel_through_a_thin_slab() {
    let swept = blade_through_slab(true);
    let sampled = blade_through_slab(false);
    eprintln!("blade dropping 3 cm in one step through a 0.4 cm slab: highest node under the blade is {swept:+.4} cm above its lower face when swept, {sampled:+.3} cm when only the end pose is tested");
    assert!(
        swept <= 1e-3,
        "a node tunnelled through the swept blade: {swept} cm above its lower face"
    );
    // Without the sweep the slab is left behind: the test can tell.
    assert!(sampled > 1.0, "{sampled}");
}

/// Exact signed distance by brute force: the nearest triangle, the sign by the parity of a ray's
/// crossings in `f64` (a random direction, so no degenerate hits).
fn brute_force_distance(mesh: &TriMesh, p: Vec3, dir: DVec3) -> f64 {
    let mut best = f64::INFINITY;
    let mut crossings = 0;
    let p64 = p.as_dvec3();
    for t in 0..mesh.triangle_count() {
        let [a, b, c] = mesh.corners(t).map(|q| q.as_dvec3());
        // Closest point by dense reference: project and clamp via the three edge regions.
        let d = point_triangle_distance(p64, a, b, c);
        best = best.min(d);
        // Möller–Trumbore.
        let (e1, e2) = (b - a, c - a);
        let h = dir.cross(e2);
        let det = e1.dot(h);
        if det.abs() < 1e-15 {
            continue;
        }
        let s = p64 - a;
        let u = s.dot(h) / det;
        let q = s.cross(e1);
        let v = dir.dot(q) / det;
        let t = e2.dot(q) / det;
        if u >= 0.0 && v >= 0.0 && u + v <= 1.0 && t > 0.0 {
            crossings += 1;
        }
    }
    if crossings % 2 == 1 {
        -best
    } else {
        best
    }
}

/// Point–triangle distance in `f64` (minimum over the face if the projection is inside, else
/// over the three edges).
fn point_triangle_distance(p: DVec3, a: DVec3, b: DVec3, c: DVec3) -> f64 {
    let n = (b - a).cross(c - a);
    let n2 = n.length_squared();
    let proj = p - n * ((p - a).dot(n) / n2);
    let inside = [(a, b), (b, c), (c, a)]
        .iter()
        .all(|(u, v)| (*v - *u).cross(proj - *u).dot(n) >= 0.0);
    if inside {
        return (p - proj).length();
    }
    [(a, b), (b, c), (c, a)]
        .iter()
        .map(|(u, v)| {
            let e = *v - *u;
            let t = ((p - *u).dot(e) / e.length_squared()).clamp(0.0, 1.0);
            (p - (*u + e * t)).length()
        })
        .fold(f64::INFINITY, f64::min)
}

#[test]
fn voxel_distance_field_matches_brute_force_distance_to_the_mesh() {
    let surface = bunny().boundary_surface().unwrap();
    let cell = 0.25;
    let t = std::time::Instant::now();
    let collider = VoxelCollider::from_mesh(&surface, cell).unwrap();
    let build = t.elapsed().as_secs_f64();
    let (lo, hi) = collider.bounds();
    let mut rng = Rng(11);
    let dir = DVec3::new(0.3123, 0.8412, -0.4417).normalize();
    let (mut worst, mut sum, mut n, mut wrong_sign, mut inside) = (0.0f64, 0.0, 0, 0, 0);
    for _ in 0..400 {
        let u = Vec3::new(rng.signed(), rng.signed(), rng.signed()) * 0.5 + Vec3::splat(0.5);
        let p = lo + (hi - lo) * u * 0.999;
        let exact = brute_force_distance(&surface, p, dir);
        let got = collider.signed_distance(p).unwrap() as f64;
        let err = (got - exact).abs();
        worst = worst.max(err);
        sum += err;
        n += 1;
        if exact.abs() > cell as f64 && got.signum() != exact.signum() {
            wrong_sign += 1;
        }
        inside += (exact < 0.0) as usize;
    }
    eprintln!(
        "distance field of {} triangles, cell {cell} cm, {:?} corners, built in {build:.2} s, {} of {} cells occupied: over {n} random points ({inside} inside) max |error| {worst:.4} cm, mean {:.5} cm, {wrong_sign} wrong signs",
        surface.triangle_count(),
        collider.corner_counts(),
        collider.occupied_cell_count(),
        collider.cell_count(),
        sum / n as f64
    );
    assert!(inside > 10, "too few points inside to test the sign");
    assert_eq!(wrong_sign, 0);
    assert!(
        worst <= cell as f64,
        "error {worst} cm exceeds the cell size"
    );
}

#[test]
fn bad_collider_and_tool_input_is_refused_naming_where() {
    let b = OrientedBox::tray(0.0, 0.0, 0.0, 10.0, 10.0, 1.0);
    assert!(matches!(
        VoxelCollider::new(&[], 0.5, 0.5),
        Err(PbdError::InvalidParameter {
            param: PbdParam::Shapes,
            ..
        })
    ));
    for cell in [0.0, -1.0, f32::NAN] {
        assert!(matches!(
            VoxelCollider::from_box(b, cell),
            Err(PbdError::InvalidParameter {
                param: PbdParam::CellSize,
                ..
            })
        ));
    }
    let open = tissue_mesh::grid(5, 2.0).unwrap();
    let e = VoxelCollider::new(
        &[ColliderShape::Box(b), ColliderShape::Mesh(&open)],
        0.5,
        0.5,
    )
    .unwrap_err();
    assert!(
        matches!(e, PbdError::ColliderMeshNotClosed { shape: 1, .. }),
        "{e}"
    );
    assert!(e.to_string().contains("shape 1"), "{e}");
    let flat = OrientedBox {
        half_extents: Vec3::new(1.0, 0.0, 1.0),
        ..b
    };
    assert!(matches!(
        VoxelCollider::from_box(flat, 0.5),
        Err(PbdError::InvalidColliderShape { shape: 0, .. })
    ));
    assert!(matches!(
        VoxelCollider::from_box(b, 0.001),
        Err(PbdError::ColliderTooLarge { .. })
    ));

    let mut body =
        SoftBody::new(&tet_box(2, 2, 2, Vec3::ONE).unwrap(), &Material::default()).unwrap();
    let tray = VoxelCollider::from_box(b, 0.5).unwrap();
    let e = body
        .add_collider(
            tray.clone(),
            ContactParams {
                margin: 0.4,
                detection: 0.2,
                ..ContactParams::default()
            },
        )
        .unwrap_err();
    assert!(matches!(
        e,
        PbdError::InvalidParameter {
            param: PbdParam::ContactReach,
            ..
        }
    ));
    assert!(matches!(
        body.add_collider(
            tray.clone(),
            ContactParams {
                static_friction: -1.0,
                ..ContactParams::default()
            }
        ),
        Err(PbdError::InvalidParameter {
            param: PbdParam::StaticFriction,
            ..
        })
    ));
    assert_eq!(
        body.set_collider_params(3, ContactParams::default()),
        Err(PbdError::NoSuchContactSource {
            what: "collider",
            id: 3,
            count: 0
        })
    );
    let bad = [
        ToolShape::Capsule {
            a: Vec3::ZERO,
            b: Vec3::X,
            radius: 0.0,
        },
        ToolShape::Blade {
            a: Vec3::ZERO,
            b: Vec3::X,
            c: Vec3::X * 2.0,
            thickness: 0.1,
        },
        ToolShape::Blade {
            a: Vec3::ZERO,
            b: Vec3::X,
            c: Vec3::Y,
            thickness: -0.1,
        },
    ];
    for shape in bad {
        assert!(matches!(
            body.add_tool(shape, Pose::IDENTITY, ContactParams::default()),
            Err(PbdError::InvalidTool { .. })
        ));
    }
    let id = body
        .add_tool(
            ToolShape::Capsule {
                a: Vec3::ZERO,
                b: Vec3::X,
                radius: 0.1,
            },
            Pose::IDENTITY,
            ContactParams::default(),
        )
        .unwrap();
    assert!(matches!(
        body.set_tool_pose(
            id,
            Pose::new(Quat::from_xyzw(0.0, 0.0, 0.0, 2.0), Vec3::ZERO)
        ),
        Err(PbdError::InvalidTool { .. })
    ));
    assert_eq!(
        body.set_tool_pose(5, Pose::IDENTITY),
        Err(PbdError::NoSuchContactSource {
            what: "tool",
            id: 5,
            count: 1
        })
    );
}

#[test]
fn contacts_are_deterministic() {
    let run = || {
        let (_, mut body) = pinned_block();
        body.add_collider(tray(0.0), ContactParams::default())
            .unwrap();
        let id = body
            .add_tool(
                ToolShape::Blade {
                    a: Vec3::new(-1.0, 0.0, -1.0),
                    b: Vec3::new(1.0, 0.0, -1.0),
                    c: Vec3::new(0.0, 0.0, 1.0),
                    thickness: 0.05,
                },
                Pose::from_translation(Vec3::new(0.0, 3.5, 0.0)),
                ContactParams::default(),
            )
            .unwrap();
        for s in 0..20 {
            let q = Quat::from_rotation_x(0.02 * s as f32);
            body.set_tool_pose(
                id,
                Pose::new(q, Vec3::new(0.01 * s as f32, 3.5 - 0.06 * s as f32, 0.0)),
            )
            .unwrap();
            body.step().unwrap();
        }
        body.positions()
            .iter()
            .flat_map(|p| p.to_array())
            .map(f32::to_bits)
            .collect::<Vec<u32>>()
    };
    assert!(run() == run());
}
