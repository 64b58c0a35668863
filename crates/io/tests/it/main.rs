//! Integration tests of the readers: the bundled IRB 140 and its DH tables, the authors' files, bad input.

mod bad_input;
mod irb140;
mod readers;
