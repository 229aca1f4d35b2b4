//! Packed triangles: a leaf's or cell's triangles copied into blocks of
//! [`LANES`] (structure of arrays, Embree's `Triangle4`), whose misses are
//! decided [`LANES`] at a time with SIMD, exactly.
//!
//! Exactness is kept the filtered way. The watertight test
//! ([`crate::triangle::intersect_triangle`]) first computes the sheared
//! vertices and the plain products of its three edge functions in `f64`, and
//! rejects the triangle when two of them have surely opposite signs. The
//! block test ([`TriangleBlock`]) makes that first stage, with the same
//! operations in the same order, on every lane at once: a lane it rejects is
//! one the scalar test rejects, bit for bit. Every other lane (a likely hit,
//! or a sign too close to call) is handed to the structure, which runs the
//! ordinary test on it ([`crate::PrimitiveSet::intersect`]). Answers are
//! therefore those of the indexed layout, not merely close to them.
//!
//! The instruction set is chosen at run time, once ([`simd_level`]): the
//! block test is written with AVX2 intrinsics and used where the CPU has
//! them. Elsewhere (other architectures, x86-64 CPUs without AVX2) the lists
//! are tested one by one, as the indexed layout does: the portable build of
//! the block test, which the compiler leaves scalar, measured slower than
//! that. A build of the same four-lane test for AVX-512 measured as fast as
//! AVX2's and is not kept; AVX-512 would pay with blocks of eight, which the
//! short lists of these structures would mostly leave half empty.
//!
//! The same first stage also runs on its side, one triangle against four
//! rays ([`RayQuad`]), for structures that walk rays in packets: the grid's
//! packets test a cell's triangles so.
//!
//! Packed and indexed lists are a speed–memory dial ([`Layout`]): a block of
//! four `f32` triangles takes 144 bytes, against 4 bytes per reference into
//! the shared mesh.

#[cfg(test)]
use crate::Vec3;
use crate::{PreparedRay, PrimitiveSet, Real};
use std::sync::OnceLock;

/// Triangles per block.
pub const LANES: usize = 4;

/// The shortest list that is packed; shorter ones are tested one by one.
/// With lists of two and three packed too, the grid on the 100k soup traced
/// 0.62–0.81× as fast as indexed; from four on, 0.94–1.04×.
pub const PACK_MIN: usize = 4;

/// How a structure stores the triangles of its leaves or cells. Every
/// structure defaults to [`Layout::Indexed`], which traced faster on most
/// scenes and ray kinds measured: a packed copy of each list takes several
/// times the memory (a triangle is copied into every list holding it), and
/// its cache misses cost more than the block test saves except where rays
/// are coherent and lists long (the grid on a dense sphere's shadow rays).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Layout {
    /// Indices into the primitive set only: the least memory.
    Indexed,
    /// Each list's triangles also copied into blocks of [`LANES`], tested
    /// several at once ([`PackedTriangles`]); sets that are not watertight
    /// triangles ([`PrimitiveSet::watertight_triangle`]) stay indexed.
    Packed,
}

impl Layout {
    /// Every layout.
    pub const ALL: [Layout; 2] = [Layout::Indexed, Layout::Packed];

    /// The layout's name, as `--layout` takes it.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Layout::Indexed => "indexed",
            Layout::Packed => "packed",
        }
    }
}

/// The SIMD instruction set the block test and the ray quads
/// ([`RayQuad`]) run with.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum SimdLevel {
    /// No block test (each list's triangles are tested one by one) and no
    /// quads (each ray of a packet tests a cell's triangles alone).
    Portable,
    /// AVX2.
    Avx2,
}

impl SimdLevel {
    /// The level's name, as `ACCEL_SIMD` takes it.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            SimdLevel::Portable => "portable",
            SimdLevel::Avx2 => "avx2",
        }
    }

    /// Whether this CPU can run the level.
    #[must_use]
    pub fn available(self) -> bool {
        match self {
            SimdLevel::Portable => true,
            #[cfg(target_arch = "x86_64")]
            SimdLevel::Avx2 => std::arch::is_x86_feature_detected!("avx2"),
            #[cfg(not(target_arch = "x86_64"))]
            _ => false,
        }
    }
}

