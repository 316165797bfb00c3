//! The isoparametric solid elements and their reference data.
//!
//! Node ordering is Abaqus/CalculiX's (files with other conventions are converted at input):
//!
//! | kind | nodes | ordering |
//! |---|---|---|
//! | [`Tet4`](ElementKind::Tet4) (C3D4) | 4 | 1-2-3 base, counter-clockwise seen from 4 |
//! | [`Tet10`](ElementKind::Tet10) (C3D10) | 10 | corners, then mid-edges 1-2, 2-3, 3-1, 1-4, 2-4, 3-4 |
//! | [`Hex8`](ElementKind::Hex8) (C3D8) | 8 | bottom face 1-2-3-4 (`zeta = -1`), then top 5-6-7-8 |
//! | [`Hex20`](ElementKind::Hex20) (C3D20) | 20 | corners, mid-edges 1-2, 2-3, 3-4, 4-1, 5-6, 6-7, 7-8, 8-5, 1-5, 2-6, 3-7, 4-8 |
//! | [`Penta6`](ElementKind::Penta6) (C3D6) | 6 | bottom triangle 1-2-3, top 4-5-6 |
//! | [`Penta15`](ElementKind::Penta15) (C3D15) | 15 | corners, mid-edges 1-2, 2-3, 3-1, 4-5, 5-6, 6-4, 1-4, 2-5, 3-6 |
//! | [`Pyramid5`](ElementKind::Pyramid5) | 5 | base 1-2-3-4 (counter-clockwise seen from the apex), apex 5 |
//! | [`Pyramid13`](ElementKind::Pyramid13) | 13 | corners, mid-edges 1-2, 2-3, 3-4, 4-1, 1-5, 2-5, 3-5, 4-5 (Nastran's CPYRAM, VTK's) |
//!
//! Integration (the rules are exact for the undistorted element wherever noted):
//!
//! | kind | stiffness | consistent mass |
//! |---|---|---|
//! | tet4 | 1 point (exact) | 4 points, degree 2 (exact) |
//! | tet10 | 4 points, degree 2 (exact; as C3D10) | conical product, degree 4 (exact) |
//! | hex8 | 2x2x2 Gauss (as C3D8) | 2x2x2 (exact; as C3D8) |
//! | hex20 | 3x3x3 Gauss (as C3D20) | 3x3x3 (exact; as C3D20) |
//! | penta6 | 3-point triangle x 2 Gauss, degree 2 (exact) | same (exact) |
//! | penta15 | 6-point triangle x 3 Gauss, degree 4 (exact) | same (exact) |
//! | pyramid5 | collapsed cube 2x2x2 (exact) | collapsed cube 2x2x4 (exact) |
//! | pyramid13 | collapsed cube 3x3x5 (exact) | same (exact) |
//!
//! The pyramids are Bedrosian's: the reference pyramid has the base `[-1, 1]^2` at `zeta = 0` and
//! the apex at `zeta = 1`, and the shape functions are rational (`xi eta / (1 - zeta)`) so that
//! they match the neighbouring hexahedra and tetrahedra on every face. On the cube
//! `(a, b, c) in [-1, 1]^2 x [0, 1]` with `xi = a (1 - c)`, `eta = b (1 - c)`, `zeta = c`
//! (Jacobian `(1 - c)^2`) they and their gradients are polynomials, so tensor Gauss rules on the
//! cube integrate the undistorted element's stiffness and mass exactly (docs/MATH.md).
//!
//! CalculiX 2.20 under-integrates the mass of C3D4, C3D10, C3D6 and C3D15 into singular matrices;
//! femu integrates every consistent mass exactly, so every element mass matrix is positive definite.

use crate::quadrature::{self, QuadratureRule};
use serde::{Deserialize, Serialize};
use std::sync::OnceLock;

/// The solid element types.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
pub enum ElementKind {
    /// 4-node linear tetrahedron (C3D4).
    Tet4,
    /// 10-node quadratic tetrahedron (C3D10).
    Tet10,
    /// 8-node trilinear hexahedron (C3D8).
    Hex8,
    /// 20-node serendipity hexahedron (C3D20).
    Hex20,
    /// 6-node linear wedge / pentahedron (C3D6).
    Penta6,
    /// 15-node quadratic wedge (C3D15).
    Penta15,
    /// 5-node linear pyramid (Nastran CPYRAM, Gmsh 7; no CalculiX equivalent).
    Pyramid5,
    /// 13-node quadratic pyramid (Nastran CPYRAM, Gmsh 19; no CalculiX equivalent).
    Pyramid13,
}

