//! `kage render`: one image of a scene or model, the frames of a turntable or
//! camera path, tiles of a frame, or the ray-traced reference — its options,
//! how they become a scene, and the run with its progress and statistics.
//! `kage batch` renders each file through [`render_command`] too.

use std::path::{Path, PathBuf};

use glam::Vec3;
use kage::csg::openscad::{CsgOptions, Geometry};
use kage::image::{PixelRect, ToneCurve};
use kage::limits::{LimitSetting, Limits};
use kage::scene::framing::{CameraOverride, View};
use kage::scene::load::InputFormat;
use kage::scene::model::{self, ModelOptions};
use kage::scene::{
    demo::demo_scene, file, Antialias, EdgeFilter, EdgeMode, EdgeSelection, Exposure, Scene, ShadowMethod, Up,
};
use kage::{Component, ComponentSet, RenderOptions, Renderer};

use crate::{report, scad, tiles};

#[derive(clap::Args, Clone)]
pub struct RenderArgs {
    /// Scene or model file (omit for the built-in demo): .toml, .obj, .stl,
    /// .off, .gltf, .glb, .csg, or .scad (through `openscad`, when installed).
    input: Option<PathBuf>,
    /// No "wrote" lines (a batch reports each file itself); warnings still.
    #[arg(skip)]
    pub(crate) quiet: bool,
    /// Output image: .png or .jpg (8-bit sRGB through the tone curve), .exr or
    /// .pfm (linear float, as rendered). For many frames, a run of #s in the
    /// name is replaced by the frame number, zero-padded to its length
    /// (spin.####.png: spin.0000.png, spin.0001.png, ...).
    #[arg(short, long, default_value = "kage.png")]
    output: PathBuf,
    /// Render N frames of a turntable: the camera goes once round the
    /// vertical through what it looks at (a model: its centre), frame i at
    /// 360·i/N degrees. A model's own light rig turns with the camera, so
    /// every side is lit alike; a scene file's (or a glTF file's) lights stay
    /// put. The output name needs #s for the frame number.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=1_000_000))]
    turntable: Option<u32>,
    /// Render only frame I (from 0) of the turntable or of the scene file's
    /// camera path, exactly as the whole run renders it.
    #[arg(long, value_name = "I", conflicts_with = "shard")]
    frame: Option<u32>,
    /// Render only share I (from 0) of N of the frames: frames I, I + N,
    /// I + 2N, ... of the turntable or camera path, in one process (the
    /// scene loaded once).
    #[arg(long, value_parser = tiles::parse_share, value_name = "I/N")]
    shard: Option<(u32, u32)>,
    /// Render only pixels X0..X1 (columns) by Y0..Y1 (rows) of the image,
    /// exactly as the whole image has them. An .exr output records where
    /// the tile goes, for `kage merge`; other formats hold just the crop.
    #[arg(long, value_parser = tiles::parse_region, value_name = "X0,Y0,X1,Y1", conflicts_with = "tile")]
    region: Option<PixelRect>,
    /// Render only tile I (from 0) of N: the image cut into a grid of N
    /// tiles as near square as N allows, numbered row by row from the top
    /// left. As --region otherwise.
    #[arg(long, value_parser = tiles::parse_share, value_name = "I/N")]
    tile: Option<(u32, u32)>,
    /// Image width in pixels (default: the scene's, 960 for a model).
    #[arg(long)]
    width: Option<u32>,
    /// Image height in pixels (default: the scene's, 540 for a model).
    #[arg(long)]
    height: Option<u32>,
    /// Worker threads (default: one per core).
    #[arg(long)]
    threads: Option<usize>,
    /// Render the ray-traced reference (slow, the truth to compare with)
    /// instead of the fast raster pipeline.
    #[arg(long)]
    reference: bool,
    /// Reference: primary rays per pixel along each axis (n x n per pixel).
    #[arg(long, default_value_t = 4, value_parser = clap::value_parser!(u32).range(1..=64))]
    spp: u32,
    /// Reference: shadow rays per light along each axis, for lights with a size.
    #[arg(long, default_value_t = 4, value_parser = clap::value_parser!(u32).range(1..=64))]
    light_samples: u32,
    /// Reference: no shadows.
    #[arg(long)]
    no_shadows: bool,
    /// How many times light may bounce off mirrors and through glass
    /// (materials with reflection `kr` or transmission `kt`).
    #[arg(long, default_value_t = 4, value_parser = clap::value_parser!(u32).range(0..=16))]
    ray_depth: u32,
    /// Antialiasing. `edge` (the default): smooths outlines and creases in one
    /// extra step, about 1.0-1.3x the time of a frame, and traces mirrors and
    /// glass again where what they show has an edge; `edge:all` smooths every
    /// triangle edge, `edge:paper` blends as the original edge-pass paper does.
    /// `jitter:N`: renders N slightly shifted frames and averages them (also
    /// smooths shadows, textures and reflections; N times the time). `none`: off.
    #[arg(long, value_parser = parse_antialias)]
    antialias: Option<Antialias>,
    /// Also write these parts of the image, each on its own, next to the
    /// output as NAME.PART.EXT: a comma list of ambient, diffuse, specular,
    /// reflection (the environment map), emission (with the background),
    /// traced (ray-traced reflections and refraction), fog; or `all` (these
    /// seven, which add up to the image). `shadow` writes each light's shadow
    /// term as NAME.shadow.N.exr (N: the light's number from 0, in the
    /// scene's order; 1 lit, 0 in shadow); `occlusion` writes ambient
    /// occlusion's open share as NAME.occlusion.EXT (with --ao; 1 open).
    #[arg(long, value_parser = parse_aovs)]
    aov: Option<Aovs>,
    /// Brightness of 8-bit output: stops (e.g. 1.5, -1) or `auto`.
    #[arg(long, value_parser = parse_exposure, allow_hyphen_values = true)]
    exposure: Option<Exposure>,
    /// How 8-bit output rolls off light brighter than white: `neutral` (the
    /// default: colours as the materials say, highlights compressed without
    /// changing their hue), `agx`, `aces` (film-like contrast), or `none`
    /// (clipped).
    #[arg(long, value_parser = parse_tone)]
    tonemap: Option<ToneCurve>,
    /// Every light's shadows by this method instead of its own: `none`,
    /// `map` (shadow maps), `slb` (silhouette-line buffer: shadow maps with
    /// exact edges inside each texel), `soft` (soft shadows from two shadow
    /// maps) or `pcss` (percentage-closer soft shadows). Each light keeps its
    /// other shadow settings.
    #[arg(long, value_parser = parse_shadow_method)]
    shadows: Option<ShadowMethod>,
    /// Section: everything beyond a plane removed and the cut faces of closed
    /// parts drawn (red). `x=VALUE` removes x > VALUE, `-x=VALUE` removes
    /// x < VALUE (likewise y, z), in the model file's own coordinates (a
    /// scene file's world; its `[section]` takes any plane).
    #[arg(long, value_parser = parse_section, allow_hyphen_values = true, value_name = "[-]AXIS=VALUE")]
    section: Option<kage::scene::section::SectionPlane>,
    /// X-ray: every part but the ground drawn see-through (front and back faces
    /// blended in depth order, whatever order the file lists them in), so
    /// parts inside others show; shadows off.
    #[arg(long)]
    xray: bool,
    /// Feature lines: silhouettes, boundaries and creases drawn as dark
    /// antialiased lines over the image (the scene file's `[lines]`, or these
    /// defaults).
    #[arg(long)]
    lines: bool,
    /// Feature lines hidden behind surfaces drawn too, dashed. Implies --lines.
    #[arg(long)]
    hidden_lines: bool,
    /// Feature lines' width in pixels (default 1.5). Implies --lines.
    #[arg(long, value_name = "PIXELS", value_parser = parse_line_width)]
    line_width: Option<f32>,
    /// A technical drawing: white surfaces with flat light, no ground, no
    /// shadows, feature lines with the hidden ones dashed.
    #[arg(long)]
    drawing: bool,
    /// Ambient occlusion: darkens the ambient light in creases, at the foot
    /// of parts and inside holes, by rays from each pixel's surface point
    /// (the scene file's `[ambient_occlusion]`, or these defaults).
    #[arg(long)]
    ao: bool,
    /// Ambient occlusion: how far away (world units) a surface still darkens
    /// (default: a tenth of the model's diagonal). Implies --ao.
    #[arg(long, value_name = "DISTANCE", value_parser = parse_positive)]
    ao_radius: Option<f32>,
    /// Ambient occlusion: rays per pixel (default 16; more: less grain, more
    /// time). Implies --ao.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=4096))]
    ao_rays: Option<u32>,
    /// Ambient occlusion estimated from the frame's depth buffer instead of
    /// rays (the viewer's form while the camera moves): a fraction of the
    /// cost, blind to surfaces the image does not show. Implies --ao.
    #[arg(long)]
    ao_screen: bool,
    /// An OpenSCAD .csg model's spheres and cylinders: `exact` (true curved
    /// surfaces) or `faceted` as OpenSCAD's own mesh ($fn, $fa, $fs), to compare
    /// with OpenSCAD pixel for pixel.
    #[arg(long, value_enum, default_value_t = GeometryArg::Exact)]
    geometry: GeometryArg,
    /// An OpenSCAD .csg model: skip nodes kage cannot render (linear_extrude,
    /// text, import, ...) with a warning instead of failing.
    #[arg(long)]
    skip_unsupported: bool,
    /// A model file: which of its axes points up (default: its format's: z
    /// for STL and OpenSCAD, y for OBJ and glTF).
    #[arg(long, value_enum)]
    up: Option<UpArg>,
    /// A model file: no ground under it.
    #[arg(long)]
    no_ground: bool,
    /// A model file: `framed` (a camera that frames the model) or `file` (the
    /// file's own camera: a glTF camera, an OpenSCAD camera sidecar or
    /// OpenSCAD's default view).
    #[arg(long, value_enum, default_value_t = CameraArg::Framed)]
    camera: CameraArg,
    /// Frame the model (a scene: its shadow casters) from the front, right,
    /// top or iso (isometric) side.
    #[arg(long, value_enum, conflicts_with = "orbit")]
    view: Option<ViewArg>,
    /// Frame the model from AZIMUTH,ELEVATION degrees: azimuth about the
    /// vertical from the front (90: from the right), elevation above the
    /// horizon (negative: from below). E.g. --orbit 30,20.
    #[arg(long, value_parser = parse_orbit, allow_hyphen_values = true, value_name = "AZIMUTH,ELEVATION")]
    orbit: Option<View>,
    /// Put the camera's eye at X,Y,Z (world units, +y up).
    #[arg(long, value_parser = parse_point, allow_hyphen_values = true, value_name = "X,Y,Z")]
    eye: Option<Vec3>,
    /// Point the camera at X,Y,Z.
    #[arg(long, value_parser = parse_point, allow_hyphen_values = true, value_name = "X,Y,Z")]
    target: Option<Vec3>,
    /// Vertical field of view in degrees (0 to 180).
    #[arg(long, value_parser = parse_fov)]
    fov: Option<f32>,
    /// Sets one limit on what the input may ask for, as NAME=VALUE (again for
    /// more; over a scene's `[limits]`): e.g. `--limit triangles=50000000`.
    /// The limits and their defaults are listed in docs/scene-format.md.
    #[arg(long = "limit", value_name = "NAME=VALUE")]
    limits: Vec<LimitSetting>,
}

