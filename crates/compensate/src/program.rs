//! Robot programs of the compensated joints, for the controller to run as they are: ABB RAPID
//! (`MoveAbsJ` to `jointtarget`s), KUKA KRL (`PTP` to `E6AXIS`) and Universal Robots URScript (`movej`).
//! This is the post-processing the paper's conclusion (a) says is manual today.
//!
//! Joint targets by default: a Cartesian target is solved again by the controller on its *nominal* model.
//! ABB `robtarget`s are offered for users whose programs must stay Cartesian: each is the pose the
//! *nominal* robot reaches with the compensated joints (so the controller's own IK lands on them), with
//! the configuration data that pins that branch. A transient run gives one program per model update (one
//! block of the program per minute in the paper's cycle), each loading the joints valid for that time,
//! instead of one module with every target of every minute. Targets that were not reached become
//! comments, never motions.

use thermokin_chain::{Chain, JointKind, quaternion_wxyz};

use crate::run::{RunOutput, TargetResult};

/// Which controller language.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum Controller {
    /// ABB RAPID: a module with `CONST jointtarget`s and `MoveAbsJ`.
    Abb,
    /// KUKA KRL: a `.src` with `E6AXIS` aggregates and `PTP`.
    Kuka,
    /// Universal Robots URScript: `movej` with joint vectors in radians.
    UniversalRobots,
}

thermokin_chain::choices!(
    Controller,
    "controller",
    [
        ("abb", "ABB RAPID (.mod: MoveAbsJ to jointtargets)", Controller::Abb),
        ("kuka", "KUKA KRL (.src: PTP to E6AXIS)", Controller::Kuka),
        ("ur", "Universal Robots URScript (.script: movej)", Controller::UniversalRobots),
    ]
);

impl Controller {
    /// The file extensions [`Controller::from_extension`] knows, in words.
    pub const EXTENSIONS: &'static str = ".mod or .modx (ABB RAPID), .src (KUKA KRL), .script or .urscript (URScript)";

    /// The controller whose programs use this file extension (any case): `.mod` or `.modx` for ABB,
    /// `.src` for KUKA, `.script` or `.urscript` for Universal Robots. `.prg` is none of them: an ABB S4
    /// program, and other makers' too — the controller must then be said.
    pub fn from_extension(extension: &str) -> Option<Self> {
        match extension.to_ascii_lowercase().as_str() {
            "mod" | "modx" => Some(Controller::Abb),
            "src" => Some(Controller::Kuka),
            "script" | "urscript" => Some(Controller::UniversalRobots),
            _ => None,
        }
    }

    /// The controller of a program written to `path`: `given` when there is one, else the one its
    /// extension names ([`Controller::from_extension`]).
    ///
    /// ```
    /// use thermokin_compensate::Controller;
    /// let path = std::path::Path::new("warmup.SRC");
    /// assert_eq!(Controller::for_file(path, None).unwrap(), Controller::Kuka);
    /// assert!(Controller::for_file(std::path::Path::new("x.prg"), None).is_err());
    /// ```
    pub fn for_file(path: &std::path::Path, given: Option<Self>) -> Result<Self, ProgramError> {
        let by_extension = path.extension().and_then(|e| e.to_str()).and_then(Controller::from_extension);
        given.or(by_extension).ok_or_else(|| ProgramError::UnknownExtension { path: path.display().to_string() })
    }

    /// The file extension programs of this controller use.
    pub fn extension(self) -> &'static str {
        match self {
            Controller::Abb => "mod",
            Controller::Kuka => "src",
            Controller::UniversalRobots => "script",
        }
    }
}

/// What an ABB program moves to.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum AbbTargets {
    /// `MoveAbsJ` to `jointtarget`s: the compensated joints themselves.
    #[default]
    Joint,
    /// `MoveJ` to `robtarget`s: FK of the compensated joints on the nominal robot, with `confdata`.
    Robtarget,
}

/// Settings of a program, each in the controller's own terms.
#[derive(Clone, Debug, PartialEq)]
pub struct ProgramSettings {
    /// The language.
    pub controller: Controller,
    /// Program (module, procedure) name; made a valid identifier.
    pub name: String,
    /// ABB `speeddata` (`v100`); KUKA axis velocity in % (`30`); UR joint speed in rad/s (`1.05`).
    pub speed: String,
    /// ABB `zonedata` (`fine`, `z10`); KUKA: `fine` or an approximation (`C_PTP`); UR blend radius in m
    /// (`0` stops at each target).
    pub zone: String,
    /// ABB `tooldata` (`tool0`); unused by the others (joint motions).
    pub tool: String,
    /// ABB: joint targets or robtargets.
    pub abb_targets: AbbTargets,
}

