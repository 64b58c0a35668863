//! Command-line arguments (clap) and the parsers of their small languages (joint lists, poses, profiles).

use std::path::PathBuf;

use clap::builder::{PossibleValue, PossibleValuesParser, TypedValueParser};
use clap::{Args, Parser, Subcommand};
use thermokin_compensate::{Accumulation, Controller, Cycle, ResultsFormat};
use thermokin_deform::{SemanticsKind, TimeProfile};
use thermokin_diagnose::{Config, Extrapolation, FoldGrouping, Masses, Outliers, Shrinkage, SimulationConfig};
use thermokin_identify::{FrameMode, ToolMode};
use thermokin_io::{JointUnits, PositionUnits};
use thermokin_planner::{BeyondArcs, Criterion, Params};

/// A value parser for a library setting with named values (its `CHOICES`): `--help` lists each name with
/// its help, and the name parses into the library's own value.
fn choice<T: Clone + Send + Sync + 'static>(
    choices: &'static [(&'static str, &'static str, T)],
) -> impl TypedValueParser<Value = T> {
    let names = choices.iter().map(|(name, help, _)| PossibleValue::new(*name).help(*help));
    PossibleValuesParser::new(names).map(move |name| {
        // Only the listed names get here; the first value stands in for an impossible other.
        let found = choices.iter().find(|(n, _, _)| *n == name).unwrap_or(&choices[0]);
        found.2.clone()
    })
}

const AFTER_HELP: &str = "\
Units: millimetres and degrees everywhere on the command line and in files.
Orientations: X-Y-Z Euler angles in degrees, R = Rx(rx)·Ry(ry)·Rz(rz) (the paper's and CoppeliaSim's
convention; (0, 90, 0) points the tool's Z axis along world +X).

Exit status:
  0  success
  1  internal failure (a bug, or an output that could not be written)
  2  bad input: unreadable or malformed file, bad flag value, conflicting flags
  3  the run finished but some targets were not reached (each is a record in the output)
  4  reproduce-paper --check found drift from the golden outputs
  5  the diagnosis does not transfer: --export refused
  130  interrupted (Ctrl-C, SIGTERM, SIGHUP): temporary files removed, no output half-written
  141  standard output closed (| head)

Examples:
  thermokin fk --robot configs/irb140.toml --joints 0,30,10,0,-40,0
  thermokin ik --robot configs/irb140.toml --pose 600,0,400,0,90,0
  thermokin compensate --robot configs/irb140.toml --deformation fixtures/paper/deformations-case-study.toml \\
      --targets fixtures/paper/table12-targets.csv --out results.csv --program prog.mod
  thermokin compensate ... --profile linear-grow:180 --duration 200 --step 1 --plot plots/
  thermokin diagnose --robot configs/irb140.toml --measurements M.csv --html report.html --export calibrated.toml
  thermokin plan --robot configs/irb140.toml --samples 2000 --poses 30 --out plan.csv --html plan.html
  thermokin reproduce-paper";

/// Thermal error compensation for serial industrial robots on the paper's extended forward model.
#[derive(Parser, Debug)]
#[command(name = "thermokin", version, about, long_about = None, after_help = AFTER_HELP)]
pub struct Cli {
    /// What to do.
    #[command(subcommand)]
    pub command: Command,
}

/// Subcommands.
#[derive(Subcommand, Debug)]
pub enum Command {
    /// Forward kinematics: the TCP pose for joint angles (optionally on a deformed robot).
    #[command(after_help = "Example:\n  thermokin fk --robot configs/irb140.toml --joints 0,30,10,0,-40,0 --json")]
    Fk(FkArgs),
    /// Inverse kinematics: joint angles that reach a pose (optionally on a deformed robot).
    #[command(
        after_help = "Example:\n  thermokin ik --robot configs/irb140.toml --pose 600,0,400,0,90,0 --seed 0,30,10,0,-40,0"
    )]
    Ik(IkArgs),
    /// Compensate a program of targets: for a deviation table (static or over a warm-up cycle), or on a
    /// calibrated robot file (its drift, joint corrections, compliance) in each target's state.
    #[command(
        after_help = "Examples:\n  thermokin compensate --robot configs/irb140.toml --deformation fixtures/paper/deformations-case-study.toml \\\n      --targets fixtures/paper/table12-targets.csv --out results.csv\n  thermokin compensate ... --profile linear-grow:180 --duration 200 --step 1 --program prog.src --controller kuka --plot plots/\n  thermokin compensate --robot calibrated.toml --targets program.csv --time 60 --out joints.csv --format joints --program p60.mod\n\nA plain robot with --deformation: without --profile the run is static (the full table, one state); with\n--profile it is transient (the model updated every --step minutes for --duration minutes, every target\nre-solved). A calibrated robot (the TOML `diagnose --export` writes): each target solved on the robot as it\nis at its own time_min / temp_* columns, else at --time / --temperature / --payload; with --duration, every\ntarget at every step of a warm-up. The joints written are the values to command (gear-ratio, cyclic and\ncompliance corrections inverted)."
    )]
    Compensate(CompensateArgs),
    /// URDF: import a serial chain into the extended table (TOML), or export a (deformed) robot as URDF.
    #[command(subcommand)]
    Urdf(UrdfCommand),
    /// Diagnose the sim-to-real gap: which unmodelled effect explains measured poses, judged on held-out data.
    #[command(
        after_help = "Examples:\n  thermokin diagnose --robot configs/irb140.toml --measurements M.csv --json report.json --plot plots/\n  thermokin diagnose --robot robot.toml --measurements tracker.csv --frame tracker --tool unknown\n\nMeasurements CSV: time_min (optional), q1..qn (degrees), x,y,z (mm), optional rx,ry,rz (degrees),\noptional temp_<name> (°C). The authors' results files are accepted too."
    )]
    Diagnose(DiagnoseArgs),
    /// Plan which poses to measure: the N that make the diagnosis' parameters identifiable and precise.
    #[command(
        after_help = "Examples:\n  thermokin plan --robot fixtures/urdf/ur10.urdf --tip tool0 --frame tracker --tool unknown \\\n      --candidates taught.csv --poses 60 --out plan.csv --program plan.script\n  thermokin plan --robot configs/irb140.toml --samples 3000 --box -200,-800,0,900,800,1200 --poses 30 --out plan.csv\n  thermokin plan --robot robot.toml --candidates taught.csv --measured done.csv --poses 12 --out next.csv\n  thermokin plan --robot robot.toml --candidates taught.csv --for program.csv --poses auto --out plan.csv\n\nCandidates CSV: q1..qn (degrees; other columns ignored) — the poses you can reach. --for: the joints of\nthe program the robot will run (q1..qn); the poses are chosen for the error there. The plan CSV keeps\ntheir values and lines, in a measuring order that keeps joint motion short, with where the tracker should\nsee the tool (nominal, base frame). The report: the held-out error the plan promises at the poses of use\nagainst random poses, every parameter's predicted σ at --noise, and the condition number and O1–O5\nagainst random poses of the same candidates (docs/planner.md)."
    )]
    Plan(PlanArgs),
    /// Generate a measurement set from hidden effects (to check what the diagnosis finds).
    #[command(
        after_help = "Examples:\n  thermokin simulate --robot configs/irb140.toml --effect joint_offset:2 --noise 0.005 --poses 240 --minutes 240 -o M.csv\n  thermokin simulate --robot configs/irb140.toml --effect link_deviation:3=0.3,-0.2,0.25,0.02,0,0.015 --effect base_frame -o M.csv\n\nEffect: KIND[:JOINT][=VALUES] with KIND one of base_frame, tool_frame, joint_offset, link_deviation,\njoint_compliance, joint_scale (gear ratio, Δq = s·q), periodic (Δq = a1 sin q + b1 cos q + a2 sin 2q + b2 cos 2q),\nthermal_drift (linear), thermal_drift_exp (exponential), compliance_coupling (joints J and J+1 each sag by c times the other's\ngravity torque), lateral_compliance (the joint's row tilts under the gravity moment across its axis, a slide's also bends with\nits extension; without masses its loads are lumped), straightness (a slide's guide: the carriage tilts and rolls with the extension, deg/mm,\nand bows with its square, per mm); values in mm, degrees, minutes and degrees per N·m (default: a seeded random effect of typical size)."
    )]
    Simulate(SimulateArgs),
    /// Reproduce the paper's case studies (Tables 13–18) from the bundled fixtures, and compare with the
    /// authors' full files (bundled in fixtures/paper/authors).
    #[command(
        after_help = "Examples:\n  thermokin reproduce-paper\n  thermokin reproduce-paper --report paper.md --plot plots/ --json measured.json\n  thermokin reproduce-paper --json measured.json --check fixtures/golden/paper-reproduction.json   # exit 4 on drift"
    )]
    ReproducePaper(ReproduceArgs),
}

