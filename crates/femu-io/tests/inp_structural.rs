//! Beams and springs of Abaqus/CalculiX decks: B33 against Euler-Bernoulli theory with the
//! section's axes as Abaqus defines them, B31 against CalculiX (which expands each beam into a
//! brick: the difference falls as its mesh is refined), springs against hand-solved oscillators,
//! and what femu cannot build refused with its line.

use femu_fem::assembly::MassKind;
use femu_io::inp::parse_inp;
use femu_sparse::eigen::{EigenOptions, Which};
use std::f64::consts::PI;

/// A cantilever along x of `n` elements of `ty`, RECT 0.02 (along n1 = y) x 0.01, steel.
fn cantilever(n: usize, ty: &str, frequency: bool) -> String {
    let mut s = String::from("*HEADING\ncantilever\n*NODE, NSET=ALL\n");
    for i in 0..=n {
        s.push_str(&format!("{}, {}, 0., 0.\n", i + 1, i as f64 / n as f64));
    }
    s.push_str(&format!("*ELEMENT, TYPE={ty}, ELSET=BEAM\n"));
    for i in 0..n {
        s.push_str(&format!("{}, {}, {}\n", i + 1, i + 1, i + 2));
    }
    s.push_str(
        "*MATERIAL, NAME=STEEL\n*ELASTIC\n2.1e11, 0.3\n*DENSITY\n7850.\n\
         *BEAM SECTION, ELSET=BEAM, MATERIAL=STEEL, SECTION=RECT\n0.02, 0.01\n0., 1., 0.\n\
         *BOUNDARY\n1, 1, 6\n",
    );
    if frequency {
        s.push_str("*STEP\n*FREQUENCY\n6\n*END STEP\n");
    }
    s
}

fn lowest(text: &str, count: usize) -> (Vec<f64>, femu_fem::model::Model, faer::Mat<f64>) {
    let deck = parse_inp(text, "deck.inp").unwrap();
    let model = deck.to_model().unwrap();
    let sys = model.assemble(MassKind::Consistent).unwrap();
    let modes = sys
        .modes(Which::Lowest(count), &EigenOptions::default())
        .unwrap();
    (modes.values, model, modes.vectors)
}

/// B33 (Euler-Bernoulli) cantilever of 40 elements: `(beta L)^4 E I / (rho A L^4)` in both
/// planes; `n1 = y` makes the 0.02 side the section's 1-axis, so the stiff plane bends along y
/// (`I = 0.01 x 0.02^3 / 12`) and the lowest mode moves along z.
#[test]
fn b33_cantilever_against_euler_bernoulli() {
    let (values, model, vectors) = lowest(&cantilever(40, "B33", false), 4);
    let (a, e, rho) = (0.02 * 0.01, 2.1e11, 7850.0);
    let i_z = 0.02 * 0.01f64.powi(3) / 12.0;
    let i_y = 0.01 * 0.02f64.powi(3) / 12.0;
    let beta: [f64; 2] = [1.875_104_068_711_96, 4.694_091_132_974_17];
    let mut want: Vec<f64> = [i_z, i_y]
        .iter()
        .flat_map(|i| beta.iter().map(move |b| b.powi(4) * e * i / (rho * a)))
        .collect();
    want.sort_by(f64::total_cmp);
    for (got, w) in values.iter().zip(&want) {
        assert!((got / w - 1.0).abs() < 1e-6, "{got} against {w}");
    }
    // the first mode's tip moves along z only
    let sys = model.assemble(MassKind::Consistent).unwrap();
    let tip = model.mesh().node_index(41).unwrap();
    let uy = vectors[(sys.dofs.free_index(tip, 1).unwrap(), 0)];
    let uz = vectors[(sys.dofs.free_index(tip, 2).unwrap(), 0)];
    assert!(uy.abs() < 1e-9 * uz.abs(), "{uy} {uz}");
}

/// B31 against CalculiX, which solves each B31 as a brick it expands from the section: the
/// lowest four bending frequencies differ by 6e-4 to 4e-3 with 20 elements, by a quarter to a
/// third of that with 40 (CalculiX's bricks converging as h^2 to the beam femu solves exactly).
#[test]
fn b31_cantilever_against_calculix() {
    if !femu_testkit::ccx::available() {
        return;
    }
    let mut previous: Option<Vec<f64>> = None;
    for n in [20, 40] {
        let text = cantilever(n, "B31", true);
        let ccx = femu_testkit::ccx::frequency_eigenvalues(&text, &format!("b31-{n}"));
        let (femu, _, _) = lowest(&text, 4);
        let diff: Vec<f64> = femu
            .iter()
            .zip(&ccx)
            .map(|(f, c)| (c / f - 1.0).abs())
            .collect();
        for d in &diff {
            assert!(*d < 1e-2, "{n} elements: {diff:?}");
        }
        if let Some(p) = &previous {
            for (now, before) in diff.iter().zip(p) {
                assert!(now < &(0.5 * before), "{n} elements: {diff:?} after {p:?}");
            }
        }
        previous = Some(diff);
    }
}

/// A cantilevered quarter ring of B32 (radius 1 m, RECT 0.02 along `n1 = z` by 0.01 in the plane,
/// steel; nodes end, middle, end on the arc), `n` elements.
fn arc(n: usize) -> String {
    let mut s = String::from("*HEADING\narc\n*NODE, NSET=ALL\n");
    for i in 0..=2 * n {
        let a = std::f64::consts::FRAC_PI_2 * i as f64 / (2 * n) as f64;
        s.push_str(&format!(
            "{}, {:.17}, {:.17}, 0.\n",
            i + 1,
            a.cos(),
            a.sin()
        ));
    }
    s.push_str("*ELEMENT, TYPE=B32, ELSET=BEAM\n");
    for e in 0..n {
        s.push_str(&format!(
            "{}, {}, {}, {}\n",
            e + 1,
            2 * e + 1,
            2 * e + 2,
            2 * e + 3
        ));
    }
    s.push_str(
        "*MATERIAL, NAME=STEEL\n*ELASTIC\n2.1e11, 0.3\n*DENSITY\n7850.\n\
         *BEAM SECTION, ELSET=BEAM, MATERIAL=STEEL, SECTION=RECT\n0.02, 0.01\n0., 0., 1.\n\
         *BOUNDARY\n1, 1, 6\n*STEP\n*FREQUENCY\n6\n*END STEP\n",
    );
    s
}

/// B32 against CalculiX on a curved beam (a cantilevered quarter ring), which CalculiX solves as
/// the 20-node bricks (C3D20R) it expands each B32 into. femu's frequencies are converged with 16
/// elements (32 change them by 1.1e-4 at most, on the fifth), and with 8 they equal femu's B31
/// on 128 straight elements to 2e-3 (1e-5 on the first two). CalculiX's curved bricks converge
/// to them from above (with 8 they are twice as stiff): on the three in-plane bending modes (1, 3
/// and 5) its frequencies are 3.8-5.3 % higher with 16 elements, 0.56-0.83 % with 32 and
/// 0.19-0.25 % with 64 (and a CalculiX C3D8I solid of the same arc, 96 x 2 x 4 bricks, is 0.05-0.19
/// % above femu's B32 on them). On the out-of-plane modes (2, 4, 6), where the ring's curvature
/// couples bending with torsion, CalculiX stays 1.6-4.1 % higher at every mesh: one brick across
/// the section is stiffer in torsion than the section's torsion constant (Roark's, which femu
/// uses).
#[test]
fn b32_arc_against_calculix() {
    if !femu_testkit::ccx::available() {
        return;
    }
    let (coarse, _, _) = lowest(&arc(16), 6);
    let (finer, _, _) = lowest(&arc(32), 6);
    let change: Vec<f64> = coarse
        .iter()
        .zip(&finer)
        .map(|(a, b)| (a / b).sqrt() - 1.0)
        .collect();
    assert!(change.iter().all(|c| c.abs() < 2e-4), "{change:?}");
    let mut previous = [f64::INFINITY; 3];
    for n in [16, 32, 64] {
        let ccx = femu_testkit::ccx::frequency_eigenvalues(&arc(n), &format!("b32-{n}"));
        // frequency ratios
        let diff: Vec<f64> = finer
            .iter()
            .zip(&ccx)
            .map(|(f, c)| (c / f).sqrt() - 1.0)
            .collect();
        for (k, mode) in [0, 2, 4].into_iter().enumerate() {
            assert!(
                diff[mode] > 0.0 && diff[mode] < previous[k] / 2.5,
                "{n} elements: {diff:?}"
            );
            previous[k] = diff[mode];
        }
        for mode in [1, 3, 5] {
            assert!(diff[mode] > 0.01 && diff[mode] < 0.05, "{n}: {diff:?}");
        }
    }
    assert!(previous.iter().all(|d| *d < 3e-3), "{previous:?}");
}

