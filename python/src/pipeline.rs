//! The pipeline from a notebook: measurement sets, `simulate`, `diagnose` (its report, the calibrated
//! robot) and `compensate`, each a call of the library the command line calls, with the same defaults
//! (`Config::default`, `SimulationConfig::default`) and the same refusals.

use std::collections::HashMap;
use std::path::PathBuf;

use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
use numpy::{AllowTypeChange, PyArrayDyn, PyArrayLikeDyn};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use thermokin_chain::{Dataset, JointKind, Measurement, OperatingState, Target};
use thermokin_compensate::{Plan, PlanError, Request, RunOutput, RunSettings, SummaryOut};
use thermokin_diagnose::{Config, HiddenEffect, Report, SimulationConfig};
use thermokin_io::units::{joints_to_internal, xyz_euler_deg, xyz_rotation_deg};

use crate::arrays::{Rows, output};
use crate::convert::{choice, profile_of, semantics_of, state};
use crate::errors::{Kind, input, io, must_exist, raise};
use crate::robot::PyRobot;

/// A measurement set: joint values, measured tool positions (and orientations), times and sensor
/// readings, in the robot's joint order.
#[pyclass(module = "thermokin", name = "Measurements", frozen)]
#[derive(Clone)]
pub struct PyMeasurements {
    pub data: Dataset,
    pub kinds: Vec<JointKind>,
    /// Where it came from (a file's path, or what made it), named in a calibrated robot's name.
    pub source: String,
}

fn kinds(robot: &PyRobot) -> Vec<JointKind> {
    robot.chain().joints().iter().map(|j| j.kind).collect()
}

/// The units keyword arguments of a measurement set.
fn units(joint_units: Option<&str>, position_units: Option<&str>) -> PyResult<thermokin_io::MeasurementFormat> {
    let parse_joint = |n: &str| n.parse().map_err(|e| input(format!("joint_units: {e}")));
    let parse_position = |n: &str| n.parse().map_err(|e| input(format!("position_units: {e}")));
    Ok(thermokin_io::MeasurementFormat {
        joint_units: joint_units.map(parse_joint).transpose()?,
        position_units: position_units.map(parse_position).transpose()?,
        ..thermokin_io::MeasurementFormat::default()
    })
}

/// A unit the numbers contradict, in the words of the keyword arguments.
fn units_error(e: thermokin_io::IoError) -> PyErr {
    let thermokin_io::IoError::UnitsUnclear { unclear, .. } = &e else { return io(e) };
    let say = match unclear {
        thermokin_io::UnitsUnclear::JointsLookLikeRadians { .. } => {
            "give joint_units=\"rad\" (or joint_units=\"deg\" to read them as degrees)"
        }
        thermokin_io::UnitsUnclear::PositionsLookLikeMetres { .. } => {
            "give position_units=\"m\" (or position_units=\"mm\" to read them as millimetres)"
        }
    };
    input(format!("{e}: {say}"))
}

