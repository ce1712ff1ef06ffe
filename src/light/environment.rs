//! The environment light: radiance arriving from every direction at
//! infinity, constant or from an equirectangular (lat-long) map, turned
//! by a rotation. Rays that hit nothing see it; shadow rays towards it are
//! occlusion rays to infinity.
//!
//! The map's directions follow Mitsuba 3's `envmap`, so that one file
//! looks the same in both: in the light's own frame (+y up), column
//! u = atan2(x, −z)/2π and row v = θ/π with θ the angle from +y; texel
//! (i, j) covers u ∈ [i/W, (i+1)/W), v ∈ [j/H, (j+1)/H) and is constant
//! there (a nearest lookup, which makes the radiance and the sampling
//! density the same piecewise-constant function).
//!
//! Sampling (`light_sampling = "solid_angle"`): a map by its luminance
//! through a piecewise-constant 2D distribution over (u, v) whose rows are
//! weighted by sin θ, the lat-long mapping's Jacobian, so that the density
//! in solid angle is p(u, v) / (2π² sin θ) (Pharr, Jakob and Humphreys,
//! "Physically Based Rendering", 3rd ed., §14.2.4; Mitsuba's `envmap`); a
//! constant environment seen from a surface by the cosine around its
//! normal (the directions below it light nothing, and a diffuse
//! surface's integrand is then constant). `"area"` samples every
//! environment uniformly over the sphere: a baseline.

use super::{LightSample, LightSampling};
use crate::math::Frame;
use crate::sampling::distribution::Distribution2D;
use crate::sampling::warp::{concentric_disk, uniform_sphere};
use glam::{Mat3, Vec2, Vec3};
use std::f32::consts::{FRAC_1_PI, PI};
use std::sync::Arc;

/// An environment light: what it emits and how it is turned.
#[derive(Debug, Clone, PartialEq)]
pub struct Environment {
    pub emission: Emission,
    /// The rotation from the light's frame to the world's.
    pub to_world: Mat3,
}

/// What an environment emits.
#[derive(Debug, Clone, PartialEq)]
pub enum Emission {
    /// The same radiance from every direction.
    Constant(Vec3),
    /// A lat-long map (its texels already multiplied by the light's scale).
    Map(Arc<EnvMap>),
}

/// One direction drawn towards an environment, with its radiance and the
/// density it was drawn with (per steradian).
#[derive(Debug, Clone, Copy)]
pub struct EnvSample {
    pub wi: Vec3,
    pub radiance: Vec3,
    pub pdf: f32,
}

impl Environment {
    /// A constant environment of `radiance`, the same from every direction.
    pub fn constant(radiance: Vec3) -> Self {
        Self {
            emission: Emission::Constant(radiance),
            to_world: Mat3::IDENTITY,
        }
    }

    /// True for a map, whose sampling is worth combining with a glossy
    /// lobe's; a constant environment is best sampled by the lobe alone.
    pub fn has_map(&self) -> bool {
        matches!(self.emission, Emission::Map(_))
    }

    /// The radiance arriving along the reverse of `direction` (any length):
    /// what a ray travelling along `direction` sees when it hits nothing.
    #[inline]
    pub fn radiance(&self, direction: Vec3) -> Vec3 {
        match &self.emission {
            Emission::Constant(l) => *l,
            Emission::Map(map) => {
                let local = self.to_world.transpose() * direction;
                map.texel(direction_to_uv(local))
            }
        }
    }

