//! Outlines where surfaces pass through each other: a box standing in a floor,
//! a ball sunk into a stage. No mesh edge bounds them, so seed 004's walker
//! (which steps along polygon edges, [`super::edges`]) never meets them, yet
//! they are outlines like any other: aliased, the line where one surface dives
//! under the other is a staircase.
//!
//! They are found in the visibility buffer instead. Where two neighbouring
//! pixels `c` and `o` show triangles of different objects, A at `c` and B at
//! `o`, each triangle's plane gives a depth over the screen (affine in x and
//! y: [`Screen::depth_plane`]). If B's plane lies behind A's at `c`'s centre
//! and in front of it at `o`'s, the two surfaces cross between the centres:
//! the outline is the line where the planes' depths are equal, and the part of
//! `c` beyond it — where B's plane is in front — shows B. That part's area and
//! centroid come from clipping the pixel's square by the line, exactly as for a
//! polygon edge, and become an ordinary [`EdgeBlend`]. (Where instead A's plane
//! is in front at `o` too, A's triangle simply ends between the pixels: that is
//! an edge, the walker's.)
//!
//! Two surfaces can only meet where their objects' bounds overlap, so only the
//! screen rows' spans under the overlap of two objects' world boxes are scanned
//! (a part standing on a plate: a thin slab along its foot).

use std::ops::Range;

use glam::{Vec2, Vec3};
use rayon::prelude::*;

use super::blend::{EdgeBlend, PixelSet};
use super::dda::square_part;
use super::screen::{ClipMap, DepthPlane, Screen};
use crate::scene::{box_corners, Scene};
use crate::visibility::{ItemId, VisibilityBuffer};

/// The `source` of a blend across an intersection (no edge of a mesh).
pub(super) const INTERSECTION: u64 = u64::MAX;

/// Which neighbouring pixels a walked edge already runs between: per pixel,
/// one bit for the pair with its right neighbour and one for the pair with the
/// one below.
pub(super) struct WalkedPairs {
    /// Bit `2·i + k` for pixel `i`: k = 0 right, 1 below.
    bits: PixelSet,
}

impl WalkedPairs {
    /// The pairs `blends` join, on a frame holding `width` × `height` pixels.
    pub(super) fn of(blends: &[EdgeBlend], width: u32, height: u32) -> Self {
        let mut bits = PixelSet::new(2 * width * height);
        for b in blends {
            let (first, second) = (b.c.min(b.o), b.c.max(b.o));
            bits.insert(2 * first + u32::from(second != first + 1));
        }
        WalkedPairs { bits }
    }

    /// Whether an edge runs between pixel `i` and its neighbour `towards`
    /// ([`RIGHT`] or [`BELOW`]).
    fn contains(&self, i: usize, towards: u8) -> bool {
        self.bits.contains(2 * i as u32 + u32::from(towards == BELOW))
    }
}

/// The neighbour to the right.
const RIGHT: u8 = 1;
/// The neighbour below.
const BELOW: u8 = 2;

