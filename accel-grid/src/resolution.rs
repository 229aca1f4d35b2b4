//! How many cells: the seed's rule, made safe for flat scenes and budgets.
//!
//! For `n` objects in a box of extents `w`, the seed takes the cube side
//! `s = cbrt(wx·wy·wz / n)` and `n_i = trunc(m·w_i / s) + 1` cells per axis, about
//! `m³·n` cells in all (the seed's "mn³" is a typo): `m = 2` gives the 8 cells
//! per object where grids are said to do best.
//!
//! A scene flat in an axis (`w_i = 0`) would make `s = 0`. Such an axis, and any
//! axis the rule would give less than one cell's worth of extent (`m·w_i/s < 1`,
//! a nearly flat scene, where the "+1" alone would otherwise blow up the other
//! axes), gets one cell, and `s` is recomputed over the remaining `k` axes as
//! `(Π w_i / n)^(1/k)`: a flat scene gets a 2D grid of about `m²·n` cells, a
//! scene along a line a 1D grid of about `m·n`.

use accel_core::{Aabb, BuildError, Real};

/// Cells per axis by the rule above, for `object_count` objects over `bounds`
/// with density `density` (`m`), refusing more than `max_cells` cells.
///
/// # Errors
/// [`BuildError::InvalidParameter`] for a density that is not finite and
/// positive; [`BuildError::BudgetExceeded`] when the cells would number more
/// than `max_cells`.
pub fn resolution<T: Real>(
    bounds: &Aabb<T>,
    object_count: usize,
    density: f64,
    max_cells: u64,
) -> Result<[u32; 3], BuildError> {
    if !(density.is_finite() && density > 0.0) {
        return Err(BuildError::InvalidParameter {
            name: "density",
            value: density.to_string(),
            expected: "a finite number above 0",
        });
    }
    if object_count == 0 || bounds.is_empty() {
        return Ok([1, 1, 1]);
    }
    let n = object_count as f64;
    let w = bounds.diagonal().map(T::to_f64).to_array();
    let mut active: Vec<usize> = (0..3).filter(|&a| w[a] > 0.0).collect();
    let mut cells = [1.0f64; 3];
    while !active.is_empty() {
        let k = active.len() as f64;
        // Product in logs: extents of 1e±20 must not overflow or underflow.
        let log_s = (active.iter().map(|&a| w[a].ln()).sum::<f64>() - n.ln()) / k;
        let per_axis: Vec<f64> = active
            .iter()
            .map(|&a| density * (w[a].ln() - log_s).exp())
            .collect();
        // Drop the thinnest axis if it gets less than one cell's worth.
        let (thin, &least) = per_axis
            .iter()
            .enumerate()
            .min_by(|x, y| x.1.total_cmp(y.1))
            .expect("active is not empty");
        if least < 1.0 {
            active.remove(thin);
            continue;
        }
        for (i, &a) in active.iter().enumerate() {
            // The guard keeps exact ratios (2·1/0.1 = 20) from truncating to 19
            // through the rounding of logs and exponentials.
            cells[a] = (per_axis[i] * (1.0 + 1e-9)).trunc() + 1.0;
        }
        break;
    }
    let total: f64 = cells.iter().product();
    if total > max_cells as f64 || cells.iter().any(|&c| c > f64::from(u32::MAX)) {
        return Err(BuildError::BudgetExceeded {
            what: "grid cells",
            needed: total.min(u64::MAX as f64) as u64,
            budget: max_cells,
        });
    }
    Ok(cells.map(|c| c as u32))
}

#[cfg(test)]
mod tests {
    use super::*;
    use accel_core::Vec3;

    fn cube(w: Vec3<f64>) -> Aabb<f64> {
        Aabb::new(Vec3::new(-1.0, 2.0, 5.0), Vec3::new(-1.0, 2.0, 5.0) + w)
    }

    fn total(r: [u32; 3]) -> u64 {
        r.iter().map(|&c| u64::from(c)).product()
    }

