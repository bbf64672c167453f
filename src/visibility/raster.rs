//! The polygon pass driver: project vertices, bin triangles into horizontal bands,
//! then scan-convert every band in parallel into its own rows of the z-buffer.
//!
//! Triangles are cut into chunks of consecutive triangles; binning runs per chunk in
//! parallel and rasterization per band in parallel. A band draws its triangles in
//! scene order (chunk by chunk), so the image does not depend on the number of
//! threads: single- and multi-threaded renders are bit-identical.
//!
//! A span's z-test runs eight pixels at a time (`span_z_test`): their depths
//! worked out in lanes, compared and blended at once. On the peers' spheres at
//! 1920×1080 on one thread (`RAYON_NUM_THREADS=1 kage-bench raster`, two
//! alternated rounds against the pixel-at-a-time loop) the visibility pass
//! went from 4.5 to 3.9–4.0 ms on 10k triangles and from 8.3–8.9 to 7.9–8.1 ms
//! on 100k; the million-triangle sphere's, bound by triangle set-up, did not
//! move.

use std::ops::Range;

use glam::{DMat4, DVec4, Mat4, Vec4};
use rayon::prelude::*;
use wide::f32x8;

use super::clip::{ClipPlanes, MAX_CLIPPED};
use super::cutout::{CutoutTriangle, Cutouts};
use super::scan::{column_range, row_range, scan_triangle, signed_area2, FixedPoint, SpanSink, ONE};
use super::{ItemId, VisibilityBuffer};
use crate::camera::Camera;
use crate::image::PixelRect;
use crate::scene::{Material, Scene};
use crate::triangle::set_bits;

/// Rows per band: the unit of parallel work and of binning.
pub const BAND_ROWS: usize = 16;
/// Triangles per binning chunk.
const CHUNK_TRIANGLES: u32 = 16 * 1024;
/// Width of the guard band around the image, in pixels: vertices inside it are not
/// clipped in x and y. With images of at most 16384 pixels a side and 12 fractional
/// bits, fixed-point coordinates stay below 2^27, so the DDA's products fit in i64.
const GUARD_PX: f32 = (1 << 14) as f32;
/// Bin entries with this bit set index a chunk's clipped triangles.
const CLIPPED: u32 = 1 << 31;

/// Counts from one polygon pass.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct RasterStats {
    /// Triangles submitted.
    pub triangles: usize,
    /// Triangles that reached at least one band.
    pub binned: usize,
    /// Triangles that needed clipping.
    pub clipped: usize,
    /// CSG solids drawn by the scanline walk (seed 003).
    pub solids: usize,
}

/// A projected vertex: fixed-point screen position and reversed depth.
#[derive(Debug, Clone, Copy, Default)]
struct ScreenVertex {
    x: i32,
    y: i32,
    z: f32,
}

impl ScreenVertex {
    fn point(self) -> FixedPoint {
        FixedPoint { x: self.x as i64, y: self.y as i64 }
    }
}

/// One object's vertices: which planes each is outside of and, where inside all,
/// its screen position; plus the object → clip matrix for the clipping path.
struct Projected {
    to_clip: DMat4,
    outcode: Vec<u8>,
    screen: Vec<ScreenVertex>,
    cull_back: bool,
}

/// Maps clip space to the fixed-point screen.
#[derive(Clone, Copy)]
struct Viewport {
    width: f32,
    height: f32,
}

impl Viewport {
    fn to_screen(self, c: DVec4) -> ScreenVertex {
        let inv_w = 1.0 / c.w;
        let sx = (c.x * inv_w * 0.5 + 0.5) * self.width as f64;
        let sy = (0.5 - c.y * inv_w * 0.5) * self.height as f64;
        let one = ONE as f64;
        ScreenVertex { x: (sx * one).round() as i32, y: (sy * one).round() as i32, z: (c.z * inv_w) as f32 }
    }
}

struct Chunk {
    object: usize,
    triangles: Range<u32>,
}

#[derive(Default)]
struct ChunkBins {
    /// Per band: triangle indices (or `CLIPPED | i`).
    bands: Vec<Vec<u32>>,
    clipped: Vec<([ScreenVertex; 3], u32)>,
    binned: usize,
    clipped_count: usize,
}

