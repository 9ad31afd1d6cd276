//! # tissue-scenes: the trainer's scenes
//!
//! What a trainer front end (the headless `trainer`, the studio's `/trainer`) sets up and drives,
//! in one place:
//!
//! - [`Organ`]: a tet mesh in cm on its tray (y up, lowest node on y = 0): a [`ShippedOrgan`]
//!   (the bunny and the liver, surfaces in `fixtures/` filled by `tissue-tetra` on load; the
//!   appendix, generated, its base pinned) or an upload ([`Organ::from_bytes`]: a closed surface,
//!   filled, or a tet mesh), at most [`MAX_TETS`] tetrahedra.
//! - [`Session`]: the organ as a `tissue-pbd` body with `tissue-surgery` state, stepped by the
//!   caller ([`Session::step`], one per frame), with the trainee's tools: the probe
//!   ([`Session::grab`], [`Session::drag`], [`Session::release`]: nodes attached to a moving
//!   target), the scalpel ([`Session::cut`]: a path and the view direction make the blade's plane;
//!   one segment is cut per step) and the needle ([`Session::suture`]); it reports
//!   [`TrainerEvent`]s (of a closed set of [`TrainerEventKind`]s), the drawable surface ([`Session::surface`], versioned), the volume drift
//!   `V/V₀ − 1`, step times and the tissue's force on the probe in newtons; contact tools the
//!   host poses ([`Session::add_tool`], [`Session::set_tool_pose`]: a probe's tip, a needle, a
//!   blade) with each one's force model of the last step for a haptic loop
//!   ([`Session::contact_force_model`], tissue-pbd's `ContactForceModel`, N), and a blade-sweep
//!   cut at once ([`Session::cut_sweep`]); the organ's demonstration ([`Session::play`]); the
//!   surface's self-collision, on by default and switched off for comparison
//!   ([`SessionOptions::self_collision`], [`Session::set_self_collision`]), its contacts ([`Session::self_contacts`]) and the exact
//!   count of intersecting surface triangle pairs ([`Session::self_intersections`]).
//! - [`script`]: scenarios written once and stepped by any host — [`AppendixProcedure`] (grasp
//!   and lift the appendix's tip, incise near the base, cut the tip off, suture the incision)
//!   and [`PressAndDrag`] (a probe pressed into an organ and dragged along waypoints), behind
//!   the [`Script`] trait (`before_step`, the host's solver step, `after_step`). The headless
//!   `trainer`, the studio's demonstration and this crate's moving-body test run these;
//!   [`PressPlan::default`] is the one press-and-drag timeline, and [`PressAndDrag::on_tray`]
//!   the one set-up of its probe.
//! - [`TissuePreset`]: Young's modulus, Poisson's ratio and density of liver, kidney, bowel,
//!   fat and skin from the literature (`docs/materials.md`), [`ShippedOrgan::tissue`];
//!   [`reference()`]: the finite-element reference (`tissue-fem`) of an organ's static states
//!   as a session holds it — settled on its support, the probe pressed — for comparing a run
//!   with the material it stands for.
//! - [`Organ::body`]: an organ as a `tissue-pbd` body held as its [`Setting`] says (on a
//!   [`Tray`], or the appendix's base pinned over the abdominal wall); [`Organ::scaled_to`].
//!
//! No threads, no I/O beyond parsing bytes; a front end owns the loop and the clock.
//!
//! ## Limits
//! Every input a front end takes from a user (over the network, for the studio) costs bounded
//! work:
//! - an organ has at most [`MAX_TETS`] tetrahedra; a closed surface whose estimated count is
//!   above it is refused before it is meshed ([`SceneError::TooLarge`] with `estimated` and the
//!   triangle count to decimate to), and the mesher stops if its work outgrows it;
//! - the tools work within [`Session::work_space`] (the tray's square grown by half its side,
//!   up to a tray's side above it): drag targets are clamped into it, grab, cut and suture
//!   points outside it refused;
//! - a scalpel path has at most [`MAX_CUT_POINTS`] points (checked before anything else), and
//!   at most [`Session::max_queued_cuts`] segments ([`CUT_QUEUE_TRAY_SIDES`] tray sides of cut)
//!   wait to be cut: a cut that would queue more is refused whole;
//! - a suture within [`SUTURE_SPACING_CM`] of an existing one is refused: a second stitch at
//!   the same place is not a new stitch.
//!
//! ## Units
//! cm, g, s inside; forces out of [`Session::tool_force`] in newtons (1 N = 10⁵ g·cm/s²).
//!
//! ## Example: grab the appendix's tip, lift it, cut across it
//! ```
//! use glam::Vec3;
//! use tissue_scenes::{Organ, Session, SessionOptions, ShippedOrgan};
//!
//! let organ = Organ::shipped(ShippedOrgan::Appendix)?;
//! let mut session = Session::new(&organ, SessionOptions::default())?;
//! // The top face's triangle nearest the tip, and a point on it.
//! let x = session.positions();
//! let (t, _) = session
//!     .surface()
//!     .iter()
//!     .enumerate()
//!     .map(|(i, f)| (i, f.iter().map(|&n| Vec3::from(x[n as usize])).sum::<Vec3>() / 3.0))
//!     .max_by(|a, b| (a.1.x + a.1.y).total_cmp(&(b.1.x + b.1.y)))
//!     .ok_or("no surface")?;
//! let corner = Vec3::from(x[session.surface()[t][0] as usize]);
//! session.grab(corner, t)?;
//! session.drag(corner + Vec3::new(0.0, 1.0, 0.0));
//! for _ in 0..5 {
//!     session.step()?;
//! }
//! session.release()?;
//! assert!(session.volume_drift().abs() < 0.1);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
#![forbid(unsafe_code)]

mod error;
mod event;
mod organ;
mod reference;
pub mod script;
mod session;
mod tissue;

pub use error::{SceneError, SceneErrorKind};
pub use event::{TrainerEvent, TrainerEventKind};
pub use organ::{Organ, Setting, ShippedOrgan, Tray, APPENDIX_BASE_X, MAX_TETS};
pub use reference::{reference, ReferencePlan, ReferencePress, ReferenceSummary};
pub use script::{
    AppendixPlan, AppendixProcedure, PressAndDrag, PressPlan, Script, ScriptStep,
    SETTLE_RELAXATION_TIME,
};
pub use session::{
    surface_self_intersections, MaterialField, OrganMaterial, Session, SessionOptions,
    CUT_QUEUE_TRAY_SIDES, MAX_CUT_POINTS, SUTURE_SPACING_CM,
};
pub use tissue::TissuePreset;
/// Self-collision's settings ([`SessionOptions::self_collision`]), re-exported so that a front
/// end needs no dependency on tissue-pbd to switch it.
pub use tissue_pbd::SelfCollision;
