//! The diagnosis as a whole: the selection on all data and its tables, the validation of the procedure
//! on data it never saw (nested, an explicit hold-out set), the warnings and the verdict — assembled
//! into one [`Report`].

use thermokin_chain::{Dataset, MeasuringOrder, Robot};

use crate::canonical::to_given_order;
use crate::config::{Config, Masses, Validation};
use crate::error::DiagnoseError;
use crate::outliers::screen;
use crate::profile::{Clock, Phase, Profile, profile};
use crate::report::{HoldoutPair, HoldoutStats, Nested, PoseHeldOut, PoseRecord, Report};
use crate::scoring::{Scorer, significantly_better};
use crate::select::select;
use crate::tables::tables;
use crate::validation::{nested, nested_folds, transfer_score};
use crate::verdict::{honest_end, said_first, verdict, warnings};

/// Runs the diagnosis of `data` against `robot`.
///
/// The effects are chosen by cross-validation on `data` (the additive and leave-one-out tables: the
/// selection's scores, optimistic because they chose). The held-out error reported for the procedure
/// itself comes from nested cross-validation ([`Validation::Nested`], the default: [`Report::nested`]),
/// and from `holdout` when given ([`Report::holdout`]) — which never influences the selection.
///
/// ```
/// use thermokin_chain::Robot;
/// use thermokin_diagnose::{Config, HiddenEffect, SimulationConfig, diagnose, simulate};
/// use thermokin_identify::{Effect, JointIndex};
///
/// let robot = Robot::new("IRB 140", thermokin_testdata::irb140_table9());
/// // A hidden zero offset of +0.05° on joint 2 (index 1), measured with 5 µm noise.
/// let offset = Effect::JointOffset(JointIndex::of(&robot, 1)?);
/// let hidden = [HiddenEffect { effect: offset, values: vec![0.05f64.to_radians()] }];
/// let data = simulate(&robot, &hidden, &SimulationConfig { poses: 120, ..SimulationConfig::default() })?;
/// let report = diagnose(&robot, &data, None, &Config::default())?;
/// assert_eq!(report.effects[0].label, "joint_offset[2]");
/// // On outer folds the selection never saw, the chosen model is at the noise (5 µm per axis).
/// assert!(report.nested.unwrap().selected.heldout_rms_mm < 0.015);
/// # Ok::<(), thermokin_diagnose::DiagnoseError>(())
/// ```
pub fn diagnose(
    robot: &Robot,
    data: &Dataset,
    holdout: Option<&Dataset>,
    config: &Config,
) -> Result<Report, DiagnoseError> {
    diagnose_with_progress(robot, data, holdout, config, &mut |_| {})
}

/// One finished stage of a diagnosis, for a progress display: `done` of `total` stages (the selection
/// on all data, each outer fold of the nested validation, the hold-out set), each costing about the same.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Progress {
    /// Stages finished.
    pub done: usize,
    /// Stages in all.
    pub total: usize,
    /// The stage just finished.
    pub stage: String,
}

/// Every measurement of the training and hold-out sets has one value per joint of the robot.
fn check_joint_counts(
    robot: &Robot,
    data: &Dataset,
    holdout: Option<&Dataset>,
    config: &Config,
) -> Result<(), DiagnoseError> {
    let n = robot.chain().dof();
    if let Some((i, q)) =
        config.poses_of_use.iter().enumerate().find(|(_, q)| q.len() != n || q.iter().any(|v| !v.is_finite()))
    {
        return Err(DiagnoseError::JointCount { set: "poses of use", measurement: i + 1, got: q.len(), expected: n });
    }
    let sets = [("training", Some(data)), ("hold-out", holdout)];
    for (set, d) in sets.iter().filter_map(|(s, d)| d.map(|d| (*s, d))) {
        if let Some((i, m)) = d.measurements.iter().enumerate().find(|(_, m)| m.q.len() != n) {
            return Err(DiagnoseError::JointCount { set, measurement: i + 1, got: m.q.len(), expected: n });
        }
    }
    Ok(())
}

/// [`diagnose`], telling `progress` after each stage.
pub fn diagnose_with_progress(
    robot: &Robot,
    data: &Dataset,
    holdout: Option<&Dataset>,
    config: &Config,
    progress: &mut (dyn FnMut(Progress) + Send),
) -> Result<Report, DiagnoseError> {
    let (main, outer) = (Clock::default(), Clock::default());
    released(run(robot, data, holdout, config, progress, &main, &outer))
}

