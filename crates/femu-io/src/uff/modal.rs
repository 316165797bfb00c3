//! Units (164) and modal data (55: real normal modes and complex modes).

use super::*;

pub(super) fn parse_164(
    path: &Path,
    body: &[(usize, &str)],
    out: &mut Universal,
) -> Result<(), IoError> {
    if body.len() < 2 {
        return Err(perr(
            path,
            body.first().map_or(0, |b| b.0),
            "dataset 164 needs 2 records",
        ));
    }
    let (ln, l) = body[0];
    let code = int(path, ln, l.get(..10).unwrap_or(l).trim())?;
    let description = l.get(10..30).unwrap_or("").trim().to_string();
    let f = nums(path, body[1].0, body[1].1, 3)?;
    out.units = Some(UffUnits {
        code,
        description,
        factors: [f[0], f[1], f[2]],
    });
    Ok(())
}

pub(super) fn parse_55(
    path: &Path,
    body: &[(usize, &str)],
    out: &mut Universal,
) -> Result<(), IoError> {
    if body.len() < 8 {
        return Err(perr(
            path,
            body.first().map_or(0, |b| b.0),
            "dataset 55 needs at least 8 records",
        ));
    }
    let (l6, r6) = body[5];
    let h = ints(path, l6, r6, 6)?;
    let (analysis, characteristic, data_type, ndv) = (h[1], h[2], h[4], h[5]);
    if !(characteristic == 2 || characteristic == 3) {
        return Err(perr(
            path,
            l6,
            format!("data characteristic {characteristic}: femu reads translations (2 or 3)"),
        ));
    }
    let complex = match data_type {
        2 => false,
        5 => true,
        o => {
            return Err(perr(
                path,
                l6,
                format!("data type {o}: expected 2 (real) or 5 (complex)"),
            ));
        }
    };
    // 3 translations, or 6 with rotations; an absurd count is an error, not an allocation
    if !(3..=6).contains(&ndv) {
        return Err(perr(
            path,
            l6,
            format!("{ndv} values per node: expected 3 (translations) to 6 (with rotations)"),
        ));
    }
    let (l7, r7) = body[6];
    let r7v = ints(path, l7, r7, 4)?;
    let (nint, nrdv) = (r7v[0], r7v[1]);
    let number = r7v.get(3).copied().unwrap_or(0);
    // the real parameters may wrap over several lines of 6
    let per_line = 6usize;
    let rec8_lines = (nrdv.max(0) as usize).div_ceil(per_line).max(1);
    let _ = nint;
    let mut reals = Vec::new();
    for k in 0..rec8_lines {
        let (ln, l) = *body
            .get(7 + k)
            .ok_or_else(|| perr(path, l7, "record 8 is missing"))?;
        reals.extend(nums(path, ln, l, 1)?);
    }
    let (frequency_hz, modal_mass, damping) = match analysis {
        2 => {
            if reals.len() < 3 {
                return Err(perr(
                    path,
                    body[7].0,
                    "a normal mode needs frequency, modal mass and damping",
                ));
            }
            (reals[0], reals[1], reals[2])
        }
        3 => {
            if reals.len() < 2 {
                return Err(perr(path, body[7].0, "a complex mode needs its eigenvalue"));
            }
            let (re, im) = (reals[0], reals[1]);
            let w = re.hypot(im);
            (
                w / (2.0 * std::f64::consts::PI),
                0.0,
                if w > 0.0 { -re / w } else { 0.0 },
            )
        }
        o => {
            return Err(perr(
                path,
                l6,
                format!("analysis type {o}: femu reads normal (2) and complex (3) modes"),
            ));
        }
    };
    if !(frequency_hz > 0.0) {
        return Err(perr(
            path,
            body[7].0,
            format!("frequency {frequency_hz} Hz must be positive"),
        ));
    }
    let width = if complex {
        2 * ndv as usize
    } else {
        ndv as usize
    };
    let mut values = Vec::new();
    let k = 7 + rec8_lines;
    let raw = node_values(path, &body[k..], width)?;
    let complexity = complexity_of(&raw, complex);
    let (real, imaginary) = translations(raw, complex);
    values.extend(real);
    out.modes.push(UffMode {
        number,
        frequency_hz,
        damping,
        modal_mass,
        values,
        complex,
        complexity,
        imaginary,
    });
    Ok(())
}

