//! What an 8-bit output shows of linear radiance: an exposure in stops,
//! then a tone curve, then the sRGB encoding (`output::image`). EXR output
//! is radiance and gets neither.
//!
//! `clamp` is the identity, clipped at 1 by the encoding. `filmic` is the
//! identity up to [`SHOULDER`] and then a rational shoulder that reaches 1
//! only at infinity: highlights roll off instead of clipping, while
//! shadows and midtones are those of `clamp`. Per channel, so a bright
//! saturated colour tends towards white as film does.

use glam::Vec3;

crate::mode::mode_enum! {
    /// The tone curve of 8-bit outputs (PNG): clamp (values above 1 clip)
    /// or filmic (the same below 0.6, then a shoulder that rolls highlights
    /// off; no value below 32 turns white). EXR stays linear.
    #[derive(Default)]
    pub enum Tonemap("tone curve") {
        #[default]
        Clamp = "clamp",
        Filmic = "filmic",
    }
}

/// Where `filmic` leaves the identity.
pub const SHOULDER: f32 = 0.6;

/// The least input that `filmic` shows as 8-bit white: inputs below it
/// land below the last level (255 needs 254.5/255 after sRGB encoding).
pub const FILMIC_WHITE: f32 = 32.0;

impl Tonemap {
    /// The displayed linear value of `x` (radiance times 2^exposure).
    pub fn curve(self, x: f32) -> f32 {
        match self {
            Tonemap::Clamp => x,
            Tonemap::Filmic => {
                if x <= SHOULDER {
                    return x;
                }
                // t/(1 + t) has slope 1 at t = 0, so the curve is smooth
                // at the shoulder, and tends to 1.
                let t = (x - SHOULDER) / (1.0 - SHOULDER);
                SHOULDER + (1.0 - SHOULDER) * (t / (1.0 + t))
            }
        }
    }
}

/// `pixels` as an 8-bit output shows them: times 2^`exposure`, through
/// `curve` (values still linear, for the sRGB encoding).
pub fn apply(pixels: &mut [Vec3], exposure: f32, curve: Tonemap) {
    let scale = exposure.exp2();
    if scale == 1.0 && curve == Tonemap::Clamp {
        return;
    }
    for p in pixels {
        *p = Vec3::from_array(p.to_array().map(|c| curve.curve(c * scale)));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::output::image::srgb_level;

    #[test]
    fn exposure_scales_before_the_curve() {
        let mut one = [Vec3::new(0.1, 0.2, 0.25)];
        apply(&mut one, 1.0, Tonemap::Clamp);
        assert_eq!(one[0], Vec3::new(0.2, 0.4, 0.5));
        let mut two = [Vec3::splat(0.5)];
        apply(&mut two, 1.0, Tonemap::Filmic);
        assert_eq!(two[0], Vec3::splat(Tonemap::Filmic.curve(1.0)));
    }

    #[test]
    fn filmic_is_monotonic_from_zero_and_never_clips_below_its_white() {
        let f = |x| Tonemap::Filmic.curve(x);
        assert_eq!(f(0.0), 0.0);
        assert_eq!(f(0.3), 0.3);
        let mut last = -1.0f32;
        let mut x = 0.0f32;
        while x < 1e6 {
            let y = f(x);
            assert!(y >= last && y < 1.0, "{x}: {y} after {last}");
            last = y;
            x = x * 1.01 + 1e-4;
        }
        // Below FILMIC_WHITE, below the last 8-bit level; above, white.
        let level = |x| srgb_level(f(x));
        assert!(level(FILMIC_WHITE * 0.99) < 255);
        assert_eq!(level(FILMIC_WHITE * 1.6), 255);
        // Where clamp clips (above 1), filmic still tells values apart.
        assert!(level(2.0) < level(4.0) && level(4.0) < level(8.0));
    }
}
