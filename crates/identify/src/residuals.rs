//! Residual rows `measured − predicted` of a model at a parameter vector, and their Jacobian.

use faer::reborrow::ReborrowMut;
use faer::{Mat, MatMut};
use nalgebra::Matrix6xX;
use thermokin_chain::{Dataset, Robot, rotation_log};

use crate::error::IdentifyError;
use crate::model::Model;
use crate::predict::PoseInputs;
use crate::terms::PoseTerms;

/// The residual rows of `rows` of `data`: per measurement the position (3 rows, mm) and, when
/// [`PoseTerms::lever_mm`] is set, the rotation `lever · log(R_measured · R_predictedᵀ)` (3 rows, mm at
/// the lever).
pub fn residuals(
    robot: &Robot,
    model: &Model,
    theta: &[f64],
    data: &Dataset,
    rows: &[usize],
    terms: &PoseTerms,
) -> Result<Vec<f64>, IdentifyError> {
    evaluate(robot, model, theta, data, rows, terms, None)
}

/// [`residuals`] and the Jacobian of `predicted` (the Gauss–Newton Jacobian of the rotation rows' log is
/// the angular twist, exact at zero residual): one row per residual, one column per parameter.
pub fn residuals_and_jacobian(
    robot: &Robot,
    model: &Model,
    theta: &[f64],
    data: &Dataset,
    rows: &[usize],
    terms: &PoseTerms,
) -> Result<(Vec<f64>, Mat<f64>), IdentifyError> {
    let mut jac = Mat::zeros(rows.len() * terms.stride(), model.len());
    let r = evaluate(robot, model, theta, data, rows, terms, Some(jac.as_mut()))?;
    Ok((r, jac))
}

/// The one loop behind [`residuals`] and [`residuals_and_jacobian`]: `jac` is filled when given.
fn evaluate(
    robot: &Robot,
    model: &Model,
    theta: &[f64],
    data: &Dataset,
    rows: &[usize],
    terms: &PoseTerms,
    mut jac: Option<MatMut<'_, f64>>,
) -> Result<Vec<f64>, IdentifyError> {
    let stride = terms.stride();
    let mut r = Vec::with_capacity(rows.len() * stride);
    let mut block = Matrix6xX::zeros(model.len());
    let mut cache = None;
    let lever = terms.lever_mm.unwrap_or(0.0);
    for (k, &i) in rows.iter().enumerate() {
        let m = &data.measurements[i];
        let inputs = PoseInputs {
            temp_rise: &terms.rise[i],
            sin_cos: Some(&terms.sin_cos[i]),
            line: terms.lines[i],
            latest_frame: terms.latest_frame,
            sensors: data.sensor_values.get(i).map_or(&[], Vec::as_slice),
            approach: data.approach.get(i).map_or(&[], Vec::as_slice),
        };
        let (p, rot) = model.predict(robot, theta, m, &inputs, jac.is_some().then_some(&mut block), &mut cache)?;
        let d = m.position_mm - p;
        r.extend_from_slice(&[d.x, d.y, d.z]);
        if stride == 6 {
            let measured = m.orientation.map(|o| o.to_rotation_matrix().into_inner()).unwrap_or(rot);
            let e = rotation_log(&(measured * rot.transpose())) * lever;
            r.extend_from_slice(&[e.x, e.y, e.z]);
        }
        if let Some(jac) = jac.as_mut() {
            // The pose's rows, column by column: the position rows as predicted, the rotation rows at the lever.
            for (c, column) in block.column_iter().enumerate() {
                let mut rows = jac.rb_mut().col_mut(c).subrows_mut(stride * k, stride);
                for a in 0..stride {
                    rows[a] = if a < 3 { column[a] } else { column[a] * lever };
                }
            }
        }
    }
    Ok(r)
}

