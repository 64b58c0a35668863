//! The poses a plan chooses from: the user's (taught, collision-free — each named by its file line), or
//! sampled within the joint limits and a workspace box.

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use thermokin_chain::Robot;
use thermokin_identify::random_configuration;

use crate::error::PlanError;
use crate::params::WorkspaceBox;

/// Fraction of each joint's travel a sampled candidate keeps from its limits: real calibration poses
/// avoid the limits (the diagnosis' simulations draw the same way).
const SAMPLING_MARGIN: f64 = 0.02;
/// Draws per wanted candidate before sampling within a box gives up.
const DRAWS_PER_CANDIDATE: usize = 200;

/// Configurations [`Candidates::sampled`] draws when the front end is not told how many: enough that a
/// 60-pose plan of a six-joint arm chooses among fifty per pose.
pub const DEFAULT_SAMPLES: usize = 3000;

/// Candidate configurations, radians (mm for a prismatic joint), each with where it came from: its
/// 1-based line in the candidates file, or its 1-based index when sampled. Built by [`Candidates::new`]
/// or [`Candidates::sampled`], which check every value against the robot.
#[derive(Clone, Debug, PartialEq)]
pub struct Candidates {
    joints: Vec<Vec<f64>>,
    lines: Vec<usize>,
    from_file: bool,
    /// The lines of the candidates set aside as exact copies of an earlier one.
    copies: Vec<usize>,
}

impl Candidates {
    /// The user's candidates with their file lines (`lines` empty: numbered 1, 2, …). Every value must be
    /// finite and within the joint limits. A candidate that repeats an earlier one exactly is set aside
    /// ([`Candidates::copies`]): one pose measured twice pins nothing down that it did not, and a plan
    /// among copies would count them as other poses.
    pub fn new(robot: &Robot, joints: Vec<Vec<f64>>, lines: Vec<usize>) -> Result<Self, PlanError> {
        let from_file = !lines.is_empty();
        let lines = if from_file { lines } else { (1..=joints.len()).collect() };
        if lines.len() != joints.len() {
            return Err(PlanError::Setting {
                setting: "lines",
                value: lines.len().to_string(),
                rule: "one line per candidate",
            });
        }
        for (q, &line) in joints.iter().zip(&lines) {
            check(robot, q, "candidate", line)?;
            if let Some(&j) = robot.chain().outside_limits(q).first() {
                return Err(PlanError::OutsideLimits { index: line, joint: j + 1 });
            }
        }
        let mut seen: std::collections::HashSet<Vec<u64>> = std::collections::HashSet::new();
        let (mut kept, mut kept_lines, mut copies) = (Vec::new(), Vec::new(), Vec::new());
        for (q, line) in joints.into_iter().zip(lines) {
            if seen.insert(q.iter().map(|v| (v + 0.0).to_bits()).collect()) {
                kept.push(q);
                kept_lines.push(line);
            } else {
                copies.push(line);
            }
        }
        Ok(Self { joints: kept, lines: kept_lines, from_file, copies })
    }

    /// The lines (or 1-based indices) of the candidates set aside as exact copies of an earlier one.
    pub fn copies(&self) -> &[usize] {
        &self.copies
    }

    /// `count` configurations drawn uniformly within the joint limits (a revolution for a joint without),
    /// seeded, keeping those that put the robot's tool point inside `workspace` when one is given.
    pub fn sampled(
        robot: &Robot,
        count: usize,
        seed: u64,
        workspace: Option<&WorkspaceBox>,
    ) -> Result<Self, PlanError> {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let chain = robot.chain();
        let mut joints = Vec::with_capacity(count);
        let tries = count.saturating_mul(DRAWS_PER_CANDIDATE).max(1);
        let mut tried = 0;
        while joints.len() < count && tried < tries {
            tried += 1;
            let q = random_configuration(chain, SAMPLING_MARGIN, &mut rng);
            let inside = match workspace {
                Some(b) => chain.tool_pose(&q).is_ok_and(|p| b.contains(&p.translation.vector)),
                None => true,
            };
            if inside {
                joints.push(q);
            }
        }
        if joints.len() < count {
            return Err(PlanError::EmptyBox { found: joints.len(), wanted: count, tried });
        }
        let lines = (1..=count).collect();
        Ok(Self { joints, lines, from_file: false, copies: Vec::new() })
    }

    /// The configurations.
    pub fn joints(&self) -> &[Vec<f64>] {
        &self.joints
    }

    /// The 1-based file line of candidate `i` (0-based), when the candidates were read from a file.
    pub fn line_of(&self, i: usize) -> Option<usize> {
        if self.from_file { self.lines.get(i).copied() } else { None }
    }

    /// Number of candidates.
    pub fn len(&self) -> usize {
        self.joints.len()
    }

    /// `true` when there are none.
    pub fn is_empty(&self) -> bool {
        self.joints.is_empty()
    }
}

/// Checks one configuration's length and values; `index` is its line or 1-based index.
pub(crate) fn check(robot: &Robot, q: &[f64], what: &'static str, index: usize) -> Result<(), PlanError> {
    let dof = robot.chain().dof();
    if q.len() != dof {
        return Err(PlanError::JointCount { what, index, got: q.len(), dof });
    }
    if let Some(j) = q.iter().position(|v| !v.is_finite()) {
        return Err(PlanError::NotFinite { what, index, joint: j + 1 });
    }
    Ok(())
}
