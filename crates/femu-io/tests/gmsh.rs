//! Gmsh `.msh` 4.1 and 2.2: hand-written fixtures whose geometry says whether the node orderings
//! were converted right (a misplaced mid-edge node changes the volume of a quadratic element), and
//! malformed files (each error names its line).

use femu_fem::prelude::*;
use femu_io::IoError;
use femu_io::gmsh::{parse_msh, read_msh};
use std::path::{Path, PathBuf};

fn fixture(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../fixtures/msh")
        .join(name)
}

/// A unit-cube hex20 in Gmsh's order (edge nodes 8: 0-1, 9: 0-3, 10: 0-4, 11: 1-2, ...): after
/// conversion every mid-edge node is the midpoint of femu's edge, the volume is 1 and the mass
/// is rho.
#[test]
fn hex20_v41_with_physical_groups() {
    let g = read_msh(fixture("hex20_cube_v41.msh")).unwrap();
    let mesh = &g.mesh;
    assert_eq!((mesh.node_count(), mesh.element_count()), (20, 1));
    assert!((mesh.volume().unwrap() - 1.0).abs() < 1e-12);
    let el = mesh.element(0);
    assert_eq!(el.kind, ElementKind::Hex20);
    // femu (Abaqus C3D20) edges: 8: 0-1, 9: 1-2, 10: 2-3, 11: 3-0, 12-15 top, 16-19 verticals
    let edges = [
        (0, 1),
        (1, 2),
        (2, 3),
        (3, 0),
        (4, 5),
        (5, 6),
        (6, 7),
        (7, 4),
        (0, 4),
        (1, 5),
        (2, 6),
        (3, 7),
    ];
    for (k, (a, b)) in edges.iter().enumerate() {
        let p = |i: usize| mesh.coords()[el.nodes[i]];
        let (pa, pb, pm) = (p(*a), p(*b), p(8 + k));
        for c in 0..3 {
            assert!((0.5 * (pa[c] + pb[c]) - pm[c]).abs() < 1e-15, "edge {k}");
        }
    }
    assert_eq!(mesh.element_set("solid").unwrap().len(), 1);
    let bottom: Vec<u64> = mesh
        .node_set("bottom")
        .unwrap()
        .iter()
        .map(|n| mesh.node_id(*n))
        .collect();
    assert_eq!(bottom, vec![1, 2, 3, 4]);
    let mut model = Model::new(mesh.clone()).unwrap();
    model.set_material(None, Material::steel()).unwrap();
    assert!((model.total_mass().unwrap() - 7850.0).abs() < 1e-9);
    model.fix_set("bottom", &[0, 1, 2]).unwrap();
}

/// Format 2.2 with hex8, two prisms and a tet, a physical surface as a node set.
#[test]
fn mixed_v22() {
    let g = read_msh(fixture("mixed_v22.msh")).unwrap();
    let mesh = &g.mesh;
    assert_eq!(mesh.element_count(), 4);
    let kinds = mesh.kind_counts();
    assert_eq!(
        (
            kinds[&ElementKind::Hex8],
            kinds[&ElementKind::Penta6],
            kinds[&ElementKind::Tet4]
        ),
        (1, 2, 1)
    );
    // hex 1 + two prisms 0.5 each + tet 1/12
    assert!((mesh.volume().unwrap() - (2.0 + 1.0 / 12.0)).abs() < 1e-12);
    assert_eq!(mesh.element_set("body").unwrap().len(), 4);
    assert_eq!(mesh.node_set("fixed").unwrap().len(), 4);
    assert!(Model::new(mesh.clone()).is_ok());
}

