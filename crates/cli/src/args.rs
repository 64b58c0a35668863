//! Command-line arguments (clap) and the parsers of their small languages (joint lists, poses, profiles).

use std::path::PathBuf;

use clap::{Args, Parser, Subcommand, ValueEnum};
use thermokin_deform::TimeProfile;

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

Examples:
  thermokin fk --robot configs/irb140.toml --joints 0,30,10,0,-40,0
  thermokin ik --robot configs/irb140.toml --pose 600,0,400,0,90,0
  thermokin compensate --robot configs/irb140.toml --deformation fixtures/paper/deformations-case-study.toml \\
      --targets fixtures/paper/table12-targets.csv --out results.csv --program prog.mod
  thermokin compensate ... --profile linear-grow:180 --duration 200 --step 1 --plot plots/
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
    /// Generate a measurement set from hidden effects (to check what the diagnosis finds).
    #[command(
        after_help = "Examples:\n  thermokin simulate --robot configs/irb140.toml --effect joint_offset:2 --noise 0.005 --poses 240 --minutes 240 -o M.csv\n  thermokin simulate --robot configs/irb140.toml --effect link_deviation:3=0.3,-0.2,0.25,0.02,0,0.015 --effect base_frame -o M.csv\n\nEffect: KIND[:JOINT][=VALUES] with KIND one of base_frame, tool_frame, joint_offset, link_deviation,\njoint_compliance, joint_scale (gear ratio, Δq = s·q), periodic (Δq = a1 sin q + b1 cos q + a2 sin 2q + b2 cos 2q),\nthermal_drift (linear), thermal_drift_exp (exponential); values in mm, degrees, minutes and degrees per N·m (default: a seeded random effect of typical size)."
    )]
    Simulate(SimulateArgs),
    /// Reproduce the paper's case studies (Tables 13–18) from the bundled fixtures, and compare with the
    /// authors' full files (bundled in fixtures/paper/authors).
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
        /// Tip link (default: the single leaf; an error lists the candidates when there are several).
        #[arg(long)]
        tip: Option<String>,
        /// Output TOML (written atomically).
        #[arg(short, long, value_name = "FILE")]
        out: PathBuf,
    },
    /// Export a robot, optionally deformed by a deviation table, as URDF whose FK equals the model's.
    #[command(
        after_help = "Example:\n  thermokin urdf export --robot configs/irb140.toml --deformation fixtures/paper/deformations-measured.toml -o deformed.urdf"
    )]
    Export {
        #[command(flatten)]
        robot: Box<RobotArgs>,
        /// Output URDF (written atomically).
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
    /// URDF tip link (default: the single leaf).
    #[arg(long, value_name = "LINK")]
    pub tip: Option<String>,
    /// Replace the robot file's tool: the TCP in the last joint's frame, x,y,z (mm) and the orientation in
    /// the --orientation convention (or a JSON pose).
    #[arg(long, value_name = "X,Y,Z,A,B,C", allow_hyphen_values = true)]
    pub tool_pose: Option<String>,
    /// Replace the robot file's base: the robot base in the world frame, as --tool-pose.
    #[arg(long, value_name = "X,Y,Z,A,B,C", allow_hyphen_values = true)]
    pub base_pose: Option<String>,
    /// Orientation convention of --pose, --tool-pose and --base-pose, and of a measurement file's
    /// orientation columns: xyz (X-Y-Z Euler degrees, R = Rx·Ry·Rz, the paper's; columns rx,ry,rz), rpy
    /// (ROS roll,pitch,yaw degrees, R = Rz·Ry·Rx; columns rx,ry,rz = roll, pitch, yaw) or quat (w,x,y,z;
    /// columns qw,qx,qy,qz).
    #[arg(long, value_name = "CONVENTION", default_value = "xyz", value_parser = parse_orientation)]
    pub orientation: thermokin_io::Orientation,
    /// Deviation table (the authors' CSV `Dx,Dy,Dz,Dox,Doy,Doz`, or TOML), mm and degrees.
    #[arg(long, value_name = "FILE")]
    pub deformation: Option<PathBuf>,
    /// Growth of the table with operating time: static, linear:T (plateau after T min), linear-grow:T
    /// (no plateau, the authors' transient file), exp:TAU, cubic:C1,C2,C3, temperature:LOG.csv (the table
    /// then holds values per kelvin, scaled by the mean rise of the logged temperatures over their first
    /// row; LOG.csv is `time_min,<sensor>,<sensor>,…` in minutes and °C, one row per reading, linearly
    /// interpolated), or a profile TOML file.
    #[arg(long, value_name = "PROFILE", value_parser = parse_profile)]
    pub profile: Option<thermokin_deform::ProfileSpec>,
    /// Operating time, minutes since the cold start of a warm-up: for a robot file whose rows drift with
    /// time (a calibrated robot, `[[drift]]`), and for fk/ik with --profile. A targets file's `time_min`
    /// column overrides it per target.
    #[arg(long, value_name = "MIN")]
    pub time: Option<f64>,
    /// Sensor readings, °C, for a robot file whose rows drift per kelvin: `temp_j2=35.1,temp_j3=30.2`
    /// (the names of the measurement files' temp_ columns; the prefix may be left out). A targets file's
    /// `temp_*` columns override them per target.
    #[arg(long, value_name = "NAME=C,...")]
    pub temperature: Option<String>,
    /// A payload on the flange (the probe, a gripper, a load): `KG@X,Y,Z`, its centre in the flange's
    /// frame in mm, e.g. `2.5@0,0,80`. Gravity compliance of a calibrated robot bends under it (it replaces
    /// the payload the robot file was calibrated with); the diagnosis merges it with the last link's mass.
    #[arg(long, value_name = "KG@X,Y,Z")]
    pub payload: Option<String>,
    /// How the table acts on the robot: canonical (Table 7: Trans·Rx·Ry·Rz at each joint) or
    /// coppeliasim (the authors' scene: world shift and Euler-angle addition of each joint object, at home).
    #[arg(long, value_enum, default_value_t = Semantics::Canonical)]
    pub semantics: Semantics,
}

