//! The bad-input table: every reader and flag, through the command line a user types. Each case pins the
//! exit status and the error text; file errors name the file, the line and the field (or XML element).

use std::path::PathBuf;
use std::process::Command;

use thermokin_testdata::workspace;

struct Case {
    name: &'static str,
    /// Files to create in a fresh directory, `{dir}` in args points there.
    files: &'static [(&'static str, &'static [u8])],
    args: &'static [&'static str],
    code: i32,
    /// Pinned text of the error (a substring of stderr, or stdout for exit 3).
    needle: &'static str,
}

const ROBOT: &str = "configs/irb140.toml";
const TABLE: &str = "fixtures/paper/deformations-case-study.toml";
const J6: &str = "0,0,0,0,0,0";
/// The bundled IRB 140 with joint 2's row drifting exponentially: a calibrated robot file.
const DRIFTING: &[u8] = concat!(
    include_str!("../../../../configs/irb140.toml"),
    "\n[[drift]]\nrow = 2\nerror = [0.2, 0.0, 0.1, 0.0, 0.01, 0.0]\nprofile = { kind = \"exponential\", tau_min = 40.0 }\n"
)
.as_bytes();

const GOOD_DEV: &[u8] =
    b"Dx,Dy,Dz,Dox,Doy,Doz\n1,1,1,1,1,1\n1,1,1,1,1,1\n1,1,1,1,1,1\n1,1,1,1,1,1\n1,1,1,1,1,1\n1,1,1,1,1,1\n";
const JOINT: &str = "[[joint]]\naxis = \"Z\"\noffset_mm = [0.0, 0.0, 100.0]\n";

macro_rules! robot_case {
    ($name:expr, $toml:expr, $needle:expr) => {
        Case {
            name: $name,
            files: &[("robot.toml", $toml)],
            args: &["fk", "--robot", "{dir}/robot.toml", "--joints", "0"],
            code: 2,
            needle: $needle,
        }
    };
}
macro_rules! dev_case {
    ($name:expr, $csv:expr, $needle:expr) => {
        Case {
            name: $name,
            files: &[("dev.csv", $csv)],
            args: &["fk", "--robot", ROBOT, "--deformation", "{dir}/dev.csv", "--joints", J6],
            code: 2,
            needle: $needle,
        }
    };
}
macro_rules! targets_case {
    ($name:expr, $csv:expr, $needle:expr) => {
        Case {
            name: $name,
            files: &[("t.csv", $csv)],
            args: &[
                "compensate",
                "--robot",
                ROBOT,
                "--deformation",
                TABLE,
                "--targets",
                "{dir}/t.csv",
                "--out",
                "{dir}/out.csv",
            ],
            code: 2,
            needle: $needle,
        }
    };
}
macro_rules! meas_case {
    ($name:expr, $csv:expr, $needle:expr) => {
        Case {
            name: $name,
            files: &[("m.csv", $csv)],
            args: &["diagnose", "--robot", ROBOT, "--measurements", "{dir}/m.csv"],
            code: 2,
            needle: $needle,
        }
    };
}
macro_rules! urdf_case {
    ($name:expr, $xml:expr, $needle:expr) => {
        Case {
            name: $name,
            files: &[("r.urdf", $xml)],
            args: &["fk", "--robot", "{dir}/r.urdf", "--joints", "0"],
            code: 2,
            needle: $needle,
        }
    };
}

