//! Robot description in TOML: the same-orientation extended table (`[[joint]]` rows), or a classic /
//! modified DH table (`[[dh]]` rows) converted exactly to it. Millimetres and degrees in the file.
//!
//! ```toml
//! name = "ABB IRB 140"
//! convention = "extended"          # or "dh", "mdh"
//! [[joint]]
//! name = "A1"
//! axis = "Z"                       # "X", "-Y", … or [x, y, z]
//! offset_mm = [0.0, 0.0, 104.5]    # from the previous joint, in its frame
//! limits_deg = [-180.0, 180.0]
//! [tool]
//! translation_mm = [25.5, 0.0, 0.0]
//! rotation_xyz_deg = [0.0, 90.0, 0.0]
//! ```

use std::path::Path;

use nalgebra::{Isometry3, Translation3, Unit, UnitQuaternion, Vector3};
use serde::Deserialize;
use thermokin_chain::{Chain, DhConvention, DhRow, DhTable, FixedRow, Joint, JointKind, JointLimits, xyz_rotation};
use thermokin_deform::{DriftLaw, DriftRow, JointCorrection, RobotModel, Row, TimeProfile};
use toml::Spanned;

use crate::{IoError, line_of, read_text, units};

use thermokin_chain::{JointRatings, LinkMass, Robot};

#[derive(Deserialize, Default, Clone, Copy, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
enum Convention {
    #[default]
    Extended,
    Dh,
    Mdh,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RobotFile {
    name: Option<String>,
    #[serde(default)]
    description: Option<String>,
    #[serde(default)]
    convention: Convention,
    base: Option<Spanned<RowSpec>>,
    tool: Option<Spanned<RowSpec>>,
    #[serde(default)]
    joint: Vec<Spanned<JointSpec>>,
    #[serde(default)]
    dh: Vec<Spanned<DhSpec>>,
    /// Gravity's direction in the file's world frame (default `[0, 0, -1]`).
    gravity: Option<Spanned<[f64; 3]>>,
    /// The payload the robot carries by default (the one it was calibrated with).
    payload: Option<Spanned<PayloadSpec>>,
    /// Rows drifting with operating time or temperature.
    #[serde(default)]
    drift: Vec<Spanned<DriftSpec>>,
    /// Accelerometers or inclinometers on the robot's links.
    #[serde(default)]
    accelerometer: Vec<Spanned<AccelerometerSpec>>,
    /// The rest of the robot's tree: serial chains hanging from its links.
    #[serde(default)]
    branch: Vec<Spanned<BranchSpec>>,
    /// The loads of branches on joints' gravity compliance (lumped without masses, a compliance with them).
    #[serde(default)]
    branch_load: Vec<Spanned<BranchLoadSpec>>,
}

/// `[[branch]]`: a serial chain hanging from link `link` (0 the base, `k` the link joint `k` moves), its
/// `[[branch.joint]]` rows as `[[joint]]` rows (geometry only).
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct BranchSpec {
    name: String,
    link: usize,
    joint: Vec<BranchJointSpec>,
}

/// `[[branch.joint]]`: a branch joint's name, axis, offset from the previous joint (mm), type and zero,
/// and the mass of the link it moves (`mass_kg`, `com_mm` in its frame, as a `[[joint]]` row's).
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct BranchJointSpec {
    name: String,
    axis: AxisSpec,
    offset_mm: [f64; 3],
    #[serde(default, rename = "type")]
    kind: KindSpec,
    #[serde(default)]
    zero: f64,
    mass_kg: Option<f64>,
    com_mm: Option<[f64; 3]>,
}

/// `[[branch_load]]`: branch `branch`'s load on joint `joint`'s (1-based) gravity compliance, the
/// weights of `thermokin_chain::branch_load_basis_into`'s functions in degrees — or, with `lateral =
/// true`, on its lateral compliance (its bearing's tilt across the axis), the weights of
/// `thermokin_chain::branch_lateral_basis_into`'s. For a branch whose joints carry masses the function
/// (one per direction) is the torque (moment) of everything the joint carries — the chain's links with
/// the file's masses and the branch's — in N·m, and the weight the joint's compliance in degrees per N·m.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct BranchLoadSpec {
    joint: usize,
    branch: String,
    load_deg: Vec<f64>,
    #[serde(default)]
    lateral: bool,
}

/// `[[accelerometer]]`: a sensor on a link, its columns `NAME_x`, `NAME_y`, `NAME_z`.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct AccelerometerSpec {
    name: String,
    /// 0 the base, `k` the link joint `k` moves.
    link: usize,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct PayloadSpec {
    mass_kg: f64,
    #[serde(default)]
    com_mm: [f64; 3],
}

