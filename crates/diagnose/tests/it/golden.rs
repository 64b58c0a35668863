//! The drift check of the diagnosis's outputs on the real and paper cases: each report's text and the
//! robot its export writes, compared byte for byte with `fixtures/golden/diagnosis/<case>.txt` — our own
//! earlier output, a drift check, never evidence of correctness (the bounds in each case's test are
//! that). A change that moves any figure fails here first; when the change is meant, rerun the cases
//! with `THERMOKIN_BLESS=1` to rewrite the files, and say in the commit what moved and why.

use thermokin_chain::Robot;
use thermokin_diagnose::Report;
use thermokin_testdata::workspace;

/// Compares (or, with `THERMOKIN_BLESS` set, writes) the golden output of `case`: the report's text, then
/// the exported robot (on `robot`, the file's robot, as `diagnose --export` writes it).
pub fn drift_check(case: &str, robot: &Robot, report: &Report) {
    let export = report.export_model(robot, None, case).unwrap();
    let text = format!("{}\n--- exported robot ---\n{}", report.text(), thermokin_io::robot_model_to_toml(&export));
    let path = workspace(&format!("fixtures/golden/diagnosis/{case}.txt"));
    if std::env::var_os("THERMOKIN_BLESS").is_some() {
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(&path, &text).unwrap();
        return;
    }
    let golden = std::fs::read_to_string(&path)
        .unwrap_or_else(|e| panic!("{}: {e} (write it with THERMOKIN_BLESS=1)", path.display()));
    if golden != text {
        let line = golden.lines().zip(text.lines()).position(|(a, b)| a != b).unwrap_or(0);
        panic!(
            "{case}: the diagnosis's output drifted from {} at line {}:\n  golden: {}\n  now:    {}\n(if the change is meant, rerun with THERMOKIN_BLESS=1 and say why in the commit)",
            path.display(),
            line + 1,
            golden.lines().nth(line).unwrap_or("<end>"),
            text.lines().nth(line).unwrap_or("<end>")
        );
    }
}

/// The robot `diagnose --export` writes (on `robot`), read back from its text, reproduces the report's
/// residual of every measurement of `data` (the fit on all of it) to 1e-9 mm — whatever was chosen,
/// compliance included: the export is the model the report scores — a backlash with each pose's direction
/// ([`thermokin_chain::Dataset::approach`]). Position-only data. After a step of the
/// measurement frame the export is in the frame the measurements ended in: the poses after every step.
pub fn export_reproduces_the_residuals(robot: &Robot, report: &Report, data: &thermokin_chain::Dataset) {
    let export = report.export_model(robot, None, "check").unwrap();
    let text = thermokin_io::robot_model_to_toml(&export);
    let read = thermokin_io::parse_robot_model_toml("exported.toml".as_ref(), &text).unwrap();
    let fitted = &report.residuals_after.per_measurement_mm;
    // The fit is on the measurements the screen for gross errors kept.
    let gross: Vec<usize> = report.outliers.iter().map(|o| o.measurement - 1).collect();
    let kept: Vec<_> = data.measurements.iter().enumerate().filter(|(i, _)| !gross.contains(i)).collect();
    assert_eq!(fitted.len(), kept.len());
    // The export is in the frame the measurements ended in: after every step of it the report chose.
    let steps: Vec<&str> =
        report.effects.iter().filter_map(|e| e.label.strip_prefix("frame_step (")?.strip_suffix(')')).collect();
    let latest = |i: usize, m: &thermokin_chain::Measurement| {
        steps.iter().all(|at| match (at.strip_prefix("line "), at.strip_suffix(" min")) {
            (Some(line), _) => data.line_of(i).is_some_and(|l| l >= line.parse::<usize>().unwrap()),
            // The label rounds the time to 0.1 min: a pose that close to it is left out of the check.
            (_, Some(t)) => m.time_min > t.parse::<f64>().unwrap() + 0.05,
            _ => panic!("{at}"),
        })
    };
    let worst = kept
        .into_iter()
        .zip(fitted)
        .filter(|((i, m), _)| latest(*i, m))
        .map(|((i, m), r)| {
            // Each pose in its state: its time, and the direction each joint reached it in (a backlash).
            let approach = data.approach.get(i).cloned().unwrap_or_default();
            let state =
                thermokin_chain::OperatingState { approach, ..thermokin_chain::OperatingState::at_time(m.time_min) };
            let p = read.tool_pose(&m.q, &state).unwrap().translation.vector;
            ((p - m.position_mm).norm() - r).abs()
        })
        .fold(0.0, f64::max);
    eprintln!("the export reproduces the fit's residuals to {worst:.2e} mm");
    assert!(worst < 1e-9, "the export's residuals differ from the report's by up to {worst:.3e} mm");
}
