//! .stl files through the real loader (and the first-bytes check before
//! it): an asset or an InputError, never a panic, and never an allocation
//! the file cannot back.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let path = std::env::temp_dir().join(format!("strata-fuzz-{}.stl", std::process::id()));
    if std::fs::write(&path, data).is_ok() {
        let _ = strata::scene::loaders::load_mesh_file(&path);
    }
});