/// Everything bands need to draw.
struct PolygonPass<'a> {
    scene: &'a Scene,
    projected: Vec<Projected>,
    planes: ClipPlanes,
    viewport: Viewport,
    /// Pixels a stored row holds (the drawn columns).
    stride: i64,
    /// The rows and columns drawn (the buffer's rectangle); bands count from
    /// its first row, stored rows and columns from its first.
    rows: Range<i64>,
    cols: Range<i64>,
    /// Rows per band: [`BAND_ROWS`], or all the rows drawn on one worker.
    band_rows: usize,
    bands: usize,
    workers: Workers,
    /// The alpha tests of cut-out materials.
    cutouts: Cutouts<'a>,
}

/// How a polygon pass runs (what it draws is the same either way, bit for bit).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Workers {
    /// On every worker: the image cut into bands of 16 rows drawn in
    /// parallel, each triangle binned into the bands it touches.
    All,
    /// On the calling thread, the image as one band: for passes that run
    /// beside others (the jittered shadow maps of an area light, one per
    /// worker), where binning and drawing a triangle once per band it touches
    /// cost more than they share out.
    One,
}

/// Which faces a polygon pass draws.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Faces {
    /// Back faces are culled unless the material is two-sided (the eye's pass).
    AsMaterials,
    /// Every face, front or back (depth passes from lights: open meshes cast too).
    All,
}

/// Draws every opaque object of `scene` seen by the scene's camera into `vb`,
/// which is cleared first (each band clears its own rows, in parallel, just before
/// drawing them): meshes by the polygon pass, then solids by the scanline walk
/// ([`super::solids::draw_solids`]; solids are drawn opaque whatever their
/// material). Translucent meshes are left to [`fragments`].
pub fn rasterize(scene: &Scene, vb: &mut VisibilityBuffer) -> RasterStats {
    let pass = PolygonPass::new(scene, &scene.camera, Faces::AsMaterials, Workers::All, vb.width(), vb.height())
        .within(vb.rect());
    let stats = pass.draw(&chunks(scene, |_, m| !m.translucent()), vb);
    RasterStats { solids: super::solids::draw_solids(scene, &scene.camera, |_| true, vb), ..stats }
}

/// Draws the objects of `scene` that `casters` marks (per object: those
/// shadow maps draw, [`Scene::map_casters`]), opaque or not, front and back
/// faces (open meshes cast too), seen by `camera` (a light's, for a shadow
/// map), into `vb`, its meshes on `workers`.
///
/// # Panics
///
/// If `casters` is shorter than the scene's objects.
pub fn rasterize_casters(
    scene: &Scene,
    camera: &Camera,
    casters: &[bool],
    workers: Workers,
    vb: &mut VisibilityBuffer,
) -> RasterStats {
    let pass = PolygonPass::new(scene, camera, Faces::All, workers, vb.width(), vb.height()).within(vb.rect());
    let stats = pass.draw(&chunks(scene, |i, _| casters[i]), vb);
    RasterStats { solids: super::solids::draw_solids(scene, camera, |i| casters[i], vb), ..stats }
}

/// A sample of a translucent surface at a pixel centre.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Fragment {
    /// The pixel's index among those the opaque buffer holds
    /// ([`VisibilityBuffer::index`]).
    pub pixel: u32,
    /// Reversed depth (larger is nearer).
    pub depth: f32,
    /// The triangle.
    pub item: ItemId,
}

