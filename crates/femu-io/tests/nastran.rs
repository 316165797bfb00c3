//! Nastran bulk data: one mixed quadratic mesh (hex20, penta15, tet10; two materials) written by
//! this test in free, small and large field formats, with continuations and implicit exponents,
//! gives the same `K` and `M` as the mesh assembled directly; coordinate systems, SPC sets, CONM2
//! and the cards femu cannot model; each bad deck an error naming the card and line.

use femu_fem::prelude::*;
use femu_io::nastran::{BdfOptions, parse_bdf, real};

/// The node order Nastran writes: CHEXA20 has the bottom edges' mid nodes (G9-G12), then the
/// vertical edges' (G13-G16), then the top edges' (G17-G20); femu (as Abaqus) has bottom, top,
/// vertical. CPENTA15 likewise (G7-G9 bottom, G10-G12 vertical, G13-G15 top). CTETRA10 is the
/// same in both.
fn nastran_order(kind: ElementKind, femu: &[u64]) -> Vec<u64> {
    match kind {
        ElementKind::Hex20 => [&femu[..12], &femu[16..20], &femu[12..16]].concat(),
        ElementKind::Penta15 => [&femu[..9], &femu[12..15], &femu[9..12]].concat(),
        _ => femu.to_vec(),
    }
}

fn name(kind: ElementKind) -> &'static str {
    match kind {
        ElementKind::Hex8 | ElementKind::Hex20 => "CHEXA",
        ElementKind::Penta6 | ElementKind::Penta15 => "CPENTA",
        _ => "CTETRA",
    }
}

#[derive(Clone, Copy)]
enum Format {
    Free,
    Small,
    Large,
}

/// A number as Nastran writes it in a short field: `2.1+11`, `7850.`, `.025`.
fn short(v: f64) -> String {
    if v == 0.0 {
        return "0.".into();
    }
    if v.abs() >= 1e6 {
        let e = v.abs().log10().floor() as i32;
        let m = v / 10f64.powi(e);
        return format!("{m}+{e}");
    }
    let s = format!("{v}");
    if s.contains('.') { s } else { format!("{s}.") }
}

/// One card in a format: `fields` after the name; continuations every 8 (small, free) or 4
/// (large) fields, labelled `+C1`, `*C1`, or by a comma.
fn card(out: &mut String, format: Format, name: &str, fields: &[String]) {
    match format {
        Format::Free => {
            for (k, chunk) in fields.chunks(8).enumerate() {
                let head = if k == 0 { name.to_string() } else { "+".into() };
                out.push_str(&format!("{head},{}\n", chunk.join(",")));
            }
        }
        Format::Small => {
            for (k, chunk) in fields.chunks(8).enumerate() {
                let head = if k == 0 {
                    name.to_string()
                } else {
                    format!("+C{k}")
                };
                out.push_str(&format!("{head:<8}"));
                for f in chunk {
                    out.push_str(&format!("{f:>8}"));
                }
                out.push('\n');
            }
        }
        Format::Large => {
            for (k, chunk) in fields.chunks(4).enumerate() {
                let head = if k == 0 {
                    format!("{name}*")
                } else {
                    format!("*C{k}")
                };
                out.push_str(&format!("{head:<8}"));
                for f in chunk {
                    out.push_str(&format!("{f:>16}"));
                }
                out.push('\n');
            }
        }
    }
}

fn plate() -> Model {
    let spec = PlateSpec {
        lengths: [0.06, 0.04, 0.01],
        divisions: [6, 4, 2],
        tet_block: [2, 2],
        quadratic: true,
    };
    // coordinates rounded to the micrometre, so that an 8-character field holds each exactly
    let generated = mixed_plate(&spec).unwrap();
    let mut mesh = Mesh::new();
    for i in 0..generated.node_count() {
        let c = generated.coords()[i].map(|v| (v * 1e6).round() / 1e6);
        mesh.add_node(generated.node_id(i), c).unwrap();
    }
    for el in generated.elements() {
        let ids: Vec<u64> = el.nodes.iter().map(|n| generated.node_id(*n)).collect();
        mesh.add_element(el.id, el.kind, &ids).unwrap();
    }
    let tet: Vec<u64> = generated
        .element_set("tet")
        .unwrap()
        .iter()
        .map(|e| generated.element(*e).id)
        .collect();
    mesh.add_element_set("tet", &tet).unwrap();
    let mut model = Model::new(mesh).unwrap();
    model.set_material(None, Material::steel()).unwrap();
    model
        .set_material(
            Some("tet"),
            Material::isotropic("al", 70e9, 70e9 / (2.0 * 26e9) - 1.0, 2700.0).unwrap(),
        )
        .unwrap();
    model
}