/// `result`, once every thread of the pool (and this one) has freed what its fits kept for the next
/// ([`thermokin_identify::release_scratch`]): a diagnosis of a week holds a Jacobian of 100 MB and more
/// per thread while it runs, and none after.
fn released<T>(result: T) -> T {
    rayon::broadcast(|_| thermokin_identify::release_scratch());
    thermokin_identify::release_scratch();
    result
}

/// [`diagnose`], with where its time went phase by phase ([`Profile`]: the benchmarks print it). The
/// report is the one [`diagnose`] gives: nothing it decides reads the clock.
pub fn diagnose_profiled(
    robot: &Robot,
    data: &Dataset,
    holdout: Option<&Dataset>,
    config: &Config,
) -> Result<(Report, Profile), DiagnoseError> {
    let (main, outer) = (Clock::default(), Clock::default());
    let t0 = std::time::Instant::now();
    let report = released(run(robot, data, holdout, config, &mut |_| {}, &main, &outer))?;
    Ok((report, profile(&main, &outer, t0.elapsed().as_secs_f64())))
}

/// `data` with each pose's approach direction from its measuring order by `by`
/// ([`thermokin_chain::Dataset::with_approach`]), where it has one and no directions yet.
fn ordered(data: std::borrow::Cow<'_, Dataset>, by: MeasuringOrder) -> std::borrow::Cow<'_, Dataset> {
    if data.approach.len() == data.len() || data.measuring_order(by).is_none() {
        data
    } else {
        std::borrow::Cow::Owned(data.into_owned().with_approach(by))
    }
}

/// The hold-out set after [`check_joint_counts`], its sensor columns as `data`'s ([`with_sensors_of`]),
/// each pose's approach direction from its own order ([`ordered`]) — twice: as the export reads it (its
/// accelerometers' tilts from the training session's reference directions, its drivers' readings as
/// given) and on the session's own references, for the refitted protocol (its accelerometers' tilts from
/// its own mean directions, its drivers' levels moved to the training session's: [`crate::sensors::re_referenced`]).
fn checked_holdout(
    robot: &Robot,
    data: &Dataset,
    holdout: Option<&Dataset>,
    config: &Config,
) -> Result<Option<HoldoutSets>, DiagnoseError> {
    let by = config.order;
    check_joint_counts(robot, data, holdout, config)?;
    let Some(given) = holdout else { return Ok(None) };
    let declared = crate::tilts::declared(robot, config);
    let (exported, own) = if declared.is_empty() {
        (given.clone(), given.clone())
    } else {
        (
            crate::tilts::with_tilts(robot, given, &declared, Some(&data.tilt_sensors))?,
            crate::tilts::with_tilts(robot, given, &declared, None)?,
        )
    };
    if let Some(missing) = data.sensor_names.iter().find(|n| !exported.sensor_names.contains(n)) {
        return Err(DiagnoseError::HoldoutLacksSensor { sensor: missing.clone() });
    }
    // In the poses' own order too (the registration refitted on it sums in that order), its branch
    // columns where the training set's are (aligned by name).
    let prepared = |h: &Dataset| {
        let h = crate::canonical::in_canonical_order(h, by).0;
        let mut h = with_sensors_of(&h, data).into_owned();
        h.branch_columns = data.branch_columns.clone();
        ordered(std::borrow::Cow::Owned(h), by).into_owned()
    };
    let own = crate::sensors::re_referenced(data, &prepared(&own));
    Ok(Some(HoldoutSets { exported: prepared(&exported), own }))
}

/// A hold-out set as each protocol reads it ([`checked_holdout`]).
pub(crate) struct HoldoutSets {
    /// As the export reads it: the training session's references.
    pub(crate) exported: Dataset,
    /// On the session's own references, for the refitted protocol.
    pub(crate) own: Dataset,
}

/// The stages a progress display counts: the selection on all data, each outer fold, the hold-out set.
fn stages(data: &Dataset, holdout: bool, config: &Config) -> usize {
    let outer = match config.validation {
        Validation::Nested { outer } => nested_folds(data, config, outer).len(),
        Validation::SelectionOnly => 0,
    };
    1 + outer + usize::from(holdout)
}

/// `holdout` with its sensor columns in `data`'s order, by name (an effect follows a column by its place
/// in the training set); one it lacks was refused before ([`checked_holdout`]).
fn with_sensors_of<'h>(holdout: &'h Dataset, data: &Dataset) -> std::borrow::Cow<'h, Dataset> {
    if holdout.sensor_names == data.sensor_names {
        return std::borrow::Cow::Borrowed(holdout);
    }
    let mut aligned = holdout.clone();
    let place: Vec<Option<usize>> =
        data.sensor_names.iter().map(|n| holdout.sensor_names.iter().position(|h| h == n)).collect();
    aligned.sensor_values = (0..holdout.len())
        .map(|i| {
            let row = holdout.sensor_values.get(i);
            place.iter().map(|p| p.and_then(|k| row.and_then(|r| r.get(k).copied())).unwrap_or(0.0)).collect()
        })
        .collect();
    aligned.sensor_names = data.sensor_names.clone();
    std::borrow::Cow::Owned(aligned)
}

