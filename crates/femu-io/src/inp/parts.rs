//! Parts, instances and the assembly (the layout Abaqus/CAE writes every deck in) flattened into
//! one deck of nodes and elements at the top level, before the keywords are read.
//!
//! Each `*INSTANCE, NAME=i, PART=p` places a copy of part `p`: its nodes moved by the instance's
//! translation and then turned about its axis (Keywords Reference, `*INSTANCE`: the first data
//! line a translation, the second two points `a`, `b` of an axis and an angle in degrees about
//! it), its sets named `i.set` (as Abaqus names them from the assembly), its sections, masses,
//! constraints and orientations carried with it (a beam section's `n1`, an orientation's points
//! and a rotary inertia's tensor turned with the instance). The first instance keeps the part's node and
//! element numbers; each further one, and the assembly's own nodes and elements, are numbered from
//! the next multiple of a power of ten above every part's numbers (said in a warning). References
//! from the assembly and the model (`*BOUNDARY`, `*NSET, INSTANCE=`, couplings, equations) take
//! `i.n` for node `n` of instance `i`, `i.set` for its set and a plain number for an
//! assembly-level node, as Abaqus does.

use super::{Line, Warning, fields, keyword};
use crate::IoError;
use std::collections::HashMap;

fn err(l: &Line, reason: String) -> IoError {
    IoError::Parse {
        path: l.path.clone(),
        line: l.number,
        reason,
    }
}

/// A line with new text, where the old one was (its errors keep pointing there).
fn at(l: &Line, text: String) -> Line {
    Line {
        path: l.path.clone(),
        number: l.number,
        text,
    }
}

/// An `*INSTANCE`: its name, its part and its placement `x -> a + R (x + t - a)`.
struct Instance {
    name: String,
    part: String,
    translation: [f64; 3],
    /// The axis point `a` and the rotation `R` (rows).
    rotation: Option<([f64; 3], [[f64; 3]; 3])>,
    node_offset: u64,
    element_offset: u64,
}

impl Instance {
    fn place(&self, x: [f64; 3]) -> [f64; 3] {
        let y = [
            x[0] + self.translation[0],
            x[1] + self.translation[1],
            x[2] + self.translation[2],
        ];
        match &self.rotation {
            None => y,
            Some((a, r)) => {
                let d = [y[0] - a[0], y[1] - a[1], y[2] - a[2]];
                std::array::from_fn(|i| a[i] + r[i][0] * d[0] + r[i][1] * d[1] + r[i][2] * d[2])
            }
        }
    }

    fn turn(&self, v: [f64; 3]) -> [f64; 3] {
        match &self.rotation {
            None => v,
            Some((_, r)) => {
                std::array::from_fn(|i| r[i][0] * v[0] + r[i][1] * v[1] + r[i][2] * v[2])
            }
        }
    }
}

/// The rotation by `angle` degrees about the unit axis `n` (Rodrigues).
fn rotation(n: [f64; 3], angle: f64) -> [[f64; 3]; 3] {
    let (s, c) = angle.to_radians().sin_cos();
    let k = [[0.0, -n[2], n[1]], [n[2], 0.0, -n[0]], [-n[1], n[0], 0.0]];
    std::array::from_fn(|i| {
        std::array::from_fn(|j| {
            let kk: f64 = (0..3).map(|m| k[i][m] * k[m][j]).sum();
            f64::from(u8::from(i == j)) + s * k[i][j] + (1.0 - c) * kk
        })
    })
}

fn number(l: &Line, s: &str, what: &str) -> Result<f64, IoError> {
    super::parse_f64(s)
        .filter(|v| v.is_finite())
        .ok_or_else(|| err(l, format!("{what}: {s:?} is not a number")))
}

/// An `*INSTANCE` as written: name, part, placement lines, its own lines (an instance meshed in
/// the assembly) and its keyword line.
type Placed = (String, String, Vec<Line>, Vec<Line>, Line);

/// Whether the deck is written in parts and an assembly.
fn has_parts(lines: &[Line]) -> bool {
    lines.iter().any(|l| {
        let t = l.text.trim_start();
        t.starts_with('*') && !t.starts_with("**") && {
            let (name, _) = keyword(t);
            matches!(name.as_str(), "PART" | "ASSEMBLY" | "INSTANCE")
        }
    })
}