fn bdf(model: &Model, format: Format) -> String {
    let mesh = model.mesh();
    let mut s = String::from("$ written by femu's test\nSOL 103\nCEND\nBEGIN BULK\n");
    for i in 0..mesh.node_count() {
        let c = mesh.coords()[i];
        let mut f = vec![mesh.node_id(i).to_string(), String::new()];
        f.extend(c.iter().map(|v| short(*v)));
        card(&mut s, format, "GRID", &f);
    }
    let tets: std::collections::BTreeSet<usize> =
        mesh.element_set("tet").unwrap().iter().copied().collect();
    for el in mesh.elements() {
        let ids: Vec<u64> = el.nodes.iter().map(|n| mesh.node_id(*n)).collect();
        let pid = if tets.contains(&el.index) { "2" } else { "1" };
        let mut f = vec![el.id.to_string(), pid.to_string()];
        f.extend(nastran_order(el.kind, &ids).iter().map(u64::to_string));
        card(&mut s, format, name(el.kind), &f);
    }
    let strings = |v: &[&str]| v.iter().map(|s| s.to_string()).collect::<Vec<_>>();
    card(&mut s, format, "PSOLID", &strings(&["1", "10"]));
    card(&mut s, format, "PSOLID", &strings(&["2", "20"]));
    // steel by E and NU, aluminium by E and G (NU = E / 2G - 1 = 0.346)
    card(
        &mut s,
        format,
        "MAT1",
        &strings(&["10", "2.1+11", "", ".3", "7850."]),
    );
    card(
        &mut s,
        format,
        "MAT1",
        &strings(&["20", "7.+10", "2.6+10", "", "2.7+3"]),
    );
    card(&mut s, format, "EIGRL", &strings(&["1", "", "", "10"]));
    card(&mut s, format, "PARAM", &strings(&["POST", "-1"]));
    s.push_str("ENDDATA\n");
    s
}

fn max_diff(a: &femu_sparse::SparseMatrix, b: &femu_sparse::SparseMatrix) -> f64 {
    let d = a - b;
    d.data().iter().fold(0.0f64, |m, v| m.max(v.abs()))
        / a.data().iter().fold(0.0f64, |m, v| m.max(v.abs()))
}

#[test]
fn three_formats_give_the_same_k_and_m_as_the_mesh() {
    let model = plate();
    let direct = model.assemble(MassKind::Consistent).unwrap();
    for format in [Format::Free, Format::Small, Format::Large] {
        let text = bdf(&model, format);
        let deck = parse_bdf(&text, "p.bdf", &BdfOptions::default()).unwrap();
        let sys = deck.model.assemble(MassKind::Consistent).unwrap();
        assert_eq!(sys.k.rows(), direct.k.rows());
        let (dk, dm) = (max_diff(&sys.k, &direct.k), max_diff(&sys.m, &direct.m));
        assert!(dk < 1e-15 && dm < 1e-15, "K {dk:e}, M {dm:e}");
        assert_eq!(deck.eigrl, Some((None, None, Some(10))));
        // PARAM,POST is skipped with a warning, once
        let w: Vec<String> = deck.warnings.iter().map(|w| w.message.clone()).collect();
        assert_eq!(w.len(), 1, "{w:?}");
        assert!(w[0].starts_with("PARAM,POST skipped"), "{w:?}");
    }
}

#[test]
fn implicit_exponents() {
    assert_eq!(real("7.+10"), Some(7e10));
    assert_eq!(real("1.-3"), Some(1e-3));
    assert_eq!(real("-2.5-4"), Some(-2.5e-4));
    assert_eq!(real(".5+1"), Some(5.0));
    assert_eq!(real("1.0D+3"), Some(1000.0));
    assert_eq!(real("3"), Some(3.0));
    assert_eq!(real("1.2.3"), None);
}

/// A hex8 cube of side 1 in a cylindrical frame and constraints, masses and bad decks.
const CUBE: &str = "\
SOL 103
CEND
SPC = 100
BEGIN BULK
$ the grids of a unit cube, four of them given in cylindrical frame 5 (r, theta, z) about z
CORD2C   5       0       0.      0.      0.      0.      0.      1.
+        1.      0.      0.
GRID     1               0.      0.      0.
GRID     2       5       1.      0.      0.
GRID     3       5       1.41421356237309590.      0.
GRID     4               0.      1.      0.
GRID     5               0.      0.      1.
GRID     6       5       1.      0.      1.
GRID     7               1.      1.      1.
GRID     8       5       1.      90.     1.
CHEXA    1       1       1       2       3       4       5       6
+        7       8
PSOLID   1       1
MAT1     1       2.1+11          .3      7850.
SPC1     100     123     1       THRU    4
SPC      200     5       123     0.
CONM2    10      7               2.5     0.1
PARAM    WTMASS  1.
ENDDATA
";

