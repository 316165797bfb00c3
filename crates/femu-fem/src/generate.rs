//! Mesh generators: boxes of any element kind and the mixed plate of the paper's study.
//!
//! Every generated mesh is conforming ([`Mesh::check_conformity`]): tetrahedra use the Kuhn
//! (six-tet) split, or the five-tet split with alternating orientation, both of which match across
//! cells; wedges split each hexahedron along a face diagonal chosen to match the Kuhn
//! triangulation, so wedges, tetrahedra and hexahedra can meet in one mesh.
//!
//! Node sets: `xmin`, `xmax`, `ymin`, `ymax`, `zmin`, `zmax` (the box faces) and `all`. Element
//! sets: `all`, and for the plate `hex`, `penta`, `tet`. Node and element ids start at 1.

use crate::FemError;
use crate::element::ElementKind;
use crate::mesh::Mesh;
use serde::{Deserialize, Serialize};
use std::collections::HashMap;

/// How a box is meshed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum BoxCells {
    /// One hexahedron per cell (hex8 or hex20 by `quadratic`).
    Hex,
    /// Two wedges per cell, triangles normal to z.
    Wedge,
    /// Five tetrahedra per cell, alternating orientation between neighbours.
    Tet5,
    /// Six tetrahedra per cell (Kuhn split along the cell's main diagonal).
    Tet6,
}

/// A box `[0, lx] x [0, ly] x [0, lz]` (m) divided into `nx x ny x nz` cells.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BoxSpec {
    /// Edge lengths in m.
    pub lengths: [f64; 3],
    /// Cells along each axis.
    pub divisions: [usize; 3],
    /// Cell splitting.
    pub cells: BoxCells,
    /// Quadratic elements (hex20, penta15, tet10) instead of linear ones.
    pub quadratic: bool,
}

impl BoxSpec {
    /// A box spec.
    pub fn new(lengths: [f64; 3], divisions: [usize; 3], cells: BoxCells, quadratic: bool) -> Self {
        Self {
            lengths,
            divisions,
            cells,
            quadratic,
        }
    }
}

/// The structured grid of corner nodes shared by the generators.
struct Grid {
    n: [usize; 3],
}

impl Grid {
    fn node(&self, i: usize, j: usize, k: usize) -> usize {
        i + (self.n[0] + 1) * (j + (self.n[1] + 1) * k)
    }
}

fn check_spec(lengths: [f64; 3], divisions: [usize; 3]) -> Result<(), FemError> {
    if lengths.iter().any(|l| !(l.is_finite() && *l > 0.0)) {
        return Err(FemError::InvalidGenerator {
            reason: format!("lengths must be positive, got {lengths:?}"),
        });
    }
    if divisions.contains(&0) {
        return Err(FemError::InvalidGenerator {
            reason: format!("divisions must be at least 1, got {divisions:?}"),
        });
    }
    Ok(())
}

fn grid_mesh(lengths: [f64; 3], divisions: [usize; 3]) -> (Mesh, Grid) {
    let g = Grid { n: divisions };
    let mut mesh = Mesh::new();
    let [nx, ny, nz] = divisions;
    let mut faces: [Vec<usize>; 6] = Default::default();
    for k in 0..=nz {
        for j in 0..=ny {
            for i in 0..=nx {
                let x = [
                    lengths[0] * i as f64 / nx as f64,
                    lengths[1] * j as f64 / ny as f64,
                    lengths[2] * k as f64 / nz as f64,
                ];
                let idx = mesh
                    .add_node(g.node(i, j, k) as u64 + 1, x)
                    .expect("generated ids are unique");
                for (f, on) in [i == 0, i == nx, j == 0, j == ny, k == 0, k == nz]
                    .iter()
                    .enumerate()
                {
                    if *on {
                        faces[f].push(idx);
                    }
                }
            }
        }
    }
    for (name, set) in ["xmin", "xmax", "ymin", "ymax", "zmin", "zmax"]
        .iter()
        .zip(faces)
    {
        mesh.add_node_set_indices(*name, set);
    }
    mesh.add_node_set_indices("all", (0..mesh.node_count()).collect());
    (mesh, g)
}