#[pymethods]
impl PyMeasurements {
    /// Measurements from arrays: `q` `(N, n)` joint values in degrees (mm for prismatic joints), `xyz`
    /// `(N, 3)` measured tool positions in mm, `time_min` `(N,)` minutes since the cold start, `temps`
    /// a dict of `(N,)` readings in °C by sensor name (`temp_j2` or `j2`).
    #[new]
    #[pyo3(signature = (robot, q, xyz, *, time_min=None, temps=None, joint_units=None, position_units=None))]
    fn new(
        robot: &PyRobot,
        q: PyArrayLikeDyn<'_, f64, AllowTypeChange>,
        xyz: PyArrayLikeDyn<'_, f64, AllowTypeChange>,
        time_min: Option<PyArrayLikeDyn<'_, f64, AllowTypeChange>>,
        temps: Option<HashMap<String, PyArrayLikeDyn<'_, f64, AllowTypeChange>>>,
        joint_units: Option<&str>,
        position_units: Option<&str>,
    ) -> PyResult<Self> {
        let format = units(joint_units, position_units)?;
        let radians = format.joint_units == Some(thermokin_io::JointUnits::Radians);
        let chain = robot.chain();
        let q = Rows::read(&q, chain.dof(), "q")?;
        let xyz = Rows::read(&xyz, 3, "xyz")?;
        let n = q.count();
        if xyz.count() != n {
            return Err(input(format!("xyz: {} rows for {n} rows of q", xyz.count())));
        }
        let column = |v: PyArrayLikeDyn<'_, f64, AllowTypeChange>, what: &str| -> PyResult<Vec<f64>> {
            let view = v.as_array();
            if view.len() != n || view.ndim() != 1 {
                return Err(input(format!("{what}: expected ({n},), got {:?}", view.shape())));
            }
            let values: Vec<f64> = view.iter().copied().collect();
            if let Some(i) = values.iter().position(|v| !v.is_finite()) {
                return Err(input(format!("{what}: row {i} is not finite")));
            }
            Ok(values)
        };
        let times = time_min.map(|t| column(t, "time_min")).transpose()?.unwrap_or_else(|| vec![0.0; n]);
        let mut names = Vec::new();
        let mut readings: Vec<Vec<f64>> = Vec::new();
        let mut temps: Vec<_> = temps.unwrap_or_default().into_iter().collect();
        temps.sort_by(|a, b| a.0.cmp(&b.0));
        for (name, values) in temps {
            let name = thermokin_io::sensor_name(&name);
            readings.push(column(values, &format!("temps[{name}]"))?);
            names.push(name);
        }
        let measurements = (0..n)
            .map(|i| {
                let row = &q.data[i * chain.dof()..(i + 1) * chain.dof()];
                let q = if radians {
                    row.to_vec()
                } else {
                    joints_to_internal(chain, row).ok_or_else(|| input("q: wrong row length"))?
                };
                Ok(Measurement {
                    time_min: times[i],
                    q,
                    position_mm: Vector3::new(xyz.data[3 * i], xyz.data[3 * i + 1], xyz.data[3 * i + 2]),
                    orientation: None,
                    position_std_mm: None,
                    temps: readings.iter().map(|r| r[i]).collect(),
                })
            })
            .collect::<PyResult<Vec<_>>>()?;
        let kinds = kinds(robot);
        let data = Dataset { measurements, temperature_names: names, source_lines: Vec::new(), ..Default::default() };
        let data =
            thermokin_io::settle_units(std::path::Path::new("arrays"), data, &kinds, format).map_err(units_error)?;
        Ok(Self { data, kinds, source: "arrays".to_string() })
    }

    /// Reads a measurements CSV (`time_min` optional, `q1..qn`, `x,y,z` mm, optional `rx,ry,rz`,
    /// `temp_*`; the authors' results files too) for `robot`'s joints; `joint_units` `"deg"` or `"rad"`,
    /// `position_units` `"mm"` or `"m"` (unstated: degrees and millimetres, refused when the numbers look
    /// like radians or metres).
    #[staticmethod]
    #[pyo3(signature = (path, robot, *, joint_units=None, position_units=None))]
    fn from_csv(
        path: PathBuf,
        robot: &PyRobot,
        joint_units: Option<&str>,
        position_units: Option<&str>,
    ) -> PyResult<Self> {
        must_exist(&path)?;
        let kinds = kinds(robot);
        let format = units(joint_units, position_units)?;
        let data = thermokin_io::read_measurements_with(&path, &kinds, format).map_err(units_error)?;
        Ok(Self { data, kinds, source: path.display().to_string() })
    }

    /// Writes the set as a measurements CSV (degrees, mm), atomically.
    fn to_csv(&self, path: PathBuf) -> PyResult<()> {
        thermokin_io::write_atomic_with(&path, |w| thermokin_io::write_measurements(w, &self.data, &self.kinds))
            .map_err(io)
    }

    fn __len__(&self) -> usize {
        self.data.len()
    }

    /// `(N, n)` joint values, degrees (mm for prismatic joints).
    #[getter]
    fn q<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
        let n = self.kinds.len();
        let data = self
            .data
            .measurements
            .iter()
            .flat_map(|m| m.q.iter().zip(&self.kinds).map(|(&v, &k)| thermokin_io::units::joint_value_out(k, v)))
            .collect();
        output(py, data, Some(self.data.len()), &[n])
    }

    /// `(N, 3)` measured tool positions, mm.
    #[getter]
    fn xyz<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
        let data =
            self.data.measurements.iter().flat_map(|m| [m.position_mm.x, m.position_mm.y, m.position_mm.z]).collect();
        output(py, data, Some(self.data.len()), &[3])
    }

    /// `(N,)` minutes since the cold start.
    #[getter]
    fn time_min<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
        output(py, self.data.measurements.iter().map(|m| m.time_min).collect(), None, &[self.data.len()])
    }

    /// Sensor names of the temperature columns.
    #[getter]
    fn temperature_names(&self) -> Vec<String> {
        self.data.temperature_names.clone()
    }

    fn __repr__(&self) -> String {
        format!("Measurements({} poses from {})", self.data.len(), self.source)
    }
}

