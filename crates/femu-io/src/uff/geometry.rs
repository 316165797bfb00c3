//! Datasets of the test geometry: nodes (15, 2411), elements (2412, with femu's node orders),
//! permanent groups (2477) and trace lines (82).

use super::*;

pub(super) const UNV_TET10: [usize; 10] = [0, 2, 4, 9, 1, 3, 5, 6, 7, 8];
/// Wedge 113: bottom loop 0-5, vertical mid-edges 6 7 8, top loop 9-14.
pub(super) const UNV_PENTA15: [usize; 15] = [0, 2, 4, 9, 11, 13, 1, 3, 5, 10, 12, 14, 6, 7, 8];
/// Brick 116: bottom loop 0-7, vertical mid-edges 8-11, top loop 12-19.
pub(super) const UNV_HEX20: [usize; 20] = [
    0, 2, 4, 6, 12, 14, 16, 18, 1, 3, 5, 7, 13, 15, 17, 19, 8, 9, 10, 11,
];

/// Beam descriptors carry an extra orientation record in dataset 2412.
pub(super) fn is_beam(descriptor: i64) -> bool {
    matches!(descriptor, 11 | 21..=24)
}

pub(super) fn parse_2477(
    path: &Path,
    body: &[(usize, &str)],
    out: &mut Universal,
) -> Result<(), IoError> {
    let mut k = 0;
    while k < body.len() {
        let (ln, l) = body[k];
        if l.trim().is_empty() {
            k += 1;
            continue;
        }
        let h = ints(path, ln, l, 8)?;
        let (number, count) = (h[0], h[7]);
        if !(0..=100_000_000).contains(&count) {
            return Err(perr(path, ln, format!("group {number}: {count} entities")));
        }
        let name = body
            .get(k + 1)
            .ok_or_else(|| perr(path, ln, format!("group {number} without its name")))?
            .1
            .trim()
            .to_string();
        k += 2;
        let mut group = UffGroup {
            number,
            name,
            nodes: Vec::new(),
            elements: Vec::new(),
        };
        let mut read = 0;
        let mut other = 0;
        while read < count {
            let (ln2, l2) = *body.get(k).ok_or_else(|| {
                perr(
                    path,
                    ln,
                    format!("group {number}: {count} entities announced, {read} found"),
                )
            })?;
            let v = ints(path, ln2, l2, 4)?;
            for q in v.chunks(4) {
                if q.len() < 4 {
                    return Err(perr(
                        path,
                        ln2,
                        "an entity needs 4 integers (type, tag, 0, 0)",
                    ));
                }
                if read == count {
                    return Err(perr(
                        path,
                        ln2,
                        format!("group {number}: more than the {count} entities announced"),
                    ));
                }
                if q[1] <= 0 {
                    return Err(perr(
                        path,
                        ln2,
                        format!("entity tag {} must be positive", q[1]),
                    ));
                }
                match q[0] {
                    7 => group.nodes.push(q[1] as u64),
                    8 => group.elements.push(q[1] as u64),
                    _ => other += 1,
                }
                read += 1;
            }
            k += 1;
        }
        if other > 0 {
            out.warnings.push(Warning {
                path: path.to_path_buf(),
                line: ln,
                message: format!(
                    "group {}: {other} entities neither nodes nor elements skipped",
                    group.name
                ),
            });
        }
        out.groups.push(group);
    }
    Ok(())
}

/// Node `id`'s coordinates `x`, given in definition system `cs`, in global coordinates: the
/// system must have been defined before (dataset 18 precedes the nodes in every export seen).
fn in_global(
    path: &Path,
    ln: usize,
    out: &Universal,
    id: i64,
    cs: i64,
    x: [f64; 3],
) -> Result<[f64; 3], IoError> {
    // 0, and 1 when the file defines no system 1 (I-DEAS's and Gmsh's label of the global
    // system), are the global system; systems come from datasets 18 and 2420
    let Some(sys) = out.coordinate_systems.get(&cs).filter(|_| cs != 0) else {
        if cs > 1 {
            return Err(perr(
                path,
                ln,
                format!(
                    "node {id} is defined in coordinate system {cs}, which no dataset 18 or 2420 before it defines"
                ),
            ));
        }
        return Ok(x);
    };
    if !(0..=2).contains(&sys.kind) {
        return Err(perr(
            path,
            ln,
            format!(
                "node {id} is defined in coordinate system {cs} ({}) of kind {}: expected 0 (cartesian), 1 (cylindrical) or 2 (spherical)",
                sys.name, sys.kind
            ),
        ));
    }
    Ok(sys.point_to_global(x))
}

