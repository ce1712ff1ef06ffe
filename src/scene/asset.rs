//! What a mesh loader hands to the scene compiler: plain arrays in file
//! order, with optional data present only where the file has it.

use super::description::{CameraDesc, CameraType, LightDesc, LightType};
use crate::error::InputError;
use crate::geometry::{MeshNormals, MeshUvs};
use crate::material::Material;
use crate::math::Transform;
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
    /// Width over height of the view, where the file gives it (a
    /// perspective camera's `aspectRatio`, an orthographic one's
    /// `xmag / ymag`).
    pub aspect_ratio: Option<f32>,
}

/// A punctual light (glTF `KHR_lights_punctual`), in world space, its
/// photometric units already turned into radiometric ones.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum LoadedLight {
    Point {
        position: Vec3,
        /// Radiant intensity in W/sr per channel.
        intensity: Vec3,
    },
    Spot {
        position: Vec3,
        /// Unit axis of the cone, the way the light shines.
        direction: Vec3,
        /// Radiant intensity on the axis in W/sr per channel.
        intensity: Vec3,
        /// Half-angles from the axis in radians, 0 ≤ inner ≤ outer ≤ π/2.
        inner_angle: f32,
        outer_angle: f32,
    },
    Directional {
        /// Unit direction the light travels.
        direction: Vec3,
        /// Irradiance in W/m² on a surface facing the light.
        irradiance: Vec3,
    },
}

impl LoadedLight {
    /// The light moved by an object's transform: positions as points,
    /// directions as vectors (renormalised).
    pub fn transformed(&self, t: &Transform) -> Self {
        match *self {
            Self::Point {
                position,
                intensity,
            } => Self::Point {
                position: t.point(position),
                intensity,
            },
            Self::Spot {
                position,
                direction,
                intensity,
                inner_angle,
                outer_angle,
            } => Self::Spot {
                position: t.point(position),
                direction: t.vector(direction).normalize_or_zero(),
                intensity,
                inner_angle,
                outer_angle,
            },
            Self::Directional {
                direction,
                irradiance,
            } => Self::Directional {
                direction: t.vector(direction).normalize_or_zero(),
                irradiance,
            },
        }
    }

    /// The `[[lights]]` entry that makes this light: a scene file's own
    /// words for it, so a file's lights and a hand-written scene's are
    /// compiled (and checked) by the same code.
    pub fn to_desc(&self) -> LightDesc {
        match *self {
            Self::Point {
                position,
                intensity,
            } => LightDesc {
                kind: LightType::Point,
                position: Some(position.into()),
                intensity: Some(intensity.into()),
                ..LightDesc::default()
            },
            Self::Spot {
                position,
                direction,
                intensity,
                inner_angle,
                outer_angle,
            } => LightDesc {
                kind: LightType::Spot,
                position: Some(position.into()),
                direction: Some(direction.into()),
                intensity: Some(intensity.into()),
                inner_angle: Some(inner_angle.to_degrees()),
                outer_angle: Some(outer_angle.to_degrees()),
                ..LightDesc::default()
            },
            Self::Directional {
                direction,
                irradiance,
            } => LightDesc {
                kind: LightType::Directional,
                direction: Some(direction.into()),
                irradiance: Some(irradiance.into()),
                ..LightDesc::default()
            },
        }
    }
}

impl LoadedCamera {
    /// The camera moved by an object's transform.
    pub fn transformed(&self, t: &Transform) -> Self {
        Self {
            position: t.point(self.position),
            forward: t.vector(self.forward),
            up: t.vector(self.up),
            ..self.clone()
        }
    }

    /// The `[camera]` table that makes this camera. `look_at` lies along
    /// the view direction as far off as the camera is from the origin (at
    /// least 1), so that `look_at − position` keeps the direction to f32
    /// precision however far from the origin the camera stands.
    pub fn to_desc(&self) -> CameraDesc {
        let reach = self.position.length().max(1.0);
        let look_at = self.position + self.forward.normalize_or_zero() * reach;
        CameraDesc {
            kind: if self.ortho_height.is_some() {
                CameraType::Orthographic
            } else {
                CameraType::Perspective
            },
            position: self.position.into(),
            look_at: look_at.into(),
            up: self.up.into(),
            fov: self
                .ortho_height
                .is_none()
                .then_some(self.yfov_degrees)
                .flatten(),
            height: self.ortho_height,
            aperture: None,
            focus_distance: None,
        }
    }
}

/// Everything one mesh file contributes to a scene.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct LoadedAsset {
    pub meshes: Vec<LoadedMesh>,
    pub materials: Vec<(String, Material)>,
    /// The images and textures the materials' `diffuse_texture` indices name.
    pub textures: Textures,
    pub cameras: Vec<LoadedCamera>,
    pub lights: Vec<LoadedLight>,
    /// What the loader read leniently, as other tools do (a material no
    /// library defines, a stray header line, no triangles at all), each
    /// naming the file and, where one applies, the line.
    pub warnings: Vec<InputError>,
}

impl LoadedAsset {
    pub fn triangle_count(&self) -> usize {
        self.meshes.iter().map(|m| m.indices.len()).sum()
    }

    /// Every vertex a triangle uses, mesh by mesh (a vertex of several
    /// triangles once per use): what bounds and frames the model, leaving
    /// out points and lines that draw nothing.
    pub fn used_positions(&self) -> impl Iterator<Item = Vec3> + '_ {
        self.meshes.iter().flat_map(|m| {
            m.indices
                .iter()
                .flatten()
                .filter_map(|&i| m.positions.get(i as usize).copied())
        })
    }
}
