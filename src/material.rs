//! The one material model: radiometric Phong with mirror and glass layers.
//!
//! ```toml
//! [materials.glass]
//! diffuse = [0.0, 0.0, 0.0]   # albedo ρ; the diffuse BRDF is ρ/π
//! specular = [0.0, 0.0, 0.0]  # k_s of the normalised Phong lobe (n+2)/(2π) k_s cosⁿα
//! shininess = 0.0             # Phong exponent n of the highlight
//! reflectivity = 0.0          # weight of the mirror (or fuzzy) reflection
//! glossiness = 0.0            # 0 = perfect mirror, else the exponent of the fuzzy lobe
//! transparency = 1.0          # weight of the refracted ray
//! ior = 1.5                   # index of refraction inside the surface
//! fresnel = false             # Schlick's Fresnel splits `transparency` into reflect/refract
//! emission = [0.0, 0.0, 0.0]  # emitted radiance L_e
//! ```
//!
//! The outgoing radiance at a hit is
//! `L_e + Σ_lights (ρ/π + k_s (n+2)/(2π) cosⁿα) E + k_r L_reflected + k_t L_refracted`,
//! the classic Whitted split with each term in radiometric units. Energy
//! conservation is the scene author's job: keep `ρ + k_s + k_r + k_t ≤ 1`.
//!
//! Mesh files may texture ρ (MTL `map_Kd`, glTF `baseColorTexture`): then
//! ρ at a hit is `diffuse` times the texture there; see [`crate::texture`].

use glam::Vec3;

/// Plain data, one per scene material; primitives refer to it by index.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Material {
    pub diffuse: Vec3,
    pub specular: Vec3,
    pub shininess: f32,
    pub reflectivity: f32,
    pub glossiness: f32,
    pub transparency: f32,
    pub ior: f32,
    pub fresnel: bool,
    pub emission: Vec3,
    /// Emit only from the front face (the surfaces of rect and disk lights).
    pub one_sided: bool,
    /// A texture (index into the scene's [`Textures`]) that multiplies
    /// `diffuse` where the surface has texture coordinates. Only mesh files
    /// give one (MTL `map_Kd`, glTF `baseColorTexture`).
    ///
    /// [`Textures`]: crate::texture::Textures
    pub diffuse_texture: Option<u32>,
}

impl Default for Material {
    /// A plain matte grey, the material of objects that name none.
    fn default() -> Self {
        Self {
            diffuse: Vec3::splat(0.8),
            specular: Vec3::ZERO,
            shininess: 0.0,
            reflectivity: 0.0,
            glossiness: 0.0,
            transparency: 0.0,
            ior: 1.5,
            fresnel: false,
            emission: Vec3::ZERO,
            one_sided: false,
            diffuse_texture: None,
        }
    }
}

impl Material {
    pub fn is_emissive(&self) -> bool {
        self.emission.max_element() > 0.0
    }

    pub fn has_specular_lobe(&self) -> bool {
        self.specular.max_element() > 0.0
    }

    /// Whether light arrives through a mirror or glass layer (a reflected
    /// or refracted ray), beyond the direct light.
    pub fn transports_specular(&self) -> bool {
        self.reflectivity > 0.0 || self.transparency > 0.0
    }
}
