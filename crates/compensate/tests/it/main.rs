//! Integration tests of the compensation runs: the paper's two case studies as golden assertions.

mod case_studies;
