//! Rendering checked against analytic values and the documented behaviour.
#![allow(clippy::unwrap_used)]

use std::collections::HashSet;
use std::f64::consts::PI;

use glam::Vec3;
use tissue_mesh::{Aabb, TriMesh};
use tissue_render::{
    before_after, render, render_mesh, viridis, BeforeAfterOptions, Camera, ColorScale, Image,
    RenderError, Rgb, Surface, View, Viewport, NAN_COLOR,
};

fn count_not(image: &Image, background: Rgb) -> usize {
    image
        .as_raw()
        .chunks_exact(3)
        .filter(|p| *p != background.0)
        .count()
}

/// Pixel bounding box `(x0, y0, x1, y1)` (inclusive) of the pixels that are not `background`.
fn covered_box(image: &Image, background: Rgb) -> (u32, u32, u32, u32) {
    let mut b = (u32::MAX, u32::MAX, 0, 0);
    for y in 0..image.height() {
        for x in 0..image.width() {
            if image.pixel(x, y) != Some(background) {
                b = (b.0.min(x), b.1.min(y), b.2.max(x), b.3.max(y));
            }
        }
    }
    b
}

#[test]
fn sphere_fills_pi_r_squared() {
    let r = 1.5;
    let sphere = tissue_mesh::uv_sphere(96, 95, r).unwrap();
    let views = [
        (-Vec3::Z, Vec3::Y),
        (Vec3::X, Vec3::Z),
        (Vec3::new(-1.0, 0.7, -0.4), Vec3::Z),
    ];
    for (size, (dir, up)) in [(400, 400), (500, 300), (300, 420)].into_iter().zip(views) {
        let camera = Camera::orthographic(sphere.bounding_box(), dir, up).unwrap();
        let image = render_mesh(&sphere, None, &camera, size.0, size.1).unwrap();
        let s = camera.pixels_per_unit(size.0, size.1);
        let expected = PI * (s * f64::from(r)).powi(2);
        let got = count_not(&image, Rgb::WHITE) as f64;
        let rel = (got - expected).abs() / expected;
        assert!(
            rel < 0.02,
            "view {dir:?} at {size:?}: {got} pixels, expected {expected:.0} ({:.2} %)",
            100.0 * rel
        );
    }
}

#[test]
fn head_on_square_fills_its_square() {
    let square = tissue_mesh::grid(2, 2.0).unwrap(); // [-1, 1]², z = 0
    for dir in [-Vec3::Z, Vec3::Z] {
        let camera = Camera::orthographic(square.bounding_box(), dir, Vec3::Y).unwrap();
        // 200 px, margin 5 %: the square spans 180 px, from pixel 10 to pixel 189.
        let image = render_mesh(&square, None, &camera, 200, 200).unwrap();
        assert_eq!(camera.pixels_per_unit(200, 200), 90.0);
        assert_eq!(
            count_not(&image, Rgb::WHITE),
            180 * 180,
            "direction {dir:?}"
        );
        assert_eq!(covered_box(&image, Rgb::WHITE), (10, 10, 189, 189));
        // Seen head-on from either side the grey is unshaded.
        assert_eq!(image.pixel(100, 100), Some(Rgb::SURFACE_GREY));

        // A wide image: the height limits the scale, the square is centred.
        let image = render_mesh(&square, None, &camera, 300, 200).unwrap();
        assert_eq!(covered_box(&image, Rgb::WHITE), (60, 10, 239, 189));
    }
}

