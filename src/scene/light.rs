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

impl LightKind {
    /// The same light moved by the rigid motion `m`.
    #[must_use]
    pub fn transformed(&self, m: &glam::Affine3A) -> LightKind {
        let dir = |d: Vec3| m.transform_vector3(d).normalize_or(d);
        match *self {
            LightKind::Point { position } => LightKind::Point { position: m.transform_point3(position) },
            LightKind::Spot { position, direction, inner, outer } => {
                LightKind::Spot { position: m.transform_point3(position), direction: dir(direction), inner, outer }
            }
            LightKind::Directional { direction } => LightKind::Directional { direction: dir(direction) },
        }
    }
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
    /// How this light's shadows are computed.
    pub shadow: ShadowSettings,
    /// Selective lighting (seed 002 §3.3): when set, only these objects (indices
    /// into `Scene::objects`) receive this light, ambient included; every object
    /// still hides the ones behind it.
    pub only: Option<Vec<usize>>,
}

impl Light {
    /// Whether anything shadows this light: the one rule the raster pipeline's
    /// shadow stage and every ray tracer (the traced term, the reference) both
    /// follow, so the oracle renders the scene the product renders.
    #[must_use]
    pub fn casts_shadows(&self) -> bool {
        self.shadow.method != ShadowMethod::None
    }
}

impl Default for Light {
    /// A white point light of intensity 1 at the origin, no ambient, shadow-mapped.
    fn default() -> Self {
        Light {
            kind: LightKind::Point { position: Vec3::ZERO },
            color: Vec3::ONE,
            intensity: 1.0,
            ambient: 0.0,
            size: 0.0,
            falloff: Falloff::None,
            shadow: ShadowSettings::default(),
            only: None,
        }
    }
}

/// Which technique computes a light's shadow term `shadow_i(x, y)` ∈ [0, 1].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ShadowMethod {
    /// The light reaches every point it faces.
    None,
    /// A depth map rendered from the light (spot: perspective; directional:
    /// orthographic, fitted to the view; point: a cube of six maps).
    #[default]
    Map,
    /// The silhouette-line buffer of seed 000: the same maps, plus the exact
    /// silhouette lines in the texels they cross, so shadow edges are exact
    /// inside a texel ([`ShadowSettings::bits`], [`ShadowSettings::scale`]).
    Slb,
    /// Soft shadows from two hard shadows (seed 001): maps from two points on
    /// the line through the light and a focus point; a pixel shadowed in
    /// both is umbra, in one penumbra, lit by its screen distances to the
    /// nearest umbra and lit pixels ([`ShadowSettings::focus`],
    /// [`ShadowSettings::search`], [`ShadowSettings::penumbra`],
    /// [`ShadowSettings::hard`]).
    Soft,
    /// Percentage-closer soft shadows (Fernando 2005): one map from the
    /// light's centre, a blocker search sized by the light, then a filter as
    /// wide as the penumbra the blockers' mean depth gives
    /// ([`ShadowSettings::blockers`], [`ShadowSettings::filter`]).
    Pcss,
    /// A test's method: every point half lit. It shows that a method is
    /// added by its unit in the shadow stage and its entry in the list.
    #[cfg(test)]
    HalfLit,
}

impl ShadowSettings {
    /// Whether the scene-file key `key` of a light's `[light.shadow]` table
    /// changes what these settings' method computes ([`ShadowMethod::keys`];
    /// a two-map soft shadow reads its hard shadows' keys too, one map from
    /// each point). Keys it does not read are ignored, with a warning, where
    /// a scene file gives them.
    #[must_use]
    pub fn applies(&self, key: &str) -> bool {
        let hard = match (self.method, self.hard) {
            (ShadowMethod::Soft, HardShadows::Map) => ShadowMethod::Map.keys(),
            (ShadowMethod::Soft, HardShadows::Slb) => ShadowMethod::Slb.keys(),
            _ => &[],
        };
        key == "method" || self.method.keys().contains(&key) || (key != "samples" && hard.contains(&key))
    }
}

/// One entry of the list of methods.
struct MethodEntry {
    method: ShadowMethod,
    /// Its name in scene files and on the command line.
    name: &'static str,
    /// What the viewer calls it.
    label: &'static str,
    /// The `[light.shadow]` keys it reads, besides `method`.
    keys: &'static [&'static str],
}