/// The blends of every pixel an intersection of two objects' surfaces crosses,
/// where no walked edge runs between the two pixels. `clips` holds every
/// object's map to clip space; `boxes` the world bounds of the opaque meshes
/// (only where two overlap is a pair of neighbours looked at, each once).
pub(super) fn find_intersection_blends(
    scene: &Scene,
    vb: &VisibilityBuffer,
    clips: &[ClipMap],
    walked: &WalkedPairs,
    boxes: &[(Vec3, Vec3)],
) -> Vec<EdgeBlend> {
    let (w, h, held) = (vb.width(), vb.height(), vb.rect());
    let screen = Screen::of(&scene.camera, w, h);
    let plane = |item: ItemId| -> Option<DepthPlane> {
        if item.is_none() || item.primitive().is_some() {
            return None;
        }
        let object = &scene.objects[item.object as usize];
        if scene.materials[object.material].translucent() {
            return None;
        }
        screen.depth_plane(&clips[item.object as usize], object.triangles()?, item.triangle)
    };
    let spans = overlap_spans(scene, &screen, boxes, (w, h));
    // The pixels held alone are looked at (a tile's, with its guard band):
    // rows and columns are the image's, `row` and `next` hold the columns
    // from x0.
    let x0 = held.x0 as usize;
    let rows: Vec<Vec<EdgeBlend>> = (held.y0..held.y1)
        .into_par_iter()
        .map(|y| {
            let mut out = Vec::new();
            let span = &spans[y as usize];
            // The span, and the pixel after it (its pair with the last one).
            let span = span.start.max(held.x0) as usize..(span.end as usize + 1).min(held.x1 as usize);
            if span.is_empty() {
                return out;
            }
            let row = vb.item_row(y);
            let next = if y + 1 < held.y1 { vb.item_row(y + 1) } else { &[] };
            let next = next.get(span.start - x0..span.end - x0).unwrap_or_default();
            for_each_boundary(&row[span.start - x0..span.end - x0], next, |x, right, below| {
                let x = (span.start + x) as u32;
                let i = vb.index(x, y);
                let pairs = [(right, (x + 1, y), RIGHT), (below, (x, y + 1), BELOW)];
                for (_, o, _) in pairs.into_iter().filter(|p| p.0 && !walked.contains(i, p.2)) {
                    out.extend(crossings(&plane, vb, (x, y), o));
                }
            });
            out
        })
        .collect();
    rows.concat()
}

/// The most objects whose bounds are compared pair by pair; a scene with more
/// is scanned whole.
const MAX_OBJECTS_PAIRED: usize = 256;

/// Per row of a `width` × `height` frame, the columns where two of the world
/// `boxes` overlap, as seen through `screen` (only there can two surfaces pass
/// through each other), with a pixel's margin; empty where no pair overlaps.
/// Boxes that touch (a part standing on a plate) overlap.
fn overlap_spans(
    scene: &Scene,
    screen: &Screen,
    boxes: &[(Vec3, Vec3)],
    (width, height): (u32, u32),
) -> Vec<Range<u32>> {
    if boxes.len() > MAX_OBJECTS_PAIRED {
        return vec![0..width; height as usize];
    }
    let view_proj = scene.camera.view_projection(width as f32 / height as f32).as_dmat4();
    let margin = boxes.iter().map(|(lo, hi)| (*hi - *lo).length()).fold(0.0, f32::max) * 1e-4;
    let mut spans = vec![width..0; height as usize];
    for (k, &(lo_a, hi_a)) in boxes.iter().enumerate() {
        for &(lo_b, hi_b) in &boxes[k + 1..] {
            let (lo, hi) = (lo_a.max(lo_b) - margin, hi_a.min(hi_b) + margin);
            if lo.cmpgt(hi).any() {
                continue;
            }
            let (x, y) = screen_rect(&view_proj, screen, (lo, hi), (width, height));
            for span in &mut spans[y] {
                *span = span.start.min(x.start)..span.end.max(x.end);
            }
        }
    }
    spans
}

/// The pixel columns and rows the box `(lo, hi)` (world space) covers on a
/// `width` × `height` frame, widened by a pixel; the whole frame if the box
/// reaches behind the eye.
fn screen_rect(
    view_proj: &glam::DMat4,
    screen: &Screen,
    (lo, hi): (Vec3, Vec3),
    (width, height): (u32, u32),
) -> (Range<u32>, Range<usize>) {
    let corners = box_corners((lo, hi)).map(|c| *view_proj * c.as_dvec3().extend(1.0));
    let mut rect = (f64::INFINITY, f64::INFINITY, f64::NEG_INFINITY, f64::NEG_INFINITY);
    for c in corners {
        if c.w <= 1e-9 {
            return (0..width, 0..height as usize);
        }
        let p = screen.project(c);
        rect = (rect.0.min(p.x), rect.1.min(p.y), rect.2.max(p.x), rect.3.max(p.y));
    }
    let clamp = |v: f64, n: u32| (v.max(0.0) as u32).min(n);
    let x = clamp(rect.0.floor() - 1.0, width)..clamp(rect.2.ceil() + 1.0, width);
    let y = clamp(rect.1.floor() - 1.0, height) as usize..clamp(rect.3.ceil() + 1.0, height) as usize;
    (x, y)
}

