//! Compensation on a calibrated robot (`compensate_model`): the authors' table with one profile as drift
//! rows gives today's runs exactly; a robot with joint corrections, compliance and per-row drift laws is
//! put on its targets, checked by a forward model written here by hand.

use nalgebra::{Point3, Vector3};
use thermokin_chain::{Chain, ErrorParams, LinkMass, OperatingState, Target};
use thermokin_compensate::{
    Cycle, RunSettings, compensate_model, compensate_model_cycle, compensate_static, compensate_transient,
};
use thermokin_deform::{
    AfterStabilization, DriftLaw, DriftRow, JointCorrection, RobotModel, Row, TableSemantics, TimeProfile,
};
use thermokin_ik::Status;
use thermokin_testdata::error_mm_deg;

use crate::case_studies::{program, robot, table};

/// The case-study settings under the canonical reading (a robot file's drift is canonical).
fn settings() -> RunSettings {
    crate::case_studies::settings(TableSemantics::Canonical)
}

/// Largest joint difference between two runs' rows, radians.
fn gap(a: &thermokin_compensate::RunOutput, b: &thermokin_compensate::RunOutput) -> f64 {
    assert_eq!(a.rows.len(), b.rows.len());
    a.rows
        .iter()
        .zip(&b.rows)
        .flat_map(|(x, y)| {
            assert_eq!((x.label.as_str(), x.time_min, x.status), (y.label.as_str(), y.time_min, y.status));
            x.joints.iter().zip(&y.joints).map(|(p, q)| (p - q).abs())
        })
        .fold(0.0, f64::max)
}

#[test]
fn the_case_study_table_as_drift_rows_gives_todays_runs() {
    let r = robot();
    // Static: the full table, every target.
    let model = RobotModel::new(r.clone()).with_table(&table(), &TimeProfile::Static).unwrap();
    let today = compensate_static(r.chain(), &table(), &program(), &settings()).unwrap();
    let as_rows = compensate_model(&model, &program(), &OperatingState::default(), &settings()).unwrap();
    let g = gap(&today, &as_rows);
    assert!(g <= 1e-9, "{g:e} rad");
    assert!((today.summary.max_uncompensated_error_mm - as_rows.summary.max_uncompensated_error_mm).abs() <= 1e-9);
    // Transient: the authors' growth (linear, no plateau), 200 minutes every minute, under the canonical
    // reading (the CoppeliaSim reading is a property of their scene, not of a robot file).
    let profile = TimeProfile::Linear { stabilization_min: 180.0, after: AfterStabilization::KeepGrowing };
    let model = RobotModel::new(r.clone()).with_table(&table(), &profile).unwrap();
    let cycle = Cycle { duration_min: 200.0, step_min: 10.0 };
    let today = compensate_transient(r.chain(), &table(), &profile, cycle, &program(), &settings(), |_, _| {}).unwrap();
    let as_rows =
        compensate_model_cycle(&model, cycle, &program(), &OperatingState::default(), &settings(), |_, _| {}).unwrap();
    let g = gap(&today, &as_rows);
    assert!(g <= 1e-9, "{g:e} rad");
}

/// Gravity torques about every joint, N·m, from the link masses (gravity along the base's −Z), computed
/// here from the chain's joint frames.
fn torques(chain: &Chain, masses: &[Option<LinkMass>], q: &[f64]) -> Vec<f64> {
    let frames = chain.joint_frames(q).unwrap();
    (0..6)
        .map(|j| {
            let axis = frames[j].rotation * chain.joints()[j].axis.into_inner();
            let origin = frames[j].translation.vector;
            let moment: Vector3<f64> = (j..6)
                .filter_map(|l| masses[l].map(|m| (m.mass_kg, (frames[l] * Point3::from(m.com_mm)).coords)))
                .map(|(m, c)| (c - origin).cross(&Vector3::new(0.0, 0.0, -9.80665 * m)))
                .sum();
            axis.dot(&moment) / 1000.0
        })
        .collect()
}