/// `--view`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
enum ViewArg {
    /// From the front (+z).
    Front,
    /// From the right (+x).
    Right,
    /// From above.
    Top,
    /// Isometric, front-right and above.
    Iso,
}

impl ViewArg {
    fn view(self) -> View {
        match self {
            ViewArg::Front => View::FRONT,
            ViewArg::Right => View::RIGHT,
            ViewArg::Top => View::TOP,
            ViewArg::Iso => View::ISO,
        }
    }
}

/// `--up`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
enum UpArg {
    /// +y up.
    Y,
    /// +z up.
    Z,
}

/// `--camera`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
enum CameraArg {
    /// A camera that frames the model.
    Framed,
    /// The file's own camera.
    File,
}

/// `--geometry`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
enum GeometryArg {
    /// True spheres, cylinders and cones.
    Exact,
    /// OpenSCAD's facets.
    Faceted,
}

/// `out.png` → `out.diffuse.png`.
fn aov_path(output: &Path, name: &str) -> PathBuf {
    let stem = output.file_stem().and_then(|s| s.to_str()).unwrap_or("kage");
    let ext = output.extension().and_then(|e| e.to_str()).unwrap_or("png");
    output.with_file_name(format!("{stem}.{name}.{ext}"))
}

/// What `--aov` asks for: components of the image, and whether the lights'
/// shadow terms and ambient occlusion's open share.
#[derive(Debug, Clone, Copy)]
struct Aovs {
    components: ComponentSet,
    shadow: bool,
    occlusion: bool,
}

