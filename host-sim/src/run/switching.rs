//! The mechanism runner's coordinate switching at dead points of its drivers
//! ([`structomat::simulation::switch`], issue 17 item 5): the alternatives from
//! [`crate::model::alternatives`], the switch log, and the CSV values of the first
//! coordinates while another choice is in use.

use super::columns::{Column, Layout};
use crate::options::RunOptions;
use structomat::config::MAX_DOF;
use structomat::simulation::switch::{Alternatives, SwitchSettings};
use structomat::{Real, Simulation, StepError};

/// Capacity of the core's alternatives: the first model and the alternatives.
const CAPACITY: usize = crate::model::alternatives::MAX_ALTERNATIVES + 1;

/// One switch of coordinates, as the summary and the log print it.
#[derive(Clone, Debug, PartialEq)]
pub struct SwitchRecord {
    /// Time, s.
    pub time: f64,
    /// The sequence in use before (its formula).
    pub from: String,
    /// The sequence in use after.
    pub to: String,
    /// The group whose conditioning called for the switch (or `-` on a switch back).
    pub group: String,
    /// The worst conditioning before and after.
    pub conditioning: [f64; 2],
}

impl SwitchRecord {
    /// The switch log's header.
    pub const HEADER: &'static str = "t,from,to,group,conditioning_before,conditioning_after";

    /// Its line in the switch log.
    pub fn csv(&self) -> String {
        format!(
            "{:.9},{},{},{},{:.6e},{:.6e}",
            self.time, self.from, self.to, self.group, self.conditioning[0], self.conditioning[1]
        )
    }
}

/// A mechanism's alternatives and the switches made.
pub struct Switching<T: Real> {
    alts: Box<Alternatives<T, CAPACITY>>,
    /// The switches, in time order.
    pub log: Vec<SwitchRecord>,
    /// Whether the core's first evaluation ([`Alternatives::first_evaluation`]) holds
    /// the present state.
    evaluated: bool,
}

impl<T: Real> Switching<T> {
    /// The alternatives of `opts`'s mechanism file for `sim`, `None` when it has none
    /// (or is not a mechanism file).
    pub fn new(opts: &RunOptions, sim: &Simulation<T>) -> Result<Option<Self>, String> {
        let Ok(file) = opts.scenario.run_file() else {
            return Ok(None);
        };
        let crate::model::runfile::Body::Mechanism(m) = &file.body else {
            return Ok(None);
        };
        let models = crate::model::alternatives::alternatives::<T>(m)
            .map_err(|e| format!("{}: alternative coordinates: {e}", opts.scenario.name()))?;
        if models.is_empty() {
            return Ok(None);
        }
        let mut alts =
            Box::new(Alternatives::new(sim, SwitchSettings::default()).map_err(|e| e.to_string())?);
        for model in models {
            alts.add(model).map_err(|e| e.to_string())?;
        }
        Ok(Some(Switching {
            alts,
            log: Vec::new(),
            evaluated: false,
        }))
    }

    /// One step of `sim` in the best coordinates, the switch logged.
    pub fn step(&mut self, sim: &mut Simulation<T>) -> Result<(), StepError> {
        self.evaluated = false;
        if let Some(s) = self.alts.step(sim)? {
            let name = |k: u8| {
                self.alts
                    .models()
                    .get(k as usize)
                    .map_or_else(String::new, |m| m.formula().to_string())
            };
            self.log.push(SwitchRecord {
                time: s.time.to_f64(),
                from: name(s.from),
                to: name(s.to),
                group: if s.to == 0 {
                    "-".into()
                } else {
                    s.group.to_string()
                },
                conditioning: [s.conditioning[0].to_f64(), s.conditioning[1].to_f64()],
            });
        }
        Ok(())
    }

    /// Where the motion from `sim`'s state meets a singularity within `steps` step
    /// lengths, in the coordinates in use or the first ones
    /// ([`Alternatives::locate_singularity`]).
    pub fn locate_singularity(
        &mut self,
        sim: &Simulation<T>,
        scratch: &mut structomat::Workspace<T>,
        steps: u32,
    ) -> Option<(T, StepError)> {
        self.evaluated = false;
        self.alts.locate_singularity(sim, scratch, steps)
    }

    /// Evaluates the first model at `sim`'s state while an alternative drives (the
    /// values [`Switching::value`] reads): call it at each state before its values.
    pub fn evaluate(&mut self, sim: &Simulation<T>) {
        self.evaluated = self.alts.first_evaluation(sim).is_some();
    }

    /// The value of `col` while an alternative is in use, in the run's first
    /// coordinates and columns: the first model evaluated at the same physical state
    /// ([`Alternatives::first_evaluation`], by [`Switching::evaluate`]): its
    /// coordinates, rates and accelerations read off the links, the motors' torques,
    /// the reactions at its joints and the torques its drivers would need. `NaN` but
    /// for t, q, q̇ only where the first model does not evaluate (exactly at its dead
    /// point, where its driver's torque is not defined: the first coordinate does not
    /// move the links there). `None` while the first coordinates are in use (the
    /// column's own value holds).
    pub fn value(&self, col: Column, sim: &Simulation<T>) -> Option<T> {
        if self.alts.active() == 0 {
            return None;
        }
        let nan = T::c(f64::NAN);
        if self.evaluated {
            if let (Some(model), ws) = (self.alts.models().first(), self.alts.last_evaluation()) {
                return Some(Layout::read(col, model, ws, sim.time()));
            }
        }
        let (q, qd) = self.alts.first_state(sim);
        Some(match col {
            Column::Time => sim.time(),
            Column::Q(j) => q.get(j).copied().unwrap_or(nan),
            Column::Qd(j) => qd.get(j).copied().unwrap_or(nan),
            _ => nan,
        })
    }

    /// The first coordinates' rates at `sim`'s state, whichever choice is in use.
    pub fn first_qd(&self, sim: &Simulation<T>) -> [T; MAX_DOF] {
        self.alts.first_state(sim).1
    }
}
