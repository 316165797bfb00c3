//! A test on its own wireframe, mapped onto the model (docs/MATH.md, "Mapping test nodes").
//!
//! A real test comes with its own node numbers, coordinates in its own frame and units, and
//! accelerometers between the FE nodes. Mapping takes the test node coordinates (universal file
//! datasets 15/2411 with their coordinate systems, or the `x,y,z` columns of CSV and JSON tests),
//! turns them into metres, aligns the wireframe onto the model if asked ([`Align`]: from node
//! pairs, or automatically onto the model's boundary), turns the measured directions with it, and
//! moves every test node onto the model ([`MapMethod`]): to the nearest FE node, or to its point
//! inside an element, where the sensor reads the shape-function combination of the element's
//! nodes. Every test node farther than the tolerance from the model is an error that names it.

use crate::{CorrelateError, Sensor, TestData};
use femu_fem::align::{Fit, Surface, Transform, fit_auto, fit_pairs};
use femu_fem::element::ElementKind;
use femu_fem::locate::Locator;
use femu_fem::mesh::Mesh;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::fmt::Write as _;

/// How test nodes land on the model.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[serde(rename_all = "lowercase")]
pub enum MapMethod {
    /// The nearest FE node (two test nodes on one FE node are an error).
    Nearest,
    /// The point inside (or, within the tolerance, nearest to) an element: the sensor reads
    /// `sum_a N_a(xi) u_a` over the element's nodes.
    Interpolate,
}

impl std::str::FromStr for MapMethod {
    type Err = CorrelateError;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s.to_ascii_lowercase().as_str() {
            "nearest" => Ok(Self::Nearest),
            "interpolate" => Ok(Self::Interpolate),
            other => Err(CorrelateError::Mapping {
                what: "map",
                reason: format!("{other:?}: expected nearest or interpolate"),
            }),
        }
    }
}

/// How the test's frame is brought onto the model's.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(try_from = "String", into = "String")]
pub enum Align {
    /// The test's coordinates are in the model's frame (after units).
    #[default]
    None,
    /// Least squares over pairs (test node, model node) the user gives: at least three, not on
    /// one line.
    Pairs(Vec<(u64, u64)>),
    /// Best fit of the test nodes onto the model's boundary.
    Auto,
}

impl std::str::FromStr for Align {
    type Err = CorrelateError;
    /// `auto`, `none`, or pairs `T:M,T:M,T:M` (test node `T` is model node `M`).
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let t = s.trim();
        match t.to_ascii_lowercase().as_str() {
            "auto" => return Ok(Self::Auto),
            "none" => return Ok(Self::None),
            _ => {}
        }
        let bad = |p: &str| CorrelateError::Mapping {
            what: "align",
            reason: format!(
                "{p:?} is not a pair TEST:MODEL of node ids (give auto, none, or pairs like 101:3,102:6,103:9)"
            ),
        };
        let pairs = t
            .split(',')
            .map(|p| {
                let (a, b) = p.split_once(':').ok_or_else(|| bad(p))?;
                Ok((
                    a.trim().parse().map_err(|_| bad(p))?,
                    b.trim().parse().map_err(|_| bad(p))?,
                ))
            })
            .collect::<Result<Vec<(u64, u64)>, CorrelateError>>()?;
        Ok(Self::Pairs(pairs))
    }
}

impl std::fmt::Display for Align {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::None => f.write_str("none"),
            Self::Auto => f.write_str("auto"),
            Self::Pairs(p) => {
                let p: Vec<String> = p.iter().map(|(t, m)| format!("{t}:{m}")).collect();
                f.write_str(&p.join(","))
            }
        }
    }
}

impl TryFrom<String> for Align {
    type Error = String;
    fn try_from(s: String) -> Result<Self, Self::Error> {
        s.parse().map_err(|e: CorrelateError| e.to_string())
    }
}

impl From<Align> for String {
    fn from(a: Align) -> String {
        a.to_string()
    }
}