/// The keys every map-based method reads.
const MAP_KEYS: [&str; 3] = ["resolution", "bias", "slope"];

/// The shadow methods: the one list of them, with what each reads. The
/// shadow stage holds what each computes (`kage::shadows::methods`).
const METHODS: &[MethodEntry] = &[
    MethodEntry { method: ShadowMethod::None, name: "none", label: "none", keys: &[] },
    MethodEntry {
        method: ShadowMethod::Map,
        name: "map",
        label: "map",
        keys: &[MAP_KEYS[0], MAP_KEYS[1], MAP_KEYS[2], "pcf", "samples"],
    },
    MethodEntry {
        method: ShadowMethod::Slb,
        name: "slb",
        label: "SLB",
        keys: &[MAP_KEYS[0], MAP_KEYS[1], MAP_KEYS[2], "samples", "bits", "scale", "antialias"],
    },
    MethodEntry {
        method: ShadowMethod::Soft,
        name: "soft",
        label: "two-map soft",
        keys: &["focus", "search", "falloff", "depth_aware", "half", "hard", "points"],
    },
    MethodEntry {
        method: ShadowMethod::Pcss,
        name: "pcss",
        label: "PCSS",
        keys: &[MAP_KEYS[0], MAP_KEYS[1], MAP_KEYS[2], "blockers", "filter"],
    },
    #[cfg(test)]
    MethodEntry { method: ShadowMethod::HalfLit, name: "half-lit", label: "half lit", keys: &[] },
];

impl ShadowMethod {
    /// Every method, in the list's order.
    pub fn all() -> impl Iterator<Item = ShadowMethod> {
        METHODS.iter().map(|e| e.method)
    }

    /// The method called `name` in scene files and on the command line
    /// (any case).
    #[must_use]
    pub fn named(name: &str) -> Option<ShadowMethod> {
        METHODS.iter().find(|e| e.name.eq_ignore_ascii_case(name.trim())).map(|e| e.method)
    }

    /// Every method's name.
    #[must_use]
    pub fn names() -> Vec<&'static str> {
        METHODS.iter().map(|e| e.name).collect()
    }

    fn entry(self) -> &'static MethodEntry {
        METHODS.iter().find(|e| e.method == self).expect("every method is in the list")
    }

    /// Its name in scene files and on the command line.
    #[must_use]
    pub fn name(self) -> &'static str {
        self.entry().name
    }

    /// What the viewer calls it.
    #[must_use]
    pub fn label(self) -> &'static str {
        self.entry().label
    }

    /// The `[light.shadow]` keys it reads itself, besides `method`.
    #[must_use]
    pub fn keys(self) -> &'static [&'static str] {
        self.entry().keys
    }
}

/// How a two-map penumbra's visibility V = D1 / (D1 + D2) becomes the shadow
/// term.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum PenumbraFalloff {
    /// V itself: the term rises linearly across the penumbra (the paper).
    Linear,
    /// The share of a disc a straight edge uncovers having swept V of the
    /// way across it: a disc light's own penumbra profile, flat at both
    /// ends.
    #[default]
    Smooth,
}

/// Where the points a two-map soft shadow's hard shadows are cast from lie.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum PenumbraPoints {
    /// Two on the line through the light and the focus, L ± l·P, l making
    /// the penumbra as wide as the disc light's at the casters' outline (the
    /// paper's pair; the penumbra lies a little outwards of the disc's).
    Paper,
    /// Two on that line, unequally far either side, each hard edge on one
    /// border of the disc light's penumbra at the casters' outline.
    #[default]
    Matched,
    /// Four across the light, on a square round its centre facing the
    /// focus: the penumbra as wide as the disc's wherever the edge is.
    Ring,
}

/// Which hard shadows a two-map soft shadow is made of.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum HardShadows {
    /// Plain depth maps (the paper's).
    #[default]
    Map,
    /// Silhouette-line buffers (seed 000): the penumbra's borders exact
    /// inside a texel.
    Slb,
}

