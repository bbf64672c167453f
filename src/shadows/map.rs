//! One shadow map (Williams 1978; seed 002 §3.3's shadow pass): the depth of the
//! surfaces nearest a light, rendered by the same polygon pass as the eye's view,
//! and the test that decides whether a point lies behind them.
//!
//! Depth is compared as distance along the light's view axis, recovered from the
//! reversed depth the rasterizer stores, so the bias is in world units: one texel's
//! world size at the receiver times (constant + slope · tan θ), θ the angle between
//! the surface normal and the light. The constant term absorbs depth quantisation;
//! the slope term the depth change across one texel of a surface the light grazes.

use glam::{Mat4, Vec2, Vec3};
use wide::f32x8;

use crate::scene::{Scene, ShadowSettings};

use crate::camera::{Camera, PixelRays, Projection};
use crate::visibility::{rasterize_casters, VisibilityBuffer, Workers};

/// Largest tan θ the slope bias uses (θ ≈ 84°); beyond it the bias would push
/// shadows off their casters.
const MAX_SLOPE: f32 = 8.0;

/// The constant bias, in texels, against surfaces of other objects than the
/// receiver ([`Located::z_other`]).
#[inline]
#[must_use]
pub fn other_bias(settings: &ShadowSettings) -> f32 {
    settings.bias / settings.scale.max(1.0)
}

/// A point located in a map: texel coordinates and the depth limit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Located {
    /// Texel column coordinate (fractional).
    pub u: f32,
    /// Texel row coordinate (fractional).
    pub v: f32,
    /// Reversed depth a surface must exceed to hide the point.
    pub z_limit: f32,
    /// World size of one texel at the point's distance from the light.
    pub texel: f32,
    /// Reversed depth a surface of another object than the point's must
    /// exceed to hide it, where that surface's depth is known at the point
    /// (a silhouette line's): the constant bias of the map drawn without the
    /// virtual projection space's scale, and no slope bias, which only the
    /// receiver's own surface, sampled away from the point, needs.
    pub z_other: f32,
}

/// Eight points located in a map ([`DepthMap::locate_lanes`]).
#[derive(Debug, Clone, Copy)]
pub struct LocatedLanes {
    /// All bits set in lanes whose point lies in the map.
    pub inside: f32x8,
    /// Texel column coordinates.
    pub u: f32x8,
    /// Texel row coordinates.
    pub v: f32x8,
    /// Depth limits.
    pub z_limit: f32x8,
    /// World sizes of one texel at the points' distances.
    pub texel: f32x8,
    /// Depth limits against other objects' surfaces ([`Located::z_other`]).
    pub z_other: f32x8,
    /// The points' distances along the light's axis.
    pub distance: f32x8,
}

/// What the points of a box can be in a map ([`DepthMap::box_bounds`]).
#[derive(Debug, Clone, Copy)]
pub struct BoxBounds {
    /// The first and last texel (x, y) they fall in, clamped to the map.
    pub texels: ((u32, u32), (u32, u32)),
    /// Whether every point falls inside the map.
    pub inside: bool,
    /// The least depth limit (reversed depth) of any of them.
    pub limit_lo: f32,
    /// The greatest, `None` where a point's limit may reach the light.
    pub limit_hi: Option<f32>,
}

/// Depths seen from a light through one camera.
#[derive(Debug, Clone)]
pub struct DepthMap {
    view_proj: Mat4,
    /// The light's rays through the texels.
    rays: PixelRays,
    eye: Vec3,
    axis: Vec3,
    resolution: u32,
    /// World size of a texel per unit distance (perspective) or absolute (orthographic).
    texel: f32,
    ortho: bool,
    near: f32,
    far: f32,
    /// Reversed depth of the nearest surface per texel (0: none).
    depth: VisibilityBuffer,
}

impl DepthMap {
    /// Renders the depth of the objects of `scene` that `casters` marks
    /// ([`Scene::map_casters`]) seen by `camera` into a square map of
    /// `resolution` texels, held in `depth` (a depth-only buffer, resized),
    /// its meshes drawn on `workers`.
    #[must_use]
    pub fn render(
        scene: &Scene,
        camera: &Camera,
        resolution: u32,
        casters: &[bool],
        workers: Workers,
        mut depth: VisibilityBuffer,
    ) -> DepthMap {
        depth.resize(resolution, resolution);
        rasterize_casters(scene, camera, casters, workers, &mut depth);
        DepthMap::of(camera, depth)
    }

