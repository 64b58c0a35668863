//! Every bundled URDF (`fixtures/urdf`): our imported table against the `k` crate (an independent implementation), and the
//! export → import round trip.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use thermokin_testdata::urdf;
use thermokin_urdf::{ImportOptions, export_urdf, import_urdf};

/// (file, tip link): the tip is the flange where a URDF's tree branches into fingers.
const ROBOTS: &[(&str, Option<&str>)] = &[
    ("abb_irb140.urdf", Some("tool0")),
    ("ur5.urdf", Some("tool0")),
    ("ur10.urdf", Some("tool0")),
    ("panda.urdf", Some("panda_hand_tcp")),
    ("xarm7.urdf", None),
    ("kinova.urdf", Some("j2s6s200_end_effector")),
    ("z1.urdf", Some("link06")),
];

fn options(tip: Option<&str>) -> ImportOptions {
    ImportOptions { base: None, tip: tip.map(str::to_string) }
}

/// 1e-9 mm: the conversion contract. k works in metres; its f64 FK carries ~1e-16 m · reach of rounding,
/// far below.
const MM: f64 = 1e-9;

#[test]
fn imported_fk_equals_the_k_crate() {
    for (file, tip) in ROBOTS {
        let path = urdf(file);
        let text = std::fs::read_to_string(&path).unwrap();
        let imported = import_urdf(&text, file, &options(*tip)).unwrap_or_else(|e| panic!("{e}"));
        let tip_link = imported.tip_link;
        let robot = imported.robot;
        let k_chain = k::Chain::<f64>::from_urdf_file(&path).unwrap();
        let end = k_chain.find_link(&tip_link).unwrap_or_else(|| panic!("{file}: k has no link {tip_link}"));
        let serial = k::SerialChain::from_end(end);
        assert_eq!(serial.dof(), robot.chain().dof(), "{file}");
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let mut worst = 0.0f64;
        for _ in 0..1000 {
            let q: Vec<f64> = robot
                .chain()
                .joints()
                .iter()
                .map(|j| {
                    let (lo, hi) = j.limits.map_or((-3.0, 3.0), |l| (l.lower, l.upper));
                    rng.random_range(lo..hi)
                })
                .collect();
            // k takes metres for prismatic joints.
            let q_k: Vec<f64> = robot
                .chain()
                .joints()
                .iter()
                .zip(&q)
                .map(|(j, v)| if j.kind == thermokin_chain::JointKind::Prismatic { v / 1000.0 } else { *v })
                .collect();
            serial.set_joint_positions_unchecked(&q_k);
            let theirs = serial.end_transform().to_homogeneous();
            let ours = robot.chain().tool_pose(&q).unwrap().to_homogeneous();
            let t = theirs.as_slice();
            let o = ours.as_slice();
            for r in 0..3 {
                for c in 0..3 {
                    assert!((t[c * 4 + r] - o[c * 4 + r]).abs() < 1e-12, "{file}: rotation differs");
                }
                worst = worst.max((t[12 + r] * 1000.0 - o[12 + r]).abs());
            }
        }
        eprintln!("{file}: {} joints, worst |ours − k| = {worst:.2e} mm", robot.chain().dof());
        assert!(worst < MM, "{file}: {worst:.3e} mm");
    }
}

#[test]
fn export_then_import_is_exact() {
    for (file, tip) in ROBOTS {
        let path = urdf(file);
        let text = std::fs::read_to_string(&path).unwrap();
        let robot = import_urdf(&text, file, &options(*tip)).unwrap().robot;
        // Deform it first: every joint gets error parameters, so the export must carry them.
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let errs: Vec<_> = (0..robot.chain().dof())
            .map(|_| thermokin_testdata::error_mm_deg([0.0; 6].map(|_: f64| rng.random_range(-1.0..1.0))))
            .collect();
        let deformed = robot
            .chain()
            .with_errors(thermokin_chain::ErrorParams::ZERO, &errs, thermokin_chain::ErrorParams::ZERO)
            .unwrap();
        let exported = export_urdf(&deformed, robot.name());
        let back = import_urdf(&exported, "exported", &ImportOptions::default()).unwrap().robot;
        assert_eq!(back.chain().dof(), deformed.dof());
        let names: Vec<_> = back.chain().joints().iter().map(|j| j.name.clone()).collect();
        let want: Vec<_> = deformed.joints().iter().map(|j| j.name.clone()).collect();
        assert_eq!(names, want, "{file}: names");
        for (a, b) in back.chain().joints().iter().zip(deformed.joints()) {
            match (a.limits, b.limits) {
                (Some(x), Some(y)) => assert!((x.lower - y.lower).abs() < 1e-12 && (x.upper - y.upper).abs() < 1e-12),
                (None, None) => {}
                other => panic!("{file}: limits {other:?}"),
            }
        }
        for _ in 0..200 {
            let q: Vec<f64> = (0..deformed.dof()).map(|_| rng.random_range(-3.0..3.0)).collect();
            let a = back.chain().tool_pose(&q).unwrap();
            let b = deformed.tool_pose(&q).unwrap();
            let dp = (a.translation.vector - b.translation.vector).norm();
            // Rotation compared as matrices: `angle_to` goes through acos and resolves only ~1e-8 rad.
            let dr = (a.rotation.to_rotation_matrix().matrix() - b.rotation.to_rotation_matrix().matrix()).norm();
            assert!(dp < MM && dr < 1e-12, "{file}: {dp:.3e} mm, {dr:.3e}");
        }
    }
}

#[test]
fn ros_industrial_irb140_against_the_bundled_table() {
    let path = urdf("abb_irb140.urdf");
    let robot = import_urdf(&std::fs::read_to_string(&path).unwrap(), "abb_irb140.urdf", &options(Some("tool0")))
        .unwrap()
        .robot;
    let toml_robot = std::fs::read_to_string(thermokin_testdata::workspace("configs/irb140.toml")).unwrap();
    assert!(toml_robot.contains("238.5"));
    // Joint positions at zero, ours (Table 9) vs the URDF: the URDF rounds 238.5 → 239 and 141.5 → 141.
    let frames = robot.chain().joint_frames(&[0.0; 6]).unwrap();
    let urdf_x: Vec<f64> = frames.iter().take(6).map(|f| f.translation.vector.x).collect();
    let table9_x = [0.0, 70.0, 70.0, 308.5, 450.0, 489.5];
    let diffs: Vec<f64> = urdf_x.iter().zip(table9_x).map(|(u, t)| u - t).collect();
    eprintln!("IRB 140 joint X positions, URDF − Table 9: {diffs:?} mm");
    assert!((diffs[3] - 0.5).abs() < 1e-9 && (diffs[4] - 0.0).abs() < 1e-9, "{diffs:?}");
}
