//! Percentage-closer soft shadows (Fernando, "Percentage-Closer Soft
//! Shadows", SIGGRAPH 2005 sketch), as game engines ship them (Bevy,
//! Filament): one map from the light's centre; around the receiver's texel a
//! blocker search as wide as the light's disc seen from the receiver through
//! the nearest casters; the blockers' mean distance `d_b` gives the penumbra
//! (d − d_b)·r/d_b at the receiver (d its distance, r the light's radius),
//! and a percentage-closer filter that wide decides the term.
//!
//! Both searches take their taps from a Vogel disc (a golden-angle spiral, as
//! Bevy's), turned by an angle hashed from the point, so neighbouring pixels
//! sample different texels and the pattern becomes fine noise instead of
//! bands. A light of size 0 gives radius-0 searches: every tap reads the
//! receiver's texel and the term is the hard map's.
//!
//! How it runs: the spiral's unit directions are a table, turned by one
//! rotation per point, and the shading passes ask for eight points at once
//! ([`lit_lanes`]): projection, radii, tap positions and depth tests as 8-lane
//! arithmetic, the texel reads one lane at a time. The three ways measured on
//! the 1920×1080 demo with `--shadows pcss` (the shading time
//! `kage render --shadows pcss --width 1920 --height 1080 --threads 1` prints;
//! 2-core machine): a sine and a cosine per tap 700 ms, the turned table
//! 455 ms, the table eight points at a time 278 ms (two threads: 354, 232,
//! 146 ms); the images agree to an RMSE of 2e-5.

use glam::Vec3;
use wide::f32x8;

use super::map::DepthMap;
use crate::scene::ShadowSettings;

/// Widest search or filter, in texels: past it a tap is too sparse to tell
/// anything and reads far from the receiver's own depth.
pub const MAX_RADIUS: f32 = 64.0;

/// The golden angle, radians: successive spiral taps turn by it.
const GOLDEN_ANGLE: f32 = 2.399_963;

/// A light's size and where its casters begin: what the searches are sized
/// by.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PcssLight {
    /// The light's radius, world units.
    pub size: f32,
    /// Distance along each map's axis to the nearest caster (at least the
    /// map's near plane): the blocker search covers what the disc's cone
    /// from the receiver reaches there.
    pub nearest: f32,
}

/// The PCSS term of `map` at `p` with N·L = `cos_theta`: 1 lit, 0 in
/// shadow, between in a penumbra.
#[must_use]
pub fn lit(map: &DepthMap, p: Vec3, cos_theta: f32, settings: &ShadowSettings, light: &PcssLight) -> f32 {
    let Some((_, _, d)) = map.project(p) else { return 1.0 };
    let texel_per_world = |at: f32| 1.0 / map.texel_size(at).max(f32::MIN_POSITIVE);
    // The disc seen from p through the nearest casters: radius r·(d − n)/d
    // at distance n, in texels there.
    let nearest = light.nearest.min(d);
    let search = (light.size * (d - nearest) / d * texel_per_world(nearest)).min(MAX_RADIUS);
    let Some(at) = map.locate(p, cos_theta, settings, 1.0) else { return 1.0 };
    let turn = hash_angle(p);
    let (mut sum, mut found) = (0.0, 0u32);
    for (du, dv) in spiral(settings.blockers, search, turn) {
        let z = map.texel_depth_clamped(at.u + du, at.v + dv);
        if z > at.z_limit {
            sum += map.distance_and_texel(z).0;
            found += 1;
        }
    }
    if found == 0 {
        return 1.0;
    }
    let blocker = (sum / found as f32).max(f32::MIN_POSITIVE);
    // The penumbra's half-width at the receiver, in texels there.
    let radius = (light.size * (d - blocker).max(0.0) / blocker * texel_per_world(d)).min(MAX_RADIUS);
    let Some(at) = map.locate(p, cos_theta, settings, 1.0 + radius.min(8.0)) else { return 1.0 };
    let n = settings.filter.max(1);
    let lit =
        spiral(n, radius, turn + 1.0).filter(|&(du, dv)| map.texel_depth_clamped(at.u + du, at.v + dv) <= at.z_limit);
    lit.count() as f32 / n as f32
}

