//! The beam's width, guarded bit for bit: rays whose Möller–Trumbore hit lies
//! outside every leaf holding its triangle, by more than a beam blind to the
//! triangle's size would reach, and which the kD-tree must still answer
//! exactly as brute force.
//!
//! **Why a beam.** Möller–Trumbore rounds its barycentrics before comparing
//! them with 0 and 1, so it reports hits a little outside the exact triangle:
//! up to its guard, `gamma(24)` of the triangle's farthest vertex *from the
//! ray origin* ([`accel_core::moller_trumbore::intersect_triangle_mt`]). A
//! triangle with an edge on a split plane is referenced only on its own side
//! of the plane (Wald & Havran's classification: an end at the plane is
//! "left only"), so such a hit can lie across the plane, in a part of space
//! whose leaves never reference the triangle. Only the beam (the query's `delta`, or the narrowed
//! `node_beam`, both counting the vertices' distance) takes the traversal to
//! the triangle's leaf.
//!
//! **What this adds.** A beam that ignores the vertices, such as
//! `gamma(1)·|t|·max|d|`, covers Möller–Trumbore's error wherever a ray has
//! travelled about as far as its triangle is large, and passes the property
//! suites (only a zero beam fails them). Here the rays are *short*: they
//! start `L/1000` above a board of cells of side about `L` and pass just
//! outside an edge on a split plane. Möller–Trumbore's error there is a few
//! `u·L` (`u` the unit roundoff), while a vertex-blind beam is about
//! `u·L/1000`, and `gamma(64)` of the travelled distance plus `delta` (the
//! narrowed beam without its `2·reach` term) a tenth or two of `u·L`. A ray
//! counts as *beam-only* if brute force hits a triangle and the exact ray
//! (error-free products and sums, not the query's precision) stays farther
//! than twice that vertex-blind width from every leaf referencing the
//! triangle, over the whole interval the traversal walks
//! (`TraversalRay::t_start..t_end`): the tree can then find the hit only
//! through the vertex term of its beam. Leaf regions are bounded by the
//! tree's split planes only, not by its bounds: past the bounds it is the
//! query's own beam ([`TraversalRay::new`]) that admits a ray, not a
//! split's.
//!
//! **The scene.** A checkerboard: 8×8 cells (sides 0.8173 and 0.6711, not
//! powers of two, so that Möller–Trumbore's products round), every other
//! cell two triangles, in the plane `z = z0`. Every edge between cells has a
//! triangle on one side only, and the SAH splits along the board's lines
//! (which ones it chose is read from the built tree, not assumed). Two
//! variants per precision:
//! - *alone*: the query beam at every split (`narrowing_pays` is false);
//! - *in a large scene*: two clusters of 40 specks (triangles 1/100 of a
//!   cell) far out at `±(S, S)`. There are more specks than board triangles,
//!   so the median primitive is a speck, and `narrowing_pays` (which needs
//!   `gamma(64)·S·64` to be at least the median size; `S` is twice that)
//!   turns on the per-node narrowed beam. Tiny specks, rather than a huge
//!   scene, keep the narrowed beam's own `gamma(64)·delta` term far below the
//!   board's rounding.
//!
//! **Where the board lies.** The traversal walks the beam's span through the
//! bounds, clipped to the ray's interval widened by `t_tol = delta/max|d|`
//! (`delta` is `gamma(64)` of the scene's farthest corner from the ray
//! origin); here that is about `delta` of travel on either side of the
//! board. The exact ray must stay across the plane over all of it while
//! meeting the board within a few `u·L` of the plane. So it may drift towards the plane by at most about
//! `u·L·(L/1000)/delta` on its way down, and its origin must be representable
//! that close to the plane. Alone, `delta` is a few hundred `u·L`: the drift
//! allowed is a few millionths of `L`, which `f32` resolves only within some
//! tens of cells of the world origin and `f64` up to about `10^10` cells away
//! (the `f64` board alone is centred at `10^6` on every axis). In the large scene
//! `delta` is about `L/3,200` in both precisions, the drift allowed a few
//! `u·L`, and only planes within a cell or two of the world origin qualify:
//! those boards are centred there (at `z0 = 10^3`, which changes nothing, as
//! Möller–Trumbore's errors are relative to the ray origin, not to the world
//! origin).

use accel_core::{
    Aabb, Accelerator, BruteForce, MollerTrumboreMesh, PrimitiveSet, Ray, Real, TraversalRay,
    TriangleMesh, Vec3,
};
use accel_kdtree::KdTree;
use core::cmp::Ordering;