/// `urdf` subcommands.
#[derive(Subcommand, Debug)]
pub enum UrdfCommand {
    /// Import a URDF's serial chain (fixed joints folded in) and write it as an extended-table TOML.
    #[command(after_help = "Example:\n  thermokin urdf import fixtures/urdf/ur5.urdf --tip tool0 -o ur5.toml")]
    Import {
        /// The URDF file.
        file: PathBuf,
        /// Base link (default: the root).
        #[arg(long)]
        base: Option<String>,
        /// Tip link (default: the single leaf; an error lists the candidates when there are several). The
        /// chains beside the path to it are written as the robot's `[[branch]]` tables.
        #[arg(long)]
        tip: Option<String>,
        /// Output TOML (written atomically).
        #[arg(short, long, value_name = "FILE")]
        out: PathBuf,
    },
    /// Export a robot, optionally deformed by a deviation table, as URDF whose FK equals the model's — or,
    /// for six revolute joints and a FILE ending in .yaml, as Universal Robots' kinematics YAML (the
    /// kinematics_params of Universal_Robots_ROS2_Description; the tool point behind tool0 named in its header).
    #[command(
        after_help = "Examples:\n  thermokin urdf export --robot configs/irb140.toml --deformation fixtures/paper/deformations-measured.toml -o deformed.urdf\n  thermokin urdf export --robot calibrated-ur10.toml -o ur10_calibration.yaml"
    )]
    Export {
        #[command(flatten)]
        robot: Box<RobotArgs>,
        /// Output URDF, or UR kinematics YAML for .yaml/.yml (written atomically).
        #[arg(short, long, value_name = "FILE")]
        out: PathBuf,
    },
}