/// Corner `c` (bits x, y, z) of cell `(i, j, k)`.
fn corner(g: &Grid, (i, j, k): (usize, usize, usize), c: [usize; 3]) -> usize {
    g.node(i + c[0], j + c[1], k + c[2])
}

fn orient(mesh: &Mesh, nodes: &mut [usize]) {
    let x = mesh.coords();
    let (a, b, c, d) = (x[nodes[0]], x[nodes[1]], x[nodes[2]], x[nodes[3]]);
    let u = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
    let v = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
    let w = [d[0] - a[0], d[1] - a[1], d[2] - a[2]];
    let det = u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0])
        + u[2] * (v[0] * w[1] - v[1] * w[0]);
    if det < 0.0 {
        nodes.swap(1, 2);
    }
}

/// Adds the elements of one cell: hexahedron, two wedges with axis `axis` (0 = x, 1 = y, 2 = z),
/// or tetrahedra.
fn add_cell(
    mesh: &mut Mesh,
    g: &Grid,
    cell: (usize, usize, usize),
    cells: BoxCells,
    axis: usize,
    next_id: &mut u64,
) -> Vec<usize> {
    let mut out = Vec::new();
    let mut push = |mesh: &mut Mesh, kind: ElementKind, nodes: &[usize]| {
        out.push(mesh.push_element(*next_id, kind, nodes));
        *next_id += 1;
    };
    match cells {
        BoxCells::Hex => {
            let n: Vec<usize> = [
                [0, 0, 0],
                [1, 0, 0],
                [1, 1, 0],
                [0, 1, 0],
                [0, 0, 1],
                [1, 0, 1],
                [1, 1, 1],
                [0, 1, 1],
            ]
            .iter()
            .map(|c| corner(g, cell, *c))
            .collect();
            push(mesh, ElementKind::Hex8, &n);
        }
        BoxCells::Wedge => {
            // (u, v, w) is a cyclic permutation of (x, y, z) with w along the axis, so the frame
            // stays right-handed; the u-v diagonal (0,0)-(1,1) matches the Kuhn split's faces.
            let perm = match axis {
                0 => [1, 2, 0],
                1 => [2, 0, 1],
                _ => [0, 1, 2],
            };
            let to_xyz = |uvw: [usize; 3]| -> [usize; 3] {
                let mut c = [0; 3];
                for (d, p) in perm.iter().enumerate() {
                    c[*p] = uvw[d];
                }
                c
            };
            for w in [
                [
                    [0, 0, 0],
                    [1, 0, 0],
                    [1, 1, 0],
                    [0, 0, 1],
                    [1, 0, 1],
                    [1, 1, 1],
                ],
                [
                    [0, 0, 0],
                    [1, 1, 0],
                    [0, 1, 0],
                    [0, 0, 1],
                    [1, 1, 1],
                    [0, 1, 1],
                ],
            ] {
                let n: Vec<usize> = w.iter().map(|c| corner(g, cell, to_xyz(*c))).collect();
                push(mesh, ElementKind::Penta6, &n);
            }
        }
        BoxCells::Tet6 => {
            for perm in [
                [0, 1, 2],
                [0, 2, 1],
                [1, 0, 2],
                [1, 2, 0],
                [2, 0, 1],
                [2, 1, 0],
            ] {
                let mut c = [0usize; 3];
                let mut n = vec![corner(g, cell, c)];
                for p in perm {
                    c[p] = 1;
                    n.push(corner(g, cell, c));
                }
                orient(mesh, &mut n);
                push(mesh, ElementKind::Tet4, &n);
            }
        }
        BoxCells::Tet5 => {
            let even = (cell.0 + cell.1 + cell.2).is_multiple_of(2);
            let flip = |c: [usize; 3]| if even { c } else { [1 - c[0], c[1], c[2]] };
            let tets = [
                [[1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 1, 1]],
                [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]],
                [[1, 1, 0], [1, 0, 0], [0, 1, 0], [1, 1, 1]],
                [[1, 0, 1], [1, 0, 0], [0, 0, 1], [1, 1, 1]],
                [[0, 1, 1], [0, 1, 0], [0, 0, 1], [1, 1, 1]],
            ];
            for t in tets {
                let mut n: Vec<usize> = t.iter().map(|c| corner(g, cell, flip(*c))).collect();
                orient(mesh, &mut n);
                push(mesh, ElementKind::Tet4, &n);
            }
        }
    }
    out
}

