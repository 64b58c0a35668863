//! Identification: Levenberg–Marquardt on faer with column scaling, the parameters the data cannot
//! identify fixed with a reason, and the parameters' uncertainties.

use faer::Mat;
use faer::linalg::solvers::DenseSolveCore;
use serde::Serialize;
use thermokin_chain::{Dataset, Robot};

use crate::error::IdentifyError;
use crate::identifiability::{FixedParameter, Identifiable, column_norms, identifiable, inert_columns};
use crate::lm::{Lm, REUSE_JACOBIAN, Rates, SPECULATE, Settle, converged_gain, residuals_settled_gain};
use crate::model::Model;
use crate::residuals::weighted;
use crate::terms::PoseTerms;

/// Levenberg–Marquardt iterations per pass of [`fit_from`] before it stops unconverged.
pub const MAX_ITERATIONS: usize = 100;

/// The outcome of one identification.
#[derive(Clone, Debug)]
pub struct Fit {
    /// All parameters (fixed ones at their starting value).
    pub theta: Vec<f64>,
    /// Standard deviation of each free parameter (NaN for fixed ones).
    pub std: Vec<f64>,
    /// Parameters fixed as unidentifiable.
    pub fixed: Vec<FixedParameter>,
    /// Free-parameter mask.
    pub free: Vec<bool>,
    /// Sum of squared residuals, mm².
    pub ssr: f64,
    /// Pairs of free parameters the data barely tell apart: correlation of their estimates above
    /// [`NEARLY_DEPENDENT`] in magnitude.
    pub correlated: Vec<CorrelatedPair>,
    /// Whether the fit stopped because [`Start::give_up`] held after a step: its parameters are where that
    /// step left them, not at a minimum.
    pub gave_up: bool,
    /// The first pass's decision of which parameters the data identify at the start (what
    /// [`Start::identified`] takes to skip deciding it again).
    pub identified: Identifiable,
    /// Whether the iteration ended by its own test — the next step predicted or found to gain less than
    /// the convergence gain (a move under a tenth of the parameters' standard deviations, `lm::SETTLED`, or 1e-9 of the cost), or no step gaining at all — rather than by [`MAX_ITERATIONS`], after
    /// which the parameters are not at the least-squares minimum.
    pub converged: bool,
}

/// Correlation above which two estimates are reported as a nearly unidentifiable combination: at 0.99
/// each one's standard deviation is inflated 7× (`1/√(1 − ρ²)`) over what it would be alone — the data
/// determine their combination, not each.
pub const NEARLY_DEPENDENT: f64 = 0.99;

/// Two parameters whose estimates move together.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CorrelatedPair {
    /// First parameter.
    pub a: String,
    /// Second parameter.
    pub b: String,
    /// Correlation of the two estimates.
    pub correlation: f64,
}

/// Levenberg–Marquardt identification of `model` on the given rows, from its initial values.
pub fn fit(
    robot: &Robot,
    model: &Model,
    data: &Dataset,
    rows: &[usize],
    terms: &PoseTerms,
) -> Result<Fit, IdentifyError> {
    fit_from(robot, model, data, rows, terms, &Start::new(model.initial(), vec![true; model.len()]))
}

/// Where a fit starts, what it may move (parameters with `movable[k] = false` keep `theta[k]`), and how
/// many Levenberg–Marquardt iterations per pass it may take.
#[derive(Clone, Debug)]
pub struct Start {
    /// The starting parameters.
    pub theta: Vec<f64>,
    /// Which parameters may move.
    pub movable: Vec<bool>,
    /// Iterations per pass before the fit stops unconverged.
    pub max_iterations: usize,
    /// A Gaussian prior on the parameters (shrinkage), none by default.
    pub prior: Option<Prior>,
    /// A test of the parameters after every accepted step: when it holds, the fit stops there
    /// ([`Fit::gave_up`]). None by default.
    pub give_up: Option<GiveUp>,
    /// Which parameters the data identify at `theta` — the first pass's decision ([`Fit::identified`] of
    /// an earlier fit of the same model on the same rows from the same `theta` with the same `movable`
    /// and a prior alike present or absent), taken instead of deciding it again. None by default: decided.
    pub identified: Option<Identifiable>,
    /// What the fit must settle before it stops: its parameters (the default) or only its residuals.
    pub settle: Settle,
}

/// A test of a fit's parameters after each accepted step from the `after_steps`-th of a pass on
/// ([`Start::give_up`]): the caller's way to stop a fit whose outcome it no longer needs — a candidate's
/// values already beyond what it would accept.
#[derive(Clone)]
pub struct GiveUp {
    /// Accepted steps of a pass before the test applies (the first steps from a cold start may overshoot
    /// and come back).
    pub after_steps: usize,
    /// The test, of the accepted steps of the pass so far and the parameters: `true` stops the fit.
    pub test: GiveUpTest,
}

