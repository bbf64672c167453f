//! `import()` and `surface()`: meshes and heightmaps from the files a model
//! names, read through the loader's [`super::Imports`] (relative to the
//! `.csg` file's folder), as closed meshes ([`crate::csg::ClosedMesh`]).
//!
//! A heightmap (`surface()`) is meshed as OpenSCAD meshes it: a `.dat` file's
//! rows of numbers, or a PNG image's pixels (their luma, 0 to 100, the
//! image's bottom row first), stand at y = 0, 1, 2, ... (columns at x = 0,
//! 1, ...), each cell cut into four triangles about its centre (at the
//! corners' mean height), walled down to a floor one unit below the lowest
//! point (or at 0, when that is lower); `center` moves the grid's middle to
//! the origin.

use glam::{Affine3A, DVec2, Vec3, Vec4};

use super::args::fragment_count;
use super::drawing::svg_region;
use super::dxf::{dxf_region, DxfOptions};
use super::flat::Region;
use super::syntax::CsgNode;
use super::{Builder, Built};
use crate::csg::ClosedMesh;
use crate::error::Result;
use crate::limits::Limit;

/// A file name's extension in lower case.
fn extension(file: &str) -> String {
    std::path::Path::new(file).extension().and_then(|e| e.to_str()).unwrap_or_default().to_ascii_lowercase()
}

/// File extensions `import()` reads as 2-D drawings.
const DRAWINGS: [&str; 2] = ["svg", "dxf"];

/// Whether an `import()` names a 2-D drawing (SVG, DXF) rather than a mesh.
#[must_use]
pub(super) fn drawing(node: &CsgNode) -> bool {
    match node.arg("file").map(|a| &a.value) {
        Some(super::syntax::CsgValue::Text(file)) => DRAWINGS.contains(&extension(file).as_str()),
        _ => false,
    }
}

