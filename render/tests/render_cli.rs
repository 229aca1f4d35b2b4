//! End-to-end runs of `render`: the equivalence promise on whole images,
//! heat maps, glTF files and the shared scenes.

mod common;

use accel::AccelKind;
use accel_scenes::gltf::shared_scene_files_for_test;
use common::{Gltf, SQUARE, SQUARE_INDICES, line, run, stdout};

/// Small enough for the dev profile with brute force on the default scene.
const SMALL: [&str; 8] = ["--width", "32", "--height", "24", "--spp", "2", "--ao", "2"];

#[test]
fn default_scene_renders_identically_with_every_accelerator() {
    let dir = tempfile::tempdir().unwrap();
    for precision in ["f32", "f64"] {
        let mut reference: Option<(String, Vec<u8>)> = None;
        for kind in AccelKind::ALL {
            let out = format!("{}-{precision}.png", kind.name());
            let mut args = vec![
                "--accel",
                kind.name(),
                "--precision",
                precision,
                "--out",
                &out,
            ];
            args.extend(SMALL);
            let o = run(dir.path(), &args);
            assert!(o.status.success(), "{kind}: {}", common::stderr(&o));
            let text = stdout(&o);
            assert!(line(&text, "build ").contains(kind.name()), "{text}");
            // Same answers to every query (counts and a digest of every hit's bits)...
            let hits = line(&text, "hits: ").to_owned();
            // ...and the same pixels, byte for byte.
            let png = std::fs::read(dir.path().join(&out)).unwrap();
            match &reference {
                None => {
                    let img = image::load_from_memory(&png).unwrap().to_rgb8();
                    assert_eq!((img.width(), img.height()), (32, 24));
                    // A picture, not a blank: sky, floor and objects differ.
                    let distinct: std::collections::HashSet<_> = img.pixels().collect();
                    assert!(distinct.len() > 50, "{} colours", distinct.len());
                    assert!(!hits.contains("primary 0/"), "{hits}");
                    reference = Some((hits, png));
                }
                Some((ref_hits, ref_png)) => {
                    assert_eq!(&hits, ref_hits, "{kind} {precision}: other answers");
                    assert!(png == *ref_png, "{kind} {precision}: other pixels");
                }
            }
        }
    }
}

#[test]
fn no_arguments_but_size_renders_the_default_scene_to_render_png() {
    let dir = tempfile::tempdir().unwrap();
    let o = run(
        dir.path(),
        &["--width", "16", "--height", "12", "--ao", "0"],
    );
    assert!(o.status.success(), "{}", common::stderr(&o));
    let text = stdout(&o);
    assert!(line(&text, "scene default: ").contains("triangles"));
    // `auto` names the structure it chose and why (issue 7: the choice
    // depends on the ray budget; for this tiny render the cheapest build).
    let auto = line(&text, "auto: ");
    assert!(
        AccelKind::ALL.iter().any(|k| auto.contains(k.name())),
        "{text}"
    );
    assert!(auto.contains("rays: est. build"), "{text}");
    assert!(line(&text, "trace ").contains("Mrays/s"));
    assert_eq!(line(&text, "wrote "), "wrote render.png");
    assert!(dir.path().join("render.png").is_file());
    // Nothing else is left behind (no temporary files).
    assert_eq!(common::entries(dir.path()), vec!["render.png".to_owned()]);
}

#[test]
fn heat_maps_show_where_each_accelerator_works() {
    let dir = tempfile::tempdir().unwrap();
    let mut maps = Vec::new();
    for kind in AccelKind::ALL {
        let heat = format!("--heatmap={}-heat.png", kind.name());
        let o = run(
            dir.path(),
            &[
                "--accel",
                kind.name(),
                "--width",
                "24",
                "--height",
                "16",
                "--ao",
                "0",
                &heat,
                "--out",
                "r.png",
            ],
        );
        assert!(o.status.success(), "{kind}: {}", common::stderr(&o));
        let text = stdout(&o);
        assert!(line(&text, "heat map: ").contains("per ray"), "{text}");
        let img = image::open(dir.path().join(format!("{}-heat.png", kind.name())))
            .unwrap()
            .to_rgb8();
        // Two panels side by side with a 4-pixel gap, the legend underneath.
        assert_eq!(img.width(), 2 * 24 + 4);
        assert!(img.height() > 16 + 20, "{}", img.height());
        maps.push(img.into_raw());
    }
    // Brute force tests everything everywhere: its map differs from a structure's.
    if maps.len() > 1 {
        assert_ne!(maps[0], maps[maps.len() - 1]);
    }
}

