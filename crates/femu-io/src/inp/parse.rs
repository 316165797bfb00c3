//! The deck's keywords and data lines into an [`InpDeck`]: one pass over the lines, in which a
//! [`DeckBuilder`] takes each keyword line and each data line to the method of that keyword, then
//! builds the mesh, resolves the sets and the point masses.

use super::*;

/// The error of line `l`.
fn err(l: &Line, reason: String) -> IoError {
    IoError::Parse {
        path: l.path.clone(),
        line: l.number,
        reason,
    }
}

/// A warning on line `l`.
fn warn(w: &mut Vec<Warning>, l: &Line, message: String) {
    w.push(Warning {
        path: l.path.clone(),
        line: l.number,
        message,
    })
}

/// Where line `l` is.
fn at(l: &Line) -> Location {
    Location {
        path: l.path.clone(),
        line: l.number,
    }
}

/// A node or node set of a data line's first field.
fn target(field: &str) -> Target {
    match field.parse::<u64>() {
        Ok(id) => Target::Node(id),
        Err(_) => Target::Set(field.to_ascii_uppercase()),
    }
}

pub(super) fn parse_collecting(
    lines: &[Line],
    path: &Path,
    options: &InpOptions,
    warnings: &mut Vec<Warning>,
) -> Result<InpDeck, IoError> {
    let mut deck = DeckBuilder::default();
    for (li, l) in lines.iter().enumerate() {
        let t = l.text.trim();
        if t.is_empty() || t.starts_with("**") {
            continue;
        }
        if t.starts_with('*') {
            deck.end_block(lines)?;
            let (name, params) = keyword(t);
            let mut sorted: Vec<(String, String)> = params.clone().into_iter().collect();
            sorted.sort();
            if check_keyword(&name, &sorted, options, l, warnings)? {
                deck.keyword(name, params, l, li, warnings)?;
            } else {
                // skipped: its data lines are skipped with it
                deck.skip_block()?;
            }
            continue;
        }
        if t.chars()
            .any(|c| c == '\u{FFFD}' || (c.is_control() && c != '\t'))
        {
            return Err(err(
                l,
                "binary data where a deck has text: is this an Abaqus/CalculiX .inp deck?".into(),
            ));
        }
        if !deck.seen_keyword {
            return Err(err(
                l,
                format!(
                    "data line {:?} before any keyword: a deck starts with a *KEYWORD line",
                    t.chars().take(40).collect::<String>()
                ),
            ));
        }
        deck.data(lines, li, t, warnings)?;
    }
    deck.finish(lines, path, warnings)
}

/// One term of an `*EQUATION`: node, DOF 1-6, coefficient.
type EquationTerm = (u64, usize, f64);

/// An `*NSET` or `*ELSET` as written: resolved once every node and element is known.
struct SetBlock {
    name: String,
    is_node: bool,
    tokens: Vec<String>,
    generate: bool,
    line: usize,
}

/// The deck read so far: raw records first, because elements and sets may refer to nodes
/// defined later in the file.
#[derive(Default)]
struct DeckBuilder {
    nodes: Vec<(u64, [f64; 3], usize)>,
    elements: Vec<(u64, ElementKind, Vec<u64>, usize)>,
    sets: Vec<SetBlock>,
    /// `*NODE, NSET=` and `*ELEMENT, ELSET=`: the ids of each block.
    node_set_of_block: Vec<(String, Vec<u64>)>,
    elem_set_of_block: Vec<(String, Vec<u64>)>,
    /// point masses: MASS elements (id, node, line index) by their ELSET, and *MASS cards
    mass_elements: Vec<(u64, u64, usize)>,
    mass_sets: BTreeMap<String, Vec<u64>>,
    mass_block: Option<String>,
    /// the element block being read is of ROTARYI elements (their sets in `rotary_sets`)
    rotary_block: bool,
    rotary_sets: BTreeMap<String, Vec<u64>>,
    nonstructural: Vec<NonstructuralMass>,
    /// `*ROTARY INERTIA`: its element set, `I11 I22 I33 I12 I13 I23`, line
    rotary_cards: Vec<(String, Option<[f64; 6]>, Location)>,
    mass_cards: Vec<MassCard>,
    materials: BTreeMap<String, Material>,
    material_damping: BTreeMap<String, super::MaterialDamping>,
    mode_ratios: Vec<(usize, usize, f64)>,
    /// `*MODAL DAMPING, STRUCTURAL` (true) or viscous ranges (false), with the first block's line.
    modal_structural: Option<(bool, Location)>,
    /// `*MODAL DAMPING, DEFINITION=FREQUENCY RANGE` points, and whether any block was by mode
    /// numbers (the two are not mixed), with its line.
    modal_frequency_points: Vec<(f64, f64)>,
    modal_by_mode: Option<(bool, Location)>,
    modal_rayleigh: Option<(f64, f64)>,
    modal_rayleigh_ranges: Vec<(usize, usize, f64, f64)>,
    laminae: BTreeMap<String, structural::Lamina>,
    orientations: Vec<orientation::OrientationCard>,
    pending: Option<PendingMaterial>,
    sections: Vec<Section>,
    boundaries: Vec<Boundary>,
    frequency: Option<FrequencyStep>,
    links: Vec<InpLink>,
    surfaces: BTreeMap<String, Vec<(Target, f64)>>,
    surface_now: Option<String>,
    /// element-based surfaces: their lines (an element or element set, a face label)
    element_surfaces: BTreeMap<String, Vec<(Target, String, Location)>>,
    /// the element-based surface being read
    element_surface_now: Option<String>,
    /// `*TIE`s: name, slave and master surfaces, position tolerance, line
    ties: Vec<Tie>,
    coupling_now: Option<(u64, String, Option<String>)>,
    /// couplings whose `REF NODE=` names a node set (Abaqus allows a set of one node): the
    /// link's index, the set and the keyword line, resolved once the sets are known
    reference_sets: Vec<(usize, String, Location)>,
    /// an *EQUATION being read: number of terms, terms so far, keyword line
    equation: Option<(usize, Vec<EquationTerm>, Location)>,
    block: String,
    block_params: HashMap<String, String>,
    element_kind_now: Option<(ElementKind, Formulation, usize)>,
    /// a beam or spring block: its type and node count
    structural_now: Option<(structural::StructuralType, usize)>,
    /// the first *BOUNDARY line that names rotations
    rotation_boundary: Option<Location>,
    structural: structural::StructuralRecords,
    incompatible_modes: Vec<u64>,
    element_buffer: Vec<String>,
    element_start: usize,
    /// A structural element's ids so far and its first line, while a trailing comma continues it
    structural_buffer: Option<(Vec<u64>, Line)>,
    seen_keyword: bool,
}

impl DeckBuilder {
    /// A keyword line ends the block before it: an element or equation must be complete.
    fn end_block(&mut self, lines: &[Line]) -> Result<(), IoError> {
        if !self.element_buffer.is_empty() {
            return Err(err(
                &lines[self.element_start],
                "element definition cut short by a keyword".into(),
            ));
        }
        if let Some((_, start)) = &self.structural_buffer {
            return Err(err(
                start,
                "element definition cut short by a keyword".into(),
            ));
        }
        self.equation_complete("before the next keyword")?;
        self.equation = None;
        self.seen_keyword = true;
        Ok(())
    }

    fn equation_complete(&self, before: &str) -> Result<(), IoError> {
        match &self.equation {
            Some((n, terms, at)) if terms.len() < *n => Err(IoError::Parse {
                path: at.path.clone(),
                line: at.line,
                reason: format!(
                    "*EQUATION announces {n} terms and gives {} {before}",
                    terms.len()
                ),
            }),
            _ => Ok(()),
        }
    }

    fn skip_block(&mut self) -> Result<(), IoError> {
        self.finish_material()?;
        self.block = String::new();
        self.element_kind_now = None;
        self.structural_now = None;
        Ok(())
    }

    /// The material being read, complete, into the deck's materials.
    fn finish_material(&mut self) -> Result<(), IoError> {
        let Some(p) = self.pending.take() else {
            return Ok(());
        };
        if p.structural.is_some() || p.alpha.is_some() || p.beta.is_some() {
            self.material_damping.insert(
                p.name.clone(),
                super::MaterialDamping {
                    structural: p.structural.unwrap_or(0.0),
                    alpha: p.alpha.unwrap_or(0.0),
                    beta: p.beta.unwrap_or(0.0),
                },
            );
        }
        if let Some(ty) = p.aniso {
            return self.finish_anisotropic(p, ty);
        }
        if p.lamina_type {
            let at = Location {
                path: p.path.clone(),
                line: p.line,
            };
            let [e1, e2, nu12, g12, g13, g23] = p.lamina.ok_or_else(|| {
                structural::at_err(
                    &at,
                    format!("material {} has no *ELASTIC data line", p.name),
                )
            })?;
            let density = p.density.ok_or_else(|| {
                structural::at_err(
                    &at,
                    format!(
                        "material {} has no *DENSITY (a frequency analysis needs it)",
                        p.name
                    ),
                )
            })?;
            let lamina = structural::Lamina {
                e1,
                e2,
                nu12,
                g12,
                g13,
                g23,
                density,
            };
            lamina.check(&at, &p.name)?;
            self.laminae.insert(p.name, lamina);
            return Ok(());
        }
        let (e, nu) = p.young.ok_or_else(|| IoError::Parse {
            path: p.path.clone(),
            line: p.line,
            reason: format!("material {} has no *ELASTIC", p.name),
        })?;
        let rho = p.density.ok_or_else(|| IoError::Parse {
            path: p.path.clone(),
            line: p.line,
            reason: format!(
                "material {} has no *DENSITY (a frequency analysis needs it)",
                p.name
            ),
        })?;
        let m =
            Material::isotropic(p.name.clone(), e, nu, rho).map_err(|source| IoError::Model {
                path: p.path.clone(),
                line: p.line,
                source,
            })?;
        self.materials.insert(p.name, m);
        Ok(())
    }