/// T3D2 trusses of a `*SOLID SECTION` whose data line gives the area. A steel rod of 40 trusses
/// along x, clamped at node 1 and held sideways: its first three axial frequencies exceed the
/// fixed-free rod's `(2 n - 1) pi / (2 L) sqrt(E / rho)` by the consistent mass's leading error
/// `(k h)^2 / 24` (6.4e-5, 5.8e-4 and 1.6e-3) to 1 % of it. A tripod: an apex with a 5 kg `*MASS` on three trusses to grounded nodes, in
/// three directions: its three frequencies are the eigenvalues of `sum_i (E A / L_i) d_i d_i^T`
/// over the apex's mass plus a third of each truss's (the consistent mass's diagonal), solved here
/// as a 3 x 3 problem, to 1e-10; without a data line a truss has Abaqus' unit area.
#[test]
fn t3d2_trusses_against_rod_theory_and_a_hand_solved_tripod() {
    let (e, rho, a): (f64, f64, f64) = (2.1e11, 7850.0, 3e-4);
    let mut deck = String::from("*NODE\n");
    for i in 0..=40 {
        deck.push_str(&format!("{}, {}, 0., 0.\n", i + 1, i as f64 / 40.0));
    }
    deck.push_str("*ELEMENT, TYPE=T3D2, ELSET=ROD\n");
    for i in 0..40 {
        deck.push_str(&format!("{}, {}, {}\n", i + 1, i + 1, i + 2));
    }
    deck.push_str(&format!(
        "*MATERIAL, NAME=STEEL\n*ELASTIC\n{e:e}, 0.3\n*DENSITY\n{rho}\n\
         *SOLID SECTION, ELSET=ROD, MATERIAL=STEEL\n{a:e},\n*NSET, NSET=ALL, GENERATE\n1, 41, 1\n\
         *BOUNDARY\n1, 1, 1\nALL, 2, 3\n"
    ));
    let (values, _, _) = lowest(&deck, 3);
    for (n, got) in values.iter().enumerate() {
        let kl = (2 * n + 1) as f64 * PI / 2.0;
        let w = kl * (e / rho).sqrt();
        // the consistent mass's leading error, (k h)^2 / 24
        let lead = (kl / 40.0).powi(2) / 24.0;
        let err = got.sqrt() / w - 1.0;
        assert!((err / lead - 1.0).abs() < 0.01, "{n}: {err} against {lead}");
    }
    // the tripod
    let apex = [0.2, 0.3, 0.1];
    let feet = [[1.5, 0.0, 0.0], [0.0, 1.2, 0.4], [0.3, -0.2, 1.1]];
    let mut deck = format!("*NODE\n1, {}, {}, {}\n", apex[0], apex[1], apex[2]);
    for (i, f) in feet.iter().enumerate() {
        deck.push_str(&format!("{}, {}, {}, {}\n", i + 2, f[0], f[1], f[2]));
    }
    deck.push_str(
        "*ELEMENT, TYPE=T3D2, ELSET=LEGS\n1, 1, 2\n2, 1, 3\n3, 1, 4\n\
         *ELEMENT, TYPE=MASS, ELSET=TOP\n9, 1\n*MASS, ELSET=TOP\n5.\n",
    );
    deck.push_str(&format!(
        "*MATERIAL, NAME=STEEL\n*ELASTIC\n{e:e}, 0.3\n*DENSITY\n{rho}\n\
         *SOLID SECTION, ELSET=LEGS, MATERIAL=STEEL\n{a:e}\n*BOUNDARY\n2, 1, 3\n3, 1, 3\n4, 1, 3\n"
    ));
    let (values, _, _) = lowest(&deck, 3);
    let mut k = faer::Mat::<f64>::zeros(3, 3);
    let mut mass = 5.0;
    for f in &feet {
        let d: Vec<f64> = (0..3).map(|c| f[c] - apex[c]).collect();
        let l = d.iter().map(|v| v * v).sum::<f64>().sqrt();
        for i in 0..3 {
            for j in 0..3 {
                k[(i, j)] += e * a / l * d[i] * d[j] / (l * l);
            }
        }
        mass += rho * a * l / 3.0;
    }
    let eig = k.self_adjoint_eigen(faer::Side::Lower).unwrap();
    for (r, got) in values.iter().enumerate() {
        let want = eig.S()[r] / mass;
        assert!((got / want - 1.0).abs() < 1e-10, "{r}: {got} {want}");
    }
    // no data line: unit area
    let unit = deck.replace(&format!("MATERIAL=STEEL\n{a:e}\n"), "MATERIAL=STEEL\n");
    assert_ne!(unit, deck);
    let model = parse_inp(&unit, "unit.inp").unwrap().to_model().unwrap();
    let femu_fem::structural::StructuralKind::Rod(r) = &model.structural()[0].kind else {
        panic!("a rod")
    };
    assert_eq!(r.area, 1.0);
}

/// Abaqus' `LUMPED` of a beam section: `LUMPED=NO` (Abaqus' consistent beam mass) is read and gives
/// the same frequencies as no `LUMPED`, which warns that Abaqus lumps B31 mass by default (with the
/// section's line; B33 beams, whose mass Abaqus does not lump, get no warning); `LUMPED=YES` and
/// a value that is neither are refused with the line.
#[test]
fn a_beam_section_s_lumped_parameter() {
    let plain = cantilever(10, "B31", false);
    let no = plain.replace("SECTION=RECT", "SECTION=RECT, LUMPED=NO");
    let read = |text: &str| parse_inp(text, "deck.inp").unwrap();
    let warned = |d: &femu_io::inp::InpDeck| {
        d.warnings
            .iter()
            .filter(|w| w.message.contains("lumps their mass"))
            .map(|w| w.line)
            .collect::<Vec<_>>()
    };
    assert_eq!(warned(&read(&plain)), vec![31]);
    assert!(warned(&read(&no)).is_empty());
    assert!(warned(&read(&cantilever(10, "B33", false))).is_empty());
    let (a, _, _) = lowest(&plain, 4);
    let (b, _, _) = lowest(&no, 4);
    assert_eq!(a, b);
    for (value, says) in [("YES", "LUMPED=YES is not read"), ("MAYBE", "YES or NO")] {
        let e = parse_inp(
            &plain.replace("SECTION=RECT", &format!("SECTION=RECT, LUMPED={value}")),
            "deck.inp",
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("deck.inp:31") && e.contains(says), "{e}");
    }
}

/// SPRING1 to ground under a *MASS: `k / m`; SPRING2 between two masses on DOF 2: `k (m1 + m2) /
/// (m1 m2)`; SPRINGA between two masses along their skew line, the same.
#[test]
fn springs_against_hand_solved_oscillators() {
    let deck = "\
*NODE
1, 0., 0., 0.
2, 1., 0., 0.
3, 2., 0., 0.
4, 0., 5., 0.
5, 0.6, 5.8, 0.
*ELEMENT, TYPE=SPRING1, ELSET=S1
10, 1
*SPRING, ELSET=S1
3
4.0e4
*ELEMENT, TYPE=SPRING2, ELSET=S2
11, 2, 3
*SPRING, ELSET=S2
2, 2
9.0e4
*ELEMENT, TYPE=SPRINGA, ELSET=SA
12, 4, 5
*SPRING, ELSET=SA
5.0e4
*ELEMENT, TYPE=MASS, ELSET=M1
20, 1
*MASS, ELSET=M1
2.5
*ELEMENT, TYPE=MASS, ELSET=M2
21, 2
22, 3
23, 4
24, 5
*MASS, ELSET=M2
2.
*BOUNDARY
1, 1, 2
2, 1, 1
2, 3, 3
3, 1, 1
3, 3, 3
4, 3, 3
5, 3, 3
";
    let parsed = parse_inp(deck, "springs.inp").unwrap();
    let model = parsed.to_model().unwrap();
    let sys = model.assemble(MassKind::Consistent).unwrap();
    let modes = sys
        .modes(Which::Lowest(7), &EigenOptions::default())
        .unwrap();
    // free: grids 2, 3 along y together (1), grids 4, 5 in the plane (3 of 4): 4 zeros
    let mut want = [4.0e4 / 2.5, 9.0e4 * 4.0 / 4.0, 5.0e4 * 4.0 / 4.0];
    want.sort_by(f64::total_cmp);
    assert!(modes.values[3].abs() < 1e-8 * want[0], "{:?}", modes.values);
    for (g, w) in modes.values[4..].iter().zip(want) {
        assert!(
            (g / w - 1.0).abs() < 1e-10,
            "{:?} against {want:?}",
            modes.values
        );
    }
}

/// What femu does not build, or a deck gets wrong, is refused with its line.
#[test]
fn bad_beam_and_spring_decks_are_refused_with_their_line() {
    let base = "*NODE\n1, 0., 0., 0.\n2, 1., 0., 0.\n*MATERIAL, NAME=STEEL\n*ELASTIC\n2.1e11, 0.3\n*DENSITY\n7850.\n";
    let cases = [
        (
            "*ELEMENT, TYPE=T3D2, ELSET=B\n1, 1, 2\n",
            "deck.inp:10",
            "T3D2 element 1 has no *SOLID SECTION",
        ),
        (
            "*ELEMENT, TYPE=T3D3, ELSET=B\n1, 1, 2, 2\n",
            "deck.inp:9",
            "T3D3 is not read",
        ),
        (
            "*ELEMENT, TYPE=T3D2, ELSET=B\n1, 1, 2\n*SOLID SECTION, ELSET=B, MATERIAL=STEEL\n0.\n",
            "deck.inp:10",
            "the area A",
        ),
        (
            "*ELEMENT, TYPE=T3D2, ELSET=B\n1, 1, 2\n*SOLID SECTION, ELSET=B, MATERIAL=STEEL\nwide\n",
            "deck.inp:11",
            "cross-sectional area",
        ),
        (
            "*ELEMENT, TYPE=B32OS, ELSET=B\n1, 1, 2, 2\n",
            "deck.inp:9",
            "B32OS is not read",
        ),
        (
            "*ELEMENT, TYPE=B32, ELSET=B\n1, 1, 2, 2\n*BEAM SECTION, ELSET=B, MATERIAL=STEEL, SECTION=RECT\n0.1, 0.01\n0., 0., 1.\n",
            "deck.inp:10",
            "distinct",
        ),
        (
            "*ELEMENT, TYPE=S8R5, ELSET=B\n1, 1, 2, 2\n",
            "deck.inp:9",
            "S8R5 is not read",
        ),
        (
            "*ELEMENT, TYPE=S8R, ELSET=B\n1, 1, 2, 2, 1,\n*NSET, NSET=X\n1\n",
            "deck.inp:10",
            "cut short by a keyword",
        ),
        (
            "*ELEMENT, TYPE=S8R, ELSET=B\n1, 1, 2, 2, 1\n",
            "deck.inp:10",
            "a S8R element is an id and 8 nodes, got 5",
        ),
        (
            "*ELEMENT, TYPE=B31, ELSET=B\n1, 1, 2\n*BEAM SECTION, ELSET=B, MATERIAL=STEEL, SECTION=HEX\n0.1, 0.01\n",
            "deck.inp:11",
            "SECTION=HEX is not read",
        ),
        (
            "*ELEMENT, TYPE=B31, ELSET=B\n1, 1, 2\n",
            "deck.inp:10",
            "has no *BEAM SECTION",
        ),
        (
            "*ELEMENT, TYPE=B31, ELSET=B\n1, 1, 2\n*BEAM SECTION, ELSET=B, MATERIAL=STEEL, SECTION=RECT\n0.1, 0.01\n1., 0., 0.\n",
            "deck.inp:10",
            "parallel",
        ),
        (
            "*ELEMENT, TYPE=B31, ELSET=B\n1, 1, 2\n*BEAM GENERAL SECTION, ELSET=B, SECTION=GENERAL\n1e-4, 1e-8, 1e-9, 2e-8, 1e-8\n0., 1., 0.\n2.1e11, 8e10\n",
            "deck.inp:11",
            "I12",
        ),
        (
            "*ELEMENT, TYPE=SPRING2, ELSET=S\n1, 1, 2\n*SPRING, ELSET=S\n1, 1\n",
            "deck.inp:11",
            "lacks its stiffness",
        ),
    ];
    for (cards, at, what) in cases {
        let text = format!("{base}{cards}");
        let e = parse_inp(&text, "deck.inp")
            .and_then(|d| d.to_model())
            .map(|_| ())
            .unwrap_err()
            .to_string();
        assert!(e.contains(at) && e.contains(what), "{cards}: {e}");
    }
}

