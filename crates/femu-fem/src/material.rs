//! Linear elastic materials.
//!
//! Stresses and strains use Voigt notation in Abaqus/CalculiX order
//! `(11, 22, 33, 12, 13, 23)` with engineering shear strains `gamma_ij = 2 eps_ij`, so that
//! `sigma = D eps` and the strain energy density is `eps^T D eps / 2`. SI units: Pa, kg/m^3.

use crate::FemError;
use serde::{Deserialize, Serialize};

/// The elasticity law of a material.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum Elasticity {
    /// Isotropic: Young's modulus `e` (Pa) and Poisson's ratio `nu`.
    Isotropic {
        /// Young's modulus in Pa.
        e: f64,
        /// Poisson's ratio, `-1 < nu < 1/2`.
        nu: f64,
    },
    /// A general symmetric positive definite 6x6 elasticity matrix (Pa) in Voigt order
    /// `(11, 22, 33, 12, 13, 23)`: orthotropic and anisotropic materials.
    Anisotropic(Box<[[f64; 6]; 6]>),
}

/// A material: elasticity and density.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Material {
    /// Name (as in the input file).
    pub name: String,
    /// Elasticity law.
    pub elasticity: Elasticity,
    /// Mass density in kg/m^3.
    pub density: f64,
}

/// Lame parameters `(lambda, mu)` from Young's modulus and Poisson's ratio.
pub fn lame_parameters(e: f64, nu: f64) -> (f64, f64) {
    (
        e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu)),
        e / (2.0 * (1.0 + nu)),
    )
}

impl Material {
    /// An isotropic material; checked by [`Material::validate`].
    pub fn isotropic(
        name: impl Into<String>,
        e: f64,
        nu: f64,
        density: f64,
    ) -> Result<Self, FemError> {
        let m = Self {
            name: name.into(),
            elasticity: Elasticity::Isotropic { e, nu },
            density,
        };
        m.validate()?;
        Ok(m)
    }

    /// A general anisotropic material; checked by [`Material::validate`].
    pub fn anisotropic(
        name: impl Into<String>,
        d: [[f64; 6]; 6],
        density: f64,
    ) -> Result<Self, FemError> {
        let m = Self {
            name: name.into(),
            elasticity: Elasticity::Anisotropic(Box::new(d)),
            density,
        };
        m.validate()?;
        Ok(m)
    }

    /// Structural steel: `E = 210 GPa`, `nu = 0.3`, `rho = 7850 kg/m^3`.
    pub fn steel() -> Self {
        Self {
            name: "steel".into(),
            elasticity: Elasticity::Isotropic { e: 210e9, nu: 0.3 },
            density: 7850.0,
        }
    }

    /// An orthotropic material from engineering constants (`e1, e2, e3` in Pa; `nu12, nu13, nu23`;
    /// shear moduli `g12, g13, g23` in Pa): the compliance matrix is built and inverted.
    pub fn orthotropic(
        name: impl Into<String>,
        e: [f64; 3],
        nu12_13_23: [f64; 3],
        g12_13_23: [f64; 3],
        density: f64,
    ) -> Result<Self, FemError> {
        let name = name.into();
        let [e1, e2, e3] = e;
        let [n12, n13, n23] = nu12_13_23;
        let mut s = nalgebra::SMatrix::<f64, 6, 6>::zeros();
        s[(0, 0)] = 1.0 / e1;
        s[(1, 1)] = 1.0 / e2;
        s[(2, 2)] = 1.0 / e3;
        s[(0, 1)] = -n12 / e1;
        s[(1, 0)] = -n12 / e1;
        s[(0, 2)] = -n13 / e1;
        s[(2, 0)] = -n13 / e1;
        s[(1, 2)] = -n23 / e2;
        s[(2, 1)] = -n23 / e2;
        for (i, g) in g12_13_23.iter().enumerate() {
            s[(3 + i, 3 + i)] = 1.0 / g;
        }
        let d = s.try_inverse().ok_or_else(|| FemError::InvalidMaterial {
            name: name.clone(),
            reason: "singular compliance matrix".into(),
        })?;
        let mut out = [[0.0; 6]; 6];
        for i in 0..6 {
            for j in 0..6 {
                out[i][j] = 0.5 * (d[(i, j)] + d[(j, i)]);
            }
        }
        Self::anisotropic(name, out, density)
    }

    /// Checks that the material is physical: finite positive density, and a symmetric positive
    /// definite elasticity matrix (for isotropic: `E > 0`, `-1 < nu < 1/2`).
    ///
    /// # Errors
    /// [`FemError::InvalidMaterial`] naming the material and the reason.
    pub fn validate(&self) -> Result<(), FemError> {
        let bad = |reason: String| {
            Err(FemError::InvalidMaterial {
                name: self.name.clone(),
                reason,
            })
        };
        if !(self.density.is_finite() && self.density > 0.0) {
            return bad(format!(
                "density must be positive and finite, got {}",
                self.density
            ));
        }
        match &self.elasticity {
            Elasticity::Isotropic { e, nu } => {
                if !(e.is_finite() && *e > 0.0) {
                    return bad(format!(
                        "Young's modulus must be positive and finite, got {e}"
                    ));
                }
                if !(nu.is_finite() && *nu > -1.0 && *nu < 0.5) {
                    return bad(format!("Poisson's ratio must lie in (-1, 0.5), got {nu}"));
                }
            }
            Elasticity::Anisotropic(d) => {
                let scale = d.iter().flatten().fold(0.0_f64, |m, v| m.max(v.abs()));
                for i in 0..6 {
                    for j in 0..6 {
                        if !d[i][j].is_finite() {
                            return bad(format!("elasticity entry ({i}, {j}) is not finite"));
                        }
                        if (d[i][j] - d[j][i]).abs() > 1e-12 * scale {
                            return bad(format!(
                                "elasticity matrix is not symmetric at ({i}, {j})"
                            ));
                        }
                    }
                }
                let m = nalgebra::SMatrix::<f64, 6, 6>::from_fn(|i, j| d[i][j]);
                if m.cholesky().is_none() {
                    return bad("elasticity matrix is not positive definite".into());
                }
            }
        }
        Ok(())
    }