/// Calls `f(x, right, below)` for each pixel x of `row` that shows another
/// object than its right neighbour (`right`) or than the pixel below it in
/// `next` (`below`; `next` is empty on the last row). Pixels are looked at
/// eight at a time: a block inside one object, the common case, costs a few
/// compares without branches.
fn for_each_boundary(row: &[ItemId], next: &[ItemId], mut f: impl FnMut(usize, bool, bool)) {
    const BLOCK: usize = 8;
    let w = row.len();
    let differs = |x: usize| {
        let right = x + 1 < w && row[x].object != row[x + 1].object;
        (right, next.get(x).is_some_and(|b| b.object != row[x].object))
    };
    for x0 in (0..w).step_by(BLOCK) {
        let whole = x0 + BLOCK < w && next.len() == w;
        let uniform = whole && {
            let (a, r, n) = (&row[x0..x0 + BLOCK], &row[x0 + 1..x0 + BLOCK + 1], &next[x0..x0 + BLOCK]);
            a.iter()
                .zip(r)
                .zip(n)
                .fold(true, |same, ((a, r), n)| same & (a.object == r.object) & (a.object == n.object))
        };
        if uniform {
            continue;
        }
        for x in x0..(x0 + BLOCK).min(w) {
            let (right, below) = differs(x);
            if right || below {
                f(x, right, below);
            }
        }
    }
}

/// The blends of pixels `c` and `o` (both held by `vb`), neighbours showing
/// different objects, if their surfaces cross between them; `plane` gives an
/// item's depth plane.
fn crossings<'a>(
    plane: impl Fn(ItemId) -> Option<DepthPlane>,
    vb: &'a VisibilityBuffer,
    c: (u32, u32),
    o: (u32, u32),
) -> impl Iterator<Item = EdgeBlend> + 'a {
    let item = |(x, y): (u32, u32)| vb.item(x, y);
    let index = move |(x, y): (u32, u32)| vb.index(x, y) as u32;
    let planes = plane(item(c)).zip(plane(item(o)));
    planes
        .into_iter()
        .flat_map(move |(pc, po)| crossing(c, o, &pc, &po, index).into_iter().chain(crossing(o, c, &po, &pc, index)))
}

