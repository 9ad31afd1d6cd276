//! The command line: flags, defaults, units and exit codes.

use std::path::PathBuf;

use clap::{Parser, ValueEnum};
use tissue_scenes::{OrganMaterial, PressPlan, SelfCollision, SessionOptions, TissuePreset};

use crate::failure::{self, Failure};

const ABOUT: &str = "Headless surgical-trainer run: an organ settles on a tray, a probe presses \
into it and drags along a path; prints per-step timing and the volume drift, writes surface \
frames and pictures.";

const LONG_ABOUT: &str = "\
Headless surgical-trainer run (position-based dynamics, tissue-pbd): a tetrahedral organ is \
scaled to --size, centred above the origin and set on a 2 cm thick tray (a static voxel collider \
with friction) whose top is the plane y = 0; gravity is -y. It settles for --settle-steps (every \
motion damped with a relaxation time of 0.05 s, so that it comes to rest), then a \
vertical probe (a capsule of --tool-radius, tip down) comes down over the first --waypoint and \
presses --depth cm below the organ's top there in --press-steps, then drags along the waypoints \
(a polyline at constant height) in --drag-steps.

With no arguments it runs the Stanford Bunny shipped in the program (fixtures/bunny_10k.obj, \
tetrahedralised on load by tissue-tetra: 9046 nodes, 39706 tets, 10 cm), the studio's default \
organ too.

SCHEMES (--scheme): `realtime` (the default, tissue-pbd's StepSettings::realtime and \
Material::soft_tissue, which the studio uses too): each 10 ms step is 9 substeps of one \
linearised-PBD iteration, classic volume constraints and one volume constraint per connected \
piece (--no-piece-volumes drops it), k = 1. `legacy` (the scheme before issue \
19, for comparison): one 10 ms step of K = 10 iterations, distance stiffness --stiffness. \
--dt, --substeps, --iterations, --solver, --compliance and --volume override any scheme's \
values (`--scheme legacy` is `--substeps 1 --iterations 10`). `material` (issue 32; \
StepSettings::material and Material::elastic): a physical material, stable neo-Hookean (Macklin \
& Müller 2021: per tet the constraint pair det F - gamma and sqrt(tr F^T F), with compliances \
1/(lambda V0) and 1/(mu V0), solved together by XPBD) of Young's modulus --young-kpa (default \
10 kPa), Poisson's ratio --poisson (0 to 0.495, default 0.45) and density --density (default \
1.05 g/cm3), no distance or volume constraints; each 10 ms step is 32 XPBD substeps of one \
iteration; damping: every motion relative to the organ's rigid motion decays as exp(-t/tau), \
tau = --relaxation-time (default 0.1 s). --tissue PRESET (liver, kidney, bowel, fat, skin) \
takes a preset tissue's E, nu and rho instead of the defaults; the explicit flags override it. \
Giving any of these five flags without --scheme selects `material`; with `--scheme realtime` \
or `legacy` they are refused. docs/trainer.md compares the schemes.

UNITS: centimetres, grams, seconds. --size, --depth, --tool-radius, --cell, the waypoints in cm \
(x and z of the tray plane, the organ centred at x = z = 0); --dt in s.";

const AFTER_LONG_HELP: &str = "\
OUTPUT: a summary on stdout: the organ, the steps, the per-step wall time (median, p99, max) \
over all steps and over the tool steps, the volume drift V/V0 - 1 at the end and its largest \
magnitude, the tets' own volume errors at the end (median, p90, volume-weighted mean of \
|V/V0 - 1| per tet: the local compression the total can hide), the organ's height as loaded and \
settled, the contacts, and the force of the tissue on the probe in newtons (the largest \
magnitude over the run and the last step's vector; tissue-pbd's SoftBody::tool_force, 1 N = 1e5 \
dyn), the self-collision of the organ's surface (on by default: its thickness and the last \
step's self-contacts; `off` with --no-self-collision) and, last, `self-intersections N`: the \
pairs of surface triangles that intersect at the end, counted exactly (every run that steps ends \
with these two lines). \
With --frames DIR (created if missing): the organ's surface every --every steps and at the end, \
frame_STEP.vtk (with point field `displacement`, cm: from the shape as loaded during the \
settling, from the settled shape afterwards) or frame_STEP.obj (--format), and with --png \
frame_STEP.png (coloured by that displacement, the probe in grey). Each file is \
written atomically.";

/// The text after the options in `--help`: the output and the exit codes (the table every
/// tissue binary shares, with what each code means here).
fn after_long_help() -> String {
    use tissue_cli::Exit;
    format!(
        "{AFTER_LONG_HELP}\n\n{}",
        Exit::help_section(&[
            (Exit::Input, "the --organ or --surface file"),
            (Exit::Mesh, "the organ's mesh"),
            (
                Exit::Meshing,
                "--surface (open, non-manifold, inside out, ...)"
            ),
            (
                Exit::Parameters,
                "also the first waypoint not over the organ",
            ),
        ])
    )
}

/// Which volume constraint the organ carries.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Volume {
    /// One classic tet-volume constraint per tet.
    Classic,
    /// The slides' centroid constraint, four per tet.
    Centroid,
    /// None (distance constraints only).
    None,
}

