//! Bad input, end to end: every refusal is one clear line on stderr and a
//! non-zero exit, never a panic, and never a partial output file.

mod common;

use common::{Gltf, SQUARE, SQUARE_INDICES, assert_refused, entries, run};
use std::path::Path;

const TINY: [&str; 6] = ["--width", "8", "--height", "8", "--ao", "0"];

/// Renders `scene` to `out.png` in `dir`, where `out.png` already holds an
/// older picture, and checks the refusal left it, and nothing else, behind.
fn refuse_scene(dir: &Path, scene: &str, needles: &[&str]) {
    let out = dir.join("out.png");
    std::fs::write(&out, b"old picture").unwrap();
    let before = entries(dir);
    let mut args = vec![scene, "--out", "out.png"];
    args.extend(TINY);
    let o = run(dir, &args);
    assert_refused(&o, needles);
    assert_eq!(
        std::fs::read(&out).unwrap(),
        b"old picture",
        "{scene}: output touched"
    );
    assert_eq!(entries(dir), before, "{scene}: files left behind");
}

#[test]
fn missing_unreadable_and_unknown_scenes() {
    let dir = tempfile::tempdir().unwrap();
    refuse_scene(
        dir.path(),
        "missing.glb",
        &["missing.glb", "cannot read the file"],
    );
    std::fs::create_dir(dir.path().join("folder.glb")).unwrap();
    refuse_scene(dir.path(), "folder.glb", &["folder.glb", "cannot read"]);
    refuse_scene(
        dir.path(),
        "sphere_1k",
        &["sphere_1k", "built-in", "default"],
    );
}

#[test]
fn malformed_gltf_files() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("garbage.glb"), b"\x00\x01 this is not glTF").unwrap();
    refuse_scene(
        dir.path(),
        "garbage.glb",
        &["garbage.glb", "not a valid glTF file"],
    );
    std::fs::write(dir.path().join("json.gltf"), b"{ \"asset\": ").unwrap();
    refuse_scene(
        dir.path(),
        "json.gltf",
        &["json.gltf", "not a valid glTF file"],
    );
    // A binary glTF cut short in its header.
    std::fs::write(dir.path().join("cut.glb"), b"glTF\x02\x00\x00\x00\xff\x00").unwrap();
    refuse_scene(dir.path(), "cut.glb", &["cut.glb"]);
    // An index past the last vertex.
    Gltf {
        positions: &SQUARE,
        indices: Some(&[0, 1, 7]),
        mode: 4,
        nodes: r#"[{"mesh":0}]"#,
        extra: "",
    }
    .write(dir.path(), "index.gltf");
    refuse_scene(dir.path(), "index.gltf", &["index.gltf", "vertex 7"]);
}

#[test]
fn unsupported_primitive_modes_are_named() {
    let dir = tempfile::tempdir().unwrap();
    for (mode, name) in [
        (0, "POINTS"),
        (1, "LINES"),
        (2, "LINE_LOOP"),
        (3, "LINE_STRIP"),
    ] {
        let file = format!("mode{mode}.gltf");
        Gltf {
            positions: &SQUARE,
            indices: None,
            mode,
            nodes: r#"[{"mesh":0}]"#,
            extra: "",
        }
        .write(dir.path(), &file);
        refuse_scene(dir.path(), &file, &[&file, name, "not a triangle mode"]);
    }
}

