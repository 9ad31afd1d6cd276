//! The run: settle, press, drag; per-step wall time, volume drift, frames.

use std::path::{Path, PathBuf};
use std::time::Instant;

use glam::Vec3;
use tissue_mesh::{Aabb, TriMesh};
use tissue_meshio::{FieldValues, VertexField};
use tissue_pbd::{ContactSource, SoftBody, ToolShape, DYN_PER_NEWTON};
use tissue_render::{draw_text, render, Camera, ColorScale, Image, Rgb, Surface, Viewport};
use tissue_scenes::{SceneError, Script};

use crate::cli::{Cli, FrameFormat};
use crate::failure::{self, Exit, Failure};
use crate::scene::Scene;

/// What the run measured.
pub struct Summary {
    /// Wall time of every step (s), in order.
    pub step_seconds: Vec<f64>,
    /// Index of the first step with the probe moving.
    pub tool_from: usize,
    /// `V/V₀` at the end.
    pub volume_ratio: f64,
    /// Largest `|V/V₀ − 1|` after any step.
    pub worst_drift: f64,
    /// The organ's height (extent along gravity, cm): as loaded and after settling.
    pub height: (f32, f32),
    /// The tets' volume errors at the end (the local compression and swelling that the total
    /// drift can hide): `|V_t/V_t,rest − 1|` median and 90th percentile, and the volume-weighted
    /// mean `Σ|V_t − V_t,rest| / Σ V_t,rest`.
    pub tet_error: [f64; 3],
    /// Contacts with the tray and the probe at the end.
    pub contacts: (usize, usize),
    /// The force of the tissue on the probe (N, from [`SoftBody::tool_force`]): the largest
    /// magnitude over all steps and the last step's vector.
    pub probe_force: (f32, Vec3),
    /// Frames written (files per frame counted once).
    pub frames: usize,
}

/// Runs the scenario.
pub fn run(cli: &Cli, scene: &mut Scene) -> Result<Summary, Failure> {
    let mut frames = match &cli.frames {
        Some(dir) => Some(Frames::new(cli, scene, dir)?),
        None => None,
    };
    let settle = scene.script.plan().settle;
    let total = scene.script.steps();
    let tool = scene.script.tool();
    let mut step_seconds = Vec::with_capacity(total);
    let rest = scene.body.rest_volume();
    let mut worst_drift = 0.0f64;
    let (mut largest_force, mut force) = (0.0f32, Vec3::ZERO);
    let loaded_height = height(&scene.body);
    let mut settled_height = loaded_height;
    if let Some(f) = frames.as_mut() {
        f.write(scene, 0, None)?;
    }
    for step in 1..=total {
        if step == settle + 1 {
            settled_height = height(&scene.body);
            if let Some(f) = frames.as_mut() {
                f.settled(scene);
            }
        }
        scene
            .script
            .before_step(step, &mut scene.body)
            .map_err(|e| match e {
                SceneError::Tool(m) => Failure::new(
                    Exit::Parameters,
                    format!(
                        "{m} (--waypoint; the organ is about --size {} cm wide)",
                        cli.size
                    ),
                ),
                e => failure::from_scene(&e),
            })?;
        let t = Instant::now();
        scene.body.step().map_err(|e| failure::from_pbd(&e))?;
        step_seconds.push(t.elapsed().as_secs_f64());
        force = scene
            .body
            .tool_force(tool)
            .map_err(|e| failure::from_pbd(&e))?
            / DYN_PER_NEWTON;
        largest_force = largest_force.max(force.length());
        worst_drift = worst_drift.max((scene.body.volume() / rest - 1.0).abs());
        if let Some(f) = frames.as_mut() {
            if step % cli.every as usize == 0 || step == total {
                f.write(
                    scene,
                    step,
                    Some(step as f64 * scene.body.settings().dt as f64),
                )?;
            }
        }
    }
    let tray = scene
        .body
        .contacts()
        .iter()
        .filter(|c| matches!(c.source, ContactSource::Collider(_)))
        .count();
    Ok(Summary {
        step_seconds,
        tool_from: settle,
        volume_ratio: scene.body.volume() / rest,
        worst_drift,
        height: (loaded_height, settled_height),
        tet_error: tet_error(&scene.body),
        contacts: (tray, scene.body.contacts().len() - tray),
        probe_force: (largest_force, force),
        frames: frames.map_or(0, |f| f.written),
    })
}

