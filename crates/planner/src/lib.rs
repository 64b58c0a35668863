#![doc = include_str!("../README.md")]
//! `thermokin-planner`: which poses to measure. From candidate poses (the user's taught, collision-free
//! ones, or sampled within the joint limits and a workspace box), it chooses the poses that make the
//! calibrated model's predicted error smallest where the robot will work ([`Region`]; I-optimal) — or
//! the parameters the diagnosis considers identifiable and precise (D-optimal) — on the same model and
//! Jacobian the diagnosis fits (`thermokin-identify`), after the poses already measured when there are
//! some; puts them in a measuring order that keeps joint motion short, and says what they promise at the
//! poses of use against random poses of the same pool ([`Promise`]), and what stays unidentifiable and why.
//!
//! ```
//! use thermokin_planner::{Candidates, Params, Poses, plan};
//! let robot = thermokin_chain::Robot::new("irb140", thermokin_testdata::irb140_table9());
//! let pool = Candidates::sampled(&robot, 300, 7, None).unwrap();
//! let plan = plan(&robot, &pool, &[], &Params { poses: Poses::Exactly(20), ..Params::default() }).unwrap();
//! assert_eq!(plan.poses.len(), 20);
//! // Each pose is one of the candidates, values unchanged.
//! assert!(plan.poses.iter().all(|p| pool.joints()[p.candidate] == p.joints_rad));
//! // The criterion (the mean predicted variance over the candidates) never rises as poses are added.
//! assert!(plan.criterion_by_pose.windows(2).all(|w| w[1] <= w[0] * (1.0 + 1e-9)));
//! ```

mod candidates;
mod design;
mod error;
mod order;
mod params;
mod precision;
mod report;
mod select;

use thermokin_chain::{Robot, units};

pub use candidates::{Candidates, DEFAULT_SAMPLES};
pub use error::PlanError;
pub use params::{BeyondArcs, Criterion, Params, Poses, Region, WorkspaceBox};
pub use report::{
    Beyond, Comparison, CountRule, JointCoverage, LeftOut, Motion, ParameterPrecision, Plan, PlannedPose, PosesOfUse,
    Promise,
};
pub use select::RIDGE;

use crate::design::Design;
use crate::precision::{Precision, median, precision, random_sets};

/// Fraction of an effect's remaining variance a pose must remove for the report to say it helps that
/// effect: a half — the pose does as much for it as everything chosen before.
const HELPS: f64 = 0.5;

