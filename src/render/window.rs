//! The pixels a render covers: the whole image, or a window of it
//! (`--crop X0,Y0,X1,Y1`). A pixel keeps its place in the whole image, so
//! its samples (a function of the pixel's index in the whole image) are
//! the same whether it is rendered alone or with the rest: a cropped image
//! equals that window of the full render, bit for bit.

use std::ops::Range;

/// Columns `x` and rows `y` of an image `image_width` pixels wide.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Window {
    pub x: Range<u32>,
    pub y: Range<u32>,
    pub image_width: u32,
}

impl Window {
    /// The whole `width` × `height` image.
    pub fn whole(width: u32, height: u32) -> Self {
        Self {
            x: 0..width,
            y: 0..height,
            image_width: width,
        }
    }

    pub fn width(&self) -> u32 {
        self.x.end - self.x.start
    }

    pub fn height(&self) -> u32 {
        self.y.end - self.y.start
    }

    pub fn pixel_count(&self) -> usize {
        self.width() as usize * self.height() as usize
    }

    /// Pixel `i` of the window (row-major) as (x, y, its index in the
    /// whole image).
    #[inline]
    pub fn pixel(&self, i: usize) -> (u32, u32, u32) {
        let w = self.width() as usize;
        let x = self.x.start + (i % w) as u32;
        let y = self.y.start + (i / w) as u32;
        (x, y, y * self.image_width + x)
    }

    /// This window grown by `margin` pixels on every side, within an image
    /// `image_height` rows tall.
    pub fn grown(&self, margin: u32, image_height: u32) -> Self {
        Self {
            x: self.x.start.saturating_sub(margin)..(self.x.end + margin).min(self.image_width),
            y: self.y.start.saturating_sub(margin)..(self.y.end + margin).min(image_height),
            image_width: self.image_width,
        }
    }

    /// Of `values`, one per pixel of this window (row-major), those of the
    /// pixels of `inner`, a window inside this one.
    pub fn cut<T: Copy>(&self, inner: &Window, values: &[T]) -> Vec<T> {
        let w = self.width() as usize;
        let x0 = (inner.x.start - self.x.start) as usize;
        inner
            .y
            .clone()
            .flat_map(|y| {
                let row = (y - self.y.start) as usize * w + x0;
                values[row..row + inner.width() as usize].iter().copied()
            })
            .collect()
    }

    /// `--crop X0,Y0,X1,Y1` (half-open pixel ranges) inside a `width` ×
    /// `height` image.
    pub fn crop(text: &str, width: u32, height: u32) -> Result<Self, String> {
        let numbers: Vec<u32> = text
            .split(',')
            .map(|s| s.trim().parse())
            .collect::<Result<_, _>>()
            .unwrap_or_default();
        let [x0, y0, x1, y1] = numbers[..] else {
            let negative = text
                .split(',')
                .any(|s| s.trim().parse::<i64>().is_ok_and(|n| n < 0));
            return Err(match negative {
                true => format!(
                    "'{text}': pixel coordinates start at 0 (X0,Y0,X1,Y1 from the top left)"
                ),
                false => format!("'{text}' is not X0,Y0,X1,Y1 (four whole numbers)"),
            });
        };
        if x0 >= x1 || y0 >= y1 {
            return Err(format!("'{text}' is empty: need X0 < X1 and Y0 < Y1"));
        }
        if x1 > width || y1 > height {
            return Err(format!(
                "'{text}' reaches past the {width}x{height} image (X1 ≤ {width}, Y1 ≤ {height})"
            ));
        }
        Ok(Self {
            x: x0..x1,
            y: y0..y1,
            image_width: width,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn window_pixels_keep_their_place_in_the_whole_image() {
        let w = Window::crop("2,1,5,3", 8, 4).unwrap();
        assert_eq!((w.width(), w.height(), w.pixel_count()), (3, 2, 6));
        assert_eq!(w.pixel(0), (2, 1, 10));
        assert_eq!(w.pixel(4), (3, 2, 19));
        let whole = Window::whole(8, 4);
        assert_eq!(whole.pixel(19), (3, 2, 19));
    }

    #[test]
    fn bad_crops_are_explained() {
        for (text, needle) in [
            ("1,2,3", "four whole numbers"),
            ("a,0,1,1", "four whole numbers"),
            ("-1,0,5,3", "pixel coordinates start at 0"),
            ("3,0,3,2", "empty"),
            ("0,0,9,2", "reaches past the 8x4 image"),
        ] {
            let e = Window::crop(text, 8, 4).unwrap_err();
            assert!(e.contains(needle), "{text}: {e}");
        }
    }

    #[test]
    fn a_grown_window_stays_in_the_image_and_cuts_back_to_the_crop() {
        let crop = Window::crop("2,1,5,3", 8, 6).unwrap();
        let grown = crop.grown(2, 6);
        assert_eq!((grown.x.clone(), grown.y.clone()), (0..7, 0..5));
        let ids: Vec<u32> = (0..grown.pixel_count()).map(|i| grown.pixel(i).2).collect();
        let mine: Vec<u32> = (0..crop.pixel_count()).map(|i| crop.pixel(i).2).collect();
        assert_eq!(grown.cut(&crop, &ids), mine);
        assert_eq!(Window::whole(8, 6).grown(3, 6), Window::whole(8, 6));
    }
}
