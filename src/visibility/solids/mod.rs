//! Scanline visibility of CSG solids (seed 003: Tokoi & Kitahashi 1988, §5).
//!
//! The frame is walked the paper's way: primitives are bucket-sorted by their
//! top scanline into the y-entry table; each scanline moves entering primitives
//! into the y-occupancy list and drops those whose bottom it passed, sorts the
//! occupants by left end into the x-entry table (and by right end, for leaving),
//! and walks its pixels keeping the x-occupancy list. A pixel with occupants gets
//! its visible surface from the depth intervals of the occupants only (seed
//! 003's procedure 3 in closed form, [`crate::csg`]), clipped at the
//! near plane as polygons are. Intervals come eight pixels of a scanline at a
//! time (one SIMD pass per occupant and block, `BlockSpans`), and a polyhedron
//! of many planes is clipped only by the faces the scanline's plane meets.
//! [`draw_solids`] writes the result into the frame's visibility buffer (depth,
//! item = object + primitive, normal) or a light's depth map, z-tested against
//! the polygons already there.
//!
//! Segments and reference counts (§5.2.1), in tree form. The paper expands the
//! expression into a sum of products (its pattern matrix) and keeps, per
//! segment, a count of its primitives not yet occupying the pixel; a segment
//! whose count is zero enters the visible-segment list. Expanding can explode
//! (the paper names it; OpenSCAD aborts previews past 100,000 terms), so the
//! tree is not expanded: the same counts are kept at every node of it
//! (`csg/occupancy.rs`). A primitive entering or leaving the x-occupancy list
//! updates its leaf and the few nodes above it whose emptiness changes; the
//! root's list of non-empty operands is the visible-segment list, a
//! difference's list of non-empty cutters is the fast path for negative
//! primitives, and a pixel's booleans visit only what is non-empty there.
//!
//! Coherence (§5.2.2): the paper reuses a pixel's answer at the next pixel
//! unless a primitive entered or left or the depth order changed. kage has it
//! exactly as the paper puts it ([`paper::coherence`],
//! `CsgMethod::SegmentsCoherent`), but measured on the corpus, checking the
//! order at every pixel costs about what the booleans of the few primitives
//! there cost, and the order of many primitives' ends breaks too often to
//! pay. By default the walk takes it a block at a time instead
//! (`block.rs`): in an eight-pixel block no occupant enters or leaves,
//! the booleans run at its first pixel, and their answer goes to the other
//! seven when the ends before it keep their order at all eight (checked in
//! lanes, once per block); ends behind the surface may swap.
//!
//! Depth (beyond the paper): most of a pixel's occupants on a part of many
//! features lie behind its surface. Where the booleans run, the occupants
//! whose interval starts beyond a horizon guessed a little past the surface
//! of the pixel before are left out, and the answer is kept when it provably
//! is the whole tree's (`horizon.rs`).
//!
//! Extents (procedures 1 and 2): an ellipsoid seen in perspective from outside
//! gets the paper's exact rows (scanline planes through the eye tangent to it)
//! and, per scanline, exact left and right ends (lines through the eye tangent to
//! it), both closed-form quadratics. A polyhedron's projection is the convex hull
//! of its projected corners: its rows and, per scanline, its ends are exact. A
//! frustum gets the hull of a circumscribed 16-sided prism (at most 2% wide).
//! Anything with a corner at or behind the eye, and spheres under an
//! orthographic camera, fall back to their box. A too-wide extent only costs
//! time: where a primitive does not reach, its interval is empty.
//!
//! A tile of a frame walks its own pixels alone: its rows, and on each row
//! each occupant's ends cut to its columns (closed meshes are rasterized on
//! its rectangle alone too); what it draws equals the whole frame's there.

mod block;
mod bounds;
mod cut_region;
mod horizon;
mod layers;
pub mod paper;
mod spans;
mod surface_frame;
mod zbuffer;

pub use surface_frame::SurfaceFrame;

use std::cell::{Cell, RefCell};

use glam::{Vec2, Vec3};
use rayon::iter::IndexedParallelIterator;
use rayon::prelude::*;

use crate::camera::{Camera, PixelRays, RowLine};
use crate::csg::occupancy::{OccupancyTree, Occupied};
use crate::csg::outline::{screen_point, Extent, Outline};
use crate::csg::{Crossing, CsgCaster, CsgSolid, FacesOnScreen, Hit, Primitive, SpanScratch};
use crate::image::PixelRect;
use crate::scene::Scene;
use crate::visibility::{ItemId, VisibilityBuffer};
use block::BlockOrder;
use bounds::BoundingLeaves;
use cut_region::CutRegions;
use horizon::Horizon;
use layers::MeshLayers;
use paper::coherence::{self, PixelCoherence};
use paper::pattern::{PatternMatrix, TooManySegments};
use spans::{BlockSpans, PixelSpans, RowRun, RowSpans};
use surface_frame::row_to_write;
use zbuffer::{DepthEnds, UnionRow};

