//! From lines to cards, as the Quick Reference Guide's "Format of Bulk Data Entries" reads them:
//! small field (10 fields of 8 characters), large field (`NAME*`: 16-character data fields, four a
//! line, continued by a line starting with `*`) and free field (commas; a free-field line holds
//! the name, eight data fields and the continuation label, four data fields when large), `$`
//! comments, `INCLUDE`; a tab in a fixed-field line moves to the next field of 8 columns (the
//! tab stops Nastran reads such decks with). A continuation line starts with `+`, `*` or a blank field 1; when its
//! field 1 carries a label (`+A001`), it continues the card whose field 10 holds that label,
//! wherever that card is, as Nastran pairs them; a bare `+`, `*` or blank continues the card above.

use super::case_control::CaseControl;
use crate::IoError;
use std::path::{Path, PathBuf};

/// One card: its name, its fields after the name (blank = `""`), where it starts.
#[derive(Debug, Clone)]
pub(super) struct Card {
    pub(super) name: String,
    pub(super) fields: Vec<String>,
    pub(super) path: PathBuf,
    pub(super) line: usize,
}

impl Card {
    /// A parse error at this card's file and line, the card's name first.
    pub(super) fn err(&self, reason: String) -> IoError {
        IoError::Parse {
            path: self.path.clone(),
            line: self.line,
            reason: format!("{} {reason}", self.name),
        }
    }

    /// A model error at this card's file and line.
    pub(super) fn located(&self) -> impl FnOnce(femu_fem::FemError) -> IoError + '_ {
        move |source| IoError::Model {
            path: self.path.clone(),
            line: self.line,
            source,
        }
    }

    /// Data field `i` (0-based: field 2 of the card is 0), trimmed; `""` when blank or absent.
    pub(super) fn field(&self, i: usize) -> &str {
        self.fields.get(i).map_or("", |s| s.trim())
    }

    pub(super) fn int(&self, i: usize, what: &str) -> Result<Option<i64>, IoError> {
        let t = self.field(i);
        if t.is_empty() {
            return Ok(None);
        }
        t.parse::<i64>()
            .map(Some)
            .map_err(|_| self.err(format!("field {} ({what}): {t:?} is not an integer", i + 2)))
    }

    pub(super) fn id(&self, i: usize, what: &str) -> Result<u64, IoError> {
        match self.int(i, what)? {
            Some(v) if v > 0 => Ok(v as u64),
            Some(v) => Err(self.err(format!("field {} ({what}): {v} must be positive", i + 2))),
            None => Err(self.err(format!("field {} ({what}) is missing", i + 2))),
        }
    }

    pub(super) fn real(&self, i: usize, what: &str) -> Result<Option<f64>, IoError> {
        let t = self.field(i);
        if t.is_empty() {
            return Ok(None);
        }
        real(t)
            .map(Some)
            .ok_or_else(|| self.err(format!("field {} ({what}): {t:?} is not a number", i + 2)))
    }
}

/// A Nastran real: `1.5`, `1.5E+3`, `1.5D3`, and the implicit exponents `7.+10`, `1.-3`,
/// `-2.5-4`. Integers are accepted where a real is expected.
pub fn real(s: &str) -> Option<f64> {
    let t = s.trim();
    if let Ok(v) = t.parse::<f64>() {
        return v.is_finite().then_some(v);
    }
    let t = t.replace(['D', 'd'], "E");
    if let Ok(v) = t.parse::<f64>() {
        return v.is_finite().then_some(v);
    }
    // a sign after the first character, not after an E: the exponent
    let b = t.as_bytes();
    let at = (1..b.len())
        .find(|&i| (b[i] == b'+' || b[i] == b'-') && b[i - 1] != b'E' && b[i - 1] != b'e')?;
    let v: f64 = format!("{}E{}", &t[..at], &t[at..]).parse().ok()?;
    v.is_finite().then_some(v)
}

/// A numbered line of a deck: its file, its 1-based number, its text.
pub(super) type Line = (PathBuf, usize, String);

