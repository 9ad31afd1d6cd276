//! Implant (tissue expander) shapes: closed outward meshes at a target volume, flat and bent onto
//! a curved body.
#![allow(clippy::unwrap_used, clippy::panic)]

use glam::{DVec3, Vec2, Vec3};
use tissue_implant::{Implant, ImplantError, ImplantFrame, ImplantShape, ImplantSpec};
use tissue_mesh::diagnose;

const ROUND: ImplantShape = ImplantShape::Round { diameter: 7.0 };
const RECTANGULAR: ImplantShape = ImplantShape::Rectangular {
    length: 10.0,
    width: 6.0,
    corner_radius: 1.5,
};
const CRESCENT: ImplantShape = ImplantShape::Crescent {
    length: 12.0,
    width: 4.0,
    bend_radius: 6.0,
};

/// Builds `spec` and checks what every implant must be: closed, of genus 0, free of defects,
/// outward (base triangles facing −normal, volume positive), within ±10 % of its vertex budget,
/// holding its volume within 0.5 %, with the volume it reports being the mesh's.
fn check(spec: ImplantSpec) -> Implant {
    let implant = spec
        .build()
        .unwrap_or_else(|e| panic!("{spec:?} failed: {e}"));
    let mesh = implant.mesh();
    assert!(mesh.is_closed(), "{spec:?}");
    assert_eq!(mesh.euler_characteristic(), 2, "{spec:?}");
    assert_eq!(mesh.topology().component_count(), 1, "{spec:?}");
    assert_eq!(
        diagnose(mesh.positions(), mesh.triangles()),
        vec![],
        "{spec:?}"
    );
    let budget = f64::from(spec.vertex_budget);
    let count = mesh.vertex_count() as f64;
    assert!(
        (count - budget).abs() <= 0.1 * budget,
        "{count} for {budget}"
    );
    let volume = mesh.signed_volume().unwrap();
    assert_eq!(volume, implant.volume());
    assert!(
        (volume - spec.volume_cm3).abs() <= 0.005 * spec.volume_cm3,
        "{spec:?}: {volume}"
    );
    // The base is flat in z = 0 and faces down; the dome is above it.
    let p = mesh.positions();
    assert!(implant.base().all(|v| p[v as usize].z == 0.0));
    assert!(implant.dome().all(|v| p[v as usize].z > 0.0));
    let top = implant.dome().map(|v| p[v as usize].z).fold(0.0, f32::max);
    assert!((f64::from(top) - implant.dome_height()).abs() < 1e-4 * implant.dome_height());
    let base = implant.base();
    for (t, n) in mesh.triangle_normals().iter().enumerate() {
        if mesh.triangles()[t].iter().all(|v| base.contains(v)) {
            assert!(n.z < -0.999, "base triangle {t} has normal {n}");
        }
    }
    implant
}

/// The rim as a closed polygon in plan.
fn rim(implant: &Implant) -> Vec<Vec2> {
    let p = implant.mesh().positions();
    implant.rim().map(|v| p[v as usize].truncate()).collect()
}

fn contains(polygon: &[Vec2], q: Vec2) -> bool {
    let mut inside = false;
    for i in 0..polygon.len() {
        let (a, b) = (polygon[i], polygon[(i + 1) % polygon.len()]);
        if (a.y > q.y) != (b.y > q.y) && q.x < a.x + (q.y - a.y) * (b.x - a.x) / (b.y - a.y) {
            inside = !inside;
        }
    }
    inside
}

/// Convex hull (Andrew's monotone chain), counter-clockwise.
fn convex_hull(points: &[Vec2]) -> Vec<Vec2> {
    let mut p = points.to_vec();
    p.sort_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
    let cross = |o: Vec2, a: Vec2, b: Vec2| (a - o).perp_dot(b - o);
    let mut hull: Vec<Vec2> = Vec::new();
    for pass in [p.clone(), p.into_iter().rev().collect()] {
        let start = hull.len();
        for q in pass {
            while hull.len() >= start + 2
                && cross(hull[hull.len() - 2], hull[hull.len() - 1], q) <= 0.0
            {
                hull.pop();
            }
            hull.push(q);
        }
        hull.pop();
    }
    hull
}

