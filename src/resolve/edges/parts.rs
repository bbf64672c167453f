//! The colours of the parts of the pixels an edge crosses: seed 004's blends
//! (Kato & Kameyama, §3 (2)), with each part's colour found where the part
//! lies rather than at its pixel's centre.
//!
//! A pixel `c` that edges cross is made of its own part (on its centre's side
//! of every edge) and, per edge, a part beyond it showing the surface of the
//! pixel across, `o`. The aliased frame gives each pixel the colour of its
//! centre; [`EdgePlan::apply`] makes `c` the parts' colours weighted by their
//! areas. A part's colour is the colour of the pixel whose surface it shows,
//! moved by how the shading changes from that pixel's centre to the part's
//! centroid:
//!
//! - a part beyond an edge (at least [`RESHADED_SHARE`] of `c`) is shaded at its
//!   centroid on `o`'s surface, by the lit passes themselves (a sub-pixel sample,
//!   [`crate::shading::subpixel`]): a shadow that begins right behind a
//!   silhouette is seen there, and no neighbour of `o` could tell;
//! - the own part of a pixel on a curved (smooth-shaded) surface is shaded at its
//!   centroid too: a terminator or a highlight can turn within one pixel;
//! - the own part of a pixel on a flat face (its vertex normals all the face's)
//!   is moved along the colour steps from `c` to its neighbours on the same
//!   object, on the centroid's side, in x and in y ([`OwnPart::Stepped`]): on a
//!   plane the passes' colour changes slowly, and the neighbours are already
//!   shaded. Against 256 jittered passes this costs no scene more than 0.6
//!   points of the aliased edge error removed, and saves a third to a half of
//!   the samples (`docs/benchmarks.md`, "Design measurements").

use glam::{Vec2, Vec3};
use rayon::prelude::*;

use super::blend::EdgeBlend;
use crate::image::{LinearImage, PixelRect};
use crate::shading::{ComponentSet, SubpixelSample, SubpixelShading, Target};
use crate::visibility::{ItemId, VisibilityBuffer};

/// The least share of a pixel beyond an edge whose colour is re-shaded at its
/// centroid; a smaller part takes the colour of the pixel across as it is.
/// From 0.1 to 0.2 no scene's share of the aliased edge error removed moves by
/// more than 0.3 points while a fifth fewer samples are shaded; 0.25 starts to
/// cost (`docs/benchmarks.md`, "Design measurements").
pub const RESHADED_SHARE: f32 = 0.2;

/// How the colour of a crossed pixel's own part is found.
#[derive(Debug, Clone, Copy, PartialEq)]
enum OwnPart {
    /// Shaded at its centroid (a sub-pixel sample).
    Shaded,
    /// The pixel's colour plus, per axis, the step to a neighbour (pixel index)
    /// times the centroid's distance from the centre along that axis (weight 0:
    /// no neighbour on that side shows the same object).
    Stepped([(u32, f32); 2]),
}

/// A pixel that edges cross, as the plan holds it.
#[derive(Debug, Clone, Copy)]
struct Crossed {
    /// Its blends: `blends[start..end]`.
    start: u32,
    end: u32,
    /// How its own part is coloured.
    own: OwnPart,
    /// How many re-shaded parts beyond edges the crossed pixels before it have.
    across_before: u32,
    /// How many crossed pixels before it have their own part shaded (its
    /// sample's ordinal, if its own is shaded too).
    shaded_before: u32,
}

/// The edge pass of one frame: its blends, found from the visibility buffer
/// alone, before shading, so the passes can shade the sub-pixel points they
/// need ([`EdgePlan::samples`]).
#[derive(Debug, Clone, Default)]
pub struct EdgePlan {
    /// Merged blends, sorted by pixel, then neighbour.
    blends: Vec<EdgeBlend>,
    /// The crossed pixels, in `blends`' order.
    crossed: Vec<Crossed>,
    /// Whether the parts' colours are found where they lie (else the pixels'
    /// colours are blended as they are).
    reshade: bool,
    /// Per target image (by its components), per part whose colour moves from
    /// its pixel's (the crossed pixels' own parts, then the re-shaded parts
    /// beyond edges), how far it moves, before fog ([`EdgePlan::record`]).
    moved: Vec<(ComponentSet, Vec<Vec3>)>,
    /// The pixels the frame holds: blends name pixels by their index among
    /// them, row-major from the top left one.
    held: PixelRect,
}

