//! Deformed chains against hand calculations (eq. 18–20) and the published tables.

use nalgebra::{Isometry3, Matrix4, Rotation3, Vector3};
use thermokin_chain::{Chain, ErrorGrouping, ErrorParams, FixedRow, Joint};
use thermokin_deform::{CoppeliaSimEdits, DeviationTable, TableSemantics};

fn two_joints() -> Chain {
    let joints = vec![
        Joint::revolute("j1", Vector3::new(0.0, 0.0, 100.0), Vector3::z_axis()),
        Joint::revolute("j2", Vector3::new(50.0, 0.0, 200.0), Vector3::y_axis()),
    ];
    Chain::new(FixedRow::identity(), joints, FixedRow::from_isometry(&Isometry3::translation(0.0, 0.0, 100.0))).unwrap()
}

#[test]
fn two_joint_case_by_hand() {
    // Joint 1 displaced by (1, 2, 3) mm and turned Δθz = 90°; q = (0, 90°).
    // By hand: row 1 ends at (1, 2, 103) turned Rz(90°); the segment (50, 0, 200) runs along the turned
    // axes to (1, 52, 303); joint 2 turns 90° about its Y (world −X); the 100 mm tool along its local Z
    // now points along world +Y: TCP (1, 152, 303).
    let chain = two_joints();
    let table = DeviationTable::from_joint_rows(vec![
        thermokin_testdata::error_mm_deg([1.0, 2.0, 3.0, 0.0, 0.0, 90.0]),
        ErrorParams::ZERO,
    ]);
    let deformed = table.apply(&chain, &TableSemantics::Canonical).unwrap();
    let p = deformed.tool_pose(&[0.0, 90f64.to_radians()]).unwrap().translation.vector;
    assert!((p - Vector3::new(1.0, 152.0, 303.0)).norm() < 1e-12, "{p:?}");
    // The nominal chain is untouched.
    assert!(chain.joints().iter().all(|j| j.error.is_zero()));
    let nominal = chain.tool_pose(&[0.0, 90f64.to_radians()]).unwrap().translation.vector;
    assert!((nominal - Vector3::new(150.0, 0.0, 300.0)).norm() < 1e-12, "{nominal:?}");
}

/// Eq. 1–6 written out as 4 × 4 matrices.
fn t(x: f64, y: f64, z: f64) -> Matrix4<f64> {
    Matrix4::new(1.0, 0.0, 0.0, x, 0.0, 1.0, 0.0, y, 0.0, 0.0, 1.0, z, 0.0, 0.0, 0.0, 1.0)
}
fn rx(a: f64) -> Matrix4<f64> {
    let (s, c) = a.sin_cos();
    Matrix4::new(1.0, 0.0, 0.0, 0.0, 0.0, c, -s, 0.0, 0.0, s, c, 0.0, 0.0, 0.0, 0.0, 1.0)
}
fn ry(a: f64) -> Matrix4<f64> {
    let (s, c) = a.sin_cos();
    Matrix4::new(c, 0.0, s, 0.0, 0.0, 1.0, 0.0, 0.0, -s, 0.0, c, 0.0, 0.0, 0.0, 0.0, 1.0)
}
fn rz(a: f64) -> Matrix4<f64> {
    let (s, c) = a.sin_cos();
    Matrix4::new(c, -s, 0.0, 0.0, s, c, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0)
}

