//! Output files hold what was rendered: PFM and EXR keep the linear floats, PNG the
//! sRGB encoding of them.

use std::path::PathBuf;

use kage::output::write_image;
use kage::resolve::LinearImage;
use kage::scene::texture::linear_to_srgb;

fn gradient() -> LinearImage {
    let mut img = LinearImage::new(7, 5);
    for (i, p) in img.pixels_mut().iter_mut().enumerate() {
        *p = glam::Vec3::new(i as f32 / 35.0, 0.5, 1.5 - i as f32 / 20.0);
    }
    img
}

fn scratch(name: &str) -> PathBuf {
    std::env::temp_dir().join(format!("kage-output-{}-{name}", std::process::id()))
}

#[test]
fn pfm_holds_the_linear_floats_bottom_row_first() {
    let img = gradient();
    let path = scratch("g.pfm");
    write_image(&img, &path).unwrap();
    let bytes = std::fs::read(&path).unwrap();
    let header = b"PF\n7 5\n-1.0\n";
    assert_eq!(&bytes[..header.len()], header);
    let floats: Vec<f32> =
        bytes[header.len()..].chunks_exact(4).map(|c| f32::from_le_bytes(c.try_into().unwrap())).collect();
    assert_eq!(floats.len(), 7 * 5 * 3);
    // First stored row is the image's bottom row (y = 4).
    for x in 0..7 {
        let p = img.get(x, 4);
        assert_eq!(&floats[3 * x as usize..3 * x as usize + 3], &p.to_array());
    }
}

#[test]
fn exr_round_trips_and_png_is_srgb() {
    let img = gradient();
    let exr = scratch("g.exr");
    write_image(&img, &exr).unwrap();
    let back = image::open(&exr).unwrap().into_rgb32f();
    for (a, b) in back.pixels().zip(img.pixels()) {
        assert_eq!([a[0], a[1], a[2]], b.to_array());
    }
    let png = scratch("g.png");
    write_image(&img, &png).unwrap();
    let back = image::open(&png).unwrap().into_rgb8();
    for (a, b) in back.pixels().zip(img.pixels()) {
        for k in 0..3 {
            let want = (linear_to_srgb(b[k].clamp(0.0, 1.0)) * 255.0).round() as i32;
            assert!((a[k] as i32 - want).abs() <= 1, "{} vs {want}", a[k]);
        }
    }
}
