//! `import()` of an SVG drawing, read as OpenSCAD 2021.01 reads it: `usvg`
//! resolves the document (styles, groups and their transforms, `use`,
//! shapes turned into paths), and OpenSCAD's own rules, measured on its
//! output, turn the paths into a region in millimetres:
//!
//! - A closed sub-path (`Z`, `rect`, `circle`, `ellipse`, `polygon`) is filled,
//!   whatever its `fill` and `stroke` say; the closed sub-paths of one path
//!   make holes by the even-odd rule.
//! - An open sub-path (`line`, `polyline`, a path without `Z`) is stroked:
//!   its `stroke-width` (1 when it has no stroke), square ends, mitred corners.
//! - Curves are cut into 20 straight pieces each.
//! - Units: the document's `width` and `height` in millimetres (`px` at 96 per
//!   inch, a bare number at the node's `dpi`, 72 unless given). Without a
//!   `viewBox` a user unit is a millimetre; with one, the `viewBox` is fitted
//!   into `width` × `height`. y turns upwards about the document's height: a
//!   point at y is at `height − y`. OpenSCAD also moves the drawing down by
//!   twice the `viewBox`'s top (kept here, as the mesh it exports has it).
//! - `center = true` moves the drawing's bounding box to the origin; `scale`
//!   and `origin` (DXF's) do nothing to an SVG.
//! - Text is not drawn (OpenSCAD 2021.01 draws none either).

use glam::{DAffine2, DVec2};
use usvg::tiny_skia_path::{PathSegment, Point};

use super::flat::Region;

/// Straight pieces per Bézier curve (OpenSCAD's).
const CURVE_STEPS: usize = 20;

/// Millimetres per inch.
const INCH_MM: f64 = 25.4;

/// The drawing of SVG `bytes` (plain or gzipped) as a region in
/// millimetres, a bare number in the document's size read at `dpi`.
///
/// # Errors
///
/// A message when the bytes are no SVG document.
pub(crate) fn svg_region(bytes: &[u8], dpi: f64, center: bool) -> Result<Region, String> {
    let unzipped;
    let bytes = if bytes.starts_with(&[0x1f, 0x8b]) {
        unzipped = usvg::decompress_svgz(bytes).map_err(|e| format!("not a gzipped SVG: {e}"))?;
        &unzipped[..]
    } else {
        bytes
    };
    let text = std::str::from_utf8(bytes).map_err(|_| "an SVG file must be UTF-8 text".to_string())?;
    let page = Page::read(text, dpi)?;
    let tree = usvg::Tree::from_str(text, &usvg::Options::default()).map_err(|e| format!("not an SVG drawing: {e}"))?;
    let to_mm = page.map(tree.size().width().into());
    let mut regions = Vec::new();
    gather(tree.root(), &to_mm, &mut regions)?;
    let region = Region::union(&regions);
    Ok(match (center, region.bounds()) {
        (true, Some((lo, hi))) => region.transformed(&DAffine2::from_translation(-(lo + hi) * 0.5)),
        _ => region,
    })
}

/// What OpenSCAD reads off the root `<svg>`: its size in millimetres and its
/// `viewBox`.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Page {
    width_mm: Option<f64>,
    height_mm: Option<f64>,
    /// `min-x`, `min-y`, `width`, `height`.
    view_box: Option<[f64; 4]>,
    dpi: f64,
}

impl Page {
    fn read(text: &str, dpi: f64) -> Result<Page, String> {
        let doc = roxmltree::Document::parse(text).map_err(|e| format!("not an SVG drawing: {e}"))?;
        if let Some(v) =
            doc.descendants().flat_map(|n| geometry_numbers(&n)).find(|v| v.is_nan() || v.abs() > LARGEST_NUMBER)
        {
            return Err(format!("a shape's number {v:e} lies past {LARGEST_NUMBER:e} (the SVG reader's limit)"));
        }
        let root = doc.root_element();
        let length = |name: &str| root.attribute(name).and_then(|v| millimetres(v, dpi));
        let view_box = root.attribute("viewBox").and_then(|v| {
            let n: Vec<f64> = v.split([' ', ',']).filter(|s| !s.is_empty()).filter_map(|s| s.parse().ok()).collect();
            (n.len() == 4 && n[2] > 0.0 && n[3] > 0.0).then(|| [n[0], n[1], n[2], n[3]])
        });
        Ok(Page { width_mm: length("width"), height_mm: length("height"), view_box, dpi })
    }

