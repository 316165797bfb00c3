//! Nastran decks read as Nastran reads them, or refused: the mass formulation (`PARAM,COUPMASS`),
//! permanent constraints (`GRID` field 8, `GRDSET`), the case control's grammar, continuations
//! paired by label, unknown cards, MAT1's moduli, a MAT9 in a turned material frame (`CORDM`),
//! and the EIGRL the case control selects. Each against an independent reference: a dense tet4
//! model written out in this test, the same structure constrained another way, a material
//! rotated here index by index, or the exact refusal.

use faer::linalg::solvers::DenseSolveCore;
use femu_fem::prelude::*;
use femu_io::nastran::{BdfDeck, BdfOptions, parse_bdf};

fn read(text: &str) -> BdfDeck {
    parse_bdf(text, "deck.bdf", &BdfOptions::default()).unwrap()
}

fn error(text: &str) -> String {
    parse_bdf(text, "deck.bdf", &BdfOptions::default())
        .unwrap_err()
        .to_string()
}

/// A steel bar of `nx` hex8 elements along x (0.1 x 0.02 x 0.03 m each end face), free field;
/// `grid_extra(id, x)` is appended to each GRID line (fields CD, PS after X3).
fn bar(nx: usize, grid_extra: impl Fn(u64, f64) -> String, psolid: &str) -> String {
    let mut s = String::new();
    let id = |i: usize, j: usize, k: usize| 1 + i + (nx + 1) * (j + 2 * k);
    for k in 0..2 {
        for j in 0..2 {
            for i in 0..=nx {
                let x = 0.1 * i as f64;
                let n = id(i, j, k) as u64;
                s.push_str(&format!(
                    "GRID,{n},,{x:?},{:?},{:?}{}\n",
                    0.02 * j as f64,
                    0.03 * k as f64,
                    grid_extra(n, x)
                ));
            }
        }
    }
    for i in 0..nx {
        s.push_str(&format!(
            "CHEXA,{},1,{},{},{},{},{},{},+C{i}\n+C{i},{},{}\n",
            i + 1,
            id(i, 0, 0),
            id(i + 1, 0, 0),
            id(i + 1, 1, 0),
            id(i, 1, 0),
            id(i, 0, 1),
            id(i + 1, 0, 1),
            id(i + 1, 1, 1),
            id(i, 1, 1)
        ));
    }
    s.push_str(psolid);
    s.push_str("\nMAT1,1,2.1+11,,.3,7850.\n");
    s
}

fn eigenvalues(deck: &BdfDeck, mass: MassKind, count: usize) -> Vec<f64> {
    let sys = deck.model.assemble(mass).unwrap();
    let k = femu_sparse::csc::to_dense(&sys.k);
    let m = femu_sparse::csc::to_dense(&sys.m);
    let mut v =
        femu_sparse::dense::generalized_symmetric_eigenvalues(k.as_ref(), m.as_ref()).unwrap();
    v.truncate(count);
    v
}

fn close(a: &[f64], b: &[f64], rel: f64) {
    assert_eq!(a.len(), b.len());
    for (j, (x, y)) in a.iter().zip(b).enumerate() {
        assert!(
            (x - y).abs() <= rel * y.abs().max(1.0),
            "mode {}: {x:e} against {y:e}",
            j + 1
        );
    }
}