/// Rows scanned by one worker in turn, each band a task of its own
/// ([`scan_bands`]): 16 rows were a few per cent sooner than 8 on the median
/// models, 12 alike, 32 slower (`docs/benchmarks.md`, "Design measurements").
const BAND_ROWS: usize = 16;

/// The visible surface of `solid` (in world space) at each pixel centre of a
/// `width` x `height` image seen by `camera`, rows top to bottom: the first
/// crossing beyond the near plane, or `None`.
#[must_use]
pub fn scan_solid(solid: &CsgSolid, camera: &Camera, width: u32, height: u32) -> Vec<Option<Crossing>> {
    scan_solid_with(solid, camera, width, height, CsgMethod::Segments).expect("segments need no expansion")
}

/// How a scanline's pixels find their surface.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CsgMethod {
    /// The tree's own segments, cut down to the occupants (no expansion),
    /// an eight-pixel block's answer found at its first pixel and spread to
    /// the others where it provably holds (`block.rs`; the default).
    Segments,
    /// [`CsgMethod::Segments`] with the booleans run at every pixel: the
    /// same surfaces to the bit (what the spreading is tested against).
    SegmentsEachPixel,
    /// [`CsgMethod::SegmentsEachPixel`] with a pixel's answer reused along
    /// the scanline while the order of every end holds (seed 003 §5.2.2 as
    /// the paper has it; [`paper::coherence`]): the same surfaces to the
    /// bit, measured slower on every corpus model.
    SegmentsCoherent,
    /// The paper's pattern matrix ([`paper::pattern`]), expanded up to `limit`
    /// segments.
    PatternMatrix {
        /// Most segments the expansion may make.
        limit: usize,
    },
}

/// [`scan_solid`] by `method`; fails when the pattern matrix would pass its
/// limit.
///
/// # Errors
///
/// [`TooManySegments`] when `method` is the pattern matrix and the solid
/// expands past its limit.
pub fn scan_solid_with(
    solid: &CsgSolid,
    camera: &Camera,
    width: u32,
    height: u32,
    method: CsgMethod,
) -> Result<Vec<Option<Crossing>>, TooManySegments> {
    let mut out = SurfaceFrame::new();
    scan_solid_into(solid, camera, (width, height), method, &mut out)?;
    Ok(out.into_pixels())
}

/// [`scan_solid_with`] into `out` (made the image's size), so a viewer
/// re-scanning frame after frame reuses one buffer, as the frame's
/// visibility buffer is reused, and clears only what the last scan wrote.
///
/// # Errors
///
/// As [`scan_solid_with`].
pub fn scan_solid_into(
    solid: &CsgSolid,
    camera: &Camera,
    (width, height): (u32, u32),
    method: CsgMethod,
    out: &mut SurfaceFrame,
) -> Result<(), TooManySegments> {
    PreparedSolid::new(solid, method)?.scan_into(camera, (width, height), out);
    Ok(())
}

/// A solid made ready for seed 003's scanline walk frame after frame, as a
/// viewer keeps it while only the camera moves: its primitives prepared for
/// casting (inverse transforms, normal matrices, a polyhedron's faces and
/// their corners), its tree for the walk (the occupancy tree, or the pattern
/// matrix expanded) and each primitive's bounding leaves.
pub struct PreparedSolid {
    caster: CsgCaster,
    walker: RowWalker,
    /// Per primitive, the leaves outside whose outlines it cannot change
    /// the solid ([`super::bounds`]).
    bounds: BoundingLeaves,
    /// Per cutter, where in space it can change the solid ([`super::cut_region`]).
    regions: CutRegions,
}

impl PreparedSolid {
    /// `solid` made ready to be walked by `method`; fails when the pattern
    /// matrix would pass its limit.
    ///
    /// # Errors
    ///
    /// As [`scan_solid_with`].
    pub fn new(solid: &CsgSolid, method: CsgMethod) -> Result<PreparedSolid, TooManySegments> {
        let bounds = solid.tree.as_ref().map(|t| BoundingLeaves::new(t, solid.primitives.len())).unwrap_or_default();
        let (caster, walker) = (CsgCaster::without_bvh(solid), RowWalker::new(solid, method)?);
        let regions = match (&walker, &solid.tree) {
            (RowWalker::Segments(walk), _) => CutRegions::new(solid, &caster, &walk.tree),
            (_, Some(tree)) => CutRegions::new(solid, &caster, &OccupancyTree::new(tree, solid.primitives.len())),
            (_, None) => CutRegions::default(),
        };
        Ok(PreparedSolid { caster, walker, bounds, regions })
    }