/// [`GiveUp::test`]: of the accepted steps of a pass so far and the parameters.
pub type GiveUpTest = std::sync::Arc<dyn Fn(usize, &[f64]) -> bool + Send + Sync>;

impl std::fmt::Debug for GiveUp {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "GiveUp {{ after_steps: {}, .. }}", self.after_steps)
    }
}

impl Start {
    /// From `theta`, moving the `movable` parameters, at most [`MAX_ITERATIONS`] per pass.
    pub fn new(theta: Vec<f64>, movable: Vec<bool>) -> Self {
        Self {
            theta,
            movable,
            max_iterations: MAX_ITERATIONS,
            prior: None,
            give_up: None,
            identified: None,
            settle: Settle::Parameters,
        }
    }
}

/// A Gaussian prior on the parameters: the fit minimises `Σ r² + Σₖ wₖ² (θₖ − cₖ)²` — the residuals of
/// the data and, for each parameter with a weight `wₖ > 0`, one more residual `wₖ (cₖ − θₖ)`
/// (Tikhonov regularisation; the maximum a posteriori estimate under a normal prior of mean `cₖ` and
/// standard deviation `σ / wₖ`, `σ` the residuals' noise). Which parameters are identifiable is decided
/// on the data alone.
#[derive(Clone, Debug, PartialEq)]
pub struct Prior {
    /// The prior's mean of each parameter.
    pub centre: Vec<f64>,
    /// Each parameter's weight (0: no prior on it), in residual units per unit of the parameter.
    pub weight: Vec<f64>,
}

/// What one fit evaluates: a model on some rows of a data set.
struct Problem<'a> {
    robot: &'a Robot,
    model: &'a Model,
    data: &'a Dataset,
    rows: &'a [usize],
    terms: &'a PoseTerms,
    prior: Option<&'a Prior>,
    /// What the fit settles before it stops ([`Start::settle`]).
    settle: Settle,
}

impl Problem<'_> {
    /// The weighted residuals at `theta` (the prior's rows after the data's), and the Jacobian into `jac`
    /// when given.
    fn residuals(&self, theta: &[f64], jac: Option<&mut Mat<f64>>) -> Result<Vec<f64>, IdentifyError> {
        crate::tally::count(self.data_rows(), jac.is_some());
        let Some(prior) = self.prior else {
            return weighted(self.robot, self.model, theta, self.data, self.rows, self.terms, jac.map(Mat::as_mut));
        };
        let n = self.data_rows();
        let priored: Vec<usize> = (0..theta.len()).filter(|&k| prior.weight[k] > 0.0).collect();
        // The data's rows written into the top of `jac` (no copy of a data Jacobian), the prior's below.
        // `weighted` writes every column of every data row; only the prior's rows are cleared here (a
        // week's Jacobian is a hundred megabytes: clearing it whole was a pass over memory per evaluation).
        let mut jac = jac;
        if let Some(jac) = jac.as_deref_mut() {
            let rows = jac.nrows() - n;
            jac.as_mut().subrows_mut(n, rows).fill(0.0);
        }
        let top = jac.as_deref_mut().map(|j| j.as_mut().subrows_mut(0, n));
        let mut r = weighted(self.robot, self.model, theta, self.data, self.rows, self.terms, top)?;
        // As the data's rows, `measured − predicted`: the prior's mean is the measurement, `wₖ θₖ` the
        // prediction (whose derivative the Jacobian holds).
        r.extend(priored.iter().map(|&k| prior.weight[k] * (prior.centre[k] - theta[k])));
        if let Some(jac) = jac {
            for (i, &k) in priored.iter().enumerate() {
                jac[(n + i, k)] = prior.weight[k];
            }
        }
        Ok(r)
    }

    /// Residual rows of the data.
    fn data_rows(&self) -> usize {
        self.rows.len() * self.terms.stride()
    }

    /// Residual rows, the prior's included.
    fn rows(&self) -> usize {
        self.data_rows() + self.prior.map_or(0, |p| p.weight.iter().filter(|w| **w > 0.0).count())
    }
}

/// Where the iteration stands: the parameters, their residuals and cost, the Jacobian (of these
/// parameters, or of earlier ones after a chord step).
struct Iterate {
    theta: Vec<f64>,
    r: Vec<f64>,
    jac: Mat<f64>,
    cost: f64,
}

/// The last pass's free columns in the scaled coordinates the uncertainties are computed in.
struct Scaled {
    cols: Vec<usize>,
    /// A column's scale per unit of θ.
    scale: Vec<f64>,
    /// The sign of `∂θ/∂u` (a correlation's sign in θ).
    signs: Vec<f64>,
    /// `AᵀA` on the scaled columns.
    normal: Mat<f64>,
}

