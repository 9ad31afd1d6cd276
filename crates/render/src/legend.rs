//! The colour bar: a horizontal gradient with tick labels and a title.

use crate::colormap::{viridis, NAN_COLOR};
use crate::font::{draw_text, text_width, LINE_HEIGHT};
use crate::{ColorScale, Image, Rgb, Viewport};

/// Number of tick labels: the two ends and three values between.
pub const TICKS: usize = 5;

/// A horizontal colour bar for a [`ColorScale`], drawn by [`ColorBar::draw`].
///
/// Layout inside its rectangle, top to bottom: the title (centred), the gradient bar (its first
/// column exactly the map's first colour, its last column exactly the last), tick marks and
/// [`TICKS`] labels (`min`, three evenly spaced values, `max`; decimals chosen so each label is
/// within 2 % of a tick step of its value). With `show_nan`, a swatch of
/// [`crate::NAN_COLOR`] labelled `NaN` sits to the right of the bar.
#[derive(Debug, Clone, PartialEq)]
pub struct ColorBar<'a> {
    /// The range shown.
    pub scale: ColorScale,
    /// Title, e.g. `"displacement, cm"`.
    pub title: &'a str,
    /// Colour of text, tick marks and the bar's outline.
    pub ink: Rgb,
    /// Size of a font pixel in image pixels (clamped to `1..=64`).
    pub text_scale: u32,
    /// Whether to add a swatch for NaN values.
    pub show_nan: bool,
}

impl ColorBar<'_> {
    /// Draws the bar into `rect` of `image`; anything that does not fit is clipped.
    pub fn draw(&self, image: &mut Image, rect: Viewport) {
        let k = self.text_scale.clamp(1, 64);
        let lh = LINE_HEIGHT * k;
        let labels = tick_labels(&self.scale, TICKS);
        let widest = labels.iter().map(|l| text_width(l, k)).max().unwrap_or(0);
        let nan_label = "NaN";
        let nan_w = if self.show_nan {
            text_width(nan_label, k).max(4 * k)
        } else {
            0
        };
        let nan_gap = if self.show_nan { 4 * k + widest / 2 } else { 0 };
        // Leave half a label on each side so the end labels, centred on their ticks, fit.
        let mut bar_x = i64::from(rect.x) + i64::from(widest / 2);
        let mut bar_w = rect.width.saturating_sub(widest + nan_w + nan_gap);
        if bar_w < 2 {
            bar_x = i64::from(rect.x);
            bar_w = rect.width.max(1);
        }
        let tick_h = 3 * k;
        let bar_y = i64::from(rect.y) + i64::from(lh + k);
        let bar_h = rect.height.saturating_sub(lh + k + tick_h + k + lh).max(1);
        let label_y = bar_y + i64::from(bar_h + tick_h + k);

        let title_w = text_width(self.title, k);
        let title_x = bar_x + i64::from(bar_w / 2) - i64::from(title_w / 2);
        draw_text(image, title_x, i64::from(rect.y), self.title, k, self.ink);

        // Outline one pixel outside the gradient, then the gradient itself.
        image.fill_rect(bar_x - 1, bar_y - 1, bar_w + 2, bar_h + 2, self.ink);
        for i in 0..bar_w {
            let t = if bar_w > 1 {
                i as f32 / (bar_w - 1) as f32
            } else {
                0.5
            };
            image.fill_rect(bar_x + i64::from(i), bar_y, 1, bar_h, viridis(t));
        }
        let tick_w = (k / 2).max(1);
        for (j, label) in labels.iter().enumerate() {
            let frac = j as f64 / (TICKS - 1) as f64;
            let x = bar_x + (frac * f64::from(bar_w.saturating_sub(1))).round() as i64;
            image.fill_rect(
                x - i64::from(tick_w / 2),
                bar_y + i64::from(bar_h),
                tick_w,
                tick_h,
                self.ink,
            );
            let w = text_width(label, k);
            draw_text(image, x - i64::from(w / 2), label_y, label, k, self.ink);
        }
        if self.show_nan {
            let x = bar_x + i64::from(bar_w) + i64::from(nan_gap);
            image.fill_rect(x - 1, bar_y - 1, nan_w + 2, bar_h + 2, self.ink);
            image.fill_rect(x, bar_y, nan_w, bar_h, NAN_COLOR);
            let w = text_width(nan_label, k);
            draw_text(
                image,
                x + i64::from(nan_w / 2) - i64::from(w / 2),
                label_y,
                nan_label,
                k,
                self.ink,
            );
        }
    }
}