/// GRID field 8 (PS) clamps permanently, as an SPC does; GRDSET's PS applies to grids that leave
/// it blank. Before this was read, the PS deck solved free-free (six zero eigenvalues).
#[test]
fn permanent_constraints_of_grid_and_grdset() {
    let psolid = "PSOLID,1,1,,2,,FULL";
    let by_spc = read(&format!(
        "SOL 103\nCEND\nSPC = 7\nBEGIN BULK\n{}SPC1,7,123,1,5,9,13\n",
        bar(3, |_, _| String::new(), psolid),
    ));
    // the grids at x = 0 of the three-element bar are ids 1, 5, 9, 13
    let clamped: Vec<u64> = by_spc.model.fixed_dofs().map(|(n, _)| n as u64).collect();
    assert_eq!(clamped.len(), 12, "{clamped:?}");
    let x0 = |_: u64, x: f64| {
        if x == 0.0 {
            ",,123".to_string()
        } else {
            String::new()
        }
    };
    let by_ps = read(&bar(3, x0, psolid));
    assert_eq!(by_ps.permanent_constraints, 4);
    let want = eigenvalues(&by_spc, MassKind::Consistent, 6);
    assert!(want[0] > 1e3, "clamped: {want:?}");
    close(&eigenvalues(&by_ps, MassKind::Consistent, 6), &want, 1e-10);
    // GRDSET PS = 3 on every grid that leaves field 8 blank: the bar may move in x and y only,
    // the x = 0 grids keep their own 123
    let grdset = read(&format!("GRDSET,,,,,,,3\n{}", bar(3, x0, psolid)));
    let fixed = grdset.model.fixed_dofs().count();
    assert_eq!(fixed, 12 + 12, "x = 0: 123 on 4 grids; z on the other 12");
    // a PS on components 4-6 of a solid grid has nothing to act on and changes nothing
    let rot = read(&bar(
        3,
        |_, x| {
            if x == 0.0 {
                ",,456".into()
            } else {
                String::new()
            }
        },
        psolid,
    ));
    assert_eq!(rot.model.fixed_dofs().count(), 0);
    // malformed components are refused with the card's line
    let bad = error(&bar(
        3,
        |_, x| {
            if x == 0.0 {
                ",,1x3".into()
            } else {
                String::new()
            }
        },
        psolid,
    ));
    assert!(bad.contains("deck.bdf:1: GRID field 8 (PS)"), "{bad}");
}

/// The case control by its grammar: `SPCFORCES = ALL` after `SPC = 7` does not reset it (it did,
/// by a prefix match), a `$` comment after the value, an abbreviated `METH`, subcases inheriting
/// the selection above them; subcases that select different sets are refused, and so is a
/// selection nothing defines, naming the case control's line.
#[test]
fn case_control_grammar() {
    let psolid = "PSOLID,1,1,,2,,FULL";
    let bulk = format!(
        "{}SPC1,7,123,1,4,7,10\nSPC1,8,1,1,4,7,10\nEIGRL,2,,,3\nEIGRL,4,,,5\n",
        bar(2, |_, _| String::new(), psolid)
    );
    let deck = |case: &str| format!("SOL 103\nCEND\n{case}\nBEGIN BULK\n{bulk}");
    for case in [
        "SPC = 7\nSPCFORCES = ALL\nMETHOD = 4",
        "SPC = 7 $ the clamp\nMETH = 4 $ five modes",
        "TITLE = SPC = 8\nSPC = 7\nSUBCASE 1\n  METHOD = 4\n  DISPLACEMENT(PLOT) = ALL",
        "SUBCASE 1\nSPC=7\nMETHOD=4\nSUBCASE 2\nSPC=7\nMETHOD=4",
    ] {
        let d = read(&deck(case));
        assert_eq!(d.spc_set, Some(7), "{case}");
        assert_eq!(d.model.fixed_dofs().count(), 12, "{case}");
        assert_eq!(d.eigrl, Some((None, None, Some(5))), "{case}");
    }
    let e = error(&deck("SUBCASE 1\nSPC = 7\nSUBCASE 2\nSPC = 8"));
    assert!(
        e.contains("deck.bdf:6: subcases 1 and 2 select different SPC sets (7 (deck.bdf line 4) and 8 (deck.bdf line 6))"),
        "{e}"
    );
    let e = error(&deck("SPC = 9"));
    assert!(
        e.contains("deck.bdf:3: SPC = 9 selects a set that no SPC, SPC1 or SPCADD defines"),
        "{e}"
    );
    let e = error(&deck("SPC = 7\nMETHOD = 3"));
    assert!(
        e.contains("deck.bdf:4: METHOD = 3 selects no EIGRL or EIGR (the deck defines [2, 4])"),
        "{e}"
    );
    let e = error(&deck("SPC = ALL"));
    assert!(e.contains("deck.bdf:3: case control SPC = \"ALL\""), "{e}");
}