#[test]
fn eq_18_to_20_multiplied_out_for_two_joints() {
    // Per joint, eq. 18 (ΔX, ΔY, ΔZ as three translations), eq. 19 (Rx Ry Rz), eq. 20 (the segment along
    // the corrected axes), then the joint rotation (eq. 22). That is the eq. 21 grouping; the library's
    // canonical parameters come from ErrorParams::regroup.
    let chain = two_joints();
    let e21: [[f64; 6]; 2] = [[0.3, -0.2, 0.5, 0.7, -0.4, 1.1], [-0.6, 0.1, 0.2, -0.9, 0.8, 0.3]];
    let q = [0.4, -0.7];
    let mut by_hand = Matrix4::identity();
    for ((j, e), qi) in chain.joints().iter().zip(e21).zip(q) {
        let (dx, dy, dz) = (e[0], e[1], e[2]);
        let (ax, ay, az) = (e[3].to_radians(), e[4].to_radians(), e[5].to_radians());
        by_hand = by_hand * t(dx, 0.0, 0.0) * t(0.0, dy, 0.0) * t(0.0, 0.0, dz); // eq. 18
        by_hand = by_hand * rx(ax) * ry(ay) * rz(az); // eq. 19
        by_hand *= t(j.offset.x, j.offset.y, j.offset.z); // eq. 20
        by_hand *= if j.name == "j1" { rz(qi) } else { ry(qi) }; // eq. 4–6
    }
    by_hand *= t(0.0, 0.0, 100.0);
    let rows: Vec<ErrorParams> = chain
        .joints()
        .iter()
        .zip(e21)
        .map(|(j, e)| {
            thermokin_testdata::error_mm_deg(e).regroup(ErrorGrouping::PaperEq21, ErrorGrouping::Canonical, &j.offset)
        })
        .collect();
    let deformed = DeviationTable::from_joint_rows(rows).apply(&chain, &TableSemantics::Canonical).unwrap();
    let ours = deformed.tool_pose(&q).unwrap().to_homogeneous();
    assert!((ours - by_hand).abs().max() < 1e-12, "{ours} vs {by_hand}");
}

fn irb140() -> Chain {
    thermokin_testdata::irb140_table9()
}

#[test]
fn home_displacement_under_the_case_study_table() {
    // Every joint 1 mm off along each axis and turned 1° about each (Tables 10–11). At home no joint
    // turns, so the rows only stack: p_tcp = Σ_i R^(i−1) (p_i + d) + R^6 t_tool with R = Rx(1°)Ry(1°)Rz(1°).
    let chain = irb140();
    let table = DeviationTable::from_joint_rows(vec![thermokin_testdata::error_mm_deg([1.0; 6]); 6]);
    let deformed = table.apply(&chain, &TableSemantics::Canonical).unwrap();
    let one = 1f64.to_radians();
    let r = Rotation3::from_axis_angle(&Vector3::x_axis(), one)
        * Rotation3::from_axis_angle(&Vector3::y_axis(), one)
        * Rotation3::from_axis_angle(&Vector3::z_axis(), one);
    let d = Vector3::new(1.0, 1.0, 1.0);
    let mut acc = Rotation3::identity();
    let mut p = Vector3::zeros();
    for j in chain.joints() {
        p += acc * (j.offset + d);
        acc *= r;
    }
    p += acc * Vector3::new(25.5, 0.0, 0.0);
    let ours = deformed.tool_pose(&[0.0; 6]).unwrap().translation.vector;
    assert!((ours - p).norm() < 1e-9, "{ours:?} vs {p:?}");
    let nominal = chain.tool_pose(&[0.0; 6]).unwrap().translation.vector;
    let shift = (ours - nominal).norm();
    eprintln!("home TCP displacement under the case-study table: {shift:.3} mm ({:?})", (ours - nominal).as_slice());
    // "Deviations of the characteristic point of even 20 mm are observed" (results section).
    assert!(shift > 10.0 && shift < 40.0, "{shift}");
}