const CASES: &[Case] = &[
    // Robot TOML.
    robot_case!("unknown key", b"[[joint]]\naxis = \"Z\"\noffset_mm = [0.0, 0.0, 100.0]\n\ncolour = \"red\"\n", "robot.toml:5: colour: unknown field `colour`"),
    robot_case!("length in metres", b"[[joint]]\naxis = \"Z\"\noffset_m = [0.0, 0.0, 0.1]\n", "offset_m: unknown field `offset_m`"),
    robot_case!("units hint", b"[[joint]]\naxis = \"Z\"\noffset_m = [0.0, 0.0, 0.1]\n", "robot files are in millimetres and degrees"),
    robot_case!("zero axis", b"[[joint]]\naxis = [0.0, 0.0, 0.0]\noffset_mm = [0.0, 0.0, 1.0]\n", "robot.toml:1: joint[1].axis: [0, 0, 0] is not a usable axis (zero or not finite)"),
    robot_case!("axis name", b"[[joint]]\naxis = \"W\"\noffset_mm = [0.0, 0.0, 1.0]\n", "robot.toml:1: joint[1].axis: `W` is not an axis"),
    robot_case!("nan offset", b"[[joint]]\naxis = \"X\"\noffset_mm = [nan, 0.0, 1.0]\n", "robot.toml:1: joint[1].offset_mm: values must be finite numbers (no nan or inf)"),
    robot_case!("inf in tool", b"[[joint]]\naxis = \"Z\"\noffset_mm = [0.0, 0.0, 100.0]\n[tool]\ntranslation_mm = [inf, 0.0, 0.0]\n", "robot.toml:4: tool.translation_mm: values must be finite numbers"),
    robot_case!("limits reversed", b"[[joint]]\naxis = \"X\"\noffset_mm = [0.0, 0.0, 1.0]\nlimits = [10.0, -10.0]\n", "robot.toml:1: joint[1].limits: lower limit 10 is above upper limit -10"),
    robot_case!("truncated", b"[[joint]]\naxis = \"X\"\noffset_mm = [0.0, 0.0", "robot.toml:3: toml: unclosed array"),
    robot_case!("missing key", b"[[joint]]\naxis = \"X\"\n", "robot.toml:1: offset_mm: missing field `offset_mm`"),
    robot_case!("duplicate joints", b"[[joint]]\nname = \"A1\"\naxis = \"Z\"\noffset_mm = [0.0, 0.0, 1.0]\n[[joint]]\nname = \"A1\"\naxis = \"Y\"\noffset_mm = [0.0, 0.0, 1.0]\n", "robot.toml:5: joint[2].name: duplicate joint name `A1`"),
    robot_case!("empty file", b"", "robot.toml: joint: no [[joint]] rows"),
    robot_case!("non-UTF-8", b"name = \"\xff\"\n", "robot.toml:1: text: not UTF-8"),
    // Deviation tables.
    dev_case!("empty", b"", "dev.csv:1: header: empty file"),
    dev_case!("missing column", b"Dx,Dy,Dz,Dox,Doy\n1,1,1,1,1\n", "dev.csv:1: Doz: missing column `Doz`"),
    dev_case!("short row", b"Dx,Dy,Dz,Dox,Doy,Doz\r\n1,1,1,1,1\r\n", "dev.csv:2: row: 5 fields, expected 6"),
    dev_case!("extra column", b"Dx,Dy,Dz,Dox,Doy,Doz\n1,1,1,1,1,1,1\n", "dev.csv:2: row: 7 fields, expected 6"),
    dev_case!("NaN", b"Dx,Dy,Dz,Dox,Doy,Doz\n1,NaN,1,1,1,1\n", "dev.csv:2: Dy: `NaN` is not a finite number"),
    dev_case!("overflow", b"Dx,Dy,Dz,Dox,Doy,Doz\n1e999,0,0,0,0,0\n", "dev.csv:2: Dx: `1e999` is not a finite number"),
    dev_case!("text", b"Dx,Dy,Dz,Dox,Doy,Doz\n1,1,one,1,1,1\n", "dev.csv:2: Dz: `one` is not a number"),
    dev_case!("semicolons", b"Dx;Dy;Dz;Dox;Doy;Doz\n1;1;1;1;1;1\n", "dev.csv:1: delimiter: expected commas; this file uses ';' or tabs"),
    dev_case!("latin-1", b"Dx,Dy,Dz,Dox,Doy,Doz\n\xe9,1,1,1,1,1\n", "dev.csv:2: text: not UTF-8"),
    dev_case!("rows are not joints", b"Dx,Dy,Dz,Dox,Doy,Doz\n1,1,1,1,1,1\n", "dev.csv: rows: 1 joint rows, but the robot has 6 joints"),
    dev_case!("header only", b"Dx,Dy,Dz,Dox,Doy,Doz\n", "dev.csv:2: rows: no joint rows after the header"),
    // Targets.
    targets_case!("missing Z", b",X,Y\nP1,500,0\n", "t.csv:1: Z: missing column `Z`"),
    targets_case!("partial orientation", b",X,Y,Z,RX,RY\nP1,500,0,500,0,90\n", "t.csv:1: RX,RY,RZ: give all the columns of an orientation or none"),
    targets_case!("inf", b",X,Y,Z\nP1,500,inf,500\n", "t.csv:2: Y: `inf` is not a finite number"),
    targets_case!("short row", b",X,Y,Z\nP1,500,0\n", "t.csv:2: row: 3 fields, expected 4"),
    targets_case!("tabs", b"\tX\tY\tZ\nP1\t500\t0\t500\n", "t.csv:1: delimiter"),
    targets_case!("empty", b"\n\n", "t.csv:1: header: empty file"),
    // Measurements.
    meas_case!("missing q6", b"q1,q2,q3,q4,q5,x,y,z\n0,0,0,0,0,1,2,3\n", "m.csv:1: q6: missing column `q6`"),
    meas_case!("extra q7", b"q1,q2,q3,q4,q5,q6,q7,x,y,z\n0,0,0,0,0,0,0,1,2,3\n", "m.csv:1: q7: more joint columns than the robot's 6 joints"),
    meas_case!("negative time", b"time_min,q1,q2,q3,q4,q5,q6,x,y,z\n-1,0,0,0,0,0,0,1,2,3\n", "m.csv:2: time_min: -1 is negative"),
    meas_case!("NaN position", b"q1,q2,q3,q4,q5,q6,x,y,z\n0,0,0,0,0,0,nan,2,3\n", "m.csv:2: x: `nan` is not a finite number"),
    meas_case!("mixed line endings, too few", b"q1,q2,q3,q4,q5,q6,x,y,z\r\n0,0,0,0,0,0,1,2,3\n0,0,0,0,0,0,1,2,3\r\n", "2 measurements are too few for 5-fold cross-validation"),
    // URDF.
    urdf_case!("malformed XML", b"<robot name=\"r\"><link name=\"a\"/>", "r.urdf: xml: malformed URDF"),
    urdf_case!("missing link", b"<robot name=\"r\"><link name=\"a\"/><joint name=\"j\" type=\"revolute\"><parent link=\"a\"/><child link=\"b\"/><axis xyz=\"0 0 1\"/></joint></robot>", "<joint name=\"j\">: its child link `b` does not exist"),
    urdf_case!("cycle", b"<robot name=\"r\"><link name=\"a\"/><link name=\"b\"/><joint name=\"j\" type=\"revolute\"><parent link=\"a\"/><child link=\"b\"/><axis xyz=\"0 0 1\"/></joint><joint name=\"k\" type=\"fixed\"><parent link=\"b\"/><child link=\"a\"/></joint></robot>", "lies on a cycle of joints"),
    urdf_case!("floating joint", b"<robot name=\"r\"><link name=\"a\"/><link name=\"b\"/><joint name=\"f\" type=\"floating\"><parent link=\"a\"/><child link=\"b\"/></joint></robot>", "<joint name=\"f\">: joint type Floating is not supported"),
    urdf_case!("ambiguous tip", b"<robot name=\"r\"><link name=\"a\"/><link name=\"b\"/><link name=\"c\"/><joint name=\"j\" type=\"revolute\"><parent link=\"a\"/><child link=\"b\"/><axis xyz=\"0 0 1\"/></joint><joint name=\"k\" type=\"revolute\"><parent link=\"a\"/><child link=\"c\"/><axis xyz=\"0 0 1\"/></joint></robot>", "the tip is ambiguous: leaves below `a` are b, c; choose one with --tip"),
    // Flags.
    Case { name: "joint count", files: &[], args: &["fk", "--robot", ROBOT, "--joints", "0,0,0"], code: 2, needle: "--joints: 3 values for a robot with 6 joints" },
    Case { name: "joint NaN", files: &[], args: &["fk", "--robot", ROBOT, "--joints", "0,0,NaN,0,0,0"], code: 2, needle: "--joints: value 3 is not finite" },
    Case { name: "time without profile", files: &[], args: &["fk", "--robot", ROBOT, "--deformation", TABLE, "--time", "5", "--joints", J6], code: 2, needle: "--time needs --profile" },
    Case { name: "bad profile", files: &[], args: &["fk", "--robot", ROBOT, "--profile", "cubic:1,2", "--joints", J6], code: 2, needle: "cubic takes three coefficients" },
    Case { name: "tip on TOML", files: &[], args: &["fk", "--robot", ROBOT, "--tip", "tool0", "--joints", J6], code: 2, needle: "base/tip: only URDF robots take a base or tip link" },
    Case { name: "negative time on compensate", files: &[("dev.csv", GOOD_DEV)], args: &["compensate", "--robot", ROBOT, "--deformation", "{dir}/dev.csv", "--profile", "linear:180", "--time=-3", "--targets", "fixtures/paper/table12-targets.csv", "--out", "{dir}/o.csv"], code: 2, needle: "target P1 (line 3): time -3 min: time must be finite and ≥ 0" },
    Case { name: "drifting robot without its time", files: &[("cal.toml", DRIFTING)], args: &["fk", "--robot", "{dir}/cal.toml", "--joints", J6], code: 2, needle: "this robot needs an operating time (minutes): joint 2's row drifts with operating time, exponential (τ = 40.0 min); give the time (0 is the cold robot)" },
    Case { name: "sensor the robot lacks", files: &[("cal.toml", DRIFTING)], args: &["fk", "--robot", "{dir}/cal.toml", "--time", "5", "--temperature", "temp_j9=30", "--joints", J6], code: 2, needle: "no row drifting with sensor `temp_j9`" },
    Case { name: "bad temperature", files: &[("cal.toml", DRIFTING)], args: &["fk", "--robot", "{dir}/cal.toml", "--time", "5", "--temperature", "temp_j2=warm", "--joints", J6], code: 2, needle: "`warm` is not a temperature in °C" },
    Case { name: "calibrated robot to diagnose", files: &[("cal.toml", DRIFTING)], args: &["diagnose", "--robot", "{dir}/cal.toml", "--measurements", "x.csv"], code: 2, needle: "carries identified corrections (joint 2's row: thermal drift, exponential (τ = 40.0 min))" },
    Case { name: "bad step", files: &[], args: &["compensate", "--robot", ROBOT, "--deformation", TABLE, "--profile", "linear:180", "--step", "0", "--targets", "fixtures/paper/table12-targets.csv", "--out", "/tmp/o.csv"], code: 2, needle: "step must be positive, got 0 min" },
    Case { name: "profile on diagnose", files: &[], args: &["diagnose", "--robot", ROBOT, "--deformation", TABLE, "--profile", "static", "--measurements", "x.csv"], code: 2, needle: "diagnose takes a static robot" },
    Case { name: "unreachable pose", files: &[], args: &["ik", "--robot", ROBOT, "--pose", "5000,0,0,0,90,0"], code: 3, needle: "status       Unreachable after 0 iterations" },
    Case { name: "unknown flag", files: &[], args: &["fk", "--robot", ROBOT, "--joints", J6, "--colour"], code: 2, needle: "unexpected argument '--colour'" },
    Case { name: "BOM and CRLF accepted", files: &[("dev.csv", b"\xef\xbb\xbfDx,Dy,Dz,Dox,Doy,Doz\r\n1,1,1,1,1,1\n1,1,1,1,1,1\r\n1,1,1,1,1,1\n1,1,1,1,1,1\n1,1,1,1,1,1\n1,1,1,1,1,1\n")], args: &["fk", "--robot", ROBOT, "--deformation", "{dir}/dev.csv", "--joints", J6], code: 0, needle: "position_mm" },
];

