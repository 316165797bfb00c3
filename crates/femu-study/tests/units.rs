//! A deck in another consistent unit system is named as such (femu computes in SI units and
//! labels its results so): pyNastran's tet10 example in inches, lbf s^2/in and seconds
//! (`MAT1 1.705+7 .31 4.14413-4`), a steel plate in millimetres, tonnes and seconds (E 210000
//! MPa, density 7.85e-9 t/mm^3); the same plate in SI has no such warning.

use femu_study::load::{ModelOptions, load_model};
use std::path::PathBuf;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn hint(path: &std::path::Path) -> Option<String> {
    load_model(path, &ModelOptions::default())
        .unwrap()
        .warnings
        .into_iter()
        .find(|w| w.contains("are not those of a structural solid in SI units"))
}

#[test]
fn decks_in_other_unit_systems_are_named() {
    let inches = hint(&root().join("fixtures/nastran/pynastran/simple_example_tet10.bdf"));
    assert!(
        inches
            .as_deref()
            .is_some_and(|w| w.contains("inches, lbf s^2/in")),
        "{inches:?}"
    );
    let dir = std::env::temp_dir().join(format!("femu-units-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let plate = |e: &str, rho: &str, size: f64| {
        let mut s = String::from("*NODE\n");
        let mut id = 1;
        for k in 0..2 {
            for j in 0..2 {
                for i in 0..3 {
                    s.push_str(&format!(
                        "{id}, {:?}, {:?}, {:?}\n",
                        size * 0.1 * i as f64,
                        size * 0.05 * j as f64,
                        size * 0.01 * k as f64
                    ));
                    id += 1;
                }
            }
        }
        s.push_str("*ELEMENT, TYPE=C3D8, ELSET=ALL\n1, 1, 2, 5, 4, 7, 8, 11, 10\n2, 2, 3, 6, 5, 8, 9, 12, 11\n");
        s.push_str(&format!(
            "*MATERIAL, NAME=STEEL\n*ELASTIC\n{e}, 0.3\n*DENSITY\n{rho}\n*SOLID SECTION, ELSET=ALL, MATERIAL=STEEL\n*BOUNDARY\n1, 1, 3\n4, 1, 3\n7, 1, 3\n10, 1, 3\n"
        ));
        s
    };
    let mm = dir.join("mm.inp");
    std::fs::write(&mm, plate("210000.", "7.85e-9", 1000.0)).unwrap();
    let w = hint(&mm);
    assert!(
        w.as_deref()
            .is_some_and(|w| w.contains("millimetres, tonnes")),
        "{w:?}"
    );
    let si = dir.join("si.inp");
    std::fs::write(&si, plate("2.1e11", "7850.", 1.0)).unwrap();
    assert_eq!(hint(&si), None);
    std::fs::remove_dir_all(&dir).ok();
}
