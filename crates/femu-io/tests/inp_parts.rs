//! Decks in parts and an assembly, as Abaqus/CAE writes them: placed by femu before the keywords
//! are read (`crates/femu-io/src/inp/parts.rs`), checked against the same structure written
//! flat by hand here (its nodes placed by the test's own arithmetic) and solved by CalculiX.

use femu_fem::assembly::MassKind;
use femu_io::inp::parse_inp;
use femu_sparse::eigen::{EigenOptions, Which};

/// The part: a bar of 4 x 1 x 1 C3D8 over 0.4 x 0.1 x 0.1 m, its nodes numbered
/// `1 + i + 5 (j + 2 k)`, with sets ROOT (x = 0) and TIP (x = 0.4), steel.
fn bar_nodes() -> Vec<(u64, [f64; 3])> {
    let mut v = Vec::new();
    for k in 0..2 {
        for j in 0..2 {
            for i in 0..5 {
                v.push((
                    1 + i + 5 * (j + 2 * k),
                    [0.1 * i as f64, 0.1 * j as f64, 0.1 * k as f64],
                ));
            }
        }
    }
    v
}

fn bar_elements() -> Vec<(u64, [u64; 8])> {
    let id = |i: u64, j: u64, k: u64| 1 + i + 5 * (j + 2 * k);
    (0..4)
        .map(|i| {
            (
                i + 1,
                [
                    id(i, 0, 0),
                    id(i + 1, 0, 0),
                    id(i + 1, 1, 0),
                    id(i, 1, 0),
                    id(i, 0, 1),
                    id(i + 1, 0, 1),
                    id(i + 1, 1, 1),
                    id(i, 1, 1),
                ],
            )
        })
        .collect()
}

const ROOT: [u64; 4] = [1, 6, 11, 16];
const TIP: [u64; 4] = [5, 10, 15, 20];

/// The deck as Abaqus/CAE writes it: part BAR; instance A as it is, instance B translated by
/// (0.5, 0, 0) and then turned 30 degrees about the vertical axis through (0.5, 0, 0); an
/// assembly-level reference point 1 coupled kinematically to A's tip, carrying a 2 kg mass;
/// A clamped by its root set (`ENCASTRE`), B by its root and its tip held in global x.
fn cae_deck() -> String {
    let mut s = String::from(
        "*Heading\n** Job name: Job-1 Model name: Model-1\n*Preprint, echo=NO, model=NO, history=NO, contact=NO\n\
         **\n** PARTS\n**\n*Part, name=BAR\n*Node\n",
    );
    for (id, x) in bar_nodes() {
        s.push_str(&format!(
            "{id:7}, {:>12}, {:>12}, {:>12}\n",
            x[0], x[1], x[2]
        ));
    }
    s.push_str("*Element, type=C3D8\n");
    for (id, n) in bar_elements() {
        let n: Vec<String> = n.iter().map(|v| v.to_string()).collect();
        s.push_str(&format!("{id}, {}\n", n.join(", ")));
    }
    s.push_str(
        "*Nset, nset=ROOT\n 1, 6, 11, 16\n*Nset, nset=TIP\n 5, 10, 15, 20\n\
         *Elset, elset=ALL, generate\n 1, 4, 1\n\
         ** Section: Section-1\n*Solid Section, elset=ALL, material=STEEL\n,\n*End Part\n**\n\
         **\n** ASSEMBLY\n**\n*Assembly, name=Assembly\n**\n*Instance, name=A, part=BAR\n*End Instance\n**\n\
         *Instance, name=B, part=BAR\n          0.5,           0.,           0.\n\
         0.5, 0., 0., 0.5, 0., 1., 30.\n*End Instance\n**\n\
         *Node\n      1,          0.45,          0.05,          0.05\n\
         *Nset, nset=RP, internal\n1,\n\
         *Nset, nset=BTIP, instance=B\n 5, 10, 15, 20\n\
         *Element, type=MASS, elset=RPMASS\n1, 1\n*Mass, elset=RPMASS\n2.,\n\
         ** Constraint: Constraint-1\n*Kinematic Coupling, ref node=RP\nA.TIP, 1, 3\n\
         *End Assembly\n**\n** MATERIALS\n**\n*Material, name=STEEL\n*Density\n7850.,\n*Elastic\n 2.1e+11, 0.3\n\
         **\n** BOUNDARY CONDITIONS\n**\n*Boundary\nA.ROOT, ENCASTRE\nB.ROOT, ENCASTRE\nBTIP, 1, 1\n\
         ** ----------------------------------------------------------------\n**\n** STEP: Step-1\n**\n\
         *Step, name=Step-1, nlgeom=NO, perturbation\n*Frequency, eigensolver=Lanczos, normalization=displacement\n6, , , , ,\n\
         *End Step\n",
    );
    s
}

