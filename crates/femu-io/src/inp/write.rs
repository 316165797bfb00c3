//! A model written as a CalculiX deck (`write_inp`, `inp_string`).

use super::*;

/// A number for a deck field: the shortest representation that reads back exactly, or, when that
/// is longer than CalculiX's 20-character fields (17 digits with a sign or an exponent), 14
/// significant digits (relative error at most 5e-14).
pub(super) fn number_field(v: f64) -> String {
    let exact = format!("{v:?}");
    if exact.len() <= 20 {
        exact
    } else {
        format!("{v:.13e}")
    }
}

/// A CalculiX deck for `model` (nodes, elements grouped by kind, the mesh's sets, one material and
/// section per distinct material, fixed DOFs, and a `*FREQUENCY` step when `step` is given).
/// Sets named `NALL`, `EALL` and `FEMU_MAT*` are the writer's own and are regenerated, so writing
/// a deck that was read gives the same deck.
///
/// # Errors
/// An element without material.
pub fn inp_string(model: &Model, step: Option<&FrequencyStep>) -> Result<String, IoError> {
    let mesh = model.mesh();
    let unwritable = |reason: String| IoError::Content {
        path: PathBuf::from("<model>"),
        reason,
    };
    if femu_fem::model::DirectMatrix::ALL
        .iter()
        .any(|w| !model.direct_entries(*w).is_empty())
    {
        return Err(unwritable(
            "the model has direct input matrices (Nastran's K2GG, M2GG or K42GG), which femu does not write as .inp (keep the deck they came from)".into(),
        ));
    }
    if let Some(s) = model.structural().first() {
        return Err(unwritable(format!(
            "the model has {} beams, rods, springs or bushings (the first: element {}), which femu does not write as .inp (keep the deck they came from)",
            model.structural().len(),
            s.id
        )));
    }
    if let Some(e) = mesh
        .elements()
        .find(|e| matches!(e.kind, ElementKind::Pyramid5 | ElementKind::Pyramid13))
    {
        return Err(unwritable(format!(
            "element {} is a {}: Abaqus and CalculiX have no pyramid element (write the model as VTK, or keep its Nastran deck)",
            e.id, e.kind
        )));
    }
    let mut s = String::from("*HEADING\nwritten by femu\n*NODE, NSET=NALL\n");
    for i in 0..mesh.node_count() {
        let x = mesh.coords()[i];
        let _ = writeln!(
            s,
            "{}, {}, {}, {}",
            mesh.node_id(i),
            number_field(x[0]),
            number_field(x[1]),
            number_field(x[2])
        );
    }
    for (name, els) in element_blocks(model) {
        let _ = writeln!(s, "*ELEMENT, TYPE={name}, ELSET=EALL");
        for el in els.iter().map(|e| mesh.element(*e)) {
            let ids: Vec<String> = std::iter::once(el.id)
                .chain(el.nodes.iter().map(|n| mesh.node_id(*n)))
                .map(|v| v.to_string())
                .collect();
            // at most 16 entries per line; a trailing comma continues the definition
            for (c, chunk) in ids.chunks(16).enumerate() {
                let last = (c + 1) * 16 >= ids.len();
                let _ = writeln!(s, "{}{}", chunk.join(", "), if last { "" } else { "," });
            }
        }
    }
    // the sets this writer generates itself are not copied (a read deck has them)
    let generated = |name: &str| {
        let u = name.to_ascii_uppercase();
        u == "NALL" || u == "EALL" || u.starts_with("FEMU_MAT")
    };
    for (name, nodes) in mesh.node_sets().iter().filter(|(n, _)| !generated(n)) {
        let _ = writeln!(s, "*NSET, NSET={name}");
        write_ids(&mut s, nodes.iter().map(|n| mesh.node_id(*n)).collect());
    }
    for (name, els) in mesh.element_sets().iter().filter(|(n, _)| !generated(n)) {
        let _ = writeln!(s, "*ELSET, ELSET={name}");
        write_ids(&mut s, els.iter().map(|e| mesh.element(*e).id).collect());
    }
    write_materials(&mut s, model)?;
    write_point_masses(&mut s, model)?;
    // rotations of reference nodes: as CalculiX's rotational nodes, an extra node per reference
    // (ids after the mesh's) whose translations 1-3 are the reference's rotations 4-6
    let first_rot = (0..mesh.node_count())
        .map(|i| mesh.node_id(i))
        .max()
        .unwrap_or(0)
        + 1;
    let rot_id = |n: usize| -> Option<u64> {
        model
            .rotation_nodes()
            .iter()
            .position(|r| *r == n)
            .map(|k| first_rot + k as u64)
    };
    let dof = |n: usize, c: usize| -> (u64, usize) {
        if c < 3 {
            (mesh.node_id(n), c + 1)
        } else {
            (rot_id(n).expect("rotations on a rotation node"), c - 2)
        }
    };
    if !model.rotation_nodes().is_empty() {
        s.push_str("** rotational nodes: their DOFs 1-3 are the rotations of the node named\n*NODE, NSET=FEMU_ROT\n");
        for &n in model.rotation_nodes() {
            let x = mesh.coords()[n];
            let _ = writeln!(
                s,
                "{}, {}, {}, {}\n** rotations of node {}",
                rot_id(n).expect("listed"),
                number_field(x[0]),
                number_field(x[1]),
                number_field(x[2]),
                mesh.node_id(n)
            );
        }
    }
    let (rot_fixed, rot_constraints) = model.rotation_closure();
    for con in model.constraints().iter().chain(&rot_constraints) {
        let _ = writeln!(s, "** {}\n*EQUATION\n{}", con.label, 1 + con.terms.len());
        let mut terms = vec![(dof(con.dependent.0, con.dependent.1), 1.0)];
        terms.extend(con.terms.iter().map(|((n, c), w)| (dof(*n, *c), -w)));
        for chunk in terms.chunks(4) {
            let t: Vec<String> = chunk
                .iter()
                .map(|((id, d), a)| format!("{id}, {d}, {}", number_field(*a)))
                .collect();
            let _ = writeln!(s, "{}", t.join(", "));
        }
    }
    let fixed: Vec<(usize, usize)> = model.fixed_dofs().chain(rot_fixed).collect();
    if !fixed.is_empty() {
        s.push_str("*BOUNDARY\n");
        for (n, c) in fixed {
            let (id, d) = dof(n, c);
            let _ = writeln!(s, "{id}, {d}, {d}");
        }
    }
    if let Some(step) = step {
        s.push_str("*STEP\n*FREQUENCY\n");
        match step.shift_cycles2 {
            Some(shift) => {
                let _ = writeln!(s, "{}, , {}", step.count, number_field(shift));
            }
            None => {
                let _ = writeln!(s, "{}", step.count);
            }
        }
        s.push_str("*NODE FILE\nU\n*END STEP\n");
    }
    Ok(s)
}

