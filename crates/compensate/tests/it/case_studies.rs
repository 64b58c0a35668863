//! Static (50 targets) and transient (200 minutes × 50 targets) runs on the bundled IRB 140 with the
//! case-study table (Tables 10–12), under both table semantics; per-target failure records; exports.

use nalgebra::Isometry3;
use thermokin_chain::Robot;
use thermokin_chain::Target;
use thermokin_compensate::{
    AbbTargets, Controller, Cycle, ProgramSettings, RunSettings, compensate_static, compensate_transient, confdata,
    programs, write_results_csv,
};
use thermokin_deform::{AfterStabilization, CoppeliaSimEdits, DeviationTable, TableSemantics, TimeProfile};
use thermokin_ik::{Params, Status};
use thermokin_io::{read_deviation_table, read_paper_results, read_robot, read_targets};
use thermokin_testdata::workspace;

pub(crate) fn robot() -> Robot {
    read_robot(&workspace("configs/irb140.toml")).unwrap()
}

pub(crate) fn program() -> Vec<Target> {
    read_targets(&workspace("fixtures/paper/table12-targets.csv")).unwrap()
}

pub(crate) fn table() -> DeviationTable {
    read_deviation_table(&workspace("fixtures/paper/deformations-case-study.toml")).unwrap()
}

pub(crate) fn settings(semantics: TableSemantics) -> RunSettings {
    RunSettings {
        semantics,
        accumulation: Default::default(),
        ik: Params::default(),
        start: [0.0, 20.0, 20.0, 0.0, -45.0, 0.0].map(f64::to_radians).to_vec(),
    }
}

fn coppelia() -> TableSemantics {
    TableSemantics::CoppeliaSim(CoppeliaSimEdits::at(vec![0.0; 6]))
}

/// A row's joints in degrees (the IRB 140's joints are all revolute).
fn joints_deg(r: &thermokin_compensate::TargetResult) -> Vec<f64> {
    r.joints.iter().map(|v| v.to_degrees()).collect()
}

/// Independent check of one row: FK of the reported joints on the deformed chain against the target.
fn check_rows(deformed_at: impl Fn(f64) -> thermokin_chain::Chain, run: &thermokin_compensate::RunOutput) {
    for r in &run.rows {
        assert_eq!(r.status, Status::Converged, "{} at {} min", r.label, r.time_min);
        let reached = deformed_at(r.time_min).tool_pose(&r.joints).unwrap();
        let dp = (reached.translation.vector - r.programmed.translation.vector).norm();
        let dr = reached.rotation.angle_to(&r.programmed.rotation).to_degrees();
        // Issue bound: 1e-6 mm and 1e-6° (published: up to 0.0099 mm / 0.02° static, 0.199 mm / 0.07°
        // transient). The written joints' round trip is checked by the writer tests.
        assert!(dp <= 1e-6 && dr <= 1e-6, "{} at {} min: {dp:.3e} mm {dr:.3e}°", r.label, r.time_min);
    }
}

#[test]
fn static_case_reaches_all_50_targets() {
    let r = robot();
    for semantics in [coppelia(), TableSemantics::Canonical] {
        let run = compensate_static(r.chain(), &table(), &program(), &settings(semantics.clone())).unwrap();
        assert_eq!(run.rows.len(), 50);
        assert_eq!(run.summary.failures, 0);
        let deformed = table().apply(r.chain(), &semantics).unwrap();
        check_rows(|_| deformed.clone(), &run);
        // The uncompensated program misses by tens of millimetres ("even 20 mm", results section).
        assert!(run.summary.max_uncompensated_error_mm > 10.0, "{}", run.summary.max_uncompensated_error_mm);
    }
}

#[test]
fn transient_case_reaches_all_10050_targets() {
    let r = robot();
    let profile = TimeProfile::Linear { stabilization_min: 180.0, after: AfterStabilization::KeepGrowing };
    let run =
        compensate_transient(r.chain(), &table(), &profile, Cycle::PAPER, &program(), &settings(coppelia()), |_, _| {})
            .unwrap();
    assert_eq!(run.rows.len(), 10_050);
    assert_eq!(run.summary.failures, 0);
    let t = table();
    check_rows(|time| profile.table_at(&t, time).unwrap().apply(r.chain(), &coppelia()).unwrap(), &run);
    // Minute 0 is the nominal robot: compensation changes nothing there.
    assert!(run.rows.iter().filter(|r| r.time_min == 0.0).all(|r| r.uncompensated_error_mm < 1e-6));
}

