//! Writing a universal file: every dataset femu reads, in a form that reads back to the same
//! bytes.

use super::*;

pub(super) fn e13(v: f64) -> String {
    efmt(v, 13, 5)
}

/// Fortran `1PEw.d`: `d.dddde+xx`, right-aligned in `w`, with a leading blank always: a
/// three-digit exponent (beyond Fortran's) would otherwise run into the previous field (found by
/// the fuzzer). Non-finite values are written as they are (the reader refuses them, naming the
/// line).
pub(super) fn efmt(v: f64, w: usize, d: usize) -> String {
    let s = format!("{v:.d$E}");
    let body = match s.split_once('E').map(|(m, e)| (m, e.parse::<i32>())) {
        Some((m, Ok(e))) => format!("{m}E{}{:02}", if e < 0 { '-' } else { '+' }, e.abs()),
        _ => s,
    };
    format!(" {body:>width$}", width = w - 1)
}

/// ASCII only, at most `n` characters (fixed-width text fields); a text that would read as the
/// dataset delimiter `-1` is bracketed (found by the fuzzer: an identification line of
/// non-ASCII bytes around "-1" became the delimiter when written).
pub(super) fn field(text: &str, n: usize) -> String {
    let t = text
        .chars()
        .filter(|c| c.is_ascii_graphic() || *c == ' ')
        .take(n)
        .collect::<String>()
        .trim()
        .to_string();
    if t == "-1" { "(-1)".into() } else { t }
}

/// Dataset 58 records 1-11 (after the header line).
pub(super) fn trace_line_text(t: &UffTraceLine, s: &mut String) {
    s.push_str("    -1\n    82\n");
    let _ = writeln!(s, "{:>10}{:>10}{:>10}", t.number, t.nodes.len(), t.color);
    let _ = writeln!(s, "{}", field(&t.id, 80));
    for chunk in t.nodes.chunks(8) {
        let row: Vec<String> = chunk.iter().map(|n| format!("{n:>10}")).collect();
        let _ = writeln!(s, "{}", row.concat());
    }
    s.push_str("    -1\n");
}

/// The whole file as bytes: [`uff_string`]'s datasets, with the functions marked binary as 58b.
pub fn uff_bytes(u: &Universal) -> Vec<u8> {
    let mut out = head_text(u).into_bytes();
    for f in &u.functions {
        function_bytes(f, f.binary, &mut out);
    }
    let mut s = String::new();
    for t in &u.trace_lines {
        trace_line_text(t, &mut s);
    }
    out.extend(s.as_bytes());
    out
}

/// Writes units, nodes, elements, normal modes (complex ones with their imaginary parts), functions and trace lines as datasets 164,
/// 2411 or 15, 2412, 55, 58 and 82, all as text (functions read from 58b included: use
/// [`uff_bytes`] to keep them binary).
pub fn uff_string(u: &Universal) -> String {
    let mut bytes = head_text(u).into_bytes();
    for f in &u.functions {
        function_bytes(f, false, &mut bytes);
    }
    let mut s = String::from_utf8(bytes).expect("text datasets are ASCII");
    for t in &u.trace_lines {
        trace_line_text(t, &mut s);
    }
    s
}

