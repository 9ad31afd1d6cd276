//! The before/after figure of the `insert` program.

use tissue_mesh::TriMesh;

use crate::font::{draw_text, text_width, LINE_HEIGHT};
use crate::{render, ColorBar, ColorScale, Image, RenderError, Rgb, Surface, View, Viewport};

/// Settings of [`before_after`].
#[derive(Debug, Clone, PartialEq)]
pub struct BeforeAfterOptions {
    /// Image width in pixels (default 1200).
    pub width: u32,
    /// Image height in pixels (default 600).
    pub height: u32,
    /// Direction of view (default [`View::Oblique`], the three-quarter view that shows a
    /// bump's height; [`View::Front`] looks head-on along minus the mean normal).
    pub view: View,
    /// Background colour (default white); text is dark on light backgrounds, light on dark.
    pub background: Rgb,
    /// Title of the colour bar (default `"displacement, cm"`).
    pub title: String,
    /// Colour range (default `None`: the range of the field's finite values, see
    /// [`ColorScale::auto`]).
    pub range: Option<ColorScale>,
}

impl Default for BeforeAfterOptions {
    fn default() -> Self {
        BeforeAfterOptions {
            width: 1200,
            height: 600,
            view: View::Oblique,
            background: Rgb::WHITE,
            title: "displacement, cm".to_owned(),
            range: None,
        }
    }
}

/// Where the parts of the figure go.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Layout {
    pub(crate) before: Viewport,
    pub(crate) after: Viewport,
    pub(crate) legend: Viewport,
    pub(crate) text_scale: u32,
    pub(crate) caption_y: u32,
}

/// Captions on top; two equal panels side by side; the colour bar centred below, half the
/// image wide. Text scale 1 per 600 × 300 pixels (at least 1).
pub(crate) fn layout(width: u32, height: u32) -> Layout {
    let k = (width / 600).min(height / 300).max(1);
    let lh = LINE_HEIGHT * k;
    let pad = 4 * k;
    let caption_h = lh + 2 * pad;
    let bar_h = 12 * k;
    let legend_h = lh + k + bar_h + 3 * k + k + lh;
    let panels_h = height.saturating_sub(caption_h + legend_h + 2 * pad);
    let half = width / 2;
    let top = caption_h.min(height);
    Layout {
        before: Viewport {
            x: 0,
            y: top,
            width: half,
            height: panels_h,
        },
        after: Viewport {
            x: half,
            y: top,
            width: half,
            height: panels_h,
        },
        legend: Viewport {
            x: width / 4,
            y: (top + panels_h + pad).min(height),
            width: half,
            height: legend_h,
        },
        text_scale: k,
        caption_y: pad.min(height),
    }
}

