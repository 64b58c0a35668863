//! The design problem: the identification Jacobian of the diagnosis' model at every candidate and
//! measured pose — the same [`Model`] and analytic Jacobian the diagnosis fits (`thermokin-identify`),
//! evaluated at the nominal robot, since a plan is made before anything is measured — reduced to the
//! columns the candidates can identify and scaled.

use faer::linalg::matmul::matmul;
use faer::{Accum, Mat, Par};
use nalgebra::Vector3;
use rayon::prelude::*;
use thermokin_chain::{Dataset, Measurement, Robot, units};
use thermokin_identify::{
    Effect, Eligibility, FixedParameter, Model, PoseTerms, Setup, arc_needed, frame_refitted_weight, identifiable,
    residuals_and_jacobian, travel,
};

use crate::error::PlanError;
use crate::params::{BeyondArcs, Params, Region};
use crate::report::LeftOut;

/// Poses per chunk of the Jacobian's parallel evaluation.
const CHUNK: usize = 256;

/// The model a plan is made for, and its Jacobian at the candidates and at the measured poses.
pub(crate) struct Design {
    /// The model: the blocks always estimated (registration, unknown tool), then the effects.
    pub model: Model,
    /// The columns the candidates and measured poses together can identify (model column indices).
    pub free: Vec<usize>,
    /// The model's columns they cannot, each with its reason.
    pub not_identifiable: Vec<FixedParameter>,
    /// Per free column, its root-mean-square per pose over the candidates and the measured poses (the
    /// scale the criterion is taken in).
    pub scale: Vec<f64>,
    /// Rows `3i..3i+3`: candidate `i`'s position rows on the free columns, divided by `scale`.
    pub candidates: Mat<f64>,
    /// The measured poses' rows, the same way.
    pub measured: Mat<f64>,
    /// Nominal tool positions of the candidates, mm (the robot's base frame).
    pub positions: Vec<Vector3<f64>>,
    /// `W`: the mean over the poses of use ([`crate::Region`]; one beyond the candidates' arcs taken at
    /// its nearest candidate unless [`BeyondArcs::AsGiven`]) of `M̃ᵢᵀ M̃ᵢ`, `M̃` their rows with the
    /// frame a test re-measures projected out ([`thermokin_identify::frame_refitted_weight`]) — so that `trace(W Σ)` is the mean
    /// squared error of the predicted tool position over the poses of use, once that frame is fitted
    /// there, of a parameter covariance `Σ` (scaled columns).
    pub use_weight: Mat<f64>,
    /// [`Design::use_weight`] of the poses of use as given, where some reach beyond the candidates' arcs
    /// and `use_weight` takes them at their nearest candidates ([`BeyondArcs::Nearest`]): what the model
    /// planned for, taken as the robot there too, would promise at them.
    pub as_given_weight: Option<Mat<f64>>,
    /// The poses of use.
    pub region_poses: usize,
    /// How many poses of use reach beyond the candidates' arcs and are planned for at their nearest
    /// candidate or measured pose ([`BeyondArcs::Nearest`]).
    pub at_nearest: usize,
    /// The free columns of the frame a test re-measures (registration, unknown tool), fitted again on
    /// the poses of use: what their fit takes of a test's own noise.
    pub refitted: usize,
    /// The catalogue effects left out: the diagnosis refuses them on any choice of the candidates.
    pub left_out: Vec<LeftOut>,
}

/// A data set of configurations at their nominal tool positions (the Jacobian needs no measurement).
fn nominal_set(robot: &Robot, joints: &[Vec<f64>]) -> Result<Dataset, PlanError> {
    let measurements = joints
        .iter()
        .map(|q| {
            Ok(Measurement {
                time_min: 0.0,
                q: q.clone(),
                position_mm: robot
                    .chain()
                    .tool_pose(q)
                    .map_err(thermokin_identify::IdentifyError::from)?
                    .translation
                    .vector,
                orientation: None,
                position_std_mm: None,
                temps: Vec::new(),
            })
        })
        .collect::<Result<Vec<_>, PlanError>>()?;
    Ok(Dataset { measurements, ..Dataset::default() })
}

