//! Functions at nodal DOFs (58, and the binary 58b): records 1-11 and the values, read and
//! written.

use super::*;

/// Dataset 58 records 1-11, as a function without values, and the count of stored values.
pub(super) fn parse_58_header(
    path: &Path,
    body: &[(usize, &str)],
    start: usize,
) -> Result<(UffFunction, usize), IoError> {
    if body.len() < 11 {
        return Err(perr(
            path,
            start,
            format!("dataset 58 needs 11 header records, found {}", body.len()),
        ));
    }
    let ids: [String; 5] = std::array::from_fn(|k| body[k].1.trim_end().to_string());
    let (l6, r6) = body[5];
    let dof = |name: (usize, usize),
               node: (usize, usize),
               dir: (usize, usize)|
     -> Result<UffDof, IoError> {
        let entity = col(r6, name.0, name.1).trim().to_string();
        let n = col_int(path, l6, r6, node.0, node.1)?;
        // vendors write -1 for the node of a reference that does not exist ("NONE")
        let n = if n < 0 && entity.eq_ignore_ascii_case("NONE") {
            0
        } else {
            n
        };
        if n < 0 {
            return Err(perr(
                path,
                l6,
                format!("node label {n} must not be negative"),
            ));
        }
        Ok(UffDof {
            entity,
            node: n as u64,
            direction: col_int(path, l6, r6, dir.0, dir.1)?,
        })
    };
    let function_type = col_int(path, l6, r6, 0, 5)?;
    let numbers = [
        col_int(path, l6, r6, 5, 15)?,
        col_int(path, l6, r6, 15, 20)?,
        col_int(path, l6, r6, 20, 30)?,
    ];
    let response = dof((31, 41), (41, 51), (51, 55))?;
    let reference = dof((56, 66), (66, 76), (76, 80))?;
    let (l7, r7) = body[6];
    let t = ints_then_nums(path, l7, r7)?;
    let (data_type, points, spacing) = (t.0[0], t.0[1], t.0[2]);
    let (min, step, z_value) = (t.1[0], t.1[1], t.1[2]);
    let (double, complex) = match data_type {
        2 => (false, false),
        4 => (true, false),
        5 => (false, true),
        6 => (true, true),
        o => {
            return Err(perr(
                path,
                l7,
                format!("ordinate data type {o}: expected 2, 4 (real) or 5, 6 (complex)"),
            ));
        }
    };
    if !(0..=100_000_000).contains(&points) || !(spacing == 0 || spacing == 1) {
        return Err(perr(
            path,
            l7,
            format!(
                "{points} points with abscissa spacing {spacing}: need 0..1e8 points and spacing 0 (uneven) or 1 (even)"
            ),
        ));
    }
    let axes: [UffAxis; 4] = {
        let mut a: [UffAxis; 4] = Default::default();
        for (k, axis) in a.iter_mut().enumerate() {
            let (ln, l) = body[7 + k];
            *axis = UffAxis {
                data_type: col_int(path, ln, l, 0, 10)?,
                exponents: [
                    col_int(path, ln, l, 10, 15)?,
                    col_int(path, ln, l, 15, 20)?,
                    col_int(path, ln, l, 20, 25)?,
                ],
                label: col(l, 26, 46).trim().to_string(),
                units: col(l, 47, 67).trim().to_string(),
            };
        }
        a
    };
    let even = spacing == 1;
    let f = UffFunction {
        ids,
        function_type,
        numbers,
        response,
        reference,
        double,
        abscissa: if even {
            Abscissa::Even { min, step }
        } else {
            Abscissa::Uneven(Vec::new())
        },
        z_value,
        axes,
        ordinate: if complex {
            Ordinate::Complex(Vec::new())
        } else {
            Ordinate::Real(Vec::new())
        },
        binary: false,
    };
    let per_point = match (complex, even) {
        (false, true) => 1,
        (true, false) => 3,
        _ => 2,
    };
    let count = points as usize * per_point;
    Ok((f, count))
}

/// Record 7: three integers (I10) then three reals (E13.5), by columns, or separated by blanks.
pub(super) fn ints_then_nums(
    path: &Path,
    ln: usize,
    l: &str,
) -> Result<([i64; 3], [f64; 3]), IoError> {
    let by_columns = || -> Result<([i64; 3], [f64; 3]), IoError> {
        let mut r = [0.0; 3];
        for (k, v) in r.iter_mut().enumerate() {
            *v = match col(l, 30 + 13 * k, 43 + 13 * k).trim() {
                "" => 0.0,
                t => num(path, ln, t)?,
            };
        }
        Ok((
            [
                col_int(path, ln, l, 0, 10)?,
                col_int(path, ln, l, 10, 20)?,
                col_int(path, ln, l, 20, 30)?,
            ],
            r,
        ))
    };
    by_columns().or_else(|e| {
        let t: Vec<&str> = l.split_whitespace().collect();
        if t.len() != 6 {
            return Err(e);
        }
        Ok((
            [
                int(path, ln, t[0])?,
                int(path, ln, t[1])?,
                int(path, ln, t[2])?,
            ],
            [
                num(path, ln, t[3])?,
                num(path, ln, t[4])?,
                num(path, ln, t[5])?,
            ],
        ))
    })
}

