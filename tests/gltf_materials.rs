//! glTF materials as their files mean them: metallic-roughness textures,
//! metals that mirror a studio, transmission and index of refraction,
//! embedded `data:` buffers and images, photometric lights through a tone
//! curve without clipping.

#[path = "common/skip.rs"]
mod skip;
use std::path::{Path, PathBuf};

use base64::Engine as _;
use glam::Vec3;
use kage::scene::model::scene_for_model;
use kage::{render, RenderOptions, Scene};

fn asset(rel: &str) -> Option<PathBuf> {
    skip::asset(&format!("gltf/{rel}"))
}

/// Mean colour of the pixels showing the model (not the ground, not the
/// background).
fn model_mean(
    scene: &Scene,
    image: &kage::image::LinearImage,
    visibility: &kage::visibility::VisibilityBuffer,
) -> Vec3 {
    mean_of(scene, image, visibility, |name| name != "ground")
}

/// Mean colour of the pixels showing objects whose name passes `keep`.
fn mean_of(
    scene: &Scene,
    image: &kage::image::LinearImage,
    visibility: &kage::visibility::VisibilityBuffer,
    keep: impl Fn(&str) -> bool,
) -> Vec3 {
    let (mut sum, mut n) = (Vec3::ZERO, 0);
    for y in 0..scene.height {
        for x in 0..scene.width {
            let item = visibility.item(x, y);
            if !item.is_none() && keep(&scene.objects[item.object as usize].name) {
                sum += image.get(x, y);
                n += 1;
            }
        }
    }
    assert!(n > 200, "the model shows ({n} pixels)");
    sum / n as f32
}

#[test]
fn the_avocado_is_green_and_the_metal_spheres_are_not_black() {
    let Some(avocado) = asset("Avocado/Avocado.gltf") else { return };
    let scene = scene_for_model(&avocado, 160, 120).unwrap();
    let frame = render(&scene, &RenderOptions::default()).unwrap();
    let mean = model_mean(&scene, &frame.image, &frame.visibility);
    assert!(mean.y > 0.08 && mean.y > mean.z, "the avocado: mean {mean}");
    let Some(spheres) = asset("MetalRoughSpheresNoTextures/MetalRoughSpheresNoTextures.glb") else { return };
    let scene = scene_for_model(&spheres, 160, 120).unwrap();
    assert!(scene.environment.is_some(), "a metal model gets a studio to mirror");
    let frame = render(&scene, &RenderOptions::default()).unwrap();
    let mean = model_mean(&scene, &frame.image, &frame.visibility);
    assert!(mean.max_element() > 0.15, "the metal spheres: mean {mean}");
}

#[test]
fn the_lamps_photometric_lights_do_not_clip() {
    let Some(lamp) = asset("LightsPunctualLamp/LightsPunctualLamp.gltf") else { return };
    let scene = scene_for_model(&lamp, 240, 180).unwrap();
    let frame = render(&scene, &RenderOptions::default()).unwrap();
    let bytes = frame.image.to_srgb8_toned(scene.exposure.scale(&frame.image), scene.tone);
    let clipped = bytes.chunks_exact(3).filter(|p| p.contains(&255)).count();
    assert!(clipped * 100 < bytes.len() / 3, "{clipped} of {} pixels clipped", bytes.len() / 3);
    let glass = scene.materials.iter().filter(|m| m.kt.max_element() > 0.0).count();
    assert!(glass > 0, "the lamp's shade transmits (KHR_materials_transmission)");
}

/// One quad, its buffer and its 2 × 2 texture both inline `data:` URIs, as
/// "glTF Embedded" exports write them; transmission and IOR on a second
/// material.
fn embedded_gltf(dir: &Path) -> PathBuf {
    let b64 = |bytes: &[u8]| base64::engine::general_purpose::STANDARD.encode(bytes);
    let mut png = Vec::new();
    image::RgbImage::from_pixel(2, 2, image::Rgb([230, 20, 20]))
        .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
        .unwrap();
    let positions: [f32; 12] = [-1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 2.0, 0.0, -1.0, 2.0, 0.0];
    let uvs: [f32; 8] = [0.0, 1.0, 1.0, 1.0, 1.0, 0.0, 0.0, 0.0];
    let indices: [u16; 6] = [0, 1, 2, 0, 2, 3];
    let mut buffer: Vec<u8> = positions.iter().chain(&uvs).flat_map(|f| f.to_le_bytes()).collect();
    buffer.extend(indices.iter().flat_map(|i| i.to_le_bytes()));
    let json = format!(
        r#"{{
  "asset": {{ "version": "2.0" }},
  "extensionsUsed": ["KHR_materials_transmission", "KHR_materials_ior"],
  "scene": 0, "scenes": [{{ "nodes": [0, 1] }}],
  "nodes": [{{ "mesh": 0 }}, {{ "mesh": 1, "translation": [2.5, 0, 0] }}],
  "meshes": [
    {{ "name": "painted", "primitives": [{{ "attributes": {{ "POSITION": 0, "TEXCOORD_0": 1 }}, "indices": 2, "material": 0 }}] }},
    {{ "name": "glass", "primitives": [{{ "attributes": {{ "POSITION": 0 }}, "indices": 2, "material": 1 }}] }}
  ],
  "materials": [
    {{ "pbrMetallicRoughness": {{ "baseColorTexture": {{ "index": 0 }}, "metallicFactor": 0.0 }} }},
    {{ "pbrMetallicRoughness": {{ "metallicFactor": 0.0 }},
       "extensions": {{ "KHR_materials_transmission": {{ "transmissionFactor": 0.9 }}, "KHR_materials_ior": {{ "ior": 1.7 }} }} }}
  ],
  "textures": [{{ "source": 0 }}],
  "images": [{{ "uri": "data:image/png;base64,{png}" }}],
  "buffers": [{{ "byteLength": {len}, "uri": "data:application/octet-stream;base64,{buf}" }}],
  "bufferViews": [
    {{ "buffer": 0, "byteOffset": 0, "byteLength": 48 }},
    {{ "buffer": 0, "byteOffset": 48, "byteLength": 32 }},
    {{ "buffer": 0, "byteOffset": 80, "byteLength": 12 }}
  ],
  "accessors": [
    {{ "bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3", "min": [-1, 0, 0], "max": [1, 2, 0] }},
    {{ "bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC2" }},
    {{ "bufferView": 2, "componentType": 5123, "count": 6, "type": "SCALAR" }}
  ]
}}"#,
        png = b64(&png),
        len = buffer.len(),
        buf = b64(&buffer)
    );
    let path = dir.join("embedded.gltf");
    std::fs::write(&path, json).unwrap();
    path
}

#[test]
fn embedded_data_uris_and_transmission_are_read() {
    let dir = std::env::temp_dir().join(format!("kage-gltf-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let scene = scene_for_model(&embedded_gltf(&dir), 120, 120).unwrap();
    let glass = scene.materials.iter().find(|m| m.kt.max_element() > 0.0).expect("the transmissive material");
    assert!((glass.kt.x - 0.9).abs() < 1e-6 && glass.ior == 1.7, "kt {} ior {}", glass.kt, glass.ior);
    let frame = render(&scene, &RenderOptions::default()).unwrap();
    let mean = mean_of(&scene, &frame.image, &frame.visibility, |name| name.ends_with("/painted"));
    assert!(mean.x > 3.0 * mean.y && mean.x > 3.0 * mean.z, "the embedded red texture shows: {mean}");
}
