//! Universal File Format (what test systems export), read and written: datasets 15 and 2411
//! (nodes), 2412 (elements), 164 (units), 55 (modal data: real normal modes and complex modes),
//! 58 and its binary variant 58b (functions at nodal DOFs: FRFs, time histories, spectra), 82
//! (trace lines) and 2477 (permanent groups: the sets of [`Universal::to_mesh`]). Other datasets are skipped with a warning naming their number and line. Fortran
//! `D` exponents and CRLF line ends are read; a file written by femu reads back to the same bytes.
//!
//! Dataset 58b: records 1-11 as text, then the values as raw IEEE numbers in the byte order of
//! the header (little or big endian), 4 bytes each for single-precision data (ordinate types 2,
//! 5) and 8 for double (4, 6), an uneven abscissa in the same precision as the ordinate (as
//! pyuff and the files it reads do). The byte count is computed from record 7 (points, type,
//! spacing); a header that says otherwise gets a warning.

use crate::{IoError, Warning};
use faer::Mat;
use femu_correlate::{Sensor, TestModes};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// Units of dataset 164.
#[derive(Debug, Clone, PartialEq)]
pub struct UffUnits {
    /// Unit system code (1 = SI: m, N, s).
    pub code: i64,
    /// Description.
    pub description: String,
    /// Length, force, temperature factors to SI.
    pub factors: [f64; 3],
}

/// One node of dataset 15.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct UffNode {
    /// Node label.
    pub id: u64,
    /// Coordinates.
    pub x: [f64; 3],
}

/// Dataset 151 (header): what the file says it is and which program wrote it.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct UffHeader {
    /// Record 1: the model file's name.
    pub model: String,
    /// Record 2: its description.
    pub description: String,
    /// Record 6 (record 3 when 6 is blank): the program that wrote the file.
    pub program: String,
}

/// One mode of dataset 55 (test modes) or 2414 (modes another FE code computed).
#[derive(Debug, Clone, PartialEq)]
pub struct UffMode {
    /// Mode number (record 7).
    pub number: i64,
    /// Frequency, Hz.
    pub frequency_hz: f64,
    /// Viscous damping ratio.
    pub damping: f64,
    /// Modal mass (0 when not given).
    pub modal_mass: f64,
    /// Per node: the translations (x, y, z); for complex data the real-normalised values (each
    /// mode rotated by the phase of its largest component, then the real part).
    pub values: Vec<(u64, [f64; 3])>,
    /// Whether the file stored complex values.
    pub complex: bool,
    /// How complex the stored mode is (MPC, MPD over its translations), for complex data.
    pub complexity: Option<femu_correlate::Complexity>,
    /// For complex data, the imaginary parts of the turned translations, node by node in the
    /// order of `values` (the mode is `values + i imaginary`); `None` for real data.
    pub imaginary: Option<Vec<[f64; 3]>>,
}

/// The supported content of a universal file.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Universal {
    /// Dataset 164, if present.
    pub units: Option<UffUnits>,
    /// Nodes of dataset 15 (single precision) or 2411 (double precision).
    pub nodes: Vec<UffNode>,
    /// Whether the nodes came from (and are written as) dataset 2411 instead of 15.
    pub nodes_2411: bool,
    /// Dataset 2412 elements.
    pub elements: Vec<UffElement>,
    /// The header of dataset 151, when the file has one.
    pub header: Option<UffHeader>,
    /// Modes: test modes of dataset 55, then analysis results of dataset 2414.
    pub modes: Vec<UffMode>,
    /// How many of `modes` came from dataset 2414 (analysis results) rather than 55.
    pub modes_from_2414: usize,
    /// Dataset 58/58b functions (FRFs, time histories, ...).
    pub functions: Vec<UffFunction>,
    /// Dataset 82 trace lines.
    pub trace_lines: Vec<UffTraceLine>,
    /// Dataset 2477 (and 2467) permanent groups.
    pub groups: Vec<UffGroup>,
    /// Dataset 18 coordinate systems, by number (node coordinates in a non-global definition
    /// system are transformed to global ones when read).
    pub coordinate_systems: std::collections::BTreeMap<i64, CoordinateSystem>,
    /// The displacement coordinate system of each node that names one other than the global
    /// (datasets 15 and 2411; 0, and 1 when no system 1 is defined, are the global system): test
    /// modes measured there are turned to global directions by [`Universal::test_data`].
    pub displacement_systems: std::collections::BTreeMap<u64, i64>,
    /// Skipped datasets and approximations.
    pub warnings: Vec<Warning>,
}

/// A coordinate system of dataset 18 or 2420: a frame (`origin`, `axes`) and a kind.
///
/// A point's local cartesian coordinates `c` give `x_global = origin + axes c`; a cylindrical
/// system's coordinates are `(r, theta, z)` with `c = (r cos theta, r sin theta, z)`, a spherical
/// system's `(r, theta, phi)` with `theta` from the local z axis and `phi` about it from the local
/// x axis, `c = r (sin theta cos phi, sin theta sin phi, cos theta)` (angles in degrees, as
/// I-DEAS and Nastran write them). Displacements in a cylindrical or spherical system are along its
/// unit vectors at the node (`e_r, e_theta, e_z` or `e_r, e_theta, e_phi`).
#[derive(Debug, Clone, PartialEq)]
pub struct CoordinateSystem {
    /// Its name (record 2).
    pub name: String,
    /// 0 cartesian, 1 cylindrical, 2 spherical.
    pub kind: i64,
    /// Origin in global coordinates.
    pub origin: [f64; 3],
    /// `axes[i][j]`: global component `i` of local axis `j`.
    pub axes: [[f64; 3]; 3],
}

