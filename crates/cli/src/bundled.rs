//! The files the README's commands name — the bundled robots, the paper's tables, the authors' files,
//! the public URDFs — built into the binary, so that an installed `thermokin` runs them from any
//! directory.
//!
//! A relative path under `configs/` or `fixtures/` that does not exist on disk is read from this copy in
//! memory ([`thermokin_io::bundle`]): nothing is unpacked, so no copy on disk can be edited or planted,
//! and every message gives the path the user typed. A file that does exist on disk always wins.

use crate::Failure;
use crate::args::{Cli, Command, UrdfCommand};

/// `(path, content)` of each file named, read from the repository at build time.
macro_rules! bundle {
    ($($name:literal),+ $(,)?) => {
        &[$(($name, include_bytes!(concat!("../../../", $name)))),+]
    };
}

/// Repository path and content of every bundled file.
const FILES: &[(&str, &[u8])] = bundle![
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
];

/// The bundled robots, by the paths the README gives them.
fn bundled_robots() -> Vec<&'static str> {
    FILES
        .iter()
        .map(|(name, _)| *name)
        .filter(|n| (n.starts_with("configs/") && n.ends_with(".toml")) || n.ends_with(".urdf"))
        .collect()
}

/// Makes the bundled files readable where no file of their path exists, and checks that the robot a
/// command names exists: on disk, or bundled — an error names the bundled robots otherwise.
pub fn check_inputs(cli: &Cli) -> Result<(), Failure> {
    thermokin_io::bundle(FILES);
    let robot = match &cli.command {
        Command::Fk(a) => &a.robot,
        Command::Ik(a) => &a.robot,
        Command::Compensate(a) => &a.robot,
        Command::Urdf(UrdfCommand::Export { robot, .. }) => robot.as_ref(),
        Command::Diagnose(a) => &a.robot,
        Command::Simulate(a) => &a.robot,
        Command::Plan(a) => &a.robot,
        Command::Urdf(UrdfCommand::Import { .. }) | Command::ReproducePaper(_) => return Ok(()),
    };
    if thermokin_io::file_exists(&robot.robot) {
        return Ok(());
    }
    Err(Failure::input(anyhow::anyhow!(
        "{}: no such file (bundled robots: {})",
        robot.robot.display(),
        bundled_robots().join(", ")
    )))
}