/// NAFEMS FV16 (a cantilevered square plate of `n x n` S4 shells): femu's frequencies, and
/// CalculiX's of the same deck.
fn fv16(n: usize) -> String {
    fv16_of(n, false)
}

/// [`fv16`] with each square cut into two S3 when `triangles`.
fn fv16_of(n: usize, triangles: bool) -> String {
    let mut s = fv16_nodes(n);
    s.push_str(if triangles {
        "*ELEMENT, TYPE=S3, ELSET=PLATE\n"
    } else {
        "*ELEMENT, TYPE=S4, ELSET=PLATE\n"
    });
    let g = |i: usize, j: usize| 1 + i + (n + 1) * j;
    for j in 0..n {
        for i in 0..n {
            let id = 1 + i + n * j;
            if triangles {
                s.push_str(&format!(
                    "{}, {}, {}, {}\n{}, {}, {}, {}\n",
                    2 * id,
                    g(i, j),
                    g(i + 1, j),
                    g(i + 1, j + 1),
                    2 * id + 1,
                    g(i, j),
                    g(i + 1, j + 1),
                    g(i, j + 1)
                ));
            } else {
                s.push_str(&format!(
                    "{id}, {}, {}, {}, {}\n",
                    g(i, j),
                    g(i + 1, j),
                    g(i + 1, j + 1),
                    g(i, j + 1)
                ));
            }
        }
    }
    fv16_end(s, n)
}

/// FV16's heading and the `(m + 1) x (m + 1)` grid of its 10 m square plate, node `1 + i + (m +
/// 1) j` at `(10 i / m, 10 j / m, 0)`.
fn fv16_nodes(m: usize) -> String {
    let mut s = String::from("*HEADING\nfv16\n*NODE\n");
    for j in 0..=m {
        for i in 0..=m {
            s.push_str(&format!(
                "{}, {}, {}, 0.\n",
                1 + i + (m + 1) * j,
                10.0 * i as f64 / m as f64,
                10.0 * j as f64 / m as f64
            ));
        }
    }
    s
}

/// FV16's deck after its elements (set PLATE) on the grid of [`fv16_nodes`]: the edge x = 0
/// clamped, steel, 50 mm, and a `*FREQUENCY` step of six modes.
fn fv16_end(mut s: String, m: usize) -> String {
    s.push_str("*NSET, NSET=CLAMP\n");
    for j in 0..=m {
        s.push_str(&format!("{}\n", 1 + (m + 1) * j));
    }
    s.push_str(
        "*MATERIAL, NAME=STEEL\n*ELASTIC\n2.e11, 0.3\n*DENSITY\n8000.\n\
         *SHELL SECTION, ELSET=PLATE, MATERIAL=STEEL\n0.05\n*BOUNDARY\nCLAMP, 1, 6\n\
         *STEP\n*FREQUENCY\n6\n*END STEP\n",
    );
    s
}

/// S4 shells read from a deck: NAFEMS FV16's frequencies (0.421, 1.029, 2.582, 3.306, 3.753,
/// 6.555 Hz) to 1 % with 16 x 16 shells (and with 32 x 32 x 2 S3); and CalculiX on the same deck, which expands each S4 into
/// a brick through the thickness and converges to femu's shells as the mesh is refined: its
/// frequencies exceed femu's by up to 11 % with 16 x 16 shells and by under 1 % with 32 x 32
/// (0.2-0.6 % measured on modes 2-6).
#[test]
fn s4_plate_against_nafems_fv16_and_calculix() {
    // S4 16 x 16, and S3 32 x 32 x 2
    for text in [fv16(16), fv16_of(32, true)] {
        let (values, _, _) = lowest(&text, 6);
        for (l, r) in values
            .iter()
            .zip([0.421, 1.029, 2.582, 3.306, 3.753, 6.555])
        {
            let f = l.sqrt() / (2.0 * std::f64::consts::PI);
            assert!((f / r - 1.0).abs() < 1e-2, "{f} Hz against {r}");
        }
    }
    if !femu_testkit::ccx::available() {
        return;
    }
    let mut previous: Option<f64> = None;
    for n in [16, 32] {
        let text = fv16(n);
        let ccx = femu_testkit::ccx::frequency_eigenvalues(&text, &format!("s4-{n}"));
        let (femu, _, _) = lowest(&text, 6);
        let worst = femu
            .iter()
            .zip(&ccx)
            .map(|(f, c)| (c / f).sqrt() - 1.0)
            .fold(0.0f64, |m, d| m.max(d.abs()));
        if let Some(p) = previous {
            assert!(worst < 0.25 * p && worst < 1e-2, "{n}: {worst} after {p}");
        }
        previous = Some(worst);
    }
}

/// `*SHELL SECTION, OFFSET=` as Abaqus defines it (the nodes' surface from the midsurface, a
/// fraction of the thickness): two S4 layers 0.05 thick on the same nodes, one `OFFSET=SNEG`
/// (the nodes on its bottom face), the other `OFFSET=SPOS`, are the FV16 plate 0.1 thick: its six
/// lowest eigenvalues to 1 %, from below (3.5e-4 to 6.8e-3 measured on 8 x 8 shells: S4's
/// incompatible-mode membranes relax the layers' share `z kappa` of the bending; with the bilinear
/// membrane the identity holds to 1e-6, `two_offset_layers_are_one_plate_twice_as_thick`); with
/// `OFFSET=0.5` on both their midsurfaces coincide, two plates 0.05 thick with a quarter of its
/// bending stiffness per mass (the first eigenvalue a quarter of the plate's).
#[test]
fn shell_section_offsets_make_one_plate_of_two() {
    let n = 8;
    let base = fv16(n);
    let single = base.replace("MATERIAL=STEEL\n0.05\n", "MATERIAL=STEEL\n0.1\n");
    let layered = |top: &str, bottom: &str| {
        let mut lower = String::from("*ELEMENT, TYPE=S4, ELSET=LOWER\n");
        let g = |i: usize, j: usize| 1 + i + (n + 1) * j;
        for j in 0..n {
            for i in 0..n {
                lower.push_str(&format!(
                    "{}, {}, {}, {}, {}\n",
                    1000 + i + n * j,
                    g(i, j),
                    g(i + 1, j),
                    g(i + 1, j + 1),
                    g(i, j + 1)
                ));
            }
        }
        base.replace(
            "*NSET, NSET=CLAMP\n",
            &format!("{lower}*NSET, NSET=CLAMP\n"),
        )
        .replace(
            "*SHELL SECTION, ELSET=PLATE, MATERIAL=STEEL\n0.05\n",
            &format!(
                "*SHELL SECTION, ELSET=PLATE, MATERIAL=STEEL, OFFSET={top}\n0.05\n\
                     *SHELL SECTION, ELSET=LOWER, MATERIAL=STEEL, OFFSET={bottom}\n0.05\n"
            ),
        )
    };
    let (want, _, _) = lowest(&single, 6);
    let (got, _, _) = lowest(&layered("SNEG", "SPOS"), 6);
    let (same_side, _, _) = lowest(&layered("0.5", "0.5"), 6);
    for (w, g) in want.iter().zip(&got) {
        assert!(g < w && g / w > 0.99, "{got:?} against {want:?}");
    }
    assert!(
        same_side[0] / want[0] < 0.3,
        "{same_side:?} against {want:?}"
    );
}

