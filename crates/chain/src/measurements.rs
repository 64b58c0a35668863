//! Measured poses: plain data, read from files by `thermokin-io` and fitted by `thermokin-diagnose`. They
//! live in the core so that the readers sit below the algorithms that use them.

use nalgebra::{UnitQuaternion, Vector3};

/// One measured pose.
#[derive(Clone, Debug, PartialEq)]
pub struct Measurement {
    /// Operating time, minutes (0 when the file has none).
    pub time_min: f64,
    /// Joint values, radians (mm for prismatic joints).
    pub q: Vec<f64>,
    /// Measured TCP position, mm.
    pub position_mm: Vector3<f64>,
    /// Measured tool orientation in the same frame, when the probe measures one (a 6-D probe: T-Mac,
    /// three reflectors); `None` for a position-only reflector.
    pub orientation: Option<UnitQuaternion<f64>>,
    /// The tracker's stated standard deviation of this position per axis, mm, when it reports one
    /// (`std_x, std_y, std_z`): the fit weighs each axis by it.
    pub position_std_mm: Option<Vector3<f64>>,
    /// Temperatures, °C, in the order of [`Dataset::temperature_names`].
    pub temps: Vec<f64>,
}

/// A set of measurements.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct Dataset {
    /// The measurements.
    pub measurements: Vec<Measurement>,
    /// Names of the temperature columns.
    pub temperature_names: Vec<String>,
    /// Where each measurement was read: its 1-based line in the measurements file (the header is line
    /// 1; of the poses file when joints and poses are kept apart), one per measurement — empty when the
    /// set was not read from a file. What a report names a measurement by ([`Dataset::line_of`]).
    pub source_lines: Vec<usize>,
    /// Names of the sensor columns (an accelerometer's or inclinometer's tilt, a load): the readings a
    /// row's error may follow linearly; empty when the set has none.
    pub sensor_names: Vec<String>,
    /// Per measurement, its reading of each sensor column (in [`Dataset::sensor_names`]' order); empty
    /// when the set has no sensor columns.
    pub sensor_values: Vec<Vec<f64>>,
    /// Per measurement, per joint: the direction the joint last moved in before the pose was taken
    /// (what a gearbox's backlash follows), from the measuring order ([`Dataset::with_approach`]); empty
    /// when the set has no order.
    pub approach: Vec<Vec<Approach>>,
    /// The accelerometers (or inclinometers) declared on the robot's links, each read as the tilt of its
    /// link: sensor columns of [`Dataset::sensor_names`] hold, per pose, the small rotation (radians, in
    /// the sensor's axes) its reading shows against its reference direction ([`TiltSensor::tilt`]), and
    /// the declared sensor's below it on the chain. Empty when none is declared.
    pub tilt_sensors: Vec<TiltSensor>,
    /// The robot's branches whose joints the sensor columns log ([`crate::Branch`]): per branch, its index
    /// in [`crate::Robot::branches`] and the first of its consecutive columns, one per branch joint
    /// (degrees; mm for a slide) — no drivers.
    pub branch_columns: Vec<BranchColumns>,
}

/// The sensor columns that log one of the robot's branches ([`Dataset::branch_columns`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BranchColumns {
    /// The branch's index in [`crate::Robot::branches`].
    pub branch: usize,
    /// The first of its columns in [`Dataset::sensor_names`], one per branch joint in the branch's order.
    pub column: usize,
    /// How many: the branch's joints.
    pub len: usize,
}

impl BranchColumns {
    /// Whether sensor column `k` is one of them.
    pub fn holds(&self, k: usize) -> bool {
        (self.column..self.column + self.len).contains(&k)
    }
}

/// An accelerometer or inclinometer declared on a link ([`Dataset::tilt_sensors`]): its name, the link
/// (0: the robot's base, `k`: the link joint `k` moves), and the first of its tilt columns among the
/// set's sensor columns: its own tilt's `x`, `y`, `z`, then, with a sensor below it, that sensor's.
#[derive(Clone, Debug, PartialEq)]
pub struct TiltSensor {
    /// The sensor's name (its raw columns are `NAME_x`, `NAME_y`, `NAME_z`).
    pub name: String,
    /// The link it sits on: 0 the base, `k` the link joint `k` moves.
    pub link: usize,
    /// The first of its tilt columns in [`Dataset::sensor_names`].
    pub column: usize,
    /// Its reference direction, the unit vector of its readings the tilt is measured from (the training
    /// session's mean), in its own axes.
    pub reference: [f64; 3],
    /// The declared sensor below it on the chain, whose tilt (already turning everything above it) is
    /// taken from its own — what its link turns beyond — if any: that sensor's name.
    pub below: Option<String>,
}

