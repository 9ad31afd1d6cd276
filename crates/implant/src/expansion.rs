//! Expansion over weeks: an expander filled on a schedule under a skin region that
//! grows, then removed; the flap it leaves and how sure we are of it.
//!
//! ## The run ([`expand`])
//! 1. **Fills.** At each fill the expander (the same base, built for the new volume: the
//!    injected total less the leakage) replaces the last one under the tissue *where the
//!    tissue is* ([`Insertion`]'s warm refill: positions, pocket and grown rest metric kept; the
//!    expander rises from its previous shape) and the mechanics settle.
//! 2. **Growth.** Between fills, in steps of [`GrowthParams::step_hours`] (at most a day): every
//!    region triangle's total area stretch `θ` is read from the settled state, its `θg` updated
//!    by [`GrowthLaw::step`] (backward Euler in closed form), the in-plane springs of both
//!    layers given the grown metric ([`TissueLayers::grow`]), and the mechanics re-settled from
//!    the previous state.
//! 3. **Removal.** The material points over the expander's base at the end form the flap
//!    (recruited skin included: the region's boundary, not the base's rim, is held). The flap
//!    relaxes to its grown area (`Σ θg·A₀`) and, raised off the capsule, loses the explant
//!    retraction [`GrowthParams::flap_release`]: `A_flap = Σ θg·A₀ / release`. The linear
//!    retraction is `1 − √(A_flap / A_dome)`. The geometric gain is the dome's area less the
//!    base's at the injected total without growth or leakage (a reference run), the efficiency
//!    the grown gain (`Σ θg·A₀ − A_base`) over it.
//!
//! ## The band ([`BandOptions`], [`Band`])
//! P5/P50/P95 of the flap area, the retraction and the efficiency over samples of the uncertain
//! parameters: `ln k ~ N(−3.096, 0.230)`, the threshold ± [`HUMAN_THRESHOLD_SPREAD`],
//! leakage `N(leak, 0.125)` truncated to [0, 0.6], stiffness × U(0.9, 1.1). Each sample is
//! seeded by its index, run in parallel (rayon): the band does not depend on the thread count.
//!
//! A sample is not a full mechanical run but a **surrogate** checked against full runs
//! (`tests/it/expansion.rs`): the growth is integrated per triangle over the nominal run's own
//! stretch history `θ(t)`, scaled per triangle by how the stretch changes with the expander's
//! volume (a ladder of reference runs without growth, interpolated linearly in volume) and
//! with the skin's stiffness (two reference runs at ×0.9 and ×1.1). The nominal run carries
//! what growth does to the mechanics (recruitment, relaxation); the ladder carries the sample's
//! leakage.

use std::ops::ControlFlow;
use std::time::{Duration, Instant};

use glam::{Vec3, Vec3A};
use rayon::prelude::*;
use tissue_mesh::TriMesh;

use crate::growth::{
    GrowthParams, Protocol, HUMAN_THRESHOLD_SPREAD, LEAKAGE_SD, LN_RATE_MEAN, LN_RATE_SD,
};
use crate::{
    place_implant, Implant, ImplantError, ImplantSpec, Insertion, InsertionParams, Layer,
    TissueLayers,
};
use crate::{Param, ProtocolField};

/// Where the expander goes on a simulation surface, and the mechanics.
#[derive(Debug, Clone)]
pub struct ExpansionSetup {
    /// The skin region the mechanics run on (layer 1 at rest, normals out of the body).
    pub region: TriMesh,
    /// The expander's centre on the region (cm).
    pub centre: Vec3,
    /// The body's outward normal there.
    pub normal: Vec3,
    /// The expander's local `x` direction.
    pub tangent: Vec3,
    /// The expander (shape and vertex budget; its volume is set per fill).
    pub implant: ImplantSpec,
    /// Tissue, implant and run parameters.
    pub params: InsertionParams,
}