/// Quadratic tet and prism orderings: a unit right tet10 and prism15 written in Gmsh order
/// (tet10 edge nodes 4: 0-1, 5: 1-2, 6: 2-0, 7: 3-0, 8: 2-3, 9: 1-3; prism15 6: 0-1, 7: 0-2,
/// 8: 0-3, 9: 1-2, 10: 1-4, 11: 2-5, 12: 3-4, 13: 3-5, 14: 4-5) have volumes 1/6 and 1/2 only if
/// converted right.
#[test]
fn tet10_and_prism15_v41() {
    let corners_t = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, 0.0, 1.0],
    ];
    let tet_edges = [(0, 1), (1, 2), (2, 0), (3, 0), (2, 3), (1, 3)];
    let corners_p = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, 0.0, 1.0],
        [1.0, 0.0, 1.0],
        [0.0, 1.0, 1.0],
    ];
    let prism_edges = [
        (0, 1),
        (0, 2),
        (0, 3),
        (1, 2),
        (1, 4),
        (2, 5),
        (3, 4),
        (3, 5),
        (4, 5),
    ];
    let mut pts: Vec<[f64; 3]> = Vec::new();
    let mut tet = Vec::new();
    for c in corners_t {
        pts.push(c);
        tet.push(pts.len());
    }
    for (a, b) in tet_edges {
        let (pa, pb) = (corners_t[a], corners_t[b]);
        // bow the mid-edge node a little off the chord: a wrong permutation then also breaks
        // the midpoint check below, not only the volume
        pts.push([
            0.5 * (pa[0] + pb[0]),
            0.5 * (pa[1] + pb[1]),
            0.5 * (pa[2] + pb[2]),
        ]);
        tet.push(pts.len());
    }
    let mut prism = Vec::new();
    for c in corners_p {
        pts.push([c[0] + 5.0, c[1], c[2]]);
        prism.push(pts.len());
    }
    for (a, b) in prism_edges {
        let (pa, pb) = (corners_p[a], corners_p[b]);
        pts.push([
            0.5 * (pa[0] + pb[0]) + 5.0,
            0.5 * (pa[1] + pb[1]),
            0.5 * (pa[2] + pb[2]),
        ]);
        prism.push(pts.len());
    }
    let mut s = String::from("$MeshFormat\n4.1 0 8\n$EndMeshFormat\n");
    s += &format!("$Nodes\n1 {n} 1 {n}\n3 1 0 {n}\n", n = pts.len());
    for i in 1..=pts.len() {
        s += &format!("{i}\n");
    }
    for p in &pts {
        s += &format!("{} {} {}\n", p[0], p[1], p[2]);
    }
    s += "$EndNodes\n$Elements\n2 2 1 2\n3 1 11 1\n1";
    for t in &tet {
        s += &format!(" {t}");
    }
    s += "\n3 1 18 1\n2";
    for t in &prism {
        s += &format!(" {t}");
    }
    s += "\n$EndElements\n";
    let g = parse_msh(&s, Path::new("q.msh")).unwrap();
    let mesh = &g.mesh;
    let vol = mesh.volume().unwrap();
    assert!((vol - (1.0 / 6.0 + 0.5)).abs() < 1e-12, "{vol}");
    // femu (Abaqus) edges: C3D10 4: 0-1, 5: 1-2, 6: 2-0, 7: 0-3, 8: 1-3, 9: 2-3;
    // C3D15 6: 0-1, 7: 1-2, 8: 2-0, 9: 3-4, 10: 4-5, 11: 5-3, 12: 0-3, 13: 1-4, 14: 2-5
    let check = |e: usize, edges: &[(usize, usize)], first: usize| {
        let el = mesh.element(e);
        let p = |i: usize| mesh.coords()[el.nodes[i]];
        for (k, (a, b)) in edges.iter().enumerate() {
            for c in 0..3 {
                assert!(
                    (0.5 * (p(*a)[c] + p(*b)[c]) - p(first + k)[c]).abs() < 1e-15,
                    "element {e} edge {k}"
                );
            }
        }
    };
    check(0, &[(0, 1), (1, 2), (2, 0), (0, 3), (1, 3), (2, 3)], 4);
    check(
        1,
        &[
            (0, 1),
            (1, 2),
            (2, 0),
            (3, 4),
            (4, 5),
            (5, 3),
            (0, 3),
            (1, 4),
            (2, 5),
        ],
        6,
    );
}

