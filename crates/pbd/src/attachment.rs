//! Kinematic attachments ([`SoftBody::attach`](crate::SoftBody::attach)) under stable ids.
//!
//! An attachment lives in a slot; freeing it ([`SoftBody::unpin`](crate::SoftBody::unpin))
//! empties the slot and bumps its generation, and a later attachment may reuse the slot under
//! the new generation. An [`AttachmentId`] names a slot *and* a generation, so an id stays
//! valid until its own attachment is removed, whatever else is attached or freed, and a stale
//! id is refused ([`PbdError::NoSuchAttachment`]) instead of moving another node.

use glam::Vec3A;

use crate::PbdError;

/// The id of an attachment, returned by [`SoftBody::attach`](crate::SoftBody::attach). It stays
/// valid until that attachment's node is freed; it is never reused for another attachment.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct AttachmentId {
    slot: u32,
    generation: u32,
}

impl std::fmt::Display for AttachmentId {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}v{}", self.slot, self.generation)
    }
}

#[derive(Debug, Clone)]
struct Slot {
    generation: u32,
    /// The node and its target, or `None` for a free slot.
    held: Option<(u32, Vec3A)>,
}

/// The body's attachments: slots, the free ones, and how many are live.
#[derive(Debug, Clone, Default)]
pub(crate) struct Attachments {
    slots: Vec<Slot>,
    free: Vec<u32>,
    live: usize,
}

impl Attachments {
    /// No live attachment.
    pub(crate) fn is_empty(&self) -> bool {
        self.live == 0
    }

    /// The live attachments: (node, target).
    pub(crate) fn iter(&self) -> impl Iterator<Item = (u32, Vec3A)> + '_ {
        self.slots.iter().filter_map(|s| s.held)
    }

    /// A new attachment of `node` to `target`.
    pub(crate) fn insert(&mut self, node: u32, target: Vec3A) -> AttachmentId {
        self.live += 1;
        if let Some(slot) = self.free.pop() {
            let s = &mut self.slots[slot as usize];
            s.held = Some((node, target));
            return AttachmentId {
                slot,
                generation: s.generation,
            };
        }
        let slot = u32::try_from(self.slots.len()).unwrap_or(u32::MAX);
        self.slots.push(Slot {
            generation: 0,
            held: Some((node, target)),
        });
        AttachmentId {
            slot,
            generation: 0,
        }
    }

    /// Removes every attachment of `node`; their ids become stale.
    pub(crate) fn remove_node(&mut self, node: u32) {
        for (i, s) in self.slots.iter_mut().enumerate() {
            if matches!(s.held, Some((n, _)) if n == node) {
                s.held = None;
                s.generation = s.generation.wrapping_add(1);
                self.free.push(i as u32);
                self.live -= 1;
            }
        }
    }

    /// The live attachment `id`: its node and target.
    pub(crate) fn get_mut(&mut self, id: AttachmentId) -> Result<&mut (u32, Vec3A), PbdError> {
        let live = self.live;
        self.slots
            .get_mut(id.slot as usize)
            .filter(|s| s.generation == id.generation)
            .and_then(|s| s.held.as_mut())
            .ok_or(PbdError::NoSuchAttachment { id, count: live })
    }
}