/// Continuations pair with their parent by label (Nastran's rule), not by position: an SPC1 whose
/// continuation comes after a GRID clamps all six grids; a free-field line with fewer fields than
/// it holds is padded, so its continuation starts at field 10; the Quick Reference Guide's
/// large-field free-format GRID is read; a label no card holds is refused with its line.
#[test]
fn continuations_by_label_and_field_formats() {
    let psolid = "PSOLID,1,1,,2,,FULL";
    let base = bar(2, |_, _| String::new(), psolid);
    // SPC1 SID C G1..G6: grids 1 4 7 10 on the first line, 2 and 5 on a continuation labelled +S
    // that is written after another card
    let text = format!(
        "SOL 103\nCEND\nSPC = 1\nBEGIN BULK\n{base}SPC1,1,123,1,4,7,10,,,+S\nGRID,99,,9.,9.,9.\n+S,2,5\n"
    );
    let d = read(&text);
    let fixed: std::collections::BTreeSet<u64> = d
        .model
        .fixed_dofs()
        .map(|(n, _)| d.model.mesh().node_id(n))
        .collect();
    assert_eq!(
        fixed.into_iter().collect::<Vec<_>>(),
        vec![1, 2, 4, 5, 7, 10]
    );
    // free field with fewer than eight data fields before a continuation: the line's missing
    // fields are blank, so the continuation starts at G7, as Nastran reads it (the fields were
    // run together, a valid 8-grid CHEXA that Nastran does not see); G3-G6 blank are refused
    let short = base.replace(
        "CHEXA,1,1,1,2,5,4,7,8,+C0\n+C0,11,10",
        "CHEXA,1,1,1,2\n+,5,4,7,8,11,10",
    );
    assert_ne!(short, base);
    let e = error(&short);
    assert!(e.contains("CHEXA 1: a corner grid (G1-G8) is blank"), "{e}");
    // the Quick Reference Guide's large-field free format: GRID*, 4 fields a line
    let large = read(&base.replace(
        "GRID,1,,0.0,0.0,0.0\n",
        "GRID*,1,,0.0,0.0,*G1\n*G1,0.0,,123\n",
    ));
    assert_eq!(large.permanent_constraints, 1);
    assert_eq!(large.model.mesh().coords()[0], [0.0, 0.0, 0.0]);
    // a labelled continuation whose label no card's field 10 holds, below a card that ends with
    // another label
    let e = error(&format!("{base}SPC1,1,123,1,4,7,10,,,+S\n+T,2,5\n"));
    assert!(
        e.contains("continuation +T: no card above ends with the label +T in field 10"),
        "{e}"
    );
}

/// An unknown card is an error naming the nearest known one (it dropped the element or grid with
/// a warning); `--lenient` reads past it with a warning; PARAMs are read (COUPMASS, WTMASS) or
/// named as skipped.
#[test]
fn unknown_and_misspelt_cards() {
    let psolid = "PSOLID,1,1,,2,,FULL";
    let base = bar(2, |_, _| String::new(), psolid);
    let typo = base.replacen("CHEXA,1,", "CHEXAA,1,", 1);
    let e = error(&typo);
    assert!(
        e.contains("unknown card CHEXAA (did you mean CHEXA?)"),
        "{e}"
    );
    let e = error(&base.replacen("GRID,1,", "GIRD,1,", 1));
    assert!(
        e.contains("deck.bdf:1: unknown card GIRD (did you mean GRID?)"),
        "{e}"
    );
    // --lenient: the card and its continuation (paired by its label) are left out, with a warning
    let lenient = parse_bdf(&typo, "deck.bdf", &BdfOptions { lenient: true }).unwrap();
    assert_eq!(lenient.model.mesh().element_count(), 1);
    assert!(
        lenient.warnings[0]
            .message
            .starts_with("unknown card CHEXAA (did you mean CHEXA?) skipped (--lenient)")
    );
    let skipped = parse_bdf(
        &format!("{base}FOOBAR,1,2\n"),
        "deck.bdf",
        &BdfOptions { lenient: true },
    )
    .unwrap();
    assert!(skipped.warnings.iter().any(|w| {
        w.message
            .starts_with("unknown card FOOBAR skipped (--lenient)")
    }));
    let p = read(&format!("{base}PARAM,GRDPNT,0\nPARAM,FOO,1\n"));
    let w: Vec<&str> = p.warnings.iter().map(|w| w.message.as_str()).collect();
    assert!(
        w.iter()
            .any(|m| m.starts_with("PARAM,GRDPNT skipped: it does not change")),
        "{w:?}"
    );
    assert!(
        w.iter()
            .any(|m| m.starts_with("PARAM,FOO skipped: femu does not know")),
        "{w:?}"
    );
}

