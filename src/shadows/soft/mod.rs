//! Soft shadows from two hard shadows (seed 001, Tsutsumi 2005, §3): two
//! hard shadows from L1 = L + l·P and L2 = L − l·P, on the line through the
//! light L and a focus point G (P = (L − G)/|L − G|, eqs. 3.1–3.2); in the
//! eye's view a pixel shadowed in both is umbra, in one penumbra, in neither
//! lit, and a penumbra pixel's visibility comes from its screen distances to
//! the nearest umbra and the nearest lit pixel ([`penumbra`]: by the paper's
//! search every N pixels, or by an exact distance transform, [`edt`], for
//! every pixel at once, optionally kept from crossing the view's depth
//! discontinuities).
//!
//! # Where the two points are
//!
//! Both lie on the axis through L and G. An occluder's edge `ρ` off the axis
//! at distance `a` from the light, over a receiver `b` beyond it, casts its
//! hard edge from a light moved `t` along the axis (away from G) at
//! ρ·(1 + b/(a + t)) from the axis; a disc light of radius `r` casts a
//! penumbra r·b/a either side of its centre's hard edge. The paper puts the
//! points at L ± l·P; kage's default (`points = "matched"`) moves them
//! unequally so each hard edge lands on one border of the disc's penumbra,
//! for every receiver distance b: t₁ = r·a/(ρ − r) away from G (the umbra's
//! border) and t₂ = r·a/(ρ + r) towards it (the penumbra's outer border).
//! The paper's symmetric pair (`points = "paper"`, l = a·(√(ρ² + 4r²) −
//! ρ)/(2r), which makes the penumbra as wide as the disc's) shifts the
//! penumbra outwards by about r·b·l/(ρ·a) — a sixth of its width for a
//! light half as wide as the occluder's outline.
//!
//! kage takes a = |L − G| and ρ the casters' lateral half-extent about the
//! axis (the root mean square of their bounds' half-extents across P): the
//! penumbra matches the disc's where the casters' outline is — the test of a
//! sphere under its light holds its width to 10% of the ray-traced truth at
//! three heights — and elsewhere it is about h/ρ times the disc's for an
//! edge h off the axis: none on the axis through G, twice as wide twice as
//! far out. L1 is kept within 8a of the light (for ρ ≤ r it would go to
//! infinity), L2 within half the way to the focus (on the light's side of
//! the casters), and, for a light inside the casters' bounds (a lamp in a
//! room), L1 within half the way to the bounds' side behind it (in the
//! room): there the penumbra is narrower than the disc's.
//!
//! The ring (`points = "ring"`) leaves the line: four hard shadows from a
//! square round L in the plane facing G, its corners 1.11 r out (a
//! square's reach across an edge is 0.71–1 of its corners', 0.90 on
//! average). An edge's hard shadows then spread as the disc's penumbra
//! does, whatever its place: from 0.79 to 1.11 of it, by the edge's
//! direction. On a pair's line an edge gets no penumbra — a rod under the
//! light casts umbra where the truth is more than half lit — and pixels
//! shadowed by different casters from the two points are umbra too; the
//! ring's pixels are umbra only when all four are shadowed (a grille of
//! slats: 5.1% of the pixels falsely umbra with the pair, 0.15% with the
//! ring, `kage-bench soft --defects`). A pixel whose hard shadows do not
//! overlap (reaching no umbra) takes the share of the points that reach it.
//!
//! # Which pixels are looked up
//!
//! The frame is taken 16 rows at a time; each 16 × 16 tile's surfaces are
//! bounded by a box, and where every hard shadow is one plain map read one
//! tap a point, the box's corners in each map and the map's depth bounds
//! over 8 × 8-texel blocks ([`tiles`]) decide the whole tile lit or umbra
//! when they can; only the other tiles' pixels take the hard lookups, eight
//! at a time. On the 640 × 360 frames of the soft-shadow example and the
//! demo the boxes decide 653 of 840 and 490 of 760 tiles. The lookups are
//! not where the term spends its time (on the 1920×1080 demo, 2 threads:
//! 3–7 ms for the bounds, 44–47 ms finding the surfaces, classifying and
//! cutting the bands, 24–26 ms for the distances), so deciding tiles saves
//! a few milliseconds of the stage's 70.
//!
//! # How visibility rises across the penumbra
//!
//! `falloff = "linear"` is the paper's V = D1/(D1 + D2). `"smooth"` (the
//! default) maps it through the share of a disc that a straight edge sweeping
//! across it uncovers, (x·√(1 − x²) + asin x)/π + ½ at x = 2V − 1: a disc
//! light's own penumbra profile, flat at both ends (from 10% to 90% it
//! spans 0.69 of the penumbra, the linear ramp 0.8).
//!
//! A directional light has no size in kage (the reference's shadows from it
//! are hard), and neither has a light of size 0: their soft term is their
//! hard one.

