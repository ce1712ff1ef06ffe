//! Partial renders on disk (`.strata`): a slice's (or a checkpoint's) film
//! with everything needed to check that parts belong together.
//!
//! `strata render --slice k/P -o part_k.strata` writes one; `strata merge`
//! sums them; `--checkpoint FILE` writes the same format after every pass,
//! with the sample range done so far. Because film sums are fixed point,
//! merging is exact and order-independent.
//!
//! Layout, all little-endian:
//!
//! | bytes | field |
//! |---|---|
//! | 8 | magic `STRATAPT` |
//! | 4 | format version: 3 (1 and 2, written before, are read as well) |
//! | 2 + n | strata version that wrote it (u16 length, UTF-8) |
//! | 8 | scene fingerprint (`partial::fingerprint`) |
//! | 4 × 8 | width, height, spp, seed, sampler (0 random, 1 stratified, 2 sobol), shadow samples, reflection samples, max depth |
//! | 4 × 3 | slices `first..end` of `count`: a part holds one (`k..k+1`), a merged part a run of them |
//! | 4 × 2 | sample indices `start..end` summed: the slices' samples, or less in an unfinished checkpoint |
//! | 4 × 3 | version 3 only: the display of 8-bit outputs, exposure (f32 stops) and tone curve (0 clamp, 1 filmic), and whether squares follow the pixels (0/1) |
//! | 8 × 2 | invalid samples dropped, samples clamped |
//! | 4 × 4 | first invalid sample: present (0/1), x, y, sample |
//! | 52 × w·h | per pixel, row-major: sums r, g, b as i128 (units of 2⁻³²), valid sample count u32 |
//! | 16 × w·h | version 2, or 3 with squares: per pixel, the sum of squared luminance as i128 (units of 2⁻³²), which a `--noise` render's checkpoint needs |
//! | 8 | checksum: `fingerprint::Hasher64` of every byte before it |
//!
//! Reading checks the magic, the version and the header's numbers, then
//! that the file is exactly as long as the header implies *before*
//! allocating anything (a corrupt header claiming 10¹² pixels allocates
//! nothing), and that its film fits in the machine's memory (a sparse file
//! may have any length), then the checksum.

use super::fingerprint::{scene_fingerprint, Hasher64};
use crate::output::tonemap::Tonemap;
use crate::render::film::{BadSample, Film, FILM_PIXEL_BYTES};
use crate::render::SliceSpec;
use crate::sampling::SamplerKind;
use crate::scene::Scene;
use crate::system::budget::Budget;
use std::io::{Read, Write};
use std::ops::Range;
use std::path::Path;

pub const MAGIC: [u8; 8] = *b"STRATAPT";
/// The version written: version 1 with the display of 8-bit outputs (so
/// that `strata merge` shows the film as `strata render` would) and a flag
/// for the squares.
pub const FORMAT_VERSION: u32 = 3;
/// Read only: the first version, without display or squares.
const FORMAT_VERSION_PLAIN: u32 = 1;
/// Read only: version 1 followed by the squares (`Film::squares`, a
/// `--noise` render's).
const FORMAT_VERSION_SQUARES: u32 = 2;
/// Bytes per pixel record: three i128 sums and a u32 count, as in memory.
pub const PIXEL_BYTES: u64 = FILM_PIXEL_BYTES;
const MAX_VERSION_BYTES: usize = 256;

/// What a partial file says about the render it belongs to.
#[derive(Debug, Clone, PartialEq)]
pub struct PartialHeader {
    /// The strata build that wrote the file ([`crate::VERSION`]).
    pub strata_version: String,
    pub scene_hash: u64,
    pub width: u32,
    pub height: u32,
    pub spp: u32,
    pub seed: u32,
    pub sampler: SamplerKind,
    pub shadow_samples: u32,
    pub reflection_samples: u32,
    pub max_depth: u32,
    /// Slices `first..end` of `slice_count`.
    pub slices: Range<u32>,
    pub slice_count: u32,
    /// Sample indices whose sums the file holds.
    pub samples: Range<u32>,
    /// How 8-bit outputs show the film ([render] exposure, in stops): not
    /// part of the film, but what an image merged from it shows.
    pub exposure: f32,
    /// The tone curve of 8-bit outputs ([render] tonemap).
    pub tonemap: Tonemap,
}

