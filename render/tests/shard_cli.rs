//! Sharded renders and ray batches (issue 31): processes that each run one
//! shard, and `render merge`, which must give back byte for byte what one
//! process writes, or refuse, writing nothing.

mod common;

use common::{Gltf, assert_refused, entries, render, run, stdout};
use std::path::Path;
use std::process::Output;

const SMALL: [&str; 8] = ["--width", "48", "--height", "40", "--spp", "1", "--ao", "2"];

/// Runs shards `0..n` of `args` as `n` processes at once, each writing
/// `part-I.part` in `dir`; `env` names the index variable to use with
/// `--shards`, or `None` for `--shard I/N`.
fn run_shards(dir: &Path, args: &[&str], n: u32, env: Option<&str>) -> Vec<String> {
    let children: Vec<_> = (0..n)
        .map(|i| {
            let out = format!("part-{i}.part");
            let mut cmd = std::process::Command::new(env!("CARGO_BIN_EXE_render"));
            cmd.current_dir(dir).args(args).args(["--out", &out]);
            cmd.env_remove("JOB_COMPLETION_INDEX")
                .env_remove("SLURM_ARRAY_TASK_ID");
            match env {
                Some(var) => cmd
                    .env(var, i.to_string())
                    .args(["--shards", &n.to_string()]),
                None => cmd.args(["--shard", &format!("{i}/{n}")]),
            };
            (out, cmd.output_spawned())
        })
        .collect();
    children
        .into_iter()
        .map(|(out, child)| {
            let o = child.wait_with_output().unwrap();
            assert!(o.status.success(), "{out}: {}", common::stderr(&o));
            out
        })
        .collect()
}

/// Spawning without waiting, so that the shards run side by side.
trait SpawnOutput {
    fn output_spawned(&mut self) -> std::process::Child;
}

impl SpawnOutput for std::process::Command {
    fn output_spawned(&mut self) -> std::process::Child {
        self.stdout(std::process::Stdio::piped())
            .stderr(std::process::Stdio::piped())
            .spawn()
            .unwrap()
    }
}

fn merge(dir: &Path, parts: &[&str], out: &str) -> Output {
    let mut args = vec!["merge"];
    args.extend(parts);
    args.extend(["--out", out]);
    run(dir, &args)
}

fn whole_render(dir: &Path, args: &[&str], out: &str) -> Vec<u8> {
    let mut a = args.to_vec();
    a.extend(["--out", out]);
    let o = run(dir, &a);
    assert!(o.status.success(), "{}", common::stderr(&o));
    std::fs::read(dir.join(out)).unwrap()
}

#[test]
fn shards_of_the_default_scene_merge_into_the_one_process_image() {
    let dir = tempfile::tempdir().unwrap();
    let mut args = vec!["--accel", "kdtree"];
    args.extend(SMALL);
    let whole = whole_render(dir.path(), &args, "whole.png");
    // 3 shards by --shard, 4 by Slurm's variable, 5 by Kubernetes'.
    for (n, env) in [
        (3, None),
        (4, Some("SLURM_ARRAY_TASK_ID")),
        (5, Some("JOB_COMPLETION_INDEX")),
    ] {
        let sub = dir.path().join(format!("n{n}"));
        std::fs::create_dir(&sub).unwrap();
        let mut parts = run_shards(&sub, &args, n, env);
        parts.reverse(); // any order
        let refs: Vec<&str> = parts.iter().map(String::as_str).collect();
        let o = merge(&sub, &refs, "merged.png");
        assert!(o.status.success(), "{}", common::stderr(&o));
        assert!(stdout(&o).contains(&format!("merged {n} shards")));
        let merged = std::fs::read(sub.join("merged.png")).unwrap();
        assert!(merged == whole, "{n} shards: other bytes than one process");
    }
}

#[test]
fn shards_of_a_gltf_merge_into_the_one_process_image() {
    let dir = tempfile::tempdir().unwrap();
    // A pyramid on a square base, framed by render (the file has no camera).
    let positions = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [1.0, 0.0, 1.0],
        [0.0, 0.0, 1.0],
        [0.5, 0.8, 0.5],
    ];
    let indices = [0u16, 1, 2, 0, 2, 3, 0, 1, 4, 1, 2, 4, 2, 3, 4, 3, 0, 4];
    let file = Gltf {
        positions: &positions,
        indices: Some(&indices),
        mode: 4,
        nodes: r#"[{"children":[1]},{"mesh":0}]"#,
        extra: "",
    }
    .write(dir.path(), "pyramid.gltf");
    let scene = file.to_str().unwrap();
    let mut args = vec![scene, "--accel", "grid", "--precision", "f64"];
    args.extend(SMALL);
    let whole = whole_render(dir.path(), &args, "whole.png");
    let parts = run_shards(dir.path(), &args, 2, Some("JOB_COMPLETION_INDEX"));
    let refs: Vec<&str> = parts.iter().map(String::as_str).collect();
    let o = merge(dir.path(), &refs, "merged.png");
    assert!(o.status.success(), "{}", common::stderr(&o));
    assert!(std::fs::read(dir.path().join("merged.png")).unwrap() == whole);
}

