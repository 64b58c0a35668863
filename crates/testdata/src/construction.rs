//! A construction robot (issue #59's class, as the real sessions are shaped): a lifting column 1 to 4 m
//! tall carrying a six-joint arm of 1.6 m reach, measured by a total station in blocks of poses at five
//! column heights (no time column), the chassis resting differently in each session, accelerometers on
//! the chassis and on the carriage that are remounted between sessions (their readings offset). The
//! truth is written here with rotations and translations of its own — the column bends as a cantilever
//! under the moment of the arm's masses (tilt `M L / EI`, shift `M L² / 2EI` at its top, `L` its standing
//! length), the chassis rocks about a point on the floor under the same moment, the arm's joints sag
//! under their gravity torques — independently of any model's rows or functions.

use nalgebra::{Rotation3, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use thermokin_chain::Dataset;

use crate::{gauss, measured_point};

/// One joint of the robot: name, axis, origin in the previous joint's frame at zero (mm), limits (degrees;
/// mm for the column), the mass its link carries (kg, centre in its frame, mm), its compliance (rad per
/// N·m), and its true geometric error (origin shift, mm; turn, degrees) and zero offset (degrees).
struct Joint {
    name: &'static str,
    axis: [f64; 3],
    origin: [f64; 3],
    limits: [f64; 2],
    mass: (f64, [f64; 3]),
    compliance: f64,
    shift: [f64; 3],
    turn_deg: [f64; 3],
    zero_deg: f64,
}

/// The column (a slide along z, its foot 1,000 mm above the floor), then an arm of the IRB 140's axes at
/// twice its size, with masses of a 150 kg arm; the tool 200 mm past the flange.
fn joints() -> Vec<Joint> {
    let j = |name, axis, origin, limits, mass, compliance, shift, turn_deg, zero_deg| Joint {
        name,
        axis,
        origin,
        limits,
        mass,
        compliance,
        shift,
        turn_deg,
        zero_deg,
    };
    let (x, y, z) = ([1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]);
    vec![
        j(
            "column",
            z,
            [0.0, 0.0, 1000.0],
            [0.0, 3000.0],
            (40.0, [0.0, 0.0, 100.0]),
            0.0,
            [0.4, -0.3, 0.8],
            [0.02, -0.01, 0.0],
            0.0,
        ),
        j(
            "a1",
            z,
            [0.0, 0.0, 209.0],
            [-170.0, 170.0],
            (60.0, [60.0, 20.0, 300.0]),
            0.0,
            [0.6, 0.3, -0.5],
            [0.01, 0.03, 0.0],
            0.08,
        ),
        j(
            "a2",
            y,
            [140.0, 130.0, 495.0],
            [-80.0, 100.0],
            (35.0, [0.0, -40.0, 360.0]),
            2.5e-6,
            [-0.4, 0.7, 0.3],
            [0.02, 0.0, -0.03],
            -0.12,
        ),
        j(
            "a3",
            y,
            [0.0, -246.0, 720.0],
            [-200.0, 40.0],
            (25.0, [180.0, 60.0, 20.0]),
            3.0e-6,
            [0.5, -0.2, 0.4],
            [-0.03, 0.02, 0.01],
            0.1,
        ),
        j(
            "a4",
            x,
            [477.0, 116.0, 0.0],
            [-180.0, 180.0],
            (10.0, [160.0, 0.0, 0.0]),
            0.0,
            [-0.3, 0.4, 0.2],
            [0.0, 0.02, 0.03],
            0.05,
        ),
        j(
            "a5",
            y,
            [283.0, 0.0, 0.0],
            [-110.0, 110.0],
            (5.0, [40.0, 0.0, 0.0]),
            4.0e-6,
            [0.2, 0.2, -0.3],
            [0.03, 0.0, 0.02],
            -0.06,
        ),
        j(
            "a6",
            x,
            [79.0, 0.0, 0.0],
            [-300.0, 300.0],
            (12.0, [150.0, 0.0, 0.0]),
            0.0,
            [0.1, -0.2, 0.1],
            [0.0, 0.0, 0.0],
            0.0,
        ),
    ]
}

/// The tool point past joint 6 (mm, its frame at zero).
const TOOL: [f64; 3] = [251.0, 0.0, 0.0];
/// The column's bending stiffness (N·m²): 1.5 mrad of tilt at its top standing 4 m under 780 N·m.
const COLUMN_EI: f64 = 2.1e6;
/// The chassis's rocking compliance (rad per N·m) and the point on the floor it rocks about (mm).
const CHASSIS_COMPLIANCE: f64 = 0.8e-6;
const CHASSIS_PIVOT: [f64; 3] = [300.0, -200.0, 0.0];
/// The column's extensions the sessions stand at (mm).
const HEIGHTS: [f64; 5] = [200.0, 800.0, 1400.0, 2000.0, 2600.0];

/// The construction robot as a user gives it (`[[joint]]` tables, no masses).
pub fn construction_robot_toml() -> String {
    let mut text = String::from("name = \"construction robot\"\nconvention = \"extended\"\n");
    for j in joints() {
        let axis = if j.axis[0] == 1.0 {
            "X"
        } else if j.axis[1] == 1.0 {
            "Y"
        } else {
            "Z"
        };
        let kind = if j.name == "column" { "type = \"prismatic\"\n" } else { "" };
        let [a, b, c] = j.origin;
        let [lo, hi] = j.limits;
        text += &format!(
            "\n[[joint]]\nname = \"{}\"\naxis = \"{axis}\"\n{kind}offset_mm = [{a:.1}, {b:.1}, {c:.1}]\nlimits = [{lo:.1}, {hi:.1}]\n",
            j.name
        );
    }
    let [a, b, c] = TOOL;
    text + &format!("\n[tool]\ntranslation_mm = [{a:.1}, {b:.1}, {c:.1}]\n")
}

/// How one session stands: the chassis's rest (a tilt, radians), and the accelerometers' mountings —
/// each off level by its own small turn (radians) and offset in its readings (m/s²), as a remounted
/// sensor is.
#[derive(Clone, Copy, Debug)]
pub struct Session {
    /// The chassis's tilt at rest, radians about x and y.
    pub rest: [f64; 2],
    /// Each sensor's (chassis, carriage) reading offset, m/s² per axis.
    pub offsets: [[f64; 3]; 2],
    /// The share of each arm joint's range the poses span, about its middle (0.8: 10 % inside the limits;
    /// a program's work at a wall spans less).
    pub spread: f64,
    /// How far the chassis settles anew at each column height (radians, standard deviation per axis):
    /// what only the chassis's accelerometer sees.
    pub settle: f64,
}

/// Frames `(rotation, origin)` of each joint (after its motion) and of the tool, in the column's foot
/// frame, for joint values `q` (radians; mm for the column), with the true geometric errors.
fn frames(t: &[Joint], q: &[f64]) -> Vec<(Rotation3<f64>, Vector3<f64>)> {
    let mut r = Rotation3::identity();
    let mut p = Vector3::zeros();
    let mut out = Vec::with_capacity(t.len() + 1);
    for (j, &v) in t.iter().zip(q) {
        let turn = Vector3::from(j.turn_deg).map(f64::to_radians);
        p += r * (Vector3::from(j.origin) + Vector3::from(j.shift));
        r *= Rotation3::from_scaled_axis(turn);
        let axis = Vector3::from(j.axis);
        if j.name == "column" {
            p += r * axis * v;
        } else {
            r *= Rotation3::from_scaled_axis(axis * (v + j.zero_deg.to_radians()));
        }
        out.push((r, p));
    }
    out.push((r, p + r * Vector3::from(TOOL)));
    out
}

/// `per_height` poses at each of five column heights, measured height after height (the file's lines in
/// that order, no time column), the arm's joints drawn 10 % inside their limits; the total station's
/// noise `noise_mm` per axis; the sensors `acc_base` (on the chassis) and `acc_top` (on the carriage),
/// columns `_x`, `_y`, `_z` in m/s², mounted at yaws 0.4 and −0.7 rad.
pub fn construction_session(per_height: usize, seed: u64, session: Session, noise_mm: f64) -> Dataset {
    let t = joints();
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let g = 9.80665;
    let mut data = Dataset::default();
    for a in ["acc_base", "acc_top"] {
        data.sensor_names.extend(["x", "y", "z"].map(|c| format!("{a}_{c}")));
    }
    for h in HEIGHTS {
        // The chassis settles anew at each height: its rest plus a turn of its own per block.
        let settled = Vector3::new(gauss(&mut rng), gauss(&mut rng), 0.0) * session.settle;
        let rest = Vector3::new(session.rest[0], session.rest[1], 0.0) + settled;
        for _ in 0..per_height {
            let mut q = vec![h];
            q.extend(t[1..].iter().map(|j| {
                let (lo, hi) = (j.limits[0].to_radians(), j.limits[1].to_radians());
                let (mid, half) = ((lo + hi) / 2.0, (hi - lo) / 2.0 * session.spread);
                rng.random_range(mid - half..mid + half)
            }));
            // Gravity in the column's foot frame, turned by the rest (small: its effect on the sags only).
            let down = Rotation3::from_scaled_axis(rest).inverse() * Vector3::new(0.0, 0.0, -g);
            let at = frames(&t, &q);
            let mut sagged = q.clone();
            for a in 1..t.len() {
                let (ra, oa) = at[a];
                let axis = ra * Vector3::from(t[a].axis);
                let torque: f64 = (a..t.len())
                    .map(|l| {
                        let (rl, ol) = at[l];
                        let centre = ol + rl * Vector3::from(t[l].mass.1);
                        axis.dot(&((centre - oa) / 1000.0).cross(&(down * t[l].mass.0)))
                    })
                    .sum();
                sagged[a] += t[a].compliance * torque;
            }
            let at = frames(&t, &sagged);
            // The moment of the arm about the carriage (N·m), horizontal part.
            let carriage = at[0].1;
            let moment: Vector3<f64> = (1..t.len())
                .map(|l| {
                    let (rl, ol) = at[l];
                    let centre = ol + rl * Vector3::from(t[l].mass.1);
                    ((centre - carriage) / 1000.0).cross(&(down * t[l].mass.0))
                })
                .sum();
            let moment = Vector3::new(moment.x, moment.y, 0.0);
            // The column, standing `length` m above the chassis, bends as a cantilever under it: its top
            // turns by M L / EI and shifts by (M L² / 2EI) × z.
            let length = (t[0].origin[2] + h) / 1000.0;
            let bend = moment * (length / COLUMN_EI);
            let shift = (moment * (length * length / (2.0 * COLUMN_EI))).cross(&Vector3::z()) * 1000.0;
            let tool = at[t.len()].1;
            let above = carriage + shift + Rotation3::from_scaled_axis(bend) * (tool - carriage);
            // The chassis rocks about its pivot under the same moment, on top of its rest.
            let rock = moment * CHASSIS_COMPLIANCE;
            let chassis = Rotation3::from_scaled_axis(rest + rock);
            let pivot = Vector3::from(CHASSIS_PIVOT);
            let world = pivot + chassis * (above - pivot);
            let mut row = reading(&chassis, 0.4, session.offsets[0], &mut rng);
            row.extend(reading(&(chassis * Rotation3::from_scaled_axis(bend)), -0.7, session.offsets[1], &mut rng));
            data.measurements.push(measured_point(q, world, noise_mm, &mut rng));
            data.sensor_values.push(row);
        }
    }
    data.source_lines = (2..2 + data.len()).collect();
    data
}

/// An accelerometer's reading (m/s², its own axes) on a link the world turns by `link`, mounted at `yaw`
/// (radians about the link's z) and 0.2° off level, offset by `offset`, with 2e-4 m/s² of noise.
fn reading(link: &Rotation3<f64>, yaw: f64, offset: [f64; 3], rng: &mut ChaCha8Rng) -> Vec<f64> {
    let mount = Rotation3::from_axis_angle(&Vector3::z_axis(), yaw)
        * Rotation3::from_scaled_axis(Vector3::new(0.0035, -0.002, 0.0));
    let up = (link * mount).inverse() * Vector3::new(0.0, 0.0, 9.80665);
    (0..3).map(|k| up[k] + offset[k] + 2e-4 * gauss(rng)).collect()
}
