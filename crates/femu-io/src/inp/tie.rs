//! `*TIE`: each node of the slave surface follows the point of the master surface it lies on
//! (docs/MATH.md, "Multipoint constraints"): `u_s = sum_i N_i(xi) u_i` over the nodes of the
//! master face, `xi` the node's local coordinates in the face's element, found by the inverse
//! isoparametric map ([`femu_fem::locate::inverse_map`]; the element's shape functions of the
//! nodes off the face vanish on it). Abaqus's face labels (`S1`-`S6`) by element type.

use super::orientation::dist;
use super::structural::at_err;
use super::*;
use femu_fem::element::ElementKind;

/// The local (1-based) nodes of face `label` of an element of `kind`, as Abaqus numbers them.
fn face_nodes(kind: ElementKind, label: &str) -> Option<&'static [usize]> {
    let k = label.strip_prefix('S')?.parse::<usize>().ok()?;
    let faces: &[&[usize]] = match kind {
        ElementKind::Hex8 => &[
            &[1, 2, 3, 4],
            &[5, 8, 7, 6],
            &[1, 5, 6, 2],
            &[2, 6, 7, 3],
            &[3, 7, 8, 4],
            &[4, 8, 5, 1],
        ],
        ElementKind::Hex20 => &[
            &[1, 2, 3, 4, 9, 10, 11, 12],
            &[5, 8, 7, 6, 16, 15, 14, 13],
            &[1, 5, 6, 2, 17, 13, 18, 9],
            &[2, 6, 7, 3, 18, 14, 19, 10],
            &[3, 7, 8, 4, 19, 15, 20, 11],
            &[4, 8, 5, 1, 20, 16, 17, 12],
        ],
        ElementKind::Tet4 => &[&[1, 2, 3], &[1, 4, 2], &[2, 4, 3], &[3, 4, 1]],
        ElementKind::Tet10 => &[
            &[1, 2, 3, 5, 6, 7],
            &[1, 4, 2, 8, 9, 5],
            &[2, 4, 3, 9, 10, 6],
            &[3, 4, 1, 10, 8, 7],
        ],
        ElementKind::Penta6 => &[
            &[1, 2, 3],
            &[4, 6, 5],
            &[1, 4, 5, 2],
            &[2, 5, 6, 3],
            &[3, 6, 4, 1],
        ],
        ElementKind::Penta15 => &[
            &[1, 2, 3, 7, 8, 9],
            &[4, 6, 5, 12, 11, 10],
            &[1, 4, 5, 2, 13, 10, 14, 7],
            &[2, 5, 6, 3, 14, 11, 15, 8],
            &[3, 6, 4, 1, 15, 12, 13, 9],
        ],
        _ => return None,
    };
    faces.get(k.checked_sub(1)?).copied()
}

/// A master face: its element (internal index) and its nodes (internal indices).
struct Face {
    element: usize,
    nodes: Vec<usize>,
}

impl InpDeck {
    /// The faces of element-based surface `name` (the tie's line `at` for its errors).
    fn surface_faces(&self, name: &str, at: &Location) -> Result<Vec<Face>, IoError> {
        let lines = self.element_surfaces.get(name).ok_or_else(|| {
            at_err(
                at,
                format!(
                    "*TIE: {name} is no element-based *SURFACE of the deck{}",
                    crate::spelling::suggestion(
                        name,
                        self.element_surfaces.keys().map(String::as_str),
                        ""
                    )
                ),
            )
        })?;
        let mut faces = Vec::new();
        for (target, label, l) in lines {
            let elements: Vec<usize> = match target {
                Target::Node(id) => vec![self.mesh.element_index(*id).ok_or_else(|| {
                    at_err(
                        l,
                        format!("*SURFACE {name}: element {id} is no solid element of the deck (femu ties the faces of solids)"),
                    )
                })?],
                Target::Set(s) => self
                    .mesh
                    .element_sets()
                    .get(s)
                    .cloned()
                    .ok_or_else(|| {
                        at_err(
                            l,
                            format!("*SURFACE {name}: {s} is no element set of solids (femu ties the faces of solids)"),
                        )
                    })?,
            };
            for e in elements {
                let el = self.mesh.element(e);
                let local = face_nodes(el.kind, label).ok_or_else(|| {
                    at_err(
                        l,
                        format!(
                            "*SURFACE {name}: face {label:?} of a {:?} element: femu ties the faces S1-S6 of bricks, tetrahedra and wedges",
                            el.kind
                        ),
                    )
                })?;
                faces.push(Face {
                    element: e,
                    nodes: local.iter().map(|k| el.nodes[k - 1]).collect(),
                });
            }
        }
        Ok(faces)
    }

