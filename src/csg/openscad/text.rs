//! `text()`: a string's glyph outlines as a 2-D region, laid out as OpenSCAD
//! 2021.01 lays it out with FreeType and HarfBuzz, so that a label's letters
//! land where OpenSCAD's own mesh has them.
//!
//! OpenSCAD sets FreeType's size to `size · 1000` (26.6 points) at 100 dpi and
//! divides outline coordinates by 1000: a font unit is `size / 0.72 / upem`
//! model units. It divides HarfBuzz's advances and the glyphs' grid-fitted
//! boxes by 64 · 16 instead of 64 · 1000/64, so advances come out
//! 1000/1024 of the outlines' scale; this module does the same. Curves are
//! cut into `max(⌊fragments(size) / 8⌋ + 1, 2)` straight pieces each.
//! Kerning comes from the font's `kern` table; there is no other shaping
//! (ligatures, marks, complex scripts).
//!
//! Fonts: Liberation Sans (Regular and Bold, OpenSCAD's default font) is
//! bundled; any other `font = "Family:style=Style"` is looked up among the
//! fonts beside the model and the system's font folders, then as its
//! metric-compatible stand-in (Helvetica and Arial: Liberation Sans, as
//! fontconfig substitutes them); a font not found is a warning, and the font
//! drawn instead is the one fontconfig matches to the name (`fc-match`, what
//! OpenSCAD draws on the same machine) or, without fontconfig, Liberation
//! Sans.

use std::path::{Path, PathBuf};
use std::sync::{Arc, OnceLock};

use glam::DVec2;
use ttf_parser::{name_id, Face, GlyphId, OutlineBuilder};

use super::flat::Region;
use super::syntax::CsgNode;
use super::Builder;
use crate::error::Result;
use crate::limits::Limit;

/// The bundled fonts: family, style, file.
static BUNDLED: [(&str, &str, &[u8]); 2] = [
    ("Liberation Sans", "Regular", include_bytes!("../../../assets/fonts/LiberationSans-Regular.ttf")),
    ("Liberation Sans", "Bold", include_bytes!("../../../assets/fonts/LiberationSans-Bold.ttf")),
];

/// Families and the open fonts of the same metrics that fontconfig (and so
/// OpenSCAD on Linux) draws in their place when they are not installed.
const METRIC_ALIASES: [(&str, &str); 6] = [
    ("Helvetica", "Liberation Sans"),
    ("Arial", "Liberation Sans"),
    ("Times", "Liberation Serif"),
    ("Times New Roman", "Liberation Serif"),
    ("Courier", "Liberation Mono"),
    ("Courier New", "Liberation Mono"),
];

/// A font file's bytes and the face's index in it.
#[derive(Clone)]
struct FontFile {
    bytes: Arc<[u8]>,
    index: u32,
}

/// `font = "Family:style=Style"` taken apart (fontconfig's pattern, as
/// OpenSCAD users write it); an empty family is OpenSCAD's default font.
fn family_and_style(font: &str) -> (String, String) {
    let mut parts = font.split(':');
    let family = parts.next().unwrap_or("").trim();
    let style = parts.find_map(|p| p.trim().strip_prefix("style=")).unwrap_or("Regular").trim();
    let family = if family.is_empty() { "Liberation Sans" } else { family };
    (family.to_string(), style.to_string())
}

/// A face's family and style names (the typographic ones where given).
fn names(face: &Face) -> Option<(String, String)> {
    let find = |ids: [u16; 2]| {
        ids.iter().find_map(|id| face.names().into_iter().filter(|n| n.name_id == *id).find_map(|n| n.to_string()))
    };
    Some((
        find([name_id::TYPOGRAPHIC_FAMILY, name_id::FAMILY])?,
        find([name_id::TYPOGRAPHIC_SUBFAMILY, name_id::SUBFAMILY])?,
    ))
}

