//! The demo report says what its numbers mean: every heading, table header, legend and verdict of
//! `report.md`, and every label of its two charts, as a reviewed snapshot. Numbers are masked
//! (`#`): they are checked elsewhere against references; here the words around them are.

use femu_study::demo::{DemoOptions, run_demo};

/// Every measured number replaced by `#`: a token of digits with a decimal point, an exponent or
/// three digits or more (with its sign). Small integers stay: table and figure numbers, exponents
/// of units (`s^-2`), mode numbers, counts of the fixed quick demo.
fn mask_numbers(text: &str) -> String {
    let chars: Vec<char> = text.chars().collect();
    let mut out = String::new();
    let mut i = 0;
    while i < chars.len() {
        if !chars[i].is_ascii_digit() {
            out.push(chars[i]);
            i += 1;
            continue;
        }
        let start = i;
        let mut masked = false;
        while i < chars.len() {
            let c = chars[i];
            let exponent = (c == 'e' || c == 'E')
                && chars
                    .get(i + 1)
                    .is_some_and(|n| n.is_ascii_digit() || *n == '-' || *n == '+');
            let exponent_sign = (c == '-' || c == '+') && matches!(chars[i - 1], 'e' | 'E');
            let decimal = c == '.' && chars.get(i + 1).is_some_and(char::is_ascii_digit);
            if c.is_ascii_digit() || exponent || exponent_sign || decimal {
                masked |= exponent || decimal;
                i += 1;
            } else {
                break;
            }
        }
        let token: String = chars[start..i].iter().collect();
        if masked || token.len() >= 3 {
            if out.ends_with(['-', '+']) && !out.ends_with("^-") {
                out.pop();
            }
            out.push('#');
        } else {
            out.push_str(&token);
        }
    }
    out
}

/// The text of every `<text>` element of an SVG, once each.
fn svg_labels(svg: &str) -> Vec<String> {
    let mut labels: Vec<String> = Vec::new();
    for part in svg.split("<text").skip(1) {
        let Some(start) = part.find('>') else {
            continue;
        };
        let Some(end) = part.find("</text>") else {
            continue;
        };
        let label = mask_numbers(&part[start + 1..end]);
        if !labels.contains(&label) {
            labels.push(label);
        }
    }
    labels
}

#[test]
fn demo_report_headers_legends_and_chart_labels() {
    let out = std::env::temp_dir().join(format!("femu-report-headers-{}", std::process::id()));
    let options = DemoOptions {
        out: out.clone(),
        ..DemoOptions::quick()
    };
    run_demo(&options, |_| {}).unwrap();
    let report = std::fs::read_to_string(out.join("report.md")).unwrap();
    // table rows are numbers; keep headings, table headers and the prose around the tables
    let mut kept = Vec::new();
    let lines: Vec<&str> = report.lines().collect();
    for (i, line) in lines.iter().enumerate() {
        let header =
            line.starts_with('|') && lines.get(i + 1).is_some_and(|n| n.starts_with("|---"));
        if !line.starts_with('|') || header {
            kept.push(mask_numbers(line));
        }
    }
    // the verdicts of Table 2 are words: keep the distinct ones
    let mut verdicts: Vec<String> = lines
        .iter()
        .filter(|l| l.contains("the gap"))
        .filter_map(|l| l.split('|').nth(7))
        .map(|v| mask_numbers(v.trim()))
        .collect();
    verdicts.sort();
    verdicts.dedup();
    let mut snapshot = kept.join("\n");
    snapshot.push_str("\n\n== Table 2 verdicts\n");
    snapshot.push_str(&verdicts.join("\n"));
    for chart in ["figure1.svg", "error_map.svg"] {
        let svg = std::fs::read_to_string(out.join(chart)).unwrap();
        snapshot.push_str(&format!("\n\n== {chart} labels\n"));
        snapshot.push_str(&svg_labels(&svg).join("\n"));
    }
    let _ = std::fs::remove_dir_all(&out);
    insta::assert_snapshot!(snapshot);
}
