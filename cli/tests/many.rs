//! Rendering past one machine, end to end: frames of a turntable and of a
//! scene's camera path rendered one at a time equal the whole run's, tiles
//! merge into the whole image and misfits are refused, a batch keeps going
//! past a bad file and resumes, and the job templates in `jobs/` run (the
//! OpenJD one under `openjd run`, skipped with a message when it is not
//! installed; `.ci/run` installs it).

#[path = "../../tests/common/skip.rs"]
mod skip;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("kage-many-{}-{name}", std::process::id()));
    std::fs::remove_dir_all(&dir).ok();
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn repo(path: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..").join(path)
}

fn run(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_kage")).args(args).output().unwrap()
}

fn kage(args: &[&str]) -> String {
    let out = run(args);
    let said = String::from_utf8_lossy(&out.stderr).to_string();
    assert!(out.status.success(), "kage {args:?}: {said}");
    said
}

fn bytes(p: &Path) -> Vec<u8> {
    std::fs::read(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

#[test]
fn a_frame_rendered_alone_equals_the_same_frame_of_the_turntable() {
    let dir = scratch("turntable");
    let teapot = repo("assets/teapot.obj");
    let pattern = dir.join("spin.###.png");
    kage(&[
        "render",
        teapot.to_str().unwrap(),
        "--turntable",
        "6",
        "--width",
        "96",
        "--height",
        "54",
        "-o",
        pattern.to_str().unwrap(),
    ]);
    for i in 0..6 {
        assert!(dir.join(format!("spin.{i:03}.png")).exists(), "frame {i} written");
    }
    for i in [0, 2, 5] {
        let one = dir.join(format!("one{i}.png"));
        let args = ["render", teapot.to_str().unwrap(), "--turntable", "6", "--frame", &i.to_string()];
        kage(&[&args[..], &["--width", "96", "--height", "54", "-o", one.to_str().unwrap()]].concat());
        assert_eq!(bytes(&one), bytes(&dir.join(format!("spin.{i:03}.png"))), "frame {i}");
    }
    // A share of the frames, in one process: frames 1 and 4 of 6.
    let shard = dir.join("shard");
    std::fs::create_dir_all(&shard).unwrap();
    let shard_pattern = shard.join("s.###.png");
    let args =
        ["render", teapot.to_str().unwrap(), "--turntable", "6", "--shard", "1/3", "--width", "96", "--height", "54"];
    kage(&[&args[..], &["-o", shard_pattern.to_str().unwrap()]].concat());
    let mut written: Vec<String> =
        std::fs::read_dir(&shard).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
    written.sort();
    assert_eq!(written, ["s.001.png", "s.004.png"]);
    assert_eq!(bytes(&shard.join("s.004.png")), bytes(&dir.join("spin.004.png")));
    // The turn shows the model from another side: frames differ.
    assert_ne!(bytes(&dir.join("spin.000.png")), bytes(&dir.join("spin.003.png")));
    // Many frames and no place for the number in the name: refused.
    let out = run(&["render", teapot.to_str().unwrap(), "--turntable", "6", "-o", dir.join("x.png").to_str().unwrap()]);
    assert!(!out.status.success() && String::from_utf8_lossy(&out.stderr).contains("#"), "{out:?}");
    let out = run(&["render", teapot.to_str().unwrap(), "--turntable", "6", "--frame", "6", "-o", "x.png"]);
    assert!(String::from_utf8_lossy(&out.stderr).contains("0 to 5"), "{out:?}");
}

#[test]
fn a_scene_files_camera_path_renders_frame_by_frame_as_a_whole() {
    let dir = scratch("path");
    let scene = std::fs::read_to_string(repo("examples/scenes/showroom.toml")).unwrap();
    let scene = scene.replace("../../assets/", &format!("{}/", repo("assets").display()));
    let path = format!(
        "{scene}\n[path]\nframes = 5\ninterpolation = \"catmull-rom\"\n\
         [[path.key]]\nframe = 0\neye = [0.3, 2.2, 4.1]\n\
         [[path.key]]\nframe = 2\neye = [3.0, 1.5, 2.0]\nfov = 30\n\
         [[path.key]]\nframe = 4\neye = [2.0, 3.0, -3.0]\n"
    );
    let file = dir.join("path.toml");
    std::fs::write(&file, path).unwrap();
    let all = dir.join("f.#.png");
    kage(&["render", file.to_str().unwrap(), "--width", "96", "--height", "54", "-o", all.to_str().unwrap()]);
    let one = dir.join("one.png");
    kage(&[
        "render",
        file.to_str().unwrap(),
        "--frame",
        "3",
        "--width",
        "96",
        "--height",
        "54",
        "-o",
        one.to_str().unwrap(),
    ]);
    assert_eq!(bytes(&one), bytes(&dir.join("f.3.png")));
    assert_ne!(bytes(&dir.join("f.1.png")), bytes(&dir.join("f.3.png")));
    // A key out of order is found with its line.
    let bad = std::fs::read_to_string(&file).unwrap().replace("frame = 4", "frame = 1");
    std::fs::write(&file, bad).unwrap();
    let out = run(&["render", file.to_str().unwrap(), "-o", dir.join("x.#.png").to_str().unwrap()]);
    let said = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && said.contains("path.toml:") && said.contains("must rise"), "{said}");
}

#[test]
fn tiles_merge_into_the_whole_image_and_misfits_are_refused() {
    let dir = scratch("tiles");
    let scene = repo("examples/scenes/csg.toml");
    let size = ["--width", "150", "--height", "90"];
    let whole = dir.join("whole.exr");
    kage(&[&["render", scene.to_str().unwrap(), "-o", whole.to_str().unwrap()][..], &size].concat());
    let mut tiles = Vec::new();
    for i in 0..5 {
        let t = dir.join(format!("t{i}.exr"));
        let share = format!("{i}/5");
        kage(&[&["render", scene.to_str().unwrap(), "--tile", &share, "-o", t.to_str().unwrap()][..], &size].concat());
        tiles.push(t.to_str().unwrap().to_string());
    }
    let merged = dir.join("merged.exr");
    let args: Vec<&str> = ["merge"].into_iter().chain(tiles.iter().map(String::as_str)).collect();
    kage(&[&args[..], &["-o", merged.to_str().unwrap()]].concat());
    let (a, b) = (image::open(&merged).unwrap().into_rgb32f(), image::open(&whole).unwrap().into_rgb32f());
    assert_eq!(a.dimensions(), b.dimensions());
    assert!(
        a.as_raw().iter().zip(b.as_raw()).all(|(x, y)| x.to_bits() == y.to_bits()),
        "merged tiles = whole, bit for bit"
    );
    // A region as an 8-bit crop equals the crop of the whole 8-bit image.
    let crop = dir.join("crop.png");
    let full = dir.join("full.png");
    kage(
        &[&["render", scene.to_str().unwrap(), "--region", "30,20,101,77", "-o", crop.to_str().unwrap()][..], &size]
            .concat(),
    );
    kage(&[&["render", scene.to_str().unwrap(), "-o", full.to_str().unwrap()][..], &size].concat());
    let (c, f) = (image::open(&crop).unwrap().to_rgb8(), image::open(&full).unwrap().to_rgb8());
    assert_eq!(c.dimensions(), (71, 57));
    assert!(c.enumerate_pixels().all(|(x, y, p)| p == f.get_pixel(x + 30, y + 20)));
    // Misfits: a gap, an overlap, a tile of another image.
    let refused = |args: &[&str], says: &str| {
        let out = run(args);
        let said = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success() && said.contains(says), "{args:?}: {said}");
    };
    let o = dir.join("x.exr");
    let o = o.to_str().unwrap();
    refused(&["merge", &tiles[0], &tiles[1], &tiles[2], &tiles[3], "-o", o], "uncovered");
    refused(&["merge", &tiles[0], &tiles[1], &tiles[2], &tiles[3], &tiles[4], &tiles[4], "-o", o], "overlap");
    let other = dir.join("other.exr");
    kage(&[
        "render",
        scene.to_str().unwrap(),
        "--tile",
        "0/5",
        "--width",
        "151",
        "--height",
        "90",
        "-o",
        other.to_str().unwrap(),
    ]);
    refused(&["merge", other.to_str().unwrap(), &tiles[1], &tiles[2], &tiles[3], &tiles[4], "-o", o], "151x90");
    refused(&["render", scene.to_str().unwrap(), "--region", "0,0,151,10", "-o", o, "--width", "150"], "not inside");
}