#[test]
fn every_shape_and_volume_is_a_closed_outward_mesh_holding_its_volume() {
    for shape in [ROUND, RECTANGULAR, CRESCENT] {
        for volume in [50.0, 100.0, 150.0] {
            for budget in [500, 2000] {
                check(ImplantSpec::new(shape, volume).with_vertex_budget(budget));
            }
        }
    }
}

#[test]
fn round_base_is_the_disc_of_its_diameter() {
    for budget in [50, 500, 2000] {
        let implant = check(ImplantSpec::new(ROUND, 100.0).with_vertex_budget(budget));
        let p = implant.mesh().positions();
        for v in implant.base() {
            assert!(p[v as usize].truncate().length() <= 3.5 + 1e-5);
        }
        for v in implant.rim() {
            assert!((p[v as usize].truncate().length() - 3.5).abs() < 1e-5);
        }
        // The dome too stays over the base.
        assert!(implant
            .dome()
            .all(|v| p[v as usize].truncate().length() < 3.5));
    }
}

#[test]
fn rectangular_base_spans_length_by_width() {
    for corner_radius in [0.0, 1.5, 3.0] {
        let shape = ImplantShape::Rectangular {
            length: 10.0,
            width: 6.0,
            corner_radius,
        };
        let implant = check(ImplantSpec::new(shape, 100.0));
        let rim = rim(&implant);
        let (lo, hi) = rim.iter().fold((Vec2::MAX, Vec2::MIN), |(lo, hi), &q| {
            (lo.min(q), hi.max(q))
        });
        assert!(
            (lo - Vec2::new(-5.0, -3.0)).abs().max_element() < 1e-5,
            "{lo}"
        );
        assert!(
            (hi - Vec2::new(5.0, 3.0)).abs().max_element() < 1e-5,
            "{hi}"
        );
        let p = implant.mesh().positions();
        for v in implant.base() {
            let q = p[v as usize];
            assert!(q.x.abs() <= 5.0 + 1e-5 && q.y.abs() <= 3.0 + 1e-5);
        }
        // Every rim vertex is on the rounded rectangle: its signed distance is 0.
        for q in &rim {
            let inner = Vec2::new(5.0 - corner_radius, 3.0 - corner_radius);
            let d = q.abs() - inner;
            let distance = d.max(Vec2::ZERO).length() + d.max_element().min(0.0) - corner_radius;
            assert!(
                distance.abs() < 1e-5,
                "{q} is {distance} cm off the outline"
            );
        }
        // A sharp corner is a rim vertex.
        if corner_radius == 0.0 {
            assert!(rim
                .iter()
                .any(|q| (*q - Vec2::new(5.0, 3.0)).length() < 1e-6));
        }
    }
}

#[test]
fn crescent_base_is_not_convex() {
    for volume in [50.0, 100.0, 150.0] {
        let implant = check(ImplantSpec::new(CRESCENT, volume));
        let rim = rim(&implant);
        let hull = convex_hull(&rim);
        let area = |polygon: &[Vec2]| {
            (0..polygon.len())
                .map(|i| 0.5 * polygon[i].perp_dot(polygon[(i + 1) % polygon.len()]))
                .sum::<f32>()
        };
        // The bite: the hull is much larger than the base, and the point (0, −3), below the
        // inner edge at (0, −2) and above the chord between the tips, is in the hull only.
        assert!(
            area(&hull) > 1.05 * area(&rim),
            "{} vs {}",
            area(&hull),
            area(&rim)
        );
        let bite = Vec2::new(0.0, -3.0);
        assert!(contains(&hull, bite) && !contains(&rim, bite));
        assert!(contains(&rim, Vec2::ZERO) && contains(&rim, Vec2::new(0.0, 1.9)));
        // The crescent's centre line is the arc of radius 6 about (0, −6): the band's inner
        // and outer edges are at radius 4 and 8 from it.
        for q in &rim {
            let r = (*q - Vec2::new(0.0, -6.0)).length();
            assert!((4.0 - 1e-4..=8.0 + 1e-4).contains(&r), "{q}: {r}");
        }
    }
}

