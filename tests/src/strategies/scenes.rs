//! Scene strategies.

use super::rays::unit;
use crate::scene::{Degenerate, DegenerateKind, Item, LineKind, Placement, SceneSpec, Shape, Tri};
use accel_core::Real;
use accel_scenes::strategies::lattice_tri;
use proptest::prelude::*;

/// The offsets (in scene sizes) that put a scene far from the origin in
/// precision `T`: 1e4 and 1e7 in `f32`, and 1e15 too in `f64`.
#[must_use]
pub fn far_offsets<T: Real>() -> Vec<f64> {
    if size_of::<T>() == 4 {
        vec![1e4, 1e7]
    } else {
        vec![1e4, 1e7, 1e15]
    }
}

/// Mostly unit scale at the origin; sometimes a mild scale or offset.
pub fn ordinary_placement() -> BoxedStrategy<Placement> {
    prop_oneof![
        6 => Just(Placement::IDENTITY),
        1 => (-3..=3i32, prop::sample::select(vec![0.0, 3.0, 100.0]))
            .prop_map(|(scale_exp, offset)| Placement { scale_exp, offset }),
    ]
    .boxed()
}

/// Always extreme: a scale of 10^±7 to 10^±20, a far offset, or both.
pub fn extreme_placement(offsets: Vec<f64>) -> BoxedStrategy<Placement> {
    let scale = prop::sample::select(vec![-20, -13, -7, 7, 13, 20]);
    let offset = prop::sample::select(offsets);
    prop_oneof![
        scale.clone().prop_map(|scale_exp| Placement {
            scale_exp,
            offset: 0.0
        }),
        offset.clone().prop_map(|offset| Placement {
            scale_exp: 0,
            offset
        }),
        (scale, offset).prop_map(|(scale_exp, offset)| Placement { scale_exp, offset }),
    ]
    .boxed()
}

/// A point in the unit cube.
fn point() -> impl Strategy<Value = [f64; 3]> + Clone {
    [unit(), unit(), unit()]
}

/// A triangle in the unit cube.
pub fn tri() -> impl Strategy<Value = Tri> + Clone {
    [point(), point(), point()]
}

/// A closed mesh (sphere, box or torus) or a heightfield, with few triangles.
pub fn closed_shape(heightfields: bool) -> BoxedStrategy<Shape> {
    let extent = || prop_oneof![Just(1.0), Just(0.5), Just(0.25), 0.2..1.0f64];
    let closed = prop_oneof![
        (8usize..=160).prop_map(Shape::Sphere),
        (1u32..=3, [extent(), extent(), extent()]).prop_map(|(k, e)| Shape::Box(k, e)),
        (3u32..=10, 3u32..=6).prop_map(|(r, s)| Shape::Torus(r, s)),
    ];
    if heightfields {
        prop_oneof![
            3 => closed,
            1 => (2usize..=128, 0u64..4).prop_map(|(n, s)| Shape::Terrain(n, s)),
        ]
        .boxed()
    } else {
        closed.boxed()
    }
}

fn degenerate() -> impl Strategy<Value = Degenerate> {
    (
        prop::sample::select(vec![
            DegenerateKind::Sliver,
            DegenerateKind::Needle,
            DegenerateKind::Collinear,
            DegenerateKind::Point,
            DegenerateKind::Repeated,
        ]),
        point(),
        point(),
        unit(),
        -12..=-1i32,
    )
        .prop_map(|(kind, a, b, s, eps_exp)| Degenerate {
            kind,
            a,
            b,
            s,
            eps_exp,
        })
}

/// A triangle or a sphere (radius up to 0.3, sometimes exactly 0).
pub fn mixed_item() -> impl Strategy<Value = Item> {
    prop_oneof![
        tri().prop_map(Item::Tri),
        (point(), prop_oneof![4 => 0.0..0.3f64, 1 => Just(0.0)])
            .prop_map(|(c, r)| Item::Ball(c, r)),
    ]
}

/// Every kind of scene, placed by `place`.
pub fn scene(place: BoxedStrategy<Placement>) -> BoxedStrategy<SceneSpec> {
    let p = || place.clone();
    prop_oneof![
        1 => Just(SceneSpec::Empty),
        6 => (prop::collection::vec(tri(), 1..24), p()).prop_map(|(t, p)| SceneSpec::Soup(t, p)),
        4 => (prop::collection::vec(lattice_tri(), 1..16), p())
            .prop_map(|(t, p)| SceneSpec::Lattice(t, p)),
        5 => (closed_shape(true), p()).prop_map(|(s, p)| SceneSpec::Closed(s, p)),
        2 => (20usize..160, prop::sample::select(vec![8.0, 100.0, 1e4]), p())
            .prop_map(|(dense, stadium, place)| SceneSpec::Teapot { dense, stadium, place }),
        // Large enough to be built in parts (see `SceneSpec::Teapot`).
        2 => (260usize..400, prop::sample::select(vec![100.0, 1e4]), p())
            .prop_map(|(dense, stadium, place)| SceneSpec::Teapot { dense, stadium, place }),
        // From 12 quads a side (288 triangles) the floor is a part of its own
        // (`accel_core::parts::split_flat`).
        2 => (2u32..24, 40usize..400, p())
            .prop_map(|(quads, dense, place)| SceneSpec::FlatField { quads, dense, place }),
        2 => (prop::collection::vec([[unit(), unit()], [unit(), unit()], [unit(), unit()]], 1..16), p())
            .prop_map(|(t, p)| SceneSpec::Flat(t, p)),
        2 => (
            prop::collection::vec(point(), 1..12),
            prop::sample::select(vec![LineKind::AxisX, LineKind::Oblique]),
            p(),
        )
            .prop_map(|(t, k, p)| SceneSpec::Line(t, k, p)),
        2 => (prop::collection::vec(tri(), 1..12), -6..=-1i32, p())
            .prop_map(|(cluster, size_exp, place)| SceneSpec::OneCell { cluster, size_exp, place }),
        3 => (
            prop::collection::vec(tri(), 1..4),
            prop::collection::vec((0usize..4, 0u8..4), 2..12),
            p(),
        )
            .prop_map(|(base, picks, place)| SceneSpec::Duplicates { base, picks, place }),
        3 => (prop::collection::vec(degenerate(), 1..12), p())
            .prop_map(|(t, p)| SceneSpec::Degenerate(t, p)),
        4 => (prop::collection::vec(mixed_item(), 1..16), p())
            .prop_map(|(t, p)| SceneSpec::Mixed(t, p)),
    ]
    .boxed()
}
