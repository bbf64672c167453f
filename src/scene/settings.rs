//! How a scene is finished: exposure of 8-bit output, antialiasing, fog and the
//! order of translucent surfaces. Plain data, read from scene files and command
//! lines; the stages that act on them live further up the frame.

use glam::{Affine3A, Vec2, Vec3};

use crate::camera::{Camera, Projection};
use crate::image::LinearImage;
use crate::sampling::radical_inverse;

/// Which axis of a model file points up. kage's world is y-up; a z-up model
/// (STL from CAD tools and slicers, OpenSCAD) is turned as it is placed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Up {
    /// +y up (OBJ's convention, glTF's rule).
    #[default]
    Y,
    /// +z up (STL, OpenSCAD).
    Z,
}

impl Up {
    /// The turn from a model with this up axis into kage's y-up world: a
    /// z-up model's +z becomes +y, its +y becomes −z.
    #[must_use]
    pub fn turn(self) -> Affine3A {
        match self {
            Up::Y => Affine3A::IDENTITY,
            Up::Z => Affine3A::from_rotation_x(-std::f32::consts::FRAC_PI_2),
        }
    }
}

/// How bright the 8-bit image is made.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Exposure {
    /// Multiply by 2^stops (0: the buffer as it is).
    Stops(f32),
    /// Scale so the brightest 5% of pixels just reach white (for scenes lit in
    /// physical units, such as glTF lights in candela).
    Auto,
}

impl Default for Exposure {
    fn default() -> Self {
        Exposure::Stops(0.0)
    }
}

impl Exposure {
    /// The linear multiplier this exposure applies to `image`.
    #[must_use]
    pub fn scale(self, image: &LinearImage) -> f32 {
        match self {
            Exposure::Stops(ev) => ev.exp2(),
            Exposure::Auto => {
                let mut lum: Vec<f32> =
                    image.pixels().iter().map(|p| p.dot(Vec3::new(0.2126, 0.7152, 0.0722))).collect();
                if lum.is_empty() {
                    return 1.0;
                }
                let k = (lum.len() * 95 / 100).min(lum.len() - 1);
                let (_, p95, _) = lum.select_nth_unstable_by(k, f32::total_cmp);
                if *p95 > 0.0 && p95.is_finite() {
                    (0.9 / *p95).clamp(1.0 / 4096.0, 4096.0)
                } else {
                    1.0
                }
            }
        }
    }
}

/// How a frame is antialiased. The default is the edge pass with its default
/// mode: silhouettes, boundaries and creases blended by coverage, at about the
/// cost of one more shading pass over the edge pixels.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Antialias {
    /// One sample at each pixel centre.
    None,
    /// `n` frames with sub-pixel jitter, averaged (n = 1 is one centred frame).
    Jitter(u32),
    /// One frame, then the edge pass (seed 004).
    Edge(EdgeMode),
}

impl Default for Antialias {
    fn default() -> Self {
        Antialias::Edge(EdgeMode::default())
    }
}

/// Most jittered passes one frame may take.
pub const MAX_JITTER_SAMPLES: u32 = 1024;

impl Antialias {
    /// Sub-pixel offsets of the passes, in pixels within (−0.5, 0.5)²: one centred
    /// pass, or the first `n` points of the Halton (2, 3) sequence, which fill the
    /// pixel evenly for every prefix length.
    #[must_use]
    pub fn offsets(self) -> Vec<Vec2> {
        match self {
            Antialias::None | Antialias::Edge(_) | Antialias::Jitter(0 | 1) => vec![Vec2::ZERO],
            Antialias::Jitter(n) => (1..=n.min(MAX_JITTER_SAMPLES))
                .map(|i| Vec2::new(radical_inverse(i, 2), radical_inverse(i, 3)) - 0.5)
                .collect(),
        }
    }
}

/// Which edges the edge pass walks.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum EdgeSelection {
    /// Silhouettes, mesh boundaries and creases.
    #[default]
    Outline,
    /// Every triangle edge with a face towards the eye (the paper).
    All,
}

/// How the edge pass weights its blends.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum EdgeFilter {
    /// The pixel the edge crosses moves towards the pixel across by the share of its
    /// area beyond the edge (exact for a straight edge).
    #[default]
    Coverage,
    /// The paper's: the edge's colour is blended into the two pixels whose centres
    /// straddle the edge, with alphas `Filter(D_Q)` and `Filter(D_P)`, D the
    /// distance from each centre (a Wu line along the edge).
    Paper,
}

/// Which edges the pass walks and how it blends: what a scene asks for.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct EdgeMode {
    /// Which edges.
    pub selection: EdgeSelection,
    /// How blends are weighted.
    pub filter: EdgeFilter,
}

/// How fog thickens with distance.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum FogMode {
    /// f = (d − start) / (end − start), clamped to [0, 1].
    Linear {
        /// Distance where fog begins.
        start: f32,
        /// Distance where fog is complete.
        end: f32,
    },
    /// f = 1 − e^(−density · d).
    Exp {
        /// Extinction per unit distance.
        density: f32,
    },
    /// f = 1 − e^(−(density · d)²).
    Exp2 {
        /// Extinction per unit distance.
        density: f32,
    },
}

/// Fog of one colour.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Fog {
    /// How f grows with distance.
    pub mode: FogMode,
    /// Linear RGB colour of full fog.
    pub color: Vec3,
}