#[test]
fn nan_vertices_and_empty_scenes() {
    let dir = tempfile::tempdir().unwrap();
    let mut nan = SQUARE;
    nan[2][1] = f32::NAN;
    Gltf {
        positions: &nan,
        indices: Some(&SQUARE_INDICES),
        mode: 4,
        nodes: r#"[{"mesh":0}]"#,
        extra: "",
    }
    .write(dir.path(), "nan.gltf");
    refuse_scene(
        dir.path(),
        "nan.gltf",
        &["nan.gltf", "vertex 2", "non-finite"],
    );
    // A scale past the f32 range reads as infinity: blamed on the node,
    // not on the vertices it would move (issue 32, item 5).
    Gltf {
        positions: &SQUARE,
        indices: Some(&SQUARE_INDICES),
        mode: 4,
        nodes: r#"[{"mesh":0,"scale":[1e39,1,1]}]"#,
        extra: "",
    }
    .write(dir.path(), "inf.gltf");
    refuse_scene(
        dir.path(),
        "inf.gltf",
        &["inf.gltf", "node 0's transform is not finite"],
    );
    // Nodes without meshes: nothing to render.
    Gltf {
        positions: &SQUARE,
        indices: Some(&SQUARE_INDICES),
        mode: 4,
        nodes: r#"[{"children":[]}]"#,
        extra: "",
    }
    .write(dir.path(), "empty.gltf");
    refuse_scene(dir.path(), "empty.gltf", &["empty.gltf", "no triangles"]);
    // Triangles that exist but are all degenerate are not an error: they
    // render as empty space.
    Gltf {
        positions: &[[1.0, 1.0, 1.0]; 3],
        indices: None,
        mode: 4,
        nodes: r#"[{"mesh":0}]"#,
        extra: "",
    }
    .write(dir.path(), "point.gltf");
    let o = run(
        dir.path(),
        &[
            "point.gltf",
            "--out",
            "p.png",
            "--width",
            "8",
            "--height",
            "8",
        ],
    );
    assert!(o.status.success(), "{}", common::stderr(&o));
}

#[test]
fn bad_ray_files() {
    let dir = tempfile::tempdir().unwrap();
    let mut good = b"RAYS".to_vec();
    good.extend(1u32.to_le_bytes());
    good.extend(2u64.to_le_bytes());
    for ray in [[0.0f32, 0.0, 5.0, 0.0, 0.0, -1.0, 0.0, f32::INFINITY]; 2] {
        good.extend(ray.iter().flat_map(|v| v.to_le_bytes()));
    }
    let mut cases: Vec<(&str, Vec<u8>, &[&str])> = vec![
        (
            "short.rays",
            good[..9].to_vec(),
            &["shorter than the 16-byte header"],
        ),
        (
            "magic.rays",
            [b"SYAR", &good[4..]].concat(),
            &["not \"RAYS\""],
        ),
        (
            "version.rays",
            [&good[..4], &7u32.to_le_bytes()[..], &good[8..]].concat(),
            &["version 7"],
        ),
        (
            "count.rays",
            good[..good.len() - 4].to_vec(),
            &["announces 2 rays"],
        ),
    ];
    let mut nan = good.clone();
    nan[16 + 32 + 8..16 + 32 + 12].copy_from_slice(&f32::NAN.to_le_bytes());
    cases.push((
        "nan.rays",
        nan,
        &["ray 1 is invalid", "origin is not finite"],
    ));
    for (name, bytes, needles) in cases {
        std::fs::write(dir.path().join(name), bytes).unwrap();
        let before = entries(dir.path());
        let o = run(
            dir.path(),
            &[
                "bench",
                "--rays",
                name,
                "--json",
                "b.json",
                "--min-time",
                "0",
            ],
        );
        let mut all = vec![name];
        all.extend(needles);
        assert_refused(&o, &all);
        assert_eq!(entries(dir.path()), before, "{name}: files left behind");
    }
    let o = run(dir.path(), &["bench", "--rays", "absent.rays"]);
    assert_refused(&o, &["absent.rays", "cannot read"]);
    // The good file is accepted (two rays, both hit the floor).
    std::fs::write(dir.path().join("good.rays"), &good).unwrap();
    let o = run(
        dir.path(),
        &[
            "bench",
            "--rays",
            "good.rays",
            "--accel",
            "grid",
            "--min-time",
            "0",
        ],
    );
    assert!(o.status.success(), "{}", common::stderr(&o));
}