/// What the nested validation and the selection's folds say of the chosen model beside its alternatives:
/// a fallback to the completed geometry ([`fall_back`]), and whether the data disagree with the file's
/// masses ([`crate::masses`]); the sentences the report gives.
fn judged_beside_the_folds(
    scorer: &Scorer<'_>,
    config: &Config,
    sel: &mut crate::selection::Selection,
    nested: Option<&Nested>,
) -> Result<Vec<String>, DiagnoseError> {
    let mut said: Vec<String> = fall_back(sel, nested, config).into_iter().collect();
    said.extend(crate::masses::disagreement(scorer, config, sel)?);
    said.extend(unconfirmed_by_neighbourhoods(scorer, config, sel)?);
    Ok(said)
}

/// For poses in time order, whose folds are blocks of time: whether the chosen model's gain over the
/// always-estimated blocks holds on folds of neighbouring configurations too (each fold a set of
/// k-means blocks of joint space, [`crate::folds::neighbourhood_folds`]), by the selection's gate over
/// those blocks. Time blocks break what time confounds (a drift, a tracker that moved); neighbourhoods
/// break what the arm's configuration does — a gain that only one of them shows is a claim the data do
/// not carry. The sentence the report gives when it does not hold. (Where the session visited some
/// configurations in one stretch of time, neighbourhoods and time blocks are confounded alike: a step of
/// the frame there is said by [`steps_between_configurations`].)
fn unconfirmed_by_neighbourhoods(
    scorer: &Scorer<'_>,
    config: &Config,
    sel: &crate::selection::Selection,
) -> Result<Option<String>, DiagnoseError> {
    let data = scorer.data;
    let chosen = sel.chosen();
    if data.time_span() <= 0.0 || chosen.is_empty() || !crate::folds::by_neighbourhood(data.len(), config.folds) {
        return Ok(None);
    }
    let partition = crate::folds::neighbourhood_folds(data, config.folds, config.seed);
    let always = &sel.effects[..sel.always];
    let (before, before_errors) = scorer.heldout_errors(always, &partition.folds)?;
    let (after, after_errors) = scorer.heldout_errors(&sel.effects, &partition.folds)?;
    if significantly_better(&before_errors, &after_errors, config.gate_standard_errors, &partition.block) {
        return Ok(None);
    }
    Ok(Some(format!(
        "on folds of neighbouring arm configurations (instead of blocks of time) the chosen effects take the held-out RMS from {:.4} to {:.4} mm only, not beyond the gate: the gain the time blocks show may follow where the arm was rather than when — measure the same configurations at other times to tell",
        before.heldout_rms_mm, after.heldout_rms_mm
    )))
}

/// A selection the nested validation cannot tell from the completed geometry it turned down (the
/// procedure not better than the outer folds' completed models by [`Config::gate_standard_errors`]
/// standard errors of the paired difference): its choice rests on folds that cannot carry it — a small
/// set, whose few-effect model extrapolates beyond the poses as the shrunk complete geometry does not —
/// and the completed model is taken. The sentence the report gives, if it falls back.
fn fall_back(sel: &mut crate::selection::Selection, nested: Option<&Nested>, config: &Config) -> Option<String> {
    let n = nested?;
    let mut completed = sel.fallback.take()?;
    // What a later phase refused (a compliance coupling no positive semidefinite pair holds) stays out.
    completed.effects.retain(|e| !sel.refused.iter().any(|r| r.effect == e.label()));
    if n.versus_complete_mm < -config.gate_standard_errors * n.versus_complete_se_mm {
        return None;
    }
    crate::completion::adopt(sel, completed, "taken: the selection is not better than it on the nested outer folds");
    Some(format!(
        "the selection was not better on the nested outer folds than the completed geometry it turned down ({:+.4} ± {:.4} mm): the completed geometry is used",
        n.versus_complete_mm, n.versus_complete_se_mm
    ))
}