    /// The deck's `*TIE`s into `model`: each slave node within the position tolerance of the
    /// master surface follows the point of the nearest master face, in its three translations.
    pub(super) fn apply_ties(&self, model: &mut Model) -> Result<Vec<Warning>, IoError> {
        let mut warnings = Vec::new();
        for tie in &self.ties {
            let at = &tie.line;
            if tie.slave.is_empty() {
                return Err(at_err(
                    at,
                    "*TIE without its data line (slave, master)".into(),
                ));
            }
            let faces = self.surface_faces(&tie.master, at)?;
            // the slave's nodes: a node-based surface's, or the faces' of an element-based one
            let mut slaves: Vec<usize> = if let Some(list) = self.surfaces.get(&tie.slave) {
                let mut v = Vec::new();
                for (t, _) in list {
                    for id in self.target_ids(t, at, "*TIE")? {
                        v.push(self.mesh.node_index(id).ok_or_else(|| {
                            at_err(at, format!("*TIE: node {id} is not in the deck"))
                        })?);
                    }
                }
                v
            } else {
                self.surface_faces(&tie.slave, at)?
                    .into_iter()
                    .flat_map(|f| f.nodes)
                    .collect()
            };
            slaves.sort_unstable();
            slaves.dedup();
            let x = self.mesh.coords();
            let on_master: std::collections::HashSet<usize> =
                faces.iter().flat_map(|f| f.nodes.iter().copied()).collect();
            // each master face's diagonal, and their mean: Abaqus's default tolerance is 5 % of it
            let diagonals: Vec<f64> = faces
                .iter()
                .map(|f| {
                    f.nodes
                        .iter()
                        .flat_map(|a| f.nodes.iter().map(move |b| dist(x[*a], x[*b])))
                        .fold(0.0f64, f64::max)
                })
                .collect();
            let diagonal = diagonals.iter().sum::<f64>() / faces.len().max(1) as f64;
            let tolerance = tie.tolerance.unwrap_or(0.05 * diagonal);
            let label = format!("*TIE {} ({} line {})", tie.name, at.path.display(), at.line);
            let (mut untied, mut moved, mut gap) = (Vec::new(), 0usize, 0.0f64);
            for &s in slaves.iter().filter(|s| !on_master.contains(s)) {
                let p = x[s];
                // the nearest point of the master surface: each face's element mapped back,
                // the weights of the nodes off the face dropped (they vanish on it)
                let mut best: Option<(f64, Vec<(usize, f64)>)> = None;
                for (f, d) in faces.iter().zip(&diagonals) {
                    // a point on a face lies within its diagonal of each of its nodes
                    let near = f.nodes.iter().any(|n| dist(x[*n], p) <= d + tolerance);
                    if !near {
                        continue;
                    }
                    let el = self.mesh.element(f.element);
                    let coords: Vec<[f64; 3]> = el.nodes.iter().map(|n| x[*n]).collect();
                    let map = femu_fem::locate::inverse_map(el.kind, &coords, p);
                    let mut n = vec![0.0; el.nodes.len()];
                    el.kind.shape(map.xi, &mut n);
                    let mut w: Vec<(usize, f64)> = el
                        .nodes
                        .iter()
                        .zip(&n)
                        .filter(|(node, _)| f.nodes.contains(node))
                        .map(|(node, v)| (*node, *v))
                        .collect();
                    let sum: f64 = w.iter().map(|p| p.1).sum();
                    if !(sum.abs() > 1e-12) {
                        continue;
                    }
                    for p in &mut w {
                        p.1 /= sum;
                    }
                    let q = w.iter().fold([0.0; 3], |q, (node, v)| {
                        [
                            q[0] + v * x[*node][0],
                            q[1] + v * x[*node][1],
                            q[2] + v * x[*node][2],
                        ]
                    });
                    let d = dist(p, q);
                    if best.as_ref().is_none_or(|b| d < b.0) {
                        best = Some((d, w));
                    }
                }
                match best {
                    Some((d, w)) if d <= tolerance => {
                        if d > 1e-9 * diagonal {
                            moved += 1;
                            gap = gap.max(d);
                        }
                        let id = self.mesh.node_id(s);
                        for c in 0..3 {
                            let terms: Vec<((u64, usize), f64)> = w
                                .iter()
                                .filter(|(_, v)| *v != 0.0)
                                .map(|(node, v)| ((self.mesh.node_id(*node), c), *v))
                                .collect();
                            model
                                .add_constraint((id, c), &terms, &label)
                                .map_err(|source| IoError::Model {
                                    path: at.path.clone(),
                                    line: at.line,
                                    source,
                                })?;
                        }
                    }
                    _ => untied.push(self.mesh.node_id(s)),
                }
            }
            if !untied.is_empty() {
                warnings.push(Warning {
                    path: at.path.clone(),
                    line: at.line,
                    message: format!(
                        "*TIE {}: {} slave nodes lie farther than the position tolerance {tolerance:e} from the master surface and are not tied (as Abaqus leaves them), the first {:?}",
                        tie.name,
                        untied.len(),
                        &untied[..untied.len().min(5)]
                    ),
                });
            }
            if moved > 0 {
                warnings.push(Warning {
                    path: at.path.clone(),
                    line: at.line,
                    message: format!(
                        "*TIE {}: {moved} slave nodes lie off the master surface (up to {gap:e}); femu ties each to the nearest point of the surface where it stands{}",
                        tie.name,
                        if tie.adjust {
                            ", where Abaqus's ADJUST=YES first moves it there"
                        } else {
                            ""
                        }
                    ),
                });
            }
        }
        Ok(warnings)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every face's nodes are nodes of its element that the element's shape functions of the
    /// other nodes vanish on: at each face node, the shape functions of the nodes off the face
    /// are 0 (hex8, hex20, tet4, tet10, wedges; reference coordinates of the nodes from the
    /// element's own table).
    #[test]
    fn off_face_shape_functions_vanish_on_the_face() {
        for kind in [
            ElementKind::Hex8,
            ElementKind::Hex20,
            ElementKind::Tet4,
            ElementKind::Tet10,
            ElementKind::Penta6,
            ElementKind::Penta15,
        ] {
            let nn = kind.num_nodes();
            let reference = kind.reference_nodes();
            for k in 1..=6 {
                let Some(face) = face_nodes(kind, &format!("S{k}")) else {
                    continue;
                };
                // the face's centroid in reference coordinates
                let mut c = [0.0; 3];
                for &a in face {
                    for d in 0..3 {
                        c[d] += reference[a - 1][d] / face.len() as f64;
                    }
                }
                for xi in face.iter().map(|a| reference[a - 1]).chain([c]) {
                    let mut n = vec![0.0; nn];
                    kind.shape(xi, &mut n);
                    for (b, v) in n.iter().enumerate() {
                        if !face.contains(&(b + 1)) {
                            assert!(v.abs() < 1e-14, "{kind:?} S{k}: N{} = {v}", b + 1);
                        }
                    }
                }
            }
        }
    }
}
