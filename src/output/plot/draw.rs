//! Plots with plotters, as SVG or PNG ([`PlotFormat`]): [`super::plot_curve`]
//! (`curve.svg`) and [`super::plot_sweep`] (`sweep.svg`), sized and labelled for a
//! paper: a two-line title, integer ticks where the axis counts something,
//! tick labels with as many decimals as make them distinct, the legend
//! beside the data. Text in PNG is drawn with a font compiled into the
//! binary (`assets/fonts/`), so no system font is needed.

use std::io::BufWriter;
use std::ops::Range;
use std::path::Path;
use std::sync::OnceLock;

use plotters::coord::Shift;
use plotters::coord::ranged1d::{DefaultFormatting, KeyPointHint, Ranged};
use plotters::element::DashedPathElement;
use plotters::prelude::*;
use plotters::style::colors::colormaps::ViridisRGB;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::{CurvePlot, PlotFormat, PlotSize, Returned, ReturnedValue, SweepPoint, Title};
use crate::optimise::{IterationRecord, RecordSource};
use crate::output::OutputError;

/// Width of the legend column right of the data.
const LEGEND_WIDTH: u32 = 230;
/// Height of the two title lines.
const TITLE_HEIGHT: u32 = 56;
/// Lines with at most this many points also get a marker per point.
const MAX_MARKED_POINTS: usize = 200;
/// The bounds get at most this many markers (spread evenly over their points).
const MAX_BOUND_MARKERS: usize = 40;
/// The font family named in SVG files and registered for text layout and PNG.
const FONT: &str = "sans-serif";
/// DejaVu Sans cut down to Latin-1, Greek and mathematical symbols
/// (`assets/fonts/README.md`).
const FONT_BYTES: &[u8] = include_bytes!("../../../assets/fonts/DejaVuSans-subset.ttf");
/// The value at the last iterate (thin, dark grey, on top of the estimate).
const VALUE_COLOUR: RGBColor = RGBColor(70, 70, 70);
/// The worst-case estimate (thick, light blue, under the other lines).
const ESTIMATE_COLOUR: RGBColor = RGBColor(140, 175, 230);
/// The certified band and its edges.
const LOWER_COLOUR: RGBColor = RGBColor(26, 130, 60);
const UPPER_COLOUR: RGBColor = RGBColor(200, 40, 30);
const BAND_COLOUR: RGBColor = RGBColor(120, 170, 120);
/// The returned defender's certified bracket.
const RETURNED_COLOUR: RGBColor = RGBColor(0, 0, 0);

/// The error of drawing a plot (plotters' or the PNG encoder's).
type DrawError = Box<dyn std::error::Error + Send + Sync>;

/// Draws `curve` into `path` as `format` ([`super::plot_curve`]).
pub(super) fn curve(path: &Path, format: PlotFormat, curve: &CurvePlot) -> Result<(), OutputError> {
    render(path, (format, curve.size), curve)
}

/// Draws the heatmap of `points` into `path` as `format`
/// ([`super::plot_sweep`]).
pub(super) fn sweep(
    path: &Path,
    (format, size): (PlotFormat, PlotSize),
    title: &Title,
    points: &[SweepPoint],
) -> Result<(), OutputError> {
    render(path, (format, size), &SweepPlot { title, points })
}

/// A plot drawn the same way on any plotters backend.
trait Figure {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), DrawError>
    where
        DB::ErrorType: 'static;
}

/// Draws `figure` into `path`: an SVG file, or a PNG image rendered into
/// memory and encoded.
fn render(
    path: &Path,
    (format, size): (PlotFormat, PlotSize),
    figure: &impl Figure,
) -> Result<(), OutputError> {
    let dimensions = (size.width, size.height);
    let drawn = || -> Result<(), DrawError> {
        register_font()?;
        match format {
            PlotFormat::Svg => {
                let root = SVGBackend::new(path, dimensions).into_drawing_area();
                figure.draw(&root)?;
                root.present()?;
            }
            PlotFormat::Png => {
                let mut pixels = vec![0u8; size.width as usize * size.height as usize * 3];
                {
                    let root =
                        BitMapBackend::with_buffer(&mut pixels, dimensions).into_drawing_area();
                    figure.draw(&root)?;
                    root.present()?;
                }
                write_png(path, size, &pixels)?;
            }
        }
        Ok(())
    };
    drawn().map_err(|error| OutputError::Plot {
        path: path.to_path_buf(),
        problem: error.to_string(),
    })
}

/// Registers the bundled font under [`FONT`] (once): plotters lays out the
/// text of both backends with it and draws PNG text with it.
fn register_font() -> Result<(), DrawError> {
    static REGISTERED: OnceLock<bool> = OnceLock::new();
    let ok = *REGISTERED.get_or_init(|| {
        plotters::style::register_font(FONT, FontStyle::Normal, FONT_BYTES).is_ok()
    });
    if ok {
        Ok(())
    } else {
        Err("the font compiled into posg-fsc could not be read".into())
    }
}

/// Encodes 8-bit RGB `pixels` of `size` as a PNG file at `path`, with
/// the program and version as its `Software` text.
fn write_png(path: &Path, size: PlotSize, pixels: &[u8]) -> Result<(), DrawError> {
    let file = std::fs::File::create(path)?;
    let mut encoder = png::Encoder::new(BufWriter::new(file), size.width, size.height);
    let per_metre = (f64::from(size.dpi) / 0.0254).round() as u32;
    encoder.set_pixel_dims(Some(png::PixelDimensions {
        xppu: per_metre,
        yppu: per_metre,
        unit: png::Unit::Meter,
    }));
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    encoder.add_text_chunk(
        "Software".to_string(),
        format!("posg-fsc {}", env!("CARGO_PKG_VERSION")),
    )?;
    let mut writer = encoder.write_header()?;
    writer.write_image_data(pixels)?;
    writer.finish()?;
    Ok(())
}

/// One legend entry: its lines of text and how its sample is drawn.
struct LegendEntry {
    lines: Vec<String>,
    colour: RGBColor,
    kind: LegendKind,
}

