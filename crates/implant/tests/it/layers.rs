//! The two-layer tissue model against the continuum slab it stands for.
#![allow(clippy::unwrap_used)]

use glam::{Vec3, Vec3A};
use tissue_implant::{ImplantError, Layer, LayerParams, Param, TissueLayers};
use tissue_mesh::{disc, uv_sphere, TriMesh};
use tissue_mss::{Integrator, StopCriterion, StopReason};

fn params() -> LayerParams {
    LayerParams {
        depth: 0.8,
        ..LayerParams::default()
    }
}

/// Sum of the forces on the free and fixed particles of one layer.
fn layer_force(layers: &TissueLayers, layer: Layer) -> Vec3 {
    layers
        .system()
        .particles()
        .forces()
        .iter()
        .skip(layer as usize)
        .step_by(2)
        .fold(Vec3::ZERO, |s, f| s + Vec3::from(*f))
}

fn shift_layer(layers: &mut TissueLayers, layer: Layer, by: Vec3) {
    for x in layers
        .system_mut()
        .particles_mut()
        .positions_mut()
        .iter_mut()
        .skip(layer as usize)
        .step_by(2)
    {
        *x += Vec3A::from(by);
    }
}

#[test]
fn structure_of_the_model() {
    let region = disc(6, 24, 3.0).unwrap();
    let p = params();
    let layers = TissueLayers::new(&region, &p).unwrap();
    let n = region.vertex_count();
    let e = region.topology().edges().len();
    let s = layers.system();
    assert_eq!(s.particles().len(), 2 * n);
    // Two layers of edge springs and one vertical per vertex (the shear is a force of its own).
    assert_eq!(s.springs().len(), 2 * e + n);
    // Layer 2 lies `depth` below the flat region.
    for (a, b) in layers
        .positions(Layer::Outer)
        .iter()
        .zip(layers.positions(Layer::Inner))
    {
        assert!((*a - b - Vec3::new(0.0, 0.0, 0.8)).length() < 1e-6);
    }
    // Boundary fixed in both layers.
    let fixed = s
        .particles()
        .inverse_masses()
        .iter()
        .filter(|&&w| w == 0.0)
        .count();
    assert_eq!(fixed, 2 * 24);
    assert_eq!(layers.boundary().len(), 24);
    // Mass = area × (skin thickness + depth) × density: the skin and the slab below it.
    let total: f64 = s.particles().masses().iter().map(|&m| f64::from(m)).sum();
    let expected = region.area() * (p.skin_thickness + p.depth) * p.density;
    assert!(
        (total - expected).abs() < 1e-5 * expected,
        "{total} vs {expected}"
    );
}

#[test]
fn no_force_at_rest() {
    let region = disc(6, 24, 3.0).unwrap();
    let mut layers = TissueLayers::new(&region, &params()).unwrap();
    layers.system_mut().compute_forces();
    let k_scale = params().young * 3.0 / params().depth; // a generous stiffness scale, g/s²
    let worst = layers
        .system()
        .particles()
        .forces()
        .iter()
        .map(|f| f.length())
        .fold(0.0f32, f32::max);
    assert!(
        f64::from(worst) < 1e-6 * k_scale,
        "largest force at rest {worst} dyn"
    );
}

#[test]
fn shear_of_the_outer_layer_meets_the_slab_shear_stiffness() {
    // Shifting layer 1 rigidly by u along x leaves the in-layer springs and the anchors alone:
    // only the interlayer springs act, and the slab's answer is G·A·u/depth.
    let region = disc(8, 32, 3.0).unwrap();
    let p = params();
    let mut layers = TissueLayers::new(&region, &p).unwrap();
    let u = 1e-4 * p.depth as f32;
    shift_layer(&mut layers, Layer::Outer, Vec3::new(u, 0.0, 0.0));
    layers.compute_forces();
    let f = layer_force(&layers, Layer::Outer);
    let g = p.slab_young / (2.0 * (1.0 + p.poisson));
    let expected = -g * region.area() * f64::from(u) / p.depth;
    assert!(
        (f64::from(f.x) - expected).abs() < 0.01 * expected.abs(),
        "shear force {} vs G·A·u/depth = {expected}",
        f.x
    );
    assert!(f.y.abs() < 1e-3 * f.x.abs() && f.z.abs() < 1e-2 * f.x.abs());
}

