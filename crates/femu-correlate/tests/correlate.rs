//! Evidence for femu-correlate, gathered in one test binary.

mod correlate {
    mod bounds;
    pub mod common;
    mod correlation;
    mod expansion;
    mod frf;
    mod identities;
    mod inputs;
    mod placement;
    mod study;
}