/// The time-stepping scheme (its library preset).
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Scheme {
    /// tissue-pbd's real-time preset: 9 substeps of one iteration per 10 ms step, classic
    /// volume, k = 1.
    Realtime,
    /// The scheme before the real-time preset: one 10 ms step of K = 10 linearised-PBD iterations.
    Legacy,
    /// tissue-pbd's material scheme: a stable neo-Hookean organ (--young-kpa, --poisson,
    /// --density) in 32 XPBD substeps of one iteration per 10 ms step.
    Material,
}

/// The stiffness model (tissue_pbd::Solver).
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum SolverArg {
    /// PBD, stiffness as given.
    Pbd,
    /// PBD with the stiffness linearised over the iterations.
    Linearised,
    /// XPBD with compliance.
    Xpbd,
}

/// Format of the surface frames.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum FrameFormat {
    /// Legacy VTK polydata with the `displacement` point field (ParaView).
    Vtk,
    /// Wavefront OBJ.
    Obj,
}

/// A scripted scenario.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Scenario {
    /// Deform, incise, cut a piece off, suture the wound.
    Appendix,
    /// A beam of --length along x and square section --thickness, clamped at x = 0, no tray,
    /// settling under gravity for --settle-steps; prints its tip deflection.
    Cantilever,
}

