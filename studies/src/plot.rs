//! PNG charts for the measurement commands, drawn with `plotters` and
//! labelled with the crate's own bitmap font ([`render::font`]).
//!
//! `plotters`' text needs a font engine (its `ttf` feature loads system fonts
//! through fontconfig). [`FontBackend`] wraps the bitmap backend and draws
//! every label, tick and caption with the 5×7 font instead, so charts render
//! identically on a machine without any font installed.

use plotters::coord::Shift;
use plotters::prelude::*;
use plotters_backend::text_anchor::{HPos, VPos};
use plotters_backend::{
    BackendColor, BackendCoord, BackendStyle, BackendTextStyle, DrawingErrorKind, FontTransform,
};
use render::font::{ADVANCE, GLYPH_H, GLYPH_W, glyph};
use render::output::PendingFile;

type BitmapError = <BitMapBackend<'static> as DrawingBackend>::ErrorType;

/// A bitmap backend whose text is drawn with the bitmap font.
pub struct FontBackend<'a> {
    inner: BitMapBackend<'a>,
}

impl<'a> FontBackend<'a> {
    /// A backend drawing into `rgb` (`width × height` pixels, RGB8).
    #[must_use]
    pub fn new(rgb: &'a mut [u8], width: u32, height: u32) -> Self {
        Self {
            inner: BitMapBackend::with_buffer(rgb, (width, height)),
        }
    }
}

/// The glyph scale for a plotters font size (about 10 pixels per unit).
fn scale_for(size: f64) -> i32 {
    ((size / 10.0).round() as i32).max(1)
}

/// Unrotated size of `text` at `scale`, in pixels.
fn text_size(text: &str, scale: i32) -> (i32, i32) {
    let n = text.chars().count() as i32;
    (
        ((n * ADVANCE as i32) - 1).max(0) * scale,
        GLYPH_H as i32 * scale,
    )
}

impl DrawingBackend for FontBackend<'_> {
    type ErrorType = BitmapError;

    fn get_size(&self) -> (u32, u32) {
        self.inner.get_size()
    }

    fn ensure_prepared(&mut self) -> Result<(), DrawingErrorKind<BitmapError>> {
        self.inner.ensure_prepared()
    }

    fn present(&mut self) -> Result<(), DrawingErrorKind<BitmapError>> {
        self.inner.present()
    }

    fn draw_pixel(
        &mut self,
        point: BackendCoord,
        color: BackendColor,
    ) -> Result<(), DrawingErrorKind<BitmapError>> {
        self.inner.draw_pixel(point, color)
    }

    fn draw_line<S: BackendStyle>(
        &mut self,
        from: BackendCoord,
        to: BackendCoord,
        style: &S,
    ) -> Result<(), DrawingErrorKind<BitmapError>> {
        self.inner.draw_line(from, to, style)
    }

    fn draw_rect<S: BackendStyle>(
        &mut self,
        upper_left: BackendCoord,
        bottom_right: BackendCoord,
        style: &S,
        fill: bool,
    ) -> Result<(), DrawingErrorKind<BitmapError>> {
        self.inner.draw_rect(upper_left, bottom_right, style, fill)
    }

    fn draw_path<S: BackendStyle, I: IntoIterator<Item = BackendCoord>>(
        &mut self,
        path: I,
        style: &S,
    ) -> Result<(), DrawingErrorKind<BitmapError>> {
        self.inner.draw_path(path, style)
    }

    fn draw_circle<S: BackendStyle>(
        &mut self,
        center: BackendCoord,
        radius: u32,
        style: &S,
        fill: bool,
    ) -> Result<(), DrawingErrorKind<BitmapError>> {
        self.inner.draw_circle(center, radius, style, fill)
    }

    fn fill_polygon<S: BackendStyle, I: IntoIterator<Item = BackendCoord>>(
        &mut self,
        vert: I,
        style: &S,
    ) -> Result<(), DrawingErrorKind<BitmapError>> {
        self.inner.fill_polygon(vert, style)
    }

    fn blit_bitmap(
        &mut self,
        pos: BackendCoord,
        size: (u32, u32),
        src: &[u8],
    ) -> Result<(), DrawingErrorKind<BitmapError>> {
        self.inner.blit_bitmap(pos, size, src)
    }

    fn estimate_text_size<TStyle: BackendTextStyle>(
        &self,
        text: &str,
        style: &TStyle,
    ) -> Result<(u32, u32), DrawingErrorKind<BitmapError>> {
        let (w, h) = text_size(text, scale_for(style.size()));
        Ok((w as u32, h as u32))
    }

    fn draw_text<TStyle: BackendTextStyle>(
        &mut self,
        text: &str,
        style: &TStyle,
        pos: BackendCoord,
    ) -> Result<(), DrawingErrorKind<BitmapError>> {
        let color = style.color();
        if color.alpha == 0.0 {
            return Ok(());
        }
        let scale = scale_for(style.size());
        let (width, height) = text_size(text, scale);
        let dx = match style.anchor().h_pos {
            HPos::Left => 0,
            HPos::Right => -width,
            HPos::Center => -width / 2,
        };
        let dy = match style.anchor().v_pos {
            VPos::Top => 0,
            VPos::Center => -height / 2,
            VPos::Bottom => -height,
        };
        let trans: FontTransform = style.transform();
        let (w, h) = self.get_size();
        for (i, c) in text.chars().enumerate() {
            let gx = i as i32 * ADVANCE as i32 * scale;
            for (row, bits) in glyph(c).iter().enumerate() {
                for col in 0..GLYPH_W {
                    if bits & (0x10 >> col) == 0 {
                        continue;
                    }
                    for sy in 0..scale {
                        for sx in 0..scale {
                            let x = gx + col as i32 * scale + sx + dx;
                            let y = row as i32 * scale + sy + dy;
                            let (x, y) = trans.transform(x, y);
                            let (x, y) = (pos.0 + x, pos.1 + y);
                            if x >= 0 && y >= 0 && (x as u32) < w && (y as u32) < h {
                                self.inner.draw_pixel((x, y), color)?;
                            }
                        }
                    }
                }
            }
        }
        Ok(())
    }
}

