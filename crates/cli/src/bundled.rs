//! The bundled files ([`thermokin_bundled`]) made readable, and the robot a command names checked: on
//! disk or bundled, every message giving the path the user typed.

use crate::Failure;
use crate::args::{Cli, Command, UrdfCommand};

/// Makes the bundled files readable where no file of their path exists, and checks that the robot a
/// command names exists: on disk, or bundled — an error names the bundled robots otherwise.
pub fn check_inputs(cli: &Cli) -> Result<(), Failure> {
    thermokin_io::bundle(thermokin_bundled::FILES);
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
        thermokin_bundled::robots().join(", ")
    )))
}
