//! Eligibility, before any selection: a candidate whose parameters these data cannot pin down is not
//! selectable, and the report says what to measure instead.
//!
//! Six rules, each stated with its threshold:
//! - **Coverage.** An effect that is a function of its joint's own angle (a gear-ratio scale, a cyclic
//!   encoder error) needs the arc [`thermokin_identify::arc_needed`] gives — a quarter of the travel
//!   ([`Eligibility::min_travel_fraction`]), half a revolution for a cyclic error; the rule, and why, is
//!   `thermokin-identify`'s, which the measurement planner plans by too. A gravity compliance needs a joint gravity loads at all (`τ_max`, the
//!   largest gravity torque over the joint space, sampled, above a millionth of the largest joint's).
//! - **A deflection told from an offset.** A compliance is identified from how the gravity torque changes
//!   beside its level: where it changes little, `k·τ` is an offset `k·τ̄` and a remainder. Judged in the
//!   fit it would join — the always-estimated blocks and the zero offsets of the joints it deflects —
//!   by the report's criterion for a nearly unidentifiable pair (correlation above
//!   [`NEARLY_DEPENDENT`]), not by a fraction of the torque range: how many poses sit in a range, and how
//!   precisely they are measured, decide what it pins down. On sixty random poses of the real UR10's
//!   series C, whose shoulder torque spans 18–22 % of its range, the shoulder compliance is eligible
//!   (its estimate's correlation with joint 2's offset stays within ±0.99); on the paper's static set,
//!   where joint 5's spans 20 %, it is not (−0.9954).
//! - **Both sides.** A backlash needs the joint reached rising and falling in the measuring order, at
//!   least [`MIN_POSES_EACH_SIDE`] poses each in the training part of every fold of the selection.
//! - **Temperature.** A drift per kelvin needs the temperature to move: at least
//!   [`Eligibility::min_temperature_span_k`] (2 K by default: over 2 K a 1 m steel link grows by 23 µm,
//!   the order of a laser tracker's noise — below it a fitted coefficient is mostly noise and whatever
//!   else drifted).
//! - **Room for a lumped load.** A compliance without masses lumps its loads into many weights (a
//!   lateral one two per link carried and three more: 26 for a six-joint arm's base): it needs every
//!   fit of the selection (each fold's training part) to hold [`crate::MIN_REDUNDANCY`] residual rows per
//!   parameter of it and the always-estimated blocks — the gross-error screen's rule for the same
//!   effects. On fewer, its weights bend to the fold's noise: offered to the real Rokae's 30 poses, the
//!   base's lateral compliance (26 weights in folds of 72 rows) was chosen and the nested held-out mean
//!   rose from 0.1161 to 0.1219 mm (6-D: 0.1397 to 0.1528).
//! - **Nuisance.** A parameter whose estimate would move with one of the always-estimated blocks'
//!   (tracker registration, unknown tool point) — correlation of the two estimates above
//!   [`NEARLY_DEPENDENT`], the report's criterion for a nearly unidentifiable pair, at which each
//!   one's standard deviation is inflated 7× — is a re-description of the frame, not an effect of the
//!   robot. (Exact equivalences are not refused here: the identifiability gate fixes those parameters
//!   and the block is scored with the rest.)

use faer::linalg::solvers::DenseSolveCore;
use thermokin_chain::{Dataset, units};
use thermokin_identify::{DriftShape, Effect, JointIndex, NEARLY_DEPENDENT, arc_needed, identifiable, travel};

use crate::config::Eligibility;
use crate::error::DiagnoseError;
use crate::report::Refusal;
use crate::scoring::Scorer;
use crate::stats::span;

/// The fewest poses a backlash needs reached from each side in every fit of the selection (each fold's
/// training part): its column is `±1`, the play the difference of the two groups' means — ten poses a side
/// put its half at a quarter of the noise (`σ/2 · √(2/10)`).
pub const MIN_POSES_EACH_SIDE: usize = 10;