#[test]
fn unreachable_targets_are_records_and_the_run_goes_on() {
    let r = robot();
    let mut prog = program();
    prog.truncate(5);
    prog.insert(2, Target::new("FAR", Isometry3::translation(3000.0, 0.0, 0.0)));
    let run = compensate_static(r.chain(), &table(), &prog, &settings(TableSemantics::Canonical)).unwrap();
    assert_eq!(run.rows.len(), 6);
    assert_eq!(run.summary.failures, 1);
    assert_eq!(run.rows[2].status, Status::Unreachable);
    assert!(run.rows.iter().enumerate().all(|(i, row)| i == 2 || row.status == Status::Converged));
    // The RAPID module never moves to a failed target.
    let rapid = programs(&run, r.chain(), &ProgramSettings::new(Controller::Abb)).unwrap().remove(0).text;
    assert!(rapid.contains("! jt_FAR: not reached (Unreachable)"));
    assert!(!rapid.contains("MoveAbsJ jt_FAR"));
    assert_eq!(rapid.matches("MoveAbsJ").count(), 5);
}

#[test]
fn results_csv_reads_back_in_the_authors_layout() {
    let r = robot();
    let run = compensate_static(r.chain(), &table(), &program(), &settings(coppelia())).unwrap();
    let dir = std::env::temp_dir().join(format!("thermokin-comp-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("static.csv");
    let mut buf = Vec::new();
    write_results_csv(&mut buf, &run, false).unwrap();
    std::fs::write(&path, &buf).unwrap();
    // Our writer's layout is the authors': their reader takes it.
    let back = read_paper_results(&path).unwrap();
    assert_eq!(back.len(), 50);
    for (b, row) in back.iter().zip(&run.rows) {
        assert_eq!(b.label, row.label);
        let ours = joints_deg(row);
        let theirs: Vec<f64> = b.joints.iter().map(|v| v.to_degrees()).collect();
        // Written at 1e-12° (the writer's joint precision): half of that, plus a few ulps of the value.
        assert!(
            theirs.iter().zip(&ours).all(|(x, y)| (x - y).abs() <= 5e-13 + 8.0 * f64::EPSILON * y.abs()),
            "{}: {:?} vs {:?}",
            b.label,
            theirs,
            ours
        );
        assert!((b.reached_mm - row.reached.translation.vector).norm() < 1e-9);
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn rapid_module_is_well_formed() {
    let r = robot();
    let mut prog = program();
    prog.truncate(3);
    let run = compensate_static(r.chain(), &table(), &prog, &settings(coppelia())).unwrap();
    let m = programs(&run, r.chain(), &ProgramSettings::new(Controller::Abb)).unwrap().remove(0).text;
    assert!(m.starts_with("MODULE thermokin_compensated\n"));
    assert!(m.trim_end().ends_with("ENDMODULE"));
    let line = m.lines().find(|l| l.contains("CONST jointtarget jt_P1:=")).unwrap();
    assert!(line.ends_with(",[9E9,9E9,9E9,9E9,9E9,9E9]];"), "{line}");
    assert!(m.contains("    MoveAbsJ jt_P1\\NoEOffs, v100, fine, tool0;"));
}

/// The numbers between `open` and `close` on a line, split on commas (the last word of each cell, past
/// KUKA's `A1 ` names).
fn numbers_between(line: &str, open: &str, close: &str) -> Vec<f64> {
    let start = line.find(open).unwrap() + open.len();
    let end = start + line[start..].find(close).unwrap();
    line[start..end].split(',').map(|cell| cell.split_whitespace().last().unwrap().parse::<f64>().unwrap()).collect()
}

/// Reads each program back with a parser of its own syntax and compares with the run's joints.
#[test]
fn programs_for_abb_kuka_and_ur_parse_back_to_the_same_joints() {
    let r = robot();
    let mut prog = program();
    prog.truncate(10);
    prog.insert(4, Target::new("FAR", Isometry3::translation(3000.0, 0.0, 0.0)));
    let run = compensate_static(r.chain(), &table(), &prog, &settings(coppelia())).unwrap();
    let reached: Vec<Vec<f64>> = run.rows.iter().filter(|r| r.status == Status::Converged).map(joints_deg).collect();
    assert_eq!(reached.len(), 10);
    let parsed = |controller: Controller, settings: ProgramSettings| -> Vec<Vec<f64>> {
        let text = programs(&run, r.chain(), &settings).unwrap().remove(0).text;
        match controller {
            Controller::Abb => text
                .lines()
                .filter(|l| l.contains("CONST jointtarget"))
                .map(|l| numbers_between(l, ":=[[", "]"))
                .collect(),
            Controller::Kuka => {
                assert!(text.starts_with("DEF ") && text.trim_end().ends_with("END"));
                text.lines()
                    .filter(|l| l.starts_with("PTP {E6AXIS:"))
                    .map(|l| numbers_between(l, "E6AXIS:", "}"))
                    .collect()
            }
            Controller::UniversalRobots => {
                assert!(text.starts_with("def ") && text.trim_end().ends_with("end"));
                text.lines()
                    .filter(|l| l.trim_start().starts_with("movej("))
                    .map(|l| numbers_between(l, "movej([", "]").into_iter().map(f64::to_degrees).collect())
                    .collect()
            }
            _ => unreachable!(),
        }
    };
    for controller in [Controller::Abb, Controller::Kuka, Controller::UniversalRobots] {
        let mut settings = ProgramSettings::new(controller);
        settings.zone = if controller == Controller::UniversalRobots { "0.002".into() } else { "z5".into() };
        let back = parsed(controller, settings.clone());
        assert_eq!(back.len(), 10, "{controller:?}: the failed target must not be a motion");
        for (b, q) in back.iter().zip(&reached) {
            // Six decimals of degrees (nine of radians for UR): 1e-6° after the round trip.
            assert!(b.iter().zip(q.iter()).all(|(x, y)| (x - y).abs() <= 1e-6), "{controller:?}: {b:?} vs {q:?}");
        }
        let text = programs(&run, r.chain(), &settings).unwrap().remove(0).text;
        assert!(text.contains("FAR"), "{controller:?}: the failed target is named in a comment");
        assert!(text.contains(&settings.zone), "{controller:?}: zone flag honoured");
    }
}

#[test]
fn a_transient_run_gives_one_program_per_time_step() {
    let r = robot();
    let mut prog = program();
    prog.truncate(4);
    let profile = TimeProfile::Linear { stabilization_min: 180.0, after: AfterStabilization::KeepGrowing };
    let cycle = Cycle { duration_min: 3.0, step_min: 1.0 };
    let run =
        compensate_transient(r.chain(), &table(), &profile, cycle, &prog, &settings(coppelia()), |_, _| {}).unwrap();
    let out = programs(&run, r.chain(), &ProgramSettings::new(Controller::Kuka)).unwrap();
    let suffixes: Vec<&str> = out.iter().map(|p| p.suffix.as_str()).collect();
    assert_eq!(suffixes, ["_t0", "_t1", "_t2", "_t3"]);
    assert!(out.iter().all(|p| p.text.matches("PTP {E6AXIS").count() == 4));
}

/// ABB robtargets: FK of the compensated joints on the nominal robot, with confdata. Read back and solved
/// by an IK on the nominal robot (what the controller does) from 300 seeded random seeds, every solution
/// whose configuration data match the written ones is the compensated joint vector: the robtarget and its
/// confdata pin exactly the joints that were compensated.
#[test]
fn abb_robtargets_pin_the_compensated_joints() {
    use rand::{Rng, SeedableRng};
    let r = robot();
    let mut prog = program();
    prog.truncate(8);
    let run = compensate_static(r.chain(), &table(), &prog, &settings(coppelia())).unwrap();
    let mut s = ProgramSettings::new(Controller::Abb);
    s.abb_targets = AbbTargets::Robtarget;
    let text = programs(&run, r.chain(), &s).unwrap().remove(0).text;
    assert!(text.contains("ConfJ \\On;") && text.contains("MoveJ p_P1, v100, fine, tool0;"));
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(140);
    let mut ws = thermokin_ik::Workspace::new(6);
    for (line, row) in text.lines().filter(|l| l.contains("CONST robtarget")).zip(&run.rows) {
        let pos = numbers_between(line, ":=[[", "]");
        let quat = numbers_between(line, "],[", "]");
        let conf_start = line.find("],[").unwrap() + 3;
        let conf: Vec<i64> = numbers_between(&line[conf_start..], "],[", "]").iter().map(|&v| v as i64).collect();
        let rotation =
            nalgebra::UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(quat[0], quat[1], quat[2], quat[3]));
        let goal = Isometry3::from_parts(nalgebra::Translation3::new(pos[0], pos[1], pos[2]), rotation);
        let mut matched = 0;
        for k in 0..300 {
            let seed: Vec<f64> = r
                .chain()
                .joints()
                .iter()
                .map(|j| j.limits.map_or(0.0, |l| rng.random_range(l.lower..l.upper)))
                .collect();
            let params = thermokin_ik::Params { restarts: 0, ..thermokin_ik::Params::default() };
            let sol =
                thermokin_ik::solve(r.chain(), &thermokin_ik::Goal::Pose(goal), &seed, &params, &mut ws, k).unwrap();
            if !sol.converged() || confdata(r.chain(), &sol.q).to_vec() != conf {
                continue;
            }
            matched += 1;
            let deg: Vec<f64> = sol.q.iter().map(|v| v.to_degrees()).collect();
            // The robtarget is written to 1e-6 mm and 1e-9 in the quaternion: joints agree to 1e-5°.
            assert!(
                deg.iter().zip(joints_deg(row)).all(|(a, b)| (a - b).abs() < 1e-5),
                "{}: {deg:?} vs {:?}",
                row.label,
                joints_deg(row)
            );
        }
        assert!(matched > 0, "{}: no IK solution with the written confdata {conf:?}", row.label);
    }
}

/// How far two runs' deformed states are apart, row by row: the largest difference of the uncompensated
/// program's error (mm; nominal joints on the deformed robot) and of the compensated joints (degrees).
fn state_gap(a: &thermokin_compensate::RunOutput, b: &thermokin_compensate::RunOutput) -> (f64, f64) {
    let mut gap: (f64, f64) = (0.0, 0.0);
    for (x, y) in a.rows.iter().zip(&b.rows) {
        assert_eq!((x.time_min, &x.label), (y.time_min, &y.label));
        gap.0 = gap.0.max((x.uncompensated_error_mm - y.uncompensated_error_mm).abs());
        for (p, q) in x.joints.iter().zip(&y.joints) {
            gap.1 = gap.1.max((p - q).abs().to_degrees());
        }
    }
    gap
}

#[test]
fn increments_equal_the_share_from_nominal_unless_euler_angles_are_read_back_at_a_lock() {
    let r = robot();
    let prog: Vec<Target> = program().into_iter().take(5).collect();
    let profile = TimeProfile::Linear { stabilization_min: 180.0, after: AfterStabilization::KeepGrowing };
    let cycle = Cycle { duration_min: 40.0, step_min: 1.0 };
    let run = |table: &DeviationTable, semantics: TableSemantics, accumulation| {
        let s = RunSettings { accumulation, ..settings(semantics) };
        compensate_transient(r.chain(), table, &profile, cycle, &prog, &s, |_, _| {}).unwrap()
    };
    use thermokin_compensate::Accumulation::{FromNominal, Increments};
    // Canonical: error parameters add, so 40 increments of table/180 are the table × 40/180.
    let gap = state_gap(
        &run(&table(), TableSemantics::Canonical, FromNominal),
        &run(&table(), TableSemantics::Canonical, Increments),
    );
    assert!(gap.0 < 1e-9 && gap.1 < 1e-9, "{gap:?}");
    // CoppeliaSim edits with shifts only: world shifts at home add up as well.
    let mut shifts = table();
    for row in &mut shifts.joints {
        row.rotation = nalgebra::Vector3::zeros();
    }
    let gap = state_gap(&run(&shifts, coppelia(), FromNominal), &run(&shifts, coppelia(), Increments));
    assert!(gap.0 < 1e-9 && gap.1 < 1e-9, "{gap:?}");
    // The case-study table under CoppeliaSim edits: joint 4's object sits at the gimbal lock at home, the
    // read-back drops part of each small increment, and the path shows — by tenths of a millimetre
    // within 40 minutes (the full 200-minute file: docs/paper-reproduction.md).
    let gap = state_gap(&run(&table(), coppelia(), FromNominal), &run(&table(), coppelia(), Increments));
    eprintln!("increments vs from-nominal, CoppeliaSim edits, 40 minutes: {gap:?} (mm, °)");
    assert!(gap.0 > 0.1, "{gap:?}");
    // Every row is still solved: the increments change the state, not the solver.
    assert_eq!(run(&table(), coppelia(), Increments).summary.failures, 0);
}