#[test]
fn shared_edges_leave_no_cracks() {
    // grid(3) at 201 px: the middle vertex lands on a pixel centre (100.5, 100.5), so the inner
    // edges run exactly through pixel centres and only the tie rule decides who draws them.
    // grid(11) at 217 px: generic positions. Either way the covered pixels form a full rectangle
    // of the square's size.
    for (n, size) in [(3, 201), (11, 217), (4, 199)] {
        let square = tissue_mesh::grid(n, 2.0).unwrap();
        let camera = Camera::orthographic(square.bounding_box(), -Vec3::Z, Vec3::Y).unwrap();
        let image = render_mesh(&square, None, &camera, size, size).unwrap();
        let side = 2.0 * camera.pixels_per_unit(size, size);
        let got = count_not(&image, Rgb::WHITE) as f64;
        assert!(
            (got - side * side).abs() <= 2.0 * side + 1.0,
            "grid({n}): {got} vs {}",
            side * side
        );
        let (x0, y0, x1, y1) = covered_box(&image, Rgb::WHITE);
        assert_eq!(
            count_not(&image, Rgb::WHITE),
            ((x1 - x0 + 1) * (y1 - y0 + 1)) as usize,
            "grid({n}): holes inside the square"
        );
    }
}

/// Two parallel squares overlapping around the origin: `A` at z = 0 with field 0, `B` at z = 1
/// with field 1.
fn two_squares(b_first: bool) -> (Vec<Vec3>, Vec<[u32; 3]>, Vec<f32>) {
    let quad = |x0: f32, y0: f32, x1: f32, y1: f32, z: f32| {
        [
            Vec3::new(x0, y0, z),
            Vec3::new(x1, y0, z),
            Vec3::new(x1, y1, z),
            Vec3::new(x0, y1, z),
        ]
    };
    let a = quad(-1.0, -1.0, 0.5, 0.5, 0.0);
    let b = quad(-0.5, -0.5, 1.0, 1.0, 1.0);
    let (first, second, f_first, f_second) = if b_first {
        (b, a, 1.0, 0.0)
    } else {
        (a, b, 0.0, 1.0)
    };
    let positions: Vec<Vec3> = first.into_iter().chain(second).collect();
    let triangles = vec![[0, 1, 2], [0, 2, 3], [4, 5, 6], [4, 6, 7]];
    let field = [[f_first; 4], [f_second; 4]].concat();
    (positions, triangles, field)
}

#[test]
fn depth_buffer_keeps_the_nearer_square() {
    let scale = ColorScale::new(0.0, 1.0).unwrap();
    for b_first in [false, true] {
        let (positions, triangles, field) = two_squares(b_first);
        let bounds = Aabb::from_points(&positions).unwrap();
        // From +z, B (z = 1, yellow) is nearer; from -z, A (z = 0, purple).
        for (dir, near, far) in [(-Vec3::Z, 1.0, 0.0), (Vec3::Z, 0.0, 1.0)] {
            let camera = Camera::orthographic(bounds, dir, Vec3::Y).unwrap();
            let mut image = Image::new(120, 120, Rgb::WHITE).unwrap();
            let surface = Surface::from_parts(&positions, &triangles).with_field(&field);
            let vp = Viewport::full(&image);
            render(&mut image, vp, &camera, &scale, &[surface]).unwrap();
            let at = |p: Vec3| {
                let q = camera.project(p, 120, 120);
                image.pixel(q.x as u32, q.y as u32)
            };
            let what = format!("b_first {b_first}, direction {dir:?}");
            assert_eq!(at(Vec3::ZERO), Some(viridis(near)), "overlap, {what}");
            assert_eq!(
                at(Vec3::new(-0.8, -0.8, 0.0)),
                Some(viridis(0.0)),
                "A only, {what}"
            );
            assert_eq!(
                at(Vec3::new(0.8, 0.8, 1.0)),
                Some(viridis(1.0)),
                "B only, {what}"
            );
            let nears = image
                .as_raw()
                .chunks_exact(3)
                .filter(|p| *p == viridis(near).0)
                .count();
            let fars = image
                .as_raw()
                .chunks_exact(3)
                .filter(|p| *p == viridis(far).0)
                .count();
            // The nearer square shows whole (1.5²), the farther one minus the overlap (1²).
            let ratio = nears as f64 / fars as f64;
            assert!((ratio - 2.25 / 1.25).abs() < 0.05, "{what}: ratio {ratio}");
        }
    }
}