/// The keywords a part may hold: femu's mesh, sections, masses, constraints and orientations.
const IN_PART: &[&str] = &[
    "NODE",
    "ELEMENT",
    "NSET",
    "ELSET",
    "SOLID SECTION",
    "SHELL SECTION",
    "MEMBRANE SECTION",
    "BEAM SECTION",
    "BEAM GENERAL SECTION",
    "SPRING",
    "DASHPOT",
    "MASS",
    "ROTARY INERTIA",
    "NONSTRUCTURAL MASS",
    "SHELL GENERAL SECTION",
    "ORIENTATION",
    "SURFACE",
    "EQUATION",
    "KINEMATIC COUPLING",
    "COUPLING",
    "KINEMATIC",
    "DISTRIBUTING",
];

/// The largest node and element ids of a block of lines (its `*NODE` and `*ELEMENT` records).
fn largest_ids(lines: &[Line]) -> (u64, u64) {
    let (mut node, mut element) = (0, 0);
    let mut block = String::new();
    let mut continued = false;
    for l in lines {
        let t = l.text.trim();
        if t.is_empty() || t.starts_with("**") {
            continue;
        }
        if t.starts_with('*') {
            block = keyword(t).0;
            continued = false;
            continue;
        }
        let first = fields(t).first().and_then(|s| s.parse::<u64>().ok());
        match block.as_str() {
            "NODE" => node = node.max(first.unwrap_or(0)),
            "ELEMENT" => {
                if !continued {
                    element = element.max(first.unwrap_or(0));
                }
                continued = t.ends_with(',');
            }
            _ => {}
        }
    }
    (node, element)
}

/// The smallest power of ten above `n`.
fn decade_above(n: u64) -> u64 {
    let mut d = 10;
    while d <= n {
        d *= 10;
    }
    d
}

/// The scope a line's references are read in: an instance's (inside its part) or the
/// assembly's (and the model's).
#[derive(Clone, Copy)]
enum Scope<'a> {
    Instance(&'a Instance),
    Assembly,
}

struct Flattener<'a> {
    instances: &'a [Instance],
    /// the assembly's own nodes and elements: the offset their numbers take
    assembly_offset: (u64, u64),
}