    /// The map from usvg's canvas (`canvas_width` wide) to OpenSCAD's
    /// millimetres, y up.
    fn map(&self, canvas_width: f64) -> DAffine2 {
        let bare = INCH_MM / self.dpi;
        let (factor, shift, height) = match self.view_box {
            Some([_, min_y, w, h]) => {
                let (width_mm, height_mm) = (self.width_mm.unwrap_or(w * bare), self.height_mm.unwrap_or(h * bare));
                let per_unit = (width_mm / w).min(height_mm / h);
                (width_mm / canvas_width, 2.0 * min_y * per_unit, height_mm)
            }
            None => (1.0, 0.0, self.height_mm.unwrap_or(0.0)),
        };
        DAffine2::from_cols_array(&[factor, 0.0, 0.0, -factor, 0.0, height - shift])
    }
}

/// The largest number a shape's geometry may hold: curves past it would be
/// cut into more pieces than memory holds.
const LARGEST_NUMBER: f64 = 1e9;

/// Attributes that place a shape's geometry.
const GEOMETRY: [&str; 15] =
    ["d", "points", "x", "y", "x1", "y1", "x2", "y2", "cx", "cy", "r", "rx", "ry", "width", "height"];

/// Every number in an element's geometry attributes.
fn geometry_numbers(node: &roxmltree::Node) -> Vec<f64> {
    let mut out = Vec::new();
    for value in GEOMETRY.iter().filter_map(|name| node.attribute(*name)) {
        let bytes = value.as_bytes();
        let mut i = 0;
        while i < bytes.len() {
            let start = i;
            let digit = |i: usize| bytes.get(i).is_some_and(u8::is_ascii_digit);
            if matches!(bytes[i], b'+' | b'-') {
                i += 1;
            }
            while digit(i) {
                i += 1;
            }
            if bytes.get(i) == Some(&b'.') {
                i += 1;
                while digit(i) {
                    i += 1;
                }
            }
            if i > start && matches!(bytes.get(i), Some(b'e' | b'E')) {
                let mut j = i + 1;
                if matches!(bytes.get(j), Some(b'+' | b'-')) {
                    j += 1;
                }
                if digit(j) {
                    i = j;
                    while digit(i) {
                        i += 1;
                    }
                }
            }
            match std::str::from_utf8(&bytes[start..i]).ok().and_then(|t| t.parse::<f64>().ok()).ok_or(()) {
                Ok(v) => out.push(v),
                Err(_) => i = start + 1,
            }
        }
    }
    out
}

/// An SVG length in millimetres, a bare number at `dpi` (`None` for a
/// percentage or what does not parse).
fn millimetres(value: &str, dpi: f64) -> Option<f64> {
    let value = value.trim();
    let split = value.find(|c: char| c.is_ascii_alphabetic() || c == '%').unwrap_or(value.len());
    let (number, unit) = value.split_at(split);
    let n: f64 = number.trim().parse().ok()?;
    let per = match unit.trim() {
        "" => INCH_MM / dpi,
        "px" => INCH_MM / 96.0,
        "pt" => INCH_MM / 72.0,
        "pc" => INCH_MM / 6.0,
        "mm" => 1.0,
        "cm" => 10.0,
        "in" => INCH_MM,
        _ => return None,
    };
    Some(n * per)
}

/// The farthest a drawing's point may lie from the origin, in millimetres.
const FARTHEST: f64 = 1e12;

