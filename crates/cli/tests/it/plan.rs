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
