#![doc = include_str!("../README.md")]
//! `thermokin-io`: every file format at the edge of thermokin — robot TOML, deviation tables (the
//! authors' CSV and TOML), targets CSV, temperature logs, the authors' results files — and atomic writes.
//!
//! This is the one boundary where millimetres and degrees become the library's millimetres and radians.
//! Every error names the file, the line and the field. The readers know nothing about kinematics beyond
//! building the chain's table.

mod bundled;
mod csvtext;
mod deviation;
mod load;
mod measurements;
mod notation;
mod paper;
mod robot;
mod targets;
pub mod units;
mod write;

pub use bundled::{bundle, bundled, bundled_names, file_exists, open, read_bytes};
pub use deviation::{
    parse_deviation_table, parse_temperature_log, read_deviation_table, read_deviation_table_for, read_profile_spec,
    read_temperature_log,
};
pub use load::{LoadError, LoadedRobot, RobotRequest};
pub use measurements::{
    JointRow, JointUnits, MeasurementFormat, PositionUnits, UnitsUnclear, parse_measurements, parse_measurements_with,
    read_configurations, read_configurations_checked, read_joint_rows, read_measurements, read_measurements_joined,
    read_measurements_with, settle_units, unread_columns, write_measurements,
};
pub use notation::{
    PoseOut, PoseRow, csv_cell, outside_limits, parse_list, parse_payload, parse_pose, parse_temperatures,
};
pub use paper::{PaperResultRow, parse_paper_results, read_paper_results};
pub use robot::{
    RobotOptions, is_ur_yaml, parse_robot_model_toml, parse_robot_toml, read_robot, read_robot_model,
    read_robot_model_with, read_robot_with, robot_file_text, robot_model_to_toml, robot_to_toml,
    ur_kinematics_in_state, urdf_in_state,
};
pub use targets::{
    DEFAULT_ORIENTATION_DEG, TargetReader, TargetRows, parse_target_rows, parse_target_rows_for, parse_targets,
    read_target_rows, read_target_rows_for, read_targets, sensor_name,
};
pub use units::Orientation;
pub use write::{remove_temporaries, write_atomic, write_atomic_with};

use std::path::{Path, PathBuf};

/// An input or output problem, located as precisely as the format allows.
#[derive(Debug, thiserror::Error)]
pub enum IoError {
    /// The file could not be read or written at all.
    #[error("{path}: {message}")]
    File {
        /// The file.
        path: PathBuf,
        /// What the operating system said.
        message: String,
    },
    /// The content is wrong at a known place.
    #[error("{path}{at}: {field}: {message}", path = path.display(), at = line.map_or(String::new(), |l| format!(":{l}")))]
    Input {
        /// The file.
        path: PathBuf,
        /// 1-based line, when known.
        line: Option<usize>,
        /// The field, key or column.
        field: String,
        /// What is wrong.
        message: String,
    },
    /// The numbers of a file contradict the unit it is read in, which was not stated.
    #[error("{path}: {unclear} (the unit was not stated)", path = path.display())]
    UnitsUnclear {
        /// The file.
        path: PathBuf,
        /// What the numbers look like.
        unclear: UnitsUnclear,
    },
}

impl IoError {
    pub(crate) fn input(
        path: &Path,
        line: Option<usize>,
        field: impl Into<String>,
        message: impl Into<String>,
    ) -> Self {
        IoError::Input { path: path.to_path_buf(), line, field: field.into(), message: message.into() }
    }

    pub(crate) fn file(path: &Path, err: impl std::fmt::Display) -> Self {
        IoError::File { path: path.to_path_buf(), message: err.to_string() }
    }
}

/// Reads a whole file as UTF-8 text, without a leading byte-order mark. Non-UTF-8 content is an error
/// naming the line of the first bad byte.
pub fn read_text(path: &Path) -> Result<String, IoError> {
    let bytes = read_bytes(path)?.into_owned();
    match String::from_utf8(bytes) {
        Ok(mut s) => {
            if s.starts_with('\u{feff}') {
                s.drain(..3);
            }
            Ok(s)
        }
        Err(e) => {
            let good = e.utf8_error().valid_up_to();
            let line = e.as_bytes()[..good].iter().filter(|&&b| b == b'\n').count() + 1;
            Err(IoError::input(path, Some(line), "text", format!("not UTF-8 (byte {good})")))
        }
    }
}

/// 1-based line of a byte offset in `text`.
pub(crate) fn line_of(text: &str, offset: usize) -> usize {
    text.as_bytes()[..offset.min(text.len())].iter().filter(|&&b| b == b'\n').count() + 1
}
