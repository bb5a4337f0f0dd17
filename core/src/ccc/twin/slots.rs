//! The twin's working slots and their roles.

use super::super::params::CccParams;
use super::slot::Slot;
use super::{Twin, Work};
use crate::scalar::Real;
use crate::workspace::WarmStart;

/// The twin's three slots (20 KB each in f64, 10 KB in f32) and their roles: the
/// current slot, the backup (the pre-step slot once a step changed the current one, see
/// [`Twin::scratch`]) and the candidate slot. The roles move, never the slots: taking
/// a candidate, restoring the backup or handing the backup's role to the slot that
/// holds a pick permutes `role` (a 30 KB swap cost 7.5k instructions per event).
///
/// The mode choice's reference model (I0, see [`Twin::choose`]) has no slot of its
/// own: it is built, at each event, in the one slot the choice does not need
/// ([`Slots::reference`]), and nothing of it is read after the event. Its models
/// are dyads only, so it gives the same bits in any slot (a rebuild and a
/// reposition of a dyad agree).
#[derive(Clone, Debug)]
pub(super) struct Slots<T: Real> {
    pub(super) s: [Slot<T>; 3],
    /// Indices into `s` of the current slot, the backup and the candidate slot: a
    /// permutation of 0, 1, 2 (only ever swapped).
    pub(super) role: [u8; 3],
    /// The role whose slot holds the reference model during a mode choice
    /// ([`Slots::reference_role`]).
    pub(super) reference: u8,
}

impl<T: Real> Slots<T> {
    pub(super) fn at(&self, k: usize) -> &Slot<T> {
        let [a, b, c] = &self.s;
        match self.role.get(k) {
            Some(0) => a,
            Some(1) => b,
            _ => c,
        }
    }

    /// The current slot: the mode and coordinates the twin integrates.
    pub(super) fn cur(&self) -> &Slot<T> {
        self.at(0)
    }

    pub(super) fn cur_mut(&mut self) -> &mut Slot<T> {
        self.at_mut(0)
    }

    fn at_mut(&mut self, k: usize) -> &mut Slot<T> {
        let [a, b, c] = &mut self.s;
        match self.role.get(k) {
            Some(0) => a,
            Some(1) => b,
            _ => c,
        }
    }

    /// The role free for the reference model during a mode choice, `switched`: the step
    /// changed the current slot before. Before that the current slot is the pre-step
    /// one and the backup the scratch: the candidate slot is free. After, the backup
    /// holds the pre-step slot and the candidate slot is the scratch: the current slot
    /// (the mode the event ends) is free, as the choice replaces it (and a failed
    /// choice fails the attempt, which restores the backup).
    pub(super) fn reference_role(switched: bool) -> u8 {
        if switched {
            0
        } else {
            2
        }
    }

    /// The reference model of the mode choice under way (its slot
    /// [`Slots::reference_role`], set by [`Twin::choose`]).
    pub(super) fn reference(&self) -> &Slot<T> {
        self.at(usize::from(self.reference))
    }

    pub(super) fn reference_mut(&mut self) -> &mut Slot<T> {
        self.at_mut(usize::from(self.reference))
    }

    /// `(reference, scratch)` of the mode choice under way: the scratch is the backup
    /// before the step changed the current slot, the candidate slot after
    /// ([`Twin::scratch`]); always another slot than the reference's.
    pub(super) fn reference_and_scratch(&mut self) -> (&mut Slot<T>, &mut Slot<T>) {
        let scratch = if self.reference == 0 { 2 } else { 1 };
        let (r, s) = (self.role_of(self.reference), self.role_of(scratch));
        let [a, b, c] = &mut self.s;
        // Two distinct roles of a permutation: two distinct slots.
        match (r, s) {
            (0, 1) => (a, b),
            (0, _) => (a, c),
            (1, 0) => (b, a),
            (1, _) => (b, c),
            (_, 0) => (c, a),
            _ => (c, b),
        }
    }

    /// Makes the slot of the reference model the scratch's ([`Twin::scratch`]), so that
    /// taking the scratch takes the reference model.
    pub(super) fn reference_to_scratch(&mut self) {
        if self.reference == 0 {
            self.role.swap(0, 2);
        } else {
            self.role.swap(2, 1);
        }
    }

    fn role_of(&self, k: u8) -> u8 {
        self.role.get(usize::from(k)).copied().unwrap_or(2)
    }

    /// `(backup, candidate slot)`.
    pub(super) fn spares(&mut self) -> (&mut Slot<T>, &mut Slot<T>) {
        let [a, b, c] = &mut self.s;
        // The roles are a permutation: the two spares are distinct slots.
        match (self.role.get(1), self.role.get(2)) {
            (Some(0), Some(1)) => (a, b),
            (Some(0), _) => (a, c),
            (Some(1), Some(0)) => (b, a),
            (Some(1), _) => (b, c),
            (_, Some(0)) => (c, a),
            _ => (c, b),
        }
    }
}

impl<T: Real> Twin<T> {
    /// The slot new modes and coordinate choices are built in (with the parameters):
    /// the backup until the step first changes the current slot (the backup holds
    /// nothing the step needs until then), the candidate slot after. So
    /// [`Twin::take_candidate`] keeps the pre-step slot as the backup with one swap, no
    /// copy (a slot is 30 KB in f64).
    pub(super) fn scratch(&mut self, switched: bool) -> (&mut Slot<T>, &CccParams<T>) {
        let (backup, cand) = self.slots.spares();
        (if switched { cand } else { backup }, &self.params)
    }

    /// Makes the scratch slot ([`Twin::scratch`]), which holds the new mode or
    /// coordinates, the current one; the first time in a step the pre-step slot goes
    /// to the backup.
    pub(super) fn take_candidate(&mut self, w: &mut Work<T>) {
        let r = &mut self.slots.role;
        if w.switched {
            r.swap(0, 2);
        } else {
            r.swap(0, 1);
            w.switched = true;
        }
    }

    /// Back to the state before the step: the pre-step slot (kept by
    /// [`Twin::take_candidate`] if the step changed it) with its groups' warm starts
    /// `saved`, evaluated there under the last step's inputs, DP5 seeded with that
    /// evaluation (a retry under the same inputs takes it as its first stage).
    pub(super) fn restore(&mut self, switched: bool, saved: &WarmStart<T>) {
        if switched {
            self.slots.role.swap(0, 1);
        }
        let slot = self.slots.cur_mut();
        slot.ws.restore_warm_start(slot.model.groups(), saved);
        self.dp5.invalidate();
        self.last_guards = None;
        let w = self.work_from_state();
        // It evaluated at this very state before: this cannot fail, and if it did the
        // workspace would merely hold the failed evaluation.
        let inputs = self.inputs.inputs();
        let _ = self.restart_at(&w, &inputs);
    }
}
