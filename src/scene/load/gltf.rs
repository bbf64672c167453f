//! glTF 2.0 (`.gltf` and `.glb`): node transforms, materials, the first camera and
//! `KHR_lights_punctual` lights.
//!
//! Metallic-roughness materials map onto seed 002's Phong coefficients:
//! Kd = base colour · (1 − metallic), Ka = Kd · occlusion, Ks = mix(0.04, base
//! colour, metallic), Km = base colour · metallic (a metal mirrors the
//! environment: a lone model gets a studio one), n = 2/α² − 2 with α =
//! roughness² (the Blinn-Phong exponent of equal lobe width), Ke = emissive.
//! The base-colour texture multiplies Kd and Ka; with a metallic-roughness or
//! occlusion texture, Kd, Ka and Ks are baked into textures texel by texel
//! (Km and n take the material's mean). `KHR_materials_transmission` makes
//! Kt = base colour · transmission (Kd scaled by what is not transmitted),
//! `KHR_materials_ior` the index of refraction. The normal texture tilts the
//! shading normal (`shading/normal_map.rs`: tangents from the texture
//! coordinates; a `TANGENT` attribute is not read). Buffers and images may be
//! files, GLB chunks or `data:` URIs.

use std::cell::{Cell, RefCell};
use std::collections::HashMap;
use std::path::Path;
use std::sync::Arc;

use glam::{Affine3A, Mat4, Vec2, Vec3};

use super::{checked, Files, LoadedModel, Part};
use crate::camera::{Camera, Projection};
use crate::limits::{Limit, LimitExceeded};
use crate::scene::mesh::{Mesh, NormalMode};
use crate::scene::{ComponentMaps, Falloff, Light, LightKind, Material, NormalMap, Texture};

struct Context<'a> {
    doc: gltf::Document,
    buffers: Vec<Vec<u8>>,
    dir: &'a Path,
    from: Files<'a>,
    path: &'a Path,
    /// Nodes placed so far ([`Limit::Instances`]): 40 nodes each listing the
    /// next twice would place 2⁴⁰.
    placed: Cell<u64>,
    /// Textures decoded so far, by image and colour space: materials share them.
    textures: RefCell<HashMap<(usize, bool), Arc<Texture>>>,
}

/// Parses glTF or GLB bytes; `path` locates external buffers and images
/// (read through `from`, within its limits).
pub(super) fn load(bytes: &[u8], path: &Path, from: Files) -> Result<LoadedModel, String> {
    super::contained("the glTF reader (gltf)", || load_contained(bytes, path, from))?
}

fn load_contained(bytes: &[u8], path: &Path, from: Files) -> Result<LoadedModel, String> {
    let gltf = gltf::Gltf::from_slice_without_validation(bytes).map_err(|e| e.to_string())?;
    let nodes = gltf.document.as_json().nodes.len() as u64;
    from.limits.check(Limit::GltfNodes, nodes, || "the file's nodes".into()).map_err(|e| e.to_string())?;
    // The gltf crate's own validation indexes some arrays unchecked, and its
    // image sources unwrap: what they assume is checked here first.
    checked_references(gltf.document.as_json())?;
    checked_accessors(gltf.document.as_json())?;
    let document = gltf::Document::from_json(gltf.document.into_json()).map_err(|e| format!("invalid glTF: {e}"))?;
    let dir = path.parent().unwrap_or(Path::new(""));
    let buffers = buffers(&document, gltf.blob, dir, from)?;
    let cx = Context {
        doc: document,
        buffers,
        dir,
        from,
        path,
        placed: Cell::new(0),
        textures: RefCell::new(HashMap::new()),
    };
    let materials: Vec<Material> = cx.doc.materials().map(|m| cx.material(&m)).collect::<Result<_, _>>()?;
    let mut model = LoadedModel::default();
    let scene = cx.doc.default_scene().or_else(|| cx.doc.scenes().next()).ok_or("the file has no scene")?;
    for node in scene.nodes() {
        cx.visit(&node, Mat4::IDENTITY, &materials, &mut model, &mut Vec::new())?;
    }
    if model.parts.is_empty() {
        return Err("the default scene has no triangle meshes".into());
    }
    Ok(model)
}