    /// An anisotropic material: its elasticity matrix from the constants of its type (docs/MATH.md,
    /// "Material orientations"); ENGINEERING CONSTANTS are also a shell's ply
    /// ([`structural::Lamina`]: `E1 E2 NU12 G12 G13 G23`, plane stress).
    fn finish_anisotropic(&mut self, p: PendingMaterial, ty: AnisoType) -> Result<(), IoError> {
        let at = Location {
            path: p.path.clone(),
            line: p.line,
        };
        if p.aniso_values.len() < ty.count() {
            return Err(structural::at_err(
                &Location {
                    path: p.path.clone(),
                    line: p.aniso_line,
                },
                format!(
                    "material {}: *ELASTIC, TYPE={} takes {} constants, got {}",
                    p.name,
                    ty.name(),
                    ty.count(),
                    p.aniso_values.len()
                ),
            ));
        }
        let density = p.density.ok_or_else(|| {
            structural::at_err(
                &at,
                format!(
                    "material {} has no *DENSITY (a frequency analysis needs it)",
                    p.name
                ),
            )
        })?;
        let v = &p.aniso_values;
        let model_err = |source| IoError::Model {
            path: p.path.clone(),
            line: p.line,
            source,
        };
        let m = match ty {
            AnisoType::EngineeringConstants => {
                let [e1, e2, e3, nu12, nu13, nu23, g12, g13, g23] =
                    [v[0], v[1], v[2], v[3], v[4], v[5], v[6], v[7], v[8]];
                let lamina = structural::Lamina {
                    e1,
                    e2,
                    nu12,
                    g12,
                    g13,
                    g23,
                    density,
                };
                lamina.check(&at, &p.name)?;
                self.laminae.insert(p.name.clone(), lamina);
                Material::orthotropic(
                    p.name.clone(),
                    [e1, e2, e3],
                    [nu12, nu13, nu23],
                    [g12, g13, g23],
                    density,
                )
                .map_err(model_err)?
            }
            AnisoType::Orthotropic => {
                let mut d = [[0.0; 6]; 6];
                // D1111 D1122 D2222 D1133 D2233 D3333 D1212 D1313 D2323
                d[0][0] = v[0];
                d[0][1] = v[1];
                d[1][1] = v[2];
                d[0][2] = v[3];
                d[1][2] = v[4];
                d[2][2] = v[5];
                d[3][3] = v[6];
                d[4][4] = v[7];
                d[5][5] = v[8];
                for i in 0..6 {
                    for j in 0..i {
                        d[i][j] = d[j][i];
                    }
                }
                Material::anisotropic(p.name.clone(), d, density).map_err(model_err)?
            }
            AnisoType::Anisotropic => {
                // the upper triangle column by column: D(0,0); D(0,1) D(1,1); D(0,2) ...
                let mut d = [[0.0; 6]; 6];
                let mut k = 0;
                for j in 0..6 {
                    for i in 0..=j {
                        d[i][j] = v[k];
                        d[j][i] = v[k];
                        k += 1;
                    }
                }
                Material::anisotropic(p.name.clone(), d, density).map_err(model_err)?
            }
        };
        self.materials.insert(p.name, m);
        Ok(())
    }

    /// A keyword femu reads: the block its data lines belong to.
    fn keyword(
        &mut self,
        name: String,
        params: HashMap<String, String>,
        l: &Line,
        li: usize,
        warnings: &mut Vec<Warning>,
    ) -> Result<(), IoError> {
        let material_keyword = matches!(name.as_str(), "ELASTIC" | "DENSITY")
            || (name == "DAMPING" && self.pending.is_some());
        if !material_keyword && name != "MATERIAL" {
            self.finish_material()?;
        }
        self.block = name.clone();
        self.block_params = params.clone();
        self.element_kind_now = None;
        self.structural_now = None;
        self.mass_block = None;
        self.rotary_block = false;
        let is_mass_element = || {
            params.get("TYPE").is_some_and(|t| {
                t.eq_ignore_ascii_case("MASS") || t.eq_ignore_ascii_case("ROTARYI")
            })
        };
        match name.as_str() {
            "KINEMATIC COUPLING" | "COUPLING" => self.coupling_keyword(&name, &params, l),
            "KINEMATIC" | "DISTRIBUTING" => self.coupling_method_keyword(&name, &params, l),
            "SURFACE" => self.surface_keyword(&params, l, warnings),
            "NODE" => self.node_keyword(&params, l),
            "ELEMENT" if is_mass_element() => self.mass_element_keyword(&params, l),
            "ELEMENT" => self.element_keyword(&params, l, warnings),
            "MASS" => self.mass_keyword(&params, l),
            "NONSTRUCTURAL MASS" => {
                let set = params
                    .get("ELSET")
                    .ok_or_else(|| err(l, "*NONSTRUCTURAL MASS without ELSET=".into()))?;
                let units = match params
                    .get("UNITS")
                    .map(|u| u.to_ascii_uppercase())
                    .as_deref()
                {
                    Some("MASS PER AREA") => NsmUnits::PerArea,
                    Some("MASS PER LENGTH") => NsmUnits::PerLength,
                    Some("TOTAL MASS") => NsmUnits::Total,
                    Some(u) => {
                        return Err(err(
                            l,
                            format!(
                                "*NONSTRUCTURAL MASS, UNITS={u}: femu reads MASS PER AREA (shells), MASS PER LENGTH (beams) and TOTAL MASS"
                            ),
                        ));
                    }
                    None => {
                        return Err(err(
                            l,
                            "*NONSTRUCTURAL MASS without UNITS= (MASS PER AREA, MASS PER LENGTH or TOTAL MASS)".into(),
                        ));
                    }
                };
                let by_volume = match params
                    .get("DISTRIBUTION")
                    .map(|d| d.to_ascii_uppercase())
                    .as_deref()
                {
                    None | Some("MASS PROPORTIONAL") => false,
                    Some("VOLUME PROPORTIONAL") => true,
                    Some(d) => {
                        return Err(err(
                            l,
                            format!(
                                "*NONSTRUCTURAL MASS, DISTRIBUTION={d}: MASS PROPORTIONAL or VOLUME PROPORTIONAL"
                            ),
                        ));
                    }
                };
                self.nonstructural.push(NonstructuralMass {
                    elset: set.to_ascii_uppercase(),
                    units,
                    by_volume,
                    value: None,
                    line: at(l),
                });
                Ok(())
            }
            "ROTARY INERTIA" => {
                let set = params
                    .get("ELSET")
                    .ok_or_else(|| err(l, "*ROTARY INERTIA without ELSET=".into()))?;
                self.rotary_cards
                    .push((set.to_ascii_uppercase(), None, at(l)));
                Ok(())
            }
            "NSET" | "ELSET" => self.set_keyword(&name, &params, l, li),
            "MATERIAL" => self.material_keyword(&params, l),
            "ELASTIC" | "DENSITY" => self.material_option_keyword(&name, &params, l),
            "DAMPING" => self.damping_keyword(&params, l, warnings),
            "SOLID SECTION" => self.section_keyword(&params, l),
            "ORIENTATION" => self.orientation_keyword(&params, l),
            "RIGID BODY" => self.rigid_body_keyword(&params, l),
            "TIE" => self.tie_keyword(&params, l),
            "BEAM SECTION" | "BEAM GENERAL SECTION" => {
                let elset = params
                    .get("ELSET")
                    .ok_or_else(|| err(l, format!("*{name} without ELSET=")))?;
                let density = match params.get("DENSITY") {
                    Some(d) => Some(
                        parse_f64(d)
                            .ok_or_else(|| err(l, format!("DENSITY={d:?} is not a number")))?,
                    ),
                    None => None,
                };
                // Abaqus' LUMPED: NO is the consistent mass of a cubic deflection and a quadratic
                // rotation, femu's; YES (Abaqus' default for B31) a lumped mass femu cannot match
                let lumped_stated = match params.get("LUMPED") {
                    None => false,
                    Some(v) if v.eq_ignore_ascii_case("NO") => true,
                    Some(v) if v.eq_ignore_ascii_case("YES") => {
                        return Err(err(
                            l,
                            format!(
                                "*{name}, LUMPED=YES is not read: Abaqus' lumped mass of linear Timoshenko beams, whose rotary terms femu does not know; LUMPED=NO (the consistent mass of a cubic deflection and a quadratic rotation, which femu builds) or no LUMPED (femu then builds that consistent mass, as CalculiX does)"
                            ),
                        ));
                    }
                    Some(v) => return Err(err(l, format!("LUMPED={v}: YES or NO"))),
                };
                self.structural.sections.push(structural::BeamSectionCard {
                    elset: elset.to_ascii_uppercase(),
                    material: params.get("MATERIAL").map(|m| m.to_ascii_uppercase()),
                    section: params
                        .get("SECTION")
                        .map(|s| s.to_ascii_uppercase())
                        .unwrap_or_default(),
                    general: {
                        if name == "BEAM GENERAL SECTION" {
                            warn(
                                warnings,
                                l,
                                "*BEAM GENERAL SECTION: the shear area of its B31 and B32 elements is taken as A (shear factor 1); femu's *BEAM SECTION shapes use 5/6 (RECT), 0.9 (CIRC), 1/2 (PIPE)".into(),
                            );
                        }
                        name == "BEAM GENERAL SECTION"
                    },
                    density,
                    lumped_stated,
                    lines: Vec::new(),
                    line: at(l),
                });
                Ok(())
            }
            "SHELL SECTION" | "SHELL GENERAL SECTION" => {
                let elset = params
                    .get("ELSET")
                    .ok_or_else(|| err(l, format!("*{name} without ELSET=")))?;
                if name == "SHELL GENERAL SECTION" && !params.contains_key("MATERIAL") {
                    return Err(err(
                        l,
                        "*SHELL GENERAL SECTION without MATERIAL= gives the section's stiffness matrix, which femu does not read (give the material)".into(),
                    ));
                }
                let composite = params.contains_key("COMPOSITE");
                let material = match params.get("MATERIAL") {
                    Some(m) => m.clone(),
                    None if composite => String::new(),
                    None => return Err(err(l, "*SHELL SECTION without MATERIAL=".into())),
                };
                // OFFSET: the nodes' surface from the midsurface, a fraction of the thickness
                // along the normal (SPOS the top surface, SNEG the bottom one)
                let offset = match params.get("OFFSET").map(|o| o.to_ascii_uppercase()) {
                    None => 0.0,
                    Some(o) => match o.as_str() {
                        "MIDSURFACE" => 0.0,
                        "SPOS" => 0.5,
                        "SNEG" => -0.5,
                        _ => o.parse::<f64>().ok().filter(|v| v.is_finite()).ok_or_else(|| {
                            err(
                                l,
                                format!(
                                    "*SHELL SECTION, OFFSET={o}: a fraction of the thickness, SPOS, SNEG or MIDSURFACE"
                                ),
                            )
                        })?,
                    },
                };
                self.structural
                    .shell_sections
                    .push(structural::ShellSectionCard {
                        elset: elset.to_ascii_uppercase(),
                        material: material.to_ascii_uppercase(),
                        offset,
                        composite,
                        symmetric: params.contains_key("SYMMETRIC"),
                        membrane: false,
                        orientation: params.get("ORIENTATION").map(|o| o.to_ascii_uppercase()),
                        lines: Vec::new(),
                        line: at(l),
                    });
                Ok(())
            }
            "MEMBRANE SECTION" => {
                let elset = params
                    .get("ELSET")
                    .ok_or_else(|| err(l, "*MEMBRANE SECTION without ELSET=".into()))?;
                let material = params
                    .get("MATERIAL")
                    .ok_or_else(|| err(l, "*MEMBRANE SECTION without MATERIAL=".into()))?;
                // POISSON sets the thickness change under large strain: no effect on K or M
                self.structural
                    .shell_sections
                    .push(structural::ShellSectionCard {
                        elset: elset.to_ascii_uppercase(),
                        material: material.to_ascii_uppercase(),
                        offset: 0.0,
                        composite: false,
                        symmetric: false,
                        membrane: true,
                        orientation: params.get("ORIENTATION").map(|o| o.to_ascii_uppercase()),
                        lines: Vec::new(),
                        line: at(l),
                    });
                Ok(())
            }
            "SPRING" | "DASHPOT" => {
                let elset = params
                    .get("ELSET")
                    .ok_or_else(|| err(l, format!("*{name} without ELSET=")))?;
                self.structural.springs.push(structural::SpringCard {
                    elset: elset.to_ascii_uppercase(),
                    dashpot: name == "DASHPOT",
                    lines: Vec::new(),
                    line: at(l),
                });
                Ok(())
            }
            "BOUNDARY" => {
                self.boundary_keyword(&params, l, warnings);
                Ok(())
            }
            _ => Ok(()), // HEADING, STEP, FREQUENCY, INCLUDE: nothing to do at the keyword
        }
    }

