//! Nastran bulk data (`.bdf`, `.dat`, `.nas`): the solid models of automotive and aerospace
//! correlation work, read as MSC Nastran reads them (its Quick Reference Guide, QRG, cited by
//! section), or refused with card and line; never a different model with exit 0.
//!
//! - **Fields** (`cards.rs`): small, large (`NAME*`) and free field (commas; a short free-field
//!   line's missing fields are blank; the QRG's large-field free format `GRID*,...` and `*`
//!   continuation), implicit exponents (`7.+10`), `$` comments, `INCLUDE`, `ENDDATA`.
//!   Continuations pair with their parent by label (field 1 of the continuation against field 10
//!   of the parent, wherever it is); a bare `+`, `*` or blank field 1 continues the card above; a
//!   label no card holds is an error.
//! - **Case control** (`case_control.rs`): commands by their grammar (`SPC = n`, not a prefix of
//!   `SPCFORCES`; `$` comments; four-letter abbreviations such as `METH`; `SUBCASE` blocks
//!   inheriting the commands above them). The `SPC` set and the `METHOD` (the EIGRL or EIGR of
//!   the modes) are read; subcases that select different ones are refused (femu solves one model).
//! - **Mass** (QRG PARAM COUPMASS): lumped unless `PARAM,COUPMASS` is positive, MSC Nastran's
//!   default ([`BdfDeck::mass`]); `PARAM,WTMASS` scales every mass. Other PARAMs do not change a
//!   solid model's `K` or `M` (`K6ROT` acts on shells only; output and solution controls) and are
//!   named as skipped.
//! - **Damping** of frequency responses: each material's `GE` (MAT1, MAT2, MAT8, MAT9; a PCOMP's
//!   own) damps its elements (`Model::set_element_damping`), springs and bushings carry theirs,
//!   and `PARAM,G` is the whole model's loss factor (`Model::uniform_damping`), which `femu frf`
//!   uses when told no other; the case control's `SDAMPING` selects a `TABDMP1`, the modes'
//!   damping as a function of their frequency (`Model::modal_damping`).
//! - **Constraints** (`constraints.rs`): the selected SPC set (`SPC`, `SPC1`, `SPCADD`) and the
//!   permanent constraints of GRID field 8 (`PS`), with `GRDSET`'s CP, CD and PS for grids that
//!   leave them blank. Components 4-6 act on grids with rotations (those of beams, springs and
//!   bushings, RBE2 reference grids) only.
//! - **Elements**: `CHEXA` (8/20), `CPENTA` (6/15), `CTETRA` (4/10), `CPYRAM` (5/13) in Nastran's
//!   grid order; blank mid-side grids make a straight edge (a node at its midpoint tied to the
//!   average of its ends, docs/MATH.md "Multipoint constraints"). MSC integrates 8-node CHEXA and
//!   6-node CPENTA with reduced shear and bubble functions unless the PSOLID asks for `IN = 2`,
//!   `ISOP = FULL`; femu builds the fully integrated elements and says so once per property.
//! - **Materials** (`materials.rs`): `PSOLID` with `MAT1` completed as the QRG's MAT1 remarks say
//!   (three moduli that are not isotropic within 1 % refused) or `MAT9` in the material frame
//!   `CORDM` (a rectangular system; cylindrical, spherical and the element frame refused).
//! - **Bars, beams, rods, springs, bushings, shells** (`structural.rs`): `CBAR`, `CBEAM`, `CROD`,
//!   `CONROD`, `CELAS1`, `CELAS2`, `CBUSH`, `CQUAD4`, `CQUAD8`, `CTRIA3` with `PBAR`, `PBARL`, `PBEAM`, `PBEAML`,
//!   `PROD`, `PELAS`, `PBUSH`, `PSHELL` and `BAROR`/`BEAMOR` defaults, into femu's structural elements on grids with
//!   rotations (docs/MATH.md, "Beams, springs and bushings"); each property's elements are the set
//!   `PID<n>`.
//! - **Links and masses** (`links.rs`, `masses.rs`): `RBE2`, `RBE3`, `CONM2` (a rigid mass with
//!   offset, `CID` frame and inertia on a grid with rotations (a beam's, a bushing's, an RBE2
//!   reference), or on a grid an RBE2 moves in all six components, carried to its reference;
//!   elsewhere the translational mass, as `AUTOSPC` leaves it).
//! - **Unknown cards** are errors naming the nearest known card; cards that cannot change `K` or
//!   `M` (loads, output requests, tables) and cards that act only in other solutions (contact,
//!   nonlinear controls, temperature-dependent materials) are warnings, once per card name. Cards
//!   that change `K` or `M` and that femu cannot model (shells, scalar dampers, RBAR and MPC, other
//!   materials) are an error that counts them by kind. [`BdfOptions::lenient`] reads the rest
//!   with a warning (unknown cards skipped; for the unsupported ones, that `K` and `M` are then
//!   incomplete).

mod cards;
mod case_control;
mod constraints;
mod design;
mod dmig;
mod elements;
mod geometry;
mod links;
mod masses;
mod materials;
mod structural;

use crate::{IoError, Warning};
pub use cards::real;
use cards::{Card, Line};
pub use dmig::{Dmig, read_dmig};
use femu_fem::assembly::MassKind;
use femu_fem::element::Formulation;
use femu_fem::mesh::Mesh;
use femu_fem::model::Model;
use geometry::Geometry;
use std::collections::{BTreeMap, HashMap};
use std::path::{Path, PathBuf};

/// The modes an `EIGRL` asks for: `V1`, `V2` in Hz and `ND`.
pub type Eigrl = (Option<f64>, Option<f64>, Option<usize>);

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
    /// The modes the `EIGRL` (or `EIGR`) the case control's `METHOD` selects asks for (`V1`, `V2`
    /// in Hz, `ND`); the deck's only one when nothing is selected.
    pub eigrl: Option<Eigrl>,
    /// The mass formulation the deck asks for: MSC Nastran's default, lumped, unless
    /// `PARAM,COUPMASS` is positive (QRG PARAM COUPMASS).
    pub mass: MassKind,
    /// The value of `PARAM,COUPMASS`, when the deck gives one.
    pub coupmass: Option<i64>,
    /// Grids with permanent single-point constraints (GRID field 8, `PS`, or GRDSET's).
    pub permanent_constraints: usize,
    /// The SPC set the case control selects.
    pub spc_set: Option<i64>,
    /// Findings that did not stop the reading.
    pub warnings: Vec<Warning>,
}