/// The direction a joint last moved in before a pose: the flank of its gears that carries it (what a
/// backlash follows, [`Dataset::approach`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub enum Approach {
    /// Not known: the first pose of a session, or a joint that has not moved yet.
    #[default]
    Unknown,
    /// The joint's value rose to this pose.
    Rising,
    /// The joint's value fell to this pose.
    Falling,
}

impl Approach {
    /// `+1`, `−1`, or `0` when unknown: the sign a backlash's half-width is applied with.
    pub fn sign(self) -> f64 {
        match self {
            Approach::Unknown => 0.0,
            Approach::Rising => 1.0,
            Approach::Falling => -1.0,
        }
    }

    /// The direction of a move from `from` to `to`; a move smaller than `still` (radians, mm) keeps
    /// `self` — the joint did not leave the flank it rests on.
    pub fn after_move(self, from: f64, to: f64, still: f64) -> Approach {
        if to - from > still {
            Approach::Rising
        } else if from - to > still {
            Approach::Falling
        } else {
            self
        }
    }

    /// Each joint's direction after the move `from` → `to` ([`Approach::after_move`] with
    /// [`STILL_MOVE`]): one step along a sequence of poses, in place.
    pub fn advance(directions: &mut [Approach], from: &[f64], to: &[f64]) {
        for ((a, &f), &t) in directions.iter_mut().zip(from).zip(to) {
            *a = a.after_move(f, t, STILL_MOVE);
        }
    }

    /// The direction a flag or a file writes as `+`/`-`/`?` (or `1`/`-1`/`0`).
    pub fn parse(s: &str) -> Option<Approach> {
        match s.trim() {
            "+" | "+1" | "1" => Some(Approach::Rising),
            "-" | "-1" => Some(Approach::Falling),
            "?" | "0" => Some(Approach::Unknown),
            _ => None,
        }
    }
}

impl TiltSensor {
    /// The small rotation of the sensor (radians, in its own axes) that its `reading` shows against its
    /// unit `reference` direction (any unit proportional to g: only the direction counts): turned by `ω`,
    /// the sensor sees gravity turned by `−ω`, `û ≈ r̂ − ω × r̂`, so `ω = û × r̂` (its part across gravity:
    /// a turn about the vertical leaves gravity where it was). Its size is the sine of the angle, the
    /// angle itself to a part in 10⁴ below 1°. `None` for a reading of no length or not finite.
    pub fn tilt(reading: [f64; 3], reference: [f64; 3]) -> Option<Vector3<f64>> {
        let u = Vector3::from(reading);
        let n = u.norm();
        if !(n.is_finite() && n > 0.0) {
            return None;
        }
        Some((u / n).cross(&Vector3::from(reference)))
    }
}

/// Where the order the poses were measured in comes from, for what follows the direction of motion (a
/// backlash: [`Dataset::with_approach`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum MeasuringOrder {
    /// The default: the poses' times order them; a set without a time span has no order.
    #[default]
    Time,
    /// The file lists the poses as they were measured: their lines order them where no time span does.
    File,
}

crate::choices!(
    MeasuringOrder,
    "measuring order",
    [
        ("time", "the time_min column orders the poses (a set without one has no order)", MeasuringOrder::Time),
        (
            "file",
            "the file lists the poses as they were measured (a time column, where there is one, still decides)",
            MeasuringOrder::File
        ),
    ]
);

/// The order of a sequence of moves (a program's targets, a joints file's rows) given each one's time:
/// by time where every one has a time and they span time (ties in the given order), else the given
/// order — what a backlash's directions are taken along where no measurement set orders them.
pub fn time_order(times: &[Option<f64>]) -> Vec<usize> {
    let mut order: Vec<usize> = (0..times.len()).collect();
    let known: Option<Vec<f64>> = times.iter().copied().collect();
    if let Some(t) = known
        && t.iter().any(|&v| v != t[0])
    {
        order.sort_by(|&a, &b| t[a].total_cmp(&t[b]).then(a.cmp(&b)));
    }
    order
}

/// A joint move smaller than this (radians, mm) is not a move: what a controller repeats as the same
/// commanded value after rounding.
pub const STILL_MOVE: f64 = 1e-9;

