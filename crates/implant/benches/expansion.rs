//! Expansion over weeks against Table 2, in the same run (the speed target of expansion over weeks: a 10-week
//! protocol with its band at most 40 × the Table 2 case).
//!
//! `cargo bench -p tissue-implant --bench expansion -- [repeats] [volume] [weeks] [samples]`
//! (defaults 3, 200, 10, 32): the Table 2 case (100 cm³, round 7 cm, the 65² plane) and the
//! clinical protocol (round 7 cm, `volume` cm³ nominal over `weeks` weekly fills and a week's
//! hold, human growth, leakage 0.29, the band of `samples`) alternate `repeats` times; it
//! prints both medians, their ratio, and the protocol's figures.
#![allow(missing_docs, clippy::print_stdout)]

use std::ops::ControlFlow;
use std::time::{Duration, Instant};

use glam::Vec3;
use tissue_implant::{
    default_radius, expand, place_implant, select_region_with, BandOptions, ExpansionOutcome,
    ExpansionSetup, GrowthParams, ImplantShape, ImplantSpec, Insertion, InsertionParams, Protocol,
    RegionOptions, RegionRule, TissueLayers, LEAKAGE_MEAN,
};

type Result<T> = std::result::Result<T, Box<dyn std::error::Error>>;

fn region() -> Result<tissue_mesh::TriMesh> {
    let patient = tissue_mesh::grid(65, 20.0)?;
    let selection = select_region_with(
        &patient,
        Vec3::ZERO,
        default_radius(3.5)?,
        &RegionOptions {
            rule: RegionRule::TouchesVertex,
            ..RegionOptions::default()
        },
    )?;
    Ok(selection.mesh().clone())
}

fn table2(region: &tissue_mesh::TriMesh) -> Result<Duration> {
    let start = Instant::now();
    let params = InsertionParams::default();
    let layers = TissueLayers::new(region, &params.layers)?;
    let spec = ImplantSpec::new(ImplantShape::Round { diameter: 7.0 }, 100.0);
    let implant = place_implant(&layers, &spec, Vec3::ZERO, Vec3::Z, Vec3::X)?;
    let mut insertion = Insertion::new(region, &implant, &params)?;
    insertion.run(|_| ControlFlow::Continue(()))?;
    Ok(start.elapsed())
}

fn protocol_run(
    region: &tissue_mesh::TriMesh,
    volume: f64,
    weeks: u32,
    samples: usize,
) -> Result<ExpansionOutcome> {
    let setup = ExpansionSetup {
        region: region.clone(),
        centre: Vec3::ZERO,
        normal: Vec3::Z,
        tangent: Vec3::X,
        implant: ImplantSpec::new(ImplantShape::Round { diameter: 7.0 }, volume),
        params: InsertionParams::default(),
    };
    let protocol = Protocol::weekly(volume, weeks, 1.0, LEAKAGE_MEAN, 0.0)?;
    let band = BandOptions {
        samples,
        ..BandOptions::default()
    };
    Ok(expand(
        &setup,
        &protocol,
        &GrowthParams::human(),
        Some(&band),
        &|_| ControlFlow::Continue(()),
    )?)
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() -> Result<()> {
    let numbers: Vec<f64> = std::env::args()
        .skip(1)
        .filter_map(|a| a.parse().ok())
        .collect();
    let repeats = numbers.first().map_or(3, |&n| n.max(1.0) as usize);
    let volume = numbers.get(1).copied().unwrap_or(200.0);
    let weeks = numbers.get(2).map_or(10, |&w| w as u32);
    let samples = numbers.get(3).map_or(32, |&s| s as usize);
    let region = region()?;
    let (mut t2, mut tp) = (Vec::new(), Vec::new());
    let mut last = None;
    for _ in 0..repeats {
        t2.push(table2(&region)?.as_secs_f64());
        let out = protocol_run(&region, volume, weeks, samples)?;
        tp.push(out.wall_time.as_secs_f64());
        last = Some(out);
    }
    let (a, b) = (median(t2), median(tp));
    println!("Table 2 (100 cm³, round 7 cm, 65² plane): median {a:.3} s over {repeats}");
    println!(
        "{weeks}-week protocol, {volume} cm³ nominal, band of {samples}: median {b:.3} s; ratio {:.1} ×",
        b / a
    );
    if let Some(o) = last {
        println!(
            "steps {} nominal + {} reference; base {:.2} cm², recruited {:.2}, dome {:.2}, grown {:.2}, flap {:.2} cm²",
            o.steps, o.reference_steps, o.base_area, o.recruited_area, o.dome_area, o.grown_area, o.flap_area
        );
        println!(
            "geometric gain {:.2} cm², grown gain {:.2} cm², efficiency {:.1} %, retraction {:.1} %",
            o.geometric_gain,
            o.grown_gain,
            100.0 * o.efficiency,
            100.0 * o.retraction
        );
        if let Some(band) = &o.band {
            println!(
                "band: flap {:.1} / {:.1} / {:.1} cm², retraction {:.1} / {:.1} / {:.1} %, efficiency {:.1} / {:.1} / {:.1} %",
                band.flap_area.p5, band.flap_area.p50, band.flap_area.p95,
                100.0 * band.retraction.p5, 100.0 * band.retraction.p50, 100.0 * band.retraction.p95,
                100.0 * band.efficiency.p5, 100.0 * band.efficiency.p50, 100.0 * band.efficiency.p95
            );
        }
        println!("day  injected  volume  area_gain  grown_gain  mean_growth  steps settled");
        for r in &o.records {
            println!(
                "{:>5.1} {:>8.1} {:>7.1} {:>9.2} {:>10.2} {:>10.4} {:>6} {}",
                r.day,
                r.injected,
                r.volume,
                r.area_gain,
                r.grown_gain,
                r.mean_growth,
                r.steps,
                r.settled
            );
        }
    }
    Ok(())
}