enum LegendKind {
    /// A line of this width, dashed or not, with or without the marker.
    Line {
        width: u32,
        dashed: bool,
        marker: Option<Marker>,
    },
    Band,
    /// The returned defender's bracket.
    Returned,
    /// Text only.
    Note,
}

#[derive(Clone, Copy)]
enum Marker {
    Circle,
    Triangle,
    Cross,
}

impl Figure for CurvePlot<'_> {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), DrawError>
    where
        DB::ErrorType: 'static,
    {
        draw_curve(root, self)
    }
}

fn draw_curve<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    curve: &CurvePlot,
) -> Result<(), DrawError>
where
    DB::ErrorType: 'static,
{
    // The iterates; the returned record is drawn as the returned bracket,
    // where its defender was found.
    let records: Vec<IterationRecord> = curve
        .records
        .iter()
        .filter(|r| !r.returned)
        .copied()
        .collect();
    let records = &records[..];
    let source = (curve.records.iter())
        .find(|r| r.returned)
        .map(|r| r.source);
    let at = |pick: fn(&IterationRecord) -> Option<f64>| -> Vec<(f64, f64)> {
        records
            .iter()
            .filter_map(|r| pick(r).map(|y| (r.iteration as f64, y)))
            .collect()
    };
    let values = at(|r| Some(r.value));
    let estimates = at(|r| r.worst_case);
    let lower = at(|r| r.certified_lower);
    let upper = at(|r| r.upper_bound);
    let returned = curve.returned.as_ref().map_or(Vec::new(), returned_points);
    let x_last = records.last().map_or(1.0, |r| r.iteration.max(1) as f64);
    // The returned bracket stands at the iterate that found it, else (found
    // by rounding or local search after the race) a little right of the
    // last iterate.
    let found_at = where_found(records, source, curve.minimise);
    let x_returned = found_at.map_or(x_last * 1.04 + 0.25, |t| t as f64);
    let x_end = x_last * 1.08 + 0.5;
    let all = values.iter().chain(&estimates).chain(&lower).chain(&upper);
    let (y_min, y_max) = padded_range(all.map(|&(_, y)| y).chain(returned.iter().copied()));
    let (y_ticks, decimals) = value_ticks(y_min, y_max);
    root.fill(&WHITE)?;
    let (plot_area, legend_area) = frame(root, curve.title)?;
    let seconds_axis = curve.seconds_axis && records.len() > 1;
    let y_label_width = 30 + 9 * (decimals as u32 + 2);
    let mut chart = ChartBuilder::on(&plot_area)
        .margin(10)
        .margin_top(if seconds_axis { 48 } else { 10 })
        .x_label_area_size(45)
        .y_label_area_size(y_label_width)
        .build_cartesian_2d(
            Ticked::new(0.0..x_end, integer_ticks(x_last)),
            Ticked::new(y_min..y_max, y_ticks),
        )?;
    chart
        .configure_mesh()
        .x_desc("iteration")
        .y_desc(curve.quantity)
        .x_label_formatter(&|x| format!("{x:.0}"))
        .y_label_formatter(&|y| format!("{y:.decimals$}"))
        .label_style((FONT, 15))
        .axis_desc_style((FONT, 17))
        .light_line_style(WHITE.mix(0.0))
        .bold_line_style(BLACK.mix(0.08))
        .draw()?;
    let mut legend = Vec::new();
    if !lower.is_empty() && lower.len() == upper.len() {
        let band: Vec<(f64, f64)> = lower.iter().chain(upper.iter().rev()).copied().collect();
        chart.draw_series(std::iter::once(Polygon::new(
            band,
            BAND_COLOUR.mix(0.25).filled(),
        )))?;
        legend.push(entry(&["certified bracket"], BAND_COLOUR, LegendKind::Band));
    }
    // Thick and light first, thin and dark on top, the upper bound dashed
    // over the lower: every series stays visible where they coincide.
    if !estimates.is_empty() {
        chart.draw_series(LineSeries::new(
            estimates.iter().copied(),
            ESTIMATE_COLOUR.stroke_width(5),
        ))?;
        if estimates.len() <= MAX_MARKED_POINTS {
            chart.draw_series(
                estimates
                    .iter()
                    .map(|&p| Circle::new(p, 4, ESTIMATE_COLOUR.filled())),
            )?;
        }
        let kind = line_kind(5, false, Some(Marker::Circle));
        legend.push(entry(&["worst-case estimate"], ESTIMATE_COLOUR, kind));
    }
    if !values.is_empty() {
        chart.draw_series(LineSeries::new(
            values.iter().copied(),
            VALUE_COLOUR.stroke_width(1),
        ))?;
        legend.push(entry(
            &["value (last iterate)"],
            VALUE_COLOUR,
            line_kind(1, false, None),
        ));
    }
    if !lower.is_empty() {
        chart.draw_series(LineSeries::new(
            lower.iter().copied(),
            LOWER_COLOUR.stroke_width(2),
        ))?;
        chart.draw_series(thinned(&lower).map(|p| {
            EmptyElement::at(p) + TriangleMarker::new((0, 3), 5, LOWER_COLOUR.filled())
        }))?;
        let kind = line_kind(2, false, Some(Marker::Triangle));
        legend.push(entry(&["certified lower bound"], LOWER_COLOUR, kind));
    }
    if !upper.is_empty() {
        chart.draw_series(DashedLineSeries::new(
            upper.iter().copied(),
            7,
            5,
            UPPER_COLOUR.stroke_width(2),
        ))?;
        chart.draw_series(
            thinned(&upper).map(|p| {
                EmptyElement::at(p) + Cross::new((0, -4), 4, UPPER_COLOUR.stroke_width(2))
            }),
        )?;
        let kind = line_kind(2, true, Some(Marker::Cross));
        legend.push(entry(&["game upper bound"], UPPER_COLOUR, kind));
    }
    if let Some(returned) = &curve.returned {
        // An infinite expected reward has no place on the axis: the
        // legend alone says it.
        if returned_points(returned).iter().all(|y| y.is_finite()) {
            draw_returned(&mut chart, returned, x_returned)?;
        }
        legend.push(returned_entry(returned, source, found_at));
    }
    if seconds_axis {
        draw_seconds_axis(root, &chart, records, x_end, y_max)?;
    }
    draw_legend(&legend_area, &legend)?;
    Ok(())
}

