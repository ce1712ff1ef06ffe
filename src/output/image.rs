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
            let data: Vec<u8> = pixels
                .iter()
                .flat_map(|p| {
                    p.to_array()
                        .map(|c| (linear_to_srgb(c) * 255.0 + 0.5) as u8)
                })
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