/// [`residuals`] (and the Jacobian into `jac` when given: its rows are the residuals') as the fit
/// minimises them: position rows weighted by the tracker's stated standard deviations (weighted least
/// squares), unchanged otherwise.
pub(crate) fn weighted(
    robot: &Robot,
    model: &Model,
    theta: &[f64],
    data: &Dataset,
    rows: &[usize],
    terms: &PoseTerms,
    mut jac: Option<MatMut<'_, f64>>,
) -> Result<Vec<f64>, IdentifyError> {
    let mut r = evaluate(robot, model, theta, data, rows, terms, jac.as_mut().map(|j| j.rb_mut()))?;
    if let Some(weights) = &terms.weights {
        let stride = terms.stride();
        for (k, &i) in rows.iter().enumerate() {
            for a in 0..3 {
                let (row, w) = (stride * k + a, weights[i][a]);
                r[row] *= w;
                if let Some(jac) = jac.as_mut() {
                    for c in 0..jac.ncols() {
                        jac[(row, c)] *= w;
                    }
                }
            }
        }
    }
    Ok(r)
}

/// Per-measurement error norms of residual rows of `stride` rows each.
pub fn norms(r: &[f64], stride: usize) -> Vec<f64> {
    r.chunks(stride).map(|c| c.iter().map(|x| x * x).sum::<f64>().sqrt()).collect()
}

#[cfg(test)]
#[allow(clippy::unwrap_used)] // Tests unwrap to fail.
mod tests {
    use nalgebra::Vector3;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;
    use thermokin_chain::{Dataset, LinkMass, Robot};
    use thermokin_testdata::{gauss, irb140_table9, measured_point};

    use super::{residuals, residuals_and_jacobian};
    use crate::{Effect, JointIndex, Model, PoseTerms, Support};

    /// The analytic Jacobian of `model` at `theta` on every measurement of `data`, checked column by column
    /// against central differences of step `h` of the residuals (which are `measured − predicted`: the
    /// Jacobian is the prediction's, the negative of the residuals'), to 1e-5 of each column's largest entry.
    /// The residuals evaluated beside the Jacobian are those evaluated alone, bit for bit: a fit takes a
    /// trial's residuals from either pass (`fit::damped_step`'s speculation) and must step alike.
    fn jacobian_is_the_differences(
        robot: &Robot,
        model: &Model,
        theta: &[f64],
        data: &Dataset,
        terms: &PoseTerms,
        h: f64,
    ) -> faer::Mat<f64> {
        let rows: Vec<usize> = (0..data.len()).collect();
        let (with_jacobian, jac) = residuals_and_jacobian(robot, model, theta, data, &rows, terms).unwrap();
        let alone = residuals(robot, model, theta, data, &rows, terms).unwrap();
        assert!(
            with_jacobian.iter().zip(&alone).all(|(a, b)| a.to_bits() == b.to_bits()),
            "the residuals beside the Jacobian differ from those alone"
        );
        for k in 0..theta.len() {
            let (mut plus, mut minus) = (theta.to_vec(), theta.to_vec());
            plus[k] += h;
            minus[k] -= h;
            let rp = residuals(robot, model, &plus, data, &rows, terms).unwrap();
            let rm = residuals(robot, model, &minus, data, &rows, terms).unwrap();
            for (r, (p, m)) in rp.iter().zip(&rm).enumerate() {
                let numeric = -(p - m) / (2.0 * h);
                let scale = jac.col(k).norm_max().max(1.0);
                assert!(
                    (jac[(r, k)] - numeric).abs() < 1e-5 * scale,
                    "column {k}, row {r}: {} vs {numeric}",
                    jac[(r, k)]
                );
            }
        }
        jac
    }

    /// Eight poses of the IRB 140 (joints drawn around zero with `seed`, within ±1.5 rad), measured at a
    /// fixed point: where only the Jacobian's shape matters.
    fn eight_poses(seed: u64) -> Dataset {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let measurements = (0..8)
            .map(|_| {
                let q = (0..6).map(|_| gauss(&mut rng).clamp(-1.5, 1.5)).collect();
                measured_point(q, Vector3::new(500.0, 0.0, 600.0), 0.0, &mut rng)
            })
            .collect();
        Dataset { measurements, ..Dataset::default() }
    }

