//! The ground floor: a linear-light RGB float image, the buffer every stage of
//! the frame writes into, and the sRGB transfer curve that turns it into 8-bit
//! colour for display (and decodes 8-bit colour textures).

mod tone;

use std::sync::LazyLock;

use glam::Vec3;
use rayon::prelude::*;

pub use tone::ToneCurve;

/// A rectangle of pixels, `x0..x1` × `y0..y1` (half-open), in the
/// coordinates of a whole image: what a tile of a frame covers (the
/// default: empty, at the origin).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Hash)]
pub struct PixelRect {
    /// First column.
    pub x0: u32,
    /// First row.
    pub y0: u32,
    /// One past the last column.
    pub x1: u32,
    /// One past the last row.
    pub y1: u32,
}

impl PixelRect {
    /// The whole of a `width` × `height` image.
    #[must_use]
    pub fn full(width: u32, height: u32) -> PixelRect {
        PixelRect { x0: 0, y0: 0, x1: width, y1: height }
    }

    /// Width in pixels (0 when empty).
    #[must_use]
    pub fn width(self) -> u32 {
        self.x1.saturating_sub(self.x0)
    }

    /// Height in pixels (0 when empty).
    #[must_use]
    pub fn height(self) -> u32 {
        self.y1.saturating_sub(self.y0)
    }

    /// Whether it holds no pixel.
    #[must_use]
    pub fn is_empty(self) -> bool {
        self.width() == 0 || self.height() == 0
    }

    /// Whether it lies inside a `width` × `height` image.
    #[must_use]
    pub fn fits(self, width: u32, height: u32) -> bool {
        self.x0 <= self.x1 && self.y0 <= self.y1 && self.x1 <= width && self.y1 <= height
    }

    /// Whether pixel (x, y) is in it.
    #[must_use]
    pub fn contains(self, x: u32, y: u32) -> bool {
        (self.x0..self.x1).contains(&x) && (self.y0..self.y1).contains(&y)
    }

    /// Whether it lies inside `outer`.
    #[must_use]
    pub fn inside(self, outer: PixelRect) -> bool {
        self.x0 >= outer.x0 && self.y0 >= outer.y0 && self.x1 <= outer.x1 && self.y1 <= outer.y1
    }

    /// The same pixels counted from `outer`'s top left pixel (where they lie
    /// in an image that holds `outer` alone).
    ///
    /// # Panics
    ///
    /// If it does not lie [`PixelRect::inside`] `outer`.
    #[must_use]
    pub fn relative_to(self, outer: PixelRect) -> PixelRect {
        assert!(self.inside(outer), "{self:?} is not inside {outer:?}");
        let (dx, dy) = (outer.x0, outer.y0);
        PixelRect { x0: self.x0 - dx, y0: self.y0 - dy, x1: self.x1 - dx, y1: self.y1 - dy }
    }

    /// Grown by `by` pixels on every side, kept inside a `width` × `height`
    /// image.
    #[must_use]
    pub fn grown(self, by: u32, width: u32, height: u32) -> PixelRect {
        PixelRect {
            x0: self.x0.saturating_sub(by),
            y0: self.y0.saturating_sub(by),
            x1: self.x1.saturating_add(by).min(width),
            y1: self.y1.saturating_add(by).min(height),
        }
    }

    /// Tile `index` of `count` tiles cutting a `width` × `height` image into a
    /// grid: `count` = columns × rows, the pair whose tiles are closest to
    /// square; tiles numbered row by row from the top left, their edges at
    /// `⌊k·width/columns⌋` and `⌊k·height/rows⌋`.
    ///
    /// # Panics
    ///
    /// If `index >= count`.
    #[must_use]
    pub fn tile(index: u32, count: u32, width: u32, height: u32) -> PixelRect {
        assert!(index < count, "tile {index} of {count}");
        let (columns, rows) = grid(count, width, height);
        let (i, j) = (index % columns, index / columns);
        let cut = |k: u32, n: u32, size: u32| (u64::from(k) * u64::from(size) / u64::from(n)) as u32;
        PixelRect {
            x0: cut(i, columns, width),
            x1: cut(i + 1, columns, width),
            y0: cut(j, rows, height),
            y1: cut(j + 1, rows, height),
        }
    }
}

/// Columns × rows = `count`, the factor pair whose cells of a `width` ×
/// `height` image are nearest to square.
fn grid(count: u32, width: u32, height: u32) -> (u32, u32) {
    let squareness = |c: u32| {
        let (cw, ch) = (width as f64 / f64::from(c), height as f64 / f64::from(count / c));
        (cw / ch).ln().abs()
    };
    let columns =
        (1..=count).filter(|c| count.is_multiple_of(*c)).min_by(|a, b| squareness(*a).total_cmp(&squareness(*b)));
    let columns = columns.unwrap_or(1);
    (columns, count / columns)
}

/// A linear-light RGB image, rows top to bottom.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct LinearImage {
    width: u32,
    height: u32,
    pixels: Vec<Vec3>,
}

