//! Writing and reading images: 8-bit sRGB PNG and JPEG for looking at (through
//! a tone curve), linear float OpenEXR and PFM for measuring. The format follows
//! the file extension.

use std::path::Path;

use crate::error::{Error, Result};
use crate::image::{srgb_to_linear, LinearImage, ToneCurve};

/// JPEG quality of `.jpg` output: no visible blocking on smooth shading.
const JPEG_QUALITY: u8 = 92;

/// Writes `image` to `path` as `.png`, `.jpg`/`.jpeg`, `.exr` or `.pfm`.
/// `exposure` (a linear multiplier) and the tone curve `tone` apply to the
/// 8-bit formats only: float formats keep the rendered values.
///
/// # Errors
///
/// [`Error::Output`] for an unknown extension or when the file cannot be
/// written.
pub fn write_image(image: &LinearImage, path: &Path, exposure: f32, tone: ToneCurve) -> Result<()> {
    let fail = |message: String| Error::Output { path: path.to_path_buf(), message };
    let ext = path.extension().and_then(|e| e.to_str()).unwrap_or_default().to_ascii_lowercase();
    let (w, h) = (image.width(), image.height());
    match ext.as_str() {
        "png" => ::image::save_buffer(path, &image.to_srgb8_toned(exposure, tone), w, h, ::image::ColorType::Rgb8)
            .map_err(|e| fail(e.to_string())),
        "jpg" | "jpeg" => {
            let file = std::fs::File::create(path).map_err(|e| fail(e.to_string()))?;
            let mut out = std::io::BufWriter::new(file);
            let mut encoder = ::image::codecs::jpeg::JpegEncoder::new_with_quality(&mut out, JPEG_QUALITY);
            let pixels = image.to_srgb8_toned(exposure, tone);
            encoder.encode(&pixels, w, h, ::image::ExtendedColorType::Rgb8).map_err(|e| fail(e.to_string()))
        }
        "exr" => {
            let data: Vec<f32> = image.pixels().iter().flat_map(|p| p.to_array()).collect();
            let buf = ::image::Rgb32FImage::from_raw(w, h, data).ok_or_else(|| fail("buffer size".into()))?;
            buf.save(path).map_err(|e| fail(e.to_string()))
        }
        "pfm" => std::fs::write(path, pfm_bytes(image)).map_err(|e| fail(e.to_string())),
        _ => Err(fail(format!("unknown image format '.{ext}' (use .png, .jpg, .exr or .pfm)"))),
    }
}

/// Checks, before any work, that [`write_image`] can write `path`: a known
/// image extension, and a folder that exists.
///
/// # Errors
///
/// [`Error::Output`] naming what is wrong.
pub fn check_output(path: &Path) -> Result<()> {
    let fail = |message: String| Error::Output { path: path.to_path_buf(), message };
    let ext = path.extension().and_then(|e| e.to_str()).unwrap_or_default().to_ascii_lowercase();
    if !matches!(ext.as_str(), "png" | "jpg" | "jpeg" | "exr" | "pfm") {
        return Err(fail(format!("unknown image format '.{ext}' (use .png, .jpg, .exr or .pfm)")));
    }
    let folder = path.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
    if !folder.is_dir() {
        return Err(fail(format!("the folder {} does not exist", folder.display())));
    }
    Ok(())
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

/// Reads an image as linear RGB: `.exr` and `.pfm` as stored, 8-bit formats
/// (`.png`, `.jpg`) decoded from sRGB.
///
/// # Errors
///
/// [`Error::Read`] when the file cannot be read, [`Error::ImageRead`] when it
/// does not decode.
pub fn read_image(path: &Path) -> Result<LinearImage> {
    let fail = |message: String| Error::ImageRead { path: path.to_path_buf(), message };
    let ext = path.extension().and_then(|e| e.to_str()).unwrap_or_default().to_ascii_lowercase();
    if ext == "pfm" {
        let bytes = std::fs::read(path).map_err(|source| Error::Read { path: path.to_path_buf(), source })?;
        return parse_pfm(&bytes).map_err(fail);
    }
    let img = ::image::open(path).map_err(|e| fail(e.to_string()))?;
    let linear = ext == "exr" || ext == "hdr";
    let rgb = img.into_rgb32f();
    let mut out = LinearImage::new(rgb.width(), rgb.height());
    for (o, p) in out.pixels_mut().iter_mut().zip(rgb.pixels()) {
        let c = glam::Vec3::new(p[0], p[1], p[2]);
        *o = if linear { c } else { c.map(srgb_to_linear) };
    }
    Ok(out)
}

/// Parses a colour PFM (`PF`), either byte order.
fn parse_pfm(bytes: &[u8]) -> std::result::Result<LinearImage, String> {
    let mut fields = Vec::new();
    let mut at = 0;
    while fields.len() < 4 {
        while at < bytes.len() && bytes[at].is_ascii_whitespace() {
            at += 1;
        }
        let start = at;
        while at < bytes.len() && !bytes[at].is_ascii_whitespace() {
            at += 1;
        }
        if start == at {
            return Err("truncated PFM header".into());
        }
        fields.push(String::from_utf8_lossy(&bytes[start..at]).into_owned());
    }
    at += 1; // the single whitespace after the scale
    if fields[0] != "PF" {
        return Err(format!("not a colour PFM (magic '{}')", fields[0]));
    }
    let num = |s: &str| s.parse::<u32>().map_err(|_| format!("bad PFM size '{s}'"));
    let (w, h) = (num(&fields[1])?, num(&fields[2])?);
    crate::scene::check_image_size(w as u64, h as u64).map_err(|e| e.to_string())?;
    let scale: f32 = fields[3].parse().map_err(|_| format!("bad PFM scale '{}'", fields[3]))?;
    let data = bytes.get(at..).unwrap_or_default();
    let need = w as usize * h as usize * 12;
    if data.len() < need {
        return Err(format!("PFM holds {} bytes of pixels, {need} needed", data.len()));
    }
    let word = |c: &[u8]| {
        let b = [c[0], c[1], c[2], c[3]];
        if scale < 0.0 {
            f32::from_le_bytes(b)
        } else {
            f32::from_be_bytes(b)
        }
    };
    let mut out = LinearImage::new(w, h);
    for (row, chunk) in data[..need].chunks_exact(w as usize * 12).enumerate() {
        let y = h as usize - 1 - row;
        for (x, px) in chunk.chunks_exact(12).enumerate() {
            out.pixels_mut()[y * w as usize + x] = glam::Vec3::new(word(&px[0..4]), word(&px[4..8]), word(&px[8..12]));
        }
    }
    Ok(out)
}
