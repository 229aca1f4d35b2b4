//! Heat maps of traversal cost: where each accelerator works hard.
//!
//! Two panels side by side, from the `*_counted` queries of the primary rays:
//! cells or nodes visited per ray (left) and primitive tests per ray (right),
//! each averaged over a pixel's samples. Colours follow the turbo colour map
//! on a logarithmic scale (`ln(1 + v) / ln(1 + max)`), since costs span orders
//! of magnitude; a legend under each panel names the quantity and labels the
//! scale.

use crate::font::{GLYPH_H, draw_text, text_width};
use accel_core::TraversalCounters;

/// An 8-bit RGB image.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RgbImage {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Row-major RGB bytes.
    pub rgb: Vec<u8>,
}

/// Means and maxima of the cost per primary ray.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct HeatStats {
    /// Mean cells or nodes visited per primary ray.
    pub mean_nodes: f64,
    /// Most cells or nodes visited per ray in one pixel (averaged over its samples).
    pub max_nodes: f64,
    /// Mean primitive tests per primary ray.
    pub mean_tests: f64,
    /// Most primitive tests per ray in one pixel.
    pub max_tests: f64,
}

/// The turbo colour map (Mikhailov 2019, polynomial fit), `x` in `[0, 1]`.
#[must_use]
pub fn turbo(x: f64) -> [u8; 3] {
    let x = x.clamp(0.0, 1.0);
    let poly = |c: [f64; 6]| c[0] + x * (c[1] + x * (c[2] + x * (c[3] + x * (c[4] + x * c[5]))));
    let r = poly([
        0.135_721_38,
        4.615_392_6,
        -42.660_322_58,
        132.131_082_34,
        -152.942_393_96,
        59.286_379_43,
    ]);
    let g = poly([
        0.091_402_61,
        2.194_188_39,
        4.842_966_58,
        -14.185_033_33,
        4.277_298_57,
        2.829_566_04,
    ]);
    let b = poly([
        0.106_673_3,
        12.641_946_08,
        -60.582_048_36,
        110.362_767_71,
        -89.903_109_12,
        27.348_249_73,
    ]);
    [r, g, b].map(|c| (c.clamp(0.0, 1.0) * 255.0 + 0.5) as u8)
}

/// Position of `v` on the logarithmic scale up to `max`.
fn scale_pos(v: f64, max: f64) -> f64 {
    if max <= 0.0 {
        0.0
    } else {
        (v.max(0.0).ln_1p() / max.ln_1p()).min(1.0)
    }
}

/// The value at position `pos` of the scale up to `max` (inverse of [`scale_pos`]).
fn scale_value(pos: f64, max: f64) -> f64 {
    (pos * max.ln_1p()).exp_m1()
}

/// A short label: `7`, `2.5`, `120`, `3.4k`, `1.2M`.
#[must_use]
pub fn label(v: f64) -> String {
    if v < 10.0 {
        let s = format!("{v:.1}");
        s.strip_suffix(".0").map_or(s.clone(), str::to_owned)
    } else if v < 1e3 {
        format!("{v:.0}")
    } else if v < 1e6 {
        format!("{:.1}k", v / 1e3)
    } else {
        format!("{:.1}M", v / 1e6)
    }
}

/// Font scale for a panel of this width.
fn font_scale(width: u32) -> u32 {
    if width >= 320 { 2 } else { 1 }
}

/// Height of the legend under a panel.
fn legend_height(scale: u32) -> u32 {
    // caption, gap, bar, gap, labels, margins
    4 + GLYPH_H * scale + 3 + 8 * scale + 3 + GLYPH_H * scale + 4
}

const GAP: u32 = 4;
const BACKGROUND: [u8; 3] = [24, 24, 28];
const INK: [u8; 3] = [235, 235, 235];

/// Draws one panel (values row-major, `w × h`) with its legend at column `x0`.
fn draw_panel(img: &mut RgbImage, x0: u32, w: u32, h: u32, values: &[f64], caption: &str) {
    let max = values.iter().copied().fold(0.0, f64::max);
    for y in 0..h {
        for x in 0..w {
            let v = values[(y * w + x) as usize];
            let at = 3 * (y as usize * img.width as usize + (x0 + x) as usize);
            img.rgb[at..at + 3].copy_from_slice(&turbo(scale_pos(v, max)));
        }
    }
    let s = font_scale(w);
    let (iw, ih) = (img.width, img.height);
    let mut y = h + 4;
    draw_text(&mut img.rgb, iw, ih, (x0 + 2 * s, y), caption, s, INK);
    y += GLYPH_H * s + 3;
    let bar_h = 8 * s;
    for x in 0..w {
        let c = turbo(f64::from(x) / f64::from((w - 1).max(1)));
        for dy in 0..bar_h {
            let at = 3 * ((y + dy) as usize * iw as usize + (x0 + x) as usize);
            img.rgb[at..at + 3].copy_from_slice(&c);
        }
    }
    y += bar_h + 3;
    // Labels at 0, 1 (the maximum), then ½, ¼ and ¾ of the bar where they fit.
    let mut placed: Vec<(u32, u32)> = Vec::new();
    for k in [0u32, 4, 2, 1, 3] {
        let pos = f64::from(k) / 4.0;
        let text = label(scale_value(pos, max));
        let tw = text_width(&text, s);
        let margin = 2 * s;
        if tw + 2 * margin > w {
            continue;
        }
        let centre = x0 + (pos * f64::from(w - 1)) as u32;
        let left = centre
            .saturating_sub(tw / 2)
            .clamp(x0 + margin, x0 + w - tw - margin);
        let right = left + tw;
        if placed
            .iter()
            .any(|&(l, r)| left < r + 3 * s && l < right + 3 * s)
        {
            continue;
        }
        draw_text(&mut img.rgb, iw, ih, (left, y), &text, s, INK);
        placed.push((left, right));
    }
}

