//! Colour textures, decoded once, with a mip chain: sampled
//! bilinearly at the finest level, or trilinearly at the level matching a
//! footprint (the texture-space size of the pixel), with a wrap mode.
//!
//! Textures of one size can be stored side by side ([`Texture::interleaved`]):
//! a textured pixel reads all its material's maps at one place, and with
//! them interleaved the lookups after the first find their texels in the
//! cache and share one [`Footprint`] ([`SharedFootprint`]). On the
//! DamagedHelmet (six 2048² maps a pixel) that took the viewer's quick
//! frame from 95.7–97.7 ms to 62.4–63.7 ms together with the
//! reflection-map pass's band of mirrors (1280×720, 2 threads, alternated).

use std::sync::{Arc, LazyLock};

use glam::{Vec2, Vec3, Vec4};
use rayon::prelude::*;

use crate::image::{linear_to_srgb8, srgb_to_linear};
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

/// Texture filtering.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Filter {
    /// The finest level, bilinear (sharp; shimmers where texels are smaller
    /// than pixels).
    Bilinear,
    /// The mip level matching each pixel's texture footprint, trilinear.
    #[default]
    Trilinear,
    /// The mip level nearest each pixel's footprint, bilinear: half the
    /// lookups of trilinear, with seams where the level changes (the
    /// viewer's frames while its camera moves).
    NearestLevel,
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

/// How a level's texels are stored.
#[derive(Debug, Clone)]
enum Texels {
    /// Eight bits a channel, red, green, blue and alpha: the colour decoded
    /// through the texture's [`Codec`] (4 bytes a texel; the form nearly
    /// every JPEG and PNG comes in).
    Bytes(Vec<[u8; 4]>),
    /// Linear floats, opaque (high dynamic range images and maps made in
    /// code; 12 bytes a texel).
    Floats(Vec<Vec3>),
}

impl Texels {
    fn bytes(&self) -> usize {
        match self {
            Texels::Bytes(t) => std::mem::size_of_val(&t[..]),
            Texels::Floats(t) => std::mem::size_of_val(&t[..]),
        }
    }
}

/// What an 8-bit code means: the linear value of each of the 256 codes
/// (the sRGB curve's for colours, the code over 255 for data), and the way
/// back.
#[derive(Debug)]
struct Codec {
    linear: [f32; 256],
    srgb: bool,
}

impl Codec {
    fn new(srgb: bool) -> Codec {
        let linear = std::array::from_fn(|k| {
            let c = k as f32 / 255.0;
            if srgb {
                srgb_to_linear(c)
            } else {
                c
            }
        });
        Codec { linear, srgb }
    }

    /// The code nearest linear value `c` (clamped to [0, 1]).
    fn encode(&self, c: f32) -> u8 {
        if self.srgb {
            linear_to_srgb8(c)
        } else {
            (c.clamp(0.0, 1.0) * 255.0 + 0.5) as u8
        }
    }

    fn colour(&self, t: [u8; 4]) -> Vec3 {
        Vec3::new(self.linear[t[0] as usize], self.linear[t[1] as usize], self.linear[t[2] as usize])
    }
}

static SRGB: LazyLock<Codec> = LazyLock::new(|| Codec::new(true));
static LINEAR: LazyLock<Codec> = LazyLock::new(|| Codec::new(false));

/// The four texels a bilinear lookup blends, and the blend's fractions.
#[derive(Debug, Clone, Copy)]
struct Corners {
    /// Top left, top right, bottom left, bottom right.
    at: [usize; 4],
    fx: f32,
    fy: f32,
}

impl Corners {
    fn blend<T>(&self, texel: impl Fn(usize) -> T, lerp: impl Fn(T, T, f32) -> T) -> T {
        let top = lerp(texel(self.at[0]), texel(self.at[1]), self.fx);
        let bottom = lerp(texel(self.at[2]), texel(self.at[3]), self.fx);
        lerp(top, bottom, self.fy)
    }
}