#[test]
fn frames_constraints_and_masses() {
    // grid 3 at r = 1.414..., theta = 0.0 (the field "1.41421356237309590." is 16 characters:
    // r and theta touch in fixed columns)
    let text = CUBE.replace("1.41421356237309590.      0.", "1.41421 45.     0.");
    let deck = parse_bdf(&text, "cube.bdf", &BdfOptions::default()).unwrap();
    let mesh = deck.model.mesh();
    let at = |id: u64| mesh.coords()[mesh.node_index(id).unwrap()];
    // r 1.41421 at 45 degrees: (1, 1) to 6 digits; r 1 at 90 degrees: (0, 1)
    assert!((at(3)[0] - 1.0).abs() < 1e-5 && (at(3)[1] - 1.0).abs() < 1e-5);
    assert!(at(8)[0].abs() < 1e-12 && (at(8)[1] - 1.0).abs() < 1e-12 && at(8)[2] == 1.0);
    assert!((mesh.volume().unwrap() - 1.0).abs() < 1e-4);
    // SPC = 100 selects the SPC1 (grids 1 to 4 in all three directions), not set 200
    let fixed: Vec<(usize, usize)> = deck.model.fixed_dofs().collect();
    assert_eq!(fixed.len(), 12);
    assert!(fixed.iter().all(|(n, _)| mesh.node_id(*n) <= 4));
    // CONM2 with an offset: the mass is kept, the offset reported
    assert_eq!(deck.model.point_masses().len(), 1);
    assert_eq!(deck.model.point_masses()[0].mass[0][0], 2.5);
    assert!(
        deck.warnings.iter().any(|w| w.message.contains(
            "GRID 7 has no rotations (only RBE2 reference grids, and grids an RBE2 moves in all six components, have), so its offset is dropped"
        )),
        "{:?}",
        deck.warnings
    );
    assert!(
        (deck.model.total_mass().unwrap() - (7850.0 * mesh.volume().unwrap() + 2.5)).abs() < 1e-9
    );
    // WTMASS scales every mass
    let weighted = text.replace("PARAM    WTMASS  1.", "PARAM    WTMASS  .5");
    let half = parse_bdf(&weighted, "cube.bdf", &BdfOptions::default()).unwrap();
    assert!(
        (half.model.total_mass().unwrap() - 0.5 * deck.model.total_mass().unwrap()).abs() < 1e-9
    );
}

#[test]
fn bad_decks_name_the_card_and_line() {
    let base = CUBE.replace("1.41421356237309590.      0.", "1.41421 45.     0.");
    let cases: Vec<(String, &str)> = vec![
        (
            base.replace("+        7       8", "+        7       9"),
            "cube.bdf:16: CHEXA 1 refers to GRID 9, which the deck does not define",
        ),
        (
            base.replace("CORD2C   5       0 ", "CORD2C   5       6 ")
                .replace("PARAM    WTMASS  1.", "CORD2R   6       5       0.      0.      0.      0.      0.      1.\n+        1.      0.      0.\nPARAM    WTMASS  1."),
            "coordinate systems refer to each other in a cycle: 5 -> 6 -> 5",
        ),
        (
            base.replace("PSOLID   1       1", "PSOLID   1       3"),
            "cube.bdf:18: PSOLID 1 refers to MAT1 3, which the deck does not define (femu reads MAT1 and MAT9)",
        ),
        (
            base.replace("SPC1     100     123     1       THRU    4", "SPC1     100     123     1       44"),
            "cube.bdf:20: SPC1 constrains GRID 44, which the deck does not define",
        ),
        (
            base.replace("GRID     2       5 ", "GRID     2       7 "),
            "cube.bdf:9: GRID refers to coordinate system 7, which the deck does not define",
        ),
        (
            base.replace("MAT1     1       2.1+11          .3 ", "MAT1     1       2.1+11             "),
            "cube.bdf:19: MAT1 1: two of E, G and NU are needed",
        ),
        (
            base.replace("GRID     3       5       1.41421 45.     0.", "GRID,3,5,1.41421,45.,0.,5")
                .replace("SPC1     100     123     1       THRU    4", "SPC1     100     1       1       THRU    4"),
            "cube.bdf:20: SPC1 constrains the translations [1] of GRID 3 in its displacement frame 5, whose axes for them are not along basic ones",
        ),
        (
            base.replace("SPC = 100", "SPC = 300"),
            "cube.bdf:3: SPC = 300 selects a set that no SPC, SPC1 or SPCADD defines",
        ),
        (
            base.replace("PARAM    WTMASS  1.", "CQUADR   2       1       1       2       3       4\nRTRPLT   3       7       6       1\nCQUADR   4       1       5       6       7       8\nPARAM    WTMASS  1."),
            "cube.bdf:23: the deck has cards that change the stiffness or the mass and that femu cannot model: 1 rigid triangles (RTRPLT), 2 shells (CQUADR)",
        ),
    ];
    for (text, want) in cases {
        let e = parse_bdf(&text, "cube.bdf", &BdfOptions::default())
            .unwrap_err()
            .to_string();
        assert!(e.contains(want), "want {want:?}\n got {e}");
    }
    // lenient: the rest is read, with a warning that K and M are incomplete
    let with_shell = base.replace(
        "PARAM    WTMASS  1.",
        "CQUADR   2       1       1       2       3       4\nPARAM    WTMASS  1.",
    );
    let deck = parse_bdf(&with_shell, "cube.bdf", &BdfOptions { lenient: true }).unwrap();
    assert_eq!(deck.model.mesh().element_count(), 1);
    assert!(deck.warnings.iter().any(|w| {
        w.message
            .ends_with("left out (--lenient), so the model's K and M are incomplete")
    }));
}

