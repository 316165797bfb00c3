//! `*ORIENTATION`: the material axes of an anisotropic solid section and of a shell's plies
//! (docs/MATH.md, "Material orientations").
//!
//! An orientation is a frame `(e1, e2, e3)`: `SYSTEM=RECTANGULAR` from a point `a` on its 1-axis,
//! a point `b` in its 1-2 plane and its origin `c` (the global origin when not given), `e1 = (a -
//! c) / |a - c|`, `e3 = e1 x (b - c)` normalised, `e2 = e3 x e1`; `SYSTEM=CYLINDRICAL` from two
//! points `a`, `b` on its axis, at a point `p`: `e1` radial (the part of `p - a` normal to the
//! axis), `e3` along the axis from `a` to `b`, `e2 = e3 x e1` (the circumferential direction).
//! The points are coordinates (`DEFINITION=COORDINATES`), node numbers (`NODES`) or the element's
//! own local node numbers (`OFFSET TO NODES`, whose origin defaults to its first node). A second
//! data line names a local axis `k` and an angle `alpha`: the two other axes turn by `alpha`
//! degrees about `e_k`, right-handed.
//!
//! A solid takes the frame as its material's axes. A shell (Abaqus's rule for shells and
//! membranes) takes `k` as the axis nearest its normal and projects the next axis in the cycle
//! (1, 2, 3) onto its surface as the material 1-direction; the material 2-direction is the normal
//! crossed with it.

use super::structural::at_err;
use super::*;

/// The frame's type.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum System {
    Rectangular,
    Cylindrical,
}

/// What the points of the first data line are.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Definition {
    Coordinates,
    Nodes,
    OffsetToNodes,
}

/// An `*ORIENTATION` as written: resolved per element once the nodes are known.
#[derive(Debug, Clone)]
pub(super) struct OrientationCard {
    pub(super) name: String,
    pub(super) system: System,
    pub(super) definition: Definition,
    pub(super) lines: Vec<Vec<String>>,
    pub(super) line: Location,
}

/// The points `a`, `b` and the origin `c` where one is given.
type Points = ([f64; 3], [f64; 3], Option<[f64; 3]>);

/// A frame: its axes `e1, e2, e3` (rows, unit, right-handed) in the global frame.
pub(super) type Frame = [[f64; 3]; 3];

pub(super) fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// The distance between two points.
pub(super) fn dist(a: [f64; 3], b: [f64; 3]) -> f64 {
    let d = sub(a, b);
    dot(d, d).sqrt()
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// `v / |v|`, or none for a vector of no length (relative to `scale`).
fn unit(v: [f64; 3], scale: f64) -> Option<[f64; 3]> {
    let n = dot(v, v).sqrt();
    (n > 1e-12 * scale && n.is_finite()).then(|| [v[0] / n, v[1] / n, v[2] / n])
}

/// The unit normal of a shell element of corner coordinates `x` (three corners for a triangle,
/// four for a quadrilateral; midside nodes after them), by the right-hand rule around its nodes:
/// for a quadrilateral the cross product of its diagonals.
pub(super) fn shell_normal(x: &[[f64; 3]]) -> Option<[f64; 3]> {
    let n = if x.len() == 3 || x.len() == 6 {
        cross(sub(x[1], x[0]), sub(x[2], x[0]))
    } else {
        cross(sub(x[2], x[0]), sub(x[3], x[1]))
    };
    let scale = x.iter().map(|p| dot(sub(*p, x[0]), sub(*p, x[0]))).sum();
    unit(n, scale)
}

/// Where an orientation is resolved: the element's id and its nodes' coordinates (in the deck's
/// order), and the coordinates of any node by id.
pub(super) struct At<'a> {
    pub(super) element: u64,
    pub(super) x: &'a [[f64; 3]],
    pub(super) node: &'a dyn Fn(u64) -> Option<[f64; 3]>,
}

impl OrientationCard {
    fn err(&self, reason: String) -> IoError {
        at_err(
            &self.line,
            format!("*ORIENTATION, NAME={}: {reason}", self.name),
        )
    }