pub mod edt;
pub mod penumbra;
pub mod tiles;

use glam::Vec3;
use rayon::prelude::*;

use wide::f32x8;

use super::screen::{ScreenSurfaces, ScreenTerm, VisibleSurface};
use super::{DepthMap, PixelView, Receiver, ReceiverLanes, ShadowTerm, UNKNOWN_RECEIVER};
use crate::scene::{Light, LightKind, PenumbraFalloff, PenumbraPoints, ShadowSettings};
use penumbra::{visibility_across_cuts, visibility_searched, Zone};
use tiles::{classify_box, DepthBounds, TileClass};

/// Farthest the paper's search looks for an umbra or lit pixel, in pixels: a
/// penumbra pixel that finds neither within it is half lit.
pub const SEARCH_REACH: usize = 128;

/// Rows of the frame one worker classifies at a time: enough that the
/// triangles a band's pixels show are prepared once for many of them, few
/// enough that a band's surfaces stay in the worker's cache.
const BAND: usize = 16;

/// Pixels along a side of the screen tiles the hard maps' depth bounds
/// decide whole (as many as the rows of a band).
const TILE: usize = BAND;

/// A light's soft shadow from two (or more) hard shadows.
#[derive(Debug)]
pub struct TwoMaps {
    /// The hard shadows from each of the points (L1, away from the focus,
    /// then L2, towards it; or the ring's).
    hard: Vec<ShadowTerm>,
    /// The points.
    points: Vec<Vec3>,
    /// The light's centre L.
    centre: Vec3,
    settings: ShadowSettings,
    /// The term at every pixel of the frame it was last prepared for.
    screen: Option<ScreenTerm>,
    /// The hard maps' depth bounds, when every hard shadow is one map read
    /// one tap a point ([`tiles`]); found at the first frame.
    bounds: Option<Vec<DepthBounds>>,
}

impl TwoMaps {
    /// The soft term of `light` (its hard shadows built by `hard` for each of
    /// the two lights moved to L1 and L2), with the casters within `bounds`;
    /// `None` when the light has no size or no position (directional).
    pub fn build(light: &Light, bounds: (Vec3, Vec3), mut hard: impl FnMut(&Light) -> ShadowTerm) -> Option<TwoMaps> {
        let (centre, points) = Self::placed(light, bounds)?;
        let hard = points.iter().map(|&p| hard(&Self::moved(light, p))).collect();
        Some(TwoMaps { hard, points, centre, settings: light.shadow, screen: None, bounds: None })
    }

    /// The lights the hard shadows of `light` are cast from, as
    /// [`TwoMaps::build`] casts them: `light` moved to each point (L1 and
    /// L2, or the ring's four); `None` where [`TwoMaps::build`] gives none.
    #[must_use]
    pub fn hard_lights(light: &Light, bounds: (Vec3, Vec3)) -> Option<Vec<Light>> {
        let (_, points) = Self::placed(light, bounds)?;
        Some(points.iter().map(|&p| Self::moved(light, p)).collect())
    }

    /// The light's centre and the points its hard shadows are cast from.
    fn placed(light: &Light, bounds: (Vec3, Vec3)) -> Option<(Vec3, Vec<Vec3>)> {
        let centre = match light.kind {
            LightKind::Point { position } | LightKind::Spot { position, .. } => position,
            LightKind::Directional { .. } => return None,
        };
        let focus = light.shadow.focus.unwrap_or((bounds.0 + bounds.1) * 0.5);
        let points = match light.shadow.points {
            PenumbraPoints::Ring => ring_points(centre, light.size, focus)?.to_vec(),
            placing => two_points(centre, light.size, focus, bounds, placing)?.to_vec(),
        };
        Some((centre, points))
    }

