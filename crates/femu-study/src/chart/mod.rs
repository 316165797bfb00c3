//! femu's charts: self-contained SVG (no fonts or scripts needed to view it) and PNG rasterised
//! with the font shipped in this crate ([`svg_to_png`]).

mod png;

pub use png::{svg_to_png, write_png};

use femu_correlate::Method;
use femu_correlate::study::StudyPoint;
use femu_update::Localisation;
use std::fmt::Write as _;

/// The label of a study point's method: its name, or `full` when nothing was expanded.
pub fn method_label(method: Option<Method>) -> String {
    method.map_or_else(|| "full".to_string(), |m| m.name())
}

/// The sensor-removal study as an SVG line chart in the manner of the paper's Figure 1: `rho_M` (log scale)
/// against the number of measured nodes, one line per (method, test mode). Self-contained SVG
/// (no fonts or libraries needed to view it).
pub fn figure1_svg(points: &[StudyPoint]) -> String {
    let (w, h, left, right, top, bottom) = (760.0, 480.0, 80.0, 200.0, 30.0, 50.0);
    let (pw, ph) = (w - left - right, h - top - bottom);
    let mut s = String::new();
    let _ = writeln!(
        s,
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{w}\" height=\"{h}\" viewBox=\"0 0 {w} {h}\" font-family=\"sans-serif\" font-size=\"12\">"
    );
    let _ = writeln!(s, "<rect width=\"{w}\" height=\"{h}\" fill=\"white\"/>");
    let _ = writeln!(
        s,
        "<text x=\"{:.1}\" y=\"18\" text-anchor=\"middle\">rho_M of each test mode's expanded shape against the number of measured nodes</text>",
        left + pw / 2.0
    );
    let finite: Vec<&StudyPoint> = points
        .iter()
        .filter(|p| p.rho_m > 0.0 && p.rho_m.is_finite())
        .collect();
    if finite.is_empty() {
        let _ = writeln!(
            s,
            "<text x=\"{}\" y=\"{}\">no data</text>\n</svg>",
            w / 2.0,
            h / 2.0
        );
        return s;
    }
    let xmin = finite.iter().map(|p| p.nodes).min().unwrap_or(0) as f64;
    let xmax = (finite.iter().map(|p| p.nodes).max().unwrap_or(1) as f64).max(xmin + 1.0);
    let ymin = finite
        .iter()
        .map(|p| p.rho_m.log10())
        .fold(f64::INFINITY, f64::min)
        .floor();
    let ymax = finite
        .iter()
        .map(|p| p.rho_m.log10())
        .fold(f64::NEG_INFINITY, f64::max)
        .ceil()
        .max(ymin + 1.0);
    let px = |x: f64| left + (x - xmin) / (xmax - xmin) * pw;
    let py = |y: f64| top + (ymax - y) / (ymax - ymin) * ph;
    // axes, decade grid and labels
    let _ = writeln!(
        s,
        "<rect x=\"{left}\" y=\"{top}\" width=\"{pw}\" height=\"{ph}\" fill=\"none\" stroke=\"black\"/>"
    );
    let mut d = ymin;
    while d <= ymax + 1e-9 {
        let y = py(d);
        let _ = writeln!(
            s,
            "<line x1=\"{left}\" y1=\"{y:.1}\" x2=\"{:.1}\" y2=\"{y:.1}\" stroke=\"#ddd\"/>",
            left + pw
        );
        let _ = writeln!(
            s,
            "<text x=\"{:.1}\" y=\"{:.1}\" text-anchor=\"end\">1e{}</text>",
            left - 6.0,
            y + 4.0,
            d as i64
        );
        d += 1.0;
    }
    for k in 0..=5 {
        let xv = xmin + (xmax - xmin) * k as f64 / 5.0;
        let _ = writeln!(
            s,
            "<text x=\"{:.1}\" y=\"{:.1}\" text-anchor=\"middle\">{:.0}</text>",
            px(xv),
            top + ph + 18.0,
            xv
        );
    }
    let _ = writeln!(
        s,
        "<text x=\"{:.1}\" y=\"{:.1}\" text-anchor=\"middle\">measured nodes (x, y and z at each, removed in Effective Independence order)</text>",
        left + pw / 2.0,
        h - 10.0
    );
    let _ = writeln!(
        s,
        "<text x=\"16\" y=\"{:.1}\" transform=\"rotate(-90 16 {:.1})\" text-anchor=\"middle\">rho_M (s^-2)</text>",
        top + ph / 2.0,
        top + ph / 2.0
    );
    // one polyline per (method, mode), in first-appearance order
    let colors = [
        "#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b", "#e377c2", "#17becf",
    ];
    let mut series: Vec<(String, usize)> = Vec::new();
    let label = |p: &StudyPoint| method_label(p.method);
    for p in &finite {
        if !series.iter().any(|(m, k)| *m == label(p) && *k == p.mode) {
            series.push((label(p), p.mode));
        }
    }
    let mut methods: Vec<&str> = Vec::new();
    for (m, _) in &series {
        if !methods.contains(&m.as_str()) {
            methods.push(m);
        }
    }
    for (i, (method, mode)) in series.iter().enumerate() {
        let mut pts: Vec<(f64, f64)> = finite
            .iter()
            .filter(|p| label(p) == *method && p.mode == *mode)
            .map(|p| (px(p.nodes as f64), py(p.rho_m.log10())))
            .collect();
        pts.sort_by(|a, b| a.0.total_cmp(&b.0));
        // colour by test mode, dash pattern by method
        let color = colors[*mode % colors.len()];
        let method_index = methods.iter().position(|m| m == method).unwrap_or(0);
        let dash = [
            "",
            " stroke-dasharray=\"6 3\"",
            " stroke-dasharray=\"2 3\"",
            " stroke-dasharray=\"8 3 2 3\"",
        ][method_index % 4];
        let coords: Vec<String> = pts.iter().map(|(x, y)| format!("{x:.1},{y:.1}")).collect();
        let _ = writeln!(
            s,
            "<polyline fill=\"none\" stroke=\"{color}\" stroke-width=\"1.5\"{dash} points=\"{}\"/>",
            coords.join(" ")
        );
        for (x, y) in &pts {
            let _ = writeln!(
                s,
                "<circle cx=\"{x:.1}\" cy=\"{y:.1}\" r=\"2.5\" fill=\"{color}\"/>"
            );
        }
        let ly = top + 14.0 * i as f64 + 8.0;
        let _ = writeln!(
            s,
            "<line x1=\"{:.1}\" y1=\"{ly:.1}\" x2=\"{:.1}\" y2=\"{ly:.1}\" stroke=\"{color}\" stroke-width=\"1.5\"{dash}/>",
            left + pw + 10.0,
            left + pw + 34.0
        );
        let _ = writeln!(
            s,
            "<text x=\"{:.1}\" y=\"{:.1}\">mode {} {}</text>",
            left + pw + 40.0,
            ly + 4.0,
            mode + 1,
            method
        );
    }
    s.push_str("</svg>\n");
    s
}