    /// The points of the first data line: `a`, `b` and the origin `c` where given.
    fn points(&self, at: &At) -> Result<Points, IoError> {
        let row = self
            .lines
            .first()
            .ok_or_else(|| self.err("no data line (the points a and b)".into()))?;
        let f: Vec<&str> = row.iter().map(|s| s.trim()).collect();
        let node = |s: &str, what: &str| -> Result<[f64; 3], IoError> {
            let id: u64 = s
                .parse()
                .map_err(|_| self.err(format!("{what} {s:?} is not a node number")))?;
            match self.definition {
                Definition::Nodes => (at.node)(id).ok_or_else(|| {
                    self.err(format!(
                        "{what} is node {id}, which the deck does not define"
                    ))
                }),
                _ => id
                    .checked_sub(1)
                    .and_then(|k| at.x.get(k as usize))
                    .copied()
                    .ok_or_else(|| {
                        self.err(format!(
                            "{what} is local node {id}, and element {} has {} nodes",
                            at.element,
                            at.x.len()
                        ))
                    }),
            }
        };
        match self.definition {
            Definition::Coordinates => {
                let v = |k: usize| -> Result<f64, IoError> {
                    let s = f.get(k).copied().unwrap_or("");
                    parse_f64(s).ok_or_else(|| {
                        self.err(format!(
                            "coordinate {} of its points is {s:?}, not a number",
                            k + 1
                        ))
                    })
                };
                let p = |k: usize| -> Result<[f64; 3], IoError> {
                    Ok([v(3 * k)?, v(3 * k + 1)?, v(3 * k + 2)?])
                };
                let c = if f.len() > 6 && f[6..].iter().any(|s| !s.is_empty()) {
                    Some(p(2)?)
                } else {
                    None
                };
                Ok((p(0)?, p(1)?, c))
            }
            _ => {
                let a = node(f.first().copied().unwrap_or(""), "point a")?;
                let b = node(f.get(1).copied().unwrap_or(""), "point b")?;
                let c = match f.get(2).copied() {
                    Some(s) if !s.is_empty() => Some(node(s, "the origin c")?),
                    _ if self.definition == Definition::OffsetToNodes => at.x.first().copied(),
                    _ => None,
                };
                Ok((a, b, c))
            }
        }
    }

    /// The second data line: the local axis (0-based) about which the others turn, and the angle
    /// (degrees); none when the card has one data line.
    fn rotation(&self) -> Result<Option<(usize, f64)>, IoError> {
        let Some(row) = self.lines.get(1) else {
            return Ok(None);
        };
        let field = |k: usize| row.get(k).map(|s| s.trim()).unwrap_or("");
        let axis = match field(0) {
            "" => 0,
            s => match s.parse::<usize>() {
                Ok(k @ 1..=3) => k - 1,
                _ => {
                    return Err(self.err(format!(
                        "the local axis of the additional rotation is {s:?}, not 1, 2 or 3"
                    )));
                }
            },
        };
        let angle = match field(1) {
            "" => 0.0,
            s => parse_f64(s).filter(|v| v.is_finite()).ok_or_else(|| {
                self.err(format!("the additional rotation {s:?} is not a number"))
            })?,
        };
        Ok(Some((axis, angle)))
    }

    /// The frame at element `at` (a cylindrical one at the element's centre), turned by the
    /// additional rotation.
    pub(super) fn frame(&self, at: &At) -> Result<Frame, IoError> {
        let (a, b, c) = self.points(at)?;
        let scale = [a, b, c.unwrap_or([0.0; 3])]
            .iter()
            .flatten()
            .fold(0.0f64, |m, v| m.max(v.abs()))
            .max(1.0);
        let mut e = match self.system {
            System::Rectangular => {
                let c = c.unwrap_or([0.0; 3]);
                let e1 = unit(sub(a, c), scale)
                    .ok_or_else(|| self.err("point a is its origin: no 1-axis".into()))?;
                let e3 = unit(cross(e1, sub(b, c)), scale)
                    .ok_or_else(|| self.err("point b lies on its 1-axis: no 1-2 plane".into()))?;
                [e1, cross(e3, e1), e3]
            }
            System::Cylindrical => {
                let e3 = unit(sub(b, a), scale)
                    .ok_or_else(|| self.err("points a and b coincide: no axis".into()))?;
                let n = at.x.len() as f64;
                let p = at.x.iter().fold([0.0; 3], |s, q| {
                    [s[0] + q[0] / n, s[1] + q[1] / n, s[2] + q[2] / n]
                });
                let r = sub(p, a);
                let r = sub(r, {
                    let s = dot(r, e3);
                    [s * e3[0], s * e3[1], s * e3[2]]
                });
                let e1 = unit(r, scale).ok_or_else(|| {
                    self.err(format!(
                        "element {}'s centre lies on its axis: no radial direction",
                        at.element
                    ))
                })?;
                [e1, cross(e3, e1), e3]
            }
        };
        if let Some((k, angle)) = self.rotation()? {
            let (i, j) = ((k + 1) % 3, (k + 2) % 3);
            let (s, co) = angle.to_radians().sin_cos();
            let (ei, ej) = (e[i], e[j]);
            for d in 0..3 {
                e[i][d] = co * ei[d] + s * ej[d];
                e[j][d] = -s * ei[d] + co * ej[d];
            }
        }
        Ok(e)
    }