/// A structured box mesh of one element kind.
///
/// ```
/// use femu_fem::generate::{box_mesh, BoxCells, BoxSpec};
/// let mesh = box_mesh(&BoxSpec::new([1.0, 0.5, 0.25], [4, 2, 1], BoxCells::Tet6, true)).unwrap();
/// assert_eq!(mesh.element_count(), 4 * 2 * 6);
/// assert!(mesh.check_conformity().is_conforming());
/// ```
///
/// # Errors
/// [`FemError::InvalidGenerator`] for non-positive lengths or zero divisions.
pub fn box_mesh(spec: &BoxSpec) -> Result<Mesh, FemError> {
    check_spec(spec.lengths, spec.divisions)?;
    let (mut mesh, g) = grid_mesh(spec.lengths, spec.divisions);
    let [nx, ny, nz] = spec.divisions;
    let mut id = 1;
    for k in 0..nz {
        for j in 0..ny {
            for i in 0..nx {
                add_cell(&mut mesh, &g, (i, j, k), spec.cells, 2, &mut id);
            }
        }
    }
    mesh.add_element_set_indices("all", (0..mesh.element_count()).collect());
    Ok(if spec.quadratic {
        to_quadratic(&mesh)
    } else {
        mesh
    })
}

/// The mixed plate: hexahedra, wedges and tetrahedra in one conforming mesh.
///
/// The plate `[0, lx] x [0, ly] x [0, lz]` is divided into `nx x ny x nz` cells. The cells with
/// `i >= nx - tet_block[0]` and `j >= ny - tet_block[1]` (a corner block through the thickness)
/// are split into six tetrahedra each; the strips that separate that block from the hexahedra are
/// wedges whose triangular faces meet the tetrahedra (axis x for the strip along x, axis y for the
/// strip along y); every other cell is a hexahedron.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PlateSpec {
    /// Plate dimensions in m.
    pub lengths: [f64; 3],
    /// Cells along x, y and through the thickness.
    pub divisions: [usize; 3],
    /// Cells of the tetrahedral corner block along x and y.
    pub tet_block: [usize; 2],
    /// Quadratic elements.
    pub quadratic: bool,
}

impl Default for PlateSpec {
    /// Sized like the paper's plate: 1,845 nodes (5,535 DOFs) and 1,360 elements (912 hex8,
    /// 400 penta6, 48 tet4) on a 0.2 x 0.07 x 0.01 m steel-sized plate with 5 mm cells.
    fn default() -> Self {
        Self {
            lengths: [0.2, 0.07, 0.01],
            divisions: [40, 14, 2],
            tet_block: [2, 2],
            quadratic: false,
        }
    }
}

/// Generates the mixed plate of [`PlateSpec`].
///
/// ```
/// use femu_fem::generate::{mixed_plate, PlateSpec};
/// let mesh = mixed_plate(&PlateSpec::default()).unwrap();
/// assert_eq!((mesh.node_count(), mesh.element_count()), (1845, 1360));
/// assert!(mesh.check_conformity().is_conforming());
/// ```
///
/// # Errors
/// [`FemError::InvalidGenerator`] for bad sizes or a tetrahedral block that does not fit.
pub fn mixed_plate(spec: &PlateSpec) -> Result<Mesh, FemError> {
    check_spec(spec.lengths, spec.divisions)?;
    let [nx, ny, nz] = spec.divisions;
    let [tx, ty] = spec.tet_block;
    if tx == 0 || ty == 0 || tx >= nx || ty >= ny {
        return Err(FemError::InvalidGenerator {
            reason: format!(
                "tet block {tx} x {ty} must be at least 1 x 1 and smaller than the plate's {nx} x {ny} cells"
            ),
        });
    }
    let (mut mesh, g) = grid_mesh(spec.lengths, spec.divisions);
    let (ix, iy) = (nx - tx, ny - ty);
    let mut sets: [Vec<usize>; 3] = Default::default();
    let mut id = 1;
    for k in 0..nz {
        for j in 0..ny {
            for i in 0..nx {
                let (cells, axis, set) = match (i >= ix, j >= iy) {
                    (true, true) => (BoxCells::Tet6, 2, 2),
                    (false, true) => (BoxCells::Wedge, 0, 1),
                    (true, false) => (BoxCells::Wedge, 1, 1),
                    (false, false) => (BoxCells::Hex, 2, 0),
                };
                let added = add_cell(&mut mesh, &g, (i, j, k), cells, axis, &mut id);
                sets[set].extend(added);
            }
        }
    }
    for (name, set) in ["hex", "penta", "tet"].iter().zip(sets) {
        mesh.add_element_set_indices(*name, set);
    }
    mesh.add_element_set_indices("all", (0..mesh.element_count()).collect());
    Ok(if spec.quadratic {
        to_quadratic(&mesh)
    } else {
        mesh
    })
}