/// The element stiffness of a linear tetrahedron written out here: `V B^T D B`, with `B` from the
/// gradients of the barycentric coordinates (the inverse of the 4x4 matrix of `[1, x, y, z]`).
fn tet4_stiffness(x: &[[f64; 3]; 4], e: f64, nu: f64) -> (Vec<Vec<f64>>, f64) {
    let a = faer::Mat::<f64>::from_fn(4, 4, |i, j| if j == 0 { 1.0 } else { x[i][j - 1] });
    let inv = a.as_ref().partial_piv_lu().inverse();
    let det: f64 = {
        // volume = |det A| / 6 by the triple product
        let d = |p: [f64; 3], q: [f64; 3]| [q[0] - p[0], q[1] - p[1], q[2] - p[2]];
        let (u, v, w) = (d(x[0], x[1]), d(x[0], x[2]), d(x[0], x[3]));
        u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0])
            + u[2] * (v[0] * w[1] - v[1] * w[0])
    };
    let vol = det.abs() / 6.0;
    // dN_a/dx_c = inv[(1 + c, a)]
    let g = |a: usize, c: usize| inv[(1 + c, a)];
    let lam = e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu));
    let mu = e / (2.0 * (1.0 + nu));
    // Voigt (xx, yy, zz, xy, yz, zx) with engineering shears
    let mut dm = [[0.0; 6]; 6];
    for i in 0..3 {
        for j in 0..3 {
            dm[i][j] = lam + if i == j { 2.0 * mu } else { 0.0 };
        }
        dm[3 + i][3 + i] = mu;
    }
    let mut b = vec![vec![0.0; 12]; 6];
    for a in 0..4 {
        let (bx, by, bz) = (g(a, 0), g(a, 1), g(a, 2));
        b[0][3 * a] = bx;
        b[1][3 * a + 1] = by;
        b[2][3 * a + 2] = bz;
        b[3][3 * a] = by;
        b[3][3 * a + 1] = bx;
        b[4][3 * a + 1] = bz;
        b[4][3 * a + 2] = by;
        b[5][3 * a] = bz;
        b[5][3 * a + 2] = bx;
    }
    let mut k = vec![vec![0.0; 12]; 12];
    for p in 0..12 {
        for q in 0..12 {
            k[p][q] = vol
                * (0..6)
                    .map(|r| (0..6).map(|s| b[r][p] * dm[r][s] * b[s][q]).sum::<f64>())
                    .sum::<f64>();
        }
    }
    (k, vol)
}

