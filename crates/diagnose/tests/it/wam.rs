//! Another class of arm: a real cable-driven 7-joint Barrett WAM (`fixtures/real/jacobi-wam/`), fitted on
//! its 216-pose grid and scored on its 20 random poses, in the base frame its author registered.

use thermokin_chain::{Dataset, Robot};
use thermokin_diagnose::{Config, diagnose};
use thermokin_identify::{FrameMode, ToolMode};
use thermokin_testdata::workspace;

/// The WAM (URDF, `wam_base` → `wam_flange`) and its grid and random sets.
pub fn wam() -> (Robot, Dataset, Dataset) {
    let options = thermokin_io::RobotOptions::default();
    let robot = thermokin_io::read_robot_with(&workspace("fixtures/real/jacobi-wam/wam.urdf"), &options).unwrap();
    let kinds: Vec<_> = robot.chain().joints().iter().map(|j| j.kind).collect();
    let read = |f: &str| thermokin_io::read_measurements(&workspace(&format!("fixtures/real/jacobi-wam/{f}")), &kinds);
    (robot.clone(), read("wam-grid.csv").unwrap(), read("wam-random.csv").unwrap())
}

#[test]
fn wam_grid_to_random() {
    let (robot, grid, random) = wam();
    assert_eq!((grid.len(), random.len()), (216, 20));
    let config = Config { frame: FrameMode::Tracker, tool: ToolMode::Unknown, ..Config::default() };
    let report = diagnose(&robot, &grid, Some(&random), &config).unwrap();
    crate::golden::drift_check("wam-grid-holdout-random", &robot, &report);
    let h = report.holdout.as_ref().unwrap();
    eprintln!(
        "WAM random: nominal {:.4} → chosen {:.4} mm mean (refit)",
        h.nominal.heldout_mean_mm, h.selected.heldout_mean_mm
    );
    // The nominal model with registration and tool refitted on the test poses: the independent 3.573.
    assert!((h.nominal.heldout_mean_mm - 3.573).abs() < 0.01, "{}", h.nominal.heldout_mean_mm);
}
