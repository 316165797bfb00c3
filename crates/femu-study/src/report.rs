//! Report writers: text files that name themselves in errors and are listed as written, JSON,
//! and the CSV of the sensor-removal study.

use crate::StudyError;
use crate::chart::method_label;
use femu_correlate::study::StudyPoint;
use serde::Serialize;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// Writes `text` to `path` and adds the path to `files`.
///
/// # Errors
/// [`StudyError::File`] naming the file.
pub fn write_text(path: &Path, text: &str, files: &mut Vec<PathBuf>) -> Result<(), StudyError> {
    std::fs::write(path, text).map_err(|e| StudyError::file(path, e))?;
    files.push(path.to_path_buf());
    Ok(())
}

/// Writes `value` as pretty JSON to `path`.
///
/// # Errors
/// [`StudyError::File`] naming the file.
pub fn write_json<T: Serialize + ?Sized>(path: &Path, value: &T) -> Result<(), StudyError> {
    let text = serde_json::to_string_pretty(value)?;
    std::fs::write(path, text).map_err(|e| StudyError::file(path, e))
}

/// Creates the folder `dir` (and its parents).
///
/// # Errors
/// [`StudyError::File`] naming the folder.
pub fn create_dir(dir: &Path) -> Result<(), StudyError> {
    std::fs::create_dir_all(dir).map_err(|e| StudyError::file(dir, e))
}

/// The sensor-removal study as CSV (`nodes,sensors,method,mode,rho_m,rho_2`, one row per point;
/// method `full` where nothing was expanded, modes 1-based, `rho` in s^-2).
pub fn study_csv(points: &[StudyPoint]) -> String {
    let mut s = String::from("nodes,sensors,method,mode,rho_m,rho_2\n");
    for p in points {
        let _ = writeln!(
            s,
            "{},{},{},{},{:e},{:e}",
            p.nodes,
            p.sensors,
            method_label(p.method),
            p.mode + 1,
            p.rho_m,
            p.rho_2
        );
    }
    s
}

/// Free-DOF columns of `x` scattered to full nodal vectors (3 components per node, zero on fixed
/// DOFs), for VTK point fields.
pub fn full_fields(
    dofs: &femu_fem::dof::DofMap,
    nodes: usize,
    x: faer::MatRef<'_, f64>,
) -> Vec<Vec<f64>> {
    (0..x.ncols())
        .map(|j| {
            let mut v = vec![0.0; 3 * nodes];
            for f in 0..x.nrows() {
                v[dofs.full_of_free(f)] = x[(f, j)];
            }
            v
        })
        .collect()
}
