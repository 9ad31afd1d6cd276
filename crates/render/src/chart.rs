//! A line chart: axes with ticks and labels, polylines, a legend, and whiskers (P5–P95 with the
//! median marked) at chosen abscissae — the weekly figures of an expansion over weeks.

use crate::font::{draw_text, text_width, GLYPH_HEIGHT};
use crate::{Image, RenderError, Rgb};

/// One line of a chart.
#[derive(Debug, Clone, PartialEq)]
pub struct Series {
    /// Its legend label.
    pub label: String,
    /// Its colour.
    pub color: Rgb,
    /// Its points `(x, y)`, drawn in order.
    pub points: Vec<(f64, f64)>,
}

/// A vertical whisker: at `x`, from `low` to `high`, the median `mid` marked.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Whisker {
    /// Abscissa.
    pub x: f64,
    /// P5.
    pub low: f64,
    /// P50.
    pub mid: f64,
    /// P95.
    pub high: f64,
    /// Its colour.
    pub color: Rgb,
}

/// What a chart shows.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct LineChart {
    /// Title, above the plot.
    pub title: String,
    /// The x axis's label.
    pub x_label: String,
    /// The y axis's label.
    pub y_label: String,
    /// The lines.
    pub series: Vec<Series>,
    /// The whiskers.
    pub whiskers: Vec<Whisker>,
}

const WHITE: Rgb = Rgb([255, 255, 255]);
const INK: Rgb = Rgb([40, 40, 40]);
const GRID: Rgb = Rgb([225, 225, 225]);

/// "Nice" tick step for a span split in about `n` parts: 1, 2 or 5 × 10^k.
fn tick_step(span: f64, n: f64) -> f64 {
    let raw = (span / n).max(f64::MIN_POSITIVE);
    let p = 10f64.powf(raw.log10().floor());
    let m = raw / p;
    let f = if m <= 1.0 {
        1.0
    } else if m <= 2.0 {
        2.0
    } else if m <= 5.0 {
        5.0
    } else {
        10.0
    };
    f * p
}

fn label(v: f64, step: f64) -> String {
    if step >= 1.0 {
        format!("{v:.0}")
    } else if step >= 0.1 {
        format!("{v:.1}")
    } else {
        format!("{v:.2}")
    }
}

/// A thick line from `a` to `b` (pixels), clipped to the image.
fn line(image: &mut Image, a: (f64, f64), b: (f64, f64), width: u32, color: Rgb) {
    let n = ((b.0 - a.0).abs().max((b.1 - a.1).abs()).ceil() as usize).max(1);
    let half = i64::from(width / 2);
    for i in 0..=n {
        let t = i as f64 / n as f64;
        let x = (a.0 + t * (b.0 - a.0)).round() as i64;
        let y = (a.1 + t * (b.1 - a.1)).round() as i64;
        image.fill_rect(x - half, y - half, width, width, color);
    }
}