/// `trainer` arguments.
#[derive(Debug, Parser)]
#[command(
    name = "trainer",
    version,
    allow_negative_numbers = true,
    about = ABOUT,
    long_about = LONG_ABOUT,
    after_long_help = after_long_help()
)]
pub struct Cli {
    /// A scripted scenario instead of the press-and-drag run: `appendix` (an appendix-like
    /// 8 × 2 × 2 cm organ pinned at its base sags under gravity, is incised near the base, has
    /// its tip cut off, and the incision is sutured; per-step timing and the surgery events).
    #[arg(long, value_enum)]
    pub scenario: Option<Scenario>,
    /// The organ, a tetrahedral mesh: a VTK XML .vtu (ascii, base64 or raw appended, zlib or
    /// uncompressed), a Gmsh .msh (versions 1 as SOFA ships, 2.2 and 4.1, ASCII or binary), a
    /// legacy .vtk tet grid, or a TetGen mesh (its stem, .node or .ele); other cells than
    /// tetrahedra are skipped [default: the shipped bunny, else a generated box].
    #[arg(long, value_name = "PATH", conflicts_with_all = ["surface", "box_cells"])]
    pub organ: Option<PathBuf>,
    /// A closed surface (.obj, .ply, .stl) to tetrahedralise first (tissue-tetra: the surface
    /// vertices become nodes, interior nodes on a lattice about 1.7 surface edges apart).
    #[arg(long, value_name = "FILE", conflicts_with = "box_cells")]
    pub surface: Option<PathBuf>,
    /// Use a generated tet box of N × N × N cells as the organ.
    #[arg(long = "box", value_name = "N", value_parser = clap::value_parser!(u32).range(1..=64))]
    pub box_cells: Option<u32>,
    /// Largest extent of the organ after scaling (cm).
    #[arg(long, value_name = "CM", default_value_t = 10.0)]
    pub size: f32,
    /// Time-stepping scheme: `realtime` (library preset, 9 substeps of 1 iteration), `legacy`
    /// (one step of K = 10 PBD iterations, as before the real-time preset) or `material` (a
    /// stable neo-Hookean organ in SI-consistent units, 32 XPBD substeps) [default: realtime,
    /// or material when a material flag is given].
    #[arg(long, value_enum)]
    pub scheme: Option<Scheme>,
    /// A preset tissue's Young's modulus, Poisson's ratio and density for the organ (material
    /// scheme): liver, kidney, bowel, fat or skin (docs/materials.md); --young-kpa, --poisson
    /// and --density override its values.
    #[arg(long, value_name = "PRESET", value_parser = parse_tissue)]
    pub tissue: Option<TissuePreset>,
    /// Young's modulus of the organ (kPa; material scheme) [default: 10, or --tissue's].
    #[arg(long, value_name = "E")]
    pub young_kpa: Option<f32>,
    /// Poisson's ratio of the organ, 0 to 0.495 (material scheme) [default: 0.45, or
    /// --tissue's].
    #[arg(long, value_name = "NU")]
    pub poisson: Option<f32>,
    /// Density of the organ (g/cm³; material scheme) [default: 1.05, or --tissue's].
    #[arg(long, value_name = "RHO")]
    pub density: Option<f32>,
    /// Relaxation time of the damping (s; material scheme): motion relative to the organ's
    /// rigid motion decays as exp(-t/tau) [default: 0.1].
    #[arg(long, value_name = "S")]
    pub relaxation_time: Option<f32>,
    /// Over-relaxation beta of the neo-Hookean pairs, 0 to 1 (material scheme; 0 is plain XPBD,
    /// which leaves the organ softer than its material by about (h omega)^2) [default: 1].
    #[arg(long, value_name = "BETA")]
    pub over_relaxation: Option<f32>,
    /// Time step per frame (s) [default: 0.01, every scheme].
    #[arg(long, value_name = "S")]
    pub dt: Option<f32>,
    /// Substeps per step [default: realtime 9, legacy 1, material 32].
    #[arg(long, value_name = "N")]
    pub substeps: Option<u32>,
    /// Gauss–Seidel iterations K per substep [default: realtime 1, legacy 10, material 1].
    #[arg(long, value_name = "K")]
    pub iterations: Option<u32>,
    /// Stiffness model [default: linearised PBD; XPBD, the only one it accepts, for material].
    #[arg(long, value_enum)]
    pub solver: Option<SolverArg>,
    /// XPBD compliance of the distance constraints (cm/dyn; with --solver xpbd) [default: 0].
    #[arg(long, value_name = "ALPHA")]
    pub compliance: Option<f32>,
    /// Volume constraint (realtime and legacy; the material scheme has none) [default: classic].
    #[arg(long, value_enum, default_value_t = Volume::Classic)]
    pub volume: Volume,
    /// PBD stiffness of the distance constraints, in [0, 1] (legacy scheme).
    #[arg(long, value_name = "K", default_value_t = 1.0)]
    pub stiffness: f32,
    /// Voxel size of the tray collider (cm).
    #[arg(long, value_name = "CM", default_value_t = 0.5)]
    pub cell: f32,
    /// Friction coefficient (static and kinetic) of the tray and the probe.
    #[arg(long, value_name = "MU", default_value_t = 0.5)]
    pub friction: f32,
    /// Radius of the probe (cm).
    #[arg(long, value_name = "CM", default_value_t = PressPlan::default().radius)]
    pub tool_radius: f32,
    /// How far below the organ's top the probe's tip presses (cm).
    #[arg(long, value_name = "CM", default_value_t = PressPlan::default().depth)]
    pub depth: f32,
    /// A point X,Z (cm) of the drag path on the tray plane; give two or more in order [default:
    /// from -size/4,0 to size/4,0].
    #[arg(long = "waypoint", value_name = "X,Z", value_parser = parse_xz, allow_hyphen_values = true)]
    pub waypoints: Vec<[f32; 2]>,
    /// Steps to let the organ settle on the tray, every motion damped (τ = 0.05 s) so that the
    /// press starts from an organ at rest (the defaults of the timeline are tissue-scenes'
    /// PressPlan::default(), the studio's demonstration's too).
    #[arg(long, value_name = "N", default_value_t = PressPlan::default().settle)]
    pub settle_steps: usize,
    /// Steps to press the probe in.
    #[arg(long, value_name = "N", default_value_t = PressPlan::default().press)]
    pub press_steps: usize,
    /// Steps to drag the probe along the path.
    #[arg(long, value_name = "N", default_value_t = PressPlan::default().drag)]
    pub drag_steps: usize,
    /// Write surface frames into this folder (created if missing).
    #[arg(long, value_name = "DIR")]
    pub frames: Option<PathBuf>,
    /// Write a frame every N steps.
    #[arg(long, value_name = "N", default_value_t = 25, value_parser = clap::value_parser!(u32).range(1..))]
    pub every: u32,
    /// Format of the surface frames.
    #[arg(long, value_enum, default_value_t = FrameFormat::Vtk)]
    pub format: FrameFormat,
    /// Also write a PNG picture with each frame.
    #[arg(long, requires = "frames")]
    pub png: bool,
    /// Project constraints colour-parallel on all cores (bit-identical to serial).
    #[arg(long)]
    pub parallel: bool,
    /// Self-collision of the organ's surface on (tissue-scenes' SelfCollision::default, cut
    /// walls included): the default, as in the studio, the C ABI and Python; accepted for
    /// scripts that say so. Every run prints its self-intersections.
    #[arg(long, conflicts_with = "no_self_collision")]
    pub self_collision: bool,
    /// Switch the self-collision of the organ's surface off, for comparison (it costs about
    /// twice the step on the shipped bunny: docs/trainer.md).
    #[arg(long)]
    pub no_self_collision: bool,
    /// Drop the realtime scheme's volume constraint per connected piece (tissue-pbd's
    /// Material::hold_piece_volumes), keeping the tets' own: for comparison.
    #[arg(long)]
    pub no_piece_volumes: bool,
    /// Instead of stepping, solve the run's static states with the finite-element reference
    /// (tissue-fem, the same stable neo-Hookean material, organ, support and probe depth) and
    /// print the same summary lines: the heights as loaded and settled, the probe's force at
    /// --depth (a cantilever: its tip deflection). Implies the material scheme.
    #[arg(long)]
    pub reference: bool,
    /// The cantilever's length along x (cm; --scenario cantilever).
    #[arg(long, value_name = "CM", default_value_t = 10.0)]
    pub length: f32,
    /// The cantilever's square section's side (cm; --scenario cantilever).
    #[arg(long, value_name = "CM", default_value_t = 1.0)]
    pub thickness: f32,
    /// The cantilever's cells through its thickness, as many per thickness along it, six tets
    /// a cell (--scenario cantilever).
    #[arg(long, value_name = "N", default_value_t = 4, value_parser = clap::value_parser!(u32).range(1..=16))]
    pub cells: u32,
}