/// pyNastran's two-tet10 example (`fixtures/nastran/pynastran/`, BSD): read as specified (the
/// SPCADD of the case control's SPC = 10, the large-field MAT1 with implicit exponents, fields
/// that touch; loads, tables and output cards skipped with a warning each), and compared with
/// MSC Nastran's eigenvalues from its `.f06`. The deck has no PARAM,COUPMASS, so MSC used its
/// lumped mass; a model of two elements is far from converged, so the mass formulation moves every
/// eigenvalue by 10-40 %: MSC's lie between femu's with lumped and with consistent mass for all
/// ten modes (the consistent mass gives the Rayleigh-Ritz upper bounds of its stiffness).
#[test]
fn pynastran_tet10_example_against_msc_nastran() {
    let path = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../fixtures/nastran/pynastran/simple_example_tet10.bdf");
    let deck = femu_io::nastran::read_bdf(&path, &BdfOptions::default()).unwrap();
    let model = &deck.model;
    assert_eq!(model.mesh().element_count(), 2);
    assert_eq!(model.mesh().node_count(), 14);
    // SPC1 123456 on grids 2128, 2260, 2488, 2551: their translations
    assert_eq!(model.fixed_dofs().count(), 12);
    let skipped: Vec<&str> = deck
        .warnings
        .iter()
        .filter_map(|w| w.message.split(" skipped").next())
        .collect();
    for card in [
        "PARAM,POST",
        "PARAM,PRTMAXIM",
        "FREQ1",
        "LSEQ",
        "DLOAD",
        "RLOAD1",
        "FORCE",
        "MOMENT",
        "TABLED1",
    ] {
        assert!(skipped.contains(&card), "{card}: {skipped:?}");
    }
    assert_eq!(deck.eigrl, Some((None, None, Some(10))));
    // MAT1* 1 1.705+7 .31 / 4.14413-4 (in-lbf-s units)
    let msc = [
        3.007285E+11,
        3.269210E+11,
        4.137910E+11,
        2.811446E+12,
        3.164506E+12,
        4.658380E+12,
        9.469630E+12,
        9.925428E+12,
        1.096105E+13,
        2.166837E+13,
    ];
    let solve = |mass| {
        let sys = model.assemble(mass).unwrap();
        femu_sparse::eigen::eigs(
            &sys.k,
            &sys.m,
            femu_sparse::eigen::Which::Lowest(10),
            &Default::default(),
        )
        .unwrap()
        .values
    };
    let (lumped, consistent) = (solve(MassKind::Lumped), solve(MassKind::Consistent));
    for j in 0..10 {
        assert!(
            lumped[j] < msc[j] && msc[j] < consistent[j],
            "mode {}: lumped {:e}, MSC {:e}, consistent {:e}",
            j + 1,
            lumped[j],
            msc[j],
            consistent[j]
        );
    }
}

/// MAT9: an orthotropic material whose three shear moduli differ, written as Nastran orders its
/// matrix (stresses `sx, sy, sz, txy, tyz, tzx`: G44 = G_xy, G55 = G_yz, G66 = G_zx), gives the
/// same `K` as the material given to femu directly (whose order is 11, 22, 33, 12, 13, 23).
#[test]
fn mat9_in_nastran_order() {
    let mesh = box_mesh(&BoxSpec::new(
        [0.2, 0.1, 0.05],
        [2, 2, 1],
        BoxCells::Hex,
        false,
    ))
    .unwrap();
    let ortho = Material::orthotropic(
        "o",
        [150e9, 10e9, 12e9],
        [0.3, 0.28, 0.4],
        [5e9, 6e9, 3.5e9],
        1600.0,
    )
    .unwrap();
    let d = ortho.elasticity_matrix();
    let mut direct = Model::new(mesh.clone()).unwrap();
    direct.set_material(None, ortho.clone()).unwrap();
    // femu index of each Nastran row: x, y, z, xy, yz (femu 5), zx (femu 4)
    let femu_of = [0, 1, 2, 3, 5, 4];
    let mut g = Vec::new();
    for i in 0..6 {
        for j in i..6 {
            g.push(format!("{:e}", d[femu_of[i]][femu_of[j]]));
        }
    }
    let mut deck = String::from("BEGIN BULK\n");
    for i in 0..mesh.node_count() {
        let c = mesh.coords()[i];
        deck.push_str(&format!(
            "GRID,{},,{:e},{:e},{:e}\n",
            mesh.node_id(i),
            c[0],
            c[1],
            c[2]
        ));
    }
    for el in mesh.elements() {
        let ids: Vec<String> = el
            .nodes
            .iter()
            .map(|n| mesh.node_id(*n).to_string())
            .collect();
        deck.push_str(&format!("CHEXA,{},1,{}\n", el.id, ids[..6].join(",")));
        deck.push_str(&format!("+,{}\n", ids[6..].join(",")));
    }
    // IN = 2, ISOP = FULL: the fully integrated brick of the direct model
    deck.push_str("PSOLID,1,9,,2,,FULL\n");
    // MAT9 MID G11..G16 / G22..G26, G33 / G34..G36, G44..G46, G55 / G56, G66, RHO
    deck.push_str(&format!("MAT9,9,{}\n", g[..7].join(",")));
    deck.push_str(&format!("+,{}\n", g[7..15].join(",")));
    deck.push_str(&format!("+,{},1600.\nENDDATA\n", g[15..].join(",")));
    let read = parse_bdf(&deck, "m9.bdf", &BdfOptions::default()).unwrap();
    let (a, b) = (
        read.model.assemble(MassKind::Consistent).unwrap(),
        direct.assemble(MassKind::Consistent).unwrap(),
    );
    assert!(max_diff(&a.k, &b.k) < 1e-14, "{}", max_diff(&a.k, &b.k));
    assert!(max_diff(&a.m, &b.m) < 1e-15);
    // the swap matters: read with yz and zx exchanged, K differs
    let mut swapped = Vec::new();
    for i in 0..6 {
        for j in i..6 {
            swapped.push(format!("{:e}", d[i][j]));
        }
    }
    let wrong = deck
        .replace(&g[..7].join(","), &swapped[..7].join(","))
        .replace(&g[7..15].join(","), &swapped[7..15].join(","))
        .replace(&g[15..].join(","), &swapped[15..].join(","));
    let w = parse_bdf(&wrong, "m9.bdf", &BdfOptions::default()).unwrap();
    assert!(max_diff(&w.model.assemble(MassKind::Consistent).unwrap().k, &b.k) > 1e-3);
}

