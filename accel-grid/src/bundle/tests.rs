//! The two ways a slice marks which members meet which full cells agree;
//! a packet too spread to walk whole walks its coherent runs; the two ways
//! a cell's triangles are tested give the same answers.

use super::part::PartCells;
use super::*;
use crate::Grid;
use accel_core::{Accelerator, TriangleMesh, Vec3};
use accel_scenes::generated::{SplitMix64, random_soup};

/// Fans of 64 rays through a dense soup: in every slice of the main axis,
/// [`Packet::spread`] (cell ranges from each rectangle) marks exactly the
/// members that [`Packet::cull`] (each rectangle against each full cell's
/// closed box) marks, on every full cell, and both drop the same members
/// past the slice. Either one decides the cells a ray is tested in, so a
/// cell one of them left out would lose hits.
#[test]
fn spread_and_cull_mark_the_same_members() {
    let mesh: TriangleMesh<f32> = random_soup(20_000, 7).cast().unwrap();
    let grid = Grid::new(&mesh).unwrap();
    let part = &grid.first;
    let cells = PartCells::<f32, _, false> { part, prims: &mesh };
    let geom = &part.geometry;
    let mut rng = SplitMix64::new(11);
    let (mut marked, mut slices) = (0usize, 0usize);
    for _ in 0..24 {
        let origin = Vec3::splat(0.5) + rng.unit_vector() * rng.range(0.3, 3.0);
        let aim = Vec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64()) - origin;
        let spread = rng.range(0.002, 0.04);
        let rays: Vec<Ray<f32>> = (0..64)
            .map(|i| {
                let (di, dj) = ((i % 8) as f64 - 3.5, (i / 8) as f64 - 3.5);
                let d = aim + Vec3::new(spread * di, spread * dj, spread * (di + dj));
                Ray::new(origin, d).unwrap().cast()
            })
            .collect();
        let Some(packet) = Packet::form(&rays, geom.bounds(), |_, _| {}) else {
            continue;
        };
        let all = u64::MAX >> (64 - packet.members.len());
        let lines = Lines::of(&packet.members, all, packet.pivot).unwrap();
        let k = packet.axes[0];
        let xs = geom.boundaries(k);
        let mut scratch = Scratch::default();
        let mut spread_marks = Vec::new();
        for i in 0..geom.resolution()[k] {
            let (x_lo, x_hi) = (xs[i as usize], xs[i as usize + 1]);
            let window = Window::under(geom, packet.axes, &lines.hull(x_lo, x_hi));
            full_cells(&cells, packet.axes, i, window, &mut scratch.cells);
            let by_spread = packet.spread(all, geom, x_lo, x_hi, window, &mut spread_marks);
            let by_cull = packet.cull(all, geom, x_lo, x_hi, window, &mut scratch);
            assert_eq!(by_spread, by_cull, "members still live after slice {i}");
            for &(cell, place, _) in &scratch.cells {
                assert_eq!(
                    spread_marks[place], scratch.meeting[place],
                    "members marked on cell {cell} of slice {i}"
                );
                marked += scratch.meeting[place].count_ones() as usize;
            }
            slices += usize::from(!scratch.cells.is_empty());
        }
    }
    assert!(
        slices > 100 && marked > 10_000,
        "{slices} slices, {marked} marks"
    );
}

/// A packet whose rays spread over the whole grid, in four runs of
/// [`SUB_PACKET`] rays that each stay together (the 4 × 4 blocks of a tile
/// in Z order), is walked run by run rather than one ray at a time, and
/// each ray still gets its single walk's nearest hit.
#[test]
fn a_spread_packet_walks_its_coherent_runs() {
    let mesh: TriangleMesh<f32> = random_soup(20_000, 7).cast().unwrap();
    let grid = Grid::new(&mesh).unwrap();
    let part = &grid.first;
    let cells = PartCells::<f32, _, false> { part, prims: &mesh };
    let origin = Vec3::new(0.5, 0.5, -2.0);
    let rays: Vec<Ray<f32>> = (0..4 * SUB_PACKET)
        .map(|i| {
            let (run, j) = (i / SUB_PACKET, i % SUB_PACKET);
            let corner = |r: usize| 0.2 + 0.6 * r as f64;
            let aim = Vec3::new(corner(run % 2), corner(run / 2), 1.0);
            let fan = Vec3::new(1e-3 * (j % 4) as f64, 1e-3 * (j / 4) as f64, 0.0);
            Ray::new(origin, aim - origin + fan).unwrap().cast()
        })
        .collect();
    let mut packet = Packet::form(&rays, part.geometry.bounds(), |_, _| {}).unwrap();
    assert_eq!(packet.members.len(), rays.len());
    assert!(!coherent(&packet.members, &part.geometry, packet.axes));
    assert_eq!(packet.walk_coherent(&cells), u64::MAX, "every run walked");
    let mut hits = 0;
    for m in &packet.members {
        let single = grid.intersect(&rays[m.slot]).unwrap();
        assert_eq!(m.best, single, "ray {}", m.slot);
        hits += usize::from(single.is_some());
    }
    assert!(hits > 32, "{hits} rays hit the soup");
}

/// A coherent packet of 64 rays through a dense soup gets its single
/// walks' answers, nearest and any hit, whether its cells are tested
/// triangle by triangle with the quads' first stage (where the CPU has
/// AVX2) or member by member (the quads taken away); members past the 32nd
/// too.
#[test]
fn cells_tested_by_triangles_or_by_members_give_the_single_answers() {
    let mesh: TriangleMesh<f32> = random_soup(20_000, 7).cast().unwrap();
    let grid = Grid::new(&mesh).unwrap();
    let part = &grid.first;
    let origin = Vec3::new(0.45, 0.55, -2.0);
    let rays: Vec<Ray<f32>> = (0..PACKET)
        .map(|i| {
            let fan = Vec3::new(4e-3 * (i % 8) as f64, 4e-3 * (i / 8) as f64, 0.0);
            Ray::new(origin, Vec3::new(0.5, 0.5, 0.5) - origin + fan)
                .unwrap()
                .cast()
        })
        .collect();
    let form = |by_triangles: bool| {
        let mut packet = Packet::form(&rays, part.geometry.bounds(), |_, _| {}).unwrap();
        assert_eq!(packet.members.len(), PACKET);
        assert!(coherent(&packet.members, &part.geometry, packet.axes));
        if simd_level() >= SimdLevel::Avx2 {
            assert!(packet.quads.iter().all(Option::is_some), "one axis order");
        }
        if !by_triangles {
            packet.quads.clear();
        }
        packet
    };
    let mut hits = 0;
    for by_triangles in [true, false] {
        let mut nearest = form(by_triangles);
        nearest.walk(&PartCells::<f32, _, false> { part, prims: &mesh }, u64::MAX);
        let mut any = form(by_triangles);
        any.walk(&PartCells::<f32, _, true> { part, prims: &mesh }, u64::MAX);
        for (i, m) in nearest.members.iter().enumerate() {
            let single = grid.intersect(&rays[m.slot]).unwrap();
            assert_eq!(
                m.best, single,
                "ray {} by triangles: {by_triangles}",
                m.slot
            );
            let occluded = any.finished & (1 << i) != 0;
            assert_eq!(occluded, single.is_some(), "ray {} occluded", m.slot);
            hits += usize::from(single.is_some());
        }
    }
    assert!(hits > 2 * 48, "{hits} hits over both ways");
}