    /// The analytic Jacobian of a measured tilt (`Effect::Tilt`: the mounting yaw and the pivot) against
    /// central differences, at a yaw and pivot away from zero, beside a link deviation of the same row,
    /// on tilts of a few hundredths of a degree that differ pose by pose.
    #[test]
    fn a_measured_tilts_jacobian_is_the_finite_differences() {
        let robot = Robot::new("IRB 140", irb140_table9());
        let mut data = eight_poses(7);
        let mut rng = ChaCha8Rng::seed_from_u64(8);
        data.sensor_names = ["x", "y", "z", "bx", "by", "bz"].map(|c| format!("acc.tilt_{c}")).to_vec();
        data.sensor_values = (0..data.len()).map(|_| (0..6).map(|_| 5e-4 * gauss(&mut rng)).collect()).collect();
        let sensor = crate::SensorId::of(&data, 0).unwrap();
        let joint = JointIndex::of(&robot, 1).unwrap();
        let tilt = Effect::Tilt(joint, sensor, crate::TiltOver::Below);
        let model = Model::new(&robot, vec![Effect::LinkDeviation(joint), tilt]).unwrap();
        let terms = PoseTerms::of(&robot, &data, 0.0);
        let theta = vec![0.1, -0.2, 0.05, 1e-3, -2e-3, 5e-4, 0.3, 120.0, -40.0, 250.0, -0.7];
        let jac = jacobian_is_the_differences(&robot, &model, &theta, &data, &terms, 1e-6);
        // Every column moves the poses: the yaws turn the tilts, the pivot shifts the row.
        for k in 6..11 {
            assert!(jac.col(k).norm_max() > 1e-6, "column {k} is zero");
        }
    }

    /// The analytic Jacobian of a branch's load on a joint (`Effect::BranchLoad`: an arm of two joints
    /// hanging from the IRB 140's second link, its joints logged in degrees pose by pose) against central
    /// differences, beside the joint's own compliance without masses; every weight moves the poses.
    /// The IRB 140 with an arm of two joints hanging from its second link, and eight poses (`seed`) with
    /// the arm's joints logged in degrees pose by pose.
    fn second_arm(seed: u64) -> (Robot, Dataset) {
        let branch = thermokin_chain::Branch {
            name: "second_arm".into(),
            link: 2,
            joints: vec![
                thermokin_chain::Joint::revolute("b1", Vector3::new(0.0, 200.0, 100.0), Vector3::y_axis()),
                thermokin_chain::Joint::revolute("b2", Vector3::new(0.0, 0.0, -300.0), Vector3::x_axis()),
            ],
            masses: Vec::new(),
        };
        let robot = Robot::new("IRB 140", irb140_table9()).with_branches(vec![branch]).unwrap();
        let mut data = eight_poses(seed);
        let mut rng = ChaCha8Rng::seed_from_u64(seed + 1);
        data.sensor_names = vec!["b1".into(), "b2".into()];
        data.sensor_values = (0..data.len()).map(|_| vec![60.0 * gauss(&mut rng), 40.0 * gauss(&mut rng)]).collect();
        data.branch_columns = vec![thermokin_chain::BranchColumns { branch: 0, column: 0, len: 2 }];
        (robot, data)
    }

    #[test]
    fn a_branch_loads_jacobian_is_the_finite_differences() {
        let (robot, data) = second_arm(9);
        let joint = JointIndex::of(&robot, 1).unwrap();
        let at = crate::BranchAt { branch: 0, count: 4, lateral: false, masses: false };
        let load = Effect::BranchLoad(joint, crate::SensorId::of(&data, 0).unwrap(), at);
        let model =
            Model::new(&robot, vec![Effect::named(&robot, "joint_compliance", Some(1)).unwrap(), load]).unwrap();
        let terms = PoseTerms::of(&robot, &data, 0.0);
        let theta: Vec<f64> = (0..model.len()).map(|k| 2e-4 * ((k as f64 * 0.9).cos() + 0.2)).collect();
        let jac = jacobian_is_the_differences(&robot, &model, &theta, &data, &terms, 1e-7);
        for k in model.len() - 4..model.len() {
            assert!(jac.col(k).norm_max() > 1e-3, "column {k} is zero");
        }
    }