/// Adds node `id` (datasets 15 and 2411) with coordinates `x` in its definition system
/// `systems[0]`, made global, and records its displacement system `systems[1]` unless global.
fn push_node(
    path: &Path,
    ln: usize,
    out: &mut Universal,
    id: i64,
    systems: [i64; 2],
    x: [f64; 3],
) -> Result<(), IoError> {
    let x = in_global(path, ln, out, id, systems[0], x)?;
    let displacement = systems[1];
    if displacement > 1 || out.coordinate_systems.contains_key(&displacement) {
        out.displacement_systems.insert(id as u64, displacement);
    }
    out.nodes.push(UffNode { id: id as u64, x });
    Ok(())
}

/// Dataset 18 (coordinate systems, defined by three points: the origin, a point on the local x
/// axis, a point in the local xz plane), relative to the global system.
pub(super) fn parse_18(
    path: &Path,
    body: &[(usize, &str)],
    out: &mut Universal,
) -> Result<(), IoError> {
    let lines: Vec<(usize, &str)> = body.to_vec();
    let mut k = 0;
    while k < lines.len() {
        let (ln, l) = lines[k];
        if l.trim().is_empty() {
            k += 1;
            continue;
        }
        if k + 3 >= lines.len() {
            return Err(perr(
                path,
                ln,
                "dataset 18: a coordinate system needs 4 records",
            ));
        }
        let h = ints(path, ln, l, 5)?;
        let (number, kind, reference) = (h[0], h[1], h[2]);
        let name = lines.get(k + 1).map_or("", |x| x.1).trim().to_string();
        let mut v = nums(path, lines[k + 2].0, lines[k + 2].1, 6)?;
        let (ln3, l3) = *lines
            .get(k + 3)
            .ok_or_else(|| perr(path, ln, "dataset 18: a coordinate system needs 4 records"))?;
        v.extend(nums(path, ln3, l3, 3)?);
        if reference != 0 {
            return Err(perr(
                path,
                ln,
                format!(
                    "coordinate system {number} is defined relative to system {reference}: femu reads systems relative to the global one only"
                ),
            ));
        }
        let a = [v[0], v[1], v[2]];
        let sub = |p: [f64; 3]| [p[0] - a[0], p[1] - a[1], p[2] - a[2]];
        let dot = |p: [f64; 3], q: [f64; 3]| p[0] * q[0] + p[1] * q[1] + p[2] * q[2];
        let unit = |p: [f64; 3]| {
            let n = dot(p, p).sqrt();
            (n > 0.0).then(|| [p[0] / n, p[1] / n, p[2] / n])
        };
        let degenerate = || {
            perr(
                path,
                ln3,
                format!(
                    "coordinate system {number}: its three points do not define axes (coincident or collinear)"
                ),
            )
        };
        let ex = unit(sub([v[3], v[4], v[5]])).ok_or_else(degenerate)?;
        let c = sub([v[6], v[7], v[8]]);
        let cx = dot(c, ex);
        let ez = unit([c[0] - cx * ex[0], c[1] - cx * ex[1], c[2] - cx * ex[2]])
            .ok_or_else(degenerate)?;
        let ey = [
            ez[1] * ex[2] - ez[2] * ex[1],
            ez[2] * ex[0] - ez[0] * ex[2],
            ez[0] * ex[1] - ez[1] * ex[0],
        ];
        out.coordinate_systems.insert(
            number,
            CoordinateSystem {
                name,
                kind,
                origin: a,
                axes: std::array::from_fn(|i| [ex[i], ey[i], ez[i]]),
            },
        );
        k += 4;
    }
    Ok(())
}

