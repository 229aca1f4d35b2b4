//! The assertions every accelerator must pass, against brute force.
//!
//! Each returns `Err` with a readable message instead of panicking, so that
//! proptest shrinks the failing case and the message names the accelerator,
//! the ray or box, and both answers.

use accel_core::{
    Aabb, Accelerator, BruteForce, Hit, PreparedRay, PrimitiveSet, QueryError, Ray, Real,
    TraversalCounters,
};
use rayon::prelude::*;

/// The reference answers for a set of rays and regions.
#[derive(Clone, Debug)]
pub struct Expected<T> {
    /// Brute force's nearest hit per ray.
    pub hits: Vec<Option<Hit<T>>>,
    /// Brute force's region answer per region.
    pub regions: Vec<Vec<u32>>,
}

impl<T: Real> Expected<T> {
    /// Asks brute force.
    ///
    /// # Errors
    /// A message if brute force refuses a valid query.
    pub fn compute<P: PrimitiveSet<T> + ?Sized>(
        brute: &BruteForce<'_, T, P>,
        rays: &[Ray<T>],
        regions: &[Aabb<T>],
    ) -> Result<Self, String> {
        let hits = rays
            .par_iter()
            .map(|r| {
                brute
                    .intersect(r)
                    .map_err(|e| format!("brute force refused valid ray {r:?}: {e}"))
            })
            .collect::<Result<_, _>>()?;
        let regions = regions
            .iter()
            .map(|b| {
                brute
                    .query_region(b)
                    .map_err(|e| format!("brute force refused region {b:?}: {e}"))
            })
            .collect::<Result<_, _>>()?;
        Ok(Self { hits, regions })
    }
}

/// Describes a primitive of a failing case by its bounds.
fn describe<T: Real, P: PrimitiveSet<T> + ?Sized>(prims: &P, hit: Option<Hit<T>>) -> String {
    match hit {
        Some(h) if (h.prim as usize) < prims.len() => {
            format!("prim {} bounds {:?}", h.prim, prims.bounds(h.prim as usize))
        }
        Some(h) => format!("prim {} out of range", h.prim),
        None => "no hit".into(),
    }
}

/// Checks one ray: `intersect` (and `intersect_counted`) equal brute force
/// bit for bit; `occluded` (and `occluded_counted`) equal whether brute force
/// hits.
///
/// # Errors
/// A message naming the accelerator, the ray and both answers.
pub fn check_ray<T: Real, P: PrimitiveSet<T> + ?Sized>(
    name: &str,
    acc: &dyn Accelerator<T>,
    prims: &P,
    ray: &Ray<T>,
    want: Option<Hit<T>>,
) -> Result<(), String> {
    let fail = |what: &str, got: String| {
        Err(format!(
            "{name} ({}): {what}\n  ray  {ray:?}\n  got  {got}\n  want {want:?} ({})",
            T::NAME,
            describe(prims, want)
        ))
    };
    let key = |h: Option<Hit<T>>| h.map(|h| h.bit_key());
    match acc.intersect(ray) {
        Ok(got) if key(got) == key(want) => {}
        Ok(got) => {
            return fail(
                "intersect differs from brute force",
                format!("{got:?} ({})", describe(prims, got)),
            );
        }
        Err(e) => return fail("intersect refused a valid ray", e.to_string()),
    }
    let mut counters = TraversalCounters::default();
    match acc.intersect_counted(ray, &mut counters) {
        Ok(got) if key(got) == key(want) => {}
        Ok(got) => {
            return fail(
                "intersect_counted differs from brute force",
                format!("{got:?}"),
            );
        }
        Err(e) => return fail("intersect_counted refused a valid ray", e.to_string()),
    }
    match acc.occluded(ray) {
        Ok(got) if got == want.is_some() => {}
        Ok(got) => {
            return fail(
                "occluded differs from brute force's hit",
                format!("occluded = {got}"),
            );
        }
        Err(e) => return fail("occluded refused a valid ray", e.to_string()),
    }
    match acc.occluded_counted(ray, &mut counters) {
        Ok(got) if got == want.is_some() => {}
        Ok(got) => {
            return fail(
                "occluded_counted differs from brute force's hit",
                format!("occluded = {got}"),
            );
        }
        Err(e) => return fail("occluded_counted refused a valid ray", e.to_string()),
    }
    Ok(())
}