/// Writes [`inp_string`] to `path`.
///
/// # Errors
/// As [`inp_string`], or [`IoError::Io`].
pub fn write_inp(
    model: &Model,
    step: Option<&FrequencyStep>,
    path: impl AsRef<Path>,
) -> Result<(), IoError> {
    let text = inp_string(model, step)?;
    std::fs::write(path.as_ref(), text).map_err(|e| IoError::io(path.as_ref(), e))
}

/// The elements in the order they are written: by kind, bricks with incompatible modes as their
/// own C3D8I block; each block's Abaqus name and internal element indices.
fn element_blocks(model: &Model) -> Vec<(&'static str, Vec<usize>)> {
    let mesh = model.mesh();
    let mut blocks = Vec::new();
    for kind in femu_fem::element::ALL_KINDS {
        for formulation in [Formulation::Full, Formulation::IncompatibleModes] {
            let els: Vec<usize> = mesh
                .elements()
                .filter(|e| e.kind == kind && model.formulation(e.index) == formulation)
                .map(|e| e.index)
                .collect();
            if !els.is_empty() {
                let name = match formulation {
                    Formulation::IncompatibleModes => "C3D8I",
                    Formulation::Full => kind.abaqus_name(),
                };
                blocks.push((name, els));
            }
        }
    }
    blocks
}

/// Ids, 16 to a line.
fn write_ids(s: &mut String, ids: Vec<u64>) {
    for chunk in ids.chunks(16) {
        let t: Vec<String> = chunk.iter().map(|v| v.to_string()).collect();
        let _ = writeln!(s, "{}", t.join(", "));
    }
}