#[test]
fn the_bad_input_table() {
    assert!(CASES.len() >= 40, "{} cases", CASES.len());
    // docs/reliability.md states the table's size: kept true here.
    let doc = std::fs::read_to_string(workspace("docs/reliability.md")).unwrap();
    let stated = format!("`crates/cli/tests/it/bad_inputs.rs`: {} cases", CASES.len());
    assert!(doc.contains(&stated), "docs/reliability.md does not say `{stated}`");
    let _ = JOINT;
    let mut failures = Vec::new();
    for (k, case) in CASES.iter().enumerate() {
        let dir: PathBuf = std::env::temp_dir().join(format!("thermokin-bad-{}-{k}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        for (name, content) in case.files {
            std::fs::write(dir.join(name), content).unwrap();
        }
        let args: Vec<String> = case.args.iter().map(|a| a.replace("{dir}", dir.to_str().unwrap())).collect();
        let o = Command::new(env!("CARGO_BIN_EXE_thermokin")).args(&args).current_dir(workspace("")).output().unwrap();
        let out = format!("{}{}", String::from_utf8_lossy(&o.stderr), String::from_utf8_lossy(&o.stdout));
        if o.status.code() != Some(case.code) || !out.contains(case.needle) || out.contains("panicked") {
            failures.push(format!(
                "{}: exit {:?} (want {}), `{}` in:\n{out}",
                case.name,
                o.status.code(),
                case.code,
                case.needle
            ));
        }
        std::fs::remove_dir_all(&dir).ok();
    }
    assert!(failures.is_empty(), "{} of {} cases:\n{}", failures.len(), CASES.len(), failures.join("\n"));
}
