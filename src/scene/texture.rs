//! Colour textures, decoded once to linear RGB, with a mip chain: sampled
//! bilinearly at the finest level, or trilinearly at the level matching a
//! footprint (the texture-space size of the pixel), with a wrap mode.

use std::sync::Arc;

use glam::{Vec2, Vec3};

use crate::image::srgb_to_linear;
use crate::limits::{Limit, Limits};

/// What happens outside [0, 1] texture coordinates.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum Wrap {
    /// The image tiles.
    #[default]
    Repeat,
    /// The edge texels extend.
    Clamp,
    /// The image tiles, every other copy mirrored.
    Mirror,
    /// An equirectangular map: tiles across (longitude goes round), the top
    /// and bottom rows extend (latitude stops at the poles).
    Longitude,
    /// Its own mode across (u) and down (v), as a glTF sampler gives them.
    Each(Edge, Edge),
}

/// One axis's mode, for [`Wrap::Each`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum Edge {
    /// The image tiles.
    #[default]
    Repeat,
    /// The edge texels extend.
    Clamp,
    /// The image tiles, every other copy mirrored.
    Mirror,
}

impl From<Edge> for Wrap {
    fn from(edge: Edge) -> Wrap {
        match edge {
            Edge::Repeat => Wrap::Repeat,
            Edge::Clamp => Wrap::Clamp,
            Edge::Mirror => Wrap::Mirror,
        }
    }
}

impl Wrap {
    /// The modes across (u) and down (v).
    fn axes(self) -> (Wrap, Wrap) {
        match self {
            Wrap::Longitude => (Wrap::Repeat, Wrap::Clamp),
            Wrap::Each(across, down) => (across.into(), down.into()),
            w => (w, w),
        }
    }

    /// Texel index `i` of a row of `n`, wrapped.
    fn index(self, i: i64, n: i64) -> i64 {
        match self {
            // `Each` is split by `axes` before any lookup.
            Wrap::Repeat | Wrap::Longitude | Wrap::Each(..) => i.rem_euclid(n),
            Wrap::Clamp => i.clamp(0, n - 1),
            Wrap::Mirror => {
                let k = i.rem_euclid(2 * n);
                if k < n {
                    k
                } else {
                    2 * n - 1 - k
                }
            }
        }
    }

    /// Texel indices `i` and `i + 1` of a row of `n`, wrapped (the two a
    /// bilinear lookup blends; inside the row, as nearly all are, no division).
    /// A coordinate far outside the texture saturates `i` to the ends of
    /// i64, where `i + 1` would overflow: the comparisons are made without it.
    fn pair(self, i: i64, n: i64) -> [usize; 2] {
        if i >= 0 && i < n - 1 {
            [i as usize, i as usize + 1]
        } else {
            [self.index(i, n) as usize, self.index(i.saturating_add(1), n) as usize]
        }
    }
}

/// One level of the mip chain.
#[derive(Debug, Clone)]
struct Level {
    width: u32,
    height: u32,
    texels: Vec<Vec3>,
}

impl Level {
    fn bilinear(&self, uv: Vec2, wrap: Wrap) -> Vec3 {
        let (w, h) = (self.width as i64, self.height as i64);
        let x = uv.x * self.width as f32 - 0.5;
        let y = uv.y * self.height as f32 - 0.5;
        if !(x.is_finite() && y.is_finite()) {
            return self.texels[0];
        }
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let (across, down) = wrap.axes();
        let [i0, i1] = across.pair(x0 as i64, w);
        let [j0, j1] = down.pair(y0 as i64, h).map(|j| j * w as usize);
        let at = |i: usize, j: usize| self.texels[j + i];
        let top = at(i0, j0).lerp(at(i1, j0), fx);
        let bottom = at(i0, j1).lerp(at(i1, j1), fx);
        top.lerp(bottom, fy)
    }