/// The references the gltf crate follows without checking: each primitive's
/// attribute and index accessors, and each image's data (a URI, or a buffer
/// view with a MIME type).
fn checked_references(root: &gltf::json::Root) -> Result<(), String> {
    let accessors = root.accessors.len();
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, prim) in mesh.primitives.iter().enumerate() {
            let used = prim.attributes.values().map(|a| a.value()).chain(prim.indices.map(|i| i.value()));
            if let Some(bad) = used.into_iter().find(|&i| i >= accessors) {
                return Err(format!(
                    "mesh {m} primitive {p} uses accessor {bad}, but the file has {accessors} accessor(s)"
                ));
            }
        }
    }
    for (i, image) in root.images.iter().enumerate() {
        match (&image.uri, &image.buffer_view, &image.mime_type) {
            (None, None, _) => return Err(format!("image {i} has neither a uri nor a bufferView")),
            (None, Some(_), None) => return Err(format!("image {i} is in a bufferView but has no mimeType")),
            _ => {}
        }
    }
    Ok(())
}

/// What the gltf crate's reader assumes of the accessors kage reads (positions,
/// normals, the first texture coordinates, indices) and does not check: their
/// element type (indices of floats are `unreachable!` to it), at least one
/// element, every element inside the buffer view, no sparse storage.
fn checked_accessors(root: &gltf::json::Root) -> Result<(), String> {
    use gltf::json::accessor::{ComponentType as C, Type as T};
    use gltf::json::mesh::Semantic;
    use gltf::json::validation::Checked;
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, prim) in mesh.primitives.iter().enumerate() {
            let mut used: Vec<(&str, usize, &[T], &[C])> = Vec::new();
            for (semantic, index) in &prim.attributes {
                let (name, types, components): (&str, &[T], &[C]) = match semantic {
                    Checked::Valid(Semantic::Positions) => ("POSITION", &[T::Vec3], &[C::F32]),
                    Checked::Valid(Semantic::Normals) => ("NORMAL", &[T::Vec3], &[C::F32]),
                    Checked::Valid(Semantic::TexCoords(0)) => ("TEXCOORD_0", &[T::Vec2], &[C::F32, C::U8, C::U16]),
                    _ => continue,
                };
                used.push((name, index.value(), types, components));
            }
            if let Some(i) = prim.indices {
                used.push(("indices", i.value(), &[T::Scalar], &[C::U8, C::U16, C::U32]));
            }
            for (what, i, types, components) in used {
                let fail = |why: &str| Err(format!("mesh {m} primitive {p}: its {what} accessor {i} {why}"));
                let a = &root.accessors[i];
                let (Checked::Valid(t), Checked::Valid(c)) = (a.type_, a.component_type) else {
                    return fail("has an unknown element type");
                };
                if !types.contains(&t) || !components.contains(&c.0) {
                    return fail(&format!("holds {:?} {t:?} elements, which {what} cannot be", c.0));
                }
                if a.sparse.is_some() {
                    return fail("is sparse, which kage does not read");
                }
                if a.count.0 == 0 {
                    return fail("has no elements");
                }
                let Some(v) = a.buffer_view else { continue };
                let view = root
                    .buffer_views
                    .get(v.value())
                    .ok_or_else(|| format!("accessor {i}: no buffer view {}", v.value()))?;
                let size = (t.multiplicity() * c.0.size()) as u64;
                let stride = view.byte_stride.map_or(size, |s| s.0 as u64);
                if stride < size {
                    return fail("steps through its buffer view by less than one element (byteStride)");
                }
                let end = (a.count.0 - 1)
                    .checked_mul(stride)
                    .and_then(|e| e.checked_add(size + a.byte_offset.map_or(0, |o| o.0)));
                if end.is_none_or(|end| end > view.byte_length.0) {
                    return fail("reaches past its buffer view");
                }
            }
        }
    }
    Ok(())
}