impl EdgePlan {
    /// The plan for `blends` (merged, sorted by pixel) on the frame whose
    /// visibility buffer is `vb`; `reshade` says whether the parts' colours are
    /// found where they lie (the coverage filter) or taken from the pixels as
    /// they are (the paper's filter, which blends the edge's colour); `flat`
    /// says whether an item's surface is flat-shaded.
    pub(super) fn new(
        blends: Vec<EdgeBlend>,
        reshade: bool,
        vb: &VisibilityBuffer,
        flat: impl Fn(ItemId) -> bool + Sync,
    ) -> EdgePlan {
        let (mut start, mut across) = (0, 0);
        let groups: Vec<(u32, u32, u32)> = blends
            .chunk_by(|a, b| a.c == b.c)
            .map(|group| {
                let (first, before) = (start, across);
                start += group.len() as u32;
                across += group.iter().filter(|b| reshaded_across(b)).count() as u32;
                (first, start, before)
            })
            .collect();
        let mut crossed: Vec<Crossed> = groups
            .par_iter()
            .map(|&(start, end, across_before)| {
                let group = &blends[start as usize..end as usize];
                let own = if reshade {
                    own_part(group, vb.items(), vb.rect().width(), &flat)
                } else {
                    OwnPart::Stepped([(group[0].c, 0.0); 2]) // the paper's: pixels as they are
                };
                Crossed { start, end, own, across_before, shaded_before: 0 }
            })
            .collect();
        let mut shaded = 0;
        for c in &mut crossed {
            c.shaded_before = shaded;
            shaded += u32::from(c.own == OwnPart::Shaded);
        }
        EdgePlan { blends, crossed, reshade, moved: Vec::new(), held: vb.rect() }
    }

    /// The blends of crossed pixel `c`.
    fn blends_of(&self, c: &Crossed) -> &[EdgeBlend] {
        &self.blends[c.start as usize..c.end as usize]
    }

    /// How many parts beyond edges are re-shaded.
    fn across(&self) -> usize {
        self.crossed
            .last()
            .map_or(0, |c| c.across_before as usize + self.blends_of(c).iter().filter(|b| reshaded_across(b)).count())
    }

    /// How many crossed pixels have their own part shaded.
    fn shaded(&self) -> usize {
        self.crossed.last().map_or(0, |c| c.shaded_before as usize + usize::from(c.own == OwnPart::Shaded))
    }

    /// Pixel blends: one per pixel and neighbour across an edge.
    #[must_use]
    pub fn len(&self) -> usize {
        self.blends.len()
    }

