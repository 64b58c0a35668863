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
    let h = report.holdout.as_ref().unwrap();
    let labels: Vec<&str> = report.effects.iter().chain(&report.completed).map(|e| e.label.as_str()).collect();
    eprintln!(
        "WAM random: same frame {:.4} → {:.4}, refitted {:.4} → {:.4} mm mean; {labels:?}",
        h.same_frame.nominal.heldout_mean_mm,
        h.same_frame.selected.heldout_mean_mm,
        h.nominal.heldout_mean_mm,
        h.selected.heldout_mean_mm
    );
    for r in &report.identifiability.not_identifiable {
        eprintln!("refused: {} — {}", r.effect, r.reason);
    }
    // The nominal model scored as the data's README scores it, both protocols: the independent 4.046
    // (training registration and tool kept) and 3.573 (refitted on the 20 test poses).
    assert!((h.same_frame.nominal.heldout_mean_mm - 4.046).abs() < 0.01, "{}", h.same_frame.nominal.heldout_mean_mm);
    assert!((h.nominal.heldout_mean_mm - 3.573).abs() < 0.01, "{}", h.nominal.heldout_mean_mm);
    // At or below the independent DH + gravity compliance fit in both protocols (issue #36: 2.741 same
    // frame, 2.361 refitted; the diagnosis before the issue: 3.779 and 3.535; with the geometry and the
    // determined compliances completed: 2.928 and 2.533; with the compliance coupling of joints 5 and 6 —
    // the WAM's wrist differential — that the selection now finds: 2.671 and 2.255; with the pair's own
    // compliances beside it, its compliance matrix positive semidefinite: 2.688 and 2.292).
    assert!(h.same_frame.selected.heldout_mean_mm <= 2.741, "same frame {:.4}", h.same_frame.selected.heldout_mean_mm);
    assert!(h.selected.heldout_mean_mm <= 2.361, "refitted {:.4}", h.selected.heldout_mean_mm);
    assert!(labels.contains(&"compliance_coupling[5]"), "{labels:?}");
    // A cable-driven arm's real wrist millimetres are not refused as implausible (the absolute 5 mm bound
    // refused link_deviation[5] at 9 mm with advice about masses and units), and every row is in the model.
    assert!(
        report.identifiability.not_identifiable.iter().all(|r| !r.reason.contains("beyond the plausible")),
        "{:?}",
        report.identifiability.not_identifiable
    );
    // A cable-driven arm sags under its own weight: the completion carries the compliances the data
    // determine (three standard errors from zero), and none that rises under its load.
    assert!(labels.iter().any(|l| l.starts_with("joint_compliance[")), "{labels:?}");
    for j in 1..=7 {
        assert!(labels.contains(&format!("link_deviation[{j}]").as_str()), "{labels:?}");
    }
    // Joint 1 carries no gravity torque: its compliance is refused as such, not as a 0/0 span.
    let c1 = report.identifiability.not_identifiable.iter().find(|r| r.effect == "joint_compliance[1]").unwrap();
    assert!(c1.reason.contains("gravity never loads joint 1"), "{}", c1.reason);
    assert!(report.identifiability.not_identifiable.iter().all(|r| !r.reason.contains("±0.0 N·m")));
    crate::golden::export_reproduces_the_residuals(&robot, &report, &grid);
    crate::golden::drift_check("wam-grid-holdout-random", &robot, &report);
}
