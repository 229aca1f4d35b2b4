//! Mutated real files (issue 32, item 7): a small glTF (as `.gltf` text and
//! as `.glb`) and a ray file, written here, then damaged byte by byte, cut
//! short, lengthened, or given hostile values in their JSON fields. The
//! loader and the ray-file reader must never panic: each answer is a valid
//! scene or ray list, or an error naming the file. The cases are bounded
//! (`PROPTEST_CASES` scales them) so that this runs with every test run.

use accel_core::{Ray, Vec3};
use accel_scenes::gltf::load;
use accel_scenes::rayfile;
use proptest::prelude::*;
use proptest::test_runner::Config;
use serde_json::Value;
use std::path::Path;

/// Cases per property unless `PROPTEST_CASES` says otherwise.
fn config(cases: u32) -> Config {
    let cases = std::env::var("PROPTEST_CASES")
        .ok()
        .and_then(|s| s.trim().parse().ok())
        .unwrap_or(cases);
    Config {
        cases,
        // Each case writes its own files: nothing to persist but the seed.
        failure_persistence: None,
        ..Config::default()
    }
}

/// Two triangles of a unit square, indexed, and the buffer holding them.
fn square_buffer() -> Vec<u8> {
    let positions: [[f32; 3]; 4] = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [1.0, 1.0, 0.0],
    ];
    let mut data: Vec<u8> = positions
        .iter()
        .flatten()
        .flat_map(|v| v.to_le_bytes())
        .collect();
    data.extend([0u16, 1, 2, 2, 1, 3].iter().flat_map(|i| i.to_le_bytes()));
    data
}

/// The glTF JSON of the square; `uri` names its buffer, or `None` for a
/// `.glb`'s binary chunk.
fn square_json(uri: Option<&str>) -> Value {
    let buffer = match uri {
        Some(uri) => serde_json::json!({"byteLength": 60, "uri": uri}),
        None => serde_json::json!({"byteLength": 60}),
    };
    serde_json::json!({
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"children": [1], "translation": [1, 2, 3]}, {"mesh": 0, "scale": [2, 2, 2]}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "mode": 4}]}],
        "buffers": [buffer],
        "bufferViews": [
            {"buffer": 0, "byteLength": 48},
            {"buffer": 0, "byteOffset": 48, "byteLength": 12}
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
             "min": [0, 0, 0], "max": [1, 1, 0]},
            {"bufferView": 1, "componentType": 5123, "count": 6, "type": "SCALAR"}
        ],
        "cameras": [{"type": "perspective", "perspective": {"yfov": 0.8, "znear": 0.1}}]
    })
}

/// A `.glb`: header, JSON chunk, binary chunk (each padded to 4 bytes).
fn glb(json: &[u8], bin: &[u8]) -> Vec<u8> {
    let pad = |v: &[u8], with: u8| {
        let mut v = v.to_vec();
        while !v.len().is_multiple_of(4) {
            v.push(with);
        }
        v
    };
    let (json, bin) = (pad(json, b' '), pad(bin, 0));
    let total = 12 + 8 + json.len() + 8 + bin.len();
    let mut out = b"glTF".to_vec();
    out.extend(2u32.to_le_bytes());
    out.extend((total as u32).to_le_bytes());
    out.extend((json.len() as u32).to_le_bytes());
    out.extend(b"JSON");
    out.extend(json);
    out.extend((bin.len() as u32).to_le_bytes());
    out.extend(b"BIN\0");
    out.extend(bin);
    out
}

/// One damage done to a file's bytes.
#[derive(Clone, Debug)]
enum Damage {
    /// Byte `at` (modulo the length) set to `to`.
    Set { at: usize, to: u8 },
    /// Cut to `keep` (modulo the length + 1) bytes.
    Cut { keep: usize },
    /// `bytes` inserted at `at`.
    Insert { at: usize, bytes: Vec<u8> },
}