impl Context<'_> {
    /// Places `node` (under the transform `parent`, below the nodes `above`)
    /// and its children into `out`: refused when it is among its own
    /// ancestors, too deep ([`Limit::Nesting`]: a chain of 100,000 would
    /// overflow the stack) or one placement too many ([`Limit::Instances`]).
    fn visit(
        &self,
        node: &gltf::Node,
        parent: Mat4,
        materials: &[Material],
        out: &mut LoadedModel,
        above: &mut Vec<usize>,
    ) -> Result<(), String> {
        let index = node.index();
        if above.contains(&index) {
            return Err(format!("node {index} is its own ancestor (the node tree has a cycle)"));
        }
        let limits = self.from.limits;
        let depth = above.len() as u64 + 1;
        if depth > limits.get(Limit::Nesting) {
            let allowed = limits.get(Limit::Nesting);
            let what = format!("node {index}, nested this deep,");
            return Err(LimitExceeded { limit: Limit::Nesting, asked: depth, allowed, what }.to_string());
        }
        self.placed.set(self.placed.get() + 1);
        let what = || "the nodes the scene places (a node listed by several parents is placed once for each)".into();
        limits.check(Limit::Instances, self.placed.get(), what).map_err(|e| e.to_string())?;
        let world = parent * Mat4::from_cols_array_2d(&node.transform().matrix());
        let affine = Affine3A::from_mat4(world);
        if let Some(mesh) = node.mesh() {
            for prim in mesh.primitives() {
                self.primitive(&prim, mesh.name().unwrap_or("mesh"), affine, materials, out)?;
            }
        }
        if let (Some(cam), None) = (node.camera(), out.camera) {
            out.camera = Some(camera(&cam, affine)?);
        }
        if let Some(light) = node.light() {
            out.lights.push(self::light(&light, affine)?);
        }
        // An error ends the walk, so `above` is only kept right on success.
        above.push(index);
        for child in node.children() {
            self.visit(&child, world, materials, out, above)?;
        }
        above.pop();
        Ok(())
    }

    fn primitive(
        &self,
        prim: &gltf::Primitive,
        name: &str,
        transform: Affine3A,
        materials: &[Material],
        out: &mut LoadedModel,
    ) -> Result<(), String> {
        if prim.mode() != gltf::mesh::Mode::Triangles {
            out.warnings.push(format!(
                "{}: mesh '{name}' uses {:?}, not triangles; skipped",
                self.path.display(),
                prim.mode()
            ));
            return Ok(());
        }
        let reader = prim.reader(|b| self.buffers.get(b.index()).map(|d| &d[..]));
        let positions: Vec<Vec3> =
            reader.read_positions().ok_or_else(|| format!("mesh '{name}' has no positions"))?.map(Vec3::from).collect();
        let normals = reader.read_normals().map(|n| n.map(Vec3::from).collect()).unwrap_or_default();
        let uvs = reader.read_tex_coords(0).map(|t| t.into_f32().map(Vec2::from).collect()).unwrap_or_default();
        let indices: Vec<u32> = match reader.read_indices() {
            Some(i) => i.into_u32().collect(),
            None => (0..positions.len() as u32).collect(),
        };
        let triangles = indices.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
        let built = Mesh::new(positions, normals, uvs, triangles, NormalMode::Smooth);
        let mesh = checked(out, self.path, built, &format!("mesh '{name}'"))?;
        let material = prim.material().index().and_then(|i| materials.get(i).cloned());
        out.parts.push(Part { name: name.to_string(), mesh: Arc::new(mesh), material, transform, ghost: false });
        Ok(())
    }

    fn material(&self, m: &gltf::Material) -> Result<Material, String> {
        let pbr = m.pbr_metallic_roughness();
        let [r, g, b, a] = pbr.base_color_factor();
        let surface = Surface {
            base: Vec3::new(r, g, b),
            base_map: pbr.base_color_texture().map(|t| self.texture(&t.texture(), true)).transpose()?,
            metal: pbr.metallic_factor().clamp(0.0, 1.0),
            roughness: pbr.roughness_factor().clamp(0.0, 1.0),
            metal_roughness_map: pbr
                .metallic_roughness_texture()
                .map(|t| self.texture(&t.texture(), false))
                .transpose()?,
            occlusion: m
                .occlusion_texture()
                .map(|t| Ok::<_, String>((self.texture(&t.texture(), false)?, t.strength().clamp(0.0, 1.0))))
                .transpose()?,
        };
        let transmission = m.transmission().map_or(0.0, |t| t.transmission_factor().clamp(0.0, 1.0));
        let mut out = surface.material();
        out.name = m.name().unwrap_or("gltf").to_string();
        out.ke = Vec3::from(m.emissive_factor());
        out.maps.emission =
            m.emissive_texture().map(|t| self.texture(&t.texture(), true)).transpose()?.into_iter().collect();
        out.maps.normal = m
            .normal_texture()
            .map(|t| Ok::<_, String>(NormalMap { texture: self.texture(&t.texture(), false)?, scale: t.scale() }))
            .transpose()?
            .filter(|n| n.scale.is_finite() && n.scale != 0.0);
        out.two_sided = m.double_sided();
        // BLEND materials are translucent with the base colour's alpha; MASK and
        // OPAQUE ones are drawn opaque (alpha cut-outs are not supported).
        out.opacity = if m.alpha_mode() == gltf::material::AlphaMode::Blend { a.clamp(0.0, 1.0) } else { 1.0 };
        if transmission > 0.0 {
            // Light through the surface, tinted by the base colour, bent by
            // the index of refraction; what goes through is not diffused.
            out.kt = surface.base * transmission;
            out.kd *= 1.0 - transmission;
            out.ka *= 1.0 - transmission;
            out.kr = Vec3::splat(0.04 * transmission);
        }
        out.ior = m.ior().filter(|n| n.is_finite() && *n >= 1.0).unwrap_or(1.5);
        Ok(out)
    }

    /// The texture of `t`'s image, decoded once however many materials use it.
    fn texture(&self, t: &gltf::Texture, srgb: bool) -> Result<Arc<Texture>, String> {
        let key = (t.source().index(), srgb);
        if let Some(done) = self.textures.borrow().get(&key) {
            return Ok(Arc::clone(done));
        }
        let limits = self.from.limits;
        let bytes = match t.source().source() {
            gltf::image::Source::View { view, .. } => {
                let data = self.buffers.get(view.buffer().index()).ok_or("image view of a missing buffer")?;
                let range = view.offset()..view.offset().saturating_add(view.length());
                data.get(range).ok_or("image view outside its buffer")?.to_vec()
            }
            gltf::image::Source::Uri { uri, .. } if uri.starts_with("data:") => data_uri(uri)?,
            gltf::image::Source::Uri { uri, .. } => {
                let path = self.dir.join(percent_decoded(uri));
                let texture =
                    crate::scene::load::texture(&path, srgb, self.from.assets, limits).map_err(|e| e.to_string())?;
                self.textures.borrow_mut().insert(key, Arc::clone(&texture));
                return Ok(texture);
            }
        };
        let texture = Texture::decode(&bytes, srgb, limits)
            .map(Arc::new)
            .map_err(|e| format!("embedded image {}: {e}", t.index()))?;
        self.textures.borrow_mut().insert(key, Arc::clone(&texture));
        Ok(texture)
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
}