/// Plans `params.poses` poses out of `candidates` after the `measured` configurations (radians; mm for
/// a prismatic joint).
pub fn plan(robot: &Robot, candidates: &Candidates, measured: &[Vec<f64>], params: &Params) -> Result<Plan, PlanError> {
    params.validate()?;
    for (i, q) in measured.iter().enumerate() {
        candidates::check(robot, q, "measured pose", i + 1)?;
    }
    // An automatic count plans at most every candidate.
    let count = match params.poses {
        Poses::Exactly(n) => Poses::Exactly(n),
        Poses::Auto { at_most } => Poses::Auto { at_most: at_most.min(candidates.len()) },
    };
    let wanted = count.at_most();
    if wanted > candidates.len() {
        let copies = candidates.copies().len();
        return Err(PlanError::TooFewCandidates { poses: wanted, candidates: candidates.len(), copies });
    }
    let design = Design::new(robot, candidates.joints(), measured, params)?;
    let select::Chosen { rows: selected, stop } =
        select::choose(&design, count, params.criterion).ok_or(PlanError::Singular)?;
    let planned = precision(&design, &selected);
    let random = random_sets(&design, selected.len(), params.random_draws, params.seed);
    let chosen: Vec<Vec<f64>> = selected.iter().map(|&i| candidates.joints()[i].clone()).collect();
    // The order on the joints as the controller moves them: degrees, mm for a prismatic joint.
    let chosen_external: Vec<Vec<f64>> = chosen.iter().map(|q| external(robot, q)).collect();
    let from = measured.last().map(|q| external(robot, q));
    let order = order::measuring_order(&chosen_external, from.as_deref());
    let in_order: Vec<usize> = order.iter().map(|&k| selected[k]).collect();
    let (criterion_by_pose, reduction) =
        select::along(&design, &in_order, params.criterion).ok_or(PlanError::Singular)?;
    let poses = order
        .iter()
        .zip(&reduction)
        .map(|(&k, reduced)| {
            let i = selected[k];
            let p = design.positions[i];
            PlannedPose {
                candidate: i,
                line: candidates.line_of(i),
                joints: chosen_external[k].clone(),
                joints_rad: chosen[k].clone(),
                nominal_position_mm: [p.x, p.y, p.z],
                helps: helps(&design, reduced),
            }
        })
        .collect();
    let mut visited: Vec<Vec<f64>> = measured.to_vec();
    visited.extend(chosen.iter().cloned());
    let identity: Vec<usize> = (0..chosen.len()).collect();
    let motion = Motion {
        ordered: order::path_length(&chosen_external, from.as_deref(), &order),
        as_chosen: order::path_length(&chosen_external, from.as_deref(), &identity),
    };
    Ok(Plan {
        criterion: params.criterion,
        candidates: candidates.len(),
        copies: candidates.copies().to_vec(),
        measured: measured.len(),
        noise_mm: params.noise_mm,
        effects: design.model.effects().iter().map(|e| e.label()).collect(),
        poses,
        criterion_by_pose,
        comparison: comparison(&planned, &random),
        promise: promise(&design, params, &planned, &random),
        beyond_candidates: match &params.region {
            Region::Poses(poses) => beyond(robot, poses, candidates.joints(), measured),
            Region::Candidates => Vec::new(),
        },
        count: match count {
            Poses::Auto { at_most } => Some(CountRule {
                at_most,
                stopped: stop.map(|s| [s.next_gain * params.noise_mm, s.resolution * params.noise_mm]),
            }),
            Poses::Exactly(_) => None,
        },
        parameters: parameters(&design, &planned, &random, params.noise_mm),
        not_identifiable: planned.not_identifiable.clone(),
        never_identifiable: design.not_identifiable.clone(),
        left_out: design.left_out.clone(),
        coverage: coverage(robot, &visited),
        motion,
    })
}

/// Joint values as the controller and the files take them: degrees, mm for a prismatic joint.
fn external(robot: &Robot, q: &[f64]) -> Vec<f64> {
    robot.chain().joints().iter().zip(q).map(|(j, &v)| units::joint_value_out(j.kind, v)).collect()
}

/// The reported effects a pose removed at least [`HELPS`] of the remaining variance of (in one of their
/// parameters), given the fraction it removed per free column.
fn helps(design: &Design, reduced: &[f64]) -> Vec<String> {
    let mut out: Vec<String> = Vec::new();
    for (c, &col) in design.free.iter().enumerate() {
        let Some((effect, _)) = design.model.parameter(col) else { continue };
        let label = effect.label();
        if effect.is_reported() && reduced[c] >= HELPS && !out.contains(&label) {
            out.push(label);
        }
    }
    out
}

/// The joints along which the poses of use reach more than [`design::ARC_MARGIN`] (a degree; a slide: a
/// millimetre) beyond every candidate's and measured pose's arc.
fn beyond(robot: &Robot, poses: &[Vec<f64>], candidates: &[Vec<f64>], measured: &[Vec<f64>]) -> Vec<Beyond> {
    let ext = |j: usize, v: f64| units::joint_value_out(robot.chain().joints()[j].kind, v);
    let arcs = design::arcs(robot, candidates, measured);
    (0..robot.chain().dof())
        .filter_map(|j| {
            let (lo, hi) = design::arc(poses.iter().map(Vec::as_slice), j);
            let (c_lo, c_hi) = arcs[j];
            let out = (ext(j, c_lo) - ext(j, lo)).max(ext(j, hi) - ext(j, c_hi));
            (out > design::ARC_MARGIN).then(|| Beyond {
                joint: j + 1,
                use_arc: [ext(j, lo), ext(j, hi)],
                candidates_arc: [ext(j, c_lo), ext(j, c_hi)],
            })
        })
        .collect()
}