type Chart<'a, DB> = ChartContext<'a, DB, Cartesian2d<Ticked, Ticked>>;

/// The iteration whose iterate the structure returned: where gradient
/// play made it (`source`), the first iterate with the best certified
/// lower bound (else the best worst-case estimate: the lowest where
/// `minimise`, a cost's curve); `None` where rounding or a local search
/// made it, after the race.
fn where_found(
    records: &[IterationRecord],
    source: Option<RecordSource>,
    minimise: bool,
) -> Option<usize> {
    if source != Some(RecordSource::Gradient) {
        return None;
    }
    let score = |r: &IterationRecord| r.certified_lower.or(r.worst_case);
    let better = if minimise { f64::min } else { f64::max };
    let best = records.iter().filter_map(score).reduce(better)?;
    (records.iter())
        .find(|r| score(r) == Some(best))
        .map(|r| r.iteration)
}

/// The returned bracket at `x`: a vertical bar from the certified lower
/// bound to the upper bound with caps and a diamond at the lower bound (or
/// a diamond at the estimate).
fn draw_returned<DB: DrawingBackend>(
    chart: &mut Chart<DB>,
    returned: &Returned,
    x: f64,
) -> Result<(), DrawError>
where
    DB::ErrorType: 'static,
{
    let (low, high) = match returned.certified {
        Some(b) => (b.certified_lower, b.upper_bound),
        None => (returned.worst_case, returned.worst_case),
    };
    let style = RETURNED_COLOUR.stroke_width(2);
    chart.draw_series(std::iter::once(PathElement::new(
        vec![(x, low), (x, high)],
        style,
    )))?;
    for y in [low, high] {
        chart.draw_series(std::iter::once(
            EmptyElement::at((x, y)) + PathElement::new(vec![(-7, 0), (7, 0)], style),
        ))?;
    }
    chart.draw_series(std::iter::once(
        EmptyElement::at((x, low)) + diamond(6, RETURNED_COLOUR),
    ))?;
    Ok(())
}

/// A filled diamond of half-width `r` pixels around the origin.
fn diamond(r: i32, colour: RGBColor) -> Polygon<(i32, i32)> {
    Polygon::new(vec![(0, -r), (r, 0), (0, r), (-r, 0)], colour.filled())
}

/// The values the returned bracket puts on the y axis.
fn returned_points(returned: &Returned) -> Vec<f64> {
    match returned.certified {
        Some(b) => vec![b.certified_lower, b.upper_bound],
        None => vec![returned.worst_case],
    }
}

/// The legend entry of the returned bracket: what made the defender
/// (`source`, at iteration `found_at` for gradient play) and its numbers
/// as `solve` prints them (six decimals).
fn returned_entry(
    returned: &Returned,
    source: Option<RecordSource>,
    found_at: Option<usize>,
) -> LegendEntry {
    let made = match (source, found_at) {
        (Some(RecordSource::Gradient), Some(t)) => format!("gradient play, iteration {t}"),
        (Some(RecordSource::Gradient), None) => "gradient play".to_string(),
        (Some(RecordSource::Rounding), _) => "rounding, after the race".to_string(),
        (Some(RecordSource::LocalSearch), _) => "local search".to_string(),
        (None, _) => "the run".to_string(),
    };
    let mut lines = vec!["returned, from".to_string(), made];
    match returned.certified {
        Some(b) => lines.extend([
            "certified:".to_string(),
            format!("[{:.6}, {:.6}]", b.certified_lower, b.upper_bound),
        ]),
        None => lines.extend([
            match returned.kind {
                ReturnedValue::Estimated => "estimated:",
                ReturnedValue::Exact => "exact:",
                ReturnedValue::Guaranteed => "guaranteed:",
            }
            .to_string(),
            format!("{:.6}", returned.worst_case),
        ]),
    };
    LegendEntry {
        lines,
        colour: RETURNED_COLOUR,
        kind: LegendKind::Returned,
    }
}

/// At most [`MAX_BOUND_MARKERS`] of `points`, evenly spread, the last one
/// included.
fn thinned(points: &[(f64, f64)]) -> impl Iterator<Item = (f64, f64)> + '_ {
    let step = points.len().div_ceil(MAX_BOUND_MARKERS).max(1);
    let last = points.len().saturating_sub(1);
    points
        .iter()
        .enumerate()
        .filter(move |&(i, _)| i % step == 0 || i == last)
        .map(|(_, &p)| p)
}

/// The top axis with the seconds elapsed, over the chart's top edge.
fn draw_seconds_axis<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    chart: &Chart<DB>,
    records: &[IterationRecord],
    x_end: f64,
    y_max: f64,
) -> Result<(), DrawError>
where
    DB::ErrorType: 'static,
{
    let top = |x: f64| chart.backend_coord(&(x, y_max));
    let (left, right) = (top(0.0), top(x_end));
    let style = TextStyle::from((FONT, 13).into_font()).pos(anchor(HPos::Center, VPos::Bottom));
    root.draw(&PathElement::new(vec![left, right], BLACK.stroke_width(1)))?;
    // A label that would touch the one before it is left out (the seconds
    // of a run can bunch up where its iterations are fast).
    let mut free_from = i32::MIN;
    for (position, label) in seconds_ticks(records) {
        let (x, y) = top(position);
        let half = root.estimate_text_size(&label, &style)?.0 as i32 / 2;
        if x - half < free_from {
            continue;
        }
        free_from = x + half + TICK_LABEL_GAP;
        root.draw(&PathElement::new(
            vec![(x, y), (x, y - 5)],
            BLACK.stroke_width(1),
        ))?;
        root.draw(&Text::new(label, (x, y - 7), style.clone()))?;
    }
    let desc = TextStyle::from((FONT, 15).into_font()).pos(anchor(HPos::Center, VPos::Bottom));
    root.draw(&Text::new(
        "seconds",
        ((left.0 + right.0) / 2, left.1 - 22),
        desc,
    ))?;
    Ok(())
}

