//! Real laser-tracker data (Rokae robot B, 30 poses, tracker frame, unknown tool, nominal modified DH),
//! and the paper's static case against the authors' coordinates.

use nalgebra::Vector3;
use thermokin_chain::{Dataset, Measurement, Robot};
use thermokin_chain::{DhConvention, DhRow, DhTable};
use thermokin_diagnose::{Config, diagnose};
use thermokin_identify::{FrameMode, ToolMode};
use thermokin_testdata::{authors, rokae_robot_b};

/// Rows of numbers of a small comma-separated file with one header line.
fn numbers(path: &std::path::Path) -> Vec<Vec<f64>> {
    std::fs::read_to_string(path)
        .unwrap()
        .lines()
        .skip(1)
        .filter(|l| !l.trim().is_empty())
        .map(|l| l.split(',').map(|c| c.trim().parse::<f64>().unwrap()).collect())
        .collect()
}

pub fn rokae() -> (Robot, Dataset) {
    let mdh = rokae_robot_b("nominal-mdh.csv");
    let joints = rokae_robot_b("joints-deg.csv");
    let poses = rokae_robot_b("tracker-poses.csv");
    let rows = numbers(&mdh)
        .iter()
        .enumerate()
        .map(|(i, r)| DhRow::revolute(format!("J{}", i + 1), r[1], r[0].to_radians(), r[2], r[3].to_radians()))
        .collect();
    let table = DhTable {
        convention: DhConvention::Modified,
        rows,
        base: nalgebra::Isometry3::identity(),
        tool: nalgebra::Isometry3::identity(),
    };
    let chain = table.to_extended().unwrap();
    let q = numbers(&joints);
    let p = numbers(&poses);
    assert_eq!(q.len(), p.len());
    let measurements = q
        .iter()
        .zip(&p)
        .map(|(q, p)| Measurement {
            time_min: 0.0,
            q: q.iter().map(|d| d.to_radians()).collect(),
            position_mm: Vector3::new(p[0], p[1], p[2]),
            orientation: None,
            position_std_mm: None,
            temps: Vec::new(),
        })
        .collect();
    (Robot::new("Rokae robot B", chain), Dataset { measurements, ..Dataset::default() })
}

#[test]
fn rokae_robot_b_additive_table() {
    let (base, data) = rokae();
    assert_eq!(data.len(), 30);
    let config = Config { frame: FrameMode::Tracker, tool: ToolMode::Unknown, ..Config::default() };
    let report = diagnose(&base, &data, None, &config).unwrap();
    crate::golden::drift_check("rokae-positions", &base, &report);
    for row in &report.additive {
        eprintln!(
            "{:<40} mean {:.4}  rms {:.4}  max {:.4}",
            row.model, row.stats.heldout_mean_mm, row.stats.heldout_rms_mm, row.stats.heldout_max_mm
        );
    }
    for row in &report.leave_one_out {
        eprintln!("{:<40} rms {:.4}", row.model, row.stats.heldout_rms_mm);
    }
    eprintln!("observability: {:?}", report.identifiability.observability);
    // The honest figure beside the optimistic one: the whole selection rerun on each outer training
    // fold (24 poses), its choice scored on the 6 poses it never saw.
    let nested = report.nested.as_ref().unwrap();
    eprintln!(
        "nested held-out mean: nominal {:.4} → selected {:.4} mm (selection's own CV: {:.4}); choices {:?}",
        nested.nominal.heldout_mean_mm,
        nested.selected.heldout_mean_mm,
        report.additive.last().unwrap().stats.heldout_mean_mm,
        nested.selections
    );
    assert_eq!(nested.nominal.heldout_count, 30, "every pose is tested once");
    // The always-estimated blocks are reported: where the tracker saw the base, and the probe.
    eprintln!("registration {:?}; tool point {:?} mm", report.frames.registration, report.frames.tool_point_mm);
    assert!(report.frames.registration.is_some() && report.frames.tool_point_mm.is_some());
    // With an unknown probe and positions only, the wrist row's rotations and translations trade against
    // each other and the probe: the report must name that trade — as a nearly unidentifiable pair of
    // the final model, or as the wrist row refused before selection (its translation runs away along the
    // probe, tens of millimetres, when fitted beside it).
    for r in &report.identifiability.not_identifiable {
        eprintln!("not identifiable: {} — {}", r.effect, r.reason);
    }
    let wrist_refused = report
        .identifiability
        .not_identifiable
        .iter()
        .any(|r| r.effect == "link_deviation[6]" && r.reason.contains("plausible"));
    assert!(
        !report.identifiability.correlated.is_empty() || wrist_refused,
        "no nearly unidentifiable combination named"
    );
    for c in &report.identifiability.correlated {
        eprintln!("nearly unidentifiable: {} ~ {} ({:+.4})", c.a, c.b, c.correlation);
        assert!(c.correlation.abs() > thermokin_identify::NEARLY_DEPENDENT);
    }
    assert!(nested.selected.heldout_mean_mm < nested.nominal.heldout_mean_mm);
    // The independent fit, 5-fold held-out: 2.22 mm nominal (registration and tool fitted) → 0.22 mm with
    // joint offsets → 0.125 mm with full geometry. Those are mean errors: our nominal held-out mean is
    // 2.223 mm (RMS 2.392). Ours must match or beat the end point.
    let nominal = report.nominal.heldout_mean_mm;
    let last = report.additive.last().unwrap().stats.heldout_mean_mm;
    assert!((nominal - 2.22).abs() < 0.05, "nominal held-out mean {nominal:.3} mm");
    assert!(last <= 0.125, "final held-out mean {last:.4} mm");
    // A 5× reduction at least, with the arm's kinematics as the cause: its geometry (offsets, link
    // deviations) or its joint transmission (a gear ratio, a cyclic encoder error) — nothing about frames,
    // load or time, which this static, unloaded set cannot show.
    assert!(nominal / last > 5.0);
    for e in &report.effects {
        eprintln!("{}: {:?}", e.label, e.parameters);
    }
    assert!(
        report
            .effects
            .iter()
            .all(|e| matches!(e.effect.as_str(), "joint_offset" | "link_deviation" | "joint_scale" | "periodic")),
        "{:?}",
        report.effects.iter().map(|e| &e.label).collect::<Vec<_>>()
    );
}

