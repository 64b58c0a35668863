//! A torso carrying two arms (issue #59's class): the robot's tree written here as plain joints, the
//! URDF a user would give (no masses) generated from it, and sessions measured at the right arm's tool
//! while the robot logs the left arm's joints — the truth's joint sag computed here from masses on every
//! link of the tree with rotations of its own, independently of any model's functions.

use nalgebra::{Rotation3, Unit, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use thermokin_chain::Dataset;

use crate::measured_point;

/// One joint of the tree: its name, its parent joint (index; `None`: the base), its origin in the
/// parent's frame (m), its axis, its limits (degrees) and the mass of the link it moves (kg, centre in
/// its frame, m), and its compliance (rad per N·m).
struct TreeJoint {
    name: &'static str,
    parent: Option<usize>,
    origin: [f64; 3],
    axis: [f64; 3],
    limits_deg: [f64; 2],
    mass: (f64, [f64; 3]),
    compliance: f64,
}

/// The tree: a torso (a vertical turn, a forward bend) and two five-joint arms from its chest, 250 mm
/// either side; the right arm's last joint carries the measured tool 100 mm out.
fn tree() -> Vec<TreeJoint> {
    let j = |name, parent, origin, axis, limits_deg, mass, compliance| TreeJoint {
        name,
        parent,
        origin,
        axis,
        limits_deg,
        mass,
        compliance,
    };
    let mut t = vec![
        j("torso_turn", None, [0.0, 0.0, 0.5], [0.0, 0.0, 1.0], [-90.0, 90.0], (6.0, [0.0, 0.0, 0.1]), 0.0),
        j("torso_bend", Some(0), [0.0, 0.0, 0.2], [0.0, 1.0, 0.0], [-20.0, 40.0], (15.0, [0.02, 0.0, 0.2]), 1.5e-4),
    ];
    for (side, y) in [("right", -1.0), ("left", 1.0)] {
        let names: [&'static str; 5] = if side == "right" {
            ["right_1", "right_2", "right_3", "right_4", "right_5"]
        } else {
            ["left_1", "left_2", "left_3", "left_4", "left_5"]
        };
        let first = t.len();
        let rows = [
            ([0.0, 0.25 * y, 0.35], [0.0, 1.0, 0.0], [-90.0, 90.0], (3.0, [0.0, 0.04 * y, 0.0]), 3e-5),
            ([0.0, 0.08 * y, 0.0], [1.0, 0.0, 0.0], [-60.0, 60.0], (2.5, [0.0, 0.0, -0.08]), 3e-5),
            ([0.0, 0.0, -0.15], [0.0, 0.0, 1.0], [-90.0, 90.0], (2.0, [0.0, 0.0, -0.07]), 2e-5),
            ([0.0, 0.0, -0.15], [0.0, 1.0, 0.0], [-120.0, 0.0], (1.5, [0.0, 0.0, -0.14]), 3e-5),
            ([0.0, 0.0, -0.28], [0.0, 0.0, 1.0], [-90.0, 90.0], (1.0, [0.0, 0.0, -0.05]), 2e-5),
        ];
        for (k, (origin, axis, limits, mass, c)) in rows.into_iter().enumerate() {
            let parent = if k == 0 { Some(1) } else { Some(first + k - 1) };
            t.push(j(names[k], parent, origin, axis, limits, mass, c));
        }
    }
    t
}

/// Indices of the measured chain (the torso, then the right arm) and of the logged branch (the left arm).
const MEASURED: [usize; 7] = [0, 1, 2, 3, 4, 5, 6];
const LOGGED: [usize; 5] = [7, 8, 9, 10, 11];
/// The tool point in the right arm's last link (m).
const TOOL: [f64; 3] = [0.0, 0.0, -0.1];

/// The URDF of the tree as a user gives it: geometry and limits, no masses; the right arm ends in the
/// link `right_tool`, the left in `left_hand`. With `left_arm` false, the left arm is left out (a robot
/// file of the measured chain alone).
pub fn two_armed_torso_urdf(left_arm: bool) -> String {
    torso_urdf(left_arm, Inertials::None)
}

/// [`two_armed_torso_urdf`] with every link's `<inertial>`: the masses and centres the sessions' truth
/// sags under (a small sphere's inertia beside them, which no static load reads).
pub fn two_armed_torso_urdf_with_masses(left_arm: bool) -> String {
    torso_urdf(left_arm, Inertials::TheTruths)
}

/// Which `<inertial>` elements the URDF writes.
#[derive(Clone, Copy, PartialEq)]
enum Inertials {
    None,
    TheTruths,
}

fn torso_urdf(left_arm: bool, inertials: Inertials) -> String {
    let t = tree();
    let link = |i: Option<usize>| i.map_or("base".to_string(), |i| format!("{}_link", t[i].name));
    let mut s = String::from("<robot name=\"two_armed_torso\">\n  <link name=\"base\"/>\n");
    for (i, j) in t.iter().enumerate().filter(|(i, _)| left_arm || !LOGGED.contains(i)) {
        if inertials == Inertials::TheTruths {
            let (m, c) = j.mass;
            s.push_str(&format!(
                "  <link name=\"{}\"><inertial><origin xyz=\"{} {} {}\"/><mass value=\"{m}\"/><inertia ixx=\"0.01\" ixy=\"0\" ixz=\"0\" iyy=\"0.01\" iyz=\"0\" izz=\"0.01\"/></inertial></link>\n",
                link(Some(i)),
                c[0],
                c[1],
                c[2]
            ));
        } else {
            s.push_str(&format!("  <link name=\"{}\"/>\n", link(Some(i))));
        }
        s.push_str(&format!(
            "  <joint name=\"{n}\" type=\"revolute\"><parent link=\"{p}\"/><child link=\"{child}\"/><origin xyz=\"{} {} {}\"/><axis xyz=\"{} {} {}\"/><limit lower=\"{}\" upper=\"{}\" effort=\"100\" velocity=\"1\"/></joint>\n",
            j.origin[0],
            j.origin[1],
            j.origin[2],
            j.axis[0],
            j.axis[1],
            j.axis[2],
            j.limits_deg[0].to_radians(),
            j.limits_deg[1].to_radians(),
            n = j.name,
            p = link(j.parent),
            child = link(Some(i)),
        ));
    }
    s.push_str(&format!(
        "  <link name=\"right_tool\"/>\n  <joint name=\"right_tool_fixed\" type=\"fixed\"><parent link=\"right_5_link\"/><child link=\"right_tool\"/><origin xyz=\"{} {} {}\"/></joint>\n",
        TOOL[0], TOOL[1], TOOL[2]
    ));
    if left_arm {
        s.push_str("  <link name=\"left_hand\"/>\n  <joint name=\"left_hand_fixed\" type=\"fixed\"><parent link=\"left_5_link\"/><child link=\"left_hand\"/><origin xyz=\"0 0 -0.1\"/></joint>\n");
    }
    s.push_str("</robot>\n");
    s
}

/// Each joint's world rotation and origin (m) at joint values `q` (radians, one per tree joint).
fn frames(t: &[TreeJoint], q: &[f64]) -> Vec<(Rotation3<f64>, Vector3<f64>)> {
    let mut out: Vec<(Rotation3<f64>, Vector3<f64>)> = Vec::with_capacity(t.len());
    for (i, j) in t.iter().enumerate() {
        let (r0, p0) = j.parent.map_or((Rotation3::identity(), Vector3::zeros()), |p| out[p]);
        let origin = p0 + r0 * Vector3::from(j.origin);
        let turn = Rotation3::from_axis_angle(&Unit::new_normalize(Vector3::from(j.axis)), q[i]);
        out.push((r0 * turn, origin));
    }
    out
}

/// Whether joint `a` carries joint `l` (is `l` or one of its ancestors).
fn carries(t: &[TreeJoint], a: usize, l: usize) -> bool {
    let mut at = Some(l);
    while let Some(i) = at {
        if i == a {
            return true;
        }
        at = t[i].parent;
    }
    false
}

/// `n` poses of the two-armed torso, measured at the right arm's tool (mm) with `noise_mm` per axis: every
/// joint of the tree drawn inside its limits, each measured joint sagging by its compliance times the
/// gravity torque about it of every link it carries (the left arm's too, when the torso's joints carry
/// it); the left arm's five joints logged as columns `left_1` … `left_5` in degrees. No time column.
pub fn two_armed_torso_session(n: usize, seed: u64, noise_mm: f64) -> Dataset {
    elastic_torso_session(n, seed, noise_mm, Elastic { joints: 1.0, torso_bearing: 0.0 })
}

/// How elastic the two-armed torso is: its joints' compliances scaled by `joints`, and the torso's turning
/// bearing tilting under the gravity moment across its axis of everything it carries (rad per N·m).
#[derive(Clone, Copy, Debug)]
pub struct Elastic {
    /// The factor on every joint's compliance.
    pub joints: f64,
    /// The torso bearing's lateral compliance, rad per N·m.
    pub torso_bearing: f64,
}

/// [`two_armed_torso_session`] of a torso `elastic` as given: the sag of every joint scaled, and the
/// torso's bearing tilting everything above it about the bearing's centre by its compliance times the
/// horizontal gravity moment of every link of the tree (both arms) about that centre.
pub fn elastic_torso_session(n: usize, seed: u64, noise_mm: f64, elastic: Elastic) -> Dataset {
    let t = tree();
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let g = Vector3::new(0.0, 0.0, -9.80665);
    let mut data =
        Dataset { sensor_names: LOGGED.iter().map(|&i| t[i].name.to_string()).collect(), ..Dataset::default() };
    for _ in 0..n {
        let q: Vec<f64> = t
            .iter()
            .map(|j| {
                let (lo, hi) = (j.limits_deg[0].to_radians(), j.limits_deg[1].to_radians());
                let m = 0.1 * (hi - lo);
                rng.random_range(lo + m..hi - m)
            })
            .collect();
        let at = frames(&t, &q);
        let mut sagged = q.clone();
        for &a in &MEASURED {
            let (ra, oa) = at[a];
            let axis = ra * Vector3::from(t[a].axis).normalize();
            let torque: f64 = (0..t.len())
                .filter(|&l| carries(&t, a, l))
                .map(|l| {
                    let (rl, ol) = at[l];
                    let centre = ol + rl * Vector3::from(t[l].mass.1);
                    axis.dot(&(centre - oa).cross(&(g * t[l].mass.0)))
                })
                .sum();
            sagged[a] += elastic.joints * t[a].compliance * torque;
        }
        let seen = frames(&t, &sagged);
        let (r, p) = seen[MEASURED[6]];
        let mut tool = p + r * Vector3::from(TOOL);
        if elastic.torso_bearing != 0.0 {
            let centre = seen[0].1;
            let moment: Vector3<f64> = (0..t.len())
                .map(|l| {
                    let (rl, ol) = seen[l];
                    (ol + rl * Vector3::from(t[l].mass.1) - centre).cross(&(g * t[l].mass.0))
                })
                .sum();
            let tilt = Rotation3::from_scaled_axis(Vector3::new(moment.x, moment.y, 0.0) * elastic.torso_bearing);
            tool = centre + tilt * (tool - centre);
        }
        let tool_mm = tool * 1000.0;
        let measured_q: Vec<f64> = MEASURED.iter().map(|&i| q[i]).collect();
        data.measurements.push(measured_point(measured_q, tool_mm, noise_mm, &mut rng));
        data.sensor_values.push(LOGGED.iter().map(|&i| q[i].to_degrees()).collect());
    }
    data
}
