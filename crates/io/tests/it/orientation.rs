//! Orientation conventions at the edge, against rotations built independently (nalgebra's axis-angle
//! and hand-composed elementary rotations): every convention round-trips, ROS rpy is `Rz·Ry·Rx`, and the
//! Euler singularity prints clean.

use nalgebra::{Rotation3, Unit, UnitQuaternion, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use thermokin_io::Orientation;
use thermokin_io::units::{quaternion_wxyz, ros_rpy_deg, xyz_euler_deg};

fn random_rotations() -> Vec<UnitQuaternion<f64>> {
    let mut rng = ChaCha8Rng::seed_from_u64(0x0e11);
    let mut out: Vec<UnitQuaternion<f64>> = (0..500)
        .map(|_| {
            let axis = Unit::new_normalize(Vector3::new(
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
            ));
            UnitQuaternion::from_axis_angle(&axis, rng.random_range(0.0..std::f64::consts::PI))
        })
        .collect();
    // At and next to both singularities of both Euler conventions, and the half turns.
    for pitch in [90.0, -90.0, 90.0 - 1e-7, -90.0 + 1e-7, 89.9, -89.9] {
        for other in [0.0, 25.0, -170.0] {
            let p = f64::to_radians(pitch);
            let o = f64::to_radians(other);
            out.push(
                UnitQuaternion::from_axis_angle(&Vector3::x_axis(), o)
                    * UnitQuaternion::from_axis_angle(&Vector3::y_axis(), p),
            );
            out.push(
                UnitQuaternion::from_axis_angle(&Vector3::z_axis(), o)
                    * UnitQuaternion::from_axis_angle(&Vector3::y_axis(), p),
            );
        }
    }
    for axis in [Vector3::x_axis(), Vector3::y_axis(), Vector3::z_axis()] {
        out.push(UnitQuaternion::from_axis_angle(&axis, std::f64::consts::PI));
    }
    out
}

fn angle(a: &UnitQuaternion<f64>, b: &UnitQuaternion<f64>) -> f64 {
    thermokin_chain::rotation_angle(a, b)
}

#[test]
fn every_convention_round_trips() {
    for r in random_rotations() {
        let xyz = xyz_euler_deg(&r);
        let rpy = ros_rpy_deg(&r);
        let q = quaternion_wxyz(&r);
        // 1e-12 rad: a few ulps of the trigonometry; the singular cases go through the explicit branch.
        assert!(angle(&Orientation::XyzEuler.rotation(&xyz).unwrap(), &r) < 1e-12, "xyz {xyz:?}");
        assert!(angle(&Orientation::Rpy.rotation(&rpy).unwrap(), &r) < 1e-12, "rpy {rpy:?}");
        assert!(angle(&Orientation::Quaternion.rotation(&q).unwrap(), &r) < 1e-12, "quat {q:?}");
        assert!(q[0] >= 0.0);
        assert!((-90.0..=90.0).contains(&xyz[1]) && (-90.0..=90.0).contains(&rpy[1]));
    }
}

#[test]
fn ros_rpy_is_fixed_axis_xyz() {
    // R = Rz(yaw)·Ry(pitch)·Rx(roll), composed by hand from elementary rotations.
    let (roll, pitch, yaw) = (10.0_f64, -35.0_f64, 120.0_f64);
    let by_hand = Rotation3::from_axis_angle(&Vector3::z_axis(), yaw.to_radians())
        * Rotation3::from_axis_angle(&Vector3::y_axis(), pitch.to_radians())
        * Rotation3::from_axis_angle(&Vector3::x_axis(), roll.to_radians());
    let ours = Orientation::Rpy.rotation(&[roll, pitch, yaw]).unwrap();
    assert!(angle(&ours, &UnitQuaternion::from_rotation_matrix(&by_hand)) < 1e-14);
    // The paper's convention is the other order: R = Rx·Ry·Rz.
    let xyz = Orientation::XyzEuler.rotation(&[roll, pitch, yaw]).unwrap();
    let by_hand_xyz = Rotation3::from_axis_angle(&Vector3::x_axis(), roll.to_radians())
        * Rotation3::from_axis_angle(&Vector3::y_axis(), pitch.to_radians())
        * Rotation3::from_axis_angle(&Vector3::z_axis(), yaw.to_radians());
    assert!(angle(&xyz, &UnitQuaternion::from_rotation_matrix(&by_hand_xyz)) < 1e-14);
    assert!(angle(&xyz, &ours) > 0.1, "the two conventions must differ here");
}

#[test]
fn bad_orientations_are_refused() {
    assert!(Orientation::Quaternion.rotation(&[1.0, 0.1, 0.0, 0.0]).is_err());
    assert!(Orientation::Quaternion.rotation(&[0.0, 0.0, 0.0, 0.0]).is_err());
    assert!(Orientation::XyzEuler.rotation(&[0.0, f64::NAN, 0.0]).is_err());
    assert!(Orientation::Rpy.rotation(&[0.0, 0.0]).is_err());
    assert!(thermokin_io::units::rotation_from_matrix([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, -1.0]]).is_err());
    assert!("zyx".parse::<Orientation>().is_err());
}