/// A header and its film.
#[derive(Debug, Clone, PartialEq)]
pub struct Partial {
    pub header: PartialHeader,
    pub film: Film,
}

impl PartialHeader {
    /// The header of `scene`'s render of `slice`, holding `samples`.
    pub fn for_scene(scene: &Scene, slice: SliceSpec, samples: Range<u32>) -> Self {
        let s = &scene.settings;
        Self {
            strata_version: crate::VERSION.to_string(),
            scene_hash: scene_fingerprint(scene),
            width: s.width,
            height: s.height,
            spp: s.spp,
            seed: s.seed,
            sampler: s.sampler,
            shadow_samples: s.shadow_samples,
            reflection_samples: s.reflection_samples,
            max_depth: s.max_depth,
            slices: slice.index..slice.index + 1,
            slice_count: slice.count,
            samples,
            exposure: s.exposure,
            tonemap: s.tonemap,
        }
    }

    /// Check that a checkpoint with this header continues the render that
    /// `expected` describes (same render, same slice, and, unless `force`,
    /// the same build), and return the end of the samples it has done.
    pub fn resume_point(&self, expected: &PartialHeader, force: bool) -> Result<u32, String> {
        if let (false, Some(m)) = (force, self.build_mismatch(expected)) {
            return Err(m);
        }
        if let Some(m) = self.render_mismatch(expected) {
            let same_but_spp = PartialHeader {
                spp: expected.spp,
                ..self.clone()
            };
            if same_but_spp.render_mismatch(expected).is_none() {
                return Err(self.other_spp(expected.spp));
            }
            return Err(format!(
                "the checkpoint is of a different render: {m} (checkpoint vs now)"
            ));
        }
        if self.slices != expected.slices {
            return Err(format!(
                "the checkpoint is of slice {}, this render is slice {}",
                self.slices_text(),
                expected.slices_text()
            ));
        }
        Ok(self.samples.end)
    }

    /// Why a checkpoint of this render cannot be taken on to `spp`
    /// samples per pixel, and what to do instead. A render's samples are
    /// indices into each pixel's one stratified set of spp samples (see
    /// [`SliceSpec`]), whose points all depend on spp, so the first 64
    /// samples of a 128-spp render are not a 64-spp render: another spp is
    /// a new render, which `--slice` can plan ahead for. (The random
    /// sampler's numbers do not depend on spp, but parts record their spp
    /// and merge only with their own.)
    fn other_spp(&self, spp: u32) -> String {
        let (have, want) = (self.spp, spp);
        let now = if self.is_complete() {
            format!("it is finished, and strata merge on it writes its {have}-spp image")
        } else {
            format!("pass --spp {have} to finish it")
        };
        // Slice 0 of P holds the first have samples of the larger set
        // when want is a multiple of have.
        let parts = if want % have == 0 { want / have } else { 2 };
        let plan = if want > have && self.slice_count == 1 {
            format!(
                ". To be able to stop at {have} and add samples later, render the larger count in slices: --spp {want} --slice 0/{parts} -o part_0.strata first (strata merge --partial part_0.strata -o preview.png shows it), the other slices of {parts} later, then strata merge part_*.strata -o final.exr"
            )
        } else {
            String::new()
        };
        let why = match self.sampler {
            SamplerKind::Stratified => format!(
                "each pixel's samples are one stratified set of spp samples, so the first {have} of a {want}-spp render are not this render's {have}"
            ),
            SamplerKind::Random | SamplerKind::Sobol => {
                "a checkpoint continues, and a part merges with, renders of its own spp only"
                    .to_string()
            }
        };
        format!(
            "the checkpoint is of a {have}-spp render and this one asks for {want}, which is a new render: {why}; {now}, and another --checkpoint file starts the {want}-spp render{plan}"
        )
    }