    /// A map of `camera` with nothing drawn in it (every point it holds is
    /// lit), in `depth` (made one texel).
    #[must_use]
    pub fn empty(camera: &Camera, mut depth: VisibilityBuffer) -> DepthMap {
        depth.resize(1, 1);
        depth.clear();
        DepthMap::of(camera, depth)
    }

    /// The map of `camera` whose depths `depth` holds (square).
    fn of(camera: &Camera, depth: VisibilityBuffer) -> DepthMap {
        let resolution = depth.width();
        let (ortho, texel) = match camera.projection {
            Projection::Perspective { fov_y_deg } => (false, 2.0 * (fov_y_deg.to_radians() * 0.5).tan()),
            Projection::Orthographic { height } => (true, height),
        };
        DepthMap {
            view_proj: camera.view_projection(1.0),
            rays: camera.pixel_rays(Vec2::splat(resolution as f32)),
            eye: camera.eye,
            axis: (camera.target - camera.eye).normalize(),
            resolution,
            texel: texel / resolution as f32,
            ortho,
            near: camera.near,
            far: camera.far,
            depth,
        }
    }

    /// Where `p` falls in the map: texel coordinates and distance along the
    /// light's axis; `None` outside the map (or behind the light).
    #[inline]
    #[must_use]
    pub fn project(&self, p: Vec3) -> Option<(f32, f32, f32)> {
        let c = self.view_proj * p.extend(1.0);
        if c.w <= 0.0 {
            return None;
        }
        let (x, y) = (c.x / c.w, c.y / c.w);
        let n = self.resolution as f32;
        let (u, v) = ((x * 0.5 + 0.5) * n, (0.5 - y * 0.5) * n);
        // Perspective: w is the distance along the axis; orthographic: w = 1.
        let d = if self.ortho { (p - self.eye).dot(self.axis) } else { c.w };
        (u >= 0.0 && v >= 0.0 && u < n && v < n).then_some((u, v, d))
    }

    /// Bounds for every point of the box `lo`..`hi` read with `settings`
    /// (one tap): the texels they fall in, clamped to the map, whether all
    /// of them fall inside it, and the least and the greatest depth limit
    /// any of them can have, whatever its N·L. `None` when part of the box
    /// lies behind the light or at it.
    #[must_use]
    pub fn box_bounds(&self, lo: Vec3, hi: Vec3, settings: &ShadowSettings) -> Option<BoxBounds> {
        let n = self.resolution as f32;
        let (mut u0, mut v0, mut u1, mut v1) = (f32::INFINITY, f32::INFINITY, f32::NEG_INFINITY, f32::NEG_INFINITY);
        let (mut near, mut far) = (f32::INFINITY, f32::NEG_INFINITY);
        for k in 0..8 {
            let c = Vec3::new([lo.x, hi.x][k & 1], [lo.y, hi.y][(k >> 1) & 1], [lo.z, hi.z][(k >> 2) & 1]);
            let clip = self.view_proj * c.extend(1.0);
            if clip.w <= 0.0 {
                return None;
            }
            let (u, v) = ((clip.x / clip.w * 0.5 + 0.5) * n, (0.5 - clip.y / clip.w * 0.5) * n);
            let d = if self.ortho { (c - self.eye).dot(self.axis) } else { clip.w };
            (u0, v0, u1, v1) = (u0.min(u), v0.min(v), u1.max(u), v1.max(v));
            (near, far) = (near.min(d), far.max(d));
        }
        let inside = u0 >= 0.0 && v0 >= 0.0 && u1 < n && v1 < n;
        let last = n - 1.0;
        let texel = |u: f32| u.floor().clamp(0.0, last) as u32;
        // The limit lies `bias + slope · tan` texels before the point, tan
        // between 0 and MAX_SLOPE; a perspective texel grows with distance.
        let before = |d: f32, texels: f32| d - texels * if self.ortho { self.texel } else { self.texel * d };
        let least = before(far, settings.bias);
        let most = before(near, settings.bias + settings.slope * MAX_SLOPE);
        Some(BoxBounds {
            texels: ((texel(u0), texel(v0)), (texel(u1), texel(v1))),
            inside,
            // Reversed depth falls with distance; a limit at the light is
            // lit (no bound from below there).
            limit_lo: self.reversed(least)?,
            limit_hi: self.reversed(most),
        })
    }

