#![doc = include_str!("../README.md")]
//! `thermokin-urdf`: URDF import of a serial chain into the same-orientation extended table, and URDF
//! export of any chain — deformed or identified — whose FK equals the chain's.
//!
//! Import follows the paper's two rules (section 2.3): joint positions and axes are expressed at the zero
//! configuration with every joint frame keeping the base orientation; fixed joints are folded in. Metres
//! and radians become millimetres (and radians inside the library) here, at this boundary. The reader
//! knows nothing about kinematics beyond building the table.

mod ur;

use std::collections::{HashMap, HashSet};

use nalgebra::{Isometry3, Translation3, Unit, UnitQuaternion, Vector3};
use thermokin_chain::{Chain, ChainError, JointFactor, JointKind, JointLimits, JointRatings, LinkMass, Robot};

/// Errors of URDF import and export, naming the element concerned.
#[derive(Debug, thiserror::Error)]
pub enum UrdfError {
    /// The XML could not be parsed as URDF.
    #[error("{source_name}: malformed URDF: {message}")]
    Parse {
        /// File name or description of the source.
        source_name: String,
        /// What the parser said.
        message: String,
    },
    /// A problem with one element.
    #[error("{source_name}: <{element} name=\"{name}\">: {message}")]
    Element {
        /// File name or description of the source.
        source_name: String,
        /// `joint` or `link`.
        element: &'static str,
        /// The element's name.
        name: String,
        /// What is wrong.
        message: String,
    },
    /// A problem with the robot as a whole (root, leaves, path).
    #[error("{source_name}: {message}")]
    Structure {
        /// File name or description of the source.
        source_name: String,
        /// What is wrong.
        message: String,
    },
    /// The resulting chain is invalid.
    #[error("{source_name}: {source}")]
    Chain {
        /// File name or description of the source.
        source_name: String,
        /// The chain error.
        source: ChainError,
    },
}

/// Which part of the tree to import.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct ImportOptions {
    /// Base link; default: the root (the one link that is no joint's child).
    pub base: Option<String>,
    /// Tip link; default: the single leaf below the base.
    pub tip: Option<String>,
}

/// An imported robot: the robot (chain, and the masses of the links each joint moves from `<inertial>`,
/// fixed links folded in, in the same-orientation joint frames; the ratings from `<limit velocity
/// effort>` where positive) and the links the chain was cut between.
#[derive(Clone, Debug, PartialEq)]
pub struct ImportedRobot {
    /// The robot, named as in the URDF.
    pub robot: Robot,
    /// Base link used.
    pub base_link: String,
    /// Tip link used.
    pub tip_link: String,
}

use thermokin_chain::units::{MM_PER_M, metres, millimetres};
pub use ur::{UrKinematics, base_link_from_inertia, export_ur_kinematics_noting};

fn pose_mm(p: &urdf_rs::Pose) -> Isometry3<f64> {
    let [x, y, z] = p.xyz.0;
    let [r, pi, yw] = p.rpy.0;
    // URDF rpy: R = Rz(yaw) · Ry(pitch) · Rx(roll), nalgebra's from_euler_angles.
    Isometry3::from_parts(
        Translation3::new(millimetres(x), millimetres(y), millimetres(z)),
        UnitQuaternion::from_euler_angles(r, pi, yw),
    )
}

