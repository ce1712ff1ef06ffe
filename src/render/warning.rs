//! What a render (or a merge of its parts) warns of, as data: each front
//! end says it once, its own way (`strata` prints a `warning:` line,
//! Python raises a warning), in the one wording of [`Warning`]'s `Display`.

use super::film::{BadSample, Film};
use crate::scene::Scene;
use std::fmt;

#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Warning {
    /// The scene has no lights and no emissive materials.
    Unlit,
    /// More passes were asked for than there were samples per pixel to
    /// render: a pass holds at least one, so the render made `made`.
    FewerPasses { asked: u32, made: u32 },
    /// Samples dropped as NaN, infinite or negative, and the first of them.
    InvalidSamples { count: u64, first: BadSample },
}

impl Warning {
    /// [`Warning::Unlit`] where nothing in `scene` gives light.
    pub fn unlit(scene: &Scene) -> Option<Self> {
        let lit = !scene.lights.is_empty() || scene.materials.iter().any(|m| m.is_emissive());
        (!lit).then_some(Self::Unlit)
    }

    /// [`Warning::InvalidSamples`] where `film` dropped any.
    pub fn dropped(film: &Film) -> Option<Self> {
        film.first_invalid.map(|first| Self::InvalidSamples {
            count: film.invalid,
            first,
        })
    }
}

impl fmt::Display for Warning {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Unlit => write!(
                f,
                "no lights and no emissive materials, so everything but the background renders black"
            ),
            Self::FewerPasses { asked, made } => write!(
                f,
                "--passes {asked}: only {made} samples per pixel to render, and a pass holds at least one, so {made} passes"
            ),
            Self::InvalidSamples {
                count,
                first: BadSample { x, y, sample },
            } => write!(
                f,
                "{count} samples were NaN, infinite or negative and were dropped; first at pixel ({x}, {y}) sample {sample} (replay it with --debug-sample {x},{y},{sample})"
            ),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    #[test]
    fn a_film_warns_of_its_first_dropped_sample() {
        let mut film = Film::new(2, 1);
        assert_eq!(Warning::dropped(&film), None);
        let mut sum = super::super::film::PixelSum::default();
        sum.add(Vec3::ONE, 0);
        sum.add(Vec3::NAN, 3);
        sum.add(-Vec3::ONE, 4);
        film.add_pixel(1, &sum);
        let warning = Warning::dropped(&film).expect("two dropped");
        let first = BadSample {
            x: 1,
            y: 0,
            sample: 3,
        };
        assert_eq!(warning, Warning::InvalidSamples { count: 2, first });
        assert!(warning.to_string().contains("--debug-sample 1,0,3"));
    }
}
