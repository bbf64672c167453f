//! Antialiased edges after an aliased fill: seed 004 (Kato & Kameyama, "A fast and
//! simple antialiased polygon rendering", §3 (2)).
//!
//! Pass 1 (the visibility pass and shading) leaves every pixel entirely one surface:
//! the one whose triangle covers the pixel centre. Pass 2 walks the edges with a DDA
//! along each edge's major axis. At column i (an x-major edge; y-major edges are the
//! same with the axes swapped, through one walker: `dda.rs`) the edge's true height is `Y_i`;
//! the pixels `P_i` above and `Q_i` below have their centres on either side of it, at
//! distances `D_P` and `D_Q = 1 − D_P`. The paper blends the edge's colour into both,
//! with alphas `Filter(D_Q)` and `Filter(D_P)`, z-tested and never z-written, so a
//! partly covered pixel never hides anything.
//!
//! What kage makes of the paper's open points (measured in `docs/benchmarks.md`):
//!
//! - Alpha. Of the two pixels only the one whose square the edge crosses is wrong
//!   after the aliased fill: the other lies wholly on its centre's side. The wrong
//!   one, `C` (the nearer, at distance `d = min(D_P, D_Q) < ½`), shows its centre's
//!   side but has `½ − d` of its area on the far side of the edge. So `C` takes the
//!   colour of the pixel across the edge, `O`, with alpha `Filter(d) = ½ − d`:
//!   `C ← C + (½ − d)·(O − C)`. When `C` lies outside the polygon this is the
//!   paper's blend of the edge colour (the colour of the surface next to the edge);
//!   when `C` lies inside, it brings back the background the fill covered, which
//!   blending the edge colour alone cannot — without it a straight edge is drawn half
//!   a pixel too fat on every other column. Where the edge's line crosses two rows
//!   of a column, both crossed pixels are blended, each by its own share, so for a
//!   straight edge every pixel ends at its exact covered area. The paper's weights
//!   are kept as [`EdgeFilter::Paper`], to measure against.
//! - The parts' colours. The paper's colours come from pass 1's pixel centres;
//!   but a part of a pixel beyond a silhouette can lie in a shadow that begins
//!   right behind the silhouette, and a grazing surface's shading changes fast
//!   within one pixel. So the blends are found from the visibility buffer alone
//!   ([`plan`], while the first pass shades the pixels:
//!   [`EdgePass::plan`]), and a part's colour is its pixel's
//!   moved by how the shading changes from the pixel's centre to the part's
//!   centroid: shaded there by the passes themselves
//!   (parts beyond edges, and own parts on curved surfaces), or stepped along the
//!   colours of the pixel's neighbours (own parts on flat faces): `parts.rs`.
//!   Against the supersampled truth this removes about eight to ten points
//!   more of the aliased edge error than the pixels' own colours do
//!   (`docs/benchmarks.md`, "Design measurements").
//! - Intersections. Where two objects pass through each other (a box standing
//!   in a floor) the outline is no mesh edge: `intersections.rs` finds it from
//!   the two pixels' depth planes, and it is blended like an edge.
//! - Gamma. The frame is linear light, so blending there is the gamma-corrected
//!   filter the paper asks for; the sRGB curve is applied at output.
//! - Which edges. By default the outline: silhouette edges (one adjacent face towards
//!   the eye, one away), mesh boundaries and creases, with vertices welded by
//!   position so the UV seam of a smooth sphere is not an edge. A crease is where
//!   the shading breaks: the two faces' vertex normals at an end of the edge differ
//!   by more than [`EdgeOptions::crease_deg`] (a flat-shaded mesh breaks at every
//!   fold; a smooth-shaded one, however sharply folded, has no crease to smooth —
//!   blending across its folds only blurred a scanned model's detail). [`EdgeSelection::All`](crate::scene::EdgeSelection::All) walks every
//!   triangle edge, as the paper does.
//! - Depth test. Each pixel is classed against the edge: the edge's own surface (it
//!   shows a triangle that touches a face beside the edge), else by depth against
//!   the edge's depth at that point: an occluder (nearer) or what lies behind. (A
//!   depth tolerance alone cannot tell a visible silhouette, whose inside pixels lie
//!   a few per cent nearer at grazing angles, from the hidden silhouette of the same
//!   object's far side a few per cent farther.)
//!   An occluder is judged at the edge's point, not at its pixel's centre: the
//!   pixel's surface plane carried to the point must lie nearer than the edge
//!   (beyond rounding) (a floor pixel just below a box standing on it lies nearer than
//!   the box's bottom edge, but the floor meets that edge). Nothing is blended
//!   where either pixel is an occluder, so a hidden
//!   edge never bleeds through; the blend happens when at least one pixel is the
//!   edge's own surface. The pixel across the edge is always read from the frame as
//!   pass 1 left it.
//! - Order. Every edge's blends are computed from the unchanged pass-1 frame and
//!   applied in scene order (object, then edge), so the result does not depend on
//!   threads.
//! - The same blends are applied to every component image (`--aov`): each is linear
//!   in the image, so the components still sum to the frame.