/// The robot and its deformation.
#[derive(Args, Debug, Clone)]
pub struct RobotArgs {
    /// Robot description: TOML (extended, DH or modified DH table) or URDF (.urdf).
    #[arg(long, value_name = "FILE")]
    pub robot: PathBuf,
    /// URDF base link (default: the root link).
    #[arg(long, value_name = "LINK")]
    pub base: Option<String>,
    /// URDF tip link (default: the single leaf). In a tree (a torso with two arms) the chains beside the
    /// path to it are the robot's branches: a measurements column named as a branch joint is its position
    /// (degrees; mm for a slide), and what the branch carries loads the joints below it — the torque of
    /// its links' `<inertial>` masses when the file gives them, lumped otherwise.
    #[arg(long, value_name = "LINK")]
    pub tip: Option<String>,
    /// A tool behind the robot file's tool frame (the URDF's --tip link, a TOML's `[tool]`): the TCP in that
    /// frame, x,y,z (mm) and the orientation in the --orientation convention (or a JSON pose); all zeros
    /// is the file's own tool.
    #[arg(long, value_name = "X,Y,Z,A,B,C", allow_hyphen_values = true)]
    pub tool_pose: Option<String>,
    /// Replace the robot file's base: the robot base in the world frame, as --tool-pose.
    #[arg(long, value_name = "X,Y,Z,A,B,C", allow_hyphen_values = true)]
    pub base_pose: Option<String>,
    /// Orientation convention of --pose, --tool-pose and --base-pose, and of a measurement file's
    /// orientation columns: xyz (X-Y-Z Euler degrees, R = Rx·Ry·Rz, the paper's; columns rx,ry,rz), rpy
    /// (ROS roll,pitch,yaw degrees, R = Rz·Ry·Rx; columns rx,ry,rz = roll, pitch, yaw) or quat (w,x,y,z;
    /// columns qw,qx,qy,qz).
    #[arg(long, value_name = "CONVENTION", default_value_t = thermokin_io::Orientation::default(), value_parser = |s: &str| s.parse::<thermokin_io::Orientation>())]
    pub orientation: thermokin_io::Orientation,
    /// Deviation table (the authors' CSV `Dx,Dy,Dz,Dox,Doy,Doz`, or TOML), mm and degrees.
    #[arg(long, value_name = "FILE")]
    pub deformation: Option<PathBuf>,
    /// Growth of the table with operating time: static, linear:T (plateau after T min), linear-grow:T
    /// (no plateau, the authors' transient file), exp:TAU, cubic:C1,C2,C3, temperature:LOG.csv (the table
    /// then holds values per kelvin, scaled by the mean rise of the logged temperatures over their first
    /// row; LOG.csv is `time_min,<sensor>,<sensor>,…` in minutes and °C, one row per reading, linearly
    /// interpolated), or a profile TOML file.
    #[arg(long, value_name = "PROFILE", value_parser = |s: &str| TimeProfile::parse_spec(s).map_err(|e| e.to_string()))]
    pub profile: Option<thermokin_deform::ProfileSpec>,
    /// Operating time, minutes since the cold start of a warm-up: for a robot file whose rows drift with
    /// time (a calibrated robot, `[[drift]]`), and for fk/ik with --profile. A targets file's `time_min`
    /// column overrides it per target.
    #[arg(long, value_name = "MIN")]
    pub time: Option<f64>,
    /// Sensor readings, °C, for a robot file whose rows drift per kelvin: `temp_j2=35.1,temp_j3=30.2`
    /// (the names of the measurement files' temp_ columns; the prefix may be left out). A targets file's
    /// `temp_*` columns, and its columns named as the robot's sensors (an accelerometer's `NAME_x`,
    /// `NAME_y`, `NAME_z`), override them per target.
    #[arg(long, value_name = "NAME=C,...")]
    pub temperature: Option<String>,
    /// The direction each joint last moved in before the pose, for a robot file with a backlash
    /// (`backlash` in a joint's table): one of `+` (rising), `-` (falling), `?` (not known: the middle of
    /// the play) per joint, e.g. `+,-,+,?,?,?`. fk of a joints file and compensate take each row's from
    /// the rows' order (this flag then gives the first row's); one row on its own needs it.
    #[arg(long, value_name = "+|-|?,...", allow_hyphen_values = true)]
    pub approach: Option<String>,
    /// A payload on the flange (the probe, a gripper, a load): `KG@X,Y,Z`, its centre in the flange's
    /// frame in mm, e.g. `2.5@0,0,80`. Gravity compliance of a calibrated robot bends under it (it replaces
    /// the payload the robot file was calibrated with); the diagnosis merges it with the last link's mass.
    #[arg(long, value_name = "KG@X,Y,Z")]
    pub payload: Option<String>,
    /// How the table acts on the robot.
    #[arg(long, value_parser = choice(SemanticsKind::CHOICES), default_value_t = SemanticsKind::default())]
    pub semantics: SemanticsKind,
}

