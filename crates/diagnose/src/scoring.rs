//! The fit of a model of effects on some poses (least squares, or with the shrinkage's prior toward the
//! nominal robot), its held-out scoring on the selection's folds, the gate that accepts a gain only
//! when it exceeds its own uncertainty over blocks of poses, and how two blocks' parameter directions
//! relate on the data.

use std::collections::HashMap;
use std::sync::{Arc, Mutex};

use faer::Mat;
use rayon::prelude::*;
use thermokin_chain::{Dataset, Robot};
use thermokin_identify::{
    DEPENDENT, Effect, Fit, FixedParameter, GiveUp, Identifiable, Model, PoseTerms, Prior, Start, StartFrames,
    fit_from, identifiable, initial_frames, norms, project_out, residuals, residuals_and_jacobian,
};

use crate::config::Config;
use crate::error::DiagnoseError;
use crate::folds::{Folds, folds_for, forward_chained};
use crate::plausibility::{RobotScale, Trade};
use crate::stats::Stats;

/// A starting frame's key: the measurement rows, whether a registration and a tool point start.
type StartKey = (Vec<usize>, bool, bool);

/// One of the scorer's own sets of measurement rows: all of them, or fold `k`'s training part of
/// [`Scorer::folds`] — what a model's prior column squares are kept by ([`Scorer::initial_squares`]).
#[derive(Clone, Copy, PartialEq, Eq, Hash)]
pub(crate) enum RowSet {
    /// Every measurement ([`Scorer::all`]).
    All,
    /// The training part of the selection's fold `k`.
    Train(usize),
}

/// A Jacobian's squared column norms and its number of rows ([`Scorer::column_squares`]).
type ColumnSquares = (Vec<f64>, usize);

/// A kept identifiability decision's key: the model's effects, its row set, whether the fit had a prior.
type IdentifiedKey = (Vec<Effect>, RowSet, bool);

/// The value `map` keeps under `key`, or `compute`'s, then kept there (a poisoned lock only loses the
/// keeping: the value is deterministic).
fn kept_or<K: std::hash::Hash + Eq, V: Clone, E>(
    map: &Mutex<HashMap<K, V>>,
    key: K,
    compute: impl FnOnce() -> Result<V, E>,
) -> Result<V, E> {
    if let Some(known) = map.lock().ok().and_then(|m| m.get(&key).cloned()) {
        return Ok(known);
    }
    let found = compute()?;
    if let Ok(mut m) = map.lock() {
        m.insert(key, found.clone());
    }
    Ok(found)
}

/// One model's fits on the folds, fold by fold: its parameters, which of them were free, and whether
/// the fit ended by its own test.
pub(crate) type FoldFits = Arc<Vec<(Vec<f64>, Vec<bool>, bool)>>;

/// One fold's fit, scored on the fold's test poses.
struct FoldFit {
    errors: Vec<f64>,
    theta: Vec<f64>,
    free: Vec<bool>,
    /// Stopped by the caller's [`GiveUp`].
    stopped: bool,
    /// Ended by its own test (converged), not by the iteration limit or a [`GiveUp`].
    settled: bool,
}

/// What every held-out evaluation of one diagnosis shares: the robot, the data with their per-pose
/// terms, the selection's folds and the blocks its gate counts.
pub(crate) struct Scorer<'a> {
    pub(crate) robot: &'a Robot,
    pub(crate) data: &'a Dataset,
    pub(crate) terms: PoseTerms,
    pub(crate) folds: Folds,
    /// The block of each held-out error of `folds`, in order (the gate's unit of evidence).
    pub(crate) blocks: Vec<usize>,
    /// The block of each measurement, in data order.
    pub(crate) block_of: Vec<usize>,
    pub(crate) forward: Folds,
    /// The robot's scale over the data, what fitted values are judged against.
    pub(crate) scale: RobotScale,
    /// The starting frames already computed, by measurement rows and which frame blocks they start
    /// (every model of one fold starts from the same registration and tool point: the alternating
    /// closed form runs once per fold, not once per candidate).
    starts: Mutex<HashMap<StartKey, StartFrames>>,
    /// The fold fits (parameters, free mask) of the models already scored on `folds`, by their effects
    /// in order and the prior's strength (its bits): the phases score some models more than once (a
    /// backward step, a replacement, the leave-one-out table, the shrinkage's grid), and a fit is
    /// deterministic.
    scored: Mutex<HashMap<(Vec<Effect>, u64), FoldFits>>,
    /// The squared column norms of a model's Jacobian at its initial values on one of the scorer's row
    /// sets (the prior's scale, [`prior`]), by the model's effects: every strength the shrinkage and the
    /// completion try on a model's folds takes the same ones, and each was a Jacobian evaluation over
    /// the fold's poses.
    squares: Mutex<HashMap<(Vec<Effect>, RowSet), ColumnSquares>>,
    /// Which parameters the data identify at a model's initial values on one of the scorer's row sets
    /// (a fit's first decision, [`Fit::identified`]), by the model's effects and whether the fit had a
    /// prior (the Jacobian the decision is taken on is then a block of a taller one): the same for
    /// every strength of a prior, and each was a Gram matrix and an R factor over the fold's rows.
    identified: Mutex<HashMap<IdentifiedKey, Identifiable>>,
    /// The catalogue's Jacobian at the nominal robot on all measurements, as its Gram matrix (what
    /// [`Scorer::relations`] compares blocks by; formed once — the tables and parsimony relate the same
    /// blocks many times over).
    relation_gram: std::sync::OnceLock<Option<RelationGram>>,
    /// The catalogue of these data, whose blocks [`Scorer::relations`] relates.
    catalogue: Vec<Effect>,
}