/// The robot as the diagnosis reads it: without its masses where the configuration does not trust them
/// ([`Masses::Ignored`]: every compliance's loads lumped then).
fn trusted<'r>(robot: &'r Robot, config: &Config) -> Result<std::borrow::Cow<'r, Robot>, DiagnoseError> {
    Ok(if config.masses == Masses::Ignored && robot.masses().iter().any(Option::is_some) {
        std::borrow::Cow::Owned(robot.clone().with_masses(vec![None; robot.chain().dof()])?)
    } else {
        std::borrow::Cow::Borrowed(robot)
    })
}

/// The measurements as the diagnosis reads them: in the poses' own order (the same poses in any row
/// order give the same report: [`crate::canonical`], with that order to return the report to the given
/// one), without the columns that are no sensors ([`crate::sensors`], with the sentences that say so),
/// each pose's approach direction from its measuring order.
/// Each declared accelerometer's raw columns are its link's tilt first ([`crate::tilts`]).
type Prepared<'d> = (std::borrow::Cow<'d, Dataset>, Option<Vec<usize>>, Vec<String>);
fn prepared<'d>(robot: &Robot, data: &'d Dataset, config: &Config) -> Result<Prepared<'d>, DiagnoseError> {
    let (data, perm) = crate::canonical::in_canonical_order(data, config.order);
    let data = match crate::branches::with_branches(robot, &data)? {
        Some(d) => std::borrow::Cow::Owned(d),
        None => data,
    };
    let declared = crate::tilts::declared(robot, config);
    let data = if declared.is_empty() {
        data
    } else {
        std::borrow::Cow::Owned(crate::tilts::with_tilts(robot, &data, &declared, None)?)
    };
    let (data, not_sensors) = match data {
        std::borrow::Cow::Borrowed(d) => crate::sensors::only_sensors(d),
        std::borrow::Cow::Owned(d) => {
            let (kept, said) = crate::sensors::only_sensors(&d);
            (std::borrow::Cow::Owned(kept.into_owned()), said)
        }
    };
    Ok((ordered(data, config.order), perm, not_sensors))
}

