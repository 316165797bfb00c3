//! VTK XML unstructured grids (`.vtu`) for ParaView: the mesh (all six cell types), beams, rods,
//! springs and bushings as lines (vertices when grounded) with their sections as cell data, mode
//! shapes as point vectors, element indicators as cell data, and a `.pvd` collection of several
//! files.
//!
//! Node orderings: VTK's linear and quadratic tetrahedra and hexahedra use Abaqus's order; a
//! wedge's first triangle must point away from the second in VTK and towards it in Abaqus, so
//! wedges are written with that triangle (and its mid-edge nodes) reversed.

use crate::IoError;
use femu_fem::element::ElementKind;
use femu_fem::mesh::Mesh;
use femu_fem::structural::{StructuralElement, StructuralKind};
use std::fmt::Write as _;
use std::path::Path;

/// VTK cell type and the VTK node order as positions in femu's (Abaqus's) order.
pub fn vtk_cell(kind: ElementKind) -> (u8, &'static [usize]) {
    match kind {
        ElementKind::Tet4 => (10, &[0, 1, 2, 3]),
        ElementKind::Tet10 => (24, &[0, 1, 2, 3, 4, 5, 6, 7, 8, 9]),
        ElementKind::Hex8 => (12, &[0, 1, 2, 3, 4, 5, 6, 7]),
        ElementKind::Hex20 => (
            25,
            &[
                0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16, 17, 18, 19,
            ],
        ),
        ElementKind::Penta6 => (13, &[0, 2, 1, 3, 5, 4]),
        // corners reversed per triangle; mid-edge nodes follow their edges:
        // VTK edges (0,1),(1,2),(2,0) of (0,2,1) are femu's (0,2),(2,1),(1,0) = mids 8, 7, 6
        ElementKind::Penta15 => (26, &[0, 2, 1, 3, 5, 4, 8, 7, 6, 11, 10, 9, 12, 14, 13]),
        // VTK's pyramids: base normal towards the apex, mid-edges in femu's (Nastran's) order
        ElementKind::Pyramid5 => (14, &[0, 1, 2, 3, 4]),
        ElementKind::Pyramid13 => (27, &[0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12]),
    }
}

/// Point data: a named field with 1 or 3 components per node.
#[derive(Debug, Clone)]
pub struct PointField<'a> {
    /// Field name shown in ParaView.
    pub name: &'a str,
    /// Components per node (1 or 3).
    pub components: usize,
    /// `components * nodes` values, node by node.
    pub values: &'a [f64],
}

/// Cell data: one value per element (an indicator, a parameter change).
#[derive(Debug, Clone)]
pub struct CellField<'a> {
    /// Field name.
    pub name: &'a str,
    /// One value per element, in the mesh's element order.
    pub values: &'a [f64],
}

