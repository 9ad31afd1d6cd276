//! The z-buffered triangle rasteriser.

use glam::{DVec2, DVec3, Vec3};
use tissue_mesh::TriMesh;

use crate::colormap::{to_u8, viridis_f32, NAN_COLOR};
use crate::{Camera, ColorScale, Image, RenderError, Rgb};

/// Light that reaches a surface whatever its orientation, as a fraction of full brightness.
pub const AMBIENT: f32 = 0.3;
/// Headlight (Lambert) share of the brightness: a face seen head-on is at
/// `AMBIENT + DIFFUSE = 1`, i.e. exactly its colour-map colour.
pub const DIFFUSE: f32 = 0.7;

/// Normalised field values are clamped to `±FIELD_CLAMP` per vertex before interpolation, so
/// huge or infinite values interpolate without overflow (the difference from exact interpolation
/// lies far outside the colour range).
const FIELD_CLAMP: f32 = 1e6;

/// A triangle surface to draw: borrowed positions and triangles, optionally a per-vertex
/// scalar field (coloured by the [`ColorScale`] given to [`render`]), else a plain colour.
#[derive(Debug, Clone, Copy)]
pub struct Surface<'a> {
    positions: &'a [Vec3],
    triangles: &'a [[u32; 3]],
    field: Option<&'a [f32]>,
    color: Rgb,
}

impl<'a> Surface<'a> {
    /// A validated mesh, drawn in [`Rgb::SURFACE_GREY`].
    pub fn new(mesh: &'a TriMesh) -> Surface<'a> {
        Surface::from_parts(mesh.positions(), mesh.triangles())
    }

    /// Raw data, drawn in [`Rgb::SURFACE_GREY`]; checked by [`render`] (non-empty, finite
    /// positions, indices in range). Zero-area triangles are allowed and cover nothing.
    pub fn from_parts(positions: &'a [Vec3], triangles: &'a [[u32; 3]]) -> Surface<'a> {
        Surface {
            positions,
            triangles,
            field: None,
            color: Rgb::SURFACE_GREY,
        }
    }

    /// Colours the surface by `field`, one value per vertex (checked by [`render`]).
    pub fn with_field(self, field: &'a [f32]) -> Surface<'a> {
        Surface {
            field: Some(field),
            ..self
        }
    }

    /// Draws the surface (where it has no field) in `color` instead of grey.
    pub fn with_color(self, color: Rgb) -> Surface<'a> {
        Surface { color, ..self }
    }

    fn validate(&self) -> Result<(), RenderError> {
        let vertices = self.positions.len();
        if vertices == 0 || self.triangles.is_empty() {
            return Err(RenderError::EmptyMesh {
                vertices,
                triangles: self.triangles.len(),
            });
        }
        if let Some(field) = self.field {
            if field.len() != vertices {
                return Err(RenderError::FieldLength {
                    field: field.len(),
                    vertices,
                });
            }
        }
        if let Some(v) = self.positions.iter().position(|p| !p.is_finite()) {
            return Err(RenderError::NonFinitePosition {
                vertex: v,
                position: self.positions[v].to_array(),
            });
        }
        for (t, tri) in self.triangles.iter().enumerate() {
            if let Some(&index) = tri.iter().find(|&&i| i as usize >= vertices) {
                return Err(RenderError::IndexOutOfRange {
                    triangle: t,
                    index,
                    vertices,
                });
            }
        }
        Ok(())
    }
}

/// A rectangle of an image in pixels: `width × height` pixels from the top-left pixel `(x, y)`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Viewport {
    /// Left column.
    pub x: u32,
    /// Top row.
    pub y: u32,
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
}

impl Viewport {
    /// The whole of `image`.
    pub fn full(image: &Image) -> Viewport {
        Viewport {
            x: 0,
            y: 0,
            width: image.width(),
            height: image.height(),
        }
    }

    /// The part inside a `width × height` image.
    fn clip(self, width: u32, height: u32) -> Viewport {
        let x = self.x.min(width);
        let y = self.y.min(height);
        Viewport {
            x,
            y,
            width: self.width.min(width - x),
            height: self.height.min(height - y),
        }
    }
}

