//! Kinematic tools: a capsule (needle, instrument shaft) and a thick triangle (scalpel blade),
//! each a *core* (segment or triangle) inflated by a radius, with a pose the host moves between
//! steps.
//!
//! A step sweeps each tool from the pose of the previous step to the one set since: for a node
//! moving from `x` to its prediction `p`, the relative path is taken as the straight line from
//! `x` in the old tool frame to `p` in the new one. The distance from a point moving on a line
//! to a convex core is a convex function of time, so its minimum is found by ternary search and
//! the first time the path enters the inflated tool by bisection: a tool that crosses a thin
//! part within one step still finds the side each node came from, and pushes it out there.
//! Contacts are per node: a tissue edge or face can pass through a tool thinner than the node
//! spacing without any node touching it.

use glam::{Quat, Vec3, Vec3A};

use crate::geometry::{closest_point_on_segment, closest_point_on_triangle};
use crate::PbdError;

/// A rigid placement: `world = rotation · local + translation` (cm).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pose {
    /// Rotation from the tool's frame to the world's.
    pub rotation: Quat,
    /// Position of the tool frame's origin (cm).
    pub translation: Vec3,
}

impl Default for Pose {
    fn default() -> Self {
        Self::IDENTITY
    }
}

impl Pose {
    /// No rotation, no translation.
    pub const IDENTITY: Pose = Pose {
        rotation: Quat::IDENTITY,
        translation: Vec3::ZERO,
    };

    /// A pure translation.
    pub fn from_translation(translation: Vec3) -> Self {
        Self {
            rotation: Quat::IDENTITY,
            translation,
        }
    }

    /// A rotation followed by a translation.
    pub fn new(rotation: Quat, translation: Vec3) -> Self {
        Self {
            rotation,
            translation,
        }
    }

    /// Local point to world.
    pub fn transform_point(&self, local: Vec3) -> Vec3 {
        self.rotation * local + self.translation
    }

    /// World point to local.
    pub fn inverse_transform_point(&self, world: Vec3) -> Vec3 {
        self.rotation.inverse() * (world - self.translation)
    }

    fn is_valid(&self) -> bool {
        self.translation.is_finite()
            && self.rotation.is_finite()
            && (self.rotation.length() - 1.0).abs() < 1e-3
    }
}

/// A tool's shape in its own frame (cm).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ToolShape {
    /// The points within `radius` of the segment `a–b`: a needle or an instrument's shaft.
    Capsule {
        /// One end of the axis.
        a: Vec3,
        /// The other end.
        b: Vec3,
        /// Radius (cm), `> 0`.
        radius: f32,
    },
    /// The points within `thickness / 2` of the triangle `a b c`: a scalpel blade.
    Blade {
        /// A corner.
        a: Vec3,
        /// A corner.
        b: Vec3,
        /// A corner.
        c: Vec3,
        /// Full thickness (cm), `> 0`.
        thickness: f32,
    },
}

impl ToolShape {
    pub(crate) fn validate(&self) -> Result<(), PbdError> {
        match *self {
            ToolShape::Capsule { a, b, radius } => {
                if !(a.is_finite() && b.is_finite()) {
                    return Err(PbdError::InvalidTool {
                        reason: "the capsule's ends must be finite",
                    });
                }
                if !(radius.is_finite() && radius > 0.0) {
                    return Err(PbdError::InvalidTool {
                        reason: "the capsule's radius must be finite and > 0 (cm)",
                    });
                }
            }
            ToolShape::Blade { a, b, c, thickness } => {
                if !(a.is_finite() && b.is_finite() && c.is_finite()) {
                    return Err(PbdError::InvalidTool {
                        reason: "the blade's corners must be finite",
                    });
                }
                if !(thickness.is_finite() && thickness > 0.0) {
                    return Err(PbdError::InvalidTool {
                        reason: "the blade's thickness must be finite and > 0 (cm)",
                    });
                }
                let longest = (b - a).length().max((c - b).length()).max((a - c).length());
                if (b - a).cross(c - a).length() <= 1e-6 * longest * longest {
                    return Err(PbdError::InvalidTool {
                        reason: "the blade's triangle is degenerate (its corners are collinear)",
                    });
                }
            }
        }
        Ok(())
    }

    /// The radius by which the core is inflated.
    pub fn radius(&self) -> f32 {
        match *self {
            ToolShape::Capsule { radius, .. } => radius,
            ToolShape::Blade { thickness, .. } => thickness * 0.5,
        }
    }

    /// The point of the core (axis segment or blade triangle) closest to `p`, in the tool frame.
    pub fn closest_core_point(&self, p: Vec3) -> Vec3 {
        self.core(p.into()).into()
    }

    /// Signed distance from `p` (tool frame) to the tool's surface (negative inside).
    pub fn signed_distance(&self, p: Vec3) -> f32 {
        p.distance(self.closest_core_point(p)) - self.radius()
    }

    #[inline]
    fn core(&self, p: Vec3A) -> Vec3A {
        match *self {
            ToolShape::Capsule { a, b, .. } => closest_point_on_segment(p, a.into(), b.into()),
            ToolShape::Blade { a, b, c, .. } => {
                closest_point_on_triangle(p, a.into(), b.into(), c.into())
            }
        }
    }