/// The Gram matrix `JᵀJ` of the catalogue's blocks' Jacobian columns at the nominal robot on all
/// measurements, and where each block's columns start.
struct RelationGram {
    /// Residual rows the Gram matrix sums over.
    rows: usize,
    effects: Vec<Effect>,
    offsets: Vec<usize>,
    gram: Mat<f64>,
}

/// Poses per block of rows when the relations' Gram matrix is accumulated: the catalogue's Jacobian of a
/// week of poses (36,000 rows × ~350 columns) would be 100 MB at once.
const GRAM_CHUNK_POSES: usize = 1000;

/// A model scored on folds ([`Scorer::heldout_fits`]).
pub(crate) struct HeldOut {
    /// The statistics of the held-out errors.
    pub(crate) stats: Stats,
    /// Every held-out error, in fold order.
    pub(crate) errors: Vec<f64>,
    /// Each fold's fitted parameters (empty for an empty fold).
    pub(crate) thetas: Vec<Vec<f64>>,
    /// Each fold's free parameters (empty for an empty fold).
    pub(crate) free: Vec<Vec<bool>>,
    /// Whether each fold's fit ended by its own test (`true` for an empty fold): a fit stopped at the
    /// iteration limit still moved its parameters by more than a tenth of their standard deviations
    /// per step.
    pub(crate) settled: Vec<bool>,
}

/// What a candidate adds to a model ([`Scorer::new_free`]).
pub(crate) struct Addition {
    /// Its parameters that stay identifiable next to the model.
    pub(crate) new_free: usize,
    /// Its parameters that do not, with the reason.
    pub(crate) fixed: Vec<FixedParameter>,
}

/// Whether a parameter of effect `e` is shrunk ([`crate::shrinkage`]): the static effects' parameters (not the frame blocks,
/// not a time law's).
pub(crate) fn shrunk(e: Effect) -> bool {
    e.is_reported() && e.is_static()
}

/// The prior of strength `lambda` for `model` ([`crate::shrinkage`]), from the squared column norms of its
/// Jacobian at its initial values (the nominal robot; `squares` over `rows` residual rows,
/// [`Scorer::column_squares`]); centred there (zero deviation).
pub(crate) fn prior(model: &Model, (squares, rows): (&[f64], usize), lambda: f64) -> Prior {
    let n = rows.max(1) as f64;
    let mut weight = vec![0.0; model.len()];
    for (e, &o) in model.effects().iter().zip(model.offsets()) {
        if !shrunk(*e) {
            continue;
        }
        for k in o..o + e.len() {
            weight[k] = (lambda * squares[k] / n).sqrt();
        }
    }
    Prior { centre: model.initial(), weight }
}

impl<'a> Scorer<'a> {
    /// The folds and per-measurement quantities of `data`.
    pub(crate) fn new(robot: &'a Robot, data: &'a Dataset, config: &Config) -> Self {
        let partition = folds_for(data, config.folds, config.seed, config.folds_by);
        let blocks = partition.test_blocks();
        Self {
            robot,
            data,
            terms: PoseTerms::of(robot, data, config.orientation_lever_mm),
            folds: partition.folds,
            blocks,
            block_of: partition.block,
            forward: forward_chained(data, config.folds),
            scale: RobotScale::of(robot, data),
            starts: Mutex::new(HashMap::new()),
            scored: Mutex::new(HashMap::new()),
            squares: Mutex::new(HashMap::new()),
            identified: Mutex::new(HashMap::new()),
            relation_gram: std::sync::OnceLock::new(),
            catalogue: config.setup().candidates(robot, data).unwrap_or_default(),
        }
    }

    /// The model of `effects`, its registration and tool point started from the measurements `rows`
    /// ([`initial_frames`]).
    pub(crate) fn model(&self, effects: &[Effect], rows: &[usize]) -> Result<Model, DiagnoseError> {
        let m = Model::new(self.robot, effects.to_vec())?;
        let key = (rows.to_vec(), m.has_registration(), effects.contains(&Effect::ToolPoint));
        if !(key.1 || key.2) {
            return Ok(m);
        }
        let start = kept_or(&self.starts, key, || initial_frames(self.robot, self.data, rows, effects))?;
        Ok(m.with_start(start))
    }

    /// Held-out statistics of a model by cross-validation on `folds`.
    pub(crate) fn heldout(&self, effects: &[Effect], folds: &Folds) -> Result<Stats, DiagnoseError> {
        Ok(self.heldout_errors(effects, folds)?.0)
    }

    /// Held-out statistics and every held-out error (3-D norm, mm, in fold order: the same order for any
    /// model on the same folds, so that two models' errors pair up measurement by measurement).
    pub(crate) fn heldout_errors(&self, effects: &[Effect], folds: &Folds) -> Result<(Stats, Vec<f64>), DiagnoseError> {
        let h = self.heldout_fits(effects, folds)?;
        Ok((h.stats, h.errors))
    }

    /// [`Scorer::heldout_errors`] with each fold's fitted parameters.
    pub(crate) fn heldout_fits(&self, effects: &[Effect], folds: &Folds) -> Result<HeldOut, DiagnoseError> {
        self.heldout_fits_with(effects, folds, 0.0)
    }

    /// [`Scorer::heldout_fits`] of the model fitted with the prior of strength `lambda` on each fold
    /// ([`Scorer::fit_shrunk`]; 0: least squares). On the selection's own folds, a model fitted
    /// before at the same strength is not fitted again (its held-out errors are recomputed from its parameters: one
    /// evaluation per fold, and no copy of every error kept per model).
    pub(crate) fn heldout_fits_with(
        &self,
        effects: &[Effect],
        folds: &Folds,
        lambda: f64,
    ) -> Result<HeldOut, DiagnoseError> {
        Ok(self.fold_fits(effects, folds, lambda, None)?.0)
    }