fn ssr(r: &[f64]) -> f64 {
    r.iter().map(|x| x * x).sum::<f64>()
}

std::thread_local! {
    /// The Jacobian of the last fit on this thread, its memory reused by the next: a week's Jacobian is
    /// 100 MB or more, which the allocator maps afresh for each fit and the kernel then zeroes page by
    /// page — a tenth of the CPU of a diagnosis of 100,000 poses went to that (issue #60).
    static SPARE_JACOBIAN: std::cell::RefCell<Mat<f64>> = const { std::cell::RefCell::new(Mat::new()) };
}

/// Frees the memory this thread's fits keep for the next (the last [`fit_from`]'s Jacobian): a caller
/// done fitting — a diagnosis returning — gives it back rather than hold a week's Jacobian per thread.
pub fn release_scratch() {
    SPARE_JACOBIAN.with(|spare| *spare.borrow_mut() = Mat::new());
}

/// [`fit`] from `start`, moving only its movable parameters (a transfer: the effects fitted on one
/// file, only the frame and tool refitted on another).
///
/// Two passes: a parameter that acts only through another (an exponential drift's τ through its
/// amplitude, zero at the start) becomes identifiable once the first pass has moved the other. The
/// second pass is run only for such a parameter: the others' identifiability is decided once, at the
/// start, and not re-decided at the solution, where a parameter near the threshold could change sides.
pub fn fit_from(
    robot: &Robot,
    model: &Model,
    data: &Dataset,
    rows: &[usize],
    terms: &PoseTerms,
    start: &Start,
) -> Result<Fit, IdentifyError> {
    check_prior(model, start.prior.as_ref())?;
    let problem = Problem { robot, model, data, rows, terms, prior: start.prior.as_ref(), settle: start.settle };
    let rates = Rates { columns: model.time_constants() };
    let mut jac = SPARE_JACOBIAN.with(|spare| std::mem::replace(&mut *spare.borrow_mut(), Mat::new()));
    // The first evaluation writes every entry (each data row whole, the prior's rows cleared and set):
    // a Jacobian of the same shape is taken as it is, another one cleared to its shape.
    if (jac.nrows(), jac.ncols()) != (problem.rows(), model.len()) {
        jac.truncate(0, 0);
        jac.resize_with(problem.rows(), model.len(), |_, _| 0.0);
    }
    let r = problem.residuals(&start.theta, Some(&mut jac))?;
    let mut it = Iterate { theta: start.theta.clone(), cost: ssr(&r), r, jac };
    let mut free = vec![false; model.len()];
    let mut fixed = Vec::new();
    let mut scaled = Scaled { cols: Vec::new(), scale: Vec::new(), signs: Vec::new(), normal: Mat::zeros(0, 0) };
    let mut inert = true;
    let mut converged_every_pass = true;
    let mut gave_up = false;
    let mut first: Option<Identifiable> = None;
    for pass in 0..2 {
        if !inert {
            break;
        }
        let norms = column_norms(it.jac.as_ref());
        let inert_now = inert_columns(&norms);
        inert = (0..model.len()).any(|c| start.movable[c] && inert_now[c]);
        // Identifiable from the data alone: the prior's rows would make every column so. At the start,
        // the decision a caller kept from a fit of the same model, rows and start, when it has one.
        let decided = match (&start.identified, pass) {
            (Some(known), 0) => known.clone(),
            _ if problem.prior.is_some() => identifiable(it.jac.subrows(0, problem.data_rows()), &start.movable),
            _ => identifiable(it.jac.as_ref(), &start.movable),
        };
        if pass == 0 {
            first = Some(decided.clone());
        }
        if decided.free == free {
            break;
        }
        free = decided.free;
        fixed = decided.fixed;
        let cols: Vec<usize> = (0..model.len()).filter(|&c| free[c]).collect();
        if cols.is_empty() {
            scaled.cols = cols;
            break;
        }
        let mut lm = Lm::new(&cols);
        lm.refresh(&it.jac, &it.theta, &rates);
        match iterate(&problem, &rates, &mut lm, &mut it, start)? {
            PassEnd::Converged => {}
            PassEnd::Limit => converged_every_pass = false,
            PassEnd::GaveUp => {
                (converged_every_pass, gave_up) = (false, true);
            }
        }
        // Back to θ's coordinates: a column's scale per unit of θ, and the sign `∂θ/∂u` gives a correlation.
        scaled = Scaled {
            scale: lm.scale.iter().zip(&lm.chain).map(|(s, d)| s / d.abs()).collect(),
            signs: lm.chain.iter().map(|d| d.signum()).collect(),
            normal: lm.scaled_normal_matrix(&it.jac),
            cols,
        };
        if gave_up {
            break;
        }
    }
    let names = model.parameter_names();
    let (std, correlated) = uncertainty(&scaled, it.cost, problem.rows(), model.len(), &names);
    SPARE_JACOBIAN.with(|spare| *spare.borrow_mut() = std::mem::replace(&mut it.jac, Mat::new()));
    Ok(Fit {
        std,
        fixed: model.fixed_parameters(&fixed),
        free,
        ssr: it.cost,
        correlated,
        converged: converged_every_pass,
        gave_up,
        theta: it.theta,
        identified: first.unwrap_or(Identifiable { free: vec![false; model.len()], fixed: Vec::new() }),
    })
}

