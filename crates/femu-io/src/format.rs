//! The formats femu reads, by extension: one table ([`FORMATS`]) that the loader, `femu info`,
//! the command line's help and its errors all read, so that a new reader is its module and one
//! row here.

use std::path::Path;

/// A file format femu reads.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Format {
    /// Abaqus/CalculiX input deck: mesh, materials, constraints, masses, a `*FREQUENCY` step.
    Inp,
    /// Nastran bulk data: mesh, properties, constraints, masses, the case control's selections.
    Nastran,
    /// Gmsh mesh (`.msh` 4.1 and 2.2): a mesh with physical groups, no material.
    Gmsh,
    /// Universal File: a mesh (2411/2412/2477) without material, test modes (15/2411 and 55),
    /// another code's modes (2414), frequency responses (58).
    Universal,
    /// femu's JSON test modes.
    Json,
    /// CSV test modes (`mode, frequency_hz, node, direction, value`).
    Csv,
    /// Another solver's `K` and `M` with the node and component of each row: CalculiX's
    /// `job.sti` (with `job.mas`, `job.dof`), Abaqus's `job_STIF1.mtx`, Nastran's DMIG punch
    /// `job.pch` or OUTPUT4 `job.op4`, or MatrixMarket `X_K.mtx` (with `X_M.mtx`,
    /// `X_dofs.csv`); [`crate::matrices`].
    Matrices,
    /// Another solver's modes: CalculiX's `.frd` ([`crate::frd`]) or Nastran's `.f06`, `.op2` or
    /// punch `.pch` ([`crate::f06`], [`crate::op2`], [`crate::punch`], the grids from its deck),
    /// the model side of a correlation only (no `K` and `M`).
    Results,
}

/// One row of the table: the format, its extensions (lower case), what it holds for femu, and its
/// name in messages.
#[derive(Debug, Clone, Copy)]
pub struct FormatInfo {
    /// The format.
    pub format: Format,
    /// Its extensions, lower case, without the dot.
    pub extensions: &'static [&'static str],
    /// It can be the model of a command.
    pub model: bool,
    /// Its model carries its own materials and constraints (a deck); otherwise a mesh needs them
    /// from the command line or the study file.
    pub deck: bool,
    /// It can be the test of a command.
    pub test: bool,
    /// The name users know it by.
    pub name: &'static str,
}

/// Every format femu reads.
pub const FORMATS: &[FormatInfo] = &[
    FormatInfo {
        format: Format::Inp,
        extensions: &["inp"],
        model: true,
        deck: true,
        test: false,
        name: "Abaqus/CalculiX decks",
    },
    FormatInfo {
        format: Format::Nastran,
        extensions: &["bdf", "dat", "nas"],
        model: true,
        deck: true,
        test: false,
        name: "Nastran bulk data",
    },
    FormatInfo {
        format: Format::Gmsh,
        extensions: &["msh"],
        model: true,
        deck: false,
        test: false,
        name: "Gmsh meshes",
    },
    FormatInfo {
        format: Format::Universal,
        extensions: &["unv", "uff"],
        model: true,
        deck: false,
        test: true,
        name: "universal files",
    },
    FormatInfo {
        format: Format::Matrices,
        extensions: &["sti", "mtx", "pch", "op4"],
        model: true,
        deck: true,
        test: false,
        name: "stiffness and mass matrices with their DOF table",
    },
    FormatInfo {
        format: Format::Results,
        extensions: &["frd", "f06", "op2", "pch"],
        model: true,
        deck: true,
        test: false,
        name: "another solver's modes",
    },
    FormatInfo {
        format: Format::Json,
        extensions: &["json"],
        model: false,
        deck: false,
        test: true,
        name: "JSON",
    },
    FormatInfo {
        format: Format::Csv,
        extensions: &["csv", "txt"],
        model: false,
        deck: false,
        test: true,
        name: "CSV",
    },
];

/// Whether the file at `path` opens as CalculiX's printed output (its first 4 KiB); a file that
/// cannot be read is not (its reader then says why).
/// The first 4 KB of a file as text (empty if unreadable).
fn head(path: &Path) -> String {
    use std::io::Read;
    let mut head = vec![0u8; 4096];
    let Ok(mut f) = std::fs::File::open(path) else {
        return String::new();
    };
    let mut n = 0;
    while n < head.len() {
        match f.read(&mut head[n..]) {
            Ok(0) | Err(_) => break,
            Ok(k) => n += k,
        }
    }
    String::from_utf8_lossy(&head[..n]).into_owned()
}

