//! The integration tests of `tissue-scenes` in one binary, a module per area (each module's own
//! doc says what it covers).

mod material;
mod moving_body;
mod probe;
mod selfcol;
mod session;
mod shipped;

use tissue_scenes::TrainerEventKind;

/// The largest piece a run detached (cm³), read from its `PieceDetached` events' texts
/// ("… tets, V cm³"); 0 when none.
fn largest_detached(kinds: &[(TrainerEventKind, String)]) -> f64 {
    kinds
        .iter()
        .filter(|k| k.0 == TrainerEventKind::PieceDetached)
        .filter_map(|k| {
            k.1.rsplit(", ")
                .next()?
                .trim_end_matches(" cm³")
                .parse::<f64>()
                .ok()
        })
        .fold(0.0f64, f64::max)
}
