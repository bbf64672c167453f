//! OBJ and MTL text, split at the first NUL byte, loaded as a model (its MTL
//! named `m.mtl`, which may name `tex.png`) and rendered.
#![no_main]
libfuzzer_sys::fuzz_target!(|bytes: &[u8]| {
    let (obj, mtl) = match bytes.iter().position(|&b| b == 0) {
        Some(i) => (&bytes[..i], &bytes[i + 1..]),
        None => (bytes, &[][..]),
    };
    let files = kage_fuzz::files(&[("m.obj", obj), ("m.mtl", mtl)]);
    kage_fuzz::model_from("m.obj", &files);
});
