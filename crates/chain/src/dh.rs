//! Classic Denavit–Hartenberg (section 2.2.1, eq. 9–12) and Craig's modified DH (section 2.2.2, eq. 13)
//! tables, their own forward kinematics, and exact conversions to and from the extended table.
//!
//! The paper's printed matrices carry slips (eq. 12 and eq. 14 print the same matrix, with `cos θ` where
//! the (3,3) entry should be `cos α`); both conventions are implemented from their definitions:
//! - classic: `A_i = Rz(θ_i) · Tz(d_i) · Tx(a_i) · Rx(α_i)`, the joint turning about `z_{i−1}`;
//! - modified: `A_i = Rx(α_{i−1}) · Tx(a_{i−1}) · Rz(θ_i) · Tz(d_i)`, the joint turning about `z_i`.

use nalgebra::{Isometry3, Matrix3, Translation3, UnitQuaternion, Vector3};

use crate::ChainError;
use crate::chain::{Chain, JointKind, JointLimits};
use crate::factors::JointFactor;

/// One row of a DH or modified-DH table. Lengths in mm, angles in radians.
///
/// In a classic table the row reads `(a_i, α_i, d_i, θ_i)`; in a modified table `(a_{i−1}, α_{i−1}, d_i,
/// θ_i)`, as printed in Table 1. `theta` (revolute) or `d` (prismatic) is the offset added to the joint
/// variable.
#[derive(Clone, Debug, PartialEq)]
pub struct DhRow {
    /// Joint name.
    pub name: String,
    /// Link length `a` (mm).
    pub a: f64,
    /// Link twist `α` (rad).
    pub alpha: f64,
    /// Link offset `d` (mm).
    pub d: f64,
    /// Joint angle offset `θ` (rad).
    pub theta: f64,
    /// Revolute (variable added to θ) or prismatic (variable added to d).
    pub kind: JointKind,
    /// Limits of the joint variable.
    pub limits: Option<JointLimits>,
}

impl DhRow {
    /// A revolute row.
    pub fn revolute(name: impl Into<String>, a: f64, alpha: f64, d: f64, theta: f64) -> Self {
        Self { name: name.into(), a, alpha, d, theta, kind: JointKind::Revolute, limits: None }
    }
}

/// Which of the two DH conventions a [`DhTable`] follows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DhConvention {
    /// Classic DH (eq. 9–12).
    Classic,
    /// Craig's modified DH (eq. 13).
    Modified,
}

/// A DH or modified-DH table with the base and tool transforms it needs to describe a real robot.
#[derive(Clone, Debug, PartialEq)]
pub struct DhTable {
    /// Classic or modified.
    pub convention: DhConvention,
    /// Rows, one per joint.
    pub rows: Vec<DhRow>,
    /// `world_from_frame0`.
    pub base: Isometry3<f64>,
    /// `frame_n_from_tcp`.
    pub tool: Isometry3<f64>,
}

fn rx(a: f64) -> Isometry3<f64> {
    Isometry3::rotation(Vector3::x() * a)
}
fn rz(a: f64) -> Isometry3<f64> {
    Isometry3::rotation(Vector3::z() * a)
}
fn tx(v: f64) -> Isometry3<f64> {
    Isometry3::translation(v, 0.0, 0.0)
}
fn tz(v: f64) -> Isometry3<f64> {
    Isometry3::translation(0.0, 0.0, v)
}

impl DhTable {
    /// Number of joints.
    pub fn dof(&self) -> usize {
        self.rows.len()
    }

    /// The link transform `A_i(q)` of row `i`.
    pub fn link_transform(&self, i: usize, q: f64) -> Isometry3<f64> {
        let r = &self.rows[i];
        let (theta, d) = match r.kind {
            JointKind::Revolute => (r.theta + q, r.d),
            JointKind::Prismatic => (r.theta, r.d + q),
        };
        match self.convention {
            DhConvention::Classic => rz(theta) * tz(d) * tx(r.a) * rx(r.alpha),
            DhConvention::Modified => rx(r.alpha) * tx(r.a) * rz(theta) * tz(d),
        }
    }

    /// Forward kinematics straight from the table (independent of [`Chain`]): `world_from_tcp`.
    pub fn tool_pose(&self, q: &[f64]) -> Result<Isometry3<f64>, ChainError> {
        if q.len() != self.dof() {
            return Err(ChainError::WrongJointCount { expected: self.dof(), got: q.len() });
        }
        let mut t = self.base;
        for (i, &qi) in q.iter().enumerate() {
            t *= self.link_transform(i, qi);
        }
        Ok(t * self.tool)
    }

