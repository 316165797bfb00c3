//! Gmsh `.msh` meshes: format 4.1 (ASCII and binary) and 2.2 (ASCII). Volume elements of types 4 (tet4),
//! 11 (tet10), 5 (hex8), 17 (hex20), 6 (prism6) and 18 (prism15) become femu elements, their node
//! orderings converted to femu's (Abaqus) ones; physical groups of volumes become element sets
//! and node sets, physical groups of surfaces, curves and points become node sets (the nodes of
//! their elements: where boundary conditions and sensors go). Lower-dimensional elements are not
//! elements of the model. Binary 4.1 files (either byte order, 4- or 8-byte `size_t`) are read by
//! [`read_msh`] and [`parse_msh_bytes`]; their errors give the byte offset and the line of the
//! section they occur in. Binary 2.2 is refused with a message (save as 4.1).

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
    /// The surface elements (dimension 2) of each physical group, by its name: what a shell
    /// section turns into shells (the mesh has them as node sets only).
    pub surfaces: BTreeMap<String, Vec<GroupElement>>,
    /// The line elements (dimension 1) of each physical group: what a beam section turns into
    /// beams.
    pub curves: BTreeMap<String, Vec<GroupElement>>,
    /// Warnings (skipped sections, element types without a femu equivalent).
    pub warnings: Vec<Warning>,
}

/// A surface or line element of a physical group.
#[derive(Debug, Clone, PartialEq)]
pub struct GroupElement {
    /// Its element tag.
    pub tag: u64,
    /// Its Gmsh element type (1: 2-node line, 8: 3-node line; 2: 3-node triangle, 3: 4-node
    /// quadrangle, 9, 16, 10: quadratic).
    pub gmsh_type: i64,
    /// Its node tags, in Gmsh's order.
    pub nodes: Vec<u64>,
    /// The line of the file it was read from.
    pub line: usize,
}

/// An element as read: Gmsh type, tag, node tags, (entity dimension, physical tags), line.
type RawElement = (i64, u64, Vec<u64>, (i64, Vec<i64>), usize);

/// Gmsh to femu (Abaqus) node order: `femu[k] = gmsh[PERM[k]]`.
const TET10: [usize; 10] = [0, 1, 2, 3, 4, 5, 6, 7, 9, 8];
const HEX20: [usize; 20] = [
    0, 1, 2, 3, 4, 5, 6, 7, 8, 11, 13, 9, 16, 18, 19, 17, 10, 12, 14, 15,
];
const PRISM15: [usize; 15] = [0, 1, 2, 3, 4, 5, 6, 9, 7, 12, 14, 13, 8, 10, 11];
/// Gmsh's 13-node pyramid numbers its mid-edges 0-1, 0-3, 0-4, 1-2, 1-4, 2-3, 2-4, 3-4.
const PYRAMID13: [usize; 13] = [0, 1, 2, 3, 4, 5, 8, 10, 6, 7, 9, 11, 12];

/// Nodes per element of a Gmsh type (0 for types femu does not know), and its femu kind.
fn gmsh_type(t: i64) -> Option<(usize, Option<ElementKind>)> {
    Some(match t {
        4 => (4, Some(ElementKind::Tet4)),
        11 => (10, Some(ElementKind::Tet10)),
        5 => (8, Some(ElementKind::Hex8)),
        17 => (20, Some(ElementKind::Hex20)),
        6 => (6, Some(ElementKind::Penta6)),
        18 => (15, Some(ElementKind::Penta15)),
        7 => (5, Some(ElementKind::Pyramid5)),
        19 => (13, Some(ElementKind::Pyramid13)),
        15 => (1, None),
        1 => (2, None),
        8 => (3, None),
        2 => (3, None),
        9 => (6, None),
        3 => (4, None),
        16 => (8, None),
        10 => (9, None),
        _ => return None,
    })
}

