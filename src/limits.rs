//! How much work and memory one input may ask for.
//!
//! kage reads files people download, and a small file can ask for a great
//! deal: a 40-node glTF that places 2⁴⁰ instances, a 140 KB PNG that decodes
//! to 3 GB, a sphere of a million facets, a light whose maps take 256 GB. Each
//! such request is measured against a [`Limit`] before the work starts and
//! refused with an error that names the limit and how to raise it. The
//! defaults let every real model of the test corpus through with room to
//! spare (the largest asks for a few percent of each) and keep one frame
//! within a few GB; a scene file's `[limits]` table and the command line's
//! `--limit NAME=VALUE` raise them for bigger work.

use std::fmt;
use std::str::FromStr;

/// One limit: what it bounds, its name in `[limits]` and on the command line.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Limit {
    /// Levels of nesting in any recursive format: `.csg` groups and vectors,
    /// glTF node trees.
    Nesting,
    /// Nodes a glTF file may hold.
    GltfNodes,
    /// Nodes a glTF scene may place, a node counted once per parent listing it.
    Instances,
    /// Segments around one circle of an OpenSCAD primitive (`$fn`, `$fa`, `$fs`).
    Segments,
    /// Facets of one tessellated primitive (a faceted or hulled sphere has
    /// segments × segments / 2).
    Facets,
    /// Triangles in one scene, every object's counted.
    Triangles,
    /// Convex primitives in one CSG solid.
    Primitives,
    /// Points of one OpenSCAD `polygon()` or `polyhedron()`, of one imported
    /// drawing (an SVG's points, a DXF's line pieces), and heights of one
    /// height map (a `.dat` file's numbers, a PNG's pixels).
    Points,
    /// Slices of one extrusion (`linear_extrude`'s `slices`, `rotate_extrude`'s
    /// segments).
    Slices,
    /// Characters of one OpenSCAD `text()`.
    TextLength,
    /// Pixels of one decoded texture, checked from the image header.
    TexturePixels,
    /// Mebibytes of shadow maps one light holds (its jittered samples' maps together).
    LightShadowMb,
    /// Mebibytes of shadow maps one frame holds (every light's).
    FrameShadowMb,
    /// Mebibytes read from one file.
    FileMb,
    /// Mebibytes a scene may ask for in all: meshes, textures, shadow maps and
    /// the frame's buffers, as estimated before the render.
    MemoryMb,
}

impl Limit {
    /// Every limit, in the order the docs list them.
    pub const ALL: [Limit; 15] = [
        Limit::Nesting,
        Limit::GltfNodes,
        Limit::Instances,
        Limit::Segments,
        Limit::Facets,
        Limit::Triangles,
        Limit::Primitives,
        Limit::Points,
        Limit::Slices,
        Limit::TextLength,
        Limit::TexturePixels,
        Limit::LightShadowMb,
        Limit::FrameShadowMb,
        Limit::FileMb,
        Limit::MemoryMb,
    ];

    /// The name used in `[limits]` and `--limit`.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Limit::Nesting => "nesting",
            Limit::GltfNodes => "gltf_nodes",
            Limit::Instances => "instances",
            Limit::Segments => "segments",
            Limit::Facets => "facets",
            Limit::Triangles => "triangles",
            Limit::Primitives => "primitives",
            Limit::Points => "points",
            Limit::Slices => "slices",
            Limit::TextLength => "text_length",
            Limit::TexturePixels => "texture_pixels",
            Limit::LightShadowMb => "light_shadow_mb",
            Limit::FrameShadowMb => "frame_shadow_mb",
            Limit::FileMb => "file_mb",
            Limit::MemoryMb => "memory_mb",
        }
    }

    /// The default value.
    #[must_use]
    pub fn default_value(self) -> u64 {
        match self {
            Limit::Nesting => 1000,
            Limit::GltfNodes => 1_000_000,
            Limit::Instances => 100_000,
            Limit::Segments => 2048,
            Limit::Facets => 20_000,
            Limit::Triangles => 20_000_000,
            Limit::Primitives => 100_000,
            Limit::Points => 1_000_000,
            Limit::Slices => 10_000,
            Limit::TextLength => 10_000,
            Limit::TexturePixels => 8192 * 8192,
            Limit::LightShadowMb => 1024,
            Limit::FrameShadowMb => 2048,
            Limit::FileMb => 2048,
            Limit::MemoryMb => 12_288,
        }
    }

    /// The limit called `name`.
    ///
    /// # Errors
    ///
    /// A message listing the known names when there is none such.
    pub fn named(name: &str) -> Result<Limit, String> {
        Limit::ALL.into_iter().find(|l| l.name() == name).ok_or_else(|| {
            let known: Vec<&str> = Limit::ALL.iter().map(|l| l.name()).collect();
            format!("unknown limit '{name}' (known: {})", known.join(", "))
        })
    }
}

impl fmt::Display for Limit {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// The value of every [`Limit`]; [`Limits::default`] holds the defaults.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Limits {
    values: [u64; Limit::ALL.len()],
}

impl Default for Limits {
    fn default() -> Self {
        Limits { values: Limit::ALL.map(Limit::default_value) }
    }
}

