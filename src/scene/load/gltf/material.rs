//! Materials: a glTF material as kage's ([`Material`]), its textures
//! decoded once each and read at one or two sets of texture coordinates
//! ([`Channels`]), its metallic-roughness surface baked into Phong
//! coefficient maps ([`Surface`]).

use std::path::Path;
use std::sync::Arc;

use glam::{Vec2, Vec3, Vec4};

use super::{data_uri, percent_decoded, Context};
use crate::scene::load::Files;
use crate::scene::texture::{encode_8bit, Edge, Wrap};
use crate::scene::{phong_exponent, ComponentMaps, Material, NormalMap, Texture};

/// The texture coordinates a material's textures are read at: a set
/// (`TEXCOORD_n`) and a `KHR_texture_transform`.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub(super) struct Coordinates {
    pub(super) set: u32,
    pub(super) transform: Option<glam::Affine2>,
}

impl Coordinates {
    /// Where `info`'s texture is read.
    fn of(info: &gltf::texture::Info) -> Coordinates {
        let Some(t) = info.texture_transform() else { return Coordinates { set: info.tex_coord(), transform: None } };
        let set = t.tex_coord().unwrap_or(info.tex_coord());
        Coordinates::transformed(set, Vec2::from(t.offset()), t.rotation(), Vec2::from(t.scale()))
    }

    /// Where a normal or occlusion texture is read: its set, and its
    /// `KHR_texture_transform` as the JSON `transform` gives it (the gltf
    /// crate reads the extension on the other textures only).
    fn of_json(set: u32, transform: Option<&gltf::json::Value>) -> Coordinates {
        let Some(t) = transform else { return Coordinates { set, transform: None } };
        let pair = |key: &str, default: f32| {
            let v = t.get(key).and_then(gltf::json::Value::as_array);
            let at =
                |k: usize| v.and_then(|v| v.get(k)).and_then(gltf::json::Value::as_f64).map_or(default, |x| x as f32);
            Vec2::new(at(0), at(1))
        };
        let rotation = t.get("rotation").and_then(gltf::json::Value::as_f64).map_or(0.0, |r| r as f32);
        let set = t.get("texCoord").and_then(gltf::json::Value::as_u64).map_or(set, |s| s as u32);
        Coordinates::transformed(set, pair("offset", 0.0), rotation, pair("scale", 1.0))
    }

    /// uv' = T · R · S · uv (the extension's own order), R turning (0, 1)
    /// towards (1, 0) by `rotation` (the sample model's arrow marks the
    /// direction); no transform where a value is not finite.
    fn transformed(set: u32, offset: Vec2, rotation: f32, scale: Vec2) -> Coordinates {
        let transform = glam::Affine2::from_translation(offset)
            * glam::Affine2::from_angle(-rotation)
            * glam::Affine2::from_scale(scale);
        let finite = transform.to_cols_array().iter().all(|v| v.is_finite());
        Coordinates { set, transform: finite.then_some(transform) }
    }
}

/// Where a normal texture is read.
fn normal_at(t: &gltf::material::NormalTexture) -> Coordinates {
    Coordinates::of_json(t.tex_coord(), t.extension_value("KHR_texture_transform"))
}

/// Where an occlusion texture is read.
fn occlusion_at(t: &gltf::material::OcclusionTexture) -> Coordinates {
    Coordinates::of_json(t.tex_coord(), t.extension_value("KHR_texture_transform"))
}

/// The (at most two) texture coordinates a material's textures are read
/// at: the first texture's, and the first other one's (a mesh's
/// [`Mesh::uvs`] and [`Mesh::uvs1`]).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub(super) struct Channels {
    pub(super) first: Coordinates,
    pub(super) second: Option<Coordinates>,
}

impl Channels {
    /// The set (0 or 1) that reads `c`, if one does.
    fn set_of(&self, c: Coordinates) -> Option<u8> {
        if c == self.first {
            Some(0)
        } else {
            (self.second == Some(c)).then_some(1)
        }
    }
}