/// Without `PARAM,COUPMASS` MSC Nastran uses lumped mass for solids (QRG PARAM COUPMASS: -1, the
/// default); `COUPMASS,1` the coupled mass. A two-tet model, clamped at three grids, against a
/// dense model written out here: `K` from `V B^T D B`, the lumped mass `rho V / 4` on each corner,
/// the coupled mass `rho V / 20 (1 + delta_ab)`. The two formulations differ by tens of percent
/// in a frequency on this coarse model, which femu solved with coupled mass before.
#[test]
fn coupmass_lumped_by_default_against_a_dense_tet4_model() {
    let x: [[f64; 3]; 5] = [
        [0.0, 0.0, 0.0],
        [0.2, 0.0, 0.0],
        [0.0, 0.15, 0.0],
        [0.03, 0.04, 0.1],
        [0.2, 0.17, 0.08],
    ];
    let tets = [[0usize, 1, 2, 3], [1, 2, 3, 4]];
    let (e, nu, rho) = (7.0e10, 0.33, 2700.0);
    let mut text = String::from("SOL 103\nCEND\nSPC = 1\nBEGIN BULK\n");
    for (i, p) in x.iter().enumerate() {
        text.push_str(&format!(
            "GRID,{},,{:?},{:?},{:?}\n",
            i + 1,
            p[0],
            p[1],
            p[2]
        ));
    }
    for (t, n) in tets.iter().enumerate() {
        text.push_str(&format!(
            "CTETRA,{},1,{},{},{},{}\n",
            t + 1,
            n[0] + 1,
            n[1] + 1,
            n[2] + 1,
            n[3] + 1
        ));
    }
    text.push_str(&format!(
        "PSOLID,1,1\nMAT1,1,{e:?},,{nu:?},{rho:?}\nSPC1,1,123,1,2,3\n"
    ));
    // the dense reference on the 6 free DOFs (grids 4 and 5)
    let free = |node: usize, c: usize| (node >= 3).then(|| 3 * (node - 3) + c);
    let mut kd = faer::Mat::<f64>::zeros(6, 6);
    let (mut ml, mut mc) = (faer::Mat::<f64>::zeros(6, 6), faer::Mat::<f64>::zeros(6, 6));
    for n in &tets {
        let xs = [x[n[0]], x[n[1]], x[n[2]], x[n[3]]];
        let (ke, vol) = tet4_stiffness(&xs, e, nu);
        for a in 0..4 {
            for c in 0..3 {
                let Some(p) = free(n[a], c) else { continue };
                ml[(p, p)] += rho * vol / 4.0;
                for b in 0..4 {
                    let Some(q) = free(n[b], c) else { continue };
                    mc[(p, q)] += rho * vol / 20.0 * if a == b { 2.0 } else { 1.0 };
                }
                for b in 0..4 {
                    for d in 0..3 {
                        if let Some(q) = free(n[b], d) {
                            kd[(p, q)] += ke[3 * a + c][3 * b + d];
                        }
                    }
                }
            }
        }
    }
    let dense = |m: &faer::Mat<f64>| {
        femu_sparse::dense::generalized_symmetric_eigenvalues(kd.as_ref(), m.as_ref()).unwrap()
    };
    let (lumped, coupled) = (dense(&ml), dense(&mc));
    let deck = read(&text);
    assert_eq!(deck.mass, MassKind::Lumped);
    assert_eq!(deck.coupmass, None);
    close(&eigenvalues(&deck, deck.mass, 6), &lumped, 1e-9);
    let with = read(&text.replace("PSOLID,1,1\n", "PSOLID,1,1\nPARAM,COUPMASS,1\n"));
    assert_eq!((with.mass, with.coupmass), (MassKind::Consistent, Some(1)));
    close(&eigenvalues(&with, with.mass, 6), &coupled, 1e-9);
    let off = read(&text.replace("PSOLID,1,1\n", "PSOLID,1,1\nPARAM,COUPMASS,-1\n"));
    assert_eq!(off.mass, MassKind::Lumped);
    // how much the formulation matters here: the largest relative difference of a frequency
    let worst = lumped
        .iter()
        .zip(&coupled)
        .map(|(l, c)| ((c / l).sqrt() - 1.0).abs())
        .fold(0.0, f64::max);
    assert!(worst > 0.1, "the two formulations differ by {worst}");
}

/// MAT1 as the Quick Reference Guide completes it: E and G give NU = E / (2 G) - 1, G and NU give
/// E = 2 (1 + NU) G; three moduli that miss the isotropic identity by more than 1 % are refused
/// (femu's isotropic material cannot hold them), within it E and NU are used with a warning.
#[test]
fn mat1_moduli_as_nastran_completes_them() {
    let psolid = "PSOLID,1,1,,2,,FULL";
    let base = bar(1, |_, _| String::new(), psolid);
    let e = 2.1e11;
    let nu = 0.3;
    let g = e / (2.0 * (1.0 + nu));
    let k_of = |mat1: &str| {
        let d = read(&base.replace("MAT1,1,2.1+11,,.3,7850.", mat1));
        let sys = d.model.assemble(MassKind::Consistent).unwrap();
        (femu_sparse::csc::to_dense(&sys.k), d.warnings.len())
    };
    let (want, _) = k_of(&format!("MAT1,1,{e:?},,{nu:?},7850."));
    for mat1 in [
        format!("MAT1,1,{e:?},{g:?},,7850."),
        format!("MAT1,1,,{g:?},{nu:?},7850."),
    ] {
        let (k, _) = k_of(&mat1);
        let diff = (0..k.nrows())
            .flat_map(|i| (0..k.ncols()).map(move |j| (i, j)))
            .map(|(i, j)| (k[(i, j)] - want[(i, j)]).abs())
            .fold(0.0, f64::max);
        assert!(diff < 1e-12 * e, "{mat1}: {diff:e}");
    }
    let (_, warned) = k_of(&format!("MAT1,1,{e:?},{:?},{nu:?},7850.", g * 1.005));
    assert!(warned >= 1);
    let err = error(&base.replace(
        "MAT1,1,2.1+11,,.3,7850.",
        &format!("MAT1,1,{e:?},{:?},{nu:?},7850.", g * 1.2),
    ));
    assert!(err.contains("MAT1 1: E = 2.1e11"), "{err}");
    assert!(err.contains("20.0 % from G"), "{err}");
}

