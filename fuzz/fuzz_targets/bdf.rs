//! Any text given to the Nastran bulk data reader, strict and lenient, must give a model or an
//! error, never a panic. Decks with `INCLUDE` are skipped: they name files on disk.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else { return };
    if text.to_ascii_uppercase().contains("INCLUDE") {
        return;
    }
    for lenient in [false, true] {
        let options = femu_io::nastran::BdfOptions { lenient };
        if let Ok(deck) = femu_io::nastran::parse_bdf(text, "fuzz.bdf", &options) {
            let _ = deck.model.dof_map();
        }
    }
});