/// The same structure written flat: A's nodes as they are, B's numbered from 101 and placed by
/// the test (x + 0.5 turned 30 degrees about z through (0.5, 0, 0)), the reference point 1001
/// coupled by `*COUPLING` and `*KINEMATIC` (which CalculiX reads).
fn flat_deck() -> String {
    let (c, s30) = (30f64.to_radians().cos(), 30f64.to_radians().sin());
    let mut s = String::from("*HEADING\nflat\n*NODE\n");
    for (id, x) in bar_nodes() {
        s.push_str(&format!("{id}, {:?}, {:?}, {:?}\n", x[0], x[1], x[2]));
    }
    for (id, x) in bar_nodes() {
        // moved by (0.5, 0, 0), then turned about z through (0.5, 0, 0)
        let (dx, dy) = (x[0], x[1]);
        s.push_str(&format!(
            "{}, {:?}, {:?}, {:?}\n",
            id + 100,
            0.5 + c * dx - s30 * dy,
            s30 * dx + c * dy,
            x[2]
        ));
    }
    s.push_str("1001, 0.45, 0.05, 0.05\n*ELEMENT, TYPE=C3D8, ELSET=ALL\n");
    for (id, n) in bar_elements() {
        let a: Vec<String> = n.iter().map(|v| v.to_string()).collect();
        let b: Vec<String> = n.iter().map(|v| (v + 100).to_string()).collect();
        s.push_str(&format!(
            "{id}, {}\n{}, {}\n",
            a.join(", "),
            id + 100,
            b.join(", ")
        ));
    }
    let list = |ids: &[u64], add: u64| {
        ids.iter()
            .map(|v| (v + add).to_string())
            .collect::<Vec<_>>()
            .join(", ")
    };
    s.push_str(&format!(
        "*NSET, NSET=ATIP\n{}\n*NSET, NSET=FIXED\n{}, {}\n*NSET, NSET=BTIP\n{}\n",
        list(&TIP, 0),
        list(&ROOT, 0),
        list(&ROOT, 100),
        list(&TIP, 100)
    ));
    s.push_str(
        "*ELEMENT, TYPE=MASS, ELSET=RPMASS\n9001, 1001\n*MASS, ELSET=RPMASS\n2.\n\
         *SURFACE, NAME=ATIPS, TYPE=NODE\nATIP\n\
         *COUPLING, REF NODE=1001, SURFACE=ATIPS, CONSTRAINT NAME=TIP\n*KINEMATIC\n1, 3\n\
         *MATERIAL, NAME=STEEL\n*ELASTIC\n2.1e11, 0.3\n*DENSITY\n7850.\n\
         *SOLID SECTION, ELSET=ALL, MATERIAL=STEEL\n\
         *BOUNDARY\nFIXED, 1, 3\nBTIP, 1, 1\n*STEP\n*FREQUENCY\n6\n*END STEP\n",
    );
    s
}

fn lowest(text: &str, name: &str) -> Vec<f64> {
    let deck = parse_inp(text, name).unwrap();
    deck.to_model()
        .unwrap()
        .assemble(MassKind::Consistent)
        .unwrap()
        .modes(Which::Lowest(6), &EigenOptions::default())
        .unwrap()
        .values
}

