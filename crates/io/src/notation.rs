//! The small notations of values given on a command line or as Python strings — a list of numbers, a
//! pose, sensor readings, a payload — read in one place for every front end, and a pose written in every
//! convention ([`PoseOut`]). Errors are the message only; the front end says which flag or argument.

use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
use serde::Serialize;
use thermokin_chain::LinkMass;

use crate::units::{Orientation, quaternion_wxyz, ros_rpy_deg, rotation_from_matrix, rounded, xyz_euler_deg};

/// A comma-separated list of finite numbers: `10,20,-5.5`.
pub fn parse_list(text: &str) -> Result<Vec<f64>, String> {
    text.split(',')
        .enumerate()
        .map(|(i, v)| {
            let x: f64 = v.trim().parse().map_err(|_| format!("value {} `{}` is not a number", i + 1, v.trim()))?;
            if x.is_finite() { Ok(x) } else { Err(format!("value {} is not finite", i + 1)) }
        })
        .collect()
}

/// A pose: `x,y,z` (mm) followed by the orientation in `convention` (three angles in degrees, or a
/// quaternion w,x,y,z), or a JSON object `{"position_mm": [..], "rotation": [[..],[..],[..]]}` (a rotation
/// matrix, as `fk --json` prints it), with `quaternion_wxyz`, `xyz_euler_deg` or `ros_rpy_deg` in place of
/// `rotation`.
pub fn parse_pose(text: &str, convention: Orientation) -> Result<Isometry3<f64>, String> {
    if text.trim_start().starts_with('{') {
        return parse_pose_json(text);
    }
    let v = parse_list(text)?;
    let want = 3 + convention.arity();
    if v.len() != want {
        return Err(format!("expected {want} values (x,y,z then the {convention:?} orientation), got {}", v.len()));
    }
    let rotation = convention.rotation(&v[3..])?;
    Ok(Isometry3::from_parts(Translation3::new(v[0], v[1], v[2]), rotation))
}

/// A pose as the JSON object of [`parse_pose`].
fn parse_pose_json(text: &str) -> Result<Isometry3<f64>, String> {
    let v: serde_json::Value = serde_json::from_str(text).map_err(|e| format!("not JSON: {e}"))?;
    let numbers = |key: &str, n: usize| -> Result<Option<Vec<f64>>, String> {
        let Some(value) = v.get(key) else { return Ok(None) };
        let list: Option<Vec<f64>> = value.as_array().map(|a| a.iter().filter_map(serde_json::Value::as_f64).collect());
        match list {
            Some(l) if l.len() == n => Ok(Some(l)),
            _ => Err(format!("`{key}` must be an array of {n} numbers")),
        }
    };
    let p = numbers("position_mm", 3)?.ok_or("`position_mm` is missing")?;
    let rotation = if let Some(rows) = v.get("rotation") {
        let m: Option<Vec<Vec<f64>>> = rows.as_array().map(|r| {
            r.iter()
                .map(|row| {
                    row.as_array().map_or_else(Vec::new, |x| x.iter().filter_map(serde_json::Value::as_f64).collect())
                })
                .collect()
        });
        let m =
            m.filter(|m| m.len() == 3 && m.iter().all(|r| r.len() == 3)).ok_or("`rotation` must be a 3 × 3 array")?;
        rotation_from_matrix([[m[0][0], m[0][1], m[0][2]], [m[1][0], m[1][1], m[1][2]], [m[2][0], m[2][1], m[2][2]]])?
    } else if let Some(q) = numbers("quaternion_wxyz", 4)? {
        Orientation::Quaternion.rotation(&q)?
    } else if let Some(e) = numbers("xyz_euler_deg", 3)? {
        Orientation::XyzEuler.rotation(&e)?
    } else if let Some(e) = numbers("ros_rpy_deg", 3)? {
        Orientation::Rpy.rotation(&e)?
    } else {
        return Err("give `rotation`, `quaternion_wxyz`, `xyz_euler_deg` or `ros_rpy_deg`".into());
    };
    Ok(Isometry3::from_parts(Translation3::from(Vector3::new(p[0], p[1], p[2])), rotation))
}

/// Sensor readings `temp_j2=35.1,temp_j3=30.2` (°C; the `temp_` prefix added when left out), each
/// sensor once.
pub fn parse_temperatures(text: &str) -> Result<Vec<(String, f64)>, String> {
    let mut out: Vec<(String, f64)> = Vec::new();
    for item in text.split(',').map(str::trim).filter(|s| !s.is_empty()) {
        let (name, value) =
            item.split_once('=').ok_or_else(|| format!("`{item}`: expected NAME=°C, e.g. temp_j2=35.1"))?;
        let name = crate::targets::sensor_name(name.trim());
        let value: f64 = value
            .trim()
            .parse()
            .ok()
            .filter(|v: &f64| v.is_finite())
            .ok_or_else(|| format!("`{item}`: `{}` is not a temperature in °C", value.trim()))?;
        if out.iter().any(|(n, _)| *n == name) {
            return Err(format!("`{name}` given twice"));
        }
        out.push((name, value));
    }
    if out.is_empty() {
        return Err("no reading given".into());
    }
    Ok(out)
}

