//! Helpers shared by the end-to-end tests: running the binary, and writing
//! small glTF files.

#![allow(dead_code)] // each test binary uses a different part

use assert_cmd::Command;
use std::path::{Path, PathBuf};
use std::process::Output;

/// The `render` binary.
pub fn render() -> Command {
    assert_cmd::cargo::cargo_bin_cmd!("render")
}

/// Runs `render` with `args` in `dir`.
pub fn run(dir: &Path, args: &[&str]) -> Output {
    render().current_dir(dir).args(args).output().unwrap()
}

/// Standard output as text.
pub fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

/// Standard error as text.
pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// The line of `text` starting with `prefix`.
pub fn line<'a>(text: &'a str, prefix: &str) -> &'a str {
    text.lines()
        .find(|l| l.starts_with(prefix))
        .unwrap_or_else(|| panic!("no line starting with {prefix:?} in:\n{text}"))
}

/// Asserts a clean refusal: a non-zero exit, one line on stderr starting
/// with `render: error:` and containing every one of `needles`, no panic.
pub fn assert_refused(o: &Output, needles: &[&str]) {
    let err = stderr(o);
    assert!(!o.status.success(), "succeeded; stderr: {err}");
    assert!(!err.contains("panicked"), "panicked: {err}");
    assert_eq!(err.trim_end().lines().count(), 1, "not one line: {err}");
    assert!(err.starts_with("render: error: "), "{err}");
    for n in needles {
        assert!(err.contains(n), "{n:?} not in: {err}");
    }
}

/// The names in a directory, sorted.
pub fn entries(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

/// Standard base64, for `data:` URIs.
pub fn base64(bytes: &[u8]) -> String {
    const A: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut s = String::new();
    for c in bytes.chunks(3) {
        let b = |i: usize| u32::from(c.get(i).copied().unwrap_or(0));
        let n = (b(0) << 16) | (b(1) << 8) | b(2);
        for i in 0..4 {
            if i <= c.len() {
                s.push(A[(n >> (18 - 6 * i)) as usize & 63] as char);
            } else {
                s.push('=');
            }
        }
    }
    s
}

/// A small glTF: one mesh of `positions` (f32) with optional `u16` indices
/// and a primitive `mode`, placed by the JSON `nodes` (node 0 is the root);
/// `extra` is spliced into the top-level object (cameras, ...).
pub struct Gltf<'a> {
    /// Vertex positions.
    pub positions: &'a [[f32; 3]],
    /// Triangle indices, if indexed.
    pub indices: Option<&'a [u16]>,
    /// glTF primitive mode (4 = TRIANGLES).
    pub mode: u32,
    /// The `nodes` array, as JSON.
    pub nodes: &'a str,
    /// More top-level members, as JSON (`"cameras":[...]`), or empty.
    pub extra: &'a str,
}

impl Gltf<'_> {
    /// Writes the file as `dir/name` and returns its path.
    pub fn write(&self, dir: &Path, name: &str) -> PathBuf {
        let mut data: Vec<u8> = self
            .positions
            .iter()
            .flatten()
            .flat_map(|v| v.to_le_bytes())
            .collect();
        let pos_len = data.len();
        let finite = self.positions.iter().flatten().filter(|v| v.is_finite());
        let lo = finite.clone().fold(f32::INFINITY, |a, &b| a.min(b));
        let hi = finite.fold(f32::NEG_INFINITY, |a, &b| a.max(b));
        let (lo, hi) = if lo <= hi { (lo, hi) } else { (0.0, 0.0) };
        let mut views = format!(r#"{{"buffer":0,"byteLength":{pos_len}}}"#);
        let mut accessors = format!(
            r#"{{"bufferView":0,"componentType":5126,"count":{},"type":"VEC3","min":[{lo},{lo},{lo}],"max":[{hi},{hi},{hi}]}}"#,
            self.positions.len()
        );
        let mut indices = String::new();
        if let Some(ix) = self.indices {
            data.extend(ix.iter().flat_map(|i| i.to_le_bytes()));
            views += &format!(
                r#",{{"buffer":0,"byteOffset":{pos_len},"byteLength":{}}}"#,
                2 * ix.len()
            );
            accessors += &format!(
                r#",{{"bufferView":1,"componentType":5123,"count":{},"type":"SCALAR"}}"#,
                ix.len()
            );
            indices = r#","indices":1"#.to_owned();
        }
        let extra = if self.extra.is_empty() {
            String::new()
        } else {
            format!(",{}", self.extra)
        };
        let json = format!(
            r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],
"buffers":[{{"byteLength":{},"uri":"data:application/octet-stream;base64,{}"}}],
"bufferViews":[{views}],"accessors":[{accessors}],
"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}}{indices},"mode":{}}}]}}],
"nodes":{}{extra}}}"#,
            data.len(),
            base64(&data),
            self.mode,
            self.nodes
        );
        let path = dir.join(name);
        std::fs::write(&path, json).unwrap();
        path
    }
}

/// Two triangles of a unit square in the z = 0 plane.
pub const SQUARE: [[f32; 3]; 4] = [
    [0.0, 0.0, 0.0],
    [1.0, 0.0, 0.0],
    [0.0, 1.0, 0.0],
    [1.0, 1.0, 0.0],
];

/// The square's triangles.
pub const SQUARE_INDICES: [u16; 6] = [0, 1, 2, 2, 1, 3];