impl Surface {
    /// Base colour, metalness, roughness and occlusion at `uv`.
    fn at(&self, uv: Vec2) -> (Vec3, f32, f32, f32) {
        let base = self.base * self.base_map.as_ref().map_or(Vec3::ONE, |t| t.sample(uv));
        let mr = self.metal_roughness_map.as_ref().map_or(Vec3::ONE, |t| t.sample(uv));
        let occlusion = self.occlusion.as_ref().map_or(1.0, |(t, strength)| 1.0 + strength * (t.sample(uv).x - 1.0));
        (base, (self.metal * mr.z).clamp(0.0, 1.0), (self.roughness * mr.y).clamp(0.0, 1.0), occlusion)
    }

    /// Kd = base · (1 − metal), Ka = Kd · occlusion, Ks = mix(0.04, base,
    /// metal), Km = base · metal (the environment a metal mirrors); with a
    /// metallic-roughness or occlusion texture each is a texture baked texel by
    /// texel, else the base-colour texture multiplies Kd and Ka. The Phong
    /// exponent comes from the mean roughness.
    fn material(&self) -> Material {
        let Some(size) = self.baked_size() else {
            let kd = self.base * (1.0 - self.metal);
            return Material {
                ka: kd,
                kd,
                ks: Vec3::splat(0.04).lerp(self.base, self.metal),
                km: self.base * self.metal,
                shininess: shininess(self.roughness),
                maps: ComponentMaps {
                    ambient: self.base_map.iter().cloned().collect(),
                    diffuse: self.base_map.iter().cloned().collect(),
                    ..ComponentMaps::default()
                },
                ..Material::default()
            };
        };
        // One lookup of the textures per texel, for all three maps.
        let [diffuse, ambient, specular] = bake(size, |uv| {
            let (base, metal, _, occlusion) = self.at(uv);
            let kd = base * (1.0 - metal);
            [kd, kd * occlusion, Vec3::splat(0.04).lerp(base, metal)]
        });
        // Km and the exponent take one value per material: their means.
        let n = 64usize;
        let samples = (0..n * n).map(|i| Vec2::new((i % n) as f32 + 0.5, (i / n) as f32 + 0.5) / n as f32);
        let (mirror, rough) = samples.fold((Vec3::ZERO, 0.0), |(m, r), uv| {
            let (base, metal, roughness, _) = self.at(uv);
            (m + base * metal, r + roughness)
        });
        let count = (n * n) as f32;
        Material {
            ka: Vec3::ONE,
            kd: Vec3::ONE,
            ks: Vec3::ONE,
            km: mirror / count,
            shininess: shininess(rough / count),
            maps: ComponentMaps {
                ambient: vec![ambient],
                diffuse: vec![diffuse],
                specular: vec![specular],
                ..ComponentMaps::default()
            },
            ..Material::default()
        }
    }