/// Font folders of the usual systems.
fn system_folders() -> Vec<PathBuf> {
    let mut out: Vec<PathBuf> =
        ["/usr/share/fonts", "/usr/local/share/fonts", "/Library/Fonts", "/System/Library/Fonts"]
            .into_iter()
            .map(PathBuf::from)
            .collect();
    if let Some(home) = std::env::var_os("HOME").map(PathBuf::from) {
        out.extend([home.join(".fonts"), home.join(".local/share/fonts"), home.join("Library/Fonts")]);
    }
    if let Some(windows) = std::env::var_os("WINDIR").map(PathBuf::from) {
        out.push(windows.join("Fonts"));
    }
    out
}

/// Font files (`.ttf`, `.otf`, `.ttc`) below `folder`, at most 8 levels down.
fn font_files(folder: &Path, depth: u32, out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(folder) else { return };
    for path in entries.flatten().map(|e| e.path()) {
        if path.is_dir() && depth < 8 {
            font_files(&path, depth + 1, out);
        } else if path
            .extension()
            .and_then(|e| e.to_str())
            .is_some_and(|e| ["ttf", "otf", "ttc"].iter().any(|k| e.eq_ignore_ascii_case(k)))
        {
            out.push(path);
        }
    }
}

/// Every system font's family, style, file and face index (read once).
fn system_fonts() -> &'static [(String, String, PathBuf, u32)] {
    static FONTS: OnceLock<Vec<(String, String, PathBuf, u32)>> = OnceLock::new();
    FONTS.get_or_init(|| {
        let mut files = Vec::new();
        for folder in system_folders() {
            font_files(&folder, 0, &mut files);
        }
        files.iter().flat_map(|p| faces_in(p)).collect()
    })
}

/// The faces of the font file at `path`: family, style, path, index.
fn faces_in(path: &Path) -> Vec<(String, String, PathBuf, u32)> {
    // Font files are small; a file past 64 MiB is not one.
    let Ok(bytes) = std::fs::metadata(path).and_then(|m| {
        if m.len() > 64 << 20 {
            Err(std::io::Error::other("too large"))
        } else {
            std::fs::read(path)
        }
    }) else {
        return Vec::new();
    };
    let count = ttf_parser::fonts_in_collection(&bytes).unwrap_or(1);
    (0..count.min(64))
        .filter_map(|i| {
            let face = Face::parse(&bytes, i).ok()?;
            let (family, style) = names(&face)?;
            Some((family, style, path.to_path_buf(), i))
        })
        .collect()
}

/// The font fontconfig matches to `family` in `style` (its best guess for a
/// family it does not have, which is what OpenSCAD draws): its family and
/// style for messages, and its file and face index. `None` where `fc-match`
/// is not installed or answers nothing usable.
fn fontconfig_match(family: &str, style: &str) -> Option<(String, (PathBuf, u32))> {
    let pattern = format!("{}:style={}", family.replace(':', "\\:"), style.replace(':', "\\:"));
    let out = std::process::Command::new("fc-match")
        .args(["-f", "%{family[0]}\n%{style[0]}\n%{file}\n%{index}", &pattern])
        .stderr(std::process::Stdio::null())
        .output()
        .ok()?;
    let text = String::from_utf8(out.stdout).ok()?;
    let mut lines = text.lines();
    let (matched, matched_style, file) = (lines.next()?, lines.next()?, lines.next()?);
    let index = lines.next().and_then(|i| i.trim().parse().ok()).unwrap_or(0);
    let file = PathBuf::from(file);
    (out.status.success() && file.is_file()).then(|| (format!("{matched} {matched_style}"), (file, index)))
}

