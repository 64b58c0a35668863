//! The paper's static case study in a few lines: the IRB 140 deformed by Tables 10–11 (every joint row
//! 1 mm and 1° off), the programmed targets of Table 12 solved on the deformed robot, and what the
//! deformed robot reaches with the compensated and with the programmed joints.
//!
//! ```text
//! cargo run --example ik_on_a_deformed_robot -p thermokin-compensate -- [ROBOT.toml DEVIATIONS TARGETS.csv]
//! ```

use std::error::Error;
use std::path::PathBuf;

use thermokin_chain::{OperatingState, units};
use thermokin_compensate::solve_on_model;
use thermokin_deform::{RobotModel, TimeProfile};
use thermokin_ik::{Goal, Params, Status, Workspace, solve};

fn main() -> Result<(), Box<dyn Error>> {
    let root = PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../.."));
    let args: Vec<PathBuf> = std::env::args().skip(1).map(PathBuf::from).collect();
    let at = |k: usize, default: &str| args.get(k).cloned().unwrap_or_else(|| root.join(default));
    let robot = thermokin_io::read_robot(&at(0, "configs/irb140.toml"))?;
    let table = thermokin_io::read_deviation_table(&at(1, "fixtures/paper/deformations-case-study.toml"))?;
    let targets = thermokin_io::read_targets(&at(2, "fixtures/paper/table12-targets.csv"))?;

    let nominal = robot.chain().clone();
    let deformed = RobotModel::new(robot).with_table(&table, &TimeProfile::Static)?;
    let state = OperatingState::default();
    let (params, mut ws) = (Params::default(), Workspace::new(nominal.dof()));
    println!("target   programmed joints: misses by   compensated joints: misses by");
    for (k, target) in targets.iter().enumerate() {
        // The joints the nominal robot would be commanded to, then those the deformed one needs.
        let seed = vec![0.0; nominal.dof()];
        let programmed = solve(&nominal, &Goal::Pose(target.pose), &seed, &params, &mut ws, k as u64)?;
        let compensated =
            solve_on_model(&deformed, &state, &Goal::Pose(target.pose), &programmed.q, &params, &mut ws, k as u64)?;
        if programmed.status != Status::Converged || compensated.status != Status::Converged {
            println!("{:<8} not reached ({:?}, {:?})", target.label, programmed.status, compensated.status);
            continue;
        }
        let miss = |q: &[f64]| -> Result<f64, Box<dyn Error>> {
            Ok((deformed.tool_pose(q, &state)?.translation.vector - target.pose.translation.vector).norm())
        };
        let largest_change =
            programmed.q.iter().zip(&compensated.q).map(|(a, b)| units::degrees((a - b).abs())).fold(0.0, f64::max);
        println!(
            "{:<8} {:>26.4} mm {:>25.2e} mm   (joints moved by up to {largest_change:.3}°)",
            target.label,
            miss(&programmed.q)?,
            miss(&compensated.q)?
        );
    }
    Ok(())
}