    /// A shell's material 1-direction at element `at`, of unit normal `normal`: the frame's axis
    /// after the one its second data line names (the axis nearest the normal), projected onto the
    /// element's plane. Refused without that line (Abaqus requires it for shells) and where the
    /// projected axis is within 0.1 degree of the normal.
    pub(super) fn shell_axis(&self, at: &At, normal: [f64; 3]) -> Result<[f64; 3], IoError> {
        let Some((k, _)) = self.rotation()? else {
            return Err(self.err(
                "a shell's orientation needs its second data line (the local axis nearest the shell's normal, and a rotation about it), as Abaqus requires".into(),
            ));
        };
        let e = self.frame(at)?;
        let v = e[(k + 1) % 3];
        let along = dot(v, normal);
        if along.abs() > 0.1f64.to_radians().cos() {
            return Err(self.err(format!(
                "its local {}-axis, which it projects onto shell element {} as the material 1-direction, is normal to the element; name the axis nearest the normal on the second data line",
                (k + 1) % 3 + 1,
                at.element
            )));
        }
        Ok(unit(
            [
                v[0] - along * normal[0],
                v[1] - along * normal[1],
                v[2] - along * normal[2],
            ],
            1.0,
        )
        .expect("not normal"))
    }
}

/// The `*ORIENTATION` named `name` by the section of line `at`.
pub(super) fn named<'a>(
    orientations: &'a BTreeMap<String, OrientationCard>,
    name: &str,
    at: &Location,
) -> Result<&'a OrientationCard, IoError> {
    orientations.get(name).ok_or_else(|| {
        let hint = crate::spelling::suggestion(name, orientations.keys().map(String::as_str), "");
        at_err(
            at,
            format!("ORIENTATION={name}: no *ORIENTATION has that name{hint}"),
        )
    })
}

/// A shell's material axes at one element: its unit normal, where it is, and the deck's
/// orientations (docs/MATH.md, "Material orientations").
pub(super) struct ShellAxes<'a> {
    pub(super) normal: Option<[f64; 3]>,
    pub(super) at: At<'a>,
    pub(super) orientations: &'a BTreeMap<String, OrientationCard>,
    /// The section's line (for its errors).
    pub(super) line: &'a Location,
}

impl ShellAxes<'_> {
    fn normal(&self) -> Result<[f64; 3], IoError> {
        self.normal.ok_or_else(|| {
            at_err(
                self.line,
                format!(
                    "shell element {} has no normal (its corners lie on a line)",
                    self.at.element
                ),
            )
        })
    }

    /// The material 1-direction of the orientation `name`, or Abaqus's default (the global x axis
    /// projected onto the shell, or z where x is within 0.1 degree of its normal) for none.
    pub(super) fn axis(&self, name: Option<&str>) -> Result<[f64; 3], IoError> {
        let n = self.normal()?;
        match name {
            Some(name) => named(self.orientations, name, self.line)?.shell_axis(&self.at, n),
            None => {
                let v = if n[0].abs() > 0.1f64.to_radians().cos() {
                    [0.0, 0.0, 1.0]
                } else {
                    [1.0, 0.0, 0.0]
                };
                let along = dot(v, n);
                Ok(unit(
                    [
                        v[0] - along * n[0],
                        v[1] - along * n[1],
                        v[2] - along * n[2],
                    ],
                    1.0,
                )
                .expect("not normal"))
            }
        }
    }

    /// The angle (degrees, about the normal) of orientation `name`'s material 1-direction from
    /// `from` (the section's): a ply's angle given by an orientation's name.
    pub(super) fn angle_from(&self, from: [f64; 3], name: &str) -> Result<f64, IoError> {
        Ok(angle_about(from, self.axis(Some(name))?, self.normal()?))
    }
}