/// Every fragment of the translucent objects of `scene` (seen by its camera) that
/// lies in front of the opaque surface `opaque` holds at its pixel: the same scan
/// conversion as [`rasterize`], writing a list instead of a z-buffer. Fragments
/// come band by band, and within a pixel in scene order (object, triangle).
#[must_use]
pub fn fragments(scene: &Scene, opaque: &VisibilityBuffer) -> Vec<Fragment> {
    let chunks = chunks(scene, |_, m| m.translucent());
    if chunks.is_empty() {
        return Vec::new();
    }
    let (w, h) = (opaque.width(), opaque.height());
    let pass = PolygonPass::new(scene, &scene.camera, Faces::AsMaterials, Workers::All, w, h).within(opaque.rect());
    let bins: Vec<ChunkBins> = chunks.par_iter().map(|c| pass.bin(c)).collect();
    let band_len = pass.stride as usize * pass.band_rows;
    let bands = opaque.depths().par_chunks(band_len).enumerate();
    let per_band: Vec<Vec<Fragment>> = bands
        .map(|(band, depth)| {
            let mut sink = FragmentSink {
                opaque: depth,
                stride: pass.stride,
                cols: pass.cols.clone(),
                row0: pass.row0(band),
                first_pixel: (band * band_len) as u32,
                plane: LazyPlane::default(),
                item: ItemId::NONE,
                out: Vec::new(),
            };
            pass.draw_band(band, &mut sink, &chunks, &bins);
            sink.out
        })
        .collect();
    per_band.concat()
}

impl<'a> PolygonPass<'a> {
    fn new(scene: &'a Scene, camera: &Camera, faces: Faces, workers: Workers, width: u32, height: u32) -> Self {
        let (w, h) = (width as usize, height as usize);
        let view_proj = camera.view_projection(w as f32 / h as f32);
        let planes = ClipPlanes::new(
            camera.far_plane_factor() as f64,
            1.0 + 2.0 * GUARD_PX as f64 / w as f64,
            1.0 + 2.0 * GUARD_PX as f64 / h as f64,
        );
        let viewport = Viewport { width: w as f32, height: h as f32 };
        let projected: Vec<Projected> =
            scene.objects.iter().map(|o| project(scene, o, view_proj, &planes, viewport, faces, workers)).collect();
        let cutouts = Cutouts::new(scene, |i| projected[i].to_clip, w, h);
        PolygonPass {
            scene,
            projected,
            planes,
            viewport,
            stride: 0,
            rows: 0..0,
            cols: 0..0,
            band_rows: 1,
            bands: 0,
            workers,
            cutouts,
        }
        .within(PixelRect::full(width, height))
    }

    /// The pass drawing only the pixels of `rect`, into a buffer that holds
    /// them alone.
    fn within(self, rect: PixelRect) -> Self {
        let band_rows = match self.workers {
            Workers::All => BAND_ROWS,
            Workers::One => (rect.height() as usize).max(1),
        };
        PolygonPass {
            stride: i64::from(rect.width()),
            rows: i64::from(rect.y0)..i64::from(rect.y1),
            cols: i64::from(rect.x0)..i64::from(rect.x1),
            band_rows,
            bands: (rect.height() as usize).div_ceil(band_rows),
            ..self
        }
    }

    /// The first image row of `band`.
    fn row0(&self, band: usize) -> i64 {
        self.rows.start + (band * self.band_rows) as i64
    }

    /// Bins `chunks` and draws them into `vb`, bands in parallel, each band
    /// clearing its own rows first.
    fn draw(&self, chunks: &[Chunk], vb: &mut VisibilityBuffer) -> RasterStats {
        let bins: Vec<ChunkBins> = match self.workers {
            Workers::All => chunks.par_iter().map(|c| self.bin(c)).collect(),
            Workers::One => chunks.iter().map(|c| self.bin(c)).collect(),
        };
        let stride = self.stride;
        let (depth, items) = vb.parts_mut();
        let band_len = stride as usize * self.band_rows;
        let draw = |band: usize, depth: &mut [f32], items: &mut [ItemId]| {
            depth.fill(0.0);
            items.fill(ItemId::NONE);
            let (plane, item) = (LazyPlane::default(), ItemId::NONE);
            let cols = self.cols.clone();
            let cutouts = (!self.cutouts.is_empty()).then_some(&self.cutouts);
            let row0 = self.row0(band);
            let mut sink = DepthSink { depth, items, stride, cols, row0, plane, item, cutouts, cutout: None };
            self.draw_band(band, &mut sink, chunks, &bins);
        };
        if self.workers == Workers::One {
            draw(0, depth, items);
        } else if items.is_empty() {
            depth.par_chunks_mut(band_len).enumerate().for_each(|(band, d)| draw(band, d, &mut []));
        } else {
            let bands = depth.par_chunks_mut(band_len).zip(items.par_chunks_mut(band_len)).enumerate();
            bands.for_each(|(band, (d, i))| draw(band, d, i));
        }
        let drawn: usize = chunks.iter().map(|c| c.triangles.len()).sum();
        RasterStats {
            triangles: drawn,
            binned: bins.iter().map(|b| b.binned).sum(),
            clipped: bins.iter().map(|b| b.clipped_count).sum(),
            solids: 0,
        }
    }
}

