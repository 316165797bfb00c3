//! The case control section (between `CEND` and `BEGIN BULK`), read by its grammar (Quick
//! Reference Guide, "Case Control Commands"): one command a line, `NAME = value` or `NAME value`,
//! `NAME(options) = value`, `$` starting a comment, a line ending in a comma continued on the next,
//! commands abbreviated to their first four letters, `SUBCASE n` opening a subcase whose commands
//! override those above the first subcase. femu takes what changes the model it builds: the `SPC`
//! and `MPC` sets, the `METHOD` (the `EIGRL` of the modes) and the `SDAMPING` (the modal damping
//! of the responses); subcases that select different ones are refused, since femu solves one
//! model (a subcase without `SDAMPING`, which computes no damped response, differs from none).

use super::cards::Line;
use crate::IoError;
use std::path::PathBuf;

/// One selection of a case control command: its value and where it was made.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct Selected {
    /// The set id selected.
    pub(super) id: i64,
    /// Its file.
    pub(super) path: PathBuf,
    /// Its line.
    pub(super) line: usize,
}

/// What femu reads of a case control.
#[derive(Debug, Clone, Default, PartialEq)]
pub(super) struct CaseControl {
    /// `SPC = n`, the same in every subcase.
    pub(super) spc: Option<Selected>,
    /// `MPC = n`, the same in every subcase.
    pub(super) mpc: Option<Selected>,
    /// `METHOD = n` (the `EIGRL` or `EIGR` of the modes), the same in every subcase.
    pub(super) method: Option<Selected>,
    /// `SDAMPING = n` (the `TABDMP1` of the modes' damping), the same in every subcase.
    pub(super) sdamping: Option<Selected>,
    /// The subcases' ids (empty: none).
    pub(super) subcases: Vec<i64>,
    /// The direct matrices (DMIG names) the case control adds, in any subcase: the command
    /// (`K2GG`, `M2GG`, `K42GG`, `B2GG`, `K2PP`, `M2PP`, `B2PP`), the name, its factor (`1.5*KX`;
    /// 1 without), where.
    pub(super) direct: Vec<(String, String, f64, PathBuf, usize)>,
}

/// The case control commands that add direct input matrices (QRG, "K2GG", "K2PP", ...).
const DIRECT: &[&str] = &["K2GG", "M2GG", "K42GG", "B2GG", "K2PP", "M2PP", "B2PP"];

/// What one scope (above the first subcase, or one subcase) selects.
#[derive(Debug, Clone, Default)]
struct Scope {
    id: Option<i64>,
    spc: Option<Selected>,
    mpc: Option<Selected>,
    method: Option<Selected>,
    sdamping: Option<Selected>,
}

/// The command word of a case control line (upper case, before `(`, `=` or a blank) and the value
/// after `=` (or after the word when there is no `=`).
fn command(text: &str) -> (String, String) {
    let t = text.trim();
    let end = t
        .find(|c: char| c == '(' || c == '=' || c.is_whitespace())
        .unwrap_or(t.len());
    let word = t[..end].to_ascii_uppercase();
    let rest = &t[end..];
    let value = match rest.find('=') {
        Some(i) => rest[i + 1..].trim(),
        None => rest.trim(),
    };
    (word, value.to_string())
}

/// Whether `word` names the command `full` (its full name, or an abbreviation of at least four
/// letters, as Nastran accepts).
fn is(word: &str, full: &str) -> bool {
    word == full || (word.len() >= 4 && full.starts_with(word))
}