/// The blend of pixel `c` (showing plane `a`) towards its neighbour `o`
/// (showing plane `b`) if the planes cross between their centres, its pixels
/// named by `index`. Depths are reversed: greater is nearer.
fn crossing(
    c: (u32, u32),
    o: (u32, u32),
    a: &DepthPlane,
    b: &DepthPlane,
    index: impl Fn((u32, u32)) -> u32,
) -> Option<EdgeBlend> {
    let centre = |(x, y): (u32, u32)| (f64::from(x) + 0.5, f64::from(y) + 0.5);
    // How far B's plane lies in front of A's.
    let ahead = |(x, y): (f64, f64)| b.at(x, y) - a.at(x, y);
    if !(ahead(centre(c)) < 0.0 && ahead(centre(o)) > 0.0) {
        return None;
    }
    let (x0, y0) = (f64::from(c.0), f64::from(c.1));
    let (alpha, (du, dv)) = square_part(|(u, v)| ahead((x0 + u, y0 + v)));
    (alpha > 1e-6).then(|| EdgeBlend {
        c: index(c),
        o: index(o),
        alpha: alpha as f32,
        inside: true,
        source: INTERSECTION,
        far: Vec2::new(du as f32, dv as f32),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// A row of objects in runs of 1 to 16 equal ones.
    fn runs() -> impl Strategy<Value = Vec<u32>> {
        proptest::collection::vec((0u32..3, 1usize..16), 1..8)
            .prop_map(|runs| runs.into_iter().flat_map(|(object, n)| std::iter::repeat_n(object, n)).collect())
    }

    proptest! {
        /// The blockwise scan reports exactly the pixels a plain scan finds
        /// beside another object (runs of one object, so that whole blocks
        /// are skipped, mixed with boundaries; with and without a row below).
        #[test]
        fn the_boundary_scan_finds_every_pair_of_different_objects(row in runs(), below in runs(), last in any::<bool>()) {
            let item = |object: &u32| ItemId { object: *object, triangle: 0 };
            let row: Vec<ItemId> = row.iter().map(item).collect();
            let next: Vec<ItemId> =
                if last { Vec::new() } else { (0..row.len()).map(|x| item(&below[x % below.len()])).collect() };
            let mut found = Vec::new();
            for_each_boundary(&row, &next, |x, right, below| found.push((x, right, below)));
            let expected: Vec<(usize, bool, bool)> = (0..row.len())
                .map(|x| {
                    let right = x + 1 < row.len() && row[x].object != row[x + 1].object;
                    (x, right, !next.is_empty() && next[x].object != row[x].object)
                })
                .filter(|&(_, right, below)| right || below)
                .collect();
            prop_assert_eq!(found, expected);
        }
    }

    #[test]
    fn scanning_only_where_bounds_overlap_finds_what_the_whole_frame_holds() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/scenes/cad-ortho.toml");
        let scene = crate::scene::file::load_scene(&path).expect("cad-ortho loads");
        let (w, h) = (240, 135);
        let mut found = 0;
        for yaw in [0.0f32, 40.0, 110.0, 200.0] {
            let mut turned = scene.clone();
            let turn = glam::Quat::from_rotation_y(yaw.to_radians());
            turned.camera.eye = turned.camera.target + turn * (scene.camera.eye - scene.camera.target);
            let mut vb = VisibilityBuffer::new(w, h);
            crate::visibility::rasterize(&turned, &mut vb);
            let clips = ClipMap::of_objects(&turned, w, h);
            let walked = WalkedPairs::of(&[], w, h);
            let opaque =
                |o: &&crate::scene::Object| o.triangles().is_some() && !turned.materials[o.material].translucent();
            let boxes: Vec<(Vec3, Vec3)> =
                turned.objects.iter().filter(opaque).filter_map(|o| o.world_bounds()).collect();
            // A box around the eye reaches behind it: the whole frame.
            let everywhere = [(Vec3::splat(-1e6), Vec3::splat(1e6)); 2];
            let restricted = find_intersection_blends(&turned, &vb, &clips, &walked, &boxes);
            let whole = find_intersection_blends(&turned, &vb, &clips, &walked, &everywhere);
            assert_eq!(restricted, whole, "yaw {yaw}");
            found += whole.len();
        }
        assert!(found > 20, "the parts stand in the plate: {found} blends");
    }

    #[test]
    fn two_crossing_planes_share_each_pixel_by_the_line_where_their_depths_meet() {
        // A comes nearer to the right, B is level: they meet at x = 10.3, so
        // pixel 10 (centre 10.5) shows A and pixel 9 shows B.
        let a = DepthPlane { z0: 0.5 - 0.01 * 10.3, gx: 0.01, gy: 0.0 };
        let b = DepthPlane { z0: 0.5, gx: 0.0, gy: 0.0 };
        let blend =
            crossing((10, 4), (9, 4), &a, &b, |(x, y)| y * 32 + x).expect("the planes cross between the centres");
        assert!((blend.alpha - 0.3).abs() < 1e-6, "the part of pixel 10 left of x = 10.3: {}", blend.alpha);
        assert!((blend.far - Vec2::new(-0.35, 0.0)).length() < 1e-6, "its centroid: {}", blend.far);
        let back = crossing((9, 4), (10, 4), &b, &a, |(x, y)| y * 32 + x);
        assert!(back.is_none(), "pixel 9 lies wholly left of the line");
        // A plane in front at both centres ends between them: an edge, not this.
        let near = DepthPlane { z0: 0.9, gx: 0.0, gy: 0.0 };
        assert!(crossing((10, 4), (9, 4), &near, &b, |(x, y)| y * 32 + x).is_none());
    }
}