/// The least gap between two tick labels of the seconds axis, in pixels.
const TICK_LABEL_GAP: i32 = 10;

/// A linear axis over `range` with ticks exactly at `ticks` (plotters
/// picks its own otherwise).
struct Ticked {
    range: Range<f64>,
    ticks: Vec<f64>,
}

impl Ticked {
    fn new(range: Range<f64>, ticks: Vec<f64>) -> Self {
        Self { range, ticks }
    }
}

impl Ranged for Ticked {
    type FormatOption = DefaultFormatting;
    type ValueType = f64;

    fn map(&self, value: &f64, limit: (i32, i32)) -> i32 {
        let share = (value - self.range.start) / (self.range.end - self.range.start);
        limit.0 + (share * f64::from(limit.1 - limit.0)).round() as i32
    }

    fn key_points<Hint: KeyPointHint>(&self, hint: Hint) -> Vec<f64> {
        if hint.weight().allow_light_points() {
            Vec::new()
        } else {
            self.ticks.clone()
        }
    }

    fn range(&self) -> Range<f64> {
        self.range.clone()
    }
}

fn entry(lines: &[&str], colour: RGBColor, kind: LegendKind) -> LegendEntry {
    LegendEntry {
        lines: lines.iter().map(|s| s.to_string()).collect(),
        colour,
        kind,
    }
}

fn line_kind(width: u32, dashed: bool, marker: Option<Marker>) -> LegendKind {
    LegendKind::Line {
        width,
        dashed,
        marker,
    }
}

/// A plot area and the legend column beside it.
type Areas<DB> = (DrawingArea<DB, Shift>, DrawingArea<DB, Shift>);

/// Draws the title on top of `root` and returns the plot area and the
/// legend column right of it.
fn frame<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    title: &Title,
) -> Result<Areas<DB>, DrawError>
where
    DB::ErrorType: 'static,
{
    let style =
        |size: u32| TextStyle::from((FONT, size).into_font()).pos(anchor(HPos::Center, VPos::Top));
    let (root_width, _) = root.dim_in_pixel();
    let width = root_width - 2 * TITLE_MARGIN;
    let main = at_most(wrapped(root, &title.main, &style(20), width)?, TITLE_LINES);
    let detail = at_most(
        wrapped(root, &title.detail, &style(15), width)?,
        TITLE_LINES,
    );
    let extra = |lines: &[String], height: u32| height * (lines.len().max(1) as u32 - 1);
    let (head, body) = root.split_vertically(TITLE_HEIGHT + extra(&main, 24) + extra(&detail, 19));
    let centre = (root_width / 2) as i32;
    let mut y = 8;
    for line in main {
        head.draw(&Text::new(line, (centre, y), style(20)))?;
        y += 24;
    }
    y += 2;
    for line in detail {
        head.draw(&Text::new(line, (centre, y), style(15)))?;
        y += 19;
    }
    Ok(body.split_horizontally(root_width - LEGEND_WIDTH))
}

/// Left and right margin of the title, in pixels.
const TITLE_MARGIN: u32 = 16;

/// The most lines each part of a title wraps to (the rest is cut, `...`
/// said), so that the chart keeps its room on the smallest plot.
const TITLE_LINES: usize = 3;

/// The first `most` of `lines`, the last of them ending in ` ...` where
/// some were cut.
fn at_most(mut lines: Vec<String>, most: usize) -> Vec<String> {
    if lines.len() > most {
        lines.truncate(most);
        if let Some(last) = lines.last_mut() {
            last.push_str(" ...");
        }
    }
    lines
}

/// `text` broken at spaces into lines at most `width` pixels wide in
/// `style` (a word wider than that gets a line of its own); no line for
/// an empty text.
fn wrapped<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    text: &str,
    style: &TextStyle,
    width: u32,
) -> Result<Vec<String>, DrawError>
where
    DB::ErrorType: 'static,
{
    let mut lines: Vec<String> = Vec::new();
    for word in text.split(' ') {
        let joined = match lines.last() {
            Some(line) => format!("{line} {word}"),
            None => word.to_string(),
        };
        let fits = root.estimate_text_size(&joined, style)?.0 <= width;
        match lines.last_mut() {
            Some(line) if fits => *line = joined,
            _ => lines.push(word.to_string()),
        }
    }
    lines.retain(|line| !line.is_empty());
    Ok(lines)
}

/// Vertical distance between two lines of legend text.
const LEGEND_LINE: i32 = 18;

/// The legend: one sample and its lines of text per entry, from the top of
/// `area`; returns the height used.
fn draw_legend<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    entries: &[LegendEntry],
) -> Result<i32, DrawError>
where
    DB::ErrorType: 'static,
{
    let mut y = 30;
    for entry in entries {
        draw_sample(area, entry, y)?;
        let x = match entry.kind {
            LegendKind::Note => 8,
            _ => 46,
        };
        for (k, line) in entry.lines.iter().enumerate() {
            let at = (x, y - 8 + LEGEND_LINE * k as i32);
            area.draw(&Text::new(line.clone(), at, (FONT, 14).into_font()))?;
        }
        y += 10 + LEGEND_LINE * entry.lines.len().max(1) as i32;
    }
    Ok(y)
}

