//! The CSV layout: which quantity each column holds, its name, and its value at the
//! simulation's current state.

use structomat::kinetostatics::driving_torque;
use structomat::model::Model;
use structomat::structomat::JointKind;
use structomat::workspace::Workspace;
use structomat::{Real, Simulation};

/// The quantity of one CSV column.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Column {
    /// Time, s.
    Time,
    /// Coordinate `q[j]` (0-based here, 1-based in the name).
    Q(usize),
    /// Its rate.
    Qd(usize),
    /// Its acceleration.
    Qdd(usize),
    /// The applied torque of drive `k` (`ws.motor[k]`).
    Motor(usize),
    /// `|force|` of a revolute joint: joint `joint` of group `group`.
    Revolute {
        /// Group index in the sequence.
        group: usize,
        /// Joint index in the group.
        joint: usize,
    },
    /// `|normal force|` of a prismatic joint.
    Normal {
        /// Group index in the sequence.
        group: usize,
        /// Joint index in the group.
        joint: usize,
    },
    /// Reaction moment of a prismatic joint (signed).
    Moment {
        /// Group index in the sequence.
        group: usize,
        /// Joint index in the group.
        joint: usize,
    },
    /// The kinetostatic driving torque (force) of motor element `group`.
    Drive {
        /// Group index in the sequence.
        group: usize,
    },
}

impl Column {
    /// Whether the column is a reaction force magnitude (revolute or prismatic normal),
    /// the quantities the summary's maximum reaction is taken over.
    pub fn is_reaction_force(self) -> bool {
        matches!(self, Column::Revolute { .. } | Column::Normal { .. })
    }
}

/// The columns of a model's CSV, with their (unique) names.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Layout {
    /// The quantities, in column order.
    pub columns: Vec<Column>,
    /// The header names, in column order.
    pub names: Vec<String>,
}

impl Layout {
    /// The layout of `model`: `t`; `q{j}, qd{j}, qdd{j}` per coordinate;
    /// `motor_torque{coord+1}` per drive; then per group (sequence order) and joint:
    /// `R{i}_{j}`, `N{i}_{j}` + `M{i}_{j}`, or `drive_torque{coord+1}`. A repeated name
    /// gets the suffix `_2`, `_3`, ...
    pub fn new<T: Real>(model: &Model<T>) -> Layout {
        let mut cols: Vec<(Column, String)> = vec![(Column::Time, "t".into())];
        for j in 0..model.dof() {
            let n = j + 1;
            cols.push((Column::Q(j), format!("q{n}")));
            cols.push((Column::Qd(j), format!("qd{n}")));
            cols.push((Column::Qdd(j), format!("qdd{n}")));
        }
        for (k, d) in model.drives().iter().enumerate() {
            cols.push((
                Column::Motor(k),
                format!("motor_torque{}", u32::from(d.coord) + 1),
            ));
        }
        for (group, g) in model.groups().iter().enumerate() {
            for (joint, jt) in g.joints.iter().enumerate() {
                let (i, j) = (jt.i, jt.j);
                match jt.kind {
                    JointKind::Revolute => {
                        cols.push((Column::Revolute { group, joint }, format!("R{i}_{j}")))
                    }
                    JointKind::Prismatic { .. } => {
                        cols.push((Column::Normal { group, joint }, format!("N{i}_{j}")));
                        cols.push((Column::Moment { group, joint }, format!("M{i}_{j}")));
                    }
                    JointKind::DriveTorque | JointKind::DriveForce { .. } => {
                        let name = match g.coord {
                            Some(c) => format!("drive_torque{}", u32::from(c) + 1),
                            None => "drive_torque".to_string(),
                        };
                        cols.push((Column::Drive { group }, name));
                    }
                }
            }
        }
        let mut names: Vec<String> = Vec::with_capacity(cols.len());
        for (_, base) in cols.iter() {
            let mut name = base.clone();
            let mut k = 2;
            while names.contains(&name) {
                name = format!("{base}_{k}");
                k += 1;
            }
            names.push(name);
        }
        Layout {
            columns: cols.into_iter().map(|(c, _)| c).collect(),
            names,
        }
    }

    /// The value of `col` at the simulation's current state; the reaction columns read
    /// the last [`Simulation::kinetostatics`] call (make it at the current state).
    pub fn value<T: Real>(col: Column, sim: &Simulation<T>) -> T {
        match col {
            Column::Time => sim.time(),
            Column::Q(j) => sim.q().get(j).copied().unwrap_or(T::c(f64::NAN)),
            Column::Qd(j) => sim.qd().get(j).copied().unwrap_or(T::c(f64::NAN)),
            Column::Qdd(j) => sim.qdd().get(j).copied().unwrap_or(T::c(f64::NAN)),
            _ => Layout::read(col, sim.model(), sim.workspace(), sim.time()),
        }
    }

    /// The value of `col` in `model`'s evaluation `ws` at time `t` (s): its coordinates,
    /// motors and reactions (those of the last kinetostatics in `ws`).
    pub fn read<T: Real>(col: Column, model: &Model<T>, ws: &Workspace<T>, t: T) -> T {
        let nan = T::c(f64::NAN);
        let reaction =
            |group: usize, joint: usize| ws.reactions.get(group).and_then(|r| r.get(joint));
        match col {
            Column::Time => t,
            Column::Q(j) => ws.q.get(j).copied().unwrap_or(nan),
            Column::Qd(j) => ws.qd.get(j).copied().unwrap_or(nan),
            Column::Qdd(j) => ws.qdd.get(j).copied().unwrap_or(nan),
            Column::Motor(k) => ws.motor.get(k).copied().unwrap_or(nan),
            Column::Revolute { group, joint } => {
                reaction(group, joint).map_or(nan, |r| r.force.norm())
            }
            Column::Normal { group, joint } => {
                reaction(group, joint).map_or(nan, |r| r.force.norm())
            }
            Column::Moment { group, joint } => reaction(group, joint).map_or(nan, |r| r.moment),
            Column::Drive { group } => driving_torque(model, ws, group).unwrap_or(nan),
        }
    }
}
