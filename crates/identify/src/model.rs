//! The parameterised model: effects as parameter blocks on top of a robot, the parameter vector's
//! layout, and the robot they identify ([`Model::robot_model`]). Its prediction of a measured pose and
//! the Jacobian of it are in `predict`.

use nalgebra::{Isometry3, Vector3};
use thermokin_chain::{Chain, Dataset, ErrorParams, Measurement, ParameterRows, Robot};
use thermokin_deform::{DriftLaw, DriftRow, JointCorrection, RobotModel, Row};

use crate::effect::{DriftShape, Effect, INITIAL_TAU_MIN, PAIR_START, TAU_RANGE_MIN, six_at};
use crate::error::IdentifyError;
use crate::identifiability::{Dependence, DependsOn, FixedParameter};
use crate::terms::sensor_joint;

/// A model: a list of effects on top of a robot (its chain, known deviations included, and its link
/// masses), and the parameter vector's layout. Built by [`Model::new`], which checks every effect against
/// the robot; the layout is derived from the effects and cannot drift from them.
#[derive(Clone, Debug)]
pub struct Model {
    effects: Vec<Effect>,
    offsets: Vec<usize>,
    len: usize,
    registration: Isometry3<f64>,
    tool_start_mm: Vector3<f64>,
}

/// `|cos|` from which a fixed parameter's column is called equivalent to the accepted column it lies
/// along: within 1.8° of it (a parameter at `|cos| = 0.59`, 54° off, is no one column's equivalent —
/// issue #61).
pub const EQUIVALENT_COS: f64 = 0.9995;

impl Model {
    /// A model of `robot` with these effects (in parameter order).
    pub fn new(robot: &Robot, effects: Vec<Effect>) -> Result<Self, IdentifyError> {
        let dof = robot.chain().dof();
        let mut offsets = Vec::with_capacity(effects.len());
        let mut len = 0;
        for e in &effects {
            e.validate(dof)?;
            offsets.push(len);
            len += e.len();
        }
        Ok(Self { effects, offsets, len, registration: Isometry3::identity(), tool_start_mm: Vector3::zeros() })
    }

    /// The same model with its frame blocks starting at `start` ([`crate::initial_frames`]): the
    /// registration, and the tool point (when the model estimates one; ignored otherwise) — the
    /// parameters are corrections on top.
    pub fn with_start(mut self, start: StartFrames) -> Self {
        self.registration = start.registration;
        if self.effects.contains(&Effect::ToolPoint) {
            self.tool_start_mm = start.tool_point_mm;
        }
        self
    }

    /// The effects, in parameter order.
    pub fn effects(&self) -> &[Effect] {
        &self.effects
    }

    /// The first parameter of each effect.
    pub fn offsets(&self) -> &[usize] {
        &self.offsets
    }

    /// The number of parameters.
    pub fn len(&self) -> usize {
        self.len
    }

    /// `true` when the model has no parameter.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Whether the model estimates a tracker registration.
    pub fn has_registration(&self) -> bool {
        self.effects.contains(&Effect::Registration)
    }

    /// The initial parameter vector (zeros; τ at its starting value, a compliance pair's `w` at [`PAIR_START`]).
    pub fn initial(&self) -> Vec<f64> {
        let mut theta = vec![0.0; self.len];
        for (e, &o) in self.effects.iter().zip(&self.offsets) {
            match e {
                Effect::ThermalDrift(_, DriftShape::Exponential) => theta[o + 6] = INITIAL_TAU_MIN,
                Effect::CompliancePair(_) => theta[o..o + 2].fill(PAIR_START),
                _ => {}
            }
        }
        theta
    }

    /// The columns that are time constants (an exponential drift's τ, minutes), with the range a fit
    /// keeps them in: the identification moves their rate `1/τ` rather than τ ([`crate::fit`]).
    pub fn time_constants(&self) -> Vec<usize> {
        self.effects
            .iter()
            .zip(&self.offsets)
            .filter(|(e, _)| matches!(e, Effect::ThermalDrift(_, DriftShape::Exponential)))
            .map(|(_, &o)| o + 6)
            .collect()
    }

    /// Names of all parameters.
    pub fn parameter_names(&self) -> Vec<String> {
        self.effects.iter().flat_map(Effect::parameter_names).collect()
    }

    /// The effect parameter `column` belongs to, and its place in that effect's block.
    pub fn parameter(&self, column: usize) -> Option<(Effect, usize)> {
        let k = self.offsets.iter().rposition(|&o| o <= column)?;
        let e = self.effects[k];
        (column - self.offsets[k] < e.len()).then_some((e, column - self.offsets[k]))
    }

