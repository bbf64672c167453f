//! Seed 002 eq. 1: per light i, ambient Ia_i·Ka, diffuse Id_i·Kd·cosθ and specular
//! Is_i·Ks·(cosα)^n, each component multiplied by its own attribute map (§3.2),
//! plus emission Ke once.
//!
//! cosθ = N·L; cosα = R·V with R the mirror of L about N (Phong, as the paper and the
//! peers use); the specular term is zero where N·L ≤ 0.

use std::sync::Arc;

use glam::Vec3;

use super::surface::SurfacePoint;
use crate::scene::{phong_exponent, Light, Material, SharedFootprint, Texture};

/// The components of seed 002 eq. 4, summed over lights.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Components {
    /// Σ Ia_i · Ka · Mapa.
    pub ambient: Vec3,
    /// Σ shadow_i · Id_i · Kd · cosθ · Mapd.
    pub diffuse: Vec3,
    /// Σ shadow_i · Is_i · Ks · (cosα)^n · Maps.
    pub specular: Vec3,
    /// Ke · Mape.
    pub emission: Vec3,
}

impl Components {
    /// The pixel's colour: the sum of the components.
    #[must_use]
    pub fn total(&self) -> Vec3 {
        self.ambient + self.diffuse + self.specular + self.emission
    }

    /// The sum of the components in `parts` (an image that holds only those).
    #[must_use]
    pub fn total_of(&self, parts: ComponentSet) -> Vec3 {
        let keep = |c, v: Vec3| if parts.contains(c) { v } else { Vec3::ZERO };
        keep(Component::Ambient, self.ambient)
            + keep(Component::Diffuse, self.diffuse)
            + keep(Component::Specular, self.specular)
            + keep(Component::Emission, self.emission)
    }
}

impl std::ops::AddAssign for Components {
    fn add_assign(&mut self, o: Components) {
        self.ambient += o.ambient;
        self.diffuse += o.diffuse;
        self.specular += o.specular;
        self.emission += o.emission;
    }
}

/// One term of seed 002 eq. 4/5, as a pass writes it out on its own (an AOV, the
/// paper's Fig. 4).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Component {
    /// Σ Ia_i · Ka · Mapa.
    Ambient,
    /// Σ shadow_i · Id_i · Kd · cosθ · Mapd.
    Diffuse,
    /// Σ shadow_i · Is_i · Ks · (cosα)^n · Maps.
    Specular,
    /// Ke · Mape, and the background colour of pixels that see nothing.
    Emission,
    /// IrayTracing: reflection and refraction traced from the item buffer.
    Traced,
    /// Fog (§3.5): f(d) · fog colour on every visible surface, shadows or not.
    Fog,
    /// Km · Mape(R): the environment in the mirror direction, without tracing.
    Reflection,
}

impl Component {
    /// Every component, in the order of eq. 5.
    pub const ALL: [Component; 7] = [
        Component::Ambient,
        Component::Diffuse,
        Component::Specular,
        Component::Reflection,
        Component::Emission,
        Component::Traced,
        Component::Fog,
    ];

    /// Lower-case name (`--aov` and file names).
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Component::Ambient => "ambient",
            Component::Diffuse => "diffuse",
            Component::Specular => "specular",
            Component::Emission => "emission",
            Component::Traced => "traced",
            Component::Fog => "fog",
            Component::Reflection => "reflection",
        }
    }

    /// The component called `name`.
    #[must_use]
    pub fn from_name(name: &str) -> Option<Component> {
        Component::ALL.into_iter().find(|c| c.name() == name)
    }
}

/// A set of [`Component`]s.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ComponentSet(u8);

impl ComponentSet {
    /// Every component: the final image.
    pub const ALL: ComponentSet = ComponentSet(0x7f);
    /// No component.
    pub const EMPTY: ComponentSet = ComponentSet(0);

    /// The set of `components`.
    #[must_use]
    pub fn of(components: &[Component]) -> ComponentSet {
        ComponentSet(components.iter().fold(0, |m, &c| m | 1 << c as u8))
    }

    /// The components in the set, in the order of [`Component::ALL`].
    pub fn iter(self) -> impl Iterator<Item = Component> {
        Component::ALL.into_iter().filter(move |&c| self.contains(c))
    }

    /// Just `c`.
    #[must_use]
    pub fn only(c: Component) -> ComponentSet {
        ComponentSet(1 << c as u8)
    }

    /// Whether `c` is in the set.
    #[must_use]
    pub fn contains(self, c: Component) -> bool {
        self.0 & (1 << c as u8) != 0
    }
}

/// The material's coefficients at a point, with their maps applied.
#[derive(Debug, Clone, Copy)]
pub struct Coefficients {
    ka: Vec3,
    kd: Vec3,
    ks: Vec3,
    ke: Vec3,
    n: f32,
    /// Km, times the mirror map where the material reflects.
    km: Vec3,
}

impl Coefficients {
    /// (Ka, Kd, Ks, Ke, n).
    #[must_use]
    pub fn parts(&self) -> (Vec3, Vec3, Vec3, Vec3, f32) {
        (self.ka, self.kd, self.ks, self.ke, self.n)
    }

