//! The references from the code to femu's notes resolve: every `docs/<note>.md, "Heading"` cited in
//! a doc comment or comment of the sources, benches, examples and tests names a note that exists
//! and a heading (or a paragraph's bold or plain lead, as `**Heading.**`) that it contains. A
//! reference to a section renamed or removed fails here instead of sending a reader nowhere.

use std::path::{Path, PathBuf};

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for entry in entries.flatten() {
        let path = entry.path();
        let name = entry.file_name();
        if path.is_dir() {
            if name != "target" && !name.to_string_lossy().starts_with('.') {
                rust_files(&path, out);
            }
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

/// The text with comment markers removed and every run of whitespace made one space, so that a
/// reference broken over two comment lines reads as one.
fn flatten(text: &str) -> String {
    let mut words = Vec::new();
    for line in text.lines() {
        let t = line.trim_start();
        let t = ["//!", "///", "//"]
            .iter()
            .find_map(|m| t.strip_prefix(m))
            .unwrap_or(t);
        words.extend(t.split_whitespace());
    }
    words.join(" ")
}

/// `(note, heading)` for every `docs/<note>.md, "Heading"` in `text`.
fn references(text: &str) -> Vec<(String, String)> {
    let mut out = Vec::new();
    let mut rest = text;
    while let Some(i) = rest.find("docs/") {
        rest = &rest[i + 5..];
        let Some(end) = rest.find(".md") else { break };
        let note = &rest[..end];
        if note.is_empty() || !note.chars().all(|c| c.is_ascii_alphanumeric() || c == '_') {
            continue;
        }
        let after = &rest[end + 3..];
        let Some(quoted) = after.strip_prefix(", \"") else {
            continue;
        };
        let Some(close) = quoted.find('"') else { break };
        out.push((format!("{note}.md"), quoted[..close].to_string()));
    }
    out
}

/// Whether a line of the note, without its heading marks or bold, starts with `heading`.
fn contains_heading(note: &str, heading: &str) -> bool {
    note.lines().any(|line| {
        let t = line.trim_start_matches(['#', ' ', '*', '-']);
        t.starts_with(heading)
    })
}

#[test]
fn references_to_the_notes_name_sections_that_exist() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut files = Vec::new();
    for dir in ["src", "crates", "benches", "examples", "tests"] {
        rust_files(&root.join(dir), &mut files);
    }
    assert!(files.len() > 50, "found only {} sources", files.len());
    let mut checked = 0;
    let mut broken = Vec::new();
    for file in &files {
        let text = std::fs::read_to_string(file).unwrap();
        for (note, heading) in references(&flatten(&text)) {
            let path = root.join("docs").join(&note);
            let ok = std::fs::read_to_string(&path).is_ok_and(|n| contains_heading(&n, &heading));
            if !ok {
                broken.push(format!(
                    "{}: docs/{note}, \"{heading}\"",
                    file.strip_prefix(root).unwrap_or(file).display()
                ));
            }
            checked += 1;
        }
    }
    assert!(checked > 20, "found only {checked} references");
    assert!(
        broken.is_empty(),
        "references to no section:\n{}",
        broken.join("\n")
    );
}

/// The parser itself, on a reference split over two comment lines and on text that only looks
/// like one.
#[test]
fn reference_parser_reads_split_references() {
    let text =
        "/// see (docs/MATH.md, \"Multipoint\n/// constraints\") and docs/x.md and docs/A.md, 3";
    assert_eq!(
        references(&flatten(text)),
        vec![("MATH.md".to_string(), "Multipoint constraints".to_string())]
    );
    assert!(contains_heading(
        "# T\n\n## Multipoint constraints\n",
        "Multipoint constraints"
    ));
    assert!(contains_heading(
        "**Repeated modes.** text",
        "Repeated modes"
    ));
    assert!(!contains_heading(
        "see Multipoint constraints",
        "Multipoint constraints"
    ));
}
