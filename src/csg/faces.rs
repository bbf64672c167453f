//! Which faces of a many-planed polyhedron a block of eight pixels can cross
//! (seed 003 §5.2's coherence along a scanline, applied to a polyhedron's
//! faces: the rounded boxes that OpenSCAD's `hull()` makes, and every
//! sphere and cylinder in `--geometry faceted`, have hundreds of faces, and
//! a ray crosses two).
//!
//! A convex polyhedron's interval along a ray is its planes' latest entry and
//! earliest exit, and those are the faces the ray crosses: clipping by any
//! set of faces that holds them gives the same interval, to the bit (ties go
//! to the first face in rising order, and a face tied with the one crossed
//! contains the crossing, so it is in the set too). A ray that misses the
//! polyhedron is still missed when the set holds every face within a pixel of
//! the ray's pixel: the faces through the silhouette point nearest the pixel
//! bound a cone whose outline on the screen holds the silhouette, and the
//! pixel lies outside it. Three sieves, each keeping such a set:
//! - [`FaceCorners::met_by`]: the faces the plane of a scanline's rays meets;
//! - [`FacesOnScreen`]: per frame, the rows each face spans on the screen
//!   (its corners' projections, a pixel wider each way) and, per band of
//!   eight rows, the faces that reach within a pixel of it with the columns
//!   they span there (a long thin face, seen aslant, spans few of a band's
//!   columns but many of its box's);
//! - [`RowFaces`]: per scanline, its band's faces whose rows take it in,
//!   sorted into the blocks of eight pixels their columns reach, so that a
//!   block's lanes ([`super::lanes`]) clip by the faces over it alone.

use std::ops::Range;

use glam::{Vec2, Vec3};
use rayon::prelude::*;

use crate::camera::RowLine;
use crate::csg::ConvexPolyhedron;

/// Items sorted into cells (a compressed table): cell `c` holds
/// `items[starts[c − first]..starts[c − first + 1]]`, in the order the items
/// were given; only the cells from the first to the last given an item are
/// kept, so a row's table costs what its items do, not its width.
#[derive(Debug, Clone, Default)]
struct Cells<T> {
    items: Vec<T>,
    first: usize,
    starts: Vec<u32>,
    /// Where the next item of each cell goes, while sorting.
    cursor: Vec<u32>,
}

impl<T: Copy + Default> Cells<T> {
    /// `entries` (each a cell and an item for it) sorted into their cells.
    fn sort(&mut self, entries: &[(usize, T)]) {
        self.first = entries.iter().map(|e| e.0).min().unwrap_or(0);
        let cells = entries.iter().map(|e| e.0 + 1).max().unwrap_or(0).saturating_sub(self.first);
        self.starts.clear();
        self.starts.resize(cells + 1, 0);
        entries.iter().for_each(|&(c, _)| self.starts[c - self.first + 1] += 1);
        for c in 1..=cells {
            self.starts[c] += self.starts[c - 1];
        }
        self.cursor.clear();
        self.cursor.extend_from_slice(&self.starts[..cells]);
        self.items.clear();
        self.items.resize(entries.len(), T::default());
        for &(c, item) in entries {
            let at = &mut self.cursor[c - self.first];
            self.items[*at as usize] = item;
            *at += 1;
        }
    }

    /// Cell `c`'s items (none outside the kept cells).
    fn get(&self, c: usize) -> &[T] {
        let Some(k) = c.checked_sub(self.first).filter(|&k| k + 1 < self.starts.len()) else { return &[] };
        &self.items[self.starts[k] as usize..self.starts[k + 1] as usize]
    }
}

/// The cells of eight pixels (cell `c`'s pixel centres at `8c + ½` to
/// `8c + 7½`), of the first `cells`, with a centre within `lo..=hi` (and at
/// most one more at either end where `lo − 7½` or `hi − ½` rounds; never one
/// fewer: `8c` is a float, so a difference on either side of it does not
/// round past it); all of them if either end is NaN.
fn cells_over((lo, hi): (f32, f32), cells: usize) -> Range<usize> {
    if lo.is_nan() || hi.is_nan() {
        return 0..cells;
    }
    let last = cells as f32;
    let start = ((lo - 7.5) / 8.0).ceil().clamp(0.0, last) as usize;
    let end = (((hi - 0.5) / 8.0).floor() + 1.0).clamp(0.0, last) as usize;
    start..end.max(start)
}