/// `*SHELL SECTION, COMPOSITE` of `*ELASTIC, TYPE=LAMINA` layers as Abaqus defines them (one data
/// line a layer: thickness, section points, material, angle; `SYMMETRIC` the lower half): NAFEMS
/// FV16's cantilevered plate as a `[45/-45]s` of two laminae (densities 1600 and 2000, `G13 =
/// G23`) has the frequencies of the same plate as a Nastran deck with the PCOMP of MAT8 plies
/// (both readers make the section by `femu_fem::shell::laminate`; the material axis Abaqus's
/// default, global x projected, is the CQUAD4's edge G1-G2 here) to 1e-9, all four layers listed
/// or the lower two with `SYMMETRIC`; the default axis of a shell whose normal is global x is
/// global z (the plate turned into the y-z plane, a 0-degree ply, is the flat plate's 90-degree
/// one, to 1e-9); an `ORIENTATION=` or a layer's orientation of no `*ORIENTATION`, an
/// unsymmetric stack and a LAMINA short of its six constants are refused with their line.
#[test]
fn composite_shell_sections_are_the_nastran_laminate() {
    let n = 8;
    let base = fv16(n);
    let head = &base[..base.find("*MATERIAL").unwrap()];
    let tail = &base[base.find("*BOUNDARY").unwrap()..];
    let laminae = "*MATERIAL, NAME=CFRP\n*ELASTIC, TYPE=LAMINA\n1.4e11, 1.e10, 0.3, 5.e9, 4.e9, 4.e9\n*DENSITY\n1600.\n\
                   *MATERIAL, NAME=HEAVY\n*ELASTIC, TYPE=LAMINA\n1.4e11, 1.e10, 0.3, 5.e9, 4.e9, 4.e9\n*DENSITY\n2000.\n";
    let abaqus = |section: &str| format!("{head}{laminae}{section}{tail}");
    let all = abaqus(
        "*SHELL SECTION, ELSET=PLATE, COMPOSITE\n0.0125, 3, CFRP, 45.\n0.0125, 3, HEAVY, -45.\n0.0125, 3, HEAVY, -45.\n0.0125, 3, CFRP, 45.\n",
    );
    let sym = abaqus(
        "*SHELL SECTION, ELSET=PLATE, COMPOSITE, SYMMETRIC\n0.0125, 3, CFRP, 45.\n0.0125, 3, HEAVY, -45.\n",
    );
    let mut bdf = String::from("SOL 103\nCEND\nSPC = 1\nBEGIN BULK\nPARAM,COUPMASS,1\n");
    let g = |i: usize, j: usize| 1 + i + (n + 1) * j;
    for j in 0..=n {
        for i in 0..=n {
            bdf.push_str(&format!(
                "GRID,{},,{},{},0.\n",
                g(i, j),
                10.0 * i as f64 / n as f64,
                10.0 * j as f64 / n as f64
            ));
        }
        bdf.push_str(&format!("SPC1,1,123456,{}\n", g(0, j)));
    }
    for j in 0..n {
        for i in 0..n {
            bdf.push_str(&format!(
                "CQUAD4,{},1,{},{},{},{}\n",
                1 + i + n * j,
                g(i, j),
                g(i + 1, j),
                g(i + 1, j + 1),
                g(i, j + 1)
            ));
        }
    }
    bdf.push_str(
        "PCOMP,1,,,,,,,SYM\n,8,0.0125,45.,,9,0.0125,-45.\nMAT8,8,1.4+11,1.+10,0.3,5.+9,4.+9,4.+9,1600.\nMAT8,9,1.4+11,1.+10,0.3,5.+9,4.+9,4.+9,2000.\nENDDATA\n",
    );
    let nastran = femu_io::nastran::parse_bdf(&bdf, "plate.bdf", &Default::default()).unwrap();
    let want = nastran
        .model
        .assemble(MassKind::Consistent)
        .unwrap()
        .modes(Which::Lowest(4), &EigenOptions::default())
        .unwrap()
        .values;
    for deck in [&all, &sym] {
        let (got, _, _) = lowest(deck, 4);
        for (a, b) in got.iter().zip(&want) {
            assert!((a / b - 1.0).abs() < 1e-9, "{got:?} vs {want:?}");
        }
    }
    // the default local axes: the plate turned into the y-z plane (x to y, y to z: its normal
    // along x) takes global z, the image of the flat plate's y, so a 0-degree ply there is the
    // flat plate's 90-degree ply
    let single = |angle: &str| {
        abaqus(&format!(
            "*SHELL SECTION, ELSET=PLATE, COMPOSITE\n0.05, 3, CFRP, {angle}\n"
        ))
    };
    let flat = single("90.");
    let nodes_end = flat.find("*ELEMENT").unwrap();
    let turned: String = flat[..nodes_end]
        .lines()
        .map(|l| {
            let f: Vec<&str> = l.split(", ").collect();
            if f.len() == 4 {
                format!("{}, 0., {}, {}\n", f[0], f[1], f[2])
            } else {
                format!("{l}\n")
            }
        })
        .collect::<String>()
        + &single("0.")[nodes_end..];
    let (a, _, _) = lowest(&flat, 4);
    let (b, _, _) = lowest(&turned, 4);
    for (x, y) in a.iter().zip(&b) {
        assert!((x / y - 1.0).abs() < 1e-9, "{a:?} vs {b:?}");
    }
    let (c, _, _) = lowest(&single("0."), 4);
    assert!(
        (c[0] / a[0] - 1.0).abs() > 0.1,
        "the ply's angle matters: {c:?} {a:?}"
    );
    let refused = |section: &str, extra: &str| -> String {
        parse_inp(
            &abaqus(section).replace(
                "*MATERIAL, NAME=CFRP",
                &format!("{extra}*MATERIAL, NAME=CFRP"),
            ),
            "bad.inp",
        )
        .and_then(|d| d.to_model().map(|_| ()))
        .unwrap_err()
        .to_string()
    };
    let e = refused(
        "*SHELL SECTION, ELSET=PLATE, COMPOSITE, ORIENTATION=ORI\n0.01, 3, CFRP, 0.\n",
        "",
    );
    assert!(
        e.contains("bad.inp:") && e.contains("ORIENTATION=ORI: no *ORIENTATION has that name"),
        "{e}"
    );
    let e = refused(
        "*SHELL SECTION, ELSET=PLATE, COMPOSITE\n0.01, 3, CFRP, ORI\n",
        "",
    );
    assert!(
        e.contains("layer 1: ORIENTATION=ORI: no *ORIENTATION"),
        "{e}"
    );
    let e = refused(
        "*SHELL SECTION, ELSET=PLATE, COMPOSITE\n0.01, 3, CFRP, 0.\n0.01, 3, CFRP, 90.\n",
        "",
    );
    assert!(e.contains("not symmetric about its mid-plane"), "{e}");
    let e = refused(
        "*SHELL SECTION, ELSET=PLATE, COMPOSITE\n0.01, 3, THIN, 0.\n",
        "*MATERIAL, NAME=THIN\n*ELASTIC, TYPE=LAMINA\n1.e11, 1.e10, 0.3\n*DENSITY\n1.\n",
    );
    assert!(
        e.contains("needs E1, E2, NU12, G12, G13, G23, got 3 values"),
        "{e}"
    );
}

/// `*ORIENTATION` on shells, as Abaqus defines it for shells (docs/MATH.md, "Material
/// orientations"): the second data line names the local axis nearest the normal, the next axis
/// of the cycle (1, 2, 3) projected onto the shell is the material 1-direction, and the rotation
/// turns the two others about the named one. On NAFEMS FV16's plate (8 x 8 S4, in the x-y plane)
/// of one CFRP ply, 50 mm, against the default axes with the ply at 30 degrees (each to 1e-9): a
/// rectangular orientation whose 1-axis is at 30 degrees with `3, 0.`; the global axes with `3,
/// 30.`; a `*SHELL SECTION` of the LAMINA itself (not composite) in that orientation; the same of
/// a material of `ENGINEERING CONSTANTS` (its plane-stress constants those of the LAMINA); a
/// composite layer that names the orientation instead of an angle. `1, 0.` on the global axes
/// projects the 2-axis: the ply at 90 degrees. On the clamped cylindrical panel of S8R (radius 1
/// m about y), a cylindrical orientation about the panel's axis with `1, 0.` (the radial axis
/// nearest the normal: the circumferential axis projected) is Abaqus's default there (global x
/// projected, which is circumferential) to 1e-9, and `1, 90.` the ply at 90 degrees. Refused with
/// their line: an orientation no card defines (with the nearest name), a shell's orientation
/// without its second data line, one whose projected axis is the shell's normal (the element
/// named), an axis other than 1-3, `SYSTEM=SPHERICAL`, and a cylindrical orientation on an
/// anisotropic solid section.
#[test]
fn shell_orientations_turn_the_plies_as_abaqus_does() {
    let n = 8;
    let base = fv16(n);
    let head = &base[..base.find("*MATERIAL").unwrap()];
    let tail = &base[base.find("*BOUNDARY").unwrap()..];
    let materials = "*MATERIAL, NAME=CFRP\n*ELASTIC, TYPE=LAMINA\n1.4e11, 1.e10, 0.3, 5.e9, 4.e9, 3.e9\n*DENSITY\n1600.\n\
                     *MATERIAL, NAME=ENG\n*ELASTIC, TYPE=ENGINEERING CONSTANTS\n1.4e11, 1.e10, 1.2e10, 0.3, 0.25, 0.4, 5.e9, 4.e9,\n3.e9\n*DENSITY\n1600.\n";
    let (c, s) = (30f64.to_radians().cos(), 30f64.to_radians().sin());
    let orientations = format!(
        "*ORIENTATION, NAME=OR1\n{c}, {s}, 0., {}, {c}, 0.\n3, 0.\n\
         *ORIENTATION, NAME=OR2\n1., 0., 0., 0., 1., 0.\n3, 30.\n\
         *ORIENTATION, NAME=NORMAL1\n1., 0., 0., 0., 1., 0.\n1, 0.\n",
        -s
    );
    let deck = |section: &str| format!("{head}{materials}{orientations}{section}{tail}");
    let single = |angle: &str| {
        deck(&format!(
            "*SHELL SECTION, ELSET=PLATE, COMPOSITE\n0.05, 3, CFRP, {angle}\n"
        ))
    };
    let (want, _, _) = lowest(&single("30."), 4);
    let same = |text: &str, want: &[f64]| {
        let (got, _, _) = lowest(text, 4);
        for (a, b) in got.iter().zip(want) {
            assert!((a / b - 1.0).abs() < 1e-9, "{got:?} vs {want:?}");
        }
    };
    for section in [
        "*SHELL SECTION, ELSET=PLATE, COMPOSITE, ORIENTATION=OR1\n0.05, 3, CFRP, 0.\n",
        "*SHELL SECTION, ELSET=PLATE, COMPOSITE, ORIENTATION=OR2\n0.05, 3, CFRP, 0.\n",
        "*SHELL SECTION, ELSET=PLATE, MATERIAL=CFRP, ORIENTATION=OR2\n0.05\n",
        "*SHELL SECTION, ELSET=PLATE, MATERIAL=ENG, ORIENTATION=OR1\n0.05\n",
        "*SHELL SECTION, ELSET=PLATE, COMPOSITE\n0.05, 3, CFRP, OR2\n",
    ] {
        same(&deck(section), &want);
    }
    let (zero, _, _) = lowest(&single("0."), 4);
    assert!((zero[0] / want[0] - 1.0).abs() > 0.05, "{zero:?} {want:?}");
    let (ninety, _, _) = lowest(&single("90."), 4);
    same(
        &deck("*SHELL SECTION, ELSET=PLATE, COMPOSITE, ORIENTATION=NORMAL1\n0.05, 3, CFRP, 0.\n"),
        &ninety,
    );
    // the cylindrical panel: a cylindrical orientation about its axis (y)
    let panel = |section: &str| {
        let p = s8r_panel(4, 0.01, "");
        let head = &p[..p.find("*MATERIAL").unwrap()];
        let tail = &p[p.find("*BOUNDARY").unwrap()..];
        format!(
            "{head}{materials}*ORIENTATION, NAME=CYL, SYSTEM=CYLINDRICAL\n0., 0., 0., 0., 1., 0.\n1, 0.\n\
             *ORIENTATION, NAME=CYL90, SYSTEM=CYLINDRICAL\n0., 0., 0., 0., 1., 0.\n1, 90.\n{section}{tail}"
        )
    };
    let ply = |extra: &str, angle: &str| {
        panel(&format!(
            "*SHELL SECTION, ELSET=PANEL, COMPOSITE{extra}\n0.01, 3, CFRP, {angle}\n"
        ))
    };
    let (default, _, _) = lowest(&ply("", "0."), 4);
    same(&ply(", ORIENTATION=CYL", "0."), &default);
    let (at90, _, _) = lowest(&ply("", "90."), 4);
    same(&ply(", ORIENTATION=CYL90", "0."), &at90);
    assert!(
        (at90[0] / default[0] - 1.0).abs() > 0.05,
        "{at90:?} {default:?}"
    );
    // refusals
    let refused = |text: &str| -> String {
        parse_inp(text, "bad.inp")
            .and_then(|d| d.to_model().map(|_| ()))
            .unwrap_err()
            .to_string()
    };
    let e = refused(&deck(
        "*SHELL SECTION, ELSET=PLATE, COMPOSITE, ORIENTATION=OR3\n0.05, 3, CFRP, 0.\n",
    ));
    assert!(
        e.contains("ORIENTATION=OR3: no *ORIENTATION") && e.contains("OR1"),
        "{e}"
    );
    let e = refused(
        &deck("*SHELL SECTION, ELSET=PLATE, COMPOSITE, ORIENTATION=OR2\n0.05, 3, CFRP, 0.\n")
            .replace("0., 1., 0.\n3, 30.\n", "0., 1., 0.\n"),
    );
    assert!(
        e.contains("NAME=OR2") && e.contains("second data line"),
        "{e}"
    );
    let e = refused(
        &deck("*SHELL SECTION, ELSET=PLATE, COMPOSITE, ORIENTATION=OR2\n0.05, 3, CFRP, 0.\n")
            .replace("0., 1., 0.\n3, 30.\n", "0., 1., 0.\n2, 0.\n"),
    );
    assert!(
        e.contains("local 3-axis")
            && e.contains("normal to the element")
            && e.contains("element 1"),
        "{e}"
    );
    let e = refused(
        &deck("*SHELL SECTION, ELSET=PLATE, COMPOSITE, ORIENTATION=OR2\n0.05, 3, CFRP, 0.\n")
            .replace("0., 1., 0.\n3, 30.\n", "0., 1., 0.\n4, 30.\n"),
    );
    assert!(e.contains("not 1, 2 or 3"), "{e}");
    let e = refused(
        &deck("*SHELL SECTION, ELSET=PLATE, MATERIAL=CFRP\n0.05\n").replace(
            "*ORIENTATION, NAME=OR2",
            "*ORIENTATION, NAME=OR2, SYSTEM=SPHERICAL",
        ),
    );
    assert!(e.contains("SYSTEM=SPHERICAL is not read"), "{e}");
    let solid = "*NODE\n1, 0., 0., 0.\n2, 1., 0., 0.\n3, 1., 1., 0.\n4, 0., 1., 0.\n5, 0., 0., 1.\n\
                 6, 1., 0., 1.\n7, 1., 1., 1.\n8, 0., 1., 1.\n*ELEMENT, TYPE=C3D8, ELSET=B\n1, 1, 2, 3, 4, 5, 6, 7, 8\n\
                 *MATERIAL, NAME=ENG\n*ELASTIC, TYPE=ENGINEERING CONSTANTS\n1.4e11, 1.e10, 1.2e10, 0.3, 0.25, 0.4, 5.e9, 4.e9,\n3.e9\n*DENSITY\n1600.\n\
                 *ORIENTATION, NAME=CYL, SYSTEM=CYLINDRICAL\n5., 0., 0., 5., 0., 1.\n\
                 *SOLID SECTION, ELSET=B, MATERIAL=ENG, ORIENTATION=CYL\n";
    let e = refused(solid);
    assert!(
        e.contains("bad.inp:") && e.contains("changes from element to element"),
        "{e}"
    );
}