#[test]
fn round_dome_height_is_plausible_and_rises_with_volume() {
    let heights: Vec<f64> = [25.0, 50.0, 75.0, 100.0, 125.0, 150.0, 200.0]
        .iter()
        .map(|&v| check(ImplantSpec::new(ROUND, v)).dome_height())
        .collect();
    assert!(heights.windows(2).all(|w| w[0] < w[1]), "{heights:?}");
    // The inscribed mesh holds less than the smooth dome over the disc, so its height is a
    // little larger than the smooth dome's: at most 3 % with 500 vertices.
    let close_above = |h: f64, smooth: f64| h >= smooth && h <= 1.03 * smooth;
    // 50 cm³: the spherical cap π H (3R² + H²)/6 = 50 has H = 2.28 cm.
    let r2 = 3.5f64 * 3.5;
    let cap = |h: f64| std::f64::consts::PI * h * (3.0 * r2 + h * h) / 6.0;
    let (mut lo, mut hi) = (0.0, 3.5);
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        (lo, hi) = if cap(mid) < 50.0 {
            (mid, hi)
        } else {
            (lo, mid)
        };
    }
    assert!(close_above(heights[1], lo), "{} vs {lo}", heights[1]);
    // 100 and 150 cm³: over the 89.8 cm³ hemisphere, half-spheroids 3V/(2πR²) high: 3.90 and
    // 5.85 cm, in the thesis's 2–6 cm.
    for (h, v) in [(heights[3], 100.0), (heights[5], 150.0)] {
        let smooth = 3.0 * v / (2.0 * std::f64::consts::PI * r2);
        assert!(close_above(h, smooth), "{h} vs {smooth}");
    }
}

#[test]
fn round_dome_follows_the_spherical_cap() {
    // 50 cm³: a cap of height H; its sphere has radius ρ = (R² + H²)/2H about (0, 0, H − ρ).
    let implant = check(ImplantSpec::new(ROUND, 50.0).with_vertex_budget(2000));
    let h = implant.dome_height();
    let rho = (3.5 * 3.5 + h * h) / (2.0 * h);
    let centre = DVec3::new(0.0, 0.0, h - rho);
    let p = implant.mesh().positions();
    for v in implant.dome() {
        let r = (p[v as usize].as_dvec3() - centre).length();
        assert!((r - rho).abs() < 0.01 * h, "vertex {v}: {r} vs {rho}");
    }
}

#[test]
fn rectangular_dome_is_a_ridge_along_its_length() {
    // A long pillow: the membrane is flat along the middle of a 12 × 4 base.
    let shape = ImplantShape::Rectangular {
        length: 12.0,
        width: 4.0,
        corner_radius: 1.0,
    };
    let implant = check(ImplantSpec::new(shape, 100.0).with_vertex_budget(2000));
    let h = implant.dome_height() as f32;
    let p = implant.mesh().positions();
    let ridge: Vec<Vec3> = implant
        .dome()
        .map(|v| p[v as usize])
        .filter(|q| q.y.abs() < 0.3 && q.x.abs() < 3.0)
        .collect();
    assert!(ridge.len() > 4);
    assert!(ridge.iter().all(|q| q.z > 0.95 * h), "{ridge:?}");
    // Across the ridge it falls to the rim.
    assert!(implant
        .dome()
        .map(|v| p[v as usize])
        .filter(|q| q.y.abs() > 1.9)
        .all(|q| q.z < 0.6 * h));
}

/// Checks an implant bent onto a body: valid, outward, at its volume, every base vertex on the
/// body (`on_body` gives a vertex's signed distance to it), every dome vertex outside.
fn check_bent(spec: ImplantSpec, implant: &Implant, on_body: impl Fn(DVec3) -> f64) {
    let mesh = implant.mesh();
    assert!(mesh.is_closed());
    assert_eq!(mesh.euler_characteristic(), 2);
    assert_eq!(diagnose(mesh.positions(), mesh.triangles()), vec![]);
    let volume = mesh.signed_volume().unwrap();
    assert_eq!(volume, implant.volume());
    assert!(
        (volume - spec.volume_cm3).abs() <= 0.005 * spec.volume_cm3,
        "{volume}"
    );
    let p = mesh.positions();
    let worst = implant
        .base()
        .map(|v| on_body(p[v as usize].as_dvec3()).abs())
        .fold(0.0, f64::max);
    assert!(worst < 1e-4, "a base vertex is {worst} cm off the body");
    assert!(implant
        .dome()
        .all(|v| on_body(p[v as usize].as_dvec3()) > 0.0));
}