/// A deck in parts and an assembly as Abaqus/CAE writes it (two instances of one part, the second
/// translated and turned; an assembly-level reference point with a mass, kinematically coupled
/// to an instance's set named `A.TIP`; `*NSET, INSTANCE=`; `ENCASTRE`; `*BOUNDARY` on `A.ROOT`)
/// has the eigenvalues of the same structure written flat by hand to 1e-12, and CalculiX's
/// eigenvalues of that flat deck to its printed digits (1e-6). The turn matters: B's tip is held
/// in global x, so B placed without its rotation moves the first eigenvalue by more than 1 %.
/// The first instance keeps its part's numbers (node A.5 is femu's node 5); the second's and the
/// assembly's are moved up by the next power of ten above the part's (B.5 is 105, the reference
/// point 201), each said in a warning.
#[test]
fn a_cae_deck_in_parts_is_the_flat_deck() {
    let parts = lowest(&cae_deck(), "cae.inp");
    let flat = lowest(&flat_deck(), "flat.inp");
    for (a, b) in parts.iter().zip(&flat) {
        assert!((a / b - 1.0).abs() < 1e-12, "{parts:?} vs {flat:?}");
    }
    let unturned = lowest(
        &cae_deck().replace("0.5, 0., 0., 0.5, 0., 1., 30.\n", ""),
        "unturned.inp",
    );
    assert!(
        (unturned[2] / parts[2] - 1.0).abs() > 0.1,
        "{unturned:?} {parts:?}"
    );
    let deck = parse_inp(&cae_deck(), "cae.inp").unwrap();
    let model = deck.to_model().unwrap();
    let mesh = model.mesh();
    let x = |id: u64| mesh.coords()[mesh.node_index(id).unwrap()];
    assert_eq!(x(5), [0.4, 0.0, 0.0]);
    let b5 = x(105);
    let (c, s) = (30f64.to_radians().cos(), 30f64.to_radians().sin());
    assert!((b5[0] - (0.5 + 0.4 * c)).abs() < 1e-15 && (b5[1] - 0.4 * s).abs() < 1e-15);
    assert_eq!(x(201), [0.45, 0.05, 0.05]);
    let said: Vec<&str> = deck.warnings.iter().map(|w| w.message.as_str()).collect();
    assert!(
        said.iter()
            .any(|w| w.contains("instance B of part BAR") && w.contains("B.n is femu's n + 100")),
        "{said:?}"
    );
    if femu_testkit::ccx::available() {
        let ccx = femu_testkit::ccx::frequency_eigenvalues(&flat_deck(), "parts-flat");
        for (a, b) in parts.iter().zip(&ccx) {
            assert!((a / b - 1.0).abs() < 1e-6, "{parts:?} vs CalculiX {ccx:?}");
        }
    }
}

/// What a deck in parts gets wrong is refused with its line: an instance of a part no `*PART`
/// defines, a reference to an instance the assembly does not have, a keyword femu does not read
/// inside a part, a part not closed, parts that no assembly places, an instance without `PART=`,
/// springs in a turned instance, and a rotation whose axis has no length.
#[test]
fn malformed_parts_are_refused_with_their_line() {
    // the line is the first that starts with `at` in the deck as changed
    let refused = |text: String, at: &str, needle: &str| {
        let line = text.lines().position(|l| l.starts_with(at)).unwrap() + 1;
        let e = parse_inp(&text, "bad.inp")
            .and_then(|d| d.to_model().map(|_| ()))
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with(&format!("bad.inp:{line}:")) && e.contains(needle),
            "{needle}: {e}"
        );
    };
    let deck = cae_deck();
    refused(
        deck.replace("*Instance, name=B, part=BAR", "*Instance, name=B, part=BRA"),
        "*Instance, name=B",
        "no *PART is named BRA",
    );
    refused(
        deck.replace("A.TIP, 1, 3", "C.TIP, 1, 3"),
        "C.TIP",
        "\"C\" names no *INSTANCE",
    );
    refused(
        deck.replace("*End Part", "*Boundary\n1, 1, 3\n*End Part"),
        "*Boundary",
        "*BOUNDARY in part BAR",
    );
    refused(
        deck.replace("*End Part\n", ""),
        "*Assembly",
        "*END PART is missing",
    );
    refused(
        deck.replace("*Instance, name=A, part=BAR", "*Instance, name=A"),
        "*Instance, name=A",
        "without PART=",
    );
    refused(
        deck.replace(
            "0.5, 0., 0., 0.5, 0., 1., 30.",
            "0.5, 0., 0., 0.5, 0., 0., 30.",
        ),
        "0.5, 0., 0., 0.5",
        "axis of rotation coincide",
    );
    refused(
        deck.replace(
            "*End Part",
            "*Element, type=SPRING1, elset=S\n99, 5\n*Spring, elset=S\n1\n1000.\n*End Part",
        ),
        "*Spring",
        "turned instance B",
    );
    let part_only = deck[..deck.find("*Assembly").unwrap()].to_string();
    refused(part_only, "*Part", "no *ASSEMBLY places them");
}