/// The diagnosis, its phases on all measurements timed into `main`, those of the outer folds into `outer`.
fn run(
    robot: &Robot,
    data: &Dataset,
    holdout: Option<&Dataset>,
    config: &Config,
    progress: &mut (dyn FnMut(Progress) + Send),
    main: &Clock,
    outer_clock: &Clock,
) -> Result<Report, DiagnoseError> {
    config.validate()?;
    let robot = &*trusted(robot, config)?;
    let (data, perm, not_sensors) = prepared(robot, data, config)?;
    let data = &*data;
    let total = stages(data, holdout.is_some(), config);
    let mut done = 0;
    let mut tell = |stage: String| {
        done += 1;
        progress(Progress { done, total, stage });
    };
    let holdout = checked_holdout(robot, data, holdout, config)?;
    // Gross errors first: everything after works on the measurements the screen keeps.
    let screened = main.time(Phase::Screen, || screen(robot, data, config))?;
    let kept_data;
    let data = if screened.kept.len() == data.len() {
        data
    } else {
        // Too few left is the selection's refusal, as for too few given.
        kept_data = data.subset(&screened.kept);
        &kept_data
    };
    let scorer = Scorer::new(robot, data, config);
    let mut selected = select(&scorer, config, main)?;
    tell("selection on all measurements".into());
    let (nested, heldout_per_pose) = match config.validation {
        Validation::Nested { outer } => {
            let (n, per_pose) =
                main.time(Phase::Nested, || nested(robot, data, config, outer, &mut tell, outer_clock))?;
            (Some(n), per_pose)
        }
        Validation::SelectionOnly => (None, vec![None; data.len()]),
    };
    let fell_back = judged_beside_the_folds(&scorer, config, &mut selected.selection, nested.as_ref())?;
    let tables = main.time(Phase::Tables, || tables(&scorer, config, selected))?;
    let holdout_data = holdout;
    // Fitted on all of `data`, scored on `holdout`: the selection above never saw it. When the
    // registration or the tool point is always estimated, the hold-out file may be in another tracker
    // frame or carry another probe: those blocks (only) are refitted on it, the effects kept as fitted.
    let scored =
        holdout_data.as_ref().map(|h| main.time(Phase::Holdout, || holdout_stats(&scorer, h, &tables, config)));
    let holdout = scored.transpose()?.inspect(|_| tell("hold-out set".into()));
    let at_use = predicted_at_use(&scorer, config, &tables, holdout_data.as_ref(), holdout.as_ref())?;
    let report_started = std::time::Instant::now();
    // A transfer the poses cannot show is said first.
    let mut all_warnings: Vec<String> =
        fell_back.into_iter().chain(said_first(config, &tables, nested.as_ref())).collect();
    all_warnings.extend(not_sensors);
    all_warnings.extend(said_of_the_effects(robot, data, holdout_data.as_ref().map(|h| &h.exported), config, &tables));
    let verdict = verdict(config, &tables, nested.as_ref());
    let honest_end = honest_end(&tables, nested.as_ref(), holdout.as_ref());
    let poses = pose_records(robot, data, &tables, heldout_per_pose);
    let mut screen = screened.screen;
    for c in &mut screen.clusters {
        // The block's poses as the chosen model leaves them (they are in its data: kept).
        let after = c.measurements.iter().filter_map(|&m| screened.kept.binary_search(&(m - 1)).ok());
        let (lo, hi) = crate::stats::span(after.map(|k| nalgebra::Vector3::from(poses[k].after_mm).norm()));
        c.after_mm = (lo <= hi).then_some([lo, hi]);
        all_warnings.push(c.sentence(screen.threshold_mm));
    }
    main.add(Phase::Report, report_started.elapsed().as_secs_f64());
    let report = Report {
        outliers: screened.outliers,
        outlier_screen: screen,
        nominal: tables.nominal,
        nested,
        holdout,
        at_use,
        calibrated: tables.calibrated,
        identified: tables.identified,
        honest_end,
        validation: tables.validation,
        orientation_lever_mm: tables.orientation_lever_mm,
        effects: tables.reports,
        completed: tables.completed,
        shrinkage: tables.shrinkage,
        additive: tables.additive,
        leave_one_out: tables.leave_one_out,
        identifiability: tables.identifiability,
        residuals_before: tables.residuals_before,
        residuals_after: tables.residuals_after,
        bic: tables.bic,
        frames: tables.frames,
        warnings: all_warnings,
        verdict,
        poses,
    };
    Ok(to_given_order(perm.as_deref(), &screened.kept, report))
}

/// The final model's predicted error at the poses of use ([`crate::at_use`]), the hold-out set's RMS
/// (registration and tool refitted on it) beside it where the hold-out set holds those poses.
fn predicted_at_use(
    scorer: &Scorer<'_>,
    config: &Config,
    tables: &crate::tables::Tables,
    holdout: Option<&HoldoutSets>,
    stats: Option<&crate::report::HoldoutStats>,
) -> Result<Option<crate::report::AtUse>, DiagnoseError> {
    if config.poses_of_use.is_empty() {
        return Ok(None);
    }
    let at = crate::at_use::at_use(scorer, &tables.effects, &config.poses_of_use)?;
    Ok(at.map(|mut a| {
        if let (Some(h), Some(s)) = (holdout, stats)
            && crate::at_use::same_poses(&h.own, &config.poses_of_use)
        {
            a.measured_rms_mm = Some(s.selected.heldout_rms_mm);
        }
        a.promised_rms_mm = config.promised.map(|p| p.rms_mm * a.residual_scale_mm / p.noise_mm);
        a.promised_at_nearest = config.promised.map_or(0, |p| p.at_nearest);
        a
    }))
}