    fn coupling_keyword(
        &mut self,
        name: &str,
        params: &HashMap<String, String>,
        l: &Line,
    ) -> Result<(), IoError> {
        let reference = params
            .get("REF NODE")
            .filter(|v| !v.is_empty())
            .ok_or_else(|| err(l, format!("*{name} needs REF NODE=<node id or node set>")))?;
        // a node set's one node is found once the sets are known (`reference_sets`)
        let set = reference
            .parse::<u64>()
            .is_err()
            .then(|| reference.to_ascii_uppercase());
        let reference = reference.parse::<u64>().unwrap_or(0);
        self.coupling_now = None;
        if name == "COUPLING" {
            let surface = params
                .get("SURFACE")
                .ok_or_else(|| err(l, "*COUPLING needs SURFACE=<node-based surface>".into()))?;
            self.coupling_now = Some((reference, surface.to_ascii_uppercase(), set));
        }
        Ok(())
    }

    fn coupling_method_keyword(
        &mut self,
        name: &str,
        params: &HashMap<String, String>,
        l: &Line,
    ) -> Result<(), IoError> {
        let (reference, surface, set) = self
            .coupling_now
            .clone()
            .ok_or_else(|| err(l, format!("*{name} without a *COUPLING before it")))?;
        if name == "DISTRIBUTING"
            && params
                .get("WEIGHTING METHOD")
                .is_some_and(|w| !w.eq_ignore_ascii_case("UNIFORM"))
        {
            return Err(err(
                l,
                "*DISTRIBUTING: femu weights by the surface's node weights (WEIGHTING METHOD=UNIFORM)".into(),
            ));
        }
        let nodes = LinkNodes::Surface(surface);
        self.note_reference_set(set.as_deref(), l);
        let kind = if name == "KINEMATIC" {
            LinkKind::Kinematic {
                reference,
                nodes,
                dofs: Vec::new(),
            }
        } else {
            LinkKind::Distributing {
                reference,
                nodes,
                dofs: Vec::new(),
            }
        };
        self.links.push(InpLink { kind, line: at(l) });
        Ok(())
    }

    fn surface_keyword(
        &mut self,
        params: &HashMap<String, String>,
        l: &Line,
        warnings: &mut Vec<Warning>,
    ) -> Result<(), IoError> {
        let ty = params.get("TYPE").map(|t| t.to_ascii_uppercase());
        let name = params
            .get("NAME")
            .ok_or_else(|| err(l, "*SURFACE without NAME=".into()))?
            .to_ascii_uppercase();
        self.surface_now = None;
        self.element_surface_now = None;
        if ty.as_deref() != Some("NODE") {
            // an element-based surface: faces of elements (a *TIE's master); it carries loads
            // and contact otherwise, no stiffness or mass
            if ty.as_deref().is_some_and(|t| t != "ELEMENT") {
                warn(
                    warnings,
                    l,
                    format!(
                        "*SURFACE, TYPE={}, NAME={name} read past: it changes no stiffness or mass",
                        ty.unwrap_or_default()
                    ),
                );
                return Ok(());
            }
            self.element_surfaces.entry(name.clone()).or_default();
            self.element_surface_now = Some(name);
            return Ok(());
        }
        self.surfaces.entry(name.clone()).or_default();
        self.surface_now = Some(name);
        Ok(())
    }

    fn node_keyword(&mut self, params: &HashMap<String, String>, l: &Line) -> Result<(), IoError> {
        node_system(params).map_err(|reason| err(l, reason))?;
        if let Some(s) = params.get("NSET") {
            self.node_set_of_block
                .push((s.to_ascii_uppercase(), Vec::new()));
        }
        Ok(())
    }

    /// `*ELEMENT, TYPE=MASS`: one-node mass elements, whose mass comes from the `*MASS` of their
    /// set.
    fn mass_element_keyword(
        &mut self,
        params: &HashMap<String, String>,
        l: &Line,
    ) -> Result<(), IoError> {
        let set = params
            .get("ELSET")
            .map(|s| s.to_ascii_uppercase())
            .ok_or_else(|| {
                err(
                    l,
                    "*ELEMENT, TYPE=MASS needs ELSET= (the set its *MASS names)".into(),
                )
            })?;
        // one-node elements: MASS (a *MASS gives their mass) or ROTARYI (a *ROTARY INERTIA
        // their inertia)
        if params
            .get("TYPE")
            .is_some_and(|t| t.eq_ignore_ascii_case("ROTARYI"))
        {
            self.rotary_sets.entry(set.clone()).or_default();
            self.rotary_block = true;
        } else {
            self.mass_sets.entry(set.clone()).or_default();
        }
        self.mass_block = Some(set);
        Ok(())
    }

    fn mass_keyword(&mut self, params: &HashMap<String, String>, l: &Line) -> Result<(), IoError> {
        let set = params
            .get("ELSET")
            .ok_or_else(|| err(l, "*MASS without ELSET=".into()))?;
        self.mass_cards.push(MassCard {
            elset: set.to_ascii_uppercase(),
            mass: f64::NAN,
            line: at(l),
        });
        Ok(())
    }

    fn element_keyword(
        &mut self,
        params: &HashMap<String, String>,
        l: &Line,
        warnings: &mut Vec<Warning>,
    ) -> Result<(), IoError> {
        let ty = params
            .get("TYPE")
            .ok_or_else(|| err(l, "*ELEMENT without TYPE=".into()))?;
        if let Some(st) = structural::StructuralType::of(ty).map_err(|r| err(l, r))? {
            self.structural_now = Some(st);
            if let Some(s) = params.get("ELSET") {
                self.elem_set_of_block
                    .push((s.to_ascii_uppercase(), Vec::new()));
            }
            return Ok(());
        }
        let (kind, formulation, approx) = element_kind(ty).ok_or_else(|| {
            err(l, format!("element type {ty} is not supported (C3D4, C3D10, C3D8, C3D8I, C3D20, C3D6, C3D15, C3D8R, C3D20R, MASS, ROTARYI; T3D2, B31, B32, B32R, B33, SPRING1, SPRING2, SPRINGA, DASHPOT1, DASHPOT2, DASHPOTA; S4, S4R, S3, S3R, S6, STRI65, S8R, S8; M3D3, M3D4, M3D4R, M3D6, M3D8, M3D8R)"))
        })?;
        if approx {
            warn(
                warnings,
                l,
                format!("{ty} read as {} with full integration", kind.abaqus_name()),
            );
        }
        self.element_kind_now = Some((kind, formulation, kind.num_nodes()));
        if let Some(s) = params.get("ELSET") {
            self.elem_set_of_block
                .push((s.to_ascii_uppercase(), Vec::new()));
        }
        Ok(())
    }

    fn set_keyword(
        &mut self,
        name: &str,
        params: &HashMap<String, String>,
        l: &Line,
        li: usize,
    ) -> Result<(), IoError> {
        let set = params
            .get(name)
            .ok_or_else(|| err(l, format!("*{name} without {name}=")))?;
        self.sets.push(SetBlock {
            name: set.to_ascii_uppercase(),
            is_node: name == "NSET",
            tokens: Vec::new(),
            generate: params.contains_key("GENERATE"),
            line: li,
        });
        Ok(())
    }

    fn material_keyword(
        &mut self,
        params: &HashMap<String, String>,
        l: &Line,
    ) -> Result<(), IoError> {
        self.finish_material()?;
        let name = params
            .get("NAME")
            .ok_or_else(|| err(l, "*MATERIAL without NAME=".into()))?;
        self.pending = Some(PendingMaterial {
            name: name.to_ascii_uppercase(),
            line: l.number,
            path: l.path.clone(),
            ..Default::default()
        });
        Ok(())
    }

    /// `*DAMPING`: in a `*MATERIAL`, `STRUCTURAL=s` is the structural damping coefficient of its
    /// elements (Abaqus' material damping, CalculiX's too: `i s K_e` in a frequency response) and
    /// `ALPHA`, `BETA` their Rayleigh damping `alpha M_e + beta K_e` (Abaqus'); outside a material
    /// (CalculiX's Rayleigh damping of a `*DYNAMIC` step) they are not read, with a warning.
    fn damping_keyword(
        &mut self,
        params: &HashMap<String, String>,
        l: &Line,
        warnings: &mut Vec<Warning>,
    ) -> Result<(), IoError> {
        if let Some(v) = params.get("STRUCTURAL") {
            let Some(p) = self.pending.as_mut() else {
                return Err(err(
                    l,
                    "*DAMPING, STRUCTURAL= outside a *MATERIAL: structural damping is a material's"
                        .into(),
                ));
            };
            let ge = parse_f64(v)
                .filter(|g| g.is_finite() && *g >= 0.0)
                .ok_or_else(|| {
                    err(
                        l,
                        format!(
                            "STRUCTURAL={v:?}: a structural damping coefficient is a number of at least 0"
                        ),
                    )
                })?;
            p.structural = Some(ge);
        }
        if params.contains_key("COMPOSITE") {
            warn(
                warnings,
                l,
                "*DAMPING, COMPOSITE= not read: the modal damping of composite modal dynamics; femu frf takes a loss factor, Rayleigh or modal damping ratios from its options".into(),
            );
        }
        let rayleigh: Vec<&str> = ["ALPHA", "BETA"]
            .into_iter()
            .filter(|k| params.contains_key(*k))
            .collect();
        if let Some(p) = self.pending.as_mut() {
            for key in &rayleigh {
                let v = &params[*key];
                let value = parse_f64(v)
                    .filter(|x| x.is_finite() && *x >= 0.0)
                    .ok_or_else(|| {
                        err(
                            l,
                            format!("{key}={v:?}: a Rayleigh damping coefficient is a number of at least 0"),
                        )
                    })?;
                if *key == "ALPHA" {
                    p.alpha = Some(value);
                } else {
                    p.beta = Some(value);
                }
            }
        } else if !rayleigh.is_empty() {
            warn(
                warnings,
                l,
                format!(
                    "*DAMPING {} outside a *MATERIAL not read: the Rayleigh damping of a dynamic step (CalculiX's *DYNAMIC); femu frf takes Rayleigh damping of the model from --rayleigh or *MODAL DAMPING, RAYLEIGH, and of a material from its *DAMPING",
                    rayleigh.join(", ")
                ),
            );
        }
        Ok(())
    }

