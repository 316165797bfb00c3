//! Points in a mesh: the inverse isoparametric map and a search structure for elements and nodes.
//!
//! A test sensor glued between FE nodes reads the model displacement at its point `p`:
//! `u(p) = sum_a N_a(xi) u_a`, where `xi` are the local coordinates of `p` in the element that
//! holds it (`x(xi) = sum_a N_a(xi) x_a = p`). [`inverse_map`] finds `xi` by Newton's method on
//! that equation; [`Locator`] finds the element by a uniform grid over element bounding boxes
//! (a few candidates per point, not a scan of the mesh), and the closest point of the mesh when `p`
//! lies just outside it (a sensor on the surface, a wireframe a little off): the local
//! coordinates are then those of the nearest point of the element's reference cell, found by
//! projected Gauss-Newton, and the distance is reported (docs/MATH.md, "Mapping test nodes").

use crate::element::ElementKind;
use crate::mesh::Mesh;

/// The result of [`inverse_map`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct InverseMap {
    /// Local coordinates of the point (or of the nearest point of the reference cell).
    pub xi: [f64; 3],
    /// Distance from the point to `x(xi)`, in the mesh's length unit (0 up to round-off inside).
    pub distance: f64,
    /// Whether `xi` lies in the reference cell (within `INSIDE_TOL`).
    pub inside: bool,
}

/// Reference-coordinate slack for "inside" (a point on a face belongs to both elements).
pub const INSIDE_TOL: f64 = 1e-9;

/// Projects `xi` onto the reference cell of `kind` (Euclidean in reference coordinates).
pub fn clamp_to_reference(kind: ElementKind, xi: [f64; 3]) -> [f64; 3] {
    match kind {
        ElementKind::Hex8 | ElementKind::Hex20 => xi.map(|v| v.clamp(-1.0, 1.0)),
        ElementKind::Tet4 | ElementKind::Tet10 => {
            let p = project_simplex(&[xi[0], xi[1], xi[2]]);
            [p[0], p[1], p[2]]
        }
        ElementKind::Penta6 | ElementKind::Penta15 => {
            let p = project_simplex(&[xi[0], xi[1]]);
            [p[0], p[1], xi[2].clamp(-1.0, 1.0)]
        }
        ElementKind::Pyramid5 | ElementKind::Pyramid13 => project_pyramid(xi),
    }
}

/// Euclidean projection onto the reference pyramid `{0 <= zeta, |xi| <= 1 - zeta,
/// |eta| <= 1 - zeta}` by Dykstra's alternating projections onto its five half-spaces.
fn project_pyramid(p: [f64; 3]) -> [f64; 3] {
    // half-spaces n . x <= h
    const H: [([f64; 3], f64); 5] = [
        ([0.0, 0.0, -1.0], 0.0),
        ([1.0, 0.0, 1.0], 1.0),
        ([-1.0, 0.0, 1.0], 1.0),
        ([0.0, 1.0, 1.0], 1.0),
        ([0.0, -1.0, 1.0], 1.0),
    ];
    let inside = |x: &[f64; 3]| {
        H.iter()
            .all(|(n, h)| n[0] * x[0] + n[1] * x[1] + n[2] * x[2] <= h + 1e-15)
    };
    if inside(&p) {
        return p;
    }
    let mut x = p;
    let mut corr = [[0.0; 3]; 5];
    for _ in 0..500 {
        let prev = x;
        for (k, (n, h)) in H.iter().enumerate() {
            let y: [f64; 3] = std::array::from_fn(|i| x[i] + corr[k][i]);
            let v = n[0] * y[0] + n[1] * y[1] + n[2] * y[2] - h;
            let nn = n[0] * n[0] + n[1] * n[1] + n[2] * n[2];
            let z: [f64; 3] = if v > 0.0 {
                std::array::from_fn(|i| y[i] - v / nn * n[i])
            } else {
                y
            };
            corr[k] = std::array::from_fn(|i| y[i] - z[i]);
            x = z;
        }
        let step = (0..3).map(|i| (x[i] - prev[i]).abs()).fold(0.0, f64::max);
        if step < 1e-16 {
            break;
        }
    }
    x
}

