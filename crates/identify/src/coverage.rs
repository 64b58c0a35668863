//! What measured poses must cover before an effect that is a function of a joint's angle can be told from
//! a zero offset — the rule the diagnosis refuses by and the planner plans by, in one place.
//!
//! A gear-ratio error (`s · q`) or a cyclic encoder error is identified from how the error changes along
//! the joint's travel. Over a short arc its terms trade against a zero offset (`s · q = s · q̄ + s · (q −
//! q̄)`), so the fit follows whatever else varies over that arc and extrapolates it elsewhere. Required: a
//! fraction of the travel between the limits ([`Eligibility::min_travel_fraction`]; a revolution when the
//! joint has none), and half a revolution for the cyclic error (or the whole travel, if shorter), whose
//! once- and twice-per-revolution terms need it to separate from an offset and a scale.

use serde::Serialize;
use thermokin_chain::{JointKind, Robot};

use crate::effect::Effect;

/// The thresholds of eligibility: what data must show before an effect may be identified from them.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Eligibility {
    /// Fraction of a joint's travel (between its limits; a revolution without limits) the data must
    /// cover for an effect that is a function of the joint's angle. Default 0.25. (A compliance is judged
    /// by how well its deflection is told from an offset, not by a fraction of its torque range.)
    pub min_travel_fraction: f64,
    /// Temperature span (K) a per-kelvin drift needs. Default 2 K.
    pub min_temperature_span_k: f64,
}

impl Default for Eligibility {
    fn default() -> Self {
        Self { min_travel_fraction: 0.25, min_temperature_span_k: 2.0 }
    }
}

/// The travel of joint `j` (0-based): between its limits, a revolution without.
pub fn travel(robot: &Robot, j: usize) -> f64 {
    robot.chain().joints()[j].limits.map_or(std::f64::consts::TAU, |l| l.upper - l.lower)
}

/// The arc an effect of a joint of this `travel` needs: a fraction of the travel, half a revolution (or
/// the whole travel, if shorter) for a cyclic error.
pub fn needed_arc(travel: f64, cyclic: bool, rules: &Eligibility) -> f64 {
    if cyclic { std::f64::consts::PI.min(travel) } else { rules.min_travel_fraction * travel }
}

/// For an effect with a coverage rule — a gear-ratio scale or a cyclic error of a revolute joint — its
/// joint (0-based) and the arc it needs (radians); `None` for every other effect.
///
/// ```
/// use thermokin_identify::{Effect, Eligibility, JointIndex, arc_needed};
/// let robot = thermokin_chain::Robot::new("irb140", thermokin_testdata::irb140_table9());
/// let j = JointIndex::of(&robot, 1).unwrap();
/// let (joint, arc) = arc_needed(&robot, Effect::Periodic(j), &Eligibility::default()).unwrap();
/// assert_eq!(joint, 1);
/// assert!((arc - std::f64::consts::PI).abs() < 1e-12);
/// assert!(arc_needed(&robot, Effect::JointOffset(j), &Eligibility::default()).is_none());
/// ```
pub fn arc_needed(robot: &Robot, e: Effect, rules: &Eligibility) -> Option<(usize, f64)> {
    match e {
        Effect::JointScale(j) | Effect::Periodic(j)
            if robot.chain().joints()[j.index()].kind == JointKind::Revolute =>
        {
            let j = j.index();
            Some((j, needed_arc(travel(robot, j), matches!(e, Effect::Periodic(_)), rules)))
        }
        // A slide's scale (a lead-screw or rack error) and its guide's straightness need the same
        // fraction of its stroke (mm), where the file gives the stroke.
        Effect::JointScale(j) | Effect::Straightness(j) => {
            let limits = robot.chain().joints()[j.index()].limits?;
            Some((j.index(), needed_arc(limits.upper - limits.lower, false, rules)))
        }
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_arc_needed_is_a_fraction_of_the_travel_or_half_a_revolution() {
        let rules = Eligibility::default();
        let pi = std::f64::consts::PI;
        assert!((needed_arc(4.0 * pi, false, &rules) - pi).abs() < 1e-12);
        assert!((needed_arc(4.0 * pi, true, &rules) - pi).abs() < 1e-12);
        // A joint shorter than half a revolution needs all of it for a cyclic error.
        assert!((needed_arc(2.0, true, &rules) - 2.0).abs() < 1e-12);
        assert!((needed_arc(2.0, false, &rules) - 0.5).abs() < 1e-12);
    }
}
