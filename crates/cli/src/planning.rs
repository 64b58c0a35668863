//! `thermokin plan`: which poses to measure next.

use anyhow::anyhow;
use thermokin_chain::Robot;
use thermokin_compensate::poses_program;
use thermokin_identify::Effect;
use thermokin_io::read_configurations_checked;
use thermokin_planner::{Candidates, Params, Region, WorkspaceBox};

use crate::args::{PlanArgs, parse_list};
use crate::input::{load, program_controller, working_chain};
use crate::{Failure, exit};

/// The configurations of a joints file (radians), with their lines.
fn configurations(path: &std::path::Path, robot: &Robot, a: &PlanArgs) -> Result<(Vec<Vec<f64>>, Vec<usize>), Failure> {
    let kinds: Vec<_> = robot.chain().joints().iter().map(|j| j.kind).collect();
    read_configurations_checked(path, &kinds, a.joint_units).map_err(crate::input::units_error)
}

pub fn plan(a: PlanArgs) -> Result<u8, Failure> {
    let loaded = load(&a.robot)?;
    let chain = working_chain(&a.robot, &loaded)?;
    let robot = loaded.robot.with_chain(chain).map_err(Failure::input)?;
    let named = |e| Failure::input(anyhow!("{}: {e}", a.candidates.as_deref().unwrap_or(&a.out).display()));
    let candidates = match &a.candidates {
        Some(path) => {
            let (joints, lines) = configurations(path, &robot, &a)?;
            Candidates::new(&robot, joints, lines).map_err(named)?
        }
        None => {
            let corners = a.workspace.as_deref().map(|s| parse_list("box", s)).transpose().map_err(Failure::input)?;
            let workspace = corners.map(|c| WorkspaceBox::from_corners(&c)).transpose();
            let workspace = workspace.map_err(|e| Failure::input(anyhow!("--{e}")))?;
            Candidates::sampled(&robot, a.samples, a.seed, workspace.as_ref()).map_err(Failure::input)?
        }
    };
    let measured = match &a.measured {
        Some(path) => configurations(path, &robot, &a)?.0,
        None => Vec::new(),
    };
    let region = match &a.region {
        Some(path) => Region::Poses(configurations(path, &robot, &a)?.0),
        None => Region::Candidates,
    };
    let effects = a.effects.iter().map(|s| Effect::parse(&robot, s).map_err(|e| anyhow!("--effect {s}: {e}")));
    let effects = effects.collect::<anyhow::Result<Vec<_>>>().map_err(Failure::input)?;
    let params = Params {
        poses: a.poses,
        noise_mm: a.noise,
        criterion: a.criterion,
        region,
        beyond_arcs: a.beyond_arcs,
        frame: a.frame,
        tool: a.tool,
        lateral: a.lateral,
        effects: (!effects.is_empty()).then_some(effects),
        seed: a.seed,
        ..Params::default()
    };
    let plan = thermokin_planner::plan(&robot, &candidates, &measured, &params).map_err(named)?;
    say!("{}", plan.text().trim_end());
    crate::out::save_with(&a.out, |w| plan.write_csv(w))?;
    if let Some(path) = &a.program {
        let header = format!("thermokin plan: {} poses to measure, in this order", plan.poses.len());
        let poses: Vec<&[f64]> = plan.poses.iter().map(|p| p.joints_rad.as_slice()).collect();
        let controller = program_controller(path, a.controller)?;
        let text = poses_program(path, &header, &poses, robot.chain(), controller).map_err(Failure::input)?;
        crate::out::save(path, text)?;
    }
    if let Some(p) = &a.json {
        let text = serde_json::to_string_pretty(&plan).map_err(Failure::internal)?;
        crate::out::save(p, text)?;
    }
    if let Some(p) = &a.html {
        let data = a
            .candidates
            .as_ref()
            .map_or_else(|| format!("{} sampled configurations", a.samples), |c| c.display().to_string());
        let page = thermokin_report::plan_page(
            &plan,
            &thermokin_report::PageContext::new(a.robot.robot.display().to_string(), data),
        );
        crate::out::save(p, page)?;
    }
    say!("\nplan → {}", a.out.display());
    Ok(exit::OK)
}