/// A prior the fit can take: one mean and one weight per parameter of `model`, each weight finite and
/// not negative, each mean finite.
fn check_prior(model: &Model, prior: Option<&Prior>) -> Result<(), IdentifyError> {
    let Some(p) = prior else { return Ok(()) };
    if p.centre.len() != model.len() || p.weight.len() != model.len() {
        return Err(IdentifyError::PriorLength {
            expected: model.len(),
            centre: p.centre.len(),
            weight: p.weight.len(),
        });
    }
    match (0..p.weight.len()).find(|&k| !(p.weight[k] >= 0.0 && p.weight[k].is_finite() && p.centre[k].is_finite())) {
        Some(index) => Err(IdentifyError::PriorValue { index, weight: p.weight[index], centre: p.centre[index] }),
        None => Ok(()),
    }
}

/// How one pass of iterations ended.
enum PassEnd {
    /// By its own test: converged, or no step gaining at all.
    Converged,
    /// At the iteration limit.
    Limit,
    /// [`Start::give_up`] held after a step.
    GaveUp,
}

/// Levenberg–Marquardt iterations of one pass, at most `start.max_iterations`, and how the pass ended.
fn iterate(
    problem: &Problem<'_>,
    rates: &Rates,
    lm: &mut Lm,
    it: &mut Iterate,
    start: &Start,
) -> Result<PassEnd, IdentifyError> {
    let mut taken = 0;
    for _ in 0..start.max_iterations {
        let g = lm.gradient(&it.jac, &it.r);
        match damped_step(problem, rates, lm, it, &g)? {
            StepOutcome::Converged => return Ok(PassEnd::Converged),
            StepOutcome::Taken => {
                taken += 1;
                if start.give_up.as_ref().is_some_and(|g| taken >= g.after_steps && (g.test)(taken, &it.theta)) {
                    return Ok(PassEnd::GaveUp);
                }
            }
            StepOutcome::NoGain if lm.retry() => {}
            StepOutcome::NoGain => return Ok(PassEnd::Converged),
        }
    }
    Ok(PassEnd::Limit)
}

/// How one iteration ended.
enum StepOutcome {
    /// A step was accepted.
    Taken,
    /// A step was accepted that gained less than the convergence gain.
    Converged,
    /// No step was taken: the next is predicted to gain less than the convergence gain, or no
    /// damping gave one that gains (after a failed chord step, the Jacobian was refreshed: the iteration
    /// is then retried).
    NoGain,
}

/// One iteration: the damping raised until a step gains (the trial's residuals first; the Jacobian only
/// for an accepted step), or the predicted gain says the fit has converged.
///
/// A trial predicted to gain [`SPECULATE`] times the gain that refreshes the Jacobian is evaluated with
/// its Jacobian, into the iterate's own ([`Speculation`]): accepted, that is the refresh, one residual
/// pass fewer. Any other outcome puts the Jacobian of the iterate's parameters back, evaluated as it was,
/// so that every step and every reported uncertainty is the one evaluated without speculating.
fn damped_step(
    problem: &Problem<'_>,
    rates: &Rates,
    lm: &mut Lm,
    it: &mut Iterate,
    g: &Mat<f64>,
) -> Result<StepOutcome, IdentifyError> {
    let mut speculation = Speculation::Intact;
    let outcome = damped_trials(problem, rates, lm, it, g, &mut speculation)?;
    if let Speculation::Spoiled { at } = speculation {
        problem.residuals(&at, Some(&mut it.jac))?;
    }
    Ok(outcome)
}

/// Whether the iterate's Jacobian is still that of the parameters it was evaluated at.
enum Speculation {
    /// It is (or a refresh made it that of the accepted parameters).
    Intact,
    /// A speculative trial overwrote it: it is to be evaluated again at `at`, where it was.
    Spoiled { at: Vec<f64> },
}

