#![allow(missing_docs, clippy::print_stderr, clippy::unwrap_used)]
use glam::Vec3;
use tissue_pbd::SelfCollision;
use tissue_scenes::{Organ, Session, SessionOptions, ShippedOrgan};

fn main() {
    let organ = Organ::shipped(ShippedOrgan::Bunny).unwrap();
    for on in [false, true, false, true] {
        let mut s = Session::new(&organ, SessionOptions::default()).unwrap();
        for _ in 0..60 {
            s.step().unwrap();
        }
        let top = s.positions().iter().map(|p| p.y).fold(f32::MIN, f32::max);
        let path: Vec<Vec3> = (0..=10).map(|i| Vec3::new(-3.0 + 0.6 * i as f32, top + 0.5, 0.0)).collect();
        let n = s.cut(&path, Vec3::NEG_Y).unwrap();
        for _ in 0..n + 30 {
            s.step().unwrap();
        }
        s.set_self_collision(on.then(SelfCollision::default)).unwrap();
        for _ in 0..30 {
            s.step().unwrap();
        }
        let mut t = Vec::new();
        for _ in 0..200 {
            let c = std::time::Instant::now();
            s.step().unwrap();
            t.push(c.elapsed().as_secs_f64() * 1e3);
        }
        t.sort_by(f64::total_cmp);
        eprintln!("self-collision {on}: median {:.2} ms, p90 {:.2}, contacts {:?} dropped {}", t[100], t[180], s.self_contacts(), s.body().self_contacts_dropped());
    }
}