    /// The visible surface at each pixel centre of a `width` x `height`
    /// image seen by `camera`, into `out` (made the image's size), as
    /// [`scan_solid_with`] finds it.
    pub fn scan_into(&self, camera: &Camera, (width, height): (u32, u32), out: &mut SurfaceFrame) {
        let w = width as usize;
        out.fit(w, height as usize);
        if matches!(self.walker, RowWalker::Empty) {
            out.clear();
            return;
        }
        let bands = out.bands_mut(BAND_ROWS);
        let whole = PixelRect::full(width, height);
        scan_bands(self, camera, (width, height), whole, bands, |(pixels, written), dy, row| {
            let out = row_to_write(&mut pixels[dy * w..(dy + 1) * w], &mut written[dy], row.blocks());
            row.unit_crossings_into(out);
        });
    }
}

/// What walks a scanline's pixels.
enum RowWalker {
    Segments(SegmentWalk),
    Pattern(PatternMatrix),
    /// A solid with no volume.
    Empty,
}

impl RowWalker {
    fn new(solid: &CsgSolid, method: CsgMethod) -> Result<RowWalker, TooManySegments> {
        let n = solid.primitives.len();
        let Some(tree) = &solid.tree else { return Ok(RowWalker::Empty) };
        Ok(match method {
            CsgMethod::Segments | CsgMethod::SegmentsEachPixel | CsgMethod::SegmentsCoherent => {
                let reuse = match method {
                    CsgMethod::Segments => Reuse::Blocks,
                    CsgMethod::SegmentsCoherent => Reuse::Pixels,
                    _ => Reuse::Never,
                };
                let shape = OccupancyTree::new(tree, n);
                let union = shape.is_union_of_leaves();
                RowWalker::Segments(SegmentWalk {
                    horizon: reuse == Reuse::Blocks && !union,
                    nearest_entries: reuse == Reuse::Blocks && union,
                    tree: shape,
                    cut_with: if reuse == Reuse::Pixels { coherence::cut_with(tree, n) } else { Vec::new() },
                    reuse,
                })
            }
            CsgMethod::PatternMatrix { limit } => RowWalker::Pattern(PatternMatrix::expand(tree, n, limit)?),
        })
    }
}

/// The walk of the tree's own segments.
struct SegmentWalk {
    tree: OccupancyTree,
    /// Per primitive, whether a difference cuts with it (reusing by pixels).
    cut_with: Vec<bool>,
    /// How an answer is reused along the scanline (seed 003 §5.2.2).
    reuse: Reuse,
    /// Whether the booleans leave out occupants beyond a guessed horizon
    /// (`horizon.rs`): not pixel by pixel (the tests' oracle), and not
    /// for a union of primitives, whose booleans read each occupant once
    /// anyway (where leaving some out saved nothing and the second passes
    /// at silhouettes cost: the paper's random spheres).
    horizon: bool,
    /// Whether a row's pixels take the nearest entry of their occupants,
    /// found a block of eight pixels at a time ([`super::zbuffer`]): a union
    /// of primitives, not pixel by pixel (the tests' oracle).
    nearest_entries: bool,
}

/// How the segment walk reuses an answer along a scanline.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Reuse {
    /// An eight-pixel block's, where it provably holds ([`super::block`]).
    Blocks,
    /// A pixel's, while the order of every end holds ([`super::coherence`]).
    Pixels,
    /// None: the booleans at every pixel.
    Never,
}

/// Draws every solid of `scene` whose object index `include` takes, seen by `camera`, into
/// `vb` (after its polygons): where a solid's visible surface lies nearer than
/// what the pixel holds and between the near and far planes, the pixel takes
/// its depth, its item (object + primitive) and its outward normal. A
/// depth-only buffer (a shadow map) takes the depth alone. Returns the number
/// of solids drawn.
pub fn draw_solids(
    scene: &Scene,
    camera: &Camera,
    include: impl Fn(usize) -> bool,
    vb: &mut VisibilityBuffer,
) -> usize {
    let (width, height) = (vb.width(), vb.height());
    let far = camera.far_plane_factor();
    // The buffer holds the pixels of its rectangle alone, row-major from its
    // top left pixel; bands count from its first row.
    let held = vb.rect();
    let cols = held.x0 as usize..held.x1 as usize;
    let w = cols.len();
    let mut drawn = 0;
    for (object, o) in scene.objects.iter().enumerate().filter(|(i, _)| include(*i)) {
        let Some(solid) = o.solid() else { continue };
        let world = solid.transformed(&o.transform);
        let (depth, items, normals) = vb.solid_parts_mut();
        let n = w * BAND_ROWS;
        let (mut items, mut normals) = (items.chunks_mut(n), normals.chunks_mut(n));
        // Depth-only buffers have no items or normals, a map that keeps items no
        // normals: their bands get empty slices.
        let bands: Vec<(&mut [f32], &mut [ItemId], &mut [Vec3])> = depth
            .chunks_mut(n)
            .map(|d| (d, items.next().unwrap_or(&mut []), normals.next().unwrap_or(&mut [])))
            .collect();
        let bands = bands.into_par_iter().enumerate();
        let prepared = PreparedSolid::new(&world, CsgMethod::Segments).expect("segments need no expansion");
        scan_bands(&prepared, camera, (width, height), held, bands, |(_, (depth, items, normals)), dy, row| {
            for (x, h) in row.hits().filter(|(x, _)| cols.contains(x)) {
                // A hit's `t` along its row line is its distance along the view axis.
                let z = camera.depth_at_view_distance(h.t);
                let i = dy * w + x - cols.start;
                if z > depth[i] && z >= far && z <= 1.0 {
                    depth[i] = z;
                    // A depth map needs no item or normal.
                    if !items.is_empty() {
                        items[i] = ItemId::primitive_of(object as u32, h.primitive);
                    }
                    if !normals.is_empty() {
                        normals[i] = row.crossing(x, h).normal;
                    }
                }
            }
        });
        drawn += 1;
    }
    drawn
}

