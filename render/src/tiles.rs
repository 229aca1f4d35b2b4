//! The image in square tiles, traced in parallel with rayon, with a progress
//! bar on stderr (hidden when stderr is not a terminal).

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use rayon::prelude::*;
use std::sync::atomic::{AtomicUsize, Ordering};

/// Side of a tile in pixels: big enough to amortise scheduling, small enough
/// to balance the load across cores.
pub const TILE: u32 = 16;

/// A progress bar counting pixels on stderr. indicatif hides it when stderr is
/// not a terminal (a pipe, a file, CI), so logs stay clean.
#[must_use]
pub fn progress_bar(pixels: u64, message: &'static str) -> ProgressBar {
    let bar = ProgressBar::with_draw_target(Some(pixels), ProgressDrawTarget::stderr());
    if let Ok(style) =
        ProgressStyle::with_template("{msg} [{bar:40}] {percent:>3}% {elapsed} (eta {eta})")
    {
        bar.set_style(style.progress_chars("=> "));
    }
    bar.set_message(message);
    bar
}

/// A rectangle of pixels: columns `x0..x1` of rows `y0..y1`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Tile {
    /// The first column.
    pub x0: u32,
    /// The first row.
    pub y0: u32,
    /// One past the last column.
    pub x1: u32,
    /// One past the last row.
    pub y1: u32,
}

impl Tile {
    /// Columns.
    #[must_use]
    pub const fn width(&self) -> u32 {
        self.x1 - self.x0
    }

    /// Rows.
    #[must_use]
    pub const fn height(&self) -> u32 {
        self.y1 - self.y0
    }

    /// Pixels.
    #[must_use]
    pub const fn len(&self) -> usize {
        self.width() as usize * self.height() as usize
    }

    /// Whether it holds no pixel.
    #[must_use]
    pub const fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Its pixels `(x, y)`, row by row.
    pub fn pixels(self) -> impl Iterator<Item = (u32, u32)> {
        (self.y0..self.y1).flat_map(move |y| (self.x0..self.x1).map(move |x| (x, y)))
    }

    /// Its parts of at most `side` × `side` pixels, row by row (those of the
    /// last rows and columns cut short).
    ///
    /// # Panics
    /// If `side` is 0.
    pub fn parts(self, side: u32) -> impl Iterator<Item = Self> {
        assert!(side > 0, "parts of a positive side");
        (self.y0..self.y1)
            .step_by(side as usize)
            .flat_map(move |y0| {
                (self.x0..self.x1)
                    .step_by(side as usize)
                    .map(move |x0| Self {
                        x0,
                        y0,
                        x1: (x0 + side).min(self.x1),
                        y1: (y0 + side).min(self.y1),
                    })
            })
    }
}

/// Calls `f(tile)` for every [`TILE`] × [`TILE`] tile of a `width × height`
/// image (those of the last rows and columns cut short), in parallel, and
/// returns the image row by row; `f` returns the tile's pixels row by row.
///
/// # Errors
/// The error of the first tile (in tile order) whose `f` fails, whatever
/// order the threads meet failures in; a tile after a failed one may or may
/// not have run, every tile before it has.
///
/// # Panics
/// If `f` returns other than [`Tile::len`] pixels.
pub fn for_each_tile<P, E, F>(
    width: u32,
    height: u32,
    progress: &ProgressBar,
    f: F,
) -> Result<Vec<P>, E>
where
    P: Copy + Default + Send,
    E: Send,
    F: Fn(Tile) -> Result<Vec<P>, E> + Sync,
{
    let whole = Tile {
        x0: 0,
        y0: 0,
        x1: width,
        y1: height,
    };
    let tiles: Vec<Tile> = whole.parts(TILE).collect();
    // The index of the first failed tile met so far: tiles after it are
    // skipped, tiles before it still run, so the first failure in tile
    // order is always among those that ran (rayon's own collection into a
    // `Result` returns whichever error a thread met first).
    let first_failure = AtomicUsize::new(usize::MAX);
    let done: Vec<Option<Result<Vec<P>, E>>> = tiles
        .par_iter()
        .enumerate()
        .map(|(i, &tile)| {
            if i > first_failure.load(Ordering::Relaxed) {
                return None;
            }
            let out = f(tile);
            match &out {
                Ok(pixels) => {
                    assert_eq!(pixels.len(), tile.len(), "one result per pixel of {tile:?}");
                    progress.inc(pixels.len() as u64);
                }
                Err(_) => {
                    first_failure.fetch_min(i, Ordering::Relaxed);
                }
            }
            Some(out)
        })
        .collect();
    // Every tile before the first failure ran, so the first `Err` in order,
    // if any, is that failure, and no tile before it was skipped.
    let done: Vec<Vec<P>> = done
        .into_iter()
        .map(|tile| tile.expect("no tile before the first failure is skipped"))
        .collect::<Result<_, E>>()?;
    let mut image = vec![P::default(); width as usize * height as usize];
    for (tile, pixels) in tiles.iter().zip(&done) {
        let w = tile.width() as usize;
        for (row, chunk) in pixels.chunks(w).enumerate() {
            let start = (tile.y0 as usize + row) * width as usize + tile.x0 as usize;
            image[start..start + w].copy_from_slice(chunk);
        }
    }
    Ok(image)
}