/// A light's shadow technique and its parameters.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ShadowSettings {
    /// The technique.
    pub method: ShadowMethod,
    /// Texels along each side of a shadow map (a cube's faces take half):
    /// exactly, or at most when `by_need` is set.
    pub resolution: u32,
    /// Choose the resolution by need, up to `resolution`: two texels across a
    /// pixel where the shadows fall (the shadow casters' centre, as the camera
    /// sees it; half of one for a soft light's jittered maps; more for a light
    /// low over the floor), to the nearest power of two, at least 512.
    pub by_need: bool,
    /// Constant depth bias, in shadow-map texels (world size of one texel at the
    /// receiver's distance): against acne from depth quantisation.
    pub bias: f32,
    /// Slope-scaled bias, in texels per unit of tan θ (θ between the normal and
    /// the light): against acne on surfaces seen at grazing angles by the light.
    pub slope: f32,
    /// Percentage-closer filtering: k × k texel tests averaged (1: one test).
    pub pcf: u32,
    /// Soft shadows by jittering (seed 002 §3.3): a point or spot light with a
    /// `size` is rendered as this many passes, each with the light moved to
    /// another point of its disc and its own shadow map, averaged.
    pub samples: u32,
    /// Silhouette-line buffer: bits of each line's Fraction and Slope (4–16;
    /// 8 places a line within 1/256 texel).
    pub bits: u32,
    /// Silhouette-line buffer: the virtual projection space's scale — the
    /// light's view drawn this many times wider into the same map (seed 000
    /// §4.4), so one map holds a scene that many times larger.
    pub scale: f32,
    /// Silhouette-line buffer: average the term over each pixel's footprint
    /// on the receiver where a shadow's edge passes near, so the edge is
    /// antialiased (off: lit or not at the pixel's centre).
    pub antialias: bool,
    /// Two-map soft shadows: the point the two maps' line runs through from
    /// the light, where the penumbra matches the light's (`None`: the
    /// centre of the shadow casters' bounds).
    pub focus: Option<Vec3>,
    /// Two-map soft shadows: search for the nearest umbra and lit pixels at
    /// every `search`-th pixel and interpolate between (the paper's; 0: an
    /// exact distance transform at every pixel).
    pub search: u32,
    /// Two-map soft shadows: how visibility rises across the penumbra.
    pub penumbra: PenumbraFalloff,
    /// Two-map soft shadows: keep distances from crossing depth
    /// discontinuities of the eye's view (a floor's penumbra does not reach
    /// onto a plate in front of it).
    pub depth_aware: bool,
    /// Two-map soft shadows: compute the term at every second pixel each
    /// way (a quarter of the pixels) and read each pixel's from the nearest
    /// of those on its surface.
    pub half: bool,
    /// Two-map soft shadows: what the two hard shadows are.
    pub hard: HardShadows,
    /// Two-map soft shadows: where the two points lie.
    pub points: PenumbraPoints,
    /// PCSS: taps of the blocker search.
    pub blockers: u32,
    /// PCSS: taps of the filter.
    pub filter: u32,
    /// Jittered maps: only the disc point of this number (1 to `samples`)
    /// instead of all of them, so that `samples` frames, each with its own
    /// point, averaged, give the light's whole soft shadow (a progressive
    /// viewer's passes); `None`: every point in every frame.
    pub only_sample: Option<u32>,
}

impl Default for ShadowSettings {
    fn default() -> Self {
        ShadowSettings::MAP
    }
}