/// One level of the mip chain.
#[derive(Debug, Clone)]
struct Level {
    width: u32,
    height: u32,
    /// Texels of each position: 1, or the textures a [`Texture::interleaved`]
    /// bundle holds, stored side by side (layer `k` of position `i` at
    /// `i × layers + k`).
    layers: usize,
    texels: Texels,
}

impl Level {
    /// A level of one layer.
    fn single(width: u32, height: u32, texels: Texels) -> Level {
        Level { width, height, layers: 1, texels }
    }

    /// The positions around `uv` and their weights.
    fn corners(&self, uv: Vec2, wrap: Wrap) -> Corners {
        let (w, h) = (self.width as i64, self.height as i64);
        let x = uv.x * self.width as f32 - 0.5;
        let y = uv.y * self.height as f32 - 0.5;
        if !(x.is_finite() && y.is_finite()) {
            return Corners { at: [0; 4], fx: 0.0, fy: 0.0 };
        }
        let (x0, y0) = (x.floor(), y.floor());
        let (across, down) = wrap.axes();
        let [i0, i1] = across.pair(x0 as i64, w);
        let [j0, j1] = down.pair(y0 as i64, h).map(|j| j * w as usize);
        Corners { at: [j0 + i0, j0 + i1, j1 + i0, j1 + i1], fx: x - x0, fy: y - y0 }
    }

    /// Layer `layer`'s colour blended over `c`.
    fn colour(&self, c: &Corners, layer: usize, codec: &Codec) -> Vec3 {
        match &self.texels {
            Texels::Bytes(t) => c.blend(|i| codec.colour(t[i * self.layers + layer]), Vec3::lerp),
            Texels::Floats(t) => c.blend(|i| t[i], Vec3::lerp),
        }
    }

    /// Layer `layer`'s colour and alpha blended over `c` (one fetch of
    /// each texel for both).
    fn colour_alpha(&self, c: &Corners, layer: usize, codec: &Codec) -> Vec4 {
        match &self.texels {
            Texels::Bytes(t) => c.blend(
                |i| {
                    let texel = t[i * self.layers + layer];
                    codec.colour(texel).extend(f32::from(texel[3]) / 255.0)
                },
                Vec4::lerp,
            ),
            Texels::Floats(t) => c.blend(|i| t[i].extend(1.0), Vec4::lerp),
        }
    }

    /// Layer `layer`'s alpha blended over `c`.
    fn alpha(&self, c: &Corners, layer: usize) -> f32 {
        match &self.texels {
            Texels::Bytes(t) => {
                c.blend(|i| f32::from(t[i * self.layers + layer][3]), |a, b, f| a + (b - a) * f) / 255.0
            }
            Texels::Floats(_) => 1.0,
        }
    }

    /// The next coarser level: each texel the mean of (up to) 2 × 2 texels,
    /// colours averaged as linear values.
    fn halved(&self, codec: &Codec) -> Level {
        debug_assert_eq!(self.layers, 1, "a bundle's levels are interleaved from finished chains");
        let (w, h) = ((self.width / 2).max(1), (self.height / 2).max(1));
        // Rows in parallel: the levels of a baked 2048² map are as many
        // texels as the image, each encoded back to a code.
        let quads = (0..h).into_par_iter().flat_map_iter(move |y| (0..w).map(move |x| (x, y))).map(|(x, y)| {
            let xs = [2 * x, (2 * x + 1).min(self.width - 1)];
            let ys = [2 * y, (2 * y + 1).min(self.height - 1)];
            [(xs[0], ys[0]), (xs[1], ys[0]), (xs[0], ys[1]), (xs[1], ys[1])].map(|(i, j)| (j * self.width + i) as usize)
        });
        let texels = match &self.texels {
            Texels::Bytes(t) => Texels::Bytes(
                quads
                    .map(|q| {
                        let colour: Vec3 = q.iter().map(|&i| codec.colour(t[i])).sum::<Vec3>() * 0.25;
                        let alpha: u32 = q.iter().map(|&i| u32::from(t[i][3])).sum();
                        let [r, g, b] = colour.to_array().map(|c| codec.encode(c));
                        [r, g, b, ((alpha + 2) / 4) as u8]
                    })
                    .collect(),
            ),
            Texels::Floats(t) => Texels::Floats(quads.map(|q| q.iter().map(|&i| t[i]).sum::<Vec3>() * 0.25).collect()),
        };
        Level::single(w, h, texels)
    }

