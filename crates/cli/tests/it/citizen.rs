//! The command line as a careful user — and another user of the same machine — meets it: a closed pipe,
//! batches in one process, no silent guess, outputs that respect the file system, nothing read from a
//! place anyone can write. Each test runs in a private temporary directory.

use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

use thermokin_testdata::workspace;

/// The binary under test: this build's, or another given in `THERMOKIN_TEST_BIN` (to show a probe failing
/// on an earlier build).
fn bin() -> String {
    std::env::var("THERMOKIN_TEST_BIN").unwrap_or_else(|_| env!("CARGO_BIN_EXE_thermokin").to_string())
}
const J6: &str = "0,30,10,0,-40,0";

/// A fresh private directory (owner only) for one test.
fn private_dir(name: &str) -> PathBuf {
    use std::os::unix::fs::DirBuilderExt;
    let dir = std::env::temp_dir().join(format!("thermokin-citizen-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::DirBuilder::new().recursive(true).mode(0o700).create(&dir).unwrap();
    dir
}

/// Runs the binary in `dir` with `HOME`, `TMPDIR` and `XDG_CACHE_HOME` inside it.
fn run_in(dir: &Path, args: &[&str]) -> Output {
    command_in(dir, args).output().unwrap()
}

fn command_in(dir: &Path, args: &[&str]) -> Command {
    let mut c = Command::new(bin());
    c.args(args).current_dir(dir).env("HOME", dir).env("TMPDIR", dir).env("XDG_CACHE_HOME", dir.join("cache"));
    c
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

/// Every file under `dir`, relative.
fn files_under(dir: &Path) -> Vec<String> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap().flatten() {
            let p = e.path();
            if p.is_dir() {
                stack.push(p);
            } else {
                out.push(p.strip_prefix(dir).unwrap().display().to_string());
            }
        }
    }
    out.sort();
    out
}

#[test]
fn a_closed_pipe_ends_the_command_quietly() {
    let dir = private_dir("pipe");
    let rows: String = (0..2000).map(|i| format!("{},{},10,0,-40,0\n", i % 90, (i * 7) % 60)).collect();
    std::fs::write(dir.join("q.csv"), format!("q1,q2,q3,q4,q5,q6\n{rows}")).unwrap();
    for _ in 0..25 {
        for args in [
            &["fk", "--robot", "configs/irb140.toml", "--joints", J6][..],
            &["fk", "--robot", "configs/irb140.toml", "--joints-file", "q.csv"][..],
        ] {
            let mut child = command_in(&dir, args).stdout(Stdio::piped()).stderr(Stdio::piped()).spawn().unwrap();
            let mut first = String::new();
            BufReader::new(child.stdout.take().unwrap()).read_line(&mut first).unwrap();
            // The reader is dropped here: the pipe closes after one line, as `| head -1` does.
            let out = child.wait_with_output().unwrap();
            assert!(!first.is_empty());
            let code = out.status.code().unwrap_or(-1);
            assert!(code == 0 || code == 141, "{args:?}: exit {code}, stderr {}", text(&out.stderr));
            assert!(!text(&out.stderr).contains("panicked"), "{}", text(&out.stderr));
        }
    }
}

#[test]
fn a_thousand_joint_rows_in_one_process_and_a_bad_row_is_its_own_record() {
    let dir = private_dir("batch");
    let mut rows: Vec<String> =
        (0..1000).map(|i| format!("{},{},{},0,-40,{}", i % 90, (i * 7) % 60, i % 40, i % 180)).collect();
    rows[500] = "1,2,x,4,5,6".into();
    std::fs::write(dir.join("q.csv"), format!("q1,q2,q3,q4,q5,q6\n{}\n", rows.join("\n"))).unwrap();
    let o = run_in(&dir, &["fk", "--robot", "configs/irb140.toml", "--joints-file", "q.csv"]);
    assert_eq!(o.status.code(), Some(3), "{}", text(&o.stderr));
    let out = text(&o.stdout);
    let lines: Vec<&str> = out.lines().collect();
    assert_eq!(lines.len(), 1001);
    assert_eq!(lines[0], "line,x_mm,y_mm,z_mm,rx_deg,ry_deg,rz_deg,error");
    assert!(lines[501].starts_with("502,,,,,,,") && lines[501].contains("q3"), "{}", lines[501]);
    // Row 1 (file line 2) equals the single-pose command's answer.
    let single = run_in(&dir, &["fk", "--robot", "configs/irb140.toml", "--joints", "0,0,0,0,-40,0", "--json"]);
    let v: serde_json::Value = serde_json::from_str(&text(&single.stdout)).unwrap();
    let cells: Vec<f64> = lines[1].split(',').skip(1).take(3).map(|c| c.parse().unwrap()).collect();
    for (k, c) in cells.iter().enumerate() {
        assert!((c - v["position_mm"][k].as_f64().unwrap()).abs() < 1e-9, "{c} vs {}", v["position_mm"][k]);
    }
}

#[test]
fn a_file_of_poses_is_solved_row_by_row() {
    let dir = private_dir("poses");
    std::fs::write(
        dir.join("p.csv"),
        ",X,Y,Z,RX,RY,RZ\nA,600,0,400,0,90,0\nFAR,5000,0,0,0,90,0\nBAD,600,x,400,0,90,0\nB,500,100,500,0,90,0\n",
    )
    .unwrap();
    let o = run_in(&dir, &["ik", "--robot", "configs/irb140.toml", "--poses-file", "p.csv", "--seed", J6]);
    assert_eq!(o.status.code(), Some(3), "{}", text(&o.stderr));
    let out = text(&o.stdout);
    let lines: Vec<&str> = out.lines().collect();
    assert_eq!(lines.len(), 5, "{out}");
    assert!(lines[1].starts_with("2,A,") && lines[1].contains(",Converged,"), "{}", lines[1]);
    assert!(lines[2].starts_with("3,FAR,") && lines[2].contains(",Unreachable,"), "{}", lines[2]);
    assert!(lines[3].contains("Y") && lines[3].contains("not a number"), "{}", lines[3]);
    assert!(lines[4].starts_with("5,B,") && lines[4].contains(",Converged,"), "{}", lines[4]);
}

#[test]
fn bundled_robots_are_read_from_the_binary_and_nothing_planted_changes_them() {
    let dir = private_dir("planted");
    // Every place an earlier version unpacked to, and any a user could write, holds a planted robot
    // of the same length that moves the tool by 1 mm.
    let original = std::fs::read_to_string(workspace("configs/irb140.toml")).unwrap();
    let planted = original.replacen("25.5", "26.5", 1);
    assert_eq!(planted.len(), original.len());
    for d in ["thermokin-0.1.0-planted/configs", "cache/thermokin/0.1.0-planted/configs"] {
        std::fs::create_dir_all(dir.join(d)).unwrap();
        std::fs::write(dir.join(d).join("irb140.toml"), &planted).unwrap();
    }
    let before = files_under(&dir);
    let o = run_in(&dir, &["fk", "--robot", "configs/irb140.toml", "--joints", J6, "--json"]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let v: serde_json::Value = serde_json::from_str(&text(&o.stdout)).unwrap();
    let here = Command::new(bin())
        .args(["fk", "--robot", "configs/irb140.toml", "--joints", J6, "--json"])
        .current_dir(workspace(""))
        .output()
        .unwrap();
    let on_disk: serde_json::Value = serde_json::from_str(&text(&here.stdout)).unwrap();
    assert_eq!(v["position_mm"], on_disk["position_mm"]);
    // Nothing was unpacked anywhere.
    assert_eq!(files_under(&dir), before);
    // A robot that is neither on disk nor bundled names the bundled ones; a bad tip the links.
    let o = run_in(&dir, &["fk", "--robot", "configs/irb141.toml", "--joints", J6]);
    assert_eq!(o.status.code(), Some(2));
    assert!(text(&o.stderr).contains("configs/irb140.toml"), "{}", text(&o.stderr));
    let o = run_in(&dir, &["fk", "--robot", "fixtures/urdf/ur5.urdf", "--tip", "tool1", "--joints", J6]);
    assert_eq!(o.status.code(), Some(2));
    let e = text(&o.stderr);
    assert!(e.contains("tool0") && e.contains("fixtures/urdf/ur5.urdf") && !e.contains("cache"), "{e}");
}

#[test]
fn guesses_are_refused_or_named() {
    let dir = private_dir("guesses");
    // Orientation columns under unknown names: refused, the columns named.
    std::fs::write(dir.join("t.csv"), ",X,Y,Z,a,b,c\nP1,600,0,400,0,90,0\n").unwrap();
    let o = run_in(
        &dir,
        &[
            "compensate",
            "--robot",
            "configs/irb140.toml",
            "--deformation",
            "fixtures/paper/deformations-case-study.toml",
            "--targets",
            "t.csv",
            "--out",
            "r.csv",
        ],
    );
    assert_eq!(o.status.code(), Some(2), "{}", text(&o.stderr));
    assert!(text(&o.stderr).contains("`a`, `b`, `c`"), "{}", text(&o.stderr));
    // Joints written in radians, positions in metres: refused with the flag that says otherwise.
    let sim = run_in(
        &dir,
        &[
            "simulate",
            "--robot",
            "configs/irb140.toml",
            "--effect",
            "joint_offset:2",
            "--poses",
            "40",
            "--minutes",
            "0",
            "-o",
            "m.csv",
        ],
    );
    assert!(sim.status.success(), "{}", text(&sim.stderr));
    let rows: Vec<Vec<f64>> = std::fs::read_to_string(dir.join("m.csv"))
        .unwrap()
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(|c| c.parse().unwrap()).collect())
        .collect();
    let header = std::fs::read_to_string(dir.join("m.csv")).unwrap().lines().next().unwrap().to_string();
    let write = |name: &str, f: &dyn Fn(usize, f64) -> f64| {
        let body: Vec<String> = rows
            .iter()
            .map(|r| r.iter().enumerate().map(|(k, v)| f(k, *v).to_string()).collect::<Vec<_>>().join(","))
            .collect();
        std::fs::write(dir.join(name), format!("{header}\n{}\n", body.join("\n"))).unwrap();
    };
    let q = header.split(',').position(|c| c == "q1").unwrap();
    let x = header.split(',').position(|c| c == "x").unwrap();
    write("rad.csv", &|k, v| if (q..q + 6).contains(&k) { v.to_radians() } else { v });
    write("metres.csv", &|k, v| if (x..x + 3).contains(&k) { v / 1000.0 } else { v });
    for (file, flag) in [("rad.csv", "--joint-units rad"), ("metres.csv", "--position-units m")] {
        let o = run_in(&dir, &["diagnose", "--robot", "configs/irb140.toml", "--measurements", file, "--quiet"]);
        assert_eq!(o.status.code(), Some(2), "{file}: {}", text(&o.stdout));
        assert!(text(&o.stderr).contains(flag), "{file}: {}", text(&o.stderr));
        // Said, the file is read in that unit and the hidden offset found.
        let said: Vec<&str> = flag.split(' ').collect();
        let o = run_in(
            &dir,
            &["diagnose", "--robot", "configs/irb140.toml", "--measurements", file, said[0], said[1], "--quiet"],
        );
        assert!(o.status.success(), "{file}: {}", text(&o.stderr));
        assert!(text(&o.stdout).contains("joint_offset[2]"), "{file}: {}", text(&o.stdout));
    }
}

#[test]
fn outputs_respect_the_file_system() {
    let dir = private_dir("outputs");
    let args = |out: &str| {
        vec![
            "compensate".to_string(),
            "--robot".into(),
            "configs/irb140.toml".into(),
            "--deformation".into(),
            "fixtures/paper/deformations-case-study.toml".into(),
            "--targets".into(),
            "fixtures/paper/table12-targets.csv".into(),
            "--seed".into(),
            "0,20,20,0,-45,0".into(),
            "--format".into(),
            "joints".into(),
            "--out".into(),
            out.to_string(),
        ]
    };
    fn refs(v: &[String]) -> Vec<&str> {
        v.iter().map(String::as_str).collect()
    }
    // `-` is standard output: the joints there, no file named `-`.
    let o = run_in(&dir, &refs(&args("-")));
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert!(text(&o.stdout).starts_with("time_min,label,A1"), "{}", text(&o.stdout));
    assert!(!dir.join("-").exists());
    // A device stays a device.
    use std::os::unix::fs::FileTypeExt;
    let o = run_in(&dir, &refs(&args("/dev/null")));
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert!(std::fs::metadata("/dev/null").unwrap().file_type().is_char_device());
    // A directory is refused, named.
    let o = run_in(&dir, &refs(&args(dir.to_str().unwrap())));
    assert_eq!(o.status.code(), Some(1));
    assert!(text(&o.stderr).contains("is a directory"), "{}", text(&o.stderr));
    // No temporary file is left beside a written output.
    let o = run_in(&dir, &refs(&args("joints.csv")));
    assert!(o.status.success());
    assert_eq!(files_under(&dir), vec!["joints.csv".to_string()]);
}

#[test]
fn a_stream_ended_by_sigterm_leaves_nothing_beside_the_output() {
    let dir = private_dir("sigterm");
    let rows: String = (0..400_000)
        .map(|i| format!("P{i},{},{},{},0,90,0\n", 500 + i % 100, (i % 50) as i64 - 25, 400 + i % 80))
        .collect();
    std::fs::write(dir.join("big.csv"), format!(",X,Y,Z,RX,RY,RZ\n{rows}")).unwrap();
    let mut child = command_in(
        &dir,
        &[
            "compensate",
            "--robot",
            "configs/irb140.toml",
            "--deformation",
            "fixtures/paper/deformations-case-study.toml",
            "--targets",
            "big.csv",
            "--stream",
            "--format",
            "joints",
            "--out",
            "out.csv",
        ],
    )
    .stdout(Stdio::null())
    .stderr(Stdio::null())
    .spawn()
    .unwrap();
    // Wait until the temporary output exists (the run is writing), then end it.
    let started = std::time::Instant::now();
    while !files_under(&dir).iter().any(|f| f.contains("thermokin-tmp")) {
        assert!(started.elapsed().as_secs() < 60, "no temporary output appeared");
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    let killed = Command::new("kill").args(["-TERM", &child.id().to_string()]).status().unwrap();
    assert!(killed.success());
    let status = child.wait().unwrap();
    // The exit status the help and the README list for an interrupted run.
    assert_eq!(status.code(), Some(130), "{status:?}");
    assert_eq!(files_under(&dir), vec!["big.csv".to_string()], "left behind");
}

#[test]
fn flags_a_command_cannot_honour_are_not_ignored() {
    let dir = private_dir("honour");
    let drifting = "name = \"drifting\"\n\n[[joint]]\naxis = \"z\"\noffset_mm = [0.0, 0.0, 100.0]\n\n[[joint]]\naxis = \"y\"\noffset_mm = [0.0, 0.0, 300.0]\n\n[tool]\ntranslation_mm = [200.0, 0.0, 0.0]\n\n[[drift]]\nrow = 2\nerror = [0.5, 0.0, 0.2, 0.0, 0.01, 0.0]\nprofile = { kind = \"linear\", stabilization_min = 180.0, after = \"keep_growing\" }\n";
    std::fs::write(dir.join("drift.toml"), drifting).unwrap();
    let export = |extra: &[&str], out: &str| {
        let mut a = vec!["urdf", "export", "--robot", "drift.toml", "-o", out];
        a.extend_from_slice(extra);
        let o = run_in(&dir, &a);
        assert!(o.status.success(), "{}", text(&o.stderr));
        std::fs::read_to_string(dir.join(out)).unwrap()
    };
    assert_ne!(export(&[], "cold.urdf"), export(&["--time", "60"], "warm.urdf"));
}
