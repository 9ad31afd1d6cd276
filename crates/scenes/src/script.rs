//! Scripted runs: what a scenario does around each solver step. The same scripts drive the
//! headless `trainer`, the studio's demonstrations ([`crate::Session::play`]) and the tests, so
//! a scenario is written once.
//!
//! A [`Script`] is stepped by its host: [`Script::before_step`] (attachments and tools moved),
//! the solver's step, [`Script::after_step`] (cuts and sutures). The host owns the clock, the
//! timing and the output.
//!
//! - [`AppendixProcedure`]: on the shipped appendix ([`crate::ShippedOrgan::Appendix`]): the tip
//!   lifted by a grasper while the organ settles, an incision near the base, the tip cut off
//!   (held by the grasper until the blade is through, then let go: it falls), the incision
//!   sutured with three stitches.
//! - [`PressAndDrag`]: a probe (a capsule tool already in the body) settles above the organ,
//!   presses down to a depth below its top and drags along waypoints.

use glam::{Quat, Vec3, Vec3A};
use tissue_pbd::{AttachmentId, ContactParams, Pose, SoftBody, StepSettings, ToolShape};
use tissue_surgery::{BladeSweep, Surgery, SurgeryEvent};

use crate::error::SceneError;

/// The appendix's tip: its nodes beyond this x (cm), the last 0.3 cm, are grasped.
const TIP_FROM_X: f32 = 3.7;

/// What a script did after one step.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ScriptStep {
    /// What the surgery reported (cuts, pieces, sutures), in order.
    pub events: Vec<SurgeryEvent>,
    /// Whether a blade sweep was cut in this step.
    pub cut: bool,
}

/// A scenario run step by step by a host that owns the solver's step.
pub trait Script {
    /// The solver steps the script takes.
    fn steps(&self) -> usize;

    /// Before step `k` (1 to [`Script::steps`]): moves attachments and tools.
    ///
    /// # Errors
    /// [`SceneError`] when the solver refuses a target or the scenario cannot go on (a probe
    /// path that is not over the organ).
    fn before_step(&mut self, k: usize, body: &mut SoftBody) -> Result<(), SceneError>;

    /// After step `k`: cuts and sutures.
    ///
    /// # Errors
    /// [`SceneError::Surgery`] when a cut or a suture fails.
    fn after_step(
        &mut self,
        k: usize,
        body: &mut SoftBody,
        surgery: &mut Surgery,
    ) -> Result<ScriptStep, SceneError>;
}

/// The appendix procedure's timeline (steps) and places (cm, the shipped appendix's frame: its
/// base at x = −4 pinned below [`crate::APPENDIX_BASE_X`], its underside on the abdominal wall y = 0,
/// its top at y = 2).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AppendixPlan {
    /// Steps while the organ settles and the grasper lifts the tip.
    pub settle: usize,
    /// Steps of the incision near the base (a partial cut across the organ).
    pub incise: usize,
    /// Steps of the cut-off (the wide blade drawn down through the whole organ).
    pub cutoff: usize,
    /// The step at which the incision is sutured.
    pub suture_at: usize,
    /// The script's length (steps).
    pub total: usize,
    /// How high the grasper lifts the tip (cm), over the first half of the settling.
    pub lift: f32,
    /// Where the incision is (x, cm) and how deep below the top (cm).
    pub incision: (f32, f32),
    /// Where the tip is cut off (x, cm).
    pub cutoff_x: f32,
    /// The cut-off blade's height (y of its edge, cm) at its start and its end: from above the
    /// lifted tip to below the abdominal wall.
    pub cutoff_from_to: (f32, f32),
    /// Depths below the top (cm) the needle tries, in order, until it crosses the wound.
    pub needle_depths: [f32; 4],
}

impl Default for AppendixPlan {
    fn default() -> Self {
        AppendixPlan {
            settle: 60,
            incise: 20,
            cutoff: 30,
            suture_at: 140,
            total: 200,
            lift: 1.5,
            incision: (-2.45, 0.8),
            cutoff_x: 2.05,
            cutoff_from_to: (4.0, -1.0),
            // The studio's needle depth first, then shallower and deeper.
            needle_depths: [0.35, 0.21, 0.56, 0.84],
        }
    }
}