impl Context<'_> {
    /// `m` as kage's material, and the texture coordinates its textures are
    /// read at.
    pub(super) fn material(&self, m: &gltf::Material) -> (Material, Channels) {
        let pbr = m.pbr_metallic_roughness();
        let [r, g, b, a] = pbr.base_color_factor();
        let name = m.name().unwrap_or("gltf").to_string();
        let at = self.coordinates(m, &name);
        let set = |c: Coordinates| at.set_of(c).unwrap_or(0);
        let base_map = pbr.base_color_texture().map(|t| self.texture(&t.texture(), true, set(Coordinates::of(&t))));
        // The metallic-roughness and occlusion textures are baked with the
        // base colour's, texel by texel: only where they share its coordinates.
        let base_set = base_map.as_ref().map_or(0, |t| t.set);
        let shares = |c: Coordinates, what: &str| {
            let same = set(c) == base_set;
            if !same {
                self.warnings.borrow_mut().push(format!(
                    "material '{name}': its {what} texture is read at other texture coordinates than its base \
                     colour's (TEXCOORD_{}); it is not drawn",
                    c.set
                ));
            }
            same
        };
        let surface = Surface {
            base: Vec3::new(r, g, b),
            base_map,
            metal: pbr.metallic_factor().clamp(0.0, 1.0),
            roughness: pbr.roughness_factor().clamp(0.0, 1.0),
            metal_roughness_map: pbr
                .metallic_roughness_texture()
                .filter(|t| shares(Coordinates::of(t), "metallic-roughness"))
                .map(|t| self.texture(&t.texture(), false, base_set)),
            occlusion: m
                .occlusion_texture()
                .filter(|t| shares(occlusion_at(t), "occlusion"))
                .map(|t| (self.texture(&t.texture(), false, base_set), t.strength().clamp(0.0, 1.0))),
            dielectric: m.specular().map_or(Vec3::splat(0.04), |s| {
                let f0 = Vec3::from(s.specular_color_factor()) * s.specular_factor() * 0.04;
                if f0.is_finite() {
                    f0.clamp(Vec3::ZERO, Vec3::ONE)
                } else {
                    Vec3::splat(0.04)
                }
            }),
            coat: m
                .extension_value("KHR_materials_clearcoat")
                .and_then(|c| c.get("clearcoatFactor"))
                .and_then(gltf::json::Value::as_f64)
                .filter(|c| c.is_finite())
                .map_or(0.0, |c| c.clamp(0.0, 1.0) as f32),
            sheen: sheen_colour(m) * SHEEN_ALBEDO,
        };
        let transmission = m.transmission().map_or(0.0, |t| t.transmission_factor().clamp(0.0, 1.0));
        let mut out = surface.material();
        out.name = name;
        let strength = m.emissive_strength().filter(|s| s.is_finite() && *s >= 0.0).unwrap_or(1.0);
        out.ke = Vec3::from(m.emissive_factor()) * strength;
        out.maps.emission = m
            .emissive_texture()
            .map(|t| self.texture(&t.texture(), true, set(Coordinates::of(&t))))
            .into_iter()
            .collect();
        out.maps.normal = m
            .normal_texture()
            .map(|t| {
                let texture = self.texture(&t.texture(), false, set(normal_at(&t)));
                NormalMap { texture, scale: t.scale() }
            })
            .filter(|n| n.scale.is_finite() && n.scale != 0.0);
        out.two_sided = m.double_sided();
        // The base colour's alpha (factor times texture): blended over what
        // lies behind (BLEND), or cutting the surface where it is below the
        // cutoff (MASK); OPAQUE ignores it.
        let alpha_map = surface.base_map.clone().filter(|t| t.translucent());
        match m.alpha_mode() {
            gltf::material::AlphaMode::Opaque => {}
            gltf::material::AlphaMode::Blend => (out.opacity, out.maps.alpha) = (a.clamp(0.0, 1.0), alpha_map),
            gltf::material::AlphaMode::Mask => {
                let cutoff = m.alpha_cutoff().filter(|c| c.is_finite()).unwrap_or(0.5);
                (out.opacity, out.maps.alpha, out.cutoff) = (a.clamp(0.0, 1.0), alpha_map, Some(cutoff));
            }
        }
        if transmission > 0.0 {
            // Light through the surface, tinted by the base colour, bent by
            // the index of refraction; what goes through is not diffused.
            out.kt = surface.base * transmission;
            out.kd *= 1.0 - transmission;
            out.ka *= 1.0 - transmission;
            out.kr = Vec3::splat(0.04 * transmission);
        }
        out.ior = m.ior().filter(|n| n.is_finite() && *n >= 1.0).unwrap_or(1.5);
        if m.unlit() {
            // KHR_materials_unlit: the base colour as it is, lit or not.
            out = Material {
                name: out.name,
                ka: Vec3::ZERO,
                kd: Vec3::ZERO,
                ks: Vec3::ZERO,
                ke: surface.base,
                opacity: out.opacity,
                cutoff: out.cutoff,
                two_sided: out.two_sided,
                maps: ComponentMaps {
                    emission: surface.base_map.into_iter().collect(),
                    alpha: out.maps.alpha,
                    ..ComponentMaps::default()
                },
                ..Material::default()
            };
        }
        (out, at)
    }

    /// The coordinates `m`'s textures are read at: its base colour's (else
    /// its first texture's), and the first other ones a texture asks for; a
    /// warning when its textures ask for more than two.
    fn coordinates(&self, m: &gltf::Material, name: &str) -> Channels {
        let pbr = m.pbr_metallic_roughness();
        let infos = [pbr.base_color_texture(), pbr.metallic_roughness_texture(), m.emissive_texture()];
        let others = [m.normal_texture().map(|t| normal_at(&t)), m.occlusion_texture().map(|t| occlusion_at(&t))];
        let all: Vec<Coordinates> =
            infos.iter().flatten().map(Coordinates::of).chain(others.into_iter().flatten()).collect();
        let first = all.first().copied().unwrap_or_default();
        let channels = Channels { first, second: all.iter().copied().find(|c| *c != first) };
        if let Some(lost) = all.iter().find(|c| channels.set_of(**c).is_none()) {
            self.warnings.borrow_mut().push(format!(
                "material '{name}': its textures are read at more than two texture coordinates or transforms; those \
                 at TEXCOORD_{} are drawn at its first texture's (TEXCOORD_{})",
                lost.set, first.set
            ));
        }
        channels
    }

    /// The texture of `t`'s image, read at coordinate set `set` (0 or 1),
    /// decoded once however many materials use it; one that cannot be read
    /// or decoded is a warning and a magenta checker ([`super::placeholder`]).
    fn texture(&self, t: &gltf::Texture, srgb: bool, set: u8) -> Arc<Texture> {
        let decoded = self.decoded(t, srgb);
        let wrap = wrap(t.sampler());
        if decoded.wrap == wrap && decoded.set == set {
            return decoded;
        }
        // The decoded image is shared; only the wrap mode and the
        // coordinates read are the texture's own.
        let mut texture = Texture::clone(&decoded);
        (texture.wrap, texture.set) = (wrap, set);
        Arc::new(texture)
    }

    /// The image of `t` decoded (once per image and colour space), wrapping
    /// as it may.
    fn decoded(&self, t: &gltf::Texture, srgb: bool) -> Arc<Texture> {
        let key = (t.source().index(), srgb);
        if let Some(done) = self.textures.borrow().get(&key) {
            return Arc::clone(done);
        }
        let texture = decode(&self.buffers, self.dir, self.from, t, srgb, &mut self.warnings.borrow_mut());
        self.textures.borrow_mut().insert(key, Arc::clone(&texture));
        texture
    }

    /// Decodes every image the materials use, in each colour space they
    /// use it in, on all workers at once (a helmet's five 2048² images take
    /// about one worker's time each); the materials then find them decoded.
    pub(super) fn decode_all(&self) {
        use rayon::prelude::*;
        let mut wanted: Vec<(gltf::Texture, bool)> = Vec::new();
        for m in self.doc.materials() {
            let pbr = m.pbr_metallic_roughness();
            let colour = [pbr.base_color_texture(), m.emissive_texture()].into_iter().flatten().map(|i| i.texture());
            let data = pbr.metallic_roughness_texture().map(|i| i.texture());
            let data = data.into_iter().chain(m.occlusion_texture().map(|t| t.texture()));
            let data = data.chain(m.normal_texture().map(|t| t.texture()));
            wanted.extend(colour.map(|t| (t, true)).chain(data.map(|t| (t, false))));
        }
        wanted.sort_by_key(|(t, srgb)| (t.source().index(), *srgb));
        wanted.dedup_by_key(|(t, srgb)| (t.source().index(), *srgb));
        let (buffers, dir, from) = (&self.buffers, self.dir, self.from);
        let decoded: Vec<_> = wanted
            .par_iter()
            .map(|(t, srgb)| {
                let mut warnings = Vec::new();
                let texture = decode(buffers, dir, from, t, *srgb, &mut warnings);
                ((t.source().index(), *srgb), texture, warnings)
            })
            .collect();
        for (key, texture, warnings) in decoded {
            self.textures.borrow_mut().insert(key, texture);
            self.warnings.borrow_mut().extend(warnings);
        }
    }
}