#[test]
fn unwritable_outputs_are_refused_before_any_work() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::create_dir(dir.path().join("sub.png")).unwrap();
    for (args, needles) in [
        (
            &["--out", "no/such/dir/x.png"][..],
            &["no/such/dir/x.png"][..],
        ),
        (&["--out", "sub.png"], &["sub.png", "is a directory"]),
        (&["--out", "x.jpg"], &["x.jpg", "only PNG"]),
        (&["--heatmap=no/dir/h.png"], &["no/dir/h.png"]),
        (&["bench", "--json", "no/dir/b.json"], &["no/dir/b.json"]),
        (
            &["bench", "--write-rays", "sub.png"],
            &["sub.png", "is a directory"],
        ),
    ] {
        let before = entries(dir.path());
        let mut all: Vec<&str> = args.to_vec();
        if args[0] == "bench" {
            all.extend(["--width", "8", "--height", "8", "--min-time", "0"]);
        } else {
            all.extend(TINY);
        }
        let o = run(dir.path(), &all);
        assert_refused(&o, needles);
        // Refused before loading anything: no scene line was printed.
        assert!(
            common::stdout(&o).is_empty(),
            "{args:?}: {}",
            common::stdout(&o)
        );
        assert_eq!(entries(dir.path()), before, "{args:?}");
    }
}

#[test]
fn absurd_sizes_and_unknown_options() {
    let dir = tempfile::tempdir().unwrap();
    for (args, needles) in [
        (&["--width", "0"][..], &["--width", "0"][..]),
        (&["--width", "100000"], &["--width", "100000"]),
        (&["--height", "-5"], &["-5"]),
        (&["--spp", "0"], &["--spp"]),
        (&["--spp", "99999999"], &["--spp"]),
        (&["--ao", "100000"], &["--ao"]),
        (
            &["--width", "16384", "--height", "16384"],
            &["pixels", "over the limit"],
        ),
        (&["--accel", "bvh"], &["bvh"]),
        (&["--precision", "f16"], &["f16"]),
        (&["bench", "--min-time", "-1"], &["-1"]),
        (&["bench", "--width", "0"], &["--width"]),
        (&["--frobnicate"], &["--frobnicate"]),
    ] {
        let o = run(dir.path(), args);
        assert_refused(&o, needles);
        assert!(entries(dir.path()).is_empty(), "{args:?}");
    }
}

/// A square with every coordinate at `±a` (finite in `f32`).
fn square_at(a: f32) -> [[f32; 3]; 4] {
    [[-a, -a, -a], [a, -a, -a], [-a, a, a], [a, a, a]]
}

/// See: issue 32, item 1. A glTF at ±3e38 (finite `f32`, its extent is not)
/// made `--accel grid|octree` panic and the others fail on "ray origin is not
/// finite": now every accelerator refuses it in `f32`, naming the scene, the
/// limit and `--precision f64`, which renders it.
#[test]
fn finite_extremes_name_the_limit_and_the_remedy() {
    let dir = tempfile::tempdir().unwrap();
    Gltf {
        positions: &square_at(3e38),
        indices: Some(&SQUARE_INDICES),
        mode: 4,
        nodes: r#"[{"mesh":0}]"#,
        extra: "",
    }
    .write(dir.path(), "huge.gltf");
    for accel in ["grid", "octree", "kdtree", "brute", "auto"] {
        let scene = "huge.gltf";
        let out = dir.path().join("out.png");
        std::fs::write(&out, b"old picture").unwrap();
        let before = entries(dir.path());
        let mut args = vec![scene, "--accel", accel, "--out", "out.png"];
        args.extend(TINY);
        let o = run(dir.path(), &args);
        assert_refused(
            &o,
            &[
                "huge.gltf",
                "3e38",
                "largest f32 coordinate",
                "--precision f64",
            ],
        );
        assert_eq!(std::fs::read(&out).unwrap(), b"old picture", "{accel}");
        assert_eq!(entries(dir.path()), before, "{accel}: files left behind");
        args.extend(["--precision", "f64"]);
        let o = run(dir.path(), &args);
        assert!(o.status.success(), "{accel} in f64: {}", common::stderr(&o));
        assert_ne!(std::fs::read(&out).unwrap(), b"old picture", "{accel}");
    }
}

/// Just inside the `f32` limit (1e37, the limit is about 2.1e37) a scene
/// either renders or is refused in one line with the remedy: the camera,
/// framed around the scene, may stand beyond the limit.
#[test]
fn scenes_inside_the_f32_limit_render_or_name_the_remedy() {
    let dir = tempfile::tempdir().unwrap();
    Gltf {
        positions: &square_at(1e37),
        indices: Some(&SQUARE_INDICES),
        mode: 4,
        nodes: r#"[{"mesh":0}]"#,
        extra: "",
    }
    .write(dir.path(), "big.gltf");
    for accel in ["grid", "octree", "kdtree", "brute"] {
        let mut args = vec!["big.gltf", "--accel", accel, "--out", "out.png"];
        args.extend(TINY);
        let o = run(dir.path(), &args);
        if !o.status.success() {
            assert_refused(&o, &["ray origin is beyond", "--precision f64"]);
        }
    }
}

