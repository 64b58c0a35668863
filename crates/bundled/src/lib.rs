#![doc = include_str!("../README.md")]
//! `thermokin-bundled`: the files the README's and the guide's commands name — the bundled robots, the
//! paper's tables, the authors' files, the public URDFs, the real UR10 (series B and C), WAM and Rokae sets — built into the
//! binary that links this crate, so that an installed `thermokin` runs them from any directory. A front
//! end hands [`FILES`] to `thermokin_io::bundle`: a relative path under `configs/` or `fixtures/` that
//! does not exist on disk is then read from this copy in memory (nothing is unpacked, so no copy on disk
//! can be edited or planted); a file that does exist on disk always wins.

/// `(path, content)` of each file named, read from the repository at build time.
macro_rules! bundle {
    ($($name:literal),+ $(,)?) => {
        &[$(($name, include_bytes!(concat!("../../../", $name)))),+]
    };
}

/// Repository path and content of every bundled file.
pub const FILES: &[(&str, &[u8])] = bundle![
    "configs/irb140-dh-table2.toml",
    "configs/irb140-dh-table3.toml",
    "configs/irb140-dh-table4.toml",
    "configs/irb140-scene.toml",
    "configs/irb140.toml",
    "fixtures/paper/deformations-case-study.toml",
    "fixtures/paper/deformations-measured.toml",
    "fixtures/paper/table12-targets.csv",
    "fixtures/paper/table14-reached-static.csv",
    "fixtures/paper/table16-joints-static.csv",
    "fixtures/paper/authors/deformations-case-study.csv",
    "fixtures/paper/authors/deformations-measured.csv",
    "fixtures/paper/authors/deformations-zero.csv",
    "fixtures/paper/authors/results-static-case-study.csv",
    "fixtures/paper/authors/results-transient-case-study.csv",
    "fixtures/paper/authors/targets-cube-front.csv",
    "fixtures/paper/authors/targets-cube-side.csv",
    "fixtures/urdf/abb_irb140.urdf",
    "fixtures/urdf/kinova.urdf",
    "fixtures/urdf/panda.urdf",
    "fixtures/urdf/ur10.urdf",
    "fixtures/urdf/ur5.urdf",
    "fixtures/urdf/xarm7.urdf",
    "fixtures/urdf/z1.urdf",
    "fixtures/real/ur10-ipa/series_B.csv",
    "fixtures/real/ur10-ipa/series_C.csv",
    "fixtures/real/jacobi-wam/wam.urdf",
    "fixtures/real/jacobi-wam/wam-grid.csv",
    "fixtures/real/jacobi-wam/wam-random.csv",
    "fixtures/real/rokae-robot-b/rokae.toml",
    "fixtures/real/rokae-robot-b/joints-deg.csv",
    "fixtures/real/rokae-robot-b/tracker-poses.csv",
];

/// The bundled robots, by the paths the README gives them.
pub fn robots() -> Vec<&'static str> {
    FILES
        .iter()
        .map(|(name, _)| *name)
        .filter(|n| (n.starts_with("configs/") && n.ends_with(".toml")) || n.ends_with(".urdf"))
        .collect()
}
