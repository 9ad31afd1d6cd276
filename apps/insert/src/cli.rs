//! The command line: flags, their defaults (taken from the libraries), and the long help with the
//! units, the exit codes and the `--report` JSON contract.

use std::path::PathBuf;

use clap::Parser;
use tissue_planner::{ColorBy, Detect, JobMode, JobSpec, PlanRequest, Rule, Shape, Solver, Unit};

use crate::failure::{Exit, Failure};

/// The library's defaults, read from an empty request.
fn defaults() -> PlanRequest {
    PlanRequest::default()
}

const ABOUT: &str = "Plan a tissue-expander insertion: an incompressible implant is inserted \
under a patch of skin on a patient's surface scan; a mass-spring simulation gives the stretched \
skin, the area gained and the volume.";

const LONG_ABOUT: &str = "\
Plan a tissue-expander insertion: an incompressible implant is inserted under a patch of skin on \
a patient's surface scan; a mass-spring simulation (two tissue layers over the implant) gives the \
stretched skin, the area gained and the volume between the skin before and after.

With no arguments it runs the thesis's Table 2 case: a 100 cm³ round implant of 7 cm diameter \
under the centre of a flat 20 cm × 20 cm skin patch of 65 × 65 vertices (the plane of \
fixtures/plane_20cm_65.obj, generated in code), region radius 5.25 cm, region rule \
touches-vertex, normal +z, tangent +x, every tissue and run parameter at the library's default \
(the defaults shown below are read from the library), and writes its picture to \
insert_table2.png in the current directory.

Your own case: give the scan (--mesh, an open surface patch with normals out of the body), its \
unit (--unit), where the implant goes (--at X,Y,Z or --vertex N) and the implant (--shape, its \
size, --volume). Example with the chest patch shipped in fixtures/ (decimetres):

  insert --mesh fixtures/makehuman_chest_open.obj --unit dm --vertex 2277 \\
         --diameter 6.5 --volume 50 --out chest_after.vtk --report chest.json --png chest.png

UNITS. Inside, everything runs in centimetres, grams and seconds. --at is in the mesh's unit; \
the mesh is scaled to cm on load. Implant sizes, --depth, --radius, --thickness are in cm, \
--volume in cm³ (= mL), --young in kPa, --density in g/cm³. Output meshes (--out) are written \
back in the mesh's unit (as are their displacement fields); the --report JSON and the summary \
are in cm, cm², cm³ and seconds, as their names say.