/// The signed angle (degrees) from unit vector `from` to unit vector `to`, both normal to unit
/// `normal`, right-handed about it.
pub(super) fn angle_about(from: [f64; 3], to: [f64; 3], normal: [f64; 3]) -> f64 {
    dot(cross(from, to), normal)
        .atan2(dot(from, to))
        .to_degrees()
}

/// The elasticity matrix `d` given in the axes of `frame` (rows: the material axes in the global
/// frame), in the global frame ([`femu_fem::material::rotate_voigt`], whose frame is by columns).
pub(super) fn rotate_elasticity(d: &[[f64; 6]; 6], frame: &Frame) -> [[f64; 6]; 6] {
    let columns: Frame = std::array::from_fn(|i| std::array::from_fn(|j| frame[j][i]));
    femu_fem::material::rotate_voigt(d, &columns)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 90-degree turn about z maps 1 to 2: the rotated matrix exchanges the 11 and 22 entries and
    /// the 13 and 23 shears, by hand.
    #[test]
    fn a_quarter_turn_exchanges_the_axes() {
        let mut d = [[0.0; 6]; 6];
        let v = [10.0, 2.0, 3.0, 0.5, 0.7, 0.9];
        for k in 0..6 {
            d[k][k] = v[k];
        }
        d[0][1] = 1.0;
        d[1][0] = 1.0;
        d[0][2] = 0.4;
        d[2][0] = 0.4;
        // material axes: 1 along global y, 2 along -x, 3 along z
        let frame = [[0.0, 1.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 0.0, 1.0]];
        let g = rotate_elasticity(&d, &frame);
        assert_eq!(g[1][1], 10.0);
        assert_eq!(g[0][0], 2.0);
        assert_eq!(g[2][2], 3.0);
        assert_eq!(g[3][3], 0.5);
        assert_eq!(g[5][5], 0.7);
        assert_eq!(g[4][4], 0.9);
        assert_eq!(g[0][1], 1.0);
        assert_eq!(g[1][2], 0.4);
        assert_eq!(g[0][2], 0.0);
    }

    /// An orthotropic material turned by 30 degrees about z: the in-plane modulus along global x
    /// is the textbook `1 / E_x = c^4 / E1 + s^4 / E2 + c^2 s^2 (1 / G12 - 2 nu12 / E1)` (Jones,
    /// Mechanics of Composite Materials, eq. 2.98), from the inverse of the rotated matrix.
    #[test]
    fn a_turned_orthotropic_material_has_the_textbook_off_axis_modulus() {
        let (e1, e2, e3, nu12, nu13, nu23, g12, g13, g23) =
            (140e9, 10e9, 10e9, 0.3, 0.3, 0.4, 5e9, 5e9, 3.5e9);
        let m = Material::orthotropic(
            "ply",
            [e1, e2, e3],
            [nu12, nu13, nu23],
            [g12, g13, g23],
            1500.0,
        )
        .unwrap();
        let t = 30f64.to_radians();
        let frame = [
            [t.cos(), t.sin(), 0.0],
            [-t.sin(), t.cos(), 0.0],
            [0.0, 0.0, 1.0],
        ];
        let g = rotate_elasticity(&m.elasticity_matrix(), &frame);
        // S11 of the turned compliance: the strain of a unit stress sigma_xx, by Gauss-Jordan
        let mut a: Vec<[f64; 7]> = (0..6)
            .map(|i| {
                let mut r = [0.0; 7];
                r[..6].copy_from_slice(&g[i]);
                r[6] = if i == 0 { 1.0 } else { 0.0 };
                r
            })
            .collect();
        for k in 0..6 {
            let p = (k..6)
                .max_by(|x, y| a[*x][k].abs().total_cmp(&a[*y][k].abs()))
                .unwrap();
            a.swap(k, p);
            for i in 0..6 {
                if i != k {
                    let f = a[i][k] / a[k][k];
                    for j in 0..7 {
                        a[i][j] -= f * a[k][j];
                    }
                }
            }
        }
        let s11 = a[0][6] / a[0][0];
        let (c, sn) = (t.cos(), t.sin());
        let ex = 1.0
            / (c.powi(4) / e1 + sn.powi(4) / e2 + c * c * sn * sn * (1.0 / g12 - 2.0 * nu12 / e1));
        assert!((1.0 / s11 / ex - 1.0).abs() < 1e-12, "{} {ex}", 1.0 / s11);
    }
}