// Long on purpose (~200 lines): the walk from base to tip resolves each joint against the links and
// fixed joints around it (folding, masses, limits, ratings), with every error naming the element it met;
// its helpers (`pose_mm`, the namespace check) are already apart.
/// Imports a serial chain from URDF text. `source_name` is used in messages.
///
/// ```
/// use thermokin_urdf::{ImportOptions, import_urdf};
///
/// let urdf = r#"<robot name="two_link">
///   <link name="base"/> <link name="upper"/> <link name="tip"/>
///   <joint name="shoulder" type="revolute">
///     <parent link="base"/> <child link="upper"/> <origin xyz="0 0 0.3"/> <axis xyz="0 1 0"/>
///     <limit lower="-1.5" upper="1.5" effort="50" velocity="2"/>
///   </joint>
///   <joint name="elbow" type="continuous">
///     <parent link="upper"/> <child link="tip"/> <origin xyz="0.4 0 0"/> <axis xyz="0 1 0"/>
///   </joint>
/// </robot>"#;
/// let robot = import_urdf(urdf, "two_link.urdf", &ImportOptions::default()).unwrap();
/// let robot = robot.robot;
/// assert_eq!(robot.chain().dof(), 2);
/// // Metres became millimetres: at zero the tip is 400 mm out and 300 mm up.
/// let tip = robot.chain().tool_pose(&[0.0, 0.0]).unwrap().translation.vector;
/// assert!((tip - nalgebra::Vector3::new(400.0, 0.0, 300.0)).norm() < 1e-9);
/// assert_eq!(robot.ratings()[0].velocity, Some(2.0));
/// ```
pub fn import_urdf(text: &str, source_name: &str, options: &ImportOptions) -> Result<ImportedRobot, UrdfError> {
    let src = source_name.to_string();
    let robot = parse(text, &src)?;
    let tree = Tree::of(&robot, &src)?;
    let base = tree.base(options.base.as_deref())?;
    let tip = tree.tip(&base, options.tip.as_deref())?;
    let path = tree.path(&base, &tip)?;
    let folded = fold(&robot, &path, &src)?;
    if folded.factors.is_empty() {
        return Err(tree.structure(format!("no revolute or prismatic joint between `{base}` and `{tip}`")));
    }
    let described = |source: ChainError| UrdfError::Chain { source_name: src.clone(), source };
    let chain = Chain::from_factors(&folded.factors, &folded.pending).map_err(described)?;
    let masses = link_masses(&folded, &chain).map_err(described)?;
    let branches = tree.branches(&path);
    let imported = Robot::new(robot.name.clone(), chain)
        .with_masses(masses)
        .and_then(|r| r.with_ratings(folded.ratings))
        .and_then(|r| r.with_branches(branches))
        .map_err(described)?;
    Ok(ImportedRobot { robot: imported, base_link: base, tip_link: tip })
}

/// The URDF parsed, after the namespace check.
fn parse(text: &str, src: &str) -> Result<urdf_rs::Robot, UrdfError> {
    let parse_error = |message: String| UrdfError::Parse { source_name: src.to_string(), message };
    check_namespaces(text).map_err(parse_error)?;
    // urdf-rs re-serialises through RustyXML, which panics on namespace shapes the check above refuses;
    // the unwind guard is the backstop for any other panic inside the third-party parser.
    let parsed = std::panic::catch_unwind(|| urdf_rs::read_from_string(text))
        .map_err(|_| parse_error("the XML parser failed on this input".into()))?;
    parsed.map_err(|e| parse_error(e.to_string()))
}

/// The kinematic tree of a URDF, checked: unique names, joints between existing links, every link the
/// child of at most one joint, no cycle.
struct Tree<'r> {
    robot: &'r urdf_rs::Robot,
    src: String,
    links: HashSet<&'r str>,
    parent_joint: HashMap<&'r str, &'r urdf_rs::Joint>,
    children: HashMap<&'r str, Vec<&'r str>>,
}