ORIENTATION. The implant's outward normal is the surface normal at the picked point, snapped to \
the nearest surface point: the area-weighted vertex normals of the nearest triangle, \
interpolated with the point's barycentric coordinates. Its tangent (the implant's local x axis: a \
rectangle's length, a crescent's chord) is --tangent if given, else the world +x axis, or +y when \
the normal is within 25° of ±x, in both cases projected onto the plane across the normal.";

const AFTER_LONG_HELP: &str = "\
OUTPUTS (written only after a successful run, all together, each atomically: a cancelled or \
failed run leaves no output file and no temporary file):
  --out FILE      the patient surface after the run, format from the extension: .obj .ply .stl \
.vtk, in the mesh's unit. VTK carries the point fields `displacement` (how far each vertex moved, \
mesh unit), `stretch` (area after / area before of the skin around the vertex) and `in_region` \
(1 in the simulated region, 0 outside); displacement and stretch are 0 outside the region. \
--out may be given several times.
  --report FILE   JSON, one object (see below).
  --png FILE      the surface before (grey) and after, coloured by --color with a colour bar; \
outside the region displacement is 0 and stretch 1.
  stdout          a summary table (single run), one row per run (--sweep), or the runs and the \
answer (--target-gain).

REPORT JSON: one object, the contract every front end of tissue-planner writes (insert, the \
studio, the C ABI): the same request gives the same report, whatever wrote it, and fields are \
only ever added (a change that is not an addition raises schema_version). Every report has \
schema_version, tool, version, mode (single | sweep | target-gain | expansion) and inputs; the \
fields of each mode are documented in the rustdoc of tissue_planner::report, and \
fixtures/reports/ holds one example report per mode (checked against every front end).

CASE LIBRARY (--save NAME): after a successful run and its outputs, the run is stored as a plan \
(its job, its report byte for byte, a single run's result) for the patient of the scan, in the \
library's database (cases.sqlite in --data), in one transaction: `insert: saved plan c… \"NAME\" \
for patient p… in PATH` on stderr. The name, note and label are checked, and the library opened, \
before the run. `tissue-cases list` shows the plans; docs/cases.md is the guide.";

/// The text after the options in `--help`: outputs, the report, and the exit codes (the table
/// every tissue binary shares, with what each code means here).
fn after_long_help() -> String {
    use tissue_cli::Exit;
    format!(
        "{AFTER_LONG_HELP}\n\n{}\n  (130 here: the run is cancelled; 141: outputs not yet written are not written)",
        Exit::help_section(&[
            (
                Exit::Usage,
                "missing --at/--vertex with --mesh, missing shape size",
            ),
            (
                Exit::Input,
                "the --mesh file (.obj .ply .stl .vtk)",
            ),
            (
                Exit::Placement,
                "point off the surface, vertex out of range, region empty, covering the whole \
                 surface or too small for the implant, badly shaped triangles at the point",
            ),
            (
                Exit::Usage,
                "an empty or too long --save name or --label, a --note over 10000 characters \
                 (checked before the run)",
            ),
            (
                Exit::Output,
                "an output file, or the case library of --save: --data is not a usable folder \
                 (before the run), or the plan could not be stored (after the run: its outputs \
                 are written, the plan is not saved)",
            ),
            (
                Exit::Parameters,
                "non-positive volume or size, a volume the base cannot hold, tissue values out \
                 of range, a --target-gain not inside the volume bracket",
            ),
        ])
    )
}

fn default_young_kpa() -> f64 {
    defaults().young_kpa
}

fn default_poisson() -> f64 {
    defaults().poisson
}

fn default_thickness() -> f64 {
    defaults().thickness_cm
}

fn default_density() -> f64 {
    defaults().density_g_cm3
}

fn default_depth() -> f64 {
    defaults().depth_cm
}

fn default_max_steps() -> u64 {
    defaults().max_steps
}

/// `--time-step`'s help, with the factor the library uses for the automatic step.
fn time_step_help() -> String {
    format!(
        "Time step (s) [default: automatic, {} × the stability limit]. A larger step than the \
         automatic one may diverge (exit {}).",
        defaults().automatic_step_safety(),
        tissue_cli::Exit::Run.code()
    )
}

/// Parses `X,Y,Z`.
fn parse_vec3(s: &str) -> Result<[f32; 3], String> {
    let parts: Vec<&str> = s.split(',').map(str::trim).collect();
    if parts.len() != 3 {
        return Err(format!(
            "expected three comma-separated numbers X,Y,Z, got {s:?}"
        ));
    }
    let mut out = [0.0f32; 3];
    for (slot, part) in out.iter_mut().zip(&parts) {
        let v: f32 = part
            .parse()
            .map_err(|_| format!("{part:?} is not a number (expected X,Y,Z)"))?;
        if !v.is_finite() {
            return Err(format!("{part:?} is not a finite number"));
        }
        *slot = v;
    }
    Ok(out)
}

/// Parses `LOW,HIGH`.
fn parse_pair(s: &str) -> Result<(f64, f64), String> {
    let parts: Vec<&str> = s.split(',').map(str::trim).collect();
    match parts.as_slice() {
        [a, b] => {
            let a: f64 = a
                .parse()
                .map_err(|_| format!("{a:?} is not a number (expected LOW,HIGH)"))?;
            let b: f64 = b
                .parse()
                .map_err(|_| format!("{b:?} is not a number (expected LOW,HIGH)"))?;
            Ok((a, b))
        }
        _ => Err(format!(
            "expected two comma-separated numbers LOW,HIGH, got {s:?}"
        )),
    }
}

/// Parses `WxH`.
fn parse_size(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s
        .split_once(['x', 'X'])
        .ok_or_else(|| format!("expected WIDTHxHEIGHT in pixels, e.g. 1200x600, got {s:?}"))?;
    let w: u32 = w
        .trim()
        .parse()
        .map_err(|_| format!("{w:?} is not a pixel count"))?;
    let h: u32 = h
        .trim()
        .parse()
        .map_err(|_| format!("{h:?} is not a pixel count"))?;
    if !(16..=8192).contains(&w) || !(16..=8192).contains(&h) {
        return Err(format!("{w}x{h}: each side must be 16 to 8192 pixels"));
    }
    Ok((w, h))
}

/// Parses an output mesh path: its extension must name a format.
fn parse_mesh_out(s: &str) -> Result<PathBuf, String> {
    let path = PathBuf::from(s);
    match tissue_planner::is_mesh_path(&path) {
        true => Ok(path),
        false => Err(format!(
            "{s:?}: the extension must be .obj, .ply, .stl or .vtk (it picks the format)"
        )),
    }
}

/// `insert`: the command line.
#[derive(Debug, Parser)]
#[command(
    name = "insert",
    version,
    about = ABOUT,
    long_about = LONG_ABOUT,
    after_long_help = after_long_help(),
    after_help = "Units, orientation, outputs, the JSON contract and the exit codes: insert --help",
    allow_negative_numbers = true
)]
pub struct Cli {
    /// The patient surface: a scan patch or a closed (watertight) body (.obj, .ply, .stl or .vtk)
    /// with normals out of the body. Default: the Table 2 plane (20 cm, 65 × 65 vertices, cm).
    #[arg(long, value_name = "FILE", help_heading = "Patient")]
    pub mesh: Option<PathBuf>,

