//! The finite-element reference of a trainer session's static states (issue 32): the organ as
//! it is held ([`Setting`]), of an [`ElasticMaterial`] (the stable neo-Hookean energy of
//! `tissue-fem`), solved for its static equilibrium instead of stepped:
//!
//! - **settled**: under gravity (−y, 981 cm/s²) on its support — the tray's top `y = 0` as a
//!   floor on which the nodes resting on it as loaded stick (held sideways, free to lift off:
//!   the tray's friction holds them in a trainer run), or the appendix's base clamped over the
//!   abdominal wall (a floor at `y = 0`);
//! - **pressed**: the same with the probe's tip, a rigid sphere of the probe's radius, pushed
//!   `depth` below the settled organ's top at the press point, straight down (frictionless);
//!   the tissue's force on the probe in newtons.
//!
//! Each solve stops when the net force on the free nodes is below 10⁻⁶ of the load (its
//! report says how many Newton iterations it took and what was left).
//!
//! These are the states a press-and-drag run ([`crate::PressAndDrag`]) passes through slowly:
//! its height as loaded and settled, and the probe's force at the pressed depth, so a run and
//! its reference can be compared line by line (`trainer --reference`).
//!
//! ```
//! use tissue_fem::ElasticMaterial;
//! use tissue_scenes::{reference, Organ, ReferencePlan};
//!
//! let block = tissue_mesh::tet_box(4, 4, 4, glam::Vec3::splat(2.0)).unwrap();
//! let organ = Organ::from_tets(&block, "a block").unwrap();
//! let plan = ReferencePlan {
//!     material: ElasticMaterial { young_kpa: 5.0, poisson: 0.3, density: 1.0 },
//!     probe_radius: 0.4,
//!     at: [0.0, 0.0],
//!     depths: vec![0.1],
//! };
//! let summary = reference(&organ, &plan).unwrap();
//! assert!(summary.height_settled < summary.height_loaded);
//! assert!(summary.presses[0].force_n > 0.0);
//! ```

use glam::DVec3;
use tissue_fem::{
    ElasticMaterial, Plane, SolverSettings, SphereIndenter, StaticProblem, StaticReport,
    StaticSolution,
};

use crate::{Organ, SceneError, Setting, APPENDIX_BASE_X};

/// The static solves stop when the net force on the free nodes is below this fraction of the
/// load (gravity, the supports' and the probe's reactions): a millionth, far below what a
/// haptic device or a height in a summary line resolves; the probe's frictionless contact
/// on a coarse organ chatters below it.
const RESIDUAL_TOLERANCE: f64 = 1e-6;

/// Newtons per dyn.
const NEWTONS_PER_DYN: f64 = 1e-5;

/// What the reference solves.
#[derive(Debug, Clone, PartialEq)]
pub struct ReferencePlan {
    /// The organ's material.
    pub material: ElasticMaterial,
    /// The probe's radius (cm): its tip is a hemisphere of this radius.
    pub probe_radius: f32,
    /// Where the probe presses (x, z; cm).
    pub at: [f32; 2],
    /// How deep below the settled top it presses (cm), one static solve each.
    pub depths: Vec<f32>,
}

/// One pressed state.
#[derive(Debug, Clone, PartialEq)]
pub struct ReferencePress {
    /// The depth below the settled top (cm).
    pub depth: f32,
    /// The tissue's force on the probe (N), its magnitude.
    pub force_n: f64,
    /// The solve's iterations and residual.
    pub report: StaticReport,
}

/// The reference's figures, as a run prints them.
#[derive(Debug, Clone, PartialEq)]
pub struct ReferenceSummary {
    /// The organ's extent along gravity as loaded (cm).
    pub height_loaded: f64,
    /// The same, settled under gravity on its support (cm).
    pub height_settled: f64,
    /// The settled organ's top at the press point (y, cm), if it is over the organ.
    pub top: Option<f64>,
    /// A cantilever's tip deflection settled (cm, [`Organ::tip_deflection`]).
    pub tip_deflection: Option<f64>,
    /// The settling solve's iterations and residual.
    pub settle: StaticReport,
    /// One per depth of the plan.
    pub presses: Vec<ReferencePress>,
}

