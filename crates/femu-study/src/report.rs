//! Report writers: text files that name themselves in errors and are listed as written, JSON,
//! and the CSV of the sensor-removal study.

use crate::StudyError;
use crate::chart::method_label;
use faer::MatRef;
use femu_correlate::study::StudyPoint;
use femu_fem::dof::DofMap;
use femu_io::vtk::{CellField, PointField, write_vtu_with};
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

/// Writes the columns of `x` (free-DOF vectors, e.g. mode shapes) as 3-component point fields
/// named `names`, scattered to the nodes by [`DofMap::expand`] (zero on fixed DOFs), with the
/// cell fields `cells`, to a VTK `.vtu` file for ParaView: the model's solids, and its beams,
/// rods, springs and bushings as lines with their sections ([`femu_io::vtk::vtu_string_with`]).
///
/// # Errors
/// Sizes that do not match the DOF map or the names, and the writer's errors (naming the file).
pub fn write_shapes_vtu(
    path: &Path,
    model: &femu_fem::model::Model,
    dofs: &DofMap,
    x: MatRef<'_, f64>,
    names: &[String],
    cells: &[CellField<'_>],
) -> Result<(), StudyError> {
    if names.len() != x.ncols() {
        return Err(StudyError::invalid(
            "VTK point fields",
            format!("{} names for {} shapes", names.len(), x.ncols()),
        ));
    }
    let values = (0..x.ncols())
        .map(|j| dofs.expand(&x.col(j).iter().copied().collect::<Vec<f64>>()))
        .collect::<Result<Vec<_>, _>>()?;
    let points: Vec<PointField<'_>> = values
        .iter()
        .zip(names)
        .map(|(v, name)| PointField {
            name,
            components: 3,
            values: v,
        })
        .collect();
    Ok(write_vtu_with(
        model.mesh(),
        model.structural(),
        &points,
        cells,
        path,
    )?)
}