/// A skewed plate (1 m square sheared by 0.3 m along x, 20 mm) of `n x n` S8R clamped along
/// `y = 0`, of an orthotropic carbon-epoxy in a rectangular orientation turned by `angle` degrees
/// about its 3-axis (the plate's normal).
fn skewed_orthotropic_plate(n: usize, angle: f64) -> String {
    let mut s = String::from("*HEADING\nskewed orthotropic plate\n*NODE\n");
    let id = |(i, j): (usize, usize)| 1 + i + (2 * n + 1) * j;
    for p in femu_testkit::quad8_points(n, n) {
        let (u, v) = (p.0 as f64 / (2 * n) as f64, p.1 as f64 / (2 * n) as f64);
        s.push_str(&format!("{}, {:.12}, {:.12}, 0.\n", id(p), u + 0.3 * v, v));
    }
    s.push_str("*ELEMENT, TYPE=S8R, ELSET=PLATE\n");
    for (e, cell) in femu_testkit::quad8_cells(n, n).iter().enumerate() {
        let g: Vec<String> = cell.iter().map(|&p| id(p).to_string()).collect();
        s.push_str(&format!("{}, {}\n", e + 1, g.join(", ")));
    }
    s.push_str("*NSET, NSET=CLAMP\n");
    for i in 0..=2 * n {
        s.push_str(&format!("{}\n", id((i, 0))));
    }
    s.push_str(&format!(
        "*MATERIAL, NAME=CFRP\n*ELASTIC, TYPE=ENGINEERING CONSTANTS\n\
         1.4e11, 1.e10, 1.e10, 0.3, 0.3, 0.45, 5.e9, 5.e9,\n3.5e9\n*DENSITY\n1600.\n\
         *ORIENTATION, NAME=OR\n1., 0., 0., 0., 1., 0.\n3, {angle}\n\
         *SHELL SECTION, ELSET=PLATE, MATERIAL=CFRP, ORIENTATION=OR\n0.02\n\
         *BOUNDARY\nCLAMP, 1, 6\n*STEP\n*FREQUENCY\n6\n*END STEP\n"
    ));
    s
}

/// An orthotropic shell in an orientation against CalculiX on the same deck (which expands each
/// S8R into a C3D20R brick and turns the brick's material by the orientation in 3D; on a flat
/// plate whose normal is the orientation's 3-axis the two readings are one): the skewed plate's six
/// lowest frequencies with the fibres at +35 degrees and CalculiX's converge together (largest
/// difference 1.8 % on 4 x 4, 0.85 % on 8 x 8, measured 0.47 % on 16 x 16: the brick's
/// through-the-thickness model against the shell's, as for the isotropic panel), while the fibres
/// at -35 degrees, the plate's mirror image, are 37-40 % from CalculiX's +35: the sense of the
/// rotation is CalculiX's and Abaqus's.
#[test]
fn an_oriented_orthotropic_shell_against_calculix() {
    if !femu_testkit::ccx::available() {
        return;
    }
    let mut differences = Vec::new();
    for n in [4usize, 8] {
        let text = skewed_orthotropic_plate(n, 35.0);
        let (femu, _, _) = lowest(&text, 6);
        let (mirror, _, _) = lowest(&skewed_orthotropic_plate(n, -35.0), 6);
        let ccx = femu_testkit::ccx::frequency_eigenvalues(&text, &format!("oriented-s8r-{n}"));
        assert_eq!(ccx.len(), 6, "{ccx:?}");
        let worst = |a: &[f64]| {
            a.iter()
                .zip(&ccx)
                .map(|(f, c)| ((c / f).sqrt() - 1.0).abs())
                .fold(0.0f64, f64::max)
        };
        let (same, other) = (worst(&femu), worst(&mirror));
        assert!(other > 10.0 * same, "{n}: {same:.2e} {other:.2e}");
        differences.push(same);
    }
    assert!(
        differences[0] < 2.5e-2 && differences[1] < 1.2e-2 && differences[1] < 0.6 * differences[0],
        "{differences:?}"
    );
}