/// How the band is sampled.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BandOptions {
    /// Samples (≥ 8 for a band; the full band is 32).
    pub samples: usize,
    /// The seed: sample `i` draws from a generator seeded by `seed` and `i`.
    pub seed: u64,
    /// Reference runs of the volume ladder (≥ 2).
    pub rungs: usize,
}

impl Default for BandOptions {
    /// 32 samples, seed 21, a ladder of 5 volumes.
    fn default() -> Self {
        BandOptions {
            samples: 32,
            seed: 21,
            rungs: 5,
        }
    }
}

/// What the run is doing (for progress).
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub enum ExpansionStage {
    /// A reference run without growth (the geometric gain, the band's ladder): `index` of
    /// `count`.
    Reference {
        /// 0-based.
        index: usize,
        /// How many.
        count: usize,
    },
    /// Settling after fill `index` of `count`.
    Fill {
        /// 0-based.
        index: usize,
        /// How many.
        count: usize,
    },
    /// Settling after a growth step.
    Grow,
}

/// Progress of an expansion run.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ExpansionProgress {
    /// What is running.
    pub stage: ExpansionStage,
    /// The protocol's day (of the nominal run; reference runs report 0).
    pub day: f64,
    /// Steps in the current settle.
    pub steps: u64,
    /// Its step budget.
    pub budget: u64,
}

/// The nominal run's state after a fill or a growth step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ExpansionRecord {
    /// The day.
    pub day: f64,
    /// Saline injected so far (cm³).
    pub injected: f64,
    /// The expander's volume (injected less leakage, cm³).
    pub volume: f64,
    /// The region's area now less its area at rest (cm²): the elastic and grown gain together.
    pub area_gain: f64,
    /// The region's grown area `Σ θg·A₀` (cm²).
    pub grown_area: f64,
    /// `Σ (θg − 1)·A₀` over the region (cm²): the skin made by growth.
    pub grown_gain: f64,
    /// The area-weighted mean `θg` over the region.
    pub mean_growth: f64,
    /// Steps the settle took.
    pub steps: u64,
    /// Whether it settled within its budget.
    pub settled: bool,
}

/// P5, P50 and P95.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Percentiles {
    /// 5th percentile.
    pub p5: f64,
    /// Median.
    pub p50: f64,
    /// 95th percentile.
    pub p95: f64,
}

impl Percentiles {
    /// Of `values` (linear interpolation between order statistics); NaN when empty.
    pub fn of(values: &[f64]) -> Percentiles {
        let mut v: Vec<f64> = values.to_vec();
        v.sort_by(f64::total_cmp);
        let at = |q: f64| {
            if v.is_empty() {
                return f64::NAN;
            }
            let x = q * (v.len() - 1) as f64;
            let (i, f) = (x.floor() as usize, x.fract());
            let j = (i + 1).min(v.len() - 1);
            v[i] + f * (v[j] - v[i])
        };
        Percentiles {
            p5: at(0.05),
            p50: at(0.5),
            p95: at(0.95),
        }
    }
}

/// One draw of the uncertain parameters.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SampleParams {
    /// `k` (1/h).
    pub rate: f64,
    /// The growth threshold `c`.
    pub threshold: f64,
    /// The leakage fraction.
    pub leakage: f64,
    /// The skin's stiffness factor.
    pub stiffness: f64,
}

impl SampleParams {
    /// Draw `index` of a band seeded by `seed`, around `growth` and `protocol` (module docs).
    pub fn draw(seed: u64, index: usize, growth: &GrowthParams, protocol: &Protocol) -> Self {
        let mut rng = SplitMix::new(seed ^ (index as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15));
        let rate = (LN_RATE_MEAN + LN_RATE_SD * rng.normal()).exp() * growth.law.rate
            / crate::growth::RATE_MEDIAN;
        let c = growth.law.threshold;
        let threshold = if c > 1.0 {
            (c + HUMAN_THRESHOLD_SPREAD * (2.0 * rng.uniform() - 1.0)).max(1.0)
        } else {
            1.0
        };
        let leakage = loop {
            let l = protocol.leakage + LEAKAGE_SD * rng.normal();
            if (0.0..=0.6).contains(&l) {
                break l;
            }
        };
        let stiffness = growth.stiffness * (0.9 + 0.2 * rng.uniform());
        SampleParams {
            rate,
            threshold,
            leakage,
            stiffness,
        }
    }