fn project(
    scene: &Scene,
    object: &crate::scene::Object,
    view_proj: Mat4,
    planes: &ClipPlanes,
    viewport: Viewport,
    faces: Faces,
    workers: Workers,
) -> Projected {
    let m = view_proj * Mat4::from(object.transform);
    let positions = object.triangles().map_or(&[][..], |m| &m.positions[..]);
    let vertex = |p: &glam::Vec3| {
        let c: Vec4 = m * p.extend(1.0);
        let code = planes.outcode(c);
        (code, if code == 0 { viewport.to_screen(c.as_dvec4()) } else { ScreenVertex::default() })
    };
    let (outcode, screen) = match workers {
        Workers::All => positions.par_iter().map(vertex).unzip(),
        Workers::One => positions.iter().map(vertex).unzip(),
    };
    Projected {
        to_clip: view_proj.as_dmat4() * Mat4::from(object.transform).as_dmat4(),
        outcode,
        screen,
        cull_back: faces == Faces::AsMaterials && !scene.materials[object.material].two_sided,
    }
}

/// The objects that `include` accepts (given each one's index and material),
/// cut into chunks.
fn chunks(scene: &Scene, include: impl Fn(usize, &Material) -> bool) -> Vec<Chunk> {
    let mut out = Vec::new();
    for (object, o) in scene.objects.iter().enumerate().filter(|(i, o)| include(*i, &scene.materials[o.material])) {
        let Some(mesh) = o.triangles() else { continue };
        let n = mesh.triangles.len() as u32;
        out.extend(
            (0..n)
                .step_by(CHUNK_TRIANGLES as usize)
                .map(|s| Chunk { object, triangles: s..(s + CHUNK_TRIANGLES).min(n) }),
        );
    }
    out
}

