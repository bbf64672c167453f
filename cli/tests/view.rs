//! `kage view` end to end under a virtual X server (Xvfb, installed by
//! `.ci/run` when missing; these tests skip with a message without it):
//! scripted input, screenshots against `kage render`, live reload, and a
//! broken scene file that keeps the window alive with its error drawn.

#[path = "../../tests/common/skip.rs"]
mod skip;
use std::path::{Path, PathBuf};
use std::process::Command;

use image::RgbImage;

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("kage-view-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Whether a virtual X server can be started (says why not when not).
fn have_xvfb() -> bool {
    let ok = Command::new("xvfb-run").arg("--help").output().is_ok();
    if !ok {
        skip::skipped("xvfb-run is not installed (apt-get install xvfb; .ci/run does)");
    }
    ok
}

/// Runs `kage view args...` under Xvfb: whether it exited cleanly, and what
/// it printed.
fn view(args: &[&str]) -> (bool, String) {
    let out = Command::new("xvfb-run")
        .args(["-a", "-s", "-screen 0 1280x1024x24", env!("CARGO_BIN_EXE_kage"), "view"])
        .args(args)
        .output()
        .unwrap();
    let text = format!("{}{}", String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr));
    (out.status.success(), text)
}

/// Writes `script` to `dir/run.script` and runs `kage view args... --script`
/// on it (see [`view`]).
fn scripted(dir: &Path, script: &str, args: &[&str]) -> (bool, String) {
    let path = dir.join("run.script");
    std::fs::write(&path, script).unwrap();
    view(&[args, &["--script", path.to_str().unwrap()]].concat())
}

fn kage(args: &[&str]) {
    let out = Command::new(env!("CARGO_BIN_EXE_kage")).args(args).output().unwrap();
    assert!(out.status.success(), "kage {args:?}: {}", String::from_utf8_lossy(&out.stderr));
}

fn read(path: &Path) -> RgbImage {
    image::open(path).unwrap_or_else(|e| panic!("{}: {e}", path.display())).to_rgb8()
}

/// RMSE of two images' channels in [0, 1].
fn rmse(a: &RgbImage, b: &RgbImage) -> f64 {
    assert_eq!(a.dimensions(), b.dimensions());
    let sum: f64 =
        a.as_raw().iter().zip(b.as_raw()).map(|(&x, &y)| ((f64::from(x) - f64::from(y)) / 255.0).powi(2)).sum();
    (sum / a.as_raw().len() as f64).sqrt()
}

fn scene(shape: &str, colour: &str) -> String {
    format!(
        r#"
[image]
width = 200
height = 150
[camera]
eye = [2.0, 2.0, 4.0]
target = [0.0, 0.3, 0.0]
[[light]]
type = "point"
position = [3.0, 5.0, 2.0]
[[material]]
name = "paint"
kd = {colour}
[[object]]
shape = "plane"
scale = 6.0
[[object]]
shape = "{shape}"
material = "paint"
translate = [0.0, 0.6, 0.0]
scale = 0.6
"#
    )
}

/// With the edge pass chosen (A twice: progressive → none → edge) and the
/// refinement done, the viewer's screenshot is `kage render` of the same
/// scene and camera.
#[test]
fn a_screenshot_equals_the_render_of_the_same_camera() {
    if !have_xvfb() {
        return;
    }
    let dir = scratch("equal");
    let file = dir.join("scene.toml");
    std::fs::write(&file, scene("sphere", "[0.8, 0.3, 0.2]")).unwrap();
    let (ok, out) = scripted(&dir, "key a\nkey a\nwait\nscreenshot shot.png\nquit\n", &[file.to_str().unwrap()]);
    assert!(ok, "{out}");
    let reference = dir.join("render.png");
    kage(&["render", file.to_str().unwrap(), "-o", reference.to_str().unwrap()]);
    let e = rmse(&read(&dir.join("shot.png")), &read(&reference));
    assert!(e < 1e-3, "RMSE {e}");
}