#[test]
fn a_batch_keeps_going_past_a_bad_file_and_resumes() {
    let dir = scratch("batch");
    let models = dir.join("models");
    std::fs::create_dir_all(models.join("sub")).unwrap();
    std::fs::copy(repo("assets/teapot.obj"), models.join("teapot.obj")).unwrap();
    std::fs::copy(repo("tests/data/csg/ex001_sphere_minus_cylinders.csg"), models.join("sub/part.csg")).unwrap();
    std::fs::write(models.join("broken.stl"), b"solid broken\n facet normal 0 0 1\n  outer loop\n   vertex 0 0 0\n")
        .unwrap();
    std::fs::write(models.join("notes.txt"), b"not a model").unwrap();
    let out = dir.join("out");
    let batch = |extra: &[&str]| {
        let args = [
            &["batch", models.to_str().unwrap(), "-o", out.to_str().unwrap()][..],
            extra,
            &["--", "--width", "64", "--height", "48"],
        ];
        run(&args.concat())
    };
    let first = batch(&[]);
    let said = String::from_utf8_lossy(&first.stderr);
    assert!(!first.status.success(), "a failed file fails the batch: {said}");
    assert!(said.contains("broken.stl") && said.contains("2 rendered, 0 up to date, 1 failed"), "{said}");
    // No temporary file named; nothing left of them.
    assert!(!said.contains("partial") && !said.contains("wrote"), "{said}");
    assert_eq!(
        std::fs::read_dir(&out).unwrap().flatten().filter(|e| e.file_name().to_string_lossy().starts_with('.')).count(),
        0
    );
    let (teapot, part) = (out.join("teapot.obj.png"), out.join("sub/part.csg.png"));
    assert!(teapot.exists() && part.exists() && !out.join("broken.stl.png").exists());
    let made = std::fs::metadata(&teapot).unwrap().modified().unwrap();
    let again = batch(&[]);
    let said = String::from_utf8_lossy(&again.stderr);
    assert!(said.contains("0 rendered, 2 up to date, 1 failed"), "nothing new the second time: {said}");
    assert!(said.contains("1 of 3 files failed (0 rendered, 2 up to date)"), "{said}");
    assert_eq!(std::fs::metadata(&teapot).unwrap().modified().unwrap(), made);
    // Shares split the files between them, each file once.
    std::fs::remove_file(models.join("broken.stl")).unwrap();
    let shards = scratch("batch-shards");
    for i in 0..2 {
        let share = format!("{i}/2");
        let args = [
            "batch",
            models.to_str().unwrap(),
            "-o",
            shards.to_str().unwrap(),
            "--shard",
            &share,
            "--",
            "--width",
            "32",
            "--height",
            "24",
        ];
        let said = String::from_utf8_lossy(&run(&args).stderr).to_string();
        assert!(said.contains("1 rendered"), "share {i}: {said}");
    }
    assert!(shards.join("teapot.obj.png").exists() && shards.join("sub/part.csg.png").exists());
}

