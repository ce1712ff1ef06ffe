//! Arbitrary output variables: per pixel, the mean over its camera samples
//! of what each camera ray hit first (diffuse albedo, shading normal,
//! distance), for denoisers and compositing, and each pixel's sample
//! count. `--aov albedo,normal,depth,spp` adds them to the EXR as
//! `albedo.R/G/B`, `normal.X/Y/Z`, `depth.Z` and `spp` (what a noise target
//! gave each pixel).
//!
//! Sums are f64, added in sample order by the one worker that owns the
//! pixel in each pass and kept across passes, so they do not depend on the
//! thread count or the number of passes. A pixel where any camera ray
//! misses has depth ∞ (the mean of its samples' depths). A render without
//! AOVs allocates and computes none of this.

use crate::shade::FirstHit;
use glam::Vec3;

crate::mode::mode_enum! {
    /// One AOV.
    pub enum Aov("AOV") {
        /// The first hit's diffuse albedo (texture included).
        Albedo = "albedo",
        /// The first hit's world-space shading normal.
        Normal = "normal",
        /// The first hit's distance along the camera ray (∞ on a miss).
        Depth = "depth",
        /// The camera samples the pixel took (fewer than spp where a noise
        /// target stopped it).
        Spp = "spp",
    }
}

impl Aov {
    /// The EXR channels it fills.
    pub fn channels(self) -> &'static [&'static str] {
        match self {
            Aov::Albedo => &["albedo.R", "albedo.G", "albedo.B"],
            Aov::Normal => &["normal.X", "normal.Y", "normal.Z"],
            Aov::Depth => &["depth.Z"],
            Aov::Spp => &["spp"],
        }
    }
}

/// One pixel's sums.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct AovSum {
    pub albedo: [f64; 3],
    pub normal: [f64; 3],
    pub depth: f64,
    pub count: u32,
}

impl AovSum {
    #[inline]
    pub fn add(&mut self, hit: &FirstHit) {
        for c in 0..3 {
            self.albedo[c] += hit.albedo[c] as f64;
            self.normal[c] += hit.normal[c] as f64;
        }
        self.depth += hit.depth as f64;
        self.count += 1;
    }

    fn mean(&self, sum: [f64; 3]) -> Vec3 {
        let n = self.count.max(1) as f64;
        Vec3::new(
            (sum[0] / n) as f32,
            (sum[1] / n) as f32,
            (sum[2] / n) as f32,
        )
    }
}

/// The per-pixel means of `sums` as named channels, for `aovs` in order.
pub fn channels(sums: &[AovSum], aovs: &[Aov]) -> Vec<(String, Vec<f32>)> {
    let mut out = Vec::new();
    for &aov in aovs {
        let values: Vec<Vec3> = sums
            .iter()
            .map(|s| match aov {
                Aov::Albedo => s.mean(s.albedo),
                Aov::Normal => s.mean(s.normal),
                Aov::Depth => Vec3::splat((s.depth / s.count.max(1) as f64) as f32),
                Aov::Spp => Vec3::splat(s.count as f32),
            })
            .collect();
        for (axis, name) in aov.channels().iter().enumerate() {
            out.push((name.to_string(), values.iter().map(|v| v[axis]).collect()));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn means_per_channel_and_infinite_depth_on_a_miss() {
        let hit = FirstHit {
            albedo: Vec3::new(0.5, 0.25, 1.0),
            normal: Vec3::Z,
            depth: 2.0,
        };
        let mut s = AovSum::default();
        s.add(&hit);
        s.add(&FirstHit { depth: 4.0, ..hit });
        let c = channels(&[s], &[Aov::Depth, Aov::Albedo]);
        let names: Vec<&str> = c.iter().map(|(n, _)| n.as_str()).collect();
        assert_eq!(names, ["depth.Z", "albedo.R", "albedo.G", "albedo.B"]);
        assert_eq!((c[0].1[0], c[1].1[0], c[2].1[0]), (3.0, 0.5, 0.25));
        s.add(&FirstHit::MISS);
        let c = channels(&[s], &[Aov::Depth, Aov::Normal, Aov::Spp]);
        assert_eq!(c[0].1[0], f32::INFINITY);
        assert_eq!((c[4].0.as_str(), c[4].1[0]), ("spp", 3.0));
        assert!(
            (c[3].1[0] - 2.0 / 3.0).abs() < 1e-6,
            "normal.Z averages the miss's 0"
        );
    }
}