impl Builder<'_> {
    /// The font `font` names (beside the model, bundled, or on the system),
    /// else its metric-compatible stand-in as fontconfig picks it (Helvetica
    /// and Arial: Liberation Sans), else with a warning the font fontconfig
    /// matches (as OpenSCAD draws it) or, without fontconfig, Liberation Sans.
    fn font(&mut self, node: &CsgNode, font: &str) -> Result<FontFile> {
        let (family, style) = family_and_style(font);
        let same = |a: &str, b: &str| a.eq_ignore_ascii_case(b);
        let alias = METRIC_ALIASES.iter().find(|(name, _)| same(name, &family)).map(|(_, stand_in)| *stand_in);
        for name in std::iter::once(family.as_str()).chain(alias) {
            if let Some(found) = self.font_named(node, name, &style)? {
                return Ok(found);
            }
        }
        if let Some((matched, (path, index))) = fontconfig_match(&family, &style) {
            if let Some(found) = self.font_file(node, &path, index)? {
                self.warn(
                    &node.span,
                    format!("font \"{family}\" ({style}) not found: {matched}, fontconfig's match (as OpenSCAD picks it), drawn instead"),
                );
                return Ok(found);
            }
        }
        let fallback = if same(&style, "Bold") { "Bold" } else { "Regular" };
        self.warn(
            &node.span,
            format!("font \"{family}\" ({style}) not found: Liberation Sans {fallback} drawn instead"),
        );
        let (.., bytes) = BUNDLED.iter().find(|b| same(b.1, &style)).unwrap_or(&BUNDLED[0]);
        Ok(FontFile { bytes: Arc::from(*bytes), index: 0 })
    }

    /// The face of `family` in `style` beside the model, bundled or on the
    /// system, if there is one.
    fn font_named(&self, node: &CsgNode, family: &str, style: &str) -> Result<Option<FontFile>> {
        let same = |a: &str, b: &str| a.eq_ignore_ascii_case(b);
        let beside: Vec<_> = {
            let mut files = Vec::new();
            if let Some(folder) = self.path.parent() {
                font_files(folder, 7, &mut files);
            }
            files.iter().flat_map(|p| faces_in(p)).collect()
        };
        let found = beside
            .iter()
            .chain(if BUNDLED.iter().any(|b| same(b.0, family)) { [].iter() } else { system_fonts().iter() })
            .find(|(f, s, ..)| same(f, family) && same(s, style));
        if let Some((_, _, path, index)) = found {
            if let Some(file) = self.font_file(node, path, *index)? {
                return Ok(Some(file));
            }
        }
        let bundled = BUNDLED.iter().find(|b| same(b.0, family) && same(b.1, style));
        Ok(bundled.map(|(.., bytes)| FontFile { bytes: Arc::from(*bytes), index: 0 }))
    }

    /// The font file at `path` (face `index`), refused past the file-size
    /// limit; `None` if it cannot be read.
    fn font_file(&self, node: &CsgNode, path: &Path, index: u32) -> Result<Option<FontFile>> {
        let size = std::fs::metadata(path).map(|m| m.len()).unwrap_or(0);
        let what = || format!("the font file {}", path.display());
        self.limits.check_bytes(Limit::FileMb, size, what).map_err(|e| self.invalid(&node.span, e.to_string()))?;
        Ok(std::fs::read(path).ok().map(|bytes| FontFile { bytes: bytes.into(), index }))
    }

    /// `text()`'s region: the string's glyphs laid out by [`Layout`].
    pub(super) fn text(&mut self, node: &CsgNode) -> Result<Region> {
        let string = self.text_or(node, "text", "")?;
        let count = string.chars().count() as u64;
        self.check(node, Limit::TextLength, count, || "this text()'s characters".into())?;
        let size = self.number_or(node, "size", 10.0)?;
        if string.is_empty() || !(size > 0.0 && size.is_finite()) {
            return Ok(Region::default());
        }
        let file = self.font(node, &self.text_or(node, "font", "")?)?;
        let Ok(face) = Face::parse(&file.bytes, file.index) else {
            return Err(self.invalid(&node.span, "the font file cannot be read as a TrueType or OpenType font".into()));
        };
        let layout = Layout {
            size,
            spacing: self.number_or(node, "spacing", 1.0)?,
            steps: (self.fragments(node, size as f32)? / 8 + 1).max(2),
            halign: self.text_or(node, "halign", "left")?,
            valign: self.text_or(node, "valign", "baseline")?,
            direction: self.text_or(node, "direction", "ltr")?,
        };
        Ok(layout.region(&face, &string))
    }
}

