//! The viridis colour map and the mapping of a value range onto it.

use crate::{RenderError, Rgb};

/// Viridis (van der Walt & Smith, matplotlib's default map) at ten evenly spaced stops
/// `t = 0, 1/9, …, 1`, as published (`viridisLite::viridis(10)`): `#440154 #482878 #3E4A89
/// #31688E #26828E #1F9E89 #35B779 #6DCD59 #B4DE2C #FDE725`.
const VIRIDIS_STOPS: [[u8; 3]; 10] = [
    [0x44, 0x01, 0x54],
    [0x48, 0x28, 0x78],
    [0x3E, 0x4A, 0x89],
    [0x31, 0x68, 0x8E],
    [0x26, 0x82, 0x8E],
    [0x1F, 0x9E, 0x89],
    [0x35, 0xB7, 0x79],
    [0x6D, 0xCD, 0x59],
    [0xB4, 0xDE, 0x2C],
    [0xFD, 0xE7, 0x25],
];

/// The colour of a NaN value: a saturated magenta that viridis never produces.
pub const NAN_COLOR: Rgb = Rgb([255, 0, 255]);

/// Viridis at `t ∈ [0, 1]`: the published stops linearly interpolated in sRGB. `t` outside
/// `[0, 1]` is clamped; NaN gives [`NAN_COLOR`].
pub fn viridis(t: f32) -> Rgb {
    if t.is_nan() {
        return NAN_COLOR;
    }
    let [r, g, b] = viridis_f32(t);
    Rgb([to_u8(r), to_u8(g), to_u8(b)])
}

/// Viridis as `0..=255` floats, before rounding (`t` clamped, NaN not handled).
#[inline]
pub(crate) fn viridis_f32(t: f32) -> [f32; 3] {
    let x = t.clamp(0.0, 1.0) * (VIRIDIS_STOPS.len() - 1) as f32;
    let i = (x as usize).min(VIRIDIS_STOPS.len() - 2);
    let f = x - i as f32;
    let (a, b) = (VIRIDIS_STOPS[i], VIRIDIS_STOPS[i + 1]);
    let lerp = |k: usize| f32::from(a[k]) + f * (f32::from(b[k]) - f32::from(a[k]));
    [lerp(0), lerp(1), lerp(2)]
}

/// Rounds a `0..=255` channel value to `u8`, saturating.
#[inline]
pub(crate) fn to_u8(c: f32) -> u8 {
    (c + 0.5).clamp(0.0, 255.0) as u8
}

/// A value range `[min, max]` mapped linearly onto viridis: `min` to its first colour, `max` to
/// its last. Values outside are clamped to the end colours; NaN gets [`NAN_COLOR`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ColorScale {
    min: f32,
    max: f32,
}

impl ColorScale {
    /// The range `[min, max]`.
    ///
    /// # Errors
    /// [`RenderError::InvalidRange`] unless both ends are finite and `min < max`.
    pub fn new(min: f32, max: f32) -> Result<ColorScale, RenderError> {
        if min.is_finite() && max.is_finite() && min < max {
            Ok(ColorScale { min, max })
        } else {
            Err(RenderError::InvalidRange { min, max })
        }
    }

    /// The range of the finite values of `values`. A constant field `v` gets
    /// `[v − h, v + h]` with `h = max(|v|, 1)/2` (so it shows the middle colour); no finite value
    /// at all gives `[0, 1]`.
    pub fn auto(values: &[f32]) -> ColorScale {
        let mut finite = values.iter().copied().filter(|v| v.is_finite());
        let Some(first) = finite.next() else {
            return ColorScale { min: 0.0, max: 1.0 };
        };
        let (min, max) = finite.fold((first, first), |(lo, hi), v| (lo.min(v), hi.max(v)));
        if min < max {
            ColorScale { min, max }
        } else {
            let h = 0.5 * min.abs().max(1.0);
            ColorScale {
                min: min - h,
                max: max + h,
            }
        }
    }

    /// Lower end of the range.
    pub fn min(&self) -> f32 {
        self.min
    }

    /// Upper end of the range.
    pub fn max(&self) -> f32 {
        self.max
    }

    /// `(v − min) / (max − min)`, not clamped (computed in `f64`, so a wide range cannot
    /// overflow); NaN stays NaN.
    pub fn normalize(&self, v: f32) -> f32 {
        ((f64::from(v) - f64::from(self.min)) / (f64::from(self.max) - f64::from(self.min))) as f32
    }

    /// The colour of `v`.
    pub fn color(&self, v: f32) -> Rgb {
        viridis(self.normalize(v))
    }
}