    /// The mesh file's unit of length; outputs are written back in it [default: cm].
    #[arg(long, value_enum, requires = "mesh", help_heading = "Patient")]
    pub unit: Option<Unit>,

    /// Where the implant goes, in the mesh's unit; snapped to the nearest surface point (at most
    /// 5 % of the mesh's bounding-box diagonal away). Default without --mesh: 0,0,0.
    #[arg(long, value_name = "X,Y,Z", value_parser = parse_vec3, allow_hyphen_values = true,
          conflicts_with = "vertex", help_heading = "Placement")]
    pub at: Option<[f32; 3]>,

    /// Where the implant goes: a vertex of the mesh, counted from 0 in file order.
    #[arg(long, value_name = "N", help_heading = "Placement")]
    pub vertex: Option<u32>,

    /// The implant's local x direction (a rectangle's length), projected across the normal
    /// [default: +x, or +y when the normal is near ±x].
    #[arg(long, value_name = "X,Y,Z", value_parser = parse_vec3, allow_hyphen_values = true,
          help_heading = "Placement")]
    pub tangent: Option<[f32; 3]>,

    /// Turns the tangent about the normal by this many degrees (counter-clockwise seen from
    /// outside the body).
    #[arg(long, value_name = "DEG", default_value_t = defaults().rotation_deg,
          help_heading = "Placement")]
    pub rotation: f32,

    /// The implant's base outline.
    #[arg(long, value_enum, default_value_t = defaults().shape, help_heading = "Implant")]
    pub shape: Shape,

    /// Round base: diameter (cm).
    #[arg(long, value_name = "CM", default_value_t = defaults().diameter_cm,
          help_heading = "Implant")]
    pub diameter: f32,

    /// Rectangular base: length along the tangent; crescent: centre-line length tip to tip (cm).
    #[arg(long, value_name = "CM", help_heading = "Implant")]
    pub length: Option<f32>,

    /// Rectangular or crescent base: width (cm).
    #[arg(long, value_name = "CM", help_heading = "Implant")]
    pub width: Option<f32>,

    /// Rectangular base: corner radius (cm), at most half the shorter side.
    #[arg(long, value_name = "CM", default_value_t = defaults().corner_radius_cm,
          help_heading = "Implant")]
    pub corner_radius: f32,

    /// Crescent base: radius of the centre line's arc (cm), at least 1.5 × the width.
    #[arg(long, value_name = "CM", help_heading = "Implant")]
    pub bend_radius: Option<f32>,

    /// Implant fill volume (cm³ = mL).
    #[arg(long, value_name = "CM3", default_value_t = defaults().volume_cm3,
          help_heading = "Implant")]
    pub volume: f64,

    /// Implant mesh size: wanted vertex count (50 to 100000).
    #[arg(long, value_name = "N", default_value_t = defaults().implant_vertices,
          help_heading = "Implant")]
    pub implant_vertices: u32,

    /// Placement depth: the implant's base lies this far under the skin (cm).
    #[arg(long, value_name = "CM", default_value_t = default_depth(), help_heading = "Tissue")]
    pub depth: f64,

    /// Region radius: geodesic distance from the point to the edge of the simulated skin (cm)
    /// [default: 1.5 × the implant's footprint radius, 5.25 cm for a 7 cm round base].
    #[arg(long, value_name = "CM", help_heading = "Tissue")]
    pub radius: Option<f64>,

    /// Which triangles within the radius form the region.
    #[arg(long, value_enum, default_value_t = defaults().region_rule, help_heading = "Tissue")]
    pub region_rule: Rule,

    /// The simulation mesh's edge (cm): the region is remeshed to it, smoothed below it, its
    /// holes filled, and the result mapped back onto every vertex of the scan [default: 0.06 ×
    /// the region radius, about Table 2's particle count: 0.315 cm for a 7 cm round base].
    /// Given without --mesh, the Table 2 plane is remeshed too.
    #[arg(
        long,
        value_name = "CM",
        conflicts_with = "scan_triangles",
        help_heading = "Simulation mesh"
    )]
    pub sim_edge: Option<f64>,

    /// Run the mechanics on the mesh's own triangles instead (the thesis's planes; the default
    /// for the generated Table 2 plane). For clean, even meshes only.
    #[arg(long, help_heading = "Simulation mesh")]
    pub scan_triangles: bool,

    /// Holes of the scan up to this size across are filled for the simulation (cm); a region
    /// that reaches a larger one, or the scan's border, is refused.
    #[arg(long, value_name = "CM", default_value_t = defaults().max_hole_cm,
          help_heading = "Simulation mesh")]
    pub max_hole: f64,

    /// Young's modulus of the skin, in kPa (1 kPa = 1000 Pa).
    #[arg(long, value_name = "KPA", default_value_t = default_young_kpa(),
          help_heading = "Tissue")]
    pub young: f64,

    /// Poisson ratio of the skin, in [0, 0.5).
    #[arg(long, value_name = "NU", default_value_t = default_poisson(), help_heading = "Tissue")]
    pub poisson: f64,

    /// Skin thickness (cm).
    #[arg(long, value_name = "CM", default_value_t = default_thickness(),
          help_heading = "Tissue")]
    pub thickness: f64,

    /// Tissue density (g/cm³).
    #[arg(long, value_name = "G_CM3", default_value_t = default_density(),
          help_heading = "Tissue")]
    pub density: f64,

    /// Collision detection broad phase.
    #[arg(long, value_enum, default_value_t = defaults().detect, help_heading = "Run")]
    pub detect: Detect,

    /// How a run finds the tissue's rest state: quasi_static solves for the static equilibrium
    /// directly; explicit steps the thesis's explicit Euler until the tissue settles (the
    /// reference). Every mode (--sweep, --target-gain, --expand-weeks) uses it.
    #[arg(long, value_enum, default_value_t = defaults().solver, help_heading = "Run")]
    pub solver: Solver,

    /// Step limit of a run (at most 500000).
    #[arg(long, value_name = "N", default_value_t = default_max_steps(), help_heading = "Run")]
    pub max_steps: u64,

    /// Time step (s); the default, automatic, is a fraction of the stability limit (see
    /// `time_step_help`).
    #[arg(long, value_name = "S", help_heading = "Run", help = time_step_help())]
    pub time_step: Option<f32>,

    /// Run a series of implant volumes in parallel (cm³, comma-separated) instead of --volume;
    /// prints one row per run.
    #[arg(long, value_name = "V1,V2,...", value_delimiter = ',', num_args = 1..,
          conflicts_with_all = ["target_gain", "out", "png"], help_heading = "Run")]
    pub sweep: Option<Vec<f64>>,

    /// Find the implant volume that gives this area gain (cm²); prints every run and the answer.
    #[arg(long, value_name = "CM2", conflicts_with_all = ["out", "png"], help_heading = "Run")]
    pub target_gain: Option<f64>,

    /// The volumes (cm³) --target-gain searches between [default: a quarter to twice --volume].
    #[arg(long, value_name = "LOW,HIGH", value_parser = parse_pair, requires = "target_gain",
          help_heading = "Run")]
    pub bracket: Option<(f64, f64)>,

    /// --target-gain: stop when a run's gain is within this of the target (cm²).
    #[arg(long, value_name = "CM2", default_value_t = tissue_planner::default_gain_tolerance(),
          requires = "target_gain", help_heading = "Run")]
    pub gain_tolerance: f64,

    /// Write the patient surface after the run (.obj, .ply, .stl or .vtk; may be repeated).
    #[arg(long, value_name = "FILE", value_parser = parse_mesh_out, help_heading = "Outputs")]
    pub out: Vec<PathBuf>,

    /// Expansion over weeks: this many equal weekly fills to --volume, with skin growth, then
    /// the hold and removal; prints the weekly figures and the flap at removal with its band.
    #[arg(long, value_name = "N", conflicts_with_all = ["sweep", "target_gain", "out", "png"],
          help_heading = "Expansion")]
    pub expand_weeks: Option<u32>,

    /// Expansion: weeks the expander is held full before removal.
    #[arg(long, value_name = "WEEKS", default_value_t = defaults().hold_weeks,
          requires = "expand_weeks", help_heading = "Expansion")]
    pub hold_weeks: f64,

    /// Expansion: the fraction of every fill that leaks (in vivo 0.29 ± 0.125).
    #[arg(long, value_name = "FRACTION", default_value_t = defaults().leakage,
          requires = "expand_weeks", help_heading = "Expansion")]
    pub leakage: f64,

    /// Expansion: saline injected beyond --volume, as a fraction of it (0.41: +41 %).
    #[arg(long, value_name = "FRACTION", default_value_t = defaults().overfill,
          requires = "expand_weeks", help_heading = "Expansion")]
    pub overfill: f64,

    /// Expansion: samples of the uncertainty band (0: none; 8 or more).
    #[arg(long, value_name = "N", default_value_t = defaults().band_samples,
          requires = "expand_weeks", help_heading = "Expansion")]
    pub band_samples: usize,

    /// Expansion: the band's seed.
    #[arg(long, value_name = "N", default_value_t = defaults().band_seed,
          requires = "expand_weeks", help_heading = "Expansion")]
    pub seed: u64,

    /// Expansion: the growth step in hours, 1 to 24 (the skin re-settles after each).
    #[arg(long, value_name = "HOURS", default_value_t = defaults().growth_step_h,
          requires = "expand_weeks", help_heading = "Expansion")]
    pub growth_step: f64,

    /// Expansion: write a PNG chart over the days (volume, area gain, skin grown, the flap's
    /// band at removal).
    #[arg(
        long,
        value_name = "FILE",
        requires = "expand_weeks",
        help_heading = "Expansion"
    )]
    pub chart: Option<PathBuf>,

    /// Run this job: a JSON file in the planner's job shape (`{"mode": …, "request": {…},
    /// "volumes_cm3": […], …}`, the studio's and the C ABI's), in place of the request and
    /// mode flags (--mesh and --unit still give the patient).
    #[arg(long, value_name = "FILE", conflicts_with_all = ["sweep", "target_gain", "expand_weeks"],
          help_heading = "Run")]
    pub job: Option<PathBuf>,

    /// Write every result and its inputs as JSON (see the contract in --help).
    #[arg(long, value_name = "FILE", help_heading = "Outputs")]
    pub report: Option<PathBuf>,

    /// Write a PNG of the surface before and after, coloured by --color, with a colour bar.
    #[arg(long, value_name = "FILE", help_heading = "Outputs")]
    pub png: Option<PathBuf>,

    /// The field that colours the picture.
    #[arg(long, value_enum, default_value_t = ColorBy::Displacement, help_heading = "Outputs")]
    pub color: ColorBy,

    /// The picture's size in pixels, WIDTHxHEIGHT.
    #[arg(long, value_name = "WxH", value_parser = parse_size, default_value = "1200x600",
          help_heading = "Outputs")]
    pub png_size: (u32, u32),

    /// No progress on stderr.
    #[arg(long, short, help_heading = "Outputs")]
    pub quiet: bool,

    /// Store this run in the case library as a plan named NAME (1 to 200 characters, one line),
    /// for the patient of the scan (added the first time its scan is seen in its unit). Every
    /// mode is saved; `tissue-cases` lists, shows, exports and erases them.
    #[arg(long, value_name = "NAME", help_heading = "Case library")]
    pub save: Option<String>,

    /// The saved plan's note (up to 10000 characters).
    #[arg(
        long,
        value_name = "TEXT",
        requires = "save",
        help_heading = "Case library"
    )]
    pub note: Option<String>,

    /// The patient's label, when the scan is new to the library [default: the scan's file
    /// name, or "Table 2 plane"].
    #[arg(
        long,
        value_name = "TEXT",
        requires = "save",
        help_heading = "Case library"
    )]
    pub label: Option<String>,

    /// The case library's folder [default: the platform's data folder: $XDG_DATA_HOME/tissue or
    /// ~/.local/share/tissue on Linux, ~/Library/Application Support/tissue on macOS,
    /// %APPDATA%\tissue on Windows]. Opened only with --save.
    #[arg(
        long,
        value_name = "DIR",
        requires = "save",
        help_heading = "Case library"
    )]
    pub data: Option<PathBuf>,
}

