//! The trainer: a `Body` (tissue-scenes' `Session` on a tissue-pbd soft body, as the `trainer`,
//! the studio and the C ABI drive it), stepped by the caller with the GIL released, with its
//! contact `Tool`s (posed by the caller; their force from the last step's force model, N), the
//! probe's grasp, the scalpel, the needle and the events.
//!
//! Frame and units: cm, y up; the organ lies on a tray whose top is y = 0 (the appendix on a
//! floor at y = 0, its base pinned); forces in newtons, the tissue's force on the tool.

use std::path::PathBuf;
use std::sync::{Mutex, MutexGuard};

use glam::{Quat, Vec3};
use numpy::{PyArray1, PyArray2};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use tissue_mesh::{TetMesh, TriMesh};
use tissue_pbd::{Pose, ToolShape};
use tissue_scenes::{
    Organ, SceneError, SelfCollision, Session, SessionOptions, ShippedOrgan, TrainerEvent,
};

use crate::arrays;
use crate::errors::{bad_array, bug, mesh_io_error, scene_error, tool_error};

/// A trainee's soft body: a session on one organ. Every method may be called from any thread;
/// the body's state sits behind one lock (a step holds it for the whole step, with the GIL
/// released).
#[pyclass(module = "tissue._tissue", frozen)]
pub struct Body {
    sim: Mutex<Sim>,
}

struct Sim {
    session: Session,
    /// Events not yet taken by `events()`.
    events: Vec<TrainerEvent>,
    /// The newest pose the caller set, per tool (where its force is evaluated).
    poses: Vec<Pose>,
}

impl Body {
    fn new(py: Python<'_>, organ: &Organ) -> PyResult<Self> {
        let session = py
            .detach(|| Session::new(organ, SessionOptions::default()))
            .map_err(|e| scene_error(py, &e, None))?;
        Ok(Body {
            sim: Mutex::new(Sim {
                session,
                events: Vec::new(),
                poses: Vec::new(),
            }),
        })
    }

    fn sim(&self, py: Python<'_>) -> PyResult<MutexGuard<'_, Sim>> {
        use std::sync::TryLockError;
        loop {
            match self.sim.try_lock() {
                Ok(guard) => return Ok(guard),
                Err(TryLockError::Poisoned(_)) => {
                    return Err(bug(py, "the body's lock is poisoned (a step panicked)"))
                }
                // Another thread steps: wait for it without the GIL (its step does not need
                // the GIL, but this thread's caller may hold other Python threads up).
                Err(TryLockError::WouldBlock) => py.detach(|| drop(self.sim.lock())),
            }
        }
    }
}

fn scene<'py>(py: Python<'py>, field: Option<&'static str>) -> impl Fn(SceneError) -> PyErr + 'py {
    move |e| scene_error(py, &e, field)
}

fn event_dict<'py>(py: Python<'py>, e: &TrainerEvent) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("step", e.step)?;
    d.set_item("kind", e.kind.name())?;
    d.set_item("text", &e.text)?;
    Ok(d)
}

fn pose_of(
    py: Python<'_>,
    rotation: &Bound<'_, PyAny>,
    translation: &Bound<'_, PyAny>,
) -> PyResult<Pose> {
    let np = numpy::get_array_module(py)?;
    let q = np
        .call_method1("asarray", (rotation, "float64"))
        .and_then(|a| a.call_method1("reshape", (-1,)))
        .and_then(|a| a.extract::<Vec<f64>>())
        .map_err(|e| bad_array(py, "pose", format!("the pose's quaternion: {e}")))?;
    let [x, y, z, w] = q[..] else {
        return Err(bad_array(
            py,
            "pose",
            format!(
                "the pose's rotation must be a quaternion (x, y, z, w), got {} numbers",
                q.len()
            ),
        ));
    };
    let rotation = Quat::from_xyzw(x as f32, y as f32, z as f32, w as f32);
    let translation = arrays::point(translation, "pose")?;
    if !rotation.is_finite() || (rotation.length() - 1.0).abs() > 1e-3 {
        return Err(bad_array(
            py,
            "pose",
            format!("the pose needs a unit quaternion (x, y, z, w), got {rotation}"),
        ));
    }
    Ok(Pose::new(rotation.normalize(), translation))
}

