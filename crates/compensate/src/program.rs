//! Robot programs of the compensated joints, for the controller to run as they are: ABB RAPID
//! (`MoveAbsJ` to `jointtarget`s), KUKA KRL (`PTP` to `E6AXIS`) and Universal Robots URScript (`movej`).
//! This is the post-processing the paper's conclusion (a) says is manual today.
//!
//! Joint targets, not Cartesian ones: a Cartesian target would be solved again by the controller on its
//! *nominal* model, undoing the compensation. A transient run gives one program per model update (one
//! block of the program per minute in the paper's cycle), each loading the joints valid for that time,
//! instead of one module with every target of every minute. Targets that were not reached become
//! comments, never motions.

use crate::run::{RunOutput, TargetResult};

/// Which controller language.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum Controller {
    /// ABB RAPID: a module with `CONST jointtarget`s and `MoveAbsJ`.
    Abb,
    /// KUKA KRL: a `.src` with `E6AXIS` aggregates and `PTP`.
    Kuka,
    /// Universal Robots URScript: `movej` with joint vectors in radians.
    UniversalRobots,
}

impl Controller {
    /// The file extension programs of this controller use.
    pub fn extension(self) -> &'static str {
        match self {
            Controller::Abb => "mod",
            Controller::Kuka => "src",
            Controller::UniversalRobots => "script",
        }
    }
}

/// Settings of a program, each in the controller's own terms.
#[derive(Clone, Debug, PartialEq)]
pub struct ProgramSettings {
    /// The language.
    pub controller: Controller,
    /// Program (module, procedure) name; made a valid identifier.
    pub name: String,
    /// ABB `speeddata` (`v100`); KUKA axis velocity in % (`30`); UR joint speed in rad/s (`1.05`).
    pub speed: String,
    /// ABB `zonedata` (`fine`, `z10`); KUKA: `fine` or an approximation (`C_PTP`); UR blend radius in m
    /// (`0` stops at each target).
    pub zone: String,
    /// ABB `tooldata` (`tool0`); unused by the others (joint motions).
    pub tool: String,
}

impl ProgramSettings {
    /// Conservative defaults for a controller: slow, stopping at every target.
    pub fn new(controller: Controller) -> Self {
        let (speed, zone) = match controller {
            Controller::Abb => ("v100", "fine"),
            Controller::Kuka => ("30", "fine"),
            Controller::UniversalRobots => ("1.05", "0"),
        };
        Self {
            controller,
            name: "thermokin_compensated".into(),
            speed: speed.into(),
            zone: zone.into(),
            tool: "tool0".into(),
        }
    }
}

/// One program of a run: `suffix` is empty for a static run, `_t<minutes>` for each time of a transient
/// one (to append to the file stem).
#[derive(Clone, Debug, PartialEq)]
pub struct Program {
    /// File-name suffix.
    pub suffix: String,
    /// The program text.
    pub text: String,
}

/// An identifier from free text: letters, digits and `_`, starting with a letter, at most `max` chars.
fn identifier(text: &str, max: usize) -> String {
    let mut s: String = text.chars().map(|c| if c.is_ascii_alphanumeric() { c } else { '_' }).collect();
    if !s.starts_with(|c: char| c.is_ascii_alphabetic()) {
        s.insert(0, 'p');
    }
    s.truncate(max);
    s
}

/// Minutes as a file and identifier fragment: `12`, `12p5` for 12.5.
fn minutes(t: f64) -> String {
    let text = format!("{}", (t * 1e6).round() / 1e6);
    text.replace('.', "p").replace('-', "m")
}