/// Options of [`map_test`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MapOptions {
    /// Nearest node or interpolation.
    pub method: MapMethod,
    /// The largest distance (m) from a test node to the model; `None`: 1 % of the model's
    /// bounding-box diagonal.
    #[serde(default)]
    pub tolerance: Option<f64>,
    /// Alignment of the test's frame onto the model's.
    #[serde(default)]
    pub align: Align,
    /// Let the alignment fit a uniform scale too (units the file does not state).
    #[serde(default)]
    pub scale: bool,
}

/// Where one test node landed.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Target {
    /// On a model node.
    Node {
        /// The model node's id.
        model: u64,
    },
    /// Inside an element.
    Element {
        /// The element's id.
        element: u64,
        /// Its kind.
        kind: ElementKind,
        /// Local coordinates of the point.
        xi: [f64; 3],
    },
}

/// One row of the mapping table.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct NodeMapping {
    /// The test node's label.
    pub test: u64,
    /// Its position in the model's frame after units and alignment, m.
    pub position: [f64; 3],
    /// Where it landed.
    pub target: Target,
    /// Distance from the position to the point it reads, m.
    pub distance: f64,
}

/// The alignment found.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Alignment {
    /// `pairs` or `auto`.
    pub method: &'static str,
    /// Test frame (metres) to model frame.
    pub transform: Transform,
    /// Per aligned test node: its distance to its target after alignment (the paired model node,
    /// or the model's boundary), m.
    pub residuals: Vec<(u64, f64)>,
}

impl Alignment {
    /// Root mean square of the residuals, m.
    pub fn rms(&self) -> f64 {
        let n = self.residuals.len().max(1) as f64;
        (self.residuals.iter().map(|r| r.1 * r.1).sum::<f64>() / n).sqrt()
    }
}

/// What [`map_test`] did: the report's mapping section.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Mapping {
    /// Nearest node or interpolation.
    pub method: MapMethod,
    /// The tolerance used, m.
    pub tolerance: f64,
    /// Metres per unit of the test's coordinates.
    pub metres_per_unit: f64,
    /// The alignment, when one was asked for.
    pub alignment: Option<Alignment>,
    /// One row per test node, in label order.
    pub nodes: Vec<NodeMapping>,
}

impl std::fmt::Display for Mapping {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let mut s = String::new();
        let _ = writeln!(
            s,
            "Mapping of the test nodes onto the model ({}, tolerance {:.3e} m, test units {} m)",
            match self.method {
                MapMethod::Nearest => "nearest node",
                MapMethod::Interpolate => "interpolated in elements",
            },
            self.tolerance,
            self.metres_per_unit
        );
        if let Some(a) = &self.alignment {
            let t = &a.transform;
            let _ = writeln!(
                s,
                "alignment ({}): rotation {:.4} deg, translation ({:.6}, {:.6}, {:.6}) m, scale {:.6}; residual rms {:.3e} m, largest {:.3e} m (node {})",
                a.method,
                t.angle_degrees(),
                t.translation[0],
                t.translation[1],
                t.translation[2],
                t.scale,
                a.rms(),
                a.residuals.iter().map(|r| r.1).fold(0.0, f64::max),
                a.residuals
                    .iter()
                    .max_by(|x, y| x.1.total_cmp(&y.1))
                    .map_or(0, |r| r.0)
            );
        }
        let _ = writeln!(
            s,
            "{:>10}  {:>12} {:>12} {:>12}  {:<34} {:>10}",
            "test node", "x (m)", "y (m)", "z (m)", "model node / element (xi)", "dist. (m)"
        );
        for n in &self.nodes {
            let target = match &n.target {
                Target::Node { model } => format!("node {model}"),
                Target::Element { element, kind, xi } => format!(
                    "{kind} {element} ({:.3}, {:.3}, {:.3})",
                    xi[0], xi[1], xi[2]
                ),
            };
            let _ = writeln!(
                s,
                "{:>10}  {:>12.6} {:>12.6} {:>12.6}  {:<34} {:>10.3e}",
                n.test, n.position[0], n.position[1], n.position[2], target, n.distance
            );
        }
        f.write_str(&s)
    }
}