/// Each path under `group` as a region in millimetres (`to_mm` after the
/// path's own transform).
///
/// # Errors
///
/// A message when a point lies past [`FARTHEST`] (or is not finite).
fn gather(group: &usvg::Group, to_mm: &DAffine2, out: &mut Vec<Region>) -> Result<(), String> {
    for node in group.children() {
        match node {
            usvg::Node::Group(g) => gather(g, to_mm, out)?,
            usvg::Node::Path(path) => {
                let t = path.abs_transform();
                let own = DAffine2::from_cols_array(&[t.sx, t.ky, t.kx, t.sy, t.tx, t.ty].map(f64::from));
                let m = *to_mm * own;
                let (closed, open) = sub_paths(path.data(), &m);
                let far =
                    closed.iter().chain(&open).flatten().find(|p| !p.is_finite() || p.abs().max_element() > FARTHEST);
                if let Some(p) = far {
                    return Err(format!("a point at ({}, {}) mm lies beyond {FARTHEST:e} mm", p.x, p.y));
                }
                out.push(Region::even_odd(&closed));
                if !open.is_empty() {
                    let width = path.stroke().map_or(1.0, |s| f64::from(s.width().get()));
                    // The width grows with the path's scale (the root of the
                    // map's area factor).
                    let width = width * m.matrix2.determinant().abs().sqrt();
                    if width.is_nan() || width > FARTHEST {
                        return Err(format!("a stroke {width:e} mm wide is wider than {FARTHEST:e} mm"));
                    }
                    out.push(Region::stroked(&open, width));
                }
            }
            usvg::Node::Image(_) | usvg::Node::Text(_) => {}
        }
    }
    Ok(())
}

