//! Tone curves: how linear light above display white becomes 8-bit colour.
//!
//! A render's values are light, not paint: a lamp's glare, a metal's
//! highlight or a photometric glTF light reach far past 1. Clipping each
//! channel at 1 turns such pixels white and shifts their hue (an orange
//! highlight clips to yellow, then white). A tone curve rolls them off
//! instead. The default, [`ToneCurve::Neutral`], is Khronos' *PBR Neutral*
//! curve: the identity (less a small toe offset) up to 0.76, above it a
//! compression of the brightest channel that keeps the hue, desaturating
//! only what is far past white — so a material's base colour comes out as
//! its file says. [`ToneCurve::Agx`] is the AgX curve (a log encoding, a
//! sigmoid, a gamut inset that keeps bright saturated light from going
//! flat), [`ToneCurve::Aces`] Narkowicz's fit of the ACES film curve per
//! channel (contrasty; saturated highlights shift hue; white at 7.24), [`ToneCurve::Clip`]
//! no curve.

use glam::{Mat3, Vec3};

/// A tone curve for 8-bit output; see the module doc.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ToneCurve {
    /// Each channel clipped at 1.
    Clip,
    /// Khronos PBR Neutral: hue-preserving, identity below 0.76.
    #[default]
    Neutral,
    /// AgX (Sobotka's curve, in its common polynomial approximation).
    Agx,
    /// Narkowicz's ACES film curve fit, per channel.
    Aces,
}

impl ToneCurve {
    /// Every curve with its name, as the command line and scene files spell it.
    pub const NAMES: [(&'static str, ToneCurve); 4] = [
        ("none", ToneCurve::Clip),
        ("neutral", ToneCurve::Neutral),
        ("agx", ToneCurve::Agx),
        ("aces", ToneCurve::Aces),
    ];

    /// The curve named `name` (`none`, `neutral`, `agx`, `aces`).
    #[must_use]
    pub fn from_name(name: &str) -> Option<ToneCurve> {
        Self::NAMES.iter().find(|(n, _)| *n == name).map(|&(_, c)| c)
    }

    /// The curve's name, as [`ToneCurve::from_name`] reads it.
    #[must_use]
    pub fn name(self) -> &'static str {
        Self::NAMES.iter().find(|(_, c)| *c == self).map_or("neutral", |&(n, _)| n)
    }

    /// Display-linear colour in [0, 1]³ for scene-linear `c` (already times
    /// the exposure); negative and NaN channels count as 0.
    #[must_use]
    pub fn apply(self, c: Vec3) -> Vec3 {
        let c = Vec3::new(finite(c.x), finite(c.y), finite(c.z));
        match self {
            ToneCurve::Clip => c.min(Vec3::ONE),
            ToneCurve::Neutral => neutral(c),
            ToneCurve::Agx => agx(c),
            ToneCurve::Aces => aces(c),
        }
    }
}

/// `v` within [0, 10⁶] (NaN: 0): far past white every curve is flat, and
/// their arithmetic stays finite.
fn finite(v: f32) -> f32 {
    if v > 0.0 {
        v.min(1e6)
    } else {
        0.0
    }
}

/// Khronos PBR Neutral (the reference formulation of the Khronos 3D
/// Commerce group's specification).
fn neutral(c: Vec3) -> Vec3 {
    const START: f32 = 0.8 - 0.04;
    const DESATURATION: f32 = 0.15;
    let x = c.min_element();
    let offset = if x < 0.08 { x - 6.25 * x * x } else { 0.04 };
    let c = c - offset;
    let peak = c.max_element();
    if peak < START {
        return c;
    }
    let d = 1.0 - START;
    let new_peak = 1.0 - d * d / (peak + d - START);
    let c = c * (new_peak / peak);
    let g = 1.0 - 1.0 / (DESATURATION * (peak - new_peak) + 1.0);
    c.lerp(Vec3::splat(new_peak), g).clamp(Vec3::ZERO, Vec3::ONE)
}

/// AgX: inset, log2 encoding over [−12.47, 4.03] stops, the default
/// contrast sigmoid, outset, the 2.2 display power back to linear.
fn agx(c: Vec3) -> Vec3 {
    const MIN_EV: f32 = -12.473_93;
    const MAX_EV: f32 = 4.026_069;
    let inset = Mat3::from_cols_array(&[
        0.842_479_06,
        0.042_328_242,
        0.042_375_655,
        0.078_433_6,
        0.878_468_6,
        0.078_433_6,
        0.079_223_745,
        0.079_166_13,
        0.879_143,
    ]);
    let outset = Mat3::from_cols_array(&[
        1.196_879,
        -0.052_896_85,
        -0.052_971_635,
        -0.098_020_88,
        1.151_903_1,
        -0.098_043_45,
        -0.099_029_74,
        -0.098_961_18,
        1.151_073_7,
    ]);
    let v = inset * c;
    let encoded =
        v.max(Vec3::splat(1e-10)).to_array().map(|x| (x.log2().clamp(MIN_EV, MAX_EV) - MIN_EV) / (MAX_EV - MIN_EV));
    let shaped = Vec3::from_array(encoded.map(agx_contrast));
    let display = (outset * shaped).clamp(Vec3::ZERO, Vec3::ONE);
    display.powf(2.2)
}

