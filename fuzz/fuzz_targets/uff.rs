//! Any bytes given to the universal-file reader (text and binary 58b datasets), and its
//! conversions to test data and to a mesh, must give a value or an error, never a panic; what it
//! reads must write and read back to the same bytes.
#![no_main]
use libfuzzer_sys::fuzz_target;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    if let Ok(u) = femu_io::uff::parse_uff_bytes(data, Path::new("fuzz.unv")) {
        let _ = u.test_data(Path::new("fuzz.unv"));
        if let Ok((mesh, _)) = u.to_mesh(Path::new("fuzz.unv")) {
            let _ = femu_fem::model::Model::new(mesh);
        }
        let once = femu_io::uff::uff_bytes(&u);
        let back = femu_io::uff::parse_uff_bytes(&once, Path::new("again.unv"))
            .expect("femu's own output reads");
        assert_eq!(femu_io::uff::uff_bytes(&back), once);
    }
});