impl Cli {
    /// The mesh unit (cm when not given).
    pub fn unit(&self) -> Unit {
        self.unit.unwrap_or(Unit::Cm)
    }

    /// The planning request the flags make.
    /// What to run: `--job`'s file, or the job the flags make.
    ///
    /// # Errors
    /// A `--job` file that cannot be read or is not a job, or one given with request flags.
    pub fn job(&self) -> Result<JobSpec, Failure> {
        let Some(path) = &self.job else {
            return Ok(self.job_spec());
        };
        let given = serde_json::to_value(self.request()).ok();
        if given != serde_json::to_value(PlanRequest::default()).ok() {
            return Err(Failure::new(
                Exit::Usage,
                "--job takes the whole job: put the request's values in its \"request\", not \
                 in flags",
            ));
        }
        let text = std::fs::read_to_string(path).map_err(|e| {
            Failure::new(
                Exit::Input,
                format!("cannot read the job {}: {e}", path.display()),
            )
        })?;
        serde_json::from_str(&text).map_err(|e| {
            Failure::new(
                Exit::Usage,
                format!(
                    "{} is not a job: {e}; see tissue_planner::JobSpec for its members",
                    path.display()
                ),
            )
        })
    }

    /// What the flags ask to run: the planner's job, as the studio and the C ABI send it.
    /// `--sweep` makes a sweep, `--target-gain` a search, `--expand-weeks` an expansion;
    /// otherwise one run.
    pub fn job_spec(&self) -> JobSpec {
        let mode = if self.sweep.is_some() {
            JobMode::Sweep
        } else if self.expand_weeks.is_some() {
            JobMode::Expansion
        } else if self.target_gain.is_some() {
            JobMode::TargetGain
        } else {
            JobMode::Single
        };
        JobSpec {
            mode,
            request: self.request(),
            volumes_cm3: self.sweep.clone().unwrap_or_default(),
            target_gain_cm2: self.target_gain,
            bracket_cm3: self.bracket,
            gain_tolerance_cm2: Some(self.gain_tolerance),
        }
    }

