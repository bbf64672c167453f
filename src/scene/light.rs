//! Light sources of seed 002: each light contributes its own ambient, diffuse and
//! specular terms (Ia_i, Id_i, Is_i of eq. 1), so a light is only more passes.

use glam::Vec3;

/// Where light comes from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum LightKind {
    /// Emits in all directions from a point.
    Point {
        /// Position, world space.
        position: Vec3,
    },
    /// A point light restricted to a cone.
    Spot {
        /// Position, world space.
        position: Vec3,
        /// Unit axis of the cone.
        direction: Vec3,
        /// Full intensity inside this half-angle (radians).
        inner: f32,
        /// Zero intensity outside this half-angle (radians).
        outer: f32,
    },
    /// Parallel light, like the sun.
    Directional {
        /// Unit direction the light travels in.
        direction: Vec3,
    },
}

/// How a positional light dims with distance.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Falloff {
    /// No dimming (the CAD-preview default: a light is as bright everywhere).
    #[default]
    None,
    /// 1 / d² (physically based; glTF lights use it).
    InverseSquare,
}

/// A light source.
#[derive(Debug, Clone, PartialEq)]
pub struct Light {
    /// Type and placement.
    pub kind: LightKind,
    /// Linear RGB colour.
    pub color: Vec3,
    /// Scales the diffuse and specular terms (Id_i = Is_i = color · intensity).
    pub intensity: f32,
    /// Scales the ambient term (Ia_i = color · ambient); never shadowed.
    pub ambient: f32,
    /// Radius of the emitting sphere (0: a point); used by soft-shadow techniques.
    pub size: f32,
    /// Distance attenuation for point and spot lights.
    pub falloff: Falloff,
}

/// Light arriving at a point: unit direction towards the light and the radiance
/// scale (intensity × colour × attenuation).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Incident {
    /// Unit vector from the surface towards the light.
    pub to_light: Vec3,
    /// Colour × intensity × distance and cone attenuation.
    pub radiance: Vec3,
}

impl Light {
    /// The light arriving at `p`.
    #[must_use]
    pub fn incident(&self, p: Vec3) -> Incident {
        let scale = self.color * self.intensity;
        match self.kind {
            LightKind::Directional { direction } => Incident { to_light: -direction, radiance: scale },
            LightKind::Point { position } => self.positional(position, p, scale),
            LightKind::Spot { position, direction, inner, outer } => {
                let mut inc = self.positional(position, p, scale);
                let cos = (-inc.to_light).dot(direction);
                let (ci, co) = (inner.cos(), outer.cos());
                let t = if ci > co { ((cos - co) / (ci - co)).clamp(0.0, 1.0) } else { f32::from(cos >= co) };
                inc.radiance *= t * t * (3.0 - 2.0 * t);
                inc
            }
        }
    }

    fn positional(&self, position: Vec3, p: Vec3, scale: Vec3) -> Incident {
        let d = position - p;
        let dist2 = d.length_squared().max(1e-12);
        let att = match self.falloff {
            Falloff::None => 1.0,
            Falloff::InverseSquare => 1.0 / dist2,
        };
        Incident { to_light: d / dist2.sqrt(), radiance: scale * att }
    }
}
