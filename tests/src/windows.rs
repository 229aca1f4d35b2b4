//! Ray intervals: open, ranged, unbounded, or narrow around a hit.

use accel_core::{Hit, Ray, Real};

/// Where a narrow window sits around brute force's nearest hit `t`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HitWindow {
    /// `[t_min, next_down(t)]`: ends just before the hit.
    EndBefore,
    /// `[t_min, t]`: ends on the hit.
    EndAt,
    /// `[t_min, next_up(t)]`: ends just after the hit.
    EndAfter,
    /// `[next_down(t), +∞]`: starts just before the hit.
    StartBefore,
    /// `[t, +∞]`: starts on the hit.
    StartAt,
    /// `[next_up(t), +∞]`: starts just after the hit (the next hit beyond).
    StartAfter,
    /// `[t, t]`: exactly the hit.
    Point,
    /// `[next_down(t), next_up(t)]`.
    Ulp,
}

/// The `[t_min, t_max]` of a ray.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum WindowSpec {
    /// The ray's own `t_min` (usually 0) to +∞.
    Open,
    /// `[a, b]` in scene sizes along the ray (empty when `a > b`).
    Range(f64, f64),
    /// `[−∞, +∞]`: hits behind the origin count too.
    Everything,
    /// A narrow window around brute force's nearest hit on the open ray
    /// (the open ray when there is none).
    AtHit(HitWindow),
}

impl WindowSpec {
    /// Applies the window to `ray`; `nearest` is brute force's answer.
    #[must_use]
    pub fn apply<T: Real>(
        &self,
        ray: Ray<T>,
        size: f64,
        nearest: impl Fn(&Ray<T>) -> Option<Hit<T>>,
    ) -> Ray<T> {
        let mut r = ray;
        match *self {
            Self::Open => {}
            Self::Range(a, b) => {
                let unit = size / ray.direction.cast::<f64>().length();
                r.t_min = T::from_f64(a * unit);
                r.t_max = T::from_f64(b * unit);
            }
            Self::Everything => {
                r.t_min = T::NEG_INFINITY;
                r.t_max = T::INFINITY;
            }
            Self::AtHit(w) => {
                let Some(h) = nearest(&ray) else {
                    return ray;
                };
                let t = h.t;
                let (lo, hi) = match w {
                    HitWindow::EndBefore => (ray.t_min, t.next_down()),
                    HitWindow::EndAt => (ray.t_min, t),
                    HitWindow::EndAfter => (ray.t_min, t.next_up()),
                    HitWindow::StartBefore => (t.next_down(), T::INFINITY),
                    HitWindow::StartAt => (t, T::INFINITY),
                    HitWindow::StartAfter => (t.next_up(), T::INFINITY),
                    HitWindow::Point => (t, t),
                    HitWindow::Ulp => (t.next_down(), t.next_up()),
                };
                r.t_min = lo;
                r.t_max = hi;
            }
        }
        r
    }
}
