//! Test helpers shared by femu's crates (a dev-dependency only, never published): a seeded
//! random generator, so tests need no RNG crate and are reproducible, and the small steel models
//! several crates test on.

use femu_fem::prelude::*;

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
