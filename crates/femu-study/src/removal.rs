//! The sensor-removal study (the paper's Figure 1): triaxial sensors at the test's nodes removed
//! one node at a time in Effective Independence order, the test shapes expanded from each set by
//! each method, and `rho_M` of the expanded shapes against the number of measured nodes.

use crate::StudyError;
use crate::chart::{figure1_svg, write_png};
use crate::load::{LoadedModel, LoadedTest};
use crate::report::{study_csv, write_text};
use faer::MatRef;
use femu_correlate::SensorLayout;
use femu_correlate::expansion::Method;
use femu_correlate::placement::efi_removal_order;
use femu_correlate::study::{StudyPoint, sensor_removal_study};
use femu_fem::assembly::SystemMatrices;
use femu_fem::mesh::Mesh;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// Settings of [`removal_study`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RemovalOptions {
    /// Expansion methods compared (default static, dynamic and minimum residual).
    pub methods: Vec<Method>,
    /// Nodes left at the end (default 2).
    pub keep: usize,
    /// Every `stride`-th sensor set is evaluated, the first and last always (default 1).
    pub stride: usize,
}

impl Default for RemovalOptions {
    fn default() -> Self {
        Self {
            methods: Method::FIGURE1.to_vec(),
            keep: 2,
            stride: 1,
        }
    }
}

/// What [`removal_study`] found.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RemovalStudy {
    /// The starting nodes (triaxial sensors at each).
    pub nodes: Vec<u64>,
    /// The nodes in the order they were removed.
    pub removal: Vec<u64>,
    /// One point per evaluated set, method and test mode.
    pub points: Vec<StudyPoint>,
}

/// Runs the study from triaxial sensors at `nodes`: the removal order is Effective Independence
/// on `efi_basis` (full-length shapes: the model's modes or the expanded test shapes), and the
/// test shapes `x` (full length) with eigenvalues `lambdas` are re-expanded from every set.
///
/// # Errors
/// Fewer than `keep + 1` nodes, and the placement and expansion errors (with the set size).
pub fn removal_study(
    sys: &SystemMatrices,
    mesh: &Mesh,
    nodes: &[u64],
    efi_basis: MatRef<'_, f64>,
    lambdas: &[f64],
    x: MatRef<'_, f64>,
    options: &RemovalOptions,
) -> Result<RemovalStudy, StudyError> {
    if nodes.len() <= options.keep.max(1) {
        return Err(StudyError::invalid(
            "sensor-removal study",
            format!(
                "{} measured nodes: the study needs more than the {} it keeps",
                nodes.len(),
                options.keep.max(1)
            ),
        ));
    }
    let tri = SensorLayout::triaxial(mesh, &sys.dofs, nodes)?;
    let order = efi_removal_order(&tri, efi_basis)?;
    let removal: Vec<u64> = order.into_iter().take(nodes.len() - options.keep).collect();
    let points = sensor_removal_study(
        &sys.k,
        &sys.m,
        mesh,
        &sys.dofs,
        lambdas,
        x,
        nodes,
        &removal,
        &options.methods,
        None,
        options.stride,
    )?;
    Ok(RemovalStudy {
        nodes: nodes.to_vec(),
        removal,
        points,
    })
}

/// The study over the test's own nodes (triaxial sensors at each, the default methods, down to 2
/// nodes), with the expanded test shapes `x` as the EfI basis and as the shapes re-expanded.
///
/// # Errors
/// As [`removal_study`].
pub fn removal_over_test(
    model: &LoadedModel,
    test: &LoadedTest,
    x: MatRef<'_, f64>,
) -> Result<RemovalStudy, StudyError> {
    removal_study(
        &model.sys,
        model.model.mesh(),
        &sensor_nodes(&test.layout),
        x,
        &test.data.modes.eigenvalues(),
        x,
        &RemovalOptions::default(),
    )
}

/// The distinct nodes of a layout's sensors, ascending.
pub fn sensor_nodes(layout: &SensorLayout) -> Vec<u64> {
    let mut nodes: Vec<u64> = layout.sensors().iter().map(|s| s.node).collect();
    nodes.sort_unstable();
    nodes.dedup();
    nodes
}

/// Writes `STEM.csv`, `STEM.svg` and `STEM.png` of the study into `dir`; returns the files.
///
/// # Errors
/// File system errors naming the file.
pub fn write_removal_study(
    dir: &Path,
    stem: &str,
    points: &[StudyPoint],
) -> Result<Vec<PathBuf>, StudyError> {
    let mut files = Vec::new();
    let svg = figure1_svg(points);
    write_text(&dir.join(format!("{stem}.svg")), &svg, &mut files)?;
    let png = dir.join(format!("{stem}.png"));
    write_png(&svg, 2.0, &png)?;
    files.push(png);
    write_text(
        &dir.join(format!("{stem}.csv")),
        &study_csv(points),
        &mut files,
    )?;
    Ok(files)
}