    /// `growth` and `protocol` with this draw's values: what a full run of the sample uses.
    pub fn apply(&self, growth: &GrowthParams, protocol: &Protocol) -> (GrowthParams, Protocol) {
        let mut g = *growth;
        g.law.rate = self.rate;
        g.law.threshold = self.threshold;
        g.stiffness = self.stiffness;
        let p = Protocol {
            leakage: self.leakage,
            ..protocol.clone()
        };
        (g, p)
    }
}

/// The flap figures of one sample.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SampleResult {
    /// Its parameters.
    pub params: SampleParams,
    /// The dome's area at removal (cm²).
    pub dome_area: f64,
    /// The flap's grown area (cm²).
    pub grown_area: f64,
    /// The flap's area after removal (cm²).
    pub flap_area: f64,
    /// The linear retraction at removal.
    pub retraction: f64,
    /// The efficiency.
    pub efficiency: f64,
}

/// The uncertainty band at removal.
#[derive(Debug, Clone, PartialEq)]
pub struct Band {
    /// The seed.
    pub seed: u64,
    /// Every sample, in index order.
    pub samples: Vec<SampleResult>,
    /// The flap's area after removal (cm²).
    pub flap_area: Percentiles,
    /// The linear retraction.
    pub retraction: Percentiles,
    /// The efficiency.
    pub efficiency: Percentiles,
    /// The flap's grown area (cm²).
    pub grown_area: Percentiles,
}

/// What an expansion gives the surgeon. Areas in cm².
#[derive(Debug, Clone)]
pub struct ExpansionOutcome {
    /// After every fill and growth step, in order.
    pub records: Vec<ExpansionRecord>,
    /// Per region triangle: the total area stretch at removal.
    pub theta: Vec<f64>,
    /// Per region triangle: the area growth at removal.
    pub theta_g: Vec<f64>,
    /// Per region triangle: whether it is over the expander's base at removal (the flap).
    pub flap: Vec<bool>,
    /// The expander's base area.
    pub base_area: f64,
    /// The flap's scan area less the base's: the skin recruited from around the expander.
    pub recruited_area: f64,
    /// The flap's area on the expander at removal.
    pub dome_area: f64,
    /// The flap's grown area `Σ θg·A₀`.
    pub grown_area: f64,
    /// The flap's area after removal (relaxed, raised).
    pub flap_area: f64,
    /// `1 − √(flap_area / dome_area)`.
    pub retraction: f64,
    /// The dome's area less the base's at the injected total, without growth or leakage.
    pub geometric_gain: f64,
    /// `grown_area − base_area`.
    pub grown_gain: f64,
    /// `grown_gain / geometric_gain`.
    pub efficiency: f64,
    /// The flap's mean area growth, `grown_area / (base_area + recruited_area)`.
    pub flap_growth: f64,
    /// The region at rest.
    pub region_rest: TriMesh,
    /// The region on the expander at removal.
    pub region_expanded: TriMesh,
    /// The expander at removal.
    pub implant_final: TriMesh,
    /// Steps of the nominal run.
    pub steps: u64,
    /// Steps of the reference runs.
    pub reference_steps: u64,
    /// Wall time of the whole.
    pub wall_time: Duration,
    /// The band, when asked for.
    pub band: Option<Band>,
}

/// The window (steps) of a growth step's re-settle: the mean speed under the run's
/// `settle_speed` for this many steps in a row ends it ([`Insertion`]'s quick rule).
pub const QUICK_WINDOW: u64 = 10;

/// The progress callback of [`expand`]: called from the runs' threads.
pub type ExpansionMonitor<'a> = &'a (dyn Fn(&ExpansionProgress) -> ControlFlow<()> + Sync);

