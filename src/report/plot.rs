//! PNG figures: a grid of panels, each with x–y series drawn as lines, dashed lines or dots,
//! and axis labels; one legend for the whole figure, in a band under its title, off the data.
//! A series' colour follows its name, so a case has the same colour in every panel.
//!
//! Text is rasterised by `plotters`' `ab_glyph` backend from a TrueType file read at run time
//! (DejaVu Sans, Debian package `fonts-dejavu-core`), so no system font service is involved.
//! Every failure, a missing font included, is returned as a [`PlotError`] naming the output
//! file; nothing here panics on odd data (empty series, one point, constant values, NaN).

use std::io;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::{Path, PathBuf};
use std::sync::{Arc, OnceLock};

use plotters::coord::Shift;
use plotters::element::DashedPathElement;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use plotters::style::{register_font, FontStyle};

/// A failed drawing call of plotters' bitmap backend.
pub type DrawError = DrawingAreaErrorKind<<BitMapBackend<'static> as DrawingBackend>::ErrorType>;

/// Why a figure was not written. Every variant names the figure's file (`path`).
#[derive(Debug, thiserror::Error)]
pub enum PlotError {
    /// No panels were given.
    #[error("{}: no panels to plot", .path.display())]
    NoPanels {
        /// The figure's file.
        path: PathBuf,
    },
    /// More rows of panels than a figure may have.
    #[error("{}: {rows} rows of panels is more than the {MAX_ROWS} a figure may have", .path.display())]
    TooManyRows {
        /// The figure's file.
        path: PathBuf,
        /// Rows the panels would fill.
        rows: usize,
    },
    /// No usable font for the text.
    #[error("{}: no font for the text", .path.display())]
    Font {
        /// The figure's file.
        path: PathBuf,
        /// Why the font could not be used (kept from the first figure of the process).
        source: Arc<FontError>,
    },
    /// The figure's folder is missing or not a folder.
    #[error("{}: folder {} {problem}", .path.display(), .folder.display())]
    Folder {
        /// The figure's file.
        path: PathBuf,
        /// Its folder.
        folder: PathBuf,
        /// "does not exist" or "is not a folder".
        problem: &'static str,
    },
    /// The temporary file to draw into could not be created.
    #[error("{}: cannot create a temporary file in {}", .path.display(), .folder.display())]
    TempFile {
        /// The figure's file.
        path: PathBuf,
        /// Its folder, where the temporary file goes.
        folder: PathBuf,
        /// The file system's error.
        source: io::Error,
    },
    /// A drawing call failed.
    #[error("{}: drawing {place} failed", .path.display())]
    Draw {
        /// The figure's file.
        path: PathBuf,
        /// What was drawn: "the title", "panel \"…\"", ….
        place: String,
        /// plotters' error.
        source: DrawError,
    },
    /// plotters panicked while drawing.
    #[error("{}: plotting failed: {message}", .path.display())]
    Panicked {
        /// The figure's file.
        path: PathBuf,
        /// The panic's message.
        message: String,
    },
    /// The drawn figure could not be saved under its name.
    #[error("{}: cannot save the figure", .path.display())]
    Save {
        /// The figure's file.
        path: PathBuf,
        /// The file system's error.
        source: io::Error,
    },
}

/// Why the text font could not be used.
#[derive(Debug, thiserror::Error)]
pub enum FontError {
    /// None of the places a font may be held a readable file.
    #[error("no font for plot text ({}); install the Debian package fonts-dejavu-core", tried_text(.tried))]
    Missing {
        /// Each place tried and why it could not be read.
        tried: Vec<(PathBuf, io::Error)>,
    },
    /// The file is no TrueType font plotters can use.
    #[error("font {} is not a usable TrueType font", .path.display())]
    Unusable {
        /// The font file.
        path: PathBuf,
    },
}