#[test]
fn implant_bent_onto_a_cylinder_lies_on_it_and_keeps_its_volume() {
    // A body cylinder of radius 10 cm, axis along (1, 1, 0) through (2, −1, 3); the implant on
    // its top, its local y along the axis, so the surface under it is z = √(100 − x²) − 10.
    let axis = DVec3::new(1.0, 1.0, 0.0).normalize();
    let through = DVec3::new(2.0, -1.0, 3.0);
    let normal = DVec3::Z;
    let frame = ImplantFrame::new(
        (through + 10.0 * normal).as_vec3(),
        normal.as_vec3(),
        axis.cross(normal).as_vec3(),
    )
    .unwrap();
    assert!((frame.bitangent().as_dvec3() - axis).length() < 1e-6);
    let on_body = |q: DVec3| {
        let d = q - through;
        (d - d.dot(axis) * axis).length() - 10.0
    };
    for shape in [ROUND, RECTANGULAR, CRESCENT] {
        for volume in [50.0, 150.0] {
            let spec = ImplantSpec::new(shape, volume);
            let bent = spec
                .build_on(&frame, |x, _| (100.0 - x * x).sqrt() - 10.0)
                .unwrap();
            check_bent(spec, &bent, on_body);
            // Bending changes the volume of the flat-height mesh only a little, so the height
            // changes only a little.
            let flat = spec.build().unwrap().dome_height();
            assert!((bent.dome_height() - flat).abs() < 0.01 * flat);
        }
    }
}

#[test]
fn implant_bent_onto_a_sphere_lies_on_it_and_keeps_its_volume() {
    // A body sphere of radius 15 cm about (1, 2, 3); the implant at the point along (1, 1, 2).
    let centre = DVec3::new(1.0, 2.0, 3.0);
    let normal = DVec3::new(1.0, 1.0, 2.0).normalize();
    let frame = ImplantFrame::new(
        (centre + 15.0 * normal).as_vec3(),
        normal.as_vec3(),
        Vec3::X,
    )
    .unwrap();
    let on_body = |q: DVec3| (q - centre).length() - 15.0;
    for shape in [ROUND, RECTANGULAR, CRESCENT] {
        let spec = ImplantSpec::new(shape, 100.0).with_vertex_budget(2000);
        let bent = spec
            .build_on(&frame, |x, y| (225.0 - x * x - y * y).sqrt() - 15.0)
            .unwrap();
        check_bent(spec, &bent, on_body);
        // The rim runs round the sphere at the base's distance from the frame origin.
        let p = bent.mesh().positions();
        let origin = frame.origin().as_dvec3();
        if shape == ROUND {
            for v in bent.rim() {
                let along = (p[v as usize].as_dvec3() - origin).dot(normal);
                let expected = (225.0f64 - 3.5 * 3.5).sqrt() - 15.0;
                assert!((along - expected).abs() < 1e-4, "{along} vs {expected}");
            }
        }
    }
}

