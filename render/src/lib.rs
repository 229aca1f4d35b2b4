//! The workspace's shared binary, `render`: look at a scene through any
//! accelerator, see where it works hard, and measure it.
//!
//! - `render` with no arguments renders the embedded default scene
//!   ([`scene::default_scene`]: dense objects and sparse pillars on a huge
//!   floor) to `render.png` and prints build and trace statistics.
//! - `render SCENE.glb` renders a glTF file ([`accel_core::gltf_scene`]) or a
//!   built-in scene, with `--accel grid|octree|kdtree|brute|auto`, size,
//!   samples, precision; diffuse shading with a shadow ray to one light and
//!   ambient-occlusion rays ([`shade`]), traced in parallel tiles
//!   ([`tiles`]) with a progress bar.
//! - `--heatmap` also writes the traversal cost per pixel ([`heatmap`]).
//! - `render bench SCENE` measures build time, bytes and Mrays/s per
//!   accelerator and ray kind ([`mod@bench`]), and reads or writes the binary
//!   ray file of DESIGN.md ([`rayfile`]).
//!
//! - `render tradeoff SCENE|all` measures every speed-against-accuracy dial
//!   ([`tradeoff`]): precision, triangle test, spawn offset and structure
//!   quality, as throughput against mismatches, leaks and self-hits
//!   (table, CSV, PNG plot via [`plot`]).
//! - `render sweep-density` sweeps the grid density ([`sweep`]);
//!   `render choose-bench` checks `--accel auto` ([`choose`]) against the
//!   best accelerator per scene ([`choose_bench`]).
//! - `render peers SCENE` runs our accelerators and other libraries (obvhs,
//!   parry3d, the bvh crate, Embree 3; each behind a cargo feature) on the
//!   same scene and rays on one thread, and checks that they agree
//!   ([`peers`]).
//!
//! Bad input is refused with a one-line error and a non-zero exit; output
//! files are written whole or not at all ([`output`]). Every accelerator is
//! one entry in [`accel`]. The binary (`src/main.rs`) only parses the
//! command line ([`cli`]) and calls [`app`].

pub mod accel;
pub mod app;
pub mod bench;
pub mod choose;
pub mod choose_bench;
pub mod cli;
pub mod font;
pub mod heatmap;
pub mod output;
pub mod peers;
pub mod plot;
pub mod rayfile;
pub mod report;
pub mod scene;
pub mod shade;
pub mod shard;
pub mod sweep;
pub mod tiles;
pub mod tradeoff;