impl Cli {
    /// Whether a material flag (--tissue, --young-kpa, --poisson, --density,
    /// --relaxation-time, --over-relaxation) or --reference is given.
    fn material_flags(&self) -> bool {
        self.tissue.is_some()
            || self.young_kpa.is_some()
            || self.poisson.is_some()
            || self.density.is_some()
            || self.relaxation_time.is_some()
            || self.over_relaxation.is_some()
            || self.reference
    }

    /// The material scheme's organ (tissue-scenes' `OrganMaterial`, the studio's and the C
    /// ABI's too): `--tissue`'s preset or the default soft organ, with `--young-kpa`,
    /// `--poisson`, `--density` and `--relaxation-time` as given. Unchecked: its `pbd()` checks
    /// E, ν and ρ (naming the parameter, which `failure` turns into its flag).
    pub fn organ_material(&self) -> OrganMaterial {
        let mut m = match self.tissue {
            Some(tissue) => OrganMaterial::preset(tissue),
            None => OrganMaterial::soft_organ(),
        };
        if let Some(e) = self.young_kpa {
            m.elastic.young_kpa = f64::from(e);
        }
        if let Some(nu) = self.poisson {
            m.elastic.poisson = f64::from(nu);
        }
        if let Some(rho) = self.density {
            m.elastic.density = f64::from(rho);
        }
        if let Some(tau) = self.relaxation_time {
            m.relaxation_time = tau;
        }
        m
    }