/// One growth step of the nominal run, kept for the band.
struct StepRecord {
    hours: f64,
    injected: f64,
    theta: Vec<f32>,
}

struct Shared<'a> {
    setup: &'a ExpansionSetup,
    rest: TissueLayers,
    areas: Vec<f64>,
    base_end: u32,
    base_area: f64,
    reach: f32,
}

impl Shared<'_> {
    fn implant(&self, volume: f64) -> Result<Implant, ImplantError> {
        let mut spec = self.setup.implant;
        spec.volume_cm3 = volume;
        place_implant(
            &self.rest,
            &spec,
            self.setup.centre,
            self.setup.normal,
            self.setup.tangent,
        )
    }

    /// The flap: region triangles whose layer-2 centroid lies on the expander's dome (within
    /// half a mean edge of it), where the skin is carried by the expander.
    fn on_dome(&self, layers: &TissueLayers, implant: &TriMesh) -> Vec<bool> {
        let position = layers.system().particles().positions();
        let at = |v: u32| position[TissueLayers::particle(Layer::Inner, v) as usize];
        let p = implant.positions();
        let dome: Vec<[Vec3A; 3]> = implant
            .triangles()
            .iter()
            .filter(|t| t.iter().any(|&v| v >= self.base_end))
            .map(|t| t.map(|v| Vec3A::from(p[v as usize])))
            .collect();
        let reach = self.reach;
        layers
            .rest(Layer::Outer)
            .triangles()
            .iter()
            .map(|&[a, b, c]| {
                let x = (at(a) + at(b) + at(c)) / 3.0;
                dome.iter().any(|&[a, b, c]| {
                    let (q, _) = tissue_bvh::closest_point_on_triangle(x, a, b, c);
                    q.distance(x) <= reach
                })
            })
            .collect()
    }
}

fn params_for(setup: &ExpansionSetup, stiffness: f64) -> InsertionParams {
    let mut p = setup.params.clone();
    p.layers.young *= stiffness;
    p
}

/// Runs `protocol` under `setup` with `growth`, and the band when `band` is given (module
/// docs). `monitor` is called between steps from the runs' threads and cancels with
/// [`ControlFlow::Break`].
///
/// # Errors
/// [`ImplantError::InvalidProtocol`], [`ImplantError::InvalidParameter`] (growth, band), the
/// set-up and run errors of [`Insertion`] (a cancel is [`ImplantError::Cancelled`]).
pub fn expand(
    setup: &ExpansionSetup,
    protocol: &Protocol,
    growth: &GrowthParams,
    band: Option<&BandOptions>,
    monitor: ExpansionMonitor<'_>,
) -> Result<ExpansionOutcome, ImplantError> {
    let _span = tracing::info_span!("expansion", fills = protocol.fills.len()).entered();
    let start = Instant::now();
    protocol.validate()?;
    growth.check()?;
    if let Some(b) = band {
        if !(8..=4096).contains(&b.samples) {
            return Err(ImplantError::InvalidParameter {
                param: Param::BandSamples,
                value: b.samples as f64,
                expected: "8 to 4096 (32 for the issue's band)".into(),
            });
        }
        if !(2..=16).contains(&b.rungs) {
            return Err(ImplantError::InvalidParameter {
                param: Param::BandRungs,
                value: b.rungs as f64,
                expected: "2 to 16 reference volumes".into(),
            });
        }
    }
    let params = params_for(setup, growth.stiffness);
    let rest = TissueLayers::new(&setup.region, &params.layers)?;
    let areas = setup.region.triangle_areas();
    let mut shared = Shared {
        setup,
        rest,
        areas,
        base_end: 0,
        base_area: 0.0,
        reach: 0.5 * crate::contact_run::mean_edge_length(&setup.region),
    };
    let probe = shared.implant(protocol.injected_total())?;
    shared.base_end = probe.base().end;
    let mesh = probe.mesh();
    let p = mesh.positions();
    shared.base_area = mesh
        .triangles()
        .iter()
        .filter(|t| t.iter().all(|&v| v < shared.base_end))
        .map(|&[a, b, c]| {
            let (a, b, c) = (p[a as usize], p[b as usize], p[c as usize]);
            0.5 * f64::from((b - a).cross(c - a).length())
        })
        .sum();
    let shared = &shared;

    let (nominal, reference) = rayon::join(
        || nominal_run(shared, protocol, growth, &params, band.is_some(), monitor),
        || reference_runs(shared, protocol, growth, band, monitor),
    );
    let (mut outcome, history) = nominal?;
    let reference = reference?;
    let g = reference.geometric_gain;
    outcome.geometric_gain = g;
    outcome.efficiency = outcome.grown_gain / g;
    outcome.reference_steps = reference.steps;
    if let Some(options) = band {
        outcome.band = Some(surrogate_band(
            shared, protocol, growth, options, &outcome, &history, &reference,
        ));
    }
    outcome.wall_time = start.elapsed();
    Ok(outcome)
}

