//! Gravity compliance with a payload on the flange (a heavy probe): data made here by bending joint 2
//! under the torque of the links and the payload, computed in this file from the chain's joint frames
//! (not by the diagnosis's `gravity_torques`). Told the payload, the diagnosis explains the data to the
//! noise; not told, the torques it fits against miss the payload's share.

use nalgebra::{Point3, Vector3};
use thermokin_chain::{Chain, LinkMass};
use thermokin_diagnose::{Config, diagnose};
use thermokin_testdata::workspace;

use crate::tracker::{NOISE_MM, measure};

/// 12 kg, 120 mm out along the flange's X (the tool's direction on the IRB 140).
fn payload() -> LinkMass {
    LinkMass { mass_kg: 12.0, com_mm: Vector3::new(120.0, 0.0, 0.0) }
}

/// Gravity torque about joint 2, N·m: every body beyond it, gravity along the base's −Z.
fn torque_2(chain: &Chain, masses: &[Option<LinkMass>], q: &[f64]) -> f64 {
    let frames = chain.joint_frames(q).unwrap();
    let axis = frames[1].rotation * chain.joints()[1].axis.into_inner();
    let origin = frames[1].translation.vector;
    let mut bodies: Vec<(f64, Vector3<f64>)> =
        (1..6).filter_map(|l| masses[l].map(|m| (m.mass_kg, (frames[l] * Point3::from(m.com_mm)).coords))).collect();
    bodies.push((payload().mass_kg, (frames[5] * Point3::from(payload().com_mm)).coords));
    let moment: Vector3<f64> = bodies.iter().map(|(m, c)| (c - origin).cross(&Vector3::new(0.0, 0.0, -9.81 * m))).sum();
    axis.dot(&moment) / 1000.0
}

#[test]
fn a_payload_told_is_a_compliance_explained() {
    let robot = thermokin_io::read_robot(&workspace("configs/irb140.toml")).unwrap();
    let k = 0.002f64.to_radians(); // rad per N·m
    let chain = robot.chain().clone();
    let masses = robot.masses().to_vec();
    let data = measure(robot.chain(), 200, 91, |q| {
        let mut a = q.to_vec();
        a[1] += k * torque_2(&chain, &masses, q);
        a
    });
    let noise_rms = NOISE_MM * 3f64.sqrt();
    let told = robot.clone().with_payload(payload()).unwrap();
    let with = diagnose(&told, &data, None, &Config::default()).unwrap();
    let without = diagnose(&robot, &data, None, &Config::default()).unwrap();
    let (a, b) = (with.nested.as_ref().unwrap(), without.nested.as_ref().unwrap());
    let labels = |r: &thermokin_diagnose::Report| r.effects.iter().map(|e| e.label.clone()).collect::<Vec<_>>();
    eprintln!(
        "told: {:?} {:.4} → {:.4} mm; not told: {:?} → {:.4} mm",
        labels(&with),
        a.nominal.heldout_rms_mm,
        a.selected.heldout_rms_mm,
        labels(&without),
        b.selected.heldout_rms_mm
    );
    assert_eq!(labels(&with), ["joint_compliance[2]"]);
    assert!(a.nominal.heldout_rms_mm > 10.0 * noise_rms);
    assert!(a.selected.heldout_rms_mm <= 1.5 * noise_rms, "{} mm", a.selected.heldout_rms_mm);
    // Not told, the torques miss the payload's share: five effects and still 18× the noise.
    assert!(b.selected.heldout_rms_mm > 1.5 * noise_rms, "{} mm", b.selected.heldout_rms_mm);
}

#[test]
fn a_payload_is_merged_with_the_last_link() {
    let robot = thermokin_io::read_robot(&workspace("configs/irb140.toml")).unwrap();
    let link = robot.masses()[5];
    let told = robot.clone().with_payload(payload()).unwrap();
    let merged = told.masses()[5].unwrap();
    let m0 = link.map_or(0.0, |l| l.mass_kg);
    assert!((merged.mass_kg - (m0 + 12.0)).abs() < 1e-12);
    let c0 = link.map_or(Vector3::zeros(), |l| l.com_mm * l.mass_kg);
    assert!((merged.com_mm * merged.mass_kg - (c0 + payload().com_mm * 12.0)).norm() < 1e-9);
    assert!(robot.clone().with_payload(LinkMass { mass_kg: 0.0, com_mm: Vector3::zeros() }).is_err());
    assert!(robot.with_payload(LinkMass { mass_kg: 1.0, com_mm: Vector3::new(f64::NAN, 0.0, 0.0) }).is_err());
}