/// Cards that cannot change `K` or `M`: read past with a warning.
const NO_EFFECT: &[&str] = &[
    "PARAM", "FORCE", "MOMENT", "LOAD", "DLOAD", "RLOAD1", "RLOAD2", "TLOAD1", "TLOAD2", "TABLED1",
    "TABLED2", "TABLED3", "TABLED4", "FREQ", "FREQ1", "FREQ2", "GRAV", "TEMP", "TEMPD", "PLOAD",
    "PLOAD2", "PLOAD4", "EIGR", "EIGRL", "SPOINT", "DAREA", "NSM", "SET1", "DESVAR", "DRESP1",
    "DCONSTR", "MONPNT1", "ASET", "ASET1", "OMIT", "OMIT1", "SUPORT", "SUPORT1", "MDLPRM", "LSEQ",
    "RLOAD1", "RLOAD2", "USET", "USET1",
    // plot elements (lines drawn between grids) and monitor points (loads and displacements
    // integrated for output): neither stiffness nor mass
    "PLOTEL", "MONDSP1", "MONPNT3",
    // design optimisation data (SOL 200) that leaves the initial design as the cards give it
    // (a DVGRID moves its grid by the change of its design variable from XINIT: none at first)
    "DCONADD", "DRESP2", "DRESP3", "DVGRID", "DLINK", "DOPTPRM", "DEQATN", "DTABLE", "DSCREEN",
    // aeroelastic data (QRG, "Aeroelastic"): the aerodynamic model, its splines to the
    // structure and the flutter, trim and gust conditions act on the modes, not in `K` or `M`
    "AERO", "AEROS", "AEFACT", "AELINK", "AELIST", "AEPARM", "AESTAT", "AESURF", "AESURFS",
    "AECOMP", "AECOMPL", "AEDW", "AEFORCE", "AEPRESS", "AESCALE", "CAERO1", "CAERO2", "CAERO3",
    "CAERO4", "CAERO5", "PAERO1", "PAERO2", "PAERO3", "PAERO4", "PAERO5", "SPLINE1", "SPLINE2",
    "SPLINE3", "SPLINE4", "SPLINE5", "SPLINE6", "SPLINE7", "MKAERO1", "MKAERO2", "FLFACT",
    "FLUTTER", "GUST", "TRIM", "TRIM2", "DIVERG", "CSSCHD", "UXVEC", "MONPNT2",
];

/// Cards that change `K` or `M` and that femu cannot model yet, with what they are.
const UNSUPPORTED: &[(&str, &str)] = &[
    ("CQUADR", "shells"),
    ("CTRIAR", "shells"),
    ("CELAS3", "scalar springs on scalar points"),
    ("CELAS4", "scalar springs on scalar points"),
    (
        "DVPREL2",
        "design relations (SOL 200 sets the initial design's properties from them)",
    ),
    (
        "DVCREL1",
        "design relations (SOL 200 sets the initial design's properties from them)",
    ),
    (
        "DVCREL2",
        "design relations (SOL 200 sets the initial design's properties from them)",
    ),
    (
        "DVMREL1",
        "design relations (SOL 200 sets the initial design's properties from them)",
    ),
    (
        "DVMREL2",
        "design relations (SOL 200 sets the initial design's properties from them)",
    ),
    ("TF", "transfer functions"),
    ("CMASS3", "scalar masses on scalar points"),
    ("CMASS4", "scalar masses on scalar points"),
    ("CDAMP3", "scalar dampers on scalar points"),
    ("CDAMP4", "scalar dampers on scalar points"),
    ("CBEND", "curved beams"),
    ("PBEND", "curved beams"),
    ("PBCOMP", "composite beams"),
    ("PBRSECT", "arbitrary beam sections"),
    ("PBMSECT", "arbitrary beam sections"),
    ("RTRPLT", "rigid triangles"),
    ("RTRPLT1", "rigid triangles"),
    ("RSPLINE", "interpolation constraints"),
    ("RSSCON", "shell-solid connectors"),
    ("RJOINT", "rigid joints"),
    ("CORD3G", "coordinate systems"),
    ("GENEL", "general elements"),
];

/// Whether the first kilobytes `head` of a file are a Nastran deck's: the first line that is not
/// blank or a comment (`$` Nastran's, `**` Abaqus') is an executive or case control statement
/// (`SOL`, `ID`, `TIME`, `CEND`, `NASTRAN`, `ASSIGN`, `INIT`, `DIAG`, `BEGIN BULK`) or a bulk data
/// card in free, small or large field (`GRID`, `GRID*`, `CQUAD4,`), and no line begins an Abaqus
/// keyword (`*` then a letter) before it. MSC's own examples name such decks `.inp`.
pub fn looks_like_nastran(head: &str) -> bool {
    let Some(first) = head
        .lines()
        .map(str::trim_end)
        .find(|l| !l.trim().is_empty() && !l.starts_with('$') && !l.starts_with("**"))
    else {
        return false;
    };
    if first.starts_with('*') {
        return false;
    }
    let word: String = first
        .trim_start()
        .chars()
        .take_while(|c| c.is_ascii_alphanumeric())
        .collect::<String>()
        .to_ascii_uppercase();
    let statements = [
        "SOL", "ID", "TIME", "CEND", "NASTRAN", "ASSIGN", "INIT", "DIAG", "BEGIN", "APP",
    ];
    if statements.contains(&word.as_str()) {
        return true;
    }
    // a bulk card: a known card name followed by a field separator
    let rest = &first.trim_start()[word.len()..];
    [
        "GRID", "CORD2R", "CORD2C", "MAT1", "PSHELL", "PSOLID", "CQUAD4", "CTRIA3", "CHEXA",
        "CTETRA", "CBAR", "CBEAM", "CONM2", "PARAM", "EIGRL",
    ]
    .contains(&word.as_str())
        && (rest.starts_with(',')
            || rest.starts_with(' ')
            || rest.starts_with('*')
            || rest.starts_with('\t'))
}

/// Reads a bulk data deck.
///
/// # Errors
/// As [`parse_bdf`], and the file system's.
pub fn read_bdf(path: impl AsRef<Path>, options: &BdfOptions) -> Result<BdfDeck, IoError> {
    let mut lines = Vec::new();
    cards::load(path.as_ref(), 0, &mut lines)?;
    parse_lines(&lines, path.as_ref(), options)
}

/// A grid point read for where it is and how its displacements are written.
#[derive(Debug, Clone, PartialEq)]
pub struct GridPoint {
    /// The grid id.
    pub id: u64,
    /// Its position in the basic frame.
    pub position: [f64; 3],
    /// Its displacement frame (`CD`, GRID field 7, or GRDSET's), 0 the basic frame.
    pub cd: i64,
    /// The displacement frame's axes at the grid in basic components (`axes[i][j]`: component `i`
    /// of direction `j`; the identity for the basic frame): a result `u` in the CD frame is
    /// `axes u` in the basic frame.
    pub axes: [[f64; 3]; 3],
}