/// How a transient run moves from one update to the next (`thermokin_compensate::Accumulation`).
#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum AccumulateArg {
    /// The profile's share of the table, applied to the undeformed robot at every update.
    FromNominal,
    /// The change of the share since the previous update, applied to the deformed robot.
    Increments,
}

impl From<AccumulateArg> for thermokin_compensate::Accumulation {
    fn from(a: AccumulateArg) -> Self {
        match a {
            AccumulateArg::FromNominal => Self::FromNominal,
            AccumulateArg::Increments => Self::Increments,
        }
    }
}

/// Deviation-table semantics.
#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum Semantics {
    /// Table 7's reading (this library's model).
    Canonical,
    /// The authors' CoppeliaSim edits, applied at the home configuration.
    Coppeliasim,
}

/// `fk` arguments.
#[derive(Args, Debug)]
pub struct FkArgs {
    #[command(flatten)]
    pub robot: RobotArgs,
    /// Joint values, degrees (mm for prismatic joints), comma separated.
    #[arg(long, value_name = "Q1,...,QN", allow_hyphen_values = true)]
    pub joints: String,
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
    #[arg(long, value_name = "X,Y,Z,RX,RY,RZ", allow_hyphen_values = true)]
    pub pose: String,
    /// Solve for the position only (orientation free).
    #[arg(long)]
    pub position_only: bool,
    /// Seed joint values, degrees (default: all zero).
    #[arg(long, value_name = "Q1,...,QN", allow_hyphen_values = true)]
    pub seed: Option<String>,
    /// Random restarts when a solve stalls.
    #[arg(long, default_value_t = 100)]
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
    /// Program of targets: CSV `,X,Y,Z` (mm) with optional `RX,RY,RZ` (degrees; default 0,90,0).
    #[arg(long, value_name = "FILE")]
    pub targets: PathBuf,
    /// The results (written atomically), in --format.
    #[arg(long, value_name = "FILE")]
    pub out: PathBuf,
    /// Layout of --out: authors (their CSV layout, two header rows, diffs against their files), long
    /// (one row per target, time and value: time_min,label,status,quantity,component,value,unit — for
    /// pandas and SQL), json ({"summary": …, "rows": […]}) or joints (time_min,label,A1..An,status).
    #[arg(long, value_enum, default_value_t = ResultsFormat::Authors)]
    pub format: ResultsFormat,
    /// Transient cycle length, minutes: with --profile (default 200), or to run a calibrated robot's
    /// warm-up (every target at every step).
    #[arg(long, value_name = "MIN")]
    pub duration: Option<f64>,
    /// Model update interval, minutes (transient runs).
    #[arg(long, value_name = "MIN", default_value_t = 1.0)]
    pub step: f64,
    /// How each update brings the table into force (with --profile): from-nominal (the profile's share
    /// applied to the undeformed robot; the state at t depends on t alone) or increments (only the change
    /// since the previous update, applied to the robot as already deformed — what the authors' script
    /// did every minute, paper section 4 and Appendix A, Figure A5; with --semantics coppeliasim the
    /// state then depends on the path, see docs/paper-reproduction.md).
    #[arg(long, value_enum, value_name = "HOW", default_value_t = AccumulateArg::FromNominal)]
    pub accumulate: AccumulateArg,
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
    /// Controller language of --program: abb, kuka or ur (default: from the file extension).
    #[arg(long, value_enum)]
    pub controller: Option<ControllerArg>,
    /// Motion speed in the controller's terms: ABB speeddata (v100), KUKA axis % (30), UR rad/s (1.05).
    #[arg(long, value_name = "SPEED")]
    pub speed: Option<String>,
    /// Zone in the controller's terms: ABB zonedata (fine, z10), KUKA fine or C_PTP, UR blend radius m (0).
    #[arg(long, value_name = "ZONE")]
    pub zone: Option<String>,
    /// ABB tooldata of the motion instructions.
    #[arg(long, value_name = "NAME", default_value = "tool0")]
    pub tooldata: String,
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
    /// Frame of the measurements: base (a base misalignment is a candidate) or tracker (an unknown
    /// registration, always estimated).
    #[arg(long, value_enum, default_value_t = FrameArg::Base)]
    pub frame: FrameArg,
    /// Tool point: known (a tool error is a candidate) or unknown (always estimated).
    #[arg(long, value_enum, default_value_t = ToolArg::Known)]
    pub tool: ToolArg,
    /// Cross-validation folds.
    #[arg(long, default_value_t = 5)]
    pub folds: usize,
    /// Write the report as JSON.
    #[arg(long, value_name = "FILE")]
    pub json: Option<PathBuf>,
    /// Write SVG plots (residuals before/after, held-out error per effect) into this directory.
    #[arg(long, value_name = "DIR")]
    pub plot: Option<PathBuf>,
    /// How poses are grouped into validation folds. neighbourhood (default): time-grouped when the data
    /// span time; otherwise blocks of neighbouring arm configurations (4 per fold, k-means in joint
    /// space; single poses below 10 per block), so that an effect is scored on poses unlike those it was
    /// fitted on and the gate counts blocks, not poses. time: time-grouped, or single poses shuffled.
    /// region: leave one workspace quadrant out. configuration: leave one arm branch out.
    #[arg(long, value_enum, default_value_t = FoldsByArg::Neighbourhood)]
    pub folds_by: FoldsByArg,
    /// Unit of the measurement files' revolute joint columns: deg (default) or rad (ROS, robot SDKs).
    #[arg(long, value_enum, default_value_t = JointUnitsArg::Deg)]
    pub joint_units: JointUnitsArg,
    /// The measurement noise per axis (one standard deviation, mm) — your tracker's specification, e.g.
    /// 0.01. The verdict then says whether what remains is that noise or an effect the catalogue lacks.
    #[arg(long, value_name = "MM")]
    pub noise: Option<f64>,
    /// Weight of measured orientations (rx, ry, rz columns: a 6-D probe) as a lever in mm: a rotation
    /// error of δφ counts as the displacement lever·δφ it causes that far from the tool point. 0 fits
    /// positions only. Ignored when the files carry no orientation.
    #[arg(long, value_name = "MM", default_value_t = 100.0)]
    pub orientation_lever: f64,
    /// The orientation noise per axis of a 6-D probe (one standard deviation, degrees), e.g. 0.01: with
    /// --noise, the verdict's noise floor then includes the orientations.
    #[arg(long, value_name = "DEG")]
    pub orientation_noise: Option<f64>,
    /// Write the identified robot — every chosen effect, the model the report scores: registration (as
    /// the base row, so that FK gives the measurement frame), tool point, base frame, joint offsets, link
    /// deviations, gear ratios, cyclic errors, gravity compliance (with the --payload measured with) and
    /// each drifting row with its law — as a robot TOML that fk, ik and compensate accept (--time,
    /// --temperature, --payload give the state). A FILE ending in .urdf holds the geometry and zeros only
    /// and names in its header what it cannot hold. Refused when the chosen model does not beat the
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

/// `--folds-by`.
#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum FoldsByArg {
    /// Time-grouped folds, or blocks of neighbouring arm configurations.
    Neighbourhood,
    /// Time-grouped folds (or a seeded shuffle of single poses).
    Time,
    /// Leave one workspace region out.
    Region,
    /// Leave one arm configuration out.
    Configuration,
}