    /// Layer `layer`'s 8-bit texels, in order (`None` for floats).
    fn layer_bytes(&self, layer: usize) -> Option<impl Iterator<Item = [u8; 4]> + '_> {
        match &self.texels {
            Texels::Bytes(t) => Some(t.iter().skip(layer).step_by(self.layers).copied()),
            Texels::Floats(_) => None,
        }
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

/// The opaque 8-bit texel nearest linear colour `c` (each channel clamped to
/// [0, 1]): sRGB-encoded where `srgb`, as it is otherwise.
#[must_use]
pub fn encode_8bit(c: Vec3, srgb: bool) -> [u8; 4] {
    let codec = if srgb { &*SRGB } else { &*LINEAR };
    let [r, g, b] = c.to_array().map(|c| codec.encode(c));
    [r, g, b, 255]
}

/// A decoded texture with its mip chain: colours read as linear RGB, with
/// an alpha channel (1 where the image has none).
///
/// Images of 8 or 16 bits a channel are kept in 8 bits, four channels a
/// texel, and decoded through a 256-entry table at each lookup (the sRGB
/// curve's for colour maps): a third of the memory linear floats take, and
/// on the textured benchmark scenes no slower to shade. Floating-point
/// images (OpenEXR) keep linear floats.
#[derive(Debug, Clone)]
pub struct Texture {
    /// Shared by the copies that differ in their wrap mode only, and by the
    /// textures of one [`Texture::interleaved`] bundle.
    levels: Arc<Vec<Level>>,
    /// Which of the levels' layers this texture reads.
    layer: usize,
    /// What the 8-bit codes mean.
    codec: &'static Codec,
    /// Whether some texel is less than opaque.
    translucent: bool,
    /// Wrap mode of every lookup.
    pub wrap: Wrap,
    /// Which of a mesh's texture-coordinate sets it is read at: 0
    /// ([`Mesh::uvs`](super::Mesh::uvs)) or 1 ([`Mesh::uvs1`](super::Mesh::uvs1)).
    pub set: u8,
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
        let floats = matches!(decoded.color(), ::image::ColorType::Rgb32F | ::image::ColorType::Rgba32F);
        if floats {
            // An EXR may hold NaN, infinite or negative values: none is a colour.
            let decode = |c: f32| {
                let c = if c.is_finite() { c.max(0.0) } else { 0.0 };
                if srgb {
                    srgb_to_linear(c)
                } else {
                    c
                }
            };
            let img = decoded.into_rgb32f();
            let texels = img.pixels().map(|p| Vec3::new(decode(p[0]), decode(p[1]), decode(p[2]))).collect();
            return Ok(Texture::from_texels(width, height, texels));
        }
        let texels = decoded.into_rgba8().pixels().map(|p| p.0).collect();
        Ok(Texture::from_levels(Level::single(width, height, Texels::Bytes(texels)), srgb))
    }

    /// A texture from linear texels, row 0 at the top, repeating, kept as
    /// floats.
    ///
    /// # Panics
    ///
    /// If there are not `width × height` texels.
    #[must_use]
    pub fn from_texels(width: u32, height: u32, texels: Vec<Vec3>) -> Texture {
        assert_eq!(texels.len(), (width * height) as usize, "texel count");
        Texture::from_levels(Level::single(width, height, Texels::Floats(texels)), false)
    }

    /// A texture from 8-bit texels (red, green, blue, alpha), row 0 at the
    /// top, repeating: sRGB-encoded colours where `srgb`, linear data
    /// otherwise ([`encode_8bit`] makes them from linear values).
    ///
    /// # Panics
    ///
    /// If there are not `width × height` texels.
    #[must_use]
    pub fn from_texels_8bit(width: u32, height: u32, texels: Vec<[u8; 4]>, srgb: bool) -> Texture {
        assert_eq!(texels.len(), (width * height) as usize, "texel count");
        Texture::from_levels(Level::single(width, height, Texels::Bytes(texels)), srgb)
    }