impl Limits {
    /// The value of `limit`.
    #[must_use]
    pub fn get(&self, limit: Limit) -> u64 {
        self.values[limit as usize]
    }

    /// [`Limits::get`] as a count of bytes, for the limits in mebibytes.
    #[must_use]
    pub fn bytes(&self, limit: Limit) -> u64 {
        self.get(limit).saturating_mul(1 << 20)
    }

    /// These limits with `limit` set to `value`.
    #[must_use]
    pub fn with(mut self, limit: Limit, value: u64) -> Limits {
        self.values[limit as usize] = value;
        self
    }

    /// Sets `limit` to `value`.
    pub fn set(&mut self, limit: Limit, value: u64) {
        self.values[limit as usize] = value;
    }

    /// These limits with `settings` applied in order.
    #[must_use]
    pub fn with_settings(mut self, settings: &[LimitSetting]) -> Limits {
        settings.iter().for_each(|s| self.set(s.limit, s.value));
        self
    }

    /// `Ok` when `asked` is within `limit`; else the message refusing `what`.
    ///
    /// # Errors
    ///
    /// A [`LimitExceeded`] naming the limit, what asked, and how to raise it.
    pub fn check(&self, limit: Limit, asked: u64, what: impl FnOnce() -> String) -> Result<(), LimitExceeded> {
        let allowed = self.get(limit);
        if asked <= allowed {
            return Ok(());
        }
        Err(LimitExceeded { limit, asked, allowed, what: what() })
    }

    /// [`Limits::check`] for a limit in mebibytes and a request in bytes.
    ///
    /// # Errors
    ///
    /// As [`Limits::check`], with the request rounded up to mebibytes.
    pub fn check_bytes(&self, limit: Limit, bytes: u64, what: impl FnOnce() -> String) -> Result<(), LimitExceeded> {
        if bytes <= self.bytes(limit) {
            return Ok(());
        }
        self.check(limit, bytes.div_ceil(1 << 20).max(self.get(limit) + 1), what)
    }
}

/// A request over a limit: what asked, how much, and the limit.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct LimitExceeded {
    /// The limit.
    pub limit: Limit,
    /// What was asked for, in the limit's unit.
    pub asked: u64,
    /// The limit's value.
    pub allowed: u64,
    /// What asked for it ("sphere() at line 3", "texture wood.png").
    pub what: String,
}

impl fmt::Display for LimitExceeded {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let LimitExceeded { limit, asked, allowed, what } = self;
        let unit = if limit.name().ends_with("_mb") { " MiB" } else { "" };
        write!(
            f,
            "{what}: {asked}{unit} is over the `{limit}` limit of {allowed}{unit}; \
             if that is meant, raise it with `{limit} = {asked}` in the scene's [limits] table \
             or `--limit {limit}={asked}`"
        )
    }
}

impl std::error::Error for LimitExceeded {}

/// One `NAME=VALUE` setting, as `--limit` takes it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct LimitSetting {
    /// The limit.
    pub limit: Limit,
    /// Its new value.
    pub value: u64,
}

impl FromStr for LimitSetting {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let (name, value) = s.split_once('=').ok_or_else(|| format!("'{s}' is not NAME=VALUE"))?;
        let limit = Limit::named(name.trim())?;
        let value = value
            .trim()
            .replace('_', "")
            .parse()
            .map_err(|_| format!("the value of limit '{}' must be a whole number ≥ 0", limit.name()))?;
        Ok(LimitSetting { limit, value })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_setting_reads_name_and_value_and_refuses_unknown_names() {
        let s: LimitSetting = "triangles=1_000".parse().unwrap();
        assert_eq!(s, LimitSetting { limit: Limit::Triangles, value: 1000 });
        let e = "triangle=3".parse::<LimitSetting>().unwrap_err();
        assert!(e.contains("unknown limit 'triangle'") && e.contains("triangles"), "{e}");
        assert!("triangles=-1".parse::<LimitSetting>().is_err());
        assert!("triangles".parse::<LimitSetting>().is_err());
    }

    #[test]
    fn a_check_passes_at_the_limit_and_names_it_one_past() {
        let limits = Limits::default().with(Limit::Facets, 10);
        assert!(limits.check(Limit::Facets, 10, || "x".into()).is_ok());
        let e = limits.check(Limit::Facets, 11, || "sphere()".into()).unwrap_err();
        let text = e.to_string();
        assert!(text.contains("`facets` limit of 10") && text.contains("--limit facets=11"), "{text}");
        let mb = Limits::default().with(Limit::FileMb, 1);
        assert!(mb.check_bytes(Limit::FileMb, 1 << 20, String::new).is_ok());
        assert_eq!(mb.check_bytes(Limit::FileMb, (1 << 20) + 1, String::new).unwrap_err().asked, 2);
    }

    #[test]
    fn names_are_distinct_and_round_trip() {
        for l in Limit::ALL {
            assert_eq!(Limit::named(l.name()), Ok(l));
            assert_eq!(Limit::ALL[l as usize], l, "ALL is in declaration order");
        }
    }
}