    /// The columns [`identifiable`](crate::identifiable) fixed, named, each with its reason in words: one
    /// along a single accepted column to within [`EQUIVALENT_COS`] is equivalent to it; one less aligned
    /// is a combination of the accepted ones, named by the column it lies most along.
    pub fn fixed_parameters(&self, fixed: &[Dependence]) -> Vec<FixedParameter> {
        let names = self.parameter_names();
        fixed
            .iter()
            .map(|d| {
                let reason = match d.on {
                    // A tool's rotation moves no point: it is seen in measured orientations only.
                    DependsOn::Nothing if matches!(self.parameter(d.column), Some((Effect::ToolFrame, 3..))) => {
                        "moves no measured point: a tool's rotation is identified from measured orientations (rx, ry, rz)".to_string()
                    }
                    DependsOn::Nothing => "no effect on the measurements".to_string(),
                    DependsOn::Column { column, cos } if cos >= EQUIVALENT_COS => {
                        format!("equivalent to {} (|cos| = {cos:.3})", names[column])
                    }
                    DependsOn::Column { column, cos } => format!(
                        "a combination of the parameters already identified, mostly along {} (|cos| = {cos:.3})",
                        names[column]
                    ),
                    DependsOn::Combination => "a combination of the parameters already identified".to_string(),
                };
                FixedParameter { parameter: names[d.column].clone(), reason }
            })
            .collect()
    }

    /// The drift factor `s = f(t) / f(180)` of a shape at one measurement (`f` the law of the deform
    /// profile, [`DriftShape::profile`]) and `ds/dτ` for the exponential — zero where τ is held at a
    /// (gravity compliance, thermal drift), which are left out.
    pub fn calibrated_chain(&self, robot: &Robot, theta: &[f64]) -> Result<(Chain, Vec<Effect>), IdentifyError> {
        let (chain, _) = self.static_chain(robot, theta)?;
        let left_out = self.effects.iter().filter(|e| !e.is_static()).copied().collect();
        Ok((chain, left_out))
    }

