//! Any text given to the `.inp` reader, and the model it builds, must give a value or an error,
//! never a panic. Decks with `*INCLUDE` are skipped: they name files on disk.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else { return };
    if text.to_ascii_uppercase().contains("INCLUDE") {
        return;
    }
    if let Ok(deck) = femu_io::inp::parse_inp(text, "fuzz.inp") {
        let _ = deck.to_model();
    }
});
