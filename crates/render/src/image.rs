//! An RGB8 raster and its PNG encoding.

use std::ffi::OsString;
use std::fs;
use std::io::{self, Write};
use std::path::Path;
use std::sync::atomic::{AtomicU64, Ordering};

use crate::RenderError;

/// An sRGB colour, 8 bits per channel, `[red, green, blue]`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Rgb(pub [u8; 3]);

impl Rgb {
    /// `(255, 255, 255)`.
    pub const WHITE: Rgb = Rgb([255, 255, 255]);
    /// `(0, 0, 0)`.
    pub const BLACK: Rgb = Rgb([0, 0, 0]);
    /// The neutral grey of surfaces drawn without a field, `(200, 200, 200)` before shading.
    pub const SURFACE_GREY: Rgb = Rgb([200, 200, 200]);

    /// The colour `(r, g, b)`.
    pub const fn new(r: u8, g: u8, b: u8) -> Rgb {
        Rgb([r, g, b])
    }

    /// Relative luminance in `[0, 1]` (Rec. 709 weights on linearised sRGB).
    pub fn luminance(self) -> f32 {
        let lin = |c: u8| {
            let c = f32::from(c) / 255.0;
            if c <= 0.04045 {
                c / 12.92
            } else {
                ((c + 0.055) / 1.055).powf(2.4)
            }
        };
        let [r, g, b] = self.0;
        0.2126 * lin(r) + 0.7152 * lin(g) + 0.0722 * lin(b)
    }
}

/// A `width × height` RGB8 picture, rows stored top to bottom, each row left to right.
///
/// Pixel `(x, y)` is the unit square `[x, x+1) × [y, y+1)` of screen space with `y` pointing down;
/// its centre is `(x + 0.5, y + 0.5)`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Image {
    width: u32,
    height: u32,
    data: Vec<u8>,
}

impl Image {
    /// Largest allowed width or height, in pixels.
    pub const MAX_SIDE: u32 = 16_384;
    /// Largest allowed number of pixels, `2^25` (about 33.5 million: e.g. 8192 × 4096).
    pub const MAX_PIXELS: u64 = 1 << 25;

    /// An image filled with `background`.
    ///
    /// # Errors
    /// [`RenderError::ImageSize`] when a side is 0 or above [`Image::MAX_SIDE`], or the image has
    /// more than [`Image::MAX_PIXELS`] pixels.
    pub fn new(width: u32, height: u32, background: Rgb) -> Result<Image, RenderError> {
        check_size(width, height)?;
        let pixels = width as usize * height as usize;
        let mut data = Vec::with_capacity(pixels * 3);
        for _ in 0..pixels {
            data.extend_from_slice(&background.0);
        }
        Ok(Image {
            width,
            height,
            data,
        })
    }

    /// Width in pixels.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Height in pixels.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// The colour of pixel `(x, y)`, `None` outside the image.
    pub fn pixel(&self, x: u32, y: u32) -> Option<Rgb> {
        let i = self.index(x, y)?;
        Some(Rgb([self.data[i], self.data[i + 1], self.data[i + 2]]))
    }

    /// Sets pixel `(x, y)`; does nothing outside the image.
    pub fn set_pixel(&mut self, x: u32, y: u32, color: Rgb) {
        if let Some(i) = self.index(x, y) {
            self.data[i..i + 3].copy_from_slice(&color.0);
        }
    }

    /// Fills the rectangle of `w × h` pixels whose top-left pixel is `(x, y)`, clipped to the
    /// image (the corner may lie outside).
    pub fn fill_rect(&mut self, x: i64, y: i64, w: u32, h: u32, color: Rgb) {
        let x0 = x.clamp(0, i64::from(self.width)) as usize;
        let x1 = x
            .saturating_add(i64::from(w))
            .clamp(0, i64::from(self.width)) as usize;
        let y0 = y.clamp(0, i64::from(self.height)) as usize;
        let y1 = y
            .saturating_add(i64::from(h))
            .clamp(0, i64::from(self.height)) as usize;
        let stride = self.width as usize * 3;
        for row in y0..y1 {
            for px in self.data[row * stride + x0 * 3..row * stride + x1 * 3].chunks_exact_mut(3) {
                px.copy_from_slice(&color.0);
            }
        }
    }

