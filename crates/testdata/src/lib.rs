#![doc = include_str!("../README.md")]
//! Test support: where the workspace and its fixtures are, Table 9's IRB 140 built in code, and what the
//! simulated trackers of several crates' tests share (seeded Gaussian noise, poses inside the limits, a
//! bench's peak memory).
//!
//! Every file a test reads is inside the repository (`fixtures/`, `configs/`): the authors' published
//! files, the real tracker data and the URDFs were copied in with their provenance (`fixtures/README.md`),
//! so no test skips and none depends on anything beside the checkout.

use std::path::{Path, PathBuf};

/// The workspace root.
pub fn workspace_root() -> PathBuf {
    let here = Path::new(env!("CARGO_MANIFEST_DIR"));
    here.parent().and_then(Path::parent).map_or_else(|| here.to_path_buf(), Path::to_path_buf)
}

/// A path inside the workspace.
pub fn workspace(rel: &str) -> PathBuf {
    workspace_root().join(rel)
}

/// A file of the authors' published CoppeliaSim data (`fixtures/paper/authors/`).
pub fn authors(file: &str) -> PathBuf {
    workspace("fixtures/paper/authors").join(file)
}

/// A file of the real Rokae robot B tracker data (`fixtures/real/rokae-robot-b/`).
pub fn rokae_robot_b(file: &str) -> PathBuf {
    workspace("fixtures/real/rokae-robot-b").join(file)
}

/// The bundled IRB 140's robot file (`configs/irb140.toml`) on a vertical lift of 800 mm stroke — a
/// prismatic first joint 300 mm under the arm — with `extra` lines (TOML, each ending in a newline) in
/// the lift's table.
pub fn lifted_irb140_toml(extra: &str) -> String {
    let text = std::fs::read_to_string(workspace("configs/irb140.toml")).expect("the bundled IRB 140");
    let at = text.find("[[joint]]").expect("a [[joint]] table");
    let lift = "[[joint]]\nname = \"lift\"\naxis = \"Z\"\ntype = \"prismatic\"\noffset_mm = [0.0, 0.0, 300.0]\nlimits = [0.0, 800.0]\n";
    format!("{}{lift}{extra}\n{}", &text[..at], &text[at..])
}

/// One of the public URDFs (`fixtures/urdf/`).
pub fn urdf(file: &str) -> PathBuf {
    workspace("fixtures/urdf").join(file)
}

/// Table 9's nominal ABB IRB 140 in the same-orientation convention, built in code for crates that must
/// not read files (the bundled `configs/irb140.toml` holds the same numbers; a test in `thermokin-io`
/// compares them). Joint axes Z, Y, Y, X, Y, X; the TCP 25.5 mm along X past joint 6, turned Ry(90°).
pub fn irb140_table9() -> thermokin_chain::Chain {
    use nalgebra::{Isometry3, Vector3};
    use thermokin_chain::{Chain, FixedRow, Joint};
    let axes = [
        Vector3::z_axis(),
        Vector3::y_axis(),
        Vector3::y_axis(),
        Vector3::x_axis(),
        Vector3::y_axis(),
        Vector3::x_axis(),
    ];
    let offsets = [
        [0.0, 0.0, 104.5],
        [70.0, 65.0, 247.5],
        [0.0, -123.0, 360.0],
        [238.5, 58.0, 0.0],
        [141.5, 0.0, 0.0],
        [39.5, 0.0, 0.0],
    ];
    let joints = axes
        .iter()
        .zip(offsets)
        .enumerate()
        .map(|(i, (a, o))| Joint::revolute(format!("A{}", i + 1), Vector3::from(o), *a))
        .collect();
    let tool = Isometry3::new(Vector3::new(25.5, 0.0, 0.0), Vector3::new(0.0, 90f64.to_radians(), 0.0));
    match Chain::new(FixedRow::identity(), joints, FixedRow::from_isometry(&tool)) {
        Ok(c) => c,
        Err(e) => unreachable!("Table 9 is a valid chain: {e}"),
    }
}

/// Six error parameters written as the paper's tables write them (`Dx,Dy,Dz` mm, `Dox,Doy,Doz`
/// degrees), for tests of crates below the unit boundary (`thermokin_io::units::error_params_in` is the
/// boundary itself).
pub fn error_mm_deg(values: [f64; 6]) -> thermokin_chain::ErrorParams {
    let [dx, dy, dz, ox, oy, oz] = values;
    thermokin_chain::ErrorParams::new(
        nalgebra::Vector3::new(dx, dy, dz),
        nalgebra::Vector3::new(ox.to_radians(), oy.to_radians(), oz.to_radians()),
    )
}

