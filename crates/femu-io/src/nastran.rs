//! Nastran bulk data (`.bdf`, `.dat`, `.nas`): the solid models of automotive and aerospace
//! correlation work.
//!
//! Formats: small field (8 characters), large field (`*` after the card name, 16 characters) and
//! free field (commas), continuations with and without labels (`+`, `*`, a blank first field, a
//! comma), implicit exponents (`7.+10`, `1.-3`), `$` comments, `INCLUDE`, the case control's
//! `SPC =` before `BEGIN BULK`, and `ENDDATA`.
//!
//! Mid-side grids of quadratic solids may be blank, as Nastran allows: that edge is straight and
//! the element varies linearly along it, which femu states with a node at the edge's midpoint tied
//! to the average of its ends (docs/MATH.md, "Multipoint constraints").
//!
//! Cards read: `GRID` (with its `CP` frame), `CORD2R/C/S` and `CORD1R/C/S`, `CHEXA` (8/20),
//! `CPENTA` (6/15), `CTETRA` (4/10), `CPYRAM` (5/13), `PSOLID`, `MAT1` (two of `E`, `G`, `NU`), `MAT9`, `SPC`, `SPC1`,
//! `SPCADD` (components 4-6 on rigid links' reference grids, the only grids with rotations),
//! `CONM2` (on an RBE2 reference grid a rigid mass with its offset, `CID` frame and inertia
//! `[[I11, -I21, -I31], [-I21, I22, -I32], [-I31, -I32, I33]]`; on a solid grid, which has no
//! rotations, its mass, with the offset and inertia reported and dropped), `RBE2` (a rigid link: its reference grid gets rotations, the
//! translations of the dependent grids follow its rigid motion; components 4-6 of solid grids have
//! nothing to act on), `RBE3` (the reference follows the weighted least-squares rigid motion of
//! its grids, docs/MATH.md "Multipoint constraints"; weight groups on components 123), `EIGRL` and
//! `PARAM,WTMASS`. Cards that cannot change `K` and `M` (output requests, loads, other
//! parameters) are warnings, once per card name. Cards that would change them and that femu cannot
//! model (shells, bars, springs, RBAR and MPC, other materials) are an error that counts
//! them by kind; [`BdfOptions::lenient`] reads the rest with a warning that the model is then
//! incomplete.

use crate::uff::CoordinateSystem;
use crate::{IoError, Warning};
use femu_fem::element::ElementKind;
use femu_fem::material::Material;
use femu_fem::mesh::Mesh;
use femu_fem::model::Model;
use std::collections::{BTreeMap, HashMap};
use std::path::{Path, PathBuf};

/// Options of the reader.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct BdfOptions {
    /// Read a deck with cards femu cannot model (they are left out, with a warning that `K` and
    /// `M` are incomplete) instead of refusing it.
    pub lenient: bool,
}

/// A model read from bulk data, with what the reader noticed.
#[derive(Debug, Clone)]
pub struct BdfDeck {
    /// The model: mesh, materials, constraints of the selected SPC set, point masses.
    pub model: Model,
    /// The modes an `EIGRL` asks for (`V1`, `V2` in Hz, `ND`), if any.
    pub eigrl: Option<(Option<f64>, Option<f64>, Option<usize>)>,
    /// Findings that did not stop the reading.
    pub warnings: Vec<Warning>,
}

/// One card: its name, its fields after the name (blank = `None`), where it starts.
#[derive(Debug, Clone)]
struct Card {
    name: String,
    fields: Vec<String>,
    path: PathBuf,
    line: usize,
}

impl Card {
    fn err(&self, reason: String) -> IoError {
        IoError::Parse {
            path: self.path.clone(),
            line: self.line,
            reason: format!("{} {reason}", self.name),
        }
    }

    /// A model error at this card's file and line.
    fn located(&self) -> impl FnOnce(femu_fem::FemError) -> IoError + '_ {
        move |source| IoError::Model {
            path: self.path.clone(),
            line: self.line,
            source,
        }
    }

    fn field(&self, i: usize) -> &str {
        self.fields.get(i).map_or("", |s| s.trim())
    }

    fn int(&self, i: usize, what: &str) -> Result<Option<i64>, IoError> {
        let t = self.field(i);
        if t.is_empty() {
            return Ok(None);
        }
        t.parse::<i64>()
            .map(Some)
            .map_err(|_| self.err(format!("field {} ({what}): {t:?} is not an integer", i + 2)))
    }

    fn id(&self, i: usize, what: &str) -> Result<u64, IoError> {
        match self.int(i, what)? {
            Some(v) if v > 0 => Ok(v as u64),
            Some(v) => Err(self.err(format!("field {} ({what}): {v} must be positive", i + 2))),
            None => Err(self.err(format!("field {} ({what}) is missing", i + 2))),
        }
    }

    fn real(&self, i: usize, what: &str) -> Result<Option<f64>, IoError> {
        let t = self.field(i);
        if t.is_empty() {
            return Ok(None);
        }
        real(t)
            .map(Some)
            .ok_or_else(|| self.err(format!("field {} ({what}): {t:?} is not a number", i + 2)))
    }
}

/// A Nastran real: `1.5`, `1.5E+3`, `1.5D3`, and the implicit exponents `7.+10`, `1.-3`,
/// `-2.5-4`. Integers are accepted where a real is expected.
pub fn real(s: &str) -> Option<f64> {
    let t = s.trim();
    if let Ok(v) = t.parse::<f64>() {
        return v.is_finite().then_some(v);
    }
    let t = t.replace(['D', 'd'], "E");
    if let Ok(v) = t.parse::<f64>() {
        return v.is_finite().then_some(v);
    }
    // a sign after the first character, not after an E: the exponent
    let b = t.as_bytes();
    let at = (1..b.len())
        .find(|&i| (b[i] == b'+' || b[i] == b'-') && b[i - 1] != b'E' && b[i - 1] != b'e')?;
    let v: f64 = format!("{}E{}", &t[..at], &t[at..]).parse().ok()?;
    v.is_finite().then_some(v)
}

