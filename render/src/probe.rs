//! The render's probe for `--accel auto`: the rays a render of a view
//! would trace, in miniature, for [`accel::choose_with_probe`].

use crate::scene::View;
use crate::shade::{cosine_direction, spawn};
#[cfg(doc)]
use accel::choose::{PROBE_PRIMARIES, PROBE_TILE};
use accel::choose::{ProbeRay, tiled_primaries};
use accel_core::spawn::SpawnOffset;
use accel_core::{Accelerator, QueryError, Ray, Real, TriangleMesh, Vec3};
use accel_scenes::SplitMix64;
use rayon::prelude::*;

/// The render a probe stands for, and how many primary rays it traces.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ProbeShape {
    /// Image width of the render.
    pub width: u32,
    /// Image height of the render.
    pub height: u32,
    /// Occlusion rays per sample.
    pub ao: u32,
    /// Primary rays of the probe (a coarser view of the same camera).
    pub primaries: u32,
}

/// Probe rays for a render of `view` at `width × height` with `ao`
/// occlusion rays per sample: about `primaries` primary rays
/// ([`PROBE_PRIMARIES`] for the chooser) in [`PROBE_TILE`]² tiles ([`tiled_primaries`]) of
/// neighbouring pixels of the full-resolution view, the tiles spread evenly
/// over it, and from each primary hit the shadow ray and `ao` occlusion rays
/// the shader would trace, each after its primary ray (so that thinning
/// keeps the mix).
///
/// Tiles keep the coherence of the render's own rays: a structure whose
/// speed depends on it is priced as it will run. Primary rays of a coarser
/// view instead (one per 18×18 pixels for the chooser's final budget) priced
/// the kD-tree, whose descent branches on every node, about 1.5× too slow
/// (`render bench default --accel octree,kdtree` at 40×30: the kD-tree 0.95×
/// the octree; at 800×600: 1.7×, with the same nodes and primitives per ray).
///
/// # Errors
/// A [`QueryError`] if a ray is not valid in this precision.
pub fn view_probe<T: Real>(
    accel: &dyn Accelerator<T>,
    mesh: &TriangleMesh<T>,
    view: &View,
    shape: ProbeShape,
    offset: SpawnOffset<T>,
) -> Result<Vec<ProbeRay<T>>, QueryError> {
    let ProbeShape {
        width,
        height,
        ao,
        primaries,
    } = shape;
    let primary: Vec<Ray<T>> = tiled_primaries(&view.camera, width, height, primaries);
    let hits: Vec<_> = primary
        .par_iter()
        .map(|r| accel.intersect(r))
        .collect::<Result<_, _>>()?;
    let mut out = Vec::with_capacity(primary.len() * (2 + ao as usize));
    let mut rng = SplitMix64::new(0xC405);
    for (ray, hit) in primary.iter().zip(&hits) {
        out.push(ProbeRay {
            ray: *ray,
            any_hit: false,
        });
        let Some(hit) = hit else { continue };
        let s = spawn(mesh, ray, hit, offset);
        let to_light = view.light - s.origin;
        if s.normal.dot(to_light) > 0.0 {
            out.push(ProbeRay {
                ray: Ray {
                    origin: s.origin.cast(),
                    direction: to_light.cast(),
                    t_min: T::ZERO,
                    t_max: T::ONE,
                },
                any_hit: true,
            });
        }
        for _ in 0..ao {
            let d: Vec3<f64> = cosine_direction(s.normal, &mut rng);
            out.push(ProbeRay {
                ray: Ray {
                    origin: s.origin.cast(),
                    direction: d.cast(),
                    t_min: T::ZERO,
                    t_max: T::from_f64(view.ao_distance),
                },
                any_hit: true,
            });
        }
    }
    Ok(out)
}