    /// The samples that the slices `slices` of `slice_count` cover.
    pub fn slice_samples(&self) -> Range<u32> {
        let lo = SliceSpec {
            index: self.slices.start,
            count: self.slice_count,
        }
        .samples(self.spp);
        let hi = SliceSpec {
            index: self.slices.end - 1,
            count: self.slice_count,
        }
        .samples(self.spp);
        lo.start..hi.end
    }

    /// Whether every sample of its slices is in (not an unfinished checkpoint).
    pub fn is_complete(&self) -> bool {
        self.samples == self.slice_samples()
    }

    /// Slices as text: `3/8`, or `0-3/8` for a merged run.
    pub fn slices_text(&self) -> String {
        if self.slices.len() == 1 {
            format!("{}/{}", self.slices.start, self.slice_count)
        } else {
            format!(
                "{}-{}/{}",
                self.slices.start,
                self.slices.end - 1,
                self.slice_count
            )
        }
    }

    /// Why `self` and `other` may not mix though they describe the same
    /// render: they were written by different builds of strata, whose
    /// samples need not agree bit for bit.
    pub fn build_mismatch(&self, other: &PartialHeader) -> Option<String> {
        (self.strata_version != other.strata_version).then(|| {
            format!(
                "written by strata {}, not {}: samples of different builds need not agree; rerun it with this build, or pass --force to use it anyway",
                self.strata_version, other.strata_version
            )
        })
    }

    /// The first way in which `self` belongs to a different render than
    /// `other` (ignoring which slices and samples each holds, and which
    /// build wrote it), as "what: mine vs theirs".
    pub fn render_mismatch(&self, other: &PartialHeader) -> Option<String> {
        // The settings first, the scene's fingerprint (which covers the
        // camera, and so the resolution too) last: a part of another size
        // is told its size, not a hash.
        let pairs: [(&str, String, String); 9] = [
            (
                "resolution",
                format!("{}x{}", self.width, self.height),
                format!("{}x{}", other.width, other.height),
            ),
            ("spp", self.spp.to_string(), other.spp.to_string()),
            ("seed", self.seed.to_string(), other.seed.to_string()),
            (
                "sampler",
                format!("{:?}", self.sampler).to_lowercase(),
                format!("{:?}", other.sampler).to_lowercase(),
            ),
            (
                "shadow samples",
                self.shadow_samples.to_string(),
                other.shadow_samples.to_string(),
            ),
            (
                "reflection samples",
                self.reflection_samples.to_string(),
                other.reflection_samples.to_string(),
            ),
            (
                "max depth",
                self.max_depth.to_string(),
                other.max_depth.to_string(),
            ),
            (
                "slice count P",
                self.slice_count.to_string(),
                other.slice_count.to_string(),
            ),
            (
                "scene (fingerprint of geometry, materials, lights, camera)",
                format!("{:016x}", self.scene_hash),
                format!("{:016x}", other.scene_hash),
            ),
        ];
        pairs
            .into_iter()
            .find(|(_, a, b)| a != b)
            .map(|(what, a, b)| format!("{what}: {a} vs {b}"))
    }