/// One named series of points.
#[derive(Clone, Debug, PartialEq)]
pub struct Series {
    /// Legend name.
    pub name: String,
    /// Points `(x, y)` in data coordinates.
    pub points: Vec<(f64, f64)>,
    /// Join the points with lines (else markers only).
    pub line: bool,
}

/// One chart: axes, series and point labels.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Panel {
    /// Caption above the chart.
    pub title: String,
    /// X axis description.
    pub x_label: String,
    /// Y axis description.
    pub y_label: String,
    /// Logarithmic x axis (values must be positive).
    pub x_log: bool,
    /// Logarithmic y axis (values must be positive).
    pub y_log: bool,
    /// The data.
    pub series: Vec<Series>,
    /// Text placed at data coordinates (one label per point, say).
    pub labels: Vec<(f64, f64, String)>,
}

/// A palette that stays apart on white.
pub const PALETTE: [RGBColor; 10] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
    RGBColor(188, 189, 34),
    RGBColor(23, 190, 207),
];

/// Why a chart could not be drawn.
#[derive(Debug, thiserror::Error)]
#[error("drawing the chart: {0}")]
pub struct PlotError(String);

fn plot_err<E: std::fmt::Debug>(e: E) -> PlotError {
    PlotError(format!("{e:?}"))
}

/// Draws `panels` in a grid of `cols` columns, each `panel_w × panel_h`
/// pixels, and returns the RGB8 image `(width, height, pixels)`.
///
/// # Errors
/// [`PlotError`] if plotters refuses a range (no finite data, say).
pub fn draw_panels(
    panels: &[Panel],
    cols: u32,
    panel_w: u32,
    panel_h: u32,
) -> Result<(u32, u32, Vec<u8>), PlotError> {
    let cols = cols.clamp(1, panels.len().max(1) as u32);
    let rows = (panels.len() as u32).div_ceil(cols).max(1);
    let (w, h) = (cols * panel_w, rows * panel_h);
    let mut rgb = vec![255u8; (w * h * 3) as usize];
    {
        let root = FontBackend::new(&mut rgb, w, h).into_drawing_area();
        root.fill(&WHITE).map_err(plot_err)?;
        let areas = root.split_evenly((rows as usize, cols as usize));
        for (panel, area) in panels.iter().zip(&areas) {
            draw_panel(panel, area)?;
        }
        root.present().map_err(plot_err)?;
    }
    Ok((w, h, rgb))
}

/// The data range of one axis, padded, positive for a log axis.
fn range(values: impl Iterator<Item = f64>, log: bool) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in values.filter(|v| v.is_finite() && (!log || *v > 0.0)) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if !(lo <= hi) {
        return if log { (0.1, 10.0) } else { (0.0, 1.0) };
    }
    if log {
        (lo / 1.6, hi * 6.0)
    } else {
        let pad = ((hi - lo) * 0.08).max(hi.abs() * 0.05).max(1e-9);
        (
            (lo - pad).min(if lo >= 0.0 { 0.0 } else { lo - pad }),
            hi + pad,
        )
    }
}

