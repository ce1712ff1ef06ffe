//! Shading: the distribution ray tracer, Whitted's recursion (1980) with Cook's
//! distributed effects (Cook, Porter and Carpenter 1984).
//!
//! At each hit: emitted radiance, direct light from every light through
//! shadow rays (radiometric Phong: ρ/π diffuse plus the normalised lobe
//! (n+2)/(2π) k_s cosⁿα), then a mirror ray weighted by `reflectivity` and a
//! refracted ray weighted by `transparency` (Snell's law, total internal
//! reflection sends the refracted weight into the reflection).
//! Recursion stops at `max_depth` or when the path weight falls below 1e-3.
//!
//! Distributed effects, each stratified over the pixel's one sample set:
//! area lights take `shadow_samples` M samples per hit; a glossy surface
//! (`glossiness` n > 0) replaces the mirror ray by rays importance-sampled
//! from the normalised cosⁿ lobe around the mirror direction (Lafortune and
//! Willems 1994), and the reflected radiance is the lobe-weighted average of
//! incoming radiance. The first glossy hit of a path branches into
//! `reflection_samples` K rays; deeper glossy hits trace one ray each, so
//! the cost grows by K once, not Kᵈᵉᵖᵗʰ. Lobe directions that fall below the
//! surface are rejected (they contribute nothing) and counted.
//!
//! A batch's coherent rays are traced as packets where [`PacketMode`]
//! says (its rule lives in [`crate::geometry::travel`]): the
//! camera rays of its neighbouring samples ([`Integrator::camera_batch`])
//! and the shadow rays of the batch, from its hits towards one light
//! sample, one per hit (`direct.rs`). Packets return exactly the hits of
//! single rays and every batch is shaded in sample order, so the image is
//! bit-identical with packets on or off. The hits of one batch are
//! lit together, one SIMD lane each (a rect light's spherical rectangles
//! are built and sampled in `f32x8` lanes); each lane computes exactly what
//! its sample alone would, so the image does not depend on the batching.
//!
//! | file | what |
//! |---|---|
//! | [`integrator`] | the [`Integrator`]: camera samples, batches, the recursion |
//! | [`direct`] | direct light: shadow rays towards every light |
//! | [`specular`] | mirror, glossy and refracted rays |
//! | [`bsdf`] | the Phong BRDF, Snell's law and Schlick's Fresnel |
//! | [`sample`] | what identifies a sample, ray counts, replay events |
//! | [`path`] | the path integrator (`integrator = "path"`): NEE with MIS, Russian roulette |
//! | `path_lanes` | the path integrator's batches bounce by bounce: rays traced together, light samples in SIMD lanes |
//! | [`scatter`] | the path integrator's BSDFs: the Phong keys as lobes, metallic-roughness |
//! | [`microfacet`] | GGX, Smith masking, visible-normal sampling, coloured Schlick |
//! | [`maps`] | normal and bump maps, metallic-roughness and emissive textures (both integrators) |
//!
//! All of the above but the last three is the distribution ray tracer,
//! the default for scene files; `integrator = "path"` ([`path`]) shares
//! its camera samples, counts and replays, and nothing of its shading.

pub mod bsdf;
pub mod direct;
pub mod integrator;
pub mod maps;
pub mod microfacet;
pub mod path;
mod path_lanes;
pub mod sample;
pub mod scatter;
#[cfg(test)]
mod scatter_tests;
pub mod specular;

pub use crate::geometry::travel::{BatchRays, PacketMode, CAMERA_PACKET_MIN};
pub use integrator::Integrator;
pub use sample::{CameraSample, FirstHit, PathEvent, RayCounts, SampleContext};