/// A measured FRF over the model's as an SVG chart: magnitude (log-log) above, phase in degrees
/// (log frequency) below, the measured curve solid black, the model's dashed red. Lines at 0 Hz
/// and zero magnitudes have no place on log axes and are left out. Self-contained SVG.
pub fn frf_svg(
    title: &str,
    lines_hz: &[f64],
    measured: &[faer::c64],
    model: &[faer::c64],
) -> String {
    let (w, h, left, right, top, gap, bottom) = (760.0, 560.0, 90.0, 30.0, 40.0, 40.0, 50.0);
    let pw = w - left - right;
    let ph = (h - top - gap - bottom) / 2.0;
    let mut s = String::new();
    let _ = writeln!(
        s,
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{w}\" height=\"{h}\" viewBox=\"0 0 {w} {h}\" font-family=\"sans-serif\" font-size=\"12\">"
    );
    let _ = writeln!(s, "<rect width=\"{w}\" height=\"{h}\" fill=\"white\"/>");
    let _ = writeln!(
        s,
        "<text x=\"{:.1}\" y=\"20\" text-anchor=\"middle\">{}</text>",
        left + pw / 2.0,
        xml(title)
    );
    let keep = |k: usize| {
        lines_hz[k] > 0.0
            && [measured[k], model[k]]
                .iter()
                .all(|v| v.norm() > 0.0 && v.norm().is_finite())
    };
    let idx: Vec<usize> = (0..lines_hz.len().min(measured.len()).min(model.len()))
        .filter(|k| keep(*k))
        .collect();
    if idx.is_empty() {
        let _ = writeln!(
            s,
            "<text x=\"{}\" y=\"{}\">no data</text>\n</svg>",
            w / 2.0,
            h / 2.0
        );
        return s;
    }
    let lx: Vec<f64> = idx.iter().map(|k| lines_hz[*k].log10()).collect();
    let (x0, x1) = (
        lx.iter().copied().fold(f64::INFINITY, f64::min),
        lx.iter().copied().fold(f64::NEG_INFINITY, f64::max),
    );
    let x1 = x1.max(x0 + 1e-3);
    let px = |x: f64| left + (x - x0) / (x1 - x0) * pw;
    let mags: Vec<f64> = idx
        .iter()
        .flat_map(|k| [measured[*k].norm().log10(), model[*k].norm().log10()])
        .collect();
    let (y0, y1) = (
        mags.iter().copied().fold(f64::INFINITY, f64::min).floor(),
        mags.iter()
            .copied()
            .fold(f64::NEG_INFINITY, f64::max)
            .ceil(),
    );
    let y1 = y1.max(y0 + 1.0);
    let top2 = top + ph + gap;
    let pm = |y: f64| top + (y1 - y) / (y1 - y0) * ph;
    let pp = |deg: f64| top2 + (180.0 - deg) / 360.0 * ph;
    for (t, label) in [(top, "magnitude"), (top2, "phase (deg)")] {
        let _ = writeln!(
            s,
            "<rect x=\"{left}\" y=\"{t}\" width=\"{pw}\" height=\"{ph}\" fill=\"none\" stroke=\"black\"/>"
        );
        let _ = writeln!(
            s,
            "<text x=\"16\" y=\"{:.1}\" transform=\"rotate(-90 16 {:.1})\" text-anchor=\"middle\">{label}</text>",
            t + ph / 2.0,
            t + ph / 2.0
        );
    }
    let mut d = y0;
    while d <= y1 + 1e-9 {
        let y = pm(d);
        let _ = writeln!(
            s,
            "<line x1=\"{left}\" y1=\"{y:.1}\" x2=\"{:.1}\" y2=\"{y:.1}\" stroke=\"#ddd\"/>\n<text x=\"{:.1}\" y=\"{:.1}\" text-anchor=\"end\">1e{}</text>",
            left + pw,
            left - 6.0,
            y + 4.0,
            d as i64
        );
        d += 1.0;
    }
    for deg in [-180.0, -90.0, 0.0, 90.0, 180.0] {
        let y = pp(deg);
        let _ = writeln!(
            s,
            "<line x1=\"{left}\" y1=\"{y:.1}\" x2=\"{:.1}\" y2=\"{y:.1}\" stroke=\"#ddd\"/>\n<text x=\"{:.1}\" y=\"{:.1}\" text-anchor=\"end\">{deg}</text>",
            left + pw,
            left - 6.0,
            y + 4.0
        );
    }
    let mut decade = x0.floor();
    while decade <= x1 {
        if decade >= x0 {
            let x = px(decade);
            let _ = writeln!(
                s,
                "<line x1=\"{x:.1}\" y1=\"{top}\" x2=\"{x:.1}\" y2=\"{:.1}\" stroke=\"#ddd\"/>\n<text x=\"{x:.1}\" y=\"{:.1}\" text-anchor=\"middle\">{}</text>",
                top2 + ph,
                top2 + ph + 18.0,
                10f64.powf(decade)
            );
        }
        decade += 1.0;
    }
    let _ = writeln!(
        s,
        "<text x=\"{:.1}\" y=\"{:.1}\" text-anchor=\"middle\">frequency (Hz)</text>",
        left + pw / 2.0,
        h - 10.0
    );
    for (curve, style) in [
        (measured, "stroke=\"black\""),
        (model, "stroke=\"#d62728\" stroke-dasharray=\"6 3\""),
    ] {
        let mag: Vec<String> = idx
            .iter()
            .zip(&lx)
            .map(|(k, x)| format!("{:.1},{:.1}", px(*x), pm(curve[*k].norm().log10())))
            .collect();
        let phase: Vec<String> = idx
            .iter()
            .zip(&lx)
            .map(|(k, x)| {
                let deg = curve[*k].im.atan2(curve[*k].re).to_degrees();
                format!("{:.1},{:.1}", px(*x), pp(deg))
            })
            .collect();
        for pts in [mag, phase] {
            let _ = writeln!(
                s,
                "<polyline fill=\"none\" {style} stroke-width=\"1.3\" points=\"{}\"/>",
                pts.join(" ")
            );
        }
    }
    let _ = writeln!(
        s,
        "<text x=\"{:.1}\" y=\"{:.1}\" text-anchor=\"end\">measured: solid black; model: dashed red</text>",
        left + pw - 6.0,
        top + 16.0
    );
    s.push_str("</svg>\n");
    s
}