    fn material_option_keyword(
        &mut self,
        name: &str,
        params: &HashMap<String, String>,
        l: &Line,
    ) -> Result<(), IoError> {
        if self.pending.is_none() {
            return Err(err(l, format!("*{name} outside a *MATERIAL")));
        }
        if name == "ELASTIC"
            && params
                .get("TYPE")
                .is_some_and(|ty| ty.eq_ignore_ascii_case("LAMINA"))
        {
            if let Some(p) = self.pending.as_mut() {
                p.lamina_type = true;
            }
            return Ok(());
        }
        let unsupported = params
            .get("TYPE")
            .filter(|ty| !ty.eq_ignore_ascii_case("ISOTROPIC") && !ty.eq_ignore_ascii_case("ISO"));
        if let (true, Some(ty)) = (name == "ELASTIC", unsupported) {
            // CalculiX spells ORTHO and ANISO
            let aniso = match ty.to_ascii_uppercase().as_str() {
                "ENGINEERING CONSTANTS" => AnisoType::EngineeringConstants,
                "ORTHOTROPIC" | "ORTHO" => AnisoType::Orthotropic,
                "ANISOTROPIC" | "ANISO" => AnisoType::Anisotropic,
                _ => {
                    return Err(err(
                        l,
                        format!(
                            "*ELASTIC, TYPE={ty} is not read (ISOTROPIC, ENGINEERING CONSTANTS, ORTHOTROPIC, ANISOTROPIC, and LAMINA for shells, are)"
                        ),
                    ));
                }
            };
            if let Some(p) = self.pending.as_mut()
                && p.aniso.is_none()
                && p.young.is_none()
            {
                p.aniso = Some(aniso);
                p.aniso_line = l.number;
            }
        }
        Ok(())
    }

    /// `*RIGID BODY, REF NODE=`: the nodes of its `ELSET`'s elements and of its `TIE NSET`
    /// (CalculiX's `NSET`) follow the reference node rigidly (all their DOFs, a kinematic
    /// coupling's), those of its `PIN NSET` in their translations alone (Abaqus's rigid body of
    /// deformable elements; docs/MATH.md, "Multipoint constraints").
    fn rigid_body_keyword(
        &mut self,
        params: &HashMap<String, String>,
        l: &Line,
    ) -> Result<(), IoError> {
        let reference = params
            .get("REF NODE")
            .filter(|v| !v.is_empty())
            .ok_or_else(|| err(l, "*RIGID BODY needs REF NODE=<node id or node set>".into()))?;
        if let Some(p) = params
            .get("POSITION")
            .filter(|p| !p.eq_ignore_ascii_case("INPUT"))
        {
            return Err(err(
                l,
                format!(
                    "*RIGID BODY, POSITION={p}: femu keeps the reference node where the deck puts it (POSITION=INPUT)"
                ),
            ));
        }
        if let Some(r) = params.get("ROT NODE") {
            return Err(err(
                l,
                format!(
                    "*RIGID BODY, ROT NODE={r}: femu gives the reference node its rotations (DOFs 4-6) instead of CalculiX's rotational node; fix or load them on the reference node"
                ),
            ));
        }
        let set = reference
            .parse::<u64>()
            .is_err()
            .then_some(reference.as_str());
        let id = reference.parse::<u64>().unwrap_or(0);
        let mut any = false;
        // CalculiX spells TIE NSET as NSET
        for (key, dofs) in [
            ("ELSET", Vec::new()),
            ("TIE NSET", Vec::new()),
            ("NSET", Vec::new()),
            ("PIN NSET", vec![1, 2, 3]),
        ] {
            let Some(name) = params.get(key).filter(|v| !v.is_empty()) else {
                continue;
            };
            let name = name.to_ascii_uppercase();
            let nodes = if key == "ELSET" {
                LinkNodes::Elements(name)
            } else {
                LinkNodes::Targets(vec![Target::Set(name)])
            };
            self.note_reference_set(set, l);
            self.links.push(InpLink {
                kind: LinkKind::Kinematic {
                    reference: id,
                    nodes,
                    dofs,
                },
                line: at(l),
            });
            any = true;
        }
        if !any {
            return Err(err(
                l,
                "*RIGID BODY without ELSET, TIE NSET or PIN NSET: it holds nothing".into(),
            ));
        }
        Ok(())
    }

    /// `*TIE`: its data line names the slave and the master surface; the slave's nodes follow
    /// the master's faces (docs/MATH.md, "Multipoint constraints").
    fn tie_keyword(&mut self, params: &HashMap<String, String>, l: &Line) -> Result<(), IoError> {
        let tolerance = match params.get("POSITION TOLERANCE") {
            None => None,
            Some(v) => Some(
                parse_f64(v)
                    .filter(|t| t.is_finite() && *t >= 0.0)
                    .ok_or_else(|| {
                        err(
                            l,
                            format!("*TIE, POSITION TOLERANCE={v}: a distance of 0 or more"),
                        )
                    })?,
            ),
        };
        if let Some(t) = params.get("TYPE").filter(|t| {
            !t.eq_ignore_ascii_case("SURFACE TO SURFACE")
                && !t.eq_ignore_ascii_case("NODE TO SURFACE")
        }) {
            return Err(err(
                l,
                format!("*TIE, TYPE={t}: SURFACE TO SURFACE or NODE TO SURFACE"),
            ));
        }
        self.ties.push(Tie {
            name: params.get("NAME").cloned().unwrap_or_default(),
            slave: String::new(),
            master: String::new(),
            tolerance,
            adjust: !params
                .get("ADJUST")
                .is_some_and(|a| a.eq_ignore_ascii_case("NO")),
            line: at(l),
        });
        Ok(())
    }

    /// `*ORIENTATION, NAME=`: a rectangular or cylindrical frame of coordinates, nodes or the
    /// element's own nodes (its data lines follow).
    fn orientation_keyword(
        &mut self,
        params: &HashMap<String, String>,
        l: &Line,
    ) -> Result<(), IoError> {
        let name = params
            .get("NAME")
            .ok_or_else(|| err(l, "*ORIENTATION without NAME=".into()))?
            .to_ascii_uppercase();
        if let Some(first) = self.orientations.iter().find(|o| o.name == name) {
            return Err(err(
                l,
                format!(
                    "*ORIENTATION, NAME={name} is defined twice (first on line {})",
                    first.line.line
                ),
            ));
        }
        let system = match params
            .get("SYSTEM")
            .map(|s| s.to_ascii_uppercase())
            .as_deref()
        {
            None | Some("RECTANGULAR") => orientation::System::Rectangular,
            Some("CYLINDRICAL") => orientation::System::Cylindrical,
            Some(s) => {
                return Err(err(
                    l,
                    format!(
                        "*ORIENTATION, SYSTEM={s} is not read (RECTANGULAR and CYLINDRICAL are)"
                    ),
                ));
            }
        };
        let definition = match params
            .get("DEFINITION")
            .map(|s| s.to_ascii_uppercase())
            .as_deref()
        {
            None | Some("COORDINATES") => orientation::Definition::Coordinates,
            Some("NODES") => orientation::Definition::Nodes,
            Some("OFFSET TO NODES") => orientation::Definition::OffsetToNodes,
            Some(s) => {
                return Err(err(
                    l,
                    format!(
                        "*ORIENTATION, DEFINITION={s} is not read (COORDINATES, NODES and OFFSET TO NODES are)"
                    ),
                ));
            }
        };
        self.orientations.push(orientation::OrientationCard {
            name,
            system,
            definition,
            lines: Vec::new(),
            line: at(l),
        });
        Ok(())
    }

    fn section_keyword(
        &mut self,
        params: &HashMap<String, String>,
        l: &Line,
    ) -> Result<(), IoError> {
        let elset = params
            .get("ELSET")
            .ok_or_else(|| err(l, "*SOLID SECTION without ELSET=".into()))?;
        let material = params
            .get("MATERIAL")
            .ok_or_else(|| err(l, "*SOLID SECTION without MATERIAL=".into()))?;
        self.sections.push(Section {
            elset: elset.to_ascii_uppercase(),
            material: material.to_ascii_uppercase(),
            area: None,
            orientation: params.get("ORIENTATION").map(|o| o.to_ascii_uppercase()),
            line: at(l),
        });
        Ok(())
    }

    fn boundary_keyword(
        &mut self,
        params: &HashMap<String, String>,
        l: &Line,
        warnings: &mut Vec<Warning>,
    ) {
        if params
            .get("OP")
            .is_some_and(|v| v.eq_ignore_ascii_case("NEW"))
        {
            // OP=NEW removes every boundary condition defined before it
            self.boundaries.clear();
        }
        if params.contains_key("TYPE") || params.contains_key("AMPLITUDE") {
            warn(
                warnings,
                l,
                "*BOUNDARY options ignored (homogeneous constraints only)".into(),
            );
        }
    }

