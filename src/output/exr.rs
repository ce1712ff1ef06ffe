//! OpenEXR output with everything a compositing pipeline reads: any named
//! channels (the beauty pass `R`, `G`, `B`, and AOVs such as `albedo.R` or
//! `depth.Z`), header attributes, and a data window placed inside a larger
//! display window for crops. Linear f32, ZIP-compressed scan lines.

use super::atomic::write_bytes_atomic;
use exr::block::writer::ChunksWriter;
use exr::block::UncompressedBlock;
use exr::image::write::layers::{LayersWriter, WritableLayers};
use exr::prelude::{
    AnyChannel, AnyChannels, AttributeValue, Encoding, FlatSamples, Image, IntegerBounds, Layer,
    LayerAttributes, Text, Vec2, WritableImage,
};
use rayon::prelude::*;

/// A header attribute's value.
#[derive(Debug, Clone, PartialEq)]
pub enum Attribute {
    /// `m44f`: 16 floats, row-vector convention (OpenEXR's).
    Matrix([f32; 16]),
    Int(i32),
    Float(f32),
    Double(f64),
    Text(String),
}

/// One image to write as EXR.
#[derive(Debug, Clone, Default)]
pub struct ExrImage {
    /// The pixels held (the data window).
    pub width: u32,
    pub height: u32,
    /// Where they sit in the whole image (the display window).
    pub origin: (u32, u32),
    pub display: (u32, u32),
    /// `(name, values)`, each `width × height` values in row-major order.
    pub channels: Vec<(String, Vec<f32>)>,
    pub attributes: Vec<(String, Attribute)>,
}

impl ExrImage {
    /// The beauty pass alone: `R`, `G`, `B` from linear RGB pixels.
    pub fn rgb(pixels: &[glam::Vec3], width: u32, height: u32) -> Self {
        let mut image = Self {
            width,
            height,
            display: (width, height),
            ..Self::default()
        };
        image.add_vec3(["R", "G", "B"], pixels);
        image
    }

    /// Three channels from one vector per pixel.
    pub fn add_vec3(&mut self, names: [&str; 3], values: &[glam::Vec3]) {
        for (axis, name) in names.into_iter().enumerate() {
            self.channels
                .push((name.to_string(), values.iter().map(|v| v[axis]).collect()));
        }
    }

    /// The file's bytes.
    pub fn encode(&self) -> Result<Vec<u8>, String> {
        write_blocks(&self.to_exr()?).map_err(|e| e.to_string())
    }

    /// The image as the exr crate holds it.
    fn to_exr(&self) -> Result<Image<Layer<AnyChannels<FlatSamples>>>, String> {
        let n = self.width as usize * self.height as usize;
        if let Some((name, _)) = self.channels.iter().find(|(_, v)| v.len() != n) {
            return Err(format!("channel {name} does not have {n} values"));
        }
        let channels = self
            .channels
            .iter()
            .map(|(name, values)| AnyChannel::new(name.as_str(), FlatSamples::F32(values.clone())))
            .collect();
        let mut attributes = LayerAttributes {
            layer_position: Vec2(self.origin.0 as i32, self.origin.1 as i32),
            ..LayerAttributes::default()
        };
        for (name, value) in &self.attributes {
            // The crate keeps OpenEXR's standard camera attributes in fields
            // of their own.
            match (name.as_str(), value) {
                ("worldToCamera", Attribute::Matrix(m)) => {
                    attributes.world_to_camera = Some(*m);
                    continue;
                }
                ("worldToNDC", Attribute::Matrix(m)) => {
                    attributes.world_to_normalized_device = Some(*m);
                    continue;
                }
                _ => {}
            }
            let value = match value {
                Attribute::Matrix(m) => AttributeValue::Matrix4x4(*m),
                Attribute::Int(i) => AttributeValue::I32(*i),
                Attribute::Float(f) => AttributeValue::F32(*f),
                Attribute::Double(f) => AttributeValue::F64(*f),
                Attribute::Text(t) => AttributeValue::Text(Text::from(t.as_str())),
            };
            attributes.other.insert(Text::from(name.as_str()), value);
        }
        let size = (self.width as usize, self.height as usize);
        let layer = Layer::new(
            size,
            attributes,
            Encoding::SMALL_LOSSLESS,
            AnyChannels::sort(channels),
        );
        let mut image = Image::from_layer(layer);
        image.attributes.display_window =
            IntegerBounds::new((0, 0), (self.display.0 as usize, self.display.1 as usize));
        Ok(image)
    }

    /// Encode and write atomically.
    pub fn write(&self, path: &std::path::Path) -> Result<(), String> {
        let bytes = self.encode()?;
        write_bytes_atomic(path, &bytes).map_err(|e| format!("cannot write: {e}"))
    }
}