/// Cards that cannot change `K` or `M`: read past with a warning.
const NO_EFFECT: &[&str] = &[
    "PARAM", "FORCE", "MOMENT", "LOAD", "DLOAD", "RLOAD1", "RLOAD2", "TLOAD1", "TLOAD2", "TABLED1",
    "TABLED2", "TABLED3", "TABLED4", "TABDMP1", "FREQ", "FREQ1", "FREQ2", "GRAV", "TEMP", "TEMPD",
    "PLOAD", "PLOAD2", "PLOAD4", "EIGR", "EIGRL", "SPOINT", "DAREA", "NSM", "SET1", "DESVAR",
    "DRESP1", "DCONSTR", "MONPNT1", "ASET", "ASET1", "OMIT", "OMIT1", "SUPORT", "SUPORT1",
    "MDLPRM", "LSEQ", "RLOAD1", "RLOAD2",
];

/// Cards that change `K` or `M` and that femu cannot model yet, with what they are.
const UNSUPPORTED: &[(&str, &str)] = &[
    ("CQUAD4", "shells"),
    ("CQUAD8", "shells"),
    ("CTRIA3", "shells"),
    ("CTRIA6", "shells"),
    ("CQUADR", "shells"),
    ("CTRIAR", "shells"),
    ("PSHELL", "shells"),
    ("PCOMP", "shells"),
    ("CBAR", "beams"),
    ("CBEAM", "beams"),
    ("CROD", "rods"),
    ("CONROD", "rods"),
    ("PBAR", "beams"),
    ("PBARL", "beams"),
    ("PBEAM", "beams"),
    ("PBEAML", "beams"),
    ("PROD", "rods"),
    ("CELAS1", "springs"),
    ("CELAS2", "springs"),
    ("CBUSH", "springs"),
    ("PELAS", "springs"),
    ("PBUSH", "springs"),
    ("CONM1", "general mass matrices"),
    ("CMASS1", "scalar masses"),
    ("CMASS2", "scalar masses"),
    ("RBAR", "rigid links"),
    ("MPC", "multipoint constraints"),
    ("MPCADD", "multipoint constraints"),
    ("MAT2", "anisotropic materials"),
    ("MAT8", "orthotropic materials"),
    ("CORD3G", "coordinate systems"),
    ("GENEL", "general elements"),
    ("DMIG", "direct matrix input"),
];

/// Lines with their file and number, `INCLUDE`s expanded.
fn load(path: &Path, depth: usize, out: &mut Vec<(PathBuf, usize, String)>) -> Result<(), IoError> {
    if depth > 16 {
        return Err(IoError::Content {
            path: path.to_path_buf(),
            reason: "INCLUDE nested more than 16 deep (an include cycle?)".into(),
        });
    }
    let bytes = std::fs::read(path).map_err(|e| IoError::io(path, e))?;
    let text = String::from_utf8_lossy(&bytes);
    for (i, raw) in text.lines().enumerate() {
        let l = raw.trim_end_matches('\r');
        let head = l.trim_start();
        if head.len() >= 7 && head[..7].eq_ignore_ascii_case("INCLUDE") {
            let name = head[7..]
                .trim()
                .trim_matches(|c| c == '\'' || c == '"')
                .trim();
            let target = path.parent().unwrap_or(Path::new(".")).join(name);
            if !target.exists() {
                return Err(IoError::Parse {
                    path: path.to_path_buf(),
                    line: i + 1,
                    reason: format!("INCLUDE {name}: {} does not exist", target.display()),
                });
            }
            load(&target, depth + 1, out)?;
            continue;
        }
        out.push((path.to_path_buf(), i + 1, l.to_string()));
    }
    Ok(())
}

/// The fields of one physical line: the first (name or continuation), then the data fields
/// (8 for small and free field, 4 for a large-field line).
fn split(l: &str) -> (String, Vec<String>, bool) {
    let l = match l.find('$') {
        Some(i) => &l[..i],
        None => l,
    };
    if l.contains(',') {
        let mut t: Vec<String> = l.split(',').map(|s| s.trim().to_string()).collect();
        let first = t.remove(0);
        // a tenth field is the continuation label
        if t.len() == 9 {
            t.pop();
        }
        let large = first.ends_with('*');
        return (first, t, large);
    }
    let chars: Vec<char> = l.chars().collect();
    let cut = |a: usize, b: usize| -> String {
        chars
            .get(a.min(chars.len())..b.min(chars.len()))
            .map(|c| c.iter().collect::<String>())
            .unwrap_or_default()
            .trim()
            .to_string()
    };
    let first = cut(0, 8);
    // a large-field card's name ends with '*', its continuations start with one
    let large = first.ends_with('*') || first.starts_with('*');
    let fields = if large {
        (0..4).map(|k| cut(8 + 16 * k, 24 + 16 * k)).collect()
    } else {
        (0..8).map(|k| cut(8 + 8 * k, 16 + 8 * k)).collect()
    };
    (first, fields, large)
}

/// Whether a line's first field continues the card before it.
fn is_continuation(first: &str) -> bool {
    first.is_empty() || first.starts_with('+') || first.starts_with('*')
}

/// The cards of the bulk data, and the case control's `SPC` selection.
fn cards(lines: &[(PathBuf, usize, String)]) -> (Vec<Card>, Option<i64>, bool) {
    let has_begin = lines.iter().any(|(_, _, l)| {
        l.trim_start()
            .to_ascii_uppercase()
            .starts_with("BEGIN BULK")
    });
    let mut in_bulk = !has_begin;
    let mut spc = None;
    let mut out: Vec<Card> = Vec::new();
    // large-field cards hold 4 fields a line; pad each line to its width
    for (path, number, l) in lines {
        let t = l.trim();
        let upper = t.to_ascii_uppercase();
        if !in_bulk {
            if upper.starts_with("BEGIN BULK") {
                in_bulk = true;
            } else if let Some(rest) = upper.strip_prefix("SPC")
                && let Some((_, v)) = rest.split_once('=')
            {
                spc = v.trim().parse::<i64>().ok();
            }
            continue;
        }
        if upper.starts_with("ENDDATA") {
            break;
        }
        if t.is_empty() || t.starts_with('$') {
            continue;
        }
        let (first, fields, _large) = split(l);
        if is_continuation(&first) && !out.is_empty() {
            let card = out.last_mut().expect("checked");
            card.fields.extend(fields);
            continue;
        }
        let name = first.trim_end_matches('*').to_ascii_uppercase();
        out.push(Card {
            name,
            fields,
            path: path.clone(),
            line: *number,
        });
    }
    (out, spc, has_begin)
}

