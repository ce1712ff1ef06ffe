//! Per-pixel sums in fixed point.
//!
//! Each sample's radiance is rounded to a multiple of 2⁻³² and added as an
//! integer. Integer addition is associative, so the sum — and the image —
//! is bit-identical however the samples are split over threads, passes,
//! processes or resumed checkpoints, and in whatever order parts are merged.
//! (Floating-point sums would depend on the order.) The rounding, 2.3e-10
//! absolute, is far below what any output format stores. i128 leaves room
//! for 2⁴⁸ per sample (values above are clamped and counted) times 2⁴⁷ samples.

use super::window::Window;
use glam::Vec3;

pub const FIXED_SCALE: f64 = 4_294_967_296.0; // 2^32

/// A fixed-point sum as f64, the same value `x as f64` gives: through i64
/// where it fits (one instruction, against a library call of some 25
/// cycles for i128), as every sum under 2³¹ does (two billion samples of
/// radiance 1). Noise decisions convert four sums a pixel.
#[inline]
pub fn fixed_to_f64(x: i128) -> f64 {
    match i64::try_from(x) {
        Ok(small) => small as f64,
        Err(_) => wide_to_f64(x),
    }
}

/// `x as f64` out of line: inlined, the optimizer saw that both of
/// [`fixed_to_f64`]'s arms compute `x as f64` and kept only the library
/// call, on every sum.
#[inline(never)]
fn wide_to_f64(x: i128) -> f64 {
    x as f64
}

/// Largest radiance one sample may carry before it is clamped.
pub const MAX_SAMPLE_VALUE: f64 = 281_474_976_710_656.0; // 2^48

/// Where a sample went wrong, for the report and for `--debug-sample`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct BadSample {
    pub x: u32,
    pub y: u32,
    pub sample: u32,
}

#[derive(Debug, Clone, PartialEq)]
pub struct Film {
    pub width: u32,
    pub height: u32,
    pub sums: Vec<[i128; 3]>,
    pub counts: Vec<u32>,
    /// Per pixel, the sum of its samples' squared luminance, in the same
    /// fixed point: what a `--noise` render estimates each pixel's error
    /// from (`render::adaptive`). Empty, and never added to, in a render
    /// without a noise target ([`Film::track_squares`]).
    pub squares: Vec<i128>,
    /// Samples dropped for NaN, infinity or negative values.
    pub invalid: u64,
    pub first_invalid: Option<BadSample>,
    /// Samples clamped at [`MAX_SAMPLE_VALUE`].
    pub clamped: u64,
}

/// One pixel's accumulator, owned by one worker at a time.
#[derive(Debug, Clone, Copy, Default)]
pub struct PixelSum {
    pub sum: [i128; 3],
    /// The sum of the samples' squared luminance ([`luminance`]).
    pub square: i128,
    pub count: u32,
    pub invalid: u32,
    pub first_invalid: Option<u32>,
    pub clamped: u32,
}

impl PixelSum {
    #[inline]
    pub fn add(&mut self, value: Vec3, sample: u32) {
        if !value.is_finite() || value.min_element() < 0.0 {
            self.invalid += 1;
            self.first_invalid.get_or_insert(sample);
            return;
        }
        for c in 0..3 {
            let mut v = value[c];
            if v as f64 > MAX_SAMPLE_VALUE {
                v = MAX_SAMPLE_VALUE as f32;
                self.clamped += 1;
            }
            self.sum[c] += fixed(v);
        }
        // What the noise target's estimate needs: Y² per sample, in the
        // film's fixed point (Y² at most 2⁴⁸ here, for the sum's room).
        let y = luminance(value.min(Vec3::splat(MAX_SAMPLE_VALUE as f32)));
        self.square += fixed((y * y).min(MAX_SAMPLE_VALUE as f32));
        self.count += 1;
    }
}

/// Adds one pixel's accumulator to its sums, count and (where kept) sum
/// of squares.
#[inline]
fn fold(sums: &mut [i128; 3], count: &mut u32, square: Option<&mut i128>, p: &PixelSum) {
    for (s, add) in sums.iter_mut().zip(p.sum) {
        *s += add;
    }
    *count += p.count;
    if let Some(q) = square {
        *q += p.square;
    }
}

/// What samples lost: those dropped (NaN, infinite or negative) and
/// those clamped at [`MAX_SAMPLE_VALUE`].
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Losses {
    pub invalid: u64,
    /// The first dropped sample in (row, column, sample) order.
    pub first_invalid: Option<BadSample>,
    pub clamped: u64,
}

