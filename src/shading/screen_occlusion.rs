//! Ambient occlusion's quick form, for the frames of a moving camera: the
//! hemisphere's samples tested against the frame's own depth buffer instead
//! of traced through the scene (screen-space ambient occlusion: Mittring,
//! "Finding next gen: CryEngine 2", SIGGRAPH 2007 course notes; the
//! normal-oriented hemisphere of Filion & McNaughton, "StarCraft II: effects
//! and techniques", the same course 2008).
//!
//! It estimates the same quantity as the traced form
//! ([`crate::raytrace::occlusion`]): the cosine-weighted share of the
//! hemisphere about each pixel's surface normal that is open within the
//! radius. A sample point at a distance along a hemisphere direction counts
//! as closed when the surface the depth buffer holds at its pixel lies in
//! front of it by less than the radius. It sees only what the frame sees:
//! surfaces hidden from the eye or off-screen close nothing, and a thin part
//! in front closes what lies behind it.
//!
//! To cost a fraction of a quick frame:
//! - it runs on cells of [`CELL`] × [`CELL`] pixels: one surface point each,
//!   [`SAMPLES`] directions of [`STEPS`] points, each cell of a 4 × 4 block
//!   taking other directions of one sequence; each cell is then averaged
//!   with its 3 × 3 neighbours of like depth (72 directions reach every
//!   cell's value), and each pixel takes the four nearest cells' of like
//!   depth, bilinearly, eight pixels at a time;
//! - a cell's sixteen points are projected eight at a time and read a
//!   quarter of the depth buffer (every second pixel of every second row),
//!   which stays in a core's cache: the points fall all over the radius,
//!   and reading the whole buffer they waited on memory for most of their
//!   time;
//! - it runs before the shading, which scales the ambient term by each
//!   pixel's share as it shades it ([`crate::shading::OpenShares`]): no
//!   pass of its own over the image, no ambient image to shade.
//!
//! Measured (`kage-bench ao`, 960×540, 2-core EPYC VM): 1.0–1.1 ms, 5–13% of
//! a quick frame (the whole frame with it 1.10–1.22× the one without), at
//! 0.033–0.045 RMSE from the reference's traced share (the traced form's 64
//! passes: 0.005–0.009). Before these three choices the same estimate cost
//! 6.9–9.5 ms.

use glam::{DVec2, Vec2, Vec3};
use rayon::prelude::*;
use wide::f32x8;

use super::subpixel::SubpixelShading;
use crate::camera::PixelRays;
use crate::image::LinearImage;
use crate::sampling::concentric_disc;
use crate::scene::Scene;
use crate::visibility::VisibilityBuffer;

/// Hemisphere directions a cell tests.
pub const SAMPLES: u32 = 8;

/// Points tested along each direction, spread over the radius.
pub const STEPS: u32 = 3;

/// A cell's side in pixels.
pub const CELL: usize = 8;

/// Cells of a block that take different directions, along each axis.
const BLOCK: usize = 4;

/// The R2 sequence's steps (as the traced form's).
const R2: DVec2 = DVec2::new(0.754_877_666_246_692_7, 0.569_840_290_998_053_3);

/// Neighbouring cells are averaged when their view distances differ by less
/// than this share.
const LIKE_DEPTH: f32 = 0.05;

/// Direction `j`'s points within a unit radius, in the frame of the normal
/// (z along it): a cosine-weighted direction of the R2 sequence, marched in
/// [`STEPS`] even steps from a start of its own (a ray is closed by
/// whatever it meets along its length, not at one distance).
fn offsets(j: u32) -> [Vec3; STEPS as usize] {
    let p = (R2 * f64::from(j)).fract();
    let d = concentric_disc(Vec2::new(p.x as f32, p.y as f32));
    let dir = Vec3::new(d.x, d.y, (1.0 - d.length_squared()).max(0.0).sqrt());
    let start = (f64::from(j) * 0.618_033_988_749_894_8).fract() as f32;
    std::array::from_fn(|k| dir * ((k as f32 + start) / STEPS as f32).max(0.05))
}

/// One cell's estimate, or its blurred estimate.
#[derive(Debug, Clone, Copy)]
struct Cell {
    /// Open share (1 where the cell shows nothing).
    open: f32,
    /// The [`Probe::key`] of its surface point's depth (NaN where it shows
    /// nothing, which is like no depth).
    key: f32,
}

