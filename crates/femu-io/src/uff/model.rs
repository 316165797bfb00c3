//! A universal file as femu data: test modes on sensors, and solids as a mesh with sets.

use super::*;

impl Universal {
    /// The file's length factor (dataset 164; 1 without it): SI = file units / factor.
    ///
    /// # Errors
    /// A factor that is not a positive finite number.
    pub fn length_factor(&self, path: &Path) -> Result<f64, IoError> {
        let f = self.units.as_ref().map_or(1.0, |u| u.factors[0]);
        if f.is_finite() && f > 0.0 {
            Ok(f)
        } else {
            Err(IoError::Content {
                path: path.to_path_buf(),
                reason: format!("dataset 164's length factor {f} is not a positive number"),
            })
        }
    }

    /// The femu mesh of the file's nodes and solid elements: linear (descriptors 111 tetrahedron,
    /// 112 wedge, 115 brick, whose node orders are Abaqus') and parabolic (118, 113, 116, whose
    /// I-DEAS orders interleave corners and mid-edge nodes around each face: converted, see
    /// `UNV_HEX20`); other elements (shells, beams) are skipped and counted in the returned
    /// warnings. Coordinates are converted to metres with the file's units (dataset 164: SI = file
    /// units / length factor, so a millimetre file's factor is 1000), said in a warning when not 1.
    ///
    /// # Errors
    /// A wrong node count (element label), a mesh error (duplicate or missing node), no solid, a
    /// length factor that is not a positive number.
    pub fn to_mesh(&self, path: &Path) -> Result<(femu_fem::mesh::Mesh, Vec<Warning>), IoError> {
        use femu_fem::element::ElementKind;
        let model_err = |source| IoError::Model {
            path: path.to_path_buf(),
            line: 0,
            source,
        };
        let length = self.length_factor(path)?;
        let mut mesh = femu_fem::mesh::Mesh::new();
        for n in &self.nodes {
            mesh.add_node(n.id, n.x.map(|v| v / length))
                .map_err(model_err)?;
        }
        let mut skipped = 0;
        for e in &self.elements {
            let (kind, order): (ElementKind, &[usize]) = match e.descriptor {
                111 => (ElementKind::Tet4, &[0, 1, 2, 3]),
                112 => (ElementKind::Penta6, &[0, 1, 2, 3, 4, 5]),
                115 => (ElementKind::Hex8, &[0, 1, 2, 3, 4, 5, 6, 7]),
                118 => (ElementKind::Tet10, &UNV_TET10),
                113 => (ElementKind::Penta15, &UNV_PENTA15),
                116 => (ElementKind::Hex20, &UNV_HEX20),
                _ => {
                    skipped += 1;
                    continue;
                }
            };
            if e.nodes.len() != order.len() {
                return Err(IoError::Content {
                    path: path.to_path_buf(),
                    reason: format!(
                        "element {}: descriptor {} needs {} nodes, found {}",
                        e.id,
                        e.descriptor,
                        order.len(),
                        e.nodes.len()
                    ),
                });
            }
            let nodes: Vec<u64> = order.iter().map(|&k| e.nodes[k]).collect();
            mesh.add_element(e.id, kind, &nodes).map_err(model_err)?;
        }
        if mesh.element_count() == 0 {
            return Err(IoError::Content {
                path: path.to_path_buf(),
                reason: if self.nodes.is_empty() && self.elements.is_empty() {
                    "no mesh in the file: a model needs nodes (dataset 2411 or 15) and solid elements (dataset 2412, descriptors 111-118)".into()
                } else {
                    format!(
                        "no solid element in the file ({} nodes, {} elements of other kinds): a model needs solid elements (dataset 2412, descriptors 111-118)",
                        self.nodes.len(),
                        self.elements.len()
                    )
                },
            });
        }
        // groups: solid elements make an element set; every element (shells and beams too) and
        // node of a group puts its nodes in the node set of that name (where clamps and sensors
        // go), as Gmsh does with physical groups
        let by_id: std::collections::HashMap<u64, &UffElement> =
            self.elements.iter().map(|e| (e.id, e)).collect();
        for g in &self.groups {
            let mut nodes: Vec<u64> = g.nodes.clone();
            let mut solids = Vec::new();
            for id in &g.elements {
                let e = by_id.get(id).ok_or_else(|| IoError::Content {
                    path: path.to_path_buf(),
                    reason: format!("group {}: element {id} is not in dataset 2412", g.name),
                })?;
                nodes.extend(&e.nodes);
                if mesh.element_index(*id).is_some() {
                    solids.push(*id);
                }
            }
            nodes.sort_unstable();
            nodes.dedup();
            let set_err = |e| IoError::Content {
                path: path.to_path_buf(),
                reason: format!("group {}: {e}", g.name),
            };
            if !solids.is_empty() {
                mesh.add_element_set(g.name.clone(), &solids)
                    .map_err(set_err)?;
            }
            if !nodes.is_empty() {
                mesh.add_node_set(g.name.clone(), &nodes).map_err(set_err)?;
            }
        }
        let mut warnings = Vec::new();
        if length != 1.0 {
            warnings.push(Warning {
                path: path.to_path_buf(),
                line: 0,
                message: format!(
                    "coordinates converted to metres: divided by the length factor {length} of dataset 164 ({})",
                    self.units.as_ref().map_or("", |u| u.description.as_str())
                ),
            });
        }
        if skipped > 0 {
            warnings.push(Warning {
                path: path.to_path_buf(),
                line: 0,
                message: format!("{skipped} non-solid elements (shells, beams) skipped"),
            });
        }
        Ok((mesh, warnings))
    }