impl Fog {
    /// The fog amount f(d) ∈ [0, 1] at distance `d`.
    #[must_use]
    pub fn amount(&self, d: f32) -> f32 {
        let f = match self.mode {
            FogMode::Linear { start, end } => (d - start) / (end - start).max(f32::MIN_POSITIVE),
            FogMode::Exp { density } => 1.0 - (-density * d).exp(),
            FogMode::Exp2 { density } => 1.0 - (-(density * d) * (density * d)).exp(),
        };
        f.clamp(0.0, 1.0)
    }

    /// The fog amount at world point `p` seen by `camera` (the same distance as
    /// fog pass measures: along the ray, or from the image plane when
    /// orthographic).
    #[must_use]
    pub fn amount_at(&self, camera: &Camera, p: Vec3) -> f32 {
        let d = match camera.projection {
            Projection::Perspective { .. } => (p - camera.eye).length(),
            Projection::Orthographic { .. } => (p - camera.eye).dot((camera.target - camera.eye).normalize()),
        };
        self.amount(d)
    }
}

/// How translucent fragments are ordered in a pixel.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum TranslucencyOrder {
    /// By depth, far to near (correct wherever surfaces overlap or intersect).
    #[default]
    Sorted,
    /// In drawing order (scene order), as the paper's z-write-off fallback.
    Unsorted,
}

/// Ambient occlusion: the ambient term at a point scaled by the share of the
/// hemisphere above it that is open within `radius` (cosine-weighted), found by
/// rays ([`crate::raytrace::occlusion`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AmbientOcclusion {
    /// How far away an occluder still darkens, in world units (`None`:
    /// [`AmbientOcclusion::RADIUS_OF_SIZE`] of the diagonal of the objects' box).
    pub radius: Option<f32>,
    /// Rays a point casts in one pass.
    pub rays: u32,
    /// Which of each point's rays a pass casts: pass `p` casts rays
    /// `p · rays .. (p + 1) · rays` of the point's sequence, so the passes of a
    /// progressive preview (or of jittered antialiasing) add new rays, not the
    /// same ones again.
    pub pass: u32,
    /// Estimate the share from the frame's depth buffer instead of casting
    /// rays ([`crate::shading::screen_occlusion`]): far cheaper, blind to what
    /// the frame does not show; the viewer's form while the camera moves.
    pub screen_space: bool,
}

impl AmbientOcclusion {
    /// The default radius's share of the diagonal of the objects' box.
    pub const RADIUS_OF_SIZE: f32 = 0.1;
    /// Most rays a point may cast in one pass.
    pub const MAX_RAYS: u32 = 4096;
}

impl Default for AmbientOcclusion {
    /// The radius from the model's size, 16 rays a point, the first pass,
    /// traced.
    fn default() -> Self {
        AmbientOcclusion { radius: None, rays: 16, pass: 0, screen_space: false }
    }
}

/// Feature lines: silhouettes, creases and boundaries drawn over the image as
/// antialiased lines of one width and colour ([`crate::resolve::edges::lines`]),
/// and, if asked, the hidden ones dashed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FeatureLines {
    /// Line width in pixels.
    pub width: f32,
    /// Linear RGB colour of the lines.
    pub colour: Vec3,
    /// Draw the lines hidden behind surfaces too, dashed and fainter.
    pub hidden: bool,
    /// Two faces meeting at more than this angle (degrees between their
    /// normals) meet at a crease, which is drawn.
    pub crease_deg: f32,
}

impl FeatureLines {
    /// The thinnest and widest lines, in pixels.
    pub const WIDTHS: std::ops::RangeInclusive<f32> = 0.5..=16.0;
}

impl Default for FeatureLines {
    /// Near-black lines 1.5 pixels wide at creases of over 30°, hidden lines
    /// not drawn.
    fn default() -> Self {
        FeatureLines { width: 1.5, colour: Vec3::splat(0.01), hidden: false, crease_deg: 30.0 }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn offsets_stay_inside_the_pixel_and_average_near_its_centre() {
        assert_eq!(Antialias::None.offsets(), vec![Vec2::ZERO]);
        for n in [2, 4, 16, 64] {
            let o = Antialias::Jitter(n).offsets();
            assert_eq!(o.len(), n as usize);
            assert!(o.iter().all(|p| p.abs().max_element() < 0.5));
            let mean = o.iter().sum::<Vec2>() / n as f32;
            assert!(mean.abs().max_element() < 1.0 / n as f32 + 0.02, "n {n}: mean {mean}");
        }
    }

    #[test]
    fn offsets_fill_each_quarter_of_the_pixel_evenly() {
        for n in [16, 64, 256] {
            let o = Antialias::Jitter(n).offsets();
            for q in 0..4 {
                let inside = o.iter().filter(|p| (p.x >= 0.0) == (q & 1 == 1) && (p.y >= 0.0) == (q & 2 == 2)).count();
                assert!(inside.abs_diff(n as usize / 4) <= (n as usize / 64).max(1), "n {n}, quarter {q}: {inside}");
            }
        }
    }

    #[test]
    fn amounts_follow_their_formulas() {
        let fog = |mode| Fog { mode, color: Vec3::ONE };
        let lin = fog(FogMode::Linear { start: 2.0, end: 6.0 });
        assert_eq!((lin.amount(1.0), lin.amount(4.0), lin.amount(9.0)), (0.0, 0.5, 1.0));
        let exp = fog(FogMode::Exp { density: 0.5 });
        assert!((exp.amount(2.0) - (1.0 - (-1.0f32).exp())).abs() < 1e-6);
        let exp2 = fog(FogMode::Exp2 { density: 0.5 });
        assert!((exp2.amount(4.0) - (1.0 - (-4.0f32).exp())).abs() < 1e-6);
    }
}
