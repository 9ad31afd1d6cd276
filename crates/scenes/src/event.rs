//! What a session reports: [`TrainerEvent`]s of a closed set of [`TrainerEventKind`]s, and the
//! one place a surgery event is put into words ([`TrainerEvent::surgery`]).

use serde::{Deserialize, Serialize};
use tissue_surgery::SurgeryEvent;

/// What happened. Its JSON is the snake_case name (`"cut_advanced"`, `"demo_finished"`, …),
/// which the studio's page and the C ABI's `tissue_event_kind` map one to one.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum TrainerEventKind {
    /// The scalpel opened more of the tissue.
    CutAdvanced,
    /// A piece came off.
    PieceDetached,
    /// A suture was placed.
    SuturePlaced,
    /// A suture was removed.
    SutureRemoved,
    /// The needle crossed no wound.
    SutureMissed,
    /// The probe grasped tissue.
    Grabbed,
    /// The probe let go.
    Released,
    /// A demonstration started ([`crate::Session::play`]).
    DemoStarted,
    /// The demonstration ended: the organ is the trainee's again.
    DemoFinished,
    /// A surgery event of a kind this list does not name yet (`tissue-surgery`'s events are
    /// `#[non_exhaustive]`); its text is the event's debug form.
    Surgery,
}

impl TrainerEventKind {
    /// Every kind, in declaration order.
    pub const ALL: [TrainerEventKind; 10] = [
        TrainerEventKind::CutAdvanced,
        TrainerEventKind::PieceDetached,
        TrainerEventKind::SuturePlaced,
        TrainerEventKind::SutureRemoved,
        TrainerEventKind::SutureMissed,
        TrainerEventKind::Grabbed,
        TrainerEventKind::Released,
        TrainerEventKind::DemoStarted,
        TrainerEventKind::DemoFinished,
        TrainerEventKind::Surgery,
    ];

    /// Its name, as in the JSON: `cut_advanced`, `demo_started`, ….
    pub fn name(self) -> &'static str {
        match self {
            TrainerEventKind::CutAdvanced => "cut_advanced",
            TrainerEventKind::PieceDetached => "piece_detached",
            TrainerEventKind::SuturePlaced => "suture_placed",
            TrainerEventKind::SutureRemoved => "suture_removed",
            TrainerEventKind::SutureMissed => "suture_missed",
            TrainerEventKind::Grabbed => "grabbed",
            TrainerEventKind::Released => "released",
            TrainerEventKind::DemoStarted => "demo_started",
            TrainerEventKind::DemoFinished => "demo_finished",
            TrainerEventKind::Surgery => "surgery",
        }
    }
}

impl std::fmt::Display for TrainerEventKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// Something that happened, for the events list. Its JSON is `{"step", "kind", "text"}`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TrainerEvent {
    /// The step it happened in.
    pub step: u64,
    /// What happened.
    pub kind: TrainerEventKind,
    /// One line for a person.
    pub text: String,
}

impl TrainerEvent {
    /// An event of `kind` at `step`.
    pub fn new(step: u64, kind: TrainerEventKind, text: impl Into<String>) -> TrainerEvent {
        TrainerEvent {
            step,
            kind,
            text: text.into(),
        }
    }

    /// A surgery event at `step`, in words: the one description every host shows (the
    /// session's events, the headless `trainer`'s appendix scenario).
    pub fn surgery(step: u64, e: &SurgeryEvent) -> TrainerEvent {
        let (kind, text) = match e {
            SurgeryEvent::CutAdvanced {
                new_nodes,
                opened_faces,
                changed_tets,
                ..
            } => (
                TrainerEventKind::CutAdvanced,
                format!(
                    "cut advanced: {} wall triangles opened, {} nodes added, {} tets moved",
                    opened_faces.len(),
                    new_nodes.len(),
                    changed_tets.len()
                ),
            ),
            SurgeryEvent::PieceDetached {
                tets,
                nodes,
                rest_volume,
                ..
            } => (
                TrainerEventKind::PieceDetached,
                format!(
                    "piece detached: {} tets, {} nodes, {rest_volume:.2} cm³",
                    tets.len(),
                    nodes.len()
                ),
            ),
            SurgeryEvent::SuturePlaced { suture, nodes, .. } => (
                TrainerEventKind::SuturePlaced,
                format!(
                    "suture {suture} placed between nodes {} and {}",
                    nodes[0], nodes[1]
                ),
            ),
            SurgeryEvent::SutureRemoved { suture, nodes } => (
                TrainerEventKind::SutureRemoved,
                format!(
                    "suture {suture} removed (it linked nodes {} and {})",
                    nodes[0], nodes[1]
                ),
            ),
            other => (TrainerEventKind::Surgery, format!("{other:?}")),
        };
        TrainerEvent { step, kind, text }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_kind_is_written_as_its_snake_case_name() {
        for kind in TrainerEventKind::ALL {
            let json = serde_json::to_string(&kind).unwrap_or_default();
            assert_eq!(json, format!("\"{}\"", kind.name()));
            let back: Option<TrainerEventKind> = serde_json::from_str(&json).ok();
            assert_eq!(back, Some(kind));
        }
    }

    #[test]
    fn an_event_is_step_kind_and_text() {
        let e = TrainerEvent::new(7, TrainerEventKind::DemoStarted, "demonstration");
        assert_eq!(
            serde_json::to_string(&e).unwrap_or_default(),
            r#"{"step":7,"kind":"demo_started","text":"demonstration"}"#
        );
    }
}
