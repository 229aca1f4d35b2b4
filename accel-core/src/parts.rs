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

use crate::{Aabb, Ray, Real, SceneSurvey, TraversalRay};
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
    partition_by(boxes.len(), |i| boxes[i], bounds)
}

/// [`partition`] of `n` primitives whose boxes `boxes(i)` gives, for a
/// builder that keeps no array of boxes (the uniform grid asks its
/// triangles again).
#[must_use]
pub fn partition_by<T: Real>(
    n: usize,
    boxes: impl Fn(usize) -> Aabb<T> + Sync,
    bounds: &Aabb<T>,
) -> Vec<Group<T>> {
    let all = || {
        vec![Group {
            prims: (0..n as u32).collect(),
            bounds: *bounds,
        }]
    };
    if n == 0 || bounds.is_empty() {
        return all();
    }
    let factor = T::from_f64(f64::from(ISOLATION));
    let extent = bounds.max - bounds.min;
    let largest = extent.max_component();
    // Whether the scene splits, from a count and a union alone: nearly
    // every scene stays one part, and lists made for nothing cost the 1M
    // terrain's kD-tree build 8 ms on one thread.
    let (large_count, small_bounds) = (0..n)
        .into_par_iter()
        .with_min_len(CHUNK)
        .fold(
            || (0usize, Aabb::empty()),
            |(k, u), i| {
                let b = boxes(i);
                if is_large(&b, largest) {
                    (k + 1, u)
                } else {
                    (k, u.union(&b))
                }
            },
        )
        .reduce(|| (0, Aabb::empty()), |a, b| (a.0 + b.0, a.1.union(&b.1)));
    let small_count = n - large_count;
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
    for i in 0..n {
        let b = boxes(i);
        let group = if is_large(&b, largest) {
            &mut large
        } else {
            &mut small
        };
        group.prims.push(i as u32);
        group.bounds.merge(&b);
    }
    vec![small, large]
}

/// Boxes per task of the check whether a scene splits.
const CHUNK: usize = 1 << 14;

/// The fewest primitives lying flat in one plane that [`split_flat`] sets
/// apart, and the smallest share of the scene (one in `FLAT_SHARE`) they
/// must be.
pub const FLAT_MIN: usize = 256;
/// See [`FLAT_MIN`].
pub const FLAT_SHARE: usize = 64;

/// The scene of `boxes` as two parts when many primitives lie flat in one
/// axis-aligned plane (a floor, a wall): the others, then the flat ones,
/// whose bounds are a box of zero thickness on that axis. `None` when no
/// plane holds [`FLAT_MIN`] primitives and one in [`FLAT_SHARE`] of them,
/// or when it holds them all.
///
/// A ray that leaves such a surface (a shadow or diffuse ray spawned on it)
/// then misses the flat part's bounds outright, as it misses a BVH's flat
/// box, instead of walking down to the leaf it starts in: the beam of
/// [`crate::TraversalRay::with_wide_hits`] is far thinner than the spawn
/// offset. A kD-tree's SAH cannot see this (a flat child's surface area is
/// nearly its parent's), so the build does it before the SAH runs.
#[must_use]
pub fn split_flat<T: Real>(boxes: &[Aabb<T>]) -> Option<[Group<T>; 2]> {
    split_flat_by(boxes.len(), |i| boxes[i])
}

/// [`split_flat`] of `n` primitives whose boxes `boxes(i)` gives.
#[must_use]
pub fn split_flat_by<T: Real>(
    n: usize,
    boxes: impl Fn(usize) -> Aabb<T> + Sync,
) -> Option<[Group<T>; 2]> {
    if n < FLAT_MIN || n / FLAT_SHARE == 0 {
        return None;
    }
    let (axis, plane, count) = (0..3)
        .filter_map(|axis| {
            let mut flat: Vec<u64> = (0..n)
                .into_par_iter()
                .map(&boxes)
                .filter(|b| b.min[axis] == b.max[axis])
                // -0 and +0 are one plane.
                .map(|b| (b.min[axis] + T::ZERO).to_bits_u64())
                .collect();
            if flat.len() < FLAT_MIN {
                return None;
            }
            flat.sort_unstable();
            let (bits, count) = most_common(&flat);
            Some((axis, bits, count))
        })
        // The most primitives; the lowest axis among equals.
        .fold(None, |best: Option<(usize, u64, usize)>, c| match best {
            Some(b) if b.2 >= c.2 => Some(b),
            _ => Some(c),
        })?;
    if count < FLAT_MIN || count < n / FLAT_SHARE || count == n {
        return None;
    }
    let group = |count| Group {
        prims: Vec::with_capacity(count),
        bounds: Aabb::empty(),
    };
    let (mut rest, mut flat) = (group(n - count), group(count));
    for i in 0..n {
        let b = boxes(i);
        let in_plane = b.min[axis] == b.max[axis] && (b.min[axis] + T::ZERO).to_bits_u64() == plane;
        let g = if in_plane { &mut flat } else { &mut rest };
        g.prims.push(i as u32);
        g.bounds.merge(&b);
    }
    Some([rest, flat])
}