/// The level the block test runs with: the widest this CPU has, detected
/// once. The environment variable `ACCEL_SIMD` (`portable`, `avx2`) caps
/// it, for measuring one level against another; a level the
/// CPU lacks, or an unknown name, is ignored.
#[must_use]
pub fn simd_level() -> SimdLevel {
    static LEVEL: OnceLock<SimdLevel> = OnceLock::new();
    *LEVEL.get_or_init(|| {
        let best = if SimdLevel::Avx2.available() {
            SimdLevel::Avx2
        } else {
            SimdLevel::Portable
        };
        let cap = std::env::var("ACCEL_SIMD").ok().and_then(|name| {
            [SimdLevel::Portable, SimdLevel::Avx2]
                .into_iter()
                .find(|l| l.name() == name)
        });
        cap.map_or(best, |c| c.min(best))
    })
}

/// Four triangles, coordinate by coordinate: `v[vertex][axis][lane]`.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(16))]
pub struct TriangleBlock<T> {
    v: [[[T; LANES]; 3]; 3],
}

/// The per-ray constants of the block test, in `f64` as the scalar test
/// takes them.
#[derive(Clone, Copy, Debug)]
struct BlockRay {
    origin: [f64; 3],
    shear_x: f64,
    shear_y: f64,
    axes: [usize; 3],
}

impl BlockRay {
    #[inline(always)]
    fn new<T: Real>(ray: &PreparedRay<T>) -> Self {
        let o = ray.ray.origin;
        Self {
            origin: [o.x.to_f64(), o.y.to_f64(), o.z.to_f64()],
            shear_x: ray.shear.x,
            shear_y: ray.shear.y,
            axes: ray.axes,
        }
    }
}

#[cfg(test)]
impl<T: Real> TriangleBlock<T> {
    /// The scalar statement of the block test, which the tests hold the
    /// SIMD builds to: the lanes (bit `l` for lane `l`) that the watertight test's first
    /// stage does not reject: the sheared vertices and the sure signs of the
    /// plain edge products, computed as [`crate::triangle::intersect_triangle`]
    /// computes them.
    #[inline(always)]
    fn survivors(&self, ray: &BlockRay) -> u32 {
        (0..LANES).fold(0, |m, l| {
            let vertex = |k: usize| {
                let p = &self.v[k];
                [p[0][l], p[1][l], p[2][l]].map(T::to_f64)
            };
            let sheared = |k| sheared(vertex(k), ray.origin, [ray.shear_x, ray.shear_y], ray.axes);
            m | (u32::from(survives(sheared(0), sheared(1), sheared(2))) << l)
        })
    }
}

/// A vertex `p` translated to a ray's origin `o` and sheared by its
/// constants `s`: its `x` and `y` in the ray's frame, as
/// [`crate::triangle::intersect_triangle`] computes them.
#[inline(always)]
fn sheared(p: [f64; 3], o: [f64; 3], s: [f64; 2], [kx, ky, kz]: [usize; 3]) -> (f64, f64) {
    let az = p[kz] - o[kz];
    ((p[kx] - o[kx]) - s[0] * az, (p[ky] - o[ky]) - s[1] * az)
}

/// Whether the watertight test's first stage keeps a triangle whose sheared
/// vertices are `a`, `b`, `c`: no two of its plain edge products' sure
/// signs are opposite.
#[inline(always)]
fn survives((ax, ay): (f64, f64), (bx, by): (f64, f64), (cx, cy): (f64, f64)) -> bool {
    use crate::triangle::{opposite_signs, sure_sign};
    !opposite_signs(
        sure_sign(cx * by, cy * bx),
        sure_sign(ax * cy, ay * cx),
        sure_sign(bx * ay, by * ax),
    )
}

/// The triangles of a structure's reference lists in blocks of [`LANES`].
///
/// A list is known by where it starts in the structure's reference array:
/// the blocks of the list at `start` begin at `first_block[start]`, one
/// block per [`LANES`] references, the last padded (its padding lanes are
/// never reported). Lists shorter than [`PACK_MIN`] are not packed.
#[derive(Clone, Debug)]
pub struct PackedTriangles<T> {
    blocks: Vec<TriangleBlock<T>>,
    first_block: Vec<u32>,
}