    /// A data line of the current block.
    fn data(
        &mut self,
        lines: &[Line],
        li: usize,
        t: &str,
        warnings: &mut Vec<Warning>,
    ) -> Result<(), IoError> {
        let l = &lines[li];
        let f = fields(t);
        match self.block.as_str() {
            "NODE" => self.node_line(&f, l, li, t),
            "ELEMENT" if self.mass_block.is_some() => self.mass_element_line(&f, l, li, t),
            "ELEMENT" if self.structural_now.is_some() => self.structural_line(&f, l, t),
            "ELEMENT" => self.element_line(&f, lines, li),
            "BEAM SECTION" | "BEAM GENERAL SECTION" => {
                if let Some(c) = self.structural.sections.last_mut() {
                    c.lines.push(f.iter().map(|s| s.to_string()).collect());
                }
                Ok(())
            }
            "SOLID SECTION" => {
                // the first data line's first field: a truss's area
                if let Some(s) = self.sections.last_mut()
                    && s.area.is_none()
                {
                    s.area = Some(f.first().map_or(String::new(), |v| v.to_string()));
                }
                Ok(())
            }
            "TIE" => {
                let tie = self.ties.last_mut().expect("read at the keyword");
                if !tie.slave.is_empty() {
                    return Err(err(
                        l,
                        "*TIE takes one data line (its slave and master surfaces)".into(),
                    ));
                }
                match f[..] {
                    [slave, master, ..] if !slave.is_empty() && !master.is_empty() => {
                        tie.slave = slave.to_ascii_uppercase();
                        tie.master = master.to_ascii_uppercase();
                        Ok(())
                    }
                    _ => Err(err(
                        l,
                        format!("*TIE needs its slave and master surfaces, got {t:?}"),
                    )),
                }
            }
            "ORIENTATION" => {
                if let Some(c) = self.orientations.last_mut() {
                    c.lines.push(f.iter().map(|s| s.to_string()).collect());
                }
                Ok(())
            }
            "SHELL SECTION" | "SHELL GENERAL SECTION" | "MEMBRANE SECTION" => {
                if let Some(c) = self.structural.shell_sections.last_mut() {
                    c.lines.push(f.iter().map(|s| s.to_string()).collect());
                }
                Ok(())
            }
            "SPRING" | "DASHPOT" => {
                if let Some(c) = self.structural.springs.last_mut() {
                    c.lines.push(f.iter().map(|s| s.to_string()).collect());
                }
                Ok(())
            }
            "MASS" => self.mass_line(&f, l, t),
            "NONSTRUCTURAL MASS" => {
                let card = self.nonstructural.last_mut().expect("set with the keyword");
                if card.value.is_none() {
                    card.value = Some(
                        f.first()
                            .and_then(|s| parse_f64(s))
                            .filter(|v| v.is_finite() && *v >= 0.0)
                            .ok_or_else(|| {
                                err(
                                    l,
                                    format!(
                                        "*NONSTRUCTURAL MASS needs a mass of 0 or more, got {t:?}"
                                    ),
                                )
                            })?,
                    );
                }
                Ok(())
            }
            "ROTARY INERTIA" => {
                let card = self.rotary_cards.last_mut().expect("set with the keyword");
                if card.1.is_none() {
                    if f.len() < 3 {
                        return Err(err(
                            l,
                            format!(
                                "*ROTARY INERTIA needs I11, I22, I33 (and I12, I13, I23), got {t:?}"
                            ),
                        ));
                    }
                    let mut v = [0.0; 6];
                    for (k, s) in f.iter().take(6).enumerate() {
                        if s.is_empty() {
                            continue;
                        }
                        v[k] = parse_f64(s).filter(|x| x.is_finite()).ok_or_else(|| {
                            err(l, format!("*ROTARY INERTIA: {s:?} is not a number"))
                        })?;
                    }
                    card.1 = Some(v);
                }
                Ok(())
            }
            "NSET" | "ELSET" => {
                let last = self.sets.last_mut().expect("set with the keyword");
                last.tokens.extend(f.iter().map(|s| s.to_string()));
                Ok(())
            }
            "ELASTIC" => self.elastic_line(&f, l, warnings),
            "DENSITY" => self.density_line(&f, l, t),
            "BOUNDARY" => self.boundary_line(&f, l, t, warnings),
            "FREQUENCY" if self.frequency.is_none() => self.frequency_line(&f, l, t),
            "MODAL DAMPING" => self.modal_damping_line(&f, l, t),
            "EQUATION" => self.equation_line(&f, l, t),
            "KINEMATIC COUPLING" => self.kinematic_coupling_line(&f, l),
            "KINEMATIC" | "DISTRIBUTING" => {
                let more = dof_range(f.first().copied(), f.get(1).copied())
                    .map_err(|reason| err(l, format!("*{}: {reason}", self.block)))?;
                if let Some(InpLink {
                    kind: LinkKind::Kinematic { dofs, .. } | LinkKind::Distributing { dofs, .. },
                    ..
                }) = self.links.last_mut()
                {
                    dofs.extend(more);
                }
                Ok(())
            }
            "SURFACE" => self.surface_line(&f, l),
            _ => Ok(()), // data of a keyword with none to read, or of an ignored one
        }
    }

    fn node_line(&mut self, f: &[&str], l: &Line, li: usize, t: &str) -> Result<(), IoError> {
        if f.len() < 3 {
            return Err(err(
                l,
                format!("a node needs an id and coordinates, got {t:?}"),
            ));
        }
        let id = f[0]
            .parse::<u64>()
            .map_err(|_| err(l, format!("node id {:?} is not a positive integer", f[0])))?;
        let mut x = [0.0; 3];
        for (c, s) in f[1..f.len().min(4)].iter().enumerate() {
            x[c] = parse_f64(s).ok_or_else(|| {
                err(
                    l,
                    format!("coordinate {s:?} of node {id} is not a finite number"),
                )
            })?;
        }
        if node_system(&self.block_params) == Ok(true) {
            x = cylindrical(x);
        }
        self.nodes.push((id, x, li));
        if let Some(last) = self
            .node_set_of_block
            .last_mut()
            .filter(|_| self.block_params.contains_key("NSET"))
        {
            last.1.push(id);
        }
        Ok(())
    }

    fn mass_element_line(
        &mut self,
        f: &[&str],
        l: &Line,
        li: usize,
        t: &str,
    ) -> Result<(), IoError> {
        let set = self.mass_block.as_ref().expect("checked");
        let malformed = || {
            err(
                l,
                format!("a MASS element line is an id and a node, got {t:?}"),
            )
        };
        let ids: Vec<u64> = f
            .iter()
            .filter(|s| !s.is_empty())
            .map(|s| s.parse::<u64>())
            .collect::<Result<_, _>>()
            .map_err(|_| malformed())?;
        let [id, node] = ids[..] else {
            return Err(malformed());
        };
        self.mass_elements.push((id, node, li));
        let sets = if self.rotary_block {
            &mut self.rotary_sets
        } else {
            &mut self.mass_sets
        };
        sets.get_mut(set).expect("created with the block").push(id);
        Ok(())
    }

    fn mass_line(&mut self, f: &[&str], l: &Line, t: &str) -> Result<(), IoError> {
        let card = self.mass_cards.last_mut().expect("set with the keyword");
        if card.mass.is_nan() {
            card.mass = f
                .first()
                .and_then(|s| parse_f64(s))
                .filter(|m| *m > 0.0)
                .ok_or_else(|| err(l, format!("*MASS needs a positive mass, got {t:?}")))?;
        }
        Ok(())
    }

    /// A beam's, spring's or shell's line: its id and nodes (a line that ends in a comma
    /// continues on the next, as Abaqus writes elements of many nodes).
    fn structural_line(&mut self, f: &[&str], l: &Line, t: &str) -> Result<(), IoError> {
        let (ty, nn) = self.structural_now.expect("checked");
        let more: Vec<u64> = f
            .iter()
            .filter(|s| !s.is_empty())
            .map(|s| s.parse::<u64>())
            .collect::<Result<_, _>>()
            .map_err(|_| err(l, format!("element line has a non-integer entry: {t:?}")))?;
        let (mut ids, start) = self
            .structural_buffer
            .take()
            .unwrap_or_else(|| (Vec::new(), l.clone()));
        ids.extend(more);
        if ids.len() < nn + 1 && t.trim_end().ends_with(',') {
            self.structural_buffer = Some((ids, start));
            return Ok(());
        }
        let l = &start;
        if ids.len() != nn + 1 {
            return Err(err(
                l,
                format!(
                    "a {} element is an id and {nn} nodes, got {}",
                    ty.name(),
                    ids.len()
                ),
            ));
        }
        self.structural
            .elements
            .push((ids[0], ty, ids[1..].to_vec(), at(l)));
        if let Some(last) = self
            .elem_set_of_block
            .last_mut()
            .filter(|_| self.block_params.contains_key("ELSET"))
        {
            last.1.push(ids[0]);
        }
        Ok(())
    }

    /// An element's line; an element may continue on the lines after it.
    fn element_line(&mut self, f: &[&str], lines: &[Line], li: usize) -> Result<(), IoError> {
        let (kind, formulation, nn) = self.element_kind_now.expect("set with the keyword");
        if self.element_buffer.is_empty() {
            self.element_start = li;
        }
        self.element_buffer.extend(f.iter().map(|s| s.to_string()));
        if self.element_buffer.len() < nn + 1 {
            return Ok(()); // continued on the next line
        }
        let start = &lines[self.element_start];
        if self.element_buffer.len() > nn + 1 {
            return Err(err(
                start,
                format!(
                    "{} needs {nn} nodes, got {}",
                    kind.abaqus_name(),
                    self.element_buffer.len() - 1
                ),
            ));
        }
        let ids: Result<Vec<u64>, _> = self
            .element_buffer
            .iter()
            .map(|s| s.parse::<u64>())
            .collect();
        let ids = ids.map_err(|_| {
            err(
                start,
                format!(
                    "element line has a non-integer entry: {:?}",
                    self.element_buffer
                ),
            )
        })?;
        self.elements
            .push((ids[0], kind, ids[1..].to_vec(), self.element_start));
        if formulation == Formulation::IncompatibleModes {
            self.incompatible_modes.push(ids[0]);
        }
        if let Some(last) = self
            .elem_set_of_block
            .last_mut()
            .filter(|_| self.block_params.contains_key("ELSET"))
        {
            last.1.push(ids[0]);
        }
        self.element_buffer.clear();
        Ok(())
    }

