//! Deterministic sample patterns shared by the techniques that average several
//! samples: jittered sub-pixel passes, area lights moved over their extent, and
//! the reference renderer's stratified rays. Deterministic, so every render of a
//! scene is the same image.

use glam::Vec2;

/// The digits of `i` in `base` mirrored about the radix point (van der Corput).
pub fn radical_inverse(mut i: u32, base: u32) -> f32 {
    let (mut value, mut scale) = (0.0f64, 1.0f64 / base as f64);
    while i > 0 {
        value += (i % base) as f64 * scale;
        i /= base;
        scale /= base as f64;
    }
    value as f32
}

/// Sample `k` of an n × n stratified grid over the unit square, jittered by `h`
/// (n = 1: the centre).
pub fn stratified(k: u32, n: u32, h: u32) -> Vec2 {
    if n == 1 {
        return Vec2::splat(0.5);
    }
    let jitter = Vec2::new((h & 0xffff) as f32 / 65536.0, (h >> 16) as f32 / 65536.0);
    (Vec2::new((k % n) as f32, (k / n) as f32) + jitter) / n as f32
}

/// The unit square mapped onto the unit disc, area-preserving (Shirley–Chiu).
pub fn concentric_disc(p: Vec2) -> Vec2 {
    let q = 2.0 * p - Vec2::ONE;
    if q == Vec2::ZERO {
        return q;
    }
    let (r, theta) = if q.x.abs() > q.y.abs() {
        (q.x, std::f32::consts::FRAC_PI_4 * (q.y / q.x))
    } else {
        (q.y, std::f32::consts::FRAC_PI_2 - std::f32::consts::FRAC_PI_4 * (q.x / q.y))
    };
    r * Vec2::new(theta.cos(), theta.sin())
}

/// A well-mixed 32-bit hash of three numbers (deterministic jitter).
pub fn hash3(a: u32, b: u32, c: u32) -> u32 {
    let mut h = a.wrapping_mul(0x9E37_79B1) ^ b.wrapping_mul(0x85EB_CA77) ^ c.wrapping_mul(0xC2B2_AE3D);
    h ^= h >> 16;
    h = h.wrapping_mul(0x7FEB_352D);
    h ^= h >> 15;
    h = h.wrapping_mul(0x846C_A68B);
    h ^ (h >> 16)
}