fn draw_panel(panel: &Panel, area: &DrawingArea<FontBackend<'_>, Shift>) -> Result<(), PlotError> {
    let xs = panel
        .series
        .iter()
        .flat_map(|s| s.points.iter().map(|p| p.0));
    let ys = panel
        .series
        .iter()
        .flat_map(|s| s.points.iter().map(|p| p.1));
    let (x0, x1) = range(xs, panel.x_log);
    let (y0, y1) = range(ys, panel.y_log);
    let mut builder = ChartBuilder::on(area);
    builder
        .caption(&panel.title, ("sans-serif", 20))
        .margin(12)
        .x_label_area_size(44)
        .y_label_area_size(64);
    // The four axis combinations are four chart types.
    macro_rules! body {
        ($chart:expr) => {{
            let mut chart = $chart;
            chart
                .configure_mesh()
                .x_desc(panel.x_label.as_str())
                .y_desc(panel.y_label.as_str())
                .label_style(("sans-serif", 10))
                .axis_desc_style(("sans-serif", 10))
                .x_labels(8)
                .y_labels(8)
                .light_line_style(RGBColor(235, 235, 235))
                .draw()
                .map_err(plot_err)?;
            for (i, s) in panel.series.iter().enumerate() {
                let colour = PALETTE[i % PALETTE.len()];
                let pts: Vec<(f64, f64)> = s
                    .points
                    .iter()
                    .copied()
                    .filter(|p| p.0.is_finite() && p.1.is_finite())
                    .collect();
                if s.line {
                    chart
                        .draw_series(LineSeries::new(
                            pts.clone(),
                            Color::stroke_width(&colour, 2),
                        ))
                        .map_err(plot_err)?;
                }
                chart
                    .draw_series(pts.iter().map(|&p| Circle::new(p, 4, colour.filled())))
                    .map_err(plot_err)?
                    .label(s.name.as_str())
                    .legend(move |(x, y)| Circle::new((x + 6, y), 4, colour.filled()));
            }
            for (x, y, text) in &panel.labels {
                chart
                    .draw_series(std::iter::once(Text::new(
                        text.clone(),
                        (*x, *y),
                        ("sans-serif", 10).into_font().color(&BLACK),
                    )))
                    .map_err(plot_err)?;
            }
            if panel.series.len() > 1 {
                chart
                    .configure_series_labels()
                    .background_style(WHITE.mix(0.85))
                    .border_style(RGBColor(180, 180, 180))
                    .label_font(("sans-serif", 10))
                    .position(SeriesLabelPosition::LowerRight)
                    .draw()
                    .map_err(plot_err)?;
            }
        }};
    }
    match (panel.x_log, panel.y_log) {
        (false, false) => body!(
            builder
                .build_cartesian_2d(x0..x1, y0..y1)
                .map_err(plot_err)?
        ),
        (true, false) => {
            body!(
                builder
                    .build_cartesian_2d((x0..x1).log_scale(), y0..y1)
                    .map_err(plot_err)?
            )
        }
        (false, true) => {
            body!(
                builder
                    .build_cartesian_2d(x0..x1, (y0..y1).log_scale())
                    .map_err(plot_err)?
            )
        }
        (true, true) => body!(
            builder
                .build_cartesian_2d((x0..x1).log_scale(), (y0..y1).log_scale())
                .map_err(plot_err)?
        ),
    }
    Ok(())
}

/// Writes `csv` to `csv_out`, then `panels` (two columns of 640 × 480
/// pixels) as a PNG to `plot_out`, and says `wrote …` for each: the end of
/// `studies tradeoff` and `studies sweep-density`.
///
/// # Errors
/// A file that cannot be written, or [`PlotError`].
pub fn write_csv_and_plot(
    csv_out: PendingFile,
    csv: &str,
    plot_out: PendingFile,
    panels: &[Panel],
) -> anyhow::Result<()> {
    let dest = csv_out.dest().display().to_string();
    csv_out.write_all(csv.as_bytes())?;
    println!("wrote {dest}");
    let (w, h, rgb) = draw_panels(panels, 2, 640, 480)?;
    let dest = plot_out.dest().display().to_string();
    plot_out.write_png(w, h, &rgb)?;
    println!("wrote {dest}");
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn charts_draw_text_without_a_font_engine() {
        let panel = Panel {
            title: "Throughput against error".into(),
            x_label: "error (%)".into(),
            y_label: "Mrays/s".into(),
            x_log: true,
            series: vec![
                Series {
                    name: "grid".into(),
                    points: vec![(0.01, 1.0), (0.1, 2.0), (1.0, 3.0)],
                    line: true,
                },
                Series {
                    name: "kdtree".into(),
                    points: vec![(0.02, 2.5)],
                    line: false,
                },
            ],
            labels: vec![(0.1, 2.0, "m=2".into())],
            ..Panel::default()
        };
        let (w, h, rgb) = draw_panels(&[panel.clone(), panel], 2, 320, 240).unwrap();
        assert_eq!((w, h), (640, 240));
        // The caption row holds dark (text) pixels; a blank chart would not.
        let dark_in_caption = (0..30u32)
            .flat_map(|y| (0..w).map(move |x| (x, y)))
            .filter(|&(x, y)| rgb[3 * (y * w + x) as usize] < 100)
            .count();
        assert!(dark_in_caption > 50, "{dark_in_caption} dark pixels");
        // Both series colours appear.
        let has = |c: RGBColor| rgb.chunks(3).any(|p| p == [c.0, c.1, c.2]);
        assert!(has(PALETTE[0]) && has(PALETTE[1]));
    }

    #[test]
    fn ranges_pad_and_respect_log_axes() {
        let (lo, hi) = range([1.0, 10.0].into_iter(), true);
        assert!(lo > 0.0 && lo < 1.0 && hi > 10.0);
        let (lo, hi) = range([0.0, -1.0, f64::NAN].into_iter(), true);
        assert_eq!((lo, hi), (0.1, 10.0));
        let (lo, hi) = range([2.0, 4.0].into_iter(), false);
        assert!(lo <= 0.0 && hi > 4.0);
    }
}