/// Splits `candidates` into the selectable ones and the refused ones. `nuisance` are the always-estimated
/// blocks.
pub(crate) fn check(
    scorer: &Scorer<'_>,
    nuisance: &[Effect],
    candidates: &[Effect],
    rules: &Eligibility,
) -> Result<(Vec<Effect>, Vec<Refusal>), DiagnoseError> {
    let mut eligible = Vec::new();
    let mut refused = Vec::new();
    for &c in candidates {
        let verdict = match coverage(scorer, c, rules).or_else(|| room_for(scorer, nuisance, c)) {
            Some(r) => Some(r),
            None => match c {
                Effect::JointCompliance(_) | Effect::ComplianceCoupling(_) => offset_trade(scorer, nuisance, c)?,
                _ => nuisance_trade(scorer, nuisance, c)?,
            },
        };
        match verdict {
            Some(r) => refused.push(r),
            None => eligible.push(c),
        }
    }
    Ok((eligible, refused))
}

/// `x` with three significant digits (a torque of a light wrist is milli-newton-metres: a fixed number
/// of decimals would print it as 0.0).
fn significant(x: f64) -> String {
    if x == 0.0 || !x.is_finite() {
        return format!("{x}");
    }
    let decimals = (2 - x.abs().log10().floor() as i32).max(0) as usize;
    format!("{x:.decimals$}")
}

/// The arc `(lowest, highest)` joint `j` covers in the data.
pub(crate) fn arc(data: &Dataset, j: usize) -> (f64, f64) {
    span(data.measurements.iter().map(|m| m.q[j]))
}

/// A compliance without masses' rule: every fit of the selection holds [`crate::MIN_REDUNDANCY`] residual
/// rows per parameter of it and the always-estimated blocks.
fn room_for(scorer: &Scorer<'_>, always: &[Effect], e: Effect) -> Option<Refusal> {
    if !matches!(e, Effect::LumpedCompliance(..) | Effect::LumpedLateralCompliance(..) | Effect::BranchLoad(..)) {
        return None;
    }
    let nuisance: usize = always.iter().map(Effect::len).sum();
    let parameters = nuisance + e.len();
    let stride = scorer.terms.stride();
    let fewest = scorer.folds.iter().map(|(train, _)| train.len()).min().unwrap_or(0).min(scorer.data.len());
    (fewest * stride < crate::MIN_REDUNDANCY * parameters).then(|| Refusal {
        effect: e.label(),
        reason: format!(
            "its {} weights (its loads lumped: the robot file has no masses) with the frame's {nuisance} parameters need {} residual rows in every fit of the selection; a fit sees as few as {} ({fewest} poses)",
            e.len(),
            crate::MIN_REDUNDANCY * parameters,
            fewest * stride
        ),
        remedy: format!(
            "measure at least {} poses, or give the robot file's link masses (a compliance on them has one parameter per direction)",
            (crate::MIN_REDUNDANCY * parameters).div_ceil(stride) * scorer.data.len().max(1) / fewest.max(1)
        ),
    })
}

/// A backlash's rule: the joint reached from both sides in every fit of the selection
/// ([`MIN_POSES_EACH_SIDE`]).
fn both_sides(scorer: &Scorer<'_>, e: Effect, j: JointIndex) -> Option<Refusal> {
    let counts = |rows: &[usize]| thermokin_identify::approach_counts(scorer.data, rows.iter().copied(), j.index());
    let (up, down) = counts(&scorer.all());
    // What every fit of the selection sees: the fewest from one side in a fold's training part.
    let fewest = scorer
        .folds
        .iter()
        .map(|(train, _)| {
            let (u, d) = counts(train);
            u.min(d)
        })
        .min()
        .unwrap_or(0)
        .min(up.min(down));
    (fewest < MIN_POSES_EACH_SIDE).then(|| Refusal {
        effect: e.label(),
        reason: format!(
            "in the measuring order joint {} reached {up} poses rising and {down} falling, and a fit of the selection's folds sees as few as {fewest} from one side; a backlash needs {MIN_POSES_EACH_SIDE} from each side in every fit",
            j.number()
        ),
        remedy: format!(
            "measure at least {MIN_POSES_EACH_SIDE} poses with joint {} arriving from each side (alternate the direction of approach)",
            j.number()
        ),
    })
}