/// The sample of one legend entry, centred at height `y`.
fn draw_sample<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    entry: &LegendEntry,
    y: i32,
) -> Result<(), DrawError>
where
    DB::ErrorType: 'static,
{
    let colour = entry.colour;
    match entry.kind {
        LegendKind::Line {
            width,
            dashed,
            marker,
        } => {
            let style = colour.stroke_width(width);
            if dashed {
                area.draw(&DashedPathElement::new(vec![(6, y), (40, y)], 7, 5, style))?;
            } else {
                area.draw(&PathElement::new(vec![(6, y), (40, y)], style))?;
            }
            match marker {
                Some(Marker::Circle) => area.draw(&Circle::new((23, y), 4, colour.filled()))?,
                Some(Marker::Triangle) => {
                    area.draw(&TriangleMarker::new((23, y), 5, colour.filled()))?
                }
                Some(Marker::Cross) => area.draw(&Cross::new((23, y), 4, style))?,
                None => {}
            }
        }
        LegendKind::Band => area.draw(&Rectangle::new(
            [(6, y - 7), (40, y + 7)],
            colour.mix(0.25).filled(),
        ))?,
        LegendKind::Returned => {
            let style = colour.stroke_width(2);
            area.draw(&PathElement::new(vec![(23, y - 8), (23, y + 8)], style))?;
            for cap in [y - 8, y + 8] {
                area.draw(&PathElement::new(vec![(16, cap), (30, cap)], style))?;
            }
            area.draw(&(EmptyElement::at((23, y + 8)) + diamond(6, colour)))?;
        }
        LegendKind::Note => {}
    }
    Ok(())
}

/// `[min, max]` of the values widened by 5% (at least 0.001 on each side);
/// `[0, 1]` without values.
fn padded_range(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) = values
        .filter(|y| y.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), y| {
            (lo.min(y), hi.max(y))
        });
    if !lo.is_finite() {
        return (0.0, 1.0);
    }
    let margin = ((hi - lo) * 0.05).max(1e-3);
    (lo - margin, hi + margin)
}

/// About six ticks inside `[lo, hi]` at multiples of a step of 1, 2 or 5
/// times a power of ten, and the number of decimals that shows each tick
/// exactly (so neighbouring labels always differ).
fn value_ticks(lo: f64, hi: f64) -> (Vec<f64>, usize) {
    let step = nice_step((hi - lo) / 6.0);
    let decimals = decimals_of(step);
    let first = (lo / step).ceil() as i64;
    let last = (hi / step).floor() as i64;
    let ticks = (first..=last).map(|k| k as f64 * step).collect();
    (ticks, decimals)
}

/// The decimals that write multiples of `step` (1, 2 or 5 times a power of
/// ten) exactly.
fn decimals_of(step: f64) -> usize {
    if step >= 1.0 {
        0
    } else {
        (-step.log10().floor()) as usize
    }
}

/// About eight ticks at multiples of 1, 2 or 5 times a power of ten, all
/// whole numbers, from 0 to `max`.
fn integer_ticks(max: f64) -> Vec<f64> {
    let step = nice_step(max / 8.0).max(1.0);
    let count = (max / step).floor() as usize;
    (0..=count).map(|k| k as f64 * step).collect()
}

/// The smallest of 1, 2, 5 times a power of ten that is at least `raw`.
fn nice_step(raw: f64) -> f64 {
    if raw <= 0.0 || !raw.is_finite() {
        return 1.0;
    }
    let power = 10f64.powf(raw.log10().floor());
    [1.0, 2.0, 5.0, 10.0]
        .into_iter()
        .map(|m| m * power)
        .find(|&s| s >= raw * (1.0 - 1e-12))
        .unwrap_or(10.0 * power)
}

/// The top axis: for round numbers of seconds, the (fractional) iteration
/// at which that much time had elapsed, and the label to show there. The
/// records' seconds count from the structure's start, before the local
/// search that precedes the race: only the times from the first record on
/// have an iteration, so the round numbers are those of that span.
fn seconds_ticks(records: &[IterationRecord]) -> Vec<(f64, String)> {
    let first = records.first().map_or(0.0, |r| r.seconds);
    let total = records.last().map_or(0.0, |r| r.seconds);
    let step = nice_step((total - first) / 6.0);
    let decimals = decimals_of(step);
    let mut ticks = Vec::new();
    let mut k = (first / step).ceil().max(1.0);
    while k * step <= total {
        let target = k * step;
        if let Some(w) = records.windows(2).find(|w| w[1].seconds >= target) {
            let (a, b) = (&w[0], &w[1]);
            let share = if b.seconds > a.seconds {
                ((target - a.seconds) / (b.seconds - a.seconds)).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let position = a.iteration as f64 + share * (b.iteration as f64 - a.iteration as f64);
            ticks.push((position, format!("{target:.decimals$}")));
        }
        k += 1.0;
    }
    ticks
}

/// The sweep's heatmap ([`super::plot_sweep`]).
struct SweepPlot<'a> {
    title: &'a Title,
    points: &'a [SweepPoint],
}

impl Figure for SweepPlot<'_> {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), DrawError>
    where
        DB::ErrorType: 'static,
    {
        draw_sweep(root, self.title, self.points)
    }
}

/// The number a cell shows and is coloured by: the certified lower bound,
/// else the worst-case estimate.
fn shown(point: &SweepPoint) -> f64 {
    point.bracket.map_or(point.worst_case, |b| b.0)
}

