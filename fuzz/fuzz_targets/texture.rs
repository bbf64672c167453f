//! Image bytes (PNG, JPEG, OpenEXR, guessed from their start) decoded as a
//! texture and sampled: every texel must be finite and ≥ 0.
#![no_main]
libfuzzer_sys::fuzz_target!(|bytes: &[u8]| {
    for srgb in [true, false] {
        if let Ok(t) = kage::scene::Texture::decode(bytes, srgb, &kage_fuzz::limits()) {
            for uv in [glam::Vec2::ZERO, glam::Vec2::new(0.3, 0.7), glam::Vec2::ONE] {
                let v = t.sample(uv);
                assert!(v.is_finite() && v.min_element() >= 0.0, "texel {v}");
            }
        }
    }
});
