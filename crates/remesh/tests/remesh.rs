//! The public API of tissue-remesh on seeded and real surfaces.

mod common;

use common::{assert_same_topology, fit};
use tissue_remesh::{remesh, scenes, RemeshOptions};

#[test]
fn explore() {
    let patch = scenes::noisy_plane(10.0, 0.05, 0.02, 7).unwrap();
    let t0 = std::time::Instant::now();
    let out = remesh(&patch, &RemeshOptions::new(0.3)).unwrap();
    println!("time {:?}", t0.elapsed());
    println!("{:#?}", out.stats);
    assert_same_topology(&patch, &out.mesh);
    if std::env::var("FIT").is_err() { return; }
    let f = fit(&patch, &out.mesh);
    println!(
        "boundary {} interior {} dot {} agree {}",
        f.boundary_max, f.interior_max, f.min_normal_dot, f.agreeing
    );
}