/// Whether two depths of keys `a` and `b` ([`Probe::key`]) lie within
/// [`LIKE_DEPTH`] of `b`'s view distance of each other (perspective: stored
/// depth is the reciprocal of the distance, so its relative difference is
/// the distances' to first order). Never with a NaN.
#[inline(always)]
fn alike(a: f32, b: f32) -> bool {
    (a - b).abs() < LIKE_DEPTH * b
}

/// Writes each pixel's open share of the frame whose visibility buffer is
/// `vb` into `open` (resized to the pixels the buffer holds; every lane the
/// share, 1 where no surface is seen), found from the depth buffer alone:
/// what the shading scales the ambient term by
/// ([`crate::shading::OpenShares`]). Nothing happens without the scene's
/// ambient occlusion.
pub fn open_shares(scene: &Scene, vb: &VisibilityBuffer, open: &mut LinearImage) {
    let Some(radius) = scene.occlusion_radius() else { return };
    let held = vb.rect();
    let (w, h) = (held.width() as usize, held.height() as usize);
    let (cw, ch) = (w.div_ceil(CELL), h.div_ceil(CELL));
    let probe = Probe::new(scene, vb, radius);
    let cells: Vec<Cell> = (0..cw * ch).into_par_iter().with_min_len(64).map(|c| probe.cell(c % cw, c / cw)).collect();
    let blurred: Vec<Cell> = (0..cw * ch)
        .into_par_iter()
        .with_min_len(256)
        .map(|c| Cell { open: blur(&cells, cw, ch, c), key: cells[c].key })
        .collect();
    open.resize(held.width(), held.height());
    let key = probe.keys();
    let rows = open.pixels_mut().par_chunks_mut(w).zip(vb.depths().par_chunks(w));
    rows.enumerate().for_each(|(y, (out, depths))| Rows::new(&blurred, (cw, ch), y).shares(depths, key, out));
}

/// Scales the ambient term of the edge pass's samples by the open share of
/// their pixels in `open` (as [`open_shares`] wrote it for `vb`).
pub fn darken_samples(vb: &VisibilityBuffer, open: &LinearImage, subpixel: &mut SubpixelShading) {
    let share = |(x, y): (u32, u32)| open.pixels()[vb.index(x, y)].x;
    let samples = subpixel.lit.par_iter_mut().zip(&subpixel.samples);
    samples.for_each(|(lit, sample)| lit.ambient *= share(sample.pixel));
}

/// The two rows of cells a row of pixels takes its shares from, with how
/// far the pixels lie between them.
struct Rows<'a> {
    above: &'a [Cell],
    below: &'a [Cell],
    /// Weight of the row below.
    ty: f32,
    /// The row of cells the pixels lie in.
    own: &'a [Cell],
}

impl<'a> Rows<'a> {
    /// The rows of cells about pixel row `y` (from the held rectangle's top).
    fn new(cells: &'a [Cell], (cw, ch): (usize, usize), y: usize) -> Self {
        let fy = (y as f32 + 0.5) / CELL as f32 - 0.5;
        let y0 = fy.floor().max(0.0) as usize;
        let ty = (fy - y0 as f32).clamp(0.0, 1.0);
        let row = |r: usize| &cells[r.min(ch - 1) * cw..][..cw];
        Rows { above: row(y0), below: row(y0 + 1), ty, own: row(y / CELL) }
    }