impl<'r> Tree<'r> {
    fn of(robot: &'r urdf_rs::Robot, src: &str) -> Result<Self, UrdfError> {
        let element = |element: &'static str, name: &str, message: String| UrdfError::Element {
            source_name: src.to_string(),
            element,
            name: name.to_string(),
            message,
        };
        let links: HashSet<&str> = robot.links.iter().map(|l| l.name.as_str()).collect();
        let mut seen_links = HashSet::new();
        for l in &robot.links {
            if !seen_links.insert(l.name.as_str()) {
                return Err(element("link", &l.name, "duplicate link name".into()));
            }
        }
        let mut parent_joint: HashMap<&str, &urdf_rs::Joint> = HashMap::new();
        let mut seen_joints = HashSet::new();
        for j in &robot.joints {
            if !seen_joints.insert(j.name.as_str()) {
                return Err(element("joint", &j.name, "duplicate joint name".into()));
            }
            for (role, link) in [("parent", &j.parent.link), ("child", &j.child.link)] {
                if !links.contains(link.as_str()) {
                    return Err(element("joint", &j.name, format!("its {role} link `{link}` does not exist")));
                }
            }
            if j.parent.link == j.child.link {
                return Err(element("joint", &j.name, "parent and child are the same link (a cycle)".into()));
            }
            if let Some(other) = parent_joint.insert(j.child.link.as_str(), j) {
                return Err(element(
                    "link",
                    &j.child.link,
                    format!("is the child of two joints, `{}` and `{}` (not a tree)", other.name, j.name),
                ));
            }
        }
        // Cycles: walking up from any link must end at a root.
        for l in &robot.links {
            let mut at = l.name.as_str();
            let mut steps = 0;
            while let Some(j) = parent_joint.get(at) {
                at = j.parent.link.as_str();
                steps += 1;
                if steps > robot.joints.len() {
                    return Err(element("link", &l.name, "lies on a cycle of joints".into()));
                }
            }
        }
        let mut children: HashMap<&str, Vec<&str>> = HashMap::new();
        for j in &robot.joints {
            children.entry(j.parent.link.as_str()).or_default().push(j.child.link.as_str());
        }
        Ok(Self { robot, src: src.to_string(), links, parent_joint, children })
    }

    fn structure(&self, message: String) -> UrdfError {
        UrdfError::Structure { source_name: self.src.clone(), message }
    }

    /// The base: the one given, or the single root link.
    fn base(&self, given: Option<&str>) -> Result<String, UrdfError> {
        let roots: Vec<&str> =
            self.robot.links.iter().map(|l| l.name.as_str()).filter(|l| !self.parent_joint.contains_key(l)).collect();
        match given {
            Some(b) if self.links.contains(b) => Ok(b.to_string()),
            Some(b) => {
                Err(self.structure(format!("base link `{b}` does not exist (root links: {})", roots.join(", "))))
            }
            None => match roots.as_slice() {
                [one] => Ok((*one).to_string()),
                [] => Err(self.structure("no root link".into())),
                many => Err(self.structure(format!("several root links: {}; choose one with --base", many.join(", ")))),
            },
        }
    }

    /// The leaf links below `base`, sorted.
    fn leaves(&self, base: &str) -> Vec<&'r str> {
        let mut leaves = Vec::new();
        let mut stack = match self.links.get(base) {
            Some(b) => vec![*b],
            None => Vec::new(),
        };
        while let Some(l) = stack.pop() {
            match self.children.get(l) {
                Some(c) if !c.is_empty() => stack.extend(c.iter().copied()),
                _ => leaves.push(l),
            }
        }
        leaves.sort_unstable();
        leaves
    }

    /// The tip: the one given, or the single leaf below `base`.
    fn tip(&self, base: &str, given: Option<&str>) -> Result<String, UrdfError> {
        match given {
            Some(t) if self.links.contains(t) => Ok(t.to_string()),
            Some(t) => {
                let mut all: Vec<&str> = self.links.iter().copied().collect();
                all.sort_unstable();
                Err(self.structure(format!(
                    "tip link `{t}` does not exist (leaves below `{base}`: {}; links: {})",
                    self.leaves(base).join(", "),
                    all.join(", ")
                )))
            }
            None => match self.leaves(base).as_slice() {
                [one] => Ok((*one).to_string()),
                many => Err(self.structure(format!(
                    "the tip is ambiguous: leaves below `{base}` are {}; choose one with --tip",
                    many.join(", ")
                ))),
            },
        }
    }

    /// The branches hanging from the links of `path` (the measured chain's joints): from each link on it
    /// (the base's too), each joint leading off the path starts one, followed down its tree (at a fork,
    /// into the child with the most moving joints below it, then the first by name) and cut before a
    /// mimic joint; folded like the measured chain along the path to it, so that its joints are in the
    /// same-orientation table's terms, and its links' `<inertial>` masses with them (as the chain's own;
    /// none when no link of it has one). A branch of no moving joint is none.
    fn branches(&self, path: &[&'r urdf_rs::Joint]) -> Vec<thermokin_chain::Branch> {
        let on_path: HashSet<&str> = path.iter().map(|j| j.child.link.as_str()).collect();
        let moving = |j: &urdf_rs::Joint| !matches!(j.joint_type, urdf_rs::JointType::Fixed);
        let mut out = Vec::new();
        for k in 0..=path.len() {
            let link = if k == 0 {
                path.first().map(|j| j.parent.link.as_str())
            } else {
                Some(path[k - 1].child.link.as_str())
            };
            let Some(link) = link else { continue };
            let mut leaving: Vec<&urdf_rs::Joint> = self
                .robot
                .joints
                .iter()
                .filter(|j| j.parent.link == link && !on_path.contains(j.child.link.as_str()))
                .collect();
            leaving.sort_by(|a, b| a.name.cmp(&b.name));
            for first in leaving {
                let mut along: Vec<&urdf_rs::Joint> = Vec::new();
                let mut next = Some(first);
                let modelled = |j: &&urdf_rs::Joint| {
                    j.mimic.is_none()
                        && matches!(
                            j.joint_type,
                            urdf_rs::JointType::Fixed
                                | urdf_rs::JointType::Revolute
                                | urdf_rs::JointType::Continuous
                                | urdf_rs::JointType::Prismatic
                        )
                };
                while let Some(j) = next.filter(modelled) {
                    along.push(j);
                    let mut below: Vec<&urdf_rs::Joint> =
                        self.robot.joints.iter().filter(|c| c.parent.link == j.child.link).collect();
                    below.sort_by(|a, b| self.moving_below(b).cmp(&self.moving_below(a)).then(a.name.cmp(&b.name)));
                    next = below.first().copied();
                }
                if !along.iter().any(|j| moving(j)) {
                    continue;
                }
                let shared = path[..k].iter().filter(|j| moving(j)).count();
                let full: Vec<&urdf_rs::Joint> = path[..k].iter().copied().chain(along).collect();
                // A side branch the model cannot read (a zero axis) leaves the measured chain as it was.
                let Ok(folded) = fold(self.robot, &full, &self.src) else { continue };
                let Ok(chain) = Chain::from_factors(&folded.factors, &folded.pending) else { continue };
                let Ok(masses) = link_masses(&folded, &chain) else { continue };
                let masses = &masses[shared.min(masses.len())..];
                out.push(thermokin_chain::Branch {
                    name: first.child.link.clone(),
                    link: shared,
                    joints: chain.joints()[shared..].to_vec(),
                    masses: if masses.iter().any(Option::is_some) { masses.to_vec() } else { Vec::new() },
                });
            }
        }
        out
    }

    /// How many moving joints the subtree below joint `j` holds, `j` included.
    fn moving_below(&self, j: &urdf_rs::Joint) -> usize {
        let own = usize::from(!matches!(j.joint_type, urdf_rs::JointType::Fixed));
        own + self
            .robot
            .joints
            .iter()
            .filter(|c| c.parent.link == j.child.link)
            .map(|c| self.moving_below(c))
            .sum::<usize>()
    }

    /// The joints from `base` to `tip`, in order.
    fn path(&self, base: &str, tip: &str) -> Result<Vec<&'r urdf_rs::Joint>, UrdfError> {
        let mut path = Vec::new();
        let mut at = tip;
        while at != base {
            let Some(j) = self.parent_joint.get(at) else {
                return Err(self.structure(format!("`{tip}` is not below `{base}`: no serial path between them")));
            };
            path.push(*j);
            at = j.parent.link.as_str();
        }
        path.reverse();
        Ok(path)
    }
}

