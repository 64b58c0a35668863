//! `thermokin compensate`: which run a request is (the library's `Plan`), the run with its progress, and
//! its outputs — results, joints, robot programs, plots — each written atomically.

use anyhow::anyhow;
use thermokin_chain::Chain;
use thermokin_compensate::{
    AbbTargets, Cycle, Plan, PlanError, ProgramSettings, Request, RunOutput, RunSettings, StreamSettings, Summary,
    SummaryOut, compensate_static_stream, program_files, write_joint_csv,
};
use thermokin_ik::Params;
use thermokin_io::{TargetReader, write_atomic_with};

use std::path::{Path, PathBuf};

use crate::args::CompensateArgs;
use crate::input::{load, program, program_controller, progress_bar, warn_ignored};
use crate::{Failure, exit};

/// The summary on standard output, as text or JSON.
fn print_summary(summary: &Summary, as_json: bool) -> Result<(), Failure> {
    let s = SummaryOut::of(summary);
    if as_json {
        say!("{}", serde_json::to_string(&s).map_err(Failure::internal)?);
    } else {
        say!("{}", s.to_string().trim_end());
    }
    Ok(())
}

pub fn compensate(a: CompensateArgs) -> Result<u8, Failure> {
    let loaded = load(&a.robot)?;
    // Which run this is — the paper's static or transient case on a plain robot's table, or a calibrated
    // robot's targets in their states or over a warm-up — is the library's decision (`Plan::new`).
    let request = Request {
        model: &loaded.model,
        table: loaded.table.as_ref(),
        profile: loaded.profile.as_ref(),
        state: &loaded.state,
        semantics: &loaded.semantics,
        accumulation: a.accumulate,
        duration_min: a.duration,
        step_min: a.step,
    };
    let plan = Plan::new(&request).map_err(|e| plan_error(&a, e))?;
    let settings = run_settings(&a, loaded.semantics.clone(), loaded.model.robot().chain())?;
    if a.stream {
        return match &plan {
            Plan::Static { table } => compensate_streamed(&a, &loaded, table, settings),
            Plan::Transient { .. } => Err(Failure::input(anyhow!("--stream runs the static case: drop --profile"))),
            Plan::InStates { .. } | Plan::Warmup { .. } => Err(Failure::input(anyhow!(
                "--stream runs a plain robot's static case; a calibrated robot's run holds its targets in memory"
            ))),
        };
    }
    let prog = program(&a.targets, a.position_units, &loaded.model)?;
    let run = match plan.cycle() {
        Some(cycle) => with_cycle_bar(cycle, |progress| plan.run(&request, &prog, &settings, progress))?,
        None => plan.run(&request, &prog, &settings, |_, _| {}),
    }
    .map_err(Failure::input)?;
    write_outputs(&a, &loaded, &run)?;
    print_summary(&run.summary, a.json)?;
    Ok(if run.summary.failures > 0 { exit::PARTIAL } else { exit::OK })
}

/// A request the library refuses, in the words of the command line.
fn plan_error(a: &CompensateArgs, e: thermokin_compensate::CompensateError) -> Failure {
    let thermokin_compensate::CompensateError::Plan(plan) = &e else { return Failure::input(e) };
    Failure::input(match plan {
        PlanError::NothingToCompensate => anyhow!(
            "nothing to compensate: {} is a robot as designed (no error parameters, zero offsets or corrections); give --deformation TABLE, or the calibrated robot `diagnose --export` writes",
            a.robot.robot.display()
        ),
        PlanError::IncrementsNeedTransient => {
            anyhow!("--accumulate increments needs a transient run: give --profile (e.g. linear-grow:180)")
        }
        // The library's own words name the setting plainly (accumulation, semantics, a temperature log).
        other => anyhow!("{other}"),
    })
}

/// A run's settings: the semantics, `--accumulate`, the IK's defaults, and `--seed` (degrees; all zero by
/// default) for the first solve.
fn run_settings(
    a: &CompensateArgs,
    semantics: thermokin_deform::TableSemantics,
    chain: &Chain,
) -> Result<RunSettings, Failure> {
    let start = crate::input::seed(chain, a.seed.as_deref())?;
    Ok(RunSettings { semantics, accumulation: a.accumulate, ik: Params::default(), start })
}

