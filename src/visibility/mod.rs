//! The visibility pass: every polygon is scan-converted into ONE visibility buffer
//! (seed 002 §4's item buffer; seed 004 §3(1)'s aliased polygon pass), holding per
//! pixel the depth and the id of the nearest item. Shading happens afterwards, once
//! per visible pixel, by passes that read this buffer.
//!
//! Stages, one file each: `clip.rs` (homogeneous clipping), [`scan`] (exact
//! fixed-point DDA scan conversion, top-left rule) and `raster.rs` (projection,
//! binning into bands and the band-parallel z-buffer), `cutout.rs` (the alpha
//! test of cut-out materials, in every polygon pass). [`solids`] finds the
//! visible surfaces of CSG solids by seed 003's scanline walk and writes them
//! into the same buffer, so solids and meshes hide each other.

mod clip;
mod cutout;
mod raster;
pub mod scan;
pub mod solids;

use glam::Vec3;

use crate::image::PixelRect;
use crate::scene::{Body, Scene};

pub use clip::{ClipPlanes, MAX_CLIPPED};
pub use raster::{fragments, rasterize, rasterize_casters, Faces, Fragment, RasterStats, Workers};

/// What a pixel sees: an object and one of its triangles, or one primitive of a
/// CSG solid (seed 003: item id = object + primitive).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct ItemId {
    /// Index into `Scene::objects`.
    pub object: u32,
    /// Triangle index within the object's mesh, or [`ItemId::PRIMITIVE`] plus
    /// the index of a solid's primitive.
    pub triangle: u32,
}

impl ItemId {
    /// The id of pixels that see nothing.
    pub const NONE: ItemId = ItemId { object: u32::MAX, triangle: u32::MAX };

    /// The bit that marks a CSG primitive rather than a triangle.
    pub const PRIMITIVE: u32 = 1 << 31;

    /// The id of primitive `primitive` of the solid `object`.
    #[must_use]
    pub fn primitive_of(object: u32, primitive: u32) -> ItemId {
        ItemId { object, triangle: Self::PRIMITIVE | primitive }
    }

    /// The CSG primitive this id names, if it names one (not a triangle, not
    /// nothing).
    #[inline]
    #[must_use]
    pub fn primitive(self) -> Option<u32> {
        (self.triangle & Self::PRIMITIVE != 0 && !self.is_none()).then_some(self.triangle & !Self::PRIMITIVE)
    }

    /// Both fields in one integer (one comparison instead of two, for the
    /// hot loops that look for runs of equal ids).
    #[inline]
    #[must_use]
    pub fn key(self) -> u64 {
        (u64::from(self.object) << 32) | u64::from(self.triangle)
    }

    /// Whether this pixel sees nothing.
    #[must_use]
    pub fn is_none(self) -> bool {
        self == Self::NONE
    }

    /// The index into [`Scene::materials`] of what this id shows: a mesh
    /// object's material, or a solid's primitive's (`self` must name an
    /// object of `scene`).
    #[must_use]
    pub fn material(self, scene: &Scene) -> usize {
        let o = &scene.objects[self.object as usize];
        match (&o.body, self.primitive()) {
            (Body::Solid { materials, .. }, Some(p)) => materials.get(p as usize).copied().unwrap_or(o.material),
            _ => o.material,
        }
    }
}

/// Per-pixel depth and item id, rows top to bottom, of a rectangle of an
/// image ([`VisibilityBuffer::rect`]: the whole image but for a tile of a
/// frame). Pixels are named by the whole image's coordinates everywhere; only
/// the storage is the rectangle's, row-major from its top left pixel
/// ([`VisibilityBuffer::index`]).
///
/// Depth is reversed: `1` at the near plane, falling towards `0` (perspective: at
/// infinity, depth = near / distance along the view axis; orthographic: at the far
/// plane). Larger is nearer; empty pixels hold `0` and [`ItemId::NONE`].
#[derive(Debug, Clone)]
pub struct VisibilityBuffer {
    width: u32,
    height: u32,
    /// The pixels held (and drawn); the rest of the image is not stored.
    rect: PixelRect,
    depth: Vec<f32>,
    items: Vec<ItemId>,
    /// World-space outward normals of the pixels that show a CSG solid (held
    /// only once a solid has been drawn; other pixels' entries mean nothing).
    normals: Vec<Vec3>,
    /// False for a depth-only buffer (shadow maps), whose `items` stay empty.
    with_items: bool,
    /// False for a buffer whose solids' normals are not wanted (every shadow
    /// map, even one that keeps items).
    with_normals: bool,
}

impl VisibilityBuffer {
    /// An empty buffer. The size must have been checked
    /// ([`crate::scene::check_image_size`]).
    #[must_use]
    pub fn new(width: u32, height: u32) -> Self {
        let n = width as usize * height as usize;
        VisibilityBuffer {
            width,
            height,
            depth: vec![0.0; n],
            items: vec![ItemId::NONE; n],
            normals: Vec::new(),
            with_items: true,
            with_normals: true,
            rect: PixelRect::full(width, height),
        }
    }

    /// A buffer that keeps depth only ([`VisibilityBuffer::items`] is empty): a
    /// shadow map needs no item ids, and skipping them saves two thirds of the
    /// memory.
    #[must_use]
    pub fn depth_only(width: u32, height: u32) -> Self {
        let n = width as usize * height as usize;
        VisibilityBuffer {
            width,
            height,
            depth: vec![0.0; n],
            items: Vec::new(),
            normals: Vec::new(),
            with_items: false,
            with_normals: false,
            rect: PixelRect::full(width, height),
        }
    }

