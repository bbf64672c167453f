//! Tiles of a frame: `--region` and `--tile` pick the part of the image one
//! process renders; an `.exr` tile records where it belongs (its data window
//! inside the whole image's display window, as OpenEXR means them) and how
//! the whole is to be exposed; `kage merge` puts tiles back together and
//! refuses tiles that do not fit.

use std::path::{Path, PathBuf};

use exr::prelude::{
    AttributeValue, Encoding, Image, IntegerBounds, Layer, LayerAttributes, SpecificChannels, Text, Vec2, WritableImage,
};
use kage::image::{LinearImage, PixelRect, ToneCurve};
use kage::scene::{check_image_size, Exposure};

/// Parses `X0,Y0,X1,Y1` (pixels, the first column and row and one past the
/// last).
pub fn parse_region(s: &str) -> Result<PixelRect, String> {
    let n: Vec<u32> = s.split(',').map(|v| v.trim().parse::<u32>()).collect::<Result<_, _>>().map_err(|_| {
        format!("'{s}': a region is X0,Y0,X1,Y1 in whole pixels (the first column and row, one past the last)")
    })?;
    match n[..] {
        [x0, y0, x1, y1] if x0 < x1 && y0 < y1 => Ok(PixelRect { x0, y0, x1, y1 }),
        [_, _, _, _] => Err(format!("'{s}': the region is empty (X0 < X1 and Y0 < Y1)")),
        _ => Err(format!("'{s}': a region is four numbers, X0,Y0,X1,Y1")),
    }
}

/// Parses `I/N`: part `I` (from 0) of `N`.
pub fn parse_share(s: &str) -> Result<(u32, u32), String> {
    let bad = || format!("'{s}': give I/N, part I (from 0) of N, e.g. 3/16");
    let (i, n) = s.split_once('/').ok_or_else(bad)?;
    let (i, n) = (i.trim().parse::<u32>().map_err(|_| bad())?, n.trim().parse::<u32>().map_err(|_| bad())?);
    if n == 0 || i >= n {
        return Err(format!("'{s}': I must be from 0 to N - 1"));
    }
    Ok((i, n))
}

/// Attribute naming the exposure the whole image is to be shown with.
const EXPOSURE_ATTRIBUTE: &str = "kageExposure";
/// Attribute naming the tone curve of 8-bit output.
const TONE_ATTRIBUTE: &str = "kageTone";

/// Writes `part` (the pixels of `rect` of a `width` × `height` frame) as an
/// OpenEXR tile: 32-bit float RGB, its data window `rect`, its display
/// window the whole frame; `exposure` and `tone` go with it for the merged
/// image's 8-bit output.
pub fn write_tile(
    part: &LinearImage,
    rect: PixelRect,
    (width, height): (u32, u32),
    exposure: Exposure,
    tone: ToneCurve,
    path: &Path,
) -> Result<(), String> {
    let channels = SpecificChannels::rgb(|p: Vec2<usize>| {
        let c = part.get(p.0 as u32, p.1 as u32);
        (c.x, c.y, c.z)
    });
    let attributes = LayerAttributes { layer_position: Vec2(rect.x0 as i32, rect.y0 as i32), ..Default::default() };
    let size = (rect.width() as usize, rect.height() as usize);
    let mut image = Image::from_layer(Layer::new(size, attributes, Encoding::FAST_LOSSLESS, channels));
    image.attributes.display_window = IntegerBounds::new((0, 0), (width as usize, height as usize));
    let exposure = match exposure {
        Exposure::Auto => AttributeValue::Text(Text::from("auto")),
        Exposure::Stops(s) => AttributeValue::F32(s),
    };
    image.attributes.other.insert(Text::from(EXPOSURE_ATTRIBUTE), exposure);
    image.attributes.other.insert(Text::from(TONE_ATTRIBUTE), AttributeValue::Text(Text::from(tone.name())));
    image.write().to_file(path).map_err(|e| format!("cannot write {}: {e}", path.display()))
}

/// A tile read back: its pixels, where they go and in what.
pub struct Tile {
    /// The file.
    pub path: PathBuf,
    /// Its pixels.
    pub image: LinearImage,
    /// Where they go.
    pub rect: PixelRect,
    /// The whole image's size.
    pub whole: (u32, u32),
    /// The exposure recorded with it (none: 0 stops).
    pub exposure: Exposure,
    /// The tone curve recorded with it (none: the default).
    pub tone: ToneCurve,
}

