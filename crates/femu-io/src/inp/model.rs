//! An [`InpDeck`] into femu's [`Model`]: sets, materials, sections, constraints, links, masses.

use super::*;

impl InpDeck {
    /// The model: mesh (validated), materials by section, fixed DOFs.
    ///
    /// # Errors
    /// [`IoError::Model`] naming the line of an invalid element (inverted, degenerate), a section
    /// on an unknown set or material, a boundary on an unknown node or set; elements without a
    /// section.
    pub fn to_model(&self) -> Result<Model, IoError> {
        self.to_model_with_warnings().map(|(m, _)| m)
    }

    /// The model, with what building it found worth saying (slave nodes of a `*TIE` left untied
    /// or tied across a gap), beside the deck's own [`InpDeck::warnings`].
    ///
    /// # Errors
    /// As [`InpDeck::to_model`].
    pub fn to_model_with_warnings(&self) -> Result<(Model, Vec<Warning>), IoError> {
        self.build_model().map_err(|e| e.after(&self.warnings))
    }

    /// Where element `id` was defined, or the deck itself.
    fn at_element(&self, id: Option<u64>, source: femu_fem::FemError) -> IoError {
        match id.and_then(|id| self.element_lines.get(&id)) {
            Some(l) => IoError::Model {
                path: l.path.clone(),
                line: l.line,
                source,
            },
            None => IoError::Content {
                path: self.path.clone(),
                reason: source.to_string(),
            },
        }
    }

    /// An anisotropic solid section's material turned from the axes of `card` to the global
    /// frame (docs/MATH.md, "Material orientations"): one frame for the whole section, so a
    /// rectangular orientation of coordinates or nodes.
    fn solid_orientation(
        &self,
        card: &orientation::OrientationCard,
        d: &[[f64; 6]; 6],
        material: &Material,
        at: &Location,
    ) -> Result<Material, IoError> {
        if card.system != orientation::System::Rectangular
            || card.definition == orientation::Definition::OffsetToNodes
        {
            return Err(structural::at_err(
                at,
                format!(
                    "*SOLID SECTION, ORIENTATION={}: femu gives a solid section of an anisotropic material one frame; this orientation changes from element to element (a cylindrical system or OFFSET TO NODES)",
                    card.name
                ),
            ));
        }
        let node = |id: u64| self.mesh.node_index(id).map(|i| self.mesh.coords()[i]);
        let frame = card.frame(&orientation::At {
            element: 0,
            x: &[],
            node: &node,
        })?;
        Material::anisotropic(
            material.name.clone(),
            orientation::rotate_elasticity(d, &frame),
            material.density,
        )
        .map_err(|source| IoError::Model {
            path: at.path.clone(),
            line: at.line,
            source,
        })
    }

