//! Any bytes given to the Gmsh reader (ASCII or binary 4.1), and the model built on what it reads,
//! must give a value or an error, never a panic.
#![no_main]
use libfuzzer_sys::fuzz_target;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    if let Ok(g) = femu_io::gmsh::parse_msh_bytes(data, Path::new("fuzz.msh")) {
        let _ = femu_fem::model::Model::new(g.mesh);
    }
});
