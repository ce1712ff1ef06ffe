//! Replaying one sample: every random number is a function of (seed,
//! pixel, sample, dimension), so one sample can be recomputed alone and its
//! whole path printed (`strata render --debug-sample x,y,s`).

use super::adaptive;
use super::schedule::{render_pixel_of, SampleSet};
use crate::render::film::{PixelSum, FIXED_SCALE};
use crate::scene::Scene;
use crate::shade::{Integrator, PathEvent};
use glam::Vec3;
use std::fmt::Write;

/// A pixel and sample index.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SampleId {
    pub x: u32,
    pub y: u32,
    pub sample: u32,
}

impl std::str::FromStr for SampleId {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        let parts: Vec<&str> = s.split(',').map(str::trim).collect();
        let [x, y, sample] = parts.as_slice() else {
            return Err(format!("'{s}' is not of the form x,y,sample"));
        };
        let num = |v: &str| {
            v.parse::<u32>()
                .map_err(|_| format!("'{v}' is not a non-negative integer"))
        };
        Ok(Self {
            x: num(x)?,
            y: num(y)?,
            sample: num(sample)?,
        })
    }
}

/// Recompute one sample; returns its radiance and the path it took, or
/// an error if the pixel or sample is outside the render. `per_pass`: the
/// render drew each pass's samples from a set of its own (`--time`; a
/// `--noise` scene's settings say so themselves), so the sample is
/// replayed from its pass's set. A noise render's pixel may have stopped
/// before the sample: it is then the sample the pixel would have taken.
pub fn replay(
    scene: &Scene,
    id: SampleId,
    per_pass: bool,
) -> Result<(Vec3, Vec<PathEvent>), String> {
    let s = &scene.settings;
    if id.x >= s.width || id.y >= s.height || id.sample >= s.spp {
        return Err(format!(
            "sample ({}, {}, {}) is outside {}x{} pixels with {} spp",
            id.x, id.y, id.sample, s.width, s.height, s.spp
        ));
    }
    let mut integrator = Integrator::new(scene);
    integrator.trace = Some(Vec::new());
    let mut acc = PixelSum::default();
    let index = id.y as usize * s.width as usize + id.x as usize;
    let may_stop = per_pass || s.noise.is_some();
    let pass = match may_stop {
        true => adaptive::passes(0, s.spp)
            .into_iter()
            .find(|pass| pass.contains(&id.sample))
            .expect("the passes cover 0..spp"),
        false => 0..s.spp,
    };
    let set = SampleSet::of(s, may_stop, &pass);
    let samples = id.sample..id.sample + 1;
    render_pixel_of(&mut integrator, scene, index, samples, set, &mut acc);
    let events = integrator.trace.take().unwrap_or_default();
    // The sample's value as the film holds it: under the path integrator
    // the first event's radiance is only its own vertex's light.
    let value = Vec3::from_array(acc.sum.map(|s| (s as f64 / FIXED_SCALE) as f32));
    Ok((value, events))
}