impl CoordinateSystem {
    /// Whether the system is the global one (cartesian, axes equal to the identity to 1e-12).
    pub fn is_global_orientation(&self) -> bool {
        self.kind == 0
            && (0..3).all(|i| {
                (0..3).all(|j| (self.axes[i][j] - f64::from(u8::from(i == j))).abs() < 1e-12)
            })
    }

    /// `axes v` (a local cartesian vector in global components).
    pub fn to_global(&self, v: [f64; 3]) -> [f64; 3] {
        std::array::from_fn(|i| (0..3).map(|j| self.axes[i][j] * v[j]).sum())
    }

    /// The global position of the point with coordinates `c` in this system (by its kind).
    pub fn point_to_global(&self, c: [f64; 3]) -> [f64; 3] {
        let local = match self.kind {
            1 => {
                let t = c[1].to_radians();
                [c[0] * t.cos(), c[0] * t.sin(), c[2]]
            }
            2 => {
                let (t, p) = (c[1].to_radians(), c[2].to_radians());
                [
                    c[0] * t.sin() * p.cos(),
                    c[0] * t.sin() * p.sin(),
                    c[0] * t.cos(),
                ]
            }
            _ => c,
        };
        let g = self.to_global(local);
        std::array::from_fn(|i| self.origin[i] + g[i])
    }

    /// The displacement axes at global point `x` in global components (`axes[i][j]`: component
    /// `i` of local direction `j`): the frame's axes for a cartesian system, the unit vectors of
    /// the cylindrical or spherical coordinates at `x` otherwise. On the axis of a cylindrical
    /// system (or the polar axis of a spherical one) the angle is taken as 0.
    pub fn axes_at(&self, x: [f64; 3]) -> [[f64; 3]; 3] {
        if self.kind != 1 && self.kind != 2 {
            return self.axes;
        }
        let d: [f64; 3] = std::array::from_fn(|i| x[i] - self.origin[i]);
        // local cartesian coordinates: axes^T d
        let c: [f64; 3] = std::array::from_fn(|j| (0..3).map(|i| self.axes[i][j] * d[i]).sum());
        let local: [[f64; 3]; 3] = if self.kind == 1 {
            let t = c[1].atan2(c[0]);
            let (s, co) = t.sin_cos();
            [[co, s, 0.0], [-s, co, 0.0], [0.0, 0.0, 1.0]]
        } else {
            let rho = c[0].hypot(c[1]);
            let theta = rho.atan2(c[2]);
            let phi = c[1].atan2(c[0]);
            let (st, ct) = theta.sin_cos();
            let (sp, cp) = phi.sin_cos();
            [
                [st * cp, st * sp, ct],
                [ct * cp, ct * sp, -st],
                [-sp, cp, 0.0],
            ]
        };
        // column j of the result: axes * local[j]
        let cols: [[f64; 3]; 3] = std::array::from_fn(|j| self.to_global(local[j]));
        std::array::from_fn(|i| std::array::from_fn(|j| cols[j][i]))
    }
}

/// One element of dataset 2412.
#[derive(Debug, Clone, PartialEq)]
pub struct UffElement {
    /// Element label.
    pub id: u64,
    /// FE descriptor id (111 linear tetrahedron, 112 linear wedge, 115 linear brick, ...).
    pub descriptor: i64,
    /// Node labels in the file's order.
    pub nodes: Vec<u64>,
}

/// An axis of dataset 58 (records 8-11: abscissa, ordinate numerator, ordinate denominator,
/// z axis).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct UffAxis {
    /// Specific data type (0 unknown, 1 general, 8 displacement, 12 acceleration, 13 excitation
    /// force, 17 time, 18 frequency, ...).
    pub data_type: i64,
    /// Length, force and temperature unit exponents.
    pub exponents: [i64; 3],
    /// Axis label (20 characters at most when written).
    pub label: String,
    /// Units label (20 characters at most when written).
    pub units: String,
}

/// The abscissa of a dataset 58 function.
#[derive(Debug, Clone, PartialEq)]
pub enum Abscissa {
    /// `min + k step` (record 7; written with 6 significant digits, as the format has them).
    Even {
        /// First abscissa.
        min: f64,
        /// Increment.
        step: f64,
    },
    /// One abscissa per point, stored with the values.
    Uneven(Vec<f64>),
}

/// The ordinate values of a dataset 58 function.
#[derive(Debug, Clone, PartialEq)]
pub enum Ordinate {
    /// Real values.
    Real(Vec<f64>),
    /// Complex values as (real, imaginary).
    Complex(Vec<(f64, f64)>),
}

