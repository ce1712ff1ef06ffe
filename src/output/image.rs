//! PNG (sRGB-encoded, clamped, 8-bit) and EXR (linear f32), chosen by extension.

use super::atomic::write_bytes_atomic;
use glam::Vec3;
use std::path::Path;

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ImageFormat {
    Png,
    Exr,
}

impl ImageFormat {
    pub fn from_path(path: &Path) -> Option<Self> {
        match path.extension()?.to_str()?.to_ascii_lowercase().as_str() {
            "png" => Some(Self::Png),
            "exr" => Some(Self::Exr),
            _ => None,
        }
    }
}

/// The sRGB transfer function (IEC 61966-2-1).
pub fn linear_to_srgb(x: f32) -> f32 {
    let x = x.clamp(0.0, 1.0);
    if x <= 0.003_130_8 {
        12.92 * x
    } else {
        1.055 * x.powf(1.0 / 2.4) - 0.055
    }
}

/// The 8-bit sRGB level of a linear value, `(linear_to_srgb(x) · 255 + 0.5)`
/// truncated, as the PNG output writes it: 0 for NaN and below 0, 255 from
/// 1 on.
///
/// Found without `powf` (six per cent of a 640 × 480 one-sample render's
/// instructions): the level is monotone in `x`, so it is the number of
/// the 255 linear values at which it steps up that are at most `x`. Those
/// steps are found once, by bisecting the bits of non-negative floats
/// (whose order is their values'), with [`linear_to_srgb`] itself, so
/// every level is the formula's, bit for bit. The level at the start of
/// `x`'s 1/4096th of the range is looked up, and one step compared: the
/// level rises by at most 0.81 across such a bucket (its steepest, 12.92
/// · 255 levels a unit, is where the curve starts), so no bucket holds
/// two steps.
pub fn srgb_level(x: f32) -> u8 {
    SrgbLevels::get().level(x)
}

/// Buckets of the lookup that [`srgb_level`] starts from.
const BUCKETS: usize = 4096;

/// The linear values at which the 8-bit sRGB level steps up, and the level
/// at the start of each bucket.
struct SrgbLevels {
    /// `steps[k]`: the least `x ≥ 0` whose level is above `k`; `steps[255]`
    /// is +∞ (there is no level above 255).
    steps: [f32; 256],
    start: [u8; BUCKETS],
}

impl SrgbLevels {
    fn get() -> &'static Self {
        static LEVELS: std::sync::OnceLock<SrgbLevels> = std::sync::OnceLock::new();
        LEVELS.get_or_init(|| {
            let level = |bits: u32| (linear_to_srgb(f32::from_bits(bits)) * 255.0 + 0.5) as u8;
            let steps: [f32; 256] = std::array::from_fn(|k| {
                if k == 255 {
                    return f32::INFINITY;
                }
                // The least bits in (0, 1.0] whose level is above k.
                let (mut lo, mut hi) = (0u32, 1.0f32.to_bits());
                while hi - lo > 1 {
                    let mid = lo + (hi - lo) / 2;
                    if level(mid) > k as u8 {
                        hi = mid;
                    } else {
                        lo = mid;
                    }
                }
                f32::from_bits(hi)
            });
            let mut level = 0;
            let start = std::array::from_fn(|i| {
                let x = i as f32 / BUCKETS as f32;
                while x >= steps[level] {
                    level += 1;
                }
                level as u8
            });
            SrgbLevels { steps, start }
        })
    }

    /// [`srgb_level`] of `x`.
    #[inline]
    fn level(&self, x: f32) -> u8 {
        if !(x > 0.0) {
            return 0;
        }
        if x >= 1.0 {
            return 255;
        }
        // x · 4096 is exact (a power of two) and below 4096: its floor is
        // x's bucket, whose lowest value has level `start`.
        let level = self.start[(x * BUCKETS as f32) as usize];
        level + (x >= self.steps[level as usize]) as u8
    }
}

pub fn srgb_to_linear(x: f32) -> f32 {
    if x <= 0.040_45 {
        x / 12.92
    } else {
        ((x + 0.055) / 1.055).powf(2.4)
    }
}

/// Encode an image in memory.
pub fn encode(
    pixels: &[Vec3],
    width: u32,
    height: u32,
    format: ImageFormat,
) -> Result<Vec<u8>, String> {
    let mut bytes = std::io::Cursor::new(Vec::new());
    match format {
        ImageFormat::Png => {
            let levels = SrgbLevels::get();
            let data: Vec<u8> = pixels
                .iter()
                .flat_map(|p| p.to_array().map(|c| levels.level(c)))
                .collect();
            let img =
                image::RgbImage::from_raw(width, height, data).ok_or("image size mismatch")?;
            img.write_to(&mut bytes, image::ImageFormat::Png)
                .map_err(|e| e.to_string())?;
        }
        ImageFormat::Exr => {
            if pixels.len() != width as usize * height as usize {
                return Err("image size mismatch".to_string());
            }
            return super::exr::ExrImage::rgb(pixels, width, height).encode();
        }
    }
    Ok(bytes.into_inner())
}