/// The effects a plan is made for: the setup's always-estimated blocks, then the given effects or the
/// catalogue's pose-dependent ones that some choice of the candidates (`pool`, beside the `measured`
/// poses) can make eligible for the diagnosis — and the catalogue's others, left out with the reason.
fn effects(
    robot: &Robot,
    pool: &Dataset,
    measured: &Dataset,
    params: &Params,
) -> Result<(Vec<Effect>, Vec<LeftOut>), PlanError> {
    let setup = Setup { frame: params.frame, tool: params.tool, orientation_lever_mm: 0.0, lateral: params.lateral };
    let mut effects = setup.always_estimated(pool);
    let mut left_out = Vec::new();
    let chosen = match &params.effects {
        Some(e) => e.clone(),
        None => {
            let mut kept = Vec::new();
            for e in setup.candidates(robot, pool)? {
                match out_of_reach(robot, pool, measured, e, &params.eligibility) {
                    Some(reason) => left_out.push(LeftOut { effect: e.label(), reason }),
                    None => kept.push(e),
                }
            }
            kept
        }
    };
    for e in chosen {
        if !effects.contains(&e) {
            effects.push(e);
        }
    }
    Ok((effects, left_out))
}

/// The lowest and highest value of joint `j` over the configurations `qs`.
pub(crate) fn arc<'a>(qs: impl Iterator<Item = &'a [f64]>, j: usize) -> (f64, f64) {
    qs.fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), q| (l.min(q[j]), h.max(q[j])))
}

/// How far a pose of use may reach beyond the candidates' arc on a joint and still count as within it,
/// degrees (millimetres on a slide): the rounding of a taught program's joints, not an arc of its own.
pub(crate) const ARC_MARGIN: f64 = 1.0;

/// Per joint, the lowest and highest value over the candidates and the measured poses.
pub(crate) fn arcs(robot: &Robot, candidates: &[Vec<f64>], measured: &[Vec<f64>]) -> Vec<(f64, f64)> {
    (0..robot.chain().dof()).map(|j| arc(candidates.iter().chain(measured).map(Vec::as_slice), j)).collect()
}

/// Whether `q` reaches beyond `arcs` ([`arcs`]) on some joint by more than [`ARC_MARGIN`].
fn reaches_beyond(robot: &Robot, arcs: &[(f64, f64)], q: &[f64]) -> bool {
    robot.chain().joints().iter().zip(arcs).zip(q).any(|((joint, &(lo, hi)), &v)| {
        let ext = |x: f64| units::joint_value_out(joint.kind, x);
        ext(lo) - ext(v) > ARC_MARGIN || ext(v) - ext(hi) > ARC_MARGIN
    })
}

/// The configurations a plan for prediction chooses for, one per pose of use: the pose itself, or —
/// where it reaches beyond the candidates' arcs and `beyond` is [`BeyondArcs::Nearest`] — the nearest
/// candidate or measured pose, joint differences in fractions of each joint's travel (a slide's
/// millimetres and a wrist's radians weigh by how much of their range they are). With how many were
/// replaced.
fn stand_ins(
    robot: &Robot,
    poses: &[Vec<f64>],
    candidates: &[Vec<f64>],
    measured: &[Vec<f64>],
    beyond: BeyondArcs,
) -> (Vec<Vec<f64>>, usize) {
    if beyond == BeyondArcs::AsGiven {
        return (poses.to_vec(), 0);
    }
    let arcs = arcs(robot, candidates, measured);
    let travel: Vec<f64> = (0..robot.chain().dof()).map(|j| travel(robot, j).max(f64::MIN_POSITIVE)).collect();
    let distance =
        |a: &[f64], b: &[f64]| a.iter().zip(b).zip(&travel).map(|((x, y), t)| ((x - y) / t).powi(2)).sum::<f64>();
    let mut replaced = 0;
    let out = poses
        .iter()
        .map(|q| {
            if !reaches_beyond(robot, &arcs, q) {
                return q.clone();
            }
            replaced += 1;
            let nearest = candidates.iter().chain(measured).min_by(|a, b| distance(a, q).total_cmp(&distance(b, q)));
            nearest.unwrap_or(q).clone()
        })
        .collect();
    (out, replaced)
}