/// A payload `KG@X,Y,Z`: its mass in kg at its centre in the flange's frame, mm.
pub fn parse_payload(spec: &str) -> Result<LinkMass, String> {
    let (kg, at) = spec.split_once('@').ok_or_else(|| format!("{spec}: expected KG@X,Y,Z (kg @ mm)"))?;
    let mass_kg: f64 = kg.trim().parse().map_err(|_| format!("{spec}: mass `{kg}` is not a number"))?;
    let c = parse_list(at)?;
    if c.len() != 3 {
        return Err(format!("{spec}: the centre takes 3 values (mm), got {}", c.len()));
    }
    Ok(LinkMass { mass_kg, com_mm: Vector3::new(c[0], c[1], c[2]) })
}

/// A pose in every convention, for output: position, rotation matrix, X-Y-Z Euler (the paper's), ROS
/// roll-pitch-yaw and the quaternion; numbers at their meaningful precision, not binary noise — 1e-10 mm
/// and degrees (a tenth of the solver's 1e-9 tolerance, so a printed pose fed back to `ik` loses nothing),
/// 1e-13 for matrix and quaternion entries. Its JSON is what `fk --json` prints; its `Display` the text.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PoseOut {
    /// Position, mm.
    pub position_mm: [f64; 3],
    /// Rotation matrix, rows.
    pub rotation: [[f64; 3]; 3],
    /// X-Y-Z Euler angles, `R = Rx·Ry·Rz`, degrees (the first set to 0 at the singularity RY = ±90°).
    pub xyz_euler_deg: [f64; 3],
    /// ROS roll, pitch, yaw, `R = Rz(yaw)·Ry(pitch)·Rx(roll)`, degrees.
    pub ros_rpy_deg: [f64; 3],
    /// Unit quaternion `w, x, y, z`.
    pub quaternion_wxyz: [f64; 4],
}

impl PoseOut {
    /// `pose` in every convention, rounded to its meaningful precision.
    pub fn of(pose: &Isometry3<f64>) -> Self {
        let m = pose.rotation.to_rotation_matrix().into_inner();
        let p = pose.translation.vector;
        let mm_deg = |x: f64| rounded(x, 10);
        let unitless = |x: f64| rounded(x, 13);
        Self {
            position_mm: [mm_deg(p.x), mm_deg(p.y), mm_deg(p.z)],
            rotation: [0, 1, 2].map(|r| [0, 1, 2].map(|c| unitless(m[(r, c)]))),
            xyz_euler_deg: xyz_euler_deg(&pose.rotation).map(mm_deg),
            ros_rpy_deg: ros_rpy_deg(&pose.rotation).map(mm_deg),
            quaternion_wxyz: quaternion_wxyz(&pose.rotation).map(unitless),
        }
    }

    /// The rotation as a unit quaternion.
    pub fn rotation(&self) -> UnitQuaternion<f64> {
        let [w, x, y, z] = self.quaternion_wxyz;
        UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(w, x, y, z))
    }
}

/// One row of a batch of poses (`fk --joints-file`): the input's line, and its pose or why it has none.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PoseRow {
    /// The input row's line.
    pub line: usize,
    /// The pose, when there is one.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub pose: Option<PoseOut>,
    /// Why there is none.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub error: Option<String>,
}

impl PoseRow {
    /// Every row of a joints file (`fk --joints-file`: `q1..qn` in degrees, optional `time_min` /
    /// `temp_*`) through `model`, each in its own state or, where it gives none, in `flags`: its pose, or
    /// why it has none (a bad row, a state the model refuses).
    pub fn of_file(
        model: &thermokin_deform::RobotModel,
        path: &std::path::Path,
        flags: &thermokin_chain::OperatingState,
    ) -> Result<Vec<PoseRow>, crate::IoError> {
        let kinds: Vec<_> = model.robot().chain().joints().iter().map(|j| j.kind).collect();
        let rows = crate::read_joint_rows(path, &kinds, crate::JointUnits::Degrees)?;
        let mut read: Vec<ReadRow> = rows
            .into_iter()
            .map(|row| {
                let values = row.values.map_err(|e| e.to_string()).map(|(q, state)| {
                    let state = if state == thermokin_chain::OperatingState::default() { flags.clone() } else { state };
                    (q, state)
                });
                (row.line, values)
            })
            .collect();
        if model.has_backlash() {
            with_approach_in_measuring_order(&mut read, flags);
        }
        Ok(read
            .into_iter()
            .map(|(line, values)| {
                match values.and_then(|(q, state)| model.tool_pose(&q, &state).map_err(|e| e.to_string())) {
                    Ok(p) => PoseRow { line, pose: Some(PoseOut::of(&p)), error: None },
                    Err(e) => PoseRow { line, pose: None, error: Some(e) },
                }
            })
            .collect())
    }

