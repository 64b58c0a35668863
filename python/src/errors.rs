//! Library errors as Python exceptions (`thermokin.errors`): every one a [`ThermokinError`] subclass,
//! carrying the same text as the command line (file, line and field where the library names them).
//!
//! [`ThermokinError`]: ../../thermokin/errors.py

use std::fmt::Display;
use std::path::Path;

use pyo3::prelude::*;
use pyo3::types::PyAnyMethods;

/// Which Python exception a failure becomes.
#[derive(Clone, Copy, Debug)]
pub enum Kind {
    /// Bad input: a value, a setting, a file's content (`InputError`, a `ValueError`).
    Input,
    /// A file that is not there (`MissingFileError`, a `FileNotFoundError`).
    Missing,
    /// A result the library refuses to hand over as asked: a diagnosis that does not transfer
    /// (`RefusedError`).
    Refused,
    /// Anything else the library refuses (`ThermokinError`).
    Other,
}

/// The exception `kind` with `message`.
pub fn raise(kind: Kind, message: impl Display) -> PyErr {
    let name = match kind {
        Kind::Input => "InputError",
        Kind::Missing => "MissingFileError",
        Kind::Refused => "RefusedError",
        Kind::Other => "ThermokinError",
    };
    let message = message.to_string();
    Python::attach(|py| {
        let made = py
            .import("thermokin.errors")
            .and_then(|m| m.getattr(name))
            .and_then(|class| class.call1((message.clone(),)));
        match made {
            Ok(exception) => PyErr::from_value(exception),
            // The package's own module is missing: the installation is broken; say what failed anyway.
            Err(e) => pyo3::exceptions::PyRuntimeError::new_err(format!("{message} (thermokin.errors: {e})")),
        }
    })
}

/// Bad input.
pub fn input(e: impl Display) -> PyErr {
    raise(Kind::Input, e)
}

/// A file error: `MissingFileError` when the file is not there, `InputError` for its content.
pub fn io(e: thermokin_io::IoError) -> PyErr {
    match &e {
        thermokin_io::IoError::File { path, .. } if !Path::new(path).exists() => raise(Kind::Missing, e),
        _ => raise(Kind::Input, e),
    }
}

/// `Err(MissingFileError)` naming `path` when it does not exist (before a reader that would only say
/// "cannot read").
pub fn must_exist(path: &Path) -> PyResult<()> {
    if path.exists() { Ok(()) } else { Err(raise(Kind::Missing, format!("{}: no such file", path.display()))) }
}