    /// Writes the open share of each pixel of the row into `out`, from its
    /// stored depth in `depths` (whose [`Probe::key`] is `key.0 + key.1 ·
    /// depth`; 0: nothing seen, open): [`Rows::share`], eight pixels at a
    /// time between the centres of two cells.
    fn shares(&self, depths: &[f32], key: (f32, f32), out: &mut [Vec3]) {
        const { assert!(CELL == 8, "a cell is a vector of pixels wide") };
        let scalar = |x: usize, depth: f32| if depth == 0.0 { 1.0 } else { self.share(x, key.0 + key.1 * depth) };
        // Pixels left of the first cell's centre, then runs from one centre
        // to the next.
        let first = (CELL / 2).min(out.len());
        for x in 0..first {
            out[x] = Vec3::splat(scalar(x, depths[x]));
        }
        let splat = f32x8::splat;
        let tx = f32x8::new(std::array::from_fn(|k| (k as f32 + 0.5) / CELL as f32));
        let (ty, last) = (splat(self.ty), self.above.len() - 1);
        let weights = [(splat(1.0) - tx) * (splat(1.0) - ty), tx * (splat(1.0) - ty), (splat(1.0) - tx) * ty, tx * ty];
        let mut x = first;
        while x + CELL <= out.len() {
            let left = (x - CELL / 2) / CELL;
            let right = (left + 1).min(last);
            let depth = f32x8::new(depths[x..x + CELL].try_into().expect("a run of eight"));
            let pixel = splat(key.0) + splat(key.1) * depth;
            let (mut sum, mut weight) = (splat(0.0), splat(0.0));
            for (c, w) in [self.above[left], self.above[right], self.below[left], self.below[right]].iter().zip(weights)
            {
                let like = (splat(c.key) - pixel).abs().simd_lt(splat(LIKE_DEPTH) * pixel);
                let w = like.select(w, splat(0.0));
                sum += w * splat(c.open);
                weight += w;
            }
            let own = f32x8::new(std::array::from_fn(|k| self.own[(x + k) / CELL].open));
            let share = weight.simd_gt(splat(1e-4)).select(sum / weight, own);
            let share = depth.simd_eq(splat(0.0)).select(splat(1.0), share);
            for (o, s) in out[x..x + CELL].iter_mut().zip(share.to_array()) {
                *o = Vec3::splat(s);
            }
            x += CELL;
        }
        for x in x..out.len() {
            out[x] = Vec3::splat(scalar(x, depths[x]));
        }
    }

    /// The open share at pixel `x` of the row whose depth has key `key`:
    /// the four nearest cells' blurred shares, weighted by nearness
    /// (bilinear) and by how alike their depth is (joint bilateral
    /// upsampling: Kopf et al., SIGGRAPH 2007), so a cell on one side of a
    /// silhouette does not bleed onto the other; the share of the cell the
    /// pixel lies in when no near cell lies at a like depth.
    #[inline(always)]
    fn share(&self, x: usize, key: f32) -> f32 {
        // The cells whose centres lie left and right of the pixel's.
        let left = x.saturating_sub(CELL / 2) / CELL;
        let right = (left + 1).min(self.above.len() - 1);
        let tx = ((x as f32 + 0.5) / CELL as f32 - 0.5 - left as f32).clamp(0.0, 1.0);
        let ty = self.ty;
        let (mut sum, mut weight) = (0.0, 0.0);
        for (c, w) in [
            (self.above[left], (1.0 - tx) * (1.0 - ty)),
            (self.above[right], tx * (1.0 - ty)),
            (self.below[left], (1.0 - tx) * ty),
            (self.below[right], tx * ty),
        ] {
            let w = if alike(c.key, key) { w } else { 0.0 };
            sum += w * c.open;
            weight += w;
        }
        if weight > 1e-4 {
            sum / weight
        } else {
            self.own[x / CELL].open
        }
    }
}

/// Cell `c`'s open share averaged with its 4 × 4 neighbours of like depth.
fn blur(cells: &[Cell], cw: usize, ch: usize, c: usize) -> f32 {
    let (cx, cy) = (c % cw, c / cw);
    let own = cells[c].key;
    if own.is_nan() {
        return 1.0;
    }
    let (mut sum, mut count) = (0.0, 0.0);
    for ny in cy.saturating_sub(1)..(cy + 2).min(ch) {
        for nx in cx.saturating_sub(1)..(cx + 2).min(cw) {
            let n = cells[ny * cw + nx];
            if alike(n.key, own) {
                sum += n.open;
                count += 1.0;
            }
        }
    }
    if count > 0.0 {
        sum / count
    } else {
        cells[c].open
    }
}

/// Vectors of eight a cell's points fill.
const VECTORS: usize = (SAMPLES * STEPS).div_ceil(8) as usize;

const _: () = assert!(SAMPLES * STEPS <= 32, "a cell's closed points fit a mask");