    /// `light` moved to `to`, its kind and everything else kept.
    fn moved(light: &Light, to: Vec3) -> Light {
        let kind = match light.kind {
            LightKind::Spot { direction, inner, outer, .. } => {
                LightKind::Spot { position: to, direction, inner, outer }
            }
            _ => LightKind::Point { position: to },
        };
        Light { kind, ..light.clone() }
    }

    /// The points the hard shadows are cast from: L1 and L2, or the ring's.
    #[must_use]
    pub fn points(&self) -> &[Vec3] {
        &self.points
    }

    /// The hard terms, one per point.
    #[must_use]
    pub fn hard(&self) -> &[ShadowTerm] {
        &self.hard
    }

    /// Takes the hard terms (their maps' buffers back to a pool).
    #[must_use]
    pub fn into_hard(self) -> Vec<ShadowTerm> {
        self.hard
    }

    /// Sets the pixel rays the hard terms look up through.
    pub fn set_view(&mut self, view: Option<PixelView>) {
        self.hard.iter_mut().for_each(|h| h.set_view(view));
    }

    /// Computes the term at every pixel of `surfaces` (seed 001 §3.2–3.3):
    /// the zones from the two hard shadows, then visibility from the
    /// distances, shaped by the falloff. The frame is taken sixteen rows at
    /// a time, each band's surfaces found, classified and let go on one
    /// worker: only a byte of zone, a byte of cuts and the count of points
    /// reaching each pixel are kept for the distances.
    pub fn prepare(&mut self, surfaces: &ScreenSurfaces) {
        // The grid the term is computed on: every pixel, or every second one
        // each way (`half`), each sample the surface at its grid point's
        // first pixel.
        let stride = if self.settings.half { 2 } else { 1 };
        let (w, h) = ((surfaces.width as usize).div_ceil(stride), (surfaces.height as usize).div_ceil(stride));
        let n = w * h;
        let (mut zones, mut reached, mut cuts) = (vec![Zone::Lit; n], vec![0u8; n], vec![0u8; n]);
        let (mut distances, mut reach) = (vec![f32::NAN; n], vec![0.0f32; n]);
        let band = BAND * w.max(1);
        let bands = zones
            .par_chunks_mut(band)
            .zip(reached.par_chunks_mut(band))
            .zip(cuts.par_chunks_mut(band))
            .zip(distances.par_chunks_mut(band).zip(reach.par_chunks_mut(band)));
        let depth_aware = self.settings.depth_aware && self.settings.search == 0;
        if self.bounds.is_none() {
            let maps: Option<Vec<_>> = self.hard.iter().map(|h| h.one_tap_map()).collect();
            let bounds = maps.map(|maps| maps.par_iter().map(|(m, _)| DepthBounds::of(m)).collect());
            self.bounds = Some(bounds.unwrap_or_default());
        }
        let this = &*self;
        let bounded: Vec<_> = this.hard.iter().filter_map(|h| h.one_tap_map()).map(|(m, _)| m).collect();
        let pairs: Vec<(&DepthMap, &DepthBounds)> = match &this.bounds {
            Some(bounds) if !bounds.is_empty() => bounded.into_iter().zip(bounds).collect(),
            _ => Vec::new(),
        };
        let hard_settings = this.hard.first().and_then(|h| h.one_tap_map()).map(|(_, s)| *s);
        bands.enumerate().for_each_init(
            || (Vec::new(), Vec::new(), Vec::new(), Vec::new()),
            |(seen, footprints, row, classes), (b, (((zones, reached), cuts), (distances, reach)))| {
                let rows = zones.len() / w;
                // One row more than the band: its last row's cuts look below.
                let grid_rows = b * BAND..(b * BAND + rows + 1).min(h);
                if stride == 1 {
                    surfaces.rows(grid_rows, seen);
                } else {
                    seen.clear();
                    for y in grid_rows {
                        surfaces.rows(y * stride..y * stride + 1, row);
                        seen.extend(row.iter().step_by(stride));
                    }
                }
                let inside = rows * w;
                classes.clear();
                if let Some(settings) = &hard_settings {
                    this.classify_tiles(&seen[..inside], w, &pairs, settings, classes);
                }
                let all = this.hard.len() as u8;
                footprints.clear();
                footprints.resize(seen.len(), 0.0);
                let eights = seen[..inside].chunks(8).zip(zones.chunks_mut(8).zip(reached.chunks_mut(8)));
                for (k, (eight, (zones, reached))) in eights.enumerate() {
                    let lanes = Lanes::of(eight);
                    let class = |i: usize| classes.get((k * 8 + i) % w / TILE).copied().unwrap_or(TileClass::Mixed);
                    if (0..eight.len()).all(|i| class(i) != TileClass::Mixed) {
                        // A decided tile: what the lookups would say, unasked.
                        for (i, s) in eight.iter().enumerate() {
                            (zones[i], reached[i]) = match (s, class(i)) {
                                (None, _) | (_, TileClass::Lit) => (Zone::Lit, all),
                                _ => (Zone::Umbra, 0),
                            };
                        }
                    } else {
                        this.classify(&lanes, zones, reached);
                    }
                    let (footprint, distance) = surfaces.footprint_lanes(lanes.p, lanes.normal);
                    let (footprint, distance) = (footprint.to_array(), distance.to_array());
                    for (i, s) in eight.iter().enumerate() {
                        let at = k * 8 + i;
                        (footprints[at], distances[at]) =
                            if s.is_some() { (footprint[i] * stride as f32, distance[i]) } else { (0.0, f32::NAN) };
                        reach[at] = 2.0 * footprints[at];
                    }
                }
                for (f, s) in footprints[inside..].iter_mut().zip(&seen[inside..]) {
                    *f = s.as_ref().map_or(0.0, |s| surfaces.footprint(s) * stride as f32);
                }
                if depth_aware {
                    let apart = |i: usize, j: usize| {
                        j < seen.len()
                            && ScreenSurfaces::lie_apart(
                                seen[i].as_ref(),
                                footprints[i],
                                seen[j].as_ref(),
                                footprints[j],
                            )
                    };
                    for (i, cut) in cuts.iter_mut().enumerate() {
                        let right = (i + 1) % w != 0 && apart(i, i + 1);
                        *cut = edt::cut_bits(right, apart(i, i + w));
                    }
                }
            },
        );
        let all = self.hard.len().max(1) as f32;
        let unreached = |i: usize| f32::from(reached[i]) / all;
        let mut v = match self.settings.search {
            0 => visibility_across_cuts(&zones, &cuts, w, h, unreached),
            n => visibility_searched(&zones, w, h, n as usize, SEARCH_REACH, unreached),
        };
        if self.settings.penumbra == PenumbraFalloff::Smooth {
            v.par_iter_mut().for_each(|v| *v = disc_share(*v));
        }
        self.screen = Some(surfaces.term((w, h), distances, reach, v));
    }