/// `run` given a progress callback over `cycle`'s steps: a bar on stderr once the run has lasted a second.
fn with_cycle_bar<T>(cycle: Cycle, run: impl FnOnce(&mut dyn FnMut(usize, usize)) -> T) -> Result<T, Failure> {
    let steps = cycle.times().map_err(Failure::input)?.len();
    let bar = progress_bar(steps as u64, "compensating");
    let out = run(&mut |done, total| bar.set_position(done as u64, total as u64));
    bar.finish();
    Ok(out)
}

/// `compensate --stream`: the static run in chunks, --out written as it goes (atomically: a temporary file
/// renamed at the end, removed on an error).
fn compensate_streamed(
    a: &CompensateArgs,
    loaded: &thermokin_io::LoadedRobot,
    table: &thermokin_deform::DeviationTable,
    settings: RunSettings,
) -> Result<u8, Failure> {
    if a.format != thermokin_compensate::ResultsFormat::Joints {
        return Err(Failure::input(anyhow!("--stream writes the joints only: add --format joints")));
    }
    if a.joints_out.is_some() || a.program.is_some() || a.plot.is_some() {
        return Err(Failure::input(anyhow!("--stream writes --out only: drop --joints-out, --program and --plot")));
    }
    let input = thermokin_io::open(&a.targets).map_err(Failure::input)?;
    let mut targets = TargetReader::new(&a.targets, input).map_err(Failure::input)?;
    warn_ignored(&a.targets, targets.ignored_columns());
    let stream = StreamSettings::new(settings);
    let spinner = indicatif::ProgressBar::hidden();
    spinner.set_style(
        indicatif::ProgressStyle::with_template("{spinner} compensating: {human_pos} targets, {per_sec}")
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_spinner()),
    );
    let bar = crate::input::DelayedBar::new(spinner);
    let mut run = None;
    let written = write_atomic_with(&a.out, |w| {
        let r = compensate_static_stream(loaded.robot.chain(), table, &mut targets, w, &stream, |done| {
            bar.set_position(done as u64, done as u64)
        });
        let failed = r.as_ref().err().map(|e| std::io::Error::other(e.to_string()));
        run = Some(r);
        failed.map_or(Ok(()), Err)
    });
    bar.finish();
    let summary = match run {
        Some(r) => r.map_err(Failure::input)?,
        None => {
            return Err(Failure::internal(written.err().map_or_else(|| anyhow!("nothing was run"), |e| anyhow!(e))));
        }
    };
    written.map_err(Failure::internal)?;
    print_summary(&summary, a.json)?;
    Ok(if summary.failures > 0 { exit::PARTIAL } else { exit::OK })
}

fn write_outputs(a: &CompensateArgs, loaded: &thermokin_io::LoadedRobot, run: &RunOutput) -> Result<(), Failure> {
    crate::out::save_with(&a.out, |w| a.format.write(w, run, run.timed))?;
    if let Some(p) = &a.joints_out {
        crate::out::save_with(p, |w| write_joint_csv(w, run))?;
    }
    if let Some(p) = &a.program {
        for (path, text) in robot_programs(a, p, loaded.robot.chain(), run)? {
            crate::out::save(&path, text)?;
        }
    }
    if let Some(dir) = &a.plot {
        let deformed = loaded.table.as_ref().map(|t| t.apply(loaded.robot.chain(), &loaded.semantics)).transpose();
        let deformed = deformed.map_err(Failure::input)?;
        crate::out::save_plots(dir, thermokin_plot::run_plots(run, loaded.robot.chain(), deformed.as_ref()))?;
    }
    Ok(())
}

/// The program files of `--program`: one, or one per time step of a transient run.
fn robot_programs(
    a: &CompensateArgs,
    path: &Path,
    nominal: &Chain,
    run: &RunOutput,
) -> Result<Vec<(PathBuf, String)>, Failure> {
    let mut settings = ProgramSettings::new(program_controller(path, a.controller)?);
    settings.speed = a.speed.clone().unwrap_or(settings.speed);
    settings.zone = a.zone.clone().unwrap_or(settings.zone);
    settings.tool = a.tooldata.clone().unwrap_or(settings.tool);
    settings.abb_targets = if a.robtargets { AbbTargets::Robtarget } else { AbbTargets::Joint };
    program_files(path, run, nominal, &settings).map_err(Failure::input)
}
