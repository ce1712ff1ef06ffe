//! Diffuse textures: images decoded once from PNG, JPEG, BMP or TGA,
//! kept as 8-bit sRGB texels, and looked up bilinearly in linear space
//! with a wrap mode per axis.
//!
//! A texture multiplies a material's diffuse colour: the albedo at a hit
//! is `diffuse × texture(u, v)`, looked up once per hit. Mesh files name
//! them; the scene file has no texture keys of its own. Where a surface
//! has no texture coordinates (analytic shapes, CSG solids, a mesh file
//! without `vt` or `TEXCOORD_n`, or a material given to a shape other than
//! its mesh) the diffuse colour applies alone.
//!
//! ```text
//! # scene.mtl (OBJ)                          # glTF
//! newmtl wood                                "materials": [{ "pbrMetallicRoughness": {
//! Kd 1 1 1                                     "baseColorFactor": [1, 1, 1, 1],
//! map_Kd -clamp on textures/wood.png           "baseColorTexture": { "index": 0 } } }]
//! ```
//!
//! # Conventions
//!
//! - **Texture space.** `(0, 0)` is the top-left corner of the image (its
//!   first stored row), `u` runs right and `v` down, as in glTF. The OBJ
//!   loader turns its `vt` coordinates (with `v` up, from the bottom row)
//!   into this space when it reads them.
//! - **Colour.** Texels are sRGB-encoded, as PNG and JPEG colour images and
//!   glTF's base colour are; a 256-entry table decodes them to linear
//!   (IEC 61966-2-1), and filtering happens on the linear values. Alpha is
//!   dropped; 16-bit PNGs are reduced to 8 bits.
//! - **Filtering.** Bilinear, between the four texels whose centres
//!   surround the point, texel `i` having its centre at `(i + ½) / width`.
//!   There is no mipmapping: a texture seen from far away aliases, and the
//!   pixel's samples average it.
//! - **Wrapping.** Per axis, as glTF's sampler `wrapS` and `wrapT`:
//!   [`Wrap::Repeat`] (the default of glTF and MTL), [`Wrap::ClampToEdge`]
//!   (MTL `-clamp on`), [`Wrap::MirroredRepeat`].
//!
//! [`Textures`] holds a scene's images and the textures (image plus wrap
//! modes) that materials name by index, so a file that several materials
//! use is decoded and stored once.

use glam::{Vec2, Vec3};
use std::fmt;
use std::sync::LazyLock;

/// How a coordinate outside [0, 1] finds its texel, per axis.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Wrap {
    /// The image tiles the plane (`GL_REPEAT`, glTF 10497).
    Repeat,
    /// Coordinates stop at the edge texels (`GL_CLAMP_TO_EDGE`, glTF 33071).
    ClampToEdge,
    /// The image tiles with every other copy mirrored (`GL_MIRRORED_REPEAT`,
    /// glTF 33648).
    MirroredRepeat,
}

/// A decoded image: 8-bit sRGB texels, row by row from the top.
#[derive(Clone, PartialEq)]
pub struct Image {
    width: u32,
    height: u32,
    texels: Vec<[u8; 3]>,
}

impl fmt::Debug for Image {
    /// The size only: a texture's megabytes do not belong in a debug print.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "Image({}×{})", self.width, self.height)
    }
}

/// How a texture's bytes turn into numbers.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum Encoding {
    /// Colour: the sRGB curve decodes each byte (base colour, emission).
    #[default]
    Srgb,
    /// Data: byte / 255, no curve (metallic-roughness, normal and height
    /// maps; glTF 2.0 says these are linear).
    Linear,
}

/// An image with the wrap modes of its `u` and `v` axes and how its texels
/// are read: what a material's texture index names. One image may be read
/// as colour by one texture and as data by another.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Texture {
    /// Index into [`Textures::images`].
    pub image: u32,
    pub wrap: [Wrap; 2],
    pub encoding: Encoding,
}