    /// The analytic Jacobian of a branch's load across a joint (a bearing tilting under the branch's
    /// moment: `BranchAt::lateral`, the same arm on the IRB 140's first joint, beside the joint's own lateral
    /// compliance without masses) against central differences; every weight moves the poses.
    #[test]
    fn a_lateral_branch_loads_jacobian_is_the_finite_differences() {
        let (robot, data) = second_arm(11);
        let joint = JointIndex::of(&robot, 0).unwrap();
        let count = thermokin_chain::branch_lateral_basis_len(robot.chain(), &robot.branches()[0], 0) as u8;
        assert_eq!(count, 8);
        let at = crate::BranchAt { branch: 0, count, lateral: true, masses: false };
        let load = Effect::BranchLoad(joint, crate::SensorId::of(&data, 0).unwrap(), at);
        let own = Effect::named(&robot, "lateral_compliance", Some(0)).unwrap();
        let model = Model::new(&robot, vec![own, load]).unwrap();
        let terms = PoseTerms::of(&robot, &data, 0.0);
        let theta: Vec<f64> = (0..model.len()).map(|k| 2e-4 * ((k as f64 * 0.9).cos() + 0.2)).collect();
        let jac = jacobian_is_the_differences(&robot, &model, &theta, &data, &terms, 1e-7);
        for k in model.len() - count as usize..model.len() {
            assert!(jac.col(k).norm_max() > 1e-3, "column {k} is zero");
        }
    }

    /// The analytic Jacobians of a branch's load about and across a joint when the branch and the chain
    /// carry masses (`BranchAt::masses`: one compliance under the torque of everything the joint carries,
    /// one per direction across) against central differences; every weight moves the poses.
    #[test]
    fn a_branch_with_masses_loads_jacobian_is_the_finite_differences() {
        let (robot, data) = second_arm(13);
        let mut branch = robot.branches()[0].clone();
        branch.masses = vec![
            Some(thermokin_chain::LinkMass { mass_kg: 5.0, com_mm: Vector3::new(20.0, 0.0, -80.0) }),
            Some(thermokin_chain::LinkMass { mass_kg: 3.0, com_mm: Vector3::new(0.0, 30.0, -150.0) }),
        ];
        // The chain's own links carry masses too: the load is the joint's under everything it carries.
        let link =
            |kg: f64, x: f64| Some(thermokin_chain::LinkMass { mass_kg: kg, com_mm: Vector3::new(x, 10.0, 40.0) });
        let masses = vec![
            link(20.0, 50.0),
            link(12.0, 180.0),
            link(8.0, 60.0),
            link(4.0, 120.0),
            link(2.0, 0.0),
            link(1.0, 30.0),
        ];
        let robot = Robot::new("IRB 140", irb140_table9())
            .with_masses(masses)
            .and_then(|r| r.with_branches(vec![branch]))
            .unwrap();
        let first = crate::SensorId::of(&data, 0).unwrap();
        let about = crate::BranchAt { branch: 0, count: 1, lateral: false, masses: true };
        let across = crate::BranchAt { branch: 0, count: 2, lateral: true, masses: true };
        let effects = vec![
            Effect::BranchLoad(JointIndex::of(&robot, 1).unwrap(), first, about),
            Effect::BranchLoad(JointIndex::of(&robot, 0).unwrap(), first, across),
        ];
        let model = Model::new(&robot, effects).unwrap();
        assert_eq!(model.len(), 3);
        let terms = PoseTerms::of(&robot, &data, 0.0);
        let theta = [2e-4, -3e-4, 1.5e-4];
        let jac = jacobian_is_the_differences(&robot, &model, &theta, &data, &terms, 1e-7);
        for k in 0..3 {
            assert!(jac.col(k).norm_max() > 1e-3, "column {k} is zero");
        }
    }