#[test]
fn coppeliasim_edits_are_re_expressed_exactly() {
    // Applying the edits by hand (world shift + Euler addition of one joint object, children following)
    // and reading the TCP must equal the FK of the re-expressed chain, at home and elsewhere.
    let chain = irb140();
    let table = DeviationTable::from_joint_rows(vec![
        thermokin_testdata::error_mm_deg([0.0, 0.0, 0.0, 0.0, 0.0, 0.0]),
        thermokin_testdata::error_mm_deg([0.0, 0.0, 0.0, 1.0, 0.0, 0.0]),
        ErrorParams::ZERO,
        ErrorParams::ZERO,
        ErrorParams::ZERO,
        ErrorParams::ZERO,
    ]);
    let deformed = table.apply(&chain, &TableSemantics::CoppeliaSim(CoppeliaSimEdits::at(vec![0.0; 6]))).unwrap();
    // Joint 2 object: local Z along world Y, i.e. Rx(−90°); adding 1° to its first Euler angle turns it
    // to Rx(−89°): the joint frame turns Rx(+1°) about joint 2's origin (70, 65, 352).
    let o2 = Vector3::new(70.0, 65.0, 352.0);
    let turn = Isometry3::rotation_wrt_point(
        nalgebra::UnitQuaternion::from_axis_angle(&Vector3::x_axis(), 1f64.to_radians()),
        o2.into(),
    );
    let q = [0.3, -0.2, 0.5, 0.1, 0.4, -0.6];
    let expected = {
        // Joint 1 at q1 carries everything; the edit was made at home, so it sits inside joint 1's motion.
        let frames = chain.joint_frames(&[q[0], 0.0, 0.0, 0.0, 0.0, 0.0]).unwrap();
        let world_from_j1 = frames[0];
        let home_j1 = chain.joint_frames(&[0.0; 6]).unwrap()[0];
        let rest = home_j1.inverse() * turn * chain.tool_pose(&[0.0, q[1], q[2], q[3], q[4], q[5]]).unwrap();
        world_from_j1 * rest
    };
    let ours = deformed.tool_pose(&q).unwrap();
    assert!(
        (ours.translation.vector - expected.translation.vector).norm() < 1e-9,
        "{:?}",
        ours.translation.vector - expected.translation.vector
    );
    assert!(ours.rotation.angle_to(&expected.rotation) < 1e-12);
}

#[test]
fn row_count_mismatch_is_an_error() {
    let t = DeviationTable::zeros(5);
    assert!(t.apply(&irb140(), &TableSemantics::Canonical).is_err());
}