/// The script edits the scene file: the viewer reloads it, keeps its camera
/// (a turned one), and shows the new scene as `kage render` does from there.
#[test]
fn an_edited_scene_file_is_shown_again() {
    if !have_xvfb() {
        return;
    }
    let dir = scratch("reload");
    let file = dir.join("scene.toml");
    std::fs::write(&file, scene("sphere", "[0.8, 0.3, 0.2]")).unwrap();
    std::fs::write(dir.join("edited.toml"), scene("cube", "[0.2, 0.3, 0.8]")).unwrap();
    let script = "key a\nkey a\nwait\nscreenshot before.png\ncopy edited.toml scene.toml\nsleep 1.5\nwait\n\
                  screenshot after.png\nquit\n";
    let (ok, out) = scripted(&dir, script, &[file.to_str().unwrap()]);
    assert!(ok, "{out}");
    let (before, after) = (read(&dir.join("before.png")), read(&dir.join("after.png")));
    assert!(rmse(&before, &after) > 0.01, "the change is shown");
    let reference = dir.join("render.png");
    kage(&["render", file.to_str().unwrap(), "-o", reference.to_str().unwrap()]);
    let e = rmse(&after, &read(&reference));
    assert!(e < 1e-3, "RMSE {e} against kage render of the edited file");
}

/// A broken edit keeps the process alive (the script goes on to quit
/// cleanly), the last good scene stays on screen and the error is drawn
/// over it in red, naming the file and line.
#[test]
fn a_broken_scene_file_keeps_the_window_and_draws_the_error() {
    if !have_xvfb() {
        return;
    }
    let dir = scratch("broken");
    let file = dir.join("scene.toml");
    std::fs::write(&file, scene("sphere", "[0.8, 0.3, 0.2]")).unwrap();
    std::fs::write(dir.join("broken.toml"), "[camera]\neye = \"up\"\n").unwrap();
    let script = "key z\nkey a\nwait\ncapture good.png\nscreenshot before.png\ncopy broken.toml scene.toml\n\
                  sleep 1.5\nwait\ncapture bad.png\nscreenshot image.png\nquit\n";
    let (ok, out) = scripted(&dir, script, &[file.to_str().unwrap()]);
    assert!(ok, "the viewer exits cleanly after the bad edit: {out}");
    assert!(out.contains("scene.toml:2:"), "the error names file and line: {out}");
    assert_eq!(out.matches("scene.toml:2:").count(), 1, "the error is said once: {out}");
    let red = |img: &RgbImage| img.pixels().filter(|p| p[0] > 200 && p[1] < 120 && p[2] < 120).count();
    let (good, bad) = (read(&dir.join("good.png")), read(&dir.join("bad.png")));
    assert!(red(&bad) > red(&good) + 30, "red error text drawn: {} against {}", red(&bad), red(&good));
    // Under the error (wrapped to the window's width, it covers most of so
    // small a window) the window still shows the last good image.
    let shown = read(&dir.join("image.png"));
    assert!(shown.dimensions() == (200, 150));
    assert!(rmse(&shown, &read(&dir.join("before.png"))) < 1e-3, "the last good scene stays");
}

/// Left to rest, the progressive refinement averages 64 jittered passes:
/// a scene without area lights as `kage render --antialias jitter:64`
/// renders it. Keys pressed halfway give up the step rendering (the
/// refinement starts over and still ends on the same image).
#[test]
fn the_refined_image_equals_64_jittered_passes() {
    if !have_xvfb() {
        return;
    }
    let dir = scratch("refined");
    let file = dir.join("scene.toml");
    std::fs::write(&file, scene("cube", "[0.3, 0.7, 0.3]")).unwrap();
    let (ok, out) = scripted(
        &dir,
        "wait 8\nkey r\nkey r\nwait\nscreenshot shot.png\nquit\n",
        &[file.to_str().unwrap(), "--timings"],
    );
    assert!(ok, "{out}");
    let given_up = out.split(" steps given up").next().and_then(|s| s.rsplit(' ').next()).and_then(|n| n.parse().ok());
    assert!(given_up.is_some_and(|n: u32| n >= 1), "a rendering step is given up for the keys: {out}");
    let reference = dir.join("render.png");
    kage(&["render", file.to_str().unwrap(), "--antialias", "jitter:64", "-o", reference.to_str().unwrap()]);
    let e = rmse(&read(&dir.join("shot.png")), &read(&reference));
    assert!(e < 1e-3, "RMSE {e}");
}