    /// A direction drawn towards the environment with `u` uniform in
    /// [0,1)², from a surface with geometric normal `n` facing the viewer
    /// where there is one. `None` where the draw has no density (a pole).
    #[inline]
    pub fn sample(&self, n: Option<Vec3>, u: Vec2, method: LightSampling) -> Option<EnvSample> {
        match (&self.emission, method, n) {
            (Emission::Constant(l), m, Some(n)) if m.by_solid_angle() => {
                // Cosine-weighted about n (Malley's method on the concentric disk).
                let d = concentric_disk(u);
                let z = (1.0 - d.length_squared()).max(0.0).sqrt();
                let pdf = z * FRAC_1_PI;
                (pdf > 0.0).then(|| EnvSample {
                    wi: Frame::from_z(n).to_world(Vec3::new(d.x, d.y, z)),
                    radiance: *l,
                    pdf,
                })
            }
            (Emission::Map(map), m, _) if m.by_solid_angle() => {
                let (uv, pdf_uv) = map.distribution.sample(u);
                let (local, sin_theta) = uv_to_direction(uv);
                let pdf = pdf_uv / (2.0 * PI * PI * sin_theta);
                (sin_theta > 0.0 && pdf > 0.0 && pdf.is_finite()).then(|| EnvSample {
                    wi: self.to_world * local,
                    radiance: map.texel(uv),
                    pdf,
                })
            }
            _ => {
                let wi = uniform_sphere(u);
                Some(EnvSample {
                    wi,
                    radiance: self.radiance(wi),
                    pdf: 0.25 * FRAC_1_PI,
                })
            }
        }
    }

    /// The density (per steradian) with which [`Environment::sample`]
    /// draws the unit direction `wi`.
    #[inline]
    pub fn pdf(&self, n: Option<Vec3>, wi: Vec3, method: LightSampling) -> f32 {
        match (&self.emission, method, n) {
            (Emission::Constant(_), m, Some(n)) if m.by_solid_angle() => {
                n.dot(wi).max(0.0) * FRAC_1_PI
            }
            (Emission::Map(map), m, _) if m.by_solid_angle() => {
                let local = self.to_world.transpose() * wi;
                let sin_theta = (1.0 - local.y * local.y).max(0.0).sqrt();
                if sin_theta > 0.0 {
                    map.distribution.pdf(direction_to_uv(local)) / (2.0 * PI * PI * sin_theta)
                } else {
                    0.0
                }
            }
            _ => 0.25 * FRAC_1_PI,
        }
    }

    /// [`Environment::sample`] as a light sample: radiance over density,
    /// at infinite distance.
    #[inline]
    pub fn light_sample(
        &self,
        n: Option<Vec3>,
        u: Vec2,
        method: LightSampling,
    ) -> Option<LightSample> {
        let s = self.sample(n, u, method)?;
        let weight = s.radiance / s.pdf;
        weight.is_finite().then_some(LightSample {
            wi: s.wi,
            distance: f32::INFINITY,
            weight,
        })
    }
}

/// A unit direction in the light's frame to its lat-long coordinates in
/// [0,1]² (Mitsuba's `envmap` convention; see the module's comment).
#[inline]
pub fn direction_to_uv(d: Vec3) -> Vec2 {
    let u = d.x.atan2(-d.z) * (0.5 * FRAC_1_PI);
    let u = if u < 0.0 { u + 1.0 } else { u };
    Vec2::new(u, d.y.clamp(-1.0, 1.0).acos() * FRAC_1_PI)
}

/// Lat-long coordinates to the unit direction in the light's frame, and
/// sin θ there.
#[inline]
pub fn uv_to_direction(uv: Vec2) -> (Vec3, f32) {
    let phi = 2.0 * PI * uv.x;
    let theta = PI * uv.y;
    let (sin_t, cos_t) = theta.sin_cos();
    let (sin_p, cos_p) = phi.sin_cos();
    (Vec3::new(sin_t * sin_p, cos_t, -sin_t * cos_p), sin_t)
}

/// Rec. 709 luminance, the weight a texel is drawn by.
fn luminance(c: Vec3) -> f32 {
    0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z
}

/// A lat-long environment map: linear RGB texels, row 0 at the top (+y),
/// and the distribution its directions are drawn from.
#[derive(Clone, PartialEq)]
pub struct EnvMap {
    width: u32,
    height: u32,
    texels: Vec<Vec3>,
    distribution: Distribution2D,
    /// A hash of the texels' bits: what the map's `Debug` text (and so a
    /// partial file's scene fingerprint) says of them.
    digest: u64,
}