/// The appendix procedure ([`AppendixPlan`]): grasp and lift, incise, cut off, suture.
#[derive(Debug, Clone)]
pub struct AppendixProcedure {
    plan: AppendixPlan,
    /// The grasped tip nodes: (node, its position when grasped, attachment).
    grasp: Vec<(u32, Vec3, AttachmentId)>,
    scalpel: ToolShape,
    wide: ToolShape,
    /// The blade's pose at the previous step (a sweep needs two).
    last_pose: Option<Pose>,
    /// The blade's pose at this step.
    pose: Option<Pose>,
}

impl AppendixProcedure {
    /// The procedure on `body` (the shipped appendix as [`crate::Organ::body`] made it): the
    /// grasper takes the tip's top nodes (x > 3.7 cm, within 0.1 cm of the top).
    ///
    /// # Errors
    /// [`SceneError::Tool`] when the body has no such nodes (not the appendix);
    /// [`SceneError::Pbd`] when an attachment is refused.
    pub fn new(body: &mut SoftBody, plan: AppendixPlan) -> Result<AppendixProcedure, SceneError> {
        let top = body
            .positions()
            .iter()
            .map(|p| p.y)
            .fold(f32::NEG_INFINITY, f32::max);
        let tip: Vec<u32> = (0..body.node_count() as u32)
            .filter(|&i| {
                let p = body.positions()[i as usize];
                p.x > TIP_FROM_X && p.y > top - 0.1
            })
            .collect();
        if tip.is_empty() {
            return Err(SceneError::Tool(
                "the appendix procedure needs the shipped appendix (8 × 2 × 2 cm, base at x = −4 \
                 cm): this body has no tip beyond x = 3.7 cm"
                    .to_owned(),
            ));
        }
        let mut grasp = Vec::with_capacity(tip.len());
        for i in tip {
            let p = Vec3::from(body.positions()[i as usize]);
            grasp.push((i, p, body.attach(i, p)?));
        }
        Ok(AppendixProcedure {
            plan,
            grasp,
            scalpel: ToolShape::Blade {
                a: Vec3::new(0.0, 0.0, -0.4),
                b: Vec3::new(0.0, 0.0, 0.4),
                c: Vec3::new(0.0, 3.0, 0.0),
                thickness: 0.02,
            },
            wide: ToolShape::Blade {
                a: Vec3::new(0.0, 0.0, -2.0),
                b: Vec3::new(0.0, 0.0, 2.0),
                c: Vec3::new(0.0, 4.0, 0.0),
                thickness: 0.02,
            },
            last_pose: None,
            pose: None,
        })
    }

    /// Its plan.
    pub fn plan(&self) -> &AppendixPlan {
        &self.plan
    }

    /// The blade's pose for step `k`, relative to the sagging organ (found on its nodes).
    fn blade_pose(&self, k: usize, body: &SoftBody) -> Option<Pose> {
        let p = &self.plan;
        let incision_end = p.settle + p.incise;
        if k > p.settle && k <= incision_end {
            // Near the base, `incision.1` below the top, drawn across z.
            let s = (k - p.settle) as f32 / p.incise as f32;
            let (x, depth) = p.incision;
            let top = top_near(body, x);
            Some(Pose::new(
                Quat::IDENTITY,
                Vec3::new(x, top - depth, -1.4 + 2.8 * s),
            ))
        } else if k > incision_end && k <= incision_end + p.cutoff {
            let s = (k - incision_end) as f32 / p.cutoff as f32;
            let (from, to) = p.cutoff_from_to;
            Some(Pose::new(
                Quat::IDENTITY,
                Vec3::new(p.cutoff_x, from + (to - from) * s, 0.0),
            ))
        } else {
            None
        }
    }