/// The places tried for a font and their errors, for [`FontError::Missing`].
fn tried_text(tried: &[(PathBuf, io::Error)]) -> String {
    tried.iter().map(|(path, e)| format!("{}: {e}", path.display())).collect::<Vec<_>>().join("; ")
}

/// How a series is drawn.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Style {
    /// A solid line through the points in their order (broken where a point is NaN or infinite).
    Line,
    /// A dashed line through the points in their order (broken like [`Style::Line`]).
    Dashed,
    /// A dot at each point, unconnected.
    Points,
}

/// One named curve of a panel.
#[derive(Clone, Debug, PartialEq)]
pub struct Series {
    /// Legend entry; an empty name leaves the series out of the legend.
    pub name: String,
    /// `(x, y)` points in the panel's axis units. Points with a NaN or infinite coordinate, or one
    /// beyond ±1e100, are skipped (a line is broken there).
    pub points: Vec<(f64, f64)>,
    /// How the points are drawn.
    pub style: Style,
}

/// One plot of a figure: axes, labels and the series drawn in it.
#[derive(Clone, Debug, PartialEq)]
pub struct Panel {
    /// Caption above the plot.
    pub title: String,
    /// Horizontal axis label, units included (e.g. `"t [s]"`).
    pub x_label: String,
    /// Vertical axis label, units included (e.g. `"τ [N·m]"`).
    pub y_label: String,
    /// The curves, drawn in order (later ones on top); series of the same name share a
    /// colour across the figure.
    pub series: Vec<Series>,
}

/// Figure width, pixels.
const WIDTH: u32 = 1000;
/// Height of one row of panels, pixels.
const ROW_HEIGHT: u32 = 320;
/// Height of the band holding the figure title, pixels (none when the title is blank).
const TITLE_HEIGHT: u32 = 44;
/// Most panel rows in one figure (keeps the bitmap below ~50 MB).
const MAX_ROWS: usize = 50;
/// Coordinates beyond this magnitude are not plotted (keeps axis spans finite).
const LIMIT: f64 = 1e100;
/// Font family name the text styles below ask for; the TTF is registered under it.
const FAMILY: &str = "sans-serif";

/// Where the regular font may be: Debian/Ubuntu (`fonts-dejavu-core`), Arch, Fedora.
const REGULAR_FONTS: [&str; 3] = [
    "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf",
    "/usr/share/fonts/TTF/DejaVuSans.ttf",
    "/usr/share/fonts/dejavu-sans-fonts/DejaVuSans.ttf",
];
/// Where the bold font may be; optional (titles fall back to the regular face).
const BOLD_FONTS: [&str; 3] = [
    "/usr/share/fonts/truetype/dejavu/DejaVuSans-Bold.ttf",
    "/usr/share/fonts/TTF/DejaVuSans-Bold.ttf",
    "/usr/share/fonts/dejavu-sans-fonts/DejaVuSans-Bold.ttf",
];