#[test]
fn paper_static_case_gap() {
    // Our model with the authors' deviation table (applied as their CoppeliaSim script did) leaves
    // 0.45 mm RMS against their coordinates (0.26 mm per coordinate). What explains it?
    let path = authors("results-static-case-study.csv");
    let robot = thermokin_io::read_robot(&thermokin_testdata::workspace("configs/irb140.toml")).unwrap();
    let table = thermokin_io::read_deviation_table(&thermokin_testdata::workspace(
        "fixtures/paper/deformations-case-study.toml",
    ))
    .unwrap();
    let semantics = thermokin_deform::TableSemantics::CoppeliaSim(thermokin_deform::CoppeliaSimEdits::at(vec![0.0; 6]));
    let chain = table.apply(robot.chain(), &semantics).unwrap();
    let data = thermokin_io::read_measurements(&path, &[thermokin_chain::JointKind::Revolute; 6]).unwrap();
    assert_eq!(data.len(), 50);
    let deformed = robot.with_chain(chain).unwrap();
    let report = diagnose(&deformed, &data, None, &Config::default()).unwrap();
    crate::golden::drift_check("paper-static", &deformed, &report);
    for row in &report.additive {
        eprintln!(
            "{:<40} mean {:.4}  rms {:.4}  max {:.4}",
            row.model, row.stats.heldout_mean_mm, row.stats.heldout_rms_mm, row.stats.heldout_max_mm
        );
    }
    let before = report.nominal.heldout_rms_mm;
    let after = report.additive.last().unwrap().stats.heldout_rms_mm;
    assert!((before - 0.4517).abs() < 1e-3, "{before}");
    // A translation of the wrist (joint 6's row) explains nearly all of it: every target has the same
    // tool orientation, so a constant offset there is what a wrist shift looks like.
    assert_eq!(report.effects[0].label, "link_deviation[6]");
    assert!(report.additive[1].stats.heldout_rms_mm < 0.01, "{:?}", report.additive[1]);
    assert!(after < 0.005, "{after}");
}