    /// The class of each tile of `TILE` columns of the band of rows whose
    /// surfaces are `seen` (rows of `w`), into `classes`: from the box round
    /// its surfaces in every hard map ([`classify_box`]); lit only where
    /// every surface faces the light's centre (one facing away is umbra
    /// whatever the maps say); lit where none is seen.
    fn classify_tiles(
        &self,
        seen: &[Option<VisibleSurface>],
        w: usize,
        pairs: &[(&DepthMap, &DepthBounds)],
        settings: &ShadowSettings,
        classes: &mut Vec<TileClass>,
    ) {
        for x0 in (0..w).step_by(TILE) {
            let (mut lo, mut hi, mut facing) = (Vec3::INFINITY, Vec3::NEG_INFINITY, true);
            let surfaces = seen.chunks(w).flat_map(|row| row[x0..(x0 + TILE).min(w)].iter().flatten());
            for s in surfaces {
                (lo, hi) = (lo.min(s.position), hi.max(s.position));
                facing &= s.normal.dot(self.centre - s.position) > 0.0;
            }
            classes.push(if lo.x > hi.x {
                TileClass::Lit
            } else {
                match classify_box(pairs, lo, hi, settings) {
                    TileClass::Lit if !facing => TileClass::Mixed,
                    class => class,
                }
            });
        }
    }