/// The values of record 12 as text: blank-separated numbers, or fields of 13 and 20 columns run
/// together (the widths of the data type).
pub(super) fn parse_58_ascii(
    path: &Path,
    body: &[(usize, &str)],
    f: &UffFunction,
) -> Result<Vec<f64>, IoError> {
    let widths: &[usize] = match (f.data_type(), f.per_point()) {
        (2 | 5, _) => &[13],
        (4, 2) => &[13, 20],
        (6, 3) => &[13, 20, 20],
        _ => &[20],
    };
    let mut v = Vec::new();
    for &(ln, l) in body {
        if l.trim().is_empty() {
            continue;
        }
        match nums(path, ln, l, 1) {
            Ok(x) => v.extend(x),
            Err(e) => {
                // fields run together: cut by the format's widths
                let (mut at, mut k) = (0, 0);
                let mut any = false;
                while at < l.len() {
                    let w = widths[k % widths.len()];
                    let t = col(l, at, at + w).trim();
                    if !t.is_empty() {
                        v.push(num(path, ln, t)?);
                        any = true;
                    }
                    at += w;
                    k += 1;
                }
                if !any {
                    return Err(e);
                }
            }
        }
    }
    Ok(v)
}

/// Puts the stored values into the function, checking their count.
pub(super) fn finish_58(
    path: &Path,
    mut f: UffFunction,
    values: Vec<f64>,
    count: usize,
    start: usize,
) -> Result<UffFunction, IoError> {
    let per = f.per_point();
    if values.len() != count || count == 0 {
        return Err(perr(
            path,
            start,
            format!(
                "dataset 58: record 7 announces {} points ({count} values), {} values found",
                count / per,
                values.len()
            ),
        ));
    }
    let points = values.len() / per;
    let complex = matches!(f.ordinate, Ordinate::Complex(_));
    let off = usize::from(matches!(f.abscissa, Abscissa::Uneven(_)));
    if off == 1 {
        f.abscissa = Abscissa::Uneven((0..points).map(|k| values[k * per]).collect());
    }
    f.ordinate = if complex {
        Ordinate::Complex(
            (0..points)
                .map(|k| (values[k * per + off], values[k * per + off + 1]))
                .collect(),
        )
    } else {
        Ordinate::Real((0..points).map(|k| values[k * per + off]).collect())
    };
    Ok(f)
}

/// Dataset 58b: the header line's fields, the 11 text records, then the binary values.
pub(super) fn parse_58b(
    path: &Path,
    src: &mut ByteLines<'_>,
    start: usize,
    head: &str,
    warnings: &mut Vec<Warning>,
) -> Result<UffFunction, IoError> {
    let h: Vec<i64> = head
        .split_whitespace()
        .skip(1)
        .map(|t| int(path, start, t))
        .collect::<Result<_, _>>()?;
    if h.len() < 4 {
        return Err(perr(
            path,
            start,
            "dataset 58b header: expected byte order, number format, text lines and bytes",
        ));
    }
    let big = match h[0] {
        1 => false,
        2 => true,
        o => {
            return Err(perr(
                path,
                start,
                format!("byte order {o}: expected 1 (little endian) or 2 (big endian)"),
            ));
        }
    };
    if h[1] != 2 {
        return Err(perr(
            path,
            start,
            format!("number format {}: femu reads IEEE 754 (2) only", h[1]),
        ));
    }
    if h[2] != 11 {
        return Err(perr(
            path,
            start,
            format!("{} text records: dataset 58b has 11", h[2]),
        ));
    }
    let mut owned = Vec::with_capacity(11);
    for _ in 0..11 {
        let (l, t) = src
            .next_line()
            .ok_or_else(|| perr(path, start, "dataset 58b ends inside its 11 text records"))?;
        owned.push((l, t.into_owned()));
    }
    // a delimiter among the text records is a truncated dataset, not an identification line
    if let Some((l, _)) = owned.iter().find(|(_, t)| t.trim() == "-1") {
        return Err(perr(
            path,
            *l,
            "dataset 58b ends inside its 11 text records",
        ));
    }
    let body: Vec<(usize, &str)> = owned.iter().map(|(l, t)| (*l, t.as_str())).collect();
    let (mut f, count) = parse_58_header(path, &body, start)?;
    let size = if f.double { 8 } else { 4 };
    let bytes = count * size;
    if h[3] != bytes as i64 {
        warnings.push(Warning {
            path: path.to_path_buf(),
            line: start,
            message: format!(
                "dataset 58b: the header says {} bytes, record 7 needs {bytes} ({count} values of {size} bytes); read {bytes}",
                h[3]
            ),
        });
    }
    let at = src.at;
    if src.b.len() - at < bytes {
        return Err(perr(
            path,
            src.line + 1,
            format!(
                "dataset 58b: {bytes} bytes of values expected, the file has {} left (byte offset {at})",
                src.b.len() - at
            ),
        ));
    }
    let data = &src.b[at..at + bytes];
    let mut values = Vec::with_capacity(count);
    for (k, c) in data.chunks_exact(size).enumerate() {
        let v = if f.double {
            let a: [u8; 8] = c.try_into().expect("8 bytes");
            if big {
                f64::from_be_bytes(a)
            } else {
                f64::from_le_bytes(a)
            }
        } else {
            let a: [u8; 4] = c.try_into().expect("4 bytes");
            (if big {
                f32::from_be_bytes(a)
            } else {
                f32::from_le_bytes(a)
            }) as f64
        };
        if !v.is_finite() {
            return Err(perr(
                path,
                src.line + 1,
                format!(
                    "dataset 58b: value {k} is {v} (byte offset {})",
                    at + k * size
                ),
            ));
        }
        values.push(v);
    }
    // the newlines inside the binary block still count as lines for later messages
    src.line += data.iter().filter(|c| **c == b'\n').count();
    src.at = at + bytes;
    f.binary = true;
    finish_58(path, f, values, count, start)
}