/// The trials of [`damped_step`]; a speculative one records where the Jacobian is to be put back.
fn damped_trials(
    problem: &Problem<'_>,
    rates: &Rates,
    lm: &mut Lm,
    it: &mut Iterate,
    g: &Mat<f64>,
    speculation: &mut Speculation,
) -> Result<StepOutcome, IdentifyError> {
    while lm.lambda < 1e12 {
        let Some((step, predicted)) = lm.step(g) else {
            lm.lambda *= 10.0;
            continue;
        };
        // Converged when the step at this damping is predicted to gain less than `converged_gain` (the
        // parameters would move by less than a tenth of their uncertainty — or, settling the residuals
        // alone, the residuals by less than their `Settle` fraction): the trial is not evaluated —
        // damping further only shortens the step.
        let prior_cost = ssr(&it.r[problem.data_rows().min(it.r.len())..]);
        let settled = converged_gain(it.cost, prior_cost, problem.data_rows(), lm.cols.len());
        if predicted <= settled.max(residuals_settled_gain(it.cost, prior_cost, problem.settle)) {
            return Ok(StepOutcome::NoGain);
        }
        let mut trial = it.theta.clone();
        for (k, &c) in lm.cols.iter().enumerate() {
            trial[c] = rates.moved(c, it.theta[c], step[k] / lm.scale[k]);
        }
        let cost_before = it.cost;
        let speculative = !lm.stale
            && matches!(speculation, Speculation::Intact)
            && predicted >= SPECULATE * REUSE_JACOBIAN * cost_before;
        if speculative {
            *speculation = Speculation::Spoiled { at: it.theta.clone() };
        }
        let rt = problem.residuals(&trial, speculative.then_some(&mut it.jac))?;
        let ct = ssr(&rt);
        if ct < it.cost {
            let gain = (it.cost - ct) / it.cost.max(1e-300);
            it.theta = trial;
            it.r = rt;
            it.cost = ct;
            lm.adapt(gain * cost_before / predicted.max(1e-300));
            // A step that gained less than `converged_gain` ends the fit, as a predicted one does.
            if gain * cost_before <= settled {
                return Ok(StepOutcome::Converged);
            }
            // A small step keeps its Jacobian for the next (chord) step ([`REUSE_JACOBIAN`]).
            if gain >= REUSE_JACOBIAN {
                if !speculative {
                    problem.residuals(&it.theta, Some(&mut it.jac))?;
                }
                *speculation = Speculation::Intact;
                lm.refresh(&it.jac, &it.theta, rates);
            } else {
                lm.stale = true;
            }
            return Ok(StepOutcome::Taken);
        }
        if lm.stale {
            problem.residuals(&it.theta, Some(&mut it.jac))?;
            lm.refresh(&it.jac, &it.theta, rates);
            return Ok(StepOutcome::NoGain);
        }
        lm.raise();
    }
    Ok(StepOutcome::NoGain)
}

/// Standard deviations `σ̂² (AᵀA)⁻¹` on the scaled columns, unscaled (NaN for fixed parameters), and
/// the pairs of estimates correlated above [`NEARLY_DEPENDENT`].
fn uncertainty(
    scaled: &Scaled,
    cost: f64,
    rows: usize,
    len: usize,
    names: &[String],
) -> (Vec<f64>, Vec<CorrelatedPair>) {
    let p = scaled.cols.len();
    let dof = (rows as f64 - p as f64).max(1.0);
    let sigma2 = cost / dof;
    let mut std = vec![f64::NAN; len];
    let mut correlated = Vec::new();
    if p == 0 {
        return (std, correlated);
    }
    let Ok(llt) = scaled.normal.llt(faer::Side::Lower) else { return (std, correlated) };
    let inv = llt.inverse();
    for (k, &c) in scaled.cols.iter().enumerate() {
        std[c] = (sigma2 * inv[(k, k)]).max(0.0).sqrt() / scaled.scale[k];
    }
    for i in 0..p {
        for j in i + 1..p {
            let rho = scaled.signs[i] * scaled.signs[j] * inv[(i, j)] / (inv[(i, i)] * inv[(j, j)]).sqrt();
            if rho.abs() > NEARLY_DEPENDENT {
                let (a, b) = (names[scaled.cols[i]].clone(), names[scaled.cols[j]].clone());
                correlated.push(CorrelatedPair { a, b, correlation: rho });
            }
        }
    }
    (std, correlated)
}

#[cfg(test)]
#[allow(clippy::unwrap_used)] // Tests unwrap to fail.
mod convergence {
    use nalgebra::Vector3;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;
    use thermokin_chain::{Dataset, ErrorParams, Measurement, Robot};
    use thermokin_testdata::{gauss, irb140_table9, measured_point};

