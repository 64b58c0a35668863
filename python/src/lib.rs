//! `thermokin` for Python: the native module `thermokin._native`, re-exported by the `thermokin`
//! package (`python/thermokin/__init__.py`). Every call is a call of the libraries the command line
//! calls, in the command line's units (mm, degrees) and names; batches release the GIL and run on
//! rayon; library errors become `thermokin.errors` exceptions with the command line's text.

mod arrays;
mod convert;
mod errors;
mod pipeline;
mod planning;
mod robot;

use pyo3::prelude::*;

/// The native module.
#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<robot::PyRobot>()?;
    m.add_class::<robot::IkResult>()?;
    m.add_class::<pipeline::PyMeasurements>()?;
    m.add_class::<pipeline::PyReport>()?;
    m.add_class::<pipeline::PyCompensation>()?;
    m.add_function(wrap_pyfunction!(pipeline::simulate, m)?)?;
    m.add_function(wrap_pyfunction!(pipeline::diagnose, m)?)?;
    m.add_function(wrap_pyfunction!(pipeline::compensate, m)?)?;
    m.add_class::<planning::PyPlan>()?;
    m.add_function(wrap_pyfunction!(planning::plan, m)?)?;
    m.add_function(wrap_pyfunction!(pipeline::pose_to_xyz_euler, m)?)?;
    Ok(())
}