fn parse_aovs(s: &str) -> Result<Aovs, String> {
    let mut aovs = Aovs { components: ComponentSet::EMPTY, shadow: false, occlusion: false };
    let mut list = Vec::new();
    for name in s.split(',').map(str::trim) {
        match name {
            "all" => aovs.components = ComponentSet::ALL,
            "shadow" => aovs.shadow = true,
            "occlusion" => aovs.occlusion = true,
            _ => list.push(Component::from_name(name).ok_or_else(|| {
                let known: Vec<&str> = Component::ALL.iter().map(|c| c.name()).collect();
                format!(
                    "'{name}' is not a component (expected 'all', 'shadow', 'occlusion' or some of {})",
                    known.join(", ")
                )
            })?),
        }
    }
    if aovs.components != ComponentSet::ALL {
        aovs.components = ComponentSet::of(&list);
    }
    Ok(aovs)
}

fn parse_antialias(s: &str) -> Result<Antialias, String> {
    let max = kage::scene::settings::MAX_JITTER_SAMPLES;
    let bad = || {
        format!(
            "'{s}' is not an antialiasing method (expected 'none', 'edge' with optional ':all' or ':outline' and \
             ':paper' or ':coverage' (e.g. edge:all:paper), or 'jitter:N', e.g. jitter:8)"
        )
    };
    let mut parts = s.split(':');
    match parts.next() {
        Some("none") if s == "none" => Ok(Antialias::None),
        Some("edge") => {
            let mut mode = EdgeMode::default();
            for p in parts {
                match p {
                    "outline" => mode.selection = EdgeSelection::Outline,
                    "all" => mode.selection = EdgeSelection::All,
                    "coverage" => mode.filter = EdgeFilter::Coverage,
                    "paper" => mode.filter = EdgeFilter::Paper,
                    _ => return Err(bad()),
                }
            }
            Ok(Antialias::Edge(mode))
        }
        Some("jitter") => match s.split_once(':').map(|(_, n)| n.parse::<u32>()) {
            Some(Ok(k @ 1..)) if k <= max => Ok(Antialias::Jitter(k)),
            _ => Err(format!("'{s}' is not jitter:N with N a number of passes between 1 and {max}")),
        },
        _ => Err(bad()),
    }
}