impl Builder<'_> {
    /// `import()` of a mesh file: the closed mesh of its triangles.
    pub(super) fn import(&mut self, node: &CsgNode, m: Affine3A, color: Option<Vec4>) -> Result<Built> {
        let file = self.text_or(node, "file", "")?;
        let (positions, triangles) = self.imports.mesh(&file).map_err(|e| self.invalid(&node.span, e))?;
        self.check(node, Limit::Triangles, triangles.len() as u64, || format!("the triangles of {file}"))?;
        match ClosedMesh::new(positions, triangles) {
            Some(mesh) => {
                let open = mesh.open_edges();
                if open > 0 {
                    self.warn(
                        &node.span,
                        format!(
                            "{file} is not closed ({open} edges bound one side only): its inside is taken from the \
                             parity of its surfaces along each ray, which can be wrong near the gaps (OpenSCAD's \
                             render refuses it)"
                        ),
                    );
                }
                self.push_mesh(node, mesh, m, color)
            }
            None => {
                self.warn(&node.span, format!("{file} holds no triangle with an area: nothing is drawn"));
                Ok(Built::Empty)
            }
        }
    }

    /// `import()` of a 2-D drawing: an SVG file's region ([`svg_region`]) or
    /// a DXF file's ([`Builder::dxf`]).
    pub(super) fn drawing(&mut self, node: &CsgNode) -> Result<Region> {
        let file = self.text_or(node, "file", "")?;
        if extension(&file) == "dxf" {
            return self.dxf(node, &file);
        }
        let bytes = self.imports.bytes(&file).map_err(|e| self.invalid(&node.span, e))?;
        let (dpi, center) = (self.number_or(node, "dpi", 72.0)?, self.flag_or(node, "center", false)?);
        if !(dpi.is_finite() && dpi > 0.0) {
            return Err(self.invalid(&self.span_of(node, "dpi"), format!("`dpi` must be a positive number, not {dpi}")));
        }
        let region = svg_region(&bytes, dpi, center).map_err(|e| self.invalid(&node.span, format!("{file}: {e}")))?;
        let points = region.points().count() as u64;
        self.check(node, Limit::Points, points, || format!("the points of {file}"))?;
        Ok(region)
    }

    /// A DXF drawing's region ([`dxf_region`]): `import()`'s, or the profile
    /// of an extrusion that names a `file` (its `scale`'s x scales the
    /// drawing, as in OpenSCAD). Entities OpenSCAD does not draw either and
    /// values that do not read are warnings.
    pub(super) fn dxf(&mut self, node: &CsgNode, file: &str) -> Result<Region> {
        let bytes = self.imports.bytes(file).map_err(|e| self.invalid(&node.span, e))?;
        let layer = self.text_or(node, "layer", "")?;
        let origin = if node.arg("origin").is_some() { self.pair(node, "origin")? } else { DVec2::ZERO };
        let scale = match node.name.as_str() {
            "linear_extrude" if node.arg("scale").is_some() => self.pair(node, "scale")?.x,
            _ => self.number_or(node, "scale", 1.0)?,
        };
        if !scale.is_finite() {
            return Err(
                self.invalid(&self.span_of(node, "scale"), format!("`scale` must be a finite number, not {scale}"))
            );
        }
        // Refuses a `$fn` (or `$fa`) past the limit for any radius.
        self.fragments(node, f32::MAX)?;
        let spec = self.fragment_spec(node)?;
        let fragments = |r: f64| fragment_count(spec, r) as usize;
        let max_lines = self.limits.get(Limit::Points) as usize;
        let options = DxfOptions { layer: &layer, origin, scale, fragments: &fragments, max_lines };
        let drawing = dxf_region(&bytes, &options);
        self.check(node, Limit::Points, drawing.lines as u64, || format!("the line pieces of {file}"))?;
        for problem in &drawing.problems {
            self.warn(&node.span, format!("{file}, {problem}"));
        }
        for (entity, count) in &drawing.unsupported {
            let on = if layer.is_empty() { String::new() } else { format!(" on layer `{layer}`") };
            let (noun, verb) = if *count == 1 { ("entity", "is") } else { ("entities", "are") };
            let message = format!("{file}: {count} {entity} {noun}{on} {verb} not drawn (OpenSCAD draws none either)");
            self.warn(&node.span, message);
        }
        Ok(drawing.region)
    }

    /// `surface()`: a heightmap's closed mesh.
    pub(super) fn surface(&mut self, node: &CsgNode, m: Affine3A, color: Option<Vec4>) -> Result<Built> {
        let file = self.text_or(node, "file", "")?;
        let bytes = self.imports.bytes(&file).map_err(|e| self.invalid(&node.span, e))?;
        let rows = if bytes.starts_with(PNG_SIGNATURE) {
            let invert = self.flag_or(node, "invert", false)?;
            let (w, h) = image::ImageReader::with_format(std::io::Cursor::new(&bytes), image::ImageFormat::Png)
                .into_dimensions()
                .map_err(|e| self.invalid(&node.span, format!("{file}: not a PNG image: {e}")))?;
            self.check(node, Limit::Points, u64::from(w) * u64::from(h), || format!("the pixels of {file}"))?;
            image_heights(&bytes, invert).map_err(|e| self.invalid(&node.span, format!("{file}: {e}")))?
        } else {
            heights(&bytes).map_err(|e| self.invalid(&node.span, format!("{file}: {e}")))?
        };
        let cells = rows.len() as u64 * rows.first().map_or(0, Vec::len) as u64;
        self.check(node, Limit::Points, cells, || format!("the heights of {file}"))?;
        let center = self.flag_or(node, "center", false)?;
        match heightmap(&rows, center) {
            Some(mesh) => self.push_mesh(node, mesh, m, color),
            None => Ok(Built::Empty),
        }
    }
}

/// The outlines OpenSCAD 2021.01 draws of a 2-D drawing file's bytes (an
/// SVG at 72 per inch when `dxf` is false, a DXF on every layer at the
/// default `$fa` and `$fs` when true), each a closed contour, outer ones
/// counter-clockwise. `None` when the bytes are no drawing.
#[must_use]
pub fn drawing_outlines(bytes: &[u8], dxf: bool) -> Option<Vec<Vec<[f64; 2]>>> {
    let region = if dxf {
        let fragments = |r: f64| fragment_count([0.0, 12.0, 2.0], r) as usize;
        let options =
            DxfOptions { layer: "", origin: DVec2::ZERO, scale: 1.0, fragments: &fragments, max_lines: 1_000_000 };
        dxf_region(bytes, &options).region
    } else {
        svg_region(bytes, 72.0, false).ok()?
    };
    Some(region.contours().iter().map(|c| c.iter().map(|p| [p.x, p.y]).collect()).collect())
}