fn coverage(scorer: &Scorer<'_>, e: Effect, rules: &Eligibility) -> Option<Refusal> {
    let robot = scorer.robot;
    match e {
        Effect::JointScale(j) | Effect::Periodic(j) | Effect::Straightness(j)
            if arc_needed(robot, e, rules).is_some() =>
        {
            let (lo, hi) = arc(scorer.data, j.index());
            let t = travel(robot, j.index());
            let need = arc_needed(robot, e, rules).map_or(0.0, |(_, need)| need);
            // A slide's stroke in millimetres, a revolute joint's arc in degrees.
            let (shown, unit): (fn(f64) -> f64, &str) = match robot.chain().joints()[j.index()].kind {
                thermokin_chain::JointKind::Revolute => (units::degrees, "°"),
                thermokin_chain::JointKind::Prismatic => (|v| v, " mm"),
            };
            (hi - lo < need).then(|| Refusal {
                effect: e.label(),
                reason: format!(
                    "joint {} covers {:.1}{unit} … {:.1}{unit} only ({:.0}% of its {:.0}{unit} travel); {} needs {:.0}{unit}",
                    j.number(),
                    shown(lo),
                    shown(hi),
                    100.0 * (hi - lo) / t,
                    shown(t),
                    e.kind_name(),
                    shown(need)
                ),
                remedy: format!("measure joint {} over at least {:.0}{unit} of its travel", j.number(), shown(need)),
            })
        }
        Effect::Backlash(j) => both_sides(scorer, e, j),
        Effect::JointCompliance(j) => {
            let j = j.index();
            let torques = &scorer.scale.max_torque_nm;
            let bound = torques[j];
            // Rounding in the torque sum leaves ~1e-15 of the largest torque on an axis gravity never
            // loads; a millionth of it is a torque no joint deflects under.
            if bound <= 1e-6 * torques.iter().copied().fold(0.0, f64::max) {
                return Some(Refusal {
                    effect: e.label(),
                    reason: format!(
                        "gravity never loads joint {} (its largest gravity torque over the joint space is {bound:.1e} N·m): a compliance there moves nothing",
                        j + 1
                    ),
                    remedy: "nothing to measure: the axis is vertical in every pose, or the masses beyond it sit on its axis or are missing from the robot description".into(),
                });
            }
            None
        }
        Effect::ComplianceCoupling(j) => {
            // Each joint of the pair moves with the other's torque: gravity must load both; the first
            // refusal of the two is the coupling's.
            let next = j.next(robot)?;
            [j, next].into_iter().find_map(|k| coverage(scorer, Effect::JointCompliance(k), rules)).map(|r| Refusal {
                effect: e.label(),
                reason: format!(
                    "it moves joints {} and {} with each other's torque; {}",
                    j.number(),
                    next.number(),
                    r.reason
                ),
                remedy: r.remedy,
            })
        }
        Effect::ThermalDrift(j, DriftShape::Temperature) => {
            let j = j.index();
            let (lo, hi) = span(scorer.terms.rise.iter().map(|r| r[j]));
            (hi - lo < rules.min_temperature_span_k).then(|| Refusal {
                effect: e.label(),
                reason: format!(
                    "the temperature it follows moves by {:.2} K only (a per-kelvin drift needs {} K)",
                    hi - lo,
                    rules.min_temperature_span_k
                ),
                remedy: format!(
                    "measure through a warm-up with joint {}'s temperature logged (a `temp_j{}` column)",
                    j + 1,
                    j + 1
                ),
            })
        }
        _ => None,
    }
}

/// The refusal of a candidate one of whose identifiable parameters is estimated in a nearly
/// unidentifiable pair with a parameter of the always-estimated blocks: correlation of the two estimates
/// above [`NEARLY_DEPENDENT`] (the report's own criterion for naming a pair), linearised at the start on
/// all data.
fn nuisance_trade(scorer: &Scorer<'_>, nuisance: &[Effect], c: Effect) -> Result<Option<Refusal>, DiagnoseError> {
    Ok(worst_trade(scorer, nuisance, c)?.map(|(k, n, rho)| Refusal {
        effect: c.label(),
        reason: format!("{k} would be estimated together with {n} (correlation {rho:+.4}, beyond ±{NEARLY_DEPENDENT}): the data determine their combination, not each"),
        remedy: match c.joint() {
            Some(j) => format!(
                "measure joint {} over more of its travel, or state the base or tool frame (measurements in the base frame, the tool known)",
                j.number()
            ),
            None => "state the base or tool frame (measurements in the base frame, the tool known)".to_string(),
        },
    }))
}