/// How a row grows over a test's 180-minute warm-up: `(1 − e^(−t/τ)) / (1 − e^(−180/τ))`, `t / 180`, or
/// not at all (a static deviation, in force from the cold start) — the true robot's law, written here
/// apart from the diagnosis's model.
#[derive(Clone, Copy, Debug)]
pub enum WarmUpLaw {
    /// Rising with time constant `tau_min`, reaching the row at minute 180.
    Exponential {
        /// Minutes.
        tau_min: f64,
    },
    /// Growing in proportion to time, the row at minute 180.
    Linear,
    /// The whole row from the start.
    Static,
}

impl WarmUpLaw {
    /// The share of the row in force at minute `t`.
    pub fn at(self, t: f64) -> f64 {
        match self {
            WarmUpLaw::Exponential { tau_min } => (1.0 - (-t / tau_min).exp()) / (1.0 - (-180.0 / tau_min).exp()),
            WarmUpLaw::Linear => t / 180.0,
            WarmUpLaw::Static => 1.0,
        }
    }
}

/// A six-joint `chain` at minute `t` of a warm-up: joint 2's zero `offset_deg` off, its row and joint
/// 3's each grown by its own law (the warm-up tests' true robots, built on the chain).
pub fn warmed_up(
    chain: &thermokin_chain::Chain,
    offset_deg: f64,
    row2: (thermokin_chain::ErrorParams, WarmUpLaw),
    row3: (thermokin_chain::ErrorParams, WarmUpLaw),
    t: f64,
) -> thermokin_chain::Chain {
    use thermokin_chain::ErrorParams;
    let mut rows = vec![ErrorParams::ZERO; 6];
    rows[1] = row2.0.scaled(row2.1.at(t));
    rows[2] = row3.0.scaled(row3.1.at(t));
    let mut zeros = vec![0.0; 6];
    zeros[1] = offset_deg.to_radians();
    chain.with_errors_and_zeros(ErrorParams::ZERO, &rows, ErrorParams::ZERO, &zeros).expect("a six-joint chain")
}

/// A standard normal sample (Box–Muller), from a seeded generator.
pub fn gauss(rng: &mut rand_chacha::ChaCha8Rng) -> f64 {
    use rand::Rng;
    let (u1, u2): (f64, f64) = (rng.random_range(f64::MIN_POSITIVE..1.0), rng.random_range(0.0..1.0));
    (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
}

/// A static, position-only measurement at commanded joints `q`: `position_mm` with Gaussian noise of
/// `noise_mm` per axis drawn from `rng` (x, y, z in that order), at time 0, without orientation or
/// temperatures — what the simulated trackers of the tests record.
pub fn measured_point(
    q: Vec<f64>,
    position_mm: nalgebra::Vector3<f64>,
    noise_mm: f64,
    rng: &mut rand_chacha::ChaCha8Rng,
) -> thermokin_chain::Measurement {
    let noise = nalgebra::Vector3::new(gauss(rng), gauss(rng), gauss(rng)) * noise_mm;
    thermokin_chain::Measurement {
        time_min: 0.0,
        q,
        position_mm: position_mm + noise,
        orientation: None,
        position_std_mm: None,
        temps: Vec::new(),
    }
}

/// Joint values drawn uniformly 10 % inside each joint's limits (real calibration poses avoid them); every
/// joint must have limits.
pub fn random_q(chain: &thermokin_chain::Chain, rng: &mut rand_chacha::ChaCha8Rng) -> Vec<f64> {
    use rand::Rng;
    chain
        .joints()
        .iter()
        .map(|j| {
            let l = j.limits.expect("a simulated tracker draws poses inside the joint limits");
            let m = 0.1 * (l.upper - l.lower);
            rng.random_range(l.lower + m..l.upper - m)
        })
        .collect()
}

/// Peak resident memory of this process, MiB (Linux `VmHWM`); `None` elsewhere: what a bench reports
/// beside its time.
pub fn peak_rss_mib() -> Option<f64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let kb: f64 = status.lines().find(|l| l.starts_with("VmHWM:"))?.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb / 1024.0)
}

/// CPU seconds this process has used so far, user and system, all threads (`/proc/self/stat`, fields 14
/// and 15, in clock ticks of 1/100 s — the kernel's `USER_HZ` on every Linux this runs on); `None` off
/// Linux. Read twice around a run, the difference is the run's CPU time.
pub fn cpu_seconds() -> Option<f64> {
    let stat = std::fs::read_to_string("/proc/self/stat").ok()?;
    // The command name (field 2) is in parentheses and may hold spaces: count from the closing one.
    let rest = &stat[stat.rfind(')')? + 1..];
    let fields: Vec<&str> = rest.split_whitespace().collect();
    let ticks = |k: usize| fields.get(k)?.parse::<f64>().ok();
    // After ')': field 3 is at 0, so utime (14) at 11 and stime (15) at 12.
    Some((ticks(11)? + ticks(12)?) / 100.0)
}