/// Measurements generated on `robot` with hidden `effects` (`KIND[:JOINT][=VALUES]`, as `thermokin
/// simulate --effect`; a typical size drawn when no values are given), `poses` random poses over
/// `minutes`, Gaussian noise of `noise_mm` per axis; seeded, the same set as the command line.
#[pyfunction]
#[pyo3(signature = (robot, effects=None, *, poses=None, minutes=None, noise_mm=None, orientation_noise_deg=None, seed=None))]
pub fn simulate(
    py: Python<'_>,
    robot: &PyRobot,
    effects: Option<Vec<String>>,
    poses: Option<usize>,
    minutes: Option<f64>,
    noise_mm: Option<f64>,
    orientation_noise_deg: Option<f64>,
    seed: Option<u64>,
) -> PyResult<PyMeasurements> {
    robot.model.require_plain().map_err(|e| input(format!("robot: {e}: simulate hides effects on a plain robot")))?;
    let effects = effects.unwrap_or_default();
    let defaults = SimulationConfig::default();
    let config = SimulationConfig {
        poses: poses.unwrap_or(defaults.poses),
        minutes: minutes.unwrap_or(defaults.minutes),
        noise_mm: noise_mm.unwrap_or(defaults.noise_mm),
        seed: seed.unwrap_or(defaults.seed),
        orientation_noise_rad: orientation_noise_deg.map(thermokin_chain::units::radians),
        ..defaults
    };
    config.validate().map_err(setting_error)?;
    let plain = robot.model.robot();
    let mut rng = config.effect_rng();
    let hidden = effects
        .iter()
        .map(|s| HiddenEffect::parse(s, plain, &mut rng).map_err(|e| input(format!("effects: {e}"))))
        .collect::<PyResult<Vec<_>>>()?;
    let data = py.detach(|| thermokin_diagnose::simulate(plain, &hidden, &config)).map_err(setting_error)?;
    Ok(PyMeasurements { data, kinds: kinds(robot), source: format!("simulate({})", effects.join(", ")) })
}

/// A library setting's error named by the keyword argument that set it.
fn setting_error(e: thermokin_diagnose::DiagnoseError) -> PyErr {
    match e {
        thermokin_diagnose::DiagnoseError::BadSetting { setting, rule, value } => {
            let name = match setting {
                "orientation_noise_rad" => "orientation_noise_deg",
                other => other,
            };
            input(format!("{name} {rule} (got {value})"))
        }
        other => input(other),
    }
}

/// What `diagnose` found: the effects, the held-out tables, the verdict, the warnings, and the
/// calibrated robot (the model the report scores).
#[pyclass(module = "thermokin", name = "Report", frozen)]
pub struct PyReport {
    report: Report,
    /// The robot as its file describes it (the export's starting point).
    file_robot: thermokin_chain::Robot,
    source: String,
}

#[pymethods]
impl PyReport {
    /// The report as `thermokin diagnose` prints it.
    #[getter]
    fn text(&self) -> String {
        self.report.text().to_string()
    }

    /// The report as JSON text: what `thermokin diagnose --json` writes.
    fn to_json(&self) -> PyResult<String> {
        serde_json::to_string_pretty(&self.report).map_err(|e| raise(Kind::Other, e))
    }

