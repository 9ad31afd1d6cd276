//! A bench binary for issue 35's studio case: the shipped bunny in a session (the studio's
//! physics: realtime preset, parallel on rayon's pool), settled 60 steps, cut across its top
//! with the scalpel, settled again, then self-collision switched off or on and 200 steps timed.
//! Off and on alternate twice in one run (the machine is shared: compare within a run). Prints
//! each case's step median and 90th percentile (ms) and the last step's self-contacts.
//!
//! `cargo run --release -p tissue-scenes --example selfcol_bunny_cut`
#![allow(missing_docs, clippy::print_stderr, clippy::unwrap_used)]

use glam::Vec3;
use tissue_pbd::SelfCollision;
use tissue_scenes::{Organ, Session, SessionOptions, ShippedOrgan};

fn main() {
    let organ = Organ::shipped(ShippedOrgan::Bunny).unwrap();
    for on in [false, true, false, true] {
        // Settled and cut without self-collision, whichever case is timed (a comparison of the
        // two: the state before the switch is the same, as when docs/trainer.md's figures were
        // measured, before self-collision was on by default).
        let options = SessionOptions {
            self_collision: None,
            ..SessionOptions::default()
        };
        let mut s = Session::new(&organ, options).unwrap();
        for _ in 0..60 {
            s.step().unwrap();
        }
        // Across the top, from the side seen from above.
        let top = s.positions().iter().map(|p| p.y).fold(f32::MIN, f32::max);
        let path: Vec<Vec3> = (0..=10)
            .map(|i| Vec3::new(-3.0 + 0.6 * i as f32, top + 0.5, 0.0))
            .collect();
        let segments = s.cut(&path, Vec3::NEG_Y).unwrap();
        for _ in 0..segments + 30 {
            s.step().unwrap();
        }
        s.set_self_collision(on.then(SelfCollision::default))
            .unwrap();
        for _ in 0..30 {
            s.step().unwrap();
        }
        let mut ms = Vec::new();
        for _ in 0..200 {
            let clock = std::time::Instant::now();
            s.step().unwrap();
            ms.push(clock.elapsed().as_secs_f64() * 1e3);
        }
        ms.sort_by(f64::total_cmp);
        eprintln!(
            "self-collision {}: step median {:.2} ms, p90 {:.2} ms, self-contacts (found, active) {:?}, dropped {}",
            if on { "on " } else { "off" },
            ms[100],
            ms[180],
            s.self_contacts(),
            s.body().self_contacts_dropped()
        );
    }
}