/// The organ in a file: `.obj`, `.ply`, `.stl` a closed surface (filled with tetrahedra);
/// `.vtu`, `.msh`, `.node`/`.ele` tets; a legacy `.vtk` tets when it has tetrahedra, else a
/// surface (tissue-capi's `tissue_mesh_load`, the trainer's `--surface` and `--organ`).
fn organ_from_file(py: Python<'_>, path: &std::path::Path) -> PyResult<Organ> {
    let name = path.display().to_string();
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .unwrap_or_default();
    enum Read {
        Surface(TriMesh),
        Tets(TetMesh),
    }
    let read = py.detach(|| match ext.as_str() {
        "obj" | "ply" | "stl" => tissue_meshio::read_surface(path).map(Read::Surface),
        "vtk" => match tissue_meshio::read_tets(path) {
            Ok(m) => Ok(Read::Tets(m)),
            Err(_) => tissue_meshio::read_surface(path).map(Read::Surface),
        },
        _ => tissue_meshio::read_tets(path).map(Read::Tets),
    });
    let read = read.map_err(|e| mesh_io_error(py, &e, "path"))?;
    py.detach(|| match read {
        Read::Surface(m) => Organ::from_surface(&m, &name),
        Read::Tets(m) => Organ::from_tets(&m, &name),
    })
    .map_err(scene(py, Some("path")))
}

#[pymethods]
impl Body {
    /// An organ shipped with the library: `"bunny"` (the Stanford Bunny, 10 cm, on a tray),
    /// `"liver"` (SOFA's liver, 16 cm, on a tray) or `"appendix"` (8 × 2 × 2 cm along x on a
    /// floor at y = 0, its base pinned).
    #[staticmethod]
    fn shipped(py: Python<'_>, name: &str) -> PyResult<Self> {
        let which = ShippedOrgan::from_id(name).ok_or_else(|| {
            tool_error(
                py,
                Some("name"),
                format!("no shipped organ {name:?}: give \"bunny\", \"liver\" or \"appendix\""),
            )
        })?;
        let organ = py
            .detach(|| Organ::shipped(which))
            .map_err(scene(py, Some("name")))?;
        Body::new(py, &organ)
    }

    /// An organ from a file (any format the trainer reads: a closed surface `.obj`, `.ply`,
    /// `.stl`, filled with tetrahedra; tets in `.vtu`, `.msh`, `.vtk`, `.node`), in cm, scaled
    /// so that its largest extent is `size_cm` when given (the trainer's `--size`), set on a
    /// tray.
    #[staticmethod]
    #[pyo3(signature = (path, size_cm = None))]
    fn load(py: Python<'_>, path: PathBuf, size_cm: Option<f32>) -> PyResult<Self> {
        let organ = organ_from_file(py, &path)?;
        let organ = match size_cm {
            Some(size) => organ.scaled_to(size).map_err(scene(py, Some("size_cm")))?,
            None => organ,
        };
        Body::new(py, &organ)
    }

