//! Writing images: 8-bit sRGB PNG for looking at, linear float OpenEXR and PFM for
//! measuring. The format follows the file extension.

use std::path::Path;

use crate::error::{Error, Result};
use crate::resolve::LinearImage;

/// Writes `image` to `path` as `.png`, `.exr` or `.pfm`. `exposure` (a linear
/// multiplier) applies to PNG only: float formats keep the rendered values.
pub fn write_image(image: &LinearImage, path: &Path, exposure: f32) -> Result<()> {
    let fail = |message: String| Error::Output { path: path.to_path_buf(), message };
    let ext = path.extension().and_then(|e| e.to_str()).unwrap_or_default().to_ascii_lowercase();
    let (w, h) = (image.width(), image.height());
    match ext.as_str() {
        "png" => image::save_buffer(path, &image.to_srgb8(exposure), w, h, image::ColorType::Rgb8)
            .map_err(|e| fail(e.to_string())),
        "exr" => {
            let data: Vec<f32> = image.pixels().iter().flat_map(|p| p.to_array()).collect();
            let buf = image::Rgb32FImage::from_raw(w, h, data).ok_or_else(|| fail("buffer size".into()))?;
            buf.save(path).map_err(|e| fail(e.to_string()))
        }
        "pfm" => std::fs::write(path, pfm_bytes(image)).map_err(|e| fail(e.to_string())),
        _ => Err(fail(format!("unknown image format '.{ext}' (use .png, .exr or .pfm)"))),
    }
}

/// Portable float map: little-endian RGB floats, rows bottom to top.
#[must_use]
pub fn pfm_bytes(image: &LinearImage) -> Vec<u8> {
    let (w, h) = (image.width() as usize, image.height() as usize);
    let mut out = format!("PF\n{w} {h}\n-1.0\n").into_bytes();
    for row in image.pixels().chunks(w).rev() {
        out.extend(row.iter().flat_map(|p| p.to_array()).flat_map(f32::to_le_bytes));
    }
    out
}
