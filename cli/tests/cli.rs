//! The `kage` command: exit codes, located reports, warnings and what it
//! writes, run as a user runs it.

#[path = "../../tests/common/skip.rs"]
mod skip;
use std::path::{Path, PathBuf};
use std::process::Command;

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("kage-cli-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path
}

/// The repository's test models.
fn data() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/data/csg")
}

/// Runs `kage args`: its output.
fn run(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_kage")).args(args).output().unwrap()
}

fn kage(args: &[&str]) -> (bool, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_kage")).args(args).output().unwrap();
    (out.status.success(), String::from_utf8_lossy(&out.stderr).into_owned())
}

#[test]
fn the_cli_exits_non_zero_with_a_located_report() {
    let dir = scratch("cli");
    let scene = write(&dir, "broken.toml", "[[object]]\nshape = \"cube\"\nmaterial = \"gold\"\n");
    let (ok, err) = kage(&["render", scene.to_str().unwrap(), "-o", dir.join("x.png").to_str().unwrap()]);
    assert!(!ok);
    assert!(err.contains("broken.toml:3:12") && err.contains("no material named 'gold'"), "{err}");
    let (ok, err) =
        kage(&["render", "--width", "100000", "--height", "100000", "-o", dir.join("y.png").to_str().unwrap()]);
    assert!(!ok && err.contains("invalid image size 100000x100000"), "{err}");
    let (ok, err) = kage(&["render", "-o", dir.join("z.bmp").to_str().unwrap()]);
    assert!(!ok && err.contains("unknown image format '.bmp'"), "{err}");
    let (ok, err) = kage(&["render", "--antialias", "edge:most", "-o", dir.join("e.png").to_str().unwrap()]);
    assert!(!ok && err.contains("'edge:most' is not an antialiasing method"), "{err}");
    let (ok, err) = kage(&[
        "render",
        "--width",
        "96",
        "--height",
        "54",
        "--antialias",
        "edge",
        "-o",
        dir.join("e.png").to_str().unwrap(),
    ]);
    assert!(ok && err.contains("antialiased edges"), "{err}");
}

/// Errors lead with what is wrong, not with a diagnostic code; `--help`
/// speaks of what options do, not of the papers behind them.
#[test]
fn errors_lead_with_the_message_and_help_is_in_users_words() {
    let dir = scratch("words");
    let scene = write(&dir, "broken.toml", "[[object]]\nshape = \"cube\"\nmaterial = \"gold\"\n");
    let (ok, err) = kage(&["render", scene.to_str().unwrap(), "-o", dir.join("x.png").to_str().unwrap()]);
    let first = err.lines().find(|l| !l.trim().is_empty()).unwrap_or_default();
    assert!(!ok && first.contains("no material named 'gold'"), "first line: {first}\n{err}");
    assert!(!err.contains("kage::"), "{err}");
    let help = String::from_utf8_lossy(&run(&["render", "--help"]).stdout).into_owned();
    assert!(help.contains("--antialias") && help.contains("--tonemap") && help.contains("--orbit"), "{help}");
    for jargon in ["seed", "Fig.", "§"] {
        assert!(!help.contains(jargon), "help mentions '{jargon}':\n{help}");
    }
}

/// Pixels of the demo whose colour `--antialias none` leaves alone but the
/// default changes: only pixels beside an outline, and a good many of them.
#[test]
fn the_default_render_blends_outline_pixels() {
    let dir = scratch("aa-default");
    let size = ["--width", "160", "--height", "90"];
    let (plain, blended) = (dir.join("none.png"), dir.join("default.png"));
    let (ok, err) = kage(&[&["render", "-o", blended.to_str().unwrap()], &size[..]].concat());
    assert!(ok && err.contains("antialiased edges"), "{err}");
    let (ok, err) = kage(&[&["render", "--antialias", "none", "-o", plain.to_str().unwrap()], &size[..]].concat());
    assert!(ok && !err.contains("antialiased edges"), "{err}");
    let (a, b) = (image::open(&plain).unwrap().to_rgb8(), image::open(&blended).unwrap().to_rgb8());
    let step = |x: u32, y: u32, dx: i32, dy: i32| {
        let (p, q) = (a.get_pixel(x, y).0, a.get_pixel((x as i32 + dx) as u32, (y as i32 + dy) as u32).0);
        p.iter().zip(q).map(|(&u, v)| u.abs_diff(v)).max().unwrap()
    };
    let (mut changed, mut off_edge) = (0, 0);
    for y in 1..89 {
        for x in 1..159 {
            let d = a.get_pixel(x, y).0.iter().zip(b.get_pixel(x, y).0).map(|(&u, v)| u.abs_diff(v)).max().unwrap();
            if d > 2 {
                changed += 1;
                // Blending moves a pixel towards a neighbour it differs from.
                let steps = [(1, 0), (-1, 0), (0, 1), (0, -1), (1, 1), (-1, -1), (1, -1), (-1, 1)];
                off_edge += usize::from(steps.iter().all(|&(dx, dy)| step(x, y, dx, dy) < d));
            }
        }
    }
    assert!(changed > 100, "{changed} pixels blended");
    assert!(off_edge * 50 < changed, "{off_edge} of {changed} changed pixels sit on no edge");
}

