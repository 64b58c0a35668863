//! The streamed static run: the same bytes whatever the chunk size and the number of threads, every
//! written joint vector put back on its target by the deformed robot's own FK, failures as rows, bad
//! input as an error naming its line.

use std::io::Cursor;

use thermokin_compensate::{RunSettings, StreamSettings, compensate_static_stream};
use thermokin_deform::{CoppeliaSimEdits, DeviationTable, TableSemantics};
use thermokin_ik::Params;
use thermokin_io::{TargetReader, read_deviation_table, read_robot};
use thermokin_testdata::workspace;

fn setup() -> (thermokin_chain::Chain, DeviationTable, RunSettings, String) {
    let chain = read_robot(&workspace("configs/irb140.toml")).unwrap().chain().clone();
    let table = read_deviation_table(&workspace("fixtures/paper/deformations-case-study.toml")).unwrap();
    let run = RunSettings {
        semantics: TableSemantics::CoppeliaSim(CoppeliaSimEdits::at(vec![0.0; 6])),
        accumulation: Default::default(),
        ik: Params::default(),
        start: [0.0, 20.0, 20.0, 0.0, -45.0, 0.0].map(f64::to_radians).to_vec(),
    };
    let csv = std::fs::read_to_string(workspace("fixtures/paper/table12-targets.csv")).unwrap();
    (chain, table, run, csv)
}

fn stream(
    chain: &thermokin_chain::Chain,
    table: &DeviationTable,
    run: &RunSettings,
    csv: &str,
    chunk: usize,
) -> String {
    let mut reader = TargetReader::new("t.csv".as_ref(), Cursor::new(csv.to_string())).unwrap();
    let mut out = Vec::new();
    let settings = StreamSettings { chunk, ..StreamSettings::new(run.clone()) };
    let summary = compensate_static_stream(chain, table, &mut reader, &mut out, &settings, |_| {}).unwrap();
    assert_eq!(summary.solves, 50);
    String::from_utf8(out).unwrap()
}

#[test]
fn the_same_bytes_for_any_chunk_and_thread_count() {
    let (chain, table, run, csv) = setup();
    let reference = stream(&chain, &table, &run, &csv, 1 << 16);
    for chunk in [1, 7, 49] {
        assert_eq!(stream(&chain, &table, &run, &csv, chunk), reference, "chunk {chunk}");
    }
    let one = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
    assert_eq!(one.install(|| stream(&chain, &table, &run, &csv, 8)), reference, "one thread");
}

#[test]
fn every_written_row_puts_the_deformed_robot_on_its_target() {
    let (chain, table, run, csv) = setup();
    let deformed = table.apply(&chain, &run.semantics).unwrap();
    let targets = thermokin_io::parse_targets("t.csv".as_ref(), &csv).unwrap();
    let text = stream(&chain, &table, &run, &csv, 16);
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some("time_min,label,A1,A2,A3,A4,A5,A6,status"));
    for (line, target) in lines.zip(&targets) {
        let cells: Vec<&str> = line.split(',').collect();
        assert_eq!(cells[1], target.label);
        assert_eq!(cells[8], "Converged");
        // Degrees as written (1e-12°), back to radians: an independent path through the file.
        let q: Vec<f64> = cells[2..8].iter().map(|c| c.parse::<f64>().unwrap().to_radians()).collect();
        let reached = deformed.tool_pose(&q).unwrap();
        let dp = (reached.translation.vector - target.pose.translation.vector).norm();
        let dr = reached.rotation.angle_to(&target.pose.rotation).to_degrees();
        assert!(dp < 1e-6 && dr < 1e-6, "{}: {dp:e} mm, {dr:e}°", target.label);
    }
}

#[test]
fn unreachable_targets_are_rows_and_bad_rows_are_located_errors() {
    let (chain, table, run, _) = setup();
    let csv = ",X,Y,Z\nP1,641,21,473\nFAR,3000,0,0\nP3,656,242,373\n";
    let mut reader = TargetReader::new("t.csv".as_ref(), Cursor::new(csv)).unwrap();
    let mut out = Vec::new();
    let settings = StreamSettings::new(run.clone());
    let summary = compensate_static_stream(&chain, &table, &mut reader, &mut out, &settings, |_| {}).unwrap();
    assert_eq!((summary.solves, summary.failures), (3, 1));
    assert_eq!(summary.failed, vec!["FAR (Unreachable)".to_string()]);
    let text = String::from_utf8(out).unwrap();
    assert!(text.lines().nth(2).unwrap().starts_with("0,FAR,"), "{text}");

    let bad = ",X,Y,Z\nP1,641,21,473\nP2,536,oops,281\n";
    let mut reader = TargetReader::new("bad.csv".as_ref(), Cursor::new(bad)).unwrap();
    let err = compensate_static_stream(&chain, &table, &mut reader, &mut Vec::new(), &settings, |_| {}).unwrap_err();
    let msg = err.to_string();
    assert!(msg.contains("bad.csv") && msg.contains('3') && msg.contains('Y'), "{msg}");
    // A header with no target is an error too.
    let mut reader = TargetReader::new("empty.csv".as_ref(), Cursor::new(",X,Y,Z\n")).unwrap();
    assert!(compensate_static_stream(&chain, &table, &mut reader, &mut Vec::new(), &settings, |_| {}).is_err());
}
