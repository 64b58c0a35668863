//! A robot as a front end asks for it: its file (TOML or URDF, the URDF's base and tip), the tool and
//! base it replaces, a deviation table with its time profile and semantics, and the operating state — read
//! and checked once, by the rules every front end shares ([`RobotModel::check_state`],
//! [`table_in_force`]).

use std::path::PathBuf;

use nalgebra::Isometry3;
use thermokin_chain::{Chain, ChainError, FixedRow, OperatingState, Robot};
use thermokin_deform::{
    DeformError, DeviationTable, ProfileSpec, RobotModel, SemanticsKind, TableSemantics, TimeProfile, table_in_force,
};

use crate::{IoError, RobotOptions, read_deviation_table_for, read_profile_spec, read_robot_model_with};

/// What a front end asks of a robot file.
#[derive(Clone, Debug, Default)]
pub struct RobotRequest {
    /// The robot file: TOML (extended, DH, modified DH; a calibrated robot) or URDF.
    pub path: PathBuf,
    /// The URDF's base and tip links.
    pub options: RobotOptions,
    /// A tool behind the file's: the TCP in the file's tool frame (a URDF's tip link, a TOML's `[tool]`),
    /// composed after it — the identity is the file's own tool.
    pub tool: Option<Isometry3<f64>>,
    /// A base replacing the file's: the robot base in the world frame.
    pub base: Option<Isometry3<f64>>,
    /// A deviation table (the authors' CSV or TOML).
    pub deformation: Option<PathBuf>,
    /// How the table grows with time (its file, if it names one, read here).
    pub profile: Option<ProfileSpec>,
    /// How the table acts on the robot.
    pub semantics: SemanticsKind,
    /// The operating state: time, sensor readings, payload.
    pub state: OperatingState,
}

/// Why a robot could not be loaded: a file, or a state or table the robot cannot use
/// ([`DeformError::State`]), or an override that makes no chain.
#[derive(Debug, thiserror::Error)]
pub enum LoadError {
    /// A file could not be read.
    #[error(transparent)]
    Io(#[from] IoError),
    /// A state, table or profile the robot cannot use.
    #[error(transparent)]
    Deform(#[from] DeformError),
    /// A tool or base that makes no valid chain.
    #[error(transparent)]
    Chain(#[from] ChainError),
}

/// A robot loaded as requested.
#[derive(Clone, Debug)]
pub struct LoadedRobot {
    /// The robot (with the requested tool and base).
    pub robot: Robot,
    /// The robot with every correction its file carries.
    pub model: RobotModel,
    /// The deviation table, when one was given.
    pub table: Option<DeviationTable>,
    /// How the table acts on the robot.
    pub semantics: TableSemantics,
    /// The operating state.
    pub state: OperatingState,
    /// The time profile, its file read.
    pub profile: Option<TimeProfile>,
}

impl LoadedRobot {
    /// Reads the robot, puts the requested tool behind its tool frame and replaces its base, reads the
    /// table and profile, and checks the state against what the robot can use.
    pub fn load(request: &RobotRequest) -> Result<Self, LoadError> {
        let model = read_robot_model_with(&request.path, &request.options)?;
        let mut robot = model.robot().clone();
        if let Some(tip_from_tcp) = &request.tool {
            let last_joint_from_tcp = robot.chain().tool().pose() * tip_from_tcp;
            robot = robot.with_chain(robot.chain().with_tool(FixedRow::from_isometry(&last_joint_from_tcp))?)?;
        }
        if let Some(world_from_base) = &request.base {
            robot = robot.with_chain(robot.chain().with_base(FixedRow::from_isometry(world_from_base))?)?;
        }
        let dof = robot.chain().dof();
        let table = request.deformation.as_ref().map(|p| read_deviation_table_for(p, dof)).transpose()?;
        let model = model.with_robot(robot.clone())?;
        let profile = request.profile.as_ref().map(|p| read_profile_spec(p, dof)).transpose()?;
        model.check_state(&request.state, table.is_some(), profile.is_some())?;
        let semantics = request.semantics.at_home(dof);
        Ok(Self { robot, model, table, semantics, state: request.state.clone(), profile })
    }

    /// The chain fk and ik work on: the robot's, or deformed by the table in force ([`table_in_force`]:
    /// the profile's share at the state's time, or the table in full).
    pub fn working_chain(&self) -> Result<Chain, LoadError> {
        let Some(table) = &self.table else { return Ok(self.robot.chain().clone()) };
        let drifts = self.model.needs().0;
        let table = table_in_force(table, self.profile.as_ref(), self.state.time_min, drifts)?;
        Ok(table.apply(self.robot.chain(), &self.semantics)?)
    }

    /// The robot fk and ik work on: the file's model, its chain deformed by the table in force when a
    /// table is given.
    pub fn working_model(&self) -> Result<RobotModel, LoadError> {
        if self.table.is_none() {
            return Ok(self.model.clone());
        }
        let robot = self.robot.with_chain(self.working_chain()?)?;
        Ok(self.model.clone().with_robot(robot)?)
    }
}