impl ProgramSettings {
    /// Conservative defaults for a controller: slow, stopping at every target.
    pub fn new(controller: Controller) -> Self {
        let (speed, zone) = match controller {
            Controller::Abb => ("v100", "fine"),
            Controller::Kuka => ("30", "fine"),
            Controller::UniversalRobots => ("1.05", "0"),
        };
        Self {
            controller,
            name: "thermokin_compensated".into(),
            speed: speed.into(),
            zone: zone.into(),
            tool: "tool0".into(),
            abb_targets: AbbTargets::Joint,
        }
    }
}

/// One program of a run: `suffix` is empty for a static run, `_t<minutes>` for each time of a transient
/// one (to append to the file stem).
#[derive(Clone, Debug, PartialEq)]
pub struct Program {
    /// File-name suffix.
    pub suffix: String,
    /// The program text.
    pub text: String,
}

/// An identifier from free text: letters, digits and `_`, starting with a letter, at most `max` chars.
fn identifier(text: &str, max: usize) -> String {
    let mut s: String = text.chars().map(|c| if c.is_ascii_alphanumeric() { c } else { '_' }).collect();
    if !s.starts_with(|c: char| c.is_ascii_alphabetic()) {
        s.insert(0, 'p');
    }
    s.truncate(max);
    s
}

/// Minutes as a file and identifier fragment: `12`, `12p5` for 12.5.
fn minutes(t: f64) -> String {
    let text = format!("{}", (t * 1e6).round() / 1e6);
    text.replace('.', "p").replace('-', "m")
}

/// Why a program cannot be written.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum ProgramError {
    /// ABB robtargets need a six-joint arm whose last three axes meet in one point (a spherical wrist):
    /// that is what `confdata`'s definition assumes.
    #[error("robtargets need a six-joint robot with a spherical wrist (joint axes 4, 5, 6 meeting at one point)")]
    NotSphericalWrist,
    /// A program file whose extension names no controller, and no controller given.
    #[error("{path}: unknown program type; name it {known}", known = Controller::EXTENSIONS)]
    UnknownExtension {
        /// The file as given.
        path: String,
    },
}

/// The program files of a run written to `path` — one, or one per time step of a transient run, named
/// `<stem><suffix>.<extension>` beside it — with `settings`, its name the file's stem.
pub fn program_files(
    path: &std::path::Path,
    run: &RunOutput,
    nominal: &Chain,
    settings: &ProgramSettings,
) -> Result<Vec<(std::path::PathBuf, String)>, ProgramError> {
    let stem = path.file_stem().and_then(|s| s.to_str()).unwrap_or("program");
    let ext = path.extension().and_then(|e| e.to_str()).unwrap_or(settings.controller.extension());
    let named = ProgramSettings { name: stem.to_string(), ..settings.clone() };
    Ok(programs(run, nominal, &named)?
        .into_iter()
        .map(|p| (path.with_file_name(format!("{stem}{}.{ext}", p.suffix)), p.text))
        .collect())
}

/// The programs of a run: one for a static run, one per time step for a transient one. `nominal` is the
/// robot as the controller knows it (for ABB robtargets; the joint programs do not use it).
pub fn programs(run: &RunOutput, nominal: &Chain, settings: &ProgramSettings) -> Result<Vec<Program>, ProgramError> {
    if settings.controller == Controller::Abb && settings.abb_targets == AbbTargets::Robtarget {
        check_spherical_wrist(nominal)?;
    }
    let transient = run.rows.iter().any(|r| r.time_min != 0.0);
    let mut blocks: Vec<(f64, Vec<&TargetResult>)> = Vec::new();
    for r in &run.rows {
        match blocks.last_mut() {
            Some((t, rows)) if *t == r.time_min => rows.push(r),
            _ => blocks.push((r.time_min, vec![r])),
        }
    }
    let out = blocks
        .into_iter()
        .map(|(t, rows)| {
            let suffix = if transient { format!("_t{}", minutes(t)) } else { String::new() };
            let name = format!("{}{}", settings.name, suffix);
            let header = format!(
                "thermokin: joints compensated on the deformed model{}; {} targets, {} not reached (comments)",
                if transient { format!(" valid at {t} min") } else { String::new() },
                rows.len(),
                rows.iter().filter(|r| !r.converged()).count()
            );
            let motions: Vec<Motion<'_>> = rows.iter().map(|r| Motion::of(r)).collect();
            let text = program_text(&name, &header, &motions, nominal, settings);
            Program { suffix, text }
        })
        .collect::<Vec<_>>();
    Ok(out)
}