impl LinearImage {
    /// A black image. The size must have been checked.
    #[must_use]
    pub fn new(width: u32, height: u32) -> Self {
        LinearImage { width, height, pixels: vec![Vec3::ZERO; width as usize * height as usize] }
    }

    /// Makes the image `width` × `height`, reusing its memory when it can; the
    /// contents are undefined until written.
    pub fn resize(&mut self, width: u32, height: u32) {
        self.width = width;
        self.height = height;
        self.pixels.resize(width as usize * height as usize, Vec3::ZERO);
    }

    /// Width in pixels.
    #[must_use]
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Height in pixels.
    #[must_use]
    pub fn height(&self) -> u32 {
        self.height
    }

    /// All pixels, row-major.
    #[must_use]
    pub fn pixels(&self) -> &[Vec3] {
        &self.pixels
    }

    /// All pixels, row-major, for writing.
    pub fn pixels_mut(&mut self) -> &mut [Vec3] {
        &mut self.pixels
    }

    /// The pixels of `rect`, a new image of its size.
    ///
    /// # Panics
    ///
    /// If `rect` does not lie inside the image.
    #[must_use]
    pub fn crop(&self, rect: PixelRect) -> LinearImage {
        assert!(rect.fits(self.width, self.height), "{rect:?} outside a {}x{} image", self.width, self.height);
        let w = self.width as usize;
        let pixels = (rect.y0..rect.y1)
            .flat_map(|y| &self.pixels[y as usize * w + rect.x0 as usize..y as usize * w + rect.x1 as usize])
            .copied()
            .collect();
        LinearImage { width: rect.width(), height: rect.height(), pixels }
    }

    /// Copies `part` into the image with its top left corner at (x, y).
    ///
    /// # Panics
    ///
    /// If `part` placed there does not lie inside the image.
    pub fn paste(&mut self, part: &LinearImage, x: u32, y: u32) {
        let rect = PixelRect { x0: x, y0: y, x1: x + part.width, y1: y + part.height };
        assert!(rect.fits(self.width, self.height), "{rect:?} outside a {}x{} image", self.width, self.height);
        let (w, pw) = (self.width as usize, part.width as usize);
        for (r, row) in part.pixels.chunks(pw.max(1)).enumerate() {
            let start = (y as usize + r) * w + x as usize;
            self.pixels[start..start + pw].copy_from_slice(row);
        }
    }

    /// Pixel (x, y).
    #[must_use]
    pub fn get(&self, x: u32, y: u32) -> Vec3 {
        self.pixels[y as usize * self.width as usize + x as usize]
    }

    /// 8-bit sRGB of the image times `scale` (the exposure), RGB interleaved, rows
    /// top to bottom.
    #[must_use]
    pub fn to_srgb8(&self, scale: f32) -> Vec<u8> {
        self.to_srgb8_toned(scale, ToneCurve::Clip)
    }

    /// 8-bit sRGB of the image times `scale` through the tone curve `tone`,
    /// RGB interleaved, rows top to bottom.
    #[must_use]
    pub fn to_srgb8_toned(&self, scale: f32, tone: ToneCurve) -> Vec<u8> {
        let encoder = &*SRGB8;
        let mut out = vec![0; self.pixels.len() * 3];
        let rows = out.par_chunks_mut(3 * 1024).zip(self.pixels.par_chunks(1024));
        rows.for_each(|(out, pixels)| {
            let values = pixels.iter().flat_map(|&p| match tone {
                ToneCurve::Clip => (p * scale).to_array(),
                _ => tone.apply(p * scale).to_array(),
            });
            out.iter_mut().zip(values).for_each(|(o, c)| *o = encoder.encode(c));
        });
        out
    }

    /// As [`LinearImage::to_srgb8_toned`], each pixel packed in a word as
    /// window frame buffers take it (`0x00RRGGBB`), into `out` (resized to
    /// the pixel count; its memory reused from call to call).
    pub fn to_0rgb_toned_into(&self, scale: f32, tone: ToneCurve, out: &mut Vec<u32>) {
        let encoder = &*SRGB8;
        out.resize(self.pixels.len(), 0);
        out.par_chunks_mut(1024).zip(self.pixels.par_chunks(1024)).for_each(|(out, pixels)| {
            for (o, &p) in out.iter_mut().zip(pixels) {
                let c = match tone {
                    ToneCurve::Clip => p * scale,
                    _ => tone.apply(p * scale),
                };
                let [r, g, b] = c.to_array().map(|v| u32::from(encoder.encode(v)));
                *o = r << 16 | g << 8 | b;
            }
        });
    }
}

/// The 8-bit sRGB code of a linear value in [0, 1] (clamped; NaN is 0):
/// round(255 · sRGB(c)), found without a power per value. Code k begins at the
/// least linear value that rounds to it (`starts[k]`, found once by bisecting
/// the float line with the transfer curve itself, so every value gets exactly
/// the curve's code); a table over [`Srgb8Encoder::BUCKETS`] equal steps of
/// the linear range gives the code at each step's start, and the next codes'
/// starts are compared from there (at most two lie within one step).
struct Srgb8Encoder {
    starts: [f32; 257],
    bucket: Vec<u8>,
}

