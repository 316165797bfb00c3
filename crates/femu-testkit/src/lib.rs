//! Test helpers shared by femu's crates (a dev-dependency only, never published): a seeded
//! random generator, so tests need no RNG crate and are reproducible, the small steel models
//! several crates test on, and the 3D Laplacian with its analytic spectrum.

pub mod ccx;
pub mod op2;
pub mod op4;

use femu_fem::prelude::*;
use femu_sparse::SparseMatrix;

/// The 7-point Laplacian on an `nn^3` grid with Dirichlet ends (h = 1), both triangles stored:
/// its eigenvalues are [`laplacian_3d_spectrum`].
pub fn laplacian_3d(nn: usize) -> SparseMatrix {
    let id = |i: usize, j: usize, k: usize| i + nn * (j + nn * k);
    let mut t = femu_sparse::sprs::TriMat::new((nn * nn * nn, nn * nn * nn));
    for k in 0..nn {
        for j in 0..nn {
            for i in 0..nn {
                let a = id(i, j, k);
                t.add_triplet(a, a, 6.0);
                for (di, dj, dk) in [(1, 0, 0), (0, 1, 0), (0, 0, 1)] {
                    let (i2, j2, k2) = (i + di, j + dj, k + dk);
                    if i2 < nn && j2 < nn && k2 < nn {
                        let b = id(i2, j2, k2);
                        t.add_triplet(a, b, -1.0);
                        t.add_triplet(b, a, -1.0);
                    }
                }
            }
        }
    }
    t.to_csc()
}

/// The eigenvalues of [`laplacian_3d`], ascending: `4 sum_d sin^2(k_d pi / (2 (nn + 1)))` for
/// `k_d = 1..=nn`, with multiplicities from the cube's symmetry.
pub fn laplacian_3d_spectrum(nn: usize) -> Vec<f64> {
    let s = |k: usize| {
        let x = (k as f64 * std::f64::consts::PI / (2.0 * (nn + 1) as f64)).sin();
        4.0 * x * x
    };
    let mut v = Vec::with_capacity(nn * nn * nn);
    for a in 1..=nn {
        for b in 1..=nn {
            for c in 1..=nn {
                v.push(s(a) + s(b) + s(c));
            }
        }
    }
    v.sort_by(f64::total_cmp);
    v
}

/// SplitMix64 (Steele, Lea and Flood 2014): a small deterministic generator.
pub struct Rng(pub u64);