    use super::{Start, fit_from};
    use crate::{Effect, JointIndex, Model, PoseTerms};

    /// `converged` is the iteration's own verdict, not the loop's end: one iteration from zero stops by
    /// the limit (unconverged); the full fit stops by its test, and — checked independently of that test —
    /// lands on the hidden values within a few of its standard deviations. The data are the FK of a chain
    /// built with the hidden errors (joint 2's zero, joint 4's row), not of the model being fitted.
    #[test]
    fn a_fit_stopped_by_the_iteration_limit_says_it_did_not_converge() {
        let nominal = irb140_table9();
        let (offset, link_dx_mm) = (0.05f64.to_radians(), 0.3);
        let mut zeros = vec![0.0; 6];
        zeros[1] = offset;
        let mut rows = vec![ErrorParams::default(); 6];
        rows[3] = ErrorParams::new(Vector3::new(link_dx_mm, 0.0, 0.0), Vector3::zeros());
        let truth = nominal.with_errors_and_zeros(nominal.base().error, &rows, nominal.tool().error, &zeros).unwrap();
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let measurements = (0..60)
            .map(|_| {
                let q: Vec<f64> = (0..6).map(|_| 2.0 * gauss(&mut rng).clamp(-1.2, 1.2)).collect();
                let p = truth.tool_pose(&q).unwrap().translation.vector;
                measured_point(q, p, 0.005, &mut rng)
            })
            .collect();
        let data = Dataset { measurements, ..Dataset::default() };
        let robot = Robot::new("IRB 140", nominal);
        let joint = |j| JointIndex::of(&robot, j).unwrap();
        let model = Model::new(&robot, vec![Effect::JointOffset(joint(1)), Effect::LinkDeviation(joint(3))]).unwrap();
        let all: Vec<usize> = (0..data.len()).collect();
        let terms = PoseTerms::of(&robot, &data, 0.0);
        let start = Start::new(model.initial(), vec![true; model.len()]);
        let one = fit_from(&robot, &model, &data, &all, &terms, &Start { max_iterations: 1, ..start }).unwrap();
        assert!(!one.converged);
        let full = fit_from(&robot, &model, &data, &all, &terms, &Start::new(model.initial(), vec![true; model.len()]))
            .unwrap();
        assert!(full.converged);
        assert!(full.ssr < one.ssr);
        for (k, truth) in [(0, offset), (1, link_dx_mm)] {
            assert!(
                (full.theta[k] - truth).abs() < 5.0 * full.std[k],
                "{k}: {} ± {} vs {truth}",
                full.theta[k],
                full.std[k]
            );
        }
    }

    /// Table 9's IRB 140 with every joint's row off and joint 3's row drifting as the square root of the
    /// time over a 240-minute warm-up, at `poses` seeded configurations one after the other, and the
    /// model of every joint's row with an exponential drift of joint 3's (its τ fitted): residuals well
    /// above the noise along a curved valley in τ, where Gauss–Newton converges linearly — the gross-error
    /// screen's situation.
    fn warming_up(poses: usize) -> (Robot, Dataset, Model) {
        let nominal = irb140_table9();
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        let mut row = || {
            let d = Vector3::new(gauss(&mut rng), gauss(&mut rng), gauss(&mut rng)) * 0.3;
            let r = Vector3::new(gauss(&mut rng), gauss(&mut rng), gauss(&mut rng)) * 0.02f64.to_radians();
            ErrorParams::new(d, r)
        };
        let rows: Vec<ErrorParams> = (0..6).map(|_| row()).collect();
        let drift = ErrorParams::new(row().translation * 3.0, row().rotation * 3.0);
        let measurements = (0..poses)
            .map(|i| {
                let t = 240.0 * i as f64 / poses as f64;
                let mut now = rows.clone();
                now[2] = ErrorParams::new(
                    rows[2].translation + drift.translation * (t / 60.0).sqrt(),
                    rows[2].rotation + drift.rotation * (t / 60.0).sqrt(),
                );
                let chain = nominal.with_errors_and_zeros(nominal.base().error, &now, nominal.tool().error, &[0.0; 6]);
                let q: Vec<f64> = (0..6).map(|_| 2.0 * gauss(&mut rng).clamp(-1.2, 1.2)).collect();
                let mut bent = q.clone();
                bent[1] += 0.05f64.to_radians() * (2.0 * q[1]).sin();
                bent[2] += 0.05f64.to_radians() * (2.0 * q[2]).cos();
                let p = chain.unwrap().tool_pose(&bent).unwrap().translation.vector;
                Measurement { time_min: t, ..measured_point(q, p, 0.005, &mut rng) }
            })
            .collect();
        let robot = Robot::new("IRB 140", nominal);
        let joint = |j| JointIndex::of(&robot, j).unwrap();
        let effects = (0..6)
            .map(|j| Effect::LinkDeviation(joint(j)))
            .chain([Effect::ThermalDrift(joint(2), crate::DriftShape::Exponential)])
            .collect();
        let model = Model::new(&robot, effects).unwrap();
        (robot, Dataset { measurements, ..Dataset::default() }, model)
    }