/// How an element's stiffness is formed. Every kind has the full formulation; the 8-node brick
/// also has incompatible modes ([`crate::kernel::hex8_incompatible_stiffness`]). The mass is the
/// same in both.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Default, Hash, serde::Serialize, serde::Deserialize,
)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[serde(rename_all = "snake_case")]
pub enum Formulation {
    /// The element's own integration rule over its shape functions (CalculiX C3D8, Nastran
    /// `IN = 2`, `ISOP = FULL`).
    #[default]
    Full,
    /// The 8-node brick with three bubbles per component condensed out (CalculiX and Abaqus
    /// C3D8I; the bubble functions of Nastran's default 8-node CHEXA).
    IncompatibleModes,
}

/// Every element kind, for loops in tests and tools.
pub const ALL_KINDS: [ElementKind; 8] = [
    ElementKind::Tet4,
    ElementKind::Tet10,
    ElementKind::Hex8,
    ElementKind::Hex20,
    ElementKind::Penta6,
    ElementKind::Penta15,
    ElementKind::Pyramid5,
    ElementKind::Pyramid13,
];

const PYRAMID_CORNERS: [[f64; 3]; 5] = [
    [-1.0, -1.0, 0.0],
    [1.0, -1.0, 0.0],
    [1.0, 1.0, 0.0],
    [-1.0, 1.0, 0.0],
    [0.0, 0.0, 1.0],
];
const PYRAMID_EDGES: [[usize; 2]; 8] = [
    [0, 1],
    [1, 2],
    [2, 3],
    [3, 0],
    [0, 4],
    [1, 4],
    [2, 4],
    [3, 4],
];
const PYRAMID_FACES: [&[usize]; 5] = [
    &[0, 1, 2, 3],
    &[0, 4, 1],
    &[1, 4, 2],
    &[2, 4, 3],
    &[3, 4, 0],
];

/// `1 / (1 - zeta)`, zero at the apex: every term it multiplies vanishes on the pyramid's axis at
/// least as fast, so the shape functions take their limits there.
fn apex_inverse(zeta: f64) -> f64 {
    let s = 1.0 - zeta;
    if s > 1e-14 { 1.0 / s } else { 0.0 }
}

const HEX_CORNERS: [[f64; 3]; 8] = [
    [-1.0, -1.0, -1.0],
    [1.0, -1.0, -1.0],
    [1.0, 1.0, -1.0],
    [-1.0, 1.0, -1.0],
    [-1.0, -1.0, 1.0],
    [1.0, -1.0, 1.0],
    [1.0, 1.0, 1.0],
    [-1.0, 1.0, 1.0],
];
/// Hex20 reference nodes: the corners, then the mid-edges in [`HEX_EDGES`] order.
const HEX20_NODES: [[f64; 3]; 20] = [
    [-1.0, -1.0, -1.0],
    [1.0, -1.0, -1.0],
    [1.0, 1.0, -1.0],
    [-1.0, 1.0, -1.0],
    [-1.0, -1.0, 1.0],
    [1.0, -1.0, 1.0],
    [1.0, 1.0, 1.0],
    [-1.0, 1.0, 1.0],
    [0.0, -1.0, -1.0],
    [1.0, 0.0, -1.0],
    [0.0, 1.0, -1.0],
    [-1.0, 0.0, -1.0],
    [0.0, -1.0, 1.0],
    [1.0, 0.0, 1.0],
    [0.0, 1.0, 1.0],
    [-1.0, 0.0, 1.0],
    [-1.0, -1.0, 0.0],
    [1.0, -1.0, 0.0],
    [1.0, 1.0, 0.0],
    [-1.0, 1.0, 0.0],
];
const HEX_EDGES: [[usize; 2]; 12] = [
    [0, 1],
    [1, 2],
    [2, 3],
    [3, 0],
    [4, 5],
    [5, 6],
    [6, 7],
    [7, 4],
    [0, 4],
    [1, 5],
    [2, 6],
    [3, 7],
];
const TET_EDGES: [[usize; 2]; 6] = [[0, 1], [1, 2], [2, 0], [0, 3], [1, 3], [2, 3]];
const WEDGE_EDGES: [[usize; 2]; 9] = [
    [0, 1],
    [1, 2],
    [2, 0],
    [3, 4],
    [4, 5],
    [5, 3],
    [0, 3],
    [1, 4],
    [2, 5],
];

