//! Planning: the `Patient` (the planner's `Patient`), a job's JSON run on it (`_run`, what
//! `tissue.plan`, `tissue.sweep`, `tissue.target_gain` and `tissue.expand` call), and its `Plan`
//! (the report and the deformed patient).
//!
//! Running: the job (placing the request, planning and running it through
//! [`PlannedJob::run`](tissue_planner::PlannedJob::run)) runs on a thread of its own; the
//! calling thread waits with the GIL released, taking it back every [`POLL`] to call the
//! caller's `progress(step, max_steps, settle)` with the newest progress and to check for
//! signals. `progress` returning `False` cancels the job (`tissue.Cancelled`, unless it
//! finished first); an exception from it, or a signal handler's (Ctrl-C's
//! `KeyboardInterrupt`), cancels the job and is raised at once: the job's thread stops within
//! one step on its own.

use std::path::PathBuf;
use std::sync::{Arc, Mutex};
use std::time::Duration;

use crossbeam_channel::RecvTimeoutError;
use numpy::{PyArray1, PyArray2};
use pyo3::prelude::*;
use pyo3::types::PyTuple;
use tissue_mesh::TriMesh;
use tissue_planner::{
    CancelToken, ErrorKind, Finished, JobReport, JobSpec, PlanError, PlanRequest, ProgressEvent,
    Scenario, Shipped, Stopped, Tool, Unit,
};

use crate::arrays;
use crate::errors::{bug, plan_error, usage};

/// How often the waiting thread takes the GIL back: for progress, Ctrl-C and the callback's
/// cancel (so Ctrl-C is seen within this, and the job stops one step later).
pub const POLL: Duration = Duration::from_millis(20);

/// A patient surface, in its file's unit and in cm (tissue-planner's `Patient`). Immutable.
#[pyclass(module = "tissue._tissue", frozen)]
pub struct Patient {
    patient: Arc<tissue_planner::Patient>,
    shipped: Option<Shipped>,
}

fn unit_of(py: Python<'_>, unit: &str) -> PyResult<Unit> {
    Unit::ALL
        .into_iter()
        .find(|u| u.symbol() == unit)
        .ok_or_else(|| {
            usage(
                py,
                Some("unit"),
                format!("`unit` {unit:?} is not a unit: give \"mm\", \"cm\", \"dm\" or \"m\""),
            )
        })
}

#[pymethods]
impl Patient {
    /// A patient shipped with the library: `"table2"` (the thesis's Table 2 plane, 20 cm square,
    /// 65 × 65 vertices, cm), `"chest"` or `"head"` (MakeHuman patches, dm).
    #[staticmethod]
    fn shipped(py: Python<'_>, name: &str) -> PyResult<Self> {
        let which = Shipped::from_id(name).ok_or_else(|| {
            usage(
                py,
                Some("name"),
                format!("no shipped patient {name:?}: give \"table2\", \"chest\" or \"head\""),
            )
        })?;
        let patient = py
            .detach(|| tissue_planner::Patient::shipped(which))
            .map_err(|e| plan_error(py, &e))?;
        Ok(Patient {
            patient: Arc::new(patient),
            shipped: Some(which),
        })
    }

    /// Reads a patient surface (`.obj`, `.ply`, `.stl`, `.vtk`) whose coordinates are in `unit`
    /// (`"mm"`, `"cm"`, `"dm"`, `"m"`).
    #[staticmethod]
    #[pyo3(signature = (path, unit = "cm"))]
    fn load(py: Python<'_>, path: PathBuf, unit: &str) -> PyResult<Self> {
        let unit = unit_of(py, unit)?;
        let patient = py
            .detach(|| tissue_planner::Patient::read(&path, unit))
            .map_err(|e| plan_error(py, &e))?;
        Ok(Patient {
            patient: Arc::new(patient),
            shipped: None,
        })
    }