/// The body's extent along gravity (cm).
fn height(body: &SoftBody) -> f32 {
    let up = -body.settings().gravity.normalize_or(Vec3::NEG_Y);
    let (lo, hi) = body
        .positions()
        .iter()
        .fold((f32::MAX, f32::MIN), |(lo, hi), x| {
            let h = up.dot(Vec3::from(*x));
            (lo.min(h), hi.max(h))
        });
    hi - lo
}

/// The tets' `|V/V_rest − 1|`: median and 90th percentile; and `Σ|V − V_rest| / ΣV_rest`.
fn tet_error(body: &SoftBody) -> [f64; 3] {
    let x = body.positions();
    // Per tet: |V/V_rest − 1| and |V − V_rest| (cm³), in one pass.
    let (mut e, mut off) = (Vec::with_capacity(body.tets().len()), 0.0f64);
    for (t, &rest) in body.tets().iter().zip(body.tet_rest_volumes()) {
        let [a, b, c, d] = t.map(|i| x[i as usize].as_dvec3());
        let dv = ((b - a).cross(c - a).dot(d - a) / 6.0 - rest as f64).abs();
        e.push(dv / rest as f64);
        off += dv;
    }
    if e.is_empty() {
        return [0.0; 3];
    }
    e.sort_unstable_by(f64::total_cmp);
    let at = |q: f64| e[((e.len() - 1) as f64 * q).round() as usize];
    [at(0.5), at(0.9), off / body.rest_volume()]
}

/// The frame writer: the organ's boundary surface (its own vertex numbering), the probe's mesh,
/// a fixed camera.
struct Frames {
    dir: PathBuf,
    format: FrameFormat,
    png: bool,
    /// Body node of each surface vertex.
    nodes: Vec<u32>,
    surface: TriMesh,
    /// Where displacements are measured from.
    rest: Vec<Vec3>,
    probe: TriMesh,
    camera: Camera,
    scale: ColorScale,
    written: usize,
    /// What `rest` is: "rest" (as loaded) or "settled" (after the settling steps).
    since: &'static str,
}

impl Frames {
    fn new(cli: &Cli, scene: &Scene, dir: &Path) -> Result<Self, Failure> {
        std::fs::create_dir_all(dir)
            .map_err(|e| Failure::output(&format!("frames folder {}", dir.display()), e))?;
        let faces = scene.organ.mesh.boundary_faces();
        let mut local = vec![u32::MAX; scene.organ.mesh.vertex_count()];
        let mut nodes = Vec::new();
        let triangles: Vec<[u32; 3]> = faces
            .iter()
            .map(|f| {
                f.map(|v| {
                    if local[v as usize] == u32::MAX {
                        local[v as usize] = nodes.len() as u32;
                        nodes.push(v);
                    }
                    local[v as usize]
                })
            })
            .collect();
        let rest: Vec<Vec3> = nodes
            .iter()
            .map(|&n| scene.organ.mesh.positions()[n as usize])
            .collect();
        let surface = TriMesh::new(rest.clone(), triangles).map_err(|e| {
            Failure::new(
                Exit::Mesh,
                format!("the organ's boundary is not a valid surface for the frames: {e}"),
            )
        })?;
        let probe = capsule_mesh(&scene.probe).map_err(|e| Failure::output("probe picture", e))?;
        let b = surface.bounding_box();
        let pad = Vec3::splat(0.15 * b.size().max_element());
        let bounds = Aabb {
            min: b.min - pad,
            max: b.max + pad,
        };
        let camera = Camera::orthographic(bounds, Vec3::new(-0.8, -0.7, -1.0), Vec3::Y)
            .map_err(|e| Failure::output("picture", e))?;
        let scale = ColorScale::new(0.0, (cli.depth + 0.5).max(0.5))
            .map_err(|e| Failure::output("picture", e))?;
        Ok(Self {
            dir: dir.to_path_buf(),
            format: cli.format,
            png: cli.png,
            nodes,
            surface,
            rest,
            probe,
            camera,
            scale,
            written: 0,
            since: "rest",
        })
    }

