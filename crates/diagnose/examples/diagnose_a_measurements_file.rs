//! A diagnosis of a measurements file, as `thermokin diagnose` runs it: the robot file, the tracker's
//! poses (in the tracker's own frame, the probe on the flange unknown), and a hold-out file scored in
//! both protocols. The report prints itself.
//!
//! ```text
//! cargo run --release --example diagnose_a_measurements_file -p thermokin-diagnose -- [ROBOT MEASUREMENTS.csv HOLDOUT.csv]
//! ```
//! Without arguments: the real Barrett WAM of `fixtures/real/jacobi-wam` (its 216 grid poses, its 20
//! random poses held out).

use std::error::Error;
use std::path::PathBuf;

use thermokin_diagnose::{Config, diagnose};
use thermokin_identify::{FrameMode, ToolMode};
use thermokin_io::{RobotOptions, read_measurements, read_robot_with};

fn main() -> Result<(), Box<dyn Error>> {
    let root = PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures/real/jacobi-wam"));
    let args: Vec<PathBuf> = std::env::args().skip(1).map(PathBuf::from).collect();
    let at = |k: usize, default: &str| args.get(k).cloned().unwrap_or_else(|| root.join(default));
    let robot = read_robot_with(&at(0, "wam.urdf"), &RobotOptions::default())?;
    let kinds: Vec<_> = robot.chain().joints().iter().map(|j| j.kind).collect();
    let data = read_measurements(&at(1, "wam-grid.csv"), &kinds)?;
    let holdout = read_measurements(&at(2, "wam-random.csv"), &kinds)?;
    let config = Config { frame: FrameMode::Tracker, tool: ToolMode::Unknown, ..Config::default() };
    let report = diagnose(&robot, &data, Some(&holdout), &config)?;
    print!("{}", report.text());
    Ok(())
}