    /// An organ from arrays: `vertices` `(n, 3)` in cm × `cm_per_unit`, and `cells` either
    /// `(m, 4)` tetrahedra or `(m, 3)` triangles of a closed surface (filled with tetrahedra),
    /// set on a tray.
    #[staticmethod]
    #[pyo3(signature = (vertices, tets_or_triangles, cm_per_unit = 1.0))]
    fn from_mesh(
        py: Python<'_>,
        vertices: &Bound<'_, PyAny>,
        tets_or_triangles: &Bound<'_, PyAny>,
        cm_per_unit: f32,
    ) -> PyResult<Self> {
        if !(cm_per_unit.is_finite() && cm_per_unit > 0.0) {
            return Err(bad_array(
                py,
                "cm_per_unit",
                format!("`cm_per_unit` must be a positive scale (1 for cm, 0.1 for mm), got {cm_per_unit}"),
            ));
        }
        let positions: Vec<Vec3> = arrays::points(vertices, "vertices")?
            .into_iter()
            .map(|p| p * cm_per_unit)
            .collect();
        let (flat, k) = arrays::indices(tets_or_triangles, "tets_or_triangles", &[3, 4])?;
        let field = "tets_or_triangles";
        enum Failed {
            Invalid(String),
            Scene(SceneError),
        }
        let organ = py.detach(|| {
            if k == 4 {
                let tets = TetMesh::new(positions, arrays::quads(&flat))
                    .map_err(|e| Failed::Invalid(format!("not a valid tet mesh: {e}")))?;
                Organ::from_tets(&tets, "arrays").map_err(Failed::Scene)
            } else {
                let surface = TriMesh::new(positions, arrays::triples(&flat))
                    .map_err(|e| Failed::Invalid(format!("not a valid surface: {e}")))?;
                Organ::from_surface(&surface, "arrays").map_err(Failed::Scene)
            }
        });
        let organ = organ.map_err(|e| match e {
            Failed::Scene(e) => scene_error(py, &e, Some(field)),
            Failed::Invalid(text) => bad_array(py, field, text),
        })?;
        Body::new(py, &organ)
    }

