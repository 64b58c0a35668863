//! The authors' scene against the authors' files: the tool point identified on minute 0, the static
//! replay checked on the 50 static rows, the candidate explanations judged.
#![allow(clippy::unwrap_used, clippy::panic, missing_docs)] // Tests unwrap and panic to fail.

mod print;
mod scene;
