//! glTF 2.0 (`.gltf` and `.glb`): node transforms, materials, the first camera and
//! `KHR_lights_punctual` lights.
//!
//! Metallic-roughness materials map onto seed 002's Phong coefficients:
//! Kd = base colour · (1 − metallic), Ka = Kd · occlusion, Ks = mix(F0, base
//! colour, metallic) with F0 = 0.04 (or `KHR_materials_specular`'s colour ×
//! strength × 0.04), Km = base colour · metallic (a metal mirrors the
//! environment: a lone model gets a studio one) plus 0.04 ×
//! `KHR_materials_clearcoat`'s factor (a clear coat, approximated as a sharp
//! 4% mirror), n = 2/α² − 2 with α =
//! roughness² (the Blinn-Phong exponent of equal lobe width), Ke = emissive
//! (times `KHR_materials_emissive_strength`). The base-colour texture
//! multiplies Kd and Ka; with a metallic-roughness or occlusion texture, Kd,
//! Ka, Ks and Km are baked into textures texel by texel (n takes the
//! material's mean roughness). `KHR_materials_transmission` makes Kt = base colour ·
//! transmission (Kd scaled by what is not transmitted), `KHR_materials_ior`
//! the index of refraction; `KHR_materials_unlit` shows the base colour as
//! emission, unlit. The base colour's alpha (factor times texture) blends the
//! surface over what lies behind it in BLEND mode and cuts it where it is
//! below `alphaCutoff` in MASK mode (for the eye, the shadow maps and
//! traced rays: `visibility/cutout.rs`); OPAQUE ignores it. The normal texture tilts the shading normal
//! (`shading/normal_map.rs`: tangents from the texture coordinates; a
//! `TANGENT` attribute is not read). Buffers and images may be files, GLB
//! chunks or `data:` URIs; an image that cannot be read or decoded is a
//! warning and a magenta checker.
//!
//! Geometry: triangle lists, strips and fans (points and lines are skipped,
//! with a warning); attributes stored as floats or as the integers of
//! `KHR_mesh_quantization` ([`accessors`]), dense or sparse, in buffer views
//! stored plain or compressed by meshoptimizer ([`meshopt`]), or a
//! primitive's whole geometry as one Draco stream ([`draco`]); `COLOR_0`
//! vertex colours (multiplying Ka and Kd); a node that
//! mirrors (negative determinant) has its triangles turned round so their
//! front faces stay outside. A material's textures are read at two sets of
//! texture coordinates at most (a set with its `KHR_texture_transform`: its
//! first texture's, and the first other one a texture asks for, kept as the
//! mesh's `uvs` and `uvs1`; a warning where a texture asks for a third);
//! the metallic-roughness and occlusion textures only at the base colour's,
//! with which they are baked. Each texture wraps as its sampler says. Which extensions are read,
//! drawn without or refused: [`extensions`].

use std::cell::{Cell, RefCell};
use std::collections::HashMap;
use std::path::Path;
use std::sync::Arc;

use glam::{Affine3A, Mat4, Vec2, Vec3};

mod accessors;
mod draco;
mod extensions;
mod meshopt;

use super::{checked, Files, LoadedModel, Part};
use crate::camera::{Camera, Projection};
use crate::limits::{Limit, LimitExceeded};
use crate::scene::mesh::{Mesh, NormalMode};
use crate::scene::texture::{encode_8bit, Edge, Wrap};
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
    /// What was drawn otherwise than the file says (a missing texture).
    warnings: RefCell<Vec<String>>,
}