    pub fn request(&self) -> PlanRequest {
        PlanRequest {
            at: self.at,
            vertex: self.vertex,
            tangent: self.tangent,
            rotation_deg: self.rotation,
            shape: self.shape,
            diameter_cm: self.diameter,
            length_cm: self.length,
            width_cm: self.width,
            corner_radius_cm: self.corner_radius,
            bend_radius_cm: self.bend_radius,
            volume_cm3: self.volume,
            implant_vertices: self.implant_vertices,
            depth_cm: self.depth,
            region_radius_cm: self.radius,
            region_rule: self.region_rule,
            sim_edge_cm: self.sim_edge,
            scan_triangles: self.scan_triangles,
            max_hole_cm: self.max_hole,
            young_kpa: self.young,
            poisson: self.poisson,
            thickness_cm: self.thickness,
            density_g_cm3: self.density,
            detect: self.detect,
            solver: self.solver,
            max_steps: self.max_steps,
            time_step_s: self.time_step,
            expand_weeks: self.expand_weeks,
            hold_weeks: self.hold_weeks,
            leakage: self.leakage,
            overfill: self.overfill,
            band_samples: self.band_samples,
            band_seed: self.seed,
            growth_step_h: self.growth_step,
        }
    }
}

/// The flag that sets a request field (the planner's messages name fields).
pub fn flag_of(field: &str) -> Option<&'static str> {
    Some(match field {
        "mesh" => "--mesh",
        "unit" => "--unit",
        "at" => "--at",
        "vertex" => "--vertex",
        "tangent" => "--tangent",
        "rotation_deg" => "--rotation",
        "shape" => "--shape",
        "diameter_cm" => "--diameter",
        "length_cm" => "--length",
        "width_cm" => "--width",
        "corner_radius_cm" => "--corner-radius",
        "bend_radius_cm" => "--bend-radius",
        "volume_cm3" => "--volume",
        "volumes_cm3" => "--sweep",
        "implant_vertices" => "--implant-vertices",
        "depth_cm" => "--depth",
        "region_radius_cm" => "--radius",
        "region_rule" => "--region-rule",
        "sim_edge_cm" => "--sim-edge",
        "scan_triangles" => "--scan-triangles",
        "max_hole_cm" => "--max-hole",
        "young_kpa" => "--young",
        "poisson" => "--poisson",
        "thickness_cm" => "--thickness",
        "density_g_cm3" => "--density",
        "detect" => "--detect",
        "solver" => "--solver",
        "max_steps" => "--max-steps",
        "time_step_s" => "--time-step",
        "target_gain_cm2" => "--target-gain",
        "bracket_cm3" => "--bracket",
        "gain_tolerance_cm2" => "--gain-tolerance",
        "out" => "--out",
        "expand_weeks" => "--expand-weeks",
        "hold_weeks" => "--hold-weeks",
        "leakage" => "--leakage",
        "overfill" => "--overfill",
        "band_samples" => "--band-samples",
        "band_seed" => "--seed",
        "growth_step_h" => "--growth-step",
        "mode" => "--job",
        _ => return None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::CommandFactory;

    #[test]
    fn the_command_is_well_formed() {
        Cli::command().debug_assert();
    }

    #[test]
    fn every_request_field_has_its_flag() {
        let json = serde_json::to_value(PlanRequest::default()).unwrap();
        for field in json.as_object().unwrap().keys() {
            assert!(flag_of(field).is_some(), "no flag for {field}");
        }
    }

    /// Every default shown in `--help` is the library's: the flags with no value give
    /// `PlanRequest::default()` exactly.
    #[test]
    fn the_defaults_are_the_librarys() {
        let cli = Cli::try_parse_from(["insert"]).unwrap();
        assert_eq!(
            serde_json::to_value(cli.request()).unwrap(),
            serde_json::to_value(PlanRequest::default()).unwrap()
        );
        assert_eq!(cli.job_spec().mode, JobMode::Single);
        let sweep = Cli::try_parse_from(["insert", "--sweep", "50,100"]).unwrap();
        assert_eq!(sweep.job_spec().mode, JobMode::Sweep);
        assert_eq!(sweep.job_spec().volumes_cm3, [50.0, 100.0]);
        let weeks = Cli::try_parse_from(["insert", "--expand-weeks", "4"]).unwrap();
        assert_eq!(weeks.job_spec().mode, JobMode::Expansion);
    }

    /// `--solver` takes the JSON names, defaults to the library's solver and sets the request's.
    #[test]
    fn the_solver_flag_takes_the_json_names() {
        let default = Cli::try_parse_from(["insert"]).unwrap();
        assert_eq!(default.request().solver, Solver::Explicit);
        for s in Solver::ALL {
            let cli = Cli::try_parse_from(["insert", "--solver", s.name()]).unwrap();
            assert_eq!(cli.request().solver, s);
            assert_eq!(cli.job_spec().request.params().solver, s.into());
        }
        assert!(Cli::try_parse_from(["insert", "--solver", "quasi-static"]).is_err());
        assert!(Cli::try_parse_from(["insert", "--solver", "implicit"]).is_err());
    }

    #[test]
    fn value_parsers() {
        assert_eq!(parse_vec3("1, -2,3.5"), Ok([1.0, -2.0, 3.5]));
        assert!(parse_vec3("1,2").is_err());
        assert!(parse_vec3("1,2,nan").is_err());
        assert_eq!(parse_pair("10,200"), Ok((10.0, 200.0)));
        assert_eq!(parse_size("640x480"), Ok((640, 480)));
        assert!(parse_size("0x480").is_err());
        assert!(parse_mesh_out("a.xyz").is_err());
    }
}
