//! Measuring images against each other: how far a technique's render is from the
//! reference (ray traced, supersampled) render of the same scene.
//!
//! Errors are over linear RGB values, every channel of every pixel: RMSE, PSNR
//! (peak 1.0), the largest channel error, and the share of pixels whose largest
//! channel error exceeds a threshold. For masks (shadow / lit images) the share of
//! pixels classified differently at a level. A false-colour image shows where the
//! differences are.

use glam::Vec3;

use crate::error::{Error, Result};
use crate::image::LinearImage;

/// How two images differ.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Comparison {
    /// Root mean square error over all channels.
    pub rmse: f64,
    /// Peak signal-to-noise ratio in dB for a peak of 1.0 (infinite when equal).
    pub psnr: f64,
    /// Largest absolute channel difference.
    pub max_error: f64,
    /// Share (0–1) of pixels whose largest channel difference exceeds the threshold.
    pub share_over: f64,
    /// The threshold used for `share_over`.
    pub threshold: f64,
}

/// Compares `a` with reference `b` (same size).
///
/// # Errors
///
/// [`Error::SizeMismatch`] when the images differ in size.
pub fn compare(a: &LinearImage, b: &LinearImage, threshold: f32) -> Result<Comparison> {
    same_size(a, b)?;
    let (mut sum, mut max, mut over) = (0.0f64, 0.0f64, 0usize);
    for (p, q) in a.pixels().iter().zip(b.pixels()) {
        let d = (*p - *q).abs();
        sum += d.as_dvec3().length_squared();
        max = max.max(d.max_element() as f64);
        over += usize::from(d.max_element() > threshold);
    }
    let n = a.pixels().len().max(1) as f64;
    let rmse = (sum / (3.0 * n)).sqrt();
    let psnr = if rmse == 0.0 { f64::INFINITY } else { -20.0 * rmse.log10() };
    Ok(Comparison { rmse, psnr, max_error: max, share_over: over as f64 / n, threshold: threshold as f64 })
}

/// Share (0–1) of pixels that one image puts above `level` and the other not,
/// judged on each pixel's mean channel value.
///
/// # Errors
///
/// [`Error::SizeMismatch`] when the images differ in size.
pub fn mask_disagreement(a: &LinearImage, b: &LinearImage, level: f32) -> Result<f64> {
    same_size(a, b)?;
    let above = |p: &Vec3| p.element_sum() / 3.0 > level;
    let differ = a.pixels().iter().zip(b.pixels()).filter(|(p, q)| above(p) != above(q)).count();
    Ok(differ as f64 / a.pixels().len().max(1) as f64)
}

/// A false-colour picture of |a − b|: black where equal, then blue, green, yellow
/// and red as the largest channel difference grows to `full_scale` and beyond.
///
/// # Errors
///
/// [`Error::SizeMismatch`] when the images differ in size.
pub fn difference_image(a: &LinearImage, b: &LinearImage, full_scale: f32) -> Result<LinearImage> {
    same_size(a, b)?;
    let mut out = LinearImage::new(a.width(), a.height());
    for ((o, p), q) in out.pixels_mut().iter_mut().zip(a.pixels()).zip(b.pixels()) {
        *o = ramp((*p - *q).abs().max_element() / full_scale.max(f32::MIN_POSITIVE));
    }
    Ok(out)
}

/// Colour ramp over [0, 1]: black, blue, green, yellow, red.
fn ramp(x: f32) -> Vec3 {
    const STOPS: [Vec3; 5] = [
        Vec3::ZERO,
        Vec3::new(0.0, 0.0, 1.0),
        Vec3::new(0.0, 1.0, 0.0),
        Vec3::new(1.0, 1.0, 0.0),
        Vec3::new(1.0, 0.0, 0.0),
    ];
    let x = x.clamp(0.0, 1.0) * (STOPS.len() - 1) as f32;
    let i = (x as usize).min(STOPS.len() - 2);
    STOPS[i].lerp(STOPS[i + 1], x - i as f32)
}

fn same_size(a: &LinearImage, b: &LinearImage) -> Result<()> {
    let (sa, sb) = ((a.width(), a.height()), (b.width(), b.height()));
    if sa == sb {
        Ok(())
    } else {
        Err(Error::SizeMismatch { a: sa, b: sb })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn image(values: &[f32]) -> LinearImage {
        let mut img = LinearImage::new(values.len() as u32, 1);
        img.pixels_mut().iter_mut().zip(values).for_each(|(p, v)| *p = Vec3::splat(*v));
        img
    }

    #[test]
    fn known_differences() {
        let a = image(&[0.0, 0.5, 1.0, 0.25]);
        let same = compare(&a, &a, 0.01).unwrap();
        assert_eq!((same.rmse, same.max_error, same.share_over), (0.0, 0.0, 0.0));
        assert!(same.psnr.is_infinite());
        let b = image(&[0.0, 0.5, 0.5, 0.25]);
        let c = compare(&a, &b, 0.1).unwrap();
        // One pixel of four off by 0.5 in all three channels.
        assert!((c.rmse - (0.25f64 / 4.0).sqrt()).abs() < 1e-9, "{}", c.rmse);
        assert!((c.psnr - -20.0 * c.rmse.log10()).abs() < 1e-9);
        assert_eq!((c.max_error, c.share_over), (0.5, 0.25));
        assert_eq!(mask_disagreement(&a, &b, 0.75).unwrap(), 0.25);
        assert_eq!(mask_disagreement(&a, &b, 0.4).unwrap(), 0.0);
        let d = difference_image(&a, &b, 0.5).unwrap();
        assert_eq!(d.get(2, 0), Vec3::new(1.0, 0.0, 0.0));
        assert_eq!(d.get(0, 0), Vec3::ZERO);
        assert!(compare(&a, &image(&[0.0]), 0.1).unwrap_err().to_string().contains("differ in size"));
    }
}