fn to_femu(kind: ElementKind, g: &[u64]) -> Vec<u64> {
    match kind {
        ElementKind::Tet10 => TET10.iter().map(|&i| g[i]).collect(),
        ElementKind::Hex20 => HEX20.iter().map(|&i| g[i]).collect(),
        ElementKind::Penta15 => PRISM15.iter().map(|&i| g[i]).collect(),
        ElementKind::Pyramid13 => PYRAMID13.iter().map(|&i| g[i]).collect(),
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
    parse_msh_bytes(&bytes, path)
}

/// Parses a `.msh` file's bytes, ASCII or binary (`path` names it in errors).
///
/// # Errors
/// As [`read_msh`].
pub fn parse_msh_bytes(bytes: &[u8], path: &Path) -> Result<GmshMesh, IoError> {
    if binary::is_binary(bytes) {
        return binary::parse(bytes, path);
    }
    parse_msh(&String::from_utf8_lossy(bytes), path)
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
                    return Err(l.err(ln2, "a binary .msh as text: read it with read_msh or parse_msh_bytes (binary 2.2 is not read: save as 4.1)".into()));
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
                    let (key, name) = physical_name(s).map_err(|r| l.err(ln2, r))?;
                    names.insert(key, name);
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
            "$Nodes" => nodes_section(&mut l, version, ln, &mut nodes)?,
            "$Elements" => elements_section(&mut l, version, ln, &entity_phys, &mut elements)?,
            s if s.starts_with('$') && !s.starts_with("$End") => {
                let name = s[1..].to_string();
                warnings.push(skipped_section(path, ln, &name));
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
    build(path, &nodes, &elements, &names, warnings)
}

/// A `$Nodes` section (format 4.1 or 2.2), its nodes appended to `nodes`.
fn nodes_section(
    l: &mut Lines<'_>,
    version: Option<i32>,
    ln: usize,
    nodes: &mut Vec<(u64, [f64; 3], usize)>,
) -> Result<(), IoError> {
    match version {
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
                // a count is not trusted with memory: at most one tag per line left
                // (found by the fuzzer: a block of 10^15 nodes aborted the process)
                let left = l.lines.len() - l.at;
                let mut tags = Vec::with_capacity((b[3].max(0) as usize).min(left));
                for _ in 0..b[3] {
                    let (ln3, t) = l.ints("a node tag", 1)?;
                    if t[0] <= 0 {
                        return Err(l.err(ln3, format!("node tag {} must be positive", t[0])));
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
                            format!("expected 'tag x y z' with a positive tag, found '{s}'"),
                        ));
                    }
                }
            }
            l.expect_end("Nodes")?;
        }
        None => return Err(l.err(ln, "$Nodes before $MeshFormat".into())),
    }
    Ok(())
}

/// An `$Elements` section (format 4.1 or 2.2), its elements appended to `elements` with the
/// physical tags of their entities (4.1) or their own (2.2).
fn elements_section(
    l: &mut Lines<'_>,
    version: Option<i32>,
    ln: usize,
    entity_phys: &BTreeMap<(i64, i64), Vec<i64>>,
    elements: &mut Vec<RawElement>,
) -> Result<(), IoError> {
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
                    return Err(l.err(
                        ln2,
                        format!(
                            "element type {ty} with {ntags} tags needs {} values, found {}",
                            3 + ntags + nn,
                            e.len()
                        ),
                    ));
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
    Ok(())
}

/// The warning for a section femu does not read.
fn skipped_section(path: &Path, line: usize, name: &str) -> Warning {
    Warning {
        path: path.to_path_buf(),
        line,
        message: format!("section ${name} is not read by femu (skipped)"),
    }
}

/// `dim tag "name"` of `$PhysicalNames`.
fn physical_name(s: &str) -> Result<((i64, i64), String), String> {
    let mut it = s.splitn(3, char::is_whitespace);
    let dim = it.next().and_then(|t| t.parse::<i64>().ok());
    let tag = it.next().and_then(|t| t.trim().parse::<i64>().ok());
    let name = it.next().map(|t| t.trim().trim_matches('"').to_string());
    match (dim, tag, name) {
        (Some(d), Some(t), Some(nm)) => Ok(((d, t), nm)),
        _ => Err(format!("expected 'dim tag \"name\"', found '{s}'")),
    }
}