    /// The local bounding box of the core, `(min, max)`.
    fn core_bounds(&self) -> (Vec3, Vec3) {
        match *self {
            ToolShape::Capsule { a, b, .. } => (a.min(b), a.max(b)),
            ToolShape::Blade { a, b, c, .. } => (a.min(b).min(c), a.max(b).max(c)),
        }
    }

    /// A normal to use when a point lies on the core itself: the blade's face normal, or any
    /// direction perpendicular to the capsule's axis.
    fn fallback_normal(&self) -> Vec3A {
        match *self {
            ToolShape::Capsule { a, b, .. } => {
                let d = (b - a).normalize_or(Vec3::X);
                Vec3A::from(d.any_orthonormal_vector())
            }
            ToolShape::Blade { a, b, c, .. } => Vec3A::from((b - a).cross(c - a).normalize()),
        }
    }
}

/// A kinematic tool in a body's scene: its shape, the pose set by the host, and where the next
/// step's sweep starts.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Tool {
    pub(crate) shape: ToolShape,
    /// The pose set by the host (the end of the next sweep).
    pub(crate) pose: Pose,
    /// The pose at the end of the last step (the start of the next sweep).
    pub(crate) start: Pose,
    /// The sweep of the last step, `(from, to)`.
    pub(crate) last_sweep: (Pose, Pose),
}

impl Tool {
    pub(crate) fn new(shape: ToolShape, pose: Pose) -> Result<Self, PbdError> {
        shape.validate()?;
        check_pose(&pose)?;
        Ok(Self {
            shape,
            pose,
            start: pose,
            last_sweep: (pose, pose),
        })
    }
    /// The shape, in the tool's frame.
    pub fn shape(&self) -> &ToolShape {
        &self.shape
    }
    /// The pose set by the host (where the next step moves the tool to).
    pub fn pose(&self) -> Pose {
        self.pose
    }
    /// The pose at the end of the last step (where the next step's sweep starts).
    pub fn start_pose(&self) -> Pose {
        self.start
    }
    /// The sweep of the last step, `(from, to)`: what a cutting step needs to find the surface
    /// triangles the blade crossed.
    pub fn last_sweep(&self) -> (Pose, Pose) {
        self.last_sweep
    }

    /// Signed distance from a world point to the tool at its current pose (cm, negative inside).
    pub fn signed_distance(&self, point: Vec3) -> f32 {
        self.shape
            .signed_distance(self.pose.inverse_transform_point(point))
    }

    /// The world bounding box of the tool inflated by `extra`, over the sweep from `from` to
    /// `to` (both poses' boxes; the straight-line motion between them stays inside when the
    /// rotation between the poses is small).
    pub(crate) fn swept_bounds(&self, from: &Pose, to: &Pose, extra: f32) -> (Vec3A, Vec3A) {
        let (lo, hi) = self.shape.core_bounds();
        let r = self.shape.radius() + extra;
        let mut min = Vec3A::splat(f32::INFINITY);
        let mut max = Vec3A::splat(f32::NEG_INFINITY);
        for pose in [from, to] {
            for corner in 0..8 {
                let c = Vec3::new(
                    if corner & 1 == 0 { lo.x } else { hi.x },
                    if corner & 2 == 0 { lo.y } else { hi.y },
                    if corner & 4 == 0 { lo.z } else { hi.z },
                );
                let w = Vec3A::from(pose.transform_point(c));
                min = min.min(w);
                max = max.max(w);
            }
        }
        (min - Vec3A::splat(r), max + Vec3A::splat(r))
    }
}

pub(crate) fn check_pose(pose: &Pose) -> Result<(), PbdError> {
    if pose.is_valid() {
        Ok(())
    } else {
        Err(PbdError::InvalidTool {
            reason: "the pose must have a finite translation and a unit-quaternion rotation",
        })
    }
}

/// Where a node's swept path meets a tool: the contact plane in the end pose's world frame.
#[derive(Debug, Clone, Copy)]
pub(crate) struct ToolHit {
    /// Outward unit normal (world).
    pub normal: Vec3A,
    /// A point of the tool's surface on the contact plane (world, end pose).
    pub point: Vec3A,
    /// How far that surface point moved during the step (world).
    pub motion: Vec3A,
}

/// Ternary-search iterations for the closest approach (the interval shrinks to `(2/3)^n`).
const TERNARY: usize = 24;
/// Bisection iterations for the first entry.
const BISECT: usize = 20;