impl Flattener<'_> {
    fn instance(&self, l: &Line, name: &str) -> Result<&Instance, IoError> {
        self.instances
            .iter()
            .find(|i| i.name.eq_ignore_ascii_case(name))
            .ok_or_else(|| err(l, format!("{name:?} names no *INSTANCE of the assembly")))
    }

    /// A node (or element, `element`) reference or a set's name, as the flattened deck names
    /// it.
    fn reference(&self, l: &Line, s: &str, scope: Scope, element: bool) -> Result<String, IoError> {
        let s = s.trim();
        if s.is_empty() {
            return Ok(String::new());
        }
        let offset = |i: &Instance| {
            if element {
                i.element_offset
            } else {
                i.node_offset
            }
        };
        if let Ok(n) = s.parse::<u64>() {
            return Ok(match scope {
                Scope::Instance(i) => n + offset(i),
                Scope::Assembly => {
                    n + if element {
                        self.assembly_offset.1
                    } else {
                        self.assembly_offset.0
                    }
                }
            }
            .to_string());
        }
        match scope {
            Scope::Instance(i) => Ok(format!("{}.{}", i.name, s).to_ascii_uppercase()),
            Scope::Assembly => match s.rsplit_once('.') {
                Some((inst, rest)) => {
                    let i = self.instance(l, inst)?;
                    Ok(match rest.parse::<u64>() {
                        Ok(n) => (n + offset(i)).to_string(),
                        Err(_) => format!("{}.{}", i.name, rest).to_ascii_uppercase(),
                    })
                }
                None => Ok(s.to_ascii_uppercase()),
            },
        }
    }

    /// A keyword line with its set, surface and orientation names (and reference nodes) in
    /// `scope`.
    fn keyword_line<'s>(
        &'s self,
        l: &Line,
        scope: Scope<'s>,
    ) -> Result<(Line, Scope<'s>), IoError> {
        let (name, params) = keyword(&l.text);
        // *NSET, *ELSET, INSTANCE=i: the data lines are instance i's
        let mut data_scope = scope;
        let mut out = format!("*{name}");
        let mut keys: Vec<(&String, &String)> = params.iter().collect();
        keys.sort();
        for (k, v) in keys {
            let v = match k.as_str() {
                "INSTANCE" => {
                    data_scope = Scope::Instance(self.instance(l, v)?);
                    continue;
                }
                "NSET" | "ELSET" | "SURFACE" | "ORIENTATION" if !v.is_empty() => {
                    self.reference(l, v, scope, false)?
                }
                "NAME" if matches!(name.as_str(), "SURFACE" | "ORIENTATION") => {
                    self.reference(l, v, scope, false)?
                }
                "REF NODE" => self.reference(l, v, scope, false)?,
                // an instance's nodes are written rectangular, placed
                "SYSTEM"
                    if name == "NODE"
                        && matches!(scope, Scope::Instance(_))
                        && v.eq_ignore_ascii_case("C") =>
                {
                    continue;
                }
                _ => v.clone(),
            };
            if params[k].is_empty() {
                out.push_str(&format!(", {k}"));
            } else {
                out.push_str(&format!(", {k}={v}"));
            }
        }
        Ok((at(l, out), data_scope))
    }

    /// The lines of a part placed as instance `inst`, or of the assembly (`scope` Assembly).
    fn block<'s>(
        &'s self,
        lines: &[Line],
        scope: Scope<'s>,
        out: &mut Vec<Line>,
    ) -> Result<(), IoError> {
        let mut block = String::new();
        let mut params = HashMap::new();
        let mut data_scope = scope;
        let mut continued = false;
        let mut data_index = 0usize;
        for l in lines {
            let t = l.text.trim();
            if t.is_empty() || t.starts_with("**") {
                out.push(l.clone());
                continue;
            }
            if t.starts_with('*') {
                let (name, p) = keyword(t);
                // a keyword of no mesh: the reader skips it or refuses it with its own reason
                let passed = !IN_PART.contains(&name.as_str())
                    && !super::READ.iter().any(|(k, _)| *k == name);
                if passed {
                    out.push(l.clone());
                    block = name;
                    params = p;
                    data_scope = scope;
                    continued = false;
                    data_index = 0;
                    continue;
                }
                if let Scope::Instance(i) = scope
                    && !IN_PART.contains(&name.as_str())
                {
                    return Err(err(
                        l,
                        format!(
                            "*{name} in part {}: femu reads a part's nodes, elements, sets, sections, masses, constraints and orientations",
                            i.part
                        ),
                    ));
                }
                let (line, ds) = self.keyword_line(l, scope)?;
                if matches!(name.as_str(), "SPRING" | "DASHPOT")
                    && let Scope::Instance(i) = scope
                    && i.rotation.is_some()
                {
                    return Err(err(
                        l,
                        format!(
                            "*{name} in part {} of the turned instance {}: its degrees of freedom would turn with it, which femu does not do; place this part without a rotation",
                            i.part, i.name
                        ),
                    ));
                }
                out.push(line);
                block = name;
                params = p;
                data_scope = ds;
                continued = false;
                data_index = 0;
                continue;
            }
            let f = fields(t);
            let text = match block.as_str() {
                "NODE" => {
                    let id = self.reference(l, f[0], scope, false)?;
                    match scope {
                        Scope::Instance(i) => {
                            let mut x = [0.0; 3];
                            for (c, s) in f.iter().skip(1).take(3).enumerate() {
                                x[c] = number(l, s, "a coordinate")?;
                            }
                            // a cylindrical block's nodes placed as rectangular ones (the
                            // keyword line lost its SYSTEM)
                            if super::parse::node_system(&params) == Ok(true) {
                                x = super::parse::cylindrical(x);
                            }
                            let y = i.place(x);
                            format!("{id}, {:?}, {:?}, {:?}", y[0], y[1], y[2])
                        }
                        Scope::Assembly => {
                            let mut g = f.clone();
                            let id = id.clone();
                            g[0] = &id;
                            g.join(", ")
                        }
                    }
                }
                "ELEMENT" => {
                    let mut g = Vec::with_capacity(f.len());
                    for (k, s) in f.iter().enumerate() {
                        let element = k == 0 && !continued;
                        g.push(self.reference(l, s, scope, element)?);
                    }
                    continued = t.ends_with(',');
                    g.join(", ") + if continued { "," } else { "" }
                }
                "NSET" | "ELSET" => {
                    let element = block == "ELSET";
                    if params.contains_key("GENERATE") {
                        let mut g = Vec::with_capacity(3);
                        for (k, s) in f.iter().enumerate() {
                            g.push(if k < 2 {
                                self.reference(l, s, data_scope, element)?
                            } else {
                                s.to_string()
                            });
                        }
                        g.join(", ")
                    } else {
                        f.iter()
                            .map(|s| self.reference(l, s, data_scope, element))
                            .collect::<Result<Vec<_>, _>>()?
                            .join(", ")
                    }
                }
                "BEAM SECTION" | "BEAM GENERAL SECTION" if data_index == 1 => {
                    // the section's 1-axis direction turns with the instance
                    if let (Scope::Instance(i), true) = (scope, f.len() >= 3) {
                        let v = [
                            number(l, f[0], "n1")?,
                            number(l, f[1], "n1")?,
                            number(l, f[2], "n1")?,
                        ];
                        let w = i.turn(v);
                        format!("{:?}, {:?}, {:?}", w[0], w[1], w[2])
                    } else {
                        t.to_string()
                    }
                }
                "ORIENTATION" if data_index == 0 => {
                    self.orientation_points(l, &f, &params, scope)?
                }
                // a part's rotary inertia is about the part's axes: turned with the instance
                "ROTARY INERTIA" if data_index == 0 => match scope {
                    Scope::Instance(i) if i.rotation.is_some() => {
                        let mut v = [0.0; 6];
                        for (k, s) in f.iter().take(6).enumerate() {
                            if !s.is_empty() {
                                v[k] = number(l, s, "an inertia")?;
                            }
                        }
                        let j = [[v[0], v[3], v[4]], [v[3], v[1], v[5]], [v[4], v[5], v[2]]];
                        let r = i.rotation.as_ref().map(|(_, r)| *r).expect("a rotation");
                        let g: [[f64; 3]; 3] = std::array::from_fn(|a| {
                            std::array::from_fn(|b| {
                                (0..3)
                                    .flat_map(|p| (0..3).map(move |q| (p, q)))
                                    .map(|(p, q)| r[a][p] * j[p][q] * r[b][q])
                                    .sum()
                            })
                        });
                        format!(
                            "{:?}, {:?}, {:?}, {:?}, {:?}, {:?}",
                            g[0][0], g[1][1], g[2][2], g[0][1], g[0][2], g[1][2]
                        )
                    }
                    _ => t.to_string(),
                },
                "SURFACE" | "KINEMATIC COUPLING" => {
                    let element = block == "SURFACE"
                        && !params
                            .get("TYPE")
                            .is_some_and(|v| v.eq_ignore_ascii_case("NODE"));
                    let mut g: Vec<String> = f.iter().map(|s| s.to_string()).collect();
                    g[0] = self.reference(l, f[0], scope, element)?;
                    g.join(", ")
                }
                "EQUATION" if f.len() >= 3 => {
                    let mut g: Vec<String> = f.iter().map(|s| s.to_string()).collect();
                    for k in (0..f.len()).step_by(3) {
                        g[k] = self.reference(l, f[k], scope, false)?;
                    }
                    g.join(", ")
                }
                _ => t.to_string(),
            };
            data_index += 1;
            out.push(at(l, text));
        }
        Ok(())
    }

    /// An orientation's first data line in an instance: points by coordinates placed with the
    /// instance (the origin, the global one when not given, with them), nodes renumbered.
    fn orientation_points(
        &self,
        l: &Line,
        f: &[&str],
        params: &HashMap<String, String>,
        scope: Scope,
    ) -> Result<String, IoError> {
        let Scope::Instance(i) = scope else {
            return Ok(f.join(", "));
        };
        match params
            .get("DEFINITION")
            .map(|d| d.to_ascii_uppercase())
            .as_deref()
        {
            None | Some("COORDINATES") => {
                let point = |k: usize| -> Result<[f64; 3], IoError> {
                    let mut p = [0.0; 3];
                    for (c, v) in p.iter_mut().enumerate() {
                        *v = number(l, f.get(3 * k + c).copied().unwrap_or(""), "a point")?;
                    }
                    Ok(p)
                };
                let cylindrical = params
                    .get("SYSTEM")
                    .is_some_and(|s| s.eq_ignore_ascii_case("CYLINDRICAL"));
                let (a, b) = (i.place(point(0)?), i.place(point(1)?));
                let c = if f.len() > 6 && !cylindrical {
                    Some(i.place(point(2)?))
                } else if cylindrical {
                    None
                } else {
                    Some(i.place([0.0; 3]))
                };
                let mut s = format!(
                    "{:?}, {:?}, {:?}, {:?}, {:?}, {:?}",
                    a[0], a[1], a[2], b[0], b[1], b[2]
                );
                if let Some(c) = c {
                    s.push_str(&format!(", {:?}, {:?}, {:?}", c[0], c[1], c[2]));
                }
                Ok(s)
            }
            Some("NODES") => Ok(f
                .iter()
                .map(|s| self.reference(l, s, scope, false))
                .collect::<Result<Vec<_>, _>>()?
                .join(", ")),
            _ => Ok(f.join(", ")),
        }
    }
}

