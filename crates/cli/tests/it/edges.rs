//! The rough edges issue #50 found, each a clear sentence or a refusal now: a program in metres, a run
//! that reaches nothing, a program type the extension does not tell, the exit statuses and every
//! command's help.

use crate::cli::{stderr, stdout, thermokin, tmp};

/// The paper's 50 targets with their positions written in metres.
fn targets_in_metres() -> std::path::PathBuf {
    let text = std::fs::read_to_string(thermokin_testdata::workspace("fixtures/paper/table12-targets.csv")).unwrap();
    let mut out = String::new();
    let mut header = true;
    for line in text.lines() {
        if line.starts_with('#') || header {
            header &= line.starts_with('#');
            out.push_str(line);
        } else {
            let mut cells: Vec<String> = line.split(',').map(str::to_string).collect();
            for c in cells.iter_mut().skip(1).take(3) {
                *c = format!("{}", c.trim().parse::<f64>().unwrap() / 1000.0);
            }
            out.push_str(&cells.join(","));
        }
        out.push('\n');
    }
    let path = tmp("targets-in-metres.csv");
    std::fs::write(&path, out).unwrap();
    path
}

#[test]
fn a_program_in_metres_gets_the_unit_hint_and_runs_when_the_unit_is_said() {
    let targets = targets_in_metres();
    let t = targets.display().to_string();
    let out = tmp("metres-out.csv").display().to_string();
    let base = ["--robot", "configs/irb140.toml", "--deformation", "fixtures/paper/deformations-case-study.toml"];
    let mut args = vec!["compensate"];
    args.extend(base);
    args.extend(["--targets", &t, "--seed", "0,20,20,0,-45,0", "--out", &out]);
    let o = thermokin(&args);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("look like metres") && stderr(&o).contains("--position-units m"), "{}", stderr(&o));
    args.extend(["--position-units", "m"]);
    let o = thermokin(&args);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    // ik --poses-file reads the same files the same way.
    let o = thermokin(&["ik", "--robot", "configs/irb140.toml", "--poses-file", &t]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("--position-units m"), "{}", stderr(&o));
}

#[test]
fn a_run_that_reaches_nothing_says_so_instead_of_infinite_ranges() {
    // Every target 10 m away: none is reachable.
    let path = tmp("far-targets.csv");
    let rows: Vec<String> = (1..=3).map(|k| format!("P{k},{},0,400,0,90,0", 10_000 + k)).collect();
    std::fs::write(&path, format!(",X,Y,Z,RX,RY,RZ\n{}\n", rows.join("\n"))).unwrap();
    let out = tmp("far-out.csv").display().to_string();
    let p = path.display().to_string();
    let o = thermokin(&[
        "compensate",
        "--robot",
        "configs/irb140.toml",
        "--deformation",
        "fixtures/paper/deformations-case-study.toml",
        "--targets",
        &p,
        "--out",
        &out,
    ]);
    assert_eq!(o.status.code(), Some(3), "{}", stderr(&o));
    let text = stdout(&o);
    assert!(text.contains("no target reached"), "{text}");
    assert!(!text.contains("inf") && !text.contains("largest error"), "{text}");
}

