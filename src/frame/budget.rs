//! What a frame of a scene asks for, checked against the scene's
//! [`Limits`] before any of it is allocated: its triangles, each light's
//! shadow maps, every light's together, and the memory of the whole.
//!
//! The memory is an estimate from sizes known before the render: per triangle
//! drawn, its mesh, its ray-tracing copy and their bounding-volume
//! hierarchies ([`BYTES_PER_TRIANGLE`]); per texture, its texels and mip
//! chain (16 bytes a texel); the shadow maps at their configured resolution,
//! counted from what each light's method builds
//! ([`ShadowTerm::bytes_needed`]); per pixel drawn (a tile's pixels and guard
//! band alone), the item buffer, the component images and the edge pass's
//! records ([`BYTES_PER_PIXEL`]).

use std::collections::HashSet;
use std::sync::Arc;

use crate::error::Result;
use crate::image::PixelRect;
use crate::limits::Limit;
use crate::scene::{Body, Light, Scene};
use crate::shading::frame_lights_within;
use crate::shadows::ShadowTerm;

/// Bytes a triangle takes while a frame is drawn, on the generous side: its
/// vertices and index (about 100 with normals and texture coordinates), its
/// ray-tracing copy (48) and two hierarchies' share of nodes (about 64).
pub const BYTES_PER_TRIANGLE: u64 = 256;

/// Bytes a pixel takes while a frame is drawn: depth, item and normal (24),
/// the linear image and a few component targets (about 100), the edge pass's
/// and the traced term's records (about 36).
pub const BYTES_PER_PIXEL: u64 = 160;

/// Checks what a frame of `scene` drawing the pixels `drawn` asks for
/// against `scene.limits`.
///
/// # Errors
///
/// [`crate::Error::Limit`] naming the first limit passed: [`Limit::Triangles`],
/// [`Limit::LightShadowMb`] (naming the light), [`Limit::FrameShadowMb`] or
/// [`Limit::MemoryMb`].
pub fn check(scene: &Scene, drawn: PixelRect) -> Result<()> {
    let limits = &scene.limits;
    let triangles: u64 = scene.objects.iter().filter_map(|o| o.triangles()).map(|m| m.triangles.len() as u64).sum();
    limits.check(Limit::Triangles, triangles, || "the scene's objects".into())?;
    let shadows = shadow_bytes(scene, true)?;
    let need = MemoryNeeded::of(scene, shadows, drawn);
    limits.check_bytes(Limit::MemoryMb, need.total(), || {
        let mb = |b: u64| b.div_ceil(1 << 20);
        format!(
            "the frame (meshes {} MiB, textures {} MiB, shadow maps {} MiB, image buffers {} MiB)",
            mb(need.meshes),
            mb(need.textures),
            mb(need.shadow_maps),
            mb(need.pixels)
        )
    })?;
    Ok(())
}

/// The memory a frame of a scene is estimated to take, in bytes, by what
/// takes it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct MemoryNeeded {
    /// The distinct meshes' triangles ([`BYTES_PER_TRIANGLE`] each).
    pub meshes: u64,
    /// The distinct textures' texels and mip chains.
    pub textures: u64,
    /// Every light's shadow maps at their configured resolution.
    pub shadow_maps: u64,
    /// The frame's per-pixel buffers ([`BYTES_PER_PIXEL`] each).
    pub pixels: u64,
}

impl MemoryNeeded {
    /// The estimate for a whole frame of `scene`, what [`Limit::MemoryMb`]
    /// is checked against.
    #[must_use]
    pub fn estimate(scene: &Scene) -> MemoryNeeded {
        let shadows = shadow_bytes(scene, false).unwrap_or_default();
        MemoryNeeded::of(scene, shadows, PixelRect::full(scene.width, scene.height))
    }

    fn of(scene: &Scene, shadow_maps: u64, drawn: PixelRect) -> MemoryNeeded {
        MemoryNeeded {
            meshes: unique_mesh_triangles(scene) * BYTES_PER_TRIANGLE,
            textures: texture_bytes(scene),
            shadow_maps,
            pixels: u64::from(drawn.width()) * u64::from(drawn.height()) * BYTES_PER_PIXEL,
        }
    }

    /// The sum.
    #[must_use]
    pub fn total(&self) -> u64 {
        self.meshes + self.textures + self.shadow_maps + self.pixels
    }
}

/// Bytes of every light's shadow maps; with `checked`, each light's and
/// their sum checked on the way.
fn shadow_bytes(scene: &Scene, checked: bool) -> Result<u64> {
    let limits = &scene.limits;
    let Some(bounds) = scene.caster_bounds() else { return Ok(0) };
    let mut total = 0;
    for (i, light) in frame_lights_within(scene, bounds).iter().enumerate() {
        let bytes: u64 = light.samples.iter().map(|s| ShadowTerm::bytes_needed(s, bounds) as u64).sum();
        if checked {
            limits.check_bytes(Limit::LightShadowMb, bytes, || light_named(i, &light.light, light.samples.len()))?;
        }
        total += bytes;
    }
    if checked {
        limits.check_bytes(Limit::FrameShadowMb, total, || "the lights' shadow maps together".into())?;
    }
    Ok(total)
}

fn light_named(index: usize, light: &Light, maps: usize) -> String {
    let s = &light.shadow;
    let sets = if maps == 1 { "one set of maps".to_string() } else { format!("{maps} jittered sets of maps") };
    format!("light {} (shadow resolution {}, {sets})", index + 1, s.resolution)
}

/// Triangles of the distinct meshes (an instanced mesh is held once).
fn unique_mesh_triangles(scene: &Scene) -> u64 {
    let mut seen = HashSet::new();
    scene
        .objects
        .iter()
        .filter_map(|o| match &o.body {
            Body::Mesh(m) => seen.insert(Arc::as_ptr(m)).then(|| m.triangles.len() as u64),
            Body::Solid { .. } => None,
        })
        .sum()
}

/// Bytes of the distinct textures of the scene's materials and environment.
fn texture_bytes(scene: &Scene) -> u64 {
    let mut seen = HashSet::new();
    let maps = scene.materials.iter().flat_map(|m| {
        let c = &m.maps;
        c.ambient
            .iter()
            .chain(&c.diffuse)
            .chain(&c.specular)
            .chain(&c.emission)
            .chain(c.normal.as_ref().map(|n| &n.texture))
    });
    let env = scene.environment.as_ref().map(|e| &e.map);
    maps.chain(env)
        .filter(|t| seen.insert(Arc::as_ptr(t)))
        .map(|t| {
            let (w, h) = t.size();
            u64::from(w) * u64::from(h) * 16
        })
        .sum()
}