    /// The zones of up to eight pixels showing `lanes`, and how many of
    /// the points reach each: umbra where a surface faces away from the
    /// light's centre, else by the hard shadows (looked up eight at a time);
    /// lit where nothing is seen.
    fn classify(&self, lanes: &Lanes, zones: &mut [Zone], reached: &mut [u8]) {
        let all = self.hard.len() as u8;
        if lanes.seen.iter().all(|&s| !s) {
            zones.fill(Zone::Lit);
            reached.fill(all);
            return;
        }
        let (p, normal) = (lanes.p, lanes.normal);
        // N·L towards `at`, eight at a time.
        let facing = |at: Vec3| {
            let to = [at.x, at.y, at.z].map(f32x8::splat);
            let d = [to[0] - p[0], to[1] - p[1], to[2] - p[2]];
            let length = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt().max(f32x8::splat(f32::MIN_POSITIVE));
            (normal[0] * d[0] + normal[1] * d[1] + normal[2] * d[2]) / length
        };
        let mut count = [0u8; 8];
        for (hard, &at) in self.hard.iter().zip(&self.points) {
            let cos = facing(at).max(f32x8::splat(1e-3));
            for (n, v) in count.iter_mut().zip(hard.lit_lanes(p, cos, &lanes.receivers).to_array()) {
                *n += u8::from(v >= 0.5);
            }
        }
        let towards_centre = facing(self.centre).to_array();
        for (i, (zone, reached)) in zones.iter_mut().zip(reached.iter_mut()).enumerate() {
            (*zone, *reached) = if !lanes.seen[i] {
                (Zone::Lit, all)
            } else if towards_centre[i] <= 0.0 {
                (Zone::Umbra, 0)
            } else {
                match count[i] {
                    0 => (Zone::Umbra, 0),
                    n if n == all => (Zone::Lit, all),
                    n => (Zone::Penumbra, n),
                }
            };
        }
    }

    /// The term at `p` on `receiver` with N·L = `cos_theta`: the prepared
    /// frame's where a pixel shows `p`, else from the hard shadows alone
    /// (the share of the points that reach `p`).
    #[must_use]
    pub fn lit(&self, p: Vec3, cos_theta: f32, receiver: &Receiver) -> f32 {
        if let Some(v) = self.screen.as_ref().and_then(|s| s.at(p)) {
            return v;
        }
        let sum: f32 = self.hard.iter().map(|h| h.lit(p, cos_theta, receiver)).sum();
        sum / self.hard.len().max(1) as f32
    }

    /// The term at every pixel of the frame last prepared, row by row.
    #[must_use]
    pub fn screen(&self) -> Option<&ScreenTerm> {
        self.screen.as_ref()
    }

    /// Bytes held by the maps and the per-pixel term.
    #[must_use]
    pub fn memory_bytes(&self) -> usize {
        self.hard.iter().map(ShadowTerm::memory_bytes).sum::<usize>()
            + self.screen.as_ref().map_or(0, ScreenTerm::memory_bytes)
    }
}

/// Up to eight pixels' surfaces as lanes: points, normals, receivers, and
/// which lanes show a surface (the others hold zeros).
struct Lanes {
    seen: [bool; 8],
    p: [f32x8; 3],
    normal: [f32x8; 3],
    receivers: ReceiverLanes,
}

impl Lanes {
    fn of(surfaces: &[Option<VisibleSurface>]) -> Lanes {
        let (mut p, mut normal, mut planes) = ([[0.0f32; 8]; 3], [[0.0f32; 8]; 3], [[0.0f32; 8]; 3]);
        let (mut objects, mut seen) = ([UNKNOWN_RECEIVER; 8], [false; 8]);
        for (i, s) in surfaces.iter().take(8).enumerate() {
            if let Some(s) = s {
                for a in 0..3 {
                    (p[a][i], normal[a][i], planes[a][i]) = (s.position[a], s.normal[a], s.receiver.plane[a]);
                }
                (objects[i], seen[i]) = (s.receiver.object, true);
            }
        }
        let receivers = ReceiverLanes { objects, planes: planes.map(f32x8::new) };
        Lanes { seen, p: p.map(f32x8::new), normal: normal.map(f32x8::new), receivers }
    }
}