/// `*DAMPING, STRUCTURAL=` in a `*MATERIAL` gives the solids and shells of its sections that
/// structural damping coefficient (`GE`: `K_4` is 0.03 `K`, to 1e-14) and `ALPHA=`, `BETA=` their
/// Rayleigh damping (Abaqus' material damping: the viscous `C` is `2 M + 1e-5 K` of the consistent
/// mass and the stiffness assembled, to 1e-14); outside a material `ALPHA` (CalculiX's Rayleigh
/// damping of a `*DYNAMIC` step) is not read, with a warning on its line; `STRUCTURAL=` outside a
/// material, a negative value, a negative `ALPHA` and a composite section whose plies' materials
/// are damped differently are refused with the line.
#[test]
fn material_structural_damping_reaches_solids_and_shells() {
    let base = "\
*NODE
1, 0., 0., 0.
2, 1., 0., 0.
3, 1., 1., 0.
4, 0., 1., 0.
5, 0., 0., 1.
6, 1., 0., 1.
7, 1., 1., 1.
8, 0., 1., 1.
9, 2., 0., 0.
10, 2., 1., 0.
*ELEMENT, TYPE=C3D8, ELSET=BLOCK
1, 1, 2, 3, 4, 5, 6, 7, 8
*ELEMENT, TYPE=S4, ELSET=SKIN
2, 2, 9, 10, 3
*MATERIAL, NAME=STEEL
*ELASTIC
2.1e11, 0.3
*DENSITY
7850.
";
    let read = |rest: &str| femu_io::inp::parse_inp(&format!("{base}{rest}"), "d.inp");
    let deck = read(
        "*DAMPING, STRUCTURAL=0.03, ALPHA=2., BETA=1e-5\n*SOLID SECTION, ELSET=BLOCK, MATERIAL=STEEL\n\
         *SHELL SECTION, ELSET=SKIN, MATERIAL=STEEL\n0.01\n",
    )
    .unwrap();
    assert!(deck.warnings.is_empty(), "{:?}", deck.warnings);
    let model = deck.to_model().unwrap();
    assert_eq!(
        model.element_damping().iter().collect::<Vec<_>>(),
        vec![(&1, &0.03), (&2, &0.03)]
    );
    assert_eq!(
        model.element_rayleigh().iter().collect::<Vec<_>>(),
        vec![(&1, &(2.0, 1e-5)), (&2, &(2.0, 1e-5))]
    );
    let consistent = femu_fem::assembly::MassKind::Consistent;
    let asm = femu_fem::assembly::Assembler::new(&model).unwrap();
    let c = femu_sparse::csc::to_dense(&asm.dampers(&model, consistent).unwrap().viscous.unwrap());
    let sys = model.assemble(consistent).unwrap();
    let (k, m) = (
        femu_sparse::csc::to_dense(&sys.k),
        femu_sparse::csc::to_dense(&sys.m),
    );
    let scale = (0..k.nrows())
        .flat_map(|i| (0..k.ncols()).map(move |j| (i, j)))
        .map(|(i, j)| (2.0 * m[(i, j)] + 1e-5 * k[(i, j)]).abs())
        .fold(0.0, f64::max);
    let worst = (0..k.nrows())
        .flat_map(|i| (0..k.ncols()).map(move |j| (i, j)))
        .map(|(i, j)| (c[(i, j)] - 2.0 * m[(i, j)] - 1e-5 * k[(i, j)]).abs())
        .fold(0.0, f64::max);
    assert!(worst < 1e-14 * scale, "{worst:e}");
    let outside = read(
        "*SOLID SECTION, ELSET=BLOCK, MATERIAL=STEEL\n*SHELL SECTION, ELSET=SKIN, MATERIAL=STEEL\n0.01\n\
         *DAMPING, ALPHA=2.\n",
    )
    .unwrap();
    let w: Vec<String> = outside.warnings.iter().map(|w| w.to_string()).collect();
    assert!(
        w.iter()
            .any(|w| w.contains("d.inp:24") && w.contains("ALPHA")),
        "{w:?}"
    );
    assert!(outside.to_model().unwrap().element_rayleigh().is_empty());
    let asm = femu_fem::assembly::Assembler::new(&model).unwrap();
    let k4 = asm
        .dampers(&model, femu_fem::assembly::MassKind::Consistent)
        .unwrap()
        .structural
        .unwrap();
    let sys = model
        .assemble(femu_fem::assembly::MassKind::Lumped)
        .unwrap();
    // every entry of K_4 is 0.03 of K's (both elements damped alike)
    let (a, b) = (
        femu_sparse::csc::to_dense(&k4),
        femu_sparse::csc::to_dense(&sys.k),
    );
    let scale = b.norm_max();
    let worst = (0..b.nrows())
        .flat_map(|i| (0..b.ncols()).map(move |j| (i, j)))
        .map(|(i, j)| (a[(i, j)] - 0.03 * b[(i, j)]).abs())
        .fold(0.0, f64::max);
    assert!(worst < 1e-14 * scale, "{worst:e}");

    // *MODAL DAMPING: ranges of modes with a ratio (a mode in none undamped), or Rayleigh's
    let modal = read(
        "*SOLID SECTION, ELSET=BLOCK, MATERIAL=STEEL\n*SHELL SECTION, ELSET=SKIN, MATERIAL=STEEL\n0.01\n\
         *MODAL DAMPING\n1, 3, 0.02\n5, , 0.04\n",
    )
    .unwrap()
    .to_model()
    .unwrap();
    let ratios: Vec<Option<f64>> = (1..=6).map(|r| modal.mode_ratio(r)).collect();
    assert_eq!(
        ratios,
        [0.02, 0.02, 0.02, 0.0, 0.04, 0.0].map(Some).to_vec()
    );
    assert!(!modal.modal_damping_structural());
    // STRUCTURAL: a structural damping factor s per mode, the loss factor 2 zeta (kept as s / 2)
    let structural = read(
        "*SOLID SECTION, ELSET=BLOCK, MATERIAL=STEEL\n*SHELL SECTION, ELSET=SKIN, MATERIAL=STEEL\n0.01\n\
         *MODAL DAMPING, STRUCTURAL\n1, 2, 0.04\n*MODAL DAMPING, STRUCTURAL\n4, , 0.1\n",
    )
    .unwrap()
    .to_model()
    .unwrap();
    assert!(structural.modal_damping_structural());
    // RAYLEIGH by ranges of modes: mode r of omega_r the ratio alpha / (2 omega_r) + beta omega_r / 2
    let ranged = read(
        "*SOLID SECTION, ELSET=BLOCK, MATERIAL=STEEL\n*SHELL SECTION, ELSET=SKIN, MATERIAL=STEEL\n0.01\n\
         *MODAL DAMPING, RAYLEIGH\n1, 2, 2., 1e-6\n4, , 0., 1e-5\n",
    )
    .unwrap()
    .to_model()
    .unwrap();
    let w = 300.0;
    for (mode, want) in [
        (1, 2.0 / (2.0 * w) + 1e-6 * w / 2.0),
        (3, 0.0),
        (4, 1e-5 * w / 2.0),
    ] {
        let got = ranged.mode_rayleigh_ratio(mode, w).unwrap();
        assert!((got - want).abs() < 1e-15, "mode {mode}: {got}");
    }
    assert!(ranged.uniform_damping().is_none());
    // DEFINITION=FREQUENCY RANGE (Abaqus): linear between the points, the nearest end's value
    // outside them, worked by hand; with STRUCTURAL the factor is the loss factor 2 zeta
    let by_frequency = read(
        "*SOLID SECTION, ELSET=BLOCK, MATERIAL=STEEL\n*SHELL SECTION, ELSET=SKIN, MATERIAL=STEEL\n0.01\n\
         *MODAL DAMPING, DEFINITION=FREQUENCY RANGE, VISCOUS=FRACTION OF CRITICAL DAMPING\n30., 0.03\n10., 0.01\n",
    )
    .unwrap()
    .to_model()
    .unwrap();
    let table = by_frequency.modal_damping().expect("a table");
    for (hz, want) in [
        (5.0, 0.01),
        (10.0, 0.01),
        (20.0, 0.02),
        (25.0, 0.025),
        (50.0, 0.03),
    ] {
        assert!(
            (table.ratio_at(hz) - want).abs() < 1e-15,
            "{hz}: {}",
            table.ratio_at(hz)
        );
    }
    assert!(!by_frequency.modal_damping_structural());
    let factors = read(
        "*SOLID SECTION, ELSET=BLOCK, MATERIAL=STEEL\n*SHELL SECTION, ELSET=SKIN, MATERIAL=STEEL\n0.01\n\
         *MODAL DAMPING, DEFINITION=FREQUENCY RANGE, STRUCTURAL\n10., 0.04\n",
    )
    .unwrap()
    .to_model()
    .unwrap();
    assert!(factors.modal_damping_structural());
    assert!((factors.modal_damping().unwrap().ratio_at(70.0) - 0.02).abs() < 1e-15);
    let ratios: Vec<Option<f64>> = (1..=5).map(|r| structural.mode_ratio(r)).collect();
    assert_eq!(ratios, [0.02, 0.02, 0.0, 0.05, 0.0].map(Some).to_vec());
    let rayleigh = read(
        "*SOLID SECTION, ELSET=BLOCK, MATERIAL=STEEL\n*SHELL SECTION, ELSET=SKIN, MATERIAL=STEEL\n0.01\n\
         *MODAL DAMPING, RAYLEIGH\n, , 2., 1e-6\n",
    )
    .unwrap()
    .to_model()
    .unwrap();
    assert_eq!(
        rayleigh.uniform_damping(),
        Some(femu_fem::model::UniformDamping::Rayleigh {
            alpha: 2.0,
            beta: 1e-6
        })
    );
    for (rest, line, says) in [
        ("*MODAL DAMPING\n3, 1, 0.02\n", 22, "end before they start"),
        (
            "*MODAL DAMPING\n1, 3, 0.02\n*MODAL DAMPING, STRUCTURAL\n4, 5, 0.04\n",
            24,
            "STRUCTURAL damping here and viscous damping at d.inp:22",
        ),
        (
            "*MODAL DAMPING, RAYLEIGH, STRUCTURAL\n, , 2., 1e-6\n",
            22,
            "RAYLEIGH and STRUCTURAL",
        ),
        ("*MODAL DAMPING\n1, 3, -0.02\n", 22, "at least 0"),
        (
            "*MODAL DAMPING, DEFINITION=EIGENMODES\n1., 100., 0.02\n",
            22,
            "MODE NUMBERS or FREQUENCY RANGE",
        ),
        (
            "*MODAL DAMPING\n1, 3, 0.02\n*MODAL DAMPING, DEFINITION=FREQUENCY RANGE\n10., 0.02\n",
            24,
            "by frequency range here and by mode numbers at d.inp:22",
        ),
        (
            "*MODAL DAMPING, RAYLEIGH, DEFINITION=FREQUENCY RANGE\n10., 2., 1e-6\n",
            22,
            "varies with frequency",
        ),
        (
            "*MODAL DAMPING, RAYLEIGH\n1, 3, 2., 1e-6\n, , 2., 1e-6\n",
            23,
            "give one or the other",
        ),
        (
            "*MODAL DAMPING\n1, 3, 0.02\n*MODAL DAMPING, RAYLEIGH\n4, 5, 2., 1e-6\n",
            24,
            "beside damping ratios",
        ),
        (
            "*MODAL DAMPING, VISCOUS=COMPOSITE\n1, 3\n",
            22,
            "VISCOUS=COMPOSITE",
        ),
        ("*DAMPING, STRUCTURAL=-0.1\n", 21, "at least 0"),
        ("*DAMPING, ALPHA=-1.\n", 21, "at least 0"),
        (
            "*SOLID SECTION, ELSET=BLOCK, MATERIAL=STEEL\n*DAMPING, STRUCTURAL=0.1\n",
            22,
            "outside a *MATERIAL",
        ),
        (
            "*DAMPING, STRUCTURAL=0.02\n*MATERIAL, NAME=SOFT\n*ELASTIC\n1e9, 0.3\n*DENSITY\n1000.\n\
             *SOLID SECTION, ELSET=BLOCK, MATERIAL=STEEL\n\
             *SHELL SECTION, ELSET=SKIN, COMPOSITE\n0.005, 3, STEEL, 0.\n0.005, 3, SOFT, 90.\n",
            28,
            "damped differently",
        ),
    ] {
        let e = read(rest)
            .and_then(|d| d.to_model().map(|_| ()))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains(&format!("d.inp:{line}")) && e.contains(says),
            "{e}"
        );
    }
}

/// A cylindrical panel of `n x n` S8R shells (radius 1 m, a 60 degree arc, 1 m long, `t` thick,
/// steel), clamped along one straight edge; `extra` is added before the step. The first element's
/// line continues on the next.
fn s8r_panel(n: usize, t: f64, extra: &str) -> String {
    let mut s = String::from("*HEADING\ncylindrical panel\n*NODE\n");
    let id = |(i, j): (usize, usize)| 1 + i + (2 * n + 1) * j;
    for p in femu_testkit::quad8_points(n, n) {
        let a = (PI / 3.0) * (p.0 as f64 / (2 * n) as f64 - 0.5);
        s.push_str(&format!(
            "{}, {:.12}, {:.12}, {:.12}\n",
            id(p),
            a.sin(),
            p.1 as f64 / (2 * n) as f64,
            a.cos()
        ));
    }
    s.push_str("*ELEMENT, TYPE=S8R, ELSET=PANEL\n");
    for (e, cell) in femu_testkit::quad8_cells(n, n).iter().enumerate() {
        let g: Vec<String> = cell.iter().map(|&p| id(p).to_string()).collect();
        // the first element continued on a second line after a trailing comma, as Abaqus
        // writes long element lines
        let split = if e == 0 { ",\n" } else { "," };
        s.push_str(&format!(
            "{}, {}{split} {}\n",
            e + 1,
            g[..4].join(", "),
            g[4..].join(", ")
        ));
    }
    let id = |i: usize, j: usize| id((i, j));
    s.push_str("*NSET, NSET=CLAMP\n");
    for i in 0..=2 * n {
        s.push_str(&format!("{}\n", id(i, 0)));
    }
    s.push_str(&format!(
        "*MATERIAL, NAME=STEEL\n*ELASTIC\n2.e11, 0.3\n*DENSITY\n8000.\n\
         *SHELL SECTION, ELSET=PANEL, MATERIAL=STEEL\n{t}\n*BOUNDARY\nCLAMP, 1, 6\n{extra}\
         *STEP\n*FREQUENCY\n6\n*END STEP\n"
    ));
    s
}

