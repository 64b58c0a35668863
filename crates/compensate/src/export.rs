//! Writers for a run's results: the authors' results layout (so a run diffs against their files) and a
//! joint-target CSV. Robot programs are in [`crate::program`]. Writers take any `io::Write`; the caller
//! makes it atomic.

use std::io::{self, Write};

use serde::Serialize;
use thermokin_chain::{JointKind, quaternion_wxyz, xyz_angles_for_output};
use thermokin_io::units::{degrees, degrees3, joint_value_out, rounded};

use crate::run::{Axes, RunOutput, Summary, TargetResult};

/// The layouts a run's results are written in.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum ResultsFormat {
    /// The authors' results layout ([`write_results_csv`]).
    #[default]
    Authors,
    /// Long (tidy) CSV ([`write_long_csv`]).
    Long,
    /// JSON ([`write_results_json`]).
    Json,
    /// The compensated joints only ([`write_joint_csv`]).
    Joints,
}

thermokin_chain::choices!(
    ResultsFormat,
    "results format",
    [
        ("authors", "the authors' CSV layout (two header rows; diffs against their files)", ResultsFormat::Authors),
        (
            "long",
            "one row per target and value: time_min,label,status,quantity,component,value,unit (pandas, SQL)",
            ResultsFormat::Long
        ),
        ("json", "{\"summary\": …, \"rows\": […]}", ResultsFormat::Json),
        (
            "joints",
            "the compensated joints: time_min,label,A1..An,status (degrees; mm for prismatic joints)",
            ResultsFormat::Joints
        ),
    ]
);

impl ResultsFormat {
    /// Writes `run` in this layout; `with_time` adds the time column of the authors' layout.
    pub fn write(self, out: &mut impl Write, run: &RunOutput, with_time: bool) -> io::Result<()> {
        match self {
            ResultsFormat::Authors => write_results_csv(out, run, with_time),
            ResultsFormat::Long => write_long_csv(out, run),
            ResultsFormat::Json => write_results_json(out, run),
            ResultsFormat::Joints => write_joint_csv(out, run),
        }
    }
}

/// Decimals written for millimetres and degrees: 1e-9, the solver's tolerance. Below it a number is
/// binary noise (`640.9999999999994` is written `641`, `5.68e-13` is written `0`).
const DECIMALS: i32 = 9;

/// Decimals written for joint angles: 1e-12°, because a joint error is multiplied by the arm's lever
/// (1e-9° × 1 m would already be 1.7e-8 mm, above the solver's tolerance).
const JOINT_DECIMALS: i32 = 12;

/// `x` at the written precision of mm and degrees; −0 becomes 0.
fn meaningful(x: f64) -> f64 {
    rounded(x, DECIMALS)
}

/// A row's joint values as files give them (degrees, mm for prismatic joints).
fn joints_out(run: &RunOutput, r: &TargetResult) -> Vec<f64> {
    run.kinds.iter().zip(&r.joints).map(|(&k, &v)| joint_value_out(k, v)).collect()
}

fn join_joints(values: &[f64]) -> String {
    values.iter().map(|&v| format!("{}", rounded(v, JOINT_DECIMALS))).collect::<Vec<_>>().join(",")
}

fn euler_deg(r: &TargetResult, reached: bool) -> [f64; 3] {
    let pose = if reached { &r.reached } else { &r.programmed };
    let a = xyz_angles_for_output(pose.rotation.to_rotation_matrix().matrix());
    degrees3([a.x, a.y, a.z])
}

/// The summary as the results documents carry it: millimetres and degrees.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SummaryOut {
    /// Solves in the run.
    pub solves: usize,
    /// Solves that did not converge.
    pub failures: usize,
    /// The failed targets, named.
    pub failed: Vec<String>,
    /// Programmed − reached, mm (Tables 15, 17).
    pub position_mm: Axes,
    /// Orientation error rotation vector, degrees (Tables 13, 18).
    pub orientation_deg: Axes,
    /// Largest position error, mm.
    pub max_position_error_mm: f64,
    /// Largest orientation error angle, degrees.
    pub max_orientation_error_deg: f64,
    /// Largest position error of the uncompensated program over the reached targets, mm.
    pub max_uncompensated_error_mm: f64,
}

impl std::fmt::Display for SummaryOut {
    /// The summary as `compensate` prints it: solves and failures (the failed targets named, twenty at
    /// most), the position and orientation deviations' ranges, the largest errors — or, when no target
    /// was reached, that none was.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        writeln!(f, "solves {}  failed {}", self.solves, self.failures)?;
        if !self.failed.is_empty() {
            let shown: Vec<&str> = self.failed.iter().take(20).map(String::as_str).collect();
            let more = if self.failed.len() > 20 {
                format!(" … and {} more (status column of the results)", self.failed.len() - 20)
            } else {
                String::new()
            };
            writeln!(f, "not reached (left out of the statistics below): {}{more}", shown.join(", "))?;
        }
        if self.failures >= self.solves {
            // Nothing reached: no deviation to give a range of (the statistics' empty extremes are ±∞).
            return writeln!(
                f,
                "no target reached: nothing to compensate with — check the targets' units (millimetres) and that they lie in the robot's reach"
            );
        }
        let ranges = |a: &Axes| {
            format!(
                "min {:+.3e} {:+.3e} {:+.3e}   max {:+.3e} {:+.3e} {:+.3e}",
                a.min[0], a.min[1], a.min[2], a.max[0], a.max[1], a.max[2]
            )
        };
        writeln!(f, "position deviation (programmed − reached), mm:  {}", ranges(&self.position_mm))?;
        writeln!(f, "orientation deviation (rotation vector), deg:   {}", ranges(&self.orientation_deg))?;
        writeln!(
            f,
            "largest error: compensated {:.3e} mm, {:.3e}°; uncompensated program {:.3} mm",
            self.max_position_error_mm, self.max_orientation_error_deg, self.max_uncompensated_error_mm
        )
    }
}

