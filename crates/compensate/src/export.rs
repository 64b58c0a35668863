//! Writers for a run's results: the authors' results layout (so a run diffs against their files) and a
//! joint-target CSV. Robot programs are in [`crate::program`]. Writers take any `io::Write`; the caller
//! makes it atomic.

use std::io::{self, Write};

use thermokin_chain::xyz_angles;

use crate::run::{RunOutput, TargetResult};

fn euler_deg(r: &TargetResult, reached: bool) -> [f64; 3] {
    let pose = if reached { &r.reached } else { &r.programmed };
    let a = xyz_angles(pose.rotation.to_rotation_matrix().matrix()).map(f64::to_degrees);
    [a.x, a.y, a.z]
}

fn join(values: &[f64]) -> String {
    values.iter().map(|v| format!("{v}")).collect::<Vec<_>>().join(",")
}

/// The results in the authors' column layout: two header rows; per target `time`, label, programmed
/// X,Y,Z, reached X,Y,Z, differences (programmed − reached), programmed RX,RY,RZ, reached RX,RY,RZ
/// (X-Y-Z Euler, degrees), the orientation error (rotation vector, degrees: DRX,DRY,DRZ), joints
/// A1..An, then our `status`; `MIN`/`MAX` trailer rows. With `with_time = false` the time column is left
/// out, as in the authors' static file.
pub fn write_results_csv(out: &mut impl Write, run: &RunOutput, with_time: bool) -> io::Result<()> {
    let n = run.rows.first().map_or(6, |r| r.joints_deg.len());
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
        let time = if with_time { format!("{},", r.time_min) } else { String::new() };
        writeln!(
            out,
            "{time}{},{},{},{},{},{},{},{},{:?}",
            r.label,
            join(&[p.x, p.y, p.z]),
            join(&[q.x, q.y, q.z]),
            join(&r.position_deviation_mm),
            join(&euler_deg(r, false)),
            join(&euler_deg(r, true)),
            join(&r.orientation_deviation_deg),
            join(&r.joints_deg),
            r.status
        )?;
    }
    let s = &run.summary;
    let pad = if with_time { ",,,,,,," } else { ",,,,,," };
    writeln!(out, "{pad}MIN,{},,,,,,MIN,{}", join(&s.position_mm.min), join(&s.orientation_deg.min))?;
    writeln!(out, "{pad}MAX,{},,,,,,MAX,{}", join(&s.position_mm.max), join(&s.orientation_deg.max))?;
    Ok(())
}

/// The compensated joint targets: `time_min,label,A1..An` (degrees), one row per target and time.
pub fn write_joint_csv(out: &mut impl Write, run: &RunOutput) -> io::Result<()> {
    let n = run.rows.first().map_or(6, |r| r.joints_deg.len());
    let joints: Vec<String> = (1..=n).map(|i| format!("A{i}")).collect();
    writeln!(out, "time_min,label,{},status", joints.join(","))?;
    for r in &run.rows {
        writeln!(out, "{},{},{},{:?}", r.time_min, r.label, join(&r.joints_deg), r.status)?;
    }
    Ok(())
}