/// The file's bytes, its blocks compressed on the rayon pool the caller
/// runs on. The exr crate's own parallel writer starts a pool of its own
/// threads for every file (`ParallelBlocksCompressor::new`), beside the
/// render's: here a 64 × 64 render's output takes 0.65 ms less
/// (docs/performance.md, "An EXR's blocks compressed on the command's
/// pool"). Blocks are compressed a window at a time, so that no more than
/// a few a thread are held uncompressed, and written in the order the
/// crate's writers write them (increasing lines), so the bytes are theirs.
fn write_blocks<L>(image: &Image<L>) -> exr::error::Result<Vec<u8>>
where
    for<'a> L: WritableLayers<'a>,
{
    let writer = image.write();
    let headers = writer.infer_meta_data();
    let layers = image.layer_data.create_writer(&headers);
    let mut bytes = std::io::Cursor::new(Vec::new());
    exr::block::write(&mut bytes, headers, true, |meta, chunks| {
        let window = 4 * rayon::current_num_threads().max(1);
        let mut blocks = meta.collect_ordered_block_data(|index| {
            layers.extract_uncompressed_block(&meta.headers, index)
        });
        loop {
            let some: Vec<(usize, UncompressedBlock)> = blocks.by_ref().take(window).collect();
            if some.is_empty() {
                return Ok(());
            }
            let compressed: Vec<_> = some
                .into_par_iter()
                .map(|(at, block)| block.compress_to_chunk(&meta.headers).map(|c| (at, c)))
                .collect();
            for chunk in compressed {
                let (at, chunk) = chunk?;
                chunks.write_chunk(at, chunk)?;
            }
        }
    })?;
    Ok(bytes.into_inner())
}

#[cfg(test)]
mod tests {
    use super::*;
    use exr::prelude::{read, ReadChannels, ReadLayers};

    /// The blocks compressed on the caller's pool make the very bytes the
    /// crate's own writer makes, one thread or its pool, for an image of
    /// more blocks (16 lines each) than one window of any pool here holds.
    #[test]
    fn blocks_compressed_here_make_the_crates_own_bytes() {
        let (w, h) = (37u32, 16 * 40 + 5);
        let pixels: Vec<glam::Vec3> = (0..w * h)
            .map(|i| {
                let x = (i % w) as f32;
                let y = (i / w) as f32;
                glam::Vec3::new((x * 0.37).sin() + y * 0.01, (x * y).sqrt(), 1.0 / (1.0 + x))
            })
            .collect();
        let mut image = ExrImage::rgb(&pixels, w, h);
        image.origin = (3, 2);
        image.display = (50, 700);
        image.attributes.push(("spp".into(), Attribute::Int(4)));
        let ours = image.encode().unwrap();
        // The crate's own writers on the same image.
        let theirs = image.to_exr().unwrap();
        let mut one = std::io::Cursor::new(Vec::new());
        theirs.write().non_parallel().to_buffered(&mut one).unwrap();
        let mut pooled = std::io::Cursor::new(Vec::new());
        theirs.write().to_buffered(&mut pooled).unwrap();
        assert!(
            ours == one.into_inner(),
            "not the one-thread writer's bytes"
        );
        assert!(ours == pooled.into_inner(), "not the pooled writer's bytes");
        for threads in [1, 3] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            assert!(
                pool.install(|| image.encode().unwrap()) == ours,
                "{threads} threads"
            );
        }
    }

    #[test]
    fn channels_attributes_and_windows_read_back() {
        let mut image = ExrImage::rgb(&[glam::Vec3::new(0.25, 0.5, 2.0); 6], 3, 2);
        image.origin = (4, 1);
        image.display = (10, 8);
        image.channels.push((
            "depth.Z".into(),
            vec![1.0, f32::INFINITY, 3.0, 4.0, 5.0, 6.0],
        ));
        let m: [f32; 16] = std::array::from_fn(|i| i as f32);
        image
            .attributes
            .push(("worldToCamera".into(), Attribute::Matrix(m)));
        image.attributes.push(("spp".into(), Attribute::Int(16)));
        image
            .attributes
            .push(("sampler".into(), Attribute::Text("stratified".into())));
        let bytes = image.encode().unwrap();
        let back = read()
            .no_deep_data()
            .largest_resolution_level()
            .all_channels()
            .first_valid_layer()
            .all_attributes()
            .from_buffered(std::io::Cursor::new(bytes))
            .unwrap();
        let layer = &back.layer_data;
        assert_eq!(layer.size, Vec2(3, 2));
        assert_eq!(layer.attributes.layer_position, Vec2(4, 1));
        assert_eq!(back.attributes.display_window.size, Vec2(10, 8));
        let names: Vec<String> = layer
            .channel_data
            .list
            .iter()
            .map(|c| c.name.to_string())
            .collect();
        assert_eq!(names, ["B", "G", "R", "depth.Z"]);
        let depth = &layer.channel_data.list[3].sample_data;
        assert_eq!(depth.value_by_flat_index(1).to_f32(), f32::INFINITY);
        let attr = |name: &str| layer.attributes.other.get(&Text::from(name)).cloned();
        assert_eq!(layer.attributes.world_to_camera, Some(m));
        assert_eq!(attr("spp"), Some(AttributeValue::I32(16)));
        assert_eq!(
            attr("sampler"),
            Some(AttributeValue::Text(Text::from("stratified")))
        );
        image.channels.push(("x".into(), vec![]));
        assert!(image.encode().is_err(), "a channel of the wrong size");
    }
}