/// The eight bytes a PNG file starts with (OpenSCAD reads a heightmap as a
/// PNG image when it starts with them, as numbers otherwise).
const PNG_SIGNATURE: &[u8] = b"\x89PNG\r\n\x1a\n";

/// A PNG heightmap's rows, bottom row of the image first: each pixel's
/// luma (0.2126 R + 0.7152 G + 0.0722 B, alpha ignored) times 100 / 255;
/// `invert` takes 1 − luma instead, as OpenSCAD 2021.01 does (a pixel's
/// luma counts from 0 to 255 there, so an inverted map lies below 0).
fn image_heights(bytes: &[u8], invert: bool) -> std::result::Result<Vec<Vec<f32>>, String> {
    let image = image::load_from_memory_with_format(bytes, image::ImageFormat::Png)
        .map_err(|e| format!("not a PNG image: {e}"))?
        .to_rgba8();
    let height = |p: &image::Rgba<u8>| {
        let [r, g, b, _] = p.0.map(f64::from);
        let luma = 0.2126 * r + 0.7152 * g + 0.0722 * b;
        (100.0 / 255.0 * if invert { 1.0 - luma } else { luma }) as f32
    };
    Ok(image.rows().rev().map(|row| row.map(height).collect()).collect())
}

/// A `.dat` heightmap's rows of numbers (`#` starts a comment; every row as
/// long as the first).
fn heights(bytes: &[u8]) -> std::result::Result<Vec<Vec<f32>>, String> {
    let text =
        std::str::from_utf8(bytes).map_err(|_| "a heightmap must be text (rows of numbers) or a PNG".to_string())?;
    let mut rows: Vec<Vec<f32>> = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let line = line.split('#').next().unwrap_or("");
        if line.trim().is_empty() {
            continue;
        }
        let row: Vec<f32> = line
            .split(|c: char| c.is_whitespace() || c == ',')
            .filter(|w| !w.is_empty())
            .map(|w| w.parse::<f32>().ok().filter(|v| v.is_finite()))
            .collect::<Option<_>>()
            .ok_or_else(|| format!("line {}: a heightmap row holds finite numbers only", n + 1))?;
        if rows.first().is_some_and(|first| first.len() != row.len()) {
            return Err(format!("line {}: {} numbers, where the first row has {}", n + 1, row.len(), rows[0].len()));
        }
        rows.push(row);
    }
    Ok(rows)
}

