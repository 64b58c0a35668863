//! A link's mass and centre, and gravity's standard value: what every gravity load is computed from —
//! the chain's links ([`crate::Robot::masses`]) and a branch's ([`crate::Branch::masses`]) alike.

use nalgebra::Vector3;

/// Standard gravity, m/s²: a link mass in kg and a lever in mm give N·mm ([`crate::units::newton_metres`]
/// for N·m).
pub(crate) const STANDARD_GRAVITY: f64 = 9.806_65;

/// Mass (kg) and centre of mass (mm, in the same-orientation frame of the joint that moves the link) of
/// one link: what gravity compliance needs. Description data carried beside the chain.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LinkMass {
    /// Mass, kg.
    pub mass_kg: f64,
    /// Centre of mass, mm, in the frame of the joint that moves the link.
    pub com_mm: Vector3<f64>,
}

impl LinkMass {
    /// Two bodies in one frame as one: masses added, centres weighted by mass (a link and the payload it
    /// carries). The sum must be positive.
    pub fn combined_with(self, other: LinkMass) -> LinkMass {
        let mass_kg = self.mass_kg + other.mass_kg;
        LinkMass { mass_kg, com_mm: (self.com_mm * self.mass_kg + other.com_mm * other.mass_kg) / mass_kg }
    }
}
