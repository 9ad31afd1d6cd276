//! # tissue-capi: the C ABI (`tissue.h`)
//!
//! The library `tissue` (`libtissue.a`, `libtissue.so`) for C and C++ hosts: a planning
//! application that runs insertions with progress and cancel, and a surgical trainer whose
//! haptic loop asks for the force on a tool at 1 kHz or more. The header,
//! `crates/capi/include/tissue.h`, is generated from this crate by cbindgen and checked in; the
//! test `header` fails when it is stale, and `TISSUE_BLESS=1 cargo test -p tissue-capi --test
//! header` rewrites it. Guide: `docs/c-api.md`.
//!
//! ## Brief overview
//! - Handles (opaque, `_new`/`_free`; freeing NULL does nothing): [`tissue_mesh`] (a surface or
//!   a tet mesh, from a file in any of tissue-meshio's formats or the caller's arrays),
//!   [`tissue_patient`] (planning's patient, tissue-planner's `Patient`), [`tissue_job`] (a
//!   planning job on tissue-app's worker: progress, cancel from any thread, wait with a
//!   timeout, a blocking run with a progress callback, the report's numbers and JSON, the
//!   deformed patient; sweeps and the inverse search), [`tissue_body`] (the trainer's body,
//!   tissue-scenes' `Session`: steps, surface with revision counters, tools, scalpel, needle,
//!   events, and [`tissue_tool_force`] for haptics).
//! - The body's material, [`tissue_material`] (issue 32): the material scheme's physical organ
//!   (Young's modulus, Poisson's ratio, density, relaxation time; presets by tissue or shipped
//!   organ) given to [`tissue_body_new_with_material`] or
//!   [`tissue_body_new_shipped_with_material`], checked by tissue-scenes'
//!   `SessionOptions::material` (the trainer's and the studio's entry point too), and read back
//!   by [`tissue_body_get_material`].
//! - Conventions (those of rustls-ffi and wasmtime's C API): every fallible call returns a
//!   [`tissue_status`]; the message of the last failure on the calling thread is copied out by
//!   [`tissue_last_error`]; every entry point catches panics (`TISSUE_PANIC`, never an unwind
//!   into C; [`tissue_debug_panic`] tests it); no global state but that message; sizes are
//!   queried before buffers are filled; each function's doc says which threads may call it.
//! - Planning goes through tissue-planner, the one planning front door: the same request, the
//!   same checks and messages, the same report (with `tool: "capi"`) as `insert` and the studio.
//!
//! ## Units
//! cm, g, s inside; planning results in cm, cm², cm³ (a patient file's unit is given when it is
//! loaded); trainer positions in cm; forces in newtons.
//!
//! ## Example (Rust, through the C ABI): a finished Table 2 job
//! ```
//! use tissue::*;
//! let mut patient = std::ptr::null_mut();
//! assert_eq!(tissue_patient_shipped(0, &mut patient), tissue_status::TISSUE_OK);
//! let mut options = std::mem::MaybeUninit::uninit();
//! assert_eq!(tissue_plan_options_default(options.as_mut_ptr()), tissue_status::TISSUE_OK);
//! let mut options = unsafe { options.assume_init() };
//! options.max_steps = 30; // a short run for the example
//! let mut job = std::ptr::null_mut();
//! assert_eq!(tissue_plan_start(patient, &options, &mut job), tissue_status::TISSUE_OK);
//! assert_eq!(tissue_job_wait(job, -1.0), tissue_status::TISSUE_OK);
//! let mut result = tissue_plan_result::default();
//! assert_eq!(tissue_job_result(job, &mut result), tissue_status::TISSUE_OK);
//! assert_eq!(result.steps, 30);
//! assert!(result.area_gain_cm2 > 0.0);
//! tissue_job_free(job);
//! tissue_patient_free(patient);
//! ```
// The ABI is raw pointers by nature: unsafe code is confined to the pointer helpers of `ffi.rs`
// and a few marked blocks, each with its SAFETY note. Entry points are plain `extern "C" fn`s
// that check every pointer for NULL before use (the header states each one's contract), so
// clippy's `not_unsafe_ptr_arg_deref` does not apply. Type names follow C (`tissue_status`).
#![allow(unsafe_code, clippy::not_unsafe_ptr_arg_deref, non_camel_case_types)]

mod ffi;
mod material;
mod mesh;
mod plan;
mod trainer;

pub use ffi::{tissue_debug_panic, tissue_last_error, tissue_status, tissue_version};
pub use material::{
    tissue_material, tissue_material_default, tissue_material_preset, tissue_material_shipped,
    tissue_preset, tissue_scheme,
};
pub use mesh::{
    tissue_mesh, tissue_mesh_copy_indices, tissue_mesh_copy_positions, tissue_mesh_free,
    tissue_mesh_from_tets, tissue_mesh_from_triangles, tissue_mesh_kind, tissue_mesh_load,
    tissue_mesh_save, tissue_mesh_sizes,
};
pub use plan::{
    tissue_field, tissue_inverse_result, tissue_inverse_start, tissue_job, tissue_job_cancel,
    tissue_job_copy_field, tissue_job_free, tissue_job_inverse_result, tissue_job_patient_after,
    tissue_job_progress, tissue_job_report_json, tissue_job_result, tissue_job_run,
    tissue_job_start_json, tissue_job_state, tissue_job_sweep_count, tissue_job_sweep_row,
    tissue_job_wait, tissue_patient, tissue_patient_free, tissue_patient_from_mesh,
    tissue_patient_load, tissue_patient_mesh, tissue_patient_shipped, tissue_placement,
    tissue_plan_options, tissue_plan_options_default, tissue_plan_result, tissue_plan_run,
    tissue_plan_start, tissue_progress, tissue_progress_callback, tissue_shape,
    tissue_shipped_patient, tissue_sweep_start, tissue_unit,
};
pub use trainer::{
    tissue_body, tissue_body_add_blade, tissue_body_add_capsule, tissue_body_copy_positions,
    tissue_body_copy_triangles, tissue_body_cut, tissue_body_cut_sweep, tissue_body_drag,
    tissue_body_free, tissue_body_get_info, tissue_body_get_material, tissue_body_grab,
    tissue_body_grasp_force, tissue_body_info, tissue_body_new, tissue_body_new_shipped,
    tissue_body_new_shipped_with_material, tissue_body_new_with_material, tissue_body_next_event,
    tissue_body_release, tissue_body_step, tissue_body_suture, tissue_event, tissue_event_kind,
    tissue_pose, tissue_shipped_organ, tissue_tool_force, tissue_tool_set_pose, TISSUE_EVENT_TEXT,
};