/// Most taps a search or filter takes (the scene format's limit).
const MAX_TAPS: usize = 256;

/// The unit directions of the spiral's taps, (cos, sin) of i·(golden angle):
/// computed once, then turned per point by one rotation, where a sine and a
/// cosine per tap made up most of a PCSS lookup's cost.
fn unit_taps() -> &'static [(f32, f32); MAX_TAPS] {
    static TAPS: std::sync::OnceLock<[(f32, f32); MAX_TAPS]> = std::sync::OnceLock::new();
    TAPS.get_or_init(|| {
        std::array::from_fn(|i| {
            let (s, c) = (f64::from(i as u32) * f64::from(GOLDEN_ANGLE)).sin_cos();
            (c as f32, s as f32)
        })
    })
}

/// [`lit`] for eight points (`p` as x, y and z lanes): the projection, the
/// searches' radii, the taps' positions and the depth tests as vector
/// arithmetic, eight points a tap; the texel reads one lane at a time.
#[must_use]
pub fn lit_lanes(
    map: &DepthMap,
    p: [f32x8; 3],
    cos_theta: f32x8,
    settings: &ShadowSettings,
    light: &PcssLight,
) -> f32x8 {
    let at = map.locate_lanes(p, cos_theta, settings, 1.0);
    if at.inside.to_array().iter().all(|&m| m == 0.0) {
        return f32x8::ONE;
    }
    let (x, y, z) = (p[0].to_array(), p[1].to_array(), p[2].to_array());
    let turn: [f32; 8] = std::array::from_fn(|i| hash_angle(Vec3::new(x[i], y[i], z[i])));
    let d = at.distance;
    let size = f32x8::splat(light.size);
    let nearest = f32x8::splat(light.nearest).min(d);
    let search = (size * (d - nearest) / d / map.texel_size_lanes(nearest)).min(f32x8::splat(MAX_RADIUS));
    let (mut sum, mut found) = (f32x8::ZERO, f32x8::ZERO);
    for (du, dv) in spiral_lanes(settings.blockers, search, turn) {
        let z = depths(map, at.u + du, at.v + dv);
        let blocks = z.simd_gt(at.z_limit);
        sum += blocks.select(map.distance_lanes(z.max(f32x8::splat(f32::MIN_POSITIVE))), f32x8::ZERO);
        found += blocks.select(f32x8::ONE, f32x8::ZERO);
    }
    let none = found.simd_eq(f32x8::ZERO) | at.inside.simd_eq(f32x8::ZERO);
    if none.to_array().iter().all(|&m| m != 0.0) {
        return f32x8::ONE;
    }
    let blocker = (sum / found.max(f32x8::ONE)).max(f32x8::splat(f32::MIN_POSITIVE));
    let radius =
        (size * (d - blocker).max(f32x8::ZERO) / blocker / map.texel_size_lanes(d)).min(f32x8::splat(MAX_RADIUS));
    let at = map.locate_lanes_reaching(p, cos_theta, settings, f32x8::ONE + radius.min(f32x8::splat(8.0)));
    let n = settings.filter.max(1);
    let mut lit = f32x8::ZERO;
    for (du, dv) in spiral_lanes(n, radius, turn.map(|t| t + 1.0)) {
        lit += depths(map, at.u + du, at.v + dv).simd_le(at.z_limit).select(f32x8::ONE, f32x8::ZERO);
    }
    none.select(f32x8::ONE, lit / f32x8::splat(n.min(MAX_TAPS as u32) as f32))
}

/// The map's depths at eight texel positions (clamped to the map).
fn depths(map: &DepthMap, u: f32x8, v: f32x8) -> f32x8 {
    let (u, v) = (u.to_array(), v.to_array());
    f32x8::new(std::array::from_fn(|i| map.texel_depth_clamped(u[i], v[i])))
}