/// A wireframe larger than the model is in other units (or another frame): the reason, with the
/// unit whose factor matches the size ratio, when the test's nodes as `placed` span more than
/// twice the model's `diagonal` (and the tolerance).
fn check_span(
    placed: &[[f64; 3]],
    diagonal: f64,
    tolerance: f64,
    metres: f64,
) -> Result<(), String> {
    let test_span = femu_fem::mesh::bounding_diagonal(placed);
    if !placed.is_empty() && test_span > 2.0 * diagonal + 2.0 * tolerance {
        let ratio = test_span / diagonal.max(f64::MIN_POSITIVE);
        let units = [("mm", 1000.0), ("cm", 100.0), ("in", 39.37), ("ft", 3.281)];
        let likely = units
            .iter()
            .filter(|(_, r)| ratio <= 1.25 * r && ratio >= 0.05 * r)
            .min_by(|a, b| {
                (ratio / a.1)
                    .ln()
                    .abs()
                    .total_cmp(&(ratio / b.1).ln().abs())
            })
            .map(|(u, _)| *u);
        return Err(format!(
            "the test's nodes span {test_span:.4e} m, {ratio:.0} times the model's {diagonal:.4e} m (its bounding-box diagonal): a test cannot be larger than the structure it measures, so its coordinates are in other units{}{}",
            match likely {
                Some(u) => format!(
                    " (the ratio is about that of {u} to the model's unit: --test-units {u}, or test_units = \"{u}\" in a study file)"
                ),
                None => " (--test-units)".into(),
            },
            if metres != 1.0 {
                format!("; they were read as {metres} m per unit")
            } else {
                String::new()
            }
        ));
    }
    Ok(())
}

