//! Integration tests of the `thermokin` binary: outputs, exit statuses, bad input, atomic writes.

mod cli;