/// O turns ambient occlusion on; refined, the viewer's 64 passes cast 4 new
/// rays a pixel each, as `kage render --ao --ao-rays 4 --antialias
/// jitter:64` does; X (x-ray) then changes the image.
#[test]
fn ambient_occlusion_refines_as_64_jittered_passes_do() {
    if !have_xvfb() {
        return;
    }
    let dir = scratch("occlusion");
    let file = dir.join("scene.toml");
    // A cube standing on the floor (the helper's floats over it), a strong ambient light.
    let lit = scene("cube", "[0.3, 0.7, 0.3]")
        .replace("position = [3.0, 5.0, 2.0]", "position = [3.0, 5.0, 2.0]\nambient = 0.6")
        .replace("translate = [0.0, 0.6, 0.0]", "translate = [0.0, 0.3, 0.0]");
    std::fs::write(&file, lit).unwrap();
    let script = "key o\nwait\nscreenshot ao.png\nkey x\nwait 4\nscreenshot xray.png\nquit\n";
    let (ok, out) = scripted(&dir, script, &[file.to_str().unwrap()]);
    assert!(ok, "{out}");
    let (with, plain) = (dir.join("render-ao.png"), dir.join("render.png"));
    let file = file.to_str().unwrap();
    kage(&["render", file, "--ao", "--ao-rays", "4", "--antialias", "jitter:64", "-o", with.to_str().unwrap()]);
    kage(&["render", file, "--antialias", "jitter:64", "-o", plain.to_str().unwrap()]);
    let shot = read(&dir.join("ao.png"));
    let (e, darker) = (rmse(&shot, &read(&with)), rmse(&shot, &read(&plain)));
    assert!(e < 1e-3 && darker > 2e-3, "RMSE {e} to the render with ambient occlusion, {darker} to the one without");
    assert!(rmse(&read(&dir.join("xray.png")), &shot) > 1e-2, "x-ray changes the image");
}

/// A file dropped on the window opens with its own camera, the toggles
/// kept (here the edge pass): the screenshot is `kage render` of that file.
#[test]
fn a_dropped_file_opens() {
    if !have_xvfb() {
        return;
    }
    let dir = scratch("dropped");
    let (first, other) = (dir.join("first.toml"), dir.join("other.toml"));
    std::fs::write(&first, scene("sphere", "[0.8, 0.3, 0.2]")).unwrap();
    let other_scene = scene("cube", "[0.2, 0.3, 0.8]").replace("eye = [2.0, 2.0, 4.0]", "eye = [-3.0, 1.5, 3.0]");
    std::fs::write(&other, other_scene).unwrap();
    let script = "key a\nkey a\nwait\ndrop other.toml\nwait\nscreenshot shot.png\nquit\n";
    let (ok, out) = scripted(&dir, script, &[first.to_str().unwrap()]);
    assert!(ok, "{out}");
    let reference = dir.join("render.png");
    kage(&["render", other.to_str().unwrap(), "-o", reference.to_str().unwrap()]);
    let e = rmse(&read(&dir.join("shot.png")), &read(&reference));
    assert!(e < 1e-3, "RMSE {e} against kage render of the dropped file");
}

/// `wait N` right after an input waits for N passes of the new view, not
/// the passes already shown of the old one.
#[test]
fn wait_for_passes_after_a_drop_waits_for_the_dropped_file() {
    if !have_xvfb() {
        return;
    }
    let dir = scratch("wait-passes");
    let (first, other) = (dir.join("first.toml"), dir.join("other.toml"));
    std::fs::write(&first, scene("sphere", "[0.8, 0.3, 0.2]")).unwrap();
    std::fs::write(&other, scene("cube", "[0.2, 0.3, 0.8]")).unwrap();
    let script = "wait\ndrop other.toml\nwait 8\nscreenshot shot.png\nquit\n";
    let (ok, out) = scripted(&dir, script, &[first.to_str().unwrap()]);
    assert!(ok, "{out}");
    let (was, now) = (dir.join("first.png"), dir.join("other.png"));
    kage(&["render", first.to_str().unwrap(), "-o", was.to_str().unwrap()]);
    kage(&["render", other.to_str().unwrap(), "-o", now.to_str().unwrap()]);
    let shot = read(&dir.join("shot.png"));
    let (to_other, to_first) = (rmse(&shot, &read(&now)), rmse(&shot, &read(&was)));
    assert!(to_other < 0.03 && to_first > 0.05, "RMSE {to_other} to the dropped file, {to_first} to the first");
}