/// The texture coordinates a material's textures are read at: a set
/// (`TEXCOORD_n`) and a `KHR_texture_transform`.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
struct Coordinates {
    set: u32,
    transform: Option<glam::Affine2>,
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
struct Channels {
    first: Coordinates,
    second: Option<Coordinates>,
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

/// Parses glTF or GLB bytes; `path` locates external buffers and images
/// (read through `from`, within its limits).
pub(super) fn load(bytes: &[u8], path: &Path, from: Files) -> Result<LoadedModel, String> {
    super::contained("the glTF reader (gltf)", || load_contained(bytes, path, from))?
}

fn load_contained(bytes: &[u8], path: &Path, from: Files) -> Result<LoadedModel, String> {
    let gltf = gltf::Gltf::from_slice_without_validation(bytes).map_err(|e| e.to_string())?;
    let nodes = gltf.document.as_json().nodes.len() as u64;
    from.limits.check(Limit::GltfNodes, nodes, || "the file's nodes".into()).map_err(|e| e.to_string())?;
    let mut warnings = Vec::new();
    let mut json = gltf.document.into_json();
    extensions::check(&mut json, &mut warnings)?;
    // The gltf crate's own validation indexes some arrays unchecked, and its
    // image sources unwrap: what they assume is checked here first.
    checked_references(&json)?;
    checked_accessors(&json)?;
    let zeros = zeroed_accessors(&mut json)?;
    let document = gltf::Document::from_json(json).map_err(|e| format!("invalid glTF: {e}"))?;
    let dir = path.parent().unwrap_or(Path::new(""));
    let mut buffers = buffers(&document, gltf.blob, zeros, dir, from)?;
    meshopt::decode_views(&document, &mut buffers)?;
    let cx = Context {
        doc: document,
        buffers,
        dir,
        from,
        path,
        placed: Cell::new(0),
        textures: RefCell::new(HashMap::new()),
        warnings: RefCell::new(warnings),
    };
    cx.decode_all();
    let materials: Vec<(Material, Channels)> = cx.doc.materials().map(|m| cx.material(&m)).collect();
    let mut model = LoadedModel::default();
    let scene = cx.doc.default_scene().or_else(|| cx.doc.scenes().next()).ok_or("the file has no scene")?;
    for node in scene.nodes() {
        cx.visit(&node, Mat4::IDENTITY, &materials, &mut model, &mut Vec::new())?;
    }
    if model.parts.is_empty() {
        return Err("the default scene has no triangle meshes".into());
    }
    let said = cx.warnings.take().into_iter().map(|w| format!("{}: {w}", path.display()));
    model.warnings.splice(0..0, said);
    Ok(model)
}

/// Accessors with neither a buffer view nor sparse values: zeros, as the
/// glTF specification says, or values an extension fills (a Draco
/// primitive's). The gltf crate refuses them, so each is given a view of a
/// buffer of zeros added to `root` for them; that buffer's index, if added.
fn zeroed_accessors(root: &mut gltf::json::Root) -> Result<Option<usize>, String> {
    use gltf::json::accessor::Type as T;
    use gltf::json::validation::Checked;
    let bytes = |a: &gltf::json::Accessor| {
        let components = match a.type_ {
            Checked::Valid(T::Scalar) => 1,
            Checked::Valid(T::Vec2) => 2,
            Checked::Valid(T::Vec3) => 3,
            Checked::Valid(T::Vec4 | T::Mat2) => 4,
            Checked::Valid(T::Mat3) => 9,
            Checked::Valid(T::Mat4) => 16,
            Checked::Invalid => 0,
        };
        let size = match a.component_type {
            Checked::Valid(c) => c.0.size() as u64,
            Checked::Invalid => 0,
        };
        a.count.0.saturating_mul(components * size)
    };
    let empty = |a: &gltf::json::Accessor| a.buffer_view.is_none() && a.sparse.is_none();
    let Some(length) = root.accessors.iter().filter(|a| empty(a)).map(bytes).max() else { return Ok(None) };
    let length = length.max(1);
    let buffer = root.buffers.len();
    let zeros = gltf::json::deserialize::from_str(&format!(r#"{{"byteLength": {length}}}"#));
    root.buffers.push(zeros.map_err(|e| e.to_string())?);
    let view = root.buffer_views.len() as u32;
    let over = gltf::json::deserialize::from_str(&format!(r#"{{"buffer": {buffer}, "byteLength": {length}}}"#));
    root.buffer_views.push(over.map_err(|e| e.to_string())?);
    for a in root.accessors.iter_mut().filter(|a| empty(a)) {
        a.buffer_view = Some(gltf::json::Index::new(view));
        a.byte_offset = None;
    }
    Ok(Some(buffer))
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
/// normals, texture coordinates, indices) and does not check: their element
/// type (indices of floats are `unreachable!` to it), at least one element,
/// every element inside the buffer view, a sparse accessor's indices and
/// values inside theirs.
fn checked_accessors(root: &gltf::json::Root) -> Result<(), String> {
    use gltf::json::accessor::{ComponentType as C, Type as T};
    use gltf::json::mesh::Semantic;
    use gltf::json::validation::Checked;
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, prim) in mesh.primitives.iter().enumerate() {
            let mut used: Vec<(String, usize, &[T], &[C])> = Vec::new();
            for (semantic, index) in &prim.attributes {
                // Floats, or the integers KHR_mesh_quantization allows.
                let (name, types, components): (String, &[T], &[C]) = match semantic {
                    Checked::Valid(Semantic::Positions) => {
                        ("POSITION".into(), &[T::Vec3], &[C::F32, C::I8, C::U8, C::I16, C::U16])
                    }
                    Checked::Valid(Semantic::Normals) => ("NORMAL".into(), &[T::Vec3], &[C::F32, C::I8, C::I16]),
                    Checked::Valid(Semantic::TexCoords(n)) => {
                        (format!("TEXCOORD_{n}"), &[T::Vec2], &[C::F32, C::I8, C::U8, C::I16, C::U16])
                    }
                    Checked::Valid(Semantic::Colors(0)) => {
                        ("COLOR_0".into(), &[T::Vec3, T::Vec4], &[C::F32, C::U8, C::U16])
                    }
                    _ => continue,
                };
                used.push((name, index.value(), types, components));
            }
            if let Some(i) = prim.indices {
                used.push(("indices".into(), i.value(), &[T::Scalar], &[C::U8, C::U16, C::U32]));
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
                if a.count.0 == 0 {
                    return fail("has no elements");
                }
                let size = (t.multiplicity() * c.0.size()) as u64;
                if let Some(sparse) = &a.sparse {
                    checked_sparse(root, sparse, a.count.0, size).map_err(|why| {
                        format!("mesh {m} primitive {p}: its {what} accessor {i} is sparse, and its {why}")
                    })?;
                }
                let Some(v) = a.buffer_view else { continue };
                let view = root
                    .buffer_views
                    .get(v.value())
                    .ok_or_else(|| format!("accessor {i}: no buffer view {}", v.value()))?;
                let stride = view.byte_stride.map_or(size, |s| s.0 as u64);
                if stride < size {
                    return fail("steps through its buffer view by less than one element (byteStride)");
                }
                if !within(view, a.byte_offset.map_or(0, |o| o.0), a.count.0, stride, size) {
                    return fail("reaches past its buffer view");
                }
            }
        }
    }
    Ok(())
}

/// Whether `count` elements of `size` bytes, `stride` apart from `offset`,
/// lie within `view`.
fn within(view: &gltf::json::buffer::View, offset: u64, count: u64, stride: u64, size: u64) -> bool {
    let end = count.saturating_sub(1).checked_mul(stride).and_then(|e| e.checked_add(size + offset));
    end.is_some_and(|end| end <= view.byte_length.0)
}

/// What the gltf crate's sparse reader assumes: at least one and at most
/// `count` replaced elements, indices and values (of `size` bytes) within
/// their buffer views.
fn checked_sparse(
    root: &gltf::json::Root,
    sparse: &gltf::json::accessor::sparse::Sparse,
    count: u64,
    size: u64,
) -> Result<(), String> {
    use gltf::json::validation::Checked;
    let n = sparse.count.0;
    if n == 0 || n > count {
        return Err(format!("count {n} is not between 1 and its accessor's {count}"));
    }
    let view = |v: gltf::json::Index<gltf::json::buffer::View>| {
        root.buffer_views.get(v.value()).ok_or_else(|| format!("buffer view {} is not in the file", v.value()))
    };
    let index_size = match sparse.indices.component_type {
        Checked::Valid(t) => t.0.size() as u64,
        Checked::Invalid => return Err("indices have an unknown type".into()),
    };
    let (indices, values) = (view(sparse.indices.buffer_view)?, view(sparse.values.buffer_view)?);
    if !within(indices, sparse.indices.byte_offset.0, n, index_size, index_size) {
        return Err("indices reach past their buffer view".into());
    }
    if !within(values, sparse.values.byte_offset.0, n, size, size) {
        return Err("values reach past their buffer view".into());
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
        materials: &[(Material, Channels)],
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
        materials: &[(Material, Channels)],
        out: &mut LoadedModel,
    ) -> Result<(), String> {
        use gltf::mesh::Mode;
        if !matches!(prim.mode(), Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan) {
            out.warnings.push(format!(
                "{}: mesh '{name}' uses {:?}, not triangles; skipped",
                self.path.display(),
                prim.mode()
            ));
            return Ok(());
        }
        use gltf::mesh::Semantic;
        let data = |b: gltf::Buffer| self.buffers.get(b.index()).map(|d| &d[..]);
        let reader = prim.reader(data);
        // Draco-compressed geometry stands in for the accessors it names.
        let draco = draco::DracoGeometry::of(prim, &self.doc, &self.buffers, self.from.limits)
            .map_err(|e| format!("mesh '{name}': {e}"))?;
        let floats3 = |s: Semantic| match draco.as_ref().and_then(|d| d.floats::<3>(&s.to_string())) {
            Some(values) => Some(values),
            None => prim.get(&s).and_then(|a| accessors::floats::<3>(&a, data)),
        };
        let positions: Vec<Vec3> = floats3(Semantic::Positions)
            .ok_or_else(|| format!("mesh '{name}' has no positions"))?
            .into_iter()
            .map(Vec3::from)
            .collect();
        let normals = floats3(Semantic::Normals);
        let normals = normals.map(|n| n.into_iter().map(Vec3::from).collect()).unwrap_or_default();
        let (material, at) = match prim.material().index().and_then(|i| materials.get(i)) {
            Some((m, at)) => (Some(m.clone()), *at),
            None => (None, Channels::default()),
        };
        let read_uvs = |c: Coordinates| {
            let semantic = Semantic::TexCoords(c.set);
            let uvs = match draco.as_ref().and_then(|d| d.floats::<2>(&semantic.to_string())) {
                Some(uvs) => Some(uvs),
                None => prim.get(&semantic).and_then(|a| accessors::floats::<2>(&a, data)),
            };
            uvs.map(|uvs| {
                let uv = uvs.into_iter().map(Vec2::from);
                match c.transform {
                    Some(t) => uv.map(|uv| t.transform_point2(uv)).collect(),
                    None => uv.collect::<Vec<_>>(),
                }
            })
        };
        let uvs = read_uvs(at.first).unwrap_or_default();
        let indices: Vec<u32> = match (&draco, reader.read_indices()) {
            (Some(d), _) => d.indices(),
            (None, Some(i)) => i.into_u32().collect(),
            (None, None) => (0..positions.len() as u32).collect(),
        };
        // A node that mirrors (a negative determinant) turns each triangle's
        // winding round: turned back, its front faces stay outside.
        let mirrored = transform.matrix3.determinant() < 0.0;
        let triangles =
            triangles(prim.mode(), &indices).map(|[a, b, c]| if mirrored { [a, c, b] } else { [a, b, c] }).collect();
        let built = Mesh::new(positions, normals, uvs, triangles, NormalMode::Smooth);
        let mut mesh = checked(out, self.path, built, &format!("mesh '{name}'"))?;
        if let Some(second) = at.second {
            let with = read_uvs(second).ok_or_else(|| "the primitive has no such attribute".to_string());
            if let Err(why) = with.and_then(|uvs| mesh.set_second_uvs(uvs)) {
                self.warnings.borrow_mut().push(format!(
                    "mesh '{name}': its second texture coordinates (TEXCOORD_{}) are not read ({why}); the textures \
                     meant for them are drawn at TEXCOORD_{}",
                    second.set, at.first.set
                ));
            }
        }
        if let Some(colors) = draco.as_ref().and_then(|d| d.floats::<4>(&Semantic::Colors(0).to_string())) {
            // Three components read as four: the fourth is zero, and unused.
            let colors = colors.into_iter().map(|[r, g, b, _]| Vec3::new(r, g, b)).collect();
            if let Err(why) = mesh.set_colors(colors) {
                self.warnings
                    .borrow_mut()
                    .push(format!("mesh '{name}': its vertex colours (COLOR_0) are not drawn: {why}"));
            }
        } else if let Some(colors) = prim.get(&Semantic::Colors(0)) {
            let read = match colors.dimensions() {
                gltf::accessor::Dimensions::Vec4 => accessors::floats::<4>(&colors, data)
                    .map(|c| c.into_iter().map(|[r, g, b, _]| Vec3::new(r, g, b)).collect()),
                _ => accessors::floats::<3>(&colors, data).map(|c| c.into_iter().map(Vec3::from).collect()),
            };
            let with = read.ok_or_else(|| "its data is out of reach".to_string());
            if let Err(why) = with.and_then(|colors| mesh.set_colors(colors)) {
                self.warnings
                    .borrow_mut()
                    .push(format!("mesh '{name}': its vertex colours (COLOR_0) are not drawn: {why}"));
            }
        }
        out.parts.push(Part { name: name.to_string(), mesh: Arc::new(mesh), material, transform, ghost: false });
        Ok(())
    }

    /// `m` as kage's material, and the texture coordinates its textures are
    /// read at.
    fn material(&self, m: &gltf::Material) -> (Material, Channels) {
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
    fn decode_all(&self) {
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
            return super::texture_or_placeholder(&path, srgb, from.assets, from.limits, warnings);
        }
    };
    bytes.and_then(|bytes| Texture::decode(&bytes, srgb, from.limits)).map(Arc::new).unwrap_or_else(|e| {
        warnings.push(format!("embedded image {}: {e}; drawn as a magenta checker", t.source().index()));
        super::placeholder()
    })
}

/// The triangles a list, strip or fan of `indices` makes, front faces
/// wound as the glTF specification says (a strip's every other triangle
/// turned round; a fan's round its first vertex).
fn triangles(mode: gltf::mesh::Mode, indices: &[u32]) -> Box<dyn Iterator<Item = [u32; 3]> + '_> {
    use gltf::mesh::Mode;
    let runs = indices.len().saturating_sub(2);
    match mode {
        Mode::TriangleStrip => Box::new((0..runs).map(move |i| {
            let v = |k: usize| indices[i + k];
            if i % 2 == 0 {
                [v(0), v(1), v(2)]
            } else {
                [v(1), v(0), v(2)]
            }
        })),
        Mode::TriangleFan => Box::new((0..runs).map(move |i| [indices[i + 1], indices[i + 2], indices[0]])),
        _ => Box::new(indices.chunks_exact(3).map(|c| [c[0], c[1], c[2]])),
    }
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
}

impl Surface {
    /// Base colour, metalness, roughness and occlusion at `uv`.
    fn at(&self, uv: Vec2) -> (Vec3, f32, f32, f32) {
        let base = self.base * self.base_map.as_ref().map_or(Vec3::ONE, |t| t.sample(uv));
        let mr = self.metal_roughness_map.as_ref().map_or(Vec3::ONE, |t| t.sample(uv));
        let occlusion = self.occlusion.as_ref().map_or(1.0, |(t, strength)| 1.0 + strength * (t.sample(uv).x - 1.0));
        (base, (self.metal * mr.z).clamp(0.0, 1.0), (self.roughness * mr.y).clamp(0.0, 1.0), occlusion)
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
    /// exponent comes from the mean roughness.
    fn material(&self) -> Material {
        let Some(size) = self.baked_size() else {
            let kd = self.base * (1.0 - self.metal);
            return Material {
                ka: kd,
                kd,
                ks: self.dielectric.lerp(self.base, self.metal),
                km: self.mirrored(self.base, self.metal),
                shininess: shininess(self.roughness),
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
        // One lookup of the textures per texel, for all four maps.
        // Without an occlusion texture Ka is Kd texel for texel: one map,
        // sampled once for both.
        let [diffuse, ambient, specular, mirror] = if self.occlusion.is_some() {
            bake(size, like, |uv| {
                let (base, metal, _, occlusion) = self.at(uv);
                let kd = base * (1.0 - metal);
                [kd, kd * occlusion, self.dielectric.lerp(base, metal), self.mirrored(base, metal)]
            })
        } else {
            let [diffuse, specular, mirror] = bake(size, like, |uv| {
                let (base, metal, _, _) = self.at(uv);
                [base * (1.0 - metal), self.dielectric.lerp(base, metal), self.mirrored(base, metal)]
            });
            [Arc::clone(&diffuse), diffuse, specular, mirror]
        };
        // The exponent takes one value per material: the mean roughness's.
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
            shininess: shininess(rough / count),
            maps: ComponentMaps {
                ambient: vec![ambient],
                diffuse: vec![diffuse],
                specular: vec![specular],
                mirror: mirrors.then_some(mirror),
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

/// `N` `width × height` colour textures of `f`'s `N` values at each texel
/// centre's uv, kept in 8 bits (sRGB) as the images they come from.
/// Each wraps and reads the coordinates `like` does.
fn bake<const N: usize>(
    (width, height): (u32, u32),
    like: &Texture,
    f: impl Fn(Vec2) -> [Vec3; N] + Sync,
) -> [Arc<Texture>; N] {
    use rayon::prelude::*;
    let size = Vec2::new(width as f32, height as f32);
    let texels: Vec<[[u8; 4]; N]> = (0..width * height)
        .into_par_iter()
        .map(|i| f(Vec2::new((i % width) as f32 + 0.5, (i / width) as f32 + 0.5) / size).map(|c| encode_8bit(c, true)))
        .collect();
    std::array::from_fn(|k| {
        let mut baked = Texture::from_texels_8bit(width, height, texels.iter().map(|t| t[k]).collect(), true);
        (baked.wrap, baked.set) = (like.wrap, like.set);
        Arc::new(baked)
    })
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
/// or a file next to the glTF (read through `from`, within its limits);
/// zeros for a meshopt fallback and for buffer `zeros` ([`zeroed_accessors`]).
fn buffers(
    doc: &gltf::Document,
    mut blob: Option<Vec<u8>>,
    zeros: Option<usize>,
    dir: &Path,
    from: Files,
) -> Result<Vec<Vec<u8>>, String> {
    doc.buffers()
        .map(|b| {
            let data = match b.source() {
                // Room for meshopt-compressed views, decoded into it, and
                // the zeros of accessors without a view.
                _ if meshopt::is_fallback(&b) || zeros == Some(b.index()) => {
                    let bytes = b.length() as u64;
                    let what = || format!("buffer {} (decompressed)", b.index());
                    from.limits.check_bytes(Limit::FileMb, bytes, what).map_err(|e| e.to_string())?;
                    vec![0; b.length()]
                }
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