// A lift on a chassis that rocks, with two accelerometers.
mod rocking {
    use nalgebra::{Isometry3, Rotation3, Translation3, UnitQuaternion, Vector3};
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;
    use thermokin_chain::{Chain, Dataset};

    use crate::{gauss, measured_point, random_q};

    /// A turn `angles` (radians) about the point `at`.
    fn about(at: Vector3<f64>, angles: Vector3<f64>) -> Isometry3<f64> {
        let turn = UnitQuaternion::from_scaled_axis(angles);
        Translation3::from(at) * turn * Translation3::from(-at)
    }

    /// The accelerometer's reading (m/s², its own axes) on a link the world turns by `link`, mounted at
    /// `yaw` (radians about the link's z) and off level by `off`, with noise `sigma` (m/s²).
    fn reading(link: &Rotation3<f64>, yaw: f64, off: Vector3<f64>, sigma: f64, rng: &mut ChaCha8Rng) -> [f64; 3] {
        let mount = Rotation3::from_axis_angle(&Vector3::z_axis(), yaw) * Rotation3::from_scaled_axis(off);
        let up = (link * mount).inverse() * Vector3::new(0.0, 0.0, 9.81);
        [up.x + sigma * gauss(rng), up.y + sigma * gauss(rng), up.z + sigma * gauss(rng)]
    }

    /// `n` poses of one session of a lift ([`crate::lifted_irb140_toml`]) on a chassis that rocks, measured with 5 µm
    /// of noise per axis (issue #59's class, written with isometries about the pivots, independently of any
    /// model's rows): the chassis rests tilted by `rest` (radians) and tilts further by 1.5 µrad
    /// per mm of the tool's reach across the column, about a point 150 mm out, 100 mm aside, at the floor;
    /// the column bends beyond it by 1.5 nrad per mm of reach per mm of extension, about a point 250 mm
    /// below the carriage. Poses sorted by the column's height, lines in that order, no time column; the
    /// accelerometers `acc_base` and `acc_top` (columns `_x`, `_y`, `_z`).
    pub fn rocking_lift_session(chain: &Chain, n: usize, seed: u64, rest: Vector3<f64>) -> Dataset {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let mut poses: Vec<Vec<f64>> = (0..n).map(|_| random_q(chain, &mut rng)).collect();
        poses.sort_by(|a, b| a[0].total_cmp(&b[0]));
        let mut data = Dataset { sensor_names: Vec::new(), ..Dataset::default() };
        for a in ["acc_base", "acc_top"] {
            data.sensor_names.extend(["x", "y", "z"].map(|c| format!("{a}_{c}")));
        }
        for q in poses {
            let frames = chain.joint_frames(&q).expect("poses drawn within the chain's joints");
            let (carriage, tool) = (frames[0], frames[chain.dof()]);
            let reach = tool.translation.vector;
            let across = Vector3::new(-reach.y, reach.x, 0.0);
            let chassis = rest + across * 1.5e-6;
            let bend = across * (1.5e-9 * q[0]);
            // Above the carriage turned about its pivot, then the whole robot about the chassis's.
            let carriage_bent = carriage * about(Vector3::new(0.0, 0.0, -250.0), bend) * carriage.inverse();
            let world_from_tool = about(Vector3::new(150.0, -100.0, 0.0), chassis) * carriage_bent * tool;
            let base_turn = Rotation3::from_scaled_axis(chassis);
            let top_turn = base_turn * carriage.rotation.to_rotation_matrix() * Rotation3::from_scaled_axis(bend);
            let mut row = reading(&base_turn, 0.35, Vector3::new(0.004, -0.002, 0.0), 2e-5, &mut rng).to_vec();
            row.extend(reading(&top_turn, -0.6, Vector3::new(-0.003, 0.001, 0.0), 2e-5, &mut rng));
            data.measurements.push(measured_point(q, world_from_tool.translation.vector, 0.005, &mut rng));
            data.sensor_values.push(row);
        }
        data.source_lines = (2..2 + data.len()).collect();
        data
    }
}
pub use rocking::rocking_lift_session;

mod torso;
pub use torso::{
    Elastic, elastic_torso_session, two_armed_torso_session, two_armed_torso_urdf, two_armed_torso_urdf_with_masses,
};

mod construction;
pub use construction::{Session, construction_robot_toml, construction_session};