impl Format {
    /// The format of `path` by its extension (any case), if femu reads it. A `.dat` is Nastran
    /// bulk data unless its first kilobytes are CalculiX's printed output
    /// ([`crate::ccx_dat::looks_like_calculix`]), and a `.pch` DMIG matrices unless they are
    /// result output ([`crate::punch::looks_like_results`]): then another solver's modes. An
    /// `.inp` is an Abaqus/CalculiX deck unless its first kilobytes are a Nastran deck's
    /// ([`crate::nastran::looks_like_nastran`], as MSC names its examples).
    pub fn from_path(path: &Path) -> Option<Format> {
        let ext = path.extension()?.to_str()?.to_ascii_lowercase();
        if (ext == "dat" && crate::ccx_dat::looks_like_calculix(&head(path)))
            || (ext == "pch" && crate::punch::looks_like_results(&head(path)))
        {
            return Some(Format::Results);
        }
        if ext == "inp" && crate::nastran::looks_like_nastran(&head(path)) {
            return Some(Format::Nastran);
        }
        FORMATS
            .iter()
            .find(|f| f.extensions.contains(&ext.as_str()))
            .map(|f| f.format)
    }

    /// Its row of [`FORMATS`].
    pub fn info(self) -> &'static FormatInfo {
        FORMATS
            .iter()
            .find(|f| f.format == self)
            .expect("every format has a row")
    }
}

/// The formats for models (`model = true`) or tests, as a list for messages and help:
/// `Abaqus/CalculiX decks (.inp), Nastran bulk data (.bdf, .dat, .nas), ...`.
pub fn described(models: bool) -> String {
    let items: Vec<String> = FORMATS
        .iter()
        .filter(|f| if models { f.model } else { f.test })
        .map(|f| {
            let exts: Vec<String> = f.extensions.iter().map(|e| format!(".{e}")).collect();
            format!("{} ({})", f.name, exts.join(", "))
        })
        .collect();
    match items.split_last() {
        Some((last, rest)) if !rest.is_empty() => format!("{} and {last}", rest.join(", ")),
        _ => items.join(""),
    }
}

/// Every extension femu reads, for `femu info`'s refusal.
pub fn all_extensions() -> Vec<&'static str> {
    // `.pch` is in two rows (DMIG matrices, punched modes): listed once
    let mut out: Vec<&'static str> = Vec::new();
    for e in FORMATS.iter().flat_map(|f| f.extensions.iter().copied()) {
        if !out.contains(&e) {
            out.push(e);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The table read by extension, in any case; the lists the refusals print, written out.
    #[test]
    fn formats_by_extension() {
        assert_eq!(
            Format::from_path(Path::new("a/b.BDF")),
            Some(Format::Nastran)
        );
        assert_eq!(
            Format::from_path(Path::new("t.Uff")),
            Some(Format::Universal)
        );
        assert_eq!(Format::from_path(Path::new("t.txt")), Some(Format::Csv));
        assert_eq!(Format::from_path(Path::new("m.xlsx")), None);
        assert_eq!(Format::from_path(Path::new("noextension")), None);
        assert!(Format::Inp.info().deck && !Format::Gmsh.info().deck);
        assert_eq!(
            described(true),
            "Abaqus/CalculiX decks (.inp), Nastran bulk data (.bdf, .dat, .nas), Gmsh meshes (.msh), universal files (.unv, .uff), stiffness and mass matrices with their DOF table (.sti, .mtx, .pch, .op4) and another solver's modes (.frd, .f06, .op2, .pch)"
        );
        assert_eq!(
            described(false),
            "universal files (.unv, .uff), JSON (.json) and CSV (.csv, .txt)"
        );
        assert_eq!(all_extensions().len(), 17);
        assert_eq!(
            Format::from_path(Path::new("job.sti")),
            Some(Format::Matrices)
        );
        // a .pch that is not there (or holds DMIG cards) is matrices
        assert_eq!(
            Format::from_path(Path::new("no/such/job.pch")),
            Some(Format::Matrices)
        );
    }
}
