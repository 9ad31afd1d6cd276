//! # tissue-surgery: cutting and suturing on `tissue-pbd` soft bodies
//!
//! ## Brief overview
//! - [`Surgery`]: the state kept next to one [`tissue_pbd::SoftBody`] — tet adjacency across
//!   faces (cut walls have none), node → tets, the distance constraint of each edge, sutures —
//!   with [`Surgery::cut`], [`Surgery::suture`] and [`Surgery::remove_suture`], the boundary
//!   surface for rendering ([`Surgery::boundary_faces`]) and [`Surgery::validate`].
//! - [`BladeSweep`]: a scalpel blade ([`tissue_pbd::ToolShape::Blade`]) swept over one step,
//!   from two poses or from a body's tool ([`tissue_pbd::Tool::last_sweep`]).
//! - [`SurgeryEvent`]: "cut advanced" (new nodes, changed tets, opened wall triangles), "piece
//!   detached" (a new connected component), "suture placed" / "suture removed".
//! - [`SurgerySettings`], [`SurgeryError`].
//!
//! ## Cutting (SPEC Part B), and where it departs from the slides
//! The slides split the crossed surface triangles (into 4 where the cut starts or ends, into 3
//! along its path), snap vertices, and rebuild the physics model from the new elements. Here the
//! cut **separates the mesh along existing tet faces** instead of subdividing: a face between
//! two tets is cut when the segment between their centroids crosses the blade's swept surface
//! (the area the blade triangle swept within its own plane; motion along its normal does not cut); each node on a newly
//! cut face is duplicated once per extra face-connected group of its tets; tets on the far side
//! are moved onto the copies. This is the limit case of vertex snapping (every crossing snaps to
//! the nearest tet face, threshold one tet), and it buys robustness:
//! - **no tet is created or split**, so no sliver can appear: the quality bound is the input
//!   mesh's own smallest rest volume and radius ratio ([`Surgery::quality_bound`]), and it
//!   holds after any number of cuts;
//! - constraints keep their rest values; an edge that now exists on both sides gets a second
//!   distance constraint with the same rest length; masses of the split nodes are rebuilt from
//!   their tets (eq. (1)) — all locally, through `tissue-pbd`'s edit API (nodes appended,
//!   changed constraints moved to a dynamic set projected after the block tree, no rebuild);
//! - before a cut is committed, newly cut faces that would leave a non-manifold edge or a
//!   pinched vertex (typically at the cut's front) are glued back, so the boundary surface stays
//!   closed, manifold and consistently oriented.
//!
//! - faces that must wait (at the cut's front, or with no node split yet, which would make a
//!   zero-width double face) are kept and retried whenever a later sweep passes near them; a
//!   group of fewer than [`MIN_PIECE`] tets that new faces would enclose (a staircase crumb)
//!   stays glued;
//! - pieces: two alternating searches through shared nodes per split node prove that an
//!   incision detached nothing (cheap); only when one runs out are the pieces relabelled
//!   globally ([`SurgeryEvent::PieceDetached`] for each new one).
//!
//! The price: the wall follows the blade only to within about one tet (a staircase on coarse
//! meshes), the surface triangles are not subdivided and nodes are not moved onto the blade
//! (no geometric vertex snapping), and a tet stretched to more than 1.5 × its longest rest edge
//! may be missed by a sweep. A cut that crosses no face (a blade
//! sweep smaller than a tet) opens nothing until the blade has moved on; partial incisions and
//! cuts continued over many steps are just more sweeps.
//!
//! ## Suturing
//! No change of geometry: the needle's axis is intersected with the boundary faces; the first
//! face it leaves the body through and the next it enters through are the two sides of the
//! wound; their nodes nearest the crossings are linked by a distance constraint (rest length and
//! stiffness in [`SurgerySettings`]) unless already linked. Linked nodes then move together.
//!
//! ## Invariants
//! - Architecture Invariant: the surgery state and its body change together; every operation
//!   takes the body and refuses one whose node or tet count differs from the state's.
//! - Tets are never created or destroyed, only moved onto duplicated nodes; tet indices are
//!   stable for the host. New nodes are appended (indices past the old count).
//! - After every cut the boundary (faces without a neighbour) is closed, edge- and
//!   vertex-manifold and wound outward, if the input's was; [`Surgery::validate`] checks it.
//! - No I/O, no printing; spans `cut` and `suture`.
//!
//! ## Units
//! Centimetres, grams, seconds, as `tissue-pbd`.
//!
//! ## Example: a block cut in two
//! ```
//! use glam::Vec3;
//! use tissue_mesh::tet_box;
//! use tissue_pbd::{Material, Pose, SoftBody, ToolShape};
//! use tissue_surgery::{BladeSweep, Surgery, SurgeryEvent, SurgerySettings};
//!
//! let mesh = tet_box(6, 3, 3, Vec3::new(6.0, 3.0, 3.0))?;
//! let mut body = SoftBody::new(&mesh, &Material::default())?;
//! let mut surgery = Surgery::new(&body, SurgerySettings::default())?;
//! // A big blade in the plane x = 0.3, drawn down through the whole block.
//! let blade = ToolShape::Blade {
//!     a: Vec3::new(0.0, 0.0, -5.0),
//!     b: Vec3::new(0.0, 0.0, 5.0),
//!     c: Vec3::new(0.0, 5.0, 0.0),
//!     thickness: 0.01,
//! };
//! let from = Pose::from_translation(Vec3::new(0.3, 2.0, 0.0));
//! let to = Pose::from_translation(Vec3::new(0.3, -8.0, 0.0));
//! let events = surgery.cut(&mut body, &BladeSweep::new(&blade, &from, &to)?)?;
//! assert!(events.iter().any(|e| matches!(e, SurgeryEvent::PieceDetached { .. })));
//! assert_eq!(surgery.component_count(), 2);
//! surgery.validate(&body)?;
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
#![forbid(unsafe_code)]
#![warn(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::print_stdout,
    clippy::print_stderr
)]

mod cut;
mod error;
mod event;
mod geometry;
mod settings;
mod split;
mod state;
mod suture;

pub use cut::{BladeSweep, MIN_PIECE};
pub use error::SurgeryError;
pub use event::{SplitTriangle, SurgeryEvent};
pub use settings::SurgerySettings;
pub use split::{
    FRONT_SNAP, MAX_SPLIT_DEPTH, MIN_PIECE_FRACTION, MIN_RATIO, MIN_VOLUME_FRACTION, SNAP_FRACTION,
};
pub use state::{Surgery, Suture};