/// The image of `t` decoded from `buffers` or a file beside the model (in
/// `dir`, read through `from`); one that cannot be read or decoded is a
/// warning in `warnings` and a magenta checker.
fn decode(
    buffers: &[Vec<u8>],
    dir: &Path,
    from: Files,
    t: &gltf::Texture,
    srgb: bool,
    warnings: &mut Vec<String>,
) -> Arc<Texture> {
    let bytes = match t.source().source() {
        gltf::image::Source::View { view, .. } => buffers
            .get(view.buffer().index())
            .ok_or_else(|| "its buffer view's buffer is missing".to_string())
            .and_then(|data| {
                let range = view.offset()..view.offset().saturating_add(view.length());
                data.get(range).map(<[u8]>::to_vec).ok_or_else(|| "its buffer view is outside its buffer".into())
            }),
        gltf::image::Source::Uri { uri, .. } if uri.starts_with("data:") => data_uri(uri),
        gltf::image::Source::Uri { uri, .. } => {
            let path = dir.join(percent_decoded(uri));
            return super::super::texture_or_placeholder(&path, srgb, from.assets, from.limits, warnings);
        }
    };
    bytes.and_then(|bytes| Texture::decode(&bytes, srgb, from.limits)).map(Arc::new).unwrap_or_else(|e| {
        warnings.push(format!("embedded image {}: {e}; drawn as a magenta checker", t.source().index()));
        super::super::placeholder()
    })
}