/// Splits a mesh into `count` equal slabs along `axis` (0 = x) of its bounding box and adds each as
/// an element set `"{prefix}{k}"` (an element belongs to the slab holding its centroid): the
/// regions of an updating study. Returns the set names.
///
/// ```
/// use femu_fem::generate::{add_slab_sets, box_mesh, BoxCells, BoxSpec};
/// let mut mesh = box_mesh(&BoxSpec::new([0.2, 0.02, 0.02], [10, 1, 1], BoxCells::Hex, false)).unwrap();
/// let names = add_slab_sets(&mut mesh, 0, 5, "r").unwrap();
/// assert_eq!(names, ["r0", "r1", "r2", "r3", "r4"]);
/// assert_eq!(mesh.element_set("r2").unwrap().len(), 2);
/// ```
///
/// # Errors
/// [`FemError::InvalidGenerator`] for an axis above 2, no slab, or a mesh without elements.
pub fn add_slab_sets(
    mesh: &mut Mesh,
    axis: usize,
    count: usize,
    prefix: &str,
) -> Result<Vec<String>, FemError> {
    if axis > 2 || count == 0 || mesh.element_count() == 0 {
        return Err(FemError::InvalidGenerator {
            reason: format!(
                "slabs: axis {axis} (0-2), count {count} (at least 1), {} elements",
                mesh.element_count()
            ),
        });
    }
    let (lo, hi) = mesh
        .coords()
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), p| {
            (l.min(p[axis]), h.max(p[axis]))
        });
    let mut sets = vec![Vec::new(); count];
    let mut xs = Vec::new();
    for e in 0..mesh.element_count() {
        mesh.element_coords(e, &mut xs);
        let c = xs.iter().map(|p| p[axis]).sum::<f64>() / xs.len() as f64;
        let k = ((c - lo) / (hi - lo) * count as f64) as usize;
        sets[k.min(count - 1)].push(e);
    }
    let names: Vec<String> = (0..count).map(|k| format!("{prefix}{k}")).collect();
    for (name, set) in names.iter().zip(sets) {
        mesh.add_element_set_indices(name.clone(), set);
    }
    Ok(names)
}