/// A serial path folded into joint factors: each moving joint with the fixed transforms before it, its
/// Per joint of `chain` (folded as `folded`), the mass of the link it moves, its centre in the joint's
/// same-orientation frame: at the zero configuration every joint frame keeps the base's orientation, so
/// the centre is the accumulated world centre less the frame's origin there.
fn link_masses(folded: &Folded, chain: &Chain) -> Result<Vec<Option<LinkMass>>, ChainError> {
    let frames = chain.joint_frames(&vec![0.0; chain.dof()])?;
    Ok(folded
        .mass_acc
        .iter()
        .zip(&frames)
        .map(|((m, mc), f)| (*m > 0.0).then(|| LinkMass { mass_kg: *m, com_mm: mc / *m - f.translation.vector }))
        .collect())
}

/// ratings, the fixed transform after the last one, and the links' masses accumulated per joint.
struct Folded {
    factors: Vec<JointFactor>,
    ratings: Vec<JointRatings>,
    pending: Isometry3<f64>,
    /// Per joint: Σm and Σ m·c (centres in the world frame at the zero configuration).
    mass_acc: Vec<(f64, Vector3<f64>)>,
}

/// Folds `path`: fixed joints into the transforms beside the moving ones, each link's mass onto the joint
/// that moves it.
fn fold(robot: &urdf_rs::Robot, path: &[&urdf_rs::Joint], src: &str) -> Result<Folded, UrdfError> {
    let element = |name: &str, message: String| UrdfError::Element {
        source_name: src.to_string(),
        element: "joint",
        name: name.to_string(),
        message,
    };
    let inertial = |link: &str| -> Option<(f64, Isometry3<f64>)> {
        let l = robot.links.iter().find(|l| l.name == link)?;
        let m = l.inertial.mass.value;
        (m > 0.0 && m.is_finite()).then(|| (m, pose_mm(&l.inertial.origin)))
    };
    let mut out =
        Folded { factors: Vec::new(), ratings: Vec::new(), pending: Isometry3::identity(), mass_acc: Vec::new() };
    let mut world_at_zero = Isometry3::identity();
    for j in path {
        let origin = pose_mm(&j.origin);
        if j.mimic.is_some() {
            return Err(element(&j.name, "mimic joints are not supported in a serial chain".into()));
        }
        let kind = match j.joint_type {
            urdf_rs::JointType::Fixed => None,
            urdf_rs::JointType::Revolute | urdf_rs::JointType::Continuous => Some(JointKind::Revolute),
            urdf_rs::JointType::Prismatic => Some(JointKind::Prismatic),
            ref other => {
                return Err(element(
                    &j.name,
                    format!("joint type {other:?} is not supported (serial revolute/prismatic chains only)"),
                ));
            }
        };
        world_at_zero *= origin;
        out.pending *= origin;
        if let Some(kind) = kind {
            let (factor, rating) = moving_joint(j, kind, out.pending).map_err(|m| element(&j.name, m))?;
            out.factors.push(factor);
            out.ratings.push(rating);
            out.pending = Isometry3::identity();
            out.mass_acc.push((0.0, Vector3::zeros()));
        }
        if let (Some((m, com)), Some(acc)) = (inertial(&j.child.link), out.mass_acc.last_mut()) {
            let c = (world_at_zero * com).translation.vector;
            acc.0 += m;
            acc.1 += c * m;
        }
    }
    Ok(out)
}