impl Light {
    /// Seed 002 §3.3's soft shadows by jittering: a shadowed point or spot light
    /// with a `size` is shadowed from `shadow.samples` points spread over the disc
    /// of that radius facing `towards`: these are the lights its shadow maps are
    /// rendered from, each map at half the resolution (the averaged penumbra hides
    /// the coarser texels; the n maps cost n/4 of full ones); the light itself is
    /// still lit once, from its centre ([`crate::shading::FrameLight`]). Any other
    /// light is itself. The disc points are
    /// stratified (Halton 2, 3 through an area-preserving square-to-disc map), the
    /// same on every frame; [`ShadowSettings::only_sample`] keeps one of them.
    #[must_use]
    pub fn jittered(&self, towards: Vec3) -> Vec<Light> {
        let n = self.shadow.samples.max(1);
        let position = match self.kind {
            LightKind::Point { position } | LightKind::Spot { position, .. } => position,
            LightKind::Directional { .. } => return vec![self.clone()],
        };
        if self.size <= 0.0 || n == 1 || !matches!(self.shadow.method, ShadowMethod::Map | ShadowMethod::Slb) {
            return vec![self.clone()];
        }
        let axis = (towards - position).normalize_or(Vec3::NEG_Y);
        let (u, v) = axis.any_orthonormal_pair();
        let points = match self.shadow.only_sample {
            Some(k) => (k.clamp(1, n))..=(k.clamp(1, n)),
            None => 1..=n,
        };
        points
            .map(|i| {
                let d = crate::sampling::concentric_disc(glam::Vec2::new(
                    crate::sampling::radical_inverse(i, 2),
                    crate::sampling::radical_inverse(i, 3),
                ));
                let moved = position + self.size * (u * d.x + v * d.y);
                let kind = match self.kind {
                    LightKind::Spot { direction, inner, outer, .. } => {
                        LightKind::Spot { position: moved, direction, inner, outer }
                    }
                    _ => LightKind::Point { position: moved },
                };
                let shadow = ShadowSettings { resolution: (self.shadow.resolution / 2).max(16), ..self.shadow };
                Light { kind, shadow, ..self.clone() }
            })
            .collect()
    }
}

impl ShadowSettings {
    /// A shadow map sized by need up to 2048², eight jittered maps for a
    /// light with a size, biases of 1 and 1.5 texels, no PCF: the default.
    pub const MAP: ShadowSettings = ShadowSettings {
        method: ShadowMethod::Map,
        resolution: 2048,
        by_need: true,
        bias: 1.0,
        slope: 1.5,
        pcf: 1,
        samples: 8,
        bits: 8,
        scale: 1.0,
        antialias: true,
        focus: None,
        search: 0,
        penumbra: PenumbraFalloff::Smooth,
        depth_aware: true,
        half: false,
        hard: HardShadows::Map,
        points: PenumbraPoints::Matched,
        blockers: 16,
        filter: 16,
        only_sample: None,
    };

    /// The silhouette-line buffer's defaults: a 1024² map, 8-bit lines, scale
    /// 1, antialiased edges.
    pub const SLB: ShadowSettings =
        ShadowSettings { method: ShadowMethod::Slb, resolution: 1024, by_need: false, ..ShadowSettings::MAP };

    /// No shadows.
    pub const NONE: ShadowSettings = ShadowSettings { method: ShadowMethod::None, ..ShadowSettings::MAP };

    /// These settings with `method` instead, and that method's default
    /// resolution when it differs from this one's.
    #[must_use]
    pub fn with_method(self, method: ShadowMethod) -> ShadowSettings {
        let base = |m: ShadowMethod| if m == ShadowMethod::Slb { ShadowSettings::SLB } else { ShadowSettings::MAP };
        let mut s = ShadowSettings { method, ..self };
        if (s.resolution, s.by_need) == (base(self.method).resolution, base(self.method).by_need) {
            (s.resolution, s.by_need) = (base(method).resolution, base(method).by_need);
        }
        s
    }
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

#[cfg(test)]
mod tests {
    use super::*;

    /// `only_sample = k` keeps the k-th of the disc points every frame would
    /// otherwise use, so frames 1..=n between them visit them all.
    #[test]
    fn one_sample_is_the_kth_of_the_whole_set() {
        let light = Light {
            size: 0.3,
            shadow: ShadowSettings { samples: 16, ..ShadowSettings::MAP },
            kind: LightKind::Point { position: Vec3::new(0.0, 5.0, 0.0) },
            ..Light::default()
        };
        let all = light.jittered(Vec3::ZERO);
        assert_eq!(all.len(), 16);
        for k in 1..=16 {
            let one = Light { shadow: ShadowSettings { only_sample: Some(k), ..light.shadow }, ..light.clone() };
            let picked = one.jittered(Vec3::ZERO);
            assert_eq!(picked.len(), 1);
            assert_eq!(picked[0].kind, all[k as usize - 1].kind, "point {k}");
        }
    }
}