/// `fk` arguments.
#[derive(Args, Debug)]
pub struct FkArgs {
    #[command(flatten)]
    pub robot: RobotArgs,
    /// Joint values, degrees (mm for prismatic joints), comma separated.
    #[arg(long, value_name = "Q1,...,QN", allow_hyphen_values = true, required_unless_present = "joints_file")]
    pub joints: Option<String>,
    /// A file of joint values instead (`q1..qn` columns, degrees; optional `time_min`, `temp_*` for each
    /// row's state): one output row per input row on standard output — `line,x_mm,y_mm,z_mm,rx_deg,
    /// ry_deg,rz_deg,error` (X-Y-Z Euler), or a JSON object per line with --json — a bad row is its
    /// error, the others are computed (exit 3 when any row failed).
    #[arg(long, value_name = "FILE", conflicts_with = "joints")]
    pub joints_file: Option<PathBuf>,
    /// Print JSON: position_mm, rotation (3×3), xyz_euler_deg (the paper's R = Rx·Ry·Rz), ros_rpy_deg
    /// (R = Rz·Ry·Rx), quaternion_wxyz, and outside_limits (joints beyond their limits, named).
    #[arg(long)]
    pub json: bool,
}

/// `ik` arguments.
#[derive(Args, Debug)]
pub struct IkArgs {
    #[command(flatten)]
    pub robot: RobotArgs,
    /// Target pose x,y,z (mm),rx,ry,rz (degrees, X-Y-Z Euler); or x,y,z alone with --position-only.
    #[arg(long, value_name = "X,Y,Z,RX,RY,RZ", allow_hyphen_values = true, required_unless_present = "poses_file")]
    pub pose: Option<String>,
    /// A file of poses instead (a targets CSV: `X,Y,Z` and `RX,RY,RZ`, `ROLL,PITCH,YAW` or `QW,QX,QY,QZ`,
    /// optional label, `time_min`, `temp_*`), each solved from --seed: one output row per input row on
    /// standard output — `line,label,q1..qn,status,position_error_mm,orientation_error_deg,error`, or a
    /// JSON object per line with --json (exit 3 when any row was not reached or could not be read).
    #[arg(long, value_name = "FILE", conflicts_with_all = ["pose", "branches", "position_only"])]
    pub poses_file: Option<PathBuf>,
    /// Solve for the position only (orientation free).
    #[arg(long)]
    pub position_only: bool,
    /// Unit of --poses-file's positions (default: millimetres, refused when ten or more targets all lie
    /// within ±5 — a program in metres).
    #[arg(long, value_parser = choice(PositionUnits::CHOICES))]
    pub position_units: Option<PositionUnits>,
    /// Seed joint values, degrees (default: all zero).
    #[arg(long, value_name = "Q1,...,QN", allow_hyphen_values = true)]
    pub seed: Option<String>,
    /// Random restarts when a solve stalls.
    #[arg(long, default_value_t = thermokin_ik::Params::default().restarts)]
    pub restarts: usize,
    /// List every arm configuration that reaches the pose instead of one solution: for arms with a
    /// closed form (axes 2 and 3 parallel and a spherical wrist — the IRB 140, most ABB/KUKA/Fanuc arms —
    /// or axes 2, 3, 4 parallel — the UR family), the
    /// up to 8 branches (shoulder front/back, elbow up/down, wrist flip), each refined on the robot as
    /// loaded, with ABB confdata (cf1, cf4, cf6, cfx), KUKA Status and Turn and whether it is reachable in the limits.
    #[arg(long)]
    pub branches: bool,
    /// Print JSON.
    #[arg(long)]
    pub json: bool,
}

