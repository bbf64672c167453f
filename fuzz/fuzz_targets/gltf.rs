//! glTF JSON or GLB bytes (GLB when they start with its magic) loaded as a
//! model, with `buf.bin` and `tex.png` to name, and rendered.
#![no_main]
libfuzzer_sys::fuzz_target!(|bytes: &[u8]| {
    let name = if bytes.starts_with(b"glTF") { "m.glb" } else { "m.gltf" };
    kage_fuzz::model(name, bytes);
});