/// Why no choice of the candidates can make `e` eligible for the diagnosis: its joint's arc over every
/// candidate and measured pose is shorter than `e` needs ([`thermokin_identify::arc_needed`]).
fn out_of_reach(robot: &Robot, pool: &Dataset, measured: &Dataset, e: Effect, rules: &Eligibility) -> Option<String> {
    let (j, need) = arc_needed(robot, e, rules)?;
    let (lo, hi) = arc(pool.measurements.iter().chain(&measured.measurements).map(|m| m.q.as_slice()), j);
    let travel = travel(robot, j);
    (hi - lo < need).then(|| {
        format!(
            "joint {} spans {:.1}° … {:.1}° over every candidate{} ({:.0} % of its {:.0}° travel); {} needs {:.0}°",
            j + 1,
            units::degrees(lo),
            units::degrees(hi),
            if measured.is_empty() { "" } else { " and measured pose" },
            100.0 * (hi - lo) / travel,
            units::degrees(travel),
            e.kind_name(),
            units::degrees(need)
        )
    })
}

/// The Jacobian of the model's predicted positions at `data`'s poses (3 rows each), in parallel chunks.
fn jacobian(robot: &Robot, model: &Model, data: &Dataset) -> Result<Mat<f64>, PlanError> {
    let terms = PoseTerms::of(robot, data, 0.0);
    let theta = model.initial();
    let n = data.len();
    let chunks: Vec<(usize, Mat<f64>)> = (0..n.div_ceil(CHUNK))
        .into_par_iter()
        .map(|c| {
            let rows: Vec<usize> = (c * CHUNK..((c + 1) * CHUNK).min(n)).collect();
            residuals_and_jacobian(robot, model, &theta, data, &rows, &terms).map(|(_, j)| (c * CHUNK, j))
        })
        .collect::<Result<_, _>>()?;
    let mut jac = Mat::zeros(3 * n, model.len());
    for (start, block) in chunks {
        for r in 0..block.nrows() {
            for c in 0..block.ncols() {
                jac[(3 * start + r, c)] = block[(r, c)];
            }
        }
    }
    Ok(jac)
}

impl Design {
    /// The design for `candidates` after `measured` poses.
    pub fn new(
        robot: &Robot,
        candidates: &[Vec<f64>],
        measured: &[Vec<f64>],
        params: &Params,
    ) -> Result<Self, PlanError> {
        let pool = nominal_set(robot, candidates)?;
        let done = nominal_set(robot, measured)?;
        let (effects, left_out) = effects(robot, &pool, &done, params)?;
        let model = Model::new(robot, effects)?;
        let jac_pool = jacobian(robot, &model, &pool)?;
        let jac_done = jacobian(robot, &model, &done)?;
        // Identifiable from everything that may be measured: the candidates and the poses already measured.
        let mut all = Mat::zeros(jac_pool.nrows() + jac_done.nrows(), model.len());
        all.as_mut().submatrix_mut(0, 0, jac_pool.nrows(), model.len()).copy_from(&jac_pool);
        all.as_mut().submatrix_mut(jac_pool.nrows(), 0, jac_done.nrows(), model.len()).copy_from(&jac_done);
        let ident = identifiable(all.as_ref(), &vec![true; model.len()]);
        let free: Vec<usize> = (0..model.len()).filter(|&c| ident.free[c]).collect();
        // Over the candidates and the measured poses: a column seen by the measured poses alone keeps a
        // finite scale (it is free, so its norm over all rows is not zero).
        let n = (candidates.len() + measured.len()).max(1) as f64;
        let scale: Vec<f64> = free
            .iter()
            .map(|&c| ((0..all.nrows()).map(|r| all[(r, c)].powi(2)).sum::<f64>() / n).sqrt().max(f64::MIN_POSITIVE))
            .collect();
        let reduce = |j: &Mat<f64>| Mat::from_fn(j.nrows(), free.len(), |r, k| j[(r, free[k])] / scale[k]);
        let candidates_rows = reduce(&jac_pool);
        let refitted = thermokin_identify::refitted_frame(&model, &free);
        let weight_at = |poses: &[Vec<f64>]| -> Result<Mat<f64>, PlanError> {
            let rows = reduce(&jacobian(robot, &model, &nominal_set(robot, poses)?)?);
            Ok(frame_refitted_weight(&rows, &refitted))
        };
        let (use_weight, as_given_weight, region_poses, at_nearest) = match &params.region {
            Region::Candidates => (frame_refitted_weight(&candidates_rows, &refitted), None, candidates.len(), 0),
            Region::Poses(poses) => {
                for (i, q) in poses.iter().enumerate() {
                    crate::candidates::check(robot, q, "pose of use", i + 1)?;
                }
                let (chosen_for, at_nearest) = stand_ins(robot, poses, candidates, measured, params.beyond_arcs);
                let as_given = (at_nearest > 0).then(|| weight_at(poses)).transpose()?;
                (weight_at(&chosen_for)?, as_given, poses.len(), at_nearest)
            }
        };
        Ok(Self {
            left_out,
            not_identifiable: model.fixed_parameters(&ident.fixed),
            use_weight,
            as_given_weight,
            region_poses,
            at_nearest,
            refitted: refitted.len(),
            candidates: candidates_rows,
            measured: reduce(&jac_done),
            positions: pool.measurements.iter().map(|m| m.position_mm).collect(),
            free,
            scale,
            model,
        })
    }