    /// The size of the largest texture when a texture varies more than the
    /// base colour (metalness, roughness or occlusion); `None` otherwise.
    fn baked_size(&self) -> Option<(u32, u32)> {
        if self.metal_roughness_map.is_none() && self.occlusion.is_none() {
            return None;
        }
        let maps = [self.base_map.as_ref(), self.metal_roughness_map.as_ref(), self.occlusion.as_ref().map(|(t, _)| t)];
        maps.into_iter().flatten().map(|t| t.size()).reduce(|a, b| (a.0.max(b.0), a.1.max(b.1)))
    }
}

/// n = 2/α² − 2 with α = roughness², the Blinn-Phong exponent whose lobe is
/// as wide as the microfacet distribution's.
fn shininess(roughness: f32) -> f32 {
    let alpha = roughness.clamp(0.05, 1.0).powi(2);
    (2.0 / (alpha * alpha) - 2.0).clamp(1.0, 2048.0)
}

/// Three `width × height` textures of `f`'s three values at each texel
/// centre's uv.
fn bake((width, height): (u32, u32), f: impl Fn(Vec2) -> [Vec3; 3] + Sync) -> [Arc<Texture>; 3] {
    use rayon::prelude::*;
    let texels: Vec<[Vec3; 3]> = (0..width * height)
        .into_par_iter()
        .map(|i| {
            f(Vec2::new((i % width) as f32 + 0.5, (i / width) as f32 + 0.5) / Vec2::new(width as f32, height as f32))
        })
        .collect();
    std::array::from_fn(|k| Arc::new(Texture::from_texels(width, height, texels.iter().map(|t| t[k]).collect())))
}

/// The bytes of a `data:[<media type>][;base64],<data>` URI.
fn data_uri(uri: &str) -> Result<Vec<u8>, String> {
    use base64::Engine as _;
    let (head, data) = uri.split_once(',').ok_or("a data URI without ','")?;
    if head.ends_with(";base64") {
        base64::engine::general_purpose::STANDARD
            .decode(data.trim())
            .map_err(|e| format!("a data URI's base64 does not decode: {e}"))
    } else {
        Ok(percent_decoded(data).into_bytes())
    }
}

/// The bytes of every buffer of `doc`: the GLB chunk `blob`, a `data:` URI,
/// or a file next to the glTF (read through `from`, within its limits).
fn buffers(doc: &gltf::Document, mut blob: Option<Vec<u8>>, dir: &Path, from: Files) -> Result<Vec<Vec<u8>>, String> {
    doc.buffers()
        .map(|b| {
            let data = match b.source() {
                gltf::buffer::Source::Bin => blob.take().ok_or("a buffer refers to the GLB chunk, which is absent")?,
                gltf::buffer::Source::Uri(uri) if uri.starts_with("data:") => data_uri(uri)?,
                gltf::buffer::Source::Uri(uri) => {
                    from.read(&dir.join(percent_decoded(uri))).map_err(|e| format!("buffer {}: {e}", b.index()))?
                }
            };
            if data.len() < b.length() {
                return Err(format!(
                    "buffer {} holds {} bytes, not the {} it declares",
                    b.index(),
                    data.len(),
                    b.length()
                ));
            }
            Ok(data)
        })
        .collect()
}