    /// A fit that settles its residuals alone ([`super::Settle::Residuals`]) stops where its next step is
    /// predicted to gain less than `g` of the cost, which moves the residual rows by `√g·σ̂` in RMS
    /// (`σ̂` their scale): against the same fit settling its parameters, on a warm-up of 4,000 poses whose
    /// drift and gears the model does not describe (residuals 30 times the noise), its rows lie within
    /// `2√g·σ̂` of the parameters' fit's (twice: the step's gain is a prediction of the linearised model)
    /// for `g` from 1e-2 to 1e-6, and at 1e-2 it is not that fit (the rule stops it); with `g = 0` it is
    /// that fit to the bit. Fails if the rule ends a fit on anything but the predicted gain's size.
    #[test]
    fn a_fit_settling_its_residuals_stops_where_they_would_move_by_its_fraction() {
        use super::Settle;
        let (robot, data, model) = warming_up(4000);
        let all: Vec<usize> = (0..data.len()).collect();
        let terms = PoseTerms::of(&robot, &data, 0.0);
        let with = |settle| {
            let start = Start { settle, ..Start::new(model.initial(), vec![true; model.len()]) };
            fit_from(&robot, &model, &data, &all, &terms, &start).unwrap()
        };
        let parameters = with(Settle::Parameters);
        assert_eq!(with(Settle::Residuals { relative_gain: 0.0 }).theta, parameters.theta);
        let r = |f: &super::Fit| crate::residuals(&robot, &model, &f.theta, &data, &all, &terms).unwrap();
        let rp = r(&parameters);
        let m = rp.len() as f64;
        let sigma = (parameters.ssr / (m - model.len() as f64)).sqrt();
        assert!(sigma > 30.0 * 0.005, "σ̂ {sigma}");
        for g in [1e-2, 1e-4, 1e-6] {
            let residuals = with(Settle::Residuals { relative_gain: g });
            let rr = r(&residuals);
            let moved = (rp.iter().zip(&rr).map(|(a, b)| (a - b).powi(2)).sum::<f64>() / m).sqrt();
            eprintln!("g {g:e}: residuals {:.3e} σ̂ from the parameters' fit", moved / sigma);
            assert!(residuals.converged);
            assert!(moved <= 2.0 * g.sqrt() * sigma, "g {g}: {moved} vs σ̂ {sigma}");
            assert!(residuals.ssr >= parameters.ssr * (1.0 - 1e-9), "g {g}");
            if g >= 1e-2 {
                assert_ne!(residuals.theta, parameters.theta);
            }
        }
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)] // Tests unwrap to fail.
mod prior {
    use nalgebra::{DMatrix, DVector, Vector3};
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;
    use thermokin_chain::{Dataset, Measurement, Robot};
    use thermokin_testdata::{gauss, irb140_table9, measured_point};

    use super::{Prior, Start, fit_from};
    use crate::{Effect, Model, PoseTerms, residuals_and_jacobian};

    /// Table 9's IRB 140 carrying a tool point `tool` (mm from the flange), measured at `poses` seeded
    /// configurations with 0.05 mm of noise.
    fn tool_point_data(seed: u64, poses: usize, tool: Vector3<f64>) -> (Robot, Dataset) {
        let chain = irb140_table9();
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let measurements: Vec<Measurement> = (0..poses)
            .map(|_| {
                let q: Vec<f64> = (0..6).map(|_| 2.0 * gauss(&mut rng).clamp(-1.2, 1.2)).collect();
                let pose = chain.tool_pose(&q).unwrap();
                measured_point(q, (pose * nalgebra::Point3::from(tool)).coords, 0.05, &mut rng)
            })
            .collect();
        (Robot::new("IRB 140", chain), Dataset { measurements, ..Dataset::default() })
    }