/// A moving joint's factor (its axis, limits in mm and radians, the fixed transform `before` it) and its
/// ratings (velocity in mm/s or rad/s, effort).
fn moving_joint(
    j: &urdf_rs::Joint,
    kind: JointKind,
    before: Isometry3<f64>,
) -> Result<(JointFactor, JointRatings), String> {
    let axis = Vector3::from(j.axis.xyz.0);
    let n = axis.norm();
    if !(n.is_finite() && n > 1e-12) {
        return Err("the axis is zero or not finite".into());
    }
    let lim = &j.limit;
    let unit = if kind == JointKind::Prismatic { MM_PER_M } else { 1.0 };
    let limits = if j.joint_type == urdf_rs::JointType::Continuous {
        None
    } else if lim.lower.is_finite() && lim.upper.is_finite() && lim.lower < lim.upper {
        Some(JointLimits { lower: lim.lower * unit, upper: lim.upper * unit })
    } else {
        None
    };
    let positive = |v: f64| (v.is_finite() && v > 0.0).then_some(v);
    let rating = JointRatings { velocity: positive(lim.velocity).map(|v| v * unit), effort: positive(lim.effort) };
    let factor = JointFactor { before, axis: Unit::new_normalize(axis), kind, name: j.name.clone(), limits };
    Ok((factor, rating))
}