/// L1 and L2 for a light at `centre` of radius `size`, focused on `focus`,
/// casters within `bounds`, placed as `placing` says (see the module's doc
/// for the derivation); `None` for a light of no size or one at the focus.
#[must_use]
pub fn two_points(
    centre: Vec3,
    size: f32,
    focus: Vec3,
    bounds: (Vec3, Vec3),
    placing: PenumbraPoints,
) -> Option<[Vec3; 2]> {
    let to_light = centre - focus;
    let a = to_light.length();
    if size <= 0.0 || a <= f32::EPSILON {
        return None;
    }
    let p = to_light / a;
    let half = (bounds.1 - bounds.0) * 0.5;
    // Root mean square of the bounds' half-extents across P.
    let rho = ((half * half).dot(Vec3::ONE - p * p) * 0.5).sqrt().max(a * 1e-3);
    let r = size;
    let (away, towards) = match placing {
        // The ring has its own points (`ring_points`): a pair asked for it is matched.
        PenumbraPoints::Matched | PenumbraPoints::Ring => {
            let away = if rho > r { r * a / (rho - r) } else { f32::INFINITY };
            (away, r * a / (rho + r))
        }
        PenumbraPoints::Paper => {
            let l = a * ((rho * rho + 4.0 * r * r).sqrt() - rho) / (2.0 * r);
            (l, l)
        }
    };
    let behind = exit_distance(centre, p, bounds).map_or(f32::INFINITY, |exit| 0.5 * exit);
    let (away, towards) = (away.min(8.0 * a).min(behind), towards.min(0.5 * a));
    Some([centre + p * away, centre - p * towards])
}

/// Four points round a light at `centre` of radius `size`, on a square in
/// the plane facing `focus`: the hard shadows from them bound a disc light's
/// penumbra wherever an edge is, to within the square's support (its
/// corners at 1.11 × the radius, so that across every direction the mean
/// reach is the disc's: from 0.79 to 1.11 of it); `None` for a light of no
/// size or one at the focus.
#[must_use]
pub fn ring_points(centre: Vec3, size: f32, focus: Vec3) -> Option<[Vec3; 4]> {
    let to_light = centre - focus;
    if size <= 0.0 || to_light.length() <= f32::EPSILON {
        return None;
    }
    let (u, v) = to_light.normalize().any_orthonormal_pair();
    // A square's mean support over directions is (4/π)·sin(π/4) = 0.900 of
    // its corners' radius.
    let reach = size / (4.0 / std::f32::consts::PI * std::f32::consts::FRAC_1_SQRT_2);
    Some([centre + u * reach, centre + v * reach, centre - u * reach, centre - v * reach])
}

/// The share of a disc a straight edge uncovers when it has swept a share
/// `v` of the way across it: (x·√(1 − x²) + asin x)/π + ½ at x = 2v − 1.
#[must_use]
pub fn disc_share(v: f32) -> f32 {
    let x = (2.0 * v - 1.0).clamp(-1.0, 1.0);
    ((x * (1.0 - x * x).sqrt() + x.asin()) / std::f32::consts::PI + 0.5).clamp(0.0, 1.0)
}

