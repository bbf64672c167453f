//! glTF 2.0 (`.gltf` and `.glb`): node transforms, materials, the first camera and
//! `KHR_lights_punctual` lights.
//!
//! Metallic-roughness materials map onto seed 002's Phong coefficients:
//! Kd = base colour · (1 − metallic), Ka = Kd · occlusion, Ks = mix(F0, base
//! colour, metallic) with F0 = 0.04 (or `KHR_materials_specular`'s colour ×
//! strength × 0.04), Km = base colour · metallic (a metal mirrors the
//! environment: a lone model gets a studio one) plus 0.04 ×
//! `KHR_materials_clearcoat`'s factor (a clear coat, approximated as a sharp
//! 4% mirror), Kd tinted by `KHR_materials_sheen`'s colour (a quarter of it,
//! the base dimmed by as much: a velvet's sheen approximated as a diffuse
//! tint), n = 2/α² − 2 with α =
//! roughness² (the Blinn-Phong exponent of equal lobe width, rounded:
//! [`phong_exponent`](crate::scene::phong_exponent)), Ke = emissive
//! (times `KHR_materials_emissive_strength`). The base-colour texture
//! multiplies Kd and Ka; with a metallic-roughness or occlusion texture, Kd,
//! Ka, Ks and Km are baked into textures texel by texel, the roughness in
//! the Ks map's alpha (n set point by point where a metallic-roughness
//! texture varies it). `KHR_materials_transmission` makes Kt = base colour ·
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
mod material;

use material::{Channels, Coordinates};
mod meshopt;

use super::{checked, Files, LoadedModel, Part};
use crate::camera::{Camera, Projection};
use crate::limits::{Limit, LimitExceeded};
use crate::scene::mesh::{Mesh, NormalMode};
use crate::scene::{Falloff, Light, LightKind, Material, Texture};

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
    let mut materials: Vec<(Material, Channels)> = cx.doc.materials().map(|m| cx.material(&m)).collect();
    crate::scene::material::interleave_maps(materials.iter_mut().map(|(m, _)| m));
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