    /// The report as a dict (the JSON of `thermokin diagnose --json`, parsed).
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let text = serde_json::to_string(&self.report).map_err(|e| raise(Kind::Other, e))?;
        py.import("json")?.call_method1("loads", (text,))
    }

    /// The report as one self-contained HTML page, the page `thermokin diagnose --html` writes (opens
    /// offline; in a notebook, `IPython.display.HTML(report.html())`).
    fn html(&self) -> String {
        let context = thermokin_report::PageContext::new(self.file_robot.name(), self.source.clone());
        thermokin_report::diagnosis_page(&self.report, &context)
    }

    /// The effects chosen, main cause first (labels such as `joint_offset[2]`).
    #[getter]
    fn effects(&self) -> Vec<String> {
        self.report.effects.iter().map(|e| e.label.clone()).collect()
    }

    /// The joint rows and compliances the completion added beside the effects for use (not causes found; in the
    /// scores and the export).
    #[getter]
    fn completed(&self) -> Vec<String> {
        self.report.completed.iter().map(|e| e.label.clone()).collect()
    }

    /// The strength of the prior toward the nominal robot the model is fitted with, in rows of data per
    /// parameter (0.0: none — cross-validation preferred none, or the gate did not take it).
    #[getter]
    fn shrinkage(&self) -> f64 {
        self.report.shrinkage
    }

    /// Whether the effects found explain the data.
    #[getter]
    fn verdict(&self) -> String {
        self.report.verdict.clone()
    }

    /// What the data look like they got wrong (units, frame).
    #[getter]
    fn warnings(&self) -> Vec<String> {
        self.report.warnings.clone()
    }

    /// Said first when the chosen model does not beat the nominal one on data it never saw; `export`
    /// then refuses unless forced.
    #[getter]
    fn honest_end(&self) -> Option<String> {
        self.report.honest_end.clone()
    }

    /// The identified robot with every chosen effect: the model the report scores, as `thermokin
    /// diagnose --export` writes it.
    #[getter]
    fn calibrated(&self) -> PyResult<PyRobot> {
        let model = self.report.export_model(&self.file_robot, None, &self.source).map_err(input)?;
        Ok(PyRobot { model })
    }

    /// Writes the calibrated robot (URDF for `.urdf`, the complete TOML otherwise); refuses, as the
    /// command line does, when the diagnosis did not beat the nominal model held out, unless `force`.
    #[pyo3(signature = (path, *, force=false))]
    fn export(&self, path: PathBuf, force: bool) -> PyResult<()> {
        if let Err(e) = self.report.check_export(force) {
            return Err(raise(
                Kind::Refused,
                format!("not writing {}: {e} (force=True writes it anyway)", path.display()),
            ));
        }
        self.calibrated()?.save_to(&path)
    }

    /// `{"before": (N,), "after": (N,)}`: |position residual| per measurement of the nominal model and
    /// of the model found (both fitted on all measurements), mm.
    fn residuals<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        let before = &self.report.residuals_before.per_measurement_mm;
        let after = &self.report.residuals_after.per_measurement_mm;
        d.set_item("before", output(py, before.clone(), None, &[before.len()])?)?;
        d.set_item("after", output(py, after.clone(), None, &[after.len()])?)?;
        Ok(d)
    }

    /// The held-out table as effects are added (one row per model, the cross-validated errors in mm), as
    /// a pandas DataFrame (pandas imported here, only when asked for).
    fn to_dataframe<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let pandas = py.import("pandas")?;
        let rows = PyList::empty(py);
        for r in &self.report.additive {
            let d = PyDict::new(py);
            d.set_item("model", &r.model)?;
            d.set_item("heldout_mean_mm", r.stats.heldout_mean_mm)?;
            d.set_item("heldout_rms_mm", r.stats.heldout_rms_mm)?;
            d.set_item("heldout_median_mm", r.stats.heldout_median_mm)?;
            d.set_item("heldout_p95_mm", r.stats.heldout_p95_mm)?;
            d.set_item("heldout_max_mm", r.stats.heldout_max_mm)?;
            d.set_item("heldout_count", r.stats.heldout_count)?;
            rows.append(d)?;
        }
        pandas.call_method1("DataFrame", (rows,))
    }

    fn __repr__(&self) -> String {
        format!("Report(effects={:?})", self.effects())
    }
}