/// One scanned row as the walk hands it on: each pixel's visible [`Hit`], its
/// `t` counted along the row's rays `line` (the distance along the view
/// axis), and what gives a hit its normal.
struct ScannedRow<'a> {
    /// Every pixel's hit (`None` outside `columns`).
    hits: &'a [Option<Hit>],
    /// The columns that may hold hits.
    columns: std::ops::Range<usize>,
    line: &'a RowLine,
    /// The row's rays in each occupant's unit space.
    units: &'a [RowLine],
    caster: &'a CsgCaster,
    /// The last flat face given a normal: a hit on it, and its crossing.
    flat: Cell<Option<(Hit, Crossing)>>,
}

impl ScannedRow<'_> {
    /// The hits of the columns that may hold any, with their columns.
    fn hits(&self) -> impl Iterator<Item = (usize, Hit)> + '_ {
        let hits = &self.hits[self.columns.clone()];
        self.columns.clone().zip(hits).filter_map(|(x, h)| Some((x, (*h)?)))
    }

    /// The columns of the eight-pixel blocks that take in [`Self::columns`]
    /// (the last cut short by the row's end).
    fn blocks(&self) -> std::ops::Range<usize> {
        if self.columns.is_empty() {
            return 0..0;
        }
        self.columns.start / 8 * 8..self.columns.end.next_multiple_of(8).min(self.hits.len())
    }

    /// Into `out` (the row's pixels), each pixel's crossing
    /// ([`Self::crossing`]) over [`Self::blocks`], eight at a time, `t` taken
    /// along each pixel's unit ray (the row line's direction is not of unit
    /// length). A block showing one curved face at all eight pixels finds
    /// their normals in lanes, one showing a flat face shares one normal.
    fn unit_crossings_into(&self, out: &mut [Option<Crossing>]) {
        for x0 in self.blocks().step_by(8) {
            let end = (x0 + 8).min(self.hits.len());
            let (hits, out) = (&self.hits[x0..end], &mut out[x0..end]);
            let lengths = wide::f32x8::new(self.line.dir_lengths(x0));
            if let (Ok(hits), Some(first)) = (<&[Option<Hit>; 8]>::try_from(hits), hits[0]) {
                if hits.iter().all(|h| h.is_some_and(|h| h.same_face(&first))) {
                    let t = hits.map(|h| h.map_or(0.0, |h| h.t));
                    let along = (wide::f32x8::new(t) * lengths).to_array();
                    if self.caster.flat(first) {
                        let c = self.crossing(x0, first);
                        out.iter_mut().zip(along).for_each(|(o, t)| *o = Some(Crossing { t, ..c }));
                    } else {
                        let unit = &self.units[first.primitive as usize];
                        let found = self.caster.crossings_on_eight(first, t, unit, x0);
                        out.iter_mut().zip(along).zip(found).for_each(|((o, t), c)| *o = Some(Crossing { t, ..c }));
                    }
                    continue;
                }
            }
            let lengths = lengths.to_array();
            for (j, (o, h)) in out.iter_mut().zip(hits).enumerate() {
                *o = h.map(|h| Crossing { t: h.t * lengths[j], ..self.crossing(x0 + j, h) });
            }
        }
    }

    /// Pixel `x`'s `hit` with its outward normal (a flat face's computed
    /// once while pixel after pixel shows it).
    #[inline]
    fn crossing(&self, x: usize, hit: Hit) -> Crossing {
        if let Some((_, c)) = self.flat.get().filter(|(h, _)| h.same_face(&hit)) {
            return Crossing { t: hit.t, ..c };
        }
        let c = self.caster.crossing_on_line(hit, &self.units[hit.primitive as usize], x as f32);
        if self.caster.flat(hit) {
            self.flat.set(Some((hit, c)));
        }
        c
    }
}