/// [`spiral`] for eight points at once, each with its own radius and turn.
fn spiral_lanes(n: u32, radius: f32x8, turn: [f32; 8]) -> impl Iterator<Item = (f32x8, f32x8)> {
    let n = n.clamp(1, MAX_TAPS as u32);
    let (ts, tc): ([f32; 8], [f32; 8]) = (turn.map(|t| t.sin_cos().0), turn.map(|t| t.sin_cos().1));
    let (ts, tc) = (f32x8::new(ts), f32x8::new(tc));
    unit_taps()[..n as usize].iter().enumerate().map(move |(i, &(c, s))| {
        let r = radius * f32x8::splat(((i as f32 + 0.5) / n as f32).sqrt());
        let (c, s) = (f32x8::splat(c), f32x8::splat(s));
        (r * (c * tc - s * ts), r * (s * tc + c * ts))
    })
}

/// `n` taps of a Vogel disc of `radius` turned by `turn` radians: tap i at
/// radius·√((i + ½)/n), angle i·(golden angle) + turn.
fn spiral(n: u32, radius: f32, turn: f32) -> impl Iterator<Item = (f32, f32)> {
    let n = n.clamp(1, MAX_TAPS as u32);
    let (ts, tc) = turn.sin_cos();
    unit_taps()[..n as usize].iter().enumerate().map(move |(i, &(c, s))| {
        let r = radius * ((i as f32 + 0.5) / n as f32).sqrt();
        (r * (c * tc - s * ts), r * (s * tc + c * ts))
    })
}

/// An angle in [0, 2π) hashed from `p`'s bits: the same point always turns
/// its taps the same way.
fn hash_angle(p: Vec3) -> f32 {
    let mut h = p.x.to_bits().wrapping_mul(0x9E37_79B1) ^ p.y.to_bits().rotate_left(11).wrapping_mul(0x85EB_CA77);
    h ^= p.z.to_bits().rotate_left(21).wrapping_mul(0xC2B2_AE3D);
    h ^= h >> 15;
    h = h.wrapping_mul(0x2C1B_3C6D);
    h ^= h >> 12;
    (h >> 8) as f32 / (1u32 << 24) as f32 * std::f32::consts::TAU
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spiral_taps_fill_the_disc_evenly() {
        let taps: Vec<(f32, f32)> = spiral(64, 2.0, 0.3).collect();
        assert!(taps.iter().all(|(x, y)| x.hypot(*y) <= 2.0));
        // Each quarter of the disc holds about a quarter of the taps.
        for q in 0..4 {
            let inside =
                taps.iter().filter(|(x, y)| (*x >= 0.0) == (q & 1 == 0) && (*y >= 0.0) == (q & 2 == 0)).count();
            assert!((12..=20).contains(&inside), "quarter {q}: {inside}");
        }
        // Half the taps within the radius's 1/√2 (equal area).
        let inner = taps.iter().filter(|(x, y)| x.hypot(*y) <= 2.0 / 2f32.sqrt()).count();
        assert_eq!(inner, 32);
        assert!(spiral(16, 0.0, 1.0).all(|t| t == (0.0, 0.0)));
    }

    /// The turned table gives the spiral's definition: tap i at
    /// radius·√((i + ½)/n), angle i·(golden angle) + turn.
    #[test]
    fn the_turned_table_is_the_spiral() {
        for (n, radius, turn) in [(16u32, 3.0f32, 0.0f32), (64, 10.5, 2.7), (256, 64.0, 6.1), (1, 1.0, 1.0)] {
            for (i, (x, y)) in spiral(n, radius, turn).enumerate() {
                let r = radius * ((i as f32 + 0.5) / n as f32).sqrt();
                let a = f64::from(i as u32) * f64::from(GOLDEN_ANGLE) + f64::from(turn);
                let (want_x, want_y) = (r * a.cos() as f32, r * a.sin() as f32);
                assert!((x - want_x).abs() < 1e-4 * radius && (y - want_y).abs() < 1e-4 * radius, "{n} {i}");
            }
            assert_eq!(spiral(n, radius, turn).count(), n as usize);
        }
    }
}