/// Series colours, cycled: ten well-separated hues.
const PALETTE: [RGBColor; 10] = [
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

/// Writes a PNG of the panels in a grid of `columns` (0 counts as 1), row by row, under `title`
/// (if not blank) and one legend of the named series, in order of first appearance. Each row is
/// `ROW_HEIGHT` px tall, the figure `WIDTH` px wide; each axis spans its panel's data with a 5 %
/// margin. Always PNG, whatever `path`'s extension, written atomically (a temporary file in the
/// same folder, renamed over `path`), so a failure leaves no partial file. Errors, each naming
/// `path`: no panels, more than `MAX_ROWS` rows, the folder missing or not writable, no usable
/// font (install Debian's `fonts-dejavu-core`), or a drawing failure.
pub fn write_png(path: &Path, title: &str, panels: &[Panel], columns: usize) -> Result<(), PlotError> {
    let named = || path.to_path_buf();
    if panels.is_empty() {
        return Err(PlotError::NoPanels { path: named() });
    }
    let columns = columns.clamp(1, panels.len());
    let rows = panels.len().div_ceil(columns);
    if rows > MAX_ROWS {
        return Err(PlotError::TooManyRows { path: named(), rows });
    }
    ensure_font().map_err(|source| PlotError::Font { path: named(), source })?;

    let dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    if !dir.is_dir() {
        let problem = if dir.exists() { "is not a folder" } else { "does not exist" };
        return Err(PlotError::Folder { path: named(), folder: dir.to_path_buf(), problem });
    }
    // The suffix matters: the bitmap backend picks the image format from the extension.
    let tmp = crate::table::readable_temp_file()
        .prefix(".neurarm-")
        .suffix(".png")
        .tempfile_in(dir)
        .map_err(|source| PlotError::TempFile { path: named(), folder: dir.to_path_buf(), source })?;

    // plotters has internal unwraps; keep a surprise there from taking the caller down.
    let rendered = catch_unwind(AssertUnwindSafe(|| render(tmp.path(), title, panels, columns, rows)));
    match rendered {
        Ok(result) => result.map_err(|DrawFailure { place, source }| PlotError::Draw { path: named(), place, source })?,
        Err(payload) => return Err(PlotError::Panicked { path: named(), message: panic_text(payload.as_ref()) }),
    }
    tmp.as_file().sync_all().map_err(|source| PlotError::Save { path: named(), source })?;
    tmp.persist(path).map_err(|e| PlotError::Save { path: named(), source: e.error })?;
    Ok(())
}

/// One legend entry: a series name, its style and its palette index.
struct Entry {
    name: String,
    style: Style,
    colour: usize,
}

/// The legend of `panels`: each named series once, in order of first appearance.
fn legend_entries(panels: &[Panel]) -> Vec<Entry> {
    let mut entries: Vec<Entry> = Vec::new();
    for s in panels.iter().flat_map(|p| &p.series) {
        if !s.name.is_empty() && !entries.iter().any(|e| e.name == s.name) {
            entries.push(Entry { name: s.name.clone(), style: s.style, colour: entries.len() });
        }
    }
    entries
}

/// Pixel width of a legend entry: its mark, its text (≈ 7.5 px per character at 13 px) and a gap.
fn entry_width(e: &Entry) -> i32 {
    40 + (e.name.chars().count() as f64 * 7.5) as i32
}

/// Lines the legend takes when laid out over the figure's width.
fn legend_lines(entries: &[Entry]) -> usize {
    let (mut lines, mut x) = (usize::from(!entries.is_empty()), 10);
    for e in entries {
        if x + entry_width(e) > WIDTH as i32 - 10 && x > 10 {
            lines += 1;
            x = 10;
        }
        x += entry_width(e);
    }
    lines
}

/// Height of one legend line, pixels.
const LEGEND_LINE: u32 = 24;

/// A drawing call that failed in [`render`], and the part of the figure it drew.
struct DrawFailure {
    /// "the title", "panel \"…\"", ….
    place: String,
    /// plotters' error.
    source: DrawError,
}

/// Wraps a drawing error of `place` for [`render`].
fn drawing(place: impl Into<String>) -> impl FnOnce(DrawError) -> DrawFailure {
    move |source| DrawFailure { place: place.into(), source }
}

/// Draws the whole figure into `file` (a `.png` path).
fn render(file: &Path, title: &str, panels: &[Panel], columns: usize, rows: usize) -> Result<(), DrawFailure> {
    let entries = legend_entries(panels);
    let title_height = if title.trim().is_empty() { 0 } else { TITLE_HEIGHT };
    let legend_height = LEGEND_LINE * legend_lines(&entries) as u32 + if entries.is_empty() { 0 } else { 8 };
    let height = title_height + legend_height + ROW_HEIGHT * rows as u32;
    let root = BitMapBackend::new(file, (WIDTH, height)).into_drawing_area();
    root.fill(&WHITE).map_err(drawing("the background"))?;
    let body = if title_height > 0 {
        let (band, rest) = root.split_vertically(title_height);
        let style = TextStyle::from((FAMILY, 24, FontStyle::Bold)).pos(Pos::new(HPos::Center, VPos::Center));
        band.draw_text(title.trim(), &style, (WIDTH as i32 / 2, title_height as i32 / 2)).map_err(drawing("the title"))?;
        rest
    } else {
        root.clone()
    };
    let body = if legend_height > 0 {
        let (band, rest) = body.split_vertically(legend_height);
        draw_legend(&band, &entries).map_err(drawing("the legend"))?;
        rest
    } else {
        body
    };
    for (panel, area) in panels.iter().zip(body.split_evenly((rows, columns))) {
        draw_panel(&area, panel, &entries).map_err(drawing(format!("panel \"{}\"", panel.title)))?;
    }
    root.present().map_err(drawing("the bitmap into its file"))?;
    Ok(())
}

/// Draws the legend entries into `band`, flowing over lines.
fn draw_legend(band: &DrawingArea<BitMapBackend<'_>, Shift>, entries: &[Entry]) -> Result<(), DrawError> {
    let style = TextStyle::from((FAMILY, 13)).pos(Pos::new(HPos::Left, VPos::Center));
    let (mut x, mut y) = (10, LEGEND_LINE as i32 / 2 + 2);
    for e in entries {
        if x + entry_width(e) > WIDTH as i32 - 10 && x > 10 {
            x = 10;
            y += LEGEND_LINE as i32;
        }
        let colour = PALETTE[e.colour % PALETTE.len()];
        band.draw(&legend_mark(e.style, (x, y), colour.stroke_width(2), colour.filled()))?;
        band.draw_text(&e.name, &style, (x + 28, y))?;
        x += entry_width(e);
    }
    Ok(())
}

/// Draws one panel (axes, mesh, series) into `area`; colours from the figure's `legend`.
fn draw_panel(area: &DrawingArea<BitMapBackend<'_>, Shift>, panel: &Panel, legend: &[Entry]) -> Result<(), DrawError> {
    let runs: Vec<Vec<Vec<(f64, f64)>>> = panel.series.iter().map(|s| plottable_runs(&s.points)).collect();
    let all = || runs.iter().flatten().flatten();
    let (x0, x1) = axis_range(all().map(|p| p.0));
    let (y0, y1) = axis_range(all().map(|p| p.1));

    let mut chart = ChartBuilder::on(area)
        .caption(&panel.title, (FAMILY, 17, FontStyle::Bold))
        .margin(10)
        .x_label_area_size(44)
        .y_label_area_size(70)
        .build_cartesian_2d(x0..x1, y0..y1)?;
    let x_ticks = tick_format(x0, x1);
    let y_ticks = tick_format(y0, y1);
    chart
        .configure_mesh()
        .x_desc(panel.x_label.as_str())
        .y_desc(panel.y_label.as_str())
        .x_label_formatter(&x_ticks)
        .y_label_formatter(&y_ticks)
        .x_labels(8)
        .y_labels(6)
        .label_style((FAMILY, 13))
        .axis_desc_style((FAMILY, 15))
        .bold_line_style(RGBColor(215, 215, 215))
        .light_line_style(RGBColor(242, 242, 242))
        .draw()?;

    for (i, (series, runs)) in panel.series.iter().zip(&runs).enumerate() {
        let index = legend.iter().find(|e| !series.name.is_empty() && e.name == series.name).map_or(legend.len() + i, |e| e.colour);
        let colour = PALETTE[index % PALETTE.len()];
        let line = colour.stroke_width(2);
        let dot = colour.filled();
        match series.style {
            Style::Line => chart.draw_series(runs.iter().map(|run| PathElement::new(run.clone(), line))),
            Style::Dashed => chart.draw_series(runs.iter().map(|run| DashedPathElement::new(run.clone(), 8, 5, line))),
            Style::Points => chart.draw_series(runs.iter().flatten().map(|&p| Circle::new(p, 2, dot))),
        }?;
        // A run of one point draws no line: mark it so it is not lost.
        if series.style != Style::Points {
            let lone = runs.iter().filter(|run| run.len() == 1).map(|run| Circle::new(run[0], 3, dot));
            chart.draw_series(lone)?;
        }
    }
    Ok(())
}

/// The legend sample for a series: a short line, dashed line or dot at backend pixel `(x, y)`.
fn legend_mark<DB: DrawingBackend>(
    style: Style,
    (x, y): (i32, i32),
    line: ShapeStyle,
    dot: ShapeStyle,
) -> DynElement<'static, DB, (i32, i32)> {
    match style {
        Style::Line => PathElement::new(vec![(x, y), (x + 22, y)], line).into_dyn(),
        Style::Dashed => DashedPathElement::new(vec![(x, y), (x + 22, y)], 6, 4, line).into_dyn(),
        Style::Points => Circle::new((x + 11, y), 3, dot).into_dyn(),
    }
}