    /// The shrunk fit against the closed form of ridge regression: the tool point's position enters the
    /// prediction affinely (`p = R(q)·t + p₀(q)`), so the penalised least squares has the solution
    /// `θ* = θ₀ + (JᵀJ + W)⁻¹ (Jᵀ r₀ + W (c − θ₀))` (`W = diag(wₖ²)`, `r₀` the residuals at `θ₀`),
    /// computed here with nalgebra, not by the iteration. A zero weight leaves the parameter to the
    /// data; an overwhelming one holds it at the prior's mean.
    #[test]
    fn the_prior_gives_the_ridge_solution_of_an_affine_problem() {
        let tool = Vector3::new(0.8, -0.5, 1.2);
        let (robot, data) = tool_point_data(17, 25, tool);
        let model = Model::new(&robot, vec![Effect::ToolPoint]).unwrap();
        let all: Vec<usize> = (0..data.len()).collect();
        let terms = PoseTerms::of(&robot, &data, 0.0);
        let theta0 = model.initial();
        let (r0, jac) = residuals_and_jacobian(&robot, &model, &theta0, &data, &all, &terms).unwrap();
        let j = DMatrix::from_fn(jac.nrows(), jac.ncols(), |i, k| jac[(i, k)]);
        let centre = vec![0.3, 0.0, -0.4];
        for weight in [vec![0.0; 3], vec![2.0, 5.0, 0.0], vec![1e6; 3]] {
            let w2 = DMatrix::from_diagonal(&DVector::from_iterator(3, weight.iter().map(|w| w * w)));
            let c_minus = DVector::from_iterator(3, centre.iter().zip(&theta0).map(|(c, t)| c - t));
            let rhs = j.transpose() * DVector::from_column_slice(&r0) + &w2 * c_minus;
            let step = (j.transpose() * &j + &w2).lu().solve(&rhs).unwrap();
            let mut start = Start::new(theta0.clone(), vec![true; 3]);
            start.prior = Some(Prior { centre: centre.clone(), weight: weight.clone() });
            let f = fit_from(&robot, &model, &data, &all, &terms, &start).unwrap();
            assert!(f.converged);
            for k in 0..3 {
                // The iteration stops within 1e-9 of the cost: ~1e-5 of a σ of 0.01 mm, far below 1e-6 mm.
                assert!(
                    (f.theta[k] - (theta0[k] + step[k])).abs() < 1e-6,
                    "{weight:?} {k}: {} vs {}",
                    f.theta[k],
                    theta0[k] + step[k]
                );
            }
            if weight[0] > 1e5 {
                assert!((f.theta[0] - centre[0]).abs() < 1e-6);
            }
        }
        // The data decide where the prior has no weight: the tool point found within 0.05 mm (its length:
        // the parameters are in the last joint's same-orientation frame, turned against the tool's).
        // A weight that is not a number is refused, not fitted with.
        let mut bad = Start::new(theta0.clone(), vec![true; 3]);
        bad.prior = Some(Prior { centre: centre.clone(), weight: vec![1.0, f64::NAN, 0.0] });
        assert!(fit_from(&robot, &model, &data, &all, &terms, &bad).is_err());
        let free = fit_from(&robot, &model, &data, &all, &terms, &Start::new(theta0.clone(), vec![true; 3])).unwrap();
        let o = model.offsets()[0];
        let found = Vector3::new(free.theta[o], free.theta[o + 1], free.theta[o + 2]);
        assert!((found.norm() - tool.norm()).abs() < 0.05, "{found:?}");
    }

    /// A fit takes the thread's spare Jacobian as it is when its shape is the fit's (`fit_from`; the
    /// first evaluation writes every entry): the same fit, after one whose prior's rows sat in other
    /// columns of a Jacobian of the same shape, lands on the same values to the bit as on a fresh
    /// Jacobian. Fails if an entry of the last fit's Jacobian — a prior's weight left in a column the
    /// next prior does not shrink — reaches the next fit.
    #[test]
    fn a_fit_is_the_same_whatever_the_last_fit_left_in_its_jacobian() {
        let (robot, data) = tool_point_data(29, 40, Vector3::new(0.4, 0.2, -0.9));
        let model = Model::new(&robot, vec![Effect::ToolPoint]).unwrap();
        let all: Vec<usize> = (0..data.len()).collect();
        let terms = PoseTerms::of(&robot, &data, 0.0);
        let with = |weight: Vec<f64>| {
            let mut start = Start::new(model.initial(), vec![true; 3]);
            start.prior = Some(Prior { centre: vec![0.3, 0.0, -0.4], weight });
            fit_from(&robot, &model, &data, &all, &terms, &start).unwrap()
        };
        super::release_scratch();
        let fresh = with(vec![2.0, 5.0, 0.0]);
        // Two prior rows as well (the same shape), in columns 1 and 2, and other values everywhere.
        let other = with(vec![0.0, 30.0, 70.0]);
        assert_ne!(other.theta, fresh.theta);
        let again = with(vec![2.0, 5.0, 0.0]);
        assert_eq!(again.theta, fresh.theta);
        assert_eq!(again.ssr.to_bits(), fresh.ssr.to_bits());
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&again.std), bits(&fresh.std));
    }
}
