//! Surface materials: the coefficients of seed 002 eq. 1 and their attribute maps.
//!
//! Each component (ambient Ka, diffuse Kd, specular Ks, emission Ke) may carry its
//! own texture, which multiplies that component only (seed 002 §3.2, "attribute
//! mapping"): a diffuse map never tints the highlight.

use std::sync::Arc;

use glam::{Vec2, Vec3};

pub use super::texture::Filter;
use super::texture::Texture;

/// A Phong material of seed 002 eq. 1.
#[derive(Debug, Clone)]
pub struct Material {
    /// Name, for messages.
    pub name: String,
    /// Ambient reflectance Ka.
    pub ka: Vec3,
    /// Diffuse reflectance Kd.
    pub kd: Vec3,
    /// Specular reflectance Ks.
    pub ks: Vec3,
    /// Phong exponent n.
    pub shininess: f32,
    /// Emitted radiance Ke (added once, not per light).
    pub ke: Vec3,
    /// Per-component texture maps.
    pub maps: ComponentMaps,
    /// Draw back faces too (no culling); shading uses the side facing the eye.
    pub two_sided: bool,
    /// Mirror reflectance Kr: the share of the reflected ray's light added (seed
    /// 002 §4, traced from the item buffer).
    pub kr: Vec3,
    /// Transmittance Kt: the share of the refracted ray's light added.
    pub kt: Vec3,
    /// Index of refraction of the material (the outside is taken as 1).
    pub ior: f32,
    /// Reflection-map coefficient Km (seed 002 eq. 4's Ke · Mape): the share of the
    /// environment seen in the mirror direction that is added, without tracing.
    pub km: Vec3,
    /// Opacity α (seed 002 §3.4): below 1 the surface is translucent and blended
    /// over what lies behind it. [`ComponentMaps::alpha`] multiplies it.
    pub opacity: f32,
    /// An alpha test (glTF's MASK mode): where the opacity (times its map)
    /// is at least this the surface is there, drawn opaque; elsewhere it is
    /// cut away, for the eye, the shadow maps and traced rays alike.
    pub cutoff: Option<f32>,
}

impl Material {
    /// Whether the material is translucent (drawn after the opaque surfaces,
    /// blended over them): an opacity below 1 or an alpha map, without an
    /// alpha test.
    #[must_use]
    pub fn translucent(&self) -> bool {
        self.cutoff.is_none() && (self.opacity < 1.0 || self.maps.alpha.is_some())
    }

    /// Whether the material's alpha test can cut some of its surface away.
    #[must_use]
    pub fn cuts_out(&self) -> bool {
        self.cutoff.is_some_and(|c| self.opacity < c || self.maps.alpha.as_ref().is_some_and(|t| t.translucent()))
    }

    /// The texture-coordinate set its alpha map is read at (0 without one).
    #[must_use]
    pub fn alpha_set(&self) -> u8 {
        self.maps.alpha.as_ref().map_or(0, |t| t.set)
    }

    /// The opacity at texture coordinates `uv` (of set [`Material::alpha_set`]) of a pixel whose texture
    /// footprint is `duv` (see [`Texture::alpha_footprint`]).
    #[must_use]
    pub fn alpha_at(&self, uv: Vec2, duv: [Vec2; 2]) -> f32 {
        self.opacity * self.maps.alpha.as_ref().map_or(1.0, |t| t.alpha_footprint(uv, duv))
    }

    /// Whether the alpha test keeps the surface at `uv` (bilinear at the
    /// texture's finest level; always where there is no test).
    #[must_use]
    pub fn covers(&self, uv: Vec2) -> bool {
        self.cutoff.is_none_or(|c| self.opacity * self.maps.alpha.as_ref().map_or(1.0, |t| t.alpha(uv)) >= c)
    }

    /// Whether it mirrors the environment (a Km above zero): the
    /// reflection-map pass looks the environment up where it is seen.
    #[must_use]
    pub fn reflects_environment(&self) -> bool {
        self.km.max_element() > 0.0
    }

    /// Whether shading this material needs secondary rays.
    #[must_use]
    pub fn traces(&self) -> bool {
        self.kr.max_element() > 0.0 || self.kt.max_element() > 0.0
    }
}

