#![doc = include_str!("../README.md")]
//! The `thermokin` command line: forward and inverse kinematics, thermal compensation runs, the
//! sim-to-real diagnosis, and the reproduction of the paper's case studies. It parses, calls the
//! libraries and prints: every default, rule and refusal is a library's.

/// Prints one line of results on standard output ([`out::line`]); a closed pipe ends the command quietly.
macro_rules! say {
    ($($arg:tt)*) => {
        $crate::out::line(format_args!($($arg)*))?
    };
}

mod args;
mod bundled;
mod commands;
mod compensation;
mod diagnosis;
mod input;
mod out;
mod planning;
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
    /// The diagnosis does not transfer: the export was refused (the report says why).
    pub const REFUSED: u8 = 5;
    /// Interrupted by SIGINT, SIGTERM or SIGHUP: the run stopped, its temporary files removed, no output
    /// half-written.
    pub const INTERRUPTED: i32 = 130;
    /// Standard output closed early (`… | head -1`): reported as SIGPIPE would, and nothing is said.
    pub const CLOSED_PIPE: u8 = 141;
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
    let cli = match args::Cli::try_parse() {
        Ok(c) => c,
        Err(e) => {
            let code = if e.use_stderr() { exit::BAD_INPUT } else { exit::OK };
            let _ = e.print();
            return ExitCode::from(code);
        }
    };
    if let Err(f) = bundled::check_inputs(&cli) {
        eprintln!("error: {:#}", f.error);
        return ExitCode::from(f.code);
    }
    // A run interrupted (Ctrl-C, SIGTERM, SIGHUP) leaves no temporary file beside its outputs.
    let _ = ctrlc::set_handler(|| {
        thermokin_io::remove_temporaries();
        std::process::exit(exit::INTERRUPTED);
    });
    match commands::run(cli) {
        Ok(code) => ExitCode::from(code),
        Err(f) if f.code == exit::CLOSED_PIPE => ExitCode::from(f.code),
        Err(f) => {
            eprintln!("error: {:#}", f.error);
            ExitCode::from(f.code)
        }
    }
}