    /// The material scheme's organ as the finite-element reference takes it (E, ν, ρ).
    pub fn elastic_material(&self) -> tissue_fem::ElasticMaterial {
        self.organ_material().elastic
    }

    /// The self-collision of the run: none with `--no-self-collision`, tissue-scenes'
    /// [`SelfCollision::default`] with `--self-collision`, else tissue-scenes' default (on, the
    /// studio's, the C ABI's and Python's).
    pub fn self_collision(&self) -> Option<SelfCollision> {
        if self.self_collision {
            Some(SelfCollision::default())
        } else if self.no_self_collision {
            None
        } else {
            SessionOptions::default().self_collision
        }
    }

    /// The scheme of the run: `--scheme` as given; without it `material` when a material flag
    /// is given, else `realtime`.
    pub fn scheme(&self) -> Scheme {
        match self.scheme {
            Some(s) => s,
            None if self.material_flags() => Scheme::Material,
            None => Scheme::Realtime,
        }
    }

    /// Refuses the material flags with the realtime or legacy scheme (they have no physical
    /// material): the message says which flag and what to do.
    pub fn check(&self) -> Result<(), String> {
        if self.material_flags() && self.scheme() != Scheme::Material {
            return Err(format!(
                "--tissue, --young-kpa, --poisson, --density, --relaxation-time, --over-relaxation \
                 and --reference need the material scheme's organ; the {:?} scheme has no \
                 physical material: drop them or \
                 use --scheme material",
                self.scheme()
            )
            .to_lowercase());
        }
        Ok(())
    }