/// The refusal of a compliance (or a coupled pair) the data cannot tell from a zero offset of the joints
/// it deflects: a deflection `k·τ` whose torque changes little beside its level is, over these poses,
/// `k·τ̄` — an offset — plus a small remainder. Judged in the fit it would join (the always-estimated
/// blocks and the deflected joints' offsets, linearised at the start on all data) by the report's
/// criterion for a nearly unidentifiable pair, correlation above [`NEARLY_DEPENDENT`]: no fraction of a
/// torque range, which says nothing of how many poses, how precisely measured, sit in it.
fn offset_trade(scorer: &Scorer<'_>, nuisance: &[Effect], c: Effect) -> Result<Option<Refusal>, DiagnoseError> {
    let joints: Vec<JointIndex> = match c {
        Effect::JointCompliance(j) => vec![j],
        Effect::ComplianceCoupling(j) => std::iter::once(j).chain(j.next(scorer.robot)).collect(),
        _ => Vec::new(),
    };
    let mut blocks = nuisance.to_vec();
    blocks.extend(joints.iter().map(|&j| Effect::JointOffset(j)));
    let spans: Vec<String> = joints
        .iter()
        .map(|j| {
            let (lo, hi) = span(scorer.terms.torques.iter().map(|t| t[j.index()]));
            let bound = scorer.scale.max_torque_nm[j.index()];
            format!(
                "the gravity torque about joint {} spans {} … {} N·m ({:.0}% of ±{} N·m)",
                j.number(),
                significant(lo),
                significant(hi),
                100.0 * (hi - lo) / (2.0 * bound),
                significant(bound)
            )
        })
        .collect();
    let numbers: Vec<String> = joints.iter().map(|j| j.number().to_string()).collect();
    Ok(worst_trade(scorer, &blocks, c)?.map(|(k, n, rho)| Refusal {
        effect: c.label(),
        reason: if n.starts_with("joint_offset") {
            format!(
                "{k} would be estimated together with {n} (correlation {rho:+.4}, beyond ±{NEARLY_DEPENDENT}): {}, too little change beside its level to tell a deflection from an offset",
                spans.join("; ")
            )
        } else {
            format!(
                "{k} would be estimated together with {n} (correlation {rho:+.4}, beyond ±{NEARLY_DEPENDENT}): the data determine their combination, not each ({})",
                spans.join("; ")
            )
        },
        remedy: format!(
            "measure poses that load joint {} over more of its gravity-torque range (arm stretched out on both sides)",
            numbers.join(" and ")
        ),
    }))
}

/// The most correlated pair (candidate parameter, block parameter, correlation) beyond
/// [`NEARLY_DEPENDENT`] when `c` is fitted beside `blocks`, linearised at the start on all data.
fn worst_trade(
    scorer: &Scorer<'_>,
    blocks: &[Effect],
    c: Effect,
) -> Result<Option<(String, String, f64)>, DiagnoseError> {
    if blocks.is_empty() {
        return Ok(None);
    }
    let mut effects = blocks.to_vec();
    effects.push(c);
    let model = scorer.model(&effects, &scorer.all())?;
    let jac = scorer.jacobian_at_start(&model)?;
    let names = model.parameter_names();
    let free = identifiable(jac.as_ref(), &vec![true; model.len()]).free;
    let cols: Vec<usize> = (0..model.len()).filter(|&k| free[k]).collect();
    let start = model.offsets()[model.offsets().len() - 1];
    let m = jac.nrows();
    let mut a = faer::Mat::<f64>::zeros(m, cols.len());
    for (k, &col) in cols.iter().enumerate() {
        let n = (0..m).map(|r| jac[(r, col)].powi(2)).sum::<f64>().sqrt().max(1e-300);
        for r in 0..m {
            a[(r, k)] = jac[(r, col)] / n;
        }
    }
    let ata = a.transpose() * &a;
    let Ok(llt) = ata.llt(faer::Side::Lower) else { return Ok(None) };
    let inv = llt.inverse();
    let mut worst: Option<(usize, usize, f64)> = None;
    for (i, &ci) in cols.iter().enumerate() {
        if ci < start {
            continue;
        }
        for (j, &cj) in cols.iter().enumerate() {
            if cj >= start {
                continue;
            }
            let rho = inv[(i, j)] / (inv[(i, i)] * inv[(j, j)]).sqrt();
            if rho.abs() > NEARLY_DEPENDENT && worst.is_none_or(|w| rho.abs() > w.2.abs()) {
                worst = Some((ci, cj, rho));
            }
        }
    }
    Ok(worst.map(|(k, n, rho)| (names[k].clone(), names[n].clone(), rho)))
}
