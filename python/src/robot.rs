//! `thermokin.Robot`: a robot file (TOML or URDF) or a DH table, with FK, the Jacobian and IK, one
//! configuration or a batch; millimetres and degrees at this edge, converted once
//! (`thermokin_io::units`).

use std::collections::HashMap;
use std::path::PathBuf;

use nalgebra::{Isometry3, Translation3, Vector3};
use numpy::{AllowTypeChange, PyArrayDyn, PyArrayLikeDyn};
use pyo3::prelude::*;
use rayon::prelude::*;
use thermokin_chain::{Chain, DhConvention, DhRow, DhTable, OperatingState, Robot};
use thermokin_deform::RobotModel;
use thermokin_ik::{Goal, Params, Solution, Workspace};
use thermokin_io::units::{joints_to_external, joints_to_internal, rotation_from_matrix};

use crate::arrays::{Rows, output};
use crate::convert::{Approaches, profile_of, semantics_of, state_of, states};
use crate::errors::{input, io, must_exist};

/// A robot: its kinematic chain (same-orientation joint frames with their error parameters) and what a
/// calibration added (joint corrections, drifting rows, payload).
#[pyclass(module = "thermokin", name = "Robot", frozen)]
#[derive(Clone)]
pub struct PyRobot {
    pub model: RobotModel,
}

impl PyRobot {
    pub fn chain(&self) -> &Chain {
        self.model.robot().chain()
    }

    /// Writes the robot: URDF when the path ends in `.urdf`, a UR kinematics YAML for `.yaml`/`.yml` (what
    /// either cannot hold named in its header), the complete TOML otherwise; atomically. `save` and a report's `export`.
    pub fn save_to(&self, path: &std::path::Path) -> PyResult<()> {
        let (text, _) = thermokin_io::robot_file_text(&self.model, path).map_err(io)?;
        thermokin_io::write_atomic(path, text.as_bytes()).map_err(io)
    }

    /// A batch of joint rows (degrees; mm for prismatic joints) in the chain's units.
    fn joint_rows(
        &self,
        q: PyArrayLikeDyn<'_, f64, AllowTypeChange>,
        what: &str,
    ) -> PyResult<(Vec<Vec<f64>>, Option<usize>)> {
        let chain = self.chain();
        let rows = Rows::read(&q, chain.dof(), what)?;
        let internal = rows
            .data
            .chunks(chain.dof())
            .map(|r| {
                joints_to_internal(chain, r).ok_or_else(|| input(format!("{what}: {} values per row", chain.dof())))
            })
            .collect::<PyResult<Vec<_>>>()?;
        Ok((internal, rows.batch))
    }
}

/// A 4×4 homogeneous matrix (mm) as a pose; the rotation block must be a rotation.
fn pose_of(m: &[f64], what: &str, index: Option<usize>) -> PyResult<Isometry3<f64>> {
    let at = index.map_or(String::new(), |i| format!(" {i}"));
    let rows = [[m[0], m[1], m[2]], [m[4], m[5], m[6]], [m[8], m[9], m[10]]];
    let rotation = rotation_from_matrix(rows).map_err(|e| input(format!("{what}{at}: {e}")))?;
    if [m[12], m[13], m[14]].iter().any(|v| v.abs() > 1e-9) || (m[15] - 1.0).abs() > 1e-9 {
        return Err(input(format!("{what}{at}: the last row of a homogeneous matrix is 0, 0, 0, 1")));
    }
    Ok(Isometry3::from_parts(Translation3::new(m[3], m[7], m[11]), rotation))
}

/// The result of inverse kinematics: one target, or arrays over a batch.
#[pyclass(module = "thermokin", name = "IKResult", frozen, get_all)]
pub struct IkResult {
    /// Joint values to command, degrees (mm for prismatic joints): `(n,)` or `(N, n)`.
    pub q: Py<PyAny>,
    /// `"Converged"` (verified by FK independently of the solver), `"JointLimit"`, `"Unreachable"`,
    /// `"Singular"`, `"FarFromSeed"` or `"Unverified"`; a list over a batch.
    pub status: Py<PyAny>,
    /// Position error re-measured by FK, mm.
    pub position_error_mm: Py<PyAny>,
    /// Orientation error re-measured by FK, degrees (0 for position targets).
    pub orientation_error_deg: Py<PyAny>,
    /// Solver iterations over all attempts.
    pub iterations: Py<PyAny>,
    /// `True` where the status is `"Converged"`.
    pub converged: Py<PyAny>,
}