    /// The identified robot with every effect of this model at `theta` — what a robot file carries and
    /// every command evaluates ([`RobotModel`]): the static effects in the chain
    /// ([`Model::calibrated_chain`]); gear-ratio, cyclic and compliance terms as joint corrections; each
    /// thermal drift as a drift row with its own law — linear and exponential as the deform profile whose
    /// factor at 180 minutes is 1 after dividing by `f(180)` ([`DriftShape::reference_factor`]), a
    /// temperature drift per kelvin of the joint's own sensor (or of the mean of all, as fitted), each
    /// against its reading at the earliest measurement of `data` (the fit's reference). Gravity keeps its
    /// direction in the robot's base frame while the registration turns the base row into the tracker's.
    /// After a step of the measurement frame ([`Effect::FrameStep`]) the base row is the frame the
    /// measurements ended in (a knocked tracker stays where it was knocked).
    ///
    /// Its forward model equals [`Model::predict`]'s at every measurement after the last step of the frame
    /// (every one without a step; a test checks it to 1e-9 mm).
    pub fn robot_model(&self, robot: &Robot, theta: &[f64], data: &Dataset) -> Result<RobotModel, IdentifyError> {
        let (chain, _) = self.static_chain(robot, theta)?;
        // A measured frame's rows in their simplest form: the tracker registration's start and correction,
        // and an unknown tool point's, are one pose each — written as one (a start of −31.66 mm and a
        // correction of +31.25 mm read as alarming numbers that cancel).
        let mut chain = chain;
        // The frame the measurements ended in: after every step of it (a knocked tracker stays where it was
        // knocked; a later use is measured there).
        let mut world_from_base = chain.base().pose();
        let mut stepped = false;
        for (_, &o) in self.effects.iter().zip(&self.offsets).filter(|(e, _)| matches!(e, Effect::FrameStep(_))) {
            let rotation = thermokin_chain::xyz_rotation(&Vector3::new(theta[o + 3], theta[o + 4], theta[o + 5]));
            let step = Isometry3::from_parts(
                Vector3::new(theta[o], theta[o + 1], theta[o + 2]).into(),
                nalgebra::UnitQuaternion::from_matrix(&rotation),
            );
            world_from_base = step * world_from_base;
            stepped = true;
        }
        if self.has_registration() || stepped {
            chain = chain.with_base(thermokin_chain::FixedRow::from_isometry(&world_from_base))?;
        }
        // Gravity keeps its direction in the robot's base, in whichever frame the base row now puts it.
        let down = self.gravity_down(&chain, robot);
        if self.effects.contains(&Effect::ToolPoint) {
            chain = chain.with_tool(thermokin_chain::FixedRow::from_isometry(&chain.tool().pose()))?;
        }
        let dof = robot.chain().dof();
        let mut joints = vec![JointCorrection::NONE; dof];
        let mut loads: Vec<Vec<f64>> = vec![Vec::new(); dof];
        let mut lateral_loads: Vec<Vec<f64>> = vec![Vec::new(); dof];
        let mut drift = Vec::new();
        let mut branch_loads: Vec<thermokin_deform::BranchLoad> = Vec::new();
        let first = data.measurements.iter().min_by(|a, b| a.time_min.total_cmp(&b.time_min));
        for (e, &o) in self.effects.iter().zip(&self.offsets) {
            match *e {
                Effect::JointCompliance(j) => joints[j.index()].compliance_rad_per_nm += theta[o],
                Effect::LumpedCompliance(j, n) | Effect::LumpedLateralCompliance(j, n, _) => {
                    let own = match e {
                        Effect::LumpedCompliance(..) => &mut loads[j.index()],
                        _ => &mut lateral_loads[j.index()],
                    };
                    own.resize(n as usize, 0.0);
                    own.iter_mut().zip(&theta[o..o + n as usize]).for_each(|(l, t)| *l += t);
                }
                Effect::ComplianceCoupling(j) => joints[j.index()].coupling_rad_per_nm += theta[o],
                Effect::CompliancePair(j) => add_pair(&mut joints, j.index(), theta[o], theta[o + 1]),
                Effect::BranchLoad(j, _, at) => branch_loads.push(branch_load(robot, j, at, &theta[o..])),
                Effect::LateralCompliance(j, n) => {
                    for (c, t) in joints[j.index()].lateral.iter_mut().zip(&theta[o..o + n as usize]) {
                        *c += t;
                    }
                }
                Effect::Straightness(j) => {
                    for (c, t) in joints[j.index()].straightness.iter_mut().zip(&theta[o..o + 5]) {
                        *c += t;
                    }
                }
                Effect::JointScale(j) => joints[j.index()].scale += theta[o],
                Effect::Backlash(j) => joints[j.index()].backlash += theta[o],
                Effect::Periodic(j) => {
                    for (c, t) in joints[j.index()].cyclic_rad.iter_mut().zip(&theta[o..o + 4]) {
                        *c += t;
                    }
                }
                Effect::ThermalDrift(j, shape) => {
                    let tau = theta.get(o + 6).copied().unwrap_or(0.0).clamp(TAU_RANGE_MIN.0, TAU_RANGE_MIN.1);
                    let at_reference = six_at(theta, o);
                    let law = match shape.profile(tau) {
                        Some(profile) => DriftLaw::Time(profile),
                        None => DriftLaw::PerKelvin { sensors: self.sensors_of(j.index(), data, first)? },
                    };
                    let deviation = at_reference.scaled(1.0 / shape.reference_factor(tau));
                    drift.push(DriftRow { row: Row::Joint(j.index()), deviation, law });
                }
                // Per unit of the reading: the law of a per-kelvin row with the sensor's name and a
                // reference of zero (the row moves by `δ · s`); `fk`, `ik` and `compensate` take the
                // reading by name as they take a temperature.
                Effect::SensorDrift(j, sensor) => drift.push(DriftRow {
                    row: Row::Joint(j.index()),
                    deviation: six_at(theta, o),
                    law: DriftLaw::PerKelvin { sensors: vec![(sensor.name().to_string(), 0.0)] },
                }),
                // A measured tilt: one row per component of each sensor's tilt it reads.
                Effect::Tilt(j, sensor, over) => drift.extend(tilt_rows(data, j, sensor, over, &theta[o..o + e.len()])),
                _ => {}
            }
        }
        let base = robot.with_chain(chain)?;
        Ok(RobotModel::new(base)
            .with_gravity(down)
            .with_joint_corrections(joints)?
            .with_gravity_loads(loads)?
            .with_lateral_loads(lateral_loads)?
            .with_branch_loads(branch_loads)?
            .with_drift(drift)?)
    }