    /// Where `p` falls in the map and the depth a surface there must be
    /// nearer than (reversed depth, larger is nearer) to hide it, with
    /// `cos_theta` = N·L at `p` for the slope bias and the bias reaching
    /// `reach` texels from `p`'s own; `None` when `p` is outside the map or
    /// at the light (lit).
    #[inline]
    #[must_use]
    pub fn locate(&self, p: Vec3, cos_theta: f32, settings: &ShadowSettings, reach: f32) -> Option<Located> {
        let (u, v, d) = self.project(p)?;
        let texel = if self.ortho { self.texel } else { self.texel * d };
        let c = cos_theta.clamp(1e-3, 1.0);
        let tan = ((1.0 - c * c).sqrt() / c).min(MAX_SLOPE);
        let limit = d - texel * (settings.bias + settings.slope * tan * reach);
        let z_limit = self.reversed(limit)?;
        let z_other = self.reversed(d - texel * other_bias(settings)).unwrap_or(z_limit);
        Some(Located { u, v, z_limit, texel, z_other })
    }

    /// Distance `limit` along the light's axis as the stored reversed depth
    /// (which falls with distance: one division per lookup instead of one
    /// per texel); `None` for a perspective map's point at the light.
    #[inline]
    fn reversed(&self, limit: f32) -> Option<f32> {
        if self.ortho {
            Some(((self.far - limit) / (self.far - self.near)).max(0.0))
        } else if limit > self.near {
            Some(self.near / limit)
        } else {
            None
        }
    }

    /// The distance along the light's axis of a surface the map holds at
    /// reversed depth `z` (above 0), and the world size of a texel there.
    #[must_use]
    pub fn distance_and_texel(&self, z: f32) -> (f32, f32) {
        if self.ortho {
            (self.far - z * (self.far - self.near), self.texel)
        } else {
            let d = self.near / z;
            (d, self.texel * d)
        }
    }

    /// [`DepthMap::distance_and_texel`]'s distances for eight reversed
    /// depths (above 0).
    #[must_use]
    pub fn distance_lanes(&self, z: f32x8) -> f32x8 {
        if self.ortho {
            f32x8::splat(self.far) - z * f32x8::splat(self.far - self.near)
        } else {
            f32x8::splat(self.near) / z
        }
    }

    /// [`DepthMap::texel_size`] at eight distances.
    #[must_use]
    pub fn texel_size_lanes(&self, along: f32x8) -> f32x8 {
        if self.ortho {
            f32x8::splat(self.texel)
        } else {
            along * f32x8::splat(self.texel)
        }
    }

    /// The direction from `p` towards the light (not normalised).
    #[inline]
    #[must_use]
    pub fn towards_light(&self, p: Vec3) -> Vec3 {
        if self.ortho {
            -self.axis
        } else {
            self.eye - p
        }
    }

    /// The reversed depth at which the plane through `p` with normal `n`
    /// crosses the light's ray through the centre of texel `(x, y)`, brought
    /// `bias` world units nearer the light: what a surface seen there must
    /// exceed to lie in front of that plane. `None` where the ray runs along
    /// the plane or the limit is at the light.
    #[must_use]
    pub fn plane_limit(&self, p: Vec3, n: Vec3, (x, y): (u32, u32), bias: f32) -> Option<f32> {
        let ray = self.rays.ray(Vec2::new(x as f32 + 0.5, y as f32 + 0.5));
        let along = n.dot(ray.dir);
        if along.abs() < 1e-6 {
            return None;
        }
        let q = ray.origin + ray.dir * (n.dot(p - ray.origin) / along);
        self.reversed((q - self.eye).dot(self.axis) - bias)
    }