impl Losses {
    /// Counts in what pixel `index` (of an image `width` wide) lost.
    fn note(&mut self, index: usize, width: u32, p: &PixelSum) {
        self.clamped += p.clamped as u64;
        if p.invalid > 0 {
            let bad = BadSample {
                x: index as u32 % width,
                y: index as u32 / width,
                sample: p.first_invalid.unwrap_or(0),
            };
            self.merge_in(p.invalid as u64, Some(bad));
        }
    }

    /// Both parts' losses. The first dropped sample is the earlier in
    /// (row, column, sample) order whichever part it came from, so the
    /// sum of many parts does not depend on the order they are added in.
    pub fn merge(mut self, other: Self) -> Self {
        self.clamped += other.clamped;
        self.merge_in(other.invalid, other.first_invalid);
        self
    }

    fn merge_in(&mut self, invalid: u64, first: Option<BadSample>) {
        self.invalid += invalid;
        if let Some(b) = first {
            let key = |f: BadSample| (f.y, f.x, f.sample);
            if self.first_invalid.is_none_or(|f| key(f) > key(b)) {
                self.first_invalid = Some(b);
            }
        }
    }
}

/// A run of a film's consecutive pixels ([`Film::runs_mut`]), which one
/// worker adds its pixels' samples to while others add to theirs.
#[derive(Debug)]
pub struct FilmRun<'a> {
    /// The index of the run's first pixel in the film.
    first: usize,
    width: u32,
    sums: &'a mut [[i128; 3]],
    counts: &'a mut [u32],
    /// Empty where the film keeps no squares.
    squares: &'a mut [i128],
    /// What the samples added so far lost.
    pub losses: Losses,
}

impl FilmRun<'_> {
    /// The run's pixels.
    pub fn len(&self) -> usize {
        self.counts.len()
    }

    /// Whether the run has no pixels.
    pub fn is_empty(&self) -> bool {
        self.counts.is_empty()
    }

    /// Fold the accumulator of the run's pixel `k` in.
    #[inline]
    pub fn add_pixel(&mut self, k: usize, p: &PixelSum) {
        fold(
            &mut self.sums[k],
            &mut self.counts[k],
            self.squares.get_mut(k),
            p,
        );
        self.losses.note(self.first + k, self.width, p);
    }
}

/// Rec. 709 luminance Y of linear RGB (ITU-R BT.709 primaries): the one
/// number a pixel's noise is judged by.
#[inline]
pub fn luminance(c: Vec3) -> f32 {
    let [r, g, b] = LUMINANCE;
    r as f32 * c.x + g as f32 * c.y + b as f32 * c.z
}

/// The weights of [`luminance`].
pub const LUMINANCE: [f64; 3] = [0.2126, 0.7152, 0.0722];

/// `(v · 2³²).round() as i128` for a float `v` in [0, [`MAX_SAMPLE_VALUE`]],
/// from its bits, in integers: v = m · 2^e with a 24-bit m, so v · 2³² is
/// m shifted left by e + 32, or shifted right with the half added first
/// (rounding half up, which for v ≥ 0 is `round`'s half away from zero).
/// Through f64 this took two saturating f64 → i64 conversions and a
/// rounding per channel, with their range checks, which were most of the
/// film's cost (docs/mitsuba.md, "What was tried for the render").
#[inline]
fn fixed(v: f32) -> i128 {
    let bits = v.to_bits() & 0x7fff_ffff;
    let biased = (bits >> 23) as i32;
    let fraction = bits & 0x7f_ffff;
    // Subnormals have no implicit bit and the exponent of the smallest normal.
    let (m, shift) = if biased == 0 {
        (fraction, 32 - 149)
    } else {
        (fraction | 0x80_0000, biased - 150 + 32)
    };
    if shift >= 0 {
        (m as i128) << shift
    } else {
        // Beyond 25 places right every 24-bit m rounds to 0.
        let k = (-shift).min(40) as u32;
        ((m as u64 + (1u64 << (k - 1))) >> k) as i128
    }
}

/// Bytes of each pixel's record in a film: three i128 sums and a u32 count.
pub const FILM_PIXEL_BYTES: u64 = (size_of::<[i128; 3]>() + size_of::<u32>()) as u64;

/// Bytes a render holds at once per pixel of its window: the film's sums
/// (a pass's, [`PixelSum`], are held a work item at a time); with `aovs`,
/// their sums ([`AovSum`](super::aov::AovSum)) and seven channels of f32,
/// made and encoded; with `image`, the image made from the film (linear RGB, its
/// channels or 8-bit texels, and its encoding), which a `.strata` output
/// streams instead. What [`check_memory`] weighs.
pub fn render_bytes_per_pixel(aovs: bool, image: bool) -> u64 {
    let sums = FILM_PIXEL_BYTES;
    let rgb = size_of::<Vec3>() as u64;
    let aov = size_of::<super::aov::AovSum>() as u64 + rgb + 2 * 7 * 4;
    sums + if aovs { aov } else { 0 } + if image { 3 * rgb } else { 0 }
}

