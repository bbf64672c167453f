//! Feature lines: the outline of every object drawn over the finished image as
//! antialiased lines of one width and colour, the look of a technical drawing
//! ([`crate::scene::FeatureLines`]).
//!
//! - Meshes: from the edge pass's edge lists ([`MeshEdges`]: vertices welded
//!   by position, the faces on either side): a mesh's boundaries, its
//!   silhouettes (one face towards the eye, the other away) and its creases,
//!   where the two faces' normals differ by more than the lines'
//!   `crease_deg` (the surface's own fold, not the shading's: a smooth-shaded
//!   box still has its edges drawn, a finely tessellated sphere none inside).
//!   Each edge is projected as the edge pass projects it and stepped along a
//!   pixel at a time, each step depth-tested against the visibility buffer:
//!   hidden where the surface its pixel shows lies nearer than the edge even
//!   a pixel to either side (`visible.rs`). Hidden steps are dropped, or
//!   dashed when the lines ask for hidden lines (then the creases between
//!   faces turned away are drawn too). A step is a stroke of its own,
//!   counted from the edge's projected start, so a tile draws the strokes
//!   the whole frame draws there.
//! - CSG solids have no edge lists: their outlines are found in the image
//!   (`solids.rs`), between neighbouring pixels where a solid meets another
//!   object, the background, or itself across a fold or a step in depth, the
//!   crossing placed between the two pixels' centres by the two surfaces'
//!   planes (a fold) or a ray; the crossings are joined cell by cell
//!   (marching squares). They have no hidden lines.
//! - The lines are drawn as round-capped strokes (`draw.rs`): each pixel
//!   takes the largest coverage any stroke gives it, so where strokes meet
//!   (a polygon's corner, a dash's overlap) nothing is drawn twice darker,
//!   and the result does not depend on the order of the strokes or threads.
//!
//! Lines are drawn over the image only: the component images (`--aov`) are
//! left without them.
//!
//! Measured (`kage-bench ao`, 960×540, 2-core EPYC VM): lines cost 1.07–1.14×
//! a frame on the demo, the bunny and the glTF truck, 1.22× on a corpus
//! OpenSCAD part (its outline's crossings each cast a ray).

mod draw;
mod solids;
mod visible;

use std::sync::Arc;

use glam::DVec2;

use super::mesh_edges::MeshEdges;
use crate::image::LinearImage;
use crate::raytrace::TraceScene;
use crate::scene::{FeatureLines, Scene};
use crate::visibility::VisibilityBuffer;

/// A piece of a feature line on the screen (pixel units, pixel centres at
/// +0.5): from `a` to `b`, where the line's length so far (for dashes) is
/// `start` at `a`.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Stroke {
    a: DVec2,
    b: DVec2,
    start: f64,
}

/// The strokes of one frame's lines: those that show, and those hidden
/// behind a surface.
#[derive(Debug, Default)]
struct Strokes {
    shown: Vec<Stroke>,
    hidden: Vec<Stroke>,
}

/// How dark a hidden line is drawn, as a share of a shown one.
const HIDDEN_SHARE: f32 = 0.6;

/// Draws `lines` for the frame of `scene` whose visibility buffer is `vb`
/// into `image` (the pixels `vb` holds), the meshes' edges from `edges`
/// (per object, as the edge pass found them) and the solids' outlines
/// measured by `trace` (`None`: no solid in the scene). Returns the pixels
/// drawn on.
pub fn draw_lines(
    scene: &Scene,
    vb: &VisibilityBuffer,
    image: &mut LinearImage,
    edges: &[Option<Arc<MeshEdges>>],
    trace: Option<&TraceScene>,
    lines: &FeatureLines,
) -> usize {
    let width = lines.width.clamp(*FeatureLines::WIDTHS.start(), *FeatureLines::WIDTHS.end());
    let mut strokes = visible::mesh_strokes(scene, vb, edges, lines, width);
    if let Some(trace) = trace {
        strokes.shown.extend(solids::outline_strokes(scene, vb, trace, lines.crease_deg));
    }
    let held = vb.rect();
    let shown = draw::coverage(&strokes.shown, held, width, None);
    let hidden = if lines.hidden {
        draw::coverage(&strokes.hidden, held, width, Some(draw::Dashes::of(width)))
    } else {
        Vec::new()
    };
    let faint = hidden.into_iter().map(|(i, c)| (i, c * HIDDEN_SHARE));
    // Shown and hidden lines over one pixel: the darker.
    let mut spots: Vec<(u32, f32)> = shown.into_iter().chain(faint).collect();
    draw::largest_each(&mut spots);
    let pixels = image.pixels_mut();
    for &(i, alpha) in &spots {
        let px = &mut pixels[i as usize];
        *px += (lines.colour - *px) * alpha;
    }
    spots.len()
}