/// The least and greatest x of the convex polygon whose corners are
/// `corners` (in any order) within the rows `top..=bottom`, or `None` if it
/// does not reach them: the extremes lie at corners within the rows or where
/// an edge crosses their bounds, and every edge is among the pairs of
/// corners (the other pairs cross inside the polygon).
fn columns_within(corners: &[Vec2], (top, bottom): (f32, f32)) -> Option<(f32, f32)> {
    let (mut lo, mut hi) = (f32::INFINITY, f32::NEG_INFINITY);
    let mut take = |x: f32| (lo, hi) = (lo.min(x), hi.max(x));
    for (k, p) in corners.iter().enumerate() {
        if top <= p.y && p.y <= bottom {
            take(p.x);
        }
        for q in &corners[k + 1..] {
            for y in [top, bottom] {
                if (p.y < y && y < q.y) || (q.y < y && y < p.y) {
                    take(p.x + (q.x - p.x) * ((y - p.y) / (q.y - p.y)));
                }
            }
        }
    }
    (lo <= hi).then_some((lo, hi))
}

/// Faces' rows, and the bands they show in ([`FacesOnScreen::shown`]).
type FacesShown = (Vec<(f32, f32)>, Vec<(usize, BandFace)>);

/// A face as one band of rows sees it: the face, and the columns it spans
/// within a pixel of the band's rows (a pixel wider each way).
#[derive(Debug, Clone, Copy, Default)]
struct BandFace {
    face: u32,
    columns: (f32, f32),
}

/// Where each face of a many-planed polyhedron shows in one frame
/// ([`super::CsgCaster::faces_on_screen`]), from its corners' projections:
/// the rows it spans, a pixel wider each way so that rounding loses no face,
/// and per band of eight rows the faces that reach within a pixel of it,
/// with the columns they span there. A scanline whose plane meets a face
/// lies within its rows (a face is convex, and a scanline's rays fill the
/// plane through the eye that projects onto it), and a pixel whose ray
/// crosses the face within its columns on the scanline.
#[derive(Debug, Clone)]
pub struct FacesOnScreen {
    /// This frame's own number (a row's table of faces by block, built
    /// once per band, is this frame's only if it carries it).
    frame: u64,
    /// Per face, its least and greatest y.
    rows: Vec<(f32, f32)>,
    /// The frame's width in pixels, and its bands of eight rows.
    size: (usize, usize),
    /// Per band of eight rows, the faces that show within a pixel of it.
    bands: Cells<BandFace>,
}

impl FacesOnScreen {
    /// Faces with more corners than this take their box's columns in every
    /// band (a cylinder's caps): the pairs of corners would cost more than
    /// the few blocks they save.
    const MOST_CORNERS: usize = 8;

    /// Faces on a scanline from which they are sorted by block: below, a
    /// block clips by them all sooner than the row sorts them.
    const SORT_FROM: usize = 12;

    /// Faces from which [`FacesOnScreen::new`] finds them in pieces at once
    /// (a hull of faceted balls has hundreds).
    const SPLIT_FROM: usize = 256;

    /// Faces in each such piece: in two halves, one half waited on the
    /// other (the frame's start took as long on two threads as on one); in
    /// pieces of 32, a hull of some 500 faces starts its bands about a third
    /// sooner.
    const PIECE: usize = 32;