/// The `.vtu` text of `mesh` with point and cell fields.
///
/// # Errors
/// A field whose length does not match the mesh, or a non-finite value (named).
pub fn vtu_string(
    mesh: &Mesh,
    points: &[PointField<'_>],
    cells: &[CellField<'_>],
) -> Result<String, IoError> {
    vtu_string_with(mesh, &[], points, cells)
}

/// The section values written as cell data of structural elements: `(area, I1, I2, J,
/// stiffness)`, zero where they do not apply (a spring's stiffness, a bushing's largest).
fn section_values(s: &StructuralElement) -> [f64; 6] {
    match &s.kind {
        StructuralKind::Beam(b) => [
            b.section.area,
            b.section.i1,
            b.section.i2,
            b.section.j,
            0.0,
            0.0,
        ],
        StructuralKind::Rod(r) => [r.area, 0.0, 0.0, r.j, 0.0, 0.0],
        StructuralKind::Spring(k) => [0.0, 0.0, 0.0, 0.0, k.k, 0.0],
        StructuralKind::Bushing(b) => [
            0.0,
            0.0,
            0.0,
            0.0,
            b.k.iter().fold(0.0, |m, v| v.max(m)),
            0.0,
        ],
        StructuralKind::Shell(sh) => [0.0, 0.0, 0.0, 0.0, 0.0, sh.t],
    }
}

/// [`vtu_string`] for a model with beams, rods, springs and bushings (`structural`, after the
/// mesh's cells: lines, or vertices for grounded ones), their area, `I1`, `I2`, `J` and
/// stiffness as cell data. A cell field has a value per solid element (the structural cells get
/// 0), or per solid and structural element.
///
/// # Errors
/// As [`vtu_string`].
pub fn vtu_string_with(
    mesh: &Mesh,
    structural: &[StructuralElement],
    points: &[PointField<'_>],
    cells: &[CellField<'_>],
) -> Result<String, IoError> {
    let all = mesh.element_count() + structural.len();
    let bad = |reason: String| IoError::Content {
        path: "<vtu>".into(),
        reason,
    };
    for p in points {
        if p.values.len() != p.components * mesh.node_count()
            || !(p.components == 1 || p.components == 3)
        {
            return Err(bad(format!(
                "point field {} has {} values for {} nodes x {} components",
                p.name,
                p.values.len(),
                mesh.node_count(),
                p.components
            )));
        }
        if let Some(i) = p.values.iter().position(|v| !v.is_finite()) {
            return Err(bad(format!(
                "point field {} is not finite at node {}",
                p.name,
                mesh.node_id(i / p.components)
            )));
        }
    }
    for c in cells {
        if c.values.len() != mesh.element_count() && c.values.len() != all {
            return Err(bad(format!(
                "cell field {} has {} values for {} elements",
                c.name,
                c.values.len(),
                all
            )));
        }
        if let Some(i) = c.values.iter().position(|v| !v.is_finite()) {
            let id = if i < mesh.element_count() {
                mesh.element(i).id
            } else {
                structural[i - mesh.element_count()].id
            };
            return Err(bad(format!(
                "cell field {} is not finite at element {id}",
                c.name
            )));
        }
    }
    let mut s = String::new();
    let _ = writeln!(
        s,
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n<UnstructuredGrid>"
    );
    let _ = writeln!(
        s,
        "<Piece NumberOfPoints=\"{}\" NumberOfCells=\"{}\">",
        mesh.node_count(),
        all
    );
    s.push_str(
        "<Points>\n<DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">\n",
    );
    for x in mesh.coords() {
        let _ = writeln!(s, "{:?} {:?} {:?}", x[0], x[1], x[2]);
    }
    s.push_str("</DataArray>\n</Points>\n<Cells>\n<DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">\n");
    let mut offsets = Vec::with_capacity(mesh.element_count());
    let mut types = Vec::with_capacity(mesh.element_count());
    let mut off = 0;
    for el in mesh.elements() {
        let (ty, order) = vtk_cell(el.kind);
        let ids: Vec<String> = order.iter().map(|p| el.nodes[*p].to_string()).collect();
        let _ = writeln!(s, "{}", ids.join(" "));
        off += order.len();
        offsets.push(off);
        types.push(ty);
    }
    for st in structural {
        let ids: Vec<String> = st.nodes.iter().map(ToString::to_string).collect();
        let _ = writeln!(s, "{}", ids.join(" "));
        off += st.nodes.len();
        offsets.push(off);
        // VTK_QUADRATIC_QUAD, VTK_QUADRATIC_TRIANGLE, VTK_QUAD or VTK_TRIANGLE for a shell (VTK's
        // node order is femu's),
        // VTK_QUADRATIC_EDGE for a three-node beam (ends, then middle: femu's order too),
        // VTK_LINE, or VTK_VERTEX for a grounded spring or bushing
        types.push(match (st.nodes.len(), &st.kind) {
            (3, StructuralKind::Beam(_)) => 21,
            (8, _) => 23,
            (6, _) => 22,
            (4, _) => 9,
            (3, _) => 5,
            (2, _) => 3,
            _ => 1,
        });
    }
    s.push_str("</DataArray>\n<DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n");
    for o in offsets {
        let _ = writeln!(s, "{o}");
    }
    s.push_str("</DataArray>\n<DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">\n");
    for t in types {
        let _ = writeln!(s, "{t}");
    }
    s.push_str("</DataArray>\n</Cells>\n<PointData>\n");
    let ids: Vec<String> = (0..mesh.node_count())
        .map(|i| mesh.node_id(i).to_string())
        .collect();
    let _ = writeln!(
        s,
        "<DataArray type=\"Int64\" Name=\"node_id\" format=\"ascii\">\n{}\n</DataArray>",
        ids.join(" ")
    );
    for p in points {
        let _ = writeln!(
            s,
            "<DataArray type=\"Float64\" Name=\"{}\" NumberOfComponents=\"{}\" format=\"ascii\">",
            xml_escape(p.name),
            p.components
        );
        for chunk in p.values.chunks(p.components) {
            let v: Vec<String> = chunk.iter().map(|x| format!("{x:?}")).collect();
            let _ = writeln!(s, "{}", v.join(" "));
        }
        s.push_str("</DataArray>\n");
    }
    s.push_str("</PointData>\n<CellData>\n");
    let eids: Vec<String> = mesh
        .elements()
        .map(|e| e.id)
        .chain(structural.iter().map(|s| s.id))
        .map(|id| id.to_string())
        .collect();
    let _ = writeln!(
        s,
        "<DataArray type=\"Int64\" Name=\"element_id\" format=\"ascii\">\n{}\n</DataArray>",
        eids.join(" ")
    );
    for c in cells {
        let _ = writeln!(
            s,
            "<DataArray type=\"Float64\" Name=\"{}\" format=\"ascii\">",
            xml_escape(c.name)
        );
        let pad = all - c.values.len();
        let v: Vec<String> = c
            .values
            .iter()
            .chain(std::iter::repeat_n(&0.0, pad))
            .map(|x| format!("{x:?}"))
            .collect();
        let _ = writeln!(s, "{}\n</DataArray>", v.join(" "));
    }
    if !structural.is_empty() {
        for (k, name) in ["area", "I1", "I2", "J", "stiffness", "thickness"]
            .iter()
            .enumerate()
        {
            let v: Vec<String> = std::iter::repeat_n("0".to_string(), mesh.element_count())
                .chain(
                    structural
                        .iter()
                        .map(|st| format!("{:?}", section_values(st)[k])),
                )
                .collect();
            let _ = writeln!(
                s,
                "<DataArray type=\"Float64\" Name=\"{name}\" format=\"ascii\">\n{}\n</DataArray>",
                v.join(" ")
            );
        }
    }
    s.push_str("</CellData>\n</Piece>\n</UnstructuredGrid>\n</VTKFile>\n");
    Ok(s)
}

fn xml_escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// Writes [`vtu_string`] to `path`.
///
/// # Errors
/// As [`vtu_string`], or [`IoError::Io`].
pub fn write_vtu(
    mesh: &Mesh,
    points: &[PointField<'_>],
    cells: &[CellField<'_>],
    path: impl AsRef<Path>,
) -> Result<(), IoError> {
    write_vtu_with(mesh, &[], points, cells, path)
}

/// Writes [`vtu_string_with`] to `path`.
///
/// # Errors
/// As [`vtu_string_with`], or [`IoError::Io`].
pub fn write_vtu_with(
    mesh: &Mesh,
    structural: &[StructuralElement],
    points: &[PointField<'_>],
    cells: &[CellField<'_>],
    path: impl AsRef<Path>,
) -> Result<(), IoError> {
    let text = vtu_string_with(mesh, structural, points, cells)?;
    std::fs::write(path.as_ref(), text).map_err(|e| IoError::io(path.as_ref(), e))
}

/// A ParaView collection (`.pvd`) of `.vtu` files, one per "time step" (for example one per mode,
/// with the frequency as its time value).
pub fn pvd_string(entries: &[(f64, &str)]) -> String {
    let mut s = String::from(
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"1.0\">\n<Collection>\n",
    );
    for (t, file) in entries {
        let _ = writeln!(
            s,
            "<DataSet timestep=\"{t:?}\" file=\"{}\"/>",
            xml_escape(file)
        );
    }
    s.push_str("</Collection>\n</VTKFile>\n");
    s
}