#[test]
fn commanded_joints_put_a_calibrated_robot_on_its_targets_in_their_states() {
    let r = robot();
    let mut joints = vec![JointCorrection::NONE; 6];
    joints[0].scale = 4e-4;
    joints[2].cyclic_rad = [0.03f64.to_radians(), -0.01f64.to_radians(), 0.0, 0.008f64.to_radians()];
    joints[1].compliance_rad_per_nm = 0.002f64.to_radians();
    let row2 = error_mm_deg([0.2, -0.1, 0.3, 0.01, 0.02, 0.005]);
    let row3 = error_mm_deg([0.05, 0.02, -0.04, 0.004, 0.0, 0.003]);
    let drift = vec![
        DriftRow {
            row: Row::Joint(1),
            deviation: row2,
            law: DriftLaw::Time(TimeProfile::Exponential { tau_min: 40.0 }),
        },
        DriftRow {
            row: Row::Joint(2),
            deviation: row3,
            law: DriftLaw::PerKelvin { sensors: vec![("temp_j3".into(), 21.5)] },
        },
    ];
    let model = RobotModel::new(r.clone()).with_joint_corrections(joints).unwrap().with_drift(drift).unwrap();
    // Each target at its own time and joint-3 temperature.
    let program: Vec<Target> = program()
        .into_iter()
        .enumerate()
        .map(|(k, t)| {
            let state = OperatingState {
                time_min: Some(4.0 * k as f64),
                temperatures_c: vec![("temp_j3".into(), 21.5 + 0.1 * k as f64)],
                ..OperatingState::default()
            };
            t.in_state(state)
        })
        .collect();
    let run = compensate_model(&model, &program, &OperatingState::default(), &settings()).unwrap();
    assert_eq!(run.summary.failures, 0, "{:?}", run.summary.failed);
    for (row, target) in run.rows.iter().zip(&program) {
        assert_eq!(row.status, Status::Converged);
        // By hand: the rows in force, the joint values the robot takes for the commanded ones.
        let t = target.state.time_min.unwrap();
        let rise = target.state.temperatures_c[0].1 - 21.5;
        let mut rows = vec![ErrorParams::ZERO; 6];
        rows[1] = row2.scaled(1.0 - (-t / 40.0).exp());
        rows[2] = row3.scaled(rise);
        let warm = r.chain().with_errors(ErrorParams::ZERO, &rows, ErrorParams::ZERO).unwrap();
        let c = &row.joints;
        let tau = torques(r.chain(), r.masses(), c);
        let mut q = c.clone();
        q[0] += 4e-4 * c[0];
        q[2] += 0.03f64.to_radians() * c[2].sin() - 0.01f64.to_radians() * c[2].cos()
            + 0.008f64.to_radians() * (2.0 * c[2]).cos();
        q[1] += 0.002f64.to_radians() * tau[1];
        let reached = warm.tool_pose(&q).unwrap();
        let dp = (reached.translation.vector - target.pose.translation.vector).norm();
        let dr = reached.rotation.angle_to(&target.pose.rotation).to_degrees();
        // The IK's tolerance is 1e-9 mm; the hand model repeats the library's arithmetic in another order.
        assert!(dp <= 1e-6 && dr <= 1e-6, "{}: {dp:e} mm, {dr:e}°", row.label);
    }
    // The corrections matter: commanding the cold robot's IK would miss by a tenth of a millimetre or more.
    assert!(run.summary.max_uncompensated_error_mm > 0.1, "{}", run.summary.max_uncompensated_error_mm);
}

#[test]
fn a_target_in_a_state_the_robot_cannot_evaluate_is_named() {
    let r = robot();
    let drift = vec![DriftRow {
        row: Row::Joint(1),
        deviation: error_mm_deg([0.2, 0.0, 0.0, 0.0, 0.0, 0.0]),
        law: DriftLaw::Time(TimeProfile::Exponential { tau_min: 40.0 }),
    }];
    let model = RobotModel::new(r).with_drift(drift).unwrap();
    let e = compensate_model(&model, &program(), &OperatingState::default(), &settings()).unwrap_err().to_string();
    assert!(e.contains("target P1") && e.contains("operating time") && e.contains("joint 2"), "{e}");
}