#[test]
fn coppeliasim_euler_angles_rebuild_the_rotation_outside_the_gimbal_band_only() {
    use thermokin_chain::xyz_rotation;
    use thermokin_deform::coppeliasim_euler_angles;
    let rot = |a: f64, b: f64, c: f64| xyz_rotation(&Vector3::new(a, b, c));
    // Small angles through the Frobenius distance (‖P − Q‖ = 2√2·sin(θ/2)): acos of the trace loses
    // half the digits near zero.
    let angle_between = |p: &nalgebra::Matrix3<f64>, q: &nalgebra::Matrix3<f64>| {
        2.0 * ((p - q).norm() / (2.0 * std::f64::consts::SQRT_2)).asin()
    };
    // Away from β = ±90°: the angles are the rotation's own (500 seeded rotations, |β| < 89.5°).
    use rand::{Rng, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
    for _ in 0..500 {
        let (a, b, c) = (rng.random_range(-3.1..3.1), rng.random_range(-1.562..1.562), rng.random_range(-3.1..3.1));
        let r = rot(a, b, c);
        let e = coppeliasim_euler_angles(&r);
        assert!(angle_between(&r, &xyz_rotation(&e)) < 1e-12, "{a} {b} {c} -> {e:?}");
        assert!((e - Vector3::new(a, b, c)).norm() < 1e-9);
    }
    // Exactly at the lock (an X-axis joint object at home is Ry(90°)·Rz(spin)): α = 0, and the rotation
    // is rebuilt.
    let r = rot(0.0, std::f64::consts::FRAC_PI_2, 0.3);
    let e = coppeliasim_euler_angles(&r);
    assert_eq!(e.x, 0.0);
    assert!(angle_between(&r, &xyz_rotation(&e)) < 1e-12);
    // Inside the band (β 0.05° short of 90°, α = 0.01 rad): α is reported as 0 and a rotation of
    // |α|·cos β (to first order in α) is lost.
    let (alpha, beta) = (0.01, std::f64::consts::FRAC_PI_2 - 0.05f64.to_radians());
    let r = rot(alpha, beta, 0.2);
    let e = coppeliasim_euler_angles(&r);
    assert_eq!(e.x, 0.0);
    assert!((e.y - beta).abs() < 1e-9);
    let lost = angle_between(&r, &xyz_rotation(&e));
    let first_order = alpha * beta.cos();
    assert!((lost - first_order).abs() < 0.01 * first_order, "{lost} vs {first_order}");
    // Just outside the band (0.2° short of 90°) nothing is lost.
    let r = rot(alpha, std::f64::consts::FRAC_PI_2 - 0.2f64.to_radians(), 0.2);
    assert!(angle_between(&r, &xyz_rotation(&coppeliasim_euler_angles(&r))) < 1e-9);
}

/// A slide on a guide bent to curvature κ about its first lateral direction (`straightness` with
/// `σ₁ = −κ/2`): through the robot model, its carriage lies on the circle of radius 1/κ tangent to the
/// axis at the foot and is turned by κd — the arc's geometry, to the model's second order (κ²d³).
#[test]
fn a_bent_guides_carriage_follows_the_arc() {
    use thermokin_chain::{JointKind, OperatingState, Robot};
    use thermokin_deform::{JointCorrection, RobotModel};
    let joints = vec![Joint::prismatic("column", Vector3::new(0.0, 0.0, 250.0), Vector3::z_axis())];
    let chain = Chain::new(FixedRow::identity(), joints, FixedRow::identity()).unwrap();
    assert_eq!(chain.joints()[0].kind, JointKind::Prismatic);
    let [e1, _] = thermokin_chain::lateral_directions(&chain, 0).unwrap();
    let a = Vector3::z();
    let kappa = 2e-7; // rad per mm: 0.2 mrad per metre of travel
    let correction = JointCorrection { straightness: [kappa, 0.0, 0.0, -kappa / 2.0, 0.0], ..JointCorrection::NONE };
    let model = RobotModel::new(Robot::new("column", chain)).with_joint_corrections(vec![correction]).unwrap();
    for d in [0.0, 300.0, 800.0, 1500.0] {
        let pose = model.tool_pose(&[d], &OperatingState::default()).unwrap();
        let phi = kappa * d;
        // The arc turns a toward a × e₁ ... by the right-hand rule about e₁: R(φe₁)a = a cosφ + (e₁ × a) sinφ.
        let across = e1.cross(&a);
        let expected = Vector3::new(0.0, 0.0, 250.0) + a * (phi.sin() / kappa) + across * ((1.0 - phi.cos()) / kappa);
        let expected = if d == 0.0 { Vector3::new(0.0, 0.0, 250.0) } else { expected };
        let gap = (pose.translation.vector - expected).norm();
        assert!(gap < 2.0 * kappa * kappa * d.powi(3) + 1e-12, "d {d}: {gap}");
        let turned = Rotation3::from_axis_angle(&nalgebra::Unit::new_normalize(e1), phi);
        // The matrices' difference (an angle's extraction by acos loses half the digits near zero).
        let angle = (pose.rotation.to_rotation_matrix().matrix() - turned.matrix()).norm();
        assert!(angle < 1e-12 + kappa * kappa * d * d, "d {d}: {angle}");
    }
}

/// A column's lateral compliance known without masses is the one computed from masses: an IRB 140 on a
/// lift, its column tilting, bending and shifting under the moment of made-up masses (`lateral` of the
/// lift's [`JointCorrection`], the moments summed by the chain from the masses); the lumped weights
/// are each compliance times the weights that rebuild the moments from the lateral-load functions
/// (least squares here over 400 poses). On 50 fresh poses the two robot models — the one with the
/// masses, the one without them and with the weights — place the tool alike (1e-6 mm), where the column
/// moves it by a tenth of a millimetre and more.
#[test]
fn a_columns_lumped_lateral_compliance_is_the_one_of_its_masses() {
    use nalgebra::{DMatrix, DVector};
    use rand::SeedableRng;
    use thermokin_chain::{LinkMass, OperatingState, Robot};
    use thermokin_deform::{JointCorrection, RobotModel};
    let arm = thermokin_testdata::irb140_table9();
    let mut joints = vec![Joint::prismatic("lift", Vector3::new(0.0, 0.0, 300.0), Vector3::z_axis())];
    joints.extend(arm.joints().iter().cloned());
    let chain = Chain::new(FixedRow::identity(), joints, arm.tool().clone()).unwrap();
    let masses: Vec<Option<LinkMass>> = (0..7)
        .map(|l| Some(LinkMass { mass_kg: 30.0 - 4.0 * l as f64, com_mm: Vector3::new(60.0, 10.0 * l as f64, 40.0) }))
        .collect();
    let with_masses = Robot::new("lifted", chain.clone()).with_masses(masses.clone()).unwrap();
    let lateral = [2e-7, -1e-7, 4e-10, 2e-10, 1e-4, -2e-4];
    let mut corrections = vec![JointCorrection::NONE; 7];
    corrections[0] = JointCorrection { lateral, ..JointCorrection::NONE };
    let truth = RobotModel::new(with_masses).with_joint_corrections(corrections).unwrap();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(17);
    let mut random_q = || {
        use rand::Rng;
        let mut q = vec![rng.random_range(0.0..800.0)];
        q.extend((0..6).map(|_| rng.random_range(-2.5..2.5)));
        q
    };
    // The moments' weights over the lateral-load functions, per direction.
    let down = -Vector3::z_axis();
    let n = thermokin_chain::lateral_load_basis_len(&chain, 0);
    let half = n / 2;
    let (mut rows, mut along) = ([Vec::new(), Vec::new()], [Vec::new(), Vec::new()]);
    let (mut basis, mut moments) = (Vec::new(), Vec::new());
    for _ in 0..400 {
        let q = random_q();
        thermokin_chain::lateral_load_basis_into(&chain, &q, None, &down, 0, &mut basis).unwrap();
        thermokin_chain::lateral_gravity_moments_into(&chain, &masses, &q, None, &down, &mut moments).unwrap();
        for k in 0..2 {
            rows[k].extend_from_slice(&basis[k * half..(k + 1) * half]);
            along[k].push(moments[0][k]);
        }
    }
    let theta: Vec<Vec<f64>> = (0..2)
        .map(|k| {
            let a = DMatrix::from_row_slice(400, half, &rows[k]);
            a.svd(true, true).solve(&DVector::from_vec(along[k].clone()), 1e-12).unwrap().as_slice().to_vec()
        })
        .collect();
    let mut weights = Vec::new();
    for set in 0..3 {
        for k in 0..2 {
            weights.extend(theta[k].iter().map(|t| t * lateral[2 * set + k]));
        }
    }
    assert_eq!(weights.len(), thermokin_deform::lumped_lateral_weights_len(&chain, 0));
    let mut loads = vec![Vec::new(); 7];
    loads[0] = weights;
    let lumped = RobotModel::new(Robot::new("lifted", chain.clone())).with_lateral_loads(loads).unwrap();
    let state = OperatingState::default();
    let mut moved = 0.0f64;
    for _ in 0..50 {
        let q = random_q();
        let (a, b) = (truth.tool_pose(&q, &state).unwrap(), lumped.tool_pose(&q, &state).unwrap());
        assert!((a.translation.vector - b.translation.vector).norm() < 1e-6, "{q:?}");
        moved = moved.max((a.translation.vector - chain.tool_pose(&q).unwrap().translation.vector).norm());
    }
    assert!(moved > 0.1, "{moved}");
}