    fn elastic_line(
        &mut self,
        f: &[&str],
        l: &Line,
        warnings: &mut Vec<Warning>,
    ) -> Result<(), IoError> {
        let p = self.pending.as_mut().expect("checked at the keyword");
        if let Some(ty) = p.aniso {
            // the constants run over the data lines, eight to a line; a line after they are
            // complete is another temperature's
            if p.aniso_values.len() >= ty.count() {
                warn(
                    warnings,
                    l,
                    "temperature-dependent elasticity: the first set of constants is used".into(),
                );
                return Ok(());
            }
            for s in f {
                if p.aniso_values.len() == ty.count() {
                    break;
                }
                let v = parse_f64(s).ok_or_else(|| {
                    err(
                        l,
                        format!(
                            "*ELASTIC, TYPE={}: constant {} = {s:?} is not a number",
                            ty.name(),
                            p.aniso_values.len() + 1
                        ),
                    )
                })?;
                p.aniso_values.push(v);
            }
            return Ok(());
        }
        if p.lamina_type {
            if f.len() < 6 {
                return Err(err(
                    l,
                    format!(
                        "*ELASTIC, TYPE=LAMINA needs E1, E2, NU12, G12, G13, G23, got {} values",
                        f.len()
                    ),
                ));
            }
            let mut v = [0.0; 6];
            for (k, name) in ["E1", "E2", "NU12", "G12", "G13", "G23"].iter().enumerate() {
                v[k] = parse_f64(f[k])
                    .ok_or_else(|| err(l, format!("{name} = {:?} is not a number", f[k])))?;
            }
            if f.len() > 6 {
                warn(
                    warnings,
                    l,
                    "temperature-dependent elasticity: the first line is used".into(),
                );
            }
            if p.lamina.is_none() {
                p.lamina = Some(v);
            }
            return Ok(());
        }
        if f.len() < 2 {
            return Err(err(l, "*ELASTIC needs E and nu".into()));
        }
        let e = parse_f64(f[0]).ok_or_else(|| err(l, format!("E = {:?} is not a number", f[0])))?;
        let nu =
            parse_f64(f[1]).ok_or_else(|| err(l, format!("nu = {:?} is not a number", f[1])))?;
        if f.len() > 2 {
            warn(
                warnings,
                l,
                "temperature-dependent elasticity: the first line is used".into(),
            );
        }
        if p.young.is_none() {
            p.young = Some((e, nu));
        }
        Ok(())
    }

    fn density_line(&mut self, f: &[&str], l: &Line, t: &str) -> Result<(), IoError> {
        let p = self.pending.as_mut().expect("checked at the keyword");
        let rho = f
            .first()
            .and_then(|s| parse_f64(s))
            .ok_or_else(|| err(l, format!("density {t:?} is not a number")))?;
        if p.density.is_none() {
            p.density = Some(rho);
        }
        Ok(())
    }

    fn boundary_line(
        &mut self,
        f: &[&str],
        l: &Line,
        t: &str,
        warnings: &mut Vec<Warning>,
    ) -> Result<(), IoError> {
        if f.len() < 2 {
            return Err(err(
                l,
                format!("*BOUNDARY needs a node or set and a DOF, got {t:?}"),
            ));
        }
        let target = target(f[0]);
        // Abaqus's named boundary types (Keywords Reference, *BOUNDARY): the DOFs each fixes
        let named: Option<&[usize]> = match f[1].to_ascii_uppercase().as_str() {
            "ENCASTRE" => Some(&[1, 2, 3, 4, 5, 6]),
            "PINNED" => Some(&[1, 2, 3]),
            "XSYMM" => Some(&[1, 5, 6]),
            "YSYMM" => Some(&[2, 4, 6]),
            "ZSYMM" => Some(&[3, 4, 5]),
            "XASYMM" => Some(&[2, 3, 4]),
            "YASYMM" => Some(&[1, 3, 5]),
            "ZASYMM" => Some(&[1, 2, 6]),
            _ => None,
        };
        if let Some(dofs) = named {
            if dofs.iter().any(|d| *d > 3) && self.rotation_boundary.is_none() {
                self.rotation_boundary = Some(at(l));
            }
            for &d in dofs {
                self.boundaries.push(Boundary {
                    target: target.clone(),
                    first: d,
                    last: d,
                    line: at(l),
                });
            }
            return Ok(());
        }
        let first = f[1].parse::<usize>().map_err(|_| {
            err(
                l,
                format!(
                    "DOF {:?} is neither an integer nor a boundary type (ENCASTRE, PINNED, XSYMM, YSYMM, ZSYMM, XASYMM, YASYMM, ZASYMM)",
                    f[1]
                ),
            )
        })?;
        let last = match f.get(2) {
            Some(s) if !s.is_empty() => s
                .parse::<usize>()
                .map_err(|_| err(l, format!("DOF {s:?} is not an integer")))?,
            _ => first,
        };
        if let Some(v) = f.get(3).and_then(|s| parse_f64(s)).filter(|v| *v != 0.0) {
            warn(
                warnings,
                l,
                format!("prescribed value {v} read as 0 (femu's constraints are homogeneous)"),
            );
        }
        if first == 0 || last < first {
            return Err(err(l, format!("DOF range {first}..{last} is invalid")));
        }
        if last > 6 {
            warn(
                warnings,
                l,
                "DOFs above 6 (temperature, pressure) do not exist here: ignored".into(),
            );
        }
        if last > 3 && self.rotation_boundary.is_none() {
            // said at the end, when no beam or spring gave nodes rotations
            self.rotation_boundary = Some(at(l));
        }
        if first <= 6 {
            self.boundaries.push(Boundary {
                target,
                first,
                last: last.min(6),
                line: at(l),
            });
        }
        Ok(())
    }

    fn frequency_line(&mut self, f: &[&str], l: &Line, t: &str) -> Result<(), IoError> {
        let count = f
            .first()
            .and_then(|s| s.parse::<usize>().ok())
            .filter(|c| *c > 0)
            .ok_or_else(|| {
                err(
                    l,
                    format!("*FREQUENCY needs a positive number of eigenvalues, got {t:?}"),
                )
            })?;
        let shift_cycles2 = f.get(2).and_then(|s| parse_f64(s));
        self.frequency = Some(FrequencyStep {
            count,
            shift_cycles2,
        });
        Ok(())
    }

    /// A `*MODAL DAMPING` line (Abaqus and CalculiX): `first mode, last mode, value` (MODAL=DIRECT,
    /// the default: a fraction of critical damping, or a structural damping factor with
    /// `STRUCTURAL`), `frequency, value` with `DEFINITION=FREQUENCY RANGE` (Abaqus: linear between
    /// the frequencies, the nearest end's value outside them), or `, , alpha, beta` with
    /// `RAYLEIGH` (one line, for every mode). Composite modal damping, Rayleigh damping by
    /// frequency or by ranges of modes, and blocks by mode numbers beside blocks by frequency are
    /// refused.
    fn modal_damping_line(&mut self, f: &[&str], l: &Line, t: &str) -> Result<(), IoError> {
        let p = &self.block_params;
        let by_frequency = match p.get("DEFINITION") {
            None => false,
            Some(v) if v.eq_ignore_ascii_case("MODE NUMBERS") => false,
            Some(v) if v.eq_ignore_ascii_case("FREQUENCY RANGE") => true,
            Some(v) => {
                return Err(err(
                    l,
                    format!(
                        "*MODAL DAMPING, DEFINITION={v}: femu reads MODE NUMBERS or FREQUENCY RANGE"
                    ),
                ));
            }
        };
        match &self.modal_by_mode {
            Some((mode, first)) if *mode == by_frequency => {
                return Err(err(
                    l,
                    format!(
                        "*MODAL DAMPING: damping by {} here and by {} at {}:{}: give one definition",
                        if by_frequency {
                            "frequency range"
                        } else {
                            "mode numbers"
                        },
                        if by_frequency {
                            "mode numbers"
                        } else {
                            "frequency range"
                        },
                        first.path.display(),
                        first.line
                    ),
                ));
            }
            Some(_) => {}
            None => self.modal_by_mode = Some((!by_frequency, at(l))),
        }
        if let Some(v) = p
            .get("VISCOUS")
            .filter(|v| !v.eq_ignore_ascii_case("FRACTION OF CRITICAL DAMPING"))
        {
            return Err(err(
                l,
                format!(
                    "*MODAL DAMPING, VISCOUS={v}: femu reads direct modal damping (VISCOUS=FRACTION OF CRITICAL DAMPING)"
                ),
            ));
        }
        if let Some(v) = p.get("MODAL").filter(|v| !v.eq_ignore_ascii_case("DIRECT")) {
            return Err(err(
                l,
                format!(
                    "*MODAL DAMPING, MODAL={v}: femu reads direct modal damping (MODAL=DIRECT)"
                ),
            ));
        }
        let number = |i: usize, what: &str| -> Result<f64, IoError> {
            let v = f.get(i).copied().unwrap_or("");
            if v.is_empty() {
                return Ok(0.0);
            }
            parse_f64(v)
                .filter(|x| x.is_finite() && *x >= 0.0)
                .ok_or_else(|| {
                    err(
                        l,
                        format!(
                            "*MODAL DAMPING: {what} {v:?} is not a number of at least 0 ({t:?})"
                        ),
                    )
                })
        };
        let structural = p.contains_key("STRUCTURAL");
        if p.contains_key("RAYLEIGH") {
            if structural {
                return Err(err(
                    l,
                    "*MODAL DAMPING: RAYLEIGH and STRUCTURAL on one block (give Rayleigh damping or structural damping factors per mode)".into(),
                ));
            }
            if by_frequency {
                return Err(err(
                    l,
                    "*MODAL DAMPING, RAYLEIGH, DEFINITION=FREQUENCY RANGE: Rayleigh damping that varies with frequency is not read (give one line of alpha and beta for every mode)".into(),
                ));
            }
            let (alpha, beta) = (number(2, "alpha")?, number(3, "beta")?);
            let ranged = f.iter().take(2).any(|v| !v.is_empty());
            if self.modal_rayleigh.is_some() || (!ranged && !self.modal_rayleigh_ranges.is_empty())
            {
                return Err(err(
                    l,
                    format!(
                        "*MODAL DAMPING, RAYLEIGH: {t:?} after a line for every mode, or a line for every mode after ranges of modes: give one or the other"
                    ),
                ));
            }
            if !ranged {
                self.modal_rayleigh = Some((alpha, beta));
                return Ok(());
            }
            if !self.mode_ratios.is_empty() {
                return Err(err(
                    l,
                    "*MODAL DAMPING: Rayleigh damping by mode numbers beside damping ratios by mode numbers (Abaqus adds them; femu takes one form)".into(),
                ));
            }
            let mode = |i: usize| {
                f.get(i)
                    .and_then(|v| v.parse::<usize>().ok())
                    .filter(|m| *m > 0)
            };
            let first = mode(0).ok_or_else(|| {
                err(
                    l,
                    format!(
                        "*MODAL DAMPING, RAYLEIGH: the first mode of {t:?} is not a mode number"
                    ),
                )
            })?;
            let last = match f.get(1).copied() {
                None | Some("") => first,
                Some(_) => mode(1).ok_or_else(|| {
                    err(
                        l,
                        format!(
                            "*MODAL DAMPING, RAYLEIGH: the last mode of {t:?} is not a mode number"
                        ),
                    )
                })?,
            };
            if last < first {
                return Err(err(
                    l,
                    format!("*MODAL DAMPING: modes {first} to {last} end before they start"),
                ));
            }
            self.modal_rayleigh_ranges.push((first, last, alpha, beta));
            return Ok(());
        }
        // Abaqus adds viscous and structural modal damping; femu takes one form for all modes
        match &self.modal_structural {
            Some((s, first)) if *s != structural => {
                let name = |s: bool| if s { "STRUCTURAL" } else { "viscous" };
                return Err(err(
                    l,
                    format!(
                        "*MODAL DAMPING: {} damping here and {} damping at {}:{}: femu takes one form of modal damping (viscous ratios or structural damping factors)",
                        name(structural),
                        name(*s),
                        first.path.display(),
                        first.line
                    ),
                ));
            }
            Some(_) => {}
            None => self.modal_structural = Some((structural, at(l))),
        }
        if by_frequency {
            let hz = f
                .first()
                .and_then(|v| parse_f64(v))
                .filter(|x| x.is_finite() && *x >= 0.0)
                .ok_or_else(|| {
                    err(
                        l,
                        format!(
                            "*MODAL DAMPING: the frequency of {t:?} is not a number of at least 0"
                        ),
                    )
                })?;
            let value = number(
                1,
                if structural {
                    "structural damping factor"
                } else {
                    "fraction of critical damping"
                },
            )?;
            self.modal_frequency_points.push((hz, value));
            return Ok(());
        }
        let mode = |i: usize, what: &str| -> Result<usize, IoError> {
            f.get(i)
                .and_then(|v| v.parse::<usize>().ok())
                .filter(|m| *m > 0)
                .ok_or_else(|| {
                    err(
                        l,
                        format!("*MODAL DAMPING: the {what} mode of {t:?} is not a mode number"),
                    )
                })
        };
        let first = mode(0, "first")?;
        let last = match f.get(1).copied() {
            None | Some("") => first,
            Some(_) => mode(1, "last")?,
        };
        if last < first {
            return Err(err(
                l,
                format!("*MODAL DAMPING: modes {first} to {last} end before they start"),
            ));
        }
        // a structural damping factor s is the loss factor 2 zeta: kept as zeta = s / 2
        let value = number(
            2,
            if structural {
                "structural damping factor"
            } else {
                "ratio"
            },
        )?;
        if !self.modal_rayleigh_ranges.is_empty() {
            return Err(err(
                l,
                "*MODAL DAMPING: damping ratios by mode numbers beside Rayleigh damping by mode numbers (Abaqus adds them; femu takes one form)".into(),
            ));
        }
        self.mode_ratios
            .push((first, last, if structural { value / 2.0 } else { value }));
        Ok(())
    }