/// The sim-to-real diagnosis (`thermokin diagnose`): which unmodelled effects explain where `robot`
/// and the measurements disagree, chosen by cross-validation and scored by nested validation (and on
/// `holdout`, never seen by the selection). The measurements: a `Measurements`, or arrays — `data` the
/// joint values `(N, n)` in degrees with `xyz` `(N, 3)` in mm, `time_min` `(N,)` and `temps` (°C by
/// sensor) as for `Measurements`. Settings as the command line's flags: `noise_mm` (the tracker's σ per
/// axis), `folds`, `folds_by` (`"neighbourhood"`, `"time"`, `"region"`, `"configuration"`), `frame`
/// (`"base"` or `"tracker"`: estimate the measurement frame), `tool` (`"known"` or `"unknown"`:
/// estimate the tool point), `orientation_lever_mm`, `orientation_noise_deg`, `outliers` (`"exclude"`:
/// gross errors listed and left out, or `"keep"`), `shrinkage` (`"cross-validated"` or `"off"`),
/// `extrapolation` (`"half-arcs"`: a chosen angle- or load-dependent effect must hold beyond the poses it
/// was fitted on, or `"off"`), `masses` (`"from-file"`, or `"ignore"`: every gravity compliance's loads lumped
/// and identified from the data), `order` (`"time"`, or `"file"`: the rows are in the order measured —
/// what a backlash follows), `lateral` (`"slides"`, or `"joints"`: every joint's bearing may tilt under the
/// gravity moment across its axis, its loads lumped without masses), `accelerometers` (`{"acc_top": 1}`:
/// each sensor's link, 0 the base — its columns `NAME_x`, `NAME_y`, `NAME_z` of a measurements file read
/// as the link's tilt, as `--accelerometer NAME=LINK`), `region` (the poses of use, `(M, n)` degrees, as
/// `--for`: the report's `at_use` predicts the final model's held-out error there from its fit, beside a
/// `holdout` of those poses), `plan` (the `Plan` these poses were measured by, made for the poses of use
/// `region`, as `--plan`: its promise there restated at the residual scale the fit found, beside the
/// prediction and the hold-out's measured error). Runs without the GIL.
#[pyfunction]
#[pyo3(signature = (robot, data, xyz=None, *, time_min=None, temps=None, holdout=None, noise_mm=None, folds=None, folds_by=None, frame=None, tool=None, orientation_lever_mm=None, orientation_noise_deg=None, outliers=None, shrinkage=None, extrapolation=None, masses=None, order=None, lateral=None, accelerometers=None, region=None, plan=None))]
#[allow(clippy::too_many_arguments)] // Python's keyword arguments, one per setting.
pub fn diagnose(
    py: Python<'_>,
    robot: &PyRobot,
    data: &Bound<'_, PyAny>,
    xyz: Option<PyArrayLikeDyn<'_, f64, AllowTypeChange>>,
    time_min: Option<PyArrayLikeDyn<'_, f64, AllowTypeChange>>,
    temps: Option<HashMap<String, PyArrayLikeDyn<'_, f64, AllowTypeChange>>>,
    holdout: Option<&PyMeasurements>,
    noise_mm: Option<f64>,
    folds: Option<usize>,
    folds_by: Option<&str>,
    frame: Option<&str>,
    tool: Option<&str>,
    orientation_lever_mm: Option<f64>,
    orientation_noise_deg: Option<f64>,
    outliers: Option<&str>,
    shrinkage: Option<&str>,
    extrapolation: Option<&str>,
    masses: Option<&str>,
    order: Option<&str>,
    lateral: Option<&str>,
    accelerometers: Option<HashMap<String, usize>>,
    region: Option<PyArrayLikeDyn<'_, f64, AllowTypeChange>>,
    plan: Option<&crate::planning::PyPlan>,
) -> PyResult<PyReport> {
    let measurements: PyMeasurements = match (data.cast::<PyMeasurements>(), xyz) {
        (Ok(m), None) => {
            if time_min.is_some() || temps.is_some() {
                return Err(input("time_min, temps: given with the arrays (a Measurements carries its own)"));
            }
            m.get().clone()
        }
        (Ok(_), Some(_)) => {
            return Err(input("xyz: a Measurements carries its positions; give q and xyz, or a Measurements"));
        }
        (Err(_), Some(xyz)) => PyMeasurements::new(robot, data.extract()?, xyz, time_min, temps, None, None)?,
        (Err(_), None) => {
            return Err(input(
                "xyz: the measured positions (N, 3) in mm go with joint values (or give a Measurements)",
            ));
        }
    };
    let measurements = &measurements;
    let defaults = Config::default();
    let config = Config {
        folds_by: choice("folds_by", folds_by, defaults.folds_by)?,
        noise_mm,
        orientation_lever_mm: orientation_lever_mm.unwrap_or(defaults.orientation_lever_mm),
        orientation_noise_rad: orientation_noise_deg.map(thermokin_chain::units::radians),
        folds: folds.unwrap_or(defaults.folds),
        frame: choice("frame", frame, defaults.frame)?,
        tool: choice("tool", tool, defaults.tool)?,
        outliers: choice("outliers", outliers, defaults.outliers)?,
        shrinkage: choice("shrinkage", shrinkage, defaults.shrinkage)?,
        extrapolation: choice("extrapolation", extrapolation, defaults.extrapolation)?,
        masses: choice("masses", masses, defaults.masses)?,
        order: choice("order", order, defaults.order)?,
        lateral: choice("lateral", lateral, defaults.lateral)?,
        accelerometers: {
            let mut a: Vec<thermokin_diagnose::Accelerometer> = accelerometers
                .unwrap_or_default()
                .into_iter()
                .map(|(name, link)| thermokin_diagnose::Accelerometer { name, link })
                .collect();
            a.sort_by(|x, y| x.name.cmp(&y.name));
            a
        },
        poses_of_use: region
            .map(|r| crate::planning::configurations(robot, &r, "region"))
            .transpose()?
            .unwrap_or_default(),
        promised: plan.map(|p| thermokin_diagnose::Promised {
            rms_mm: p.plan.promise.planned_rms_mm,
            noise_mm: p.plan.promise.noise_mm,
            poses: p.plan.promise.poses_of_use,
            at_nearest: p.plan.promise.planned_at_nearest,
        }),
        ..defaults
    };
    config.validate().map_err(setting_error)?;
    robot.model.require_plain().map_err(|e| {
        input(format!("robot: {e}: diagnose the robot they were identified on, or the calibrated geometry alone"))
    })?;
    let file_robot = robot.model.robot().clone();
    let (data, held) = (&measurements.data, holdout.map(|h| &h.data));
    let report = py.detach(|| thermokin_diagnose::diagnose(&file_robot, data, held, &config)).map_err(input)?;
    Ok(PyReport { report, file_robot, source: measurements.source.clone() })
}

