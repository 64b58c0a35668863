//! Integration tests of the error-parameter model.

mod model;
mod profiles;