const HEX_FACES: [&[usize]; 6] = [
    &[0, 1, 2, 3],
    &[4, 7, 6, 5],
    &[0, 4, 5, 1],
    &[1, 5, 6, 2],
    &[2, 6, 7, 3],
    &[3, 7, 4, 0],
];
const TET_FACES: [&[usize]; 4] = [&[0, 1, 2], &[0, 3, 1], &[1, 3, 2], &[2, 3, 0]];
const WEDGE_FACES: [&[usize]; 5] = [
    &[0, 1, 2],
    &[3, 5, 4],
    &[0, 3, 4, 1],
    &[1, 4, 5, 2],
    &[2, 5, 3, 0],
];

impl ElementKind {
    /// Number of nodes.
    pub const fn num_nodes(self) -> usize {
        match self {
            Self::Tet4 => 4,
            Self::Tet10 => 10,
            Self::Hex8 => 8,
            Self::Hex20 => 20,
            Self::Penta6 => 6,
            Self::Penta15 => 15,
            Self::Pyramid5 => 5,
            Self::Pyramid13 => 13,
        }
    }

    /// Number of corner (vertex) nodes; they come first in the ordering.
    pub const fn num_corners(self) -> usize {
        match self {
            Self::Tet4 | Self::Tet10 => 4,
            Self::Hex8 | Self::Hex20 => 8,
            Self::Penta6 | Self::Penta15 => 6,
            Self::Pyramid5 | Self::Pyramid13 => 5,
        }
    }

    /// Whether the element has mid-edge nodes.
    pub const fn is_quadratic(self) -> bool {
        matches!(
            self,
            Self::Tet10 | Self::Hex20 | Self::Penta15 | Self::Pyramid13
        )
    }

    /// The linear element with the same corners.
    pub const fn linear(self) -> Self {
        match self {
            Self::Tet4 | Self::Tet10 => Self::Tet4,
            Self::Hex8 | Self::Hex20 => Self::Hex8,
            Self::Penta6 | Self::Penta15 => Self::Penta6,
            Self::Pyramid5 | Self::Pyramid13 => Self::Pyramid5,
        }
    }

    /// The quadratic element with the same corners.
    pub const fn quadratic(self) -> Self {
        match self {
            Self::Tet4 | Self::Tet10 => Self::Tet10,
            Self::Hex8 | Self::Hex20 => Self::Hex20,
            Self::Penta6 | Self::Penta15 => Self::Penta15,
            Self::Pyramid5 | Self::Pyramid13 => Self::Pyramid13,
        }
    }