    /// Takes `n` steps of 10 ms (the GIL released): the tools move to the poses last set, the
    /// grasp follows its target, one queued scalpel segment is cut per step. Returns the number
    /// of events they added (read them with `events()`).
    #[pyo3(signature = (n = 1))]
    fn step(&self, py: Python<'_>, n: usize) -> PyResult<usize> {
        let mut added = 0;
        let mut left = n;
        while left > 0 {
            // In batches, checking for Ctrl-C between them.
            let batch = left.min(10);
            // A panic in the solver is a bug, raised as `TissueError` (kind `bug`), never
            // PyO3's `PanicException`; the body's lock is then poisoned and refuses further use.
            let done = py.detach(|| {
                std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                    let mut sim = self
                        .sim
                        .lock()
                        .map_err(|_| SceneError::Tool("the body's lock is poisoned".to_owned()))?;
                    let mut count = 0;
                    for _ in 0..batch {
                        let events = sim.session.step()?;
                        count += events.len();
                        sim.events.extend(events);
                    }
                    Ok::<usize, SceneError>(count)
                }))
            });
            let done = done.map_err(|_| {
                bug(
                    py,
                    "the trainer's step panicked (a bug: please report it with the organ and \
                     the tool moves); this body can no longer be used",
                )
            })?;
            added += done.map_err(scene(py, None))?;
            left -= batch;
            py.check_signals()?;
        }
        Ok(added)
    }

    /// Every node's position, cm, float64 `(n, 3)` (the surface's triangles index these); a new
    /// array each time.
    #[getter]
    fn positions<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let sim = self.sim(py)?;
        arrays::positions_out(py, sim.session.positions())
    }

    /// The surface's triangles (node indices, counter-clockwise seen from outside), int64
    /// `(m, 3)`; they change with cuts and sutures.
    #[getter]
    fn triangles<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<i64>>> {
        let sim = self.sim(py)?;
        arrays::indices_out(py, sim.session.surface())
    }

    /// The tetrahedra (node indices), int64 `(m, 4)`.
    #[getter]
    fn tets<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<i64>>> {
        let sim = self.sim(py)?;
        arrays::indices_out(py, sim.session.body().tets())
    }

    /// The body's figures: `label`, `nodes`, `tets`, `triangles`, `steps`, `surface_version`
    /// (changes with cuts and sutures), `volume_drift` (V/V₀ − 1), `step_ms_median`,
    /// `step_ms_p99` (ms), `time_step_s`, `tools`, `tray_side_cm`, `up` (`"y"`),
    /// `self_collision` (on?), `self_contacts` and `self_contacts_active` (the last step's
    /// self-contacts of the surface, and those the solver pushed apart).
    #[getter]
    fn info<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let sim = self.sim(py)?;
        let s = &sim.session;
        let (median, p99) = s.step_ms();
        let d = PyDict::new(py);
        d.set_item("label", s.label())?;
        d.set_item("nodes", s.body().node_count())?;
        d.set_item("tets", s.body().tets().len())?;
        d.set_item("triangles", s.surface().len())?;
        d.set_item("steps", s.steps())?;
        d.set_item("surface_version", s.surface_version())?;
        d.set_item("volume_drift", s.volume_drift())?;
        d.set_item("step_ms_median", median)?;
        d.set_item("step_ms_p99", p99)?;
        d.set_item("time_step_s", f64::from(s.body().settings().dt))?;
        d.set_item("tools", s.tool_count())?;
        d.set_item("tray_side_cm", s.tray_side())?;
        d.set_item("up", "y")?;
        let (found, active) = s.self_contacts();
        d.set_item("self_collision", s.options().self_collision.is_some())?;
        d.set_item("self_contacts", found)?;
        d.set_item("self_contacts_active", active)?;
        Ok(d)
    }

    /// Self-collision of the organ's surface, cut walls included (tissue-scenes'
    /// `SessionOptions::self_collision`): on by default, as in the trainer, the studio and the
    /// C ABI; set `False` to switch it off for comparison (a step costs about half as much), `True`
    /// to switch it on again (from the next step on).
    #[getter]
    fn self_collision(&self, py: Python<'_>) -> PyResult<bool> {
        Ok(self.sim(py)?.session.options().self_collision.is_some())
    }

    #[setter]
    fn set_self_collision(&self, py: Python<'_>, on: bool) -> PyResult<()> {
        let settings = on.then(SelfCollision::default);
        self.sim(py)?
            .session
            .set_self_collision(settings)
            .map_err(scene(py, Some("self_collision")))
    }

    /// The number of pairs of surface triangles that intersect now, counted exactly: 0 when the
    /// organ does not pass through itself (the two walls of a fresh cut touch and count until
    /// the steps part them).
    fn self_intersections(&self, py: Python<'_>) -> PyResult<usize> {
        self.sim(py)?
            .session
            .self_intersections()
            .map_err(scene(py, None))
    }

    /// Adds a capsule tool (a probe's tip, a needle, a shaft): the points within `radius` cm of
    /// the segment `a`–`b` (cm, in the tool's frame), placed at `pose` (`(quaternion (x, y, z,
    /// w), translation cm)`; default: identity, so `a` and `b` are where it is). It pushes the
    /// tissue from the next step on.
    #[pyo3(signature = (a, b, radius, pose = None))]
    fn add_capsule(
        slf: &Bound<'_, Self>,
        a: &Bound<'_, PyAny>,
        b: &Bound<'_, PyAny>,
        radius: f32,
        pose: Option<(Bound<'_, PyAny>, Bound<'_, PyAny>)>,
    ) -> PyResult<Tool> {
        let shape = ToolShape::Capsule {
            a: arrays::point(a, "a")?,
            b: arrays::point(b, "b")?,
            radius,
        };
        add_tool(slf, shape, pose)
    }

    /// Adds a blade tool: the points within `thickness / 2` cm of the triangle `a b c` (cm, the
    /// tool's frame), at `pose`. It pushes the tissue like any tool (it does not cut: see
    /// `cut`).
    #[pyo3(signature = (a, b, c, thickness, pose = None))]
    fn add_blade(
        slf: &Bound<'_, Self>,
        a: &Bound<'_, PyAny>,
        b: &Bound<'_, PyAny>,
        c: &Bound<'_, PyAny>,
        thickness: f32,
        pose: Option<(Bound<'_, PyAny>, Bound<'_, PyAny>)>,
    ) -> PyResult<Tool> {
        let shape = ToolShape::Blade {
            a: arrays::point(a, "a")?,
            b: arrays::point(b, "b")?,
            c: arrays::point(c, "c")?,
            thickness,
        };
        add_tool(slf, shape, pose)
    }

    /// Grasps the surface near `point` (cm): the free surface nodes within 0.6 cm, at least the
    /// corners of surface triangle `triangle` (default: the one whose centroid is nearest),
    /// follow the probe's target (`drag`) until `release`. Returns the event.
    #[pyo3(signature = (point, triangle = None))]
    fn grab<'py>(
        &self,
        py: Python<'py>,
        point: &Bound<'py, PyAny>,
        triangle: Option<usize>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let p = arrays::point(point, "point")?;
        let mut sim = self.sim(py)?;
        let t = match triangle {
            Some(t) => t,
            None => nearest_triangle(&sim.session, p),
        };
        let e = sim.session.grab(p, t).map_err(scene(py, Some("point")))?;
        let d = event_dict(py, &e)?;
        sim.events.push(e);
        Ok(d)
    }

    /// Moves the grasped point towards `target` (cm) from the next step on (nothing while
    /// nothing is grasped), clamped into the tools' working space.
    fn drag(&self, py: Python<'_>, target: &Bound<'_, PyAny>) -> PyResult<()> {
        let t = arrays::point(target, "target")?;
        self.sim(py)?.session.drag(t);
        Ok(())
    }

    /// Lets go of what the probe grasps (nothing when nothing is).
    fn release(&self, py: Python<'_>) -> PyResult<()> {
        let mut sim = self.sim(py)?;
        if let Some(e) = sim.session.release().map_err(scene(py, None))? {
            sim.events.push(e);
        }
        Ok(())
    }

    /// The tissue's force on the grasp at the last step, N, float64 `(3,)` (zero when nothing
    /// is grasped).
    #[getter]
    fn grasp_force<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let f = self.sim(py)?.session.tool_force();
        Ok(arrays::vec3_out(py, f))
    }

    /// Queues a scalpel cut along `path` (`(k, 3)` surface points, cm) seen along `view_dir`:
    /// the blade's plane holds the path's overall direction and the view; it cuts 1 cm below
    /// the path, one segment (about 0.4 cm) per step. Returns the segments queued; the cut's
    /// events (`cut_advanced`, …) come with the steps.
    fn cut(
        &self,
        py: Python<'_>,
        path: &Bound<'_, PyAny>,
        view_dir: &Bound<'_, PyAny>,
    ) -> PyResult<usize> {
        let points = arrays::points(path, "path")?;
        let view = arrays::point(view_dir, "view_dir")?;
        let mut sim = self.sim(py)?;
        sim.session
            .cut(&points, view)
            .map_err(scene(py, Some("path")))
    }

    /// Places a suture between surface points `a` and `b` (cm) on the two sides of a wound: a
    /// needle passes below them and the wound's walls are linked. Returns the event
    /// (`suture_placed`, or `suture_missed` when the needle crossed no wound), also queued.
    fn suture<'py>(
        &self,
        py: Python<'py>,
        a: &Bound<'py, PyAny>,
        b: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let (a, b) = (arrays::point(a, "a")?, arrays::point(b, "b")?);
        let mut sim = self.sim(py)?;
        let e = sim.session.suture(a, b).map_err(scene(py, Some("a")))?;
        let d = event_dict(py, &e)?;
        sim.events.push(e);
        Ok(d)
    }

    /// Plays the organ's demonstration from the next step on (the studio's: the appendix
    /// procedure, or a probe pressed and dragged across a tray's organ; its probe becomes the
    /// next tool).
    fn play(&self, py: Python<'_>) -> PyResult<()> {
        let mut sim = self.sim(py)?;
        let started = sim.session.play().map_err(scene(py, None))?;
        sim.events.push(started);
        for id in sim.poses.len()..sim.session.tool_count() {
            let pose = sim
                .session
                .body()
                .tool(id)
                .map(|t| t.pose())
                .unwrap_or_default();
            sim.poses.push(pose);
        }
        Ok(())
    }

    /// The events since the last call, oldest first, as dicts `{"step", "kind", "text"}`
    /// (`kind`: `cut_advanced`, `piece_detached`, `suture_placed`, `suture_removed`,
    /// `suture_missed`, `grabbed`, `released`, `demo_started`, `demo_finished`, `surgery`).
    fn events<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyList>> {
        let taken = std::mem::take(&mut self.sim(py)?.events);
        let list = PyList::empty(py);
        for e in &taken {
            list.append(event_dict(py, e)?)?;
        }
        Ok(list)
    }

    fn __repr__(&self, py: Python<'_>) -> PyResult<String> {
        let sim = self.sim(py)?;
        let s = &sim.session;
        Ok(format!(
            "Body({:?}, {} nodes, {} tets, {} steps)",
            s.label(),
            s.body().node_count(),
            s.body().tets().len(),
            s.steps()
        ))
    }
}