fn height(positions: &[DVec3]) -> f64 {
    let (lo, hi) = positions
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| {
            (lo.min(p.y), hi.max(p.y))
        });
    hi - lo
}

/// The organ's problem as it is held, under gravity along −y.
fn problem(organ: &Organ, material: ElasticMaterial) -> Result<StaticProblem, SceneError> {
    let mut p = StaticProblem::new(&organ.mesh, material)?;
    p.set_gravity(DVec3::new(0.0, -tissue_fem::GRAVITY, 0.0))?;
    if organ.setting != Setting::Cantilever {
        p.set_floor(Plane {
            point: DVec3::ZERO,
            normal: DVec3::Y,
        })?;
    }
    p.set_settings(SolverSettings {
        residual_tolerance: RESIDUAL_TOLERANCE,
        max_iterations: 200,
        load_steps: 4,
        ..SolverSettings::default()
    })?;
    match organ.setting {
        Setting::Tray => {
            // The tray's friction (the trainer's 0.5) sticks the nodes that rest on it: the
            // bottom nodes held in x and z, free to lift off. (Two of them held, the rest
            // sliding freely, left the organ's top free to shear under the probe: its pressed
            // nodes slid off the sphere's apex and the force at a depth came out 15–20 % below
            // a sticking tray's on the 10 cm box.) An organ that touches the tray at one node
            // (the bunny) is held as well by the bottom node farthest from it — "bottom":
            // within 1 % of the height above the lowest — across the line between them (in z
            // when that line runs more along x, else in x): no spin about y. (Held by the
            // lowest node's neighbour instead, the short lever left the spin all but free and
            // Newton crept along it for hundreds of iterations.)
            let rest = p.rest_positions().to_vec();
            let (lowest, highest) = rest
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), q| {
                    (lo.min(q.y), hi.max(q.y))
                });
            let bottom: Vec<u32> = p.nodes_where(|q| q.y <= lowest + 1e-6);
            let Some(&a) = bottom.first() else {
                return Err(SceneError::mesh(&organ.label, "an organ without nodes"));
            };
            for &n in &bottom {
                p.fix_axes(n, [true, false, true])?;
            }
            if bottom.len() == 1 {
                let pa = rest[a as usize];
                let band = lowest + 0.01 * (highest - lowest);
                let across = |n: u32| {
                    let d = rest[n as usize] - pa;
                    d.x.hypot(d.z)
                };
                let far = p
                    .nodes_where(|q| q.y <= band)
                    .into_iter()
                    .max_by(|&i, &j| across(i).total_cmp(&across(j)))
                    .filter(|&n| across(n) > 0.0)
                    .or_else(|| {
                        // A body without a base: the nearest node beside the lowest one.
                        (0..rest.len() as u32)
                            .filter(|&n| across(n) > 0.0)
                            .min_by(|&i, &j| rest[i as usize].y.total_cmp(&rest[j as usize].y))
                    });
                if let Some(b) = far {
                    let d = rest[b as usize] - pa;
                    let held = if d.x.abs() >= d.z.abs() {
                        [false, false, true]
                    } else {
                        [true, false, false]
                    };
                    p.fix_axes(b, held)?;
                }
            }
        }
        Setting::Appendix => {
            p.clamp_where(|q| q.x < f64::from(APPENDIX_BASE_X));
        }
        Setting::Cantilever => {
            for node in organ.clamped_nodes() {
                p.clamp(node)?;
            }
        }
    }
    Ok(p)
}

/// The settled organ's top near `at` (within `reach` horizontally), if any node is there.
fn top_near(solution: &StaticSolution, at: [f32; 2], reach: f64) -> Option<f64> {
    solution
        .positions
        .iter()
        .filter(|q| (q.x - f64::from(at[0])).hypot(q.z - f64::from(at[1])) <= reach)
        .map(|q| q.y)
        .reduce(f64::max)
}