/// The outlines `text(string, size)` makes in the font file `font` (its
/// first face), as OpenSCAD lays them out: closed contours of straight
/// pieces, outer ones counter-clockwise and holes clockwise. `None` when the
/// bytes are not a TrueType or OpenType font.
#[must_use]
pub fn text_outlines(font: &[u8], string: &str, size: f64) -> Option<Vec<Vec<[f64; 2]>>> {
    let face = Face::parse(font, 0).ok()?;
    let layout = Layout {
        size,
        spacing: 1.0,
        steps: 4,
        halign: "left".into(),
        valign: "baseline".into(),
        direction: "ltr".into(),
    };
    let region = layout.region(&face, string);
    Some(region.contours().iter().map(|c| c.iter().map(|p| [p.x, p.y]).collect()).collect())
}

/// How `text()` lays a string out.
struct Layout {
    size: f64,
    spacing: f64,
    /// Straight pieces per curve.
    steps: usize,
    halign: String,
    valign: String,
    direction: String,
}

impl Layout {
    /// The region of `string` in `face`.
    fn region(&self, face: &Face, string: &str) -> Region {
        let upem = f64::from(face.units_per_em().max(1));
        // FreeType's pixels per em at OpenSCAD's size, and the model units of
        // an outline's font unit and of an advance's.
        let ppem = self.size * 1000.0 / 64.0 * 100.0 / 72.0;
        let outline_scale = ppem / upem * 64.0 / 1000.0;
        let advance_scale = ppem / upem / 16.0;
        let vertical = matches!(self.direction.as_str(), "ttb" | "btt");
        let mut glyphs: Vec<GlyphId> = string.chars().map(|c| face.glyph_index(c).unwrap_or(GlyphId(0))).collect();
        if matches!(self.direction.as_str(), "rtl" | "btt") {
            glyphs.reverse();
        }
        // Each glyph's pen offset, and the run's width and height.
        let line = f64::from(face.ascender()) - f64::from(face.descender());
        let mut pen = DVec2::ZERO;
        let mut placed = Vec::with_capacity(glyphs.len());
        let (mut width, mut ascend, mut descend) = (0.0f64, 0.0f64, 0.0f64);
        for (k, &g) in glyphs.iter().enumerate() {
            placed.push((g, pen));
            let bbox = face.glyph_bounding_box(g);
            if vertical {
                let w = bbox.map_or(0.0, |b| {
                    ((f64::from(b.x_max) * ppem / upem).ceil() - (f64::from(b.x_min) * ppem / upem).floor()) / 16.0
                });
                width = width.max(w);
                let step = line * advance_scale * self.spacing;
                ascend += step;
                pen.y -= step;
            } else {
                let kern = glyphs.get(k + 1).and_then(|&next| kerning(face, g, next)).unwrap_or(0.0);
                let advance = (f64::from(face.glyph_hor_advance(g).unwrap_or(0)) + kern) * advance_scale * self.spacing;
                width += advance;
                pen.x += advance;
                if let Some(b) = bbox {
                    ascend = ascend.max((f64::from(b.y_max) * ppem / upem).ceil().max(0.0) / 16.0);
                    descend = descend.max((-f64::from(b.y_min) * ppem / upem).ceil().max(0.0) / 16.0);
                }
            }
        }
        let x = match self.halign.as_str() {
            "right" => -width,
            "center" => -width / 2.0,
            _ => 0.0,
        };
        let y = match self.valign.as_str() {
            "top" => -ascend,
            "center" => descend / 2.0 - ascend / 2.0,
            "bottom" => descend,
            _ => 0.0,
        };
        let mut contours = Vec::new();
        for (g, at) in placed {
            let mut pen = Pen { scale: outline_scale, at: at + DVec2::new(x, y), steps: self.steps, ..Pen::default() };
            face.outline_glyph(g, &mut pen);
            pen.close();
            contours.extend(pen.contours);
        }
        Region::non_zero(&contours)
    }
}