/// The predicted held-out error at the poses of use ([`Promise`]).
fn promise(design: &Design, params: &Params, planned: &Precision, random: &[Precision]) -> Promise {
    let rms = |v: f64| params.noise_mm * select::heldout_rms(design, v);
    Promise {
        region: match params.region {
            Region::Candidates => PosesOfUse::Candidates,
            Region::Poses(_) => PosesOfUse::Given,
        },
        poses_of_use: design.region_poses,
        planned_at_nearest: design.at_nearest,
        planned_as_given_rms_mm: planned.variance_as_given.map(rms).filter(|r| r.is_finite()),
        refitted: design.refitted,
        noise_mm: params.noise_mm,
        planned_rms_mm: rms(planned.variance),
        planned_model_rms_mm: params.noise_mm * planned.variance.max(0.0).sqrt(),
        random_rms_mm: median(random.iter().map(|r| r.variance.is_finite().then(|| rms(r.variance)))),
        resolution: select::resolution(design),
    }
}

/// The plan's criterion and indices against the random draws' medians.
fn comparison(planned: &Precision, random: &[Precision]) -> Comparison {
    let med = |f: fn(&thermokin_identify::Observability) -> f64| {
        median(random.iter().map(|r| r.observability.as_ref().map(f))).unwrap_or(f64::INFINITY)
    };
    let random_observability =
        random.first().and_then(|r| r.observability.clone()).map(|o| thermokin_identify::Observability {
            condition_number: med(|o| o.condition_number),
            o1: med(|o| o.o1),
            o2: med(|o| o.o2),
            o3: med(|o| o.o3),
            o4: med(|o| o.o4),
            o5: med(|o| o.o5),
            ..o
        });
    Comparison {
        random_draws: random.len(),
        planned_criterion: planned.criterion,
        random_criterion: median(random.iter().map(|r| Some(r.criterion))).unwrap_or(f64::NEG_INFINITY),
        planned: planned.observability.clone(),
        random: random_observability,
    }
}

/// Every free parameter's predicted standard deviation at the noise, planned and random (median), in
/// report units.
fn parameters(design: &Design, planned: &Precision, random: &[Precision], noise_mm: f64) -> Vec<ParameterPrecision> {
    let names = design.model.parameter_names();
    design
        .free
        .iter()
        .enumerate()
        .filter_map(|(c, &col)| {
            let (effect, k) = design.model.parameter(col)?;
            let report = |s: Option<f64>| s.map(|s| effect.to_report_units(k, s * noise_mm).abs());
            Some(ParameterPrecision {
                parameter: names[col].clone(),
                planned: report(planned.sigma_per_mm[c]),
                random: report(median(random.iter().map(|r| r.sigma_per_mm[c]))),
            })
        })
        .collect()
}

/// The arc each joint covers over `poses`, against its travel.
fn coverage(robot: &Robot, poses: &[Vec<f64>]) -> Vec<JointCoverage> {
    robot
        .chain()
        .joints()
        .iter()
        .enumerate()
        .map(|(j, joint)| {
            let (lo, hi) = design::arc(poses.iter().map(Vec::as_slice), j);
            let travel = thermokin_identify::travel(robot, j);
            let ext = |v: f64| units::joint_value_out(joint.kind, v);
            JointCoverage { joint: j + 1, arc: [ext(lo), ext(hi)], fraction_of_travel: ((hi - lo) / travel).min(1.0) }
        })
        .collect()
}
