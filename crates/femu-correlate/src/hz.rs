//! Eigenvalues in s^-2 and frequencies in Hz, one conversion for every module.

use std::f64::consts::PI;

/// `lambda = (2 pi f)^2` in s^-2 from a frequency in Hz.
pub fn eigenvalue_of_hz(f: f64) -> f64 {
    let w = 2.0 * PI * f;
    w * w
}

/// `f = sqrt(max(lambda, 0)) / (2 pi)` in Hz from an eigenvalue in s^-2.
pub fn hz_of_eigenvalue(lambda: f64) -> f64 {
    lambda.max(0.0).sqrt() / (2.0 * PI)
}