    /// The Abaqus/CalculiX name of the fully integrated element (the pyramids, which neither has,
    /// get the names of their node counts; the deck writer refuses them).
    pub const fn abaqus_name(self) -> &'static str {
        match self {
            Self::Pyramid5 => "C3D5",
            Self::Pyramid13 => "C3D13",
            Self::Tet4 => "C3D4",
            Self::Tet10 => "C3D10",
            Self::Hex8 => "C3D8",
            Self::Hex20 => "C3D20",
            Self::Penta6 => "C3D6",
            Self::Penta15 => "C3D15",
        }
    }

    /// Edges as pairs of corner indices; for a quadratic element, edge `e` carries the mid-edge node
    /// `num_corners() + e`.
    pub const fn edges(self) -> &'static [[usize; 2]] {
        match self {
            Self::Tet4 | Self::Tet10 => &TET_EDGES,
            Self::Hex8 | Self::Hex20 => &HEX_EDGES,
            Self::Penta6 | Self::Penta15 => &WEDGE_EDGES,
            Self::Pyramid5 | Self::Pyramid13 => &PYRAMID_EDGES,
        }
    }

    /// Faces as cycles of corner indices (Abaqus face order S1, S2, ...).
    pub const fn faces(self) -> &'static [&'static [usize]] {
        match self {
            Self::Tet4 | Self::Tet10 => &TET_FACES,
            Self::Hex8 | Self::Hex20 => &HEX_FACES,
            Self::Penta6 | Self::Penta15 => &WEDGE_FACES,
            Self::Pyramid5 | Self::Pyramid13 => &PYRAMID_FACES,
        }
    }

    /// All local node indices of face `f`: its corners, then (quadratic elements) its mid-edge nodes.
    pub fn face_nodes(self, f: usize) -> Vec<usize> {
        let corners = self.faces()[f];
        let mut nodes = corners.to_vec();
        if self.is_quadratic() {
            for i in 0..corners.len() {
                let (a, b) = (corners[i], corners[(i + 1) % corners.len()]);
                let e = self
                    .edges()
                    .iter()
                    .position(|e| (e[0] == a && e[1] == b) || (e[0] == b && e[1] == a))
                    .expect("every face edge is an element edge");
                nodes.push(self.num_corners() + e);
            }
        }
        nodes
    }

    /// Reference coordinates of the nodes.
    pub fn reference_nodes(self) -> Vec<[f64; 3]> {
        let corners: Vec<[f64; 3]> = match self {
            Self::Tet4 | Self::Tet10 => vec![
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [0.0, 1.0, 0.0],
                [0.0, 0.0, 1.0],
            ],
            Self::Hex8 | Self::Hex20 => HEX_CORNERS.to_vec(),
            Self::Penta6 | Self::Penta15 => vec![
                [0.0, 0.0, -1.0],
                [1.0, 0.0, -1.0],
                [0.0, 1.0, -1.0],
                [0.0, 0.0, 1.0],
                [1.0, 0.0, 1.0],
                [0.0, 1.0, 1.0],
            ],
            Self::Pyramid5 | Self::Pyramid13 => PYRAMID_CORNERS.to_vec(),
        };
        let mut nodes = corners.clone();
        if self.is_quadratic() {
            for e in self.edges() {
                let (a, b) = (corners[e[0]], corners[e[1]]);
                nodes.push([
                    0.5 * (a[0] + b[0]),
                    0.5 * (a[1] + b[1]),
                    0.5 * (a[2] + b[2]),
                ]);
            }
        }
        nodes
    }

    /// Volume of the reference cell.
    pub const fn reference_volume(self) -> f64 {
        match self {
            Self::Tet4 | Self::Tet10 => 1.0 / 6.0,
            Self::Hex8 | Self::Hex20 => 8.0,
            Self::Penta6 | Self::Penta15 => 1.0,
            Self::Pyramid5 | Self::Pyramid13 => 4.0 / 3.0,
        }
    }

    /// Shape functions `N_a(xi)` into `n` (length `num_nodes()`).
    pub fn shape(self, xi: [f64; 3], n: &mut [f64]) {
        let [x, y, z] = xi;
        match self {
            Self::Tet4 => {
                n[0] = 1.0 - x - y - z;
                n[1] = x;
                n[2] = y;
                n[3] = z;
            }
            Self::Tet10 => {
                let l = [1.0 - x - y - z, x, y, z];
                for a in 0..4 {
                    n[a] = l[a] * (2.0 * l[a] - 1.0);
                }
                for (e, [a, b]) in TET_EDGES.iter().enumerate() {
                    n[4 + e] = 4.0 * l[*a] * l[*b];
                }
            }
            Self::Hex8 => {
                for (a, c) in HEX_CORNERS.iter().enumerate() {
                    n[a] = 0.125 * (1.0 + c[0] * x) * (1.0 + c[1] * y) * (1.0 + c[2] * z);
                }
            }
            Self::Hex20 => {
                for (a, c) in HEX20_NODES.iter().enumerate() {
                    let (fx, fy, fz) = (1.0 + c[0] * x, 1.0 + c[1] * y, 1.0 + c[2] * z);
                    n[a] = if a < 8 {
                        0.125 * fx * fy * fz * (c[0] * x + c[1] * y + c[2] * z - 2.0)
                    } else if c[0] == 0.0 {
                        0.25 * (1.0 - x * x) * fy * fz
                    } else if c[1] == 0.0 {
                        0.25 * fx * (1.0 - y * y) * fz
                    } else {
                        0.25 * fx * fy * (1.0 - z * z)
                    };
                }
            }
            Self::Penta6 => {
                let l = [1.0 - x - y, x, y];
                for a in 0..3 {
                    n[a] = 0.5 * l[a] * (1.0 - z);
                    n[a + 3] = 0.5 * l[a] * (1.0 + z);
                }
            }
            Self::Penta15 => {
                let l = [1.0 - x - y, x, y];
                let b = 1.0 - z * z;
                for a in 0..3 {
                    n[a] = 0.5 * l[a] * (2.0 * l[a] - 1.0) * (1.0 - z) - 0.5 * l[a] * b;
                    n[a + 3] = 0.5 * l[a] * (2.0 * l[a] - 1.0) * (1.0 + z) - 0.5 * l[a] * b;
                    let (i, j) = (a, (a + 1) % 3);
                    n[6 + a] = 2.0 * l[i] * l[j] * (1.0 - z);
                    n[9 + a] = 2.0 * l[i] * l[j] * (1.0 + z);
                    n[12 + a] = l[a] * b;
                }
            }
            Self::Pyramid5 => {
                let q = x * y * z * apex_inverse(z);
                for (a, c) in PYRAMID_CORNERS[..4].iter().enumerate() {
                    n[a] = 0.25 * ((1.0 + c[0] * x) * (1.0 + c[1] * y) - z + c[0] * c[1] * q);
                }
                n[4] = z;
            }
            Self::Pyramid13 => {
                let inv = apex_inverse(z);
                let q = x * y * z * inv;
                for (a, c) in PYRAMID_CORNERS[..4].iter().enumerate() {
                    let (ci, ei) = (c[0], c[1]);
                    n[a] = 0.25
                        * (ci * x + ei * y - 1.0)
                        * ((1.0 + ci * x) * (1.0 + ei * y) - z + ci * ei * q);
                    // lateral mid-edge a-apex
                    n[9 + a] = z * (1.0 + ci * x - z) * (1.0 + ei * y - z) * inv;
                }
                n[4] = z * (2.0 * z - 1.0);
                // base mid-edges 0-1 (eta = -1), 1-2 (xi = 1), 2-3 (eta = 1), 3-0 (xi = -1)
                let along_xi =
                    |em: f64| 0.5 * (1.0 + x - z) * (1.0 - x - z) * (1.0 + em * y - z) * inv;
                let along_eta =
                    |xm: f64| 0.5 * (1.0 + y - z) * (1.0 - y - z) * (1.0 + xm * x - z) * inv;
                n[5] = along_xi(-1.0);
                n[6] = along_eta(1.0);
                n[7] = along_xi(1.0);
                n[8] = along_eta(-1.0);
            }
        }
    }

    /// Shape function gradients in reference coordinates, `dn[3 a + k] = dN_a / dxi_k`.
    pub fn shape_gradients(self, xi: [f64; 3], dn: &mut [f64]) {
        let [x, y, z] = xi;
        match self {
            Self::Tet4 => {
                dn[..12].copy_from_slice(&[
                    -1.0, -1.0, -1.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0,
                ]);
            }
            Self::Tet10 => {
                let l = [1.0 - x - y - z, x, y, z];
                // dL_a / dxi
                let dl = [
                    [-1.0, -1.0, -1.0],
                    [1.0, 0.0, 0.0],
                    [0.0, 1.0, 0.0],
                    [0.0, 0.0, 1.0],
                ];
                for a in 0..4 {
                    for k in 0..3 {
                        dn[3 * a + k] = (4.0 * l[a] - 1.0) * dl[a][k];
                    }
                }
                for (e, [a, b]) in TET_EDGES.iter().enumerate() {
                    for k in 0..3 {
                        dn[3 * (4 + e) + k] = 4.0 * (dl[*a][k] * l[*b] + l[*a] * dl[*b][k]);
                    }
                }
            }
            Self::Hex8 => {
                for (a, c) in HEX_CORNERS.iter().enumerate() {
                    let (fx, fy, fz) = (1.0 + c[0] * x, 1.0 + c[1] * y, 1.0 + c[2] * z);
                    dn[3 * a] = 0.125 * c[0] * fy * fz;
                    dn[3 * a + 1] = 0.125 * fx * c[1] * fz;
                    dn[3 * a + 2] = 0.125 * fx * fy * c[2];
                }
            }
            Self::Hex20 => {
                for (a, c) in HEX20_NODES.iter().enumerate() {
                    let (fx, fy, fz) = (1.0 + c[0] * x, 1.0 + c[1] * y, 1.0 + c[2] * z);
                    let g = if a < 8 {
                        let s = c[0] * x + c[1] * y + c[2] * z - 2.0;
                        [
                            0.125 * c[0] * fy * fz * (s + fx),
                            0.125 * c[1] * fx * fz * (s + fy),
                            0.125 * c[2] * fx * fy * (s + fz),
                        ]
                    } else if c[0] == 0.0 {
                        [
                            -0.5 * x * fy * fz,
                            0.25 * (1.0 - x * x) * c[1] * fz,
                            0.25 * (1.0 - x * x) * fy * c[2],
                        ]
                    } else if c[1] == 0.0 {
                        [
                            0.25 * c[0] * (1.0 - y * y) * fz,
                            -0.5 * y * fx * fz,
                            0.25 * fx * (1.0 - y * y) * c[2],
                        ]
                    } else {
                        [
                            0.25 * c[0] * fy * (1.0 - z * z),
                            0.25 * fx * c[1] * (1.0 - z * z),
                            -0.5 * z * fx * fy,
                        ]
                    };
                    dn[3 * a..3 * a + 3].copy_from_slice(&g);
                }
            }
            Self::Penta6 => {
                let l = [1.0 - x - y, x, y];
                let dl = [[-1.0, -1.0], [1.0, 0.0], [0.0, 1.0]];
                for a in 0..3 {
                    dn[3 * a..3 * a + 3].copy_from_slice(&[
                        0.5 * dl[a][0] * (1.0 - z),
                        0.5 * dl[a][1] * (1.0 - z),
                        -0.5 * l[a],
                    ]);
                    dn[3 * (a + 3)..3 * (a + 3) + 3].copy_from_slice(&[
                        0.5 * dl[a][0] * (1.0 + z),
                        0.5 * dl[a][1] * (1.0 + z),
                        0.5 * l[a],
                    ]);
                }
            }
            Self::Penta15 => {
                let l = [1.0 - x - y, x, y];
                let dl = [[-1.0, -1.0], [1.0, 0.0], [0.0, 1.0]];
                let b = 1.0 - z * z;
                for a in 0..3 {
                    let q = l[a] * (2.0 * l[a] - 1.0);
                    let dq = 4.0 * l[a] - 1.0; // dq/dL
                    for (off, s) in [(0usize, -1.0), (3, 1.0)] {
                        let zf = 1.0 + s * z;
                        let row = 3 * (a + off);
                        for k in 0..2 {
                            dn[row + k] = 0.5 * dq * dl[a][k] * zf - 0.5 * dl[a][k] * b;
                        }
                        dn[row + 2] = 0.5 * q * s + l[a] * z;
                    }
                    let (i, j) = (a, (a + 1) % 3);
                    for (off, s) in [(6usize, -1.0), (9, 1.0)] {
                        let zf = 1.0 + s * z;
                        let row = 3 * (off + a);
                        for k in 0..2 {
                            dn[row + k] = 2.0 * (dl[i][k] * l[j] + l[i] * dl[j][k]) * zf;
                        }
                        dn[row + 2] = 2.0 * l[i] * l[j] * s;
                    }
                    let row = 3 * (12 + a);
                    dn[row] = dl[a][0] * b;
                    dn[row + 1] = dl[a][1] * b;
                    dn[row + 2] = -2.0 * l[a] * z;
                }
            }
            Self::Pyramid5 | Self::Pyramid13 => {
                // the gradients of the rational terms have no limit at the apex: take them just
                // below it, on the axis (only the validity check asks there)
                let z = z.min(1.0 - 1e-9);
                let inv = 1.0 / (1.0 - z);
                if self == Self::Pyramid5 {
                    for (a, c) in PYRAMID_CORNERS[..4].iter().enumerate() {
                        let (ci, ei) = (c[0], c[1]);
                        dn[3 * a] = 0.25 * (ci * (1.0 + ei * y) + ci * ei * y * z * inv);
                        dn[3 * a + 1] = 0.25 * (ei * (1.0 + ci * x) + ci * ei * x * z * inv);
                        dn[3 * a + 2] = 0.25 * (-1.0 + ci * ei * x * y * inv * inv);
                    }
                    dn[12..15].copy_from_slice(&[0.0, 0.0, 1.0]);
                    return;
                }
                for (a, c) in PYRAMID_CORNERS[..4].iter().enumerate() {
                    let (ci, ei) = (c[0], c[1]);
                    let aa = ci * x + ei * y - 1.0;
                    let bb = (1.0 + ci * x) * (1.0 + ei * y) - z + ci * ei * x * y * z * inv;
                    let db = [
                        ci * (1.0 + ei * y) + ci * ei * y * z * inv,
                        ei * (1.0 + ci * x) + ci * ei * x * z * inv,
                        -1.0 + ci * ei * x * y * inv * inv,
                    ];
                    let da = [ci, ei, 0.0];
                    for k in 0..3 {
                        dn[3 * a + k] = 0.25 * (da[k] * bb + aa * db[k]);
                    }
                    // lateral mid-edge a-apex: z U V / (1 - z)
                    let (u, v) = (1.0 + ci * x - z, 1.0 + ei * y - z);
                    let row = 3 * (9 + a);
                    dn[row] = z * ci * v * inv;
                    dn[row + 1] = z * u * ei * inv;
                    dn[row + 2] = (u * v - z * v - z * u) * inv + z * u * v * inv * inv;
                }
                dn[12..15].copy_from_slice(&[0.0, 0.0, 4.0 * z - 1.0]);
                // base mid-edges: P Q R / (2 (1 - z)), P Q along the edge, R across it
                let mids: [(usize, bool, f64); 4] = [
                    (5, true, -1.0),
                    (6, false, 1.0),
                    (7, true, 1.0),
                    (8, false, -1.0),
                ];
                for (m, along_xi, side) in mids {
                    let (t, o) = if along_xi { (x, y) } else { (y, x) };
                    let (p, q, r) = (1.0 + t - z, 1.0 - t - z, 1.0 + side * o - z);
                    let d_along = -t * r * inv;
                    let d_across = 0.5 * p * q * side * inv;
                    let d_z = 0.5 * (-q * r - p * r - p * q) * inv + 0.5 * p * q * r * inv * inv;
                    let row = 3 * m;
                    if along_xi {
                        dn[row] = d_along;
                        dn[row + 1] = d_across;
                    } else {
                        dn[row] = d_across;
                        dn[row + 1] = d_along;
                    }
                    dn[row + 2] = d_z;
                }
            }
        }
    }

    /// The stiffness quadrature rule (table in the module docs).
    pub fn stiffness_rule(self) -> QuadratureRule {
        match self {
            Self::Tet4 => quadrature::tet_1(),
            Self::Tet10 => quadrature::tet_4(),
            Self::Hex8 => quadrature::hex_gauss(2),
            Self::Hex20 => quadrature::hex_gauss(3),
            Self::Penta6 => quadrature::wedge(2),
            Self::Penta15 => quadrature::wedge(4),
            Self::Pyramid5 => quadrature::pyramid(2, 2),
            Self::Pyramid13 => quadrature::pyramid(3, 5),
        }
    }

    /// The consistent-mass quadrature rule, exact for the undistorted element.
    pub fn mass_rule(self) -> QuadratureRule {
        match self {
            Self::Tet4 => quadrature::tet_4(),
            Self::Tet10 => quadrature::tet_conical(4),
            Self::Hex8 => quadrature::hex_gauss(2),
            Self::Hex20 => quadrature::hex_gauss(3),
            Self::Penta6 => quadrature::wedge(2),
            Self::Penta15 => quadrature::wedge(4),
            Self::Pyramid5 => quadrature::pyramid(2, 4),
            Self::Pyramid13 => quadrature::pyramid(3, 5),
        }
    }

    /// Shape functions and gradients tabulated at the stiffness and mass rules' points, computed once.
    pub fn reference(self) -> &'static ReferenceData {
        static CACHE: [OnceLock<ReferenceData>; 8] = [
            OnceLock::new(),
            OnceLock::new(),
            OnceLock::new(),
            OnceLock::new(),
            OnceLock::new(),
            OnceLock::new(),
            OnceLock::new(),
            OnceLock::new(),
        ];
        let i = ALL_KINDS
            .iter()
            .position(|k| *k == self)
            .expect("kind listed in ALL_KINDS");
        CACHE[i].get_or_init(|| ReferenceData {
            stiffness: Tabulated::new(self, self.stiffness_rule()),
            mass: Tabulated::new(self, self.mass_rule()),
        })
    }
}

