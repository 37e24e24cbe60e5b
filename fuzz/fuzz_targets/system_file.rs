//! (c) The co-simulation system file (TOML). An accepted system writes back to TOML that
//! reads as the same system.

#![no_main]

use neurarm_cosim::SystemSpec;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else { return };
    let Ok(spec) = SystemSpec::from_toml(text, "fuzz.toml") else { return };
    let written = spec.to_toml().expect("an accepted system writes");
    let again = SystemSpec::from_toml(&written, "again.toml").expect("an accepted system reads back");
    assert_eq!(format!("{again:?}"), format!("{spec:?}"), "TOML round trip");
});
