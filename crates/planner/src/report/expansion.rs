//! `mode: "expansion"`: expansion over weeks with skin growth, its weekly figures, the flap at
//! removal and its band, and the chart.

use serde::Serialize;

use super::{Inputs, Report, Tool};
use crate::error::{ErrorKind, PlanError};
use crate::job::JobMode;

/// One row of an expansion's weekly or daily figures.
#[derive(Debug, Clone, Serialize)]
pub struct ExpansionRow {
    /// The protocol day.
    pub day: f64,
    /// Whole weeks since the first fill.
    pub week: u32,
    /// Saline injected so far, cm³.
    pub injected_cm3: f64,
    /// The expander's volume (injected less leakage), cm³.
    pub volume_cm3: f64,
    /// The region's area now less at rest, cm² (elastic and grown).
    pub area_gain_cm2: f64,
    /// The region's grown area `Σ θg·A₀`, cm².
    pub grown_area_cm2: f64,
    /// The skin made by growth over the region, cm².
    pub grown_gain_cm2: f64,
    /// The region's area-weighted mean `θg`.
    pub mean_growth: f64,
}

/// The fill protocol as run.
#[derive(Debug, Clone, Serialize)]
pub struct ProtocolFigures {
    /// Every fill.
    pub fills: Vec<FillFigures>,
    /// The removal day.
    pub removal_day: f64,
    /// The leakage fraction.
    pub leakage: f64,
    /// The nominal volume, cm³.
    pub nominal_volume_cm3: f64,
    /// Injected in all, cm³.
    pub injected_cm3: f64,
}

/// One fill.
#[derive(Debug, Clone, Serialize)]
pub struct FillFigures {
    /// Its day.
    pub day: f64,
    /// Injected, cm³.
    pub volume_cm3: f64,
}

/// The growth parameters as run.
#[derive(Debug, Clone, Serialize)]
pub struct GrowthFigures {
    /// `k`, 1/h.
    pub rate_per_h: f64,
    /// `θp`.
    pub prestretch: f64,
    /// The threshold `c`.
    pub threshold: f64,
    /// The growth step, hours.
    pub step_h: f64,
    /// The flap's area release at removal.
    pub flap_release: f64,
}

/// The flap at removal.
#[derive(Debug, Clone, Serialize)]
pub struct FlapFigures {
    /// The expander's base area, cm².
    pub base_area_cm2: f64,
    /// The flap's scan area less the base's, cm².
    pub recruited_area_cm2: f64,
    /// The flap on the expander, cm².
    pub dome_area_cm2: f64,
    /// The flap's grown area, cm².
    pub grown_area_cm2: f64,
    /// The flap after removal, cm².
    pub flap_area_cm2: f64,
    /// The linear retraction at removal (a fraction).
    pub retraction: f64,
    /// The dome's area less the base's at the injected total without growth, cm².
    pub geometric_gain_cm2: f64,
    /// The grown area less the base's, cm².
    pub grown_gain_cm2: f64,
    /// Grown gain over geometric gain.
    pub efficiency: f64,
    /// The flap's mean `θg`.
    pub flap_growth: f64,
}

/// P5, P50, P95.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct Spread {
    /// 5th percentile.
    pub p5: f64,
    /// Median.
    pub p50: f64,
    /// 95th percentile.
    pub p95: f64,
}

impl From<tissue_implant::Percentiles> for Spread {
    fn from(p: tissue_implant::Percentiles) -> Self {
        Spread {
            p5: p.p5,
            p50: p.p50,
            p95: p.p95,
        }
    }
}

/// The band at removal.
#[derive(Debug, Clone, Serialize)]
pub struct BandFigures {
    /// Samples.
    pub samples: usize,
    /// The seed.
    pub seed: u64,
    /// How a sample is computed: `"surrogate"` (tissue-implant's expansion docs).
    pub method: BandMethod,
    /// The flap after removal, cm².
    pub flap_area_cm2: Spread,
    /// The linear retraction.
    pub retraction: Spread,
    /// The efficiency.
    pub efficiency: Spread,
    /// The flap's grown area, cm².
    pub grown_area_cm2: Spread,
}

/// How the band's samples are computed (`band.method`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum BandMethod {
    /// The surrogate of tissue-implant's expansion docs.
    Surrogate,
}

/// `mode: "expansion"`: the envelope and the expansion's figures.
pub type ExpansionReport = Report<ExpansionBody>;

/// An expansion's figures.
#[derive(Debug, Clone, Serialize)]
pub struct ExpansionBody {
    /// The fills.
    pub protocol: ProtocolFigures,
    /// The growth parameters.
    pub growth: GrowthFigures,
    /// Weekly figures (and at removal).
    pub weeks: Vec<ExpansionRow>,
    /// After every fill and growth step.
    pub days: Vec<ExpansionRow>,
    /// The flap at removal.
    pub flap: FlapFigures,
    /// The band, or null.
    pub band: Option<BandFigures>,
    /// Steps of the protocol's run.
    pub steps: u64,
    /// Steps of the reference runs.
    pub reference_steps: u64,
    /// Wall time, s.
    pub wall_time_s: f64,
}