/// The walk itself: for each band of [`BAND_ROWS`] rows from the first of
/// `window` (in parallel, `bands` gives each its output), `visit(band,
/// row_in_band, row)` with the row's visible hits ([`ScannedRow`]), for the
/// rows of `window`, each row walked over the columns of `window` alone.
fn scan_bands<B: Send>(
    prepared: &PreparedSolid,
    camera: &Camera,
    (width, height): (u32, u32),
    window: PixelRect,
    bands: impl IndexedParallelIterator<Item = B>,
    visit: impl Fn(&mut B, usize, &ScannedRow) + Sync,
) {
    let walker = &prepared.walker;
    if matches!(walker, RowWalker::Empty) {
        return;
    }
    // The whole frame in the pool: its preparation's parallel parts and
    // the bands start no second time from outside it.
    rayon::scope(|_| {
        let rows = window.y0 as usize..window.y1 as usize;
        let frame = FrameWalk::new(prepared, camera, (width, height), window);
        let h = height as usize;
        // Each band its own piece of work: left to split only where stolen,
        // rayon hands each thread a quarter of the frame, and a thread done
        // with its own finds the rest of the other's unsplittable (a second
        // thread could sit idle for the last part of the frame).
        bands.enumerate().with_max_len(1).for_each_init(
            || Lent::fitted(width as usize, prepared.caster.solid().primitives.len(), walker),
            |lent, (band, mut out)| {
                let first = rows.start + band * BAND_ROWS;
                let mut occupancy = YOccupancy::at(&frame.entry, first as i64);
                for dy in 0..BAND_ROWS.min(rows.end.min(h).saturating_sub(first)) {
                    let y = first + dy;
                    let occupied = occupancy.advance(y as i64);
                    frame.walk_row(y, occupied, &mut lent.0, |row| visit(&mut out, dy, row));
                }
            },
        );
    });
}

/// What a frame's walk knows before its first scanline: each primitive's
/// outline on the screen, the y-entry table, the caster, where each face of a
/// many-planed polyhedron shows, and the pixels' rays.
struct FrameWalk<'a> {
    walker: &'a RowWalker,
    outlines: Vec<Option<Outline>>,
    /// Per primitive, the leaves outside whose outlines it cannot change
    /// the solid ([`super::bounds`]).
    bounds: &'a BoundingLeaves,
    /// The y-entry table (procedure 1): the primitives that show at all, by
    /// top scanline.
    entry: Vec<(usize, Extent)>,
    caster: &'a CsgCaster,
    /// Per primitive, where its faces show ([`CsgCaster::faces_on_screen`]:
    /// polyhedra of many planes).
    faces: Vec<Option<FacesOnScreen>>,
    /// The closed meshes' layers at every pixel.
    layers: MeshLayers,
    rays: PixelRays,
    /// Along a row line's direction (unit component along the view axis),
    /// the near plane lies at t = near, under either projection.
    near: f32,
    width: usize,
    /// The columns walked (a tile's own; the others are left empty).
    columns: (i64, i64),
}

impl<'a> FrameWalk<'a> {
    /// Primitives from which a frame's outlines and faces are found in
    /// parallel.
    const PARALLEL_FROM: usize = 16;

    /// The frame of `solid` seen by `camera` at `width` x `height`, walked by
    /// `walker` over the pixels of `window`.
    fn new(prepared: &'a PreparedSolid, camera: &Camera, (width, height): (u32, u32), window: PixelRect) -> Self {
        let (caster, solid) = (&prepared.caster, prepared.caster.solid());
        let vp = camera.view_projection(width as f32 / height as f32);
        let rays = camera.pixel_rays(Vec2::new(width as f32, height as f32));
        let many = solid.primitives.len() >= Self::PARALLEL_FROM;
        let outlines = || -> Vec<Option<Outline>> {
            let outline = |p: &Primitive| Outline::new(p, vp, &rays);
            if many {
                solid.primitives.par_iter().map(outline).collect()
            } else {
                solid.primitives.iter().map(outline).collect()
            }
        };
        let faces = || -> Vec<Option<FacesOnScreen>> {
            let size = (width as usize, height as usize);
            let face = |i: usize| caster.faces_on_screen(i, |p| screen_point(p, vp, (width, height)), size);
            let n = solid.primitives.len();
            if many {
                (0..n).into_par_iter().map(face).collect()
            } else {
                (0..n).map(face).collect()
            }
        };
        // Many primitives: each primitive's outline and faces at once.
        let (outlines, faces) = if many { rayon::join(outlines, faces) } else { (outlines(), faces()) };
        // A closed mesh's layers show where its rasterized pixels say.
        let layers = MeshLayers::new(caster, vp, &rays, (width as usize, height as usize), window);
        let mut outlines: Vec<Option<Outline>> =
            outlines.into_iter().enumerate().map(|(i, o)| layers.narrow(i, o)).collect();
        if let Some(tree) = &solid.tree {
            let mut boxes: Vec<Option<Extent>> = outlines.iter().map(|o| o.as_ref().map(|o| o.rows)).collect();
            bounds::narrow(tree, &mut boxes);
            for (i, b) in boxes.iter_mut().enumerate() {
                *b = prepared.regions.narrow(i, *b, camera, vp, (width, height));
            }
            for (o, b) in outlines.iter_mut().zip(boxes) {
                match (o.as_mut(), b) {
                    (Some(o), Some(b)) => o.rows = b,
                    _ => *o = None,
                }
            }
        }
        let mut entry: Vec<(usize, Extent)> =
            outlines.iter().enumerate().filter_map(|(i, o)| o.as_ref().map(|o| (i, o.rows))).collect();
        entry.sort_by_key(|(_, e)| e.y0);
        FrameWalk {
            walker: &prepared.walker,
            outlines,
            bounds: &prepared.bounds,
            entry,
            caster,
            faces,
            layers,
            rays,
            near: camera.near,
            width: width as usize,
            columns: (i64::from(window.x0), i64::from(window.x1) - 1),
        }
    }