/// The size and a digest, not millions of texels: the scene fingerprint
/// hashes lights through this text.
impl std::fmt::Debug for EnvMap {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("EnvMap")
            .field("width", &self.width)
            .field("height", &self.height)
            .field("digest", &format_args!("{:016x}", self.digest))
            .finish()
    }
}

/// Bytes a map holds per texel as it is made, besides the decoder's own:
/// the f32 RGB conversion, the texels as read and as scaled, and the
/// sampling distribution (its function and its cumulative sums).
const MAP_TEXEL_BYTES: u64 = 3 * 12 + 4 * 4;

impl EnvMap {
    /// A map of `width` × `height` texels (row-major, top row first), each
    /// multiplied by `scale`. Errors name the first texel that is not a
    /// finite, non-negative colour.
    pub fn new(
        width: u32,
        height: u32,
        texels: Vec<[f32; 3]>,
        scale: Vec3,
    ) -> Result<Self, String> {
        let (w, h) = (width as usize, height as usize);
        if w == 0 || h == 0 || texels.len() != w * h {
            return Err(format!(
                "a {width}×{height} map needs {} texels, got {}",
                w * h,
                texels.len()
            ));
        }
        if let Some(i) = texels
            .iter()
            .position(|t| t.iter().any(|c| !(c.is_finite() && *c >= 0.0)))
        {
            return Err(format!(
                "texel ({}, {}) is {:?}; an environment map's texels must be finite and ≥ 0",
                i % w,
                i / w,
                texels[i]
            ));
        }
        let texels: Vec<Vec3> = texels.iter().map(|&t| Vec3::from(t) * scale).collect();
        // Each row's texels weighted by sin θ at the row's centre: the
        // lat-long mapping's area element.
        let func: Vec<f32> = texels
            .iter()
            .enumerate()
            .map(|(i, &t)| luminance(t) * (PI * ((i / w) as f32 + 0.5) / h as f32).sin())
            .collect();
        let distribution = Distribution2D::new(&func, w, h);
        // FNV-1a over the bits.
        let mut digest = 0xcbf2_9ce4_8422_2325u64;
        for c in texels.iter().flat_map(|t| t.to_array()) {
            for b in c.to_bits().to_le_bytes() {
                digest = (digest ^ b as u64).wrapping_mul(0x0100_0000_01b3);
            }
        }
        Ok(Self {
            width,
            height,
            texels,
            distribution,
            digest,
        })
    }

    /// Decode an EXR or Radiance HDR (RGBE) file's bytes into a map, its
    /// texels multiplied by `scale`; alpha is dropped.
    pub fn decode(bytes: &[u8], scale: Vec3) -> Result<Self, String> {
        use image::ImageFormat;
        let format = image::guess_format(bytes)
            .map_err(|_| "not an EXR or Radiance HDR image".to_string())?;
        if !matches!(format, ImageFormat::OpenExr | ImageFormat::Hdr) {
            return Err(format!(
                "a {} image; an environment map must be EXR or Radiance HDR (.hdr), linear and high dynamic range",
                format.extensions_str().first().unwrap_or(&"?").to_uppercase()
            ));
        }
        // Weighed before a texel is decoded; then the decoder may use what
        // the machine has, not its default 512 MiB (a 16k map is 1.5 GiB).
        crate::system::budget::check_image("an environment map", bytes, MAP_TEXEL_BYTES)?;
        let mut reader = image::ImageReader::with_format(std::io::Cursor::new(bytes), format);
        reader.limits(crate::system::budget::decoder_limits());
        let image = reader
            .decode()
            .map_err(|e| format!("cannot decode: {e}"))?
            .into_rgb32f();
        let (width, height) = image.dimensions();
        let texels = image.pixels().map(|p| p.0).collect();
        Self::new(width, height, texels, scale)
    }