/// Splits `points` into runs of plottable points (finite, within ±[`LIMIT`]); each point that
/// is not plottable ends a run. Empty runs are dropped.
fn plottable_runs(points: &[(f64, f64)]) -> Vec<Vec<(f64, f64)>> {
    let ok = |v: f64| v.is_finite() && v.abs() <= LIMIT;
    let mut runs = Vec::new();
    let mut run = Vec::new();
    for &(x, y) in points {
        if ok(x) && ok(y) {
            run.push((x, y));
        } else if !run.is_empty() {
            runs.push(std::mem::take(&mut run));
        }
    }
    if !run.is_empty() {
        runs.push(run);
    }
    runs
}

/// Axis limits for `values` (all finite, within ±[`LIMIT`]): their span plus 5 % each side; a
/// band of ±5 % (at least ±0.5) around constant values; 0–1 when there are none.
fn axis_range(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) = values.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| (lo.min(v), hi.max(v)));
    if lo > hi {
        return (0.0, 1.0);
    }
    let span = hi - lo;
    let magnitude = lo.abs().max(hi.abs());
    if span <= magnitude * 1e-12 {
        let centre = 0.5 * (lo + hi);
        let half = (centre.abs() * 0.05).max(0.5);
        return (centre - half, centre + half);
    }
    let pad = 0.05 * span;
    (lo - pad, hi + pad)
}

