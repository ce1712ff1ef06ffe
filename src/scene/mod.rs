//! The scene: what a render reads, and how it is made from a scene file.
//!
//! [`Scene`] is plain data: the [`Geometry`] rays are traced against, the
//! materials, textures and lights that shading reads, the camera and the
//! render settings. [`description`] is the scene file as serde types, [`parse`]
//! reads it, [`loaders`] read mesh files, and [`compile`] turns all of
//! that into a [`Scene`], validating every number on the way. [`model`]
//! makes a scene around one model file (`strata render model.glb`).

pub mod asset;
pub mod compile;
pub mod description;
pub mod edit;
pub mod loaders;
pub mod model;
pub mod parse;
pub mod settings;
pub mod source_map;

use crate::camera::Camera;
use crate::error::InputError;
use crate::geometry::Geometry;
use crate::light::{Emitters, Light};
use crate::material::Material;
use crate::texture::Textures;

/// The BVH build effort a render or a mesh query asks for (`bvh_quality`).
pub use crate::accel::BuildQuality;
pub use compile::{
    check_extent, load_edited_scene, load_edited_text, load_mesh_scene, load_scene,
    load_scene_for_tracing, mesh_geometry, scene_from_str, LoadTimings, MeshArraysError, EXTENT,
};
pub use settings::{RenderOverrides, RenderSettings};

/// A compiled scene. Primitives refer to materials by index.
#[derive(Debug, Clone)]
pub struct Scene {
    pub geometry: Geometry,
    pub materials: Vec<Material>,
    /// What the materials' `diffuse_texture` indices name.
    pub textures: Textures,
    pub lights: Vec<Light>,
    /// The surfaces whose material glows, which the path integrator
    /// samples as one more light (made from `geometry` and `materials`).
    pub emitters: Emitters,
    pub camera: Camera,
    pub settings: RenderSettings,
    /// What the mesh loaders read leniently, as other tools do (see
    /// [`loaders`]); the CLI prints each as a `warning:` line.
    pub warnings: Vec<InputError>,
}