/// The wrap modes of a glTF sampler.
fn wrap(sampler: gltf::texture::Sampler) -> Wrap {
    use gltf::texture::WrappingMode;
    let edge = |mode| match mode {
        WrappingMode::ClampToEdge => Edge::Clamp,
        WrappingMode::MirroredRepeat => Edge::Mirror,
        WrappingMode::Repeat => Edge::Repeat,
    };
    match (edge(sampler.wrap_s()), edge(sampler.wrap_t())) {
        (Edge::Repeat, Edge::Repeat) => Wrap::Repeat,
        (across, down) => Wrap::Each(across, down),
    }
}

/// A metallic-roughness surface, factors and textures as the file gives
/// them, before it becomes kage's Phong coefficients.
struct Surface {
    base: Vec3,
    base_map: Option<Arc<Texture>>,
    metal: f32,
    roughness: f32,
    /// Roughness in green, metalness in blue (linear).
    metal_roughness_map: Option<Arc<Texture>>,
    /// Occlusion in red (linear), with its strength.
    occlusion: Option<(Arc<Texture>, f32)>,
    /// A dielectric's reflectance at normal incidence: 0.04, or
    /// `KHR_materials_specular`'s colour × strength × 0.04.
    dielectric: Vec3,
    /// `KHR_materials_clearcoat`'s factor: a clear layer mirroring 4% of the
    /// environment over the surface.
    coat: f32,
    /// `KHR_materials_sheen`'s colour factor times [`SHEEN_ALBEDO`]: what
    /// the sheen layer adds to the diffuse reflectance.
    sheen: Vec3,
}