    /// Three stitches across the incision, needles along x, each at the first depth that
    /// crosses the wound.
    fn suture(
        &self,
        body: &mut SoftBody,
        surgery: &mut Surgery,
        events: &mut Vec<SurgeryEvent>,
    ) -> Result<(), SceneError> {
        let x = self.plan.incision.0;
        let needle = ToolShape::Capsule {
            a: Vec3::new(-0.6, 0.0, 0.0),
            b: Vec3::new(0.6, 0.0, 0.0),
            radius: 0.02,
        };
        for z in [-0.6f32, 0.0, 0.6] {
            let top = top_near(body, x);
            for depth in self.plan.needle_depths {
                let at = Pose::from_translation(Vec3::new(x, top - depth, z + 0.05));
                if let Some(e) = surgery.suture(body, &needle, &at)? {
                    events.push(e);
                    break;
                }
            }
        }
        Ok(())
    }
}

impl Script for AppendixProcedure {
    fn steps(&self) -> usize {
        self.plan.total
    }

    fn before_step(&mut self, k: usize, body: &mut SoftBody) -> Result<(), SceneError> {
        let p = self.plan;
        let cutoff_start = p.settle + p.incise + 1;
        if k <= p.settle {
            let lift = p.lift * (k as f32 / (p.settle as f32 * 0.5)).min(1.0);
            for &(_, at, id) in &self.grasp {
                body.set_attachment_target(id, at + Vec3::new(0.0, lift, 0.0))?;
            }
        } else if k == cutoff_start {
            // A new blade: its first pose starts a new sweep (not one from where the scalpel
            // ended, 4.5 cm away).
            self.last_pose = None;
        } else if k == cutoff_start + p.cutoff {
            // The grasper lets go once the blade is through: the tip held still while it is
            // cut comes off wherever the blade crosses (x = 1.95 … 2.15 cm, with or without
            // self-collision, `tests/it/selfcol.rs`); let go as the blade came down, the tip
            // fell while it was cut and stayed on at two planes of five.
            for &(i, _, _) in &self.grasp {
                body.unpin(i)?;
            }
        }
        self.pose = self.blade_pose(k, body);
        Ok(())
    }

    fn after_step(
        &mut self,
        k: usize,
        body: &mut SoftBody,
        surgery: &mut Surgery,
    ) -> Result<ScriptStep, SceneError> {
        let mut out = ScriptStep::default();
        if let (Some(to), Some(from)) = (self.pose, self.last_pose) {
            let blade = if k > self.plan.settle + self.plan.incise {
                &self.wide
            } else {
                &self.scalpel
            };
            let sweep = BladeSweep::new(blade, &from, &to)?;
            out.events = surgery.cut(body, &sweep)?;
            out.cut = true;
        }
        if k == self.plan.suture_at {
            self.suture(body, surgery, &mut out.events)?;
        }
        self.last_pose = self.pose;
        Ok(out)
    }
}

/// The highest node y within 0.3 cm of `x` on the organ's midline (its top there).
fn top_near(body: &SoftBody, x: f32) -> f32 {
    body.positions()
        .iter()
        .filter(|p| (p.x - x).abs() < 0.3 && p.z.abs() < 0.3)
        .map(|p| p.y)
        .fold(f32::NEG_INFINITY, f32::max)
        .max(-10.0)
}

/// The press-and-drag run's timeline (steps), probe and path (cm). [`PressPlan::default`] is the
/// run the studio's demonstration on a tray plays and the headless `trainer`'s defaults.
#[derive(Debug, Clone, PartialEq)]
pub struct PressPlan {
    /// Steps while the organ settles (the probe parked above), every motion damped with
    /// [`SETTLE_RELAXATION_TIME`] so that it comes to rest.
    pub settle: usize,
    /// Steps of the press, from 0.5 cm above the top to `depth` below it.
    pub press: usize,
    /// Steps of the drag along the waypoints at that height.
    pub drag: usize,
    /// How deep below the organ's top the probe's tip goes (cm).
    pub depth: f32,
    /// The probe's radius (cm): a capsule as long as the organ, its tip at the local origin,
    /// its axis +y.
    pub radius: f32,
    /// The drag's path (x, z), two points or more; the press is over the first. Empty: across
    /// the organ along its longest horizontal extent, from −¼ to +¼ of it
    /// ([`PressPlan::path_over`]).
    pub waypoints: Vec<[f32; 2]>,
    /// Horizontal radius within which the organ's top is looked for (cm);
    /// [`PressAndDrag::on_tray`] widens it to the body's mean tet edge when that is longer.
    pub reach: f32,
}

