//! Where a diagnosis spends its time, phase by phase ([`Profile`], from [`crate::diagnose_profiled`]).
//!
//! Wall-clock seconds, measured with [`std::time::Instant`] around each phase; nothing a diagnosis
//! decides reads them (a profiled diagnosis gives the same report as an unprofiled one, and a test says
//! so). The selection on all measurements runs its phases one after the other, each parallel inside,
//! so its figures add up to its wall time. The nested validation's outer folds run two at a time (or as
//! many as there are cores): their phases are summed over the folds, which is more than the wall time
//! the nested validation took — its own line gives that.

use std::sync::Mutex;
use std::time::Instant;

use serde::Serialize;

/// A phase of the diagnosis ([`Profile`]); serialised as its name in a table ([`Phase::name`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Phase {
    /// The screen for gross errors.
    Screen,
    /// Candidates and eligibility: what the data cannot pin down, refused before anything is scored.
    Eligibility,
    /// Forward steps.
    Forward,
    /// Backward steps.
    Backward,
    /// Parsimony: exponential to linear drifts, blocks replaced by smaller ones.
    Parsimony,
    /// The shapes judged beyond the measured poses (half arcs).
    Extrapolation,
    /// The completion for use.
    Completion,
    /// Coupled compliance pairs made physical.
    Pairs,
    /// Shrinkage toward the nominal robot.
    Shrinkage,
    /// The final model's tables: leave-one-out, effect reports, identifiability, residual breakdowns.
    Tables,
    /// The nested validation: every outer fold's whole selection (wall time).
    Nested,
    /// The explicit hold-out set, both protocols.
    Holdout,
    /// Warnings and the verdict.
    Report,
}

impl Phase {
    /// Every phase, in the order a diagnosis runs them.
    pub const ALL: [Phase; 13] = [
        Phase::Screen,
        Phase::Eligibility,
        Phase::Forward,
        Phase::Backward,
        Phase::Parsimony,
        Phase::Extrapolation,
        Phase::Completion,
        Phase::Pairs,
        Phase::Shrinkage,
        Phase::Tables,
        Phase::Nested,
        Phase::Holdout,
        Phase::Report,
    ];

    /// Its name in a table.
    pub fn name(self) -> &'static str {
        match self {
            Phase::Screen => "screen",
            Phase::Eligibility => "eligibility",
            Phase::Forward => "forward",
            Phase::Backward => "backward",
            Phase::Parsimony => "parsimony",
            Phase::Extrapolation => "extrapolation",
            Phase::Completion => "completion",
            Phase::Pairs => "pairs",
            Phase::Shrinkage => "shrinkage",
            Phase::Tables => "tables",
            Phase::Nested => "nested folds",
            Phase::Holdout => "hold-out",
            Phase::Report => "report",
        }
    }

    fn index(self) -> usize {
        Phase::ALL.iter().position(|p| *p == self).unwrap_or(0)
    }
}

impl Serialize for Phase {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        serializer.serialize_str(self.name())
    }
}

/// One phase's cost.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct PhaseCost {
    /// The phase.
    pub phase: Phase,
    /// Wall seconds in the diagnosis on all measurements (the nested validation's line: its wall time).
    pub seconds: f64,
    /// Wall seconds of the same phase inside the nested validation's outer folds, summed over the folds
    /// (they run in parallel: the sum exceeds the nested line's wall time).
    pub outer_fold_seconds: f64,
}

/// Where a diagnosis spent its time.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Profile {
    /// Every phase, in the order they run.
    pub phases: Vec<PhaseCost>,
    /// Wall seconds of the whole diagnosis.
    pub total_seconds: f64,
}

impl Profile {
    /// The phases as a table: each phase's seconds on all measurements and summed over the outer folds.
    pub fn table(&self) -> String {
        let mut out = format!("  {:<16} {:>10} {:>16}\n", "phase", "all data s", "outer folds Σ s");
        for p in &self.phases {
            out += &format!("  {:<16} {:>10.3} {:>16.3}\n", p.phase.name(), p.seconds, p.outer_fold_seconds);
        }
        out
    }
}

/// Seconds per phase, accumulated from any thread.
#[derive(Debug, Default)]
pub(crate) struct Clock {
    seconds: Mutex<[f64; Phase::ALL.len()]>,
}

impl Clock {
    /// Runs `f`, its wall time added to `phase`.
    pub(crate) fn time<T>(&self, phase: Phase, f: impl FnOnce() -> T) -> T {
        let t0 = Instant::now();
        let out = f();
        self.add(phase, t0.elapsed().as_secs_f64());
        out
    }

    /// Adds `seconds` to `phase`.
    pub(crate) fn add(&self, phase: Phase, seconds: f64) {
        if let Ok(mut s) = self.seconds.lock() {
            s[phase.index()] += seconds;
        }
    }

    /// Every phase's seconds so far.
    pub(crate) fn read(&self) -> [f64; Phase::ALL.len()] {
        self.seconds.lock().map(|s| *s).unwrap_or_default()
    }
}

/// The profile of a diagnosis: `main` on all measurements, `outer` summed over the outer folds.
pub(crate) fn profile(main: &Clock, outer: &Clock, total_seconds: f64) -> Profile {
    let (m, o) = (main.read(), outer.read());
    let phases = Phase::ALL
        .iter()
        .map(|&p| PhaseCost { phase: p, seconds: m[p.index()], outer_fold_seconds: o[p.index()] })
        .collect();
    Profile { phases, total_seconds }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)] // Tests unwrap to fail.
mod tests {
    use super::{Phase, PhaseCost, Profile};

    /// A phase's cost serialises with the phase's table name — what `cargo xtask bench` reads back from
    /// the benches' JSON (`phase`, `seconds`, `outer_fold_seconds`) — and the table has a line per phase.
    #[test]
    fn a_profile_serialises_and_tabulates_its_phases_by_name() {
        let cost = PhaseCost { phase: Phase::Nested, seconds: 1.5, outer_fold_seconds: 0.25 };
        let json = serde_json::to_value(cost).unwrap();
        assert_eq!(json, serde_json::json!({"phase": "nested folds", "seconds": 1.5, "outer_fold_seconds": 0.25}));
        let profile = Profile { phases: vec![cost], total_seconds: 1.5 };
        let table = profile.table();
        assert_eq!(table.lines().count(), 2);
        assert!(
            table
                .lines()
                .nth(1)
                .is_some_and(|l| l.contains("nested folds") && l.contains("1.500") && l.contains("0.250"))
        );
    }
}
