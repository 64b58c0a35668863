//! A short deterministic replay of every fuzz target's corpus (`fuzz/corpus/<target>/`, minimised after
//! the fuzzing runs recorded in docs/reliability.md): each input goes through the reader again, which
//! must return (an error or a value), never panic.

use std::path::Path;

use thermokin_testdata::workspace;

fn replay(target: &str, f: impl Fn(&str)) -> usize {
    let dir = workspace(&format!("fuzz/corpus/{target}"));
    let mut entries: Vec<_> =
        std::fs::read_dir(&dir).unwrap_or_else(|e| panic!("{}: {e}", dir.display())).filter_map(Result::ok).collect();
    entries.sort_by_key(|e| e.file_name());
    let mut n = 0;
    for e in entries {
        let Ok(bytes) = std::fs::read(e.path()) else { continue };
        if let Ok(text) = std::str::from_utf8(&bytes) {
            f(text);
        }
        n += 1;
    }
    assert!(n > 0, "{target}: empty corpus");
    n
}

#[test]
fn every_corpus_replays_without_a_panic() {
    let p = |name: &'static str| Path::new(name);
    let counts = [
        ("robot_toml", replay("robot_toml", |t| drop(thermokin_io::parse_robot_toml(p("fuzz.toml"), t)))),
        ("deviation_csv", replay("deviation_csv", |t| drop(thermokin_io::parse_deviation_table(p("fuzz.csv"), t)))),
        ("deviation_toml", replay("deviation_toml", |t| drop(thermokin_io::parse_deviation_table(p("fuzz.toml"), t)))),
        ("targets_csv", replay("targets_csv", |t| drop(thermokin_io::parse_targets(p("fuzz.csv"), t)))),
        (
            "measurements_csv",
            replay("measurements_csv", |t| {
                drop(thermokin_io::parse_measurements(p("fuzz.csv"), t, &[thermokin_chain::JointKind::Revolute; 6]))
            }),
        ),
        ("temperature_log", replay("temperature_log", |t| drop(thermokin_io::parse_temperature_log(p("fuzz.csv"), t)))),
        ("paper_results", replay("paper_results", |t| drop(thermokin_io::parse_paper_results(p("fuzz.csv"), t)))),
        (
            "urdf",
            replay("urdf", |t| {
                if let Ok(r) = thermokin_urdf::import_urdf(t, "fuzz.urdf", &thermokin_urdf::ImportOptions::default()) {
                    let _ = thermokin_urdf::export_robot(&r.robot);
                }
            }),
        ),
    ];
    eprintln!("replayed: {counts:?}");
}