/// Euclidean projection onto `{x >= 0, sum x <= 1}`.
fn project_simplex(x: &[f64]) -> Vec<f64> {
    let pos: Vec<f64> = x.iter().map(|v| v.max(0.0)).collect();
    if pos.iter().sum::<f64>() <= 1.0 {
        return pos;
    }
    // onto {x >= 0, sum x = 1}: subtract the threshold theta (sort-based algorithm)
    let mut u = x.to_vec();
    u.sort_by(|a, b| b.total_cmp(a));
    let mut cum = 0.0;
    let mut theta = 0.0;
    for (j, v) in u.iter().enumerate() {
        cum += v;
        let t = (cum - 1.0) / (j + 1) as f64;
        if v - t > 0.0 {
            theta = t;
        }
    }
    x.iter().map(|v| (v - theta).max(0.0)).collect()
}

/// Whether `xi` lies in the reference cell of `kind`, within `tol`.
pub fn in_reference(kind: ElementKind, xi: [f64; 3], tol: f64) -> bool {
    match kind {
        ElementKind::Hex8 | ElementKind::Hex20 => xi.iter().all(|v| v.abs() <= 1.0 + tol),
        ElementKind::Tet4 | ElementKind::Tet10 => {
            xi.iter().all(|v| *v >= -tol) && xi[0] + xi[1] + xi[2] <= 1.0 + tol
        }
        ElementKind::Penta6 | ElementKind::Penta15 => {
            xi[0] >= -tol && xi[1] >= -tol && xi[0] + xi[1] <= 1.0 + tol && xi[2].abs() <= 1.0 + tol
        }
        ElementKind::Pyramid5 | ElementKind::Pyramid13 => {
            xi[2] >= -tol && xi[0].abs() + xi[2] <= 1.0 + tol && xi[1].abs() + xi[2] <= 1.0 + tol
        }
    }
}

fn centroid(kind: ElementKind) -> [f64; 3] {
    match kind {
        ElementKind::Hex8 | ElementKind::Hex20 => [0.0; 3],
        ElementKind::Tet4 | ElementKind::Tet10 => [0.25; 3],
        ElementKind::Penta6 | ElementKind::Penta15 => [1.0 / 3.0, 1.0 / 3.0, 0.0],
        ElementKind::Pyramid5 | ElementKind::Pyramid13 => [0.0, 0.0, 0.25],
    }
}

/// `x(xi)` and the Jacobian `J[i][k] = dx_i / dxi_k`.
fn map_point(kind: ElementKind, coords: &[[f64; 3]], xi: [f64; 3]) -> ([f64; 3], [[f64; 3]; 3]) {
    let nn = kind.num_nodes();
    let mut n = [0.0; 20];
    let mut dn = [0.0; 60];
    kind.shape(xi, &mut n[..nn]);
    kind.shape_gradients(xi, &mut dn[..3 * nn]);
    let mut x = [0.0; 3];
    let mut j = [[0.0; 3]; 3];
    for a in 0..nn {
        for i in 0..3 {
            x[i] += n[a] * coords[a][i];
            for k in 0..3 {
                j[i][k] += dn[3 * a + k] * coords[a][i];
            }
        }
    }
    (x, j)
}

/// Solves `A d = b` for a 3x3 `A` (Cramer); `None` when singular.
fn solve3(a: [[f64; 3]; 3], b: [f64; 3]) -> Option<[f64; 3]> {
    let det = a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1])
        - a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0])
        + a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0]);
    let scale = a.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
    if !(det.is_finite() && det.abs() > 1e-14 * scale.powi(3)) {
        return None;
    }
    let mut out = [0.0; 3];
    for (c, o) in out.iter_mut().enumerate() {
        let mut m = a;
        for r in 0..3 {
            m[r][c] = b[r];
        }
        *o = (m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
            - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]))
            / det;
    }
    Some(out)
}