    /// The raw pixel bytes, `[r, g, b]` per pixel, row-major from the top-left corner
    /// (`3 · width · height` bytes).
    pub fn as_raw(&self) -> &[u8] {
        &self.data
    }

    /// Encodes the image as an 8-bit RGB PNG (no metadata, so the same pixels always give the
    /// same bytes).
    ///
    /// # Errors
    /// [`RenderError::Encode`] if the encoder fails (it does not for a valid image).
    pub fn encode_png(&self) -> Result<Vec<u8>, RenderError> {
        let mut out = Vec::with_capacity(self.data.len() / 4 + 1024);
        let mut encoder = png::Encoder::new(&mut out, self.width, self.height);
        encoder.set_color(png::ColorType::Rgb);
        encoder.set_depth(png::BitDepth::Eight);
        let mut writer = encoder.write_header()?;
        writer.write_image_data(&self.data)?;
        writer.finish()?;
        Ok(out)
    }

    /// Writes the image as a PNG file at `path`, replacing any existing file.
    ///
    /// The bytes go to a new temporary file in the same directory (named
    /// `.<file name>.<process id>.<n>.tmp`), which is flushed to disk and then renamed over
    /// `path`, so `path` never holds a half-written picture. On any error the temporary file is
    /// removed.
    ///
    /// # Errors
    /// [`RenderError::Io`] naming `path` (missing directory, no permission, `path` names a
    /// directory, …); [`RenderError::Encode`] if encoding fails.
    pub fn write_png(&self, path: impl AsRef<Path>) -> Result<(), RenderError> {
        let path = path.as_ref();
        let io_error = |source: io::Error| RenderError::Io {
            path: path.to_path_buf(),
            source,
        };
        let bytes = self.encode_png()?;
        let Some(file_name) = path.file_name() else {
            return Err(io_error(io::Error::new(
                io::ErrorKind::InvalidInput,
                "the path does not name a file",
            )));
        };
        let dir = match path.parent() {
            Some(d) if !d.as_os_str().is_empty() => d,
            _ => Path::new("."),
        };
        static COUNTER: AtomicU64 = AtomicU64::new(0);
        let mut tmp_name = OsString::from(".");
        tmp_name.push(file_name);
        tmp_name.push(format!(
            ".{}.{}.tmp",
            std::process::id(),
            COUNTER.fetch_add(1, Ordering::Relaxed)
        ));
        let tmp = dir.join(tmp_name);
        let file = fs::OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(&tmp)
            .map_err(io_error)?;
        // From here on the temporary file is ours: remove it on any failure.
        let written = write_and_sync(file, &bytes).and_then(|()| fs::rename(&tmp, path));
        if let Err(e) = written {
            // Best effort: the original error is the one worth reporting.
            let _ = fs::remove_file(&tmp);
            return Err(io_error(e));
        }
        tracing::debug!(path = %path.display(), bytes = bytes.len(), "wrote PNG");
        Ok(())
    }

    fn index(&self, x: u32, y: u32) -> Option<usize> {
        (x < self.width && y < self.height)
            .then(|| (y as usize * self.width as usize + x as usize) * 3)
    }
}

/// Writes everything and flushes it to disk; the file is closed on return.
fn write_and_sync(mut file: fs::File, bytes: &[u8]) -> io::Result<()> {
    file.write_all(bytes)?;
    file.sync_all()
}

/// Checks an image size against [`Image::MAX_SIDE`] and [`Image::MAX_PIXELS`].
pub(crate) fn check_size(width: u32, height: u32) -> Result<(), RenderError> {
    let ok = (1..=Image::MAX_SIDE).contains(&width)
        && (1..=Image::MAX_SIDE).contains(&height)
        && u64::from(width) * u64::from(height) <= Image::MAX_PIXELS;
    if ok {
        Ok(())
    } else {
        Err(RenderError::ImageSize { width, height })
    }
}