/// Solves the organ's settled and pressed states: under gravity on its support, then with the
/// probe's tip pressed at each depth of `plan` (see [`ReferencePlan`]).
///
/// # Errors
/// [`SceneError::Reference`] for a material or setting the solver refuses (a Poisson ratio
/// above 0.495, …) or a matrix it cannot factor; [`SceneError::Tool`] when the press point is
/// not over the organ or a depth is negative or not finite.
pub fn reference(organ: &Organ, plan: &ReferencePlan) -> Result<ReferenceSummary, SceneError> {
    let _span = tracing::info_span!("fem_reference", organ = %organ.label).entered();
    if let Some(d) = plan.depths.iter().find(|d| !(d.is_finite() && **d >= 0.0)) {
        return Err(SceneError::Tool(format!(
            "a press depth of {d} cm: give depths ≥ 0"
        )));
    }
    if !(plan.probe_radius.is_finite() && plan.probe_radius > 0.0) {
        return Err(SceneError::Tool(format!(
            "a probe radius of {} cm: give a positive radius",
            plan.probe_radius
        )));
    }
    let settled = problem(organ, plan.material)?.solve()?;
    let height_loaded = height(&settled.rest);
    let height_settled = height(&settled.positions);
    let settled_f32: Vec<glam::Vec3A> = settled
        .positions
        .iter()
        .map(|p| p.as_vec3().into())
        .collect();
    let tip_deflection = organ.tip_deflection(&settled_f32);
    let reach = f64::from(organ.extent()) / 20.0 + f64::from(plan.probe_radius);
    let top = top_near(&settled, plan.at, reach);
    let press_top = match (top, plan.depths.is_empty()) {
        (_, true) => 0.0,
        (Some(top), false) => top,
        (None, false) => {
            return Err(SceneError::Tool(format!(
                "the press point {},{} is not over the organ (no node within {reach:.2} cm of \
                 it)",
                plan.at[0], plan.at[1]
            )))
        }
    };
    let mut presses = Vec::with_capacity(plan.depths.len());
    for &depth in &plan.depths {
        let mut p = problem(organ, plan.material)?;
        p.set_indenter(SphereIndenter {
            contact: DVec3::new(f64::from(plan.at[0]), press_top, f64::from(plan.at[1])),
            direction: -DVec3::Y,
            radius: f64::from(plan.probe_radius),
            depth: f64::from(depth),
        })?;
        let s = p.solve()?;
        presses.push(ReferencePress {
            depth,
            force_n: s.indenter_force.length() * NEWTONS_PER_DYN,
            report: s.report,
        });
    }
    Ok(ReferenceSummary {
        height_loaded,
        height_settled,
        tip_deflection,
        top,
        settle: settled.report,
        presses,
    })
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;

    fn block(side: f32, cells: u32) -> Organ {
        let mesh = tissue_mesh::tet_box(cells, cells, cells, glam::Vec3::splat(side)).unwrap();
        Organ::from_tets(&mesh, "a block").unwrap()
    }

    /// A block of ν = 0 on its tray settles as a column under its own weight,
    /// `δ = ρ g H² / (2E)` (small strain: uniaxial, no lateral stress), within 5 % at 8 cells
    /// a side (the sag converges as the cells shrink: −25, −11, −5.7 and −3.5 % at 2, 4, 6
    /// and 8 cells a side, `tet_box`'s tets); twice E
    /// halves the sag, twice ρ doubles it; the probe's force grows with the depth and doubles
    /// with E.
    #[test]
    fn a_block_settles_and_resists_the_probe_as_its_material_says() {
        let organ = block(2.0, 8);
        let plan = |young_kpa: f64, density: f64| ReferencePlan {
            material: ElasticMaterial {
                young_kpa,
                poisson: 0.0,
                density,
            },
            probe_radius: 0.4,
            at: [0.0, 0.0],
            depths: vec![0.05, 0.1],
        };
        let base = reference(&organ, &plan(20.0, 1.0)).unwrap();
        let sag = |s: &ReferenceSummary| s.height_loaded - s.height_settled;
        let h = base.height_loaded;
        let analytic = 1.0 * tissue_fem::GRAVITY * h * h / (2.0 * 20.0 * tissue_fem::KPA);
        assert!(
            (sag(&base) - analytic).abs() <= 0.05 * analytic,
            "sag {} against ρgH²/2E = {analytic}",
            sag(&base)
        );
        assert!(base.settle.converged);
        let stiff = reference(&organ, &plan(40.0, 1.0)).unwrap();
        let heavy = reference(&organ, &plan(20.0, 2.0)).unwrap();
        let r_e = sag(&stiff) / sag(&base);
        let r_rho = sag(&heavy) / sag(&base);
        assert!((0.45..=0.55).contains(&r_e), "twice E: sag × {r_e}");
        assert!((1.9..=2.1).contains(&r_rho), "twice ρ: sag × {r_rho}");
        let [shallow, deep] = [&base.presses[0], &base.presses[1]];
        assert!(
            shallow.report.converged && deep.report.converged,
            "{:?}\n{:?}",
            shallow.report,
            deep.report
        );
        assert!(deep.force_n > 1.5 * shallow.force_n, "{shallow:?} {deep:?}");
        let f_e = stiff.presses[1].force_n / deep.force_n;
        assert!((1.9..=2.1).contains(&f_e), "twice E: force × {f_e}");
    }

    /// A slender cantilever (L/H = 10, ν = 0) under its own weight: the reference's tip
    /// deflection against Euler–Bernoulli, `δ = q L⁴/(8 E I)`, `q = ρ g H²`, `I = H⁴/12`.
    /// `tet_box`'s linear tetrahedra, cubic cells, are stiff in bending: 4 cells through
    /// the thickness come within 20 % (measured −17 %), 6 within 11 % (−8 %), the error
    /// shrinking with the cells (tissue-fem's own beam test, with cells half as long, comes
    /// within 1.9 %). A trainer run and its reference share the mesh, so this error cancels
    /// between them.
    #[test]
    fn a_cantilever_bends_towards_beam_theory() {
        let (length, thickness) = (10.0f32, 1.0f32);
        let material = ElasticMaterial {
            young_kpa: 10_000.0,
            poisson: 0.0,
            density: 1.0,
        };
        let (l, h) = (f64::from(length), f64::from(thickness));
        let q = material.density * tissue_fem::GRAVITY * h * h;
        let analytic = q * l.powi(4) / (8.0 * material.young() * h.powi(4) / 12.0);
        let error = |cells: u32| {
            let organ = Organ::cantilever(length, thickness, cells).unwrap();
            let plan = ReferencePlan {
                material,
                probe_radius: 0.4,
                at: [0.0, 0.0],
                depths: Vec::new(),
            };
            let s = reference(&organ, &plan).unwrap();
            assert!(s.settle.converged);
            s.tip_deflection.unwrap() / analytic - 1.0
        };
        let (coarse, fine) = (error(4), error(6));
        let figures = format!(
            "tip deflection {coarse:+.4} (4 cells), {fine:+.4} (6 cells) of beam theory \
             ({analytic:.4} cm)"
        );
        assert!(coarse.abs() < 0.20 && fine.abs() < 0.11, "{figures}");
        assert!(fine.abs() < coarse.abs(), "{figures}");
    }

    #[test]
    fn a_press_off_the_organ_is_refused() {
        let organ = block(2.0, 2);
        let plan = ReferencePlan {
            material: ElasticMaterial {
                young_kpa: 10.0,
                poisson: 0.3,
                density: 1.0,
            },
            probe_radius: 0.4,
            at: [5.0, 0.0],
            depths: vec![0.1],
        };
        let e = reference(&organ, &plan).unwrap_err();
        assert!(e.to_string().contains("not over the organ"), "{e}");
        let bad = ReferencePlan {
            material: ElasticMaterial {
                poisson: 0.6,
                ..plan.material
            },
            at: [0.0, 0.0],
            ..plan
        };
        let e = reference(&organ, &bad).unwrap_err();
        assert_eq!(e.kind(), crate::SceneErrorKind::Parameters, "{e}");
    }
}