    /// The test modes and sensors of the file's dataset-55 modes: one sensor per node and axis
    /// whose value is non-zero in some mode (test systems write unmeasured directions as zeros),
    /// in node order then x, y, z. Modes without node records are a test of frequencies alone (no
    /// sensor). `path` names the file in errors.
    ///
    /// # Errors
    /// No modes, modes on different node lists, no non-zero value, invalid frequencies.
    pub fn test_data(&self, path: &Path) -> Result<crate::TestData, IoError> {
        let bad = |reason: String| IoError::Content {
            path: PathBuf::from(path),
            reason,
        };
        let first = self.modes.first().ok_or_else(|| {
            bad("no modes in the file: test modes are dataset 55 (modal data), modes of another FE code dataset 2414 (analysis results)".into())
        })?;
        let nodes: Vec<u64> = first.values.iter().map(|(n, _)| *n).collect();
        for m in &self.modes {
            let these: Vec<u64> = m.values.iter().map(|(n, _)| *n).collect();
            if these != nodes {
                return Err(bad(format!(
                    "mode {} is given on other nodes than mode {}",
                    m.number, first.number
                )));
            }
        }
        // modes without node records: a test of frequencies alone
        if nodes.is_empty() {
            let modes = TestModes::frequencies_only(
                self.modes.iter().map(|m| m.frequency_hz).collect(),
                Some(self.modes.iter().map(|m| m.damping).collect()),
            )
            .map_err(|e| bad(e.to_string()))?;
            return Ok(crate::TestData {
                sensors: Vec::new(),
                modes,
                coordinates: Default::default(),
            });
        }
        // Values are in each node's displacement coordinate system. A node measured along all
        // three local axes is turned to global components (global axis sensors); one measured
        // along some of them keeps its readings, on sensors along those local axes in global
        // components (oblique sensors).
        let mut sensors = Vec::new();
        // per row: node position, and the global combination of its local components
        let mut rows: Vec<(usize, [f64; 3])> = Vec::new();
        let positions: std::collections::HashMap<u64, [f64; 3]> =
            self.nodes.iter().map(|n| (n.id, n.x)).collect();
        for (k, n) in nodes.iter().enumerate() {
            let measured: Vec<usize> = (0..3)
                .filter(|c| self.modes.iter().any(|m| m.values[k].1[*c] != 0.0))
                .collect();
            let system = match self.displacement_systems.get(n) {
                None => None,
                Some(cs) => {
                    let sys = self.coordinate_systems.get(cs).ok_or_else(|| {
                        bad(format!(
                            "node {n} measures in displacement coordinate system {cs}, which the file does not define (dataset 18)"
                        ))
                    })?;
                    if sys.is_global_orientation() {
                        None
                    } else if sys.kind == 0 {
                        Some(sys.axes)
                    } else {
                        // cylindrical and spherical axes depend on where the node is
                        let x = positions.get(n).ok_or_else(|| {
                            bad(format!(
                                "node {n} measures in the {} coordinate system {cs}, whose axes depend on the node's position, and the file gives no coordinates for it (dataset 15 or 2411)",
                                if sys.kind == 1 { "cylindrical" } else { "spherical" }
                            ))
                        })?;
                        Some(sys.axes_at(*x))
                    }
                }
            };
            match system {
                None => {
                    for c in measured {
                        sensors.push(Sensor::axis(*n, c));
                        let mut w = [0.0; 3];
                        w[c] = 1.0;
                        rows.push((k, w));
                    }
                }
                Some(axes) if measured.len() == 3 => {
                    // global component i = sum_j axes[i][j] local_j
                    for (i, row) in axes.iter().enumerate() {
                        sensors.push(Sensor::axis(*n, i));
                        rows.push((k, *row));
                    }
                }
                Some(axes) => {
                    for c in measured {
                        let direction = std::array::from_fn(|i| axes[i][c]);
                        sensors.push(Sensor::new(*n, direction));
                        let mut w = [0.0; 3];
                        w[c] = 1.0;
                        rows.push((k, w));
                    }
                }
            }
        }
        if sensors.is_empty() {
            return Err(bad("every mode shape value is zero".into()));
        }
        let shapes = Mat::from_fn(rows.len(), self.modes.len(), |r, j| {
            let (k, w) = rows[r];
            let v = self.modes[j].values[k].1;
            w[0] * v[0] + w[1] * v[1] + w[2] * v[2]
        });
        let damping = self.modes.iter().map(|m| m.damping).collect();
        let mut modes = TestModes::new(
            self.modes.iter().map(|m| m.frequency_hz).collect(),
            Some(damping),
            shapes,
        )
        .map_err(|e| bad(e.to_string()))?;
        // complex modes keep their imaginary parts (a real mode among them: zero)
        if self.modes.iter().any(|m| m.imaginary.is_some()) {
            let imaginary = Mat::from_fn(rows.len(), self.modes.len(), |r, j| {
                let (k, w) = rows[r];
                self.modes[j].imaginary.as_ref().map_or(0.0, |im| {
                    let v = im[k];
                    w[0] * v[0] + w[1] * v[1] + w[2] * v[2]
                })
            });
            modes = modes
                .with_imaginary(imaginary)
                .map_err(|e| bad(e.to_string()))?;
        }
        // coordinates of the nodes that carry sensors, in the file's units
        let coordinates = sensors
            .iter()
            .filter_map(|s| positions.get(&s.node).map(|x| (s.node, *x)))
            .collect();
        Ok(crate::TestData {
            sensors,
            modes,
            coordinates,
        })
    }
}
