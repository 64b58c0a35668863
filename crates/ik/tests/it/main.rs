//! Integration tests of the IK solver on the bundled IRB 140, nominal and deformed.

mod solve;