/// See: issue 32, item 3 (left over). `render bench --width 8192 --height
/// 8192` passes the 64-megapixel cap, but its generated rays need about
/// 30 GiB in `f64` (480 bytes a pixel): the estimate is refused against
/// `--memory-budget` before the scene is even loaded, as a render's is. A
/// bench within the budget runs, and rays read from a file are not
/// estimated by the image size (the file bounds them).
#[test]
fn benches_over_the_memory_budget_are_refused_before_any_work() {
    let dir = tempfile::tempdir().unwrap();
    for (args, needles) in [
        (
            &[
                "bench",
                "--width",
                "8192",
                "--height",
                "8192",
                "--precision",
                "f64",
            ][..],
            &[
                "8192",
                "30.0 GiB",
                "in f64",
                "480 bytes a pixel",
                "--memory-budget of 8 GiB",
            ][..],
        ),
        (
            &[
                "bench",
                "--width",
                "4096",
                "--height",
                "4096",
                "--memory-budget",
                "4",
            ],
            &[
                "4.7 GiB",
                "in f32",
                "300 bytes a pixel",
                "--memory-budget of 4 GiB",
            ],
        ),
    ] {
        let o = run(dir.path(), args);
        assert_refused(&o, needles);
        assert!(common::stdout(&o).is_empty(), "{}", common::stdout(&o));
        assert!(entries(dir.path()).is_empty());
    }
    let small = [
        "bench",
        "--accel",
        "grid",
        "--width",
        "32",
        "--height",
        "32",
        "--min-time",
        "0.001",
    ];
    let mut args = small.to_vec();
    args.extend(["--memory-budget", "0.01", "--write-rays", "r.rays"]);
    let o = run(dir.path(), &args);
    assert!(o.status.success(), "{}", common::stderr(&o));
    // 32² × 300 bytes is 0.0003 GiB: over a budget of 0.0001 GiB.
    let mut args = small.to_vec();
    args.extend(["--memory-budget", "0.0001"]);
    assert_refused(&run(dir.path(), &args), &["--memory-budget of 0.0001 GiB"]);
    // With --rays the image size does not count.
    let mut args = small.to_vec();
    args.extend(["--memory-budget", "0.0001", "--rays", "r.rays"]);
    let o = run(dir.path(), &args);
    assert!(o.status.success(), "{}", common::stderr(&o));
}

/// See: issue 32, item 1 (left over). A scene at 2e37 (inside the `f32`
/// limit of about 2.1e37) is framed from a camera beyond it. Every named
/// accelerator refuses the first pixel's ray with the remedy; `--accel auto`
/// traces probe rays from that camera before any pixel (on an image large
/// enough to be worth probing: 2 triangles × 256² pixels × 2 rays is past
/// `choose::TINY_WORK`), and must name the remedy too. In `f64` it renders.
#[test]
fn a_camera_beyond_the_f32_limit_names_the_remedy_with_every_accelerator() {
    let dir = tempfile::tempdir().unwrap();
    Gltf {
        positions: &square_at(2e37),
        indices: Some(&SQUARE_INDICES),
        mode: 4,
        nodes: r#"[{"mesh":0}]"#,
        extra: "",
    }
    .write(dir.path(), "far.gltf");
    let size = [
        "--width", "256", "--height", "256", "--ao", "0", "--spp", "1",
    ];
    for accel in ["grid", "octree", "kdtree", "brute", "auto"] {
        let mut args = vec!["far.gltf", "--accel", accel, "--out", "out.png"];
        args.extend(size);
        let o = run(dir.path(), &args);
        assert_refused(&o, &["ray origin is beyond", "f32", "--precision f64"]);
        assert!(!dir.path().join("out.png").exists(), "{accel}");
    }
    let mut args = vec!["far.gltf", "--accel", "auto", "--out", "out.png"];
    args.extend(size);
    args.extend(["--precision", "f64"]);
    let o = run(dir.path(), &args);
    assert!(o.status.success(), "auto in f64: {}", common::stderr(&o));
    assert!(common::stdout(&o).contains("auto: "), "premise: auto chose");
}