/// For each chosen row a sensor column drives ([`thermokin_identify::Effect::SensorDrift`]), the sentence
/// the report gives where the hold-out set's readings of it reach beyond the range the row was fitted on
/// by more than a tenth of that range: its gain is extrapolated there, and the hold-out figure carries
/// whatever that does.
fn drivers_beyond_their_range(
    data: &Dataset,
    holdout: Option<&Dataset>,
    effects: &[thermokin_identify::Effect],
) -> Vec<String> {
    let Some(h) = holdout else { return Vec::new() };
    let column = |d: &Dataset, k: usize| crate::stats::span(d.sensor_values.iter().filter_map(|r| r.get(k).copied()));
    let mut said = Vec::new();
    let mut seen = Vec::new();
    for e in effects {
        let thermokin_identify::Effect::SensorDrift(_, sensor) = e else { continue };
        if seen.contains(&sensor.index()) {
            continue;
        }
        seen.push(sensor.index());
        let ((lo, hi), (h_lo, h_hi)) = (column(data, sensor.index()), column(h, sensor.index()));
        let margin = 0.1 * (hi - lo);
        if h_lo < lo - margin || h_hi > hi + margin {
            said.push(format!(
                "the hold-out readings of `{}` ({h_lo:.4} … {h_hi:.4}) reach beyond the range the rows it drives were fitted on ({lo:.4} … {hi:.4}): their gains are extrapolated there — measure the training session over the readings the robot will see, or declare the sensor for what it measures (--accelerometer NAME=LINK for a tilt)",
                sensor.name()
            ));
        }
    }
    said
}

/// What the report says of the chosen effects and the data: the tables' warnings, the drivers the hold-out
/// set reads beyond their range, the data's, each step of the frame and each backlash found.
fn said_of_the_effects(
    robot: &Robot,
    data: &Dataset,
    holdout: Option<&Dataset>,
    config: &Config,
    tables: &crate::tables::Tables,
) -> Vec<String> {
    let mut said: Vec<String> = tables.warnings.clone();
    said.extend(drivers_beyond_their_range(data, holdout, &tables.effects));
    said.extend(warnings(robot, data, config, tables));
    said.extend(tables.reports.iter().filter(|e| e.effect == "frame_step").map(frame_step_warning));
    said.extend(steps_between_configurations(robot, data, &tables.effects));
    said.extend(tables.reports.iter().filter(|e| e.effect == "backlash").map(backlash_warning));
    said
}

/// The model of `tables` fitted on all of the scorer's data and the nominal one, scored on `holdout` in
/// both protocols. When the registration or the tool point is always estimated, the hold-out file may be
/// in another tracker frame or carry another probe: those blocks (only) are refitted on it, the effects
/// kept as fitted; and scored as fitted too (the training frame).
fn holdout_stats(
    scorer: &Scorer<'_>,
    holdout: &HoldoutSets,
    tables: &crate::tables::Tables,
    config: &Config,
) -> Result<HoldoutStats, DiagnoseError> {
    let always = config.setup().always_estimated(scorer.data);
    let score = |e: &[thermokin_identify::Effect], lambda| {
        transfer_score(scorer, &holdout.exported, &holdout.own, e, lambda, config)
    };
    let refitted = always.iter().map(thermokin_identify::Effect::label).collect();
    let (nominal, selected) = (score(&always, 0.0)?, score(&tables.effects, tables.shrinkage)?);
    Ok(HoldoutStats {
        nominal: nominal.refitted,
        selected: selected.refitted,
        refitted,
        same_frame: HoldoutPair { nominal: nominal.same_frame, selected: selected.same_frame },
    })
}

/// Every kept measurement as the report's pictures show it ([`PoseRecord`]), in report units.
fn pose_records(
    robot: &Robot,
    data: &Dataset,
    tables: &crate::tables::Tables,
    heldout: Vec<Option<PoseHeldOut>>,
) -> Vec<PoseRecord> {
    let kinds: Vec<_> = robot.chain().joints().iter().map(|j| j.kind).collect();
    data.measurements
        .iter()
        .enumerate()
        .zip(heldout)
        .map(|((i, m), heldout)| PoseRecord {
            line: data.line_of(i),
            time_min: m.time_min,
            joints: m.q.iter().zip(&kinds).map(|(&q, &k)| thermokin_chain::units::joint_value_out(k, q)).collect(),
            measured_mm: [m.position_mm.x, m.position_mm.y, m.position_mm.z],
            before_mm: tables.vectors_before.get(i).copied().unwrap_or_default(),
            after_mm: tables.vectors_after.get(i).copied().unwrap_or_default(),
            heldout,
        })
        .collect()
}