#[test]
fn second_surface_is_grey_and_occludes_by_depth() {
    let (positions, triangles, field) = two_squares(false);
    let a = Surface::from_parts(&positions[..4], &triangles[..2]).with_field(&field[..4]);
    let b_triangles = [[0, 1, 2], [0, 2, 3]];
    let b = Surface::from_parts(&positions[4..], &b_triangles);
    let bounds = Aabb::from_points(&positions).unwrap();
    let camera = Camera::orthographic(bounds, -Vec3::Z, Vec3::Y).unwrap();
    let scale = ColorScale::new(0.0, 1.0).unwrap();
    for order in [[a, b], [b, a]] {
        let mut image = Image::new(100, 100, Rgb::BLACK).unwrap();
        let vp = Viewport::full(&image);
        render(&mut image, vp, &camera, &scale, &order).unwrap();
        let q = camera.project(Vec3::ZERO, 100, 100);
        assert_eq!(image.pixel(q.x as u32, q.y as u32), Some(Rgb::SURFACE_GREY));
        let q = camera.project(Vec3::new(-0.8, -0.8, 0.0), 100, 100);
        assert_eq!(image.pixel(q.x as u32, q.y as u32), Some(viridis(0.0)));
    }
}

#[test]
fn viewport_confines_drawing() {
    let square = tissue_mesh::grid(2, 2.0).unwrap();
    let camera = Camera::orthographic(square.bounding_box(), -Vec3::Z, Vec3::Y).unwrap();
    let mut image = Image::new(300, 100, Rgb::WHITE).unwrap();
    let vp = Viewport {
        x: 200,
        y: 0,
        width: 100,
        height: 100,
    };
    let scale = ColorScale::new(0.0, 1.0).unwrap();
    render(&mut image, vp, &camera, &scale, &[Surface::new(&square)]).unwrap();
    assert_eq!(covered_box(&image, Rgb::WHITE), (205, 5, 294, 94));
    // A viewport partly or wholly outside the image is clipped, not an error.
    let vp = Viewport {
        x: 250,
        y: 50,
        width: 1000,
        height: 1000,
    };
    render(&mut image, vp, &camera, &scale, &[Surface::new(&square)]).unwrap();
    let vp = Viewport {
        x: 5000,
        y: 0,
        width: 10,
        height: 10,
    };
    render(&mut image, vp, &camera, &scale, &[Surface::new(&square)]).unwrap();
}

#[test]
fn colour_map_ends_clamping_nan_and_luminance() {
    assert_eq!(viridis(0.0), Rgb::new(0x44, 0x01, 0x54));
    assert_eq!(viridis(1.0), Rgb::new(0xFD, 0xE7, 0x25));
    // matplotlib's viridis(0.5) is #21918C.
    let mid = viridis(0.5).0;
    let expected = [0x21, 0x91, 0x8C];
    for k in 0..3 {
        assert!(mid[k].abs_diff(expected[k]) <= 3, "{mid:?}");
    }
    assert_eq!(viridis(-3.0), viridis(0.0));
    assert_eq!(viridis(7.0), viridis(1.0));
    assert_eq!(viridis(f32::NEG_INFINITY), viridis(0.0));
    assert_eq!(viridis(f32::INFINITY), viridis(1.0));
    assert_eq!(viridis(f32::NAN), NAN_COLOR);
    let mut previous = -1.0;
    for i in 0..=200 {
        let c = viridis(i as f32 / 200.0);
        let y = c.luminance();
        assert!(y > previous, "luminance not increasing at {i}: {c:?}");
        previous = y;
        // The NaN colour is far from every map colour.
        let d: u32 =
            c.0.iter()
                .zip(NAN_COLOR.0)
                .map(|(a, b)| u32::from(a.abs_diff(b)))
                .sum();
        assert!(d > 150, "{c:?} too close to the NaN colour");
    }

    let scale = ColorScale::new(2.0, 4.0).unwrap();
    assert_eq!(scale.color(3.0), viridis(0.5));
    assert_eq!(scale.color(2.0), viridis(0.0));
    assert_eq!(scale.color(-100.0), viridis(0.0));
    assert_eq!(scale.color(1e30), viridis(1.0));
    assert_eq!(scale.color(f32::NAN), NAN_COLOR);
    let wide = ColorScale::new(-f32::MAX, f32::MAX).unwrap();
    assert_eq!(wide.color(0.0), viridis(0.5));

    let auto = ColorScale::auto(&[0.5, f32::NAN, 2.0, f32::INFINITY, 1.0]);
    assert_eq!((auto.min(), auto.max()), (0.5, 2.0));
    let constant = ColorScale::auto(&[0.0; 4]);
    assert_eq!((constant.min(), constant.max()), (-0.5, 0.5));
    let none = ColorScale::auto(&[f32::NAN]);
    assert_eq!((none.min(), none.max()), (0.0, 1.0));
}

