//! Textures: a material's `baseColorTexture` (or any other map) resolved to its
//! `textures[i]`, that texture's sampler (wrap modes) and image, the image
//! read from a file beside the glTF, a base64 `data:` URI or a buffer view
//! (GLB), and decoded once however many textures use it.

use super::buffer::{decode_base64, uri_file};
use super::Loader;
use crate::error::InputResult;
use crate::scene::loaders::io_message;
use crate::texture::{Encoding, Image, Texture, Textures, Wrap};
use ::gltf::json;
use json::texture::WrappingMode;
use json::validation::Checked;

/// The textures read so far, and which glTF texture and image each of ours
/// came from.
#[derive(Default)]
pub(super) struct TextureCache {
    pub(super) textures: Textures,
    /// Ours for each `textures[i]` read so far, as colour or as data.
    by_texture: Vec<((usize, Encoding), u32)>,
    /// Ours for each `images[j]` decoded so far.
    by_image: Vec<(usize, u32)>,
}

fn find<K: PartialEq>(list: &[(K, u32)], key: K) -> Option<u32> {
    list.iter().find(|(k, _)| *k == key).map(|(_, v)| *v)
}

impl Loader<'_> {
    /// Our index of the texture `textures[index]`, read on first use;
    /// `referrer` is where the file names it, for errors.
    pub(super) fn texture(
        &self,
        cache: &mut TextureCache,
        index: usize,
        encoding: Encoding,
        referrer: &str,
    ) -> InputResult<u32> {
        if let Some(ours) = find(&cache.by_texture, (index, encoding)) {
            return Ok(ours);
        }
        let location = format!("textures[{index}]");
        let texture = self
            .root
            .textures
            .get(index)
            .ok_or_else(|| self.error(referrer, format!("{location} does not exist")))?;
        let wrap = match texture.sampler.map(|s| s.value()) {
            None => [Wrap::Repeat; 2],
            Some(s) => {
                let sampler = self.root.samplers.get(s).ok_or_else(|| {
                    self.error(&location, format!("samplers[{s}] does not exist"))
                })?;
                let wrap = |mode: &Checked<WrappingMode>| match mode {
                    Checked::Valid(WrappingMode::Repeat) => Ok(Wrap::Repeat),
                    Checked::Valid(WrappingMode::ClampToEdge) => Ok(Wrap::ClampToEdge),
                    Checked::Valid(WrappingMode::MirroredRepeat) => Ok(Wrap::MirroredRepeat),
                    Checked::Invalid => Err(self.error(
                        format!("samplers[{s}]"),
                        "wrapS and wrapT must be 33071, 33648 or 10497",
                    )),
                };
                [wrap(&sampler.wrap_s)?, wrap(&sampler.wrap_t)?]
            }
        };
        let image_index = texture.source.value();
        let image = match find(&cache.by_image, image_index) {
            Some(image) => image,
            None => {
                let image = self.image(image_index, &location)?;
                let ours = cache.textures.add_image(image);
                cache.by_image.push((image_index, ours));
                ours
            }
        };
        let ours = cache.textures.add_texture(Texture {
            image,
            wrap,
            encoding,
        });
        cache.by_texture.push(((index, encoding), ours));
        Ok(ours)
    }

    /// Read and decode `images[index]`; `user` is the texture that uses it.
    fn image(&self, index: usize, user: &str) -> InputResult<Image> {
        let location = format!("images[{index}]");
        let at = |message: String| self.error(&location, format!("{message} (used by {user})"));
        let image = self
            .root
            .images
            .get(index)
            .ok_or_else(|| self.error(user, format!("{location} does not exist")))?;
        let bytes: Vec<u8>;
        let (data, what, file): (&[u8], String, Option<std::path::PathBuf>) =
            match (&image.uri, image.buffer_view) {
                (Some(uri), _) if uri.starts_with("data:") => {
                    let Some((header, payload)) = uri.split_once(',') else {
                        return Err(at("data: URI has no ',' before its data".to_string()));
                    };
                    if !header.ends_with(";base64") {
                        return Err(at("only base64 data: URIs are supported".to_string()));
                    }
                    bytes = decode_base64(payload).map_err(at)?;
                    (&bytes, "its data: URI".to_string(), None)
                }
                (Some(uri), _) => {
                    let file = uri_file(self.path, uri).map_err(at)?;
                    bytes = std::fs::read(&file).map_err(|e| {
                        at(format!(
                            "cannot read texture {}: {}",
                            file.display(),
                            io_message(&e)
                        ))
                    })?;
                    (&bytes, format!("texture {}", file.display()), Some(file))
                }
                (None, Some(view)) => {
                    let view = view.value();
                    let (_, data) = self.view(view, &location)?;
                    (data, format!("bufferViews[{view}]"), None)
                }
                (None, None) => return Err(at("has neither a uri nor a bufferView".to_string())),
            };
        // A file's name can tell TGA, which has no signature of its own.
        match file {
            Some(file) => Image::decode_file(data, &file),
            None => Image::decode(data),
        }
        .map_err(|e| at(format!("{what}: {e}")))
    }
}