#[pymethods]
impl IkResult {
    fn __repr__(&self, py: Python<'_>) -> String {
        format!("IKResult(status={}, position_error_mm={})", self.status.bind(py), self.position_error_mm.bind(py))
    }
}

#[pymethods]
impl PyRobot {
    /// Reads a robot file: TOML (`configs/*.toml`, or what `diagnose --export` writes) or URDF
    /// (`tip=` the link the chain ends at, `base=` where it starts).
    #[staticmethod]
    #[pyo3(signature = (path, *, tip=None, base=None))]
    fn from_file(path: PathBuf, tip: Option<String>, base: Option<String>) -> PyResult<Self> {
        must_exist(&path)?;
        let options = thermokin_io::RobotOptions { base, tip };
        let model = thermokin_io::read_robot_model_with(&path, &options).map_err(io)?;
        Ok(Self { model })
    }

    /// A robot from a DH table: `rows` is `(n, 4)` of `a` (mm), `α` (deg), `d` (mm), `θ` offset (deg),
    /// revolute joints; `convention` is `"classic"` (eq. 9–12) or `"modified"` (Craig, eq. 13); `base`
    /// and `tool` are optional 4×4 matrices (mm).
    #[staticmethod]
    #[pyo3(signature = (rows, *, convention="classic", names=None, base=None, tool=None, name="dh"))]
    fn from_dh(
        rows: PyArrayLikeDyn<'_, f64, AllowTypeChange>,
        convention: &str,
        names: Option<Vec<String>>,
        base: Option<PyArrayLikeDyn<'_, f64, AllowTypeChange>>,
        tool: Option<PyArrayLikeDyn<'_, f64, AllowTypeChange>>,
        name: &str,
    ) -> PyResult<Self> {
        let convention = match convention {
            "classic" | "standard" => DhConvention::Classic,
            "modified" | "craig" => DhConvention::Modified,
            other => return Err(input(format!("convention: `{other}` is not \"classic\" or \"modified\""))),
        };
        let table = Rows::read(&rows, 4, "rows")?;
        let n = table.count();
        let names = names.unwrap_or_else(|| (1..=n).map(|i| format!("joint{i}")).collect());
        if names.len() != n {
            return Err(input(format!("names: {} names for {n} rows", names.len())));
        }
        let r = thermokin_chain::units::radians;
        let dh_rows = table
            .data
            .chunks(4)
            .zip(names)
            .map(|(v, name)| DhRow::revolute(name, v[0], r(v[1]), v[2], r(v[3])))
            .collect();
        let frame = |m: Option<PyArrayLikeDyn<'_, f64, AllowTypeChange>>, what: &str| -> PyResult<Isometry3<f64>> {
            match m {
                Some(m) => {
                    let rows = Rows::read_shaped(&m, &[4, 4], what)?;
                    if rows.batch.is_some() {
                        return Err(input(format!("{what}: one 4×4 matrix")));
                    }
                    pose_of(&rows.data, what, None)
                }
                None => Ok(Isometry3::identity()),
            }
        };
        let dh = DhTable { convention, rows: dh_rows, base: frame(base, "base")?, tool: frame(tool, "tool")? };
        let chain = dh.to_extended().map_err(input)?;
        Ok(Self { model: RobotModel::new(Robot::new(name, chain)) })
    }

    /// The robot's name.
    #[getter]
    fn name(&self) -> String {
        self.model.robot().name().to_string()
    }

    /// Joints of the chain.
    #[getter]
    fn dof(&self) -> usize {
        self.chain().dof()
    }

    /// Joint names, base to tip.
    #[getter]
    fn joint_names(&self) -> Vec<String> {
        self.chain().joints().iter().map(|j| j.name.clone()).collect()
    }

    /// The robot's branches (a URDF tree's chains beside the measured one): `{name: (link, [joint
    /// names])}`, the link of the measured chain each hangs from (0 the base). A measurements column named
    /// as a branch joint is its position (degrees; mm for a slide), what the branch carries loading the
    /// joints below it in `diagnose`.
    #[getter]
    fn branches(&self) -> std::collections::BTreeMap<String, (usize, Vec<String>)> {
        let robot = self.model.robot();
        robot
            .branches()
            .iter()
            .map(|b| (b.name.clone(), (b.link, b.joints.iter().map(|j| j.name.clone()).collect())))
            .collect()
    }

    /// `(dof, 2)`: lower and upper limit per joint, degrees (mm for prismatic joints); ±inf where the
    /// file gives none.
    #[getter]
    fn limits_deg<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
        let chain = self.chain();
        let lower: Vec<f64> = chain.joints().iter().map(|j| j.limits.map_or(f64::NEG_INFINITY, |l| l.lower)).collect();
        let upper: Vec<f64> = chain.joints().iter().map(|j| j.limits.map_or(f64::INFINITY, |l| l.upper)).collect();
        let (lo, hi) = (joints_to_external(chain, &lower), joints_to_external(chain, &upper));
        let data = lo.iter().zip(&hi).flat_map(|(a, b)| [*a, *b]).collect();
        output(py, data, Some(chain.dof()), &[2])
    }

    /// `True` when the robot carries nothing beyond its geometry (no joint corrections, drift or
    /// payload): what `diagnose` and `simulate` start from.
    #[getter]
    fn is_plain(&self) -> bool {
        self.model.is_plain()
    }

    /// What a URDF cannot hold of this robot (empty for a plain one).
    #[getter]
    fn beyond_urdf(&self) -> Vec<String> {
        self.model.beyond_urdf()
    }

    /// Forward kinematics: `q` in degrees (mm for prismatic joints), `(n,)` or `(N, n)`; returns the tool
    /// pose in the base frame as a 4×4 homogeneous matrix in mm, `(4, 4)` or `(N, 4, 4)`. `time_min` and
    /// `temps` (°C by sensor) give the operating state of a calibrated robot's drift, `approach` (per joint
    /// 1, -1 or 0: the direction it last moved in; one list for every row, or one per row `(N, n)`) a
    /// backlash's side. A batch runs on every core without the GIL.
    #[pyo3(signature = (q, *, time_min=None, temps=None, approach=None))]
    fn fk<'py>(
        &self,
        py: Python<'py>,
        q: PyArrayLikeDyn<'py, f64, AllowTypeChange>,
        time_min: Option<f64>,
        temps: Option<HashMap<String, f64>>,
        approach: Option<Approaches>,
    ) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
        let chain = self.chain();
        let n = chain.dof();
        let rows = Rows::read(&q, n, "q")?;
        let states = states(time_min, temps, approach, rows.count())?;
        for s in &states {
            self.model.check_state(s, false, false).map_err(input)?;
        }
        let batch = rows.batch;
        let model = &self.model;
        let plain = model.is_plain() && states.iter().all(|s| *s == OperatingState::default());
        let kinds: Vec<_> = chain.joints().iter().map(|j| j.kind).collect();
        let data = py.detach(|| -> Result<Vec<f64>, String> {
            let mut out = vec![0.0; rows.count() * 16];
            // Per thread, one joint vector reused; a plain robot's FK without building a quaternion
            // (`Chain::tool_position_rotation`), else the whole model in its state.
            out.par_chunks_mut(16).zip(rows.data.par_chunks(n)).enumerate().try_for_each_init(
                || vec![0.0; n],
                |q, (i, (dst, row))| {
                    for ((v, &x), &k) in q.iter_mut().zip(row).zip(&kinds) {
                        *v = thermokin_io::units::joint_value_in(k, x);
                    }
                    let at = |e: String| if batch.is_some() { format!("q row {i}: {e}") } else { e };
                    let (p, r) = if plain {
                        chain.tool_position_rotation(q).map_err(|e| at(e.to_string()))?
                    } else {
                        let pose = model.tool_pose(q, state_of(&states, i)).map_err(|e| at(e.to_string()))?;
                        (pose.translation.vector, *pose.rotation.to_rotation_matrix().matrix())
                    };
                    for row in 0..3 {
                        dst[4 * row..4 * row + 3].copy_from_slice(&[r[(row, 0)], r[(row, 1)], r[(row, 2)]]);
                        dst[4 * row + 3] = p[row];
                    }
                    dst[12..].copy_from_slice(&[0.0, 0.0, 0.0, 1.0]);
                    Ok::<(), String>(())
                },
            )?;
            Ok(out)
        });
        output(py, data.map_err(input)?, batch, &[4, 4])
    }

    /// The geometric Jacobian at the tool point in the base frame, `(6, n)` or `(N, 6, n)`: rows 0–2 the
    /// tool point's linear velocity in **mm per radian** of a revolute joint (mm per mm of a prismatic
    /// one), rows 3–5 the angular velocity in **radians per radian** (0 for a prismatic joint) — per
    /// radian, as Pinocchio's; multiply by π/180 for per degree. `q` in degrees (mm for prismatic joints).
    /// For a calibrated robot, the derivative is with respect to the joint values the chain takes in
    /// the state (`time_min`, `temps`); for one whose rows tilt with the configuration (a lateral
    /// compliance), on the chain in force at `q`, its tilt held.
    #[pyo3(signature = (q, *, time_min=None, temps=None, approach=None))]
    fn jacobian<'py>(
        &self,
        py: Python<'py>,
        q: PyArrayLikeDyn<'py, f64, AllowTypeChange>,
        time_min: Option<f64>,
        temps: Option<HashMap<String, f64>>,
        approach: Option<Approaches>,
    ) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
        let (rows, batch) = self.joint_rows(q, "q")?;
        let states = states(time_min, temps, approach, rows.len())?;
        for s in &states {
            self.model.check_state(s, false, false).map_err(input)?;
        }
        let chain = self.model.chain_at(&states[0]).map_err(input)?;
        let (n, model) = (chain.dof(), &self.model);
        let data = py.detach(|| -> Result<Vec<f64>, String> {
            let per: Vec<Vec<f64>> = rows
                .par_iter()
                .enumerate()
                .map(|(i, q)| {
                    let bent = if model.bends() {
                        Some(model.chain_at_joints(state_of(&states, i), q).map_err(|e| format!("q row {i}: {e}"))?)
                    } else {
                        None
                    };
                    let j = bent.as_ref().unwrap_or(&chain).jacobian(q).map_err(|e| format!("q row {i}: {e}"))?;
                    Ok((0..6).flat_map(|r| (0..n).map(move |c| (r, c))).map(|(r, c)| j[(r, c)]).collect())
                })
                .collect::<Result<_, String>>()?;
            Ok(per.concat())
        });
        output(py, data.map_err(input)?, batch, &[6, n])
    }

    /// Inverse kinematics on the robot as it is in the state (`time_min`, `temps`): `pose` a 4×4 matrix
    /// (mm) or `(N, 4, 4)`; with `position_only=True`, a point `(3,)` or `(N, 3)`. `seed` in degrees
    /// (zeros by default), one for every target or `(N, n)`, one per target; `approach` (a backlash's
    /// side, per joint 1, -1 or 0) likewise one list for every target or one per target. Returns an
    /// `IKResult`: the
    /// joints to command (a calibrated robot's joint corrections inverted and re-measured), the status
    /// — `"Converged"` only when FK of the answer, recomputed independently of the solver, is within
    /// the tolerances — and the re-measured errors.
    /// A batch runs on every core without the GIL, each target from its seed; the result does not
    /// depend on the number of threads.
    #[pyo3(signature = (pose, seed=None, *, position_only=false, time_min=None, temps=None, approach=None, restarts=None))]
    #[allow(clippy::too_many_arguments)] // Python's keyword arguments, one per state and option.
    fn ik<'py>(
        &self,
        py: Python<'py>,
        pose: PyArrayLikeDyn<'py, f64, AllowTypeChange>,
        seed: Option<PyArrayLikeDyn<'py, f64, AllowTypeChange>>,
        position_only: bool,
        time_min: Option<f64>,
        temps: Option<HashMap<String, f64>>,
        approach: Option<Approaches>,
        restarts: Option<usize>,
    ) -> PyResult<IkResult> {
        let chain = self.chain();
        let n = chain.dof();
        let (goals, batch) = if position_only {
            let rows = Rows::read(&pose, 3, "pose")?;
            let goals = rows.data.chunks(3).map(|p| Goal::Position(Vector3::new(p[0], p[1], p[2]))).collect::<Vec<_>>();
            (goals, rows.batch)
        } else {
            let rows = Rows::read_shaped(&pose, &[4, 4], "pose")?;
            let goals = rows
                .data
                .chunks(16)
                .enumerate()
                .map(|(i, m)| pose_of(m, "pose", rows.batch.map(|_| i)).map(Goal::Pose))
                .collect::<PyResult<Vec<_>>>()?;
            (goals, rows.batch)
        };
        let states = states(time_min, temps, approach, goals.len())?;
        for s in &states {
            self.model.check_state(s, false, false).map_err(input)?;
        }
        // One seed for every target, or one per target (`(N, n)` for N targets).
        let seeds: Vec<Vec<f64>> = match seed {
            Some(s) => {
                let (rows, b) = self.joint_rows(s, "seed")?;
                if b.is_some() && rows.len() != goals.len() {
                    return Err(input(format!(
                        "seed: {} seeds for {} targets (give one, or one per target)",
                        rows.len(),
                        goals.len()
                    )));
                }
                rows
            }
            None => vec![vec![0.0; n]],
        };
        let mut params = Params::default();
        if let Some(r) = restarts {
            params.restarts = r;
        }
        let model = &self.model;
        let solved = py.detach(|| -> Result<Vec<Solution>, String> {
            goals
                .par_iter()
                .enumerate()
                .map_init(
                    || Workspace::new(n),
                    |ws, (i, goal)| {
                        let seed = if seeds.len() == 1 { &seeds[0] } else { &seeds[i] };
                        let state = state_of(&states, i);
                        thermokin_compensate::solve_on_model(model, state, goal, seed, &params, ws, i as u64)
                            .map_err(|e| if batch.is_some() { format!("pose {i}: {e}") } else { e.to_string() })
                    },
                )
                .collect()
        });
        let solved = solved.map_err(input)?;
        ik_result(py, chain, &solved, batch)
    }

    /// A copy deformed by a deviation table (`deformation`: a TOML or CSV file, paper Table 7's layout)
    /// under `semantics` (`"canonical"`, or `"coppeliasim"` for the authors' scene), at `time_min` of a
    /// `profile` (e.g. `"linear-grow:180"`, a law or a TOML file) when one is given.
    #[pyo3(signature = (deformation, *, semantics=None, profile=None, time_min=None))]
    fn deformed(
        &self,
        deformation: PathBuf,
        semantics: Option<&str>,
        profile: Option<String>,
        time_min: Option<f64>,
    ) -> PyResult<Self> {
        let dof = self.chain().dof();
        must_exist(&deformation)?;
        let table = thermokin_io::read_deviation_table_for(&deformation, dof).map_err(io)?;
        let profile = profile.map(|p| profile_of(&p, dof)).transpose()?;
        // The table in force: the command line's rule (a time needs a profile, a profile a time).
        let drifts = self.model.needs().0;
        let table = thermokin_deform::table_in_force(&table, profile.as_ref(), time_min, drifts).map_err(input)?;
        let chain = table.apply(self.chain(), &semantics_of(semantics, dof)?).map_err(input)?;
        let robot = self.model.robot().with_chain(chain).map_err(input)?;
        Ok(Self { model: self.model.clone().with_robot(robot).map_err(input)? })
    }

    /// The robot as URDF text (what a URDF cannot hold, named in its header).
    fn to_urdf(&self) -> String {
        thermokin_urdf::export_robot_noting(self.model.robot(), &self.model.beyond_urdf())
    }

    /// The robot as the project's TOML (the complete record: drift, joint corrections, payload).
    fn to_toml(&self) -> String {
        thermokin_io::robot_model_to_toml(&self.model)
    }

    /// Writes the robot: URDF when the path ends in `.urdf`, TOML otherwise; atomically (a temporary
    /// file renamed).
    fn save(&self, path: PathBuf) -> PyResult<()> {
        self.save_to(&path)
    }

    fn __repr__(&self) -> String {
        format!("Robot({:?}, dof={})", self.model.robot().name(), self.chain().dof())
    }
}