fn damage() -> impl Strategy<Value = Damage> {
    prop_oneof![
        4 => (any::<usize>(), any::<u8>()).prop_map(|(at, to)| Damage::Set { at, to }),
        1 => any::<usize>().prop_map(|keep| Damage::Cut { keep }),
        1 => (any::<usize>(), prop::collection::vec(any::<u8>(), 1..16))
            .prop_map(|(at, bytes)| Damage::Insert { at, bytes }),
    ]
}

fn apply(bytes: &mut Vec<u8>, damage: &[Damage]) {
    for d in damage {
        match d {
            Damage::Set { at, to } if !bytes.is_empty() => {
                let n = bytes.len();
                bytes[at % n] = *to;
            }
            Damage::Set { .. } => {}
            Damage::Cut { keep } => bytes.truncate(keep % (bytes.len() + 1)),
            Damage::Insert { at, bytes: new } => {
                let at = at % (bytes.len() + 1);
                bytes.splice(at..at, new.iter().copied());
            }
        }
    }
}

/// Hostile values for a JSON field.
fn hostile() -> impl Strategy<Value = Value> {
    prop::sample::select(vec![
        Value::Null,
        serde_json::json!(-1),
        serde_json::json!(0),
        serde_json::json!(3),
        serde_json::json!(1e39),
        serde_json::json!(-3e38),
        serde_json::json!(4_294_967_296u64),
        serde_json::json!(18_446_744_073_709_551_615u64),
        serde_json::json!(0.5),
        serde_json::json!("x"),
        serde_json::json!("../../../dev/zero"),
        serde_json::json!([]),
        serde_json::json!({}),
    ])
}

/// Every leaf of a JSON value (numbers, strings, ...), as pointers.
fn leaves(v: &Value, at: String, out: &mut Vec<String>) {
    match v {
        Value::Object(m) => m
            .iter()
            .for_each(|(k, v)| leaves(v, format!("{at}/{k}"), out)),
        Value::Array(a) => a
            .iter()
            .enumerate()
            .for_each(|(i, v)| leaves(v, format!("{at}/{i}"), out)),
        _ => out.push(at),
    }
}

/// Loads `path`: a scene, or an error that names the file.
fn check_load(path: &Path) -> Result<(), TestCaseError> {
    match load(path) {
        Ok(scene) => {
            prop_assert!(scene.mesh.positions().iter().all(|p| p.is_finite()));
        }
        Err(e) => {
            let name = path.file_name().unwrap().to_string_lossy().into_owned();
            prop_assert!(e.to_string().contains(&name), "{e}");
        }
    }
    Ok(())
}

