//! Standard output of a command's results: every line through [`line`], which turns a closed pipe (`… |
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
