//! `import()` and `surface()`: meshes and heightmaps from the files a model
//! names, read through the loader's [`super::Imports`] (relative to the
//! `.csg` file's folder), as closed meshes ([`crate::csg::ClosedMesh`]).
//!
//! A heightmap (`surface()`) is meshed as OpenSCAD meshes it: a `.dat` file's
//! rows of numbers stand at y = 0, 1, 2, ... (columns at x = 0, 1, ...), each
//! cell cut into four triangles about its centre (at the corners' mean
//! height), walled down to a floor one unit below the lowest point; `center`
//! moves the grid's middle to the origin.

use glam::{Affine3A, Vec3, Vec4};

use super::drawing::svg_region;
use super::flat::Region;
use super::syntax::CsgNode;
use super::{Builder, Built};
use crate::csg::ClosedMesh;
use crate::error::Result;
use crate::limits::Limit;

/// File extensions `import()` reads as 2-D drawings.
const DRAWINGS: [&str; 2] = ["svg", "dxf"];

/// Whether an `import()` names a 2-D drawing (SVG, DXF) rather than a mesh.
#[must_use]
pub(super) fn drawing(node: &CsgNode) -> bool {
    match node.arg("file").map(|a| &a.value) {
        Some(super::syntax::CsgValue::Text(file)) => {
            let ext = std::path::Path::new(file).extension().and_then(|e| e.to_str()).unwrap_or_default();
            DRAWINGS.iter().any(|d| d.eq_ignore_ascii_case(ext))
        }
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
            Some(mesh) => self.push_mesh(node, mesh, m, color),
            None => {
                self.warn(&node.span, format!("{file} holds no triangle with an area: nothing is drawn"));
                Ok(Built::Empty)
            }
        }
    }

    /// `import()` of a 2-D drawing: an SVG file's region ([`svg_region`]); a
    /// DXF file is not read yet.
    pub(super) fn drawing(&mut self, node: &CsgNode) -> Result<Region> {
        let file = self.text_or(node, "file", "")?;
        let svg = std::path::Path::new(&file).extension().is_some_and(|e| e.eq_ignore_ascii_case("svg"));
        if !svg {
            self.unsupported(node, format!("{file}: an imported DXF drawing is not drawn yet (SVG drawings are)"))?;
            return Ok(Region::default());
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

    /// `surface()`: a heightmap's closed mesh.
    pub(super) fn surface(&mut self, node: &CsgNode, m: Affine3A, color: Option<Vec4>) -> Result<Built> {
        let file = self.text_or(node, "file", "")?;
        let bytes = self.imports.bytes(&file).map_err(|e| self.invalid(&node.span, e))?;
        let ext =
            std::path::Path::new(&file).extension().and_then(|e| e.to_str()).unwrap_or_default().to_ascii_lowercase();
        if ext == "png" {
            let message = format!("{file}: a PNG heightmap is not drawn yet (a .dat file of numbers is)");
            self.unsupported(node, message)?;
            return Ok(Built::Skipped);
        }
        let rows = heights(&bytes).map_err(|e| self.invalid(&node.span, format!("{file}: {e}")))?;
        let cells = rows.len() as u64 * rows.first().map_or(0, Vec::len) as u64;
        self.check(node, Limit::Points, cells, || format!("the heights of {file}"))?;
        let center = self.flag_or(node, "center", false)?;
        match heightmap(&rows, center) {
            Some(mesh) => self.push_mesh(node, mesh, m, color),
            None => Ok(Built::Empty),
        }
    }
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
    let floor = rows.iter().flatten().copied().fold(f32::INFINITY, f32::min) - 1.0;
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
    fn a_heightmap_is_openscads_closed_surface() {
        let rows = heights(b"# a tiny heightmap\n1 2 3\n4 5 6\n7 8 20\n").unwrap();
        let mesh = heightmap(&rows, false).unwrap();
        // OpenSCAD's STL of surface(file = "h.dat"): 21 distinct points, the
        // floor at 0, a cell's centre at its corners' mean.
        assert_eq!(mesh.bounds(), (Vec3::ZERO, Vec3::new(2.0, 2.0, 20.0)));
        assert!(mesh.contains(Vec3::new(0.5, 0.5, 2.9)) && !mesh.contains(Vec3::new(0.5, 0.5, 3.1)));
        assert!(mesh.contains(Vec3::new(1.5, 1.5, 9.7)) && !mesh.contains(Vec3::new(1.5, 1.5, 9.8)));
        assert!(heights(b"1 2\n3\n").unwrap_err().contains("line 2"));
        assert!(heights(b"1 x\n").is_err());
    }
}