    /// The table as fixed factors and unit joint motions about local Z.
    fn factors(&self) -> (Vec<JointFactor>, Isometry3<f64>) {
        let mut out = Vec::with_capacity(self.dof());
        let mut pending = self.base;
        for r in &self.rows {
            let (before, after) = match (self.convention, r.kind) {
                (DhConvention::Classic, JointKind::Revolute) => (rz(r.theta), tz(r.d) * tx(r.a) * rx(r.alpha)),
                (DhConvention::Classic, JointKind::Prismatic) => (rz(r.theta) * tz(r.d), tx(r.a) * rx(r.alpha)),
                (DhConvention::Modified, JointKind::Revolute) => (rx(r.alpha) * tx(r.a) * rz(r.theta), tz(r.d)),
                (DhConvention::Modified, JointKind::Prismatic) => {
                    (rx(r.alpha) * tx(r.a) * rz(r.theta) * tz(r.d), Isometry3::identity())
                }
            };
            out.push(JointFactor {
                before: pending * before,
                axis: Vector3::z_axis(),
                kind: r.kind,
                name: r.name.clone(),
                limits: r.limits,
            });
            pending = after;
        }
        (out, pending * self.tool)
    }

    /// The exact same-orientation extended table of this robot (see [`Chain::from_factors`]).
    pub fn to_extended(&self) -> Result<Chain, ChainError> {
        let (factors, tail) = self.factors();
        Chain::from_factors(&factors, &tail)
    }
}

/// A line in space: a point and a unit direction.
#[derive(Clone, Copy, Debug)]
struct Line {
    point: Vector3<f64>,
    dir: Vector3<f64>,
}

/// Closest points of two lines: `(s, t)` with `a.point + s a.dir` and `b.point + t b.dir`, or `None` when
/// the lines are parallel.
fn closest_params(a: &Line, b: &Line) -> Option<(f64, f64)> {
    let w = a.point - b.point;
    let bb = a.dir.dot(&b.dir);
    let denom = 1.0 - bb * bb;
    if denom < 1e-12 {
        return None;
    }
    let d = a.dir.dot(&w);
    let e = b.dir.dot(&w);
    Some(((bb * e - d) / denom, (e - bb * d) / denom))
}

/// Geometric tolerance for deciding that a line meets another or is perpendicular to it: 1e-9 mm and
/// 1e-12 rad, well under the 1e-9 mm the conversions promise.
const LINE_TOL: f64 = 1e-9;

impl Chain {
    /// The joint axes at the zero configuration as world lines `(point, direction)`, and the TCP pose.
    fn axis_lines(&self) -> (Vec<Line>, Isometry3<f64>) {
        let zeros = vec![0.0; self.dof()];
        // The frames after each joint's motion at q = 0; the joint turns about the line through the frame
        // origin along its axis, which the joint's own motion does not move.
        let frames = self.joint_frames(&zeros).unwrap_or_default();
        let lines = self
            .joints()
            .iter()
            .zip(&frames)
            .map(|(j, f)| Line { point: f.translation.vector, dir: f.rotation * j.axis.into_inner() })
            .collect();
        (lines, frames.last().copied().unwrap_or_else(Isometry3::identity))
    }