/// The grids of a deck (with its `INCLUDE`s) in the basic frame, with their displacement frames,
/// and nothing else: the geometry of a model another run of Nastran solved (its `.f06`), whatever
/// elements it has. `GRID`, `GRDSET` and the `CORD1/2R/C/S` frames are read as
/// [`read_bdf`] reads them; every other card is left alone.
///
/// # Errors
/// The file system's; [`IoError::Parse`] naming the card's line for a malformed GRID or frame, a
/// frame cycle or an unknown frame; [`IoError::Content`] for a deck without GRID.
pub fn read_grids(path: impl AsRef<Path>) -> Result<Vec<GridPoint>, IoError> {
    let path = path.as_ref();
    let mut lines = Vec::new();
    cards::load(path, 0, &mut lines)?;
    let deck = cards::deck(&lines)?;
    let grids: Vec<&Card> = deck.cards.iter().filter(|c| c.name == "GRID").collect();
    let cords: Vec<&Card> = deck
        .cards
        .iter()
        .filter(|c| c.name.starts_with("CORD1") || c.name.starts_with("CORD2"))
        .collect();
    let grdset = deck.cards.iter().find(|c| c.name == "GRDSET");
    if grids.is_empty() {
        return Err(IoError::Content {
            path: path.to_path_buf(),
            reason: "the deck defines no GRID".into(),
        });
    }
    let mut geometry = Geometry::new(&cords, &grids, grdset)?;
    let mut ids: Vec<u64> = geometry.grid_of.keys().copied().collect();
    ids.sort_unstable();
    let identity = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    ids.iter()
        .map(|id| {
            let g = geometry.grid_of[id];
            let position = geometry.position(*id, g)?;
            let cd = geometry.grid_int(g, 5, "CD")?.unwrap_or(0);
            let axes = if cd == 0 {
                identity
            } else {
                geometry.frame(cd, g)?.axes_at(position)
            };
            Ok(GridPoint {
                id: *id,
                position,
                cd,
                axes,
            })
        })
        .collect()
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

/// The bulk data's cards sorted by what they define.
#[derive(Default)]
struct Sorted<'a> {
    grids: Vec<&'a Card>,
    grdset: Option<&'a Card>,
    cords: Vec<&'a Card>,
    elements: Vec<&'a Card>,
    psolids: HashMap<u64, (u64, &'a Card)>,
    materials: HashMap<u64, &'a Card>,
    spcs: Vec<&'a Card>,
    /// `MPC` and `MPCADD` cards.
    mpcs: Vec<&'a Card>,
    conm2: Vec<&'a Card>,
    links: Vec<&'a Card>,
    structural: structural::StructuralCards<'a>,
    /// `EIGRL` and `EIGR` cards by set id.
    methods: BTreeMap<i64, &'a Card>,
    wtmass: f64,
    coupmass: Option<(i64, &'a Card)>,
    /// `PARAM,G`: the uniform structural damping coefficient.
    g: Option<(f64, &'a Card)>,
    /// `PARAM,ALPHA1` and `PARAM,ALPHA2`: the Rayleigh damping `ALPHA1 M + ALPHA2 K` of a
    /// frequency response.
    alpha: [Option<(f64, &'a Card)>; 2],
    /// `PARAM,KDAMP`, when given.
    kdamp: Option<(i64, &'a Card)>,
    /// `TABDMP1` cards by table id.
    tabdmp: BTreeMap<i64, &'a Card>,
    /// `DVPREL1` design relations, checked at the initial design.
    dvprel1: Vec<&'a Card>,
    /// `DMIG` direct matrices, checked against the case control that selects them.
    dmigs: Vec<&'a Card>,
    /// `PARAM,CK2` and `PARAM,CM2`: the factors of the direct stiffness and mass (`K2GG`,
    /// `M2GG`).
    ck2: f64,
    cm2: f64,
}

fn warn(warnings: &mut Vec<Warning>, c: &Card, message: String) {
    warnings.push(Warning {
        path: c.path.clone(),
        line: c.line,
        message,
    })
}

/// `PARAM`s that change neither stiffness nor mass of a solid model: output requests, solution
/// controls, and `K6ROT` (the drilling stiffness of shells).
const PARAM_NO_EFFECT: &[&str] = &[
    "POST", "PRTMAXIM", "GRDPNT", "AUTOSPC", "MAXRATIO", "BAILOUT", "OGEOM", "NOCOMPS", "SNORM",
    "PATVER", "PRGPST", "OUGCORD", "EST", "NOFISR", "SRCOMPS", "OMACHPR", "USETPRT", "K6ROT",
    "RESVEC", "PEDGEP", "LGDISP", "NASPRT", "PRTGPL", "PRTEQXIN", "PRTGPDT", "PRTCSTM", "PRTBGPDT",
    "PRTGPTT", "PRTMGG", "PRTPG", "DBALL", "DBDICT", "CHECKOUT", "SEMAP", "OLDSEQ", "TINY", "W3",
    "W4", "OIBULK", "POSTEXT", "UNITSYS", "LFREQ", "HFREQ", "LMODES", "NOELOF", "NOELOP", "NOGPF",
    "SRTOUT", "PRTRESLT",
];

/// Cards that act only in other solutions than a linear modal one: contact (nonlinear or contact
/// solutions), nonlinear and transient controls, temperature-dependent material tables (a modal
/// analysis has no temperature field): skipped with a warning that says why.
const OTHER_SOLUTIONS: &[(&str, &str)] = &[
    ("EPOINT", "extra points (the dynamic responses' p-set)"),
    ("BCTSET", "contact"),
    ("BCTPARA", "contact"),
    ("BCTPARM", "contact"),
    ("BCTADD", "contact"),
    ("BCRPARA", "contact"),
    ("BCPARA", "contact"),
    ("BCPROP", "contact"),
    ("BCBODY", "contact"),
    ("BCONP", "contact"),
    ("BSURF", "contact"),
    ("BSURFS", "contact"),
    ("BLSEG", "contact"),
    ("BFRIC", "contact"),
    ("NLPARM", "nonlinear solution controls"),
    ("NLPCI", "nonlinear solution controls"),
    ("TSTEP", "transient solution controls"),
    ("TSTEPNL", "nonlinear solution controls"),
    ("MATT1", "temperature-dependent material properties"),
    ("MATT9", "temperature-dependent material properties"),
    ("TABLEM1", "temperature-dependent material properties"),
    ("TABLEM2", "temperature-dependent material properties"),
    ("TABLEM3", "temperature-dependent material properties"),
    ("TABLEM4", "temperature-dependent material properties"),
    ("TABLES1", "nonlinear material properties"),
    ("TABLEST", "nonlinear material properties"),
];

/// Every card name the reader knows, for the nearest spelling of an unknown one.
fn known_cards() -> Vec<&'static str> {
    let mut v: Vec<&'static str> = vec![
        "GRID", "GRDSET", "CORD2R", "CORD2C", "CORD2S", "CORD1R", "CORD1C", "CORD1S", "CHEXA",
        "CPENTA", "CTETRA", "CPYRAM", "PSOLID", "MAT1", "MAT9", "MAT2", "MAT8", "SPC", "SPC1",
        "SPCADD", "MPC", "MPCADD", "CONM2", "CONM1", "RBE2", "RBE3", "RBAR", "RBAR1", "RROD",
        "RBE1", "PARAM", "EIGRL", "EIGR", "BAROR", "BEAMOR",
    ];
    v.extend(structural::ELEMENTS);
    v.extend(structural::PROPERTIES);
    v.extend(NO_EFFECT);
    v.extend(UNSUPPORTED.iter().map(|(n, _)| *n));
    v.extend(OTHER_SOLUTIONS.iter().map(|(n, _)| *n));
    v
}

/// Sorts the cards, reads the `PARAM`s that change the model (`WTMASS`, `COUPMASS`), and refuses
/// what femu cannot model (counted by kind) and unknown cards (naming the nearest known one),
/// unless `lenient`.
fn sort<'a>(
    cards: &'a [Card],
    options: &BdfOptions,
    warnings: &mut Vec<Warning>,
) -> Result<Sorted<'a>, IoError> {
    let mut s = Sorted {
        wtmass: 1.0,
        ck2: 1.0,
        cm2: 1.0,
        ..Default::default()
    };
    // what cannot be modelled: counted by kind
    let mut unsupported: BTreeMap<&str, (usize, Vec<&str>, &Card)> = BTreeMap::new();
    let mut warned: Vec<String> = Vec::new();
    let known = known_cards();
    for c in cards {
        match c.name.as_str() {
            "GRID" => s.grids.push(c),
            "GRDSET" => {
                if let Some(first) = s.grdset.replace(c) {
                    return Err(c.err(format!(
                        "appears twice (first at line {}): a deck has one GRDSET",
                        first.line
                    )));
                }
            }
            "CORD2R" | "CORD2C" | "CORD2S" | "CORD1R" | "CORD1C" | "CORD1S" => s.cords.push(c),
            "CHEXA" | "CPENTA" | "CTETRA" | "CPYRAM" => s.elements.push(c),
            "PSOLID" => {
                let pid = c.id(0, "PID")?;
                let mid = c.id(1, "MID")?;
                if s.psolids.insert(pid, (mid, c)).is_some() {
                    return Err(c.err(format!("{pid} is defined twice")));
                }
            }
            "MAT1" | "MAT9" | "MAT2" | "MAT8" => {
                let mid = c.id(0, "MID")?;
                if let Some(first) = s.materials.insert(mid, c) {
                    return Err(c.err(format!(
                        "{mid} is defined twice (first as {} at line {}: MAT1, MAT2, MAT8 and MAT9 share ids)",
                        first.name, first.line
                    )));
                }
            }
            "SPC" | "SPC1" | "SPCADD" => s.spcs.push(c),
            "MPC" | "MPCADD" => s.mpcs.push(c),
            "CONM2" | "CONM1" => s.conm2.push(c),
            "RBE2" | "RBE3" | "RBAR" | "RBAR1" | "RROD" | "RBE1" => s.links.push(c),
            "TABDMP1" => {
                let tid = c.id(0, "TID")? as i64;
                if let Some(first) = s.tabdmp.insert(tid, c) {
                    return Err(c.err(format!(
                        "{tid} is defined twice (first at line {})",
                        first.line
                    )));
                }
            }
            "EIGRL" | "EIGR" => {
                let sid = c.id(0, "SID")? as i64;
                if s.methods.insert(sid, c).is_some() {
                    return Err(c.err(format!("{sid} is defined twice (EIGRL and EIGR share ids)")));
                }
            }
            "PARAM" => param(c, &mut s, &mut warned, warnings)?,
            "DVPREL1" => s.dvprel1.push(c),
            "DMIG" => s.dmigs.push(c),
            _ if s.structural.take(c)? => {}
            name => {
                if let Some((card, kind)) = UNSUPPORTED.iter().find(|(n, _)| *n == name) {
                    let e = unsupported.entry(kind).or_insert((0, Vec::new(), c));
                    e.0 += 1;
                    if !e.1.contains(card) {
                        e.1.push(card);
                    }
                } else {
                    // skipped cards are named once per card name
                    let message = if let Some((_, what)) =
                        OTHER_SOLUTIONS.iter().find(|(n, _)| *n == name)
                    {
                        format!(
                            "{name} skipped: {what} act in other solutions, not in a linear modal analysis's stiffness and mass (once per card name)"
                        )
                    } else if NO_EFFECT.contains(&name) {
                        format!(
                            "{name} skipped: it does not change the stiffness or the mass (once per card name)"
                        )
                    } else {
                        let hint = crate::spelling::nearest(name, known.iter().copied())
                            .map_or(String::new(), |k| format!(" (did you mean {k}?)"));
                        let text = format!("unknown card {name}{hint}");
                        if !options.lenient {
                            return Err(IoError::Parse {
                                path: c.path.clone(),
                                line: c.line,
                                reason: format!(
                                    "{text}: femu cannot tell whether it changes the stiffness or the mass (--lenient skips unknown cards with a warning)"
                                ),
                            });
                        }
                        format!(
                            "{text} skipped (--lenient): check that it changes neither stiffness nor mass (once per card name)"
                        )
                    };
                    if !warned.contains(&c.name) {
                        warned.push(c.name.clone());
                        warn(warnings, c, message);
                    }
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
            "the deck has cards that change the stiffness or the mass and that femu cannot model: {}; femu models solids (CHEXA 8/20, CPENTA 6/15, CTETRA 4/10, CPYRAM 5/13) with MAT1 or MAT9, bars and beams (CBAR, CBEAM with PBAR, PBARL, PBEAM, PBEAML), rods (CROD, CONROD, CTUBE), springs, dampers, scalar masses and bushings (CELAS1, CELAS2, CDAMP1, CDAMP2, CMASS1, CMASS2, CVISC, CBUSH, CBUSH1D), shells (CQUAD4, CQUAD8, CTRIA3, CTRIA6 with PSHELL, PCOMP, PCOMPG), CONM2 and CONM1 masses, RBE2, RBAR, RBAR1, RBE1, RROD and RBE3 links, MPC and SPC constraints",
            list.join(", ")
        );
        if options.lenient {
            warn(
                warnings,
                first,
                format!("{text}: left out (--lenient), so the model's K and M are incomplete"),
            );
        } else {
            return Err(IoError::Parse {
                path: first.path.clone(),
                line: first.line,
                reason: format!("{text} (--lenient reads the rest)"),
            });
        }
    }
    if let Err(e) = design::check_dvprel1(cards, &s.dvprel1, warnings) {
        if !options.lenient {
            return Err(e);
        }
        warnings.push(Warning {
            path: s.dvprel1[0].path.clone(),
            line: s.dvprel1[0].line,
            message: format!("{e}; read as the analysis model gives it (--lenient)"),
        });
    }
    Ok(s)
}

/// The `DMIG` matrices against the case control (QRG DMIG, remark 1: a DMIG acts only where a
/// `K2GG`, `M2GG`, `K42GG`, `B2GG`, `K2PP`, `M2PP` or `B2PP` command names it). Those `K2GG`,
/// `M2GG` and `K42GG` add to the structure's stiffness, mass and structural damping are returned,
/// `(command, name, factor)`, for [`add_direct`]; one that only the dynamic responses' commands
/// name (`B2GG`, `K2PP`, `M2PP`, `B2PP`: viscous damping, or the p-set of the responses, not the
/// normal modes) and one no command names are read past with a warning. A command given on two
/// lines is refused (Nastran takes one).
fn direct_matrices(
    dmigs: &[&Card],
    case_control: &case_control::CaseControl,
    warnings: &mut Vec<Warning>,
) -> Result<Vec<(String, String, f64)>, IoError> {
    let mut selected = Vec::new();
    for (k, d) in case_control.direct.iter().enumerate() {
        if let Some(first) = case_control.direct[..k]
            .iter()
            .find(|e| e.0 == d.0 && (e.3 != d.3 || e.4 != d.4))
        {
            return Err(IoError::Parse {
                path: d.3.clone(),
                line: d.4,
                reason: format!(
                    "{} is given again (first at {} line {}): Nastran takes one {} command; list the matrices on it ({} = (A, 2.*B))",
                    d.0,
                    first.3.display(),
                    first.4,
                    d.0,
                    d.0
                ),
            });
        }
    }
    let mut names: Vec<(String, &Card)> = Vec::new();
    for c in dmigs {
        let name = c.field(0).to_ascii_uppercase();
        if !names.iter().any(|(n, _)| *n == name) {
            names.push((name, c));
        }
    }
    for (name, c) in names {
        let by: Vec<&(String, String, f64, PathBuf, usize)> =
            case_control.direct.iter().filter(|d| d.1 == name).collect();
        for (command, _, factor, _, _) in by
            .iter()
            .filter(|d| matches!(d.0.as_str(), "K2GG" | "M2GG" | "K42GG"))
        {
            selected.push((command.clone(), name.clone(), *factor));
        }
        if by
            .iter()
            .any(|d| matches!(d.0.as_str(), "K2GG" | "M2GG" | "K42GG"))
        {
            continue;
        }
        if let Some((command, _, _, _, _)) = by.first() {
            warn(
                warnings,
                c,
                format!(
                    "DMIG {name} skipped: {command} adds it to the dynamic responses (damping or their p-set), not to the normal modes' stiffness and mass; femu's FRFs leave it out"
                ),
            );
        } else {
            warn(
                warnings,
                c,
                format!(
                    "DMIG {name} skipped: no K2GG, M2GG, K42GG, B2GG, K2PP, M2PP or B2PP command names it, so it has no effect (as in Nastran)"
                ),
            );
        }
    }
    // a matrix the case control adds that no DMIG defines
    for (command, name, _, path, line) in case_control
        .direct
        .iter()
        .filter(|d| matches!(d.0.as_str(), "K2GG" | "M2GG" | "K42GG"))
    {
        if !dmigs.iter().any(|c| c.field(0).eq_ignore_ascii_case(name)) {
            return Err(IoError::Parse {
                path: path.clone(),
                line: *line,
                reason: format!("{command} = {name}: the deck defines no DMIG {name}"),
            });
        }
    }
    Ok(selected)
}

/// Adds the `K2GG` and `M2GG` matrices `selected` ([`direct_matrices`]) to `model`: each DMIG's
/// entries as a symmetric matrix ([`dmig::symmetric_entries`]), times its factor and `PARAM,CK2`
/// or `CM2` (QRG M2GG: not times WTMASS), on the grids' components in the basic frame (a grid in
/// a turned displacement frame refused). `M2GG` takes a symmetric DMIG (`IFO = 6`, QRG M2GG).
fn add_direct(
    selected: &[(String, String, f64)],
    dmigs: &[&Card],
    (ck2, cm2): (f64, f64),
    turned: &HashMap<u64, i64>,
    model: &mut Model,
    path: &Path,
) -> Result<(), IoError> {
    if selected.is_empty() {
        return Ok(());
    }
    let all = dmig::from_cards(dmigs.iter().copied())?;
    for (command, name, factor) in selected {
        let Some(m) = all.get(name) else { continue };
        let header = dmigs
            .iter()
            .find(|c| c.field(0).eq_ignore_ascii_case(name))
            .copied();
        let at = |reason: String| match header {
            Some(c) => c.err(reason),
            None => IoError::Content {
                path: path.to_path_buf(),
                reason,
            },
        };
        if command == "M2GG" && m.form != 6 {
            return Err(at(format!(
                "{name}: M2GG takes a symmetric DMIG (IFO = 6), this one has IFO = {}",
                m.form
            )));
        }
        let (which, scale) = match command.as_str() {
            "K2GG" => (femu_fem::model::DirectMatrix::Stiffness, factor * ck2),
            "M2GG" => (femu_fem::model::DirectMatrix::Mass, factor * cm2),
            _ => (femu_fem::model::DirectMatrix::StructuralDamping, *factor),
        };
        let entries = dmig::symmetric_entries(m, path)?;
        if let Some(((g, _), _, _)) = entries
            .iter()
            .flat_map(|e| [(e.0, e.1, e.2), (e.1, e.0, e.2)])
            .find(|(a, _, _)| turned.contains_key(&a.0))
        {
            return Err(at(format!(
                "{name}: GRID {g} is in a turned displacement frame {}: femu adds {command}'s terms in the basic frame",
                turned[&g]
            )));
        }
        let scaled: Vec<_> = entries.iter().map(|&(a, b, v)| (a, b, v * scale)).collect();
        model
            .add_direct_entries(which, &scaled, &format!("{command} = {name}"))
            .map_err(|source| match header {
                Some(c) => c.located()(source),
                None => IoError::Model {
                    path: path.to_path_buf(),
                    line: 0,
                    source,
                },
            })?;
    }
    Ok(())
}

/// A `PARAM`: `WTMASS` (the mass factor) and `COUPMASS` (coupled or lumped mass) change the model
/// and are read; those of [`PARAM_NO_EFFECT`] are skipped with a warning; others are reported as
/// unknown to femu.
fn param<'a>(
    c: &'a Card,
    s: &mut Sorted<'a>,
    warned: &mut Vec<String>,
    warnings: &mut Vec<Warning>,
) -> Result<(), IoError> {
    let name = c.field(0).to_ascii_uppercase();
    match name.as_str() {
        "WTMASS" => {
            s.wtmass = c
                .real(1, "WTMASS")?
                .filter(|v| *v > 0.0)
                .ok_or_else(|| c.err("WTMASS needs a positive value".into()))?;
        }
        "CK2" | "CM2" => {
            // QRG PARAM CK2, CM2: real factors of K2GG and M2GG (a complex one refused)
            let v = c
                .real(1, &name)?
                .filter(|v| v.is_finite())
                .ok_or_else(|| c.err(format!("{name} needs a real value")))?;
            if c.real(2, &name)?.is_some_and(|im| im != 0.0) {
                return Err(c.err(format!("{name} is complex: femu takes a real factor")));
            }
            if name == "CK2" {
                s.ck2 = v;
            } else {
                s.cm2 = v;
            }
        }
        "ALPHA1" | "ALPHA2" => {
            // QRG PARAM ALPHA1, ALPHA2: real or complex (the imaginary part in field 3)
            let v = c
                .real(1, &name)?
                .filter(|v| v.is_finite() && *v >= 0.0)
                .ok_or_else(|| {
                    c.err(format!(
                        "{name} needs a value of at least 0 (a Rayleigh damping coefficient)"
                    ))
                })?;
            if c.real(2, &name)?.is_some_and(|im| im != 0.0) {
                return Err(c.err(format!(
                    "{name} is complex: femu takes real Rayleigh damping coefficients"
                )));
            }
            s.alpha[usize::from(name == "ALPHA2")] = Some((v, c));
        }
        "KDAMP" => {
            // MSC: 1 or -1; Autodesk: ON (1) or OFF (-1); OptiStruct: NO (1) or YES (-1)
            let v = match c.field(1).to_ascii_uppercase().as_str() {
                "ON" | "NO" => 1,
                "OFF" | "YES" => -1,
                _ => c
                    .int(1, "KDAMP")?
                    .ok_or_else(|| c.err("KDAMP needs a value (1 or -1)".into()))?,
            };
            s.kdamp = Some((v, c));
        }
        "G" => {
            let g = c
                .real(1, "G")?
                .filter(|v| v.is_finite() && *v >= 0.0)
                .ok_or_else(|| {
                    c.err("G needs a value of at least 0 (the uniform structural damping coefficient)".into())
                })?;
            s.g = Some((g, c));
        }
        "COUPMASS" => {
            let v = c.field(1).to_ascii_uppercase();
            let value = match v.as_str() {
                "YES" | "ON" => 1,
                "NO" | "OFF" => -1,
                _ => c.int(1, "COUPMASS")?.ok_or_else(|| {
                    c.err("COUPMASS needs a value (1: coupled mass, -1: lumped)".into())
                })?,
            };
            s.coupmass = Some((value, c));
        }
        _ => {
            let key = format!("PARAM,{name}");
            if warned.contains(&key) {
                return Ok(());
            }
            warned.push(key);
            let why = if name == "K6ROT" {
                "femu's shells have their own drilling stiffness (docs/MATH.md, \"Shells\"), which this value does not change"
            } else if PARAM_NO_EFFECT.contains(&name.as_str()) {
                "it does not change the stiffness or the mass of a solid model"
            } else {
                "femu does not know this parameter; check that it changes neither stiffness nor mass"
            };
            warn(warnings, c, format!("PARAM,{name} skipped: {why}"));
        }
    }
    Ok(())
}

/// The grids as femu's mesh holds them: the mesh, the grids whose displacement frame (CD, or
/// GRDSET's) is turned from the basic frame with that frame, and how many grids name a frame
/// (with the first of them).
struct Grids<'a> {
    mesh: Mesh,
    turned: HashMap<u64, i64>,
    /// The turned grids' displacement axes at their positions (columns the axes).
    turned_axes: HashMap<u64, [[f64; 3]; 3]>,
    named_cd: Option<(usize, &'a Card)>,
}

/// The grids into a mesh, at their basic positions.
fn grids_into_mesh<'a>(geometry: &mut Geometry<'a>) -> Result<Grids<'a>, IoError> {
    let mut mesh = Mesh::new();
    let mut ids: Vec<u64> = geometry.grid_of.keys().copied().collect();
    ids.sort_unstable();
    let mut named_cd: Option<(usize, &Card)> = None;
    let mut turned: HashMap<u64, i64> = HashMap::new();
    let mut turned_axes = HashMap::new();
    for id in &ids {
        let g = geometry.grid_of[id];
        let p = geometry.position(*id, g)?;
        let cd = geometry.grid_int(g, 5, "CD")?.unwrap_or(0);
        if cd != 0 {
            let e = named_cd.get_or_insert((0, g));
            e.0 += 1;
            let frame = geometry.frame(cd, g)?;
            if !frame.is_global_orientation() {
                turned.insert(*id, cd);
                turned_axes.insert(*id, frame.axes_at(p));
            }
        }
        mesh.add_node(*id, p).map_err(g.located())?;
    }
    Ok(Grids {
        mesh,
        turned,
        turned_axes,
        named_cd,
    })
}

/// The element sets `PID<n>` and the model with each property's material.
fn model_with_materials(
    mut mesh: Mesh,
    element_pid: &[(u64, u64, &Card)],
    sorted: &Sorted<'_>,
    geometry: &mut Geometry<'_>,
    path: &Path,
    warnings: &mut Vec<Warning>,
) -> Result<Model, IoError> {
    let mut by_pid: BTreeMap<u64, Vec<u64>> = BTreeMap::new();
    for (eid, pid, _) in element_pid {
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
        let (mid, pc) = sorted.psolids.get(pid).ok_or_else(|| {
            first.err(format!(
                "{} refers to PSOLID {pid}, which the deck does not define",
                eids[0]
            ))
        })?;
        let m = sorted.materials.get(mid).ok_or_else(|| {
            pc.err(format!(
                "{pid} refers to MAT1 {mid}, which the deck does not define (femu reads MAT1 and MAT9)"
            ))
        })?;
        if m.name != "MAT1" && m.name != "MAT9" {
            return Err(pc.err(format!(
                "{pid} refers to {} {mid}: a solid takes a MAT1 or a MAT9 ({} is a shell's material)",
                m.name, m.name
            )));
        }
        let material = materials::material(m, pc, geometry, sorted.wtmass, warnings)?;
        model
            .set_material(Some(&format!("PID{pid}")), material)
            .map_err(pc.located())?;
        let ge = materials::material_ge(m)?;
        if ge != 0.0 {
            for &eid in eids {
                model.set_element_damping(eid, ge).map_err(m.located())?;
            }
        }
        formulation(pc, eids, element_pid, &mut model, warnings)?;
    }
    Ok(model)
}

/// MSC Nastran forms 8-node CHEXA and 6-node CPENTA of a PSOLID whose `IN` and `ISOP` are blank
/// with bubble functions and a reduced rule for the shear (QRG PSOLID, remarks). femu builds such
/// CHEXA with incompatible modes (the bubbles, [`Formulation::IncompatibleModes`]; the shear rule
/// is not reproduced) and such CPENTA as the fully integrated wedge, stiffer in bending where few
/// elements span a thickness; one warning per property says which. `IN = 2`, `ISOP = FULL` ask
/// for the fully integrated elements, which femu builds as asked.
fn formulation(
    pc: &Card,
    eids: &[u64],
    element_pid: &[(u64, u64, &Card)],
    model: &mut Model,
    warnings: &mut Vec<Warning>,
) -> Result<(), IoError> {
    let isop = pc.field(5).to_ascii_uppercase();
    let integration = pc.field(3).to_ascii_uppercase();
    let full = (isop == "1" || isop == "FULL") && (integration == "2" || integration == "TWO");
    if full {
        return Ok(());
    }
    let of_kind = |name: &str, grids: usize| -> Vec<&Card> {
        element_pid
            .iter()
            .filter(|e| eids.contains(&e.0))
            .map(|e| e.2)
            .filter(|c| {
                c.name == name
                    && c.fields[2..]
                        .iter()
                        .filter(|f| !f.trim().is_empty())
                        .count()
                        == grids
            })
            .collect()
    };
    let (bricks, wedges) = (of_kind("CHEXA", 8), of_kind("CPENTA", 6));
    for c in &bricks {
        let id: u64 = c.field(0).trim().parse().unwrap_or(0);
        let e = model
            .mesh()
            .element_index(id)
            .ok_or_else(|| c.err(format!("{} is not in the mesh", c.field(0))))?;
        model
            .set_formulation(e, Formulation::IncompatibleModes)
            .map_err(c.located())?;
    }
    if let Some(first) = bricks.first() {
        warn(
            warnings,
            pc,
            format!(
                "PSOLID {}: its {} 8-node CHEXA (first: CHEXA {}, line {}) are built with incompatible modes, the bubble functions MSC Nastran adds when IN and ISOP are blank; MSC's reduced shear integration is not reproduced (IN = 2 and ISOP = FULL make both solve the fully integrated brick, which is 20-65 % stiffer in bending with one or two elements through a thickness: docs/VERIFICATION.md)",
                pc.field(0),
                bricks.len(),
                first.field(0),
                first.line
            ),
        );
    }
    if let Some(first) = wedges.first() {
        warn(
            warnings,
            pc,
            format!(
                "PSOLID {}: its {} 6-node CPENTA (first: CPENTA {}, line {}) are built fully integrated, where MSC Nastran adds bubble functions unless IN = 2 and ISOP = FULL; they are stiffer in bending where few elements span a thickness (femu update's discretisation estimate measures that error on this mesh)",
                pc.field(0),
                wedges.len(),
                first.field(0),
                first.line
            ),
        );
    }
    Ok(())
}

/// The `EIGRL` (or `EIGR`) the case control's `METHOD` selects, or the deck's only one when no
/// method is selected: `(V1, V2, ND)` with the frequencies in Hz.
/// The `TABDMP1` the case control's `SDAMPING` selects (QRG TABDMP1: `TID TYPE`, then pairs
/// `f g` to `ENDT`, `SKIP` in either field dropping a pair; TYPE `G` (default), `CRIT` or `Q`).
/// Nastran applies the table as viscous damping unless `PARAM,KDAMP` is -1, where each mode's
/// stiffness becomes complex (`lambda (1 + i g)`, `g = 2 zeta`), which the caller sets on the
/// model (`Model::set_modal_damping_structural`).
fn modal_damping_table(
    sorted: &Sorted<'_>,
    sel: &case_control::Selected,
) -> Result<femu_fem::model::ModalDampingTable, IoError> {
    use femu_fem::model::{ModalDampingTable, ModalDampingUnits};
    let c = *sorted.tabdmp.get(&sel.id).ok_or_else(|| IoError::Parse {
        path: sel.path.clone(),
        line: sel.line,
        reason: format!(
            "SDAMPING = {} selects no TABDMP1 (the deck defines {:?})",
            sel.id,
            sorted.tabdmp.keys().collect::<Vec<_>>()
        ),
    })?;
    let units = match c.field(1).to_ascii_uppercase().as_str() {
        "" | "G" => ModalDampingUnits::G,
        "CRIT" => ModalDampingUnits::Crit,
        "Q" => ModalDampingUnits::Q,
        other => {
            return Err(c.err(format!("{}: TYPE {other} is not G, CRIT or Q", c.field(0))));
        }
    };
    // the pairs start on the first continuation (field 10 of the card, data field 8)
    let mut points = Vec::new();
    let mut i = 8;
    loop {
        let (f, g) = (c.field(i), c.field(i + 1));
        let (fu, gu) = (f.to_ascii_uppercase(), g.to_ascii_uppercase());
        let rest_blank = c.fields.iter().skip(i).all(|x| x.trim().is_empty());
        if fu == "ENDT" || gu == "ENDT" || rest_blank {
            break;
        }
        if fu == "SKIP" || gu == "SKIP" {
            i += 2;
            continue;
        }
        let value = |t: &str, at: usize, what: &str| {
            cards::real(t).ok_or_else(|| {
                c.err(format!(
                    "{}: field {} ({what}) {t:?} is not a number",
                    c.field(0),
                    at + 2
                ))
            })
        };
        points.push((value(f, i, "f")?, value(g, i + 1, "g")?));
        i += 2;
    }
    if points.is_empty() {
        return Err(c.err(format!("{}: no (f, g) point before ENDT", c.field(0))));
    }
    // QRG: ascending or descending, not both
    if points.windows(2).all(|w| w[1].0 <= w[0].0) {
        points.reverse();
    }
    if points.windows(2).any(|w| w[1].0 < w[0].0) {
        return Err(c.err(format!(
            "{}: the frequencies go up and down (they ascend or descend, not both)",
            c.field(0)
        )));
    }
    Ok(ModalDampingTable {
        units,
        points,
        hold_ends: false,
    })
}

fn selected_method(
    sorted: &Sorted<'_>,
    method: Option<&case_control::Selected>,
) -> Result<Option<Eigrl>, IoError> {
    let card = match method {
        Some(m) => Some(*sorted.methods.get(&m.id).ok_or_else(|| IoError::Parse {
            path: m.path.clone(),
            line: m.line,
            reason: format!(
                "METHOD = {} selects no EIGRL or EIGR (the deck defines {:?})",
                m.id,
                sorted.methods.keys().collect::<Vec<_>>()
            ),
        })?),
        None if sorted.methods.len() == 1 => sorted.methods.values().next().copied(),
        None => None,
    };
    let Some(c) = card else {
        return Ok(None);
    };
    // EIGRL: SID V1 V2 ND ...; EIGR: SID METHOD F1 F2 NE ND ...
    let (f1, f2, nd) = if c.name == "EIGRL" {
        (1, 2, 3)
    } else {
        (2, 3, 5)
    };
    // EIGR's tridiagonal methods find every eigenvalue and the vectors of the lowest ND, F1 and
    // F2 aside when ND is given: pyNastran's pt145 (GIV, F1 0, F2 0.1 Hz, ND 6) prints all 30
    // eigenvalues of its run and the generalized masses of the six lowest modes, the first at
    // 40 Hz
    let tridiagonal = c.name == "EIGR"
        && matches!(
            c.field(1).trim().to_ascii_uppercase().as_str(),
            "GIV" | "MGIV" | "HOU" | "MHOU" | "AHOU" | "AGIV"
        );
    if tridiagonal && let Some(n) = c.int(nd, "ND")?.filter(|n| *n > 0) {
        return Ok(Some((None, None, Some(n as usize))));
    }
    Ok(Some((
        c.real(f1, "V1")?,
        c.real(f2, "V2")?,
        c.int(nd, "ND")?.map(|v| v.max(0) as usize),
    )))
}

fn parse_lines(lines: &[Line], path: &Path, options: &BdfOptions) -> Result<BdfDeck, IoError> {
    let deck = cards::deck(lines)?;
    let mut warnings = Vec::new();
    let sorted = sort(&deck.cards, options, &mut warnings)?;
    let direct = direct_matrices(&sorted.dmigs, &deck.case_control, &mut warnings)?;
    let mut geometry = Geometry::new(&sorted.cords, &sorted.grids, sorted.grdset)?;
    let Grids {
        mut mesh,
        turned,
        turned_axes,
        named_cd,
    } = grids_into_mesh(&mut geometry)?;
    let max_grid = geometry.grid_of.keys().copied().max().unwrap_or(0);
    let els = elements::add_elements(&sorted.elements, &mut mesh, max_grid)?;
    if mesh.element_count() == 0 && sorted.structural.elements.is_empty() {
        return Err(IoError::Content {
            path: path.to_path_buf(),
            reason: format!(
                "the deck defines {} GRID{} and no element (solids: CHEXA, CPENTA, CTETRA, CPYRAM; bars, beams, rods, springs, dampers, bushings, shells: CBAR, CBEAM, CROD, CONROD, CELAS1, CELAS2, CDAMP1, CDAMP2, CVISC, CBUSH, CQUAD4, CQUAD8, CTRIA3, CTRIA6)",
                mesh.node_count(),
                if mesh.node_count() == 1 { "" } else { "s" }
            ),
        });
    }
    let mut model = model_with_materials(
        mesh,
        &els.element_pid,
        &sorted,
        &mut geometry,
        path,
        &mut warnings,
    )?;
    structural::add_structural(
        &sorted.structural,
        &mut model,
        &mut structural::Context {
            geometry: &mut geometry,
            materials: &sorted.materials,
            turned: &turned,
            wtmass: sorted.wtmass,
            mat1: HashMap::new(),
        },
        &mut warnings,
    )?;
    for (id, ga, gb, label) in &els.ties {
        for k in 0..3 {
            model
                .add_constraint((*id, k), &[((*ga, k), 0.5), ((*gb, k), 0.5)], label)
                .map_err(|source| IoError::Content {
                    path: path.to_path_buf(),
                    reason: source.to_string(),
                })?;
        }
    }
    if let Some(c) = els.first_blank {
        warn(
            &mut warnings,
            c,
            format!(
                "{} mid-side grids are blank: those edges are straight and the elements vary linearly along them, as Nastran reads them (femu adds a node at each such midpoint, ids from {}, tied to the average of the edge's ends)",
                els.ties.len(),
                els.ties.first().map_or(0, |t| t.0)
            ),
        );
    }
    let dependents = links::read_links(
        &sorted.links,
        &mut model,
        &turned,
        &turned_axes,
        &mut warnings,
    )?;
    constraints::apply_mpc(
        &sorted.mpcs,
        deck.case_control.mpc.as_ref(),
        deck.has_case_control,
        &mut model,
        &turned,
        path,
        &mut warnings,
    )?;
    let mut fix = |c: &Card, g: u64, comps: &[usize]| {
        constraints::fix_components(&mut model, &turned, &turned_axes, c, g, comps)
    };
    let permanent = constraints::apply_permanent(&sorted.grids, &geometry, &mut fix)?;
    constraints::apply_spc(
        &sorted.spcs,
        deck.case_control.spc.as_ref(),
        deck.has_case_control,
        &geometry,
        path,
        &mut warnings,
        &mut fix,
    )?;
    if let Some((n, g)) = named_cd {
        warn(
            &mut warnings,
            g,
            format!(
                "{n} grids name a displacement frame (CD): femu reports displacements in the basic frame"
            ),
        );
    }
    masses::add_masses(
        &sorted.conm2,
        &mut model,
        &mut geometry,
        sorted.wtmass,
        options.lenient,
        &dependents,
        &mut warnings,
    )?;
    add_direct(
        &direct,
        &sorted.dmigs,
        (sorted.ck2, sorted.cm2),
        &turned,
        &mut model,
        path,
    )?;
    // conflicts between links and constraints, found now rather than at the first solve
    model.dof_map().map_err(|source| IoError::Content {
        path: path.to_path_buf(),
        reason: source.to_string(),
    })?;
    let eigrl = selected_method(&sorted, deck.case_control.method.as_ref())?;
    // QRG PARAM,G: the uniform structural damping of a frequency response, `K (1 + i G)`; QRG
    // PARAM,ALPHA1, ALPHA2: its Rayleigh damping `ALPHA1 M + ALPHA2 K`
    let rayleigh = sorted.alpha.iter().flatten().next().map(|(_, c)| *c);
    match (sorted.g, rayleigh) {
        (Some((_, g)), Some(a)) => {
            return Err(a.err(format!(
                "PARAM,ALPHA1/ALPHA2 beside PARAM,G (line {}): Nastran adds a Rayleigh and a structural damping of the whole model, femu holds one; keep one of them (or give each material its GE)",
                g.line
            )));
        }
        (Some((g, c)), None) => {
            model
                .set_uniform_damping(Some(femu_fem::model::UniformDamping::LossFactor(g)))
                .map_err(c.located())?;
        }
        (None, Some(c)) => {
            let value = |k: usize| sorted.alpha[k].map_or(0.0, |(v, _)| v);
            model
                .set_uniform_damping(Some(femu_fem::model::UniformDamping::Rayleigh {
                    alpha: value(0),
                    beta: value(1),
                }))
                .map_err(c.located())?;
        }
        (None, None) => {}
    }
    // QRG SDAMPING and TABDMP1: the modes' damping as a function of their frequency
    if let Some(sel) = deck.case_control.sdamping.as_ref() {
        let table = modal_damping_table(&sorted, sel)?;
        model
            .set_modal_damping(Some(table))
            .map_err(|source| IoError::Model {
                path: sel.path.clone(),
                line: sel.line,
                source,
            })?;
        // QRG PARAM,KDAMP: -1 enters the modal damping as complex stiffness
        model.set_modal_damping_structural(sorted.kdamp.is_some_and(|(k, _)| k < 0));
    }
    // QRG PARAM,COUPMASS: -1 (the default) lumped, > 0 coupled
    let (mass, coupmass) = match sorted.coupmass {
        Some((v, c)) if v > 0 => (MassKind::Consistent, Some((v, c.line))),
        Some((v, c)) => (MassKind::Lumped, Some((v, c.line))),
        None => (MassKind::Lumped, None),
    };
    Ok(BdfDeck {
        model,
        eigrl,
        mass,
        coupmass: coupmass.map(|c| c.0),
        permanent_constraints: permanent,
        spc_set: deck.case_control.spc.as_ref().map(|s| s.id),
        warnings,
    })
}

/// The g-set of a deck, the rows of the matrices Nastran assembles before any constraint (`KGG`,
/// `MGG`): each GRID's six components in the order of the grids' ids (Nastran's internal
/// sequence when nothing resequences it), with the components the deck constrains.
#[derive(Debug, Clone, PartialEq)]
pub struct GSet {
    /// The grids, ids increasing: rows `6 i .. 6 i + 6` are grid `grids[i]`'s T1-T3, R1-R3.
    pub grids: Vec<u64>,
    /// The components (0-based) the deck fixes: the grids' permanent constraints (`PS`) and the
    /// SPC set the case control selects (or the only one of a deck without case control).
    pub constrained: std::collections::BTreeSet<(u64, usize)>,
}

/// Cards whose constraints a g-set matrix does not hold (Nastran applies them after `KGG`).
const MULTIPOINT: &[&str] = &[
    "MPC", "MPCADD", "RBE1", "RBE2", "RBE3", "RBAR", "RBAR1", "RROD", "RTRPLT", "RTRPLT1",
    "RSPLINE", "RSSCON", "RJOINT",
];

/// Reads the g-set of the deck at `path` ([`GSet`]): its grids and single-point constraints,
/// whatever its elements.
///
/// # Errors
/// The file system's; [`IoError::Parse`] naming the card's line for a malformed GRID, SPC, SPC1
/// or SPCADD, a grid in a turned displacement frame (`CD`, whose g-set components are not the
/// basic ones), a scalar point (`SPOINT`: a g-set row that is not a grid's) and a multipoint
/// constraint or rigid element (its constraint is not in a g-set matrix: the model would lose
/// it); a selected SPC set nothing defines.
pub fn read_gset(path: impl AsRef<Path>) -> Result<GSet, IoError> {
    let path = path.as_ref();
    let mut lines = Vec::new();
    cards::load(path, 0, &mut lines)?;
    let deck = cards::deck(&lines)?;
    if let Some(c) = deck.cards.iter().find(|c| c.name == "SPOINT") {
        return Err(c.err(
            "defines scalar points: femu's rows are grids' components, so a g-set matrix with scalar points cannot be labelled (give its DOF table, or a matrix without them)".into(),
        ));
    }
    if let Some(c) = deck
        .cards
        .iter()
        .find(|c| MULTIPOINT.contains(&c.name.as_str()))
    {
        return Err(c.err(format!(
            "{}: a multipoint constraint, which Nastran applies after assembling the g-set matrices: KGG and MGG do not hold it and the model would lose it (export the matrices after it, KAA and MAA or KFF and MFF, with their DOF table)",
            c.name
        )));
    }
    let grids: Vec<&Card> = deck.cards.iter().filter(|c| c.name == "GRID").collect();
    if grids.is_empty() {
        return Err(IoError::Content {
            path: path.to_path_buf(),
            reason: "the deck defines no GRID".into(),
        });
    }
    let cords: Vec<&Card> = deck
        .cards
        .iter()
        .filter(|c| c.name.starts_with("CORD1") || c.name.starts_with("CORD2"))
        .collect();
    let grdset = deck.cards.iter().find(|c| c.name == "GRDSET");
    let geometry = Geometry::new(&cords, &grids, grdset)?;
    for g in &grids {
        let cd = geometry.grid_int(g, 5, "CD")?.unwrap_or(0);
        if cd != 0 {
            return Err(g.err(format!(
                "has its displacements in frame CD = {cd}: its g-set rows are in that frame, and femu's rows are in the basic one (give the grids CD = 0)"
            )));
        }
    }
    let mut ids: Vec<u64> = geometry.grid_of.keys().copied().collect();
    ids.sort_unstable();
    let mut constrained = std::collections::BTreeSet::new();
    let mut fix = |c: &Card, g: u64, comps: &[usize]| -> Result<(), IoError> {
        if !geometry.grid_of.contains_key(&g) {
            return Err(c.err(format!(
                "constrains GRID {g}, which the deck does not define"
            )));
        }
        constrained.extend(comps.iter().map(|&k| (g, k)));
        Ok(())
    };
    constraints::apply_permanent(&grids, &geometry, &mut fix)?;
    let spcs: Vec<&Card> = deck
        .cards
        .iter()
        .filter(|c| matches!(c.name.as_str(), "SPC" | "SPC1" | "SPCADD"))
        .collect();
    let mut warnings = Vec::new();
    constraints::apply_spc(
        &spcs,
        deck.case_control.spc.as_ref(),
        deck.has_case_control,
        &geometry,
        path,
        &mut warnings,
        &mut fix,
    )?;
    Ok(GSet {
        grids: ids,
        constrained,
    })
}