/// The Phong exponent of a microfacet roughness r: n = 2/α² − 2 with
/// α = r² (the Blinn-Phong exponent whose lobe is as wide as the microfacet
/// distribution's), rounded to a whole number within 1 to 2048 (whole
/// exponents are raised by repeated squaring, also eight lanes of different
/// exponents at once). r is taken as at least 0.05 (a mirror-like 2048).
#[must_use]
pub fn phong_exponent(roughness: f32) -> f32 {
    let alpha = if roughness.is_nan() { 1.0 } else { roughness.clamp(0.05, 1.0).powi(2) };
    (2.0 / (alpha * alpha) - 2.0).clamp(1.0, 2048.0).round()
}

/// The textures of each shading component (seed 002 §3.2, attribute mapping).
/// A component with several maps is several passes added: Kd · (map₁ + map₂ + …);
/// with none, the coefficient alone.
#[derive(Debug, Clone, Default)]
pub struct ComponentMaps {
    /// Multiply Ka.
    pub ambient: Vec<Arc<Texture>>,
    /// Multiply Kd.
    pub diffuse: Vec<Arc<Texture>>,
    /// Multiply Ks.
    pub specular: Vec<Arc<Texture>>,
    /// Multiply Ke.
    pub emission: Vec<Arc<Texture>>,
    /// Multiplies Km (a glTF metal's share of the environment it mirrors,
    /// where its metalness varies over a texture).
    pub mirror: Option<Arc<Texture>>,
    /// Multiplies the opacity (the alpha of glTF's base-colour texture, in
    /// BLEND or MASK mode).
    pub alpha: Option<Arc<Texture>>,
    /// Its alpha is a roughness r ∈ [0, 1] that sets the Phong exponent
    /// point by point ([`phong_exponent`]), in place of
    /// [`Material::shininess`] (a glTF roughness that varies over its
    /// texture; baked into the specular map's alpha, where one lookup reads
    /// both).
    pub roughness: Option<Arc<Texture>>,
    /// Tilts the shading normal (glTF's `normalTexture`).
    pub normal: Option<NormalMap>,
    /// How the maps are filtered.
    pub filter: Filter,
}

/// A tangent-space normal map as glTF defines it: red, green and blue hold x,
/// y and z of the normal in [−1, 1] mapped to [0, 1] (linear, not sRGB),
/// with x along increasing texture u, y along decreasing v (up the image) and
/// z out of the surface; `scale` multiplies x and y.
#[derive(Debug, Clone)]
pub struct NormalMap {
    /// The map.
    pub texture: Arc<Texture>,
    /// How strongly it tilts the normal: 1 as painted, 0 not at all.
    pub scale: f32,
}

impl Default for Material {
    fn default() -> Self {
        Material {
            name: "default".into(),
            ka: Vec3::splat(0.8),
            kd: Vec3::splat(0.8),
            ks: Vec3::splat(0.2),
            shininess: 32.0,
            ke: Vec3::ZERO,
            maps: ComponentMaps::default(),
            two_sided: false,
            kr: Vec3::ZERO,
            kt: Vec3::ZERO,
            ior: 1.5,
            km: Vec3::ZERO,
            opacity: 1.0,
            cutoff: None,
        }
    }
}

impl ComponentMaps {
    /// The single maps of each component, the normal map's and the mirror's
    /// (a component with several maps is left as it is).
    fn singles(&mut self) -> Vec<&mut Arc<Texture>> {
        fn one(v: &mut [Arc<Texture>]) -> Option<&mut Arc<Texture>> {
            if v.len() == 1 {
                v.first_mut()
            } else {
                None
            }
        }
        let (ambient, diffuse, specular, emission) =
            (&mut self.ambient, &mut self.diffuse, &mut self.specular, &mut self.emission);
        [
            one(diffuse),
            one(ambient),
            one(specular),
            one(emission),
            self.mirror.as_mut(),
            self.roughness.as_mut(),
            self.normal.as_mut().map(|n| &mut n.texture),
        ]
        .into_iter()
        .flatten()
        .collect()
    }
}

