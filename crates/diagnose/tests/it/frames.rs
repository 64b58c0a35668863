//! The user's frames: the fitted tool point in the robot's tip frame, whatever the tip link's turn against
//! the last joint.

use nalgebra::{UnitQuaternion, Vector3};
use thermokin_chain::FixedRow;
use thermokin_diagnose::{Config, Validation, diagnose};
use thermokin_identify::{FrameMode, ToolMode};
use thermokin_testdata::workspace;

use crate::tracker::measure;

#[test]
fn the_tool_point_is_reported_in_the_tip_frame() {
    // A tip link turned against the last joint (as a FANUC `flange` against `link_6`: 90° about Y, then
    // 30° about Z) and offset 80 mm; a probe 12, −7, 150 mm from the tip's origin in the tip's own axes.
    // Measured with the probe, diagnosed with the tool point unknown: the point reported is the probe's
    // in the tip frame — where a user looks it up — not the last joint's axes.
    let robot = thermokin_io::read_robot(&workspace("configs/irb140.toml")).unwrap();
    let c = robot.chain();
    let turn = UnitQuaternion::from_euler_angles(0.0, 90f64.to_radians(), 30f64.to_radians());
    let tip = FixedRow { translation: Vector3::new(0.0, 0.0, 80.0), rotation: turn, ..FixedRow::identity() };
    let given = c.with_tool(tip.clone()).unwrap();
    let robot = robot.with_chain(given.clone()).unwrap();
    let probe_in_tip = Vector3::new(12.0, -7.0, 150.0);
    let truth =
        given.with_tool(FixedRow { translation: tip.translation + turn * probe_in_tip, ..tip.clone() }).unwrap();
    let data = measure(&truth, 80, 311, <[f64]>::to_vec);
    let config = Config {
        frame: FrameMode::Tracker,
        tool: ToolMode::Unknown,
        validation: Validation::SelectionOnly,
        ..Config::default()
    };
    let report = diagnose(&robot, &data, None, &config).unwrap();
    let [x, y, z] = report.frames.tool_point_mm.unwrap();
    eprintln!(
        "tool point in the tip frame {x:.4}, {y:.4}, {z:.4}; in the joint frame {:?}",
        report.frames.tool_point_joint_frame_mm
    );
    // Noise 0.005 mm per axis over 80 poses: the point is known to a few µm.
    assert!((Vector3::new(x, y, z) - probe_in_tip).norm() < 0.01, "{x}, {y}, {z}");
    let [a, b, c] = report.frames.tool_point_joint_frame_mm.unwrap();
    let expected = tip.translation + turn * probe_in_tip;
    assert!((Vector3::new(a, b, c) - expected).norm() < 0.01, "{a}, {b}, {c}");
}