/// `compensate` arguments.
#[derive(Args, Debug)]
pub struct CompensateArgs {
    #[command(flatten)]
    pub robot: RobotArgs,
    /// Program of targets: CSV `,X,Y,Z` (mm) with optional `RX,RY,RZ` (degrees; default 0,90,0), and for
    /// a calibrated robot each target's state: `time_min`, `temp_*` and the robot's other sensors by the
    /// names its measurements gave them (an accelerometer's `NAME_x`, `NAME_y`, `NAME_z`).
    #[arg(long, value_name = "FILE")]
    pub targets: PathBuf,
    /// Unit of the targets' positions (default: millimetres, refused when ten or more targets all lie
    /// within ±5 — a program in metres).
    #[arg(long, value_parser = choice(PositionUnits::CHOICES))]
    pub position_units: Option<PositionUnits>,
    /// The results (written atomically), in --format.
    #[arg(long, value_name = "FILE")]
    pub out: PathBuf,
    /// Layout of --out.
    #[arg(long, value_parser = choice(ResultsFormat::CHOICES), default_value_t = ResultsFormat::default())]
    pub format: ResultsFormat,
    /// Transient cycle length, minutes: with --profile (default 200), or to run a calibrated robot's
    /// warm-up (every target at every step).
    #[arg(long, value_name = "MIN")]
    pub duration: Option<f64>,
    /// Model update interval, minutes (transient runs).
    #[arg(long, value_name = "MIN", default_value_t = Cycle::PAPER.step_min)]
    pub step: f64,
    /// How each update brings the table into force (with --profile): from-nominal (the profile's share
    /// applied to the undeformed robot; the state at t depends on t alone) or increments (only the change
    /// since the previous update, applied to the robot as already deformed — what the authors' script
    /// did every minute, paper section 4 and Appendix A, Figure A5; with --semantics coppeliasim the
    /// state then depends on the path, see docs/paper-reproduction.md).
    #[arg(long, value_name = "HOW", value_parser = choice(Accumulation::CHOICES), default_value_t = Accumulation::default())]
    pub accumulate: Accumulation,
    /// Seed of the first solve, degrees (default: all zero).
    #[arg(long, value_name = "Q1,...,QN", allow_hyphen_values = true)]
    pub seed: Option<String>,
    /// Also write the compensated joint targets as CSV.
    #[arg(long, value_name = "FILE")]
    pub joints_out: Option<PathBuf>,
    /// Also write a robot program of the compensated joints: ABB RAPID (.mod), KUKA KRL (.src) or
    /// Universal Robots URScript (.script), by --controller or the extension. A transient run writes one
    /// program per time step, FILE's stem + `_t<minutes>`.
    #[arg(long, value_name = "FILE", alias = "rapid")]
    pub program: Option<PathBuf>,
    /// Controller language of --program (default: from the file extension).
    #[arg(long, value_parser = choice(Controller::CHOICES))]
    pub controller: Option<Controller>,
    /// Motion speed in the controller's terms: ABB speeddata (v100), KUKA axis % (30), UR rad/s (1.05).
    #[arg(long, value_name = "SPEED")]
    pub speed: Option<String>,
    /// Zone in the controller's terms: ABB zonedata (fine, z10), KUKA fine or C_PTP, UR blend radius m (0).
    #[arg(long, value_name = "ZONE")]
    pub zone: Option<String>,
    /// ABB tooldata of the motion instructions (default: tool0, the flange).
    #[arg(long, value_name = "NAME")]
    pub tooldata: Option<String>,
    /// ABB: MoveJ to robtargets (the nominal robot's pose at the compensated joints, with confdata, so
    /// the controller's own IK lands on them) instead of MoveAbsJ to jointtargets.
    #[arg(long)]
    pub robtargets: bool,
    /// Write SVG plots (deviation vs time; nominal vs deformed structure) into this directory.
    #[arg(long, value_name = "DIR")]
    pub plot: Option<PathBuf>,
    /// Print the summary as JSON.
    #[arg(long)]
    pub json: bool,
    /// Stream a static program of any length with constant memory: targets are read in chunks, each
    /// chunk solved on every core, --out (--format joints) written as it goes. Each target is solved on
    /// its own from --seed (for a closed-form arm: the branch nearest to it) rather than chained from the
    /// previous target. Not with --profile, --joints-out, --program or --plot.
    #[arg(long)]
    pub stream: bool,
}

