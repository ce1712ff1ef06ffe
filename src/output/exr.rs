//! OpenEXR output with everything a compositing pipeline reads: any named
//! channels (the beauty pass `R`, `G`, `B`, and AOVs such as `albedo.R` or
//! `depth.Z`), header attributes, and a data window placed inside a larger
//! display window for crops. Linear f32, ZIP-compressed scan lines.
//!
//! The blocks are compressed here, at zlib's fastest level, not by the
//! exr crate (level 4): on strata's renders level 1 took a quarter to a
//! half of the time, for files 0.1 to 2.5 points of their raw size larger
//! (2 to 13% larger files with the smooth AOV channels; docs/performance.md,
//! "EXR blocks at zlib's fastest level"). Every reader reads either: the
//! level is not in the file.

use super::atomic::write_bytes_atomic;
use exr::block::chunk::{Chunk, CompressedBlock, CompressedScanLineBlock};
use exr::block::writer::ChunksWriter;
use exr::block::UncompressedBlock;
use exr::image::write::layers::{LayersWriter, WritableLayers};
use exr::meta::header::Header;
use exr::meta::BlockDescription;
use exr::prelude::Compression;
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
                .map(|(at, block)| compress_block(block, &meta.headers).map(|c| (at, c)))
                .collect();
            for chunk in compressed {
                let (at, chunk) = chunk?;
                chunks.write_chunk(at, chunk)?;
            }
        }
    })?;
    Ok(bytes.into_inner())
}

/// zlib's level for the blocks: its fastest, greedy one-probe parse.
const ZIP_LEVEL: u8 = 1;

/// One block's chunk: ZIP scan-line blocks compressed here at
/// [`ZIP_LEVEL`], anything else by the exr crate. The steps are
/// OpenEXR's ZIP format (the file layout document, "ZIP compression"):
/// the block's little-endian bytes split into their even and odd bytes,
/// each byte replaced by its difference from the one before plus 128
/// (mod 256), then zlib. A block that does not shrink is stored as it is,
/// which readers tell by its size.
fn compress_block(block: UncompressedBlock, headers: &[Header]) -> exr::error::Result<Chunk> {
    let header = &headers[block.index.layer];
    let zip = matches!(header.compression, Compression::ZIP16 | Compression::ZIP1);
    // Native bytes are the file's little-endian ones only on a
    // little-endian machine; elsewhere the crate converts them.
    if !zip
        || header.blocks != BlockDescription::ScanLines
        || header.deep
        || cfg!(target_endian = "big")
        || block.data.len() != header.channels.bytes_per_pixel * block.index.pixel_size.area()
    {
        return block.compress_to_chunk(headers);
    }
    let raw = block.data;
    let packed = zip_predict(&raw);
    let compressed = miniz_oxide::deflate::compress_to_vec_zlib(&packed, ZIP_LEVEL);
    let y = i32::try_from(block.index.pixel_position.y())
        .map_err(|_| exr::error::Error::Invalid("block line beyond i32".into()))?;
    Ok(Chunk {
        layer_index: block.index.layer,
        compressed_block: CompressedBlock::ScanLine(CompressedScanLineBlock {
            y_coordinate: y + header.own_attributes.layer_position.y(),
            compressed_pixels_le: if compressed.len() < raw.len() {
                compressed
            } else {
                raw
            },
        }),
    })
}

/// OpenEXR's ZIP predictor: the even bytes, then the odd ones, each byte
/// then its difference from the previous plus 128, wrapping.
fn zip_predict(raw: &[u8]) -> Vec<u8> {
    let mut split = Vec::with_capacity(raw.len());
    split.extend(raw.iter().step_by(2));
    split.extend(raw.iter().skip(1).step_by(2));
    let mut previous = split.first().copied().unwrap_or(0);
    for b in split.iter_mut().skip(1) {
        let here = *b;
        *b = here.wrapping_sub(previous).wrapping_add(128);
        previous = here;
    }
    split
}

#[cfg(test)]
mod tests {
    use super::*;
    use exr::prelude::{read, ReadChannels, ReadLayers};