    /// The header of [`PoseRow::csv`]: the position and the X-Y-Z Euler angles.
    pub const CSV_HEADER: &'static str = "line,x_mm,y_mm,z_mm,rx_deg,ry_deg,rz_deg,error";

    /// The row as CSV.
    pub fn csv(&self) -> String {
        match (&self.pose, &self.error) {
            (Some(p), _) => {
                let ([x, y, z], [rx, ry, rz]) = (p.position_mm, p.xyz_euler_deg);
                format!("{},{x},{y},{z},{rx},{ry},{rz},", self.line)
            }
            (None, e) => format!("{},,,,,,,{}", self.line, csv_cell(e.as_deref().unwrap_or(""))),
        }
    }
}

/// A joints file's row as `fk --joints-file` reads it: its line, and its joint values and state or why it
/// has none.
type ReadRow = (usize, Result<(Vec<f64>, thermokin_chain::OperatingState), String>);

/// Each readable row's [`thermokin_chain::OperatingState::approach`] — the direction each joint last
/// moved in, what a backlash follows — along the robot's moves: in the order of the rows' `time_min`
/// where every readable row has one and they span time (rows of one time in file order), else in the
/// file's order (a joints file lists the moves as the robot makes them). The first move starts from the
/// flags' directions (none given: unknown).
fn with_approach_in_measuring_order(rows: &mut [ReadRow], flags: &thermokin_chain::OperatingState) {
    let readable: Vec<usize> = (0..rows.len()).filter(|&k| rows[k].1.is_ok()).collect();
    let times: Vec<Option<f64>> =
        readable.iter().map(|&k| rows[k].1.as_ref().ok().and_then(|(_, s)| s.time_min)).collect();
    let order: Vec<usize> = thermokin_chain::time_order(&times).into_iter().map(|i| readable[i]).collect();
    let mut last: Option<(Vec<f64>, Vec<thermokin_chain::Approach>)> = None;
    for k in order {
        let Ok((q, state)) = &mut rows[k].1 else { continue };
        if let Some((from, approach)) = &last {
            state.approach.clone_from(approach);
            thermokin_chain::Approach::advance(&mut state.approach, from, q);
        } else {
            state.approach.clone_from(&flags.approach);
        }
        let known = if state.approach.len() == q.len() {
            state.approach.clone()
        } else {
            vec![thermokin_chain::Approach::Unknown; q.len()]
        };
        last = Some((q.clone(), known));
    }
}

/// A CSV cell: quoted when it holds a comma, a quote or a line break (quotes doubled).
pub fn csv_cell(text: &str) -> String {
    if text.contains([',', '"', '\n', '\r']) { format!("\"{}\"", text.replace('"', "\"\"")) } else { text.to_string() }
}

impl std::fmt::Display for PoseOut {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let [x, y, z] = self.position_mm;
        let [a, b, c] = self.xyz_euler_deg;
        let [roll, pitch, yaw] = self.ros_rpy_deg;
        let [qw, qx, qy, qz] = self.quaternion_wxyz;
        writeln!(f, "position_mm     {x:.6} {y:.6} {z:.6}")?;
        writeln!(f, "xyz_euler_deg   {a:.6} {b:.6} {c:.6}   (R = Rx·Ry·Rz, the paper's convention)")?;
        writeln!(f, "ros_rpy_deg     {roll:.6} {pitch:.6} {yaw:.6}   (R = Rz(yaw)·Ry(pitch)·Rx(roll))")?;
        writeln!(f, "quaternion_wxyz {qw:.9} {qx:.9} {qy:.9} {qz:.9}")?;
        if b.abs() == 90.0 {
            writeln!(f, "note: RY = ±90° is the X-Y-Z Euler singularity; only RX ± RZ is defined, shown as RX = 0")?;
        }
        Ok(())
    }
}

/// The joints of `q` outside `chain`'s limits ([`thermokin_chain::Chain::outside_limits`]), each named
/// with its value and limits in degrees (mm for a prismatic joint): `A2 = 115.000000 outside
/// [-90.000000, 110.000000]`.
pub fn outside_limits(chain: &thermokin_chain::Chain, q: &[f64]) -> Vec<String> {
    use crate::units::joints_to_external;
    let lower: Vec<f64> = chain.joints().iter().map(|j| j.limits.map_or(f64::NEG_INFINITY, |l| l.lower)).collect();
    let upper: Vec<f64> = chain.joints().iter().map(|j| j.limits.map_or(f64::INFINITY, |l| l.upper)).collect();
    let (lo, hi, v) =
        (joints_to_external(chain, &lower), joints_to_external(chain, &upper), joints_to_external(chain, q));
    let joints = chain.joints();
    chain
        .outside_limits(q)
        .into_iter()
        .map(|i| format!("{} = {:.6} outside [{:.6}, {:.6}]", joints[i].name, v[i], lo[i], hi[i]))
        .collect()
}