/// `.jpg` output is written and reads back as the PNG does.
#[test]
fn jpeg_output() {
    let dir = scratch("jpeg");
    let (png, jpg) = (dir.join("a.png"), dir.join("a.jpg"));
    for out in [&png, &jpg] {
        let (ok, err) = kage(&["render", "--width", "96", "--height", "54", "-o", out.to_str().unwrap()]);
        assert!(ok, "{err}");
    }
    let (a, b) = (image::open(&png).unwrap().to_rgb8(), image::open(&jpg).unwrap().to_rgb8());
    assert_eq!(a.dimensions(), b.dimensions());
    let mean = a.as_raw().iter().zip(b.as_raw()).map(|(&u, &v)| f64::from(u.abs_diff(v))).sum::<f64>()
        / a.as_raw().len() as f64;
    assert!(mean < 4.0, "mean difference {mean} of 255");
}

/// `--aov shadow` writes one linear image per light (1 lit, 0 in shadow) and
/// the components asked for beside it; an unknown name lists `shadow`.
#[test]
fn aov_shadow_writes_each_lights_term() {
    let dir = scratch("aov-shadow");
    let out = dir.join("a.png");
    let (ok, err) =
        kage(&["render", "--width", "96", "--height", "54", "--aov", "shadow,diffuse", "-o", out.to_str().unwrap()]);
    assert!(ok, "{err}");
    assert!(dir.join("a.diffuse.png").exists(), "{err}");
    for light in 0..2 {
        let term = image::open(dir.join(format!("a.shadow.{light}.exr"))).unwrap().to_rgb32f();
        assert_eq!(term.dimensions(), (96, 54));
        let values = term.as_raw();
        assert!(values.iter().all(|v| (0.0..=1.0).contains(v)), "light {light}: a term outside 0..1");
        let shadowed = values.iter().filter(|&&v| v < 0.5).count();
        assert!(shadowed > 30 && shadowed < values.len() / 2, "light {light}: {shadowed} shadowed values");
    }
    assert!(!dir.join("a.shadow.2.exr").exists(), "the demo has two lights");
    let (ok, err) = kage(&["render", "--aov", "shade", "-o", out.to_str().unwrap()]);
    assert!(!ok && err.contains("'shade' is not a component") && err.contains("'shadow'"), "{err}");
}

#[test]
fn a_csg_node_kage_cannot_render_is_reported_at_its_line() {
    let dir = scratch("csg-node");
    // `roof()`, of OpenSCAD's later releases.
    let model = write(&dir, "roof.csg", "group() {\n\troof(method = \"voronoi\") {\n\t\tsquare(size = 1);\n\t}\n}\n");
    let (ok, err) = kage(&["render", model.to_str().unwrap(), "-o", dir.join("x.png").to_str().unwrap()]);
    assert!(!ok && err.contains("roof.csg:2:2") && err.contains("is not a node kage knows"), "{err}");
    // The report shows the offending line of the file, the node marked.
    assert!(err.contains("roof(method = \"voronoi\")") && err.contains("here"), "{err}");
}

#[test]
fn an_empty_view_is_warned_about_not_silent() {
    let dir = scratch("empty-view");
    let scene =
        write(&dir, "away.toml", "[camera]\neye = [0, 0, 5]\ntarget = [0, 0, 10]\n[[object]]\nshape = \"cube\"\n");
    let (ok, err) = kage(&["render", scene.to_str().unwrap(), "-o", dir.join("a.png").to_str().unwrap()]);
    assert!(ok, "{err}");
    assert!(err.contains("no object is in view"), "{err}");
}

