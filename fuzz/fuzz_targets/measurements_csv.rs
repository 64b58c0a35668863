//! Fuzz target: the measurements CSV reader — never a panic, whatever the bytes.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    // The readers take UTF-8 text (non-UTF-8 is refused before parsing, with the line of the bad byte).
    let Ok(text) = std::str::from_utf8(data) else { return };
    let path = std::path::Path::new("fuzz.csv");
    let _ = thermokin_io::parse_measurements(path, text, &[thermokin_io::JointKind::Revolute; 6]);
});