    #[test]
    fn about_m_cubed_n_cells() {
        for (n, m) in [
            (1000usize, 2.0),
            (100_000, 2.0),
            (100_000, 1.0),
            (50_000, 4.0),
        ] {
            let r = resolution(&cube(Vec3::new(3.0, 1.0, 2.0)), n, m, u64::MAX).unwrap();
            let ratio = total(r) as f64 / (m * m * m * n as f64);
            // The "+1" per axis adds a few percent on top of m³·n.
            assert!(
                (1.0..1.35).contains(&ratio),
                "n {n} m {m}: {r:?}, ratio {ratio}"
            );
            // Roughly cubical cells: extents 3:1:2 give cells 3:1:2 (within the +1).
            let (a, b, c) = (
                f64::from(r[0] - 1),
                f64::from(r[1] - 1),
                f64::from(r[2] - 1),
            );
            assert!(
                (a / b - 3.0).abs() < 0.1 && (c / b - 2.0).abs() < 0.1,
                "{r:?}"
            );
        }
    }

    #[test]
    fn seed_formula_on_a_unit_cube() {
        // s = cbrt(1/1000) = 0.1, n_i = trunc(2·1/0.1) + 1 = 21.
        let r = resolution(&cube(Vec3::splat(1.0)), 1000, 2.0, u64::MAX).unwrap();
        assert_eq!(r, [21, 21, 21]);
    }

    #[test]
    fn flat_scenes_get_a_2d_or_1d_grid() {
        let flat = resolution(&cube(Vec3::new(4.0, 1.0, 0.0)), 10_000, 2.0, u64::MAX).unwrap();
        assert_eq!(flat[2], 1);
        let ratio = total(flat) as f64 / (4.0 * 10_000.0);
        assert!((1.0..1.2).contains(&ratio), "{flat:?}");
        let line = resolution(&cube(Vec3::new(0.0, 7.0, 0.0)), 500, 2.0, u64::MAX).unwrap();
        assert_eq!(line, [1, 1001, 1]);
        let point = resolution(&cube(Vec3::splat(0.0)), 500, 2.0, u64::MAX).unwrap();
        assert_eq!(point, [1, 1, 1]);
    }

    #[test]
    fn nearly_flat_scene_does_not_explode() {
        // 1e-9 thick: the plain seed rule would give ~2e5 × 2e5 cells.
        let r = resolution(&cube(Vec3::new(1.0, 1.0, 1e-9)), 1_000_000, 2.0, u64::MAX).unwrap();
        assert_eq!(r[2], 1);
        assert!(total(r) < 5_000_000, "{r:?}");
    }

    #[test]
    fn single_object() {
        let r = resolution(&cube(Vec3::new(1.0, 2.0, 4.0)), 1, 2.0, u64::MAX).unwrap();
        // s = cbrt(8) = 2: n = trunc(2·w/2) + 1 = w + 1.
        assert_eq!(r, [2, 3, 5]);
    }

    #[test]
    fn extreme_extents_keep_the_rule() {
        for scale in [1e-20, 1e20] {
            let b = Aabb::new(Vec3::splat(0.0), Vec3::splat(scale));
            let r = resolution(&b, 1000, 2.0, u64::MAX).unwrap();
            assert_eq!(r, [21, 21, 21], "scale {scale}");
        }
    }

    #[test]
    fn budget_and_density_are_checked() {
        let err = resolution(&cube(Vec3::splat(1.0)), 1_000_000, 100.0, 1 << 28).unwrap_err();
        assert!(matches!(err, BuildError::BudgetExceeded { budget, .. } if budget == 1 << 28));
        for bad in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            assert!(matches!(
                resolution(&cube(Vec3::splat(1.0)), 10, bad, u64::MAX),
                Err(BuildError::InvalidParameter {
                    name: "density",
                    ..
                })
            ));
        }
    }
}
