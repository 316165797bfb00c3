//! Shared helpers of the workflow tests.
pub mod real;