impl<T: Real> PackedTriangles<T> {
    /// Packs the lists `(start, len)` of `refs` (each `refs[start..start +
    /// len]`), or `None` when `layout` is [`Layout::Indexed`] or `prims` are
    /// not watertight triangles.
    ///
    /// # Panics
    /// If a list lies outside `refs`, or refers to a primitive `prims`
    /// lacks.
    #[must_use]
    pub fn new<P: PrimitiveSet<T> + ?Sized>(
        layout: Layout,
        prims: &P,
        refs: &[u32],
        lists: impl IntoIterator<Item = (usize, usize)>,
    ) -> Option<Self> {
        if layout == Layout::Indexed || prims.is_empty() || prims.watertight_triangle(0).is_none() {
            return None;
        }
        // Lists sharing a start share their first references: the longest
        // one's blocks serve them all.
        let mut lists: Vec<(usize, usize)> =
            lists.into_iter().filter(|l| l.1 >= PACK_MIN).collect();
        lists.sort_unstable_by_key(|&(start, len)| (start, std::cmp::Reverse(len)));
        lists.dedup_by_key(|l| l.0);
        let mut first_block = vec![0u32; refs.len() + 1];
        let mut blocks = Vec::new();
        for (start, len) in lists {
            first_block[start] = u32::try_from(blocks.len()).ok()?;
            for chunk in refs[start..start + len].chunks(LANES) {
                let mut block = TriangleBlock {
                    v: [[[T::ZERO; LANES]; 3]; 3],
                };
                for (l, &p) in chunk.iter().enumerate() {
                    let tri = prims.watertight_triangle(p as usize)?;
                    for (k, vertex) in tri.iter().enumerate() {
                        for a in 0..3 {
                            block.v[k][a][l] = vertex[a];
                        }
                    }
                }
                blocks.push(block);
            }
        }
        Some(Self {
            blocks,
            first_block,
        })
    }

    /// The bytes [`PackedTriangles::new`] adds for one list of `len`
    /// references under `layout`: its blocks (lists of [`PACK_MIN`] or more)
    /// and its entries of the list index. Zero for [`Layout::Indexed`]. Lets
    /// a build count the packed layout against a memory budget before it
    /// packs anything.
    #[must_use]
    pub const fn bytes_for_list(layout: Layout, len: usize) -> usize {
        match layout {
            Layout::Indexed => 0,
            Layout::Packed => {
                let blocks = if len >= PACK_MIN {
                    len.div_ceil(LANES)
                } else {
                    0
                };
                blocks * size_of::<TriangleBlock<T>>() + len * size_of::<u32>()
            }
        }
    }

    /// Bytes held (the blocks and the list index).
    #[must_use]
    pub fn memory_bytes(&self) -> usize {
        self.blocks.len() * size_of::<TriangleBlock<T>>()
            + self.first_block.len() * size_of::<u32>()
    }

    /// [`for_each_candidate`] of a packed list (of [`PACK_MIN`] or more).
    #[inline(always)]
    fn for_each_candidate(
        &self,
        start: usize,
        list: &[u32],
        ray: &PreparedRay<T>,
        mut test: impl FnMut(u32) -> bool,
    ) -> bool {
        match simd_level() {
            #[cfg(target_arch = "x86_64")]
            SimdLevel::Avx2 => {
                let first = self.first_block[start] as usize;
                let blocks = &self.blocks[first..first + list.len().div_ceil(LANES)];
                // SAFETY: simd_level reports AVX2 only when the CPU has it.
                unsafe { candidates_avx2(blocks, list, &BlockRay::new(ray), test) }
            }
            // The portable block test measured slower than testing the
            // list one by one (the compiler keeps it scalar).
            _ => list.iter().any(|&p| test(p)),
        }
    }
}

/// Calls `test` with each primitive of `list` (the references
/// `refs[start..start + list.len()]` of the structure) that the block test
/// could not reject, in list order, until `test` returns `true`; returns
/// whether it did. A rejected primitive is one the ray surely misses
/// ([`crate::PrimitiveSet::intersect`] would return `None`). Without
/// `packed` lists, and for a list shorter than [`PACK_MIN`] (never
/// packed), every primitive of the list is a candidate.
#[inline(always)]
pub fn for_each_candidate<T: Real>(
    packed: Option<&PackedTriangles<T>>,
    start: usize,
    list: &[u32],
    ray: &PreparedRay<T>,
    mut test: impl FnMut(u32) -> bool,
) -> bool {
    match packed {
        Some(packed) if list.len() >= PACK_MIN => packed.for_each_candidate(start, list, ray, test),
        _ => list.iter().any(|&p| test(p)),
    }
}

