//! The workspace's shared binary, `render`: look at a scene through any
//! accelerator, see where it works hard, and measure it.
//!
//! - `render` with no arguments renders the embedded default scene
//!   ([`scene::default_scene`]: dense objects and sparse pillars on a huge
//!   floor) to `render.png` and prints build and trace statistics.
//! - `render SCENE.glb` renders a glTF file ([`accel_scenes::gltf`]) or a
//!   built-in scene, with `--accel grid|octree|kdtree|brute|auto`, size,
//!   samples, precision; diffuse shading with a shadow ray to one light and
//!   ambient-occlusion rays ([`shade`]), traced in parallel tiles
//!   ([`tiles`]) with a progress bar, each through bundles of coherent
//!   rays ([`tile_shade`]). `--accel auto` asks
//!   [`accel::choose_with_probe`] with the render's own probe rays
//!   ([`probe`]).
//! - `--heatmap` also writes the traversal cost per pixel ([`heatmap`]).
//! - `render bench SCENE` measures build time, bytes and Mrays/s per
//!   accelerator and ray kind ([`mod@bench`]), and reads or writes the binary
//!   ray file of DESIGN.md ([`accel_scenes::rayfile`]).
//!
//! - `render --shard I/N` renders one shard of the image for a job array,
//!   `render bench --hits` writes the nearest hits of a ray file (or of one
//!   shard's slice), and `render merge` joins the parts ([`shard`] for the
//!   format and checks, [`part_io`] for what each command writes).
//!
//! The studies (`tradeoff`, `sweep-density`, `choose-bench`, `peers`) are
//! the `studies` crate's binary, built on this library's scenes, ray sets
//! and output files.
//!
//! Bad input is refused with a one-line error and a non-zero exit
//! ([`report`]); output files are written whole or not at all
//! ([`output`]). The binary (`src/main.rs`) only parses the command line
//! ([`cli`]) and calls [`app`].

pub mod app;
pub mod bench;
pub mod cli;
pub mod font;
pub mod heatmap;
pub mod output;
pub mod part_io;
pub mod probe;
pub mod report;
pub mod scene;
pub mod shade;
pub mod shard;
pub mod tile_shade;
pub mod tiles;