    /// The next coarser level: each texel the mean of (up to) 2 × 2 texels.
    fn halved(&self) -> Level {
        let (w, h) = ((self.width / 2).max(1), (self.height / 2).max(1));
        let texels = (0..h)
            .flat_map(|y| (0..w).map(move |x| (x, y)))
            .map(|(x, y)| {
                let xs = [2 * x, (2 * x + 1).min(self.width - 1)];
                let ys = [2 * y, (2 * y + 1).min(self.height - 1)];
                let sum: Vec3 =
                    ys.iter().flat_map(|&j| xs.iter().map(move |&i| (i, j))).map(|(i, j)| self.texel(i, j)).sum();
                sum * 0.25
            })
            .collect();
        Level { width: w, height: h, texels }
    }

    fn texel(&self, x: u32, y: u32) -> Vec3 {
        self.texels[(y * self.width + x) as usize]
    }
}

/// What the `png` decoder assumes of a PNG's palette and does not check (it
/// slices past the end of a `PLTE` chunk whose length is not a multiple of
/// 3): the chunk holds 1 to 256 whole RGB entries. Other bytes pass.
fn checked_png_palette(bytes: &[u8]) -> Result<(), String> {
    let Some(mut rest) = bytes.strip_prefix(b"\x89PNG\r\n\x1a\n") else { return Ok(()) };
    while rest.len() >= 12 {
        let len = u32::from_be_bytes([rest[0], rest[1], rest[2], rest[3]]) as usize;
        if &rest[4..8] == b"PLTE" && !(len.is_multiple_of(3) && (3..=768).contains(&len)) {
            return Err(format!("the PNG's palette (PLTE) holds {len} bytes, not 1 to 256 RGB entries"));
        }
        let Some(next) = rest.get(12usize.saturating_add(len)..) else { break };
        rest = next;
    }
    Ok(())
}

/// A decoded texture in linear RGB with its mip chain.
#[derive(Debug, Clone)]
pub struct Texture {
    /// Shared by the copies that differ in their wrap mode only.
    levels: Arc<Vec<Level>>,
    /// Wrap mode of every lookup.
    pub wrap: Wrap,
}