impl Default for PressPlan {
    /// Settle 100 steps (1 s: the organ comes to rest on the tray before the probe touches
    /// it), press 50, drag 100; 1.5 cm deep with a 0.4 cm probe, across the organ, its top
    /// looked for within 1 cm.
    fn default() -> Self {
        PressPlan {
            settle: 100,
            press: 50,
            drag: 100,
            depth: 1.5,
            radius: 0.4,
            waypoints: Vec::new(),
            reach: 1.0,
        }
    }
}

impl PressPlan {
    /// The steps of the whole run: settle, press and drag.
    pub fn steps(&self) -> usize {
        self.settle + self.press + self.drag
    }

    /// The drag's path on an organ of largest extent `extent` (cm) whose nodes are at
    /// `positions` (y up): the waypoints given, or, when there are none, across the organ
    /// along its longest horizontal extent, through the horizontal centroid of its nodes, from
    /// −¼ to +¼ of the extent. The longest extent is the principal axis of the nodes' (x, z)
    /// spread; an organ as wide one way as the other (within 20 % in variance) is crossed
    /// along x. Each end of the path that has no node within `reach` (cm, horizontally: a
    /// curved organ whose centroid is off it) is moved to the nearest node, so the press
    /// starts over the organ whatever its shape and orientation.
    pub fn path_over(&self, extent: f32, positions: &[Vec3A], reach: f32) -> Vec<[f32; 2]> {
        if !self.waypoints.is_empty() {
            return self.waypoints.clone();
        }
        let n = positions.len().max(1) as f64;
        let (cx, cz) = positions.iter().fold((0.0, 0.0), |(x, z), p| {
            (x + f64::from(p.x) / n, z + f64::from(p.z) / n)
        });
        let (mut sxx, mut szz, mut sxz) = (0.0f64, 0.0f64, 0.0f64);
        for p in positions {
            let (dx, dz) = (f64::from(p.x) - cx, f64::from(p.z) - cz);
            sxx += dx * dx;
            szz += dz * dz;
            sxz += dx * dz;
        }
        // The principal axis of [[sxx, sxz], [sxz, szz]] and how anisotropic the spread is.
        let mean = 0.5 * (sxx + szz);
        let spread = (0.25 * (sxx - szz).powi(2) + sxz * sxz).sqrt();
        let (large, small) = (mean + spread, mean - spread);
        let axis = if large > 1.2 * small.max(0.0) && spread > 0.0 {
            let angle = 0.5 * (2.0 * sxz).atan2(sxx - szz);
            [angle.cos(), angle.sin()]
        } else {
            [1.0, 0.0]
        };
        let reach = f64::from(reach);
        let over = |x: f64, z: f64| -> [f32; 2] {
            let near = positions
                .iter()
                .map(|p| ((f64::from(p.x) - x).hypot(f64::from(p.z) - z), p))
                .min_by(|a, b| a.0.total_cmp(&b.0));
            match near {
                Some((d, p)) if d > reach => [p.x, p.z],
                _ => [x as f32, z as f32],
            }
        };
        let half = 0.25 * f64::from(extent);
        vec![
            over(cx - half * axis[0], cz - half * axis[1]),
            over(cx + half * axis[0], cz + half * axis[1]),
        ]
    }
}