#[derive(Deserialize)]
#[serde(untagged)]
enum RowName {
    Joint(i64),
    Name(String),
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct PerKelvinSpec {
    sensors: Vec<String>,
    reference_c: Vec<f64>,
}

/// A row turning with a declared accelerometer's tilt (`DriftLaw::Tilt`).
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct TiltSpec {
    sensor: String,
    /// `"x"`, `"y"` or `"z"`: the component of the sensor's tilt.
    axis: String,
    /// The sensor's reference direction (unit; its axes).
    reference: [f64; 3],
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct DriftSpec {
    /// A joint number (1-based), `"base"` or `"tool"`.
    row: RowName,
    /// mm and degrees: at the profile's factor 1, per kelvin, or per radian of tilt.
    error: [f64; 6],
    profile: Option<TimeProfile>,
    per_kelvin: Option<PerKelvinSpec>,
    tilt: Option<TiltSpec>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RowSpec {
    #[serde(default)]
    translation_mm: [f64; 3],
    #[serde(default)]
    rotation_xyz_deg: [f64; 3],
    error: Option<[f64; 6]>,
}

#[derive(Deserialize)]
#[serde(untagged)]
enum AxisSpec {
    Name(String),
    Vector([f64; 3]),
}

#[derive(Deserialize, Clone, Copy, Default)]
#[serde(rename_all = "lowercase")]
enum KindSpec {
    #[default]
    Revolute,
    Prismatic,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct JointSpec {
    name: Option<String>,
    axis: AxisSpec,
    offset_mm: [f64; 3],
    #[serde(default, rename = "type")]
    kind: KindSpec,
    /// Zero offset: degrees (revolute) or mm (prismatic).
    #[serde(default)]
    zero: f64,
    /// Limits: degrees (revolute) or mm (prismatic).
    limits: Option<[f64; 2]>,
    error: Option<[f64; 6]>,
    /// Gear-ratio error: Δq = scale · q.
    scale: Option<f64>,
    /// Cyclic encoder error, degrees: [sin q, cos q, sin 2q, cos 2q] coefficients.
    cyclic_deg: Option<[f64; 4]>,
    /// Gravity compliance, degrees per N·m.
    compliance_deg_per_nm: Option<f64>,
    /// The coupling of this joint's compliance with the next joint's, degrees per N·m.
    compliance_coupling_deg_per_nm: Option<f64>,
    /// Gravity compliance known without masses, degrees (degrees per mm for a slide the joint carries):
    /// the weights of `thermokin_chain::gravity_load_basis_into`'s functions.
    gravity_load_deg: Option<Vec<f64>>,
    /// Lateral compliance: degrees per N·m about the joint's two lateral directions, then a slide's
    /// degrees per N·m per mm of extension and mm per N·m of shift: `[c1, c2]` or `[c1, c2, c1', c2', s1, s2]`.
    lateral_compliance_deg_per_nm: Option<Vec<f64>>,
    /// Lateral compliance known without masses, degrees (degrees per mm for a slide the joint carries):
    /// the weights of `thermokin_chain::lateral_load_basis_into`'s functions; a slide's own three sets
    /// (`thermokin_deform::lumped_lateral_row_error`): its tilt's in degrees, its bend's in degrees per mm,
    /// its shift's in mm.
    lateral_load_deg: Option<Vec<f64>>,
    /// A slide's straightness: `[tilt1, tilt2, roll]` degrees per mm of extension, then `[bow1, bow2]`
    /// mm per mm² (`thermokin_deform::straightness_row_error`).
    straightness: Option<[f64; 5]>,
    /// Backlash: half the play between the gears' flanks, degrees (mm for a slide) — the joint sits this
    /// far on the side it last moved towards.
    backlash: Option<f64>,
    mass_kg: Option<f64>,
    com_mm: Option<[f64; 3]>,
    /// Rated speed: degrees per second (revolute) or mm/s (prismatic).
    max_velocity: Option<f64>,
    /// Rated torque (N·m) or force (N).
    max_effort: Option<f64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct DhSpec {
    name: Option<String>,
    a_mm: f64,
    alpha_deg: f64,
    d_mm: f64,
    #[serde(default)]
    theta_deg: f64,
    #[serde(default, rename = "type")]
    kind: KindSpec,
    limits: Option<[f64; 2]>,
}

/// Reads a robot TOML file that carries no state-dependent corrections (see [`read_robot_model`]).
pub fn read_robot(path: &Path) -> Result<Robot, IoError> {
    let text = read_text(path)?;
    parse_robot_toml(path, &text)
}

/// Reads a robot TOML file with every correction it carries: joint scale, cyclic and compliance terms,
/// drift rows, the default payload and gravity's direction.
pub fn read_robot_model(path: &Path) -> Result<RobotModel, IoError> {
    let text = read_text(path)?;
    parse_robot_model_toml(path, &text)
}

/// Parses robot TOML text into the robot alone; a file carrying corrections (which the robot alone would
/// silently drop) is refused with a pointer to [`parse_robot_model_toml`]. `path` is used in messages.
pub fn parse_robot_toml(path: &Path, text: &str) -> Result<Robot, IoError> {
    let model = parse_robot_model_toml(path, text)?;
    if !model.is_plain() {
        let what = model.beyond_urdf().join("; ");
        return Err(IoError::input(
            path,
            None,
            "drift, scale, cyclic_deg, compliance_deg_per_nm, compliance_coupling_deg_per_nm, gravity_load_deg, lateral_compliance_deg_per_nm, lateral_load_deg, straightness, backlash",
            format!(
                "this robot carries state-dependent corrections ({what}), which this command would drop: use fk, ik or compensate with it"
            ),
        ));
    }
    Ok(model.robot().clone())
}

/// Parses robot TOML text with every correction it carries; `path` is used in error messages.
pub fn parse_robot_model_toml(path: &Path, text: &str) -> Result<RobotModel, IoError> {
    let file: RobotFile = toml::from_str(text).map_err(|e| toml_error(path, text, &e))?;
    let _ = &file.description;
    let name = file
        .name
        .clone()
        .unwrap_or_else(|| path.file_stem().map_or_else(|| "robot".into(), |s| s.to_string_lossy().into_owned()));
    let at = |span: std::ops::Range<usize>| Some(line_of(text, span.start));
    let base = row(path, text, file.base.as_ref(), "base")?;
    let tool = row(path, text, file.tool.as_ref(), "tool")?;
    let (chain, masses, ratings) = match file.convention {
        Convention::Extended => {
            if !file.dh.is_empty() {
                return Err(IoError::input(
                    path,
                    at(file.dh[0].span()),
                    "dh",
                    "[[dh]] rows need convention = \"dh\" or \"mdh\"",
                ));
            }
            extended_chain(path, text, &file.joint, base, tool)?
        }
        conv @ (Convention::Dh | Convention::Mdh) => {
            if !file.joint.is_empty() {
                return Err(IoError::input(
                    path,
                    at(file.joint[0].span()),
                    "joint",
                    "[[joint]] rows need convention = \"extended\"",
                ));
            }
            dh_chain(path, text, &file.dh, conv, base, tool)?
        }
    };
    let described = |e: thermokin_chain::ChainError| IoError::input(path, None, "joint", e.to_string());
    let robot = Robot::new(name, chain).with_masses(masses).and_then(|r| r.with_ratings(ratings)).map_err(described)?;
    let mut sensors = Vec::new();
    for spanned in &file.accelerometer {
        let spec = spanned.get_ref();
        if sensors.iter().any(|s: &thermokin_chain::LinkSensor| s.name == spec.name) {
            return Err(IoError::input(
                path,
                at(spanned.span()),
                "accelerometer.name",
                format!("`{}` declared twice", spec.name),
            ));
        }
        sensors.push(thermokin_chain::LinkSensor { name: spec.name.clone(), link: spec.link });
        let one = Robot::new("check", robot.chain().clone()).with_accelerometers(sensors[sensors.len() - 1..].to_vec());
        one.map_err(|e| IoError::input(path, at(spanned.span()), "accelerometer", e.to_string()))?;
    }
    let robot = robot.with_accelerometers(sensors).map_err(described)?;
    let robot = with_branches(path, text, &file, robot)?;
    corrections(path, text, &file, robot)
}

/// The robot with its file's `[[branch]]` tables, each checked against its chain where it stands.
fn with_branches(path: &Path, text: &str, file: &RobotFile, robot: Robot) -> Result<Robot, IoError> {
    let mut branches = Vec::with_capacity(file.branch.len());
    for (b, spanned) in file.branch.iter().enumerate() {
        let (line, spec) = (Some(line_of(text, spanned.span().start)), spanned.get_ref());
        let mut joints = Vec::with_capacity(spec.joint.len());
        let mut masses = Vec::with_capacity(spec.joint.len());
        for (i, j) in spec.joint.iter().enumerate() {
            let field = |f: &str| format!("branch[{}].joint[{}].{f}", b + 1, i + 1);
            masses.push(link_mass(path, line, &field, (j.mass_kg, j.com_mm))?);
            let axis = axis(&j.axis).map_err(|m| IoError::input(path, line, field("axis"), m))?;
            finite(path, line, &field("offset_mm"), &j.offset_mm)?;
            finite(path, line, &field("zero"), &[j.zero])?;
            let offset = Vector3::from(j.offset_mm);
            let mut joint = match j.kind {
                KindSpec::Revolute => Joint::revolute(j.name.clone(), offset, axis),
                KindSpec::Prismatic => Joint::prismatic(j.name.clone(), offset, axis),
            };
            joint.zero = units::joint_value_in(joint.kind, j.zero);
            joints.push(joint);
        }
        let masses = if masses.iter().any(Option::is_some) { masses } else { Vec::new() };
        branches.push(thermokin_chain::Branch { name: spec.name.clone(), link: spec.link, joints, masses });
        let checked = Robot::new("check", robot.chain().clone()).with_branches(branches.clone());
        checked.map_err(|e| IoError::input(path, line, format!("branch[{}]", b + 1), e.to_string()))?;
    }
    robot.with_branches(branches).map_err(|e| IoError::input(path, None, "branch", e.to_string()))
}

/// A TOML syntax or schema error located: the line, the key it names, and for a key in other units
/// than the file's, which units the file takes.
fn toml_error(path: &Path, text: &str, e: &toml::de::Error) -> IoError {
    let line = e.span().map(|s| line_of(text, s.start));
    let message = e.message().to_string();
    let names_a_key =
        ["unknown field", "missing field", "duplicate key", "duplicate field"].iter().any(|p| message.starts_with(p));
    let field = if names_a_key { key_in(&message).unwrap_or_else(|| "toml".to_string()) } else { "toml".to_string() };
    let other_units = ["_m", "_rad", "_in", "_meters", "_radians", "_inches"];
    let hint = if message.starts_with("unknown field") && other_units.iter().any(|u| field.ends_with(u)) {
        " (robot files are in millimetres and degrees: offset_mm, translation_mm, rotation_xyz_deg, limits in degrees)"
    } else {
        ""
    };
    IoError::input(path, line, field, format!("{message}{hint}"))
}

/// What a robot file's rows give besides the chain: each joint's link mass and ratings.
type ChainParts = (Chain, Vec<Option<LinkMass>>, Vec<JointRatings>);

/// The chain of an extended table's `[[joint]]` rows, each row's errors located.
fn extended_chain(
    path: &Path,
    text: &str,
    rows: &[Spanned<JointSpec>],
    base: FixedRow,
    tool: FixedRow,
) -> Result<ChainParts, IoError> {
    if rows.is_empty() {
        return Err(IoError::input(path, None, "joint", "no [[joint]] rows"));
    }
    let mut joints = Vec::with_capacity(rows.len());
    let mut masses = Vec::with_capacity(rows.len());
    let mut ratings = Vec::with_capacity(rows.len());
    let mut names = std::collections::HashSet::new();
    for (i, spanned) in rows.iter().enumerate() {
        let line = Some(line_of(text, spanned.span().start));
        let spec = spanned.get_ref();
        if let Some(n) = &spec.name
            && !names.insert(n.clone())
        {
            let field = format!("joint[{}].name", i + 1);
            return Err(IoError::input(path, line, field, format!("duplicate joint name `{n}`")));
        }
        let (joint, rating, mass) = extended_joint(path, line, i, spec)?;
        joints.push(joint);
        ratings.push(rating);
        masses.push(mass);
    }
    let chain = Chain::new(base, joints, tool).map_err(|e| IoError::input(path, None, "joint", e.to_string()))?;
    Ok((chain, masses, ratings))
}

/// One `[[joint]]` row (the `i`-th, at `line`): the joint, its ratings and its link mass.
fn extended_joint(
    path: &Path,
    line: Option<usize>,
    i: usize,
    spec: &JointSpec,
) -> Result<(Joint, JointRatings, Option<LinkMass>), IoError> {
    let field = |f: &str| format!("joint[{}].{f}", i + 1);
    let axis = axis(&spec.axis).map_err(|m| IoError::input(path, line, field("axis"), m))?;
    finite(path, line, &field("offset_mm"), &spec.offset_mm)?;
    finite(path, line, &field("zero"), &[spec.zero])?;
    let name = spec.name.clone().unwrap_or_else(|| format!("A{}", i + 1));
    let offset = Vector3::from(spec.offset_mm);
    let mut joint = match spec.kind {
        KindSpec::Revolute => Joint::revolute(name, offset, axis),
        KindSpec::Prismatic => Joint::prismatic(name, offset, axis),
    };
    let kind = joint.kind;
    joint.zero = units::joint_value_in(kind, spec.zero);
    joint.limits = limits(path, line, &field("limits"), spec.limits, kind)?;
    if let Some(e) = spec.error {
        finite(path, line, &field("error"), &e)?;
        joint.error = units::error_params_in(e);
    }
    let positive = |key: &str, v: Option<f64>| -> Result<Option<f64>, IoError> {
        match v {
            Some(x) if !(x.is_finite() && x > 0.0) => {
                Err(IoError::input(path, line, field(key), format!("must be positive, got {x}")))
            }
            other => Ok(other),
        }
    };
    let rating = JointRatings {
        velocity: positive("max_velocity", spec.max_velocity)?.map(|v| units::joint_value_in(kind, v)),
        effort: positive("max_effort", spec.max_effort)?,
    };
    let mass = link_mass(path, line, &field, (spec.mass_kg, spec.com_mm))?;
    Ok((joint, rating, mass))
}

/// A row's link mass from its `mass_kg` and `com_mm` (`field` names a key of the row): none without
/// either, the centre at the joint's origin without `com_mm`; an error naming the key otherwise.
fn link_mass(
    path: &Path,
    line: Option<usize>,
    field: &dyn Fn(&str) -> String,
    (mass_kg, com_mm): (Option<f64>, Option<[f64; 3]>),
) -> Result<Option<LinkMass>, IoError> {
    match (mass_kg, com_mm) {
        (None, None) => Ok(None),
        (Some(m), com) => {
            let com = com.unwrap_or_default();
            finite(path, line, &field("com_mm"), &com)?;
            if !(m.is_finite() && m >= 0.0) {
                return Err(IoError::input(
                    path,
                    line,
                    field("mass_kg"),
                    format!("must be a finite mass ≥ 0, got {m}"),
                ));
            }
            Ok(Some(LinkMass { mass_kg: m, com_mm: Vector3::from(com) }))
        }
        (None, Some(_)) => Err(IoError::input(path, line, field("com_mm"), "com_mm needs mass_kg")),
    }
}

/// The chain of a classic or modified DH table's `[[dh]]` rows (converted exactly); DH rows carry no
/// masses or ratings.
fn dh_chain(
    path: &Path,
    text: &str,
    dh: &[Spanned<DhSpec>],
    conv: Convention,
    base: FixedRow,
    tool: FixedRow,
) -> Result<ChainParts, IoError> {
    if dh.is_empty() {
        return Err(IoError::input(path, None, "dh", "no [[dh]] rows"));
    }
    let mut rows = Vec::with_capacity(dh.len());
    for (i, spanned) in dh.iter().enumerate() {
        let line = Some(line_of(text, spanned.span().start));
        let s = spanned.get_ref();
        let field = |f: &str| format!("dh[{}].{f}", i + 1);
        finite(path, line, &field("a_mm, alpha_deg, d_mm, theta_deg"), &[s.a_mm, s.alpha_deg, s.d_mm, s.theta_deg])?;
        let kind = match s.kind {
            KindSpec::Revolute => JointKind::Revolute,
            KindSpec::Prismatic => JointKind::Prismatic,
        };
        rows.push(DhRow {
            name: s.name.clone().unwrap_or_else(|| format!("A{}", i + 1)),
            a: s.a_mm,
            alpha: units::radians(s.alpha_deg),
            d: s.d_mm,
            theta: units::radians(s.theta_deg),
            kind,
            limits: limits(path, line, &field("limits"), s.limits, kind)?,
        });
    }
    let convention = if conv == Convention::Dh { DhConvention::Classic } else { DhConvention::Modified };
    if !base.error.is_zero() || !tool.error.is_zero() {
        return Err(IoError::input(path, None, "error", "DH tables take error parameters only after conversion"));
    }
    let table = DhTable { convention, rows, base: base.nominal(), tool: tool.nominal() };
    let n = table.dof();
    let chain = table.to_extended().map_err(|e| IoError::input(path, None, "dh", e.to_string()))?;
    Ok((chain, vec![None; n], vec![JointRatings::default(); n]))
}

/// The corrections of a parsed file on its robot: per-joint scale, cyclic and compliance terms, drift rows,
/// payload, gravity.
fn corrections(path: &Path, text: &str, file: &RobotFile, robot: Robot) -> Result<RobotModel, IoError> {
    let at = |span: std::ops::Range<usize>| Some(line_of(text, span.start));
    let mut joints = vec![JointCorrection::NONE; robot.chain().dof()];
    let mut loads = vec![Vec::new(); robot.chain().dof()];
    let mut lateral_loads = vec![Vec::new(); robot.chain().dof()];
    for (i, spanned) in file.joint.iter().enumerate() {
        let (line, spec) = (at(spanned.span()), spanned.get_ref());
        let field = |f: &str| format!("joint[{}].{f}", i + 1);
        let c = &mut joints[i];
        if let Some(v) = spec.scale {
            finite(path, line, &field("scale"), &[v])?;
            c.scale = v;
        }
        if let Some(v) = spec.cyclic_deg {
            finite(path, line, &field("cyclic_deg"), &v)?;
            c.cyclic_rad = v.map(units::radians);
        }
        if let Some(v) = spec.compliance_deg_per_nm {
            finite(path, line, &field("compliance_deg_per_nm"), &[v])?;
            c.compliance_rad_per_nm = units::radians(v);
        }
        if let Some(v) = spec.compliance_coupling_deg_per_nm {
            finite(path, line, &field("compliance_coupling_deg_per_nm"), &[v])?;
            c.coupling_rad_per_nm = units::radians(v);
        }
        if let Some(v) = &spec.gravity_load_deg {
            finite(path, line, &field("gravity_load_deg"), v)?;
            loads[i] = v.iter().map(|&d| units::radians(d)).collect();
        }
        if let Some(v) = &spec.lateral_load_deg {
            finite(path, line, &field("lateral_load_deg"), v)?;
            let angles = lateral_load_angles(&robot, i, v.len());
            lateral_loads[i] =
                v.iter().enumerate().map(|(k, &d)| if k < angles { units::radians(d) } else { d }).collect();
        }
        if let Some(v) = spec.backlash {
            finite(path, line, &field("backlash"), &[v])?;
            let slide = robot.chain().joints()[i].kind == JointKind::Prismatic;
            c.backlash = if slide { v } else { units::radians(v) };
        }
        if let Some(v) = spec.straightness {
            finite(path, line, &field("straightness"), &v)?;
            // Turns in degrees per mm; bows in mm per mm².
            for (k, (c, &d)) in c.straightness.iter_mut().zip(&v).enumerate() {
                *c = if k < 3 { units::radians(d) } else { d };
            }
        }
        if let Some(v) = &spec.lateral_compliance_deg_per_nm {
            let name = field("lateral_compliance_deg_per_nm");
            finite(path, line, &name, v)?;
            if v.len() != 2 && v.len() != 6 {
                let message = format!(
                    "{} values: give [c1, c2] (deg/(N·m)) or, for a slide, [c1, c2, c1', c2', s1, s2]",
                    v.len()
                );
                return Err(IoError::input(path, line, name, message));
            }
            // Angles in degrees; a slide's shifts (the last two) are millimetres.
            for (k, (c, &d)) in c.lateral.iter_mut().zip(v).enumerate() {
                *c = if k < 4 { units::radians(d) } else { d };
            }
        }
    }
    let mut model = RobotModel::new(robot)
        .with_joint_corrections(joints)
        .and_then(|m| m.with_gravity_loads(loads))
        .and_then(|m| m.with_lateral_loads(lateral_loads))
        .map_err(|e| {
            let joint = match &e {
                thermokin_deform::DeformError::BadCorrection { joint, .. } => *joint,
                _ => 1,
            };
            let line = file.joint.get(joint - 1).and_then(|s| at(s.span()));
            IoError::input(path, line, format!("joint[{joint}]"), e.to_string())
        })?;
    model = with_branch_loads(path, text, file, model)?;
    let mut drift = Vec::with_capacity(file.drift.len());
    for (i, spanned) in file.drift.iter().enumerate() {
        let (line, spec) = (at(spanned.span()), spanned.get_ref());
        drift.push(drift_row(path, line, i, spec, model.robot().chain().dof())?);
    }
    model = model.with_drift(drift).map_err(|e| IoError::input(path, None, "drift", e.to_string()))?;
    if let Some(spanned) = &file.payload {
        let (line, p) = (at(spanned.span()), spanned.get_ref());
        finite(path, line, "payload.com_mm", &p.com_mm)?;
        let payload = LinkMass { mass_kg: p.mass_kg, com_mm: Vector3::from(p.com_mm) };
        model = model.with_payload(Some(payload)).map_err(|e| IoError::input(path, line, "payload", e.to_string()))?;
    }
    if let Some(spanned) = &file.gravity {
        let (line, g) = (at(spanned.span()), Vector3::from(*spanned.get_ref()));
        let norm = g.norm();
        if !(norm.is_finite() && norm > 1e-9) {
            return Err(IoError::input(path, line, "gravity", "gravity's direction must be a finite non-zero vector"));
        }
        model = model.with_gravity(Unit::new_normalize(g));
    }
    Ok(model)
}

/// The model with its file's `[[branch_load]]` tables, each checked where it stands.
fn with_branch_loads(path: &Path, text: &str, file: &RobotFile, model: RobotModel) -> Result<RobotModel, IoError> {
    let at = |span: std::ops::Range<usize>| Some(line_of(text, span.start));
    let mut branch_loads = Vec::with_capacity(file.branch_load.len());
    for (i, spanned) in file.branch_load.iter().enumerate() {
        let (line, spec) = (at(spanned.span()), spanned.get_ref());
        let field = |f: &str| format!("branch_load[{}].{f}", i + 1);
        let dof = model.robot().chain().dof();
        if !(1..=dof).contains(&spec.joint) {
            return Err(IoError::input(
                path,
                line,
                field("joint"),
                format!("joint {} of a robot with {dof} joints", spec.joint),
            ));
        }
        finite(path, line, &field("load_deg"), &spec.load_deg)?;
        let load = thermokin_deform::BranchLoad {
            joint: spec.joint - 1,
            branch: spec.branch.clone(),
            weights: spec.load_deg.iter().map(|&d| units::radians(d)).collect(),
            lateral: spec.lateral,
        };
        branch_loads.push(load);
        let checked = model.clone().with_branch_loads(branch_loads[branch_loads.len() - 1..].to_vec());
        checked.map_err(|e| IoError::input(path, line, format!("branch_load[{}]", i + 1), e.to_string()))?;
    }
    model.with_branch_loads(branch_loads).map_err(|e| IoError::input(path, None, "branch_load", e.to_string()))
}

/// One `[[drift]]` table.
fn drift_row(path: &Path, line: Option<usize>, i: usize, spec: &DriftSpec, dof: usize) -> Result<DriftRow, IoError> {
    let field = |f: &str| format!("drift[{}].{f}", i + 1);
    let row = match &spec.row {
        RowName::Joint(n) if (1..=dof as i64).contains(n) => Row::Joint(*n as usize - 1),
        RowName::Name(n) if n.eq_ignore_ascii_case("base") => Row::Base,
        RowName::Name(n) if n.eq_ignore_ascii_case("tool") => Row::Tool,
        RowName::Joint(n) => {
            return Err(IoError::input(path, line, field("row"), format!("joint {n} of a robot with {dof} joints")));
        }
        RowName::Name(n) => {
            return Err(IoError::input(
                path,
                line,
                field("row"),
                format!("`{n}`: a joint number, \"base\" or \"tool\""),
            ));
        }
    };
    finite(path, line, &field("error"), &spec.error)?;
    if let Some(t) = &spec.tilt {
        if spec.profile.is_some() || spec.per_kelvin.is_some() {
            return Err(IoError::input(path, line, field("tilt"), "give exactly one law: profile, per_kelvin or tilt"));
        }
        let component = ["x", "y", "z"].iter().position(|a| *a == t.axis).ok_or_else(|| {
            IoError::input(path, line, field("tilt.axis"), format!("`{}`: give \"x\", \"y\" or \"z\"", t.axis))
        })?;
        finite(path, line, &field("tilt.reference"), &t.reference)?;
        let law = DriftLaw::Tilt { sensor: t.sensor.clone(), component, reference: t.reference };
        return Ok(DriftRow { row, deviation: units::error_params_in(spec.error), law });
    }
    let law = match (&spec.profile, &spec.per_kelvin) {
        (Some(TimeProfile::Temperature { .. }), None) => {
            return Err(IoError::input(
                path,
                line,
                field("profile"),
                "a drift row follows named sensors with per_kelvin = { sensors, reference_c }, not a temperature log",
            ));
        }
        (Some(p), None) => {
            p.validate(dof).map_err(|e| IoError::input(path, line, field("profile"), e.to_string()))?;
            DriftLaw::Time(p.clone())
        }
        (None, Some(k)) => {
            if k.sensors.len() != k.reference_c.len() {
                return Err(IoError::input(
                    path,
                    line,
                    field("per_kelvin"),
                    format!("{} sensors and {} reference temperatures", k.sensors.len(), k.reference_c.len()),
                ));
            }
            finite(path, line, &field("per_kelvin.reference_c"), &k.reference_c)?;
            DriftLaw::PerKelvin { sensors: k.sensors.iter().cloned().zip(k.reference_c.iter().copied()).collect() }
        }
        _ => {
            return Err(IoError::input(
                path,
                line,
                field("profile"),
                "give exactly one law: profile = { kind = \"linear\" | \"exponential\" | … } or per_kelvin = { sensors, reference_c }",
            ));
        }
    };
    Ok(DriftRow { row, deviation: units::error_params_in(spec.error), law })
}

/// The key named in a serde message such as "unknown field `foo`, expected …".
fn key_in(message: &str) -> Option<String> {
    let start = message.find('`')? + 1;
    let end = start + message[start..].find('`')?;
    Some(message[start..end].to_string())
}

fn finite(path: &Path, line: Option<usize>, field: &str, values: &[f64]) -> Result<(), IoError> {
    if values.iter().all(|v| v.is_finite()) {
        Ok(())
    } else {
        Err(IoError::input(path, line, field, "values must be finite numbers (no nan or inf)"))
    }
}

fn limits(
    path: &Path,
    line: Option<usize>,
    field: &str,
    spec: Option<[f64; 2]>,
    kind: JointKind,
) -> Result<Option<JointLimits>, IoError> {
    let Some([lo, hi]) = spec else { return Ok(None) };
    finite(path, line, field, &[lo, hi])?;
    if lo > hi {
        return Err(IoError::input(path, line, field, format!("lower limit {lo} is above upper limit {hi}")));
    }
    Ok(Some(JointLimits { lower: units::joint_value_in(kind, lo), upper: units::joint_value_in(kind, hi) }))
}

fn axis(spec: &AxisSpec) -> Result<Unit<Vector3<f64>>, String> {
    match spec {
        AxisSpec::Name(s) => {
            let t = s.trim().to_ascii_uppercase();
            let (sign, letter) = match t.strip_prefix('-') {
                Some(rest) => (-1.0, rest.to_string()),
                None => (1.0, t.trim_start_matches('+').to_string()),
            };
            let v = match letter.as_str() {
                "X" => Vector3::x(),
                "Y" => Vector3::y(),
                "Z" => Vector3::z(),
                _ => return Err(format!("`{s}` is not an axis: use X, Y, Z, -X, -Y, -Z or [x, y, z]")),
            };
            Ok(Unit::new_unchecked(v * sign))
        }
        AxisSpec::Vector(v) => {
            let v = Vector3::from(*v);
            let n = v.norm();
            if !n.is_finite() || n < 1e-9 {
                return Err(format!("[{}, {}, {}] is not a usable axis (zero or not finite)", v.x, v.y, v.z));
            }
            Ok(Unit::new_normalize(v))
        }
    }
}

fn row(path: &Path, text: &str, spec: Option<&Spanned<RowSpec>>, which: &str) -> Result<FixedRow, IoError> {
    let Some(spanned) = spec else { return Ok(FixedRow::identity()) };
    let line = Some(line_of(text, spanned.span().start));
    let s = spanned.get_ref();
    finite(path, line, &format!("{which}.translation_mm"), &s.translation_mm)?;
    finite(path, line, &format!("{which}.rotation_xyz_deg"), &s.rotation_xyz_deg)?;
    let rot = xyz_rotation(&Vector3::from(s.rotation_xyz_deg).map(units::radians));
    let iso =
        Isometry3::from_parts(Translation3::from(Vector3::from(s.translation_mm)), UnitQuaternion::from_matrix(&rot));
    let mut r = FixedRow::from_isometry(&iso);
    if let Some(e) = s.error {
        finite(path, line, &format!("{which}.error"), &e)?;
        r.error = units::error_params_in(e);
    }
    Ok(r)
}

/// Where a robot file's chain starts and ends (URDF only; TOML describes one chain).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct RobotOptions {
    /// URDF base link (default: the root).
    pub base: Option<String>,
    /// URDF tip link (default: the single leaf).
    pub tip: Option<String>,
}

/// Reads a robot from TOML or, by extension, URDF (`.urdf`, `.xml`), converting metres to millimetres. A
/// TOML file carrying state-dependent corrections is refused (see [`read_robot_model_with`]).
pub fn read_robot_with(path: &Path, options: &RobotOptions) -> Result<Robot, IoError> {
    if is_urdf(path) {
        read_urdf(path, options)
    } else {
        no_link_options(path, options).and_then(|()| read_robot(path))
    }
}

/// Reads a robot with every correction its file carries: TOML ([`read_robot_model`]) or URDF (geometry
/// only: a model without corrections).
pub fn read_robot_model_with(path: &Path, options: &RobotOptions) -> Result<RobotModel, IoError> {
    if is_urdf(path) {
        read_urdf(path, options).map(RobotModel::new)
    } else {
        no_link_options(path, options)?;
        read_robot_model(path)
    }
}

fn is_urdf(path: &Path) -> bool {
    path.extension().is_some_and(|e| e.eq_ignore_ascii_case("urdf") || e.eq_ignore_ascii_case("xml"))
}

fn no_link_options(path: &Path, options: &RobotOptions) -> Result<(), IoError> {
    if options.base.is_some() || options.tip.is_some() {
        return Err(IoError::input(path, None, "base/tip", "only URDF robots take a base or tip link"));
    }
    Ok(())
}

fn read_urdf(path: &Path, options: &RobotOptions) -> Result<Robot, IoError> {
    let text = read_text(path)?;
    let name = path.display().to_string();
    let opts = thermokin_urdf::ImportOptions { base: options.base.clone(), tip: options.tip.clone() };
    let imported = thermokin_urdf::import_urdf(&text, &name, &opts).map_err(|e| {
        let (field, message) = match &e {
            thermokin_urdf::UrdfError::Element { element, name, message, .. } => {
                (format!("<{element} name=\"{name}\">"), message.clone())
            }
            thermokin_urdf::UrdfError::Parse { message, .. } => {
                ("xml".to_string(), format!("malformed URDF: {message}"))
            }
            thermokin_urdf::UrdfError::Structure { message, .. } => ("robot".to_string(), message.clone()),
            thermokin_urdf::UrdfError::Chain { source, .. } => ("chain".to_string(), source.to_string()),
        };
        IoError::input(path, None, field, message)
    })?;
    Ok(imported.robot)
}

/// Decimals of lengths (mm) and angles (degrees) in a written robot file: 1e-12 keeps FK exact to far
/// below any tolerance here and drops the binary noise of unit conversions (`100.00000000000001` mm from
/// 0.1 m, `-360.0000000000237`° from a rounded 2π).
const FILE_DECIMALS: i32 = 12;

/// One number as written: rounded to [`FILE_DECIMALS`], always with a decimal point (valid TOML float).
fn num(x: f64) -> String {
    format!("{:?}", units::rounded(x, FILE_DECIMALS))
}

fn fmt3(v: &Vector3<f64>) -> String {
    format!("[{}, {}, {}]", num(v.x), num(v.y), num(v.z))
}

fn fmt6(v: [f64; 6]) -> String {
    format!("[{}]", v.map(num).join(", "))
}

fn axis_toml(a: &Vector3<f64>) -> String {
    for (k, name) in ["X", "Y", "Z"].iter().enumerate() {
        let others_zero = (0..3).filter(|&i| i != k).all(|i| a[i] == 0.0);
        if others_zero && a[k] == 1.0 {
            return format!("\"{name}\"");
        }
        if others_zero && a[k] == -1.0 {
            return format!("\"-{name}\"");
        }
    }
    fmt3(a)
}

fn row_toml(out: &mut String, which: &str, row: &FixedRow) {
    let angles = thermokin_chain::xyz_angles_for_output(row.rotation.to_rotation_matrix().matrix()).map(units::degrees);
    out.push_str(&format!(
        "\n[{which}]\ntranslation_mm = {}\nrotation_xyz_deg = {}\n",
        fmt3(&row.translation),
        fmt3(&angles)
    ));
    if !row.error.is_zero() {
        out.push_str(&format!("error = {}\n", fmt6(units::error_params_out(&row.error))));
    }
}

/// The robot as TOML in the extended convention (what `read_robot` reads back), millimetres and
/// degrees, numbers rounded to 1e-12 (`FILE_DECIMALS`).
pub fn robot_to_toml(robot: &Robot) -> String {
    robot_model_to_toml(&RobotModel::new(robot.clone()))
}

/// A robot written as the file named `path` holds it: URDF when the path ends in `.urdf`, Universal
/// Robots' kinematics YAML when it ends in `.yaml` or `.yml` (geometry and zeros; what the file cannot
/// hold named in its header, and returned), the project's TOML otherwise (the complete record). The one
/// rule every front end's export and save follows. A YAML of a robot that is not six revolute joints is
/// refused.
pub fn robot_file_text(model: &RobotModel, path: &Path) -> Result<(String, Vec<String>), IoError> {
    if is_ur_yaml(path) {
        ur_kinematics_text(model, model.robot(), path)
    } else if path.extension().is_some_and(|e| e.eq_ignore_ascii_case("urdf")) {
        let beyond = model.beyond_urdf();
        Ok((thermokin_urdf::export_robot_noting(model.robot(), &beyond), beyond))
    } else {
        Ok((robot_model_to_toml(model), Vec::new()))
    }
}

/// Whether `path` names a UR kinematics YAML (`.yaml`, `.yml`).
pub fn is_ur_yaml(path: &Path) -> bool {
    path.extension().is_some_and(|e| e.eq_ignore_ascii_case("yaml") || e.eq_ignore_ascii_case("yml"))
}

/// `working` (the geometry of `model` in some state) as a UR kinematics YAML, with what it cannot hold.
fn ur_kinematics_text(model: &RobotModel, working: &Robot, path: &Path) -> Result<(String, Vec<String>), IoError> {
    let beyond = model.beyond_urdf();
    let text = thermokin_urdf::export_ur_kinematics_noting(working, &beyond)
        .map_err(|e| IoError::input(path, None, "robot", e.to_string()))?;
    Ok((text, beyond))
}

/// The robot as a UR kinematics YAML with the geometry in force at `state` (as [`urdf_in_state`]), written
/// for `path`, and what it cannot hold.
pub fn ur_kinematics_in_state(
    model: &RobotModel,
    state: &thermokin_chain::OperatingState,
    path: &Path,
) -> Result<(String, Vec<String>), IoError> {
    let chain = if *state == thermokin_chain::OperatingState::default() {
        model.robot().chain().clone()
    } else {
        model.chain_at(state).map_err(|e| IoError::input(path, None, "state", e.to_string()))?
    };
    let working = model.robot().with_chain(chain).map_err(|e| IoError::input(path, None, "robot", e.to_string()))?;
    ur_kinematics_text(model, &working, path)
}

/// The robot as URDF with the geometry in force at `state` (a drifting robot at its time and sensor
/// readings; the static geometry in the default state), and what URDF cannot hold — named in the file's
/// header, and returned.
pub fn urdf_in_state(
    model: &RobotModel,
    state: &thermokin_chain::OperatingState,
) -> Result<(String, Vec<String>), thermokin_deform::DeformError> {
    let chain = if *state == thermokin_chain::OperatingState::default() {
        model.robot().chain().clone()
    } else {
        model.chain_at(state)?
    };
    let working = model.robot().with_chain(chain)?;
    let beyond = model.beyond_urdf();
    Ok((thermokin_urdf::export_robot_noting(&working, &beyond), beyond))
}

/// How many of joint `i`'s `len` lateral-load weights are angles (degrees in a file, radians inside): all
/// of a revolute joint's; a slide's tilt and bend sets, not its shift set (mm).
fn lateral_load_angles(robot: &Robot, i: usize, len: usize) -> usize {
    if robot.chain().joints()[i].kind == JointKind::Prismatic { 2 * len / 3 } else { len }
}

/// The robot with every correction it carries as TOML (what [`read_robot_model`] reads back): per joint
/// `scale`, `cyclic_deg`, `compliance_deg_per_nm` beside the geometry; `gravity`, `[payload]` and one
/// `[[drift]]` table per drifting row with its law. Millimetres and degrees, numbers rounded to 1e-12.
pub fn robot_model_to_toml(model: &RobotModel) -> String {
    let robot = model.robot();
    let mut s = format!(
        "# Written by thermokin: the same-orientation extended table, mm and degrees.\nname = {:?}\nconvention = \"extended\"\n",
        robot.name()
    );
    if model.gravity().into_inner() != -Vector3::z() {
        s.push_str(&format!(
            "# Gravity's direction in this file's world frame (the base row turns the robot in it).\ngravity = {}\n",
            fmt3(&model.gravity())
        ));
    }
    for (i, j) in robot.chain().joints().iter().enumerate() {
        joint_toml(&mut s, robot, i, j, &model.joint_corrections()[i]);
        let weights = [
            (
                &model.gravity_loads()[i],
                "gravity compliance without masses: the weights of the gravity-load functions of this joint",
                "gravity_load_deg",
            ),
            (
                &model.lateral_loads()[i],
                "lateral compliance without masses: the weights of the lateral-load functions of this joint (about its first direction across the axis, then its second)",
                "lateral_load_deg",
            ),
        ];
        for (values, comment, key) in weights.into_iter().filter(|(v, ..)| !v.is_empty()) {
            let angles =
                if key == "lateral_load_deg" { lateral_load_angles(robot, i, values.len()) } else { values.len() };
            let deg: Vec<String> = values
                .iter()
                .enumerate()
                .map(|(k, &v)| format!("{:e}", if k < angles { units::degrees(v) } else { v }))
                .collect();
            s.push_str(&format!("# {comment}\n{key} = [{}]\n", deg.join(", ")));
        }
    }
    if robot.chain().base() != &FixedRow::identity() {
        row_toml(&mut s, "base", robot.chain().base());
    }
    row_toml(&mut s, "tool", robot.chain().tool());
    if let Some(p) = model.payload() {
        s.push_str(&format!(
            "\n# The payload the robot carries unless told otherwise (the one it was calibrated with).\n[payload]\nmass_kg = {}\ncom_mm = {}\n",
            num(p.mass_kg),
            fmt3(&p.com_mm)
        ));
    }
    for d in model.drift() {
        let row = match d.row {
            Row::Base => "\"base\"".to_string(),
            Row::Joint(j) => (j + 1).to_string(),
            Row::Tool => "\"tool\"".to_string(),
        };
        let law = match &d.law {
            DriftLaw::Time(p) => format!("profile = {}", profile_toml(p)),
            DriftLaw::PerKelvin { sensors } => {
                let names: Vec<String> = sensors.iter().map(|(n, _)| format!("{n:?}")).collect();
                let refs: Vec<String> = sensors.iter().map(|(_, t)| num(*t)).collect();
                format!("per_kelvin = {{ sensors = [{}], reference_c = [{}] }}", names.join(", "), refs.join(", "))
            }
            DriftLaw::Tilt { sensor, component, reference } => {
                let axis = ["x", "y", "z"].get(*component).copied().unwrap_or("x");
                format!(
                    "# turns with the tilt accelerometer {sensor} measures (give {sensor}_x, {sensor}_y, {sensor}_z at run time); error per radian of tilt\ntilt = {{ sensor = {sensor:?}, axis = {axis:?}, reference = {} }}",
                    fmt3(&Vector3::from(*reference))
                )
            }
        };
        s.push_str(&format!(
            "\n[[drift]]\nrow = {row}\nerror = {}\n{law}\n",
            fmt6(units::error_params_out(&d.deviation))
        ));
    }
    for a in robot.accelerometers() {
        s.push_str(&format!(
            "\n# Columns {n}_x, {n}_y, {n}_z of a measurements file: the tilt of link {l} (0 the base).\n[[accelerometer]]\nname = {n:?}\nlink = {l}\n",
            n = a.name,
            l = a.link
        ));
    }
    branches_toml(&mut s, model);
    s
}

/// The `[[branch]]` and `[[branch_load]]` tables of a model.
fn branches_toml(s: &mut String, model: &RobotModel) {
    for b in model.robot().branches() {
        s.push_str(&format!(
            "\n# A chain hanging from link {l} (0 the base); a measurements file's columns named as its joints give their positions (degrees; mm for a slide).\n[[branch]]\nname = {n:?}\nlink = {l}\n",
            n = b.name,
            l = b.link
        ));
        for (i, j) in b.joints.iter().enumerate() {
            joint_geometry_toml(s, "[[branch.joint]]", j);
            if let Some(m) = b.masses.get(i).copied().flatten() {
                s.push_str(&format!("mass_kg = {}\ncom_mm = {}\n", num(m.mass_kg), fmt3(&m.com_mm)));
            }
        }
    }
    for l in model.branch_loads() {
        let deg: Vec<String> = l.weights.iter().map(|&w| format!("{:e}", units::degrees(w))).collect();
        let (on, lateral) = if l.lateral {
            ("lateral compliance (its bearing's tilt)", "lateral = true\n")
        } else {
            ("compliance", "")
        };
        let masses = model.robot().branches().iter().any(|b| b.name == l.branch && b.carries_masses());
        let known = if masses {
            "with its masses: the joint's compliance under everything it carries, the branch included, degrees per N·m"
        } else {
            "without masses: the weights of its load functions"
        };
        s.push_str(&format!(
            "\n# The load of branch {b:?} on joint {j}'s {on}, {known} (give the branch's joint positions at run time).\n[[branch_load]]\njoint = {j}\nbranch = {b:?}\n{lateral}load_deg = [{}]\n",
            deg.join(", "),
            b = l.branch,
            j = l.joint + 1
        ));
    }
}

/// A joint's geometry under `header` (`[[joint]]`, `[[branch.joint]]`): name, axis, offset, type, zero.
fn joint_geometry_toml(s: &mut String, header: &str, j: &Joint) {
    s.push_str(&format!(
        "{header}\nname = {:?}\naxis = {}\noffset_mm = {}\n",
        j.name,
        axis_toml(&j.axis),
        fmt3(&j.offset)
    ));
    if j.kind == JointKind::Prismatic {
        s.push_str("type = \"prismatic\"\n");
    }
    if j.zero != 0.0 {
        s.push_str(&format!("zero = {}\n", num(units::joint_value_out(j.kind, j.zero))));
    }
}

/// One `[[joint]]` table.
fn joint_toml(s: &mut String, robot: &Robot, i: usize, j: &Joint, c: &JointCorrection) {
    let to_file = |v: f64| units::joint_value_out(j.kind, v);
    joint_geometry_toml(s, "\n[[joint]]", j);
    if let Some(l) = j.limits {
        s.push_str(&format!("limits = [{}, {}]\n", num(to_file(l.lower)), num(to_file(l.upper))));
    }
    if !j.error.is_zero() {
        s.push_str(&format!("error = {}\n", fmt6(units::error_params_out(&j.error))));
    }
    if c.scale != 0.0 {
        s.push_str(&format!("scale = {:e}\n", c.scale));
    }
    if c.cyclic_rad != [0.0; 4] {
        s.push_str(&format!("cyclic_deg = [{}]\n", c.cyclic_rad.map(|v| num(units::degrees(v))).join(", ")));
    }
    if c.compliance_rad_per_nm != 0.0 {
        s.push_str(&format!("compliance_deg_per_nm = {:e}\n", units::degrees(c.compliance_rad_per_nm)));
    }
    if c.coupling_rad_per_nm != 0.0 {
        s.push_str(&format!(
            "compliance_coupling_deg_per_nm = {:e}  # with joint {}\n",
            units::degrees(c.coupling_rad_per_nm),
            i + 2
        ));
    }
    if c.lateral != [0.0; 6] {
        let n = if j.kind == JointKind::Prismatic { 6 } else { 2 };
        let out: Vec<String> = c.lateral[..n]
            .iter()
            .enumerate()
            .map(|(k, &v)| format!("{:e}", if k < 4 { units::degrees(v) } else { v }))
            .collect();
        let slide = if n == 6 { " (then per N·m per mm of extension; the foot's shift, mm per N·m)" } else { "" };
        s.push_str(&format!(
            "# lateral compliance: tilt about the two directions across the axis, deg per N·m{slide}\nlateral_compliance_deg_per_nm = [{}]\n",
            out.join(", ")
        ));
    }
    if c.straightness != [0.0; 5] {
        let out: Vec<String> = c
            .straightness
            .iter()
            .enumerate()
            .map(|(k, &v)| format!("{:e}", if k < 3 { units::degrees(v) } else { v }))
            .collect();
        s.push_str(&format!(
            "# straightness of the guide: tilts about the two directions across the axis and roll about it, deg per mm of extension; bows across, mm per mm²\nstraightness = [{}]\n",
            out.join(", ")
        ));
    }
    if c.backlash != 0.0 {
        s.push_str(&format!(
            "# backlash: half the play; the joint sits this far towards the side it last moved to\nbacklash = {:e}\n",
            to_file(c.backlash)
        ));
    }
    if let Some(r) = robot.ratings().get(i) {
        if let Some(v) = r.velocity {
            s.push_str(&format!("max_velocity = {}\n", num(to_file(v))));
        }
        if let Some(e) = r.effort {
            s.push_str(&format!("max_effort = {}\n", num(e)));
        }
    }
    if let Some(Some(m)) = robot.masses().get(i) {
        s.push_str(&format!("mass_kg = {}\ncom_mm = {}\n", num(m.mass_kg), fmt3(&m.com_mm)));
    }
}

/// A time profile as an inline table (`{ kind = "exponential", tau_min = 45.0 }`), the form the reader's
/// `profile` key takes. Every number in full precision: a time constant is not rounded.
fn profile_toml(p: &TimeProfile) -> String {
    match p {
        TimeProfile::Static => "{ kind = \"static\" }".into(),
        TimeProfile::Linear { stabilization_min, after } => {
            let after = match after {
                thermokin_deform::AfterStabilization::Plateau => "plateau",
                thermokin_deform::AfterStabilization::KeepGrowing => "keep_growing",
            };
            format!("{{ kind = \"linear\", stabilization_min = {stabilization_min:?}, after = \"{after}\" }}")
        }
        TimeProfile::Exponential { tau_min } => format!("{{ kind = \"exponential\", tau_min = {tau_min:?} }}"),
        TimeProfile::Cubic { coefficients: [a, b, c] } => {
            format!("{{ kind = \"cubic\", coefficients = [{a:?}, {b:?}, {c:?}] }}")
        }
        // Refused by the model (a drift row's law is per kelvin instead); written for completeness.
        TimeProfile::Temperature { .. } => "{ kind = \"temperature\" }".into(),
    }
}