#[test]
fn bad_inputs_are_errors_naming_the_parameter() {
    let name_of = |spec: ImplantSpec| match spec.build() {
        Err(ImplantError::InvalidParameter { param, .. }) => param.name(),
        other => panic!("{spec:?}: {other:?}"),
    };
    for volume in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        assert_eq!(name_of(ImplantSpec::new(ROUND, volume)), "volume_cm3");
    }
    for diameter in [0.0, -7.0, f32::NAN, f32::INFINITY, 1e6] {
        assert_eq!(
            name_of(ImplantSpec::new(ImplantShape::Round { diameter }, 100.0)),
            "diameter"
        );
    }
    assert_eq!(
        name_of(ImplantSpec::new(ROUND, 100.0).with_vertex_budget(49)),
        "vertex_budget"
    );
    assert_eq!(
        name_of(ImplantSpec::new(ROUND, 100.0).with_vertex_budget(u32::MAX)),
        "vertex_budget"
    );
    let rectangle = |length, width, corner_radius| {
        ImplantSpec::new(
            ImplantShape::Rectangular {
                length,
                width,
                corner_radius,
            },
            100.0,
        )
    };
    assert_eq!(name_of(rectangle(10.0, 6.0, 3.1)), "corner_radius");
    assert_eq!(name_of(rectangle(10.0, 6.0, -0.1)), "corner_radius");
    assert_eq!(name_of(rectangle(10.0, 0.0, 1.0)), "width");
    assert_eq!(name_of(rectangle(30.0, 6.0, 1.0)), "length");
    let crescent = |length, width, bend_radius| {
        ImplantSpec::new(
            ImplantShape::Crescent {
                length,
                width,
                bend_radius,
            },
            100.0,
        )
    };
    assert_eq!(name_of(crescent(3.0, 4.0, 6.0)), "length"); // shorter than wide
    assert_eq!(name_of(crescent(12.0, 7.0, 6.0)), "width"); // wider than the bend radius
    assert_eq!(name_of(crescent(12.0, 4.5, 6.0)), "width"); // wider than 2/3 of it
    assert_eq!(name_of(crescent(15.0, 4.0, 3.0)), "width");
    assert_eq!(name_of(crescent(17.0, 4.0, 6.0)), "length"); // longer than 4 × the width
    assert_eq!(name_of(crescent(12.0, 4.0, f32::NAN)), "bend_radius");

    // Too much volume for a 7 cm base (a dome over 21 cm high), or too little (under 0.07 cm).
    for volume in [1000.0, 0.5] {
        match ImplantSpec::new(ROUND, volume).build() {
            Err(ImplantError::VolumeOutOfRange { min, max, .. }) => {
                assert!(min < 1.5 && max > 500.0 && max < 600.0, "{min} {max}")
            }
            other => panic!("{volume}: {other:?}"),
        }
    }
    // Frames and surfaces.
    for (normal, tangent) in [
        (Vec3::ZERO, Vec3::X),
        (Vec3::Z, Vec3::Z),
        (Vec3::Z, Vec3::ZERO),
        (Vec3::new(f32::NAN, 0.0, 1.0), Vec3::X),
    ] {
        assert!(matches!(
            ImplantFrame::new(Vec3::ZERO, normal, tangent),
            Err(ImplantError::InvalidParameter { .. })
        ));
    }
    // A sphere smaller than the base: the surface is undefined under the rim.
    let spec = ImplantSpec::new(ROUND, 100.0);
    assert!(matches!(
        spec.build_on(&ImplantFrame::LOCAL, |x, y| (9.0 - x * x - y * y).sqrt() - 3.0),
        Err(ImplantError::SurfaceHeight { value, .. }) if value.is_nan()
    ));
}

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig::with_cases(48))]

    /// Any accepted shape, budget and volume gives a valid implant at its volume, or says the
    /// volume does not fit the base.
    #[test]
    fn any_accepted_shape_builds_a_valid_implant(
        kind in 0..3u8,
        small in 0.5f32..20.0,
        stretch in 1.0f32..4.0,
        corner in 0.0f32..=1.0,
        bend in 1.5f32..5.0,
        fill in 0.01f64..1.5,
        budget in 50u32..1500,
    ) {
        let shape = match kind {
            0 => ImplantShape::Round { diameter: small },
            1 => ImplantShape::Rectangular {
                length: stretch * small,
                width: small,
                corner_radius: 0.5 * corner * small,
            },
            _ => ImplantShape::Crescent {
                length: stretch * small,
                width: small,
                bend_radius: bend * small,
            },
        };
        let spec = ImplantSpec::new(shape, fill * f64::from(small).powi(3))
            .with_vertex_budget(budget);
        match spec.build() {
            Ok(_) => {
                check(spec);
            }
            Err(ImplantError::VolumeOutOfRange { min, max, volume }) => {
                proptest::prop_assert!(volume < min || volume > max);
            }
            Err(e) => proptest::prop_assert!(false, "{spec:?}: {e}"),
        }
    }
}