    /// The faces of `faces`, whose corners project to `at` (pixel
    /// coordinates, a pixel's centre at `x + ½, y + ½`), in a `width` x
    /// `height` frame.
    pub(super) fn new(faces: &FaceCorners, at: &[Vec2], (width, height): (usize, usize)) -> Self {
        let count = height.div_ceil(8);
        let n = faces.count();
        // Many faces (a hull of rounded corners): in pieces at once, so that
        // the frame's bands, which wait on them, start sooner.
        let (rows, shown): (Vec<_>, Vec<_>) = if n >= Self::SPLIT_FROM {
            let pieces: Vec<FacesShown> = (0..n.div_ceil(Self::PIECE))
                .into_par_iter()
                .map(|p| Self::shown(faces, at, count, p * Self::PIECE..((p + 1) * Self::PIECE).min(n)))
                .collect();
            let (rows, shown): (Vec<_>, Vec<_>) = pieces.into_iter().unzip();
            (rows.concat(), shown.concat())
        } else {
            Self::shown(faces, at, count, 0..n)
        };
        let mut bands = Cells::default();
        bands.sort(&shown);
        static FRAMES: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
        let frame = FRAMES.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
        FacesOnScreen { frame, rows, size: (width, count), bands }
    }

    /// Of the faces `range`: each one's rows, and the bands it shows in with
    /// its columns there.
    fn shown(faces: &FaceCorners, at: &[Vec2], count: usize, range: Range<usize>) -> FacesShown {
        let mut corners = Vec::new();
        let mut rows = Vec::with_capacity(range.len());
        let mut shown: Vec<(usize, BandFace)> = Vec::new();
        for f in range {
            corners.clear();
            corners.extend(faces.on(f).iter().map(|&k| at[k as usize]));
            let (lo, hi) = corners.iter().fold((Vec2::INFINITY, Vec2::NEG_INFINITY), |(a, b), &p| (a.min(p), b.max(p)));
            // No corners: the whole plane.
            let (lo, hi) = if corners.is_empty() { (Vec2::NEG_INFINITY, Vec2::INFINITY) } else { (lo, hi) };
            let face_rows = (lo.y - 1.0, hi.y + 1.0);
            rows.push(face_rows);
            for band in cells_over(face_rows, count) {
                // The band's pixel centres' rows, a pixel wider each way.
                let within = (8.0 * band as f32 - 0.5, 8.0 * band as f32 + 8.5);
                let columns = if corners.len() > Self::MOST_CORNERS || corners.is_empty() {
                    Some((lo.x, hi.x))
                } else {
                    columns_within(&corners, within)
                };
                if let Some((left, right)) = columns {
                    shown.push((band, BandFace { face: f as u32, columns: (left - 1.0, right + 1.0) }));
                }
            }
        }
        (rows, shown)
    }

    /// Into `row`, scanline `y`'s faces: those whose rows take in its
    /// centre, and of those (when there are many) the ones over each block
    /// of eight pixels; every face for a scanline past the frame. (The
    /// band's faces are sorted by block once for its eight rows, each row
    /// reading the ones whose rows take it in.)
    fn on_row(&self, y: usize, row: &mut RowFaces) {
        row.faces.clear();
        let (width, bands) = self.size;
        if y / 8 >= bands {
            row.faces.extend(0..self.rows.len() as u32);
            return;
        }
        let centre = y as f32 + 0.5;
        let band = self.bands.get(y / 8);
        let on = |f: u32| {
            let (top, bottom) = self.rows[f as usize];
            top <= centre && centre <= bottom
        };
        row.faces.extend(band.iter().map(|b| b.face).filter(|&f| on(f)));
        if row.faces.len() < Self::SORT_FROM {
            return;
        }
        if row.band != (self.frame, y / 8) {
            row.entries.clear();
            for b in band {
                let face = BlockFace { face: b.face, rows: self.rows[b.face as usize] };
                row.entries.extend(cells_over(b.columns, width.div_ceil(8)).map(|c| (c, face)));
            }
            row.blocks.sort(&row.entries);
            row.band = (self.frame, y / 8);
        }
        row.centre = centre;
        row.by_block = true;
    }
}

