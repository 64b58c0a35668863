//! Integration tests of the kinematic core: conventions, conversions, Jacobians.

mod conversions;
mod jacobians;
mod support;
