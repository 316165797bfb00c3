//! Any text given to the CSV test-mode reader must give a value or an error, never a panic.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else { return };
    let _ = femu_io::csv::parse_test_csv(text, "fuzz.csv");
});