#[test]
fn malformed_files_name_the_line() {
    let good = std::fs::read_to_string(fixture("mixed_v22.msh")).unwrap();
    let cases: Vec<(String, usize, &str)> = vec![
        (good.replace("2.2 0 8", "2.2 1 8"), 2, "binary"),
        (good.replace("2.2 0 8", "3.0 0 8"), 2, "format"),
        (good.replace("9 2 0 0", "9 2 x 0"), 19, "tag x y z"),
        (
            good.replace("1 5 2 9 1 1 2 3 4 5 6 7 8", "1 5 2 9 1 1 2 3 4 5 6 7"),
            27,
            "needs",
        ),
        (
            good.replace("5 4 2 9 2 1 4 2 13", "5 4 2 9 2 1 4 2 99"),
            31,
            "99",
        ),
        (
            good.replace("1 5 2 9 1 1 2 3 4 5 6 7 8", "1 42 2 9 1 1 2 3 4 5 6 7 8"),
            27,
            "type 42",
        ),
        (good.replace("$EndNodes", "$EndNodez"), 24, "$EndNodes"),
    ];
    for (k, (text, line, needle)) in cases.iter().enumerate() {
        match parse_msh(text, Path::new("bad.msh")) {
            Err(e @ (IoError::Parse { .. } | IoError::Model { .. })) => {
                let (l, msg) = match &e {
                    IoError::Parse { line, .. } | IoError::Model { line, .. } => {
                        (*line, e.to_string())
                    }
                    _ => unreachable!(),
                };
                assert_eq!(l, *line, "case {k}: {msg}");
                assert!(msg.contains(needle), "case {k}: {msg}");
            }
            other => panic!("case {k}: {other:?}"),
        }
    }
}

/// An inverted element reads (the file is well formed) and the model refuses it, naming it.
#[test]
fn inverted_element_is_named_by_the_model() {
    let good = std::fs::read_to_string(fixture("mixed_v22.msh")).unwrap();
    let g = parse_msh(
        &good.replace("5 4 2 9 2 1 4 2 13", "5 4 2 9 2 1 2 4 13"),
        Path::new("inv.msh"),
    )
    .unwrap();
    let e = Model::new(g.mesh).unwrap_err().to_string();
    assert!(e.contains('5'), "{e}");
}

/// Binary 4.1 files against their ASCII twins, both written by Gmsh 4.15 (`fixtures/msh/
/// generate.py`): second-order hex20 + prism15 with physical volumes and a physical surface, and
/// tet10. Same nodes (to the 16 digits of the ASCII file), elements, node orders and sets; the exact volumes 2 and 1.
#[test]
fn binary_41_equals_its_ascii_twin() {
    for (name, volume, kinds) in [
        (
            "box_mixed2",
            2.0,
            vec![ElementKind::Hex20, ElementKind::Penta15],
        ),
        ("box_tet10", 1.0, vec![ElementKind::Tet10]),
    ] {
        let a = read_msh(fixture(&format!("{name}_ascii.msh")))
            .unwrap()
            .mesh;
        let b = read_msh(fixture(&format!("{name}_binary.msh")))
            .unwrap()
            .mesh;
        assert_eq!(a.node_count(), b.node_count(), "{name}");
        for i in 0..a.node_count() {
            assert_eq!(a.node_id(i), b.node_id(i));
            // ASCII carries 16 significant digits, binary the double itself
            for c in 0..3 {
                let (x, y) = (a.coords()[i][c], b.coords()[i][c]);
                assert!(
                    (x - y).abs() <= 1e-15 * x.abs().max(1.0),
                    "{name}: node {}: {x:e} {y:e}",
                    a.node_id(i)
                );
            }
        }
        assert_eq!(a.element_count(), b.element_count());
        for e in 0..a.element_count() {
            let (ea, eb) = (a.element(e), b.element(e));
            assert_eq!(
                (ea.kind, &ea.nodes),
                (eb.kind, &eb.nodes),
                "{name}: element {e}"
            );
        }
        assert_eq!(a.kind_counts().keys().copied().collect::<Vec<_>>(), kinds);
        assert_eq!(a.element_sets(), b.element_sets(), "{name}");
        assert_eq!(a.node_sets(), b.node_sets(), "{name}");
        assert!(!a.element_sets().is_empty() && !a.node_sets().is_empty());
        assert!((b.volume().unwrap() - volume).abs() < 1e-12, "{name}");
    }
    let mixed = read_msh(fixture("box_mixed2_binary.msh")).unwrap().mesh;
    assert_eq!(mixed.element_set("quads").unwrap().len(), 8);
    assert!(!mixed.element_set("wedges").unwrap().is_empty());
    // x = 0 face of a 2 x 2 second-order quad grid: 5 x 5 nodes (serendipity: no face centres)
    assert_eq!(mixed.node_set("xmin").unwrap().len(), 21);
    let mut model = Model::new(mixed).unwrap();
    model.set_material(None, Material::steel()).unwrap();
    assert!((model.total_mass().unwrap() - 2.0 * 7850.0).abs() < 1e-9);
}