/// Text for SVG: `&`, `<` and `>` escaped.
fn xml(t: &str) -> String {
    t.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

/// The error map as an SVG bar chart: the fraction of the expanded residual each candidate group
/// explains alone (`docs/MATH.md`, "Localisation"), selected groups in red.
pub fn error_map_svg(loc: &Localisation) -> String {
    let mut by: Vec<(String, f64)> = loc
        .ranking
        .iter()
        .map(|r| (r.name.clone(), r.explained))
        .collect();
    by.sort_by(|a, b| a.0.cmp(&b.0));
    let (w, h, left, right, top, bottom) = (660.0, 300.0, 60.0, 170.0, 34.0, 50.0);
    let (pw, ph) = (w - left - right, h - top - bottom);
    let bw = pw / by.len().max(1) as f64;
    let mut s = format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{w}\" height=\"{h}\" viewBox=\"0 0 {w} {h}\" font-family=\"sans-serif\" font-size=\"11\">\n<rect width=\"{w}\" height=\"{h}\" fill=\"white\"/>\n<text x=\"{:.1}\" y=\"18\" text-anchor=\"middle\">Fraction of the tuned modes' residual each region's stiffness explains alone</text>\n",
        left + pw / 2.0
    );
    // axes with ticks at 0, 0.25, ..., 1
    let _ = writeln!(
        s,
        "<line x1=\"{left}\" y1=\"{top}\" x2=\"{left}\" y2=\"{:.1}\" stroke=\"black\"/>\n<line x1=\"{left}\" y1=\"{:.1}\" x2=\"{:.1}\" y2=\"{:.1}\" stroke=\"black\"/>",
        top + ph,
        top + ph,
        left + pw,
        top + ph
    );
    for k in 0..=4 {
        let v = k as f64 / 4.0;
        let y = top + ph - v * ph;
        let _ = writeln!(
            s,
            "<line x1=\"{:.1}\" y1=\"{y:.1}\" x2=\"{left}\" y2=\"{y:.1}\" stroke=\"black\"/>\n<text x=\"{:.1}\" y=\"{:.1}\" text-anchor=\"end\">{v:.2}</text>",
            left - 4.0,
            left - 6.0,
            y + 4.0
        );
    }
    let _ = writeln!(
        s,
        "<text x=\"14\" y=\"{:.1}\" transform=\"rotate(-90 14 {:.1})\" text-anchor=\"middle\">explained fraction (0 to 1)</text>\n<text x=\"{:.1}\" y=\"{:.1}\" text-anchor=\"middle\">candidate region (element set)</text>",
        top + ph / 2.0,
        top + ph / 2.0,
        left + pw / 2.0,
        h - 10.0
    );
    // legend
    for (i, (colour, text)) in [
        ("#c0392b", "selected for updating"),
        ("#7f8c8d", "not selected"),
    ]
    .iter()
    .enumerate()
    {
        let y = top + 10.0 + 18.0 * i as f64;
        let _ = writeln!(
            s,
            "<rect x=\"{:.1}\" y=\"{:.1}\" width=\"12\" height=\"12\" fill=\"{colour}\"/>\n<text x=\"{:.1}\" y=\"{:.1}\">{text}</text>",
            left + pw + 12.0,
            y - 10.0,
            left + pw + 30.0,
            y
        );
    }
    for (i, (name, v)) in by.iter().enumerate() {
        let bh = v.clamp(0.0, 1.0) * ph;
        let x = left + i as f64 * bw;
        let colour = if loc
            .selected
            .iter()
            .any(|g| loc.ranking.iter().any(|r| r.group == *g && &r.name == name))
        {
            "#c0392b"
        } else {
            "#7f8c8d"
        };
        let _ = writeln!(
            s,
            "<rect x=\"{:.1}\" y=\"{:.1}\" width=\"{:.1}\" height=\"{bh:.1}\" fill=\"{colour}\"/>",
            x + 4.0,
            top + ph - bh,
            (bw - 8.0).max(1.0)
        );
        let _ = writeln!(
            s,
            "<text x=\"{:.1}\" y=\"{:.1}\" text-anchor=\"middle\">{name}</text>",
            x + bw / 2.0,
            top + ph + 14.0
        );
        let _ = writeln!(
            s,
            "<text x=\"{:.1}\" y=\"{:.1}\" text-anchor=\"middle\">{v:.2}</text>",
            x + bw / 2.0,
            top + ph - bh - 3.0
        );
    }
    s.push_str("</svg>\n");
    s
}