/// Draws `surfaces` into `viewport` of `image` (clipped to the image) through `camera`, with a
/// depth buffer shared by all surfaces: at each pixel the nearest surface wins (on an exact tie,
/// the one drawn first). Pixels no triangle covers keep their colour.
///
/// Coverage: a pixel is drawn by a triangle when its centre lies inside the projected triangle;
/// a centre exactly on an edge goes to exactly one of the two triangles sharing the edge (a
/// top-left-style tie rule evaluated identically for both), so shared edges are neither doubled
/// nor left open. Triangles are drawn whichever way they face.
///
/// Colour: the field value is interpolated linearly across each triangle (Gouraud) and then
/// colour-mapped through `scale` (NaN anywhere in the interpolation gives
/// [`crate::NAN_COLOR`]); surfaces without a field use their plain colour. The colour is then
/// multiplied by `AMBIENT + DIFFUSE·|n·l|`, with `n` the area-weighted vertex normal interpolated
/// across the triangle and `l` a headlight shining along the view direction, so both sides of an
/// open surface are lit alike.
///
/// # Errors
/// Every surface is checked before anything is drawn: [`RenderError::EmptyMesh`],
/// [`RenderError::FieldLength`], [`RenderError::NonFinitePosition`],
/// [`RenderError::IndexOutOfRange`].
pub fn render(
    image: &mut Image,
    viewport: Viewport,
    camera: &Camera,
    scale: &ColorScale,
    surfaces: &[Surface<'_>],
) -> Result<(), RenderError> {
    let _span = tracing::debug_span!(
        "render",
        width = viewport.width,
        height = viewport.height,
        surfaces = surfaces.len(),
        triangles = surfaces.iter().map(|s| s.triangles.len()).sum::<usize>()
    )
    .entered();
    for s in surfaces {
        s.validate()?;
    }
    let vp = viewport.clip(image.width(), image.height());
    if vp.width == 0 || vp.height == 0 {
        return Ok(());
    }
    let mut target = Target {
        image,
        viewport: vp,
        depth: vec![f32::INFINITY; vp.width as usize * vp.height as usize],
    };
    let pixels_per_unit = camera.pixels_per_unit(vp.width, vp.height);
    let projector = camera.projector(vp.width, vp.height, pixels_per_unit);
    let light = -camera.direction().as_dvec3();
    let mut scratch = Scratch::default();
    let mut drawn = 0usize;
    for s in surfaces {
        scratch.prepare(s, &projector, light, scale);
        drawn += draw_surface(&mut target, s, &scratch);
    }
    tracing::debug!(pixels_per_unit, drawn, "rendered");
    Ok(())
}

/// Renders one mesh through `camera` into a new `width × height` image on a white background,
/// coloured by `field` (over the range of its finite values, see [`ColorScale::auto`]) or in
/// grey without one. For a camera framing the mesh, build it from
/// [`TriMesh::bounding_box`](tissue_mesh::TriMesh::bounding_box).
///
/// # Errors
/// [`RenderError::ImageSize`], [`RenderError::FieldLength`].
pub fn render_mesh(
    mesh: &TriMesh,
    field: Option<&[f32]>,
    camera: &Camera,
    width: u32,
    height: u32,
) -> Result<Image, RenderError> {
    let mut image = Image::new(width, height, Rgb::WHITE)?;
    let mut surface = Surface::new(mesh);
    let scale = match field {
        Some(f) => {
            surface = surface.with_field(f);
            ColorScale::auto(f)
        }
        None => ColorScale::auto(&[]),
    };
    let viewport = Viewport::full(&image);
    render(&mut image, viewport, camera, &scale, &[surface])?;
    Ok(image)
}

/// The image, the part of it drawn into, and that part's depth buffer.
struct Target<'i> {
    image: &'i mut Image,
    viewport: Viewport,
    depth: Vec<f32>,
}

/// Per-vertex data of the surface being drawn, reused between surfaces.
#[derive(Default)]
struct Scratch {
    /// Screen position in viewport pixels.
    xy: Vec<DVec2>,
    /// Depth along the view direction.
    z: Vec<f32>,
    /// Signed `n·l` of the vertex normal.
    lambert: Vec<f32>,
    /// Normalised field value (clamped to `±FIELD_CLAMP`), empty without a field.
    t: Vec<f32>,
    /// Area-weighted normal sums.
    normals: Vec<DVec3>,
}

impl Scratch {
    fn prepare(
        &mut self,
        s: &Surface<'_>,
        projector: &crate::camera::Projector,
        light: DVec3,
        scale: &ColorScale,
    ) {
        self.xy.clear();
        self.z.clear();
        for &p in s.positions {
            let q = projector.apply(p);
            self.xy.push(DVec2::new(q.x, q.y));
            self.z.push(q.z as f32);
        }
        self.normals.clear();
        self.normals.resize(s.positions.len(), DVec3::ZERO);
        for tri in s.triangles {
            let [a, b, c] = tri.map(|i| s.positions[i as usize].as_dvec3());
            let n = (b - a).cross(c - a);
            for &i in tri {
                self.normals[i as usize] += n;
            }
        }
        self.lambert.clear();
        self.lambert.extend(
            self.normals
                .iter()
                .map(|n| n.normalize_or_zero().dot(light) as f32),
        );
        self.t.clear();
        if let Some(field) = s.field {
            self.t.extend(
                field
                    .iter()
                    .map(|&v| scale.normalize(v).clamp(-FIELD_CLAMP, FIELD_CLAMP)),
            );
        }
    }
}