/// Lines with their file and number, `INCLUDE`s expanded.
pub(super) fn load(path: &Path, depth: usize, out: &mut Vec<Line>) -> Result<(), IoError> {
    if depth > 16 {
        return Err(IoError::Content {
            path: path.to_path_buf(),
            reason: "INCLUDE nested more than 16 deep (an include cycle?)".into(),
        });
    }
    let bytes = std::fs::read(path).map_err(|e| IoError::io(path, e))?;
    let text = String::from_utf8_lossy(&bytes);
    for (i, raw) in text.lines().enumerate() {
        let l = raw.trim_end_matches('\r');
        let head = l.trim_start();
        if head.len() >= 7 && head[..7].eq_ignore_ascii_case("INCLUDE") {
            let name = head[7..]
                .trim()
                .trim_matches(|c| c == '\'' || c == '"')
                .trim();
            let target = path.parent().unwrap_or(Path::new(".")).join(name);
            if !target.exists() {
                return Err(IoError::Parse {
                    path: path.to_path_buf(),
                    line: i + 1,
                    reason: format!("INCLUDE {name}: {} does not exist", target.display()),
                });
            }
            load(&target, depth + 1, out)?;
            continue;
        }
        out.push((path.to_path_buf(), i + 1, l.to_string()));
    }
    Ok(())
}

/// One physical line of bulk data: field 1 (a name or a continuation mark), the data fields
/// (eight, or four on a large-field line), field 10 (the continuation label).
#[derive(Debug, Clone, PartialEq)]
pub(super) struct Physical {
    pub(super) first: String,
    pub(super) fields: Vec<String>,
    pub(super) label: String,
}

/// The physical lines one text line stands for: one, except a free-field line with more data
/// fields than a line holds, whose extra fields continue it (each further line eight data fields,
/// or four when large, and a label field).
pub(super) fn split(l: &str) -> Vec<Physical> {
    let l = match l.find('$') {
        Some(i) => &l[..i],
        None => l,
    };
    if l.contains(',') {
        let mut t: Vec<String> = l.split(',').map(|s| s.trim().to_string()).collect();
        let first = t.remove(0);
        let large = first.ends_with('*') || first.starts_with('*');
        let width = if large { 4 } else { 8 };
        let mut out = Vec::new();
        let mut rest = t.as_slice();
        let mut head = first;
        loop {
            let take = rest.len().min(width);
            let mut fields: Vec<String> = rest[..take].to_vec();
            // a line with fewer data fields than it holds: the rest are blank
            fields.resize(width, String::new());
            rest = &rest[take..];
            let label = if rest.is_empty() {
                String::new()
            } else {
                let label = rest[0].clone();
                rest = &rest[1..];
                label
            };
            let more = !rest.is_empty();
            out.push(Physical {
                first: head,
                fields,
                label: label.clone(),
            });
            if !more {
                break;
            }
            // the fields past field 10 continue the card: as the line labelled by field 10
            head = if large {
                format!("*{label}")
            } else {
                format!("+{label}")
            };
        }
        return out;
    }
    // a tab moves to the next field of 8 columns (the tab stops Nastran, and pyNastran's
    // `expandtabs`, read small-field lines with)
    let mut chars: Vec<char> = Vec::with_capacity(l.len());
    for ch in l.chars() {
        if ch == '\t' {
            chars.push(' ');
            while !chars.len().is_multiple_of(8) {
                chars.push(' ');
            }
        } else {
            chars.push(ch);
        }
    }
    let cut = |a: usize, b: usize| -> String {
        chars
            .get(a.min(chars.len())..b.min(chars.len()))
            .map(|c| c.iter().collect::<String>())
            .unwrap_or_default()
            .trim()
            .to_string()
    };
    let first = cut(0, 8);
    // a large-field card's name ends with '*', its continuations start with one
    let large = first.ends_with('*') || first.starts_with('*');
    let fields = if large {
        (0..4).map(|k| cut(8 + 16 * k, 24 + 16 * k)).collect()
    } else {
        (0..8).map(|k| cut(8 + 8 * k, 16 + 8 * k)).collect()
    };
    vec![Physical {
        first,
        fields,
        label: cut(72, 80),
    }]
}

/// Whether a line's field 1 marks a continuation.
fn is_continuation(first: &str) -> bool {
    first.is_empty() || first.starts_with('+') || first.starts_with('*')
}

/// A continuation label as Nastran compares them: without its leading `+` or `*`, upper case.
fn label_key(s: &str) -> String {
    s.trim()
        .trim_start_matches(['+', '*'])
        .trim()
        .to_ascii_uppercase()
}

/// Whether a continuation's field 1 (`cont`) names the parent's field 10 (`parent`): the same
/// label after a leading `+` or `*`, or, as Nastran pairs them, the same columns 2-8 whatever
/// column 1 holds (MSC Nastran pairs pyNastran's `pt145.bdf` FLFACT ending `KFREQ` with its
/// continuation `+FREQ`: its flutter summary lists the continuation's two values).
fn labels_match(parent: &str, cont: &str) -> bool {
    let tail = |s: &str| {
        let s = s.trim();
        s.get(1..).map(|t| t.trim().to_ascii_uppercase())
    };
    let key = label_key(cont);
    !key.is_empty()
        && (label_key(parent) == key
            || matches!((tail(parent), tail(cont)), (Some(a), Some(b)) if !a.is_empty() && a == b))
}

