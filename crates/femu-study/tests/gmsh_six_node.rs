//! Gmsh's 6-node triangles (type 9) made shells with a thickness (`--shell`), built as Nastran's
//! CTRIA6 is (docs/MATH.md, "Six-node triangles").

use femu_sparse::eigen::{EigenOptions, Which};
use femu_study::load::{MaterialOptions, ModelOptions, load_model};

/// FV16's plate (10 m, 50 mm, steel, clamped along x = 0) of `2 x 4 x 4` six-node triangles as a
/// Gmsh 2.2 mesh with `--shell plate=0.05` has the eigenvalues of the same plate as a Nastran
/// deck of CTRIA6 on the same grids (PSHELL with MID3 and TS/T = 5/6 written in full, coupled
/// mass), to 1e-10 (with TS/T blank, Nastran's 0.833333, they differ by 2.1e-7).
#[test]
fn gmsh_six_node_triangles_are_ctria6() {
    let n = 4;
    let m = 2 * n;
    let g = |i: usize, j: usize| 1 + i + (m + 1) * j;
    let mut nodes = Vec::new();
    for j in 0..=m {
        for i in 0..=m {
            nodes.push((
                g(i, j),
                10.0 * i as f64 / m as f64,
                10.0 * j as f64 / m as f64,
            ));
        }
    }
    let triangles: Vec<[usize; 6]> = femu_testkit::tri6_cells(n)
        .iter()
        .map(|c| c.map(|(i, j)| g(i, j)))
        .collect();
    let mut msh = String::from(
        "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$PhysicalNames\n2\n1 2 \"edge\"\n2 1 \"plate\"\n$EndPhysicalNames\n",
    );
    msh.push_str(&format!("$Nodes\n{}\n", nodes.len()));
    for (id, x, y) in &nodes {
        msh.push_str(&format!("{id} {x:?} {y:?} 0\n"));
    }
    let mut elements: Vec<String> = (0..m)
        .map(|j| format!("1 2 2 2 {} {}", g(0, j), g(0, j + 1)))
        .collect();
    for t in &triangles {
        let t: Vec<String> = t.iter().map(|v| v.to_string()).collect();
        elements.push(format!("9 2 1 1 {}", t.join(" ")));
    }
    msh.push_str(&format!("$EndNodes\n$Elements\n{}\n", elements.len()));
    for (k, e) in elements.iter().enumerate() {
        msh.push_str(&format!("{} {e}\n", k + 1));
    }
    msh.push_str("$EndElements\n");
    let mut bdf = String::from("SOL 103\nCEND\nSPC = 1\nBEGIN BULK\nPARAM,COUPMASS,1\n");
    for (id, x, y) in &nodes {
        bdf.push_str(&format!("GRID,{id},,{x:?},{y:?},0.\n"));
    }
    for (k, t) in triangles.iter().enumerate() {
        let t: Vec<String> = t.iter().map(|v| v.to_string()).collect();
        bdf.push_str(&format!("CTRIA6,{},7,{}\n", k + 1, t.join(",")));
    }
    bdf.push_str("PSHELL,7,3,0.05,3,,3,.8333333333333334\nMAT1,3,2.+11,,0.3,8000.\n");
    for j in 0..=m {
        bdf.push_str(&format!("SPC1,1,123456,{}\n", g(0, j)));
    }
    bdf.push_str("ENDDATA\n");
    let dir = std::env::temp_dir().join(format!("femu-gmsh-six-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("plate.msh"), msh).unwrap();
    std::fs::write(dir.join("plate.bdf"), bdf).unwrap();
    let options = ModelOptions {
        material: Some(MaterialOptions {
            young: 2e11,
            poisson: 0.3,
            density: 8000.0,
            structural_damping: 0.0,
        }),
        fix: vec!["edge".into()],
        shells: vec![("plate".into(), 0.05)],
        ..Default::default()
    };
    let gmsh = load_model(&dir.join("plate.msh"), &options).unwrap();
    let deck = load_model(&dir.join("plate.bdf"), &ModelOptions::default()).unwrap();
    let lowest = |l: &femu_study::load::LoadedModel| {
        l.sys
            .modes(Which::Lowest(6), &EigenOptions::default())
            .unwrap()
            .values
    };
    let (a, b) = (lowest(&gmsh), lowest(&deck));
    for (x, y) in a.iter().zip(&b) {
        assert!((x / y - 1.0).abs() < 1e-10, "{a:?} {b:?}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}