    fn build_model(&self) -> Result<(Model, Vec<Warning>), IoError> {
        let mut model = Model::new(self.mesh.clone())
            .map_err(|source| self.at_element(element_of(&source), source))?;
        for id in &self.incompatible_modes {
            let e = self.mesh.element_index(*id).expect("read with the mesh");
            model
                .set_formulation(e, Formulation::IncompatibleModes)
                .map_err(|source| self.at_element(Some(*id), source))?;
        }
        for s in &self.sections {
            let material = self.materials.get(&s.material).ok_or_else(|| {
                let hint = crate::spelling::suggestion(
                    &s.material,
                    self.materials.keys().map(String::as_str),
                    "",
                );
                IoError::Parse {
                    path: s.line.path.clone(),
                    line: s.line.line,
                    reason: if self.laminae.contains_key(&s.material) {
                        format!(
                            "*SOLID SECTION names material {}, a LAMINA (a shell's plane-stress ply); a solid takes an ISOTROPIC, ENGINEERING CONSTANTS, ORTHOTROPIC or ANISOTROPIC *ELASTIC",
                            s.material
                        )
                    } else {
                        format!(
                            "*SOLID SECTION names material {}, which no *MATERIAL defines{hint}",
                            s.material
                        )
                    },
                }
            })?;
            let oriented;
            let material = match &s.orientation {
                Some(name) => {
                    let card = orientation::named(&self.orientations, name, &s.line)?;
                    match &material.elasticity {
                        // an isotropic material is the same in every frame
                        Elasticity::Isotropic { .. } => material,
                        Elasticity::Anisotropic(d) => {
                            oriented = self.solid_orientation(card, d, material, &s.line)?;
                            &oriented
                        }
                    }
                }
                None => material,
            };
            if self.mesh.element_sets().get(&s.elset).is_none() {
                // a set of trusses alone: its elements take the section as trusses
                if self.structural.sets.contains_key(&s.elset) {
                    continue;
                }
                let hint = crate::spelling::suggestion(
                    &s.elset,
                    self.mesh.element_sets().keys().map(String::as_str),
                    "",
                );
                return Err(IoError::Parse {
                    path: s.line.path.clone(),
                    line: s.line.line,
                    reason: format!(
                        "*SOLID SECTION names element set {}, which the deck does not define{hint}",
                        s.elset
                    ),
                });
            }
            model
                .set_material(Some(&s.elset), material.clone())
                .map_err(|source| IoError::Model {
                    path: s.line.path.clone(),
                    line: s.line.line,
                    source,
                })?;
            if let Some(damping) = self.material_damping.get(&s.material) {
                for &e in &self.mesh.element_sets()[&s.elset] {
                    let id = self.mesh.element(e).id;
                    damping
                        .apply(&mut model, id)
                        .map_err(|source| IoError::Model {
                            path: s.line.path.clone(),
                            line: s.line.line,
                            source,
                        })?;
                }
            }
        }
        model
            .set_mode_ratios(self.mode_ratios.clone())
            .map_err(|source| self.at_element(None, source))?;
        model.set_modal_damping_structural(self.modal_structural);
        if !self.modal_frequency_points.is_empty() {
            let mut points = self.modal_frequency_points.clone();
            points.sort_by(|a, b| a.0.total_cmp(&b.0));
            model
                .set_modal_damping(Some(femu_fem::model::ModalDampingTable {
                    units: if self.modal_structural {
                        femu_fem::model::ModalDampingUnits::G
                    } else {
                        femu_fem::model::ModalDampingUnits::Crit
                    },
                    points,
                    hold_ends: true,
                }))
                .map_err(|source| self.at_element(None, source))?;
        }
        model
            .set_mode_rayleigh(self.modal_rayleigh_ranges.clone())
            .map_err(|source| self.at_element(None, source))?;
        if let Some((alpha, beta)) = self.modal_rayleigh {
            model
                .set_uniform_damping(Some(femu_fem::model::UniformDamping::Rayleigh {
                    alpha,
                    beta,
                }))
                .map_err(|source| self.at_element(None, source))?;
        }
        structural::add_structural(
            &self.structural,
            &self.sections,
            &self.materials,
            &self.material_damping,
            &self.laminae,
            &self.orientations,
            &mut model,
        )?;
        self.apply_nonstructural(&mut model)?;
        self.apply_links(&mut model)?;
        let warnings = self.apply_ties(&mut model)?;
        // rotary inertias: on nodes that carry rotations (beams', shells', couplings' references)
        for (node, inertia, at) in &self.rotary_inertias {
            model
                .add_rotary_inertia(*node, *inertia)
                .map_err(|source| IoError::Model {
                    path: at.path.clone(),
                    line: at.line,
                    source,
                })?;
        }
        for b in &self.boundaries {
            let all: Vec<usize> = (b.first - 1..b.last).collect();
            let comps: Vec<usize> = all.iter().copied().filter(|c| *c < 3).collect();
            // rotations: on the nodes that have them (coupling references)
            let rotations: Vec<usize> = all.iter().copied().filter(|c| *c >= 3).collect();
            if !rotations.is_empty() {
                let nodes: Vec<usize> = match &b.target {
                    Target::Node(id) => model.mesh().node_index(*id).into_iter().collect(),
                    Target::Set(s) => self.mesh.node_sets().get(s).cloned().unwrap_or_default(),
                };
                for n in nodes {
                    if model.has_rotations(n) {
                        let id = model.mesh().node_id(n);
                        model
                            .fix_node_dofs(id, &rotations)
                            .map_err(|source| IoError::Model {
                                path: b.line.path.clone(),
                                line: b.line.line,
                                source,
                            })?;
                    }
                }
            }
            if comps.is_empty() {
                continue;
            }
            let r = match &b.target {
                Target::Node(id) => model.fix_nodes(&[*id], &comps),
                Target::Set(s) => {
                    if self.mesh.node_sets().get(s).is_none() {
                        let hint = crate::spelling::suggestion(
                            s,
                            self.mesh.node_sets().keys().map(String::as_str),
                            "",
                        );
                        return Err(IoError::Parse {
                            path: b.line.path.clone(),
                            line: b.line.line,
                            reason: format!(
                                "*BOUNDARY names {s}, which is neither a node id nor a node set of the deck{hint}"
                            ),
                        });
                    }
                    model.fix_set(s, &comps)
                }
            };
            r.map_err(|source| IoError::Model {
                path: b.line.path.clone(),
                line: b.line.line,
                source,
            })?;
        }
        // point masses, on nodes that solid elements or constraints connect (a mass on a free
        // node would have no stiffness)
        let mut connected = model.constrained_nodes();
        for el in model.mesh().elements() {
            for n in el.nodes {
                connected[*n] = true;
            }
        }
        for s in model.structural() {
            for n in &s.nodes {
                connected[*n] = true;
            }
        }
        for ((node, mass, at), set) in self.point_masses.iter().zip(&self.point_mass_sets) {
            let located = |reason: String| IoError::Parse {
                path: at.path.clone(),
                line: at.line,
                reason,
            };
            let i = model.mesh().node_index(*node).ok_or_else(|| {
                located(format!(
                    "*MASS on node {node}, which the deck does not define"
                ))
            })?;
            if !connected[i] {
                return Err(located(format!(
                    "*MASS on node {node}, which no solid element or constraint connects: it would have no stiffness"
                )));
            }
            let in_model = |source| IoError::Model {
                path: at.path.clone(),
                line: at.line,
                source,
            };
            model.add_point_mass(*node, *mass).map_err(in_model)?;
            // the *MASS's element set is a mass set for updating
            let added: Vec<_> = model.last_mass(false).into_iter().collect();
            model.add_mass_set(set.clone(), &added).map_err(in_model)?;
        }
        // every element needs a material
        for e in 0..model.mesh().element_count() {
            if let Err(source) = model.material_of(e) {
                let id = model.mesh().element(e).id;
                return Err(self.at_element(Some(id), source));
            }
        }
        // conflicts between constraints (a DOF dependent twice or also fixed, cycles) now
        model.dof_map().map_err(|source| IoError::Content {
            path: self.path.clone(),
            reason: source.to_string(),
        })?;
        Ok((model, warnings))
    }