    /// From now on displacements are measured from the current (settled) shape.
    fn settled(&mut self, scene: &Scene) {
        let x = scene.body.positions();
        self.rest = self.nodes.iter().map(|&n| x[n as usize].into()).collect();
        self.since = "settled";
    }

    fn write(&mut self, scene: &Scene, step: usize, time: Option<f64>) -> Result<(), Failure> {
        let x = scene.body.positions();
        let now: Vec<Vec3> = self.nodes.iter().map(|&n| x[n as usize].into()).collect();
        let displacement: Vec<f32> = now
            .iter()
            .zip(&self.rest)
            .map(|(a, b)| a.distance(*b))
            .collect();
        let mesh = self
            .surface
            .with_positions(now)
            .map_err(|e| Failure::new(Exit::Run, format!("the surface became invalid: {e}")))?;
        let stem = self.dir.join(format!("frame_{step:05}"));
        let path = match self.format {
            FrameFormat::Vtk => stem.with_extension("vtk"),
            FrameFormat::Obj => stem.with_extension("obj"),
        };
        let result = match self.format {
            FrameFormat::Vtk => tissue_meshio::write_vtk(
                &path,
                &mesh,
                &[VertexField {
                    name: "displacement",
                    values: FieldValues::Scalars(&displacement),
                }],
            ),
            FrameFormat::Obj => tissue_meshio::write_obj(&path, &mesh),
        };
        result.map_err(|e| Failure::output(&format!("frame {}", path.display()), e))?;
        if self.png {
            let pose = scene
                .body
                .tool(scene.script.tool())
                .map_err(|e| failure::from_pbd(&e))?
                .pose();
            let probe = self
                .probe
                .with_positions(
                    self.probe
                        .positions()
                        .iter()
                        .map(|&p| pose.transform_point(p))
                        .collect(),
                )
                .map_err(|e| Failure::output("probe picture", e))?;
            let png = stem.with_extension("png");
            let mut image =
                Image::new(640, 480, Rgb::WHITE).map_err(|e| Failure::output("picture", e))?;
            let viewport = Viewport::full(&image);
            render(
                &mut image,
                viewport,
                &self.camera,
                &self.scale,
                &[
                    Surface::new(&mesh).with_field(&displacement),
                    Surface::new(&probe).with_color(Rgb::new(120, 120, 120)),
                ],
            )
            .map_err(|e| Failure::output("picture", e))?;
            let label = format!(
                "step {step} t {:.2} s, moved 0-{:.1} cm since {}",
                time.unwrap_or(0.0),
                self.scale.max(),
                self.since
            );
            draw_text(&mut image, 10, 10, &label, 2, Rgb::BLACK);
            image
                .write_png(&png)
                .map_err(|e| Failure::output(&format!("picture {}", png.display()), e))?;
        }
        self.written += 1;
        Ok(())
    }
}

/// A capsule surface around the probe's axis (tip at the origin, axis +y): a UV sphere whose
/// upper half is lifted by the axis length.
fn capsule_mesh(shape: &ToolShape) -> Result<TriMesh, tissue_mesh::MeshError> {
    let (length, radius) = match *shape {
        ToolShape::Capsule { a, b, radius } => (a.distance(b), radius),
        ToolShape::Blade { thickness, .. } => (0.0, thickness * 0.5),
    };
    let sphere = tissue_mesh::uv_sphere(16, 9, radius)?;
    // Sphere poles are on z; the probe's axis is y.
    let positions = sphere
        .positions()
        .iter()
        .map(|p| Vec3::new(p.x, if p.z > 0.0 { p.z + length } else { p.z }, p.y))
        .collect();
    sphere.with_positions(positions)
}

/// `(median, p99, max)` of `values` (nearest rank).
pub fn percentiles(values: &[f64]) -> (f64, f64, f64) {
    if values.is_empty() {
        return (0.0, 0.0, 0.0);
    }
    let mut v = values.to_vec();
    v.sort_by(f64::total_cmp);
    let rank = |q: f64| v[((q * v.len() as f64).ceil() as usize).clamp(1, v.len()) - 1];
    (rank(0.5), rank(0.99), v[v.len() - 1])
}
