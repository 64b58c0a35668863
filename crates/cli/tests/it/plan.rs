//! `thermokin plan`: the plan CSV is a subset of the candidates file (their lines and values), the
//! program visits the poses in the plan's order, the JSON carries the report.

use crate::cli::{stderr, stdout, thermokin, tmp};

#[test]
fn plan_keeps_the_candidates_lines_and_values_and_writes_a_program() {
    let pool = tmp("plan-pool.csv");
    // 200 candidates of the IRB 140 within its limits, an extra column the planner ignores.
    let mut text = String::from("label,q1,q2,q3,q4,q5,q6,x\n");
    for k in 0..200 {
        // A deterministic spread within each joint's limits (joint j's fraction: (k·7919 + j·104729) mod 997).
        let f = |j: usize, a: f64, b: f64| a + b * (((k * 7919 + j * 104_729) % 997) as f64 / 997.0);
        text.push_str(&format!(
            "p{k},{},{},{},{},{},{},0\n",
            f(1, -170.0, 340.0),
            f(2, -80.0, 180.0),
            f(3, -200.0, 240.0),
            f(4, -190.0, 380.0),
            f(5, -110.0, 220.0),
            f(6, -300.0, 600.0)
        ));
    }
    std::fs::write(&pool, &text).unwrap();
    let (out, program, json) = (tmp("plan.csv"), tmp("plan.mod"), tmp("plan.json"));
    let o = thermokin(&[
        "plan",
        "--robot",
        "configs/irb140.toml",
        "--candidates",
        pool.to_str().unwrap(),
        "--poses",
        "12",
        "--out",
        out.to_str().unwrap(),
        "--program",
        program.to_str().unwrap(),
        "--json",
        json.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stdout(&o).starts_with("PLAN: 12 poses of 200 candidates"), "{}", stdout(&o));
    let rows: Vec<Vec<String>> = std::fs::read_to_string(&out)
        .unwrap()
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(str::to_string).collect())
        .collect();
    assert_eq!(rows.len(), 12);
    let pool_lines: Vec<&str> = text.lines().collect();
    for r in &rows {
        // The candidate's file line, and its joint values as the file wrote them.
        let line: usize = r[1].parse().unwrap();
        let cells: Vec<&str> = pool_lines[line - 1].split(',').collect();
        for j in 0..6 {
            let (planned, given): (f64, f64) = (r[2 + j].parse().unwrap(), cells[1 + j].parse().unwrap());
            // Degrees → radians → degrees: equal to the last bit or two of a double.
            assert!(
                (planned - given).abs() <= 4.0 * f64::EPSILON * given.abs().max(1.0),
                "line {line}: {planned} vs {given}"
            );
        }
    }
    let rapid = std::fs::read_to_string(&program).unwrap();
    assert_eq!(rapid.matches("MoveAbsJ").count(), 12, "{rapid}");
    let report: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(report["poses"].as_array().unwrap().len(), 12);
    assert!(report["comparison"]["planned"]["condition_number"].as_f64().is_some());
    // More poses than candidates: bad input, named.
    let o = thermokin(&[
        "plan",
        "--robot",
        "configs/irb140.toml",
        "--candidates",
        pool.to_str().unwrap(),
        "--poses",
        "201",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("201 poses asked for, but only 200 candidates"), "{}", stderr(&o));
}

/// The planner's inputs as careful as the diagnosis's (issue #61): candidates in radians are refused
/// (they were planned as degrees without a word), copies of one pose are set aside (100 copies were
/// planned into 20 copies), a backlash is refused as what the poses alone cannot show (it was "planned
/// for" and then said to have no effect), and the measuring order's motion carries its unit.
#[test]
fn the_planners_inputs_are_read_as_carefully_as_the_diagnosiss() {
    let plan = |candidates: &std::path::Path, extra: &[&str]| {
        let out = tmp("careful-plan.csv");
        let mut args = vec![
            "plan",
            "--robot",
            "configs/irb140.toml",
            "--candidates",
            candidates.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ];
        args.extend(extra);
        thermokin(&args)
    };
    // Forty poses written in radians.
    let radians = tmp("careful-radians.csv");
    let rows: Vec<String> = (0..40)
        .map(|k| {
            let f = |j: usize, span: f64| span * ((((k * 7919 + j * 104_729) % 997) as f64 / 997.0) - 0.5);
            format!("{},{},{},{},{},{}", f(1, 5.0), f(2, 2.5), f(3, 3.0) - 1.5, f(4, 5.0), f(5, 3.0), f(6, 8.0))
        })
        .collect();
    std::fs::write(&radians, format!("q1,q2,q3,q4,q5,q6\n{}\n", rows.join("\n"))).unwrap();
    let o = plan(&radians, &["--poses", "10"]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("look like radians") && stderr(&o).contains("--joint-units rad"), "{}", stderr(&o));
    let o = plan(&radians, &["--poses", "10", "--joint-units", "rad"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stdout(&o).contains("° of largest-joint motion"), "{}", stdout(&o));
    // A hundred copies of one pose: one distinct candidate.
    let copies = tmp("careful-copies.csv");
    std::fs::write(&copies, format!("q1,q2,q3,q4,q5,q6\n{}", "10,20,30,40,50,60\n".repeat(100))).unwrap();
    let o = plan(&copies, &["--poses", "20"]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("only 1 distinct candidates (99 more repeat one of them exactly)"), "{}", stderr(&o));
    // Copies among distinct poses are set aside and said, by line.
    let mixed = tmp("careful-mixed.csv");
    let degrees: Vec<String> = rows
        .iter()
        .map(|r| {
            r.split(',').map(|v| format!("{}", v.parse::<f64>().unwrap().to_degrees())).collect::<Vec<_>>().join(",")
        })
        .collect();
    std::fs::write(&mixed, format!("q1,q2,q3,q4,q5,q6\n{}\n{}\n{}\n", degrees.join("\n"), degrees[0], degrees[3]))
        .unwrap();
    let o = plan(&mixed, &["--poses", "10"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        stdout(&o).contains("2 candidates repeat an earlier one exactly and were set aside (lines 42, 43)"),
        "{}",
        stdout(&o)
    );
    // A backlash is the order's, not the poses'.
    let o = plan(&mixed, &["--poses", "10", "--effect", "backlash:2"]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("backlash[2] follows the direction each joint comes from"), "{}", stderr(&o));
}

/// `plan --for` and `diagnose --for` on the real WAM: the plan chosen for the 20 random poses' joints
/// says what it promises there against random draws (JSON and text), `--poses auto` says where it stopped
/// and why, and the diagnosis of the planned poses' measurements predicts its own error at those poses
/// and sets the hold-out set's and the plan's promise (`--plan`, its JSON) beside it. A poses-of-use file
/// with a joint missing is refused by name.
#[test]
fn plan_and_diagnose_for_the_poses_of_use() {
    let wam = ["--robot", "fixtures/real/jacobi-wam/wam.urdf", "--frame", "tracker", "--tool", "unknown"];
    let (out, json, page) = (tmp("plan-for.csv"), tmp("plan-for.json"), tmp("plan-for.html"));
    let mut args = vec!["plan"];
    args.extend(wam);
    args.extend([
        "--candidates",
        "fixtures/real/jacobi-wam/wam-grid.csv",
        "--for",
        "fixtures/real/jacobi-wam/wam-random.csv",
        "--poses",
        "auto",
        "--out",
        out.to_str().unwrap(),
        "--json",
        json.to_str().unwrap(),
        "--html",
        page.to_str().unwrap(),
    ]);
    let o = thermokin(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = stdout(&o);
    assert!(text.contains("chosen for the prediction (I-optimal)"), "{text}");
    let html = std::fs::read_to_string(&page).unwrap();
    assert!(html.contains("predicted held-out RMS at the 20 poses of use"), "the page's promise row");
    assert!(html.contains("a test at the poses of use can show"), "the page's count rule");
    assert!(text.contains("Predicted held-out RMS at the 20 poses of use given"), "{text}");
    // Three of the 20 reach beyond the grid's arcs (by more than a degree): planned for at their nearest
    // grid poses, and said so.
    assert!(text.contains("3 of the 20 poses of use reach beyond those arcs"), "{text}");
    assert!(html.contains("3 of the 20 poses of use reach beyond those arcs"), "the page's stand-ins");
    assert!(text.contains("a test at the poses of use can show"), "{text}");
    let report: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let promise = &report["promise"];
    assert!(promise["planned_rms_mm"].as_f64().unwrap() < promise["random_rms_mm"].as_f64().unwrap());
    assert_eq!(promise["planned_at_nearest"].as_u64(), Some(3));
    assert!(promise["planned_as_given_rms_mm"].as_f64().unwrap() > 0.0);
    let stopped = report["count"]["stopped"].as_array().unwrap();
    assert!(stopped[0].as_f64().unwrap() < stopped[1].as_f64().unwrap());
    // The planned poses' rows of the grid, measured, diagnosed for the same poses of use.
    let grid = std::fs::read_to_string(thermokin_testdata::workspace("fixtures/real/jacobi-wam/wam-grid.csv")).unwrap();
    let lines: Vec<&str> = grid.lines().collect();
    let mut measured = format!("{}\n", lines[0]);
    for row in std::fs::read_to_string(&out).unwrap().lines().skip(1) {
        let line: usize = row.split(',').nth(1).unwrap().parse().unwrap();
        measured.push_str(lines[line - 1]);
        measured.push('\n');
    }
    let measured_path = tmp("plan-for-measured.csv");
    std::fs::write(&measured_path, measured).unwrap();
    let mut args = vec!["diagnose"];
    args.extend(wam);
    args.extend([
        "--measurements",
        measured_path.to_str().unwrap(),
        "--holdout",
        "fixtures/real/jacobi-wam/wam-random.csv",
        "--for",
        "fixtures/real/jacobi-wam/wam-random.csv",
        "--plan",
        json.to_str().unwrap(),
        "--quiet",
    ]);
    let o = thermokin(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = stdout(&o);
    assert!(text.contains("predicted at the 20 poses of use"), "{text}");
    assert!(text.contains("the hold-out set holds these poses: measured"), "{text}");
    assert!(text.contains("the plan promised"), "{text}");
    // A poses-of-use file one joint short.
    let short = tmp("plan-for-short.csv");
    std::fs::write(&short, "q1,q2,q3,q4,q5,q6\n0,0,0,90,0,0\n").unwrap();
    let mut args = vec!["plan"];
    args.extend(wam);
    args.extend(["--candidates", "fixtures/real/jacobi-wam/wam-grid.csv", "--for", short.to_str().unwrap()]);
    let short_out = tmp("plan-for-short-out.csv");
    args.extend(["--out", short_out.to_str().unwrap()]);
    let o = thermokin(&args);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("plan-for-short.csv"), "{}", stderr(&o));
}