/// The `kern` table's adjustment between two glyphs, in font units.
fn kerning(face: &Face, left: GlyphId, right: GlyphId) -> Option<f64> {
    let kern = face.tables().kern?;
    kern.subtables
        .into_iter()
        .filter(|s| s.horizontal && !s.variable)
        .find_map(|s| s.glyphs_kerning(left, right))
        .map(f64::from)
}

/// Collects a glyph's outline as contours of straight pieces, curves cut
/// into `steps` each, in model units placed at `at`.
#[derive(Default)]
struct Pen {
    scale: f64,
    at: DVec2,
    steps: usize,
    current: Vec<DVec2>,
    last: DVec2,
    contours: Vec<Vec<DVec2>>,
}

impl Pen {
    fn point(&self, x: f32, y: f32) -> DVec2 {
        DVec2::new(f64::from(x), f64::from(y)) * self.scale + self.at
    }

    fn push(&mut self, p: DVec2) {
        self.current.push(p);
        self.last = p;
    }
}

impl OutlineBuilder for Pen {
    fn move_to(&mut self, x: f32, y: f32) {
        self.close();
        let p = self.point(x, y);
        self.push(p);
    }

    fn line_to(&mut self, x: f32, y: f32) {
        let p = self.point(x, y);
        self.push(p);
    }

    fn quad_to(&mut self, x1: f32, y1: f32, x: f32, y: f32) {
        let (p0, c, p1) = (self.last, self.point(x1, y1), self.point(x, y));
        for k in 1..=self.steps {
            let a = k as f64 / self.steps as f64;
            self.push(p0 * (1.0 - a).powi(2) + c * 2.0 * (1.0 - a) * a + p1 * a * a);
        }
    }

    fn curve_to(&mut self, x1: f32, y1: f32, x2: f32, y2: f32, x: f32, y: f32) {
        let (p0, c1, c2, p1) = (self.last, self.point(x1, y1), self.point(x2, y2), self.point(x, y));
        for k in 1..=self.steps {
            let a = k as f64 / self.steps as f64;
            let b = 1.0 - a;
            self.push(p0 * b.powi(3) + c1 * 3.0 * b * b * a + c2 * 3.0 * b * a * a + p1 * a.powi(3));
        }
    }

    fn close(&mut self) {
        let mut c = std::mem::take(&mut self.current);
        if c.len() > 1 && c.first() == c.last() {
            c.pop();
        }
        if c.len() >= 3 {
            self.contours.push(c);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn layout(size: f64) -> Layout {
        let steps = 4;
        Layout { size, spacing: 1.0, steps, halign: "left".into(), valign: "baseline".into(), direction: "ltr".into() }
    }

    #[test]
    fn letters_land_where_openscads_mesh_has_them() {
        // OpenSCAD 2021.01's STL of linear_extrude(1) text("H", size = 10)
        // spans x 1.1393 to 8.89699, y 0 to 9.55479; "HH" to x 18.692.
        let face = Face::parse(BUNDLED[0].2, 0).unwrap();
        let (lo, hi) = layout(10.0).region(&face, "H").bounds().unwrap();
        assert!((lo - DVec2::new(1.1393, 0.0)).abs().max_element() < 1e-3, "{lo}");
        assert!((hi - DVec2::new(8.89699, 9.55479)).abs().max_element() < 1e-3, "{hi}");
        let (_, hi) = layout(10.0).region(&face, "HH").bounds().unwrap();
        assert!((hi.x - 18.692).abs() < 1e-3, "{hi}");
        // "O" has two contours (a hole); its bottom dips below the baseline.
        let o = layout(10.0).region(&face, "O");
        assert_eq!(o.contours().len(), 2);
        assert!((o.bounds().unwrap().0.y + 0.13559).abs() < 1e-3);
    }

    #[test]
    fn font_names_split_into_family_and_style() {
        assert_eq!(family_and_style(""), ("Liberation Sans".into(), "Regular".into()));
        assert_eq!(family_and_style("Liberation Sans:style=Bold"), ("Liberation Sans".into(), "Bold".into()));
        assert_eq!(family_and_style("DejaVu Sans Mono"), ("DejaVu Sans Mono".into(), "Regular".into()));
    }
}