/// Settles `insertion`, reporting as `stage` on `day`.
fn settle(
    insertion: &mut Insertion,
    budget: u64,
    stage: ExpansionStage,
    day: f64,
    quick: bool,
    monitor: ExpansionMonitor<'_>,
) -> Result<(u64, bool), ImplantError> {
    // A day's growth from a settled state is a small change: the criterion's speed floor on a
    // window of QUICK_WINDOW steps ends its settle.
    let quick = quick.then_some(QUICK_WINDOW);
    insertion.settle(budget, quick, |p| {
        monitor(&ExpansionProgress {
            stage,
            day,
            steps: p.steps,
            budget,
        })
    })
}

fn nominal_run(
    shared: &Shared<'_>,
    protocol: &Protocol,
    growth: &GrowthParams,
    params: &InsertionParams,
    keep_history: bool,
    monitor: ExpansionMonitor<'_>,
) -> Result<(ExpansionOutcome, Vec<StepRecord>), ImplantError> {
    let _span = tracing::info_span!("expansion_nominal").entered();
    let region = &shared.setup.region;
    let n = region.triangle_count();
    let rest_area: f64 = shared.areas.iter().sum();
    let budget = params.run.stop.max_steps;
    let mut theta_g = vec![1.0f64; n];
    let mut theta = vec![1.0f64; n];
    let mut records = Vec::new();
    let mut history = Vec::new();
    let mut insertion: Option<Insertion> = None;
    let mut day = protocol.start_day();
    let mut steps = 0u64;
    let count = protocol.fills.len();

    // `injected`: what is in the expander during the settle (a growth step ending on a fill's
    // day is before that fill).
    let record = |insertion: &Insertion,
                  theta_g: &[f64],
                  day: f64,
                  injected: f64,
                  taken: (u64, bool)|
     -> ExpansionRecord {
        let grown: f64 = theta_g.iter().zip(&shared.areas).map(|(g, a)| g * a).sum();
        ExpansionRecord {
            day,
            injected,
            volume: injected * (1.0 - protocol.leakage),
            area_gain: insertion.contact_run().layers().outer_area() - rest_area,
            grown_area: grown,
            grown_gain: grown - rest_area,
            mean_growth: grown / rest_area,
            steps: taken.0,
            settled: taken.1,
        }
    };

    // Grows from `day` to `until` in steps of at most `step_hours`, re-settling after each.
    let advance = |insertion: &mut Insertion,
                   theta_g: &mut [f64],
                   theta: &mut [f64],
                   day: &mut f64,
                   until: f64,
                   records: &mut Vec<ExpansionRecord>,
                   history: &mut Vec<StepRecord>,
                   steps: &mut u64|
     -> Result<(), ImplantError> {
        let step_days = growth.step_hours / 24.0;
        while until - *day > 1e-9 {
            let dt = step_days.min(until - *day);
            insertion.contact_run().layers().area_stretch(theta);
            for (g, &t) in theta_g.iter_mut().zip(theta.iter()) {
                *g = growth.law.step(*g, t, 24.0 * dt);
            }
            if keep_history {
                history.push(StepRecord {
                    hours: 24.0 * dt,
                    injected: protocol.injected_by(*day),
                    theta: theta.iter().map(|&t| t as f32).collect(),
                });
            }
            insertion.layers_mut().grow(theta_g)?;
            let injected = protocol.injected_by(*day);
            *day += dt;
            let taken = settle(insertion, budget, ExpansionStage::Grow, *day, true, monitor)?;
            *steps += taken.0;
            records.push(record(insertion, theta_g, *day, injected, taken));
        }
        Ok(())
    };

    for (index, fill) in protocol.fills.iter().enumerate() {
        if let Some(ins) = insertion.as_mut() {
            advance(
                ins,
                &mut theta_g,
                &mut theta,
                &mut day,
                fill.day,
                &mut records,
                &mut history,
                &mut steps,
            )?;
        }
        day = fill.day;
        let volume = protocol.volume_by(fill.day, protocol.leakage);
        let implant = shared.implant(volume)?;
        let mut ins = match insertion.take() {
            None => Insertion::new(region, &implant, params)?,
            Some(previous) => previous.refill(&implant, params)?,
        };
        let taken = settle(
            &mut ins,
            budget,
            ExpansionStage::Fill { index, count },
            day,
            false,
            monitor,
        )?;
        steps += taken.0;
        if !taken.1 {
            tracing::warn!(index, "the fill did not settle within its budget");
        }
        records.push(record(
            &ins,
            &theta_g,
            day,
            protocol.injected_by(day),
            taken,
        ));
        insertion = Some(ins);
    }
    let mut ins = insertion.ok_or_else(|| ImplantError::InvalidProtocol {
        field: ProtocolField::Fills,
        problem: "no fill: give at least one (day, volume)".into(),
    })?;
    advance(
        &mut ins,
        &mut theta_g,
        &mut theta,
        &mut day,
        protocol.removal_day,
        &mut records,
        &mut history,
        &mut steps,
    )?;
    let implant_final = ins.outcome_implant()?;
    let layers = ins.contact_run().layers();
    layers.area_stretch(&mut theta);
    let flap = shared.on_dome(layers, &implant_final);
    let sum = |f: &dyn Fn(usize) -> f64| -> f64 { (0..n).filter(|&t| flap[t]).map(f).sum() };
    let dome_area = sum(&|t| theta[t] * shared.areas[t]);
    let grown_area = sum(&|t| theta_g[t] * shared.areas[t]);
    let flap_scan = sum(&|t| shared.areas[t]);
    let flap_area = grown_area / growth.flap_release;
    let region_expanded = layers.current(Layer::Outer)?;
    Ok((
        ExpansionOutcome {
            records,
            base_area: shared.base_area,
            recruited_area: flap_scan - shared.base_area,
            dome_area,
            grown_area,
            flap_area,
            retraction: 1.0 - (flap_area / dome_area).sqrt(),
            geometric_gain: f64::NAN,
            grown_gain: grown_area - shared.base_area,
            efficiency: f64::NAN,
            flap_growth: grown_area / flap_scan,
            theta,
            theta_g,
            flap,
            region_rest: region.clone(),
            region_expanded,
            implant_final,
            steps,
            reference_steps: 0,
            wall_time: Duration::ZERO,
            band: None,
        },
        history,
    ))
}