#[test]
fn gltf_files_use_their_camera_or_are_framed() {
    let dir = tempfile::tempdir().unwrap();
    let small = [
        "--width", "16", "--height", "16", "--spp", "1", "--ao", "1", "--out", "g.png",
    ];
    // A camera 3 units above the square, looking down its −z axis.
    let with_camera = Gltf {
        positions: &SQUARE,
        indices: Some(&SQUARE_INDICES),
        mode: 4,
        nodes: r#"[{"children":[1,2]},{"mesh":0},{"camera":0,"translation":[0.5,0.5,3]}]"#,
        extra: r#""cameras":[{"type":"perspective","perspective":{"yfov":0.2,"znear":0.1}}]"#,
    }
    .write(dir.path(), "camera.gltf");
    let mut args = vec![with_camera.to_str().unwrap()];
    args.extend(small);
    let o = run(dir.path(), &args);
    assert!(o.status.success(), "{}", common::stderr(&o));
    let text = stdout(&o);
    assert!(text.contains("2 triangles"), "{text}");
    assert!(text.contains("the file's first camera"), "{text}");
    // The square fills the narrow view: every primary ray hits it.
    assert!(
        line(&text, "hits: ").starts_with("hits: primary 256/256"),
        "{text}"
    );

    // No camera; the mesh instanced twice, once moved and scaled (TRS).
    let instanced = Gltf {
        positions: &SQUARE,
        indices: Some(&SQUARE_INDICES),
        mode: 4,
        nodes: r#"[{"children":[1,2]},{"mesh":0},{"mesh":0,"translation":[2,0,0],"scale":[1,2,1]}]"#,
        extra: "",
    }
    .write(dir.path(), "instanced.gltf");
    let mut args = vec![instanced.to_str().unwrap()];
    args.extend(small);
    let o = run(dir.path(), &args);
    assert!(o.status.success(), "{}", common::stderr(&o));
    let text = stdout(&o);
    assert!(text.contains("4 triangles"), "{text}");
    assert!(
        text.contains("bounds (0.0000, 0.0000, 0.0000) .. (3.0000, 2.0000, 0.0000)"),
        "{text}"
    );
    assert!(text.contains("framed automatically"), "{text}");
    assert!(
        !line(&text, "hits: ").starts_with("hits: primary 0/"),
        "{text}"
    );

    // A triangle strip without indices: 4 vertices, 2 triangles.
    let strip = Gltf {
        positions: &SQUARE,
        indices: None,
        mode: 5,
        nodes: r#"[{"mesh":0}]"#,
        extra: "",
    }
    .write(dir.path(), "strip.gltf");
    let mut args = vec![strip.to_str().unwrap()];
    args.extend(small);
    let o = run(dir.path(), &args);
    assert!(o.status.success(), "{}", common::stderr(&o));
    assert!(stdout(&o).contains("2 triangles"), "{}", stdout(&o));
}

#[test]
fn shared_scenes_render_with_their_counts_and_bounds() {
    let Some(files) = shared_scene_files_for_test() else {
        return;
    };
    let boxed = files
        .iter()
        .find(|p| p.ends_with("khronos_box_textured.glb"))
        .expect("the shared scenes hold khronos_box_textured.glb");
    let dir = tempfile::tempdir().unwrap();
    // uint16 indices and a node matrix (a rotation) in the original Khronos file.
    let o = run(
        dir.path(),
        &[
            boxed.to_str().unwrap(),
            "--width",
            "16",
            "--height",
            "16",
            "--out",
            "box.png",
        ],
    );
    assert!(o.status.success(), "{}", common::stderr(&o));
    let text = stdout(&o);
    assert!(
        text.contains(
            ": 12 triangles, bounds (-0.5000, -0.5000, -0.5000) .. (0.5000, 0.5000, 0.5000)"
        ),
        "{text}"
    );
    assert!(dir.path().join("box.png").is_file());
    if let Some(teapot) = files.iter().find(|p| p.ends_with("teapot.glb")) {
        let o = run(
            dir.path(),
            &[
                teapot.to_str().unwrap(),
                "--width",
                "16",
                "--height",
                "16",
                "--accel",
                "grid",
                "--out",
                "t.png",
            ],
        );
        assert!(o.status.success(), "{}", common::stderr(&o));
        assert!(stdout(&o).contains(": 992 triangles"), "{}", stdout(&o));
    }
}