    /// Procedure 2 on row `y` for each of the `occupied`: their ends, each
    /// clipped to the ends of the leaves that bound it, into `ends` (`own`
    /// keeps every occupant's unclipped ends, stamped with the row).
    fn ends(&self, y: usize, occupied: &[(usize, Extent)], own: &mut [OwnEnds], ends: &mut Vec<RowEnds>) {
        for &(i, _) in occupied {
            own[i] = (y, self.outlines[i].as_ref().and_then(|o| o.columns(y as i64)));
        }
        let clipped = |i: usize| {
            let (mut a, mut b) = own[i].1?;
            for &q in self.bounds.of(i) {
                // A bound that does not occupy the row leaves nothing.
                let (row, ends) = own[q as usize];
                let (c, d) = ends.filter(|_| row == y)?;
                (a, b) = (a.max(c), b.min(d));
            }
            // Only the window's columns.
            (a, b) = (a.max(self.columns.0), b.min(self.columns.1));
            (a <= b).then_some((i, a, b))
        };
        ends.clear();
        ends.extend(occupied.iter().filter_map(|&(i, _)| clipped(i)));
    }

    /// A union's row by [`RowSpans::nearest_entries`], the occupants `ends`
    /// taken nearest first; `false`, the row left empty, where the booleans
    /// must find it.
    fn nearest_entries(
        &self,
        ends: &[RowEnds],
        spans: &RowSpans,
        row: &mut [Option<Hit>],
        by_depth: &mut Vec<DepthEnds>,
        union: &mut UnionRow,
    ) -> bool {
        let nearest = |i: usize| self.outlines[i].as_ref().map_or(f32::MIN, |o| o.nearest);
        by_depth.clear();
        by_depth.extend(ends.iter().map(|&(i, a, b)| (i, a, b, nearest(i))));
        by_depth.sort_unstable_by(|p, q| p.3.total_cmp(&q.3));
        let found = spans.nearest_entries(by_depth, self.near, row, union);
        if !found {
            row.fill(None);
        }
        found
    }

    /// Scanline `y`, its y-occupancy list `occupied`, walked with `buffers`:
    /// `visit` is handed the row's hits.
    fn walk_row(
        &self,
        y: usize,
        occupied: &[(usize, Extent)],
        buffers: &mut RowBuffers,
        visit: impl FnOnce(&ScannedRow),
    ) {
        let RowBuffers { row, lines, own_ends, ends, scan, blocks, by_depth, union } = buffers;
        let caster = self.caster;
        // Procedure 2: each occupant's left and right ends on this scanline.
        self.ends(y, occupied, own_ends, ends);
        let ends = &*ends;
        // The columns the occupants may cover: the walk writes no other.
        debug_assert!(row.iter().all(Option::is_none), "row {y}: hits left from the row before");
        let w = self.width as i64;
        let lo = ends.iter().map(|e| e.1).min().unwrap_or(0).clamp(0, w) as usize;
        let hi = ends.iter().map(|e| e.2 + 1).max().unwrap_or(0).clamp(lo as i64, w) as usize;
        // The row's rays, carried into each occupant's unit space once.
        let line = self.rays.row_line(y);
        ends.iter().for_each(|&(i, _, _)| lines[i] = caster.unit_line(i, &line));
        blocks.begin_row(caster, ends.iter().map(|e| e.0), lines, &self.faces, y);
        let spans = RowSpans { blocks, caster, lines, layers: &self.layers, y };
        match self.walker {
            RowWalker::Segments(walk) => {
                if !(walk.nearest_entries && self.nearest_entries(ends, &spans, row, by_depth, union)) {
                    scan_row(walk, &spans, self.near, ends, row, scan);
                }
            }
            RowWalker::Pattern(matrix) => {
                let source = spans.source();
                matrix.walk_row(caster, ends, &|i, x| blocks.span(source, i, &lines[i], x), self.near, row);
            }
            RowWalker::Empty => {}
        }
        visit(&ScannedRow { hits: row, columns: lo..hi, line: &line, units: lines, caster, flat: Cell::new(None) });
        // Between rows, the row's hits are all None.
        row[lo..hi].fill(None);
    }
}

/// The y-occupancy list (seed 003 §5): the primitives whose rows take in
/// the scanline at hand, kept row by row down a band from the y-entry table.
struct YOccupancy<'a> {
    entry: &'a [(usize, Extent)],
    /// The first entry not yet met.
    next: usize,
    occupied: Vec<(usize, Extent)>,
}

