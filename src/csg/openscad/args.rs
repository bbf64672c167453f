//! Reading a node's arguments: numbers, flags, lists, points, colours, the
//! transform matrix and OpenSCAD's fragment count, each refused with its
//! place in the file when it is not what OpenSCAD writes.

use std::ops::Range;

use glam::{DVec2, Mat4, Vec3};

use super::syntax::{CsgNode, CsgValue};
use super::Builder;
use crate::error::Result;
use crate::limits::Limit;

impl Builder<'_> {
    /// The number `name`, or `default` when the node does not write it.
    pub(super) fn number_or(&self, node: &CsgNode, name: &str, default: f64) -> Result<f64> {
        if node.arg(name).is_none() {
            return Ok(default);
        }
        self.number(node, name)
    }

    /// The flag `name`, or `default` when the node does not write it.
    pub(super) fn flag_or(&self, node: &CsgNode, name: &str, default: bool) -> Result<bool> {
        if node.arg(name).is_none() {
            return Ok(default);
        }
        self.flag(node, name)
    }

    /// The string `name`, or `default` when the node does not write it.
    pub(super) fn text_or(&self, node: &CsgNode, name: &str, default: &str) -> Result<String> {
        match node.arg(name).map(|a| &a.value) {
            None | Some(CsgValue::Undef) => Ok(default.to_string()),
            Some(CsgValue::Text(t)) => Ok(t.clone()),
            Some(other) => {
                Err(self.invalid(&self.span_of(node, name), format!("`{name}` should be a string, not {other:?}")))
            }
        }
    }

    /// Two numbers from `name`: `[x, y]`, or one number for both.
    pub(super) fn pair(&self, node: &CsgNode, name: &str) -> Result<DVec2> {
        let bad = || self.invalid(&self.span_of(node, name), format!("`{name}` should be a number or [x, y]"));
        match self.arg(node, name)? {
            CsgValue::Number(v) if v.is_finite() => Ok(DVec2::splat(*v)),
            CsgValue::Vector(xs) => match xs[..] {
                [CsgValue::Number(x), CsgValue::Number(y)] if x.is_finite() && y.is_finite() => Ok(DVec2::new(x, y)),
                _ => Err(bad()),
            },
            _ => Err(bad()),
        }
    }

    /// A list of `[x, y]` points (at most [`Limit::Points`] of them).
    pub(super) fn points2(&self, node: &CsgNode, name: &str) -> Result<Vec<DVec2>> {
        let list = self.list(node, name)?;
        self.check(node, Limit::Points, list.len() as u64, || format!("`{}()`'s points", node.name))?;
        let bad = || self.invalid(&self.span_of(node, name), format!("`{name}` should hold finite [x, y] points"));
        list.iter()
            .map(|p| match p {
                CsgValue::Vector(xs) => match xs[..] {
                    [CsgValue::Number(x), CsgValue::Number(y), ..] if x.is_finite() && y.is_finite() => {
                        Ok(DVec2::new(x, y))
                    }
                    _ => Err(bad()),
                },
                _ => Err(bad()),
            })
            .collect()
    }

    /// Lists of indices below `count` (`polygon()`'s `paths`, `polyhedron()`'s
    /// `faces`).
    pub(super) fn index_lists(&self, node: &CsgNode, name: &str, count: usize) -> Result<Vec<Vec<usize>>> {
        let span = self.span_of(node, name);
        self.list(node, name)?
            .iter()
            .map(|f| {
                let CsgValue::Vector(ix) = f else {
                    return Err(self.invalid(&span, format!("each of `{name}` must be a list of point indices")));
                };
                ix.iter()
                    .map(|i| match i {
                        CsgValue::Number(k) if *k >= 0.0 && (*k as usize) < count && k.fract() == 0.0 => {
                            Ok(*k as usize)
                        }
                        _ => Err(self.invalid(&span, format!("index {i:?} is not one of the {count} points"))),
                    })
                    .collect()
            })
            .collect()
    }

    /// Refuses `value` past `limit` with the node's place.
    pub(super) fn check(&self, node: &CsgNode, limit: Limit, value: u64, what: impl FnOnce() -> String) -> Result<()> {
        self.limits.check(limit, value, what).map_err(|e| self.invalid(&node.span, e.to_string()))
    }

    /// OpenSCAD's number of fragments around a circle of radius `r`, at
    /// most [`Limit::Segments`] ([`Builder::fragment_spec`] checks the
    /// numbers it comes from).
    pub(super) fn fragments(&self, node: &CsgNode, r: f32) -> Result<usize> {
        let spec = self.fragment_spec(node)?;
        let n = fragment_count(spec, f64::from(r));
        let what = || format!("`{}()`'s circle", node.name);
        if let Err(e) = self.limits.check(Limit::Segments, n.min(1e18) as u64, what) {
            let span = self.span_of(node, if spec[0] > 0.0 { "$fn" } else { "$fs" });
            return Err(self.invalid(&span, e.to_string()));
        }
        Ok(n as usize)
    }

    /// A node's `[$fn, $fa, $fs]` (OpenSCAD's defaults where a hand-written
    /// file leaves them out): finite, and `$fa`, `$fs` positive when `$fn`
    /// does not decide.
    pub(super) fn fragment_spec(&self, node: &CsgNode) -> Result<[f64; 3]> {
        let (fine, fa, fs) =
            (self.number_or(node, "$fn", 0.0)?, self.number_or(node, "$fa", 12.0)?, self.number_or(node, "$fs", 2.0)?);
        for (name, v) in [("$fn", fine), ("$fa", fa), ("$fs", fs)] {
            if !v.is_finite() {
                return Err(
                    self.invalid(&self.span_of(node, name), format!("`{name}` must be a finite number, not {v}"))
                );
            }
        }
        if fine <= 0.0 && (fa <= 0.0 || fs <= 0.0) {
            let name = if fa <= 0.0 { "$fa" } else { "$fs" };
            return Err(self.invalid(&self.span_of(node, name), format!("`{name}` must be above 0 when `$fn` is 0")));
        }
        Ok([fine, fa, fs])
    }

    pub(super) fn arg<'n>(&self, node: &'n CsgNode, name: &str) -> Result<&'n CsgValue> {
        node.arg(name)
            .map(|a| &a.value)
            .ok_or_else(|| self.invalid(&node.span, format!("`{}()` has no `{name}` argument", node.name)))
    }

    pub(super) fn span_of(&self, node: &CsgNode, name: &str) -> Range<usize> {
        node.arg(name).map_or(node.span.clone(), |a| a.span.clone())
    }

    pub(super) fn number(&self, node: &CsgNode, name: &str) -> Result<f64> {
        match self.arg(node, name)? {
            CsgValue::Number(x) if x.is_finite() && (*x as f32).is_finite() => Ok(*x),
            CsgValue::Number(x) => {
                Err(self.invalid(&self.span_of(node, name), format!("`{name}` must be a finite number, not {x}")))
            }
            other => {
                Err(self.invalid(&self.span_of(node, name), format!("`{name}` should be a number, not {other:?}")))
            }
        }
    }

    pub(super) fn flag(&self, node: &CsgNode, name: &str) -> Result<bool> {
        match self.arg(node, name)? {
            CsgValue::Bool(b) => Ok(*b),
            other => {
                Err(self.invalid(&self.span_of(node, name), format!("`{name}` should be true or false, not {other:?}")))
            }
        }
    }

    pub(super) fn list<'n>(&self, node: &'n CsgNode, name: &str) -> Result<&'n [CsgValue]> {
        match self.arg(node, name)? {
            CsgValue::Vector(v) => Ok(v),
            other => Err(self.invalid(&self.span_of(node, name), format!("`{name}` should be a list, not {other:?}"))),
        }
    }

    pub(super) fn vec3(&self, node: &CsgNode, name: &str, v: &CsgValue) -> Result<Vec3> {
        let bad = || self.invalid(&self.span_of(node, name), format!("`{name}` should hold [x, y, z] points"));
        let CsgValue::Vector(xs) = v else { return Err(bad()) };
        match xs[..] {
            [CsgValue::Number(x), CsgValue::Number(y), CsgValue::Number(z)] => {
                let p = Vec3::new(x as f32, y as f32, z as f32);
                if p.is_finite() {
                    Ok(p)
                } else {
                    Err(self.invalid(&self.span_of(node, name), format!("`{name}` holds a point that is not finite")))
                }
            }
            _ => Err(bad()),
        }
    }

    /// `count` numbers from the argument `name` (`None`: the first, unnamed).
    pub(super) fn floats(&self, node: &CsgNode, name: Option<&str>, count: usize) -> Result<Vec<f32>> {
        let (value, span) = match name {
            Some(n) => (self.arg(node, n)?, self.span_of(node, n)),
            None => node
                .args
                .first()
                .map(|a| (&a.value, a.span.clone()))
                .ok_or_else(|| self.invalid(&node.span, format!("`{}()` needs an argument", node.name)))?,
        };
        let numbers: Option<Vec<f32>> = match value {
            CsgValue::Vector(xs) if xs.len() == count => xs
                .iter()
                .map(|x| if let CsgValue::Number(v) = x { Some(*v as f32).filter(|v| v.is_finite()) } else { None })
                .collect(),
            _ => None,
        };
        numbers.ok_or_else(|| self.invalid(&span, format!("expected {count} finite numbers")))
    }

    /// `multmatrix`'s row-major 4 × 4 matrix.
    pub(super) fn matrix(&self, node: &CsgNode) -> Result<Mat4> {
        let bad = || self.invalid(&node.span, "`multmatrix` needs a 4 x 4 matrix of numbers".into());
        let Some(CsgValue::Vector(rows)) = node.args.first().map(|a| &a.value) else { return Err(bad()) };
        let mut m = [[0.0f32; 4]; 4];
        for (r, row) in rows.iter().enumerate().take(4) {
            let CsgValue::Vector(xs) = row else { return Err(bad()) };
            for (c, x) in xs.iter().enumerate().take(4) {
                let CsgValue::Number(v) = x else { return Err(bad()) };
                m[r][c] = *v as f32;
                if !m[r][c].is_finite() {
                    let message = format!("`multmatrix` entry ({}, {}) must be a finite number, not {v}", r + 1, c + 1);
                    return Err(self.invalid(&node.span, message));
                }
            }
        }
        if rows.len() != 4 {
            return Err(bad());
        }
        Ok(Mat4::from_cols_array_2d(&m).transpose())
    }
}

/// OpenSCAD's number of straight pieces round a circle of radius `r` for
/// `[$fn, $fa, $fs]` (`$fa` and `$fs` above 0 where `$fn` is not).
#[must_use]
pub(super) fn fragment_count([fine, fa, fs]: [f64; 3], r: f64) -> f64 {
    if r < 1e-10 {
        3.0
    } else if fine > 0.0 {
        fine.floor().max(3.0)
    } else {
        (360.0 / fa).min(2.0 * std::f64::consts::PI * r / fs).max(5.0).ceil()
    }
}
