//! Gmsh `.msh` meshes: format 4.1 (ASCII) and 2.2 (ASCII). Volume elements of types 4 (tet4),
//! 11 (tet10), 5 (hex8), 17 (hex20), 6 (prism6) and 18 (prism15) become femu elements, their node
//! orderings converted to femu's (Abaqus) ones; physical groups of volumes become element sets
//! and node sets, physical groups of surfaces, curves and points become node sets (the nodes of
//! their elements: where boundary conditions and sensors go). Lower-dimensional elements are not
//! elements of the model. Binary files are refused with a message (write ASCII with
//! `gmsh -save -format msh41` or `Mesh.Binary = 0`).

use crate::{IoError, Warning};
use femu_fem::element::ElementKind;
use femu_fem::mesh::Mesh;
use std::collections::BTreeMap;
use std::path::Path;

/// A mesh read from Gmsh, with what was noticed on the way.
#[derive(Debug, Clone)]
pub struct GmshMesh {
    /// The mesh (element sets and node sets from physical groups, named by their physical name
    /// or `"physical<tag>"`).
    pub mesh: Mesh,
    /// Warnings (skipped sections, element types without a femu equivalent).
    pub warnings: Vec<Warning>,
}

/// An element as read: Gmsh type, tag, node tags, (entity dimension, physical tags), line.
type RawElement = (i64, u64, Vec<u64>, (i64, Vec<i64>), usize);

/// Gmsh to femu (Abaqus) node order: `femu[k] = gmsh[PERM[k]]`.
const TET10: [usize; 10] = [0, 1, 2, 3, 4, 5, 6, 7, 9, 8];
const HEX20: [usize; 20] = [
    0, 1, 2, 3, 4, 5, 6, 7, 8, 11, 13, 9, 16, 18, 19, 17, 10, 12, 14, 15,
];
const PRISM15: [usize; 15] = [0, 1, 2, 3, 4, 5, 6, 9, 7, 12, 14, 13, 8, 10, 11];

/// Nodes per element of a Gmsh type (0 for types femu does not know), and its femu kind.
fn gmsh_type(t: i64) -> Option<(usize, Option<ElementKind>)> {
    Some(match t {
        4 => (4, Some(ElementKind::Tet4)),
        11 => (10, Some(ElementKind::Tet10)),
        5 => (8, Some(ElementKind::Hex8)),
        17 => (20, Some(ElementKind::Hex20)),
        6 => (6, Some(ElementKind::Penta6)),
        18 => (15, Some(ElementKind::Penta15)),
        15 => (1, None),
        1 => (2, None),
        8 => (3, None),
        2 => (3, None),
        9 => (6, None),
        3 => (4, None),
        16 => (8, None),
        10 => (9, None),
        7 => (5, None),
        _ => return None,
    })
}

fn to_femu(kind: ElementKind, g: &[u64]) -> Vec<u64> {
    match kind {
        ElementKind::Tet10 => TET10.iter().map(|&i| g[i]).collect(),
        ElementKind::Hex20 => HEX20.iter().map(|&i| g[i]).collect(),
        ElementKind::Penta15 => PRISM15.iter().map(|&i| g[i]).collect(),
        _ => g.to_vec(),
    }
}

/// Lines with their 1-based numbers, CR removed.
struct Lines<'a> {
    lines: Vec<&'a str>,
    at: usize,
    path: &'a Path,
}

impl<'a> Lines<'a> {
    fn next(&mut self, what: &str) -> Result<(usize, &'a str), IoError> {
        while self.at < self.lines.len() {
            let l = self.lines[self.at].trim();
            self.at += 1;
            if !l.is_empty() {
                return Ok((self.at, l));
            }
        }
        Err(self.err(self.lines.len(), format!("file ends inside {what}")))
    }

    fn err(&self, line: usize, reason: String) -> IoError {
        IoError::Parse {
            path: self.path.to_path_buf(),
            line,
            reason,
        }
    }

    fn ints(&mut self, what: &str, want: usize) -> Result<(usize, Vec<i64>), IoError> {
        let (ln, l) = self.next(what)?;
        let v: Vec<i64> = l
            .split_whitespace()
            .map(|t| {
                t.parse::<i64>()
                    .map_err(|_| self.err(ln, format!("{what}: '{t}' is not an integer")))
            })
            .collect::<Result<_, _>>()?;
        if v.len() < want {
            return Err(self.err(
                ln,
                format!("{what}: expected {want} integers, found {}", v.len()),
            ));
        }
        Ok((ln, v))
    }