#[test]
fn field_is_interpolated_and_nan_is_marked() {
    // A strip from x = -1 (value 0) to x = 1 (value 1): colours follow x.
    let positions = vec![
        Vec3::new(-1.0, -0.2, 0.0),
        Vec3::new(1.0, -0.2, 0.0),
        Vec3::new(1.0, 0.2, 0.0),
        Vec3::new(-1.0, 0.2, 0.0),
    ];
    let triangles = vec![[0, 1, 2], [0, 2, 3]];
    let mesh = TriMesh::new(positions, triangles).unwrap();
    let camera = Camera::orthographic(mesh.bounding_box(), -Vec3::Z, Vec3::Y).unwrap();
    let field = [0.0, 1.0, 1.0, 0.0];
    let image = render_mesh(&mesh, Some(&field), &camera, 200, 100).unwrap();
    for x in [-0.6f32, 0.0, 0.5] {
        let q = camera.project(Vec3::new(x, 0.0, 0.0), 200, 100);
        let got = image.pixel(q.x as u32, q.y as u32).unwrap();
        // The pixel centre's x differs from the probe by at most half a pixel.
        let centre_x = ((q.x.floor() + 0.5 - 100.0) / camera.pixels_per_unit(200, 100)) as f32;
        assert_eq!(got, viridis((centre_x + 1.0) / 2.0), "at x = {x}");
    }
    let nan_field = [0.0, f32::NAN, 1.0, 0.0];
    let image = render_mesh(&mesh, Some(&nan_field), &camera, 200, 100).unwrap();
    assert!(image.as_raw().chunks_exact(3).any(|p| p == NAN_COLOR.0));
}

fn bump() -> (TriMesh, TriMesh, Vec<f32>) {
    let before = tissue_mesh::grid(41, 10.0).unwrap();
    let moved: Vec<Vec3> = before
        .positions()
        .iter()
        .map(|p| *p + Vec3::Z * 1.5 * (1.0 - p.length_squared() / 6.25).max(0.0))
        .collect();
    let after = before.with_positions(moved).unwrap();
    let field = before
        .positions()
        .iter()
        .zip(after.positions())
        .map(|(a, b)| a.distance(*b))
        .collect();
    (before, after, field)
}

#[test]
fn before_after_panels_and_colour_bar() {
    let (before, after, field) = bump();
    for view in [View::Oblique, View::Front] {
        let options = BeforeAfterOptions {
            view,
            ..BeforeAfterOptions::default()
        };
        let image = before_after(&before, &after, &field, &options).unwrap();
        assert_eq!((image.width(), image.height()), (1200, 600));
        let (w, h) = (image.width(), image.height());
        let mut after_colours = HashSet::new();
        let mut differing = 0;
        let mut surface_pixels = 0;
        for y in 0..h * 3 / 4 {
            for x in 0..w / 2 {
                let left = image.pixel(x, y).unwrap();
                let right = image.pixel(x + w / 2, y).unwrap();
                after_colours.insert(right);
                if left != Rgb::WHITE {
                    surface_pixels += 1;
                    if left != right {
                        differing += 1;
                    }
                }
            }
        }
        assert!(
            after_colours.len() > 200,
            "{view:?}: {} colours",
            after_colours.len()
        );
        assert!(
            surface_pixels > 50_000,
            "{view:?}: before panel nearly empty"
        );
        assert!(differing * 2 > surface_pixels, "{view:?}: panels too alike");
        // The colour bar is below the panels and shows both ends of the map.
        let mut bar = HashSet::new();
        for y in h * 4 / 5..h {
            for x in 0..w {
                bar.insert(image.pixel(x, y).unwrap());
            }
        }
        assert!(
            bar.contains(&viridis(0.0)) && bar.contains(&viridis(1.0)),
            "{view:?}"
        );
        assert!(!bar.contains(&NAN_COLOR));
    }
}