    /// The exact Craig modified-DH table of this chain with the base frame fixed to the chain's base
    /// (identity `base` transform) and the remainder in the tool transform.
    ///
    /// Frame `i` has `z_i` along joint `i`'s axis and `x_i` along the common normal to the next axis. The
    /// base frame is fixed, so joint 1's axis must be reachable by `Rx(α_0) · Tx(a_0)`: perpendicular to the
    /// base X axis and meeting the base X line. When it is not (a tilted or sideways-offset first axis, a
    /// non-perpendicular offset), no modified-DH table without a base transform exists and the error says
    /// which condition fails.
    pub fn to_modified_dh(&self) -> Result<DhTable, ChainError> {
        let (lines, world_from_tcp) = self.axis_lines();
        let n = lines.len();
        // Frame 0 is the base itself.
        let mut frames: Vec<Isometry3<f64>> = vec![Isometry3::identity()];
        for i in 0..n {
            let prev = frames[i];
            let x_prev = prev.rotation * Vector3::x();
            let line = lines[i];
            if i == 0 {
                // z_1 must be perpendicular to x_0, and the line must meet the x_0 line.
                let tilt = x_prev.dot(&line.dir);
                if tilt.abs() > LINE_TOL {
                    return Err(ChainError::NoModifiedDh {
                        joint: 1,
                        reason: format!("the axis is not perpendicular to the base X axis (cos = {tilt:.3e})"),
                    });
                }
            }
            // P: where the x_{i−1} line meets line i.
            let x_line = Line { point: prev.translation.vector, dir: x_prev };
            let p = match closest_params(&x_line, &line) {
                Some((s, t)) => {
                    let on_x = x_line.point + x_line.dir * s;
                    let on_axis = line.point + line.dir * t;
                    let gap = (on_x - on_axis).norm();
                    if gap > LINE_TOL {
                        return Err(ChainError::NoModifiedDh {
                            joint: i + 1,
                            reason: format!("the axis misses the previous X line by {gap:.3e} mm"),
                        });
                    }
                    on_axis
                }
                None => {
                    return Err(ChainError::NoModifiedDh {
                        joint: i + 1,
                        reason: "the axis is parallel to the previous X axis".into(),
                    });
                }
            };
            // x_i: the common normal from line i to line i+1 (or, for the last joint, x_{i−1} made
            // perpendicular to z_i); origin O_i: its foot on line i.
            let (origin, x_dir) = if i + 1 < n {
                common_normal(&line, &lines[i + 1], p, x_prev)
            } else {
                (p, perpendicular_part(x_prev, line.dir))
            };
            let z = line.dir;
            let y = z.cross(&x_dir);
            let rot = Matrix3::from_columns(&[x_dir, y, z]);
            let rotation = UnitQuaternion::from_matrix(&rot);
            frames.push(Isometry3::from_parts(Translation3::from(origin), rotation));
        }
        let mut rows = Vec::with_capacity(n);
        for (i, joint) in self.joints().iter().enumerate() {
            let rel = frames[i].inverse() * frames[i + 1];
            let z_in_prev = rel.rotation * Vector3::z();
            let alpha = (-z_in_prev.y).atan2(z_in_prev.z);
            let a = rel.translation.vector.x;
            let rest = (rx(alpha) * tx(a)).inverse() * rel;
            let x_in = rest.rotation * Vector3::x();
            let theta = x_in.y.atan2(x_in.x);
            let d = rest.translation.vector.z;
            let rebuilt = rz(theta) * tz(d);
            // A rotation residual counts as the displacement it causes a metre away (a lever, not a unit).
            const LEVER_MM: f64 = 1000.0;
            let residual = (rebuilt.inverse() * rest).translation.vector.norm()
                + LEVER_MM * (rebuilt.rotation.inverse() * rest.rotation).angle();
            if residual > LINE_TOL {
                return Err(ChainError::NoModifiedDh {
                    joint: i + 1,
                    reason: format!("the frames do not decompose (residual {residual:.3e})"),
                });
            }
            // Joint variable zero = the chain's zero configuration, so θ (or d) carries the geometry at
            // q = 0 and the joint's own zero offset is already inside it.
            rows.push(DhRow { name: joint.name.clone(), a, alpha, d, theta, kind: joint.kind, limits: joint.limits });
        }
        let tool = frames[n].inverse() * world_from_tcp;
        Ok(DhTable { convention: DhConvention::Modified, rows, base: Isometry3::identity(), tool })
    }
}

/// The component of `v` perpendicular to the unit vector `n`, normalised (falls back to any
/// perpendicular when `v` is parallel to `n`).
fn perpendicular_part(v: Vector3<f64>, n: Vector3<f64>) -> Vector3<f64> {
    let w = v - n * n.dot(&v);
    if w.norm() > 1e-12 {
        w.normalize()
    } else {
        let trial = if n.x.abs() < 0.9 { Vector3::x() } else { Vector3::y() };
        (trial - n * n.dot(&trial)).normalize()
    }
}

/// Origin and x direction of frame i from its axis line and the next one. `p` is where the previous X
/// line meets line i (used when the common normal is not unique) and `x_prev` the previous x axis.
fn common_normal(line: &Line, next: &Line, p: Vector3<f64>, x_prev: Vector3<f64>) -> (Vector3<f64>, Vector3<f64>) {
    match closest_params(line, next) {
        Some((s, t)) => {
            let foot = line.point + line.dir * s;
            let other = next.point + next.dir * t;
            let gap = other - foot;
            let x = if gap.norm() > LINE_TOL {
                gap.normalize()
            } else {
                // Intersecting axes: x along z_i × z_{i+1}.
                line.dir.cross(&next.dir).normalize()
            };
            (foot, x)
        }
        None => {
            // Parallel axes: any foot works; take p so that d_i = 0.
            let w = next.point - p;
            let w = w - line.dir * line.dir.dot(&w);
            let x = if w.norm() > LINE_TOL { w.normalize() } else { perpendicular_part(x_prev, line.dir) };
            (p, x)
        }
    }
}