/// The results of `compensate`: per target (and time), the joints to command and how the robot reaches
/// the target with them.
#[pyclass(module = "thermokin", name = "Compensation", frozen)]
pub struct PyCompensation {
    run: RunOutput,
    dof: usize,
}

#[pymethods]
impl PyCompensation {
    /// Target labels, one per row.
    #[getter]
    fn labels(&self) -> Vec<String> {
        self.run.rows.iter().map(|r| r.label.clone()).collect()
    }

    /// `(R,)` minutes of each row (0 for a static run).
    #[getter]
    fn time_min<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
        output(py, self.run.rows.iter().map(|r| r.time_min).collect(), None, &[self.run.rows.len()])
    }

    /// `(R, n)` compensated joints to command, degrees (mm for prismatic joints).
    #[getter]
    fn joints<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
        let data = self
            .run
            .rows
            .iter()
            .flat_map(|r| {
                r.joints.iter().zip(&self.run.kinds).map(|(&v, &k)| thermokin_io::units::joint_value_out(k, v))
            })
            .collect();
        output(py, data, Some(self.run.rows.len()), &[self.dof])
    }

    /// Per row: `"Converged"` (verified by FK of the deformed robot), or why not.
    #[getter]
    fn status(&self) -> Vec<String> {
        self.run.rows.iter().map(|r| format!("{:?}", r.status)).collect()
    }

    /// `(R,)` |programmed − reached| with the compensated joints, mm.
    #[getter]
    fn position_error_mm<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
        let data = self.run.rows.iter().map(|r| Vector3::from(r.position_deviation_mm).norm()).collect();
        output(py, data, None, &[self.run.rows.len()])
    }

    /// `(R,)` orientation error angle with the compensated joints, degrees.
    #[getter]
    fn orientation_error_deg<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
        let data = self
            .run
            .rows
            .iter()
            .map(|r| thermokin_chain::units::degrees(Vector3::from(r.orientation_deviation_rad).norm()))
            .collect();
        output(py, data, None, &[self.run.rows.len()])
    }

    /// `(R,)` position error of the uncompensated program on the deformed robot, mm.
    #[getter]
    fn uncompensated_error_mm<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
        output(py, self.run.rows.iter().map(|r| r.uncompensated_error_mm).collect(), None, &[self.run.rows.len()])
    }

    /// The run's summary (mm, degrees), as `thermokin compensate --json` prints it.
    fn summary<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let text = serde_json::to_string(&SummaryOut::of(&self.run.summary)).map_err(|e| raise(Kind::Other, e))?;
        py.import("json")?.call_method1("loads", (text,))
    }

    /// Writes the results as `thermokin compensate --format` does: `"authors"` (the authors' results
    /// CSV), `"long"`, `"json"` or `"joints"`; atomically.
    #[pyo3(signature = (path, *, format=None))]
    fn write(&self, path: PathBuf, format: Option<&str>) -> PyResult<()> {
        let format = choice("format", format, thermokin_compensate::ResultsFormat::default())?;
        thermokin_io::write_atomic_with(&path, |w| format.write(w, &self.run, self.run.timed)).map_err(io)
    }

    /// One row per target and time: label, time, joints, status and errors, as a pandas DataFrame
    /// (pandas imported here, only when asked for).
    fn to_dataframe<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let pandas = py.import("pandas")?;
        let d = PyDict::new(py);
        d.set_item("label", self.labels())?;
        d.set_item("time_min", self.time_min(py)?)?;
        let joints = self.joints(py)?;
        for k in 0..self.dof {
            d.set_item(
                format!("q{}_deg", k + 1),
                joints.call_method1("__getitem__", ((pyo3::types::PySlice::full(py), k),))?,
            )?;
        }
        d.set_item("status", self.status())?;
        d.set_item("position_error_mm", self.position_error_mm(py)?)?;
        d.set_item("orientation_error_deg", self.orientation_error_deg(py)?)?;
        d.set_item("uncompensated_error_mm", self.uncompensated_error_mm(py)?)?;
        pandas.call_method1("DataFrame", (d,))
    }

    fn __len__(&self) -> usize {
        self.run.rows.len()
    }
}

