//! `structomat.Twin`: the converter's twin ([`structomat::ccc::Twin`]) stepped from
//! Python with per-step inputs, as the firmware steps it: `step(motor, load)`, then its
//! mode, coordinates, speeds, clutch torques and energy audit. It is built as `host-sim
//! run` builds the twin of a converter scenario ([`host_sim::ccc::new_twin`], the same
//! options), so that stepping it under the scenario's own motor and load gives the
//! run's rows ([`host_sim::ccc::row`]) bit for bit.

use crate::errors::{error, run_error, TwinError};
use crate::options::run_options;
use crate::table::as_csv;
use host_sim::ccc::{columns, new_twin, row, settings};
use host_sim::options::Steps;
use host_sim::output::Cell;
use numpy::PyArray1;
use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use structomat::ccc::{Inputs, Measurement, MotorInput, Twin as CoreTwin};
use structomat::Real;

/// A twin in either precision.
enum Any {
    F64(Box<CoreTwin<f64>>),
    F32(Box<CoreTwin<f32>>),
}

/// Runs `$body` with `$t` bound to the twin, whatever its scalar.
macro_rules! each {
    ($self:expr, $t:ident => $body:expr) => {
        match &$self.twin {
            Any::F64($t) => $body,
            Any::F32($t) => $body,
        }
    };
}

/// The converter's twin, stepped from Python.
#[pyclass(module = "structomat._core")]
pub struct Twin {
    twin: Any,
    /// The scenario's motor law and load: a step's inputs when it gives none.
    motor_law: [MotorInput<f64>; 1],
    motor_law32: [MotorInput<f32>; 1],
    load: f64,
    columns: Vec<String>,
    name: String,
}

/// `inputs` in scalar `T` from the Python step's `motor` and `load`, or else the
/// scenario's law and load.
fn inputs<T: Real>(
    law: MotorInput<T>,
    load: f64,
    motor: Option<f64>,
    given_load: Option<f64>,
    measured: Option<(i64, u32, f64)>,
) -> Inputs<T> {
    Inputs {
        motor: motor.map_or(law, |m| MotorInput::Torque(T::c(m))),
        load: T::c(given_load.unwrap_or(load)),
        measured: measured
            .map(|(counts, per_turn, zero)| Measurement::crank(counts, per_turn, T::c(zero))),
    }
}

/// One of the twin's values as Python reads it: the `f64` of the CSV's text.
fn v<T: Real>(x: T) -> f64 {
    as_csv(x)
}

#[pymethods]
impl Twin {
    /// A twin of the converter scenario `source` (`ccc-s1`, `ccc-s2` or a converter
    /// run file) with `host-sim run`'s converter options (`h`, `motor`, `load`, `ccw`,
    /// `spread_events`, `f32`), at its initial state, its first mode chosen under the scenario's motor
    /// and load.
    #[new]
    #[pyo3(signature = (source = "ccc-s2", **overrides))]
    fn new(source: &str, overrides: Option<&Bound<'_, PyDict>>) -> PyResult<Self> {
        // A run's keywords that a twin has no use for: refused, not ignored.
        for key in ["t_end", "every"] {
            if overrides.is_some_and(|kw| kw.contains(key).unwrap_or(false)) {
                return Err(PyTypeError::new_err(format!(
                    "unexpected keyword argument '{key}' (a twin has no run: the keywords of a twin: h, step, f32, f64, motor, load, ccw, spread_events)"
                )));
            }
        }
        let opts = run_options(source, overrides)?;
        let name = opts.scenario.name().to_string();
        let s = settings(&opts).ok_or_else(|| {
            error(format!(
                "{name} is not a converter scenario: structomat.Twin steps the converter's twin"
            ))
        })?;
        let bad_motor =
            |e: structomat::ModelError| error(format!("cannot set up {name}: motor: {e}"));
        let law = MotorInput::Law(s.motor.motor::<f64>().map_err(bad_motor)?);
        let law32 = MotorInput::Law(s.motor.motor::<f32>().map_err(bad_motor)?);
        let twin = if opts.f32 {
            let (_, h) = Steps::of::<f32>(&opts).map_err(|e| run_error(&e))?;
            let start = inputs(law32, s.load, None, None, None);
            Any::F32(Box::new(
                new_twin(&name, &s, h, start).map_err(|e| run_error(&e))?,
            ))
        } else {
            let (_, h) = Steps::of::<f64>(&opts).map_err(|e| run_error(&e))?;
            let start = inputs(law, s.load, None, None, None);
            Any::F64(Box::new(
                new_twin(&name, &s, h, start).map_err(|e| run_error(&e))?,
            ))
        };
        Ok(Twin {
            twin,
            motor_law: [law],
            motor_law32: [law32],
            load: s.load,
            columns: columns(),
            name,
        })
    }