/// Checks a region query against brute force's answer.
///
/// # Errors
/// A message naming the accelerator, the box and the difference.
pub fn check_region<T: Real>(
    name: &str,
    acc: &dyn Accelerator<T>,
    region: &Aabb<T>,
    want: &[u32],
) -> Result<(), String> {
    match acc.query_region(region) {
        Ok(got) if got == want => Ok(()),
        Ok(got) => {
            let missing: Vec<u32> = want.iter().copied().filter(|p| !got.contains(p)).collect();
            let extra: Vec<u32> = got.iter().copied().filter(|p| !want.contains(p)).collect();
            Err(format!(
                "{name} ({}): query_region differs from brute force\n  box {region:?}\n  \
                 missing {missing:?}, extra {extra:?} (got {} ids, want {})",
                T::NAME,
                got.len(),
                want.len()
            ))
        }
        Err(e) => Err(format!(
            "{name} ({}): query_region refused a finite box {region:?}: {e}",
            T::NAME
        )),
    }
}

/// Checks an accelerator's statistics and bounds against the scene.
///
/// # Errors
/// A message naming what is off.
pub fn check_shape<T: Real, P: PrimitiveSet<T> + ?Sized>(
    name: &str,
    acc: &dyn Accelerator<T>,
    prims: &P,
    scene_bounds: &Aabb<T>,
) -> Result<(), String> {
    let stats = acc.stats();
    if stats.primitives != prims.len() {
        return Err(format!(
            "{name}: stats report {} primitives, the scene has {}",
            stats.primitives,
            prims.len()
        ));
    }
    if !scene_bounds.is_empty() && !acc.bounds().contains(scene_bounds) {
        return Err(format!(
            "{name}: bounds {:?} do not hold the scene's {scene_bounds:?}",
            acc.bounds()
        ));
    }
    Ok(())
}

/// Every check of one accelerator on a list of rays and regions; rays in
/// parallel when there are many. Reports the first failing ray in list order.
///
/// # Errors
/// The first failure's message.
pub fn check_accelerator<T: Real, P: PrimitiveSet<T> + ?Sized>(
    name: &str,
    acc: &dyn Accelerator<T>,
    prims: &P,
    rays: &[Ray<T>],
    regions: &[Aabb<T>],
    expected: &Expected<T>,
) -> Result<(), String> {
    let scene_bounds = (0..prims.len()).fold(Aabb::empty(), |b, i| b.union(&prims.bounds(i)));
    check_shape(name, acc, prims, &scene_bounds)?;
    let failure = if rays.len() > 64 {
        rays.par_iter()
            .zip(&expected.hits)
            .find_map_first(|(r, &w)| check_ray(name, acc, prims, r, w).err())
    } else {
        rays.iter()
            .zip(&expected.hits)
            .find_map(|(r, &w)| check_ray(name, acc, prims, r, w).err())
    };
    if let Some(f) = failure {
        return Err(f);
    }
    check_bundles(name, acc, prims, rays, &expected.hits)?;
    for (region, want) in regions.iter().zip(&expected.regions) {
        check_region(name, acc, region, want)?;
    }
    Ok(())
}