/// The system of a `CORD` card through points `a` (origin), `b` (on the z axis) and `c` (in the xz
/// plane), all basic; `kind` 0 rectangular, 1 cylindrical, 2 spherical. Positions in it follow
/// [`CoordinateSystem::point_to_global`], whose cylindrical `(r, theta, z)` and spherical
/// `(r, theta from z, phi)` in degrees are Nastran's.
fn frame_through(kind: i64, a: [f64; 3], b: [f64; 3], c: [f64; 3]) -> Option<CoordinateSystem> {
    let sub = |p: [f64; 3], q: [f64; 3]| -> [f64; 3] { std::array::from_fn(|i| p[i] - q[i]) };
    let cross = |p: [f64; 3], q: [f64; 3]| {
        [
            p[1] * q[2] - p[2] * q[1],
            p[2] * q[0] - p[0] * q[2],
            p[0] * q[1] - p[1] * q[0],
        ]
    };
    let unit = |p: [f64; 3]| {
        let n = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
        (n > 1e-300).then(|| p.map(|v| v / n))
    };
    let ez = unit(sub(b, a))?;
    let ey = unit(cross(ez, sub(c, a)))?;
    let ex = cross(ey, ez);
    Some(CoordinateSystem {
        name: String::new(),
        kind,
        origin: a,
        axes: std::array::from_fn(|i| [ex[i], ey[i], ez[i]]),
    })
}

/// The kind of a `CORDxR/C/S` card: 0, 1 or 2.
fn cord_kind(c: &Card) -> i64 {
    match c.name.chars().last() {
        Some('C') => 1,
        Some('S') => 2,
        _ => 0,
    }
}

/// Coordinate systems and grid positions, resolved on demand: a system may be defined relative
/// to another, or through grids given in a third; a cycle is an error naming it.
struct Geometry<'a> {
    frames: HashMap<i64, CoordinateSystem>,
    cord2: HashMap<i64, (&'a Card, i64)>,
    cord1: Vec<(i64, [u64; 3], &'a Card)>,
    grid_of: HashMap<u64, &'a Card>,
    positions: HashMap<u64, [f64; 3]>,
    stack: Vec<i64>,
}

impl Geometry<'_> {
    /// System `cid` in basic terms (`asked_by` names the card in errors).
    fn frame(&mut self, cid: i64, asked_by: &Card) -> Result<CoordinateSystem, IoError> {
        if let Some(f) = self.frames.get(&cid) {
            return Ok(f.clone());
        }
        if self.stack.contains(&cid) {
            return Err(asked_by.err(format!(
                "coordinate systems refer to each other in a cycle: {}",
                self.stack
                    .iter()
                    .chain([&cid])
                    .map(i64::to_string)
                    .collect::<Vec<_>>()
                    .join(" -> ")
            )));
        }
        self.stack.push(cid);
        let frame = if let Some(&(c, rid)) = self.cord2.get(&cid) {
            let reference = self.frame(rid, c)?;
            let mut p = [[0.0; 3]; 3];
            for (k, point) in p.iter_mut().enumerate() {
                for (i, v) in point.iter_mut().enumerate() {
                    *v = c.real(2 + 3 * k + i, "point")?.unwrap_or(0.0);
                }
                *point = reference.point_to_global(*point);
            }
            frame_through(cord_kind(c), p[0], p[1], p[2]).ok_or_else(|| {
                c.err(format!(
                    "{cid}: its points A, B, C do not define axes (coincident or collinear)"
                ))
            })?
        } else if let Some(&(_, g, c)) = self.cord1.iter().find(|e| e.0 == cid) {
            let mut pts = [[0.0; 3]; 3];
            for (k, id) in g.iter().enumerate() {
                pts[k] = self.position(*id, c)?;
            }
            frame_through(cord_kind(c), pts[0], pts[1], pts[2]).ok_or_else(|| {
                c.err(format!(
                    "{cid}: its grids do not define axes (coincident or collinear)"
                ))
            })?
        } else {
            return Err(asked_by.err(format!(
                "refers to coordinate system {cid}, which the deck does not define"
            )));
        };
        self.stack.pop();
        self.frames.insert(cid, frame.clone());
        Ok(frame)
    }

    /// The basic position of GRID `id`.
    fn position(&mut self, id: u64, asked_by: &Card) -> Result<[f64; 3], IoError> {
        if let Some(p) = self.positions.get(&id) {
            return Ok(*p);
        }
        let g = *self.grid_of.get(&id).ok_or_else(|| {
            asked_by.err(format!(
                "refers to GRID {id}, which the deck does not define"
            ))
        })?;
        let cp = g.int(1, "CP")?.unwrap_or(0);
        let x: [f64; 3] = [
            g.real(2, "X1")?.unwrap_or(0.0),
            g.real(3, "X2")?.unwrap_or(0.0),
            g.real(4, "X3")?.unwrap_or(0.0),
        ];
        let p = self.frame(cp, g)?.point_to_global(x);
        self.positions.insert(id, p);
        Ok(p)
    }
}

/// Reads a bulk data deck.
///
/// # Errors
/// As [`parse_bdf`], and the file system's.
pub fn read_bdf(path: impl AsRef<Path>, options: &BdfOptions) -> Result<BdfDeck, IoError> {
    let mut lines = Vec::new();
    load(path.as_ref(), 0, &mut lines)?;
    parse_lines(&lines, path.as_ref(), options)
}