    /// Whether no edge crosses a pixel.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.blends.is_empty()
    }

    /// The points the shading passes shade for [`EdgePlan::apply`] (none
    /// under the paper's filter): per crossed pixel
    /// whose own part is shaded, its surface at that part's centroid; per blend
    /// that moves the pixel by at least [`RESHADED_SHARE`], the surface across
    /// at the centroid of the part beyond. (The pixels' centres, which they
    /// are compared with, are the passes' own pixels: [`EdgePlan::record`].)
    #[must_use]
    pub fn samples(&self) -> Vec<SubpixelSample> {
        if !self.reshade {
            return Vec::new();
        }
        let pixel = |i: u32| self.pixel(i);
        let at = |i: u32, offset: Vec2| {
            let p = pixel(i);
            SubpixelSample { pixel: p, at: Vec2::new(p.0 as f32 + 0.5, p.1 as f32 + 0.5) + offset }
        };
        let shaded = self.crossed.iter().filter(|c| c.own == OwnPart::Shaded).map(|c| self.blends_of(c));
        let near = shaded.map(|b| at(b[0].c, near_centroid(b)));
        let far = self.blends.iter().filter(|b| reshaded_across(b)).map(|b| {
            // The surface `o` shows, met by a ray through `c`.
            SubpixelSample { pixel: pixel(b.o), ..at(b.c, b.far) }
        });
        near.chain(far).collect()
    }

    /// Records, in every target, how far each part's colour moves from the
    /// colour of the pixel whose surface it shows, as the lit passes, the
    /// reflection map and the traced term left the image (before fog and
    /// translucency): a shaded part by its sample's colour in `shaded` (the
    /// samples of [`EdgePlan::samples`], shaded), a stepped part by its
    /// neighbours' colours.
    pub fn record(&mut self, targets: &[Target], shaded: &SubpixelShading) {
        if !self.matches(shaded) {
            return;
        }
        let record = |t: &Target| {
            let moves = (0..self.moves()).into_par_iter();
            moves.map(|k| self.part_move(k, t.image.pixels(), t.parts, shaded)).collect()
        };
        self.moved = targets.iter().map(|t| (t.parts, record(t))).collect();
    }

    /// Blends `image` (holding the components `parts`): each crossed pixel
    /// becomes its parts' colours weighted by their areas, each part's colour
    /// its pixel's moved as [`EdgePlan::record`] found, scaled by how much of
    /// the opaque surface the pixel still shows (`seen[pixel]`: `1 − fog`
    /// times the transmittance of translucent surfaces over it). Every blend
    /// reads the image as it was before any of them.
    pub fn apply(&self, image: &mut LinearImage, parts: ComponentSet, seen: Option<&[f32]>) {
        let Some((_, moved)) = self.moved.iter().find(|(p, _)| *p == parts) else {
            return self.blend(image, |_, _, _| Vec3::ZERO); // not re-shaded
        };
        self.blend(image, |_, pixel, k| moved[k] * seen.map_or(1.0, |s| s[pixel as usize]));
    }

    /// [`EdgePlan::record`] and [`EdgePlan::apply`] in one step, for a frame
    /// that nothing changes between its passes and the edge pass (no fog, no
    /// translucent surfaces): each part's move is found as its pixel is
    /// blended.
    pub fn record_and_apply(&self, targets: &mut [Target], shaded: &SubpixelShading) {
        let reshaded = self.matches(shaded);
        for t in targets {
            let parts = t.parts;
            let moved = |px: &[Vec3], _, k| {
                if reshaded {
                    self.part_move(k, px, parts, shaded)
                } else {
                    Vec3::ZERO
                }
            };
            self.blend(t.image, moved);
        }
    }

    /// Whether the parts are re-shaded and `shaded` holds this plan's samples.
    fn matches(&self, shaded: &SubpixelShading) -> bool {
        self.reshade && shaded.samples.len() == self.shaded() + self.across()
    }

    /// How many parts have a move: the crossed pixels' own parts (by ordinal),
    /// then the re-shaded parts beyond edges.
    fn moves(&self) -> usize {
        self.crossed.len() + self.across()
    }

    /// The image coordinates of the pixel of index `i` among those held.
    fn pixel(&self, i: u32) -> (u32, u32) {
        let w = self.held.width().max(1);
        (self.held.x0 + i % w, self.held.y0 + i / w)
    }

    /// How far part `k`'s colour moves from its pixel's in an image (its
    /// pixels: those held) holding the components `parts`: a shaded part's
    /// sample in `shaded` less its pixel, a stepped part by its neighbours.
    fn part_move(&self, k: usize, px: &[Vec3], parts: ComponentSet, shaded: &SubpixelShading) -> Vec3 {
        let sampled = |s: usize| {
            let (x, y) = shaded.samples[s].pixel;
            let i = (y - self.held.y0) as usize * self.held.width() as usize + (x - self.held.x0) as usize;
            shaded.colour(s, parts).map_or(Vec3::ZERO, |colour| colour - px[i])
        };
        let Some(crossed) = self.crossed.get(k) else {
            return sampled(self.shaded() + k - self.crossed.len());
        };
        match crossed.own {
            OwnPart::Shaded => sampled(crossed.shaded_before as usize),
            OwnPart::Stepped(steps) => {
                let c = self.blends[crossed.start as usize].c as usize;
                steps.iter().map(|&(m, weight)| (px[m as usize] - px[c]) * weight).sum()
            }
        }
    }

    /// Sets every crossed pixel of `image` to its parts' colours weighted by
    /// their areas, part `k` of pixel `p` moved by `moved(pixels, p, k)` from
    /// its pixel's colour (own parts by the crossed pixel's ordinal, re-shaded
    /// parts across after all own parts). Every blend reads the image as it
    /// was before any of them.
    fn blend(&self, image: &mut LinearImage, moved: impl Fn(&[Vec3], u32, usize) -> Vec3 + Sync) {
        let px = image.pixels();
        let updates: Vec<(u32, Vec3)> = (self.crossed.par_iter().enumerate())
            .map(|(near, crossed)| {
                let blends = self.blends_of(crossed);
                let c = blends[0].c;
                let own = px[c as usize] + moved(px, c, near);
                let mut far = self.crossed.len() + crossed.across_before as usize;
                let mut colour = own;
                for b in blends {
                    let mut across = px[b.o as usize];
                    if reshaded_across(b) {
                        across += moved(px, b.o, far);
                        far += 1;
                    }
                    colour += (across - own) * b.alpha;
                }
                (c, colour)
            })
            .collect();
        let px = image.pixels_mut();
        for (c, colour) in updates {
            px[c as usize] = colour;
        }
    }
}

/// Whether the part of `b.c` beyond the edge is re-shaded.
fn reshaded_across(b: &EdgeBlend) -> bool {
    b.alpha >= RESHADED_SHARE
}

