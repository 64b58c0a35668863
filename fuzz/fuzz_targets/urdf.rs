//! Fuzz target: the URDF importer (and export of what it imports) — never a panic, whatever the bytes.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    // The readers take UTF-8 text (non-UTF-8 is refused before parsing, with the line of the bad byte).
    let Ok(text) = std::str::from_utf8(data) else { return };
    let path = std::path::Path::new("fuzz.urdf");
    if let Ok(r) = thermokin_urdf::import_urdf(text, &path.display().to_string(), &thermokin_urdf::ImportOptions::default()) { let _ = thermokin_urdf::export_robot(&r.robot); }
});