    /// The header as `version` writes it, for a film with `squares` or
    /// without.
    fn header_bytes(&self, version: u32, squares: bool) -> Vec<u8> {
        let mut b = Vec::with_capacity(128);
        b.extend_from_slice(&MAGIC);
        b.extend_from_slice(&version.to_le_bytes());
        let v = self.strata_version.as_bytes();
        let v = &v[..v.len().min(MAX_VERSION_BYTES)];
        b.extend_from_slice(&(v.len() as u16).to_le_bytes());
        b.extend_from_slice(v);
        b.extend_from_slice(&self.scene_hash.to_le_bytes());
        let sampler = match self.sampler {
            SamplerKind::Random => 0u32,
            SamplerKind::Stratified => 1,
            SamplerKind::Sobol => 2,
        };
        for x in [
            self.width,
            self.height,
            self.spp,
            self.seed,
            sampler,
            self.shadow_samples,
            self.reflection_samples,
            self.max_depth,
            self.slices.start,
            self.slices.end,
            self.slice_count,
            self.samples.start,
            self.samples.end,
        ] {
            b.extend_from_slice(&x.to_le_bytes());
        }
        if version == FORMAT_VERSION {
            let tonemap = match self.tonemap {
                Tonemap::Clamp => 0u32,
                Tonemap::Filmic => 1,
            };
            for x in [self.exposure.to_bits(), tonemap, squares as u32] {
                b.extend_from_slice(&x.to_le_bytes());
            }
        }
        b
    }
}

/// A writer that hashes what passes through it.
struct HashingWriter<W: Write> {
    inner: W,
    hash: Hasher64,
}

impl<W: Write> Write for HashingWriter<W> {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        let n = self.inner.write(buf)?;
        self.hash.write(&buf[..n]);
        Ok(n)
    }
    fn flush(&mut self) -> std::io::Result<()> {
        self.inner.flush()
    }
}

/// Serialise a header and its film into `w`.
pub fn write_partial_to(
    w: &mut impl Write,
    header: &PartialHeader,
    film: &Film,
) -> std::io::Result<()> {
    write_version(w, header, film, FORMAT_VERSION)
}

/// [`write_partial_to`] in format `version` (older ones for the tests
/// that read them).
fn write_version(
    w: &mut impl Write,
    header: &PartialHeader,
    film: &Film,
    version: u32,
) -> std::io::Result<()> {
    assert_eq!((header.width, header.height), (film.width, film.height));
    let mut w = HashingWriter {
        inner: w,
        hash: Hasher64::new(),
    };
    let squares = !film.squares.is_empty();
    debug_assert!(version != FORMAT_VERSION_PLAIN || !squares);
    w.write_all(&header.header_bytes(version, squares))?;
    w.write_all(&film.invalid.to_le_bytes())?;
    w.write_all(&film.clamped.to_le_bytes())?;
    let bad = film.first_invalid;
    for x in [
        bad.is_some() as u32,
        bad.map_or(0, |b| b.x),
        bad.map_or(0, |b| b.y),
        bad.map_or(0, |b| b.sample),
    ] {
        w.write_all(&x.to_le_bytes())?;
    }
    let mut record = [0u8; PIXEL_BYTES as usize];
    for (sum, count) in film.sums.iter().zip(&film.counts) {
        for (c, v) in sum.iter().enumerate() {
            record[16 * c..16 * c + 16].copy_from_slice(&v.to_le_bytes());
        }
        record[48..52].copy_from_slice(&count.to_le_bytes());
        w.write_all(&record)?;
    }
    for q in &film.squares {
        w.write_all(&q.to_le_bytes())?;
    }
    let checksum = w.hash.finish();
    w.inner.write_all(&checksum.to_le_bytes())
}

/// Write a partial file atomically (temporary file, then rename): a kill
/// during the write leaves the previous file intact.
pub fn write_partial(path: &Path, header: &PartialHeader, film: &Film) -> std::io::Result<()> {
    crate::output::atomic::write_atomic(path, |w| write_partial_to(w, header, film))
}

/// Reads fields in order, hashing them, and names truncation.
struct FieldReader<R: Read> {
    inner: R,
    hash: Hasher64,
}