/// The faces of a many-planed polyhedron that one scanline's rays can cross
/// ([`super::CsgCaster::row_faces`]), with buffers reused from row to row.
#[derive(Debug, Clone, Default)]
pub struct RowFaces {
    /// Whether `faces` applies (the primitive is such a polyhedron).
    pub(super) active: bool,
    /// The faces the row's rays can cross, in rising order (when they are
    /// not known by block).
    faces: Vec<u32>,
    distances: Vec<f32>,
    /// Whether the faces' columns are known ([`FacesOnScreen`]), and
    /// `blocks` holds the faces over each block of eight pixels of the
    /// band: those whose rows take in `centre` are the row's.
    by_block: bool,
    blocks: Cells<BlockFace>,
    /// The frame and band of eight rows `blocks` was sorted for.
    band: (u64, usize),
    /// The row's centre.
    centre: f32,
    /// Each face with each block it is over, while sorting.
    entries: Vec<(usize, BlockFace)>,
}

/// A face in a band's table by block, with its rows.
#[derive(Debug, Clone, Copy, Default)]
struct BlockFace {
    face: u32,
    rows: (f32, f32),
}

impl RowFaces {
    /// No faces: the primitive is not a polyhedron of many planes.
    pub(super) fn off(&mut self) {
        self.active = false;
        self.by_block = false;
    }

    /// The faces found by `sieve`: one of [`FacesOnScreen`] at a scanline,
    /// or [`FaceCorners::met_by`] a row line.
    pub(super) fn find(&mut self, sieve: Sieve) {
        self.off();
        match sieve {
            Sieve::Screen(screen, y) => screen.on_row(y, self),
            Sieve::Plane(corners, line) => corners.met_by(line, &mut self.distances, &mut self.faces),
        }
        self.active = true;
    }

    /// The faces that the rays of pixels `8·block..8·block + 8` can cross,
    /// in rising order.
    pub(super) fn over(&self, block: usize) -> impl Iterator<Item = u32> + '_ {
        let centre = self.centre;
        let (by_block, all) =
            if self.by_block { (self.blocks.get(block), &[][..]) } else { (&[][..], &self.faces[..]) };
        let on_row = by_block.iter().filter(move |f| f.rows.0 <= centre && centre <= f.rows.1).map(|f| f.face);
        on_row.chain(all.iter().copied())
    }
}

/// How [`RowFaces::find`] finds a row's faces.
pub(super) enum Sieve<'a> {
    /// By where they show in the frame, at scanline `y`.
    Screen(&'a FacesOnScreen, usize),
    /// By the plane of a row's rays.
    Plane(&'a FaceCorners, &'a RowLine),
}

/// Which corners of a convex polyhedron lie on each face, so that a
/// scanline can leave out the faces its rays cannot cross: the rays of a row
/// lie in one plane (through the eye, or along the view axis under an
/// orthographic camera), and a ray in that plane enters and leaves the solid
/// through faces the plane meets. Clipping by those alone gives the same
/// interval: a face the plane misses lies farther than [`FaceCorners::margin`]
/// from every crossing, so its plane does not win or tie — to the bit, unless
/// it is within rounding of coplanar with the face that does (then the two
/// differ in the last bits of `t` and of the normal).
#[derive(Debug, Clone)]
pub(super) struct FaceCorners {
    corners: Vec<Vec3>,
    /// Face `f`'s corners: `on[start[f]..start[f + 1]]`.
    on: Vec<u32>,
    start: Vec<u32>,
    /// How near the row's plane a face must come to be kept.
    margin: f32,
}