/// The share of light a sheen layer of colour 1 reflects, taken as one
/// number: the sheen (a velvet's grazing glow) is approximated as a diffuse
/// tint of its colour over a base dimmed by as much, as the glTF extension
/// layers it. 0.25 is about the mean directional albedo of its
/// "Charlie" distribution at medium sheen roughness.
const SHEEN_ALBEDO: f32 = 0.25;

impl Surface {
    /// Base colour, metalness, roughness and occlusion at `uv`.
    fn at(&self, uv: Vec2) -> (Vec3, f32, f32, f32) {
        let base = self.base * self.base_map.as_ref().map_or(Vec3::ONE, |t| t.sample(uv));
        let mr = self.metal_roughness_map.as_ref().map_or(Vec3::ONE, |t| t.sample(uv));
        let occlusion = self.occlusion.as_ref().map_or(1.0, |(t, strength)| 1.0 + strength * (t.sample(uv).x - 1.0));
        (base, (self.metal * mr.z).clamp(0.0, 1.0), (self.roughness * mr.y).clamp(0.0, 1.0), occlusion)
    }

    /// Kd: the base's diffuse share (base · (1 − metal)), dimmed by what a
    /// sheen layer over it reflects and tinted by it.
    fn diffuse(&self, base: Vec3, metal: f32) -> Vec3 {
        base * (1.0 - metal) * (1.0 - self.sheen.max_element()) + self.sheen
    }

    /// Ks = mix(F0, base, metal) with the roughness beside it (in alpha).
    fn specular(&self, base: Vec3, metal: f32, roughness: f32) -> Vec4 {
        self.dielectric.lerp(base, metal).extend(roughness)
    }

    /// Km: the environment a metal mirrors (base · metal), and a clear
    /// coat's 4% over it.
    fn mirrored(&self, base: Vec3, metal: f32) -> Vec3 {
        base * metal + Vec3::splat(0.04 * self.coat)
    }

    /// Kd = base · (1 − metal), Ka = Kd · occlusion, Ks = mix(F0, base,
    /// metal) with F0 the dielectric's reflectance (0.04 unless
    /// `KHR_materials_specular` says otherwise), Km = base · metal (the
    /// environment a metal mirrors) plus 0.04 × a clear coat's factor; with a
    /// metallic-roughness or occlusion texture each is a texture baked texel by
    /// texel, else the base-colour texture multiplies Kd and Ka. The Phong
    /// exponent comes from the roughness: with a metallic-roughness
    /// texture texel by texel (baked into the Ks map's alpha), else the
    /// factor's.
    fn material(&self) -> Material {
        let Some(size) = self.baked_size() else {
            let kd = self.diffuse(self.base, self.metal);
            return Material {
                ka: kd,
                kd,
                ks: self.dielectric.lerp(self.base, self.metal),
                km: self.mirrored(self.base, self.metal),
                shininess: phong_exponent(self.roughness),
                maps: ComponentMaps {
                    ambient: self.base_map.iter().cloned().collect(),
                    diffuse: self.base_map.iter().cloned().collect(),
                    ..ComponentMaps::default()
                },
                ..Material::default()
            };
        };
        // The baked maps wrap and read coordinates as the base colour's map
        // (else the first map baked) does.
        let maps = [self.base_map.as_ref(), self.metal_roughness_map.as_ref(), self.occlusion.as_ref().map(|(t, _)| t)];
        let like: &Texture = maps.into_iter().flatten().next().expect("a baked size comes from a map");
        // One lookup of the textures per texel, for all four maps; the
        // specular map's alpha holds the roughness.
        // Without an occlusion texture Ka is Kd texel for texel: one map,
        // sampled once for both.
        let [diffuse, ambient, specular, mirror] = if self.occlusion.is_some() {
            bake(size, like, |uv| {
                let (base, metal, rough, occlusion) = self.at(uv);
                let kd = self.diffuse(base, metal);
                [
                    kd.extend(1.0),
                    (kd * occlusion).extend(1.0),
                    self.specular(base, metal, rough),
                    self.mirrored(base, metal).extend(1.0),
                ]
            })
        } else {
            let [diffuse, specular, mirror] = bake(size, like, |uv| {
                let (base, metal, rough, _) = self.at(uv);
                [
                    self.diffuse(base, metal).extend(1.0),
                    self.specular(base, metal, rough),
                    self.mirrored(base, metal).extend(1.0),
                ]
            });
            [Arc::clone(&diffuse), diffuse, specular, mirror]
        };
        // The mean roughness's exponent, for a reader of the coefficients
        // alone; with a roughness texture the shading reads it texel by texel.
        let n = 64usize;
        let samples = (0..n * n).map(|i| Vec2::new((i % n) as f32 + 0.5, (i / n) as f32 + 0.5) / n as f32);
        let (metal, rough) = samples.fold((0.0, 0.0), |(m, r), uv| {
            let (_, metal, roughness, _) = self.at(uv);
            (m + metal, r + roughness)
        });
        let count = (n * n) as f32;
        // A metal or a clear coat anywhere: Km from the baked map, texel by texel.
        let mirrors = metal > 0.0 || self.coat > 0.0;
        Material {
            ka: Vec3::ONE,
            kd: Vec3::ONE,
            ks: Vec3::ONE,
            km: if mirrors { Vec3::ONE } else { Vec3::ZERO },
            shininess: phong_exponent(rough / count),
            maps: ComponentMaps {
                ambient: vec![ambient],
                diffuse: vec![diffuse],
                roughness: self.metal_roughness_map.is_some().then(|| Arc::clone(&specular)),
                specular: vec![specular],
                mirror: mirrors.then_some(mirror),
                ..ComponentMaps::default()
            },
            ..Material::default()
        }
    }

