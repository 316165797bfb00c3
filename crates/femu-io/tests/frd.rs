//! CalculiX's result file read as CalculiX writes it: `fixtures/frd/cantilever.frd`, written by
//! CalculiX 2.20 from `cantilever.inp` beside it, has the frequencies CalculiX's `.dat` of the
//! same run prints (written here by hand, 7 digits), its 20 nodes at the deck's coordinates, a
//! clamped root that does not move, and mass-normalised shapes (CalculiX's generalized mass is 1:
//! checked against the consistent mass of femu's assembly of the same deck to 1e-5, the `.frd`'s
//! 6 digits).

use femu_fem::assembly::MassKind;
use std::path::PathBuf;

#[test]
fn a_calculix_frd_is_read_as_calculix_wrote_it() {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/frd");
    let frd = femu_io::frd::read_frd(dir.join("cantilever.frd")).unwrap();
    let dat = [425.0754, 425.0754, 2017.692, 2647.684];
    assert_eq!(frd.modes.len(), 4);
    for (m, f) in frd.modes.iter().zip(dat) {
        assert!(
            (m.frequency_hz / f - 1.0).abs() < 1e-6,
            "{} vs {f}",
            m.frequency_hz
        );
    }
    let deck = femu_io::inp::read_inp(dir.join("cantilever.inp")).unwrap();
    let model = deck.to_model().unwrap();
    let mesh = model.mesh();
    assert_eq!(frd.nodes.len(), mesh.node_count());
    for (id, x) in &frd.nodes {
        let y = mesh.coords()[mesh.node_index(*id).unwrap()];
        assert!((0..3).all(|c| (x[c] - y[c]).abs() < 1e-6), "node {id}");
    }
    let sys = model.assemble(MassKind::Consistent).unwrap();
    for m in &frd.modes {
        let mut v = vec![0.0; sys.dofs.free_count()];
        for (n, (id, _)) in frd.nodes.iter().enumerate() {
            let p = mesh.node_index(*id).unwrap();
            for c in 0..3 {
                match sys.dofs.free_index(p, c) {
                    Some(r) => v[r] = m.shape[n][c],
                    None => assert_eq!(m.shape[n][c], 0.0, "clamped node {id} moves"),
                }
            }
        }
        let mass = femu_sparse::csc::bilinear(&sys.m, &v, &v).unwrap();
        assert!(
            (mass - 1.0).abs() < 1e-5,
            "mode {}: generalized mass {mass}",
            m.number
        );
    }
}
