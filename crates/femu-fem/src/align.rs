//! Aligning a test wireframe onto the model: similarity transforms fitted by least squares.
//!
//! A test's coordinates are the test engineer's: another origin, other axes, sometimes another
//! scale. [`fit_pairs`] fits `x -> s R x + t` (`R` a rotation, `s` a uniform scale or 1) to node
//! pairs the user gives by the closed-form least-squares solution of Umeyama (1991): centre both
//! point sets, take the SVD `U S V^T` of their cross-covariance, `R = U diag(1, 1, det(U V^T)) V^T`
//! (never a reflection), `s = tr(S D) / var(from)`, `t = mean(to) - s R mean(from)`.
//! [`fit_surface`] refines a transform by iterative closest points: every test point is moved to
//! the nearest point of the model's boundary (its faces split into triangles through the corner
//! nodes) and the pairs are fitted again, until the mean distance stops falling.
//! (docs/MATH.md, "Mapping test nodes".)

use crate::FemError;
use crate::locate::{Grid, dist};
use crate::mesh::Mesh;
use nalgebra::{Matrix3, Vector3};
use std::collections::HashMap;

/// `x -> scale * rotation * x + translation`.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Transform {
    /// A proper rotation (row-major).
    pub rotation: [[f64; 3]; 3],
    /// Translation, in the target's units.
    pub translation: [f64; 3],
    /// Uniform scale (1 for a rigid transform).
    pub scale: f64,
}

impl Transform {
    /// The identity.
    pub const IDENTITY: Self = Self {
        rotation: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
        translation: [0.0; 3],
        scale: 1.0,
    };

    /// The image of a point.
    pub fn apply(&self, p: [f64; 3]) -> [f64; 3] {
        let r = self.rotate(p);
        std::array::from_fn(|i| self.scale * r[i] + self.translation[i])
    }

    /// The image of a direction (rotation only).
    pub fn rotate(&self, v: [f64; 3]) -> [f64; 3] {
        std::array::from_fn(|i| (0..3).map(|k| self.rotation[i][k] * v[k]).sum())
    }

    /// The rotation angle, degrees.
    pub fn angle_degrees(&self) -> f64 {
        let tr = self.rotation[0][0] + self.rotation[1][1] + self.rotation[2][2];
        ((tr - 1.0) / 2.0).clamp(-1.0, 1.0).acos().to_degrees()
    }
}

/// A fitted transform and the distance left at every point.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Fit {
    /// The transform.
    pub transform: Transform,
    /// Per point: the distance between its image and its target.
    pub residuals: Vec<f64>,
}

impl Fit {
    /// Root mean square of the residuals.
    pub fn rms(&self) -> f64 {
        (self.residuals.iter().map(|r| r * r).sum::<f64>() / self.residuals.len().max(1) as f64)
            .sqrt()
    }
}

fn mean(p: &[[f64; 3]]) -> Vector3<f64> {
    let mut m = Vector3::zeros();
    for q in p {
        m += Vector3::from(*q);
    }
    m / p.len() as f64
}

/// The least-squares similarity (or rigid, without `scale`) transform taking `from[i]` to `to[i]`.
///
/// # Errors
/// [`FemError::Alignment`]: fewer than three pairs, lengths that differ, non-finite coordinates,
/// or `from` points (nearly) on one line, which leave a rotation about that line undetermined.
pub fn fit_pairs(from: &[[f64; 3]], to: &[[f64; 3]], scale: bool) -> Result<Fit, FemError> {
    let bad = |reason: String| FemError::Alignment { reason };
    if from.len() != to.len() {
        return Err(bad(format!(
            "{} test points against {} model points",
            from.len(),
            to.len()
        )));
    }
    if from.len() < 3 {
        return Err(bad(format!(
            "{} point pair(s) given: a rotation needs at least three",
            from.len()
        )));
    }
    if from.iter().chain(to).flatten().any(|v| !v.is_finite()) {
        return Err(bad("a point has a non-finite coordinate".into()));
    }
    let (cf, ct) = (mean(from), mean(to));
    let mut h = Matrix3::zeros();
    let mut spread = Matrix3::zeros();
    let mut var = 0.0;
    for (a, b) in from.iter().zip(to) {
        let (a, b) = (Vector3::from(*a) - cf, Vector3::from(*b) - ct);
        h += b * a.transpose();
        spread += a * a.transpose();
        var += a.norm_squared();
    }
    let n = from.len() as f64;
    h /= n;
    var /= n;
    // collinear test points: the second principal spread vanishes
    let mut s = spread.symmetric_eigenvalues().as_slice().to_vec();
    s.sort_by(|a, b| b.total_cmp(a));
    if !(s[1] > 1e-10 * s[0]) {
        return Err(bad(format!(
            "the {} test points lie on one line (or on one point): the rotation about it is undetermined; give a point off that line",
            from.len()
        )));
    }
    let svd = h.svd(true, true);
    let (u, v_t) = (svd.u.expect("U asked for"), svd.v_t.expect("V^T asked for"));
    let mut d = Matrix3::identity();
    if (u * v_t).determinant() < 0.0 {
        d[(2, 2)] = -1.0;
    }
    let r = u * d * v_t;
    let sc = if scale {
        (Matrix3::from_diagonal(&svd.singular_values) * d).trace() / var
    } else {
        1.0
    };
    let t = ct - sc * r * cf;
    let transform = Transform {
        rotation: std::array::from_fn(|i| std::array::from_fn(|k| r[(i, k)])),
        translation: [t[0], t[1], t[2]],
        scale: sc,
    };
    let residuals = from
        .iter()
        .zip(to)
        .map(|(a, b)| dist(transform.apply(*a), *b))
        .collect();
    Ok(Fit {
        transform,
        residuals,
    })
}