#[test]
fn a_program_type_the_extension_does_not_tell_is_refused_with_the_list() {
    let out = tmp("prg-out.csv").display().to_string();
    let prg = tmp("x.prg").display().to_string();
    let o = thermokin(&[
        "compensate",
        "--robot",
        "configs/irb140.toml",
        "--deformation",
        "fixtures/paper/deformations-case-study.toml",
        "--targets",
        "fixtures/paper/table12-targets.csv",
        "--seed",
        "0,20,20,0,-45,0",
        "--out",
        &out,
        "--program",
        &prg,
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    for known in [".mod", ".src", ".script", "--controller"] {
        assert!(stderr(&o).contains(known), "{known}: {}", stderr(&o));
    }
    assert!(!std::path::Path::new(&prg).exists(), "nothing written");
}

#[test]
fn the_help_lists_every_command_every_exit_status_and_an_example_each() {
    let top = stdout(&thermokin(&["--help"]));
    for command in ["fk", "ik", "compensate", "urdf", "diagnose", "plan", "simulate", "reproduce-paper"] {
        assert!(top.lines().next().unwrap().contains(command), "the first line names {command}: {top}");
        assert!(top.contains(&format!("  {command} ")), "{command} listed: {top}");
    }
    for status in ["  0  ", "  1  ", "  2  ", "  3  ", "  4  ", "  5  ", "  130  ", "  141  "] {
        assert!(top.contains(status), "exit status {status} in the table: {top}");
    }
    let commands: [&[&str]; 9] = [
        &["fk"],
        &["ik"],
        &["compensate"],
        &["urdf", "import"],
        &["urdf", "export"],
        &["diagnose"],
        &["plan"],
        &["simulate"],
        &["reproduce-paper"],
    ];
    for c in commands {
        let mut args = c.to_vec();
        args.push("--help");
        let help = stdout(&thermokin(&args));
        assert!(help.contains("Example"), "{c:?} --help has no example:\n{help}");
        assert!(help.contains("  thermokin "), "{c:?} --help shows no command:\n{help}");
    }
    // simulate --help names every effect of the catalogue.
    let simulate = stdout(&thermokin(&["simulate", "--help"]));
    for name in thermokin_identify::EFFECT_NAMES {
        assert!(simulate.contains(name), "simulate --help omits {name}");
    }
}

/// Every numeric default of the command line comes from a library's `Default` or constant: none is typed
/// into clap, where it could drift from what the libraries (and the Python front end) use.
#[test]
fn no_numeric_default_is_typed_into_clap() {
    let src = thermokin_testdata::workspace("crates/cli/src");
    for entry in std::fs::read_dir(src).unwrap() {
        let path = entry.unwrap().path();
        let text = std::fs::read_to_string(&path).unwrap();
        for (k, line) in text.lines().enumerate() {
            for key in ["default_value_t = ", "default_value = \""] {
                if let Some(at) = line.find(key) {
                    let value = &line[at + key.len()..];
                    let numeric = value.trim_start_matches('-').starts_with(|c: char| c.is_ascii_digit());
                    assert!(!numeric, "{}:{}: a number typed into clap: {}", path.display(), k + 1, line.trim());
                }
            }
        }
    }
}

#[test]
fn a_column_the_diagnosis_does_not_read_is_said() {
    // A simulated set with an accelerometer's column and a point-name column appended: the diagnosis runs,
    // reads the numbers as a sensor and names the text column it does not read.
    let m = tmp("with-sensor.csv");
    let o = thermokin(&[
        "simulate",
        "--robot",
        "configs/irb140.toml",
        "--effect",
        "joint_offset:2=0.05",
        "--poses",
        "40",
        "--minutes",
        "0",
        "-o",
        m.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = std::fs::read_to_string(&m).unwrap();
    let mut lines: Vec<String> = Vec::new();
    for (k, line) in text.lines().enumerate() {
        let extra = if line.starts_with('#') {
            String::new()
        } else if lines.iter().all(|l| l.starts_with('#')) {
            ",acc_col_x,point".to_string()
        } else {
            format!(",{},P{k}", 0.01 * (k % 7) as f64)
        };
        lines.push(format!("{line}{extra}"));
    }
    std::fs::write(&m, lines.join("\n") + "\n").unwrap();
    let o = thermokin(&["diagnose", "--robot", "configs/irb140.toml", "--measurements", m.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains("column `point` is not read"), "{}", stderr(&o));
    assert!(stderr(&o).contains("column `acc_col_x` read as a sensor"), "{}", stderr(&o));
    // The columns it reads are not named.
    assert!(!stderr(&o).contains("column `q1`") && !stderr(&o).contains("column `x`"), "{}", stderr(&o));
    // A hold-out file without the sensor column is refused, naming it (issue #59: scored at a reading of
    // 0 without a word).
    let plain = tmp("without-sensor.csv");
    std::fs::write(&plain, &text).unwrap();
    let o = thermokin(&[
        "diagnose",
        "--robot",
        "configs/irb140.toml",
        "--measurements",
        m.to_str().unwrap(),
        "--holdout",
        plain.to_str().unwrap(),
    ]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("no column `acc_col_x`"), "{}", stderr(&o));
    // A copy of joint 2's angle (in radians, offset) and a constant column are no sensors: said, not read.
    let mut lines: Vec<String> = Vec::new();
    let mut q2 = None;
    for line in text.lines() {
        if line.starts_with('#') {
            lines.push(line.to_string());
        } else if q2.is_none() {
            q2 = line.split(',').position(|c| c.trim() == "q2");
            lines.push(format!("{line},q2_rad,station"));
        } else {
            let v: f64 = line.split(',').nth(q2.unwrap()).unwrap().trim().parse().unwrap();
            lines.push(format!("{line},{},7", v.to_radians() + 0.5));
        }
    }
    std::fs::write(&m, lines.join("\n") + "\n").unwrap();
    let o = thermokin(&["diagnose", "--robot", "configs/irb140.toml", "--measurements", m.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("column `q2_rad` is not read as a sensor: it repeats joint 2's value"),
        "{}",
        stderr(&o)
    );
    assert!(stderr(&o).contains("column `station` is not read as a sensor: it does not change"), "{}", stderr(&o));
    assert!(!stderr(&o).contains("`q2_rad` read as a sensor"), "{}", stderr(&o));
}