/// [`partition`], then, where the scene stays one part and `floor_apart`
/// says so, [`split_flat`]: the parts a structure builds. Structures pass
/// `floor_apart` only where their walk can miss a flat part's bounds (their
/// own dial on, and primitives with wide hits).
#[must_use]
pub fn partition_with_floor<T: Real>(
    boxes: &[Aabb<T>],
    bounds: &Aabb<T>,
    floor_apart: bool,
) -> Vec<Group<T>> {
    partition_with_floor_by(boxes.len(), |i| boxes[i], bounds, floor_apart)
}

/// [`partition_with_floor`] of `n` primitives whose boxes `boxes(i)` gives.
#[must_use]
pub fn partition_with_floor_by<T: Real>(
    n: usize,
    boxes: impl Fn(usize) -> Aabb<T> + Sync,
    bounds: &Aabb<T>,
    floor_apart: bool,
) -> Vec<Group<T>> {
    let groups = partition_by(n, &boxes, bounds);
    match (groups.len(), floor_apart) {
        (1, true) => split_flat_by(n, boxes).map_or(groups, Vec::from),
        _ => groups,
    }
}

/// [`partition_with_floor_by`], where the survey of the scene's boxes
/// ([`crate::bounds_survey`]) leaves a chance of a part; `None` when the
/// scene stays one part. A scene without a primitive as wide as
/// [`is_large`] asks and without [`FLAT_MIN`] primitives flat on one axis
/// (every dense mesh, scan and terrain) costs no pass: on the 1M-triangle
/// terrain the two passes cost the uniform grid's one-thread build about
/// 15%.
#[must_use]
pub fn split_surveyed<T: Real>(
    n: usize,
    boxes: impl Fn(usize) -> Aabb<T> + Sync,
    survey: &SceneSurvey<T>,
    floor_apart: bool,
) -> Option<Vec<Group<T>>> {
    let bounds = &survey.bounds;
    if n == 0 || bounds.is_empty() {
        return None;
    }
    let largest = (bounds.max - bounds.min).max_component();
    let large = survey.widest * T::from_f64(f64::from(ISOLATION)) >= largest;
    let flat = floor_apart && survey.flat.iter().any(|&c| c >= FLAT_MIN);
    if !large && !flat {
        return None;
    }
    let groups = partition_with_floor_by(n, boxes, bounds, floor_apart);
    (groups.len() > 1).then_some(groups)
}

/// The beam of `ray` through a part with box `bounds`, `None` when nothing
/// there can be hit. A flat part's box (a floor built apart,
/// [`split_flat`]) is tested first with the wide type's thin beam
/// ([`TraversalRay::with_wide_hits`]) where the primitives' hits are wide
/// (`wide_hits`, [`crate::PrimitiveSet::wide_hits`]): a ray leaving the
/// floor misses it there, where a walk's own beam, as wide as `T`'s
/// rounding of its cell or plane crossings, would still graze it. Other
/// parts skip that test: on the teapot in a stadium it cost the octree
/// 7–12% of its throughput and spared nothing.
#[inline]
#[must_use]
pub fn part_beam<T: Real>(
    ray: &Ray<T>,
    bounds: &Aabb<T>,
    wide_hits: bool,
) -> Option<TraversalRay<T>> {
    let flat = (0..3).any(|a| bounds.min[a] == bounds.max[a]);
    if flat && wide_hits && TraversalRay::with_wide_hits(ray, bounds).is_none() {
        return None;
    }
    TraversalRay::new(ray, bounds)
}

