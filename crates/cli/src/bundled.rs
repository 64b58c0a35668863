//! The files the README's commands name — the bundled robots, the paper's tables, the authors' files,
//! the public URDFs — built into the binary, so that an installed `thermokin` runs them from any
//! directory.
//!
//! A relative path under `configs/` or `fixtures/` that does not exist on disk is served from this copy:
//! the file (or every file of the directory) is written once into a cache folder under the system's
//! temporary directory, named by the content's hash, and the path is replaced by the cached one. A file
//! that does exist on disk always wins.

use std::path::{Path, PathBuf};

use crate::args::{Cli, Command, RobotArgs, UrdfCommand};

/// Repository path and content of every bundled file.
const FILES: &[(&str, &[u8])] = &[
    ("configs/irb140-dh-table2.toml", include_bytes!("../../../configs/irb140-dh-table2.toml")),
    ("configs/irb140-dh-table3.toml", include_bytes!("../../../configs/irb140-dh-table3.toml")),
    ("configs/irb140-dh-table4.toml", include_bytes!("../../../configs/irb140-dh-table4.toml")),
    ("configs/irb140-scene.toml", include_bytes!("../../../configs/irb140-scene.toml")),
    ("configs/irb140.toml", include_bytes!("../../../configs/irb140.toml")),
    (
        "fixtures/paper/deformations-case-study.toml",
        include_bytes!("../../../fixtures/paper/deformations-case-study.toml"),
    ),
    ("fixtures/paper/deformations-measured.toml", include_bytes!("../../../fixtures/paper/deformations-measured.toml")),
    ("fixtures/paper/table12-targets.csv", include_bytes!("../../../fixtures/paper/table12-targets.csv")),
    ("fixtures/paper/table14-reached-static.csv", include_bytes!("../../../fixtures/paper/table14-reached-static.csv")),
    ("fixtures/paper/table16-joints-static.csv", include_bytes!("../../../fixtures/paper/table16-joints-static.csv")),
    (
        "fixtures/paper/authors/deformations-case-study.csv",
        include_bytes!("../../../fixtures/paper/authors/deformations-case-study.csv"),
    ),
    (
        "fixtures/paper/authors/deformations-measured.csv",
        include_bytes!("../../../fixtures/paper/authors/deformations-measured.csv"),
    ),
    (
        "fixtures/paper/authors/deformations-zero.csv",
        include_bytes!("../../../fixtures/paper/authors/deformations-zero.csv"),
    ),
    (
        "fixtures/paper/authors/results-static-case-study.csv",
        include_bytes!("../../../fixtures/paper/authors/results-static-case-study.csv"),
    ),
    (
        "fixtures/paper/authors/results-transient-case-study.csv",
        include_bytes!("../../../fixtures/paper/authors/results-transient-case-study.csv"),
    ),
    (
        "fixtures/paper/authors/targets-cube-front.csv",
        include_bytes!("../../../fixtures/paper/authors/targets-cube-front.csv"),
    ),
    (
        "fixtures/paper/authors/targets-cube-side.csv",
        include_bytes!("../../../fixtures/paper/authors/targets-cube-side.csv"),
    ),
    ("fixtures/urdf/abb_irb140.urdf", include_bytes!("../../../fixtures/urdf/abb_irb140.urdf")),
    ("fixtures/urdf/kinova.urdf", include_bytes!("../../../fixtures/urdf/kinova.urdf")),
    ("fixtures/urdf/panda.urdf", include_bytes!("../../../fixtures/urdf/panda.urdf")),
    ("fixtures/urdf/ur10.urdf", include_bytes!("../../../fixtures/urdf/ur10.urdf")),
    ("fixtures/urdf/ur5.urdf", include_bytes!("../../../fixtures/urdf/ur5.urdf")),
    ("fixtures/urdf/xarm7.urdf", include_bytes!("../../../fixtures/urdf/xarm7.urdf")),
    ("fixtures/urdf/z1.urdf", include_bytes!("../../../fixtures/urdf/z1.urdf")),
];

/// 64-bit FNV-1a of every bundled file: the cache folder's name changes with the content.
fn content_hash() -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for (name, bytes) in FILES {
        for b in name.bytes().chain(bytes.iter().copied()) {
            h ^= u64::from(b);
            h = h.wrapping_mul(0x0100_0000_01b3);
        }
    }
    h
}

/// The cache folder; the hash reads every bundled byte (~1.6 MB), so it is computed once per process.
fn cache_root() -> PathBuf {
    static ROOT: std::sync::OnceLock<PathBuf> = std::sync::OnceLock::new();
    ROOT.get_or_init(|| {
        std::env::temp_dir().join(format!("thermokin-{}-{:016x}", env!("CARGO_PKG_VERSION"), content_hash()))
    })
    .clone()
}

/// Writes one bundled file into the cache (atomically, once) and returns its path there.
fn materialize(name: &str, bytes: &[u8]) -> Option<PathBuf> {
    let path = cache_root().join(name);
    if std::fs::metadata(&path).is_ok_and(|m| m.len() == bytes.len() as u64) {
        return Some(path);
    }
    std::fs::create_dir_all(path.parent()?).ok()?;
    thermokin_io::write_atomic(&path, bytes).ok()?;
    Some(path)
}

/// `path` itself when it exists (or is not a bundled name); otherwise the cached copy of the bundled file
/// or directory of that name.
pub fn resolve(path: &Path) -> PathBuf {
    if path.is_absolute() || path.exists() {
        return path.to_path_buf();
    }
    let key: String =
        path.to_string_lossy().replace('\\', "/").trim_start_matches("./").trim_end_matches('/').to_string();
    if let Some((name, bytes)) = FILES.iter().find(|(name, _)| *name == key) {
        return materialize(name, bytes).unwrap_or_else(|| path.to_path_buf());
    }
    let prefix = format!("{key}/");
    let inside: Vec<&(&str, &[u8])> = FILES.iter().filter(|(name, _)| name.starts_with(&prefix)).collect();
    if inside.is_empty() || inside.iter().any(|(name, bytes)| materialize(name, bytes).is_none()) {
        return path.to_path_buf();
    }
    cache_root().join(key)
}

fn resolve_opt(path: &mut Option<PathBuf>) {
    if let Some(p) = path {
        *p = resolve(p);
    }
}

fn resolve_robot(args: &mut RobotArgs) {
    args.robot = resolve(&args.robot);
    resolve_opt(&mut args.deformation);
}

/// Resolves every input path of a command line (outputs are left as they are).
pub fn resolve_inputs(cli: &mut Cli) {
    match &mut cli.command {
        Command::Fk(a) => resolve_robot(&mut a.robot),
        Command::Ik(a) => resolve_robot(&mut a.robot),
        Command::Compensate(a) => {
            resolve_robot(&mut a.robot);
            a.targets = resolve(&a.targets);
        }
        Command::Urdf(UrdfCommand::Import { file, .. }) => *file = resolve(file),
        Command::Urdf(UrdfCommand::Export { robot, .. }) => resolve_robot(robot),
        Command::Diagnose(a) => {
            resolve_robot(&mut a.robot);
            a.measurements = resolve(&a.measurements);
            resolve_opt(&mut a.holdout);
        }
        Command::Simulate(a) => resolve_robot(&mut a.robot),
        Command::ReproducePaper(a) => {
            a.fixtures = resolve(&a.fixtures);
            a.robot = resolve(&a.robot);
            a.scene_robot = resolve(&a.scene_robot);
            a.authors = resolve(&a.authors);
        }
    }
}