impl std::fmt::Display for ElementKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let s = match self {
            Self::Tet4 => "tet4",
            Self::Tet10 => "tet10",
            Self::Hex8 => "hex8",
            Self::Hex20 => "hex20",
            Self::Penta6 => "penta6",
            Self::Penta15 => "penta15",
            Self::Pyramid5 => "pyramid5",
            Self::Pyramid13 => "pyramid13",
        };
        f.write_str(s)
    }
}

/// A rule with the shape functions and reference gradients at its points.
#[derive(Debug, Clone)]
pub struct Tabulated {
    /// The quadrature rule.
    pub rule: QuadratureRule,
    /// `n[q * nn + a] = N_a(xi_q)`.
    pub n: Vec<f64>,
    /// `dn[(q * nn + a) * 3 + k] = dN_a / dxi_k (xi_q)`.
    pub dn: Vec<f64>,
}

impl Tabulated {
    fn new(kind: ElementKind, rule: QuadratureRule) -> Self {
        let nn = kind.num_nodes();
        let mut n = vec![0.0; rule.len() * nn];
        let mut dn = vec![0.0; rule.len() * nn * 3];
        for (q, p) in rule.points.iter().enumerate() {
            kind.shape(*p, &mut n[q * nn..(q + 1) * nn]);
            kind.shape_gradients(*p, &mut dn[q * nn * 3..(q + 1) * nn * 3]);
        }
        Self { rule, n, dn }
    }
}