fn parse_shadow_method(s: &str) -> Result<ShadowMethod, String> {
    ShadowMethod::named(s)
        .ok_or_else(|| format!("'{s}' is not a shadow method (expected one of {})", ShadowMethod::names().join(", ")))
}

fn parse_tone(s: &str) -> Result<ToneCurve, String> {
    ToneCurve::from_name(s).ok_or_else(|| {
        let names: Vec<&str> = ToneCurve::NAMES.iter().map(|(n, _)| *n).collect();
        format!("'{s}' is not a tone curve (expected one of {})", names.join(", "))
    })
}

/// Comma-separated finite numbers, exactly `n` of them.
fn parse_numbers(s: &str, n: usize, what: &str) -> Result<Vec<f32>, String> {
    let values: Vec<f32> =
        s.split(',').filter_map(|v| v.trim().parse::<f32>().ok()).filter(|v| v.is_finite()).collect();
    if values.len() == n && s.split(',').count() == n {
        Ok(values)
    } else {
        Err(format!("'{s}' is not {what}"))
    }
}

fn parse_point(s: &str) -> Result<Vec3, String> {
    parse_numbers(s, 3, "a point X,Y,Z (three numbers, e.g. 0,1.5,4)").map(|v| Vec3::new(v[0], v[1], v[2]))
}

fn parse_orbit(s: &str) -> Result<View, String> {
    let v = parse_numbers(s, 2, "AZIMUTH,ELEVATION in degrees (e.g. 30,20)")?;
    if v[1].abs() > 90.0 {
        return Err(format!("elevation {} is not between -90 and 90 degrees", v[1]));
    }
    Ok(View { azimuth_deg: v[0], elevation_deg: v[1] })
}

fn parse_fov(s: &str) -> Result<f32, String> {
    match s.parse::<f32>() {
        Ok(v) if v > 0.0 && v < 180.0 => Ok(v),
        _ => Err(format!("'{s}' is not a field of view between 0 and 180 degrees")),
    }
}

fn parse_section(s: &str) -> Result<kage::scene::section::SectionPlane, String> {
    let bad = || format!("'{s}' is not a section (expected AXIS=VALUE or -AXIS=VALUE, AXIS x, y or z: e.g. z=5)");
    let (axis, value) = s.split_once('=').ok_or_else(bad)?;
    let value: f32 = value.trim().parse().ok().filter(|v: &f32| v.is_finite()).ok_or_else(bad)?;
    let (sign, axis) = axis.trim().strip_prefix('-').map_or((1.0, axis.trim()), |a| (-1.0, a));
    let normal = match axis {
        "x" | "X" => Vec3::X,
        "y" | "Y" => Vec3::Y,
        "z" | "Z" => Vec3::Z,
        _ => return Err(bad()),
    } * sign;
    kage::scene::section::SectionPlane::through(normal * value * sign, normal).ok_or_else(bad)
}