    /// The material and step settings of the run: the scheme's library preset with the
    /// overrides given.
    ///
    /// # Errors
    /// The material scheme's E, ν or ρ out of range (exit code `Parameters`, naming the flag).
    pub fn physics(&self) -> Result<(tissue_pbd::Material, tissue_pbd::StepSettings), Failure> {
        use tissue_pbd::{Material, StepSettings, VolumeConstraintKind};
        let scheme = self.scheme();
        let organ = self.organ_material();
        let (mut material, mut settings) = match scheme {
            Scheme::Realtime => (Material::soft_tissue(), StepSettings::realtime()),
            Scheme::Material => (
                organ.pbd().map_err(|e| failure::from_scene(&e))?,
                StepSettings::material(),
            ),
            Scheme::Legacy => (
                Material {
                    distance_stiffness: self.stiffness,
                    volume_stiffness: 1.0,
                    ..Material::default()
                },
                StepSettings::legacy(),
            ),
        };
        // (Ignored by the material scheme's elastic organ.)
        material.volume = match self.volume {
            Volume::Classic => VolumeConstraintKind::Classic,
            Volume::Centroid => VolumeConstraintKind::Centroid,
            Volume::None => VolumeConstraintKind::None,
        };
        if let Some(solver) = self.solver {
            settings.solver = match solver {
                SolverArg::Pbd => tissue_pbd::Solver::Pbd,
                SolverArg::Linearised => tissue_pbd::Solver::PbdLinearised,
                SolverArg::Xpbd => tissue_pbd::Solver::Xpbd,
            };
        }
        if let Some(a) = self.compliance {
            material.distance_compliance = a;
        }
        if let Some(dt) = self.dt {
            settings.dt = dt;
        }
        if let Some(n) = self.substeps {
            settings.substeps = n;
        }
        if let Some(k) = self.iterations {
            settings.iterations = k;
        }
        settings.parallel = self.parallel;
        if scheme == Scheme::Material {
            // After --dt: the damping per step follows the step.
            settings = settings.with_relaxation_time(organ.relaxation_time);
        }
        if self.no_piece_volumes {
            material.hold_piece_volumes = false;
        }
        if let Some(b) = self.over_relaxation {
            // Validated when the settings are set (tissue-pbd's error names the parameter).
            settings.over_relaxation = b;
        }
        Ok((material, settings))
    }
}

fn parse_tissue(s: &str) -> Result<TissuePreset, String> {
    TissuePreset::from_id(s).ok_or_else(|| {
        let ids: Vec<&str> = TissuePreset::ALL.iter().map(|t| t.id()).collect();
        format!("{s:?} is not a preset tissue: one of {}", ids.join(", "))
    })
}