/// Solutions as an [`IkResult`] in degrees.
fn ik_result(py: Python<'_>, chain: &Chain, solved: &[Solution], batch: Option<usize>) -> PyResult<IkResult> {
    let n = chain.dof();
    let q: Vec<f64> = solved.iter().flat_map(|s| joints_to_external(chain, &s.q)).collect();
    let status: Vec<String> = solved.iter().map(|s| format!("{:?}", s.status)).collect();
    let dp: Vec<f64> = solved.iter().map(|s| s.position_error_mm).collect();
    let dr: Vec<f64> = solved.iter().map(|s| thermokin_chain::units::degrees(s.orientation_error_rad)).collect();
    let it: Vec<usize> = solved.iter().map(|s| s.iterations).collect();
    let ok: Vec<bool> = solved.iter().map(Solution::converged).collect();
    Ok(match batch {
        Some(_) => IkResult {
            q: output(py, q, batch, &[n])?.into_any().unbind(),
            status: status.into_pyobject(py)?.into_any().unbind(),
            position_error_mm: output(py, dp, None, &[solved.len()])?.into_any().unbind(),
            orientation_error_deg: output(py, dr, None, &[solved.len()])?.into_any().unbind(),
            iterations: numpy::PyArray1::from_vec(py, it).into_any().unbind(),
            converged: numpy::PyArray1::from_vec(py, ok).into_any().unbind(),
        },
        None => IkResult {
            q: output(py, q, None, &[n])?.into_any().unbind(),
            status: status[0].clone().into_pyobject(py)?.into_any().unbind(),
            position_error_mm: dp[0].into_pyobject(py)?.into_any().unbind(),
            orientation_error_deg: dr[0].into_pyobject(py)?.into_any().unbind(),
            iterations: it[0].into_pyobject(py)?.into_any().unbind(),
            converged: pyo3::types::PyBool::new(py, ok[0]).to_owned().into_any().unbind(),
        },
    })
}
