//! Test support: where the workspace, its fixtures and the shared data (`../shared`, other people's
//! files that are never copied into the project) are.
//!
//! A test that needs shared data calls [`shared`]: when the data are missing it fails under `CI=true`
//! and otherwise prints a skip note and returns `None`.

use std::path::{Path, PathBuf};

/// The workspace root.
pub fn workspace_root() -> PathBuf {
    let here = Path::new(env!("CARGO_MANIFEST_DIR"));
    here.parent().and_then(Path::parent).map_or_else(|| here.to_path_buf(), Path::to_path_buf)
}

/// A path inside the workspace.
pub fn workspace(rel: &str) -> PathBuf {
    workspace_root().join(rel)
}

/// The shared data directory: `$THERMOKIN_SHARED`, else `../shared` beside the workspace.
pub fn shared_root() -> PathBuf {
    std::env::var_os("THERMOKIN_SHARED")
        .map(PathBuf::from)
        .unwrap_or_else(|| workspace_root().join("..").join("shared"))
}

/// A file under the shared data directory, or `None` (with a skip note) when it is missing.
///
/// # Panics
/// Under `CI=true`, when the file is missing: CI must run every test.
pub fn shared(rel: &str) -> Option<PathBuf> {
    let p = shared_root().join(rel);
    if p.exists() {
        return Some(p);
    }
    let ci = std::env::var("CI").is_ok_and(|v| v == "true" || v == "1");
    assert!(!ci, "shared data missing under CI=true: {}", p.display());
    eprintln!("skip: shared data not found at {} (set THERMOKIN_SHARED or place ../shared)", p.display());
    None
}

/// Table 9's nominal ABB IRB 140 in the same-orientation convention, built in code for crates that must
/// not read files (the bundled `configs/irb140.toml` holds the same numbers; a test in `thermokin-io`
/// compares them). Joint axes Z, Y, Y, X, Y, X; the TCP 25.5 mm along X past joint 6, turned Ry(90°).
pub fn irb140_table9() -> thermokin_chain::Chain {
    use nalgebra::{Isometry3, Vector3};
    use thermokin_chain::{Chain, FixedRow, Joint};
    let axes = [
        Vector3::z_axis(),
        Vector3::y_axis(),
        Vector3::y_axis(),
        Vector3::x_axis(),
        Vector3::y_axis(),
        Vector3::x_axis(),
    ];
    let offsets = [
        [0.0, 0.0, 104.5],
        [70.0, 65.0, 247.5],
        [0.0, -123.0, 360.0],
        [238.5, 58.0, 0.0],
        [141.5, 0.0, 0.0],
        [39.5, 0.0, 0.0],
    ];
    let joints = axes
        .iter()
        .zip(offsets)
        .enumerate()
        .map(|(i, (a, o))| Joint::revolute(format!("A{}", i + 1), Vector3::from(o), *a))
        .collect();
    let tool = Isometry3::new(Vector3::new(25.5, 0.0, 0.0), Vector3::new(0.0, 90f64.to_radians(), 0.0));
    match Chain::new(FixedRow::identity(), joints, FixedRow::from_isometry(&tool)) {
        Ok(c) => c,
        Err(e) => unreachable!("Table 9 is a valid chain: {e}"),
    }
}