/// Datasets 164, 2411/15, 2412 and 55.
pub(super) fn head_text(u: &Universal) -> String {
    let mut s = String::new();
    if let Some(units) = &u.units {
        s.push_str("    -1\n   164\n");
        // fixed columns I10, 20A1, I10: the description as the reader sees it (ASCII, 20 chars)
        let description: String = units
            .description
            .chars()
            .filter(|c| c.is_ascii_graphic() || *c == ' ')
            .take(20)
            .collect();
        let _ = writeln!(s, "{:>10}{:<20}{:>10}", units.code, description.trim(), 2);
        let _ = writeln!(
            s,
            " {:>24.17E} {:>24.17E} {:>24.17E}",
            units.factors[0], units.factors[1], units.factors[2]
        )
        .map(|_| ());
        s.push_str(&format!(" {:>24.17E}\n", 273.15));
        s.push_str("    -1\n");
    }
    // coordinate systems by their three points (origin, a point on x, a point in the xz plane);
    // node coordinates are global, and a node keeps its displacement system
    if !u.coordinate_systems.is_empty() {
        s.push_str("    -1\n    18\n");
        for (number, c) in &u.coordinate_systems {
            let _ = writeln!(s, "{:>10}{:>10}{:>10}{:>10}{:>10}", number, c.kind, 0, 8, 1);
            let _ = writeln!(s, "{}", c.name);
            let o = c.origin;
            let xp: [f64; 3] = std::array::from_fn(|i| o[i] + c.axes[i][0]);
            let zp: [f64; 3] = std::array::from_fn(|i| o[i] + c.axes[i][2]);
            let _ = writeln!(
                s,
                "{}{}{}{}{}{}",
                e13(o[0]),
                e13(o[1]),
                e13(o[2]),
                e13(xp[0]),
                e13(xp[1]),
                e13(xp[2])
            );
            let _ = writeln!(s, "{}{}{}", e13(zp[0]), e13(zp[1]), e13(zp[2]));
        }
        s.push_str("    -1\n");
    }
    // the global system's label: 1 (I-DEAS's and Gmsh's) unless the file defines a system 1
    let global = if u.coordinate_systems.contains_key(&1) {
        0
    } else {
        1
    };
    let displacement =
        |id: u64, default: i64| u.displacement_systems.get(&id).copied().unwrap_or(default);
    if !u.nodes.is_empty() && u.nodes_2411 {
        s.push_str("    -1\n  2411\n");
        for n in &u.nodes {
            let _ = writeln!(
                s,
                " {:>9} {:>9} {:>9} {:>9}",
                n.id,
                global,
                displacement(n.id, global),
                11
            );
            let _ = writeln!(
                s,
                " {:>24.16E} {:>24.16E} {:>24.16E}",
                n.x[0], n.x[1], n.x[2]
            );
        }
        s.push_str("    -1\n");
    }
    if !u.elements.is_empty() {
        s.push_str("    -1\n  2412\n");
        for e in &u.elements {
            let _ = writeln!(
                s,
                " {:>9} {:>9} {:>9} {:>9} {:>9} {:>9}",
                e.id,
                e.descriptor,
                1,
                1,
                7,
                e.nodes.len()
            );
            if is_beam(e.descriptor) {
                let _ = writeln!(s, " {:>9} {:>9} {:>9}", 0, 1, 1);
            }
            for chunk in e.nodes.chunks(8) {
                let row: Vec<String> = chunk.iter().map(|n| format!(" {n:>9}")).collect();
                let _ = writeln!(s, "{}", row.concat());
            }
        }
        s.push_str("    -1\n");
    }
    if !u.groups.is_empty() {
        s.push_str("    -1\n  2477\n");
        for g in &u.groups {
            let entities: Vec<(i64, u64)> = g
                .nodes
                .iter()
                .map(|n| (7, *n))
                .chain(g.elements.iter().map(|e| (8, *e)))
                .collect();
            let _ = writeln!(
                s,
                "{:>10}{:>10}{:>10}{:>10}{:>10}{:>10}{:>10}{:>10}",
                g.number,
                0,
                0,
                0,
                0,
                0,
                0,
                entities.len()
            );
            let _ = writeln!(s, "{}", field(&g.name, 40));
            for pair in entities.chunks(2) {
                let row: Vec<String> = pair
                    .iter()
                    .map(|(t, n)| format!("{t:>10}{n:>10}{:>10}{:>10}", 0, 0))
                    .collect();
                let _ = writeln!(s, "{}", row.concat());
            }
        }
        s.push_str("    -1\n");
    }
    if !u.nodes.is_empty() && !u.nodes_2411 {
        s.push_str("    -1\n    15\n");
        for n in &u.nodes {
            let _ = writeln!(
                s,
                " {:>9} {:>9} {:>9} {:>9}{}{}{}",
                n.id,
                0,
                displacement(n.id, 0),
                11,
                e13(n.x[0]),
                e13(n.x[1]),
                e13(n.x[2])
            );
        }
        s.push_str("    -1\n");
    }
    for m in &u.modes {
        s.push_str("    -1\n    55\n");
        for line in [
            format!("mode {}", m.number),
            "femu".to_string(),
            "NONE".to_string(),
            "NONE".to_string(),
            "NONE".to_string(),
        ] {
            let _ = writeln!(s, "{line}");
        }
        match &m.imaginary {
            // a complex mode (analysis type 3, single precision complex data): its eigenvalue
            // `lambda = -zeta w + i w sqrt(1 - zeta^2)`, which the reader turns back into the
            // frequency `|lambda| / 2 pi` and the damping `-Re lambda / |lambda|`, and its turned
            // values with their imaginary parts
            Some(im) => {
                let _ = writeln!(s, " {:>9} {:>9} {:>9} {:>9} {:>9} {:>9}", 1, 3, 2, 8, 5, 3);
                let _ = writeln!(s, " {:>9} {:>9} {:>9} {:>9}", 2, 6, 1, m.number);
                let w = 2.0 * std::f64::consts::PI * m.frequency_hz;
                let (re, imag) = (-m.damping * w, w * (1.0 - m.damping * m.damping).sqrt());
                let _ = writeln!(
                    s,
                    "{}{}{}{}{}{}",
                    e13(re),
                    e13(imag),
                    e13(0.0),
                    e13(0.0),
                    e13(0.0),
                    e13(0.0)
                );
                for ((n, v), i) in m.values.iter().zip(im) {
                    let _ = writeln!(s, "{n:>10}");
                    let _ = writeln!(
                        s,
                        "{}{}{}{}{}{}",
                        e13(v[0]),
                        e13(i[0]),
                        e13(v[1]),
                        e13(i[1]),
                        e13(v[2]),
                        e13(i[2])
                    );
                }
            }
            None => {
                let _ = writeln!(s, " {:>9} {:>9} {:>9} {:>9} {:>9} {:>9}", 1, 2, 2, 8, 2, 3);
                let _ = writeln!(s, " {:>9} {:>9} {:>9} {:>9}", 2, 4, 1, m.number);
                let _ = writeln!(
                    s,
                    "{}{}{}{}",
                    e13(m.frequency_hz),
                    e13(m.modal_mass),
                    e13(m.damping),
                    e13(0.0)
                );
                for (n, v) in &m.values {
                    let _ = writeln!(s, "{n:>10}");
                    let _ = writeln!(s, "{}{}{}", e13(v[0]), e13(v[1]), e13(v[2]));
                }
            }
        }
        s.push_str("    -1\n");
    }
    s
}

/// Writes [`uff_bytes`] to a file.
///
/// # Errors
/// [`IoError::Io`].
pub fn write_uff(path: impl AsRef<Path>, u: &Universal) -> Result<(), IoError> {
    let path = path.as_ref();
    std::fs::write(path, uff_bytes(u)).map_err(|e| IoError::io(path, e))
}