/// The AgX default-look sigmoid over the encoded range [0, 1], as a
/// sixth-degree polynomial.
fn agx_contrast(x: f32) -> f32 {
    let (x2, x4) = (x * x, x * x * x * x);
    15.5 * x4 * x2 - 40.14 * x4 * x + 31.96 * x4 - 6.868 * x2 * x + 0.4298 * x2 + 0.1191 * x - 0.002_32
}

/// Narkowicz's fit of the ACES reference rendering and output transforms.
fn aces(c: Vec3) -> Vec3 {
    let f = |x: f32| ((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14)).clamp(0.0, 1.0);
    Vec3::new(f(c.x), f(c.y), f(c.z))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grey(v: f32) -> Vec3 {
        Vec3::splat(v)
    }

    #[test]
    fn neutral_is_the_identity_less_its_offset_below_the_shoulder() {
        let c = ToneCurve::Neutral.apply(Vec3::new(0.5, 0.3, 0.2));
        assert!((c - Vec3::new(0.46, 0.26, 0.16)).abs().max_element() < 1e-6, "{c}");
        assert_eq!(ToneCurve::Neutral.apply(Vec3::ZERO), Vec3::ZERO);
        // The toe: x − 6.25 x² below 0.08 joins the constant 0.04 there.
        let at = |x: f32| ToneCurve::Neutral.apply(Vec3::new(0.6, 0.5, x)).z;
        assert!((at(0.079_99) - at(0.080_01)).abs() < 1e-4);
    }

    #[test]
    fn neutral_keeps_the_hue_of_what_it_compresses() {
        // Past the shoulder the channels scale together (hue kept) and only
        // far past white move towards grey.
        let c = ToneCurve::Neutral.apply(Vec3::new(2.0, 1.0, 0.5));
        assert!(c.max_element() < 1.0 && c.x > c.y && c.y > c.z, "{c}");
        let ratio = (c.x - c.y) / (c.x - c.z);
        let want = (2.0 - 1.0) / (2.0 - 0.5);
        assert!((ratio - want).abs() < 0.02, "hue moved: {ratio} vs {want}");
    }

    #[test]
    fn every_curve_is_monotone_on_grey_and_stays_in_the_unit_cube() {
        for (name, curve) in ToneCurve::NAMES {
            let mut last = -1.0;
            for i in 0..=4000 {
                let v = (i as f32 / 200.0).powi(2); // 0 .. 400
                let c = curve.apply(grey(v));
                assert!(c.min_element() >= 0.0 && c.max_element() <= 1.0, "{name}({v}) = {c}");
                assert!(c.x >= last - 1e-6, "{name} falls at {v}: {} after {last}", c.x);
                last = c.x;
            }
            assert!(curve.apply(grey(0.0)).max_element() < 1e-3, "{name}: black stays black");
            let c = curve.apply(Vec3::new(f32::NAN, -1.0, f32::INFINITY));
            assert!(c.is_finite(), "{name}: {c}");
        }
    }

    #[test]
    fn the_rolling_curves_do_not_clip_a_bright_highlight() {
        // Four times display white still has headroom: distinguishable from
        // eight times, and below the 8-bit top code's linear value. (ACES's
        // fit reaches white at 7.24.)
        for curve in [ToneCurve::Neutral, ToneCurve::Agx] {
            let (four, eight) = (curve.apply(grey(4.0)).x, curve.apply(grey(8.0)).x);
            assert!(four < eight && eight < 0.995, "{curve:?}: 4 → {four}, 8 → {eight}");
        }
        let (four, eight) = (ToneCurve::Aces.apply(grey(4.0)).x, ToneCurve::Aces.apply(grey(8.0)).x);
        assert!(four < 0.99 && eight == 1.0, "ACES: 4 → {four}, 8 → {eight}");
        assert_eq!(ToneCurve::Clip.apply(grey(4.0)), Vec3::ONE);
    }

    #[test]
    fn names_round_trip() {
        for (name, curve) in ToneCurve::NAMES {
            assert_eq!(ToneCurve::from_name(name), Some(curve));
        }
        assert_eq!(ToneCurve::from_name("filmic"), None);
    }
}