    fn from_levels(finest: Level, srgb: bool) -> Texture {
        let codec = if srgb { &*SRGB } else { &*LINEAR };
        let translucent = match &finest.texels {
            Texels::Bytes(t) => t.iter().any(|t| t[3] < 255),
            Texels::Floats(_) => false,
        };
        let mut levels = vec![finest];
        while let Some(last) = levels.last().filter(|l| l.width > 1 || l.height > 1) {
            let next = last.halved(codec);
            levels.push(next);
        }
        Texture { levels: Arc::new(levels), layer: 0, codec, translucent, wrap: Wrap::Repeat, set: 0 }
    }

    /// This texture as an alpha map: itself where some texel is less than
    /// opaque, else one whose alpha is its red channel's code (a grey mask,
    /// as OBJ's `map_d` often is).
    #[must_use]
    pub fn coverage(&self) -> Texture {
        if self.translucent {
            return self.clone();
        }
        let finest = &self.levels[0];
        let texels = match (&finest.texels, finest.layer_bytes(self.layer)) {
            (_, Some(bytes)) => bytes.map(|p| [p[0], p[1], p[2], p[0]]).collect(),
            (Texels::Floats(t), None) => t.iter().map(|c| [LINEAR.encode(c.x); 4]).collect(),
            (Texels::Bytes(_), None) => unreachable!("bytes have layers"),
        };
        let level = Level::single(finest.width, finest.height, Texels::Bytes(texels));
        Texture { wrap: self.wrap, set: self.set, ..Texture::from_levels(level, false) }
    }

    /// The textures of `bundle` stored side by side, each position's texels
    /// of all of them together in memory, at every level: what a lookup of
    /// one reads, its neighbour's lookup at the same place finds in the
    /// cache. The results read what the inputs read (their colour spaces,
    /// wrap modes and coordinate sets kept); `None` unless there are at
    /// least two, all of 8-bit texels with chains of one size.
    #[must_use]
    pub fn interleaved(bundle: &[&Texture]) -> Option<Vec<Texture>> {
        let first = bundle.first()?;
        let alike = |t: &&Texture| {
            t.levels.len() == first.levels.len()
                && t.levels.iter().zip(first.levels.iter()).all(|(a, b)| (a.width, a.height) == (b.width, b.height))
                && matches!(t.levels[0].texels, Texels::Bytes(_))
        };
        if bundle.len() < 2 || !bundle.iter().all(alike) {
            return None;
        }
        let levels = (0..first.levels.len())
            .map(|k| {
                // Each input's texels at level k, with its stride and layer.
                let inputs: Vec<(&[[u8; 4]], usize, usize)> = bundle
                    .iter()
                    .map(|t| match &t.levels[k].texels {
                        Texels::Bytes(b) => (&b[..], t.levels[k].layers, t.layer),
                        Texels::Floats(_) => unreachable!("checked above: 8-bit levels"),
                    })
                    .collect();
                let (width, height) = (first.levels[k].width, first.levels[k].height);
                let mut texels = vec![[0u8; 4]; (width * height) as usize * bundle.len()];
                texels.par_chunks_mut(bundle.len()).enumerate().for_each(|(i, out)| {
                    for (o, &(src, layers, layer)) in out.iter_mut().zip(&inputs) {
                        *o = src[i * layers + layer];
                    }
                });
                Level { width, height, layers: bundle.len(), texels: Texels::Bytes(texels) }
            })
            .collect();
        let levels = Arc::new(levels);
        Some(
            bundle
                .iter()
                .enumerate()
                .map(|(k, t)| Texture { levels: Arc::clone(&levels), layer: k, ..(*t).clone() })
                .collect(),
        )
    }

