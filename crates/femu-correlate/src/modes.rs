//! The two mode sets correlation works on: the model's (eigenvalues in s^-2, full shapes) and the
//! test's (frequencies in Hz, shapes at the sensors).

use crate::CorrelateError;
use crate::estimators::SpectrumProof;
use faer::{Mat, MatRef, c64};
use femu_sparse::SparseMatrix;
use femu_sparse::eigen::Modes;

/// Gives each column of `shapes` a sign fixed by the shape itself: the one that makes
/// `sum_i w_i x_i` positive, with weights `w_i = 1 + frac(0.618.. i)` that no symmetry of a
/// structure or of a sensor grid can make vanish (a plain sum vanishes for antisymmetric shapes).
/// An eigenvector's sign is arbitrary, decided by round-off; anything computed from shapes
/// with noise added (a simulated test) must not depend on it.
pub fn canonical_signs(shapes: &mut Mat<f64>) {
    for j in 0..shapes.ncols() {
        let s: f64 = shapes
            .col(j)
            .iter()
            .enumerate()
            .map(|(i, v)| (1.0 + (0.618_033_988_749_894_9 * i as f64).fract()) * v)
            .sum();
        if s < 0.0 {
            shapes.col_mut(j).iter_mut().for_each(|v| *v = -*v);
        }
    }
}

pub use crate::hz::{eigenvalue_of_hz, hz_of_eigenvalue};

fn check_finite(what: &'static str, values: &[f64]) -> Result<(), CorrelateError> {
    match values.iter().position(|v| !v.is_finite()) {
        Some(index) => Err(CorrelateError::NonFinite { what, index }),
        None => Ok(()),
    }
}

fn check_shapes(what: &'static str, shapes: MatRef<'_, f64>) -> Result<(), CorrelateError> {
    for j in 0..shapes.ncols() {
        let col = shapes.col(j);
        if let Some(i) = col.iter().position(|v| !v.is_finite()) {
            return Err(CorrelateError::NonFinite {
                what,
                index: j * shapes.nrows() + i,
            });
        }
        if col.iter().all(|v| *v == 0.0) {
            return Err(CorrelateError::ZeroVector { what, index: j });
        }
    }
    Ok(())
}

/// Model modes: eigenvalues `lambda_j = omega_j^2` (s^-2) and shapes on the free DOFs.
#[derive(Debug, Clone)]
pub struct ModeSet {
    /// Eigenvalues in s^-2, ascending.
    pub values: Vec<f64>,
    /// Shapes in the columns (`n x m`).
    pub shapes: Mat<f64>,
    /// Whether `phi_i^T M phi_j = delta_ij` holds (recorded, not assumed).
    pub mass_normalised: bool,
    /// What proves that no eigenvalue among `values` was skipped (the eigensolver's Sturm
    /// check; [`SpectrumProof::Unverified`] for modes given by hand).
    pub proof: SpectrumProof,
    /// The model's damped (complex) modes in the coordinates of these (modes x modes, column `r`
    /// the damped mode paired as mode `r`; [`crate::damped::DampedModes::coordinates`]), when the
    /// correlation compares complex shapes with them ([`ModeSet::with_damped`]).
    pub damped: Option<Mat<c64>>,
}

impl ModeSet {
    /// A mode set from values and shapes.
    ///
    /// # Errors
    /// Mismatched counts, non-finite values, zero shapes, or values not ascending.
    pub fn new(
        values: Vec<f64>,
        shapes: Mat<f64>,
        mass_normalised: bool,
    ) -> Result<Self, CorrelateError> {
        if values.len() != shapes.ncols() {
            return Err(CorrelateError::DimensionMismatch {
                what: "model eigenvalues against mode shapes",
                expected: shapes.ncols(),
                got: values.len(),
            });
        }
        check_finite("model eigenvalue", &values)?;
        check_shapes("model mode shape", shapes.as_ref())?;
        if let Some(i) = values.windows(2).position(|w| w[1] < w[0]) {
            return Err(CorrelateError::Invalid {
                what: "model eigenvalues",
                reason: format!("not ascending at mode {}", i + 1),
            });
        }
        Ok(Self {
            values,
            shapes,
            mass_normalised,
            proof: SpectrumProof::Unverified,
            damped: None,
        })
    }

    /// The modes of the sparse eigensolver (M-normalised by construction).
    pub fn from_modes(modes: &Modes) -> Self {
        Self {
            values: modes.values.clone(),
            shapes: modes.vectors.clone(),
            mass_normalised: true,
            proof: SpectrumProof::of(modes),
            damped: None,
        }
    }

    /// These modes with the coordinates of the model's damped modes in them (`coordinates`, modes
    /// x modes), which the correlation's complex MAC then compares with.
    ///
    /// # Errors
    /// Coordinates of another size than the modes.
    pub fn with_damped(mut self, coordinates: Mat<c64>) -> Result<Self, CorrelateError> {
        let n = self.values.len();
        if coordinates.nrows() != n || coordinates.ncols() != n {
            return Err(CorrelateError::DimensionMismatch {
                what: "damped modes' coordinates (modes x modes)",
                expected: n,
                got: coordinates.nrows(),
            });
        }
        self.damped = Some(coordinates);
        Ok(self)
    }

    /// Scales every shape to `phi^T M phi = 1` and records it.
    ///
    /// # Errors
    /// A dimension mismatch with `M`.
    pub fn mass_normalise(&mut self, m: &SparseMatrix) -> Result<(), CorrelateError> {
        crate::correlation::mass_normalise(m, self.shapes.as_mut())?;
        self.mass_normalised = true;
        Ok(())
    }

    /// Number of modes.
    pub fn len(&self) -> usize {
        self.values.len()
    }

