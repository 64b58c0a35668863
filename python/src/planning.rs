//! `plan`: which poses to measure, from a notebook — the library call `thermokin plan` makes, with its
//! defaults (`Params::default`) and refusals; joints in degrees (mm for a prismatic joint) in and out.

use numpy::{AllowTypeChange, PyArrayDyn, PyArrayLikeDyn};
use pyo3::prelude::*;
use thermokin_identify::Effect;
use thermokin_io::units::joints_to_internal;
use thermokin_planner::{Candidates, Params, Plan, Poses, Region, WorkspaceBox};

use crate::arrays::{Rows, output};
use crate::convert::choice;
use crate::errors::{Kind, input, raise};
use crate::robot::PyRobot;

/// A measurement plan: the poses in measuring order and what they are predicted to give.
#[pyclass(module = "thermokin", name = "Plan", frozen)]
pub struct PyPlan {
    pub(crate) plan: Plan,
    /// The robot's name and what the candidates were, for the page.
    robot: String,
    candidates: String,
}

#[pymethods]
impl PyPlan {
    /// The plan as `thermokin plan` prints it.
    #[getter]
    fn text(&self) -> String {
        self.plan.text()
    }

    /// The planned joint values, (N, dof), degrees (mm for a prismatic joint), in measuring order.
    #[getter]
    fn joints<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
        let dof = self.plan.poses.first().map_or(0, |p| p.joints.len());
        let data = self.plan.poses.iter().flat_map(|p| p.joints.iter().copied()).collect();
        output(py, data, Some(self.plan.poses.len()), &[dof])
    }

    /// The planned poses' 0-based rows in the candidates, in measuring order.
    #[getter]
    fn indices(&self) -> Vec<usize> {
        self.plan.poses.iter().map(|p| p.candidate).collect()
    }

    /// Where the tracker should see the tool, (N, 3), mm: the nominal robot in its base frame.
    #[getter]
    fn expected_xyz<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
        let data = self.plan.poses.iter().flat_map(|p| p.nominal_position_mm).collect();
        output(py, data, Some(self.plan.poses.len()), &[3])
    }

    /// The criterion after the measured poses and after each planned pose, in measuring order.
    #[getter]
    fn criterion_by_pose(&self) -> Vec<f64> {
        self.plan.criterion_by_pose.clone()
    }

    /// The plan as one self-contained HTML page, the page `thermokin plan --html` writes.
    fn html(&self) -> String {
        thermokin_report::plan_page(
            &self.plan,
            &thermokin_report::PageContext::new(self.robot.clone(), self.candidates.clone()),
        )
    }

    /// The report as a dict (the JSON of `thermokin plan --json`, parsed).
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let text = serde_json::to_string(&self.plan).map_err(|e| raise(Kind::Other, e))?;
        py.import("json")?.call_method1("loads", (text,))
    }

    fn __repr__(&self) -> String {
        format!("<thermokin.Plan: {} poses of {} candidates>", self.plan.poses.len(), self.plan.candidates)
    }
}

/// `poses`: a positive count or `"auto"` (at most every candidate).
fn pose_count(value: Option<&Bound<'_, PyAny>>) -> PyResult<Option<Poses>> {
    let Some(v) = value else { return Ok(None) };
    if let Ok(s) = v.extract::<String>() {
        return match s.trim().to_ascii_lowercase().as_str() {
            "auto" => Ok(Some(Poses::Auto { at_most: usize::MAX })),
            _ => Err(input(format!("poses: `{s}`: a positive number of poses, or \"auto\""))),
        };
    }
    match v.extract::<usize>() {
        Ok(n) if n > 0 => Ok(Some(Poses::Exactly(n))),
        _ => Err(input(format!("poses: {v}: a positive number of poses, or \"auto\""))),
    }
}

/// Configurations (N, dof) in degrees (mm for a prismatic joint), in the library's units.
pub(crate) fn configurations(
    robot: &PyRobot,
    value: &PyArrayLikeDyn<'_, f64, AllowTypeChange>,
    what: &str,
) -> PyResult<Vec<Vec<f64>>> {
    let chain = robot.chain();
    let dof = chain.dof();
    let rows = Rows::read(value, dof, what)?;
    rows.data
        .chunks(dof)
        .map(|row| joints_to_internal(chain, row).ok_or_else(|| input(format!("{what}: {dof} values per row"))))
        .collect()
}