impl Rng {
    /// Uniform in `[0, 1)`.
    pub fn next_f64(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        (z >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Uniform in `[-1, 1]`.
    pub fn sym(&mut self) -> f64 {
        2.0 * self.next_f64() - 1.0
    }
}

/// A steel bar `0.2 x 0.04 x 0.02` m of hex8 cells, optionally clamped at `x = 0`.
pub fn bar(divisions: [usize; 3], clamped: bool) -> Model {
    let mesh = box_mesh(&BoxSpec::new(
        [0.2, 0.04, 0.02],
        divisions,
        BoxCells::Hex,
        false,
    ))
    .expect("a valid box");
    let mut model = Model::new(mesh).expect("a valid mesh");
    model.set_material(None, Material::steel()).expect("steel");
    if clamped {
        model.fix_set("xmin", &[0, 1, 2]).expect("the xmin set");
    }
    model
}

/// The small mixed plate (hex8/penta6/tet4, or their quadratic twins) `0.06 x 0.04 x 0.01` m in
/// `[6, 4, through]` cells, steel with an aluminium tet block (`tet` set), free-free.
pub fn mixed_steel_aluminium_plate(through: usize, quadratic: bool) -> Model {
    let spec = PlateSpec {
        lengths: [0.06, 0.04, 0.01],
        divisions: [6, 4, through],
        tet_block: [2, 2],
        quadratic,
    };
    let mut model = Model::new(mixed_plate(&spec).expect("a valid plate")).expect("a valid mesh");
    model.set_material(None, Material::steel()).expect("steel");
    model
        .set_material(
            Some("tet"),
            Material::isotropic("al", 70e9, 0.33, 2700.0).expect("aluminium"),
        )
        .expect("the tet set");
    model
}

/// The cells of an `n x n` mesh of squares each cut into two 6-node triangles along its diagonal
/// from `(2i, 2j)`, on the `(2 n + 1) x (2 n + 1)` grid of points `(i, j)`: each as its corners
/// counterclockwise, then the midsides of the edges 1-2, 2-3, 3-1 (the order of Nastran's CTRIA6,
/// Abaqus's and CalculiX's S6 and STRI65, and Gmsh's 6-node triangle).
pub fn tri6_cells(n: usize) -> Vec<[(usize, usize); 6]> {
    let mut out = Vec::with_capacity(2 * n * n);
    for j in 0..n {
        for i in 0..n {
            let (a, b) = (2 * i, 2 * j);
            out.push([
                (a, b),
                (a + 2, b),
                (a + 2, b + 2),
                (a + 1, b),
                (a + 2, b + 1),
                (a + 1, b + 1),
            ]);
            out.push([
                (a, b),
                (a + 2, b + 2),
                (a, b + 2),
                (a + 1, b + 1),
                (a + 1, b + 2),
                (a, b + 1),
            ]);
        }
    }
    out
}

/// The points of an `nx x ny` mesh of 8-node quadrilaterals on a `(2 nx + 1) x (2 ny + 1)` grid:
/// The eight corner node ids of brick `(i, j, k)` of a structured grid numbered by `id`, in
/// Abaqus's and Nastran's order (the bottom face counter-clockwise, then the top), as an element
/// line's fields: `"n1, n2, ..., n8"`.
pub fn hex8_nodes<T: std::fmt::Display>(
    id: impl Fn(usize, usize, usize) -> T,
    i: usize,
    j: usize,
    k: usize,
) -> String {
    [
        id(i, j, k),
        id(i + 1, j, k),
        id(i + 1, j + 1, k),
        id(i, j + 1, k),
        id(i, j, k + 1),
        id(i + 1, j, k + 1),
        id(i + 1, j + 1, k + 1),
        id(i, j + 1, k + 1),
    ]
    .iter()
    .map(|v| v.to_string())
    .collect::<Vec<_>>()
    .join(", ")
}

/// every `(i, j)` but the cells' centres (both odd), row by row.
pub fn quad8_points(nx: usize, ny: usize) -> Vec<(usize, usize)> {
    (0..=2 * ny)
        .flat_map(|j| (0..=2 * nx).map(move |i| (i, j)))
        .filter(|(i, j)| i % 2 == 0 || j % 2 == 0)
        .collect()
}

/// The cells of [`quad8_points`], row by row, each as its eight grid points in the element order
/// of Nastran's CQUAD8, Abaqus's S8R and Gmsh's 8-node quadrangle: the corners counterclockwise
/// from `(2i, 2j)`, then the midsides of the edges 1-2, 2-3, 3-4, 4-1.
pub fn quad8_cells(nx: usize, ny: usize) -> Vec<[(usize, usize); 8]> {
    (0..ny)
        .flat_map(|j| (0..nx).map(move |i| (2 * i, 2 * j)))
        .map(|(a, b)| {
            [
                (a, b),
                (a + 2, b),
                (a + 2, b + 2),
                (a, b + 2),
                (a + 1, b),
                (a + 2, b + 1),
                (a + 1, b + 2),
                (a, b + 1),
            ]
        })
        .collect()
}

/// A Nastran deck of a cantilevered steel plate (1 m x 0.5 m, 5 mm, `n x n` CQUAD4, coupled
/// mass, clamped at `x = 0`) whose halves `x < 0.5` and `x > 0.5` are PSHELLs 1 and 2 of MAT1s with
/// structural damping `GE` `ge1` and `ge2` (blank: undamped); `extra` bulk data added.
pub fn damped_plate_deck(n: usize, ge1: &str, ge2: &str, extra: &str) -> String {
    let mut s = String::from("SOL 103\nCEND\nSPC = 1\nBEGIN BULK\nPARAM,COUPMASS,1\n");
    let id = |i: usize, j: usize| 1 + i + (n + 1) * j;
    for j in 0..=n {
        for i in 0..=n {
            s.push_str(&format!(
                "GRID,{},,{},{},0.\n",
                id(i, j),
                i as f64 / n as f64,
                0.5 * j as f64 / n as f64
            ));
        }
        s.push_str(&format!("SPC1,1,123456,{}\n", id(0, j)));
    }
    for j in 0..n {
        for i in 0..n {
            s.push_str(&format!(
                "CQUAD4,{},{},{},{},{},{}\n",
                1 + i + n * j,
                if 2 * i < n { 1 } else { 2 },
                id(i, j),
                id(i + 1, j),
                id(i + 1, j + 1),
                id(i, j + 1)
            ));
        }
    }
    s.push_str(&format!(
        "PSHELL,1,1,0.005,1,,1\nPSHELL,2,2,0.005,2,,2\n\
         MAT1,1,2.1+11,,0.3,7850.,,,{ge1}\nMAT1,2,2.1+11,,0.3,7850.,,,{ge2}\n{extra}ENDDATA\n"
    ));
    s
}

/// Asserts that the frequencies of `eigenvalues` (`omega^2`, s^-2) are `reference` (Hz) to the
/// relative `tolerance`, pairwise in order (`what` names the case in a failure).
pub fn assert_frequencies(eigenvalues: &[f64], reference: &[f64], tolerance: f64, what: &str) {
    assert!(
        eigenvalues.len() >= reference.len(),
        "{what}: {eigenvalues:?}"
    );
    for (l, r) in eigenvalues.iter().zip(reference) {
        let f = l.sqrt() / (2.0 * std::f64::consts::PI);
        assert!(
            (f / r - 1.0).abs() < tolerance,
            "{what}: {f} Hz against {r}"
        );
    }
}
