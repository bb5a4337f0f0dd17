//! The built-in scenarios by command-line name: the thesis's validation mechanisms of
//! [`structomat::mechanisms`], and the Constantinesco converter's scenarios S1 and S2
//! (SPEC 3, run on a [`structomat::ccc::Twin`] by [`crate::ccc`]).

use crate::ccc::CccScenario;
use structomat::mechanisms::{five_bar, slider_crank, Scenario};
use structomat::{ModelError, Real};

/// A built-in scenario.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ScenarioId {
    /// `slider-crank`: [`slider_crank()`](fn@structomat::mechanisms::slider_crank).
    SliderCrank,
    /// `five-bar`: [`five_bar()`](fn@structomat::mechanisms::five_bar).
    FiveBar,
    /// `ccc-s1`: the converter in free mode (no clutch), 12 N·m on the crank, from rest
    /// (SPEC 3's S1, thesis 7.1); it ends at a singularity of the mechanism.
    CccS1,
    /// `ccc-s2`: the converter with its diode, 12 N·m on the crank, T_r = 800 N·m on the
    /// shaft from t = 0, shaft turning clockwise (SPEC 3's S2, thesis 7.2).
    CccS2,
}

impl ScenarioId {
    /// Every built-in scenario, in listing order.
    pub const ALL: [ScenarioId; 4] = [
        ScenarioId::SliderCrank,
        ScenarioId::FiveBar,
        ScenarioId::CccS1,
        ScenarioId::CccS2,
    ];

    /// The mechanism scenarios (a core [`Scenario`] each), in listing order.
    pub const MECHANISMS: [ScenarioId; 2] = [ScenarioId::SliderCrank, ScenarioId::FiveBar];

    /// The converter scenarios (a [`CccScenario`] each).
    pub const CONVERTER: [ScenarioId; 2] = [ScenarioId::CccS1, ScenarioId::CccS2];

    /// The command-line name.
    pub fn name(self) -> &'static str {
        match self {
            ScenarioId::SliderCrank => "slider-crank",
            ScenarioId::FiveBar => "five-bar",
            ScenarioId::CccS1 => "ccc-s1",
            ScenarioId::CccS2 => "ccc-s2",
        }
    }

    /// A one-line description (without the integration settings).
    pub fn description(self) -> &'static str {
        match self {
            ScenarioId::SliderCrank => {
                "slider-crank, asynchronous motor (10 N·m at 10 rpm, 3 N·m at 45 rpm, synchronous 70 rpm), from rest"
            }
            ScenarioId::FiveBar => {
                "five-bar, 2 DOF, 10 N·m on crank 1, no motor on link 2, gravity, from rest"
            }
            ScenarioId::CccS1 => {
                "Constantinesco converter, free mode (no clutch), 12 N·m on the crank, from rest; ends at a singularity of the mechanism"
            }
            ScenarioId::CccS2 => {
                "Constantinesco converter, 12 N·m on the crank, T_r = 800 N·m on the shaft from t = 0, shaft CW, from rest"
            }
        }
    }

    /// Whether this is a converter scenario (run by [`crate::ccc`]).
    pub fn is_converter(self) -> bool {
        matches!(self, ScenarioId::CccS1 | ScenarioId::CccS2)
    }

    /// The scenario of a command-line name.
    pub fn from_name(name: &str) -> Option<ScenarioId> {
        ScenarioId::ALL.into_iter().find(|s| s.name() == name)
    }

    /// The comma-separated list of names, for messages.
    pub fn names() -> String {
        ScenarioId::ALL.map(ScenarioId::name).join(", ")
    }

    /// Builds a mechanism scenario (model, initial state, `h`, `t_end`) in scalar `T`;
    /// `None` for a converter scenario (see [`ScenarioId::converter`]).
    pub fn build<T: Real>(self) -> Option<Result<Scenario<T>, ModelError>> {
        match self {
            ScenarioId::SliderCrank => Some(slider_crank()),
            ScenarioId::FiveBar => Some(five_bar()),
            ScenarioId::CccS1 | ScenarioId::CccS2 => None,
        }
    }

    /// The scenario's own step size and simulated time `(h, t_end)`, s; an error if a
    /// mechanism scenario cannot build.
    pub fn default_steps(self) -> Result<(f64, f64), ModelError> {
        let mechanism = |s: Scenario<f64>| (s.h, s.t_end);
        let converter = |c: CccScenario| (c.h, c.t_end);
        match self {
            ScenarioId::SliderCrank => slider_crank().map(mechanism),
            ScenarioId::FiveBar => five_bar().map(mechanism),
            ScenarioId::CccS1 => Ok(converter(CccScenario::s1())),
            ScenarioId::CccS2 => Ok(converter(CccScenario::s2())),
        }
    }

    /// The converter scenario's default settings; `None` for a mechanism scenario.
    pub fn converter(self) -> Option<CccScenario> {
        match self {
            ScenarioId::CccS1 => Some(CccScenario::s1()),
            ScenarioId::CccS2 => Some(CccScenario::s2()),
            ScenarioId::SliderCrank | ScenarioId::FiveBar => None,
        }
    }
}
