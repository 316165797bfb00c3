//! Evidence for femu-correlate, gathered in one test binary.

mod correlate {
    mod bounds;
    pub mod common;
    mod correlation;
    mod identities;
    mod inputs;
}