/// The programs of a run: one for a static run, one per time step for a transient one.
pub fn programs(run: &RunOutput, settings: &ProgramSettings) -> Vec<Program> {
    let transient = run.rows.iter().any(|r| r.time_min != 0.0);
    let mut blocks: Vec<(f64, Vec<&TargetResult>)> = Vec::new();
    for r in &run.rows {
        match blocks.last_mut() {
            Some((t, rows)) if *t == r.time_min => rows.push(r),
            _ => blocks.push((r.time_min, vec![r])),
        }
    }
    blocks
        .into_iter()
        .map(|(t, rows)| {
            let suffix = if transient { format!("_t{}", minutes(t)) } else { String::new() };
            let name = format!("{}{}", settings.name, suffix);
            let header = format!(
                "thermokin: joints compensated on the deformed model{}; {} targets, {} not reached (comments)",
                if transient { format!(" valid at {t} min") } else { String::new() },
                rows.len(),
                rows.iter().filter(|r| !r.status_is_converged()).count()
            );
            let text = match settings.controller {
                Controller::Abb => abb(&name, &header, &rows, settings),
                Controller::Kuka => kuka(&name, &header, &rows, settings),
                Controller::UniversalRobots => ur(&name, &header, &rows, settings),
            };
            Program { suffix, text }
        })
        .collect()
}

impl TargetResult {
    fn status_is_converged(&self) -> bool {
        self.status == thermokin_ik::Status::Converged
    }
}

/// Joint values written with 6 decimals: 1e-6° is below every controller's resolution (ABB and KUKA
/// store 1e-4° or coarser), and ~2e-8 rad for UR.
fn axes(values: &[f64], decimals: usize) -> Vec<String> {
    values.iter().map(|v| format!("{:.*}", decimals, v + 0.0)).collect()
}

fn abb(name: &str, header: &str, rows: &[&TargetResult], s: &ProgramSettings) -> String {
    let module = identifier(name, 32);
    let mut out = format!("MODULE {module}\n  ! {header}\n");
    let mut moves = String::new();
    for r in rows {
        let target = identifier(&format!("jt_{}", r.label), 32);
        if r.status_is_converged() {
            let mut a = axes(&r.joints_deg, 6);
            a.resize(6, "0".into());
            out.push_str(&format!("  CONST jointtarget {target}:=[[{}],[9E9,9E9,9E9,9E9,9E9,9E9]];\n", a.join(",")));
            moves.push_str(&format!("    MoveAbsJ {target}\\NoEOffs, {}, {}, {};\n", s.speed, s.zone, s.tool));
        } else {
            out.push_str(&format!("  ! {target}: not reached ({:?})\n", r.status));
            moves.push_str(&format!("    ! skipped {}\n", r.label));
        }
    }
    out.push_str(&format!("  PROC main()\n{moves}  ENDPROC\nENDMODULE\n"));
    out
}

fn kuka(name: &str, header: &str, rows: &[&TargetResult], s: &ProgramSettings) -> String {
    let program = identifier(name, 24);
    let approx = if s.zone.eq_ignore_ascii_case("fine") { String::new() } else { format!(" {}", s.zone) };
    let mut out = format!("DEF {program}( )\n; {header}\nBAS(#INITMOV, 0)\nBAS(#VEL_PTP, {})\n", s.speed);
    for r in rows {
        if r.status_is_converged() {
            let a = axes(&r.joints_deg, 6);
            let named: Vec<String> = a.iter().enumerate().take(6).map(|(i, v)| format!("A{} {v}", i + 1)).collect();
            out.push_str(&format!("PTP {{E6AXIS: {}}}{approx} ; {}\n", named.join(", "), r.label));
        } else {
            out.push_str(&format!("; skipped {}: not reached ({:?})\n", r.label, r.status));
        }
    }
    out.push_str("END\n");
    out
}

fn ur(name: &str, header: &str, rows: &[&TargetResult], s: &ProgramSettings) -> String {
    let program = identifier(name, 64);
    let mut out = format!("def {program}():\n  # {header}\n");
    for r in rows {
        if r.status_is_converged() {
            let radians: Vec<f64> = r.joints_deg.iter().map(|d| d.to_radians()).collect();
            out.push_str(&format!(
                "  movej([{}], a=1.4, v={}, r={})  # {}\n",
                axes(&radians, 9).join(", "),
                s.speed,
                s.zone,
                r.label
            ));
        } else {
            out.push_str(&format!("  # skipped {}: not reached ({:?})\n", r.label, r.status));
        }
    }
    out.push_str("end\n");
    out
}