/// The closed mesh of a heightmap (OpenSCAD's `surface()`).
fn heightmap(rows: &[Vec<f32>], center: bool) -> Option<ClosedMesh> {
    let (ny, nx) = (rows.len(), rows.first()?.len());
    if nx < 2 || ny < 2 {
        return None;
    }
    // One below the lowest height, or 0 when that is higher (OpenSCAD's).
    let floor = (rows.iter().flatten().copied().fold(f32::INFINITY, f32::min) - 1.0).min(0.0);
    let shift = if center { Vec3::new((nx - 1) as f32 / 2.0, (ny - 1) as f32 / 2.0, 0.0) } else { Vec3::ZERO };
    let mut positions = Vec::with_capacity(2 * nx * ny + (nx - 1) * (ny - 1));
    let at = |x: usize, y: usize| y * nx + x;
    for (y, row) in rows.iter().enumerate() {
        positions.extend(row.iter().enumerate().map(|(x, h)| Vec3::new(x as f32, y as f32, *h) - shift));
    }
    let below = positions.len();
    positions.extend((0..nx * ny).map(|i| Vec3::new((i % nx) as f32, (i / nx) as f32, floor) - shift));
    let mut triangles = Vec::new();
    for y in 0..ny - 1 {
        for x in 0..nx - 1 {
            let corners = [at(x, y), at(x + 1, y), at(x + 1, y + 1), at(x, y + 1)];
            let mean = corners.iter().map(|&c| positions[c].z).sum::<f32>() / 4.0;
            let centre = positions.len() as u32;
            positions.push(Vec3::new(x as f32 + 0.5, y as f32 + 0.5, mean) - shift);
            for k in 0..4 {
                triangles.push([corners[k] as u32, corners[(k + 1) % 4] as u32, centre]);
            }
            // The floor under the cell.
            let f = corners.map(|c| (below + c) as u32);
            triangles.extend([[f[0], f[2], f[1]], [f[0], f[3], f[2]]]);
        }
    }
    // Walls round the edge, top to floor.
    let edge: Vec<usize> = (0..nx - 1)
        .map(|x| at(x, 0))
        .chain((0..ny - 1).map(|y| at(nx - 1, y)))
        .chain((1..nx).rev().map(|x| at(x, ny - 1)))
        .chain((1..ny).rev().map(|y| at(0, y)))
        .collect();
    for k in 0..edge.len() {
        let (a, b) = (edge[k], edge[(k + 1) % edge.len()]);
        let (fa, fb) = ((below + a) as u32, (below + b) as u32);
        triangles.extend([[a as u32, fa, fb], [a as u32, fb, b as u32]]);
    }
    ClosedMesh::new(positions, triangles)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_png_heightmap_is_its_pixels_luma_bottom_row_first() {
        // The construct model's image: OpenSCAD's STL of surface() of it
        // (a tenth high) has its floor at 0 and its top at 9.0196 (the
        // ring's grey 230); inverted, its top at -1.1373 (the ground's grey
        // 30 at the corner).
        let png = std::fs::read(concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/openscad/parts/relief.png")).unwrap();
        let rows = image_heights(&png, false).unwrap();
        assert_eq!((rows.len(), rows[0].len()), (24, 32));
        let top = rows.iter().flatten().copied().fold(f32::MIN, f32::max);
        assert!((top - 90.196).abs() < 1e-3, "{top}");
        // The image's top row (y = 0 in the file) is the map's last row: its
        // pixel (0, 0) is (30, 30, 30), its bottom-left (30, 53, 30).
        let luma = |r: f32, g: f32, b: f32| (0.2126 * r + 0.7152 * g + 0.0722 * b) * 100.0 / 255.0;
        assert!(
            (rows[23][0] - luma(30.0, 30.0, 30.0)).abs() < 1e-4 && (rows[0][0] - luma(30.0, 53.0, 30.0)).abs() < 1e-4
        );
        let inverted = image_heights(&png, true).unwrap();
        assert!((inverted[23][0] - (100.0 / 255.0) * (1.0 - 30.0)).abs() < 1e-4);
        assert!(image_heights(b"\x89PNG\r\n\x1a\nnope", false).is_err());
    }

    #[test]
    fn a_heightmap_is_openscads_closed_surface() {
        let rows = heights(b"# a tiny heightmap\n1 2 3\n4 5 6\n7 8 20\n").unwrap();
        let mesh = heightmap(&rows, false).unwrap();
        // OpenSCAD's STL of surface(file = "h.dat"): 21 distinct points, the
        // floor at 0, a cell's centre at its corners' mean.
        assert_eq!(mesh.bounds(), (Vec3::ZERO, Vec3::new(2.0, 2.0, 20.0)));
        assert!(mesh.contains(Vec3::new(0.5, 0.5, 2.9)) && !mesh.contains(Vec3::new(0.5, 0.5, 3.1)));
        assert!(mesh.contains(Vec3::new(1.5, 1.5, 9.7)) && !mesh.contains(Vec3::new(1.5, 1.5, 9.8)));
        // Heights from 5 up: the floor stays at 0 (OpenSCAD's STL of it).
        let high = heightmap(&heights(b"5 6\n7 9\n").unwrap(), false).unwrap();
        assert_eq!(high.bounds(), (Vec3::ZERO, Vec3::new(1.0, 1.0, 9.0)));
        assert!(heights(b"1 2\n3\n").unwrap_err().contains("line 2"));
        assert!(heights(b"1 x\n").is_err());
    }
}
