//! What a mesh loader hands to the scene compiler: plain arrays in file
//! order, with optional data present only where the file has it.

use crate::error::InputError;
use crate::geometry::{MeshNormals, MeshUvs};
use crate::material::Material;
use crate::texture::Textures;
use glam::Vec3;

/// One triangle mesh read from a file. Triangles keep the file's order, so a
/// triangle's index in `indices` is the primitive id that `strata trace`
/// reports and that Embree sees.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct LoadedMesh {
    pub name: String,
    pub positions: Vec<Vec3>,
    pub indices: Vec<[u32; 3]>,
    /// Shading normals, only if the file has them.
    pub normals: Option<MeshNormals>,
    /// Texture coordinates (in [`crate::texture`]'s space), only if the file
    /// has them for every triangle and the mesh's material has a texture.
    pub uvs: Option<MeshUvs>,
    /// Index into [`LoadedAsset::materials`], if the file assigns one.
    pub material: Option<usize>,
}

/// A camera found in a glTF file, already placed in world space.
#[derive(Debug, Clone, PartialEq)]
pub struct LoadedCamera {
    pub position: Vec3,
    pub forward: Vec3,
    pub up: Vec3,
    /// Vertical field of view in degrees for a perspective camera.
    pub yfov_degrees: Option<f32>,
    /// World-space view height for an orthographic camera.
    pub ortho_height: Option<f32>,
}

/// A punctual point light (glTF `KHR_lights_punctual`), in world space.
#[derive(Debug, Clone, PartialEq)]
pub struct LoadedPointLight {
    pub position: Vec3,
    /// Radiant intensity in W/sr per channel.
    pub intensity: Vec3,
}

/// Everything one mesh file contributes to a scene.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct LoadedAsset {
    pub meshes: Vec<LoadedMesh>,
    pub materials: Vec<(String, Material)>,
    /// The images and textures the materials' `diffuse_texture` indices name.
    pub textures: Textures,
    pub cameras: Vec<LoadedCamera>,
    pub point_lights: Vec<LoadedPointLight>,
    /// What the loader read leniently, as other tools do (a material no
    /// library defines, a stray header line, no triangles at all), each
    /// naming the file and, where one applies, the line.
    pub warnings: Vec<InputError>,
}

impl LoadedAsset {
    pub fn triangle_count(&self) -> usize {
        self.meshes.iter().map(|m| m.indices.len()).sum()
    }
}