/// The value repeated most often in the sorted `values` (the first of
/// equals), and how often.
fn most_common(values: &[u64]) -> (u64, usize) {
    let mut best = (0, 0);
    let mut i = 0;
    while i < values.len() {
        let run = values[i..].iter().take_while(|&&v| v == values[i]).count();
        if run > best.1 {
            best = (values[i], run);
        }
        i += run;
    }
    best
}

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

    /// A flat quad `[x, x+1] × [y, y+1]` at height `z`.
    fn tile(x: f64, y: f64, z: f64) -> Aabb<f64> {
        Aabb::new(Vec3::new(x, y, z), Vec3::new(x + 1.0, y + 1.0, z))
    }

    #[test]
    fn a_floor_of_many_flat_primitives_is_set_apart() {
        // 300 tiles of a floor at z = 0 (one at -0.0), 100 small cubes above
        // it, and 20 tiles of a shelf at z = 2 (too few to matter).
        let mut boxes: Vec<Aabb<f64>> = (0..300)
            .map(|i| tile(f64::from(i % 20), f64::from(i / 20), 0.0))
            .collect();
        boxes[7] = tile(7.0, 0.0, -0.0);
        boxes.extend((0..100).map(|i| cube(f64::from(i) * 0.1, 0.05)));
        boxes.extend((0..20).map(|i| tile(f64::from(i), 0.0, 2.0)));
        let [rest, flat] = split_flat(&boxes).expect("the floor is set apart");
        assert_eq!(flat.prims, (0..300).collect::<Vec<u32>>());
        assert_eq!(rest.prims, (300..420).collect::<Vec<u32>>());
        assert_eq!(
            flat.bounds,
            Aabb::new(Vec3::new(0.0, 0.0, 0.0), Vec3::new(20.0, 15.0, 0.0))
        );
        assert_eq!(
            rest.bounds,
            boxes[300..].iter().fold(Aabb::empty(), |u, b| u.union(b))
        );
    }

    #[test]
    fn few_or_only_flat_primitives_stay_whole() {
        // Too few in one plane: 255 tiles.
        let mut boxes: Vec<Aabb<f64>> = (0..255).map(|i| tile(f64::from(i), 0.0, 0.0)).collect();
        boxes.extend((0..100).map(|i| cube(f64::from(i), 0.5)));
        assert!(split_flat(&boxes).is_none());
        // Too small a share: 300 tiles among 30,000 cubes.
        let mut boxes: Vec<Aabb<f64>> = (0..300).map(|i| tile(f64::from(i), 0.0, 0.0)).collect();
        boxes.extend((0..30_000).map(|i| cube(f64::from(i), 0.5)));
        assert!(split_flat(&boxes).is_none());
        // Everything in the plane: nothing to set apart from.
        let boxes: Vec<Aabb<f64>> = (0..300).map(|i| tile(f64::from(i), 0.0, 0.0)).collect();
        assert!(split_flat(&boxes).is_none());
        // Flat, but in 300 different planes.
        let boxes: Vec<Aabb<f64>> = (0..300)
            .map(|i| tile(0.0, 0.0, f64::from(i)))
            .chain((0..10).map(|i| cube(f64::from(i), 0.5)))
            .collect();
        assert!(split_flat(&boxes).is_none());
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

    /// A scene of `dense` small triangles near the origin, `walls` large
    /// ones across a box 200 wide and `flat` small ones lying in the plane
    /// z = -50.
    fn scene(dense: usize, walls: usize, flat: usize) -> Vec<crate::Triangle<f64>> {
        let tri = |a: Vec3<f64>, s: f64, flat: bool| crate::Triangle {
            vertices: [
                a,
                a + Vec3::new(s, 0.0, 0.0),
                a + Vec3::new(0.0, s, if flat { 0.0 } else { s }),
            ],
        };
        let k = |i: usize| (i % 17) as f64;
        let mut t: Vec<_> = (0..dense)
            .map(|i| tri(Vec3::new(k(i), k(i / 17), k(i / 289)) * 0.05, 0.1, false))
            .collect();
        t.extend((0..walls).map(|i| tri(Vec3::new(-100.0, -100.0, k(i) - 100.0), 200.0, false)));
        t.extend(
            (0..flat).map(|i| tri(Vec3::new(k(i) - 90.0, k(i / 17) - 90.0, -50.0), 1.0, true)),
        );
        t
    }

    #[test]
    fn the_survey_skips_exactly_the_scenes_that_stay_whole() {
        // (dense, walls, flat, expected parts): dense alone; with walls (a
        // small dense part, set apart); with a floor of FLAT_MIN (set
        // apart); with too few flat ones (whole).
        for (dense, walls, flat, parts) in [
            (5000, 0, 0, 1),
            (5000, 12, 0, 2),
            (5000, 0, FLAT_MIN, 2),
            (5000, 0, FLAT_MIN - 1, 1),
        ] {
            let tris = scene(dense, walls, flat);
            let survey = crate::bounds_survey(tris.as_slice()).unwrap();
            let (boxes, bounds) = crate::primitive_bounds(tris.as_slice()).unwrap();
            assert_eq!(survey.bounds, bounds);
            assert_eq!(survey.flat[2], flat);
            let full = partition_with_floor(&boxes, &bounds, true);
            assert_eq!(full.len(), parts, "{dense} {walls} {flat}");
            let surveyed = split_surveyed(boxes.len(), |i| boxes[i], &survey, true);
            assert_eq!(surveyed, (full.len() > 1).then_some(full));
        }
    }
}