    /// [`Scorer::heldout_fits`] of a candidate's model, each fold's fit stopped once `give_up` holds
    /// (the candidate's values beyond what the caller accepts): when it holds at the end of every fold's
    /// fit, stopped or not, the held-out fits are returned as they stand (`true`: the caller refuses
    /// the model, the scores do not matter); otherwise the stopped folds are fitted to the end, and the
    /// scores are those of [`Scorer::heldout_fits`] (`false`).
    pub(crate) fn heldout_fits_unless(
        &self,
        effects: &[Effect],
        folds: &Folds,
        give_up: &GiveUp,
    ) -> Result<(HeldOut, bool), DiagnoseError> {
        let (held, stopped) = self.fold_fits(effects, folds, 0.0, Some(give_up))?;
        let every = held.thetas.iter().filter(|t| !t.is_empty()).all(|t| (give_up.test)(usize::MAX, t));
        if every || !stopped.iter().any(|s| *s) {
            return Ok((held, every));
        }
        Ok((self.heldout_fits(effects, folds)?, false))
    }

    /// The fold loop of [`Scorer::heldout_fits_with`], each fold's fit stopped once `give_up` holds
    /// (which folds were stopped is returned beside: their fits are not kept).
    pub(crate) fn fold_fits(
        &self,
        effects: &[Effect],
        folds: &Folds,
        lambda: f64,
        give_up: Option<&GiveUp>,
    ) -> Result<(HeldOut, Vec<bool>), DiagnoseError> {
        let kept = std::ptr::eq(folds, &self.folds);
        let key = (effects.to_vec(), lambda.to_bits());
        let known = if kept { self.scored.lock().ok().and_then(|m| m.get(&key).cloned()) } else { None };
        // Folds in parallel, their errors concatenated in fold order (the same on any thread count).
        let per_fold: Vec<FoldFit> = folds
            .par_iter()
            .enumerate()
            .map(|(k, (train, test))| {
                if train.is_empty() || test.is_empty() {
                    let empty = FoldFit { errors: vec![], theta: vec![], free: vec![], stopped: false, settled: true };
                    return Ok(empty);
                }
                let (model, theta, free, stopped, settled) = match &known {
                    Some(fits) => {
                        let (theta, free, settled) = fits[k].clone();
                        (self.model(effects, train)?, theta, free, false, settled)
                    }
                    None => {
                        let set = kept.then_some(RowSet::Train(k));
                        let (model, f) = self.fit_until(effects, train, set, lambda, give_up)?;
                        (model, f.theta, f.free, f.gave_up, f.converged)
                    }
                };
                let r = residuals(self.robot, &model, &theta, self.data, test, &self.terms)?;
                Ok(FoldFit { errors: norms(&r, self.terms.stride()), theta, free, stopped, settled })
            })
            .collect::<Result<_, DiagnoseError>>()?;
        let errors: Vec<f64> = per_fold.iter().flat_map(|f| f.errors.iter().copied()).collect();
        let stopped: Vec<bool> = per_fold.iter().map(|f| f.stopped).collect();
        let settled: Vec<bool> = per_fold.iter().map(|f| f.settled).collect();
        let (thetas, free): (Vec<Vec<f64>>, Vec<Vec<bool>>) = per_fold.into_iter().map(|f| (f.theta, f.free)).unzip();
        if kept
            && known.is_none()
            && !stopped.iter().any(|s| *s)
            && let Ok(mut m) = self.scored.lock()
        {
            let fits = thetas.iter().cloned().zip(free.iter().cloned()).zip(&settled).map(|((t, f), s)| (t, f, *s));
            m.insert(key, Arc::new(fits.collect()));
        }
        Ok((HeldOut { stats: Stats::of(&errors), errors, thetas, free, settled }, stopped))
    }

    /// The least-squares fold fits of `effects` on the selection's folds, when that model has been scored
    /// there ([`crate::linearised`] steps from them).
    pub(crate) fn kept_fold_fits(&self, effects: &[Effect]) -> Option<FoldFits> {
        self.scored.lock().ok().and_then(|m| m.get(&(effects.to_vec(), 0f64.to_bits())).cloned())
    }

    /// The model of `effects` fitted on `rows` with the prior of strength `lambda` ([`prior`]; 0: the
    /// plain least-squares fit), from the initial values as every fit (a start at the unshrunk fit was
    /// tried: where that fit had wandered along a nearly flat valley, the shrunk one stayed there).
    pub(crate) fn fit_shrunk(
        &self,
        effects: &[Effect],
        rows: &[usize],
        lambda: f64,
    ) -> Result<(Model, Fit), DiagnoseError> {
        let all = rows.len() == self.data.len() && rows.iter().enumerate().all(|(i, &r)| i == r);
        self.fit_until(effects, rows, all.then_some(RowSet::All), lambda, None)
    }

    /// [`Scorer::fit_shrunk`], stopped once `give_up` holds after a step.
    fn fit_until(
        &self,
        effects: &[Effect],
        rows: &[usize],
        set: Option<RowSet>,
        lambda: f64,
        give_up: Option<&GiveUp>,
    ) -> Result<(Model, Fit), DiagnoseError> {
        let model = self.model(effects, rows)?;
        let initial = model.initial();
        let mut start = Start::new(initial, vec![true; model.len()]);
        start.give_up = give_up.cloned();
        if lambda > 0.0 {
            let (squares, n) = self.initial_squares(&model, rows, set)?;
            start.prior = Some(prior(&model, (&squares, n), lambda));
        }
        let key = set.map(|s| (model.effects().to_vec(), s, lambda > 0.0));
        start.identified = key.as_ref().and_then(|k| self.identified.lock().ok().and_then(|m| m.get(k).cloned()));
        let mut best = fit_from(self.robot, &model, self.data, rows, &self.terms, &start)?;
        if let Some(k) = key
            && start.identified.is_none()
            && let Ok(mut m) = self.identified.lock()
        {
            m.insert(k, best.identified.clone());
        }
        // Two or more exponential drifts started at one time constant: their laws begin alike and the
        // fit may settle with both near one of them (a warm-up whose rows rise over 20 and 60 minutes,
        // `warmup_loop.rs`). They are fitted again from the other starts too, and the lowest training
        // cost wins (the held-out poses play no part). One drift's time constant is found from the
        // default start (in the rate `1/τ` its cost is nearly quadratic) and is not refitted: a week of
        // poses scores such a candidate every round.
        let taus = model.time_constants();
        if taus.len() >= 2 {
            for tau in self.tau_starts() {
                let mut other = start.clone();
                other.identified = None;
                for &c in &taus {
                    other.theta[c] = tau;
                }
                let f = fit_from(self.robot, &model, self.data, rows, &self.terms, &other)?;
                if f.ssr < best.ssr {
                    best = f;
                }
            }
        }
        Ok((model, best))
    }