/// The boundary of a mesh as triangles (faces owned by one element, split through their corner
/// nodes), with a grid for nearest-point queries.
#[derive(Debug, Clone)]
pub struct Surface {
    triangles: Vec<[[f64; 3]; 3]>,
    grid: Grid,
    cell: f64,
    extent: f64,
}

impl Surface {
    /// The boundary of `mesh`. Curved faces of quadratic elements are replaced by flat triangles
    /// through their corners.
    pub fn new(mesh: &Mesh) -> Self {
        let mut faces: HashMap<Vec<usize>, (usize, Vec<usize>)> = HashMap::new();
        for el in mesh.elements() {
            for f in el.kind.faces() {
                let cycle: Vec<usize> = f.iter().map(|a| el.nodes[*a]).collect();
                let mut key = cycle.clone();
                key.sort_unstable();
                faces.entry(key).or_insert((0, cycle)).0 += 1;
            }
        }
        let c = mesh.coords();
        let mut triangles = Vec::new();
        let mut keys: Vec<&Vec<usize>> = faces.keys().collect();
        keys.sort_unstable();
        for key in keys {
            let (count, cycle) = &faces[key];
            if *count == 1 {
                for k in 1..cycle.len() - 1 {
                    triangles.push([c[cycle[0]], c[cycle[k]], c[cycle[k + 1]]]);
                }
            }
        }
        let boxes: Vec<([f64; 3], [f64; 3])> = triangles
            .iter()
            .map(|t| {
                (
                    std::array::from_fn(|i| t[0][i].min(t[1][i]).min(t[2][i])),
                    std::array::from_fn(|i| t[0][i].max(t[1][i]).max(t[2][i])),
                )
            })
            .collect();
        let typical =
            boxes.iter().map(|(a, b)| dist(*a, *b)).sum::<f64>() / boxes.len().max(1) as f64;
        let extent = boxes.iter().fold(0.0f64, |m, (a, b)| {
            m.max(dist(*a, boxes[0].0)).max(dist(*b, boxes[0].0))
        });
        Self {
            grid: Grid::new(&boxes, typical),
            triangles,
            cell: typical.max(f64::MIN_POSITIVE),
            extent,
        }
    }

    /// Number of boundary triangles.
    pub fn len(&self) -> usize {
        self.triangles.len()
    }

    /// Whether the mesh has no boundary.
    pub fn is_empty(&self) -> bool {
        self.triangles.is_empty()
    }

    /// The nearest point of the boundary to `p`, and its distance.
    pub fn nearest(&self, p: [f64; 3]) -> Option<([f64; 3], f64)> {
        self.nearest_with_normal(p).map(|(q, d, _)| (q, d))
    }