#[test]
fn before_after_options_are_honoured() {
    let (before, after, mut field) = bump();
    field[7] = f32::NAN;
    let options = BeforeAfterOptions {
        width: 640,
        height: 360,
        background: Rgb::new(20, 20, 30),
        title: "stretch, cm²/cm²".to_owned(),
        range: Some(ColorScale::new(0.0, 3.0).unwrap()),
        ..BeforeAfterOptions::default()
    };
    let image = before_after(&before, &after, &field, &options).unwrap();
    assert_eq!((image.width(), image.height()), (640, 360));
    assert_eq!(image.pixel(0, 0), Some(Rgb::new(20, 20, 30)));
    // NaN swatch in the legend.
    assert!(image.as_raw().chunks_exact(3).any(|p| p == NAN_COLOR.0));
    // Light text on the dark background.
    assert!(image.as_raw().chunks_exact(3).any(|p| p == [225, 225, 225]));
    // Tiny images draw what fits and do not panic.
    for (w, h) in [(1, 1), (7, 3), (50, 40)] {
        let small = BeforeAfterOptions {
            width: w,
            height: h,
            ..BeforeAfterOptions::default()
        };
        let image = before_after(&before, &after, &field, &small).unwrap();
        assert_eq!((image.width(), image.height()), (w, h));
    }
}

#[test]
fn rendering_is_deterministic() {
    let (before, after, field) = bump();
    let options = BeforeAfterOptions::default();
    let a = before_after(&before, &after, &field, &options)
        .unwrap()
        .encode_png()
        .unwrap();
    let b = before_after(&before, &after, &field, &options)
        .unwrap()
        .encode_png()
        .unwrap();
    assert_eq!(a, b);
}

#[test]
fn png_round_trips() {
    let mut image = Image::new(31, 17, Rgb::new(1, 2, 3)).unwrap();
    image.set_pixel(0, 0, Rgb::new(255, 0, 0));
    image.set_pixel(30, 16, Rgb::new(0, 255, 7));
    image.set_pixel(31, 0, Rgb::BLACK); // outside: ignored
    let bytes = image.encode_png().unwrap();
    let decoded = decode(&bytes);
    assert_eq!(decoded.width(), 31);
    assert_eq!(decoded.height(), 17);
    assert_eq!(decoded.pixel(0, 0), Some(Rgb::new(255, 0, 0)));
    assert_eq!(decoded.pixel(30, 16), Some(Rgb::new(0, 255, 7)));
    assert_eq!(decoded.pixel(5, 5), Some(Rgb::new(1, 2, 3)));
    assert_eq!(decoded.as_raw(), image.as_raw());
}

/// Decodes an 8-bit RGB PNG with the `png` crate.
fn decode(bytes: &[u8]) -> Image {
    let decoder = png::Decoder::new(bytes);
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size()];
    let info = reader.next_frame(&mut buf).unwrap();
    assert_eq!(info.color_type, png::ColorType::Rgb);
    assert_eq!(info.bit_depth, png::BitDepth::Eight);
    let mut image = Image::new(info.width, info.height, Rgb::BLACK).unwrap();
    for y in 0..info.height {
        for x in 0..info.width {
            let i = (y * info.width + x) as usize * 3;
            image.set_pixel(x, y, Rgb([buf[i], buf[i + 1], buf[i + 2]]));
        }
    }
    image
}