    /// A patient from arrays: `vertices` `(n, 3)` in `unit`, `triangles` `(m, 3)` vertex
    /// indices from 0, counter-clockwise seen from outside.
    #[staticmethod]
    #[pyo3(signature = (vertices, triangles, unit = "cm", label = None))]
    fn from_arrays(
        py: Python<'_>,
        vertices: &Bound<'_, PyAny>,
        triangles: &Bound<'_, PyAny>,
        unit: &str,
        label: Option<String>,
    ) -> PyResult<Self> {
        let unit = unit_of(py, unit)?;
        let positions = arrays::points(vertices, "vertices")?;
        let (flat, _) = arrays::indices(triangles, "triangles", &[3])?;
        let label = label.unwrap_or_else(|| {
            format!(
                "arrays: {} vertices, {} triangles",
                positions.len(),
                flat.len() / 3
            )
        });
        let patient = py
            .detach(|| {
                let mesh = TriMesh::new(positions, arrays::triples(&flat)).map_err(|e| {
                    PlanError::field(
                        ErrorKind::Mesh,
                        "triangles",
                        format!("{label}: not a valid surface: {e}"),
                    )
                })?;
                tissue_planner::Patient::from_mesh(mesh, unit, label)
            })
            .map_err(|e| plan_error(py, &e))?;
        Ok(Patient {
            patient: Arc::new(patient),
            shipped: None,
        })
    }

    /// The vertices as the file has them (its unit), float64 `(n, 3)`; a new array each time.
    #[getter]
    fn vertices<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        arrays::positions_out(py, self.patient.file.positions())
    }

    /// The triangles, int64 `(m, 3)`; a new array each time.
    #[getter]
    fn triangles<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<i64>>> {
        arrays::indices_out(py, self.patient.file.triangles())
    }

    /// The file's unit: `"mm"`, `"cm"`, `"dm"` or `"m"`.
    #[getter]
    fn unit(&self) -> &'static str {
        self.patient.unit.symbol()
    }

    /// Centimetres per unit.
    #[getter]
    fn cm_per_unit(&self) -> f32 {
        self.patient.cm_per_unit()
    }

    /// The path, name or description (the report's `inputs.mesh`).
    #[getter]
    fn label(&self) -> &str {
        &self.patient.label
    }

    /// The shipped patient's name, or `None`.
    #[getter]
    fn shipped_name(&self) -> Option<&'static str> {
        self.shipped.map(Shipped::id)
    }

    /// A placement that runs with the default implant on a shipped patient (the plane's centre,
    /// the chest's vertex of the README, the top of the forehead), or `None`.
    #[getter]
    fn suggested_vertex(&self) -> Option<u32> {
        self.shipped.map(|s| s.suggested_vertex(&self.patient.file))
    }

    fn __len__(&self) -> usize {
        self.patient.file.positions().len()
    }

    /// Pickling (Dask ships patients to its workers): a shipped patient by its name, any other
    /// by its arrays, unit and label (the same mesh, bit for bit).
    fn __reduce__<'py>(
        slf: &Bound<'py, Self>,
    ) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyTuple>)> {
        let py = slf.py();
        let this = slf.get();
        let class = slf.get_type();
        match this.shipped {
            Some(which) => Ok((class.getattr("shipped")?, (which.id(),).into_pyobject(py)?)),
            None => Ok((
                class.getattr("from_arrays")?,
                (
                    arrays::positions_out(py, this.patient.file.positions())?,
                    arrays::indices_out(py, this.patient.file.triangles())?,
                    this.patient.unit.symbol(),
                    this.patient.label.clone(),
                )
                    .into_pyobject(py)?,
            )),
        }
    }

    fn __repr__(&self) -> String {
        format!(
            "Patient({:?}, {} vertices, {} triangles, unit={:?})",
            self.patient.label,
            self.patient.file.positions().len(),
            self.patient.file.triangles().len(),
            self.patient.unit.symbol()
        )
    }
}

/// A finished planning job: its report (the JSON contract of `insert --report`, `tool`
/// `"python"`) and, for a single insertion, the patient after the run with its fields.
#[pyclass(module = "tissue._tissue", frozen)]
pub struct Plan {
    mode: &'static str,
    report: Py<PyAny>,
    report_json: String,
    area_gain_cm2: Option<f64>,
    volume_difference_cm3: Option<f64>,
    volume_cm3: Option<f64>,
    vertices_after: Option<Py<PyArray2<f64>>>,
    displacement: Option<Py<PyArray1<f64>>>,
    stretch: Option<Py<PyArray1<f64>>>,
    in_region: Option<Py<PyArray1<f64>>>,
}