/// PSOLID's CORDM: a MAT9 given in a material frame turned 30 degrees about z is turned into the
/// basic frame (it was read as if given in the basic frame). The reference turns the fourth-order
/// tensor `C_ijkl` index by index, `C'_pqrs = R_pi R_qj R_rk R_sl C_ijkl`, and gives it to femu
/// directly.
#[test]
fn mat9_in_a_turned_material_frame() {
    // an orthotropic material (E1 = 150 GPa along its own x), as a MAT9 in Nastran's order
    let (e1, e2, e3) = (150e9, 10e9, 10e9);
    let (n12, n13, n23) = (0.3, 0.3, 0.45);
    let (g12, g13, g23) = (5e9, 5e9, 3.5e9);
    let s = faer::Mat::<f64>::from_fn(3, 3, |i, j| {
        let e = [e1, e2, e3];
        let n = [
            [0.0, n12, n13],
            [n12 * e2 / e1, 0.0, n23],
            [n13 * e3 / e1, n23 * e3 / e2, 0.0],
        ];
        if i == j { 1.0 / e[i] } else { -n[i][j] / e[i] }
    });
    let c3 = s.as_ref().partial_piv_lu().inverse();
    // Nastran order (x, y, z, xy, yz, zx)
    let mut g = [[0.0; 6]; 6];
    for i in 0..3 {
        for j in 0..3 {
            g[i][j] = 0.5 * (c3[(i, j)] + c3[(j, i)]);
        }
    }
    g[3][3] = g12;
    g[4][4] = g23;
    g[5][5] = g13;
    let mut upper = Vec::new();
    for i in 0..6 {
        for j in i..6 {
            upper.push(format!("{:?}", g[i][j]));
        }
    }
    // MID G11..G23 / G24..G44 / G45..G66 RHO: eight data fields a free-field line
    let mat9 = format!(
        "MAT9,1,{}\n,{}\n,{},1600.",
        upper[..7].join(","),
        upper[7..15].join(","),
        upper[15..21].join(",")
    );
    let angle = 30f64.to_radians();
    let (c, sn) = (angle.cos(), angle.sin());
    // CORD2R 3: origin 0, z axis along z, x-z plane through (cos, sin, 0)
    let frame = format!("CORD2R,3,0,0.,0.,0.,0.,0.,1.\n,{c:?},{sn:?},0.\n");
    let base = bar(2, |_, _| String::new(), "PSOLID,1,1,3,2,,FULL");
    let deck = read(&format!(
        "{frame}{}",
        base.replace("\nMAT1,1,2.1+11,,.3,7850.\n", &format!("\n{mat9}\n"))
    ));
    // the reference: the tensor in the material frame, turned with R (columns: the frame's axes)
    let r = [[c, -sn, 0.0], [sn, c, 0.0], [0.0, 0.0, 1.0]];
    let voigt = |i: usize, j: usize| -> usize {
        // Nastran's order, engineering shears: 11 22 33 12 23 31
        match (i.min(j), i.max(j)) {
            (0, 0) => 0,
            (1, 1) => 1,
            (2, 2) => 2,
            (0, 1) => 3,
            (1, 2) => 4,
            _ => 5,
        }
    };
    let tensor = |i: usize, j: usize, k: usize, l: usize| g[voigt(i, j)][voigt(k, l)];
    let turned = |p: usize, q: usize, rr: usize, s: usize| -> f64 {
        let mut v = 0.0;
        for i in 0..3 {
            for j in 0..3 {
                for k in 0..3 {
                    for l in 0..3 {
                        v += r[p][i] * r[q][j] * r[rr][k] * r[s][l] * tensor(i, j, k, l);
                    }
                }
            }
        }
        v
    };
    // femu's order 11 22 33 12 13 23
    let pairs = [(0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2)];
    let d: [[f64; 6]; 6] = std::array::from_fn(|a| {
        std::array::from_fn(|b| turned(pairs[a].0, pairs[a].1, pairs[b].0, pairs[b].1))
    });
    let mut model = deck.model.clone();
    model
        .set_material(
            Some("PID1"),
            Material::anisotropic("turned", d, 1600.0).unwrap(),
        )
        .unwrap();
    let (k, want) = (
        deck.model.assemble(MassKind::Consistent).unwrap(),
        model.assemble(MassKind::Consistent).unwrap(),
    );
    let (kd, wd) = (
        femu_sparse::csc::to_dense(&k.k),
        femu_sparse::csc::to_dense(&want.k),
    );
    let diff = (0..kd.nrows())
        .flat_map(|i| (0..kd.ncols()).map(move |j| (i, j)))
        .map(|(i, j)| (kd[(i, j)] - wd[(i, j)]).abs())
        .fold(0.0, f64::max);
    assert!(diff < 1e-12 * e1, "{diff:e}");
    // and it is not the material read in the basic frame
    let basic = read(&format!(
        "{frame}{}",
        bar(2, |_, _| String::new(), "PSOLID,1,1,0,2,,FULL")
            .replace("\nMAT1,1,2.1+11,,.3,7850.\n", &format!("\n{mat9}\n"))
    ));
    let bk = femu_sparse::csc::to_dense(&basic.model.assemble(MassKind::Consistent).unwrap().k);
    let apart = (0..kd.nrows())
        .flat_map(|i| (0..kd.ncols()).map(move |j| (i, j)))
        .map(|(i, j)| (kd[(i, j)] - bk[(i, j)]).abs())
        .fold(0.0, f64::max);
    assert!(apart > 1e-3 * e1, "{apart:e}");
    // a cylindrical material frame and the element frame are refused by name
    let e = error(&format!(
        "CORD2C,4,0,0.,0.,0.,0.,0.,1.\n,1.,0.,0.\n{}",
        base.replace("PSOLID,1,1,3,", "PSOLID,1,1,4,")
            .replace("\nMAT1,1,2.1+11,,.3,7850.\n", &format!("\n{mat9}\n"))
    ));
    assert!(e.contains("CORDM = 4 is a cylindrical system"), "{e}");
}