/// Whether a render of a `width` × `height` window fits in this process's
/// memory ([`crate::system::budget`]), before its film is allocated: the
/// message says the image, its bytes and the machine's memory.
pub fn check_memory(width: u32, height: u32, aovs: bool, image: bool) -> Result<(), String> {
    let per_pixel = render_bytes_per_pixel(aovs, image);
    let need = u128::from(width) * u128::from(height) * u128::from(per_pixel);
    let what = if aovs {
        "its sums, AOVs and image"
    } else if image {
        "its sums and image"
    } else {
        "its sums"
    };
    crate::system::budget::check(
        need,
        format_args!("a {width}×{height} image ({per_pixel} bytes a pixel: {what})"),
    )
}

impl Film {
    pub fn new(width: u32, height: u32) -> Self {
        let n = width as usize * height as usize;
        Self {
            width,
            height,
            sums: vec![[0; 3]; n],
            counts: vec![0; n],
            squares: Vec::new(),
            invalid: 0,
            first_invalid: None,
            clamped: 0,
        }
    }

    /// [`Film::new`], or an error where its memory cannot be had (an
    /// allocation failure is an error, never an abort).
    pub fn try_new(width: u32, height: u32) -> Result<Self, String> {
        let n = width as usize * height as usize;
        let what = format!("the film of a {width}×{height} image");
        Ok(Self {
            width,
            height,
            sums: crate::system::budget::try_filled(n, [0; 3], &what)?,
            counts: crate::system::budget::try_filled(n, 0, &what)?,
            squares: Vec::new(),
            invalid: 0,
            first_invalid: None,
            clamped: 0,
        })
    }

    pub fn pixel_count(&self) -> usize {
        self.sums.len()
    }

    /// The film of window `inner`, cut from this film of window `outer`
    /// (which holds it). The counts of invalid and clamped samples are the
    /// whole film's: they are not kept per pixel; the first invalid one is
    /// kept only if it lies inside `inner`.
    pub fn cut(&self, outer: &Window, inner: &Window) -> Film {
        let (dx, dy) = (inner.x.start - outer.x.start, inner.y.start - outer.y.start);
        let first_invalid = self.first_invalid.and_then(|b| {
            let (x, y) = (b.x.checked_sub(dx)?, b.y.checked_sub(dy)?);
            (x < inner.width() && y < inner.height()).then_some(BadSample { x, y, ..b })
        });
        Film {
            width: inner.width(),
            height: inner.height(),
            sums: outer.cut(inner, &self.sums),
            counts: outer.cut(inner, &self.counts),
            squares: if self.squares.is_empty() {
                Vec::new()
            } else {
                outer.cut(inner, &self.squares)
            },
            invalid: self.invalid,
            first_invalid,
            clamped: self.clamped,
        }
    }

    /// Keep each pixel's sum of squared luminance from now on (zero for
    /// the samples already in): a `--noise` render's films do.
    pub fn track_squares(&mut self) {
        if self.squares.is_empty() {
            self.squares = vec![0; self.pixel_count()];
        }
    }

    /// The sum of pixel `index`'s squared luminance, in units of 2⁻³²
    /// (0 where the film keeps none).
    pub fn square(&self, index: usize) -> i128 {
        self.squares.get(index).copied().unwrap_or(0)
    }

    /// Fold one pixel's accumulator in.
    pub fn add_pixel(&mut self, index: usize, p: &PixelSum) {
        let square = self.squares.get_mut(index);
        fold(&mut self.sums[index], &mut self.counts[index], square, p);
        let mut losses = Losses::default();
        losses.note(index, self.width, p);
        self.add_losses(losses);
    }