impl LineChart {
    /// Draws the chart on a white `width × height` image. Non-finite points are skipped.
    ///
    /// # Errors
    /// [`RenderError::ImageSize`] for an image size out of range.
    pub fn draw(&self, width: u32, height: u32) -> Result<Image, RenderError> {
        let mut image = Image::new(width, height, WHITE)?;
        let scale = if width >= 800 { 2 } else { 1 };
        let glyph = i64::from(GLYPH_HEIGHT * scale);
        let (left, right) = (i64::from(14 * 6 * scale) / 2 + 2 * glyph, 20);
        let (top, bottom) = (2 * glyph + 10, 2 * glyph + 20);
        let (w, h) = (
            (i64::from(width) - left - right).max(10),
            (i64::from(height) - top - bottom).max(10),
        );
        let finite = |p: &(f64, f64)| p.0.is_finite() && p.1.is_finite();
        let xs = self
            .series
            .iter()
            .flat_map(|s| s.points.iter().filter(|p| finite(p)).map(|p| p.0))
            .chain(self.whiskers.iter().map(|w| w.x));
        let ys = self
            .series
            .iter()
            .flat_map(|s| s.points.iter().filter(|p| finite(p)).map(|p| p.1))
            .chain(self.whiskers.iter().flat_map(|w| [w.low, w.high]))
            .filter(|v| v.is_finite());
        let (x0, x1) = xs.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
            (a.min(x), b.max(x))
        });
        let (y0, y1) = ys.fold((0.0f64, f64::NEG_INFINITY), |(a, b), y| {
            (a.min(y), b.max(y))
        });
        let (x0, x1) = if x1 > x0 { (x0, x1) } else { (0.0, 1.0) };
        let ystep = tick_step(if y1 > y0 { y1 - y0 } else { 1.0 }, 5.0);
        let y1 = if y1 > y0 {
            (y1 / ystep).ceil() * ystep
        } else {
            y0 + 1.0
        };
        let y0 = (y0 / ystep).floor() * ystep;
        let px = |x: f64| left as f64 + (x - x0) / (x1 - x0) * w as f64;
        let py = |y: f64| (top + h) as f64 - (y - y0) / (y1 - y0) * h as f64;

        // Grid and ticks.
        let mut y = y0;
        while y <= y1 + 1e-9 * ystep {
            let yy = py(y).round() as i64;
            image.fill_rect(left, yy, w as u32, 1, GRID);
            let text = label(y, ystep);
            let tw = i64::from(text_width(&text, scale));
            draw_text(&mut image, left - tw - 6, yy - glyph / 2, &text, scale, INK);
            y += ystep;
        }
        let xstep = tick_step(x1 - x0, 8.0);
        let mut x = (x0 / xstep).ceil() * xstep;
        while x <= x1 + 1e-9 * xstep {
            let xx = px(x).round() as i64;
            image.fill_rect(xx, top + h, 1, 5, INK);
            let text = label(x, xstep);
            let tw = i64::from(text_width(&text, scale));
            draw_text(&mut image, xx - tw / 2, top + h + 8, &text, scale, INK);
            x += xstep;
        }
        image.fill_rect(left, top, 1, h as u32, INK);
        image.fill_rect(left, top + h, w as u32, 1, INK);

        // Lines, then whiskers.
        for s in &self.series {
            let pts: Vec<(f64, f64)> = s
                .points
                .iter()
                .filter(|p| finite(p))
                .map(|&(x, y)| (px(x), py(y)))
                .collect();
            for pair in pts.windows(2) {
                line(&mut image, pair[0], pair[1], 1 + scale, s.color);
            }
        }
        for wh in &self.whiskers {
            let x = px(wh.x);
            line(
                &mut image,
                (x, py(wh.low)),
                (x, py(wh.high)),
                1 + scale,
                wh.color,
            );
            for v in [wh.low, wh.high] {
                line(
                    &mut image,
                    (x - 6.0, py(v)),
                    (x + 6.0, py(v)),
                    1 + scale,
                    wh.color,
                );
            }
            let r = i64::from(3 * scale);
            image.fill_rect(
                x.round() as i64 - r,
                py(wh.mid).round() as i64 - r,
                (2 * r) as u32,
                (2 * r) as u32,
                wh.color,
            );
        }

        // Title, axis labels, legend.
        draw_text(&mut image, left, 6, &self.title, scale, INK);
        let tw = i64::from(text_width(&self.x_label, scale));
        draw_text(
            &mut image,
            left + w / 2 - tw / 2,
            top + h + 10 + glyph,
            &self.x_label,
            scale,
            INK,
        );
        draw_text(&mut image, 4, top - glyph - 4, &self.y_label, scale, INK);
        let mut ly = top + 6;
        for s in &self.series {
            let lx = left + 12;
            image.fill_rect(lx, ly + glyph / 2 - 1, 18, 3, s.color);
            draw_text(&mut image, lx + 24, ly, &s.label, scale, INK);
            ly += glyph + 6;
        }
        Ok(image)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_chart_is_drawn_deterministically_with_its_lines() {
        let chart = LineChart {
            title: "Expansion".into(),
            x_label: "day".into(),
            y_label: "cm2".into(),
            series: vec![Series {
                label: "grown".into(),
                color: Rgb([200, 30, 30]),
                points: vec![(0.0, 0.0), (7.0, 10.0), (14.0, f64::NAN), (70.0, 40.0)],
            }],
            whiskers: vec![Whisker {
                x: 70.0,
                low: 30.0,
                mid: 40.0,
                high: 50.0,
                color: Rgb([30, 30, 200]),
            }],
        };
        let a = chart.draw(640, 400).unwrap_or_else(|e| panic!("{e}"));
        let b = chart.draw(640, 400).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(a.as_raw(), b.as_raw());
        let red = a.as_raw().chunks(3).filter(|p| p == &[200, 30, 30]).count();
        assert!(red > 100, "{red}");
        assert!(LineChart::default().draw(0, 10).is_err());
    }
}