/// A readable listing of a replayed path.
pub fn describe(scene: &Scene, id: SampleId, value: Vec3, events: &[PathEvent]) -> String {
    let mut out = format!(
        "sample ({}, {}) #{}: radiance {:?}\n",
        id.x,
        id.y,
        id.sample,
        value.to_array()
    );
    for e in events {
        let indent = "  ".repeat(e.depth as usize + 1);
        let _ = write!(
            out,
            "{indent}{} ray from {:?} dir {:?}",
            e.kind,
            e.ray.origin.to_array(),
            e.ray.direction.to_array()
        );
        match e.hit {
            Some((t, prim, p)) => {
                let _ = writeln!(
                    out,
                    " hits {} at t {t} p {:?} -> L {:?}",
                    scene.geometry.describe_prim(prim),
                    p.to_array(),
                    e.radiance.to_array()
                );
            }
            None => {
                let _ = writeln!(out, " escapes -> background {:?}", e.radiance.to_array());
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::schedule::render_pixel;
    use crate::render::RenderOptions;

    /// A render whose passes draw sets of their own (a noise target, or a
    /// time budget) replays each pixel's samples from its pass's set: the
    /// replayed samples of every pixel, as many as it took, sum to its film.
    #[test]
    fn a_noise_or_time_render_replays_from_its_passes_sets() {
        let text =
            std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/seed-mc.toml"))
                .unwrap();
        // At 40 × 30 pixels (the camera made for them), 20 spp: passes
        // 0..16 and 16..20.
        let overrides = crate::scene::settings::RenderOverrides {
            width: Some(40),
            height: Some(30),
            spp: Some(20),
            ..Default::default()
        };
        let path = std::path::Path::new("seed-mc.toml");
        let mut scene = crate::scene::scene_from_str(&text, path, &overrides).unwrap();
        let check = |scene: &crate::scene::Scene, film: &crate::render::film::Film, per_pass| {
            let mut counts = std::collections::BTreeSet::new();
            for (x, y) in [(20, 17), (5, 5), (33, 20), (20, 12)] {
                let index = y * 40 + x;
                let taken = film.counts[index];
                counts.insert(taken);
                let mut replayed = PixelSum::default();
                for sample in 0..taken {
                    let id = SampleId {
                        x: x as u32,
                        y: y as u32,
                        sample,
                    };
                    replayed.add(replay(scene, id, per_pass).unwrap().0, sample);
                }
                assert_eq!(replayed.sum, film.sums[index], "pixel ({x}, {y})");
            }
            counts
        };
        let timed = RenderOptions {
            budget: Some(1e9),
            ..Default::default()
        };
        let film = super::super::render(&scene, &timed, None, ()).film;
        assert_eq!(check(&scene, &film, true), [20].into());
        // The same pixels replayed from the one set of a plain render differ.
        let plain = super::super::render(&scene, &Default::default(), None, ()).film;
        assert!(plain.sums != film.sums, "the sets differ");
        scene.settings.noise = Some(0.05);
        let film = super::super::render(&scene, &Default::default(), None, ()).film;
        // Some of these pixels stopped at the first decision, some went on
        // to the ceiling.
        let counts = check(&scene, &film, false);
        let first = crate::render::adaptive::FIRST_DECISION;
        assert!(
            counts.contains(&first) && counts.contains(&20),
            "{counts:?}"
        );
    }

    #[test]
    fn a_replayed_sample_equals_the_rendered_one() {
        // The distribution integrator, and the path integrator, whose
        // batches trace their camera rays together and a replay alone.
        for name in ["seed.toml", "cornell.toml"] {
            replayed_samples_equal_the_rendered_ones(name);
        }
    }

    fn replayed_samples_equal_the_rendered_ones(name: &str) {
        let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/");
        let text = std::fs::read_to_string(format!("{dir}{name}")).unwrap();
        let mut scene =
            crate::scene::scene_from_str(&text, std::path::Path::new(name), &Default::default())
                .unwrap();
        scene.settings.width = 40;
        scene.settings.height = 30;
        scene.settings.spp = 3;
        let film = super::super::render(&scene, &Default::default(), None, ()).film;
        for (x, y) in [(20, 17), (5, 5), (33, 20)] {
            let index = y * 40 + x;
            let mut acc = PixelSum::default();
            let mut integrator = Integrator::new(&scene);
            render_pixel(&mut integrator, &scene, index, 0..3, &mut acc);
            assert_eq!(acc.sum, film.sums[index]);
            let mut replayed = PixelSum::default();
            for sample in 0..3 {
                let (value, events) = replay(
                    &scene,
                    SampleId {
                        x: x as u32,
                        y: y as u32,
                        sample,
                    },
                    false,
                )
                .unwrap();
                assert_eq!(events[0].kind, "camera");
                assert!(
                    events.windows(2).all(|w| w[1].depth <= w[0].depth + 1),
                    "pre-order"
                );
                replayed.add(value, sample);
            }
            assert_eq!(
                replayed.sum, film.sums[index],
                "replay reproduces the pixel exactly"
            );
        }
        assert!(replay(
            &scene,
            SampleId {
                x: 40,
                y: 0,
                sample: 0
            },
            false,
        )
        .is_err());
        assert_eq!(
            "3, 4,5".parse::<SampleId>(),
            Ok(SampleId {
                x: 3,
                y: 4,
                sample: 5
            })
        );
    }
}