impl Texture {
    /// Decodes an encoded image (PNG, JPEG or OpenEXR). `srgb` says whether its
    /// values are sRGB-encoded colours (true for colour maps) or already linear.
    /// Its size is read from the header first and refused past
    /// [`Limit::TexturePixels`] (a 140 KB PNG can hold 11000² grey pixels).
    ///
    /// # Errors
    ///
    /// The decoder's message when the bytes are no image it reads; the limit's
    /// when it is too large.
    pub fn decode(bytes: &[u8], srgb: bool, limits: &Limits) -> Result<Texture, String> {
        checked_png_palette(bytes)?;
        let reader =
            ::image::ImageReader::new(std::io::Cursor::new(bytes)).with_guessed_format().map_err(|e| e.to_string())?;
        let mut header = reader.into_decoder().map_err(|e| e.to_string())?;
        let (width, height) = ::image::ImageDecoder::dimensions(&header);
        let pixels = u64::from(width) * u64::from(height);
        limits
            .check(Limit::TexturePixels, pixels, || format!("the {width} × {height} image"))
            .map_err(|e| e.to_string())?;
        // The decoder's own allocations are bounded too: what it holds
        // while decoding is at most its output, 16 bytes a pixel (RGBA f32).
        let mut own = ::image::Limits::default();
        own.max_alloc = Some(pixels.saturating_mul(16).max(1 << 20));
        ::image::ImageDecoder::set_limits(&mut header, own).map_err(|e| e.to_string())?;
        // A decoder's panic on a malformed image not yet known to it is its
        // bug, not kage's end: it becomes this image's error.
        let decoded =
            std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| ::image::DynamicImage::from_decoder(header)))
                .map_err(|_| "the image decoder failed on this file (it is malformed, or the decoder has a bug)")?;
        let decoded = decoded.map_err(|e| e.to_string())?;
        let (width, height) = (decoded.width(), decoded.height());
        if width == 0 || height == 0 {
            return Err("the image has no pixels".into());
        }
        // An EXR may hold NaN, infinite or negative values: none is a colour.
        let decode = |c: f32| {
            let c = if c.is_finite() { c.max(0.0) } else { 0.0 };
            if srgb {
                srgb_to_linear(c)
            } else {
                c
            }
        };
        let texels = if decoded.color().bytes_per_pixel() == decoded.color().channel_count() {
            // Eight bits a channel (JPEG, most PNGs): 256 values, each decoded
            // once rather than with a power per texel.
            let table: Vec<f32> = (0..=255u8).map(|k| decode(f32::from(k) / 255.0)).collect();
            let img = decoded.into_rgb8();
            img.pixels().map(|p| Vec3::new(table[p[0] as usize], table[p[1] as usize], table[p[2] as usize])).collect()
        } else {
            let img = decoded.into_rgb32f();
            img.pixels().map(|p| Vec3::new(decode(p[0]), decode(p[1]), decode(p[2]))).collect()
        };
        Ok(Texture::from_texels(width, height, texels))
    }

    /// A texture from linear texels, row 0 at the top, repeating.
    ///
    /// # Panics
    ///
    /// If there are not `width × height` texels.
    #[must_use]
    pub fn from_texels(width: u32, height: u32, texels: Vec<Vec3>) -> Texture {
        assert_eq!(texels.len(), (width * height) as usize, "texel count");
        let mut levels = vec![Level { width, height, texels }];
        while let Some(last) = levels.last().filter(|l| l.width > 1 || l.height > 1) {
            let next = last.halved();
            levels.push(next);
        }
        Texture { levels: Arc::new(levels), wrap: Wrap::Repeat }
    }

    /// Width and height of the finest level, in texels.
    #[must_use]
    pub fn size(&self) -> (u32, u32) {
        (self.levels[0].width, self.levels[0].height)
    }

    /// Whether `other` reads the same decoded texels (a copy that differs in
    /// its wrap mode only).
    #[must_use]
    pub fn shares_texels(&self, other: &Texture) -> bool {
        Arc::ptr_eq(&self.levels, &other.levels)
    }

    /// Bytes its levels hold (shared by the copies that differ in their
    /// wrap mode only).
    #[must_use]
    pub fn memory_bytes(&self) -> usize {
        self.levels.iter().map(|l| l.texels.len() * std::mem::size_of::<Vec3>()).sum()
    }

    /// Bilinear sample of the finest level at `uv` (origin top-left, texel centres
    /// at +0.5).
    #[must_use]
    pub fn sample(&self, uv: Vec2) -> Vec3 {
        self.levels[0].bilinear(uv, self.wrap)
    }

    /// Trilinear sample for a pixel whose neighbours to the right and below are
    /// `duv[0]` and `duv[1]` away in texture space: the level whose texels match
    /// the longer of the two steps, blended with the next. A zero footprint is the
    /// bilinear sample of the finest level.
    #[must_use]
    pub fn sample_footprint(&self, uv: Vec2, duv: [Vec2; 2]) -> Vec3 {
        let size = Vec2::new(self.levels[0].width as f32, self.levels[0].height as f32);
        let step = (duv[0] * size).length().max((duv[1] * size).length());
        let lod = if step > 1.0 && step.is_finite() { step.log2() } else { 0.0 };
        let top = self.levels.len() - 1;
        let k = (lod.floor() as usize).min(top);
        let a = self.levels[k].bilinear(uv, self.wrap);
        if k == top {
            return a;
        }
        a.lerp(self.levels[k + 1].bilinear(uv, self.wrap), lod - k as f32)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An 8-bit image (decoded through a table of its 256 values) and the
    /// same values in 16 bits (a power per texel) give the same texels: the
    /// sRGB curve's, or the code over 255 for linear data.
    #[test]
    fn eight_and_sixteen_bit_images_decode_alike() {
        let encode = |image: ::image::DynamicImage| {
            let mut bytes = Vec::new();
            image.write_to(&mut std::io::Cursor::new(&mut bytes), ::image::ImageFormat::Png).unwrap();
            bytes
        };
        let codes: Vec<u8> = (0..=255u8).flat_map(|k| [k, k.wrapping_mul(7), 255 - k]).collect();
        let eight = ::image::RgbImage::from_raw(16, 16, codes.clone()).unwrap();
        let wide: Vec<u16> = codes.iter().map(|&k| u16::from(k) * 257).collect();
        let sixteen = ::image::ImageBuffer::<::image::Rgb<u16>, _>::from_raw(16, 16, wide).unwrap();
        let (eight, sixteen) = (encode(eight.into()), encode(sixteen.into()));
        for srgb in [true, false] {
            let a = Texture::decode(&eight, srgb, &Limits::default()).unwrap();
            let b = Texture::decode(&sixteen, srgb, &Limits::default()).unwrap();
            for ((ta, tb), k) in a.levels[0].texels.iter().zip(&b.levels[0].texels).zip(codes.chunks(3)) {
                let want = Vec3::from_array([k[0], k[1], k[2]].map(|k| {
                    let c = f32::from(k) / 255.0;
                    if srgb {
                        srgb_to_linear(c)
                    } else {
                        c
                    }
                }));
                assert!((*ta - want).abs().max_element() < 1e-6, "8-bit {ta} vs {want}");
                assert!((*tb - want).abs().max_element() < 1e-6, "16-bit {tb} vs {want}");
            }
        }
    }

    #[test]
    fn bilinear_repeats_and_interpolates() {
        let t = Texture::from_texels(2, 1, vec![Vec3::ZERO, Vec3::ONE]);
        assert_eq!(t.sample(Vec2::new(0.25, 0.5)), Vec3::ZERO);
        assert_eq!(t.sample(Vec2::new(0.75, 0.5)), Vec3::ONE);
        assert!((t.sample(Vec2::new(0.5, 0.5)).x - 0.5).abs() < 1e-6);
        // u = 0 lies halfway between the last texel (wrapped) and the first.
        assert!((t.sample(Vec2::new(0.0, 0.5)).x - 0.5).abs() < 1e-6);
        assert_eq!(t.sample(Vec2::new(1.25, 0.5)), Vec3::ZERO);
    }

    #[test]
    fn wrap_modes_fold_coordinates() {
        let n = 4;
        let idx = |w: Wrap| [-2, -1, 0, 3, 4, 5].map(|i| w.index(i, n));
        assert_eq!(idx(Wrap::Repeat), [2, 3, 0, 3, 0, 1]);
        assert_eq!(idx(Wrap::Clamp), [0, 0, 0, 3, 3, 3]);
        assert_eq!(idx(Wrap::Mirror), [1, 0, 0, 3, 3, 2]);
        // The pair a bilinear lookup takes, with and without its fast path.
        for wrap in [Wrap::Repeat, Wrap::Clamp, Wrap::Mirror] {
            for i in -9..9 {
                let expected = [i, i + 1].map(|i| wrap.index(i, n) as usize);
                assert_eq!(wrap.pair(i, n), expected, "{wrap:?} {i}");
            }
        }
    }

    #[test]
    fn the_mip_chain_keeps_the_mean_and_wide_footprints_reach_it() {
        // A 64 × 64 checker of single texels: every level above the first is grey.
        let texels = (0..64 * 64).map(|i| Vec3::splat(((i % 64 + i / 64) % 2) as f32)).collect();
        let t = Texture::from_texels(64, 64, texels);
        assert_eq!(t.levels.len(), 7);
        assert!(t.levels.iter().skip(1).all(|l| l.texels.iter().all(|c| (c.x - 0.5).abs() < 1e-6)));
        let uv = Vec2::new(0.3, 0.7);
        // One texel per pixel: the finest level; four texels per pixel: level 2.
        assert_eq!(t.sample_footprint(uv, [Vec2::new(1.0 / 64.0, 0.0), Vec2::ZERO]), t.sample(uv));
        let wide = t.sample_footprint(uv, [Vec2::new(4.0 / 64.0, 0.0), Vec2::new(0.0, 1.0 / 64.0)]);
        assert!((wide.x - 0.5).abs() < 1e-6, "{wide}");
    }
}