#[cfg(test)]
mod tests {
    use super::super::test_support::*;
    use crate::scene::loaders::test_files::png;
    use crate::texture::Wrap;
    use glam::Vec2;

    /// A quad (two triangles) with UVs as accessor 2 and a second UV set as
    /// accessor 3, and the `rest` of a file whose material 0 is textured.
    fn textured_quad() -> Builder {
        let mut b = Builder::default();
        b.positions(&[[0., 0., 0.], [2., 0., 0.], [2., 1., 0.], [0., 1., 0.]]);
        b.u16s(&[0, 1, 2, 0, 2, 3]);
        b.vec2(&[[0., 1.], [1., 1.], [1., 0.], [0., 0.]]);
        b.vec2(&[[0.5, 0.5]; 4]);
        b
    }

    fn mesh(material: &str) -> String {
        format!(
            r#""meshes":[{{"primitives":[{{"attributes":{{"POSITION":0,"TEXCOORD_0":2,"TEXCOORD_1":3}},"indices":1,"material":{material}}}]}}],"nodes":[{{"mesh":0}}]"#
        )
    }

    #[test]
    fn base_color_textures_bring_their_uvs_image_and_wrap_modes() {
        let texels = [[255, 128, 0], [0, 64, 255]];
        let dir = temp_dir("gltf-texture");
        write(&dir, "two texels.png", &png(2, 1, &texels));
        let b = textured_quad();
        let rest = format!(
            r#"{},"materials":[
                {{"pbrMetallicRoughness":{{"baseColorFactor":[0.5,0.8,1,1],"metallicFactor":0,
                   "baseColorTexture":{{"index":1}}}}}},
                {{"pbrMetallicRoughness":{{"baseColorTexture":{{"index":0,"texCoord":1}}}}}},
                {{"pbrMetallicRoughness":{{"baseColorTexture":{{"index":2}}}}}}],
               "textures":[{{"source":0}},{{"source":0,"sampler":0}},{{"source":0,"sampler":1}}],
               "samplers":[{{"wrapS":33071,"wrapT":33648}},{{"wrapS":10497,"wrapT":33071}}],
               "images":[{{"uri":"two%20texels.png"}}]"#,
            mesh("0")
        );
        let asset = load_gltf(&b.write_gltf(&dir, "q", &rest)).unwrap();
        assert_eq!(asset.textures.images.len(), 1, "one image, decoded once");
        assert_eq!(asset.textures.images[0].texels(), texels);
        let material = asset.materials[0].1;
        assert_close(material.diffuse, Vec3::new(0.5, 0.8, 1.0));
        let texture = material.diffuse_texture.expect("textured");
        let t = asset.textures.textures[texture as usize];
        assert_eq!(t.wrap, [Wrap::ClampToEdge, Wrap::MirroredRepeat]);
        // Read in the order materials name them; no sampler means repeat.
        let wraps: Vec<_> = asset.textures.textures.iter().map(|t| t.wrap).collect();
        assert_eq!(
            wraps,
            [
                [Wrap::ClampToEdge, Wrap::MirroredRepeat],
                [Wrap::Repeat; 2],
                [Wrap::Repeat, Wrap::ClampToEdge]
            ]
        );
        // glTF's UVs are already in our space (v down from the top row).
        let uvs = asset.meshes[0].uvs.as_ref().expect("TEXCOORD_0");
        assert_eq!(uvs.values[1], Vec2::new(1., 1.));
        assert_eq!(uvs.indices, asset.meshes[0].indices);

        // texCoord 1 reads the second set.
        let asset = load_gltf(&b.write_gltf(
            &dir,
            "q1",
            &rest.replace(r#""material":0"#, r#""material":1"#),
        ))
        .unwrap();
        assert_eq!(
            asset.meshes[0].uvs.as_ref().unwrap().values,
            [Vec2::splat(0.5); 4]
        );
    }