    /// The unit direction from `p` to the light and the distance to it
    /// (infinite for a directional light's orthographic map).
    #[must_use]
    pub fn ray_to_light(&self, p: Vec3) -> (Vec3, f32) {
        let to = self.towards_light(p);
        let distance = if self.ortho { f32::INFINITY } else { to.length() };
        (to.normalize_or(-self.axis), distance)
    }

    /// The world size of one texel at distance `along` the light's axis.
    #[inline]
    #[must_use]
    pub fn texel_size(&self, along: f32) -> f32 {
        if self.ortho {
            self.texel
        } else {
            self.texel * along
        }
    }

    /// The reversed depth the map holds at the texel holding texel
    /// coordinates `(u, v)`, or at the nearest texel of the map's border
    /// for coordinates outside it.
    #[inline]
    #[must_use]
    pub fn texel_depth_clamped(&self, u: f32, v: f32) -> f32 {
        let last = self.resolution.saturating_sub(1) as f32;
        self.texel_depth(u.floor().clamp(0.0, last) as u32, v.floor().clamp(0.0, last) as u32)
    }

    /// The reversed depth the map holds at every texel, row by row (0:
    /// nothing).
    #[must_use]
    pub fn depths(&self) -> &[f32] {
        self.depth.depths()
    }

    /// The reversed depth the map holds at texel `(x, y)` (0: nothing).
    #[inline]
    #[must_use]
    pub fn texel_depth(&self, x: u32, y: u32) -> f32 {
        self.depth.depths()[(y * self.resolution + x) as usize]
    }

    /// The object whose surface the map holds at texel `(x, y)`, when the map
    /// keeps item ids (an SLB's does); `None` otherwise or where it holds
    /// nothing.
    #[inline]
    #[must_use]
    pub fn texel_object(&self, x: u32, y: u32) -> Option<u32> {
        let item = self.depth.items().get((y * self.resolution + x) as usize)?;
        (!item.is_none()).then_some(item.object)
    }

    /// Texels along a side.
    #[must_use]
    pub fn resolution(&self) -> u32 {
        self.resolution
    }

    /// Fraction of the k × k texels around `p`'s projection whose surface does not
    /// hide `p`, with `cos_theta` = N·L at `p` (for the slope bias). Points outside
    /// the map are lit.
    #[must_use]
    pub fn lit(&self, p: Vec3, cos_theta: f32, settings: &ShadowSettings) -> f32 {
        let k = settings.pcf.max(1) as i32;
        // A wider filter reaches texels further from the receiver's own, where a
        // sloped receiver is deeper: scale the slope term with the filter radius.
        let reach = 1.0 + (k - 1) as f32 * 0.5;
        let Some(Located { u, v, z_limit, .. }) = self.locate(p, cos_theta, settings, reach) else { return 1.0 };
        let (cu, cv) = (u as i32, v as i32);
        let last = self.resolution as i32 - 1;
        let depth = self.depth.depths();
        let mut lit = 0u32;
        for dy in 0..k {
            let y = (cv + dy - k / 2).clamp(0, last) as usize * self.resolution as usize;
            for dx in 0..k {
                let x = (cu + dx - k / 2).clamp(0, last) as usize;
                lit += u32::from(depth[y + x] <= z_limit);
            }
        }
        lit as f32 / (k * k) as f32
    }

    /// [`DepthMap::locate`] for eight points: which lie in the map, their
    /// texel coordinates and depth limits (infinite for a point at the light).
    #[must_use]
    pub fn locate_lanes(&self, p: [f32x8; 3], cos_theta: f32x8, settings: &ShadowSettings, reach: f32) -> LocatedLanes {
        self.locate_lanes_reaching(p, cos_theta, settings, f32x8::splat(reach))
    }