/// Dataset 2420 (coordinate systems of a part): per system a label, kind and colour, a name
/// and a 4 x 3 matrix whose rows 1-3 are the local axes in global components and row 4 the
/// origin (`x_global = x_local R + origin`, the row-vector form I-DEAS and NX write).
pub(super) fn parse_2420(
    path: &Path,
    body: &[(usize, &str)],
    out: &mut Universal,
) -> Result<(), IoError> {
    if body.len() < 2 {
        return Err(perr(
            path,
            body.first().map_or(0, |b| b.0),
            "dataset 2420 needs a part label and a part name",
        ));
    }
    let mut k = 2;
    while k < body.len() {
        let (ln, l) = body[k];
        if l.trim().is_empty() {
            k += 1;
            continue;
        }
        if k + 5 >= body.len() {
            return Err(perr(
                path,
                ln,
                "dataset 2420: a coordinate system needs 6 records (label, name, 4 matrix rows)",
            ));
        }
        let h = ints(path, ln, l, 2)?;
        let (number, kind) = (h[0], h[1]);
        if !(0..=2).contains(&kind) {
            return Err(perr(
                path,
                ln,
                format!(
                    "coordinate system {number} has kind {kind}: expected 0 (cartesian), 1 (cylindrical) or 2 (spherical)"
                ),
            ));
        }
        let name = body[k + 1].1.trim().to_string();
        let mut rows = [[0.0; 3]; 4];
        for (r, row) in rows.iter_mut().enumerate() {
            let (lr, tr) = body[k + 2 + r];
            let v = nums(path, lr, tr, 3)?;
            *row = [v[0], v[1], v[2]];
        }
        // the axes must be orthonormal (to 1e-6: files print 16 digits, some fewer)
        for a in 0..3 {
            for b in 0..3 {
                let d: f64 = (0..3).map(|i| rows[a][i] * rows[b][i]).sum();
                let want = if a == b { 1.0 } else { 0.0 };
                if (d - want).abs() > 1e-6 {
                    return Err(perr(
                        path,
                        body[k + 2].0,
                        format!(
                            "coordinate system {number}: rows 1-3 of its matrix are not orthonormal axes (row {} . row {} = {d:.6})",
                            a + 1,
                            b + 1
                        ),
                    ));
                }
            }
        }
        out.coordinate_systems.insert(
            number,
            CoordinateSystem {
                name,
                kind,
                origin: rows[3],
                axes: std::array::from_fn(|i| [rows[0][i], rows[1][i], rows[2][i]]),
            },
        );
        k += 6;
    }
    Ok(())
}

/// Dataset 82.
pub(super) fn parse_82(
    path: &Path,
    body: &[(usize, &str)],
    out: &mut Universal,
) -> Result<(), IoError> {
    if body.len() < 2 {
        return Err(perr(
            path,
            body.first().map_or(0, |b| b.0),
            "dataset 82 needs a header, an identification line and node labels",
        ));
    }
    let (ln, l) = body[0];
    let h = ints(path, ln, l, 3)?;
    let (number, count, color) = (h[0], h[1], h[2]);
    let mut nodes = Vec::new();
    for &(ln2, l2) in &body[2..] {
        if l2.trim().is_empty() {
            continue;
        }
        for v in ints(path, ln2, l2, 1)? {
            if v < 0 {
                return Err(perr(
                    path,
                    ln2,
                    format!("node label {v} must not be negative"),
                ));
            }
            nodes.push(v as u64);
        }
    }
    // Writers disagree on the count: LMS TestLab announces fewer labels than it writes and pads
    // the record with zeros (0 means "lift the pen"). Labels beyond the count that are all zero
    // are padding; otherwise every label is kept, with a warning.
    let announced = usize::try_from(count).unwrap_or(0);
    if nodes.len() > announced && nodes[announced..].iter().all(|v| *v == 0) {
        nodes.truncate(announced);
    } else if nodes.len() != announced {
        out.warnings.push(Warning {
            path: path.to_path_buf(),
            line: ln,
            message: format!(
                "trace line {number}: {count} node labels announced, {} found: all {} kept",
                nodes.len(),
                nodes.len()
            ),
        });
    }
    out.trace_lines.push(UffTraceLine {
        number,
        color,
        id: body[1].1.trim_end().to_string(),
        nodes,
    });
    Ok(())
}