mod blend;
mod dda;
mod intersections;
pub mod lines;
mod mesh_edges;
mod parts;
mod screen;
mod solid_outlines;
mod walk;

use glam::Vec3;

pub use mesh_edges::{EdgeCache, MeshEdges};
pub use parts::{EdgePlan, RESHADED_SHARE};
pub use solid_outlines::{apply_outline_blends, find_outline_blends, OutlineBlend};

use crate::raytrace::TraceCache;
use crate::scene::{EdgeFilter, EdgeMode, Object, Scene};
use crate::shading::{SubpixelShading, Target};
use crate::visibility::{ItemId, VisibilityBuffer};
use screen::ClipMap;
use walk::{find_blends, merge};

/// The edge pass as one stage of the frame, kept from frame to frame (the
/// meshes' edges are found once per mesh). Its steps, at their places in the
/// frame:
///
/// 1. [`EdgePass::plan`], beside the first shading pass: the blends, found
///    from the visibility buffer alone, and the sub-pixel points the passes
///    shade for the parts' colours;
/// 2. [`EdgePass::record`], after the traced term: how far each part's colour
///    moves from its pixel's, as the passes left the images (and the blends
///    applied at once when nothing is drawn over the frame later);
/// 3. [`EdgePass::apply`], after fog and translucency: the crossed pixels
///    blended, then the solids' outlines, measured by rays.
///
/// A jittered frame has no edge pass: its passes sample every pixel at as many
/// points, outlines and all (the scene asks for one or the other,
/// [`crate::scene::Antialias`]).
#[derive(Debug, Default)]
pub struct EdgePass {
    cache: EdgeCache,
    /// This frame's plan (`None`: no edge pass).
    plan: Option<EdgePlan>,
    /// Whether the plan's blends are in the images already.
    applied: bool,
    /// Pixels blended this frame.
    blends: usize,
}

impl EdgePass {
    /// Step 1: plans the pass over the frame whose visibility buffer is `vb`
    /// (nothing when `options` is `None`), and sets `subpixel` to the samples
    /// the plan needs shaded.
    pub fn plan(
        &mut self,
        scene: &Scene,
        vb: &VisibilityBuffer,
        options: Option<&EdgeOptions>,
        subpixel: &mut SubpixelShading,
    ) {
        self.plan = options.map(|o| plan(scene, vb, o, &mut self.cache));
        (self.applied, self.blends) = (false, self.plan.as_ref().map_or(0, EdgePlan::len));
        let samples = self.plan.as_ref().map_or_else(Vec::new, |p| p.samples());
        subpixel.reset(scene, vb, samples);
    }

    /// Step 2: records the parts' colours from `targets` as the shading
    /// passes and the traced term left them, and `subpixel`'s samples, shaded;
    /// when `nothing_over` (no fog, no translucent surface to come) the
    /// blends go into the images at once.
    pub fn record(&mut self, targets: &mut [Target], subpixel: &SubpixelShading, nothing_over: bool) {
        let Some(plan) = &mut self.plan else { return };
        if nothing_over {
            plan.record_and_apply(targets, subpixel);
            self.applied = true;
        } else {
            plan.record(targets, subpixel);
        }
    }