    /// The size of the largest texture when a texture varies more than the
    /// base colour (metalness, roughness or occlusion); `None` otherwise.
    /// A sheen over a base-colour texture is baked too (it is added to Kd,
    /// not multiplied).
    fn baked_size(&self) -> Option<(u32, u32)> {
        let sheen = self.sheen != Vec3::ZERO && self.base_map.is_some();
        if self.metal_roughness_map.is_none() && self.occlusion.is_none() && !sheen {
            return None;
        }
        let maps = [self.base_map.as_ref(), self.metal_roughness_map.as_ref(), self.occlusion.as_ref().map(|(t, _)| t)];
        maps.into_iter().flatten().map(|t| t.size()).reduce(|a, b| (a.0.max(b.0), a.1.max(b.1)))
    }
}

/// `KHR_materials_sheen`'s colour factor (black without one; its textures
/// are not read).
fn sheen_colour(m: &gltf::Material) -> Vec3 {
    let Some(sheen) = m.extension_value("KHR_materials_sheen") else { return Vec3::ZERO };
    let factor = sheen.get("sheenColorFactor").and_then(gltf::json::Value::as_array);
    let channel = |k: usize| factor.and_then(|f| f.get(k)).and_then(gltf::json::Value::as_f64).unwrap_or(0.0);
    let colour = Vec3::new(channel(0) as f32, channel(1) as f32, channel(2) as f32);
    if colour.is_finite() {
        colour.clamp(Vec3::ZERO, Vec3::ONE)
    } else {
        Vec3::ZERO
    }
}

