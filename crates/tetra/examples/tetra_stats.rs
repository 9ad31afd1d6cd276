//! Tetrahedralises a closed surface file and prints the quality report and the median time of
//! five runs: `cargo run --release -p tissue-tetra --example tetra_stats -- FILE [SPACING_FACTOR]`.
#![allow(missing_docs, clippy::print_stdout, clippy::print_stderr)]

use std::time::Instant;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let Some(path) = args.get(1) else {
        eprintln!("usage: tetra_stats FILE [SPACING_FACTOR]");
        std::process::exit(2);
    };
    let surface = match tissue_meshio::read_surface(path) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("{e}");
            std::process::exit(2);
        }
    };
    let mut options = tissue_tetra::TetraOptions::default();
    if let Some(f) = args.get(2).and_then(|f| f.parse().ok()) {
        options.spacing_factor = f;
    }
    let mut times = Vec::new();
    let mut result = None;
    for _ in 0..5 {
        let start = Instant::now();
        result = Some(tissue_tetra::tetrahedralize(&surface, &options));
        times.push(start.elapsed().as_secs_f64());
    }
    times.sort_by(f64::total_cmp);
    match result {
        Some(Ok(r)) => println!(
            "{}\nspacing {} cm, slivers removed {}\ntime: median {:.3} s of 5 (min {:.3}, max {:.3})",
            r.report, r.spacing, r.slivers_removed, times[2], times[0], times[4]
        ),
        Some(Err(e)) => {
            eprintln!("{e}");
            std::process::exit(1);
        }
        None => {}
    }
}