/// A tick-label formatter for an axis from `lo` to `hi`: plain decimals with as many places as the
/// tick spacing needs (trailing zeros dropped), scientific notation for very large or very small
/// magnitudes.
fn tick_format(lo: f64, hi: f64) -> impl Fn(&f64) -> String {
    let span = hi - lo;
    let magnitude = lo.abs().max(hi.abs());
    // Ticks are at most ~10 per axis at multiples of 1, 2 or 5 × 10^k.
    let places = (-(span / 10.0).log10().floor()).clamp(0.0, 15.0) as usize;
    let scientific = magnitude >= 1e6 || places > 5;
    move |&v: &f64| {
        if v == 0.0 || (v.abs() < span * 1e-9) {
            "0".to_string()
        } else if scientific {
            let text = format!("{v:.3e}");
            match text.split_once('e') {
                Some((mantissa, exponent)) => format!("{}e{exponent}", trim_zeros(mantissa)),
                None => text,
            }
        } else {
            trim_zeros(&format!("{v:.places$}")).to_string()
        }
    }
}

/// `text` without the trailing zeros of its fraction (and the point, if nothing is left of it).
fn trim_zeros(text: &str) -> &str {
    if text.contains('.') {
        text.trim_end_matches('0').trim_end_matches('.')
    } else {
        text
    }
}

/// Text of a panic payload.
fn panic_text(payload: &(dyn std::any::Any + Send)) -> String {
    if let Some(s) = payload.downcast_ref::<&str>() {
        (*s).to_string()
    } else if let Some(s) = payload.downcast_ref::<String>() {
        s.clone()
    } else {
        "panic in the plotting library".to_string()
    }
}