    /// The analytic Jacobian of the joint-level effects that move with gravity — a compliance and a
    /// compliance coupling of two joints — against central differences of the residuals (which are
    /// `measured − predicted`: the Jacobian is the prediction's, the negative of the residuals').
    #[test]
    fn the_gravity_effects_jacobian_is_the_finite_differences() {
        let chain = irb140_table9();
        let masses = (0..6)
            .map(|j| Some(LinkMass { mass_kg: 10.0 - j as f64, com_mm: Vector3::new(50.0, 20.0 * j as f64, 100.0) }))
            .collect();
        let robot = Robot::new("IRB 140", chain).with_masses(masses).unwrap();
        let data = eight_poses(5);
        let joint = |j| JointIndex::of(&robot, j).unwrap();
        let model =
            Model::new(&robot, vec![Effect::JointCompliance(joint(1)), Effect::ComplianceCoupling(joint(1))]).unwrap();
        let terms = PoseTerms::of(&robot, &data, 0.0);
        // At a non-zero point, so that the coupling's terms interact with the compliance's.
        let theta = vec![2e-5, -1.5e-5];
        // A step of 1e-9 rad/(N·m) moves a joint by ~1e-7 rad at 100 N·m: small against the curvature,
        // large against rounding of ~1e-12 mm.
        jacobian_is_the_differences(&robot, &model, &theta, &data, &terms, 1e-9);
    }

    /// A compliance pair `K = w wᵀ` of joints 2 and 3: its analytic Jacobian against central differences
    /// (at a `w` with both signs, so each column mixes both joints' torques), its residuals those of the
    /// same matrix written as two compliances and their coupling (`k = w²`, `c = w₂ w₃`: another route
    /// through the model), and its export the fit's prediction.
    #[test]
    fn a_compliance_pair_is_its_rank_one_matrix_and_matches_the_differences() {
        let chain = irb140_table9();
        let masses = (0..6)
            .map(|j| Some(LinkMass { mass_kg: 10.0 - j as f64, com_mm: Vector3::new(50.0, 20.0 * j as f64, 100.0) }))
            .collect();
        let robot = Robot::new("IRB 140", chain).with_masses(masses).unwrap();
        let data = eight_poses(6);
        let joint = |j| JointIndex::of(&robot, j).unwrap();
        let terms = PoseTerms::of(&robot, &data, 0.0);
        let rows: Vec<usize> = (0..data.len()).collect();
        let pair = Model::new(&robot, vec![Effect::CompliancePair(joint(1))]).unwrap();
        assert_eq!(pair.len(), 2);
        let w = vec![4e-3, -3e-3];
        jacobian_is_the_differences(&robot, &pair, &w, &data, &terms, 1e-7);
        let matrix = Model::new(
            &robot,
            vec![
                Effect::JointCompliance(joint(1)),
                Effect::JointCompliance(joint(2)),
                Effect::ComplianceCoupling(joint(1)),
            ],
        )
        .unwrap();
        let k = vec![w[0] * w[0], w[1] * w[1], w[0] * w[1]];
        let (a, b) = (
            residuals(&robot, &pair, &w, &data, &rows, &terms).unwrap(),
            residuals(&robot, &matrix, &k, &data, &rows, &terms).unwrap(),
        );
        let moved = residuals(&robot, &pair, &[0.0, 0.0], &data, &rows, &terms).unwrap();
        assert!(a.iter().zip(&moved).any(|(x, y)| (x - y).abs() > 1e-3), "the pair moves the tool");
        for (i, (x, y)) in a.iter().zip(&b).enumerate() {
            assert!((x - y).abs() < 1e-9, "row {i}: {x} against {y}");
        }
        let exported = pair.robot_model(&robot, &w, &data).unwrap();
        for (i, m) in data.measurements.iter().enumerate() {
            let pose = exported.tool_pose(&m.q, &thermokin_chain::OperatingState::default()).unwrap();
            let predicted = m.position_mm - Vector3::new(a[3 * i], a[3 * i + 1], a[3 * i + 2]);
            assert!((pose.translation.vector - predicted).norm() < 1e-9, "pose {i}");
        }
    }