    /// Whether the set is empty.
    pub fn is_empty(&self) -> bool {
        self.values.is_empty()
    }

    /// Number of DOFs of the shapes.
    pub fn dim(&self) -> usize {
        self.shapes.nrows()
    }

    /// Frequencies in Hz.
    pub fn frequencies_hz(&self) -> Vec<f64> {
        self.values.iter().map(|l| hz_of_eigenvalue(*l)).collect()
    }
}

/// Identified test modes: frequencies (Hz), optional damping ratios, shapes at the sensors (one
/// row per sensor of a [`SensorLayout`](crate::SensorLayout), one column per mode). A test of
/// frequencies alone has no sensor: zero rows ([`TestModes::frequencies_only`]).
#[derive(Debug, Clone)]
pub struct TestModes {
    /// Identified natural frequencies in Hz.
    pub frequencies_hz: Vec<f64>,
    /// Modal damping ratios (fraction of critical), when identified.
    pub damping_ratios: Option<Vec<f64>>,
    /// Shapes at the sensors (`s x m`), real: for complex identified modes, each turned by the
    /// phase of its largest component and its real part taken (docs/MATH.md, "Complex modes").
    pub shapes: Mat<f64>,
    /// For complex identified modes, the imaginary parts of the same turned shapes (`s x m`):
    /// the mode is `shapes + i imaginary` (a real mode's column is zero). `None` for real data.
    pub imaginary: Option<Mat<f64>>,
}

impl TestModes {
    /// Test modes from frequencies and shapes.
    ///
    /// # Errors
    /// Mismatched counts, a frequency that is not finite and positive, a damping ratio outside
    /// `[0, 1)`, non-finite or zero shapes.
    pub fn new(
        frequencies_hz: Vec<f64>,
        damping_ratios: Option<Vec<f64>>,
        shapes: Mat<f64>,
    ) -> Result<Self, CorrelateError> {
        if frequencies_hz.len() != shapes.ncols() {
            return Err(CorrelateError::DimensionMismatch {
                what: "test frequencies against test shapes",
                expected: shapes.ncols(),
                got: frequencies_hz.len(),
            });
        }
        check_finite("test frequency", &frequencies_hz)?;
        if let Some(i) = frequencies_hz.iter().position(|f| *f <= 0.0) {
            return Err(CorrelateError::Invalid {
                what: "test frequency",
                reason: format!(
                    "mode {} has f = {} Hz; must be positive",
                    i + 1,
                    frequencies_hz[i]
                ),
            });
        }
        if let Some(z) = &damping_ratios {
            if z.len() != frequencies_hz.len() {
                return Err(CorrelateError::DimensionMismatch {
                    what: "damping ratios against test frequencies",
                    expected: frequencies_hz.len(),
                    got: z.len(),
                });
            }
            check_finite("damping ratio", z)?;
            if let Some(i) = z.iter().position(|v| !(0.0..1.0).contains(v)) {
                return Err(CorrelateError::Invalid {
                    what: "damping ratio",
                    reason: format!("mode {} has zeta = {}; must be in [0, 1)", i + 1, z[i]),
                });
            }
        }
        if shapes.nrows() > 0 {
            check_shapes("test mode shape", shapes.as_ref())?;
        }
        Ok(Self {
            frequencies_hz,
            damping_ratios,
            shapes,
            imaginary: None,
        })
    }

    /// These modes with the imaginary parts of complex identified shapes
    /// ([`TestModes::imaginary`]): correlation then reports the complex MAC of each pair beside
    /// the MAC of the real shapes.
    ///
    /// # Errors
    /// A matrix of another size than the shapes, a value that is not finite.
    pub fn with_imaginary(mut self, imaginary: Mat<f64>) -> Result<Self, CorrelateError> {
        if imaginary.nrows() != self.shapes.nrows() || imaginary.ncols() != self.shapes.ncols() {
            return Err(CorrelateError::DimensionMismatch {
                what: "imaginary parts against the test shapes (values)",
                expected: self.shapes.nrows() * self.shapes.ncols(),
                got: imaginary.nrows() * imaginary.ncols(),
            });
        }
        for j in 0..imaginary.ncols() {
            for i in 0..imaginary.nrows() {
                if !imaginary[(i, j)].is_finite() {
                    return Err(CorrelateError::Invalid {
                        what: "test mode shape",
                        reason: format!(
                            "mode {}'s imaginary part at sensor {} is {}",
                            j + 1,
                            i + 1,
                            imaginary[(i, j)]
                        ),
                    });
                }
            }
        }
        self.imaginary = Some(imaginary);
        Ok(self)
    }

    /// Test modes of frequencies alone (no shapes: zero sensors).
    ///
    /// # Errors
    /// As [`TestModes::new`].
    pub fn frequencies_only(
        frequencies_hz: Vec<f64>,
        damping_ratios: Option<Vec<f64>>,
    ) -> Result<Self, CorrelateError> {
        let m = frequencies_hz.len();
        Self::new(frequencies_hz, damping_ratios, Mat::zeros(0, m))
    }

    /// Whether the test gives mode shapes (at least one sensor).
    pub fn has_shapes(&self) -> bool {
        self.shapes.nrows() > 0
    }

    /// Number of modes.
    pub fn len(&self) -> usize {
        self.frequencies_hz.len()
    }

    /// Whether there are no modes.
    pub fn is_empty(&self) -> bool {
        self.frequencies_hz.is_empty()
    }

    /// Identified eigenvalues `lambda_id = (2 pi f)^2` in s^-2.
    pub fn eigenvalues(&self) -> Vec<f64> {
        self.frequencies_hz
            .iter()
            .map(|f| eigenvalue_of_hz(*f))
            .collect()
    }
}
