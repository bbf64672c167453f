//! Test helpers: random scenes and an independent brute-force ray caster.
//!
//! The ray caster shares no code with the renderer: its own camera basis, its own
//! ray/triangle test (with the inside test), every triangle tried for every pixel.
#![allow(dead_code)]

use std::sync::Arc;

use glam::{Affine3A, Vec3};
use kage::camera::{Camera, Projection};
use kage::scene::mesh::NormalMode;
use kage::scene::{Antialias, Falloff, Light, LightKind, Material, Mesh, Object, Scene};
use kage::shadows::ShadowTerm;
use rand::rngs::StdRng;
use rand::Rng;

/// A scene of one object holding `mesh`, seen by `camera`, one sample at each
/// pixel centre (no antialiasing), as the ray caster samples it.
pub fn scene_with(mesh: Mesh, camera: Camera, width: u32, height: u32, two_sided: bool) -> Scene {
    Scene {
        width,
        height,
        background: Vec3::new(0.1, 0.1, 0.15),
        camera,
        lights: vec![Light {
            kind: LightKind::Point { position: Vec3::new(2.0, 5.0, 3.0) },
            color: Vec3::ONE,
            intensity: 1.0,
            ambient: 0.1,
            size: 0.0,
            falloff: Falloff::None,
            ..Light::default()
        }],
        lights_follow_camera: false,
        materials: vec![Material { two_sided, ..Material::default() }],
        objects: vec![Object::mesh("soup", Arc::new(mesh), Affine3A::IDENTITY, 0)],
        warnings: Vec::new(),
        exposure: Default::default(),
        antialias: Antialias::None,
        fog: None,
        ambient_occlusion: None,
        lines: None,
        environment: None,
        translucency: Default::default(),
        tone: Default::default(),
        limits: Default::default(),
        camera_path: None,
    }
}

/// `n` random triangles of random sizes inside [-1, 1]³.
pub fn triangle_soup(rng: &mut StdRng, n: usize) -> Mesh {
    let mut positions = Vec::new();
    let mut triangles = Vec::new();
    for t in 0..n as u32 {
        let c = Vec3::new(rng.gen_range(-1.0..1.0), rng.gen_range(-1.0..1.0), rng.gen_range(-1.0..1.0));
        let s = rng.gen_range(0.1..0.9);
        for _ in 0..3 {
            positions
                .push(c + s * Vec3::new(rng.gen_range(-1.0..1.0), rng.gen_range(-1.0..1.0), rng.gen_range(-1.0..1.0)));
        }
        triangles.push([3 * t, 3 * t + 1, 3 * t + 2]);
    }
    Mesh::new(positions, vec![], vec![], triangles, NormalMode::Flat).expect("soup").0
}

/// A random camera looking at the origin from 2.5–5 units away.
pub fn random_camera(rng: &mut StdRng, ortho: bool) -> Camera {
    let dir = Vec3::new(rng.gen_range(-1.0..1.0), rng.gen_range(-0.8..0.8), rng.gen_range(-1.0..1.0)).normalize();
    let dist = rng.gen_range(2.5..5.0);
    let projection = if ortho {
        Projection::Orthographic { height: rng.gen_range(1.5..3.5) }
    } else {
        Projection::Perspective { fov_y_deg: rng.gen_range(30.0..75.0) }
    };
    // Sometimes the near plane cuts through the soup.
    let near = if rng.gen_bool(0.3) { dist - rng.gen_range(0.0..1.0) } else { 0.05 };
    Camera {
        eye: dir * dist,
        target: Vec3::ZERO,
        up: Vec3::Y,
        near,
        far: dist + rng.gen_range(0.5..3.0),
        projection,
        shift: glam::Vec2::ZERO,
    }
}

/// What the brute-force caster sees at one pixel.
#[derive(Debug, Clone, Copy)]
pub struct Hit {
    /// Triangle index.
    pub triangle: u32,
    /// Distance along the view axis.
    pub view_z: f32,
    /// View-axis distance of the second-nearest hit (infinite if none).
    pub second_z: f32,
}