    /// A gravity compliance known without masses on joints 2 and 3 of an IRB 140 whose file carries no
    /// masses: the analytic Jacobian against central differences, and the exported robot's forward model
    /// against the fit's prediction at every measurement.
    #[test]
    fn a_compliance_without_masses_matches_the_differences_and_its_export() {
        let robot = Robot::new("IRB 140", irb140_table9());
        let data = eight_poses(8);
        let joint = |j| JointIndex::of(&robot, j).unwrap();
        let effects = vec![
            Effect::named(&robot, "joint_compliance", Some(1)).unwrap(),
            Effect::named(&robot, "joint_compliance", Some(2)).unwrap(),
        ];
        assert_eq!(effects, vec![Effect::LumpedCompliance(joint(1), 10), Effect::LumpedCompliance(joint(2), 8)]);
        let model = Model::new(&robot, effects).unwrap();
        let rows: Vec<usize> = (0..data.len()).collect();
        let terms = PoseTerms::of(&robot, &data, 0.0);
        let theta: Vec<f64> = (0..model.len()).map(|k| 1e-4 * ((k as f64 * 0.7).sin() + 0.3)).collect();
        jacobian_is_the_differences(&robot, &model, &theta, &data, &terms, 1e-7);
        // The export evaluates the same law by another route (the robot model's joint values, then its
        // chain's forward kinematics): the same points to 1e-9 mm.
        let exported = model.robot_model(&robot, &theta, &data).unwrap();
        assert!(exported.gravity_loads()[1].len() == 10 && exported.gravity_loads()[2].len() == 8);
        let r = residuals(&robot, &model, &theta, &data, &rows, &terms).unwrap();
        for (i, m) in data.measurements.iter().enumerate() {
            let pose = exported.tool_pose(&m.q, &thermokin_chain::OperatingState::default()).unwrap();
            let predicted = m.position_mm - Vector3::new(r[3 * i], r[3 * i + 1], r[3 * i + 2]);
            assert!((pose.translation.vector - predicted).norm() < 1e-9, "pose {i}");
        }
        // And the law moves the tool: a milli-radian of load weight is not nothing.
        let plain = Robot::new("IRB 140", irb140_table9())
            .chain()
            .tool_pose(&data.measurements[0].q)
            .unwrap()
            .translation
            .vector;
        let moved = exported.tool_pose(&data.measurements[0].q, &Default::default()).unwrap().translation.vector;
        assert!((moved - plain).norm() > 1e-3);
    }

    /// Table 9's IRB 140 on a vertical lift of 800 mm stroke (its first joint).
    fn lifted_irb140_chain() -> thermokin_chain::Chain {
        let arm = irb140_table9();
        let lift = thermokin_chain::Joint::prismatic("lift", Vector3::new(0.0, 0.0, 300.0), Vector3::z_axis())
            .with_limits(0.0, 800.0);
        let joints: Vec<_> = std::iter::once(lift).chain(arm.joints().iter().cloned()).collect();
        thermokin_chain::Chain::new(arm.base().clone(), joints, arm.tool().clone()).unwrap()
    }

    /// `data` with the lift's extension `from + step · k` (mm) before pose `k`'s joints.
    fn lifted(mut data: Dataset, from: f64, step: f64) -> Dataset {
        for (k, m) in data.measurements.iter_mut().enumerate() {
            m.q.insert(0, from + step * k as f64);
        }
        data
    }

    /// For a model whose rows bend with the configuration: its analytic Jacobian at `theta` against
    /// central differences, and its exported robot's forward model against the fit's prediction at every
    /// pose (1e-9 mm); the largest distance the export moves the tool from the plain robot's.
    fn bends_as_fitted(robot: &Robot, model: &Model, theta: &[f64], data: &Dataset, terms: &PoseTerms) -> f64 {
        jacobian_is_the_differences(robot, model, theta, data, terms, 1e-7);
        let exported = model.robot_model(robot, theta, data).unwrap();
        assert!(exported.bends());
        let rows: Vec<usize> = (0..data.len()).collect();
        let r = residuals(robot, model, theta, data, &rows, terms).unwrap();
        let (plain, mut moved) = (robot.chain(), 0.0f64);
        for (i, m) in data.measurements.iter().enumerate() {
            let pose = exported.tool_pose(&m.q, &thermokin_chain::OperatingState::default()).unwrap();
            let predicted = m.position_mm - Vector3::new(r[3 * i], r[3 * i + 1], r[3 * i + 2]);
            assert!((pose.translation.vector - predicted).norm() < 1e-9, "pose {i}");
            moved = moved.max((pose.translation.vector - plain.tool_pose(&m.q).unwrap().translation.vector).norm());
        }
        moved
    }