fn nearest_triangle(session: &Session, p: Vec3) -> usize {
    let x = session.positions();
    session
        .surface()
        .iter()
        .enumerate()
        .map(|(i, t)| {
            let c = t.iter().map(|&n| Vec3::from(x[n as usize])).sum::<Vec3>() / 3.0;
            (i, c.distance_squared(p))
        })
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .map_or(0, |(i, _)| i)
}

fn add_tool(
    body: &Bound<'_, Body>,
    shape: ToolShape,
    pose: Option<(Bound<'_, PyAny>, Bound<'_, PyAny>)>,
) -> PyResult<Tool> {
    let py = body.py();
    let pose = match pose {
        Some((r, t)) => pose_of(py, &r, &t)?,
        None => Pose::default(),
    };
    let mut sim = body.get().sim(py)?;
    let id = sim
        .session
        .add_tool(shape, pose)
        .map_err(scene(py, Some("shape")))?;
    while sim.poses.len() <= id {
        sim.poses.push(pose);
    }
    sim.poses[id] = pose;
    Ok(Tool {
        body: body.clone().unbind(),
        id,
    })
}

/// A pose as NumPy arrays: the quaternion (x, y, z, w) and the translation (cm).
type PoseArrays<'py> = (Bound<'py, PyArray1<f64>>, Bound<'py, PyArray1<f64>>);