/// Calls `f(x, y)` for every pixel of a `width × height` image, tile by tile
/// in parallel ([`for_each_tile`]), and returns the results row by row.
///
/// # Errors
/// The first error of `f` in tile order, row by row within a tile (as
/// [`for_each_tile`]'s).
pub fn for_each_pixel<P, E, F>(
    width: u32,
    height: u32,
    progress: &ProgressBar,
    f: F,
) -> Result<Vec<P>, E>
where
    P: Copy + Default + Send,
    E: Send,
    F: Fn(u32, u32) -> Result<P, E> + Sync,
{
    for_each_tile(width, height, progress, |tile| {
        tile.pixels().map(|(x, y)| f(x, y)).collect()
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_pixel_lands_in_its_place() {
        let (w, h) = (37, 21); // not multiples of the tile size
        let bar = ProgressBar::hidden();
        let img = for_each_pixel::<_, (), _>(w, h, &bar, |x, y| Ok((x, y))).unwrap();
        assert_eq!(img.len(), (w * h) as usize);
        for y in 0..h {
            for x in 0..w {
                assert_eq!(img[(y * w + x) as usize], (x, y));
            }
        }
        assert_eq!(bar.position(), u64::from(w * h));
    }

    #[test]
    fn an_error_stops_the_image() {
        let bar = ProgressBar::hidden();
        let r = for_each_pixel(20, 20, &bar, |x, y| {
            if (x, y) == (17, 3) {
                Err("bad pixel")
            } else {
                Ok(0u8)
            }
        });
        assert_eq!(r, Err("bad pixel"));
    }

    /// Several tiles fail, the first in tile order last in time: the error
    /// returned is still the first tile's, on every run.
    #[test]
    fn the_first_failed_tile_in_order_names_the_error() {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(4)
            .build()
            .expect("a thread pool");
        let (w, h) = (8 * TILE, 4 * TILE);
        for _ in 0..5 {
            let bar = ProgressBar::hidden();
            let r = pool.install(|| {
                for_each_tile(w, h, &bar, |tile| {
                    let index = (tile.y0 / TILE) * (w / TILE) + tile.x0 / TILE;
                    match index {
                        0..3 => Ok(vec![0u8; tile.len()]),
                        3 => {
                            std::thread::sleep(std::time::Duration::from_millis(30));
                            Err(index)
                        }
                        _ => Err(index),
                    }
                })
            });
            assert_eq!(r, Err(3));
        }
    }

    #[test]
    fn parts_cover_a_tile_once_in_order() {
        let tile = Tile {
            x0: 16,
            y0: 32,
            x1: 29,
            y1: 42,
        };
        let parts: Vec<Tile> = tile.parts(8).collect();
        assert_eq!(
            parts
                .iter()
                .map(|p| (p.x0, p.y0, p.x1, p.y1))
                .collect::<Vec<_>>(),
            [
                (16, 32, 24, 40),
                (24, 32, 29, 40),
                (16, 40, 24, 42),
                (24, 40, 29, 42)
            ]
        );
        let mut seen: Vec<(u32, u32)> = parts.iter().flat_map(|p| p.pixels()).collect();
        assert_eq!(seen.len(), tile.len());
        seen.sort_unstable_by_key(|&(x, y)| (y, x));
        assert_eq!(seen, tile.pixels().collect::<Vec<_>>());
    }
}