/// `%20`-style escapes of a URI decoded (glTF URIs are URI references).
fn percent_decoded(uri: &str) -> String {
    let bytes = uri.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        let hex = |b: u8| (b as char).to_digit(16);
        match (bytes[i], bytes.get(i + 1).copied().and_then(hex), bytes.get(i + 2).copied().and_then(hex)) {
            (b'%', Some(h), Some(l)) => {
                out.push((h * 16 + l) as u8);
                i += 3;
            }
            (b, _, _) => {
                out.push(b);
                i += 1;
            }
        }
    }
    String::from_utf8_lossy(&out).into_owned()
}

fn camera(cam: &gltf::Camera, at: Affine3A) -> Result<Camera, String> {
    let which = format!("camera {}", cam.index());
    let eye = at.transform_point3(Vec3::ZERO);
    let fwd = at.transform_vector3(Vec3::NEG_Z).normalize_or_zero();
    let up = at.transform_vector3(Vec3::Y).normalize_or_zero();
    let (projection, near, far) = match cam.projection() {
        gltf::camera::Projection::Perspective(p) => {
            let yfov = p.yfov();
            if !(yfov > 0.0 && yfov < std::f32::consts::PI) {
                return Err(format!("{which}: yfov must be between 0 and π radians (both excluded), not {yfov}"));
            }
            if !(p.znear() > 0.0 && p.zfar().is_none_or(|far| far > p.znear())) {
                return Err(format!("{which}: znear must be > 0 and zfar (if given) > znear"));
            }
            (Projection::Perspective { fov_y_deg: yfov.to_degrees() }, p.znear(), p.zfar().unwrap_or(p.znear() * 1e5))
        }
        gltf::camera::Projection::Orthographic(o) => {
            if !(o.ymag() > 0.0 && o.zfar() > o.znear().max(1e-4)) {
                return Err(format!("{which}: ymag must be > 0 and zfar > znear"));
            }
            (Projection::Orthographic { height: 2.0 * o.ymag() }, o.znear().max(1e-4), o.zfar())
        }
    };
    let c = Camera { eye, target: eye + fwd, up, near, far, projection, shift: glam::Vec2::ZERO };
    c.validate().map_err(|e| format!("{which} (as its node places it): {e}"))?;
    Ok(c)
}

/// A `KHR_lights_punctual` light placed by `at`: its intensity and colour
/// finite and ≥ 0, a spot's cone angles 0 ≤ inner ≤ outer ≤ π/2 (as the
/// extension requires).
fn light(l: &gltf::khr_lights_punctual::Light, at: Affine3A) -> Result<Light, String> {
    use gltf::khr_lights_punctual::Kind;
    let which = format!("light {}", l.index());
    let values = [l.intensity(), l.color()[0], l.color()[1], l.color()[2]];
    if !values.iter().all(|v| v.is_finite() && *v >= 0.0 && *v < f32::MAX) {
        return Err(format!("{which}: intensity and colour must be finite and ≥ 0, not {values:?}"));
    }
    if let Kind::Spot { inner_cone_angle: inner, outer_cone_angle: outer } = l.kind() {
        if !(0.0 <= inner && inner <= outer && outer <= std::f32::consts::FRAC_PI_2) {
            return Err(format!("{which}: cone angles must satisfy 0 ≤ inner ≤ outer ≤ π/2, not {inner} and {outer}"));
        }
    }
    let position = at.transform_point3(Vec3::ZERO);
    let direction = at.transform_vector3(Vec3::NEG_Z).normalize_or(Vec3::NEG_Y);
    let (kind, falloff) = match l.kind() {
        Kind::Directional => (LightKind::Directional { direction }, Falloff::None),
        Kind::Point => (LightKind::Point { position }, Falloff::InverseSquare),
        Kind::Spot { inner_cone_angle, outer_cone_angle } => (
            LightKind::Spot { position, direction, inner: inner_cone_angle, outer: outer_cone_angle },
            Falloff::InverseSquare,
        ),
    };
    Ok(Light {
        kind,
        color: l.color().into(),
        intensity: l.intensity(),
        ambient: 0.0,
        size: 0.0,
        falloff,
        ..Light::default()
    })
}