/// The quadratic version of a mesh: every linear element gets straight-edge mid-edge nodes shared
/// with its neighbours (new ids follow the largest existing one). Quadratic elements are kept as
/// they are. A mid-edge node joins a node set when both ends of its edge are in the set, so face
/// sets keep covering their faces.
pub fn to_quadratic(mesh: &Mesh) -> Mesh {
    let mut out = Mesh::new();
    for i in 0..mesh.node_count() {
        out.add_node(mesh.node_id(i), mesh.coords()[i])
            .expect("ids copied from a valid mesh");
    }
    let mut next = (0..mesh.node_count())
        .map(|i| mesh.node_id(i))
        .max()
        .unwrap_or(0)
        + 1;
    let mut mid: HashMap<(usize, usize), usize> = HashMap::new();
    for el in mesh.elements() {
        let mut nodes = el.nodes.to_vec();
        if !el.kind.is_quadratic() {
            for e in el.kind.edges() {
                let (a, b) = (el.nodes[e[0]], el.nodes[e[1]]);
                let key = (a.min(b), a.max(b));
                let idx = *mid.entry(key).or_insert_with(|| {
                    let (p, q) = (mesh.coords()[a], mesh.coords()[b]);
                    let x = [
                        0.5 * (p[0] + q[0]),
                        0.5 * (p[1] + q[1]),
                        0.5 * (p[2] + q[2]),
                    ];
                    let i = out.add_node(next, x).expect("fresh id");
                    next += 1;
                    i
                });
                nodes.push(idx);
            }
        }
        out.push_element(el.id, el.kind.quadratic(), &nodes);
    }
    let mut edges: Vec<_> = mid.into_iter().collect();
    edges.sort_unstable();
    for (name, set) in mesh.node_sets() {
        let mut members = vec![false; mesh.node_count()];
        set.iter().for_each(|n| members[*n] = true);
        let mut nodes = set.clone();
        nodes.extend(
            edges
                .iter()
                .filter(|((a, b), _)| members[*a] && members[*b])
                .map(|(_, m)| *m),
        );
        out.add_node_set_indices(name.clone(), nodes);
    }
    for (name, set) in mesh.element_sets() {
        out.add_element_set_indices(name.clone(), set.clone());
    }
    out
}

/// A mesh made from another by [`refine`] or [`quadratic_refinement`], with what ties it to the
/// original: every original node keeps its id (and index), and each new node is a combination of
/// the original nodes of the face, edge or cell it lies in.
#[derive(Debug, Clone)]
pub struct Refinement {
    /// The new mesh (original nodes first, with their ids; new nodes after, ids above the largest).
    pub mesh: Mesh,
    /// For each element of the new mesh, the index of the original element it came from.
    pub parent: Vec<usize>,
    /// Each new node (index into the new mesh) with the original nodes (indices) of the entity it
    /// lies on and their shape-function values there: its displacement in the original element's
    /// interpolation is `sum w u`. A fixed or rigidly linked entity fixes or links it.
    pub new_nodes: Vec<(usize, Vec<(usize, f64)>)>,
}

/// [`to_quadratic`] with the map of [`Refinement`]: each mid-edge node is `(a + b) / 2` of its
/// edge's ends.
pub fn quadratic_refinement(mesh: &Mesh) -> Refinement {
    let out = to_quadratic(mesh);
    let n0 = mesh.node_count();
    let mut new_nodes = Vec::new();
    let mut seen = vec![false; out.node_count()];
    for (e, el) in out.elements().enumerate() {
        if mesh.element(e).kind.is_quadratic() {
            continue;
        }
        let corners = el.kind.num_corners();
        for (k, edge) in el.kind.edges().iter().enumerate() {
            let mid = el.nodes[corners + k];
            if mid >= n0 && !seen[mid] {
                seen[mid] = true;
                new_nodes.push((
                    mid,
                    vec![(el.nodes[edge[0]], 0.5), (el.nodes[edge[1]], 0.5)],
                ));
            }
        }
    }
    new_nodes.sort_unstable_by_key(|(m, _)| *m);
    Refinement {
        parent: (0..out.element_count()).collect(),
        mesh: out,
        new_nodes,
    }
}

