//! Large primitives apart: a small dense part in a large sparse scene.
//!
//! In a teapot in a stadium, the stadium's walls and floor cross every
//! plane and every cell around the teapot. A kD-tree's SAH finds no empty cut
//! there, prices halving the teapot as it prices isolating it and cuts
//! through it at the root; an octree's root cells hold pieces of both. Rays
//! near the teapot then walk a deep shell of nodes or cells that keep pieces
//! of the walls (on the 100k-triangle sphere in a 10⁴ box, the kD-tree's
//! floor rays visited 29.9 nodes and its sphere rays 62.2; built apart, 13.8
//! and 48.2).
//!
//! So a build first sorts out the *large* primitives, whose bounds span at
//! least 1/[`ISOLATION`] of the scene's largest side. When the others are at
//! least [`ISOLATION`] times as many and their bounds are at most
//! 1/[`ISOLATION`] of the scene's extent on every axis, each group gets a
//! structure of its own, and a query walks both (the small part's first,
//! then the large part's with the best hit so far). Anywhere else the scene
//! stays one part: dense scenes, scans and terrains have no large
//! primitives, and a room whose furniture fills it has no small part.

use crate::{Aabb, Real};
use rayon::prelude::*;

/// How much narrower than the scene a small part must be, on every axis,
/// and how many times as many primitives as the large part it must hold
/// (the kD-tree's depth rule uses the same factor for the cuts that isolate
/// a dense part).
pub const ISOLATION: u32 = 16;

/// The primitives of one part (ascending) and the bounds of their boxes.
#[derive(Clone, Debug, PartialEq)]
pub struct Group<T> {
    /// The primitives' indices, ascending.
    pub prims: Vec<u32>,
    /// The union of their boxes.
    pub bounds: Aabb<T>,
}

/// Whether a primitive with bounds `b` is large in a scene whose largest
/// side is `scene_side`: its bounds span at least 1/[`ISOLATION`] of it
/// along some axis.
#[inline]
#[must_use]
pub fn is_large<T: Real>(b: &Aabb<T>, scene_side: T) -> bool {
    (b.max - b.min).max_component() * T::from_f64(f64::from(ISOLATION)) >= scene_side
}

/// The parts of a scene whose primitives have the boxes `boxes` and the
/// bounds `bounds`: the small primitives, then the large ones, when the
/// scene splits; all of them otherwise.
#[must_use]
pub fn partition<T: Real>(boxes: &[Aabb<T>], bounds: &Aabb<T>) -> Vec<Group<T>> {
    let all = || {
        vec![Group {
            prims: (0..boxes.len() as u32).collect(),
            bounds: *bounds,
        }]
    };
    if boxes.is_empty() || bounds.is_empty() {
        return all();
    }
    let factor = T::from_f64(f64::from(ISOLATION));
    let extent = bounds.max - bounds.min;
    let largest = extent.max_component();
    // Whether the scene splits, from a count and a union alone: nearly
    // every scene stays one part, and lists made for nothing cost the 1M
    // terrain's kD-tree build 8 ms on one thread.
    let (large_count, small_bounds) = boxes
        .par_chunks(CHUNK)
        .map(|chunk| {
            chunk.iter().fold((0usize, Aabb::empty()), |(n, u), b| {
                if is_large(b, largest) {
                    (n + 1, u)
                } else {
                    (n, u.union(b))
                }
            })
        })
        .reduce(|| (0, Aabb::empty()), |a, b| (a.0 + b.0, a.1.union(&b.1)));
    let small_count = boxes.len() - large_count;
    let narrow = (0..3).all(|a| (small_bounds.max[a] - small_bounds.min[a]) * factor <= extent[a]);
    let many = small_count >= large_count.saturating_mul(ISOLATION as usize);
    if large_count == 0 || small_count == 0 || !narrow || !many {
        return all();
    }
    let group = |count| Group {
        prims: Vec::with_capacity(count),
        bounds: Aabb::empty(),
    };
    let (mut small, mut large) = (group(small_count), group(large_count));
    for (i, b) in boxes.iter().enumerate() {
        let group = if is_large(b, largest) {
            &mut large
        } else {
            &mut small
        };
        group.prims.push(i as u32);
        group.bounds.merge(b);
    }
    vec![small, large]
}