/// See: issue 32, item 4. A run killed while it traces (SIGKILL: no
/// destructor runs, as after an unhandled Ctrl-C or SIGTERM) leaves no hidden
/// `.out.png.XXXXXX.tmp` behind: the outputs were checked before the work
/// began, but no temporary file exists until the picture is written.
#[test]
fn an_interrupted_run_leaves_no_temporary_file() {
    use std::io::{BufRead, BufReader};
    use std::process::{Command, Stdio};
    let dir = tempfile::tempdir().unwrap();
    let mut child = Command::new(env!("CARGO_BIN_EXE_render"))
        .current_dir(dir.path())
        .args(["--out", "out.png", "--heatmap=heat.png"])
        .args(["--width", "1024", "--height", "1024", "--ao", "16"])
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let lines = BufReader::new(child.stdout.take().unwrap()).lines();
    // The structure is built: tracing starts next (seconds of work).
    let tracing = lines.map_while(Result::ok).any(|l| l.starts_with("build "));
    child.kill().unwrap();
    child.wait().unwrap();
    assert!(tracing, "premise: the run got as far as tracing");
    assert!(
        !dir.path().join("out.png").exists(),
        "premise: killed before the picture was written"
    );
    assert_eq!(entries(dir.path()), Vec::<String>::new());
}

/// See: issue 32, item 3. `--width 8192 --height 8192` passed the 64-Mpx
/// cap but needed about 13 GiB: the estimate is refused against
/// `--memory-budget` (8 GiB by default) before the scene is even loaded, and
/// a smaller budget refuses smaller renders the same way.
#[test]
fn renders_over_the_memory_budget_are_refused_before_any_work() {
    let dir = tempfile::tempdir().unwrap();
    for (args, needles) in [
        (
            &["--width", "8192", "--height", "8192"][..],
            &[
                "8192",
                "13.0 GiB",
                "208 bytes a pixel",
                "--memory-budget of 8 GiB",
            ][..],
        ),
        (
            &[
                "--width",
                "64",
                "--height",
                "64",
                "--memory-budget",
                "0.0001",
            ],
            &["64", "--memory-budget of 0.0001 GiB"],
        ),
    ] {
        let o = run(dir.path(), args);
        assert_refused(&o, needles);
        assert!(common::stdout(&o).is_empty(), "{}", common::stdout(&o));
        assert!(entries(dir.path()).is_empty());
    }
    let o = run(dir.path(), &["--memory-budget", "nan"]);
    assert_refused(&o, &["--memory-budget", "not a number of GiB"]);
    let mut args = vec!["--memory-budget", "0.01", "--out", "ok.png"];
    args.extend(TINY);
    let o = run(dir.path(), &args);
    assert!(o.status.success(), "{}", common::stderr(&o));
}

/// `--memory-budget` also bounds the structure a named `--accel` builds:
/// each structure stops at it with the figure, naming the option, and no
/// image is written. A 100k-triangle sphere takes about 4 MiB in each.
#[test]
fn a_structure_over_the_memory_budget_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    for accel in ["grid", "octree", "kdtree"] {
        let render = |extra: &[&str]| {
            let mut args = vec![
                "sphere_100k",
                "--accel",
                accel,
                "--width",
                "16",
                "--height",
                "16",
                "--out",
                "x.png",
            ];
            args.extend(extra);
            run(dir.path(), &args)
        };
        let o = render(&["--memory-budget", "0.0005"]);
        assert_refused(
            &o,
            &["--memory-budget 0.0005 GiB", accel, "over the budget"],
        );
        assert!(
            entries(dir.path()).is_empty(),
            "{accel}: {:?}",
            entries(dir.path())
        );
        // The same render with the default budget builds and writes.
        let o = render(&[]);
        assert!(o.status.success(), "{}", common::stderr(&o));
        std::fs::remove_file(dir.path().join("x.png")).unwrap();
    }
}