/// A scene's (or one mesh file's) images and textures.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Textures {
    pub images: Vec<Image>,
    pub textures: Vec<Texture>,
}

/// sRGB-encoded byte → linear value, the IEC 61966-2-1 curve: linear below
/// 0.04045, a 2.4 power above.
static SRGB_TO_LINEAR: LazyLock<[f32; 256]> = LazyLock::new(|| {
    std::array::from_fn(|i| {
        let c = i as f64 / 255.0;
        let linear = if c <= 0.04045 {
            c / 12.92
        } else {
            ((c + 0.055) / 1.055).powf(2.4)
        };
        linear as f32
    })
});

/// The linear value of an sRGB-encoded byte.
#[inline]
pub fn srgb_to_linear(c: u8) -> f32 {
    SRGB_TO_LINEAR[c as usize]
}

impl Image {
    /// An image of `width × height` texels, row by row from the top; `None`
    /// if the sizes disagree or either is zero.
    pub fn new(width: u32, height: u32, texels: Vec<[u8; 3]>) -> Option<Self> {
        let count = (width as u64).checked_mul(height as u64)?;
        (width > 0 && height > 0 && texels.len() as u64 == count).then_some(Self {
            width,
            height,
            texels,
        })
    }

    /// Decode an image file's bytes: PNG, JPEG, BMP or TGA, told by its
    /// first bytes (TGA, which has none of its own, only by
    /// [`Image::decode_file`]'s name). Anything else is an error naming
    /// what it is, and anything truncated or corrupt one too; the `image`
    /// crate's default limit (512 MiB) keeps a lying header from
    /// allocating more.
    pub fn decode(bytes: &[u8]) -> Result<Self, String> {
        Self::decode_as(bytes, None)
    }