#[pymethods]
impl Plan {
    /// What was run: `"single"`, `"sweep"`, `"target-gain"` or `"expansion"`.
    #[getter]
    fn mode(&self) -> &'static str {
        self.mode
    }

    /// The report as a dict (the same JSON as `insert --report`); the same dict each time.
    #[getter]
    fn report(&self, py: Python<'_>) -> Py<PyAny> {
        self.report.clone_ref(py)
    }

    /// The report's JSON text.
    #[getter]
    fn report_json(&self) -> &str {
        &self.report_json
    }

    /// The skin gained, cm² (a single run's, or the answer's of a target-gain search; `None`
    /// for a sweep or an expansion: see `report`).
    #[getter]
    fn area_gain_cm2(&self) -> Option<f64> {
        self.area_gain_cm2
    }

    /// The volume between the skin before and after, cm³ (a single run; else `None`).
    #[getter]
    fn volume_difference_cm3(&self) -> Option<f64> {
        self.volume_difference_cm3
    }

    /// The fill volume, cm³: a single run's, or the answer of a target-gain search.
    #[getter]
    fn volume_cm3(&self) -> Option<f64> {
        self.volume_cm3
    }

    /// Every vertex of the patient after the run, in the patient's unit, float64 `(n, 3)` (a
    /// single run; else `None`). Vertices that did not move keep the input's positions.
    #[getter]
    fn vertices_after(&self, py: Python<'_>) -> Option<Py<PyArray2<f64>>> {
        self.vertices_after.as_ref().map(|a| a.clone_ref(py))
    }

    /// How far each vertex moved, in the patient's unit, float64 `(n,)`; 0 outside the region.
    #[getter]
    fn displacement(&self, py: Python<'_>) -> Option<Py<PyArray1<f64>>> {
        self.displacement.as_ref().map(|a| a.clone_ref(py))
    }

    /// Area after / area before around each vertex (no unit), float64 `(n,)`; 0 outside the
    /// region.
    #[getter]
    fn stretch(&self, py: Python<'_>) -> Option<Py<PyArray1<f64>>> {
        self.stretch.as_ref().map(|a| a.clone_ref(py))
    }

    /// 1.0 for a vertex of the simulated region, 0.0 outside, float64 `(n,)`.
    #[getter]
    fn in_region(&self, py: Python<'_>) -> Option<Py<PyArray1<f64>>> {
        self.in_region.as_ref().map(|a| a.clone_ref(py))
    }

    /// Pickling (Dask returns plans from its workers): its figures, report and arrays.
    fn __reduce__<'py>(
        slf: &Bound<'py, Self>,
    ) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyTuple>)> {
        let py = slf.py();
        let p = slf.get();
        let restore = py.import("tissue._tissue")?.getattr("_plan_restore")?;
        let state = (
            p.mode,
            p.report_json.as_str(),
            (p.area_gain_cm2, p.volume_difference_cm3, p.volume_cm3),
            (
                p.vertices_after.as_ref().map(|a| a.clone_ref(py)),
                p.displacement.as_ref().map(|a| a.clone_ref(py)),
                p.stretch.as_ref().map(|a| a.clone_ref(py)),
                p.in_region.as_ref().map(|a| a.clone_ref(py)),
            ),
        )
            .into_pyobject(py)?;
        Ok((restore, state))
    }

    fn __repr__(&self) -> String {
        match (self.area_gain_cm2, self.volume_cm3) {
            (Some(gain), Some(volume)) => format!(
                "Plan(mode={:?}, volume_cm3={volume:.2}, area_gain_cm2={gain:.3})",
                self.mode
            ),
            _ => format!("Plan(mode={:?})", self.mode),
        }
    }
}

/// The arrays of a pickled plan: after, displacement, stretch, in region.
type PlanArrays = (
    Option<Py<PyArray2<f64>>>,
    Option<Py<PyArray1<f64>>>,
    Option<Py<PyArray1<f64>>>,
    Option<Py<PyArray1<f64>>>,
);

/// A `Plan` from its pickled state (`Plan.__reduce__`).
#[pyfunction]
pub fn _plan_restore(
    py: Python<'_>,
    mode: &str,
    report_json: String,
    figures: (Option<f64>, Option<f64>, Option<f64>),
    fields: PlanArrays,
) -> PyResult<Plan> {
    let mode = ["single", "sweep", "target-gain", "expansion"]
        .into_iter()
        .find(|m| *m == mode)
        .ok_or_else(|| usage(py, Some("mode"), format!("no planning mode {mode:?}")))?;
    let report = py
        .import("json")?
        .call_method1("loads", (&report_json,))?
        .unbind();
    let (vertices_after, displacement, stretch, in_region) = fields;
    Ok(Plan {
        mode,
        report,
        report_json,
        area_gain_cm2: figures.0,
        volume_difference_cm3: figures.1,
        volume_cm3: figures.2,
        vertices_after,
        displacement,
        stretch,
        in_region,
    })
}

