//! The robot as one value — its name, its chain and the description data carried beside the chain
//! (link masses for gravity, joint ratings for planners) — and a programmed target. Plain data: the
//! readers build them, every algorithm crate takes them; they live in the core so that readers sit below
//! the algorithms.

use nalgebra::{Isometry3, Vector3};

use crate::{Chain, ChainError};

/// Mass (kg) and centre of mass (mm, in the same-orientation frame of the joint that moves the link) of
/// one link: what gravity compliance needs. Description data carried beside the chain.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LinkMass {
    /// Mass, kg.
    pub mass_kg: f64,
    /// Centre of mass, mm, in the frame of the joint that moves the link.
    pub com_mm: Vector3<f64>,
}

/// Rated maximum speed and effort of a joint — what URDF's `<limit velocity effort>` and a controller's
/// axis data carry: rad/s and N·m for a revolute joint, mm/s and N for a prismatic one. Description data
/// carried beside the chain, like [`LinkMass`]; `None` where the robot's description does not say.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct JointRatings {
    /// Largest joint speed.
    pub velocity: Option<f64>,
    /// Largest joint torque or force.
    pub effort: Option<f64>,
}

/// A robot: name, chain, and per joint the mass of the link it moves and its ratings. The per-joint
/// lists always have one entry per joint of the chain (checked on construction), so that a robot
/// cannot carry the masses of another.
///
/// ```
/// use nalgebra::Vector3;
/// use thermokin_chain::{Chain, FixedRow, Joint, LinkMass, Robot};
///
/// let chain = Chain::new(
///     FixedRow::identity(),
///     vec![Joint::revolute("A1", Vector3::zeros(), Vector3::z_axis())],
///     FixedRow::from_isometry(&nalgebra::Isometry3::translation(100.0, 0.0, 0.0)),
/// )?;
/// let robot = Robot::new("one-axis", chain)
///     .with_masses(vec![Some(LinkMass { mass_kg: 2.0, com_mm: Vector3::new(50.0, 0.0, 0.0) })])?;
/// assert_eq!(robot.masses()[0].unwrap().mass_kg, 2.0);
/// assert!(robot.clone().with_masses(vec![None, None]).is_err()); // one entry per joint
/// # Ok::<(), thermokin_chain::ChainError>(())
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct Robot {
    name: String,
    chain: Chain,
    masses: Vec<Option<LinkMass>>,
    ratings: Vec<JointRatings>,
}

impl Robot {
    /// A robot with no masses and no ratings known.
    pub fn new(name: impl Into<String>, chain: Chain) -> Self {
        let n = chain.dof();
        Self { name: name.into(), chain, masses: vec![None; n], ratings: vec![JointRatings::default(); n] }
    }

    /// The same robot with these link masses (one per joint).
    pub fn with_masses(mut self, masses: Vec<Option<LinkMass>>) -> Result<Self, ChainError> {
        check_len("masses", self.chain.dof(), masses.len())?;
        self.masses = masses;
        Ok(self)
    }

    /// The same robot with these joint ratings (one per joint).
    pub fn with_ratings(mut self, ratings: Vec<JointRatings>) -> Result<Self, ChainError> {
        check_len("ratings", self.chain.dof(), ratings.len())?;
        self.ratings = ratings;
        Ok(self)
    }

    /// The same robot on another chain of as many joints — a deformed or calibrated one; masses and
    /// ratings are kept.
    pub fn with_chain(&self, chain: Chain) -> Result<Self, ChainError> {
        if chain.dof() != self.chain.dof() {
            return Err(ChainError::JointCountChanged { expected: self.chain.dof(), got: chain.dof() });
        }
        Ok(Self { chain, ..self.clone() })
    }

    /// The same robot under another name.
    pub fn renamed(mut self, name: impl Into<String>) -> Self {
        self.name = name.into();
        self
    }

    /// The robot carrying `payload` on its flange (a probe, a gripper, a load), its centre in the last
    /// link's frame (the flange's same-orientation frame, mm): merged with that link's own mass as one
    /// body (masses added, centres weighted by mass). A non-positive or non-finite payload is refused.
    pub fn with_payload(mut self, payload: LinkMass) -> Result<Self, ChainError> {
        let ok = payload.mass_kg.is_finite() && payload.mass_kg > 0.0 && payload.com_mm.iter().all(|v| v.is_finite());
        let last = self.chain.dof().checked_sub(1);
        let (true, Some(last)) = (ok, last) else {
            return Err(ChainError::BadPayload { mass_kg: payload.mass_kg });
        };
        self.masses[last] = Some(match self.masses[last] {
            None => payload,
            Some(link) => {
                let mass_kg = link.mass_kg + payload.mass_kg;
                LinkMass { mass_kg, com_mm: (link.com_mm * link.mass_kg + payload.com_mm * payload.mass_kg) / mass_kg }
            }
        });
        Ok(self)
    }

    /// Display name.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// The extended table.
    pub fn chain(&self) -> &Chain {
        &self.chain
    }

    /// Per joint: the mass of the link it moves, when known.
    pub fn masses(&self) -> &[Option<LinkMass>] {
        &self.masses
    }

    /// Per joint: rated speed and effort (rad/s, N·m; mm/s, N for prismatic joints).
    pub fn ratings(&self) -> &[JointRatings] {
        &self.ratings
    }

    /// The robot's parts: name, chain, masses, ratings.
    pub fn into_parts(self) -> (String, Chain, Vec<Option<LinkMass>>, Vec<JointRatings>) {
        (self.name, self.chain, self.masses, self.ratings)
    }
}

fn check_len(field: &'static str, expected: usize, got: usize) -> Result<(), ChainError> {
    if expected == got { Ok(()) } else { Err(ChainError::DescriptionLength { field, expected, got }) }
}

/// A programmed target: a label (`P1`, …) and the TCP pose to reach in the base frame (mm). What a
/// targets file holds and what a compensation run solves for; `line` is where it was read, when it was.
#[derive(Clone, Debug, PartialEq)]
pub struct Target {
    /// Label (`P1`, …).
    pub label: String,
    /// Programmed `base_from_tcp`, mm.
    pub pose: Isometry3<f64>,
    /// Line of the file it was read from, if any (for messages).
    pub line: Option<usize>,
}

impl Target {
    /// A target not read from a file.
    pub fn new(label: impl Into<String>, pose: Isometry3<f64>) -> Self {
        Self { label: label.into(), pose, line: None }
    }
}
