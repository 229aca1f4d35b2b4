//! What the triangle tests of camera rays have in common, for judging SIMD
//! over a cell's triangles and packets of rays (performance log,
//! 2026-12-04 21:17).
//!
//! Each ray walks the grid (`BeamWalk`, without the empty blocks) up to its
//! nearest hit, as `Grid::intersect` does, and tests the triangles of the
//! cells it opens, each once. Printed: per ray, the cells and triangles; per
//! cell where a ray tests something, how many (what 4- or 8-wide tests of a
//! cell's triangles would batch); and per tile of rays, the union of the
//! tile's cells and triangles (what a packet that tests every triangle
//! against all its rays would open and test).
//!
//! Usage: `ray_sharing [SCENE]`, SCENE a generated scene's name (default
//! sphere_100k) or a glTF file, framed from `Camera::DEFAULT_SIDE`;
//! 512×512 camera rays.

use accel_core::{Accelerator, Ray, TraversalRay};
use accel_grid::Grid;
use accel_grid::dda::{BeamWalk, Step};
use accel_scenes::gltf;
use accel_scenes::{Camera, GeneratedScene};
use std::collections::HashSet;

/// Side of the camera image, in rays.
const SIDE: u32 = 512;

/// The most tests in one cell the histogram tells apart.
const MOST: usize = 16;

fn main() {
    let name = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "sphere_100k".to_owned());
    let (mesh, camera) = if let Some(scene) = GeneratedScene::from_name(&name) {
        (scene.mesh(), scene.camera())
    } else {
        let mesh = gltf::load(std::path::Path::new(&name))
            .unwrap_or_else(|e| {
                eprintln!("{name}: {e}");
                std::process::exit(2);
            })
            .mesh;
        let camera = Camera::frame(&mesh.bounds(), Camera::DEFAULT_SIDE, accel_scenes::Z_UP);
        (mesh, camera)
    };
    let mesh = mesh.cast::<f32>().expect("the scene fits f32");
    let grid = Grid::new(&mesh).expect("grid builds");
    let rays = camera.rays::<f32>(SIDE, SIDE);
    let walks: Vec<RayWork> = rays.iter().map(|r| ray_work(&grid, r)).collect();

    let n = walks.len() as f64;
    let cells: usize = walks.iter().map(|w| w.cells.len()).sum();
    let tests: usize = walks.iter().map(|w| w.triangles.len()).sum();
    let mut per_cell = [0usize; MOST + 1];
    for w in &walks {
        for &k in &w.tests_per_cell {
            per_cell[k.min(MOST)] += 1;
        }
    }
    let cells_with_tests: usize = per_cell[1..].iter().sum();
    let share_from = |least: usize| {
        let from: usize = (least..=MOST).map(|k| k * per_cell[k]).sum();
        100.0 * from as f64 / tests as f64
    };
    println!(
        "{name}: {} triangles, {} camera rays; per ray {:.1} cells, {:.2} triangle tests",
        mesh.triangle_count(),
        walks.len(),
        cells as f64 / n,
        tests as f64 / n
    );
    println!(
        "cells where a ray tests: {:.2} per ray, {:.2} tests each; tests in cells of >= 4: {:.0}%, >= 8: {:.0}%",
        cells_with_tests as f64 / n,
        tests as f64 / cells_with_tests as f64,
        share_from(4),
        share_from(8)
    );
    for tile in [4, 8] {
        let (tile_cells, tile_triangles, tiles) = tile_unions(&walks, tile);
        let per_ray = f64::from(tile * tile);
        println!(
            "{tile}x{tile} tiles: {:.1} cells, {:.1} triangles each; per ray {:.1}x fewer cells, \
             {:.2} tests 8 rays at a time per test alone",
            tile_cells / tiles,
            tile_triangles / tiles,
            (cells as f64 / n) / (tile_cells / tiles / per_ray),
            (tile_triangles / tiles / 8.0) / (tests as f64 / n)
        );
    }
}

/// What one ray's walk opens and tests.
struct RayWork {
    /// The cells it opens (linear indices).
    cells: HashSet<usize>,
    /// The triangles it tests, each once.
    triangles: HashSet<u32>,
    /// For each cell it opens, the triangles first tested there.
    tests_per_cell: Vec<usize>,
}

/// The walk of `ray` through `grid` up to its nearest hit (the limit the
/// grid's own query stops at), and the triangles of the cells it opens.
fn ray_work(grid: &Grid<'_, f32, accel_core::TriangleMesh<f32>>, ray: &Ray<f32>) -> RayWork {
    let mut work = RayWork {
        cells: HashSet::new(),
        triangles: HashSet::new(),
        tests_per_cell: Vec::new(),
    };
    let geometry = grid.geometry();
    let Some(tr) = TraversalRay::new(ray, geometry.bounds()) else {
        return work;
    };
    let best = grid.intersect(ray).expect("a valid camera ray");
    let limit = best.map_or(tr.t_end, |b| tr.t_end.min(b.t + tr.t_tol));
    let mut open = |c: usize| {
        if work.cells.insert(c) {
            let first = grid
                .cells()
                .cell(c)
                .iter()
                .filter(|&&p| work.triangles.insert(p))
                .count();
            work.tests_per_cell.push(first);
        }
    };
    let (mut walk, start) = BeamWalk::start(geometry, &tr, tr.t_start);
    let mut step = Step::Cells(start);
    loop {
        match step {
            Step::End => break,
            Step::Cell(c) => open(geometry.linear_index(c)),
            Step::Cells(b) => geometry.for_each_cell_index(&b, &mut open),
        }
        step = walk.step(limit);
    }
    work
}

/// The unions of each `tile`×`tile` tile's cells and triangles, summed over
/// the tiles of the image: (cells, triangles, number of tiles).
fn tile_unions(walks: &[RayWork], tile: u32) -> (f64, f64, f64) {
    let (mut cells, mut triangles, mut tiles) = (0usize, 0usize, 0usize);
    for ty in (0..SIDE).step_by(tile as usize) {
        for tx in (0..SIDE).step_by(tile as usize) {
            let mut tile_cells = HashSet::new();
            let mut tile_triangles = HashSet::new();
            for y in ty..ty + tile {
                for x in tx..tx + tile {
                    let w = &walks[(y * SIDE + x) as usize];
                    tile_cells.extend(w.cells.iter().copied());
                    tile_triangles.extend(w.triangles.iter().copied());
                }
            }
            cells += tile_cells.len();
            triangles += tile_triangles.len();
            tiles += 1;
        }
    }
    (cells as f64, triangles as f64, tiles as f64)
}
