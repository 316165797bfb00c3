//! The deck's keywords and data lines into an [`InpDeck`]: the one pass over the lines.

use super::*;

#[allow(clippy::type_complexity)]
pub(super) fn parse_collecting(
    lines: &[Line],
    path: &Path,
    options: &InpOptions,
    warnings: &mut Vec<Warning>,
) -> Result<InpDeck, IoError> {
    let err = |l: &Line, reason: String| IoError::Parse {
        path: l.path.clone(),
        line: l.number,
        reason,
    };
    let warn = |w: &mut Vec<Warning>, l: &Line, message: String| {
        w.push(Warning {
            path: l.path.clone(),
            line: l.number,
            message,
        })
    };
    // raw records first: elements may refer to nodes defined later in the file
    let mut nodes: Vec<(u64, [f64; 3], usize)> = Vec::new();
    let mut elements: Vec<(u64, ElementKind, Vec<u64>, usize)> = Vec::new();
    // set name -> (is_node_set, tokens, line index)
    let mut sets: Vec<(String, bool, Vec<String>, bool, usize)> = Vec::new();
    let mut node_set_of_block: Vec<(String, Vec<u64>)> = Vec::new();
    let mut elem_set_of_block: Vec<(String, Vec<u64>)> = Vec::new();
    // point masses: MASS elements (id, node, line index) by their ELSET, and *MASS cards
    let mut mass_elements: Vec<(u64, u64, usize)> = Vec::new();
    let mut mass_sets: BTreeMap<String, Vec<u64>> = BTreeMap::new();
    let mut mass_block: Option<String> = None;
    let mut mass_cards: Vec<MassCard> = Vec::new();
    let mut materials = BTreeMap::new();
    let mut pending: Option<PendingMaterial> = None;
    let mut sections = Vec::new();
    let mut boundaries = Vec::new();
    let mut frequency = None;
    let mut links: Vec<InpLink> = Vec::new();
    let mut surfaces: BTreeMap<String, Vec<(Target, f64)>> = BTreeMap::new();
    let mut surface_now: Option<String> = None;
    let mut coupling_now: Option<(u64, String)> = None;
    // an *EQUATION being read: number of terms, terms so far, keyword line
    let mut equation: Option<(usize, Vec<(u64, usize, f64)>, Location)> = None;
    let mut block = String::new();
    let mut block_params: HashMap<String, String> = HashMap::new();
    let mut element_kind_now: Option<(ElementKind, usize)> = None;
    let mut element_buffer: Vec<String> = Vec::new();
    let mut element_start = 0usize;
    let mut seen_keyword = false;
    let finish_material = |p: Option<PendingMaterial>,
                           materials: &mut BTreeMap<String, Material>|
     -> Result<(), IoError> {
        if let Some(p) = p {
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
            let m = Material::isotropic(p.name.clone(), e, nu, rho).map_err(|source| {
                IoError::Model {
                    path: p.path.clone(),
                    line: p.line,
                    source,
                }
            })?;
            materials.insert(p.name, m);
        }
        Ok(())
    };
    for (li, l) in lines.iter().enumerate() {
        let t = l.text.trim();
        if t.is_empty() || t.starts_with("**") {
            continue;
        }
        if t.starts_with('*') {
            if !element_buffer.is_empty() {
                return Err(err(
                    &lines[element_start],
                    "element definition cut short by a keyword".into(),
                ));
            }
            if let Some((n, terms, at)) = &equation
                && terms.len() < *n
            {
                return Err(IoError::Parse {
                    path: at.path.clone(),
                    line: at.line,
                    reason: format!(
                        "*EQUATION announces {n} terms and gives {} before the next keyword",
                        terms.len()
                    ),
                });
            }
            equation = None;
            seen_keyword = true;
            let (name, params) = keyword(t);
            let mut sorted: Vec<(String, String)> = params.clone().into_iter().collect();
            sorted.sort();
            if !check_keyword(&name, &sorted, options, l, warnings)? {
                // skipped: its data lines are skipped with it
                finish_material(pending.take(), &mut materials)?;
                block = String::new();
                element_kind_now = None;
                continue;
            }
            let material_keyword = matches!(name.as_str(), "ELASTIC" | "DENSITY");
            if !material_keyword && name != "MATERIAL" {
                finish_material(pending.take(), &mut materials)?;
            }
            block = name.clone();
            block_params = params.clone();
            element_kind_now = None;
            mass_block = None;
            match name.as_str() {
                "HEADING" | "END STEP" | "STEP" => {}
                "KINEMATIC COUPLING" | "COUPLING" => {
                    let reference = params
                        .get("REF NODE")
                        .and_then(|v| v.parse::<u64>().ok())
                        .ok_or_else(|| err(l, format!("*{name} needs REF NODE=<node id>")))?;
                    coupling_now = None;
                    if name == "COUPLING" {
                        let surface = params.get("SURFACE").ok_or_else(|| {
                            err(l, "*COUPLING needs SURFACE=<node-based surface>".into())
                        })?;
                        coupling_now = Some((reference, surface.to_ascii_uppercase()));
                    }
                }
                "KINEMATIC" | "DISTRIBUTING" => {
                    let (reference, surface) = coupling_now
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
                    links.push(InpLink {
                        kind,
                        line: Location {
                            path: l.path.clone(),
                            line: l.number,
                        },
                    });
                }
                "SURFACE" => {
                    let ty = params.get("TYPE").map(|t| t.to_ascii_uppercase());
                    if ty.as_deref() != Some("NODE") {
                        return Err(err(
                            l,
                            format!(
                                "*SURFACE, TYPE={}: femu reads node-based surfaces (TYPE=NODE) for couplings",
                                ty.unwrap_or_else(|| "ELEMENT".into())
                            ),
                        ));
                    }
                    let name = params
                        .get("NAME")
                        .ok_or_else(|| err(l, "*SURFACE without NAME=".into()))?
                        .to_ascii_uppercase();
                    surfaces.entry(name.clone()).or_default();
                    surface_now = Some(name);
                }
                "NODE" => {
                    if let Some(sys) = params
                        .get("SYSTEM")
                        .filter(|v| !v.eq_ignore_ascii_case("R"))
                    {
                        return Err(err(
                            l,
                            format!(
                                "*NODE, SYSTEM={sys}: only rectangular coordinates (SYSTEM=R) are supported"
                            ),
                        ));
                    }
                    if let Some(s) = params.get("NSET") {
                        node_set_of_block.push((s.to_ascii_uppercase(), Vec::new()));
                    }
                }
                "ELEMENT"
                    if params
                        .get("TYPE")
                        .is_some_and(|t| t.eq_ignore_ascii_case("MASS")) =>
                {
                    // one-node mass elements: their mass comes from the *MASS of their set
                    let set = params
                        .get("ELSET")
                        .map(|s| s.to_ascii_uppercase())
                        .ok_or_else(|| {
                            err(
                                l,
                                "*ELEMENT, TYPE=MASS needs ELSET= (the set its *MASS names)".into(),
                            )
                        })?;
                    mass_sets.entry(set.clone()).or_default();
                    mass_block = Some(set);
                }
                "MASS" => {
                    let set = params
                        .get("ELSET")
                        .ok_or_else(|| err(l, "*MASS without ELSET=".into()))?;
                    mass_cards.push(MassCard {
                        elset: set.to_ascii_uppercase(),
                        mass: f64::NAN,
                        line: Location {
                            path: l.path.clone(),
                            line: l.number,
                        },
                    });
                }
                "ELEMENT" => {
                    let ty = params
                        .get("TYPE")
                        .ok_or_else(|| err(l, "*ELEMENT without TYPE=".into()))?;
                    let (kind, approx) = element_kind(ty).ok_or_else(|| {
                        err(l, format!("element type {ty} is not supported (C3D4, C3D10, C3D8, C3D20, C3D6, C3D15, C3D8R, C3D20R, MASS)"))
                    })?;
                    if approx {
                        warn(
                            warnings,
                            l,
                            format!("{ty} read as {} with full integration", kind.abaqus_name()),
                        );
                    }
                    element_kind_now = Some((kind, kind.num_nodes()));
                    if let Some(s) = params.get("ELSET") {
                        elem_set_of_block.push((s.to_ascii_uppercase(), Vec::new()));
                    }
                }
                "NSET" | "ELSET" => {
                    let key = if name == "NSET" { "NSET" } else { "ELSET" };
                    let set = params
                        .get(key)
                        .ok_or_else(|| err(l, format!("*{name} without {key}=")))?;
                    sets.push((
                        set.to_ascii_uppercase(),
                        name == "NSET",
                        Vec::new(),
                        params.contains_key("GENERATE"),
                        li,
                    ));
                }
                "MATERIAL" => {
                    finish_material(pending.take(), &mut materials)?;
                    let mname = params
                        .get("NAME")
                        .ok_or_else(|| err(l, "*MATERIAL without NAME=".into()))?;
                    pending = Some(PendingMaterial {
                        name: mname.to_ascii_uppercase(),
                        line: l.number,
                        path: l.path.clone(),
                        ..Default::default()
                    });
                }
                "ELASTIC" | "DENSITY" => {
                    if pending.is_none() {
                        return Err(err(l, format!("*{name} outside a *MATERIAL")));
                    }
                    let unsupported = params.get("TYPE").filter(|ty| {
                        !ty.eq_ignore_ascii_case("ISOTROPIC") && !ty.eq_ignore_ascii_case("ISO")
                    });
                    if let (true, Some(ty)) = (name == "ELASTIC", unsupported) {
                        return Err(err(
                            l,
                            format!("*ELASTIC, TYPE={ty} is not supported yet (isotropic only)"),
                        ));
                    }
                }
                "SOLID SECTION" => {
                    let elset = params
                        .get("ELSET")
                        .ok_or_else(|| err(l, "*SOLID SECTION without ELSET=".into()))?;
                    let material = params
                        .get("MATERIAL")
                        .ok_or_else(|| err(l, "*SOLID SECTION without MATERIAL=".into()))?;
                    sections.push(Section {
                        elset: elset.to_ascii_uppercase(),
                        material: material.to_ascii_uppercase(),
                        line: Location {
                            path: l.path.clone(),
                            line: l.number,
                        },
                    });
                }
                "BOUNDARY" => {
                    if params
                        .get("OP")
                        .is_some_and(|v| v.eq_ignore_ascii_case("NEW"))
                    {
                        // OP=NEW removes every boundary condition defined before it
                        boundaries.clear();
                    }
                    if params.contains_key("TYPE") || params.contains_key("AMPLITUDE") {
                        warn(
                            warnings,
                            l,
                            "*BOUNDARY options ignored (homogeneous constraints only)".into(),
                        );
                    }
                }
                _ => {} // HEADING, FREQUENCY, INCLUDE: nothing to do at the keyword
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
        if !seen_keyword {
            return Err(err(
                l,
                format!(
                    "data line {:?} before any keyword: a deck starts with a *KEYWORD line",
                    t.chars().take(40).collect::<String>()
                ),
            ));
        }
        // data line of the current block
        let f = fields(t);
        match block.as_str() {
            "NODE" => {
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
                nodes.push((id, x, li));
                if let Some(last) = node_set_of_block
                    .last_mut()
                    .filter(|_| block_params.contains_key("NSET"))
                {
                    last.1.push(id);
                }
            }
            "ELEMENT" if mass_block.is_some() => {
                let set = mass_block.as_ref().expect("checked");
                let ids: Vec<u64> = f
                    .iter()
                    .filter(|s| !s.is_empty())
                    .map(|s| s.parse::<u64>())
                    .collect::<Result<_, _>>()
                    .map_err(|_| {
                        err(
                            l,
                            format!("a MASS element line is an id and a node, got {t:?}"),
                        )
                    })?;
                let [id, node] = ids[..] else {
                    return Err(err(
                        l,
                        format!("a MASS element line is an id and a node, got {t:?}"),
                    ));
                };
                mass_elements.push((id, node, li));
                mass_sets
                    .get_mut(set)
                    .expect("created with the block")
                    .push(id);
            }
            "MASS" => {
                let card = mass_cards.last_mut().expect("set with the keyword");
                if card.mass.is_nan() {
                    card.mass = f
                        .first()
                        .and_then(|s| parse_f64(s))
                        .filter(|m| *m > 0.0)
                        .ok_or_else(|| err(l, format!("*MASS needs a positive mass, got {t:?}")))?;
                }
            }
            "ELEMENT" => {
                let (kind, nn) = element_kind_now.expect("set with the keyword");
                if element_buffer.is_empty() {
                    element_start = li;
                }
                element_buffer.extend(f.iter().map(|s| s.to_string()));
                if element_buffer.len() < nn + 1 {
                    continue; // continued on the next line
                }
                let start = &lines[element_start];
                if element_buffer.len() > nn + 1 {
                    return Err(err(
                        start,
                        format!(
                            "{} needs {nn} nodes, got {}",
                            kind.abaqus_name(),
                            element_buffer.len() - 1
                        ),
                    ));
                }
                let ids: Result<Vec<u64>, _> =
                    element_buffer.iter().map(|s| s.parse::<u64>()).collect();
                let ids = ids.map_err(|_| {
                    err(
                        start,
                        format!("element line has a non-integer entry: {element_buffer:?}"),
                    )
                })?;
                elements.push((ids[0], kind, ids[1..].to_vec(), element_start));
                if let Some(last) = elem_set_of_block
                    .last_mut()
                    .filter(|_| block_params.contains_key("ELSET"))
                {
                    last.1.push(ids[0]);
                }
                element_buffer.clear();
            }
            "NSET" | "ELSET" => {
                let last = sets.last_mut().expect("set with the keyword");
                last.2.extend(f.iter().map(|s| s.to_string()));
            }
            "ELASTIC" => {
                let p = pending.as_mut().expect("checked at the keyword");
                if f.len() < 2 {
                    return Err(err(l, "*ELASTIC needs E and nu".into()));
                }
                let e = parse_f64(f[0])
                    .ok_or_else(|| err(l, format!("E = {:?} is not a number", f[0])))?;
                let nu = parse_f64(f[1])
                    .ok_or_else(|| err(l, format!("nu = {:?} is not a number", f[1])))?;
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
            }
            "DENSITY" => {
                let p = pending.as_mut().expect("checked at the keyword");
                let rho = f
                    .first()
                    .and_then(|s| parse_f64(s))
                    .ok_or_else(|| err(l, format!("density {t:?} is not a number")))?;
                if p.density.is_none() {
                    p.density = Some(rho);
                }
            }
            "BOUNDARY" => {
                if f.len() < 2 {
                    return Err(err(
                        l,
                        format!("*BOUNDARY needs a node or set and a DOF, got {t:?}"),
                    ));
                }
                let target = match f[0].parse::<u64>() {
                    Ok(id) => Target::Node(id),
                    Err(_) => Target::Set(f[0].to_ascii_uppercase()),
                };
                let first = f[1]
                    .parse::<usize>()
                    .map_err(|_| err(l, format!("DOF {:?} is not an integer", f[1])))?;
                let last = match f.get(2) {
                    Some(s) if !s.is_empty() => s
                        .parse::<usize>()
                        .map_err(|_| err(l, format!("DOF {s:?} is not an integer")))?,
                    _ => first,
                };
                if let Some(v) = f.get(3).and_then(|s| parse_f64(s)).filter(|v| *v != 0.0) {
                    {
                        warn(
                            warnings,
                            l,
                            format!(
                                "prescribed value {v} read as 0 (femu's constraints are homogeneous)"
                            ),
                        );
                    }
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
                if last > 3 {
                    warn(warnings, l, "DOFs 4-6 (rotations) exist only on coupling reference nodes: ignored on other nodes".into());
                }
                if first <= 6 {
                    boundaries.push(Boundary {
                        target,
                        first,
                        last: last.min(6),
                        line: Location {
                            path: l.path.clone(),
                            line: l.number,
                        },
                    });
                }
            }
            "FREQUENCY" if frequency.is_none() => {
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
                frequency = Some(FrequencyStep {
                    count,
                    shift_cycles2,
                });
            }
            "EQUATION" => {
                let at = Location {
                    path: l.path.clone(),
                    line: l.number,
                };
                match &mut equation {
                    None => {
                        let n = f
                            .first()
                            .and_then(|v| v.parse::<usize>().ok())
                            .filter(|n| *n > 0)
                            .ok_or_else(|| {
                                err(l, format!("*EQUATION needs its number of terms, got {t:?}"))
                            })?;
                        equation = Some((n, Vec::new(), at));
                    }
                    Some((n, terms, _)) => {
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
                                .ok_or_else(|| {
                                    err(l, format!("*EQUATION: DOF {:?} is not 1-6", c[1]))
                                })?;
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
                            let (_, terms, at) = equation.take().expect("some");
                            links.push(InpLink {
                                kind: LinkKind::Equation(terms),
                                line: at,
                            });
                        }
                    }
                }
            }
            "KINEMATIC COUPLING" => {
                let reference = block_params
                    .get("REF NODE")
                    .and_then(|v| v.parse::<u64>().ok())
                    .unwrap_or(0);
                let target = match f.first().map(|v| v.parse::<u64>()) {
                    Some(Ok(id)) => Target::Node(id),
                    Some(Err(_)) => Target::Set(f[0].to_ascii_uppercase()),
                    None => {
                        return Err(err(
                            l,
                            "*KINEMATIC COUPLING needs a node or node set".into(),
                        ));
                    }
                };
                let dofs = dof_range(f.get(1).copied(), f.get(2).copied())
                    .map_err(|reason| err(l, format!("*KINEMATIC COUPLING: {reason}")))?;
                links.push(InpLink {
                    kind: LinkKind::Kinematic {
                        reference,
                        nodes: LinkNodes::Targets(vec![target]),
                        dofs,
                    },
                    line: Location {
                        path: l.path.clone(),
                        line: l.number,
                    },
                });
            }
            "KINEMATIC" | "DISTRIBUTING" => {
                let more = dof_range(f.first().copied(), f.get(1).copied())
                    .map_err(|reason| err(l, format!("*{block}: {reason}")))?;
                if let Some(InpLink {
                    kind: LinkKind::Kinematic { dofs, .. } | LinkKind::Distributing { dofs, .. },
                    ..
                }) = links.last_mut()
                {
                    dofs.extend(more);
                }
            }
            "SURFACE" => {
                let target = match f.first().map(|v| v.parse::<u64>()) {
                    Some(Ok(id)) => Target::Node(id),
                    Some(Err(_)) => Target::Set(f[0].to_ascii_uppercase()),
                    None => continue,
                };
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
                if let Some(name) = &surface_now {
                    surfaces.entry(name.clone()).or_default().push((target, w));
                }
            }
            "HEADING" | "SOLID SECTION" | "STEP" | "END STEP" => {}
            _ => {} // data of an ignored keyword
        }
    }
    if !element_buffer.is_empty() {
        return Err(err(
            &lines[element_start],
            "element definition cut short at the end of the file".into(),
        ));
    }
    if let Some((n, terms, at)) = &equation {
        return Err(IoError::Parse {
            path: at.path.clone(),
            line: at.line,
            reason: format!(
                "*EQUATION announces {n} terms and gives {} before the end of the file",
                terms.len()
            ),
        });
    }
    finish_material(pending.take(), &mut materials)?;
    if let Some(c) = mass_cards.iter().find(|c| c.mass.is_nan()) {
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
    // build the mesh
    let model_err = |li: usize, source| IoError::Model {
        path: lines[li].path.clone(),
        line: lines[li].number,
        source,
    };
    let mut mesh = Mesh::new();
    for (id, x, li) in &nodes {
        mesh.add_node(*id, *x).map_err(|e| model_err(*li, e))?;
    }
    let mut element_lines = HashMap::new();
    for (id, kind, ids, li) in &elements {
        mesh.add_element(*id, *kind, ids)
            .map_err(|e| model_err(*li, e))?;
        element_lines.insert(
            *id,
            Location {
                path: lines[*li].path.clone(),
                line: lines[*li].number,
            },
        );
    }
    let mut node_sets: BTreeMap<String, Vec<u64>> = BTreeMap::new();
    let mut elem_sets: BTreeMap<String, Vec<u64>> = BTreeMap::new();
    for (name, ids) in node_set_of_block {
        node_sets.entry(name).or_default().extend(ids);
    }
    for (name, ids) in elem_set_of_block {
        elem_sets.entry(name).or_default().extend(ids);
    }
    for (name, is_node, tokens, generate, li) in sets {
        let l = &lines[li];
        let (what, a_what) = if is_node {
            ("node", "a node")
        } else {
            ("element", "an element")
        };
        let mut ids = Vec::new();
        if generate {
            let nums: Result<Vec<u64>, _> = tokens.iter().map(|s| s.parse::<u64>()).collect();
            let nums =
                nums.map_err(|_| err(l, format!("GENERATE needs integers, got {tokens:?}")))?;
            if nums.len() % 3 != 0 && nums.len() != 2 {
                return Err(err(
                    l,
                    format!("GENERATE needs first, last[, increment], got {tokens:?}"),
                ));
            }
            for chunk in nums.chunks(3) {
                let (a, b, inc) = (chunk[0], chunk[1], chunk.get(2).copied().unwrap_or(1));
                if inc == 0 || b < a {
                    return Err(err(l, format!("GENERATE range {a}, {b}, {inc} is invalid")));
                }
                // every generated id must exist, so a range longer than the model is an error
                // before it is an allocation
                let (count, have, what) = if is_node {
                    ((b - a) / inc + 1, mesh.node_count(), "nodes")
                } else {
                    ((b - a) / inc + 1, mesh.element_count(), "elements")
                };
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
        } else {
            for tok in &tokens {
                match tok.parse::<u64>() {
                    Ok(id) => ids.push(id),
                    Err(_) => {
                        let key = tok.to_ascii_uppercase();
                        let src = if is_node { &node_sets } else { &elem_sets };
                        let members = src.get(&key).ok_or_else(|| {
                            let hint = crate::spelling::suggestion(
                                &key,
                                src.keys().map(String::as_str),
                                "",
                            );
                            err(
                                l,
                                format!(
                                    "*{}SET {name} names {tok}, which is neither {a_what} id nor {a_what} set defined before it{hint}",
                                    if is_node { "N" } else { "EL" }
                                ),
                            )
                        })?;
                        ids.extend(members.iter().copied());
                    }
                }
            }
        }
        // every id listed here must exist: the error names this set and its line
        let exists = |id: &u64| {
            if is_node {
                mesh.node_index(*id).is_some()
            } else {
                mesh.element_index(*id).is_some()
            }
        };
        if let Some(bad) = ids.iter().find(|id| !exists(id)) {
            return Err(err(
                l,
                format!("{what} set {name} lists {what} {bad}, which the deck does not define"),
            ));
        }
        if is_node {
            &mut node_sets
        } else {
            &mut elem_sets
        }
        .entry(name)
        .or_default()
        .extend(ids);
    }
    if nodes.is_empty() {
        return Err(whole(if lines.iter().all(|l| l.text.trim().is_empty()) {
            "the deck is empty: an Abaqus/CalculiX deck needs *NODE, *ELEMENT, *MATERIAL and *SOLID SECTION".into()
        } else {
            "the deck defines no nodes (*NODE)".into()
        }));
    }
    if elements.is_empty() {
        return Err(whole(format!(
            "the deck defines {} nodes and no elements (*ELEMENT, TYPE=C3D8 and the other solids)",
            nodes.len()
        )));
    }
    // the ids were checked where each set was defined
    for (name, ids) in &node_sets {
        mesh.add_node_set(name.clone(), ids)
            .map_err(|e| whole(format!("node set {name}: {e}")))?;
    }
    for (name, ids) in &elem_sets {
        mesh.add_element_set(name.clone(), ids)
            .map_err(|e| whole(format!("element set {name}: {e}")))?;
    }
    // mass elements: their nodes exist, their ids are not those of solids
    let mut point_masses = Vec::new();
    for (id, node, li) in &mass_elements {
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
    for c in &mass_cards {
        let members = mass_sets.get(&c.elset).ok_or_else(|| {
            let hint =
                crate::spelling::suggestion(&c.elset, mass_sets.keys().map(String::as_str), "");
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
            let (_, node, _) = mass_elements.iter().find(|e| e.0 == *id).expect("listed");
            point_masses.push((*node, c.mass, c.line.clone()));
        }
    }
    Ok(InpDeck {
        mesh,
        materials,
        sections,
        boundaries,
        point_masses,
        links,
        surfaces,
        frequency,
        warnings: std::mem::take(warnings),
        element_lines,
        path: path.to_path_buf(),
    })
}
