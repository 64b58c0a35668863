//! Standard output of a command's results: every line through [`line()`], which turns a closed pipe (`… |
//! head -1`) into [`exit::CLOSED_PIPE`] — the command ends quietly — instead of `println!`'s panic.

use std::io::Write;

use crate::{Failure, exit};

/// Writes `text` and a newline on standard output.
pub fn line(text: std::fmt::Arguments<'_>) -> Result<(), Failure> {
    let mut out = std::io::stdout().lock();
    writeln!(out, "{text}").and_then(|()| out.flush()).map_err(|e| {
        if e.kind() == std::io::ErrorKind::BrokenPipe {
            Failure { code: exit::CLOSED_PIPE, error: anyhow::anyhow!("standard output closed") }
        } else {
            Failure::internal(anyhow::anyhow!("writing standard output: {e}"))
        }
    })
}

/// Writes `bytes` to `path` atomically ([`thermokin_io::write_atomic`]): a write that fails is an internal
/// failure.
pub fn save(path: &std::path::Path, bytes: impl AsRef<[u8]>) -> Result<(), Failure> {
    thermokin_io::write_atomic(path, bytes.as_ref()).map_err(Failure::internal)
}

/// Writes `path` atomically through `write` ([`thermokin_io::write_atomic_with`]).
pub fn save_with(
    path: &std::path::Path,
    fill: impl FnOnce(&mut std::io::BufWriter<Box<dyn Write>>) -> std::io::Result<()>,
) -> Result<(), Failure> {
    thermokin_io::write_atomic_with(path, fill).map_err(Failure::internal)
}

/// Writes each plot into `dir` (created when missing), atomically.
pub fn save_plots(
    dir: &std::path::Path,
    plots: Result<thermokin_plot::Plots, thermokin_plot::PlotError>,
) -> Result<(), Failure> {
    std::fs::create_dir_all(dir).map_err(|e| Failure::internal(anyhow::anyhow!("{}: {e}", dir.display())))?;
    for (name, svg) in plots.map_err(Failure::internal)? {
        save(&dir.join(name), svg)?;
    }
    Ok(())
}

/// Prints `rows` on standard output: as CSV under `header`, or as one JSON object per line.
pub fn rows<T: serde::Serialize>(
    rows: &[T],
    json: bool,
    header: &str,
    csv: impl Fn(&T) -> String,
) -> Result<(), Failure> {
    if !json {
        line(format_args!("{header}"))?;
    }
    for row in rows {
        let text = if json { serde_json::to_string(row).map_err(Failure::internal)? } else { csv(row) };
        line(format_args!("{text}"))?;
    }
    Ok(())
}
