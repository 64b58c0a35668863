//! 6-D measurements (a probe that reports its orientation): a tool rotation — invisible to positions —
//! and a gear-ratio error hidden at once, measured by the independent tracker of `tracker.rs` (the
//! robot built on the chain, the probe's pose composed with nalgebra, not the diagnosis's model).

use nalgebra::{Isometry3, Translation3, UnitQuaternion};
use thermokin_chain::Robot;
use thermokin_diagnose::{Config, diagnose};
use thermokin_testdata::workspace;

use crate::tracker::{NOISE_MM, ORIENTATION_NOISE_DEG, measure, measure_6d};

fn robot() -> Robot {
    thermokin_io::read_robot(&workspace("configs/irb140.toml")).unwrap()
}

/// The probe as mounted: 0.2, −0.1, 0.3 mm off the tool point and turned (0.3°, −0.2°, 0.4°).
fn tool_from_probe() -> Isometry3<f64> {
    Isometry3::from_parts(
        Translation3::new(0.2, -0.1, 0.3),
        UnitQuaternion::from_euler_angles(0.3f64.to_radians(), -0.2f64.to_radians(), 0.4f64.to_radians()),
    )
}

/// Joint 2 turns 0.05 % more than commanded.
fn actual(q: &[f64]) -> Vec<f64> {
    let mut a = q.to_vec();
    a[1] *= 1.0 + 5e-4;
    a
}

#[test]
fn a_tool_rotation_and_a_gear_ratio_at_once_from_6d_poses() {
    let robot = robot();
    let data = measure_6d(robot.chain(), 200, 61, actual, tool_from_probe());
    let config = Config::default();
    let report = diagnose(&robot, &data, None, &config).unwrap();
    let lever = report.orientation_lever_mm.expect("orientations fitted");
    let labels: Vec<&str> = report.effects.iter().map(|e| e.label.as_str()).collect();
    let nested = report.nested.as_ref().unwrap();
    eprintln!(
        "found {labels:?}; nested held-out RMS {:.4} → {:.4} mm (lever {lever} mm); choices {:?}",
        nested.nominal.heldout_rms_mm, nested.selected.heldout_rms_mm, nested.selections
    );
    assert!(labels.contains(&"tool_frame") && labels.contains(&"joint_scale[2]"), "{labels:?}");
    // The noise floor of the combined error: 3 axes of position noise and 3 of orientation noise at the
    // lever. A model at the noise lands within 1.5× of it (the RMS of ~200 samples scatters by ~5 %).
    let noise_rms = (3.0 * NOISE_MM.powi(2) + 3.0 * (lever * ORIENTATION_NOISE_DEG.to_radians()).powi(2)).sqrt();
    assert!(nested.nominal.heldout_rms_mm > 10.0 * noise_rms, "the hidden effects must matter");
    assert!(
        nested.selected.heldout_rms_mm <= 1.5 * noise_rms,
        "{} mm vs noise {noise_rms}",
        nested.selected.heldout_rms_mm
    );
    // The identified tool (the tool_frame block of the model the report scores, fitted jointly with the
    // gear ratio) against the probe as mounted, compared as poses (no convention shared): at
    // configurations with joint 2 at zero, where the gear-ratio error is nil.
    let tool = report.effects.iter().find(|e| e.label == "tool_frame").unwrap();
    let p = |n: &str| tool.parameters[&format!("tool_frame.{n}")].value;
    let tool_error =
        thermokin_testdata::error_mm_deg([p("dx_mm"), p("dy_mm"), p("dz_mm"), p("rx_deg"), p("ry_deg"), p("rz_deg")]);
    let chain = robot.chain();
    let zeros: Vec<f64> = chain.joints().iter().map(|j| j.zero).collect();
    let errors: Vec<_> = chain.joints().iter().map(|j| j.error).collect();
    let identified_chain = chain.with_errors_and_zeros(chain.base().error, &errors, tool_error, &zeros).unwrap();
    // The identified robot carries the gear ratio it scored (joint 2's scale, as hidden).
    assert!(report.identified.joint_corrections()[1].scale != 0.0);
    for k in 0..20 {
        let t = k as f64 * 0.3;
        let q = [t.sin(), 0.0, 0.3 * t.cos(), -t, 0.5 + 0.2 * t.sin(), t];
        let truth = robot.chain().tool_pose(&q).unwrap() * tool_from_probe();
        let identified = identified_chain.tool_pose(&q).unwrap();
        let dp = (identified.translation.vector - truth.translation.vector).norm();
        let dr = identified.rotation.angle_to(&truth.rotation).to_degrees();
        // Estimation error ≈ noise / √poses (0.005 mm, 0.002° over 200 poses: ~4e-4 mm, ~1.5e-4°); the
        // bounds are the single-measurement noise, ten times that.
        assert!(dp < NOISE_MM && dr < ORIENTATION_NOISE_DEG, "pose {k}: {dp:.5} mm, {dr:.5}°");
    }
}