    /// One step of `h` with the motor torque `motor` (N·m, CCW positive, held over the
    /// step; `None`: the scenario's motor law, evaluated at every stage), the load
    /// torque `load` on the shaft (N·m ≥ 0; `None`: the scenario's) and optionally the
    /// crank encoder's reading `(counts, counts per turn, zero angle in rad)` to compare
    /// against (the angle `zero + (counts + ½)·2π/per_turn`). A refused or
    /// failed step raises `structomat.TwinError` with the core's message and keeps the
    /// last good state.
    #[pyo3(signature = (motor = None, load = None, measured = None))]
    fn step(
        &mut self,
        motor: Option<f64>,
        load: Option<f64>,
        measured: Option<(i64, u32, f64)>,
    ) -> PyResult<()> {
        let r = match &mut self.twin {
            Any::F64(t) => t.step(&inputs(self.motor_law[0], self.load, motor, load, measured)),
            Any::F32(t) => t.step(&inputs(
                self.motor_law32[0],
                self.load,
                motor,
                load,
                measured,
            )),
        };
        r.map_err(|e| {
            TwinError::new_err(format!(
                "{}: step {} failed: {e}",
                self.name,
                self.steps() + 1
            ))
        })
    }

    /// Steps taken.
    #[getter]
    fn steps(&self) -> u64 {
        each!(self, t => t.steps())
    }

    /// Time of the present state, s.
    #[getter]
    fn time(&self) -> f64 {
        each!(self, t => v(t.time()))
    }

    /// How far the twin's time is behind the clock's `steps · h`, s: 0 unless it
    /// spreads its events (`spread_events=True`), a few steps at most after an event.
    #[getter]
    fn lag(&self) -> f64 {
        each!(self, t => v(t.lag()))
    }

    /// The fixed step, s.
    #[getter]
    fn h(&self) -> f64 {
        each!(self, t => v(t.h()))
    }