/// The `insert` figure: the surface `before` (grey) and `after` (coloured by `field_after`, one
/// value per vertex of `after`) in two side-by-side panels captioned "before" and "after", seen
/// through one camera that frames the union of both bounding boxes, and one colour bar titled
/// `options.title` below them.
///
/// The camera's view is `options.view` of `before` (its mean normal sets the standard views).
///
/// # Errors
/// [`RenderError::ImageSize`] for a bad size, [`RenderError::FieldLength`] when `field_after`
/// does not have one value per vertex of `after`, [`RenderError::InvalidCamera`] for a bad
/// [`View::Along`].
pub fn before_after(
    before: &TriMesh,
    after: &TriMesh,
    field_after: &[f32],
    options: &BeforeAfterOptions,
) -> Result<Image, RenderError> {
    let _span = tracing::debug_span!(
        "before_after",
        width = options.width,
        height = options.height,
        vertices = after.vertex_count()
    )
    .entered();
    let mut image = Image::new(options.width, options.height, options.background)?;
    if field_after.len() != after.vertex_count() {
        return Err(RenderError::FieldLength {
            field: field_after.len(),
            vertices: after.vertex_count(),
        });
    }
    let bounds = before.bounding_box().union(&after.bounding_box());
    let camera = options.view.camera(before, bounds)?;
    let scale = options
        .range
        .unwrap_or_else(|| ColorScale::auto(field_after));
    let l = layout(options.width, options.height);
    render(
        &mut image,
        l.before,
        &camera,
        &scale,
        &[Surface::new(before)],
    )?;
    render(
        &mut image,
        l.after,
        &camera,
        &scale,
        &[Surface::new(after).with_field(field_after)],
    )?;
    let ink = if options.background.luminance() > 0.25 {
        Rgb::new(40, 40, 40)
    } else {
        Rgb::new(225, 225, 225)
    };
    let k = l.text_scale;
    for (caption, panel) in [("before", l.before), ("after", l.after)] {
        let x =
            i64::from(panel.x) + i64::from(panel.width / 2) - i64::from(text_width(caption, k) / 2);
        draw_text(&mut image, x, i64::from(l.caption_y), caption, k, ink);
    }
    ColorBar {
        scale,
        title: &options.title,
        ink,
        text_scale: k,
        show_nan: field_after.iter().any(|v| v.is_nan()),
    }
    .draw(&mut image, l.legend);
    Ok(image)
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;
    use crate::viridis;

    /// `color` is `reference` times one shading factor in `(0, 1]`, to within rounding.
    fn is_shaded(color: Rgb, reference: Rgb) -> bool {
        let [r, g, b] = reference.0.map(f32::from);
        let [cr, cg, cb] = color.0.map(f32::from);
        let shade = (cr + cg + cb) / (r + g + b);
        shade > 0.0
            && shade <= 1.0 + 1e-3
            && [(cr, r), (cg, g), (cb, b)]
                .iter()
                .all(|(c, x)| (c - shade * x).abs() <= 1.5)
    }

    #[test]
    fn after_panel_shows_the_field_where_the_before_panel_is_grey() {
        let before = tissue_mesh::grid(41, 10.0).unwrap();
        let moved: Vec<Vec3> = before
            .positions()
            .iter()
            .map(|p| *p + Vec3::Z * 2.0 * (1.0 - p.length_squared() / 6.25).max(0.0))
            .collect();
        let after = before.with_positions(moved).unwrap();
        let field: Vec<f32> = after.positions().iter().map(|p| p.z).collect();
        for view in [View::Oblique, View::Front] {
            let options = BeforeAfterOptions {
                view,
                ..BeforeAfterOptions::default()
            };
            let image = before_after(&before, &after, &field, &options).unwrap();
            let l = layout(options.width, options.height);
            let bounds = before.bounding_box().union(&after.bounding_box());
            let camera = view.camera(&before, bounds).unwrap();
            let pixel = |panel: Viewport, p: Vec3| {
                let q = camera.project(p, panel.width, panel.height);
                image
                    .pixel(panel.x + q.x as u32, panel.y + q.y as u32)
                    .unwrap()
            };
            // The apex (field 2 = max) is yellow in the after panel; the same spot of the flat
            // surface is grey in the before panel.
            let apex = pixel(l.after, Vec3::new(0.0, 0.0, 2.0));
            assert!(is_shaded(apex, viridis(1.0)), "{view:?}: apex {apex:?}");
            let flat = pixel(l.before, Vec3::ZERO);
            assert!(is_shaded(flat, Rgb::SURFACE_GREY), "{view:?}: {flat:?}");
            // Where the field is zero, the after panel shows the map's first colour.
            let corner = Vec3::new(4.0, -4.0, 0.0);
            let low = pixel(l.after, corner);
            assert!(is_shaded(low, viridis(0.0)), "{view:?}: corner {low:?}");
            assert!(is_shaded(pixel(l.before, corner), Rgb::SURFACE_GREY));
        }
    }

    #[test]
    fn layout_fits_the_image() {
        for (w, h) in [(1200, 600), (640, 360), (1, 1), (3000, 400)] {
            let l = layout(w, h);
            for vp in [l.before, l.after] {
                assert!(
                    vp.x + vp.width <= w && vp.y + vp.height <= h,
                    "{w}x{h}: {vp:?}"
                );
            }
            assert_eq!(l.before.width, l.after.width);
            assert!(l.legend.y >= l.before.y + l.before.height);
        }
        assert_eq!(layout(1200, 600).text_scale, 2);
    }
}