/// The deck's lines with its parts placed by their instances, or none for a deck without parts.
pub(super) fn flatten(
    lines: &[Line],
    warnings: &mut Vec<Warning>,
) -> Result<Option<Vec<Line>>, IoError> {
    if !has_parts(lines) {
        return Ok(None);
    }
    // the parts, the instances (with their placement lines), the assembly's lines and the rest
    let mut parts: Vec<(String, Vec<Line>, Line)> = Vec::new();
    // each instance: name, part, placement lines, its own lines (an instance meshed in the
    // assembly), keyword line
    let mut placed: Vec<Placed> = Vec::new();
    let mut assembly: Vec<Line> = Vec::new();
    // the model's lines, and where the assembly stood among them
    let mut model: Vec<Line> = Vec::new();
    let mut assembly_at: Option<usize> = None;
    enum State {
        Top,
        Part,
        Assembly,
        Instance,
    }
    let mut state = State::Top;
    let mut opened: Option<Line> = None;
    for l in lines {
        let t = l.text.trim();
        let key = (t.starts_with('*') && !t.starts_with("**")).then(|| keyword(t));
        let name = key.as_ref().map(|k| k.0.as_str()).unwrap_or("");
        match (&state, name) {
            (State::Top, "PART") => {
                let p = key
                    .as_ref()
                    .and_then(|k| k.1.get("NAME"))
                    .ok_or_else(|| err(l, "*PART without NAME=".into()))?;
                if let Some(first) = parts.iter().find(|q| q.0.eq_ignore_ascii_case(p)) {
                    return Err(err(
                        l,
                        format!(
                            "part {p} is defined again (first at line {})",
                            first.2.number
                        ),
                    ));
                }
                parts.push((p.clone(), Vec::new(), l.clone()));
                state = State::Part;
                opened = Some(l.clone());
            }
            (State::Part, "END PART") => {
                state = State::Top;
                opened = None;
            }
            (State::Part, "PART" | "ASSEMBLY" | "INSTANCE" | "STEP") => {
                return Err(err(
                    l,
                    format!("*{name} inside a *PART: *END PART is missing"),
                ));
            }
            (State::Part, _) => parts.last_mut().expect("opened").1.push(l.clone()),
            (State::Top, "ASSEMBLY") => {
                if assembly_at.is_some() {
                    return Err(err(l, "a second *ASSEMBLY".into()));
                }
                assembly_at = Some(model.len());
                state = State::Assembly;
                opened = Some(l.clone());
            }
            (State::Assembly, "END ASSEMBLY") => {
                state = State::Top;
                opened = None;
            }
            (State::Assembly, "INSTANCE") => {
                let k = &key.as_ref().expect("a keyword").1;
                let n = k
                    .get("NAME")
                    .ok_or_else(|| err(l, "*INSTANCE without NAME=".into()))?;
                let p = k.get("PART").ok_or_else(|| {
                    err(
                        l,
                        format!(
                            "*INSTANCE, NAME={n} without PART=: an instance that defines its own mesh is not read; define it as a *PART"
                        ),
                    )
                })?;
                if placed.iter().any(|q| q.0.eq_ignore_ascii_case(n)) {
                    return Err(err(l, format!("instance {n} is defined twice")));
                }
                placed.push((n.clone(), p.clone(), Vec::new(), Vec::new(), l.clone()));
                state = State::Instance;
            }
            (State::Instance, "END INSTANCE") => state = State::Assembly,
            (State::Instance, "PART" | "ASSEMBLY" | "INSTANCE" | "STEP" | "END ASSEMBLY") => {
                return Err(err(
                    l,
                    format!("*{name} inside an *INSTANCE: *END INSTANCE is missing"),
                ));
            }
            (State::Instance, _) => {
                // its placement: the data lines before its first keyword; then its own mesh
                // (an instance meshed in the assembly), placed as its part's
                let inst = placed.last_mut().expect("opened");
                if name.is_empty() && inst.3.is_empty() {
                    if !t.is_empty() && !t.starts_with("**") {
                        inst.2.push(l.clone());
                    }
                } else {
                    inst.3.push(l.clone());
                }
            }
            (State::Assembly, "PART" | "ASSEMBLY" | "STEP") => {
                return Err(err(
                    l,
                    format!("*{name} inside the *ASSEMBLY: *END ASSEMBLY is missing"),
                ));
            }
            (State::Assembly, _) => assembly.push(l.clone()),
            (State::Top, "END PART" | "END ASSEMBLY" | "INSTANCE" | "END INSTANCE") => {
                return Err(err(l, format!("*{name} outside its block")));
            }
            (State::Top, _) => model.push(l.clone()),
        }
    }
    if let Some(l) = opened {
        return Err(err(
            &l,
            format!(
                "*{} is not closed before the end of the deck",
                keyword(&l.text).0
            ),
        ));
    }
    if placed.is_empty() {
        let l = parts
            .first()
            .map(|p| p.2.clone())
            .unwrap_or_else(|| lines[0].clone());
        return Err(err(
            &l,
            "the deck defines parts but no *ASSEMBLY places them with an *INSTANCE".into(),
        ));
    }
    // numbering: the first instance keeps its part's numbers, the others and the assembly
    // from the next multiple of a power of ten above every part's
    let mut largest = (0u64, 0u64);
    for body in parts
        .iter()
        .map(|p| &p.1)
        .chain(placed.iter().map(|i| &i.3))
    {
        let (n, e) = largest_ids(body);
        largest = (largest.0.max(n), largest.1.max(e));
    }
    let step = (decade_above(largest.0), decade_above(largest.1));
    let mut instances = Vec::with_capacity(placed.len());
    for (k, (name, part, placement, _, l)) in placed.iter().enumerate() {
        if !parts.iter().any(|p| p.0.eq_ignore_ascii_case(part)) {
            return Err(err(
                l,
                format!("*INSTANCE {name}: no *PART is named {part}"),
            ));
        }
        let mut translation = [0.0; 3];
        let mut rot = None;
        if let Some(p) = placement.first() {
            let f = fields(&p.text);
            for (c, v) in translation.iter_mut().enumerate() {
                *v = match f.get(c) {
                    Some(s) if !s.is_empty() => number(p, s, "the instance's translation")?,
                    _ => 0.0,
                };
            }
        }
        if let Some(p) = placement.get(1) {
            let f = fields(&p.text);
            let mut v = [0.0; 7];
            for (c, x) in v.iter_mut().enumerate() {
                *x = number(
                    p,
                    f.get(c).copied().unwrap_or(""),
                    "the instance's rotation (two points of its axis and an angle)",
                )?;
            }
            let axis = [v[3] - v[0], v[4] - v[1], v[5] - v[2]];
            let len = (axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]).sqrt();
            if !(len > 0.0) {
                return Err(err(
                    p,
                    format!("*INSTANCE {name}: the two points of its axis of rotation coincide"),
                ));
            }
            if v[6] != 0.0 {
                rot = Some((
                    [v[0], v[1], v[2]],
                    rotation([axis[0] / len, axis[1] / len, axis[2] / len], v[6]),
                ));
            }
        }
        if placement.len() > 2 {
            return Err(err(
                &placement[2],
                format!("*INSTANCE {name}: a translation and a rotation are its only data lines"),
            ));
        }
        instances.push(Instance {
            name: name.to_ascii_uppercase(),
            part: part.to_ascii_uppercase(),
            translation,
            rotation: rot,
            node_offset: k as u64 * step.0,
            element_offset: k as u64 * step.1,
        });
    }
    let (asm_nodes, asm_elements) = largest_ids(&assembly);
    let assembly_offset = if asm_nodes > 0 || asm_elements > 0 {
        (
            instances.len() as u64 * step.0,
            instances.len() as u64 * step.1,
        )
    } else {
        (0, 0)
    };
    let flattener = Flattener {
        instances: &instances,
        assembly_offset,
    };
    let mut out = Vec::with_capacity(lines.len() + 16 * instances.len());
    let split = assembly_at.unwrap_or(model.len());
    out.extend(model[..split].iter().cloned());
    for (i, (_, _, _, own, l)) in instances.iter().zip(&placed) {
        let body = &parts
            .iter()
            .find(|p| p.0.eq_ignore_ascii_case(&i.part))
            .expect("checked")
            .1;
        flattener.block(body, Scope::Instance(i), &mut out)?;
        flattener.block(own, Scope::Instance(i), &mut out)?;
        if i.node_offset > 0 || i.element_offset > 0 {
            warnings.push(Warning {
                path: l.path.clone(),
                line: l.number,
                message: format!(
                    "instance {} of part {}: its nodes are numbered {} and its elements {} above the part's in femu's model (Abaqus's {}.n is femu's n + {})",
                    i.name, i.part, i.node_offset, i.element_offset, i.name, i.node_offset
                ),
            });
        }
    }
    flattener.block(&assembly, Scope::Assembly, &mut out)?;
    if assembly_offset != (0, 0)
        && let Some(l) = assembly.iter().find(|l| keyword(&l.text).0 == "NODE")
    {
        warnings.push(Warning {
            path: l.path.clone(),
            line: l.number,
            message: format!(
                "the assembly's own nodes are numbered {} and its elements {} above the deck's in femu's model",
                assembly_offset.0, assembly_offset.1
            ),
        });
    }
    // the model's data after the assembly: its references read at the assembly's level
    let mut rest = Vec::new();
    flattener.model(&model[split..], &mut rest)?;
    out.extend(rest);
    Ok(Some(out))
}