/// One motion of a program: its label, and the joint values to move to (radians, mm for a prismatic
/// joint) — or why there are none, written as a comment in place of the motion.
#[derive(Clone, Debug, PartialEq)]
pub struct Motion<'a> {
    /// The target's label (made part of an identifier).
    pub label: &'a str,
    /// The joints, or the reason the motion is skipped.
    pub joints: Result<&'a [f64], String>,
}

impl<'a> Motion<'a> {
    /// A compensated target: its joints when the IK reached it, skipped with its status otherwise.
    fn of(r: &'a TargetResult) -> Self {
        let joints = if r.converged() { Ok(r.joints.as_slice()) } else { Err(format!("not reached ({:?})", r.status)) };
        Self { label: &r.label, joints }
    }
}

/// A program that visits `motions` in order (joint motions; ABB robtargets as in [`programs`]), named
/// `settings.name`, with `header` as its first comment: the program of any list of joint values — the
/// poses a measurement plan asks for, as well as a compensation's.
pub fn motion_program(
    header: &str,
    motions: &[Motion<'_>],
    nominal: &Chain,
    settings: &ProgramSettings,
) -> Result<String, ProgramError> {
    if settings.controller == Controller::Abb && settings.abb_targets == AbbTargets::Robtarget {
        check_spherical_wrist(nominal)?;
    }
    Ok(program_text(&settings.name, header, motions, nominal, settings))
}

/// A program for `controller` that visits `poses` (joint values, radians and mm) in order, each labelled
/// `pose_<k>` from 1, named after `path`'s stem, with `header` as its first comment: a measurement plan
/// as the robot runs it.
pub fn poses_program(
    path: &std::path::Path,
    header: &str,
    poses: &[&[f64]],
    nominal: &Chain,
    controller: Controller,
) -> Result<String, ProgramError> {
    let labels: Vec<String> = (1..=poses.len()).map(|k| format!("pose_{k}")).collect();
    let motions: Vec<Motion<'_>> =
        poses.iter().zip(&labels).map(|(q, label)| Motion { label, joints: Ok(q) }).collect();
    let name = path.file_stem().and_then(|s| s.to_str()).unwrap_or("plan").to_string();
    motion_program(header, &motions, nominal, &ProgramSettings { name, ..ProgramSettings::new(controller) })
}

/// The text of one program in the controller's language.
fn program_text(name: &str, header: &str, motions: &[Motion<'_>], nominal: &Chain, s: &ProgramSettings) -> String {
    match s.controller {
        Controller::Abb => abb(name, header, motions, nominal, s),
        Controller::Kuka => kuka(name, header, motions, nominal, s),
        Controller::UniversalRobots => ur(name, header, motions, nominal, s),
    }
}

/// Joint values written with 6 decimals: 1e-6° is below every controller's resolution (ABB and KUKA
/// store 1e-4° or coarser), and ~2e-8 rad for UR.
fn axes(values: &[f64], decimals: usize) -> Vec<String> {
    values.iter().map(|v| format!("{:.*}", decimals, v + 0.0)).collect()
}

fn abb(name: &str, header: &str, rows: &[Motion<'_>], nominal: &Chain, s: &ProgramSettings) -> String {
    let module = identifier(name, 32);
    let mut out = format!("MODULE {module}\n  ! {header}\n");
    let mut moves = String::new();
    for r in rows {
        let robtarget = s.abb_targets == AbbTargets::Robtarget;
        let target = identifier(&format!("{}_{}", if robtarget { "p" } else { "jt" }, r.label), 32);
        let q = match &r.joints {
            Ok(q) => *q,
            Err(why) => {
                out.push_str(&format!("  ! {target}: {why}\n"));
                moves.push_str(&format!("    ! skipped {}\n", r.label));
                continue;
            }
        };
        let pose = if robtarget { nominal.tool_pose(q).ok() } else { None };
        if let Some(base_from_tcp) = pose {
            let p = base_from_tcp.translation.vector;
            let quat = quaternion_wxyz(&base_from_tcp.rotation).map(|v| format!("{v:.9}"));
            let [cf1, cf4, cf6, cfx] = confdata(nominal, q);
            out.push_str(&format!(
                "  CONST robtarget {target}:=[[{:.6},{:.6},{:.6}],[{}],[{cf1},{cf4},{cf6},{cfx}],[9E9,9E9,9E9,9E9,9E9,9E9]];\n",
                p.x + 0.0,
                p.y + 0.0,
                p.z + 0.0,
                quat.join(",")
            ));
            moves.push_str(&format!("    MoveJ {target}, {}, {}, {};\n", s.speed, s.zone, s.tool));
        } else {
            let mut a = axes(&controller_joints(nominal, q), 6);
            a.resize(6, "0".into());
            out.push_str(&format!("  CONST jointtarget {target}:=[[{}],[9E9,9E9,9E9,9E9,9E9,9E9]];\n", a.join(",")));
            moves.push_str(&format!("    MoveAbsJ {target}\\NoEOffs, {}, {}, {};\n", s.speed, s.zone, s.tool));
        }
    }
    let conf = if s.abb_targets == AbbTargets::Robtarget { "    ConfJ \\On;\n" } else { "" };
    out.push_str(&format!("  PROC main()\n{conf}{moves}  ENDPROC\nENDMODULE\n"));
    out
}

/// Joint values of a result (radians, mm) as ABB and KUKA controllers take them (degrees, mm).
fn controller_joints(chain: &Chain, q: &[f64]) -> Vec<f64> {
    thermokin_io::units::joints_to_external(chain, q)
}

/// The wrist centre of a six-joint arm: joint 5's origin, where axes 4, 5 and 6 meet. Not
/// `thermokin_ik::ClosedForm::detect`: that one finds the nearest ideal geometry within 5° and 5 mm (and
/// needs axes 2 ∥ 3) to seed a solve, where confdata's definition needs the wrist exact (1e-6 mm) and
/// nothing of the arm.
fn check_spherical_wrist(chain: &Chain) -> Result<(), ProgramError> {
    if chain.dof() != 6 || chain.joints().iter().any(|j| j.kind != JointKind::Revolute) {
        return Err(ProgramError::NotSphericalWrist);
    }
    // Axes 4 and 6 must pass through joint 5's origin at any configuration; checked at two.
    for q in [[0.0; 6], [0.3, -0.4, 0.5, 0.7, -0.9, 1.1]] {
        let Ok(frames) = chain.joint_frames(&q) else { return Err(ProgramError::NotSphericalWrist) };
        let wrist = frames[4].translation.vector;
        for k in [3usize, 5] {
            let origin = frames[k].translation.vector;
            let axis = frames[k].rotation * chain.joints()[k].axis.into_inner();
            let off = (wrist - origin) - axis * axis.dot(&(wrist - origin));
            // 1e-6 mm: a real spherical wrist is exact; an offset wrist misses by millimetres.
            if off.norm() > 1e-6 {
                return Err(ProgramError::NotSphericalWrist);
            }
        }
    }
    Ok(())
}

/// ABB `confdata` [cf1, cf4, cf6, cfx] of joint values `q` (radians) on a six-joint arm with a spherical
/// wrist, from ABB's definition for serial six-axis robots: cf1, cf4, cf6 are the quadrants of axes 1, 4
/// and 6 (`floor(q / 90°)`: 0 for [0°, 90°), −1 for [−90°, 0), …); cfx numbers the arm configuration,
/// `4·(wrist centre behind axis 1) + 2·(wrist centre behind the lower arm) + (axis 5 negative)`, where
/// "behind axis 1" is the wrist centre on the negative side of the arm's forward direction (joint 1's X
/// after its turn) and "behind the lower arm" on the rear side of the line from joint 2 to joint 3.
pub fn confdata(chain: &Chain, q: &[f64]) -> [i64; 4] {
    let quadrant = |v: f64| (v / std::f64::consts::FRAC_PI_2).floor() as i64;
    let Ok(frames) = chain.joint_frames(q) else { return [0; 4] };
    // The arm plane: joint 1's frame after its turn; forward is its X, up its Z (the base's, for an arm
    // whose joint 1 turns about the vertical).
    let arm = frames[0];
    let local = |p: nalgebra::Vector3<f64>| arm.inverse_transform_point(&nalgebra::Point3::from(p)).coords;
    let wrist = local(frames[4].translation.vector);
    let shoulder = local(frames[1].translation.vector);
    let elbow = local(frames[2].translation.vector);
    let behind_axis1 = wrist.x < 0.0;
    let lower_arm = elbow - shoulder;
    // Forward normal of the lower arm in the X-Z plane: (uz, −ux) is +X for a vertical lower arm.
    let forward = nalgebra::Vector3::new(lower_arm.z, 0.0, -lower_arm.x);
    let behind_lower_arm = forward.dot(&(wrist - shoulder)) < 0.0;
    let axis5_negative = q[4] < 0.0;
    let cfx = 4 * i64::from(behind_axis1) + 2 * i64::from(behind_lower_arm) + i64::from(axis5_negative);
    [quadrant(q[0]), quadrant(q[3]), quadrant(q[5]), cfx]
}

/// A six-joint arm's configuration at joint values `q` (radians), as controllers name it: ABB's
/// `confdata` ([`confdata`]) with its cfx bits in words, KUKA's Status and Turn.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub struct ArmConfiguration {
    /// The wrist centre behind axis 1 (cfx bit 2).
    pub wrist_centre_behind_axis1: bool,
    /// The wrist centre behind the lower arm (cfx bit 1).
    pub wrist_centre_behind_lower_arm: bool,
    /// Axis 5 negative (cfx bit 0).
    pub axis5_negative: bool,
    /// ABB `confdata` [cf1, cf4, cf6, cfx].
    pub abb_confdata: [i64; 4],
    /// KUKA Status ([`kuka_status`]).
    pub kuka_status: u8,
    /// KUKA Turn ([`kuka_turn`]).
    pub kuka_turn: u8,
}

/// The [`ArmConfiguration`] of joint values `q` on `chain`.
pub fn arm_configuration(chain: &Chain, q: &[f64]) -> ArmConfiguration {
    let conf = confdata(chain, q);
    ArmConfiguration {
        wrist_centre_behind_axis1: conf[3] & 4 != 0,
        wrist_centre_behind_lower_arm: conf[3] & 2 != 0,
        axis5_negative: conf[3] & 1 != 0,
        abb_confdata: conf,
        kuka_status: kuka_status(chain, q),
        kuka_turn: kuka_turn(q),
    }
}

/// KUKA's Status of joint values `q` (radians) on a six-joint arm, read with the same geometry as
/// [`confdata`]'s cfx: bit 0 the wrist centre behind axis 1 (KUKA's overhead area), bit 1 the wrist
/// centre behind the lower arm (KUKA's A3 beyond the stretched-arm angle), bit 2 axis 5 at or below 0.
/// Pinned by tests to the branch it names; not checked against a KUKA controller.
pub fn kuka_status(chain: &Chain, q: &[f64]) -> u8 {
    let cfx = confdata(chain, q)[3];
    let axis5_not_positive = q.get(4).is_some_and(|&v| v <= 0.0);
    (u8::from(cfx & 4 != 0)) | (u8::from(cfx & 2 != 0) << 1) | (u8::from(axis5_not_positive) << 2)
}

/// KUKA's Turn of joint values `q` (radians): bit `i` set when axis `i + 1` is negative (KUKA's
/// definition; it tells apart configurations that differ by whole turns of an axis).
pub fn kuka_turn(q: &[f64]) -> u8 {
    q.iter().take(6).enumerate().fold(0u8, |t, (i, &v)| if v < 0.0 { t | (1 << i) } else { t })
}

fn kuka(name: &str, header: &str, rows: &[Motion<'_>], nominal: &Chain, s: &ProgramSettings) -> String {
    let program = identifier(name, 24);
    let approx = if s.zone.eq_ignore_ascii_case("fine") { String::new() } else { format!(" {}", s.zone) };
    let mut out = format!("DEF {program}( )\n; {header}\nBAS(#INITMOV, 0)\nBAS(#VEL_PTP, {})\n", s.speed);
    for r in rows {
        match &r.joints {
            Ok(q) => {
                let a = axes(&controller_joints(nominal, q), 6);
                let named: Vec<String> = a.iter().enumerate().take(6).map(|(i, v)| format!("A{} {v}", i + 1)).collect();
                out.push_str(&format!("PTP {{E6AXIS: {}}}{approx} ; {}\n", named.join(", "), r.label));
            }
            Err(why) => out.push_str(&format!("; skipped {}: {why}\n", r.label)),
        }
    }
    out.push_str("END\n");
    out
}

fn ur(name: &str, header: &str, rows: &[Motion<'_>], nominal: &Chain, s: &ProgramSettings) -> String {
    let program = identifier(name, 64);
    let mut out = format!("def {program}():\n  # {header}\n");
    for r in rows {
        if let Ok(q) = &r.joints {
            // URScript takes radians and metres: the library's radians, its millimetres / 1000.
            let si: Vec<f64> = nominal
                .joints()
                .iter()
                .zip(q.iter())
                .map(|(j, &v)| if j.kind == JointKind::Prismatic { thermokin_chain::units::metres(v) } else { v })
                .collect();
            out.push_str(&format!(
                "  movej([{}], a=1.4, v={}, r={})  # {}\n",
                axes(&si, 9).join(", "),
                s.speed,
                s.zone,
                r.label
            ));
        } else if let Err(why) = &r.joints {
            out.push_str(&format!("  # skipped {}: {why}\n", r.label));
        }
    }
    out.push_str("end\n");
    out
}

/// One arm configuration that reaches a pose, for output (`ik --branches`): where the wrist centre is,
/// the sign of axis 5, the solve's status, the joints (degrees; mm for prismatic joints, to 1e-12) and
/// the controllers' names of the configuration.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct BranchOut {
    /// `in front` of axis 1 or `behind` it.
    pub wrist_centre_vs_axis1: &'static str,
    /// `in front` of the lower arm or `behind` it.
    pub wrist_centre_vs_lower_arm: &'static str,
    /// `positive` or `negative`.
    pub axis5: &'static str,
    /// The solve's status (`Converged` only as checked by an independent FK).
    pub status: String,
    /// The joint values.
    pub joints_deg: Vec<f64>,
    /// ABB `confdata` [cf1, cf4, cf6, cfx].
    pub abb_confdata: [i64; 4],
    /// KUKA Status.
    pub kuka_status: u8,
    /// KUKA Turn.
    pub kuka_turn: u8,
    /// The position error of the solution, mm (independent FK).
    pub position_error_mm: f64,
}

impl BranchOut {
    /// The branch of `solution` on `chain`.
    pub fn of(chain: &Chain, solution: &thermokin_ik::Solution) -> Self {
        let conf = arm_configuration(chain, &solution.q);
        let side = |behind: bool| if behind { "behind" } else { "in front" };
        let joints = thermokin_io::units::joints_to_external(chain, &solution.q);
        Self {
            wrist_centre_vs_axis1: side(conf.wrist_centre_behind_axis1),
            wrist_centre_vs_lower_arm: side(conf.wrist_centre_behind_lower_arm),
            axis5: if conf.axis5_negative { "negative" } else { "positive" },
            status: format!("{:?}", solution.status),
            joints_deg: joints.iter().map(|&d| thermokin_io::units::rounded(d, 12)).collect(),
            abb_confdata: conf.abb_confdata,
            kuka_status: conf.kuka_status,
            kuka_turn: conf.kuka_turn,
            position_error_mm: solution.position_error_mm,
        }
    }

    /// The branches as a table, a header and one line each.
    pub fn table(rows: &[BranchOut]) -> String {
        let mut out = format!(
            "{:<10} {:<10} {:<8} {:<12} {:<66} {:<14} S  T\n",
            "vs axis 1", "vs arm", "axis 5", "status", "joints_deg", "confdata"
        );
        for r in rows {
            let joints: Vec<String> = r.joints_deg.iter().map(|v| format!("{v:.4}")).collect();
            let confdata = format!("[{}]", r.abb_confdata.map(|c| c.to_string()).join(","));
            out += &format!(
                "{:<10} {:<10} {:<8} {:<12} {:<66} {:<14} {:<2} {}\n",
                r.wrist_centre_vs_axis1,
                r.wrist_centre_vs_lower_arm,
                r.axis5,
                r.status,
                joints.join(","),
                confdata,
                r.kuka_status,
                r.kuka_turn
            );
        }
        out
    }
}

/// One row of a batch of inverse kinematics (`ik --poses-file`): the input's line and label, and the
/// joints to command with the status checked by FK — or why the row has none.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct SolutionRow {
    /// The input row's line.
    pub line: Option<usize>,
    /// The target's label.
    pub label: String,
    /// The joints (degrees; mm for prismatic joints, to 1e-12), when solved.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub joints_deg: Option<Vec<f64>>,
    /// The status (`Converged` only as checked by an independent FK).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub status: Option<String>,
    /// The position error, mm, and orientation error, degrees (independent FK).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub errors: Option<(f64, f64)>,
    /// Why the row has no solution.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub error: Option<String>,
}

/// One solve as `thermokin ik` reports it: the joints to command (degrees; mm for prismatic joints, to
/// 1e-12), the status (`Converged` only as checked by an independent FK), the solver's work, and the
/// independently measured errors; JSON through serde, text through `Display`.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct SolveOut {
    /// The joints to command, degrees (mm for prismatic joints).
    pub joints_deg: Vec<f64>,
    /// The status.
    pub status: String,
    /// Iterations of the last attempt.
    pub iterations: usize,
    /// Restarts taken.
    pub restarts: usize,
    /// Position error, mm (independent FK).
    pub position_error_mm: f64,
    /// Orientation error, degrees (independent FK).
    pub orientation_error_deg: f64,
}

impl SolveOut {
    /// The report of solve `s` on `chain`.
    pub fn of(chain: &Chain, s: &thermokin_ik::Solution) -> Self {
        let joints = thermokin_io::units::joints_to_external(chain, &s.q);
        Self {
            joints_deg: joints.iter().map(|&d| thermokin_io::units::rounded(d, 12)).collect(),
            status: format!("{:?}", s.status),
            iterations: s.iterations,
            restarts: s.restarts,
            position_error_mm: s.position_error_mm,
            orientation_error_deg: thermokin_io::units::degrees(s.orientation_error_rad),
        }
    }
}

impl std::fmt::Display for SolveOut {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let list: Vec<String> =
            self.joints_deg.iter().map(|&d| format!("{:.6}", thermokin_io::units::rounded(d, 6))).collect();
        writeln!(f, "joints_deg   {}", list.join(","))?;
        writeln!(
            f,
            "status       {} after {} iterations, {} restarts; error {:.3e} mm, {:.3e}° (checked by FK)",
            self.status, self.iterations, self.restarts, self.position_error_mm, self.orientation_error_deg
        )
    }
}