/// Targets from a CSV file (`,X,Y,Z[,RX,RY,RZ][,time_min][,temp_*]`, and a column named as one of
/// `model`'s sensors its reading: an accelerometer's `NAME_x`) or an `(N, 6)` array of x, y, z (mm) and
/// the paper's X-Y-Z Euler angles (degrees).
fn targets_of(value: &Bound<'_, PyAny>, model: &thermokin_deform::RobotModel) -> PyResult<Vec<Target>> {
    if let Ok(path) = value.extract::<PathBuf>() {
        must_exist(&path)?;
        let (_, sensors) = model.needs();
        let read = thermokin_io::read_target_rows_for(&path, &sensors).map_err(io)?;
        return read.rows.into_iter().collect::<Result<_, _>>().map_err(io);
    }
    let array: PyArrayLikeDyn<'_, f64, AllowTypeChange> = value.extract()?;
    let rows = Rows::read(&array, 6, "targets")?;
    Ok(rows
        .data
        .chunks(6)
        .enumerate()
        .map(|(i, v)| Target {
            label: format!("P{}", i + 1),
            pose: Isometry3::from_parts(Translation3::new(v[0], v[1], v[2]), xyz_rotation_deg([v[3], v[4], v[5]])),
            line: None,
            state: OperatingState::default(),
        })
        .collect())
}