/// The reference runs without growth: the volume ladder (its top the injected total: the
/// geometric gain) and, for the band, the top at ×0.9 and ×1.1 stiffness.
struct Reference {
    /// `(volume, θ per triangle)`, increasing volume.
    ladder: Vec<(f64, Vec<f32>)>,
    /// θ at the top volume with the stiffness × 0.9 and × 1.1 (relative to the growth's).
    stiff: Option<[Vec<f32>; 2]>,
    geometric_gain: f64,
    steps: u64,
}

fn reference_runs(
    shared: &Shared<'_>,
    protocol: &Protocol,
    growth: &GrowthParams,
    band: Option<&BandOptions>,
    monitor: ExpansionMonitor<'_>,
) -> Result<Reference, ImplantError> {
    let _span = tracing::info_span!("expansion_reference").entered();
    let region = &shared.setup.region;
    let n = region.triangle_count();
    let top = protocol.injected_total();
    let rungs = band.map_or(1, |b| b.rungs);
    let count = rungs + if band.is_some() { 2 } else { 0 };
    let params = params_for(shared.setup, growth.stiffness);
    let budget = params.run.stop.max_steps;
    let mut ladder = Vec::with_capacity(rungs);
    let mut insertion: Option<Insertion> = None;
    let mut steps = 0;
    let mut theta = vec![1.0f64; n];
    for j in 1..=rungs {
        let volume = top * j as f64 / rungs as f64;
        let implant = shared.implant(volume)?;
        let mut ins = match insertion.take() {
            None => Insertion::new(region, &implant, &params)?,
            Some(previous) => previous.refill(&implant, &params)?,
        };
        let stage = ExpansionStage::Reference {
            index: j - 1,
            count,
        };
        steps += settle(&mut ins, budget, stage, 0.0, false, monitor)?.0;
        ins.contact_run().layers().area_stretch(&mut theta);
        ladder.push((volume, theta.iter().map(|&t| t as f32).collect()));
        insertion = Some(ins);
    }
    let ins = insertion.ok_or_else(|| ImplantError::InvalidParameter {
        param: Param::BandRungs,
        value: 0.0,
        expected: "at least 1".into(),
    })?;
    let layers = ins.contact_run().layers();
    let flap = shared.on_dome(layers, &ins.outcome_implant()?);
    layers.area_stretch(&mut theta);
    let dome: f64 = (0..n)
        .filter(|&t| flap[t])
        .map(|t| theta[t] * shared.areas[t])
        .sum();
    let geometric_gain = dome - shared.base_area;
    let stiff = if band.is_some() {
        let mut out = [Vec::new(), Vec::new()];
        for (i, factor) in [0.9, 1.1].into_iter().enumerate() {
            // Warm from the top rung, the skin's stiffness scaled.
            let mut ins = ins.clone();
            ins.layers_mut().scale_skin_stiffness(factor)?;
            let stage = ExpansionStage::Reference {
                index: rungs + i,
                count,
            };
            steps += settle(&mut ins, budget, stage, 0.0, true, monitor)?.0;
            ins.contact_run().layers().area_stretch(&mut theta);
            out[i] = theta.iter().map(|&t| t as f32).collect();
        }
        Some(out)
    } else {
        None
    };
    Ok(Reference {
        ladder,
        stiff,
        geometric_gain,
        steps,
    })
}

