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
//! ## Cutting (SPEC Part B)
//! Each sweep of the blade cuts in two phases; the first only with
//! [`SurgerySettings::split_tets`] on (the default).
//!
//! **Geometry** (module `split`): the cut surface is the polygon the blade swept in its own
//! plane. Nodes closer to the plane than [`SNAP_FRACTION`] of their shortest rest edge (and
//! whose projection is in the polygon) are **snapped** onto it, current and rest position,
//! when no tet around them would fall below the quality bound; their tets' rest volumes and
//! edges' rest lengths are rebuilt. Every other tet edge the plane crosses inside the polygon
//! (or within [`FRONT_SNAP`] of its length outside it: the cut's ends snap to tet boundaries)
//! gets a node at the crossing, interpolated in current and rest space; the tets around those
//! edges are **split** by bisecting their split edges in one global order, which is conforming
//! (no hanging node: two tets split a shared face alike) and leaves no piece with nodes on
//! both sides once all of a tet's crossing edges are split. A crossed surface triangle is so
//! split into 3 along the path (2 where the blade passes through one of its nodes). Pieces
//! below the quality bound ([`MIN_RATIO`], [`MIN_PIECE_FRACTION`]) or past
//! [`MAX_SPLIT_DEPTH`] are not made: that tet's edges stay whole; so are tets at the nodes of
//! an earlier cut's wall nearly parallel to the blade but off its plane (a body that moved
//! against the blade between two sweeps), which separate along their faces, so that the new
//! wall steps onto the old one instead of shaving a slab off it. New tets get volume
//! constraints with their rest volumes, new edges distance constraints with their rest
//! lengths, masses are rebuilt from the tets around the touched nodes (eq. (1)) — all locally
//! through `tissue-pbd`'s edit API ([`tissue_pbd::SoftBody::reshape_tet`],
//! [`tissue_pbd::SoftBody::add_tet`], ...), no rebuild.
//!
//! **Separation** (module `cut`): a face shared by tets `t` and `u` opens when the segment
//! between their centroids crosses the polygon; after the split these are the faces lying on
//! the blade's plane, so the walls are flat. Tets the sweep crossed only partly (the cut's
//! front: a crossing point outside the polygon) stay glued until a later sweep covers them;
//! where a split was refused (quality, a node that could not be snapped) the faces of the
//! whole tets open instead (a staircase within one tet). Each node on a newly opened face is
//! duplicated once per extra face-connected group of its tets; tets on the far side move onto
//! the copies. Before committing, new faces that would leave a non-manifold edge or a pinched
//! vertex, faces with no node split yet (a zero-width double face) and faces that would
//! enclose a crumb of fewer than [`MIN_PIECE`] tets are glued back and retried later (with
//! splits, a crumb whose new faces lead to both sides of the plane is glued to the side its
//! centroid lies on only, so that it cannot bridge the cut). Pieces:
//! two alternating searches through shared nodes per split node prove that an incision
//! detached nothing (cheap); only when one runs out are the pieces relabelled
//! ([`SurgeryEvent::PieceDetached`]).
//!
//! **Tips** (module `tip`): where the polygon's boundary (the blade's front, or where the cut
//! started) crosses the surface, the crossed surface triangle's edge on the plane — from its
//! crossing point in the polygon to the one just outside it — is split again at the tip (where
//! it leaves the polygon) by a second pass of the same bisection, and the tets beyond the tip
//! stay glued this sweep: the triangle is in 5 pieces and the opening on the surface ends
//! exactly at the tip, which keeps one node. No tip within [`TIP_MARGIN`] of the edge's ends
//! or where a piece would fall below the quality bound (the cut then ends at a tet boundary).
//!
//! Not built: a true 4-way split of the triangle where a cut ends (the tip lies on the crack
//! line, not joined to the corners); inside the body the cut's front snaps to a tet boundary,
//! and a partly crossed tet stays glued. A body that moves against the blade while it is cut (a
//! world-fixed blade path through a falling organ) gets slightly offset walls in every sweep,
//! joined by steps along tet faces; thin slabs between two such walls can come off as small
//! pieces. A tet stretched to more than 1.5 × its longest rest edge may be missed by a sweep.
//!
//! ## Code layout
//! One cut runs as named phases (`docs/surgery.md`, "Code map"): the straddling search and
//! the face separation (module `cut`), the split's plan (`split`, with the four-way tips of
//! `tip`) as an explicit plan (`plan`: `SplitPlan`, pieces over `NodeRef`s, the nodes the plan
//! creates typed as `NewNode`s), its application (`apply`), the fallback tips (`tip`), the
//! manifold guard (`guard`) and the commit (`commit`). Scratch buffers live in a workspace
//! (`workspace::CutScratch`), apart from the persistent state.
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
//! - Tets are never destroyed: a split tet's record holds its first piece, the other pieces
//!   are appended; tets are otherwise only moved onto duplicated nodes. New nodes are appended
//!   (indices past the old count).
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

mod apply;
mod commit;
mod cut;
mod error;
mod event;
mod geometry;
mod guard;
mod plan;
mod settings;
mod split;
mod state;
mod suture;
mod tip;
mod workspace;

pub use cut::{BladeSweep, MIN_PIECE};
pub use error::SurgeryError;
pub use event::{SplitTriangle, SurgeryEvent};
pub use settings::SurgerySettings;
pub use split::{
    FRONT_SNAP, MAX_SPLIT_DEPTH, MIN_PIECE_FRACTION, MIN_RATIO, MIN_VOLUME_FRACTION, SNAP_FRACTION,
};
pub use state::{Surgery, Suture};
pub use tip::{TipCounts, FACE_TIP_MARGIN, TIP_MARGIN};