impl PolygonPass<'_> {
    fn bin(&self, chunk: &Chunk) -> ChunkBins {
        let mut bins = ChunkBins { bands: vec![Vec::new(); self.bands], ..Default::default() };
        let p = &self.projected[chunk.object];
        let tris = &self.scene.objects[chunk.object].triangles().expect("chunks hold meshes").triangles;
        for t in chunk.triangles.clone() {
            let [a, b, c] = tris[t as usize].map(|i| i as usize);
            let codes = [p.outcode[a], p.outcode[b], p.outcode[c]];
            if codes[0] | codes[1] | codes[2] == 0 {
                self.bin_triangle(&mut bins, [p.screen[a], p.screen[b], p.screen[c]], p.cull_back, t);
            } else if codes[0] & codes[1] & codes[2] == 0 {
                bins.clipped_count += 1;
                let positions = &self.scene.objects[chunk.object].triangles().expect("chunks hold meshes").positions;
                self.bin_clipped(
                    &mut bins,
                    [a, b, c].map(|i| p.to_clip * positions[i].as_dvec3().extend(1.0)),
                    codes[0] | codes[1] | codes[2],
                    p.cull_back,
                    t,
                );
            }
        }
        bins
    }

    fn bin_clipped(&self, bins: &mut ChunkBins, tri: [DVec4; 3], mask: u8, cull_back: bool, t: u32) {
        let mut poly = [DVec4::ZERO; MAX_CLIPPED];
        let n = self.planes.clip(tri, mask, &mut poly);
        let screen: Vec<ScreenVertex> = poly[..n].iter().map(|c| self.viewport.to_screen(*c)).collect();
        for k in 1..n.saturating_sub(1) {
            let v = [screen[0], screen[k], screen[k + 1]];
            if let Some(bands) = self.bands_of(v, cull_back) {
                let entry = CLIPPED | bins.clipped.len() as u32;
                bins.clipped.push((v, t));
                bands.for_each(|b| bins.bands[b].push(entry));
            }
        }
    }

    fn bin_triangle(&self, bins: &mut ChunkBins, v: [ScreenVertex; 3], cull_back: bool, t: u32) {
        if let Some(bands) = self.bands_of(v, cull_back) {
            bins.binned += 1;
            bands.for_each(|b| bins.bands[b].push(t));
        }
    }

    /// The bands a triangle touches, or `None` if it is culled, degenerate or
    /// covers no pixel centre of the image.
    fn bands_of(&self, v: [ScreenVertex; 3], cull_back: bool) -> Option<Range<usize>> {
        let p = v.map(ScreenVertex::point);
        let area = signed_area2(&p);
        if area == 0 || (cull_back && area > 0) {
            return None;
        }
        let rows = clamp(row_range(&p), &self.rows);
        let cols = clamp(column_range(&p), &self.cols);
        if rows.is_empty() || cols.is_empty() {
            return None;
        }
        let band = |row: i64| (row - self.rows.start) as usize / self.band_rows;
        Some(band(rows.start)..band(rows.end - 1) + 1)
    }

    /// Scan-converts the triangles binned into `band` into `sink`, in scene order.
    fn draw_band(&self, band: usize, sink: &mut impl BandSink, chunks: &[Chunk], bins: &[ChunkBins]) {
        let row0 = self.row0(band);
        let rows = clamp(row0..row0 + self.band_rows as i64, &self.rows);
        if rows.is_empty() {
            return;
        }
        for (chunk, bin) in chunks.iter().zip(bins) {
            let p = &self.projected[chunk.object];
            let tris = &self.scene.objects[chunk.object].triangles().expect("chunks hold meshes").triangles;
            for &entry in &bin.bands[band] {
                let (v, t) = if entry & CLIPPED != 0 {
                    bin.clipped[(entry & !CLIPPED) as usize]
                } else {
                    (tris[entry as usize].map(|i| p.screen[i as usize]), entry)
                };
                sink.triangle(ItemId { object: chunk.object as u32, triangle: t }, v);
                scan_triangle(&v.map(ScreenVertex::point), rows.clone(), sink);
            }
        }
    }
}

fn clamp(r: Range<i64>, to: &Range<i64>) -> Range<i64> {
    r.start.max(to.start)..r.end.min(to.end)
}

/// Depth as a plane over the screen: `z(x, y) = c + dx·x + dy·y` at the centre of
/// pixel (x, y). Reversed depth divided by w is linear in screen space.
#[derive(Debug, Clone, Copy, Default)]
struct DepthPlane {
    c: f64,
    dx: f64,
    dy: f64,
}

impl DepthPlane {
    fn new(v: &[ScreenVertex; 3]) -> Self {
        let s = 1.0 / ONE as f64;
        let [(x0, y0, z0), (x1, y1, z1), (x2, y2, z2)] = v.map(|p| (p.x as f64 * s, p.y as f64 * s, p.z as f64));
        let area = (x1 - x0) * (y2 - y0) - (x2 - x0) * (y1 - y0);
        let dx = ((z1 - z0) * (y2 - y0) - (z2 - z0) * (y1 - y0)) / area;
        let dy = ((z2 - z0) * (x1 - x0) - (z1 - z0) * (x2 - x0)) / area;
        DepthPlane { c: z0 + dx * (0.5 - x0) + dy * (0.5 - y0), dx, dy }
    }
}

/// A triangle's depth plane, worked out at its first span: most triangles of
/// a dense mesh in a shadow map cover no texel centre and need none (two
/// divisions saved each).
#[derive(Debug, Clone, Copy)]
enum LazyPlane {
    Vertices([ScreenVertex; 3]),
    Plane(DepthPlane),
}

impl Default for LazyPlane {
    fn default() -> Self {
        LazyPlane::Plane(DepthPlane::default())
    }
}

impl LazyPlane {
    fn get(&mut self) -> DepthPlane {
        match *self {
            LazyPlane::Plane(p) => p,
            LazyPlane::Vertices(v) => {
                let p = DepthPlane::new(&v);
                *self = LazyPlane::Plane(p);
                p
            }
        }
    }
}