    /// The file's first layer, every channel and attribute, as the exr
    /// crate's reader gives them.
    fn read_back(bytes: Vec<u8>) -> Image<Layer<AnyChannels<FlatSamples>>> {
        read()
            .no_deep_data()
            .largest_resolution_level()
            .all_channels()
            .first_valid_layer()
            .all_attributes()
            .from_buffered(std::io::Cursor::new(bytes))
            .unwrap()
    }

    /// The blocks compressed here read back, through the exr crate's
    /// reader, as the very values written, bit for bit: smooth lines
    /// (which ZIP shrinks) and hashed noise (which it cannot, so they are
    /// stored as they are), in an image of more blocks (16 lines each)
    /// than one window of any pool here holds, placed off the origin. The
    /// bytes are the same on one thread and on three.
    #[test]
    fn blocks_compressed_here_read_back_as_written() {
        let (w, h) = (37u32, 16 * 40 + 5);
        let noisy_from = 16 * 25;
        // Finite floats of 30 random bits (a 32-bit finaliser's mix).
        let noise = |i: u32| {
            let mut v = i.wrapping_mul(0x9E37_79B9);
            v = (v ^ v >> 16).wrapping_mul(0x85EB_CA6B);
            v = (v ^ v >> 13).wrapping_mul(0xC2B2_AE35);
            f32::from_bits((v ^ v >> 16) >> 2)
        };
        let pixels: Vec<glam::Vec3> = (0..w * h)
            .map(|i| {
                let (x, y) = ((i % w) as f32, (i / w) as f32);
                if i / w < noisy_from {
                    glam::Vec3::new(x / 64.0 + y / 1024.0, y / 512.0, (x * 0.37).sin())
                } else {
                    glam::Vec3::new(noise(3 * i), noise(3 * i + 1), noise(3 * i + 2))
                }
            })
            .collect();
        let mut image = ExrImage::rgb(&pixels, w, h);
        image.origin = (3, 2);
        image.display = (50, 700);
        image.attributes.push(("spp".into(), Attribute::Int(4)));
        let ours = image.encode().unwrap();
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
        let back = read_back(ours.clone());
        let layer = &back.layer_data;
        assert_eq!(layer.size, Vec2(w as usize, h as usize));
        assert_eq!(layer.encoding.compression, Compression::ZIP16);
        // Sorted by name: B, G, R.
        for (c, axis) in layer.channel_data.list.iter().zip([2, 1, 0]) {
            for (k, p) in pixels.iter().enumerate() {
                let v = c.sample_data.value_by_flat_index(k).to_f32();
                assert_eq!(v.to_bits(), p[axis].to_bits(), "{} at {k}", c.name);
            }
        }
        // Each block's size: the smooth ones compressed to under half,
        // the noisy ones stored whole (12 bytes a pixel), each at its line.
        let chunks: Vec<Chunk> = exr::block::read(std::io::Cursor::new(ours), true)
            .unwrap()
            .all_chunks(true)
            .unwrap()
            .map(Result::unwrap)
            .collect();
        assert_eq!(chunks.len(), h.div_ceil(16) as usize);
        for (k, chunk) in chunks.iter().enumerate() {
            let CompressedBlock::ScanLine(block) = &chunk.compressed_block else {
                panic!("block {k} is not a scan-line block");
            };
            assert_eq!(block.y_coordinate, 2 + 16 * k as i32);
            let lines = (h - 16 * k as u32).min(16);
            let whole = (12 * w * lines) as usize;
            let size = block.compressed_pixels_le.len();
            if 16 * (k as u32 + 1) <= noisy_from {
                assert!(
                    size < whole / 2,
                    "smooth block {k}: {size} of {whole} bytes"
                );
            } else {
                assert_eq!(size, whole, "noisy block {k} stored whole");
            }
        }
    }

    /// The predictor against its definition, byte by byte, odd lengths too.
    #[test]
    fn zip_predictor_splits_then_differences() {
        assert!(zip_predict(&[]).is_empty());
        assert_eq!(zip_predict(&[7]), [7]);
        let raw = [10u8, 200, 13, 0, 250, 5, 9];
        let split = [10u8, 13, 250, 9, 200, 0, 5];
        let mut want = vec![split[0]];
        for k in 1..split.len() {
            want.push((split[k] as i32 - split[k - 1] as i32 + 128).rem_euclid(256) as u8);
        }
        assert_eq!(zip_predict(&raw), want);
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
        let back = read_back(bytes);
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