    /// Node ids of a target (a node, or a node set of the deck).
    pub(super) fn target_ids(
        &self,
        t: &Target,
        at: &Location,
        what: &str,
    ) -> Result<Vec<u64>, IoError> {
        match t {
            Target::Node(id) => Ok(vec![*id]),
            Target::Set(s) => match self.mesh.node_sets().get(s) {
                Some(nodes) => Ok(nodes.iter().map(|n| self.mesh.node_id(*n)).collect()),
                None => {
                    let hint = crate::spelling::suggestion(
                        s,
                        self.mesh.node_sets().keys().map(String::as_str),
                        "",
                    );
                    Err(IoError::Parse {
                        path: at.path.clone(),
                        line: at.line,
                        reason: format!(
                            "{what} names {s}, which is neither a node id nor a node set of the deck{hint}"
                        ),
                    })
                }
            },
        }
    }

    /// The coupled nodes and their weights.
    fn link_nodes(
        &self,
        nodes: &LinkNodes,
        at: &Location,
        what: &str,
    ) -> Result<Vec<(u64, f64)>, IoError> {
        let mut out = Vec::new();
        match nodes {
            LinkNodes::Targets(ts) => {
                for t in ts {
                    out.extend(self.target_ids(t, at, what)?.into_iter().map(|i| (i, 1.0)));
                }
            }
            LinkNodes::Surface(name) => {
                let list = self.surfaces.get(name).ok_or_else(|| IoError::Parse {
                    path: at.path.clone(),
                    line: at.line,
                    reason: if self.element_surfaces.contains_key(name) {
                        format!(
                            "{what}: surface {name} is element-based; a coupling takes a node-based surface (*SURFACE, TYPE=NODE)"
                        )
                    } else {
                        format!(
                            "{what}: surface {name} is not defined (femu reads *SURFACE, TYPE=NODE){}",
                            crate::spelling::suggestion(
                                name,
                                self.surfaces.keys().map(String::as_str),
                                ""
                            )
                        )
                    },
                })?;
                for (t, w) in list {
                    out.extend(self.target_ids(t, at, what)?.into_iter().map(|i| (i, *w)));
                }
            }
            LinkNodes::Elements(name) => {
                let mut ids: Vec<u64> = Vec::new();
                let solids = self.mesh.element_sets().get(name);
                for &e in solids.into_iter().flatten() {
                    ids.extend(
                        self.mesh
                            .element(e)
                            .nodes
                            .iter()
                            .map(|n| self.mesh.node_id(*n)),
                    );
                }
                let structural = self.structural.sets.get(name);
                for id in structural.into_iter().flatten() {
                    if let Some(e) = self.structural.elements.iter().find(|e| e.0 == *id) {
                        ids.extend(e.2.iter().copied());
                    }
                }
                if solids.is_none() && structural.is_none() {
                    return Err(IoError::Parse {
                        path: at.path.clone(),
                        line: at.line,
                        reason: format!(
                            "{what}: ELSET={name} names no element set of the deck{}",
                            crate::spelling::suggestion(
                                name,
                                self.mesh.element_sets().keys().map(String::as_str),
                                ""
                            )
                        ),
                    });
                }
                ids.sort_unstable();
                ids.dedup();
                out.extend(ids.into_iter().map(|i| (i, 1.0)));
            }
        }
        Ok(out)
    }