/// The cube with a rigid link (RBE2, CM 123456, its reference carrying a CONM2) from the top face
/// to a grid above it, and an RBE3 averaging the top face into a grid beside it (free field,
/// continuation): the deck gives the K and M of the same links made through femu's API, and bad
/// links are errors naming the card, its id and line.
#[test]
fn rigid_and_interpolation_links() {
    let base = CUBE.replace("1.41421356237309590.      0.", "1.41421 45.     0.");
    let links = "GRID,20,,0.5,0.5,2.0\nGRID,21,,0.5,0.5,1.0\nRBE2,30,20,123456,5,6,7,8,1.-5\nCONM2,31,20,,4.\nRBE3,40,,21,123,1.0,123,5,6\n,2.,123456,7,8\nPARAM    WTMASS  1.";
    let text = base.replace("PARAM    WTMASS  1.", links);
    let deck = parse_bdf(&text, "cube.bdf", &BdfOptions::default()).unwrap();
    let k = deck.model.assemble(MassKind::Consistent).unwrap();
    // the same through the API
    let plain = parse_bdf(
        &base
            .replace(
                "PARAM    WTMASS  1.",
                "GRID,20,,0.5,0.5,2.0\nGRID,21,,0.5,0.5,1.0\nPARAM    WTMASS  1.",
            )
            .replace("CONM2    10      7               2.5     0.1\n", ""),
        "cube.bdf",
        &BdfOptions::default(),
    )
    .unwrap();
    let mut model = plain.model.clone();
    model
        .add_rigid_link(20, &[5, 6, 7, 8], &[0, 1, 2], "RBE2 30")
        .unwrap();
    model.add_point_mass(20, 4.0).unwrap();
    // CONM2 10 (2.5 at an offset 0.1 in x from GRID 7 at (1, 1, 1)) sits on a grid RBE2 30 moves
    // rigidly in all six components: it moves with the reference GRID 20 at (0.5, 0.5, 2), as a
    // rigid mass offset (1.1 - 0.5, 1 - 0.5, 1 - 2) from it
    model
        .add_rigid_mass(20, 2.5, [0.6, 0.5, -1.0], [[0.0; 3]; 3])
        .unwrap();
    model
        .add_weighted_average(
            21,
            &[0, 1, 2],
            &[(5, 1.0), (6, 1.0), (7, 2.0), (8, 2.0)],
            "RBE3 40",
        )
        .unwrap();
    let want = model.assemble(MassKind::Consistent).unwrap();
    assert_eq!(k.dofs.free_count(), want.dofs.free_count());
    assert!(max_diff(&k.k, &want.k) < 1e-15 * 2.1e11);
    assert!(max_diff(&k.m, &want.m) < 1e-15 * 7850.0);
    // the reference of the RBE3 is dependent in all three translations
    let i21 = deck.model.mesh().node_index(21).unwrap();
    assert!((0..3).all(|c| k.dofs.is_dependent(i21, c)));
    // rotations of GN exist and an SPC on 456 of GN fixes them
    let fixed_top = text.replace(
        "SPC1     100     123     1       THRU    4",
        "SPC1     100     123     1       THRU    4\nSPC1     100     456     20",
    );
    let d = parse_bdf(&fixed_top, "cube.bdf", &BdfOptions::default()).unwrap();
    assert_eq!(
        d.model
            .assemble(MassKind::Consistent)
            .unwrap()
            .dofs
            .free_count(),
        k.dofs.free_count() - 3
    );
    let bad: Vec<(String, &str)> = vec![
        (
            text.replace("RBE2,30,20,123456,5,6,7,8", "RBE2,30,20,123456,5,6,7,88"),
            "cube.bdf:25: RBE2 30 names GRID 88, which the deck does not define",
        ),
        (
            text.replace("CONM2,31,20,,4.", "CONM2,31,20,,4.\nRBE2,32,21,1,8"),
            "constraint RBE2 32 (cube.bdf line 27): its dependent DOF, node 8 x, is already dependent in RBE2 30 (cube.bdf line 25)",
        ),
        (
            text.replace(
                "SPC1     100     123     1       THRU    4",
                "SPC1     100     123     1       THRU    4\nSPC1     100     3       7",
            ),
            "constraint RBE2 30 (cube.bdf line 26): its dependent DOF, node 7 z, is also fixed",
        ),
        (
            text.replace(",2.,123456,7,8", ",2.,123456,7,8,UM,21,3"),
            "cube.bdf:27: RBE3 40: UM (other dependent DOFs) is not supported",
        ),
        (
            text.replace("RBE3,40,,21,123,1.0,123,5,6", "RBE3,40,,21,123,1.0,12,5,6"),
            "cube.bdf:27: RBE3 40: components 12 of a weight group",
        ),
        (
            text.replace("CONM2,31,20,,4.", "CONM2,31,20,,4.\nRBE2,33,5,123,20"),
            "form a cycle",
        ),
    ];
    for (t, want) in bad {
        let e = parse_bdf(&t, "cube.bdf", &BdfOptions::default())
            .unwrap_err()
            .to_string();
        assert!(e.contains(want), "want {want:?}\n got {e}");
    }
}