/// The femu mesh from the nodes and elements read (either encoding).
fn build(
    path: &Path,
    nodes: &[(u64, [f64; 3], usize)],
    elements: &[RawElement],
    names: &BTreeMap<(i64, i64), String>,
    mut warnings: Vec<Warning>,
) -> Result<GmshMesh, IoError> {
    let mut mesh = Mesh::new();
    for (id, x, ln) in nodes {
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
    let mut surfaces: BTreeMap<String, Vec<GroupElement>> = BTreeMap::new();
    let mut curves: BTreeMap<String, Vec<GroupElement>> = BTreeMap::new();
    let mut skipped: BTreeMap<i64, usize> = BTreeMap::new();
    let mut first_skip_line = BTreeMap::new();
    for (ty, tag, g, (dim, phys), ln) in elements {
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
                    let lower = match dim {
                        2 => Some(&mut surfaces),
                        1 => Some(&mut curves),
                        _ => None,
                    };
                    if let Some(lower) = lower {
                        lower
                            .entry(set_name(*dim, *p))
                            .or_default()
                            .push(GroupElement {
                                tag: *tag,
                                gmsh_type: *ty,
                                nodes: g.clone(),
                                line: *ln,
                            });
                    }
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
    if mesh.element_count() == 0 && surfaces.is_empty() && curves.is_empty() {
        return Err(IoError::Content {
            path: path.to_path_buf(),
            reason: format!(
                "no volume elements in the mesh ({} nodes): femu needs tetrahedra, hexahedra or prisms ($Elements of dimension 3), or physical groups of surfaces or lines to make shells or beams of (--shell, --beam)",
                mesh.node_count()
            ),
        });
    }
    Ok(GmshMesh {
        mesh,
        surfaces,
        curves,
        warnings,
    })
}

/// Binary 4.1: the same sections as ASCII with their numbers as raw bytes.
mod binary {
    use super::{RawElement, build, gmsh_type, physical_name};
    use crate::IoError;
    use std::collections::BTreeMap;
    use std::path::Path;

    /// Whether the `$MeshFormat` line says binary (file-type 1).
    pub(super) fn is_binary(bytes: &[u8]) -> bool {
        let head = &bytes[..bytes.len().min(256)];
        let text = String::from_utf8_lossy(head);
        let mut lines = text.lines().map(str::trim).filter(|l| !l.is_empty());
        while let Some(l) = lines.next() {
            if l == "$MeshFormat" {
                return lines
                    .next()
                    .and_then(|f| f.split_whitespace().nth(1))
                    .is_some_and(|t| t == "1");
            }
        }
        false
    }

    struct Reader<'a> {
        b: &'a [u8],
        at: usize,
        path: &'a Path,
        /// the file's byte order differs from this machine's
        swap: bool,
        size_t: usize,
        /// (byte, its line) last counted: `line_of` is asked at every block, so it counts
        /// newlines onwards from there instead of from the start of the file
        counted: std::cell::Cell<(usize, usize)>,
    }

    impl<'a> Reader<'a> {
        /// 1-based line of byte `at` (newlines inside binary blocks count too; the line of a
        /// section header is exact).
        fn line_of(&self, at: usize) -> usize {
            let at = at.min(self.b.len());
            let (from, line) = match self.counted.get() {
                (from, line) if from <= at => (from, line),
                _ => (0, 1),
            };
            let line = line + self.b[from..at].iter().filter(|c| **c == b'\n').count();
            self.counted.set((at, line));
            line
        }

        fn err(&self, reason: String) -> IoError {
            IoError::Parse {
                path: self.path.to_path_buf(),
                line: self.line_of(self.at),
                reason: format!("{reason} (byte offset {})", self.at),
            }
        }

        fn take(&mut self, n: usize, what: &str) -> Result<&'a [u8], IoError> {
            match self.at.checked_add(n) {
                Some(end) if end <= self.b.len() => {
                    let s = &self.b[self.at..end];
                    self.at = end;
                    Ok(s)
                }
                _ => Err(self.err(format!("file ends inside {what}"))),
            }
        }

        fn raw<const N: usize>(&mut self, what: &str) -> Result<[u8; N], IoError> {
            let mut a: [u8; N] = self.take(N, what)?.try_into().expect("N bytes");
            if self.swap {
                a.reverse();
            }
            Ok(a)
        }

        fn int(&mut self, what: &str) -> Result<i64, IoError> {
            Ok(i32::from_ne_bytes(self.raw::<4>(what)?) as i64)
        }

        fn size(&mut self, what: &str) -> Result<u64, IoError> {
            Ok(match self.size_t {
                4 => u32::from_ne_bytes(self.raw::<4>(what)?) as u64,
                _ => u64::from_ne_bytes(self.raw::<8>(what)?),
            })
        }

        fn double(&mut self, what: &str) -> Result<f64, IoError> {
            let at = self.at;
            let v = f64::from_ne_bytes(self.raw::<8>(what)?);
            if !v.is_finite() {
                self.at = at;
                return Err(self.err(format!("{what}: {v} is not a finite number")));
            }
            Ok(v)
        }

        /// A count of records of at least `min_bytes` each that the rest of the file can hold
        /// (a corrupt count is an error, not a huge allocation).
        fn count(&mut self, what: &str, min_bytes: usize) -> Result<usize, IoError> {
            let at = self.at;
            let n = self.size(what)?;
            let left = (self.b.len() - self.at) as u64;
            if n.saturating_mul(min_bytes.max(1) as u64) > left {
                self.at = at;
                return Err(self.err(format!(
                    "{what}: {n} records cannot fit in the {left} bytes left"
                )));
            }
            Ok(n as usize)
        }

        /// The next non-empty text line, trimmed, with its line number.
        fn line(&mut self, what: &str) -> Result<(usize, &'a str), IoError> {
            loop {
                if self.at >= self.b.len() {
                    return Err(self.err(format!("file ends inside {what}")));
                }
                let start = self.at;
                let end = self.b[start..]
                    .iter()
                    .position(|c| *c == b'\n')
                    .map_or(self.b.len(), |p| start + p);
                self.at = (end + 1).min(self.b.len());
                let s = std::str::from_utf8(&self.b[start..end])
                    .map_err(|_| IoError::Parse {
                        path: self.path.to_path_buf(),
                        line: self.line_of(start),
                        reason: format!("{what}: expected a text line (byte offset {start})"),
                    })?
                    .trim();
                if !s.is_empty() {
                    return Ok((self.line_of(start), s));
                }
            }
        }

        fn expect_end(&mut self, section: &str) -> Result<(), IoError> {
            let (ln, l) = self.line(section)?;
            if l != format!("$End{section}") {
                return Err(IoError::Parse {
                    path: self.path.to_path_buf(),
                    line: ln,
                    reason: format!(
                        "expected $End{section} after the binary data, found '{}'",
                        l.chars().take(40).collect::<String>()
                    ),
                });
            }
            Ok(())
        }

        /// `numEntityBlocks` (blocks of at least `min_bytes`) and the three counts that follow
        /// it (total, min and max tag: not needed).
        fn section_head(&mut self, what: &str, min_bytes: usize) -> Result<usize, IoError> {
            let blocks = self.count(&format!("{what} block count"), min_bytes)?;
            for _ in 0..3 {
                self.size(&format!("{what} counts"))?;
            }
            Ok(blocks)
        }

        /// A block's line and its three `int`s (entity dimension, entity tag, then the
        /// parametric flag of a node block or the type of an element block).
        fn block_head(&mut self, what: &str) -> Result<(usize, [i64; 3]), IoError> {
            let line = self.line_of(self.at);
            let mut v = [0; 3];
            for x in &mut v {
                *x = self.int(&format!("{what} block header"))?;
            }
            Ok((line, v))
        }

        /// Skips to after `$End<name>`.
        fn skip_section(&mut self, name: &str) -> Result<(), IoError> {
            let tag = format!("$End{name}");
            let found = self.b[self.at..]
                .windows(tag.len())
                .position(|w| w == tag.as_bytes());
            match found {
                Some(p) => {
                    self.at += p + tag.len();
                    Ok(())
                }
                None => Err(self.err(format!("no {tag}"))),
            }
        }
    }

    pub(super) fn parse(bytes: &[u8], path: &Path) -> Result<super::GmshMesh, IoError> {
        let mut r = Reader {
            b: bytes,
            at: 0,
            path,
            swap: false,
            size_t: 8,
            counted: std::cell::Cell::new((0, 1)),
        };
        let mut warnings = Vec::new();
        let mut format = false;
        let mut names: BTreeMap<(i64, i64), String> = BTreeMap::new();
        let mut entity_phys: BTreeMap<(i64, i64), Vec<i64>> = BTreeMap::new();
        let mut nodes: Vec<(u64, [f64; 3], usize)> = Vec::new();
        let mut elements: Vec<RawElement> = Vec::new();
        loop {
            let head = match r.line("the file") {
                Ok(h) => h,
                Err(_) if r.at >= r.b.len() => break,
                Err(e) => return Err(e),
            };
            let (ln, head) = head;
            let parse_err = |line: usize, reason: String| IoError::Parse {
                path: path.to_path_buf(),
                line,
                reason,
            };
            if head != "$MeshFormat" && !format {
                return Err(parse_err(ln, "expected $MeshFormat first".into()));
            }
            match head {
                "$MeshFormat" => {
                    let (ln2, f) = r.line("$MeshFormat")?;
                    let t: Vec<&str> = f.split_whitespace().collect();
                    if t.len() < 3 || !t[0].starts_with("4.1") {
                        return Err(parse_err(
                            ln2,
                            format!(
                                "binary format '{f}': femu reads binary 4.1 (save 2.2 files as 4.1)"
                            ),
                        ));
                    }
                    r.size_t = match t[2] {
                        "4" => 4,
                        "8" => 8,
                        other => {
                            return Err(parse_err(
                                ln2,
                                format!("data size {other}: expected 4 or 8"),
                            ));
                        }
                    };
                    let one = r.take(4, "the byte-order marker")?;
                    let one: [u8; 4] = one.try_into().expect("4 bytes");
                    r.swap = if i32::from_ne_bytes(one) == 1 {
                        false
                    } else if i32::from_ne_bytes(one).swap_bytes() == 1 {
                        true
                    } else {
                        r.at -= 4;
                        return Err(r.err("the byte-order marker is not the integer 1".into()));
                    };
                    r.expect_end("MeshFormat")?;
                    format = true;
                }
                "$PhysicalNames" => {
                    let (ln2, n) = r.line("$PhysicalNames")?;
                    let n: usize = n
                        .parse()
                        .map_err(|_| parse_err(ln2, format!("'{n}' is not a count")))?;
                    for _ in 0..n {
                        let (ln3, s) = r.line("$PhysicalNames")?;
                        let (key, name) = physical_name(s).map_err(|e| parse_err(ln3, e))?;
                        names.insert(key, name);
                    }
                    r.expect_end("PhysicalNames")?;
                }
                "$Entities" => {
                    let counts: Vec<usize> = (0..4)
                        .map(|_| r.count("entity count", 4))
                        .collect::<Result<_, _>>()?;
                    for (dim, count) in counts.into_iter().enumerate() {
                        for _ in 0..count {
                            let tag = r.int("entity tag")?;
                            let bounds = if dim == 0 { 3 } else { 6 };
                            for _ in 0..bounds {
                                r.double("entity coordinates")?;
                            }
                            let np = r.count("physical tag count", 4)?;
                            let phys: Vec<i64> = (0..np)
                                .map(|_| r.int("physical tag").map(i64::abs))
                                .collect::<Result<_, _>>()?;
                            if dim > 0 {
                                let nb = r.count("bounding entity count", 4)?;
                                r.take(4 * nb, "bounding entities")?;
                            }
                            entity_phys.insert((dim as i64, tag), phys);
                        }
                    }
                    r.expect_end("Entities")?;
                }
                "$Nodes" => {
                    let blocks = r.section_head("node", 12)?;
                    for _ in 0..blocks {
                        let (block_line, [_dim, _entity, parametric]) = r.block_head("node")?;
                        if parametric != 0 {
                            r.at -= 4;
                            return Err(
                                r.err("parametric node coordinates are not read by femu".into())
                            );
                        }
                        let n = r.count("nodes in a block", r.size_t + 24)?;
                        let mut tags = Vec::with_capacity(n);
                        for _ in 0..n {
                            let at = r.at;
                            let t = r.size("node tag")?;
                            if t == 0 {
                                r.at = at;
                                return Err(r.err("node tag 0: tags must be positive".into()));
                            }
                            tags.push(t);
                        }
                        for t in tags {
                            let x = [
                                r.double("node coordinates")?,
                                r.double("node coordinates")?,
                                r.double("node coordinates")?,
                            ];
                            nodes.push((t, x, block_line));
                        }
                    }
                    r.expect_end("Nodes")?;
                }
                "$Elements" => {
                    let blocks = r.section_head("element", 16)?;
                    for _ in 0..blocks {
                        let (block_line, [dim, entity, ty]) = r.block_head("element")?;
                        let Some((nn, _)) = gmsh_type(ty) else {
                            r.at -= 4;
                            return Err(r.err(format!("unknown element type {ty}")));
                        };
                        let count = r.count("elements in a block", (nn + 1) * r.size_t)?;
                        let phys = entity_phys.get(&(dim, entity)).cloned().unwrap_or_default();
                        for _ in 0..count {
                            let at = r.at;
                            let ids: Vec<u64> = (0..=nn)
                                .map(|_| r.size("an element"))
                                .collect::<Result<_, _>>()?;
                            if ids.contains(&0) {
                                r.at = at;
                                return Err(r.err(format!(
                                    "element of type {ty} with a zero tag or node tag"
                                )));
                            }
                            elements.push((
                                ty,
                                ids[0],
                                ids[1..].to_vec(),
                                (dim, phys.clone()),
                                block_line,
                            ));
                        }
                    }
                    r.expect_end("Elements")?;
                }
                s if s.starts_with('$') && !s.starts_with("$End") => {
                    let name = s[1..].to_string();
                    warnings.push(super::skipped_section(path, ln, &name));
                    r.skip_section(&name)?;
                }
                other => {
                    return Err(parse_err(
                        ln,
                        format!(
                            "expected a section ($MeshFormat, $Nodes, ...), found '{}'",
                            other.chars().take(40).collect::<String>()
                        ),
                    ));
                }
            }
        }
        if !format {
            return Err(IoError::Parse {
                path: path.to_path_buf(),
                line: 1,
                reason: "no $MeshFormat section: not a Gmsh mesh".into(),
            });
        }
        build(path, &nodes, &elements, &names, warnings)
    }
}