    /// An `*EQUATION`'s lines: the number of terms, then node, DOF, coefficient triples.
    fn equation_line(&mut self, f: &[&str], l: &Line, t: &str) -> Result<(), IoError> {
        let Some((n, terms, _)) = &mut self.equation else {
            let n = f
                .first()
                .and_then(|v| v.parse::<usize>().ok())
                .filter(|n| *n > 0)
                .ok_or_else(|| err(l, format!("*EQUATION needs its number of terms, got {t:?}")))?;
            self.equation = Some((n, Vec::new(), at(l)));
            return Ok(());
        };
        if !f.len().is_multiple_of(3) {
            return Err(err(
                l,
                format!("*EQUATION terms come as node, DOF, coefficient: {t:?}"),
            ));
        }
        for c in f.chunks(3) {
            let node = c[0].parse::<u64>().map_err(|_| {
                err(l, format!("*EQUATION: node {:?} is not a node id (node sets are not read in equations)", c[0]))
            })?;
            let dof = c[1]
                .parse::<usize>()
                .ok()
                .filter(|d| (1..=6).contains(d))
                .ok_or_else(|| err(l, format!("*EQUATION: DOF {:?} is not 1-6", c[1])))?;
            let a = parse_f64(c[2]).filter(|a| a.is_finite()).ok_or_else(|| {
                err(
                    l,
                    format!("*EQUATION: coefficient {:?} is not a number", c[2]),
                )
            })?;
            terms.push((node, dof, a));
        }
        if terms.len() > *n {
            return Err(err(
                l,
                format!("*EQUATION announces {n} terms and gives {}", terms.len()),
            ));
        }
        if terms.len() == *n {
            let (_, terms, at) = self.equation.take().expect("some");
            self.links.push(InpLink {
                kind: LinkKind::Equation(terms),
                line: at,
            });
        }
        Ok(())
    }

    /// The link about to be pushed takes its reference from a node set when the block's `REF
    /// NODE=` is a name.
    fn note_reference_set(&mut self, name: Option<&str>, l: &Line) {
        if let Some(name) = name.filter(|v| v.parse::<u64>().is_err()) {
            self.reference_sets
                .push((self.links.len(), name.to_ascii_uppercase(), at(l)));
        }
    }

    fn kinematic_coupling_line(&mut self, f: &[&str], l: &Line) -> Result<(), IoError> {
        let reference = self
            .block_params
            .get("REF NODE")
            .and_then(|v| v.parse::<u64>().ok())
            .unwrap_or(0);
        let Some(first) = f.first() else {
            return Err(err(
                l,
                "*KINEMATIC COUPLING needs a node or node set".into(),
            ));
        };
        let dofs = dof_range(f.get(1).copied(), f.get(2).copied())
            .map_err(|reason| err(l, format!("*KINEMATIC COUPLING: {reason}")))?;
        let set = self.block_params.get("REF NODE").cloned();
        self.note_reference_set(set.as_deref(), l);
        self.links.push(InpLink {
            kind: LinkKind::Kinematic {
                reference,
                nodes: LinkNodes::Targets(vec![target(first)]),
                dofs,
            },
            line: at(l),
        });
        Ok(())
    }

    fn surface_line(&mut self, f: &[&str], l: &Line) -> Result<(), IoError> {
        let Some(first) = f.first() else {
            return Ok(());
        };
        if let Some(name) = &self.element_surface_now {
            let face = f.get(1).map(|s| s.to_ascii_uppercase()).unwrap_or_default();
            self.element_surfaces
                .entry(name.clone())
                .or_default()
                .push((target(first), face, at(l)));
            return Ok(());
        }
        let w = match f.get(1) {
            Some(v) if !v.is_empty() => parse_f64(v)
                .filter(|w| w.is_finite() && *w > 0.0)
                .ok_or_else(|| {
                    err(
                        l,
                        format!("*SURFACE: weight {v:?} is not a positive number"),
                    )
                })?,
            _ => 1.0,
        };
        if let Some(name) = &self.surface_now {
            self.surfaces
                .entry(name.clone())
                .or_default()
                .push((target(first), w));
        }
        Ok(())
    }

    /// The end of the file: the last block complete, then the mesh, its sets and the point
    /// masses.
    fn finish(
        mut self,
        lines: &[Line],
        path: &Path,
        warnings: &mut Vec<Warning>,
    ) -> Result<InpDeck, IoError> {
        if !self.element_buffer.is_empty() {
            return Err(err(
                &lines[self.element_start],
                "element definition cut short at the end of the file".into(),
            ));
        }
        if let Some((n, terms, at)) = &self.equation {
            return Err(IoError::Parse {
                path: at.path.clone(),
                line: at.line,
                reason: format!(
                    "*EQUATION announces {n} terms and gives {} before the end of the file",
                    terms.len()
                ),
            });
        }
        self.finish_material()?;
        if let (Some(l), true) = (&self.rotation_boundary, self.structural.elements.is_empty()) {
            warnings.push(Warning {
                path: l.path.clone(),
                line: l.line,
                message: "DOFs 4-6 (rotations) exist only on coupling reference nodes, beams and springs: ignored on other nodes".into(),
            });
        }
        if let Some(c) = self.mass_cards.iter().find(|c| c.mass.is_nan()) {
            return Err(IoError::Parse {
                path: c.line.path.clone(),
                line: c.line.line,
                reason: "*MASS without its data line (the mass)".into(),
            });
        }
        let whole = |reason: String| IoError::Content {
            path: path.to_path_buf(),
            reason,
        };
        let (mut mesh, element_lines) = self.mesh(lines)?;
        let (node_sets, elem_sets) = self.resolve_sets(lines, &mesh)?;
        if self.nodes.is_empty() {
            return Err(whole(if lines.iter().all(|l| l.text.trim().is_empty()) {
                "the deck is empty: an Abaqus/CalculiX deck needs *NODE, *ELEMENT, *MATERIAL and *SOLID SECTION".into()
            } else {
                "the deck defines no nodes (*NODE)".into()
            }));
        }
        if self.elements.is_empty() && self.structural.elements.is_empty() {
            return Err(whole(format!(
                "the deck defines {} nodes and no elements (*ELEMENT, TYPE=C3D8 and the other solids)",
                self.nodes.len()
            )));
        }
        for (k, name, at) in &self.reference_sets {
            let one = match node_sets.get(name) {
                Some(ids) if ids.len() == 1 => ids[0],
                found => {
                    return Err(IoError::Parse {
                        path: at.path.clone(),
                        line: at.line,
                        reason: match found {
                            None => format!("REF NODE={name}: no node set has that name"),
                            Some(ids) => format!(
                                "REF NODE={name}: the set holds {} nodes; a reference is one node",
                                ids.len()
                            ),
                        },
                    });
                }
            };
            if let Some(InpLink {
                kind:
                    LinkKind::Kinematic { reference, .. } | LinkKind::Distributing { reference, .. },
                ..
            }) = self.links.get_mut(*k)
            {
                *reference = one;
            }
        }
        // the ids were checked where each set was defined
        for (name, ids) in &node_sets {
            mesh.add_node_set(name.clone(), ids)
                .map_err(|e| whole(format!("node set {name}: {e}")))?;
        }
        // a set's solids are a mesh set, its beams and springs a structural one
        let structural_ids: std::collections::HashSet<u64> =
            self.structural.elements.iter().map(|e| e.0).collect();
        for (name, ids) in &elem_sets {
            let (beams, solids): (Vec<u64>, Vec<u64>) =
                ids.iter().partition(|id| structural_ids.contains(id));
            if !solids.is_empty() || beams.is_empty() {
                mesh.add_element_set(name.clone(), &solids)
                    .map_err(|e| whole(format!("element set {name}: {e}")))?;
            }
            if !beams.is_empty() {
                self.structural.sets.insert(name.clone(), beams);
            }
        }
        // B31 beams whose section leaves LUMPED to Abaqus' default
        let b31: std::collections::HashSet<u64> = self
            .structural
            .elements
            .iter()
            .filter(|e| e.1 == structural::StructuralType::B31)
            .map(|e| e.0)
            .collect();
        for c in &self.structural.sections {
            let held = self.structural.sets.get(&c.elset).into_iter().flatten();
            if !c.lumped_stated && held.clone().any(|id| b31.contains(id)) {
                warnings.push(Warning {
                    path: c.line.path.clone(),
                    line: c.line.line,
                    message: format!(
                        "*BEAM SECTION of {}: femu builds its B31 beams' consistent mass (as CalculiX does, and Abaqus with LUMPED=NO); Abaqus/Standard lumps their mass in frequency extraction by default, so its frequencies of a coarse beam mesh differ",
                        c.elset
                    ),
                });
            }
        }
        let (point_masses, point_mass_sets) = self.point_masses(lines, &mesh, &elem_sets)?;
        let mut rotary_inertias = Vec::new();
        for (set, values, l) in &self.rotary_cards {
            let members = self.rotary_sets.get(set).ok_or_else(|| {
                structural::at_err(
                    l,
                    format!(
                        "*ROTARY INERTIA names element set {set}, which no *ELEMENT, TYPE=ROTARYI defines{}",
                        crate::spelling::suggestion(
                            set,
                            self.rotary_sets.keys().map(String::as_str),
                            ""
                        )
                    ),
                )
            })?;
            let v = values.ok_or_else(|| {
                structural::at_err(l, "*ROTARY INERTIA without its data line".into())
            })?;
            let inertia = [[v[0], v[3], v[4]], [v[3], v[1], v[5]], [v[4], v[5], v[2]]];
            for id in members {
                let (_, node, _) = self
                    .mass_elements
                    .iter()
                    .find(|e| e.0 == *id)
                    .expect("listed");
                rotary_inertias.push((*node, inertia, l.clone()));
            }
        }
        Ok(InpDeck {
            mesh,
            materials: self.materials,
            material_damping: self.material_damping,
            mode_ratios: self.mode_ratios,
            modal_structural: self.modal_structural.is_some_and(|(s, _)| s),
            modal_frequency_points: self.modal_frequency_points,
            modal_rayleigh: self.modal_rayleigh,
            modal_rayleigh_ranges: self.modal_rayleigh_ranges,
            laminae: self.laminae,
            orientations: self
                .orientations
                .into_iter()
                .map(|o| (o.name.clone(), o))
                .collect(),
            sections: self.sections,
            boundaries: self.boundaries,
            point_masses,
            point_mass_sets,
            rotary_inertias,
            links: self.links,
            surfaces: self.surfaces,
            element_surfaces: self.element_surfaces,
            ties: self.ties,
            nonstructural: self.nonstructural,
            frequency: self.frequency,
            incompatible_modes: self.incompatible_modes,
            warnings: std::mem::take(warnings),
            element_lines,
            structural: std::mem::take(&mut self.structural),
            path: path.to_path_buf(),
        })
    }