/// What an operator should check when a joint shows backlash: the play, and what the export needs.
fn backlash_warning(e: &crate::report::EffectReport) -> String {
    let half = e.parameters.iter().next().map_or(0.0, |(_, v)| v.value);
    let unit = e.parameters.iter().next().map_or("", |(k, _)| if k.ends_with("_deg") { "°" } else { " mm" });
    format!(
        "joint {} sits {:.4}{unit} apart between poses reached rising and falling ({}: half of it either side): check its gearbox and brake for play; a program that approaches each target from one side avoids it, and fk, ik and compensate with the export need the direction each joint last moved in (--approach; compensate follows the program's order)",
        e.joints.first().copied().unwrap_or(0),
        2.0 * half.abs(),
        e.label
    )
}

/// A chosen step of the measurement frame whose poses before and after it occupy two separate ranges of
/// some joint (no pose of either side within the other side's range): the session visited those
/// configurations in one stretch of time, so a step of the frame there and an error of those
/// configurations fit alike (`sessions.rs`: joint 2 off wherever joint 1 stands above 30°, joint 1's poses
/// measured in order, taken for two steps of the frame and drifts — folds of neighbouring configurations
/// confirmed them too, as they are confounded alike). The sentences the report gives. Strict separation
/// needs no threshold, and poses of mixed configurations on both sides of a knock do not show it (the
/// one- and two-knock sessions of `sessions.rs` say nothing).
fn steps_between_configurations(robot: &Robot, data: &Dataset, effects: &[thermokin_identify::Effect]) -> Vec<String> {
    let steps = effects.iter().filter_map(|e| match e {
        thermokin_identify::Effect::FrameStep(at) => Some(*at),
        _ => None,
    });
    let mut said = Vec::new();
    for at in steps {
        let after = |i: usize| at.applies(data.measurements[i].time_min, data.line_of(i));
        let range = |side: bool, j: usize| {
            crate::stats::span((0..data.len()).filter(|&i| after(i) == side).map(|i| data.measurements[i].q[j]))
        };
        let separated = (0..robot.chain().dof()).find_map(|j| {
            let ((lo_b, hi_b), (lo_a, hi_a)) = (range(false, j), range(true, j));
            let kind = robot.chain().joints()[j].kind;
            let shown = |v: f64| thermokin_chain::units::joint_value_out(kind, v);
            let unit = if kind == thermokin_chain::JointKind::Revolute { "°" } else { " mm" };
            if hi_b < lo_a {
                Some(format!(
                    "joint {} at or above {:.1}{unit}, and all those before it below {:.1}{unit}",
                    j + 1,
                    shown(lo_a),
                    shown(hi_b)
                ))
            } else if hi_a < lo_b {
                Some(format!(
                    "joint {} at or below {:.1}{unit}, and all those before it above {:.1}{unit}",
                    j + 1,
                    shown(hi_a),
                    shown(lo_b)
                ))
            } else {
                None
            }
        });
        if let Some(where_) = separated {
            said.push(format!(
                "the poses after the step of the frame at {} all have {where_}: the session measured those configurations in one stretch of time, so the step and an error of those configurations fit alike — measure some of them again at another time (or in a mixed order) to tell",
                at.describe()
            ));
        }
    }
    said
}

/// What an operator should check when the measurement frame stepped: where, by how much, and what moves
/// a frame.
fn frame_step_warning(e: &crate::report::EffectReport) -> String {
    let value = |name: &str| e.parameters.iter().find(|(k, _)| k.ends_with(name)).map_or(0.0, |(_, v)| v.value);
    let t = (value(".dx_mm").powi(2) + value(".dy_mm").powi(2) + value(".dz_mm").powi(2)).sqrt();
    let r = (value(".rx_deg").powi(2) + value(".ry_deg").powi(2) + value(".rz_deg").powi(2)).sqrt();
    let at = e.label.trim_start_matches("frame_step (").trim_end_matches(')');
    format!(
        "the measurement frame moved at {at}, by {t:.3} mm and {r:.4}°: the tracker was knocked or its stand settled, or the robot's base moved — check the tracker against its reference nests and the base's bolts; each pose is fitted in the frame it was measured in, and the export carries the frame the measurements ended in (re-register before using it if the tracker was set back)"
    )
}