/// Plans `poses` poses out of `candidates` ((N, dof) degrees; `None`: `samples` configurations (default
/// `thermokin_planner::DEFAULT_SAMPLES`, 3000) sampled
/// within the joint limits, kept inside `box` — `(x0, y0, z0, x1, y1, z1)` mm of the base frame — when
/// given), after the `measured` configurations. `effects`: `"KIND[:JOINT]"` strings (default: the
/// catalogue's that some choice of the candidates can make eligible — the others are in
/// `to_dict()["left_out"]`); `region`: the poses of use ((N, dof) degrees: the program the robot will
/// run, `thermokin plan --for`) — the plan then chooses for the predicted error there and states its
/// promise there (`to_dict()["promise"]`); `beyond_arcs` (`"nearest"`, the default: a pose of use beyond
/// the candidates' arcs planned for at its nearest candidate; `"as-given"`, as `--beyond-arcs`); `poses`: a count or `"auto"`; `criterion` (`"parameters"`:
/// D-optimal, `"prediction"`: I-optimal, the default),
/// `frame`, `tool` as `diagnose`; `noise_mm` for the predicted σ. Runs without the GIL.
#[pyfunction]
#[pyo3(signature = (robot, candidates=None, *, poses=None, measured=None, samples=None, r#box=None, effects=None, noise_mm=None, criterion=None, frame=None, tool=None, seed=None, region=None, beyond_arcs=None))]
#[allow(clippy::too_many_arguments)]
pub fn plan(
    py: Python<'_>,
    robot: &PyRobot,
    candidates: Option<PyArrayLikeDyn<'_, f64, AllowTypeChange>>,
    poses: Option<Bound<'_, PyAny>>,
    measured: Option<PyArrayLikeDyn<'_, f64, AllowTypeChange>>,
    samples: Option<usize>,
    r#box: Option<Vec<f64>>,
    effects: Option<Vec<String>>,
    noise_mm: Option<f64>,
    criterion: Option<&str>,
    frame: Option<&str>,
    tool: Option<&str>,
    seed: Option<u64>,
    region: Option<PyArrayLikeDyn<'_, f64, AllowTypeChange>>,
    beyond_arcs: Option<&str>,
) -> PyResult<PyPlan> {
    let samples = samples.unwrap_or(thermokin_planner::DEFAULT_SAMPLES);
    let defaults = Params::default();
    let file_robot = robot.model.robot().clone();
    let effects = effects
        .map(|list| {
            list.iter()
                .map(|s| Effect::parse(&file_robot, s).map_err(|e| input(format!("effects: {s}: {e}"))))
                .collect::<PyResult<Vec<_>>>()
        })
        .transpose()?;
    let region = match region {
        Some(r) => Region::Poses(configurations(robot, &r, "region")?),
        None => Region::Candidates,
    };
    let params = Params {
        poses: pose_count(poses.as_ref())?.unwrap_or(defaults.poses),
        noise_mm: noise_mm.unwrap_or(defaults.noise_mm),
        criterion: choice("criterion", criterion, defaults.criterion)?,
        region,
        beyond_arcs: choice("beyond_arcs", beyond_arcs, defaults.beyond_arcs)?,
        frame: choice("frame", frame, defaults.frame)?,
        tool: choice("tool", tool, defaults.tool)?,
        effects,
        seed: seed.unwrap_or(defaults.seed),
        ..defaults
    };
    let measured = measured.map(|m| configurations(robot, &m, "measured")).transpose()?.unwrap_or_default();
    let described = match &candidates {
        Some(_) => "the candidates given".to_string(),
        None => format!("{samples} sampled configurations"),
    };
    let pool = match candidates {
        Some(c) => Candidates::new(&file_robot, configurations(robot, &c, "candidates")?, vec![]).map_err(input)?,
        None => {
            let workspace = r#box.as_deref().map(WorkspaceBox::from_corners).transpose();
            let workspace = workspace.map_err(|e| input(format!("box: {e}")))?;
            Candidates::sampled(&file_robot, samples, params.seed, workspace.as_ref()).map_err(input)?
        }
    };
    let plan = py.detach(|| thermokin_planner::plan(&file_robot, &pool, &measured, &params)).map_err(input)?;
    Ok(PyPlan { plan, robot: file_robot.name().to_string(), candidates: described })
}