    /// Width and height of the finest level, in texels.
    #[must_use]
    pub fn size(&self) -> (u32, u32) {
        (self.levels[0].width, self.levels[0].height)
    }

    /// Whether some texel's alpha is below 1.
    #[must_use]
    pub fn translucent(&self) -> bool {
        self.translucent
    }

    /// Whether `other` reads the same decoded texels (a copy that differs in
    /// its wrap mode only).
    #[must_use]
    pub fn shares_texels(&self, other: &Texture) -> bool {
        Arc::ptr_eq(&self.levels, &other.levels)
    }

    /// One number for the texels it reads: equal for textures that
    /// [`Texture::shares_texels`].
    pub(crate) fn texels_id(&self) -> usize {
        Arc::as_ptr(&self.levels) as usize
    }

    /// Bytes its levels hold (shared by the copies that differ in their
    /// wrap mode only, and by an [`Texture::interleaved`] bundle's textures).
    #[must_use]
    pub fn memory_bytes(&self) -> usize {
        self.levels.iter().map(|l| l.texels.bytes()).sum()
    }

    /// Bilinear sample of the finest level at `uv` (origin top-left, texel centres
    /// at +0.5).
    #[must_use]
    pub fn sample(&self, uv: Vec2) -> Vec3 {
        self.read(&self.footprint(Filter::Bilinear, uv, [Vec2::ZERO; 2]))
    }

    /// Trilinear sample for a pixel whose neighbours to the right and below are
    /// `duv[0]` and `duv[1]` away in texture space: the level whose texels match
    /// the longer of the two steps, blended with the next. A zero footprint is the
    /// bilinear sample of the finest level.
    #[must_use]
    pub fn sample_footprint(&self, uv: Vec2, duv: [Vec2; 2]) -> Vec3 {
        self.read(&self.footprint(Filter::Trilinear, uv, duv))
    }

    /// The colour at `uv` for a pixel whose footprint is `duv`, filtered
    /// as `filter` says.
    #[must_use]
    pub fn sample_filtered(&self, filter: Filter, uv: Vec2, duv: [Vec2; 2]) -> Vec3 {
        self.read(&self.footprint(filter, uv, duv))
    }

    /// Where a lookup at `uv` over the footprint `duv`, filtered as `filter`
    /// says, reads: the same for every texture that
    /// [`Texture::reads_like`] this one, so the maps of one
    /// [`Texture::interleaved`] bundle find it once.
    #[must_use]
    pub fn footprint(&self, filter: Filter, uv: Vec2, duv: [Vec2; 2]) -> Footprint {
        let at = |k: usize| (k, self.levels[k].corners(uv, self.wrap));
        match filter {
            Filter::Bilinear => Footprint { fine: at(0), coarse: None },
            Filter::NearestLevel => Footprint { fine: at(self.lod(duv).round() as usize), coarse: None },
            Filter::Trilinear => {
                let lod = self.lod(duv);
                let k = lod.floor() as usize;
                if k + 1 >= self.levels.len() {
                    return Footprint { fine: at(self.levels.len() - 1), coarse: None };
                }
                let (next, corners) = at(k + 1);
                Footprint { fine: at(k), coarse: Some((next, corners, lod - k as f32)) }
            }
        }
    }

    /// Whether a [`Footprint`] of `other`'s is one of this texture's too:
    /// levels of the same sizes, wrapped alike. (Both must be read at the
    /// same texture coordinates.)
    #[must_use]
    pub fn reads_like(&self, other: &Texture) -> bool {
        // A chain's sizes follow from its finest level's.
        self.wrap.axes() == other.wrap.axes() && self.size() == other.size() && self.levels.len() == other.levels.len()
    }

    /// The colour over footprint `f` (made by this texture, or by one it
    /// [`Texture::reads_like`]).
    #[must_use]
    pub fn read(&self, f: &Footprint) -> Vec3 {
        let colour = |(k, c): (usize, Corners)| self.levels[k].colour(&c, self.layer, self.codec);
        match f.coarse {
            None => colour(f.fine),
            Some((k, c, t)) => colour(f.fine).lerp(colour((k, c)), t),
        }
    }

