//! The orthographic camera and the standard views of a surface.

use glam::{DVec3, Vec3};
use tissue_mesh::{Aabb, TriMesh};

use crate::RenderError;

/// An orthographic camera: looks along [`Camera::direction`], with [`Camera::up`] pointing up
/// on screen and [`Camera::right`] to the right, and frames a box so that the box's projection
/// fills the viewport up to a margin of [`Camera::MARGIN`] on the limiting side.
///
/// The framing depends only on the box and the directions, and the scale only on the viewport
/// size ([`Camera::pixels_per_unit`]), so one camera used for two panels of the same size gives
/// them identical framing. Nothing is clipped in depth: every triangle in the viewport is drawn.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Camera {
    center: DVec3,
    direction: DVec3,
    up: DVec3,
    right: DVec3,
    half_width: f64,
    half_height: f64,
}

impl Camera {
    /// Fraction of the viewport's limiting side left empty on each side of the framed box.
    pub const MARGIN: f64 = 0.05;

    /// A camera looking along `direction` (from the eye into the scene), with `up` projected
    /// onto the image plane as the screen's up, framing `bounds`.
    ///
    /// A box of zero extent in the image plane (a single point) is framed as if it were 2 units
    /// wide and high.
    ///
    /// # Errors
    /// [`RenderError::InvalidCamera`] when `bounds` is not finite or has `min > max`,
    /// `direction` is zero or not finite, or `up` is not finite or (nearly) parallel to
    /// `direction`.
    pub fn orthographic(bounds: Aabb, direction: Vec3, up: Vec3) -> Result<Camera, RenderError> {
        let invalid = |reason: String| Err(RenderError::InvalidCamera { reason });
        if !(bounds.min.is_finite() && bounds.max.is_finite()) || bounds.min.cmpgt(bounds.max).any()
        {
            return invalid(format!(
                "the box to frame, {:?} to {:?}, is not finite or has min > max",
                bounds.min, bounds.max
            ));
        }
        let d = direction.as_dvec3();
        if !d.is_finite() || d.length_squared() == 0.0 {
            return invalid(format!(
                "view direction {direction:?} is zero or not finite"
            ));
        }
        let d = d.normalize();
        let u0 = up.as_dvec3();
        let u = u0 - d * d.dot(u0);
        if !u0.is_finite() || u0.length_squared() == 0.0 || u.length() <= 1e-6 * u0.length() {
            return invalid(format!(
                "up vector {up:?} is zero, not finite or parallel to the view direction {direction:?}"
            ));
        }
        let u = u.normalize();
        let r = d.cross(u);
        let (lo, hi) = (bounds.min.as_dvec3(), bounds.max.as_dvec3());
        let center = (lo + hi) * 0.5;
        let size = hi - lo;
        // Half the extent of the projected box: the corners are symmetric about the centre.
        let half_width = 0.5 * (size * r.abs()).element_sum();
        let half_height = 0.5 * (size * u.abs()).element_sum();
        let (half_width, half_height) = if half_width > 0.0 || half_height > 0.0 {
            (half_width, half_height)
        } else {
            (1.0, 1.0)
        };
        Ok(Camera {
            center,
            direction: d,
            up: u,
            right: r,
            half_width,
            half_height,
        })
    }

    /// Unit view direction (from the eye into the scene).
    pub fn direction(&self) -> Vec3 {
        self.direction.as_vec3()
    }

    /// Unit screen-up direction in the world, perpendicular to [`Camera::direction`].
    pub fn up(&self) -> Vec3 {
        self.up.as_vec3()
    }

    /// Unit screen-right direction in the world, `direction × up`.
    pub fn right(&self) -> Vec3 {
        self.right.as_vec3()
    }

    /// The framed point, drawn at the centre of the viewport.
    pub fn center(&self) -> Vec3 {
        self.center.as_vec3()
    }

    /// The scale of a `width × height` viewport, in pixels per world unit (per cm in tissue):
    /// the framed box spans `1 − 2·MARGIN` of the viewport on its limiting side.
    pub fn pixels_per_unit(&self, width: u32, height: u32) -> f64 {
        let usable = 1.0 - 2.0 * Self::MARGIN;
        let fit = |pixels: u32, half: f64| {
            if half > 0.0 {
                f64::from(pixels) * usable / (2.0 * half)
            } else {
                f64::INFINITY
            }
        };
        fit(width, self.half_width).min(fit(height, self.half_height))
    }

