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
//!
//! A material may instead be glTF's metallic-roughness model (the scene
//! file's `base_color`, `metallic` and `roughness` keys, or a glTF
//! material): [`MetallicRoughness`], which the path integrator shades
//! with its own BSDF (GGX; `shade::microfacet`). The distribution
//! integrator shades such a material by its Phong stand-in
//! ([`Material::metallic_roughness`]): the fields above, as it always has
//! for glTF files.

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
    /// glTF's metallic-roughness parameters, where the material is one:
    /// what the path integrator shades (the Phong fields above are its
    /// stand-in under the distribution integrator). The diffuse texture
    /// multiplies `base_color`.
    pub pbr: Option<MetallicRoughness>,
    /// The texture maps mesh files give beyond the diffuse one; none from
    /// the scene file.
    pub maps: Maps,
}

/// Texture maps a material may read (indices into the scene's
/// [`Textures`]), each where the surface has texture coordinates.
///
/// [`Textures`]: crate::texture::Textures
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Maps {
    /// glTF's `metallicRoughnessTexture` (linear): blue multiplies
    /// `metallic`, green `roughness`. The path integrator reads it.
    pub metallic_roughness: Option<u32>,
    /// glTF's `emissiveTexture` (sRGB): multiplies `emission`, in both
    /// integrators and in the glowing surfaces' sampling.
    pub emission: Option<u32>,
    /// A normal or bump map (linear); both integrators shade with the
    /// normal it gives.
    pub normal: Option<NormalMap>,
}

/// A map that bends the shading normal.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NormalMap {
    pub texture: u32,
    pub kind: NormalMapKind,
    /// glTF `normalTexture.scale` (scales the map's x and y), or MTL
    /// `-bm` (scales a height map's heights).
    pub scale: f32,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NormalMapKind {
    /// A tangent-space normal, rgb = (n + 1)/2 (glTF `normalTexture`,
    /// MTL `norm`).
    Normal,
    /// A height field, its red channel the height (MTL `bump`/`map_Bump`),
    /// turned into a normal by Blinn's (1978) bump mapping.
    Height,
}

impl Maps {
    /// Whether any map needs the surface's texture coordinates.
    pub fn any(&self) -> bool {
        self.metallic_roughness.is_some() || self.emission.is_some() || self.normal.is_some()
    }

    /// The same maps with `offset` added to every texture index.
    pub fn offset(self, offset: u32) -> Self {
        Self {
            metallic_roughness: self.metallic_roughness.map(|t| t + offset),
            emission: self.emission.map(|t| t + offset),
            normal: self.normal.map(|n| NormalMap {
                texture: n.texture + offset,
                ..n
            }),
        }
    }
}

/// glTF 2.0's core material (Khronos, "glTF 2.0 Specification", Appendix
/// B): a Lambertian base under a GGX specular layer, blended by `metallic`
/// between a dielectric (F0 = 0.04) and a conductor (F0 = `base_color`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MetallicRoughness {
    /// Linear RGB in [0, 1]: the diffuse albedo of the dielectric, the
    /// normal-incidence reflectance of the metal.
    pub base_color: Vec3,
    /// 0 a dielectric, 1 a metal.
    pub metallic: f32,
    /// Perceptual roughness in [0, 1]; the GGX α is its square.
    pub roughness: f32,
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
            pbr: None,
            maps: Maps::default(),
        }
    }
}

/// Largest Phong exponent the roughness mapping produces.
const MAX_PHONG_EXPONENT: f32 = 1.0e6;

/// Phong exponent matching roughness `r`: `2/α² − 2` with `α = r²`
/// (Walter, Marschner, Li and Torrance 2007, the Beckmann–Phong relation
/// carried over to GGX), clamped to [1, 10⁶].
fn phong_exponent(roughness: f32) -> f32 {
    let alpha = roughness * roughness;
    let alpha2 = alpha * alpha;
    if alpha2 <= 0.0 {
        return MAX_PHONG_EXPONENT;
    }
    (2.0 / alpha2 - 2.0).clamp(1.0, MAX_PHONG_EXPONENT)
}

impl Material {
    /// A metallic-roughness material, with the Phong stand-in the
    /// distribution integrator shades it by (the table in the glTF
    /// loader's documentation): diffuse `base (1 − metallic)`, a 0.04
    /// highlight and a mirror of weight `metallic`, both with the Phong
    /// exponent of the roughness.
    pub fn metallic_roughness(base: Vec3, metallic: f32, roughness: f32, emission: Vec3) -> Self {
        let exponent = phong_exponent(roughness);
        Material {
            diffuse: base * (1.0 - metallic),
            specular: Vec3::splat(0.04 * (1.0 - metallic)),
            shininess: exponent,
            reflectivity: metallic,
            glossiness: if roughness == 0.0 { 0.0 } else { exponent },
            emission,
            pbr: Some(MetallicRoughness {
                base_color: base,
                metallic,
                roughness,
            }),
            ..Material::default()
        }
    }
}

impl Material {
    pub fn is_emissive(&self) -> bool {
        self.emission.max_element() > 0.0
    }

    /// Whether a surface of this material needs texture coordinates.
    pub fn is_textured(&self) -> bool {
        self.diffuse_texture.is_some() || self.maps.any()
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