/// Records of a node label followed by `width` values (over as many lines as they take).
fn node_values(
    path: &Path,
    body: &[(usize, &str)],
    width: usize,
) -> Result<Vec<(u64, Vec<f64>)>, IoError> {
    let mut raw = Vec::new();
    let mut k = 0;
    while k < body.len() {
        let (ln, l) = body[k];
        if l.trim().is_empty() {
            k += 1;
            continue;
        }
        let node = int(path, ln, l.split_whitespace().next().unwrap_or(""))?;
        if node <= 0 {
            return Err(perr(
                path,
                ln,
                format!("node label {node} must be positive"),
            ));
        }
        let mut v = Vec::with_capacity(width);
        k += 1;
        while v.len() < width {
            let (ln2, l2) = *body.get(k).ok_or_else(|| {
                perr(
                    path,
                    ln,
                    format!("node {node}: {width} values expected, found {}", v.len()),
                )
            })?;
            v.extend(nums(path, ln2, l2, 1)?);
            k += 1;
        }
        if v.len() != width {
            return Err(perr(
                path,
                ln,
                format!("node {node}: {width} values expected, found {}", v.len()),
            ));
        }
        raw.push((node as u64, v));
    }
    Ok(raw)
}

/// MPC and MPD of a complex mode's translations (`None` for real data).
fn complexity_of(raw: &[(u64, Vec<f64>)], complex: bool) -> Option<femu_correlate::Complexity> {
    if !complex {
        return None;
    }
    let components: Vec<(f64, f64)> = raw
        .iter()
        .flat_map(|(_, v)| (0..3).map(move |c| (v[2 * c], v[2 * c + 1])))
        .collect();
    femu_correlate::Complexity::of(&components)
}

/// The translations of each node; complex values rotated by the phase of the mode's largest
/// component and their real part taken (a real mode stored as complex comes back exactly), and
/// for complex data the imaginary parts of the same turned values, node by node.
#[allow(clippy::type_complexity)]
fn translations(
    raw: Vec<(u64, Vec<f64>)>,
    complex: bool,
) -> (Vec<(u64, [f64; 3])>, Option<Vec<[f64; 3]>>) {
    if !complex {
        let real = raw
            .into_iter()
            .map(|(n, v)| (n, [v[0], v[1], v[2]]))
            .collect();
        return (real, None);
    }
    let (mut best, mut phase) = (0.0, 0.0);
    for (_, v) in &raw {
        for c in 0..3 {
            let (re, im) = (v[2 * c], v[2 * c + 1]);
            if re.hypot(im) > best {
                best = re.hypot(im);
                phase = im.atan2(re);
            }
        }
    }
    // (re + i im) e^(-i phase)
    let (cs, sn) = (phase.cos(), phase.sin());
    let imaginary = raw
        .iter()
        .map(|(_, v)| std::array::from_fn(|c| v[2 * c + 1] * cs - v[2 * c] * sn))
        .collect();
    let real = raw
        .into_iter()
        .map(|(n, v)| {
            let r = |c: usize| v[2 * c] * cs + v[2 * c + 1] * sn;
            (n, [r(0), r(1), r(2)])
        })
        .collect();
    (real, Some(imaginary))
}