    /// [`DepthMap::locate_lanes`] with each point's bias reaching its own
    /// number of texels.
    #[must_use]
    pub fn locate_lanes_reaching(
        &self,
        p: [f32x8; 3],
        cos_theta: f32x8,
        settings: &ShadowSettings,
        reach: f32x8,
    ) -> LocatedLanes {
        let m = self.view_proj;
        let row = |r: usize| {
            let (a, b, c, d) = (m.x_axis[r], m.y_axis[r], m.z_axis[r], m.w_axis[r]);
            p[0].mul_add(f32x8::splat(a), p[1].mul_add(f32x8::splat(b), p[2].mul_add(f32x8::splat(c), f32x8::splat(d))))
        };
        let (cx, cy, cw) = (row(0), row(1), row(3));
        let n = f32x8::splat(self.resolution as f32);
        let half = f32x8::splat(0.5);
        let inv_w = f32x8::ONE / cw;
        let u = (cx * inv_w).mul_add(half, half) * n;
        let v = (half - cy * inv_w * half) * n;
        let zero = f32x8::ZERO;
        let inside = cw.simd_gt(zero) & u.simd_ge(zero) & v.simd_ge(zero) & u.simd_lt(n) & v.simd_lt(n);
        let d = if self.ortho {
            let e = self.eye;
            let a = self.axis;
            (p[0] - f32x8::splat(e.x)) * f32x8::splat(a.x)
                + (p[1] - f32x8::splat(e.y)) * f32x8::splat(a.y)
                + (p[2] - f32x8::splat(e.z)) * f32x8::splat(a.z)
        } else {
            cw
        };
        let texel = if self.ortho { f32x8::splat(self.texel) } else { d * f32x8::splat(self.texel) };
        let c = cos_theta.max(f32x8::splat(1e-3)).min(f32x8::ONE);
        let tan = ((f32x8::ONE - c * c).sqrt() / c).min(f32x8::splat(MAX_SLOPE));
        let bias = f32x8::splat(settings.bias) + tan * f32x8::splat(settings.slope) * reach;
        let reversed = |limit: f32x8| {
            if self.ortho {
                ((f32x8::splat(self.far) - limit) / f32x8::splat(self.far - self.near)).max(zero)
            } else {
                let near = f32x8::splat(self.near);
                limit.simd_gt(near).select(near / limit, f32x8::splat(f32::INFINITY))
            }
        };
        let z_limit = reversed(d - texel * bias);
        let z_other = reversed(d - texel * f32x8::splat(other_bias(settings)));
        LocatedLanes { inside, u, v, z_limit, texel, z_other, distance: d }
    }

    /// [`DepthMap::lit`] for eight points at once (`p` as x, y and z lanes): the
    /// projection, bias and depth limit as vector arithmetic, the texel reads one
    /// lane at a time.
    #[must_use]
    pub fn lit_lanes(&self, p: [f32x8; 3], cos_theta: f32x8, settings: &ShadowSettings) -> f32x8 {
        let k = settings.pcf.max(1) as i32;
        let reach = 1.0 + (k - 1) as f32 * 0.5;
        let LocatedLanes { inside, u, v, z_limit, .. } = self.locate_lanes(p, cos_theta, settings, reach);
        let zero = f32x8::ZERO;
        let depth = self.depth.depths();
        let res = self.resolution as usize;
        // k × k taps; each tap's eight texel reads are issued before any compare, so
        // their cache misses overlap. Texel coordinates are clamped to the map as
        // vectors (lanes outside it read texel 0 and count lit), leaving one load
        // per lane.
        let last = f32x8::splat((self.resolution - 1) as f32);
        let (u0, v0) = (inside.select(u, zero).floor(), inside.select(v, zero).floor());
        let texels = |base: f32x8, d: i32| (base + f32x8::splat(d as f32)).max(zero).min(last).round_int().to_array();
        let mut lit = zero;
        for dy in 0..k {
            let y = texels(v0, dy - k / 2);
            for dx in 0..k {
                let x = texels(u0, dx - k / 2);
                let texel: [f32; 8] = std::array::from_fn(|i| depth[y[i] as usize * res + x[i] as usize]);
                lit += f32x8::new(texel).simd_le(z_limit).select(f32x8::ONE, zero);
            }
        }
        inside.select(lit * f32x8::splat(1.0 / (k * k) as f32), f32x8::ONE)
    }

    /// Gives the map's buffer back (for the next map to reuse).
    #[must_use]
    pub fn into_buffer(self) -> VisibilityBuffer {
        self.depth
    }

    /// Bytes held by the map.
    #[must_use]
    pub fn memory_bytes(&self) -> usize {
        self.depth.memory_bytes()
    }
}
