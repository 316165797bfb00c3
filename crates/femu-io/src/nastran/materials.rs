//! `PSOLID` with `MAT1` and `MAT9`: the material of each property, as the Quick Reference Guide
//! defines them (MAT1's remarks for the moduli, PSOLID's `CORDM` for the frame of a MAT9).

use super::cards::Card;
use super::geometry::Geometry;
use crate::{IoError, Warning};
use femu_fem::material::Material;

/// The isotropic moduli of a MAT1 as Nastran completes them (QRG MAT1, remarks): one of `E`, `G`,
/// `NU` blank is computed from `E = 2 (1 + NU) G`; with all three given they are used as given, and
/// Nastran warns when they miss that identity by more than 1 %. femu's isotropic material holds
/// `E` and `NU` (its shear modulus is `E / (2 (1 + NU))`), so three moduli that miss the identity
/// by more than 1 % are refused rather than read as another material; within 1 %, `E` and `NU` are
/// used and the difference is reported.
pub(super) fn mat1_moduli(m: &Card, warnings: &mut Vec<Warning>) -> Result<(f64, f64), IoError> {
    let mid = m.field(0);
    let (e, g, nu) = (m.real(1, "E")?, m.real(2, "G")?, m.real(3, "NU")?);
    Ok(match (e, g, nu) {
        (Some(e), Some(g), Some(nu)) => {
            let g_iso = e / (2.0 * (1.0 + nu));
            let miss = (g / g_iso - 1.0).abs();
            if miss > 0.01 {
                return Err(m.err(format!(
                    "{mid}: E = {e:e}, G = {g:e} and NU = {nu} are not isotropic (E / (2 (1 + NU)) = {g_iso:e}, {:.1} % from G): Nastran uses the three as given; femu models isotropic materials by E and NU (leave G blank, or give the material as a MAT9)",
                    100.0 * miss
                )));
            }
            if miss > 0.0 {
                warnings.push(Warning {
                    path: m.path.clone(),
                    line: m.line,
                    message: format!(
                        "MAT1 {mid}: G = {g:e} differs from E / (2 (1 + NU)) = {g_iso:e} by {:.3} %: femu uses E and NU",
                        100.0 * miss
                    ),
                });
            }
            (e, nu)
        }
        (Some(e), None, Some(nu)) => (e, nu),
        (Some(e), Some(g), None) => (e, e / (2.0 * g) - 1.0),
        (None, Some(g), Some(nu)) => (2.0 * g * (1.0 + nu), nu),
        // QRG MAT1: with E and NU (or G and NU) both blank they are both 0; a solid with NU = 0
        // and a zero modulus is not what a modal model means
        _ => {
            return Err(m.err(format!(
                "{mid}: two of E, G and NU are needed (Nastran sets the blank pair to 0, a material with no stiffness in shear or in tension)"
            )));
        }
    })
}

/// A MAT9's 6x6 matrix in femu's order (11, 22, 33, 12, 13, 23) and in the basic frame: the card's
/// `G11 ... G66` relate `(sx, sy, sz, txy, tyz, tzx)` to the engineering strains in that order, in
/// the material frame `CORDM` of the PSOLID (QRG PSOLID: 0 basic, -1 the element's own, `n` a
/// coordinate system), turned into the basic frame by the stress transformation of a rectangular
/// system's axes.
pub(super) fn mat9_matrix(
    m: &Card,
    psolid: &Card,
    geometry: &mut Geometry<'_>,
) -> Result<[[f64; 6]; 6], IoError> {
    let mut g = [[0.0; 6]; 6];
    let mut k = 1;
    for i in 0..6 {
        for j in i..6 {
            let v = m.real(k, "G")?.unwrap_or(0.0);
            g[i][j] = v;
            g[j][i] = v;
            k += 1;
        }
    }
    // Nastran's (x, y, z, xy, yz, zx) to femu's (11, 22, 33, 12, 13, 23)
    let from = [0, 1, 2, 3, 5, 4];
    let d: [[f64; 6]; 6] = std::array::from_fn(|i| std::array::from_fn(|j| g[from[i]][from[j]]));
    let cordm = psolid.int(2, "CORDM")?.unwrap_or(0);
    match cordm {
        0 => Ok(d),
        -1 => Err(psolid.err(format!(
            "{}: CORDM = -1 gives MAT9 {} in each element's own coordinate system, which femu does not build; give the material frame as a coordinate system (CORDM = n)",
            psolid.field(0),
            m.field(0)
        ))),
        cid => {
            let frame = geometry.frame(cid, psolid)?;
            if frame.kind != 0 {
                return Err(psolid.err(format!(
                    "{}: CORDM = {cid} is a {} system: the anisotropic MAT9 {} would turn from element to element, which femu does not model (a rectangular material system is read)",
                    psolid.field(0),
                    if frame.kind == 1 { "cylindrical" } else { "spherical" },
                    m.field(0)
                )));
            }
            Ok(femu_fem::material::rotate_voigt(&d, &frame.axes))
        }
    }
}

/// The structural element damping coefficient `GE` of a material card (QRG: MAT1 field 9, MAT2
/// field 14, MAT8 field 18, MAT9 field 32; blank is 0): `i GE K_e` in the dynamic stiffness of a
/// direct frequency response of the elements made of it.
pub(super) fn material_ge(m: &Card) -> Result<f64, IoError> {
    let at = match m.name.as_str() {
        "MAT1" => 7,
        "MAT2" => 12,
        "MAT8" => 16,
        "MAT9" => 30,
        _ => return Ok(0.0),
    };
    let ge = m.real(at, "GE")?.unwrap_or(0.0);
    if !(ge.is_finite() && ge >= 0.0) {
        return Err(m.err(format!(
            "{}: GE = {ge}: a structural damping coefficient is at least 0",
            m.field(0)
        )));
    }
    Ok(ge)
}

/// The material of MAT1 or MAT9 `m` for the PSOLID `psolid`, its density times `wtmass`.
pub(super) fn material(
    m: &Card,
    psolid: &Card,
    geometry: &mut Geometry<'_>,
    wtmass: f64,
    warnings: &mut Vec<Warning>,
) -> Result<Material, IoError> {
    let mid = m.field(0);
    let located = |source| IoError::Model {
        path: m.path.clone(),
        line: m.line,
        source,
    };
    let (rho_field, name) = if m.name == "MAT9" {
        (22, format!("MAT9 {mid}"))
    } else {
        (4, format!("MAT1 {mid}"))
    };
    let rho = m
        .real(rho_field, "RHO")?
        .filter(|r| *r > 0.0)
        .ok_or_else(|| {
            m.err(format!(
                "{mid} has no RHO (a modal analysis needs the density)"
            ))
        })?;
    if m.name == "MAT9" {
        let d = mat9_matrix(m, psolid, geometry)?;
        return Material::anisotropic(name, d, rho * wtmass).map_err(located);
    }
    let (e, nu) = mat1_moduli(m, warnings)?;
    Material::isotropic(name, e, nu, rho * wtmass).map_err(located)
}