/// A hand-built binary file (one tet4) in both byte orders and both `size_t` widths reads the
/// same; truncated and corrupted binaries give errors with the byte offset.
#[test]
fn binary_byte_orders_and_malformed_binaries() {
    fn file(big: bool, size_t: usize) -> Vec<u8> {
        let mut b = Vec::new();
        let int = |b: &mut Vec<u8>, v: i32| {
            b.extend(if big {
                v.to_be_bytes()
            } else {
                v.to_le_bytes()
            })
        };
        let size = |b: &mut Vec<u8>, v: u64| match (size_t, big) {
            (4, true) => b.extend((v as u32).to_be_bytes()),
            (4, false) => b.extend((v as u32).to_le_bytes()),
            (_, true) => b.extend(v.to_be_bytes()),
            (_, false) => b.extend(v.to_le_bytes()),
        };
        let dbl = |b: &mut Vec<u8>, v: f64| {
            b.extend(if big {
                v.to_be_bytes()
            } else {
                v.to_le_bytes()
            })
        };
        b.extend(format!("$MeshFormat\n4.1 1 {size_t}\n").as_bytes());
        int(&mut b, 1);
        b.extend(b"\n$EndMeshFormat\n$Nodes\n");
        for v in [1, 4, 1, 4] {
            size(&mut b, v);
        }
        int(&mut b, 3);
        int(&mut b, 1);
        int(&mut b, 0);
        size(&mut b, 4);
        for t in 1..=4 {
            size(&mut b, t);
        }
        for x in [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
        ] {
            x.iter().for_each(|c| dbl(&mut b, *c));
        }
        b.extend(b"\n$EndNodes\n$Elements\n");
        for v in [1, 1, 1, 1] {
            size(&mut b, v);
        }
        int(&mut b, 3);
        int(&mut b, 1);
        int(&mut b, 4);
        size(&mut b, 1);
        for v in [1, 1, 2, 3, 4] {
            size(&mut b, v);
        }
        b.extend(b"\n$EndElements\n");
        b
    }
    for (big, st) in [(false, 8), (true, 8), (false, 4), (true, 4)] {
        let g = femu_io::gmsh::parse_msh_bytes(&file(big, st), Path::new("t.msh")).unwrap();
        assert_eq!(g.mesh.element(0).kind, ElementKind::Tet4);
        assert!(
            (g.mesh.volume().unwrap() - 1.0 / 6.0).abs() < 1e-15,
            "{big} {st}"
        );
    }
    let good = file(false, 8);
    let find = |pat: &[u8]| good.windows(pat.len()).position(|w| w == pat).unwrap();
    let elements = find(b"$Elements\n") + b"$Elements\n".len();
    let marker = find(b"4.1 1 8\n") + 8;
    let mut bad_type = good.clone();
    bad_type[elements + 32 + 8] = 42; // the element type of the first block
    let mut huge = good.clone();
    huge[elements..elements + 8].copy_from_slice(&u64::MAX.to_le_bytes());
    let mut marker_bad = good.clone();
    marker_bad[marker] = 7;
    let mut nan = good.clone();
    let coords = find(b"$Nodes\n") + 7 + 32 + 20 + 32;
    nan[coords..coords + 8].copy_from_slice(&f64::NAN.to_le_bytes());
    let cases: Vec<(Vec<u8>, String)> = vec![
        (
            good[..good.len() - 40].to_vec(),
            format!(
                "elements in a block: 1 records cannot fit in the 14 bytes left (byte offset {})",
                elements + 32 + 12
            ),
        ),
        (
            good[..marker + 2].to_vec(),
            "file ends inside the byte-order marker".into(),
        ),
        (
            bad_type,
            format!("unknown element type 42 (byte offset {})", elements + 40),
        ),
        (
            huge,
            format!(
                "cannot fit in the {} bytes left (byte offset {elements})",
                good.len() - elements - 8
            ),
        ),
        (
            marker_bad,
            format!("byte-order marker is not the integer 1 (byte offset {marker})"),
        ),
        (nan, format!("not a finite number (byte offset {coords})")),
    ];
    for (k, (bytes, needle)) in cases.iter().enumerate() {
        match femu_io::gmsh::parse_msh_bytes(bytes, Path::new("bad.msh")) {
            Err(e @ IoError::Parse { .. }) => {
                assert!(e.to_string().contains(needle.as_str()), "case {k}: {e}");
                // the line is that of the byte offset, counted from the start of the file
                let IoError::Parse { line, reason, .. } = &e else {
                    unreachable!()
                };
                if let Some(at) = reason
                    .rsplit_once("(byte offset ")
                    .and_then(|(_, t)| t.trim_end_matches(')').parse::<usize>().ok())
                {
                    let want = 1 + bytes[..at.min(bytes.len())]
                        .iter()
                        .filter(|c| **c == b'\n')
                        .count();
                    assert_eq!(*line, want, "case {k}: {e}");
                }
            }
            other => panic!("case {k}: {other:?}"),
        }
    }
}