    /// The colour and alpha over footprint `f`, as [`Texture::read`] and
    /// [`Texture::alpha`] read them, in one lookup.
    #[must_use]
    pub fn read_rgba(&self, f: &Footprint) -> Vec4 {
        let rgba = |(k, c): (usize, Corners)| self.levels[k].colour_alpha(&c, self.layer, self.codec);
        match f.coarse {
            None => rgba(f.fine),
            Some((k, c, t)) => rgba(f.fine).lerp(rgba((k, c)), t),
        }
    }

    /// The (fractional) mip level whose texels match the longer of the
    /// footprint's two steps, within the chain.
    fn lod(&self, duv: [Vec2; 2]) -> f32 {
        let size = Vec2::new(self.levels[0].width as f32, self.levels[0].height as f32);
        let step = (duv[0] * size).length_squared().max((duv[1] * size).length_squared());
        let lod = if step > 1.0 && step.is_finite() { 0.5 * step.log2() } else { 0.0 };
        lod.min((self.levels.len() - 1) as f32)
    }

    /// Alpha at `uv` (bilinear at the finest level), in [0, 1].
    #[must_use]
    pub fn alpha(&self, uv: Vec2) -> f32 {
        self.read_alpha(&self.footprint(Filter::Bilinear, uv, [Vec2::ZERO; 2]))
    }

    /// Alpha for a pixel's footprint, filtered as [`Texture::sample_footprint`]
    /// filters colour.
    #[must_use]
    pub fn alpha_footprint(&self, uv: Vec2, duv: [Vec2; 2]) -> f32 {
        self.read_alpha(&self.footprint(Filter::Trilinear, uv, duv))
    }

    fn read_alpha(&self, f: &Footprint) -> f32 {
        let alpha = |(k, c): (usize, Corners)| self.levels[k].alpha(&c, self.layer);
        match f.coarse {
            None => alpha(f.fine),
            Some((k, c, t)) => {
                let a = alpha(f.fine);
                a + (alpha((k, c)) - a) * t
            }
        }
    }
}

/// Where a filtered texture lookup reads ([`Texture::footprint`]): the
/// level or two levels, and the four texels blended in each.
#[derive(Debug, Clone, Copy)]
pub struct Footprint {
    fine: (usize, Corners),
    /// The next coarser level and its share, for trilinear filtering.
    coarse: Option<(usize, Corners, f32)>,
}

/// The footprint of the last texture a surface point sampled, reused by
/// the next one that [`Texture::reads_like`] it with the same filter: the
/// maps of one [`Texture::interleaved`] bundle find their level and texels
/// once a point. One is made for each point (the coordinates are the
/// point's).
#[derive(Debug, Default)]
pub struct SharedFootprint<'a> {
    last: Option<(&'a Texture, Filter, Footprint)>,
}

impl<'a> SharedFootprint<'a> {
    /// `t` sampled at `uv` (of its coordinate set `t.set`) over `duv`, as
    /// [`Texture::sample_filtered`] samples it.
    pub fn sample(&mut self, t: &'a Texture, filter: Filter, uv: Vec2, duv: [Vec2; 2]) -> Vec3 {
        t.read(&self.find(t, filter, uv, duv))
    }

    /// `t`'s alpha at `uv` over `duv`, filtered as `filter` says (as
    /// [`SharedFootprint::sample`] reads its colour).
    pub fn alpha(&mut self, t: &'a Texture, filter: Filter, uv: Vec2, duv: [Vec2; 2]) -> f32 {
        t.read_alpha(&self.find(t, filter, uv, duv))
    }

    /// `t`'s colour and alpha at once ([`Texture::read_rgba`]).
    pub fn sample_rgba(&mut self, t: &'a Texture, filter: Filter, uv: Vec2, duv: [Vec2; 2]) -> Vec4 {
        t.read_rgba(&self.find(t, filter, uv, duv))
    }

