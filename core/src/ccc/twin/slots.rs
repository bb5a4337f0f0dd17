//! The twin's working slots and their roles.

use super::super::params::CccParams;
use super::slot::Slot;
use super::{Twin, Work};
use crate::scalar::Real;
use crate::workspace::WarmStart;

/// The twin's three working slots (30 KB each in f64) and their roles: the current
/// slot, the backup (the pre-step slot once a step changed the current one, see
/// [`Twin::scratch`]) and the candidate slot. The roles move, never the slots: taking
/// a candidate, restoring the backup or handing the backup's role to the slot that
/// holds a pick permutes `role` (a 30 KB swap cost 7.5k instructions per event).
#[derive(Clone, Debug)]
pub(super) struct Slots<T: Real> {
    pub(super) s: [Slot<T>; 3],
    /// Indices into `s` of the current slot, the backup and the candidate slot: a
    /// permutation of 0, 1, 2 (only ever swapped).
    pub(super) role: [u8; 3],
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
        let [a, b, c] = &mut self.s;
        match self.role.first() {
            Some(0) => a,
            Some(1) => b,
            _ => c,
        }
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

    /// The slot a candidate is built in: the scratch ([`Twin::scratch`]), or with
    /// `second` before the step changed the current slot (`switched` false), the
    /// candidate slot, the other one free then.
    pub(super) fn build_slot(
        &mut self,
        switched: bool,
        second: bool,
    ) -> (&mut Slot<T>, &CccParams<T>) {
        if second && !switched {
            (self.slots.spares().1, &self.params)
        } else {
            self.scratch(switched)
        }
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
    /// `saved`.
    pub(super) fn restore(&mut self, switched: bool, saved: &WarmStart<T>) {
        if switched {
            self.slots.role.swap(0, 1);
        }
        self.slots.cur_mut().ws.restore_warm_start(saved);
        self.dp5.invalidate();
        self.last_guards = None;
        let w = self.work_from_state();
        // It evaluated at this very state before: this cannot fail, and if it did the
        // workspace would merely hold the failed evaluation.
        let inputs = self.inputs;
        let _ = self.restart_at(&w, &inputs);
    }
}