impl Dataset {
    /// The measurements at `rows` (in that order), with the same temperature columns.
    pub fn subset(&self, rows: &[usize]) -> Dataset {
        Dataset {
            measurements: rows.iter().filter_map(|&i| self.measurements.get(i).cloned()).collect(),
            temperature_names: self.temperature_names.clone(),
            source_lines: if self.source_lines.len() == self.measurements.len() {
                rows.iter().filter_map(|&i| self.source_lines.get(i).copied()).collect()
            } else {
                Vec::new()
            },
            sensor_names: self.sensor_names.clone(),
            sensor_values: if self.sensor_values.len() == self.measurements.len() {
                rows.iter().filter_map(|&i| self.sensor_values.get(i).cloned()).collect()
            } else {
                Vec::new()
            },
            approach: if self.approach.len() == self.measurements.len() {
                rows.iter().filter_map(|&i| self.approach.get(i).cloned()).collect()
            } else {
                Vec::new()
            },
            tilt_sensors: self.tilt_sensors.clone(),
            branch_columns: self.branch_columns.clone(),
        }
    }

    /// The set without the sensor columns named in `names` (each pose's readings with them), its
    /// [`Dataset::tilt_sensors`]' columns moved to their new places.
    pub fn without_sensor_columns(&self, names: &[String]) -> Dataset {
        let keep: Vec<usize> =
            (0..self.sensor_names.len()).filter(|&k| !names.contains(&self.sensor_names[k])).collect();
        let mut out = self.clone();
        out.sensor_names = keep.iter().map(|&k| self.sensor_names[k].clone()).collect();
        out.sensor_values = if out.sensor_names.is_empty() {
            Vec::new()
        } else {
            self.sensor_values.iter().map(|r| keep.iter().filter_map(|&k| r.get(k).copied()).collect()).collect()
        };
        for t in &mut out.tilt_sensors {
            t.column = keep.iter().position(|&k| k == t.column).unwrap_or(t.column);
        }
        for b in &mut out.branch_columns {
            b.column = keep.iter().position(|&k| k == b.column).unwrap_or(b.column);
        }
        out
    }

    /// The file line measurement `i` (0-based) was read from, when the set was read from a file.
    pub fn line_of(&self, i: usize) -> Option<usize> {
        (self.source_lines.len() == self.measurements.len()).then(|| self.source_lines.get(i).copied()).flatten()
    }

