//! Orientation errors of 180°: the case where the old rotation log read a half turn as no error and
//! the solver reported `Converged` with the tool upside down. Every `Converged` answer here is checked
//! by FK and nalgebra's quaternion angle, independently of the solver.

use std::f64::consts::PI;

use nalgebra::{Isometry3, Rotation3, Translation3, UnitQuaternion, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use thermokin_chain::{Chain, xyz_rotation};
use thermokin_ik::{Goal, Params, Status, Workspace, solve};
use thermokin_testdata::workspace;

fn irb140() -> Chain {
    thermokin_io::read_robot(&workspace("configs/irb140.toml")).expect("bundled robot").chain().clone()
}

/// A pose from mm and X-Y-Z Euler degrees (the CLI's `--pose` convention).
fn pose(x: f64, y: f64, z: f64, rx: f64, ry: f64, rz: f64) -> Isometry3<f64> {
    let r = xyz_rotation(&Vector3::new(rx, ry, rz).map(f64::to_radians));
    Isometry3::from_parts(Translation3::new(x, y, z), UnitQuaternion::from_matrix(&r))
}

/// Position (mm) and angle (degrees, nalgebra's `angle_to`) between FK(q) and the goal.
fn fk_error(chain: &Chain, goal: &Isometry3<f64>, q: &[f64]) -> (f64, f64) {
    let reached = chain.tool_pose(q).unwrap();
    (
        (reached.translation.vector - goal.translation.vector).norm(),
        reached.rotation.angle_to(&goal.rotation).to_degrees(),
    )
}

/// A converged answer must be right; a wrong answer must not be converged.
fn assert_honest(chain: &Chain, goal: &Isometry3<f64>, s: &thermokin_ik::Solution, what: &str) {
    let (dp, dr) = fk_error(chain, goal, &s.q);
    if s.converged() {
        // 1e-9 mm / 1e-9° are the solver's tolerances; nalgebra's `angle_to` (2·acos w) resolves angles
        // only to ~2e-6° near zero, so the orientation bound here is that resolution.
        assert!(dp <= 1e-9 && dr <= 2e-6, "{what}: Converged but FK is {dp:e} mm, {dr:e}° off");
        assert!(chain.within_limits(&s.q), "{what}: outside the limits");
    } else {
        assert!(dp > 1e-9 || dr > 1e-9, "{what}: {:?} although FK is on target", s.status);
    }
    // The reported errors are the independent ones.
    assert!((s.position_error_mm - dp).abs() <= 1e-9, "{what}: reported {} mm, FK {dp} mm", s.position_error_mm);
    let reported = s.orientation_error_rad.to_degrees();
    assert!((reported - dr).abs() <= 2e-6, "{what}: reported {reported}°, FK {dr}°");
}

#[test]
fn the_reported_case_tool_down_at_500_0_300() {
    // `thermokin ik --robot configs/irb140.toml --pose 500,0,300,180,0,0` printed Converged with the
    // tool 180° from the request.
    let chain = irb140();
    let goal = pose(500.0, 0.0, 300.0, 180.0, 0.0, 0.0);
    let mut ws = Workspace::new(6);
    for seed in [[0.0; 6], [0.0, 20.0, 20.0, 0.0, -45.0, 0.0].map(f64::to_radians)] {
        let s = solve(&chain, &Goal::Pose(goal), &seed, &Params::default(), &mut ws, 0).unwrap();
        assert_honest(&chain, &goal, &s, "500,0,300,180,0,0");
        assert_eq!(s.status, Status::Converged, "the pose is reachable (tool down in front of the robot)");
    }
}

#[test]
fn half_turns_from_the_seed_about_every_tool_axis() {
    // Seed at q0, goal = FK(q0) turned by exactly π about the tool's own X, Y and Z axes at the same TCP
    // point: the solver starts with an orientation error of exactly 180°.
    let chain = irb140();
    let mut rng = ChaCha8Rng::seed_from_u64(0x180);
    let mut ws = Workspace::new(6);
    let mut converged = [0usize; 3];
    let cases = 60;
    for case in 0..cases {
        let q0: Vec<f64> =
            chain.joints().iter().map(|j| j.limits.map_or(0.0, |l| rng.random_range(l.lower..l.upper))).collect();
        let start = chain.tool_pose(&q0).unwrap();
        for (k, axis) in [Vector3::x_axis(), Vector3::y_axis(), Vector3::z_axis()].into_iter().enumerate() {
            let turn = UnitQuaternion::from_rotation_matrix(&Rotation3::from_axis_angle(&axis, PI));
            let goal = Isometry3::from_parts(start.translation, start.rotation * turn);
            let s = solve(&chain, &Goal::Pose(goal), &q0, &Params::default(), &mut ws, case).unwrap();
            assert_honest(&chain, &goal, &s, &format!("case {case}, tool axis {k}"));
            converged[k] += usize::from(s.converged());
        }
    }
    eprintln!("half turns about tool X, Y, Z: {converged:?} of {cases} converged");
    // About the tool's Z axis a half turn is joint 6 (axis X, ±400°) turning by π: always reachable.
    assert_eq!(converged[2] as u64, cases);
}

#[test]
fn tool_down_targets_for_every_bundled_robot() {
    let mut robots: Vec<_> = std::fs::read_dir(workspace("configs"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    robots.sort();
    assert!(robots.len() >= 4, "{robots:?}");
    let mut ws = Workspace::new(6);
    for path in robots {
        let chain = thermokin_io::read_robot(&path).unwrap().chain().clone();
        let mut solved = 0;
        let mut total = 0;
        for x in [350.0, 450.0, 550.0, 650.0] {
            for y in [-250.0, 0.0, 250.0] {
                for z in [100.0, 300.0, 500.0] {
                    // X-Y-Z Euler (180, 0, 0): the tool's Z axis along world −Z, the common machining and
                    // pick-and-place orientation; (180, 0, 90) is the same with the tool turned.
                    for rz in [0.0, 90.0] {
                        let goal = pose(x, y, z, 180.0, 0.0, rz);
                        let s =
                            solve(&chain, &Goal::Pose(goal), &[0.0; 6], &Params::default(), &mut ws, total).unwrap();
                        assert_honest(
                            &chain,
                            &goal,
                            &s,
                            &format!("{} at ({x}, {y}, {z}, 180, 0, {rz})", path.display()),
                        );
                        solved += usize::from(s.converged());
                        total += 1;
                    }
                }
            }
        }
        eprintln!("{}: {solved} of {total} tool-down targets converged", path.display());
        // Every one of these points lies well inside the IRB 140's 810 mm reach with room for the
        // 65 mm wrist-to-flange lever pointing down.
        assert_eq!(solved, total as usize, "{}", path.display());
    }
}