/// The children of a reference cell split once, as the reference coordinates of their corners:
/// the cube in 8, the tetrahedron in 8 (4 corner tetrahedra and the central octahedron cut along
/// a diagonal), the wedge in 8 (4 triangles by 2 layers). `None` for pyramids.
fn children(kind: ElementKind) -> Option<Vec<Vec<[f64; 3]>>> {
    let lin = kind.linear();
    let c = lin.reference_nodes();
    let mid = |a: [f64; 3], b: [f64; 3]| {
        [
            0.5 * (a[0] + b[0]),
            0.5 * (a[1] + b[1]),
            0.5 * (a[2] + b[2]),
        ]
    };
    Some(match lin {
        ElementKind::Hex8 => {
            let mut out = Vec::new();
            for oz in [-0.5, 0.5] {
                for oy in [-0.5, 0.5] {
                    for ox in [-0.5, 0.5] {
                        out.push(
                            c.iter()
                                .map(|p| [ox + 0.5 * p[0], oy + 0.5 * p[1], oz + 0.5 * p[2]])
                                .collect(),
                        );
                    }
                }
            }
            out
        }
        ElementKind::Tet4 => {
            let (p0, p1, p2, p3) = (c[0], c[1], c[2], c[3]);
            let (m01, m02, m03) = (mid(p0, p1), mid(p0, p2), mid(p0, p3));
            let (m12, m13, m23) = (mid(p1, p2), mid(p1, p3), mid(p2, p3));
            vec![
                vec![p0, m01, m02, m03],
                vec![m01, p1, m12, m13],
                vec![m02, m12, p2, m23],
                vec![m03, m13, m23, p3],
                vec![m02, m13, m01, m03],
                vec![m02, m13, m03, m23],
                vec![m02, m13, m23, m12],
                vec![m02, m13, m12, m01],
            ]
        }
        ElementKind::Penta6 => {
            let t = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]];
            let m = |a: [f64; 2], b: [f64; 2]| [0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1])];
            let (m01, m12, m02) = (m(t[0], t[1]), m(t[1], t[2]), m(t[0], t[2]));
            let tris = [
                [t[0], m01, m02],
                [m01, t[1], m12],
                [m02, m12, t[2]],
                [m12, m02, m01],
            ];
            let mut out = Vec::new();
            for (lo, hi) in [(-1.0, 0.0), (0.0, 1.0)] {
                for tr in &tris {
                    let mut v: Vec<[f64; 3]> = tr.iter().map(|p| [p[0], p[1], lo]).collect();
                    v.extend(tr.iter().map(|p| [p[0], p[1], hi]));
                    out.push(v);
                }
            }
            out
        }
        _ => return None,
    })
}

/// The determinant of the affine map from the reference cell of `lin` to the child with corners
/// `c` (reference coordinates of the parent).
fn child_orientation(lin: ElementKind, c: &[[f64; 3]]) -> f64 {
    let centre = match lin {
        ElementKind::Tet4 => [0.25; 3],
        ElementKind::Penta6 => [1.0 / 3.0, 1.0 / 3.0, 0.0],
        _ => [0.0; 3],
    };
    let mut dn = vec![0.0; 3 * lin.num_nodes()];
    lin.shape_gradients(centre, &mut dn);
    let mut j = [[0.0; 3]; 3];
    for (a, p) in c.iter().enumerate() {
        for r in 0..3 {
            for s in 0..3 {
                j[r][s] += p[r] * dn[3 * a + s];
            }
        }
    }
    j[0][0] * (j[1][1] * j[2][2] - j[1][2] * j[2][1])
        - j[0][1] * (j[1][0] * j[2][2] - j[1][2] * j[2][0])
        + j[0][2] * (j[1][0] * j[2][1] - j[1][1] * j[2][0])
}

