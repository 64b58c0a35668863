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