fn draw_sweep<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    title: &Title,
    points: &[SweepPoint],
) -> Result<(), DrawError>
where
    DB::ErrorType: 'static,
{
    let sizes = |pick: fn(&SweepPoint) -> usize| {
        let mut v: Vec<usize> = points.iter().map(pick).collect();
        v.sort_unstable();
        v.dedup();
        v
    };
    let (defender_sizes, adversary_sizes) =
        (sizes(|p| p.defender_nodes), sizes(|p| p.adversary_nodes));
    let certified = points.iter().all(|p| p.bracket.is_some());
    let scale = colour_scale(points.iter().map(shown));
    let decimals = distinct_decimals(points.iter().flat_map(|p| {
        let (lower, upper) = p.bracket.unwrap_or((p.worst_case, p.worst_case));
        [lower, upper, p.worst_case]
    }));
    root.fill(&WHITE)?;
    let (plot_area, legend_area) = frame(root, title)?;
    let mut chart = ChartBuilder::on(&plot_area)
        .margin(10)
        .x_label_area_size(45)
        .y_label_area_size(65)
        .build_cartesian_2d(cells(defender_sizes.len()), cells(adversary_sizes.len()))?;
    let label = |sizes: &[usize], v: &f64| {
        sizes
            .get(v.floor() as usize)
            .map_or(String::new(), |s| s.to_string())
    };
    chart
        .configure_mesh()
        .disable_mesh()
        .x_desc("defender nodes")
        .y_desc("adversary nodes")
        .x_label_formatter(&|v| label(&defender_sizes, v))
        .y_label_formatter(&|v| label(&adversary_sizes, v))
        .label_style((FONT, 15))
        .axis_desc_style((FONT, 17))
        .draw()?;
    for p in points {
        let i = defender_sizes.binary_search(&p.defender_nodes).unwrap_or(0) as f64;
        let j = adversary_sizes
            .binary_search(&p.adversary_nodes)
            .unwrap_or(0) as f64;
        let cell = [(i, j), (i + 1.0, j + 1.0)];
        let colour = scale.colour(shown(p));
        chart.draw_series(std::iter::once(Rectangle::new(cell, colour.filled())))?;
        chart.draw_series(std::iter::once(Rectangle::new(cell, WHITE.stroke_width(2))))?;
        let (left, top) = chart.backend_coord(&(i, j + 1.0));
        let (right, bottom) = chart.backend_coord(&(i + 1.0, j));
        let text = cell_text(p, decimals);
        let box_size = ((right - left).abs(), (bottom - top).abs());
        let centre = ((left + right) / 2, (top + bottom) / 2);
        draw_cell_text(root, &text, centre, box_size, ink_on(colour))?;
    }
    let measured = if certified {
        "certified lower bound"
    } else {
        "worst-case estimate"
    };
    let mut legend = vec![entry(
        &["cell and colour:", measured],
        BLACK,
        LegendKind::Note,
    )];
    if certified {
        legend.push(entry(
            &["est.: worst-case estimate", "ub: game upper bound"],
            BLACK,
            LegendKind::Note,
        ));
    }
    let used = draw_legend(&legend_area, &legend)?;
    draw_colour_bar(&legend_area, &scale, used + 10)?;
    Ok(())
}

/// The lines of a cell: the shown number, then (with a bracket) the
/// estimate and the upper bound.
fn cell_text(point: &SweepPoint, decimals: usize) -> Vec<String> {
    let mut lines = vec![format!("{:.decimals$}", shown(point))];
    if let Some((_, upper)) = point.bracket {
        lines.push(format!("est. {:.decimals$}", point.worst_case));
        lines.push(format!("ub {upper:.decimals$}"));
    }
    lines
}

/// Draws `lines` centred at `centre` inside a cell of `size` pixels: the
/// first line as large as fits (up to 22 px), the others smaller below it,
/// dropped when they do not fit; nothing when even the first does not.
fn draw_cell_text<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    lines: &[String],
    centre: (i32, i32),
    size: (i32, i32),
    ink: RGBColor,
) -> Result<(), DrawError>
where
    DB::ErrorType: 'static,
{
    let usable = (f64::from(size.0) * 0.88, f64::from(size.1) * 0.88);
    let fits = |text: &str, px: u32| -> Result<bool, DrawError> {
        let (w, _) = root.estimate_text_size(text, &TextStyle::from((FONT, px).into_font()))?;
        Ok(f64::from(w) <= usable.0)
    };
    let largest = |text: &str, from: u32, to: u32| -> Result<Option<u32>, DrawError> {
        for px in (to..=from).rev() {
            if fits(text, px)? {
                return Ok(Some(px));
            }
        }
        Ok(None)
    };
    let Some(big) = largest(&lines[0], 22, 8)? else {
        return Ok(());
    };
    let mut small = None;
    if lines.len() > 1 {
        let mut px = big.saturating_sub(6).clamp(9, 14);
        while px >= 9 {
            let all_fit = lines[1..]
                .iter()
                .try_fold(true, |ok, l| Ok::<_, DrawError>(ok && fits(l, px)?))?;
            let height = f64::from(big) * 1.2 + f64::from(px) * 1.25 * (lines.len() - 1) as f64;
            if all_fit && height <= usable.1 {
                small = Some(px);
                break;
            }
            px -= 1;
        }
    }
    let sizes: Vec<u32> = match small {
        Some(px) => std::iter::once(big)
            .chain(std::iter::repeat_n(px, lines.len() - 1))
            .collect(),
        None => vec![big],
    };
    let heights: Vec<i32> = sizes
        .iter()
        .map(|&px| (f64::from(px) * 1.25) as i32)
        .collect();
    let mut y = centre.1 - heights.iter().sum::<i32>() / 2;
    for ((line, &px), &h) in lines.iter().zip(&sizes).zip(&heights) {
        let style = TextStyle::from((FONT, px).into_font())
            .color(&ink)
            .pos(anchor(HPos::Center, VPos::Center));
        root.draw(&Text::new(line.clone(), (centre.0, y + h / 2), style))?;
        y += h;
    }
    Ok(())
}

/// The fewest decimals (3 to 6) that write different values (differing
/// by at least 1e-6) differently.
fn distinct_decimals(values: impl Iterator<Item = f64>) -> usize {
    let mut values: Vec<f64> = values.filter(|v| v.is_finite()).collect();
    values.sort_by(f64::total_cmp);
    values.dedup_by(|a, b| (*a - *b).abs() < 1e-6);
    (3..6)
        .find(|&d| {
            values
                .windows(2)
                .all(|w| format!("{:.d$}", w[0]) != format!("{:.d$}", w[1]))
        })
        .unwrap_or(6)
}

/// The heatmap's continuous colour scale (viridis) over `[low, high]`.
struct ColourScale {
    low: f64,
    high: f64,
}

/// The scale over the values' range; a range narrower than 0.01 is widened
/// to 0.01 around its middle (inside `[0, 1]` where possible).
fn colour_scale(values: impl Iterator<Item = f64>) -> ColourScale {
    let (lo, hi) = values
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
            (lo.min(v), hi.max(v))
        });
    if !lo.is_finite() {
        return ColourScale {
            low: 0.0,
            high: 1.0,
        };
    }
    const NARROWEST: f64 = 0.01;
    if hi - lo >= NARROWEST {
        return ColourScale { low: lo, high: hi };
    }
    let low = ((lo + hi) / 2.0 - NARROWEST / 2.0).clamp(0.0, 1.0 - NARROWEST);
    ColourScale {
        low,
        high: low + NARROWEST,
    }
}