/// Refuses XML namespace use, which URDF does not have and the parser underneath mishandles (found by
/// fuzzing: RustyXML panics with "No namespace prefix bound"): namespaced element and attribute names,
/// malformed qualified names, default namespaces, reserved or empty-URI prefix declarations. Only
/// `xmlns:prefix="…"` declarations (xacro leftovers in real files) pass. Comments are skipped.
fn check_namespaces(text: &str) -> Result<(), String> {
    let mut stripped = String::with_capacity(text.len());
    let mut rest = text;
    while let Some(start) = rest.find("<!--") {
        stripped.push_str(&rest[..start]);
        rest = match rest[start..].find("-->") {
            Some(end) => &rest[start + end + 3..],
            None => "",
        };
    }
    stripped.push_str(rest);
    let is_name = |c: char| c.is_alphanumeric() || matches!(c, '_' | '-' | '.');
    let bytes = stripped.as_bytes();
    for (i, _) in stripped.match_indices(':') {
        // The qualified name around this colon.
        let before =
            stripped[..i].char_indices().rev().find(|&(_, c)| !is_name(c)).map_or(0, |(k, c)| k + c.len_utf8());
        let after = stripped[i + 1..].find(|c: char| !is_name(c)).map_or(stripped.len(), |k| i + 1 + k);
        let prefix = &stripped[before..i];
        let local = &stripped[i + 1..after];
        let opener = before.checked_sub(1).map(|k| bytes[k]);
        let next = bytes.get(after).copied();
        let in_name_position = matches!(opener, Some(b'<' | b'/' | b' ' | b'\t' | b'\n' | b'\r'));
        if in_name_position && (prefix.is_empty() || local.is_empty()) && (next == Some(b'=') || opener == Some(b'<')) {
            return Err(format!("malformed qualified name `{prefix}:{local}`"));
        }
        if prefix.is_empty() || local.is_empty() {
            continue;
        }
        let is_element =
            matches!(opener, Some(b'<')) || (matches!(opener, Some(b'/')) && before >= 2 && bytes[before - 2] == b'<');
        let is_attribute = matches!(opener, Some(b' ' | b'\t' | b'\n' | b'\r')) && next == Some(b'=');
        if prefix == "xmlns" && is_attribute {
            if local == "xmlns" || local == "xml" {
                return Err(format!("the reserved prefix `{local}` cannot be declared"));
            }
            let value = stripped[after + 1..].trim_start();
            if value.starts_with("\"\"") || value.starts_with("''") {
                return Err(format!("namespace prefix `{local}` is bound to an empty URI"));
            }
        } else if is_element || is_attribute {
            // URDF has no namespaced elements or attributes; only `xmlns:` declarations (xacro's) occur.
            return Err(format!("namespaced name `{prefix}:{local}` is not URDF"));
        }
    }
    // A default namespace (`xmlns="…"`) is not URDF either, and the parser underneath mishandles it.
    for (i, _) in stripped.match_indices("xmlns") {
        let opener = i.checked_sub(1).map(|k| bytes[k]);
        let after = stripped[i + 5..].trim_start();
        if matches!(opener, Some(b' ' | b'\t' | b'\n' | b'\r')) && after.starts_with('=') {
            return Err("a default XML namespace (xmlns=\"…\") is not URDF".into());
        }
    }
    Ok(())
}

/// Formats a number so that it parses back to the same `f64`.
fn num(v: f64) -> String {
    format!("{v:?}")
}