/// Aligns and maps the test `data` onto `model` (coordinates of the file times `metres`): the
/// sensors are relabelled to model nodes ([`MapMethod::Nearest`]) or become sensors between
/// nodes ([`MapMethod::Interpolate`]); their directions turn with the alignment.
///
/// # Errors
/// A sensor node without coordinates; a bad tolerance; alignment pairs naming nodes that do not
/// exist, fewer than three, or on one line; a test node farther than the tolerance from the
/// model (its label, position and distance); two test nodes on one model node (nearest).
pub fn map_test(
    data: &mut TestData,
    mesh: &Mesh,
    options: &MapOptions,
    metres: f64,
) -> Result<Mapping, CorrelateError> {
    let in_file = |reason: String| CorrelateError::Mapping {
        what: "map",
        reason,
    };
    let mut labels: Vec<u64> = data.sensors.iter().map(|s| s.node).collect();
    labels.sort_unstable();
    labels.dedup();
    if data.coordinates.is_empty() {
        return Err(in_file(
            "mapping needs the test nodes' coordinates: a universal file with dataset 15 or 2411, or CSV/JSON columns x, y, z".into(),
        ));
    }
    let mut test: BTreeMap<u64, [f64; 3]> = BTreeMap::new();
    for &t in &labels {
        let x = data.coordinates.get(&t).ok_or_else(|| {
            in_file(format!(
                "test node {t} has modes but no coordinates (dataset 15 or 2411, or the x, y, z columns)"
            ))
        })?;
        test.insert(t, x.map(|v| v * metres));
    }
    // the model's size sets the default tolerance; its box serves the distance of far nodes
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for c in mesh.coords() {
        for i in 0..3 {
            lo[i] = lo[i].min(c[i]);
            hi[i] = hi[i].max(c[i]);
        }
    }
    let diagonal = (0..3).map(|i| (hi[i] - lo[i]).powi(2)).sum::<f64>().sqrt();
    let tolerance = options.tolerance.unwrap_or(0.01 * diagonal);
    if !(tolerance.is_finite() && tolerance >= 0.0) {
        return Err(CorrelateError::Invalid {
            what: "mapping tolerance",
            reason: format!("{tolerance} m is not a non-negative distance"),
        });
    }
    let alignment = align(data, &test, mesh, options, metres)?;
    let transform = alignment
        .as_ref()
        .map_or(Transform::IDENTITY, |a| a.transform);
    // a wireframe larger than the model is in other units (or another frame): said before any
    // node is searched for, with the unit whose factor matches the size ratio
    let placed: Vec<[f64; 3]> = test.values().map(|x| transform.apply(*x)).collect();
    check_span(&placed, diagonal, tolerance, metres).map_err(in_file)?;
    let locator = Locator::new(mesh);
    let mut nodes = Vec::with_capacity(test.len());
    let mut reads: BTreeMap<u64, Vec<(u64, f64)>> = BTreeMap::new();
    let mut taken: BTreeMap<u64, u64> = BTreeMap::new();
    // test nodes beyond the tolerance: (distance, node, what), all of them, to name the worst
    let mut beyond: Vec<(f64, u64, [f64; 3], String)> = Vec::new();
    // the distance from the model's bounding box, which needs no search
    let outside_box = |p: [f64; 3]| -> f64 {
        (0..3)
            .map(|i| (lo[i] - p[i]).max(p[i] - hi[i]).max(0.0).powi(2))
            .sum::<f64>()
            .sqrt()
    };
    for (&t, x) in &test {
        let p = transform.apply(*x);
        // beyond the tolerance from the bounding box: beyond it from the model; described below
        // if it is the farthest
        let boxed = outside_box(p);
        if boxed > tolerance {
            beyond.push((boxed, t, p, String::new()));
            continue;
        }
        let row = match options.method {
            MapMethod::Nearest => {
                let Some((i, d)) = locator.nearest_node(mesh, p, tolerance) else {
                    match locator.nearest_node(mesh, p, f64::INFINITY) {
                        Some((i, d)) => beyond.push((
                            d,
                            t,
                            p,
                            format!(
                                "is {d:.3e} m from the nearest model node ({})",
                                mesh.node_id(i)
                            ),
                        )),
                        None => beyond.push((f64::INFINITY, t, p, "finds no model node".into())),
                    }
                    continue;
                };
                let id = mesh.node_id(i);
                if let Some(other) = taken.insert(id, t) {
                    return Err(in_file(format!(
                        "test nodes {other} and {t} both map to model node {id}: lower the tolerance, refine the mesh, or use --map interpolate"
                    )));
                }
                reads.insert(t, vec![(id, 1.0)]);
                NodeMapping {
                    test: t,
                    position: p,
                    target: Target::Node { model: id },
                    distance: d,
                }
            }
            MapMethod::Interpolate => {
                let Some(loc) = locator.locate(mesh, p, tolerance) else {
                    match locator.locate(mesh, p, f64::INFINITY) {
                        Some(l) => beyond.push((
                            l.distance,
                            t,
                            p,
                            format!(
                                "lies outside the model, {:.3e} m from element {}",
                                l.distance,
                                mesh.element(l.element).id
                            ),
                        )),
                        None => beyond.push((f64::INFINITY, t, p, "lies outside the model".into())),
                    }
                    continue;
                };
                let el = mesh.element(loc.element);
                // a point on a node reads that node alone
                let on_node = loc.weights.iter().find(|w| (w.1 - 1.0).abs() < 1e-9);
                let (target, at) = match on_node {
                    Some(&(a, _)) => (
                        Target::Node {
                            model: mesh.node_id(a),
                        },
                        vec![(mesh.node_id(a), 1.0)],
                    ),
                    None => (
                        Target::Element {
                            element: el.id,
                            kind: el.kind,
                            xi: loc.xi,
                        },
                        loc.weights
                            .iter()
                            .filter(|w| w.1 != 0.0)
                            .map(|(a, w)| (mesh.node_id(*a), *w))
                            .collect(),
                    ),
                };
                reads.insert(t, at);
                NodeMapping {
                    test: t,
                    position: p,
                    target,
                    distance: loc.distance,
                }
            }
        };
        nodes.push(row);
    }
    if !beyond.is_empty() {
        return Err(far_node_error(
            &beyond,
            tolerance,
            alignment.is_some(),
            options.method,
            &locator,
            mesh,
        ));
    }
    for s in &mut data.sensors {
        let at = &reads[&s.node];
        let direction = transform.rotate(s.direction);
        *s = match at.as_slice() {
            [(id, _)] => Sensor::new(*id, direction),
            _ => Sensor::between(s.node, direction, at.clone()),
        };
    }
    // coordinates now belong to the model's nodes or points: keep the mapped positions
    data.coordinates = nodes.iter().map(|n| (n.test, n.position)).collect();
    Ok(Mapping {
        method: options.method,
        tolerance,
        metres_per_unit: metres,
        alignment,
        nodes,
    })
}