/// One cell's sample points within the radius, in the frame of its normal
/// (z along it), eight to a vector: point `k` is direction `k / STEPS`'s
/// step `k % STEPS`; the lanes past the last point are NaN (never closed).
struct Kernel {
    x: [f32x8; VECTORS],
    y: [f32x8; VECTORS],
    z: [f32x8; VECTORS],
}

impl Kernel {
    /// The points of block slot `slot` (directions `slot · SAMPLES ..`).
    fn new(slot: u32, radius: f32) -> Self {
        let points: Vec<Vec3> = (slot * SAMPLES..(slot + 1) * SAMPLES).flat_map(offsets).map(|o| o * radius).collect();
        let lane = |k: usize, axis: usize| points.get(k).map_or(f32::NAN, |p| p[axis]);
        let vectors = |axis| std::array::from_fn(|b| f32x8::new(std::array::from_fn(|i| lane(b * 8 + i, axis))));
        Kernel { x: vectors(0), y: vectors(1), z: vectors(2) }
    }
}

/// What a cell's samples read: the frame, its camera and the radius.
struct Probe<'a> {
    scene: &'a Scene,
    vb: &'a VisibilityBuffer,
    rays: PixelRays,
    radius: f32,
    /// A pixel's size at unit view distance (orthographic: its size).
    pixel: f32,
    /// Every cell's sample points, in the frame of its normal (z along
    /// it), scaled to the radius: [`SAMPLES`] directions of [`STEPS`]
    /// points for each cell of a block.
    kernel: Vec<Kernel>,
    /// World points to pixels.
    to_pixel: ToPixel,
    /// Every second pixel's stored depth of every second row (from the held
    /// rectangle's corner): what the samples read, a quarter of the depth
    /// buffer, so that it stays in a core's cache (the samples fall all over
    /// the radius; reading the whole buffer, they waited on memory for most
    /// of their time).
    coarse: Vec<f32>,
    /// The coarse grid's row length.
    coarse_width: usize,
}

/// The camera's projection from world points to image points, as affine
/// maps of the point's offset from the eye divided by its view distance
/// (orthographic: not divided): `x = v·to_x / d + centre.x`,
/// `y = centre.y − v·to_y / d`.
struct ToPixel {
    origin: Vec3,
    /// The camera's unit view direction.
    forward: Vec3,
    to_x: Vec3,
    to_y: Vec3,
    centre: Vec2,
    ortho: bool,
}

impl ToPixel {
    fn new(r: &PixelRays, forward: Vec3) -> Self {
        // Perspective: the ray through a point is `forward + right·x + up·y`
        // scaled by its distance (`forward` holds a shifted camera's offset
        // too).
        let offset = if r.ortho { Vec3::ZERO } else { r.forward - forward };
        let (right, up) = (r.right / r.right.length_squared(), r.up / r.up.length_squared());
        ToPixel {
            origin: r.origin,
            forward,
            to_x: right * (0.5 * r.size.x),
            to_y: up * (0.5 * r.size.y),
            centre: Vec2::new((1.0 - offset.dot(right)) * 0.5 * r.size.x, (1.0 + offset.dot(up)) * 0.5 * r.size.y),
            ortho: r.ortho,
        }
    }
}

impl<'a> Probe<'a> {
    fn new(scene: &'a Scene, vb: &'a VisibilityBuffer, radius: f32) -> Self {
        let rays = scene.camera.pixel_rays(Vec2::new(vb.width() as f32, vb.height() as f32));
        let forward = (scene.camera.target - scene.camera.eye).normalize_or_zero();
        let kernel = (0..(BLOCK * BLOCK) as u32).map(|slot| Kernel::new(slot, radius)).collect();
        let pixel = 2.0 * rays.up.length() / rays.size.y;
        let to_pixel = ToPixel::new(&rays, forward);
        let held = vb.rect();
        let (w, h) = (held.width() as usize, held.height() as usize);
        let coarse_width = w.div_ceil(2);
        let mut coarse = vec![0.0; coarse_width * h.div_ceil(2)];
        coarse.par_chunks_mut(coarse_width).zip(vb.depths().par_chunks(2 * w)).for_each(|(out, rows)| {
            out.iter_mut().zip(rows[..w].iter().step_by(2)).for_each(|(o, d)| *o = *d);
        });
        Probe { scene, vb, rays, radius, pixel, kernel, to_pixel, coarse, coarse_width }
    }