/// Boxes per task of the check whether a scene splits.
const CHUNK: usize = 1 << 14;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Vec3;

    fn cube(c: f64, h: f64) -> Aabb<f64> {
        Aabb::new(Vec3::splat(c - h), Vec3::splat(c + h))
    }

    /// A wall of the ±100 box, flat at `x`.
    fn wall(x: f64) -> Aabb<f64> {
        Aabb::new(Vec3::new(x, -100.0, -100.0), Vec3::new(x, 100.0, 100.0))
    }

    /// The prims of each part of the boxes' scene.
    fn parts_of(boxes: &[Aabb<f64>]) -> Vec<Vec<u32>> {
        let bounds = boxes.iter().fold(Aabb::empty(), |u, b| u.union(b));
        partition(boxes, &bounds)
            .into_iter()
            .map(|g| g.prims)
            .collect()
    }

    #[test]
    fn a_small_cluster_in_a_large_box_is_built_apart() {
        // 32 small boxes near the origin, two walls of the ±100 box.
        let mut boxes: Vec<Aabb<f64>> = (0..32).map(|i| cube(f64::from(i) * 0.01, 0.1)).collect();
        boxes.extend([wall(-100.0), wall(100.0)]);
        let bounds = boxes.iter().fold(Aabb::empty(), |u, b| u.union(b));
        let parts = partition(&boxes, &bounds);
        assert_eq!(
            parts.iter().map(|g| g.prims.clone()).collect::<Vec<_>>(),
            vec![(0..32).collect::<Vec<u32>>(), vec![32, 33]]
        );
        // Each part's bounds are its own boxes'.
        assert_eq!(
            parts[0].bounds,
            boxes[..32].iter().fold(Aabb::empty(), |u, b| u.union(b))
        );
        assert_eq!(parts[1].bounds, bounds);
    }

    #[test]
    fn a_cluster_checked_by_several_tasks_is_built_apart_with_its_bounds() {
        // More small boxes than one task of the check takes, the walls in
        // the middle of the list.
        let n = 3 * CHUNK + 5;
        let mut boxes: Vec<Aabb<f64>> = (0..n)
            .map(|i| cube((i % 1000) as f64 * 1e-3, 0.01))
            .collect();
        boxes.insert(CHUNK + 1, wall(-100.0));
        boxes.insert(2 * CHUNK + 7, wall(100.0));
        let bounds = boxes.iter().fold(Aabb::empty(), |u, b| u.union(b));
        let parts = partition(&boxes, &bounds);
        let walls = vec![CHUNK as u32 + 1, 2 * CHUNK as u32 + 7];
        let small: Vec<u32> = (0..boxes.len() as u32)
            .filter(|i| !walls.contains(i))
            .collect();
        let small_bounds = small
            .iter()
            .fold(Aabb::empty(), |u, &i| u.union(&boxes[i as usize]));
        assert_eq!(parts.len(), 2);
        assert_eq!((&parts[0].prims, parts[0].bounds), (&small, small_bounds));
        assert_eq!((&parts[1].prims, parts[1].bounds), (&walls, bounds));
        // The last task's boxes widen the cluster to a fifth of the box:
        // not narrow, so one part.
        let last = boxes.len() - 1;
        boxes[last] = cube(40.0, 0.01);
        assert_eq!(parts_of(&boxes).len(), 1);
    }

    #[test]
    fn scenes_without_a_small_dense_part_stay_whole() {
        // The cluster fills a quarter of the box: not narrow enough.
        let mut boxes: Vec<Aabb<f64>> = (0..32).map(|i| cube(f64::from(i), 0.5)).collect();
        boxes.push(wall(-100.0));
        assert_eq!(parts_of(&boxes).len(), 1);
        // Too few small ones for the large: 16 small boxes beside 2 walls.
        let mut boxes: Vec<Aabb<f64>> = (0..16).map(|i| cube(f64::from(i) * 0.01, 0.1)).collect();
        boxes.extend([wall(-100.0), wall(100.0)]);
        assert_eq!(parts_of(&boxes).len(), 1);
        // No large primitive at all.
        let boxes: Vec<Aabb<f64>> = (0..64).map(|i| cube(f64::from(i), 0.4)).collect();
        assert_eq!(parts_of(&boxes).len(), 1);
    }
}