    /// Lateral compliances of an IRB 140 on a vertical lift, with masses: the lift's six terms (its foot's
    /// tilt and shift, its bending with the extension) and the shoulder's two — the analytic Jacobian
    /// against central differences, and the exported robot's forward model against the fit's prediction.
    #[test]
    fn a_lateral_compliance_matches_the_differences_and_its_export() {
        let chain = lifted_irb140_chain();
        let masses = (0..7)
            .map(|j| Some(LinkMass { mass_kg: 12.0 - j as f64, com_mm: Vector3::new(80.0, 15.0 * j as f64, 60.0) }))
            .collect();
        let robot = Robot::new("lifted IRB 140", chain).with_masses(masses).unwrap();
        let data = lifted(eight_poses(9), 0.0, 100.0);
        let effects = vec![
            Effect::named(&robot, "lateral_compliance", Some(0)).unwrap(),
            Effect::named(&robot, "lateral_compliance", Some(2)).unwrap(),
        ];
        let joint = |j| JointIndex::of(&robot, j).unwrap();
        assert_eq!(effects, vec![Effect::LateralCompliance(joint(0), 6), Effect::LateralCompliance(joint(2), 2)]);
        let model = Model::new(&robot, effects).unwrap();
        let terms = PoseTerms::of(&robot, &data, 0.0);
        // Tilts of ~1e-4 rad at a few hundred N·m; the bending term per mm, the shift in mm per N·m.
        let theta = vec![3e-7, -2e-7, 4e-10, 1e-10, 2e-4, -3e-4, 5e-7, 2e-7];
        let moved = bends_as_fitted(&robot, &model, &theta, &data, &terms);
        // And it moves the tool: by a tenth of a millimetre or more somewhere.
        assert!(moved > 0.1, "{moved}");
    }

    /// Lateral compliances of a lifted IRB 140 whose file has no masses (their loads lumped): the
    /// column's (tilting, bending, shifting), the shoulder's and the elbow's — the analytic Jacobian
    /// against central differences, and the exported robot's forward model against the fit's prediction.
    #[test]
    fn a_lumped_lateral_compliance_matches_the_differences_and_its_export() {
        let chain = lifted_irb140_chain();
        let robot = Robot::new("lifted IRB 140", chain);
        let data = lifted(eight_poses(13), 0.0, 100.0);
        let effects = vec![
            Effect::named(&robot, "lateral_compliance", Some(0)).unwrap(),
            Effect::named(&robot, "lateral_compliance", Some(2)).unwrap(),
            Effect::named(&robot, "lateral_compliance", Some(3)).unwrap(),
        ];
        let joint = |j| JointIndex::of(&robot, j).unwrap();
        // Per direction: 3 for the joint's own link, 2 per revolute joint beyond; a column's three sets.
        assert_eq!(
            effects,
            vec![
                Effect::LumpedLateralCompliance(joint(0), 90, Support::Column),
                Effect::LumpedLateralCompliance(joint(2), 22, Support::Bearing),
                Effect::LumpedLateralCompliance(joint(3), 18, Support::Bearing)
            ]
        );
        let model = Model::new(&robot, effects).unwrap();
        let terms = PoseTerms::of(&robot, &data, 0.0);
        // Weights of 1e-3 rad (the column's 1e-5 rad, its bend 1e-8 rad/mm, its shift 0.01 mm): tilts of a
        // few 1e-4 rad.
        let theta: Vec<f64> = (0..model.len())
            .map(|k| {
                let size = match k {
                    0..30 => 1e-5,
                    30..60 => 1e-8,
                    60..90 => 0.01,
                    _ => 1e-3,
                };
                size * ((k as f64 * 0.7).sin())
            })
            .collect();
        let moved = bends_as_fitted(&robot, &model, &theta, &data, &terms);
        assert!(moved > 0.1, "{moved}");
    }