fn parse_positive(s: &str) -> Result<f32, String> {
    match s.parse::<f32>() {
        Ok(v) if v.is_finite() && v > 0.0 => Ok(v),
        _ => Err(format!("'{s}' is not a distance above 0")),
    }
}

fn parse_line_width(s: &str) -> Result<f32, String> {
    let widths = kage::scene::FeatureLines::WIDTHS;
    match s.parse::<f32>() {
        Ok(v) if widths.contains(&v) => Ok(v),
        _ => Err(format!("'{s}' is not a line width of {} to {} pixels", widths.start(), widths.end())),
    }
}

/// The feature lines and drawing look the arguments ask for, over the
/// scene file's `[lines]`.
fn apply_lines(args: &RenderArgs, scene: &mut Scene) {
    if args.drawing {
        scene.drawing();
    }
    if args.lines || args.hidden_lines || args.line_width.is_some() {
        let lines = scene.lines.get_or_insert_with(Default::default);
        lines.hidden |= args.hidden_lines;
        lines.width = args.line_width.unwrap_or(lines.width);
    }
}

fn parse_exposure(s: &str) -> Result<Exposure, String> {
    match s {
        "auto" => Ok(Exposure::Auto),
        _ => s
            .parse::<f32>()
            .ok()
            .filter(|v| v.is_finite())
            .map(Exposure::Stops)
            .ok_or_else(|| format!("'{s}' is neither a number of stops nor 'auto'")),
    }
}

fn camera_override(args: &RenderArgs) -> CameraOverride {
    CameraOverride {
        view: args.view.map(ViewArg::view).or(args.orbit),
        eye: args.eye,
        target: args.target,
        fov_deg: args.fov,
    }
}

fn load(args: &RenderArgs) -> kage::error::Result<Scene> {
    let geometry = match args.geometry {
        GeometryArg::Exact => Geometry::Exact,
        GeometryArg::Faceted => Geometry::Faceted,
    };
    let options = ModelOptions {
        csg: CsgOptions { geometry, skip_unsupported: args.skip_unsupported },
        up: args.up.map(|u| match u {
            UpArg::Y => Up::Y,
            UpArg::Z => Up::Z,
        }),
        ground: !args.no_ground,
        file_camera: args.camera == CameraArg::File,
        camera: camera_override(args),
        limits: Limits::default().with_settings(&args.limits),
        section: args.section,
        section_across: None,
    };
    let (width, height) = (args.width, args.height);
    let (w, h) = (width.unwrap_or(960), height.unwrap_or(540));
    let mut scene = match args.input.as_deref().map(|p| (p, InputFormat::from_path(p))) {
        None => demo_scene()?,
        Some((p, Some(InputFormat::Scene))) => file::load_scene_with(p, &args.limits)?,
        Some((p, Some(InputFormat::Scad))) => return scad::scene_for_scad(p, w, h, &options),
        Some((p, Some(_))) => return model::scene_for_model_with(p, w, h, &options),
        Some((p, None)) => {
            return Err(kage::Error::UnknownInput { path: p.to_path_buf(), reads: InputFormat::described() })
        }
    };
    if args.input.is_none() {
        scene.limits = scene.limits.with_settings(&args.limits);
    }
    if let Some(plane) = args.section {
        scene.section(plane);
    }
    scene.width = width.unwrap_or(scene.width);
    scene.height = height.unwrap_or(scene.height);
    // A scene keeps its lights; the camera moves about what casts shadows
    // (not the floor it stands on).
    if let Some(bounds) = scene.caster_bounds().or_else(|| scene.bounds()) {
        let aspect = scene.width as f32 / scene.height as f32;
        scene.camera = options.camera.apply(scene.camera, bounds, aspect);
    }
    Ok(scene)
}

/// A path's extension, lower case ("" when it has none).
pub(crate) fn extension(p: &Path) -> String {
    p.extension().and_then(|e| e.to_str()).unwrap_or_default().to_ascii_lowercase()
}

/// What a `kage render` asks for beyond one image: its frames and its part.
struct Job {
    /// Frames in the turntable or camera path (`None`: a still).
    frames: Option<u32>,
    /// The frames to render, in order.
    wanted: Vec<u32>,
    /// The pixels to render (`None`: all).
    part: Option<PixelRect>,
}

