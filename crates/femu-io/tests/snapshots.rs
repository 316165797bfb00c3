//! insta snapshots of every parsed fixture: a readable summary of what each reader made of the
//! file (counts, sets, first and last entries, warnings), so a change in parsing shows up as a
//! reviewed diff.

use femu_fem::mesh::Mesh;
use std::fmt::Write as _;
use std::path::PathBuf;

fn fixture(dir: &str, name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../fixtures")
        .join(dir)
        .join(name)
}

fn mesh_summary(mesh: &Mesh) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "nodes: {}", mesh.node_count());
    let _ = writeln!(s, "elements: {:?}", mesh.kind_counts());
    for (i, p) in mesh.coords().iter().enumerate().take(3) {
        let _ = writeln!(s, "node {}: {:?}", mesh.node_id(i), p);
    }
    for el in mesh.elements().take(3) {
        let ids: Vec<u64> = el.nodes.iter().map(|n| mesh.node_id(*n)).collect();
        let _ = writeln!(s, "element {} {:?}: {:?}", el.id, el.kind, ids);
    }
    for (name, set) in mesh.node_sets() {
        let _ = writeln!(s, "node set {name}: {} nodes", set.len());
    }
    for (name, set) in mesh.element_sets() {
        let _ = writeln!(s, "element set {name}: {} elements", set.len());
    }
    s
}

#[test]
fn inp_two_hex() {
    let deck = femu_io::inp::read_inp(fixture("inp", "two_hex.inp")).unwrap();
    let mut s = mesh_summary(&deck.mesh);
    for (name, m) in &deck.materials {
        let _ = writeln!(s, "material {name}: {:?}", m);
    }
    let _ = writeln!(s, "sections: {}", deck.sections.len());
    // no paths in snapshots: they differ between clones
    for b in &deck.boundaries {
        let _ = writeln!(
            s,
            "boundary {:?} DOFs {}-{} (line {})",
            b.target, b.first, b.last, b.line.line
        );
    }
    let _ = writeln!(s, "frequency: {:?}", deck.frequency);
    for w in &deck.warnings {
        let _ = writeln!(s, "warning line {}: {}", w.line, w.message);
    }
    insta::assert_snapshot!(s);
}

#[test]
fn msh_fixtures() {
    for name in [
        "hex20_cube_v41.msh",
        "mixed_v22.msh",
        "box_mixed2_binary.msh",
        "box_tet10_binary.msh",
        "box_mixed1.msh",
    ] {
        let g = femu_io::gmsh::read_msh(fixture("msh", name)).unwrap();
        let mut s = mesh_summary(&g.mesh);
        for w in &g.warnings {
            let _ = writeln!(s, "warning line {}: {}", w.line, w.message);
        }
        insta::assert_snapshot!(name, s);
    }
}

#[test]
fn uff_plate_test() {
    let path = fixture("uff", "plate_test.unv");
    let u = femu_io::uff::read_uff(&path).unwrap();
    let mut s = String::new();
    let _ = writeln!(s, "units: {:?}", u.units);
    let _ = writeln!(s, "nodes: {} (first {:?})", u.nodes.len(), u.nodes.first());
    for m in &u.modes {
        let _ = writeln!(
            s,
            "mode {}: {} Hz, damping {}, {} nodes, first {:?}",
            m.number,
            m.frequency_hz,
            m.damping,
            m.values.len(),
            m.values.first()
        );
    }
    let td = u.test_data(&path).unwrap();
    let _ = writeln!(
        s,
        "sensors: {} (first {:?})",
        td.sensors.len(),
        td.sensors.first()
    );
    insta::assert_snapshot!(s);
}

#[test]
fn csv_two_modes() {
    let td = femu_io::csv::read_test_csv(fixture("csv", "two_modes.csv")).unwrap();
    let mut s = String::new();
    for sensor in &td.sensors {
        let _ = writeln!(s, "sensor: {sensor:?}");
    }
    let _ = writeln!(s, "frequencies: {:?}", td.modes.frequencies_hz);
    let _ = writeln!(s, "damping: {:?}", td.modes.damping_ratios);
    for j in 0..td.modes.shapes.ncols() {
        let col: Vec<f64> = td.modes.shapes.col(j).iter().copied().collect();
        let _ = writeln!(s, "shape {}: {col:?}", j + 1);
    }
    insta::assert_snapshot!(s);
}

#[test]
fn uff_functions_and_trace_lines() {
    for name in ["frf_ascii.uff", "frf_binary.uff"] {
        let u = femu_io::uff::read_uff(fixture("uff", name)).unwrap();
        let mut s = String::new();
        for f in &u.functions {
            let _ = writeln!(
                s,
                "function type {} {:?} -> {:?}, double {}, binary {}, {} points, abscissa {:?}",
                f.function_type,
                f.reference,
                f.response,
                f.double,
                f.binary,
                f.ordinate.len(),
                match &f.abscissa {
                    femu_io::uff::Abscissa::Even { min, step } => format!("even {min} + k {step}"),
                    femu_io::uff::Abscissa::Uneven(x) => format!("uneven {x:?}"),
                }
            );
            let _ = writeln!(s, "  ids {:?}", f.ids);
            let _ = writeln!(s, "  axes {:?}", f.axes);
            let v = match &f.ordinate {
                femu_io::uff::Ordinate::Real(y) => format!("{:?} .. {:?}", y.first(), y.last()),
                femu_io::uff::Ordinate::Complex(y) => format!("{:?} .. {:?}", y.first(), y.last()),
            };
            let _ = writeln!(s, "  values {v}");
        }
        for t in &u.trace_lines {
            let _ = writeln!(s, "trace line {t:?}");
        }
        for w in &u.warnings {
            let _ = writeln!(s, "warning line {}: {}", w.line, w.message);
        }
        insta::assert_snapshot!(name, s);
    }
}

#[test]
fn unv_meshes() {
    for name in ["box_mixed2.unv", "box_tet10.unv"] {
        let path = fixture("msh", name);
        let u = femu_io::uff::read_uff(&path).unwrap();
        let (mesh, warnings) = u.to_mesh(&path).unwrap();
        let mut s = mesh_summary(&mesh);
        let descriptors: std::collections::BTreeMap<i64, usize> =
            u.elements.iter().fold(Default::default(), |mut m, e| {
                *m.entry(e.descriptor).or_default() += 1;
                m
            });
        let _ = writeln!(s, "descriptors: {descriptors:?}");
        for w in u.warnings.iter().chain(&warnings) {
            let _ = writeln!(s, "warning line {}: {}", w.line, w.message);
        }
        insta::assert_snapshot!(name, s);
    }
}
