//! End-to-end runs of `studies peers`: our accelerators always, the peers
//! when their features are enabled, the table, the JSON report, ray files.

use serde_json::Value;
use std::path::Path;
use std::process::Output;

/// Runs the `studies` binary with `args` in `dir`.
fn run(dir: &Path, args: &[&str]) -> Output {
    assert_cmd::cargo::cargo_bin_cmd!("studies")
        .current_dir(dir)
        .args(args)
        .output()
        .unwrap()
}

/// Standard output as text.
fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

/// Standard error as text.
fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

const FAST: [&str; 6] = ["--width", "12", "--height", "8", "--min-time", "0"];

/// Runs `args` with a tiny view, asserts success, and returns stdout.
fn run_fast(dir: &std::path::Path, args: &[&str]) -> String {
    let args: Vec<&str> = args.iter().chain(&FAST).copied().collect();
    let o = run(dir, &args);
    assert!(o.status.success(), "{}", stderr(&o));
    stdout(&o)
}

/// `studies peers default` with `args` and a tiny view in `dir`: its stdout
/// and its JSON report.
fn peers_on_default(dir: &std::path::Path, args: &[&str]) -> (String, Value) {
    let args: Vec<&str> = ["peers", "default", "--json", "p.json"]
        .iter()
        .chain(args)
        .copied()
        .collect();
    let text = run_fast(dir, &args);
    let report = serde_json::from_slice(&std::fs::read(dir.join("p.json")).unwrap()).unwrap();
    (text, report)
}

#[test]
fn peers_runs_our_accelerators_and_names_the_missing_peers() {
    let dir = tempfile::tempdir().unwrap();
    let (text, report) = peers_on_default(dir.path(), &["--build-rounds", "3", "--rounds", "4"]);
    for name in ["grid", "octree", "kdtree"] {
        assert!(text.lines().any(|l| l.starts_with(name)), "{name}: {text}");
    }
    if !cfg!(feature = "peers") {
        assert!(
            text.contains(
                "not built in: obvhs, parry3d, bvh (build studies with --features peers)"
            ),
            "{text}"
        );
    }
    if !cfg!(feature = "embree") {
        assert!(text.contains("--features embree"), "{text}");
    }
    assert_eq!(report["scene"], "default");
    let sets = report["sets"].as_array().unwrap();
    assert!(sets.iter().all(|s| s["reference"] == "grid"), "{report}");
    // Ours agree with each other exactly, on every set.
    for s in sets
        .iter()
        .filter(|s| ["grid", "octree", "kdtree"].contains(&s["name"].as_str().unwrap()))
    {
        assert_eq!(s["agreement"]["hit_miss"], 0, "{s}");
        assert_eq!(s["agreement"]["prim"], 0, "{s}");
        assert_eq!(s["agreement"]["t"], 0, "{s}");
        assert!(s["mrays"].as_f64().unwrap() > 0.0, "{s}");
    }
    // Every tool with bundle queries has a bundle figure per set, with the
    // same answers as its single rays (ours bit for bit: the same digest);
    // the peers without packets have none.
    for s in sets {
        let name = s["name"].as_str().unwrap();
        let bundles = s["bundles"].as_array().unwrap();
        let sizes: Vec<u64> = bundles
            .iter()
            .map(|b| b["rays_per_bundle"].as_u64().unwrap())
            .collect();
        let expected: &[u64] = match name {
            "grid" | "octree" | "kdtree" | "kdtree-fast" => &[64],
            "embree" | "embree-robust" => &[16, 8],
            _ => &[],
        };
        assert_eq!(sizes, expected, "{s}");
        for b in bundles {
            assert!(b["mrays"].as_f64().unwrap() > 0.0, "{s}");
            assert_eq!(b["agreement"]["rays"], s["agreement"]["rays"], "{s}");
            if expected == [64] {
                assert_eq!(b["digest"], s["digest"], "{s}");
                assert_eq!(b["agreement"]["hit_miss"], 0, "{s}");
            }
        }
    }
    let header = text
        .lines()
        .find(|l| l.starts_with("Mrays/s"))
        .unwrap_or_else(|| panic!("{text}"));
    assert_eq!(
        header.split_whitespace().collect::<Vec<_>>(),
        [
            "Mrays/s", "bundle", "primary", "bundled", "shadow", "bundled", "diffuse", "bundled"
        ],
        "{text}"
    );
    assert!(text.contains("grid x64 "), "{text}");
    let kinds: Vec<_> = report["ray_sets"]
        .as_array()
        .unwrap()
        .iter()
        .map(|k| k[0].as_str().unwrap().to_owned())
        .collect();
    assert_eq!(kinds, ["primary", "shadow", "diffuse"]);
    // Every figure timed in four interleaved rounds, each giving it at
    // least one pass.
    assert_eq!(report["rounds"], 4);
    for s in sets {
        assert!(s["passes"].as_u64().unwrap() >= 4, "{s}");
        for b in s["bundles"].as_array().unwrap() {
            assert!(b["passes"].as_u64().unwrap() >= 4, "{s}");
        }
    }
    // Every tool built three times; the figure is the middle round.
    assert_eq!(report["build_rounds"], 3);
    for b in report["builds"].as_array().unwrap() {
        let mut rounds: Vec<f64> = b["rounds_ms"]
            .as_array()
            .unwrap()
            .iter()
            .map(|r| r.as_f64().unwrap())
            .collect();
        assert_eq!(rounds.len(), 3, "{b}");
        rounds.sort_by(f64::total_cmp);
        assert_eq!(b["build_ms"].as_f64().unwrap(), rounds[1], "{b}");
    }
}