impl<'a> YOccupancy<'a> {
    /// The list as scanline `first` finds it, from the y-entry table `entry`.
    fn at(entry: &'a [(usize, Extent)], first: i64) -> Self {
        let next = entry.partition_point(|(_, e)| e.y0 <= first);
        let occupied = entry[..next].iter().copied().filter(|(_, e)| e.y1 >= first).collect();
        YOccupancy { entry, next, occupied }
    }

    /// The list at scanline `y` (the one after the last asked for, or the
    /// first): those whose top is reached join, those whose bottom is
    /// passed leave.
    fn advance(&mut self, y: i64) -> &[(usize, Extent)] {
        while self.next < self.entry.len() && self.entry[self.next].1.y0 <= y {
            self.occupied.push(self.entry[self.next]);
            self.next += 1;
        }
        self.occupied.retain(|(_, e)| e.y1 >= y);
        &self.occupied
    }
}

/// One worker's buffers for walking scanlines: the row's hits (all `None`
/// between rows), each occupant's row line, the occupancy counts, the
/// booleans' stack, the eight-pixel blocks and the reusable answers. Kept
/// between pieces of work on the worker's thread ([`Lent`]): a solid of a
/// thousand primitives needs ~250 KB of them, and a scan hands out ~20 pieces.
#[derive(Default)]
struct RowBuffers {
    row: Vec<Option<Hit>>,
    lines: Vec<RowLine>,
    /// Per primitive, the row it last occupied and its unclipped ends there.
    own_ends: Vec<OwnEnds>,
    /// The row's occupants with their ends, clipped by their bounds.
    ends: Vec<RowEnds>,
    /// What the booleans' walk along the row keeps.
    scan: ScanBuffers,
    blocks: BlockSpans,
    /// A union's occupants, nearest first ([`RowSpans::nearest_entries`]).
    by_depth: Vec<DepthEnds>,
    union: UnionRow,
}

/// What [`scan_row`] keeps from row to row: the x-entry and x-exit tables,
/// the occupancy counts, the booleans' stack and the reused answers' state.
#[derive(Default)]
struct ScanBuffers {
    x_order: XOrder,
    counts: Occupied,
    scratch: SpanScratch,
    coherence: PixelCoherence,
    order: BlockOrder,
}

thread_local! {
    /// The [`RowBuffers`] the thread's last piece of work gave back.
    static SPARE_ROWS: RefCell<Option<RowBuffers>> = RefCell::default();
}

/// [`RowBuffers`] lent to a piece of work, given back to its thread when it
/// is done.
struct Lent(RowBuffers);

impl Lent {
    /// The thread's spare buffers (or new ones) sized for rows `width` wide
    /// of a solid of `primitives` walked by `walker`.
    fn fitted(width: usize, primitives: usize, walker: &RowWalker) -> Lent {
        let mut b = SPARE_ROWS.with_borrow_mut(Option::take).unwrap_or_default();
        b.row.resize(width, None);
        b.lines.resize(primitives, RowLine::default());
        // Rows of an earlier frame must not pass for this one's.
        b.own_ends.clear();
        b.own_ends.resize(primitives, (usize::MAX, None));
        if let RowWalker::Segments(walk) = walker {
            b.scan.counts.fit(&walk.tree);
        }
        b.blocks.fit(primitives);
        Lent(b)
    }
}

impl Drop for Lent {
    fn drop(&mut self) {
        let buffers = std::mem::take(&mut self.0);
        SPARE_ROWS.with_borrow_mut(|spare| *spare = Some(buffers));
    }
}

/// An occupant of a scanline: primitive, left end, right end (columns).
pub(super) type RowEnds = (usize, i64, i64);

/// A primitive's own ends on the row it last occupied: the row, and its
/// unclipped ends there (if it shows).
type OwnEnds = (usize, Option<(i64, i64)>);

/// A scanline's x-entry table (occupants by left end) and x-exit order (by
/// right end).
#[derive(Debug, Default)]
pub(super) struct XOrder {
    pub(super) entry: Vec<RowEnds>,
    pub(super) exit: Vec<RowEnds>,
}

impl XOrder {
    /// The tables of the occupants `ends` (what they held before dropped).
    pub(super) fn sort(&mut self, ends: impl IntoIterator<Item = RowEnds>) -> &Self {
        self.entry.clear();
        self.entry.extend(ends);
        self.entry.sort_by_key(|e| e.1);
        self.exit.clear();
        self.exit.extend_from_slice(&self.entry);
        self.exit.sort_by_key(|e| e.2);
        self
    }
}

/// Whether a row's walk spreads the booleans' answer from the first pixel
/// after an occupant entered or left inside a block (beyond the paper, which
/// reuses an answer only where nothing entered or left). It pays where at
/// least three of the block's pixels follow and the answer holds on for two
/// or more of them; on rows of many small parts (a Menger sponge, a printer
/// carriage of hundreds of primitives) it mostly stops at once, and the booleans pixel by
/// pixel cost less. A row starts out spreading and stops once such spreads
/// have failed twice more than they paid (two paid ones at most banked).
#[derive(Debug, Clone, Copy, Default)]
struct EventSpreads(i32);