impl Job {
    /// Checks the frame and part options against `scene` and the output name.
    fn of(args: &RenderArgs, scene: &Scene) -> miette::Result<Job> {
        let frames = args.turntable.or(scene.camera_path.as_ref().map(|p| p.frames));
        let wanted: Vec<u32> = match (frames, args.frame, args.shard) {
            (None, Some(_), _) | (None, _, Some(_)) => miette::bail!(
                "--frame and --shard pick frames of a --turntable or of a scene file's [path]: there is neither"
            ),
            (Some(n), Some(i), _) if i >= n => miette::bail!("--frame {i}: the frames are 0 to {}", n - 1),
            (Some(_), Some(i), _) => vec![i],
            (Some(n), None, shard) => {
                if !has_frame_number(&args.output) {
                    miette::bail!(
                        "{}: {n} frames need a frame number in the output name: put #s where it goes (e.g. spin.####.png), or render one with --frame",
                        args.output.display()
                    );
                }
                let (i, count) = shard.unwrap_or((0, 1));
                (i..n).step_by(count as usize).collect()
            }
            (None, None, None) => vec![0],
        };
        let part = match (args.region, args.tile) {
            (Some(r), _) => Some(r),
            (None, Some((index, count))) => Some(PixelRect::tile(index, count, scene.width, scene.height)),
            (None, None) => None,
        };
        if let Some(r) = part {
            if !r.fits(scene.width, scene.height) {
                miette::bail!(
                    "--region {},{},{},{} is not inside the {}x{} image",
                    r.x0,
                    r.y0,
                    r.x1,
                    r.y1,
                    scene.width,
                    scene.height
                );
            }
            let exposure = args.exposure.unwrap_or(scene.exposure);
            if exposure == Exposure::Auto && !matches!(extension(&args.output).as_str(), "exr" | "pfm") {
                miette::bail!(
                    "auto exposure measures the whole image, which a tile does not have: give --exposure STOPS, or write .exr tiles (kage merge exposes the whole)"
                );
            }
        }
        Ok(Job { frames, wanted, part })
    }
}

/// Whether `path`'s file name holds a run of #s (where a frame number goes).
fn has_frame_number(path: &Path) -> bool {
    path.file_name().and_then(|n| n.to_str()).is_some_and(|n| n.contains('#'))
}

/// `pattern` with its file name's last run of #s replaced by `frame`,
/// zero-padded to the run's length (unchanged when it has none).
fn frame_path(pattern: &Path, frame: u32) -> PathBuf {
    let Some(name) = pattern.file_name().and_then(|n| n.to_str()) else { return pattern.to_path_buf() };
    let Some(end) = name.rfind('#') else { return pattern.to_path_buf() };
    let start = name[..end].rfind(|c| c != '#').map_or(0, |i| i + 1);
    let digits = end + 1 - start;
    pattern.with_file_name(format!("{}{frame:0digits$}{}", &name[..start], &name[end + 1..]))
}

/// The camera of frame `frame`: the turntable's (`--turntable`, about
/// `base`), the scene's path's, or `base` itself.
fn camera_of(args: &RenderArgs, scene: &Scene, base: &kage::camera::Camera, frame: u32) -> kage::camera::Camera {
    match (args.turntable, &scene.camera_path) {
        (Some(n), _) => kage::scene::camera_path::turntable(base, frame, n),
        (None, Some(path)) => path.camera_at(frame, base),
        (None, None) => *base,
    }
}