fn parse_xz(s: &str) -> Result<[f32; 2], String> {
    let parts: Vec<&str> = s.split(',').map(str::trim).collect();
    if parts.len() != 2 {
        return Err(format!("expected X,Z (two numbers in cm), got {s:?}"));
    }
    let mut out = [0.0f32; 2];
    for (o, p) in out.iter_mut().zip(&parts) {
        *o = p
            .parse::<f32>()
            .ok()
            .filter(|v| v.is_finite())
            .ok_or_else(|| format!("{p:?} is not a finite number"))?;
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The headless run and the studio's demonstration on a tray run one timeline: the flags'
    /// defaults are tissue-scenes' PressPlan::default().
    #[test]
    fn the_press_flags_default_to_the_scenes_plan() {
        let cli = Cli::try_parse_from(["trainer"]).unwrap_or_else(|e| panic!("{e}"));
        let plan = PressPlan::default();
        assert_eq!(
            (cli.settle_steps, cli.press_steps, cli.drag_steps),
            (plan.settle, plan.press, plan.drag)
        );
        assert_eq!((cli.depth, cli.tool_radius), (plan.depth, plan.radius));
        assert!(cli.waypoints.is_empty() && plan.waypoints.is_empty());
    }

    /// --reference solves the material scheme's organ: it implies the scheme, is refused with
    /// the others, and takes the material flags (the reference's E, ν, ρ are the run's).
    #[test]
    fn the_reference_is_the_material_schemes() {
        let parse = |args: &[&str]| Cli::try_parse_from(args).unwrap_or_else(|e| panic!("{e}"));
        let cli = parse(&["trainer", "--reference", "--young-kpa", "20"]);
        assert_eq!(cli.scheme(), Scheme::Material);
        assert!(cli.check().is_ok());
        let m = cli.elastic_material();
        assert_eq!(
            (m.young_kpa, m.poisson as f32, m.density as f32),
            (
                20.0,
                tissue_pbd::Material::ORGAN_POISSON,
                tissue_pbd::Material::ORGAN_DENSITY
            )
        );
        let refused = parse(&["trainer", "--reference", "--scheme", "legacy"]);
        assert!(refused.check().unwrap_err().contains("--reference"));
        let beam = parse(&["trainer", "--scenario", "cantilever", "--length", "4"]);
        assert_eq!((beam.length, beam.thickness, beam.cells), (4.0, 1.0, 4));
    }

    #[test]
    fn material_flags_imply_the_material_scheme_and_are_refused_with_the_others() {
        let parse = |args: &[&str]| Cli::try_parse_from(args).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(parse(&["trainer"]).scheme(), Scheme::Realtime);
        let cli = parse(&["trainer", "--young-kpa", "20", "--poisson", "0.49"]);
        assert_eq!(cli.scheme(), Scheme::Material);
        assert!(cli.check().is_ok());
        let (material, settings) = cli.physics().unwrap_or_else(|e| panic!("{e:?}"));
        let e = material
            .elastic
            .unwrap_or_else(|| panic!("no elastic material"));
        assert_eq!((e.young_kpa, e.poisson), (20.0, 0.49));
        assert_eq!(material.density, tissue_pbd::Material::ORGAN_DENSITY);
        assert_eq!(settings.solver, tissue_pbd::Solver::Xpbd);
        assert_eq!(
            settings.substeps,
            tissue_pbd::StepSettings::MATERIAL_SUBSTEPS
        );
        let cli = parse(&["trainer", "--scheme", "material"]);
        assert!(cli
            .physics()
            .unwrap_or_else(|e| panic!("{e:?}"))
            .0
            .elastic
            .is_some());
        for scheme in ["realtime", "legacy"] {
            let cli = parse(&["trainer", "--scheme", scheme, "--density", "1.1"]);
            let err = cli.check().unwrap_err();
            assert!(err.contains("--scheme material"), "{err}");
        }
        // The old schemes are as they were.
        let (m, s) = parse(&["trainer"])
            .physics()
            .unwrap_or_else(|e| panic!("{e:?}"));
        assert!(m.elastic.is_none());
        assert_eq!(s, tissue_pbd::StepSettings::realtime());
    }

    /// --tissue takes a preset's E, ν, ρ into the one organ material (the flags override it),
    /// implies the material scheme, and a bad value is refused naming its flag.
    #[test]
    fn a_tissue_preset_fills_the_organ_material_and_flags_override_it() {
        let parse = |args: &[&str]| Cli::try_parse_from(args).unwrap_or_else(|e| panic!("{e}"));
        let cli = parse(&["trainer", "--tissue", "skin", "--poisson", "0.49"]);
        assert_eq!(cli.scheme(), Scheme::Material);
        let skin = TissuePreset::Skin.material();
        let m = cli.organ_material();
        assert_eq!(
            (m.elastic.young_kpa, m.elastic.density),
            (skin.young_kpa, skin.density)
        );
        assert_eq!(m.elastic.poisson, f64::from(0.49f32));
        assert_eq!(cli.elastic_material(), m.elastic);
        let (material, settings) = cli.physics().unwrap_or_else(|e| panic!("{e:?}"));
        let pbd = m.pbd().unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(
            (material.elastic, material.density),
            (pbd.elastic, pbd.density)
        );
        assert_eq!(
            settings.relaxation_time(),
            tissue_pbd::StepSettings::material()
                .with_relaxation_time(m.relaxation_time)
                .relaxation_time()
        );
        assert!(Cli::try_parse_from(["trainer", "--tissue", "bone"]).is_err());
        let refused = parse(&["trainer", "--tissue", "liver", "--scheme", "realtime"]);
        assert!(refused.check().unwrap_err().contains("--tissue"));
        let bad = parse(&["trainer", "--poisson", "0.6"])
            .physics()
            .unwrap_err();
        assert_eq!(bad.code, failure::Exit::Parameters);
        assert!(bad.message.contains("--poisson"), "{}", bad.message);
    }
}