impl<R: Read> FieldReader<R> {
    fn bytes<const N: usize>(&mut self) -> Result<[u8; N], String> {
        let mut b = [0u8; N];
        self.inner.read_exact(&mut b).map_err(|e| {
            if e.kind() == std::io::ErrorKind::UnexpectedEof {
                "truncated: the file ends inside its header".to_string()
            } else {
                format!("cannot read: {e}")
            }
        })?;
        self.hash.write(&b);
        Ok(b)
    }
    fn u32(&mut self) -> Result<u32, String> {
        Ok(u32::from_le_bytes(self.bytes()?))
    }
    fn u64(&mut self) -> Result<u64, String> {
        Ok(u64::from_le_bytes(self.bytes()?))
    }
}

/// Read and verify a partial file. The error is one line, without the path.
pub fn read_partial(path: &Path) -> Result<Partial, String> {
    let file = std::fs::File::open(path).map_err(|e| format!("cannot open: {e}"))?;
    let file_len = file
        .metadata()
        .map_err(|e| format!("cannot read: {e}"))?
        .len();
    read_partial_from(std::io::BufReader::new(file), file_len)
}

/// Read and verify a partial of `file_len` bytes from `r`.
pub fn read_partial_from(r: impl Read, file_len: u64) -> Result<Partial, String> {
    read_within(r, file_len, Budget::of_this_process())
}