/// The request's field names (`PlanRequest`'s JSON names), in the order the JSON has them.
#[pyfunction]
pub fn _request_fields() -> Vec<String> {
    request_fields()
}

fn request_fields() -> Vec<String> {
    match serde_json::to_value(PlanRequest::default()) {
        Ok(serde_json::Value::Object(map)) => map.keys().cloned().collect(),
        _ => Vec::new(),
    }
}

/// The job of `job_json` (a `JobSpec` in JSON), with every unknown or ill-typed request member
/// refused by name (`PlanError` of kind `usage` with its `.field`).
fn job_of(py: Python<'_>, job_json: &str, shipped: Option<(Shipped, u32)>) -> PyResult<JobSpec> {
    let mut job: serde_json::Value = serde_json::from_str(job_json)
        .map_err(|e| usage(py, None, format!("the job's JSON does not parse: {e}")))?;
    let known = request_fields();
    if let Some(request) = job.get_mut("request").and_then(|r| r.as_object_mut()) {
        for (name, value) in request.iter() {
            if !known.iter().any(|k| k == name) {
                return Err(usage(
                    py,
                    Some(name),
                    format!(
                        "`{name}` is not a request field; the fields are: {}",
                        known.join(", ")
                    ),
                ));
            }
            let alone = serde_json::json!({ name.clone(): value.clone() });
            if let Err(e) = serde_json::from_value::<PlanRequest>(alone) {
                return Err(usage(py, Some(name), format!("`{name}`: {e}")));
            }
        }
        // A shipped patch runs at its suggested vertex when no placement is given (the plane
        // runs at its centre, the planner's default).
        if let Some((Shipped::Chest | Shipped::Head, vertex)) = shipped {
            let placed = ["vertex", "at"]
                .iter()
                .any(|k| request.get(*k).is_some_and(|v| !v.is_null()));
            if !placed {
                request.insert("vertex".to_owned(), serde_json::json!(vertex));
            }
        }
    }
    serde_json::from_value(job).map_err(|e| usage(py, None, format!("the job: {e}")))
}

/// Runs a job (its JSON: `{"mode": …, "request": {…}, "volumes_cm3": […], …}`, tissue-planner's
/// `JobSpec`) on `patient` with the GIL released, calling `progress(step, max_steps, settle)`
/// on this thread about every 20 ms while it runs (module docs).
#[pyfunction]
#[pyo3(signature = (patient, job_json, progress = None))]
pub fn _run(
    py: Python<'_>,
    patient: &Bound<'_, Patient>,
    job_json: &str,
    progress: Option<Bound<'_, PyAny>>,
) -> PyResult<Plan> {
    let patient = patient.get();
    let shipped = patient
        .shipped
        .map(|s| (s, s.suggested_vertex(&patient.patient.file)));
    let spec = job_of(py, job_json, shipped)?;
    let finished = run(py, Arc::clone(&patient.patient), spec, progress.as_ref())?;
    plan_of(py, finished)
}

/// What the job's thread hands back.
type End = Result<Finished, Stopped>;