/// Cells per side of the board.
const CELLS: usize = 8;
/// Cell sides along x and y.
const CELL: [f64; 2] = [0.8173, 0.6711];
/// Specks per far cluster (two clusters: more than the board's triangles).
const SPECKS: usize = 40;
/// A speck's side, in cells.
const SPECK: f64 = 1.0 / 100.0;
/// Height of the ray origins above the board, in cells: small, so that a
/// beam proportional to the distance travelled is far thinner than
/// Möller–Trumbore's error, which is proportional to the cell.
const HEIGHT: f64 = 1e-3;
/// Positions along each edge (fractions of its length), away from corners.
const ALONG: [f64; 3] = [0.3, 0.55, 0.8];
/// Distances outside the edge, in quarters of `u·L`: up to 6 `u·L`, past
/// the few `u·L` that Möller–Trumbore's barycentrics err by on these rays.
const QUARTERS: u32 = 24;
/// Run along the edge per unit of fall, in cells: a steep ray and a
/// shallower one round differently.
const SLOPES: [f64; 2] = [0.3, 3.0];
/// Beam-only rays each variant must find (of about 18,000 candidates): enough
/// that a too-thin beam fails many, not one unlucky rounding.
const MIN_BEAM_ONLY: usize = 100;

/// Where a candidate ray meets the board's plane.
#[derive(Clone, Copy, Debug)]
struct Aim {
    /// The axis across the edge (0 or 1).
    axis: usize,
    /// The edge's grid line on that axis.
    plane: f64,
    /// The empty side of the edge: +1 above `plane`, −1 below.
    out: f64,
    /// How far outside the edge.
    gap: f64,
    /// The coordinate along the edge (on the other axis of the board).
    at: f64,
    /// Run along the edge per unit of fall, in cells.
    slope: f64,
}

/// The board: `CELLS × CELLS` cells centred at `centre` (x, y) in the plane
/// `z = centre.z`, cell `(i, j)` present when `i + j` is even.
#[derive(Clone, Copy, Debug)]
struct Board {
    centre: [f64; 3],
}

impl Board {
    /// The coordinate of grid line `i` (0 to `CELLS`) along axis `a` (0 or 1).
    fn line(&self, a: usize, i: usize) -> f64 {
        self.centre[a] + (i as f64 - (CELLS / 2) as f64) * CELL[a]
    }

    /// Whether cell `(i, j)` exists and holds triangles.
    fn present(i: isize, j: isize) -> bool {
        let inside = |k: isize| (0..CELLS as isize).contains(&k);
        inside(i) && inside(j) && (i + j) % 2 == 0
    }

    /// The board, and with `far = Some(s)` two clusters of specks at
    /// `centre ± (s, s)`.
    fn mesh(&self, far: Option<f64>) -> TriangleMesh<f64> {
        let z = self.centre[2];
        let at = |x, y| Vec3::new(x, y, z);
        let mut tris = Vec::new();
        for i in 0..CELLS {
            for j in 0..CELLS {
                if Self::present(i as isize, j as isize) {
                    let (x0, x1) = (self.line(0, i), self.line(0, i + 1));
                    let (y0, y1) = (self.line(1, j), self.line(1, j + 1));
                    tris.push([at(x0, y0), at(x1, y0), at(x1, y1)]);
                    tris.push([at(x0, y0), at(x1, y1), at(x0, y1)]);
                }
            }
        }
        if let Some(s) = far {
            let side = SPECK * CELL[0];
            for sign in [1.0, -1.0] {
                for k in 0..SPECKS {
                    let x = self.centre[0] + sign * (s - 2.0 * side * k as f64);
                    let y = self.centre[1] + sign * s;
                    tris.push([at(x, y), at(x + side, y), at(x, y + side)]);
                }
            }
        }
        TriangleMesh::from_triangles(&tris).expect("a valid board")
    }

    /// Candidate rays: for every edge of the board with a cell on one side
    /// only (every inner edge, half the border's), aimed from `HEIGHT` cells
    /// above at points of the board's plane `k/4·u·L` outside the edge, on
    /// the empty side (`L` the larger cell side).
    ///
    /// The origin, rounded to `T`, may lie farther out than the aim point;
    /// the component across the edge then brings the ray back towards the
    /// plane by that much at the board, never past it before the traversal's
    /// interval ends (where it would, the ray is simply not counted). It is
    /// never zero: a zero component takes the query's own beam at that split
    /// ([`TraversalRay::plane_band`]), not the beam under test.
    fn rays<T: Real>(&self) -> Vec<Ray<T>> {
        let unit = T::UNIT_ROUNDOFF.to_f64() * CELL[0].max(CELL[1]);
        let h = HEIGHT * CELL[0].max(CELL[1]);
        let mut rays = Vec::new();
        for a in 0..2 {
            // Cell (i across the lines, j along them) as (x index, y index).
            let cell = |i: isize, j: isize| if a == 0 { (i, j) } else { (j, i) };
            for i in 0..=CELLS {
                let plane = self.line(a, i);
                for j in 0..CELLS {
                    let (lx, ly) = cell(i as isize - 1, j as isize);
                    let (hx, hy) = cell(i as isize, j as isize);
                    let (low, high) = (Self::present(lx, ly), Self::present(hx, hy));
                    if low == high {
                        continue;
                    }
                    // The side of the plane with no triangle here.
                    let out = if low { 1.0 } else { -1.0 };
                    for along in ALONG {
                        for slope in SLOPES {
                            for k in 1..=QUARTERS {
                                let aim = Aim {
                                    axis: a,
                                    plane,
                                    out,
                                    gap: f64::from(k) * 0.25 * unit,
                                    at: self.line(1 - a, j) + along * CELL[1 - a],
                                    slope,
                                };
                                rays.push(self.ray(&aim, h));
                            }
                        }
                    }
                }
            }
        }
        rays
    }