/// [`read_partial_from`] whose film must fit in `budget`.
fn read_within(r: impl Read, file_len: u64, budget: Option<Budget>) -> Result<Partial, String> {
    let mut r = FieldReader {
        inner: r,
        hash: Hasher64::new(),
    };
    let not_partial = "not a strata partial file (no STRATAPT magic)";
    if file_len < MAGIC.len() as u64 {
        return Err(not_partial.to_string());
    }
    if r.bytes::<8>()? != MAGIC {
        return Err(not_partial.to_string());
    }
    let version = r.u32()?;
    if ![FORMAT_VERSION_PLAIN, FORMAT_VERSION_SQUARES, FORMAT_VERSION].contains(&version) {
        return Err(format!(
            "partial format version {version}; this strata reads versions 1 to {FORMAT_VERSION}"
        ));
    }
    let vlen = u16::from_le_bytes(r.bytes()?) as usize;
    if vlen > MAX_VERSION_BYTES {
        return Err(format!("corrupt header: version string of {vlen} bytes"));
    }
    let mut vbytes = Vec::with_capacity(vlen);
    for _ in 0..vlen {
        vbytes.push(r.bytes::<1>()?[0]);
    }
    let strata_version = String::from_utf8(vbytes)
        .map_err(|_| "corrupt header: version string is not UTF-8".to_string())?;
    let scene_hash = r.u64()?;
    let mut f = [0u32; 13];
    for x in &mut f {
        *x = r.u32()?;
    }
    let [width, height, spp, seed, sampler, shadow_samples, reflection_samples, max_depth, s0, s1, slice_count, n0, n1] =
        f;
    let sampler = match sampler {
        0 => SamplerKind::Random,
        1 => SamplerKind::Stratified,
        2 => SamplerKind::Sobol,
        other => return Err(format!("corrupt header: sampler {other}")),
    };
    // Versions 1 and 2 were written before the display was kept: they show
    // the film as the defaults do.
    let (exposure, tonemap, squares) = if version == FORMAT_VERSION {
        let [exposure, tonemap, squares] = [r.u32()?, r.u32()?, r.u32()?];
        let exposure = f32::from_bits(exposure);
        if !exposure.is_finite() {
            return Err(format!("corrupt header: exposure {exposure}"));
        }
        let tonemap = match tonemap {
            0 => Tonemap::Clamp,
            1 => Tonemap::Filmic,
            other => return Err(format!("corrupt header: tone curve {other}")),
        };
        if squares > 1 {
            return Err(format!("corrupt header: squares flag {squares}"));
        }
        (exposure, tonemap, squares == 1)
    } else {
        (0.0, Tonemap::Clamp, version == FORMAT_VERSION_SQUARES)
    };
    let header = PartialHeader {
        strata_version,
        scene_hash,
        width,
        height,
        spp,
        seed,
        sampler,
        shadow_samples,
        reflection_samples,
        max_depth,
        slices: s0..s1,
        slice_count,
        samples: n0..n1,
        exposure,
        tonemap,
    };
    // No render makes an image of no pixels or past MAX_SIDE on a side.
    let max = crate::scene::settings::MAX_SIDE;
    if width == 0 || height == 0 || width > max || height > max {
        return Err(format!("corrupt header: image size {width}x{height}"));
    }
    if slice_count == 0 || s0 >= s1 || s1 > slice_count {
        return Err(format!(
            "corrupt header: slices {s0}..{s1} of {slice_count}"
        ));
    }
    let covered = header.slice_samples();
    if n0 != covered.start || n1 < n0 || n1 > covered.end {
        return Err(format!(
            "corrupt header: samples {n0}..{n1} outside slices' {}..{}",
            covered.start, covered.end
        ));
    }
    let invalid = r.u64()?;
    let clamped = r.u64()?;
    let [has_bad, bx, by, bs] = [r.u32()?, r.u32()?, r.u32()?, r.u32()?];
    let first_invalid = (has_bad != 0).then_some(BadSample {
        x: bx,
        y: by,
        sample: bs,
    });

    // Check the length before allocating: the header may be garbage.
    let display_len = if version == FORMAT_VERSION { 3 * 4 } else { 0 };
    let head_len = (8 + 4 + 2 + vlen + 8 + 13 * 4 + display_len + 2 * 8 + 4 * 4) as u128;
    let pixels = width as u128 * height as u128;
    let square_bytes = if squares { 16 } else { 0 };
    let expected = head_len + pixels * (PIXEL_BYTES + square_bytes) as u128 + 8;
    if (file_len as u128) < expected {
        return Err(format!(
            "truncated: {file_len} bytes, but a {width}x{height} partial needs {expected}"
        ));
    }
    if file_len as u128 > expected {
        return Err(format!(
            "corrupt: {file_len} bytes, but a {width}x{height} partial has {expected}"
        ));
    }

    // The length may be a sparse file's: the film is weighed against the
    // machine's memory, and made where a failure is an error.
    let need = pixels * u128::from(FILM_PIXEL_BYTES + square_bytes);
    let per_pixel = FILM_PIXEL_BYTES + square_bytes;
    let what = format_args!("its {width}×{height} film ({per_pixel} bytes a pixel)");
    crate::system::budget::check_against(budget, need, what)?;
    let mut film = Film::try_new(width, height)?;
    film.invalid = invalid;
    film.clamped = clamped;
    film.first_invalid = first_invalid;
    for i in 0..pixels as usize {
        let rec: [u8; PIXEL_BYTES as usize] = r.bytes().map_err(|_| {
            "truncated: the file ends inside its pixels (did it shrink while read?)".to_string()
        })?;
        for c in 0..3 {
            film.sums[i][c] = i128::from_le_bytes(rec[16 * c..16 * c + 16].try_into().unwrap());
        }
        film.counts[i] = u32::from_le_bytes(rec[48..52].try_into().unwrap());
    }
    if squares {
        film.track_squares();
        for q in &mut film.squares {
            *q = i128::from_le_bytes(r.bytes().map_err(|_| {
                "truncated: the file ends inside its squares (did it shrink while read?)"
                    .to_string()
            })?);
        }
    }
    let computed = r.hash.finish();
    let mut stored = [0u8; 8];
    r.inner
        .read_exact(&mut stored)
        .map_err(|_| "truncated: the checksum is missing".to_string())?;
    if u64::from_le_bytes(stored) != computed {
        return Err("checksum mismatch: the file is corrupt".to_string());
    }
    Ok(Partial { header, film })
}

#[cfg(test)]
mod tests;
