//! The image in square tiles, traced in parallel with rayon, with a progress
//! bar on stderr (hidden when stderr is not a terminal).

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use rayon::prelude::*;

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

/// Calls `f(x, y)` for every pixel of a `width × height` image, tile by tile
/// in parallel, and returns the results row by row.
///
/// # Errors
/// The first error of `f` met (in tile order); the other tiles may or may not
/// have run.
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
    let tiles_x = width.div_ceil(TILE);
    let tiles_y = height.div_ceil(TILE);
    let tiles: Vec<(u32, u32)> = (0..tiles_y)
        .flat_map(|ty| (0..tiles_x).map(move |tx| (tx * TILE, ty * TILE)))
        .collect();
    let done: Vec<Vec<P>> = tiles
        .par_iter()
        .map(|&(x0, y0)| {
            let x1 = (x0 + TILE).min(width);
            let y1 = (y0 + TILE).min(height);
            let mut out = Vec::with_capacity(((x1 - x0) * (y1 - y0)) as usize);
            for y in y0..y1 {
                for x in x0..x1 {
                    out.push(f(x, y)?);
                }
            }
            progress.inc(out.len() as u64);
            Ok(out)
        })
        .collect::<Result<_, E>>()?;
    let mut image = vec![P::default(); width as usize * height as usize];
    for (&(x0, y0), tile) in tiles.iter().zip(&done) {
        let w = ((x0 + TILE).min(width) - x0) as usize;
        for (row, chunk) in tile.chunks(w).enumerate() {
            let start = (y0 as usize + row) * width as usize + x0 as usize;
            image[start..start + w].copy_from_slice(chunk);
        }
    }
    Ok(image)
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
}