impl SummaryOut {
    /// The summary in millimetres and degrees.
    pub fn of(s: &Summary) -> Self {
        let deg = |a: &Axes| Axes { min: degrees3(a.min), max: degrees3(a.max) };
        Self {
            solves: s.solves,
            failures: s.failures,
            failed: s.failed.clone(),
            position_mm: s.position_mm,
            orientation_deg: deg(&s.orientation_rad),
            max_position_error_mm: s.max_position_error_mm,
            max_orientation_error_deg: degrees(s.max_orientation_error_rad),
            max_uncompensated_error_mm: s.max_uncompensated_error_mm,
        }
    }
}

fn join(values: &[f64]) -> String {
    values.iter().map(|&v| format!("{}", meaningful(v))).collect::<Vec<_>>().join(",")
}

/// The results in the authors' column layout: two header rows; per target `time`, label, programmed
/// X,Y,Z, reached X,Y,Z, differences (programmed − reached), programmed RX,RY,RZ, reached RX,RY,RZ
/// (X-Y-Z Euler, degrees), the orientation error (rotation vector, degrees: DRX,DRY,DRZ), joints
/// A1..An, then our `status`; `MIN`/`MAX` trailer rows. With `with_time = false` the time column is left
/// out, as in the authors' static file.
pub fn write_results_csv(out: &mut impl Write, run: &RunOutput, with_time: bool) -> io::Result<()> {
    let n = run.kinds.len();
    let lead = if with_time { "," } else { "" };
    writeln!(
        out,
        "{lead},Programmed coordinate,,,Reached coordinates,,,Coordinates differences,,,Programmed TCP orientation,,,Reached TCP orientation,,,TCP orientation difference,,,{}",
        ",".repeat(n + 1)
    )?;
    let joints: Vec<String> = (1..=n).map(|i| format!("A{i}")).collect();
    writeln!(
        out,
        "{}P#,X,Y,Z,X,Y,Z,DX,DY,DZ,RX,RY,RZ,RX,RY,RZ,DRX,DRY,DRZ,{},status",
        if with_time { "Time (min)," } else { "" },
        joints.join(",")
    )?;
    for r in &run.rows {
        let p = r.programmed.translation.vector;
        let q = r.reached.translation.vector;
        let time = if with_time { format!("{},", meaningful(r.time_min)) } else { String::new() };
        writeln!(
            out,
            "{time}{},{},{},{},{},{},{},{},{:?}",
            r.label,
            join(&[p.x, p.y, p.z]),
            join(&[q.x, q.y, q.z]),
            join(&r.position_deviation_mm),
            join(&euler_deg(r, false)),
            join(&euler_deg(r, true)),
            join(&degrees3(r.orientation_deviation_rad)),
            join_joints(&joints_out(run, r)),
            r.status
        )?;
    }
    let s = SummaryOut::of(&run.summary);
    let pad = if with_time { ",,,,,,," } else { ",,,,,," };
    writeln!(out, "{pad}MIN,{},,,,,,MIN,{}", join(&s.position_mm.min), join(&s.orientation_deg.min))?;
    writeln!(out, "{pad}MAX,{},,,,,,MAX,{}", join(&s.position_mm.max), join(&s.orientation_deg.max))?;
    Ok(())
}

/// The compensated joint targets: `time_min,label,A1..An` (degrees), one row per target and time.
pub fn write_joint_csv(out: &mut impl Write, run: &RunOutput) -> io::Result<()> {
    write_joint_header(out, run.kinds.len())?;
    for r in &run.rows {
        write_joint_row(out, &run.kinds, r)?;
    }
    Ok(())
}

/// The header of the joint CSV for `n` joints.
pub(crate) fn write_joint_header(out: &mut impl Write, n: usize) -> io::Result<()> {
    let joints: Vec<String> = (1..=n).map(|i| format!("A{i}")).collect();
    writeln!(out, "time_min,label,{},status", joints.join(","))
}

/// One row of the joint CSV: the joints in degrees (mm for prismatic joints).
pub(crate) fn write_joint_row(out: &mut impl Write, kinds: &[JointKind], r: &TargetResult) -> io::Result<()> {
    let joints: Vec<f64> = kinds.iter().zip(&r.joints).map(|(&k, &v)| joint_value_out(k, v)).collect();
    writeln!(out, "{},{},{},{:?}", meaningful(r.time_min), r.label, join_joints(&joints), r.status)
}