/// The OpenJD template's path, and the `openjd` command: on the PATH, in
/// `.ci/venv` (where `.ci/run` installs it) or named by `OPENJD`.
fn openjd() -> Option<PathBuf> {
    let candidates = [
        std::env::var_os("OPENJD").map(PathBuf::from),
        Some(repo(".ci/venv/bin/openjd")),
        Some(PathBuf::from("openjd")),
    ];
    candidates.into_iter().flatten().find(|c| Command::new(c).arg("--help").output().is_ok_and(|o| o.status.success()))
}

#[test]
fn the_openjd_template_renders_the_frames_from_their_tiles() {
    let Some(openjd) = openjd() else {
        skip::skipped("openjd is not installed (pip install openjd-cli; .ci/run does, into .ci/venv)");
        return;
    };
    let dir = scratch("openjd");
    let teapot = repo("assets/teapot.obj");
    let params = [
        format!("Input={}", teapot.display()),
        format!("OutputDir={}", dir.display()),
        "Frames=4".into(),
        "FrameRange=0-3".into(),
        "Tiles=3".into(),
        "TileRange=0-2".into(),
        "Width=80".into(),
        "Height=45".into(),
        format!("Kage={}", env!("CARGO_BIN_EXE_kage")),
    ];
    let mut cmd = Command::new(&openjd);
    cmd.args(["run", repo("jobs/openjd-turntable.yaml").to_str().unwrap(), "--step", "Merge", "--run-dependencies"]);
    params.iter().for_each(|p| {
        cmd.args(["-p", p]);
    });
    let out = cmd.output().unwrap();
    assert!(
        out.status.success(),
        "openjd run: {}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    for i in 0..4 {
        let alone = dir.join(format!("alone{i}.png"));
        let frame = i.to_string();
        kage(&[
            "render",
            teapot.to_str().unwrap(),
            "--turntable",
            "4",
            "--frame",
            &frame,
            "--width",
            "80",
            "--height",
            "45",
            "-o",
            alone.to_str().unwrap(),
        ]);
        assert_eq!(bytes(&dir.join(format!("frame.{i:04}.png"))), bytes(&alone), "frame {i} from three tiles");
    }
}