impl EventSpreads {
    /// Whether to spread from pixel `x` along a run that ends at `upto`.
    fn worth(self, x: usize, upto: usize) -> bool {
        upto >= x + 3 && self.0 > -2
    }

    /// A spread from pixel `x` settled pixels up to `last`.
    fn paid(&mut self, x: usize, last: usize) {
        self.0 = if last >= x + 2 { (self.0 + 1).min(2) } else { self.0 - 1 };
    }
}

/// One scanline: the x-entry table of the occupants (sorted by left end), the
/// x-exit order (by right end), the x-occupancy list as the counts of
/// `occupied` (empty on entry and on return), and each occupied pixel's
/// surface from the non-empty part of the tree, reused as the walk's
/// [`Reuse`] says.
fn scan_row(
    walk: &SegmentWalk,
    spans: &RowSpans,
    near: f32,
    ends: &[RowEnds],
    row: &mut [Option<Hit>],
    buffers: &mut ScanBuffers,
) {
    let ScanBuffers { x_order, counts, scratch, coherence, order } = buffers;
    let (tree, caster) = (&walk.tree, spans.caster);
    let XOrder { entry, exit } = x_order.sort(ends.iter().copied());
    let (mut next_in, mut next_out) = (0, 0);
    let Some(first) = entry.first().map(|e| e.1.max(0) as usize) else { return };
    coherence.forget();
    let mut x = first;
    // The last surface found and its rise from the pixel before: where the
    // next pixel's horizon is guessed.
    let mut surface: Option<(f32, f32)> = None;
    // Whether the pixel before `x` was settled with the occupants `x` has.
    let mut steady = false;
    let mut event_spreads = EventSpreads::default();
    while x < row.len() {
        while next_in < entry.len() && entry[next_in].1 <= x as i64 {
            counts.set(tree, entry[next_in].0, true);
            coherence.forget();
            steady = false;
            next_in += 1;
        }
        // The last pixel this step settles: `x`, or the last its answer was
        // spread or carried to.
        let mut last = x;
        if let Some(root) = counts.root(tree) {
            // The run from `x` to its block's end that nothing enters or
            // leaves inside of (a right end leaves after its pixel). The
            // booleans' answer is spread along it from a block's first pixel,
            // and from the first after an occupant entered or left where
            // that is worth it ([`EventSpreads`]).
            let mut upto = (x | 7).min(row.len() - 1) as i64;
            upto = entry.get(next_in).map_or(upto, |e| upto.min(e.1 - 1));
            upto = exit.get(next_out).map_or(upto, |e| upto.min(e.2)).max(x as i64);
            let upto = upto as usize;
            let after_event = !steady && event_spreads.worth(x, upto);
            let spreading = walk.reuse == Reuse::Blocks && (x % 8 == 0 || after_event);
            // The answer of the pixel before carried on where it holds, or
            // the booleans' at `x` spread along the run.
            let ids = counts.present().ids();
            // (Carried only into a block's first pixel: the pixel before is
            // the last of the block before, whose lanes the walk keeps.)
            let carry = spreading && steady && x % 8 == 0;
            let carried = carry.then(|| spans.carry(order, ids, x, near, RowRun { row, upto })).flatten();
            if let Some(l) = carried {
                last = l;
            } else {
                let hit = if walk.reuse == Reuse::Pixels {
                    let present = counts.present();
                    coherence.look(present, near, |i| spans.at(i, x));
                    coherence.reused().unwrap_or_else(|| {
                        let hit = caster.first_hit_in_by(root, &|i| coherence.span(present, i), near, scratch);
                        coherence.learn(present, &walk.cut_with, hit);
                        hit
                    })
                } else if walk.horizon {
                    spans.first_hit(root, x, near, Horizon::guess(surface, ids.len()), scratch)
                } else {
                    caster.first_hit_in_by(root, &PixelSpans { row: spans, x }, near, scratch)
                };
                row[x] = hit;
                if spreading && upto > x {
                    last = spans.spread(order, ids, x, hit, near, RowRun { row: &mut *row, upto });
                    if x % 8 != 0 {
                        event_spreads.paid(x, last);
                    }
                }
            }
            if let Some(h) = row[last].filter(|_| walk.horizon) {
                let rise = row[last.saturating_sub(1)].map_or(0.0, |p| h.t - p.t);
                surface = Some((h.t, rise));
            }
            steady = true;
        } else {
            steady = false;
        }
        // Primitives whose right end is passed leave the x-occupancy list.
        while next_out < exit.len() && exit[next_out].2 <= last as i64 {
            counts.set(tree, exit[next_out].0, false);
            coherence.forget();
            steady = false;
            next_out += 1;
        }
        if next_out == exit.len() {
            break;
        }
        x = last + 1;
    }
    counts.clear(tree);
}