#[test]
fn a_holdout_file_in_another_tracker_frame_is_refitted_not_misread() {
    // Rokae robot B: 20 poses to diagnose, the other 10 as a hold-out file moved into another tracker
    // frame (metres away, turned 70°): the registration and the probe are refitted on it, the effects
    // kept — instead of reporting the frame change as thousands of millimetres of error.
    let (robot, data) = rokae();
    let train = data.subset(&(0..20).collect::<Vec<_>>());
    let mut holdout = data.subset(&(20..30).collect::<Vec<_>>());
    let other_from_tracker =
        nalgebra::Isometry3::new(Vector3::new(-2400.0, 1300.0, 250.0), Vector3::new(0.1, -0.05, 1.2));
    for m in &mut holdout.measurements {
        m.position_mm = (other_from_tracker * nalgebra::Point3::from(m.position_mm)).coords;
    }
    let config = Config {
        frame: FrameMode::Tracker,
        tool: ToolMode::Unknown,
        validation: thermokin_diagnose::Validation::SelectionOnly,
        ..Config::default()
    };
    let report = diagnose(&robot, &train, Some(&holdout), &config).unwrap();
    let h = report.holdout.unwrap();
    eprintln!(
        "hold-out in another frame: nominal {:.4} → selected {:.4} mm (mean), refitted {:?}; selection CV {:.4} mm",
        h.nominal.heldout_mean_mm,
        h.selected.heldout_mean_mm,
        h.refitted,
        report.additive.last().unwrap().stats.heldout_mean_mm
    );
    assert_eq!(h.refitted, vec!["registration".to_string(), "tool_point".to_string()]);
    assert!(h.nominal.heldout_mean_mm > 1.0 && h.nominal.heldout_mean_mm < 10.0, "{}", h.nominal.heldout_mean_mm);
    assert!(h.selected.heldout_mean_mm < 0.5 * h.nominal.heldout_mean_mm, "{}", h.selected.heldout_mean_mm);
}

#[test]
fn rokae_robot_b_orientations_are_roll_pitch_yaw_and_fit() {
    // The tracker file's rx, ry, rz read in two conventions: only one is consistent with a rigid probe on
    // the robot. Read as X-Y-Z Euler angles, no model comes near (tens of millimetres at the 100 mm
    // lever: a wrong convention, not an error of the robot); read as roll, pitch, yaw (R = Rz·Ry·Rx), the
    // nominal 6-D error is the position error's size and the effects bring it down as they do positions.
    use thermokin_io::{MeasurementFormat, Orientation, read_measurements_joined};
    let (robot, positions) = rokae();
    let kinds = vec![thermokin_chain::JointKind::Revolute; 6];
    let read = |orientation| {
        let f = MeasurementFormat { orientation, ..MeasurementFormat::default() };
        read_measurements_joined(&rokae_robot_b("joints-deg.csv"), &rokae_robot_b("tracker-poses.csv"), None, &kinds, f)
            .unwrap()
    };
    let config = Config { frame: FrameMode::Tracker, tool: ToolMode::Unknown, ..Config::default() };
    let nested = |data: &Dataset| diagnose(&robot, data, None, &config).unwrap().nested.unwrap();
    let rpy_report = diagnose(&robot, &read(Orientation::Rpy), None, &config).unwrap();
    crate::golden::drift_check("rokae-6d-rpy", &robot, &rpy_report);
    let (xyz, rpy, pos) = (nested(&read(Orientation::XyzEuler)), rpy_report.nested.unwrap(), nested(&positions));
    eprintln!(
        "nested RMS nominal → selected: positions {:.4} → {:.4}; 6-D xyz {:.4} → {:.4}; 6-D rpy {:.4} → {:.4} mm",
        pos.nominal.heldout_rms_mm,
        pos.selected.heldout_rms_mm,
        xyz.nominal.heldout_rms_mm,
        xyz.selected.heldout_rms_mm,
        rpy.nominal.heldout_rms_mm,
        rpy.selected.heldout_rms_mm
    );
    assert!(xyz.nominal.heldout_rms_mm > 20.0 && xyz.selected.heldout_rms_mm > 20.0);
    assert!(rpy.nominal.heldout_rms_mm < 1.2 * pos.nominal.heldout_rms_mm);
    // Measured: 2.6545 → 0.1452 mm (positions alone 2.4887 → 0.1222): the orientations add ~0.08 mm at
    // the lever, ~0.045° — what is left of them after the effects.
    assert!(rpy.selected.heldout_rms_mm < 0.2, "{}", rpy.selected.heldout_rms_mm);
}