    /// [`Surface::nearest`] with the unit normal of the triangle it lies on.
    fn nearest_with_normal(&self, p: [f64; 3]) -> Option<([f64; 3], f64, [f64; 3])> {
        if self.triangles.is_empty() {
            return None;
        }
        let mut radius = self.cell;
        loop {
            let mut best: Option<([f64; 3], f64, usize)> = None;
            self.grid.visit(p, radius, |t| {
                let q = closest_on_triangle(p, &self.triangles[t]);
                let d = dist(p, q);
                if best.is_none_or(|b| d < b.1) {
                    best = Some((q, d, t));
                }
            });
            match best {
                Some(b) if b.1 <= radius => {
                    return Some((b.0, b.1, normal(&self.triangles[b.2])));
                }
                _ if radius > 4.0 * (self.extent + dist(p, self.triangles[0][0])) => {
                    return best.map(|b| (b.0, b.1, normal(&self.triangles[b.2])));
                }
                _ => radius *= 2.0,
            }
        }
    }
}

/// The unit normal of a triangle (zero for a degenerate one).
fn normal(t: &[[f64; 3]; 3]) -> [f64; 3] {
    let a: [f64; 3] = std::array::from_fn(|i| t[1][i] - t[0][i]);
    let b: [f64; 3] = std::array::from_fn(|i| t[2][i] - t[0][i]);
    let n = [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ];
    let l = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
    if l > 0.0 { n.map(|v| v / l) } else { n }
}