/// A path's closed and open sub-paths, placed by `m`, curves cut into
/// [`CURVE_STEPS`] pieces.
fn sub_paths(data: &usvg::tiny_skia_path::Path, m: &DAffine2) -> (Vec<Vec<DVec2>>, Vec<Vec<DVec2>>) {
    let at = |p: Point| m.transform_point2(DVec2::new(p.x.into(), p.y.into()));
    let (mut closed, mut open) = (Vec::new(), Vec::new());
    let mut current: Vec<DVec2> = Vec::new();
    let finish = |current: &mut Vec<DVec2>, open: &mut Vec<Vec<DVec2>>| {
        if current.len() >= 2 {
            open.push(std::mem::take(current));
        }
        current.clear();
    };
    for segment in data.segments() {
        match segment {
            PathSegment::MoveTo(p) => {
                finish(&mut current, &mut open);
                current.push(at(p));
            }
            PathSegment::LineTo(p) => current.push(at(p)),
            PathSegment::QuadTo(c, p) => {
                let p0 = current.last().copied().unwrap_or_default();
                let (c, p) = (at(c), at(p));
                current.extend((1..=CURVE_STEPS).map(|k| {
                    let t = k as f64 / CURVE_STEPS as f64;
                    p0 * (1.0 - t) * (1.0 - t) + c * 2.0 * t * (1.0 - t) + p * t * t
                }));
            }
            PathSegment::CubicTo(c1, c2, p) => {
                let p0 = current.last().copied().unwrap_or_default();
                let (c1, c2, p) = (at(c1), at(c2), at(p));
                current.extend((1..=CURVE_STEPS).map(|k| {
                    let t = k as f64 / CURVE_STEPS as f64;
                    let s = 1.0 - t;
                    p0 * s * s * s + c1 * 3.0 * s * s * t + c2 * 3.0 * s * t * t + p * t * t * t
                }));
            }
            PathSegment::Close => {
                if current.len() >= 3 {
                    closed.push(std::mem::take(&mut current));
                }
                current.clear();
            }
        }
    }
    finish(&mut current, &mut open);
    (closed, open)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn region(svg: &str) -> Region {
        svg_region(svg.as_bytes(), 72.0, false).unwrap()
    }

    #[test]
    fn units_and_the_view_box_place_the_drawing_as_openscad_does() {
        // Each case's bounds as OpenSCAD 2021.01 exports them (its STL).
        let rect = r#"<rect x="10" y="10" width="40" height="20"/>"#;
        let cases = [
            // A bare size at 72 per inch; user units are millimetres.
            (format!(r#"<svg xmlns="http://www.w3.org/2000/svg" width="200" height="100">{rect}</svg>"#), [10.0, 5.278, 50.0, 25.278]),
            // px at 96 per inch.
            (format!(r#"<svg xmlns="http://www.w3.org/2000/svg" width="200px" height="100px">{rect}</svg>"#), [10.0, -3.542, 50.0, 16.458]),
            // A viewBox fitted into millimetres.
            (format!(r#"<svg xmlns="http://www.w3.org/2000/svg" width="100mm" height="50mm" viewBox="0 0 200 100">{rect}</svg>"#), [5.0, 35.0, 25.0, 45.0]),
            // A viewBox alone: its units at 72 per inch.
            (format!(r#"<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 200 100">{rect}</svg>"#), [3.528, 24.694, 17.639, 31.75]),
            // A viewBox that does not start at 0.
            (r#"<svg xmlns="http://www.w3.org/2000/svg" width="100mm" height="100mm" viewBox="10 20 200 200"><rect x="10" y="20" width="40" height="20"/></svg>"#.to_string(), [0.0, 70.0, 20.0, 80.0]),
            // A transformed group.
            (r#"<svg xmlns="http://www.w3.org/2000/svg" width="100mm" height="100mm"><g transform="rotate(90) scale(2)"><rect x="0" y="0" width="10" height="5"/></g></svg>"#.to_string(), [-10.0, 80.0, 0.0, 100.0]),
            // An open path is stroked: a line of width 1 with square ends.
            (r#"<svg xmlns="http://www.w3.org/2000/svg" width="100mm" height="100mm"><line x1="0" y1="0" x2="50" y2="0"/></svg>"#.to_string(), [-0.5, 99.5, 50.5, 100.5]),
            // A closed one is filled, though it says fill="none".
            (r#"<svg xmlns="http://www.w3.org/2000/svg" width="100mm" height="100mm"><path d="M 10 10 L 50 10 L 30 40 Z" fill="none" stroke="black" stroke-width="4"/></svg>"#.to_string(), [10.0, 60.0, 50.0, 90.0]),
        ];
        for (svg, [x0, y0, x1, y1]) in cases {
            let (lo, hi) = region(&svg).bounds().unwrap();
            let got = [lo.x, lo.y, hi.x, hi.y];
            assert!(got.iter().zip([x0, y0, x1, y1]).all(|(g, w)| (g - w).abs() < 2e-3), "{svg}: {got:?}");
        }
    }

    #[test]
    fn holes_go_by_the_even_odd_rule_and_curves_are_cut_alike() {
        // A square with a square hole drawn the same way round: still a hole.
        let ring = region(
            r#"<svg xmlns="http://www.w3.org/2000/svg" width="100mm" height="100mm"><path d="M 0 0 L 40 0 L 40 40 L 0 40 Z M 10 10 L 30 10 L 30 30 L 10 30 Z"/></svg>"#,
        );
        assert!((ring.area() - 1200.0).abs() < 1e-6, "{}", ring.area());
        // A circle of radius 10: OpenSCAD's 40-gon holds 98.77% of the disc;
        // four cubics of 20 pieces each come as close.
        let disc = region(
            r#"<svg xmlns="http://www.w3.org/2000/svg" width="100mm" height="100mm"><circle cx="50" cy="50" r="10"/></svg>"#,
        );
        let share = disc.area() / (std::f64::consts::PI * 100.0);
        assert!(share > 0.987 && share <= 1.0005, "{share}");
        // Centred: the bounding box about the origin.
        let c = svg_region(br#"<svg xmlns="http://www.w3.org/2000/svg" width="200" height="100"><rect x="10" y="10" width="40" height="20"/></svg>"#, 72.0, true).unwrap();
        let (lo, hi) = c.bounds().unwrap();
        assert!((lo + DVec2::new(20.0, 10.0)).length() < 1e-6 && (hi - DVec2::new(20.0, 10.0)).length() < 1e-6);
        assert!(svg_region(b"<nope", 72.0, false).is_err());
    }
}