pub(super) fn parse_15(
    path: &Path,
    body: &[(usize, &str)],
    out: &mut Universal,
) -> Result<(), IoError> {
    for &(ln, l) in body {
        if l.trim().is_empty() {
            continue;
        }
        let t: Vec<&str> = l.split_whitespace().collect();
        if t.len() < 7 {
            return Err(perr(
                path,
                ln,
                format!("a dataset 15 node needs 7 fields, found {}", t.len()),
            ));
        }
        let id = int(path, ln, t[0])?;
        if id <= 0 {
            return Err(perr(path, ln, format!("node label {id} must be positive")));
        }
        let x = [
            num(path, ln, t[4])?,
            num(path, ln, t[5])?,
            num(path, ln, t[6])?,
        ];
        let systems = [int(path, ln, t[1])?, int(path, ln, t[2])?];
        push_node(path, ln, out, id, systems, x)?;
    }
    Ok(())
}

pub(super) fn parse_2411(
    path: &Path,
    body: &[(usize, &str)],
    out: &mut Universal,
) -> Result<(), IoError> {
    let lines: Vec<(usize, &str)> = body
        .iter()
        .copied()
        .filter(|(_, l)| !l.trim().is_empty())
        .collect();
    if !lines.len().is_multiple_of(2) {
        return Err(perr(
            path,
            lines.last().map_or(0, |l| l.0),
            "dataset 2411: a node without its coordinate record",
        ));
    }
    for pair in lines.chunks(2) {
        let (ln, l) = pair[0];
        let h = ints(path, ln, l, 4)?;
        if h[0] <= 0 {
            return Err(perr(
                path,
                ln,
                format!("node label {} must be positive", h[0]),
            ));
        }
        let x = nums(path, pair[1].0, pair[1].1, 3)?;
        push_node(path, ln, out, h[0], [h[1], h[2]], [x[0], x[1], x[2]])?;
    }
    out.nodes_2411 = true;
    Ok(())
}

pub(super) fn parse_2412(
    path: &Path,
    body: &[(usize, &str)],
    out: &mut Universal,
) -> Result<(), IoError> {
    let lines: Vec<(usize, &str)> = body
        .iter()
        .copied()
        .filter(|(_, l)| !l.trim().is_empty())
        .collect();
    let mut k = 0;
    while k < lines.len() {
        let (ln, l) = lines[k];
        let h = ints(path, ln, l, 6)?;
        let (id, descriptor, count) = (h[0], h[1], h[5]);
        if id <= 0 || !(1..=27).contains(&count) {
            return Err(perr(
                path,
                ln,
                format!("element {id}: label must be positive and node count 1-27, found {count}"),
            ));
        }
        k += 1;
        if is_beam(descriptor) {
            k += 1; // orientation record
        }
        let mut nodes = Vec::with_capacity(count as usize);
        while nodes.len() < count as usize {
            let (ln2, l2) = *lines.get(k).ok_or_else(|| {
                perr(
                    path,
                    ln,
                    format!(
                        "element {id}: {count} node labels expected, found {}",
                        nodes.len()
                    ),
                )
            })?;
            for v in ints(path, ln2, l2, 1)? {
                if v <= 0 {
                    return Err(perr(
                        path,
                        ln2,
                        format!("element {id}: node label {v} must be positive"),
                    ));
                }
                nodes.push(v as u64);
            }
            k += 1;
        }
        if nodes.len() != count as usize {
            return Err(perr(
                path,
                ln,
                format!(
                    "element {id}: {count} node labels expected, found {}",
                    nodes.len()
                ),
            ));
        }
        out.elements.push(UffElement {
            id: id as u64,
            descriptor,
            nodes,
        });
    }
    Ok(())
}