    /// The whole image's width in pixels.
    #[must_use]
    pub fn width(&self) -> u32 {
        self.width
    }

    /// The whole image's height in pixels.
    #[must_use]
    pub fn height(&self) -> u32 {
        self.height
    }

    /// The pixels the buffer holds ([`VisibilityBuffer::resize_to`]).
    #[must_use]
    pub fn rect(&self) -> PixelRect {
        self.rect
    }

    /// Where pixel (x, y) of the image is stored in [`VisibilityBuffer::depths`]
    /// and [`VisibilityBuffer::items`]: `(y − y0) · rect width + x − x0`.
    ///
    /// # Panics
    ///
    /// May panic (in debug builds) for a pixel outside [`VisibilityBuffer::rect`].
    #[inline]
    #[must_use]
    pub fn index(&self, x: u32, y: u32) -> usize {
        debug_assert!(self.rect.contains(x, y), "({x}, {y}) outside {:?}", self.rect);
        (y - self.rect.y0) as usize * self.rect.width() as usize + (x - self.rect.x0) as usize
    }

    /// Depth of every pixel held, row-major from the top left of
    /// [`VisibilityBuffer::rect`].
    #[must_use]
    pub fn depths(&self) -> &[f32] {
        &self.depth
    }

    /// Item of every pixel held, as [`VisibilityBuffer::depths`] (empty for a
    /// depth-only buffer).
    #[must_use]
    pub fn items(&self) -> &[ItemId] {
        &self.items
    }

    /// The items of row `y` held, columns `rect.x0..rect.x1`.
    ///
    /// # Panics
    ///
    /// On a depth-only buffer, or for a row outside [`VisibilityBuffer::rect`].
    #[must_use]
    pub fn item_row(&self, y: u32) -> &[ItemId] {
        let start = self.index(self.rect.x0, y);
        &self.items[start..start + self.rect.width() as usize]
    }

    /// Item at pixel (x, y).
    ///
    /// # Panics
    ///
    /// On a depth-only buffer, or outside the buffer.
    #[must_use]
    pub fn item(&self, x: u32, y: u32) -> ItemId {
        self.items[self.index(x, y)]
    }

    /// The solid's outward normal (world space) at pixel (x, y), meaningful
    /// where the pixel's item is a CSG primitive ([`ItemId::primitive`]); zero
    /// when no solid was drawn.
    #[must_use]
    pub fn normal(&self, x: u32, y: u32) -> Vec3 {
        self.normals.get(self.index(x, y)).copied().unwrap_or(Vec3::ZERO)
    }

    /// Depth at pixel (x, y).
    #[must_use]
    pub fn depth(&self, x: u32, y: u32) -> f32 {
        self.depth[self.index(x, y)]
    }

    /// Makes the buffer hold a whole `width` × `height` image, reusing its
    /// memory when it can. The contents are undefined until the next
    /// [`rasterize`].
    pub fn resize(&mut self, width: u32, height: u32) {
        self.resize_to(width, height, None);
    }

    /// Makes the buffer hold the pixels of `rect` of a `width` × `height`
    /// image (`None`: all of them), reusing its memory when it can; a
    /// rectangle's buffer costs its area. [`rasterize`] and [`fragments`]
    /// draw the pixels held exactly as they draw those pixels of the whole
    /// image: coordinates stay the whole image's, so a tile of a frame is
    /// computed by the same arithmetic as the frame. The contents are
    /// undefined until the next [`rasterize`].
    ///
    /// # Panics
    ///
    /// If `rect` does not lie inside the image.
    pub fn resize_to(&mut self, width: u32, height: u32, rect: Option<PixelRect>) {
        let rect = rect.unwrap_or(PixelRect::full(width, height));
        assert!(rect.fits(width, height), "{rect:?} outside a {width}x{height} image");
        let n = rect.width() as usize * rect.height() as usize;
        (self.width, self.height, self.rect) = (width, height, rect);
        self.depth.resize(n, 0.0);
        if self.with_items {
            self.items.resize(n, ItemId::NONE);
        }
        if !self.normals.is_empty() {
            self.normals.resize(n, Vec3::ZERO);
        }
    }

    /// Whether the buffer keeps item ids from the next [`rasterize`] on (a
    /// depth-only buffer that starts to, or one that stops and frees them).
    pub fn keep_items(&mut self, keep: bool) {
        self.with_items = keep;
        if keep {
            self.items.resize(self.depth.len(), ItemId::NONE);
        } else {
            self.items = Vec::new();
            self.normals = Vec::new();
        }
    }

    /// Forgets everything drawn.
    pub fn clear(&mut self) {
        self.depth.fill(0.0);
        self.items.fill(ItemId::NONE);
    }

    fn parts_mut(&mut self) -> (&mut [f32], &mut [ItemId]) {
        (&mut self.depth, &mut self.items)
    }

    /// Depth, items (empty for a depth-only buffer) and normals (allocated here
    /// when the buffer keeps items), for drawing solids.
    fn solid_parts_mut(&mut self) -> (&mut [f32], &mut [ItemId], &mut [Vec3]) {
        if self.with_normals && self.normals.len() != self.depth.len() {
            self.normals.resize(self.depth.len(), Vec3::ZERO);
        }
        (&mut self.depth, &mut self.items, &mut self.normals)
    }

    /// Bytes held by the buffer.
    #[must_use]
    pub fn memory_bytes(&self) -> usize {
        self.depth.len() * std::mem::size_of::<f32>()
            + self.items.len() * std::mem::size_of::<ItemId>()
            + self.normals.len() * std::mem::size_of::<Vec3>()
    }
}