    /// [`Image::decode`] for the bytes of file `name`, which may be TGA if
    /// its name ends in `.tga` and no other format claims its first bytes.
    pub fn decode_file(bytes: &[u8], name: &std::path::Path) -> Result<Self, String> {
        let tga = name
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("tga"));
        Self::decode_as(bytes, tga.then_some(image::ImageFormat::Tga))
    }

    fn decode_as(bytes: &[u8], by_name: Option<image::ImageFormat>) -> Result<Self, String> {
        use image::ImageFormat;
        let format = match (image::guess_format(bytes), by_name) {
            (Ok(format), _) => format,
            (Err(_), Some(format)) => format,
            (Err(_), None) => return Err(not_an_image(bytes)),
        };
        if !matches!(
            format,
            ImageFormat::Png | ImageFormat::Jpeg | ImageFormat::Bmp | ImageFormat::Tga
        ) {
            let hdr = matches!(format, ImageFormat::OpenExr | ImageFormat::Hdr);
            return Err(format!(
                "{} is not a texture format; textures are {TEXTURE_FORMATS} images{}",
                format_name(format),
                if hdr {
                    " (EXR and Radiance HDR images light a scene as an environment map)"
                } else {
                    ""
                }
            ));
        }
        crate::system::budget::check_image("a texture", bytes, 6)?; // 8-bit RGB, converted and kept
        let decoded = image::ImageReader::with_format(std::io::Cursor::new(bytes), format)
            .decode()
            .map_err(|e| format!("cannot decode the {} image: {e}", format_name(format)))?
            .into_rgb8();
        let (width, height) = decoded.dimensions();
        let texels = decoded
            .into_raw()
            .chunks_exact(3)
            .map(|t| [t[0], t[1], t[2]])
            .collect();
        Self::new(width, height, texels).ok_or_else(|| "the image has no texels".to_string())
    }

    pub fn width(&self) -> u32 {
        self.width
    }

    pub fn height(&self) -> u32 {
        self.height
    }

    /// The sRGB texels, row by row from the top.
    pub fn texels(&self) -> &[[u8; 3]] {
        &self.texels
    }

    /// The linear colour of texel `(x, y)` (already wrapped into range).
    #[inline]
    fn linear(&self, x: usize, y: usize, encoding: Encoding) -> Vec3 {
        let [r, g, b] = self.texels[y * self.width as usize + x];
        match encoding {
            Encoding::Srgb => Vec3::new(srgb_to_linear(r), srgb_to_linear(g), srgb_to_linear(b)),
            Encoding::Linear => Vec3::new(r as f32, g as f32, b as f32) * (1.0 / 255.0),
        }
    }

    /// The bilinearly filtered linear colour at `uv` (see the module docs
    /// for the conventions) of an sRGB-encoded image.
    #[inline]
    pub fn bilinear(&self, uv: Vec2, wrap: [Wrap; 2]) -> Vec3 {
        self.bilinear_as(uv, wrap, Encoding::Srgb)
    }

    /// The bilinearly filtered value at `uv`, the texels read as `encoding`
    /// says.
    #[inline]
    pub fn bilinear_as(&self, uv: Vec2, wrap: [Wrap; 2], encoding: Encoding) -> Vec3 {
        let (x0, x1, fx) = axis(uv.x, self.width, wrap[0]);
        let (y0, y1, fy) = axis(uv.y, self.height, wrap[1]);
        let at = |x, y| self.linear(x, y, encoding);
        let top = at(x0, y0) * (1.0 - fx) + at(x1, y0) * fx;
        let bottom = at(x0, y1) * (1.0 - fx) + at(x1, y1) * fx;
        top * (1.0 - fy) + bottom * fy
    }

    /// The mean of every texel, read as `encoding` says: what a glowing
    /// texture's power is weighed by.
    pub fn mean(&self, encoding: Encoding) -> Vec3 {
        let sum = self
            .texels
            .iter()
            .fold(glam::DVec3::ZERO, |sum, &[r, g, b]| {
                let c = match encoding {
                    Encoding::Srgb => {
                        Vec3::new(srgb_to_linear(r), srgb_to_linear(g), srgb_to_linear(b))
                    }
                    Encoding::Linear => Vec3::new(r as f32, g as f32, b as f32) / 255.0,
                };
                sum + c.as_dvec3()
            });
        (sum / self.texels.len() as f64).as_vec3()
    }
}

/// The image formats textures are read from, for messages.
pub const TEXTURE_FORMATS: &str = "PNG, JPEG, BMP or TGA";

/// A format's usual name ("OpenEXR", "WebP").
fn format_name(format: image::ImageFormat) -> String {
    use image::ImageFormat;
    match format {
        ImageFormat::Png => "PNG".into(),
        ImageFormat::Jpeg => "JPEG".into(),
        ImageFormat::Bmp => "BMP".into(),
        ImageFormat::Tga => "TGA".into(),
        ImageFormat::OpenExr => "OpenEXR".into(),
        ImageFormat::Hdr => "Radiance HDR".into(),
        ImageFormat::WebP => "WebP".into(),
        other => other
            .extensions_str()
            .first()
            .map_or_else(|| format!("{other:?}"), |e| e.to_ascii_uppercase()),
    }
}

/// What bytes that no image format claims are, as far as can be told.
fn not_an_image(bytes: &[u8]) -> String {
    let head = &bytes[..bytes.len().min(512)];
    // UTF-8 up to where the head may have cut a character.
    let utf8 = std::str::from_utf8(head).map_or_else(|e| e.error_len().is_none(), |_| true);
    let what = if bytes.is_empty() {
        "an empty file"
    } else if utf8 && !head.contains(&0) {
        "a text file"
    } else {
        "data of no image format strata knows"
    };
    format!("{what}, not an image; textures are {TEXTURE_FORMATS} images (TGA named .tga)")
}