    /// The deck's couplings and equations into `model`: kinematic couplings first (their
    /// references get rotations), then distributing couplings, then equations (which may name
    /// the references' rotations, DOFs 4-6).
    fn apply_links(&self, model: &mut Model) -> Result<(), IoError> {
        for pass in 0..3 {
            for link in &self.links {
                let at = &link.line;
                let located = |source| IoError::Model {
                    path: at.path.clone(),
                    line: at.line,
                    source,
                };
                match (&link.kind, pass) {
                    (
                        LinkKind::Kinematic {
                            reference,
                            nodes,
                            dofs,
                        },
                        0,
                    ) => {
                        let label = format!(
                            "kinematic coupling to node {reference} ({} line {})",
                            at.path.display(),
                            at.line
                        );
                        let ids = self.link_nodes(nodes, at, "*KINEMATIC COUPLING")?;
                        let ids: Vec<u64> = ids.into_iter().map(|p| p.0).collect();
                        let all: &[usize] = if dofs.is_empty() {
                            &[1, 2, 3, 4, 5, 6]
                        } else {
                            dofs
                        };
                        let trans: Vec<usize> =
                            all.iter().filter(|d| **d <= 3).map(|d| d - 1).collect();
                        model
                            .add_rigid_link(*reference, &ids, &trans, &label)
                            .map_err(located)?;
                        // coupled nodes that carry rotations follow the reference's
                        for &id in &ids {
                            let has = model
                                .mesh()
                                .node_index(id)
                                .is_some_and(|n| model.has_rotations(n));
                            if has && id != *reference {
                                for d in all.iter().filter(|d| **d > 3) {
                                    model
                                        .add_constraint(
                                            (id, d - 1),
                                            &[((*reference, d - 1), 1.0)],
                                            &label,
                                        )
                                        .map_err(located)?;
                                }
                            }
                        }
                    }
                    (
                        LinkKind::Distributing {
                            reference,
                            nodes,
                            dofs,
                        },
                        1,
                    ) => {
                        let label = format!(
                            "distributing coupling of node {reference} ({} line {})",
                            at.path.display(),
                            at.line
                        );
                        let pairs = self.link_nodes(nodes, at, "*DISTRIBUTING")?;
                        let has_rot = model
                            .mesh()
                            .node_index(*reference)
                            .is_some_and(|n| model.has_rotations(n));
                        let all: &[usize] = if dofs.is_empty() {
                            &[1, 2, 3, 4, 5, 6]
                        } else {
                            dofs
                        };
                        let comps: Vec<usize> = all
                            .iter()
                            .filter(|d| **d <= 3 || has_rot)
                            .map(|d| d - 1)
                            .collect();
                        model
                            .add_weighted_average(*reference, &comps, &pairs, &label)
                            .map_err(located)?;
                    }
                    (LinkKind::Equation(terms), 2) => {
                        let label = format!("*EQUATION ({} line {})", at.path.display(), at.line);
                        let (n0, d0, a0) = terms[0];
                        if a0 == 0.0 {
                            return Err(IoError::Parse {
                                path: at.path.clone(),
                                line: at.line,
                                reason: "*EQUATION: the first coefficient (of the dependent DOF) is zero".into(),
                            });
                        }
                        let rest: Vec<((u64, usize), f64)> = terms[1..]
                            .iter()
                            .map(|(n, d, a)| ((*n, d - 1), -a / a0))
                            .collect();
                        model
                            .add_constraint((n0, d0 - 1), &rest, &label)
                            .map_err(located)?;
                    }
                    _ => {}
                }
            }
        }
        Ok(())
    }
}

pub(super) fn element_of(e: &femu_fem::FemError) -> Option<u64> {
    use femu_fem::FemError as E;
    match e {
        E::InvertedElement { element, .. } | E::DegenerateElement { element, .. } => Some(*element),
        _ => None,
    }
}