    fn floats(&mut self, what: &str, want: usize) -> Result<(usize, Vec<f64>), IoError> {
        let (ln, l) = self.next(what)?;
        let v: Vec<f64> = l
            .split_whitespace()
            .map(|t| match t.parse::<f64>() {
                Ok(x) if x.is_finite() => Ok(x),
                _ => Err(self.err(ln, format!("{what}: '{t}' is not a finite number"))),
            })
            .collect::<Result<_, _>>()?;
        if v.len() < want {
            return Err(self.err(
                ln,
                format!("{what}: expected {want} numbers, found {}", v.len()),
            ));
        }
        Ok((ln, v))
    }

    fn expect_end(&mut self, section: &str) -> Result<(), IoError> {
        let (ln, l) = self.next(section)?;
        if l != format!("$End{section}") {
            return Err(self.err(ln, format!("expected $End{section}, found '{l}'")));
        }
        Ok(())
    }

    fn skip_section(&mut self, name: &str) -> Result<(), IoError> {
        loop {
            let (_, l) = self.next(name)?;
            if l == format!("$End{name}") {
                return Ok(());
            }
        }
    }
}

/// Reads a `.msh` file.
///
/// # Errors
/// [`IoError::Io`] for an unreadable file, [`IoError::Parse`] with the line for malformed content
/// or a binary file, [`IoError::Model`] with the line for an element femu refuses (a repeated id,
/// a missing node).
pub fn read_msh(path: impl AsRef<Path>) -> Result<GmshMesh, IoError> {
    let path = path.as_ref();
    let bytes = std::fs::read(path).map_err(|e| IoError::io(path, e))?;
    let text = String::from_utf8_lossy(&bytes);
    parse_msh(&text, path)
}