/// CPYRAM with 5 and 13 grids (Nastran's order: base mid-edges 1-2, 2-3, 3-4, 4-1, then 1-5 to
/// 4-5): the deck's K and M equal those of the same pyramids built through femu's API, and the
/// volume is the analytic one.
#[test]
fn pyramids() {
    let corners = [
        [0.0, 0.0, 0.0],
        [2.0, 0.0, 0.0],
        [2.0, 2.0, 0.0],
        [0.0, 2.0, 0.0],
        [1.0, 1.0, 1.5],
    ];
    let mut nodes: Vec<[f64; 3]> = corners.to_vec();
    for [a, b] in ElementKind::Pyramid13.edges() {
        nodes.push(std::array::from_fn(|i| {
            0.5 * (corners[*a][i] + corners[*b][i])
        }));
    }
    nodes.push([1.0, 1.0, -1.0]);
    let mut text = String::from("BEGIN BULK\n");
    for (i, p) in nodes.iter().enumerate() {
        text.push_str(&format!("GRID,{},,{},{},{}\n", i + 1, p[0], p[1], p[2]));
    }
    text.push_str("CPYRAM,1,1,1,2,3,4,5,6,+\n+,7,8,9,10,11,12,13\nCPYRAM,2,1,1,4,3,2,14\nPSOLID,1,1\nMAT1,1,7.+10,,.33,2700.\nENDDATA\n");
    let deck = parse_bdf(&text, "pyr.bdf", &BdfOptions::default()).unwrap();
    let mut mesh = Mesh::new();
    for (i, p) in nodes.iter().enumerate() {
        mesh.add_node(i as u64 + 1, *p).unwrap();
    }
    mesh.add_element(1, ElementKind::Pyramid13, &(1..=13).collect::<Vec<u64>>())
        .unwrap();
    mesh.add_element(2, ElementKind::Pyramid5, &[1, 4, 3, 2, 14])
        .unwrap();
    assert!((mesh.volume().unwrap() - (2.0 + 4.0 / 3.0)).abs() < 1e-13);
    let mut model = Model::new(mesh).unwrap();
    model
        .set_material(None, Material::isotropic("al", 7e10, 0.33, 2700.0).unwrap())
        .unwrap();
    let (a, b) = (
        deck.model.assemble(MassKind::Consistent).unwrap(),
        model.assemble(MassKind::Consistent).unwrap(),
    );
    assert!(max_diff(&a.k, &b.k) == 0.0 && max_diff(&a.m, &b.m) == 0.0);
    // CalculiX has no pyramid: the deck writer says so
    let e = femu_io::inp::inp_string(&deck.model, None)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("element 1 is a pyramid13: Abaqus and CalculiX have no pyramid element"),
        "{e}"
    );
    let e = parse_bdf(
        &text.replace("CPYRAM,2,1,1,4,3,2,14", "CPYRAM,2,1,1,4,3,2"),
        "pyr.bdf",
        &BdfOptions::default(),
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("CPYRAM 2 has 4 grids: femu reads CPYRAM with 5 or 13"),
        "{e}"
    );
}