    /// Number of measurements.
    pub fn len(&self) -> usize {
        self.measurements.len()
    }
    /// `true` when there are none.
    pub fn is_empty(&self) -> bool {
        self.measurements.is_empty()
    }
    /// `true` when every measurement carries an orientation (the diagnosis then fits 6-D poses).
    pub fn has_orientation(&self) -> bool {
        !self.measurements.is_empty() && self.measurements.iter().all(|m| m.orientation.is_some())
    }
    /// `true` when every measurement carries the tracker's stated standard deviations.
    pub fn has_position_std(&self) -> bool {
        !self.measurements.is_empty() && self.measurements.iter().all(|m| m.position_std_mm.is_some())
    }
    /// The time span covered, minutes.
    pub fn time_span(&self) -> f64 {
        let (lo, hi) = self
            .measurements
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), m| (l.min(m.time_min), h.max(m.time_min)));
        if lo.is_finite() { hi - lo } else { 0.0 }
    }

    /// The order the poses were measured in, when the set carries one: by time when it spans time, else
    /// by file line when `by` says the file lists them as measured; `None` otherwise. Poses of one time
    /// are in file order where `by` says the file is the order, else in the set's order (a file's lines
    /// are no order unless said: the diagnosis puts such a set in an order of its own poses first).
    pub fn measuring_order(&self, by: MeasuringOrder) -> Option<Vec<usize>> {
        let mut idx: Vec<usize> = (0..self.len()).collect();
        if self.time_span() > 0.0 {
            let t = |i: usize| self.measurements[i].time_min;
            let line = |i: usize| if by == MeasuringOrder::File { self.line_of(i).unwrap_or(i) } else { i };
            idx.sort_by(|&a, &b| t(a).total_cmp(&t(b)).then(line(a).cmp(&line(b))).then(a.cmp(&b)));
            return Some(idx);
        }
        if by != MeasuringOrder::File {
            return None;
        }
        let lines: Vec<usize> = (0..self.len()).map(|i| self.line_of(i)).collect::<Option<_>>()?;
        idx.sort_by_key(|&i| lines[i]);
        Some(idx)
    }

    /// The set with [`Dataset::approach`] filled from its measuring order ([`Dataset::measuring_order`] by
    /// `by`):
    /// each joint's direction is that of its last move, from the pose before, that is larger than
    /// [`STILL_MOVE`] — a joint that stays put rests on the flank it came to. The first pose's joints are
    /// [`Approach::Unknown`]. A set without an order, or with its approach already given, is returned as
    /// is.
    pub fn with_approach(mut self, by: MeasuringOrder) -> Self {
        if self.approach.len() == self.len() && !self.is_empty() {
            return self;
        }
        self.approach.clear();
        let Some(order) = self.measuring_order(by) else { return self };
        let dof = self.measurements.first().map_or(0, |m| m.q.len());
        let mut approach = vec![vec![Approach::Unknown; dof]; self.len()];
        let mut last = vec![Approach::Unknown; dof];
        for pair in order.windows(2) {
            Approach::advance(&mut last, &self.measurements[pair[0]].q, &self.measurements[pair[1]].q);
            approach[pair[1]].clone_from(&last);
        }
        self.approach = approach;
        self
    }

    /// Pose `i`'s approach direction of joint `j` ([`Approach::Unknown`] without an order).
    pub fn approach_of(&self, i: usize, j: usize) -> Approach {
        self.approach.get(i).and_then(|a| a.get(j)).copied().unwrap_or_default()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn moves_follow_their_times_where_every_one_has_one() {
        assert_eq!(time_order(&[Some(3.0), Some(1.0), Some(1.0), Some(2.0)]), [1, 2, 3, 0]);
        // One without a time, or all at one time: the given order.
        assert_eq!(time_order(&[Some(3.0), None, Some(1.0)]), [0, 1, 2]);
        assert_eq!(time_order(&[Some(5.0), Some(5.0)]), [0, 1]);
    }

    #[test]
    fn a_tilt_is_the_sensors_turn() {
        // A sensor reading +z (up) at rest, turned by 0.01 rad about x: it sees up at Rᵀ·z.
        let turn = nalgebra::Rotation3::from_scaled_axis(Vector3::new(0.01, -0.004, 0.0));
        let reading = turn.inverse() * Vector3::new(0.0, 0.0, 9.81);
        let tilt = TiltSensor::tilt(reading.into(), [0.0, 0.0, 1.0]).expect("a reading of length 9.81");
        assert!((tilt - Vector3::new(0.01, -0.004, 0.0)).norm() < 1e-6, "{tilt}");
        assert!(TiltSensor::tilt([0.0; 3], [0.0, 0.0, 1.0]).is_none());
    }

    fn pose(time_min: f64, q: [f64; 2]) -> Measurement {
        Measurement {
            time_min,
            q: q.to_vec(),
            position_mm: Vector3::zeros(),
            orientation: None,
            position_std_mm: None,
            temps: Vec::new(),
        }
    }

    #[test]
    fn approach_follows_the_last_move_in_measuring_order() {
        // Written out of time order: the times decide; joint 2 stays put from the second pose on.
        let data = Dataset {
            measurements: vec![
                pose(2.0, [0.3, 1.0]),
                pose(0.0, [0.1, 0.0]),
                pose(1.0, [0.5, 1.0]),
                pose(3.0, [0.3, 1.0]),
            ],
            ..Dataset::default()
        }
        .with_approach(MeasuringOrder::Time);
        use Approach::*;
        assert_eq!(data.approach[1], vec![Unknown, Unknown]);
        assert_eq!(data.approach[2], vec![Rising, Rising]);
        assert_eq!(data.approach[0], vec![Falling, Rising]);
        // Same joint values as the pose before: each joint stays on its flank.
        assert_eq!(data.approach[3], vec![Falling, Rising]);
        // A subset keeps each pose's direction (the robot moved through the poses left out).
        assert_eq!(data.subset(&[3, 1]).approach, vec![vec![Falling, Rising], vec![Unknown, Unknown]]);
    }

    #[test]
    fn a_set_without_an_order_has_no_approach_and_lines_are_one_when_said() {
        let data = Dataset { measurements: vec![pose(0.0, [0.1, 0.0]), pose(0.0, [0.2, 0.0])], ..Dataset::default() };
        assert!(data.with_approach(MeasuringOrder::File).approach.is_empty());
        // File lines are an order when the file is said to list the poses as measured.
        let lined = Dataset {
            measurements: vec![pose(0.0, [0.1, 0.0]), pose(0.0, [0.2, 0.0])],
            source_lines: vec![3, 2],
            ..Dataset::default()
        };
        assert!(lined.clone().with_approach(MeasuringOrder::Time).approach.is_empty());
        let lined = lined.with_approach(MeasuringOrder::File);
        assert_eq!(lined.approach[0], vec![Approach::Falling, Approach::Unknown]);
    }
}