proptest! {
    #![proptest_config(config(1000))]

    /// Damaged bytes of a `.gltf` (inline base64 buffer) and of a `.glb`.
    #[test]
    fn damaged_gltf_and_glb_files_load_or_are_refused(
        glb_form in any::<bool>(),
        damage in prop::collection::vec(damage(), 1..6),
    ) {
        let dir = tempfile::tempdir().unwrap();
        let (name, mut bytes) = if glb_form {
            let json = serde_json::to_vec(&square_json(None)).unwrap();
            ("square.glb", glb(&json, &square_buffer()))
        } else {
            let uri = format!(
                "data:application/octet-stream;base64,{}",
                base64(&square_buffer())
            );
            ("square.gltf", serde_json::to_vec(&square_json(Some(&uri))).unwrap())
        };
        apply(&mut bytes, &damage);
        let path = dir.path().join(name);
        std::fs::write(&path, &bytes).unwrap();
        check_load(&path)?;
    }

    /// Hostile values in the JSON fields of a `.gltf` whose buffer is a file
    /// beside it (a `uri` may become `../../../dev/zero`, a `byteLength`
    /// 2^64 − 1, a count or an offset past the buffer).
    #[test]
    fn hostile_gltf_fields_load_or_are_refused(
        picks in prop::collection::vec((any::<prop::sample::Index>(), hostile()), 1..4),
    ) {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("square.bin"), square_buffer()).unwrap();
        let mut json = square_json(Some("square.bin"));
        for (index, value) in picks {
            let mut all = Vec::new();
            leaves(&json, String::new(), &mut all);
            let at = index.get(&all);
            *json.pointer_mut(at).unwrap() = value;
        }
        let path = dir.path().join("fields.gltf");
        std::fs::write(&path, serde_json::to_vec(&json).unwrap()).unwrap();
        check_load(&path)?;
    }

    /// Damaged ray files: valid rays, or an error naming the file.
    #[test]
    fn damaged_ray_files_read_or_are_refused(
        damage in prop::collection::vec(damage(), 1..6),
    ) {
        let rays = [
            Ray::new(Vec3::new(0.0f32, 0.0, 0.0), Vec3::new(0.0, 0.0, 1.0)).unwrap(),
            Ray::with_interval(Vec3::new(1.0, 2.0, 3.0), Vec3::new(-1.0, 0.5, 0.0), 0.1, 7.0).unwrap(),
        ];
        let mut bytes = rayfile::encode(&rays);
        apply(&mut bytes, &damage);
        let path = Path::new("damaged.rays");
        match rayfile::decode(path, &bytes) {
            Ok(read) => {
                prop_assert!(read.iter().all(|r| r.validate().is_ok()));
                prop_assert_eq!((bytes.len() - rayfile::HEADER_BYTES) / rayfile::RAY_BYTES, read.len());
            }
            Err(e) => prop_assert!(e.to_string().contains("damaged.rays"), "{e}"),
        }
    }
}

/// Standard base64, for the inline buffer.
fn base64(bytes: &[u8]) -> String {
    const ALPHABET: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::new();
    for chunk in bytes.chunks(3) {
        let b = [
            chunk[0],
            *chunk.get(1).unwrap_or(&0),
            *chunk.get(2).unwrap_or(&0),
        ];
        let n = u32::from(b[0]) << 16 | u32::from(b[1]) << 8 | u32::from(b[2]);
        for i in 0..4 {
            if i <= chunk.len() {
                out.push(ALPHABET[(n >> (18 - 6 * i) & 63) as usize] as char);
            } else {
                out.push('=');
            }
        }
    }
    out
}

/// The premise of the properties: undamaged, each file loads (two
/// triangles, moved by the nodes) and the ray file reads back.
#[test]
fn the_undamaged_files_load() {
    let dir = tempfile::tempdir().unwrap();
    let uri = format!(
        "data:application/octet-stream;base64,{}",
        base64(&square_buffer())
    );
    let gltf = dir.path().join("a.gltf");
    std::fs::write(&gltf, serde_json::to_vec(&square_json(Some(&uri))).unwrap()).unwrap();
    let json = serde_json::to_vec(&square_json(None)).unwrap();
    let glb_path = dir.path().join("a.glb");
    std::fs::write(&glb_path, glb(&json, &square_buffer())).unwrap();
    std::fs::write(dir.path().join("square.bin"), square_buffer()).unwrap();
    let external = dir.path().join("b.gltf");
    std::fs::write(
        &external,
        serde_json::to_vec(&square_json(Some("square.bin"))).unwrap(),
    )
    .unwrap();
    for path in [gltf, glb_path, external] {
        let scene = load(&path).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(scene.mesh.triangle_count(), 2, "{}", path.display());
        let b = scene.mesh.bounds();
        assert_eq!((b.min.x, b.max.x), (1.0, 3.0), "translated, then scaled");
        assert_eq!(scene.cameras.len(), 0, "the camera is on no node");
    }
    let rays = [Ray::new(Vec3::new(0.0f32, 0.0, 0.0), Vec3::new(0.0, 0.0, 1.0)).unwrap()];
    let read = rayfile::decode(Path::new("r.rays"), &rayfile::encode(&rays)).unwrap();
    assert_eq!(read, rays);
}