/// The heat map of a `width × height` render with `spp` samples per pixel,
/// from each pixel's summed primary-ray work.
///
/// # Panics
/// If `work.len() != width × height` (the renderer's contract).
#[must_use]
pub fn heat_map(
    width: u32,
    height: u32,
    spp: u32,
    work: &[TraversalCounters],
) -> (RgbImage, HeatStats) {
    assert_eq!(work.len(), width as usize * height as usize);
    let per_ray = 1.0 / f64::from(spp.max(1));
    let nodes: Vec<f64> = work.iter().map(|c| c.nodes as f64 * per_ray).collect();
    let tests: Vec<f64> = work.iter().map(|c| c.prims as f64 * per_ray).collect();
    let n = nodes.len().max(1) as f64;
    let stats = HeatStats {
        mean_nodes: nodes.iter().sum::<f64>() / n,
        max_nodes: nodes.iter().copied().fold(0.0, f64::max),
        mean_tests: tests.iter().sum::<f64>() / n,
        max_tests: tests.iter().copied().fold(0.0, f64::max),
    };
    let s = font_scale(width);
    let total_w = 2 * width + GAP;
    let total_h = height + legend_height(s);
    let mut img = RgbImage {
        width: total_w,
        height: total_h,
        rgb: BACKGROUND
            .iter()
            .copied()
            .cycle()
            .take(3 * total_w as usize * total_h as usize)
            .collect(),
    };
    draw_panel(&mut img, 0, width, height, &nodes, "primary nodes/ray");
    draw_panel(
        &mut img,
        width + GAP,
        width,
        height,
        &tests,
        "primary tests/ray",
    );
    (img, stats)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn turbo_runs_from_dark_through_blue_to_red() {
        let lo = turbo(0.0);
        let blue = turbo(0.15);
        let hi = turbo(1.0);
        assert!(lo.iter().all(|&c| c < 60), "{lo:?}");
        assert!(blue[2] > blue[0] && blue[2] > blue[1], "{blue:?}");
        assert!(hi[0] > hi[1] && hi[0] > hi[2], "{hi:?}");
        assert_eq!(turbo(-5.0), lo);
        assert_eq!(turbo(7.0), hi);
    }

    #[test]
    fn scale_is_logarithmic_and_invertible() {
        assert_eq!(scale_pos(0.0, 100.0), 0.0);
        assert_eq!(scale_pos(100.0, 100.0), 1.0);
        assert!((scale_pos(9.0, 99.0) - 0.5).abs() < 1e-12);
        for v in [0.0, 1.0, 37.0, 100.0] {
            assert!((scale_value(scale_pos(v, 100.0), 100.0) - v).abs() < 1e-9);
        }
        assert_eq!(scale_pos(5.0, 0.0), 0.0);
    }

    #[test]
    fn labels_are_short() {
        assert_eq!(label(0.0), "0");
        assert_eq!(label(2.5), "2.5");
        assert_eq!(label(120.4), "120");
        assert_eq!(label(3_400.0), "3.4k");
        assert_eq!(label(1_250_000.0), "1.2M");
    }

    #[test]
    fn panels_show_the_costs_and_a_legend() {
        let (w, h) = (40, 10);
        let mut work = vec![TraversalCounters::default(); (w * h) as usize];
        // One expensive pixel at (5, 5); tests twice the nodes everywhere.
        for (i, c) in work.iter_mut().enumerate() {
            c.nodes = 2 + u64::from(i == 5 * w as usize + 5) * 198;
            c.prims = 2 * c.nodes;
        }
        let (img, stats) = heat_map(w, h, 2, &work);
        assert_eq!(img.width, 2 * w + GAP);
        assert!(img.height > h);
        assert_eq!(stats.max_nodes, 100.0);
        assert_eq!(stats.max_tests, 200.0);
        assert!((stats.mean_nodes - (1.0 + 99.0 / 400.0)).abs() < 1e-12);
        let px = |x: u32, y: u32| {
            let at = 3 * (y * img.width + x) as usize;
            [img.rgb[at], img.rgb[at + 1], img.rgb[at + 2]]
        };
        // The hot pixel is the maximum colour in both panels, the rest is not.
        assert_eq!(px(5, 5), turbo(1.0));
        assert_eq!(px(w + GAP + 5, 5), turbo(1.0));
        assert_ne!(px(6, 5), turbo(1.0));
        // The legend's bar runs from the lowest to the highest colour, and
        // some label text was drawn in the legend area.
        let bar_y = h + 4 + GLYPH_H + 3;
        assert_eq!(px(0, bar_y), turbo(0.0));
        assert_eq!(px(w - 1, bar_y), turbo(1.0));
        let ink = (h..img.height)
            .flat_map(|y| (0..img.width).map(move |x| (x, y)))
            .filter(|&(x, y)| px(x, y) == INK)
            .count();
        assert!(ink > 20, "{ink} ink pixels");
    }
}
