//! Texture files (what `map_Kd` and glTF images name) through the decoder
//! the loaders use: an image or an error message, never a panic, and never
//! more memory than the `image` crate's limit.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(image) = strata::texture::Image::decode(data) {
        assert_eq!(
            image.texels().len() as u64,
            u64::from(image.width()) * u64::from(image.height())
        );
    }
});