/// A probe pressed into the organ and dragged ([`PressPlan`]); the probe is a capsule tool of
/// the body with its tip at the local origin and its axis +y.
#[derive(Debug, Clone)]
pub struct PressAndDrag {
    plan: PressPlan,
    tool: usize,
    /// The press's start and end (the tip, cm), known once the organ has settled.
    start: Vec3,
    end: Vec3,
    /// The body's plain velocity damping before the settling raised it (restored after it).
    damping: Option<f32>,
}

/// The relaxation time (s) of the plain velocity damping that brings the organ to rest while it
/// settles ([`PressAndDrag`]): the rigid-mode damping of the step settings keeps the organ's
/// centre-of-mass motion, and the bounce of an organ set down on its tray carries some, so
/// without it a 10 cm box at 10 kPa still swung ±0.06 cm at its top after the default 1 s (its
/// top read 0.06 cm low, each press went that much deeper than planned and the probe's force
/// came out 27 % high at 0.25 cm). A static state is the same with or without damping.
pub const SETTLE_RELAXATION_TIME: f32 = 0.05;

impl PressAndDrag {
    /// The run of tool `tool` (a capsule of [`PressPlan::radius`], already in the body) along
    /// `plan`, whose waypoints must be given (see [`PressPlan::path_over`]).
    ///
    /// # Errors
    /// [`SceneError::Tool`] when the plan has fewer than two waypoints, a negative or
    /// non-finite depth, or a reach that is not positive.
    pub fn new(tool: usize, plan: PressPlan) -> Result<PressAndDrag, SceneError> {
        if plan.waypoints.len() < 2 {
            return Err(SceneError::Tool(format!(
                "a drag path needs two or more waypoints, not {}",
                plan.waypoints.len()
            )));
        }
        if !(plan.depth.is_finite() && plan.depth >= 0.0) {
            return Err(SceneError::Tool(format!(
                "a press depth of {} cm: give a depth ≥ 0",
                plan.depth
            )));
        }
        if !(plan.reach.is_finite() && plan.reach > 0.0) {
            return Err(SceneError::Tool(format!(
                "a reach of {} cm: give a positive radius",
                plan.reach
            )));
        }
        Ok(PressAndDrag {
            plan,
            tool,
            start: Vec3::ZERO,
            end: Vec3::ZERO,
            damping: None,
        })
    }

    /// The press-and-drag set-up on an organ of largest extent `extent` (cm) lying on its tray:
    /// adds the probe to `body` (a capsule of [`PressPlan::radius`] as long as the organ, with
    /// `contact`'s friction), parks it ([`PressAndDrag::parked`]) and plans its run: the path
    /// of [`PressPlan::path_over`], the top looked for within the plan's reach or the body's mean tet
    /// edge, whichever is longer. The probe's id is [`PressAndDrag::tool`].
    ///
    /// # Errors
    /// [`SceneError::Pbd`] when the solver refuses the probe (a radius that is not positive,
    /// bad contact parameters); [`SceneError::Tool`] as [`PressAndDrag::new`].
    pub fn on_tray(
        body: &mut SoftBody,
        extent: f32,
        plan: PressPlan,
        contact: ContactParams,
    ) -> Result<PressAndDrag, SceneError> {
        let probe = ToolShape::Capsule {
            a: Vec3::ZERO,
            b: Vec3::new(0.0, extent, 0.0),
            radius: plan.radius,
        };
        let tool = body.add_tool(probe, PressAndDrag::parked(extent), contact)?;
        PressAndDrag::again(body, tool, extent, plan)
    }

    /// The run of `plan` with the probe `tool` that [`PressAndDrag::on_tray`] added before
    /// (a demonstration played again): parks it and plans the run as `on_tray` does.
    ///
    /// # Errors
    /// [`SceneError::Pbd`] for an unknown tool; [`SceneError::Tool`] as [`PressAndDrag::new`].
    pub fn again(
        body: &mut SoftBody,
        tool: usize,
        extent: f32,
        plan: PressPlan,
    ) -> Result<PressAndDrag, SceneError> {
        body.set_tool_pose(tool, PressAndDrag::parked(extent))?;
        let edges = body.distance_constraints();
        let mean_edge =
            edges.iter().map(|c| f64::from(c.rest_length)).sum::<f64>() / edges.len().max(1) as f64;
        let reach = plan.reach.max(mean_edge as f32);
        let plan = PressPlan {
            waypoints: plan.path_over(extent, body.positions(), reach),
            reach,
            ..plan
        };
        PressAndDrag::new(tool, plan)
    }