    /// One candidate ray (see [`Board::rays`]), starting `h` above the board.
    fn ray<T: Real>(&self, aim: &Aim, h: f64) -> Ray<T> {
        let Aim {
            axis: a,
            plane,
            out,
            gap,
            at,
            slope,
        } = *aim;
        let b = 1 - a;
        // The origin's coordinate across the plane: at least `gap` out.
        let mut oa = T::from_f64(plane + out * gap);
        while out * (oa.to_f64() - plane) < gap {
            oa = if out > 0.0 {
                oa.next_up()
            } else {
                oa.next_down()
            };
        }
        let excess = out * (oa.to_f64() - plane) - gap;
        let da = -out * excess.max(gap * 1e-3) / h;
        let mut o = [T::ZERO; 3];
        let mut d = [T::ZERO; 3];
        o[a] = oa;
        o[b] = T::from_f64(at - slope * CELL[b] * h);
        o[2] = T::from_f64(self.centre[2] + h);
        d[a] = T::from_f64(da);
        d[b] = T::from_f64(slope * CELL[b]);
        d[2] = -T::ONE;
        Ray::new(Vec3::new(o[0], o[1], o[2]), Vec3::new(d[0], d[1], d[2])).expect("a valid ray")
    }
}

/// Knuth's error-free sum: `a + b = s + e` exactly.
fn two_sum(a: f64, b: f64) -> (f64, f64) {
    let s = a + b;
    let bb = s - a;
    (s, (a - (s - bb)) + (b - bb))
}

/// The exact sign of a sum of doubles: Shewchuk's grow-expansion, then the
/// sign of the largest nonzero component.
fn exact_sign(terms: &[f64]) -> Ordering {
    let mut expansion: Vec<f64> = Vec::with_capacity(terms.len());
    for &t in terms {
        let mut q = t;
        let mut grown = Vec::with_capacity(expansion.len() + 1);
        for &c in &expansion {
            let (s, e) = two_sum(q, c);
            grown.push(e);
            q = s;
        }
        grown.push(q);
        expansion = grown;
    }
    expansion
        .iter()
        .rev()
        .find(|&&c| c != 0.0)
        .map_or(Ordering::Equal, |&c| c.total_cmp(&0.0))
}

/// Whether the exact point `o + t·d` (one coordinate) lies more than
/// `margin` above `face` (`up`) or below it (`!up`); never past an infinite
/// face.
fn beyond(o: f64, d: f64, t: f64, face: f64, margin: f64, up: bool) -> bool {
    if !face.is_finite() {
        return false;
    }
    let p = t * d;
    let p_err = t.mul_add(d, -p);
    let s = if up { 1.0 } else { -1.0 };
    exact_sign(&[s * o, s * p, s * p_err, -s * face, -margin]) == Ordering::Greater
}

/// Whether the exact segment of `ray` over `[t0, t1]` stays more than
/// `margin` outside `region` along one axis (sufficient for missing it).
fn clear_of<T: Real>(region: &Aabb<T>, ray: &Ray<T>, t0: T, t1: T, margin: f64) -> bool {
    let (t0, t1) = (t0.to_f64(), t1.to_f64());
    (0..3).any(|a| {
        let (o, d) = (ray.origin[a].to_f64(), ray.direction[a].to_f64());
        let (lo, hi) = (region.min[a].to_f64(), region.max[a].to_f64());
        let side =
            |face, up| beyond(o, d, t0, face, margin, up) && beyond(o, d, t1, face, margin, up);
        side(hi, true) || side(lo, false)
    })
}