/// θ of triangle `t` at `volume` on the ladder (linear in volume from θ = 1 at 0; held
/// proportionally beyond the top).
fn ladder_theta(ladder: &[(f64, Vec<f32>)], volume: f64, t: usize) -> f64 {
    let mut below = (0.0, 1.0);
    for (v, theta) in ladder {
        let here = (*v, f64::from(theta[t]));
        if volume <= *v {
            let w = if here.0 > below.0 {
                (volume - below.0) / (here.0 - below.0)
            } else {
                1.0
            };
            return below.1 + w * (here.1 - below.1);
        }
        below = here;
    }
    below.1
}

fn surrogate_band(
    shared: &Shared<'_>,
    protocol: &Protocol,
    growth: &GrowthParams,
    options: &BandOptions,
    nominal: &ExpansionOutcome,
    history: &[StepRecord],
    reference: &Reference,
) -> Band {
    let _span = tracing::info_span!("expansion_band", samples = options.samples).entered();
    let n = shared.areas.len();
    let top = reference.ladder.last().map_or(1.0, |(v, _)| *v);
    let injected_end = protocol.injected_total();
    let samples: Vec<SampleResult> = (0..options.samples)
        .into_par_iter()
        .map(|i| {
            let params = SampleParams::draw(options.seed, i, growth, protocol);
            let law = crate::GrowthLaw {
                rate: params.rate,
                threshold: params.threshold,
                ..growth.law
            };
            let s = params.stiffness / growth.stiffness;
            // Per triangle: θ of the sample over θ of the nominal run at the same moment.
            let scale = |t: usize, injected: f64| -> f64 {
                let v_nom = injected * (1.0 - protocol.leakage);
                let v_s = injected * (1.0 - params.leakage);
                let volume = ladder_theta(&reference.ladder, v_s, t)
                    / ladder_theta(&reference.ladder, v_nom, t);
                let stiffness = match &reference.stiff {
                    Some([lo, hi]) => {
                        let at_top = ladder_theta(&reference.ladder, top, t);
                        let r = if s < 1.0 {
                            1.0 + (f64::from(lo[t]) / at_top - 1.0) * (1.0 - s) / 0.1
                        } else {
                            1.0 + (f64::from(hi[t]) / at_top - 1.0) * (s - 1.0) / 0.1
                        };
                        r.max(1e-3).powf((v_s / top).min(1.0))
                    }
                    None => 1.0,
                };
                volume * stiffness
            };
            let (mut dome, mut grown) = (0.0, 0.0);
            for t in 0..n {
                if !nominal.flap[t] {
                    continue;
                }
                let mut g = 1.0;
                for step in history {
                    let theta = f64::from(step.theta[t]) * scale(t, step.injected);
                    g = law.step(g, theta, step.hours);
                }
                let theta_end = nominal.theta[t] * scale(t, injected_end);
                dome += theta_end * shared.areas[t];
                grown += g * shared.areas[t];
            }
            let flap_area = grown / growth.flap_release;
            SampleResult {
                params,
                dome_area: dome,
                grown_area: grown,
                flap_area,
                retraction: 1.0 - (flap_area / dome).sqrt(),
                efficiency: (grown - shared.base_area) / nominal.geometric_gain,
            }
        })
        .collect();
    let of =
        |f: fn(&SampleResult) -> f64| Percentiles::of(&samples.iter().map(f).collect::<Vec<_>>());
    Band {
        seed: options.seed,
        flap_area: of(|s| s.flap_area),
        retraction: of(|s| s.retraction),
        efficiency: of(|s| s.efficiency),
        grown_area: of(|s| s.grown_area),
        samples,
    }
}