#[test]
fn compression_of_the_slab_meets_its_axial_stiffness_alone() {
    // Pressing layer 1 rigidly down by w: the vertical springs give E·A/depth, and the shear
    // force adds nothing (the slab vector stays along the normal).
    let region = disc(8, 32, 3.0).unwrap();
    let p = params();
    let mut layers = TissueLayers::new(&region, &p).unwrap();
    let w = 1e-4 * p.depth as f32;
    shift_layer(&mut layers, Layer::Outer, Vec3::new(0.0, 0.0, -w));
    layers.compute_forces();
    let f = layer_force(&layers, Layer::Outer);
    let expected = p.slab_young * region.area() * f64::from(w) / p.depth;
    assert!(
        (f64::from(f.z) - expected).abs() < 0.01 * expected,
        "compression force {} vs E·A·w/depth = {expected}",
        f.z
    );
    assert!(f.x.abs() < 1e-3 * f.z.abs() && f.y.abs() < 1e-3 * f.z.abs());
}

#[test]
fn a_rigid_rotation_of_both_layers_meets_no_shear_force() {
    // Tilting the whole model by 30° about x: the slab vector turns with layer 2's normal,
    // so the shear force is zero up to rounding (a fixed-direction shear spring would pull).
    let region = disc(8, 32, 3.0).unwrap();
    let p = params();
    let mut layers = TissueLayers::new(&region, &p).unwrap();
    let turn = glam::Quat::from_rotation_x(30f32.to_radians());
    for x in layers.system_mut().particles_mut().positions_mut() {
        *x = glam::Vec3A::from(turn * glam::Vec3::from(*x));
    }
    let before: Vec<glam::Vec3A> = {
        layers.system_mut().compute_forces();
        layers.system().particles().forces().to_vec()
    };
    layers.compute_forces();
    let shear_scale = p.slab_young * region.area() / p.depth * 1e-6;
    for (i, (a, b)) in layers
        .system()
        .particles()
        .forces()
        .iter()
        .zip(&before)
        .enumerate()
    {
        assert!(
            f64::from((*a - *b).length()) < shear_scale,
            "particle {i}: shear force {}",
            *a - *b
        );
    }
}

#[test]
fn lifted_layers_relax_back_to_rest() {
    let region = disc(4, 16, 2.0).unwrap();
    let mut layers = TissueLayers::new(&region, &params()).unwrap();
    let rest_outer = layers.positions(Layer::Outer);
    layers.lift(0.2).unwrap();
    let lifted = layers.positions(Layer::Outer);
    assert!((lifted[0] - rest_outer[0]).length() > 0.19); // the centre moved
    let s = layers.system_mut();
    s.set_integrator(Integrator::SymplecticEuler);
    s.set_damping(0.99).unwrap();
    let h = 0.5 * s.stable_time_step().unwrap();
    let report = s
        .run(
            h,
            &StopCriterion {
                window: 200,
                tolerance: 1e-4,
                max_steps: 200_000,
                floor: 1e-4,
            },
        )
        .unwrap();
    assert_eq!(report.reason, StopReason::Settled, "{report:?}");
    let worst = layers
        .positions(Layer::Outer)
        .iter()
        .zip(&rest_outer)
        .map(|(a, b)| a.distance(*b))
        .fold(0.0f32, f32::max);
    assert!(worst < 1e-3 * 0.2, "layer 1 is {worst} cm from rest");
}

