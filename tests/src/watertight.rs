//! Watertightness: rays from outside a closed mesh aimed at its shared edges
//! and vertices must hit, in every accelerator. Zero leaks is the only pass.
//!
//! A ray is aimed so that it crosses the surface at the target, not grazes
//! it: it comes from the side that every triangle around the target (around
//! both ends of an edge) faces, by a margin. Then the triangles around the
//! target cover a neighbourhood of it as the ray sees them, and the
//! watertight triangle test must report one of them (or an earlier hit),
//! whatever the rounding of the ray. The rays come from
//! [`accel_scenes::aimed`] (the generator `studies tradeoff` uses too).

use crate::registry::accelerators;
use accel_core::{Accelerator, BruteForce, PrimitiveSet, Ray, Real};
pub use accel_scenes::aimed::{Aim, ClosedParts, Target};

/// Rays (by index) that hit nothing, per accelerator, brute force first.
///
/// # Errors
/// A message if an accelerator cannot be built or refuses a valid ray.
pub fn leaks<T: Real, P: PrimitiveSet<T> + ?Sized + 'static>(
    prims: &P,
    rays: &[Ray<T>],
) -> Result<Vec<(&'static str, Vec<usize>)>, String> {
    let mut out = Vec::new();
    let brute = BruteForce::new(prims).map_err(|e| e.to_string())?;
    out.push(("brute (reference)", missed(&brute, rays)?));
    for entry in accelerators::<T, P>() {
        let acc = (entry.build)(prims).map_err(|e| format!("{}: {e}", entry.name))?;
        out.push((entry.name, missed(&*acc, rays)?));
    }
    Ok(out)
}

fn missed<T: Real>(acc: &dyn Accelerator<T>, rays: &[Ray<T>]) -> Result<Vec<usize>, String> {
    let mut out = Vec::new();
    for (i, r) in rays.iter().enumerate() {
        if acc.intersect(r).map_err(|e| e.to_string())?.is_none() {
            out.push(i);
        }
    }
    Ok(out)
}

/// Fails with the leaking rays if any accelerator leaks.
///
/// # Errors
/// A message listing, per leaking accelerator, the count and the first rays.
pub fn assert_no_leaks<T: Real, P: PrimitiveSet<T> + ?Sized + 'static>(
    prims: &P,
    rays: &[Ray<T>],
) -> Result<(), String> {
    let report = leaks(prims, rays)?;
    let leaking: Vec<String> = report
        .iter()
        .filter(|(_, l)| !l.is_empty())
        .map(|(name, l)| {
            let first: Vec<&Ray<T>> = l.iter().take(3).map(|&i| &rays[i]).collect();
            format!(
                "{name} ({}): {} of {} rays leaked, first {first:?}",
                T::NAME,
                l.len(),
                rays.len()
            )
        })
        .collect();
    if leaking.is_empty() {
        Ok(())
    } else {
        Err(leaking.join("\n"))
    }
}