    /// The nodes and elements as a mesh, and where each element was defined.
    fn mesh(&self, lines: &[Line]) -> Result<(Mesh, HashMap<u64, Location>), IoError> {
        let model_err = |li: usize, source| IoError::Model {
            path: lines[li].path.clone(),
            line: lines[li].number,
            source,
        };
        let mut mesh = Mesh::new();
        for (id, x, li) in &self.nodes {
            mesh.add_node(*id, *x).map_err(|e| model_err(*li, e))?;
        }
        let mut element_lines = HashMap::new();
        for (id, kind, ids, li) in &self.elements {
            mesh.add_element(*id, *kind, ids)
                .map_err(|e| model_err(*li, e))?;
            element_lines.insert(*id, at(&lines[*li]));
        }
        Ok((mesh, element_lines))
    }

    /// Every node and element set: the blocks' own, then each `*NSET`/`*ELSET` in file order
    /// (a set may name sets defined before it); every id must exist.
    #[allow(clippy::type_complexity)]
    fn resolve_sets(
        &mut self,
        lines: &[Line],
        mesh: &Mesh,
    ) -> Result<(BTreeMap<String, Vec<u64>>, BTreeMap<String, Vec<u64>>), IoError> {
        let mut node_sets: BTreeMap<String, Vec<u64>> = BTreeMap::new();
        let mut elem_sets: BTreeMap<String, Vec<u64>> = BTreeMap::new();
        for (name, ids) in self.node_set_of_block.drain(..) {
            node_sets.entry(name).or_default().extend(ids);
        }
        for (name, ids) in self.elem_set_of_block.drain(..) {
            elem_sets.entry(name).or_default().extend(ids);
        }
        for set in self.sets.drain(..) {
            let l = &lines[set.line];
            let ids = if set.generate {
                generated_ids(&set, l, mesh, self.structural.elements.len())?
            } else {
                let known = if set.is_node { &node_sets } else { &elem_sets };
                listed_ids(&set, l, known)?
            };
            let structural = &self.structural.elements;
            let (what, exists): (&str, &dyn Fn(&u64) -> bool) = if set.is_node {
                ("node", &|id| mesh.node_index(*id).is_some())
            } else {
                ("element", &|id| {
                    mesh.element_index(*id).is_some() || structural.iter().any(|e| e.0 == *id)
                })
            };
            // every id listed here must exist: the error names this set and its line
            if let Some(bad) = ids.iter().find(|id| !exists(id)) {
                return Err(err(
                    l,
                    format!(
                        "{what} set {} lists {what} {bad}, which the deck does not define",
                        set.name
                    ),
                ));
            }
            if set.is_node {
                &mut node_sets
            } else {
                &mut elem_sets
            }
            .entry(set.name)
            .or_default()
            .extend(ids);
        }
        Ok((node_sets, elem_sets))
    }

    /// The mass elements' nodes and masses, from the `*MASS` of each set.
    fn point_masses(
        &self,
        lines: &[Line],
        mesh: &Mesh,
        elem_sets: &BTreeMap<String, Vec<u64>>,
    ) -> Result<PointMasses, IoError> {
        // mass elements: their nodes exist, their ids are not those of solids
        for (id, node, li) in &self.mass_elements {
            if mesh.node_index(*node).is_none() {
                return Err(err(
                    &lines[*li],
                    format!("MASS element {id} is on node {node}, which the deck does not define"),
                ));
            }
            if mesh.element_index(*id).is_some() {
                return Err(err(
                    &lines[*li],
                    format!("MASS element {id} has the id of a solid element"),
                ));
            }
        }
        let mut point_masses = Vec::new();
        let mut sets = Vec::new();
        for c in &self.mass_cards {
            let members = self.mass_sets.get(&c.elset).ok_or_else(|| {
                let hint = crate::spelling::suggestion(
                    &c.elset,
                    self.mass_sets.keys().map(String::as_str),
                    "",
                );
                let solid = elem_sets.contains_key(&c.elset);
                IoError::Parse {
                    path: c.line.path.clone(),
                    line: c.line.line,
                    reason: if solid {
                        format!(
                            "*MASS names element set {}, a set of solid elements: a *MASS gives the mass of the one-node elements of an *ELEMENT, TYPE=MASS set",
                            c.elset
                        )
                    } else {
                        format!(
                            "*MASS names element set {}, which no *ELEMENT, TYPE=MASS defines{hint}",
                            c.elset
                        )
                    },
                }
            })?;
            for id in members {
                let (_, node, _) = self
                    .mass_elements
                    .iter()
                    .find(|e| e.0 == *id)
                    .expect("listed");
                point_masses.push((*node, c.mass, c.line.clone()));
                sets.push(c.elset.clone());
            }
        }
        Ok((point_masses, sets))
    }
}

/// `*NSET/*ELSET, GENERATE`: first, last[, increment] ranges; a range longer than the model is an
/// error before it is an allocation.
fn generated_ids(
    set: &SetBlock,
    l: &Line,
    mesh: &Mesh,
    structural: usize,
) -> Result<Vec<u64>, IoError> {
    let tokens = &set.tokens;
    let nums: Result<Vec<u64>, _> = tokens.iter().map(|s| s.parse::<u64>()).collect();
    let nums = nums.map_err(|_| err(l, format!("GENERATE needs integers, got {tokens:?}")))?;
    if nums.len() % 3 != 0 && nums.len() != 2 {
        return Err(err(
            l,
            format!("GENERATE needs first, last[, increment], got {tokens:?}"),
        ));
    }
    let mut ids = Vec::new();
    for chunk in nums.chunks(3) {
        let (a, b, inc) = (chunk[0], chunk[1], chunk.get(2).copied().unwrap_or(1));
        if inc == 0 || b < a {
            return Err(err(l, format!("GENERATE range {a}, {b}, {inc} is invalid")));
        }
        // every generated id must exist
        let (have, what) = if set.is_node {
            (mesh.node_count(), "nodes")
        } else {
            (mesh.element_count() + structural, "elements")
        };
        let count = (b - a) / inc + 1;
        if count > have as u64 {
            return Err(err(
                l,
                format!(
                    "GENERATE range {a}, {b}, {inc} names {count} ids; the model has {have} {what}"
                ),
            ));
        }
        ids.extend((a..=b).step_by(inc as usize));
    }
    Ok(ids)
}

/// A set's listed ids, and the members of the sets (defined before it) that it names.
fn listed_ids(
    set: &SetBlock,
    l: &Line,
    known: &BTreeMap<String, Vec<u64>>,
) -> Result<Vec<u64>, IoError> {
    let a_what = if set.is_node { "a node" } else { "an element" };
    let mut ids = Vec::new();
    for tok in &set.tokens {
        match tok.parse::<u64>() {
            Ok(id) => ids.push(id),
            Err(_) => {
                let key = tok.to_ascii_uppercase();
                let members = known.get(&key).ok_or_else(|| {
                    let hint =
                        crate::spelling::suggestion(&key, known.keys().map(String::as_str), "");
                    err(
                        l,
                        format!(
                            "*{}SET {} names {tok}, which is neither {a_what} id nor {a_what} set defined before it{hint}",
                            if set.is_node { "N" } else { "EL" },
                            set.name
                        ),
                    )
                })?;
                ids.extend(members.iter().copied());
            }
        }
    }
    Ok(ids)
}

/// The point masses `(node, mass, the *MASS's line)` and the element set of each.
type PointMasses = (Vec<(u64, f64, Location)>, Vec<String>);

/// A `*NODE` block's `SYSTEM=`: rectangular (`R`, the default: false) or cylindrical (`C`: true,
/// its coordinates `r, theta (degrees), z`); other systems refused.
pub(super) fn node_system(params: &HashMap<String, String>) -> Result<bool, String> {
    match params
        .get("SYSTEM")
        .map(|v| v.to_ascii_uppercase())
        .as_deref()
    {
        None | Some("R") => Ok(false),
        Some("C") => Ok(true),
        Some(sys) => Err(format!(
            "*NODE, SYSTEM={sys}: femu reads rectangular (SYSTEM=R) and cylindrical (SYSTEM=C) coordinates"
        )),
    }
}

/// Cylindrical coordinates `(r, theta in degrees, z)` as rectangular ones (Abaqus's `*NODE,
/// SYSTEM=C`).
pub(super) fn cylindrical(x: [f64; 3]) -> [f64; 3] {
    let (s, c) = x[1].to_radians().sin_cos();
    [x[0] * c, x[0] * s, x[2]]
}
