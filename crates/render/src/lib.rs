//! # tissue-render: headless pictures of surfaces coloured by a per-vertex field
//!
//! A small software rasteriser (no GPU, no window) that draws [`tissue_mesh::TriMesh`] surfaces
//! coloured by a per-vertex scalar field (displacement in cm, stretch, …), adds a colour bar
//! with tick labels in a tiny built-in bitmap font, and writes the result as a PNG file.
//!
//! - [`Image`]: an RGB8 picture; [`Image::encode_png`], and [`Image::write_png`] which replaces
//!   the file atomically (temporary file in the same directory, then rename).
//! - [`Camera`]: orthographic, looking along a direction with an up vector, framing a bounding
//!   box; [`View`] builds the standard head-on and three-quarter views of a surface.
//! - [`render`]: z-buffered rasterisation of [`Surface`]s (a mesh, optionally a field, else a
//!   plain colour) into a [`Viewport`] of an image; [`render_mesh`] for one mesh in a new image.
//! - [`viridis`], [`ColorScale`]: the perceptual colour map and a value range mapped onto it;
//!   out-of-range values are clamped, NaN is [`NAN_COLOR`].
//! - [`ColorBar`], [`draw_text`]: the legend and the 5 × 7 font (digits, `. - + , = : / % ( ) _
//!   ' ?`, space, `a–z`, `A–Z`, `²`, `³`).
//! - [`before_after`]: the `insert` program's figure, two panels through one camera plus a
//!   colour bar.
//!
//! ## Conventions and invariants
//! - **Deterministic**: the same inputs give the same pixels and the same PNG bytes (no
//!   threads, no time stamps, no hashing; a fixed drawing order). Ties in depth go to the
//!   surface or triangle drawn first.
//! - **Pixel centres**: pixel `(x, y)` covers `[x, x+1) × [y, y+1)` of screen space, `y` down
//!   from the top-left corner, and is covered by a triangle when its centre `(x + ½, y + ½)` is
//!   inside it; a centre exactly on a shared edge belongs to exactly one of the two triangles.
//! - **Orthographic**: a length `L` (cm) in the image plane is `L ·`
//!   [`Camera::pixels_per_unit`] pixels, the same in every panel of the same size.
//! - **Shading**: Lambert from a headlight plus ambient light ([`AMBIENT`] + [`DIFFUSE`]` = 1`,
//!   so a face seen head-on shows its exact map colour); both faces of an open surface are lit.
//! - **Input checks**: bad sizes, fields, meshes and cameras are [`RenderError`]s, never panics;
//!   nothing is drawn when a check fails.
//! - Units: whatever the positions are in (cm in tissue); the framing does not depend on them.
//!
//! ## Example
//! ```
//! use glam::Vec3;
//! use tissue_render::{before_after, render_mesh, BeforeAfterOptions, Camera};
//!
//! // One sphere, seen from +z, coloured by height.
//! let sphere = tissue_mesh::uv_sphere(16, 15, 1.0)?;
//! let height: Vec<f32> = sphere.positions().iter().map(|p| p.z).collect();
//! let camera = Camera::orthographic(sphere.bounding_box(), -Vec3::Z, Vec3::Y)?;
//! let image = render_mesh(&sphere, Some(&height), &camera, 200, 200)?;
//! let png = image.encode_png()?;
//! assert!(png.starts_with(b"\x89PNG\r\n\x1a\n"));
//!
//! // A skin patch pushed up into a bump, before and after.
//! let before = tissue_mesh::grid(33, 10.0)?;
//! let moved: Vec<Vec3> = before
//!     .positions()
//!     .iter()
//!     .map(|p| *p + Vec3::Z * (1.0 - p.length_squared() / 9.0).max(0.0))
//!     .collect();
//! let after = before.with_positions(moved)?;
//! let displacement: Vec<f32> = before
//!     .positions()
//!     .iter()
//!     .zip(after.positions())
//!     .map(|(a, b)| a.distance(*b))
//!     .collect();
//! let figure = before_after(&before, &after, &displacement, &BeforeAfterOptions::default())?;
//! assert_eq!((figure.width(), figure.height()), (1200, 600));
//! let _bytes = figure.encode_png()?; // or figure.write_png("bump.png")?
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

#![forbid(unsafe_code)]

mod camera;
mod chart;
mod colormap;
mod compose;
mod error;
mod font;
mod image;
mod legend;
mod raster;

pub use camera::{Camera, View};
pub use chart::{LineChart, Series, Whisker};
pub use colormap::{viridis, ColorScale, NAN_COLOR};
pub use compose::{before_after, BeforeAfterOptions};
pub use error::RenderError;
pub use font::{draw_text, has_glyph, text_width, ADVANCE, GLYPH_HEIGHT, GLYPH_WIDTH, LINE_HEIGHT};
pub use image::{Image, Rgb};
pub use legend::{ColorBar, TICKS};
pub use raster::{render, render_mesh, Surface, Viewport, AMBIENT, DIFFUSE};