/// Two instances of the bar end to end (B moved 0.4 m along x) joined by a `*TIE` written as
/// Abaqus/CAE writes one in the assembly: the slave a node-based surface of `B.ROOT`, the master
/// an element-based surface of A's tip element (face S4, x = 0.4) through an internal element set
/// of the instance. The tied pair is one bar of eight elements (written flat by hand) to 1e-10.
#[test]
fn instances_tied_in_the_assembly_are_one_bar() {
    let deck = cae_deck();
    let part = &deck[..deck.find("*Assembly").unwrap()];
    let model = &deck[deck.find("** MATERIALS").unwrap()..];
    let tied = format!(
        "{part}*Assembly, name=Assembly\n*Instance, name=A, part=BAR\n*End Instance\n\
         *Instance, name=B, part=BAR\n0.4, 0., 0.\n*End Instance\n\
         *Elset, elset=_m_Surf-1_S4, internal, instance=A\n 4,\n\
         *Surface, type=ELEMENT, name=m_Surf-1\n_m_Surf-1_S4, S4\n\
         *Surface, type=NODE, name=s_Set-1_CNS_, internal\nB.ROOT, 1.\n\
         ** Constraint: Constraint-1\n*Tie, name=Constraint-1, adjust=yes\ns_Set-1_CNS_, m_Surf-1\n\
         *End Assembly\n{}",
        model.replace("B.ROOT, ENCASTRE\nBTIP, 1, 1\n", "")
    );
    // the flat bar of eight elements, nodes 1 + i + 9 (j + 2 k)
    let id = |i: u64, j: u64, k: u64| 1 + i + 9 * (j + 2 * k);
    let mut flat = String::from("*NODE\n");
    for k in 0..2 {
        for j in 0..2 {
            for i in 0..9 {
                flat.push_str(&format!(
                    "{}, {:?}, {:?}, {:?}\n",
                    id(i, j, k),
                    0.1 * i as f64,
                    0.1 * j as f64,
                    0.1 * k as f64
                ));
            }
        }
    }
    flat.push_str("*ELEMENT, TYPE=C3D8, ELSET=ALL\n");
    for i in 0..8 {
        flat.push_str(&format!(
            "{}, {}\n",
            i + 1,
            femu_testkit::hex8_nodes(|a, b, c| id(a as u64, b as u64, c as u64), i as usize, 0, 0)
        ));
    }
    flat.push_str(&format!(
        "*NSET, NSET=ROOT\n{}, {}, {}, {}\n*MATERIAL, NAME=STEEL\n*ELASTIC\n2.1e11, 0.3\n*DENSITY\n7850.\n\
         *SOLID SECTION, ELSET=ALL, MATERIAL=STEEL\n*BOUNDARY\nROOT, 1, 3\n",
        id(0, 0, 0),
        id(0, 1, 0),
        id(0, 0, 1),
        id(0, 1, 1)
    ));
    let a = lowest(&tied, "tied.inp");
    let b = lowest(&flat, "flat.inp");
    for (x, y) in a.iter().zip(&b) {
        assert!((x / y - 1.0).abs() < 1e-10, "{a:?} vs {b:?}");
    }
}

/// A part of beams carrying its own point inertia (`ROTARYI` with `*ROTARY INERTIA`) and
/// `*NONSTRUCTURAL MASS`, as CAE writes inertia defined on a part, placed by a translated and
/// turned instance: the eigenvalues of the flat deck (the same beam along x, its boundary on its
/// first node) to 1e-10, since a cantilever's frequencies do not depend on where it stands or how
/// it is turned (the part's section axis `n1` and its inertia tensor turn with it).
#[test]
fn a_part_with_its_own_inertia_and_nonstructural_mass() {
    let mut body = String::from("*NODE\n");
    for i in 0..=10 {
        body.push_str(&format!("{}, {}, 0., 0.\n", i + 1, 0.1 * i as f64));
    }
    body.push_str("*ELEMENT, TYPE=B31, ELSET=BEAM\n");
    for i in 0..10 {
        body.push_str(&format!("{}, {}, {}\n", i + 1, i + 1, i + 2));
    }
    body.push_str(
        "*BEAM SECTION, ELSET=BEAM, MATERIAL=STEEL, SECTION=RECT\n0.02, 0.01\n0., 1., 0.\n\
         *ELEMENT, TYPE=ROTARYI, ELSET=TIPI\n50, 11\n*ROTARY INERTIA, ELSET=TIPI\n2.e-3, 5.e-3, 1.e-3\n\
         *NONSTRUCTURAL MASS, ELSET=BEAM, UNITS=MASS PER LENGTH\n0.8\n",
    );
    let material = "*MATERIAL, NAME=STEEL\n*ELASTIC\n2.1e11, 0.3\n*DENSITY\n7850.\n";
    let flat = format!("{body}{material}*BOUNDARY\n1, 1, 6\n");
    let parts = format!(
        "*PART, NAME=P\n{body}*END PART\n*ASSEMBLY, NAME=A\n*INSTANCE, NAME=I, PART=P\n0.5, -1., 2.\n\
         0.5, -1., 2., 1.5, 0., 3., 40.\n*END INSTANCE\n*END ASSEMBLY\n{material}*BOUNDARY\nI.1, ENCASTRE\n"
    );
    let a = lowest(&flat, "flat.inp");
    let b = lowest(&parts, "parts.inp");
    for (x, y) in a.iter().zip(&b) {
        assert!((x / y - 1.0).abs() < 1e-10, "{a:?} vs {b:?}");
    }
}