pub(crate) fn dist(a: [f64; 3], b: [f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

/// Local coordinates of `p` in the element of `kind` with node coordinates `coords`.
///
/// Newton's method on `x(xi) = p` from the reference centroid (quadratic convergence on
/// undistorted and moderately distorted elements; at most 30 steps); if the solution lies outside
/// the reference cell, or Newton fails, projected Gauss-Newton steps give the nearest point of the
/// element instead, with its distance.
pub fn inverse_map(kind: ElementKind, coords: &[[f64; 3]], p: [f64; 3]) -> InverseMap {
    let (xi, converged) = newton(kind, coords, p);
    if converged && in_reference(kind, xi, INSIDE_TOL) {
        let (x, _) = map_point(kind, coords, xi);
        return InverseMap {
            xi,
            distance: dist(x, p),
            inside: true,
        };
    }
    nearest_in_cell(kind, coords, p, xi)
}

/// The local coordinates of `p` when it lies in the element (Newton only; `None` outside).
pub fn inverse_map_inside(kind: ElementKind, coords: &[[f64; 3]], p: [f64; 3]) -> Option<[f64; 3]> {
    let (xi, converged) = newton(kind, coords, p);
    (converged && in_reference(kind, xi, INSIDE_TOL)).then_some(xi)
}

/// Newton's method on `x(xi) = p` from the reference centroid: the last iterate and whether it
/// converged.
fn newton(kind: ElementKind, coords: &[[f64; 3]], p: [f64; 3]) -> ([f64; 3], bool) {
    let size = coords
        .iter()
        .map(|c| dist(*c, coords[0]))
        .fold(0.0f64, f64::max)
        .max(f64::MIN_POSITIVE);
    let mut xi = centroid(kind);
    let mut converged = false;
    for _ in 0..30 {
        let (x, j) = map_point(kind, coords, xi);
        let r = [p[0] - x[0], p[1] - x[1], p[2] - x[2]];
        if dist(x, p) <= 1e-13 * size {
            converged = true;
            break;
        }
        let Some(d) = solve3(j, r) else { break };
        xi = [xi[0] + d[0], xi[1] + d[1], xi[2] + d[2]];
        if xi.iter().any(|v| !v.is_finite() || v.abs() > 1e3) {
            break;
        }
        if d.iter().map(|v| v.abs()).fold(0.0, f64::max) < 1e-14 {
            converged = true;
            break;
        }
    }
    (xi, converged)
}

/// The nearest point of the element to `p` (projected Gauss-Newton from `start`, clamped).
fn nearest_in_cell(
    kind: ElementKind,
    coords: &[[f64; 3]],
    p: [f64; 3],
    start: [f64; 3],
) -> InverseMap {
    let size = coords
        .iter()
        .map(|c| dist(*c, coords[0]))
        .fold(0.0f64, f64::max)
        .max(f64::MIN_POSITIVE);
    let xi = start;
    let mut xi = if xi.iter().all(|v| v.is_finite()) {
        clamp_to_reference(kind, xi)
    } else {
        centroid(kind)
    };
    let mut best = (f64::INFINITY, xi);
    for _ in 0..200 {
        let (x, j) = map_point(kind, coords, xi);
        let d0 = dist(x, p);
        if d0 < best.0 {
            best = (d0, xi);
        }
        let r = [p[0] - x[0], p[1] - x[1], p[2] - x[2]];
        // normal equations J^T J d = J^T r
        let mut jtj = [[0.0; 3]; 3];
        let mut jtr = [0.0; 3];
        for a in 0..3 {
            for b in 0..3 {
                jtj[a][b] = (0..3).map(|i| j[i][a] * j[i][b]).sum();
            }
            jtr[a] = (0..3).map(|i| j[i][a] * r[i]).sum();
        }
        // the Gauss-Newton step, and the gradient step (exact line search of the linearised
        // problem) where the projected Gauss-Newton step stalls on the cell's boundary
        let jg: [f64; 3] = std::array::from_fn(|i| (0..3).map(|k| j[i][k] * jtr[k]).sum());
        let g2: f64 = jtr.iter().map(|v| v * v).sum();
        let jg2: f64 = jg.iter().map(|v| v * v).sum();
        let gradient = (jg2 > 0.0).then(|| jtr.map(|v| v * g2 / jg2));
        let mut moved = false;
        for d in [solve3(jtj, jtr), gradient].into_iter().flatten() {
            let mut t = 1.0;
            for _ in 0..30 {
                let trial = clamp_to_reference(
                    kind,
                    [xi[0] + t * d[0], xi[1] + t * d[1], xi[2] + t * d[2]],
                );
                let (xt, _) = map_point(kind, coords, trial);
                if dist(xt, p) < d0 * (1.0 - 1e-13) {
                    moved = dist(trial, xi) > 1e-14;
                    xi = trial;
                    break;
                }
                t *= 0.5;
            }
            if moved {
                break;
            }
        }
        if !moved {
            break;
        }
    }
    let (x, _) = map_point(kind, coords, best.1);
    let distance = dist(x, p);
    InverseMap {
        xi: best.1,
        distance,
        inside: distance <= 1e-10 * size,
    }
}

/// A point located in a mesh: the element, its local coordinates and the interpolation weights.
#[derive(Debug, Clone, PartialEq)]
pub struct Location {
    /// Internal element index.
    pub element: usize,
    /// Local coordinates in that element.
    pub xi: [f64; 3],
    /// Distance from the point to the mesh (0 inside).
    pub distance: f64,
    /// `(internal node index, N_a(xi))` for every node of the element: `u(p) = sum w_a u_a`.
    pub weights: Vec<(usize, f64)>,
}

/// A uniform grid of cells, each listing the items whose boxes overlap it (compressed rows).
#[derive(Debug, Clone)]
pub(crate) struct Grid {
    lo: [f64; 3],
    pub(crate) cell: f64,
    dims: [usize; 3],
    start: Vec<u32>,
    items: Vec<u32>,
}

impl Grid {
    pub(crate) fn new(boxes: &[([f64; 3], [f64; 3])], typical: f64) -> Self {
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for (a, b) in boxes {
            for i in 0..3 {
                lo[i] = lo[i].min(a[i]);
                hi[i] = hi[i].max(b[i]);
            }
        }
        if boxes.is_empty() {
            lo = [0.0; 3];
            hi = [0.0; 3];
        }
        let extent = (0..3).map(|i| hi[i] - lo[i]).fold(0.0f64, f64::max);
        // about one item per cell, at most 2^21 cells per axis product
        let mut cell = typical.max(extent * 1e-6).max(f64::MIN_POSITIVE);
        let dims_for =
            |c: f64| std::array::from_fn(|i| (((hi[i] - lo[i]) / c).floor() as usize + 1).max(1));
        let mut dims: [usize; 3] = dims_for(cell);
        while dims.iter().product::<usize>() > 4 * boxes.len().max(1) + 64 {
            cell *= 1.5;
            dims = dims_for(cell);
        }
        let index = |x: f64, i: usize| -> usize {
            (((x - lo[i]) / cell).floor().max(0.0) as usize).min(dims[i] - 1)
        };
        let ncell = dims.iter().product::<usize>();
        let mut count = vec![0u32; ncell + 1];
        let range = |a: &[f64; 3], b: &[f64; 3]| -> [(usize, usize); 3] {
            std::array::from_fn(|i| (index(a[i], i), index(b[i], i)))
        };
        let cell_id = |x: usize, y: usize, z: usize| (z * dims[1] + y) * dims[0] + x;
        for (a, b) in boxes {
            let r = range(a, b);
            for z in r[2].0..=r[2].1 {
                for y in r[1].0..=r[1].1 {
                    for x in r[0].0..=r[0].1 {
                        count[cell_id(x, y, z) + 1] += 1;
                    }
                }
            }
        }
        for c in 0..ncell {
            count[c + 1] += count[c];
        }
        let mut fill = count.clone();
        let mut items = vec![0u32; count[ncell] as usize];
        for (e, (a, b)) in boxes.iter().enumerate() {
            let r = range(a, b);
            for z in r[2].0..=r[2].1 {
                for y in r[1].0..=r[1].1 {
                    for x in r[0].0..=r[0].1 {
                        let c = cell_id(x, y, z);
                        items[fill[c] as usize] = e as u32;
                        fill[c] += 1;
                    }
                }
            }
        }
        Self {
            lo,
            cell,
            dims,
            start: count,
            items,
        }
    }

    /// Items of the cells overlapping the box `[p - r, p + r]` (with repetitions).
    pub(crate) fn visit(&self, p: [f64; 3], r: f64, mut f: impl FnMut(usize)) {
        let mut range = [(0usize, 0usize); 3];
        for i in 0..3 {
            let a = ((p[i] - r - self.lo[i]) / self.cell).floor();
            let b = ((p[i] + r - self.lo[i]) / self.cell).floor();
            if b < 0.0 || a > (self.dims[i] - 1) as f64 {
                return;
            }
            range[i] = (a.max(0.0) as usize, (b as usize).min(self.dims[i] - 1));
        }
        for z in range[2].0..=range[2].1 {
            for y in range[1].0..=range[1].1 {
                for x in range[0].0..=range[0].1 {
                    let c = (z * self.dims[1] + y) * self.dims[0] + x;
                    for &e in &self.items[self.start[c] as usize..self.start[c + 1] as usize] {
                        f(e as usize);
                    }
                }
            }
        }
    }
}

/// Finds the elements and nodes near points of space, for a mesh that does not change.
#[derive(Debug, Clone)]
pub struct Locator {
    boxes: Vec<([f64; 3], [f64; 3])>,
    elements: Grid,
    nodes: Grid,
}

impl Locator {
    /// Builds the grids (element bounding boxes, node points) of `mesh`: `O(elements)`.
    pub fn new(mesh: &Mesh) -> Self {
        let mut coords = Vec::new();
        let mut boxes = Vec::with_capacity(mesh.element_count());
        let mut total = 0.0;
        for e in 0..mesh.element_count() {
            mesh.element_coords(e, &mut coords);
            let mut lo = [f64::INFINITY; 3];
            let mut hi = [f64::NEG_INFINITY; 3];
            for c in &coords {
                for i in 0..3 {
                    lo[i] = lo[i].min(c[i]);
                    hi[i] = hi[i].max(c[i]);
                }
            }
            total += (0..3).map(|i| hi[i] - lo[i]).fold(0.0f64, f64::max);
            boxes.push((lo, hi));
        }
        let typical = total / boxes.len().max(1) as f64;
        let elements = Grid::new(&boxes, typical);
        let points: Vec<([f64; 3], [f64; 3])> = mesh.coords().iter().map(|c| (*c, *c)).collect();
        let nodes = Grid::new(&points, typical);
        Self {
            boxes,
            elements,
            nodes,
        }
    }

    /// The element holding `p`, or the nearest element within `tolerance` of it (`None` when the
    /// mesh is farther). Among elements holding `p` (a point on a shared face or node), the lowest
    /// index.
    pub fn locate(&self, mesh: &Mesh, p: [f64; 3], tolerance: f64) -> Option<Location> {
        let mut candidates = Vec::new();
        self.elements.visit(p, tolerance, |e| candidates.push(e));
        candidates.sort_unstable();
        candidates.dedup();
        let mut coords = Vec::new();
        candidates.retain(|&e| {
            let (lo, hi) = self.boxes[e];
            (0..3).all(|i| p[i] >= lo[i] - tolerance && p[i] <= hi[i] + tolerance)
        });
        // first the elements whose box holds p, by Newton alone: most points are inside one
        for &e in &candidates {
            let (lo, hi) = self.boxes[e];
            if (0..3).any(|i| p[i] < lo[i] || p[i] > hi[i]) {
                continue;
            }
            mesh.element_coords(e, &mut coords);
            let kind = mesh.element(e).kind;
            if let Some(xi) = inverse_map_inside(kind, &coords, p) {
                let mut n = vec![0.0; kind.num_nodes()];
                kind.shape(xi, &mut n);
                return Some(Location {
                    element: e,
                    xi,
                    distance: 0.0,
                    weights: mesh.element(e).nodes.iter().copied().zip(n).collect(),
                });
            }
        }
        // outside every element: the nearest point within the tolerance
        let mut best: Option<(usize, InverseMap)> = None;
        for e in candidates {
            mesh.element_coords(e, &mut coords);
            let map = inverse_map(mesh.element(e).kind, &coords, p);
            let better = match &best {
                None => true,
                Some((_, b)) => map.distance < b.distance && !b.inside,
            };
            if better && map.distance <= tolerance.max(0.0) + 1e-12 * (1.0 + tolerance) {
                best = Some((e, map));
            }
            if best.as_ref().is_some_and(|(_, b)| b.inside) {
                break;
            }
        }
        let (element, map) = best?;
        let el = mesh.element(element);
        let mut n = vec![0.0; el.kind.num_nodes()];
        el.kind.shape(map.xi, &mut n);
        Some(Location {
            element,
            xi: map.xi,
            distance: if map.inside { 0.0 } else { map.distance },
            weights: el.nodes.iter().copied().zip(n).collect(),
        })
    }

    /// The node nearest `p` within `tolerance` (internal index and distance); `None` when every
    /// node is farther. Ties go to the lowest index.
    pub fn nearest_node(&self, mesh: &Mesh, p: [f64; 3], tolerance: f64) -> Option<(usize, f64)> {
        // rings of growing radius: a node found within the radius is the nearest
        let mut radius = self.nodes.cell.min(tolerance);
        loop {
            let mut best: Option<(usize, f64)> = None;
            self.nodes.visit(p, radius, |i| {
                let d = dist(mesh.coords()[i], p);
                if d <= radius && best.is_none_or(|(b, bd)| d < bd || (d == bd && i < b)) {
                    best = Some((i, d));
                }
            });
            if best.is_some() || radius >= tolerance {
                return best;
            }
            radius = (2.0 * radius).min(tolerance);
            if radius.is_infinite() {
                // no node within any finite ring of the grid's extent: scan
                return (0..mesh.node_count())
                    .map(|i| (i, dist(mesh.coords()[i], p)))
                    .min_by(|a, b| a.1.total_cmp(&b.1).then(a.0.cmp(&b.0)));
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::element::ALL_KINDS;

    #[test]
    fn simplex_projection_is_the_nearest_point() {
        // (1, 1, 1) -> (1/3, 1/3, 1/3); (-1, 0.5, 0.2) -> (0, 0.5, 0.2); (2, -1, 0) -> (1, 0, 0)
        let p = project_simplex(&[1.0, 1.0, 1.0]);
        assert!(p.iter().all(|v| (v - 1.0 / 3.0).abs() < 1e-15));
        assert_eq!(project_simplex(&[-1.0, 0.5, 0.2]), vec![0.0, 0.5, 0.2]);
        assert_eq!(project_simplex(&[2.0, -1.0, 0.0]), vec![1.0, 0.0, 0.0]);
    }

    #[test]
    fn reference_nodes_map_to_themselves() {
        for kind in ALL_KINDS {
            let nodes = kind.reference_nodes();
            for (a, x) in nodes.iter().enumerate() {
                let m = inverse_map(kind, &nodes, *x);
                assert!(m.inside, "{kind} node {a}");
                for k in 0..3 {
                    assert!(
                        (m.xi[k] - x[k]).abs() < 1e-12,
                        "{kind} node {a}: {:?}",
                        m.xi
                    );
                }
            }
        }
    }
}