fn run(
    py: Python<'_>,
    patient: Arc<tissue_planner::Patient>,
    spec: JobSpec,
    progress: Option<&Bound<'_, PyAny>>,
) -> PyResult<Finished> {
    let cancel = CancelToken::new();
    let latest: Arc<Mutex<Option<ProgressEvent>>> = Arc::default();
    let (send, receive) = crossbeam_channel::bounded::<End>(1);
    let worker = {
        let (cancel, latest) = (cancel.clone(), Arc::clone(&latest));
        std::thread::Builder::new()
            .name("tissue-python-job".into())
            .spawn(move || {
                let end = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                    job(&patient, &spec, &cancel, &latest)
                }))
                .unwrap_or_else(|_| {
                    Err(Stopped::Failed(PlanError::new(
                        ErrorKind::Run,
                        "the planning job panicked (a bug, please report it)",
                    )))
                });
                let _ = send.send(end);
            })
            .map_err(|e| bug(py, format!("cannot start the job's thread: {e}")))?
    };
    let mut shown: Option<ProgressEvent> = None;
    loop {
        let got = py.detach(|| receive.recv_timeout(POLL));
        match got {
            Ok(end) => {
                // The thread has sent its end: it is returning.
                let _ = py.detach(|| worker.join());
                return end.map_err(|stopped| plan_error(py, &PlanError::from(stopped)));
            }
            Err(RecvTimeoutError::Disconnected) => {
                return Err(bug(py, "the job's thread ended without a result"));
            }
            Err(RecvTimeoutError::Timeout) => {}
        }
        if let Err(e) = py.check_signals() {
            // Ctrl-C: stop the job (its thread ends within one step on its own) and raise now.
            cancel.cancel();
            return Err(e);
        }
        let Some(callback) = progress else { continue };
        let newest = latest.lock().ok().and_then(|p| *p);
        let Some(p) = newest.filter(|p| shown.is_none_or(|s| s != *p)) else {
            continue;
        };
        shown = Some(p);
        match callback.call1((p.step, p.max_steps, p.settle)) {
            Ok(answer) => {
                if answer.is(&*pyo3::types::PyBool::new(py, false)) {
                    cancel.cancel();
                }
            }
            Err(e) => {
                cancel.cancel();
                return Err(e);
            }
        }
    }
}

/// The job, on its own thread: placed, planned and run to its end.
fn job(
    patient: &tissue_planner::Patient,
    spec: &JobSpec,
    cancel: &CancelToken,
    latest: &Mutex<Option<ProgressEvent>>,
) -> End {
    let scenario = Scenario::new(patient.clone(), spec.request.clone())?;
    if cancel.is_cancelled() {
        return Err(Stopped::Cancelled { steps: 0 });
    }
    let planned = spec.plan(&scenario)?;
    planned.run(&scenario, Tool::Python, cancel, |p| {
        if let Ok(mut slot) = latest.lock() {
            *slot = Some(*p);
        }
    })
}

fn plan_of(py: Python<'_>, finished: Finished) -> PyResult<Plan> {
    let report_json = finished.report.to_json().map_err(|e| plan_error(py, &e))?;
    let report = py
        .import("json")?
        .call_method1("loads", (&report_json,))?
        .unbind();
    let (mode, gain, difference, volume) = match &finished.report {
        JobReport::Single(r) => (
            "single",
            Some(r.body.area_gain_cm2),
            Some(r.body.volume_difference_cm3),
            Some(r.inputs.volume_cm3),
        ),
        JobReport::Sweep(_) => ("sweep", None, None, None),
        JobReport::TargetGain(r) => (
            "target-gain",
            Some(r.body.area_gain_cm2),
            None,
            Some(r.body.volume_cm3),
        ),
        JobReport::Expansion(_) => ("expansion", None, None, None),
    };
    let mut plan = Plan {
        mode,
        report,
        report_json,
        area_gain_cm2: gain,
        volume_difference_cm3: difference,
        volume_cm3: volume,
        vertices_after: None,
        displacement: None,
        stretch: None,
        in_region: None,
    };
    if let Some(p) = &finished.patient {
        plan.vertices_after = Some(arrays::positions_out(py, p.after.positions())?.unbind());
        plan.displacement = Some(arrays::field_out(py, &p.displacement).unbind());
        plan.stretch = Some(arrays::field_out(py, &p.stretch).unbind());
        plan.in_region = Some(arrays::field_out(py, &p.in_region).unbind());
    }
    Ok(plan)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The keywords the package takes are the request's JSON names, placement included, and
    /// each one parses on its own (how `job_of` finds the field a bad value is in).
    #[test]
    fn the_request_fields_are_the_json_names_and_parse_alone() {
        let fields = request_fields();
        for name in [
            "vertex",
            "at",
            "volume_cm3",
            "diameter_cm",
            "expand_weeks",
            "solver",
        ] {
            assert!(fields.iter().any(|f| f == name), "{name}: {fields:?}");
        }
        let defaults = serde_json::to_value(PlanRequest::default()).unwrap_or_default();
        for name in &fields {
            let alone = serde_json::json!({ name.clone(): defaults[name].clone() });
            let parsed = serde_json::from_value::<PlanRequest>(alone);
            assert_eq!(parsed.ok(), Some(PlanRequest::default()), "{name}");
        }
    }
}