/// Registers the text font with plotters once per process. The outcome, failure included, is
/// kept: the font file is read (and its bytes leaked, as plotters needs them `'static`) once.
fn ensure_font() -> Result<(), Arc<FontError>> {
    static OUTCOME: OnceLock<Result<(), Arc<FontError>>> = OnceLock::new();
    OUTCOME
        .get_or_init(|| {
            let (path, bytes) = read_font(&REGULAR_FONTS.map(Path::new))?;
            register_font(FAMILY, FontStyle::Normal, bytes).map_err(|_| FontError::Unusable { path })?;
            // Bold is a nicety: without it plotters falls back to the regular face.
            if let Ok((_, bold)) = read_font(&BOLD_FONTS.map(Path::new)) {
                let _ = register_font(FAMILY, FontStyle::Bold, bold);
            }
            Ok(())
        })
        .clone()
}

/// Reads the first of `candidates` that exists, leaking its bytes to make them `'static`.
fn read_font(candidates: &[&Path]) -> Result<(PathBuf, &'static [u8]), FontError> {
    let mut tried = Vec::new();
    for &path in candidates {
        match std::fs::read(path) {
            Ok(bytes) => return Ok((path.to_path_buf(), Box::leak(bytes.into_boxed_slice()))),
            Err(e) => tried.push((path.to_path_buf(), e)),
        }
    }
    Err(FontError::Missing { tried })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sine(n: usize, phase: f64) -> Vec<(f64, f64)> {
        (0..n).map(|i| i as f64 * 0.01).map(|t| (t, (6.0 * t + phase).sin())).collect()
    }

    fn series(name: &str, points: Vec<(f64, f64)>, style: Style) -> Series {
        Series { name: name.into(), points, style }
    }

    fn panel(title: &str, series: Vec<Series>) -> Panel {
        Panel { title: title.into(), x_label: "t [s]".into(), y_label: "q [rad]".into(), series }
    }

    fn leftovers(dir: &Path) -> Vec<String> {
        std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .filter(|n| n.starts_with(".neurarm-"))
            .collect()
    }

    #[test]
    fn two_panel_figure_is_a_png() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("figure.png");
        let panels = [
            panel(
                "Joint 1",
                vec![
                    series("reference", sine(500, 0.0), Style::Line),
                    series("network", sine(500, 0.3), Style::Dashed),
                    series("samples", sine(500, 0.6).into_iter().step_by(25).collect(), Style::Points),
                ],
            ),
            Panel {
                title: "Joint 2 torque".into(),
                x_label: "t [s]".into(),
                y_label: "τ [N·m]".into(),
                series: vec![series("τ", sine(500, 1.0).into_iter().map(|(t, v)| (t, 40.0 * v)).collect(), Style::Line)],
            },
        ];
        write_png(&path, "Two joints", &panels, 1).unwrap();
        let bytes = std::fs::read(&path).unwrap();
        assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n");
        assert!(bytes.len() > 10_000, "only {} bytes", bytes.len());
        assert!(leftovers(dir.path()).is_empty());
        if let Ok(keep) = std::env::var("NEURARM_PLOT_SAMPLE") {
            std::fs::copy(&path, keep).unwrap();
        }
    }

    #[test]
    fn odd_data_does_not_panic() {
        let dir = tempfile::tempdir().unwrap();
        let nan = f64::NAN;
        let cases: Vec<Vec<Panel>> = vec![
            vec![panel("empty panel", vec![])],
            vec![panel("empty series", vec![series("nothing", vec![], Style::Line)])],
            vec![panel("one point", vec![series("p", vec![(1.0, 2.0)], Style::Line)])],
            vec![panel("one dot", vec![series("p", vec![(1.0, 2.0)], Style::Points)])],
            vec![panel("constant", vec![series("c", vec![(0.0, 3.0), (1.0, 3.0), (2.0, 3.0)], Style::Dashed)])],
            vec![panel("zero", vec![series("z", vec![(5.0, 0.0), (5.0, 0.0)], Style::Line)])],
            vec![panel("all NaN", vec![series("n", vec![(nan, nan), (1.0, nan), (nan, 1.0)], Style::Line)])],
            vec![panel(
                "gaps",
                vec![series(
                    "g",
                    vec![(0.0, 1.0), (1.0, nan), (2.0, 2.0), (3.0, f64::INFINITY), (4.0, 1e300), (5.0, 0.5), (6.0, 0.7)],
                    Style::Line,
                )],
            )],
            vec![panel("tiny", vec![series("t", vec![(0.0, 1e-300), (1.0, 2e-300)], Style::Line)])],
            vec![panel("huge", vec![series("h", vec![(-1e99, 1e99), (1e99, -1e99)], Style::Line)])],
            vec![panel("", vec![series("", sine(10, 0.0), Style::Line)]); 5],
        ];
        for (i, panels) in cases.iter().enumerate() {
            let path = dir.path().join(format!("case{i}.png"));
            let title = if i % 2 == 0 { "odd data" } else { "" };
            match write_png(&path, title, panels, 2) {
                Ok(()) => assert_eq!(&std::fs::read(&path).unwrap()[..4], b"\x89PNG", "case {i}"),
                Err(e) => assert!(e.to_string().contains("case"), "case {i}: unclear error {e}"),
            }
        }
        let none = dir.path().join("none.png");
        let e = write_png(&none, "no panels", &[], 1).unwrap_err().to_string();
        assert!(e.contains("none.png") && e.contains("no panels"), "{e}");
        assert!(!none.exists());
        assert!(leftovers(dir.path()).is_empty());
    }

    #[test]
    fn missing_folder_is_an_error_naming_it() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("no-such-folder").join("figure.png");
        let e = write_png(&path, "t", &[panel("p", vec![series("s", sine(10, 0.0), Style::Line)])], 1).unwrap_err().to_string();
        assert!(e.contains(&path.display().to_string()), "{e}");
        assert!(e.contains("does not exist"), "{e}");
        assert!(!path.exists());
    }

    #[test]
    fn missing_font_is_a_clear_error() {
        let dir = tempfile::tempdir().unwrap();
        let fake = dir.path().join("NoSuchFont.ttf");
        let e = read_font(&[fake.as_path()]).unwrap_err().to_string();
        assert!(e.contains("NoSuchFont.ttf") && e.contains("fonts-dejavu-core"), "{e}");
    }

    #[test]
    fn axis_ranges_cover_the_data() {
        assert_eq!(axis_range(std::iter::empty()), (0.0, 1.0));
        let (lo, hi) = axis_range([2.0, 2.0].into_iter());
        assert!(lo < 2.0 && hi > 2.0 && hi - lo >= 1.0);
        let (lo, hi) = axis_range([0.0, 10.0].into_iter());
        assert!((lo + 0.5).abs() < 1e-12 && (hi - 10.5).abs() < 1e-12);
        assert_eq!(plottable_runs(&[(0.0, f64::NAN), (1.0, 1.0), (2.0, f64::NAN), (3.0, 3.0), (4.0, 4.0)]).len(), 2);
    }

    #[test]
    fn tick_labels_are_short() {
        let f = tick_format(-0.5, 10.5);
        assert_eq!(f(&2.0), "2");
        let f = tick_format(0.0, 0.03);
        assert_eq!(f(&0.005), "0.005");
        assert_eq!(f(&0.0), "0");
        let f = tick_format(0.0, 2e7);
        assert_eq!(f(&1e7), "1e7");
        assert_eq!(f(&-2.5e7), "-2.5e7");
        let f = tick_format(0.0, 1e-6);
        assert_eq!(f(&2e-7), "2e-7");
    }
}