    /// The other starting time constants of a fit with several exponential drifts
    /// ([`Scorer::fit_shrunk`]), beside the model's own: a twenty-fourth and a sixth of the session's
    /// span (7.5 and 30 minutes over a 180-minute warm-up).
    fn tau_starts(&self) -> Vec<f64> {
        let span = self.data.time_span();
        [span / 24.0, span / 6.0].into_iter().filter(|t| t.is_finite() && *t > 0.0).collect()
    }

    /// What the block at `k` of `model`, fitted at `theta` on the poses `rows`, traded with ([`Trade`]):
    /// the displacement its values give those poses, `d = J_k (θ_k − θ_k⁰)` (the Jacobian at the fit), and
    /// the share of it each other block's columns span, by least squares on their unit columns
    /// ([`unit_ridged_step`]); `None` where it gives no displacement or the model has no other block.
    pub(crate) fn traded_with(
        &self,
        model: &Model,
        theta: &[f64],
        rows: &[usize],
        k: usize,
    ) -> Result<Option<Trade>, DiagnoseError> {
        let (_, jac) = residuals_and_jacobian(self.robot, model, theta, self.data, rows, &self.terms)?;
        let start = model.initial();
        let offsets = model.offsets();
        let block = |i: usize| offsets[i]..offsets[i] + model.effects()[i].len();
        let d: Vec<f64> =
            (0..jac.nrows()).map(|r| block(k).map(|c| jac[(r, c)] * (theta[c] - start[c])).sum::<f64>()).collect();
        let dd: f64 = d.iter().map(|x| x * x).sum();
        if dd.is_nan() || dd <= 0.0 {
            return Ok(None);
        }
        // Every block's Gram matrix and inner products with `d` at once; a block's share is `gᵀx`,
        // `x` its least-squares coefficients (‖P d‖² of the projection).
        let p = model.len();
        let (mut n, mut g) = (Mat::<f64>::zeros(p, p), Mat::<f64>::zeros(p, 1));
        add_normal_equations(&mut n, &mut g, &jac, &d);
        let share = |cols: &[usize]| -> f64 {
            let idx: Vec<usize> = cols.iter().copied().filter(|&c| n[(c, c)] > 0.0).collect();
            let rhs: Vec<f64> = idx.iter().map(|&c| g[(c, 0)]).collect();
            match unit_ridged_step(&n, &idx, &rhs) {
                Some(x) if !idx.is_empty() => {
                    (rhs.iter().zip(&x).map(|(a, b)| a * b).sum::<f64>() / dd).clamp(0.0, 1.0)
                }
                _ => 0.0,
            }
        };
        let others: Vec<usize> = (0..model.effects().len()).filter(|&i| i != k).collect();
        let best = others
            .iter()
            .map(|&i| (model.effects()[i], share(&block(i).collect::<Vec<_>>())))
            .max_by(|a, b| a.1.total_cmp(&b.1));
        let Some((with, best_share)) = best else { return Ok(None) };
        let rest: Vec<usize> = others.iter().flat_map(|&i| block(i)).collect();
        Ok(Some(Trade {
            with,
            share: best_share,
            rest: share(&rest),
            half_in: half_carried_by(&d, self.terms.stride()),
            parameters: model.effects()[k].len(),
        }))
    }

    /// The parameters of `candidate` that stay identifiable next to `effects`, on all data.
    pub(crate) fn new_free(&self, effects: &[Effect], candidate: Effect) -> Result<Addition, DiagnoseError> {
        let mut all_effects = effects.to_vec();
        all_effects.push(candidate);
        let model = self.model(&all_effects, &self.all())?;
        let jac = self.jacobian_at_start(&model)?;
        let decided = identifiable(jac.as_ref(), &vec![true; model.len()]);
        let start = model.offsets()[model.offsets().len() - 1];
        let new_free = (start..model.len()).filter(|&c| decided.free[c]).count();
        let fixed = model
            .fixed_parameters(&decided.fixed)
            .into_iter()
            .filter(|f| candidate.parameter_names().contains(&f.parameter))
            .collect();
        Ok(Addition { new_free, fixed })
    }

    /// Every measurement's index.
    pub(crate) fn all(&self) -> Vec<usize> {
        (0..self.data.len()).collect()
    }

    /// The Jacobian of `model` at its initial values on all measurements (where a candidate's
    /// identifiability and relations are judged).
    pub(crate) fn jacobian_at_start(&self, model: &Model) -> Result<faer::Mat<f64>, DiagnoseError> {
        let all = self.all();
        Ok(residuals_and_jacobian(self.robot, model, &model.initial(), self.data, &all, &self.terms)?.1)
    }

    /// The model of `effects` fitted on all measurements (least squares).
    pub(crate) fn full_fit(&self, effects: &[Effect]) -> Result<(Model, Fit), DiagnoseError> {
        self.fit_shrunk(effects, &self.all(), 0.0)
    }