/// The closest point of triangle `t` to `p` (Ericson, Real-Time Collision Detection, 5.1.5).
fn closest_on_triangle(p: [f64; 3], t: &[[f64; 3]; 3]) -> [f64; 3] {
    let sub = |a: [f64; 3], b: [f64; 3]| -> [f64; 3] { std::array::from_fn(|i| a[i] - b[i]) };
    let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    let along =
        |a: [f64; 3], d: [f64; 3], s: f64| -> [f64; 3] { std::array::from_fn(|i| a[i] + s * d[i]) };
    let [a, b, c] = *t;
    let (ab, ac, ap) = (sub(b, a), sub(c, a), sub(p, a));
    let (d1, d2) = (dot(ab, ap), dot(ac, ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return a;
    }
    let bp = sub(p, b);
    let (d3, d4) = (dot(ab, bp), dot(ac, bp));
    if d3 >= 0.0 && d4 <= d3 {
        return b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return along(a, ab, d1 / (d1 - d3));
    }
    let cp = sub(p, c);
    let (d5, d6) = (dot(ab, cp), dot(ac, cp));
    if d6 >= 0.0 && d5 <= d6 {
        return c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return along(a, ac, d2 / (d2 - d6));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        return along(b, sub(c, b), (d4 - d3) / ((d4 - d3) + (d5 - d6)));
    }
    let denom = 1.0 / (va + vb + vc);
    let (v, w) = (vb * denom, vc * denom);
    std::array::from_fn(|i| a[i] + ab[i] * v + ac[i] * w)
}

/// Refines `start` by iterative closest points onto `surface`, in the Gauss-Newton form on the
/// distances ("point to plane"): each round linearises `d_i = |T p_i - q_i|` about the current
/// transform (direction `n_i` from the nearest point `q_i`, or the face normal where the point
/// lies on the face), solves the 6 x 6 (7 x 7 with `scale`) normal equations for a small rotation,
/// translation (and scale) and takes the step if the root mean square distance falls (halving it
/// otherwise); at most 200 rounds, until the step is below 1e-13 of the wireframe's size. With
/// `scale`, the distances are measured in the wireframe's own units (divided by the scale): in
/// the model's units, shrinking the wireframe onto one point of the surface drives every distance
/// to zero, and the fit collapsed to a scale of 0; in the wireframe's units such a collapse leaves
/// the distances at the wireframe's own spread and is no better than where it started.
///
/// # Errors
/// Fewer than three points, a mesh without boundary.
pub fn fit_surface(
    points: &[[f64; 3]],
    surface: &Surface,
    start: Transform,
    scale: bool,
) -> Result<Fit, FemError> {
    // the scale is freed from the rigid fit: from a far start, shrinking the wireframe into the
    // body finds minima of its own before the rotation and translation are found
    if scale {
        let rigid = refine(points, surface, start, false)?;
        return refine(points, surface, rigid.transform, true);
    }
    refine(points, surface, start, false)
}

/// [`fit_surface`]'s iterations, with the scale fitted or held.
fn refine(
    points: &[[f64; 3]],
    surface: &Surface,
    start: Transform,
    scale: bool,
) -> Result<Fit, FemError> {
    if surface.is_empty() {
        return Err(FemError::Alignment {
            reason: "the model has no boundary faces to align onto".into(),
        });
    }
    if points.len() < 3 {
        return Err(FemError::Alignment {
            reason: format!(
                "{} test point(s): aligning onto the surface needs at least three",
                points.len()
            ),
        });
    }
    let size = points
        .iter()
        .map(|p| dist(*p, points[0]))
        .fold(0.0f64, f64::max)
        .max(f64::MIN_POSITIVE);
    let evaluate = |tr: &Transform| -> Vec<([f64; 3], [f64; 3], f64)> {
        points
            .iter()
            .map(|p| {
                let y = tr.apply(*p);
                let (q, d, normal) = surface.nearest_with_normal(y).expect("a non-empty surface");
                let n = if d > 1e-12 * size {
                    std::array::from_fn(|i| (y[i] - q[i]) / d)
                } else {
                    normal
                };
                (y, n, d)
            })
            .collect()
    };
    // root mean square distance in the wireframe's units (the model's for a rigid fit)
    let rms = |e: &[([f64; 3], [f64; 3], f64)], s: f64| {
        (e.iter().map(|v| v.2 * v.2).sum::<f64>() / e.len() as f64).sqrt() / s
    };
    let unit = |t: &Transform| if scale { t.scale.abs() } else { 1.0 };
    let np = if scale { 7 } else { 6 };
    let mut transform = start;
    let mut state = evaluate(&transform);
    let mut current = rms(&state, unit(&transform));
    for _ in 0..200 {
        // signed distances along n: r_i = (y_i - q_i) . n_i = d_i, divided by the scale `s` when
        // it is fitted: with y = s R x + t and s' = s (1 + delta), d(d_i / s)/d delta =
        // (c . n - d_i) / s, c = y - t
        let s = unit(&transform);
        let mut jtj = nalgebra::DMatrix::<f64>::zeros(np, np);
        let mut jtr = nalgebra::DVector::<f64>::zeros(np);
        for (y, n, d) in &state {
            let c: [f64; 3] = std::array::from_fn(|i| y[i] - transform.translation[i]);
            let cxn = [
                c[1] * n[2] - c[2] * n[1],
                c[2] * n[0] - c[0] * n[2],
                c[0] * n[1] - c[1] * n[0],
            ];
            let mut row = vec![
                cxn[0] / s,
                cxn[1] / s,
                cxn[2] / s,
                n[0] / s,
                n[1] / s,
                n[2] / s,
            ];
            if scale {
                row.push((c[0] * n[0] + c[1] * n[1] + c[2] * n[2] - d) / s);
            }
            let r = d / s;
            for a in 0..np {
                jtr[a] += row[a] * r;
                for b in 0..np {
                    jtj[(a, b)] += row[a] * row[b];
                }
            }
        }
        // a little damping keeps directions the points do not determine (sliding along a flat
        // face) from moving
        let trace = jtj.trace().max(f64::MIN_POSITIVE);
        for a in 0..np {
            jtj[(a, a)] += 1e-12 * trace;
        }
        let Some(step) = jtj.cholesky().map(|c| -c.solve(&jtr)) else {
            break;
        };
        let mut t = 1.0;
        let mut accepted = false;
        for _ in 0..30 {
            let omega = [t * step[0], t * step[1], t * step[2]];
            let angle = (omega[0] * omega[0] + omega[1] * omega[1] + omega[2] * omega[2]).sqrt();
            let r = if angle > 0.0 {
                Matrix3::from(nalgebra::Rotation3::new(Vector3::from(omega)))
            } else {
                Matrix3::identity()
            };
            let old = Matrix3::from_fn(|i, k| transform.rotation[i][k]);
            let rr = r * old;
            let trial = Transform {
                rotation: std::array::from_fn(|i| std::array::from_fn(|k| rr[(i, k)])),
                translation: std::array::from_fn(|i| transform.translation[i] + t * step[3 + i]),
                scale: if scale {
                    transform.scale * (1.0 + t * step[6])
                } else {
                    transform.scale
                },
            };
            // a scale through zero would mirror the wireframe: halve the step instead
            if trial.scale <= 0.0 {
                t *= 0.5;
                continue;
            }
            let next_state = evaluate(&trial);
            let next = rms(&next_state, unit(&trial));
            if next < current || next == 0.0 {
                let moved = angle * size
                    + t * (step[3] * step[3] + step[4] * step[4] + step[5] * step[5]).sqrt()
                    + if scale { t * step[6].abs() * size } else { 0.0 };
                transform = trial;
                state = next_state;
                accepted = moved > 1e-13 * size && next < current * (1.0 - 1e-14);
                current = next;
                break;
            }
            t *= 0.5;
        }
        if !accepted {
            break;
        }
    }
    Ok(Fit {
        transform,
        residuals: state.iter().map(|s| s.2).collect(),
    })
}

/// Aligns `points` onto the boundary of the model without pairs: iterative closest points from
/// the identity and from the 24 proper rotations that put the points' principal axes on the
/// boundary's principal axes in any order and sense (centroids matched); the start with the
/// least final distance wins. A structure with a symmetry has as many equally good alignments:
/// give pairs for it.
///
/// # Errors
/// As [`fit_surface`].
pub fn fit_auto(points: &[[f64; 3]], surface: &Surface, scale: bool) -> Result<Fit, FemError> {
    let spread = |p: &[[f64; 3]]| -> f64 {
        let c = mean(p);
        (p.iter()
            .map(|q| (Vector3::from(*q) - c).norm_squared())
            .sum::<f64>()
            / p.len().max(1) as f64)
            .sqrt()
    };
    let axes = |p: &[[f64; 3]]| -> (Vector3<f64>, Matrix3<f64>) {
        let c = mean(p);
        let mut cov = Matrix3::zeros();
        for q in p {
            let d = Vector3::from(*q) - c;
            cov += d * d.transpose();
        }
        let e = cov.symmetric_eigen();
        let mut order: Vec<usize> = (0..3).collect();
        order.sort_by(|a, b| e.eigenvalues[*b].total_cmp(&e.eigenvalues[*a]));
        let v = Matrix3::from_columns(&[
            e.eigenvectors.column(order[0]).into_owned(),
            e.eigenvectors.column(order[1]).into_owned(),
            e.eigenvectors.column(order[2]).into_owned(),
        ]);
        (c, v)
    };
    let corners: Vec<[f64; 3]> = surface
        .triangles
        .iter()
        .flat_map(|t| t.iter().copied())
        .collect();
    let mut starts = vec![Transform::IDENTITY];
    if points.len() >= 3 && !corners.is_empty() {
        let (cp, vp) = axes(points);
        let (cm, vm) = axes(&corners);
        // the 24 rotations that take axes to axes (the principal axes of a sample of points and
        // of the whole boundary need not come in the same order)
        let perms = [
            [0, 1, 2],
            [0, 2, 1],
            [1, 0, 2],
            [1, 2, 0],
            [2, 0, 1],
            [2, 1, 0],
        ];
        let signs = [
            [1.0, 1.0, 1.0],
            [1.0, -1.0, -1.0],
            [-1.0, 1.0, -1.0],
            [-1.0, -1.0, 1.0],
            [-1.0, -1.0, -1.0],
            [-1.0, 1.0, 1.0],
            [1.0, -1.0, 1.0],
            [1.0, 1.0, -1.0],
        ];
        let mut group = Vec::new();
        for p in perms {
            for s in signs {
                let g = Matrix3::from_fn(|i, k| if p[i] == k { s[i] } else { 0.0 });
                if g.determinant() * vm.determinant() * vp.determinant() > 0.0 {
                    group.push(g);
                }
            }
        }
        // with a fitted scale, the starts bring the wireframe to the size of the boundary (the
        // ratio of their spreads about their centroids): a wireframe in millimetres read as
        // metres starts near 1/1000, not 1000 times too large
        let s0 = if scale {
            let (a, b) = (spread(&corners), spread(points));
            if a > 0.0 && b > 0.0 { a / b } else { 1.0 }
        } else {
            1.0
        };
        if s0 != 1.0 {
            // the identity start too: the test's axes, at the boundary's size and centroid
            let t = cm - s0 * cp;
            starts[0] = Transform {
                translation: [t[0], t[1], t[2]],
                scale: s0,
                ..Transform::IDENTITY
            };
        }
        for g in group {
            let r = vm * g * vp.transpose();
            let t = cm - s0 * (r * cp);
            starts.push(Transform {
                rotation: std::array::from_fn(|i| std::array::from_fn(|k| r[(i, k)])),
                translation: [t[0], t[1], t[2]],
                scale: s0,
            });
        }
    }
    let mut best: Option<Fit> = None;
    for start in starts {
        let fit = fit_surface(points, surface, start, scale)?;
        // compared in the wireframe's units, as fit_surface minimises them
        let measure = |f: &Fit| f.rms() / f.transform.scale.abs().max(f64::MIN_POSITIVE);
        if best.as_ref().is_none_or(|b| measure(&fit) < measure(b)) {
            best = Some(fit);
        }
    }
    Ok(best.expect("at least the identity start"))
}