#[test]
fn too_many_threads_is_an_error_not_a_hang() {
    let out = scratch("threads").join("t.png");
    let (ok, err) = kage(&["render", "--threads", "1000000", "-o", out.to_str().unwrap()]);
    assert!(!ok && err.contains("threads requested"), "{err}");
}

#[test]
fn compare_reports_metrics_and_refuses_mismatched_sizes() {
    let dir = scratch("compare");
    let (a, b, c) = (dir.join("a.pfm"), dir.join("b.pfm"), dir.join("c.pfm"));
    for (p, w) in [(&a, "64"), (&b, "64"), (&c, "32")] {
        let (ok, err) = kage(&["render", "--width", w, "--height", "32", "-o", p.to_str().unwrap()]);
        assert!(ok, "{err}");
    }
    let out = Command::new(env!("CARGO_BIN_EXE_kage"))
        .args(["compare", a.to_str().unwrap(), b.to_str().unwrap()])
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success() && text.contains("rmse        0.000000") && text.contains("psnr        inf dB"),
        "{text}"
    );
    let (ok, err) = kage(&["compare", a.to_str().unwrap(), c.to_str().unwrap()]);
    assert!(!ok && err.contains("differ in size: 64x32 vs 32x32"), "{err}");
    let (ok, err) = kage(&["compare", a.to_str().unwrap(), dir.join("missing.pfm").to_str().unwrap()]);
    assert!(!ok && err.contains("missing.pfm"), "{err}");
}

