//! Render settings after the scene file and the command line are merged.

use crate::light::LightSampling;
use crate::sampling::SamplerKind;
use glam::Vec3;

/// How fuzzy reflections pick directions. `lobe` importance-samples the
/// cosⁿ lobe; `uniform` samples the hemisphere uniformly (a baseline for
/// `strata converge` and the variance tests).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Deserialize, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum GlossySampling {
    #[default]
    Lobe,
    Uniform,
}

impl std::str::FromStr for GlossySampling {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "lobe" => Ok(Self::Lobe),
            "uniform" => Ok(Self::Uniform),
            _ => Err(format!(
                "unknown glossy sampling '{s}' (expected lobe or uniform)"
            )),
        }
    }
}

/// Render settings after the scene file and the command line are merged.
#[derive(Debug, Clone, PartialEq)]
pub struct RenderSettings {
    pub width: u32,
    pub height: u32,
    pub spp: u32,
    pub shadow_samples: u32,
    pub reflection_samples: u32,
    pub max_depth: u32,
    pub sampler: SamplerKind,
    pub seed: u32,
    pub background: Vec3,
    pub light_sampling: LightSampling,
    pub glossy_sampling: GlossySampling,
}