    pub fn width(&self) -> u32 {
        self.width
    }

    pub fn height(&self) -> u32 {
        self.height
    }

    /// The texel holding lat-long point `uv` (a nearest lookup).
    #[inline]
    pub fn texel(&self, uv: Vec2) -> Vec3 {
        let x = ((uv.x * self.width as f32) as u32).min(self.width - 1);
        let y = ((uv.y * self.height as f32) as u32).min(self.height - 1);
        self.texels[(y * self.width + x) as usize]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::stream::{seeded, Draw};

    /// A map with a dim sky gradient and a sun of a few bright texels.
    fn sunny(rotation: Mat3) -> Environment {
        let (w, h) = (32, 16);
        let texels = (0..w * h)
            .map(|i| {
                let (x, y) = (i % w, i / w);
                if (4..6).contains(&y) && (20..22).contains(&x) {
                    [500.0, 450.0, 400.0]
                } else {
                    [0.1 + 0.02 * y as f32, 0.2, 0.3 + 0.01 * x as f32]
                }
            })
            .collect();
        Environment {
            emission: Emission::Map(Arc::new(
                EnvMap::new(w as u32, h as u32, texels, Vec3::new(1.0, 0.5, 2.0)).unwrap(),
            )),
            to_world: rotation,
        }
    }

    #[test]
    fn lat_long_coordinates_follow_mitsuba_and_round_trip() {
        // Mitsuba's envmap: +y is the top row, −z is u = 0, +x is u = ¼.
        let uv = |d: Vec3| direction_to_uv(d);
        assert!((uv(Vec3::Y).y).abs() < 1e-6);
        assert!((uv(-Vec3::Y).y - 1.0).abs() < 1e-6);
        assert!((uv(Vec3::X) - Vec2::new(0.25, 0.5)).length() < 1e-6);
        assert!((uv(Vec3::Z) - Vec2::new(0.5, 0.5)).length() < 1e-6);
        assert!((uv(-Vec3::X) - Vec2::new(0.75, 0.5)).length() < 1e-6);
        let mut rng = seeded(5);
        for _ in 0..1000 {
            let p = Vec2::new(rng.unit(), rng.range(0.01, 0.99));
            let (d, sin_t) = uv_to_direction(p);
            assert!((d.length() - 1.0).abs() < 1e-5 && sin_t > 0.0);
            let back = uv(d);
            let du = (back.x - p.x).abs().min(1.0 - (back.x - p.x).abs());
            assert!(du < 1e-4 && (back.y - p.y).abs() < 1e-4, "{p} -> {back}");
        }
    }

    /// Irradiance on a surface by three estimators that must agree: the
    /// map's own sampling, uniform sphere sampling, and a sum over a fine
    /// grid of directions (the reference). Also checks that each sample's
    /// density is the density [`Environment::pdf`] gives, that the density
    /// integrates to 1 over the sphere, and that importance sampling has the
    /// smaller variance here (a sun: measured, not assumed).
    #[test]
    fn map_sampling_is_unbiased_matches_its_pdf_and_beats_uniform_on_a_sun() {
        let rotation = Mat3::from_axis_angle(Vec3::new(1.0, 2.0, 0.5).normalize(), 0.7);
        let env = sunny(rotation);
        // A surface facing the sun, tilted a little.
        let sun = rotation * uv_to_direction(Vec2::new(21.0 / 32.0, 5.0 / 16.0)).0;
        let n = (sun + Vec3::new(0.3, 0.2, -0.2)).normalize();
        // The reference: a midpoint sum over (u, v) with the sin θ Jacobian.
        let (gu, gv) = (1024, 512);
        let mut reference = 0.0f64;
        let mut pdf_integral = 0.0f64;
        for j in 0..gv {
            for i in 0..gu {
                let uv = Vec2::new((i as f32 + 0.5) / gu as f32, (j as f32 + 0.5) / gv as f32);
                let (local, sin_t) = uv_to_direction(uv);
                let wi = rotation * local;
                let d_omega = (2.0 * PI * PI * sin_t / (gu * gv) as f32) as f64;
                let cos = n.dot(wi).max(0.0);
                reference += (env.radiance(wi).x * cos) as f64 * d_omega;
                pdf_integral += env.pdf(None, wi, LightSampling::SolidAngle) as f64 * d_omega;
            }
        }
        assert!((pdf_integral - 1.0).abs() < 2e-3, "∫pdf = {pdf_integral}");
        let mut rng = seeded(9);
        let count = 200_000;
        let mut stats = Vec::new();
        // Samples whose density, looked up again from their direction,
        // differs: only those that round across a texel's edge may.
        let mut mismatched = 0;
        for method in [LightSampling::SolidAngle, LightSampling::Area] {
            let (mut sum, mut sum2) = (0.0f64, 0.0f64);
            for _ in 0..count {
                let u = Vec2::new(rng.unit(), rng.unit());
                let e = match env.sample(None, u, method) {
                    Some(s) => {
                        let pdf = env.pdf(None, s.wi, method);
                        mismatched += ((pdf - s.pdf).abs() > 1e-3 * s.pdf) as u32;
                        (s.radiance.x * n.dot(s.wi).max(0.0) / s.pdf) as f64
                    }
                    None => 0.0,
                };
                sum += e;
                sum2 += e * e;
            }
            let mean = sum / count as f64;
            let variance = sum2 / count as f64 - mean * mean;
            let error = (variance / count as f64).sqrt();
            assert!(
                (mean - reference).abs() < 5.0 * error + 1e-3 * reference,
                "{method:?}: {mean} ± {error} vs {reference}"
            );
            stats.push(variance);
        }
        assert!(
            mismatched < count / 1000,
            "{mismatched} samples' pdfs differ"
        );
        assert!(
            stats[0] * 10.0 < stats[1],
            "importance variance {} vs uniform {}",
            stats[0],
            stats[1]
        );
    }

    #[test]
    fn a_constant_environment_lights_a_diffuse_surface_without_noise() {
        let env = Environment::constant(Vec3::new(2.0, 1.0, 0.5));
        let n = Vec3::new(0.2, -1.0, 0.4).normalize();
        let mut rng = seeded(1);
        for _ in 0..1000 {
            let u = Vec2::new(rng.unit(), rng.unit());
            let s = env
                .light_sample(Some(n), u, LightSampling::SolidAngle)
                .unwrap();
            // f·L/pdf·cos with f = ρ/π: ρ L exactly, whatever the direction.
            let e = s.weight * n.dot(s.wi) * FRAC_1_PI;
            assert!(
                (e - Vec3::new(2.0, 1.0, 0.5)).abs().max_element() < 1e-4,
                "{e}"
            );
        }
    }

    #[test]
    fn bad_maps_are_refused_with_the_texel() {
        let e = EnvMap::new(2, 1, vec![[1.0; 3], [0.0, f32::NAN, 0.0]], Vec3::ONE).unwrap_err();
        assert!(e.contains("texel (1, 0)"), "{e}");
        let e = EnvMap::new(2, 1, vec![[-1.0, 0.0, 0.0], [0.0; 3]], Vec3::ONE).unwrap_err();
        assert!(e.contains("texel (0, 0)") && e.contains("≥ 0"), "{e}");
        assert!(EnvMap::decode(b"not an image", Vec3::ONE).is_err());
    }

    /// A header claiming more texels than the machine holds is refused
    /// before a texel is decoded, with the size and the bytes.
    #[test]
    fn a_map_past_the_machines_memory_is_refused_from_its_header() {
        let hdr = b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 1000000 +X 1000000\n\x02\x02";
        let e = EnvMap::decode(hdr, Vec3::ONE).unwrap_err();
        assert!(
            e.starts_with("an environment map of 1000000×1000000 texels") && e.contains("TiB"),
            "{e}"
        );
    }
}