impl Ordinate {
    /// Number of points.
    pub fn len(&self) -> usize {
        match self {
            Ordinate::Real(v) => v.len(),
            Ordinate::Complex(v) => v.len(),
        }
    }

    /// Whether there is no point.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// A response or reference DOF of dataset 58 (record 6).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct UffDof {
    /// Entity name (10 characters at most when written).
    pub entity: String,
    /// Node label (0 when none).
    pub node: u64,
    /// Direction: 1-3 translations X-Z, 4-6 rotations, negative for the opposite sense, 0 scalar.
    pub direction: i64,
}

/// One function of dataset 58 (ASCII) or 58b (binary).
#[derive(Debug, Clone, PartialEq)]
pub struct UffFunction {
    /// Records 1-5: identification lines (record 3 is usually the date).
    pub ids: [String; 5],
    /// Function type (0 general, 1 time response, 2 auto spectrum, 3 cross spectrum, 4 frequency
    /// response function, 6 coherence, 9 power spectral density, ...).
    pub function_type: i64,
    /// Function identification number, version number, load case.
    pub numbers: [i64; 3],
    /// Response DOF.
    pub response: UffDof,
    /// Reference DOF.
    pub reference: UffDof,
    /// Whether the values are double precision (ordinate data types 4 and 6) or single (2, 5).
    pub double: bool,
    /// Abscissa.
    pub abscissa: Abscissa,
    /// Z-axis value (record 7).
    pub z_value: f64,
    /// Records 8-11.
    pub axes: [UffAxis; 4],
    /// Values.
    pub ordinate: Ordinate,
    /// Read from, and written as, binary 58b.
    pub binary: bool,
}

impl UffFunction {
    /// The abscissa of each point.
    pub fn abscissa_values(&self) -> Vec<f64> {
        match &self.abscissa {
            Abscissa::Even { min, step } => (0..self.ordinate.len())
                .map(|k| min + k as f64 * step)
                .collect(),
            Abscissa::Uneven(x) => x.clone(),
        }
    }

    /// Ordinate data type of record 7: 2 real single, 4 real double, 5 complex single, 6 complex
    /// double.
    fn data_type(&self) -> i64 {
        match (&self.ordinate, self.double) {
            (Ordinate::Real(_), false) => 2,
            (Ordinate::Real(_), true) => 4,
            (Ordinate::Complex(_), false) => 5,
            (Ordinate::Complex(_), true) => 6,
        }
    }

    /// Values stored per point (abscissa included when uneven).
    fn per_point(&self) -> usize {
        let even = matches!(self.abscissa, Abscissa::Even { .. });
        match (&self.ordinate, even) {
            (Ordinate::Real(_), true) => 1,
            (Ordinate::Real(_), false) | (Ordinate::Complex(_), true) => 2,
            (Ordinate::Complex(_), false) => 3,
        }
    }

    /// The stored values in file order.
    fn stored(&self) -> Vec<f64> {
        let x = match &self.abscissa {
            Abscissa::Uneven(x) => Some(x),
            Abscissa::Even { .. } => None,
        };
        let mut v = Vec::with_capacity(self.ordinate.len() * self.per_point());
        for k in 0..self.ordinate.len() {
            if let Some(x) = x {
                v.push(x.get(k).copied().unwrap_or(0.0));
            }
            match &self.ordinate {
                Ordinate::Real(y) => v.push(y[k]),
                Ordinate::Complex(y) => v.extend([y[k].0, y[k].1]),
            }
        }
        v
    }
}

/// One permanent group of dataset 2477: named lists of nodes and elements (what FE
/// pre-processors and Gmsh's physical groups write), the sets of [`Universal::to_mesh`].
#[derive(Debug, Clone, PartialEq)]
pub struct UffGroup {
    /// Group number.
    pub number: i64,
    /// Group name (40 characters at most when written).
    pub name: String,
    /// Node labels (entity type 7).
    pub nodes: Vec<u64>,
    /// Element labels (entity type 8).
    pub elements: Vec<u64>,
}

/// One trace line of dataset 82: a polyline through nodes, `0` lifting the pen.
#[derive(Debug, Clone, PartialEq)]
pub struct UffTraceLine {
    /// Trace line number.
    pub number: i64,
    /// Colour number.
    pub color: i64,
    /// Identification line.
    pub id: String,
    /// Node labels, `0` for "move to the next node without drawing".
    pub nodes: Vec<u64>,
}

/// I-DEAS parabolic solids list each face's nodes corner, mid-edge, corner, ... : femu
/// (Abaqus) order `femu[k] = unv[PERM[k]]`. Tetrahedron 118: corners 0 2 4 9, mid-edges 1 (0-2),
/// 3 (2-4), 5 (4-0), 6 (0-9), 7 (2-9), 8 (4-9).
mod functions;
mod geometry;
mod modal;
mod model;
mod read;
mod write;

use functions::*;
use geometry::*;
use modal::*;
use read::*;
use write::*;

pub use read::{parse_uff, parse_uff_bytes, read_uff};
pub use write::{uff_bytes, uff_string, write_uff};