/// Checks the bundle queries against brute force: the rays as one bundle
/// (a packet-splitting override then meets a partial last packet), and in
/// bundles of 5.
///
/// # Errors
/// A message naming the accelerator, the bundle size, the ray and both
/// answers.
pub fn check_bundles<T: Real, P: PrimitiveSet<T> + ?Sized>(
    name: &str,
    acc: &dyn Accelerator<T>,
    prims: &P,
    rays: &[Ray<T>],
    want: &[Option<Hit<T>>],
) -> Result<(), String> {
    let key = |h: Option<Hit<T>>| h.map(|h| h.bit_key());
    for size in [rays.len().max(1), 5] {
        let mut nearest = vec![Ok(None); rays.len()];
        let mut any = vec![Ok(false); rays.len()];
        for ((bundle, near), occ) in rays
            .chunks(size)
            .zip(nearest.chunks_mut(size))
            .zip(any.chunks_mut(size))
        {
            acc.intersect_bundle(bundle, near);
            acc.occluded_bundle(bundle, occ);
        }
        for (i, ray) in rays.iter().enumerate() {
            let w = want[i];
            let fail = |what: &str, got: String| {
                Err(format!(
                    "{name} ({}), bundles of {size}: {what}\n  ray  {ray:?}\n  got  {got}\n  want {w:?} ({})",
                    T::NAME,
                    describe(prims, w)
                ))
            };
            match nearest[i] {
                Ok(got) if key(got) == key(w) => {}
                Ok(got) => {
                    return fail(
                        "intersect_bundle differs from brute force",
                        format!("{got:?}"),
                    );
                }
                Err(e) => return fail("intersect_bundle refused a valid ray", e.to_string()),
            }
            match any[i] {
                Ok(got) if got == w.is_some() => {}
                Ok(got) => {
                    return fail(
                        "occluded_bundle differs from brute force's hit",
                        format!("occluded = {got}"),
                    );
                }
                Err(e) => return fail("occluded_bundle refused a valid ray", e.to_string()),
            }
        }
    }
    Ok(())
}

/// Checks that every query refuses an invalid ray with the error brute force
/// gives, and that this error is one of `allowed` (the problems the ray has).
///
/// # Errors
/// A message naming the accelerator, the ray and the answers.
pub fn check_refused<T: Real>(
    name: &str,
    acc: &dyn Accelerator<T>,
    ray: &Ray<T>,
    want: QueryError,
    allowed: &[QueryError],
) -> Result<(), String> {
    if !allowed.contains(&want) {
        return Err(format!(
            "brute force's error {want:?} names none of the ray's problems {allowed:?}: {ray:?}"
        ));
    }
    let mut c = TraversalCounters::default();
    let (mut nearest, mut any) = ([Ok(None)], [Ok(false)]);
    acc.intersect_bundle(core::slice::from_ref(ray), &mut nearest);
    acc.occluded_bundle(core::slice::from_ref(ray), &mut any);
    let answers = [
        ("intersect_bundle", nearest[0].map(|h| format!("{h:?}"))),
        ("occluded_bundle", any[0].map(|o| format!("{o}"))),
        ("intersect", acc.intersect(ray).map(|h| format!("{h:?}"))),
        ("occluded", acc.occluded(ray).map(|o| format!("{o}"))),
        (
            "intersect_counted",
            acc.intersect_counted(ray, &mut c).map(|h| format!("{h:?}")),
        ),
        (
            "occluded_counted",
            acc.occluded_counted(ray, &mut c).map(|o| format!("{o}")),
        ),
    ];
    for (query, got) in answers {
        if got != Err(want) {
            return Err(format!(
                "{name} ({}): {query} on an invalid ray gave {got:?}, want Err({want:?})\n  ray {ray:?}",
                T::NAME
            ));
        }
    }
    Ok(())
}

/// The hit of primitive `prim` alone on `ray`: what a returned hit must equal.
#[must_use]
pub fn own_hit<T: Real, P: PrimitiveSet<T> + ?Sized>(
    prims: &P,
    prim: u32,
    ray: &Ray<T>,
) -> Option<Hit<T>> {
    let pr = PreparedRay::new(*ray);
    prims
        .intersect(prim as usize, &pr, ray.t_max)
        .map(|h| Hit::new(prim, h))
}
