//! Materials as their files mean them: an MTL's illumination model makes
//! mirrors and glass, a texture named in another letter case is found, and a
//! texture not found at all is a warning and a visible stand-in.

#[path = "common/skip.rs"]
mod skip;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use glam::Vec3;
use kage::scene::file::load_scene;
use kage::{render, RenderOptions};

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("kage-materials-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// OBJ text for a quad `a b c d` (counter-clockwise seen from the front)
/// with material `m`, vertices numbered from `*next`.
fn quad(obj: &mut String, next: &mut usize, m: &str, [a, b, c, d]: [Vec3; 4]) {
    writeln!(obj, "usemtl {m}").unwrap();
    for v in [a, b, c, d] {
        writeln!(obj, "v {} {} {}", v.x, v.y, v.z).unwrap();
    }
    let n = *next;
    writeln!(obj, "f {} {} {} {}", n, n + 1, n + 2, n + 3).unwrap();
    *next += 4;
}

/// A UV sphere of radius `r` at `c` with material `m`, outward faces.
fn sphere(obj: &mut String, next: &mut usize, m: &str, c: Vec3, r: f32) {
    writeln!(obj, "usemtl {m}").unwrap();
    let (rings, segments) = (24, 48);
    for i in 0..=rings {
        let theta = std::f32::consts::PI * i as f32 / rings as f32;
        for j in 0..segments {
            let phi = std::f32::consts::TAU * j as f32 / segments as f32;
            let p = c + r * Vec3::new(theta.sin() * phi.cos(), theta.cos(), theta.sin() * phi.sin());
            writeln!(obj, "v {} {} {}", p.x, p.y, p.z).unwrap();
        }
    }
    let at = |i: usize, j: usize| *next + i * segments + j % segments;
    for i in 0..rings {
        for j in 0..segments {
            let (a, b, c, d) = (at(i, j), at(i, j + 1), at(i + 1, j + 1), at(i + 1, j));
            writeln!(obj, "f {a} {b} {c} {d}").unwrap();
        }
    }
    *next += (rings + 1) * segments;
}

/// A box open towards +z, red on the left, green on the right, a mirror and
/// a glass sphere inside, materials in an MTL the way the sphere Cornell box
/// writes them (`illum 5` mirror, `illum 7` glass with `Tf` and `Ni`).
fn sphere_box(dir: &Path) -> PathBuf {
    let mtl = "newmtl white\nKd 0.7 0.7 0.7\nKs 0 0 0\nillum 2\n\
               newmtl red\nKd 0.8 0.05 0.05\nillum 2\n\
               newmtl green\nKd 0.05 0.8 0.05\nillum 2\n\
               newmtl mirror\nKd 0 0 0\nKs 0.95 0.95 0.95\nNs 500\nillum 5\n\
               newmtl glass\nKd 0 0 0\nKs 0.1 0.1 0.1\nNs 500\nTf 1 1 1\nNi 1.5\nillum 7\n";
    std::fs::write(dir.join("box.mtl"), mtl).unwrap();
    let mut obj = String::from("mtllib box.mtl\n");
    let mut next = 1;
    let v = Vec3::new;
    quad(&mut obj, &mut next, "white", [v(-1., 0., 1.), v(1., 0., 1.), v(1., 0., -1.), v(-1., 0., -1.)]); // floor
    quad(&mut obj, &mut next, "white", [v(-1., 2., -1.), v(1., 2., -1.), v(1., 2., 1.), v(-1., 2., 1.)]); // ceiling
    quad(&mut obj, &mut next, "white", [v(-1., 0., -1.), v(1., 0., -1.), v(1., 2., -1.), v(-1., 2., -1.)]); // back
    quad(&mut obj, &mut next, "red", [v(-1., 0., 1.), v(-1., 0., -1.), v(-1., 2., -1.), v(-1., 2., 1.)]); // left
    quad(&mut obj, &mut next, "green", [v(1., 0., -1.), v(1., 0., 1.), v(1., 2., 1.), v(1., 2., -1.)]); // right
    sphere(&mut obj, &mut next, "mirror", v(-0.45, 0.4, -0.2), 0.4);
    sphere(&mut obj, &mut next, "glass", v(0.45, 0.4, 0.3), 0.4);
    std::fs::write(dir.join("box.obj"), obj).unwrap();
    let scene = "[image]\nwidth = 200\nheight = 200\nantialias = { method = \"none\" }\n\
                 [camera]\neye = [0, 1, 4.2]\ntarget = [0, 1, 0]\nfov = 40\n\
                 [[light]]\ntype = \"point\"\nposition = [0, 1.9, 0.5]\nintensity = 1.0\nambient = 0.25\n\
                 [[object]]\nmesh = \"box.obj\"\n";
    std::fs::write(dir.join("box.toml"), scene).unwrap();
    dir.join("box.toml")
}

#[test]
fn mtl_illumination_models_make_mirrors_and_glass() {
    let dir = scratch("illum");
    let scene = load_scene(&sphere_box(&dir)).unwrap();
    let by_name = |n: &str| scene.materials.iter().find(|m| m.name == n).unwrap();
    let (mirror, glass) = (by_name("mirror"), by_name("glass"));
    assert!(mirror.kr.min_element() > 0.9 && mirror.kt == Vec3::ZERO, "mirror: kr {} kt {}", mirror.kr, mirror.kt);
    assert!(glass.kt.min_element() > 0.8 && glass.ior == 1.5, "glass: kt {} ior {}", glass.kt, glass.ior);
    let frame = render(&scene, &RenderOptions::default()).unwrap();
    let object_of = |m: &str| scene.objects.iter().position(|o| scene.materials[o.material].name == m).unwrap();
    let (mirror_obj, glass_obj) = (object_of("mirror"), object_of("glass"));
    // Pixels of each sphere, split at the sphere's image centre.
    let pixels = |object: usize| -> Vec<(u32, u32, Vec3)> {
        (0..scene.height)
            .flat_map(|y| (0..scene.width).map(move |x| (x, y)))
            .filter(|&(x, y)| frame.visibility.item(x, y).object as usize == object)
            .map(|(x, y)| (x, y, frame.image.get(x, y)))
            .collect()
    };
    let mirror_px = pixels(mirror_obj);
    assert!(mirror_px.len() > 500, "the mirror sphere shows: {} pixels", mirror_px.len());
    let centre = mirror_px.iter().map(|p| p.0 as f32).sum::<f32>() / mirror_px.len() as f32;
    let left: Vec<Vec3> = mirror_px.iter().filter(|p| (p.0 as f32) < centre - 8.0).map(|p| p.2).collect();
    let reddish = left.iter().filter(|c| c.x > 0.05 && c.x > 2.0 * c.y && c.x > 2.0 * c.z).count();
    assert!(reddish * 3 > left.len(), "the mirror's left side shows the red wall: {reddish} of {} pixels", left.len());
    let glass_px = pixels(glass_obj);
    let mean = glass_px.iter().map(|p| p.2).sum::<Vec3>() / glass_px.len() as f32;
    assert!(glass_px.len() > 500 && mean.max_element() > 0.1, "the glass sphere is not black: mean {mean}");
}

#[test]
fn a_texture_in_another_case_is_found_and_a_missing_one_is_a_checker() {
    let dir = scratch("textures");
    let blue = image::RgbImage::from_pixel(2, 2, image::Rgb([20, 40, 230]));
    blue.save(dir.join("paint.png")).unwrap();
    let mtl = "newmtl painted\nKd 1 1 1\nmap_Kd PAINT.PNG\nnewmtl lost\nKd 1 1 1\nmap_Kd gone.png\n";
    std::fs::write(dir.join("two.mtl"), mtl).unwrap();
    let obj = "mtllib two.mtl\nv -2 0 0\nv -0.1 0 0\nv -0.1 1 0\nv -2 1 0\nv 0.1 0 0\nv 2 0 0\nv 2 1 0\nv 0.1 1 0\n\
               vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n\
               usemtl painted\nf 1/1 2/2 3/3 4/4\nusemtl lost\nf 5/1 6/2 7/3 8/4\n";
    std::fs::write(dir.join("two.obj"), obj).unwrap();
    let scene_text = "[image]\nwidth = 160\nheight = 80\n[camera]\neye = [0, 0.5, 3]\ntarget = [0, 0.5, 0]\n\
                      [[light]]\ntype = \"directional\"\ndirection = [0, 0, -1]\nambient = 0.3\n\
                      [[object]]\nmesh = \"two.obj\"\n";
    std::fs::write(dir.join("two.toml"), scene_text).unwrap();
    let scene = load_scene(&dir.join("two.toml")).unwrap();
    let warned: Vec<&String> = scene.warnings.iter().filter(|w| w.contains("gone.png")).collect();
    assert_eq!(warned.len(), 1, "one warning for the missing texture: {:?}", scene.warnings);
    assert!(!scene.warnings.iter().any(|w| w.to_lowercase().contains("paint.png")), "{:?}", scene.warnings);
    let frame = render(&scene, &RenderOptions::default()).unwrap();
    let (painted, lost) = (frame.image.get(40, 40), frame.image.get(120, 40));
    assert!(painted.z > 3.0 * painted.x, "the texture found in another case paints blue: {painted}");
    // The checker's texels, filtered together at this size: magenta-grey.
    assert!(lost.x > 1.5 * lost.y && lost.z > 1.5 * lost.y, "the stand-in is magenta-ish: {lost}");
}

/// Sponza as shipped: ten textures named in another letter case than on
/// disk; it loads, textured, with no warning about textures.
#[test]
fn sponza_loads_with_its_textures() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/assets/scenes/sponza-dabrovic/sponza.obj");
    if !path.exists() {
        skip::skipped(&format!("{} is absent", path.display()));
        return;
    }
    let scene = kage::scene::model::scene_for_model(&path, 160, 90).unwrap();
    assert!(!scene.warnings.iter().any(|w| w.contains("texture")), "{:?}", scene.warnings);
    let textured = scene.materials.iter().filter(|m| !m.maps.diffuse.is_empty()).count();
    assert!(textured >= 15, "{textured} materials textured");
    let frame = render(&scene, &RenderOptions::default()).unwrap();
    assert!(frame.visibility.items().iter().filter(|i| !i.is_none()).count() > 160 * 90 / 2);
}