/// Reads an OpenEXR tile (any RGB OpenEXR file: one without a data window
/// offset is a tile covering its whole display window).
pub fn read_tile(path: &Path) -> Result<Tile, String> {
    use exr::prelude::{ReadChannels, ReadLayers};
    let read = exr::prelude::read()
        .no_deep_data()
        .largest_resolution_level()
        .rgb_channels(
            // A size kage would not render is not allocated: the image stays
            // empty, and is refused below.
            |size, _| match check_image_size(size.0 as u64, size.1 as u64) {
                Ok(()) => LinearImage::new(size.0 as u32, size.1 as u32),
                Err(_) => LinearImage::default(),
            },
            |image: &mut LinearImage, p: Vec2<usize>, (r, g, b): (f32, f32, f32)| {
                let w = image.width() as usize;
                if let Some(px) = image.pixels_mut().get_mut(p.1 * w + p.0) {
                    *px = glam::Vec3::new(r, g, b);
                }
            },
        )
        .first_valid_layer()
        .all_attributes()
        .from_file(path)
        .map_err(|e| format!("{}: not an RGB OpenEXR tile: {e}", path.display()))?;
    let display = read.attributes.display_window;
    let at = read.layer_data.attributes.layer_position;
    let data = read.layer_data.channel_data.pixels;
    let too_large = |what: &str, w: usize, h: usize| {
        check_image_size(w as u64, h as u64).map_err(|e| format!("{}: its {what}: {e}", path.display()))
    };
    too_large("data window", read.layer_data.size.0, read.layer_data.size.1)?;
    too_large("display window", display.size.0, display.size.1)?;
    let (dx, dy) = (display.position.0, display.position.1);
    if dx != 0 || dy != 0 {
        return Err(format!("{}: its display window starts at ({dx}, {dy}), not (0, 0)", path.display()));
    }
    let (x0, y0) = (at.0, at.1);
    if x0 < 0 || y0 < 0 {
        return Err(format!("{}: its data window starts outside the image, at ({x0}, {y0})", path.display()));
    }
    let rect = PixelRect { x0: x0 as u32, y0: y0 as u32, x1: x0 as u32 + data.width(), y1: y0 as u32 + data.height() };
    let whole = (display.size.0 as u32, display.size.1 as u32);
    // Written with the image's attributes; a reader may hand them back with
    // the layer's (one header holds both).
    let attribute = |name: &str| {
        let name = Text::from(name);
        read.attributes.other.get(&name).or_else(|| read.layer_data.attributes.other.get(&name))
    };
    let exposure = match attribute(EXPOSURE_ATTRIBUTE) {
        Some(AttributeValue::Text(t)) if t.eq("auto") => Exposure::Auto,
        Some(&AttributeValue::F32(s)) => Exposure::Stops(s),
        _ => Exposure::default(),
    };
    let tone = match attribute(TONE_ATTRIBUTE) {
        Some(AttributeValue::Text(t)) => ToneCurve::from_name(&t.to_string()).unwrap_or_default(),
        _ => ToneCurve::default(),
    };
    Ok(Tile { path: path.to_path_buf(), image: data, rect, whole, exposure, tone })
}

/// Puts `tiles` together: they must share one whole-image size and cover
/// it exactly once.
pub fn merge(tiles: &[Tile]) -> Result<LinearImage, String> {
    let first = tiles.first().ok_or("no tiles to merge")?;
    let (w, h) = first.whole;
    let mut owner: Vec<u32> = vec![u32::MAX; w as usize * h as usize];
    let mut out = LinearImage::new(w, h);
    for (k, t) in tiles.iter().enumerate() {
        if t.whole != first.whole {
            return Err(format!(
                "{} belongs to a {}x{} image, {} to a {w}x{h} one",
                t.path.display(),
                t.whole.0,
                t.whole.1,
                first.path.display()
            ));
        }
        if !t.rect.fits(w, h) {
            return Err(format!("{}: its pixels {:?} lie outside the {w}x{h} image", t.path.display(), t.rect));
        }
        for y in t.rect.y0..t.rect.y1 {
            for x in t.rect.x0..t.rect.x1 {
                let o = &mut owner[(y * w + x) as usize];
                if *o != u32::MAX {
                    let other = &tiles[*o as usize].path;
                    return Err(format!("{} and {} overlap at pixel ({x}, {y})", other.display(), t.path.display()));
                }
                *o = k as u32;
            }
        }
        out.paste(&t.image, t.rect.x0, t.rect.y0);
    }
    if let Some(i) = owner.iter().position(|&o| o == u32::MAX) {
        let (x, y) = (i as u32 % w, i as u32 / w);
        let missing = owner.iter().filter(|&&o| o == u32::MAX).count();
        return Err(format!(
            "the tiles leave {missing} pixels of the {w}x{h} image uncovered, the first at ({x}, {y})"
        ));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tile_file(name: &str, rect: PixelRect, whole: (u32, u32)) -> PathBuf {
        let path = std::env::temp_dir().join(format!("kage-tile-{}-{name}.exr", std::process::id()));
        let part = LinearImage::new(rect.width(), rect.height());
        write_tile(&part, rect, whole, Exposure::Stops(1.5), ToneCurve::Agx, &path).unwrap();
        path
    }

    #[test]
    fn a_tile_reads_back_where_it_goes_and_how_it_is_exposed() {
        let rect = PixelRect { x0: 3, y0: 5, x1: 10, y1: 9 };
        let path = tile_file("back", rect, (20, 12));
        let t = read_tile(&path).unwrap();
        assert_eq!((t.rect, t.whole, t.exposure, t.tone), (rect, (20, 12), Exposure::Stops(1.5), ToneCurve::Agx));
        std::fs::remove_file(path).ok();
    }

    #[test]
    fn a_tile_of_an_image_too_large_to_render_is_refused_before_allocating() {
        let path = tile_file("huge", PixelRect { x0: 0, y0: 0, x1: 2, y1: 2 }, (100_000, 100_000));
        let e = read_tile(&path).err().unwrap_or_default();
        assert!(e.contains("display window"), "{e}");
        std::fs::remove_file(path).ok();
    }
}
