//! Modes of the converter (SPEC 3, the thesis's evolving structure, its figure 14) and
//! the choices of independent coordinates that drive each of them.

use core::fmt;

/// The state of one lever's one-way clutch.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Clutch {
    /// Overrunning: the lever turns freely against the shaft.
    Free,
    /// Locked against a held shaft: the lever stands still (its pin is a fixed point).
    Locked,
    /// Engaged with a turning shaft: the lever turns with it.
    Engaged,
}

/// A mode: which clutches hold and whether the shaft turns.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Mode {
    /// No load and no clutch (thesis 7.1): both levers swing freely, 2 DOF.
    Free,
    /// Shaft held, both levers overrunning, 2 DOF.
    I0,
    /// Shaft held, lever 6 locked (G fixed), 1 DOF.
    I6,
    /// Shaft held, lever 8 locked (I fixed), 1 DOF.
    I8,
    /// Shaft held, both levers locked: 0 DOF, the machine stands still (a state).
    Jam,
    /// Shaft turning with lever 6, lever 8 overrunning, 2 DOF.
    A6,
    /// Shaft turning with lever 8, lever 6 overrunning, 2 DOF.
    A8,
    /// Shaft turning with both levers, 1 DOF.
    A68,
    /// Shaft turning with no lever (only with shaft inertia J_s > 0, SPEC 5): both
    /// levers overrunning, the linkage moves as in I0 (2 DOF) and the shaft coasts on
    /// its own, `J_s·ω̇_s = −T_r` (the brake opposing its turning) plus the overrunning
    /// levers' clutch drag. Its speed and angle are the twin's, not the model's: the
    /// mode's model is I0's.
    Coast,
}

impl Mode {
    /// All modes, in a fixed order (for reports and tests).
    pub const ALL: [Mode; 9] = [
        Mode::Free,
        Mode::I0,
        Mode::I6,
        Mode::I8,
        Mode::Jam,
        Mode::A6,
        Mode::A8,
        Mode::A68,
        Mode::Coast,
    ];

    /// The clutches of levers 6 and 8.
    pub fn clutches(self) -> [Clutch; 2] {
        use Clutch::*;
        match self {
            Mode::Free | Mode::I0 | Mode::Coast => [Free, Free],
            Mode::I6 => [Locked, Free],
            Mode::I8 => [Free, Locked],
            Mode::Jam => [Locked, Locked],
            Mode::A6 => [Engaged, Free],
            Mode::A8 => [Free, Engaged],
            Mode::A68 => [Engaged, Engaged],
        }
    }

    /// The mode with these clutches (`turning`: the shaft turns); `None` for a
    /// combination that is no mode (a lever locked against a turning shaft, one engaged
    /// with a held one). A turning shaft with no lever is [`Mode::Coast`], a mode only
    /// with shaft inertia: the mode choice offers it only then.
    pub fn from_clutches(c: [Clutch; 2], turning: bool) -> Option<Mode> {
        use Clutch::*;
        Some(match (c, turning) {
            ([Free, Free], false) => Mode::I0,
            ([Locked, Free], false) => Mode::I6,
            ([Free, Locked], false) => Mode::I8,
            ([Locked, Locked], false) => Mode::Jam,
            ([Engaged, Free], true) => Mode::A6,
            ([Free, Engaged], true) => Mode::A8,
            ([Engaged, Engaged], true) => Mode::A68,
            ([Free, Free], true) => Mode::Coast,
            _ => return None,
        })
    }

    /// Whether the shaft turns.
    pub fn shaft_turning(self) -> bool {
        matches!(self, Mode::A6 | Mode::A8 | Mode::A68 | Mode::Coast)
    }

    /// Degrees of freedom.
    pub fn dof(self) -> usize {
        match self {
            Mode::Free | Mode::I0 | Mode::A6 | Mode::A8 | Mode::Coast => 2,
            Mode::I6 | Mode::I8 | Mode::A68 => 1,
            Mode::Jam => 0,
        }
    }

    /// The coordinate choices that can drive this mode, preferred first.
    pub fn coordinate_choices(self) -> &'static [Coordinates] {
        use Coordinates::*;
        match self {
            Mode::Free | Mode::I0 | Mode::A6 | Mode::A8 | Mode::Coast => {
                &[CrankSwing, CrankCoupler, SwingRocker]
            }
            Mode::I6 | Mode::I8 => &[Swing, Crank, Rod],
            Mode::A68 => &[Lever, Crank],
            Mode::Jam => &[Rest],
        }
    }

    /// A small stable code (0..9, `Mode::ALL`'s order) for CSV columns.
    pub fn code(self) -> u8 {
        Mode::ALL.iter().position(|m| *m == self).unwrap_or(0) as u8
    }

    /// The name used in logs and CSV files.
    pub fn name(self) -> &'static str {
        match self {
            Mode::Free => "free",
            Mode::I0 => "I0",
            Mode::I6 => "I6",
            Mode::I8 => "I8",
            Mode::Jam => "jam",
            Mode::A6 => "A6",
            Mode::A8 => "A8",
            Mode::A68 => "A68",
            Mode::Coast => "coast",
        }
    }
}

impl fmt::Display for Mode {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// A choice of independent coordinates and the motion-transmission sequence it gives
/// (SPEC 3). "Lever k" below is the locked lever of an I mode (6 in I6, 8 in I8), its
/// rod and pin are rod k-1 and G or I.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Coordinates {
    /// 2 DOF, `(θ1, θ4)`: R(1) + R(4) + RRR(2,3) + the diode dyads (thesis eq. 3.1).
    CrankSwing,
    /// 2 DOF, `(θ1, θ2)`: R(1) + R(2) on B + RRR(3,4) + the diode dyads.
    CrankCoupler,
    /// 2 DOF, `(θ4, θ3)`: R(4) + R(3) on E + RRR(1,2) + the diode dyads.
    SwingRocker,
    /// 1 DOF, `θ1`. I6, I8: R(1) + triad RR-RR-RR(2,3,4,rod) + the free branch's dyad
    /// (thesis eq. 3.2-3.3). A68: R(1) + the six-link group ASSUR(2,3,4,5,6,7) (the
    /// joined levers are body 6), which carries the crank through A68's crank reversals
    /// where the lever coordinate cannot.
    Crank,
    /// 1 DOF (I6, I8), `θ4`: R(4) + RRR(3,rod) + RRR(1,2) + the free branch's dyad.
    Swing,
    /// 1 DOF (I6, I8), the locked branch's rod angle: R(rod) on its fixed pin +
    /// RRR(3,4) + RRR(1,2) + the free branch's dyad.
    Rod,
    /// 1 DOF (A68), `θ6`: R(6, with 8 and the shaft) + RRR(5,7) + RRR(3,4) + RRR(1,2).
    Lever,
    /// 0 DOF (jam): RRR(5,7) on the fixed pins + RRR(3,4) + RRR(1,2).
    Rest,
}

impl Coordinates {
    /// The name used in logs.
    pub fn name(self) -> &'static str {
        match self {
            Coordinates::CrankSwing => "crank+swing",
            Coordinates::CrankCoupler => "crank+coupler",
            Coordinates::SwingRocker => "swing+rocker",
            Coordinates::Crank => "crank",
            Coordinates::Swing => "swing",
            Coordinates::Rod => "rod",
            Coordinates::Lever => "lever",
            Coordinates::Rest => "none",
        }
    }
}

impl fmt::Display for Coordinates {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}