/// Along one axis of `n` texels: the two texels whose centres surround
/// coordinate `u`, and the weight of the second.
#[inline]
fn axis(u: f32, n: u32, wrap: Wrap) -> (usize, usize, f32) {
    // Bring u into one period first, so that the texel coordinate stays
    // small and its fraction exact however far the UVs tile.
    let u = if u.is_finite() { u } else { 0.0 };
    let u = match wrap {
        Wrap::Repeat => u.rem_euclid(1.0),
        Wrap::MirroredRepeat => u.rem_euclid(2.0),
        Wrap::ClampToEdge => u.clamp(0.0, 1.0),
    };
    // Texel i has its centre at (i + ½)/n.
    let x = u * n as f32 - 0.5;
    let below = x.floor();
    let i = below as i64;
    (
        wrap_index(i, n, wrap),
        wrap_index(i + 1, n, wrap),
        x - below,
    )
}

/// Texel `i` of an axis of `n`, any `i`, wrapped into `0..n`.
#[inline]
fn wrap_index(i: i64, n: u32, wrap: Wrap) -> usize {
    let n = i64::from(n);
    let i = match wrap {
        Wrap::Repeat => i.rem_euclid(n),
        Wrap::ClampToEdge => i.clamp(0, n - 1),
        Wrap::MirroredRepeat => {
            // Period 2n: 0 … n−1, then n−1 … 0.
            let k = i.rem_euclid(2 * n);
            if k < n {
                k
            } else {
                2 * n - 1 - k
            }
        }
    };
    i as usize
}

impl Textures {
    /// The filtered value of texture `texture` at `uv`: linear colour, or
    /// data in [0, 1] (as its [`Encoding`] says).
    #[inline]
    pub fn sample(&self, texture: u32, uv: Vec2) -> Vec3 {
        let t = &self.textures[texture as usize];
        self.images[t.image as usize].bilinear_as(uv, t.wrap, t.encoding)
    }

    /// The width and height in texels of texture `texture`'s image.
    pub fn size(&self, texture: u32) -> (u32, u32) {
        let image = &self.images[self.textures[texture as usize].image as usize];
        (image.width, image.height)
    }

    /// The mean of texture `texture` over its image.
    pub fn mean(&self, texture: u32) -> Vec3 {
        let t = &self.textures[texture as usize];
        self.images[t.image as usize].mean(t.encoding)
    }

    pub fn add_image(&mut self, image: Image) -> u32 {
        self.images.push(image);
        self.images.len() as u32 - 1
    }

    /// The index of `texture`, added unless an equal one is there already.
    pub fn add_texture(&mut self, texture: Texture) -> u32 {
        match self.textures.iter().position(|t| *t == texture) {
            Some(i) => i as u32,
            None => {
                self.textures.push(texture);
                self.textures.len() as u32 - 1
            }
        }
    }

