//! A tally of the rows the fits evaluate, over the whole process ([`evaluated`]): what a benchmark reads
//! to say whether a diagnosis's work grows with its poses alone — the rows of residuals and of the
//! Jacobian per pose are constant then, and a larger count per pose says the fits iterate more.
//!
//! Relaxed atomic counters, added to once per evaluation; nothing a fit or a diagnosis decides reads
//! them. Concurrent diagnoses in one process add to the same tally: read the difference over a run
//! ([`Evaluated::since`]) where nothing else runs.

use std::sync::atomic::{AtomicU64, Ordering};

use serde::Serialize;

static RESIDUAL_ROWS: AtomicU64 = AtomicU64::new(0);
static JACOBIAN_ROWS: AtomicU64 = AtomicU64::new(0);

/// Rows the fits have evaluated ([`evaluated`]), the data's rows only (a prior's are not counted).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct Evaluated {
    /// Rows evaluated as residuals alone: the trial steps.
    pub residual_rows: u64,
    /// Rows evaluated with their Jacobian (the residuals with them).
    pub jacobian_rows: u64,
}

impl Evaluated {
    /// What was evaluated between `earlier` and `self`.
    pub fn since(self, earlier: Evaluated) -> Evaluated {
        Evaluated {
            residual_rows: self.residual_rows.saturating_sub(earlier.residual_rows),
            jacobian_rows: self.jacobian_rows.saturating_sub(earlier.jacobian_rows),
        }
    }
}

/// The rows every fit in this process has evaluated so far.
///
/// ```
/// use nalgebra::{Isometry3, Vector3};
/// use thermokin_chain::{Chain, Dataset, ErrorParams, FixedRow, Joint, Measurement, Robot};
/// use thermokin_identify::{Effect, JointIndex, Model, PoseTerms, evaluated, fit};
///
/// let joints = vec![
///     Joint::revolute("shoulder", Vector3::new(0.0, 0.0, 300.0), Vector3::y_axis()),
///     Joint::revolute("elbow", Vector3::new(400.0, 0.0, 0.0), Vector3::y_axis()),
/// ];
/// let tool = FixedRow::from_isometry(&Isometry3::translation(250.0, 0.0, 0.0));
/// let robot = Robot::new("arm", Chain::new(FixedRow::identity(), joints, tool)?);
/// let zeros = ErrorParams::ZERO;
/// let real = robot.chain().with_errors_and_zeros(zeros, &[zeros, zeros], zeros, &[0.0, 0.01])?;
/// let measurements = (0..12)
///     .map(|k| {
///         let q = vec![0.1 * k as f64, 0.2 - 0.05 * k as f64];
///         let position_mm = real.tool_pose(&q).unwrap().translation.vector;
///         Measurement { time_min: 0.0, q, position_mm, orientation: None, position_std_mm: None, temps: vec![] }
///     })
///     .collect();
/// let data = Dataset { measurements, ..Dataset::default() };
/// let model = Model::new(&robot, vec![Effect::JointOffset(JointIndex::of(&robot, 1)?)])?;
/// let all: Vec<usize> = (0..data.len()).collect();
///
/// let before = evaluated();
/// fit(&robot, &model, &data, &all, &PoseTerms::of(&robot, &data, 0.0))?;
/// let run = evaluated().since(before);
/// // At least the start's Jacobian: 12 poses × 3 position rows.
/// assert!(run.jacobian_rows >= 36 && run.jacobian_rows % 36 == 0, "{run:?}");
/// assert_eq!(run.residual_rows % 36, 0);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn evaluated() -> Evaluated {
    Evaluated {
        residual_rows: RESIDUAL_ROWS.load(Ordering::Relaxed),
        jacobian_rows: JACOBIAN_ROWS.load(Ordering::Relaxed),
    }
}

/// Counts one evaluation of `rows` data rows, with their Jacobian or not.
pub(crate) fn count(rows: usize, jacobian: bool) {
    let counter = if jacobian { &JACOBIAN_ROWS } else { &RESIDUAL_ROWS };
    counter.fetch_add(rows as u64, Ordering::Relaxed);
}