impl CaseControl {
    /// Reads the case control of `lines` (everything before `BEGIN BULK`; the executive control
    /// up to `CEND` is skipped when present).
    ///
    /// # Errors
    /// A selection whose value is not an integer id, and subcases that select different `SPC` or
    /// `METHOD` sets (naming both lines).
    pub(super) fn parse(lines: &[Line]) -> Result<Self, IoError> {
        let start = lines
            .iter()
            .position(|(_, _, l)| {
                let (w, _) = command(l.split('$').next().unwrap_or(""));
                w == "CEND"
            })
            .map_or(0, |i| i + 1);
        let mut scopes = vec![Scope::default()];
        let mut direct = Vec::new();
        let mut joined = String::new();
        let mut at: Option<(PathBuf, usize)> = None;
        for (path, number, raw) in &lines[start..] {
            let text = raw.split('$').next().unwrap_or("").trim_end();
            if text.trim().is_empty() {
                continue;
            }
            if at.is_none() {
                at = Some((path.clone(), *number));
            }
            joined.push_str(text);
            // a trailing comma continues the command on the next line (SET lists)
            if text.ends_with(',') {
                continue;
            }
            let (path, line) = at.take().expect("set above");
            let (word, value) = command(&joined);
            joined.clear();
            let selected = |what: &str| -> Result<Selected, IoError> {
                value
                    .split_whitespace()
                    .next()
                    .and_then(|v| v.parse::<i64>().ok())
                    .map(|id| Selected {
                        id,
                        path: path.clone(),
                        line,
                    })
                    .ok_or_else(|| IoError::Parse {
                        path: path.clone(),
                        line,
                        reason: format!(
                            "case control {what} = {value:?}: femu reads a set id (an integer)"
                        ),
                    })
            };
            let scope = scopes.last_mut().expect("never empty");
            if word == "SUBCASE" {
                let id = value.trim().parse::<i64>().map_err(|_| IoError::Parse {
                    path: path.clone(),
                    line,
                    reason: format!("SUBCASE {value:?}: a subcase needs an integer id"),
                })?;
                scopes.push(Scope {
                    id: Some(id),
                    ..Default::default()
                });
            } else if DIRECT.contains(&word.as_str()) {
                // K2GG = KAAX, or a list of names each with an optional factor (1.5*KAAX),
                // in parentheses or not
                for item in value.split(',') {
                    let item = item.trim().trim_start_matches('(').trim_end_matches(')');
                    let (factor, name) = match item.rsplit_once('*') {
                        Some((f, n)) => (f.trim(), n),
                        None => ("", item),
                    };
                    let name = name.trim().to_ascii_uppercase();
                    let factor = if factor.is_empty() {
                        1.0
                    } else {
                        super::cards::real(factor)
                            .filter(|v| v.is_finite())
                            .ok_or_else(|| IoError::Parse {
                                path: path.clone(),
                                line,
                                reason: format!(
                                    "{word}: the factor {factor:?} of {name} is not a number"
                                ),
                            })?
                    };
                    if !name.is_empty() {
                        direct.push((word.clone(), name, factor, path.clone(), line));
                    }
                }
            } else if word == "SPC" {
                scope.spc = Some(selected("SPC")?);
            } else if word == "MPC" {
                scope.mpc = Some(selected("MPC")?);
            } else if is(&word, "SDAMPING") {
                // SDAMPING(STRUCTURE) = n and SDAMPING(FLUID) = n: the structure's
                let fluid = option_of(raw).is_some_and(|o| o == "FLUID");
                if !fluid {
                    scope.sdamping = Some(selected("SDAMPING")?);
                }
            } else if is(&word, "METHOD") {
                // METHOD(STRUCTURE) = n and METHOD(FLUID) = n: the structure's
                let fluid = option_of(raw).is_some_and(|o| o == "FLUID");
                if !fluid {
                    scope.method = Some(selected("METHOD")?);
                }
            }
        }
        let global = scopes[0].clone();
        let subcases: Vec<Scope> = scopes[1..].to_vec();
        let mut out = CaseControl {
            subcases: subcases.iter().filter_map(|s| s.id).collect(),
            direct,
            ..Default::default()
        };
        for (what, pick) in [
            (
                "SPC",
                (|s: &Scope| s.spc.clone()) as fn(&Scope) -> Option<Selected>,
            ),
            ("MPC", |s: &Scope| s.mpc.clone()),
            ("METHOD", |s: &Scope| s.method.clone()),
            ("SDAMPING", |s: &Scope| s.sdamping.clone()),
        ] {
            let mut chosen: Vec<(Option<i64>, Option<Selected>)> = if subcases.is_empty() {
                vec![(None, pick(&global))]
            } else {
                subcases
                    .iter()
                    .map(|s| (s.id, pick(s).or_else(|| pick(&global))))
                    .collect()
            };
            // SDAMPING damps the responses of the subcases that select it: one that selects none
            // (the normal modes subcase before a SOL 146 or SOL 111 response) does not differ
            if what == "SDAMPING" && chosen.iter().any(|c| c.1.is_some()) {
                chosen.retain(|c| c.1.is_some());
            }
            let first = chosen[0].clone();
            if let Some((other_id, other)) = chosen
                .iter()
                .find(|c| c.1.as_ref().map(|s| s.id) != first.1.as_ref().map(|s| s.id))
            {
                let name = |s: &Option<Selected>| {
                    s.as_ref().map_or("none".to_string(), |s| {
                        format!("{} ({} line {})", s.id, s.path.display(), s.line)
                    })
                };
                let (path, line) = other
                    .as_ref()
                    .or(first.1.as_ref())
                    .map(|s| (s.path.clone(), s.line))
                    .unwrap_or_default();
                return Err(IoError::Parse {
                    path,
                    line,
                    reason: format!(
                        "subcases {} and {} select different {what} sets ({} and {}): femu solves one model; keep one subcase, or make them select the same set",
                        first.0.unwrap_or(0),
                        other_id.unwrap_or(0),
                        name(&first.1),
                        name(other)
                    ),
                });
            }
            match what {
                "SPC" => out.spc = first.1,
                "MPC" => out.mpc = first.1,
                "METHOD" => out.method = first.1,
                _ => out.sdamping = first.1,
            }
        }
        Ok(out)
    }
}

/// The option in parentheses of a command line (`METHOD(FLUID) = 2` gives `FLUID`), upper case.
fn option_of(raw: &str) -> Option<String> {
    let t = raw.split('$').next().unwrap_or("");
    let open = t.find('(')?;
    let eq = t.find('=').unwrap_or(t.len());
    if open > eq {
        return None;
    }
    let close = t[open..].find(')')? + open;
    Some(t[open + 1..close].trim().to_ascii_uppercase())
}