    /// `"f64"` or `"f32"`.
    #[getter]
    fn precision(&self) -> &'static str {
        match self.twin {
            Any::F64(_) => "f64",
            Any::F32(_) => "f32",
        }
    }

    /// The mode's name (`"A68"`, `"I0"`, ...).
    #[getter]
    fn mode(&self) -> &'static str {
        each!(self, t => t.mode().name())
    }

    /// The mode's code (the CSV's `mode_code`).
    #[getter]
    fn mode_code(&self) -> u8 {
        each!(self, t => t.mode().code())
    }

    /// The coordinate choice's name.
    #[getter]
    fn coordinates(&self) -> &'static str {
        each!(self, t => t.coordinates().name())
    }

    /// The independent coordinates of the mode (rad), as many as its DOF.
    #[getter]
    fn q<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        let q: Vec<f64> = each!(self, t => t.q().iter().map(|x| v(*x)).collect());
        PyArray1::from_vec(py, q)
    }

    /// Their speeds (rad/s).
    #[getter]
    fn qd<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        let q: Vec<f64> = each!(self, t => t.qd().iter().map(|x| v(*x)).collect());
        PyArray1::from_vec(py, q)
    }

    /// Link p's angle (rad) for p = 1..8 (`theta[0]` is the crank, link 1).
    #[getter]
    fn theta<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        let q: Vec<f64> = each!(self, t => (1..=8).map(|p| v(t.link(p).theta)).collect());
        PyArray1::from_vec(py, q)
    }

    /// Link p's angular speed (rad/s) for p = 1..8.
    #[getter]
    fn omega<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        let q: Vec<f64> = each!(self, t => (1..=8).map(|p| v(t.link(p).omega)).collect());
        PyArray1::from_vec(py, q)
    }

    /// The crank's angle, rad.
    #[getter]
    fn crank_angle(&self) -> f64 {
        each!(self, t => v(t.link(1).theta))
    }

    /// The crank's speed, rad/s.
    #[getter]
    fn crank_speed(&self) -> f64 {
        each!(self, t => v(t.link(1).omega))
    }

    /// The shaft's angle turned, rad, CCW positive.
    #[getter]
    fn shaft_angle(&self) -> f64 {
        each!(self, t => v(t.shaft_angle()))
    }

    /// The shaft's speed, rad/s.
    #[getter]
    fn shaft_speed(&self) -> f64 {
        each!(self, t => v(t.shaft_speed()))
    }

    /// Clutch 6's torque, N·m.
    #[getter]
    fn c6(&self) -> f64 {
        each!(self, t => v(t.clutch_torques()[0]))
    }

    /// Clutch 8's torque, N·m.
    #[getter]
    fn c8(&self) -> f64 {
        each!(self, t => v(t.clutch_torques()[1]))
    }

    /// The motor torque on the crank at the present state, N·m.
    #[getter]
    fn motor_torque(&self) -> f64 {
        each!(self, t => v(t.motor_torque()))
    }

    /// The energy audit, J: motor_work, load_work, impact_loss, kinetic, potential,
    /// initial, and residual (motor work - Δ(K + V) - load work - impact losses).
    #[getter]
    fn audit<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let a: [(&str, f64); 7] = each!(self, t => {
            let a = t.audit();
            [
                ("motor_work", v(a.motor_work)),
                ("load_work", v(a.load_work)),
                ("impact_loss", v(a.impact_loss)),
                ("kinetic", v(a.kinetic)),
                ("potential", v(a.potential)),
                ("initial", v(a.initial)),
                ("residual", v(a.residual())),
            ]
        });
        let d = PyDict::new(py);
        for (k, x) in a {
            d.set_item(k, x)?;
        }
        Ok(d)
    }

    /// The twin's crank angle less the measured one (rad) of the last step given a
    /// measurement, else `None`.
    #[getter]
    fn measurement_residual(&self) -> Option<f64> {
        each!(self, t => t.measurement_residual().and_then(|r| r.crank).map(v))
    }

    /// The events of the last step (of the set-up before the first): dicts of the
    /// event log's columns.
    #[getter]
    fn events<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyList>> {
        let list = PyList::empty(py);
        each!(self, t => {
            for e in t.events() {
                let d = PyDict::new(py);
                d.set_item("time", v(e.time))?;
                d.set_item("event", e.kind.name())?;
                d.set_item("from", e.from.name())?;
                d.set_item("to", e.to.name())?;
                d.set_item("c6", v(e.c[0]))?;
                d.set_item("c8", v(e.c[1]))?;
                d.set_item("impact_loss", v(e.impact_loss))?;
                d.set_item("mismatch", v(e.mismatch))?;
                list.append(d)?;
            }
        });
        Ok(list)
    }

    /// The coordinate switches of the last step: dicts of the switch log's columns.
    #[getter]
    fn switches<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyList>> {
        let list = PyList::empty(py);
        each!(self, t => {
            for s in t.switches() {
                let d = PyDict::new(py);
                d.set_item("time", v(s.time))?;
                d.set_item("mode", s.mode.name())?;
                d.set_item("from", s.from.name())?;
                d.set_item("to", s.to.name())?;
                d.set_item("conditioning_before", v(s.conditioning[0]))?;
                d.set_item("conditioning_after", v(s.conditioning[1]))?;
                list.append(d)?;
            }
        });
        Ok(list)
    }

    /// The state as a row of `host-sim run`'s CSV: a dict of its column names to
    /// floats (`mode` and `coords` as str; cells past the mode's DOF NaN), the same
    /// values as the CSV's text read back.
    fn state<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        fn put<T: Real>(
            d: &Bound<'_, PyDict>,
            names: &[String],
            twin: &CoreTwin<T>,
        ) -> PyResult<()> {
            let mut cells = Vec::new();
            row(twin, &mut cells);
            for (name, cell) in names.iter().zip(&cells) {
                match cell {
                    Cell::Num(x) => d.set_item(name, as_csv(*x))?,
                    Cell::Int(n) => d.set_item(name, *n as f64)?,
                    Cell::Text(s) => d.set_item(name, *s)?,
                    Cell::Empty => d.set_item(name, f64::NAN)?,
                }
            }
            Ok(())
        }
        match &self.twin {
            Any::F64(t) => put(&d, &self.columns, t)?,
            Any::F32(t) => put(&d, &self.columns, t)?,
        }
        Ok(d)
    }

    fn __repr__(&self) -> String {
        format!(
            "Twin({}, {}, t = {} s, mode {}, {} coordinates)",
            self.name,
            self.precision(),
            self.time(),
            self.mode(),
            self.coordinates()
        )
    }
}
