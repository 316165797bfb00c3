//! Solid elements (`CHEXA`, `CPENTA`, `CTETRA`, `CPYRAM`) in Nastran's grid order, read into
//! femu's; blank mid-side grids become straight edges.

use super::cards::Card;
use crate::IoError;
use femu_fem::element::ElementKind;
use femu_fem::mesh::Mesh;
use std::collections::HashMap;

/// What reading the elements left for the model: each element's property, and the mid-side
/// nodes femu added for blank grids with the two grids each one is tied to.
pub(super) struct Elements<'a> {
    /// `(EID, PID, card)` in file order.
    pub(super) element_pid: Vec<(u64, u64, &'a Card)>,
    /// `(added node, grid a, grid b, label)`: a node at the midpoint of a straight edge.
    pub(super) ties: Vec<(u64, u64, u64, String)>,
    /// The first element with a blank mid-side grid.
    pub(super) first_blank: Option<&'a Card>,
}

/// Adds the elements to `mesh` (whose grids have ids up to `max_grid`).
///
/// # Errors
/// A malformed or unknown grid, a blank corner grid, a grid count femu does not read.
pub(super) fn add_elements<'a>(
    elements: &[&'a Card],
    mesh: &mut Mesh,
    max_grid: u64,
) -> Result<Elements<'a>, IoError> {
    // elements: Nastran's node order to femu's
    let mut element_pid: Vec<(u64, u64, &Card)> = Vec::new();
    // blank mid-side grids: a node at the edge's midpoint, tied to the average of its ends
    let mut next_id = max_grid;
    let mut straight: HashMap<(u64, u64), u64> = HashMap::new();
    let mut ties: Vec<(u64, u64, u64, String)> = Vec::new();
    let mut first_blank: Option<&Card> = None;
    for c in elements {
        let eid = c.id(0, "EID")?;
        let pid = c.id(1, "PID")?;
        let mut slots: Vec<Option<u64>> = (2..c.fields.len())
            .map(|i| match c.int(i, "G")? {
                Some(v) if v <= 0 => Err(c.err(format!(
                    "{eid}: field {} (G{}) is {v}: a grid id is positive (leave a mid-side grid blank instead)",
                    i + 2,
                    i - 1
                ))),
                v => Ok(v.map(|v| v as u64)),
            })
            .collect::<Result<Vec<_>, _>>()?;
        while slots.last().is_some_and(Option::is_none) {
            slots.pop();
        }
        let (corners, full) = match c.name.as_str() {
            "CHEXA" => (8, 20),
            "CPENTA" => (6, 15),
            "CPYRAM" => (5, 13),
            _ => (4, 10),
        };
        // Nastran lets mid-side grids be left blank: that edge is straight and the element
        // varies linearly along it
        let quadratic = slots.len() > corners && slots.len() <= full;
        if quadratic && slots[..corners].iter().any(Option::is_none) {
            return Err(c.err(format!(
                "{eid}: a corner grid (G1-G{corners}) is blank; only mid-side grids may be"
            )));
        }
        let blanks = quadratic && (slots.len() < full || slots.iter().any(Option::is_none));
        if blanks {
            slots.resize(full, None);
        }
        let nodes: Vec<u64> = if blanks {
            slots.iter().map(|g| g.unwrap_or(0)).collect()
        } else {
            slots.iter().flatten().copied().collect()
        };
        let (kind, order): (ElementKind, &[usize]) = match (c.name.as_str(), nodes.len()) {
            ("CHEXA", 8) => (ElementKind::Hex8, &[0, 1, 2, 3, 4, 5, 6, 7]),
            // Nastran: bottom edges, vertical edges, top edges; femu: bottom, top, vertical
            ("CHEXA", 20) => (
                ElementKind::Hex20,
                &[
                    0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 16, 17, 18, 19, 12, 13, 14, 15,
                ],
            ),
            ("CPENTA", 6) => (ElementKind::Penta6, &[0, 1, 2, 3, 4, 5]),
            ("CPENTA", 15) => (
                ElementKind::Penta15,
                &[0, 1, 2, 3, 4, 5, 6, 7, 8, 12, 13, 14, 9, 10, 11],
            ),
            ("CTETRA", 4) => (ElementKind::Tet4, &[0, 1, 2, 3]),
            ("CTETRA", 10) => (ElementKind::Tet10, &[0, 1, 2, 3, 4, 5, 6, 7, 8, 9]),
            ("CPYRAM", 5) => (ElementKind::Pyramid5, &[0, 1, 2, 3, 4]),
            // base mid-edges 1-2, 2-3, 3-4, 4-1, then 1-5, 2-5, 3-5, 4-5: femu's order
            ("CPYRAM", 13) => (
                ElementKind::Pyramid13,
                &[0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12],
            ),
            (name, n) => {
                return Err(c.err(format!(
                    "{eid} has {n} grids: femu reads {} with {}",
                    name,
                    match name {
                        "CHEXA" => "8 or 20",
                        "CPENTA" => "6 or 15",
                        "CPYRAM" => "5 or 13",
                        _ => "4 or 10",
                    }
                )));
            }
        };
        for g in nodes.iter().filter(|g| **g != 0) {
            if mesh.node_index(*g).is_none() {
                return Err(c.err(format!(
                    "{eid} refers to GRID {g}, which the deck does not define"
                )));
            }
        }
        let mut ordered: Vec<u64> = order.iter().map(|&k| nodes[k]).collect();
        if blanks {
            let nc = kind.num_corners();
            for m in nc..ordered.len() {
                if ordered[m] != 0 {
                    continue;
                }
                let [a, b] = kind.edges()[m - nc];
                let (ga, gb) = (ordered[a], ordered[b]);
                let key = (ga.min(gb), ga.max(gb));
                let id = match straight.get(&key) {
                    Some(id) => *id,
                    None => {
                        next_id += 1;
                        while mesh.node_index(next_id).is_some() {
                            next_id += 1;
                        }
                        let (pa, pb) = (
                            mesh.coords()[mesh.node_index(ga).expect("checked")],
                            mesh.coords()[mesh.node_index(gb).expect("checked")],
                        );
                        let mid: [f64; 3] = std::array::from_fn(|i| 0.5 * (pa[i] + pb[i]));
                        mesh.add_node(next_id, mid).map_err(c.located())?;
                        straight.insert(key, next_id);
                        ties.push((
                            next_id,
                            ga,
                            gb,
                            format!(
                                "{} {eid} ({} line {}): blank mid-side grid between GRIDs {ga} and {gb}",
                                c.name,
                                c.path.display(),
                                c.line
                            ),
                        ));
                        next_id
                    }
                };
                ordered[m] = id;
                first_blank.get_or_insert(c);
            }
        }
        mesh.add_element(eid, kind, &ordered).map_err(c.located())?;
        element_pid.push((eid, pid, c));
    }
    Ok(Elements {
        element_pid,
        ties,
        first_blank,
    })
}