#[test]
fn positions_alone_cannot_see_a_tool_rotation_and_say_so() {
    let robot = robot();
    // The same probe, positions only: its offset is seen, its rotation is not.
    let data = measure(robot.chain(), 200, 62, |q| q.to_vec());
    let data = thermokin_chain::Dataset {
        measurements: data
            .measurements
            .into_iter()
            .map(|mut m| {
                let pose = robot.chain().tool_pose(&m.q).unwrap() * tool_from_probe();
                let noise = m.position_mm - robot.chain().tool_pose(&m.q).unwrap().translation.vector;
                m.position_mm = pose.translation.vector + noise;
                m
            })
            .collect(),
        temperature_names: Vec::new(),
        source_lines: Vec::new(),
        ..Default::default()
    };
    let report = diagnose(&robot, &data, None, &Config::default()).unwrap();
    assert!(report.orientation_lever_mm.is_none());
    let labels: Vec<&str> = report.effects.iter().map(|e| e.label.as_str()).collect();
    assert_eq!(labels, ["tool_frame"]);
    let fixed: Vec<(&str, &str)> =
        report.identifiability.fixed.iter().map(|f| (f.parameter.as_str(), f.reason.as_str())).collect();
    eprintln!("fixed: {fixed:?}");
    for axis in ["rx_deg", "ry_deg", "rz_deg"] {
        let name = format!("tool_frame.{axis}");
        assert!(
            fixed.iter().any(|(p, r)| *p == name && r.contains("measured orientations")),
            "{name} not fixed with its reason: {fixed:?}"
        );
    }
}

#[test]
fn orientations_round_trip_through_the_measurement_file() {
    let robot = robot();
    let data = measure_6d(robot.chain(), 20, 63, |q| q.to_vec(), tool_from_probe());
    let kinds: Vec<_> = robot.chain().joints().iter().map(|j| j.kind).collect();
    let mut text = Vec::new();
    thermokin_io::write_measurements(&mut text, &data, &kinds).unwrap();
    let text = String::from_utf8(text).unwrap();
    assert!(text.lines().next().unwrap().contains(",rx,ry,rz"), "{text}");
    let back = thermokin_io::parse_measurements(std::path::Path::new("m.csv"), &text, &kinds).unwrap();
    for (a, b) in data.measurements.iter().zip(&back.measurements) {
        let angle = a.orientation.unwrap().angle_to(&b.orientation.unwrap());
        assert!(angle < 1e-12, "{angle} rad");
    }
    // A file with only some of the three angle columns is refused, naming what is missing.
    let err = thermokin_io::parse_measurements(
        std::path::Path::new("m.csv"),
        "q1,q2,q3,q4,q5,q6,x,y,z,rx,ry\n0,0,0,0,0,0,1,2,3,0,0\n",
        &kinds,
    )
    .unwrap_err()
    .to_string();
    assert!(err.contains("rz") && err.contains("m.csv"), "{err}");
}

#[test]
fn an_unknown_6d_probe_in_a_tracker_frame_is_a_nuisance_not_a_cause() {
    use thermokin_identify::{FrameMode, ToolMode};
    let robot = robot();
    // Joint 3's zero off by 0.04°; the probe as mounted; the tracker 2 m away and turned.
    let offset = |q: &[f64]| {
        let mut a = q.to_vec();
        a[2] += 0.04f64.to_radians();
        a
    };
    let tracker_from_base =
        Isometry3::new(nalgebra::Vector3::new(2000.0, -500.0, 300.0), nalgebra::Vector3::new(0.01, -0.02, 1.2));
    let mut data = measure_6d(robot.chain(), 200, 64, offset, tool_from_probe());
    for m in &mut data.measurements {
        m.position_mm = (tracker_from_base * nalgebra::Point3::from(m.position_mm)).coords;
        m.orientation = m.orientation.map(|o| tracker_from_base.rotation * o);
    }
    let config = Config { frame: FrameMode::Tracker, tool: ToolMode::Unknown, ..Config::default() };
    let report = diagnose(&robot, &data, None, &config).unwrap();
    let labels: Vec<&str> = report.effects.iter().map(|e| e.label.as_str()).collect();
    let nested = report.nested.as_ref().unwrap();
    eprintln!(
        "found {labels:?}; nested {:.4} → {:.4} mm; probe {:?} mm, {:?}°",
        nested.nominal.heldout_rms_mm,
        nested.selected.heldout_rms_mm,
        report.frames.tool_point_mm,
        report.frames.tool_rotation_deg
    );
    assert_eq!(labels, ["joint_offset[3]"]);
    let lever = report.orientation_lever_mm.unwrap();
    let noise_rms = (3.0 * NOISE_MM.powi(2) + 3.0 * (lever * ORIENTATION_NOISE_DEG.to_radians()).powi(2)).sqrt();
    assert!(nested.selected.heldout_rms_mm <= 1.5 * noise_rms, "{} mm", nested.selected.heldout_rms_mm);
    // The probe as identified — the calibrated robot's tool row — against the row as mounted, compared as
    // poses (the report's angles are the row's error angles, in the flange's same-orientation frame).
    let identified = report.calibrated.tool().pose();
    let mounted = robot.chain().tool().pose() * tool_from_probe();
    let angle = identified.rotation.angle_to(&mounted.rotation).to_degrees();
    let dp = (identified.translation.vector - mounted.translation.vector).norm();
    assert!(angle < ORIENTATION_NOISE_DEG && dp < NOISE_MM, "probe off by {dp} mm, {angle}°");
}