    /// Where `p` lands in a `width × height` viewport: `(x, y, depth)` with `x` to the right and
    /// `y` down in pixels from the viewport's top-left corner (pixel `(i, j)` has its centre at
    /// `(i + 0.5, j + 0.5)`), and `depth` the distance along the view direction from the framed
    /// centre in world units (smaller is nearer).
    pub fn project(&self, p: Vec3, width: u32, height: u32) -> DVec3 {
        let s = self.pixels_per_unit(width, height);
        self.projector(width, height, s).apply(p)
    }

    pub(crate) fn projector(&self, width: u32, height: u32, scale: f64) -> Projector {
        Projector {
            center: self.center,
            cx: 0.5 * f64::from(width),
            cy: 0.5 * f64::from(height),
            right: self.right * scale,
            up: self.up * scale,
            direction: self.direction,
        }
    }
}

/// A camera specialised to one viewport size.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Projector {
    center: DVec3,
    cx: f64,
    cy: f64,
    right: DVec3,
    up: DVec3,
    direction: DVec3,
}

impl Projector {
    #[inline]
    pub(crate) fn apply(&self, p: Vec3) -> DVec3 {
        let q = p.as_dvec3() - self.center;
        DVec3::new(
            self.cx + q.dot(self.right),
            self.cy - q.dot(self.up),
            q.dot(self.direction),
        )
    }
}

/// Which way to look at a surface; [`View::camera`] turns it into a [`Camera`].
///
/// Both standard views start from the reference surface's mean normal `n` (the normalised sum
/// of its triangles' area vectors; `+z` if that sum vanishes, as for a closed surface) and a
/// screen-up vector `u`: world `+z` projected perpendicular to `n`, or world `+y` if `n` is
/// within about 25° of `±z` (a skin patch lying in the `xy` plane gets `u = +y`).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum View {
    /// Head-on from outside: looking along `−n`, screen up `u`. Shows the field's layout
    /// without distortion, but hides height.
    Front,
    /// A three-quarter view, the default: the eye is raised 40° above the surface's mean plane,
    /// in front of it (towards `−u`) and turned 30° to the right, and the surface normal points
    /// up on screen. Shows a bump's height by its outline and shading.
    #[default]
    Oblique,
    /// An explicit direction (from the eye into the scene) and up vector.
    Along {
        /// View direction.
        direction: Vec3,
        /// Up vector (projected perpendicular to `direction`).
        up: Vec3,
    },
}

impl View {
    /// Elevation of the [`View::Oblique`] eye above the mean plane, degrees.
    pub const OBLIQUE_ELEVATION_DEG: f64 = 40.0;
    /// Azimuth of the [`View::Oblique`] eye from straight in front, degrees.
    pub const OBLIQUE_AZIMUTH_DEG: f64 = 30.0;

    /// The camera for this view of `reference` (whose mean normal sets the standard views),
    /// framing `bounds` (e.g. the union of the before and after boxes).
    ///
    /// # Errors
    /// As [`Camera::orthographic`] (only possible for bad `bounds` or a bad [`View::Along`]).
    pub fn camera(&self, reference: &TriMesh, bounds: Aabb) -> Result<Camera, RenderError> {
        let (direction, up) = match *self {
            View::Along { direction, up } => (direction.as_dvec3(), up.as_dvec3()),
            View::Front => {
                let (n, u) = normal_and_up(reference);
                (-n, u)
            }
            View::Oblique => {
                let (n, u) = normal_and_up(reference);
                let r = (-n).cross(u);
                let (el, az) = (
                    Self::OBLIQUE_ELEVATION_DEG.to_radians(),
                    Self::OBLIQUE_AZIMUTH_DEG.to_radians(),
                );
                let horizontal = -u * az.cos() + r * az.sin();
                let eye = n * el.sin() + horizontal * el.cos();
                (-eye, n)
            }
        };
        Camera::orthographic(bounds, direction.as_vec3(), up.as_vec3())
    }
}

/// Mean normal and screen-up of a surface, in `f64`.
fn normal_and_up(mesh: &TriMesh) -> (DVec3, DVec3) {
    let mut sum = DVec3::ZERO;
    let mut total = 0.0;
    for t in 0..mesh.triangle_count() {
        let [a, b, c] = mesh.corners(t).map(|p| p.as_dvec3());
        let v = (b - a).cross(c - a);
        sum += v;
        total += v.length();
    }
    let n = if sum.length() > 1e-6 * total {
        sum.normalize()
    } else {
        DVec3::Z
    };
    let world_up = if n.z.abs() < 0.9 { DVec3::Z } else { DVec3::Y };
    let u = (world_up - n * n.dot(world_up)).normalize();
    (n, u)
}