/// Casts the ray through the centre of pixel (x, y) against every triangle of the
/// scene's single object (world = object space), honouring near/far and culling.
pub fn cast(scene: &Scene, x: u32, y: u32) -> Option<Hit> {
    let cam = &scene.camera;
    let mesh = scene.objects[0].triangles().expect("a mesh");
    let cull = !scene.materials[0].two_sided;
    let fwd = (cam.target - cam.eye).normalize();
    let right = fwd.cross(cam.up).normalize();
    let up = right.cross(fwd);
    let (w, h) = (scene.width as f32, scene.height as f32);
    let sx = (x as f32 + 0.5) / w * 2.0 - 1.0;
    let sy = 1.0 - (y as f32 + 0.5) / h * 2.0;
    let (origin, dir) = match cam.projection {
        Projection::Perspective { fov_y_deg } => {
            let t = (fov_y_deg.to_radians() / 2.0).tan();
            (cam.eye, (fwd + right * sx * t * w / h + up * sy * t).normalize())
        }
        Projection::Orthographic { height } => {
            (cam.eye + right * sx * height / 2.0 * w / h + up * sy * height / 2.0, fwd)
        }
    };
    let along = dir.dot(fwd);
    let mut best: Option<Hit> = None;
    let mut second = f32::INFINITY;
    for (i, t) in mesh.triangles.iter().enumerate() {
        let [a, b, c] = t.map(|k| mesh.positions[k as usize]);
        let Some(dist) = ray_triangle(origin, dir, a, b, c, cull) else {
            continue;
        };
        let z = dist * along;
        if z < cam.near || z > cam.far {
            continue;
        }
        match best {
            Some(hb) if z >= hb.view_z => second = second.min(z),
            _ => {
                if let Some(hb) = best {
                    second = second.min(hb.view_z);
                }
                best = Some(Hit { triangle: i as u32, view_z: z, second_z: f32::INFINITY });
            }
        }
    }
    best.map(|h| Hit { second_z: second, ..h })
}

fn ray_triangle(o: Vec3, d: Vec3, a: Vec3, b: Vec3, c: Vec3, cull: bool) -> Option<f32> {
    // Barycentric solve by Cramer's rule in f64.
    let (o, d, a, b, c) = (o.as_dvec3(), d.as_dvec3(), a.as_dvec3(), b.as_dvec3(), c.as_dvec3());
    let (e1, e2) = (b - a, c - a);
    let n = e1.cross(e2);
    let denom = -d.dot(n);
    if denom.abs() < 1e-12 || (cull && denom <= 0.0) {
        return None;
    }
    let s = o - a;
    let t = s.dot(n) / denom;
    let u = (-d).dot(s.cross(e2)) / denom;
    let v = (-d).dot(e1.cross(s)) / denom;
    (u >= 0.0 && v >= 0.0 && u + v <= 1.0 && t > 0.0).then_some(t as f32)
}

/// View-axis distance encoded by the renderer's reversed depth `d` (the inverse of
/// the conventions in ARCHITECTURE.md: perspective d = near / z, orthographic
/// d = (far − z) / (far − near)).
pub fn view_distance(cam: &Camera, d: f32) -> f32 {
    match cam.projection {
        Projection::Perspective { .. } => cam.near / d,
        Projection::Orthographic { .. } => cam.far - d * (cam.far - cam.near),
    }
}

/// Shadow terms `terms` (one per light) against shadow rays: (misclassified,
/// compared) over the visible pixels' surfaces (at pixel centres) facing a
/// light that casts shadows.
pub fn terms_vs_rays(scene: &Scene, terms: &[ShadowTerm]) -> (usize, usize) {
    decisions_vs_rays(scene, |light, at| {
        let receiver = at.receiver();
        terms[light].casts().then(|| terms[light].lit(at.surface.position, at.cos_theta, &receiver))
    })
}

/// [`kage::raytrace::shadow_truth::ShadowRays::misclassified`] over `scene`'s
/// frame.
pub fn decisions_vs_rays(
    scene: &Scene,
    decide: impl Fn(usize, &kage::raytrace::shadow_truth::ShadowQuery) -> Option<f32> + Sync,
) -> (usize, usize) {
    let frame = kage::render(scene, &kage::RenderOptions::default()).expect("render");
    kage::raytrace::shadow_truth::ShadowRays::new(scene).misclassified(&frame.visibility, decide)
}

/// The demo and four example scenes whose shadows the shadow tests judge, at
/// 320 × 200.
pub fn shadow_example_scenes() -> Vec<(&'static str, Scene)> {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/scenes");
    let mut scenes = vec![("demo", kage::scene::demo::demo_scene().unwrap())];
    for name in ["spotlights", "cad-ortho", "reflections", "showroom"] {
        scenes.push((name, kage::scene::file::load_scene(&dir.join(format!("{name}.toml"))).unwrap()));
    }
    for (_, scene) in &mut scenes {
        (scene.width, scene.height) = (320, 200);
    }
    scenes
}
