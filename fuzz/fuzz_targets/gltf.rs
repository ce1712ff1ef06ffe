//! .gltf files through the real loader (it reads a path, so each input is
//! written to a per-process temporary file): an asset or an InputError, never a panic.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let path = std::env::temp_dir().join(format!("strata-fuzz-{}.gltf", std::process::id()));
    if std::fs::write(&path, data).is_ok() {
        let _ = strata::scene::loaders::load_mesh_file(&path);
    }
});