#[test]
fn missing_doubled_foreign_and_damaged_parts_are_refused_and_nothing_is_written() {
    let dir = tempfile::tempdir().unwrap();
    let mut args = vec!["--accel", "kdtree"];
    args.extend(SMALL);
    run_shards(dir.path(), &args, 3, None);
    // Shard 2 of the same image with another sample count: another job.
    let mut other = vec!["--accel", "kdtree", "--width", "48", "--height", "40"];
    other.extend([
        "--spp",
        "2",
        "--ao",
        "2",
        "--shard",
        "2/3",
        "--out",
        "other-2.part",
    ]);
    assert!(run(dir.path(), &other).status.success());
    let mut damaged = std::fs::read(dir.path().join("part-1.part")).unwrap();
    *damaged.last_mut().unwrap() ^= 0x40;
    std::fs::write(dir.path().join("damaged-1.part"), damaged).unwrap();
    let before = entries(dir.path());
    let cases: [(&[&str], &[&str]); 5] = [
        (
            &["part-0.part", "part-2.part"],
            &["1 of 3 shards missing: 1"],
        ),
        (
            &["part-0.part", "part-1.part", "part-1.part", "part-2.part"],
            &["shard 1/3 is given twice"],
        ),
        (
            &["part-0.part", "part-1.part", "other-2.part"],
            &["other-2.part belongs to another job", "spp: 2", "spp: 1"],
        ),
        (
            &["part-0.part", "damaged-1.part", "part-2.part"],
            &["damaged-1.part", "damaged"],
        ),
        (&["part-0.part", "whole.png"], &["whole.png", "cannot read"]),
    ];
    for (parts, needles) in cases {
        let o = merge(dir.path(), parts, "merged.png");
        assert_refused(&o, needles);
        assert_eq!(entries(dir.path()), before, "{parts:?} left a file");
    }
    // A shard must write a part file, and no heat map.
    let mut bad = args.clone();
    bad.extend(["--shard", "0/3", "--out", "x.png"]);
    assert_refused(&run(dir.path(), &bad), &["--shard 0/3", "NAME.part"]);
    let mut bad = args.clone();
    bad.extend(["--shard", "0/3", "--out", "x.part", "--heatmap"]);
    assert_refused(&run(dir.path(), &bad), &["--heatmap"]);
    for spec in ["3/3", "1/0", "x"] {
        let mut bad = args.clone();
        bad.extend(["--shard", spec, "--out", "x.part"]);
        assert_refused(&run(dir.path(), &bad), &["--shard"]);
    }
    let mut bad = args.clone();
    bad.extend(["--shards", "3", "--out", "x.part"]);
    let o = render()
        .current_dir(dir.path())
        .args(&bad)
        .env_remove("JOB_COMPLETION_INDEX")
        .env_remove("SLURM_ARRAY_TASK_ID")
        .output()
        .unwrap();
    assert_refused(&o, &["no shard index", "SLURM_ARRAY_TASK_ID"]);
    assert_eq!(entries(dir.path()), before);
}

#[test]
fn sharded_hits_of_a_ray_file_merge_in_ray_order() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let gen_args = [
        "bench",
        "default",
        "--width",
        "24",
        "--height",
        "16",
        "--accel",
        "grid",
        "--min-time",
        "0.001",
        "--write-rays",
        "rays.bin",
    ];
    assert!(run(d, &gen_args).status.success());
    let bench = |extra: &[&str]| {
        let mut a = vec![
            "bench",
            "default",
            "--rays",
            "rays.bin",
            "--min-time",
            "0.001",
        ];
        a.extend(extra);
        let o = run(d, &a);
        assert!(o.status.success(), "{}", common::stderr(&o));
    };
    bench(&["--accel", "kdtree", "--hits", "all.hits"]);
    for i in 0..3 {
        let shard = format!("{i}/3");
        let out = format!("h{i}.part");
        bench(&["--accel", "grid", "--shard", &shard, "--hits", &out]);
    }
    let o = merge(d, &["h2.part", "h0.part", "h1.part"], "merged.hits");
    assert!(o.status.success(), "{}", common::stderr(&o));
    let all = std::fs::read(d.join("all.hits")).unwrap();
    let merged = std::fs::read(d.join("merged.hits")).unwrap();
    // The header counts the file's rays (16-byte header, 16 bytes a ray),
    // and the grid's shards found the kD-tree's hits, ray for ray.
    let rays = std::fs::read(d.join("rays.bin")).unwrap();
    let count = u64::from_le_bytes(rays[8..16].try_into().unwrap());
    assert_eq!(&all[..8], b"ACCHITS1");
    assert_eq!(all.len() as u64, 16 + 16 * count);
    assert!(merged == all, "the merged hits differ from one process's");
    let hits = all[16..]
        .chunks(16)
        .filter(|r| r[..4] != u32::MAX.to_le_bytes())
        .count();
    assert!(hits > 0 && (hits as u64) < count, "{hits} of {count} hit");
    // Parts of the kD-tree and of the grid are different jobs.
    bench(&["--accel", "kdtree", "--shard", "1/3", "--hits", "k1.part"]);
    assert_refused(
        &merge(d, &["h0.part", "k1.part", "h2.part"], "x.hits"),
        &["belongs to another job", "accel"],
    );
}