/// `diagnose` arguments.
#[derive(Args, Debug)]
pub struct DiagnoseArgs {
    #[command(flatten)]
    pub robot: RobotArgs,
    /// Measurement set (CSV).
    #[arg(long, value_name = "FILE")]
    pub measurements: PathBuf,
    /// The measured poses (`x,y,z`, optional `rx,ry,rz`) in a second file, when --measurements holds only
    /// the joints (`q1..qn`, optional `time_min`, `temp_*`): joined row by row, or by --key.
    #[arg(long, value_name = "FILE")]
    pub poses: Option<PathBuf>,
    /// The column that joins --measurements and --poses (a point name, a timestamp), present in both.
    #[arg(long, value_name = "COLUMN", requires = "poses")]
    pub key: Option<String>,
    /// An explicit test set: scored with the model fitted on all measurements (the registration and tool
    /// refitted on it when they are estimated); it never influences the selection.
    #[arg(long, value_name = "FILE")]
    pub holdout: Option<PathBuf>,
    /// Where the robot will work: a joints or targets file with q1..qn (the program to be compensated;
    /// only the joints are read). The report predicts the final model's held-out error there from its
    /// own fit — what `plan --for` promised, at the noise the fit found — and, when --holdout holds
    /// those poses, sets the measured error beside it. Never used to choose.
    #[arg(long = "for", value_name = "FILE")]
    pub region: Option<PathBuf>,
    /// The plan of the measured poses (the JSON `plan --for ... --json` wrote): its promise at the poses
    /// of use, restated at the residual scale the fit finds, is set beside the prediction and the
    /// hold-out set's measured error. With --for, the same poses of use.
    #[arg(long, value_name = "FILE", requires = "region")]
    pub plan: Option<PathBuf>,
    /// Frame of the measurements.
    #[arg(long, value_parser = choice(FrameMode::CHOICES), default_value_t = Config::default().frame)]
    pub frame: FrameMode,
    /// Tool point.
    #[arg(long, value_parser = choice(ToolMode::CHOICES), default_value_t = Config::default().tool)]
    pub tool: ToolMode,
    /// Cross-validation folds.
    #[arg(long, default_value_t = Config::default().folds)]
    pub folds: usize,
    /// Write the report as JSON.
    #[arg(long, value_name = "FILE")]
    pub json: Option<PathBuf>,
    /// Write SVG plots (residuals before/after, held-out error per effect) into this directory.
    #[arg(long, value_name = "DIR")]
    pub plot: Option<PathBuf>,
    /// Write the report as one self-contained HTML page (opens offline): the verdict and held-out
    /// figures, then where the gap lies — residual vectors over the workspace, against each joint, over
    /// time, per fold —, the ladder of effects, each effect's values with σ, gross errors, refusals.
    #[arg(long, value_name = "FILE")]
    pub html: Option<PathBuf>,
    /// How poses are grouped into validation folds, so that an effect is scored on poses unlike those it
    /// was fitted on and the gate counts blocks, not poses.
    #[arg(long, value_parser = choice(FoldGrouping::CHOICES), default_value_t = Config::default().folds_by)]
    pub folds_by: FoldGrouping,
    /// Gross errors (a beam break, a knocked probe): listed by file line (JSON `outliers`) and left out
    /// of every fit and figure, or kept.
    #[arg(long, value_parser = choice(Outliers::CHOICES), default_value_t = Config::default().outliers)]
    pub outliers: Outliers,
    /// The robot file's link masses: a gravity compliance on them, or (`ignore`: CAD masses you do not
    /// trust) each joint's loads lumped and identified from the data, as for a file that has none.
    #[arg(long, value_parser = choice(Masses::CHOICES), default_value_t = Config::default().masses)]
    pub masses: Masses,
    /// Which joints may tilt under the gravity moment across their axis (a lateral compliance): a
    /// column's (with the file's masses), or every joint's bearing too — a humanoid's torso carrying its
    /// arm, elastic joints — on the file's masses or, without them, its loads lumped from the data.
    #[arg(long, value_parser = choice(thermokin_identify::Lateral::CHOICES), default_value_t = Config::default().lateral)]
    pub lateral: thermokin_identify::Lateral,
    /// Where the order the poses were measured in comes from, for what only that order shows — a
    /// gearbox's backlash (an offset by the direction each joint last moved in), a step of the
    /// measurement frame (a knocked tracker): the time_min column, or also the file's lines when the file
    /// lists the poses as they were measured (`file`; a time column still decides where there is one).
    /// Without either the rows have no order: the same poses in any row order give the same diagnosis.
    #[arg(long, value_parser = choice(thermokin_chain::MeasuringOrder::CHOICES), default_value_t = Config::default().order)]
    pub order: thermokin_chain::MeasuringOrder,
    /// An accelerometer or inclinometer on a link, NAME=LINK (LINK 0 the robot's base, k the link joint k
    /// moves; repeat for each): its columns NAME_x, NAME_y, NAME_z (any unit proportional to g) are read
    /// as the link's tilt from their mean direction — the row of the joint the link carries turned by it,
    /// no gain fitted — and a second sensor higher on the chain as what bends between them. The exported
    /// robot takes the readings at run time: fk --temperature NAME_x=..,NAME_y=..,NAME_z=..
    #[arg(long = "accelerometer", value_name = "NAME=LINK", value_parser = accelerometer)]
    pub accelerometers: Vec<thermokin_diagnose::Accelerometer>,
    /// A Gaussian prior toward the nominal robot on the chosen model, as strong as cross-validation
    /// asks and kept only where it passes the gate (few poses: the weakly seen directions pulled back),
    /// or the least-squares fit as it is.
    #[arg(long, value_parser = choice(Shrinkage::CHOICES), default_value_t = Config::default().shrinkage)]
    pub shrinkage: Shrinkage,
    /// A chosen gear-ratio scale, cyclic error or compliance must hold beyond the poses it was fitted on
    /// (fitted on one half of each joint's measured arc, scored on the other) at least as well as it
    /// helps among them, or leave refused; off keeps the effects as the neighbourhood folds chose them.
    #[arg(long, value_parser = choice(Extrapolation::CHOICES), default_value_t = Config::default().extrapolation)]
    pub extrapolation: Extrapolation,
    /// Unit of the measurement files' revolute joint columns (default: degrees, refused when every value
    /// lies within ±2π — joints written in radians; give deg to read them as degrees anyway).
    #[arg(long, value_parser = choice(JointUnits::CHOICES))]
    pub joint_units: Option<JointUnits>,
    /// Unit of the measured positions (default: millimetres, refused when every coordinate lies within
    /// ±5 — a workspace in metres; give mm to read them as millimetres anyway).
    #[arg(long, value_parser = choice(PositionUnits::CHOICES))]
    pub position_units: Option<PositionUnits>,
    /// The measurement noise per axis (one standard deviation, mm) — your tracker's specification, e.g.
    /// 0.01. The verdict then says whether what remains is that noise or an effect the catalogue lacks.
    #[arg(long, value_name = "MM")]
    pub noise: Option<f64>,
    /// Weight of measured orientations (rx, ry, rz columns: a 6-D probe) as a lever in mm: a rotation
    /// error of δφ counts as the displacement lever·δφ it causes that far from the tool point. 0 fits
    /// positions only. Ignored when the files carry no orientation.
    #[arg(long, value_name = "MM", default_value_t = Config::default().orientation_lever_mm)]
    pub orientation_lever: f64,
    /// The orientation noise per axis of a 6-D probe (one standard deviation, degrees), e.g. 0.01: with
    /// --noise, the verdict's noise floor then includes the orientations.
    #[arg(long, value_name = "DEG")]
    pub orientation_noise: Option<f64>,
    /// Write the identified robot — every chosen effect, the model the report scores: registration (as
    /// the base row, so that FK gives the measurement frame), tool point, base frame, joint offsets, link
    /// deviations, gear ratios, cyclic errors, gravity compliance (with the --payload measured with) and
    /// each drifting row with its law — as a robot TOML that fk, ik and compensate accept (--time,
    /// --temperature, --payload give the state). A FILE ending in .urdf (or .yaml: a UR kinematics YAML)
    /// holds the geometry and zeros only and names in its header what it cannot hold. Refused when the chosen model does not beat the
    /// nominal one on data it never saw, unless --force-export.
    #[arg(long, value_name = "FILE")]
    pub export: Option<PathBuf>,
    /// Write --export even when the chosen model does not beat the nominal one held out.
    #[arg(long)]
    pub force_export: bool,
    /// No progress on stderr (by default a bar on a terminal, a line per stage with the time left
    /// otherwise).
    #[arg(long, short)]
    pub quiet: bool,
}