    /// The scaled rows of candidates `rows`, after the measured poses' rows.
    pub fn rows_with_measured(&self, rows: &[usize]) -> Mat<f64> {
        let m = self.measured.nrows();
        Mat::from_fn(m + 3 * rows.len(), self.free.len(), |r, c| {
            if r < m { self.measured[(r, c)] } else { self.candidates[(3 * rows[(r - m) / 3] + (r - m) % 3, c)] }
        })
    }
}

/// `a · b` (a new matrix).
pub(crate) fn product(a: faer::MatRef<'_, f64>, b: faer::MatRef<'_, f64>) -> Mat<f64> {
    let mut out = Mat::zeros(a.nrows(), b.ncols());
    matmul(out.as_mut(), Accum::Replace, a, b, 1.0, Par::Seq);
    out
}

#[cfg(test)]
#[allow(clippy::unwrap_used)] // Tests unwrap to fail.
mod tests {
    use super::{BeyondArcs, stand_ins};

    /// A pose of use within the candidates' arcs (or beyond them by less than a degree) is planned for as
    /// given; one beyond them on a joint is planned for at the candidate nearest to it, in fractions of
    /// each joint's travel — not the candidate nearest in raw radians; `AsGiven` keeps every pose.
    #[test]
    fn a_pose_of_use_beyond_the_candidates_arcs_stands_in_at_its_nearest_candidate() {
        let robot = thermokin_io::read_robot(&thermokin_testdata::workspace("configs/irb140.toml")).unwrap();
        let deg = |v: [f64; 6]| v.iter().map(|x| x.to_radians()).collect::<Vec<f64>>();
        let candidates = vec![
            deg([-90.0, -30.0, -40.0, -100.0, -60.0, -150.0]),
            deg([90.0, 30.0, 40.0, 100.0, 60.0, 150.0]),
            deg([0.0, 0.0, 0.0, 0.0, 0.0, 0.0]),
        ];
        let inside = deg([10.0, 5.0, -5.0, 20.0, 0.0, 30.0]);
        let barely = deg([90.5, 0.0, 0.0, 0.0, 0.0, 0.0]);
        // Beyond joint 1's arc by 30°; nearest to the second candidate once each joint's travel weighs
        // in (joint 6's 150° is a small part of its travel), nearest to the third in raw radians.
        let beyond = deg([120.0, 20.0, 30.0, 60.0, 40.0, 0.0]);
        let poses = vec![inside.clone(), barely.clone(), beyond.clone()];
        let (out, replaced) = stand_ins(&robot, &poses, &candidates, &[], BeyondArcs::Nearest);
        assert_eq!(replaced, 1);
        assert_eq!(out, vec![inside, barely, candidates[1].clone()]);
        let raw = |a: &[f64]| a.iter().zip(&beyond).map(|(x, y)| (x - y).powi(2)).sum::<f64>();
        assert!(raw(&candidates[2]) < raw(&candidates[1]), "the case must tell the two distances apart");
        let (out, replaced) = stand_ins(&robot, &poses, &candidates, &[], BeyondArcs::AsGiven);
        assert_eq!((out, replaced), (poses, 0));
    }
}
