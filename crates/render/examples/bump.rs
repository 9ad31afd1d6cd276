//! Writes the before/after figure of a synthetic bump: `cargo run --example bump -- out.png`
//! (add `front` for the head-on view).

use glam::Vec3;
use tissue_render::{before_after, BeforeAfterOptions, View};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let path = args.next().unwrap_or_else(|| "bump.png".to_owned());
    let view = match args.next().as_deref() {
        Some("front") => View::Front,
        _ => View::Oblique,
    };
    let before = tissue_mesh::grid(101, 10.0)?;
    let moved: Vec<Vec3> = before
        .positions()
        .iter()
        .map(|p| {
            let r2 = (*p - Vec3::new(0.5, -0.5, 0.0)).length_squared();
            *p + Vec3::Z * 1.5 * (-r2 / 3.0).exp()
        })
        .collect();
    let after = before.with_positions(moved)?;
    let displacement: Vec<f32> = before
        .positions()
        .iter()
        .zip(after.positions())
        .map(|(a, b)| a.distance(*b))
        .collect();
    let options = BeforeAfterOptions {
        view,
        ..BeforeAfterOptions::default()
    };
    before_after(&before, &after, &displacement, &options)?.write_png(&path)?;
    Ok(())
}