/// The deck split into its case control and its bulk data cards.
pub(super) struct Deck {
    /// The case control (empty when the file is bulk data only).
    pub(super) case_control: CaseControl,
    /// Whether the file has a case control section (`BEGIN BULK`).
    pub(super) has_case_control: bool,
    /// The bulk data cards in file order.
    pub(super) cards: Vec<Card>,
}

/// Splits the lines into the case control (before `BEGIN BULK`) and the bulk data's cards,
/// pairing continuations with their parents by label.
///
/// # Errors
/// A malformed case control command, a continuation whose label no card's field 10 holds, a
/// continuation before any card.
pub(super) fn deck(lines: &[Line]) -> Result<Deck, IoError> {
    let begin = lines.iter().position(|(_, _, l)| {
        l.trim_start()
            .to_ascii_uppercase()
            .starts_with("BEGIN BULK")
    });
    let (case_lines, bulk) = match begin {
        Some(b) => (&lines[..b], &lines[b + 1..]),
        None => (&lines[..0], lines),
    };
    let case_control = CaseControl::parse(case_lines)?;
    let mut out: Vec<Card> = Vec::new();
    // per card: the label of its last line's field 10, which a continuation names
    let mut open: Vec<String> = Vec::new();
    for (path, number, l) in bulk {
        let t = l.trim();
        if t.to_ascii_uppercase().starts_with("ENDDATA") {
            break;
        }
        if t.is_empty() || t.starts_with('$') {
            continue;
        }
        // a further BEGIN BULK opens the main bulk data again (MSC Nastran runs pyNastran's
        // ha144ds with two); BEGIN SUPER or AUXMODEL opens a partition femu does not read
        let upper = t.to_ascii_uppercase();
        if upper.starts_with("BEGIN") && !upper.starts_with("BEGIN,") {
            let words: Vec<&str> = upper
                .split(|c: char| c.is_whitespace() || c == '=')
                .filter(|w| !w.is_empty())
                .collect();
            if words.get(1) == Some(&"BULK") {
                continue;
            }
            return Err(IoError::Parse {
                path: path.clone(),
                line: *number,
                reason: format!(
                    "{t:?}: partitioned bulk data (superelements, auxiliary models) is not read; femu reads one model's bulk data"
                ),
            });
        }
        for p in split(l) {
            if is_continuation(&p.first) {
                let key = label_key(&p.first);
                let last_open = open.last().map_or(String::new(), |l| label_key(l));
                // a labelled continuation goes to the card whose field 10 holds the label; an
                // unlabelled one, or one the card above leaves unlabelled, to the card above
                let at = if key.is_empty() {
                    out.len().checked_sub(1)
                } else {
                    match open.iter().rposition(|o| labels_match(o, &p.first)) {
                        Some(i) => Some(i),
                        // a label no field 10 holds, below a card that leaves field 10 blank:
                        // written without labels on the parents, as many exporters do
                        None if last_open.is_empty() => out.len().checked_sub(1),
                        None => {
                            return Err(IoError::Parse {
                                path: path.clone(),
                                line: *number,
                                reason: format!(
                                    "continuation {}: no card above ends with the label {} in field 10 (the card just above, {} line {}, ends with {last_open:?})",
                                    p.first,
                                    p.first,
                                    out.last().map_or("", |c| c.name.as_str()),
                                    out.last().map_or(0, |c| c.line)
                                ),
                            });
                        }
                    }
                };
                let Some(at) = at else {
                    return Err(IoError::Parse {
                        path: path.clone(),
                        line: *number,
                        reason: format!(
                            "continuation {:?} before any card (field 1 starts with +, * or is blank)",
                            p.first
                        ),
                    });
                };
                out[at].fields.extend(p.fields);
                open[at] = p.label.clone();
                continue;
            }
            let name = p.first.trim_end_matches('*').to_ascii_uppercase();
            out.push(Card {
                name,
                fields: p.fields,
                path: path.clone(),
                line: *number,
            });
            open.push(p.label.clone());
        }
    }
    Ok(Deck {
        case_control,
        has_case_control: begin.is_some(),
        cards: out,
    })
}