    /// The 6x6 elasticity matrix `D` (Voigt order of the module docs).
    pub fn elasticity_matrix(&self) -> [[f64; 6]; 6] {
        match &self.elasticity {
            Elasticity::Isotropic { e, nu } => {
                let (l, mu) = lame_parameters(*e, *nu);
                let mut d = [[0.0; 6]; 6];
                for i in 0..3 {
                    for j in 0..3 {
                        d[i][j] = l;
                    }
                    d[i][i] = l + 2.0 * mu;
                    d[3 + i][3 + i] = mu;
                }
                d
            }
            Elasticity::Anisotropic(d) => **d,
        }
    }
}

/// `D` given in a rectangular frame whose axes are the columns of `a` (basic components), turned
/// into the basic (global) frame: `D' = T D T^T` with `T` the stress transformation of the rotation `a`
/// (Voigt order 11, 22, 33, 12, 13, 23, engineering shears; docs/MATH.md, "Material
/// orientations"): Nastran's MAT9 in a PSOLID's `CORDM`, Abaqus's material in an `*ORIENTATION`.
pub fn rotate_voigt(d: &[[f64; 6]; 6], a: &[[f64; 3]; 3]) -> [[f64; 6]; 6] {
    // stress in the frame s'_ij = a_ik a_jl s_kl with a_ik = (axis k)_i: basic = A local A^T
    let pairs = [(0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2)];
    let t: [[f64; 6]; 6] = std::array::from_fn(|p| {
        let (i, j) = pairs[p];
        std::array::from_fn(|q| {
            let (k, l) = pairs[q];
            if k == l {
                a[i][k] * a[j][l]
            } else {
                a[i][k] * a[j][l] + a[i][l] * a[j][k]
            }
        })
    });
    std::array::from_fn(|i| {
        std::array::from_fn(|j| {
            (0..6)
                .map(|p| (0..6).map(|q| t[i][p] * d[p][q] * t[j][q]).sum::<f64>())
                .sum()
        })
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn isotropic_matrix_gives_uniaxial_stress_of_hookes_law() {
        // Uniaxial stress sigma_11 = E eps_11 when the lateral strains are -nu eps_11.
        let m = Material::isotropic("s", 200e9, 0.25, 7800.0).unwrap();
        let d = m.elasticity_matrix();
        let eps = [1e-3, -0.25e-3, -0.25e-3, 0.0, 0.0, 0.0];
        let sigma: Vec<f64> = (0..6)
            .map(|i| (0..6).map(|j| d[i][j] * eps[j]).sum())
            .collect();
        assert!((sigma[0] - 200e9 * 1e-3).abs() < 1e-3);
        assert!(sigma[1].abs() < 1e-3 && sigma[2].abs() < 1e-3);
        assert!((d[3][3] - 200e9 / 2.5).abs() < 1e-3);
    }

    #[test]
    fn orthotropic_with_isotropic_constants_equals_isotropic() {
        let (e, nu) = (70e9, 0.33);
        let g = e / (2.0 * (1.0 + nu));
        let o = Material::orthotropic("o", [e; 3], [nu; 3], [g; 3], 2700.0).unwrap();
        let i = Material::isotropic("i", e, nu, 2700.0).unwrap();
        let (a, b) = (o.elasticity_matrix(), i.elasticity_matrix());
        for r in 0..6 {
            for c in 0..6 {
                assert!(
                    (a[r][c] - b[r][c]).abs() < 1e-6 * e,
                    "({r},{c}) {} vs {}",
                    a[r][c],
                    b[r][c]
                );
            }
        }
    }

    #[test]
    fn unphysical_materials_are_rejected_with_their_name() {
        for (e, nu, rho) in [
            (-1.0, 0.3, 1.0),
            (1.0, 0.5, 1.0),
            (1.0, 0.3, 0.0),
            (f64::NAN, 0.3, 1.0),
        ] {
            match Material::isotropic("bad", e, nu, rho) {
                Err(FemError::InvalidMaterial { name, .. }) => assert_eq!(name, "bad"),
                other => panic!("accepted {other:?}"),
            }
        }
        let mut d = Material::steel().elasticity_matrix();
        d[0][0] = -1.0;
        assert!(Material::anisotropic("neg", d, 1.0).is_err());
        d = Material::steel().elasticity_matrix();
        d[0][5] = 1.0;
        assert!(Material::anisotropic("asym", d, 1.0).is_err());
    }
}