/// Blank mid-side grids (Nastran: that edge is straight and the element linear along it): a
/// CTETRA with its mid-side grids G6, G8 and G10 blank gives the K and M of the same tet10 built
/// through the API with those three mid-side nodes tied to the average of their edge's ends; a
/// blank corner is an error.
#[test]
fn blank_mid_side_grids_are_straight_linear_edges() {
    let corners = [
        [0.0, 0.0, 0.0],
        [1.0, 0.1, 0.0],
        [0.2, 1.0, 0.1],
        [0.1, 0.2, 1.2],
    ];
    let mut nodes: Vec<[f64; 3]> = corners.to_vec();
    for [a, b] in ElementKind::Tet10.edges() {
        nodes.push(std::array::from_fn(|i| {
            0.5 * (corners[*a][i] + corners[*b][i])
        }));
    }
    let mut text = String::from("BEGIN BULK\n");
    for (i, p) in nodes.iter().enumerate() {
        if ![6, 8, 10].contains(&(i + 1)) {
            text.push_str(&format!("GRID,{},,{},{},{}\n", i + 1, p[0], p[1], p[2]));
        }
    }
    // G5 = grid 5 (edge 1-2), G6 blank (2-3), G7 = 7 (3-1), G8 blank (1-4), G9 = 9 (2-4), G10 blank
    let deck_text = format!(
        "{text}CTETRA,1,1,1,2,3,4,5,,+\n+,7,,9\nPSOLID,1,1\nMAT1,1,2.1+11,,.3,7850.\nENDDATA\n"
    );
    let deck = parse_bdf(&deck_text, "t.bdf", &BdfOptions::default()).unwrap();
    assert!(deck.warnings.iter().any(|w| {
        w.message
            .starts_with("3 mid-side grids are blank: those edges are straight")
    }));
    let sys = deck.model.assemble(MassKind::Consistent).unwrap();
    // the API: the same tet10 with grids 6, 8, 10 present and tied
    let mut mesh = Mesh::new();
    for (i, p) in nodes.iter().enumerate() {
        mesh.add_node(i as u64 + 1, *p).unwrap();
    }
    mesh.add_element(1, ElementKind::Tet10, &(1..=10).collect::<Vec<u64>>())
        .unwrap();
    let mut model = Model::new(mesh).unwrap();
    model.set_material(None, Material::steel()).unwrap();
    for (m, a, b) in [(6, 2, 3), (8, 1, 4), (10, 3, 4)] {
        for k in 0..3 {
            model
                .add_constraint((m, k), &[((a, k), 0.5), ((b, k), 0.5)], "tie")
                .unwrap();
        }
    }
    let want = model.assemble(MassKind::Consistent).unwrap();
    assert_eq!(sys.dofs.free_count(), want.dofs.free_count());
    assert!(max_diff(&sys.k, &want.k) < 1e-15 * 2.1e11 && max_diff(&sys.m, &want.m) < 1e-15);
    let e = parse_bdf(
        &deck_text.replace("CTETRA,1,1,1,2,3,4,5,,+", "CTETRA,1,1,1,,3,4,5,6,+"),
        "t.bdf",
        &BdfOptions::default(),
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("CTETRA 1: a corner grid (G1-G4) is blank"),
        "{e}"
    );
}

/// pyNastran's NX contact model (`fixtures/nastran/pynastran/`, BSD): 1326 CTETRA (436 with 4
/// grids, 890 with 10, 40 of their mid-side grids blank), 128 CHEXA (64 with 8, 64 with 20) and 48
/// CPYRAM (16 with 5, 32 with 13) read as specified, the contact and thermal cards
/// warned about; with the contact left out one body is free, so exactly six of the lowest
/// eigenvalues are rigid-body zeros (a wrongly tied mid-side node would add a mechanism, a
/// wrongly ordered pyramid an inverted Jacobian), and the spectrum is Sturm-verified.
#[test]
fn pynastran_contact_model_with_pyramids_and_blank_mid_side_grids() {
    let path = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../fixtures/nastran/pynastran/model1_sim1-solution_1.bdf");
    let deck = femu_io::nastran::read_bdf(&path, &BdfOptions::default()).unwrap();
    let counts = deck.model.mesh().kind_counts();
    let n = |k: ElementKind| counts.get(&k).copied().unwrap_or(0);
    assert_eq!(
        [
            n(ElementKind::Tet4),
            n(ElementKind::Tet10),
            n(ElementKind::Hex8),
            n(ElementKind::Hex20),
            n(ElementKind::Pyramid5),
            n(ElementKind::Pyramid13)
        ],
        [436, 890, 64, 64, 16, 32]
    );
    assert_eq!(deck.model.constraints().len(), 3 * 40);
    for card in ["BCTSET", "BSURFS", "MATT1", "PLOAD4"] {
        assert!(
            deck.warnings
                .iter()
                .any(|w| w.message.starts_with(&format!("{card} skipped"))),
            "{card}"
        );
    }
    let sys = deck.model.assemble(MassKind::Consistent).unwrap();
    let modes = femu_sparse::eigen::eigs(
        &sys.k,
        &sys.m,
        femu_sparse::eigen::Which::Lowest(8),
        &Default::default(),
    )
    .unwrap();
    let top = modes.values[7];
    let zeros = modes.values.iter().filter(|v| v.abs() < 1e-9 * top).count();
    assert_eq!(zeros, 6, "{:?}", modes.values);
    assert!(
        modes.values[6] > 1e6,
        "first elastic eigenvalue {}",
        modes.values[6]
    );
}