/// A contact tool of a `Body`: its pose (set by the caller; the next step sweeps it there) and
/// the tissue's force on it.
#[pyclass(module = "tissue._tissue", frozen)]
pub struct Tool {
    body: Py<Body>,
    id: usize,
}

#[pymethods]
impl Tool {
    /// The tool's id in its body (0, 1, … in the order tools were added).
    #[getter]
    fn id(&self) -> usize {
        self.id
    }

    /// The newest pose set: `(quaternion (x, y, z, w), translation cm)`, float64 arrays.
    #[getter]
    fn pose<'py>(&self, py: Python<'py>) -> PyResult<PoseArrays<'py>> {
        let sim = self.body.get().sim(py)?;
        let p = sim.poses.get(self.id).copied().unwrap_or_default();
        Ok((
            PyArray1::from_slice(py, &p.rotation.to_array().map(f64::from)),
            arrays::vec3_out(py, p.translation),
        ))
    }

    /// Sets the pose `(quaternion (x, y, z, w), translation cm)`: the next step sweeps the tool
    /// from its last pose to it, and `force` is evaluated there from now on.
    #[setter]
    fn set_pose(&self, py: Python<'_>, pose: (Bound<'_, PyAny>, Bound<'_, PyAny>)) -> PyResult<()> {
        let p = pose_of(py, &pose.0, &pose.1)?;
        let mut sim = self.body.get().sim(py)?;
        sim.session
            .set_tool_pose(self.id, p)
            .map_err(scene(py, Some("pose")))?;
        if let Some(slot) = sim.poses.get_mut(self.id) {
            *slot = p;
        }
        Ok(())
    }

    /// The tissue's force on the tool, N, float64 `(3,)` (world axes, y up): the last step's
    /// contact force model evaluated at the newest pose (it follows the pose between steps).
    #[getter]
    fn force<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let sim = self.body.get().sim(py)?;
        let at = sim
            .poses
            .get(self.id)
            .copied()
            .unwrap_or_default()
            .translation;
        let f = sim
            .session
            .contact_force_model(self.id)
            .map(|m| m.evaluate(at))
            .unwrap_or(Vec3::ZERO);
        Ok(arrays::vec3_out(py, f))
    }

    fn __repr__(&self) -> String {
        format!("Tool(id={})", self.id)
    }
}