/// The expansion report of `job` and its result.
pub(crate) fn expansion(
    tool: Tool,
    mut inputs: Inputs,
    request: &crate::PlanRequest,
    job: &tissue_app::ExpansionJob,
    planned: &tissue_app::PlannedExpansion,
) -> ExpansionReport {
    inputs.expand_weeks = request.expand_weeks;
    inputs.hold_weeks = Some(request.hold_weeks);
    inputs.leakage = Some(request.leakage);
    inputs.overfill = Some(request.overfill);
    inputs.band_samples = Some(request.band_samples);
    inputs.band_seed = Some(request.band_seed);
    inputs.growth_step_h = Some(request.growth_step_h);
    let o = &planned.outcome;
    let p = &job.protocol;
    let start = p.start_day();
    let row = |r: &tissue_implant::ExpansionRecord| ExpansionRow {
        day: r.day,
        week: ((r.day - start) / 7.0 + 1e-9).floor().max(0.0) as u32,
        injected_cm3: r.injected,
        volume_cm3: r.volume,
        area_gain_cm2: r.area_gain,
        grown_area_cm2: r.grown_area,
        grown_gain_cm2: r.grown_gain,
        mean_growth: r.mean_growth,
    };
    let days: Vec<ExpansionRow> = o.records.iter().map(row).collect();
    // The last record of every week (the state before the next week's fill), and removal.
    let mut weeks: Vec<ExpansionRow> = Vec::new();
    for (i, r) in days.iter().enumerate() {
        let next_week = days.get(i + 1).map(|n| n.week);
        if next_week != Some(r.week) && (r.day - start) > 0.0 {
            weeks.push(r.clone());
        }
    }
    let g = &job.growth;
    let body = ExpansionBody {
        protocol: ProtocolFigures {
            fills: p
                .fills
                .iter()
                .map(|f| FillFigures {
                    day: f.day,
                    volume_cm3: f.volume,
                })
                .collect(),
            removal_day: p.removal_day,
            leakage: p.leakage,
            nominal_volume_cm3: p.nominal_volume,
            injected_cm3: p.injected_total(),
        },
        growth: GrowthFigures {
            rate_per_h: g.law.rate,
            prestretch: g.law.prestretch,
            threshold: g.law.threshold,
            step_h: g.step_hours,
            flap_release: g.flap_release,
        },
        weeks,
        days,
        flap: FlapFigures {
            base_area_cm2: o.base_area,
            recruited_area_cm2: o.recruited_area,
            dome_area_cm2: o.dome_area,
            grown_area_cm2: o.grown_area,
            flap_area_cm2: o.flap_area,
            retraction: o.retraction,
            geometric_gain_cm2: o.geometric_gain,
            grown_gain_cm2: o.grown_gain,
            efficiency: o.efficiency,
            flap_growth: o.flap_growth,
        },
        band: o.band.as_ref().map(|b| BandFigures {
            samples: b.samples.len(),
            seed: b.seed,
            method: BandMethod::Surrogate,
            flap_area_cm2: b.flap_area.into(),
            retraction: b.retraction.into(),
            efficiency: b.efficiency.into(),
            grown_area_cm2: b.grown_area.into(),
        }),
        steps: o.steps,
        reference_steps: o.reference_steps,
        wall_time_s: o.wall_time.as_secs_f64(),
    };
    Report::new(tool, JobMode::Expansion, inputs, body)
}

impl ExpansionReport {
    /// Writes [`ExpansionReport::chart`] to `path` as a PNG, atomically.
    ///
    /// # Errors
    /// [`ErrorKind::Output`] when drawing, encoding or writing fails.
    pub fn write_chart(&self, path: &std::path::Path, size: (u32, u32)) -> Result<(), PlanError> {
        super::write_output(path, &self.chart(size)?, "chart")
    }

    /// The chart over the protocol's days as PNG bytes: the expander's volume (cm³), the
    /// region's area gain and the skin grown (cm²), and at removal the flap's area with its
    /// P5–P95 whisker when there is a band.
    ///
    /// # Errors
    /// [`ErrorKind::Output`] when drawing or encoding fails.
    pub fn chart(&self, size: (u32, u32)) -> Result<Vec<u8>, PlanError> {
        use tissue_render::{LineChart, Rgb, Series, Whisker};
        let series = |label: &str, color: [u8; 3], f: fn(&ExpansionRow) -> f64| Series {
            label: label.into(),
            color: Rgb(color),
            points: self.body.days.iter().map(|r| (r.day, f(r))).collect(),
        };
        let removal = self.body.protocol.removal_day;
        let mut whiskers = Vec::new();
        if let Some(b) = &self.body.band {
            whiskers.push(Whisker {
                x: removal,
                low: b.flap_area_cm2.p5,
                mid: b.flap_area_cm2.p50,
                high: b.flap_area_cm2.p95,
                color: Rgb([200, 60, 40]),
            });
        }
        let chart = LineChart {
            title: format!(
                "Expansion: {} fills to {:.0} cm3, removal day {:.0}, flap {:.1} cm2, retraction {:.0} %",
                self.body.protocol.fills.len(),
                self.body.protocol.injected_cm3,
                removal,
                self.body.flap.flap_area_cm2,
                100.0 * self.body.flap.retraction
            ),
            x_label: "day".into(),
            y_label: "cm2 / cm3".into(),
            series: vec![
                series("expander volume, cm3", [90, 90, 90], |r| r.volume_cm3),
                series("area gain, cm2", [40, 90, 200], |r| r.area_gain_cm2),
                series("skin grown, cm2", [30, 150, 60], |r| r.grown_gain_cm2),
                Series {
                    label: "flap after removal, P5-P95, cm2".into(),
                    color: Rgb([200, 60, 40]),
                    points: vec![(removal, self.body.flap.flap_area_cm2)],
                },
            ],
            whiskers,
        };
        let output = |e: &dyn std::fmt::Display| {
            PlanError::new(ErrorKind::Output, format!("cannot draw the chart: {e}"))
        };
        let image = chart.draw(size.0, size.1).map_err(|e| output(&e))?;
        image.encode_png().map_err(|e| output(&e))
    }
}
