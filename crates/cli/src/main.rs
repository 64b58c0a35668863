//! The `thermokin` command line: forward and inverse kinematics, thermal compensation runs, and the
//! reproduction of the paper's case studies.

mod args;
mod bundled;
mod commands;
mod diagnosis;
mod input;
mod plots;
mod reproduce;

use std::process::ExitCode;

use clap::Parser;

/// Exit statuses, documented in `--help` and the README.
pub mod exit {
    /// Everything worked.
    pub const OK: u8 = 0;
    /// Internal failure (a bug, or an output that could not be written).
    pub const FAILURE: u8 = 1;
    /// Bad input: unreadable or malformed file, bad flag value, conflicting flags.
    pub const BAD_INPUT: u8 = 2;
    /// The run finished, but some targets were not reached (each one is a record in the output).
    pub const PARTIAL: u8 = 3;
    /// `reproduce-paper --check` found drift from the golden outputs.
    pub const DRIFT: u8 = 4;
}

/// An error with the exit status it maps to.
pub struct Failure {
    /// Exit status.
    pub code: u8,
    /// The error.
    pub error: anyhow::Error,
}

impl Failure {
    /// A bad-input failure.
    pub fn input(error: impl Into<anyhow::Error>) -> Self {
        Self { code: exit::BAD_INPUT, error: error.into() }
    }
    /// An internal failure.
    pub fn internal(error: impl Into<anyhow::Error>) -> Self {
        Self { code: exit::FAILURE, error: error.into() }
    }
}

fn main() -> ExitCode {
    let mut cli = match args::Cli::try_parse() {
        Ok(c) => c,
        Err(e) => {
            let code = if e.use_stderr() { exit::BAD_INPUT } else { exit::OK };
            let _ = e.print();
            return ExitCode::from(code);
        }
    };
    bundled::resolve_inputs(&mut cli);
    match commands::run(cli) {
        Ok(code) => ExitCode::from(code),
        Err(f) => {
            eprintln!("error: {:#}", f.error);
            ExitCode::from(f.code)
        }
    }
}
