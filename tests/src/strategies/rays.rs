//! Ray, window and box strategies.

use crate::{BoxSpec, HitWindow, RaySpec, WindowSpec};
pub use accel_scenes::strategies::unit;
use proptest::prelude::*;

/// A point in unit coordinates.
pub fn unit3() -> impl Strategy<Value = [f64; 3]> + Clone {
    [unit(), unit(), unit()]
}

fn component() -> impl Strategy<Value = f64> + Clone {
    prop_oneof![
        6 => -1.0..=1.0f64,
        1 => prop::sample::select(vec![-1.0, -0.0, 0.0, 0.5, 1.0]),
    ]
}

/// A direction (possibly with zero components; never all zero once resolved).
pub fn dir3() -> impl Strategy<Value = [f64; 3]> + Clone {
    [component(), component(), component()]
}

/// Indices of vertices, edges, primitives, cells and boundaries in the
/// small generated scenes (taken modulo their counts).
pub const INDEX_RANGE: usize = 4096;

fn grid() -> impl Strategy<Value = usize> + Clone {
    0usize..5
}

fn axis() -> impl Strategy<Value = usize> + Clone {
    0usize..3
}

/// Every way of aiming a ray.
pub fn ray() -> BoxedStrategy<RaySpec> {
    ray_in(INDEX_RANGE)
}

/// [`ray`] with indices drawn from `0..max_index` (large meshes).
pub fn ray_in(max_index: usize) -> BoxedStrategy<RaySpec> {
    let index = move || 0..max_index;
    let zero = prop::array::uniform3(prop_oneof![4 => Just(0u8), 1 => Just(1u8), 1 => Just(2u8)]);
    let len_exp = prop_oneof![8 => Just(0i32), 1 => prop::sample::select(vec![-100, -40, 40, 100])];
    prop_oneof![
        4 => (unit3(), dir3(), zero, len_exp).prop_map(|(origin, dir, zero, len_exp)| {
            RaySpec::Random { origin, dir, zero, len_exp }
        }),
        2 => (unit3(), axis(), any::<bool>(), any::<[bool; 2]>()).prop_map(
            |(origin, axis, negative, zero_neg)| RaySpec::Axis { origin, axis, negative, zero_neg }
        ),
        2 => (grid(), axis(), index(), unit3(), dir3(), any::<bool>()).prop_map(
            |(grid, axis, k, origin, dir, zero_neg)| {
                RaySpec::CellFace { grid, axis, k, origin, dir, zero_neg }
            }
        ),
        2 => (grid(), axis(), [index(), index()], unit(), any::<bool>(), any::<[bool; 2]>())
            .prop_map(|(grid, axis, k, along, negative, zero_neg)| {
                RaySpec::GridEdge { grid, axis, k, along, negative, zero_neg }
            }),
        2 => (grid(), [index(), index(), index()], unit3(), prop::option::weighted(0.3, dir3()))
            .prop_map(|(grid, k, origin, from_corner)| {
                RaySpec::CellCorner { grid, k, origin, from_corner }
            }),
        3 => (unit3(), index()).prop_map(|(origin, vertex)| RaySpec::AtVertex { origin, vertex }),
        3 => (unit3(), index(), unit())
            .prop_map(|(origin, edge, s)| RaySpec::AtEdge { origin, edge, s }),
        1 => (index(), prop_oneof![Just(0.0), Just(0.5), 0.0..3.0f64], any::<bool>())
            .prop_map(|(edge, before, reverse)| RaySpec::AlongEdge { edge, before, reverse }),
        1 => (index(), axis(), unit3(), dir3(), any::<bool>()).prop_map(
            |(vertex, axis, origin, dir, zero_neg)| {
                RaySpec::VertexPlane { vertex, axis, origin, dir, zero_neg }
            }
        ),
        2 => (
            index(),
            [unit(), unit()],
            dir3(),
            prop::sample::select(vec![0.0, 0.0, 1e-7, 1e-4]),
        )
            .prop_map(|(prim, uv, dir, eps)| RaySpec::OnSurface { prim, uv, dir, eps }),
        1 => (index(), dir3()).prop_map(|(vertex, dir)| RaySpec::FromVertex { vertex, dir }),
        1 => (index(), unit3(), dir3())
            .prop_map(|(prim, at, dir)| RaySpec::InPrimitiveBox { prim, at, dir }),
        1 => (grid(), index(), unit3(), dir3())
            .prop_map(|(grid, cell, at, dir)| RaySpec::InCell { grid, cell, at, dir }),
    ]
    .boxed()
}