    /// The Bayesian information criterion of a fit on all of the data.
    pub(crate) fn bic_of(&self, f: &Fit) -> f64 {
        let m = (self.data.len() * self.terms.stride()) as f64;
        let k = f.free.iter().filter(|&&x| x).count() as f64;
        m * (f.ssr / m).max(1e-300).ln() + k * m.ln()
    }
}

/// Ridge on unit-scaled normal equations ([`unit_ridged_step`]): a column that duplicates another (no
/// gain, singular equations) stays solvable without moving the others.
pub(crate) const RIDGE: f64 = 1e-9;

/// Poses per block wherever a Jacobian is reduced to what its use needs (normal equations, column norms,
/// predicted residuals): one block's Jacobian is alive at a time, so that memory and the cache it misses
/// do not grow with the poses (a week's training part with every shortlisted candidate's columns,
/// 80,000 poses × 3 rows × 70 columns, would be 134 MB at once; a block of 1,000 poses is 1.7 MB).
pub(crate) const CHUNK_POSES: usize = 1000;

impl Scorer<'_> {
    /// `JᵀJ` and `Jᵀr` of `model` at `theta` on the measurements `rows` (the residuals and Jacobian of
    /// [`residuals_and_jacobian`]), accumulated [`CHUNK_POSES`] poses at a time.
    pub(crate) fn normal_equations(
        &self,
        model: &Model,
        theta: &[f64],
        rows: &[usize],
    ) -> Result<(Mat<f64>, Mat<f64>), DiagnoseError> {
        let p = model.len();
        let (mut n, mut g) = (Mat::<f64>::zeros(p, p), Mat::<f64>::zeros(p, 1));
        for block in rows.chunks(CHUNK_POSES) {
            let (r, j) = residuals_and_jacobian(self.robot, model, theta, self.data, block, &self.terms)?;
            add_normal_equations(&mut n, &mut g, &j, &r);
        }
        Ok((n, g))
    }

    /// [`Scorer::column_squares`] of `model` at its initial values on `rows`, kept when `rows` are the
    /// scorer's row set `set` (a model's initial values depend on its effects and its rows alone:
    /// [`Scorer::model`]).
    pub(crate) fn initial_squares(
        &self,
        model: &Model,
        rows: &[usize],
        set: Option<RowSet>,
    ) -> Result<(Vec<f64>, usize), DiagnoseError> {
        let squares = || self.column_squares(model, &model.initial(), rows);
        match set {
            Some(set) => kept_or(&self.squares, (model.effects().to_vec(), set), squares),
            None => squares(),
        }
    }

    /// The squared norm of each column of the Jacobian of `model` at `theta` on `rows`, and its number of
    /// rows, [`CHUNK_POSES`] poses at a time.
    pub(crate) fn column_squares(
        &self,
        model: &Model,
        theta: &[f64],
        rows: &[usize],
    ) -> Result<(Vec<f64>, usize), DiagnoseError> {
        let mut squares = vec![0.0; model.len()];
        for block in rows.chunks(CHUNK_POSES) {
            let (_, j) = residuals_and_jacobian(self.robot, model, theta, self.data, block, &self.terms)?;
            for (c, sq) in squares.iter_mut().enumerate() {
                *sq += j.col(c).squared_norm_l2();
            }
        }
        Ok((squares, rows.len() * self.terms.stride()))
    }
}

/// `JᵀJ` and `Jᵀr` of the Jacobian `j` and residuals `r`, added into `n` and `g` (one product each; a
/// block of poses at a time, the sum over blocks is all of them).
pub(crate) fn add_normal_equations(n: &mut Mat<f64>, g: &mut Mat<f64>, j: &Mat<f64>, r: &[f64]) {
    let rv = faer::ColRef::from_slice(r);
    faer::linalg::matmul::matmul(n.as_mut(), faer::Accum::Add, j.transpose(), j.as_ref(), 1.0, faer::Par::Seq);
    faer::linalg::matmul::matmul(g.as_mut(), faer::Accum::Add, j.transpose(), rv.as_mat(), 1.0, faer::Par::Seq);
}

/// The step `δ` (in the parameters' own units) on columns `idx` of the normal equations `n δ = rhs`
/// (`rhs` on those columns), solved on unit columns — each scaled by `√n_cc`, so that mm, radians and
/// minutes weigh alike — with [`RIDGE`] on their unit diagonal; `None` when not solvable. Every column
/// of `idx` must move something (`n_cc > 0`).
pub(crate) fn unit_ridged_step(n: &Mat<f64>, idx: &[usize], rhs: &[f64]) -> Option<Vec<f64>> {
    let q = idx.len();
    let scale = |i: usize| n[(idx[i], idx[i])].max(0.0).sqrt();
    let sub = Mat::<f64>::from_fn(q, q, |i, k| {
        n[(idx[i], idx[k])] / (scale(i) * scale(k)) + if i == k { RIDGE } else { 0.0 }
    });
    let rhs = Mat::<f64>::from_fn(q, 1, |i, _| rhs[i] / scale(i));
    let llt = sub.llt(faer::Side::Lower).ok()?;
    let step = faer::prelude::Solve::solve(&llt, &rhs);
    Some((0..q).map(|i| step[(i, 0)] / scale(i)).collect())
}