impl FaceCorners {
    /// The faces of `poly` and their corners (within a millionth of its size
    /// of the face's plane), or `None` if it lists no corners.
    pub(super) fn new(poly: &ConvexPolyhedron) -> Option<FaceCorners> {
        let corners = poly.vertices.clone();
        let (lo, hi) = corners.iter().fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(a, b), &c| (a.min(c), b.max(c)));
        let size = (hi - lo).max_element();
        if corners.is_empty() || !size.is_finite() || size <= 0.0 {
            return None;
        }
        let tree = CornerTree::new(&corners);
        let (mut on, mut start) = (Vec::new(), vec![0]);
        for plane in &poly.planes {
            let first = on.len();
            tree.near_plane(&corners, *plane, 1e-5 * size, &mut on);
            on[first..].sort_unstable();
            start.push(on.len() as u32);
        }
        Some(FaceCorners { corners, on, start, margin: 1e-3 * size })
    }

    /// Each corner's `project`ion (its pixel coordinates), or `None` if some
    /// corner has none (lies behind the eye).
    pub(super) fn projected(&self, project: impl Fn(Vec3) -> Option<Vec2>) -> Option<Vec<Vec2>> {
        self.corners.iter().map(|&c| project(c)).collect()
    }

    /// How many faces.
    fn count(&self) -> usize {
        self.start.len() - 1
    }

    /// Face `f`'s corners (indices into the corners).
    fn on(&self, f: usize) -> &[u32] {
        &self.on[self.start[f] as usize..self.start[f + 1] as usize]
    }

    /// Into `faces` (cleared), in rising order, the faces that the plane of
    /// `line`'s rays meets or passes within the margin of; every face when
    /// the rays span no plane.
    pub(super) fn met_by(&self, line: &RowLine, distances: &mut Vec<f32>, faces: &mut Vec<u32>) {
        faces.clear();
        let all = self.count() as u32;
        let normal = [line.dir.cross(line.dir_step), line.origin_step.cross(line.dir)]
            .into_iter()
            .find_map(|m| m.try_normalize());
        let Some(m) = normal else {
            faces.extend(0..all);
            return;
        };
        let offset = m.dot(line.origin);
        distances.clear();
        distances.extend(self.corners.iter().map(|&c| m.dot(c) - offset));
        for f in 0..all as usize {
            let on = self.on(f);
            let (lo, hi) = on.iter().fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), &k| {
                let d = distances[k as usize];
                (lo.min(d), hi.max(d))
            });
            if on.is_empty() || (lo <= self.margin && hi >= -self.margin) {
                faces.push(f as u32);
            }
        }
    }
}

/// A polyhedron's corners in a tree of boxes, so that each face finds the
/// corners on its plane without measuring every corner (a faceted ball has
/// thousands of each, and a frame's walk finds them anew): halves split at
/// the median of the box's longest side, down to eight corners.
struct CornerTree {
    /// Corner indices, each node's a run of them.
    order: Vec<u32>,
    nodes: Vec<CornerNode>,
}

/// A box of corners: `order[run]`, and the nodes of its halves.
struct CornerNode {
    lo: Vec3,
    hi: Vec3,
    run: Range<usize>,
    halves: Option<(usize, usize)>,
}

impl CornerTree {
    /// The most corners a leaf holds.
    const LEAF: usize = 8;

    fn new(corners: &[Vec3]) -> Self {
        let mut tree = CornerTree { order: (0..corners.len() as u32).collect(), nodes: Vec::new() };
        tree.split(corners, 0..corners.len());
        tree
    }

