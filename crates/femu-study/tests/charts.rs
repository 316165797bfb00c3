//! The charts and the CSV of the sensor-removal study, and SVG to PNG with the shipped font.

use faer::Mat;
use femu_correlate::Method;
use femu_correlate::study::sensor_removal_study;
use femu_fem::prelude::*;
use femu_study::chart::{figure1_svg, method_label};
use femu_study::report::study_csv;

/// The study chart: one polyline per (method, mode), one marker per point; the CSV one row per
/// point (points of a real study on a small clamped bar, exact modes as the "test").
#[test]
fn study_chart_and_csv_have_one_mark_per_point() {
    let model = femu_testkit::bar([6, 2, 1], true);
    let sys = model.assemble(MassKind::Consistent).unwrap();
    let mesh = model.mesh();
    let modes = femu_sparse::eigen::eigs(
        &sys.k,
        &sys.m,
        femu_sparse::eigen::Which::Lowest(2),
        &Default::default(),
    )
    .unwrap();
    let x = Mat::from_fn(sys.k.rows(), 2, |i, j| modes.vectors[(i, j)]);
    let lambdas: Vec<f64> = modes.values[..2].iter().map(|l| 1.02 * l).collect();
    let all: Vec<u64> = (0..mesh.node_count())
        .filter(|n| sys.dofs.node_dofs(*n).iter().any(|d| d.is_some()))
        .map(|n| mesh.node_id(n))
        .collect();
    let removal: Vec<u64> = all[..all.len() - 5].to_vec();
    let methods = [Method::Static, Method::Dynamic, Method::MinimumResidual];
    let points = sensor_removal_study(
        &sys.k,
        &sys.m,
        mesh,
        &sys.dofs,
        &lambdas,
        x.as_ref(),
        &all,
        &removal,
        &methods,
        None,
        10,
    )
    .unwrap();
    let svg = figure1_svg(&points);
    let series: std::collections::BTreeSet<(String, usize)> = points
        .iter()
        .map(|p| (method_label(p.method), p.mode))
        .collect();
    assert!(svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"));
    assert_eq!(svg.matches("<polyline").count(), series.len());
    assert_eq!(svg.matches("<circle").count(), points.len());
    // full set, then 3 methods
    assert_eq!(series.len(), 2 * 4);
    let csv = study_csv(&points);
    assert!(csv.starts_with("nodes,sensors,method,mode,rho_m,rho_2\n"));
    assert_eq!(csv.lines().count(), points.len() + 1);
    assert_eq!(csv.lines().filter(|l| l.contains(",full,")).count(), 2);
}

/// SVG to PNG: the image has the SVG's size times the scale, a red square where the SVG puts it,
/// white elsewhere, and text renders (dark pixels inside the text's box) with the shipped font.
#[test]
fn svg_to_png_renders_shapes_and_text() {
    let svg = r##"<svg xmlns="http://www.w3.org/2000/svg" width="40" height="20"><rect x="0" y="0" width="10" height="10" fill="#ff0000"/><text x="15" y="16" font-size="14">A</text></svg>"##;
    let bytes = femu_study::chart::svg_to_png(svg, 2.0).unwrap();
    assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n");
    let img = resvg::tiny_skia::Pixmap::decode_png(&bytes).unwrap();
    assert_eq!((img.width(), img.height()), (80, 40));
    let px = |x: u32, y: u32| img.pixel(x, y).unwrap();
    let red = px(5, 5);
    assert_eq!((red.red(), red.green(), red.blue()), (255, 0, 0));
    let white = px(70, 5);
    assert_eq!((white.red(), white.green(), white.blue()), (255, 255, 255));
    let dark = (30..50)
        .flat_map(|x| (10..34).map(move |y| (x, y)))
        .filter(|(x, y)| px(*x, *y).red() < 100)
        .count();
    assert!(dark > 20, "text drew {dark} dark pixels");
    assert!(femu_study::chart::svg_to_png("<svg", 1.0).is_err());
    assert!(femu_study::chart::svg_to_png(svg, 0.0).is_err());
}

/// The FRF chart: lines at 1, 10 and 100 Hz (the 0 Hz line has no place on a log axis), two
/// curves of magnitude and phase (four polylines of three points). By hand, on its 760 x 560
/// canvas (plots 640 wide from x = 90; magnitude at y = 40, phase at y = 295, each 215 high;
/// phase +180 at the top): the measured `i` at 10 Hz sits at the middle decade, x = 90 + 640 / 2
/// = 410, and at 90 degrees, y = 295 + 90 / 360 * 215 = 348.75.
#[test]
fn frf_chart_places_points_by_hand() {
    use faer::c64;
    let lines = [0.0, 1.0, 10.0, 100.0];
    let measured = [
        c64::new(1.0, 0.0),
        c64::new(1.0, 0.0),
        c64::new(0.0, 1.0),
        c64::new(-1.0, 0.0),
    ];
    let model = [
        c64::new(2.0, 0.0),
        c64::new(2.0, 0.0),
        c64::new(0.0, 2.0),
        c64::new(-2.0, 0.0),
    ];
    let svg = femu_study::chart::frf_svg("a < b & c", &lines, &measured, &model);
    assert!(svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"));
    assert!(svg.contains("a &lt; b &amp; c"));
    let polylines: Vec<&str> = svg.lines().filter(|l| l.starts_with("<polyline")).collect();
    assert_eq!(polylines.len(), 4);
    for p in &polylines {
        let points = p
            .split("points=\"")
            .nth(1)
            .unwrap()
            .trim_end_matches("\"/>");
        assert_eq!(points.split(' ').count(), 3, "{p}");
    }
    // measured phase: 0 deg at 1 Hz (y = 295 + 180 / 360 * 215 = 402.5), 90 at 10 Hz
    assert!(
        polylines[1].contains("90.0,402.5 410.0,348.8"),
        "{}",
        polylines[1]
    );
}