/// `kage render model.csg --camera file` renders it lit and shadowed from its
/// camera sidecar, exact or faceted; an unsupported node stops it with file, line and
/// column unless told to skip it.
#[test]
fn the_cli_renders_openscad_files() {
    let dir = std::env::temp_dir().join(format!("kage-csg-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let model = data().join("ex004_cube_minus_sphere.csg");
    for geometry in ["exact", "faceted"] {
        let out = dir.join(format!("{geometry}.png"));
        let o = run(&[
            "render",
            model.to_str().unwrap(),
            "--geometry",
            geometry,
            "--camera",
            "file",
            "--width",
            "160",
            "--height",
            "120",
            "-o",
            out.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let img = image::open(&out).unwrap().to_rgb8();
        // The cube sits in the middle of the sidecar's view in OpenSCAD's yellow.
        let [r, g, b] = img.get_pixel(80, 60).0;
        assert!(r > 120 && g > 100 && b < r / 2, "centre pixel {r},{g},{b} is not yellow");
    }
    let bad = dir.join("bad.csg");
    // `roof()`, of OpenSCAD's later releases.
    std::fs::write(&bad, "group() {\n  cube(size = [1, 1, 1], center = false);\n  roof(method = \"voronoi\") {\n    square(size = [1, 1], center = false);\n  }\n}\n").unwrap();
    let o = run(&["render", bad.to_str().unwrap(), "-o", dir.join("bad.png").to_str().unwrap()]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && err.contains("roof") && err.contains("bad.csg:3:3"), "{err}");
    let o = run(&["render", bad.to_str().unwrap(), "--skip-unsupported", "-o", dir.join("bad.png").to_str().unwrap()]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        o.status.success() && err.contains("warning") && err.contains("roof") && err.contains("bad.csg:3:3"),
        "{err}"
    );
    std::fs::remove_dir_all(&dir).ok();
}

/// A `.scad` file is read as if OpenSCAD's `.csg` of it sat beside it: an
/// `import()` relative to it is found, and kage's errors name the `.scad`,
/// never the temporary `.csg`. Skips (and says so) without `openscad`.
#[test]
fn a_scad_file_finds_its_imports_and_its_errors_name_it() {
    if Command::new("openscad").arg("--version").output().is_err() {
        skip::skipped("openscad is not on the PATH");
        return;
    }
    let dir = scratch("scad-imports");
    let parts = dir.join("parts");
    std::fs::create_dir_all(&parts).unwrap();
    let bracket = Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/data/openscad/parts/bracket.stl");
    std::fs::copy(&bracket, parts.join("bracket.stl")).unwrap();
    let scad = write(
        &dir,
        "holder.scad",
        "difference() {\n  import(\"parts/bracket.stl\");\n  translate([10, 2, 6]) sphere(r = 3);\n}\n",
    );
    let out = dir.join("holder.png");
    let o = run(&["render", scad.to_str().unwrap(), "--width", "96", "--height", "64", "-o", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    // Over a limit: kage's own error, about the .scad.
    let o = run(&["render", scad.to_str().unwrap(), "--limit", "triangles=10", "-o", out.to_str().unwrap()]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && err.contains("holder.scad") && err.contains("triangles"), "{err}");
    // No temporary `.csg` named anywhere.
    assert!(!err.contains(".csg"), "{err}");
    // OpenSCAD's `!` (only this subtree) and `*` (disabled): the same image as
    // the model written without what they leave out.
    let image = |name: &str, text: &str| {
        let scad = write(&dir, name, text);
        let out = dir.join(format!("{name}.png"));
        let o =
            run(&["render", scad.to_str().unwrap(), "--width", "96", "--height", "64", "-o", out.to_str().unwrap()]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        image::open(&out).unwrap().to_rgb8().into_raw()
    };
    let ball = "translate([10, 0, 0]) sphere(r = 3);\n";
    let only = image("only.scad", &format!("cube(8);\n!{ball}cylinder(r = 2, h = 9);\n"));
    let off = image("off.scad", &format!("*cube(30);\n{ball}"));
    let plain = image("plain.scad", ball);
    assert!(only == plain && off == plain, "`!` or `*` changed what is drawn");
}

/// The camera from the command line: a tall box seen from the front is
/// taller than wide, from above square; `--eye` and `--target` place it;
/// malformed values are refused with what was expected.
#[test]
fn the_camera_is_set_from_the_command_line() {
    let dir = scratch("camera");
    let mut text = String::from("solid box\n");
    let (lo, hi) = ([0.0f32, 0.0, 0.0], [1.0f32, 1.0, 3.0]); // z-up, 3 tall
    let c = |i: usize| {
        [
            if i & 1 == 0 { lo[0] } else { hi[0] },
            if i & 2 == 0 { lo[1] } else { hi[1] },
            if i & 4 == 0 { lo[2] } else { hi[2] },
        ]
    };
    for q in [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]] {
        for t in [[q[0], q[1], q[2]], [q[0], q[2], q[3]]] {
            text += "facet normal 0 0 0\nouter loop\n";
            t.iter().for_each(|&i| text += &format!("vertex {} {} {}\n", c(i)[0], c(i)[1], c(i)[2]));
            text += "endloop\nendfacet\n";
        }
    }
    let stl = write(&dir, "tall.stl", &(text + "endsolid box\n"));
    let shown = |extra: &[&str]| {
        let out = dir.join("view.png");
        let args = [
            &["render", stl.to_str().unwrap(), "--no-ground", "--width", "120", "--height", "120"],
            extra,
            &["-o", out.to_str().unwrap()],
        ]
        .concat();
        let (ok, err) = kage(&args);
        assert!(ok, "{err}");
        let img = image::open(&out).unwrap().to_rgb8();
        let bg = *img.get_pixel(0, 0);
        let (mut lo, mut hi) = ((u32::MAX, u32::MAX), (0, 0));
        for (x, y, p) in img.enumerate_pixels() {
            if p.0.iter().zip(bg.0).any(|(&u, v)| u.abs_diff(v) > 12) {
                (lo, hi) = ((lo.0.min(x), lo.1.min(y)), (hi.0.max(x), hi.1.max(y)));
            }
        }
        (hi.0.saturating_sub(lo.0) + 1, hi.1.saturating_sub(lo.1) + 1)
    };
    let (w, h) = shown(&["--view", "front"]);
    assert!(h > 2 * w, "front: {w} x {h}");
    let (w, h) = shown(&["--view", "top"]);
    assert!(w.abs_diff(h) <= 3, "top: {w} x {h}");
    let (w, h) = shown(&["--orbit", "90,0"]);
    assert!(h > 2 * w, "from the right: {w} x {h}");
    // Far away on the axis of the box: a small square.
    let (w, h) = shown(&["--eye", "0.5,40,0.5", "--target", "0.5,0,0.5", "--fov", "10"]);
    assert!(w.abs_diff(h) <= 3 && w < 60, "from far above: {w} x {h}");
    let (ok, err) = kage(&["render", "--orbit", "30", "-o", dir.join("x.png").to_str().unwrap()]);
    assert!(!ok && err.contains("AZIMUTH,ELEVATION"), "{err}");
    let (ok, err) = kage(&["render", "--eye", "1,2", "-o", dir.join("x.png").to_str().unwrap()]);
    assert!(!ok && err.contains("X,Y,Z"), "{err}");
    let (ok, err) = kage(&["render", "--fov", "200", "-o", dir.join("x.png").to_str().unwrap()]);
    assert!(!ok && err.contains("between 0 and 180"), "{err}");
}

#[test]
fn exposure_on_the_command_line() {
    let dir = scratch("exposure");
    let (ok, err) = kage(&["render", "--exposure", "lots", "-o", dir.join("x.png").to_str().unwrap()]);
    assert!(!ok);
    assert!(err.contains("neither a number of stops nor 'auto'"));
}

/// An error on a line too long to show (past column 65,535 the report
/// formatter itself failed) is reported with its location, exit code 1, and
/// no source excerpt; a short line still shows its excerpt.
#[test]
fn an_error_on_a_very_long_line_is_reported_not_a_crash() {
    let regressions = Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/regressions");
    for (file, at) in [("csg/col70000.csg", ":1:70001"), ("scene/col70000.toml", ":1:70006")] {
        let out = scratch("long-line").join("x.png");
        let got = run(&["render", regressions.join(file).to_str().unwrap(), "-o", out.to_str().unwrap()]);
        let stderr = String::from_utf8_lossy(&got.stderr);
        assert_eq!(got.status.code(), Some(1), "{file}: {stderr}");
        assert!(stderr.contains(at) && !stderr.contains("panicked"), "{file}: {stderr}");
        assert!(stderr.len() < 2000, "{file}: the report quotes the line ({} bytes)", stderr.len());
    }
}

/// Cheap checks come first: an output the render could not write is refused
/// before rendering, and an input of a kind kage does not read is named as
/// such (not parsed as a scene).
#[test]
fn a_bad_output_or_an_unknown_input_is_refused_before_the_render() {
    let dir = scratch("cheap-checks");
    let missing = dir.join("no-such-folder").join("x.png");
    let (ok, stderr) = kage(&["render", "-o", missing.to_str().unwrap()]);
    assert!(!ok && stderr.contains("no-such-folder") && stderr.contains("does not exist"), "{stderr}");
    assert!(!stderr.contains("wrote"), "the render ran first: {stderr}");
    let (ok, stderr) = kage(&["render", "-o", dir.join("x.gif").to_str().unwrap()]);
    assert!(!ok && stderr.contains("unknown image format '.gif'"), "{stderr}");
    let readme = write(&dir, "README.md", "# notes\n");
    let (ok, stderr) = kage(&["render", readme.to_str().unwrap(), "-o", dir.join("x.png").to_str().unwrap()]);
    assert!(!ok && stderr.contains("not a file kage reads") && stderr.contains(".gltf"), "{stderr}");
}

#[test]
fn a_limit_set_on_the_command_line_wins_and_an_unknown_one_is_named() {
    let dir = scratch("limits");
    let scene = write(&dir, "s.toml", "[limits]\ntriangles = 1000\n[[object]]\nshape = \"cube\"\n");
    let out = dir.join("x.png");
    let (ok, stderr) =
        kage(&["render", scene.to_str().unwrap(), "-o", out.to_str().unwrap(), "--limit", "triangles=11"]);
    assert!(!ok && stderr.contains("over the `triangles` limit of 11"), "{stderr}");
    assert!(!stderr.contains("wrote"), "{stderr}");
    let (ok, stderr) =
        kage(&["render", scene.to_str().unwrap(), "-o", out.to_str().unwrap(), "--limit", "triangle=11"]);
    assert!(!ok && stderr.contains("unknown limit 'triangle'") && stderr.contains("memory_mb"), "{stderr}");
    let (ok, stderr) = kage(&[
        "render",
        scene.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--width",
        "64",
        "--height",
        "48",
        "--limit",
        "triangles=12",
    ]);
    assert!(ok, "{stderr}");
}