/// An element set, a `*MATERIAL` and a `*SOLID SECTION` per distinct material.
fn write_materials(s: &mut String, model: &Model) -> Result<(), IoError> {
    let mesh = model.mesh();
    let unwritable = |reason: String| IoError::Content {
        path: PathBuf::from("<model>"),
        reason,
    };
    // distinct materials, in order of first use in the written element order (so that a deck read
    // back and written again is the same text)
    let mut distinct: Vec<(Material, Vec<u64>)> = Vec::new();
    let written_order = element_blocks(model).into_iter().flat_map(|(_, els)| els);
    for e in written_order {
        let m = model
            .material_of(e)
            .map_err(|e| unwritable(e.to_string()))?;
        let id = mesh.element(e).id;
        match distinct.iter_mut().find(|(d, _)| d == m) {
            Some(d) => d.1.push(id),
            None => distinct.push((m.clone(), vec![id])),
        }
    }
    for (i, (m, ids)) in distinct.iter().enumerate() {
        // the material's own name when it is a valid Abaqus name not used before
        let clean: String = m
            .name
            .chars()
            .map(|c| {
                if c.is_ascii_alphanumeric() || c == '_' || c == '-' {
                    c
                } else {
                    '_'
                }
            })
            .collect();
        let taken = distinct[..i]
            .iter()
            .any(|(d, _)| d.name.eq_ignore_ascii_case(&m.name));
        let valid = clean.starts_with(|c: char| c.is_ascii_alphabetic()) && clean.len() <= 80;
        let name = if valid && !taken {
            clean
        } else {
            format!("FEMU_MAT{}", i + 1)
        };
        let _ = writeln!(s, "*ELSET, ELSET=FEMU_MAT{}", i + 1);
        write_ids(s, ids.clone());
        let elastic = match &m.elasticity {
            Elasticity::Isotropic { e, nu } => {
                format!("*ELASTIC\n{}, {}", number_field(*e), number_field(*nu))
            }
            // the 21 constants in the global axes: the upper triangle column by column (11, 22,
            // 33, 12, 13, 23), eight to a line
            Elasticity::Anisotropic(d) => {
                let values: Vec<String> = (0..6)
                    .flat_map(|j| (0..=j).map(move |i| number_field(d[i][j])))
                    .collect();
                let lines: Vec<String> = values.chunks(8).map(|c| c.join(", ")).collect();
                format!("*ELASTIC, TYPE=ANISO\n{}", lines.join(",\n"))
            }
        };
        let _ = writeln!(
            s,
            "*MATERIAL, NAME={name}\n{elastic}\n*DENSITY\n{}",
            number_field(m.density)
        );
        let _ = writeln!(
            s,
            "*SOLID SECTION, ELSET=FEMU_MAT{}, MATERIAL={name}",
            i + 1
        );
    }
    Ok(())
}

/// The point masses, and the rigid masses without offset or inertia, as MASS elements.
fn write_point_masses(s: &mut String, model: &Model) -> Result<(), IoError> {
    let mesh = model.mesh();
    let unwritable = |reason: String| IoError::Content {
        path: PathBuf::from("<model>"),
        reason,
    };
    // point masses: one MASS element each (ids after the solids'), a *MASS per element; a rigid
    // mass without offset or inertia is one too
    let first_id = mesh.elements().map(|e| e.id).max().unwrap_or(0) + 1;
    let mut masses: Vec<femu_fem::model::PointMass> = model.point_masses().to_vec();
    for r in model.rigid_masses() {
        let m = r.mass;
        let plain =
            (0..6).all(|i| (0..6).all(|k| r.matrix[i][k] == if i == k && i < 3 { m } else { 0.0 }));
        if !plain
            || r.offset
                .iter()
                .chain(r.inertia.iter().flatten())
                .any(|v| *v != 0.0)
        {
            return Err(unwritable(format!(
                "the rigid mass on node {} has an offset, rotary inertia or a general mass matrix, which CalculiX's *MASS cannot state",
                mesh.node_id(r.node)
            )));
        }
        masses.push(femu_fem::model::PointMass {
            node: r.node,
            mass: [[m, 0.0, 0.0], [0.0, m, 0.0], [0.0, 0.0, m]],
        });
    }
    for (k, p) in masses.iter().enumerate() {
        let m = p.mass[0][0];
        let isotropic =
            (0..3).all(|i| (0..3).all(|j| p.mass[i][j] == if i == j { m } else { 0.0 }));
        if !isotropic {
            return Err(IoError::Content {
                path: PathBuf::from("(deck being written)"),
                reason: format!(
                    "the point mass on node {} differs by direction ({:?}): *MASS gives one mass for all three",
                    mesh.node_id(p.node),
                    p.mass
                ),
            });
        }
        let id = first_id + k as u64;
        let _ = writeln!(
            s,
            "*ELEMENT, TYPE=MASS, ELSET=FEMU_MASS{id}\n{id}, {}\n*MASS, ELSET=FEMU_MASS{id}\n{}",
            mesh.node_id(p.node),
            number_field(m)
        );
    }
    Ok(())
}