/// `plan` arguments.
#[derive(Args, Debug)]
pub struct PlanArgs {
    #[command(flatten)]
    pub robot: RobotArgs,
    /// The poses the robot can reach (taught, collision-free): a CSV with q1..qn; the plan is a subset.
    #[arg(long, value_name = "FILE", conflicts_with_all = ["samples", "workspace"])]
    pub candidates: Option<PathBuf>,
    /// Without --candidates: configurations sampled within the joint limits (seeded).
    #[arg(long, value_name = "N", default_value_t = thermokin_planner::DEFAULT_SAMPLES)]
    pub samples: usize,
    /// Keep sampled configurations whose tool point lies in this box of the base frame, mm.
    #[arg(long = "box", value_name = "X0,Y0,Z0,X1,Y1,Z1", allow_hyphen_values = true)]
    pub workspace: Option<String>,
    /// Poses already measured (q1..qn): plan the next ones that add the most to them.
    #[arg(long, value_name = "FILE")]
    pub measured: Option<PathBuf>,
    /// Where the robot will work: a joints or targets file with q1..qn (the program to be compensated,
    /// or any poses of its work; only the joints are read). The plan then chooses for the predicted
    /// error there (I-optimal over these poses, unless --criterion says otherwise) and states what it
    /// promises there against random poses. Without it the poses of use are the candidates.
    #[arg(long = "for", value_name = "FILE")]
    pub region: Option<PathBuf>,
    /// What a plan --for makes of a pose of use beyond the candidates' arcs (by more than a degree on a
    /// joint, a millimetre on a slide): plan for it at its nearest candidate, where a measurement can
    /// check the prediction — the promise is then stated there, and beside it what the plan would
    /// promise at the poses as given — or as given: the model's extrapolation taken as the robot there.
    #[arg(long, value_parser = choice(BeyondArcs::CHOICES), default_value_t = Params::default().beyond_arcs)]
    pub beyond_arcs: BeyondArcs,
    /// Plan for these effects only, `KIND[:JOINT]` (repeat); default: every pose-dependent effect of the
    /// diagnosis' catalogue that some choice of the candidates can make eligible (a gear ratio or cyclic
    /// error whose joint no candidate moves far enough is left out, and the report says so).
    #[arg(long = "effect", value_name = "SPEC")]
    pub effects: Vec<String>,
    /// Poses to plan: a count, or `auto` — as many as each lower the predicted held-out error at the
    /// poses of use by more than a test there could show (its standard error over those poses), at most
    /// every candidate; the report says where and why it stopped.
    #[arg(long, value_name = "N|auto", default_value_t = Params::default().poses, value_parser = parse_poses)]
    pub poses: thermokin_planner::Poses,
    /// The tracker noise per axis (mm) the predicted σ are stated at.
    #[arg(long, value_name = "MM", default_value_t = Params::default().noise_mm)]
    pub noise: f64,
    /// What the poses optimise: the predicted error at the poses of use (--for; the candidates without
    /// it), or the parameters (the poses that pin down what a diagnosis refused).
    #[arg(long, value_parser = choice(Criterion::CHOICES), default_value_t = Params::default().criterion)]
    pub criterion: Criterion,
    /// Frame the poses will be measured in.
    #[arg(long, value_parser = choice(FrameMode::CHOICES), default_value_t = Params::default().frame)]
    pub frame: FrameMode,
    /// Tool point.
    #[arg(long, value_parser = choice(ToolMode::CHOICES), default_value_t = Params::default().tool)]
    pub tool: ToolMode,
    /// Which joints' lateral compliance to plan for, as `diagnose --lateral`: a column's, or every
    /// joint's bearing too (poses that vary the moments across the joints).
    #[arg(long, value_parser = choice(thermokin_identify::Lateral::CHOICES), default_value_t = Params::default().lateral)]
    pub lateral: thermokin_identify::Lateral,
    /// Unit of the candidates' and measured poses' revolute joint columns (default: degrees, refused
    /// where every value of ten or more rows stays within ±6.3°: radians, most likely).
    #[arg(long, value_parser = choice(JointUnits::CHOICES))]
    pub joint_units: Option<JointUnits>,
    /// Seed (sampled candidates, the random poses the plan is compared with).
    #[arg(long, default_value_t = Params::default().seed)]
    pub seed: u64,
    /// The plan CSV (written atomically).
    #[arg(short, long, value_name = "FILE")]
    pub out: PathBuf,
    /// Also a robot program visiting the poses: ABB RAPID (.mod), KUKA KRL (.src) or URScript (.script).
    #[arg(long, value_name = "FILE")]
    pub program: Option<PathBuf>,
    /// Controller language of --program (default: from its extension).
    #[arg(long, value_parser = choice(Controller::CHOICES))]
    pub controller: Option<Controller>,
    /// Write the report as JSON.
    #[arg(long, value_name = "FILE")]
    pub json: Option<PathBuf>,
    /// Write the plan as one self-contained HTML page (opens offline): the plan against random poses,
    /// the poses over the workspace in measuring order, joint coverage, predicted σ.
    #[arg(long, value_name = "FILE")]
    pub html: Option<PathBuf>,
}