#[test]
fn peers_measures_only_the_tools_named() {
    let dir = tempfile::tempdir().unwrap();
    let (text, report) = peers_on_default(
        dir.path(),
        &["--tools", "octree,obvhs", "--build-rounds", "1"],
    );
    // The "name" of each entry of the report's array `key`.
    let names = |key: &str| -> Vec<String> {
        report[key]
            .as_array()
            .unwrap()
            .iter()
            .map(|e| e["name"].as_str().unwrap().to_owned())
            .collect()
    };
    let expected: &[&str] = if cfg!(feature = "peers") {
        &["octree", "obvhs"]
    } else {
        &["octree"]
    };
    assert_eq!(names("builds"), expected, "{text}");
    let sets = report["sets"].as_array().unwrap();
    assert_eq!(sets.len(), 3 * expected.len(), "{report}");
    assert!(sets.iter().all(|s| s["reference"] == "octree"), "{report}");
    // Only the named peers are reported as missing.
    let missing = names("unavailable");
    let expected_missing: &[&str] = if cfg!(feature = "peers") {
        &[]
    } else {
        &["obvhs"]
    };
    assert_eq!(missing, expected_missing, "{text}");
    // A name that is no tool is refused, naming the choices.
    let o = run(dir.path(), &["peers", "default", "--tools", "grid,nope"]);
    assert!(!o.status.success());
    let err = stderr(&o);
    assert!(err.contains("nope") && err.contains("kdtree"), "{err}");
}

#[test]
fn peers_refuses_a_round_count_out_of_range() {
    let dir = tempfile::tempdir().unwrap();
    for (flag, bad) in [
        ("--build-rounds", "0"),
        ("--build-rounds", "101"),
        ("--build-rounds", "-1"),
        ("--build-rounds", "many"),
        ("--rounds", "0"),
        ("--rounds", "1001"),
        ("--rounds", "-2"),
        ("--rounds", "few"),
    ] {
        let o = run(dir.path(), &["peers", "default", flag, bad]);
        assert!(!o.status.success(), "{flag} {bad} accepted");
        assert!(stderr(&o).contains(flag), "{flag} {bad}: {}", stderr(&o));
    }
}

#[test]
fn peers_skips_a_tool_whose_pass_would_take_too_long() {
    let dir = tempfile::tempdir().unwrap();
    let (text, report) = peers_on_default(
        dir.path(),
        &[
            "--tools",
            "grid,kdtree",
            "--build-rounds",
            "1",
            "--max-pass-time",
            "0",
        ],
    );
    // No pass takes no time: every tool is skipped on every set, and says so.
    let skipped = report["skipped"].as_array().unwrap();
    assert_eq!(skipped.len(), 6, "{report}");
    for kind in ["primary", "shadow", "diffuse"] {
        for tool in ["grid", "kdtree"] {
            assert!(
                text.contains(&format!("{tool}: skipped on {kind} rays")),
                "{tool} {kind}: {text}"
            );
        }
    }
    assert!(report["sets"].as_array().unwrap().is_empty(), "{report}");
}

#[test]
fn peers_traces_a_ray_file_and_chosen_kinds() {
    let dir = tempfile::tempdir().unwrap();
    // A ray file as `render bench --write-rays` writes it.
    let scene = render::scene::default_scene().unwrap();
    let rays: Vec<accel_core::Ray<f32>> = accel_scenes::random_rays(&scene.mesh.bounds(), 96, 7);
    std::fs::write(
        dir.path().join("r.rays"),
        accel_scenes::rayfile::encode(&rays),
    )
    .unwrap();
    let text = run_fast(dir.path(), &["peers", "default", "--rays", "r.rays"]);
    assert!(text.contains("rays (r.rays): file "), "{text}");
    let text = run_fast(dir.path(), &["peers", "default", "--kinds", "shadow"]);
    assert!(text.contains(": shadow "), "{text}");
    assert!(!text.contains("primary"), "{text}");
}