/// CONM2 on an RBE2 reference grid keeps its offset and inertia (Nastran's products of inertia
/// negated), in the basic frame (CID 0), as an absolute centre of gravity (CID -1) and in a frame
/// turned 90 degrees about z (CID 5: offset and inertia rotated, `R J R^T` written out here): the
/// deck's M equals that of `add_rigid_mass` with the basic values.
#[test]
fn conm2_offset_and_inertia_on_reference_grids() {
    let base = CUBE.replace("1.41421356237309590.      0.", "1.41421 45.     0.");
    type Case<'a> = (&'a str, [f64; 3], [[f64; 3]; 3]);
    let cases: [Case; 3] = [
        (
            "CONM2,31,20,0,4.,.1,.2,-.3,,+\n+,1.,.5,2.,.1,.2,3.",
            [0.1, 0.2, -0.3],
            [[1.0, -0.5, -0.1], [-0.5, 2.0, -0.2], [-0.1, -0.2, 3.0]],
        ),
        (
            "CONM2,31,20,-1,4.,.6,.5,2.1,,+\n+,1.,.5,2.,.1,.2,3.",
            [0.1, 0.0, 0.1],
            [[1.0, -0.5, -0.1], [-0.5, 2.0, -0.2], [-0.1, -0.2, 3.0]],
        ),
        (
            // frame 7: x' = y, y' = -x, z' = z; local offset (.1, 0, 0) is basic (0, .1, 0);
            // local J = [[1, -.5, 0], [-.5, 2, 0], [0, 0, 3]] is R J R^T = [[2, .5, 0], [.5, 1, 0], [0, 0, 3]]
            "CORD2R,7,0,0.,0.,0.,0.,0.,1.,+\n+,0.,1.,0.\nCONM2,31,20,7,4.,.1,,,,+\n+,1.,.5,2.,,,3.",
            [0.0, 0.1, 0.0],
            [[2.0, 0.5, 0.0], [0.5, 1.0, 0.0], [0.0, 0.0, 3.0]],
        ),
    ];
    for (conm2, d, j) in cases {
        let text = base.replace(
            "PARAM    WTMASS  1.",
            &format!(
                "GRID,20,,0.5,0.5,2.0\nRBE2,30,20,123456,5,6,7,8\n{conm2}\nPARAM    WTMASS  1."
            ),
        );
        let deck = parse_bdf(&text, "cube.bdf", &BdfOptions::default()).unwrap();
        let plain = parse_bdf(
            &base.replace(
                "PARAM    WTMASS  1.",
                "GRID,20,,0.5,0.5,2.0\nRBE2,30,20,123456,5,6,7,8\nPARAM    WTMASS  1.",
            ),
            "cube.bdf",
            &BdfOptions::default(),
        )
        .unwrap();
        let mut model = plain.model.clone();
        model.add_rigid_mass(20, 4.0, d, j).unwrap();
        let (a, b) = (
            deck.model.assemble(MassKind::Consistent).unwrap(),
            model.assemble(MassKind::Consistent).unwrap(),
        );
        assert!(
            max_diff(&a.m, &b.m) < 1e-12,
            "{conm2}: {}",
            max_diff(&a.m, &b.m)
        );
        assert!(max_diff(&a.k, &b.k) == 0.0);
    }
}

/// Cards cut short, found by the fuzzer (an SPC1 with only its set id used to panic), and a THRU
/// range spanning billions of ids: errors or the grids defined, never a panic or a hang.
#[test]
fn cards_cut_short_and_huge_ranges() {
    let base = CUBE.replace("1.41421356237309590.      0.", "1.41421 45.     0.");
    for (card, want) in [
        ("SPC1,100", "SPC1 names no grid"),
        ("SPCADD,100", "SPCADD names no set"),
        (
            "GRID,20,,0.5,0.5,2.0\nRBE2,30,20",
            "RBE2 field 4 (CM) is missing",
        ),
        (
            "GRID,20,,0.5,0.5,2.0\nRBE2,30,20,123",
            "RBE2 30 has no dependent grids",
        ),
    ] {
        let text = base.replace(
            "PARAM    WTMASS  1.",
            &format!("{card}\nPARAM    WTMASS  1."),
        );
        let e = parse_bdf(&text, "cube.bdf", &BdfOptions::default())
            .unwrap_err()
            .to_string();
        assert!(e.contains(want), "{card}: {e}");
    }
    let text = base.replace(
        "SPC1     100     123     1       THRU    4",
        "SPC1,100,123,1,THRU,4000000000000",
    );
    let deck = parse_bdf(&text, "cube.bdf", &BdfOptions::default()).unwrap();
    // every defined grid of the range: all eight
    assert_eq!(deck.model.fixed_dofs().count(), 24);
}

/// A Nastran deck named `.inp` (MSC names its examples so) is read as Nastran bulk data by its
/// first lines, with executive control, with `$` comments before it, or bulk data alone in small
/// or large field; an Abaqus deck (`**` comments, then `*HEADING`) stays Abaqus, and a file whose
/// first line is neither stays Abaqus (its reader then says what it expected).
#[test]
fn a_nastran_deck_named_inp_is_read_as_nastran() {
    use femu_io::Format;
    let dir = std::env::temp_dir().join(format!("femu-inp-sniff-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let cases = [
        (
            "exec.inp",
            "$ an MSC example\nSOL 103\nCEND\nBEGIN BULK\nGRID,1,,0.,0.,0.\nENDDATA\n",
            Format::Nastran,
        ),
        (
            "assign.inp",
            "ASSIGN OUTPUT2='x.op2'\nSOL 103\nCEND\n",
            Format::Nastran,
        ),
        (
            "bulk.inp",
            "$ bulk only\nGRID           1               0.      0.      0.\n",
            Format::Nastran,
        ),
        (
            "large.inp",
            "GRID*                  1                              0.              0.\n",
            Format::Nastran,
        ),
        (
            "abaqus.inp",
            "** a comment\n*HEADING\nSOL 103 is a title here\n*NODE\n1, 0., 0., 0.\n",
            Format::Inp,
        ),
        ("other.inp", "hello\n*NODE\n", Format::Inp),
        ("solid.inp", "SOLID\n", Format::Inp),
    ];
    for (name, text, want) in cases {
        let p = dir.join(name);
        std::fs::write(&p, text).unwrap();
        assert_eq!(Format::from_path(&p), Some(want), "{name}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}