/// A robot whose shoulder bearing tilts under the arm's moment (a lateral compliance of joint 2, beside its
/// gravity compliance): every target of the program is reached — the chain in force follows the
/// configuration, so the solve is repeated on it — checked by a forward model written here: the moment
/// across joint 2 summed from the link frames and masses, turned into its parent's frame, tilting its row.
#[test]
fn a_robot_whose_rows_tilt_with_its_configuration_is_put_on_its_targets() {
    let r = robot();
    let mut joints = vec![JointCorrection::NONE; 6];
    joints[1].compliance_rad_per_nm = 0.001f64.to_radians();
    let c = [4e-4f64.to_radians(), -3e-4f64.to_radians()];
    joints[1].lateral = [c[0], c[1], 0.0, 0.0, 0.0, 0.0];
    let model = RobotModel::new(r.clone()).with_joint_corrections(joints).unwrap();
    assert!(model.bends());
    let run = compensate_model(&model, &program(), &OperatingState::default(), &settings()).unwrap();
    assert_eq!(run.summary.failures, 0, "{:?}", run.summary.failed);
    let directions = thermokin_chain::lateral_directions(r.chain(), 1).unwrap();
    let mut largest_tilt = 0.0f64;
    for (row, target) in run.rows.iter().zip(program()) {
        assert_eq!(row.status, Status::Converged);
        let commanded = &row.joints;
        let frames = r.chain().joint_frames(commanded).unwrap();
        let origin = frames[1].translation.vector;
        let moment: Vector3<f64> = (1..6)
            .filter_map(|l| r.masses()[l].map(|m| (m.mass_kg, (frames[l] * Point3::from(m.com_mm)).coords)))
            .map(|(m, p)| (p - origin).cross(&Vector3::new(0.0, 0.0, -9.80665 * m)) / 1000.0)
            .sum();
        let local = frames[0].rotation.inverse() * moment;
        let tilt =
            directions[0] * (c[0] * directions[0].dot(&local)) + directions[1] * (c[1] * directions[1].dot(&local));
        largest_tilt = largest_tilt.max(tilt.norm());
        let mut rows = vec![ErrorParams::ZERO; 6];
        rows[1] = ErrorParams::new(Vector3::zeros(), tilt);
        let tilted = r.chain().with_errors(ErrorParams::ZERO, &rows, ErrorParams::ZERO).unwrap();
        let mut q = commanded.clone();
        q[1] += 0.001f64.to_radians() * torques(r.chain(), r.masses(), commanded)[1];
        let reached = tilted.tool_pose(&q).unwrap();
        let dp = (reached.translation.vector - target.pose.translation.vector).norm();
        let dr = reached.rotation.angle_to(&target.pose.rotation).to_degrees();
        assert!(dp <= 1e-6 && dr <= 1e-6, "{}: {dp:e} mm, {dr:e}°", row.label);
    }
    // The tilt is not nothing: 1e-4 rad is a tenth of a millimetre at the tool.
    assert!(largest_tilt > 1e-4, "{largest_tilt:e}");
    assert!(run.summary.max_uncompensated_error_mm > 0.1, "{}", run.summary.max_uncompensated_error_mm);
}

/// A robot with play in joints 2 and 3 (a backlash: each sits its half play toward the side it last
/// moved to): the program is compensated in the order it runs, from the settings' start, and every target
/// is reached — checked here by the chain alone at the commanded values moved by ±b, the side taken in
/// this test from the commanded values of the target before.
#[test]
fn a_robot_with_backlash_is_put_on_its_targets_in_the_order_it_moves() {
    let r = robot();
    let half = [0.0, 0.02f64.to_radians(), -0.015f64.to_radians(), 0.0, 0.0, 0.0];
    let mut joints = vec![JointCorrection::NONE; 6];
    for (c, &b) in joints.iter_mut().zip(&half) {
        c.backlash = b;
    }
    let model = RobotModel::new(r.clone()).with_joint_corrections(joints).unwrap();
    let settings = settings();
    let run = compensate_model(&model, &program(), &OperatingState::default(), &settings).unwrap();
    assert_eq!(run.summary.failures, 0, "{:?}", run.summary.failed);
    let mut before = settings.start.clone();
    let mut side = [0.0f64; 6];
    for (row, target) in run.rows.iter().zip(program()) {
        assert_eq!(row.status, Status::Converged);
        let mut q = row.joints.clone();
        for j in 0..6 {
            let moved = row.joints[j] - before[j];
            if moved != 0.0 {
                side[j] = moved.signum();
            }
            q[j] += side[j] * half[j];
        }
        before.clone_from(&row.joints);
        let reached = r.chain().tool_pose(&q).unwrap();
        let dp = (reached.translation.vector - target.pose.translation.vector).norm();
        let dr = reached.rotation.angle_to(&target.pose.rotation).to_degrees();
        assert!(dp <= 1e-6 && dr <= 1e-6, "{}: {dp:e} mm, {dr:e}°", row.label);
    }
    // Not nothing: the play moves the uncompensated tool by more than a tenth of a millimetre.
    assert!(run.summary.max_uncompensated_error_mm > 0.1, "{}", run.summary.max_uncompensated_error_mm);
}