/// S8R shells read from a deck against CalculiX on the same deck: a clamped cylindrical panel
/// (radius 1 m, 60 degrees, 1 m long, 10 mm). CalculiX expands each S8R into a C3D20R brick
/// through the thickness; its six lowest frequencies and femu's converge together: the largest
/// difference is 1.7 % on 4 x 4 elements, 0.47 % on 8 x 8 and 0.25 % on 16 x 16 (femu's own
/// frequencies move by under 0.3 % from 8 x 8 to 16 x 16). The difference that remains is the
/// brick's through-the-thickness model against the shell's.
#[test]
fn s8r_panel_against_calculix() {
    if !femu_testkit::ccx::available() {
        return;
    }
    let mut worst = Vec::new();
    for n in [4usize, 8, 16] {
        let text = s8r_panel(n, 0.01, "");
        let (femu, _, _) = lowest(&text, 6);
        let ccx = femu_testkit::ccx::frequency_eigenvalues(&text, &format!("s8r-{n}"));
        assert_eq!(ccx.len(), 6, "{ccx:?}");
        worst.push(
            femu.iter()
                .zip(&ccx)
                .map(|(f, c)| ((c / f).sqrt() - 1.0).abs())
                .fold(0.0f64, f64::max),
        );
    }
    assert!(
        worst[0] < 2e-2
            && worst[1] < 6e-3
            && worst[2] < 3e-3
            && worst[2] < worst[1]
            && worst[1] < worst[0] / 2.0,
        "{worst:?}"
    );
}

/// NAFEMS FV32's tapered membrane (10 m, 5 m wide at the root to 1 m at the tip, 0.05 m, steel)
/// as `nx x ny` elements of `ty` with a `*MEMBRANE SECTION`, the out-of-plane DOF held
/// everywhere and the root clamped.
fn fv32_membrane(nx: usize, ny: usize, ty: &str) -> String {
    let eight = ty.starts_with("M3D8");
    let (mx, my) = if eight { (2 * nx, 2 * ny) } else { (nx, ny) };
    let id = |(i, j): (usize, usize)| 1 + i + (mx + 1) * j;
    type Cells = Vec<Vec<(usize, usize)>>;
    let (points, cells): (Vec<(usize, usize)>, Cells) = if eight {
        (
            femu_testkit::quad8_points(nx, ny),
            femu_testkit::quad8_cells(nx, ny)
                .iter()
                .map(|c| c.to_vec())
                .collect(),
        )
    } else {
        (
            (0..=ny)
                .flat_map(|j| (0..=nx).map(move |i| (i, j)))
                .collect(),
            (0..ny)
                .flat_map(|j| {
                    (0..nx).map(move |i| vec![(i, j), (i + 1, j), (i + 1, j + 1), (i, j + 1)])
                })
                .collect(),
        )
    };
    let mut s = String::from("*HEADING\nfv32\n*NODE, NSET=ALL\n");
    for p in points {
        let x = 10.0 * p.0 as f64 / mx as f64;
        let half = 2.5 - 0.2 * x;
        let y = 2.5 - half + 2.0 * half * p.1 as f64 / my as f64;
        s.push_str(&format!("{}, {x:.12}, {y:.12}, 0.\n", id(p)));
    }
    s.push_str(&format!("*ELEMENT, TYPE={ty}, ELSET=SKIN\n"));
    for (e, cell) in cells.iter().enumerate() {
        let g: Vec<String> = cell.iter().map(|&p| id(p).to_string()).collect();
        s.push_str(&format!("{}, {}\n", e + 1, g.join(", ")));
    }
    let id = |i: usize, j: usize| id((i, j));
    s.push_str("*NSET, NSET=ROOT\n");
    for j in 0..=my {
        s.push_str(&format!("{}\n", id(0, j)));
    }
    s.push_str(
        "*MATERIAL, NAME=STEEL\n*ELASTIC\n2.e11, 0.3\n*DENSITY\n8000.\n\
         *MEMBRANE SECTION, ELSET=SKIN, MATERIAL=STEEL\n0.05\n\
         *BOUNDARY\nALL, 3, 3\nROOT, 1, 2\n*STEP\n*FREQUENCY\n6\n*END STEP\n",
    );
    s
}

/// Membranes from a deck: NAFEMS FV32 of M3D4 against CalculiX on the same deck (its M3D4 is the
/// same bilinear membrane; it expands it into a brick): the six frequencies agree to 2e-5 on 16 x 8
/// and 32 x 16 elements (1.7e-6 to 1.2e-5 measured), and the nodes have no rotations. M3D8R
/// against NAFEMS's 44.623, 130.03, 162.70, 246.05, 379.90, 391.44 Hz: within 0.5 % on 8 x 4
/// elements and 0.05 % on 16 x 8 (0.37 % and 0.016 % measured at the worst). (CalculiX's own
/// expansion of this M3D8R deck has near-zero modes, 0.02-0.2 Hz, and is not compared.) A shell
/// element given a `*MEMBRANE SECTION`, a membrane given a `*SHELL SECTION` and an `ORIENTATION=`
/// are refused with their line.
#[test]
fn membranes_against_calculix_and_nafems() {
    for n in [16usize, 32] {
        let text = fv32_membrane(n, n / 2, "M3D4");
        let (femu, model, _) = lowest(&text, 6);
        assert!(model.structural().iter().all(|e| !e.needs_rotations()));
        if !femu_testkit::ccx::available() {
            continue;
        }
        let ccx = femu_testkit::ccx::frequency_eigenvalues(&text, &format!("m3d4-{n}"));
        assert_eq!(ccx.len(), 6);
        for (f, c) in femu.iter().zip(&ccx) {
            assert!(((c / f).sqrt() - 1.0).abs() < 2e-5, "{n}: {femu:?} {ccx:?}");
        }
    }
    let reference = [44.623, 130.03, 162.70, 246.05, 379.90, 391.44];
    for (n, bound) in [(8usize, 5e-3), (16, 5e-4)] {
        let (femu, _, _) = lowest(&fv32_membrane(n, n / 2, "M3D8R"), 6);
        for (l, r) in femu.iter().zip(reference) {
            let f = l.sqrt() / (2.0 * PI);
            assert!((f / r - 1.0).abs() < bound, "{n}: {f} Hz against {r}");
        }
    }
    // refusals
    let deck = fv32_membrane(2, 1, "M3D4");
    for (text, what) in [
        (
            deck.replace("TYPE=M3D4", "TYPE=S4"),
            "is given a *MEMBRANE SECTION",
        ),
        (
            deck.replace("*MEMBRANE SECTION,", "*SHELL SECTION,"),
            "is given a *SHELL SECTION",
        ),
        (
            deck.replace(
                "*MEMBRANE SECTION, ELSET=SKIN, MATERIAL=STEEL",
                "*MEMBRANE SECTION, ELSET=SKIN, MATERIAL=STEEL, ORIENTATION=OR1",
            ),
            "ORIENTATION=OR1",
        ),
    ] {
        let e = parse_inp(&text, "deck.inp")
            .and_then(|d| d.to_model())
            .map(|_| ())
            .unwrap_err()
            .to_string();
        assert!(e.contains(what) && e.contains("deck.inp:"), "{what}: {e}");
    }
}

/// Abaqus's named boundary types (Keywords Reference, `*BOUNDARY`) fix the DOFs they name: on a
/// B31 cantilever, `ENCASTRE` is `1, 6`, `PINNED` is `1, 3`, `XSYMM` is 1, 5, 6, `ZSYMM` 3, 4, 5
/// and `YASYMM` (lower case) 1, 3, 5: the same fixed DOFs, and the stiffness to 1e-12, as the DOFs
/// written out; a misspelt type is refused.
#[test]
fn named_boundary_types_fix_their_dofs() {
    let base = cantilever(20, "B31", false);
    let with = |bc: &str| base.replace("*BOUNDARY\n1, 1, 6\n", &format!("*BOUNDARY\n{bc}\n"));
    for (named, dofs) in [
        ("1, ENCASTRE", "1, 1, 6"),
        ("1, PINNED", "1, 1, 3"),
        ("1, XSYMM", "1, 1, 1\n1, 5, 6"),
        ("1, ZSYMM", "1, 3, 5"),
        ("1, yasymm", "1, 1, 1\n1, 3, 3\n1, 5, 5"),
    ] {
        let deck = |bc: &str| {
            let d = parse_inp(&with(bc), "bc.inp").unwrap();
            let m = d.to_model().unwrap();
            let mut fixed: Vec<(usize, usize)> = m.fixed_dofs().collect();
            fixed.sort();
            let sys = m.assemble(MassKind::Consistent).unwrap();
            let k = sys.k.to_dense();
            (fixed, k)
        };
        let (a, ka) = deck(named);
        let (b, kb) = deck(dofs);
        assert_eq!(a, b, "{named}");
        let scale = kb.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        for (x, y) in ka.iter().zip(&kb) {
            assert!((x - y).abs() <= 1e-12 * scale, "{named}");
        }
    }
    let e = parse_inp(&with("1, ENCASTER"), "bc.inp")
        .unwrap_err()
        .to_string();
    assert!(e.contains("neither an integer nor a boundary type"), "{e}");
}

/// Parameters Abaqus/CAE writes that change neither the linear stiffness nor the mass are read:
/// a beam section's `TEMPERATURE=GRADIENTS` and `POISSON=`, and a `*SECTION CONTROLS` (warned as
/// skipped) leave the B31 cantilever's eigenvalues as they are (exactly).
#[test]
fn cae_section_parameters_change_nothing() {
    let base = cantilever(20, "B31", false);
    let cae = base.replace(
        "*BEAM SECTION, ELSET=BEAM, MATERIAL=STEEL, SECTION=RECT",
        "*Section Controls, name=EC-1, hourglass=ENHANCED\n1., 1., 1.\n\
         *Beam Section, elset=BEAM, material=STEEL, temperature=GRADIENTS, section=RECT, poisson=0.3",
    );
    let (a, _, _) = lowest(&base, 4);
    let (b, _, _) = lowest(&cae, 4);
    assert_eq!(a, b);
}