/// The results in long format for notebooks and databases: one header row, then one row per target,
/// time and value — `time_min,label,status,quantity,component,value,unit` — so that
/// `pandas.read_csv(...).pivot_table(...)` or a SQL `GROUP BY` needs no knowledge of the layout.
///
/// Quantities: `programmed_position`, `reached_position`, `deviation` (programmed − reached) in mm with
/// components x, y, z; `programmed_orientation`, `reached_orientation` as quaternions (w, x, y, z);
/// `orientation_deviation` (rotation vector) in degrees; `joint` (A1…An) in degrees, mm for prismatic
/// joints; `uncompensated_error` (norm) in mm. Rows of targets that were not reached carry their status
/// and only the programmed pose.
pub fn write_long_csv(out: &mut impl Write, run: &RunOutput) -> io::Result<()> {
    writeln!(out, "time_min,label,status,quantity,component,value,unit")?;
    for r in &run.rows {
        let head = format!("{},{},{:?}", meaningful(r.time_min), r.label, r.status);
        let mut row = |quantity: &str, component: &str, value: f64, unit: &str| {
            let decimals = if quantity == "joint" { JOINT_DECIMALS } else { DECIMALS };
            writeln!(out, "{head},{quantity},{component},{},{unit}", rounded(value, decimals))
        };
        let xyz = ["x", "y", "z"];
        let wxyz = ["w", "x", "y", "z"];
        let p = r.programmed.translation.vector;
        for (c, v) in xyz.iter().zip(p.iter()) {
            row("programmed_position", c, *v, "mm")?;
        }
        for (c, v) in wxyz.iter().zip(quaternion_wxyz(&r.programmed.rotation)) {
            row("programmed_orientation", c, v, "1")?;
        }
        if !r.converged() {
            continue;
        }
        for (c, v) in xyz.iter().zip(r.reached.translation.vector.iter()) {
            row("reached_position", c, *v, "mm")?;
        }
        for (c, v) in wxyz.iter().zip(quaternion_wxyz(&r.reached.rotation)) {
            row("reached_orientation", c, v, "1")?;
        }
        for (c, v) in xyz.iter().zip(r.position_deviation_mm) {
            row("deviation", c, v, "mm")?;
        }
        for (c, v) in xyz.iter().zip(degrees3(r.orientation_deviation_rad)) {
            row("orientation_deviation", c, v, "deg")?;
        }
        for (i, (v, kind)) in joints_out(run, r).iter().zip(&run.kinds).enumerate() {
            let unit = if *kind == thermokin_chain::JointKind::Revolute { "deg" } else { "mm" };
            row("joint", &format!("A{}", i + 1), *v, unit)?;
        }
        row("uncompensated_error", "norm", r.uncompensated_error_mm, "mm")?;
    }
    Ok(())
}

/// One target of the JSON results.
#[derive(Serialize)]
struct JsonRow<'a> {
    time_min: f64,
    label: &'a str,
    status: String,
    programmed_mm: [f64; 3],
    programmed_quaternion_wxyz: [f64; 4],
    reached_mm: Option<[f64; 3]>,
    deviation_mm: Option<[f64; 3]>,
    orientation_deviation_deg: Option<[f64; 3]>,
    joints_deg: Option<Vec<f64>>,
    uncompensated_error_mm: Option<f64>,
}

/// The results as one JSON document `{"summary": {…}, "rows": [{…}, …]}`: the same fields as the long
/// CSV, one object per target and time; fields of targets not reached are `null`.
pub fn write_results_json(out: &mut impl Write, run: &RunOutput) -> io::Result<()> {
    let m3 = |v: [f64; 3]| v.map(meaningful);
    let rows: Vec<JsonRow<'_>> = run
        .rows
        .iter()
        .map(|r| {
            let ok = r.converged();
            let p = r.programmed.translation.vector;
            let reached = r.reached.translation.vector;
            JsonRow {
                time_min: meaningful(r.time_min),
                label: &r.label,
                status: format!("{:?}", r.status),
                programmed_mm: m3([p.x, p.y, p.z]),
                programmed_quaternion_wxyz: quaternion_wxyz(&r.programmed.rotation).map(meaningful),
                reached_mm: ok.then(|| m3([reached.x, reached.y, reached.z])),
                deviation_mm: ok.then(|| m3(r.position_deviation_mm)),
                orientation_deviation_deg: ok.then(|| m3(degrees3(r.orientation_deviation_rad))),
                joints_deg: ok.then(|| joints_out(run, r).iter().map(|&v| rounded(v, JOINT_DECIMALS)).collect()),
                uncompensated_error_mm: ok.then(|| meaningful(r.uncompensated_error_mm)),
            }
        })
        .collect();
    #[derive(Serialize)]
    struct Doc<'a> {
        summary: SummaryOut,
        rows: Vec<JsonRow<'a>>,
    }
    let doc = Doc { summary: SummaryOut::of(&run.summary), rows };
    serde_json::to_writer(&mut *out, &doc).map_err(io::Error::other)?;
    writeln!(out)
}