/// Compensation (`thermokin compensate`): the joints that bring the deformed robot onto `targets` (a
/// CSV path, or `(N, 6)` x, y, z mm and X-Y-Z Euler degrees), by IK on the deformed model.
///
/// A plain robot with `deformation` (a deviation table): the static case, or with a growing `profile`
/// the warm-up over `duration_min` (200 by default, the paper's) every `step_min`. A calibrated robot
/// (what `diagnose` exports, its drift and joint corrections), or any robot given a state: every target
/// in its state — `time_min` and `temps` — or, with `duration_min` (or a growing `profile` and no
/// `time_min`), every target at every step of the warm-up. The same decision as the command line's
/// (`thermokin_compensate::Plan`).
/// `seed` in degrees seeds the first solve (zeros by default); the program is chained target to target.
/// `accumulate="increments"` replays the authors' minute-by-minute CoppeliaSim updates of a plain robot's
/// growing table (the command line's `--accumulate increments`).
#[pyfunction]
#[pyo3(signature = (robot, targets, *, deformation=None, semantics=None, profile=None, time_min=None, temps=None, duration_min=None, step_min=None, seed=None, accumulate=None))]
pub fn compensate(
    py: Python<'_>,
    robot: &PyRobot,
    targets: &Bound<'_, PyAny>,
    deformation: Option<PathBuf>,
    semantics: Option<&str>,
    profile: Option<String>,
    time_min: Option<f64>,
    temps: Option<HashMap<String, f64>>,
    duration_min: Option<f64>,
    step_min: Option<f64>,
    seed: Option<PyArrayLikeDyn<'_, f64, AllowTypeChange>>,
    accumulate: Option<&str>,
) -> PyResult<PyCompensation> {
    let accumulation = choice("accumulate", accumulate, thermokin_compensate::Accumulation::default())?;
    let step_min = step_min.unwrap_or(thermokin_compensate::Cycle::PAPER.step_min);
    let chain = robot.chain();
    let dof = chain.dof();
    let program = targets_of(targets, &robot.model)?;
    let table = match &deformation {
        Some(p) => {
            must_exist(p)?;
            Some(thermokin_io::read_deviation_table_for(p, dof).map_err(io)?)
        }
        None => None,
    };
    let profile = profile.as_deref().map(|p| profile_of(p, dof)).transpose()?;
    let start = match seed {
        Some(s) => {
            let rows = Rows::read(&s, dof, "seed")?;
            joints_to_internal(chain, &rows.data).ok_or_else(|| input(format!("seed: {dof} values")))?
        }
        None => vec![0.0; dof],
    };
    let state = state(time_min, temps, None)?;
    let semantics = semantics_of(semantics, dof)?;
    let settings =
        RunSettings { semantics: semantics.clone(), accumulation, ik: thermokin_ik::Params::default(), start };
    // Which run this is, decided by the library as for the command line (`Plan::new`).
    let request = Request {
        model: &robot.model,
        table: table.as_ref(),
        profile: profile.as_ref(),
        state: &state,
        semantics: &semantics,
        accumulation: settings.accumulation,
        duration_min,
        step_min,
    };
    let plan = Plan::new(&request).map_err(plan_error)?;
    let run = py.detach(|| plan.run(&request, &program, &settings, |_, _| {})).map_err(input)?;
    Ok(PyCompensation { run, dof })
}

/// A request the library refuses, in the words of the keyword arguments.
fn plan_error(e: thermokin_compensate::CompensateError) -> PyErr {
    let thermokin_compensate::CompensateError::Plan(plan) = &e else { return input(e) };
    input(match plan {
        PlanError::NothingToCompensate => "nothing to compensate: the robot is as designed (no error parameters, zero offsets or corrections); give deformation=TABLE, or the calibrated robot diagnose returns".to_string(),
        PlanError::SemanticsOnCalibrated => "semantics=\"coppeliasim\" applies to a plain robot's table; a calibrated robot's rows drift canonically".to_string(),
        PlanError::TemperatureLogOnCalibrated => "profile: a temperature-log profile cannot be combined with a calibrated robot: give the targets' temp_* columns instead".to_string(),
        PlanError::IncrementsNeedTransient => "accumulate=\"increments\" needs a transient run: give profile= (e.g. \"linear-grow:180\")".to_string(),
        PlanError::IncrementsOnCalibrated => "accumulate=\"increments\" replays the authors' CoppeliaSim updates on a plain robot's table".to_string(),
        other => other.to_string(),
    })
}

/// A pose as x, y, z (mm) and the paper's X-Y-Z Euler angles (degrees) from a 4×4 matrix — and back:
/// the targets' convention.
#[pyfunction]
pub fn pose_to_xyz_euler<'py>(
    py: Python<'py>,
    pose: PyArrayLikeDyn<'py, f64, AllowTypeChange>,
) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
    let rows = Rows::read_shaped(&pose, &[4, 4], "pose")?;
    let mut out = Vec::with_capacity(rows.count() * 6);
    for (i, m) in rows.data.chunks(16).enumerate() {
        let r = [[m[0], m[1], m[2]], [m[4], m[5], m[6]], [m[8], m[9], m[10]]];
        let q: UnitQuaternion<f64> =
            thermokin_io::units::rotation_from_matrix(r).map_err(|e| input(format!("pose {i}: {e}")))?;
        out.extend([m[3], m[7], m[11]]);
        out.extend(xyz_euler_deg(&q));
    }
    output(py, out, rows.batch, &[6])
}