impl ColourScale {
    fn colour(&self, value: f64) -> RGBColor {
        ViridisRGB::get_color_normalized(value, self.low, self.high)
    }
}

/// Black text on light colours, white on dark ones.
fn ink_on(colour: RGBColor) -> RGBColor {
    let RGBColor(r, g, b) = colour;
    let luminance = 0.299 * f64::from(r) + 0.587 * f64::from(g) + 0.114 * f64::from(b);
    if luminance > 140.0 { BLACK } else { WHITE }
}

/// The colour bar: the scale from `low` (bottom) to `high` (top) with
/// ticks, in the legend column from height `top`.
fn draw_colour_bar<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    scale: &ColourScale,
    top: i32,
) -> Result<(), DrawError>
where
    DB::ErrorType: 'static,
{
    let (_, area_height) = area.dim_in_pixel();
    let bottom = (area_height as i32 - 60).max(top + 60);
    let (left, right) = (12, 36);
    let span = f64::from(bottom - top);
    let y_of = |v: f64| bottom - ((v - scale.low) / (scale.high - scale.low) * span).round() as i32;
    for y in top..bottom {
        let v = scale.low + f64::from(bottom - y) / span * (scale.high - scale.low);
        area.draw(&Rectangle::new(
            [(left, y), (right, y + 1)],
            scale.colour(v).filled(),
        ))?;
    }
    area.draw(&Rectangle::new(
        [(left, top), (right, bottom)],
        BLACK.stroke_width(1),
    ))?;
    let (ticks, decimals) = value_ticks(scale.low, scale.high);
    let ends = distinct_decimals([scale.low, scale.high].into_iter()).max(decimals);
    let style = TextStyle::from((FONT, 13).into_font()).pos(anchor(HPos::Left, VPos::Center));
    // The two ends, with the ticks between them that do not crowd them.
    for v in [scale.low, scale.high] {
        let label = format!("{v:.ends$}");
        area.draw(&Text::new(label, (right + 8, y_of(v)), style.clone()))?;
    }
    let clear = |y: i32| (y - top).abs() > 16 && (y - bottom).abs() > 16;
    for t in ticks.into_iter().filter(|&t| clear(y_of(t))) {
        let y = y_of(t);
        area.draw(&PathElement::new(
            vec![(right, y), (right + 5, y)],
            BLACK.stroke_width(1),
        ))?;
        area.draw(&Text::new(
            format!("{t:.decimals$}"),
            (right + 8, y),
            style.clone(),
        ))?;
    }
    Ok(())
}

/// An axis of `n` unit cells with a tick in the middle of each.
fn cells(n: usize) -> Ticked {
    Ticked::new(0.0..n as f64, (0..n).map(|i| i as f64 + 0.5).collect())
}