    /// The node over `order[run]` and the nodes below it; its index.
    fn split(&mut self, corners: &[Vec3], run: Range<usize>) -> usize {
        let ids = &mut self.order[run.clone()];
        let (lo, hi) = ids.iter().fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), &k| {
            (lo.min(corners[k as usize]), hi.max(corners[k as usize]))
        });
        let node = self.nodes.len();
        self.nodes.push(CornerNode { lo, hi, run: run.clone(), halves: None });
        if run.len() > Self::LEAF {
            let axis = (hi - lo).max_position();
            let mid = run.len() / 2;
            ids.select_nth_unstable_by(mid, |&a, &b| corners[a as usize][axis].total_cmp(&corners[b as usize][axis]));
            let first = self.split(corners, run.start..run.start + mid);
            let second = self.split(corners, run.start + mid..run.end);
            self.nodes[node].halves = Some((first, second));
        }
        node
    }

    /// Into `out`, the corners within `eps` of `plane` (`n·p = w`): those
    /// whose `|n·p − w| ≤ eps`, as measuring each would find them. A box is
    /// passed over only when `n·p` over it stays farther than `eps` from `w`
    /// by a margin above the rounding of either sum.
    fn near_plane(&self, corners: &[Vec3], plane: glam::Vec4, eps: f32, out: &mut Vec<u32>) {
        let n = plane.truncate();
        let mut stack = vec![0];
        while let Some(k) = stack.pop() {
            let Some(node) = self.nodes.get(k) else { continue };
            let (centre, half) = ((node.lo + node.hi) * 0.5, (node.hi - node.lo) * 0.5);
            let (mid, reach) = (n.dot(centre), n.abs().dot(half));
            let rounding = 1e-5 * (n.abs().dot(node.lo.abs().max(node.hi.abs())) + plane.w.abs());
            if (mid - plane.w).abs() > reach + eps + rounding {
                continue;
            }
            match node.halves {
                Some((a, b)) => stack.extend([a, b]),
                None => out.extend(
                    self.order[node.run.clone()]
                        .iter()
                        .filter(|&&c| (n.dot(corners[c as usize]) - plane.w).abs() <= eps),
                ),
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use glam::Vec4;
    use proptest::prelude::*;

    use super::super::shapes::tests::vector;
    use super::*;

    proptest! {
        /// The blocks `cells_over` gives are those with a pixel centre
        /// within the columns, as comparing each block's centres finds them
        /// (and at most one more at either end).
        #[test]
        fn the_cells_over_columns_are_those_with_a_centre_within(
            lo in prop_oneof![-20.0f32..200.0, (-3i32..30).prop_map(|c| 8.0 * c as f32 + 7.5)],
            width in prop_oneof![0.0f32..100.0, Just(0.0f32)],
            cells in 0usize..20,
        ) {
            let hi = lo + width;
            let over = cells_over((lo, hi), cells);
            let exact: Vec<usize> = (0..cells).filter(|&c| {
                let (first, last) = (8.0 * c as f32 + 0.5, 8.0 * c as f32 + 7.5);
                lo <= last && first <= hi
            }).collect();
            let (Some(&a), Some(&b)) = (exact.first(), exact.last()) else {
                prop_assert!(over.len() <= 1, "{:?} for none", over);
                return Ok(());
            };
            prop_assert!(over.start <= a && a <= over.start + 1 && over.end > b && over.end <= b + 2, "{:?} for {}..={}", over, a, b);
            prop_assert_eq!(cells_over((f32::NAN, hi), cells), 0..cells);
        }

        /// The corner tree finds each plane's corners as measuring every
        /// corner does: random clouds of corners (some repeated, some on a
        /// common plane) far from and near the origin, planes through
        /// corners and beside them.
        #[test]
        fn the_corner_tree_finds_what_measuring_every_corner_finds(
            cloud in prop::collection::vec(vector(-1.0..1.0), 1..300),
            offset in vector(-100.0..100.0),
            scale in prop_oneof![Just(1.0f32), 0.001f32..1000.0],
            normals in prop::collection::vec(vector(-1.0..1.0), 1..20),
            flat in any::<bool>(),
        ) {
            let mut corners: Vec<Vec3> = cloud.iter().map(|&c| c * scale + offset).collect();
            if flat {
                // A third of them on the plane z = offset.z.
                corners.iter_mut().step_by(3).for_each(|c| c.z = offset.z);
                corners.extend_from_within(..corners.len() / 4);
            }
            let eps = 1e-5 * scale;
            let tree = CornerTree::new(&corners);
            let planes = normals.iter().filter_map(|n| n.try_normalize()).enumerate().flat_map(|(k, n)| {
                let through = corners[k % corners.len()];
                [n.extend(n.dot(through)), n.extend(n.dot(through) + eps * 0.999), Vec4::new(0.0, 0.0, 1.0, offset.z)]
            });
            for plane in planes {
                let mut found = Vec::new();
                tree.near_plane(&corners, plane, eps, &mut found);
                found.sort_unstable();
                let n = plane.truncate();
                let every: Vec<u32> = (0..corners.len() as u32)
                    .filter(|&c| (n.dot(corners[c as usize]) - plane.w).abs() <= eps)
                    .collect();
                prop_assert_eq!(found, every);
            }
        }
    }
}