/// Per primitive, the regions of the leaves that reference it, bounded by the
/// tree's own split planes only (the root's region is all of space).
fn leaf_regions<T: Real, P: PrimitiveSet<T> + ?Sized>(
    tree: &KdTree<'_, T, P>,
) -> Vec<Vec<Aabb<T>>> {
    let mut regions = vec![Vec::new(); tree.primitives().len()];
    let everywhere = Aabb::new(Vec3::splat(T::NEG_INFINITY), Vec3::splat(T::INFINITY));
    let mut stack = vec![(0usize, everywhere)];
    while let Some((i, region)) = stack.pop() {
        let node = tree.nodes()[i];
        match tree.split_position(i) {
            None => {
                for &p in tree.leaf_primitives(&node) {
                    regions[p as usize].push(region);
                }
            }
            Some(s) => {
                let (below, above) = region.split_at(node.axis(), s);
                let [b, a] = node.children(i);
                stack.extend(b.map(|b| (b, below)));
                stack.extend(a.map(|a| (a, above)));
            }
        }
    }
    regions
}

/// Every candidate ray answers as brute force (nearest hit bit for bit, and
/// any-hit); returns how many of them are beam-only: brute force's triangle
/// is referenced only by leaves that the exact ray stays clear of, by more
/// than twice a vertex-blind beam, over the whole interval the traversal walks.
fn beam_only_rays<T: Real>(board: Board, far: Option<f64>) -> usize {
    let mesh: TriangleMesh<T> = board.mesh(far).cast().expect("representable");
    let mt = MollerTrumboreMesh::new(&mesh);
    let tree = KdTree::new(&mt).expect("a tree");
    let brute = BruteForce::new(&mt).expect("brute force");
    let regions = leaf_regions(&tree);
    let mut beam_only = 0;
    for ray in board.rays::<T>() {
        let want = brute.intersect(&ray).expect("a valid query");
        let got = tree.intersect(&ray).expect("a valid query");
        assert_eq!(
            got.map(|h| h.bit_key()),
            want.map(|h| h.bit_key()),
            "{} {board:?} far {far:?}: ray {ray:?}: kd-tree {got:?}, brute force {want:?}",
            T::NAME
        );
        assert_eq!(
            tree.occluded(&ray).expect("a valid query"),
            want.is_some(),
            "{} {board:?} far {far:?}: occluded, ray {ray:?}",
            T::NAME
        );
        let Some(hit) = want else { continue };
        let tr = TraversalRay::new(&ray, &tree.bounds()).expect("the ray meets the bounds");
        let travel = tr.t_start.abs().max(tr.t_end.abs()) * ray.direction.abs().max_component();
        // The widest beam blind to the vertices that a node of this walk can
        // get: `node_beam` without its reach, `gamma(64)·(|t|·max|d| +
        // delta)` (wider than `gamma(1)·|t|·max|d|`), doubled for slack (the
        // band's own widening, relative to the offset from the plane).
        let blind = (T::gamma(64) * (travel + tr.delta)).to_f64() * 2.0;
        if regions[hit.prim as usize]
            .iter()
            .all(|r| clear_of(r, &ray, tr.t_start, tr.t_end, blind))
        {
            beam_only += 1;
        }
    }
    beam_only
}

/// `S` for the far specks: twice what `narrowing_pays` needs, `gamma(64)·S·64`
/// at least the median primitive (a speck).
fn far_for<T: Real>() -> f64 {
    2.0 * SPECK * CELL[0] / (64.0 * T::gamma(64).to_f64())
}

/// The board centred on the world origin in x and y, where `f32` and the
/// large scene can place origins within a few `u·L` of its central lines.
const AT_ORIGIN: Board = Board {
    centre: [0.0, 0.0, 1e3],
};

/// Every candidate answers as brute force, and enough of them are
/// beam-only for the check to mean something.
fn check<T: Real>(board: Board, far: Option<f64>) {
    let n = beam_only_rays::<T>(board, far);
    assert!(
        n >= MIN_BEAM_ONLY,
        "{} {board:?} far {far:?}: {n} beam-only rays, want {MIN_BEAM_ONLY}",
        T::NAME
    );
}

#[test]
fn beam_covers_moller_trumbore_edge_hits_f32_alone() {
    check::<f32>(AT_ORIGIN, None);
}

#[test]
fn beam_covers_moller_trumbore_edge_hits_f32_in_a_large_scene() {
    check::<f32>(AT_ORIGIN, Some(far_for::<f32>()));
}

#[test]
fn beam_covers_moller_trumbore_edge_hits_f64_alone_far_from_the_origin() {
    check::<f64>(
        Board {
            centre: [1e6, 1e6, 1e6],
        },
        None,
    );
}

#[test]
fn beam_covers_moller_trumbore_edge_hits_f64_in_a_large_scene() {
    check::<f64>(AT_ORIGIN, Some(far_for::<f64>()));
}