    /// The last footprint if `t` reads like its texture, else `t`'s own.
    fn find(&mut self, t: &'a Texture, filter: Filter, uv: Vec2, duv: [Vec2; 2]) -> Footprint {
        match self.last {
            Some((last, by, f)) if by == filter && last.set == t.set && last.reads_like(t) => f,
            _ => {
                let f = t.footprint(filter, uv, duv);
                self.last = Some((t, filter, f));
                f
            }
        }
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
            let centres = (0..256).map(|i| Vec2::new((i % 16) as f32 + 0.5, (i / 16) as f32 + 0.5) / 16.0);
            let texels = centres.map(|uv| (a.sample(uv), b.sample(uv)));
            for ((ta, tb), k) in texels.zip(codes.chunks(3)) {
                let want = Vec3::from_array([k[0], k[1], k[2]].map(|k| {
                    let c = f32::from(k) / 255.0;
                    if srgb {
                        srgb_to_linear(c)
                    } else {
                        c
                    }
                }));
                assert!((ta - want).abs().max_element() < 1e-6, "8-bit {ta} vs {want}");
                assert!((tb - want).abs().max_element() < 1e-6, "16-bit {tb} vs {want}");
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
        let grey = |l: &Level| match &l.texels {
            Texels::Floats(t) => t.iter().all(|c| (c.x - 0.5).abs() < 1e-6),
            Texels::Bytes(_) => false,
        };
        assert!(t.levels.iter().skip(1).all(grey));
        let uv = Vec2::new(0.3, 0.7);
        // One texel per pixel: the finest level; four texels per pixel: level 2.
        assert_eq!(t.sample_footprint(uv, [Vec2::new(1.0 / 64.0, 0.0), Vec2::ZERO]), t.sample(uv));
        let wide = t.sample_footprint(uv, [Vec2::new(4.0 / 64.0, 0.0), Vec2::new(0.0, 1.0 / 64.0)]);
        assert!((wide.x - 0.5).abs() < 1e-6, "{wide}");
        // The nearest level alone: 1.4 texels a pixel rounds to the finest
        // (no blend with the grey level above), 1.5 to the next.
        let near = |texels: f32| t.sample_filtered(Filter::NearestLevel, uv, [Vec2::new(texels / 64.0, 0.0); 2]);
        assert_eq!(near(1.4), t.sample(uv));
        assert!((near(1.5).x - 0.5).abs() < 1e-6);
    }

    /// Eight-bit colours are averaged as light, not as codes: a black and
    /// white checker's coarser levels hold the sRGB code of a linear 0.5
    /// (188), not 128; alpha is averaged as it is.
    #[test]
    fn eight_bit_levels_average_linear_light_and_alpha() {
        let texels: Vec<Vec3> = (0..16).map(|i| Vec3::splat(((i % 4 + i / 4) % 2) as f32)).collect();
        let t = Texture::from_texels_8bit(4, 4, texels.iter().map(|&c| encode_8bit(c, true)).collect(), true);
        let Texels::Bytes(level1) = &t.levels[1].texels else { panic!("8-bit levels") };
        assert!(level1.iter().all(|p| p[..3] == [188, 188, 188] && p[3] == 255), "{level1:?}");
        assert!(!t.translucent());
        let mut png = Vec::new();
        let rgba = ::image::RgbaImage::from_fn(2, 2, |x, _| ::image::Rgba([255, 0, 0, if x == 0 { 0 } else { 255 }]));
        rgba.write_to(&mut std::io::Cursor::new(&mut png), ::image::ImageFormat::Png).unwrap();
        let t = Texture::decode(&png, true, &Limits::default()).unwrap();
        assert!(t.translucent());
        assert_eq!(t.alpha(Vec2::new(0.25, 0.25)), 0.0);
        assert_eq!(t.alpha(Vec2::new(0.75, 0.75)), 1.0);
        assert!((t.alpha(Vec2::new(0.5, 0.25)) - 0.5).abs() < 1e-6);
        assert!((t.alpha_footprint(Vec2::new(0.25, 0.25), [Vec2::new(1.0, 0.0); 2]) - 0.5).abs() <= 1.0 / 255.0);
        assert_eq!(t.sample(Vec2::new(0.25, 0.75)), Vec3::X);
        // Its own alpha is its coverage; a grey mask's is its grey.
        assert!(t.coverage().shares_texels(&t));
        let grey = Texture::from_texels_8bit(2, 1, vec![[0, 0, 0, 255], [255, 255, 255, 255]], false).coverage();
        assert_eq!((grey.alpha(Vec2::new(0.25, 0.5)), grey.alpha(Vec2::new(0.75, 0.5))), (0.0, 1.0));
    }

    /// A pseudo-random 8-bit texture (odd size, alpha varying).
    fn noise(width: u32, height: u32, seed: u32, srgb: bool) -> Texture {
        let texel = |i: u32| {
            let h = (i ^ seed).wrapping_mul(2_654_435_761).rotate_left(13).wrapping_mul(0x9E37_79B9);
            h.to_le_bytes()
        };
        Texture::from_texels_8bit(width, height, (0..width * height).map(texel).collect(), srgb)
    }

    /// Textures stored side by side read exactly what they read alone, at
    /// every filter, footprint and wrap, alpha included; one footprint
    /// serves them all; the bundle's bytes are held once.
    #[test]
    fn interleaved_textures_read_what_they_read_alone() {
        let mut alone = [noise(37, 23, 1, true), noise(37, 23, 2, false), noise(37, 23, 3, true)];
        alone[1].wrap = Wrap::Each(Edge::Clamp, Edge::Mirror);
        alone[2].set = 1;
        let refs: Vec<&Texture> = alone.iter().collect();
        let bundle = Texture::interleaved(&refs).expect("three 8-bit textures of one size");
        assert!(bundle[0].shares_texels(&bundle[2]) && !bundle[0].shares_texels(&alone[0]));
        assert_eq!(bundle[0].memory_bytes(), alone.iter().map(Texture::memory_bytes).sum::<usize>());
        assert_eq!((bundle[1].wrap, bundle[2].set), (alone[1].wrap, 1));
        let mut state = 7u32;
        let mut next = || {
            state = state.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            (state >> 8) as f32 / (1u32 << 24) as f32
        };
        for _ in 0..500 {
            let uv = Vec2::new(next() * 3.0 - 1.0, next() * 3.0 - 1.0);
            let duv = [Vec2::new(next(), next()) * 0.3 * next(), Vec2::new(next(), next()) * 0.1];
            for filter in [Filter::Bilinear, Filter::Trilinear, Filter::NearestLevel] {
                let shared = bundle[0].footprint(filter, uv, duv);
                for (b, a) in bundle.iter().zip(&alone) {
                    assert_eq!(b.sample_filtered(filter, uv, duv), a.sample_filtered(filter, uv, duv));
                    if b.reads_like(&bundle[0]) {
                        assert_eq!(b.read(&shared), a.sample_filtered(filter, uv, duv));
                    }
                }
            }
            for (b, a) in bundle.iter().zip(&alone) {
                assert_eq!(b.alpha_footprint(uv, duv), a.alpha_footprint(uv, duv));
                // Colour and alpha in one lookup: each as read alone.
                let rgba = b.read_rgba(&b.footprint(Filter::Trilinear, uv, duv));
                assert_eq!(rgba.truncate(), a.sample_footprint(uv, duv));
                assert!((rgba.w - a.alpha_footprint(uv, duv)).abs() < 1e-6);
            }
            assert_eq!(bundle[1].coverage().alpha(uv), alone[1].coverage().alpha(uv));
        }
        // Sizes that differ, or float texels, are not bundled.
        assert!(Texture::interleaved(&[&alone[0], &noise(36, 23, 4, true)]).is_none());
        assert!(Texture::interleaved(&[&alone[0]]).is_none());
        let floats = Texture::from_texels(37, 23, vec![Vec3::ONE; 37 * 23]);
        assert!(Texture::interleaved(&[&alone[0], &floats]).is_none());
    }
}