fn anchor(horizontal: HPos, vertical: VPos) -> Pos {
    Pos::new(horizontal, vertical)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn integer_ticks_are_whole_numbers_about_eight_of_them() {
        assert_eq!(integer_ticks(3.0), vec![0.0, 1.0, 2.0, 3.0]);
        assert_eq!(integer_ticks(199.0), vec![0.0, 50.0, 100.0, 150.0]);
        assert_eq!(integer_ticks(20.0), vec![0.0, 5.0, 10.0, 15.0, 20.0]);
    }

    #[test]
    fn value_ticks_of_a_narrow_range_have_distinct_labels() {
        // The POMDP curve of issue 29: 0.725 and 0.730 both read 0.73 at
        // two decimals.
        for (lo, hi) in [
            (0.7195, 0.7405),
            (0.69978, 0.69979),
            (0.0, 1.0),
            (0.5, 0.5001),
        ] {
            let (ticks, decimals) = value_ticks(lo, hi);
            assert!(ticks.len() >= 3, "{lo}..{hi}: {ticks:?}");
            assert!(ticks.iter().all(|t| (lo..=hi).contains(t)));
            let labels: Vec<String> = ticks.iter().map(|t| format!("{t:.decimals$}")).collect();
            let mut distinct = labels.clone();
            distinct.dedup();
            assert_eq!(distinct, labels, "{lo}..{hi}");
        }
        let (ticks, decimals) = value_ticks(0.7195, 0.7405);
        assert_eq!(decimals, 3);
        assert_eq!(format!("{:.decimals$}", ticks[1]), "0.725");
    }

    #[test]
    fn sweep_cells_get_enough_decimals_to_differ() {
        assert_eq!(distinct_decimals([0.687, 0.700, 0.5].into_iter()), 3);
        assert_eq!(distinct_decimals([0.6998, 0.69979].into_iter()), 5);
        assert_eq!(distinct_decimals([0.6998, 0.69980001].into_iter()), 3);
    }

    #[test]
    fn the_colour_scale_spans_the_values_and_tells_close_ones_apart() {
        let scale = colour_scale([0.687, 0.700].into_iter());
        assert_eq!((scale.low, scale.high), (0.687, 0.700));
        assert_ne!(scale.colour(0.687), scale.colour(0.700));
        let flat = colour_scale([1.0, 1.0].into_iter());
        assert!((flat.high - 1.0).abs() < 1e-12 && flat.low < flat.high);
    }

    fn record(iteration: usize, seconds: f64) -> IterationRecord {
        IterationRecord {
            start: 0,
            iteration,
            seconds,
            value: 0.5,
            defender_gradient_norm: 0.0,
            adversary_gradient_norm: 0.0,
            defender_step: 0.0,
            adversary_step: 0.0,
            worst_case: None,
            certified_lower: None,
            upper_bound: None,
            logit_bound: 4.0,
            source: crate::optimise::RecordSource::Gradient,
            returned: false,
        }
    }

    #[test]
    fn seconds_ticks_sit_where_that_much_time_had_elapsed() {
        // 0.1 s per iteration for 10 iterations, then 1 s per iteration.
        let records: Vec<IterationRecord> = (0..=20)
            .map(|t| {
                record(
                    t,
                    if t <= 10 {
                        0.1 * t as f64
                    } else {
                        1.0 + (t - 10) as f64
                    },
                )
            })
            .collect();
        let ticks = seconds_ticks(&records);
        assert_eq!(ticks[0].1, "2");
        assert!((ticks[0].0 - 11.0).abs() < 1e-9, "{ticks:?}");
        assert_eq!(ticks.last().unwrap().1, "10");
        assert!((ticks.last().unwrap().0 - 19.0).abs() < 1e-9);
    }

    /// A race that starts 4.4 s in (after its local search) has no tick
    /// before its first iteration: the ticks sit at distinct, increasing
    /// iterations with distinct labels, on the round numbers of its span.
    #[test]
    fn seconds_ticks_start_where_the_race_starts() {
        let records: Vec<IterationRecord> =
            (0..=40).map(|t| record(t, 4.4 + 0.1 * t as f64)).collect();
        let ticks = seconds_ticks(&records);
        assert_eq!(ticks[0].1, "5", "{ticks:?}");
        assert!((ticks[0].0 - 6.0).abs() < 1e-9, "{ticks:?}");
        assert_eq!(ticks.last().unwrap().1, "8");
        for pair in ticks.windows(2) {
            assert!(pair[1].0 > pair[0].0 && pair[1].1 != pair[0].1, "{ticks:?}");
        }
    }

    /// Issue 59: a long formula's title was clipped on both sides.
    #[test]
    fn a_long_title_is_wrapped_at_spaces_within_the_width() {
        register_font().unwrap();
        let mut svg = String::new();
        let root = SVGBackend::with_string(&mut svg, (900, 520)).into_drawing_area();
        let style = TextStyle::from((FONT, 20).into_font());
        let text = "GF goal & G !unsafe & (GF goal | F G !unsafe) & G (unsafe -> X !goal) & \
                    (F goal | G F goal) & G (goal -> X F goal)";
        let lines = wrapped(&root, text, &style, 868).unwrap();
        assert!(lines.len() >= 2, "{lines:?}");
        assert_eq!(lines.join(" "), text);
        for line in &lines {
            assert!(
                root.estimate_text_size(line, &style).unwrap().0 <= 868,
                "{line}"
            );
        }
        assert_eq!(wrapped(&root, "short", &style, 868).unwrap(), ["short"]);
        assert!(wrapped(&root, "", &style, 868).unwrap().is_empty());
    }

    /// Issue 59: the returned defender stands where it was found: at the
    /// first iterate with its score when gradient play made it, right of
    /// the curve otherwise.
    #[test]
    fn the_returned_defender_is_placed_where_it_was_found() {
        let mut records: Vec<IterationRecord> = (0..6).map(|t| record(t, t as f64)).collect();
        for (t, lower) in [(1, 0.2), (3, 0.5), (5, 0.5)] {
            records[t].certified_lower = Some(lower);
        }
        assert_eq!(
            where_found(&records, Some(RecordSource::Gradient), false),
            Some(3)
        );
        assert_eq!(
            where_found(&records, Some(RecordSource::LocalSearch), false),
            None
        );
        assert_eq!(
            where_found(&records, Some(RecordSource::Rounding), false),
            None
        );
        // A cost's curve (expected rewards in `worst_case`): the lowest.
        let costs: Vec<IterationRecord> = [3.0, 2.0, 1.5, 1.5, 4.0]
            .into_iter()
            .enumerate()
            .map(|(t, cost)| IterationRecord {
                worst_case: Some(cost),
                ..record(t, t as f64)
            })
            .collect();
        assert_eq!(
            where_found(&costs, Some(RecordSource::Gradient), true),
            Some(2)
        );
        assert_eq!(
            where_found(&costs, Some(RecordSource::Gradient), false),
            Some(4)
        );
    }

    #[test]
    fn nice_steps_are_one_two_or_five_times_a_power_of_ten() {
        assert_eq!(nice_step(0.3), 0.5);
        assert_eq!(nice_step(24.9), 50.0);
        assert_eq!(nice_step(20.0), 20.0);
        assert_eq!(nice_step(0.0), 1.0);
    }

    #[test]
    fn png_plots_draw_text_with_the_bundled_font() {
        let dir = std::env::temp_dir().join(format!("posg-fsc-plot-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let title = Title {
            main: "grid: F goal".into(),
            detail: "defender 2 nodes".into(),
        };
        let records: Vec<IterationRecord> = (0..=10).map(|t| record(t, t as f64)).collect();
        let returned = Some(Returned {
            worst_case: 0.5,
            certified: None,
            kind: ReturnedValue::Estimated,
        });
        let size = PlotSize {
            width: 1200,
            height: 700,
            dpi: 150,
        };
        let curve = CurvePlot {
            title: &title,
            records: &records,
            returned,
            seconds_axis: true,
            size,
            quantity: super::super::PROBABILITY_AXIS,
            minimise: false,
        };
        let path = dir.join("curve.png");
        super::curve(&path, PlotFormat::Png, &curve).unwrap();
        let bytes = std::fs::read(&path).unwrap();
        assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n");
        let decoder = png::Decoder::new(std::io::Cursor::new(bytes));
        let mut reader = decoder.read_info().unwrap();
        assert_eq!((reader.info().width, reader.info().height), (1200, 700));
        let dims = reader.info().pixel_dims.unwrap();
        assert_eq!((dims.xppu, dims.unit), (5906, png::Unit::Meter));
        let mut pixels = vec![0; reader.output_buffer_size().unwrap()];
        reader.next_frame(&mut pixels).unwrap();
        // The title's text is drawn: the top strip is not blank.
        let strip = &pixels[..(size.width * 3 * 40) as usize];
        assert!(strip.iter().any(|&b| b < 128), "no text in the title strip");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
