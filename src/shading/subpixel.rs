//! Sub-pixel samples: points inside a pixel, off its centre, that the lit passes
//! shade besides the pixel centres.
//!
//! Seed 002's passes shade one point per pixel, its centre. The edge pass
//! ([`crate::resolve::edges`]) knows more: which part of a pixel an edge cuts off
//! and which surface that part shows. To colour the part it asks for the surface
//! at the part's centroid, shaded by the same passes (same lights, same shadow
//! maps, same selective lighting) while those passes run — a shadow that ends
//! right behind a silhouette is then seen in the pixel the silhouette crosses,
//! not taken from the lit pixel beyond it.
//!
//! A sample names the pixel whose visible surface it shades (its item, as the
//! visibility buffer holds it; a triangle's plane or a solid's tangent plane is
//! met by the ray through the sample's point, extrapolated past the triangle if
//! need be) and the point the ray goes through. The passes add each sample's
//! components eight at a time ([`Lighting::shade_points`], the arithmetic they
//! shade pixels with); the reflection map's term is looked up once; the traced
//! term ([`crate::raytrace::traced`]) traces its bounces from there.

use glam::{Vec2, Vec3};
use rayon::prelude::*;

use super::lanes::{Lighting, LANES};
use super::phong::{self, Coefficients, Component, ComponentSet, Components};
use super::reflection_map::reflection_map;
use super::surface::{ObjectFrames, SurfacePoint};
use super::TriangleCache;
use crate::camera::{PixelRays, Ray};
use crate::scene::Scene;
use crate::visibility::VisibilityBuffer;

/// A point to shade on the surface a pixel shows.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SubpixelSample {
    /// The pixel (x, y) whose visible surface is shaded.
    pub pixel: (u32, u32),
    /// The image point (pixels, y down; a pixel's centre is at + ½) the ray goes
    /// through.
    pub at: Vec2,
}

/// A sample's surface, reconstructed once for all passes.
#[derive(Debug, Clone, Copy)]
pub struct SampleSurface {
    /// The ray through the sample's point.
    pub ray: Ray,
    /// The surface point it meets.
    pub point: SurfacePoint,
    /// The material's coefficients there.
    pub coefficients: Coefficients,
    /// The object it belongs to.
    pub object: u32,
}

/// Samples and what the lit passes have added at each so far.
#[derive(Debug, Clone, Default)]
pub struct SubpixelShading {
    /// The points.
    pub samples: Vec<SubpixelSample>,
    /// Per sample, its surface (`None` where the pixel shows nothing).
    pub surfaces: Vec<Option<SampleSurface>>,
    /// Per sample, the sum of the passes' components (zero where the pixel shows
    /// nothing).
    pub lit: Vec<Components>,
    /// Per sample, the reflection map's term (seed 002's Ie, zero without an
    /// environment or a Km).
    pub reflected: Vec<Vec3>,
    /// Per sample, the traced term: reflection and refraction (zero where the
    /// material neither reflects nor refracts).
    pub traced: Vec<Vec3>,
}

/// What finding a sample's surface reads: the frame it lies in.
struct SampleFrame<'a> {
    scene: &'a Scene,
    vb: &'a VisibilityBuffer,
    frames: ObjectFrames,
    rays: PixelRays,
}

impl SubpixelSample {
    /// The surface the sample's ray meets on what its pixel shows in the
    /// frame; `triangles` holds the triangles earlier samples met.
    fn surface(&self, frame: &SampleFrame, triangles: &mut TriangleCache) -> Option<SampleSurface> {
        let SampleFrame { scene, vb, frames, rays } = frame;
        let (x, y) = self.pixel;
        let item = vb.item(x, y);
        if item.is_none() {
            return None;
        }
        let ray = rays.ray(self.at);
        let surface = if item.primitive().is_some() {
            // A solid's tangent plane is taken where the pixel's own ray meets it.
            frames.prepare_at(scene, vb, x, y, &rays.ray(Vec2::new(x as f32 + 0.5, y as f32 + 0.5)))
        } else {
            *triangles.get(scene, frames, item)
        };
        let mut point = surface.surface(&ray);
        let material = &scene.materials[point.material];
        let constant = Coefficients::constant(material).filter(|_| !surface.coloured());
        let coefficients = constant.unwrap_or_else(|| {
            // Texture footprint: the same surface met one pixel right and one
            // below (ray differentials, as the passes take them).
            let uv = |dx: f32, dy: f32| surface.uv(&rays.ray(self.at + Vec2::new(dx, dy)));
            point.duv = [uv(1.0, 0.0) - point.uv, uv(0.0, 1.0) - point.uv];
            phong::sample_maps(material, &mut point)
        });
        Some(SampleSurface { ray, point, coefficients, object: item.object })
    }
}