impl Flattener<'_> {
    /// The model's and steps' lines: `*BOUNDARY`'s node or set in the first field read as the
    /// assembly reads it; everything else as written.
    fn model(&self, lines: &[Line], out: &mut Vec<Line>) -> Result<(), IoError> {
        let mut block = String::new();
        for l in lines {
            let t = l.text.trim();
            if t.starts_with('*') && !t.starts_with("**") {
                block = keyword(t).0;
                out.push(l.clone());
                continue;
            }
            if block == "BOUNDARY" && !t.is_empty() && !t.starts_with("**") {
                let f = fields(t);
                let mut g: Vec<String> = f.iter().map(|s| s.to_string()).collect();
                g[0] = self.reference(l, f[0], Scope::Assembly, false)?;
                out.push(at(l, g.join(", ")));
                continue;
            }
            out.push(l.clone());
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Rodrigues' rotation: a quarter turn about z takes x to y; about (1, 1, 1) by 120 degrees
    /// the axes cycle (x to y to z), by hand.
    #[test]
    fn rotations_about_an_axis_are_rodrigues() {
        let r = rotation([0.0, 0.0, 1.0], 90.0);
        let x = [r[0][0], r[1][0], r[2][0]];
        assert!((x[0]).abs() < 1e-15 && (x[1] - 1.0).abs() < 1e-15 && x[2].abs() < 1e-15);
        let s = 1.0 / 3f64.sqrt();
        let r = rotation([s, s, s], 120.0);
        for (i, want) in [[0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]]
            .iter()
            .enumerate()
        {
            for k in 0..3 {
                assert!((r[k][i] - want[k]).abs() < 1e-15, "{r:?}");
            }
        }
    }
}