    /// Where the probe waits before and after its run: on the tray's centre line, three organ
    /// extents above the tray.
    pub fn parked(extent: f32) -> Pose {
        Pose::from_translation(Vec3::new(0.0, 3.0 * extent, 0.0))
    }

    /// Its plan.
    pub fn plan(&self) -> &PressPlan {
        &self.plan
    }

    /// The probe's tool id in the body.
    pub fn tool(&self) -> usize {
        self.tool
    }
}

impl Script for PressAndDrag {
    fn steps(&self) -> usize {
        self.plan.steps()
    }

    fn before_step(&mut self, k: usize, body: &mut SoftBody) -> Result<(), SceneError> {
        let p = &self.plan;
        if k == 1 && p.settle > 0 {
            // The settling brings the organ to rest: every motion damped with
            // `SETTLE_RELAXATION_TIME` (its centre of mass's too), the body's own damping back
            // before the press.
            let settings = *body.settings();
            let c = 1.0 - (-settings.dt / SETTLE_RELAXATION_TIME).exp();
            if c > settings.linear_damping {
                self.damping = Some(settings.linear_damping);
                body.set_settings(StepSettings {
                    linear_damping: c,
                    ..settings
                })?;
            }
        }
        if k == p.settle + 1 {
            end_settling(&mut self.damping, body)?;
            let xz = p.waypoints[0];
            let top = top_at(body, xz, p.reach).ok_or_else(|| {
                SceneError::Tool(format!(
                    "the first waypoint {},{} is not over the organ (no node within {:.1} cm \
                     of it); the organ is centred on x = z = 0",
                    xz[0], xz[1], p.reach
                ))
            })?;
            self.start = Vec3::new(xz[0], top + 0.5 + p.radius, xz[1]);
            self.end = Vec3::new(xz[0], top - p.depth + p.radius, xz[1]);
        }
        if k > p.settle {
            let tip = if k <= p.settle + p.press {
                self.start
                    .lerp(self.end, (k - p.settle) as f32 / p.press.max(1) as f32)
            } else {
                let s = (k - p.settle - p.press) as f32 / p.drag.max(1) as f32;
                along(&p.waypoints, s).map_or(self.end, |[x, z]| Vec3::new(x, self.end.y, z))
            };
            body.set_tool_pose(self.tool, Pose::from_translation(tip))?;
        }
        Ok(())
    }

    fn after_step(
        &mut self,
        k: usize,
        body: &mut SoftBody,
        _surgery: &mut Surgery,
    ) -> Result<ScriptStep, SceneError> {
        // A plan without press or drag ends with its settling: the body's damping back.
        if k >= self.steps() {
            end_settling(&mut self.damping, body)?;
        }
        Ok(ScriptStep::default())
    }
}

/// Gives the body back the plain velocity damping the settling raised (once: `damping` taken).
fn end_settling(damping: &mut Option<f32>, body: &mut SoftBody) -> Result<(), SceneError> {
    if let Some(linear_damping) = damping.take() {
        body.set_settings(StepSettings {
            linear_damping,
            ..*body.settings()
        })?;
    }
    Ok(())
}

/// Height of the organ's top under the point (x, z): the highest node within `reach`
/// horizontally.
pub fn top_at(body: &SoftBody, xz: [f32; 2], reach: f32) -> Option<f32> {
    body.positions()
        .iter()
        .filter(|p| (p.x - xz[0]).hypot(p.z - xz[1]) <= reach)
        .map(|p| p.y)
        .reduce(f32::max)
}