/// Splits every element of a mesh once (8 children each) keeping its interpolation: each child
/// node is placed by the parent's own shape functions, so curved quadratic geometry stays curved,
/// and children of a quadratic element are quadratic. Nodes on a shared face or edge are shared
/// (identified by the face's or edge's corner nodes and the position on it, not by coordinates:
/// coincident nodes of separate parts stay separate). Node sets take the new nodes whose face,
/// edge or cell lies in the set; element sets take the children of their elements.
///
/// # Errors
/// [`FemError::InvalidGenerator`] for a pyramid (its split into pyramids and tetrahedra is not
/// implemented), named by element id.
pub fn refine(mesh: &Mesh) -> Result<Refinement, FemError> {
    let mut out = Mesh::new();
    for i in 0..mesh.node_count() {
        out.add_node(mesh.node_id(i), mesh.coords()[i])?;
    }
    let mut next = (0..mesh.node_count())
        .map(|i| mesh.node_id(i))
        .max()
        .unwrap_or(0)
        + 1;
    // a point of an element: its entity's corner nodes with the linear weights there, in 64ths
    // (the split's points are on a lattice of quarters: every weight is exact)
    type Key = Vec<(usize, i64)>;
    let mut by_key: HashMap<Key, usize> = HashMap::new();
    let mut new_nodes = Vec::new();
    let mut parent = Vec::new();
    let mut next_element = 1u64;
    let mut children_of: Vec<Vec<usize>> = vec![Vec::new(); mesh.element_count()];
    for (e, el) in mesh.elements().enumerate() {
        let kind = el.kind;
        let lin = kind.linear();
        let kids = children(kind).ok_or_else(|| FemError::InvalidGenerator {
            reason: format!(
                "refinement: element {} is a {kind:?}, and pyramids are not split",
                el.id
            ),
        })?;
        let corners = lin.num_nodes();
        let ref_nodes = kind.reference_nodes();
        // for each of the parent's nodes, the corners of the face, edge or cell it lies on
        let support: Vec<Vec<usize>> = ref_nodes
            .iter()
            .map(|xi| {
                let mut on = vec![0.0; corners];
                lin.shape(*xi, &mut on);
                (0..corners).filter(|c| on[*c].abs() > 1e-12).collect()
            })
            .collect();
        let mut n_lin = vec![0.0; corners];
        let mut n_par = vec![0.0; kind.num_nodes()];
        let key_of = |xi: [f64; 3], n_lin: &mut Vec<f64>| -> Key {
            lin.shape(xi, n_lin);
            let mut k: Key = n_lin
                .iter()
                .enumerate()
                .filter(|(_, w)| w.abs() > 1e-12)
                .map(|(a, w)| (el.nodes[a], (w * 64.0).round() as i64))
                .collect();
            k.sort_unstable();
            k
        };
        // the parent's own nodes are the original ones
        for (a, xi) in ref_nodes.iter().enumerate() {
            let k = key_of(*xi, &mut n_lin);
            by_key.entry(k).or_insert(el.nodes[a]);
        }
        for mut kid in kids {
            if child_orientation(lin, &kid) < 0.0 {
                // a mirrored child: swap two corners (and their layer partners for a wedge)
                kid.swap(1, 2);
                if lin == ElementKind::Penta6 {
                    kid.swap(4, 5);
                }
            }
            let mut nodes = Vec::with_capacity(kind.num_nodes());
            for r in &ref_nodes {
                // the child's reference point in the parent's reference coordinates (affine)
                lin.shape(*r, &mut n_lin);
                let mut xi = [0.0; 3];
                for (a, p) in kid.iter().enumerate() {
                    for d in 0..3 {
                        xi[d] += n_lin[a] * p[d];
                    }
                }
                let k = key_of(xi, &mut n_lin);
                let idx = match by_key.get(&k) {
                    Some(i) => *i,
                    None => {
                        kind.shape(xi, &mut n_par);
                        let mut x = [0.0; 3];
                        for (a, w) in n_par.iter().enumerate() {
                            let p = mesh.coords()[el.nodes[a]];
                            for d in 0..3 {
                                x[d] += w * p[d];
                            }
                        }
                        let i = out.add_node(next, x)?;
                        next += 1;
                        // the entity's original nodes with their weights (the others vanish on it)
                        let entity: Vec<usize> = k.iter().map(|(n, _)| *n).collect();
                        let weights: Vec<(usize, f64)> = n_par
                            .iter()
                            .enumerate()
                            .filter(|(a, _)| {
                                support[*a].iter().all(|c| entity.contains(&el.nodes[*c]))
                            })
                            .map(|(a, w)| (el.nodes[a], *w))
                            .collect();
                        new_nodes.push((i, weights));
                        by_key.insert(k, i);
                        i
                    }
                };
                nodes.push(idx);
            }
            children_of[e].push(out.element_count());
            out.push_element(next_element, kind, &nodes);
            next_element += 1;
            parent.push(e);
        }
    }
    for (name, set) in mesh.node_sets() {
        let mut members = vec![false; mesh.node_count()];
        set.iter().for_each(|n| members[*n] = true);
        let mut nodes = set.clone();
        nodes.extend(
            new_nodes
                .iter()
                .filter(|(_, w)| w.iter().all(|(n, _)| members[*n]))
                .map(|(i, _)| *i),
        );
        out.add_node_set_indices(name.clone(), nodes);
    }
    for (name, set) in mesh.element_sets() {
        out.add_element_set_indices(
            name.clone(),
            set.iter().flat_map(|e| children_of[*e].clone()).collect(),
        );
    }
    Ok(Refinement {
        mesh: out,
        parent,
        new_nodes,
    })
}