/// Where a band's spans go: told each triangle before its spans.
trait BandSink: SpanSink {
    fn triangle(&mut self, item: ItemId, v: [ScreenVertex; 3]);
}

impl BandSink for DepthSink<'_> {
    fn triangle(&mut self, item: ItemId, v: [ScreenVertex; 3]) {
        (self.item, self.plane) = (item, LazyPlane::Vertices(v));
        if let Some(cutouts) = self.cutouts {
            self.cutout = cutouts.triangle(item);
        }
    }
}

/// Lists the samples of a band's spans that lie in front of the opaque depth.
struct FragmentSink<'a> {
    /// The band's stored depths.
    opaque: &'a [f32],
    stride: i64,
    /// The columns drawn (and stored).
    cols: Range<i64>,
    row0: i64,
    /// The stored index of the band's first pixel.
    first_pixel: u32,
    plane: LazyPlane,
    item: ItemId,
    out: Vec<Fragment>,
}

impl BandSink for FragmentSink<'_> {
    fn triangle(&mut self, item: ItemId, v: [ScreenVertex; 3]) {
        (self.item, self.plane) = (item, LazyPlane::Vertices(v));
    }
}

impl SpanSink for FragmentSink<'_> {
    fn span(&mut self, y: i64, x0: i64, x1: i64) {
        let (x0, x1) = (x0.max(self.cols.start), x1.min(self.cols.end));
        let plane = self.plane.get();
        let row_z = plane.c + plane.dy * y as f64;
        let base = (y - self.row0) * self.stride - self.cols.start;
        for x in x0..x1 {
            let z = (row_z + plane.dx * x as f64) as f32;
            if z > self.opaque[(base + x) as usize] {
                let pixel = self.first_pixel + (base + x) as u32;
                self.out.push(Fragment { pixel, depth: z, item: self.item });
            }
        }
    }
}

/// Writes spans into a band's rows with a z-test (larger depth wins, ties keep the
/// earlier triangle); depth only when the band has no item slice.
struct DepthSink<'a> {
    depth: &'a mut [f32],
    items: &'a mut [ItemId],
    stride: i64,
    /// The columns drawn (and stored).
    cols: Range<i64>,
    row0: i64,
    plane: LazyPlane,
    item: ItemId,
    /// The scene's alpha tests, where some material has one.
    cutouts: Option<&'a Cutouts<'a>>,
    /// The current triangle's alpha test, where its material has one.
    cutout: Option<CutoutTriangle<'a>>,
}

impl SpanSink for DepthSink<'_> {
    fn span(&mut self, y: i64, x0: i64, x1: i64) {
        let (x0, x1) = (x0.max(self.cols.start), x1.min(self.cols.end));
        if x0 >= x1 {
            return;
        }
        // Where column 0 of row y would be stored (a column's place is this
        // plus the column: the drawn columns alone are stored).
        let base = (y - self.row0) * self.stride - self.cols.start;
        let plane = self.plane.get();
        let row_z = plane.c + plane.dy * y as f64;
        if let Some(cutout) = &self.cutout {
            // A cut-out triangle: the z-test, then the alpha test.
            for x in x0..x1 {
                let z = (row_z + plane.dx * x as f64) as f32;
                let at = (base + x) as usize;
                if z > self.depth[at] && cutout.covers(x, y) {
                    self.depth[at] = z;
                    if let Some(it) = self.items.get_mut(at) {
                        *it = self.item;
                    }
                }
            }
            return;
        }
        let depth = &mut self.depth[(base + x0) as usize..(base + x1) as usize];
        let items = match self.items.is_empty() {
            true => None,
            false => Some(&mut self.items[(base + x0) as usize..(base + x1) as usize]),
        };
        span_z_test(depth, items, self.item, row_z, plane.dx, x0);
    }
}