/// Whether model `b` has a lower held-out mean squared error than model `a`, by more than `z` standard
/// errors of the paired difference (errors `a[i]`, `b[i]` of the same measurement): the acceptance rule
/// of the ladder. With `z = 1` this is the one-standard-error rule: an improvement smaller than its own
/// uncertainty is not taken. The standard error is taken over blocks (`blocks[i]`, the block of error
/// `i`: a cluster-robust standard error of the mean, `√(B/(B−1) · Σ_b (D_b − n_b·d̄)²) / n`, `D_b` the
/// block's summed difference): neighbouring poses share their systematic residuals, so a gain that
/// holds in a few neighbourhoods only is not counted once per pose. With one measurement per block this
/// is the ordinary paired standard error.
pub(crate) fn significantly_better(a: &[f64], b: &[f64], z: f64, blocks: &[usize]) -> bool {
    let n = a.len().min(b.len());
    if n < 2 {
        return false;
    }
    let d: Vec<f64> = a.iter().zip(b).map(|(x, y)| x * x - y * y).collect();
    let mean = d.iter().sum::<f64>() / n as f64;
    let mut sums: std::collections::BTreeMap<usize, (f64, f64)> = std::collections::BTreeMap::new();
    for (i, v) in d.iter().enumerate() {
        let e = sums.entry(blocks.get(i).copied().unwrap_or(usize::MAX - i)).or_insert((0.0, 0.0));
        e.0 += v;
        e.1 += 1.0;
    }
    let count = sums.len();
    if count < 2 {
        return false;
    }
    let ss: f64 = sums.values().map(|(s, m)| (s - m * mean) * (s - m * mean)).sum();
    let var_of_mean = ss * count as f64 / (count - 1) as f64 / (n as f64 * n as f64);
    mean > z * var_of_mean.sqrt()
}

impl Scorer<'_> {
    /// How effect `e`'s parameter directions relate to each of `others` on these data: `Equivalent` when
    /// the two blocks' Jacobian columns span the same space, `ContainedIn` when `e`'s lie in the other's
    /// span (the other block can do all `e` does, and more), `Contains` the other way round, decided by rank with the identifiability
    /// tolerance: a direction within 1e-6 (relative) of a span belongs to it. Linearised at the nominal
    /// model (every parameter zero) over all measurements.
    pub(crate) fn relations(&self, e: Effect, others: &[Effect]) -> Result<Vec<(Effect, Relation)>, DiagnoseError> {
        let mut out = Vec::new();
        for &b in others {
            if b == e || b.is_reported() != e.is_reported() {
                continue;
            }
            let Some((e_in_b, b_in_e)) = self.spans(e, b)? else { continue };
            match (e_in_b, b_in_e) {
                (true, true) => out.push((b, Relation::Equivalent)),
                (true, false) => out.push((b, Relation::ContainedIn)),
                (false, true) => out.push((b, Relation::Contains)),
                _ => {}
            }
        }
        Ok(out)
    }
}

impl Scorer<'_> {
    /// The relations' Gram matrix of the catalogue ([`RelationGram`]), formed on first use, block of poses
    /// by block of poses; `None` when the catalogue's model cannot be built.
    fn relation_gram(&self) -> Option<&RelationGram> {
        self.relation_gram
            .get_or_init(|| {
                let model = self.model(&self.catalogue, &self.all()).ok()?;
                let initial = model.initial();
                let p = model.len();
                let mut gram = Mat::<f64>::zeros(p, p);
                let all = self.all();
                for rows in all.chunks(GRAM_CHUNK_POSES) {
                    let (_, jac) =
                        residuals_and_jacobian(self.robot, &model, &initial, self.data, rows, &self.terms).ok()?;
                    faer::linalg::matmul::matmul(
                        gram.as_mut(),
                        faer::Accum::Add,
                        jac.as_ref().transpose(),
                        jac.as_ref(),
                        1.0,
                        faer::Par::Seq,
                    );
                }
                Some(RelationGram {
                    rows: all.len() * self.terms.stride(),
                    effects: self.catalogue.clone(),
                    offsets: model.offsets().to_vec(),
                    gram,
                })
            })
            .as_ref()
    }

    /// Whether `e`'s columns lie in `b`'s span and `b`'s in `e`'s, on all measurements at the nominal
    /// robot; `None` when either block moves nothing there (gravity about a vertical axis).
    fn spans(&self, e: Effect, b: Effect) -> Result<Option<(bool, bool)>, DiagnoseError> {
        let indices = |g: &RelationGram, x: Effect| {
            g.effects.iter().position(|y| *y == x).map(|k| (g.offsets[k]..g.offsets[k] + x.len()).collect::<Vec<_>>())
        };
        if let Some(g) = self.relation_gram()
            && let (Some(ie), Some(ib)) = (indices(g, e), indices(g, b))
        {
            // As on the columns themselves (an entry beyond 1e-12), by their RMS: gravity's torque about a
            // vertical axis leaves ~1e-13 of rounding in every entry, which sums beyond 1e-12 over the rows.
            let moves = |cols: &[usize]| cols.iter().any(|&c| (g.gram[(c, c)] / g.rows.max(1) as f64).sqrt() > 1e-12);
            if !moves(&ie) || !moves(&ib) {
                return Ok(None);
            }
            return Ok(Some((within_span_gram(&g.gram, &ie, &ib), within_span_gram(&g.gram, &ib, &ie))));
        }
        // A block outside the catalogue: its pair's Jacobian.
        let model = self.model(&[e, b], &self.all())?;
        let jac = self.jacobian_at_start(&model)?;
        let cols = |range: std::ops::Range<usize>| -> Vec<Vec<f64>> {
            range.map(|c| (0..jac.nrows()).map(|r| jac[(r, c)]).collect()).collect()
        };
        let (ce, cb) = (cols(0..e.len()), cols(e.len()..e.len() + b.len()));
        let moves = |c: &[Vec<f64>]| c.iter().any(|v| v.iter().any(|x| x.abs() > 1e-12));
        if !moves(&ce) || !moves(&cb) {
            return Ok(None);
        }
        Ok(Some((within_span(&ce, &cb), within_span(&cb, &ce))))
    }
}

/// How one block's parameter directions relate to another's on the data.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Relation {
    /// The same column space.
    Equivalent,
    /// Inside the other's column space.
    ContainedIn,
    /// The other's column space is inside this one's.
    Contains,
}