    /// The estimate of cell (`cx`, `cy`): the first of its pixels that shows
    /// a surface, sampled.
    fn cell(&self, cx: usize, cy: usize) -> Cell {
        let held = self.vb.rect();
        // Its middle first, then the rest.
        let m = CELL / 2;
        let middle = [(m - 1, m - 1), (m, m), (m - 1, m), (m, m - 1)].into_iter();
        let pixel = middle
            .chain((0..CELL * CELL).map(|k| (k % CELL, k / CELL)))
            .map(|(dx, dy)| (held.x0 + (CELL * cx + dx) as u32, held.y0 + (CELL * cy + dy) as u32))
            .find(|&(x, y)| held.contains(x, y) && !self.vb.item(x, y).is_none());
        let Some((x, y)) = pixel else { return Cell { open: 1.0, key: f32::NAN } };
        let Some((position, normal)) = self.point_at(x, y) else { return Cell { open: 1.0, key: f32::NAN } };
        let kernel = &self.kernel[(cy % BLOCK) * BLOCK + cx % BLOCK];
        let (u, v) = normal.any_orthonormal_pair();
        let closed = self.closed_points(kernel, [position, u, v, normal]);
        // A direction is closed by whatever it meets along its length.
        let closed = (0..SAMPLES).filter(|d| closed >> (d * STEPS) & ((1 << STEPS) - 1) != 0).count() as u32;
        Cell { open: (SAMPLES - closed) as f32 / SAMPLES as f32, key: self.key(self.vb.depth(x, y)) }
    }

    /// Pixel `(x, y)`'s surface point and its unit normal turned to the eye:
    /// the point from the pixel's ray and depth, the normal the face's own
    /// (a triangle's plane, a solid's stored normal), not the shading's.
    fn point_at(&self, x: u32, y: u32) -> Option<(Vec3, Vec3)> {
        let ray = self.rays.ray(Vec2::new(x as f32 + 0.5, y as f32 + 0.5));
        let position = ray.origin + ray.dir * self.scene.camera.distance_at_depth(&ray, self.vb.depth(x, y));
        let item = self.vb.item(x, y);
        let normal = match item.primitive() {
            Some(_) => self.vb.normal(x, y),
            None => {
                let object = self.scene.objects.get(item.object as usize)?;
                let mesh = object.triangles()?;
                let [a, b, c] = mesh
                    .triangles
                    .get(item.triangle as usize)?
                    .map(|v| object.transform.transform_point3(mesh.positions[v as usize]));
                (b - a).cross(c - a)
            }
        }
        .try_normalize()?;
        Some((position, if normal.dot(ray.dir) > 0.0 { -normal } else { normal }))
    }