pub fn render_command(args: &RenderArgs) -> miette::Result<()> {
    // Cheap checks first: a bad output path is found before the render.
    kage::output::check_output(&args.output).map_err(report::to_report)?;
    let mut scene = load(args).map_err(report::to_report)?;
    scene.antialias = args.antialias.unwrap_or(scene.antialias);
    scene.tone = args.tonemap.unwrap_or(scene.tone);
    if let Some(method) = args.shadows {
        scene.lights.iter_mut().for_each(|l| l.shadow = l.shadow.with_method(method));
    }
    if args.xray {
        scene.xray(kage::scene::XRAY_OPACITY);
    }
    apply_lines(args, &mut scene);
    if args.ao || args.ao_screen || args.ao_radius.is_some() || args.ao_rays.is_some() {
        let ao = scene.ambient_occlusion.get_or_insert_with(Default::default);
        ao.radius = args.ao_radius.or(ao.radius);
        ao.rays = args.ao_rays.unwrap_or(ao.rays);
        ao.screen_space |= args.ao_screen;
    }
    let extra = scene.shadow_warnings();
    scene.warnings.extend(extra);
    for w in &scene.warnings {
        eprintln!("warning: {w}");
    }
    let job = Job::of(args, &scene)?;
    if args.reference {
        if job.frames.is_some() || job.part.is_some() {
            miette::bail!("--reference renders one whole image: no --turntable, --frame, --region or --tile");
        }
        return reference_command(args, &scene).map_err(report::to_report);
    }
    let wanted = args.aov.unwrap_or(Aovs { components: ComponentSet::EMPTY, shadow: false, occlusion: false });
    if scene.lines.is_some() && args.aov.is_some() {
        eprintln!("warning: feature lines are drawn over the image only; the --aov images have none");
    }
    if wanted.occlusion && scene.ambient_occlusion.is_none() {
        miette::bail!(
            "--aov occlusion writes ambient occlusion's open share, but this render has none: add --ao (or an [ambient_occlusion] table in the scene file)"
        );
    }
    let options = RenderOptions {
        threads: args.threads,
        ray_depth: args.ray_depth,
        aovs: wanted.components,
        shadow_images: wanted.shadow,
        region: job.part,
        ..RenderOptions::default()
    };
    let mut renderer = Renderer::new(&options).map_err(report::to_report)?;
    let many = job.wanted.len() > 1;
    let bar = Progress::new(if many { "frames" } else { "passes" });
    let (base, rig) = (scene.camera, scene.lights.clone());
    for (done, &frame) in job.wanted.iter().enumerate() {
        scene.camera = camera_of(args, &scene, &base, frame);
        if let (Some(n), true) = (args.turntable, scene.lights_follow_camera) {
            scene.lights = kage::scene::camera_path::turntable_lights(&rig, base.target, frame, n);
        }
        let report = |d: u32, total: u32| {
            if !many {
                bar.update(u64::from(d), u64::from(total));
            }
        };
        let frame_out = renderer.render_reporting(&scene, &report).map_err(report::to_report)?;
        let path = frame_path(&args.output, frame);
        write_frame(args, &scene, frame_out, &path, job.part).map_err(report::to_report)?;
        if many {
            bar.update(done as u64 + 1, job.wanted.len() as u64);
        } else {
            print_stats(&path, &scene, frame_out, args.quiet);
        }
    }
    bar.finish();
    if let (true, false, Some(first), Some(last)) = (many, args.quiet, job.wanted.first(), job.wanted.last()) {
        let (first, last) = (frame_path(&args.output, *first), frame_path(&args.output, *last));
        eprintln!("wrote {} frames, {} to {}", job.wanted.len(), first.display(), last.display());
    }
    Ok(())
}

/// Writes `frame`'s image (and its parts) to `path`: the pixels of `part`
/// when it is given, as an .exr tile that records where it goes.
fn write_frame(
    args: &RenderArgs,
    scene: &Scene,
    frame: &kage::Frame,
    path: &Path,
    part: Option<PixelRect>,
) -> kage::error::Result<()> {
    let exposure = args.exposure.unwrap_or(scene.exposure);
    let scale = exposure.scale(&frame.image);
    // A tile's images hold the pixels drawn for it (`frame.rect()`): the
    // tile and a guard band.
    let held = frame.rect();
    let write = |image: &kage::image::LinearImage, path: &Path, scale: f32, tone: ToneCurve| match part {
        None => kage::output::write_image(image, path, scale, tone),
        Some(rect) if extension(path) == "exr" => {
            let whole = (scene.width, scene.height);
            tiles::write_tile(&image.crop(rect.relative_to(held)), rect, whole, exposure, tone, path)
                .map_err(|message| kage::Error::Output { path: path.to_path_buf(), message })
        }
        Some(rect) => kage::output::write_image(&image.crop(rect.relative_to(held)), path, scale, tone),
    };
    write(&frame.image, path, scale, scene.tone)?;
    for (c, image) in &frame.aovs {
        // The same exposure and curve as the final image. (The parts add up
        // before the curve; with a rolling curve their 8-bit images only
        // roughly add up to the final one: .exr output adds up exactly.)
        let aov = aov_path(path, c.name());
        write(image, &aov, scale, scene.tone)?;
        if !args.quiet {
            eprintln!("wrote {} ({} component)", aov.display(), c.name());
        }
    }
    if args.aov.is_some_and(|a| a.occlusion) {
        // Grey, unexposed: 1 open, 0 closed.
        let occlusion = aov_path(path, "occlusion");
        write(&frame.occlusion, &occlusion, 1.0, ToneCurve::Clip)?;
        if !args.quiet {
            eprintln!("wrote {} (ambient occlusion's open share)", occlusion.display());
        }
    }
    for (i, image) in frame.shadows.iter().enumerate() {
        // Linear floats, unexposed: 1 is lit, 0 in shadow.
        let shadow = aov_path(&path.with_extension("exr"), &format!("shadow.{i}"));
        write(image, &shadow, 1.0, ToneCurve::Clip)?;
        if !args.quiet {
            eprintln!("wrote {} (light {i}'s shadow term)", shadow.display());
        }
    }
    Ok(())
}