    /// The film in runs of `len` consecutive pixels (the last shorter),
    /// for workers to add their pixels to at once; what each run's samples
    /// lost comes back through [`Film::add_losses`].
    pub fn runs_mut(&mut self, len: usize) -> Vec<FilmRun<'_>> {
        let len = len.max(1);
        let width = self.width;
        let mut squares = self.squares.chunks_mut(len);
        self.sums
            .chunks_mut(len)
            .zip(self.counts.chunks_mut(len))
            .enumerate()
            .map(|(k, (sums, counts))| FilmRun {
                first: k * len,
                width,
                sums,
                counts,
                squares: squares.next().unwrap_or_default(),
                losses: Losses::default(),
            })
            .collect()
    }

    /// What the film's samples lost.
    pub fn losses(&self) -> Losses {
        Losses {
            invalid: self.invalid,
            first_invalid: self.first_invalid,
            clamped: self.clamped,
        }
    }

    /// Count in what another part of the render's samples lost.
    pub fn add_losses(&mut self, other: Losses) {
        let all = self.losses().merge(other);
        (self.invalid, self.first_invalid, self.clamped) =
            (all.invalid, all.first_invalid, all.clamped);
    }

    /// Add another film of the same size (another slice of the same render).
    pub fn merge(&mut self, other: &Film) {
        assert_eq!((self.width, self.height), (other.width, other.height));
        for i in 0..self.sums.len() {
            for c in 0..3 {
                self.sums[i][c] += other.sums[i][c];
            }
            self.counts[i] += other.counts[i];
        }
        // Squares are kept only where both parts kept them.
        if other.squares.len() == self.squares.len() {
            for (q, o) in self.squares.iter_mut().zip(&other.squares) {
                *q += o;
            }
        } else {
            self.squares.clear();
        }
        self.add_losses(other.losses());
    }

    /// Mean radiance of pixel `index` (black if it has no valid sample).
    pub fn mean(&self, index: usize) -> Vec3 {
        let n = self.counts[index];
        if n == 0 {
            return Vec3::ZERO;
        }
        let s = &self.sums[index];
        let k = 1.0 / (FIXED_SCALE * n as f64);
        Vec3::new(
            (fixed_to_f64(s[0]) * k) as f32,
            (fixed_to_f64(s[1]) * k) as f32,
            (fixed_to_f64(s[2]) * k) as f32,
        )
    }

    /// Linear RGB, row-major from the top-left pixel.
    pub fn to_rgb(&self) -> Vec<Vec3> {
        (0..self.pixel_count()).map(|i| self.mean(i)).collect()
    }

    /// Valid samples per pixel, on average over the image.
    pub fn mean_samples(&self) -> f64 {
        let total: u64 = self.counts.iter().map(|&c| c as u64).sum();
        total as f64 / self.pixel_count().max(1) as f64
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A sum as f64 is `x as f64`, bit for bit, through i64 and out of
    /// line alike: at both ends of i64, just past them, at halves of the
    /// last place of large values, and at the ends of i128.
    #[test]
    fn fixed_sums_convert_as_the_direct_cast_does() {
        let mut values = vec![0i128, 1, -1, i128::MAX, i128::MIN, i128::MIN + 1];
        for edge in [i64::MAX as i128, i64::MIN as i128] {
            values.extend((-3..=3).map(|d| edge + d));
        }
        for shift in 53..126 {
            let base = 1i128 << shift;
            // Just below, at and just above half a unit in the last place.
            let half = 1i128 << (shift - 53);
            for x in [
                base + half - 1,
                base + half,
                base + half + 1,
                base + 3 * half,
            ] {
                values.extend([x, -x]);
            }
        }
        for x in values {
            assert_eq!(fixed_to_f64(x).to_bits(), (x as f64).to_bits(), "{x}");
        }
    }

    /// The integer conversion is the direct one through f64, bit for bit,
    /// at halves of the last place, subnormals, the top of the range and
    /// on random floats.
    #[test]
    fn fixed_point_conversion_matches_the_direct_one() {
        let direct = |v: f32| (v as f64 * FIXED_SCALE).round() as i128;
        let mut cases = vec![
            0.0f32,
            -0.0,
            (0.5 / FIXED_SCALE) as f32,
            (1.5 / FIXED_SCALE) as f32,
            (2.5 / FIXED_SCALE) as f32,
            (0.75 / FIXED_SCALE) as f32,
            (0.25 / FIXED_SCALE) as f32,
            f32::MIN_POSITIVE,
            f32::from_bits(1),
            f32::from_bits(0x7f_ffff),
            1.0,
            12345.678,
            MAX_SAMPLE_VALUE as f32,
            1e14,
        ];
        let mut x = 0x9e37_79b9_7f4a_7c15u64;
        for _ in 0..200_000 {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            let v = f32::from_bits((x as u32) & 0x7fff_ffff);
            if v.is_finite() && v as f64 <= MAX_SAMPLE_VALUE {
                cases.push(v);
                // Values whose last places fall on a half of 2⁻³².
                cases.push(f32::from_bits(0x2f80_0000 | (x as u32 >> 9)));
            }
        }
        for v in cases {
            assert_eq!(fixed(v), direct(v), "{v:e}");
        }
    }

    #[test]
    fn sums_do_not_depend_on_order_or_split() {
        let values: Vec<Vec3> = (0..1000)
            .map(|i| Vec3::splat(((i * 7919) % 1000) as f32 * 0.001 + 1e-7))
            .collect();
        let mut forward = PixelSum::default();
        values
            .iter()
            .enumerate()
            .for_each(|(i, v)| forward.add(*v, i as u32));
        let mut a = PixelSum::default();
        let mut b = PixelSum::default();
        for (i, v) in values.iter().enumerate().rev() {
            if i % 3 == 0 {
                a.add(*v, i as u32)
            } else {
                b.add(*v, i as u32)
            }
        }
        let mut f1 = Film::new(1, 1);
        f1.add_pixel(0, &forward);
        let mut f2 = Film::new(1, 1);
        f2.add_pixel(0, &b);
        f2.add_pixel(0, &a);
        assert_eq!(f1, f2);
        let exact: f64 = values.iter().map(|v| v.x as f64).sum::<f64>() / 1000.0;
        assert!((f1.mean(0).x as f64 - exact).abs() < 1e-6);
    }

    /// Runs of a film added to in any order, their losses summed in any
    /// order, make the film that adding each pixel in turn makes: the same
    /// sums, counts and squares, the same counts of dropped and clamped
    /// samples, and the same first dropped sample (the earliest in row,
    /// column and sample order, whichever run it is in).
    #[test]
    fn runs_added_in_any_order_make_the_same_film() {
        let (w, h) = (7u32, 5u32);
        let pixel = |i: usize| {
            let mut p = PixelSum::default();
            for k in 0..3u32 {
                let v = (i as u32 * 31 + k * 7) % 11;
                match v {
                    0 if i % 4 == 1 => p.add(Vec3::new(f32::NAN, 0.0, 0.0), k),
                    1 => p.add(Vec3::splat(1e30), k),
                    _ => p.add(Vec3::new(v as f32, 0.5, 0.25 * k as f32), k),
                }
            }
            p
        };
        let mut each = Film::new(w, h);
        each.track_squares();
        for i in 0..each.pixel_count() {
            each.add_pixel(i, &pixel(i));
        }
        assert!(each.invalid >= 2 && each.clamped > 0, "{each:?}");
        let first = (0..each.pixel_count()).find_map(|i| {
            let p = pixel(i);
            (p.invalid > 0).then(|| BadSample {
                x: i as u32 % w,
                y: i as u32 / w,
                sample: p.first_invalid.unwrap(),
            })
        });
        assert_eq!(each.first_invalid, first);
        for len in [1, 3, 8, 64] {
            let mut film = Film::new(w, h);
            film.track_squares();
            let mut runs = film.runs_mut(len);
            // Last run first, as a thief might take it.
            let losses = runs
                .iter_mut()
                .rev()
                .map(|run| {
                    let first = run.first;
                    for k in 0..run.len() {
                        run.add_pixel(k, &pixel(first + k));
                    }
                    run.losses
                })
                .fold(Losses::default(), Losses::merge);
            film.add_losses(losses);
            assert_eq!(film, each, "runs of {len}");
        }
    }

    /// A render's pixels are weighed before its film is made, and a film
    /// that cannot be had is an error naming it.
    #[test]
    fn memory_is_weighed_before_a_film_is_made() {
        assert!(render_bytes_per_pixel(false, false) >= FILM_PIXEL_BYTES);
        assert!(render_bytes_per_pixel(true, true) > render_bytes_per_pixel(false, true));
        assert!(check_memory(64, 64, true, true).is_ok());
        let e = check_memory(u32::MAX, u32::MAX, false, true).unwrap_err();
        assert!(e.starts_with("a 4294967295×4294967295 image ("), "{e}");
        assert_eq!(Film::try_new(3, 2), Ok(Film::new(3, 2)));
        let e = Film::try_new(u32::MAX, u32::MAX).unwrap_err();
        assert!(e.contains("cannot allocate the film"), "{e}");
    }

    #[test]
    fn invalid_samples_are_dropped_and_located() {
        let mut p = PixelSum::default();
        p.add(Vec3::ONE, 0);
        p.add(Vec3::new(f32::NAN, 0.0, 0.0), 5);
        p.add(Vec3::splat(f32::INFINITY), 6);
        p.add(Vec3::splat(-1.0), 7);
        let mut film = Film::new(4, 4);
        film.add_pixel(6, &p);
        assert_eq!(film.invalid, 3);
        assert_eq!(
            film.first_invalid,
            Some(BadSample {
                x: 2,
                y: 1,
                sample: 5
            })
        );
        assert_eq!(film.mean(6), Vec3::ONE);
    }
}