    /// Move `other`'s images and textures in after ours; returns what to
    /// add to `other`'s texture indices.
    pub fn append(&mut self, other: Textures) -> u32 {
        let first_texture = self.textures.len() as u32;
        let first_image = self.images.len() as u32;
        self.images.extend(other.images);
        self.textures
            .extend(other.textures.into_iter().map(|t| Texture {
                image: t.image + first_image,
                ..t
            }));
        first_texture
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lin(t: [u8; 3]) -> Vec3 {
        Vec3::new(
            srgb_to_linear(t[0]),
            srgb_to_linear(t[1]),
            srgb_to_linear(t[2]),
        )
    }

    fn close(a: Vec3, b: Vec3) -> bool {
        a.abs_diff_eq(b, 1e-6)
    }

    #[test]
    fn srgb_bytes_decode_to_linear() {
        assert_eq!(srgb_to_linear(0), 0.0);
        assert_eq!(srgb_to_linear(255), 1.0);
        // ((128/255 + 0.055)/1.055)^2.4 = 0.21586
        assert!((srgb_to_linear(128) - 0.21586).abs() < 1e-5);
        // The linear segment: 10/255 = 0.0392 ≤ 0.04045, so 0.0392/12.92.
        assert!((srgb_to_linear(10) - 10.0 / 255.0 / 12.92).abs() < 1e-7);
        for c in 1..=255u8 {
            assert!(
                srgb_to_linear(c) > srgb_to_linear(c - 1),
                "monotonic at {c}"
            );
        }
    }

    #[test]
    fn wrap_modes_map_any_texel_index_into_range() {
        let n = 4;
        let got = |wrap| -> Vec<usize> { (-5..=9).map(|i| wrap_index(i, n, wrap)).collect() };
        //            i = -5 -4 -3 -2 -1  0  1  2  3  4  5  6  7  8  9
        assert_eq!(
            got(Wrap::Repeat),
            [3, 0, 1, 2, 3, 0, 1, 2, 3, 0, 1, 2, 3, 0, 1]
        );
        assert_eq!(
            got(Wrap::ClampToEdge),
            [0, 0, 0, 0, 0, 0, 1, 2, 3, 3, 3, 3, 3, 3, 3]
        );
        assert_eq!(
            got(Wrap::MirroredRepeat),
            [3, 3, 2, 1, 0, 0, 1, 2, 3, 3, 2, 1, 0, 0, 1]
        );
        assert_eq!(wrap_index(i64::MIN, n, Wrap::MirroredRepeat), 0);
        assert_eq!(wrap_index(i64::MAX, n, Wrap::Repeat), 3);
    }

    /// A 4×1 strip of distinct texels, to see which one a lookup lands on.
    fn strip() -> Image {
        Image::new(4, 1, vec![[10, 0, 0], [60, 0, 0], [120, 0, 0], [250, 0, 0]]).unwrap()
    }

    #[test]
    fn lookups_outside_the_unit_square_wrap_as_their_mode_says() {
        let image = strip();
        let texel = |i: usize| lin(image.texels()[i]);
        // u = (i + ½)/4 lands on texel centres: no blending.
        let at = |u: f32, wrap| image.bilinear(Vec2::new(u, 0.5), [wrap, Wrap::Repeat]);
        for i in 0..4 {
            let u = (i as f32 + 0.5) / 4.0;
            for wrap in [Wrap::Repeat, Wrap::ClampToEdge, Wrap::MirroredRepeat] {
                assert!(close(at(u, wrap), texel(i)), "texel {i} {wrap:?}");
            }
        }
        // u = 1.125 is the centre of texel 4: the first again when
        // repeating, the last when mirrored, the last when clamped.
        assert!(close(at(1.125, Wrap::Repeat), texel(0)));
        assert!(close(at(1.125, Wrap::MirroredRepeat), texel(3)));
        assert!(close(at(1.125, Wrap::ClampToEdge), texel(3)));
        // u = −0.375 is the centre of texel −2.
        assert!(close(at(-0.375, Wrap::Repeat), texel(2)));
        assert!(close(at(-0.375, Wrap::MirroredRepeat), texel(1)));
        assert!(close(at(-0.375, Wrap::ClampToEdge), texel(0)));
        // Far out, the period is the same: 1 for repeat, 2 for mirrored.
        assert!(close(at(1000.375, Wrap::Repeat), texel(1)));
        assert!(close(at(1001.375, Wrap::MirroredRepeat), texel(2)));
        // Non-finite coordinates do not panic or poison the result.
        assert!(at(f32::NAN, Wrap::Repeat).is_finite());
        assert!(at(f32::INFINITY, Wrap::MirroredRepeat).is_finite());
    }

    #[test]
    fn bilinear_weights_are_the_products_of_the_axis_distances() {
        let texels = [[255, 0, 0], [0, 255, 0], [0, 0, 255], [128, 128, 128]];
        let image = Image::new(2, 2, texels.to_vec()).unwrap();
        let [t00, t10, t01, t11] = texels.map(lin);
        // Texel coordinates x = 0.25, y = 0.75: u = (x + ½)/2, v = (y + ½)/2.
        let got = image.bilinear(Vec2::new(0.375, 0.625), [Wrap::ClampToEdge; 2]);
        let want =
            t00 * (0.75 * 0.25) + t10 * (0.25 * 0.25) + t01 * (0.75 * 0.75) + t11 * (0.25 * 0.75);
        assert!(close(got, want), "{got} != {want}");
        // Halfway between two texels in linear space, not in sRGB.
        let mid = image.bilinear(Vec2::new(0.5, 0.25), [Wrap::ClampToEdge; 2]);
        assert!(close(mid, (t00 + t10) * 0.5), "{mid}");
        // Across the edge, repeat blends the last column with the first.
        let edge = image.bilinear(Vec2::new(1.0, 0.25), [Wrap::Repeat; 2]);
        assert!(close(edge, (t10 + t00) * 0.5), "{edge}");
        let clamped = image.bilinear(Vec2::new(1.0, 0.25), [Wrap::ClampToEdge; 2]);
        assert!(close(clamped, t10), "{clamped}");
    }

    fn encode(image: image::DynamicImage, format: image::ImageFormat) -> Vec<u8> {
        let mut bytes = std::io::Cursor::new(Vec::new());
        image.write_to(&mut bytes, format).unwrap();
        bytes.into_inner()
    }

    #[test]
    fn png_and_jpeg_decode_and_everything_else_is_refused() {
        use image::{DynamicImage, ImageBuffer, ImageFormat, Luma, Rgb, Rgba};
        let rgb = ImageBuffer::from_fn(3, 2, |x, y| Rgb([x as u8 * 100, y as u8 * 200, 7]));
        let png = encode(DynamicImage::ImageRgb8(rgb), ImageFormat::Png);
        let image = Image::decode(&png).unwrap();
        assert_eq!((image.width(), image.height()), (3, 2));
        assert_eq!(image.texels()[0], [0, 0, 7]);
        assert_eq!(image.texels()[5], [200, 200, 7], "row by row from the top");

        // Grey, alpha and 16 bits all come out as 8-bit RGB.
        let grey = ImageBuffer::from_pixel(1, 1, Luma([90u8]));
        let decoded = Image::decode(&encode(DynamicImage::ImageLuma8(grey), ImageFormat::Png));
        assert_eq!(decoded.unwrap().texels(), [[90, 90, 90]]);
        let rgba = ImageBuffer::from_pixel(1, 1, Rgba([1u8, 2, 3, 0]));
        let decoded = Image::decode(&encode(DynamicImage::ImageRgba8(rgba), ImageFormat::Png));
        assert_eq!(decoded.unwrap().texels(), [[1, 2, 3]]);
        let deep = ImageBuffer::from_pixel(1, 1, Rgb([65535u16, 0, 32896]));
        let decoded = Image::decode(&encode(DynamicImage::ImageRgb16(deep), ImageFormat::Png));
        assert_eq!(decoded.unwrap().texels(), [[255, 0, 128]]);

        // JPEG is lossy: a flat colour comes back within a step or two.
        let flat = ImageBuffer::from_pixel(8, 8, Rgb([200u8, 100, 50]));
        let jpeg = encode(DynamicImage::ImageRgb8(flat), ImageFormat::Jpeg);
        let image = Image::decode(&jpeg).unwrap();
        assert_eq!((image.width(), image.height()), (8, 8));
        for (got, want) in image.texels()[27].iter().zip([200u8, 100, 50]) {
            assert!(got.abs_diff(want) <= 3, "{:?}", image.texels()[27]);
        }

        let err = Image::decode(b"").unwrap_err();
        assert!(err.starts_with("an empty file, not an image"), "{err}");
        let err = Image::decode(b"hello, not an image").unwrap_err();
        assert!(err.starts_with("a text file, not an image"), "{err}");
        assert!(err.contains("PNG, JPEG, BMP or TGA"), "{err}");
        // (A cut inside the final IEND chunk still decodes: the texels are whole.)
        for cut in [8, 20, 33, png.len() / 2] {
            assert!(Image::decode(&png[..cut]).is_err(), "truncated to {cut}");
        }
        let exr = encode(
            DynamicImage::ImageRgb32F(ImageBuffer::from_pixel(1, 1, Rgb([0.5f32; 3]))),
            ImageFormat::OpenExr,
        );
        let err = Image::decode(&exr).unwrap_err();
        assert!(err.starts_with("OpenEXR is not a texture format"), "{err}");
        assert!(err.contains("environment map"), "{err}");
    }

    /// BMP is told by its bytes; TGA, which has no signature, by its
    /// name; both come out as the same texels as the PNG of the image.
    #[test]
    fn bmp_and_tga_decode_like_png() {
        use image::{DynamicImage, ImageBuffer, ImageFormat, Rgb};
        let rgb = ImageBuffer::from_fn(3, 2, |x, y| Rgb([x as u8 * 100, y as u8 * 200, 7]));
        let image = DynamicImage::ImageRgb8(rgb);
        let png = Image::decode(&encode(image.clone(), ImageFormat::Png)).unwrap();
        let bmp = Image::decode(&encode(image.clone(), ImageFormat::Bmp)).unwrap();
        assert_eq!(bmp, png);
        let tga_bytes = encode(image, ImageFormat::Tga);
        let tga = Image::decode_file(&tga_bytes, std::path::Path::new("wood.TGA")).unwrap();
        assert_eq!(tga, png);
        // Not named .tga, the same bytes are no image strata can tell.
        let err = Image::decode_file(&tga_bytes, std::path::Path::new("wood.img")).unwrap_err();
        assert!(err.contains("not an image"), "{err}");
        // A GIF is named as what it is.
        let gif = Image::decode(b"GIF89a\x01\x00\x01\x00").unwrap_err();
        assert!(gif.starts_with("GIF is not a texture format"), "{gif}");
    }

    #[test]
    fn garbage_after_a_png_signature_never_panics() {
        let mut state = 0x7e57_ab1e_5eed_0001u64;
        let mut next = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state
        };
        let png = encode(
            image::DynamicImage::ImageRgb8(image::ImageBuffer::from_pixel(
                4,
                4,
                image::Rgb([9u8, 8, 7]),
            )),
            image::ImageFormat::Png,
        );
        for _ in 0..300 {
            let mut bytes = png.clone();
            for _ in 0..1 + next() % 4 {
                let at = (next() % bytes.len() as u64) as usize;
                bytes[at] = next() as u8;
            }
            let _ = Image::decode(&bytes);
            let mut jpeg = vec![0xff, 0xd8, 0xff];
            jpeg.extend((0..next() % 200).map(|_| next() as u8));
            let _ = Image::decode(&jpeg);
        }
    }

    #[test]
    fn appended_textures_point_at_their_own_images() {
        let mut scene = Textures::default();
        scene.add_image(strip());
        let t = scene.add_texture(Texture {
            image: 0,
            wrap: [Wrap::Repeat; 2],
            encoding: crate::texture::Encoding::Srgb,
        });
        assert_eq!(t, 0);
        assert_eq!(
            scene.add_texture(Texture {
                image: 0,
                wrap: [Wrap::Repeat; 2],
                encoding: crate::texture::Encoding::Srgb,
            }),
            0,
            "deduplicated"
        );
        let mut file = Textures::default();
        file.add_image(Image::new(1, 1, vec![[1, 2, 3]]).unwrap());
        file.add_texture(Texture {
            image: 0,
            wrap: [Wrap::ClampToEdge; 2],
            encoding: crate::texture::Encoding::Srgb,
        });
        let offset = scene.append(file);
        assert_eq!(offset, 1);
        assert_eq!(scene.textures[1].image, 1);
        assert_eq!(scene.sample(1, Vec2::splat(0.3)), lin([1, 2, 3]));
    }
}