/// `simulate` arguments.
#[derive(Args, Debug)]
pub struct SimulateArgs {
    #[command(flatten)]
    pub robot: RobotArgs,
    /// A hidden effect (repeat for several): `KIND[:JOINT][=VALUES]`.
    #[arg(long = "effect", value_name = "SPEC", required = true)]
    pub effects: Vec<String>,
    /// Measurement noise per axis, mm (standard deviation).
    #[arg(long, default_value_t = SimulationConfig::default().noise_mm)]
    pub noise: f64,
    /// Number of poses.
    #[arg(long, default_value_t = SimulationConfig::default().poses)]
    pub poses: usize,
    /// Time span of the measurements, minutes.
    #[arg(long, default_value_t = SimulationConfig::default().minutes)]
    pub minutes: f64,
    /// Also measure the tool's orientation (a 6-D probe: rx, ry, rz columns), with this noise per axis
    /// in degrees (standard deviation of a small random turn).
    #[arg(long, value_name = "DEG")]
    pub orientation_noise: Option<f64>,
    /// Seed.
    #[arg(long, default_value_t = SimulationConfig::default().seed)]
    pub seed: u64,
    /// Output measurement CSV (written atomically).
    #[arg(short, long, value_name = "FILE")]
    pub out: PathBuf,
}

/// `reproduce-paper` arguments.
#[derive(Args, Debug)]
pub struct ReproduceArgs {
    /// The transcribed paper tables (Tables 10–18).
    #[arg(long, value_name = "DIR", default_value = "fixtures/paper")]
    pub fixtures: PathBuf,
    /// Table 9's IRB 140: the canonical-semantics run and the identification of the scene.
    #[arg(long, value_name = "FILE", default_value = "configs/irb140.toml")]
    pub robot: PathBuf,
    /// The IRB 140 of the authors' CoppeliaSim scene (Table 9 with joint 6's object at the flange and the
    /// tool point identified on their minute-0 rows): the CoppeliaSim-semantics runs.
    #[arg(long, value_name = "FILE", default_value = "configs/irb140-scene.toml")]
    pub scene_robot: PathBuf,
    /// The authors' published CoppeliaSim files (bundled; compared when present).
    #[arg(long, value_name = "DIR", default_value = "fixtures/paper/authors", alias = "shared")]
    pub authors: PathBuf,
    /// Write the side-by-side report here (Markdown).
    #[arg(long, value_name = "FILE")]
    pub report: Option<PathBuf>,
    /// Write the plots into this directory.
    #[arg(long, value_name = "DIR")]
    pub plot: Option<PathBuf>,
    /// Write the measured numbers as JSON (the golden file's format).
    #[arg(long, value_name = "FILE")]
    pub json: Option<PathBuf>,
    /// Compare with this golden JSON and fail (exit 4) on drift beyond its tolerances.
    #[arg(long, value_name = "FILE")]
    pub check: Option<PathBuf>,
}

/// Parses a comma-separated list of finite numbers ([`thermokin_io::parse_list`]), naming the flag in
/// errors.
/// `--poses`: a positive count, or `auto` (at most every candidate).
fn parse_poses(s: &str) -> Result<thermokin_planner::Poses, String> {
    if s.trim().eq_ignore_ascii_case("auto") {
        return Ok(thermokin_planner::Poses::Auto { at_most: usize::MAX });
    }
    match s.trim().parse::<usize>() {
        Ok(n) if n > 0 => Ok(thermokin_planner::Poses::Exactly(n)),
        _ => Err(format!("`{s}`: a positive number of poses, or auto")),
    }
}

pub fn parse_list(flag: &str, s: &str) -> anyhow::Result<Vec<f64>> {
    thermokin_io::parse_list(s).map_err(|m| anyhow::anyhow!("--{flag}: {m}"))
}

/// `--accelerometer NAME=LINK`.
fn accelerometer(text: &str) -> Result<thermokin_diagnose::Accelerometer, String> {
    let (name, link) =
        text.split_once('=').ok_or_else(|| format!("`{text}`: give NAME=LINK, e.g. acc_top=1 (0 is the base)"))?;
    let name = name.trim();
    if name.is_empty() || name.contains(',') {
        return Err(format!("`{text}`: the sensor's name (its columns are NAME_x, NAME_y, NAME_z) is missing"));
    }
    let link = link.trim().parse::<usize>().map_err(|_| {
        format!(
            "`{text}`: LINK is a link number — 0 the robot's base, k the link joint k moves — not `{}`",
            link.trim()
        )
    })?;
    Ok(thermokin_diagnose::Accelerometer { name: name.to_string(), link })
}
