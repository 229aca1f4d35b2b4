//! End-to-end runs of `render bench`: the JSON report, agreement between
//! accelerators, and ray files written and read back.

mod common;

use accel::KdTreeParams;
use common::{line, run, stdout};
use serde_json::Value;

const FAST: [&str; 8] = [
    "--width",
    "12",
    "--height",
    "8",
    "--min-time",
    "0",
    "--threads",
    "2",
];

fn json(path: &std::path::Path) -> Value {
    serde_json::from_slice(&std::fs::read(path).unwrap()).unwrap()
}

fn set<'a>(accel: &'a Value, kind: &str) -> &'a Value {
    accel["sets"]
        .as_array()
        .unwrap()
        .iter()
        .find(|s| s["kind"] == kind)
        .unwrap_or_else(|| panic!("no {kind} set in {accel}"))
}

#[test]
fn bench_reports_every_accelerator_as_a_table_and_json() {
    let dir = tempfile::tempdir().unwrap();
    let mut args = vec![
        "bench",
        "default",
        "--json",
        "b.json",
        "--write-rays",
        "r.rays",
    ];
    args.extend(FAST);
    let o = run(dir.path(), &args);
    assert!(o.status.success(), "{}", common::stderr(&o));
    let text = stdout(&o);
    assert!(line(&text, "accel ").contains("Mrays/s 2T"), "{text}");
    assert!(text.contains("all accelerators agree"), "{text}");
    let report = json(&dir.path().join("b.json"));
    assert_eq!(report["scene"], "default");
    assert_eq!(report["threads"], 2);
    assert_eq!(report["agree"], true);
    let accels = report["accelerators"].as_array().unwrap();
    let names: Vec<_> = accels
        .iter()
        .map(|a| a["accel"].as_str().unwrap())
        .collect();
    // The scene is tiny at this ray count, so brute force joins the structures.
    assert!(
        names.contains(&"grid") && names.contains(&"brute"),
        "{names:?}"
    );
    for a in accels {
        assert!(a["bytes"].as_u64().is_some() && a["build_ms"].as_f64().is_some());
        // Shape statistics: consistent with each other.
        let count = |k: &str| a[k].as_u64().unwrap_or_else(|| panic!("{k} in {a}"));
        assert!(count("empty_leaves") <= count("leaves"), "{a}");
        assert!(count("max_leaf_references") <= count("references"), "{a}");
        assert!(count("max_leaf_references") > 0, "{a}");
        let extra = &a["extra"];
        match a["accel"].as_str().unwrap() {
            "grid" => {
                let cells: f64 = ["nx", "ny", "nz"]
                    .iter()
                    .map(|k| extra[k].as_f64().unwrap())
                    .product();
                assert_eq!(cells as u64, count("leaves"), "{a}");
            }
            "kdtree" => {
                // Cuts that isolate a dense part may take a path past the
                // depth limit, never past the traversal stack.
                let depth = extra["depth"].as_f64().unwrap();
                let limit = extra["depth_limit"].as_f64().unwrap();
                assert!(
                    depth >= 1.0
                        && limit <= f64::from(KdTreeParams::MAX_DEPTH)
                        && depth <= f64::from(KdTreeParams::MAX_DEPTH),
                    "{a}"
                );
                assert!(extra["sah_cost"].as_f64().unwrap() > 0.0, "{a}");
            }
            _ => {}
        }
        for kind in ["primary", "shadow", "diffuse"] {
            let s = set(a, kind);
            assert!(s["mrays_one_thread"].as_f64().unwrap() > 0.0);
            assert!(s["mrays_all_threads"].as_f64().unwrap() > 0.0);
            // Identical answers to the first accelerator's.
            let first = set(&accels[0], kind);
            assert_eq!(s["hits"], first["hits"], "{kind}");
            assert_eq!(s["digest"], first["digest"], "{kind}");
            assert_eq!(s["t_sum"], first["t_sum"], "{kind}");
        }
        assert_eq!(set(a, "shadow")["query"], "occluded");
        assert!(set(a, "shadow")["t_sum"].is_null());
    }
    let primary = set(&accels[0], "primary");
    assert_eq!(primary["rays"], 96);
    assert!(primary["hits"].as_u64().unwrap() > 0);
    // The ray file holds every generated ray.
    let total: u64 = ["primary", "shadow", "diffuse"]
        .iter()
        .map(|k| set(&accels[0], k)["rays"].as_u64().unwrap())
        .sum();
    let bytes = std::fs::read(dir.path().join("r.rays")).unwrap();
    assert_eq!(bytes.len() as u64, 16 + 32 * total);
    assert_eq!(&bytes[..4], b"RAYS");
}

#[test]
fn written_rays_read_back_give_the_same_answers() {
    let dir = tempfile::tempdir().unwrap();
    let mut args = vec![
        "bench",
        "default",
        "--accel",
        "grid",
        "--json",
        "gen.json",
        "--write-rays",
        "r.rays",
    ];
    args.extend(FAST);
    let o = run(dir.path(), &args);
    assert!(o.status.success(), "{}", common::stderr(&o));
    let mut args = vec![
        "bench",
        "--accel",
        "grid,brute",
        "--rays",
        "r.rays",
        "--json",
        "file.json",
    ];
    args.extend(FAST);
    let o = run(dir.path(), &args);
    assert!(o.status.success(), "{}", common::stderr(&o));
    assert!(
        stdout(&o).contains("rays (r.rays): file "),
        "{}",
        stdout(&o)
    );
    let generated = json(&dir.path().join("gen.json"));
    let from_file = json(&dir.path().join("file.json"));
    let g = &generated["accelerators"][0];
    let f = &from_file["accelerators"][0];
    let file = set(f, "file");
    let hits = |k: &str| set(g, k)["hits"].as_u64().unwrap();
    let rays = |k: &str| set(g, k)["rays"].as_u64().unwrap();
    // Nearest-hit queries on the concatenated sets: a shadow ray's nearest
    // hit exists exactly when it is occluded.
    assert_eq!(
        file["rays"].as_u64().unwrap(),
        rays("primary") + rays("shadow") + rays("diffuse")
    );
    assert_eq!(
        file["hits"].as_u64().unwrap(),
        hits("primary") + hits("shadow") + hits("diffuse")
    );
    assert_eq!(from_file["agree"], true);
    // Writing the file's rays again reproduces it byte for byte.
    let mut args = vec![
        "bench",
        "--accel",
        "grid",
        "--rays",
        "r.rays",
        "--write-rays",
        "again.rays",
    ];
    args.extend(FAST);
    let o = run(dir.path(), &args);
    assert!(o.status.success(), "{}", common::stderr(&o));
    assert_eq!(
        std::fs::read(dir.path().join("r.rays")).unwrap(),
        std::fs::read(dir.path().join("again.rays")).unwrap()
    );
}