fn scratch_dir(name: &str) -> std::path::PathBuf {
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn entries(dir: &std::path::Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

#[test]
fn write_png_replaces_atomically_and_cleans_up() {
    let dir = scratch_dir("write_png");
    let path = dir.join("figure.png");
    let first = Image::new(8, 4, Rgb::WHITE).unwrap();
    first.write_png(&path).unwrap();
    assert_eq!(entries(&dir), ["figure.png"]);
    assert_eq!(decode(&std::fs::read(&path).unwrap()), first);

    let second = Image::new(5, 9, Rgb::new(9, 8, 7)).unwrap();
    second.write_png(&path).unwrap();
    assert_eq!(entries(&dir), ["figure.png"]);
    assert_eq!(decode(&std::fs::read(&path).unwrap()), second);

    // A directory in the way: an error naming the path, and no temporary file left.
    let blocked = dir.join("blocked.png");
    std::fs::create_dir(&blocked).unwrap();
    std::fs::write(blocked.join("keep"), b"x").unwrap();
    match second.write_png(&blocked) {
        Err(RenderError::Io { path, .. }) => assert_eq!(path, blocked),
        other => panic!("expected an I/O error, got {other:?}"),
    }
    assert_eq!(entries(&dir), ["blocked.png", "figure.png"]);
}

#[test]
fn write_png_into_missing_directory_names_the_path() {
    let dir = scratch_dir("missing_dir");
    let path = dir.join("no").join("such").join("out.png");
    let err = Image::new(2, 2, Rgb::WHITE)
        .unwrap()
        .write_png(&path)
        .unwrap_err();
    match &err {
        RenderError::Io { path: p, source } => {
            assert_eq!(p, &path);
            assert_eq!(source.kind(), std::io::ErrorKind::NotFound);
        }
        other => panic!("expected an I/O error, got {other:?}"),
    }
    assert!(
        err.to_string().contains(&path.display().to_string()),
        "{err}"
    );
    assert!(entries(&dir).is_empty());
}

#[test]
fn bad_input_gives_the_right_error() {
    use RenderError as E;
    for (w, h) in [(0, 10), (10, 0), (Image::MAX_SIDE + 1, 1), (8192, 8192)] {
        let err = Image::new(w, h, Rgb::WHITE).unwrap_err();
        assert!(matches!(err, E::ImageSize { width, height } if (width, height) == (w, h)));
    }
    assert!(Image::new(Image::MAX_SIDE, 1, Rgb::WHITE).is_ok());

    let square = tissue_mesh::grid(2, 2.0).unwrap();
    let camera = Camera::orthographic(square.bounding_box(), -Vec3::Z, Vec3::Y).unwrap();
    let err = render_mesh(&square, Some(&[1.0, 2.0, 3.0]), &camera, 10, 10).unwrap_err();
    assert!(
        matches!(
            err,
            E::FieldLength {
                field: 3,
                vertices: 4
            }
        ),
        "{err:?}"
    );
    let msg = err.to_string();
    assert!(msg.contains('3') && msg.contains('4'), "{msg}");
    assert!(matches!(
        render_mesh(&square, None, &camera, 0, 10),
        Err(E::ImageSize { .. })
    ));

    let scale = ColorScale::new(0.0, 1.0).unwrap();
    let mut image = Image::new(20, 20, Rgb::WHITE).unwrap();
    let untouched = image.clone();
    let vp = Viewport::full(&image);
    let mut draw =
        |s: Surface<'_>| render(&mut image, vp, &camera, &scale, &[Surface::new(&square), s]);
    assert!(matches!(
        draw(Surface::from_parts(&[], &[])),
        Err(E::EmptyMesh {
            vertices: 0,
            triangles: 0
        })
    ));
    let p = [Vec3::ZERO, Vec3::X, Vec3::Y];
    assert!(matches!(
        draw(Surface::from_parts(&p, &[])),
        Err(E::EmptyMesh {
            vertices: 3,
            triangles: 0
        })
    ));
    let bad = [Vec3::ZERO, Vec3::X, Vec3::new(0.0, f32::NAN, 0.0)];
    let err = draw(Surface::from_parts(&bad, &[[0, 1, 2]])).unwrap_err();
    assert!(
        matches!(err, E::NonFinitePosition { vertex: 2, .. }),
        "{err:?}"
    );
    assert!(err.to_string().contains("vertex 2"), "{err}");
    let err = draw(Surface::from_parts(&p, &[[0, 1, 2], [0, 1, 3]])).unwrap_err();
    assert!(
        matches!(
            err,
            E::IndexOutOfRange {
                triangle: 1,
                index: 3,
                vertices: 3
            }
        ),
        "{err:?}"
    );
    // Nothing was drawn by the failing calls, not even the valid first surface.
    assert_eq!(image, untouched);

    let b = square.bounding_box();
    for (bounds, dir, up) in [
        (b, Vec3::ZERO, Vec3::Y),
        (b, Vec3::new(f32::NAN, 0.0, 1.0), Vec3::Y),
        (b, Vec3::Z, Vec3::Z * 2.0),
        (b, Vec3::Z, Vec3::ZERO),
        (b, Vec3::Z, Vec3::new(f32::INFINITY, 0.0, 0.0)),
        (
            Aabb {
                min: Vec3::ONE,
                max: Vec3::ZERO,
            },
            Vec3::Z,
            Vec3::Y,
        ),
        (
            Aabb {
                min: Vec3::ZERO,
                max: Vec3::splat(f32::INFINITY),
            },
            Vec3::Z,
            Vec3::Y,
        ),
    ] {
        assert!(
            matches!(
                Camera::orthographic(bounds, dir, up),
                Err(E::InvalidCamera { .. })
            ),
            "{bounds:?} {dir:?} {up:?}"
        );
    }
    for (min, max) in [
        (1.0, 1.0),
        (2.0, 1.0),
        (f32::NAN, 1.0),
        (0.0, f32::INFINITY),
    ] {
        assert!(matches!(
            ColorScale::new(min, max),
            Err(E::InvalidRange { .. })
        ));
    }

    let (before, after, field) = bump();
    let options = BeforeAfterOptions::default();
    assert!(matches!(
        before_after(&before, &after, &field[1..], &options),
        Err(E::FieldLength { .. })
    ));
    let options = BeforeAfterOptions {
        width: 0,
        ..BeforeAfterOptions::default()
    };
    assert!(matches!(
        before_after(&before, &after, &field, &options),
        Err(E::ImageSize { .. })
    ));
    let options = BeforeAfterOptions {
        view: View::Along {
            direction: Vec3::Z,
            up: Vec3::Z,
        },
        ..BeforeAfterOptions::default()
    };
    assert!(matches!(
        before_after(&before, &after, &field, &options),
        Err(E::InvalidCamera { .. })
    ));
}

#[test]
fn twenty_thousand_triangles_render_quickly() {
    // grid(101, …): 20 000 triangles.
    let before = tissue_mesh::grid(101, 10.0).unwrap();
    let moved: Vec<Vec3> = before
        .positions()
        .iter()
        .map(|p| *p + Vec3::Z * (1.0 - p.length_squared() / 9.0).max(0.0))
        .collect();
    let after = before.with_positions(moved).unwrap();
    let field: Vec<f32> = after.positions().iter().map(|p| p.z).collect();
    assert_eq!(after.triangle_count(), 20_000);
    let start = std::time::Instant::now();
    let image = before_after(&before, &after, &field, &BeforeAfterOptions::default()).unwrap();
    let elapsed = start.elapsed();
    assert_eq!(image.width(), 1200);
    // Generous bound for a loaded machine; typically a few tens of milliseconds in release.
    assert!(elapsed.as_secs_f64() < 2.0, "took {elapsed:?}");
}