/// How far a ray from `from` (inside `bounds`) along `dir` runs before it
/// leaves them; `None` when `from` lies outside.
fn exit_distance(from: Vec3, dir: Vec3, (lo, hi): (Vec3, Vec3)) -> Option<f32> {
    if from.cmplt(lo).any() || from.cmpgt(hi).any() {
        return None;
    }
    let t = |o: f32, d: f32, lo: f32, hi: f32| {
        if d > 0.0 {
            (hi - o) / d
        } else if d < 0.0 {
            (lo - o) / d
        } else {
            f32::INFINITY
        }
    };
    Some(t(from.x, dir.x, lo.x, hi.x).min(t(from.y, dir.y, lo.y, hi.y)).min(t(from.z, dir.z, lo.z, hi.z)))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The disc's share is 0, ½ and 1 at the ends and the middle, rises
    /// everywhere, and is symmetric.
    #[test]
    fn a_disc_is_uncovered_from_none_to_all() {
        assert_eq!((disc_share(0.0), disc_share(1.0)), (0.0, 1.0));
        assert!((disc_share(0.5) - 0.5).abs() < 1e-6);
        let v: Vec<f32> = (0..=100).map(|i| disc_share(i as f32 / 100.0)).collect();
        assert!(v.windows(2).all(|w| w[1] > w[0]));
        assert!((0..=100).all(|i| (v[i] + v[100 - i] - 1.0).abs() < 1e-5));
        // A quarter of the way across, a segment of height r/2 is uncovered.
        let segment = (std::f32::consts::PI / 3.0 - 3f32.sqrt() / 4.0) / std::f32::consts::PI;
        assert!((disc_share(0.25) - segment).abs() < 1e-5);
    }

    /// The paper's pair: for a small light l ≈ r·a/ρ, both points on the
    /// line through the light and the focus, on either side of the light,
    /// equally far. The matched pair puts each hard edge on a border of the
    /// disc's penumbra.
    #[test]
    fn the_two_points_straddle_the_light_on_the_line_to_the_focus() {
        let bounds = (Vec3::new(-0.5, 0.5, -0.5), Vec3::new(0.5, 1.5, 0.5));
        let (centre, focus) = (Vec3::new(0.0, 20.0, 0.0), Vec3::Y);
        let [l1, l2] = two_points(centre, 0.01, focus, bounds, PenumbraPoints::Paper).unwrap();
        assert!(((l1 - centre).length() - 0.01 * 19.0 / 0.5).abs() < 1e-3);
        assert!(((l1 + l2) * 0.5 - centre).length() < 1e-4);
        assert!((l1 - focus).normalize().dot((centre - focus).normalize()) > 0.99999);
        assert!(l1.y > centre.y && l2.y < centre.y);
        assert!(two_points(centre, 0.0, focus, bounds, PenumbraPoints::Paper).is_none());
        // Matched: each hard edge of an edge ρ = 0.5 off the axis, 19 from the
        // light, lands r·b/a either side of the centre's, for any b.
        let [l1, l2] = two_points(centre, 0.2, focus, bounds, PenumbraPoints::Matched).unwrap();
        let edge = |light: Vec3, b: f32| {
            let (a, h) = (light.y - 1.0, 0.5);
            h * (a + b) / a
        };
        for b in [0.5, 1.0, 3.0] {
            let (mid, spread) = (edge(centre, b), 0.2 * b / 19.0);
            assert!((edge(l1, b) - (mid - spread)).abs() < 1e-4, "umbra border at b = {b}");
            assert!((edge(l2, b) - (mid + spread)).abs() < 1e-4, "outer border at b = {b}");
        }
    }

    /// The ring's four points lie on a square round the light, in the plane
    /// facing the focus, 1.11 radii out; none for a light of no size.
    #[test]
    fn the_ring_is_a_square_facing_the_focus() {
        let (centre, focus) = (Vec3::new(1.0, 5.0, 2.0), Vec3::new(0.0, 1.0, 0.0));
        let ring = ring_points(centre, 0.3, focus).unwrap();
        let axis = (centre - focus).normalize();
        for (k, p) in ring.iter().enumerate() {
            let out = *p - centre;
            assert!(out.dot(axis).abs() < 1e-5, "point {k} off the plane facing the focus");
            assert!((out.length() - 0.3 * std::f32::consts::PI / (2.0 * 2f32.sqrt())).abs() < 1e-5);
            assert!(out.dot(ring[(k + 1) % 4] - centre).abs() < 1e-5, "neighbours at right angles");
        }
        assert!((ring[0] + ring[2] - 2.0 * centre).length() < 1e-5);
        assert!(ring_points(centre, 0.0, focus).is_none());
    }
}
