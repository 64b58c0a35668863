//! Seeded random chains and configurations shared by the tests.

use nalgebra::{Isometry3, Unit, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use thermokin_chain::{Chain, DhConvention, DhRow, DhTable, ErrorParams, FixedRow, Joint, JointKind};

pub fn rng(seed: u64) -> ChaCha8Rng {
    ChaCha8Rng::seed_from_u64(seed)
}

pub fn random_q(rng: &mut ChaCha8Rng, n: usize) -> Vec<f64> {
    (0..n).map(|_| rng.random_range(-3.0..3.0)).collect()
}

pub fn random_iso(rng: &mut ChaCha8Rng, scale: f64) -> Isometry3<f64> {
    let t = Vector3::new(rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0));
    let r = Vector3::new(rng.random_range(-2.0..2.0), rng.random_range(-2.0..2.0), rng.random_range(-2.0..2.0));
    Isometry3::new(t * scale, r)
}

pub fn random_dh(rng: &mut ChaCha8Rng, convention: DhConvention, n: usize) -> DhTable {
    let rows = (0..n)
        .map(|i| {
            let mut row = DhRow::revolute(
                format!("j{}", i + 1),
                rng.random_range(-400.0..400.0),
                rng.random_range(-3.0..3.0),
                rng.random_range(-400.0..400.0),
                rng.random_range(-3.0..3.0),
            );
            if i == 2 && n > 3 {
                row.kind = JointKind::Prismatic;
            }
            row
        })
        .collect();
    DhTable { convention, rows, base: random_iso(rng, 300.0), tool: random_iso(rng, 100.0) }
}

pub fn random_error(rng: &mut ChaCha8Rng, mm: f64, rad: f64) -> ErrorParams {
    ErrorParams::new(
        Vector3::new(rng.random_range(-mm..mm), rng.random_range(-mm..mm), rng.random_range(-mm..mm)),
        Vector3::new(rng.random_range(-rad..rad), rng.random_range(-rad..rad), rng.random_range(-rad..rad)),
    )
}

/// A 6R chain shaped like the IRB 140 (Table 9), with random error parameters on every row.
pub fn irb140_like(rng: &mut ChaCha8Rng, with_errors: bool) -> Chain {
    let axes = [
        Vector3::z_axis(),
        Vector3::y_axis(),
        Vector3::y_axis(),
        Vector3::x_axis(),
        Vector3::y_axis(),
        Vector3::x_axis(),
    ];
    let offsets = [
        [0.0, 0.0, 104.5],
        [70.0, 65.0, 247.5],
        [0.0, -123.0, 360.0],
        [238.5, 58.0, 0.0],
        [141.5, 0.0, 0.0],
        [39.5, 0.0, 0.0],
    ];
    let joints: Vec<Joint> = axes
        .iter()
        .zip(offsets)
        .enumerate()
        .map(|(i, (a, o))| {
            let mut j = Joint::revolute(format!("j{}", i + 1), Vector3::from(o), *a);
            if with_errors {
                j.error = random_error(rng, 1.0, 0.02);
            }
            j
        })
        .collect();
    let mut base = FixedRow::identity();
    let mut tool = FixedRow::from_isometry(&Isometry3::new(
        Vector3::new(25.5, 0.0, 0.0),
        Vector3::new(0.0, std::f64::consts::FRAC_PI_2, 0.0),
    ));
    if with_errors {
        base.error = random_error(rng, 1.0, 0.02);
        tool.error = random_error(rng, 1.0, 0.02);
    }
    Chain::new(base, joints, tool).expect("valid chain")
}

/// A chain with general (non-principal) axes and a prismatic joint.
pub fn general_chain(rng: &mut ChaCha8Rng) -> Chain {
    let joints = (0..6)
        .map(|i| {
            let axis = Unit::new_normalize(Vector3::new(
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
            ));
            let offset = Vector3::new(
                rng.random_range(-300.0..300.0),
                rng.random_range(-300.0..300.0),
                rng.random_range(-300.0..300.0),
            );
            let mut j = if i == 3 {
                Joint::prismatic(format!("j{i}"), offset, axis)
            } else {
                Joint::revolute(format!("j{i}"), offset, axis)
            };
            j.zero = rng.random_range(-1.0..1.0);
            j.error = random_error(rng, 2.0, 0.05);
            j
        })
        .collect();
    Chain::new(
        FixedRow::from_isometry(&random_iso(rng, 100.0)),
        joints,
        FixedRow::from_isometry(&random_iso(rng, 100.0)),
    )
    .expect("valid chain")
}

pub fn pose_gap(a: &Isometry3<f64>, b: &Isometry3<f64>) -> (f64, f64) {
    ((a.translation.vector - b.translation.vector).norm(), a.rotation.angle_to(&b.rotation))
}