/// Parses bulk data from text (`path` names it in messages; `INCLUDE`s are not followed).
///
/// # Errors
/// [`IoError::Parse`] naming the card's line: malformed fields, a GRID used but not defined, a
/// coordinate system cycle or an unknown one, a PSOLID without its MAT1, an SPC on an unknown
/// node, an element of a kind femu cannot model (unless lenient), an invalid material.
pub fn parse_bdf(
    text: &str,
    path: impl AsRef<Path>,
    options: &BdfOptions,
) -> Result<BdfDeck, IoError> {
    let path = path.as_ref();
    let lines: Vec<(PathBuf, usize, String)> = text
        .lines()
        .enumerate()
        .map(|(i, l)| {
            (
                path.to_path_buf(),
                i + 1,
                l.trim_end_matches('\r').to_string(),
            )
        })
        .collect();
    parse_lines(&lines, path, options)
}

fn parse_lines(
    lines: &[(PathBuf, usize, String)],
    path: &Path,
    options: &BdfOptions,
) -> Result<BdfDeck, IoError> {
    let (cards, spc_selected, has_case_control) = cards(lines);
    let mut warnings = Vec::new();
    let warn = |warnings: &mut Vec<Warning>, c: &Card, message: String| {
        warnings.push(Warning {
            path: c.path.clone(),
            line: c.line,
            message,
        })
    };
    // what cannot be modelled: counted by kind
    let mut unsupported: BTreeMap<&str, (usize, Vec<&str>, &Card)> = BTreeMap::new();
    let mut warned: Vec<String> = Vec::new();
    let mut grids: Vec<&Card> = Vec::new();
    let mut cords: Vec<&Card> = Vec::new();
    let mut elements: Vec<&Card> = Vec::new();
    let mut psolids: HashMap<u64, (u64, &Card)> = HashMap::new();
    let mut mat1: HashMap<u64, &Card> = HashMap::new();
    let mut spcs: Vec<&Card> = Vec::new();
    let mut conm2: Vec<&Card> = Vec::new();
    let mut links: Vec<&Card> = Vec::new();
    let mut wtmass = 1.0;
    let mut eigrl = None;
    for c in &cards {
        match c.name.as_str() {
            "GRID" => grids.push(c),
            "CORD2R" | "CORD2C" | "CORD2S" | "CORD1R" | "CORD1C" | "CORD1S" => cords.push(c),
            "CHEXA" | "CPENTA" | "CTETRA" | "CPYRAM" => elements.push(c),
            "PSOLID" => {
                let pid = c.id(0, "PID")?;
                let mid = c.id(1, "MID")?;
                if psolids.insert(pid, (mid, c)).is_some() {
                    return Err(c.err(format!("{pid} is defined twice")));
                }
            }
            "MAT1" | "MAT9" => {
                let mid = c.id(0, "MID")?;
                if mat1.insert(mid, c).is_some() {
                    return Err(c.err(format!("{mid} is defined twice (MAT1 and MAT9 share ids)")));
                }
            }
            "SPC" | "SPC1" | "SPCADD" => spcs.push(c),
            "CONM2" => conm2.push(c),
            "RBE2" | "RBE3" => links.push(c),
            "PARAM" if c.field(0).eq_ignore_ascii_case("WTMASS") => {
                wtmass = c
                    .real(1, "WTMASS")?
                    .filter(|v| *v > 0.0)
                    .ok_or_else(|| c.err("WTMASS needs a positive value".into()))?;
            }
            "EIGRL" => {
                eigrl = Some((
                    c.real(1, "V1")?,
                    c.real(2, "V2")?,
                    c.int(3, "ND")?.map(|v| v.max(0) as usize),
                ));
            }
            name => {
                if let Some((_, kind)) = UNSUPPORTED.iter().find(|(n, _)| *n == name) {
                    let e = unsupported.entry(kind).or_insert((0, Vec::new(), c));
                    e.0 += 1;
                    if !e.1.contains(&name) {
                        e.1.push(
                            UNSUPPORTED
                                .iter()
                                .find(|(n, _)| *n == name)
                                .map(|(n, _)| *n)
                                .unwrap_or(""),
                        );
                    }
                } else if !warned.contains(&c.name) {
                    warned.push(c.name.clone());
                    let why = if NO_EFFECT.contains(&name) {
                        "it does not change the stiffness or the mass"
                    } else {
                        "femu does not know this card; check that it changes neither stiffness nor mass"
                    };
                    warn(
                        &mut warnings,
                        c,
                        format!("{name} skipped: {why} (once per card name)"),
                    );
                }
            }
        }
    }
    if !unsupported.is_empty() {
        let list: Vec<String> = unsupported
            .iter()
            .map(|(kind, (n, names, _))| format!("{n} {kind} ({})", names.join(", ")))
            .collect();
        let first = unsupported
            .values()
            .map(|v| v.2)
            .min_by_key(|c| c.line)
            .expect("non-empty");
        let text = format!(
            "the deck has cards that change the stiffness or the mass and that femu cannot model: {}; femu models solids (CHEXA 8/20, CPENTA 6/15, CTETRA 4/10, CPYRAM 5/13) with MAT1 or MAT9, CONM2 point masses, RBE2 and RBE3 links and SPC constraints",
            list.join(", ")
        );
        if options.lenient {
            warnings.push(Warning {
                path: first.path.clone(),
                line: first.line,
                message: format!(
                    "{text}: left out (--lenient), so the model's K and M are incomplete"
                ),
            });
        } else {
            return Err(IoError::Parse {
                path: first.path.clone(),
                line: first.line,
                reason: format!("{text} (--lenient reads the rest)"),
            });
        }
    }
    // coordinate systems: resolved against their references on demand, detecting cycles
    let basic = CoordinateSystem {
        name: "basic".into(),
        kind: 0,
        origin: [0.0; 3],
        axes: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
    };
    let mut geometry = Geometry {
        frames: HashMap::from([(0, basic)]),
        cord2: HashMap::new(),
        cord1: Vec::new(),
        grid_of: HashMap::new(),
        positions: HashMap::new(),
        stack: Vec::new(),
    };
    for c in &cords {
        if c.name.starts_with("CORD2") {
            let cid = c.id(0, "CID")? as i64;
            let rid = c.int(1, "RID")?.unwrap_or(0);
            if geometry.cord2.insert(cid, (c, rid)).is_some() {
                return Err(c.err(format!("{cid} is defined twice")));
            }
        } else {
            // up to two systems per card: CID G1 G2 G3
            for k in 0..2 {
                let base = 4 * k;
                if c.field(base).is_empty() {
                    continue;
                }
                let cid = c.id(base, "CID")? as i64;
                let g = [
                    c.id(base + 1, "G1")?,
                    c.id(base + 2, "G2")?,
                    c.id(base + 3, "G3")?,
                ];
                geometry.cord1.push((cid, g, c));
            }
        }
    }
    for g in &grids {
        let id = g.id(0, "ID")?;
        if geometry.grid_of.insert(id, *g).is_some() {
            return Err(g.err(format!("{id} is defined twice")));
        }
    }
    let mut mesh = Mesh::new();
    let mut ids: Vec<u64> = geometry.grid_of.keys().copied().collect();
    ids.sort_unstable();
    let mut turned_cd = 0;
    // grids whose displacement frame is turned from the basic one: an SPC on them constrains
    // components femu does not have
    let mut turned: HashMap<u64, i64> = HashMap::new();
    for id in &ids {
        let g = geometry.grid_of[id];
        let p = geometry.position(*id, g)?;
        let cd = g.int(5, "CD")?.unwrap_or(0);
        if cd != 0 {
            turned_cd += 1;
            if !geometry.frame(cd, g)?.is_global_orientation() {
                turned.insert(*id, cd);
            }
        }
        mesh.add_node(*id, p).map_err(g.located())?;
    }
    // elements: Nastran's node order to femu's
    let mut element_pid: Vec<(u64, u64, &Card)> = Vec::new();
    // blank mid-side grids: a node at the edge's midpoint, tied to the average of its ends
    let mut next_id = ids.iter().copied().max().unwrap_or(0);
    let mut straight: HashMap<(u64, u64), u64> = HashMap::new();
    let mut ties: Vec<(u64, u64, u64, String)> = Vec::new();
    let mut first_blank: Option<&Card> = None;
    for c in &elements {
        let eid = c.id(0, "EID")?;
        let pid = c.id(1, "PID")?;
        let mut slots: Vec<Option<u64>> = (2..c.fields.len())
            .map(|i| c.int(i, "G").map(|v| v.map(|v| v as u64)))
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
    if mesh.element_count() == 0 {
        return Err(IoError::Content {
            path: path.to_path_buf(),
            reason: format!(
                "the deck defines {} GRID{} and no solid element (CHEXA, CPENTA, CTETRA)",
                mesh.node_count(),
                if mesh.node_count() == 1 { "" } else { "s" }
            ),
        });
    }
    // materials by property
    let mut by_pid: BTreeMap<u64, Vec<u64>> = BTreeMap::new();
    for (eid, pid, _) in &element_pid {
        by_pid.entry(*pid).or_default().push(*eid);
    }
    for (pid, eids) in &by_pid {
        mesh.add_element_set(format!("PID{pid}"), eids)
            .map_err(|e| IoError::Content {
                path: path.to_path_buf(),
                reason: e.to_string(),
            })?;
    }
    let mut model = Model::new(mesh).map_err(|source| {
        let line = element_pid
            .iter()
            .find(|(eid, _, _)| source.to_string().contains(&format!("element {eid} ")))
            .map(|e| e.2);
        match line {
            Some(c) => IoError::Model {
                path: c.path.clone(),
                line: c.line,
                source,
            },
            None => IoError::Content {
                path: path.to_path_buf(),
                reason: source.to_string(),
            },
        }
    })?;
    for (pid, eids) in &by_pid {
        let first = element_pid
            .iter()
            .find(|e| e.0 == eids[0])
            .expect("listed")
            .2;
        let (mid, pc) = psolids.get(pid).ok_or_else(|| {
            first.err(format!(
                "{} refers to PSOLID {pid}, which the deck does not define",
                eids[0]
            ))
        })?;
        let m = mat1.get(mid).ok_or_else(|| {
            pc.err(format!(
                "{pid} refers to MAT1 {mid}, which the deck does not define (femu reads MAT1 and MAT9)"
            ))
        })?;
        if m.name == "MAT9" {
            // G11 G12 ... G66 (upper triangle by rows) relate (sx, sy, sz, txy, tyz, tzx) to the
            // engineering strains in that order; femu's order is (11, 22, 33, 12, 13, 23)
            let mut g = [[0.0; 6]; 6];
            let mut k = 1;
            for i in 0..6 {
                for j in i..6 {
                    let v = m.real(k, "G")?.unwrap_or(0.0);
                    g[i][j] = v;
                    g[j][i] = v;
                    k += 1;
                }
            }
            let from = [0, 1, 2, 3, 5, 4];
            let d: [[f64; 6]; 6] =
                std::array::from_fn(|i| std::array::from_fn(|j| g[from[i]][from[j]]));
            let rho = m.real(22, "RHO")?.filter(|r| *r > 0.0).ok_or_else(|| {
                m.err(format!(
                    "{mid} has no RHO (a modal analysis needs the density)"
                ))
            })?;
            let material = Material::anisotropic(format!("MAT9 {mid}"), d, rho * wtmass).map_err(
                |source| IoError::Model {
                    path: m.path.clone(),
                    line: m.line,
                    source,
                },
            )?;
            model
                .set_material(Some(&format!("PID{pid}")), material)
                .map_err(pc.located())?;
            continue;
        }
        let (e, g, nu) = (m.real(1, "E")?, m.real(2, "G")?, m.real(3, "NU")?);
        let (e, nu) = match (e, g, nu) {
            (Some(e), _, Some(nu)) => (e, nu),
            (Some(e), Some(g), None) => (e, e / (2.0 * g) - 1.0),
            (None, Some(g), Some(nu)) => (2.0 * g * (1.0 + nu), nu),
            _ => return Err(m.err(format!("{mid}: two of E, G and NU are needed"))),
        };
        let rho = m.real(4, "RHO")?.filter(|r| *r > 0.0).ok_or_else(|| {
            m.err(format!(
                "{mid} has no RHO (a modal analysis needs the density)"
            ))
        })?;
        let material =
            Material::isotropic(format!("MAT1 {mid}"), e, nu, rho * wtmass).map_err(|source| {
                IoError::Model {
                    path: m.path.clone(),
                    line: m.line,
                    source,
                }
            })?;
        model
            .set_material(Some(&format!("PID{pid}")), material)
            .map_err(pc.located())?;
    }
    for (id, ga, gb, label) in &ties {
        for k in 0..3 {
            model
                .add_constraint((*id, k), &[((*ga, k), 0.5), ((*gb, k), 0.5)], label)
                .map_err(|source| IoError::Content {
                    path: path.to_path_buf(),
                    reason: source.to_string(),
                })?;
        }
    }
    if let Some(c) = first_blank {
        warn(
            &mut warnings,
            c,
            format!(
                "{} mid-side grids are blank: those edges are straight and the elements vary linearly along them, as Nastran reads them (femu adds a node at each such midpoint, ids from {}, tied to the average of the edge's ends)",
                ties.len(),
                ties.first().map_or(0, |t| t.0)
            ),
        );
    }
    read_links(&links, &mut model, &turned, &mut warnings)?;
    // constraints: the case control's SPC set, or the only one a bulk-only file has
    let mut sets: BTreeMap<i64, Vec<&Card>> = BTreeMap::new();
    for c in &spcs {
        let sid = c
            .int(0, "SID")?
            .ok_or_else(|| c.err("needs a set id (SID)".into()))?;
        sets.entry(sid).or_default().push(c);
    }
    let chosen = match spc_selected {
        Some(s) => Some(s),
        None if has_case_control => {
            if let Some(c) = spcs.first() {
                warn(
                    &mut warnings,
                    c,
                    "the case control selects no SPC set: the model is free (unconstrained)".into(),
                );
            }
            None
        }
        None => match sets.keys().copied().collect::<Vec<_>>().as_slice() {
            [] => None,
            [one] => {
                warn(
                    &mut warnings,
                    spcs[0],
                    format!("no case control: the deck's only SPC set {one} is applied"),
                );
                Some(*one)
            }
            many => {
                return Err(IoError::Parse {
                    path: spcs[0].path.clone(),
                    line: spcs[0].line,
                    reason: format!(
                        "the deck defines SPC sets {many:?} and no case control selects one (SPC = n before BEGIN BULK)"
                    ),
                });
            }
        },
    };
    if let Some(sid) = chosen {
        let mut todo = vec![sid];
        let mut seen = Vec::new();
        while let Some(s) = todo.pop() {
            if seen.contains(&s) {
                continue;
            }
            seen.push(s);
            let cards = sets.get(&s).cloned().unwrap_or_default();
            if cards.is_empty() {
                return Err(IoError::Content {
                    path: path.to_path_buf(),
                    reason: format!(
                        "SPC set {s} is selected but no SPC, SPC1 or SPCADD defines it"
                    ),
                });
            }
            for c in cards {
                let comps = |c: &Card, i: usize| -> Result<Vec<usize>, IoError> {
                    let t = c.field(i);
                    let mut out = Vec::new();
                    for ch in t.chars() {
                        match ch {
                            '1'..='6' => out.push(ch as usize - '1' as usize),
                            '0' => {}
                            _ => return Err(c.err(format!("component {t:?} is not a list of 1-6"))),
                        }
                    }
                    Ok(out)
                };
                let mut fix = |c: &Card, g: u64, comps: &[usize]| -> Result<(), IoError> {
                    let Some(gi) = model.mesh().node_index(g) else {
                        return Err(c.err(format!(
                            "constrains GRID {g}, which the deck does not define"
                        )));
                    };
                    // rotations exist only on rigid links' reference grids
                    let has_rotations = model.rotation_nodes().contains(&gi);
                    let comps: Vec<usize> = comps
                        .iter()
                        .copied()
                        .filter(|k| *k < 3 || has_rotations)
                        .collect();
                    let comps = comps.as_slice();
                    if let Some(cd) = turned.get(&g).filter(|_| comps.len() < 3) {
                        return Err(c.err(format!(
                            "constrains components {:?} of GRID {g} in its displacement frame {cd}, which is turned from the basic frame: femu constrains basic components only (a constraint in a turned frame needs a multipoint constraint, not read yet)",
                            comps.iter().map(|c| c + 1).collect::<Vec<_>>()
                        )));
                    }
                    model.fix_node_dofs(g, comps).map_err(c.located())
                };
                match c.name.as_str() {
                    "SPC" => {
                        for k in 0..2 {
                            let base = 1 + 3 * k;
                            if c.field(base).is_empty() {
                                continue;
                            }
                            let g = c.id(base, "G")?;
                            let cs = comps(c, base + 1)?;
                            if c.real(base + 2, "D")?.is_some_and(|d| d != 0.0) {
                                warn(
                                    &mut warnings,
                                    c,
                                    "an enforced value is read as 0 (modal analysis)".into(),
                                );
                            }
                            fix(c, g, &cs)?;
                        }
                    }
                    "SPC1" => {
                        let cs = comps(c, 1)?;
                        let rest: Vec<String> = c
                            .fields
                            .get(2..)
                            .unwrap_or_default()
                            .iter()
                            .map(|s| s.trim().to_ascii_uppercase())
                            .filter(|s| !s.is_empty())
                            .collect();
                        let mut grids_here = Vec::new();
                        if rest.len() == 3 && rest[1] == "THRU" {
                            let (a, b) = (rest[0].parse::<u64>(), rest[2].parse::<u64>());
                            match (a, b) {
                                (Ok(a), Ok(b)) if a <= b => {
                                    // the defined grids in the range (not every id of it: a
                                    // range may span billions of ids)
                                    let mut ids: Vec<u64> = geometry
                                        .grid_of
                                        .keys()
                                        .copied()
                                        .filter(|g| (a..=b).contains(g))
                                        .collect();
                                    ids.sort_unstable();
                                    grids_here.extend(ids);
                                }
                                _ => return Err(c.err(format!("THRU range {rest:?} is invalid"))),
                            }
                        } else {
                            for t in &rest {
                                grids_here.push(
                                    t.parse::<u64>()
                                        .map_err(|_| c.err(format!("grid {t:?} is not an id")))?,
                                );
                            }
                        }
                        if rest.is_empty() {
                            return Err(c.err("names no grid (SPC1 SID C G1 G2 ...)".into()));
                        }
                        for g in grids_here {
                            fix(c, g, &cs)?;
                        }
                    }
                    _ => {
                        // SPCADD SID S1 S2 ...
                        if c.fields.iter().skip(1).all(|s| s.trim().is_empty()) {
                            return Err(c.err("names no set (SPCADD SID S1 S2 ...)".into()));
                        }
                        for t in c
                            .fields
                            .get(1..)
                            .unwrap_or_default()
                            .iter()
                            .map(|s| s.trim())
                            .filter(|s| !s.is_empty())
                        {
                            todo.push(
                                t.parse::<i64>()
                                    .map_err(|_| c.err(format!("set {t:?} is not an id")))?,
                            );
                        }
                    }
                }
            }
        }
    }
    if turned_cd > 0
        && let Some(g) = grids
            .iter()
            .find(|g| g.int(5, "CD").ok().flatten().unwrap_or(0) != 0)
    {
        warn(
            &mut warnings,
            g,
            format!(
                "{turned_cd} grids name a displacement frame (CD): femu reports displacements in the basic frame"
            ),
        );
    }
    // point masses, on grids the solids or the links connect (a mass on a free grid would have
    // no stiffness)
    let mut connected = model.constrained_nodes();
    for el in model.mesh().elements() {
        for n in el.nodes {
            connected[*n] = true;
        }
    }
    for c in &conm2 {
        let g = c.id(1, "G")?;
        let m = c
            .real(3, "M")?
            .filter(|m| *m > 0.0)
            .ok_or_else(|| c.err("needs a positive mass M".into()))?;
        let Some(gi) = model.mesh().node_index(g) else {
            return Err(c.err(format!("is on GRID {g}, which the deck does not define")));
        };
        if !connected[gi] {
            let text = format!(
                "{} is on GRID {g}, which no solid element or rigid link connects: it would have no stiffness",
                c.field(0)
            );
            if options.lenient {
                warn(&mut warnings, c, format!("{text}: left out"));
                continue;
            }
            return Err(c.err(text));
        }
        let offset = (4..7).any(|i| c.real(i, "X").ok().flatten().is_some_and(|v| v != 0.0));
        let inertia = (8..14).any(|i| c.real(i, "I").ok().flatten().is_some_and(|v| v != 0.0));
        if model.rotation_nodes().contains(&gi) {
            // a rigid link's reference: offset and inertia act on its rotations
            let cid = c.int(2, "CID")?.unwrap_or(0);
            let x: [f64; 3] = [
                c.real(4, "X1")?.unwrap_or(0.0),
                c.real(5, "X2")?.unwrap_or(0.0),
                c.real(6, "X3")?.unwrap_or(0.0),
            ];
            let xg = model.mesh().coords()[gi];
            // Nastran's I11, I21, I22, I31, I32, I33 about the centre of gravity; the products
            // of inertia are given as magnitudes and enter the matrix negated
            let v = |i: usize| -> Result<f64, IoError> { Ok(c.real(i, "I")?.unwrap_or(0.0)) };
            let local = [
                [v(8)?, -v(9)?, -v(11)?],
                [-v(9)?, v(10)?, -v(12)?],
                [-v(11)?, -v(12)?, v(13)?],
            ];
            let (d, axes) = match cid {
                -1 => (std::array::from_fn(|i| x[i] - xg[i]), None),
                0 => (x, None),
                cid => {
                    let a = geometry.frame(cid, c)?.axes_at(xg);
                    (
                        std::array::from_fn(|i| (0..3).map(|j| a[i][j] * x[j]).sum()),
                        Some(a),
                    )
                }
            };
            // inertia in basic axes: R J R^T (R's columns the frame's axes)
            let j: [[f64; 3]; 3] = match axes {
                None => local,
                Some(a) => std::array::from_fn(|i| {
                    std::array::from_fn(|k| {
                        (0..3)
                            .map(|p| (0..3).map(|q| a[i][p] * local[p][q] * a[k][q]).sum::<f64>())
                            .sum()
                    })
                }),
            };
            model
                .add_rigid_mass(g, m * wtmass, d, j.map(|r| r.map(|v| v * wtmass)))
                .map_err(c.located())?;
            continue;
        }
        if offset || inertia {
            warn(
                &mut warnings,
                c,
                format!(
                    "{}: the grid has no rotations (only RBE2 reference grids have), so its {} dropped (the translational mass is kept)",
                    c.field(0),
                    match (offset, inertia) {
                        (true, true) => "offset and rotational inertia are",
                        (true, false) => "offset is",
                        _ => "rotational inertia is",
                    }
                ),
            );
        }
        model.add_point_mass(g, m * wtmass).map_err(c.located())?;
    }
    // conflicts between links and constraints, found now rather than at the first solve
    model.dof_map().map_err(|source| IoError::Content {
        path: path.to_path_buf(),
        reason: source.to_string(),
    })?;
    Ok(BdfDeck {
        model,
        eigrl,
        warnings,
    })
}

/// Components `1-6` of a field as 0-based indices.
fn components(c: &Card, i: usize, what: &str) -> Result<Vec<usize>, IoError> {
    let t = c.field(i);
    let mut out = Vec::new();
    for ch in t.chars() {
        match ch {
            '1'..='6' => {
                let k = ch as usize - '1' as usize;
                if !out.contains(&k) {
                    out.push(k);
                }
            }
            _ => {
                return Err(c.err(format!(
                    "field {} ({what}): {t:?} is not a list of components 1-6",
                    i + 2
                )));
            }
        }
    }
    if out.is_empty() {
        return Err(c.err(format!("field {} ({what}) is missing", i + 2)));
    }
    Ok(out)
}

/// RBE2 (rigid links) and RBE3 (weighted averages) into the model's multipoint constraints
/// (docs/MATH.md, "Multipoint constraints"). Reference grids of RBE2 get rotations first, so that
/// RBE2 chains, RBE3 references with rotational components and SPCs on 4-6 find them.
fn read_links(
    links: &[&Card],
    model: &mut Model,
    turned: &HashMap<u64, i64>,
    warnings: &mut Vec<Warning>,
) -> Result<(), IoError> {
    let grid = |model: &Model, c: &Card, g: u64| -> Result<usize, IoError> {
        model.mesh().node_index(g).ok_or_else(|| {
            c.err(format!(
                "{} names GRID {g}, which the deck does not define",
                c.field(0)
            ))
        })
    };
    for c in links.iter().filter(|c| c.name == "RBE2") {
        let gn = c.id(1, "GN")?;
        grid(model, c, gn)?;
        model.add_rotations(gn).map_err(c.located())?;
    }
    let mut noted_rotations = false;
    for c in links {
        let eid = c.id(0, "EID")?;
        let label = format!("{} {eid} ({} line {})", c.name, c.path.display(), c.line);
        if c.name == "RBE2" {
            let gn = c.id(1, "GN")?;
            let cm = components(c, 2, "CM")?;
            let mut gm = Vec::new();
            for t in c
                .fields
                .get(3..)
                .unwrap_or_default()
                .iter()
                .map(|s| s.trim())
            {
                if t.is_empty() {
                    continue;
                }
                // the optional ALPHA (and TREF) after the grids are reals
                if t.contains('.') || t.contains(['E', 'e']) {
                    break;
                }
                let g =
                    t.parse::<u64>().ok().filter(|g| *g > 0).ok_or_else(|| {
                        c.err(format!("{eid}: dependent grid {t:?} is not an id"))
                    })?;
                grid(model, c, g)?;
                gm.push(g);
            }
            if gm.is_empty() {
                return Err(c.err(format!("{eid} has no dependent grids (GMi)")));
            }
            let trans: Vec<usize> = cm.iter().copied().filter(|k| *k < 3).collect();
            if trans.len() < 3
                && let Some(g) = gm.iter().find(|g| turned.contains_key(g))
            {
                return Err(c.err(format!(
                    "{eid}: components {} of GRID {g} are in its displacement frame {}, which is turned: femu links partial components in the basic frame only",
                    c.field(2),
                    turned[g]
                )));
            }
            model
                .add_rigid_link(gn, &gm, &trans, &label)
                .map_err(c.located())?;
            // rotations of dependents that carry them (another link's reference) follow GN's
            let rot: Vec<usize> = cm.iter().copied().filter(|k| *k >= 3).collect();
            for &g in &gm {
                let gi = grid(model, c, g)?;
                if model.rotation_nodes().contains(&gi) {
                    for &k in &rot {
                        model
                            .add_constraint((g, k), &[((gn, k), 1.0)], &label)
                            .map_err(c.located())?;
                    }
                } else if !rot.is_empty() && !noted_rotations {
                    noted_rotations = true;
                    warnings.push(Warning {
                        path: c.path.clone(),
                        line: c.line,
                        message: format!(
                            "RBE2 {eid}: components 4-6 of solid grids are ignored (they have no rotations; the rigid link acts on their translations)"
                        ),
                    });
                }
            }
        } else {
            // RBE3 EID, blank, REFGRID, REFC, then groups WTi Ci Gi,j ..., then UM / ALPHA
            let refgrid = c.id(2, "REFGRID")?;
            let refi = grid(model, c, refgrid)?;
            let refc = components(c, 3, "REFC")?;
            let mut nodes: Vec<(u64, f64)> = Vec::new();
            let mut k = 4;
            while k < c.fields.len() {
                let t = c.field(k).to_ascii_uppercase();
                if t.is_empty() {
                    k += 1;
                    continue;
                }
                if t == "UM" {
                    return Err(c.err(format!(
                        "{eid}: UM (other dependent DOFs) is not supported; femu makes REFGRID's REFC dependent"
                    )));
                }
                if t == "ALPHA" || t == "TREF" {
                    break;
                }
                let w = c.real(k, "WT")?.filter(|w| *w > 0.0).ok_or_else(|| {
                    c.err(format!(
                        "{eid}: field {} should be a positive weight WTi, got {t:?}",
                        k + 2
                    ))
                })?;
                let ci = components(c, k + 1, "Ci")?;
                if !(0..3).all(|j| ci.contains(&j)) {
                    return Err(c.err(format!(
                        "{eid}: components {} of a weight group: femu averages all three translations (C = 123 or 123456)",
                        c.field(k + 1)
                    )));
                }
                k += 2;
                let before = nodes.len();
                while k < c.fields.len() {
                    let t = c.field(k);
                    if t.is_empty() {
                        k += 1;
                        continue;
                    }
                    if t.contains('.') || t.chars().any(|ch| ch.is_ascii_alphabetic()) {
                        break;
                    }
                    let g = c.id(k, "Gi,j")?;
                    grid(model, c, g)?;
                    nodes.push((g, w));
                    k += 1;
                }
                if nodes.len() == before {
                    return Err(c.err(format!("{eid}: weight {w} has no grids")));
                }
            }
            let has_rot = model.rotation_nodes().contains(&refi);
            let comps: Vec<usize> = refc.iter().copied().filter(|k| *k < 3 || has_rot).collect();
            model
                .add_weighted_average(refgrid, &comps, &nodes, &label)
                .map_err(c.located())?;
        }
    }
    Ok(())
}
