//! Output files hold what was rendered: PFM and EXR keep the linear floats, PNG the
//! sRGB encoding of them.

use std::path::PathBuf;

use kage::image::ToneCurve;
use kage::image::{linear_to_srgb, LinearImage};
use kage::output::write_image;

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
    write_image(&img, &path, 1.0, ToneCurve::Clip).unwrap();
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
fn exr_round_trips_unexposed_and_png_is_exposed_srgb() {
    let img = gradient();
    let exr = scratch("g.exr");
    write_image(&img, &exr, 2.0, ToneCurve::Clip).unwrap();
    let back = image::open(&exr).unwrap().into_rgb32f();
    for (a, b) in back.pixels().zip(img.pixels()) {
        assert_eq!([a[0], a[1], a[2]], b.to_array());
    }
    let png = scratch("g.png");
    write_image(&img, &png, 0.5, ToneCurve::Clip).unwrap();
    let back = image::open(&png).unwrap().into_rgb8();
    for (a, b) in back.pixels().zip(img.pixels()) {
        for k in 0..3 {
            let want = (linear_to_srgb((0.5 * b[k]).clamp(0.0, 1.0)) * 255.0).round() as i32;
            assert!((a[k] as i32 - want).abs() <= 1, "{} vs {want}", a[k]);
        }
    }
}

#[test]
fn auto_exposure_brings_the_bright_end_to_white() {
    use kage::scene::Exposure;
    let mut img = LinearImage::new(100, 1);
    for (i, p) in img.pixels_mut().iter_mut().enumerate() {
        *p = glam::Vec3::splat(4.0 * i as f32); // physical units, far above 1
    }
    let s = Exposure::Auto.scale(&img);
    assert!((s * 4.0 * 95.0 - 0.9).abs() < 1e-4, "scale {s}");
    assert_eq!(Exposure::Stops(2.0).scale(&img), 4.0);
    assert_eq!(Exposure::Stops(0.0).scale(&LinearImage::new(1, 1)), 1.0);
}

#[test]
fn exposure_in_scene_files_and_on_the_command_line() {
    use kage::scene::file::SceneFile;
    use kage::scene::load::FileSystem;
    use kage::scene::Exposure;
    let fs = FileSystem { base: std::env::temp_dir() };
    let build = |t: &str| SceneFile::parse(t, std::path::Path::new("e.toml")).and_then(|f| f.build(&fs));
    let obj = "[[object]]\nshape = \"cube\"\n";
    assert_eq!(build(&format!("[image]\nexposure = \"auto\"\n{obj}")).unwrap().exposure, Exposure::Auto);
    assert_eq!(build(&format!("[image]\nexposure = -1.5\n{obj}")).unwrap().exposure, Exposure::Stops(-1.5));
    let e = build(&format!("[image]\nexposure = \"bright\"\n{obj}")).unwrap_err().to_string();
    assert!(e.starts_with("e.toml:2:12"), "{e}");
}

#[test]
fn written_images_read_back() {
    use kage::output::read_image;
    let img = gradient();
    for ext in ["pfm", "exr"] {
        let path = scratch(&format!("rb.{ext}"));
        write_image(&img, &path, 1.0, ToneCurve::Clip).unwrap();
        assert_eq!(read_image(&path).unwrap(), img, "{ext}");
    }
    let png = scratch("rb.png");
    write_image(&img, &png, 1.0, ToneCurve::Clip).unwrap();
    let back = read_image(&png).unwrap();
    for (a, b) in back.pixels().iter().zip(img.pixels()) {
        // 8-bit sRGB quantisation, values clamped to [0, 1].
        assert!((*a - b.clamp(glam::Vec3::ZERO, glam::Vec3::ONE)).abs().max_element() < 0.01, "{a} vs {b}");
    }
    let bad = scratch("bad.pfm");
    std::fs::write(&bad, b"PF\n7 5\n-1.0\n\x00\x00").unwrap();
    assert!(read_image(&bad).unwrap_err().to_string().contains("bytes of pixels"));
}
