//! A pinhole camera and the one framing rule of the workspace.
//!
//! [`Camera`] is the classic pinhole model (eye, orthonormal basis, vertical
//! field of view; pixel centres at `+0.5`), as in pbrt's perspective camera
//! without lens. [`Camera::frame`] points one at a box from a direction.

use accel_core::{Aabb, Ray, Real, Vec3};

/// The up direction of the generated scenes (z up).
pub const Z_UP: Vec3<f64> = Vec3::new(0.0, 0.0, 1.0);
/// The up direction of glTF files (y up).
pub const Y_UP: Vec3<f64> = Vec3::new(0.0, 1.0, 0.0);

/// A pinhole camera.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// Eye position.
    pub eye: Vec3<f64>,
    /// Unit view direction.
    pub forward: Vec3<f64>,
    /// Unit right vector.
    pub right: Vec3<f64>,
    /// Unit up vector (orthogonal to `forward` and `right`).
    pub up: Vec3<f64>,
    /// Vertical field of view, radians.
    pub vfov: f64,
}

impl Camera {
    /// A camera at `eye` looking at `target`; `up` need not be orthogonal.
    #[must_use]
    pub fn look_at(eye: Vec3<f64>, target: Vec3<f64>, up: Vec3<f64>, vfov_degrees: f64) -> Self {
        let forward = (target - eye).normalized();
        let mut right = forward.cross(up);
        if right.length_squared() < 1e-24 {
            // Looking along `up`: any perpendicular will do.
            right = forward.cross(Vec3::new(up.y, up.z, up.x));
        }
        let right = right.normalized();
        let up = right.cross(forward);
        Self {
            eye,
            forward,
            right,
            up,
            vfov: vfov_degrees.to_radians(),
        }
    }

    /// The direction from which [`Camera::frame`] shows most scenes: the
    /// generated ones but the terrain and the teapot in a stadium, and the
    /// glTF files of the examples and tests.
    pub const DEFAULT_SIDE: Vec3<f64> = Vec3::new(1.0, -1.6, 0.9);

    /// A camera looking at the centre of `b` from direction `from`, with
    /// `up` as its up direction ([`Z_UP`] for the generated scenes, [`Y_UP`]
    /// for glTF), far enough that the whole box fits a 45° view. A box that
    /// is a single point gets a small sensible distance instead.
    ///
    /// The one framing of the workspace: `render`'s automatic cameras, the
    /// generated scenes' default view and the benchmarks' views all use it.
    #[must_use]
    pub fn frame(b: &Aabb<f64>, from: Vec3<f64>, up: Vec3<f64>) -> Self {
        let center = b.center();
        let mut radius = b.diagonal().length() * 0.5;
        if !(radius > 0.0) {
            // A single point: any sensible distance will do.
            radius = (center.abs().max_component() * 1e-3).max(1.0);
        }
        let vfov: f64 = 45.0;
        let distance = radius / (vfov.to_radians() * 0.5).sin() * 1.05;
        Self::look_at(center + from.normalized() * distance, center, up, vfov)
    }

    /// The ray through image position `(x, y)` in pixels of a `width × height`
    /// image (`(0, 0)` top left; pixel centers at `+0.5`).
    #[must_use]
    pub fn ray_through<T: Real>(&self, x: f64, y: f64, width: u32, height: u32) -> Ray<T> {
        let aspect = f64::from(width) / f64::from(height);
        let h = (self.vfov * 0.5).tan();
        let sx = (2.0 * x / f64::from(width) - 1.0) * h * aspect;
        let sy = (1.0 - 2.0 * y / f64::from(height)) * h;
        let d = self.forward + self.right * sx + self.up * sy;
        Ray {
            origin: self.eye.cast(),
            direction: d.cast(),
            t_min: T::ZERO,
            t_max: T::INFINITY,
        }
    }

    /// One ray through the center of every pixel, row by row.
    #[must_use]
    pub fn rays<T: Real>(&self, width: u32, height: u32) -> Vec<Ray<T>> {
        (0..height)
            .flat_map(|y| {
                (0..width).map(move |x| {
                    self.ray_through(f64::from(x) + 0.5, f64::from(y) + 0.5, width, height)
                })
            })
            .collect()
    }
}

/// The pixels `(x, y)` of a `width × height` tile in Z order (Morton
/// order: the bits of `x` and `y` interleaved, `x`'s lowest first). Every
/// run of 2²ᵏ or 2²ᵏ⁺¹ pixels from a multiple of its length is a square or
/// a 2:1 block (eight pixels: 4 × 2), so a bundle's consecutive rays, which
/// a structure walks together as packets, are as close as a run of their
/// number can be. A tile whose sides are not powers of two skips the codes
/// beyond its sides.
pub fn z_order(width: usize, height: usize) -> impl Iterator<Item = (usize, usize)> {
    let side = width.max(height).next_power_of_two();
    // The bits of `code` at even (or odd) positions, packed.
    let spread =
        |code: usize| (0..usize::BITS / 2).fold(0, |v, b| v | ((code >> (2 * b)) & 1) << b);
    (0..side * side)
        .map(move |code| (spread(code), spread(code >> 1)))
        .filter(move |&(x, y)| x < width && y < height)
}