/// `count ≥ 2` labels for evenly spaced values from `min` to `max` of `scale`: fixed-point with
/// the fewest decimals (at most 6) that keep every label within 2 % of a step of its value and
/// the labels distinct; scientific notation for magnitudes of 10⁶ and more or steps below 10⁻⁶.
pub(crate) fn tick_labels(scale: &ColorScale, count: usize) -> Vec<String> {
    let count = count.max(2);
    let (min, max) = (f64::from(scale.min()), f64::from(scale.max()));
    let step = (max - min) / (count - 1) as f64;
    let values: Vec<f64> = (0..count)
        .map(|i| {
            if i == count - 1 {
                max
            } else {
                min + step * i as f64
            }
        })
        .collect();
    if min.abs().max(max.abs()) >= 1e6 || step < 1e-6 {
        return values.iter().map(|v| format!("{v:.2e}")).collect();
    }
    let format = |d: usize| -> Vec<String> { values.iter().map(|&v| fixed(v, d)).collect() };
    for d in 0..=6 {
        let labels = format(d);
        let close = labels
            .iter()
            .zip(&values)
            .all(|(l, v)| l.parse::<f64>().is_ok_and(|x| (x - v).abs() <= 0.02 * step));
        let distinct = labels.windows(2).all(|w| w[0] != w[1]);
        if close && distinct {
            return labels;
        }
    }
    format(6)
}

/// `v` with `d` decimals; a value that rounds to zero is printed without a sign ("-0.00"
/// would read as a negative number).
fn fixed(v: f64, d: usize) -> String {
    let s = format!("{v:.d$}");
    match s.strip_prefix('-') {
        Some(rest) if rest.bytes().all(|b| b == b'0' || b == b'.') => rest.to_owned(),
        _ => s,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn labels(min: f32, max: f32) -> Vec<String> {
        tick_labels(&ColorScale::new(min, max).unwrap(), 5)
    }

    #[test]
    fn labels_use_just_enough_decimals() {
        assert_eq!(labels(0.0, 1.0), ["0.00", "0.25", "0.50", "0.75", "1.00"]);
        assert_eq!(labels(0.0, 2.0), ["0.0", "0.5", "1.0", "1.5", "2.0"]);
        assert_eq!(labels(0.0, 40.0), ["0", "10", "20", "30", "40"]);
        assert_eq!(labels(-1.0, 1.0), ["-1.0", "-0.5", "0.0", "0.5", "1.0"]);
        assert_eq!(labels(1.0, 1.5)[0], "1.000");
        assert_eq!(labels(0.0, 1e7)[4], "1.00e7");
    }

    #[test]
    fn negative_zero_is_printed_as_zero() {
        // -1 + 4 · 0.25 in float may come out as a tiny negative; it must read "0".
        assert_eq!(fixed(-0.001, 2), "0.00");
        assert_eq!(fixed(-0.0, 0), "0");
        assert_eq!(fixed(-0.5, 1), "-0.5");
        assert_eq!(fixed(-10.0, 0), "-10");
        assert_eq!(labels(-0.3, 0.3)[2], "0.00");
    }

    #[test]
    fn bar_ends_are_the_map_ends_and_small_rects_do_not_panic() {
        let scale = ColorScale::new(0.0, 1.0).unwrap();
        let bar = ColorBar {
            scale,
            title: "stretch",
            ink: Rgb::BLACK,
            text_scale: 1,
            show_nan: true,
        };
        let mut img = Image::new(300, 60, Rgb::WHITE).unwrap();
        bar.draw(
            &mut img,
            Viewport {
                x: 0,
                y: 0,
                width: 300,
                height: 60,
            },
        );
        let has = |c: Rgb| img.as_raw().chunks_exact(3).any(|p| p == c.0);
        assert!(has(viridis(0.0)) && has(viridis(1.0)) && has(NAN_COLOR));
        for (w, h) in [(1, 1), (3, 2), (20, 5)] {
            let mut img = Image::new(w, h, Rgb::WHITE).unwrap();
            bar.draw(
                &mut img,
                Viewport {
                    x: 0,
                    y: 0,
                    width: w,
                    height: h,
                },
            );
        }
    }
}