/// Tabulated reference data of one element kind.
#[derive(Debug, Clone)]
pub struct ReferenceData {
    /// At the stiffness rule.
    pub stiffness: Tabulated,
    /// At the consistent-mass rule.
    pub mass: Tabulated,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shape_functions_are_nodal_and_partition_unity() {
        for kind in ALL_KINDS {
            let nn = kind.num_nodes();
            let mut n = vec![0.0; nn];
            for (a, p) in kind.reference_nodes().iter().enumerate() {
                kind.shape(*p, &mut n);
                for b in 0..nn {
                    let expect = if a == b { 1.0 } else { 0.0 };
                    assert!(
                        (n[b] - expect).abs() < 1e-14,
                        "{kind}: N_{b} at node {a} = {}",
                        n[b]
                    );
                }
            }
            kind.shape([0.21, 0.17, 0.13], &mut n);
            assert!((n.iter().sum::<f64>() - 1.0).abs() < 1e-14);
        }
    }

    /// Gradients against central differences of the shape functions (an independent derivation).
    #[test]
    fn gradients_match_finite_differences() {
        let h = 1e-6;
        for kind in ALL_KINDS {
            let nn = kind.num_nodes();
            let xi = [0.23, 0.19, 0.31];
            let mut dn = vec![0.0; 3 * nn];
            kind.shape_gradients(xi, &mut dn);
            let (mut np, mut nm) = (vec![0.0; nn], vec![0.0; nn]);
            for k in 0..3 {
                let (mut p, mut m) = (xi, xi);
                p[k] += h;
                m[k] -= h;
                kind.shape(p, &mut np);
                kind.shape(m, &mut nm);
                for a in 0..nn {
                    let fd = (np[a] - nm[a]) / (2.0 * h);
                    assert!(
                        (fd - dn[3 * a + k]).abs() < 1e-8,
                        "{kind}: dN_{a}/dxi_{k}: {fd} vs {}",
                        dn[3 * a + k]
                    );
                }
            }
        }
    }

    #[test]
    fn hex20_node_table_equals_the_corner_and_edge_construction() {
        assert_eq!(ElementKind::Hex20.reference_nodes(), HEX20_NODES.to_vec());
    }

    #[test]
    fn face_nodes_of_quadratic_faces() {
        // hex20 bottom face: corners 0 1 2 3 and mid-edges 8 9 10 11
        assert_eq!(
            ElementKind::Hex20.face_nodes(0),
            vec![0, 1, 2, 3, 8, 9, 10, 11]
        );
        // tet10 face S2 (1-4-2): mid-edges 1-4 (node 8 -> index 7), 4-2 (index 8), 2-1 (index 4)
        assert_eq!(ElementKind::Tet10.face_nodes(1), vec![0, 3, 1, 7, 8, 4]);
        assert_eq!(
            ElementKind::Penta15.face_nodes(2),
            vec![0, 3, 4, 1, 12, 9, 13, 6]
        );
    }
}
