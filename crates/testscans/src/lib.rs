//! # tissue-testscans: realistic, seeded test scans (a dev-dependency for tests and benches)
//!
//! ## Brief overview
//! - [`Scan`]: a valid [`tissue_mesh::TriMesh`] with its unit, named placement points
//!   ([`NamedPoint`]), the holes punched into it ([`PunchedHole`]) and, for noisy scans, the
//!   noise-free surface it came from.
//! - Generators: [`noisy_face_scan`] (mm: a photogrammetric face with 0.2 mm noise, 0.5 mm
//!   triangles and holes), [`tapered_tube`] (cm: an uneven open tube, generated),
//!   [`forearm_from_body`] (dm: the left arm cut from the body, refined), [`closed_body`]
//!   (dm: the watertight body as it is) and [`fine_face_scan`] (the face subdivided to
//!   millions of triangles, far from the origin).
//! - Building blocks for variants: [`Rng`] (splitmix64, Box–Muller), [`median_edge`],
//!   [`subdivide_midpoint`], [`loop_subdivide`], [`add_normal_noise`], [`punch_hole`],
//!   [`remove_triangles`].
//!
//! The face, arm and body are made from the public MakeHuman meshes (CC0) shipped in the
//! repository's `fixtures/` ([`meshes_dir`], found from this crate's manifest). Should one be
//! missing they return [`ScanError::Absent`]; the tests fail on it. Everything is
//! deterministic: the same seed gives the same bits.
//!
//! ```
//! let tube = tissue_testscans::tapered_tube(1)?;
//! assert_eq!(tube.unit_name, "cm");
//! assert_eq!(tube.mesh.topology().boundary_loops().len(), 2);
//! let edge = tissue_testscans::median_edge(&tube.mesh);
//! assert!((0.1..0.4).contains(&edge));
//! for point in &tube.points {
//!     assert!(point.border_distance >= 8.0);
//! }
//! # Ok::<(), tissue_testscans::ScanError>(())
//! ```

#![forbid(unsafe_code)]

mod body;
mod face;
mod fine;
mod ops;
mod rng;
mod scan;
mod tube;

pub use body::{closed_body, forearm_from_body, ARM_ELBOW, ARM_UPPER_CUT, ARM_WRIST, BODY_FILE};
pub use face::{
    noisy_face_scan, FACE_BIG_HOLE_MM, FACE_CUT_Z_MM, FACE_HOLE_BORDER_MM, FACE_NOISE_SIGMA_MM,
    HEAD_FILE,
};
pub use fine::{fine_face_scan, FINE_FACE_HOLES};
pub use ops::{
    add_normal_noise, loop_subdivide, median_edge, punch_hole, remove_triangles,
    subdivide_midpoint, Trimmed,
};
pub use rng::Rng;
pub use scan::{meshes_dir, NamedPoint, PunchedHole, Scan, ScanError};
pub use tube::{tapered_tube, TUBE_LENGTH_CM, TUBE_RADIUS_END_CM, TUBE_RADIUS_START_CM};