/// How the own part of the pixel `crossed` blends cross is coloured, on a frame
/// whose pixels show `items` (`width` pixels a row); `flat` says whether an
/// item's surface is flat-shaded.
fn own_part(crossed: &[EdgeBlend], items: &[ItemId], width: u32, flat: impl Fn(ItemId) -> bool) -> OwnPart {
    let c = crossed[0].c;
    let item = items[c as usize];
    if !item.is_none() && !flat(item) {
        return OwnPart::Shaded;
    }
    // Nothing to shade, or a flat face: per axis, the neighbour on the
    // centroid's side if it shows the same object and lies across none of the
    // pixel's edges.
    let d = near_centroid(crossed);
    let (x, n) = (c % width, items.len() as u32);
    let towards = |along: f32, step: u32, first: bool, last: bool| match along {
        a if a > 0.0 && !last => c.checked_add(step).filter(|&m| m < n),
        a if a < 0.0 && !first => c.checked_sub(step),
        _ => None,
    };
    let same =
        |m: &u32| !item.is_none() && items[*m as usize].object == item.object && crossed.iter().all(|b| b.o != *m);
    let step = |m: Option<u32>, along: f32| m.filter(same).map_or((c, 0.0), |m| (m, along.abs()));
    OwnPart::Stepped([step(towards(d.x, 1, x == 0, x + 1 == width), d.x), step(towards(d.y, width, false, false), d.y)])
}

/// The centroid of a crossed pixel's part on its centre's side of its edges,
/// from the centre: the pixel's centroid (its centre) is the parts' centroids
/// weighted by their areas.
fn near_centroid(crossed: &[EdgeBlend]) -> Vec2 {
    let across: f32 = crossed.iter().map(|b| b.alpha).sum();
    let moment: Vec2 = crossed.iter().map(|b| b.far * b.alpha).sum();
    -moment / (1.0 - across).max(0.5)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A blend of pixel `c` towards `o`, moving it by `alpha`, the part's
    /// centroid at `far` from `c`'s centre.
    fn blend(c: u32, o: u32, alpha: f32, far: Vec2) -> EdgeBlend {
        EdgeBlend { c, o, alpha, inside: true, source: 0, far }
    }

    #[test]
    fn a_flat_face_steps_towards_its_neighbours_on_the_centroids_side() {
        // 4 × 3 pixels of object 0, but pixel 2 (x 2, y 0) shows object 1.
        let mut items = vec![ItemId { object: 0, triangle: 0 }; 12];
        items[2] = ItemId { object: 1, triangle: 0 };
        // Pixel 5 (x 1, y 1) crossed towards its left neighbour 4: the part
        // beyond lies left, so its own part's centroid lies right and below.
        let crossed = [blend(5, 4, 0.25, Vec2::new(-0.375, -0.1))];
        let d = near_centroid(&crossed);
        assert!(d.x > 0.0 && d.y > 0.0, "{d}");
        let flat = |_| true;
        assert_eq!(own_part(&crossed, &items, 4, flat), OwnPart::Stepped([(6, d.x), (9, d.y)]));
        // Upwards (the part beyond lies below) the neighbour shows another
        // object: no step in y.
        let crossed = [blend(6, 10, 0.25, Vec2::new(0.1, 0.375))];
        let d = near_centroid(&crossed);
        assert_eq!(own_part(&crossed, &items, 4, flat), OwnPart::Stepped([(5, d.x.abs()), (6, 0.0)]));
        // Never towards the pixel across an edge, nor past the image's side.
        let crossed = [blend(7, 6, 0.2, Vec2::new(-0.4, 0.0)), blend(7, 11, 0.2, Vec2::new(0.0, 0.4))];
        let d = near_centroid(&crossed);
        assert!(d.x > 0.0 && d.y < 0.0, "{d}");
        assert_eq!(own_part(&crossed, &items, 4, flat), OwnPart::Stepped([(7, 0.0), (3, -d.y)]));
    }

    #[test]
    fn a_curved_surface_is_shaded_and_nothing_is_neither() {
        let mut items = vec![ItemId { object: 0, triangle: 0 }; 9];
        let crossed = [blend(4, 3, 0.25, Vec2::new(-0.375, 0.0))];
        assert_eq!(own_part(&crossed, &items, 3, |_| false), OwnPart::Shaded);
        items[4] = ItemId::NONE;
        assert_eq!(own_part(&crossed, &items, 3, |_| false), OwnPart::Stepped([(4, 0.0); 2]));
    }
}
