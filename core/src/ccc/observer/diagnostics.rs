//! What the observer's innovations tell: the named diagnostics and their thresholds.

use crate::scalar::Real;

/// A named diagnostic of an observer step.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Diagnostic {
    /// An encoder's reading left the twin's prediction by more than the gate
    /// ([`ObserverSettings::jump_gate`](super::ObserverSettings::jump_gate) standard
    /// deviations of the innovation and at least `jump_counts`): the reading is not
    /// used. The encoder: `"crank"` or `"shaft"`.
    EncoderJump(&'static str),
    /// The shaft moved where the twin's mode holds it, or away from the engaged
    /// lever's motion where the mode turns it: a clutch that slips (or catches where
    /// the twin's does not).
    ClutchSlip,
    /// The shaft stood where the twin's mode turns it: a clutch that failed to catch.
    FailedCatch,
    /// The unknown torque's estimate, averaged while the shaft turns, departs from its
    /// average while the shaft is held: the load differs from its set point.
    LoadBias,
    /// The crank's residual (measured - twin, after the update) has stayed past
    /// [`ObserverSettings::part_counts`](super::ObserverSettings::part_counts) for
    /// [`ObserverSettings::part_steps`](super::ObserverSettings::part_steps) steps in
    /// a row: the corrections do not bring the twin back to the machine (its mode
    /// sequence or its model has parted from the machine's), and its outputs are not
    /// the machine's. Raised at every step while it lasts.
    Parted,
}

impl Diagnostic {
    /// A short name for logs and CSV cells.
    pub fn name(self) -> &'static str {
        match self {
            Diagnostic::EncoderJump("shaft") => "shaft-encoder-jump",
            Diagnostic::EncoderJump(_) => "crank-encoder-jump",
            Diagnostic::ClutchSlip => "clutch-slip",
            Diagnostic::FailedCatch => "failed-catch",
            Diagnostic::LoadBias => "load-bias",
            Diagnostic::Parted => "twin-parted",
        }
    }

    /// Its bit in [`Diagnostics`].
    fn bit(self) -> u8 {
        match self {
            Diagnostic::EncoderJump("shaft") => 1,
            Diagnostic::EncoderJump(_) => 1 << 1,
            Diagnostic::ClutchSlip => 1 << 2,
            Diagnostic::FailedCatch => 1 << 3,
            Diagnostic::LoadBias => 1 << 4,
            Diagnostic::Parted => 1 << 5,
        }
    }

    /// Every diagnostic, in a fixed order.
    pub const ALL: [Diagnostic; 6] = [
        Diagnostic::EncoderJump("crank"),
        Diagnostic::EncoderJump("shaft"),
        Diagnostic::ClutchSlip,
        Diagnostic::FailedCatch,
        Diagnostic::LoadBias,
        Diagnostic::Parted,
    ];
}

/// The set of diagnostics raised by one observer step.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Diagnostics {
    bits: u8,
}

impl Diagnostics {
    /// Raises `d`.
    pub fn insert(&mut self, d: Diagnostic) {
        self.bits |= d.bit();
    }

    /// Whether `d` is raised.
    pub fn contains(self, d: Diagnostic) -> bool {
        self.bits & d.bit() != 0
    }

    /// Whether none is.
    pub fn is_empty(self) -> bool {
        self.bits == 0
    }

    /// The raised ones, in [`Diagnostic::ALL`]'s order.
    pub fn iter(self) -> impl Iterator<Item = Diagnostic> {
        Diagnostic::ALL
            .into_iter()
            .filter(move |d| self.contains(*d))
    }
}

/// The load-bias detector: the unknown torque's estimate on the crank (N·m) averaged
/// exponentially while the shaft turns and while it is held; a load off its set point
/// acts only while the shaft turns, the model's other errors (friction, inertias, the
/// motor's torque) in both. On an identified twin (whose other errors are small) the
/// difference is the load's; on a nominal one it is the model's.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BiasWatch<T> {
    /// The averages `[turning, held]`, N·m.
    pub mean: [T; 2],
    /// Seconds averaged into each, capped at the time constant.
    pub weight: [T; 2],
}

impl<T: Real> Default for BiasWatch<T> {
    fn default() -> Self {
        Self::new()
    }
}

impl<T: Real> BiasWatch<T> {
    /// Nothing averaged yet.
    pub fn new() -> Self {
        BiasWatch {
            mean: [T::zero(); 2],
            weight: [T::zero(); 2],
        }
    }

    /// Adds the value `a` (N·m) of a step of `h` (s), `turning` or held, to its
    /// average of time constant `tau` (s).
    pub fn add(&mut self, a: T, h: T, turning: bool, tau: T) {
        let k = usize::from(!turning);
        if let (Some(m), Some(w)) = (self.mean.get_mut(k), self.weight.get_mut(k)) {
            *w = (*w + h).min(tau);
            let f = h / *w;
            *m += f * (a - *m);
        }
    }

    /// The turning average less the held one, N·m, once each has averaged a whole
    /// time constant `tau` (s).
    pub fn bias(&self, tau: T) -> Option<T> {
        let [t, hd] = self.weight;
        (t >= tau && hd >= tau).then(|| self.mean[0] - self.mean[1])
    }
}
