//! Scene files: any bytes must parse and compile to a scene or an InputError, never panic.
#![no_main]

use libfuzzer_sys::fuzz_target;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    if let Ok(text) = std::str::from_utf8(data) {
        let _ = strata::scene::scene_from_str(text, Path::new("/nonexistent/fuzz.toml"), &Default::default());
    }
});