/// Encode and write atomically.
pub fn write_image(path: &Path, pixels: &[Vec3], width: u32, height: u32) -> Result<(), String> {
    let format = ImageFormat::from_path(path)
        .ok_or_else(|| "output must end in .png or .exr".to_string())?;
    let bytes = encode(pixels, width, height, format)?;
    write_bytes_atomic(path, &bytes).map_err(|e| format!("cannot write: {e}"))
}

/// Read a PNG (decoded to linear) or EXR image, for references and tests.
pub fn read_image(path: &Path) -> Result<(Vec<Vec3>, u32, u32), String> {
    let img = image::open(path).map_err(|e| e.to_string())?;
    let is_png = ImageFormat::from_path(path) == Some(ImageFormat::Png);
    let rgb = img.to_rgb32f();
    let (w, h) = rgb.dimensions();
    let pixels = rgb
        .pixels()
        .map(|p| {
            let v = Vec3::new(p[0], p[1], p[2]);
            if is_png {
                Vec3::new(
                    srgb_to_linear(v.x),
                    srgb_to_linear(v.y),
                    srgb_to_linear(v.z),
                )
            } else {
                v
            }
        })
        .collect();
    Ok((pixels, w, h))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The 8-bit level by the table is the formula's for every float within
    /// 4096 steps of each place the level changes (where a formula that is
    /// not monotone would show), on a sweep of every 61st float of [0, 1],
    /// and for the values outside it.
    #[test]
    fn srgb_levels_are_the_formula_s() {
        let formula = |x: f32| (linear_to_srgb(x) * 255.0 + 0.5) as u8;
        let levels = SrgbLevels::get();
        for (k, &step) in levels.steps[..255].iter().enumerate() {
            assert_eq!(
                formula(step),
                k as u8 + 1,
                "the level steps up at steps[{k}]"
            );
            let bits = step.to_bits();
            for b in bits.saturating_sub(4096)..=(bits + 4096).min(1.0f32.to_bits()) {
                let x = f32::from_bits(b);
                assert_eq!(srgb_level(x), formula(x), "{x:e}");
            }
        }
        for b in (0..=1.0f32.to_bits()).step_by(61) {
            let x = f32::from_bits(b);
            assert_eq!(srgb_level(x), formula(x), "{x:e}");
        }
        for x in [
            -0.0,
            -1e-30,
            -1.0,
            f32::NEG_INFINITY,
            1.0,
            1.0 + 1e-7,
            7.5,
            f32::INFINITY,
            f32::NAN,
            f32::MIN_POSITIVE,
        ] {
            assert_eq!(srgb_level(x), formula(x), "{x:e}");
        }
        assert_eq!(
            (srgb_level(0.0), srgb_level(0.5), srgb_level(1.0)),
            (0, 188, 255)
        );
        // One comparison suffices: no bucket holds two steps.
        for pair in levels.steps[..255].windows(2) {
            let bucket = |x: f32| (x * BUCKETS as f32) as usize;
            assert!(bucket(pair[1]) > bucket(pair[0]), "{pair:?}");
        }
    }

    #[test]
    fn exr_round_trips_linear_values_and_png_is_srgb() {
        let dir = std::env::temp_dir().join(format!("strata-img-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let pixels = vec![Vec3::new(0.0, 0.5, 2.0), Vec3::new(0.2158, 1e-3, 100.0)];
        let exr = dir.join("a.exr");
        write_image(&exr, &pixels, 2, 1).unwrap();
        let (back, w, h) = read_image(&exr).unwrap();
        assert_eq!((w, h), (2, 1));
        assert_eq!(back, pixels);
        let png = dir.join("a.png");
        write_image(&png, &pixels, 2, 1).unwrap();
        let raw = image::open(&png).unwrap().to_rgb8();
        // Linear 0.2158 is sRGB 128/255; values above 1 clamp to 255.
        assert_eq!(raw.get_pixel(1, 0)[0], 128);
        assert_eq!(raw.get_pixel(0, 0)[2], 255);
        assert!(write_image(&dir.join("a.jpg"), &pixels, 2, 1).is_err());
        let leftovers: Vec<_> = std::fs::read_dir(&dir)
            .unwrap()
            .filter_map(|e| e.ok())
            .filter(|e| e.file_name().to_string_lossy().contains(".tmp-"))
            .collect();
        assert!(leftovers.is_empty(), "no temporary files left behind");
        std::fs::remove_dir_all(&dir).ok();
    }
}