/// The output stage's encoder, built at first use.
static SRGB8: LazyLock<Srgb8Encoder> = LazyLock::new(Srgb8Encoder::new);

impl Srgb8Encoder {
    const BUCKETS: usize = 4096;

    fn new() -> Srgb8Encoder {
        let code = |c: f32| (linear_to_srgb(c.clamp(0.0, 1.0)) * 255.0 + 0.5) as u8;
        // starts[k]: the least non-negative float whose code is at least k
        // (codes grow with the value); starts[256] lies past 1.
        let mut starts = [f32::INFINITY; 257];
        starts[0] = 0.0;
        for (k, start) in starts.iter_mut().enumerate().take(256).skip(1) {
            let (mut lo, mut hi) = (0u32, 1.0f32.to_bits()); // code(lo) < k <= code(hi)
            while hi - lo > 1 {
                let mid = lo + (hi - lo) / 2;
                if usize::from(code(f32::from_bits(mid))) >= k {
                    hi = mid;
                } else {
                    lo = mid;
                }
            }
            *start = f32::from_bits(hi);
        }
        let bucket: Vec<u8> = (0..Self::BUCKETS).map(|i| code(i as f32 / Self::BUCKETS as f32)).collect();
        // No step holds more than two codes' starts (what `encode` relies on).
        for (i, &first) in bucket.iter().enumerate() {
            let end = (i + 1) as f32 / Self::BUCKETS as f32;
            let within = starts[usize::from(first) + 1..].iter().take_while(|&&s| s < end).count();
            assert!(within <= 2, "sRGB table step {i} holds {within} code starts");
        }
        Srgb8Encoder { starts, bucket }
    }

    fn encode(&self, c: f32) -> u8 {
        let c = c.clamp(0.0, 1.0);
        let i = ((c * Self::BUCKETS as f32) as usize).min(Self::BUCKETS - 1);
        // At most two codes start within a step (checked when the table is
        // made): two comparisons without a branch, which the frame's
        // unpredictable colours would mispredict.
        let mut k = usize::from(self.bucket[i]);
        k += usize::from(c >= self.starts[k + 1]);
        k += usize::from(c >= self.starts[k + 1]);
        k as u8
    }
}

/// The 8-bit sRGB code of a linear value in [0, 1] (clamped; NaN is 0):
/// round(255 · sRGB(c)), without a power per value.
#[must_use]
pub fn linear_to_srgb8(c: f32) -> u8 {
    SRGB8.encode(c)
}

/// sRGB transfer function, decoding direction.
#[must_use]
pub fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// sRGB transfer function, encoding direction.
#[must_use]
pub fn linear_to_srgb(c: f32) -> f32 {
    if c <= 0.003_130_8 {
        c * 12.92
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_srgb8_table_gives_every_value_the_curves_own_code() {
        let curve = |c: f32| (linear_to_srgb(c.clamp(0.0, 1.0)) * 255.0 + 0.5) as u8;
        let encoder = Srgb8Encoder::new();
        // A million even steps, and each code's start with the floats on either
        // side of it, where a table is likeliest to be off by one.
        let even = (0..=1_000_000).map(|i| i as f32 / 1e6);
        let starts = encoder.starts[1..256].iter().flat_map(|s| {
            let bits = s.to_bits();
            [f32::from_bits(bits - 1), *s, f32::from_bits(bits + 1)]
        });
        let odd = [-1.0, -0.0, 1.0, 1.5, f32::INFINITY, f32::NAN, f32::MIN_POSITIVE];
        for c in even.chain(starts).chain(odd) {
            assert_eq!(encoder.encode(c), curve(c), "linear {c} ({:#x})", c.to_bits());
        }
    }

    /// The packed words hold the interleaved bytes' codes, for every tone
    /// curve, and a reused buffer is resized to the image.
    #[test]
    fn packed_words_hold_the_interleaved_codes() {
        let mut image = LinearImage::new(37, 3);
        for (i, p) in image.pixels_mut().iter_mut().enumerate() {
            *p = Vec3::new(i as f32 / 50.0, (i % 7) as f32 / 3.0, 1.0 - i as f32 / 111.0);
        }
        let mut words = vec![7; 5000];
        for (_, tone) in ToneCurve::NAMES {
            image.to_0rgb_toned_into(1.3, tone, &mut words);
            let bytes = image.to_srgb8_toned(1.3, tone);
            assert_eq!(words.len(), 111);
            for (w, b) in words.iter().zip(bytes.chunks(3)) {
                assert_eq!(*w, u32::from(b[0]) << 16 | u32::from(b[1]) << 8 | u32::from(b[2]));
            }
        }
    }

    #[test]
    fn srgb_round_trip() {
        for c in [0.0, 0.001, 0.2, 0.5, 1.0] {
            assert!((srgb_to_linear(linear_to_srgb(c)) - c).abs() < 1e-5);
        }
    }
}