    /// Which of `kernel`'s points, placed at a surface point in its frame
    /// `[position, u, v, normal]`, are closed (bit `k` for point `k`): a
    /// surface the frame holds lies in front of the point within the radius
    /// (farther in front: an object before a gap, not a wall of it), by more
    /// than a bias: the depth a surface sloped 2:1 changes over a pixel (the
    /// pixel's centre is not where the sample falls). Eight points at a
    /// time, compared in stored depth (reversed: larger is nearer, 0 where
    /// nothing is seen) without a division, every point tested (whether a
    /// point is closed is a coin toss a branch predictor loses).
    fn closed_points(&self, kernel: &Kernel, [p, u, v, n]: [Vec3; 4]) -> u32 {
        let held = self.vb.rect();
        let camera = &self.scene.camera;
        let t = &self.to_pixel;
        let splat = |x: f32| f32x8::splat(x);
        let mut closed = 0;
        for (b, (kx, (ky, kz))) in kernel.x.iter().zip(kernel.y.iter().zip(&kernel.z)).enumerate() {
            let along =
                |k: usize| splat(p[k] - t.origin[k]) + splat(u[k]) * *kx + splat(v[k]) * *ky + splat(n[k]) * *kz;
            let (x, y, z) = (along(0), along(1), along(2));
            let dot = |a: Vec3| x * splat(a.x) + y * splat(a.y) + z * splat(a.z);
            let distance = dot(t.forward);
            let scale = if t.ortho { splat(1.0) } else { splat(1.0) / distance };
            let (ax, ay) = (splat(t.centre.x) + dot(t.to_x) * scale, splat(t.centre.y) - dot(t.to_y) * scale);
            let inside = ax.simd_ge(splat(held.x0 as f32))
                & ay.simd_ge(splat(held.y0 as f32))
                & ax.simd_lt(splat(held.x1 as f32))
                & ay.simd_lt(splat(held.y1 as f32));
            // Perspective: only points ahead of the eye.
            let inside = if t.ortho { inside } else { inside & distance.simd_gt(splat(0.0)) }.to_bitmask();
            let (ax, ay) = (ax.to_array(), ay.to_array());
            // Where the point falls outside the frame, 0: nothing seen.
            let surface = f32x8::new(std::array::from_fn(|i| {
                if inside >> i & 1 == 0 {
                    return 0.0;
                }
                let (x, y) = (ax[i] as usize - held.x0 as usize, ay[i] as usize - held.y0 as usize);
                self.coarse[y / 2 * self.coarse_width + x / 2]
            }));
            let radius = splat(self.radius);
            let shut = if t.ortho {
                let bias = splat(0.02 * self.radius + 2.0 * self.pixel);
                // Stored depth is (far − distance) / (far − near).
                let (far, span) = (splat(camera.far), splat(camera.far - camera.near));
                (surface * span).simd_gt(far - distance + bias) & (surface * span).simd_lt(far - distance + radius)
            } else {
                let bias = splat(0.02 * self.radius) + splat(2.0 * self.pixel) * distance;
                // Stored depth is near / distance.
                let near = splat(camera.near);
                (surface * (distance - bias)).simd_gt(near)
                    & (distance.simd_le(radius) | (surface * (distance - radius)).simd_lt(near))
            };
            closed |= shut.to_bitmask() << (b * 8);
        }
        closed
    }

    /// What the depths of cells and pixels are compared by ([`alike`]):
    /// stored depth `depth` itself (perspective), its view distance
    /// (orthographic).
    fn key(&self, depth: f32) -> f32 {
        let (a, b) = self.keys();
        a + b * depth
    }

    /// [`Probe::key`] as `(a, b)`: the key of `depth` is `a + b · depth`.
    fn keys(&self) -> (f32, f32) {
        let camera = &self.scene.camera;
        if self.rays.ortho {
            // Orthographic stored depth is (far − distance) / (far − near).
            (camera.far, camera.near - camera.far)
        } else {
            (0.0, 1.0)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::Projection;

    /// Each pixel's surface point projects back onto the pixel's centre at
    /// the view distance its stored depth gives, through a perspective and
    /// an orthographic camera.
    #[test]
    fn surface_points_project_back_to_their_pixels() {
        for ortho in [false, true] {
            let mut scene = crate::scene::demo::demo_scene().expect("the demo");
            (scene.width, scene.height) = (96, 54);
            if ortho {
                scene.camera.projection = Projection::Orthographic { height: 6.0 };
            }
            let mut vb = VisibilityBuffer::new(scene.width, scene.height);
            crate::visibility::rasterize(&scene, &mut vb);
            let probe = Probe::new(&scene, &vb, 1.0);
            let t = &probe.to_pixel;
            let mut seen = 0;
            for (x, y) in (0..54).flat_map(|y| (0..96).map(move |x| (x, y))) {
                let Some((p, _)) = probe.point_at(x, y) else { continue };
                seen += 1;
                let v = p - t.origin;
                let d = v.dot(t.forward);
                let s = if t.ortho { 1.0 } else { 1.0 / d };
                let at = Vec2::new(t.centre.x + v.dot(t.to_x) * s, t.centre.y - v.dot(t.to_y) * s);
                let centre = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
                assert!((at - centre).length() < 0.05, "ortho {ortho}: pixel ({x}, {y}) projects to {at}");
                let expected = scene.camera.view_distance_at_depth(vb.depth(x, y));
                assert!((d - expected).abs() < 1e-3 * expected, "ortho {ortho}: distance {d} against {expected}");
            }
            assert!(seen > 1000, "{seen} pixels seen");
        }
    }
}