/// Calls `test` with the primitive of each lane of `survivors` (bit `l` for
/// lane `l`) that `prims` fills, in lane order, until it returns `true`.
#[inline(always)]
fn visit_lanes(survivors: u32, prims: &[u32], test: &mut impl FnMut(u32) -> bool) -> bool {
    let mut m = survivors & ((1u32 << prims.len()) - 1);
    while m != 0 {
        let l = m.trailing_zeros() as usize;
        m &= m - 1;
        if test(prims[l]) {
            return true;
        }
    }
    false
}

/// The block loop with the scalar block test (for tests).
#[cfg(test)]
fn candidates<T: Real>(
    blocks: &[TriangleBlock<T>],
    list: &[u32],
    ray: &BlockRay,
    mut test: impl FnMut(u32) -> bool,
) -> bool {
    for (block, prims) in blocks.iter().zip(list.chunks(LANES)) {
        if visit_lanes(block.survivors(ray), prims, &mut test) {
            return true;
        }
    }
    false
}

/// The block loop with the block test in AVX2 intrinsics
/// ([`avx2::survivors`]), inlined into each build that has them.
///
/// # Safety
/// The CPU must have AVX2.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
unsafe fn candidates_simd<T: Real>(
    blocks: &[TriangleBlock<T>],
    list: &[u32],
    ray: &BlockRay,
    mut test: impl FnMut(u32) -> bool,
) -> bool {
    // SAFETY: the caller promises AVX2.
    let lanes = unsafe { avx2::RayLanes::broadcast(ray) };
    for (block, prims) in blocks.iter().zip(list.chunks(LANES)) {
        // SAFETY: as above.
        let survivors = unsafe { avx2::survivors(block, &lanes, ray.axes) };
        if visit_lanes(survivors, prims, &mut test) {
            return true;
        }
    }
    false
}

/// [`candidates_simd`] compiled for AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn candidates_avx2<T: Real>(
    blocks: &[TriangleBlock<T>],
    list: &[u32],
    ray: &BlockRay,
    test: impl FnMut(u32) -> bool,
) -> bool {
    // SAFETY: this function runs only where the CPU has AVX2.
    unsafe { candidates_simd(blocks, list, ray, test) }
}

#[cfg(target_arch = "x86_64")]
mod avx2;
mod quad;

pub use quad::RayQuad;