impl SolutionRow {
    /// The row of a solve on `chain`.
    pub fn solved(chain: &Chain, line: Option<usize>, label: String, s: &thermokin_ik::Solution) -> Self {
        let joints = thermokin_io::units::joints_to_external(chain, &s.q);
        Self {
            line,
            label,
            joints_deg: Some(joints.iter().map(|&d| thermokin_io::units::rounded(d, 12)).collect()),
            status: Some(format!("{:?}", s.status)),
            errors: Some((s.position_error_mm, thermokin_io::units::degrees(s.orientation_error_rad))),
            error: None,
        }
    }

    /// The header of [`SolutionRow::csv`] for `dof` joints.
    pub fn csv_header(dof: usize) -> String {
        let q: Vec<String> = (1..=dof).map(|i| format!("q{i}")).collect();
        format!("line,label,{},status,position_error_mm,orientation_error_deg,error", q.join(","))
    }

    /// The row as CSV, for `dof` joints.
    pub fn csv(&self, dof: usize) -> String {
        let line = self.line.map_or(String::new(), |l| l.to_string());
        let label = thermokin_io::csv_cell(&self.label);
        match (&self.joints_deg, &self.status, self.errors) {
            (Some(q), Some(status), Some((pe, oe))) => {
                let q: Vec<String> = q.iter().map(f64::to_string).collect();
                format!("{line},{label},{},{status},{pe:e},{oe:e},", q.join(","))
            }
            _ => format!(
                "{line},{label}{}{}",
                ",".repeat(dof + 4),
                thermokin_io::csv_cell(self.error.as_deref().unwrap_or(""))
            ),
        }
    }
}