    /// Step 3: blends the crossed pixels of every target (each part's move
    /// scaled by how much of its opaque surface its pixel still shows, `seen`:
    /// through fog and translucent surfaces), then the pixels on solids'
    /// outlines, measured by rays through the scene's BVH (from `trace`).
    pub fn apply(
        &mut self,
        scene: &Scene,
        vb: &VisibilityBuffer,
        targets: &mut [Target],
        seen: Option<&[f32]>,
        trace: &mut TraceCache,
    ) {
        let Some(plan) = &self.plan else { return };
        if !self.applied {
            targets.iter_mut().for_each(|t| plan.apply(t.image, t.parts, seen));
            self.applied = true;
        }
        if scene.objects.iter().any(|o| o.solid().is_some()) {
            // Solids' outlines are curves no mesh edge bounds: measured by rays.
            let blends = find_outline_blends(scene, vb, trace.get(scene));
            targets.iter_mut().for_each(|t| apply_outline_blends(t.image, &blends));
            self.blends += blends.len();
        }
    }

    /// Draws the scene's feature lines ([`crate::scene::FeatureLines`]) into
    /// `image` (the pixels `vb` holds), from the edge lists this pass keeps
    /// and, where the scene has solids, rays through `trace`. Returns the
    /// pixels drawn on (0 without lines).
    pub fn draw_lines(
        &mut self,
        scene: &Scene,
        vb: &VisibilityBuffer,
        image: &mut crate::image::LinearImage,
        trace: &mut TraceCache,
    ) -> usize {
        let Some(lines) = &scene.lines else { return 0 };
        let edges = self.cache.edges_as_kept(scene);
        let solids = scene.objects.iter().any(|o| o.solid().is_some());
        let trace = solids.then(|| trace.get(scene));
        lines::draw_lines(scene, vb, image, &edges, trace, lines)
    }

    /// The pixels this frame's pass blended (0 without one).
    #[must_use]
    pub fn blends(&self) -> usize {
        self.blends
    }
}

/// How the edge pass runs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EdgeOptions {
    /// Which edges and how they blend.
    pub mode: EdgeMode,
    /// Adjacent faces whose vertex normals at a shared end differ by more than
    /// this (degrees) meet at a crease, which is drawn like a silhouette.
    pub crease_deg: f32,
}

impl Default for EdgeOptions {
    fn default() -> Self {
        EdgeOptions { mode: EdgeMode::default(), crease_deg: 30.0 }
    }
}

/// Plans seed 004's edge pass over the frame whose visibility buffer is `vb`.
#[must_use]
pub fn plan(scene: &Scene, vb: &VisibilityBuffer, options: &EdgeOptions, cache: &mut EdgeCache) -> EdgePlan {
    let edges = cache.edges_of(scene, options.crease_deg);
    let clips = ClipMap::of_objects(scene, vb.width(), vb.height());
    let mut blends = find_blends(scene, vb, &edges, &clips, options.mode);
    if options.mode.filter == EdgeFilter::Coverage {
        // Where an edge runs between two pixels it bounds what they show; an
        // intersection is only looked for where none does.
        let walked = intersections::WalkedPairs::of(&blends, vb.rect().width(), vb.rect().height());
        let opaque = |o: &Object| !scene.materials[o.material].translucent();
        let objects = scene.objects.iter().zip(&edges);
        let boxes: Vec<(Vec3, Vec3)> =
            objects.filter(|(o, _)| opaque(o)).filter_map(|(o, e)| Some(o.world_box(e.as_ref()?.bounds))).collect();
        blends.extend(intersections::find_intersection_blends(scene, vb, &clips, &walked, &boxes));
    }
    // One straight edge moves a pixel by at most ½ under the coverage filter; the
    // paper's Wu weights reach 1.
    let cap = match options.mode.filter {
        EdgeFilter::Coverage => 0.5,
        EdgeFilter::Paper => 1.0,
    };
    let blends = merge(blends, cap, vb.rect().width());
    let flat = |item: ItemId| {
        let edges = edges.get(item.object as usize).and_then(Option::as_ref);
        item.primitive().is_none() && edges.is_some_and(|e| e.flat.get(item.triangle as usize) == Some(&true))
    };
    EdgePlan::new(blends, options.mode.filter == EdgeFilter::Coverage, vb, flat)
}