#[test]
fn the_slurm_array_script_renders_its_tasks_frame() {
    let dir = scratch("slurm");
    let teapot = repo("assets/teapot.obj");
    let script = repo("jobs/slurm-array.sh");
    let out = Command::new("bash")
        .arg(&script)
        .args(["turntable", teapot.to_str().unwrap(), dir.to_str().unwrap(), "5", "--width", "64", "--height", "36"])
        .env("SLURM_ARRAY_TASK_ID", "3")
        .env("SLURM_CPUS_PER_TASK", "2")
        .env("KAGE", env!("CARGO_BIN_EXE_kage"))
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let alone = dir.join("alone.png");
    kage(&[
        "render",
        teapot.to_str().unwrap(),
        "--turntable",
        "5",
        "--frame",
        "3",
        "--width",
        "64",
        "--height",
        "36",
        "-o",
        alone.to_str().unwrap(),
    ]);
    assert_eq!(bytes(&dir.join("spin.0003.png")), bytes(&alone));
}

/// The Slurm array script under a real single-node Slurm
/// (`jobs/slurm-local-check.sh`: munged, slurmctld and slurmd on this
/// machine). Needs root and Debian's `slurm-wlm`; skipped with a message
/// without them (`.ci/run` does not install Slurm: its daemons want root).
#[test]
fn the_slurm_array_script_runs_under_sbatch() {
    let root = Command::new("id").arg("-u").output().is_ok_and(|o| String::from_utf8_lossy(&o.stdout).trim() == "0");
    let slurm = Command::new("sh").args(["-c", "command -v slurmctld && command -v munged"]).output();
    if !root || !slurm.is_ok_and(|o| o.status.success()) {
        skip::skipped("a local Slurm needs root and slurm-wlm (apt-get install slurm-wlm)");
        return;
    }
    let out = Command::new("bash")
        .arg(repo("jobs/slurm-local-check.sh"))
        .env("KAGE", env!("CARGO_BIN_EXE_kage"))
        .output()
        .unwrap();
    let said = format!("{}{}", String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr));
    assert!(out.status.success() && said.contains("6 turntable frames equal"), "{said}");
}

/// The Kubernetes Indexed Job's container command, run here as a pod would
/// run it: its folded `args` through `sh -c` with `JOB_COMPLETION_INDEX` set,
/// the volume's paths pointed at a scratch folder. (No cluster: the
/// manifest's Kubernetes fields are not checked.)
#[test]
fn the_kubernetes_jobs_command_renders_its_index_frame() {
    let manifest = std::fs::read_to_string(repo("jobs/k8s-indexed-job.yaml")).unwrap();
    assert!(manifest.contains("completionMode: Indexed"));
    // The folded scalar after `- >-`: its more-indented lines, joined by spaces.
    let mut lines = manifest.lines().skip_while(|l| l.trim() != "- >-");
    let marker = lines.next().expect("a folded args entry");
    let indent = marker.len() - marker.trim_start().len();
    let command: Vec<&str> =
        lines.take_while(|l| l.len() - l.trim_start().len() > indent && !l.trim().is_empty()).map(str::trim).collect();
    let dir = scratch("k8s");
    let teapot = repo("assets/teapot.obj");
    let command = command
        .join(" ")
        .replace("/data/model.glb", teapot.to_str().unwrap())
        .replace("/data/out", dir.join("out").to_str().unwrap())
        .replace("--width 1920 --height 1080", "--width 80 --height 45")
        .replace("kage render", &format!("{} render", env!("CARGO_BIN_EXE_kage")));
    let out = Command::new("sh").args(["-c", &command]).env("JOB_COMPLETION_INDEX", "7").output().unwrap();
    assert!(out.status.success(), "{command}: {}", String::from_utf8_lossy(&out.stderr));
    let alone = dir.join("alone.png");
    let args =
        ["render", teapot.to_str().unwrap(), "--turntable", "120", "--frame", "7", "--width", "80", "--height", "45"];
    kage(&[&args[..], &["-o", alone.to_str().unwrap()]].concat());
    assert_eq!(bytes(&dir.join("out/spin.0007.png")), bytes(&alone));
}
