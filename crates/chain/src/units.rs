//! The one place where a unit is converted: degrees ↔ radians, metres ↔ millimetres, N·mm ↔ N·m.
//!
//! Every library value is in millimetres and radians (newton-metres for a torque); files, flags, URDF
//! (metres), robot programs (metres, radians or degrees) and reports (degrees) convert at their edge
//! through these functions — `thermokin_io::units` builds the edge's joint, orientation and error
//! conversions on them. `cargo xtask tidy` fails on a literal conversion (`/ 1000.0`, `* 1000.0`,
//! `PI / 180`, `to_radians`, `to_degrees`) anywhere else in the libraries.

/// Millimetres per metre.
pub const MM_PER_M: f64 = 1000.0;

/// An angle in radians, in degrees.
pub fn degrees(radians: f64) -> f64 {
    radians.to_degrees()
}

/// An angle in degrees, in radians.
pub fn radians(degrees: f64) -> f64 {
    degrees.to_radians()
}

/// A length in metres (URDF, URScript), in millimetres.
pub fn millimetres(metres: f64) -> f64 {
    metres * MM_PER_M
}

/// A length in millimetres, in metres (URDF, URScript).
pub fn metres(millimetres: f64) -> f64 {
    millimetres / MM_PER_M
}

/// One joint value from a file or flag (degrees for a revolute joint, mm for a prismatic one) in the
/// library's radians or mm.
pub fn joint_value_in(kind: crate::JointKind, value: f64) -> f64 {
    if kind == crate::JointKind::Revolute { radians(value) } else { value }
}

/// One joint value of the library (radians, mm) for a file or a terminal (degrees, mm).
pub fn joint_value_out(kind: crate::JointKind, value: f64) -> f64 {
    if kind == crate::JointKind::Revolute { degrees(value) } else { value }
}

/// A torque in N·mm (a force in newtons at a lever in millimetres), in N·m.
pub fn newton_metres(newton_millimetres: f64) -> f64 {
    newton_millimetres / MM_PER_M
}