/// A triangle's vertices as a block lane holds them (for tests).
#[cfg(test)]
fn lane<T: Real>(b: &TriangleBlock<T>, l: usize) -> [Vec3<T>; 3] {
    [0, 1, 2].map(|k| Vec3::new(b.v[k][0][l], b.v[k][1][l], b.v[k][2][l]))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Ray, TriangleMesh, triangle::intersect_triangle};
    use proptest::prelude::*;

    /// A mesh of `n` random triangles sharing edges (a strip), in a small
    /// box, so that rays meet edges and vertices too.
    fn strip<T: Real>(coords: &[f64]) -> TriangleMesh<T> {
        let vertices: Vec<Vec3<T>> = coords
            .chunks_exact(3)
            .map(|c| Vec3::new(T::from_f64(c[0]), T::from_f64(c[1]), T::from_f64(c[2])))
            .collect();
        let indices = (0..vertices.len() as u32 - 2)
            .map(|i| [i, i + 1, i + 2])
            .collect();
        TriangleMesh::new(vertices, indices).expect("finite strip")
    }

    /// Every level this CPU has reports, for every list, the primitives of
    /// the list the scalar test hits, in order, and only primitives of the
    /// list; the lanes hold the primitives' own vertices.
    fn check<T: Real>(coords: &[f64], o: [f64; 3], d: [f64; 3], sizes: &[usize]) {
        let mesh = strip::<T>(coords);
        let n = mesh.len() as u32;
        let refs: Vec<u32> = (0..sizes.iter().sum::<usize>() as u32)
            .map(|i| (i * 7) % n)
            .collect();
        let mut lists = Vec::new();
        let mut start = 0;
        for &len in sizes {
            lists.push((start, len));
            start += len;
        }
        let packed = PackedTriangles::new(Layout::Packed, &mesh, &refs, lists.clone())
            .expect("a mesh packs");
        let v = |a: [f64; 3]| Vec3::new(T::from_f64(a[0]), T::from_f64(a[1]), T::from_f64(a[2]));
        let Ok(ray) = Ray::new(v(o), v(d)) else {
            return;
        };
        let prepared = PreparedRay::new(ray);
        for &(start, len) in lists.iter().filter(|l| l.1 >= PACK_MIN) {
            let list = &refs[start..start + len];
            let hits: Vec<u32> = list
                .iter()
                .copied()
                .filter(|&p| {
                    let [a, b, c] = mesh.triangle(p as usize);
                    intersect_triangle(&prepared, a, b, c, ray.t_max).is_some()
                })
                .collect();
            let first = packed.first_block[start] as usize;
            for (i, &p) in list.iter().enumerate() {
                let block = &packed.blocks[first + i / LANES];
                assert_eq!(lane(block, i % LANES), mesh.triangle(p as usize));
            }
            for level in [SimdLevel::Portable, SimdLevel::Avx2] {
                if !level.available() {
                    continue;
                }
                let blocks = &packed.blocks[first..first + len.div_ceil(LANES)];
                let br = BlockRay::new(&prepared);
                let mut seen = Vec::new();
                let collect = |p| {
                    seen.push(p);
                    false
                };
                match level {
                    #[cfg(target_arch = "x86_64")]
                    // SAFETY: the level is available.
                    SimdLevel::Avx2 => unsafe { candidates_avx2(blocks, list, &br, collect) },
                    _ => candidates(blocks, list, &br, collect),
                };
                let mut at = 0;
                for &p in &seen {
                    let found = list[at..].iter().position(|&q| q == p);
                    assert!(found.is_some(), "{level:?}: {p} out of order or not listed");
                    at += found.unwrap_or(0) + 1;
                }
                for h in &hits {
                    assert!(seen.contains(h), "{level:?} rejected {h}, which is hit");
                }
            }
        }
    }

    fn coord() -> impl Strategy<Value = f64> {
        prop_oneof![-2.0..2.0f64, (-4i32..4).prop_map(|i| f64::from(i) * 0.5)]
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(2_000))]
        /// The block test never rejects a hit, at any level, in either
        /// precision, on strips whose shared edges and vertices lie on
        /// half-integer points that the rays aim at.
        #[test]
        fn blocks_reject_no_hit(
            coords in prop::collection::vec(coord(), 3 * 3..3 * 12),
            o in [coord(), coord(), coord()],
            d in [coord(), coord(), coord()],
            sizes in prop::collection::vec(1usize..11, 1..5),
        ) {
            let mut coords = coords;
            coords.truncate(coords.len() / 3 * 3);
            check::<f32>(&coords, o, d, &sizes);
            check::<f64>(&coords, o, d, &sizes);
        }
    }

    #[test]
    fn blocks_reject_the_triangles_a_ray_surely_misses() {
        // A fan of four triangles around the z axis, and a ray down the
        // axis well inside the first: the other three are rejected.
        let mesh = TriangleMesh::new(
            vec![
                Vec3::new(0.0f32, 0.0, 0.0),
                Vec3::new(4.0, -1.0, 0.0),
                Vec3::new(4.0, 1.0, 0.0),
                Vec3::new(-4.0, -1.0, 0.0),
                Vec3::new(-4.0, 1.0, 0.0),
                Vec3::new(-1.0, 4.0, 0.0),
                Vec3::new(1.0, 4.0, 0.0),
                Vec3::new(-1.0, -4.0, 0.0),
                Vec3::new(1.0, -4.0, 0.0),
            ],
            vec![[0, 1, 2], [0, 3, 4], [0, 5, 6], [0, 7, 8]],
        )
        .expect("finite fan");
        let refs = [0, 1, 2, 3];
        let packed = PackedTriangles::new(Layout::Packed, &mesh, &refs, [(0, 4)]).expect("packs");
        let ray = PreparedRay::new(
            Ray::new(Vec3::new(3.0, 0.0, 1.0), Vec3::new(0.0, 0.0, -1.0)).expect("valid"),
        );
        let mut seen = Vec::new();
        packed.for_each_candidate(0, &refs, &ray, |p| {
            seen.push(p);
            false
        });
        assert_eq!(seen, [0]);
    }

    #[test]
    fn indexed_layout_and_other_primitives_do_not_pack() {
        let mesh = strip::<f32>(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]);
        assert!(PackedTriangles::new(Layout::Indexed, &mesh, &[0], [(0, 1)]).is_none());
        let spheres = vec![crate::Sphere::new(Vec3::new(0.0f32, 0.0, 0.0), 1.0)];
        assert!(PackedTriangles::new(Layout::Packed, &spheres, &[0], [(0, 1)]).is_none());
    }
}
