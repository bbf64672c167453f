//! 2-D nodes: each node's region in its own frame ([`Builder::flat`]), as
//! OpenSCAD's geometry evaluator makes it — shapes, booleans, transforms
//! (their x and y rows), offsets, hulls, Minkowski sums, resizes, text and
//! projections of solids.

use glam::{Affine3A, DAffine2, DMat2, DVec2};

use super::flat::{Join, Region};
use super::meshed::projection;
use super::syntax::CsgNode;
use super::{flatness, kind, Builder, Kind};
use crate::error::Result;

impl Builder<'_> {
    /// The region `node` makes, in its own frame; empty for a `%` part, a
    /// solid among 2-D shapes (OpenSCAD ignores it too, with a warning), or
    /// a node skipped with a warning.
    pub(super) fn flat(&mut self, node: &CsgNode) -> Result<Region> {
        if node.background {
            return Ok(Region::default());
        }
        let Some(kind) = kind(node) else {
            self.unsupported(node, format!("`{}()` is not a node kage knows", node.name))?;
            return Ok(Region::default());
        };
        match flatness(node) {
            // Nothing below it: nothing to draw, nothing to say.
            None => return Ok(Region::default()),
            Some(false) if kind != Kind::Projection => {
                let message = format!("a 3-D `{}()` among 2-D shapes is ignored, as OpenSCAD ignores it", node.name);
                self.warn(&node.span, message);
                return Ok(Region::default());
            }
            _ => {}
        }
        Ok(match kind {
            Kind::Union | Kind::Color => Region::union(&self.flat_kids(node)?),
            Kind::Intersection => Region::intersection(&self.flat_kids(node)?),
            Kind::Difference => {
                let kids = self.flat_kids(node)?;
                match kids.split_first() {
                    Some((first, cutters)) => first.difference(cutters),
                    None => Region::default(),
                }
            }
            Kind::Transform => {
                let m = self.matrix(node)?;
                // The x and y rows (OpenSCAD's 2-D transform of a 4 × 4 matrix).
                let xy = DAffine2::from_mat2_translation(
                    DMat2::from_cols_array(&[m.x_axis.x, m.x_axis.y, m.y_axis.x, m.y_axis.y].map(f64::from)),
                    DVec2::new(m.w_axis.x.into(), m.w_axis.y.into()),
                );
                if xy.matrix2.determinant().abs() < 1e-12 {
                    return Ok(Region::default());
                }
                Region::union(&self.flat_kids(node)?).transformed(&xy)
            }
            Kind::Hull => Region::hull(self.flat_kids(node)?.iter().flat_map(|r| r.points().collect::<Vec<_>>())),
            Kind::Minkowski => Region::minkowski(&self.flat_kids(node)?),
            Kind::Resize => self.resize_flat(node)?,
            Kind::Shape2d => self.shape2d(node)?,
            Kind::Text => self.text(node)?,
            Kind::Offset => self.offset(node)?,
            Kind::Projection => {
                let cut = self.flag_or(node, "cut", false)?;
                let solid = self.faceted_solid(&node.children, Affine3A::IDENTITY)?;
                projection(&solid, cut)
            }
            Kind::Fill => Region::union(&self.flat_kids(node)?).filled(),
            Kind::Import => self.drawing(node)?,
            // Solid kinds were turned away above.
            Kind::Primitive | Kind::LinearExtrude | Kind::RotateExtrude | Kind::Surface => Region::default(),
        })
    }

    /// Each child's region (`%` parts and skipped nodes left out).
    fn flat_kids(&mut self, node: &CsgNode) -> Result<Vec<Region>> {
        let mut out = Vec::new();
        for kid in node.children.iter().filter(|k| !k.background) {
            out.push(self.flat(kid)?);
        }
        Ok(out)
    }

    /// `square`, `circle`, `polygon`.
    fn shape2d(&mut self, node: &CsgNode) -> Result<Region> {
        match node.name.as_str() {
            "square" => {
                let size = self.pair(node, "size")?;
                if !(size.min_element() > 0.0 && size.is_finite()) {
                    return Ok(Region::default());
                }
                Ok(Region::square(size, self.flag_or(node, "center", false)?))
            }
            "circle" => {
                let r = self.number(node, "r")?;
                if !(r > 0.0 && r.is_finite()) {
                    return Ok(Region::default());
                }
                Ok(Region::circle(r, self.fragments(node, r as f32)?))
            }
            _ => {
                let points = self.points2(node, "points")?;
                let paths = match node.arg("paths").map(|a| &a.value) {
                    None | Some(super::syntax::CsgValue::Undef) => vec![(0..points.len()).collect()],
                    Some(_) => self.index_lists(node, "paths", points.len())?,
                };
                let contours: Vec<Vec<DVec2>> = paths
                    .iter()
                    .map(|p| p.iter().map(|&i| points[i]).collect())
                    .filter(|c: &Vec<DVec2>| c.len() >= 3)
                    .collect();
                Ok(Region::even_odd(&contours))
            }
        }
    }

    /// `offset(r = ...)` (round corners of OpenSCAD's segments for |r|) or
    /// `offset(delta = ..., chamfer = ...)`.
    fn offset(&mut self, node: &CsgNode) -> Result<Region> {
        let region = Region::union(&self.flat_kids(node)?);
        if let Some(r) = node.arg("r").map(|_| self.number(node, "r")).transpose()? {
            let n = self.fragments(node, r.abs() as f32)?;
            return Ok(region.offset(r, Join::Round(n)));
        }
        let delta = self.number_or(node, "delta", 1.0)?;
        let join = if self.flag_or(node, "chamfer", false)? { Join::Chamfer } else { Join::Miter };
        Ok(region.offset(delta, join))
    }

    /// `resize()` of 2-D children (the new size's x and y).
    fn resize_flat(&mut self, node: &CsgNode) -> Result<Region> {
        let size = self.floats(node, Some("newsize"), 3)?;
        let auto = self.floats(node, Some("auto"), 3)?;
        let region = Region::union(&self.flat_kids(node)?);
        let Some((lo, hi)) = region.bounds() else { return Ok(region) };
        let now = hi - lo;
        let given = |i: usize| size[i] > 0.0 && now[i] > 0.0;
        let mut scale = DVec2::ONE;
        for i in 0..2 {
            if given(i) {
                scale[i] = f64::from(size[i]) / now[i];
            }
        }
        let largest = (0..2).filter(|&i| given(i)).map(|i| scale[i]).fold(f64::NAN, f64::max);
        for i in 0..2 {
            if !given(i) && auto[i] != 0.0 && largest.is_finite() {
                scale[i] = largest;
            }
        }
        Ok(region.transformed(&DAffine2::from_scale(scale)))
    }
}