/// Twice the signed area of `(a, b, p)`, evaluated with the edge's endpoints in a canonical
/// order so that the two triangles sharing an edge get exactly opposite values.
#[inline]
fn edge(a: DVec2, b: DVec2, p: DVec2) -> f64 {
    if (a.x, a.y) <= (b.x, b.y) {
        (b.x - a.x) * (p.y - a.y) - (b.y - a.y) * (p.x - a.x)
    } else {
        -((a.x - b.x) * (p.y - b.y) - (a.y - b.y) * (p.x - b.x))
    }
}

/// Whether a pixel centre exactly on the edge `a → b` belongs to the triangle on its positive
/// side. Exactly one of `a → b` and `b → a` owns it.
#[inline]
fn owns_edge(a: DVec2, b: DVec2) -> bool {
    let d = b - a;
    d.y > 0.0 || (d.y == 0.0 && d.x > 0.0)
}

/// Draws one prepared surface; returns the number of pixel writes.
fn draw_surface(target: &mut Target<'_>, s: &Surface<'_>, sc: &Scratch) -> usize {
    let vp = target.viewport;
    let (w, h) = (f64::from(vp.width), f64::from(vp.height));
    let base = s.color.0.map(f32::from);
    let nan = NAN_COLOR.0.map(f32::from);
    let mut drawn = 0;
    for tri in s.triangles {
        let [ia, mut ib, mut ic] = tri.map(|i| i as usize);
        let (a, mut b, mut c) = (sc.xy[ia], sc.xy[ib], sc.xy[ic]);
        let mut area = edge(a, b, c);
        if !area.is_finite() || area == 0.0 {
            continue; // seen edge-on or degenerate: covers no pixel centre
        }
        if area < 0.0 {
            std::mem::swap(&mut ib, &mut ic);
            std::mem::swap(&mut b, &mut c);
            area = -area;
        }
        let lo = a.min(b).min(c);
        let hi = a.max(b).max(c);
        // Pixels whose centre i + 0.5 lies in [lo, hi], clipped to the viewport.
        let x0 = (lo.x - 0.5).ceil().max(0.0);
        let x1 = (hi.x - 0.5).floor().min(w - 1.0);
        let y0 = (lo.y - 0.5).ceil().max(0.0);
        let y1 = (hi.y - 0.5).floor().min(h - 1.0);
        if x0 > x1 || y0 > y1 {
            continue;
        }
        let (x0, x1, y0, y1) = (x0 as u32, x1 as u32, y0 as u32, y1 as u32);
        let own = [owns_edge(b, c), owns_edge(c, a), owns_edge(a, b)];
        let inv_area = 1.0 / area;
        let z = [sc.z[ia], sc.z[ib], sc.z[ic]];
        let lambert = [sc.lambert[ia], sc.lambert[ib], sc.lambert[ic]];
        let t = (!sc.t.is_empty()).then(|| [sc.t[ia], sc.t[ib], sc.t[ic]]);
        let inside = |e: f64, owned: bool| e > 0.0 || (e == 0.0 && owned);
        for py in y0..=y1 {
            let row = (py as usize) * vp.width as usize;
            for px in x0..=x1 {
                let p = DVec2::new(f64::from(px) + 0.5, f64::from(py) + 0.5);
                let e0 = edge(b, c, p);
                let e1 = edge(c, a, p);
                let e2 = edge(a, b, p);
                if !(inside(e0, own[0]) && inside(e1, own[1]) && inside(e2, own[2])) {
                    continue;
                }
                let l = [
                    (e0 * inv_area) as f32,
                    (e1 * inv_area) as f32,
                    (e2 * inv_area) as f32,
                ];
                let depth = l[0] * z[0] + l[1] * z[1] + l[2] * z[2];
                let slot = &mut target.depth[row + px as usize];
                // Strictly nearer only (a NaN depth never wins): ties go to the first drawn.
                if depth >= *slot || depth.is_nan() {
                    continue;
                }
                *slot = depth;
                let shade = AMBIENT
                    + DIFFUSE
                        * (l[0] * lambert[0] + l[1] * lambert[1] + l[2] * lambert[2])
                            .abs()
                            .min(1.0);
                let color = match t {
                    Some(t) => {
                        let v = l[0] * t[0] + l[1] * t[1] + l[2] * t[2];
                        if v.is_nan() {
                            nan
                        } else {
                            viridis_f32(v)
                        }
                    }
                    None => base,
                };
                target.image.set_pixel(
                    vp.x + px,
                    vp.y + py,
                    Rgb(color.map(|ch| to_u8(ch * shade))),
                );
                drawn += 1;
            }
        }
    }
    drawn
}