/// URDF roll, pitch, yaw of a rotation (`R = Rz(yaw) · Ry(pitch) · Rx(roll)`), rebuilding `R` to
/// rounding even at pitch = ±90°: yaw first, then pitch and roll from entries combined with it (the
/// `asin` in nalgebra's `euler_angles` loses half the digits there).
/// URDF roll, pitch, yaw of a rotation for export: yaw first, then pitch and roll from entries combined
/// with it, which rebuilds the rotation to ~1e-15 also at the ±90° pitches URDF files are full of. Not
/// `thermokin_io::units::ros_rpy_deg` (io sits above this crate), whose explicit singular branch is for
/// clean printing and rebuilds such frames only to ~1e-11 — measured by the export round trip of the
/// Kinova URDF.
fn rpy(q: &UnitQuaternion<f64>) -> (f64, f64, f64) {
    let m = q.to_rotation_matrix().into_inner();
    let yaw = m[(1, 0)].atan2(m[(0, 0)]);
    let (sy, cy) = yaw.sin_cos();
    let pitch = (-m[(2, 0)]).atan2(cy * m[(0, 0)] + sy * m[(1, 0)]);
    let roll = (sy * m[(0, 2)] - cy * m[(1, 2)]).atan2(cy * m[(1, 1)] - sy * m[(0, 1)]);
    (roll, pitch, yaw)
}

fn origin_xml(pose: &Isometry3<f64>) -> String {
    let t = pose.translation.vector.map(metres);
    let (r, p, y) = rpy(&pose.rotation);
    format!("<origin xyz=\"{} {} {}\" rpy=\"{} {} {}\"/>", num(t.x), num(t.y), num(t.z), num(r), num(p), num(y))
}

fn xml_escape(s: &str) -> String {
    s.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;").replace('"', "&quot;")
}

/// Exports a chain (nominal, deformed or identified) as URDF whose FK from `base_link` to `tool0` equals
/// the chain's: every joint's fixed row (error parameters and zero offset included) becomes its
/// `<origin>`, the tool row a fixed joint. Names and limits are kept (limits in radians and metres).
pub fn export_urdf(chain: &Chain, robot_name: &str) -> String {
    export_robot(&Robot::new(robot_name, chain.clone()))
}

/// `<limit velocity>` of a revolute joint whose speed is unknown, rad/s: 1 rad/s (57°/s), below the
/// rated speed of every industrial arm here, so that planners (MoveIt, ros2_control) get a usable, safe
/// value instead of 0 — which they read as "cannot move".
pub const DEFAULT_VELOCITY_RAD_S: f64 = 1.0;
/// The same for a prismatic joint, mm/s (written as 0.25 m/s).
pub const DEFAULT_VELOCITY_MM_S: f64 = 250.0;
/// `<limit effort>` when unknown: 100 (N·m or N). Planners need a positive value; dynamics users must
/// supply the real one.
pub const DEFAULT_EFFORT: f64 = 100.0;
/// Radius of the solid sphere whose inertia stands in for a link's, mm: the robot files give a mass and
/// a centre of mass only, and URDF needs a positive-definite tensor.
pub const INERTIA_SPHERE_RADIUS_MM: f64 = 50.0;

/// A URDF robot name: letters, digits, `_` and `-` (other characters become `_`).
pub fn urdf_name(name: &str) -> String {
    let s: String =
        name.chars().map(|c| if c.is_ascii_alphanumeric() || c == '_' || c == '-' { c } else { '_' }).collect();
    if s.is_empty() { "robot".into() } else { s }
}

/// As [`export_urdf`] for a whole robot: its name, its chain, `<inertial>` from the link masses (a solid
/// sphere of [`INERTIA_SPHERE_RADIUS_MM`] at the centre of mass) and `<limit velocity effort>` from the
/// ratings — unknown values take the documented defaults [`DEFAULT_VELOCITY_RAD_S`],
/// [`DEFAULT_VELOCITY_MM_S`], [`DEFAULT_EFFORT`].
pub fn export_robot(robot: &Robot) -> String {
    export_robot_noting(robot, &[])
}