    /// The sensors a temperature drift of joint `j` follows (its own, or all), named as in files
    /// (`temp_j2`), each with its reading at the earliest measurement.
    fn sensors_of(
        &self,
        j: usize,
        data: &Dataset,
        first: Option<&Measurement>,
    ) -> Result<Vec<(String, f64)>, IdentifyError> {
        let dof = data.measurements.first().map_or(0, |m| m.q.len());
        let reading = |c: usize| first.and_then(|m| m.temps.get(c).copied());
        let own = data.temperature_names.iter().position(|n| sensor_joint(n, dof) == Some(j));
        let columns: Vec<usize> = match own {
            Some(c) => vec![c],
            None => (0..data.temperature_names.len()).collect(),
        };
        columns
            .into_iter()
            .map(|c| {
                let name = format!("temp_{}", data.temperature_names[c]);
                reading(c)
                    .map(|t| (name.clone(), t))
                    .ok_or(IdentifyError::NoTemperatures { effect: format!("thermal_drift[{}] (temperature)", j + 1) })
            })
            .collect()
    }

    /// The chain with the static effects at `theta` (registered), and its joint rows' errors: the part
    /// of a prediction that is the same for every measurement.
    pub(crate) fn static_chain(
        &self,
        robot: &Robot,
        theta: &[f64],
    ) -> Result<(Chain, Vec<ErrorParams>), IdentifyError> {
        let chain = robot.chain();
        let mut base_err = chain.base().error;
        let mut tool_err = chain.tool().error;
        let mut joint_err: Vec<ErrorParams> = chain.joints().iter().map(|j| j.error).collect();
        let mut zeros: Vec<f64> = chain.joints().iter().map(|j| j.zero).collect();
        let six = |o: usize| six_at(theta, o);
        for (e, &o) in self.effects.iter().zip(&self.offsets) {
            match *e {
                Effect::Registration | Effect::BaseFrame => base_err = base_err.add(&six(o)),
                Effect::ToolPoint => tool_err.translation += Vector3::new(theta[o], theta[o + 1], theta[o + 2]),
                Effect::ToolRotation => tool_err.rotation += Vector3::new(theta[o], theta[o + 1], theta[o + 2]),
                Effect::ToolFrame => tool_err = tool_err.add(&six(o)),
                Effect::JointOffset(j) => zeros[j.index()] += theta[o],
                Effect::LinkDeviation(j) => joint_err[j.index()] = joint_err[j.index()].add(&six(o)),
                Effect::JointCompliance(_)
                | Effect::LumpedCompliance(..)
                | Effect::LateralCompliance(..)
                | Effect::LumpedLateralCompliance(..)
                | Effect::Straightness(_)
                | Effect::ComplianceCoupling(_)
                | Effect::CompliancePair(_)
                | Effect::JointScale(_)
                | Effect::Periodic(_)
                | Effect::Backlash(_)
                | Effect::ThermalDrift(..)
                | Effect::SensorDrift(..)
                | Effect::Tilt(..)
                | Effect::BranchLoad(..)
                | Effect::FrameStep(_) => {}
            }
        }
        let built = self.registered(chain.with_errors_and_zeros(base_err, &joint_err, tool_err, &zeros)?)?;
        Ok((built, joint_err))
    }

    /// Gravity's direction in the world frame of `chain` (a static chain of this model): −Z of the robot's
    /// base as given, turned with the base row where a registration or base frame turned it — gravity
    /// keeps its direction in the robot's base.
    pub(crate) fn gravity_down(&self, chain: &Chain, robot: &Robot) -> nalgebra::Unit<Vector3<f64>> {
        let world_from_base_fitted = chain.base().pose().rotation;
        let world_from_base_given = robot.chain().base().pose().rotation;
        world_from_base_fitted * world_from_base_given.inverse() * -Vector3::z_axis()
    }

    /// `chain` with the registration's starting pose in its base row's nominal pose and the tool point's
    /// start in its tool row's nominal translation (their parameters are small corrections on top, in the
    /// rows' errors).
    fn registered(&self, chain: Chain) -> Result<Chain, IdentifyError> {
        let chain = if self.tool_start_mm == Vector3::zeros() {
            chain
        } else {
            let mut tool = chain.tool().clone();
            tool.translation += self.tool_start_mm;
            chain.with_tool(tool)?
        };
        if self.registration == Isometry3::identity() {
            return Ok(chain);
        }
        let mut row = chain.base().clone();
        let nominal = self.registration * row.nominal();
        row.translation = nominal.translation.vector;
        row.rotation = nominal.rotation;
        Ok(chain.with_base(row)?)
    }