/// Stores the maps each material alone reads side by side in memory
/// ([`Texture::interleaved`]): those of its largest group of maps of one
/// size. A textured pixel reads several of its material's maps at one
/// place (a baked glTF material: diffuse, ambient, specular, mirror,
/// emission and normal, often all 2048²): interleaved, the lookups after
/// the first find their texels in the cache. A texture several materials
/// read stays where it is; one map serving two components (the same
/// texture) stays one.
pub fn interleave_maps<'a>(materials: impl IntoIterator<Item = &'a mut Material>) {
    let mut materials: Vec<&mut Material> = materials.into_iter().collect();
    let mut readers: std::collections::HashMap<usize, usize> = std::collections::HashMap::new();
    for m in materials.iter_mut() {
        let mut ids: Vec<usize> = m.maps.singles().iter().map(|t| t.texels_id()).collect();
        ids.extend(
            m.maps
                .alpha
                .iter()
                .chain(m.maps.ambient.iter())
                .chain(&m.maps.diffuse)
                .chain(&m.maps.specular)
                .chain(&m.maps.emission)
                .map(|t| t.texels_id()),
        );
        ids.sort_unstable();
        ids.dedup();
        for id in ids {
            *readers.entry(id).or_default() += 1;
        }
    }
    for m in materials.iter_mut() {
        let alpha = m.maps.alpha.as_ref().map(|t| t.texels_id());
        let mut slots = m.maps.singles();
        // The distinct textures only this material reads (an alpha map's
        // texels stay where its alpha test reads them).
        let mut own: Vec<Arc<Texture>> = Vec::new();
        for t in slots.iter() {
            let id = t.texels_id();
            if readers[&id] == 1 && Some(id) != alpha && !own.iter().any(|o| Arc::ptr_eq(o, t)) {
                own.push(Arc::clone(t));
            }
        }
        // Their largest group of one size.
        let count = |size| own.iter().filter(|t| t.size() == size).count();
        let Some(size) = own.iter().map(|t| t.size()).max_by_key(|&s| count(s)) else { continue };
        own.retain(|t| t.size() == size);
        let refs: Vec<&Texture> = own.iter().map(|t| &**t).collect();
        let Some(bundle) = Texture::interleaved(&refs) else { continue };
        let bundle: Vec<Arc<Texture>> = bundle.into_iter().map(Arc::new).collect();
        for slot in slots.iter_mut() {
            if let Some(k) = own.iter().position(|o| Arc::ptr_eq(o, slot)) {
                **slot = Arc::clone(&bundle[k]);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn map(width: u32, code: u8) -> Arc<Texture> {
        Arc::new(Texture::from_texels_8bit(width, 4, vec![[code, 0, 0, 255]; width as usize * 4], true))
    }

    /// A material's own maps of its most common size are bundled (a map
    /// serving two components stays one); a map another material reads,
    /// and one of another size, stay where they are.
    #[test]
    fn a_materials_own_maps_of_one_size_are_stored_together() {
        let (base, shared, small) = (map(8, 10), map(8, 20), map(2, 30));
        let mut own = Material::default();
        own.maps.diffuse = vec![Arc::clone(&base)];
        own.maps.ambient = vec![Arc::clone(&base)];
        own.maps.specular = vec![map(8, 40)];
        own.maps.emission = vec![Arc::clone(&small)];
        own.maps.normal = Some(NormalMap { texture: Arc::clone(&shared), scale: 1.0 });
        own.maps.mirror = Some(map(8, 50));
        let mut other = Material::default();
        other.maps.diffuse = vec![Arc::clone(&shared)];
        let mut materials = [own, other];
        interleave_maps(&mut materials);
        let maps = &materials[0].maps;
        let (diffuse, specular, mirror) = (&maps.diffuse[0], &maps.specular[0], maps.mirror.as_ref().expect("kept"));
        assert!(diffuse.shares_texels(specular) && diffuse.shares_texels(mirror));
        assert!(Arc::ptr_eq(diffuse, &maps.ambient[0]), "one map for two components stays one");
        assert!(maps.emission[0].shares_texels(&small), "another size stays");
        let normal = &maps.normal.as_ref().expect("kept").texture;
        assert!(normal.shares_texels(&shared) && materials[1].maps.diffuse[0].shares_texels(&shared));
        // What each reads is unchanged.
        let uv = Vec2::new(0.3, 0.6);
        assert_eq!(diffuse.sample(uv), base.sample(uv));
        assert_eq!(mirror.sample(uv), map(8, 50).sample(uv));
    }
}
