//! Every library error as one of the package's exception classes (`tissue/_errors.py`), each a
//! subclass of `tissue.TissueError` carrying `.kind` (the error kind's snake_case name) and
//! `.field` (the request field at fault, or `None`):
//!
//! | library error | class |
//! |---|---|
//! | `PlanError` of kind `cancelled` | `tissue.Cancelled` (a `PlanError`) |
//! | `PlanError` of kind `input` | `tissue.InputError` (a `MeshError` and an `OSError`) |
//! | `PlanError` of kind `mesh` | `tissue.MeshError` (a `ValueError`) |
//! | any other `PlanError` | `tissue.PlanError` |
//! | `SceneError` of kind input / mesh, meshing, too large | `InputError` / `MeshError` |
//! | any other `SceneError` | `tissue.TrainerError` |
//!
//! The classes are Python's own (so that one can subclass both `TissueError` and `ValueError`);
//! they are looked up in `tissue._errors` when an error is raised.

use pyo3::prelude::*;
use tissue_planner::{ErrorKind, PlanError};
use tissue_scenes::{SceneError, SceneErrorKind};

/// An instance of `tissue._errors.<class>(message, kind, field)` as a `PyErr` (or the error of
/// looking it up, which only a broken installation gives).
pub fn raise(
    py: Python<'_>,
    class: &str,
    message: &str,
    kind: Option<&str>,
    field: Option<&str>,
) -> PyErr {
    let made = py
        .import("tissue._errors")
        .and_then(|m| m.getattr(class))
        .and_then(|c| c.call1((message, kind, field)));
    match made {
        Ok(instance) => PyErr::from_value(instance),
        Err(e) => e,
    }
}

/// The snake_case name of a planning error's kind (its JSON name).
pub fn kind_name(kind: ErrorKind) -> &'static str {
    match kind {
        ErrorKind::Usage => "usage",
        ErrorKind::Input => "input",
        ErrorKind::Mesh => "mesh",
        ErrorKind::Placement => "placement",
        ErrorKind::Parameters => "parameters",
        ErrorKind::Run => "run",
        ErrorKind::Output => "output",
        ErrorKind::Cancelled => "cancelled",
    }
}

/// A planning error as its class (module docs).
pub fn plan_error(py: Python<'_>, e: &PlanError) -> PyErr {
    let class = match e.kind {
        ErrorKind::Cancelled => "Cancelled",
        ErrorKind::Input => "InputError",
        ErrorKind::Mesh => "MeshError",
        _ => "PlanError",
    };
    raise(py, class, &e.message, Some(kind_name(e.kind)), e.field)
}

/// The snake_case name of a scene error's kind.
pub fn scene_kind_name(kind: SceneErrorKind) -> &'static str {
    match kind {
        SceneErrorKind::Input => "input",
        SceneErrorKind::Mesh => "mesh",
        SceneErrorKind::Meshing => "meshing",
        SceneErrorKind::TooLarge => "too_large",
        SceneErrorKind::Parameters => "parameters",
        SceneErrorKind::Tool => "tool",
        SceneErrorKind::Simulation => "simulation",
    }
}

/// A trainer error as its class (module docs); `field` names the argument at fault, if one is.
pub fn scene_error(py: Python<'_>, e: &SceneError, field: Option<&str>) -> PyErr {
    let kind = e.kind();
    let class = match kind {
        SceneErrorKind::Input => "InputError",
        SceneErrorKind::Mesh | SceneErrorKind::Meshing | SceneErrorKind::TooLarge => "MeshError",
        SceneErrorKind::Parameters | SceneErrorKind::Tool | SceneErrorKind::Simulation => {
            "TrainerError"
        }
    };
    raise(
        py,
        class,
        &e.to_string(),
        Some(scene_kind_name(kind)),
        field,
    )
}

/// A file's loader error as its class (`InputError` for a file that cannot be read or is of
/// the wrong type, else `MeshError`), naming `field`.
pub fn mesh_io_error(py: Python<'_>, e: &tissue_meshio::MeshIoError, field: &str) -> PyErr {
    match SceneErrorKind::of_mesh_io(e) {
        SceneErrorKind::Input => {
            raise(py, "InputError", &e.to_string(), Some("input"), Some(field))
        }
        _ => raise(py, "MeshError", &e.to_string(), Some("mesh"), Some(field)),
    }
}

/// A `MeshError` of kind `mesh` about the argument `field` (a bad array: its shape, type or
/// values).
pub fn bad_array(py: Python<'_>, field: &str, message: impl AsRef<str>) -> PyErr {
    raise(py, "MeshError", message.as_ref(), Some("mesh"), Some(field))
}

/// A `PlanError` of kind `usage` about `field`.
pub fn usage(py: Python<'_>, field: Option<&str>, message: impl AsRef<str>) -> PyErr {
    raise(py, "PlanError", message.as_ref(), Some("usage"), field)
}

/// A `TrainerError` of kind `tool` about the argument `field`.
pub fn tool_error(py: Python<'_>, field: Option<&str>, message: impl AsRef<str>) -> PyErr {
    raise(py, "TrainerError", message.as_ref(), Some("tool"), field)
}

/// A `TissueError` for a bug: a panic caught, a thread that could not start.
pub fn bug(py: Python<'_>, message: impl AsRef<str>) -> PyErr {
    raise(py, "TissueError", message.as_ref(), Some("bug"), None)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `.kind` is the library's own JSON name of the kind (what the report's `failed_runs`
    /// and the studio's errors carry).
    #[test]
    fn kind_names_are_the_json_names() {
        let kinds = [
            ErrorKind::Usage,
            ErrorKind::Input,
            ErrorKind::Mesh,
            ErrorKind::Placement,
            ErrorKind::Parameters,
            ErrorKind::Run,
            ErrorKind::Output,
            ErrorKind::Cancelled,
        ];
        for kind in kinds {
            assert_eq!(
                serde_json::to_value(kind).ok(),
                Some(serde_json::json!(kind_name(kind)))
            );
        }
    }
}