/// splitmix64 with a Box–Muller normal: a small, seedable, portable generator.
struct SplitMix(u64);

impl SplitMix {
    fn new(seed: u64) -> Self {
        SplitMix(seed)
    }

    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// In [0, 1).
    fn uniform(&mut self) -> f64 {
        (self.next() >> 11) as f64 / (1u64 << 53) as f64
    }

    fn normal(&mut self) -> f64 {
        let u1 = 1.0 - self.uniform();
        let u2 = self.uniform();
        (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn percentiles_interpolate() {
        let p = Percentiles::of(&[3.0, 1.0, 2.0, 4.0, 5.0]);
        assert_eq!(p.p50, 3.0);
        assert!((p.p5 - 1.2).abs() < 1e-12);
        assert!((p.p95 - 4.8).abs() < 1e-12);
    }

    #[test]
    fn draws_are_seeded_per_sample() {
        let g = GrowthParams::human();
        let p = Protocol::weekly(100.0, 10, 1.0, 0.29, 0.0).unwrap_or_else(|e| panic!("{e}"));
        let a = SampleParams::draw(7, 3, &g, &p);
        assert_eq!(a, SampleParams::draw(7, 3, &g, &p));
        assert_ne!(a, SampleParams::draw(7, 4, &g, &p));
        assert!((0.0..=0.6).contains(&a.leakage));
    }
}