/// The alignment `options` ask for of the test nodes `test` (metres) onto `mesh`.
fn align(
    data: &TestData,
    test: &BTreeMap<u64, [f64; 3]>,
    mesh: &Mesh,
    options: &MapOptions,
    metres: f64,
) -> Result<Option<Alignment>, CorrelateError> {
    let in_file = |reason: String| CorrelateError::Mapping {
        what: "map",
        reason,
    };
    let fit = |f: Result<Fit, femu_fem::FemError>| f.map_err(|e| in_file(e.to_string()));
    Ok(match &options.align {
        Align::None => None,
        Align::Pairs(pairs) => {
            let mut from = Vec::new();
            let mut to = Vec::new();
            for (t, m) in pairs {
                let x = data.coordinates.get(t).ok_or_else(|| {
                    in_file(format!(
                        "alignment pair {t}:{m}: the test file has no node {t} with coordinates"
                    ))
                })?;
                let i = mesh.node_index(*m).ok_or_else(|| {
                    in_file(format!("alignment pair {t}:{m}: the model has no node {m}"))
                })?;
                from.push(x.map(|v| v * metres));
                to.push(mesh.coords()[i]);
            }
            let f = fit(fit_pairs(&from, &to, options.scale))?;
            Some(Alignment {
                method: "pairs",
                transform: f.transform,
                residuals: pairs.iter().map(|p| p.0).zip(f.residuals).collect(),
            })
        }
        Align::Auto => {
            let surface = Surface::new(mesh);
            let points: Vec<[f64; 3]> = test.values().copied().collect();
            let f = fit(fit_auto(&points, &surface, options.scale))?;
            Some(Alignment {
                method: "auto",
                transform: f.transform,
                residuals: test.keys().copied().zip(f.residuals).collect(),
            })
        }
    })
}

/// The error for the test nodes `beyond` the tolerance: the farthest, described by a search of
/// the model, and the others by distance.
fn far_node_error(
    beyond: &[(f64, u64, [f64; 3], String)],
    tolerance: f64,
    aligned: bool,
    method: MapMethod,
    locator: &Locator,
    mesh: &Mesh,
) -> CorrelateError {
    // the farthest (the first of equals), described by a search of the model
    let worst = beyond
        .iter()
        .enumerate()
        .fold(None::<usize>, |w, (k, b)| match w {
            Some(j) if beyond[j].0 >= b.0 => Some(j),
            _ => Some(k),
        })
        .map(|k| beyond[k].clone());
    let (_, t, p, what) = worst.expect("called with nodes beyond the tolerance");
    let what = if !what.is_empty() {
        what
    } else {
        match method {
            MapMethod::Nearest => match locator.nearest_node(mesh, p, f64::INFINITY) {
                Some((i, d)) => format!(
                    "is {d:.3e} m from the nearest model node ({})",
                    mesh.node_id(i)
                ),
                None => "finds no model node".into(),
            },
            MapMethod::Interpolate => match locator.locate(mesh, p, f64::INFINITY) {
                Some(l) => format!(
                    "lies outside the model, {:.3e} m from element {}",
                    l.distance,
                    mesh.element(l.element).id
                ),
                None => "lies outside the model".into(),
            },
        }
    };
    let others = beyond.len() - 1;
    CorrelateError::Mapping {
        what: "map",
        reason: format!(
            "test node {t} at ({:.6}, {:.6}, {:.6}) m in the model's frame {what}, beyond the tolerance {tolerance:.3e} m{}{}",
            p[0],
            p[1],
            p[2],
            if others > 0 {
                format!(
                    "; the farthest of {} test nodes beyond it ({})",
                    beyond.len(),
                    beyond
                        .iter()
                        .filter(|b| b.1 != t)
                        .take(8)
                        .map(|b| format!("{} at {:.3e} m", b.1, b.0))
                        .collect::<Vec<_>>()
                        .join(", ")
                )
            } else if aligned {
                ": the only test node the alignment could not place".into()
            } else {
                String::new()
            },
            if !aligned {
                " (is the test in another frame? see --align)"
            } else {
                ""
            }
        ),
    }
}
