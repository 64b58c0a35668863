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
    let nominal = thermokin_testdata::irb140_table9();
    if !with_errors {
        return nominal;
    }
    let joints: Vec<ErrorParams> = (0..6).map(|_| random_error(rng, 1.0, 0.02)).collect();
    let base = random_error(rng, 1.0, 0.02);
    let tool = random_error(rng, 1.0, 0.02);
    nominal.with_errors(base, &joints, tool).expect("valid chain")
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
