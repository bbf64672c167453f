//! One frame, start to finish: visibility pass → shading passes → resolve.

use std::time::Instant;

use crate::error::Result;
use crate::resolve::LinearImage;
use crate::scene::Scene;
use crate::shading;
use crate::visibility::{self, RasterStats, VisibilityBuffer};

/// How to render.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct RenderOptions {
    /// Worker threads (`None`: one per core).
    pub threads: Option<usize>,
}

/// Timings and counts of one frame.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct FrameStats {
    /// Milliseconds in the visibility (polygon) pass.
    pub visibility_ms: f64,
    /// Milliseconds in the shading passes.
    pub shading_ms: f64,
    /// What the rasterizer did.
    pub raster: RasterStats,
    /// Bytes held by the frame's buffers (visibility buffer and image).
    pub buffer_bytes: usize,
}

/// A rendered frame and the buffer it was shaded from.
#[derive(Debug, Clone)]
pub struct Frame {
    /// Linear RGB result.
    pub image: LinearImage,
    /// Depth and item id per pixel.
    pub visibility: VisibilityBuffer,
    /// Timings and counts.
    pub stats: FrameStats,
}

/// Renders `scene` (validated first).
pub fn render(scene: &Scene, options: &RenderOptions) -> Result<Frame> {
    scene.validate()?;
    match options.threads {
        None => Ok(render_here(scene)),
        Some(n) => {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(n.max(1))
                .build()
                .map_err(|e| crate::Error::Scene(e.to_string()))?;
            Ok(pool.install(|| render_here(scene)))
        }
    }
}

fn render_here(scene: &Scene) -> Frame {
    let t0 = Instant::now();
    let mut visibility = VisibilityBuffer::new(scene.width, scene.height);
    let raster = visibility::rasterize(scene, &mut visibility);
    let t1 = Instant::now();
    let image = shading::shade_frame(scene, &visibility);
    let t2 = Instant::now();
    let buffer_bytes = visibility.memory_bytes() + std::mem::size_of_val(image.pixels());
    let stats = FrameStats {
        visibility_ms: (t1 - t0).as_secs_f64() * 1e3,
        shading_ms: (t2 - t1).as_secs_f64() * 1e3,
        raster,
        buffer_bytes,
    };
    Frame {
        image,
        visibility,
        stats,
    }
}