/// `N` `width × height` colour textures of `f`'s `N` values at each texel
/// centre's uv, kept in 8 bits (sRGB) as the images they come from.
/// Each wraps and reads the coordinates `like` does.
fn bake<const N: usize>(
    (width, height): (u32, u32),
    like: &Texture,
    f: impl Fn(Vec2) -> [Vec4; N] + Sync,
) -> [Arc<Texture>; N] {
    use rayon::prelude::*;
    let size = Vec2::new(width as f32, height as f32);
    let texels: Vec<[[u8; 4]; N]> = (0..width * height)
        .into_par_iter()
        .map(|i| {
            f(Vec2::new((i % width) as f32 + 0.5, (i / width) as f32 + 0.5) / size).map(|c| {
                let [r, g, b, _] = encode_8bit(c.truncate(), true);
                [r, g, b, (c.w.clamp(0.0, 1.0) * 255.0 + 0.5) as u8]
            })
        })
        .collect();
    std::array::from_fn(|k| {
        let mut baked = Texture::from_texels_8bit(width, height, texels.iter().map(|t| t[k]).collect(), true);
        (baked.wrap, baked.set) = (like.wrap, like.set);
        Arc::new(baked)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 2 × 1 texture: `left` and `right`.
    fn two_texels(left: Vec3, right: Vec3) -> Arc<Texture> {
        Arc::new(Texture::from_texels(2, 1, vec![left, right]))
    }

    #[test]
    fn a_metal_only_where_its_texture_says_mirrors_only_there() {
        // Red base; metal on the left half (blue channel), not on the right.
        let surface = Surface {
            base: Vec3::new(0.8, 0.1, 0.1),
            base_map: None,
            metal: 1.0,
            roughness: 0.5,
            metal_roughness_map: Some(two_texels(Vec3::new(0.0, 1.0, 1.0), Vec3::new(0.0, 1.0, 0.0))),
            occlusion: None,
            dielectric: Vec3::splat(0.04),
            coat: 0.0,
            sheen: Vec3::ZERO,
        };
        let m = surface.material();
        let mirror = m.maps.mirror.as_ref().expect("a mirror map");
        let (left, right) = (Vec2::new(0.25, 0.5), Vec2::new(0.75, 0.5));
        let km = |uv| m.km * mirror.sample(uv);
        let kd = |uv| m.kd * m.maps.diffuse[0].sample(uv);
        assert!((km(left) - surface.base).abs().max_element() < 0.05, "metal half mirrors its base: {}", km(left));
        assert!(km(right).max_element() < 0.05, "the other half does not mirror: {}", km(right));
        assert!(kd(left).max_element() < 0.05 && (kd(right) - surface.base).abs().max_element() < 0.05);
        // No occlusion texture: Ka is Kd's map, one texture sampled once.
        assert!(Arc::ptr_eq(&m.maps.ambient[0], &m.maps.diffuse[0]));
    }

    /// A roughness texture rides in the baked specular map's alpha (one
    /// texture: read with Ks), texel by texel, times the roughness factor;
    /// without one the exponent is the factor's and no map is made.
    #[test]
    fn a_roughness_texture_is_baked_beside_the_specular_reflectance() {
        let surface = |map: bool| Surface {
            base: Vec3::new(0.8, 0.1, 0.1),
            base_map: None,
            metal: 0.0,
            roughness: 0.5,
            metal_roughness_map: map.then(|| two_texels(Vec3::new(0.0, 0.2, 0.0), Vec3::new(0.0, 1.0, 0.0))),
            occlusion: None,
            dielectric: Vec3::splat(0.04),
            coat: 0.0,
            sheen: Vec3::ZERO,
        };
        let m = surface(true).material();
        let roughness = m.maps.roughness.as_ref().expect("a roughness map");
        assert!(Arc::ptr_eq(roughness, &m.maps.specular[0]));
        let (left, right) = (roughness.alpha(Vec2::new(0.25, 0.5)), roughness.alpha(Vec2::new(0.75, 0.5)));
        assert!((left - 0.1).abs() <= 1.0 / 255.0 && (right - 0.5).abs() <= 1.0 / 255.0, "{left} {right}");
        let ks = m.ks * m.maps.specular[0].sample(Vec2::new(0.25, 0.5));
        assert!((ks - Vec3::splat(0.04)).abs().max_element() < 0.005, "{ks}");
        let plain = surface(false).material();
        assert!(plain.maps.roughness.is_none());
        assert_eq!(plain.shininess, phong_exponent(0.5));
    }

    /// `KHR_materials_specular` sets a dielectric's highlight (none at
    /// strength 0; tinted by its colour), not a metal's; a clear coat
    /// mirrors 4% of the environment over a surface that mirrors nothing
    /// else, textured or not.
    #[test]
    fn specular_strength_and_a_clear_coat_reach_the_coefficients() {
        let plain = |metal: f32, dielectric: Vec3, coat: f32, map: bool| Surface {
            base: Vec3::new(0.2, 0.6, 0.2),
            base_map: None,
            metal,
            roughness: 0.5,
            metal_roughness_map: map.then(|| two_texels(Vec3::ONE, Vec3::ONE)),
            occlusion: None,
            dielectric,
            coat,
            sheen: Vec3::ZERO,
        };
        assert_eq!(plain(0.0, Vec3::ZERO, 0.0, false).material().ks, Vec3::ZERO);
        let tinted = plain(0.0, Vec3::new(0.04, 0.0, 0.0), 0.0, false).material().ks;
        assert!(tinted.x > 0.03 && tinted.y == 0.0, "{tinted}");
        assert_eq!(plain(1.0, Vec3::ZERO, 0.0, false).material().ks, Vec3::new(0.2, 0.6, 0.2));
        assert!((plain(0.0, Vec3::splat(0.04), 1.0, false).material().km - Vec3::splat(0.04)).length() < 1e-6);
        let baked = plain(0.0, Vec3::splat(0.04), 1.0, true).material();
        let mirror = baked.maps.mirror.as_ref().expect("a coat mirrors where nothing else does");
        let km = baked.km * mirror.sample(Vec2::splat(0.5));
        assert!((km - Vec3::splat(0.04)).abs().max_element() < 0.01, "{km}");
    }

    /// A black cloth under a red sheen comes out red, not black; a sheen
    /// over a textured base tints the baked Kd map as it tints a constant
    /// one; no sheen leaves Kd as it was.
    #[test]
    fn a_sheen_tints_the_diffuse_reflectance() {
        let cloth = |base: Vec3, map: bool, sheen: Vec3| Surface {
            base,
            base_map: map.then(|| two_texels(Vec3::ONE, Vec3::ONE)),
            metal: 0.0,
            roughness: 0.8,
            metal_roughness_map: None,
            occlusion: None,
            dielectric: Vec3::splat(0.04),
            coat: 0.0,
            sheen: sheen * SHEEN_ALBEDO,
        };
        let red = Vec3::new(1.0, 0.0, 0.0);
        let kd = |s: &Surface| {
            let m = s.material();
            m.kd * m.maps.diffuse.first().map_or(Vec3::ONE, |t| t.sample(Vec2::splat(0.5)))
        };
        assert_eq!(kd(&cloth(Vec3::ZERO, false, Vec3::ZERO)), Vec3::ZERO);
        let plain = kd(&cloth(Vec3::ZERO, false, red));
        assert!((plain - red * SHEEN_ALBEDO).length() < 1e-6, "{plain}");
        let textured = kd(&cloth(Vec3::ZERO, true, red));
        assert!((textured - plain).abs().max_element() < 0.01, "{textured} vs {plain}");
        let grey = kd(&cloth(Vec3::splat(0.5), false, red));
        assert!((grey - Vec3::new(0.5 * 0.75 + 0.25, 0.375, 0.375)).length() < 1e-6, "{grey}");
    }

    /// A normal or occlusion texture's transform, read from its JSON, is the
    /// one the gltf crate gives the other textures for the same numbers.
    #[test]
    fn a_transform_read_from_json_is_the_typed_ones() {
        let json: gltf::json::Value = gltf::json::deserialize::from_str(
            r#"{"offset": [0.5, -0.25], "rotation": 0.7, "scale": [2, 3], "texCoord": 1}"#,
        )
        .unwrap();
        let c = Coordinates::of_json(0, Some(&json));
        assert_eq!(c, Coordinates::transformed(1, Vec2::new(0.5, -0.25), 0.7, Vec2::new(2.0, 3.0)));
        let moved = c.transform.unwrap().transform_point2(Vec2::ZERO);
        assert!((moved - Vec2::new(0.5, -0.25)).length() < 1e-6);
        assert_eq!(Coordinates::of_json(2, None), Coordinates { set: 2, transform: None });
    }
}
