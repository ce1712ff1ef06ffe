//! Scene files: description (serde types), loaders (mesh files), and the
//! compiler that flattens both into the [`Scene`] the renderer reads.

pub mod asset;
pub mod compile;
pub mod description;
pub mod loaders;
pub mod parse;
pub mod world;

pub use compile::{load_mesh_scene, load_scene, scene_from_str, LoadTimings, RenderOverrides};
pub use world::{RenderSettings, Scene};