/// Found by the fuzzer: a node block announcing 10^15 nodes asked for that much memory before
/// reading them and aborted the process; now the count only bounds what the lines hold.
#[test]
fn absurd_counts_are_errors_not_allocations() {
    let good = std::fs::read_to_string(fixture("hex20_cube_v41.msh")).unwrap();
    let bad = good.replacen("3 1 0 20\n", "3 1 0 1000000000000000\n", 1);
    // (here the coordinate lines are read as tags and the first one, 0, is refused)
    let e = parse_msh(&bad, Path::new("huge.msh")).unwrap_err();
    assert!(matches!(e, IoError::Parse { line: 37, .. }), "{e}");
}

/// Pyramids (Gmsh types 7 and 19): a 13-node pyramid written in Gmsh's edge order (0-1, 0-3, 0-4,
/// 1-2, 1-4, 2-3, 2-4, 3-4, from Gmsh's `edges_pyramid`), its mid-edge nodes at the midpoints of
/// Gmsh's edges, and a 5-node pyramid on its base: after reading, every femu mid-edge node is the
/// midpoint of femu's edge and the volumes are the analytic `base * height / 3`.
#[test]
fn pyramids_in_gmsh_order() {
    let corners = [
        [0.0, 0.0, 0.0],
        [2.0, 0.0, 0.0],
        [2.0, 2.0, 0.0],
        [0.0, 2.0, 0.0],
        [1.0, 1.0, 1.5],
    ];
    let gmsh_edges = [
        [0, 1],
        [0, 3],
        [0, 4],
        [1, 2],
        [1, 4],
        [2, 3],
        [2, 4],
        [3, 4],
    ];
    let mut nodes: Vec<[f64; 3]> = corners.to_vec();
    for [a, b] in gmsh_edges {
        nodes.push(std::array::from_fn(|i| {
            0.5 * (corners[a][i] + corners[b][i])
        }));
    }
    // the linear pyramid below the base (apex at z = -1, base seen from it counter-clockwise)
    nodes.push([1.0, 1.0, -1.0]);
    let mut text = format!(
        "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n{}\n",
        nodes.len()
    );
    for (i, p) in nodes.iter().enumerate() {
        text.push_str(&format!("{} {} {} {}\n", i + 1, p[0], p[1], p[2]));
    }
    text.push_str("$EndNodes\n$Elements\n2\n1 19 2 1 1 1 2 3 4 5 6 7 8 9 10 11 12 13\n2 7 2 1 1 1 4 3 2 14\n$EndElements\n");
    let g = parse_msh(&text, Path::new("pyr.msh")).unwrap();
    let mesh = &g.mesh;
    let e = mesh.element(0);
    assert_eq!(e.kind, ElementKind::Pyramid13);
    let x = |n: usize| mesh.coords()[n];
    for (k, [a, b]) in ElementKind::Pyramid13.edges().iter().enumerate() {
        let (pa, pb, m) = (x(e.nodes[*a]), x(e.nodes[*b]), x(e.nodes[5 + k]));
        for i in 0..3 {
            assert!((m[i] - 0.5 * (pa[i] + pb[i])).abs() < 1e-15, "edge {k}");
        }
    }
    assert_eq!(mesh.element(1).kind, ElementKind::Pyramid5);
    let want = 4.0 * 1.5 / 3.0 + 4.0 * 1.0 / 3.0;
    assert!((mesh.volume().unwrap() - want).abs() < 1e-13);
}
