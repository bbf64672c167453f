//! glTF 2.0 (`.gltf` and `.glb`): node transforms, materials, the first camera and
//! `KHR_lights_punctual` lights.
//!
//! Metallic-roughness materials map onto seed 002's Phong coefficients:
//! Kd = base colour · (1 − metallic), Ka = Kd, Ks = mix(0.04, base colour, metallic),
//! n = 2/α² − 2 with α = roughness² (the Blinn-Phong exponent of equal lobe width),
//! Ke = emissive; the base-colour texture multiplies Kd and Ka, the emissive texture Ke.

use std::path::Path;
use std::sync::Arc;

use glam::{Affine3A, Mat4, Vec2, Vec3};

use super::{checked, AssetSource, LoadedModel, Part};
use crate::camera::{Camera, Projection};
use crate::scene::mesh::{Mesh, NormalMode};
use crate::scene::{ComponentMaps, Falloff, Light, LightKind, Material, Texture};

struct Context<'a> {
    doc: gltf::Document,
    buffers: Vec<gltf::buffer::Data>,
    dir: &'a Path,
    assets: &'a dyn AssetSource,
    path: &'a Path,
}

/// Parses glTF or GLB bytes; `path` locates external buffers and images.
pub fn load(bytes: &[u8], path: &Path, assets: &dyn AssetSource) -> Result<LoadedModel, String> {
    let gltf = gltf::Gltf::from_slice(bytes).map_err(|e| e.to_string())?;
    let dir = path.parent().unwrap_or(Path::new(""));
    let base = assets.base_dir().map(|b| b.join(dir));
    let buffers = gltf::import_buffers(&gltf.document, base.as_deref(), gltf.blob.clone())
        .map_err(|e| format!("buffers: {e}"))?;
    let cx = Context { doc: gltf.document, buffers, dir, assets, path };
    let materials: Vec<Material> = cx.doc.materials().map(|m| cx.material(&m)).collect::<Result<_, _>>()?;
    let mut model = LoadedModel::default();
    let scene = cx.doc.default_scene().or_else(|| cx.doc.scenes().next()).ok_or("the file has no scene")?;
    for node in scene.nodes() {
        cx.visit(&node, Mat4::IDENTITY, &materials, &mut model)?;
    }
    if model.parts.is_empty() {
        return Err("the default scene has no triangle meshes".into());
    }
    Ok(model)
}

impl Context<'_> {
    fn visit(
        &self,
        node: &gltf::Node,
        parent: Mat4,
        materials: &[Material],
        out: &mut LoadedModel,
    ) -> Result<(), String> {
        let world = parent * Mat4::from_cols_array_2d(&node.transform().matrix());
        let affine = Affine3A::from_mat4(world);
        if let Some(mesh) = node.mesh() {
            for prim in mesh.primitives() {
                self.primitive(&prim, mesh.name().unwrap_or("mesh"), affine, materials, out)?;
            }
        }
        if let (Some(cam), None) = (node.camera(), out.camera) {
            out.camera = camera(&cam, affine);
        }
        if let Some(light) = node.light() {
            out.lights.push(self::light(&light, affine));
        }
        for child in node.children() {
            self.visit(&child, world, materials, out)?;
        }
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
        let reader = prim.reader(|b| self.buffers.get(b.index()).map(|d| &d.0[..]));
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
        out.parts.push(Part { name: name.to_string(), mesh: Arc::new(mesh), material, transform });
        Ok(())
    }

    fn material(&self, m: &gltf::Material) -> Result<Material, String> {
        let pbr = m.pbr_metallic_roughness();
        let [r, g, b, a] = pbr.base_color_factor();
        let base = Vec3::new(r, g, b);
        let metal = pbr.metallic_factor().clamp(0.0, 1.0);
        let alpha = pbr.roughness_factor().clamp(0.05, 1.0).powi(2);
        let kd = base * (1.0 - metal);
        let base_map = pbr.base_color_texture().map(|t| self.texture(&t.texture())).transpose()?;
        Ok(Material {
            name: m.name().unwrap_or("gltf").to_string(),
            ka: kd,
            kd,
            ks: Vec3::splat(0.04).lerp(base, metal),
            shininess: (2.0 / (alpha * alpha) - 2.0).clamp(1.0, 2048.0),
            ke: Vec3::from(m.emissive_factor()),
            maps: ComponentMaps {
                ambient: base_map.iter().cloned().collect(),
                diffuse: base_map.into_iter().collect(),
                specular: Vec::new(),
                emission: m.emissive_texture().map(|t| self.texture(&t.texture())).transpose()?.into_iter().collect(),
                filter: Default::default(),
            },
            two_sided: m.double_sided(),
            // BLEND materials are translucent with the base colour's alpha; MASK and
            // OPAQUE ones are drawn opaque (alpha cut-outs are not supported).
            opacity: if m.alpha_mode() == gltf::material::AlphaMode::Blend { a.clamp(0.0, 1.0) } else { 1.0 },
            ..Material::default()
        })
    }

    fn texture(&self, t: &gltf::Texture) -> Result<Arc<Texture>, String> {
        let bytes = match t.source().source() {
            gltf::image::Source::View { view, .. } => {
                let data = &self.buffers[view.buffer().index()].0;
                data.get(view.offset()..view.offset() + view.length()).ok_or("image view outside its buffer")?.to_vec()
            }
            gltf::image::Source::Uri { uri, .. } if uri.starts_with("data:") => {
                return Err("data-URI images are not supported; use a .glb or an image file".into())
            }
            gltf::image::Source::Uri { uri, .. } => {
                return crate::scene::load::texture(&self.dir.join(uri), true, self.assets).map_err(|e| e.to_string())
            }
        };
        Texture::decode(&bytes, true).map(Arc::new).map_err(|e| format!("embedded image {}: {e}", t.index()))
    }
}

fn camera(cam: &gltf::Camera, at: Affine3A) -> Option<Camera> {
    let eye = at.transform_point3(Vec3::ZERO);
    let fwd = at.transform_vector3(Vec3::NEG_Z).normalize_or_zero();
    let up = at.transform_vector3(Vec3::Y).normalize_or_zero();
    let (projection, near, far) = match cam.projection() {
        gltf::camera::Projection::Perspective(p) => (
            Projection::Perspective { fov_y_deg: p.yfov().to_degrees() },
            p.znear(),
            p.zfar().unwrap_or(p.znear() * 1e5),
        ),
        gltf::camera::Projection::Orthographic(o) => {
            (Projection::Orthographic { height: 2.0 * o.ymag() }, o.znear().max(1e-4), o.zfar())
        }
    };
    let c = Camera { eye, target: eye + fwd, up, near, far, projection, shift: glam::Vec2::ZERO };
    c.validate().ok().map(|_| c)
}

fn light(l: &gltf::khr_lights_punctual::Light, at: Affine3A) -> Light {
    use gltf::khr_lights_punctual::Kind;
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
    Light {
        kind,
        color: l.color().into(),
        intensity: l.intensity(),
        ambient: 0.0,
        size: 0.0,
        falloff,
        ..Light::default()
    }
}