/// Parses `.msh` text (`path` names it in errors).
///
/// # Errors
/// As [`read_msh`].
pub fn parse_msh(text: &str, path: &Path) -> Result<GmshMesh, IoError> {
    let mut l = Lines {
        lines: text.lines().map(|s| s.trim_end_matches('\r')).collect(),
        at: 0,
        path,
    };
    let mut warnings = Vec::new();
    let mut version = None;
    let mut names: BTreeMap<(i64, i64), String> = BTreeMap::new();
    // (dim, entity tag) -> physical tags
    let mut entity_phys: BTreeMap<(i64, i64), Vec<i64>> = BTreeMap::new();
    let mut nodes: Vec<(u64, [f64; 3], usize)> = Vec::new();
    // (gmsh type, tag, node tags, physical (dim, tags), line)
    let mut elements: Vec<RawElement> = Vec::new();
    while l.at < l.lines.len() {
        let Ok((ln, head)) = l.next("the file") else {
            break;
        };
        match head {
            "$MeshFormat" => {
                let (ln2, f) = l.next("$MeshFormat")?;
                let t: Vec<&str> = f.split_whitespace().collect();
                if t.len() < 3 {
                    return Err(l.err(ln2, "expected 'version file-type data-size'".into()));
                }
                let v = t[0];
                if t[1] != "0" {
                    return Err(l.err(ln2, "binary .msh is not read by femu: save it as ASCII (gmsh -save -format msh41, or Mesh.Binary = 0)".into()));
                }
                if !(v.starts_with("4.1") || v.starts_with("2.2")) {
                    return Err(l.err(ln2, format!("format {v}: femu reads 4.1 and 2.2")));
                }
                version = Some(if v.starts_with('4') { 4 } else { 2 });
                l.expect_end("MeshFormat")?;
            }
            "$PhysicalNames" => {
                let (_, n) = l.ints("$PhysicalNames", 1)?;
                for _ in 0..n[0].max(0) {
                    let (ln2, s) = l.next("$PhysicalNames")?;
                    let mut it = s.splitn(3, char::is_whitespace);
                    let dim = it.next().and_then(|t| t.parse::<i64>().ok());
                    let tag = it.next().and_then(|t| t.trim().parse::<i64>().ok());
                    let name = it.next().map(|t| t.trim().trim_matches('"').to_string());
                    match (dim, tag, name) {
                        (Some(d), Some(t), Some(nm)) => {
                            names.insert((d, t), nm);
                        }
                        _ => {
                            return Err(
                                l.err(ln2, format!("expected 'dim tag \"name\"', found '{s}'"))
                            );
                        }
                    }
                }
                l.expect_end("PhysicalNames")?;
            }
            "$Entities" => {
                let (_, c) = l.ints("$Entities", 4)?;
                for (dim, count) in c.iter().take(4).enumerate() {
                    for _ in 0..*count {
                        let (ln2, s) = l.next("$Entities")?;
                        let t: Vec<&str> = s.split_whitespace().collect();
                        // points: tag x y z nphys phys...; others: tag 6 bounds nphys phys... nb b...
                        let at = if dim == 0 { 4 } else { 7 };
                        let parse = |k: usize| t.get(k).and_then(|x| x.parse::<i64>().ok());
                        let (Some(tag), Some(np)) = (parse(0), parse(at)) else {
                            return Err(l.err(ln2, format!("malformed entity line '{s}'")));
                        };
                        let phys: Option<Vec<i64>> =
                            (0..np.max(0) as usize).map(|k| parse(at + 1 + k)).collect();
                        let phys = phys.ok_or_else(|| {
                            l.err(ln2, format!("malformed physical tags in '{s}'"))
                        })?;
                        entity_phys.insert(
                            (dim as i64, tag),
                            phys.into_iter().map(|p| p.abs()).collect(),
                        );
                    }
                }
                l.expect_end("Entities")?;
            }
            "$Nodes" => match version {
                Some(4) => {
                    let (_, h) = l.ints("$Nodes", 4)?;
                    for _ in 0..h[0] {
                        let (ln2, b) = l.ints("a node block header", 4)?;
                        if b[2] != 0 {
                            return Err(l.err(
                                ln2,
                                "parametric node coordinates are not read by femu".into(),
                            ));
                        }
                        let mut tags = Vec::with_capacity(b[3].max(0) as usize);
                        for _ in 0..b[3] {
                            let (ln3, t) = l.ints("a node tag", 1)?;
                            if t[0] <= 0 {
                                return Err(
                                    l.err(ln3, format!("node tag {} must be positive", t[0]))
                                );
                            }
                            tags.push((t[0] as u64, ln3));
                        }
                        for (tag, _) in tags {
                            let (ln3, x) = l.floats("node coordinates", 3)?;
                            nodes.push((tag, [x[0], x[1], x[2]], ln3));
                        }
                    }
                    l.expect_end("Nodes")?;
                }
                Some(_) => {
                    let (_, h) = l.ints("$Nodes", 1)?;
                    for _ in 0..h[0] {
                        let (ln2, s) = l.next("$Nodes")?;
                        let t: Vec<&str> = s.split_whitespace().collect();
                        let id = t
                            .first()
                            .and_then(|x| x.parse::<i64>().ok())
                            .filter(|v| *v > 0);
                        let x: Option<Vec<f64>> = t.get(1..4).map(|c| {
                            c.iter()
                                .filter_map(|v| v.parse::<f64>().ok().filter(|f| f.is_finite()))
                                .collect()
                        });
                        match (id, x) {
                            (Some(id), Some(x)) if x.len() == 3 => {
                                nodes.push((id as u64, [x[0], x[1], x[2]], ln2))
                            }
                            _ => {
                                return Err(l.err(
                                    ln2,
                                    format!(
                                        "expected 'tag x y z' with a positive tag, found '{s}'"
                                    ),
                                ));
                            }
                        }
                    }
                    l.expect_end("Nodes")?;
                }
                None => return Err(l.err(ln, "$Nodes before $MeshFormat".into())),
            },
            "$Elements" => {
                match version {
                    Some(4) => {
                        let (_, h) = l.ints("$Elements", 4)?;
                        for _ in 0..h[0] {
                            let (ln2, b) = l.ints("an element block header", 4)?;
                            let (dim, entity, ty, count) = (b[0], b[1], b[2], b[3]);
                            let (nn, _) = gmsh_type(ty)
                                .ok_or_else(|| l.err(ln2, format!("unknown element type {ty}")))?;
                            let phys = entity_phys.get(&(dim, entity)).cloned().unwrap_or_default();
                            for _ in 0..count {
                                let (ln3, e) = l.ints("an element", nn + 1)?;
                                if e.len() != nn + 1 || e.iter().any(|v| *v <= 0) {
                                    return Err(l.err(ln3, format!("element type {ty} needs a positive tag and {nn} positive node tags, found {} values", e.len())));
                                }
                                elements.push((
                                    ty,
                                    e[0] as u64,
                                    e[1..].iter().map(|v| *v as u64).collect(),
                                    (dim, phys.clone()),
                                    ln3,
                                ));
                            }
                        }
                        l.expect_end("Elements")?;
                    }
                    Some(_) => {
                        let (_, h) = l.ints("$Elements", 1)?;
                        for _ in 0..h[0] {
                            let (ln2, e) = l.ints("an element", 3)?;
                            let (tag, ty, ntags) = (e[0], e[1], e[2].max(0) as usize);
                            let (nn, kind) = gmsh_type(ty)
                                .ok_or_else(|| l.err(ln2, format!("unknown element type {ty}")))?;
                            if e.len() != 3 + ntags + nn || tag <= 0 {
                                return Err(l.err(ln2, format!("element type {ty} with {ntags} tags needs {} values, found {}", 3 + ntags + nn, e.len())));
                            }
                            let phys = if ntags > 0 { vec![e[3]] } else { vec![] };
                            let dim = match (kind, nn) {
                                (Some(_), _) => 3,
                                (None, 1) => 0,
                                (None, 2) | (None, 3) if ty == 1 || ty == 8 => 1,
                                _ => 2,
                            };
                            let ids: Vec<i64> = e[3 + ntags..].to_vec();
                            if ids.iter().any(|v| *v <= 0) {
                                return Err(l.err(ln2, "node tags must be positive".into()));
                            }
                            elements.push((
                                ty,
                                tag as u64,
                                ids.iter().map(|v| *v as u64).collect(),
                                (dim, phys),
                                ln2,
                            ));
                        }
                        l.expect_end("Elements")?;
                    }
                    None => return Err(l.err(ln, "$Elements before $MeshFormat".into())),
                }
            }
            s if s.starts_with('$') && !s.starts_with("$End") => {
                let name = s[1..].to_string();
                warnings.push(Warning {
                    path: path.to_path_buf(),
                    line: ln,
                    message: format!("section ${name} is not read by femu (skipped)"),
                });
                l.skip_section(&name)?;
            }
            other => {
                return Err(l.err(
                    ln,
                    format!("expected a section ($MeshFormat, $Nodes, ...), found '{other}'"),
                ));
            }
        }
    }
    if version.is_none() {
        return Err(l.err(1, "no $MeshFormat section: not a Gmsh mesh".into()));
    }
    let mut mesh = Mesh::new();
    for (id, x, ln) in &nodes {
        mesh.add_node(*id, *x).map_err(|source| IoError::Model {
            path: path.to_path_buf(),
            line: *ln,
            source,
        })?;
    }
    let set_name = |dim: i64, tag: i64| {
        names
            .get(&(dim, tag))
            .cloned()
            .unwrap_or_else(|| format!("physical{tag}"))
    };
    let mut element_sets: BTreeMap<String, Vec<u64>> = BTreeMap::new();
    let mut node_sets: BTreeMap<String, Vec<u64>> = BTreeMap::new();
    let mut skipped: BTreeMap<i64, usize> = BTreeMap::new();
    let mut first_skip_line = BTreeMap::new();
    for (ty, tag, g, (dim, phys), ln) in &elements {
        let (_, kind) = gmsh_type(*ty).expect("checked while reading");
        match kind {
            Some(kind) => {
                mesh.add_element(*tag, kind, &to_femu(kind, g))
                    .map_err(|source| IoError::Model {
                        path: path.to_path_buf(),
                        line: *ln,
                        source,
                    })?;
                for p in phys {
                    element_sets
                        .entry(set_name(*dim, *p))
                        .or_default()
                        .push(*tag);
                    node_sets.entry(set_name(*dim, *p)).or_default().extend(g);
                }
            }
            None => {
                if phys.is_empty() {
                    *skipped.entry(*ty).or_default() += 1;
                    first_skip_line.entry(*ty).or_insert(*ln);
                }
                for p in phys {
                    node_sets.entry(set_name(*dim, *p)).or_default().extend(g);
                }
            }
        }
    }
    for (ty, count) in skipped {
        warnings.push(Warning {
            path: path.to_path_buf(),
            line: first_skip_line[&ty],
            message: format!("{count} elements of type {ty} (not a volume element) outside any physical group were ignored"),
        });
    }
    for (name, ids) in element_sets {
        mesh.add_element_set(name, &ids)
            .map_err(|source| IoError::Model {
                path: path.to_path_buf(),
                line: 0,
                source,
            })?;
    }
    for (name, mut ids) in node_sets {
        ids.sort_unstable();
        ids.dedup();
        mesh.add_node_set(name, &ids)
            .map_err(|source| IoError::Model {
                path: path.to_path_buf(),
                line: 0,
                source,
            })?;
    }
    Ok(GmshMesh { mesh, warnings })
}