/// `--joint-units` of measurement files.
#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum JointUnitsArg {
    /// Degrees.
    Deg,
    /// Radians.
    Rad,
}

/// `--format` of the results.
#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum ResultsFormat {
    /// The authors' results layout.
    Authors,
    /// Long (tidy) CSV.
    Long,
    /// JSON.
    Json,
    /// The compensated joints only: time_min,label,A1..An,status (degrees; mm for prismatic joints).
    Joints,
}

/// `--controller`.
#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum ControllerArg {
    /// ABB RAPID (MoveAbsJ to jointtargets).
    Abb,
    /// KUKA KRL (PTP to E6AXIS).
    Kuka,
    /// Universal Robots URScript (movej).
    Ur,
}

/// `--frame`.
#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum FrameArg {
    /// Robot base frame.
    Base,
    /// Laser-tracker frame.
    Tracker,
}

/// `--tool`.
#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum ToolArg {
    /// The robot description's tool.
    Known,
    /// Estimated.
    Unknown,
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
    #[arg(long, default_value_t = 0.005)]
    pub noise: f64,
    /// Number of poses.
    #[arg(long, default_value_t = 240)]
    pub poses: usize,
    /// Time span of the measurements, minutes.
    #[arg(long, default_value_t = 240.0)]
    pub minutes: f64,
    /// Also measure the tool's orientation (a 6-D probe: rx, ry, rz columns), with this noise per axis
    /// in degrees (standard deviation of a small random turn).
    #[arg(long, value_name = "DEG")]
    pub orientation_noise: Option<f64>,
    /// Seed.
    #[arg(long, default_value_t = 1)]
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

/// Parses `--profile` ([`TimeProfile::parse_spec`]): an inline law, or the file to read later.
pub fn parse_profile(s: &str) -> Result<thermokin_deform::ProfileSpec, String> {
    TimeProfile::parse_spec(s).map_err(|e| e.to_string())
}

/// Parses `--orientation`.
pub fn parse_orientation(s: &str) -> Result<thermokin_io::Orientation, String> {
    s.parse()
}

/// Parses a comma-separated list of finite numbers, naming the flag in errors.
pub fn parse_list(flag: &str, s: &str) -> anyhow::Result<Vec<f64>> {
    s.split(',')
        .enumerate()
        .map(|(i, v)| {
            let x: f64 = v
                .trim()
                .parse()
                .map_err(|_| anyhow::anyhow!("--{flag}: value {} `{}` is not a number", i + 1, v.trim()))?;
            anyhow::ensure!(x.is_finite(), "--{flag}: value {} is not finite", i + 1);
            Ok(x)
        })
        .collect()
}
