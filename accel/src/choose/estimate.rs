//! What the chooser reports: the probe rays, each candidate's estimate,
//! the choice, and why a choice failed.

use crate::{AccelConfig, AccelError, AnyAccelerator};
use accel_core::{PrimitiveSet, QueryError, Ray, Real};
use std::time::Duration;

#[cfg(doc)]
use super::{GRID_CELL_LIMIT, PROBE_SHARE, TWO_LEVEL_SHARE, choose_with_probe, probe_per_ray};

/// A probe ray and the query it stands for.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ProbeRay<T> {
    /// The ray.
    pub ray: Ray<T>,
    /// `occluded` (shadow and occlusion rays) rather than `intersect`.
    pub any_hit: bool,
}

/// How a probe ([`probe_per_ray`]) ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ProbeStop {
    /// Every probe ray was traced (and traced again, warm).
    Complete,
    /// Stopped at the time budget: priced from the rays traced so far.
    TimeCap,
    /// Stopped because the estimate already lost by the given margin.
    Loses,
}

/// A probe's result: time per ray, and how much of the probe it is from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ProbeTime {
    /// Seconds per ray.
    pub per_ray_s: f64,
    /// Seconds per ray of the rays traced in the spread-out order (the
    /// `per_ray_s` of a probe that stopped early; a complete probe's
    /// `per_ray_s` is the faster of this and a pass in the probe's order).
    /// Probes are compared on this, like with like.
    pub spread_per_ray_s: f64,
    /// Probe rays traced (all of them when [`ProbeStop::Complete`]).
    pub rays: usize,
    /// Why the probe ended.
    pub stop: ProbeStop,
}

/// Why a candidate was not built in full and probed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Skip {
    /// Its predicted build alone is past [`PROBE_SHARE`] of the best total.
    SlowBuild,
    /// The grid: its fullest cell holds this many references (more than
    /// [`GRID_CELL_LIMIT`]).
    FullCell(usize),
    /// The two-level octree: predicted to build about as fast as the default
    /// octree (not below [`TWO_LEVEL_SHARE`] of it), so nearly the same tree.
    SameTree,
}

/// How a candidate was estimated.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Status {
    /// Built in full and timed on the probe.
    Probed(ProbeTime),
    /// Not probed, and why.
    Skipped(Skip),
}

/// One candidate's estimate.
#[derive(Clone, Debug, PartialEq)]
pub struct Estimate {
    /// The structure and parameters.
    pub config: AccelConfig,
    /// Build time in seconds: measured if probed (or if skipped for a full
    /// cell), predicted otherwise.
    pub build_s: f64,
    /// Seconds per ray, measured on the probe (NaN when not probed).
    pub per_ray_s: f64,
    /// `build_s + expected rays × per_ray_s` (infinite when not probed).
    pub total_s: f64,
    /// Probed, or skipped and why.
    pub status: Status,
    /// Wall-clock seconds the chooser spent on this candidate (prediction,
    /// build and probe).
    pub cost_s: f64,
}

impl Estimate {
    /// Whether it was built in full and timed.
    #[must_use]
    pub fn probed(&self) -> bool {
        matches!(self.status, Status::Probed(_))
    }
}

/// What [`choose_with_probe`] picked, and why.
pub struct Choice<'a, T: Real, P: PrimitiveSet<T> + ?Sized> {
    /// The structure and parameters chosen.
    pub config: AccelConfig,
    /// The chosen structure, built.
    pub accel: AnyAccelerator<'a, T, P>,
    /// One line: the scene statistics and the estimates behind the choice.
    pub reason: String,
    /// Every candidate's estimate, in probe order.
    pub estimates: Vec<Estimate>,
    /// Wall-clock time of the whole choice, the winner's build included.
    pub elapsed: Duration,
}

impl<T: Real, P: PrimitiveSet<T> + ?Sized> core::fmt::Debug for Choice<'_, T, P> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("Choice")
            .field("config", &self.config)
            .field("reason", &self.reason)
            .field("estimates", &self.estimates)
            .field("elapsed", &self.elapsed)
            .finish_non_exhaustive()
    }
}

/// Why a choice failed.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ChooseError {
    /// A candidate could not be built.
    #[error(transparent)]
    Build(#[from] AccelError),
    /// A probe ray was refused.
    #[error("probe ray: {0}")]
    Query(#[from] QueryError),
}