impl SubpixelShading {
    /// The `samples` on the frame whose visibility buffer is `vb`, their
    /// surfaces found, nothing added yet.
    #[must_use]
    pub fn new(scene: &Scene, vb: &VisibilityBuffer, samples: Vec<SubpixelSample>) -> Self {
        let mut shading = SubpixelShading::default();
        shading.reset(scene, vb, samples);
        shading
    }

    /// [`SubpixelShading::new`] into this one's buffers (an interactive
    /// preview shades a similar number of samples frame after frame).
    pub fn reset(&mut self, scene: &Scene, vb: &VisibilityBuffer, samples: Vec<SubpixelSample>) {
        self.samples = samples;
        let n = self.samples.len();
        for v in [&mut self.reflected, &mut self.traced] {
            v.clear();
            v.resize(n, Vec3::ZERO);
        }
        self.lit.clear();
        self.lit.resize(n, Components::default());
        self.surfaces.clear();
        if n == 0 {
            return; // most frames: nothing to set up
        }
        let rays = scene.camera.pixel_rays(Vec2::new(vb.width() as f32, vb.height() as f32));
        let frame = SampleFrame { scene, vb, frames: ObjectFrames::new(scene), rays };
        // One cache of triangles per worker: samples along an edge keep
        // meeting the same few.
        let surface = |triangles: &mut TriangleCache, s: &SubpixelSample| s.surface(&frame, triangles);
        self.samples.par_iter().map_init(|| TriangleCache::new(64), surface).collect_into_vec(&mut self.surfaces);
        let reflected = self.reflected.par_iter_mut().zip(&self.surfaces);
        reflected.for_each(|(r, s)| *r = s.as_ref().map_or(Vec3::ZERO, |s| reflection_map(scene, &s.point)));
    }

    /// Sample `k`'s colour in an image holding the components `parts`, as the
    /// frame's pixels have it before fog and translucency: the lit passes, the
    /// reflection map and the traced term. `None` where its pixel shows
    /// nothing.
    #[must_use]
    pub fn colour(&self, k: usize, parts: ComponentSet) -> Option<Vec3> {
        self.surfaces[k].as_ref()?;
        let keep = |c, v: Vec3| if parts.contains(c) { v } else { Vec3::ZERO };
        let extra = keep(Component::Reflection, self.reflected[k]) + keep(Component::Traced, self.traced[k]);
        Some(self.lit[k].total_of(parts) + extra)
    }

    /// Adds one pass (`lighting`, reaching the objects `receivers` marks, or
    /// all) at every sample.
    pub fn add_pass(&mut self, lighting: &Lighting, receivers: Option<&[bool]>) {
        let lanes = self.lit.par_chunks_mut(LANES).zip(self.surfaces.par_chunks(LANES));
        lanes.for_each(|(acc, surfaces)| {
            let lit = |i: usize| {
                let s = surfaces.get(i)?.as_ref()?;
                receivers.is_none_or(|r| r[s.object as usize]).then_some((&s.coefficients, &s.point, s.object))
            };
            let points = std::array::from_fn(lit);
            for ((sum, added), point) in acc.iter_mut().zip(lighting.shade_points(&points)).zip(points) {
                if point.is_some() {
                    *sum += added;
                }
            }
        });
    }
}