/// Says what was written and how long each stage took (`quiet`: only a
/// warning, if any).
fn print_stats(path: &Path, scene: &Scene, frame: &kage::Frame, quiet: bool) {
    if frame.visibility.items().iter().all(|i| i.is_none()) {
        eprintln!("warning: no object is in view: the image shows only the background (check the camera)");
    }
    if quiet {
        return;
    }
    let s = frame.stats;
    eprintln!(
        "wrote {} ({}x{}, {} triangles, {} solids, {} pass{}): visibility {:.1} ms, shadow maps {:.1} ms, shading {:.1} ms, reflections and refraction {:.1} ms ({} pixels, {} refined)",
        path.display(),
        scene.width,
        scene.height,
        s.raster.triangles,
        s.raster.solids,
        s.passes,
        if s.passes == 1 { "" } else { "es" },
        s.visibility_ms,
        s.shadow_ms,
        s.shading_ms,
        s.traced_ms,
        s.traced_pixels,
        s.traced_refined
    );
    if scene.ambient_occlusion.is_some() {
        eprintln!("ambient occlusion: {:.1} ms", s.occlusion_ms);
    }
    if scene.lines.is_some() {
        eprintln!("feature lines: {:.1} ms, {} pixels drawn", s.lines_ms, s.line_pixels);
    }
    if let Antialias::Edge(_) = scene.antialias {
        eprintln!("antialiased edges: {:.1} ms, {} pixels blended", s.edge_ms, s.edge_blends);
    }
}

/// A progress bar on standard error that shows itself only once the work has
/// taken over half a second, and only on a terminal.
struct Progress {
    bar: indicatif::ProgressBar,
    start: std::time::Instant,
}

impl Progress {
    fn new(unit: &str) -> Progress {
        let bar = indicatif::ProgressBar::hidden();
        let template = format!("{{bar:40}} {{pos}}/{{len}} {unit}, {{elapsed}} (eta {{eta}})");
        bar.set_style(indicatif::ProgressStyle::with_template(&template).expect("valid template"));
        Progress { bar, start: std::time::Instant::now() }
    }

    fn update(&self, done: u64, total: u64) {
        self.bar.set_length(total);
        self.bar.set_position(done);
        if self.bar.is_hidden() && done < total && self.start.elapsed().as_secs_f32() > 0.5 {
            self.bar.set_draw_target(indicatif::ProgressDrawTarget::stderr());
        }
    }

    fn finish(&self) {
        self.bar.finish_and_clear();
    }
}

fn reference_command(args: &RenderArgs, scene: &Scene) -> kage::error::Result<()> {
    use kage::{render_reference_until, ReferenceOptions};
    scene.validate()?;
    if scene.lines.is_some() {
        eprintln!("warning: the reference renderer draws no feature lines");
    }
    let opts = ReferenceOptions {
        pixel_samples: args.spp,
        light_samples: args.light_samples,
        shadows: !args.no_shadows,
        max_depth: args.ray_depth,
        ..ReferenceOptions::default()
    };
    let bar = indicatif::ProgressBar::new(scene.height as u64);
    bar.set_style(
        indicatif::ProgressStyle::with_template("reference {bar:40} {pos}/{len} rows, {elapsed} (eta {eta})")
            .expect("valid template"),
    );
    let start = std::time::Instant::now();
    // Ctrl-C stops tracing new rows; the rows already done are written out.
    let stop = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
    let flag = stop.clone();
    let _ = ctrlc::set_handler(move || flag.store(true, std::sync::atomic::Ordering::Relaxed));
    let run = || render_reference_until(scene, &opts, &|_| bar.inc(1), &stop);
    let (image, rows) = match kage::thread_pool(args.threads)? {
        Some(pool) => pool.install(run),
        None => run(),
    };
    bar.finish_and_clear();
    if rows < scene.height {
        eprintln!("interrupted: {rows} of {} rows traced; the rest of the image is black", scene.height);
    }
    let exposure = args.exposure.unwrap_or(scene.exposure).scale(&image);
    kage::output::write_image(&image, &args.output, exposure, scene.tone)?;
    eprintln!(
        "wrote {} (ray-traced reference, {2}x{2} rays per pixel, {3}x{3} per area light, shadows {4}): {1:.2} s",
        args.output.display(),
        start.elapsed().as_secs_f64(),
        args.spp,
        args.light_samples,
        if opts.shadows { "on" } else { "off" },
    );
    if rows < scene.height {
        std::process::exit(130); // interrupted, as shells report Ctrl-C
    }
    Ok(())
}