/// `items` of an image `width` wide, row by row, reordered tile by tile
/// (`tile` × `tile` pixels, tiles row by row; within a tile in
/// [`z_order`]; the tiles of the last rows and columns cut short).
#[must_use]
pub fn by_tiles<T: Copy>(items: &[T], width: usize, tile: usize) -> Vec<T> {
    let width = width.max(1);
    let tile = tile.max(1);
    let height = items.len().div_ceil(width);
    let mut out = Vec::with_capacity(items.len());
    for ty in (0..height).step_by(tile) {
        for tx in (0..width).step_by(tile) {
            let (w, h) = (tile.min(width - tx), tile.min(height - ty));
            for (x, y) in z_order(w, h) {
                if let Some(&item) = items.get((ty + y) * width + tx + x) {
                    out.push(item);
                }
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::uv_sphere;
    use accel_core::{Accelerator, BruteForce};

    #[test]
    fn z_order_visits_blocks_of_four_by_two() {
        // An 8 × 8 tile: each run of eight is a 4 × 2 block, each run of
        // sixteen a 4 × 4 block, and every pixel comes once.
        let z: Vec<(usize, usize)> = z_order(8, 8).collect();
        assert_eq!(
            &z[..8],
            &[
                (0, 0),
                (1, 0),
                (0, 1),
                (1, 1),
                (2, 0),
                (3, 0),
                (2, 1),
                (3, 1)
            ]
        );
        for (run, block) in z.chunks(8).enumerate() {
            let (x0, y0) = (block[0].0, block[0].1);
            assert!(x0 % 4 == 0 && y0 % 2 == 0, "run {run} starts at {x0}, {y0}");
            assert!(
                block
                    .iter()
                    .all(|&(x, y)| (x0..x0 + 4).contains(&x) && (y0..y0 + 2).contains(&y))
            );
        }
        for block in z.chunks(16) {
            let (x0, y0) = block[0];
            assert!(
                block
                    .iter()
                    .all(|&(x, y)| (x0..x0 + 4).contains(&x) && (y0..y0 + 4).contains(&y))
            );
        }
        let mut sorted = z.clone();
        sorted.sort_unstable();
        let all: Vec<(usize, usize)> = (0..8).flat_map(|x| (0..8).map(move |y| (x, y))).collect();
        assert_eq!(sorted, all);
        // A cut tile keeps the order of the pixels it has.
        let cut: Vec<(usize, usize)> = z_order(3, 2).collect();
        assert_eq!(cut, [(0, 0), (1, 0), (0, 1), (1, 1), (2, 0), (2, 1)]);
    }

    #[test]
    fn tiles_cover_the_image_once_in_tile_order() {
        let pixels: Vec<u32> = (0..30).collect();
        let tiled = by_tiles(&pixels, 10, 4);
        // Three rows: tiles of 4 × 3, 4 × 3 and the last 2 × 3, each in Z
        // order (2 × 2 blocks, then the cut ones).
        let want: Vec<u32> = [0, 1, 10, 11, 2, 3, 12, 13, 20, 21, 22, 23]
            .into_iter()
            .chain([4, 5, 14, 15, 6, 7, 16, 17, 24, 25, 26, 27])
            .chain([8, 9, 18, 19, 28, 29])
            .collect();
        assert_eq!(tiled, want);
        // A ragged last row is kept, once.
        let mut ragged = by_tiles(&pixels[..27], 10, 8);
        ragged.sort_unstable();
        assert_eq!(ragged, pixels[..27]);
    }

    #[test]
    fn camera_center_ray_hits_the_framed_sphere() {
        let m = uv_sphere(Vec3::new(5.0, 0.0, 0.0), 2.0, 500);
        let cam = Camera::frame(&m.bounds(), Vec3::new(0.0, -1.0, 0.0), Z_UP);
        let brute = BruteForce::new(&m).unwrap();
        let r: Ray<f64> = cam.ray_through(50.0, 50.0, 100, 100);
        assert!(brute.intersect(&r).unwrap().is_some());
        let corner: Ray<f64> = cam.ray_through(0.0, 0.0, 100, 100);
        assert!(brute.intersect(&corner).unwrap().is_none());
    }

    #[test]
    fn framing_sees_the_whole_box() {
        let b = Aabb::new(Vec3::new(-1.0, 0.0, 2.0), Vec3::new(3.0, 1.0, 4.0));
        let cam = Camera::frame(&b, Vec3::new(0.0, 0.0, 1.0), Y_UP);
        let to_center = (b.center() - cam.eye).normalized();
        assert!((to_center.dot(cam.forward) - 1.0).abs() < 1e-12);
        // Every corner lies within the vertical half-angle of the view axis.
        for i in 0..8 {
            let d = (b.corner(i) - cam.eye).normalized();
            assert!(d.dot(cam.forward) > (cam.vfov * 0.5).cos(), "corner {i}");
        }
        let point = Aabb::from_point(Vec3::new(5.0, 5.0, 5.0));
        assert!(
            Camera::frame(&point, Vec3::new(1.0, 1.0, 1.0), Y_UP)
                .eye
                .is_finite()
        );
    }
}
