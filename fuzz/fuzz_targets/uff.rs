//! Any text given to the universal-file reader, and its conversion to test data, must give a
//! value or an error, never a panic; what it reads must write and read back to the same text.
#![no_main]
use libfuzzer_sys::fuzz_target;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else { return };
    if let Ok(u) = femu_io::uff::parse_uff(text, Path::new("fuzz.unv")) {
        let _ = u.test_data(Path::new("fuzz.unv"));
        let once = femu_io::uff::uff_string(&u);
        let back = femu_io::uff::parse_uff(&once, Path::new("again.unv")).expect("femu's own output reads");
        assert_eq!(femu_io::uff::uff_string(&back), once);
    }
});