/// The point at fraction `s ∈ [0, 1]` of the polyline's length.
fn along(points: &[[f32; 2]], s: f32) -> Option<[f32; 2]> {
    let seg = |w: &[[f32; 2]]| (w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1]);
    let length: f32 = points.windows(2).map(seg).sum();
    if length <= 0.0 {
        return points.first().copied();
    }
    let mut left = s.clamp(0.0, 1.0) * length;
    for w in points.windows(2) {
        let l = seg(w);
        if left <= l && l > 0.0 {
            let f = left / l;
            return Some([
                w[0][0] + f * (w[1][0] - w[0][0]),
                w[0][1] + f * (w[1][1] - w[0][1]),
            ]);
        }
        left -= l;
    }
    points.last().copied()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The default path crosses an organ along its longest horizontal extent, through its
    /// centre: a slab long in z is crossed along z (the old default, along x, left its first
    /// point 1.5 cm off a 1 cm wide organ), a square one along x, and given waypoints stay.
    #[test]
    fn the_default_path_follows_the_organs_longest_extent() {
        let grid = |nx: i32, nz: i32, dx: f32, dz: f32| -> Vec<Vec3A> {
            (0..=nx)
                .flat_map(|i| {
                    (0..=nz).map(move |k| {
                        Vec3A::new(
                            (i as f32 / nx as f32 - 0.5) * dx,
                            0.0,
                            (k as f32 / nz as f32 - 0.5) * dz,
                        )
                    })
                })
                .collect()
        };
        let plan = PressPlan::default();
        let close = |a: [f32; 2], b: [f32; 2]| (a[0] - b[0]).hypot(a[1] - b[1]) < 1e-4;
        let thin = plan.path_over(6.0, &grid(4, 24, 1.0, 6.0), 0.3);
        assert!(
            close(thin[0], [0.0, -1.5]) && close(thin[1], [0.0, 1.5]),
            "{thin:?}"
        );
        let square = plan.path_over(6.0, &grid(12, 12, 6.0, 6.0), 0.3);
        assert!(
            close(square[0], [-1.5, 0.0]) && close(square[1], [1.5, 0.0]),
            "{square:?}"
        );
        let given = PressPlan {
            waypoints: vec![[1.0, 2.0], [3.0, 4.0]],
            ..PressPlan::default()
        };
        assert_eq!(
            given.path_over(6.0, &grid(4, 24, 1.0, 6.0), 0.3),
            given.waypoints
        );
    }

    /// On a curved organ (a half ring, its centroid off the tissue) each end of the path is
    /// over a node, so the press finds the organ's top.
    #[test]
    fn the_default_path_stays_over_a_curved_organ() {
        let ring: Vec<Vec3A> = (0..=60)
            .flat_map(|i| {
                let a = std::f32::consts::PI * i as f32 / 60.0;
                [2.8f32, 3.0, 3.2].map(|r| Vec3A::new(r * a.cos(), 1.0, r * a.sin()))
            })
            .collect();
        let path = PressPlan::default().path_over(6.4, &ring, 0.3);
        for w in &path {
            let nearest = ring
                .iter()
                .map(|p| (p.x - w[0]).hypot(p.z - w[1]))
                .fold(f32::INFINITY, f32::min);
            assert!(nearest <= 0.3, "{w:?} is {nearest} cm from the organ");
        }
        assert!(
            (path[1][0] - path[0][0]).abs() > 1.0,
            "{path:?} crosses along x"
        );
    }

    #[test]
    fn along_a_polyline_is_by_length() {
        let path = [[0.0, 0.0], [3.0, 0.0], [3.0, 1.0]];
        assert_eq!(along(&path, 0.0), Some([0.0, 0.0]));
        assert_eq!(along(&path, 0.75), Some([3.0, 0.0]));
        assert_eq!(along(&path, 1.0), Some([3.0, 1.0]));
        let mid = along(&path, 0.5).unwrap_or_default();
        assert!((mid[0] - 2.0).abs() < 1e-6 && mid[1] == 0.0, "{mid:?}");
    }
}
