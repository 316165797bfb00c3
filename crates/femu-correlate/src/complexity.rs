//! How complex an identified mode is (`docs/MATH.md`, "Complex modes"): a mode shape `psi = x + i y`
//! of a proportionally damped structure is real up to one phase; non-proportional damping,
//! noise or a poor identification spread its components' phases.
//!
//! - **MPC**, the modal phase collinearity (Pappa, Elliott and Schenk): with the 2 x 2 matrix
//!   `S = [x^T x, x^T y; x^T y, y^T y]` and its eigenvalues `l1 >= l2`,
//!   `MPC = ((l1 - l2) / (l1 + l2))^2`: 1 for components on one line through the origin in the
//!   complex plane (a real mode, whatever its phase), 0 for a circular spread.
//! - **MPD**, the mean phase deviation (Reynier): the angle of each component from the principal
//!   line of `S` (in `[0, 90]` degrees), averaged with the components' magnitudes as weights.
//!
//! femu makes a complex mode real by turning it by the phase of its largest component and taking
//! the real part; the indicators say how much that loses.

use serde::{Deserialize, Serialize};

/// The complexity of one mode.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Complexity {
    /// Modal phase collinearity, in `[0, 1]` (1: real up to one phase).
    pub mpc: f64,
    /// Mean phase deviation from the principal line, degrees, in `[0, 90]`.
    pub mpd_degrees: f64,
}

/// An MPC below this (0.9) makes the real part of a mode a poor stand-in for it: femu warns.
pub const MPC_WARNING: f64 = 0.9;

impl Complexity {
    /// The indicators of the complex components `(re, im)` of one mode (zero components ignored);
    /// `None` when every component is zero.
    pub fn of(components: &[(f64, f64)]) -> Option<Self> {
        let (mut sxx, mut syy, mut sxy, mut weight) = (0.0, 0.0, 0.0, 0.0);
        for (x, y) in components {
            sxx += x * x;
            syy += y * y;
            sxy += x * y;
            weight += x.hypot(*y);
        }
        if !(weight > 0.0) {
            return None;
        }
        // eigenvalues of the symmetric 2 x 2 matrix, and the principal direction
        let (mean, half) = (
            0.5 * (sxx + syy),
            (0.25 * (sxx - syy).powi(2) + sxy * sxy).sqrt(),
        );
        let (l1, l2) = (mean + half, (mean - half).max(0.0));
        let mpc = ((l1 - l2) / (l1 + l2)).powi(2);
        let phi = 0.5 * (2.0 * sxy).atan2(sxx - syy);
        let (c, s) = (phi.cos(), phi.sin());
        let deviation: f64 = components
            .iter()
            .map(|(x, y)| {
                let m = x.hypot(*y);
                if m > 0.0 {
                    m * ((x * c + y * s).abs() / m).min(1.0).acos()
                } else {
                    0.0
                }
            })
            .sum();
        Some(Self {
            mpc,
            mpd_degrees: (deviation / weight).to_degrees(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// By hand: a real mode, and the same mode turned by any phase, is collinear (MPC 1, MPD 0);
    /// `[1, i]` spreads evenly (MPC 0, MPD 45 degrees); `[1, e^(i b)]` has
    /// `S = [1 + cos^2 b, cos b sin b; cos b sin b, sin^2 b]` with eigenvalues `1 +- |cos b|`,
    /// so `MPC = cos^2 b`, and its principal line bisects the two: `MPD = b / 2`.
    #[test]
    fn indicators_by_hand() {
        let real = [(1.0, 0.0), (-0.5, 0.0), (0.25, 0.0)];
        let c = Complexity::of(&real).unwrap();
        assert!(
            (c.mpc - 1.0).abs() < 1e-15 && c.mpd_degrees.abs() < 1e-6,
            "{c:?}"
        );
        let a = 0.7_f64;
        let turned: Vec<(f64, f64)> = real
            .iter()
            .map(|(x, _)| (x * a.cos(), x * a.sin()))
            .collect();
        let c = Complexity::of(&turned).unwrap();
        assert!(
            (c.mpc - 1.0).abs() < 1e-12 && c.mpd_degrees.abs() < 1e-5,
            "{c:?}"
        );
        let c = Complexity::of(&[(1.0, 0.0), (0.0, 1.0)]).unwrap();
        assert!(
            c.mpc.abs() < 1e-15 && (c.mpd_degrees - 45.0).abs() < 1e-9,
            "{c:?}"
        );
        for b in [10.0_f64, 30.0, 60.0] {
            let r = b.to_radians();
            let c = Complexity::of(&[(1.0, 0.0), (r.cos(), r.sin())]).unwrap();
            assert!((c.mpc - r.cos().powi(2)).abs() < 1e-12, "{b}: {c:?}");
            assert!((c.mpd_degrees - b / 2.0).abs() < 1e-9, "{b}: {c:?}");
        }
        assert_eq!(Complexity::of(&[(0.0, 0.0)]), None);
    }
}
