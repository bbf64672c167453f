//! The `kage` command: exit codes, located reports, warnings and what it
//! writes, run as a user runs it.

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
    assert!(ok && err.contains("edge pass (seed 004)"), "{err}");
}

#[test]
fn a_csg_node_kage_cannot_render_is_reported_at_its_line() {
    let dir = scratch("csg-node");
    let model =
        write(&dir, "extrude.csg", "group() {\n\tlinear_extrude(height = 2) {\n\t\tsquare(size = 1);\n\t}\n}\n");
    let (ok, err) = kage(&["render", model.to_str().unwrap(), "-o", dir.join("x.png").to_str().unwrap()]);
    assert!(!ok && err.contains("extrude.csg:2:2") && err.contains("is not a node kage renders"), "{err}");
    // The report shows the offending line of the file, the node marked.
    assert!(err.contains("linear_extrude(height = 2)") && err.contains("here"), "{err}");
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
    std::fs::write(&bad, "group() {\n  cube(size = [1, 1, 1], center = false);\n  linear_extrude(height = 2, center = false) {\n    square(size = [1, 1], center = false);\n  }\n}\n").unwrap();
    let o = run(&["render", bad.to_str().unwrap(), "-o", dir.join("bad.png").to_str().unwrap()]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && err.contains("linear_extrude") && err.contains("bad.csg:3:3"), "{err}");
    let o = run(&["render", bad.to_str().unwrap(), "--skip-unsupported", "-o", dir.join("bad.png").to_str().unwrap()]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success() && err.contains("warning") && err.contains("linear_extrude"), "{err}");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn exposure_on_the_command_line() {
    let dir = scratch("exposure");
    let (ok, err) = kage(&["render", "--exposure", "lots", "-o", dir.join("x.png").to_str().unwrap()]);
    assert!(!ok);
    assert!(err.contains("neither a number of stops nor 'auto'"));
}