/// As [`export_robot`], naming in a comment at the top, one line each, what the robot's own record holds
/// and URDF cannot (a calibrated robot's gear-ratio, cyclic and compliance terms, thermal drift): never
/// dropped in silence.
pub fn export_robot_noting(robot: &Robot, beyond_urdf: &[String]) -> String {
    let robot_name = robot.name();
    let (factors, tail) = robot.chain().to_factors();
    let mut s = String::new();
    s.push_str("<?xml version=\"1.0\"?>\n");
    s.push_str(&format!(
        "<!-- Generated by thermokin from \"{}\": the extended table, error parameters included. -->\n",
        xml_escape(&robot_name.replace("--", "-")),
    ));
    if !beyond_urdf.is_empty() {
        s.push_str("<!-- NOT IN THIS FILE (URDF cannot hold them; the robot TOML is the complete record):\n");
        for line in beyond_urdf {
            s.push_str(&format!("     - {}\n", xml_escape(&line.replace("--", "-"))));
        }
        s.push_str("-->\n");
    }
    s.push_str(&format!("<robot name=\"{}\">\n", urdf_name(robot_name)));
    s.push_str("  <link name=\"base_link\"/>\n");
    let mut parent = "base_link".to_string();
    for (i, f) in factors.iter().enumerate() {
        let child = format!("link_{}", i + 1);
        let kind = match (f.kind, f.limits) {
            (JointKind::Prismatic, _) => "prismatic",
            (JointKind::Revolute, Some(_)) => "revolute",
            (JointKind::Revolute, None) => "continuous",
        };
        match robot.masses()[i] {
            Some(m) if m.mass_kg > 0.0 => {
                let com = m.com_mm.map(metres);
                let r = metres(INERTIA_SPHERE_RADIUS_MM);
                let inertia = 0.4 * m.mass_kg * r * r;
                s.push_str(&format!(
                    "  <link name=\"{child}\">\n    <inertial>\n      <origin xyz=\"{} {} {}\" rpy=\"0 0 0\"/>\n      <mass value=\"{}\"/>\n      <inertia ixx=\"{i}\" ixy=\"0\" ixz=\"0\" iyy=\"{i}\" iyz=\"0\" izz=\"{i}\"/>\n    </inertial>\n  </link>\n",
                    num(com.x),
                    num(com.y),
                    num(com.z),
                    num(m.mass_kg),
                    i = num(inertia)
                ));
            }
            _ => s.push_str(&format!("  <link name=\"{child}\"/>\n")),
        }
        s.push_str(&format!("  <joint name=\"{}\" type=\"{kind}\">\n", xml_escape(&f.name)));
        s.push_str(&format!("    <parent link=\"{parent}\"/>\n    <child link=\"{child}\"/>\n"));
        s.push_str(&format!("    {}\n", origin_xml(&f.before)));
        let a = f.axis.into_inner();
        s.push_str(&format!("    <axis xyz=\"{} {} {}\"/>\n", num(a.x), num(a.y), num(a.z)));
        let prismatic = f.kind == JointKind::Prismatic;
        let scale = if prismatic { metres(1.0) } else { 1.0 };
        let rating = robot.ratings()[i];
        let velocity =
            rating.velocity.unwrap_or(if prismatic { DEFAULT_VELOCITY_MM_S } else { DEFAULT_VELOCITY_RAD_S });
        let effort = rating.effort.unwrap_or(DEFAULT_EFFORT);
        let (lower, upper) = match f.limits {
            Some(l) => (Some(l.lower * scale), Some(l.upper * scale)),
            None if prismatic => (Some(-1.0), Some(1.0)),
            None => (None, None),
        };
        match (lower, upper) {
            (Some(lo), Some(hi)) => s.push_str(&format!(
                "    <limit lower=\"{}\" upper=\"{}\" effort=\"{}\" velocity=\"{}\"/>\n",
                num(lo),
                num(hi),
                num(effort),
                num(velocity * scale)
            )),
            _ => {
                s.push_str(&format!("    <limit effort=\"{}\" velocity=\"{}\"/>\n", num(effort), num(velocity * scale)))
            }
        }
        s.push_str("  </joint>\n");
        parent = child;
    }
    s.push_str("  <link name=\"tool0\"/>\n");
    s.push_str(&format!(
        "  <joint name=\"tool0_joint\" type=\"fixed\">\n    <parent link=\"{parent}\"/>\n    <child link=\"tool0\"/>\n    {}\n  </joint>\n",
        origin_xml(&tail)
    ));
    s.push_str("</robot>\n");
    s
}
