//! .strata slice parts and checkpoints: a partial film or an error, never a
//! panic, and never an allocation larger than the file can back.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = strata::partial::format::read_partial_from(data, data.len() as u64);
});