/// The demo's lights have a size: its refined passes shadow each from a
/// point of the disc of its own (64 in all), where `jitter:64` repeats the
/// light's 8 in every pass — the same image but for the penumbrae' finer
/// grain (measured: RMSE 0.004, 1.7% of pixels off by more than 1%). The
/// window with the HUD and the keys is the README's picture (written there
/// when `KAGE_UPDATE_DOCS` is set).
#[test]
fn the_refined_demo_differs_from_64_jittered_passes_only_in_its_penumbrae() {
    if !have_xvfb() {
        return;
    }
    let dir = scratch("demo");
    let (ok, out) = scripted(
        &dir,
        "wait\nscreenshot shot.png\nkey h\ncapture window.png\nquit\n",
        &["--width", "480", "--height", "270"],
    );
    assert!(ok, "{out}");
    let reference = dir.join("render.png");
    kage(&[
        "render",
        "--width",
        "480",
        "--height",
        "270",
        "--antialias",
        "jitter:64",
        "-o",
        reference.to_str().unwrap(),
    ]);
    let e = rmse(&read(&dir.join("shot.png")), &read(&reference));
    assert!(e < 0.01, "RMSE {e}");
    if std::env::var_os("KAGE_UPDATE_DOCS").is_some() {
        let (ok, out) =
            view(&["--width", "960", "--height", "540", "--script", dir.join("run.script").to_str().unwrap()]);
        assert!(ok, "{out}");
        let docs = Path::new(env!("CARGO_MANIFEST_DIR")).join("../docs/images/view.png");
        std::fs::copy(dir.join("window.png"), &docs).unwrap();
        eprintln!("wrote {}", docs.display());
    }
}

/// An OpenSCAD file with a node kage cannot draw opens with the node left
/// out: the window says the image is incomplete, in amber over the image,
/// and so does stderr, naming the node and its place.
#[test]
fn a_skipped_node_is_said_in_the_window_and_on_stderr() {
    if !have_xvfb() {
        return;
    }
    let dir = scratch("skipped");
    let cube = "\tcube(size = [10, 10, 10], center = false);\n";
    let roof = "\troof(method = \"voronoi\") {\n\t\tsquare(size = [5, 5], center = false);\n\t}\n";
    std::fs::write(dir.join("part.csg"), format!("group() {{\n{cube}{roof}}}\n")).unwrap();
    std::fs::write(dir.join("plain.csg"), format!("group() {{\n{cube}}}\n")).unwrap();
    std::fs::write(dir.join("run.script"), "wait\ncapture window.png\nquit\n").unwrap();
    let capture = |name: &str| {
        let (ok, out) = view(&[dir.join(name).to_str().unwrap(), "--script", dir.join("run.script").to_str().unwrap()]);
        assert!(ok, "{out}");
        (out, read(&dir.join("window.png")))
    };
    let (out, with_skip) = capture("part.csg");
    assert!(out.contains("part.csg:3:2") && out.contains("roof") && out.contains("skipped"), "{out}");
    let (_, plain) = capture("plain.csg");
    // The model is OpenSCAD's yellow: the text is what the plain file lacks.
    let amber = |img: &RgbImage| img.pixels().filter(|p| p[0] > 200 && p[1] > 150 && p[1] < 220 && p[2] < 100).count();
    assert!(
        amber(&with_skip) > amber(&plain) + 100,
        "amber warning text drawn: {} pixels against {}",
        amber(&with_skip),
        amber(&plain)
    );
}

/// Without a display the viewer says what to do, not where in winit it failed.
#[test]
fn without_a_display_the_viewer_says_what_to_do() {
    let out = Command::new(env!("CARGO_BIN_EXE_kage"))
        .args(["view", "--script", "/dev/null"])
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .output()
        .unwrap();
    let said = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "{said}");
    assert!(said.contains("no display") && said.contains("xvfb-run") && !said.contains(".cargo"), "{said}");
}