/// Rotary inertia (`*ELEMENT, TYPE=ROTARYI` with `*ROTARY INERTIA`, as Abaqus/CAE writes a point
/// inertia) on the tip of a B31 cantilever of a square section whose own mass is negligible
/// (density 1e-6): the tip turns against the stiffness a tip moment meets, `G J / L` about the
/// axis and `E I / L` about the others (the tip free to move, exact for the beam element), so the
/// three lowest eigenvalues are `G J / (L I11)` and `E I / (L I22)` twice, by hand, to 1e-6; a
/// ROTARYI on a solid's node (no rotations), a `*ROTARY INERTIA` of no such set and one without
/// its data line are refused with the line.
#[test]
fn rotary_inertia_turns_a_cantilever_tip() {
    let base = cantilever(10, "B31", false)
        .replace("0.02, 0.01\n", "0.02, 0.02\n")
        .replace("*DENSITY\n7850.\n", "*DENSITY\n1.e-6\n");
    let deck = format!(
        "{base}*ELEMENT, TYPE=ROTARYI, ELSET=TIPI\n500, 11\n*ROTARY INERTIA, ELSET=TIPI\n2.e-3, 5.e-3, 5.e-3\n"
    );
    let (values, _, _) = lowest(&deck, 3);
    let (e, nu, l, a): (f64, f64, f64, f64) = (2.1e11, 0.3, 1.0, 0.02);
    let g = e / (2.0 * (1.0 + nu));
    let i = a * a.powi(3) / 12.0;
    // the torsion constant femu gives a RECT section (docs/MATH.md): 0.1408 a^4 for a square
    let c = a;
    let j = a * c.powi(3) * (1.0 / 3.0 - 0.21 * c / a * (1.0 - c.powi(4) / (12.0 * a.powi(4))));
    let mut want = [g * j / (l * 2e-3), e * i / (l * 5e-3), e * i / (l * 5e-3)];
    want.sort_by(f64::total_cmp);
    for (got, w) in values.iter().zip(&want) {
        assert!((got / w - 1.0).abs() < 1e-6, "{values:?} vs {want:?}");
    }
    let refused = |text: &str, needle: &str| {
        let e = parse_inp(text, "bad.inp")
            .and_then(|d| d.to_model().map(|_| ()))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("bad.inp:") && e.contains(needle),
            "{needle}: {e}"
        );
    };
    refused(
        &deck.replace("*ROTARY INERTIA, ELSET=TIPI", "*ROTARY INERTIA, ELSET=TIPJ"),
        "no *ELEMENT, TYPE=ROTARYI defines",
    );
    refused(
        &deck.replace("2.e-3, 5.e-3, 5.e-3\n", ""),
        "without its data line",
    );
    let solid = "*NODE\n1, 0., 0., 0.\n2, 1., 0., 0.\n3, 1., 1., 0.\n4, 0., 1., 0.\n5, 0., 0., 1.\n\
                 6, 1., 0., 1.\n7, 1., 1., 1.\n8, 0., 1., 1.\n*ELEMENT, TYPE=C3D8, ELSET=B\n1, 1, 2, 3, 4, 5, 6, 7, 8\n\
                 *MATERIAL, NAME=S\n*ELASTIC\n2.e11, 0.3\n*DENSITY\n7850.\n*SOLID SECTION, ELSET=B, MATERIAL=S\n\
                 *ELEMENT, TYPE=ROTARYI, ELSET=R\n9, 7\n*ROTARY INERTIA, ELSET=R\n1., 1., 1.\n";
    refused(solid, "has no rotations");
}

/// `*NONSTRUCTURAL MASS`: on the B33 cantilever (no rotary inertia), a mass per length equal to
/// its own `rho A` doubles its mass, so its four lowest (bending) eigenvalues halve, by hand, to
/// 1e-10 (the eigensolver's); on FV16's plate of S4, a total mass spread by mass (uniform
/// elements) equals the same mass per area over its 100 m^2 (eigenvalues to 1e-10), and the
/// model's total mass grows by
/// exactly that mass (1e-12); a mass per length on shells, a set of solids and a card without
/// `UNITS` are refused with the line.
#[test]
fn nonstructural_mass_adds_mass_alone() {
    let beam = cantilever(20, "B33", false);
    let rho_a = 7850.0 * 0.02 * 0.01;
    let heavy =
        format!("{beam}*NONSTRUCTURAL MASS, ELSET=BEAM, UNITS=MASS PER LENGTH\n{rho_a:e}\n");
    let (a, _, _) = lowest(&beam, 4);
    let (b, _, _) = lowest(&heavy, 4);
    for (x, y) in a.iter().zip(&b) {
        assert!((y / x - 0.5).abs() < 1e-10, "{a:?} {b:?}");
    }
    let plate = fv16(8);
    let with = |card: &str| plate.replace("*BOUNDARY", &format!("{card}*BOUNDARY"));
    let total = with("*NONSTRUCTURAL MASS, ELSET=PLATE, UNITS=TOTAL MASS\n2500.\n");
    let per_area = with("*NONSTRUCTURAL MASS, ELSET=PLATE, UNITS=MASS PER AREA\n25.\n");
    let (x, mx, _) = lowest(&total, 4);
    let (y, _, _) = lowest(&per_area, 4);
    for (p, q) in x.iter().zip(&y) {
        assert!((p / q - 1.0).abs() < 1e-10, "{x:?} {y:?}");
    }
    let (_, m0, _) = lowest(&plate, 1);
    let added = mx.total_mass().unwrap() - m0.total_mass().unwrap();
    assert!((added / 2500.0 - 1.0).abs() < 1e-12, "{added}");
    let refused = |text: &str, needle: &str| {
        let e = parse_inp(text, "bad.inp")
            .and_then(|d| d.to_model().map(|_| ()))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("bad.inp:") && e.contains(needle),
            "{needle}: {e}"
        );
    };
    refused(
        &with("*NONSTRUCTURAL MASS, ELSET=PLATE, UNITS=MASS PER LENGTH\n1.\n"),
        "a mass per area is a shell's",
    );
    refused(
        &with("*NONSTRUCTURAL MASS, ELSET=PLATE\n1.\n"),
        "without UNITS=",
    );
    refused(
        &with("*NONSTRUCTURAL MASS, ELSET=PLATE, UNITS=MASS PER VOLUME\n1.\n"),
        "UNITS=MASS PER VOLUME",
    );
}

/// FV16's plate (10 m, 50 mm, clamped along x = 0) as `2 n x n` six-node triangles of `ty`
/// (midside nodes on the edges' middles).
fn fv16_six(n: usize, ty: &str) -> String {
    let m = 2 * n;
    let g = |i: usize, j: usize| 1 + i + (m + 1) * j;
    let mut s = fv16_nodes(m);
    s.push_str(&format!("*ELEMENT, TYPE={ty}, ELSET=PLATE\n"));
    for (id, cell) in femu_testkit::tri6_cells(n).iter().enumerate() {
        let t: Vec<String> = cell.iter().map(|&(i, j)| g(i, j).to_string()).collect();
        s.push_str(&format!("{}, {}\n", id + 1, t.join(", ")));
    }
    fv16_end(s, m)
}

/// Six-node triangles from a deck (CalculiX's S6, Abaqus's STRI65), built as four three-node
/// triangles (docs/MATH.md, "Six-node triangles"), against CalculiX on the same deck (which
/// expands each S6 into quadratic wedges): FV16's six frequencies of femu and CalculiX converge
/// together (largest difference 16 % on 2 x 4 x 4, 2.2 % on 2 x 8 x 8, 1.1 % on 2 x 16 x 16,
/// measured), and femu's are within 1 % of NAFEMS's on 2 x 16 x 16; STRI65 is the same element.
#[test]
fn six_node_triangles_against_calculix() {
    let nafems = [0.421, 1.029, 2.582, 3.306, 3.753, 6.555];
    let (femu16, _, _) = lowest(&fv16_six(16, "S6"), 6);
    for (l, r) in femu16.iter().zip(nafems) {
        let f = l.sqrt() / (2.0 * PI);
        assert!((f / r - 1.0).abs() < 1e-2, "{f} {r}");
    }
    let (stri, _, _) = lowest(&fv16_six(4, "STRI65"), 6);
    let (s6, _, _) = lowest(&fv16_six(4, "S6"), 6);
    assert_eq!(stri, s6);
    if !femu_testkit::ccx::available() {
        return;
    }
    let mut worst = Vec::new();
    for n in [4usize, 8, 16] {
        let text = fv16_six(n, "S6");
        let (femu, _, _) = lowest(&text, 6);
        let ccx = femu_testkit::ccx::frequency_eigenvalues(&text, &format!("s6-{n}"));
        assert_eq!(ccx.len(), 6, "{ccx:?}");
        worst.push(
            femu.iter()
                .zip(&ccx)
                .map(|(f, c)| ((c / f).sqrt() - 1.0).abs())
                .fold(0.0f64, f64::max),
        );
    }
    assert!(
        worst[2] < worst[1] && worst[1] < worst[0] && worst[2] < 1.5e-2,
        "{worst:?}"
    );
}

/// `*SHELL GENERAL SECTION` with `MATERIAL=` (a homogeneous linear section, which Abaqus
/// pre-integrates as `*SHELL SECTION` integrates it) is `*SHELL SECTION`: FV16's eigenvalues
/// equal exactly; without `MATERIAL=` (a stiffness matrix given) it is refused with its line.
#[test]
fn shell_general_sections_with_a_material_are_shell_sections() {
    let plate = fv16(4);
    let general = plate.replace(
        "*SHELL SECTION, ELSET=PLATE, MATERIAL=STEEL",
        "*SHELL GENERAL SECTION, ELSET=PLATE, MATERIAL=STEEL, POISSON=0.5",
    );
    let (a, _, _) = lowest(&plate, 4);
    let (b, _, _) = lowest(&general, 4);
    assert_eq!(a, b);
    let e = parse_inp(
        &plate.replace(
            "*SHELL SECTION, ELSET=PLATE, MATERIAL=STEEL",
            "*SHELL GENERAL SECTION, ELSET=PLATE",
        ),
        "bad.inp",
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("bad.inp:") && e.contains("without MATERIAL="),
        "{e}"
    );
}