#[test]
fn offset_folding_on_a_tight_curve_is_an_error() {
    // A spherical cap of radius 1 cm: offsetting it inward by more than the radius turns it
    // inside out.
    let sphere = uv_sphere(24, 23, 1.0).unwrap();
    let keep: Vec<[u32; 3]> = sphere
        .triangles()
        .iter()
        .copied()
        .filter(|t| t.iter().all(|&v| sphere.positions()[v as usize].z > 0.3))
        .collect();
    let cap = TriMesh::new(sphere.positions().to_vec(), keep).unwrap();
    assert!(TissueLayers::new(
        &cap,
        &LayerParams {
            depth: 0.3,
            ..params()
        }
    )
    .is_ok());
    let err = TissueLayers::new(
        &cap,
        &LayerParams {
            depth: 1.5,
            ..params()
        },
    )
    .unwrap_err();
    assert!(
        matches!(
            err,
            ImplantError::InvalidParameter {
                param: Param::Depth,
                ..
            }
        ),
        "{err}"
    );
    // A closed surface has no boundary to hold.
    assert!(matches!(
        TissueLayers::new(&sphere, &params()),
        Err(ImplantError::ClosedRegion { .. })
    ));
    // Bad parameters.
    for bad in [
        LayerParams {
            young: -1.0,
            ..params()
        },
        LayerParams {
            poisson: 0.5,
            ..params()
        },
        LayerParams {
            depth: f64::NAN,
            ..params()
        },
    ] {
        assert!(matches!(
            TissueLayers::new(&cap, &bad),
            Err(ImplantError::InvalidParameter { .. })
        ));
    }
}

#[test]
fn the_thickness_guard_stops_the_approach_and_keeps_momentum() {
    // Layer 1's centre pushed to a tenth of the depth above layer 2, moving down at 5 cm/s while
    // layer 2 rises at 1 cm/s: the guard puts it back at the minimum thickness and stops the
    // pair's approach along the normal with an impulse between the two, so their momentum is
    // what it was.
    let region = disc(4, 16, 2.0).unwrap();
    let mut layers = TissueLayers::new(&region, &params()).unwrap();
    let min = layers.min_thickness();
    assert!(min > 0.0);
    let (outer, inner) = (
        TissueLayers::particle(Layer::Outer, 0) as usize,
        TissueLayers::particle(Layer::Inner, 0) as usize,
    );
    let depth = params().depth as f32;
    let particles = layers.system_mut().particles_mut();
    let (position, velocity, inverse_mass) = particles.state_mut();
    position[outer].z -= 0.9 * depth;
    velocity[outer] = Vec3A::new(0.3, 0.0, -5.0);
    velocity[inner] = Vec3A::new(0.0, 0.0, 1.0);
    let (mo, mi) = (1.0 / inverse_mass[outer], 1.0 / inverse_mass[inner]);
    let momentum = velocity[outer] * mo + velocity[inner] * mi;
    assert_eq!(layers.hold_thickness(), 1);
    let particles = layers.system().particles();
    let (x, v) = (particles.positions(), particles.velocities());
    let gap = x[outer].z - x[inner].z;
    assert!((gap - min).abs() < 1e-5, "gap {gap} against {min}");
    let approach = v[outer].z - v[inner].z;
    assert!(
        approach.abs() < 1e-5,
        "still approaching at {approach} cm/s"
    );
    let after = v[outer] * mo + v[inner] * mi;
    assert!(
        (after - momentum).length() <= 1e-5 * momentum.length(),
        "momentum {momentum} → {after}"
    );
    // The tangential velocity is left alone.
    assert_eq!(v[outer].x, 0.3);
}

/// Triangles of `region` that turn over when its vertices move by `-depth` along `directions`.
fn turned_over(region: &TriMesh, directions: &[Vec3], depth: f32) -> usize {
    let moved: Vec<Vec3> = region
        .positions()
        .iter()
        .zip(directions)
        .map(|(p, d)| *p - *d * depth)
        .collect();
    let moved = region.with_positions(moved).unwrap();
    region
        .triangle_normals()
        .iter()
        .zip(moved.triangle_normals())
        .filter(|(a, b)| a.dot(*b) <= 0.0)
        .count()
}