/// The PSOLID's `IN` and `ISOP` choose the 8-node CHEXA's formulation, as MSC Nastran's QRG
/// says: blank, the brick with bubble functions (femu's incompatible modes, with one warning that
/// names them); `IN = 2`, `ISOP = FULL`, the fully integrated brick, without a word.
#[test]
fn the_default_hexa_formulation_is_named() {
    use femu_fem::element::Formulation;
    let default = read(&bar(2, |_, _| String::new(), "PSOLID,1,1"));
    let w: Vec<&str> = default
        .warnings
        .iter()
        .map(|w| w.message.as_str())
        .filter(|m| m.contains("incompatible modes"))
        .collect();
    assert_eq!(w.len(), 1, "{w:?}");
    assert!(
        w[0].starts_with("PSOLID 1: its 2 8-node CHEXA (first: CHEXA 1"),
        "{w:?}"
    );
    let formulations =
        |m: &femu_fem::model::Model| (0..2).map(|e| m.formulation(e)).collect::<Vec<_>>();
    assert_eq!(
        formulations(&default.model),
        [Formulation::IncompatibleModes; 2]
    );
    let full = read(&bar(2, |_, _| String::new(), "PSOLID,1,1,,2,,FULL"));
    assert!(full.warnings.is_empty(), "{:?}", full.warnings);
    assert_eq!(formulations(&full.model), [Formulation::Full; 2]);
}

/// Found by the fuzz test (`fuzz_readers.rs`): a CTETRA with ten grids, a corner given as 0 and a
/// mid-side one blank, passed the blank-corner check (0 is not blank) and panicked on grid 0; an
/// explicit grid id of 0 or below is refused with its field.
#[test]
fn a_grid_id_of_zero_is_refused() {
    let text = "GRID,1,,0.,0.,0.\nGRID,2,,1.,0.,0.\nGRID,3,,0.,1.,0.\nGRID,4,,0.,0.,1.\n\
CTETRA,1,1,1,2,3,0,,,\n,,,,\nPSOLID,1,1\nMAT1,1,2.1+11,,.3,7850.\n";
    let e = error(&format!("{text}GRID,5,,.5,0.,0.\n").replace(
        "CTETRA,1,1,1,2,3,0,,,\n,,,,",
        "CTETRA,1,1,1,2,3,0,5,,\n,,,,",
    ));
    assert!(
        e.contains("CTETRA 1: field 7 (G4) is 0: a grid id is positive"),
        "{e}"
    );
    let e = error(text);
    assert!(e.contains("CTETRA 1: field 7 (G4) is 0"), "{e}");
}