/// Dataset 2477: per group a header (8I10, the last the entity count), the name, then entities
/// as (type, tag, 0, 0) quadruples, two per line; types other than nodes (7) and elements (8)
/// are skipped with a warning.
pub(super) fn function_records(f: &UffFunction, s: &mut String) {
    for id in &f.ids {
        let _ = writeln!(s, "{}", field(id, 80));
    }
    let dof = |d: &UffDof| {
        format!(
            " {:<10}{:>10}{:>4}",
            field(&d.entity, 10),
            d.node,
            d.direction
        )
    };
    let _ = writeln!(
        s,
        "{:>5}{:>10}{:>5}{:>10}{}{}",
        f.function_type,
        f.numbers[0],
        f.numbers[1],
        f.numbers[2],
        dof(&f.response),
        dof(&f.reference)
    );
    let (spacing, min, step) = match f.abscissa {
        Abscissa::Even { min, step } => (1, min, step),
        Abscissa::Uneven(_) => (0, 0.0, 0.0),
    };
    let _ = writeln!(
        s,
        "{:>10}{:>10}{:>10}{}{}{}",
        f.data_type(),
        f.ordinate.len(),
        spacing,
        e13(min),
        e13(step),
        e13(f.z_value)
    );
    for a in &f.axes {
        let _ = writeln!(
            s,
            "{:>10}{:>5}{:>5}{:>5} {:<20} {:<20}",
            a.data_type,
            a.exponents[0],
            a.exponents[1],
            a.exponents[2],
            field(&a.label, 20),
            field(&a.units, 20)
        );
    }
}

/// Dataset 58 (ASCII) or 58b (binary, little endian) of one function.
pub(super) fn function_bytes(f: &UffFunction, binary: bool, out: &mut Vec<u8>) {
    let values = f.stored();
    let mut s = String::from("    -1\n");
    let size = if f.double { 8 } else { 4 };
    if binary {
        let _ = writeln!(
            s,
            "{:>6}b{:>6}{:>6}{:>12}{:>12}{:>6}{:>6}{:>12}{:>12}",
            58,
            1,
            2,
            11,
            values.len() * size,
            0,
            0,
            0,
            0
        );
    } else {
        s.push_str("    58\n");
    }
    function_records(f, &mut s);
    if binary {
        out.extend(s.as_bytes());
        for v in &values {
            if f.double {
                out.extend(v.to_le_bytes());
            } else {
                out.extend((*v as f32).to_le_bytes());
            }
        }
        out.extend(b"    -1\n");
        return;
    }
    // record 12: the widths of the data type, as many per line as the format has
    let (widths, per_line): (&[usize], usize) = match (f.data_type(), f.per_point()) {
        (2 | 5, _) => (&[13], 6),
        (4, 2) => (&[13, 20], 4),
        (6, 3) => (&[13, 20, 20], 3),
        _ => (&[20], 4),
    };
    for row in values.chunks(per_line) {
        for (k, v) in row.iter().enumerate() {
            let w = widths[k % widths.len()];
            s.push_str(&efmt(*v, w, if w == 13 { 5 } else { 12 }));
        }
        s.push('\n');
    }
    s.push_str("    -1\n");
    out.extend(s.as_bytes());
}