    #[test]
    fn untextured_primitives_read_no_uvs() {
        let b = textured_quad();
        let rest = format!(r#"{},"materials":[{{}}]"#, mesh("0"));
        let asset = load_json(&b, &rest).unwrap();
        assert!(asset.meshes[0].uvs.is_none());
        assert!(asset.textures.images.is_empty());
        // A textured material whose primitive has no such UV set: no UVs.
        let rest = format!(
            r#"{},"materials":[{{"pbrMetallicRoughness":{{"baseColorTexture":{{"index":0,"texCoord":4}}}}}}],
               "textures":[{{"source":0}}],"images":[{{"uri":"data:image/png;base64,{}"}}]"#,
            mesh("0"),
            encode_base64(&png(1, 1, &[[1, 2, 3]]))
        );
        let asset = load_json(&b, &rest).unwrap();
        assert!(asset.meshes[0].uvs.is_none());
        assert_eq!(
            asset.textures.images[0].texels(),
            [[1, 2, 3]],
            "from a data: URI"
        );
    }

    #[test]
    fn images_in_glb_buffer_views_and_normalized_integer_uvs() {
        let mut b = Builder::default();
        b.positions(&TRIANGLE);
        // UNSIGNED_BYTE UVs, normalized: 255 is 1.
        b.raw_accessor(&[0, 0, 255, 0, 0, 255], 5121, "VEC2", true);
        let view = b.view(&png(1, 2, &[[9, 9, 9], [200, 100, 0]]));
        let rest = format!(
            r#""meshes":[{{"primitives":[{{"attributes":{{"POSITION":0,"TEXCOORD_0":1}},"material":0}}]}}],
               "nodes":[{{"mesh":0}}],
               "materials":[{{"pbrMetallicRoughness":{{"baseColorTexture":{{"index":0}}}}}}],
               "textures":[{{"source":0}}],"images":[{{"bufferView":{view},"mimeType":"image/png"}}]"#
        );
        let dir = temp_dir("glb-texture");
        let asset = load_gltf(&write(&dir, "t.glb", &b.glb(&rest))).unwrap();
        assert_eq!(
            asset.textures.images[0].texels(),
            [[9, 9, 9], [200, 100, 0]]
        );
        let uvs = &asset.meshes[0].uvs.as_ref().unwrap().values;
        assert_eq!(uvs, &[Vec2::ZERO, Vec2::X, Vec2::Y]);

        // Unnormalized integers are their values (KHR_mesh_quantization:
        // a texture transform scales them).
        let mut b = Builder::default();
        b.positions(&TRIANGLE);
        b.raw_accessor(&[0, 0, 255, 0, 0, 255], 5121, "VEC2", false);
        assert_eq!(b.view(&png(1, 1, &[[9, 9, 9]])), view, "the same layout");
        let asset = load_gltf(&write(&dir, "u.glb", &b.glb(&rest))).unwrap();
        let uvs = &asset.meshes[0].uvs.as_ref().unwrap().values;
        assert_eq!(uvs, &[Vec2::ZERO, Vec2::X * 255.0, Vec2::Y * 255.0]);
    }

    #[test]
    fn missing_and_broken_images_name_the_image_and_texture() {
        let b = textured_quad();
        let dir = temp_dir("gltf-bad-image");
        let material = r#""materials":[{"pbrMetallicRoughness":{"baseColorTexture":{"index":1}}}]"#;
        let with_images = |images: &str| {
            format!(
                r#"{},{material},"textures":[{{"source":0}},{{"source":1}}],"images":[{{"uri":"fine.png"}},{images}]"#,
                mesh("0")
            )
        };
        write(&dir, "fine.png", &png(1, 1, &[[0, 0, 0]]));
        write(&dir, "notes.png", b"not an image at all");
        let cases = [
            (
                r#"{"uri":"gone.png"}"#,
                "gone.png: No such file or directory",
            ),
            (r#"{"uri":"notes.png"}"#, "a text file, not an image"),
            (
                r#"{"uri":"data:image/png;base64,iVBORw0KGgo="}"#,
                "cannot decode",
            ),
            (r#"{"uri":"https://example.com/a.png"}"#, "scheme 'https:'"),
            (r#"{"bufferView":0}"#, "not an image"),
            (r#"{"bufferView":0,"uri":"gone.png"}"#, "gone.png"),
        ];
        for (k, (image, needle)) in cases.into_iter().enumerate() {
            let path = b.write_gltf(&dir, &format!("bad{k}"), &with_images(image));
            expect_error(
                load_gltf(&path),
                &format!("bad{k}.gltf"),
                "images[1]",
                needle,
            );
            let err = load_gltf(&path).unwrap_err();
            assert!(err.to_string().contains("used by textures[1]"), "{err}");
            // Read for its faces alone, no image is read: the quad, with
            // the default material.
            let faces = super::super::load_gltf_with(&path, false).unwrap();
            assert!(faces.materials.is_empty() && faces.textures.images.is_empty());
            assert!(faces
                .meshes
                .iter()
                .all(|m| m.material.is_none() && m.uvs.is_none()));
            assert_eq!(
                faces.meshes.iter().map(|m| m.indices.len()).sum::<usize>(),
                2
            );
        }
        // Unused images are never read.
        let rest = with_images(r#"{"uri":"gone.png"}"#).replace(r#""index":1"#, r#""index":0"#);
        let asset = load_gltf(&b.write_gltf(&dir, "unused", &rest)).unwrap();
        assert_eq!(asset.textures.images.len(), 1);
    }
}