    /// A slide's straightness (an IRB 140 on a vertical lift): the analytic Jacobian against central
    /// differences, and the exported robot's forward model against the fit's prediction.
    #[test]
    fn a_slides_straightness_matches_the_differences_and_its_export() {
        let chain = lifted_irb140_chain();
        let robot = Robot::new("lifted IRB 140", chain);
        let data = lifted(eight_poses(11), 20.0, 90.0);
        let effects = vec![Effect::named(&robot, "straightness", Some(0)).unwrap()];
        assert_eq!(effects, vec![Effect::Straightness(JointIndex::of(&robot, 0).unwrap())]);
        assert!(Effect::named(&robot, "straightness", Some(2)).is_err(), "a revolute joint has no guide");
        let model = Model::new(&robot, effects).unwrap();
        let terms = PoseTerms::of(&robot, &data, 0.0);
        // Turns of ~1e-4 rad over the stroke, a bow of ~0.1 mm.
        let theta = vec![2e-7, -1.5e-7, 1e-7, 3e-7, -2e-7];
        let moved = bends_as_fitted(&robot, &model, &theta, &data, &terms);
        assert!(moved > 0.1, "{moved}");
    }

    /// Steps of the measurement frame at minutes 50 and 75 of a session, beside a link deviation and the
    /// registration: the analytic Jacobian of every column — the steps' own and those they turn, the
    /// first step's turned by the second — against central differences, position and orientation rows
    /// alike, on poses before, between and after the steps.
    #[test]
    fn the_frame_steps_jacobian_is_the_finite_differences() {
        let robot = Robot::new("IRB 140", irb140_table9());
        let mut rng = ChaCha8Rng::seed_from_u64(8);
        let measurements = (0..10)
            .map(|k| {
                let q = (0..6).map(|_| gauss(&mut rng).clamp(-1.5, 1.5)).collect();
                let mut m = measured_point(q, Vector3::new(500.0, 0.0, 600.0), 0.0, &mut rng);
                m.time_min = 10.0 * k as f64;
                m.orientation = Some(nalgebra::UnitQuaternion::identity());
                m
            })
            .collect();
        let mut data = Dataset { measurements, ..Dataset::default() };
        let joint = |j| JointIndex::of(&robot, j).unwrap();
        let step = Effect::FrameStep(crate::StepAt::time(50.0));
        let second = Effect::FrameStep(crate::StepAt::time(75.0));
        let model =
            Model::new(&robot, vec![Effect::Registration, Effect::LinkDeviation(joint(2)), step, second]).unwrap();
        let theta: Vec<f64> = (0..model.len()).map(|k| 0.01 * ((k as f64 * 1.7).sin())).collect();
        // Measured orientations as predicted at `theta`: the rotation rows' Gauss–Newton Jacobian (the
        // angular twist) is the derivative of their log at zero residual.
        for m in &mut data.measurements {
            let zeros = [0.0; 6];
            let (_, rot) =
                model.predict(&robot, &theta, m, &crate::PoseInputs::plain(&zeros), None, &mut None).unwrap();
            m.orientation = Some(nalgebra::UnitQuaternion::from_matrix(&rot));
        }
        let terms = PoseTerms::of(&robot, &data, 100.0);
        assert_eq!(terms.stride(), 6);
        let jac = jacobian_is_the_differences(&robot, &model, &theta, &data, &terms, 1e-6);
        // Before the step the step moves nothing.
        let o = model.offsets()[2];
        for c in o..o + 6 {
            assert!((0..5 * 6).all(|r| jac[(r, c)] == 0.0), "column {c} moves a pose before the step");
        }
    }
}