/// [`within_span`] on columns given by their Gram matrix `gram` (indices `a`, `b` into it): Gram–Schmidt
/// in the Gram matrix's metric — for each unit column of `b`, its distance from the span of those kept
/// before, `√(1 − |y|²)` with `L y = s` (`L` the Cholesky factor of the kept ones' unit Gram matrix, `s`
/// their inner products with it), kept at [`DEPENDENT`] or more; then each column of `a` within
/// [`DEPENDENT`] of their span. The distance carries the rounding of a difference of squares, ~1e-8
/// where the columns themselves give ~1e-15: two orders of magnitude below the threshold.
fn within_span_gram(gram: &Mat<f64>, a: &[usize], b: &[usize]) -> bool {
    let unit = |i: usize, j: usize| gram[(i, j)] / (gram[(i, i)] * gram[(j, j)]).sqrt();
    // Rows of the Cholesky factor of the kept columns' unit Gram matrix.
    let mut kept: Vec<usize> = Vec::new();
    let mut l: Vec<Vec<f64>> = Vec::new();
    let distance = |kept: &[usize], l: &[Vec<f64>], x: usize| -> (Vec<f64>, f64) {
        let mut y = Vec::with_capacity(kept.len());
        for (k, row) in l.iter().enumerate() {
            let v = (unit(kept[k], x) - row[..k].iter().zip(&y).map(|(r, y)| r * y).sum::<f64>()) / row[k];
            y.push(v);
        }
        let rest = 1.0 - y.iter().map(|v| v * v).sum::<f64>();
        (y, rest.max(0.0).sqrt())
    };
    for &c in b {
        if gram[(c, c)].sqrt() < 1e-12 {
            continue;
        }
        let (mut y, d) = distance(&kept, &l, c);
        if d >= DEPENDENT {
            y.push(d);
            l.push(y);
            kept.push(c);
        }
    }
    a.iter().all(|&c| gram[(c, c)].sqrt() < 1e-12 || distance(&kept, &l, c).1 < DEPENDENT)
}

/// Whether every non-zero column of `a` lies in the span of `b` (Gram–Schmidt, twice, on unit columns).
fn within_span(a: &[Vec<f64>], b: &[Vec<f64>]) -> bool {
    let norm = |v: &[f64]| v.iter().map(|x| x * x).sum::<f64>().sqrt();
    let mut basis: Vec<Vec<f64>> = Vec::new();
    for col in b {
        let n0 = norm(col);
        if n0 < 1e-12 {
            continue;
        }
        let mut v: Vec<f64> = col.iter().map(|x| x / n0).collect();
        let n = project_out(&basis, &mut v);
        if n >= DEPENDENT {
            basis.push(v.iter().map(|x| x / n).collect());
        }
    }
    a.iter().all(|col| {
        let n0 = norm(col);
        if n0 < 1e-12 {
            return true;
        }
        let mut v: Vec<f64> = col.iter().map(|x| x / n0).collect();
        project_out(&basis, &mut v) < DEPENDENT
    })
}

/// How many poses carry half of a displacement `d` (`stride` rows per pose), of how many: its poses'
/// squared norms summed from the largest down until they reach half the total.
fn half_carried_by(d: &[f64], stride: usize) -> (usize, usize) {
    let mut energy: Vec<f64> = d.chunks(stride.max(1)).map(|r| r.iter().map(|x| x * x).sum()).collect();
    let (poses, total) = (energy.len(), energy.iter().sum::<f64>());
    if poses == 0 || total.is_nan() || total <= 0.0 {
        return (0, poses);
    }
    energy.sort_by(|a, b| b.total_cmp(a));
    let mut sum = 0.0;
    let count = energy.iter().take_while(|&&e| {
        let below = sum < 0.5 * total;
        sum += e;
        below
    });
    (count.count(), poses)
}

#[cfg(test)]
mod tests {
    use super::*;
    use thermokin_identify::JointIndex;

    /// Half a displacement's `‖d‖²` counted over the poses it is largest at: one pose holding most of it
    /// is one pose; equal poses take half of them; none moved, none.
    #[test]
    fn half_of_a_displacement_is_counted_from_its_largest_poses() {
        let mut d = vec![0.01; 30];
        d[3] = 5.0;
        assert_eq!(half_carried_by(&d, 3), (1, 10));
        assert_eq!(half_carried_by(&[1.0; 30], 3), (5, 10));
        assert_eq!(half_carried_by(&[0.0; 6], 3), (0, 2));
        // A value stands when no block spans half of it and more poses than its parameters carry half.
        let trade = |share, rest, half, parameters| Trade {
            with: Effect::Registration,
            share,
            rest,
            half_in: (half, 100),
            parameters,
        };
        assert!(trade(0.2, 0.4, 12, 10).stands());
        assert!(!trade(0.6, 0.6, 12, 10).stands() && !trade(0.2, 0.55, 12, 10).stands());
        assert!(!trade(0.2, 0.4, 10, 10).stands());
    }

    #[test]
    fn single_pose_blocks_give_the_paired_standard_error() {
        // a² − b² = 1 + (−1)^i · 0.5: mean 1, sample sd 0.5·√(n/(n−1)); 1 > z·SE for z up to ~ 2√n.
        let n = 16;
        let a: Vec<f64> = (0..n).map(|i| (2.0f64 + if i % 2 == 0 { 0.5 } else { -0.5 }).sqrt()).collect();
        let b = vec![1.0; n];
        let blocks: Vec<usize> = (0..n).collect();
        let se = 0.5 * (n as f64 / (n - 1) as f64).sqrt() / (n as f64).sqrt();
        assert!(significantly_better(&a, &b, 0.99 / se, &blocks));
        assert!(!significantly_better(&a, &b, 1.01 / se, &blocks));
    }