#[test]
fn a_ripple_shorter_than_the_depth_is_smoothed_out_of_layer_2_not_refused() {
    // A 4 cm plane of 0.1 cm edges with seeded spikes of 0.12–0.18 cm at a few vertices (a
    // scan's outliers, narrower than the 0.25 cm depth): along the bare vertex normals the
    // offset turns triangles over around every spike; the layers smooth the directions there.
    let flat = tissue_mesh::grid(41, 4.0).unwrap();
    let mut positions = flat.positions().to_vec();
    let mut rng = tissue_bvh::scenes::Rng::new(12345);
    for _ in 0..12 {
        let (i, j) = (
            5 + (rng.unit() * 31.0) as usize,
            5 + (rng.unit() * 31.0) as usize,
        );
        positions[i * 41 + j].z += rng.range(0.12, 0.18);
    }
    let region = flat.with_positions(positions).unwrap();
    let depth = 0.25;
    assert!(turned_over(&region, &region.vertex_normals(), depth) > 0);
    let layers = TissueLayers::new(
        &region,
        &LayerParams {
            depth: f64::from(depth),
            ..params()
        },
    )
    .unwrap();
    let inner = layers.rest(Layer::Inner);
    let folded = region
        .triangle_normals()
        .iter()
        .zip(inner.triangle_normals())
        .filter(|(a, b)| a.dot(*b) <= 0.0)
        .count();
    assert_eq!(folded, 0);
    // Every layer-2 vertex is still the depth below its layer-1 vertex, and the directions
    // changed only near the spikes: far from them layer 2 is the plane 0.25 cm down.
    for (a, b) in region.positions().iter().zip(inner.positions()) {
        assert!((a.distance(*b) - depth).abs() < 1e-5);
    }
    let level = inner
        .positions()
        .iter()
        .filter(|p| (p.z + depth).abs() < 1e-6)
        .count();
    assert!(level > inner.vertex_count() / 2, "{level}");
}

#[test]
fn layer_1_resists_bending_as_a_plate_and_the_force_is_the_energys_gradient() {
    // A flat 4 cm patch of 0.1 cm edges; one interior layer-1 particle lifted by 0.02 cm.
    let region = tissue_mesh::grid(41, 4.0).unwrap();
    let centre = 20 * 41 + 20;
    let particle = TissueLayers::particle(Layer::Outer, centre) as usize;
    let lifted = |bending: bool| {
        let mut layers = TissueLayers::new(
            &region,
            &LayerParams {
                depth: 0.25,
                skin_bending: bending,
                ..LayerParams::default()
            },
        )
        .unwrap();
        assert_eq!(layers.bending_energy(), 0.0);
        layers.system_mut().particles_mut().positions_mut()[particle].z += 0.02;
        layers.compute_forces();
        let f = layers.system().particles().forces()[particle];
        (layers, f)
    };
    let (mut bent, with) = lifted(true);
    let (_, without) = lifted(false);
    let energy = bent.bending_energy();
    assert!(energy > 0.0);
    // The bending's share of the force pulls the particle back down, and it is the energy's
    // gradient: moving the particle by a small dz along it changes the energy by −F·dz.
    let bending_force = with.z - without.z;
    assert!(bending_force < 0.0, "{bending_force}");
    let dz = 1e-4;
    bent.system_mut().particles_mut().positions_mut()[particle].z += dz;
    let change = bent.bending_energy() - energy;
    let predicted = -f64::from(bending_force) * f64::from(dz);
    assert!(
        (change - predicted).abs() < 0.05 * predicted.abs(),
        "energy change {change} against −F·dz {predicted}"
    );
}
