//! Integration tests of the diagnosis: hidden effects it must find, the real Rokae data set, the paper.
#![allow(clippy::unwrap_used, clippy::panic, clippy::type_complexity, missing_docs)] // Tests unwrap and panic to fail.

mod at_use;
mod branches;
mod catalogue;
mod causes;
mod column;
mod export;
mod frames;
mod golden;
mod gross;
mod hidden;
mod identified;
mod payload;
mod real_data;
mod screen;
mod sessions;
mod shrinkage;
mod six_d;
mod temperature;
mod tilts;
mod tracker;
mod transfer;
mod wam;
mod warmups;
mod weights;