    #[test]
    fn a_gain_held_by_one_block_is_not_significant_over_blocks() {
        // Every pose of block 0 gains a lot, the others nothing: per pose the gain looks consistent
        // (one SE passes), over four blocks it is one block's luck (it does not).
        let a: Vec<f64> = (0..40).map(|i| if i < 10 { 2.0 } else { 1.0 }).collect();
        let b = vec![1.0; 40];
        let per_pose: Vec<usize> = (0..40).collect();
        let per_block: Vec<usize> = (0..40).map(|i| i / 10).collect();
        assert!(significantly_better(&a, &b, 1.0, &per_pose));
        assert!(!significantly_better(&a, &b, 2.0, &per_block));
        // Equal gains in every block stay significant.
        let even: Vec<f64> = (0..40).map(|i| if i % 10 < 5 { 2.0 } else { 1.5 }).collect();
        assert!(significantly_better(&even, &b, 2.0, &per_block));
    }

    /// A simulated IRB 140 with every joint's row 0.1 mm off, 60 poses.
    #[allow(clippy::unwrap_used)] // Tests unwrap to fail.
    fn rows_off() -> (thermokin_chain::Robot, thermokin_chain::Dataset) {
        use crate::{HiddenEffect, SimulationConfig, simulate};
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
        let robot = thermokin_io::read_robot(&root.join("configs/irb140.toml")).unwrap();
        let hidden: Vec<HiddenEffect> = (0..6)
            .map(|j| HiddenEffect {
                effect: Effect::LinkDeviation(JointIndex::of(&robot, j).unwrap()),
                values: vec![0.1, -0.1, 0.1, 0.0, 0.0, 0.0],
            })
            .collect();
        let data = simulate(&robot, &hidden, &SimulationConfig { poses: 60, ..SimulationConfig::default() }).unwrap();
        (robot, data)
    }

    /// What a value traded with, on a simulated IRB 140 (every joint's row 0.1 mm off, 60 poses): a
    /// joint offset of 0.5° beside its link row, which holds the offset's direction (the row's rotation
    /// about the joint's axis, the parent's frame), gives a displacement that row spans entirely; a
    /// gear ratio (a scale of joint 3's angle) beside the registration and probe alone lies in neither.
    #[test]
    #[allow(clippy::unwrap_used)] // Tests unwrap to fail.
    fn a_trade_names_the_block_that_spans_the_displacement() {
        let (robot, data) = rows_off();
        let joint = |j| JointIndex::of(&robot, j).unwrap();
        let config = Config::default();
        let scorer = Scorer::new(&robot, &data, &config);
        let all = scorer.all();
        let effects = vec![Effect::Registration, Effect::LinkDeviation(joint(2)), Effect::JointOffset(joint(2))];
        let model = scorer.model(&effects, &all).unwrap();
        let mut theta = model.initial();
        let o = model.offsets()[2];
        theta[o] += 0.5f64.to_radians();
        let trade = scorer.traded_with(&model, &theta, &all, 2).unwrap().unwrap();
        assert_eq!(trade.with, Effect::LinkDeviation(joint(2)), "{trade:?}");
        assert!(trade.share > 0.999 && trade.rest > 0.999, "{trade:?}");
        assert!(trade.words().contains("traded it with link_deviation[3]"), "{}", trade.words());
        let effects = vec![Effect::Registration, Effect::ToolPoint, Effect::JointScale(joint(2))];
        let model = scorer.model(&effects, &all).unwrap();
        let mut theta = model.initial();
        let o = model.offsets()[2];
        theta[o] += 0.05;
        let trade = scorer.traded_with(&model, &theta, &all, 2).unwrap().unwrap();
        assert!(trade.share < 0.5 && trade.rest < 0.5, "{trade:?}");
        assert!(trade.words().starts_with("it traded with no block"), "{}", trade.words());
    }

    /// What a scorer keeps between fits (a model's prior column squares and its first identifiability
    /// decision, by row set) changes no fit: on a simulated IRB 140 (every joint's row 0.1 mm off, 60
    /// poses), a shrunk fit on all poses and on every fold, after the same model's least-squares and
    /// weaker fits, equals to the bit the one a fresh scorer makes first. Fails if a kept value of
    /// another row set, or of a fit without a prior, reached it.
    #[test]
    #[allow(clippy::unwrap_used)] // Tests unwrap to fail.
    fn what_a_scorer_keeps_between_fits_changes_no_fit() {
        let (robot, data) = rows_off();
        let joint = |j| JointIndex::of(&robot, j).unwrap();
        let config = Config::default();
        let effects: Vec<Effect> = [Effect::Registration, Effect::ToolPoint]
            .into_iter()
            .chain((0..6).map(|j| Effect::LinkDeviation(joint(j))))
            .collect();
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        let used = Scorer::new(&robot, &data, &config);
        for lambda in [0.0, 0.3] {
            used.fit_shrunk(&effects, &used.all(), lambda).unwrap();
            used.heldout_fits_with(&effects, &used.folds, lambda).unwrap();
        }
        let fresh = Scorer::new(&robot, &data, &config);
        let (_, a) = used.fit_shrunk(&effects, &used.all(), 3.0).unwrap();
        let (_, b) = fresh.fit_shrunk(&effects, &fresh.all(), 3.0).unwrap();
        assert_eq!(bits(&a.theta), bits(&b.theta));
        assert_eq!(a.free, b.free);
        let a = used.heldout_fits_with(&effects, &used.folds, 3.0).unwrap();
        let b = fresh.heldout_fits_with(&effects, &fresh.folds, 3.0).unwrap();
        for (x, y) in a.thetas.iter().zip(&b.thetas) {
            assert_eq!(bits(x), bits(y));
        }
        assert_eq!(a.free, b.free);
        assert_eq!(used.squares.lock().unwrap().len(), 1 + used.folds.len());
    }
}