/// Dataset 2414 (analysis results): the normal and complex modes another FE code computed, at
/// nodes, read as modes (so femu can correlate its modes with another solver's). Other results
/// (static, transient, stresses, element data) are skipped with a warning.
pub(super) fn parse_2414(
    path: &Path,
    body: &[(usize, &str)],
    out: &mut Universal,
) -> Result<(), IoError> {
    let start = body.first().map_or(0, |b| b.0);
    if body.len() < 13 {
        return Err(perr(path, start, "dataset 2414 needs at least 13 records"));
    }
    let skip = |out: &mut Universal, why: String| {
        out.warnings.push(Warning {
            path: path.to_path_buf(),
            line: start,
            message: format!("dataset 2414 {why}: skipped"),
        });
        Ok(())
    };
    let label = int(path, body[0].0, body[0].1.trim())?;
    let name = body[1].1.trim().to_string();
    let location = int(path, body[2].0, body[2].1.trim())?;
    if location != 1 {
        return skip(
            out,
            format!("{label} ({name}) holds data at location {location}, not at nodes (1)"),
        );
    }
    let (l9, r9) = body[8];
    let h = ints(path, l9, r9, 6)?;
    let (analysis, characteristic, data_type, ndv) = (h[1], h[2], h[4], h[5]);
    let analysis_name = match analysis {
        2 => "normal mode",
        3 | 7 => "complex eigenvalue",
        0 => "unknown analysis",
        1 => "static",
        4 => "transient",
        5 => "frequency response",
        6 => "buckling",
        _ => "other analysis",
    };
    if !matches!(analysis, 2 | 3 | 7) {
        return skip(
            out,
            format!("{label} ({name}) is a {analysis_name} result, not a mode"),
        );
    }
    if !(characteristic == 2 || characteristic == 3) {
        return skip(
            out,
            format!(
                "{label} ({name}) has data characteristic {characteristic}, not translations (2 or 3)"
            ),
        );
    }
    let complex = match data_type {
        2 | 4 => false,
        5 | 6 => true,
        o => {
            return Err(perr(
                path,
                l9,
                format!("data type {o}: expected 2 or 4 (real), 5 or 6 (complex)"),
            ));
        }
    };
    if !(3..=6).contains(&ndv) {
        return Err(perr(
            path,
            l9,
            format!("{ndv} values per node: expected 3 (translations) to 6 (with rotations)"),
        ));
    }
    let i10 = ints(path, body[9].0, body[9].1, 6)?;
    let number = i10[5];
    let mut reals = nums(path, body[11].0, body[11].1, 3)?;
    reals.extend(nums(path, body[12].0, body[12].1, 2)?);
    let (frequency_hz, modal_mass, damping) = if analysis == 2 {
        let f = if reals[1] > 0.0 {
            reals[1]
        } else {
            reals[2].max(0.0).sqrt() / (2.0 * std::f64::consts::PI)
        };
        (f, reals[3], reals.get(4).copied().unwrap_or(0.0))
    } else {
        // record 13: the eigenvalue's real and imaginary parts
        let (re, im) = (reals[6], reals.get(7).copied().unwrap_or(0.0));
        let w = re.hypot(im);
        (
            w / (2.0 * std::f64::consts::PI),
            0.0,
            if w > 0.0 { -re / w } else { 0.0 },
        )
    };
    if !(frequency_hz > 0.0 && frequency_hz.is_finite()) {
        return Err(perr(
            path,
            body[11].0,
            format!(
                "mode {number} of dataset 2414 {label}: frequency {frequency_hz} Hz must be positive"
            ),
        ));
    }
    let width = if complex {
        2 * ndv as usize
    } else {
        ndv as usize
    };
    let raw = node_values(path, &body[13..], width)?;
    let complexity = complexity_of(&raw, complex);
    let (values, imaginary) = translations(raw, complex);
    out.modes.push(UffMode {
        number,
        frequency_hz,
        damping,
        modal_mass,
        values,
        complex,
        complexity,
        imaginary,
    });
    out.modes_from_2414 += 1;
    Ok(())
}