/// The z-test of one span: each pixel from column `x0` on takes depth
/// `row_z + dx · x` (in f64, then rounded to f32) where that is nearer than
/// `depth` holds, and `item` with it (`items`: none for a depth-only buffer).
/// Eight pixels at a time: their depths worked out in lanes (the same
/// operations in the same order as one pixel's, so the same bits), compared
/// and blended at once, items written only where a lane won; the span's last
/// pixels one by one.
#[inline]
fn span_z_test(depth: &mut [f32], mut items: Option<&mut [ItemId]>, item: ItemId, row_z: f64, dx: f64, x0: i64) {
    const LANES: usize = 8;
    // Columns as f64 counted up from x0 (whole numbers, exact): no i64 to
    // f64 conversion a pixel, which has no vector form before AVX-512.
    let z_at = |x: f64| (row_z + dx * x) as f32;
    let whole = depth.len() / LANES * LANES;
    for k in (0..whole).step_by(LANES) {
        let x = (x0 + k as i64) as f64;
        let z = f32x8::new(std::array::from_fn(|j| z_at(x + j as f64)));
        let block: &mut [f32; LANES] = (&mut depth[k..k + LANES]).try_into().expect("eight pixels");
        let held = f32x8::new(*block);
        let nearer = z.simd_gt(held);
        let won = nearer.to_bitmask();
        if won == 0 {
            continue;
        }
        *block = nearer.bitselect(z, held).to_array();
        if let Some(items) = items.as_deref_mut() {
            let items = &mut items[k..k + LANES];
            if won == 0xff {
                items.fill(item);
            } else {
                set_bits(won).for_each(|j| items[j] = item);
            }
        }
    }
    for k in whole..depth.len() {
        let z = z_at((x0 + k as i64) as f64);
        if z > depth[k] {
            depth[k] = z;
            if let Some(items) = items.as_deref_mut() {
                items[k] = item;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use rand::rngs::StdRng;
    use rand::{Rng, SeedableRng};

    use super::{span_z_test, ItemId};

    /// The span's z-test one pixel at a time, as the formula says: the
    /// oracle of the eight-lane test.
    fn one_by_one(depth: &mut [f32], items: &mut [ItemId], item: ItemId, row_z: f64, dx: f64, x0: i64) {
        for (k, (d, it)) in depth.iter_mut().zip(items.iter_mut()).enumerate() {
            let z = (row_z + dx * (x0 + k as i64) as f64) as f32;
            if z > *d {
                (*d, *it) = (z, item);
            }
        }
    }

    /// Spans of every length up to 40 from random columns, over held depths
    /// drawn near the span's own (ties and lanes won in part included): the
    /// same depth bits and items as one pixel at a time, with and without
    /// items.
    #[test]
    fn eight_lane_spans_write_what_one_pixel_at_a_time_does() {
        let mut rng = StdRng::seed_from_u64(11);
        for round in 0..3000 {
            let n = round % 41;
            let (x0, row_z, dx) = (rng.gen_range(-20..5000), rng.gen_range(0.0..1.0), rng.gen_range(-1e-3..1e-3));
            let item = ItemId { object: 7, triangle: round as u32 };
            let held: Vec<f32> = (0..n)
                .map(|k| {
                    let own = (row_z + dx * (x0 + k as i64) as f64) as f32;
                    match rng.gen_range(0..4) {
                        0 => own,
                        1 => own + rng.gen_range(-1e-4..1e-4),
                        2 => 0.0,
                        _ => rng.gen_range(0.0..1.0),
                    }
                })
                .collect();
            let before: Vec<ItemId> = (0..n).map(|k| ItemId { object: 1, triangle: k as u32 }).collect();
            let (mut want, mut want_items) = (held.clone(), before.clone());
            one_by_one(&mut want, &mut want_items, item, row_z, dx, x0);
            let (mut got, mut got_items) = (held.clone(), before.clone());
            span_z_test(&mut got, Some(&mut got_items), item, row_z, dx, x0);
            let bits = |v: &[f32]| v.iter().map(|z| z.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&got), bits(&want), "round {round}: depths");
            assert_eq!(got_items, want_items, "round {round}: items");
            let mut depth_only = held.clone();
            span_z_test(&mut depth_only, None, item, row_z, dx, x0);
            assert_eq!(bits(&depth_only), bits(&want), "round {round}: a depth-only span");
        }
    }
}