/// A ray's `[t_min, t_max]`.
pub fn window() -> BoxedStrategy<WindowSpec> {
    let hit = prop::sample::select(vec![
        HitWindow::EndBefore,
        HitWindow::EndAt,
        HitWindow::EndAfter,
        HitWindow::StartBefore,
        HitWindow::StartAt,
        HitWindow::StartAfter,
        HitWindow::Point,
        HitWindow::Ulp,
    ]);
    prop_oneof![
        5 => Just(WindowSpec::Open),
        1 => (0.0..2.0f64, 0.0..3.0f64).prop_map(|(a, b)| WindowSpec::Range(a, b)),
        1 => Just(WindowSpec::Everything),
        3 => hit.prop_map(WindowSpec::AtHit),
    ]
    .boxed()
}

/// Rays with their windows, `1..max` of them.
pub fn rays_and_windows(max: usize) -> BoxedStrategy<Vec<(RaySpec, WindowSpec)>> {
    prop::collection::vec((ray(), window()), 1..max).boxed()
}

/// A region-query box.
pub fn boxes() -> BoxedStrategy<BoxSpec> {
    boxes_in(INDEX_RANGE)
}

/// [`boxes`] with indices drawn from `0..max_index` (large meshes).
pub fn boxes_in(max_index: usize) -> BoxedStrategy<BoxSpec> {
    let index = move || 0..max_index;
    prop_oneof![
        3 => (unit3(), unit3()).prop_map(|(a, b)| BoxSpec::Random(a, b)),
        1 => (unit3(), unit3(), axis()).prop_map(|(a, b, x)| BoxSpec::Flat(a, b, x)),
        2 => (index(), prop::sample::select(vec![-30, -6, -2, -1]))
            .prop_map(|(v, e)| BoxSpec::AroundVertex(v, e)),
        1 => index().prop_map(BoxSpec::PrimitiveBounds),
        2 => (grid(), index()).prop_map(|(g, c)| BoxSpec::Cell(g, c)),
        1 => (unit3(), unit3(), axis()).prop_map(|(a, b, x)| BoxSpec::Inverted(a, b, x)),
        1 => Just(BoxSpec::Frame),
    ]
    .boxed()
}

/// A coherent bundle, as a renderer traces one: a tile of up to 8 × 8 rays
/// from one origin whose directions fan out by `2^-spread` around a centre,
/// each with its own window. One centre component is drawn near zero in a
/// third of the tiles, so that the fan crosses it and the bundle mixes
/// directions' signs; some rays force a component to ±0 (`zero`, as in
/// [`RaySpec::Random`]).
pub fn coherent_tile() -> BoxedStrategy<Vec<(RaySpec, WindowSpec)>> {
    (
        unit3(),
        dir3(),
        (1usize..=8, 1usize..=8),
        2i32..12,
        (any::<bool>(), 0usize..3),
        (0usize..64, [0u8..3, 0u8..3, 0u8..3]),
        prop::collection::vec(window(), 64),
    )
        .prop_map(
            |(origin, centre, (w, h), spread, (straddle, axis), (every, zero), windows)| {
                let s = 2f64.powi(-spread);
                let mut centre = centre;
                if straddle {
                    centre[axis] = 0.25 * s;
                }
                let mut tile = Vec::with_capacity(w * h);
                for j in 0..h {
                    for i in 0..w {
                        let (di, dj) = (i as f64 - w as f64 / 2.0, j as f64 - h as f64 / 2.0);
                        let dir = [
                            centre[0] + s * di,
                            centre[1] + s * dj,
                            centre[2] + s * 0.5 * (di - dj),
                        ];
                        let k = i + w * j;
                        // Every `every`-th ray (none when 0) forces zeros.
                        let zero = if every > 0 && k % every == 0 {
                            zero
                        } else {
                            [0; 3]
                        };
                        tile.push((
                            RaySpec::Random {
                                origin,
                                dir,
                                zero,
                                len_exp: 0,
                            },
                            windows[k],
                        ));
                    }
                }
                tile
            },
        )
        .boxed()
}