/// The contact of a node moving from `x` to `p` with a tool swept from `from` to `to`, when the
/// relative path comes within `radius + reach` of the core. `reach` ≥ 0 is the contact margin
/// plus the detection distance.
pub(crate) fn sweep_node(
    shape: &ToolShape,
    from: &Pose,
    to: &Pose,
    x: Vec3A,
    p: Vec3A,
    reach: f32,
) -> Option<ToolHit> {
    let (inv0, inv1) = (from.rotation.inverse(), to.rotation.inverse());
    let l0 = Vec3A::from(inv0 * (Vec3::from(x) - from.translation));
    let l1 = Vec3A::from(inv1 * (Vec3::from(p) - to.translation));
    let r = shape.radius();
    let big = r + reach;
    let d = l1 - l0;
    let f = |t: f32| {
        let q = l0 + t * d;
        q.distance(shape.core(q)) - big
    };
    let (normal, core_point) = if f(0.0) <= 0.0 {
        // Started in contact: keep the side of the start unless the end is clearly on it too.
        let (c0, c1) = (shape.core(l0), shape.core(l1));
        let (n0, n1) = (l0 - c0, l1 - c1);
        if n1.dot(n0) > 0.0 && n1.length_squared() > 1e-12 {
            (n1.normalize(), c1)
        } else if n0.length_squared() > 1e-12 {
            (n0.normalize(), c1)
        } else {
            (shape.fallback_normal(), c1)
        }
    } else {
        // Closest approach on [0, 1] (f is convex), then the first entry before it.
        let (mut a, mut b) = (0.0f32, 1.0f32);
        for _ in 0..TERNARY {
            let m1 = a + (b - a) / 3.0;
            let m2 = b - (b - a) / 3.0;
            if f(m1) <= f(m2) {
                b = m2;
            } else {
                a = m1;
            }
        }
        let t_min = 0.5 * (a + b);
        let t_min = if f(1.0) <= f(t_min) { 1.0 } else { t_min };
        if f(t_min) > 0.0 {
            return None;
        }
        let (mut a, mut b) = (0.0f32, t_min);
        for _ in 0..BISECT {
            let m = 0.5 * (a + b);
            if f(m) > 0.0 {
                a = m;
            } else {
                b = m;
            }
        }
        let e = l0 + b * d;
        let ce = shape.core(e);
        let ne = e - ce;
        let ne = if ne.length_squared() > 1e-12 {
            ne.normalize()
        } else {
            let n = shape.fallback_normal();
            if n.dot(-d) >= 0.0 {
                n
            } else {
                -n
            }
        };
        let c1 = shape.core(l1);
        let n1 = l1 - c1;
        if n1.dot(ne) > 0.0 && n1.length_squared() > 1e-12 {
            // The end is still on the entry side: use the end state (sliding, resting).
            (n1.normalize(), c1)
        } else {
            (ne, ce)
        }
    };
    // The plane through the surface point with this normal; for the flat side of a blade or the
    // cylinder of a capsule that is the tangent plane, which lies outside the convex tool.
    let local_point = core_point + normal * r;
    let point = Vec3A::from(to.transform_point(local_point.into()));
    let before = Vec3A::from(from.transform_point(local_point.into()));
    Some(ToolHit {
        normal: Vec3A::from(to.rotation * Vec3::from(normal)),
        point,
        motion: point - before,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_fast_blade_finds_the_side_a_node_came_from() {
        let blade = ToolShape::Blade {
            a: Vec3::new(-2.0, 0.0, -2.0),
            b: Vec3::new(2.0, 0.0, -2.0),
            c: Vec3::new(0.0, 0.0, 3.0),
            thickness: 0.1,
        };
        // The blade drops 4 cm through a node at rest at the origin.
        let from = Pose::from_translation(Vec3::new(0.0, 2.0, 0.0));
        let to = Pose::from_translation(Vec3::new(0.0, -2.0, 0.0));
        let hit = sweep_node(&blade, &from, &to, Vec3A::ZERO, Vec3A::ZERO, 0.0)
            .unwrap_or_else(|| panic!("missed"));
        assert!(hit.normal.distance(-Vec3A::Y) < 1e-5, "{}", hit.normal);
        assert!((hit.point.y + 2.05).abs() < 1e-5, "{}", hit.point);
        assert!((hit.motion.y + 4.0).abs() < 1e-5);
        // Far to the side it misses.
        assert!(sweep_node(
            &blade,
            &from,
            &to,
            Vec3A::new(5.0, 0.0, 0.0),
            Vec3A::new(5.0, 0.0, 0.0),
            0.0
        )
        .is_none());
    }

    #[test]
    fn a_resting_node_next_to_a_capsule_gets_the_radial_normal() {
        let cap = ToolShape::Capsule {
            a: Vec3::new(0.0, 0.0, -1.0),
            b: Vec3::new(0.0, 0.0, 1.0),
            radius: 0.5,
        };
        let pose = Pose::IDENTITY;
        let x = Vec3A::new(0.3, 0.3, 0.0);
        let hit = sweep_node(&cap, &pose, &pose, x, x, 0.0).unwrap_or_else(|| panic!("missed"));
        let n = Vec3A::new(1.0, 1.0, 0.0).normalize();
        assert!(hit.normal.distance(n) < 1e-5);
        assert!((hit.point.length() - 0.5).abs() < 1e-5);
        assert!(sweep_node(
            &cap,
            &pose,
            &pose,
            Vec3A::new(0.6, 0.0, 0.0),
            Vec3A::new(0.6, 0.0, 0.0),
            0.05
        )
        .is_none());
    }
}