    /// Km: the share of the environment mirrored (seed 002 eq. 4's
    /// reflection-map coefficient), its map applied.
    #[must_use]
    pub fn km(&self) -> Vec3 {
        self.km
    }

    /// The coefficients of a material without maps (`None` if it has any: then they
    /// vary over the surface and [`sample_maps`] samples them per point).
    #[must_use]
    pub fn constant(m: &Material) -> Option<Self> {
        let maps = &m.maps;
        let none = maps.ambient.is_empty()
            && maps.diffuse.is_empty()
            && maps.specular.is_empty()
            && maps.emission.is_empty()
            && maps.normal.is_none()
            && maps.mirror.is_none()
            && maps.roughness.is_none();
        none.then_some(Coefficients { ka: m.ka, kd: m.kd, ks: m.ks, ke: m.ke, n: m.shininess, km: m.km })
    }

    /// Samples every map of `m` at the point's uv (Ka and Kd times the
    /// point's vertex colour).
    #[must_use]
    pub fn at(m: &Material, s: &SurfacePoint) -> Self {
        Self::sampled(m, s, &mut SharedFootprint::default())
    }

    /// [`Coefficients::at`], the maps' footprints shared through `shared`.
    fn sampled<'a>(m: &'a Material, s: &SurfacePoint, shared: &mut SharedFootprint<'a>) -> Self {
        let filter = m.maps.filter;
        // A roughness baked into the specular map's alpha is read with Ks,
        // in one lookup.
        let (specular, n) = match (&m.maps.roughness, m.maps.specular.as_slice()) {
            (None, _) => (None, m.shininess),
            (Some(r), [ks]) if Arc::ptr_eq(r, ks) => {
                let (uv, duv) = s.coords(ks.set);
                let rgba = shared.sample_rgba(ks, filter, uv, duv);
                (Some(rgba.truncate()), phong_exponent(rgba.w))
            }
            (Some(r), _) => {
                let (uv, duv) = s.coords(r.set);
                (None, phong_exponent(shared.alpha(r, filter, uv, duv)))
            }
        };
        let mut sample = |t: &'a Texture| {
            let (uv, duv) = s.coords(t.set);
            shared.sample(t, filter, uv, duv)
        };
        // No map: the coefficient; several: one pass per map, added.
        let mut map = |maps: &'a [Arc<Texture>]| {
            if maps.is_empty() {
                Vec3::ONE
            } else {
                maps.iter().map(|t| sample(t)).sum()
            }
        };
        let diffuse = map(&m.maps.diffuse);
        // glTF's base colour is both maps: sampled once.
        let same = m.maps.ambient.len() == m.maps.diffuse.len()
            && m.maps.ambient.iter().zip(&m.maps.diffuse).all(|(a, d)| Arc::ptr_eq(a, d));
        Coefficients {
            ka: m.ka * s.color * if same { diffuse } else { map(&m.maps.ambient) },
            kd: m.kd * s.color * diffuse,
            ks: m.ks * specular.unwrap_or_else(|| map(&m.maps.specular)),
            ke: m.ke * map(&m.maps.emission),
            n,
            km: match &m.maps.mirror {
                Some(t) if m.reflects_environment() => m.km * sample(t),
                _ => m.km,
            },
        }
    }
}

/// Samples every map of `m` at `s`: the normal map tilts `s.normal`
/// ([`super::normal_map`]), the colour maps give the coefficients.
#[must_use]
pub fn sample_maps(m: &Material, s: &mut SurfacePoint) -> Coefficients {
    let mut shared = SharedFootprint::default();
    super::normal_map::apply_shared(m, s, &mut shared);
    Coefficients::sampled(m, s, &mut shared)
}

/// Adds light `light`'s ambient, diffuse and specular terms at `s` to `acc`, with
/// `shadow` ∈ [0, 1] (1 = lit) multiplying diffuse and specular only.
pub fn add_light(acc: &mut Components, light: &Light, k: &Coefficients, s: &SurfacePoint, shadow: f32) {
    acc.ambient += light.color * light.ambient * k.ka;
    let inc = light.incident(s.position);
    let cos_theta = s.normal.dot(inc.to_light);
    if cos_theta <= 0.0 || shadow <= 0.0 {
        return;
    }
    let r = 2.0 * cos_theta * s.normal - inc.to_light;
    let cos_alpha = r.dot(s.to_eye).max(0.0);
    acc.diffuse += shadow * inc.radiance * k.kd * cos_theta;
    acc.specular += shadow * inc.radiance * k.ks * phong_power(cos_alpha, k.n);
}

/// `x^n`, by repeated squaring when n is a small whole number (the usual case),
/// which is several times faster than `powf`.
#[must_use]
pub fn phong_power(x: f32, n: f32) -> f32 {
    if n.fract() == 0.0 && (0.0..=4096.0).contains(&n) {
        x.powi(n as i32)
    } else {
        x.powf(n)
    }
}