    /// The rows of the chain's parameter Jacobian this model's columns are read from in [`Model::predict`]:
    /// the base row for a registration or base frame, the tool row for the tool, a joint's error row for
    /// its link deviation or drift, its zero column for the joint-level effects.
    pub(crate) fn parameter_rows(&self, dof: usize) -> ParameterRows {
        let mut rows = ParameterRows::none(dof);
        for e in &self.effects {
            match *e {
                Effect::Registration | Effect::BaseFrame => rows.base = true,
                Effect::ToolPoint | Effect::ToolRotation | Effect::ToolFrame => rows.tool = true,
                Effect::LinkDeviation(j)
                | Effect::ThermalDrift(j, _)
                | Effect::SensorDrift(j, _)
                | Effect::Tilt(j, ..)
                | Effect::BranchLoad(j, _, crate::BranchAt { lateral: true, .. })
                | Effect::LateralCompliance(j, _)
                | Effect::LumpedLateralCompliance(j, ..)
                | Effect::Straightness(j) => rows.joints[j.index()] = true,
                Effect::JointOffset(j)
                | Effect::JointCompliance(j)
                | Effect::LumpedCompliance(j, _)
                | Effect::BranchLoad(j, ..)
                | Effect::JointScale(j)
                | Effect::Periodic(j)
                | Effect::Backlash(j) => rows.zeros[j.index()] = true,
                Effect::ComplianceCoupling(j) | Effect::CompliancePair(j) => {
                    rows.zeros[j.index()] = true;
                    rows.zeros[j.index() + 1] = true;
                }
                Effect::FrameStep(_) => {}
            }
        }
        rows
    }
}

/// A [`Effect::CompliancePair`]'s `w = (a, b)` on joints `j` and `j + 1` as the robot file holds it: its
/// matrix `w wᵀ`, `k_j = a²`, `k_{j+1} = b²` and the coupling `c = a·b`.
fn add_pair(joints: &mut [JointCorrection], j: usize, a: f64, b: f64) {
    joints[j].compliance_rad_per_nm += a * a;
    joints[j + 1].compliance_rad_per_nm += b * b;
    joints[j].coupling_rad_per_nm += a * b;
}

/// Where a model's frame blocks start ([`crate::initial_frames`]): the registration (identity in the base
/// frame) and the tool point's offset from the robot's tool (in the tool row's parent frame, mm).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StartFrames {
    /// `tracker_from_base` at the start.
    pub registration: Isometry3<f64>,
    /// The tool point's start, added to the robot's tool translation (the last joint's frame), mm.
    pub tool_point_mm: Vector3<f64>,
}

/// A branch's load on joint `j` as the robot model carries it ([`Effect::BranchLoad`], its weights from
/// `theta[0]`): the branch by its name, which the robot model checks.
fn branch_load(
    robot: &Robot,
    j: crate::JointIndex,
    at: crate::BranchAt,
    theta: &[f64],
) -> thermokin_deform::BranchLoad {
    thermokin_deform::BranchLoad {
        joint: j.index(),
        branch: robot.branches().get(at.branch as usize).map(|b| b.name.clone()).unwrap_or_default(),
        weights: theta[..at.count as usize].to_vec(),
        lateral: at.lateral,
    }
}

/// The drift rows of a measured tilt ([`Effect::Tilt`], parameters `p`): one per component of its
/// sensor's tilt, each turning the row the way that component does once turned by the mounting yaw, about
/// the pivot — the reading taken by the sensor's name as `diagnose` declared it, its reference the
/// training session's; over a sensor below it, that sensor's tilt (already turning everything above it)
/// taken back the same way at the yaw this effect fitted for it.
fn tilt_rows(
    data: &Dataset,
    j: crate::JointIndex,
    sensor: crate::SensorId,
    over: crate::TiltOver,
    p: &[f64],
) -> Vec<DriftRow> {
    let Some(t) = data.tilt_sensors.iter().find(|t| t.column == sensor.index()) else { return Vec::new() };
    let pivot = Vector3::new(p[1], p[2], p[3]);
    let mut sources = vec![(t.name.clone(), t.reference, p[0], 1.0)];
    if over == crate::TiltOver::Below
        && let Some(b) = t.below.as_ref().and_then(|b| data.tilt_sensors.iter().find(|s| s.name == *b))
    {
        sources.push((b.name.clone(), b.reference, p[4], -1.0));
    }
    let mut rows = Vec::new();
    for (name, reference, psi, sign) in sources {
        for component in 0..3 {
            let mut unit = [0.0; 3];
            unit[component] = 1.0;
            let turn = crate::effect::tilt_turn(&unit, 0, psi).0 * sign;
            rows.push(DriftRow {
                row: Row::Joint(j.index()),
                deviation: ErrorParams { translation: pivot.cross(&turn), rotation: turn },
                law: DriftLaw::Tilt { sensor: name.clone(), component, reference },
            });
        }
    }
    rows
}
